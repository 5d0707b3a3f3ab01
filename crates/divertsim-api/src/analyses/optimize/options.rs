//! The optimisation on the analysis contract ([`crate::contract`]): one options type for its
//! three experiments (one run of a method, the paper's experiment, every method compared),
//! checked once; the search box is the scenario's `[optimize]` section with the options'
//! bounds over it, checked against the scenario before any simulation.

use std::collections::BTreeMap;

use super::line::{run_line, LineObjective, LineOptimum, LineSearch};
use super::{
    best_report, compare, compare_csv, compare_json, compare_plan, dry_check, evaluation_header,
    evaluation_row, evaluations_csv, file_settings, front_csv, history_csv, method_settings,
    paper_csv, paper_experiment, paper_json, paper_plan, paper_point, planned_evaluations,
    planned_simulations, range_help, report_json, run_method, run_robust, search_bounds,
    settings_problem, start_point, text, variable_index, BestReport, CompareRow, Method, PaperRun,
    RobustRun, RunContext, RunOptions, RunOutcome, SYMBOLS, UNITS,
};
use crate::analyses::worst_case::{RobustOptions, WorstChoice};
use crate::config::{Loaded, Problem, SearchRange};
use crate::contract::{csv_table, Analysis, Error, Hooks, LiveLog, Work};
use divertsim_core::analysis::design::design_set::{DesignEvaluation, Margins, WorstDefinition};
use divertsim_core::analysis::design::robust::RobustSettings;
use divertsim_core::analysis::design::settings_problem::{Objectives, SettingsProblem, VARIABLES};
use divertsim_core::optimize::{Bounds, Observer, OptimizeError, Record};
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// The search box as given: `NAME=LO:HI` (a range) or `NAME=VALUE` (a fixed value) texts, or
/// a mapping of names to `[lo, hi]` or a number.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum BoundsSpec {
    /// `NAME=LO:HI` or `NAME=VALUE` texts, applied in order.
    Texts(Vec<String>),
    /// Names to `[lo, hi]` or a number.
    Map(BTreeMap<String, Value>),
}

impl Default for BoundsSpec {
    fn default() -> BoundsSpec {
        BoundsSpec::Texts(Vec::new())
    }
}

impl schemars::JsonSchema for BoundsSpec {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "BoundsSpec".into()
    }

    fn inline_schema() -> bool {
        true
    }

    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "anyOf": [
                {"type": "array", "items": {"type": "string"}},
                {"type": "object", "additionalProperties": {"anyOf": [
                    {"type": "number"},
                    {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2}
                ]}}
            ],
            // Given once per range on the command line.
            "x-repeat": true
        })
    }
}

const NAMES: &str =
    "NAME one of belt_speed|v, cycle_time|t_c, start_position|R_s, light_barrier|S_d";

/// Options of the optimisation (`divertsim optimize`, Python `optimize`).
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are help text: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct OptimizeOptions {
    /// Optimisation method: ga (the paper's genetic algorithm), gradient (the paper's
    /// penalised steepest descent), de (differential evolution + COBYLA polish; the
    /// default), cmaes (CMA-ES + COBYLA polish) or nsga2 (the trade-off capacity / overload
    /// ratio / divert reserve).
    #[schemars(extend("enum" = ["ga", "gradient", "de", "cmaes", "nsga2"]))]
    pub method: Option<String>,
    /// Search range of a variable, NAME=LO:HI (or NAME=VALUE to fix it) with NAME one of
    /// belt_speed|v, cycle_time|t_c, start_position|R_s, light_barrier|S_d; or a mapping of
    /// names to [lo, hi] or a value. Over the scenario's [optimize] section, variable by
    /// variable. Defaults: v 1.0:2.3 m/s, t_c 1.0:1.5 s, R_s 0:0.9 m, S_d fixed at the
    /// scenario's light_barrier.
    #[schemars(extend("x-flag" = "bound", "x-value" = "NAME=LO:HI"))]
    pub bounds: BoundsSpec,
    /// Fix a variable, NAME=VALUE (same names as `bounds`); after the ranges.
    #[schemars(extend("x-value" = "NAME=VALUE"))]
    pub fix: Vec<String>,
    /// Starting point v,t_c,R_s[,S_d] for gradient and cmaes (default: the centre of the
    /// bounds); S_d defaults to the centre of its range.
    #[schemars(extend("x-value" = "V,T_C,R_S[,S_D]"))]
    pub start: Option<Vec<f64>>,
    /// Random seed (ga, de, cmaes, nsga2); the first seed with `compare`.
    pub seed: u64,
    /// Population size (ga, de, nsga2; λ of cmaes), 4 to 10000.
    #[schemars(extend("x-value" = "N"))]
    pub population: Option<u64>,
    /// Generations after the initial one (ga, de, nsga2; cmaes: maximum generations), 1 to
    /// 100000.
    #[schemars(extend("x-value" = "N"))]
    pub generations: Option<u64>,
    /// Evaluation budget (every method; with `compare` and `paper_experiment` a cap on each
    /// run), 1 to 10000000.
    #[schemars(extend("x-value" = "N"))]
    pub budget: Option<u64>,
    /// The COBYLA polish after de and cmaes.
    pub polish: bool,
    /// Run the paper's experiment (3 GA runs, 3 gradient runs; bounds as in the paper, S_d
    /// fixed 0). `population` and `generations` apply to the GA runs, `budget` to every run.
    pub paper_experiment: bool,
    /// Compare ga, gradient, de, cmaes and nsga2 over `seeds` seeds on the same problem
    /// (`population` and `generations` apply to ga and nsga2, `budget` caps every run).
    pub compare: bool,
    /// Number of seeds of `compare` (seeds `seed`, `seed` + 1, ...), 1 to 100.
    #[schemars(extend("x-value" = "N"))]
    pub seeds: u64,
    /// What to maximise: capacity (the paper's W, every [design] parcel diverted and the
    /// worst strike below the free fall) or line (the parcels per hour the scenario's
    /// [line] correctly diverts, measured over `parcels` parcels, the same ones at every
    /// point, with the missort and overload rates within `max_missort` and
    /// `max_overload`; methods de, ga, cmaes).
    #[schemars(extend("enum" = ["capacity", "line"]))]
    pub objective: String,
    /// Parcels of every line evaluation (objective line; default 2000), 10 to 10000000.
    #[schemars(extend("x-value" = "N"))]
    pub parcels: Option<u64>,
    /// Seed of the line's parcel stream (objective line; default: mix.seed, else 1).
    #[schemars(extend("x-value" = "SEED"))]
    pub stream_seed: Option<u64>,
    /// Largest missort rate allowed, a fraction of the parcels not ending where they were
    /// bound (objective line; default 0.001, i.e. 0.1 %), 0 to 1.
    #[schemars(extend("x-value" = "RATE"))]
    pub max_missort: Option<f64>,
    /// Largest overload rate allowed, a fraction of the parcels struck harder than the free
    /// fall from 0.3 m (objective line; default 0.01, i.e. 1 %), 0 to 1.
    #[schemars(extend("x-value" = "RATE"))]
    pub max_overload: Option<f64>,
    #[serde(flatten)]
    #[allow(missing_docs)]
    pub robust: RobustOptions,
}

impl Default for OptimizeOptions {
    fn default() -> OptimizeOptions {
        OptimizeOptions {
            method: None,
            bounds: BoundsSpec::default(),
            fix: Vec::new(),
            start: None,
            seed: 1,
            population: None,
            generations: None,
            budget: None,
            polish: true,
            paper_experiment: false,
            compare: false,
            seeds: 5,
            objective: "capacity".into(),
            parcels: None,
            stream_seed: None,
            max_missort: None,
            max_overload: None,
            robust: RobustOptions::default(),
        }
    }
}

/// The experiment of one optimisation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Experiment {
    /// One run of a method.
    Single(Method),
    /// The paper's three GA and three gradient runs.
    Paper,
    /// Every method over this many seeds.
    Compare(u64),
    /// One run of a method on the line's throughput ([`super::line`]), measured and bounded
    /// as the objective says.
    Line(Method, LineObjective),
}

/// A search box and the runs (method, options) on it.
pub type BoxAndRuns = (Bounds, Vec<(Method, RunOptions)>);

/// Checked options: everything that shapes the result but the scenario.
#[derive(Debug, Clone)]
pub struct OptimizeInputs {
    pub experiment: Experiment,
    /// The variables the options set, over the scenario's `[optimize]` box.
    pub given: Vec<(usize, SearchRange)>,
    /// The starting point as given (checked against the box with the scenario).
    pub start: Option<Vec<f64>>,
    /// The run's options (its start resolved with the scenario).
    pub run: RunOptions,
    pub worst: WorstDefinition,
    pub margins: Margins,
    /// Rounds against the searched worst case (`worst` search).
    pub robust: Option<RobustSettings>,
}

/// The checked options bound to a scenario ([`Analysis::bind`]): with the search box and
/// the runs on it.
#[derive(Debug, Clone)]
pub struct BoundOptimize {
    pub inputs: OptimizeInputs,
    pub bounds: Bounds,
    /// The runs (method, options) on `bounds`, their starts resolved.
    pub plan: Vec<(Method, RunOptions)>,
}

impl OptimizeInputs {
    /// The line objective, with the line experiment.
    fn line(&self) -> Option<LineObjective> {
        match self.experiment {
            Experiment::Line(_, o) => Some(o),
            _ => None,
        }
    }
}

/// The line objective of the options (objective line), or `None`; every problem with its
/// options pushed onto `problems`, keyed by option.
fn line_objective(
    o: &OptimizeOptions,
    method: Method,
    problems: &mut Vec<Problem>,
) -> Option<LineObjective> {
    let line = match o.objective.as_str() {
        "capacity" => false,
        "line" => true,
        other => {
            problems.push(Problem::new(
                "objective",
                format!("'{other}' is not an objective; allowed: capacity, line"),
            ));
            false
        }
    };
    if !line {
        for (key, given) in [
            ("parcels", o.parcels.is_some()),
            ("stream_seed", o.stream_seed.is_some()),
            ("max_missort", o.max_missort.is_some()),
            ("max_overload", o.max_overload.is_some()),
        ] {
            if given {
                problems.push(Problem::new(
                    key,
                    "applies only with objective line; allowed there: see `objective`",
                ));
            }
        }
        return None;
    }
    for (option, given) in [
        ("paper_experiment", o.paper_experiment),
        ("compare", o.compare),
    ] {
        if given {
            problems.push(Problem::new(
                option,
                "does not apply with objective line (one run of de, ga or cmaes)",
            ));
        }
    }
    if !super::line::LINE_METHODS.contains(&method) {
        problems.push(Problem::new(
            "method",
            format!(
                "{} does not search the line; allowed with objective line: de, ga, cmaes (the line's objective moves in steps of one parcel, which a gradient does not see)",
                method.name()
            ),
        ));
    }
    if o.robust != RobustOptions::default() {
        problems.push(Problem::new(
            "worst",
            "the worst-case options (worst, margin, scatter, rounds, the search budget) do not apply with objective line: its constraints are the line's missort and overload rates",
        ));
    }
    let parcels = o.parcels.unwrap_or(super::line::LINE_PARCELS);
    if !(10..=10_000_000).contains(&parcels) {
        problems.push(Problem::new(
            "parcels",
            format!("{parcels} is out of range; allowed: 10 to 10000000"),
        ));
    }
    let mut rate = |key: &str, v: Option<f64>, default: f64| {
        let v = v.unwrap_or(default);
        if !(0.0..=1.0).contains(&v) {
            problems.push(Problem::new(
                key,
                format!("{v} is out of range; allowed: 0 to 1 (a fraction of the parcels)"),
            ));
        }
        v
    };
    Some(LineObjective {
        parcels,
        seed: o.stream_seed,
        max_missort: rate("max_missort", o.max_missort, super::line::MAX_MISSORT),
        max_overload: rate("max_overload", o.max_overload, super::line::MAX_OVERLOAD),
    })
}

/// One range or fixed value of a text `NAME=LO:HI` / `NAME=VALUE`, or the problem with it
/// (keyed `key`).
fn setting_of_text(key: &str, text: &str) -> Result<(usize, SearchRange), Problem> {
    let bad = |why: &str| {
        Problem::new(
            key,
            format!(
                "'{text}': {why}; allowed: NAME=LO:HI or NAME=VALUE with {NAMES}, LO ≤ HI and v, t_c in [0.05 or 0.2, 10], R_s, S_d in [-5, 5] m"
            ),
        )
    };
    let (name, value) = text
        .split_once('=')
        .ok_or_else(|| bad("expected NAME=LO:HI"))?;
    let i =
        variable_index(name).ok_or_else(|| bad(&format!("unknown variable '{}'", name.trim())))?;
    let parts: Vec<f64> = value
        .split(':')
        .map(|s| s.trim().parse::<f64>().unwrap_or(f64::NAN))
        .collect();
    let setting = match parts[..] {
        [x] => SearchRange::Fixed(x),
        [lo, hi] => SearchRange::Range([lo, hi]),
        _ => return Err(bad("expected NAME=LO:HI")),
    };
    checked_setting(i, setting)
        .map_err(|why| Problem::new(key, format!("'{text}': allowed: {}={why}", name.trim())))
}

/// A setting inside the variable's allowed range, or the allowed range in words.
fn checked_setting(i: usize, setting: SearchRange) -> Result<(usize, SearchRange), String> {
    match super::allowed(i, &setting) {
        true => Ok((i, setting)),
        false => Err(match setting {
            SearchRange::Range(_) => format!("LO:HI with LO ≤ HI, {}", range_help(i)),
            SearchRange::Fixed(_) => format!("VALUE, {}", range_help(i)),
        }),
    }
}

/// The variables `bounds` and `fix` set, ranges first, or every problem with them.
fn given_settings(o: &OptimizeOptions, problems: &mut Vec<Problem>) -> Vec<(usize, SearchRange)> {
    let mut ranges = Vec::new();
    match &o.bounds {
        BoundsSpec::Texts(texts) => {
            for t in texts {
                match setting_of_text("bounds", t) {
                    Ok(s) => ranges.push(s),
                    Err(p) => problems.push(p),
                }
            }
        }
        BoundsSpec::Map(m) => {
            for (name, v) in m {
                let key = format!("bounds.{name}");
                let Some(i) = variable_index(name) else {
                    problems.push(Problem::new(
                        key,
                        format!(
                            "'{name}' is not a variable; allowed: {}",
                            VARIABLES.join(", ")
                        ),
                    ));
                    continue;
                };
                let setting = match v {
                    Value::Number(n) => n.as_f64().map(SearchRange::Fixed),
                    Value::Array(a) if a.len() == 2 => match (a[0].as_f64(), a[1].as_f64()) {
                        (Some(lo), Some(hi)) => Some(SearchRange::Range([lo, hi])),
                        _ => None,
                    },
                    _ => None,
                };
                match setting.map(|s| checked_setting(i, s)) {
                    Some(Ok(s)) => ranges.push(s),
                    Some(Err(why)) => problems.push(Problem::new(key, format!("allowed: {why}"))),
                    None => problems.push(Problem::new(key, "expected [lo, hi] or a number")),
                }
            }
        }
    }
    // Fixes come after the ranges: a fix of a variable also given a range wins.
    let mut fixes = Vec::new();
    for f in &o.fix {
        match setting_of_text("fix", f) {
            Ok((i, SearchRange::Fixed(x))) => fixes.push((i, SearchRange::Fixed(x))),
            Ok(_) => problems.push(Problem::new(
                "fix",
                format!("'{f}': expected NAME=VALUE with {NAMES}"),
            )),
            Err(p) => problems.push(p),
        }
    }
    ranges.extend(fixes);
    ranges
}

impl OptimizeInputs {
    /// The scenario with the definition of the worst case and the margins chosen here.
    pub fn designed(&self, loaded: &Loaded) -> Loaded {
        let mut l = loaded.clone();
        l.design.worst = self.worst;
        l.design.margins = self.margins;
        l
    }

    /// The search box: the scenario's `[optimize]` section (its problems keyed
    /// `optimize.NAME`), each variable the options set replacing the file's.
    pub fn bounds(&self, loaded: &Loaded) -> Result<Bounds, Vec<Problem>> {
        let lb = loaded.scenario.machine.light_barrier;
        let file = file_settings(&loaded.file.optimize);
        search_bounds(&file, lb).map_err(|p| {
            p.into_iter()
                .map(|p| Problem::new(format!("optimize.{}", p.key), p.message))
                .collect::<Vec<_>>()
        })?;
        let mut settings: Vec<(usize, SearchRange)> = file
            .into_iter()
            .filter(|(i, _)| !self.given.iter().any(|(j, _)| j == i))
            .collect();
        settings.extend(self.given.iter().cloned());
        search_bounds(&settings, lb).map_err(|p| {
            p.into_iter()
                .map(|p| Problem::new("bounds", p.message))
                .collect()
        })
    }

    /// The search box and the runs on it, on `loaded` (the scenario with this run's worst
    /// case and margins).
    fn bounds_and_plan(&self, loaded: &Loaded) -> Result<BoxAndRuns, Vec<Problem>> {
        let bounds = self.bounds(loaded)?;
        let plan = self.plan(&bounds).map_err(|p| vec![p])?;
        Ok((bounds, plan))
    }

    /// The runs (method, options) on `bounds`, the start resolved.
    fn plan(&self, bounds: &Bounds) -> Result<Vec<(Method, RunOptions)>, Problem> {
        Ok(match self.experiment {
            Experiment::Paper => paper_plan(&self.run)
                .into_iter()
                .map(|(_, _, m, _, o)| (m, o))
                .collect(),
            Experiment::Compare(seeds) => compare_plan(bounds, &self.run, seeds)
                .into_iter()
                .map(|(m, _, o)| (m, o))
                .collect(),
            Experiment::Single(m) | Experiment::Line(m, _) => {
                let start = match &self.start {
                    None => None,
                    Some(v) => {
                        Some(start_point(v, bounds).map_err(|why| start_problem(v, why, bounds))?)
                    }
                };
                vec![(
                    m,
                    RunOptions {
                        start,
                        ..self.run.clone()
                    },
                )]
            }
        })
    }
}

fn start_problem(values: &[f64], why: String, bounds: &Bounds) -> Problem {
    let ranges: Vec<String> = (0..4)
        .map(|i| {
            format!(
                "{} in [{}, {}] {}",
                SYMBOLS[i], bounds.lower[i], bounds.upper[i], UNITS[i]
            )
        })
        .collect();
    let given: Vec<String> = values.iter().map(f64::to_string).collect();
    Problem::new(
        "start",
        format!(
            "'{}': {why}; allowed: v,t_c,R_s[,S_d] inside the bounds: {}",
            given.join(","),
            ranges.join(", ")
        ),
    )
}

/// The option a solver's refused setting comes from.
fn option_of(e: &OptimizeError) -> &'static str {
    match e {
        OptimizeError::InvalidSetting { name, .. } => match *name {
            "max_evaluations" => "budget",
            "population" => "population",
            "start" => "start",
            _ => "generations",
        },
        _ => "bounds",
    }
}

/// The result of one optimisation, by experiment.
pub enum OptimizeResult {
    /// One run: its (last round's) problem, the run, its best point, and the robust rounds.
    Single {
        problem: Box<SettingsProblem>,
        run: Box<RunOutcome>,
        best: Box<BestReport>,
        robust: Option<Box<RobustRun>>,
        /// The design set as solved (its worst-case definition and margins, for the report).
        design: Box<divertsim_core::analysis::design::design_set::DesignSet>,
        /// optimum.toml: the scenario at the best point, standing alone.
        optimum_toml: String,
    },
    /// The paper's experiment: the runs, their problems, and the paper's proposed point.
    Paper {
        runs: Vec<PaperRun>,
        problems: Vec<SettingsProblem>,
        point: Box<DesignEvaluation>,
    },
    /// The comparison: a row per run, the best feasible capacity found, the box.
    Compare {
        rows: Vec<CompareRow>,
        best_known: f64,
        bounds: Bounds,
    },
    /// One run on the line's throughput.
    Line(Box<LineOptimum>),
}

/// Each run's evaluations written to a live log `evaluations-N.csv` (N counting the runs)
/// as they arrive; a convenience while a long run goes, the results do not depend on it.
struct Streams<'a> {
    live: Option<&'a LiveLog>,
    runs: std::sync::atomic::AtomicUsize,
}

impl<'a> Streams<'a> {
    /// The next run's stream of the design-set problem.
    fn open(&self, problem: &SettingsProblem) -> Option<Box<dyn Observer + 'a>> {
        let trade_off = problem.objectives() == Objectives::TradeOff;
        self.open_with(
            evaluation_header(problem),
            Box::new(move |r| evaluation_row(trade_off, r)),
        )
    }

    /// The next run's stream: `header`, then a row per record.
    fn open_with(&self, header: Vec<String>, row: RowOf<'a>) -> Option<Box<dyn Observer + 'a>> {
        let n = self.runs.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let file: Box<dyn std::io::Write> = (self.live?)(&format!("evaluations-{n}.csv"))?;
        let mut w = csv::Writer::from_writer(file);
        w.write_record(header).ok()?;
        w.flush().ok()?;
        Some(Box::new(CsvStream {
            writer: Some(w),
            row,
        }))
    }
}

/// A record's row of a CSV stream.
type RowOf<'a> = Box<dyn Fn(&Record) -> Vec<String> + 'a>;

/// One run's evaluations, each written as it arrives (the stream stops at the first error).
struct CsvStream<'a> {
    writer: Option<csv::Writer<Box<dyn std::io::Write>>>,
    row: RowOf<'a>,
}

impl Observer for CsvStream<'_> {
    fn record(&mut self, r: &Record) {
        if let Some(w) = &mut self.writer {
            let row = (self.row)(r);
            if w.write_record(&row).and_then(|_| Ok(w.flush()?)).is_err() {
                self.writer = None;
            }
        }
    }
}

/// The scenario file at the best point of a run (v, t_c, R_s, S_d set; everything else the
/// scenario's), standing alone: `simulate` and every analysis run it directly.
pub fn optimum_toml(
    file: &crate::config::ScenarioFile,
    best: &BestReport,
) -> Result<String, Error> {
    let mut f = crate::config::standalone(file);
    f.machine.belt_speed = best.x[0];
    f.machine.cycle_time = best.x[1];
    f.machine.start_position = best.x[2];
    // An infeasible best point may put S_d past R_s, which a file may not state; S_d does not
    // change a run (only the capacity).
    f.machine.light_barrier = best.x[3].min(best.x[2]);
    // The class the optimum holds against, stated: without a height band of its own the
    // search kept the scenario parcel's height, so the file says so, and `check`,
    // `reliability` and the optimisers judge it by the same parcels (issue 50, item 2).
    let class_stated = f.design.search.height.is_none();
    if class_stated {
        f.design.search.height = Some([f.parcel.height; 2]);
    }
    let verdict = match best.feasible {
        true => "feasible".to_string(),
        false => format!("INFEASIBLE, constraint violation {:.4}", best.violation),
    };
    crate::config::to_toml(
        &f,
        &format!(
            "Written by `divertsim optimize`: the best point found, W = {:.1} parcels/h ({verdict}):\nv = {} m/s, t_c = {} s, R_s = {} m, S_d = {} m. `divertsim simulate` runs this file directly.{}",
            best.capacity,
            best.x[0],
            best.x[1],
            best.x[2],
            best.x[3],
            if class_stated {
                format!(
                    "\nThe class it holds against is the scenario's, at one height: [design.search] height = [{h}, {h}]\n(parcel.height), which a mix without heights of its own follows. Give [design.search] height\nto optimise for taller parcels, which can tip over.",
                    h = f.parcel.height
                )
            } else {
                String::new()
            }
        ),
    )
}

/// The optimisation on the analysis contract.
pub struct Optimize;

impl Analysis for Optimize {
    const NAME: &'static str = "optimize";
    const ABOUT: &'static str = "Optimise the machine settings (v, t_c, R_s, S_d) for capacity under the divert and overload constraints (paper §4.3), or, with `objective` line, for the parcels per hour a [line] correctly diverts under limits on its missort and overload rates";
    type Options = OptimizeOptions;
    type Checked = OptimizeInputs;
    type Bound = BoundOptimize;
    type Output = OptimizeResult;

    fn validate(o: &OptimizeOptions) -> Result<OptimizeInputs, Vec<Problem>> {
        let mut problems = Vec::new();
        let method = match o.method.as_deref() {
            None => Method::De,
            Some(name) => Method::from_name(name).unwrap_or_else(|| {
                problems.push(Problem::new(
                    "method",
                    format!("'{name}' is not a method; allowed: ga, gradient, de, cmaes, nsga2"),
                ));
                Method::De
            }),
        };
        let batch = o.paper_experiment || o.compare;
        let mut not_with = |option: &str, given: bool, mode: &str| {
            if given {
                problems.push(Problem::new(option, format!("does not apply to `{mode}`")));
            }
        };
        let texts_given = !matches!(&o.bounds, BoundsSpec::Texts(t) if t.is_empty())
            && !matches!(&o.bounds, BoundsSpec::Map(m) if m.is_empty());
        if o.paper_experiment {
            not_with("method", o.method.is_some(), "paper_experiment");
            not_with("bounds", texts_given, "paper_experiment");
            not_with("fix", !o.fix.is_empty(), "paper_experiment");
            not_with("start", o.start.is_some(), "paper_experiment");
            not_with("compare", o.compare, "paper_experiment");
            if !o.polish {
                problems.push(Problem::new(
                    "polish",
                    "does not apply to `paper_experiment` (GA and gradient have no polish)",
                ));
            }
        } else if o.compare {
            not_with("method", o.method.is_some(), "compare");
            not_with("start", o.start.is_some(), "compare");
        }
        if !(1..=100).contains(&o.seeds) {
            problems.push(Problem::new(
                "seeds",
                format!("{} is out of range; allowed: 1 to 100", o.seeds),
            ));
        }
        let line = line_objective(o, method, &mut problems);
        let given = given_settings(o, &mut problems);
        let run = RunOptions {
            population: o.population.map(|v| v as usize),
            generations: o.generations.map(|v| v as usize),
            budget: o.budget.map(|v| v as usize),
            polish: o.polish,
            seed: o.seed,
            start: None,
        };
        if batch {
            problems.extend(super::size_problems(&run));
        } else {
            // Whether a start applies: a placeholder for the values checked with the box.
            let with_start = RunOptions {
                start: o.start.as_ref().map(|_| Vec::new()),
                ..run.clone()
            };
            problems.extend(super::option_problems(method, &with_start, !o.polish));
        }
        let mut robust = o.robust.clone();
        if batch {
            if robust.worst == Some(WorstChoice::Search) {
                problems.push(Problem::new(
                    "worst",
                    "search is not supported with `paper_experiment` or `compare`; allowed there: paper",
                ));
            }
            robust.worst = Some(WorstChoice::Paper);
        }
        if line.is_some() {
            // The line's constraints are its rates, not the design set's worst case.
            robust.worst = Some(WorstChoice::Paper);
        }
        let resolved = robust.resolve();
        if let Err(p) = &resolved {
            problems.extend(p.iter().cloned());
        }
        match resolved {
            Ok((worst, margins, robust)) if problems.is_empty() => Ok(OptimizeInputs {
                experiment: match (o.paper_experiment, o.compare, line) {
                    (_, _, Some(objective)) => Experiment::Line(method, objective),
                    (true, _, None) => Experiment::Paper,
                    (false, true, None) => Experiment::Compare(o.seeds),
                    _ => Experiment::Single(method),
                },
                given,
                start: o.start.clone(),
                run,
                worst,
                margins,
                robust,
            }),
            _ => Err(problems),
        }
    }

    fn bind(c: OptimizeInputs, s: &Loaded) -> Result<BoundOptimize, Vec<Problem>> {
        let unarmed = crate::analyses::worst_case::torque_limit_problems(&c.margins, s);
        if !unarmed.is_empty() {
            return Err(unarmed);
        }
        let s = c.designed(s);
        let (bounds, plan) = c.bounds_and_plan(&s)?;
        if let Some(objective) = c.line() {
            let problem = LineSearch::new(&s, bounds.clone(), objective)?;
            for (m, o) in &plan {
                dry_check(&problem, &method_settings(*m, o))
                    .map_err(|e| vec![Problem::new(option_of(&e), e.to_string())])?;
            }
            return Ok(BoundOptimize {
                inputs: c,
                bounds,
                plan,
            });
        }
        // The solvers' own checks of their settings, on a free stand-in, before any
        // simulation.
        for (m, o) in &plan {
            let checked = settings_problem(&s, &bounds, *m)
                .and_then(|p| dry_check(&p, &method_settings(*m, o)));
            if let Err(e) = checked {
                return Err(vec![Problem::new(option_of(&e), e.to_string())]);
            }
        }
        Ok(BoundOptimize {
            inputs: c,
            bounds,
            plan,
        })
    }

    fn work(b: &BoundOptimize, s: &Loaded) -> Work {
        let (c, bounds, plan) = (&b.inputs, &b.bounds, &b.plan);
        let s = c.designed(s);
        let free = bounds.free_indices().len();
        let evaluations: u64 = plan
            .iter()
            .map(|(m, o)| planned_evaluations(&method_settings(*m, o), free) as u64)
            .sum();
        if let Some(o) = c.line() {
            // Each evaluation (and the best and given points once more) runs every parcel
            // past every diverter at most once.
            let diverters = 1 + s.file.line.diverters.len() as u64;
            return Work {
                at_most: Some((evaluations + 2) * o.parcels * diverters),
                // Parcels that meet no arm are not simulated: nothing is certain.
                at_least: 0,
                units: evaluations,
                unit: "evaluations",
                smaller: "use fewer `parcels`, a smaller `population`, fewer `generations` or a smaller `budget`",
            };
        }
        // A robust run's first round, its two searches, and the confirmation searches (a
        // budget `confirm` times larger) that end a converged run; later rounds are
        // announced as they start.
        let search = c.robust.as_ref().map_or(0, |r| {
            2 * (1 + r.confirm as u64) * r.search.evaluations as u64
        });
        Work {
            at_most: Some(planned_simulations(
                plan,
                bounds,
                &s.design,
                c.robust.as_ref(),
            )),
            // An evaluation may be decided in closed form and a solver may converge early;
            // a robust run's first verification (its two searches) always runs.
            at_least: c
                .robust
                .as_ref()
                .map_or(0, |r| 2 * r.search.evaluations as u64),
            units: evaluations + search,
            unit: "evaluations",
            smaller: "use a smaller `population`, fewer `generations` or a smaller `budget`",
        }
    }

    fn run(s: &Loaded, b: &BoundOptimize, hooks: &Hooks) -> Result<OptimizeResult, Error> {
        let c = &b.inputs;
        let s = c.designed(s);
        let (bounds, plan) = (b.bounds.clone(), &b.plan);
        let streams = Streams {
            live: hooks.live,
            runs: Default::default(),
        };
        let open = |p: &SettingsProblem| streams.open(p);
        let ctx = RunContext {
            progress: hooks.progress,
            memo: hooks.memo,
            stream: Some(&open),
        };
        let failed = |e: OptimizeError| Error::failed(e);
        Ok(match c.experiment {
            Experiment::Line(method, objective) => {
                let problem = LineSearch::new(&s, bounds, objective).map_err(Error::Invalid)?;
                let stream = streams.open_with(
                    super::line::evaluation_header(),
                    Box::new(move |r| super::line::evaluation_row(&objective, r)),
                );
                let settings = method_settings(method, &plan[0].1);
                let stop_point = || hooks.stop_point();
                OptimizeResult::Line(Box::new(run_line(
                    &problem,
                    &settings,
                    &ctx,
                    stream,
                    &stop_point,
                )?))
            }
            Experiment::Single(method) => {
                let (_, options) = &plan[0];
                let settings = method_settings(method, options);
                let (problem, run, robust) = match &c.robust {
                    None => {
                        let problem = settings_problem(&s, &bounds, method).map_err(failed)?;
                        let run = run_method(&problem, &settings, &ctx).map_err(failed)?;
                        (problem, run, None)
                    }
                    Some(r) => {
                        let planned =
                            planned_evaluations(&settings, bounds.free_indices().len()) as u64;
                        let rounds = std::sync::atomic::AtomicU64::new(0);
                        let new_round = || {
                            // Each round after the first: the solver's evaluations and two
                            // searches more.
                            if rounds.fetch_add(1, std::sync::atomic::Ordering::Relaxed) > 0 {
                                (hooks.more)(planned + 2 * r.search.evaluations as u64);
                            }
                        };
                        let (p, run, rr) =
                            run_robust(&s, &bounds, method, &settings, r, &ctx, &new_round)
                                .map_err(failed)?;
                        (p, run, Some(Box::new(rr)))
                    }
                };
                let best = best_report(&problem, &run.result);
                OptimizeResult::Single {
                    optimum_toml: optimum_toml(&s.file, &best)?,
                    best: Box::new(best),
                    problem: Box::new(problem),
                    run: Box::new(run),
                    robust,
                    design: Box::new(s.design.clone()),
                }
            }
            Experiment::Paper => {
                let runs = paper_experiment(&s, &c.run, &ctx).map_err(failed)?;
                let problems = runs
                    .iter()
                    .map(|r| settings_problem(&s, &r.bounds, r.outcome.method))
                    .collect::<Result<Vec<_>, _>>()
                    .map_err(failed)?;
                OptimizeResult::Paper {
                    runs,
                    problems,
                    point: Box::new(paper_point(&s).map_err(failed)?),
                }
            }
            Experiment::Compare(seeds) => {
                let (rows, best_known) =
                    compare(&s, &bounds, &c.run, seeds, &ctx).map_err(failed)?;
                OptimizeResult::Compare {
                    rows,
                    best_known,
                    bounds,
                }
            }
        })
    }

    fn summary(r: &OptimizeResult, _: &BoundOptimize, _: &Loaded) -> Value {
        match r {
            OptimizeResult::Single {
                problem,
                run,
                best,
                robust,
                design,
                ..
            } => report_json(problem, run, best, design, robust.as_deref()),
            OptimizeResult::Paper { runs, point, .. } => paper_json(runs, point),
            OptimizeResult::Compare {
                rows,
                best_known,
                bounds,
            } => compare_json(rows, *best_known, bounds),
            OptimizeResult::Line(r) => super::line::report_json(r),
        }
    }

    fn tables(r: &OptimizeResult) -> Result<Vec<(String, Vec<u8>)>, Error> {
        let mut tables = Vec::new();
        match r {
            OptimizeResult::Single { problem, run, .. } => {
                tables.push(csv_table(
                    "evaluations.csv",
                    evaluations_csv(problem, &run.log),
                )?);
                tables.push(csv_table("history.csv", history_csv(&run.result.history))?);
                if let Some(front) = &run.front {
                    tables.push(csv_table("front.csv", front_csv(front))?);
                }
            }
            OptimizeResult::Paper { runs, problems, .. } => {
                tables.push(csv_table("paper_experiment.csv", paper_csv(runs))?);
                for (r, problem) in runs.iter().zip(problems) {
                    let stem = r.label.replace(' ', "_");
                    tables.push(csv_table(
                        &format!("{stem}_history.csv"),
                        history_csv(&r.outcome.result.history),
                    )?);
                    tables.push(csv_table(
                        &format!("{stem}_evaluations.csv"),
                        evaluations_csv(problem, &r.outcome.log),
                    )?);
                }
            }
            OptimizeResult::Compare { rows, .. } => {
                let (csv, medians) = compare_csv(rows).map_err(Error::io)?;
                tables.push(("comparison.csv".into(), csv));
                tables.push(("comparison_medians.csv".into(), medians));
            }
            OptimizeResult::Line(r) => {
                tables.push(csv_table(
                    "evaluations.csv",
                    super::line::evaluations_csv(&r.problem.objective, &r.run.log),
                )?);
                tables.push(csv_table(
                    "history.csv",
                    super::line::history_csv(&r.run.result.history),
                )?);
            }
        }
        Ok(tables)
    }

    fn text(r: &OptimizeResult, _: &BoundOptimize, _: &Loaded) -> String {
        match r {
            OptimizeResult::Single {
                problem,
                run,
                best,
                robust,
                ..
            } => {
                let mut t = text::report_text(run, best);
                t += &text::bounds_note(problem, best);
                if let Some(rr) = robust {
                    t += &text::robust_text(problem, rr);
                }
                t
            }
            OptimizeResult::Paper { runs, point, .. } => text::paper_table(runs, point),
            OptimizeResult::Compare {
                rows, best_known, ..
            } => text::compare_table(rows, *best_known),
            OptimizeResult::Line(r) => super::line::report_text(r),
        }
    }
}
