//! What happens at an event instant (docs/model.md §7): first every closed, approaching
//! contact is struck (Stronge's impact map, §5), then the contacts left closed get their
//! active set (which carry force, which stick or slide; §6), and the belt decides
//! between riding and sliding (§4).
//!
//! **Strikes.** Closed contacts (gap ≤ [`GAP_TOL`], point within its obstacle) approaching
//! faster than [`SPEED_TOL`] are struck one at a time, the fastest first, until none
//! approaches (a multi-point or flush strike thus becomes a short sequence, as in
//! sequential-impulse solvers). A contact struck again within the same instant, and any
//! strike slower than [`PERSIST_SPEED`], is plastic (e = 0): the contact then persists. This
//! is the paper's F3 "without rebound" and it stops low-speed re-impacts from chattering.
//! All impulses of one instant are reported as one strike. An arm's strike on a standing box
//! off its centre of mass's height takes the box's rocking mode into its effective mass
//! (§12a, `with_rocking`).
//!
//! **Jams.** Contacts that hold the parcel between the arm and the guide while the arm
//! returns, and that neither the strikes (sequential, then one simultaneous plastic impact)
//! nor an active set of finite forces can settle, end the run jammed (§6b,
//! [`Unsettled::Jammed`]): the arm's prescribed motion admits no motion of the parcel, so a
//! real drive stalls or crushes it.

use super::context::slip_of;
use super::context::Context;
use super::drift::remove_drift;
use super::motion::ActiveContact;
use super::result::{Impact, Jam, Obstacle, Stage};
use super::ride;
use super::tolerances::*;
use crate::model::active_set::{self, Body, ContactRow, Tolerances};
use crate::model::contact::{self, ContactFrame, ContactKind};
use crate::model::drive::ArmState;
use crate::model::impact::{body_velocity_change, resolve, ImpactInput, Mobility};
use glam::DVec2;

/// Bound on the rounds of active-set selection and velocity projection at one instant.
pub const MAX_PROJECTIONS: usize = 4;
/// Bound on strikes at one instant.
pub const MAX_STRIKES: usize = 64;

/// Why the contacts of an instant could not be settled.
#[derive(Debug, Clone, PartialEq)]
pub enum Unsettled {
    /// Numerical trouble, with a reason: the run fails.
    Failed(String),
    /// The parcel is wedged between the arm and the guide: the run ends jammed.
    Jammed(Jam),
}

impl From<String> for Unsettled {
    fn from(reason: String) -> Self {
        Unsettled::Failed(reason)
    }
}

/// A failure to settle the contacts `held` (each with its point (x, y) \[m]) at `t`, the arm
/// turning at `arm_rate` \[rad/s]: a jam where they hold the parcel between the arm and the
/// guide while the arm closes on it (returning, α̇ < 0: the wedge of docs/model.md §6b
/// narrows), else the failure `reason`. A jam keeps the reason as its cause.
pub(crate) fn unsettled(
    t: f64,
    held: &[(ContactKind, [f64; 2])],
    arm_rate: f64,
    reason: String,
) -> Unsettled {
    let arm = held.iter().any(|(k, _)| k.is_arm());
    let guide = held
        .iter()
        .any(|(k, _)| matches!(k, ContactKind::CornerGuide { .. }));
    if !(arm && guide && arm_rate < 0.0) {
        return Unsettled::Failed(reason);
    }
    // The arm's contacts first (the jam's place reads "between the arm … and the guide").
    let mut contacts: Vec<(Obstacle, [f64; 2])> =
        held.iter().map(|(k, p)| (obstacle_of(*k), *p)).collect();
    contacts.sort_by_key(|(o, _)| !o.is_arm());
    Unsettled::Jammed(Jam {
        t,
        contacts,
        cause: reason,
    })
}

/// The contacts of `set` with their points, for [`unsettled`].
fn points_of(set: &[(ContactKind, ContactFrame)]) -> Vec<(ContactKind, [f64; 2])> {
    set.iter()
        .map(|(k, f)| (*k, [f.point.x, f.point.y]))
        .collect()
}

/// The mode after an event (its stage label is [`stage_of`]).
#[derive(Debug, Clone)]
pub struct Settled {
    pub riding: bool,
    pub active: Vec<ActiveContact>,
    /// The strike at this instant, if any (its `stage` is left for the caller to set).
    pub impact: Option<Impact>,
    /// J_c: the strike's angular impulse on the arm about the pivot [N·m·s], −Σ Qᵢ × Pᵢ over
    /// every impulse Pᵢ the arm gave at its own point Qᵢ (face, back or tip) in this instant;
    /// `None` when the arm gave none (a strike on the guide alone).
    pub arm_angular_impulse: Option<f64>,
    /// The belt's impulse on a pivot edge in strikes off h_c (§12a) \[N·s], zero otherwise:
    /// the parcel's change of momentum less this is what the arm and the guide gave.
    pub pivot_impulse: DVec2,
}

/// Passes of [`with_rocking`] to find the pivot's regime that its own impulse keeps.
const ROCKING_PASSES: usize = 3;

/// The arm's strike on a box that can pivot (docs/model.md §12a, "A strike off h_c"): off
/// h_c the strike turns the standing box about an edge, and that rocking mode adds ΔW along
/// the far edge's normal e to the plane model's mobility, W' = W + ΔW a aᵀ with a = (e·t,
/// e·n). The impact is solved again with W' (the pivot's regime, stuck or sliding, is that of
/// the impulse found: a few passes settle it), and the pivot's friction impulse F̂ e, a belt
/// impulse through the edge's middle, joins the plane model's centre. The plane's impulse
/// `plane` stands where the strike acts at h_c, where W' is not positive definite, and where
/// no regime is kept by its own impulse within [`ROCKING_PASSES`]. Returns the arm's
/// impulses and F̂ e \[N·s].
fn with_rocking(
    geo: &crate::model::tipping::TipGeometry,
    angle: f64,
    input: &ImpactInput,
    normal: DVec2,
    plane: crate::model::impact::ImpactOutcome,
) -> Result<(crate::model::impact::ImpactOutcome, DVec2), crate::model::impact::ImpactError> {
    let (t, n) = crate::model::impact::contact_basis(normal);
    let mut mode = geo.rocking_mode(angle, plane.impulse_vector(normal));
    for _ in 0..ROCKING_PASSES {
        let Some(m) = mode else { break };
        let (a_t, a_n) = (m.direction.dot(t), m.direction.dot(n));
        let dw = m.extra_mobility;
        let w = &input.mobility;
        let mobility = Mobility {
            tt: w.tt + dw * a_t * a_t,
            tn: w.tn + dw * a_t * a_n,
            nn: w.nn + dw * a_n * a_n,
        };
        if !mobility.is_positive_definite() {
            break;
        }
        let out = resolve(&ImpactInput { mobility, ..*input })?;
        let p = out.impulse_vector(normal);
        let next = geo.rocking_mode(angle, p);
        if next.is_some_and(|k| k.same_regime(&m)) {
            return Ok((out, m.pivot_friction * p.dot(m.direction) * m.direction));
        }
        mode = next;
    }
    // No regime its own impulse keeps (an impulse near a footprint diagonal, where the box
    // would turn about a corner): the plane model's strike stands.
    Ok((plane, DVec2::ZERO))
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

/// The stage label of an active set (model.md §6: F4 = one corner on the arm,
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

/// Per parcel corner, how close to the arm's tip it counts as at the tip \[m].
pub type EndTolerances = [f64; 4];

/// How close to the arm's tip each corner counts as at the tip: [`END_TOL`], widened for a
/// corner at an end of an edge the tip holds. The tip on that edge makes the edge cross the
/// arm's line at the tip, so the corner can reach that line only at the tip; with the tip
/// contact's drift g (its gap) and the edge at an angle θ to the arm, it reaches it g/sin θ
/// from the tip (3e-6 m for g = 3.5e-8 m and θ = 0.7°, where a strike on the face followed at
/// tolerance 1e-8 and a pass beyond the tip at 1e-12). Not widened beyond
/// [`MAX_END_WIDENING`]: an edge along the arm crosses its line nowhere in particular.
pub fn end_tolerances(kin: &contact::Kinematics, held: &[ContactKind]) -> EndTolerances {
    let mut tol = [END_TOL; 4];
    for &h in held {
        let ContactKind::TipEdge { edge } = h else {
            continue;
        };
        let f = contact::frame(h, kin);
        let sin = crate::geometry::cross(f.point.normalize_or_zero(), f.tangent).abs();
        let widening = f.gap.abs() / sin;
        if widening <= MAX_END_WIDENING {
            // Edge j joins corners j and j + 1.
            for corner in [edge % 4, (edge + 1) % 4] {
                let k = usize::from(corner);
                tol[k] = tol[k].max(END_TOL + widening);
            }
        }
    }
    tol
}

/// Whether pair `kind` with frame `f` is a closed contact (the one contact-pair rule): the
/// gap within [[`DEEPEST_GAP`], [`GAP_TOL`]]; the point on its obstacle and not moving off
/// one of its ends ([`contact::leaves_end`]: a corner passing the arm's tip or pivot or the
/// guide's end, the tip passing round a parcel corner); and for the tip on an edge, an edge
/// the arm can touch from outside ([`contact::arm_into_edge`]) and the nearest of those to
/// the tip (`tip_gap`: the largest gap among them; see [`contact::tip_edge_shortfall`]).
fn closed(kind: ContactKind, f: &ContactFrame, tip_gap: f64, ends: &EndTolerances) -> bool {
    let end_tol = match kind {
        ContactKind::CornerArm { corner, .. } => ends[usize::from(corner % 4)],
        _ => END_TOL,
    };
    f.gap <= GAP_TOL
        && f.gap >= DEEPEST_GAP
        && f.along >= f.extent.0 - RANGE_TOL
        && f.along <= f.extent.1 + RANGE_TOL
        && !contact::leaves_end(f, end_tol, LEAVE_SPEED)
        && match kind {
            ContactKind::TipEdge { .. } => touchable(f) && tip_gap - f.gap <= NEAREST_TOL,
            _ => true,
        }
}

/// Whether the arm can touch the edge of tip–edge frame `f` from outside.
fn touchable(f: &ContactFrame) -> bool {
    contact::arm_into_edge(f) >= -ARM_EDGE_TOL
}

/// The closed contacts ([`closed`]). The arm tip at a parcel corner that is itself closed on
/// the arm is one contact, not two: the corner–arm pair is kept and the tip–edge pairs at
/// that corner dropped (they would strike or constrain the same point twice).
fn closed_frames(
    candidates: &[ContactKind],
    kin: &contact::Kinematics,
    ends: &EndTolerances,
) -> Vec<(ContactKind, ContactFrame)> {
    // One sine and cosine of φ and α for every candidate ([`contact::frame`] would take
    // them per pair: issue 28 found them a twelfth of a contact-heavy run).
    let (phi_sc, arm_sc) = (kin.angle.sin_cos(), kin.arm.angle.sin_cos());
    let frames: Vec<(ContactKind, ContactFrame)> = candidates
        .iter()
        .map(|&k| (k, contact::frame_with(k, kin, phi_sc, arm_sc)))
        .collect();
    // The nearest feature to the tip among the edges it can touch: a gap of an edge the arm
    // runs into (the leading face of a side on the arm) does not count, or the tip would
    // leave the side it supports the moment it ties with that face.
    let tip_gap = frames
        .iter()
        .filter(|(k, f)| matches!(k, ContactKind::TipEdge { .. }) && touchable(f))
        .map(|(_, f)| f.gap)
        .fold(f64::NEG_INFINITY, f64::max);
    let mut set: Vec<(ContactKind, ContactFrame)> = frames
        .into_iter()
        .filter(|(k, f)| closed(*k, f, tip_gap, ends))
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

/// Whether pair `kind` continues a contact held until this instant: the pair itself, or
/// the same point handed between the arm's face and its tip (a parcel corner at the tip:
/// the corner on the face and the tip on an edge at that corner). A side lying on the arm
/// whose leading corner passes the tip is then supported by the tip on that side without a
/// strike; its approach there is the drift of the hand-off, not an impact.
fn continues_held(kind: ContactKind, held: &[ContactKind], kin: &contact::Kinematics) -> bool {
    if held.contains(&kind) {
        return true;
    }
    // Edge j joins corners j and j + 1.
    let corner_of_edge =
        |corner: u8, edge: u8| corner % 4 == edge % 4 || corner % 4 == (edge + 1) % 4;
    let at_tip = |corner: u8| {
        let tip = kin.arm_length * DVec2::new(kin.arm.angle.cos(), kin.arm.angle.sin());
        let c = kin.rect.corners(kin.centre, kin.angle)[usize::from(corner % 4)];
        (c - tip).length() < AT_TIP
    };
    held.iter().any(|&h| match (h, kind) {
        (ContactKind::CornerArm { corner, .. }, ContactKind::TipEdge { edge })
        | (ContactKind::TipEdge { edge }, ContactKind::CornerArm { corner, .. }) => {
            corner_of_edge(corner, edge) && at_tip(corner)
        }
        _ => false,
    })
}

/// The outcome of a simultaneous plastic impact ([`plastic_impact`]).
struct PlasticImpact {
    /// Change of (ẋ, ẏ, ω).
    dv: [f64; 3],
    /// The sum of the impulses on the parcel [N·s].
    impulse: DVec2,
    /// Σ ½ P_n u_n0: the normal impulses' work in compression (≤ 0) \[J].
    compression_work: f64,
    /// −Σ P·(u0 + u′)/2: the energy the impact dissipates \[J].
    dissipated: f64,
    /// The contacts that carried an impulse.
    contacts: Vec<ContactKind>,
    /// −Σ Qᵢ × Pᵢ over the contacts on the arm that carried an impulse, if any [N·m·s].
    arm_angular_impulse: Option<f64>,
}

/// The closed contacts that approach, touch or separate slower than [`CLOSE_SPEED`], resolved
/// as one plastic impact with Coulomb friction ([`active_set::select_impact`]): every contact
/// that takes an impulse ends with u_n = 0, none approaches.
fn plastic_impact(
    ctx: &Context,
    kin: &contact::Kinematics,
    candidates: &[ContactKind],
    ends: &EndTolerances,
) -> Option<PlasticImpact> {
    let mut set: Vec<(ContactKind, ContactFrame)> = closed_frames(candidates, kin, ends)
        .into_iter()
        .filter(|(_, f)| f.normal_speed <= CLOSE_SPEED)
        .collect();
    set.sort_by(|a, b| a.1.normal_speed.total_cmp(&b.1.normal_speed));
    set.truncate(active_set::MAX_CONTACTS);
    let rows: Vec<ContactRow> = set
        .iter()
        .map(|(_, f)| ContactRow {
            normal: f.jacobian,
            beta: -f.normal_speed,
            tangent: f.jacobian_t,
            beta_t: -f.slip,
            friction: ctx.arm_friction,
            slip: f.slip,
        })
        .collect();
    let body = Body {
        mass: ctx.mass,
        inertia: ctx.inertia,
        external: [0.0; 3],
    };
    // Impulse slack 1e-12 m·(1 m/s), velocity slack 1e-10 m/s.
    let tol = Tolerances {
        slip: 1e-8,
        force: 1e-12 * ctx.mass,
        accel: 1e-10,
    };
    let sel = active_set::select_impact(&body, &rows, &tol)?;
    let dv = sel.solution.accel;
    let mut out = PlasticImpact {
        dv,
        impulse: DVec2::ZERO,
        compression_work: 0.0,
        dissipated: 0.0,
        contacts: Vec::new(),
        arm_angular_impulse: None,
    };
    for (i, (kind, f)) in set.iter().enumerate() {
        if sel.modes[i].is_none() {
            continue;
        }
        let (pn, pt) = (
            sel.solution.normal_force[i],
            sel.solution.tangential_force[i],
        );
        let dun = rows[i]
            .normal
            .iter()
            .zip(&dv)
            .map(|(a, b)| a * b)
            .sum::<f64>();
        let dut = rows[i]
            .tangent
            .iter()
            .zip(&dv)
            .map(|(a, b)| a * b)
            .sum::<f64>();
        let p = pn * f.normal + pt * f.tangent;
        out.impulse += p;
        if kind.is_arm() {
            *out.arm_angular_impulse.get_or_insert(0.0) -= f.point.perp_dot(p);
        }
        out.compression_work += 0.5 * pn * f.normal_speed.min(0.0);
        out.dissipated -= pn * (f.normal_speed + 0.5 * dun) + pt * (f.slip + 0.5 * dut);
        out.contacts.push(*kind);
    }
    Some(out)
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

/// Whether a touch of a parcel moving freely (riding or sliding, no contact held) is a
/// graze: it approaches slower than [`GRAZE_SPEED`] and its gap already turns, g̈ > 0
/// under the belt's law, so that it would reach at most [`TAIL_DEPTH`] deeper, u_n²/(2g̈).
/// Such a touch is no strike, as the end of a receding contact is none
/// ([`ride_with_contacts`]): the arm's tip sweeping past a riding parcel's edge within
/// 1e-8 m touched it at 2 µm/s at tolerance 1e-8 and missed it at 1e-12.
fn grazes(ctx: &Context, y: &[f64; 6], f: &ContactFrame) -> bool {
    let un = f.normal_speed;
    if -un >= GRAZE_SPEED {
        return false;
    }
    let accel = if slip_of(ctx, y) <= RIDE_SLIP {
        [0.0; 3]
    } else {
        let w = ctx.free_belt_wrench(y);
        [w[0] / ctx.mass, w[1] / ctx.mass, w[2] / ctx.inertia]
    };
    let g_ddot = f
        .jacobian
        .iter()
        .zip(&accel)
        .map(|(j, a)| j * a)
        .sum::<f64>()
        - f.beta;
    g_ddot > 0.0 && un * un / (2.0 * g_ddot) <= TAIL_DEPTH
}

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
) -> Result<Settled, Unsettled> {
    let arm = arm_at(t);
    let candidates: Vec<ContactKind> = contact::candidates(sides)
        .into_iter()
        .filter(|&k| ctx.candidate_enabled(k))
        .collect();

    // 0. The drift of the contacts held until now. The corners' tip tolerances come from the
    // drift that placed this event (as the driver's judgement of a face crossing did).
    let ends = end_tolerances(&ctx.kinematics_with(arm, y), held);
    remove_drift(ctx, arm, y, held, &[]);

    // 1. Strikes.
    let strikes = strike(ctx, t, arm, y, &candidates, &ends, held)?;

    // 2. Active set among the closed contacts.
    let kin = ctx.kinematics_with(arm, y);
    let closed_set = closed_after(&kin, &candidates, &ends, &strikes.struck, touched, held);
    let slip = slip_of(ctx, y);
    // Stuck on the belt (model.md §4): the parcel rides if riding (q̈ = 0) drives no
    // closed contact into penetration; its contacts then carry no force and their gap guards
    // watch them. With closed contacts the belt friction is regularised below
    // CONTACT_SLIP_REG, so the slip only decays towards zero: riding is tested from that
    // scale.
    let ride_slip = if closed_set.is_empty() {
        RIDE_SLIP
    } else {
        CONTACT_SLIP_REG
    };
    if slip <= ride_slip {
        if let Some(riding_y) =
            ride_with_contacts(ctx, (arm, arm_at(t + LOOK_AHEAD)), y, &closed_set)
        {
            *y = riding_y;
            return Ok(Settled {
                riding: true,
                active: Vec::new(),
                impact: strikes.impact,
                arm_angular_impulse: strikes.arm_angular_impulse,
                pivot_impulse: strikes.pivot_impulse,
            });
        }
    }
    let prefer = closed_set
        .iter()
        .enumerate()
        .filter(|(_, (k, _))| strikes.struck.contains(k) || touched == Some(*k))
        .fold(0u32, |m, (i, _)| m | (1 << i));
    let keep_still: Vec<bool> = closed_set
        .iter()
        .map(|(k, _)| strikes.persisting.contains(k) || continues_held(*k, held, &kin))
        .collect();
    let active = choose_active(ctx, t, arm, y, &closed_set, prefer, &keep_still)?;

    // 3. The belt.
    let riding = active.is_empty() && slip_of(ctx, y) <= RIDE_SLIP;
    if riding {
        *y = ride::snap(y, ctx.belt_speed);
    }
    Ok(Settled {
        riding,
        active,
        impact: strikes.impact,
        arm_angular_impulse: strikes.arm_angular_impulse,
        pivot_impulse: strikes.pivot_impulse,
    })
}

/// What the strikes of one instant leave besides the new velocities.
#[derive(Debug, Clone, Default)]
pub struct Strikes {
    /// All impulses of the instant as one strike, if any.
    pub impact: Option<Impact>,
    /// Every contact struck, in order (one may be struck again).
    pub struck: Vec<ContactKind>,
    /// Contacts struck plastically: they persist (u_n = 0 after the strike).
    pub persisting: Vec<ContactKind>,
    /// J_c, summed at each impulse's own point ([`Settled::arm_angular_impulse`]).
    pub arm_angular_impulse: Option<f64>,
    /// [`Settled::pivot_impulse`].
    pub pivot_impulse: DVec2,
}

/// Phase 1: strike every closed contact approaching faster than [`SPEED_TOL`], the fastest
/// first, until none approaches (module notes); the velocities of `y` change in place. A
/// contact held until now that drifts in slower than [`HELD_DRIFT`] is not struck, nor one
/// a free parcel merely grazes ([`grazes`]). More than [`MAX_STRIKES`] impulses is a jam
/// where the struck contacts hold the parcel between the arm and the guide, else an error.
pub fn strike(
    ctx: &Context,
    t: f64,
    arm: ArmState,
    y: &mut [f64; 6],
    candidates: &[ContactKind],
    ends: &EndTolerances,
    held: &[ContactKind],
) -> Result<Strikes, Unsettled> {
    let mut impact: Option<Impact> = None;
    let mut struck: Vec<ContactKind> = Vec::new();
    let mut persisting: Vec<ContactKind> = Vec::new();
    let mut total = DVec2::ZERO;
    // J_c, summed at each impulse's own point (two corners of a flush side struck at once
    // give Q₁ × P₁ + Q₂ × P₂, not Q₁ × (P₁ + P₂)).
    let mut arm_angular_impulse: Option<f64> = None;
    let mut first_basis = (DVec2::X, DVec2::Y);
    let mut pivot_impulse = DVec2::ZERO;
    for _ in 0..MAX_STRIKES {
        let kin = ctx.kinematics_with(arm, y);
        let hit = closed_frames(candidates, &kin, ends)
            .into_iter()
            // A contact held until this instant that drifts in slower than HELD_DRIFT
            // is not hit: it persists, and the projection below takes up its drift.
            .filter(|(k, f)| {
                f.normal_speed < -SPEED_TOL
                    && !(-f.normal_speed < HELD_DRIFT && continues_held(*k, held, &kin))
                    && !(held.is_empty() && grazes(ctx, y, f))
            })
            .min_by(|a, b| a.1.normal_speed.total_cmp(&b.1.normal_speed));
        let Some((kind, fr)) = hit else { break };
        // Struck again within this instant: the closed contacts are resolved together, as
        // one plastic impact. Struck one at a time, a parcel wedged between two obstacles
        // (the guide and the arm's tip) loses its approach only geometrically, by a
        // quarter per pair of strikes, and 64 impulses were not enough.
        if struck.contains(&kind) {
            if let Some(p) = plastic_impact(ctx, &kin, candidates, ends) {
                y[3] += p.dv[0];
                y[4] += p.dv[1];
                y[5] += p.dv[2];
                total += p.impulse;
                if let Some(jc) = p.arm_angular_impulse {
                    *arm_angular_impulse.get_or_insert(0.0) += jc;
                }
                if let Some(imp) = &mut impact {
                    imp.compression_work += p.compression_work;
                    imp.dissipated += p.dissipated;
                    imp.persistent = true;
                }
                for k in p.contacts {
                    struck.push(k);
                    persisting.push(k);
                }
                continue;
            }
        }
        let plastic = struck.contains(&kind) || -fr.normal_speed < PERSIST_SPEED;
        let input = ImpactInput {
            mobility: Mobility::at_contact(ctx.mass, ctx.inertia, fr.r, fr.normal),
            u_t0: fr.slip,
            u_n0: fr.normal_speed,
            friction: ctx.arm_friction,
            restitution: if plastic { 0.0 } else { ctx.restitution },
            law: ctx.impact_law,
        };
        let failed = |e| Unsettled::Failed(format!("strike at t = {t} s failed: {e}"));
        let mut out = resolve(&input).map_err(failed)?;
        let mut pivot_push = DVec2::ZERO;
        if kind.is_arm() {
            if let Some(geo) = &ctx.tip {
                (out, pivot_push) =
                    with_rocking(geo, y[2], &input, fr.normal, out).map_err(failed)?;
            }
        }
        let jump = body_velocity_change(
            ctx.mass,
            ctx.inertia,
            fr.r,
            fr.normal,
            out.normal_impulse,
            out.tangential_impulse,
        );
        y[3] += jump.dv.x + pivot_push.x / ctx.mass;
        y[4] += jump.dv.y + pivot_push.y / ctx.mass;
        y[5] += jump.domega;
        pivot_impulse += pivot_push;
        let impulse = out.impulse_vector(fr.normal);
        total += impulse;
        if kind.is_arm() {
            *arm_angular_impulse.get_or_insert(0.0) -= fr.point.perp_dot(impulse);
        }
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
            // Every contact struck, as the last impulse left it.
            let kin = ctx.kinematics_with(arm, y);
            let held_by: Vec<(ContactKind, ContactFrame)> = closed_frames(candidates, &kin, ends)
                .into_iter()
                .filter(|(k, _)| struck.contains(k))
                .collect();
            return Err(unsettled(
                t,
                &points_of(&held_by),
                arm.rate,
                format!("strikes at t = {t} s did not settle after {MAX_STRIKES} impulses"),
            ));
        }
    }
    if let Some(imp) = &mut impact {
        imp.normal_impulse = total.dot(first_basis.1);
        imp.tangential_impulse = total.dot(first_basis.0);
        imp.impulse = total.length();
    }
    Ok(Strikes {
        impact,
        struck,
        persisting,
        arm_angular_impulse,
        pivot_impulse,
    })
}

/// Phase 2a: the contacts closed after the strikes, nearest first, at most
/// [`active_set::MAX_CONTACTS`]: closed and not separating faster than [`SPEED_TOL`], or
/// up to [`CLOSE_SPEED`] when something holds them there (a strike at this instant, the
/// contact that just touched, a contact held until now).
pub fn closed_after(
    kin: &contact::Kinematics,
    candidates: &[ContactKind],
    ends: &EndTolerances,
    struck: &[ContactKind],
    touched: Option<ContactKind>,
    held: &[ContactKind],
) -> Vec<(ContactKind, ContactFrame)> {
    // A pair merely passing at an unrelated event while it separates is in free flight: taking
    // it up would pull it back (the projection below), an adhesion of up to CLOSE_SPEED that
    // made the outcome depend on whether some other event fell into its flight.
    let mut closed_set: Vec<(ContactKind, ContactFrame)> = closed_frames(candidates, kin, ends)
        .into_iter()
        .filter(|(k, f)| {
            f.normal_speed <= SPEED_TOL
                || (f.normal_speed <= CLOSE_SPEED
                    && (!struck.is_empty() || touched == Some(*k) || continues_held(*k, held, kin)))
        })
        .collect();
    closed_set.sort_by(|a, b| a.1.gap.abs().total_cmp(&b.1.gap.abs()));
    closed_set.truncate(active_set::MAX_CONTACTS);
    closed_set
}

/// Phase 2b: which of the closed contacts carry force, and whether each sticks or slides,
/// for the laws the motion will integrate; the velocities of `y` are projected onto the set
/// (in place) and the set chosen again until it stands, at most [`MAX_PROJECTIONS`] rounds.
/// `prefer`: a bit per closed contact to keep active where the tests allow (struck or
/// touched); `keep_still`: per closed contact, whether it is projected even when inactive
/// if it drifts in (struck plastically, or held until now), so that it leaves without a
/// micro-strike. No consistent set, even at relaxed tolerances, is a jam where the closed
/// contacts hold the parcel between the arm and the guide, else an error.
pub fn choose_active(
    ctx: &Context,
    t: f64,
    arm: ArmState,
    y: &mut [f64; 6],
    closed_set: &[(ContactKind, ContactFrame)],
    prefer: u32,
    keep_still: &[bool],
) -> Result<Vec<ActiveContact>, Unsettled> {
    debug_assert_eq!(keep_still.len(), closed_set.len());
    let tol = Tolerances {
        slip: 1e-8,
        force: 1e-10 * ctx.weight,
        accel: 1e-9,
    };
    // The force slack stays below the release guard's margin even when relaxed: a contact
    // whose guard found it pulling must not be kept by the event logic (it would then be
    // muted for good while the receding arm pulls the parcel along).
    let relaxed = Tolerances {
        slip: REST_SLIP,
        force: 0.5 * FORCE_MARGIN * ctx.weight,
        accel: 1e-6,
    };
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
                let now: Vec<(ContactKind, ContactFrame)> = closed_set
                    .iter()
                    .zip(&frames)
                    .map(|((k, _), f)| (*k, *f))
                    .collect();
                let reason = format!(
                    "no consistent contact state at t = {t} s ({} closed contacts)",
                    rows.len()
                );
                unsettled(t, &points_of(&now), arm.rate, reason)
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
            .zip(keep_still)
            .filter(|((f, m), still)| m.is_some() || (f.normal_speed < 0.0 && **still))
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
    Ok(active)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::params::Scenario;

    /// A failure to settle is a jam only for contacts on both the arm and the guide while
    /// the arm returns; otherwise it stays the failure, with its reason, and a jam keeps
    /// the reason as its cause.
    #[test]
    fn only_the_arm_closing_on_the_guide_makes_a_jam() {
        let back = ContactKind::CornerArm {
            corner: 2,
            side: -1,
        };
        let tip = ContactKind::TipEdge { edge: 1 };
        let guide = ContactKind::CornerGuide { corner: 3 };
        let (p, q) = ([0.9, 0.13], [0.91, 0.0]);
        let failed = |held: &[(ContactKind, [f64; 2])], rate: f64| {
            unsettled(0.4, held, rate, "why".into()) == Unsettled::Failed("why".into())
        };
        assert!(failed(&[], -2.0));
        assert!(failed(&[(back, p), (tip, p)], -2.0));
        assert!(failed(&[(guide, q)], -2.0));
        assert!(failed(&[(back, p), (guide, q)], 0.0));
        assert!(failed(&[(back, p), (guide, q)], 2.0));
        let Unsettled::Jammed(jam) = unsettled(0.4, &[(guide, q), (back, p)], -2.0, "why".into())
        else {
            panic!("a jam")
        };
        assert_eq!(jam.t, 0.4);
        assert_eq!(jam.cause, "why");
        assert_eq!(
            jam.contacts,
            vec![(Obstacle::ArmBack, p), (Obstacle::Guide, q)]
        );
        assert_eq!(
            jam.place(),
            "between the arm's back face at (0.900, 0.130) m and the guide at (0.910, 0.000) m"
        );
        let Unsettled::Jammed(jam) = unsettled(0.4, &[(tip, p), (guide, q)], -2.0, "why".into())
        else {
            panic!("a jam")
        };
        assert_eq!(jam.contacts[0].0, Obstacle::ArmTip);
        // Each obstacle named once, with all its points.
        let other = ContactKind::CornerGuide { corner: 2 };
        let held = [(guide, q), (back, p), (other, [0.66, 0.0])];
        let Unsettled::Jammed(jam) = unsettled(0.4, &held, -2.0, "why".into()) else {
            panic!("a jam")
        };
        assert_eq!(
            jam.place(),
            "between the arm's back face at (0.900, 0.130) m and the guide at (0.910, 0.000) m and (0.660, 0.000) m"
        );
    }

    /// The default parcel (0.4 × 0.26 m, 3 kg) with its long side flush on the retracted,
    /// resting arm (α = 0, the arm along the x axis from the pivot), moving at `v` [m/s]
    /// without spin; every corner on the working face's side.
    fn flush_on_the_arm(v: DVec2) -> (Context, ArmState, [f64; 6], Vec<ContactKind>) {
        let s = Scenario::paper_default();
        let ctx = Context::new(&s).unwrap();
        let arm = ArmState {
            angle: 0.0,
            rate: 0.0,
            accel: 0.0,
        };
        let y = [0.5, 0.5 * s.parcel.width, 0.0, v.x, v.y, 0.0];
        let candidates = contact::candidates([1; 4])
            .into_iter()
            .filter(|&k| ctx.candidate_enabled(k))
            .collect();
        (ctx, arm, y, candidates)
    }

    fn energy(ctx: &Context, y: &[f64; 6]) -> f64 {
        0.5 * ctx.mass * (y[3] * y[3] + y[4] * y[4]) + 0.5 * ctx.inertia * y[5] * y[5]
    }

    /// A box 0.3 × 0.2 × 0.6 m, 4 kg, face band `band`, belt friction `mu_b`, struck
    /// frictionlessly at the middle of its right long side towards +y by an arm closing at
    /// 1 m/s (e* = 0.3): the plane model's input, and the geometry.
    fn central_strike(
        band: (f64, f64),
        mu_b: f64,
    ) -> (crate::model::tipping::TipGeometry, ImpactInput) {
        let m = 4.0;
        let geo = crate::model::tipping::TipGeometry {
            half: DVec2::new(0.15, 0.1),
            height: 0.6,
            com_height: 0.3,
            band,
            mass: m,
            belt_friction: mu_b,
        };
        let inertia = m * (0.3f64.powi(2) + 0.2f64.powi(2)) / 12.0;
        let input = ImpactInput {
            mobility: Mobility::at_contact(m, inertia, DVec2::new(0.0, -0.1), DVec2::Y),
            u_t0: 0.0,
            u_n0: -1.0,
            friction: 0.0,
            restitution: 0.3,
            law: crate::model::impact::ImpactLaw::Energetic,
        };
        (geo, input)
    }

    /// Issue 47, item 3: struck at z_s = 0.45 m above h_c = 0.3 m, the box pivots on its far
    /// edge, which the belt holds (μ_b 0.4). The impulse–momentum balance about that edge,
    /// P z_s = I_O Δω, and the struck point's separation z_s Δω = (1 + e) u give
    /// P = (1 + e) u I_O/z_s², 34 % below the plane model's (1 + e) u m; the centre moves at
    /// h_c Δω, the pivot's friction making up the rest.
    #[test]
    fn a_strike_above_h_c_takes_the_rocking_mode_into_its_effective_mass() {
        use crate::model::tipping::TipEdge;
        let (geo, input) = central_strike((0.45, 0.6), 0.4);
        let plane = resolve(&input).unwrap();
        let (out, push) = with_rocking(&geo, 0.0, &input, DVec2::Y, plane).unwrap();
        let (z, hc, m) = (0.45, 0.3, 4.0);
        let i_o = geo.edge(TipEdge::LeftLong).inertia_edge;
        let p = 1.3 * i_o / (z * z);
        assert!(
            (out.normal_impulse - p).abs() <= 1e-12 * p,
            "{out:?} against {p}"
        );
        assert!((plane.normal_impulse - 1.3 * m).abs() <= 1e-12 * m);
        assert!(p < 0.67 * plane.normal_impulse);
        let rate = z * p / i_o;
        let centre = (p + push.y) / m;
        assert!(
            (centre - hc * rate).abs() <= 1e-12,
            "{centre} against {}",
            hc * rate
        );
        assert_eq!(push.x, 0.0);
        let pivot = geo.strike_pivot(0.0, DVec2::new(0.0, p)).unwrap();
        assert!(pivot.stuck && pivot.edge == TipEdge::LeftLong);
        assert!((pivot.rate - rate).abs() <= 1e-12 * rate);
        // Struck at h_c (a band that reaches it), the plane model's impulse stands.
        let (at_hc, input) = central_strike((0.2, 0.6), 0.4);
        let (same, push) = with_rocking(&at_hc, 0.0, &input, DVec2::Y, plane).unwrap();
        assert_eq!((same, push), (plane, DVec2::ZERO));
    }

    /// Issue 47, item 3: whatever the strike's direction, the rocking strike that stands is
    /// one whose own impulse keeps the regime it was solved with (the review found a flip
    /// A → B → A that returned A's outcome for an impulse asking for B); else the plane
    /// strike stands. Oblique normals at 0–90° on a corner, a sticking arm (μ_a 0.83), a
    /// raised face and a slippery belt, so that every regime occurs.
    #[test]
    fn a_rocking_strike_keeps_the_regime_of_its_own_impulse() {
        let (mut rocked, mut fell_back) = (0, 0);
        for mu_b in [0.02, 0.4] {
            let (geo, base) = central_strike((0.45, 0.6), mu_b);
            for k in 0..=180 {
                let normal = DVec2::from_angle((k as f64 * 0.5).to_radians());
                let input = ImpactInput {
                    mobility: Mobility::at_contact(4.0, 0.0433, DVec2::new(-0.15, -0.1), normal),
                    u_t0: 0.2,
                    friction: 0.83,
                    ..base
                };
                let plane = resolve(&input).unwrap();
                let (out, push) = with_rocking(&geo, 0.3, &input, normal, plane).unwrap();
                if out == plane {
                    assert_eq!(push, DVec2::ZERO);
                    fell_back += 1;
                    continue;
                }
                rocked += 1;
                let p = out.impulse_vector(normal);
                let mode = geo.rocking_mode(0.3, p).unwrap();
                let own = mode.pivot_friction * p.dot(mode.direction) * mode.direction;
                assert!(
                    (push - own).length() <= 1e-9 * p.length(),
                    "{k}: {push} against {own}"
                );
            }
        }
        assert!(
            rocked > 200 && fell_back > 0,
            "{rocked} rocked, {fell_back} fell back"
        );
    }

    /// Issue 47, item 3 (review): the tipping check takes the arm's impulse, not the parcel's
    /// change of momentum, which a rocking strike's pivot adds to. A side driven onto the arm
    /// with a raised face: the strikes' pivot impulse is reported, and the momentum change
    /// less it is what the arm gave.
    #[test]
    fn a_rocking_strike_reports_its_pivots_impulse_apart() {
        let mut s = Scenario::paper_default();
        s.parcel.height = 0.6;
        s.machine.arm_face_bottom = 0.45;
        let ctx = Context::new(&s).unwrap();
        let (_, arm, y0, candidates) = flush_on_the_arm(DVec2::new(0.3, -0.5));
        let mut y = y0;
        let st = strike(&ctx, 0.0, arm, &mut y, &candidates, &[END_TOL; 4], &[]).unwrap();
        let imp = st.impact.unwrap();
        assert_ne!(st.pivot_impulse, DVec2::ZERO);
        let change = ctx.mass * DVec2::new(y[3] - y0[3], y[4] - y0[4]);
        let arm_gave = change - st.pivot_impulse;
        assert!((arm_gave.length() - imp.impulse).abs() <= 1e-9 * imp.impulse);
        assert!((change.length() - imp.impulse).abs() > 1e-3 * imp.impulse);
    }

    /// Issue 47, item 3, on a sliding pivot: the same balance with the pivot's friction
    /// −σ μ_b N̂, N̂ = m p Δω, solved here as the linear system of the box's momentum along
    /// the push, its angular momentum about G and the struck point's separation: forwards on
    /// a slippery belt (μ_b 0.02: the far edge slides back towards the arm, σ = −1), and backwards (struck at
    /// 0.15 m, below h_c, about the struck side's edge, p = −d, which slides on: σ = +1). The
    /// solution must be that regime's: N̂ ≥ 0 and the pivot's slip Δv − h_c Δω along σ.
    #[test]
    fn a_strike_on_a_sliding_pivot_meets_the_impulse_balance() {
        for (band, mu_b, p_side, sigma) in [
            ((0.45, 0.6), 0.02, 0.1, -1.0),
            ((0.0, 0.15), 0.4, -0.1, 1.0),
        ] {
            let (geo, input) = central_strike(band, mu_b);
            let plane = resolve(&input).unwrap();
            let (out, push) = with_rocking(&geo, 0.0, &input, DVec2::Y, plane).unwrap();
            let (z, hc, m) = (geo.strike_height(), 0.3, 4.0);
            let i_g = geo.inertia_com(0.1);
            // Unknowns (P, Δv, Δω): m Δv = P − σ μ m p Δω; (I_G + m p² − σ μ m h_c p) Δω =
            // (z − h_c) P; Δv + (z − h_c) Δω = 1.3 (by Cramer's rule).
            let k = sigma * mu_b * m * p_side;
            let a = [
                [1.0, -m, -k],
                [
                    z - hc,
                    0.0,
                    -(i_g + m * p_side * p_side - sigma * mu_b * m * hc * p_side),
                ],
                [0.0, 1.0, z - hc],
            ];
            let b = [0.0, 0.0, 1.3];
            let det = |a: [[f64; 3]; 3]| {
                a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
                    - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
                    + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
            };
            let mut a_p = a;
            for r in 0..3 {
                a_p[r][0] = b[r];
            }
            let mut a_v = a;
            for r in 0..3 {
                a_v[r][1] = b[r];
            }
            let (p, dv) = (det(a_p) / det(a), det(a_v) / det(a));
            let domega =
                (z - hc) * p / (i_g + m * p_side * p_side - sigma * mu_b * m * hc * p_side);
            assert!(m * p_side * domega >= 0.0 && sigma * (dv - hc * domega) >= 0.0);
            assert!(
                (out.normal_impulse - p).abs() <= 1e-9 * p,
                "{band:?}: {out:?} against {p}"
            );
            assert!(
                ((p + push.y) / m - dv).abs() <= 1e-9,
                "{band:?}: the centre"
            );
            assert!(!geo.strike_pivot(0.0, DVec2::new(0.0, p)).unwrap().stuck);
        }
    }

    /// Phase 1 on a flush side driven onto the arm at 0.5 m/s: struck until no closed contact
    /// approaches, one strike reported with its approach speed, a compressive impulse, no
    /// energy created, and a record of the contacts struck.
    #[test]
    fn a_side_driven_onto_the_arm_is_struck_until_no_contact_approaches() {
        let (ctx, arm, mut y, candidates) = flush_on_the_arm(DVec2::new(0.0, -0.5));
        let ends = [END_TOL; 4];
        let before = energy(&ctx, &y);
        let s = strike(&ctx, 0.0, arm, &mut y, &candidates, &ends, &[]).unwrap();
        let imp = s.impact.expect("a strike");
        assert!((imp.approach_speed - 0.5).abs() < 1e-12, "{imp:?}");
        assert!(
            imp.normal_impulse > 0.0 && imp.impulse >= imp.normal_impulse,
            "{imp:?}"
        );
        assert_eq!(imp.obstacle, Obstacle::ArmFace);
        assert!(energy(&ctx, &y) <= before * (1.0 + 1e-12));
        assert!(
            s.struck.len() >= 2,
            "both corners of the side: {:?}",
            s.struck
        );
        let kin = ctx.kinematics_with(arm, &y);
        for (k, f) in closed_frames(&candidates, &kin, &ends) {
            assert!(
                f.normal_speed >= -SPEED_TOL,
                "{k:?} still approaches: {f:?}"
            );
        }
        // The arm took the reaction: J_c about the pivot, the impulse pushing the arm back.
        assert!(s.arm_angular_impulse.is_some_and(|j| j < 0.0), "{s:?}");
    }

    /// Phase 1 strikes nothing on a parcel that leaves the arm, and changes nothing.
    #[test]
    fn a_side_leaving_the_arm_is_not_struck() {
        let (ctx, arm, mut y, candidates) = flush_on_the_arm(DVec2::new(0.3, 0.5));
        let was = y;
        let s = strike(&ctx, 0.0, arm, &mut y, &candidates, &[END_TOL; 4], &[]).unwrap();
        assert!(s.impact.is_none() && s.struck.is_empty() && s.persisting.is_empty());
        assert_eq!(y, was);
    }

    /// Phase 2a keeps a resting side's two corners, nearest first, and drops a side that
    /// leaves faster than CLOSE_SPEED; one leaving slower is kept only when something holds
    /// it (a strike at this instant, the contact that touched, a contact held until now).
    #[test]
    fn the_closed_set_is_what_rests_or_is_held_not_what_leaves() {
        let ends = [END_TOL; 4];
        let (ctx, arm, y, candidates) = flush_on_the_arm(DVec2::ZERO);
        let resting = closed_after(
            &ctx.kinematics_with(arm, &y),
            &candidates,
            &ends,
            &[],
            None,
            &[],
        );
        assert_eq!(resting.len(), 2, "{resting:?}");
        assert!(resting
            .iter()
            .all(|(k, _)| matches!(k, ContactKind::CornerArm { .. })));
        let (ctx, arm, y, candidates) = flush_on_the_arm(DVec2::new(0.0, 2.0 * CLOSE_SPEED));
        let kin = ctx.kinematics_with(arm, &y);
        assert!(closed_after(&kin, &candidates, &ends, &[], None, &[]).is_empty());
        let slow = DVec2::new(0.0, 0.5 * (SPEED_TOL + CLOSE_SPEED));
        let (ctx, arm, y, candidates) = flush_on_the_arm(slow);
        let kin = ctx.kinematics_with(arm, &y);
        assert!(closed_after(&kin, &candidates, &ends, &[], None, &[]).is_empty());
        let held = [resting[0].0, resting[1].0];
        assert_eq!(
            closed_after(&kin, &candidates, &ends, &[], None, &held).len(),
            2
        );
        let struck = [resting[0].0];
        assert_eq!(
            closed_after(&kin, &candidates, &ends, &struck, None, &[]).len(),
            2
        );
    }

    /// Phase 2b: a side at rest on a resting arm keeps its velocities (nothing approaches,
    /// nothing to project); with the arm accelerating into it, both corners of the side carry
    /// force, on the working face.
    #[test]
    fn the_active_set_carries_the_force_of_an_arm_swinging_into_a_side() {
        let (ctx, arm, mut y, candidates) = flush_on_the_arm(DVec2::ZERO);
        let kin = ctx.kinematics_with(arm, &y);
        let closed = closed_after(&kin, &candidates, &[END_TOL; 4], &[], None, &[]);
        let was = y;
        choose_active(&ctx, 0.0, arm, &mut y, &closed, 0, &[false; 2]).unwrap();
        assert_eq!(y, was);
        // The arm swings into the parcel from rest: α̈ > 0 turns the face (+y side) into it.
        let pushing = ArmState { accel: 5.0, ..arm };
        let kin = ctx.kinematics_with(pushing, &y);
        let closed = closed_after(&kin, &candidates, &[END_TOL; 4], &[], None, &[]);
        assert_eq!(closed.len(), 2, "{closed:?}");
        let active = choose_active(&ctx, 0.0, pushing, &mut y, &closed, 0, &[false; 2]).unwrap();
        assert_eq!(active.len(), 2, "{active:?}");
        assert!(active
            .iter()
            .all(|c| matches!(c.kind, ContactKind::CornerArm { side: 1, .. })));
        // Swinging away, it would have to pull: no contact carries force.
        let receding = ArmState { accel: -5.0, ..arm };
        let kin = ctx.kinematics_with(receding, &y);
        let closed = closed_after(&kin, &candidates, &[END_TOL; 4], &[], None, &[]);
        assert_eq!(closed.len(), 2, "{closed:?}");
        let active = choose_active(&ctx, 0.0, receding, &mut y, &closed, 0, &[false; 2]).unwrap();
        assert!(active.is_empty(), "{active:?}");
    }
}
