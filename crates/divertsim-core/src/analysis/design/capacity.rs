//! Capacity map W(t_c, S_d) by the paper's §4.2 algorithm (paper Fig. 9).
//!
//! For each cycle time t_c and belt speed v of a list, the setting must divert every parcel of
//! the design set and keep the worst-case overload allowed ([`crate::analysis::design::design_set`],
//! [`crate::analysis::paper::overload`]); at a light barrier S_d the parcel rides (R_s − S_d)/v before the arm
//! starts, so the best setting is the one with the smallest delay:
//!
//!   W(t_c, S_d) = max over feasible (v, R_s ≥ S_d) of 3600/((R_s − S_d)/v + t_c).
//!
//! **Search.** The divert verdicts do not depend on S_d (only W does), so for each (t_c, v)
//! whose overload is allowed the feasible set of R_s is found once:
//! 1. every design case is simulated on an R_s grid [R_min, R_max] with step ΔR;
//! 2. each boundary between a feasible and an infeasible grid point is refined by bisection
//!    to the tolerance (always keeping a simulated feasible end), giving intervals
//!    [lo_k, hi_k] of feasible R_s;
//! 3. for each S_d and v, the candidates are R_s = max(lo_k, S_d) for every interval with
//!    hi_k ≥ S_d; the candidates of all speeds are ranked by W (descending), then by the
//!    overload ratio (ascending: the gentler setting wins a tie, which happens whenever
//!    R_s = S_d, where W = 3600/t_c for every v), then by v (ascending);
//! 4. a candidate R_s = S_d strictly inside an interval has not been simulated: it is
//!    verified (all cases) and the next candidate is taken if it fails.
//!
//! Settings whose worst-case overload is not allowed are not simulated (the paper's
//! algorithm discards them). Feasible intervals narrower than ΔR that contain no grid point
//! can be missed; infeasible gaps narrower than ΔR inside an interval are caught only at the
//! chosen point (step 4).
//!
//! **Margins.** A feasible cell's worst margin is max(0, overload margin) (a diverted case
//! has divert margin 0, see [`crate::analysis::design::design_set`]); an infeasible cell's is the smallest, over
//! the speeds and the grid points R_s ≥ S_d, of max(worst divert margin, overload margin),
//! or of max(overload margin, S_d − R_max) when no grid point lies at or beyond S_d: how far
//! the cell is from feasible. For speeds skipped for overload, only the overload margin
//! counts.
//!
//! Deterministic: every (t_c, v) and every cell depends only on its own inputs, and
//! [`par_map`] keeps the order, so the map is identical for any thread count.

use crate::analysis::design::design_set::{
    run_check, CaseEvaluation, DesignPoint, DesignSet, WorstDefinition, FAILED_MARGIN,
};
use crate::analysis::paper::overload::{worst_case_overload, WorstCaseOverload};
use crate::model::params::Scenario;
use crate::run::memo::{self, cached, Memo, NoMemo};
use crate::run::sweep::{par_map, Progress};
use crate::sim::arm_loads::StrokeProfile;

/// Largest number of R_s grid points.
pub const MAX_START_POINTS: usize = 2001;
/// Largest number of grid cells (t_c × S_d) and of settings (t_c × v).
pub const MAX_GRID: usize = 1_000_000;

/// What to search.
#[derive(Debug, Clone, PartialEq)]
pub struct CapacityOptions {
    /// t_c values \[s], > 0.
    pub cycle_times: Vec<f64>,
    /// S_d values \[m].
    pub light_barriers: Vec<f64>,
    /// v values [m/s], > 0.
    pub belt_speeds: Vec<f64>,
    /// R_min: first R_s of the grid \[m].
    pub start_min: f64,
    /// R_max: last R_s of the grid \[m], ≥ R_min.
    pub start_max: f64,
    /// ΔR: R_s grid step \[m], > 0.
    pub start_step: f64,
    /// Bisection tolerance on the interval boundaries \[m], > 0.
    pub start_tolerance: f64,
}

impl Default for CapacityOptions {
    /// The paper's ranges: t_c 1.0–1.5 s, S_d 0–0.9 m (20 × 20), v 1.0–2.3 m/s (14),
    /// R_s 0–0.9 m every 0.05 m, boundaries to 5 mm.
    fn default() -> Self {
        CapacityOptions {
            cycle_times: linspace(1.0, 1.5, 20),
            light_barriers: linspace(0.0, 0.9, 20),
            belt_speeds: linspace(1.0, 2.3, 14),
            start_min: 0.0,
            start_max: 0.9,
            start_step: 0.05,
            start_tolerance: 0.005,
        }
    }
}

/// `count` evenly spaced values from `start` to `stop` inclusive (`[start]` for count 1).
pub fn linspace(start: f64, stop: f64, count: usize) -> Vec<f64> {
    match count {
        0 => Vec::new(),
        1 => vec![start],
        _ => (0..count)
            .map(|i| {
                if i + 1 == count {
                    stop
                } else {
                    start + (stop - start) * i as f64 / (count - 1) as f64
                }
            })
            .collect(),
    }
}

/// Why the map cannot be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CapacityError {
    #[error("{0}")]
    Invalid(String),
}

/// One R_s grid point of one (t_c, v).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StartSample {
    /// R_s \[m]
    pub start_position: f64,
    /// The largest divert margin over the cases \[m] (≤ 0: all diverted).
    pub divert_margin: f64,
    /// The largest simulated S/S_fall over the checks [-]
    pub overload_ratio: f64,
    /// Every check passed: diverted (with the required reserve) and, with the searched
    /// worst case, below the overload limit.
    pub feasible: bool,
}

/// The feasible R_s of one (t_c, v).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SpeedSetting {
    /// t_c \[s]
    pub cycle_time: f64,
    /// v [m/s]
    pub belt_speed: f64,
    /// The worst-case strike, or why it failed.
    pub overload: Result<WorstCaseOverload, String>,
    /// S/S_fall − 1, [`FAILED_MARGIN`] on failure.
    pub overload_margin: f64,
    /// The R_s grid (empty when the overload is not allowed).
    pub samples: Vec<StartSample>,
    /// Intervals [lo, hi] of R_s where every case is diverted \[m], increasing.
    pub feasible_starts: Vec<(f64, f64)>,
    /// Simulations run for this setting.
    pub simulations: usize,
}

/// One cell of the map.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CapacityCell {
    /// t_c \[s]
    pub cycle_time: f64,
    /// S_d \[m]
    pub light_barrier: f64,
    /// W [parcels/h]; 0 when infeasible.
    pub capacity: f64,
    /// The chosen v [m/s] (feasible cells).
    pub belt_speed: Option<f64>,
    /// The chosen R_s \[m] (feasible cells).
    pub start_position: Option<f64>,
    /// Whether some (v, R_s ≥ S_d) is feasible.
    pub feasible: bool,
    /// See the module notes: ≤ 0 feasible, > 0 how far from it.
    pub worst_margin: f64,
    /// S/S_fall of the chosen setting (feasible cells).
    pub overload_ratio: Option<f64>,
}

/// The whole search.
#[derive(Debug, Clone, PartialEq)]
pub struct CapacityMap {
    pub options: CapacityOptions,
    /// (t_c, v) settings, t_c-major.
    pub settings: Vec<SpeedSetting>,
    /// Cells, t_c-major (index i_tc · n_Sd + i_Sd).
    pub cells: Vec<CapacityCell>,
    /// Simulations run in total.
    pub simulations: usize,
}

/// A bound of the grid that the best cell sits on: W may grow past it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct GridEdge {
    /// The grid's option: `cycle_times`, `light_barriers` or `speeds`.
    pub option: &'static str,
    /// The best cell's value there (t_c \[s], S_d \[m] or its chosen v \[m/s]).
    pub value: f64,
    /// `"largest"` or `"smallest"` of the option's values.
    pub end: &'static str,
}

impl CapacityMap {
    /// The bounds of the grid the best cell sits on (none without a feasible cell): its t_c,
    /// S_d or chosen v at the first or last of two or more values. There the map cannot say
    /// whether W goes on growing past the grid (not at the longest cycle when the best cell
    /// already reaches W = 3600/t_c, the most any longer cycle gives).
    pub fn best_on_edges(&self) -> Vec<GridEdge> {
        let Some(b) = self.best() else {
            return Vec::new();
        };
        let o = &self.options;
        let axes: [(&'static str, &[f64], Option<f64>); 3] = [
            ("cycle_times", &o.cycle_times, Some(b.cycle_time)),
            ("light_barriers", &o.light_barriers, Some(b.light_barrier)),
            ("speeds", &o.belt_speeds, b.belt_speed),
        ];
        let mut edges = Vec::new();
        for (option, values, value) in axes {
            let Some(value) = value else { continue };
            if values.len() < 2 {
                continue;
            }
            let (lo, hi) = values
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, c), &v| {
                    (a.min(v), c.max(v))
                });
            // W = 3600 / ((R_s − S_d)/v + t_c) ≤ 3600/t_c: past the longest cycle W cannot
            // beat a best cell that already reaches 3600/t_c there.
            let capped = option == "cycle_times" && b.capacity >= 3600.0 / value * (1.0 - 1e-9);
            let end = if value >= hi && !capped {
                "largest"
            } else if value >= hi {
                continue;
            } else if value <= lo {
                "smallest"
            } else {
                continue;
            };
            edges.push(GridEdge { option, value, end });
        }
        edges
    }

    /// The feasible cell with the largest W (first in grid order on a tie).
    pub fn best(&self) -> Option<&CapacityCell> {
        self.cells
            .iter()
            .filter(|c| c.feasible)
            .fold(None, |best: Option<&CapacityCell>, c| match best {
                Some(b) if b.capacity >= c.capacity => Some(b),
                _ => Some(c),
            })
    }
}

impl CapacityOptions {
    /// R_s grid points.
    pub fn starts(&self) -> Vec<f64> {
        let n = ((self.start_max - self.start_min) / self.start_step + 1e-9).floor() as usize + 1;
        let mut v: Vec<f64> = (0..n)
            .map(|i| self.start_min + i as f64 * self.start_step)
            .collect();
        if let Some(last) = v.last_mut() {
            *last = last.min(self.start_max);
        }
        if v.last().is_some_and(|&l| self.start_max - l > 1e-9) {
            v.push(self.start_max);
        }
        v
    }

    /// Every problem with the options, as messages naming the field.
    pub fn problems(&self) -> Vec<String> {
        let mut p = Vec::new();
        let list = |name: &str, v: &[f64], positive: bool, p: &mut Vec<String>| {
            if v.is_empty() {
                p.push(format!("{name}: empty"));
            }
            if v.iter().any(|x| !x.is_finite() || (positive && *x <= 0.0)) {
                p.push(format!(
                    "{name}: every value must be finite{}",
                    if positive { " and > 0" } else { "" }
                ));
            }
        };
        list("cycle_times", &self.cycle_times, true, &mut p);
        list("light_barriers", &self.light_barriers, false, &mut p);
        list("belt_speeds", &self.belt_speeds, true, &mut p);
        if !(self.start_min.is_finite() && self.start_max.is_finite())
            || self.start_max < self.start_min
        {
            p.push(format!(
                "start range [{}, {}]: must be finite with start_max ≥ start_min",
                self.start_min, self.start_max
            ));
        } else if !(self.start_step.is_finite() && self.start_step > 0.0) {
            p.push(format!("start_step {}: must be > 0", self.start_step));
        } else if (self.start_max - self.start_min) / self.start_step
            > (MAX_START_POINTS - 1) as f64
        {
            p.push(format!(
                "start_step {}: more than {MAX_START_POINTS} R_s grid points",
                self.start_step
            ));
        }
        if !(self.start_tolerance.is_finite() && self.start_tolerance > 0.0) {
            p.push(format!(
                "start_tolerance {}: must be > 0",
                self.start_tolerance
            ));
        }
        let n = self.cycle_times.len();
        if n.saturating_mul(self.light_barriers.len().max(self.belt_speeds.len())) > MAX_GRID {
            p.push(format!("more than {MAX_GRID} grid points"));
        }
        p
    }
}

/// The most simulations the map runs: every check at every R_s grid point of every
/// (t_c, v), and a bisection to the tolerance at every boundary between a feasible and an
/// infeasible grid point (at most one between each two neighbours). Exact counts depend on
/// the verdicts (a failing check ends a grid point early; most settings have two
/// boundaries or none): [`least_simulations`] is the other end.
pub fn estimated_simulations(options: &CapacityOptions, set: &DesignSet) -> usize {
    let bisection = crate::run::sweep::bisection_steps(options.start_step, options.start_tolerance);
    let starts = options.starts().len();
    options.cycle_times.len()
        * options.belt_speeds.len()
        * (starts + starts.saturating_sub(1) * bisection)
        * set.run_count()
}

/// The simulations the map runs whatever its verdicts: with the searched worst case one
/// check at every R_s grid point of every (t_c, v) (a point stops at its first failing
/// check); with the paper's, every check at every R_s grid point of each (t_c, v) whose
/// closed-form overload is within the limit (the others are discarded unsimulated).
pub fn least_simulations(base: &Scenario, options: &CapacityOptions, set: &DesignSet) -> usize {
    let starts = options.starts().len();
    let settings = options.cycle_times.len() * options.belt_speeds.len();
    if set.worst == WorstDefinition::Search {
        return settings * starts * set.run_count().min(1);
    }
    let limit = set.margins.ratio_limit();
    let kept = options
        .cycle_times
        .iter()
        .flat_map(|&t| options.belt_speeds.iter().map(move |&v| (t, v)))
        .filter(|&(t, v)| {
            worst_case_overload(base, &set.overload_parcel, t, v)
                .is_ok_and(|o| o.ratio.is_finite() && o.ratio <= limit)
        })
        .count();
    kept * starts * set.run_count()
}

/// Whether a check passes: diverted with the required reserve, within the drive-torque
/// limit and, with the searched worst case, below the overload limit.
fn passes(set: &DesignSet, e: &CaseEvaluation) -> bool {
    e.passes_divert(&set.margins)
        && e.passes_torque(&set.margins)
        && (set.worst == WorstDefinition::Paper || e.overload_ratio <= set.margins.ratio_limit())
}

/// Whether every check passes (stops at the first that does not), counting simulations;
/// with the largest S/S_fall of the checks run.
pub(crate) fn all_pass(
    base: &Scenario,
    set: &DesignSet,
    point: &DesignPoint,
    profile: Option<&StrokeProfile>,
    sims: &mut usize,
) -> (bool, f64) {
    let r = run_checks(base, set, point, profile, None, sims);
    (r.feasible, r.ratio)
}

/// The checks run at one setting, up to the first failure: how many, whether all passed,
/// and the largest margin and S/S_fall among them.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
struct CheckRun {
    done: usize,
    feasible: bool,
    /// max over the checks run of (divert margin − reserve, torque margin, and with the
    /// searched worst case S/S_fall − limit)
    margin: f64,
    ratio: f64,
}

/// What the maps of a robust run's earlier rounds found at each setting (issue 28). A round
/// maps against the poses of the round before plus new ones, appended: the checks of the
/// earlier round are the first checks of the next, in the same order. A setting that failed
/// one fails it again (the runs are the same), and one that passed them all needs only the
/// new checks. The map, cells and margins are those of running every check; only the count
/// of simulations falls. A map reads what the maps before it found and adds its own
/// findings when it is done, so what it reads does not depend on the order its threads ran
/// in; each piece keeps its findings with it in the memo, so a resumed run finds the same.
///
/// A cache belongs to one series of maps: the same base scenario, options, design cases and
/// margins, with worst poses only ever appended. Anything else needs a new cache (its
/// entries would be another set's).
#[derive(Debug, Default)]
pub struct CheckCache {
    earlier: std::collections::HashMap<[u64; 4], CheckRun>,
}

/// The checks one piece of a map ran, by setting.
type Found = Vec<([u64; 4], CheckRun)>;

/// A piece's view of a [`CheckCache`]: what earlier maps found, and what this piece finds.
struct Resume<'a> {
    earlier: &'a std::collections::HashMap<[u64; 4], CheckRun>,
    found: std::cell::RefCell<Found>,
}

impl<'a> Resume<'a> {
    fn of(cache: Option<&'a CheckCache>) -> Option<Resume<'a>> {
        cache.map(|c| Resume {
            earlier: &c.earlier,
            found: std::cell::RefCell::new(Vec::new()),
        })
    }

    fn found(resume: Option<Resume<'_>>) -> Found {
        resume.map(|r| r.found.into_inner()).unwrap_or_default()
    }
}

/// Runs the checks of `set` at `point` in order, stopping at the first failure, resumed from
/// `cache` where an earlier round ran them (see [`CheckCache`]); counts the simulations.
fn run_checks(
    base: &Scenario,
    set: &DesignSet,
    point: &DesignPoint,
    profile: Option<&StrokeProfile>,
    cache: Option<&Resume>,
    sims: &mut usize,
) -> CheckRun {
    // Every input of the runs: S_d changes none today, but the scenario carries it.
    let key = [
        point.cycle_time.to_bits(),
        point.belt_speed.to_bits(),
        point.start_position.to_bits(),
        point.light_barrier.to_bits(),
    ];
    let mut run = cache
        .and_then(|c| c.earlier.get(&key).copied())
        .unwrap_or(CheckRun {
            done: 0,
            feasible: true,
            margin: f64::NEG_INFINITY,
            ratio: 0.0,
        });
    if run.feasible {
        for (_, name, s) in set.checks_from(base, point, run.done) {
            let e = run_check(&name, &s, profile);
            *sims += 1;
            run.done += 1;
            run.margin = run
                .margin
                .max(set.margins.divert - e.overshoot)
                .max(set.margins.torque_margin(e.drive_torque));
            if set.worst == WorstDefinition::Search {
                run.margin = run.margin.max(e.overload_ratio - set.margins.ratio_limit());
            }
            run.ratio = run.ratio.max(e.overload_ratio);
            if !passes(set, &e) {
                run.feasible = false;
                break;
            }
        }
    }
    if let Some(c) = cache {
        c.found.borrow_mut().push((key, run));
    }
    run
}

/// The feasible R_s intervals of one (t_c, v).
pub fn speed_setting(
    base: &Scenario,
    set: &DesignSet,
    options: &CapacityOptions,
    cycle_time: f64,
    belt_speed: f64,
) -> SpeedSetting {
    speed_setting_with(base, set, options, cycle_time, belt_speed, None)
}

/// [`speed_setting`] with the checks of a robust run's earlier rounds (see [`CheckCache`]).
fn speed_setting_with(
    base: &Scenario,
    set: &DesignSet,
    options: &CapacityOptions,
    cycle_time: f64,
    belt_speed: f64,
    cache: Option<&Resume>,
) -> SpeedSetting {
    let overload = worst_case_overload(base, &set.overload_parcel, cycle_time, belt_speed)
        .map_err(|e| e.to_string());
    // The paper's closed form discards a whole speed; the searched worst case is checked
    // per run, so every speed is simulated.
    let overload_margin = match (&overload, set.worst) {
        (_, WorstDefinition::Search) => 0.0,
        (Ok(o), _) if o.ratio.is_finite() => o.ratio - set.margins.ratio_limit(),
        _ => FAILED_MARGIN,
    };
    let mut out = SpeedSetting {
        cycle_time,
        belt_speed,
        overload,
        overload_margin,
        samples: Vec::new(),
        feasible_starts: Vec::new(),
        simulations: 0,
    };
    if overload_margin > 0.0 {
        return out;
    }
    let profile = set.stroke_profile(base, cycle_time);
    let profile = profile.as_ref();
    let point = |r: f64| DesignPoint {
        belt_speed,
        cycle_time,
        start_position: r,
        light_barrier: r,
    };
    for r in options.starts() {
        let p = point(r);
        if set.worst == WorstDefinition::Search {
            // The first failure decides (the margin is then a lower bound of how far the
            // point is from feasible).
            let run = run_checks(base, set, &p, profile, cache, &mut out.simulations);
            out.samples.push(StartSample {
                start_position: r,
                divert_margin: run.margin,
                overload_ratio: run.ratio,
                feasible: run.feasible,
            });
            continue;
        }
        // The paper's worst case: few checks, every one run (the margin is exact).
        let mut margin = f64::NEG_INFINITY;
        let mut ratio: f64 = 0.0;
        let mut feasible = true;
        for (_, name, s) in set.checks(base, &p) {
            let e = run_check(&name, &s, profile);
            out.simulations += 1;
            margin = margin
                .max(set.margins.divert - e.overshoot)
                .max(set.margins.torque_margin(e.drive_torque));
            ratio = ratio.max(e.overload_ratio);
            feasible &= passes(set, &e);
        }
        out.samples.push(StartSample {
            start_position: r,
            divert_margin: margin,
            overload_ratio: ratio,
            feasible,
        });
    }
    // Refine a boundary between a feasible and an infeasible R_s, keeping the feasible end.
    let mut sims = 0;
    let mut refine = |mut good: f64, mut bad: f64| {
        while (good - bad).abs() > options.start_tolerance {
            let mid = 0.5 * (good + bad);
            if run_checks(base, set, &point(mid), profile, cache, &mut sims).feasible {
                good = mid;
            } else {
                bad = mid;
            }
        }
        good
    };
    let s = &out.samples;
    let mut i = 0;
    while i < s.len() {
        if !s[i].feasible {
            i += 1;
            continue;
        }
        let mut j = i;
        while j + 1 < s.len() && s[j + 1].feasible {
            j += 1;
        }
        let lo = if i > 0 {
            refine(s[i].start_position, s[i - 1].start_position)
        } else {
            s[i].start_position
        };
        let hi = if j + 1 < s.len() {
            refine(s[j].start_position, s[j + 1].start_position)
        } else {
            s[j].start_position
        };
        out.feasible_starts.push((lo, hi));
        i = j + 1;
    }
    out.simulations += sims;
    out
}

/// One cell from the settings of its t_c.
fn cell(
    base: &Scenario,
    set: &DesignSet,
    options: &CapacityOptions,
    settings: &[SpeedSetting],
    cycle_time: f64,
    light_barrier: f64,
    cache: Option<&Resume>,
) -> (CapacityCell, usize) {
    // Candidates (W, overload ratio, v, R_s, needs verification).
    let mut cands: Vec<(f64, f64, f64, f64, bool)> = Vec::new();
    for st in settings.iter().filter(|s| s.overload_margin <= 0.0) {
        let ratio = st
            .overload
            .as_ref()
            .map(|o| o.ratio)
            .unwrap_or(f64::INFINITY);
        for &(lo, hi) in st
            .feasible_starts
            .iter()
            .filter(|(_, hi)| *hi >= light_barrier)
        {
            let r = lo.max(light_barrier);
            let w = crate::analysis::design::design_set::capacity(&DesignPoint {
                belt_speed: st.belt_speed,
                cycle_time,
                start_position: r,
                light_barrier,
            });
            let simulated = r == lo
                || r == hi
                || st
                    .samples
                    .iter()
                    .any(|s| s.feasible && s.start_position == r);
            cands.push((w, ratio, st.belt_speed, r, !simulated));
        }
    }
    cands.sort_by(|a, b| {
        b.0.total_cmp(&a.0)
            .then(a.1.total_cmp(&b.1))
            .then(a.2.total_cmp(&b.2))
            .then(a.3.total_cmp(&b.3))
    });
    let mut sims = 0;
    let profile = set.stroke_profile(base, cycle_time);
    for &(w, ratio, v, r, verify) in &cands {
        let p = DesignPoint {
            belt_speed: v,
            cycle_time,
            start_position: r,
            light_barrier,
        };
        // With the searched worst case the chosen setting is always run: its simulated
        // overload ratio is the cell's.
        let mut ratio = ratio;
        if verify || set.worst == WorstDefinition::Search {
            let run = run_checks(base, set, &p, profile.as_ref(), cache, &mut sims);
            if !run.feasible {
                continue;
            }
            if set.worst == WorstDefinition::Search {
                ratio = run.ratio;
            }
        }
        let cell = CapacityCell {
            cycle_time,
            light_barrier,
            capacity: w,
            belt_speed: Some(v),
            start_position: Some(r),
            feasible: true,
            worst_margin: (ratio - set.margins.ratio_limit()).max(0.0),
            overload_ratio: Some(ratio),
        };
        return (cell, sims);
    }
    // Infeasible: how far from feasible.
    let mut worst = f64::INFINITY;
    for st in settings {
        let g = st
            .samples
            .iter()
            .filter(|s| s.start_position >= light_barrier)
            .map(|s| s.divert_margin.max(st.overload_margin))
            .fold(f64::INFINITY, f64::min);
        let g = if g.is_finite() {
            g
        } else if st.samples.is_empty() {
            st.overload_margin
        } else {
            st.overload_margin.max(light_barrier - options.start_max)
        };
        worst = worst.min(g);
    }
    let cell = CapacityCell {
        cycle_time,
        light_barrier,
        capacity: 0.0,
        belt_speed: None,
        start_position: None,
        feasible: false,
        worst_margin: if worst.is_finite() {
            worst
        } else {
            FAILED_MARGIN
        },
        overload_ratio: None,
    };
    (cell, sims)
}

/// The pieces of work of a map, each reported once to `progress` when finished: every
/// (t_c, v) setting and every cell.
pub fn pieces(options: &CapacityOptions) -> usize {
    options.cycle_times.len() * (options.belt_speeds.len() + options.light_barriers.len())
}

/// The capacity map (module notes). `progress` is called once per finished piece (see
/// [`pieces`]): settings are far from equal in cost, but a count of simulations cannot be
/// known before the bisections run.
pub fn capacity_map(
    base: &Scenario,
    set: &DesignSet,
    options: &CapacityOptions,
    progress: Progress<'_>,
) -> Result<CapacityMap, CapacityError> {
    capacity_map_kept(base, set, options, progress, &NoMemo)
}

/// [`capacity_map`] with every finished (t_c, v) setting and cell kept in `memo` and
/// recalled instead of computed (an interrupted run resumes; the map is the same bit for
/// bit).
pub fn capacity_map_kept(
    base: &Scenario,
    set: &DesignSet,
    options: &CapacityOptions,
    progress: Progress<'_>,
    memo: &dyn Memo,
) -> Result<CapacityMap, CapacityError> {
    capacity_map_resumed(base, set, options, progress, memo, None)
}

/// [`capacity_map_kept`] with the checks of a robust run's earlier rounds ([`CheckCache`]):
/// the same map, fewer simulations. The map's own checks are added to `cache` at its end.
pub fn capacity_map_resumed(
    base: &Scenario,
    set: &DesignSet,
    options: &CapacityOptions,
    progress: Progress<'_>,
    memo: &dyn Memo,
    cache: Option<&mut CheckCache>,
) -> Result<CapacityMap, CapacityError> {
    let problems = options.problems();
    if !problems.is_empty() {
        return Err(CapacityError::Invalid(problems.join("; ")));
    }
    if set.cases.is_empty() {
        return Err(CapacityError::Invalid(
            "the design set has no parcels".into(),
        ));
    }
    let pairs: Vec<(f64, f64)> = options
        .cycle_times
        .iter()
        .flat_map(|&tc| options.belt_speeds.iter().map(move |&v| (tc, v)))
        .collect();
    let reading = cache.as_deref();
    // Each piece keeps the checks it ran beside it (a resumed run finds them too).
    let settings: Vec<(SpeedSetting, Found)> = par_map(&pairs, progress, |&(tc, v)| {
        let key = memo::key(
            "capacity speed setting and its checks",
            &(base, set, options, tc, v),
        );
        cached(memo, key, || {
            let resume = Resume::of(reading);
            let s = speed_setting_with(base, set, options, tc, v, resume.as_ref());
            (s, Resume::found(resume))
        })
        .0
    });
    let (settings, mut found): (Vec<SpeedSetting>, Vec<Found>) = settings.into_iter().unzip();
    let nv = options.belt_speeds.len();
    let cells_in: Vec<(usize, f64)> = (0..options.cycle_times.len())
        .flat_map(|i| options.light_barriers.iter().map(move |&sd| (i, sd)))
        .collect();
    let cells = par_map(&cells_in, progress, |&(i, sd)| {
        let key = memo::key("capacity cell and its checks", &(base, set, options, i, sd));
        cached(memo, key, || {
            let resume = Resume::of(reading);
            let (c, sims) = cell(
                base,
                set,
                options,
                &settings[i * nv..(i + 1) * nv],
                options.cycle_times[i],
                sd,
                resume.as_ref(),
            );
            (c, sims, Resume::found(resume))
        })
        .0
    });
    let cells: Vec<(CapacityCell, usize)> = cells
        .into_iter()
        .map(|(c, sims, f)| {
            found.push(f);
            (c, sims)
        })
        .collect();
    if let Some(c) = cache {
        c.earlier.extend(found.into_iter().flatten());
    }
    let simulations = settings.iter().map(|s| s.simulations).sum::<usize>()
        + cells.iter().map(|c| c.1).sum::<usize>();
    Ok(CapacityMap {
        options: options.clone(),
        settings,
        cells: cells.into_iter().map(|c| c.0).collect(),
        simulations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::design::design_set::{evaluate, DesignCase};
    use crate::run::sweep::no_progress;
    use crate::sim::Outcome;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    fn small_options() -> CapacityOptions {
        CapacityOptions {
            cycle_times: vec![1.36],
            light_barriers: vec![0.0, 0.3, 0.85],
            belt_speeds: vec![1.2, 2.0],
            start_min: 0.0,
            start_max: 0.6,
            start_step: 0.1,
            start_tolerance: 0.01,
        }
    }

    /// One cheap case (the compact parcel at ΔP = 0) keeps the test fast.
    fn compact_only() -> DesignSet {
        let mut set = DesignSet::paper(0.7);
        set.cases.retain(|c| c.name == "compact");
        set
    }

    /// Issue 50, item 3: the best cell on a bound of the grid is named, with the end; inside
    /// the grid, or on an axis of one value, nothing is.
    #[test]
    fn a_best_cell_on_the_grids_edge_is_named() {
        let cell =
            |cycle_time: f64, light_barrier: f64, capacity: f64, v: Option<f64>| CapacityCell {
                cycle_time,
                light_barrier,
                capacity,
                belt_speed: v,
                start_position: v.map(|_| 0.5),
                feasible: v.is_some(),
                worst_margin: if v.is_some() { -0.01 } else { 0.1 },
                overload_ratio: v.map(|_| 0.9),
            };
        let options = CapacityOptions {
            cycle_times: vec![1.0, 1.2, 1.4],
            light_barriers: vec![0.0, 0.5],
            belt_speeds: vec![1.0, 1.5, 2.0],
            ..small_options()
        };
        let mut map = CapacityMap {
            options,
            settings: Vec::new(),
            cells: vec![
                cell(1.0, 0.0, 0.0, None),
                cell(1.0, 0.5, 0.0, None),
                cell(1.2, 0.0, 2000.0, Some(1.5)),
                cell(1.2, 0.5, 2100.0, Some(1.5)),
                cell(1.4, 0.0, 1900.0, Some(2.0)),
                cell(1.4, 0.5, 1950.0, Some(1.0)),
            ],
            simulations: 0,
        };
        let e = map.best_on_edges();
        assert_eq!(
            e,
            vec![GridEdge {
                option: "light_barriers",
                value: 0.5,
                end: "largest"
            }]
        );
        map.cells[5].capacity = 2200.0;
        let e = map.best_on_edges();
        let named: Vec<_> = e.iter().map(|g| (g.option, g.end)).collect();
        assert_eq!(
            named,
            vec![
                ("cycle_times", "largest"),
                ("light_barriers", "largest"),
                ("speeds", "smallest")
            ]
        );
        // At the longest cycle with W = 3600/t_c (R_s = S_d) nothing past it can do better.
        map.cells[5].capacity = 3600.0 / 1.4;
        let named: Vec<_> = map.best_on_edges().iter().map(|g| g.option).collect();
        assert_eq!(named, vec!["light_barriers", "speeds"]);
        map.cells[5].capacity = 2200.0;
        map.options.light_barriers = vec![0.5];
        map.cells.retain(|c| c.light_barrier == 0.5);
        assert_eq!(map.best_on_edges().len(), 2, "one value is not an edge");
        map.cells.iter_mut().for_each(|c| c.feasible = false);
        assert!(map.best_on_edges().is_empty());
    }

    #[test]
    fn linspace_and_grid() {
        assert_eq!(linspace(1.0, 2.0, 3), vec![1.0, 1.5, 2.0]);
        assert_eq!(linspace(1.0, 2.0, 1), vec![1.0]);
        assert!(linspace(1.0, 2.0, 0).is_empty());
        let o = CapacityOptions::default();
        let s = o.starts();
        assert_eq!(s.len(), 19);
        assert_eq!(s[0], 0.0);
        assert_relative_eq!(s[18], 0.9, epsilon = 1e-12);
        let mut o2 = small_options();
        o2.start_max = 0.65;
        assert_eq!(*o2.starts().last().unwrap(), 0.65);
        assert_eq!(o2.starts().len(), 8);
    }

    #[test]
    fn bad_options_are_errors() {
        let base = Scenario::paper_default();
        let set = compact_only();
        for f in [
            |o: &mut CapacityOptions| o.cycle_times.clear(),
            |o: &mut CapacityOptions| o.belt_speeds[0] = 0.0,
            |o: &mut CapacityOptions| o.start_step = 0.0,
            |o: &mut CapacityOptions| o.start_max = -1.0,
            |o: &mut CapacityOptions| o.start_tolerance = f64::NAN,
            |o: &mut CapacityOptions| o.light_barriers[0] = f64::INFINITY,
        ] {
            let mut o = small_options();
            f(&mut o);
            assert!(
                capacity_map(&base, &set, &o, &no_progress).is_err(),
                "{o:?}"
            );
        }
    }

    /// The map agrees with independent evaluations: every feasible cell's chosen setting is
    /// feasible by [`evaluate`] and its W is the formula's; the chosen R_s is the smallest
    /// feasible one ≥ S_d on the grid within the tolerance; an infeasible cell has no
    /// feasible grid point at or beyond S_d for any speed.
    /// Issue 26: a torque limit above every run's peak leaves the map as it is; one below
    /// the smallest stroke's inertia-free peak empties it, and every R_s sample says by how
    /// much (the torque margin).
    #[test]
    fn a_drive_torque_limit_shapes_the_map() {
        let base = Scenario::paper_default();
        let o = small_options();
        let free = capacity_map(&base, &compact_only(), &o, &no_progress).unwrap();
        let mut set = compact_only();
        set.margins.drive_torque = Some(1e6);
        let loose = capacity_map(&base, &set, &o, &no_progress).unwrap();
        let cells = |m: &CapacityMap| {
            m.cells
                .iter()
                .map(|c| (c.feasible, c.capacity, c.belt_speed, c.start_position))
                .collect::<Vec<_>>()
        };
        assert_eq!(cells(&loose), cells(&free));
        assert!(free.cells.iter().any(|c| c.feasible));
        set.margins.drive_torque = Some(1e-3);
        let tight = capacity_map(&base, &set, &o, &no_progress).unwrap();
        assert!(tight
            .cells
            .iter()
            .all(|c| !c.feasible && c.worst_margin > 0.0));
    }

    #[test]
    fn cells_agree_with_direct_evaluation() {
        let base = Scenario::paper_default();
        let set = compact_only();
        let o = small_options();
        let map = capacity_map(&base, &set, &o, &no_progress).unwrap();
        assert_eq!(map.settings.len(), 2);
        assert_eq!(map.cells.len(), 3);
        for c in &map.cells {
            if c.feasible {
                let p = DesignPoint {
                    belt_speed: c.belt_speed.unwrap(),
                    cycle_time: c.cycle_time,
                    start_position: c.start_position.unwrap(),
                    light_barrier: c.light_barrier,
                };
                let e = evaluate(&base, &set, &p);
                assert!(e.feasible, "{c:?} {e:?}");
                assert_eq!(c.capacity, e.capacity);
                assert!(c.worst_margin <= 0.0);
                // No faster feasible grid point was overlooked.
                for st in &map.settings {
                    for s in st.samples.iter().filter(|s| s.feasible) {
                        if s.start_position >= c.light_barrier {
                            let w = 3600.0
                                / ((s.start_position - c.light_barrier) / st.belt_speed
                                    + c.cycle_time);
                            assert!(w <= c.capacity * (1.0 + 1e-12), "{s:?} beats {c:?}");
                        }
                    }
                }
            } else {
                assert!(c.worst_margin > 0.0);
                for st in &map.settings {
                    assert!(!st
                        .samples
                        .iter()
                        .any(|s| s.feasible && s.start_position >= c.light_barrier));
                }
            }
        }
        // Interval ends are feasible and within the tolerance of an infeasible point.
        for st in &map.settings {
            for &(lo, hi) in &st.feasible_starts {
                assert!(lo <= hi);
                for r in [lo, hi] {
                    let p = DesignPoint {
                        belt_speed: st.belt_speed,
                        cycle_time: st.cycle_time,
                        start_position: r,
                        light_barrier: r,
                    };
                    assert!(evaluate(&base, &set, &p).cases[0].outcome == Outcome::Diverted);
                }
            }
        }
        let total: usize = map.settings.iter().map(|s| s.simulations).sum();
        assert!(map.simulations >= total && total >= 2 * 7);
    }

    /// A parcel that can never be diverted (the arm's tip cannot reach: a belt far wider than
    /// the arm) makes every cell infeasible with a positive margin.
    #[test]
    fn undivertable_set_is_infeasible_everywhere() {
        let mut base = Scenario::paper_default();
        base.machine.belt_width = 3.0;
        let mut set = compact_only();
        set.cases = vec![DesignCase {
            name: "far".into(),
            parcel: {
                let mut p = set.cases[0].parcel.clone();
                p.offset = 0.0;
                p
            },
        }];
        let mut o = small_options();
        o.belt_speeds = vec![2.0];
        o.start_step = 0.3;
        let map = capacity_map(&base, &set, &o, &no_progress).unwrap();
        assert!(map
            .cells
            .iter()
            .all(|c| !c.feasible && c.worst_margin > 0.0));
        assert!(map.best().is_none());
    }

    /// Overload beyond the limit: no setting is simulated and every cell is infeasible with
    /// the overload margin.
    #[test]
    fn overload_limit_excludes_settings() {
        let mut base = Scenario::paper_default();
        base.limits.drop_height = 1e-4;
        let set = compact_only();
        let map = capacity_map(&base, &set, &small_options(), &no_progress).unwrap();
        assert_eq!(map.simulations, 0);
        let min_margin = map
            .settings
            .iter()
            .map(|s| s.overload_margin)
            .fold(f64::INFINITY, f64::min);
        for c in &map.cells {
            assert!(!c.feasible);
            assert_eq!(c.worst_margin, min_margin);
        }
    }

    /// Issue 28: a map against poses P ∪ Q, resumed from the map against P
    /// ([`CheckCache`]), is the map computed afresh, every sample, margin and cell bit for
    /// bit, in fewer simulations; the map against P again runs nothing but its chosen
    /// cells' bookkeeping.
    #[test]
    fn a_map_resumed_from_the_round_before_is_the_map_afresh() {
        use crate::analysis::design::worst_case::Pose;
        use crate::analysis::test_support::{far_side_pose, paper_machine};
        let base = paper_machine();
        let mut set = DesignSet::paper(0.7);
        set.worst = WorstDefinition::Search;
        let options = CapacityOptions {
            cycle_times: vec![1.3, 1.5],
            light_barriers: vec![0.1, 0.5],
            belt_speeds: vec![1.0, 1.6],
            start_min: 0.0,
            start_max: 0.9,
            start_step: 0.1,
            start_tolerance: 0.02,
        };
        let second = Pose {
            angle_deg: 12.0,
            offset: 0.1,
            length: 0.6,
            ..far_side_pose()
        };
        set.worst_poses = vec![far_side_pose()];
        let map = |set: &DesignSet, cache: Option<&mut CheckCache>| {
            capacity_map_resumed(&base, set, &options, &no_progress, &NoMemo, cache).unwrap()
        };
        let mut cache = CheckCache::default();
        let before = map(&set, Some(&mut cache));
        assert_eq!(before, map(&set, None));
        // The same set again: every check is known.
        let again = map(&set, Some(&mut cache));
        assert_eq!(
            (again.cells.clone(), again.simulations),
            (before.cells.clone(), 0)
        );
        set.worst_poses.push(second);
        let afresh = map(&set, None);
        let resumed = map(&set, Some(&mut cache));
        assert_eq!(resumed.cells, afresh.cells);
        for (r, a) in resumed.settings.iter().zip(&afresh.settings) {
            assert_eq!(r.samples, a.samples);
            assert_eq!(r.feasible_starts, a.feasible_starts);
        }
        assert!(afresh.cells.iter().any(|c| c.feasible));
        assert!(
            resumed.simulations < afresh.simulations,
            "{} vs {}",
            resumed.simulations,
            afresh.simulations
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        /// The R_s grid starts at R_min, ends at R_max, and its steps are ΔR (the last one
        /// possibly shorter).
        #[test]
        fn start_grid(min in -1.0f64..1.0, span in 0.0f64..2.0, step in 0.01f64..0.5) {
            let o = CapacityOptions { start_min: min, start_max: min + span, start_step: step,
                                      ..CapacityOptions::default() };
            let s = o.starts();
            prop_assert_eq!(s[0], min);
            prop_assert!((s[s.len() - 1] - (min + span)).abs() < 1e-9);
            for w in s.windows(2) {
                prop_assert!(w[1] > w[0] && w[1] - w[0] <= step * (1.0 + 1e-9));
            }
        }
    }
}
