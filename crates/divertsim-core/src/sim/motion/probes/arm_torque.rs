//! The arm-torque probe: at every accepted state while the arm moves, the parcel's torque
//! on the arm about its pivot, M_c = −(G × F + M_G) for the arm contacts' force F and
//! moment M_G on the parcel (0 without an arm contact); the arm's loads are built from it
//! ([`crate::sim::arm_loads`]).

use super::super::dynamics::Dynamics;
use super::Probe;
use crate::sim::recorder::Recorder;

/// (t, M_c) at the accepted steps since the last drain \[s, N·m].
#[derive(Debug, Default)]
pub(crate) struct ArmTorque(Vec<(f64, f64)>);

impl Probe for ArmTorque {
    #[cfg(test)]
    fn name(&self) -> &'static str {
        "arm torque"
    }

    fn at_step(&mut self, d: &Dynamics, t: f64, y: &[f64; 6]) {
        let torque = if d.contacts.iter().any(|c| c.kind.is_arm()) {
            let f = d.evaluated(t, y, |e| e.arm);
            -(y[0] * f[1] - y[1] * f[0] + f[2])
        } else {
            0.0
        };
        if torque.is_finite() {
            self.0.push((t, torque));
        }
    }

    fn drain(&mut self, rec: &mut Recorder) {
        rec.arm_torque.append(&mut self.0);
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::{ActiveContact, Motion};
    use crate::model::active_set::Tangential;
    use crate::model::contact::{self, ContactKind};
    use crate::model::params::Scenario;
    use crate::sim::context::{arm_state, Context};
    use glam::DVec2;

    /// A corner pushed by the arm's face and sliding along it: the parcel's torque on the
    /// arm about the pivot is the normal force times its lever, the corner's distance
    /// from the pivot, and the friction along the face (through the pivot) adds no moment:
    /// M_c = −λ_n s (issue 26).
    #[test]
    fn a_corner_on_the_face_loads_the_arm_with_its_normal_force_times_its_lever() {
        let ctx = Context::new(&Scenario::paper_default()).unwrap();
        let mut m = Motion::new(&ctx, [1; 4]);
        let t = 0.05;
        let arm = arm_state(&ctx, t);
        // Corner 3 on the working face at s = 0.5 m from the pivot, the parcel sliding
        // along the face with the belt.
        let (sa, ca) = arm.angle.sin_cos();
        let rho = crate::geometry::rotate(
            Scenario::paper_default().footprint().body_corners()[3],
            0.1 + arm.angle,
        );
        let q = DVec2::new(0.5 * ca, 0.5 * sa);
        let y = [q.x - rho.x, q.y - rho.y, 0.1 + arm.angle, 2.0, 0.0, 0.0];
        let kind = ContactKind::CornerArm { corner: 3, side: 1 };
        let fr = contact::frame(kind, &ctx.kinematics(t, &y));
        assert!(fr.gap.abs() < 1e-12, "{fr:?}");
        let slide = Tangential::Slide(fr.slip.signum());
        m.configure(false, &[ActiveContact { kind, mode: slide }], t, &y);
        let e = m.dynamics.evaluate(t, &y);
        let normal = e.normal_force[0];
        assert!(normal > 0.0, "the arm pushes: {e:?}");
        assert!(
            e.tangential_force[0].abs() > 0.1 * normal,
            "friction acts: {e:?}"
        );
        // What the probe records at that state.
        let mut probe = super::ArmTorque::default();
        super::Probe::at_step(&mut probe, &m.dynamics, t, &y);
        let torque = probe.0[0].1;
        assert!(
            (torque + normal * 0.5).abs() < 1e-9 * normal,
            "M_c = {torque}, −λ_n s = {}",
            -normal * 0.5
        );
    }
}
