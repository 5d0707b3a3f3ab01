//! Drift removal of held contacts: the motion holds a persistent contact at the acceleration
//! level, so its gap drifts with the integration error; this puts the parcel back onto its
//! obstacles, at events (`settle`) and between the motion's steps (`Motion::project`).
//! physics.md §5.7; docs/model.md "Which pairs are contacts".

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
