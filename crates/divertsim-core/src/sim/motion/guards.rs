//! Guard bookkeeping: which conditions a mode watches, their values, and what the event
//! locator may assume of them within a step (speed and curvature limits, "far" gap guards
//! that cannot cross this step, guards muted after an event that changed nothing).
//!
//! Guards are all "falling" and carry small margins (a gap fires at −1e-9 m, a normal force
//! at −1e-9 m g, ...) so that a guard sitting at zero after a reset is on its pre-side and
//! fires once the condition is really violated.

use super::contacts::{separation, ContactSet};
use super::dynamics::Dynamics;
use crate::integrate::StepBounds;
use crate::model::active_set::{self, Tangential};
use crate::model::contact::{self, ContactKind};
use crate::sim::tolerances::*;
use glam::DVec2;

/// What a guard watches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Watch {
    /// P_max − y_G: the centre crosses the far edge.
    Exit,
    /// y_G: the centre crosses the open pivot-side edge.
    NearEdge,
    /// w·d_ref: the slip on the belt reaches zero.
    BeltStop,
    /// Free sliding: |w| falls to [`END_SLIP`], where the driver adds the rest of the slide
    /// in closed form (see [`super::Motion::stop_tail`]).
    SlipEnd,
    /// With contacts active: the slip falls below half the regularisation scale, where the
    /// parcel may ride (checked at the event).
    BeltSlow,
    /// The gap of an inactive candidate closes.
    Gap(ContactKind),
    /// Active contact i: its normal force reaches zero.
    Release(usize),
    /// Active contact i: its point leaves the obstacle below the range.
    RangeLow(usize),
    /// Active contact i: its point leaves the obstacle above the range.
    RangeHigh(usize),
    /// Sliding contact i: its slip reaches zero.
    SlipStop(usize),
    /// Sticking contact i: the friction force reaches the cone.
    StickBreak(usize),
    /// Riding parcel: it leaves the arm's reach.
    Reach,
}

/// Most guards in one mode: exit, near edge, stop, slip end, 12 candidate gaps, 4 per
/// active contact, reach.
const MAX_GUARDS: usize = 5 + 12 + 4 * active_set::MAX_CONTACTS;

/// Bound on the parcel's acceleration within one step, for the far-guard test [m/s²].
const ACCEL_BOUND: f64 = 200.0;

/// Distances at a step's start that the guards' speed limits need \[m].
#[derive(Debug, Clone, Copy, Default)]
struct StepStart {
    /// |G|: the centre's distance from the pivot.
    centre: f64,
    /// (G − O)·t(α): the centre's position along the arm's line (0 without an arm).
    along: f64,
    /// Each corner's position along the arm's line (0 without an arm).
    corner_along: [f64; 4],
    /// |tip − G|: the arm tip's distance from the centre (0 without an arm).
    tip: f64,
    /// Distance from the arm tip to the nearest parcel corner \[m].
    tip_corner: f64,
    /// Speed of the arm tip relative to the parcel's material point under it [m/s]: the
    /// rate of the tip's body coordinates.
    tip_slip: f64,
}

/// The guards of one mode.
pub(crate) struct Guards {
    watches: [Watch; MAX_GUARDS],
    n: usize,
    /// Guards whose last event changed nothing: silent until they have crossed and come
    /// back to their pre-side (checked at step starts), so a left root does not re-fire.
    muted: [bool; MAX_GUARDS],
    crossed: [bool; MAX_GUARDS],
    /// Extra depth of a gap guard whose touch changed nothing (doubling, bounded), so a
    /// touching contact is watched again a little deeper instead of being silenced.
    extra: [f64; MAX_GUARDS],
    /// Gap guards too far from zero to cross within this step (see [`Guards::begin_step`]).
    far: [bool; MAX_GUARDS],
    /// Distances at the step start, for the speed limits.
    start: StepStart,
    /// The step start's time and the gap guards' values there (bit i of `start_known`),
    /// from the far test: the event locator asks for them again.
    t_start: f64,
    start_known: u64,
    start_values: [f64; MAX_GUARDS],
}

impl Guards {
    pub fn new() -> Self {
        Guards {
            watches: [Watch::Exit; MAX_GUARDS],
            n: 0,
            muted: [false; MAX_GUARDS],
            crossed: [false; MAX_GUARDS],
            extra: [0.0; MAX_GUARDS],
            far: [false; MAX_GUARDS],
            start: StepStart {
                tip_corner: 0.0,
                tip_slip: f64::INFINITY,
                ..StepStart::default()
            },
            t_start: f64::NAN,
            start_known: 0,
            start_values: [0.0; MAX_GUARDS],
        }
    }

    /// The guards of the mode `d` is in at (t, y), with `sides` the face each corner is on.
    /// Gap guards that start at or below zero (a contact left closed but carrying no force)
    /// are re-based to start just on their pre-side, so they fire if the contact closes any
    /// further.
    pub fn configure(&mut self, d: &Dynamics, sides: [i8; 4], t: f64, y: &[f64; 6]) {
        self.start_known = 0;
        self.muted = [false; MAX_GUARDS];
        self.crossed = [false; MAX_GUARDS];
        self.extra = [0.0; MAX_GUARDS];
        let w = watch_list(d, sides);
        self.n = w.len().min(MAX_GUARDS);
        self.watches[..self.n].copy_from_slice(&w[..self.n]);
        for i in 0..self.n {
            match self.watches[i] {
                // A pair that separates (a corner just struck, rebounding) rises away from
                // its root by itself and only needs to start strictly on its pre-side, so
                // that a quick return is seen: re-based by half the margin, its next touch
                // fired that much deeper until a step began while it was apart, and one long
                // step over a bounce (at a loose tolerance) moved the next strike.
                Watch::Gap(kind) => {
                    let v = self.natural(d, i, t, y);
                    if v < 0.5 * GAP_MARGIN {
                        let (g, kin) = d.kinematics(t, y);
                        let separating = contact::frame_with(kind, &kin, g.phi_sc, g.arm_sc)
                            .normal_speed
                            > SEPARATING_SPEED;
                        let base = if separating {
                            SEPARATING_BASE
                        } else {
                            0.5 * GAP_MARGIN
                        };
                        // Any closed pair (down to the deepest touching gap) starts on its
                        // pre-side, or its guard could never fire as it sinks in.
                        if v < base {
                            self.extra[i] = (base - v).min(MAX_REBASE);
                        }
                    }
                }
                // A contact mode entered with the slip already in the regularised band
                // would never see the band guard fire (it starts past its root), and the
                // parcel could stay in the stiff band for good: it is watched at half the
                // slip it starts with instead, so the ride test comes again.
                Watch::BeltSlow => {
                    let slip = d.slip(y);
                    if slip < 0.5 * CONTACT_SLIP_REG {
                        self.extra[i] = 0.5 * CONTACT_SLIP_REG - 0.5 * slip;
                    }
                }
                _ => {}
            }
        }
    }

    /// How many guards the mode has.
    pub fn count(&self) -> usize {
        self.n
    }

    /// What guard `i` watches.
    pub fn watch(&self, i: usize) -> Watch {
        self.watches[i]
    }

    /// The index of the first guard watching `watch`.
    pub fn of(&self, watch: Watch) -> Option<usize> {
        self.watches[..self.n].iter().position(|&w| w == watch)
    }

    /// The pairs whose gaps are watched.
    pub fn watched_gaps(&self) -> impl Iterator<Item = ContactKind> + '_ {
        self.watches[..self.n].iter().filter_map(|w| match *w {
            Watch::Gap(kind) => Some(kind),
            _ => None,
        })
    }

    /// After an event of guard `i` that changed nothing: a gap guard is re-armed deeper
    /// (up to [`MAX_GAP_EXTRA`]), and so is a force guard (release, stick break; up to
    /// [`MAX_FORCE_EXTRA`] m g); any other guard is silenced until it has crossed and
    /// returned to its pre-side.
    ///
    /// A force guard is located on its pre-side of the root, where the force may still be
    /// admissible to the event logic; silencing it there would let a contact go on pulling
    /// for the rest of the segment (the force never comes back). Re-armed a little deeper, it
    /// fires again once the force is clearly past its limit, where the event logic refuses
    /// the contact.
    pub fn mute(&mut self, weight: f64, i: usize) {
        self.start_known = 0;
        match self.watches[i] {
            Watch::Gap(_) if self.extra[i] < MAX_GAP_EXTRA => {
                self.extra[i] = 2.0 * self.extra[i] + GAP_MARGIN;
                return;
            }
            Watch::Release(_) | Watch::StickBreak(_)
                if self.extra[i] < MAX_FORCE_EXTRA * weight =>
            {
                self.extra[i] =
                    (2.0 * self.extra[i] + FORCE_MARGIN * weight).min(MAX_FORCE_EXTRA * weight);
                return;
            }
            _ => {}
        }
        self.muted[i] = true;
        self.crossed[i] = false;
    }

    /// Guard `i`'s value at (t, y): −1 while muted, +1 while far, else its natural value.
    pub fn value(&self, d: &Dynamics, i: usize, t: f64, y: &[f64; 6]) -> f64 {
        if self.muted[i] {
            return -1.0;
        }
        if self.far[i] {
            return 1.0;
        }
        // The step start (the interpolant is y0 there): the value the far test found.
        if t == self.t_start && self.start_known & (1 << i) != 0 {
            return self.start_values[i];
        }
        self.natural(d, i, t, y)
    }

    /// The guard's value, without muting.
    fn natural(&self, d: &Dynamics, i: usize, t: f64, y: &[f64; 6]) -> f64 {
        let ctx = d.ctx;
        match self.watches[i] {
            Watch::Exit => ctx.belt_width - y[1],
            Watch::NearEdge => y[1],
            Watch::BeltStop => d.along_ref(y),
            Watch::SlipEnd => d.slip(y) - END_SLIP,
            Watch::BeltSlow => d.slip(y) - 0.5 * CONTACT_SLIP_REG + self.extra[i],
            Watch::Reach => ctx.arm_length - ctx.distance_from_pivot(y),
            Watch::Gap(kind) => {
                let (g, kin) = d.kinematics(t, y);
                separation(kind, &kin, g.phi_sc, g.arm_sc) + GAP_MARGIN + self.extra[i]
            }
            Watch::Release(k) => {
                d.evaluated(t, y, |e| e.normal_force[k]) + FORCE_MARGIN * ctx.weight + self.extra[i]
            }
            Watch::RangeLow(k) | Watch::RangeHigh(k) => {
                let Some(fr) = d.evaluated(t, y, |e| e.frames[k]) else {
                    return 1.0;
                };
                if matches!(self.watches[i], Watch::RangeLow(_)) {
                    fr.along - fr.extent.0 + RANGE_MARGIN
                } else {
                    fr.extent.1 - fr.along + RANGE_MARGIN
                }
            }
            Watch::SlipStop(k) => {
                let (Some(fr), Some(Tangential::Slide(s))) = (
                    d.evaluated(t, y, |e| e.frames[k]),
                    d.contacts.get(k).map(|c| c.mode),
                ) else {
                    return 1.0;
                };
                s * fr.slip + SLIP_MARGIN
            }
            Watch::StickBreak(k) => {
                let (ln, lt) = d.evaluated(t, y, |e| (e.normal_force[k], e.tangential_force[k]));
                ctx.arm_friction * ln - lt.abs() + FORCE_MARGIN * ctx.weight + self.extra[i]
            }
        }
    }

    /// Speed limits of the geometric guards along the step's interpolant, from the bounds
    /// on its derivatives (the parcel) and the arm's rate and acceleration bounds over the
    /// cycle (the arm), with a 1 % margin for rounding. The contact guards (forces, ranges,
    /// contact slips) have none: they are always sampled.
    pub fn speed_limit(&self, d: &Dynamics, i: usize, b: &StepBounds<6>) -> f64 {
        let ctx = d.ctx;
        let reach = ctx.half_diagonal;
        // Bounds over the step: the centre's speed, the spin, any parcel point's speed.
        let v = norm(b.rate[0], b.rate[1]);
        let w = b.rate[2];
        let point = v + w * reach;
        let limit = match self.watches[i] {
            Watch::Exit | Watch::NearEdge => b.rate[1],
            Watch::Reach | Watch::Gap(ContactKind::CornerGuide { .. }) => point,
            // A corner c against the arm's line through the pivot, g = c·n(α): ġ = ċ·n −
            // α̇ c·t, and likewise the distance along it; |c| ≤ |G| + c/2 over the step.
            Watch::Gap(ContactKind::CornerArm { .. }) => {
                point + ctx.arm_rate_max * (self.start.centre + reach + v * b.h)
            }
            // A gap plus the shortfall, a difference of two gaps: three times the rate u of
            // the tip's body coordinates, |u| ≤ |u(t0)| + h |u̇|, u = v_tip − v_G − ω J(tip − G).
            Watch::Gap(ContactKind::TipEdge { .. }) => 3.0 * self.tip_speed_bound(d, b),
            // The slip w = (v − V_b, ℓω) and its component along the fixed d_ref change no
            // faster than ẇ, bounded by the interpolant's velocity derivatives.
            Watch::BeltStop | Watch::SlipEnd | Watch::BeltSlow => {
                let l = ctx.slip_scale;
                (b.rate[3] * b.rate[3] + b.rate[4] * b.rate[4] + l * l * b.rate[5] * b.rate[5])
                    .sqrt()
            }
            _ => return f64::INFINITY,
        };
        1.01 * limit
    }

    /// A tip guard may dip between samples while a corner is within the tip's reach in this
    /// step (see [`Guards::tip_speed_bound`]).
    pub fn may_dip(&self, d: &Dynamics, i: usize, b: &StepBounds<6>) -> bool {
        if self.muted[i] || self.far[i] {
            return false;
        }
        match self.watches[i] {
            Watch::Gap(ContactKind::TipEdge { .. }) => {
                self.start.tip_corner <= self.tip_speed_bound(d, b) * b.h
            }
            // Only where the corner can be on the arm during the step: beyond the tip a dip
            // across the line and back leaves the corner on its side, and corners of a side
            // overhanging the tip hover on that line.
            Watch::Gap(ContactKind::CornerArm { corner, .. }) => {
                let along = self.start.corner_along[usize::from(corner % 4)];
                let reach = self.corner_along_speed(d, b) * b.h;
                along > -reach && along < d.ctx.arm_length + reach
            }
            _ => false,
        }
    }

    /// A corner–arm guard is the corner's gap g = (P − O)·n(α) wherever it can reach zero,
    /// as long as every corner stays ahead of the pivot over the step (the guard's other
    /// branch, behind the pivot, is then negative only where g is). Along the interpolant
    /// g̈ = n·P̈ − 2α̇ t·Ṗ − α̈ t·P − α̇² n·P, so |g̈| ≤ |P̈| + 2 Ω |Ṗ| + (Ω̇ + Ω²) |P| with the
    /// step's bounds on the parcel and the drive's proven bounds Ω ≥ |α̇|, Ω̇ ≥ |α̈|.
    pub fn curvature_limit(&self, d: &Dynamics, i: usize, b: &StepBounds<6>) -> f64 {
        let Watch::Gap(ContactKind::CornerArm { corner, .. }) = self.watches[i] else {
            return f64::INFINITY;
        };
        let ctx = d.ctx;
        let reach = ctx.half_diagonal;
        let v = norm(b.rate[0], b.rate[1]);
        let w = b.rate[2];
        let point = v + w * reach;
        let (om, om_dot) = (ctx.arm_rate_max, ctx.arm_accel_max);
        let radius = self.start.centre + reach + v * b.h;
        // The corner's position along the arm's line stays above zero over the step.
        let along = self.start.corner_along[usize::from(corner % 4)];
        if along - self.corner_along_speed(d, b) * b.h <= 0.0 {
            return f64::INFINITY;
        }
        let point_accel = norm(b.accel[0], b.accel[1]) + (b.accel[2] + w * w) * reach;
        1.01 * (point_accel + 2.0 * om * point + (om_dot + om * om) * radius)
    }

    /// A step starts at (t, y) (after `d` took its slip direction there): gap guards left
    /// apart are re-armed, the far test is made, and muted guards that crossed and came back
    /// are watched again.
    pub fn begin_step(&mut self, d: &Dynamics, t: f64, y: &[f64; 6]) {
        // A gap guard changes no faster than the relative speed of a parcel point and an arm
        // point: if it starts further from zero than that speed (plus an acceleration
        // allowance) can cover in the longest step, it cannot fire in this step.
        let ctx = d.ctx;
        let reach = ctx.half_diagonal;
        self.start = StepStart {
            centre: norm(y[0], y[1]),
            along: 0.0,
            corner_along: [0.0; 4],
            tip: 0.0,
            tip_corner: f64::INFINITY,
            tip_slip: 0.0,
        };
        let parcel_speed = norm(y[3], y[4]) + y[5].abs() * reach;
        let speed = parcel_speed + ctx.arm_rate_max * ctx.arm_length;
        let h = crate::sim::MAX_STEP;
        let travel = 2.0 * (speed * h + 0.5 * ACCEL_BOUND * h * h);
        // Floors of the arm's guards from the centre alone (−∞: none): every corner–arm
        // guard is at least its corner's gap, a corner's gap at least the centre's less c/2
        // (per face), and every tip guard at least max(|b_x| − a/2, |b_y| − b/2) for the tip
        // b in body axes (the nearest edge's max(gap, outside) value, which the shortfall
        // lifts every other edge's guard to).
        let mut arm_floor = [f64::NEG_INFINITY; 2];
        let mut tip_floor = f64::NEG_INFINITY;
        if ctx.drive.is_some() {
            let g = d.geo(t, y[2]);
            let (sp, cp) = g.phi_sc;
            let (sa, ca) = g.arm_sc;
            let gap = -sa * y[0] + ca * y[1];
            self.start.along = ca * y[0] + sa * y[1];
            for (k, rho) in ctx.rect.body_corners().iter().enumerate() {
                // The corner's offset from G, rotated by φ, along t(α).
                let (ox, oy) = (cp * rho.x - sp * rho.y, sp * rho.x + cp * rho.y);
                self.start.corner_along[k] = self.start.along + ca * ox + sa * oy;
            }
            let behind = -self.start.along - reach;
            arm_floor = [(-gap - reach).max(behind), (gap - reach).max(behind)];
            let tip = ctx.arm_length * DVec2::new(ca, sa);
            let dist = tip - DVec2::new(y[0], y[1]);
            self.start.tip = dist.length();
            let b = DVec2::new(cp * dist.x + sp * dist.y, -sp * dist.x + cp * dist.y);
            let corner = DVec2::new(
                b.x.abs() - 0.5 * ctx.rect.length,
                b.y.abs() - 0.5 * ctx.rect.width,
            );
            tip_floor = corner.x.max(corner.y);
            self.start.tip_corner = corner.length();
            // The tip relative to the parcel's material point under it.
            let tip_velocity = ctx.arm_length * g.arm.rate * DVec2::new(-sa, ca);
            let u = DVec2::new(y[3], y[4]) + y[5] * crate::geometry::perp(dist) - tip_velocity;
            self.start.tip_slip = u.length();
        }
        // The guide does not move: only the parcel's points do. Sliding freely, they
        // accelerate by friction alone, |a_P| ≤ |a_G| + |ω̇| c/2 + ω² c/2 with |ω| not growing.
        let guide_accel = if d.is_free() {
            ctx.free_point_accel + y[5] * y[5] * reach
        } else {
            ACCEL_BOUND
        };
        let guide_travel = 2.0 * (parcel_speed * h + 0.5 * guide_accel * h * h);
        // A corner–guide guard is max(y_k, x_k − x_end) + margins (the guide is y = 0 for
        // x ≤ x_end), at least max(y_G, x_G − x_end) − c/2: often far enough without the
        // corner's geometry.
        let guide_floor = y[1].max(y[0] - ctx.guide_end) - reach + GAP_MARGIN;
        self.t_start = t;
        self.start_known = 0;
        for i in 0..self.n {
            self.far[i] = false;
            if self.muted[i] {
                continue;
            }
            let limit = match self.watches[i] {
                Watch::Gap(ContactKind::CornerGuide { .. }) if guide_floor > guide_travel => {
                    self.far[i] = true;
                    continue;
                }
                Watch::Gap(ContactKind::CornerGuide { .. }) => guide_travel,
                Watch::Gap(ContactKind::CornerArm { side, .. })
                    if arm_floor[usize::from(side > 0)] > travel =>
                {
                    self.far[i] = true;
                    continue;
                }
                Watch::Gap(ContactKind::TipEdge { .. }) if tip_floor > travel => {
                    self.far[i] = true;
                    continue;
                }
                Watch::Gap(_) => travel,
                _ => continue,
            };
            let v = self.natural(d, i, t, y);
            self.far[i] = v > limit;
            self.start_values[i] = v;
            self.start_known |= 1 << i;
        }
        for i in 0..self.n {
            if self.muted[i] {
                let v = self.natural(d, i, t, y);
                if v < 0.0 {
                    self.crossed[i] = true;
                } else if self.crossed[i] && v > 0.0 {
                    self.muted[i] = false;
                }
            }
        }
    }

    /// A gap guard re-armed deeper or muted after a touch that was no contact (the tip
    /// hovering at a parcel corner, a corner at the arm's end) is watched afresh once its
    /// pair is clearly apart again, beyond the closed-contact tolerance: a guard that turned
    /// back without crossing would otherwise stay silent for the rest of the segment, and
    /// the next real touch of that pair would go unseen (a tip strike 18 ms after a corner
    /// left the tip; issue "Contacts that hold, round two").
    pub fn rearm_separated_gaps(&mut self, d: &Dynamics, t: f64, y: &[f64; 6]) {
        for i in 0..self.n {
            if matches!(self.watches[i], Watch::Gap(_)) && (self.muted[i] || self.extra[i] > 0.0) {
                let apart = self.natural(d, i, t, y) - self.extra[i] - GAP_MARGIN;
                if apart > GAP_TOL {
                    self.muted[i] = false;
                    self.crossed[i] = false;
                    self.extra[i] = 0.0;
                }
            }
        }
    }

    /// Bound on how fast a corner's position along the arm's line changes over the step [m/s]
    /// (as its gap: the corner's speed plus the arm's rate times its distance from the pivot).
    fn corner_along_speed(&self, d: &Dynamics, b: &StepBounds<6>) -> f64 {
        let reach = d.ctx.half_diagonal;
        let v = norm(b.rate[0], b.rate[1]);
        v + b.rate[2] * reach + d.ctx.arm_rate_max * (self.start.centre + reach + v * b.h)
    }

    /// Bound on the speed of the tip's body coordinates over the step [m/s]: the tip can
    /// cross a corner, in through one edge and out through the next, between two guard
    /// samples. u = v_tip − v_G − ω J(tip − G), so |u̇| ≤ |a_tip| + |a_G| + |ω̇| d + |ω| (|v_tip| +
    /// |v_G|), d ≥ |tip − G| over the step.
    fn tip_speed_bound(&self, d: &Dynamics, b: &StepBounds<6>) -> f64 {
        let ctx = d.ctx;
        let l = ctx.arm_length;
        let tip_speed = l * ctx.arm_rate_max;
        let tip_accel = l * (ctx.arm_accel_max + ctx.arm_rate_max * ctx.arm_rate_max);
        let v = norm(b.rate[0], b.rate[1]);
        let dist = self.start.tip + (tip_speed + v) * b.h;
        let u_dot = tip_accel
            + norm(b.accel[0], b.accel[1])
            + b.accel[2] * dist
            + b.rate[2] * (tip_speed + v);
        let direct = tip_speed + v + b.rate[2] * dist;
        (self.start.tip_slip + u_dot * b.h).min(direct)
    }

    #[cfg(test)]
    pub fn is_muted(&self, i: usize) -> bool {
        self.muted[i]
    }

    #[cfg(test)]
    pub fn extra(&self, i: usize) -> f64 {
        self.extra[i]
    }
}

/// The guards of the mode `d` is in, in order: exit, near edge, the belt's, the inactive
/// candidates' gaps, then four per active contact.
fn watch_list(d: &Dynamics, sides: [i8; 4]) -> Vec<Watch> {
    let ctx = d.ctx;
    let mut w = Vec::with_capacity(MAX_GUARDS);
    w.push(Watch::Exit);
    // A riding parcel keeps its y: only a sliding one can cross the near edge.
    if ctx.near_side_open() && !d.riding {
        w.push(Watch::NearEdge);
    }
    if d.riding {
        w.push(Watch::Reach);
    } else if d.contacts.is_empty() {
        w.push(Watch::BeltStop);
        w.push(Watch::SlipEnd);
    } else {
        w.push(Watch::BeltSlow);
    }
    for kind in contact::candidates(sides) {
        if !d.contacts.kinds().any(|k| k == kind) && ctx.candidate_enabled(kind) {
            w.push(Watch::Gap(kind));
        }
    }
    push_contact_watches(&mut w, &d.contacts);
    w
}

/// Four guards per active contact: release, the two ends of its range, and its slip stop or
/// stick break.
fn push_contact_watches(w: &mut Vec<Watch>, contacts: &ContactSet) {
    for (i, c) in contacts.slots().iter().enumerate() {
        let Some(c) = c else { continue };
        w.push(Watch::Release(i));
        w.push(Watch::RangeLow(i));
        w.push(Watch::RangeHigh(i));
        w.push(match c.mode {
            Tangential::Slide(_) => Watch::SlipStop(i),
            Tangential::Stick => Watch::StickBreak(i),
        });
    }
}

/// √(x² + y²) without `hypot`'s care for overflow (the bounds' values are of order one).
#[inline]
fn norm(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}
