//! The contact-force probe: at every accepted state, the active contacts' forces against
//! their laws (docs/model.md §6): λ_n ≥ 0, |λ_t| ≤ μ λ_n when sticking, λ_t u_t ≤ 0 when
//! sliding, and how far each contact's gap drifted from zero. Debug builds also assert the
//! first two, with room for the guards' margins and event location.

use super::super::dynamics::Dynamics;
use super::Probe;
use crate::model::active_set::Tangential;
use crate::model::contact;
use crate::sim::recorder::Recorder;
use crate::sim::result::ContactCheck;
use crate::sim::tolerances::REST_SLIP;

/// The contact forces' extremes at the accepted steps since the last drain.
#[derive(Debug, Default)]
pub(crate) struct ContactForces(ContactCheck);

impl Probe for ContactForces {
    #[cfg(test)]
    fn name(&self) -> &'static str {
        "contact forces"
    }

    fn at_step(&mut self, d: &Dynamics, t: f64, y: &[f64; 6]) {
        if d.riding || d.contacts.is_empty() {
            return;
        }
        let e = d.evaluate(t, y);
        let (g, kin) = d.kinematics(t, y);
        let w = d.ctx.weight;
        let mut c = ContactCheck::default();
        for (i, a) in d.contacts.slots().iter().enumerate() {
            let (Some(a), Some(fr)) = (a, e.frames[i]) else {
                continue;
            };
            let (ln, lt) = (e.normal_force[i], e.tangential_force[i]);
            c.min_normal_force = c.min_normal_force.min(ln / w);
            let (gap, _, _) = contact::gap_and_range_with(a.kind, &kin, g.phi_sc, g.arm_sc);
            c.max_gap_drift = c.max_gap_drift.max(gap.abs());
            match a.mode {
                Tangential::Stick => {
                    let excess = lt.abs() - d.ctx.arm_friction * ln.max(0.0);
                    c.max_cone_excess = c.max_cone_excess.max(excess / w);
                }
                // Only a contact that slides: at rest within the event logic's slip tolerance
                // (a corner whose slip a sticking corner of the same flush side locks at
                // zero, carrying its share of a statically indeterminate friction at its
                // cone's edge) the slip is drift, and λ_t u_t no work.
                Tangential::Slide(_) if fr.slip.abs() > REST_SLIP => {
                    c.max_friction_power = c.max_friction_power.max(lt * fr.slip);
                }
                Tangential::Slide(_) => {}
            }
        }
        debug_assert!(
            c.min_normal_force >= -1e-6 && c.max_cone_excess <= 1e-6,
            "contact forces inconsistent at t = {t}: {c:?}"
        );
        self.0 = self.0.merge(c);
    }

    fn drain(&mut self, rec: &mut Recorder) {
        rec.contact_check = rec.contact_check.merge(std::mem::take(&mut self.0));
    }
}
