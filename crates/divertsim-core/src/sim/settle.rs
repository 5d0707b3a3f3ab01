//! What happens at an event instant (physics.md §5.6): first every closed, approaching
//! contact is struck (Stronge's impact map, §2.4), then the contacts left closed get their
//! active set (which carry force, which stick or slide; §5.2, §5.7), and the belt decides
//! between riding and sliding (§3.5).
//!
//! **Strikes.** Closed contacts (gap ≤ [`GAP_TOL`], point within its obstacle) approaching
//! faster than [`SPEED_TOL`] are struck one at a time, the fastest first, until none
//! approaches (a multi-point or flush strike thus becomes a short sequence, as in
//! sequential-impulse solvers). A contact struck again within the same instant, and any
//! strike slower than [`PERSIST_SPEED`], is plastic (e = 0): the contact then persists. This
//! is the paper's F3 "without rebound" and it stops low-speed re-impacts from chattering.
//! All impulses of one instant are reported as one strike.

use super::context::Context;
use super::motion::{slip_of, ActiveContact};
use super::result::{Impact, Obstacle, Stage};
use super::ride;
use crate::model::active_set::{self, Body, ContactRow, Tolerances};
use crate::model::contact::{self, ContactFrame, ContactKind};
use crate::model::drive::ArmState;
use crate::model::impact::{body_velocity_change, resolve, ImpactInput, Mobility};
use glam::DVec2;

/// A contact within this gap counts as closed [m].
pub const GAP_TOL: f64 = 1e-7;
/// A closed contact approaching faster than this is struck [m/s].
pub const SPEED_TOL: f64 = 1e-8;
/// A closed contact separating slower than this still enters the active-set problem (it may
/// be accelerating back in) [m/s].
pub const CLOSE_SPEED: f64 = 1e-3;
/// Approach speed below which a strike is plastic and the contact persists [m/s].
pub const PERSIST_SPEED: f64 = 0.01;
/// Approach speed below which a contact held until the event is taken as drifting (the
/// integration error of a persistent contact), not struck: the projection takes it up [m/s].
pub const HELD_DRIFT: f64 = 1e-4;
/// Bound on the rounds of active-set selection and velocity projection at one instant.
pub const MAX_PROJECTIONS: usize = 4;
/// Bound on strikes at one instant.
pub const MAX_STRIKES: usize = 64;
/// Belt slip below which a parcel without contacts rides [m/s].
pub const RIDE_SLIP: f64 = 1e-6;

/// The mode after an event (its stage label is [`stage_of`]).
#[derive(Debug, Clone)]
pub struct Settled {
    pub riding: bool,
    pub active: Vec<ActiveContact>,
    /// The strike at this instant, if any (its `stage` is left for the caller to set).
    pub impact: Option<Impact>,
}

/// The obstacle of a contact pair.
pub fn obstacle_of(kind: ContactKind) -> Obstacle {
    match kind {
        ContactKind::CornerArm { side, .. } if side < 0 => Obstacle::ArmBack,
        ContactKind::CornerArm { .. } => Obstacle::ArmFace,
        ContactKind::CornerGuide { .. } => Obstacle::Guide,
        ContactKind::TipEdge { .. } => Obstacle::ArmTip,
    }
}

/// The stage label of an active set (physics.md §5.7: F4 = one corner on the arm,
/// F5 = two, F6 = arm + guide).
pub fn stage_of(riding: bool, active: &[ActiveContact]) -> Stage {
    let arm = active
        .iter()
        .filter(|c| matches!(c.kind, ContactKind::CornerArm { .. }))
        .count();
    let guide = active
        .iter()
        .filter(|c| matches!(c.kind, ContactKind::CornerGuide { .. }))
        .count();
    let tip = active
        .iter()
        .filter(|c| matches!(c.kind, ContactKind::TipEdge { .. }))
        .count();
    match (arm, guide, tip) {
        (0, 0, 0) if riding => Stage::Ride,
        (0, 0, 0) => Stage::F2,
        (1, 0, 0) => Stage::F4,
        (2, 0, 0) => Stage::F5,
        (1, _, 0) => Stage::F6,
        (2, _, 0) => Stage::F5Guide,
        (0, _, 0) => Stage::Guide,
        (0, 0, _) => Stage::Tip,
        (0, _, _) => Stage::TipGuide,
        (1, 0, 1) => Stage::ArmTip,
        _ => Stage::Contact,
    }
}

/// Deepest gap still taken as a touching contact (it is struck if approaching) [m].
pub const DEEPEST_GAP: f64 = -5e-7;

/// How far past its obstacle's end a contact point still counts as on it [m] (a parcel
/// corner a hair beyond the arm tip is the corner-on-tip contact, not no contact). The
/// range guards fire further out ([`super::motion::RANGE_MARGIN`]).
pub const RANGE_TOL: f64 = 1e-7;

/// How far a tip–edge pair's gap may fall short of the nearest edge's and still count as
/// between nearest features [m] (exact ties: the tip at a corner).
pub const NEAREST_TOL: f64 = 1e-10;

/// Whether pair `kind` with frame `f` is a closed contact: the gap within
/// [[`DEEPEST_GAP`], [`GAP_TOL`]], the point on its obstacle, and the features nearest each
/// other (the one contact-pair rule; see [`contact::tip_edge_shortfall`]).
fn closed(kind: ContactKind, f: &ContactFrame, kin: &contact::Kinematics) -> bool {
    f.gap <= GAP_TOL
        && f.gap >= DEEPEST_GAP
        && f.along >= f.extent.0 - RANGE_TOL
        && f.along <= f.extent.1 + RANGE_TOL
        && match kind {
            ContactKind::TipEdge { edge } => contact::tip_edge_shortfall(edge, kin) <= NEAREST_TOL,
            _ => true,
        }
}

/// The closed contacts (gap in [[`DEEPEST_GAP`], [`GAP_TOL`]], point on its obstacle). The arm tip at a
/// parcel corner that is itself closed on the arm is one contact, not two: the corner–arm
/// pair is kept and the tip–edge pairs at that corner dropped (they would strike or
/// constrain the same point twice).
fn closed_frames(
    candidates: &[ContactKind],
    kin: &contact::Kinematics,
) -> Vec<(ContactKind, ContactFrame)> {
    let mut set: Vec<(ContactKind, ContactFrame)> = candidates
        .iter()
        .map(|&k| (k, contact::frame(k, kin)))
        .filter(|(k, f)| closed(*k, f, kin))
        .collect();
    let corner_at_tip = set
        .iter()
        .any(|(k, f)| matches!(k, ContactKind::CornerArm { .. }) && f.extent.1 - f.along < 1e-6);
    if corner_at_tip {
        set.retain(|(k, f)| {
            !(matches!(k, ContactKind::TipEdge { .. })
                && (f.along - f.extent.0 < 1e-6 || f.extent.1 - f.along < 1e-6))
        });
    }
    set
}

/// The riding state at an event with belt slip within the regularisation scale, if riding
/// is consistent with the closed contacts: riding (q̈ = 0) accelerates none of them into
/// penetration (g̈ = −β ≥ 0 at the riding velocity), and none approaches at the riding
/// velocity, or one approaches but is opening (g̈ > 0) so fast that it would touch at most
/// [`TAIL_DEPTH`] deep.
///
/// The last case is the end of a contact held by a receding arm (fault 2 of "Contacts that
/// hold"): under exact Coulomb friction the arm holds the parcel back, with a compressive
/// force, until it recedes as fast as the belt carries the parcel (after −u_n/g̈), and the
/// parcel then sticks to the belt. That tail is closed in closed form, as the free slide's
/// last 1e-7 m/s are: the parcel rides from a position held back by the tail's depth
/// u_n²/(2 g̈) along the contact normal, so that the riding parcel just grazes the contact.
/// Integrating the tail instead would meet the regularised friction, which at that slip is
/// too weak to hold the parcel against the contact and makes the arm pull.
///
/// A pair touching with g = ġ = g̈ = 0 while riding (a corner at the arm's root as the arm
/// starts from rest) is judged a moment later, [`LOOK_AHEAD`]: if riding would then push it
/// in, the contact is kept instead of letting it be met by a strike of a few µm/s.
fn ride_with_contacts(
    ctx: &Context,
    (arm, arm_ahead): (ArmState, ArmState),
    y: &[f64; 6],
    closed_set: &[(ContactKind, ContactFrame)],
) -> Option<[f64; 6]> {
    let mut riding_y = ride::snap(y, ctx.belt_speed);
    let kin_r = ctx.kinematics_with(arm, &riding_y);
    let kin_ahead = ctx.kinematics_with(
        arm_ahead,
        &ride::advance(&riding_y, LOOK_AHEAD, ctx.belt_speed),
    );
    let mut shift = DVec2::ZERO;
    for (kind, _) in closed_set {
        let f = contact::frame(*kind, &kin_r);
        let g_ddot = -f.beta;
        if g_ddot < -1e-9 {
            return None;
        }
        if g_ddot <= 1e-9
            && f.normal_speed.abs() <= SPEED_TOL
            && -contact::frame(*kind, &kin_ahead).beta < -1e-9
        {
            return None;
        }
        if f.normal_speed < -SPEED_TOL {
            // Approaching: only a pair that is opening (g̈ > 0) lets the parcel go.
            if g_ddot <= 0.0 {
                return None;
            }
            let depth = f.normal_speed * f.normal_speed / (2.0 * g_ddot);
            if !(0.0..=TAIL_DEPTH).contains(&depth) {
                return None;
            }
            shift += depth * f.normal;
        }
    }
    riding_y[0] += shift.x;
    riding_y[1] += shift.y;
    Some(riding_y)
}

/// How far ahead a degenerate riding contact is judged ([`ride_with_contacts`]) [s].
pub const LOOK_AHEAD: f64 = 1e-6;

/// Deepest approach of a riding parcel to a receding contact that is closed in closed
/// form ([`ride_with_contacts`]) [m].
pub const TAIL_DEPTH: f64 = 0.5 * GAP_TOL;

/// Resolve the event at (t, y): strikes, active set, riding. `y` is updated in place.
/// `arm_at`: the arm's state at a time as the motion after the event sees it (at rest from
/// the end of its cycle on, although the drive's last instant still carries the cycle's α̈).
/// `held`: the contacts active until this instant.
/// `touched`: the contact whose gap just closed, if that was the event (it is preferred
/// active: it touches, and leaving it out at the tolerance boundary lets it creep in).
pub fn settle(
    ctx: &Context,
    t: f64,
    y: &mut [f64; 6],
    sides: [i8; 4],
    touched: Option<ContactKind>,
    held: &[ContactKind],
    arm_at: &dyn Fn(f64) -> ArmState,
) -> Result<Settled, String> {
    let arm = arm_at(t);
    let candidates: Vec<ContactKind> = contact::candidates(sides)
        .into_iter()
        .filter(|&k| ctx.candidate_enabled(k))
        .collect();

    // 1. Strikes.
    let mut impact: Option<Impact> = None;
    let mut struck: Vec<ContactKind> = Vec::new();
    // Contacts struck plastically at this instant: they persist (u_n = 0 after the strike).
    let mut persisting: Vec<ContactKind> = Vec::new();
    let mut total = DVec2::ZERO;
    let mut first_basis = (DVec2::X, DVec2::Y);
    for _ in 0..MAX_STRIKES {
        let kin = ctx.kinematics_with(arm, y);
        let hit = closed_frames(&candidates, &kin)
            .into_iter()
            // A contact held until this instant that drifts in slower than HELD_DRIFT
            // is not hit: it persists, and the projection below takes up its drift.
            .filter(|(k, f)| {
                f.normal_speed < -SPEED_TOL && !(held.contains(k) && -f.normal_speed < HELD_DRIFT)
            })
            .min_by(|a, b| a.1.normal_speed.total_cmp(&b.1.normal_speed));
        let Some((kind, fr)) = hit else { break };
        let plastic = struck.contains(&kind) || -fr.normal_speed < PERSIST_SPEED;
        let input = ImpactInput {
            mobility: Mobility::at_contact(ctx.mass, ctx.inertia, fr.r, fr.normal),
            u_t0: fr.slip,
            u_n0: fr.normal_speed,
            friction: ctx.arm_friction,
            restitution: if plastic { 0.0 } else { ctx.restitution },
            law: ctx.impact_law,
        };
        let out = resolve(&input).map_err(|e| format!("strike at t = {t} s failed: {e}"))?;
        let jump = body_velocity_change(
            ctx.mass,
            ctx.inertia,
            fr.r,
            fr.normal,
            out.normal_impulse,
            out.tangential_impulse,
        );
        y[3] += jump.dv.x;
        y[4] += jump.dv.y;
        y[5] += jump.domega;
        total += out.impulse_vector(fr.normal);
        match &mut impact {
            None => {
                first_basis = (fr.tangent, fr.normal);
                impact = Some(Impact {
                    t,
                    stage: Stage::F1,
                    obstacle: obstacle_of(kind),
                    point: [fr.point.x, fr.point.y],
                    normal_impulse: 0.0,
                    tangential_impulse: 0.0,
                    impulse: 0.0,
                    approach_speed: -fr.normal_speed,
                    compression_work: out.compression_work,
                    dissipated: out.dissipated,
                    persistent: plastic,
                });
            }
            Some(imp) => {
                imp.compression_work += out.compression_work;
                imp.dissipated += out.dissipated;
            }
        }
        struck.push(kind);
        if plastic {
            persisting.push(kind);
        }
        if struck.len() >= MAX_STRIKES {
            return Err(format!(
                "strikes at t = {t} s did not settle after {MAX_STRIKES} impulses"
            ));
        }
    }
    if let Some(imp) = &mut impact {
        imp.normal_impulse = total.dot(first_basis.1);
        imp.tangential_impulse = total.dot(first_basis.0);
        imp.impulse = total.length();
    }

    // 2. Active set among the closed contacts.
    let kin = ctx.kinematics_with(arm, y);
    let mut closed_set: Vec<(ContactKind, ContactFrame)> = closed_frames(&candidates, &kin)
        .into_iter()
        .filter(|(_, f)| f.normal_speed <= CLOSE_SPEED)
        .collect();
    closed_set.sort_by(|a, b| a.1.gap.abs().total_cmp(&b.1.gap.abs()));
    closed_set.truncate(active_set::MAX_CONTACTS);
    let slip = slip_of(ctx, y);
    // Stuck on the belt (physics.md §3.5): the parcel rides if riding (q̈ = 0) drives no
    // closed contact into penetration; its contacts then carry no force and their gap guards
    // watch them. With closed contacts the belt friction is regularised below
    // CONTACT_SLIP_REG, so the slip only decays towards zero: riding is tested from that
    // scale.
    let ride_slip = if closed_set.is_empty() {
        RIDE_SLIP
    } else {
        super::motion::CONTACT_SLIP_REG
    };
    if slip <= ride_slip {
        if let Some(riding_y) =
            ride_with_contacts(ctx, (arm, arm_at(t + LOOK_AHEAD)), y, &closed_set)
        {
            *y = riding_y;
            return Ok(Settled {
                riding: true,
                active: Vec::new(),
                impact,
            });
        }
    }
    let tol = Tolerances {
        slip: 1e-8,
        force: 1e-10 * ctx.weight,
        accel: 1e-9,
    };
    // The force slack stays below the release guard's margin even when relaxed: a contact
    // whose guard found it pulling must not be kept by the event logic (it would then be
    // muted for good while the receding arm pulls the parcel along).
    let relaxed = Tolerances {
        slip: 1e-6,
        force: 0.5 * super::motion::FORCE_MARGIN * ctx.weight,
        accel: 1e-6,
    };
    let prefer = closed_set
        .iter()
        .enumerate()
        .filter(|(_, (k, _))| struck.contains(k) || touched == Some(*k))
        .fold(0u32, |m, (i, _)| m | (1 << i));
    // The active set is chosen, then the velocities projected onto it; the projection
    // changes the forces (β depends on the velocities), so the set is chosen again at the
    // projected state until it stands, and the motion starts from a state whose forces
    // satisfy the very tests its guards watch.
    let mut active: Vec<ActiveContact> = Vec::new();
    let mut frames: Vec<ContactFrame> = closed_set.iter().map(|(_, f)| *f).collect();
    for round in 0..MAX_PROJECTIONS {
        // The laws the motion will integrate: ramped belt friction under contacts, the
        // exact law when free (zero at zero slip: the parcel is then riding).
        let (external, free_external) = if slip_of(ctx, y) == 0.0 {
            ([0.0; 3], [0.0; 3])
        } else {
            (ctx.contact_belt_wrench(y), ctx.free_belt_wrench(y))
        };
        let body = Body {
            mass: ctx.mass,
            inertia: ctx.inertia,
            external,
        };
        let rows: Vec<ContactRow> = frames.iter().map(|f| ctx.row(f)).collect();
        let selection = active_set::select_with_free(&body, free_external, &rows, &tol, prefer)
            .or_else(|| active_set::select_with_free(&body, free_external, &rows, &relaxed, prefer))
            .ok_or_else(|| {
                format!(
                    "no consistent contact state at t = {t} s ({} closed contacts)",
                    rows.len()
                )
            })?;
        active = closed_set
            .iter()
            .zip(selection.modes)
            .filter_map(|((kind, _), mode)| mode.map(|mode| ActiveContact { kind: *kind, mode }))
            .collect();
        // Velocity projection: active contacts keep g̈ = 0, so a residual normal speed
        // (below CLOSE_SPEED, e.g. the seesaw lift of a flush side's far end after a plastic
        // strike at its near end) would drift. Impulses along the active normals zero it.
        // A held contact that lets go here is projected too if it drifts in, so that it
        // leaves without a micro-strike; and a contact struck plastically at this instant
        // keeps its u_n = 0, so that projecting the others does not drive it in again
        // (near the arm tip a corner on the arm and the tip on an edge nearly share a point,
        // and the two would take turns: strike, project, strike…).
        let active_rows: Vec<ContactRow> = frames
            .iter()
            .zip(selection.modes)
            .zip(&closed_set)
            .filter(|((f, m), (k, _))| {
                m.is_some()
                    || ((held.contains(k) || persisting.contains(k)) && f.normal_speed < 0.0)
            })
            .map(|((f, _), _)| ContactRow {
                normal: f.jacobian,
                beta: -f.normal_speed,
                tangent: f.jacobian_t,
                beta_t: 0.0,
                friction: 0.0,
                slip: 0.0,
            })
            .collect();
        // The last round only selects, so the set always belongs to the final state.
        if round + 1 == MAX_PROJECTIONS || active_rows.iter().all(|r| r.beta.abs() <= 1e-9) {
            break;
        }
        let free = Body {
            mass: ctx.mass,
            inertia: ctx.inertia,
            external: [0.0; 3],
        };
        let modes = vec![Some(active_set::Tangential::Slide(1.0)); active_rows.len()];
        let Some(dv) = active_set::solve(&free, &active_rows, &modes) else {
            break;
        };
        y[3] += dv.accel[0];
        y[4] += dv.accel[1];
        y[5] += dv.accel[2];
        let kin = ctx.kinematics_with(arm, y);
        for ((k, _), f) in closed_set.iter().zip(frames.iter_mut()) {
            *f = contact::frame(*k, &kin);
        }
    }

    // 3. The belt.
    let riding = active.is_empty() && slip_of(ctx, y) <= RIDE_SLIP;
    if riding {
        *y = ride::snap(y, ctx.belt_speed);
    }
    Ok(Settled {
        riding,
        active,
        impact,
    })
}
