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

mod compare;
mod dry_check;
pub mod line;
pub mod options;
mod paper;
mod robust;
mod tables;
pub use compare::*;
pub use dry_check::*;
pub use paper::*;
pub use robust::*;
pub use tables::*;
pub mod text;
pub use options::{Optimize, OptimizeOptions, OptimizeResult};

use std::time::Instant;

use crate::analyses::poses::pose_json;
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

/// Problems with a run's sizes, whatever the method or experiment (keys `population`,
/// `generations`, `budget`): population 4–10,000, generations 1–100,000, budget 1–10⁷.
pub fn size_problems(o: &RunOptions) -> Vec<ConfigProblem> {
    let range = |key: &str, v: Option<usize>, lo: usize, hi: usize| {
        v.filter(|v| !(lo..=hi).contains(v))
            .map(|v| ConfigProblem::new(key, format!("{v} is out of range; allowed: {lo} to {hi}")))
    };
    [
        range("population", o.population, 4, 10_000),
        range("generations", o.generations, 1, 100_000),
        range("budget", o.budget, 1, 10_000_000),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// Problems of a run's options with `method` (keys: `start`, `population`, `generations`,
/// `polish`, `budget`): options that do not apply to the method, the sizes' ranges
/// (population 4–10,000, generations 1–100,000, budget 1–10⁷) and a budget below the
/// population. `no_polish`: the polish was turned off.
pub fn option_problems(method: Method, o: &RunOptions, no_polish: bool) -> Vec<ConfigProblem> {
    let mut p = size_problems(o);
    let not_for = |opt: &str, methods: &str| {
        ConfigProblem::new(
            opt,
            format!(
                "does not apply to method {}; allowed with {methods}",
                method.name()
            ),
        )
    };
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
struct Ticking<'a, P> {
    inner: &'a P,
    tick: &'a (dyn Fn() + Sync),
    memo: &'a dyn Memo,
    /// The key of the problem (its scenario, bounds, objectives and constraints).
    id: u64,
}

impl<P: Problem> Problem for Ticking<'_, P> {
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
    let stream = ctx.stream.and_then(|open| open(problem));
    solve(problem, settings, ctx.progress, ctx.memo, stream)
}

/// Run one method on any problem: `progress` ticks once per evaluation, `memo` keeps each
/// evaluation under the problem's key (its `Debug` text: everything that shapes its
/// values), `stream` sees each record as it is made.
pub(crate) fn solve<'a, P: Problem + std::fmt::Debug>(
    problem: &P,
    settings: &MethodSettings,
    progress: &(dyn Fn() + Sync),
    memo: &dyn Memo,
    stream: Option<Box<dyn Observer + 'a>>,
) -> Result<RunOutcome, OptimizeError> {
    let started = Instant::now();
    let p = Ticking {
        inner: problem,
        tick: progress,
        memo,
        id: memo::key("optimize problem", problem),
    };
    let mut log = StreamedLog {
        log: RecordLog::default(),
        stream,
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
