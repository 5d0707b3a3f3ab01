//! Drift removal of held contacts: the motion holds a persistent contact at the acceleration
//! level, so its gap drifts with the integration error; this puts the parcel back onto its
//! obstacles, at events (`settle`) and between the motion's steps (`Motion::project`).
//! docs/model.md §6 (the contact-pair rule) and §7 (drift).

use super::context::Context;
use super::tolerances::{DRIFT_TOL, END_TOL, HELD_GAP_TOL};
use crate::model::active_set::{self, Body, ContactRow};
use crate::model::contact::{self, ContactKind};
use crate::model::drive::ArmState;

/// Puts the contacts held until this event back on their obstacles: the smallest move of the
/// parcel (in the metric of its mass matrix, 𝕄⁻¹Jᵀ(J𝕄⁻¹Jᵀ)⁻¹(−g)) that closes the gaps g of
/// the held contacts still on their obstacles (within [`END_TOL`] of their ends) and within
/// [`HELD_GAP_TOL`], if any of them drifted beyond [`DRIFT_TOL`], leaving the gaps of the
/// pairs `keep` as they are (if the body cannot do both, nothing moves).
///
/// The motion holds a persistent contact at the acceleration level (g̈ = 0), so its gap
/// drifts with the integration error: by up to 6e-7 m over a long push at tolerance 1e-8,
/// beyond the closed-contact tolerance, and a side resting on the arm then lost its far
/// corner at the next event and met it again with a small strike. The drift is removed at
/// events and between the motion's steps (`Motion::project`); holding it in the motion
/// instead (Baumgarte's g̈ = −2Ωġ − Ω²g) cost ten times the steps. Returns whether `y`
/// moved.
pub(crate) fn remove_drift(
    ctx: &Context,
    arm: ArmState,
    y: &mut [f64; 6],
    held: &[ContactKind],
    keep: &[ContactKind],
) -> bool {
    if held.is_empty() {
        return false;
    }
    let kin = ctx.kinematics_with(arm, y);
    let mut rows: Vec<ContactRow> = held
        .iter()
        .map(|&k| contact::frame(k, &kin))
        // On its obstacle, or just past an end (the event of a corner passing the arm's tip
        // comes a hair beyond it; its drift is the one its successor, the tip, inherits).
        .filter(|f| {
            f.gap.abs() <= HELD_GAP_TOL
                && f.along >= f.extent.0 - END_TOL
                && f.along <= f.extent.1 + END_TOL
        })
        .map(|f| ContactRow {
            normal: f.jacobian,
            beta: -f.gap,
            tangent: f.jacobian_t,
            beta_t: 0.0,
            friction: 0.0,
            slip: 0.0,
        })
        .collect();
    if rows.iter().all(|r| r.beta.abs() <= DRIFT_TOL) {
        return false;
    }
    // Pairs whose gaps must not change (touching pairs the motion watches: moved across
    // their guard's root between two steps, they would sink in unseen).
    rows.extend(keep.iter().map(|&k| {
        let f = contact::frame(k, &kin);
        ContactRow {
            normal: f.jacobian,
            beta: 0.0,
            tangent: f.jacobian_t,
            beta_t: 0.0,
            friction: 0.0,
            slip: 0.0,
        }
    }));
    let free = Body {
        mass: ctx.mass,
        inertia: ctx.inertia,
        external: [0.0; 3],
    };
    let modes = vec![Some(active_set::Tangential::Slide(1.0)); rows.len()];
    let Some(dq) = active_set::solve(&free, &rows, &modes) else {
        return false;
    };
    y[0] += dq.accel[0];
    y[1] += dq.accel[1];
    y[2] += dq.accel[2];
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::params::Scenario;

    /// The default parcel (0.4 × 0.26 m) lying on the retracted arm (α = 0, the arm along
    /// the x axis from the pivot), its long side `lift` above the arm and turned by `tilt`.
    fn on_the_arm(lift: f64, tilt: f64) -> (Context, ArmState, [f64; 6], Vec<ContactKind>) {
        let s = Scenario::paper_default();
        let ctx = Context::new(&s).unwrap();
        let arm = ArmState {
            angle: 0.0,
            rate: 0.0,
            accel: 0.0,
        };
        let b = s.parcel.width;
        let y = [0.5, 0.5 * b + lift, tilt, 0.0, 0.0, 0.0];
        // The two corners nearest the arm's working face.
        let kin = ctx.kinematics_with(arm, &y);
        let mut corners: Vec<(f64, ContactKind)> = (0..4)
            .map(|corner| {
                let k = ContactKind::CornerArm { corner, side: 1 };
                (contact::frame(k, &kin).gap, k)
            })
            .collect();
        corners.sort_by(|a, b| a.0.total_cmp(&b.0));
        let held = corners.iter().take(2).map(|c| c.1).collect();
        (ctx, arm, y, held)
    }

    fn gaps(ctx: &Context, arm: ArmState, y: &[f64; 6], held: &[ContactKind]) -> Vec<f64> {
        let kin = ctx.kinematics_with(arm, y);
        held.iter().map(|&k| contact::frame(k, &kin).gap).collect()
    }

    #[test]
    fn a_drifted_resting_side_is_put_back_on_the_arm() {
        // Lifted and turned: the two corners drifted apart by different amounts, both
        // beyond DRIFT_TOL and within HELD_GAP_TOL.
        let (ctx, arm, mut y, held) = on_the_arm(4e-6, 1e-5);
        let before = gaps(&ctx, arm, &y, &held);
        assert!(
            before.iter().all(|g| *g > DRIFT_TOL && *g < HELD_GAP_TOL),
            "{before:?}"
        );
        assert!(remove_drift(&ctx, arm, &mut y, &held, &[]));
        // One linearised step: what is left is quadratic in the move (~1e-11 m here), three
        // orders below the tolerance that would trigger another.
        for g in gaps(&ctx, arm, &y, &held) {
            assert!(g.abs() < 1e-3 * DRIFT_TOL, "gap left: {g}");
        }
        // Only the position moves; the velocity is the motion's.
        assert_eq!(&y[3..], &[0.0; 3]);
    }

    #[test]
    fn a_gap_within_the_drift_tolerance_is_left_alone() {
        let (ctx, arm, mut y, held) = on_the_arm(0.5 * DRIFT_TOL, 0.0);
        let y0 = y;
        assert!(!remove_drift(&ctx, arm, &mut y, &held, &[]));
        assert_eq!(y, y0);
        assert!(!remove_drift(&ctx, arm, &mut y, &[], &[]));
    }

    #[test]
    fn a_parcel_off_the_arm_is_not_pulled_back() {
        // Beyond HELD_GAP_TOL the pair is no longer on its obstacle: nothing to hold.
        let (ctx, arm, mut y, held) = on_the_arm(10.0 * HELD_GAP_TOL, 0.0);
        let y0 = y;
        assert!(!remove_drift(&ctx, arm, &mut y, &held, &[]));
        assert_eq!(y, y0);
    }
}
