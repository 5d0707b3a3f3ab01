//! A per-parcel trigger: a controller that knows each parcel's length, width, offset and
//! angle when it crosses the light barrier (a dimensioner or a camera) and starts the arm at
//! that parcel's own R_s, read from a precomputed table.
//!
//! **The best R_s of one parcel** ([`best_start`]): the scan-and-bisect search of the
//! capacity analysis ([`crate::analysis::design::capacity`]) applied to one parcel. R_s is scanned over the
//! search interval; a point passes when the parcel is diverted with the required reserve and
//! its largest strike stays within the overload limit ([`Margins`]); every boundary between
//! passing and failing points is refined by bisection. The chosen R_s is the middle of the
//! widest passing interval: the start that tolerates the largest trigger timing error either
//! way. If no point passes, the scan point nearest to passing (largest of the two margins'
//! minimum) is chosen and the parcel is marked infeasible.
//!
//! **The table** ([`TriggerTable`]): the best R_s at the nodes of a grid over length a,
//! aspect b/a, offset fraction ΔP/(P_max − extent across) and angle φ, interpolated
//! multilinearly (clamped to the grid), so a controller evaluates it in microseconds. The
//! runs do not depend on the parcel's mass or height (the arm is driven, every force scales
//! with m, and S/S_fall too), so the nodes use 1 kg and 0.1 m; the materials are the
//! scenario's nominal ones (the controller cannot know a parcel's friction).
//!
//! The machine cannot start the arm for a parcel before it has seen it: R_s ≥ S_d
//! ([`TriggerTable::start_for`] clamps).

use crate::analysis::design::capacity::linspace;
use crate::analysis::design::design_set::{divert_overshoot, Margins};
use crate::analysis::design::worst_case::extent_across;
use crate::analysis::population::mix::{MixError, ParcelMix};
use crate::model::params::{default_duration, Parcel, Scenario};
use crate::run::sweep::{par_map, Progress};
use crate::sim::{simulate_verdict, Outcome};

pub use crate::model::trigger::StartSearch;
use crate::model::trigger::Trigger;

impl StartSearch {
    /// About how many simulations one parcel's search runs: the scan, and both ends of the
    /// passing interval bisected to the tolerance. An estimate for the work limit.
    pub fn estimated_simulations(&self) -> usize {
        let scan = crate::run::sweep::scan_points(self.range.0, self.range.1, self.step);
        scan + 2 * crate::run::sweep::bisection_steps(self.step, self.tolerance)
    }
}

impl StartSearch {
    /// The scan points.
    fn starts(&self) -> Vec<f64> {
        let (lo, hi) = self.range;
        let n = ((hi - lo) / self.step).round().max(0.0) as usize + 1;
        crate::analysis::design::capacity::linspace(lo, hi, n)
    }

    /// Every problem, as (name, message).
    pub fn problems(&self) -> Vec<(&'static str, String)> {
        let mut p = Vec::new();
        let (lo, hi) = self.range;
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            p.push((
                "search",
                format!("[{lo}, {hi}]: allowed: finite with min < max"),
            ));
        }
        if !(self.step > 0.0 && self.step.is_finite()) {
            p.push((
                "step",
                format!("{} is out of range; allowed: > 0 m", self.step),
            ));
        } else if lo < hi && (hi - lo) / self.step > 2000.0 {
            p.push((
                "step",
                format!(
                    "{} gives more than 2000 scan points; allowed: ≥ (max − min)/2000",
                    self.step
                ),
            ));
        }
        if !(self.tolerance >= MIN_TOLERANCE && self.tolerance.is_finite()) {
            p.push((
                "tolerance",
                format!(
                    "{} is out of range; allowed: ≥ {MIN_TOLERANCE} m",
                    self.tolerance
                ),
            ));
        }
        p
    }
}

/// Largest number of bisections of one interval end.
const MAX_BISECTIONS: usize = 64;

/// Smallest bisection tolerance \[m] (a nanometre: far below any trigger's precision).
pub const MIN_TOLERANCE: f64 = 1e-9;

/// The best start of one parcel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BestStart {
    /// R_s \[m]
    pub start: f64,
    /// The passing interval it is the middle of ((start, start) if none passes) \[m]
    pub interval: (f64, f64),
    /// Whether any R_s passed.
    pub feasible: bool,
    /// Simulations run.
    pub simulations: usize,
}

/// How one run at R_s fares: (passes, the smaller of the two margins, ≥ 0 when passing).
fn judge(setting: &Scenario, parcel: &Parcel, start: f64, margins: &Margins) -> (bool, f64) {
    let mut s = setting.clone();
    s.machine.start_at(start);
    s.machine.light_barrier = s.machine.light_barrier.min(start);
    s.parcel = parcel.clone();
    s.run.duration = s.run.duration.max(default_duration(s.machine.cycle_time));
    let r = simulate_verdict(&s);
    let reserve = divert_overshoot(&s, &r) - margins.divert;
    let ratio = r.overload.overload_ratio;
    let load = if ratio.is_finite() {
        margins.ratio_limit() - ratio
    } else {
        -1.0
    };
    let slack = reserve.min(load);
    (r.outcome == Outcome::Diverted && slack >= 0.0, slack)
}

/// A scenario as its machine runs it: with the adaptive trigger, the arm started at this
/// parcel's own best R_s ([`best_start`], never upstream of the light barrier S_d) and the
/// trigger fixed there, with the search that chose it; a fixed trigger's scenario unchanged.
pub fn resolve(scenario: &Scenario) -> (Scenario, Option<BestStart>) {
    let mut s = scenario.clone();
    let Trigger::Adaptive(search) = &scenario.machine.trigger else {
        return (s, None);
    };
    s.machine.trigger = Trigger::Fixed;
    let best = best_start(&s, &scenario.parcel, search);
    s.machine.start_at(best.start.max(s.machine.light_barrier));
    (s, Some(best))
}

/// The best R_s of `parcel` at `setting` (module notes).
pub fn best_start(setting: &Scenario, parcel: &Parcel, search: &StartSearch) -> BestStart {
    let starts = search.starts();
    let runs: Vec<(bool, f64)> = starts
        .iter()
        .map(|&r| judge(setting, parcel, r, &search.margins))
        .collect();
    let mut sims = runs.len();
    let mut refine = |mut good: f64, mut bad: f64| {
        // Bounded: the bracket halves each pass, and a bracket that doubles cannot split
        // further ends the search whatever the tolerance.
        for _ in 0..MAX_BISECTIONS {
            if (good - bad).abs() <= search.tolerance {
                break;
            }
            let mid = 0.5 * (good + bad);
            if mid == good || mid == bad {
                break;
            }
            sims += 1;
            if judge(setting, parcel, mid, &search.margins).0 {
                good = mid;
            } else {
                bad = mid;
            }
        }
        good
    };
    let mut best: Option<(f64, f64)> = None;
    let mut i = 0;
    while i < runs.len() {
        if !runs[i].0 {
            i += 1;
            continue;
        }
        let mut j = i;
        while j + 1 < runs.len() && runs[j + 1].0 {
            j += 1;
        }
        let lo = if i > 0 {
            refine(starts[i], starts[i - 1])
        } else {
            starts[i]
        };
        let hi = if j + 1 < runs.len() {
            refine(starts[j], starts[j + 1])
        } else {
            starts[j]
        };
        if best.is_none_or(|(a, b)| hi - lo > b - a) {
            best = Some((lo, hi));
        }
        i = j + 1;
    }
    match best {
        Some((lo, hi)) => BestStart {
            start: 0.5 * (lo + hi),
            interval: (lo, hi),
            feasible: true,
            simulations: sims,
        },
        None => {
            let k = (0..runs.len())
                .max_by(|&a, &b| runs[a].1.total_cmp(&runs[b].1).then(b.cmp(&a)))
                .unwrap_or(0);
            let r = starts.get(k).copied().unwrap_or(search.range.0);
            BestStart {
                start: r,
                interval: (r, r),
                feasible: false,
                simulations: sims,
            }
        }
    }
}

/// The grid of the table: node values along each axis (one node fixes the axis).
#[derive(Debug, Clone, PartialEq)]
pub struct TableGrid {
    /// a \[m], increasing
    pub length: Vec<f64>,
    /// b/a in (0, 1], increasing
    pub aspect: Vec<f64>,
    /// ΔP/(P_max − extent across) in [0, 1], increasing
    pub offset_fraction: Vec<f64>,
    /// φ \[rad], increasing
    pub angle: Vec<f64>,
}

impl TableGrid {
    fn axes(&self) -> [&[f64]; 4] {
        [
            &self.length,
            &self.aspect,
            &self.offset_fraction,
            &self.angle,
        ]
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.axes().iter().map(|a| a.len()).product()
    }

    /// Whether the grid has no node.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The coordinates of a parcel (a, b/a, ΔP fraction, φ) on a belt of width P_max.
    pub fn coordinates(
        length: f64,
        width: f64,
        offset: f64,
        angle: f64,
        belt_width: f64,
    ) -> [f64; 4] {
        let room = belt_width - extent_across(length, width, angle);
        let fraction = if room > 0.0 {
            (offset / room).clamp(0.0, 1.0)
        } else {
            0.0
        };
        [length, width / length, fraction, angle]
    }
}

/// Nodes of a trigger table along each axis; where they lie comes from the mix
/// ([`TableNodes::grid`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TableNodes {
    /// Along the parcel length a.
    pub length: usize,
    /// Along the aspect b/a.
    pub aspect: usize,
    /// Across the room beside the parcel (offset fraction 0–1).
    pub offset: usize,
    /// Along the angle φ.
    pub angle: usize,
}

impl Default for TableNodes {
    /// 5 × 3 × 5 × 5.
    fn default() -> Self {
        TableNodes {
            length: 5,
            aspect: 3,
            offset: 5,
            angle: 5,
        }
    }
}

impl TableNodes {
    /// Number of nodes.
    pub fn count(&self) -> usize {
        self.length * self.aspect * self.offset * self.angle
    }

    /// The grid over the quantiles 0.5 %–99.5 % of 4096 parcels the mix draws at `setting`
    /// (one node where the quantity does not vary); the offset fractions span 0–1.
    pub fn grid(
        &self,
        mix: &ParcelMix,
        setting: &Scenario,
        seed: u64,
    ) -> Result<TableGrid, MixError> {
        let mut length = Vec::new();
        let mut aspect = Vec::new();
        let mut angle = Vec::new();
        for i in 0..4096 {
            let d = mix.draw(setting, seed, i)?;
            length.push(d.length);
            aspect.push(d.width / d.length);
            angle.push(d.angle);
        }
        let axis = |mut v: Vec<f64>, n: usize| {
            v.sort_by(f64::total_cmp);
            let lo = v[v.len() * 5 / 1000];
            let hi = v[v.len() * 995 / 1000];
            if hi > lo {
                linspace(lo, hi, n)
            } else {
                vec![lo]
            }
        };
        Ok(TableGrid {
            length: axis(length, self.length),
            aspect: axis(aspect, self.aspect),
            offset_fraction: linspace(0.0, 1.0, self.offset),
            angle: axis(angle, self.angle),
        })
    }
}

/// The per-parcel trigger table.
#[derive(Debug, Clone, PartialEq)]
pub struct TriggerTable {
    pub grid: TableGrid,
    /// The best R_s at every node, the last axis (φ) fastest \[m]
    pub starts: Vec<f64>,
    /// Whether each node's parcel had a passing R_s.
    pub feasible: Vec<bool>,
    /// Simulations the table took.
    pub simulations: usize,
}

impl TriggerTable {
    /// The table for `setting` over `grid`: the nodes in parallel (results in order).
    pub fn build(
        setting: &Scenario,
        grid: TableGrid,
        search: &StartSearch,
        progress: Progress<'_>,
    ) -> TriggerTable {
        let mut nodes = Vec::with_capacity(grid.len());
        for &a in &grid.length {
            for &q in &grid.aspect {
                for &f in &grid.offset_fraction {
                    for &phi in &grid.angle {
                        nodes.push((a, q, f, phi));
                    }
                }
            }
        }
        let belt_width = setting.machine.belt_width;
        let best = par_map(&nodes, progress, |&(a, q, f, phi)| {
            let b = a * q;
            let room = (belt_width - extent_across(a, b, phi)).max(0.0);
            let parcel = Parcel::riding(a, b, 0.1, 1.0, f * room, phi);
            best_start(setting, &parcel, search)
        });
        TriggerTable {
            grid,
            starts: best.iter().map(|b| b.start).collect(),
            feasible: best.iter().map(|b| b.feasible).collect(),
            simulations: best.iter().map(|b| b.simulations).sum(),
        }
    }

    /// The table's R_s for a parcel (multilinear, clamped to the grid), not upstream of the
    /// light barrier S_d \[m].
    pub fn start_for(
        &self,
        length: f64,
        width: f64,
        offset: f64,
        angle: f64,
        setting: &Scenario,
    ) -> f64 {
        let x = TableGrid::coordinates(length, width, offset, angle, setting.machine.belt_width);
        self.interpolate(x).max(setting.machine.light_barrier)
    }

    /// Multilinear interpolation at coordinates `x`.
    pub fn interpolate(&self, x: [f64; 4]) -> f64 {
        let axes = self.grid.axes();
        if axes.iter().any(|a| a.is_empty()) || self.starts.len() != self.grid.len() {
            // A table not built by `build`: no value rather than a panic.
            return f64::NAN;
        }
        // Per axis: the lower node and the weight of the upper one.
        let mut cell = [(0usize, 0.0f64); 4];
        for (k, axis) in axes.iter().enumerate() {
            cell[k] = locate(axis, x[k]);
        }
        let strides = {
            let mut s = [1usize; 4];
            for k in (0..3).rev() {
                s[k] = s[k + 1] * axes[k + 1].len();
            }
            s
        };
        let mut value = 0.0;
        for corner in 0..16usize {
            let mut w = 1.0;
            let mut idx = 0;
            for k in 0..4 {
                let upper = corner >> k & 1 == 1;
                let (i, t) = cell[k];
                if upper {
                    if t == 0.0 {
                        w = 0.0;
                        break;
                    }
                    w *= t;
                    idx += (i + 1) * strides[k];
                } else {
                    w *= 1.0 - t;
                    idx += i * strides[k];
                }
            }
            if w != 0.0 {
                value += w * self.starts[idx];
            }
        }
        value
    }

    /// Nodes without a passing R_s.
    pub fn infeasible_nodes(&self) -> usize {
        self.feasible.iter().filter(|f| !**f).count()
    }
}

/// The cell of `x` on an increasing axis: (lower node, weight of the upper node in [0, 1)),
/// clamped to the ends.
fn locate(axis: &[f64], x: f64) -> (usize, f64) {
    let n = axis.len();
    if n < 2 || x.is_nan() || x <= axis[0] {
        return (0, 0.0);
    }
    if x >= axis[n - 1] {
        return (n - 1, 0.0);
    }
    // Clamped so that an unsorted axis gives a wrong value, never a panic.
    let i = (axis.partition_point(|&v| v <= x).max(1) - 1).min(n - 2);
    let t = (x - axis[i]) / (axis[i + 1] - axis[i]);
    (i, t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::sweep::no_progress;
    use crate::sim::{simulate, UNRESOLVED_TRIGGER};

    /// "One analysis contract": the core's simulate ran an adaptive scenario at the file's
    /// R_s, silently another run than the machine's. The policy is in the scenario now: an
    /// unresolved one is a failed run naming the fix, and `resolve` gives the machine's.
    #[test]
    fn adaptive_trigger_unresolved_is_a_failed_run_not_a_silent_one() {
        let mut s = Scenario::paper_machine();
        let search = StartSearch {
            range: (-0.2, 0.8),
            step: 0.05,
            ..StartSearch::default()
        };
        s.machine.trigger = Trigger::Adaptive(search.clone());
        s.machine.start_position = 0.77;
        let unresolved = simulate(&s);
        assert_eq!(
            unresolved.outcome,
            Outcome::Failed(UNRESOLVED_TRIGGER.to_string())
        );
        let (resolved, best) = resolve(&s);
        let best = best.expect("an adaptive trigger is searched");
        assert_eq!(resolved.machine.trigger, Trigger::Fixed);
        assert_eq!(
            resolved.machine.start_position,
            best.start.max(s.machine.light_barrier)
        );
        // The search is the one the scenario carries: the same as best_start's.
        let mut fixed = s.clone();
        fixed.machine.trigger = Trigger::Fixed;
        assert_eq!(best, best_start(&fixed, &s.parcel, &search));
        assert!(!matches!(simulate(&resolved).outcome, Outcome::Failed(_)));
        // A fixed scenario is its own resolution.
        let (same, none) = resolve(&fixed);
        assert_eq!((same, none), (fixed, None));
    }

    /// Review of the trigger's move into the scenario: the analyses that choose R_s
    /// themselves (the trigger calibration, a design case, a searched pose) kept an adaptive
    /// trigger and so ran nothing. Choosing R_s fixes the trigger there (Machine::start_at).
    #[test]
    fn analyses_that_choose_r_s_run_an_adaptive_scenario_at_it() {
        use crate::analysis::design::design_set::{case_scenario, DesignPoint};
        use crate::analysis::paper::trigger::scenario_at;
        let mut adaptive = Scenario::paper_machine();
        adaptive.machine.trigger = Trigger::Adaptive(StartSearch::default());
        let point = DesignPoint {
            belt_speed: 2.0,
            cycle_time: 1.36,
            start_position: 0.1,
            light_barrier: 0.0,
        };
        for s in [
            scenario_at(&adaptive, 2.0, 1.36, 0.1),
            case_scenario(&adaptive, &adaptive.parcel, &point),
        ] {
            assert_eq!(s.machine.trigger, Trigger::Fixed);
            assert_eq!(s.machine.start_position, 0.1);
            assert!(!matches!(simulate(&s).outcome, Outcome::Failed(_)));
        }
    }

    #[test]
    fn interpolation_is_exact_at_nodes_and_linear_between() {
        let grid = TableGrid {
            length: vec![0.2, 0.6],
            aspect: vec![0.5],
            offset_fraction: vec![0.0, 1.0],
            angle: vec![-0.1, 0.1],
        };
        // starts = 1·a + 2·f + 3·φ at the nodes: multilinear reproduces it exactly.
        let mut starts = Vec::new();
        for a in &grid.length {
            for f in &grid.offset_fraction {
                for p in &grid.angle {
                    starts.push(a + 2.0 * f + 3.0 * p);
                }
            }
        }
        let t = TriggerTable {
            grid,
            feasible: vec![true; starts.len()],
            starts,
            simulations: 0,
        };
        let f = |a: f64, f: f64, p: f64| t.interpolate([a, 0.5, f, p]);
        assert!((f(0.2, 0.0, -0.1) - (0.2 - 0.3)).abs() < 1e-15);
        assert!((f(0.4, 0.25, 0.05) - (0.4 + 0.5 + 0.15)).abs() < 1e-14);
        // Clamped outside the grid.
        assert!((f(9.0, 2.0, 1.0) - (0.6 + 2.0 + 0.3)).abs() < 1e-14);
    }

    /// Regression (review of issue 11): a tolerance below the spacing of doubles made the
    /// bisection spin for ever; now it ends when the bracket cannot split.
    #[test]
    fn tiny_tolerance_does_not_hang_the_start_search() {
        let s = Scenario::paper_default();
        let search = StartSearch {
            range: (-0.3, 0.9),
            step: 0.3,
            tolerance: 1e-300,
            ..StartSearch::default()
        };
        assert_eq!(search.problems()[0].0, "tolerance");
        let b = best_start(&s, &s.parcel, &search);
        assert!(b.feasible);
        assert!(b.simulations < 5 + 2 * MAX_BISECTIONS, "{}", b.simulations);
    }

    /// A table not built by `build` (empty axis, wrong length, unsorted axis) gives NaN or
    /// a wrong value, never a panic.
    #[test]
    fn malformed_tables_do_not_panic() {
        let grid = |length: Vec<f64>| TableGrid {
            length,
            aspect: vec![0.5],
            offset_fraction: vec![0.0],
            angle: vec![0.0],
        };
        let t = TriggerTable {
            grid: grid(vec![]),
            starts: vec![],
            feasible: vec![],
            simulations: 0,
        };
        assert!(t.interpolate([0.3, 0.5, 0.0, 0.0]).is_nan());
        let t = TriggerTable {
            grid: grid(vec![0.5, 0.2, 0.9]),
            starts: vec![1.0, 2.0, 3.0],
            feasible: vec![true; 3],
            simulations: 0,
        };
        for x in [0.1, 0.3, 0.6, 1.0] {
            assert!(t.interpolate([x, 0.5, 0.0, 0.0]).is_finite());
        }
    }

    /// The chosen start diverts the parcel, and runs at the ends of its interval pass too.
    #[test]
    fn best_start_diverts_within_its_interval() {
        let s = Scenario::paper_default();
        let search = StartSearch {
            range: (-0.3, 0.9),
            step: 0.05,
            ..StartSearch::default()
        };
        let b = best_start(&s, &s.parcel, &search);
        assert!(b.feasible, "{b:?}");
        assert!(b.interval.0 < b.start && b.start < b.interval.1);
        for r in [b.interval.0, b.start, b.interval.1] {
            assert!(judge(&s, &s.parcel, r, &search.margins).0, "R_s = {r}");
        }
        // A single-node table gives the same start.
        let [a, q, f, phi] = TableGrid::coordinates(
            s.parcel.length,
            s.parcel.width,
            s.parcel.offset,
            s.parcel.angle,
            s.machine.belt_width,
        );
        let grid = TableGrid {
            length: vec![a],
            aspect: vec![q],
            offset_fraction: vec![f],
            angle: vec![phi],
        };
        let mut setting = s.clone();
        setting.machine.light_barrier = -1.0;
        let t = TriggerTable::build(&setting, grid, &search, &no_progress);
        let r = t.start_for(
            s.parcel.length,
            s.parcel.width,
            s.parcel.offset,
            0.0,
            &setting,
        );
        assert!((r - b.start).abs() < 1e-9, "{r} vs {}", b.start);
        // R_s never upstream of the barrier.
        setting.machine.light_barrier = 5.0;
        assert_eq!(t.start_for(0.4, 0.26, 0.22, 0.0, &setting), 5.0);
    }
}
