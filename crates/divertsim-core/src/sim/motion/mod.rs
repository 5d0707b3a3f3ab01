//! The smooth motion between events, for every mode: riding (no slip, closed form), free
//! sliding F2, and sliding with an active set of arm / guide / tip contacts (F4, F5, F6,
//! ...). One right-hand side and one guard list per mode (docs/model.md §6: every stage is an
//! active set of vertex–line and tip–edge contacts). State y = (x, y, φ, ẋ, ẏ, ω) in
//! frame-fixed axes (docs/model.md §4).
//!
//! [`Motion`] is the integrator's [`HybridSystem`], made of parts:
//! - [`dynamics`]: the mode's right-hand side and what an instant of it yields;
//! - [`contacts`]: the contact set and the pair logic (when a pair touches);
//! - [`guards`]: which conditions the mode watches and what the event locator may assume
//!   of them;
//! - [`cache`]: the per-instant rings the guards and probes read;
//! - [`probes`]: the measurements a run asks for (contact forces, tipping, arm torque).

mod cache;
mod contacts;
mod dynamics;
mod guards;
pub(crate) mod probes;

pub use contacts::ActiveContact;
pub use guards::Watch;

use super::context::Context;
use super::recorder::Recorder;
use crate::integrate::{Direction, HybridSystem, StepBounds};
use dynamics::Dynamics;
use glam::DVec2;
use guards::Guards;
use probes::Probes;

/// The hybrid system of one mode, and the run's probes.
pub struct Motion<'a> {
    dynamics: Dynamics<'a>,
    guards: Guards,
    probes: Probes<'a>,
    /// Which face of the arm each corner is on (+1 working face, −1 back face).
    pub sides: [i8; 4],
}

impl<'a> Motion<'a> {
    /// The motion of a run of `ctx`, with the probes its scenario asks for.
    pub fn new(ctx: &'a Context, sides: [i8; 4]) -> Self {
        Motion {
            dynamics: Dynamics::new(ctx),
            guards: Guards::new(),
            probes: Probes::for_run(ctx),
            sides,
        }
    }

    /// Set the mode at (t, y): riding or not, and the active contacts.
    pub fn configure(&mut self, riding: bool, active: &[ActiveContact], t: f64, y: &[f64; 6]) {
        self.dynamics.set_mode(riding, active);
        self.guards.configure(&self.dynamics, self.sides, t, y);
    }

    /// Riding with the belt (no contacts).
    pub fn riding(&self) -> bool {
        self.dynamics.riding
    }

    /// The active contacts.
    pub fn active(&self) -> impl Iterator<Item = &ActiveContact> {
        self.dynamics.contacts.iter()
    }

    /// After an event of guard `i` that changed nothing ([`Guards::mute`]).
    pub fn mute(&mut self, i: usize) {
        self.guards.mute(self.dynamics.ctx.weight, i);
    }

    /// What guard `i` watches.
    pub fn watch(&self, i: usize) -> Watch {
        self.guards.watch(i)
    }

    /// The index of the first guard watching `watch`.
    pub fn guard_of(&self, watch: Watch) -> Option<usize> {
        self.guards.of(watch)
    }

    /// The end of a free slide in closed form ([`Dynamics::stop_tail`]).
    pub fn stop_tail(&self, t: f64, y: &[f64; 6]) -> (f64, [f64; 6]) {
        self.dynamics.stop_tail(t, y)
    }

    /// The end of a stretch at an event: the probes see the state just before it.
    pub fn close_stretch(&mut self, t: f64, y: &[f64; 6]) {
        self.probes.at_stretch_end(&self.dynamics, t, y);
    }

    /// The motion went on in closed form to `t`.
    pub fn tail_to(&mut self, t: f64) {
        self.probes.at_tail(t);
    }

    /// A strike at `t` gave the parcel, now at angle `phi`, the impulse `impulse`.
    pub fn strike(&mut self, t: f64, phi: f64, impulse: DVec2) {
        self.probes.at_strike(t, phi, impulse);
    }

    /// The parcel rides on unloaded from `t` (at most `horizon` s): whether a probe ends the
    /// run.
    pub fn ride_out(&mut self, t: f64, horizon: f64) -> bool {
        self.probes.ride_out(t, horizon)
    }

    /// Whether a probe has ended the run (a box gone over under the verdict rule).
    pub fn stopped_by_probe(&self) -> bool {
        self.probes.halt()
    }

    /// Give the probes' measurements since the last call to the run's record.
    pub(crate) fn drain(&mut self, rec: &mut Recorder) {
        self.probes.drain(rec);
    }
}

impl HybridSystem<6> for Motion<'_> {
    fn rhs(&self, t: f64, y: &[f64; 6]) -> [f64; 6] {
        self.dynamics.rhs(t, y)
    }

    fn guard_count(&self) -> usize {
        self.guards.count()
    }

    fn guard(&self, i: usize, t: f64, y: &[f64; 6]) -> f64 {
        self.guards.value(&self.dynamics, i, t, y)
    }

    fn guard_speed_limit(&self, i: usize, b: &StepBounds<6>) -> f64 {
        self.guards.speed_limit(&self.dynamics, i, b)
    }

    fn guard_may_dip(&self, i: usize, b: &StepBounds<6>) -> bool {
        self.guards.may_dip(&self.dynamics, i, b)
    }

    fn guard_curvature_limit(&self, i: usize, b: &StepBounds<6>) -> f64 {
        self.guards.curvature_limit(&self.dynamics, i, b)
    }

    fn guard_direction(&self, _i: usize) -> Direction {
        Direction::Falling
    }

    /// `begin_step` only moves d_ref, which changes the right-hand side past a belt stop,
    /// never at the step's initial point: the derivative there can be reused.
    fn begin_step_changes_rhs(&self) -> bool {
        false
    }

    fn stiffness(&self, _t: f64, y: &[f64; 6]) -> f64 {
        self.dynamics.stiffness(y)
    }

    fn time_to_singularity(&self, t: f64, y: &[f64; 6]) -> f64 {
        self.dynamics.time_to_singularity(t, y)
    }

    fn project(&mut self, t: f64, y: &mut [f64; 6]) -> bool {
        self.dynamics.project(t, y, self.guards.watched_gaps())
    }

    fn halt(&self) -> bool {
        self.probes.halt()
    }

    /// The probes see the accepted state first; then the guards are made ready for the step
    /// from it.
    fn begin_step(&mut self, t: f64, y: &[f64; 6]) {
        self.probes.at_step(&self.dynamics, t, y);
        self.guards.rearm_separated_gaps(&self.dynamics, t, y);
        self.dynamics.begin_step(y);
        self.guards.begin_step(&self.dynamics, t, y);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::contact::ContactKind;
    use crate::model::params::Scenario;
    use crate::sim::tolerances::{GAP_MARGIN, GAP_TOL, SEPARATING_BASE};

    /// The default parcel tilted by 0.1 rad, its lowest corner (3) `lift` above the retracted
    /// arm's line y = 0 at x = 0.5.
    fn state(lift: f64) -> [f64; 6] {
        let s = Scenario::paper_default();
        let rho = crate::geometry::rotate(s.footprint().body_corners()[3], 0.1);
        [0.5 - rho.x, lift - rho.y, 0.1, 2.0, 0.0, 0.0]
    }

    /// A gap guard muted after touches that changed nothing (a pair hovering at its root, as
    /// the tip at a parcel corner does) is watched again once the pair is clearly apart, even
    /// if it never crossed: muted for good, it let a later tip strike go unseen (issue
    /// "Contacts that hold, round two").
    #[test]
    fn a_muted_gap_guard_is_watched_again_once_apart() {
        let ctx = Context::new(&Scenario::paper_default()).unwrap();
        let mut m = Motion::new(&ctx, [1; 4]);
        let y0 = state(0.0);
        m.configure(false, &[], 0.0, &y0);
        let kind = ContactKind::CornerArm { corner: 3, side: 1 };
        let i = m
            .guard_of(Watch::Gap(kind))
            .expect("the corner's gap guard");
        // Touches that change nothing: re-armed deeper, then muted.
        while !m.guards.is_muted(i) {
            m.mute(i);
        }
        assert_eq!(m.guard(i, 0.0, &y0), -1.0);
        // A hair apart (within the closed-contact tolerance): still muted.
        let near = state(0.5 * GAP_TOL);
        m.begin_step(0.0, &near);
        assert_eq!(m.guard(i, 0.0, &near), -1.0, "re-armed while touching");
        // Clearly apart: watched again, at the normal margin.
        let apart = state(1e-6);
        m.begin_step(0.0, &apart);
        assert!(!m.guards.is_muted(i) && m.guards.extra(i) == 0.0);
        let g = m.guard(i, 0.0, &apart);
        assert!((g - (1e-6 + GAP_MARGIN)).abs() < 1e-12, "guard {g}");
    }

    /// A pair just struck and rebounding starts its guard strictly on the pre-side by a
    /// negligible depth; a touching pair that does not separate by half the margin.
    #[test]
    fn a_rebounding_pair_is_rebased_by_a_negligible_depth() {
        let ctx = Context::new(&Scenario::paper_default()).unwrap();
        let kind = ContactKind::CornerArm { corner: 3, side: 1 };
        for (vy, base) in [(0.5, SEPARATING_BASE), (0.0, 0.5 * GAP_MARGIN)] {
            let mut y = state(-GAP_MARGIN);
            y[3] = 0.0;
            y[4] = vy;
            let mut m = Motion::new(&ctx, [1; 4]);
            m.configure(false, &[], 0.0, &y);
            let i = m.guard_of(Watch::Gap(kind)).unwrap();
            let g = m.guard(i, 0.0, &y);
            assert!(
                (g - base).abs() < 1e-15,
                "v_y {vy}: guard starts at {g}, not {base}"
            );
        }
    }
}
