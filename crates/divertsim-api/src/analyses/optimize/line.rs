//! The sorter line as the optimiser's objective (issue 25, item 8): the machine settings
//! (v, t_c, R_s, S_d) that maximise the parcels per hour a line correctly diverts, as the
//! `line` analysis measures them over a stream of parcels, subject to the missort rate and the
//! overload rate staying within their limits.
//!
//! **Common random numbers.** Every evaluation runs the same parcels: parcel i depends on
//! (seed, i) only, and its gap is in metres, so a setting changes what happens to the parcels,
//! never which parcels come. The difference between two settings is then the settings' own,
//! not the luck of two draws, and the search sees an objective that changes only where a
//! parcel's fate does (steps of one parcel in N) and smoothly with v (the stream's time).
//! The best point is the scenario `optimum.toml`; `divertsim line` on it with the same
//! parcels and seed gives the same figures.
//!
//! - objective f = −throughput/1000 (thousands of parcels per hour, minimised);
//! - constraints: missort rate − limit, overload rate − limit (rates of the N parcels), and
//!   the barrier order S_d − R_s \[m], as in the paper's problem.
//!
//! The problem itself is the core's ([`LineProblem`], `analysis/line/objective.rs`): the
//! variables set the first machine, every diverter that does not give its own value takes
//! them, all in SI. This module binds it to a scenario ([`LineSearch`]), writes
//! optimum.toml (the scenario at the best point, the one file it makes) and the reports.
//! References: docs/model.md §12 (the line), docs/validation.md, "The sorter line (issue 25)".

use super::tables::{num, VARIABLE_COLUMNS};
use super::{Method, RunOutcome};
use crate::analyses::cells::pct;
use crate::analyses::line::line_of;
use crate::analyses::population::{finite_or_null, proportion_json};
use crate::config::{Loaded, Problem, ScenarioBuilder};
use crate::contract::Error;
use crate::output::csv_bytes;
use divertsim_core::analysis::line::objective::{LineFault, LineMeasure, LineProblem};
use divertsim_core::analysis::population::reliability::CONFIDENCE;
use divertsim_core::model::trigger::Trigger;
use divertsim_core::optimize::{Bounds, Evaluation, IterationSummary, Problem as Solvable, Record};
use divertsim_core::run::study::StudyError;
use divertsim_core::run::sweep::no_progress;
use serde_json::{json, Value};

pub use divertsim_core::analysis::line::objective::CONSTRAINTS;

/// Parcels per evaluation by default: a missort limit of 0.1 % is two parcels in 2,000.
pub const LINE_PARCELS: u64 = 2_000;
/// The default limit on the missort rate (parcels not where they were bound).
pub const MAX_MISSORT: f64 = 0.001;
/// The default limit on the overload rate (parcels struck harder than the free fall).
pub const MAX_OVERLOAD: f64 = 0.01;
/// Parcels per segment: `divertsim line`'s default, so that its figures on optimum.toml
/// equal the optimiser's.
pub const SEGMENT: u64 = 1_000;
/// The methods that search the line: its objective moves in steps of one parcel, which a
/// finite-difference gradient does not see, and NSGA-II's trade-off is the design set's.
pub const LINE_METHODS: [Method; 3] = [Method::De, Method::Ga, Method::Cmaes];
/// The scenario keys the variables set, in the order of the variables.
const KEYS: [&str; 4] = [
    "machine.belt_speed",
    "machine.cycle_time",
    "machine.start_position",
    "machine.light_barrier",
];

/// What the line objective measures and bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineObjective {
    /// N: parcels of every evaluation.
    pub parcels: u64,
    /// The stream's seed (`None`: the scenario's mix.seed, else 1).
    pub seed: Option<u64>,
    /// Largest missort rate allowed.
    pub max_missort: f64,
    /// Largest overload rate allowed.
    pub max_overload: f64,
}

/// The line problem of a scenario: the core's [`LineProblem`] on its line, every evaluation
/// in SI; the scenario kept for its file at the best point (optimum.toml).
#[derive(Clone)]
pub struct LineSearch {
    /// The scenario as given.
    loaded: Loaded,
    /// The problem in SI.
    pub problem: LineProblem,
    pub objective: LineObjective,
}

impl std::fmt::Debug for LineSearch {
    /// Everything that shapes an evaluation (the memo's key of the problem).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LineProblem")
            .field("file", &self.loaded.file)
            .field("bounds", &self.problem.bounds)
            .field("objective", &self.objective)
            .field("seed", &self.problem.seed)
            .field("segment", &SEGMENT)
            .finish()
    }
}

/// A point of the search explained: its setting, evaluation and measure.
#[derive(Debug, Clone)]
pub struct LinePointReport {
    /// v, t_c, R_s, S_d.
    pub x: Vec<f64>,
    pub evaluation: Evaluation,
    pub measure: LineMeasure,
}

/// A finished optimisation of the line.
#[derive(Debug, Clone)]
pub struct LineOptimum {
    pub problem: LineSearch,
    pub run: RunOutcome,
    /// The best point found.
    pub best: LinePointReport,
    /// The scenario's own setting, measured on the same parcels.
    pub given: LinePointReport,
    /// optimum.toml: the scenario at the best point, standing alone.
    pub optimum_toml: String,
}

/// A measure's fault as the contract's error (a stop is [`Error::Cancelled`]).
fn fault_error(e: LineFault) -> Error {
    match e {
        LineFault::Run(StudyError::Stopped) => Error::Cancelled,
        e => Error::Failed(e.to_string()),
    }
}

impl LineSearch {
    /// The problem on `loaded` (its `[line]` checked) over `bounds`.
    pub fn new(
        loaded: &Loaded,
        bounds: Bounds,
        objective: LineObjective,
    ) -> Result<LineSearch, Vec<Problem>> {
        let (_, line) = line_of(loaded)?;
        let adaptive = line
            .diverters
            .iter()
            .any(|d| matches!(d.setting.machine.trigger, Trigger::Adaptive(_)));
        if adaptive && !bounds.is_fixed(2) {
            return Err(vec![Problem::new(
                "bounds",
                "start_position (R_s) is free, but with machine.trigger = \"adaptive\" the trigger table sets R_s for each parcel; allowed: fix it (fix R_s=VALUE) or use trigger = \"fixed\"",
            )]);
        }
        let seed = objective.seed.unwrap_or_else(|| loaded.file.mix.seed());
        Ok(LineSearch {
            problem: LineProblem {
                line,
                bounds,
                parcels: objective.parcels,
                seed,
                segment: SEGMENT,
                max_missort: objective.max_missort,
                max_overload: objective.max_overload,
            },
            loaded: loaded.clone(),
            objective,
        })
    }

    /// The stream's seed, resolved (the objective's, else the scenario's mix.seed).
    pub fn seed(&self) -> u64 {
        self.problem.seed
    }

    /// The scenario's own setting: its first diverter's v, t_c, R_s, S_d.
    pub fn given_x(&self) -> Vec<f64> {
        self.problem.given_x()
    }

    /// The scenario file at `x` (optimum.toml's): the file with the first machine's values
    /// set, S_d no further downstream than R_s.
    pub fn scenario_at(&self, x: &[f64]) -> Result<Loaded, Vec<Problem>> {
        let values = [x[0], x[1], x[2], x[3].min(x[2])];
        let pairs: Vec<(String, toml::Value)> = KEYS
            .iter()
            .zip(values)
            .map(|(k, v)| (k.to_string(), toml::Value::Float(v)))
            .collect();
        ScenarioBuilder::resolved(&self.loaded)
            .values(&pairs)
            .load()
            .map_err(|p| p.0)
    }

    /// The line at `x`, its N parcels run (its adaptive triggers built first).
    pub fn measure(&self, x: &[f64]) -> Result<LineMeasure, Error> {
        self.problem.measure(x, &no_progress).map_err(fault_error)
    }

    /// `x` measured and explained (one more line run, not counted).
    pub fn report(&self, x: &[f64]) -> Result<LinePointReport, Error> {
        let measure = self.measure(x)?;
        Ok(LinePointReport {
            x: x.to_vec(),
            evaluation: self.problem.evaluation_of(x, &measure.tally),
            measure,
        })
    }

    /// The scenario file at the best point, standing alone, with the figures it gives.
    pub fn optimum_toml(&self, best: &LinePointReport) -> Result<String, Error> {
        let loaded = self.scenario_at(&best.x).map_err(Error::Invalid)?;
        let t = &best.measure.tally;
        let verdict = match best.evaluation.feasible() {
            true => "feasible".to_string(),
            false => format!(
                "INFEASIBLE, constraint violation {:.4}",
                best.evaluation.violation()
            ),
        };
        crate::config::to_toml(
            &loaded.file,
            &format!(
                "Written by `divertsim optimize --objective line`: the best point found ({verdict}),\nv = {} m/s, t_c = {} s, R_s = {} m, S_d = {} m:\n{:.0} parcels/h correctly diverted, missort rate {:.3} %, overload rate {:.3} % over {} parcels.\n`divertsim line` runs this file; with --parcels {} --seed {} it gives these figures.",
                best.x[0],
                best.x[1],
                best.x[2],
                best.x[3],
                t.line_throughput(),
                100.0 * t.missort_rate(CONFIDENCE).estimate,
                100.0 * t.overload_rate(CONFIDENCE).estimate,
                t.parcels,
                t.parcels,
                self.seed()
            ),
        )
    }
}

impl Solvable for LineSearch {
    fn bounds(&self) -> &Bounds {
        self.problem.bounds()
    }
    fn constraint_count(&self) -> usize {
        self.problem.constraint_count()
    }
    /// A setting the line cannot run, or a run that fails, is never feasible (NaN values).
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        self.problem.evaluate(x)
    }
}

/// The line problem whose evaluations stop at a segment: `stop_point` is called after each
/// (a segment is the natural piece of a line run; an evaluation can hold many). The same
/// problem otherwise, and the same memo key.
struct Stoppable<'a> {
    inner: &'a LineSearch,
    stop_point: &'a (dyn Fn() + Sync),
}

impl std::fmt::Debug for Stoppable<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.inner.fmt(f)
    }
}

impl Solvable for Stoppable<'_> {
    fn bounds(&self) -> &Bounds {
        self.inner.bounds()
    }
    fn constraint_count(&self) -> usize {
        self.inner.constraint_count()
    }
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        self.inner.problem.evaluate_stoppable(x, self.stop_point)
    }
}

/// Run one method on the line problem; `stop_point` is called after each segment of each
/// evaluation.
pub fn run_line(
    problem: &LineSearch,
    settings: &super::MethodSettings,
    ctx: &super::RunContext<'_>,
    stream: Option<Box<dyn divertsim_core::optimize::Observer + '_>>,
    stop_point: &(dyn Fn() + Sync),
) -> Result<LineOptimum, Error> {
    let stoppable = Stoppable {
        inner: problem,
        stop_point,
    };
    let run = super::solve(&stoppable, settings, ctx.progress, ctx.memo, stream)
        .map_err(Error::failed)?;
    let best = problem.report(&run.result.best_x)?;
    let given = problem.report(&problem.given_x())?;
    Ok(LineOptimum {
        optimum_toml: problem.optimum_toml(&best)?,
        problem: problem.clone(),
        run,
        best,
        given,
    })
}

/// A rate of N parcels from its constraint value g = rate − limit: exactly k/N again.
fn rate_of(g: f64, limit: f64, parcels: u64) -> f64 {
    ((g + limit) * parcels as f64).round() / parcels as f64
}

/// The columns of the line's evaluations.csv (also the live stream's header).
pub fn evaluation_header() -> Vec<String> {
    let mut h: Vec<String> = ["index", "iteration"].map(String::from).to_vec();
    h.extend(VARIABLE_COLUMNS.map(String::from));
    h.extend(
        ["throughput_per_h", "missort_rate", "overload_rate"]
            .map(String::from)
            .to_vec(),
    );
    h.extend(CONSTRAINTS.map(|c| format!("g:{c}")));
    h.extend(["violation", "feasible"].map(String::from));
    h
}

/// One row of the line's evaluations.csv.
pub fn evaluation_row(o: &LineObjective, r: &Record) -> Vec<String> {
    let e = &r.evaluation;
    let g = |i: usize| e.constraints.get(i).copied().unwrap_or(f64::NAN);
    let mut row = vec![r.index.to_string(), r.iteration.to_string()];
    row.extend(r.x.iter().map(|&v| num(v)));
    row.push(num(
        -1000.0 * e.objectives.first().copied().unwrap_or(f64::NAN)
    ));
    row.push(num(rate_of(g(0), o.max_missort, o.parcels)));
    row.push(num(rate_of(g(1), o.max_overload, o.parcels)));
    row.extend(e.constraints.iter().map(|&g| num(g)));
    row.push(num(e.violation()));
    row.push(e.feasible().to_string());
    row
}

/// evaluations.csv of a line optimisation.
pub fn evaluations_csv(o: &LineObjective, log: &[Record]) -> Result<Vec<u8>, csv::Error> {
    let header = evaluation_header();
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    let rows: Vec<Vec<String>> = log.iter().map(|r| evaluation_row(o, r)).collect();
    csv_bytes(&header, &rows)
}

/// history.csv of a line optimisation: the best point so far, each generation, with its
/// throughput.
pub fn history_csv(history: &[IterationSummary]) -> Result<Vec<u8>, csv::Error> {
    super::tables::history_csv_of(history, "best_throughput_per_h", &|h| {
        -1000.0 * h.best_objective
    })
}

fn point_json(p: &LinePointReport) -> Value {
    let t = &p.measure.tally;
    let names = [
        "belt_speed",
        "cycle_time",
        "start_position",
        "light_barrier",
    ];
    let x: serde_json::Map<String, Value> = names
        .iter()
        .zip(&p.x)
        .map(|(n, v)| (n.to_string(), json!(v)))
        .collect();
    json!({
        "x": x,
        "feasible": p.evaluation.feasible(),
        "violation": finite_or_null(p.evaluation.violation()),
        "constraints": CONSTRAINTS.iter().zip(&p.evaluation.constraints)
            .map(|(n, g)| (n.to_string(), finite_or_null(*g)))
            .collect::<serde_json::Map<String, Value>>(),
        "throughput_per_h": finite_or_null(t.line_throughput()),
        "arrival_rate_per_h": finite_or_null(t.arrival_rate()),
        "missort_rate": proportion_json(&t.missort_rate(CONFIDENCE)),
        "overload_rate": proportion_json(&t.overload_rate(CONFIDENCE)),
        "arm_busy": proportion_json(&t.rate("arm_busy", CONFIDENCE)),
        "diverters_throughput_per_h": (0..t.diverters.len())
            .map(|d| finite_or_null(t.throughput(d)))
            .collect::<Vec<_>>(),
    })
}

/// summary.json of a line optimisation.
pub fn report_json(r: &LineOptimum) -> Value {
    let o = &r.problem.objective;
    json!({
        "objective": "line",
        "method": r.run.method.name(),
        "parcels": o.parcels,
        "seed": r.problem.seed(),
        "max_missort": o.max_missort,
        "max_overload": o.max_overload,
        "confidence": CONFIDENCE,
        "evaluations": r.run.log.len(),
        "best": point_json(&r.best),
        "given": point_json(&r.given),
    })
}

/// One point in words: the setting, throughput and the rates against their limits.
fn point_text(p: &LinePointReport, o: &LineObjective) -> String {
    let t = &p.measure.tally;
    let within = |rate: f64, limit: f64| match rate <= limit {
        true => format!("within the limit {}", pct(limit, 2)),
        false => format!("EXCEEDS the limit {}", pct(limit, 2)),
    };
    let m = t.missort_rate(CONFIDENCE);
    let ov = t.overload_rate(CONFIDENCE);
    let mut s = format!(
        "  belt speed v = {:.4} m/s, cycle time t_c = {:.4} s, arm start R_s = {:.4} m, light barrier S_d = {:.4} m\n",
        p.x[0], p.x[1], p.x[2], p.x[3]
    );
    s += &format!(
        "  throughput {:.0} parcels/h correctly diverted, of {:.0}/h arriving\n",
        t.line_throughput(),
        t.arrival_rate()
    );
    for (what, r, limit) in [
        ("missorted", m, o.max_missort),
        ("struck harder than the 0.3 m drop", ov, o.max_overload),
    ] {
        s += &format!(
            "  {what} {} (95 % interval {} to {}), {}\n",
            pct(r.estimate, 2),
            pct(r.lower, 2),
            pct(r.upper, 2),
            within(r.estimate, limit)
        );
    }
    if p.x[3] > p.x[2] {
        s += "  the light barrier lies downstream of the arm start: INFEASIBLE\n";
    }
    s
}

/// The readable report.
pub fn report_text(r: &LineOptimum) -> String {
    let o = &r.problem.objective;
    let mut s = format!(
        "optimize --objective line ({}): {} evaluations of the line, each on the same {} parcels (seed {})\n\n",
        r.run.method.name(),
        r.run.log.len(),
        o.parcels,
        r.problem.seed()
    );
    s += &format!(
        "best point ({}):\n",
        match r.best.evaluation.feasible() {
            true => "feasible",
            false => "INFEASIBLE: no point tried met every limit",
        }
    );
    s += &point_text(&r.best, o);
    s += "\nthe scenario as given, on the same parcels:\n";
    s += &point_text(&r.given, o);
    let (best, given) = (
        r.best.measure.tally.line_throughput(),
        r.given.measure.tally.line_throughput(),
    );
    s += &match (r.given.evaluation.feasible(), r.best.evaluation.feasible()) {
        (true, _) => format!(
            "\nthe best point diverts {:+.0} parcels/h against the scenario as given.\n",
            best - given
        ),
        (false, true) => format!(
            "\nthe scenario as given misses the limits; the best point meets them at {best:.0} parcels/h ({:+.0}/h).\n",
            best - given
        ),
        (false, false) => "\nno point tried meets every limit: loosen max_missort or max_overload, widen the bounds, or lengthen the gap.\n".into(),
    };
    s += &format!(
        "optimum.toml is the scenario at the best point; `divertsim line optimum.toml --parcels {} --seed {}` gives its figures, and more parcels narrow its intervals.\n",
        o.parcels, r.problem.seed()
    );
    s
}
