//! The paper's machine-settings optimisation (§4.3, issue 5) as library functions: maximise
//! the sorting capacity W = 3600/((R_s − S_d)/v + t_c) over (v, t_c, R_s, S_d) subject to
//! every `[design]` parcel being diverted (its lateral travel reaching P_max) and the
//! worst-case impulse staying below the free fall (S/S_fall ≤ 1), with the paper's real-coded
//! GA and penalised steepest descent, differential evolution and CMA-ES (each with a COBYLA
//! polish), and NSGA-II for the trade-off capacity / overload ratio / divert reserve.
//!
//! Three experiments: one run of a method ([`run_method`], with [`run_robust`] for settings
//! that hold against the searched worst case), the paper's three GA and three gradient runs
//! ([`paper_experiment`], paper Figs 10/11), and every method over several seeds on the same
//! problem ([`compare`]); with their tidy tables (CSV, unit-suffixed columns) and JSON
//! summaries, so that every edge shows the same columns. No files, no printing: progress, the
//! memo of finished evaluations (a checkpoint to resume from) and a live stream of the evaluations are passed
//! in by the edge ([`RunContext`]).
//!
//! The problem is `divertsim_core::analysis::design::settings_problem`; the solvers are
//! `divertsim_core::optimize`; the robust rounds are `divertsim_core::analysis::design::robust`.
//! References: the paper §4.3 (GA 100 × 80, steepest descent with a growing exterior penalty);
//! docs/validation.md, "Optimisation (issue 5)" for the tuned defaults of the other methods.
//!
//! Every run is deterministic for its seed and independent of the thread count (the solvers
//! evaluate batches in parallel and record them in order). Wall times are measurements and
//! appear only in their own fields.

pub mod options;
pub mod text;
pub use options::{Optimize, OptimizeOptions, OptimizeResult};

use std::time::Instant;

use crate::analyses::worst_case::pose_json;
use crate::config::bounds::{
    SEARCHED_BELT_SPEED, SEARCHED_CYCLE_TIME, SEARCHED_LIGHT_BARRIER, SEARCHED_START_POSITION,
};
use crate::config::{Loaded, OptimizeConfig, Problem as ConfigProblem, SearchRange};
use crate::output::csv_bytes;
use divertsim_core::analysis::design::design_set::{DesignEvaluation, DesignSet};
use divertsim_core::analysis::design::robust::{robust_optimize, RobustOptimum, RobustSettings};
use divertsim_core::analysis::design::settings_problem::{Objectives, SettingsProblem, VARIABLES};
use divertsim_core::optimize::cmaes::{self, CmaesSettings};
use divertsim_core::optimize::cobyla::PolishSettings;
use divertsim_core::optimize::de::{self, DeSettings};
use divertsim_core::optimize::ga::{self, GaSettings};
use divertsim_core::optimize::gradient::{self, GradientSettings};
use divertsim_core::optimize::nsga2::{self, FrontPoint, Nsga2Settings};
use divertsim_core::optimize::{
    Bounds, Evaluation, IterationSummary, NoObserver, Observer, OptimizeError, Problem, Record,
    RecordLog, SolverResult,
};
use divertsim_core::run::memo::{self, cached, Memo, NoMemo};
use divertsim_core::sim::Outcome;
use serde_json::{json, Value};

/// Optimisation method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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
    /// The name on every edge (the CLI's `--method`, the JSON and CSV outputs).
    pub fn name(self) -> &'static str {
        match self {
            Method::Ga => "ga",
            Method::Gradient => "gradient",
            Method::De => "de",
            Method::Cmaes => "cmaes",
            Method::Nsga2 => "nsga2",
        }
    }

    /// The method of a [`Method::name`].
    pub fn from_name(name: &str) -> Option<Method> {
        COMPARE_METHODS.into_iter().find(|m| m.name() == name)
    }
}

/// Allowed range of each variable's bounds and values, with its unit.
pub const LIMITS: [(f64, f64, &str); 4] = [
    SEARCHED_BELT_SPEED.ends(),
    SEARCHED_CYCLE_TIME.ends(),
    SEARCHED_START_POSITION.ends(),
    SEARCHED_LIGHT_BARRIER.ends(),
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

pub use divertsim_core::analysis::design::settings_problem::{capacity_of, SYMBOLS, UNITS};

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

/// The allowed range of variable `i` in words: "belt_speed in [0.05, 10] m/s".
pub fn range_help(i: usize) -> String {
    let (lo, hi, unit) = LIMITS[i];
    format!("{} in [{lo}, {hi}] {unit}", VARIABLES[i])
}

/// Whether `setting` is allowed for variable `i`: finite, inside [`LIMITS`], LO ≤ HI.
pub fn allowed(i: usize, setting: &SearchRange) -> bool {
    let inside = |x: f64| x.is_finite() && x >= LIMITS[i].0 && x <= LIMITS[i].1;
    match *setting {
        SearchRange::Range([lo, hi]) => inside(lo) && inside(hi) && lo <= hi,
        SearchRange::Fixed(x) => inside(x),
    }
}

/// The search box over (v, t_c, R_s, S_d): the defaults (the paper's wide box v 1.0–2.3 m/s,
/// t_c 1.0–1.5 s, R_s 0–0.9 m; S_d fixed at the scenario's `light_barrier`) with each
/// (variable index, range or fixed value) of `settings` applied in order, or every problem
/// with them (keyed by the variable's name, each naming its allowed range).
pub fn search_bounds(
    settings: &[(usize, SearchRange)],
    light_barrier: f64,
) -> Result<Bounds, Vec<ConfigProblem>> {
    let mut lower = vec![1.0, 1.0, 0.0, light_barrier];
    let mut upper = vec![2.3, 1.5, 0.9, light_barrier];
    let mut problems = Vec::new();
    for (i, setting) in settings {
        let i = *i;
        if i >= VARIABLES.len() {
            problems.push(ConfigProblem::new(
                "bounds",
                format!(
                    "variable {i}: allowed: 0..{} ({})",
                    VARIABLES.len() - 1,
                    VARIABLES.join(", ")
                ),
            ));
            continue;
        }
        if !allowed(i, setting) {
            let message = match *setting {
                SearchRange::Range([lo, hi]) => {
                    format!("[{lo}, {hi}]: allowed: LO ≤ HI, {}", range_help(i))
                }
                SearchRange::Fixed(x) => format!("{x}: allowed: {}", range_help(i)),
            };
            problems.push(ConfigProblem::new(VARIABLES[i], message));
            continue;
        }
        let (lo, hi) = match *setting {
            SearchRange::Range([lo, hi]) => (lo, hi),
            SearchRange::Fixed(x) => (x, x),
        };
        lower[i] = lo;
        upper[i] = hi;
    }
    if !problems.is_empty() {
        return Err(problems);
    }
    Bounds::new(lower, upper).map_err(|e| vec![ConfigProblem::new("bounds", e.to_string())])
}

/// The scenario file's `[optimize]` search box as (variable index, range or fixed value), in
/// variable order (for [`search_bounds`]).
pub fn file_settings(cfg: &OptimizeConfig) -> Vec<(usize, SearchRange)> {
    [
        cfg.belt_speed,
        cfg.cycle_time,
        cfg.start_position,
        cfg.light_barrier,
    ]
    .into_iter()
    .enumerate()
    .filter_map(|(i, range)| Some((i, range?)))
    .collect()
}

/// A starting point for gradient and CMA-ES from v, t_c, R_s[, S_d] inside `bounds` (S_d
/// defaults to the centre of its range; a fixed variable takes its fixed value), or why not.
pub(crate) fn start_point(values: &[f64], bounds: &Bounds) -> Result<Vec<f64>, String> {
    if !(3..=4).contains(&values.len()) {
        return Err(format!("{} values", values.len()));
    }
    let mut x = bounds.centre();
    for (i, &v) in values.iter().enumerate() {
        if bounds.is_fixed(i) {
            continue;
        }
        if !(v.is_finite() && v >= bounds.lower[i] && v <= bounds.upper[i]) {
            return Err(format!("{} = {v} is outside its bounds", SYMBOLS[i]));
        }
        x[i] = v;
    }
    Ok(x)
}

/// Options of one run as an edge gives them (`None`: the method's default).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunOptions {
    pub population: Option<usize>,
    pub generations: Option<usize>,
    pub budget: Option<usize>,
    pub polish: bool,
    pub seed: u64,
    pub start: Option<Vec<f64>>,
}

/// Problems of a run's options with `method` (keys: `start`, `population`, `generations`,
/// `polish`, `budget`): options that do not apply to the method, the sizes' ranges
/// (population 4–10,000, generations 1–100,000, budget 1–10⁷) and a budget below the
/// population. `no_polish`: the polish was turned off.
pub fn option_problems(method: Method, o: &RunOptions, no_polish: bool) -> Vec<ConfigProblem> {
    let mut p = Vec::new();
    let not_for = |opt: &str, methods: &str| {
        ConfigProblem::new(
            opt,
            format!(
                "does not apply to method {}; allowed with {methods}",
                method.name()
            ),
        )
    };
    let range = |key: &str, v: Option<usize>, lo: usize, hi: usize| {
        v.filter(|v| !(lo..=hi).contains(v))
            .map(|v| ConfigProblem::new(key, format!("{v} is out of range; allowed: {lo} to {hi}")))
    };
    p.extend(range("population", o.population, 4, 10_000));
    p.extend(range("generations", o.generations, 1, 100_000));
    p.extend(range("budget", o.budget, 1, 10_000_000));
    if o.start.is_some() && !matches!(method, Method::Gradient | Method::Cmaes) {
        p.push(not_for("start", "gradient, cmaes"));
    }
    if method == Method::Gradient {
        if o.population.is_some() {
            p.push(not_for("population", "ga, de, cmaes, nsga2"));
        }
        if o.generations.is_some() {
            p.push(not_for("generations", "ga, de, cmaes, nsga2"));
        }
    }
    if no_polish && !matches!(method, Method::De | Method::Cmaes) {
        p.push(not_for("polish", "de, cmaes"));
    }
    if let (Some(b), Some(n)) = (o.budget, o.population) {
        if matches!(method, Method::Ga | Method::De | Method::Nsga2) && b < n {
            p.push(ConfigProblem::new(
                "budget",
                format!("{b} is below the population {n}; allowed: ≥ the population"),
            ));
        }
    }
    p
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

/// The settings of `method` with the options applied.
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

/// The most simulations a plan of runs (method, options) on `bounds` may make (what a work
/// limit counts): each evaluation runs the design set's checks; a robust run repeats the
/// solver and two worst-case searches (and their confirmations) for at most its rounds.
pub fn planned_simulations(
    plan: &[(Method, RunOptions)],
    bounds: &Bounds,
    design: &DesignSet,
    robust: Option<&RobustSettings>,
) -> u64 {
    let solver: u64 = plan
        .iter()
        .map(|(m, o)| {
            planned_evaluations(&method_settings(*m, o), bounds.free_indices().len()) as u64
        })
        .sum::<u64>()
        * design.run_count() as u64;
    match robust {
        None => solver,
        Some(r) => {
            let search = 2 * (1 + r.confirm as u64) * r.search.evaluations as u64;
            r.max_rounds.max(1) as u64 * (solver + search)
        }
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

/// Opens the stream a run's evaluations are also passed to as they are made (an edge's
/// `evaluations-N.csv` beside its checkpoint, a live table): called once at the start of
/// each run with the run's problem, in the order of the runs; `None` streams nothing. The
/// results never depend on it.
pub type OpenStream<'a> = dyn Fn(&SettingsProblem) -> Option<Box<dyn Observer + 'a>> + Sync + 'a;

/// What the runs of one experiment report to and keep their work in: the progress tick
/// (once per evaluation), the memo of finished evaluations (an edge's checkpoint, recalled
/// bit for bit on a resume) and the evaluation streams.
pub struct RunContext<'a> {
    /// Called after each evaluation (and each worst-case search simulation of a robust run).
    pub progress: &'a (dyn Fn() + Sync),
    /// Finished evaluations, keyed by the problem and the point ([`memo::NoMemo`]: none).
    pub memo: &'a dyn Memo,
    /// Opens each run's evaluation stream; `None`: no streams.
    pub stream: Option<&'a OpenStream<'a>>,
}

impl<'a> RunContext<'a> {
    /// Progress only: nothing kept, nothing streamed.
    pub fn new(progress: &'a (dyn Fn() + Sync)) -> Self {
        RunContext {
            progress,
            memo: &NoMemo,
            stream: None,
        }
    }
}

/// The evaluation log of a run, each record also passed to its stream as it arrives.
struct StreamedLog<'a> {
    log: RecordLog,
    stream: Option<Box<dyn Observer + 'a>>,
}

impl Observer for StreamedLog<'_> {
    fn record(&mut self, r: &Record) {
        self.log.record(r);
        if let Some(s) = &mut self.stream {
            s.record(r);
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
    SettingsProblem::new(
        loaded.scenario.clone(),
        loaded.design.clone(),
        bounds.clone(),
        objectives_of(method),
    )
}

/// What a method optimises: capacity only, or the trade-off for NSGA-II.
fn objectives_of(method: Method) -> Objectives {
    if method == Method::Nsga2 {
        Objectives::TradeOff
    } else {
        Objectives::Capacity
    }
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
    /// Wall time \[s].
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
        stream: ctx.stream.and_then(|open| open(problem)),
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

// ---------------------------------------------------------------------------------------------
// Tidy tables and JSON summaries.

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
    csv_bytes(&header, &rows)
}

/// The columns of evaluations.csv (also the header of a live evaluation stream).
pub fn evaluation_header(problem: &SettingsProblem) -> Vec<String> {
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

/// One row of evaluations.csv; `trade_off`: the problem is NSGA-II's
/// ([`Objectives::TradeOff`]), whose rows carry the overload ratio and divert reserve.
pub fn evaluation_row(trade_off: bool, r: &Record) -> Vec<String> {
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
    csv_bytes(
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
    csv_bytes(
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

/// The best point of a run as JSON: the point, W, feasibility, each constraint g, the active
/// ones, the worst parcel, the overload ratio S/S_fall and every design case.
pub fn best_json(b: &BestReport) -> Value {
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

/// The search box as JSON: {variable: [lower, upper]}.
pub fn bounds_json(b: &Bounds) -> Value {
    let mut m = serde_json::Map::new();
    for (i, name) in VARIABLES.iter().enumerate() {
        m.insert(name.to_string(), json!([b.lower[i], b.upper[i]]));
    }
    Value::Object(m)
}

/// report.json of one run (the CLI's `--json` too): the method and its settings, the box,
/// the best point explained, the counts, NSGA-II's front, the worst-case definition and the
/// margins of `design` (the scenario's design set, as given), and the rounds of a robust
/// run (`problem` is then its last round's).
pub fn report_json(
    problem: &SettingsProblem,
    run: &RunOutcome,
    best: &BestReport,
    design: &DesignSet,
    robust: Option<&RobustRun>,
) -> Value {
    let r = &run.result;
    let mut report = json!({
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
    });
    report["worst"] = json!(design.worst.label());
    report["margins"] = json!({
        "overload": design.margins.overload,
        "divert": design.margins.divert,
    });
    if let Some(rr) = robust {
        report["robust"] = robust_json(problem, rr);
    }
    report
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
            paper_box(b),
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
            paper_box(PAPER_WIDE),
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

/// A paper box for (v, t_c, R_s), S_d fixed at 0.
fn paper_box(b: [(f64, f64); 3]) -> Bounds {
    Bounds::new(
        vec![b[0].0, b[1].0, b[2].0, 0.0],
        vec![b[0].1, b[1].1, b[2].1, 0.0],
    )
    .expect("valid constant box")
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

/// The design evaluation of the paper's proposed setting ([`PAPER_PROPOSED`], S_d = 0) on
/// this scenario (one evaluation, not counted in any run).
pub fn paper_point(loaded: &Loaded) -> Result<DesignEvaluation, OptimizeError> {
    let problem = settings_problem(loaded, &paper_box(PAPER_WIDE), Method::Ga)?;
    let x = [PAPER_PROPOSED[0], PAPER_PROPOSED[1], PAPER_PROPOSED[2], 0.0];
    Ok(problem.design_evaluation(&x))
}

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
    csv_bytes(
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
    let mut rng = divertsim_core::stats::splitmix::SplitMix64(
        seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03,
    );
    let mut next = || rng.next_f64();
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
    let runs = csv_bytes(
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
    let medians = csv_bytes(
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

// ---------------------------------------------------------------------------------------------
// Settings that hold against the searched worst case.

/// The robust rounds of a single run against the searched worst case (a design set with
/// `WorstDefinition::Search`).
pub struct RobustRun {
    pub optimum: RobustOptimum,
    pub settings: RobustSettings,
}

/// Optimise against the searched worst case: rounds of `run_method` and a worst-case search
/// at its best point ([`robust_optimize`]). `new_round` is called before each round's solver
/// run (an edge's progress bar grows by a round). Returns the last round's problem and run.
pub fn run_robust(
    loaded: &Loaded,
    bounds: &Bounds,
    method: Method,
    settings: &MethodSettings,
    robust: &RobustSettings,
    ctx: &RunContext<'_>,
    new_round: &dyn Fn(),
) -> Result<(SettingsProblem, RunOutcome, RobustRun), OptimizeError> {
    let objectives = objectives_of(method);
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

/// The names of the worst-pose constraints that are active at the last round's best point
/// (its evaluation is in the solver's result: `problem` is that round's).
pub fn active_poses(problem: &SettingsProblem, rr: &RobustRun) -> Vec<String> {
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

// ---------------------------------------------------------------------------------------------
// Checking settings before any simulation.

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
    /// A wrongly shaped evaluation: the solver has passed its own checks by the time it
    /// evaluates, and the shape error stops it at its first batch, so the dry run costs
    /// one population whatever the generations (a full dry run of 10⁴ × 10⁴ allocated
    /// gigabytes before the work limit was checked).
    fn evaluate(&self, _: &[f64]) -> Evaluation {
        Evaluation {
            objectives: Vec::new(),
            constraints: Vec::new(),
        }
    }
}

/// Validate a method's settings before any simulation: start the solver on a free stand-in
/// problem of the same shape as `problem`, so that its own checks (population, budget,
/// start, ...) report at once, and stop it at its first evaluation. An `InvalidSetting`
/// error names the solver setting (`population`, `max_evaluations`, `start`, ...).
pub fn dry_check(
    problem: &SettingsProblem,
    settings: &MethodSettings,
) -> Result<(), OptimizeError> {
    let free = Free {
        bounds: problem.bounds(),
        objectives: problem.objective_count(),
        constraints: problem.constraint_count(),
    };
    let mut none = NoObserver;
    let started = match settings {
        MethodSettings::Ga(s) => ga::solve(&free, s, &mut none).map(|_| ()),
        MethodSettings::Gradient(s) => gradient::solve(&free, s, &mut none).map(|_| ()),
        MethodSettings::De(s) => de::solve(&free, s, &mut none).map(|_| ()),
        MethodSettings::Cmaes(s) => cmaes::solve(&free, s, &mut none).map(|_| ()),
        MethodSettings::Nsga2(s) => nsga2::solve(&free, s, &mut none).map(|_| ()),
    };
    match started {
        // The stand-in's shape error: the settings passed every check.
        Err(OptimizeError::EvaluationShape { .. }) => Ok(()),
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_numeric_bounds() {
        assert_eq!(variable_index("v"), Some(0));
        assert_eq!(variable_index("light_barrier"), Some(3));
        assert_eq!(variable_index("x"), None);
        assert_eq!(Method::from_name("cmaes"), Some(Method::Cmaes));
        assert_eq!(Method::from_name("sa"), None);
        let b = search_bounds(&[], 0.2).unwrap();
        assert_eq!(b.lower, vec![1.0, 1.0, 0.0, 0.2]);
        assert_eq!(b.upper, vec![2.3, 1.5, 0.9, 0.2]);
        let b = search_bounds(
            &[
                (0, SearchRange::Range([1.5, 2.0])),
                (3, SearchRange::Range([-0.1, 0.3])),
                (1, SearchRange::Fixed(1.3)),
            ],
            0.0,
        )
        .unwrap();
        assert_eq!(b.lower, vec![1.5, 1.3, 0.0, -0.1]);
        assert_eq!(b.upper, vec![2.0, 1.3, 0.9, 0.3]);
        for bad in [[2.0, 1.0], [0.0, 1.0], [1.0, 20.0], [f64::NAN, 1.0]] {
            let e = search_bounds(&[(0, SearchRange::Range(bad))], 0.0).unwrap_err();
            assert_eq!(e[0].key, "belt_speed", "{bad:?}");
        }
        let e = search_bounds(
            &[(2, SearchRange::Fixed(9.0)), (7, SearchRange::Fixed(1.0))],
            0.0,
        )
        .unwrap_err();
        assert_eq!(e.len(), 2);
        assert!(e[0].message.contains("[-5, 5] m"), "{}", e[0].message);
        let cfg = OptimizeConfig {
            belt_speed: Some(SearchRange::Range([1.2, 2.0])),
            light_barrier: Some(SearchRange::Fixed(-0.2)),
            ..OptimizeConfig::default()
        };
        let b = search_bounds(&file_settings(&cfg), 0.0).unwrap();
        assert_eq!(b.lower, vec![1.2, 1.0, 0.0, -0.2]);
        assert_eq!(b.upper, vec![2.0, 1.5, 0.9, -0.2]);
    }

    #[test]
    fn starts_and_medians() {
        let b = search_bounds(&[], 0.0).unwrap();
        assert_eq!(
            start_point(&[1.8, 1.5, 0.5], &b).unwrap(),
            vec![1.8, 1.5, 0.5, 0.0]
        );
        assert!(start_point(&[1.8, 1.5], &b).is_err());
        assert!(start_point(&[3.0, 1.5, 0.5], &b).is_err());
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
