//! Probes: what a run measures of its motion besides the trajectory, each behind one small
//! trait. A probe sees the accepted states (step starts) and the run's moments (the end of
//! a stretch at an event, a closed-form tail, a strike, the unloaded ride-out) and gives
//! what it measured to the run's record at the end of every stretch. A run registers the
//! probes its scenario asks for ([`Probes::for_run`]); the dynamics and the guards know none
//! of them.
//!
//! - [`contact_forces::ContactForces`]: the active contacts' forces against their laws
//!   (λ_n ≥ 0, the cone, friction against the slip) and the drift of their gaps;
//! - [`tipping::Tipping`]: the lift-off margin and the tilt about a footprint edge, which
//!   may end the run (docs/model.md, tipping);
//! - [`arm_torque::ArmTorque`]: the parcel's torque on the arm about its pivot.

pub mod arm_torque;
pub mod contact_forces;
pub mod tipping;

use super::dynamics::Dynamics;
use crate::sim::context::Context;
use crate::sim::recorder::Recorder;
use glam::DVec2;

/// One measurement of a run.
pub(crate) trait Probe {
    /// What it measures, in a few words (for the registration's tests).
    #[cfg(test)]
    fn name(&self) -> &'static str;

    /// An accepted state (t, y): a step's start.
    fn at_step(&mut self, d: &Dynamics, t: f64, y: &[f64; 6]);

    /// The last state of a stretch, just before the event that ends it.
    fn at_stretch_end(&mut self, _d: &Dynamics, _t: f64, _y: &[f64; 6]) {}

    /// The motion went on in closed form to `t` (a free slide's last sliver).
    fn at_tail(&mut self, _t: f64) {}

    /// A strike at `t` gave the parcel, now at angle `phi`, the impulse `impulse` \[N·s].
    fn at_strike(&mut self, _t: f64, _phi: f64, _impulse: DVec2) {}

    /// The parcel rides on unloaded from `t`, for at most `horizon` seconds: whether that
    /// ends the run (the box goes over).
    fn ride_out(&mut self, _t: f64, _horizon: f64) -> bool {
        false
    }

    /// Whether the run must stop now.
    fn halt(&self) -> bool {
        false
    }

    /// Give what was measured since the last call to the run's record.
    fn drain(&mut self, rec: &mut Recorder);
}

/// The probes registered for one run, called in registration order.
pub(crate) struct Probes<'a>(Vec<Box<dyn Probe + 'a>>);

impl<'a> Probes<'a> {
    /// What the scenario asks for: the contact forces always, the tipping with a tipping
    /// geometry (a parcel of some height), the arm torque with an arm.
    pub fn for_run(ctx: &'a Context) -> Self {
        let mut probes: Vec<Box<dyn Probe + 'a>> =
            vec![Box::new(contact_forces::ContactForces::default())];
        if let Some(geo) = ctx.tip {
            probes.push(Box::new(tipping::Tipping::new(geo, ctx.tip_rule)));
        }
        if ctx.drive.is_some() {
            probes.push(Box::new(arm_torque::ArmTorque::default()));
        }
        Probes(probes)
    }

    pub fn at_step(&mut self, d: &Dynamics, t: f64, y: &[f64; 6]) {
        for p in &mut self.0 {
            p.at_step(d, t, y);
        }
    }

    pub fn at_stretch_end(&mut self, d: &Dynamics, t: f64, y: &[f64; 6]) {
        for p in &mut self.0 {
            p.at_stretch_end(d, t, y);
        }
    }

    pub fn at_tail(&mut self, t: f64) {
        for p in &mut self.0 {
            p.at_tail(t);
        }
    }

    pub fn at_strike(&mut self, t: f64, phi: f64, impulse: DVec2) {
        for p in &mut self.0 {
            p.at_strike(t, phi, impulse);
        }
    }

    /// Whether any probe ends the run during the ride-out (every probe rides out).
    pub fn ride_out(&mut self, t: f64, horizon: f64) -> bool {
        let mut ends = false;
        for p in &mut self.0 {
            ends |= p.ride_out(t, horizon);
        }
        ends
    }

    pub fn halt(&self) -> bool {
        self.0.iter().any(|p| p.halt())
    }

    pub fn drain(&mut self, rec: &mut Recorder) {
        for p in &mut self.0 {
            p.drain(rec);
        }
    }

    /// The registered probes' names, in order.
    #[cfg(test)]
    pub fn names(&self) -> Vec<&'static str> {
        self.0.iter().map(|p| p.name()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::params::Scenario;

    /// The default scenario asks for all three; without the arm's motion (run.arm = false)
    /// no arm torque; with the arm's face passing over the parcel no tipping and no arm.
    #[test]
    fn a_run_registers_only_the_probes_its_scenario_asks_for() {
        let names = |s: &Scenario| Probes::for_run(&Context::new(s).unwrap()).names();
        let s = Scenario::paper_default();
        assert_eq!(names(&s), ["contact forces", "tipping", "arm torque"]);
        let mut still = s.clone();
        still.run.arm = false;
        assert_eq!(names(&still), ["contact forces", "tipping"]);
        let mut over = s.clone();
        over.machine.arm_face_bottom = 2.0 * s.parcel.height;
        over.machine.arm_face_top = 3.0 * s.parcel.height;
        assert_eq!(names(&over), ["contact forces"]);
    }
}
