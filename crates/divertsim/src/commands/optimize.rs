//! `divertsim optimize`: the machine-settings optimisation of issue 5 (paper §4.3) — maximise
//! the sorting capacity W over (v, t_c, R_s, S_d) subject to every `[design]` parcel being
//! diverted and the worst-case impulse staying below the free fall, with the paper's GA and
//! penalised steepest descent, differential evolution and CMA-ES (each with a COBYLA polish)
//! and NSGA-II for the trade-off capacity / overload / divert reserve.
//!
//! The problem is `divertsim_core::analysis::settings_problem`; the solvers are
//! `divertsim_core::optimize`. Three modes:
//! - one run (`--method`): evaluations.csv (every candidate), history.csv + history.svg (best
//!   capacity and variables against generation, paper Figs 10/11 style), for NSGA-II
//!   front.csv + front.svg, report.json, and a final report on stdout;
//! - `--paper-experiment`: the paper's three GA and three gradient runs (fig10_ga.svg,
//!   fig11_gradient.svg, paper_experiment.csv/.json, each run's history and evaluations);
//! - `--compare`: every method over `--seeds` seeds on the same problem (comparison.csv/.json
//!   and a table with medians).
//!
//! Every run is deterministic for its seed and independent of `--threads` (the solvers
//! evaluate batches in parallel and record them in order). A single run's files carry no
//! timing (its wall time is printed on stdout only); the paper experiment and the comparison
//! report wall times as measurements, in their own columns.

use divertsim_figures::charts::fit;
use std::path::Path;
use std::time::Instant;

use crate::checkpoint::Journal;
use divertsim_core::analysis::design::{
    capacity, DesignEvaluation, DesignSet, Margins, WorstDefinition,
};
use divertsim_core::analysis::memo::{self, cached, Memo, NoMemo};
use divertsim_core::analysis::robust::{robust_optimize, RobustOptimum, RobustSettings};
use divertsim_core::analysis::settings_problem::{
    point_of, Objectives, SettingsProblem, VARIABLES,
};
use divertsim_core::optimize::cmaes::{self, CmaesSettings};
use divertsim_core::optimize::cobyla::PolishSettings;
use divertsim_core::optimize::de::{self, DeSettings};
use divertsim_core::optimize::ga::{self, GaSettings};
use divertsim_core::optimize::gradient::{self, GradientSettings};
use divertsim_core::optimize::nsga2::{self, FrontPoint, Nsga2Settings};
use divertsim_core::optimize::{
    Bounds, Evaluation, IterationSummary, Observer, OptimizeError, Problem, Record, RecordLog,
    SolverResult,
};
use divertsim_core::sim::Outcome;
use plotters::prelude::*;
use serde_json::{json, Value};

use super::common::{self, OutputArgs, ScenarioArgs};
use super::worst_case::{pose_json, pose_text, RobustArgs, WorstArg};
use divertsim_api::config::{Loaded, Problem as CliProblem};
use divertsim_figures::charts::PALETTE;
use divertsim_figures::plot::{draw_err, ensure_font, format_of, Format, PlotError, FONT};

/// Optimisation method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// The paper's real-coded genetic algorithm (default 100 × 80).
    Ga,
    /// The paper's steepest descent with a growing exterior penalty.
    Gradient,
    /// Feasibility-first differential evolution (jDE) + COBYLA polish.
    De,
    /// CMA-ES with Deb-rule ranking + COBYLA polish.
    Cmaes,
    /// NSGA-II: capacity against overload ratio against divert reserve.
    Nsga2,
}

impl Method {
    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Ga => "ga",
            Method::Gradient => "gradient",
            Method::De => "de",
            Method::Cmaes => "cmaes",
            Method::Nsga2 => "nsga2",
        }
    }
}

/// Optimise the machine settings (v, t_c, R_s, S_d) for capacity.
#[derive(Debug, Clone, clap::Args)]
pub struct OptimizeArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub output: OutputArgs,
    #[command(flatten)]
    pub resume: common::ResumeArgs,
    /// Optimisation method (default de).
    #[arg(long, value_enum)]
    pub method: Option<Method>,
    /// Search range of a variable, NAME=LO:HI with NAME one of belt_speed|v, cycle_time|t_c,
    /// start_position|R_s, light_barrier|S_d. Repeatable. Defaults: v 1.0:2.3 m/s,
    /// t_c 1.0:1.5 s, R_s 0:0.9 m, S_d fixed at the scenario's light_barrier.
    #[arg(long = "bound", value_name = "NAME=LO:HI", allow_hyphen_values = true)]
    pub bounds: Vec<String>,
    /// Fix a variable, NAME=VALUE (same names as --bound). Repeatable.
    #[arg(long = "fix", value_name = "NAME=VALUE", allow_hyphen_values = true)]
    pub fixes: Vec<String>,
    /// Starting point v,t_c,R_s[,S_d] for gradient and cmaes (default: the centre of the
    /// bounds); S_d defaults to the centre of its range.
    #[arg(long, value_name = "V,T_C,R_S[,S_D]")]
    pub start: Option<String>,
    /// Random seed (ga, de, cmaes, nsga2); the first seed with --compare.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Population size (ga, de, nsga2; λ of cmaes).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(4..=10_000))]
    pub population: Option<u64>,
    /// Generations after the initial one (ga, de, nsga2; cmaes: maximum generations).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=100_000))]
    pub generations: Option<u64>,
    /// Evaluation budget (every method; with --compare and --paper-experiment a cap on
    /// each run).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    pub budget: Option<u64>,
    /// No COBYLA polish after de and cmaes.
    #[arg(long)]
    pub no_polish: bool,
    /// Run the paper's experiment (3 GA runs, 3 gradient runs; bounds as in the paper, S_d
    /// fixed 0). --population/--generations apply to the GA runs, --budget to every run.
    #[arg(long, conflicts_with_all = ["method", "bounds", "fixes", "start", "compare"])]
    pub paper_experiment: bool,
    /// Compare ga, gradient, de, cmaes and nsga2 over --seeds seeds on the same problem
    /// (--population/--generations apply to ga and nsga2, --budget caps every run).
    #[arg(long, conflicts_with_all = ["method", "start"])]
    pub compare: bool,
    /// Number of seeds of --compare (seeds --seed, --seed + 1, ...).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(1..=100))]
    pub seeds: u64,
    #[command(flatten)]
    pub robust: RobustArgs,
}

/// Allowed range of each variable's bounds and values, with its unit.
pub const LIMITS: [(f64, f64, &str); 4] = [
    (0.05, 10.0, "m/s"),
    (0.2, 10.0, "s"),
    (-5.0, 5.0, "m"),
    (-5.0, 5.0, "m"),
];

/// The paper's wide search box for (v, t_c, R_s) (§4.3).
pub const PAPER_WIDE: [(f64, f64); 3] = [(1.0, 2.3), (1.0, 1.5), (0.0, 0.9)];
/// The paper's narrow search box for (v, t_c, R_s).
pub const PAPER_NARROW: [(f64, f64); 3] = [(1.5, 2.3), (1.0, 1.5), (0.0, 0.5)];
/// The paper's gradient starting points (v, t_c, R_s).
pub const PAPER_STARTS: [[f64; 3]; 3] = [[1.8, 1.5, 0.5], [2.1, 1.2, 0.1], [1.9, 1.1, 0.0]];

/// Tolerance under which a constraint counts as active: |g| ≤ this [m for divert and barrier,
/// ratio for overload].
pub const ACTIVE_TOLERANCE: f64 = 1e-3;

/// Short symbols of the variables for tables and plots.
pub const SYMBOLS: [&str; 4] = ["v", "t_c", "R_s", "S_d"];
const UNITS: [&str; 4] = ["m/s", "s", "m", "m"];

/// Index of a variable by its name or symbol (case-sensitive symbols as in the paper).
pub fn variable_index(name: &str) -> Option<usize> {
    match name.trim() {
        "belt_speed" | "v" => Some(0),
        "cycle_time" | "t_c" => Some(1),
        "start_position" | "R_s" => Some(2),
        "light_barrier" | "S_d" => Some(3),
        _ => None,
    }
}

fn problem(key: &str, message: String) -> CliProblem {
    CliProblem {
        key: key.into(),
        message,
    }
}

fn names_help() -> &'static str {
    "NAME one of belt_speed|v, cycle_time|t_c, start_position|R_s, light_barrier|S_d"
}

fn range_help(i: usize) -> String {
    let (lo, hi, unit) = LIMITS[i];
    format!("{} in [{lo}, {hi}] {unit}", VARIABLES[i])
}

/// The search box from the defaults, `--bound` and `--fix` (`light_barrier` is the scenario's
/// S_d, the default fixed value), or every problem with them.
pub fn parse_bounds(
    bounds: &[String],
    fixes: &[String],
    light_barrier: f64,
) -> Result<Bounds, Vec<CliProblem>> {
    let mut lower = vec![1.0, 1.0, 0.0, light_barrier];
    let mut upper = vec![2.3, 1.5, 0.9, light_barrier];
    let mut problems = Vec::new();
    let inside = |i: usize, x: f64| x.is_finite() && x >= LIMITS[i].0 && x <= LIMITS[i].1;
    for b in bounds {
        let bad = |why: &str| {
            problem(
                "--bound",
                format!(
                    "'{b}': {why}; allowed: NAME=LO:HI with {}, LO ≤ HI and v, t_c in \
                     [0.05 or 0.2, 10], R_s, S_d in [-5, 5] m",
                    names_help()
                ),
            )
        };
        let Some((name, range)) = b.split_once('=') else {
            problems.push(bad("expected NAME=LO:HI"));
            continue;
        };
        let Some(i) = variable_index(name) else {
            problems.push(bad(&format!("unknown variable '{name}'")));
            continue;
        };
        let parts: Vec<f64> = range
            .split(':')
            .map(|s| s.trim().parse::<f64>().unwrap_or(f64::NAN))
            .collect();
        match parts[..] {
            [lo, hi] if inside(i, lo) && inside(i, hi) && lo <= hi => {
                lower[i] = lo;
                upper[i] = hi;
            }
            _ => problems.push(problem(
                "--bound",
                format!(
                    "'{b}': allowed: {name}=LO:HI with LO ≤ HI, {}",
                    range_help(i)
                ),
            )),
        }
    }
    for f in fixes {
        let parsed = f.split_once('=').and_then(|(name, value)| {
            let i = variable_index(name)?;
            Some((i, value.trim().parse::<f64>().unwrap_or(f64::NAN)))
        });
        match parsed {
            Some((i, x)) if inside(i, x) => {
                lower[i] = x;
                upper[i] = x;
            }
            Some((i, _)) => problems.push(problem(
                "--fix",
                format!("'{f}': allowed: {}", range_help(i)),
            )),
            None => problems.push(problem(
                "--fix",
                format!("'{f}': expected NAME=VALUE with {}", names_help()),
            )),
        }
    }
    if !problems.is_empty() {
        return Err(problems);
    }
    Bounds::new(lower, upper).map_err(|e| vec![problem("--bound", e.to_string())])
}

/// `--start v,t_c,R_s[,S_d]` inside `bounds` (S_d defaults to the centre of its range; a fixed
/// variable takes its fixed value).
pub fn parse_start(text: &str, bounds: &Bounds) -> Result<Vec<f64>, CliProblem> {
    let values: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>().unwrap_or(f64::NAN))
        .collect();
    let bad = |why: String| {
        let ranges: Vec<String> = (0..4)
            .map(|i| {
                format!(
                    "{} in [{}, {}] {}",
                    SYMBOLS[i], bounds.lower[i], bounds.upper[i], UNITS[i]
                )
            })
            .collect();
        problem(
            "--start",
            format!(
                "'{text}': {why}; allowed: v,t_c,R_s[,S_d] inside the bounds: {}",
                ranges.join(", ")
            ),
        )
    };
    if !(3..=4).contains(&values.len()) {
        return Err(bad(format!("{} values", values.len())));
    }
    let mut x = bounds.centre();
    for (i, &v) in values.iter().enumerate() {
        if bounds.is_fixed(i) {
            continue;
        }
        if !(v.is_finite() && v >= bounds.lower[i] && v <= bounds.upper[i]) {
            return Err(bad(format!("{} = {v} is outside its bounds", SYMBOLS[i])));
        }
        x[i] = v;
    }
    Ok(x)
}

/// Options of one run as given on the command line (`None`: the method's default).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunOptions {
    pub population: Option<usize>,
    pub generations: Option<usize>,
    pub budget: Option<usize>,
    pub polish: bool,
    pub seed: u64,
    pub start: Option<Vec<f64>>,
}

/// Settings of one solver run.
#[derive(Debug, Clone, PartialEq)]
pub enum MethodSettings {
    Ga(GaSettings),
    Gradient(GradientSettings),
    De(DeSettings),
    Cmaes(CmaesSettings),
    Nsga2(Nsga2Settings),
}

/// Defaults of the better methods, tuned on the paper preset (see docs/validation.md,
/// "Optimisation (issue 5)"): DE population and generations.
pub const DE_POPULATION: usize = 12;
/// DE generations after the initial one.
pub const DE_GENERATIONS: usize = 12;
/// CMA-ES maximum generations.
pub const CMAES_GENERATIONS: usize = 60;
/// CMA-ES stop on the step size (fraction of the ranges).
pub const CMAES_TOL_X: f64 = 1e-3;
/// COBYLA polish after DE and CMA-ES.
pub const POLISH: PolishSettings = PolishSettings {
    rho_begin: 0.02,
    xtol: 1e-4,
    max_evaluations: 120,
    constraint_margin: 1e-8,
};
/// Evaluation budget of the gradient method.
pub const GRADIENT_BUDGET: usize = 3000;
/// NSGA-II population and generations.
pub const NSGA2_POPULATION: usize = 60;
/// NSGA-II generations after the initial one.
pub const NSGA2_GENERATIONS: usize = 40;

/// The settings of `method` with the command-line options applied.
pub fn method_settings(method: Method, o: &RunOptions) -> MethodSettings {
    let polish = o.polish.then_some(POLISH);
    match method {
        Method::Ga => {
            let d = GaSettings::default();
            MethodSettings::Ga(GaSettings {
                population: o.population.unwrap_or(d.population),
                generations: o.generations.unwrap_or(d.generations),
                max_evaluations: o.budget,
                seed: o.seed,
                ..d
            })
        }
        Method::Gradient => MethodSettings::Gradient(GradientSettings {
            start: o.start.clone(),
            fd_step: 1e-4,
            max_evaluations: o.budget.unwrap_or(GRADIENT_BUDGET),
            ..GradientSettings::default()
        }),
        Method::De => MethodSettings::De(DeSettings {
            population: o.population.unwrap_or(DE_POPULATION),
            generations: o.generations.unwrap_or(DE_GENERATIONS),
            polish,
            max_evaluations: o.budget,
            seed: o.seed,
            ..DeSettings::default()
        }),
        Method::Cmaes => MethodSettings::Cmaes(CmaesSettings {
            start: o.start.clone(),
            population: o.population,
            max_generations: o.generations.unwrap_or(CMAES_GENERATIONS),
            tol_x: CMAES_TOL_X,
            polish,
            max_evaluations: o.budget,
            seed: o.seed,
            ..CmaesSettings::default()
        }),
        Method::Nsga2 => MethodSettings::Nsga2(Nsga2Settings {
            population: o.population.unwrap_or(NSGA2_POPULATION),
            generations: o.generations.unwrap_or(NSGA2_GENERATIONS),
            max_evaluations: o.budget,
            seed: o.seed,
            ..Nsga2Settings::default()
        }),
    }
}

/// The most evaluations a run may make (the progress bar's length).
pub fn planned_evaluations(settings: &MethodSettings, free: usize) -> usize {
    let polish = |p: &Option<PolishSettings>| p.as_ref().map_or(0, |p| p.max_evaluations);
    let plan = match settings {
        MethodSettings::Ga(s) => s.population * (s.generations + 1),
        MethodSettings::Gradient(s) => s.max_evaluations,
        MethodSettings::De(s) => s.population * (s.generations + 1) + polish(&s.polish),
        MethodSettings::Cmaes(s) => {
            let lambda = s
                .population
                .unwrap_or(4 + (3.0 * (free.max(1) as f64).ln()).floor() as usize);
            lambda * s.max_generations + polish(&s.polish)
        }
        MethodSettings::Nsga2(s) => s.population.div_ceil(2) * 2 * (s.generations + 1),
    };
    let cap = match settings {
        MethodSettings::Ga(s) => s.max_evaluations,
        MethodSettings::Gradient(_) => None,
        MethodSettings::De(s) => s.max_evaluations,
        MethodSettings::Cmaes(s) => s.max_evaluations,
        MethodSettings::Nsga2(s) => s.max_evaluations,
    };
    cap.map_or(plan, |c| c.min(plan).max(1))
}

/// What the runs of one command report to and keep their work in: the progress tick, the
/// checkpoint's memo (finished evaluations recalled on `--resume`), and the directory each
/// run streams its evaluations to as they happen (`evaluations-N.csv`, N counting the runs).
pub struct RunContext<'a> {
    pub progress: &'a (dyn Fn() + Sync),
    pub memo: &'a dyn Memo,
    pub stream_dir: Option<&'a Path>,
    runs: std::sync::atomic::AtomicUsize,
}

impl<'a> RunContext<'a> {
    /// Progress only: nothing kept, nothing streamed.
    pub fn new(progress: &'a (dyn Fn() + Sync)) -> Self {
        RunContext {
            progress,
            memo: &NoMemo,
            stream_dir: None,
            runs: Default::default(),
        }
    }

    /// Progress, with the evaluations kept in and streamed beside a checkpoint.
    pub fn kept(progress: &'a (dyn Fn() + Sync), journal: &'a Option<Journal>) -> Self {
        RunContext {
            progress,
            memo: common::memo_of(journal),
            stream_dir: journal.as_ref().map(Journal::dir),
            runs: Default::default(),
        }
    }

    /// The next run's evaluation stream (a new file; none without a directory or if it
    /// cannot be made: the stream is a convenience, the results do not depend on it).
    fn next_stream(&self, problem: &SettingsProblem) -> Option<csv::Writer<std::fs::File>> {
        let n = self.runs.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = self.stream_dir?;
        let mut w = csv::Writer::from_path(dir.join(format!("evaluations-{n}.csv"))).ok()?;
        w.write_record(evaluation_header(problem)).ok()?;
        w.flush().ok()?;
        Some(w)
    }
}

/// The evaluation log of a run, each record also written to its stream as it arrives.
struct StreamedLog {
    log: RecordLog,
    stream: Option<csv::Writer<std::fs::File>>,
    trade_off: bool,
}

impl Observer for StreamedLog {
    fn record(&mut self, r: &Record) {
        self.log.record(r);
        if let Some(w) = &mut self.stream {
            let row = evaluation_row(self.trade_off, r);
            if w.write_record(&row).and_then(|_| Ok(w.flush()?)).is_err() {
                self.stream = None;
            }
        }
    }
}

/// A problem that calls `tick` after each evaluation (the progress bar) and keeps every
/// evaluation in the memo (recalled bit for bit on a resume).
struct Ticking<'a> {
    inner: &'a SettingsProblem,
    tick: &'a (dyn Fn() + Sync),
    memo: &'a dyn Memo,
    /// The key of the problem (its scenario, design set, bounds and objectives).
    id: u64,
}

impl Problem for Ticking<'_> {
    fn bounds(&self) -> &Bounds {
        self.inner.bounds()
    }
    fn objective_count(&self) -> usize {
        self.inner.objective_count()
    }
    fn constraint_count(&self) -> usize {
        self.inner.constraint_count()
    }
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        let key = memo::key("optimize evaluation", &(self.id, x));
        let (e, _) = cached(self.memo, key, || self.inner.evaluate(x));
        (self.tick)();
        e
    }
}

/// The problem a method works on: capacity only, or the trade-off for NSGA-II.
pub fn settings_problem(
    loaded: &Loaded,
    bounds: &Bounds,
    method: Method,
) -> Result<SettingsProblem, OptimizeError> {
    let objectives = if method == Method::Nsga2 {
        Objectives::TradeOff
    } else {
        Objectives::Capacity
    };
    SettingsProblem::new(
        loaded.scenario.clone(),
        loaded.design.clone(),
        bounds.clone(),
        objectives,
    )
}

/// One finished run.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    pub method: Method,
    pub settings: MethodSettings,
    pub result: SolverResult,
    /// NSGA-II's feasible front (sorted by capacity, best first).
    pub front: Option<Vec<FrontPoint>>,
    /// Every evaluation, in order.
    pub log: Vec<Record>,
    /// Wall time [s].
    pub wall_time: f64,
}

/// Run one method on `problem` (built by [`settings_problem`] for that method).
pub fn run_method(
    problem: &SettingsProblem,
    settings: &MethodSettings,
    ctx: &RunContext<'_>,
) -> Result<RunOutcome, OptimizeError> {
    let started = Instant::now();
    let p = Ticking {
        inner: problem,
        tick: ctx.progress,
        memo: ctx.memo,
        id: memo::key("optimize problem", problem),
    };
    let mut log = StreamedLog {
        log: RecordLog::default(),
        stream: ctx.next_stream(problem),
        trade_off: problem.objectives() == Objectives::TradeOff,
    };
    let (method, result, front) = match settings {
        MethodSettings::Ga(s) => (Method::Ga, ga::solve(&p, s, &mut log)?, None),
        MethodSettings::Gradient(s) => (Method::Gradient, gradient::solve(&p, s, &mut log)?, None),
        MethodSettings::De(s) => (Method::De, de::solve(&p, s, &mut log)?, None),
        MethodSettings::Cmaes(s) => (Method::Cmaes, cmaes::solve(&p, s, &mut log)?, None),
        MethodSettings::Nsga2(s) => {
            let r = nsga2::solve(&p, s, &mut log)?;
            (Method::Nsga2, r.result, Some(r.front))
        }
    };
    Ok(RunOutcome {
        method,
        settings: settings.clone(),
        result,
        front,
        log: log.log.0,
        wall_time: started.elapsed().as_secs_f64(),
    })
}

/// W of a decision vector [parcels/h] (the paper's formula, exactly).
pub fn capacity_of(x: &[f64]) -> f64 {
    capacity(&point_of(x))
}

/// Index of the first feasible evaluation reaching `threshold` capacity.
pub fn first_reaching(log: &[Record], threshold: f64) -> Option<usize> {
    log.iter()
        .find(|r| r.evaluation.feasible() && capacity_of(&r.x) >= threshold)
        .map(|r| r.index)
}

/// The best point of a run, explained.
#[derive(Debug, Clone)]
pub struct BestReport {
    pub x: Vec<f64>,
    pub capacity: f64,
    pub feasible: bool,
    pub violation: f64,
    /// (name, g) of every constraint.
    pub constraints: Vec<(String, f64)>,
    /// Names of the constraints with |g| ≤ [`ACTIVE_TOLERANCE`].
    pub active: Vec<String>,
    /// The design case with the largest divert constraint (least reserve): (name, g).
    pub worst_parcel: Option<(String, f64)>,
    /// The full design evaluation of the best point.
    pub design: DesignEvaluation,
}

/// Explain the best point of `result` (one more design evaluation, not counted).
pub fn best_report(problem: &SettingsProblem, result: &SolverResult) -> BestReport {
    let x = result.best_x.clone();
    let names = problem.constraint_names();
    let constraints: Vec<(String, f64)> = names
        .iter()
        .cloned()
        .zip(result.best.constraints.iter().copied())
        .collect();
    let active = constraints
        .iter()
        .filter(|(_, g)| g.abs() <= ACTIVE_TOLERANCE)
        .map(|(n, _)| n.clone())
        .collect();
    let cases = problem.design_set().cases.len();
    let worst_parcel = problem
        .design_set()
        .cases
        .iter()
        .zip(&result.best.constraints[..cases.min(result.best.constraints.len())])
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(c, g)| (c.name.clone(), *g));
    BestReport {
        capacity: capacity_of(&x),
        feasible: result.best.feasible(),
        violation: result.best.violation(),
        design: problem.design_evaluation(&x),
        x,
        constraints,
        active,
        worst_parcel,
    }
}

/// A number for a CSV cell: empty when it is not finite (no `NaN` for a spreadsheet).
fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        String::new()
    }
}

/// The decision variables as unit-suffixed CSV columns (the order of `VARIABLES`).
const VARIABLE_COLUMNS: [&str; 4] = [
    "belt_speed_m_s",
    "cycle_time_s",
    "start_position_m",
    "light_barrier_m",
];

fn opt_json(v: Option<usize>) -> Value {
    v.map_or(Value::Null, |i| json!(i))
}

fn finite(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

/// evaluations.csv: every candidate with its variables, capacity, (NSGA-II: overload ratio
/// and divert reserve), each constraint by name, the violation and feasibility.
pub fn evaluations_csv(problem: &SettingsProblem, log: &[Record]) -> Result<Vec<u8>, csv::Error> {
    let trade_off = problem.objectives() == Objectives::TradeOff;
    let rows: Vec<Vec<String>> = log.iter().map(|r| evaluation_row(trade_off, r)).collect();
    let header = evaluation_header(problem);
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    divertsim_api::output::csv_bytes(&header, &rows)
}

/// The columns of evaluations.csv.
fn evaluation_header(problem: &SettingsProblem) -> Vec<String> {
    let trade_off = problem.objectives() == Objectives::TradeOff;
    let names = problem.constraint_names();
    let mut header: Vec<String> = ["index", "iteration"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    header.extend(VARIABLE_COLUMNS.iter().map(|s| s.to_string()));
    header.push("capacity_per_h".into());
    if trade_off {
        header.push("overload_ratio".into());
        header.push("divert_overshoot_m".into());
    }
    header.extend(names.iter().map(|n| format!("g:{n}")));
    header.push("violation".into());
    header.push("feasible".into());
    header
}

/// One row of evaluations.csv.
fn evaluation_row(trade_off: bool, r: &Record) -> Vec<String> {
    let mut row = vec![r.index.to_string(), r.iteration.to_string()];
    row.extend(r.x.iter().map(|&v| num(v)));
    row.push(num(capacity_of(&r.x)));
    if trade_off {
        row.push(num(r
            .evaluation
            .objectives
            .get(1)
            .copied()
            .unwrap_or(f64::NAN)));
        row.push(num(-r
            .evaluation
            .objectives
            .get(2)
            .copied()
            .unwrap_or(f64::NAN)));
    }
    row.extend(r.evaluation.constraints.iter().map(|&g| num(g)));
    row.push(num(r.evaluation.violation()));
    row.push(r.evaluation.feasible().to_string());
    row
}

/// history.csv: one row per generation / iteration with the best point so far.
pub fn history_csv(history: &[IterationSummary]) -> Result<Vec<u8>, csv::Error> {
    let rows: Vec<Vec<String>> = history
        .iter()
        .map(|h| {
            let mut row = vec![
                h.iteration.to_string(),
                h.evaluations.to_string(),
                num(capacity_of(&h.best_x)),
                (h.best_violation == 0.0).to_string(),
                num(h.best_violation),
            ];
            row.extend(h.best_x.iter().map(|&v| num(v)));
            row.push(h.feasible_in_iteration.to_string());
            row.push(h.evaluations_in_iteration.to_string());
            row.push(num(h.mean_violation));
            row
        })
        .collect();
    divertsim_api::output::csv_bytes(
        &[
            "iteration",
            "evaluations",
            "best_capacity_per_h",
            "best_feasible",
            "best_violation",
            "belt_speed_m_s",
            "cycle_time_s",
            "start_position_m",
            "light_barrier_m",
            "feasible_in_iteration",
            "evaluations_in_iteration",
            "mean_violation",
        ],
        &rows,
    )
}

/// front.csv: the NSGA-II front, best capacity first.
pub fn front_csv(front: &[FrontPoint]) -> Result<Vec<u8>, csv::Error> {
    let rows: Vec<Vec<String>> = front
        .iter()
        .map(|f| {
            let mut row = vec![
                num(capacity_of(&f.x)),
                num(f.evaluation.objectives[1]),
                num(-f.evaluation.objectives[2]),
            ];
            row.extend(f.x.iter().map(|&v| num(v)));
            row
        })
        .collect();
    divertsim_api::output::csv_bytes(
        &[
            "capacity_per_h",
            "overload_ratio",
            "divert_overshoot_m",
            "belt_speed_m_s",
            "cycle_time_s",
            "start_position_m",
            "light_barrier_m",
        ],
        &rows,
    )
}

fn best_json(b: &BestReport) -> Value {
    let mut point = serde_json::Map::new();
    for (name, v) in VARIABLES.iter().zip(&b.x) {
        point.insert(name.to_string(), json!(v));
    }
    json!({
        "point": point,
        "capacity": b.capacity,
        "feasible": b.feasible,
        "violation": finite(b.violation),
        "constraints": b.constraints.iter().map(|(n, g)| json!({"name": n, "g": g})).collect::<Vec<_>>(),
        "active": b.active,
        "active_tolerance": ACTIVE_TOLERANCE,
        "worst_parcel": b.worst_parcel.as_ref().map(|(n, g)| json!({"name": n, "g": g})),
        "overload_ratio": finite(b.design.overload_ratio),
        "paper_overload_ratio": b.design.overload.as_ref().ok().map(|o| o.ratio),
        "cases": b.design.cases.iter().map(|c| json!({
            "name": c.name,
            "diverted": c.outcome == Outcome::Diverted,
            "outcome": format!("{:?}", c.outcome),
            "max_lateral": c.max_lateral,
            "margin": c.margin,
            "overshoot": c.overshoot,
        })).collect::<Vec<_>>(),
    })
}

fn bounds_json(b: &Bounds) -> Value {
    let mut m = serde_json::Map::new();
    for (i, name) in VARIABLES.iter().enumerate() {
        m.insert(name.to_string(), json!([b.lower[i], b.upper[i]]));
    }
    Value::Object(m)
}

/// report.json of one run (also `--json`).
pub fn report_json(problem: &SettingsProblem, run: &RunOutcome, best: &BestReport) -> Value {
    let r = &run.result;
    json!({
        "method": run.method.name(),
        "settings": format!("{:?}", run.settings),
        "bounds": bounds_json(problem.bounds()),
        "constraint_names": problem.constraint_names(),
        "best": best_json(best),
        "evaluations": r.evaluations,
        "first_feasible": opt_json(r.first_feasible),
        "feasible_count": r.feasible_count,
        "iterations": r.history.len(),
        "front": run.front.as_ref().map(|f| f.iter().map(|p| json!({
            "capacity": capacity_of(&p.x),
            "overload_ratio": p.evaluation.objectives[1],
            "divert_overshoot": -p.evaluation.objectives[2],
            "x": p.x,
        })).collect::<Vec<_>>()),
    })
}

/// The final report on stdout.
pub fn report_text(run: &RunOutcome, best: &BestReport) -> String {
    use std::fmt::Write;
    let r = &run.result;
    let mut s = String::new();
    let _ = writeln!(s, "method: {}", run.method.name());
    let point: Vec<String> = (0..4)
        .map(|i| format!("{} = {:.4} {}", SYMBOLS[i], best.x[i], UNITS[i]))
        .collect();
    let _ = writeln!(
        s,
        "best point: {} ({})",
        point.join(", "),
        if best.feasible {
            "feasible".to_string()
        } else {
            format!("INFEASIBLE, violation {:.4}", best.violation)
        }
    );
    let _ = writeln!(s, "capacity W = {:.1} parcels/h", best.capacity);
    match best.design.worst {
        WorstDefinition::Paper => {
            if let Ok(o) = &best.design.overload {
                let _ = writeln!(
                    s,
                    "overload ratio S/S_fall = {:.4} (the paper's worst case)",
                    o.ratio
                );
            }
        }
        WorstDefinition::Search => {
            let _ = writeln!(
                s,
                "overload ratio S/S_fall = {:.4} (largest over the design parcels and worst poses){}",
                best.design.overload_ratio,
                best.design
                    .overload
                    .as_ref()
                    .map_or(String::new(), |o| format!("; the paper's worst case: {:.4}", o.ratio))
            );
        }
    }
    let _ = writeln!(
        s,
        "active constraints (|g| <= {ACTIVE_TOLERANCE}): {}",
        if best.active.is_empty() {
            "none".to_string()
        } else {
            best.active.join(", ")
        }
    );
    for (n, g) in &best.constraints {
        let _ = writeln!(s, "  g {n:<20} = {g:+.5}");
    }
    if let Some((n, g)) = &best.worst_parcel {
        let _ = writeln!(
            s,
            "worst parcel: {n} (divert constraint {g:+.5} m: {})",
            if *g <= 0.0 {
                format!("diverted with {:.4} m reserve", -g)
            } else {
                format!("left {g:.4} m short of P_max")
            }
        );
    }
    if let Some(front) = &run.front {
        let _ = writeln!(s, "Pareto front: {} points", front.len());
    }
    let _ = writeln!(
        s,
        "evaluations: {}, first feasible: {}, feasible: {}, wall time {:.2} s",
        r.evaluations,
        r.first_feasible
            .map_or("none".to_string(), |i| i.to_string()),
        r.feasible_count,
        run.wall_time
    );
    s
}

/// One run of a history figure.
pub struct HistoryRun<'a> {
    pub label: String,
    pub history: &'a [IterationSummary],
}

/// Paper Figs 10/11 style: best capacity and the variables (v, t_c, R_s; S_d too when it
/// varies) against generation / iteration, one line per run; the capacity is dashed while the
/// best point is still infeasible.
pub fn draw_history(
    path: &Path,
    title: &str,
    x_label: &str,
    runs: &[HistoryRun<'_>],
) -> Result<(), PlotError> {
    let format = format_of(path)?;
    ensure_font()?;
    let size = (1100, 800);
    match format {
        Format::Svg => render_history(
            SVGBackend::new(path, size).into_drawing_area(),
            title,
            x_label,
            runs,
        ),
        Format::Png => render_history(
            BitMapBackend::new(path, size).into_drawing_area(),
            title,
            x_label,
            runs,
        ),
    }
}

/// What a history panel plots of each iteration.
type PanelValue = Box<dyn Fn(&IterationSummary) -> f64>;

fn render_history<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    x_label: &str,
    runs: &[HistoryRun<'_>],
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(draw_err)?;
    let root = root.titled(title, (FONT, 20)).map_err(draw_err)?;
    let sd_varies = runs.iter().any(|r| {
        r.history
            .iter()
            .any(|h| h.best_x.get(3) != r.history.first().and_then(|f| f.best_x.get(3)))
    });
    // Panel 0: the capacity; then v, t_c, R_s (and S_d when it varies).
    let vars: Vec<usize> = if sd_varies {
        vec![0, 1, 2, 3]
    } else {
        vec![0, 1, 2]
    };
    let panels = root.split_evenly(((1 + vars.len()).div_ceil(2), 2));
    let x_max = runs
        .iter()
        .flat_map(|r| r.history.iter().map(|h| h.iteration as f64))
        .fold(1.0, f64::max);
    for (k, area) in panels.iter().enumerate().take(1 + vars.len()) {
        let (y_label, value): (String, PanelValue) = if k == 0 {
            (
                "best W [parcels/h]".into(),
                Box::new(|h: &IterationSummary| capacity_of(&h.best_x)),
            )
        } else {
            let i = vars[k - 1];
            (
                format!("{} [{}]", SYMBOLS[i], UNITS[i]),
                Box::new(move |h: &IterationSummary| h.best_x.get(i).copied().unwrap_or(f64::NAN)),
            )
        };
        let y = fit(runs.iter().flat_map(|r| r.history.iter().map(&value)));
        let mut ctx = ChartBuilder::on(area)
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(65)
            .build_cartesian_2d(0.0..x_max, y.0..y.1)
            .map_err(draw_err)?;
        ctx.configure_mesh()
            .x_desc(x_label)
            .y_desc(&y_label)
            .label_style((FONT, 12))
            .axis_desc_style((FONT, 14))
            .light_line_style(RGBColor(0xEE, 0xEE, 0xEE))
            .draw()
            .map_err(draw_err)?;
        for (j, run) in runs.iter().enumerate() {
            let color = PALETTE[j % PALETTE.len()];
            let solid = color.stroke_width(2);
            let thin = color.stroke_width(1);
            // Split into feasible / infeasible stretches (the capacity panel only).
            let mut stretch: Vec<(f64, f64)> = Vec::new();
            let mut stretch_feasible = true;
            let mut labelled = false;
            let mut flush = |pts: &mut Vec<(f64, f64)>, feasible: bool| -> Result<(), PlotError> {
                if pts.is_empty() {
                    return Ok(());
                }
                let anno = if feasible || k != 0 {
                    ctx.draw_series(LineSeries::new(pts.clone(), solid))
                        .map_err(draw_err)?
                } else {
                    ctx.draw_series(DashedLineSeries::new(pts.clone(), 6, 4, thin))
                        .map_err(draw_err)?
                };
                if k == 0 && !labelled && (feasible || pts.len() > 1) {
                    labelled = true;
                    anno.label(&run.label)
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], solid));
                }
                Ok(())
            };
            for h in run.history {
                let p = (h.iteration as f64, value(h));
                if !p.1.is_finite() {
                    continue;
                }
                let feasible = h.best_violation == 0.0;
                if feasible != stretch_feasible && !stretch.is_empty() {
                    let last = *stretch.last().unwrap_or(&p);
                    flush(&mut stretch, stretch_feasible)?;
                    stretch = vec![last];
                }
                stretch_feasible = feasible;
                stretch.push(p);
            }
            flush(&mut stretch, stretch_feasible)?;
        }
        if k == 0 && !runs.is_empty() {
            ctx.configure_series_labels()
                .label_font((FONT, 12))
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(0xB0, 0xB0, 0xB0))
                .position(SeriesLabelPosition::LowerRight)
                .draw()
                .map_err(draw_err)?;
        }
    }
    root.present().map_err(draw_err)?;
    Ok(())
}

/// The Pareto front: capacity against the overload ratio, colour = divert reserve d_min
/// (viridis, dark = small), with every other feasible evaluation in light grey behind.
pub fn draw_front(path: &Path, front: &[FrontPoint], log: &[Record]) -> Result<(), PlotError> {
    let format = format_of(path)?;
    ensure_font()?;
    let size = (950, 650);
    match format {
        Format::Svg => render_front(SVGBackend::new(path, size).into_drawing_area(), front, log),
        Format::Png => render_front(
            BitMapBackend::new(path, size).into_drawing_area(),
            front,
            log,
        ),
    }
}

fn render_front<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    front: &[FrontPoint],
    log: &[Record],
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(draw_err)?;
    let feasible: Vec<(f64, f64)> = log
        .iter()
        .filter(|r| r.evaluation.feasible() && r.evaluation.objectives.len() > 1)
        .map(|r| (capacity_of(&r.x), r.evaluation.objectives[1]))
        .collect();
    let pts: Vec<(f64, f64, f64)> = front
        .iter()
        .map(|f| {
            (
                capacity_of(&f.x),
                f.evaluation.objectives[1],
                -f.evaluation.objectives[2],
            )
        })
        .collect();
    let x = fit(feasible.iter().map(|p| p.0).chain(pts.iter().map(|p| p.0)));
    let y = fit(feasible.iter().map(|p| p.1).chain(pts.iter().map(|p| p.1)));
    let (d_lo, d_hi) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.2), b.max(p.2))
        });
    let d_span = if d_hi > d_lo { d_hi - d_lo } else { 1.0 };
    let mut ctx = ChartBuilder::on(&root)
        .caption(
            format!(
                "NSGA-II Pareto front: capacity vs overload; colour = divert reserve d_min {:.3}..{:.3} m (dark = small)",
                if d_lo.is_finite() { d_lo } else { 0.0 },
                if d_hi.is_finite() { d_hi } else { 0.0 }
            ),
            (FONT, 15),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)
        .map_err(draw_err)?;
    ctx.configure_mesh()
        .x_desc("capacity W [parcels/h]")
        .y_desc("overload ratio S/S_fall")
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 15))
        .light_line_style(RGBColor(0xEE, 0xEE, 0xEE))
        .draw()
        .map_err(draw_err)?;
    let grey = RGBColor(0xD0, 0xD0, 0xD0);
    ctx.draw_series(feasible.iter().map(|&p| Circle::new(p, 2, grey.filled())))
        .map_err(draw_err)?
        .label("feasible evaluations")
        .legend(move |(x, y)| Circle::new((x + 10, y), 3, grey.filled()));
    let mid = super::capacity::ramp(0.5);
    ctx.draw_series(pts.iter().map(|&(w, o, d)| {
        Circle::new(
            (w, o),
            5,
            super::capacity::ramp((d - d_lo) / d_span).filled(),
        )
    }))
    .map_err(draw_err)?
    .label("front (colour: divert reserve)")
    .legend(move |(x, y)| Circle::new((x + 10, y), 5, mid.filled()));
    ctx.configure_series_labels()
        .label_font((FONT, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(0xB0, 0xB0, 0xB0))
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(draw_err)?;
    root.present().map_err(draw_err)?;
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// The paper's experiment.

/// One run of the paper's experiment.
#[derive(Debug, Clone)]
pub struct PaperRun {
    /// "GA 1", "gradient 2", ...
    pub label: String,
    /// What distinguishes it: the box and seed, or the start.
    pub description: String,
    pub bounds: Bounds,
    pub outcome: RunOutcome,
    pub best: BestReport,
}

/// The paper's runs in order: (label, description, method, bounds, options).
pub fn paper_plan(o: &RunOptions) -> Vec<(String, String, Method, Bounds, RunOptions)> {
    let boxed = |b: [(f64, f64); 3]| {
        Bounds::new(
            vec![b[0].0, b[1].0, b[2].0, 0.0],
            vec![b[0].1, b[1].1, b[2].1, 0.0],
        )
        .expect("valid constant box")
    };
    let mut plan = Vec::new();
    for (k, (b, seed)) in [(PAPER_WIDE, 1u64), (PAPER_NARROW, 2), (PAPER_NARROW, 3)]
        .into_iter()
        .enumerate()
    {
        plan.push((
            format!("GA {}", k + 1),
            format!(
                "v {}-{}, t_c {}-{}, R_s {}-{}, seed {seed}",
                b[0].0, b[0].1, b[1].0, b[1].1, b[2].0, b[2].1
            ),
            Method::Ga,
            boxed(b),
            RunOptions {
                seed,
                start: None,
                ..o.clone()
            },
        ));
    }
    for (k, s) in PAPER_STARTS.iter().enumerate() {
        plan.push((
            format!("gradient {}", k + 1),
            format!("start ({}, {}, {})", s[0], s[1], s[2]),
            Method::Gradient,
            boxed(PAPER_WIDE),
            RunOptions {
                start: Some(vec![s[0], s[1], s[2], 0.0]),
                population: None,
                generations: None,
                ..o.clone()
            },
        ));
    }
    plan
}

/// Run the paper's experiment on a loaded scenario.
pub fn paper_experiment(
    loaded: &Loaded,
    o: &RunOptions,
    ctx: &RunContext<'_>,
) -> Result<Vec<PaperRun>, OptimizeError> {
    let mut runs = Vec::new();
    for (label, description, method, bounds, opts) in paper_plan(o) {
        let problem = settings_problem(loaded, &bounds, method)?;
        let settings = method_settings(method, &opts);
        let outcome = run_method(&problem, &settings, ctx)?;
        let best = best_report(&problem, &outcome.result);
        runs.push(PaperRun {
            label,
            description,
            bounds,
            outcome,
            best,
        });
    }
    Ok(runs)
}

/// The paper's reported optimum, for the table: GA (v, t_c, R_s) ranges and the proposed
/// setting.
pub const PAPER_GA_OPTIMUM: [(f64, f64); 3] = [(1.91, 1.99), (1.30, 1.31), (0.05, 0.10)];
/// The paper's proposed setting (v, t_c, R_s).
pub const PAPER_PROPOSED: [f64; 3] = [2.0, 1.36, 0.0];

/// paper_experiment.csv: one row per run.
pub fn paper_csv(runs: &[PaperRun]) -> Result<Vec<u8>, csv::Error> {
    let rows: Vec<Vec<String>> = runs
        .iter()
        .map(|r| {
            let res = &r.outcome.result;
            vec![
                r.label.clone(),
                r.description.clone(),
                num(r.best.x[0]),
                num(r.best.x[1]),
                num(r.best.x[2]),
                num(r.best.capacity),
                r.best.feasible.to_string(),
                res.evaluations.to_string(),
                res.feasible_count.to_string(),
                res.first_feasible.map_or(String::new(), |i| i.to_string()),
                r.best.active.len().to_string(),
                num(r.outcome.wall_time),
            ]
        })
        .collect();
    divertsim_api::output::csv_bytes(
        &[
            "run",
            "setup",
            "belt_speed_m_s",
            "cycle_time_s",
            "start_position_m",
            "capacity_per_h",
            "feasible",
            "evaluations",
            "feasible_evaluations",
            "first_feasible",
            "active_constraints",
            "wall_time_s",
        ],
        &rows,
    )
}

/// The paper experiment as JSON; `paper_point` is the design evaluation of the paper's
/// proposed setting on this scenario.
pub fn paper_json(runs: &[PaperRun], paper_point: &DesignEvaluation) -> Value {
    json!({
        "runs": runs.iter().map(|r| json!({
            "run": r.label,
            "setup": r.description,
            "bounds": bounds_json(&r.bounds),
            "best": best_json(&r.best),
            "evaluations": r.outcome.result.evaluations,
            "feasible_evaluations": r.outcome.result.feasible_count,
            "first_feasible": opt_json(r.outcome.result.first_feasible),
            "wall_time_s": r.outcome.wall_time,
        })).collect::<Vec<_>>(),
        "paper": {
            "ga_optimum": {"belt_speed": PAPER_GA_OPTIMUM[0], "cycle_time": PAPER_GA_OPTIMUM[1], "start_position": PAPER_GA_OPTIMUM[2]},
            "proposed": {"belt_speed": PAPER_PROPOSED[0], "cycle_time": PAPER_PROPOSED[1], "start_position": PAPER_PROPOSED[2]},
            "ga_feasible_evaluations": 8,
            "proposed_on_this_machine": {
                "capacity": paper_point.capacity,
                "feasible": paper_point.feasible,
                "overload_ratio": paper_point.overload.as_ref().ok().map(|o| o.ratio),
                "diverted": paper_point.cases.iter().map(|c| json!({"name": c.name, "diverted": c.outcome == Outcome::Diverted})).collect::<Vec<_>>(),
            },
        },
    })
}

/// The paper experiment's table.
pub fn paper_table(runs: &[PaperRun], paper_point: &DesignEvaluation) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<11} {:<38} {:>7} {:>6} {:>6} {:>8} {:>5} {:>6} {:>6} {:>6} {:>7}",
        "run", "setup", "v", "t_c", "R_s", "W [/h]", "feas", "evals", "n_feas", "first", "time_s"
    );
    for r in runs {
        let res = &r.outcome.result;
        let _ = writeln!(
            s,
            "{:<11} {:<38} {:>7.4} {:>6.4} {:>6.4} {:>8.1} {:>5} {:>6} {:>6} {:>6} {:>7.2}",
            r.label,
            r.description,
            r.best.x[0],
            r.best.x[1],
            r.best.x[2],
            r.best.capacity,
            if r.best.feasible { "yes" } else { "no" },
            res.evaluations,
            res.feasible_count,
            res.first_feasible
                .map_or("-".to_string(), |i| i.to_string()),
            r.outcome.wall_time
        );
    }
    let g = PAPER_GA_OPTIMUM;
    let w_lo = 3600.0 / (g[2].1 / g[0].0 + g[1].1);
    let w_hi = 3600.0 / (g[2].0 / g[0].1 + g[1].0);
    let _ = writeln!(
        s,
        "paper GA optimum: v {}-{} m/s, t_c {}-{} s, R_s {}-{} m (W {:.0}-{:.0} /h); 8 feasible evaluations in 100 x 80",
        g[0].0, g[0].1, g[1].0, g[1].1, g[2].0, g[2].1, w_lo, w_hi
    );
    let diverted: Vec<String> = paper_point
        .cases
        .iter()
        .map(|c| {
            format!(
                "{} {}",
                c.name,
                if c.outcome == Outcome::Diverted {
                    "diverted"
                } else {
                    "NOT diverted"
                }
            )
        })
        .collect();
    let _ = writeln!(
        s,
        "paper proposed: v 2, t_c 1.36, R_s 0 (W {:.1} /h); on this machine: {} ({}; overload ratio {})",
        paper_point.capacity,
        if paper_point.feasible { "feasible" } else { "infeasible" },
        diverted.join(", "),
        paper_point
            .overload
            .as_ref()
            .map_or("-".to_string(), |o| format!("{:.3}", o.ratio))
    );
    s
}

// ---------------------------------------------------------------------------------------------
// The comparison.

/// One run of the comparison.
#[derive(Debug, Clone, PartialEq)]
pub struct CompareRow {
    pub method: Method,
    pub seed: u64,
    /// Best feasible capacity [parcels/h] (NaN if none).
    pub best_capacity: f64,
    pub best_x: Vec<f64>,
    pub evaluations: usize,
    pub first_feasible: Option<usize>,
    /// Evaluations until a feasible point within 0.5 % of the best known capacity (1-based
    /// count), `None` if never.
    pub to_within: Option<usize>,
    pub feasible_count: usize,
    /// NSGA-II only: front size.
    pub front_size: Option<usize>,
    pub wall_time: f64,
}

/// Tolerance of "reaching the best capacity" in the comparison (issue 5: 0.5 %).
pub const WITHIN: f64 = 0.005;

/// Methods of the comparison, in order.
pub const COMPARE_METHODS: [Method; 5] = [
    Method::Ga,
    Method::Gradient,
    Method::De,
    Method::Cmaes,
    Method::Nsga2,
];

/// A gradient starting point for a seed: SplitMix64 draws, uniform in the bounds (the
/// gradient method has no randomness of its own, so the seeds vary its start).
pub fn seeded_start(bounds: &Bounds, seed: u64) -> Vec<f64> {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..bounds.dim())
        .map(|i| {
            let u = next();
            if bounds.is_fixed(i) {
                bounds.lower[i]
            } else {
                bounds.lower[i] + u * (bounds.upper[i] - bounds.lower[i])
            }
        })
        .collect()
}

/// The runs of the comparison: (method, seed, options).
pub fn compare_plan(bounds: &Bounds, o: &RunOptions, seeds: u64) -> Vec<(Method, u64, RunOptions)> {
    let mut plan = Vec::new();
    for method in COMPARE_METHODS {
        for k in 0..seeds {
            let seed = o.seed + k;
            let (population, generations) = match method {
                Method::Ga | Method::Nsga2 => (o.population, o.generations),
                _ => (None, None),
            };
            plan.push((
                method,
                seed,
                RunOptions {
                    population,
                    generations,
                    budget: o.budget,
                    polish: o.polish,
                    seed,
                    start: (method == Method::Gradient).then(|| seeded_start(bounds, seed)),
                },
            ));
        }
    }
    plan
}

/// Run the comparison; the "within 0.5 %" counts refer to the best feasible capacity over
/// every run.
pub fn compare(
    loaded: &Loaded,
    bounds: &Bounds,
    o: &RunOptions,
    seeds: u64,
    ctx: &RunContext<'_>,
) -> Result<(Vec<CompareRow>, f64), OptimizeError> {
    let mut done: Vec<(RunOutcome, u64)> = Vec::new();
    for (method, seed, opts) in compare_plan(bounds, o, seeds) {
        let problem = settings_problem(loaded, bounds, method)?;
        let settings = method_settings(method, &opts);
        done.push((run_method(&problem, &settings, ctx)?, seed));
    }
    let best_known = done
        .iter()
        .flat_map(|(r, _)| r.log.iter())
        .filter(|r| r.evaluation.feasible())
        .map(|r| capacity_of(&r.x))
        .fold(f64::NAN, f64::max);
    let rows = done
        .into_iter()
        .map(|(r, seed)| {
            let best_feasible = r
                .log
                .iter()
                .filter(|e| e.evaluation.feasible())
                .map(|e| (capacity_of(&e.x), e.x.clone()))
                .fold((f64::NAN, Vec::new()), |a, b| {
                    if a.0.is_nan() || b.0 > a.0 {
                        b
                    } else {
                        a
                    }
                });
            CompareRow {
                method: r.method,
                seed,
                best_capacity: best_feasible.0,
                best_x: if best_feasible.1.is_empty() {
                    r.result.best_x.clone()
                } else {
                    best_feasible.1
                },
                evaluations: r.result.evaluations,
                first_feasible: r.result.first_feasible.map(|i| i + 1),
                to_within: if best_known.is_finite() {
                    first_reaching(&r.log, (1.0 - WITHIN) * best_known).map(|i| i + 1)
                } else {
                    None
                },
                feasible_count: r.result.feasible_count,
                front_size: r.front.as_ref().map(Vec::len),
                wall_time: r.wall_time,
            }
        })
        .collect();
    Ok((rows, best_known))
}

/// Median of the values; `None` counts as +∞ (a run that never got there); `None` when the
/// median itself is such a run or there are no values.
pub fn median(values: &[Option<f64>]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut v: Vec<f64> = values
        .iter()
        .map(|x| x.filter(|v| !v.is_nan()).unwrap_or(f64::INFINITY))
        .collect();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let m = if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    };
    m.is_finite().then_some(m)
}

/// Medians of one method: (best capacity, first feasible, to within 0.5 %, evaluations,
/// wall time, front size).
pub fn method_medians(rows: &[CompareRow], method: Method) -> [Option<f64>; 6] {
    let r: Vec<&CompareRow> = rows.iter().filter(|r| r.method == method).collect();
    let f = |g: &dyn Fn(&CompareRow) -> Option<f64>| {
        median(&r.iter().map(|x| g(x)).collect::<Vec<_>>())
    };
    [
        f(&|x| Some(x.best_capacity)),
        f(&|x| x.first_feasible.map(|v| v as f64)),
        f(&|x| x.to_within.map(|v| v as f64)),
        f(&|x| Some(x.evaluations as f64)),
        f(&|x| Some(x.wall_time)),
        f(&|x| x.front_size.map(|v| v as f64)),
    ]
}

/// comparison.csv (one row per run) and comparison_medians.csv (one row per method, the
/// medians over its seeds): tidy tables, an empty cell where there is no value.
pub fn compare_csv(rows: &[CompareRow]) -> Result<(Vec<u8>, Vec<u8>), csv::Error> {
    let o = |v: Option<usize>| v.map_or(String::new(), |i| i.to_string());
    let of = |v: Option<f64>| v.map_or(String::new(), num);
    let runs: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                r.method.name().to_string(),
                r.seed.to_string(),
                num(r.best_capacity),
                num(r.best_x[0]),
                num(r.best_x[1]),
                num(r.best_x[2]),
                num(r.best_x[3]),
                r.evaluations.to_string(),
                o(r.first_feasible),
                o(r.to_within),
                r.feasible_count.to_string(),
                o(r.front_size),
                num(r.wall_time),
            ]
        })
        .collect();
    let medians: Vec<Vec<String>> = COMPARE_METHODS
        .into_iter()
        .filter(|&m| rows.iter().any(|r| r.method == m))
        .map(|m| {
            let md = method_medians(rows, m);
            vec![
                m.name().to_string(),
                rows.iter().filter(|r| r.method == m).count().to_string(),
                of(md[0]),
                of(md[3]),
                of(md[1]),
                of(md[2]),
                of(md[5]),
                of(md[4]),
            ]
        })
        .collect();
    let runs = divertsim_api::output::csv_bytes(
        &[
            "method",
            "seed",
            "best_capacity_per_h",
            "belt_speed_m_s",
            "cycle_time_s",
            "start_position_m",
            "light_barrier_m",
            "evaluations",
            "first_feasible",
            "evaluations_to_within_half_percent",
            "feasible_count",
            "front_size",
            "wall_time_s",
        ],
        &runs,
    )?;
    let medians = divertsim_api::output::csv_bytes(
        &[
            "method",
            "seeds",
            "best_capacity_per_h",
            "evaluations",
            "first_feasible",
            "evaluations_to_within_half_percent",
            "front_size",
            "wall_time_s",
        ],
        &medians,
    )?;
    Ok((runs, medians))
}

/// The comparison as JSON.
pub fn compare_json(rows: &[CompareRow], best_known: f64, bounds: &Bounds) -> Value {
    let oj = |v: Option<f64>| v.map_or(Value::Null, |x| json!(x));
    json!({
        "bounds": bounds_json(bounds),
        "best_known_capacity": finite(best_known),
        "within": WITHIN,
        "runs": rows.iter().map(|r| json!({
            "method": r.method.name(),
            "seed": r.seed,
            "best_capacity": finite(r.best_capacity),
            "best_x": r.best_x,
            "evaluations": r.evaluations,
            "first_feasible": opt_json(r.first_feasible),
            "to_within": opt_json(r.to_within),
            "feasible_count": r.feasible_count,
            "front_size": opt_json(r.front_size),
            "wall_time_s": r.wall_time,
        })).collect::<Vec<_>>(),
        "medians": COMPARE_METHODS.iter().filter(|m| rows.iter().any(|r| r.method == **m)).map(|&m| {
            let md = method_medians(rows, m);
            json!({
                "method": m.name(),
                "best_capacity": oj(md[0]),
                "first_feasible": oj(md[1]),
                "to_within": oj(md[2]),
                "evaluations": oj(md[3]),
                "wall_time_s": oj(md[4]),
                "front_size": oj(md[5]),
            })
        }).collect::<Vec<_>>(),
    })
}

/// The comparison's table (medians per method).
pub fn compare_table(rows: &[CompareRow], best_known: f64) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let f = |v: Option<f64>, p: usize| v.map_or("-".to_string(), |x| format!("{x:.p$}"));
    let _ = writeln!(
        s,
        "best known feasible capacity: {best_known:.2} parcels/h; medians over {} seeds",
        rows.iter()
            .filter(|r| r.method == Method::Ga)
            .count()
            .max(1)
    );
    let _ = writeln!(
        s,
        "{:<9} {:>10} {:>12} {:>14} {:>8} {:>9} {:>6}",
        "method", "best W", "1st feasible", "within 0.5 %", "evals", "time [s]", "front"
    );
    for m in COMPARE_METHODS {
        if !rows.iter().any(|r| r.method == m) {
            continue;
        }
        let md = method_medians(rows, m);
        let _ = writeln!(
            s,
            "{:<9} {:>10} {:>12} {:>14} {:>8} {:>9} {:>6}",
            m.name(),
            f(md[0], 1),
            f(md[1], 0),
            f(md[2], 0),
            f(md[3], 0),
            f(md[4], 2),
            f(md[5], 0)
        );
    }
    let ga = method_medians(rows, Method::Ga)[2];
    for m in [Method::De, Method::Cmaes] {
        let other = method_medians(rows, m)[2];
        if let (Some(a), Some(b)) = (ga, other) {
            let _ = writeln!(
                s,
                "GA / {}: {:.1}x fewer evaluations to within 0.5 % of the best",
                m.name(),
                a / b
            );
        }
    }
    s
}

// ---------------------------------------------------------------------------------------------
// The command.

fn run_options(args: &OptimizeArgs, start: Option<Vec<f64>>) -> RunOptions {
    RunOptions {
        population: args.population.map(|v| v as usize),
        generations: args.generations.map(|v| v as usize),
        budget: args.budget.map(|v| v as usize),
        polish: !args.no_polish,
        seed: args.seed,
        start,
    }
}

/// Checks that need the method: options that do not apply, and the solver's own validation
/// (run on a zero-cost dry check of the settings).
fn method_problems(args: &OptimizeArgs, method: Method) -> Vec<CliProblem> {
    let mut p = Vec::new();
    let not_for = |opt: &str, methods: &str| {
        problem(
            opt,
            format!(
                "does not apply to --method {}; allowed with {methods}",
                method.name()
            ),
        )
    };
    if args.start.is_some() && !matches!(method, Method::Gradient | Method::Cmaes) {
        p.push(not_for("--start", "gradient, cmaes"));
    }
    if method == Method::Gradient {
        if args.population.is_some() {
            p.push(not_for("--population", "ga, de, cmaes, nsga2"));
        }
        if args.generations.is_some() {
            p.push(not_for("--generations", "ga, de, cmaes, nsga2"));
        }
    }
    if args.no_polish && !matches!(method, Method::De | Method::Cmaes) {
        p.push(not_for("--no-polish", "de, cmaes"));
    }
    if let (Some(b), Some(n)) = (args.budget, args.population) {
        if matches!(method, Method::Ga | Method::De | Method::Nsga2) && b < n {
            p.push(problem(
                "--budget",
                format!("{b} is below --population {n}; allowed: ≥ the population"),
            ));
        }
    }
    p
}

fn write_single(
    dir: &Path,
    problem: &SettingsProblem,
    run: &RunOutcome,
    report: &Value,
    file: &divertsim_api::config::ScenarioFile,
) -> Result<i32, String> {
    let mut files = vec![
        divertsim_api::output::scenario_toml("optimize", file),
        (
            "evaluations.csv".to_string(),
            evaluations_csv(problem, &run.log).map_err(|e| e.to_string())?,
        ),
        (
            "history.csv".to_string(),
            history_csv(&run.result.history).map_err(|e| e.to_string())?,
        ),
        ("report.json".to_string(), common::json_bytes(report)),
    ];
    if let Some(front) = &run.front {
        files.push((
            "front.csv".to_string(),
            front_csv(front).map_err(|e| e.to_string())?,
        ));
    }
    let method = run.method;
    Ok(common::write_outputs(dir, files, |staging| {
        let x_label = if method == Method::Gradient {
            "iteration"
        } else {
            "generation"
        };
        for ext in ["svg", "png"] {
            draw_history(
                &staging.join(format!("history.{ext}")),
                &format!(
                    "divertsim optimize --method {}: best point against {x_label}",
                    method.name()
                ),
                x_label,
                &[HistoryRun {
                    label: format!("{} (seed or start as given)", method.name()),
                    history: &run.result.history,
                }],
            )
            .map_err(|e| e.to_string())?;
            if let Some(front) = &run.front {
                draw_front(&staging.join(format!("front.{ext}")), front, &run.log)
                    .map_err(|e| e.to_string())?;
            }
        }
        Ok(())
    }))
}

/// The robust rounds of a single run with `--worst search`.
pub struct RobustRun {
    pub optimum: RobustOptimum,
    pub settings: RobustSettings,
}

/// Optimise against the searched worst case: rounds of `run_method` and a worst-case search
/// at its best point ([`robust_optimize`]). Returns the last round's problem and run.
pub fn run_robust(
    loaded: &Loaded,
    bounds: &Bounds,
    method: Method,
    settings: &MethodSettings,
    robust: &RobustSettings,
    ctx: &RunContext<'_>,
    new_round: &dyn Fn(),
) -> Result<(SettingsProblem, RunOutcome, RobustRun), OptimizeError> {
    let objectives = if method == Method::Nsga2 {
        Objectives::TradeOff
    } else {
        Objectives::Capacity
    };
    let make = |set: DesignSet| {
        SettingsProblem::new(loaded.scenario.clone(), set, bounds.clone(), objectives)
    };
    let mut last: Option<RunOutcome> = None;
    let mut solve = |p: &SettingsProblem| {
        new_round();
        let run = run_method(p, settings, ctx)?;
        let result = run.result.clone();
        last = Some(run);
        Ok(result)
    };
    let optimum = robust_optimize(
        &loaded.scenario,
        &loaded.design,
        robust,
        &make,
        &mut solve,
        ctx.progress,
    )?;
    // The last round's problem: the pose set it was solved against.
    let problem = make(optimum.solved.clone())?;
    let run = last.ok_or_else(|| OptimizeError::InvalidSetting {
        name: "rounds",
        reason: "no round ran".into(),
    })?;
    Ok((
        problem,
        run,
        RobustRun {
            optimum,
            settings: robust.clone(),
        },
    ))
}

fn single(
    args: &OptimizeArgs,
    loaded: &Loaded,
    bounds: &Bounds,
    method: Method,
    start: Option<Vec<f64>>,
    robust: Option<&RobustSettings>,
    journal: &Option<Journal>,
) -> i32 {
    let o = run_options(args, start);
    let settings = method_settings(method, &o);
    let problem = match settings_problem(loaded, bounds, method) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: --bound: {e}");
            return 2;
        }
    };
    let planned = planned_evaluations(&settings, bounds.free_indices().len()) as u64;
    let bar = common::progress_bar(planned, method.name(), args.output.quiet);
    let tick = || bar.inc(1);
    let ctx = RunContext::kept(&tick, journal);
    let (problem, run, robust_run) = match robust {
        None => {
            let run = divertsim_api::threads::with_threads(args.output.threads, || {
                run_method(&problem, &settings, &ctx)
            });
            (problem, run, None)
        }
        Some(r) => {
            let rounds = std::sync::atomic::AtomicU64::new(0);
            let search = 2 * r.search.evaluations as u64;
            let new_round = || {
                // Each round: the solver's evaluations and two searches.
                if rounds.fetch_add(1, std::sync::atomic::Ordering::Relaxed) > 0 {
                    bar.inc_length(planned + search);
                } else {
                    bar.set_length(planned + search);
                }
            };
            match divertsim_api::threads::with_threads(args.output.threads, || {
                run_robust(loaded, bounds, method, &settings, r, &ctx, &new_round)
            }) {
                Ok((p, run, rr)) => (p, Ok(run), Some(rr)),
                Err(e) => (problem, Err(e), None),
            }
        }
    };
    bar.finish_and_clear();
    let run = match run {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let best = best_report(&problem, &run.result);
    let mut report = report_json(&problem, &run, &best);
    report["worst"] = json!(loaded.design.worst.label());
    report["margins"] = json!({
        "overload": loaded.design.margins.overload,
        "divert": loaded.design.margins.divert,
    });
    if let Some(rr) = &robust_run {
        report["robust"] = robust_json(&problem, rr);
    }
    let report = divertsim_api::output::describe(report, "optimize", &loaded.file);
    if let Some(dir) = &args.output.out {
        match write_single(dir, &problem, &run, &report, &loaded.file) {
            Ok(0) => {}
            Ok(code) => return code,
            Err(e) => {
                eprintln!("error: cannot format the outputs: {e}");
                return 1;
            }
        }
    }
    if args.output.json {
        common::emit_json(&report);
    } else {
        let mut text = report_text(&run, &best);
        if let Some(rr) = &robust_run {
            text += &robust_text(&problem, rr);
        }
        common::emit(&text);
    }
    0
}

/// The names of the worst-pose constraints that are active at the last round's best point
/// (its evaluation is in the solver's result: `problem` is that round's).
fn active_poses(problem: &SettingsProblem, rr: &RobustRun) -> Vec<String> {
    problem
        .constraint_names()
        .iter()
        .zip(&rr.optimum.last().result.best.constraints)
        .filter(|(n, g)| n.starts_with("divert:worst") && g.abs() <= ACTIVE_TOLERANCE)
        .map(|(n, _)| n.clone())
        .collect()
}

/// The rounds of a robust run as JSON.
pub fn robust_json(problem: &SettingsProblem, rr: &RobustRun) -> Value {
    let o = &rr.optimum;
    let set = problem.design_set();
    let last = o.last();
    json!({
        "converged": o.converged,
        "rounds": o.rounds.iter().map(|r| {
            let v = &r.verification;
            json!({
                "poses": r.poses,
                "best_x": r.result.best_x,
                "capacity": capacity_of(&r.result.best_x),
                "feasible_on_pose_set": r.result.best.feasible(),
                "searched_overload_ratio": v.impulse.value,
                "searched_reserve": v.reserve.value,
                "violating_poses": v.violating.len(),
            })
        }).collect::<Vec<_>>(),
        "search": {
            "evaluations": rr.settings.search.evaluations,
            "starts": rr.settings.search.starts,
            "seed": rr.settings.search.seed,
        },
        "scatter": {
            "belt_speed": rr.settings.scatter.belt_speed,
            "phase": rr.settings.scatter.phase,
            "belt_friction": rr.settings.scatter.belt_friction,
        },
        "overload_excess": last.verification.overload_excess(set),
        "divert_shortfall": last.verification.divert_shortfall(set),
        "worst_impulse_pose": pose_json(&last.verification.impulse.pose),
        "worst_reserve_pose": pose_json(&last.verification.reserve.pose),
        "poses": set.worst_poses.iter().map(pose_json).collect::<Vec<_>>(),
        "active_poses": active_poses(problem, rr),
    })
}

/// The rounds of a robust run, for the table.
pub fn robust_text(problem: &SettingsProblem, rr: &RobustRun) -> String {
    use std::fmt::Write;
    let o = &rr.optimum;
    let set = problem.design_set();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "robust against the searched worst case: {} round{}, {}",
        o.rounds.len(),
        if o.rounds.len() == 1 { "" } else { "s" },
        if o.converged {
            "converged (the search at the optimum finds no violating pose)"
        } else if o.rounds.len() < rr.settings.max_rounds && !o.last().result.best.feasible() {
            "NOT converged: no setting within the bounds holds against the worst poses found \
             (the best point violates them); relax the margins or widen the bounds"
        } else {
            "NOT converged (raise --rounds)"
        }
    );
    for (k, r) in o.rounds.iter().enumerate() {
        let x = &r.result.best_x;
        let _ = writeln!(
            s,
            "  round {}: {} worst poses, best v = {:.4}, t_c = {:.4}, R_s = {:.4}, W = {:.1}; searched S/S_fall = {:.4}, reserve = {:.4} m, {} violating pose(s)",
            k + 1,
            r.poses,
            x[0],
            x[1],
            x[2],
            capacity_of(x),
            r.verification.impulse.value,
            r.verification.reserve.value,
            r.verification.violating.len()
        );
    }
    for (k, p) in set.worst_poses.iter().enumerate() {
        let _ = writeln!(s, "  worst{}: {}", k + 1, pose_text(p));
    }
    let active = active_poses(problem, rr);
    let _ = writeln!(
        s,
        "active worst poses: {}",
        if active.is_empty() {
            "none".to_string()
        } else {
            active.join(", ")
        }
    );
    s
}

fn paper_mode(args: &OptimizeArgs, loaded: &Loaded, journal: &Option<Journal>) -> i32 {
    let o = run_options(args, None);
    let plan = paper_plan(&o);
    let total: usize = plan
        .iter()
        .map(|(_, _, m, b, opts)| {
            planned_evaluations(&method_settings(*m, opts), b.free_indices().len())
        })
        .sum();
    let bar = common::progress_bar(total as u64, "paper", args.output.quiet);
    let tick = || bar.inc(1);
    let ctx = RunContext::kept(&tick, journal);
    let result = divertsim_api::threads::with_threads(args.output.threads, || {
        let runs = paper_experiment(loaded, &o, &ctx)?;
        let problem = settings_problem(loaded, &runs[0].bounds, Method::Ga)?;
        let x = [PAPER_PROPOSED[0], PAPER_PROPOSED[1], PAPER_PROPOSED[2], 0.0];
        Ok::<_, OptimizeError>((runs, problem.design_evaluation(&x)))
    });
    bar.finish_and_clear();
    let (runs, paper_point) = match result {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let report =
        divertsim_api::output::describe(paper_json(&runs, &paper_point), "optimize", &loaded.file);
    if let Some(dir) = &args.output.out {
        let mut files = Vec::new();
        let mut push = |name: String, bytes: Result<Vec<u8>, csv::Error>| -> Result<(), String> {
            files.push((name, bytes.map_err(|e| e.to_string())?));
            Ok(())
        };
        let mut ok = push("paper_experiment.csv".into(), paper_csv(&runs));
        for r in &runs {
            let stem = r.label.replace(' ', "_");
            let problem = match settings_problem(loaded, &r.bounds, r.outcome.method) {
                Ok(p) => p,
                Err(e) => {
                    eprintln!("error: {e}");
                    return 2;
                }
            };
            ok = ok
                .and_then(|_| {
                    push(
                        format!("{stem}_history.csv"),
                        history_csv(&r.outcome.result.history),
                    )
                })
                .and_then(|_| {
                    push(
                        format!("{stem}_evaluations.csv"),
                        evaluations_csv(&problem, &r.outcome.log),
                    )
                });
        }
        if let Err(e) = ok {
            eprintln!("error: cannot format the outputs: {e}");
            return 1;
        }
        files.push(divertsim_api::output::scenario_toml(
            "optimize",
            &loaded.file,
        ));
        files.push(("paper_experiment.json".into(), common::json_bytes(&report)));
        let code = common::write_outputs(dir, files, |staging| {
            let of = |m: Method| -> Vec<HistoryRun<'_>> {
                runs.iter()
                    .filter(|r| r.outcome.method == m)
                    .map(|r| HistoryRun {
                        label: format!("{}: {}", r.label, r.description),
                        history: &r.outcome.result.history,
                    })
                    .collect()
            };
            for ext in ["svg", "png"] {
                draw_history(
                    &staging.join(format!("fig10_ga.{ext}")),
                    "GA (paper Fig. 10): best point against generation, dashed while infeasible",
                    "generation",
                    &of(Method::Ga),
                )
                .map_err(|e| e.to_string())?;
                draw_history(
                    &staging.join(format!("fig11_gradient.{ext}")),
                    "Penalised steepest descent (paper Fig. 11): best point against iteration, dashed while infeasible",
                    "iteration",
                    &of(Method::Gradient),
                )
                .map_err(|e| e.to_string())?;
            }
            Ok(())
        });
        if code != 0 {
            return code;
        }
    }
    if args.output.json {
        common::emit_json(&report);
    } else {
        common::emit(&paper_table(&runs, &paper_point));
    }
    0
}

fn compare_mode(
    args: &OptimizeArgs,
    loaded: &Loaded,
    bounds: &Bounds,
    journal: &Option<Journal>,
) -> i32 {
    let o = run_options(args, None);
    let plan = compare_plan(bounds, &o, args.seeds);
    let total: usize = plan
        .iter()
        .map(|(m, _, opts)| {
            planned_evaluations(&method_settings(*m, opts), bounds.free_indices().len())
        })
        .sum();
    let bar = common::progress_bar(total as u64, "compare", args.output.quiet);
    let tick = || bar.inc(1);
    let ctx = RunContext::kept(&tick, journal);
    let result = divertsim_api::threads::with_threads(args.output.threads, || {
        compare(loaded, bounds, &o, args.seeds, &ctx)
    });
    bar.finish_and_clear();
    let (rows, best_known) = match result {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let report = divertsim_api::output::describe(
        compare_json(&rows, best_known, bounds),
        "optimize",
        &loaded.file,
    );
    if let Some(dir) = &args.output.out {
        let (csv, medians) = match compare_csv(&rows) {
            Ok(c) => c,
            Err(e) => {
                eprintln!("error: cannot format comparison.csv: {e}");
                return 1;
            }
        };
        let files = vec![
            divertsim_api::output::scenario_toml("optimize", &loaded.file),
            ("comparison.csv".to_string(), csv),
            ("comparison_medians.csv".to_string(), medians),
            ("comparison.json".to_string(), common::json_bytes(&report)),
        ];
        let code = common::write_outputs(dir, files, |_| Ok(()));
        if code != 0 {
            return code;
        }
    }
    if args.output.json {
        common::emit_json(&report);
    } else {
        common::emit(&compare_table(&rows, best_known));
    }
    0
}

/// The scenario file's `[optimize]` search box as `--bound` / `--fix` texts, in variable
/// order (the command line's come after them, so they override).
pub fn file_bounds(cfg: &divertsim_api::config::OptimizeConfig) -> (Vec<String>, Vec<String>) {
    use divertsim_api::config::SearchRange;
    let (mut bounds, mut fixes) = (Vec::new(), Vec::new());
    let keys = [
        cfg.belt_speed,
        cfg.cycle_time,
        cfg.start_position,
        cfg.light_barrier,
    ];
    for (name, range) in VARIABLES.iter().zip(keys) {
        match range {
            Some(SearchRange::Fixed(x)) => fixes.push(format!("{name}={x}")),
            Some(SearchRange::Range([lo, hi])) => bounds.push(format!("{name}={lo}:{hi}")),
            None => {}
        }
    }
    (bounds, fixes)
}

/// `divertsim optimize`.
pub fn run(args: &OptimizeArgs) -> i32 {
    let loaded = common::load_scenario(&args.scenario);
    let mut problems = common::out_problems(&args.output);
    let loaded = match loaded {
        Ok(l) => l,
        Err(code) => {
            let _ = common::check(problems);
            return code;
        }
    };
    // The file's [optimize] box first (its problems named by key), then the command line's,
    // which override it variable by variable; each is checked on its own so that every
    // problem is reported.
    let lb = loaded.scenario.machine.light_barrier;
    let (mut all_bounds, mut all_fixes) = file_bounds(&loaded.file.optimize);
    let file_ok = match parse_bounds(&all_bounds, &all_fixes, lb) {
        Ok(_) => true,
        Err(p) => {
            problems.extend(p.into_iter().map(|mut pr| {
                let name = VARIABLES
                    .iter()
                    .find(|n| pr.message.contains(&format!("'{n}=")))
                    .map_or(String::new(), |n| format!(".{n}"));
                pr.key = format!("optimize{name}");
                pr
            }));
            false
        }
    };
    let cli_ok = match parse_bounds(&args.bounds, &args.fixes, lb) {
        Ok(_) => true,
        Err(p) => {
            problems.extend(p);
            false
        }
    };
    // parse_bounds applies fixes after ranges: a file fix must not override a command-line
    // range of the same variable.
    let cli_ranged: Vec<Option<usize>> = args
        .bounds
        .iter()
        .map(|b| b.split_once('=').and_then(|(n, _)| variable_index(n)))
        .collect();
    all_fixes.retain(|f| {
        let i = f.split_once('=').and_then(|(n, _)| variable_index(n));
        !cli_ranged.contains(&i)
    });
    all_bounds.extend(args.bounds.iter().cloned());
    all_fixes.extend(args.fixes.iter().cloned());
    let bounds = if file_ok && cli_ok {
        match parse_bounds(&all_bounds, &all_fixes, lb) {
            Ok(b) => Some(b),
            Err(p) => {
                problems.extend(p);
                None
            }
        }
    } else {
        None
    };
    let batch = args.paper_experiment || args.compare;
    let (worst, margins, robust) = match args.robust.resolve(batch) {
        Ok(r) => r,
        Err(p) => {
            problems.extend(p);
            (WorstArg::Paper, Margins::default(), None)
        }
    };
    let mut loaded = loaded;
    loaded.design.worst = worst.definition();
    loaded.design.margins = margins;
    let method = args.method.unwrap_or(Method::De);
    let mut start = None;
    if !args.paper_experiment && !args.compare {
        problems.extend(method_problems(args, method));
        if let (Some(text), Some(b)) = (&args.start, &bounds) {
            match parse_start(text, b) {
                Ok(x) => start = Some(x),
                Err(p) => problems.push(p),
            }
        }
    } else if args.no_polish && args.paper_experiment {
        problems.push(problem(
            "--no-polish",
            "does not apply to --paper-experiment (GA and gradient have no polish)".into(),
        ));
    }
    if let Err(code) = common::check(problems) {
        return code;
    }
    let Some(bounds) = bounds else { return 2 };
    // The solvers' own setting checks, before any simulation.
    let check_plan: Vec<(Method, RunOptions)> = if args.paper_experiment {
        paper_plan(&run_options(args, None))
            .into_iter()
            .map(|(_, _, m, _, o)| (m, o))
            .collect()
    } else if args.compare {
        compare_plan(&bounds, &run_options(args, None), args.seeds)
            .into_iter()
            .map(|(m, _, o)| (m, o))
            .collect()
    } else {
        vec![(method, run_options(args, start.clone()))]
    };
    for (m, o) in &check_plan {
        if let Err(e) = dry_check(&loaded, &bounds, *m, o) {
            eprintln!("error: {e}");
            return 2;
        }
    }
    // Each evaluation runs the design set's checks; a robust run repeats the solver and two
    // searches (and their confirmations) for at most its rounds.
    let solver: u64 = check_plan
        .iter()
        .map(|(m, o)| {
            planned_evaluations(&method_settings(*m, o), bounds.free_indices().len()) as u64
        })
        .sum::<u64>()
        * loaded.design.run_count() as u64;
    let sims = match &robust {
        None => solver,
        Some(r) => {
            let search = 2 * (1 + r.confirm as u64) * r.search.evaluations as u64;
            r.max_rounds.max(1) as u64 * (solver + search)
        }
    };
    if let Err(code) = common::within_budget(
        "optimize",
        sims,
        &args.output,
        "use a smaller --population, --generations or --budget",
    ) {
        return code;
    }
    let journal = match common::open_journal(
        args.output.out.as_deref(),
        args.resume.resume,
        "optimize",
        &(
            &loaded.scenario,
            &loaded.design,
            &bounds,
            &check_plan,
            (args.paper_experiment, args.compare, args.seeds),
            &robust,
        ),
    ) {
        Ok(j) => j,
        Err(code) => return code,
    };
    let code = if args.paper_experiment {
        paper_mode(args, &loaded, &journal)
    } else if args.compare {
        compare_mode(args, &loaded, &bounds, &journal)
    } else {
        single(
            args,
            &loaded,
            &bounds,
            method,
            start,
            robust.as_ref(),
            &journal,
        )
    };
    common::close_journal(journal, code)
}

/// A stand-in problem of the same shape that costs nothing (see [`dry_check`]).
struct Free<'a> {
    bounds: &'a Bounds,
    objectives: usize,
    constraints: usize,
}

impl Problem for Free<'_> {
    fn bounds(&self) -> &Bounds {
        self.bounds
    }
    fn objective_count(&self) -> usize {
        self.objectives
    }
    fn constraint_count(&self) -> usize {
        self.constraints
    }
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        Evaluation {
            objectives: vec![x.iter().sum::<f64>(); self.objectives],
            constraints: vec![-1.0; self.constraints],
        }
    }
}

/// Validate a method's settings before any simulation: run the solver on a free stand-in
/// problem of the same shape, so that its own checks (population, budget, start, ...) report
/// as exit 2 naming the option.
fn dry_check(
    loaded: &Loaded,
    bounds: &Bounds,
    method: Method,
    o: &RunOptions,
) -> Result<(), String> {
    let p = settings_problem(loaded, bounds, method).map_err(|e| format!("--bound: {e}"))?;
    let free = Free {
        bounds,
        objectives: p.objective_count(),
        constraints: p.constraint_count(),
    };
    let settings = method_settings(method, o);
    let mut log = RecordLog::default();
    let r = match &settings {
        MethodSettings::Ga(s) => ga::solve(&free, s, &mut log).map(|_| ()),
        MethodSettings::Gradient(s) => gradient::solve(&free, s, &mut log).map(|_| ()),
        MethodSettings::De(s) => de::solve(&free, s, &mut log).map(|_| ()),
        MethodSettings::Cmaes(s) => cmaes::solve(&free, s, &mut log).map(|_| ()),
        MethodSettings::Nsga2(s) => nsga2::solve(&free, s, &mut log).map(|_| ()),
    };
    r.map_err(|e| {
        let opt = match &e {
            OptimizeError::InvalidSetting { name, .. } => match *name {
                "population" => "--population",
                "max_evaluations" => "--budget",
                "start" => "--start",
                _ => "--generations",
            },
            _ => "--bound",
        };
        format!("{opt}: {e}")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_bounds_and_fixes() {
        assert_eq!(variable_index("v"), Some(0));
        assert_eq!(variable_index("light_barrier"), Some(3));
        assert_eq!(variable_index("x"), None);
        let b = parse_bounds(&[], &[], 0.2).unwrap();
        assert_eq!(b.lower, vec![1.0, 1.0, 0.0, 0.2]);
        assert_eq!(b.upper, vec![2.3, 1.5, 0.9, 0.2]);
        let b = parse_bounds(
            &["v=1.5:2".into(), "S_d=-0.1:0.3".into()],
            &["t_c=1.3".into()],
            0.0,
        )
        .unwrap();
        assert_eq!(b.lower, vec![1.5, 1.3, 0.0, -0.1]);
        assert_eq!(b.upper, vec![2.0, 1.3, 0.9, 0.3]);
        for bad in ["v=2:1", "v=0:1", "q=1:2", "v=1", "t_c=1:20", "v=a:b"] {
            let e = parse_bounds(&[bad.into()], &[], 0.0).unwrap_err();
            assert_eq!(e[0].key, "--bound", "{bad}");
        }
        let e = parse_bounds(&[], &["R_s=9".into(), "w=1".into()], 0.0).unwrap_err();
        assert_eq!(e.len(), 2);
        assert!(e[0].message.contains("[-5, 5] m"), "{}", e[0].message);
    }

    #[test]
    fn starts_and_medians() {
        let b = parse_bounds(&[], &[], 0.0).unwrap();
        assert_eq!(
            parse_start("1.8,1.5,0.5", &b).unwrap(),
            vec![1.8, 1.5, 0.5, 0.0]
        );
        assert!(parse_start("1.8,1.5", &b).is_err());
        assert!(parse_start("3,1.5,0.5", &b).is_err());
        assert_eq!(median(&[Some(3.0), None, Some(1.0)]), Some(3.0));
        assert_eq!(median(&[Some(3.0), None, None]), None);
        assert_eq!(median(&[Some(1.0), Some(2.0)]), Some(1.5));
        let s = seeded_start(&b, 3);
        assert_eq!(s, seeded_start(&b, 3));
        assert_ne!(s, seeded_start(&b, 4));
        for (i, &si) in s.iter().enumerate() {
            assert!(si >= b.lower[i] && si <= b.upper[i]);
        }
        assert_eq!(s[3], 0.0);
    }
}
