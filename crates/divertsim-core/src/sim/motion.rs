//! The smooth motion between events, for every mode: riding (no slip, closed form),
//! free sliding F2, and sliding with an active set of arm / guide / tip contacts (F4, F5,
//! F6, ...). One right-hand side and one guard list per mode (docs/model.md §6: every stage is
//! an active set of vertex–line and tip–edge contacts).
//!
//! State y = (x, y, φ, ẋ, ẏ, ω) in frame-fixed axes (docs/model.md §4).
//!
//! **Belt stop.** Coulomb friction stops the slip in finite time and is discontinuous at zero
//! slip. The right-hand side is *continued* past the stop: the footprint law is homogeneous
//! of degree 0 and odd in w = (v_r, ℓω), so evaluating it at −w once w·d_ref < 0 (d_ref the
//! slip direction at the step start) keeps the pre-stop force, and the guard w·d_ref crosses
//! zero transversally (docs/model.md §4). The approach to the stop is not smooth (the slip
//! direction converges like a power of the time left): free sliding reports the time left to
//! the integrator ([`HybridSystem::time_to_singularity`]), which scales its steps with it, and
//! the last 1e-7 m/s of slip are closed in closed form ([`Motion::stop_tail`]).
//!
//! **Guards** are all "falling" and carry small margins (a gap fires at −1e-9 m, a normal
//! force at −1e-9 m g, ...) so that a guard sitting at zero after a reset is on its pre-side
//! and fires once the condition is really violated.

use super::context::{arm_state_trig, slip_of, slip_vector_of, Context};
use super::result::ContactCheck;
use super::tolerances::*;
use crate::integrate::{Direction, HybridSystem, StepBounds};
use crate::model::active_set::{self, Body, ContactRow, Tangential};
use crate::model::contact::{self, ContactKind};
use crate::model::drive::ArmState;
use crate::model::params::TippingRule;
use crate::model::tilt::{LoadSample, Rocker, Tilt};
use crate::model::tipping::{Pivot, Tip, TipCause, TipEdge, TipRecord};
use glam::DVec2;
use std::cell::{Cell, RefCell};

/// One active contact and its tangential mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActiveContact {
    pub kind: ContactKind,
    pub mode: Tangential,
}

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
    /// in closed form (see [`Motion::stop_tail`]).
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

/// What the right-hand side and the guards need of one (t, y) in a contact mode.
#[derive(Debug, Clone, Copy)]
struct Evaluation {
    accel: [f64; 3],
    /// Per active contact: where along its obstacle it is and its slip.
    frames: [Option<FrameSummary>; active_set::MAX_CONTACTS],
    normal_force: [f64; active_set::MAX_CONTACTS],
    tangential_force: [f64; active_set::MAX_CONTACTS],
    /// The arm's contacts' force on the parcel (x, y) \[N] and its moment about G \[N·m].
    arm: [f64; 3],
    /// Per active contact: its force on the parcel (x, y) \[N].
    forces: [[f64; 2]; active_set::MAX_CONTACTS],
}

/// The parts of a [`ContactFrame`] the guards watch.
#[derive(Debug, Clone, Copy)]
struct FrameSummary {
    along: f64,
    extent: (f64, f64),
    slip: f64,
}

/// Slots of the per-state evaluation cache: the event locator asks the contact guards one
/// after the other at the same sample points of a step.
const EVAL_SLOTS: usize = 8;

/// A cached evaluation with its (t, y).
type EvalSlot = (f64, [f64; 6], Evaluation);

/// (t, y, dy/dt) of a free-sliding parcel.
type FreeDerivative = (f64, [f64; 6], [f64; 6]);

/// The hybrid system of one mode.
pub struct Motion<'a> {
    ctx: &'a Context,
    /// Riding with the belt (no contacts).
    pub riding: bool,
    active: [Option<ActiveContact>; active_set::MAX_CONTACTS],
    /// Which face of the arm each corner is on (+1 working face, −1 back face).
    pub sides: [i8; 4],
    d_ref: [f64; 3],
    watches: [Watch; MAX_GUARDS],
    n_watches: usize,
    cache: RefCell<([Option<EvalSlot>; EVAL_SLOTS], usize)>,
    /// Free sliding: the last (t, y, dy/dt), which is the next step's start (FSAL).
    last_free: Cell<Option<FreeDerivative>>,
    /// Guards whose last event changed nothing: silent until they have crossed and come
    /// back to their pre-side (checked at step starts), so a left root does not re-fire.
    muted: [bool; MAX_GUARDS],
    crossed: [bool; MAX_GUARDS],
    /// Extra depth of a gap guard whose touch changed nothing (doubling, bounded), so a
    /// touching contact is watched again a little deeper instead of being silenced.
    extra: [f64; MAX_GUARDS],
    /// Geometry of the last few instants asked: the event locator evaluates every guard at
    /// the same few sample times of a step, guard by guard.
    geo_cache: RefCell<([Geo; GEO_SLOTS], usize)>,
    /// Gap guards too far from zero to cross within this step (see `begin_step`).
    far: [bool; MAX_GUARDS],
    /// The contact forces' extremes at the accepted steps so far ([`Motion::take_check`]).
    check: ContactCheck,
    /// The smallest tipping margin at the accepted steps so far ([`Motion::take_tip`]).
    tip: TipRecord,
    /// Tipped under [`TippingRule::Verdict`]: the integrator is asked to stop.
    halt: bool,
    /// The tilt about a footprint edge ([`crate::model::tilt`]).
    rocker: Rocker,
    /// The tilt loads at the last accepted state of this stretch (none after an event), and
    /// whether the box stood there with no edge lifting.
    last_load: Option<(LoadSample, bool)>,
    /// (t, M_c) at the accepted steps with an arm: the parcel's torque on the arm about the
    /// pivot \[s, N·m] ([`crate::sim::arm_loads`]).
    pub arm_torque: Vec<(f64, f64)>,
    /// Distance from the arm tip to the nearest parcel corner at the step start \[m].
    tip_corner_distance: f64,
    /// Speed of the arm tip relative to the parcel's material point under it, at the step
    /// start [m/s]: the rate of the tip's body coordinates.
    tip_slip_speed: f64,
    /// Distances at the step start, for [`HybridSystem::guard_speed_limit`].
    start: StepStart,
    /// The step start's time and the gap guards' values there (bit i of `start_known`),
    /// from the far test: the event locator asks for them again.
    t_start: f64,
    start_known: u64,
    start_values: [f64; MAX_GUARDS],
}

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
}

/// Bound on the parcel's acceleration within one step, for the far-guard test [m/s²].
const ACCEL_BOUND: f64 = 200.0;

/// Slots of the per-instant geometry cache (≥ the sample points of one step).
const GEO_SLOTS: usize = 8;

/// The arm state and the trigonometry at one (t, φ).
#[derive(Debug, Clone, Copy)]
struct Geo {
    t: f64,
    phi: f64,
    arm: ArmState,
    phi_sc: (f64, f64),
    arm_sc: (f64, f64),
}

impl<'a> Motion<'a> {
    pub fn new(ctx: &'a Context, sides: [i8; 4]) -> Self {
        let mut m = Motion {
            ctx,
            riding: false,
            active: [None; active_set::MAX_CONTACTS],
            sides,
            d_ref: [1.0, 0.0, 0.0],
            watches: [Watch::Exit; MAX_GUARDS],
            n_watches: 0,
            cache: RefCell::new(([None; EVAL_SLOTS], 0)),
            last_free: Cell::new(None),
            muted: [false; MAX_GUARDS],
            crossed: [false; MAX_GUARDS],
            extra: [0.0; MAX_GUARDS],
            geo_cache: RefCell::new((
                [Geo {
                    t: f64::NAN,
                    phi: f64::NAN,
                    arm: ArmState::default(),
                    phi_sc: (0.0, 1.0),
                    arm_sc: (0.0, 1.0),
                }; GEO_SLOTS],
                0,
            )),
            far: [false; MAX_GUARDS],
            check: ContactCheck::default(),
            tip: TipRecord::default(),
            halt: false,
            rocker: Rocker::default(),
            last_load: None,
            arm_torque: Vec::new(),
            tip_corner_distance: 0.0,
            tip_slip_speed: f64::INFINITY,
            start: StepStart::default(),
            t_start: f64::NAN,
            start_known: 0,
            start_values: [0.0; MAX_GUARDS],
        };
        m.n_watches = 0;
        m
    }

    /// Set the mode at (t, y): riding or not, and the active contacts. Gap guards that
    /// start at or below zero (a contact left closed but carrying no force) are re-based to
    /// start just on their pre-side, so they fire if the contact closes any further.
    pub fn configure(&mut self, riding: bool, active: &[ActiveContact], t: f64, y: &[f64; 6]) {
        self.riding = riding;
        self.active = [None; active_set::MAX_CONTACTS];
        for (slot, c) in self.active.iter_mut().zip(active) {
            *slot = Some(*c);
        }
        *self.cache.borrow_mut() = ([None; EVAL_SLOTS], 0);
        self.start_known = 0;
        self.muted = [false; MAX_GUARDS];
        self.crossed = [false; MAX_GUARDS];
        self.extra = [0.0; MAX_GUARDS];
        let mut w = Vec::with_capacity(MAX_GUARDS);
        w.push(Watch::Exit);
        // A riding parcel keeps its y: only a sliding one can cross the near edge.
        if self.ctx.near_side_open() && !riding {
            w.push(Watch::NearEdge);
        }
        if riding {
            w.push(Watch::Reach);
        } else if active.is_empty() {
            w.push(Watch::BeltStop);
            w.push(Watch::SlipEnd);
        } else {
            w.push(Watch::BeltSlow);
        }
        for kind in contact::candidates(self.sides) {
            if !self.active_kinds().any(|k| k == kind) && self.ctx.candidate_enabled(kind) {
                w.push(Watch::Gap(kind));
            }
        }
        for (i, c) in self.active.iter().enumerate() {
            let Some(c) = c else { continue };
            w.push(Watch::Release(i));
            w.push(Watch::RangeLow(i));
            w.push(Watch::RangeHigh(i));
            w.push(match c.mode {
                Tangential::Slide(_) => Watch::SlipStop(i),
                Tangential::Stick => Watch::StickBreak(i),
            });
        }
        self.n_watches = w.len().min(MAX_GUARDS);
        self.watches[..self.n_watches].copy_from_slice(&w[..self.n_watches]);
        for i in 0..self.n_watches {
            match self.watches[i] {
                // A pair that separates (a corner just struck, rebounding) rises away from
                // its root by itself and only needs to start strictly on its pre-side, so
                // that a quick return is seen: re-based by half the margin, its next touch
                // fired that much deeper until a step began while it was apart, and one long
                // step over a bounce (at a loose tolerance) moved the next strike.
                Watch::Gap(kind) => {
                    let v = self.natural_guard(i, t, y);
                    if v < 0.5 * GAP_MARGIN {
                        let g = self.geo(t, y[2]);
                        let kin = self.ctx.kinematics_with(g.arm, y);
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
                    let slip = self.slip(y);
                    if slip < 0.5 * CONTACT_SLIP_REG {
                        self.extra[i] = 0.5 * CONTACT_SLIP_REG - 0.5 * slip;
                    }
                }
                _ => {}
            }
        }
    }

    /// The active contacts.
    pub fn active(&self) -> impl Iterator<Item = &ActiveContact> {
        self.active.iter().flatten()
    }

    fn active_kinds(&self) -> impl Iterator<Item = ContactKind> + '_ {
        self.active.iter().flatten().map(|c| c.kind)
    }

    /// The cached geometry at (t, φ).
    fn geo(&self, t: f64, phi: f64) -> Geo {
        let mut cache = self.geo_cache.borrow_mut();
        let (slots, next) = &mut *cache;
        // Newest first: the locator asks guard after guard at the same few instants.
        for k in 1..=GEO_SLOTS {
            let g = &slots[(*next + GEO_SLOTS - k) % GEO_SLOTS];
            if g.t == t && g.phi == phi {
                return *g;
            }
        }
        let (arm, arm_sc) = arm_state_trig(self.ctx, t);
        let g = Geo {
            t,
            phi,
            arm,
            phi_sc: phi.sin_cos(),
            arm_sc,
        };
        slots[*next] = g;
        *next = (*next + 1) % GEO_SLOTS;
        g
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
    pub fn mute(&mut self, i: usize) {
        self.start_known = 0;
        match self.watches[i] {
            Watch::Gap(_) if self.extra[i] < MAX_GAP_EXTRA => {
                self.extra[i] = 2.0 * self.extra[i] + GAP_MARGIN;
                return;
            }
            Watch::Release(_) | Watch::StickBreak(_)
                if self.extra[i] < MAX_FORCE_EXTRA * self.ctx.weight =>
            {
                self.extra[i] = (2.0 * self.extra[i] + FORCE_MARGIN * self.ctx.weight)
                    .min(MAX_FORCE_EXTRA * self.ctx.weight);
                return;
            }
            _ => {}
        }
        self.muted[i] = true;
        self.crossed[i] = false;
    }

    /// What guard `i` watches.
    pub fn watch(&self, i: usize) -> Watch {
        self.watches[i]
    }

    /// w = (v_r, ℓω): the slip of the parcel on the belt [m/s].
    #[inline]
    pub fn slip_vector(&self, y: &[f64; 6]) -> [f64; 3] {
        slip_vector_of(self.ctx, y)
    }

    /// |w| [m/s].
    pub fn slip(&self, y: &[f64; 6]) -> f64 {
        slip_of(self.ctx, y)
    }

    fn along_ref(&self, y: &[f64; 6]) -> f64 {
        let w = self.slip_vector(y);
        w[0] * self.d_ref[0] + w[1] * self.d_ref[1] + w[2] * self.d_ref[2]
    }

    /// Belt friction wrench (F_x, F_y, M). Free sliding: continued past the stop. With
    /// active contacts: ramped linearly to zero below [`CONTACT_SLIP_REG`] of slip, because
    /// a contact can hold the parcel at zero belt slip, where the exact law's set-valued
    /// friction would make the motion chatter.
    fn belt_wrench(&self, y: &[f64; 6]) -> [f64; 3] {
        if self.active.iter().any(Option::is_some) {
            return self.ctx.contact_belt_wrench(y);
        }
        let sign = if self.along_ref(y) < 0.0 { -1.0 } else { 1.0 };
        let v_rel = sign * DVec2::new(y[3] - self.ctx.belt_speed, y[4]);
        let (f, m) = self.ctx.friction.wrench(v_rel, sign * y[5], y[2]);
        [f.x, f.y, m]
    }

    /// The evaluation at (t, y), a copy (once per step: the force check at a step's start).
    fn evaluate(&self, t: f64, y: &[f64; 6]) -> Evaluation {
        self.evaluated(t, y, |e| *e)
    }

    /// What `read` takes of the evaluation at (t, y), from the cache when it holds (t, y):
    /// read in place, since the guards ask one number each of an evaluation several hundred
    /// bytes long, many times per sample instant.
    fn evaluated<R>(&self, t: f64, y: &[f64; 6], read: impl FnOnce(&Evaluation) -> R) -> R {
        {
            let cache = self.cache.borrow();
            if let Some((_, _, e)) = cache
                .0
                .iter()
                .flatten()
                .find(|(ct, cy, _)| *ct == t && cy == y)
            {
                return read(e);
            }
        }
        let e = self.evaluation(t, y);
        let value = read(&e);
        let mut cache = self.cache.borrow_mut();
        let k = cache.1;
        cache.0[k] = Some((t, *y, e));
        cache.1 = (k + 1) % EVAL_SLOTS;
        value
    }

    /// The acceleration with the contacts active, apart from the right-hand side so that
    /// the free slide's path through it stays short.
    #[inline(never)]
    fn contact_accel(&self, t: f64, y: &[f64; 6]) -> [f64; 3] {
        self.evaluated(t, y, |e| e.accel)
    }

    /// The evaluation at (t, y), computed.
    fn evaluation(&self, t: f64, y: &[f64; 6]) -> Evaluation {
        let f = self.belt_wrench(y);
        let body = Body {
            mass: self.ctx.mass,
            inertia: self.ctx.inertia,
            external: f,
        };
        let mut e = Evaluation {
            accel: body.free_accel(),
            frames: [None; active_set::MAX_CONTACTS],
            normal_force: [0.0; active_set::MAX_CONTACTS],
            tangential_force: [0.0; active_set::MAX_CONTACTS],
            arm: [0.0; 3],
            forces: [[0.0; 2]; active_set::MAX_CONTACTS],
        };
        if self.active.iter().any(Option::is_some) {
            let g = self.geo(t, y[2]);
            let kin = self.ctx.kinematics_with(g.arm, y);
            let mut rows = [ContactRow {
                normal: [0.0; 3],
                beta: 0.0,
                tangent: [0.0; 3],
                beta_t: 0.0,
                friction: 0.0,
                slip: 0.0,
            }; active_set::MAX_CONTACTS];
            let mut modes = [None; active_set::MAX_CONTACTS];
            for (i, c) in self.active.iter().enumerate() {
                if let Some(c) = c {
                    let fr = contact::frame_with(c.kind, &kin, g.phi_sc, g.arm_sc);
                    rows[i] = self.ctx.row(&fr);
                    modes[i] = Some(c.mode);
                    e.frames[i] = Some(FrameSummary {
                        along: fr.along,
                        extent: fr.extent,
                        slip: fr.slip,
                    });
                }
            }
            match active_set::solve(&body, &rows, &modes) {
                Some(sol) => {
                    e.accel = sol.accel;
                    e.normal_force = sol.normal_force;
                    e.tangential_force = sol.tangential_force;
                    // J_n, J_t carry r×n, r×t: the moment about G comes with the force.
                    for (i, c) in self.active.iter().enumerate() {
                        let Some(c) = c else { continue };
                        let (ln, lt) = (sol.normal_force[i], sol.tangential_force[i]);
                        for k in 0..2 {
                            e.forces[i][k] = ln * rows[i].normal[k] + lt * rows[i].tangent[k];
                        }
                        if c.kind.is_arm() {
                            for k in 0..3 {
                                e.arm[k] += ln * rows[i].normal[k] + lt * rows[i].tangent[k];
                            }
                        }
                    }
                }
                None => e.accel = [f64::NAN; 3],
            }
        }
        e
    }
}

impl HybridSystem<6> for Motion<'_> {
    fn rhs(&self, t: f64, y: &[f64; 6]) -> [f64; 6] {
        if self.riding {
            return [y[3], y[4], y[5], 0.0, 0.0, 0.0];
        }
        if self.active.iter().all(Option::is_none) {
            // Free sliding: the belt wrench alone, without building an `Evaluation`.
            let f = self.belt_wrench(y);
            let dy = [
                y[3],
                y[4],
                y[5],
                f[0] / self.ctx.mass,
                f[1] / self.ctx.mass,
                f[2] / self.ctx.inertia,
            ];
            self.last_free.set(Some((t, *y, dy)));
            return dy;
        }
        let a = self.contact_accel(t, y);
        [y[3], y[4], y[5], a[0], a[1], a[2]]
    }

    fn guard_count(&self) -> usize {
        self.n_watches
    }

    fn guard(&self, i: usize, t: f64, y: &[f64; 6]) -> f64 {
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
        self.natural_guard(i, t, y)
    }

    /// Speed limits of the geometric guards along the step's interpolant, from the bounds
    /// on its derivatives (the parcel) and the arm's rate and acceleration bounds over the
    /// cycle (the arm), with a 1 % margin for rounding. The contact guards (forces, ranges,
    /// contact slips) have none: they are always sampled.
    fn guard_speed_limit(&self, i: usize, b: &StepBounds<6>) -> f64 {
        let ctx = self.ctx;
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
            Watch::Gap(ContactKind::TipEdge { .. }) => 3.0 * self.tip_speed_bound(b),
            // The slip w = (v − V_b, ℓω) and its component along the fixed d_ref change no
            // faster than ẇ, bounded by the interpolant's velocity derivatives.
            Watch::BeltStop | Watch::SlipEnd | Watch::BeltSlow => {
                let l = self.ctx.slip_scale;
                (b.rate[3] * b.rate[3] + b.rate[4] * b.rate[4] + l * l * b.rate[5] * b.rate[5])
                    .sqrt()
            }
            _ => return f64::INFINITY,
        };
        1.01 * limit
    }

    /// A tip guard may dip between samples while a corner is within the tip's reach in this
    /// step (see [`Motion::tip_speed_bound`]).
    fn guard_may_dip(&self, i: usize, b: &StepBounds<6>) -> bool {
        if self.muted[i] || self.far[i] {
            return false;
        }
        match self.watches[i] {
            Watch::Gap(ContactKind::TipEdge { .. }) => {
                self.tip_corner_distance <= self.tip_speed_bound(b) * b.h
            }
            // Only where the corner can be on the arm during the step: beyond the tip a dip
            // across the line and back leaves the corner on its side, and corners of a side
            // overhanging the tip hover on that line.
            Watch::Gap(ContactKind::CornerArm { corner, .. }) => {
                let along = self.start.corner_along[usize::from(corner % 4)];
                let reach = self.corner_along_speed(b) * b.h;
                along > -reach && along < self.ctx.arm_length + reach
            }
            _ => false,
        }
    }

    /// A corner–arm guard is the corner's gap g = (P − O)·n(α) wherever it can reach zero,
    /// as long as every corner stays ahead of the pivot over the step (the guard's other
    /// branch, behind the pivot, is then negative only where g is). Along the interpolant
    /// g̈ = n·P̈ − 2α̇ t·Ṗ − α̈ t·P − α̇² n·P, so |g̈| ≤ |P̈| + 2 Ω |Ṗ| + (Ω̇ + Ω²) |P| with the
    /// step's bounds on the parcel and the drive's proven bounds Ω ≥ |α̇|, Ω̇ ≥ |α̈|.
    fn guard_curvature_limit(&self, i: usize, b: &StepBounds<6>) -> f64 {
        let Watch::Gap(ContactKind::CornerArm { corner, .. }) = self.watches[i] else {
            return f64::INFINITY;
        };
        let ctx = self.ctx;
        let reach = ctx.half_diagonal;
        let v = norm(b.rate[0], b.rate[1]);
        let w = b.rate[2];
        let point = v + w * reach;
        let (om, om_dot) = (ctx.arm_rate_max, ctx.arm_accel_max);
        let radius = self.start.centre + reach + v * b.h;
        // The corner's position along the arm's line stays above zero over the step.
        let along = self.start.corner_along[usize::from(corner % 4)];
        if along - self.corner_along_speed(b) * b.h <= 0.0 {
            return f64::INFINITY;
        }
        let point_accel = norm(b.accel[0], b.accel[1]) + (b.accel[2] + w * w) * reach;
        1.01 * (point_accel + 2.0 * om * point + (om_dot + om * om) * radius)
    }

    fn guard_direction(&self, _i: usize) -> Direction {
        Direction::Falling
    }

    /// `begin_step` only moves d_ref, which changes the right-hand side past a belt stop,
    /// never at the step's initial point: the derivative there can be reused.
    fn begin_step_changes_rhs(&self) -> bool {
        false
    }

    /// In contact: Coulomb friction damps the slip's free directions at about μ_b g / |w| (the
    /// force turns with the slip; a spin mode is damped alike, ⟨ρ²⟩ being about the
    /// footprint's i²), |w| no smaller than the regularised band. On the slender parcel
    /// squeezed between arm and guide from the arm's start (fig08) the explicit steps show the
    /// true rate within a factor 1.5 of this. Free sliding and riding are not stiff (a free
    /// slide's approach to its stop is the singularity's business).
    fn stiffness(&self, _t: f64, y: &[f64; 6]) -> f64 {
        if self.riding || self.is_free() {
            return 0.0;
        }
        self.ctx.belt_decel / self.slip(y).max(CONTACT_SLIP_REG)
    }

    /// Free sliding: the time left to the belt stop at the present deceleration.
    fn time_to_singularity(&self, t: f64, y: &[f64; 6]) -> f64 {
        if !self.is_free() {
            return f64::INFINITY;
        }
        // Below END_SLIP (a free segment can start there if riding was refused) the stop is
        // crossed and located by the belt-stop guard instead.
        if self.slip(y) <= END_SLIP {
            return f64::INFINITY;
        }
        // The derivative at a step start is the last one computed (first same as last);
        // without it (a segment's first step) say nothing rather than pay for it.
        let dy = match self.last_free.get() {
            Some((ct, cy, dy)) if ct == t && cy == *y => dy,
            _ => return f64::INFINITY,
        };
        self.time_to_stop(y, &dy)
    }

    /// The active contacts' drift from their obstacles, put back between steps
    /// ([`super::drift::remove_drift`]): acceleration-level constraints let a long push
    /// drift 1e-6 m into the arm between two events.
    fn project(&mut self, t: f64, y: &mut [f64; 6]) -> bool {
        if self.riding || self.active.iter().all(Option::is_none) {
            return false;
        }
        let mut held = [ContactKind::TipEdge { edge: 0 }; active_set::MAX_CONTACTS];
        let mut n = 0;
        for c in self.active.iter().flatten() {
            held[n] = c.kind;
            n += 1;
        }
        // Cheaply first: most steps have nothing to remove.
        let g = self.geo(t, y[2]);
        let kin = self.ctx.kinematics_with(g.arm, y);
        let drifted = held[..n].iter().any(|&k| {
            let (gap, _, _) = contact::gap_and_range_with(k, &kin, g.phi_sc, g.arm_sc);
            gap.abs() > DRIFT_TOL
        });
        if !drifted {
            return false;
        }
        // The watched pairs touching now keep their gaps.
        let arm = g.arm;
        let keep: Vec<ContactKind> = self.watches[..self.n_watches]
            .iter()
            .filter_map(|w| match *w {
                Watch::Gap(kind) => Some(kind),
                _ => None,
            })
            .filter(|&kind| {
                let (gap, along, (lo, hi)) = contact::gap_and_range(kind, &kin);
                gap.abs() <= GAP_TOL && along >= lo && along <= hi
            })
            .collect();
        super::drift::remove_drift(self.ctx, arm, y, &held[..n], &keep)
    }

    fn halt(&self) -> bool {
        self.halt
    }

    fn begin_step(&mut self, t: f64, y: &[f64; 6]) {
        self.check_forces(t, y);
        self.check_tipping(t, y);
        self.note_arm_torque(t, y);
        self.rearm_separated_gaps(t, y);
        let w = self.slip_vector(y);
        let n = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        if n > 0.0 {
            self.d_ref = [w[0] / n, w[1] / n, w[2] / n];
        }
        // A gap guard changes no faster than the relative speed of a parcel point and an arm
        // point: if it starts further from zero than that speed (plus an acceleration
        // allowance) can cover in the longest step, it cannot fire in this step.
        let ctx = self.ctx;
        let reach = ctx.half_diagonal;
        self.start = StepStart {
            centre: norm(y[0], y[1]),
            along: 0.0,
            corner_along: [0.0; 4],
            tip: 0.0,
        };
        let parcel_speed = norm(y[3], y[4]) + y[5].abs() * reach;
        let speed = parcel_speed + ctx.arm_rate_max * ctx.arm_length;
        let h = super::MAX_STEP;
        let travel = 2.0 * (speed * h + 0.5 * ACCEL_BOUND * h * h);
        // Floors of the arm's guards from the centre alone (−∞: none): every corner–arm
        // guard is at least its corner's gap, a corner's gap at least the centre's less c/2
        // (per face), and every tip guard at least max(|b_x| − a/2, |b_y| − b/2) for the tip
        // b in body axes (the nearest edge's max(gap, outside) value, which the shortfall
        // lifts every other edge's guard to).
        let mut arm_floor = [f64::NEG_INFINITY; 2];
        let mut tip_floor = f64::NEG_INFINITY;
        (self.tip_corner_distance, self.tip_slip_speed) = if ctx.drive.is_some() {
            let g = self.geo(t, y[2]);
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
            let d = tip - DVec2::new(y[0], y[1]);
            self.start.tip = d.length();
            let b = DVec2::new(cp * d.x + sp * d.y, -sp * d.x + cp * d.y);
            let corner = DVec2::new(
                b.x.abs() - 0.5 * ctx.rect.length,
                b.y.abs() - 0.5 * ctx.rect.width,
            );
            tip_floor = corner.x.max(corner.y);
            let corner = corner.length();
            // The tip relative to the parcel's material point under it.
            let tip_velocity = ctx.arm_length * g.arm.rate * DVec2::new(-sa, ca);
            let u = DVec2::new(y[3], y[4]) + y[5] * crate::geometry::perp(d) - tip_velocity;
            (corner, u.length())
        } else {
            (f64::INFINITY, 0.0)
        };
        // The guide does not move: only the parcel's points do. Sliding freely, they
        // accelerate by friction alone, |a_P| ≤ |a_G| + |ω̇| c/2 + ω² c/2 with |ω| not growing.
        let guide_accel = if self.is_free() {
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
        for i in 0..self.n_watches {
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
            let v = self.natural_guard(i, t, y);
            self.far[i] = v > limit;
            self.start_values[i] = v;
            self.start_known |= 1 << i;
        }
        for i in 0..self.n_watches {
            if self.muted[i] {
                let v = self.natural_guard(i, t, y);
                if v < 0.0 {
                    self.crossed[i] = true;
                } else if self.crossed[i] && v > 0.0 {
                    self.muted[i] = false;
                }
            }
        }
    }
}

impl Motion<'_> {
    /// A gap guard re-armed deeper or muted after a touch that was no contact (the tip
    /// hovering at a parcel corner, a corner at the arm's end) is watched afresh once its
    /// pair is clearly apart again, beyond the closed-contact tolerance: a guard that turned
    /// back without crossing would otherwise stay silent for the rest of the segment, and
    /// the next real touch of that pair would go unseen (a tip strike 18 ms after a corner
    /// left the tip; issue "Contacts that hold, round two").
    fn rearm_separated_gaps(&mut self, t: f64, y: &[f64; 6]) {
        for i in 0..self.n_watches {
            if matches!(self.watches[i], Watch::Gap(_)) && (self.muted[i] || self.extra[i] > 0.0) {
                let apart = self.natural_guard(i, t, y) - self.extra[i] - GAP_MARGIN;
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
    fn corner_along_speed(&self, b: &StepBounds<6>) -> f64 {
        let reach = self.ctx.half_diagonal;
        let v = norm(b.rate[0], b.rate[1]);
        let point = v + b.rate[2] * reach;
        point + self.ctx.arm_rate_max * (self.start.centre + reach + v * b.h)
    }

    /// Bound on the speed of the arm tip's body coordinates over the step (the tip relative
    /// to the parcel's material point under it): the arm tip can sweep across a parcel
    /// corner, in through one edge and out through the next, between two guard samples.
    /// u = v_tip − v_G − ω J(tip − G), so |u̇| ≤ |a_tip| + |a_G| + |ω̇| d + |ω| (|v_tip| +
    /// |v_G|), d ≥ |tip − G| over the step.
    fn tip_speed_bound(&self, b: &StepBounds<6>) -> f64 {
        let ctx = self.ctx;
        let l = ctx.arm_length;
        let tip_speed = l * ctx.arm_rate_max;
        let tip_accel = l * (ctx.arm_accel_max + ctx.arm_rate_max * ctx.arm_rate_max);
        let v = norm(b.rate[0], b.rate[1]);
        let d = self.start.tip + (tip_speed + v) * b.h;
        let u_dot =
            tip_accel + norm(b.accel[0], b.accel[1]) + b.accel[2] * d + b.rate[2] * (tip_speed + v);
        let direct = tip_speed + v + b.rate[2] * d;
        (self.tip_slip_speed + u_dot * b.h).min(direct)
    }

    /// The guard's value, without muting.
    fn natural_guard(&self, i: usize, t: f64, y: &[f64; 6]) -> f64 {
        let ctx = self.ctx;
        match self.watches[i] {
            Watch::Exit => ctx.belt_width - y[1],
            Watch::NearEdge => y[1],
            Watch::BeltStop => self.along_ref(y),
            Watch::SlipEnd => self.slip(y) - END_SLIP,
            Watch::BeltSlow => self.slip(y) - 0.5 * CONTACT_SLIP_REG + self.extra[i],
            Watch::Reach => ctx.arm_length - ctx.distance_from_pivot(y),
            Watch::Gap(kind) => {
                let g = self.geo(t, y[2]);
                let kin = ctx.kinematics_with(g.arm, y);
                let (gap, along, extent) =
                    contact::gap_and_range_with(kind, &kin, g.phi_sc, g.arm_sc);
                match kind {
                    // A corner crossing the arm's line beyond the tip switches faces (the
                    // driver flips its side); behind the pivot the line is no obstacle.
                    ContactKind::CornerArm { .. } => {
                        gap.max(extent.0 - along) + GAP_MARGIN + self.extra[i]
                    }
                    // Elsewhere a crossing outside the obstacle's extent is no contact: watch
                    // max(gap, distance outside the extent), negative only when touching.
                    ContactKind::CornerGuide { .. } => {
                        gap.max((extent.0 - along).max(along - extent.1))
                            + GAP_MARGIN
                            + self.extra[i]
                    }
                    // The tip touches an edge only if that edge is its nearest: the shortfall
                    // (≥ 0, and 0 for the nearest edge) lifts the guard of every other edge,
                    // continuously, to at least the largest edge gap, which is negative
                    // only with the tip wholly inside the parcel.
                    ContactKind::TipEdge { edge } => {
                        let shortfall =
                            contact::tip_edge_shortfall_with(edge, &kin, g.phi_sc, g.arm_sc);
                        gap.max((extent.0 - along).max(along - extent.1))
                            + shortfall
                            + GAP_MARGIN
                            + self.extra[i]
                    }
                }
            }
            Watch::Release(k) => {
                self.evaluated(t, y, |e| e.normal_force[k])
                    + FORCE_MARGIN * ctx.weight
                    + self.extra[i]
            }
            Watch::RangeLow(k) | Watch::RangeHigh(k) => {
                let Some(fr) = self.evaluated(t, y, |e| e.frames[k]) else {
                    return 1.0;
                };
                if matches!(self.watches[i], Watch::RangeLow(_)) {
                    fr.along - fr.extent.0 + RANGE_MARGIN
                } else {
                    fr.extent.1 - fr.along + RANGE_MARGIN
                }
            }
            Watch::SlipStop(k) => {
                let (
                    Some(fr),
                    Some(ActiveContact {
                        mode: Tangential::Slide(s),
                        ..
                    }),
                ) = (self.evaluated(t, y, |e| e.frames[k]), self.active[k])
                else {
                    return 1.0;
                };
                s * fr.slip + SLIP_MARGIN
            }
            Watch::StickBreak(k) => {
                let (ln, lt) = self.evaluated(t, y, |e| (e.normal_force[k], e.tangential_force[k]));
                ctx.arm_friction * ln - lt.abs() + FORCE_MARGIN * ctx.weight + self.extra[i]
            }
        }
    }
}

impl Motion<'_> {
    /// Record the active contacts' forces at an accepted state (a step start): the
    /// invariants λ_n ≥ 0, |λ_t| ≤ μ λ_n when sticking, λ_t u_t ≤ 0 when sliding. Debug
    /// builds also assert them, with room for the guards' margins and event location.
    fn check_forces(&mut self, t: f64, y: &[f64; 6]) {
        if self.riding || self.active.iter().all(Option::is_none) {
            return;
        }
        let e = self.evaluate(t, y);
        let w = self.ctx.weight;
        let mut c = ContactCheck::default();
        for (i, a) in self.active.iter().enumerate() {
            let (Some(a), Some(fr)) = (a, e.frames[i]) else {
                continue;
            };
            let (ln, lt) = (e.normal_force[i], e.tangential_force[i]);
            c.min_normal_force = c.min_normal_force.min(ln / w);
            let g = self.geo(t, y[2]);
            let kin = self.ctx.kinematics_with(g.arm, y);
            let (gap, _, _) = contact::gap_and_range_with(a.kind, &kin, g.phi_sc, g.arm_sc);
            c.max_gap_drift = c.max_gap_drift.max(gap.abs());
            match a.mode {
                Tangential::Stick => {
                    let excess = lt.abs() - self.ctx.arm_friction * ln.max(0.0);
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
        self.check = self.check.merge(c);
    }

    /// The tilt loads at (t, y): the contacts' forces and the centre's acceleration from the
    /// plane model ([`crate::model::tipping::TipGeometry::loads`]); none while riding. `None` without a tipping
    /// geometry or where the plane model's forces are not finite.
    fn tilt_loads(&self, t: f64, y: &[f64; 6]) -> Option<LoadSample> {
        let geo = self.ctx.tip.as_ref()?;
        if self.riding {
            return Some(LoadSample::none(t));
        }
        let m = self.ctx.mass;
        let mut forces = [DVec2::ZERO; active_set::MAX_CONTACTS];
        let accel = if self.active.iter().all(Option::is_none) {
            // Free sliding: the belt alone, m a = F_belt; the step's first derivative is
            // usually the last step's end (first same as last).
            match self.last_free.get() {
                Some((ft, fy, dy)) if ft == t && fy == *y => DVec2::new(dy[3], dy[4]),
                _ => {
                    let f = self.belt_wrench(y);
                    DVec2::new(f[0], f[1]) / m
                }
            }
        } else {
            let (a, f) = self.evaluated(t, y, |e| (e.accel, e.forces));
            for (slot, f) in forces.iter_mut().zip(f) {
                *slot = DVec2::new(f[0], f[1]);
            }
            DVec2::new(a[0], a[1])
        };
        if !(accel.is_finite() && forces.iter().all(|f| f.is_finite())) {
            return None;
        }
        Some(LoadSample {
            t,
            loads: geo.loads(
                y[2],
                &forces,
                accel,
                DVec2::new(y[3] - self.ctx.belt_speed, y[4]),
            ),
        })
    }

    /// The tipping check at an accepted state: the lift-off margin there, and the tilt
    /// followed from the last accepted state of this stretch to this one.
    fn check_tipping(&mut self, t: f64, y: &[f64; 6]) {
        let Some(geo) = self.ctx.tip else {
            return;
        };
        if self.riding && self.rocker.is_flat() {
            return;
        }
        let Some(sample) = self.tilt_loads(t, y) else {
            return;
        };
        if !self.riding {
            self.note_tip(t, geo.lift(&sample.loads), TipCause::Forces);
        }
        self.advance_tilt(sample);
    }

    /// Follow the tilt to `sample` from the last one of this stretch, and keep `sample`.
    fn advance_tilt(&mut self, sample: LoadSample) {
        let Some(geo) = self.ctx.tip else {
            return;
        };
        // A standing box with no edge lifting at either end stays standing (the loads are
        // linear in between): nothing to follow.
        let still = self.rocker.is_flat()
            && TipEdge::ALL
                .iter()
                .zip(&sample.loads)
                .all(|(e, l)| !Rocker::lifts(&geo, *e, l));
        if let Some((from, from_still)) = self.last_load {
            if !(still && from_still) {
                let max_tilt = self.rocker.advance(&geo, &from, &sample);
                self.tip.note_tilt(max_tilt);
                if let Tilt::Over { edge, t } = self.rocker.tilt {
                    let alpha = geo.edge(edge).over_angle;
                    self.tip.note_over(t, edge, alpha);
                    if self.ctx.tip_rule == TippingRule::Verdict {
                        self.halt = true;
                    }
                }
            }
        }
        self.last_load = Some((sample, still));
    }

    /// The end of a stretch at an event: the state just before it is checked like a step
    /// start, and the next stretch starts its loads afresh (they jump at the event).
    pub fn close_stretch(&mut self, t: f64, y: &[f64; 6]) {
        self.check_tipping(t, y);
        self.last_load = None;
    }

    /// The stretch's last loads held on to `t` (a closed-form tail of the motion).
    pub fn hold_loads_to(&mut self, t: f64) {
        if let Some((last, _)) = self.last_load {
            if t > last.t {
                self.advance_tilt(LoadSample { t, ..last });
            }
        }
    }

    /// The parcel rides on unloaded from `t`: the tilt is followed (at most `horizon`
    /// seconds) until the box stands or goes over. Returns whether it went over.
    pub fn finish_tilt(&mut self, t: f64, horizon: f64) -> bool {
        if self.ctx.tip.is_none() || self.rocker.is_flat() {
            return self.rocker.is_over();
        }
        self.last_load = Some((LoadSample::none(t), false));
        let mut now = t;
        while !self.rocker.is_flat() && !self.rocker.is_over() && now < t + horizon {
            now += 0.05;
            self.advance_tilt(LoadSample::none(now));
        }
        self.last_load = None;
        self.rocker.is_over()
    }

    /// A strike's pivot ([`crate::model::tipping::TipGeometry::strike_pivot`]) at t: its
    /// tilt rate joins the tilt.
    pub fn strike_tilt(&mut self, pivot: &Pivot) {
        self.rocker.strike(pivot);
    }

    /// The parcel's torque on the arm about the pivot at an accepted state, M_c =
    /// −(G × F + M_G) for the arm contacts' force F and moment M_G on the parcel (0 without
    /// an arm contact), kept while the arm moves.
    fn note_arm_torque(&mut self, t: f64, y: &[f64; 6]) {
        if self.ctx.drive.is_none() {
            return;
        }
        let torque = if self.active.iter().flatten().any(|c| c.kind.is_arm()) {
            let f = self.evaluated(t, y, |e| e.arm);
            -(y[0] * f[1] - y[1] * f[0] + f[2])
        } else {
            0.0
        };
        if torque.is_finite() {
            self.arm_torque.push((t, torque));
        }
    }

    /// Keep a tipping check at `t` (a margin; the verdict is the tilt's).
    pub fn note_tip(&mut self, t: f64, tip: Tip, cause: TipCause) {
        self.tip.note(t, tip, cause);
    }

    /// Whether the parcel has tipped under [`TippingRule::Verdict`]: the run ends.
    pub fn tipped_out(&self) -> bool {
        self.halt
    }

    /// The tipping record since the last call, reset (a verdict's halt stays).
    pub fn take_tip(&mut self) -> TipRecord {
        std::mem::take(&mut self.tip)
    }

    /// The contact-force record since the last call, reset.
    pub fn take_check(&mut self) -> ContactCheck {
        std::mem::take(&mut self.check)
    }

    /// Free sliding: not riding and no active contact.
    pub fn is_free(&self) -> bool {
        !self.riding && self.active.iter().all(Option::is_none)
    }

    /// The index of the first guard watching `watch`.
    pub fn guard_of(&self, watch: Watch) -> Option<usize> {
        self.watches[..self.n_watches]
            .iter()
            .position(|&w| w == watch)
    }

    /// Free sliding: the time the slip would take to vanish at its present rate,
    /// |w|²/(−w·ẇ) \[s], given dy/dt at y; infinite if the slip does not decrease. Coulomb
    /// friction decreases both |v_r| and |ω| (the footprint is centrally symmetric, model.md
    /// §3), so w·ẇ < 0 whenever w ≠ 0.
    fn time_to_stop(&self, y: &[f64; 6], dy: &[f64; 6]) -> f64 {
        let w = self.slip_vector(y);
        let l = self.ctx.slip_scale;
        let q2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
        let decay = -(w[0] * dy[3] + w[1] * dy[4] + w[2] * l * dy[5]);
        if decay > 0.0 {
            q2 / decay
        } else {
            f64::INFINITY
        }
    }

    /// The end of a free slide from a state y with a slip of about [`END_SLIP`]: the time
    /// left, Δt = |w|²/(−w·ẇ) (constant deceleration along the present direction), and the
    /// riding state at the stop, moved by the mean velocity over Δt (the slip falling
    /// linearly to zero). The errors are a fraction of Δt ≈ 2.5e-8 s in time and of
    /// Δt |w| / 2 ≈ 1e-15 m in position.
    pub fn stop_tail(&self, t: f64, y: &[f64; 6]) -> (f64, [f64; 6]) {
        let dy = self.rhs(t, y);
        let dt = self.time_to_stop(y, &dy);
        if !dt.is_finite() {
            return (0.0, *y);
        }
        let v = self.ctx.belt_speed;
        let mut z = *y;
        z[0] += 0.5 * (y[3] + v) * dt;
        z[1] += 0.5 * y[4] * dt;
        z[2] += 0.5 * y[5] * dt;
        (dt, super::ride::snap(&z, v))
    }
}

/// √(x² + y²) without `hypot`'s care for overflow (the bounds' values are of order one).
#[inline]
fn norm(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::params::Scenario;

    /// The default parcel tilted by 0.1 rad, its lowest corner (3) `lift` above the retracted
    /// arm's line y = 0 at x = 0.5.
    fn state(lift: f64) -> [f64; 6] {
        let s = Scenario::paper_default();
        let rho = crate::geometry::rotate(s.footprint().body_corners()[3], 0.1);
        [0.5 - rho.x, lift - rho.y, 0.1, 2.0, 0.0, 0.0]
    }

    /// A corner pushed by the arm's face and sliding along it: the parcel's torque on the
    /// arm about the pivot is the normal force times its lever, the corner's distance
    /// from the pivot, and the friction along the face (through the pivot) adds no moment:
    /// M_c = −λ_n s (issue 26).
    #[test]
    fn a_corner_on_the_face_loads_the_arm_with_its_normal_force_times_its_lever() {
        let ctx = Context::new(&Scenario::paper_default()).unwrap();
        let mut m = Motion::new(&ctx, [1; 4]);
        let t = 0.05;
        let arm = super::super::context::arm_state(&ctx, t);
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
        let e = m.evaluate(t, &y);
        let normal = e.normal_force[0];
        assert!(normal > 0.0, "the arm pushes: {e:?}");
        assert!(
            e.tangential_force[0].abs() > 0.1 * normal,
            "friction acts: {e:?}"
        );
        let torque = -(y[0] * e.arm[1] - y[1] * e.arm[0] + e.arm[2]);
        assert!(
            (torque + normal * 0.5).abs() < 1e-9 * normal,
            "M_c = {torque}, −λ_n s = {}",
            -normal * 0.5
        );
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
        let i = (0..m.n_watches)
            .find(|&i| m.watches[i] == Watch::Gap(kind))
            .expect("the corner's gap guard");
        // Touches that change nothing: re-armed deeper, then muted.
        while !m.muted[i] {
            m.mute(i);
        }
        assert_eq!(m.guard(i, 0.0, &y0), -1.0);
        // A hair apart (within the closed-contact tolerance): still muted.
        let near = state(0.5 * super::super::tolerances::GAP_TOL);
        m.begin_step(0.0, &near);
        assert_eq!(m.guard(i, 0.0, &near), -1.0, "re-armed while touching");
        // Clearly apart: watched again, at the normal margin.
        let apart = state(1e-6);
        m.begin_step(0.0, &apart);
        assert!(!m.muted[i] && m.extra[i] == 0.0);
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
            let i = (0..m.n_watches)
                .find(|&i| m.watches[i] == Watch::Gap(kind))
                .unwrap();
            let g = m.guard(i, 0.0, &y);
            assert!(
                (g - base).abs() < 1e-15,
                "v_y {vy}: guard starts at {g}, not {base}"
            );
        }
    }
}
