//! Event location on the dense output and the integrate-until-event loop.
//!
//! After every accepted step, each guard g_i(t, y(t)) is sampled on the step's interpolant at
//! t0, at [`INTERIOR_SAMPLES`] equally spaced interior points and at t1. Relative to a guard's
//! [`Direction`], a value is on the *pre-side* if it is > 0 (Falling), < 0 (Rising) or ≠ 0
//! (Either, the side being the sign of the value). An event of guard i happens in the first
//! sample interval that goes from strictly pre-side to the other side or to zero.
//!
//! Consequences of "strictly pre-side first":
//! - a guard that is exactly 0 at the start of a step (or of an `integrate` call) does not
//!   fire until it has been strictly on its pre-side, so a reset that leaves a guard at 0
//!   does not re-trigger at once;
//! - a guard that starts strictly on its pre-side but only a rounding error away from the
//!   crossing (as at a located left root when the caller continues without a reset that
//!   moves it away) fires again almost at once: resets must move the state off the surface
//!   or switch the guard.
//!
//! Touch-and-leave inside a step: a guard may dip to the post-side and back between two
//! samples. Where the samples show a local minimum of the (oriented) guard that is still
//! pre-side — at an interior sample, or at an end of the step where a one-sided difference
//! shows the guard turning — a Brent minimisation on the interpolant looks for a post-side
//! value; if it finds one, that dip is located like a crossing. Dips between two samples
//! where the sampled guard is monotone (two turning points inside one sample interval) can
//! still be missed; limit `h_max` if that matters.
//!
//! Culling: a guard with a known speed limit L (a bound on |dg/dt| over the step, see
//! [`HybridSystem::guard_speed_limit`]) whose two end values are pre-side on the same side
//! with |g(t0)| + |g(t1)| > L (t1 − t0) cannot reach zero inside the step (g(t) ≥
//! max(g(t0) − L (t − t0), g(t1) − L (t1 − t))) and is not sampled inside; if no guard needs
//! them, the interior states are not even interpolated. Likewise a guard with a known
//! curvature limit K (a bound on |d²g/dt²|, [`HybridSystem::guard_curvature_limit`]) whose two
//! end values are pre-side on the same side and keep the parabola g(t0) + (g(t1) − g(t0)) u −
//! (K h²/2) u (1 − u) above zero over the step. With true limits this changes no event: it
//! only skips samples that could not find one.
//!
//! A bracket [a, b] with g(a) pre-side and g(b) not is refined by the Illinois variant of
//! regula falsi (with bisection safeguards) until b − a ≤ max(1e-12 s, 4 ulp(t)); the
//! reported time is a, the "left root": the guard has not flipped there. The earliest event
//! over all guards wins; ties go to the lowest index.
//!
//! References: M. Dowell, P. Jarratt, "A modified regula falsi method for computing the root
//! of an equation", BIT 11 (1971) 168–174 (Illinois); R. P. Brent, *Algorithms for
//! Minimization without Derivatives* (1973), ch. 5 (`localmin`); L. F. Shampine, I. Gladwell,
//! R. W. Brankin, "Reliable solution of special event location problems for ODEs", ACM TOMS
//! 17 (1991) 11–25 (sampling for events that a sign test at the step ends would miss).

use super::stepper::{hand_over, Stepper};
use super::{DenseStep, Dopri5, IntegrateError, Options, Rosenbrock, StepBounds};

/// Steps are scaled with [`HybridSystem::time_to_singularity`] once they exceed this
/// fraction of it (further away, the step is set by the solution's own smoothness).
pub const SINGULAR_NEAR: f64 = 0.05;
/// Largest step as a fraction of [`HybridSystem::time_to_singularity`].
pub const SINGULAR_STEP_FRACTION: f64 = 0.7;
/// |λ| h of an explicit step above which the next is taken by the stiff stepper (DOPRI5 is
/// stable to about 3.3: a step this close is held by stability, not accuracy).
pub const STIFF_ENTER: f64 = 2.5;
/// |λ| h of a stiff step below which DOPRI5 takes over again: the implicit step has not
/// grown beyond what the explicit one could take (at 10 rather than 6 evaluations a step,
/// the implicit one only pays where it is larger).
pub const STIFF_LEAVE: f64 = 3.0;
/// Interior sample points per step and guard (besides t0 and t1).
pub const INTERIOR_SAMPLES: usize = 4;
const SAMPLES: usize = INTERIOR_SAMPLES + 2;
/// Width of the final root bracket \[s] (or 4 ulp of t, whichever is larger).
pub const EVENT_TIME_TOL: f64 = 1e-12;
/// Iteration caps; never reached with sane guards (bisection alone needs ≤ 64 + 1100 for an
/// f64 interval), they only turn a pathological guard into a slightly less precise event.
const MAX_ROOT_ITERS: usize = 200;
const MAX_MIN_ITERS: usize = 200;
/// Relative length of the one-sided difference that tests whether a guard turns at a step end.
const PROBE_FRACTION: f64 = 1e-6;
/// Relative resolution of the minimisation (≈ √ε: a minimum is flat below that).
const MIN_REL_TOL: f64 = 1.5e-8;

/// Which sign change of a guard counts as an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// From negative to positive.
    Rising,
    /// From positive to negative.
    Falling,
    /// Either way.
    Either,
}

impl Direction {
    /// The orientation σ such that σ·g > 0 on the pre-side, if `g` is strictly pre-side.
    #[inline]
    fn pre_side(self, g: f64) -> Option<f64> {
        match self {
            Direction::Falling => (g > 0.0).then_some(1.0),
            Direction::Rising => (g < 0.0).then_some(-1.0),
            Direction::Either => (g != 0.0 && !g.is_nan()).then(|| g.signum()),
        }
    }
}

/// A system with a right-hand side and guard functions.
pub trait HybridSystem<const N: usize> {
    /// dy/dt at (t, y).
    fn rhs(&self, t: f64, y: &[f64; N]) -> [f64; N];
    /// Number of guard functions.
    fn guard_count(&self) -> usize {
        0
    }
    /// Value of guard `i` at (t, y).
    fn guard(&self, i: usize, t: f64, y: &[f64; N]) -> f64 {
        let _ = (i, t, y);
        0.0
    }
    /// A bound on |dg_i/dt| along the step's interpolant, whose derivatives `bounds` bounds,
    /// or infinity if none is known (the default). It lets the event locator skip the
    /// interior samples of a guard that cannot reach zero in the step (see the module
    /// documentation). It must be a true bound: an underestimate can hide an event.
    fn guard_speed_limit(&self, i: usize, bounds: &StepBounds<N>) -> f64 {
        let _ = (i, bounds);
        f64::INFINITY
    }
    /// Whether guard `i` may dip to zero and back between two samples in this step without
    /// the samples showing it (default: no). If so, every sample interval whose two pre-side
    /// values are too close to zero to rule out a dip at the guard's speed limit
    /// (σg_a + σg_b < limit × width) is searched for one, however the samples look.
    fn guard_may_dip(&self, i: usize, bounds: &StepBounds<N>) -> bool {
        let _ = (i, bounds);
        false
    }
    /// A bound K on |d²g_i/dt²| along the step's interpolant, where guard `i` may dip
    /// ([`HybridSystem::guard_may_dip`]), or infinity if none is known (the default). With it
    /// a sample interval [a, b] of width w is searched only where the guard could reach zero
    /// between its two pre-side values, g(t) ≥ g_a + (g_b − g_a) u − (K w²/2) u (1 − u),
    /// u = (t − a)/w, instead of wherever g_a + g_b < L w at its speed limit L: far fewer
    /// searches near a touch. It must be a true bound of a guard that is smooth over the
    /// step (a max of two guards is not).
    fn guard_curvature_limit(&self, i: usize, bounds: &StepBounds<N>) -> f64 {
        let _ = (i, bounds);
        f64::INFINITY
    }
    /// Crossing direction that counts for guard `i`.
    fn guard_direction(&self, i: usize) -> Direction {
        let _ = i;
        Direction::Either
    }
    /// Called before every step, before [`HybridSystem::begin_step`]: a system whose motion
    /// keeps constraints only at the acceleration level may put the state back onto them
    /// (coordinate projection; E. Hairer, C. Lubich, M. Roche, *The Numerical Solution of
    /// Differential-Algebraic Systems by Runge–Kutta Methods*, 1989, ch. VII). Returns whether
    /// it moved `y` (the next step then evaluates its first derivative afresh). Default: no.
    fn project(&mut self, t: f64, y: &mut [f64; N]) -> bool {
        let _ = (t, y);
        false
    }
    /// Called before every step with the step's initial point; a system may update internal
    /// references here (it stays fixed during the step).
    fn begin_step(&mut self, t: f64, y: &[f64; N]) {
        let _ = (t, y);
    }
    /// The time from (t, y) to a predicted point where the solution stops being smooth
    /// (such as a Coulomb stop) \[s], asked after `begin_step`; infinite if none (the
    /// default). Where the solution approaches such a point like a power of the time left,
    /// the step that meets the tolerance shrinks in proportion to the time left. The
    /// integrator therefore scales its proposed step by the ratio of two successive values,
    /// instead of proposing the last step's size and having it rejected, and keeps every step
    /// below [`SINGULAR_STEP_FRACTION`] of it, so that no step reaches over the point.
    fn time_to_singularity(&self, t: f64, y: &[f64; N]) -> f64 {
        let _ = (t, y);
        f64::INFINITY
    }
    /// An estimate of the fastest decay rate |λ| of the right-hand side at (t, y) [1/s], asked
    /// after `begin_step` (default 0: not stiff). Where an explicit step would be held near
    /// its stability limit (|λ| h ≥ [`STIFF_ENTER`]), the loop steps with the linearly
    /// implicit [`Rosenbrock`] stepper instead, until its own step no longer needs it
    /// (|λ| h < [`STIFF_LEAVE`]). The estimate only chooses the method: both are accurate.
    fn stiffness(&self, t: f64, y: &[f64; N]) -> f64 {
        let _ = (t, y);
        0.0
    }
    /// Whether the system asks to stop at this step's start, asked after `begin_step`
    /// (default: never): `integrate` then returns [`StopReason::Halt`] there.
    fn halt(&self) -> bool {
        false
    }
    /// Whether `begin_step` may change `rhs` (default: yes). Return `false` if it never does:
    /// the integrator then reuses the derivative at the end of a step as the first stage of
    /// the next ("first same as last"), saving one of seven rhs evaluations per step.
    fn begin_step_changes_rhs(&self) -> bool {
        true
    }
}

/// A located event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventHit {
    /// Which guard.
    pub index: usize,
    /// Left root: the latest time found where the guard has not flipped yet \[s].
    pub t: f64,
}

/// Why `integrate` stopped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StopReason {
    /// Reached `t_end`.
    End,
    /// A guard event.
    Event(EventHit),
    /// The system asked to stop ([`HybridSystem::halt`]) at the start of a step.
    Halt,
}

/// Where `integrate` stopped.
#[derive(Debug, Clone, PartialEq)]
pub struct Stop<const N: usize> {
    /// Time of the stop \[s]: `t_end`, or the event's left root.
    pub t: f64,
    /// State at `t` (from the interpolant at an event).
    pub y: [f64; N],
    /// End or event.
    pub reason: StopReason,
    /// Accepted steps taken.
    pub steps: usize,
}

/// Integrate from (t0, y0) until `t_end` or the first event, whichever comes first. The
/// observer sees every accepted step, the last one truncated at the event.
///
/// `t_end` may be `+∞` (run until an event or `max_steps`). If `t_end <= t0` nothing is
/// integrated and the stop is `End` at (t0, y0).
pub fn integrate<const N: usize, S: HybridSystem<N>, O: FnMut(&DenseStep<N>)>(
    system: &mut S,
    t0: f64,
    y0: [f64; N],
    t_end: f64,
    options: &Options,
    observer: O,
) -> Result<Stop<N>, IntegrateError> {
    let mut stepper = Dopri5::new(*options);
    integrate_with(&mut stepper, system, t0, y0, t_end, observer)
}

/// [`integrate`] with a caller-owned stepper, so that its step-size proposal carries over
/// from one call to the next (e.g. across event resets). Uses `stepper.options`.
pub fn integrate_with<const N: usize, S: HybridSystem<N>, O: FnMut(&DenseStep<N>)>(
    stepper: &mut Dopri5<N>,
    system: &mut S,
    t0: f64,
    y0: [f64; N],
    t_end: f64,
    mut observer: O,
) -> Result<Stop<N>, IntegrateError> {
    if !t0.is_finite() || t_end.is_nan() || y0.iter().any(|v| !v.is_finite()) {
        return Err(IntegrateError::NonFinite { t: t0 });
    }
    let max_steps = stepper.options.max_steps;
    let start = stepper.stats();
    let mut stiff = Rosenbrock::new(stepper.options);
    let mut in_stiff = false;
    let (mut t, mut y) = (t0, y0);
    let mut steps = 0;
    // time_to_singularity at the previous step's start
    let mut last_singular = f64::INFINITY;
    let h_max = stepper.options.h_max;
    while t < t_end {
        let now = stepper.stats();
        let extra = stiff.stats();
        if (now.accepted + now.rejected + extra.accepted + extra.rejected)
            - (start.accepted + start.rejected)
            >= max_steps
        {
            return Err(IntegrateError::TooManySteps { max_steps });
        }
        let projected = system.project(t, &mut y);
        system.begin_step(t, &y);
        if system.halt() {
            return Ok(Stop {
                t,
                y,
                reason: StopReason::Halt,
                steps,
            });
        }
        if projected || system.begin_step_changes_rhs() {
            stepper.forget_derivative();
            stiff.forget_derivative();
        }
        let sys: &S = system;
        let singular = sys.time_to_singularity(t, &y);
        // (A singularity closer than a few smallest steps is left to the step control.)
        if singular > 1e3 * stepper.options.h_min && singular.is_finite() {
            let near = stepper
                .proposed_step()
                .is_some_and(|h| h > SINGULAR_NEAR * last_singular);
            if near {
                stepper.scale_proposed_step((singular / last_singular).clamp(0.2, 1.0));
            }
            let limit = SINGULAR_STEP_FRACTION * singular;
            if limit < h_max || h_max.is_nan() || h_max <= 0.0 {
                stepper.options.h_max = limit;
            }
            last_singular = singular;
        } else {
            last_singular = f64::INFINITY;
        }
        // Stiff or not: the explicit step against its stability limit, the implicit step
        // against the rate at which it stops being needed.
        let rate = sys.stiffness(t, &y);
        let use_stiff = rate > 0.0
            && if in_stiff {
                stiff
                    .proposed_step()
                    .is_some_and(|h| rate * h >= STIFF_LEAVE)
            } else {
                stepper
                    .proposed_step()
                    .is_some_and(|h| rate * h >= STIFF_ENTER)
            };
        if use_stiff && !in_stiff {
            hand_over(stepper, &mut stiff);
        } else if !use_stiff && in_stiff {
            hand_over(&stiff, stepper);
        }
        in_stiff = use_stiff;
        let step = if use_stiff {
            stiff.options_mut().h_max = stepper.options.h_max;
            Stepper::step(&mut stiff, |tt, yy| sys.rhs(tt, yy), t, &y, t_end)
        } else {
            Stepper::step(stepper, |tt, yy| sys.rhs(tt, yy), t, &y, t_end)
        };
        stepper.options.h_max = h_max;
        let step = step?;
        steps += 1;
        if let Some(hit) = locate_event(sys, &step)? {
            let part = step.truncated(hit.t);
            observer(&part);
            return Ok(Stop {
                t: hit.t,
                y: part.y1,
                reason: StopReason::Event(hit),
                steps,
            });
        }
        observer(&step);
        t = step.t1;
        y = step.y1;
    }
    Ok(Stop {
        t,
        y,
        reason: StopReason::End,
        steps,
    })
}

/// The earliest event of `system`'s guards on `step` (see the module documentation), or
/// `None`. Errors with `NonFinite` if a guard evaluates to NaN.
pub fn locate_event<const N: usize, S: HybridSystem<N> + ?Sized>(
    system: &S,
    step: &DenseStep<N>,
) -> Result<Option<EventHit>, IntegrateError> {
    let n_guards = system.guard_count();
    if n_guards == 0 {
        return Ok(None);
    }
    let (t0, t1) = (step.t0, step.t1);
    let h = t1 - t0;
    // The ends are known; the interior states come from the interpolant, once for all guards
    // and only when a guard needs them.
    let mut ts = [t1; SAMPLES];
    let mut ys = [step.y1; SAMPLES];
    (ts[0], ys[0]) = (t0, step.y0);
    for (j, t) in ts.iter_mut().enumerate().take(SAMPLES - 1).skip(1) {
        *t = t0 + h * (j as f64 / (SAMPLES - 1) as f64);
    }
    let mut interior = false;
    let bounds = step.bounds();
    let mut best: Option<EventHit> = None;
    let checked = |t: f64, v: f64| {
        if v.is_nan() {
            Err(IntegrateError::NonFinite { t })
        } else {
            Ok(v)
        }
    };
    for i in 0..n_guards {
        let dir = system.guard_direction(i);
        let mut g = [0.0; SAMPLES];
        g[0] = checked(t0, system.guard(i, t0, &ys[0]))?;
        let mut end_known = false;
        let limit_speed = system.guard_speed_limit(i, &bounds);
        if limit_speed.is_finite() {
            if let Some(s) = dir.pre_side(g[0]) {
                // Too far from zero to reach it at the limit speed: no event in the step.
                let reach = limit_speed * h;
                if s * g[0] > reach {
                    continue;
                }
                g[SAMPLES - 1] = checked(t1, system.guard(i, t1, &ys[SAMPLES - 1]))?;
                end_known = true;
                if dir.pre_side(g[SAMPLES - 1]) == Some(s) && s * (g[0] + g[SAMPLES - 1]) > reach {
                    continue;
                }
            }
        }
        let may_dip = limit_speed.is_finite() && system.guard_may_dip(i, &bounds);
        let dip_bound = if !may_dip {
            DipBound::None
        } else {
            match system.guard_curvature_limit(i, &bounds) {
                k if k.is_finite() => DipBound::Curvature(k),
                _ => DipBound::Speed(limit_speed),
            }
        };
        // The dip test a sample interval gets, over the whole step from its end values: a
        // guard whose curvature bound rules out a zero has no event in the step, so its
        // interior samples (which could only find a zero) are skipped. (A speed bound's
        // whole-step test is the cull above.)
        if let (DipBound::Curvature(_), Some(s)) = (dip_bound, dir.pre_side(g[0])) {
            if !end_known {
                g[SAMPLES - 1] = checked(t1, system.guard(i, t1, &ys[SAMPLES - 1]))?;
                end_known = true;
            }
            if dir.pre_side(g[SAMPLES - 1]) == Some(s)
                && !dip_bound.may_reach_zero(s * g[0], s * g[SAMPLES - 1], h)
            {
                continue;
            }
        }
        if !interior {
            for j in 1..SAMPLES - 1 {
                ys[j] = step.eval(ts[j]);
            }
            interior = true;
        }
        let last = if end_known { SAMPLES - 1 } else { SAMPLES };
        for j in 1..last {
            g[j] = checked(ts[j], system.guard(i, ts[j], &ys[j]))?;
        }
        let limit = best.map_or(f64::INFINITY, |b| b.t);
        let guard_at = |t: f64| -> Result<f64, IntegrateError> {
            checked(t, system.guard(i, t, &step.eval(t)))
        };
        if let Some(t) = first_event(guard_at, dir, dip_bound, &ts, &g, limit)? {
            if t < limit {
                best = Some(EventHit { index: i, t });
            }
        }
    }
    Ok(best)
}

/// What bounds a guard between two samples, for the search of dips the samples cannot show.
#[derive(Debug, Clone, Copy)]
enum DipBound {
    /// Nothing known: only dips the samples show are searched.
    None,
    /// |dg/dt| ≤ L.
    Speed(f64),
    /// |d²g/dt²| ≤ K.
    Curvature(f64),
}

impl DipBound {
    /// Whether the guard may reach zero between two pre-side oriented values `ha`, `hb`
    /// (> 0) a time `w` apart.
    fn may_reach_zero(self, ha: f64, hb: f64, w: f64) -> bool {
        // (Also false for a NaN width.)
        if w.is_nan() || w <= 0.0 {
            return false;
        }
        match self {
            DipBound::None => false,
            // g ≥ max(ha − L s, hb − L (w − s)), lowest where the two meet.
            DipBound::Speed(l) => ha + hb < l * w,
            // g ≥ ha + (hb − ha) u − c u (1 − u), c = K w²/2, lowest at
            // u* = ½ − (hb − ha)/(2c) if that lies inside.
            DipBound::Curvature(k) => {
                let c = 0.5 * k * w * w;
                if c.is_nan() || c <= 0.0 {
                    return false;
                }
                let u = 0.5 - (hb - ha) / (2.0 * c);
                (0.0..=1.0).contains(&u) && ha + (hb - ha) * u - c * u * (1.0 - u) <= 0.0
            }
        }
    }
}

/// The first event of one guard on the sample grid `ts` with values `g`, if it starts before
/// `limit`.
fn first_event<G: Fn(f64) -> Result<f64, IntegrateError>>(
    guard_at: G,
    dir: Direction,
    dip_bound: DipBound,
    ts: &[f64; SAMPLES],
    g: &[f64; SAMPLES],
    limit: f64,
) -> Result<Option<f64>, IntegrateError> {
    const K1: usize = SAMPLES - 1;
    // Oriented guard σ·g (pre-side > 0).
    let oriented = |s: f64, t: f64| guard_at(t).map(|v| s * v);
    // σ if both samples are strictly pre-side on the same side.
    let same_pre = |a: usize, b: usize| match (dir.pre_side(g[a]), dir.pre_side(g[b])) {
        (Some(sa), Some(sb)) if sa == sb => Some(sa),
        _ => None,
    };
    let probe = PROBE_FRACTION * (ts[1] - ts[0]);

    // Dip inside the first interval: rising at the first sample but falling at t0.
    if let Some(s) = same_pre(0, 1) {
        if ts[0] >= limit {
            return Ok(None);
        }
        if s * g[1] > s * g[0] && probe > 0.0 {
            let tp = ts[0] + probe;
            let hp = oriented(s, tp)?;
            if hp <= 0.0 {
                return left_root(|t| oriented(s, t), ts[0], s * g[0], tp, hp).map(Some);
            }
            let slope = (s * g[0] - hp) / probe;
            if hp < s * g[0] && !end_dip_clear(s * g[0], slope, s * g[1], ts[1] - ts[0]) {
                if let Some((u, hu)) = dip(|t| oriented(s, t), ts[0], ts[1], tp, hp)? {
                    return left_root(|t| oriented(s, t), ts[0], s * g[0], u, hu).map(Some);
                }
            }
        }
    }
    for j in 0..K1 {
        if ts[j] >= limit {
            return Ok(None);
        }
        // A sampled crossing in [ts_j, ts_j+1].
        if let Some(s) = dir.pre_side(g[j]) {
            if s * g[j + 1] <= 0.0 {
                let f = |t| oriented(s, t);
                return left_root(f, ts[j], s * g[j], ts[j + 1], s * g[j + 1]).map(Some);
            }
        }
        // Both ends pre-side, but closer to zero than the guard's bounds allow a dip
        // between them to be ruled out: search the interval.
        if let (Some(s), false) = (same_pre(j, j + 1), matches!(dip_bound, DipBound::None)) {
            let (ha, hb) = (s * g[j], s * g[j + 1]);
            let f = |t| oriented(s, t);
            if let Some((u, hu)) = bounded_dip(&f, dip_bound, (ts[j], ha), (ts[j + 1], hb))? {
                return left_root(f, ts[j], ha, u, hu).map(Some);
            }
        }
        // A local minimum of the oriented samples at j + 1 that is still pre-side.
        if j + 2 <= K1 {
            if let (Some(s), Some(s2)) = (same_pre(j, j + 1), same_pre(j + 1, j + 2)) {
                let (ha, hm, hb) = (s * g[j], s * g[j + 1], s * g[j + 2]);
                if s == s2
                    && ((hm < ha && hm <= hb) || (hm <= ha && hm < hb))
                    && !interior_dip_clear(ha, hm, hb)
                {
                    let f = |t| oriented(s, t);
                    if let Some((u, hu)) = dip(f, ts[j], ts[j + 2], ts[j + 1], hm)? {
                        return left_root(|t| oriented(s, t), ts[j], ha, u, hu).map(Some);
                    }
                }
            }
        }
    }
    // Dip inside the last interval: falling at the last interior sample, rising at t1.
    if let Some(s) = same_pre(K1 - 1, K1) {
        let (ha, hb) = (s * g[K1 - 1], s * g[K1]);
        if ts[K1 - 1] < limit && ha > hb && probe > 0.0 {
            let tp = ts[K1] - probe;
            let hp = oriented(s, tp)?;
            if hp <= 0.0 {
                return left_root(|t| oriented(s, t), ts[K1 - 1], ha, tp, hp).map(Some);
            }
            let slope = (hb - hp) / probe;
            if hp < hb && !end_dip_clear(hb, slope, ha, ts[K1] - ts[K1 - 1]) {
                if let Some((u, hu)) = dip(|t| oriented(s, t), ts[K1 - 1], ts[K1], tp, hp)? {
                    return left_root(|t| oriented(s, t), ts[K1 - 1], ha, u, hu).map(Some);
                }
            }
        }
    }
    Ok(None)
}

/// Splits of an interval by a guard's curvature bound before a full minimisation
/// ([`bounded_dip`]).
const MAX_DIP_SPLITS: usize = 4;

/// A point in [a, b] where the oriented guard `h` (pre-side > 0 at both ends) is ≤ 0, if its
/// bound allows one: a minimisation from the midpoint ([`dip`]), unless a curvature bound
/// rules the dip out first. With |g̈| ≤ K the guard stays above the parabola
/// ha + (hb − ha) u − (K w²/2) u (1 − u); where that dips below zero, the interval is split
/// at the parabola's lowest point by one evaluation and each half tested again (a quarter as
/// deep), up to [`MAX_DIP_SPLITS`] times: most intervals near a touch are cleared by a split
/// or two, and only the rest are minimised, once.
fn bounded_dip<H: Fn(f64) -> Result<f64, IntegrateError>>(
    h: &H,
    bound: DipBound,
    (a, ha): (f64, f64),
    (b, hb): (f64, f64),
) -> Result<Option<(f64, f64)>, IntegrateError> {
    if !bound.may_reach_zero(ha, hb, b - a) {
        return Ok(None);
    }
    if let DipBound::Curvature(k) = bound {
        match clear_by_splits(h, k, (a, ha), (b, hb), MAX_DIP_SPLITS)? {
            Split::Cleared => return Ok(None),
            Split::Found(t, ht) => return Ok(Some((t, ht))),
            Split::Undecided => {}
        }
    }
    let m = a + 0.5 * (b - a);
    let hm = h(m)?;
    if hm <= 0.0 {
        return Ok(Some((m, hm)));
    }
    dip(h, a, b, m, hm)
}

/// What splitting an interval by a curvature bound found.
enum Split {
    /// No dip is possible.
    Cleared,
    /// The guard is ≤ 0 here.
    Found(f64, f64),
    /// The bound could not rule a dip out within the splits allowed.
    Undecided,
}

/// See [`bounded_dip`].
fn clear_by_splits<H: Fn(f64) -> Result<f64, IntegrateError>>(
    h: &H,
    k: f64,
    (a, ha): (f64, f64),
    (b, hb): (f64, f64),
    splits: usize,
) -> Result<Split, IntegrateError> {
    let w = b - a;
    let bound = DipBound::Curvature(k);
    if !bound.may_reach_zero(ha, hb, w) {
        return Ok(Split::Cleared);
    }
    if splits == 0 {
        return Ok(Split::Undecided);
    }
    let c = 0.5 * k * w * w;
    let m = a + w * (0.5 - (hb - ha) / (2.0 * c)).clamp(0.0, 1.0);
    if !(m > a && m < b) {
        return Ok(Split::Undecided);
    }
    let hm = h(m)?;
    if hm <= 0.0 {
        return Ok(Split::Found(m, hm));
    }
    match clear_by_splits(h, k, (a, ha), (m, hm), splits - 1)? {
        Split::Cleared => clear_by_splits(h, k, (m, hm), (b, hb), splits - 1),
        other => Ok(other),
    }
}

/// How far above zero, in units of its own depth, the quadratic model of a sampled local
/// minimum must lie for the minimisation to be skipped (see [`interior_dip_clear`]).
const DIP_CLEARANCE: f64 = 2.0;

/// Whether a pre-side local minimum of the oriented samples (ha, hm, hb), equally spaced, is
/// so far above zero that looking for a dip is pointless: the parabola through them has its
/// minimum m above zero by more than [`DIP_CLEARANCE`] times its depth below the higher
/// sample. A smooth guard departs from that parabola by far less than the parabola's own
/// variation between samples; the minimisation would only confirm a positive minimum.
fn interior_dip_clear(ha: f64, hm: f64, hb: f64) -> bool {
    let curvature = ha + hb - 2.0 * hm;
    if curvature <= 0.0 {
        return false;
    }
    let m = hm - (hb - ha) * (hb - ha) / (8.0 * curvature);
    m > DIP_CLEARANCE * (ha.max(hb) - m)
}

/// [`interior_dip_clear`] for a minimum next to a step end: the end value `he`, the rate at
/// which the guard falls into the interval there (`slope` > 0), and the value `ho` at the
/// interval's other end, a distance `w` away.
fn end_dip_clear(he: f64, slope: f64, ho: f64, w: f64) -> bool {
    let curvature = (ho - he + slope * w) / (w * w);
    if curvature <= 0.0 || !slope.is_finite() {
        return false;
    }
    let m = he - slope * slope / (4.0 * curvature);
    m > DIP_CLEARANCE * (he.max(ho) - m)
}

/// Final bracket width at time scale `t` \[s].
#[inline]
fn time_tol(t: f64) -> f64 {
    let t = t.abs();
    let ulp = f64::from_bits(t.to_bits() + 1) - t;
    EVENT_TIME_TOL.max(4.0 * ulp)
}

/// Left root of the oriented guard `h` in [a, b], given h(a) = `ha` > 0 ≥ h(b) = `hb`:
/// Illinois regula falsi, with a bisection step whenever two iterations failed to halve the
/// bracket, until b − a ≤ [`time_tol`]. Returns the final a (h(a) > 0).
fn left_root<H: Fn(f64) -> Result<f64, IntegrateError>>(
    h: H,
    mut a: f64,
    mut ha: f64,
    mut b: f64,
    mut hb: f64,
) -> Result<f64, IntegrateError> {
    // Which end moved last: -1 = b, +1 = a (Illinois halves the value at a stuck end).
    let mut side = 0i8;
    let mut widths = [f64::INFINITY; 2];
    for _ in 0..MAX_ROOT_ITERS {
        let w = b - a;
        let tol = time_tol(a.abs().max(b.abs()));
        if w <= tol {
            break;
        }
        let mut c = if w > 0.5 * widths[1] {
            a + 0.5 * w
        } else {
            // ha > 0 ≥ hb, so the secant point lies in [a, b].
            a + w * (ha / (ha - hb))
        };
        // Keep c at least tol/2 inside so that the bracket always shrinks by that much, and a
        // root hugging one end is enclosed in a final bracket of width ≤ tol.
        let m = 0.5 * tol;
        c = c.max(a + m).min(b - m);
        let hc = h(c)?;
        if hc <= 0.0 {
            b = c;
            hb = hc;
            if side == -1 {
                ha *= 0.5;
            }
            side = -1;
        } else {
            a = c;
            ha = hc;
            if side == 1 {
                hb *= 0.5;
            }
            side = 1;
        }
        widths = [w, widths[0]];
    }
    Ok(a)
}

/// Brent's `localmin` on [a, b] from the point x (value `fx`), stopped as soon as the
/// function reaches ≤ 0: returns that point and value, or `None` if the minimum found is > 0.
fn dip<H: Fn(f64) -> Result<f64, IntegrateError>>(
    h: H,
    mut a: f64,
    mut b: f64,
    x0: f64,
    f0: f64,
) -> Result<Option<(f64, f64)>, IntegrateError> {
    const CGOLD: f64 = 0.381_966_011_250_105_1;
    let (mut x, mut w, mut v) = (x0, x0, x0);
    let (mut fx, mut fw, mut fv) = (f0, f0, f0);
    let (mut d, mut e) = (0.0f64, 0.0f64);
    for _ in 0..MAX_MIN_ITERS {
        let xm = 0.5 * (a + b);
        let tol1 = MIN_REL_TOL * x.abs() + EVENT_TIME_TOL;
        let tol2 = 2.0 * tol1;
        if (x - xm).abs() <= tol2 - 0.5 * (b - a) {
            break;
        }
        let mut golden = true;
        if e.abs() > tol1 {
            // Parabola through (v, fv), (w, fw), (x, fx).
            let r = (x - w) * (fx - fv);
            let mut q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            }
            q = q.abs();
            let e_prev = e;
            e = d;
            if !(p.abs() >= (0.5 * q * e_prev).abs() || p <= q * (a - x) || p >= q * (b - x)) {
                d = p / q;
                let u = x + d;
                if u - a < tol2 || b - u < tol2 {
                    d = tol1.copysign(xm - x);
                }
                golden = false;
            }
        }
        if golden {
            e = if x >= xm { a - x } else { b - x };
            d = CGOLD * e;
        }
        let u = if d.abs() >= tol1 {
            x + d
        } else {
            x + tol1.copysign(d)
        };
        let fu = h(u)?;
        if fu <= 0.0 {
            return Ok(Some((u, fu)));
        }
        if fu <= fx {
            if u >= x {
                a = x;
            } else {
                b = x;
            }
            (v, fv, w, fw, x, fx) = (w, fw, x, fx, u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv, w, fw) = (w, fw, u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::super::test_models::*;
    use super::*;
    use proptest::prelude::*;
    use std::f64::consts::{PI, TAU};

    /// v = (T − t)^{3/2} → 0 at T = 1: v' = −(3/2) v^{1/3}, not smooth at T (its second
    /// derivative is infinite there), like a Coulomb stop. With `hint`, the system reports
    /// the exact time left, v^{2/3}.
    struct PowerStop {
        hint: bool,
    }

    impl HybridSystem<2> for PowerStop {
        fn rhs(&self, _t: f64, y: &[f64; 2]) -> [f64; 2] {
            let v = y[1].max(0.0);
            [v, -1.5 * v.cbrt()]
        }
        fn begin_step_changes_rhs(&self) -> bool {
            false
        }
        fn time_to_singularity(&self, _t: f64, y: &[f64; 2]) -> f64 {
            if self.hint {
                y[1].max(0.0).powf(2.0 / 3.0)
            } else {
                f64::INFINITY
            }
        }
    }

    /// Prothero–Robinson y' = λ(y − cos t) − sin t (exact y = cos t) with λ = −1e5, guard
    /// y − 1/2 (falling at t = π/3); with `report` the system tells its stiffness |λ|.
    struct StiffCosine {
        report: bool,
    }

    impl HybridSystem<1> for StiffCosine {
        fn rhs(&self, t: f64, y: &[f64; 1]) -> [f64; 1] {
            [-1e5 * (y[0] - t.cos()) - t.sin()]
        }
        fn guard_count(&self) -> usize {
            1
        }
        fn guard(&self, _i: usize, _t: f64, y: &[f64; 1]) -> f64 {
            y[0] - 0.5
        }
        fn guard_direction(&self, _i: usize) -> Direction {
            Direction::Falling
        }
        fn stiffness(&self, _t: f64, _y: &[f64; 1]) -> f64 {
            if self.report {
                1e5
            } else {
                0.0
            }
        }
    }

    /// A stiff system that reports its stiffness is stepped by the implicit stepper: the
    /// event y = 1/2 is found at π/3 to within the tolerance, in a small fraction of the
    /// explicit method's steps (held at |λ| h ≈ 3.3 by stability).
    #[test]
    fn stiff_stretches_switch_to_the_implicit_stepper() {
        let run = |report: bool| {
            let options = Options {
                rtol: 1e-8,
                atol: 1e-10,
                max_steps: 1_000_000,
                ..Options::default()
            };
            integrate(
                &mut StiffCosine { report },
                0.0,
                [1.0],
                2.0,
                &options,
                |_| {},
            )
            .unwrap()
        };
        let (explicit, implicit) = (run(false), run(true));
        for stop in [&explicit, &implicit] {
            assert!(matches!(stop.reason, StopReason::Event(_)));
            assert!((stop.t - PI / 3.0).abs() < 1e-7, "event at {}", stop.t);
            assert!((stop.y[0] - 0.5).abs() < 1e-8);
        }
        assert!(
            implicit.steps * 5 < explicit.steps,
            "{} implicit against {} explicit steps",
            implicit.steps,
            explicit.steps
        );
    }

    /// Up to 1e-6 s before the singularity: with the time left reported, the steps shrink
    /// with it and none is rejected (without it, about a third are), no step reaches over
    /// the singularity, and the solution stays within the tolerance of the exact one.
    #[test]
    fn steps_scale_with_the_time_to_a_singularity() {
        let run = |hint: bool| {
            let mut stepper = Dopri5::new(Options {
                rtol: 1e-8,
                atol: 1e-9,
                ..Options::default()
            });
            let mut max_ratio: f64 = 0.0;
            let stop = integrate_with(
                &mut stepper,
                &mut PowerStop { hint },
                0.0,
                [0.0, 1.0],
                1.0 - 1e-6,
                |step| max_ratio = max_ratio.max((step.t1 - step.t0) / (1.0 - step.t0)),
            )
            .unwrap();
            (stop, stepper.stats(), max_ratio)
        };
        let (plain, plain_stats, _) = run(false);
        let (hinted, stats, max_ratio) = run(true);
        assert_eq!(stats.rejected, 0, "{stats:?}");
        assert!(plain_stats.rejected >= 5, "{plain_stats:?}");
        assert!(
            stats.rhs_evals < plain_stats.rhs_evals,
            "{stats:?} {plain_stats:?}"
        );
        assert!(max_ratio < SINGULAR_STEP_FRACTION + 0.05, "{max_ratio}");
        // x = (1 − (T − t)^{5/2}) / (5/2), v = (T − t)^{3/2}
        let s: f64 = 1e-6;
        let exact = [(1.0 - s.powf(2.5)) / 2.5, s.powf(1.5)];
        for stop in [&plain, &hinted] {
            assert!((stop.y[0] - exact[0]).abs() < 1e-8, "{:?}", stop.y);
            assert!((stop.y[1] - exact[1]).abs() < 1e-8, "{:?}", stop.y);
        }
    }

    fn hit<const N: usize>(stop: &Stop<N>) -> EventHit {
        match stop.reason {
            StopReason::Event(hit) => hit,
            other => panic!("expected an event, got {other:?} at t = {}", stop.t),
        }
    }

    /// y' = y from 1, asking to stop once a step starts at y ≥ 2.
    struct Doubling {
        halt: bool,
    }

    impl HybridSystem<1> for Doubling {
        fn rhs(&self, _t: f64, y: &[f64; 1]) -> [f64; 1] {
            [y[0]]
        }
        fn begin_step(&mut self, _t: f64, y: &[f64; 1]) {
            self.halt = y[0] >= 2.0;
        }
        fn halt(&self) -> bool {
            self.halt
        }
    }

    /// A system's halt stops the integration at the start of the first step where it asks,
    /// on the solution (y = e^t there), having observed every step before it.
    #[test]
    fn halt_stops_at_the_step_start_where_it_is_asked() {
        let mut sys = Doubling { halt: false };
        let mut observed_end = 0.0;
        let stop = integrate(&mut sys, 0.0, [1.0], 10.0, &tight(), |s| {
            observed_end = s.t1
        })
        .expect("integrates");
        assert_eq!(stop.reason, StopReason::Halt);
        assert!(stop.y[0] >= 2.0 && stop.t < 10.0, "{stop:?}");
        assert!((stop.y[0] - stop.t.exp()).abs() < 1e-9 * stop.y[0]);
        assert_eq!(
            observed_end, stop.t,
            "the last observed step ends where it halted"
        );
        // The step before it started below 2.
        assert!(stop.steps >= 1);
    }

    fn tight() -> Options {
        Options {
            rtol: 1e-12,
            atol: 1e-14,
            ..Options::default()
        }
    }

    /// y' = 0 with time-only guards, from t0, to t_end = 20.
    fn time_event(
        g: impl Fn(usize, f64) -> f64,
        dirs: &[Direction],
        t0: f64,
        o: &Options,
    ) -> Stop<1> {
        let mut sys = TimeGuards {
            guards: g,
            directions: dirs.to_vec(),
        };
        integrate(&mut sys, t0, [0.0], 20.0, o, |_| {}).unwrap()
    }

    /// Bouncing ball from 1 m, e = 0.8: six impact times match t₁ = √(2h₀/g),
    /// t_{k+1} = t_k + 2 eᵏ v₁/g to 1e-10 s, and each stop is a left root (h ≥ 0).
    #[test]
    fn bouncing_ball_impact_times() {
        let (g, e) = (9.81, 0.8);
        let mut ball = BouncingBall { g };
        let exact = ball.impact_times(1.0, e, 6);
        let (mut t, mut y) = (0.0, [1.0, 0.0]);
        let mut steps = 0;
        for (k, &te) in exact.iter().enumerate() {
            let s = integrate(&mut ball, t, y, 100.0, &Options::default(), |_| {}).unwrap();
            assert_eq!(hit(&s).index, 0);
            assert!((s.t - te).abs() <= 1e-10, "bounce {k}: {} vs {te}", s.t);
            assert!(
                s.y[0] >= 0.0 && s.y[0] < 1e-9,
                "left root: h = {:e}",
                s.y[0]
            );
            assert!(s.y[1] < 0.0);
            (t, y) = (s.t, [s.y[0], -e * s.y[1]]);
            steps += s.steps;
        }
        // y'' = −g is integrated exactly: a handful of steps per flight.
        assert!(steps < 60, "{steps} steps");
    }

    /// sin t from t0 = 0.1: Rising fires only at upward crossings (2π, 4π, ...), Falling at π,
    /// Either at the first crossing; restarting past each event finds the next one.
    #[test]
    fn direction_filters() {
        let o = tight();
        let sin = |_: usize, t: f64| t.sin();
        let s = time_event(sin, &[Direction::Rising], 0.1, &o);
        assert!((hit(&s).t - TAU).abs() <= 1e-10, "{}", s.t);
        assert!(s.t.sin() < 0.0, "left root on the pre-side");
        let s = time_event(sin, &[Direction::Falling], 0.1, &o);
        assert!((s.t - PI).abs() <= 1e-10 && s.t.sin() > 0.0);
        let s = time_event(sin, &[Direction::Either], 0.1, &o);
        assert!((s.t - PI).abs() <= 1e-10);
        // Rising events over [0.1, 20]: 2π, 4π, 6π only.
        let mut t = 0.1;
        let mut found = vec![];
        loop {
            let s = time_event(sin, &[Direction::Rising], t, &o);
            if s.reason == StopReason::End {
                break;
            }
            found.push(s.t);
            t = s.t + 1e-6;
        }
        assert_eq!(found.len(), 3, "{found:?}");
        for (k, t) in found.iter().enumerate() {
            assert!((t - TAU * (k + 1) as f64).abs() <= 1e-10);
        }
    }

    /// g(t) = (t − 1)² − 1e-4 dips below zero only on (0.99, 1.01), inside one large step:
    /// detected at 0.99 (to 1e-10) whatever the step layout — dip at an interior sample, in
    /// the first or the last sample interval of a step, or straddling samples.
    #[test]
    fn touch_and_leave_inside_one_step() {
        let dip = |_: usize, t: f64| (t - 1.0) * (t - 1.0) - 1e-4;
        let inverted = |_: usize, t: f64| -((t - 1.0) * (t - 1.0) - 1e-4);
        for h_init in [
            None,
            Some(0.5),
            Some(0.98),
            Some(1.02),
            Some(2.0),
            Some(3.7),
            Some(10.0),
        ] {
            let o = Options {
                h_init,
                ..Options::default()
            };
            let s = time_event(dip, &[Direction::Falling], 0.0, &o);
            assert!((s.t - 0.99).abs() <= 1e-10, "h_init {h_init:?}: {}", s.t);
            assert!(dip(0, s.t) > 0.0);
            let s = time_event(inverted, &[Direction::Rising], 0.0, &o);
            assert!(
                (s.t - 0.99).abs() <= 1e-10,
                "rising, h_init {h_init:?}: {}",
                s.t
            );
            let s = time_event(dip, &[Direction::Either], 0.0, &o);
            assert!(
                (s.t - 0.99).abs() <= 1e-10,
                "either, h_init {h_init:?}: {}",
                s.t
            );
            // A near miss is not an event.
            let s = time_event(
                |_, t| (t - 1.0) * (t - 1.0) + 1e-6,
                &[Direction::Falling],
                0.0,
                &o,
            );
            assert_eq!((s.reason, s.t), (StopReason::End, 20.0));
        }
    }

    /// g(t) = 0.1 − 0.05 t + 0.06 cos(10π t) over one step [0, 1]: its samples at 0, 0.2, …, 1
    /// fall monotonically from 0.16 to 0.11, yet it dips below zero around t = 0.9 (two turning
    /// points inside one sample interval), which no sample shows.
    struct HiddenDip {
        bound: DipBound,
    }

    impl HiddenDip {
        fn g(t: f64) -> f64 {
            0.1 - 0.05 * t + 0.06 * (10.0 * PI * t).cos()
        }
    }

    impl HybridSystem<1> for HiddenDip {
        fn rhs(&self, _t: f64, _y: &[f64; 1]) -> [f64; 1] {
            [0.0]
        }
        fn guard_count(&self) -> usize {
            1
        }
        fn guard(&self, _i: usize, t: f64, _y: &[f64; 1]) -> f64 {
            Self::g(t)
        }
        fn guard_direction(&self, _i: usize) -> Direction {
            Direction::Falling
        }
        // |g'| ≤ 0.05 + 0.6π, |g''| ≤ 6π².
        fn guard_speed_limit(&self, _i: usize, _b: &StepBounds<1>) -> f64 {
            0.05 + 0.6 * PI
        }
        fn guard_may_dip(&self, _i: usize, _b: &StepBounds<1>) -> bool {
            !matches!(self.bound, DipBound::None)
        }
        fn guard_curvature_limit(&self, _i: usize, _b: &StepBounds<1>) -> f64 {
            match self.bound {
                DipBound::Curvature(k) => k,
                _ => f64::INFINITY,
            }
        }
    }

    /// A touch and leave between samples that look monotone is found with a bound on the
    /// guard (its speed, or more cheaply its curvature), and missed without one: a corner of
    /// the parcel rebounding from the arm and caught again 0.85 ms later by an arm at
    /// 2,000 rad/s², inside one 3 ms step (issue "Contacts that hold, round two").
    #[test]
    fn a_dip_between_monotone_samples_is_found_by_the_guards_bound() {
        let o = Options {
            h_init: Some(1.0),
            h_max: 1.0,
            ..Options::default()
        };
        let run = |bound| integrate(&mut HiddenDip { bound }, 0.0, [0.0], 1.0, &o, |_| {}).unwrap();
        for t in [0.0, 0.2, 0.4, 0.6, 0.8, 1.0] {
            assert!(HiddenDip::g(t) > 0.1, "sample at {t}");
        }
        assert_eq!(run(DipBound::None).reason, StopReason::End);
        for bound in [
            DipBound::Speed(0.05 + 0.6 * PI),
            DipBound::Curvature(6.0 * PI * PI),
        ] {
            let s = run(bound);
            assert!(matches!(s.reason, StopReason::Event(_)), "{bound:?}");
            assert!(
                HiddenDip::g(s.t) > 0.0 && HiddenDip::g(s.t + 1e-9) <= 0.0,
                "{bound:?}: {}",
                s.t
            );
            assert!((s.t - 0.87).abs() < 0.03, "{bound:?}: {}", s.t);
        }
    }

    /// g(t) = (t − ½)² + c over one step [0, 1], falling, with a loose speed limit (10, which
    /// culls nothing) and its true curvature 2.
    struct Bowl {
        c: f64,
        evaluations: std::cell::Cell<usize>,
    }

    impl HybridSystem<1> for Bowl {
        fn rhs(&self, _t: f64, _y: &[f64; 1]) -> [f64; 1] {
            [0.0]
        }
        fn guard_count(&self) -> usize {
            1
        }
        fn guard(&self, _i: usize, t: f64, _y: &[f64; 1]) -> f64 {
            self.evaluations.set(self.evaluations.get() + 1);
            (t - 0.5) * (t - 0.5) + self.c
        }
        fn guard_direction(&self, _i: usize) -> Direction {
            Direction::Falling
        }
        fn guard_speed_limit(&self, _i: usize, _b: &StepBounds<1>) -> f64 {
            10.0
        }
        fn guard_may_dip(&self, _i: usize, _b: &StepBounds<1>) -> bool {
            true
        }
        fn guard_curvature_limit(&self, _i: usize, _b: &StepBounds<1>) -> f64 {
            2.0
        }
    }

    /// A guard whose curvature bound and end values rule out a zero over the whole step is
    /// evaluated at the step's two ends only (it was sampled at four interior points as well);
    /// the same guard dipping to −0.1 between the same end values is still found, at its
    /// first root ½ − √0.1.
    #[test]
    fn a_step_its_curvature_bound_clears_is_not_sampled_inside() {
        let o = Options {
            h_init: Some(1.0),
            h_max: 1.0,
            ..Options::default()
        };
        let mut clear = Bowl {
            c: 0.2,
            evaluations: Default::default(),
        };
        let s = integrate(&mut clear, 0.0, [0.0], 1.0, &o, |_| {}).unwrap();
        assert_eq!((s.reason, s.steps), (StopReason::End, 1));
        assert_eq!(clear.evaluations.get(), 2);

        let mut dip = Bowl {
            c: -0.1,
            evaluations: Default::default(),
        };
        let s = integrate(&mut dip, 0.0, [0.0], 1.0, &o, |_| {}).unwrap();
        assert!(matches!(s.reason, StopReason::Event(_)), "{s:?}");
        assert!((s.t - (0.5 - 0.1f64.sqrt())).abs() < 1e-11, "{}", s.t);
    }

    /// The reported time is a left root: the guard is still pre-side there and has flipped
    /// within 2e-12 s after it (time guards are exact, so this tests the root finder alone).
    #[test]
    fn left_root_property() {
        let o = Options::default();
        for (c, dir) in [
            (0.3, Direction::Falling),
            (-0.7, Direction::Rising),
            (0.9, Direction::Either),
        ] {
            let g = move |_: usize, t: f64| (1.7 * t).cos() - c;
            let s = time_event(g, &[dir], 0.0, &o);
            let (before, after) = (g(0, s.t), g(0, s.t + 2e-12));
            match dir {
                Direction::Falling => assert!(before >= 0.0 && after <= 0.0),
                Direction::Rising => assert!(before <= 0.0 && after >= 0.0),
                Direction::Either => assert!(before * after <= 0.0),
            }
            assert!(before != 0.0 || dir == Direction::Either);
        }
    }

    /// Oscillator x = A cos ωt with the guard x − c: Falling fires at arccos(c/A)/ω, Rising at
    /// (2π − arccos(c/A))/ω, both to 1e-10 s at tight tolerances; the stop state matches.
    #[test]
    fn oscillator_threshold_event_times() {
        let (omega, a) = (1.3, 1.5);
        for (c, dir, te) in [
            (0.3, Direction::Falling, (0.3f64 / 1.5).acos() / 1.3),
            (
                -0.4,
                Direction::Rising,
                (TAU - (-0.4f64 / 1.5).acos()) / 1.3,
            ),
        ] {
            let mut osc = Oscillator {
                omega,
                threshold: Some((c, dir)),
            };
            let s = integrate(&mut osc, 0.0, [a, 0.0], f64::INFINITY, &tight(), |_| {}).unwrap();
            assert!((hit(&s).t - te).abs() <= 1e-10, "{dir:?}: {} vs {te}", s.t);
            assert!((s.y[0] - c).abs() < 1e-10);
            let ex = osc.exact(s.t, [a, 0.0]);
            assert!((s.y[0] - ex[0]).abs() < 1e-10 && (s.y[1] - ex[1]).abs() < 1e-10);
        }
    }

    /// A guard exactly 0 at the start does not fire there: −sin t (Falling) from 0 first goes
    /// post-side, then pre-side after π, and fires at 2π; sin t (Falling) fires at π.
    #[test]
    fn zero_at_start_does_not_fire() {
        let o = tight();
        let s = time_event(|_, t| -t.sin(), &[Direction::Falling], 0.0, &o);
        assert!((s.t - TAU).abs() <= 1e-10, "{}", s.t);
        let s = time_event(|_, t| t.sin(), &[Direction::Falling], 0.0, &o);
        assert!((s.t - PI).abs() <= 1e-10, "{}", s.t);
        let s = time_event(|_, t| t.sin(), &[Direction::Either], 0.0, &o);
        assert!((s.t - PI).abs() <= 1e-10, "{}", s.t);
    }

    /// The earliest guard wins; equal times go to the lowest index.
    #[test]
    fn earliest_event_and_tie_break() {
        let g = |i: usize, t: f64| [t - 2.0, 1.5 - t, t - 1.0, t - 1.0][i];
        let dirs = [
            Direction::Rising,
            Direction::Falling,
            Direction::Rising,
            Direction::Rising,
        ];
        let s = time_event(g, &dirs, 0.0, &Options::default());
        assert_eq!(hit(&s).index, 2);
        assert!((s.t - 1.0).abs() <= 1e-10);
        let s = time_event(g, &dirs[..2], 0.0, &Options::default());
        assert_eq!(hit(&s).index, 1);
        assert!((s.t - 1.5).abs() <= 1e-10);
    }

    /// The observer sees contiguous steps ending at the stop (truncated at the event), and
    /// `begin_step` is called once per step with the step's initial point.
    #[test]
    fn observer_and_begin_step() {
        let mut sys = Recording {
            inner: Oscillator::free(2.0),
            calls: vec![],
        };
        let mut seen = vec![];
        let s = integrate(&mut sys, 0.5, [1.0, 0.0], 7.0, &Options::default(), |st| {
            seen.push((st.t0, st.y0, st.t1, st.y1));
        })
        .unwrap();
        assert_eq!(s.reason, StopReason::End);
        assert_eq!(sys.calls.len(), s.steps);
        assert_eq!(seen.len(), s.steps);
        for (k, (call, step)) in sys.calls.iter().zip(&seen).enumerate() {
            assert_eq!(*call, (step.0, step.1));
            if k > 0 {
                assert_eq!((step.0, step.1), (seen[k - 1].2, seen[k - 1].3));
            }
        }
        assert_eq!(seen[0].0, 0.5);
        assert_eq!(seen.last().map(|s| (s.2, s.3)), Some((7.0, s.y)));

        let mut osc = Oscillator {
            omega: 2.0,
            threshold: Some((0.1, Direction::Falling)),
        };
        let mut last = None;
        let s = integrate(&mut osc, 0.0, [1.0, 0.0], 7.0, &Options::default(), |st| {
            last = Some((st.t1, st.y1));
        })
        .unwrap();
        assert_eq!(last, Some((s.t, s.y)));
    }

    /// max_steps bounds the work; an empty interval returns at once; NaN guards are errors.
    #[test]
    fn limits_and_errors() {
        let o = Options {
            max_steps: 10,
            ..Options::default()
        };
        let r = integrate(
            &mut Oscillator::free(1.0),
            0.0,
            [1.0, 0.0],
            100.0,
            &o,
            |_| {},
        );
        assert_eq!(r, Err(IntegrateError::TooManySteps { max_steps: 10 }));
        let s = integrate(&mut Oscillator::free(1.0), 3.0, [1.0, 0.0], 3.0, &o, |_| {}).unwrap();
        assert_eq!(
            (s.t, s.y, s.reason, s.steps),
            (3.0, [1.0, 0.0], StopReason::End, 0)
        );
        let mut nan_guard = TimeGuards {
            guards: |_, t: f64| if t > 1.0 { f64::NAN } else { 1.0 },
            directions: vec![Direction::Falling],
        };
        let r = integrate(&mut nan_guard, 0.0, [0.0], 5.0, &Options::default(), |_| {});
        assert!(matches!(r, Err(IntegrateError::NonFinite { t }) if t > 1.0));
    }

    /// A caller-owned stepper keeps its step proposal across calls (no new HINIT) and the
    /// result is the same as with a fresh stepper.
    #[test]
    fn integrate_with_reuses_the_stepper() {
        let mut st = Dopri5::new(Options::default());
        let mut sys = Decay;
        let s1 = integrate_with(&mut st, &mut sys, 0.0, [1.0], 1.0, |_| {}).unwrap();
        let evals = st.stats().rhs_evals;
        let s2 = integrate_with(&mut st, &mut sys, 1.0, s1.y, 2.0, |_| {}).unwrap();
        // Decay allows FSAL reuse, so the second call costs 6 per step (+0 for HINIT); at
        // most one extra evaluation at its start (the first derivative is cached too).
        let per = st.stats().rhs_evals - evals;
        assert!(per <= 6 * (s2.steps + st.stats().rejected) + 1, "{per}");
        assert!((s2.y[0] - (-2.0f64).exp()).abs() < 1e-9);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// Random oscillators x = A cos ωt with a random Falling threshold c = rA: the event is
        /// at arccos(r)/ω, to the accuracy the state tolerance allows
        /// (δt ≈ δx / |ẋ| = δx / (Aω sin ωt)).
        #[test]
        fn oscillator_events_match_arccos(
            omega in 0.5f64..5.0,
            a in 0.1f64..2.0,
            r in -0.95f64..0.95,
            lg in 8i32..12,
        ) {
            let rtol = 10f64.powi(-lg);
            let o = Options { rtol, atol: rtol * a, ..Options::default() };
            let mut osc = Oscillator { omega, threshold: Some((r * a, Direction::Falling)) };
            let s = integrate(&mut osc, 0.0, [a, 0.0], 100.0, &o, |_| {}).unwrap();
            let te = r.acos() / omega;
            let tol = 10.0 * rtol / (omega * (1.0 - r * r).sqrt()) + 1e-12;
            prop_assert!((hit(&s).t - te).abs() <= tol, "{} vs {}", s.t, te);
            prop_assert!(s.y[0] - r * a > 0.0 || (s.y[0] - r * a).abs() < 1e-15);
        }

        /// Random balls (h₀, e): four impact times to 1e-10 s, each stop a left root.
        #[test]
        fn random_bouncing_balls(h0 in 0.01f64..5.0, e in 0.2f64..0.95) {
            let mut ball = BouncingBall { g: 9.81 };
            let exact = ball.impact_times(h0, e, 4);
            let (mut t, mut y) = (0.0, [h0, 0.0]);
            for te in exact {
                let s = integrate(&mut ball, t, y, 100.0, &Options::default(), |_| {}).unwrap();
                prop_assert!((hit(&s).t - te).abs() <= 1e-10, "{} vs {}", s.t, te);
                prop_assert!(s.y[0] >= 0.0);
                (t, y) = (s.t, [s.y[0], -e * s.y[1]]);
            }
        }

        /// Narrow dips g = (t − c)² − w² anywhere in steps of any size (first step h_init up
        /// to 10 s, no h_max) are found at c − w, with any direction convention.
        #[test]
        fn narrow_dips_are_found(
            c in 0.3f64..8.0,
            w in 1e-3f64..0.1,
            h_init in 0.01f64..10.0,
            rising in proptest::bool::ANY,
        ) {
            let o = Options { h_init: Some(h_init), ..Options::default() };
            let sign = if rising { -1.0 } else { 1.0 };
            let dir = if rising { Direction::Rising } else { Direction::Falling };
            let g = move |_: usize, t: f64| sign * ((t - c) * (t - c) - w * w);
            let s = time_event(g, &[dir], 0.0, &o);
            prop_assert!(matches!(s.reason, StopReason::Event(_)), "missed, stop at {}", s.t);
            prop_assert!((s.t - (c - w)).abs() <= 1e-10, "{} vs {}", s.t, c - w);
        }
    }
}
