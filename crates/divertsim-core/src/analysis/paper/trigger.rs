//! Trigger calibration (paper §4.1, Fig. 4): for each belt speed v, the start position R_s
//! (x of the parcel's front when the arm starts) that gives the parcel the same transverse
//! displacement as the machine documentation's reference setting (v = 0.65 m/s,
//! t_c = 1.36 s, R_s = 0.8 m).
//!
//! The displacement is `max_lateral` of [`simulate`](crate::sim::simulate): the largest y of the parcel centre over
//! the run. The target is the reference run's; the reference must not be diverted (a diverted
//! run ends when its centre crosses the far edge, so its `max_lateral` is saturated at P_max
//! and says nothing about the displacement).
//!
//! Root finding on the simulation. `max_lateral(R_s)` is neither monotone nor continuous (the
//! stage sequence changes with R_s, strikes appear or vanish), so for each speed:
//! 1. scan R_s on a uniform grid over the search interval and keep every grid cell where
//!    `max_lateral − target` changes sign (a grid point that hits the target exactly is a root
//!    by itself); runs that fail numerically break the scan there;
//! 2. refine every bracket by bisection until it is narrower than the tolerance, and report
//!    the end of the final bracket nearer the target (so the reported displacement, stages and
//!    outcome are those of an actual run at the reported R_s);
//! 3. classify the root: a [`RootKind::Crossing`] when the displacement is continuous there
//!    (the two bracket ends differ by at most [`JUMP_THRESHOLD`]), else a [`RootKind::Jump`]:
//!    the displacement jumps over the target (e.g. a strike appears) and no R_s matches it
//!    exactly;
//! 4. when a speed has several roots, choose by continuity of the curve R_s(v): at the speed
//!    nearest the reference speed, the root nearest the reference R_s; then, walking away from
//!    it in both directions through the speeds in increasing order, the root nearest the
//!    previously chosen one. Crossings are preferred to jumps (a jump is chosen only at a
//!    speed without a crossing): with the default machine the displacement has several
//!    crossing branches and many jumps near the reference (whose R_s = 0.8 m sits on a local
//!    maximum of the displacement), and following jumps strays onto late-trigger branches
//!    where only the arm tip reaches the parcel's tail. The choice is made after the parallel scan, so it does not depend
//!    on the thread count. A speed without a root reports none (it does not move the
//!    continuation anchor).
//!
//! Machine and parcel come from the scenario. What the calibration changes in each run: the
//! belt speed, R_s, the parcel rides with the belt (initial velocity = belt velocity, no spin:
//! the parcel arrives on the belt), the run lasts at least t_c + 2 s, and the light barrier is
//! moved to S_d = min(S_d, R_s) (the simulation does not use S_d; the scenario contract only
//! requires S_d ≤ R_s, so a searched R_s upstream of the barrier is allowed and reported as
//! is). The reference run uses the reference's v, t_c and R_s; the calibrated runs use the
//! scenario's t_c (the paper keeps t_c = 1.36 s for both).
//!
//! References: the paper §4.1, Figs. 3–4; docs/model.md §1 (reference setting, R_s range).

use crate::model::params::{default_duration, Parcel, Scenario};
use crate::run::memo::{self, cached, Memo, NoMemo};
use crate::run::sweep::{par_map, Progress};
use crate::sim::{simulate_verdict, Outcome, SimResult, Stage};

/// v of the machine documentation's reference setting [m/s] (paper Fig. 3).
pub const REFERENCE_SPEED: f64 = 0.65;
/// t_c of the reference setting \[s].
pub const REFERENCE_CYCLE: f64 = 1.36;
/// R_s of the reference setting \[m].
pub const REFERENCE_START: f64 = 0.8;
/// A root whose bracket ends differ in displacement by more than this is a jump \[m].
pub const JUMP_THRESHOLD: f64 = 1e-3;

/// The paper's Fig. 3 parcel: the slender 0.7 × 0.1 × 0.1 m box, 1.5 kg (docs/model.md §1),
/// at the pivot-side edge (ΔP = 0), parallel to the belt (φ = 0), riding with the belt.
pub fn fig3_parcel() -> Parcel {
    Parcel::riding(0.7, 0.1, 0.1, 1.5, 0.0, 0.0)
}

/// The reference setting and the search.
#[derive(Debug, Clone, PartialEq)]
pub struct TriggerSettings {
    /// v of the reference setting [m/s]
    pub reference_speed: f64,
    /// t_c of the reference setting \[s]
    pub reference_cycle: f64,
    /// R_s of the reference setting \[m]
    pub reference_start: f64,
    /// Search interval of R_s, (min, max) \[m]
    pub search: (f64, f64),
    /// Largest spacing of the scan grid over the search interval \[m]
    pub scan_step: f64,
    /// Bisection stops when the bracket is narrower than this \[m]
    pub tolerance: f64,
}

impl Default for TriggerSettings {
    /// The paper's reference (0.65 m/s, 1.36 s, 0.8 m); search −0.5…1.5 m (the paper's range
    /// 0–0.9 m with room on both sides), scanned every 0.02 m, tolerance 0.1 mm.
    fn default() -> Self {
        TriggerSettings {
            reference_speed: REFERENCE_SPEED,
            reference_cycle: REFERENCE_CYCLE,
            reference_start: REFERENCE_START,
            search: (-0.5, 1.5),
            scan_step: 0.02,
            tolerance: 1e-4,
        }
    }
}

impl TriggerSettings {
    /// Every problem with the settings (empty when they are usable).
    pub fn problems(&self) -> Vec<String> {
        let mut p = Vec::new();
        let finite_pos = |v: f64| v.is_finite() && v > 0.0;
        if !finite_pos(self.reference_speed) {
            p.push(format!(
                "reference speed {} m/s must be finite and > 0",
                self.reference_speed
            ));
        }
        if !finite_pos(self.reference_cycle) {
            p.push(format!(
                "reference cycle {} s must be finite and > 0",
                self.reference_cycle
            ));
        }
        if !self.reference_start.is_finite() {
            p.push(format!(
                "reference start {} m must be finite",
                self.reference_start
            ));
        }
        let (lo, hi) = self.search;
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            p.push(format!(
                "search interval [{lo}, {hi}] m must be finite with min < max"
            ));
        }
        if !finite_pos(self.scan_step) {
            p.push(format!(
                "scan step {} m must be finite and > 0",
                self.scan_step
            ));
        } else if lo.is_finite() && hi.is_finite() && (hi - lo) / self.scan_step > 1e5 {
            p.push(format!(
                "scan step {} m gives more than 100000 grid points",
                self.scan_step
            ));
        }
        if !finite_pos(self.tolerance) {
            p.push(format!(
                "tolerance {} m must be finite and > 0",
                self.tolerance
            ));
        }
        p
    }

    /// The most simulations a curve over `speeds` speeds runs: the reference, and at each
    /// speed the scan grid plus a bisection to the tolerance in every interval of the grid
    /// where the excess changes sign (the count depends on the roots found: most speeds
    /// have one or two; [`TriggerSettings::least_simulations`] is the other end).
    pub fn estimated_simulations(&self, speeds: usize) -> usize {
        let (lo, hi) = self.search;
        let grid = crate::run::sweep::scan_points(lo, hi, self.scan_step);
        let bisection = crate::run::sweep::bisection_steps(self.scan_step, self.tolerance);
        1 + speeds * (grid + grid.saturating_sub(1) * bisection)
    }

    /// The simulations a curve over `speeds` speeds runs whatever its roots: the reference
    /// and the scan grid at each speed.
    pub fn least_simulations(&self, speeds: usize) -> usize {
        let (lo, hi) = self.search;
        1 + speeds * crate::run::sweep::scan_points(lo, hi, self.scan_step)
    }

    /// The scan grid: n + 1 equally spaced points from min to max, spacing ≤ `scan_step`.
    pub fn grid(&self) -> Vec<f64> {
        let (lo, hi) = self.search;
        let n = ((hi - lo) / self.scan_step).ceil().max(1.0) as usize;
        (0..=n)
            .map(|i| {
                if i == n {
                    hi
                } else {
                    lo + (hi - lo) * i as f64 / n as f64
                }
            })
            .collect()
    }
}

/// Why a calibration cannot start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TriggerError {
    /// Unusable settings.
    #[error("invalid trigger settings: {}", .0.join("; "))]
    Settings(Vec<String>),
    /// The reference run is diverted: its displacement saturates at P_max.
    #[error(
        "the reference run (v = {speed} m/s, t_c = {cycle} s, R_s = {start} m) diverts the \
         parcel: its centre crosses the far belt edge, so its largest displacement is the belt \
         width, not a transverse displacement to match; choose a parcel or reference setting \
         that is not diverted (the paper's is the slender 0.7 × 0.1 m parcel at ΔP = 0)"
    )]
    ReferenceDiverted { speed: f64, cycle: f64, start: f64 },
    /// The reference run failed numerically.
    #[error("the reference run failed: {0}")]
    ReferenceFailed(String),
}

/// The reference run and the displacement to match.
#[derive(Debug, Clone, PartialEq)]
pub struct TriggerReference {
    /// v [m/s]
    pub speed: f64,
    /// t_c \[s]
    pub cycle: f64,
    /// R_s \[m]
    pub start: f64,
    /// The target: largest y of the parcel centre in the reference run \[m]
    pub max_lateral: f64,
    /// Stages the reference run visits.
    pub stages: Vec<Stage>,
    /// Its verdict (never diverted).
    pub outcome: Outcome,
}

/// Whether the displacement is continuous at a root.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum RootKind {
    /// max_lateral crosses the target continuously (within [`JUMP_THRESHOLD`]).
    Crossing,
    /// max_lateral jumps over the target: the nearest R_s, the target is not met exactly.
    Jump,
}

impl RootKind {
    /// The label used in outputs.
    pub fn label(self) -> &'static str {
        match self {
            RootKind::Crossing => "crossing",
            RootKind::Jump => "jump",
        }
    }
}

/// One R_s where the displacement meets the target.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Root {
    /// R_s \[m]
    pub start: f64,
    /// The run's largest y of the centre at this R_s \[m]
    pub max_lateral: f64,
    /// Continuous crossing or jump.
    pub kind: RootKind,
    /// Bisection steps spent on this root (0: a grid point hit the target).
    pub iterations: usize,
    /// Stages visited by the run at this R_s.
    pub stages: Vec<Stage>,
    /// Its verdict.
    pub outcome: Outcome,
}

/// The calibration at one belt speed.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TriggerPoint {
    /// v [m/s]
    pub speed: f64,
    /// Every root found over the search interval, in increasing R_s.
    pub roots: Vec<Root>,
    /// Index into `roots` of the one chosen by continuity; `None`: no root.
    pub chosen: Option<usize>,
    /// Simulations run for this speed (scan and bisection).
    pub simulations: usize,
}

impl TriggerPoint {
    /// The chosen root, if any.
    pub fn root(&self) -> Option<&Root> {
        self.chosen.and_then(|i| self.roots.get(i))
    }
}

/// The calibration curve R_s(v).
#[derive(Debug, Clone, PartialEq)]
pub struct TriggerCurve {
    pub reference: TriggerReference,
    /// One point per requested speed, in the order given.
    pub points: Vec<TriggerPoint>,
}

/// The scenario of one calibration run: `base` at belt speed `v`, cycle `t_c`, start `r_s`,
/// with the parcel riding with the belt.
pub fn scenario_at(base: &Scenario, speed: f64, cycle: f64, start: f64) -> Scenario {
    let mut s = base.clone();
    s.machine.belt_speed = speed;
    s.machine.cycle_time = cycle;
    s.machine.start_at(start);
    // The scenario contract wants S_d ≤ R_s; S_d does not enter the simulation.
    s.machine.light_barrier = s.machine.light_barrier.min(start);
    s.parcel.velocity = None;
    s.parcel.spin = 0.0;
    s.run.duration = s.run.duration.max(default_duration(cycle));
    s
}

/// Run the reference setting and check that it can serve as a target.
pub fn reference(
    base: &Scenario,
    settings: &TriggerSettings,
) -> Result<TriggerReference, TriggerError> {
    let problems = settings.problems();
    if !problems.is_empty() {
        return Err(TriggerError::Settings(problems));
    }
    let (speed, cycle, start) = (
        settings.reference_speed,
        settings.reference_cycle,
        settings.reference_start,
    );
    let r = simulate_verdict(&scenario_at(base, speed, cycle, start));
    match r.outcome {
        Outcome::Diverted => Err(TriggerError::ReferenceDiverted {
            speed,
            cycle,
            start,
        }),
        Outcome::Failed(reason) => Err(TriggerError::ReferenceFailed(reason)),
        outcome => Ok(TriggerReference {
            speed,
            cycle,
            start,
            max_lateral: r.max_lateral,
            stages: r.stages,
            outcome,
        }),
    }
}

/// One evaluated R_s: the displacement minus the target, `None` for a failed run.
struct Eval {
    start: f64,
    excess: Option<f64>,
    result: SimResult,
}

fn eval(base: &Scenario, speed: f64, start: f64, target: f64) -> Eval {
    let result = simulate_verdict(&scenario_at(base, speed, base.machine.cycle_time, start));
    let excess = match result.outcome {
        Outcome::Failed(_) => None,
        _ if result.max_lateral.is_finite() => Some(result.max_lateral - target),
        _ => None,
    };
    Eval {
        start,
        excess,
        result,
    }
}

fn root_of(e: &Eval, kind: RootKind, iterations: usize) -> Root {
    Root {
        start: e.start,
        max_lateral: e.result.max_lateral,
        kind,
        iterations,
        stages: e.result.stages.clone(),
        outcome: e.result.outcome.clone(),
    }
}

/// Every root of `max_lateral(R_s) − target` at belt speed `speed` (scan, then bisection),
/// in increasing R_s, and the number of simulations run.
pub fn roots_at(
    base: &Scenario,
    speed: f64,
    target: f64,
    settings: &TriggerSettings,
) -> (Vec<Root>, usize) {
    let grid = settings.grid();
    let scan: Vec<Eval> = grid.iter().map(|&x| eval(base, speed, x, target)).collect();
    let mut sims = scan.len();
    let mut roots = Vec::new();
    for (i, e) in scan.iter().enumerate() {
        let Some(f) = e.excess else { continue };
        if f == 0.0 {
            roots.push(root_of(e, RootKind::Crossing, 0));
            continue;
        }
        let Some(next) = scan.get(i + 1) else { break };
        let Some(g) = next.excess else { continue };
        if g == 0.0 || (f > 0.0) == (g > 0.0) {
            continue;
        }
        let (root, n) = bisect(base, speed, target, settings.tolerance, e, next);
        sims += n;
        roots.push(root);
    }
    (roots, sims)
}

/// Bisection on a sign-changing bracket (`a.excess`, `b.excess` finite, opposite signs).
fn bisect(base: &Scenario, speed: f64, target: f64, tol: f64, a: &Eval, b: &Eval) -> (Root, usize) {
    let sign_a = a.excess.is_some_and(|f| f > 0.0);
    // The bracket ends found so far (`None`: still the scan's `a` or `b`).
    let mut lo: Option<Eval> = None;
    let mut hi: Option<Eval> = None;
    let mut n = 0;
    // A bracket on the floating-point grid cannot shrink forever; 200 halvings cover any
    // interval down to f64 resolution.
    while n < 200 {
        let (l, h) = (
            lo.as_ref().unwrap_or(a).start,
            hi.as_ref().unwrap_or(b).start,
        );
        let mid = 0.5 * (l + h);
        if h - l <= tol || mid <= l || mid >= h {
            break;
        }
        let m = eval(base, speed, mid, target);
        n += 1;
        match m.excess {
            Some(0.0) => return (root_of(&m, RootKind::Crossing, n), n),
            Some(f) if (f > 0.0) == sign_a => lo = Some(m),
            Some(_) => hi = Some(m),
            // A failed run inside the bracket: stop at what is known.
            None => break,
        }
    }
    let lo_ref = lo.as_ref().unwrap_or(a);
    let hi_ref = hi.as_ref().unwrap_or(b);
    let (fl, fh) = (
        lo_ref.excess.unwrap_or(f64::NAN),
        hi_ref.excess.unwrap_or(f64::NAN),
    );
    let kind = if (fl - fh).abs() <= JUMP_THRESHOLD {
        RootKind::Crossing
    } else {
        RootKind::Jump
    };
    let best = if fl.abs() <= fh.abs() { lo_ref } else { hi_ref };
    (root_of(best, kind, n), n)
}

/// Choose one root per point by continuity from the reference (see the module notes).
pub fn choose_by_continuity(points: &mut [TriggerPoint], ref_speed: f64, ref_start: f64) {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&i, &j| points[i].speed.total_cmp(&points[j].speed));
    let Some(anchor) = (0..order.len()).min_by(|&i, &j| {
        let di = (points[order[i]].speed - ref_speed).abs();
        let dj = (points[order[j]].speed - ref_speed).abs();
        di.total_cmp(&dj)
    }) else {
        return;
    };
    // Crossings first: a jump meets the target only approximately, and following jumps
    // would leave the smooth branch the paper draws.
    let nearest = |p: &TriggerPoint, to: f64| -> Option<usize> {
        let any_crossing = p.roots.iter().any(|r| r.kind == RootKind::Crossing);
        (0..p.roots.len())
            .filter(|&a| !any_crossing || p.roots[a].kind == RootKind::Crossing)
            .min_by(|&a, &b| {
                (p.roots[a].start - to)
                    .abs()
                    .total_cmp(&(p.roots[b].start - to).abs())
            })
    };
    let pa = &mut points[order[anchor]];
    pa.chosen = nearest(pa, ref_start);
    let anchor_start = pa.root().map_or(ref_start, |r| r.start);
    for dir in [1isize, -1] {
        let mut prev = anchor_start;
        let mut k = anchor as isize + dir;
        while k >= 0 && (k as usize) < order.len() {
            let p = &mut points[order[k as usize]];
            p.chosen = nearest(p, prev);
            if let Some(r) = p.root() {
                prev = r.start;
            }
            k += dir;
        }
    }
}

/// R_s(v) for every speed in `speeds` (in parallel, one progress tick per speed).
pub fn calibrate(
    base: &Scenario,
    speeds: &[f64],
    settings: &TriggerSettings,
    progress: Progress<'_>,
) -> Result<TriggerCurve, TriggerError> {
    calibrate_kept(base, speeds, settings, progress, &NoMemo)
}

/// [`calibrate`] with every finished speed kept in `memo` and recalled instead of searched
/// again (an interrupted run resumes; the curve is the same bit for bit).
pub fn calibrate_kept(
    base: &Scenario,
    speeds: &[f64],
    settings: &TriggerSettings,
    progress: Progress<'_>,
    memo: &dyn Memo,
) -> Result<TriggerCurve, TriggerError> {
    let reference = reference(base, settings)?;
    if let Some(v) = speeds.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
        return Err(TriggerError::Settings(vec![format!(
            "belt speed {v} m/s must be finite and > 0"
        )]));
    }
    let target = reference.max_lateral;
    let mut points = par_map(speeds, progress, |&v| {
        let key = memo::key("trigger speed", &(base, v, target, settings));
        let ((roots, simulations), _) = cached(memo, key, || roots_at(base, v, target, settings));
        TriggerPoint {
            speed: v,
            roots,
            chosen: None,
            simulations,
        }
    });
    choose_by_continuity(
        &mut points,
        settings.reference_speed,
        settings.reference_start,
    );
    Ok(TriggerCurve { reference, points })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::sweep::no_progress;
    use proptest::prelude::*;

    /// The slender parcel at the edge on the paper preset's machine
    /// (configs/paper/machine.toml: R_z 1.15 m, μ_b 0.5, μ_a 0.38), where it is not
    /// diverted at the reference setting (finding (a)). On the built-in default machine
    /// (R_z 1 m) it slides along and over the arm tip and is diverted.
    fn slender() -> Scenario {
        let mut s = Scenario::paper_machine();
        s.parcel = fig3_parcel();
        s
    }

    fn narrow(lo: f64, hi: f64) -> TriggerSettings {
        TriggerSettings {
            search: (lo, hi),
            ..TriggerSettings::default()
        }
    }

    fn excess(base: &Scenario, v: f64, rs: f64, target: f64) -> f64 {
        crate::sim::simulate(&scenario_at(base, v, base.machine.cycle_time, rs)).max_lateral
            - target
    }

    #[test]
    fn grid_spans_the_interval_with_at_most_the_step() {
        let s = narrow(-0.5, 1.5);
        let g = s.grid();
        assert_eq!(g.first(), Some(&-0.5));
        assert_eq!(g.last(), Some(&1.5));
        assert_eq!(g.len(), 101);
        assert!(g
            .windows(2)
            .all(|w| w[1] > w[0] && w[1] - w[0] <= 0.02 + 1e-15));
        // A step that does not divide the interval still ends exactly at its max.
        let g = TriggerSettings {
            scan_step: 0.3,
            ..narrow(0.0, 1.0)
        }
        .grid();
        assert_eq!(g.len(), 5);
        assert_eq!(g.last(), Some(&1.0));
    }

    #[test]
    fn scenario_at_rides_and_keeps_the_barrier_upstream() {
        let mut base = slender();
        base.machine.light_barrier = 0.5;
        base.parcel.velocity = Some(glam::DVec2::new(3.0, 1.0));
        base.parcel.spin = 2.0;
        let s = scenario_at(&base, 1.2, 1.3, -0.2);
        assert_eq!(s.machine.belt_speed, 1.2);
        assert_eq!(s.machine.cycle_time, 1.3);
        assert_eq!(s.machine.start_position, -0.2);
        assert_eq!(s.machine.light_barrier, -0.2);
        assert_eq!(s.initial_velocity(), glam::DVec2::new(1.2, 0.0));
        assert_eq!(s.parcel.spin, 0.0);
        assert!(s.run.duration >= 1.3 + 2.0);
        // The parcel's front is at R_s, its pivot-side edge at ΔP.
        let g = s.initial_centre();
        assert!((g.x + 0.35 - -0.2).abs() < 1e-15 && (g.y - 0.05).abs() < 1e-15);
    }

    /// At the reference speed the reference R_s itself is a root (the target is its own
    /// displacement); the bisection lands within the tolerance of 0.8 m.
    #[test]
    fn reference_start_is_the_root_at_the_reference_speed() {
        let base = slender();
        let settings = narrow(0.76, 0.84);
        let c = calibrate(&base, &[0.65], &settings, &no_progress).unwrap();
        assert_eq!(c.reference.outcome.label(), "not_diverted");
        let r = c.points[0].root().expect("a root");
        assert!((r.start - 0.8).abs() <= 1e-4, "R_s = {}", r.start);
        assert!((r.max_lateral - c.reference.max_lateral).abs() < 1e-3);
    }

    /// A crossing root: runs at R_s ± tolerance lie on opposite sides of the target
    /// (checked by separate simulations), and the reported displacement is that of a run at
    /// the reported R_s.
    #[test]
    fn crossing_root_is_bracketed_by_independent_runs() {
        let base = slender();
        let settings = narrow(0.40, 0.50);
        let reference = reference(&base, &settings).unwrap();
        let target = reference.max_lateral;
        let (roots, sims) = roots_at(&base, 1.1, target, &settings);
        assert!(sims >= settings.grid().len());
        let r = roots
            .iter()
            .find(|r| r.kind == RootKind::Crossing)
            .expect("a crossing in 0.40..0.50 m at 1.1 m/s");
        assert!(r.iterations > 0 && r.iterations <= 10);
        let tol = settings.tolerance;
        let (a, b) = (
            excess(&base, 1.1, r.start - tol, target),
            excess(&base, 1.1, r.start + tol, target),
        );
        assert!(a * b <= 0.0, "no sign change around {}: {a}, {b}", r.start);
        assert!((r.max_lateral - target).abs() <= JUMP_THRESHOLD);
        assert_eq!(excess(&base, 1.1, r.start, target), r.max_lateral - target);
    }

    #[test]
    fn diverted_reference_is_refused() {
        // The slender parcel at v = 2 m/s, R_s = 0.2 m is diverted (its centre reaches P_max).
        let base = slender();
        let settings = TriggerSettings {
            reference_speed: 2.0,
            reference_start: 0.2,
            ..TriggerSettings::default()
        };
        let e = calibrate(&base, &[1.0], &settings, &no_progress).unwrap_err();
        assert!(matches!(e, TriggerError::ReferenceDiverted { .. }), "{e}");
        assert!(e.to_string().contains("diverts the parcel"));
    }

    #[test]
    fn bad_settings_and_speeds_are_errors() {
        let base = slender();
        let bad = TriggerSettings {
            tolerance: 0.0,
            search: (1.0, 0.0),
            ..TriggerSettings::default()
        };
        match calibrate(&base, &[1.0], &bad, &no_progress) {
            Err(TriggerError::Settings(p)) => assert_eq!(p.len(), 2, "{p:?}"),
            other => panic!("{other:?}"),
        }
        let e = calibrate(&base, &[f64::NAN], &narrow(0.7, 0.9), &no_progress).unwrap_err();
        assert!(matches!(e, TriggerError::Settings(_)));
    }

    fn point(speed: f64, roots: &[(f64, RootKind)]) -> TriggerPoint {
        TriggerPoint {
            speed,
            roots: roots
                .iter()
                .map(|&(start, kind)| Root {
                    start,
                    max_lateral: 0.5,
                    kind,
                    iterations: 1,
                    stages: vec![],
                    outcome: Outcome::Diverted,
                })
                .collect(),
            chosen: None,
            simulations: 1,
        }
    }

    #[test]
    fn continuity_prefers_crossings_and_follows_the_branch() {
        use RootKind::{Crossing as C, Jump as J};
        // Given out of speed order on purpose.
        let mut pts = vec![
            point(1.0, &[(0.1, C), (0.45, C), (0.9, J)]),
            point(0.65, &[(0.64, C), (0.8, C), (0.84, J)]),
            point(0.8, &[(0.53, C), (0.64, C), (0.81, J)]),
            point(1.2, &[]),
            point(1.4, &[(0.05, C), (0.3, C), (1.2, C)]),
            point(0.5, &[(0.9, J)]),
        ];
        choose_by_continuity(&mut pts, 0.65, 0.8);
        let got: Vec<Option<f64>> = pts.iter().map(|p| p.root().map(|r| r.start)).collect();
        assert_eq!(
            got,
            vec![
                Some(0.45),
                Some(0.8),
                Some(0.64),
                None,
                Some(0.3),
                Some(0.9)
            ]
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        /// The chosen root is one of the point's own roots, a crossing whenever the point has
        /// one, and there is a choice exactly when there are roots.
        #[test]
        fn chosen_root_is_own_and_prefers_crossings(
            pts in prop::collection::vec(
                (0.1f64..3.0, prop::collection::vec((-1.0f64..2.0, any::<bool>()), 0..5)),
                1..12,
            ),
            rs in -0.5f64..1.5,
        ) {
            let mut points: Vec<TriggerPoint> = pts
                .iter()
                .map(|(v, roots)| {
                    let roots: Vec<(f64, RootKind)> = roots
                        .iter()
                        .map(|&(x, c)| (x, if c { RootKind::Crossing } else { RootKind::Jump }))
                        .collect();
                    point(*v, &roots)
                })
                .collect();
            choose_by_continuity(&mut points, 0.65, rs);
            for p in &points {
                prop_assert_eq!(p.chosen.is_some(), !p.roots.is_empty());
                if let Some(r) = p.root() {
                    let any_crossing = p.roots.iter().any(|r| r.kind == RootKind::Crossing);
                    prop_assert!(!any_crossing || r.kind == RootKind::Crossing);
                }
            }
        }
    }
}
