//! `divertsim optimize`: the machine-settings optimisation of issue 5 (paper §4.3) — maximise
//! the sorting capacity W over (v, t_c, R_s, S_d) subject to every `[design]` parcel being
//! diverted and the worst-case impulse staying below the free fall, with the paper's GA and
//! penalised steepest descent, differential evolution and CMA-ES (each with a COBYLA polish)
//! and NSGA-II for the trade-off capacity / overload / divert reserve.
//!
//! The experiments, their tables and JSON are `divertsim_api::analyses::optimize`; this file
//! is the command-line edge: arguments, the checkpoint and the live evaluation streams, the
//! output files, text tables and figures. Three modes:
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

use std::path::Path;

use crate::checkpoint::Journal;
use divertsim_api::analyses::optimize as optimize_api;
use divertsim_api::analyses::optimize::{
    allowed, best_report, compare, compare_csv, compare_json, compare_plan, dry_check,
    evaluation_header, evaluation_row, evaluations_csv, file_settings, front_csv, history_csv,
    method_settings, paper_csv, paper_experiment, paper_json, paper_plan, paper_point,
    planned_evaluations, planned_simulations, range_help, report_json, run_method, run_robust,
    search_bounds, settings_problem, start_point, variable_index, Method, RunContext, RunOptions,
    RunOutcome, SYMBOLS, UNITS,
};
use divertsim_api::config::{Loaded, Problem as CliProblem, SearchRange};
use divertsim_core::analysis::design::design_set::Margins;
use divertsim_core::analysis::design::robust::RobustSettings;
use divertsim_core::analysis::design::settings_problem::{Objectives, SettingsProblem, VARIABLES};
use divertsim_core::optimize::{Bounds, Observer, OptimizeError, Record};
use serde_json::Value;

use super::common::{self, OutputArgs, ScenarioArgs};
use super::worst_case::{RobustArgs, WorstArg};
use divertsim_figures::optimize::{draw_front, draw_history, HistoryRun};

/// Optimisation method (`--method`; the api's [`Method`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
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

impl From<MethodArg> for Method {
    fn from(m: MethodArg) -> Method {
        match m {
            MethodArg::Ga => Method::Ga,
            MethodArg::Gradient => Method::Gradient,
            MethodArg::De => Method::De,
            MethodArg::Cmaes => Method::Cmaes,
            MethodArg::Nsga2 => Method::Nsga2,
        }
    }
}

/// Optimise the machine settings (v, t_c, R_s, S_d) for capacity.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
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
    pub method: Option<MethodArg>,
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

fn problem(key: &str, message: String) -> CliProblem {
    CliProblem {
        key: key.into(),
        message,
    }
}

fn names_help() -> &'static str {
    "NAME one of belt_speed|v, cycle_time|t_c, start_position|R_s, light_barrier|S_d"
}

/// The search box from the defaults, `--bound` and `--fix` (`light_barrier` is the scenario's
/// S_d, the default fixed value), or every problem with them: the texts parsed here, the
/// ranges checked by the api's [`search_bounds`] (ranges first, then fixes).
pub fn parse_bounds(
    bounds: &[String],
    fixes: &[String],
    light_barrier: f64,
) -> Result<Bounds, Vec<CliProblem>> {
    let mut settings = Vec::new();
    let mut problems = Vec::new();
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
            [lo, hi] if allowed(i, &SearchRange::Range([lo, hi])) => {
                settings.push((i, SearchRange::Range([lo, hi])));
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
            Some((i, x)) if allowed(i, &SearchRange::Fixed(x)) => {
                settings.push((i, SearchRange::Fixed(x)));
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
    search_bounds(&settings, light_barrier).map_err(|p| {
        p.into_iter()
            .map(|p| problem("--bound", p.message))
            .collect()
    })
}

/// `--start v,t_c,R_s[,S_d]` inside `bounds` (the api's [`start_point`]: S_d defaults to the
/// centre of its range; a fixed variable takes its fixed value).
pub fn parse_start(text: &str, bounds: &Bounds) -> Result<Vec<f64>, CliProblem> {
    let values: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>().unwrap_or(f64::NAN))
        .collect();
    start_point(&values, bounds).map_err(|why| {
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
    })
}

/// The live streams of the runs' evaluations beside the checkpoint (`evaluations-N.csv`, N
/// counting the runs of the command): a convenience while a long run goes, the results do
/// not depend on them.
struct Streams<'a> {
    dir: Option<&'a Path>,
    runs: std::sync::atomic::AtomicUsize,
}

impl<'a> Streams<'a> {
    fn beside(journal: &'a Option<Journal>) -> Self {
        Streams {
            dir: journal.as_ref().map(Journal::dir),
            runs: Default::default(),
        }
    }

    /// The next run's stream (a new file; none without a directory or if it cannot be made).
    fn open(&self, problem: &SettingsProblem) -> Option<Box<dyn Observer + 'a>> {
        let n = self.runs.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = self.dir?;
        let mut w = csv::Writer::from_path(dir.join(format!("evaluations-{n}.csv"))).ok()?;
        w.write_record(evaluation_header(problem)).ok()?;
        w.flush().ok()?;
        Some(Box::new(CsvStream {
            writer: Some(w),
            trade_off: problem.objectives() == Objectives::TradeOff,
        }))
    }
}

/// One run's evaluations, each written to its CSV file as it arrives (the stream stops at
/// the first write error).
struct CsvStream {
    writer: Option<csv::Writer<std::fs::File>>,
    trade_off: bool,
}

impl Observer for CsvStream {
    fn record(&mut self, r: &Record) {
        if let Some(w) = &mut self.writer {
            let row = evaluation_row(self.trade_off, r);
            if w.write_record(&row).and_then(|_| Ok(w.flush()?)).is_err() {
                self.writer = None;
            }
        }
    }
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
    let o = run_options(args, args.start.as_ref().map(|_| Vec::new()));
    optimize_api::option_problems(method, &o, args.no_polish)
        .into_iter()
        .map(|p| match p.key.as_str() {
            "polish" => CliProblem::new("--no-polish", p.message),
            _ => common::flags(vec![p]).remove(0),
        })
        .collect()
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
    let streams = Streams::beside(journal);
    let open = |p: &SettingsProblem| streams.open(p);
    let ctx = RunContext {
        progress: &tick,
        memo: common::memo_of(journal),
        stream: Some(&open),
    };
    let (problem, run, robust_run) = match robust {
        None => {
            let run =
                divertsim_api::threads::with_threads(args.output.threads.map(usize::from), || {
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
            match divertsim_api::threads::with_threads(args.output.threads.map(usize::from), || {
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
    let report = report_json(&problem, &run, &best, &loaded.design, robust_run.as_ref());
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
        let mut text = optimize_api::text::report_text(&run, &best);
        if let Some(rr) = &robust_run {
            text += &optimize_api::text::robust_text(&problem, rr);
        }
        common::emit(&text);
    }
    0
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
    let streams = Streams::beside(journal);
    let open = |p: &SettingsProblem| streams.open(p);
    let ctx = RunContext {
        progress: &tick,
        memo: common::memo_of(journal),
        stream: Some(&open),
    };
    let result = divertsim_api::threads::with_threads(args.output.threads.map(usize::from), || {
        let runs = paper_experiment(loaded, &o, &ctx)?;
        Ok::<_, OptimizeError>((runs, paper_point(loaded)?))
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
        common::emit(&optimize_api::text::paper_table(&runs, &paper_point));
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
    let streams = Streams::beside(journal);
    let open = |p: &SettingsProblem| streams.open(p);
    let ctx = RunContext {
        progress: &tick,
        memo: common::memo_of(journal),
        stream: Some(&open),
    };
    let result = divertsim_api::threads::with_threads(args.output.threads.map(usize::from), || {
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
        common::emit(&optimize_api::text::compare_table(&rows, best_known));
    }
    0
}

/// The scenario file's `[optimize]` search box as `--bound` / `--fix` texts, in variable
/// order (the command line's come after them, so they override).
pub fn file_bounds(cfg: &divertsim_api::config::OptimizeConfig) -> (Vec<String>, Vec<String>) {
    let (mut bounds, mut fixes) = (Vec::new(), Vec::new());
    for (i, range) in file_settings(cfg) {
        let name = VARIABLES[i];
        match range {
            SearchRange::Fixed(x) => fixes.push(format!("{name}={x}")),
            SearchRange::Range([lo, hi]) => bounds.push(format!("{name}={lo}:{hi}")),
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
    let method = args.method.map_or(Method::De, Method::from);
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
        if let Err(e) = check_settings(&loaded, &bounds, *m, o) {
            eprintln!("error: {e}");
            return 2;
        }
    }
    let sims = planned_simulations(&check_plan, &bounds, &loaded.design, robust.as_ref());
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

/// Validate a method's settings before any simulation (the api's [`dry_check`] on a free
/// stand-in problem), naming the option of a setting the solver refuses.
fn check_settings(
    loaded: &Loaded,
    bounds: &Bounds,
    method: Method,
    o: &RunOptions,
) -> Result<(), String> {
    let p = settings_problem(loaded, bounds, method).map_err(|e| format!("--bound: {e}"))?;
    dry_check(&p, &method_settings(method, o)).map_err(|e| {
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
    fn bounds_and_fixes_as_text() {
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
    fn starts_as_text() {
        let b = parse_bounds(&[], &[], 0.0).unwrap();
        assert_eq!(
            parse_start("1.8,1.5,0.5", &b).unwrap(),
            vec![1.8, 1.5, 0.5, 0.0]
        );
        assert!(parse_start("1.8,1.5", &b).is_err());
        assert!(parse_start("3,1.5,0.5", &b).is_err());
    }
}
