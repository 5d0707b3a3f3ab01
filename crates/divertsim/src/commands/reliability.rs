//! `divertsim reliability`: divert and overload rates over a parcel mix (issue 11), by
//! `divertsim_core::analysis::population::reliability`: exact 95 % intervals, failure breakdowns, the
//! failure rate binned against every input, optional sweeps over one scenario key, a fixed or
//! per-parcel (adaptive) trigger.
//!
//! This edge owns the arguments, the checkpoint directory, the files and the plots:
//! - with `--out DIR`, each finished shard is kept as Parquet in a checkpoint directory beside
//!   DIR (`.DIR.reliability-checkpoint`, written atomically shard by shard), so a run killed
//!   by SIGINT, SIGTERM or SIGKILL continues with `--resume` from its last complete shard; the
//!   checkpoint is tied to the command by a fingerprint of everything that shapes the result;
//! - at the end the shards are merged (one row group each) into `samples.parquet`, the
//!   summary and plots are written, all moved into DIR at once, and the checkpoint removed.

use std::path::{Path, PathBuf};

use divertsim_api::analyses::reliability::{self as api, setting_line, Point};
use divertsim_api::contract::{self, Error};
use divertsim_core::analysis::population::adaptive_trigger::TriggerTable;
use divertsim_core::analysis::population::reliability::{
    NoStore, PointResult, RunPlan, ShardStore, StartRule, Tally,
};
use serde_json::{json, Value};

use super::analysis::{self, flags_for, Flagged, OptionArgs};
use super::common::{self, OutputArgs, ScenarioArgs};
use divertsim_api::config::{self, Problem};
use divertsim_api::samples;
use divertsim_core::run::memo;
use divertsim_figures::reliability as figures;

/// The flags of the reliability options ([`api::Options`]: names, help texts, defaults).
#[derive(Debug, Clone, Copy)]
pub struct StudyFlags;

impl Flagged for StudyFlags {
    type Options = api::Options;
}

/// Divert and overload rates over a parcel mix.
#[derive(Debug, clap::Args)]
pub struct ReliabilityArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub options: OptionArgs<StudyFlags>,
    /// Also write samples.csv (the same table as samples.parquet).
    #[arg(long)]
    pub csv: bool,
    /// Continue the interrupted run of this same command from its checkpoint beside --out.
    #[arg(long)]
    pub resume: bool,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The checkpoint's fingerprint: the core's memo key (FNV-1a over the `Debug` text, which
/// prints floats in their shortest exact form: equal text, equal inputs) of everything
/// that shapes the result.
fn fingerprint(options: &api::Options, plan: &RunPlan, points: &[Point]) -> String {
    let points: Vec<_> = points
        .iter()
        .map(|p| {
            (
                &p.value,
                p.seed,
                &p.loaded.scenario,
                &p.loaded.mix,
                &p.loaded.file.machine.trigger,
                &p.loaded.file.machine.adaptive,
            )
        })
        .collect();
    let inputs = (
        env!("CARGO_PKG_VERSION"),
        plan,
        &options.sweep,
        options.bins,
        points,
    );
    format!("{:016x}", memo::key("reliability checkpoint", &inputs))
}

/// The checkpoint directory of `--out DIR`.
fn checkpoint_dir(out: &Path) -> PathBuf {
    crate::outdir::beside(out, "reliability-checkpoint")
}

/// The options given and every point's scenario (the swept key set last), collecting the
/// problems keyed by flag.
fn load_points(
    args: &ReliabilityArgs,
    problems: &mut Vec<Problem>,
) -> Option<(api::Options, Option<api::Sweep>, Vec<Point>)> {
    let given = Value::Object(args.options.given.clone());
    let options: api::Options = match contract::options_from_json(&given) {
        Ok(o) => o,
        Err(Error::Invalid(p)) => {
            problems.extend(flags_for::<StudyFlags>(p));
            return None;
        }
        Err(e) => {
            problems.push(Problem::new("options", e.to_string()));
            return None;
        }
    };
    let sweep = match options.sweep.as_ref().map(api::SweepSpec::resolve) {
        None => None,
        Some(Ok((s, warning))) => {
            if let Some(w) = warning {
                eprintln!("{}", common::flags_in(&w));
            }
            Some(s)
        }
        Some(Err(p)) => {
            problems.extend(flags_for::<StudyFlags>(vec![p]));
            return None;
        }
    };
    let load = |extra: &[String]| {
        let sets: Vec<String> = args.scenario.sets.iter().chain(extra).cloned().collect();
        config::load_with(
            args.scenario.scenario.as_deref(),
            &sets,
            args.scenario.load_options(),
        )
    };
    // The scenario's problems keep their keys; only the sweep's is an option.
    match api::load_points(&load, sweep.as_ref(), options.seed) {
        Ok(points) => Some((options, sweep, points)),
        Err(found) => {
            problems.extend(found.into_iter().map(|p| match p.key.as_str() {
                "sweep" => Problem::new("--sweep", p.message),
                _ => p,
            }));
            None
        }
    }
}

/// Option problems that need no scenario.
fn option_problems(args: &ReliabilityArgs) -> Vec<Problem> {
    let mut p = common::out_problems(&args.output);
    if args.resume && args.output.out.is_none() {
        p.push(Problem::new(
            "--resume",
            "needs --out DIR: the checkpoint is kept beside DIR",
        ));
    }
    if args.csv && args.output.out.is_none() {
        p.push(Problem::new(
            "--csv",
            "needs --out DIR (samples.csv is written there)",
        ));
    }
    p
}

/// The progress bars of a run: the trigger table's, then the samples' over every point.
struct Bars {
    quiet: bool,
    samples: u64,
    table: std::sync::Mutex<Option<indicatif::ProgressBar>>,
    run: indicatif::ProgressBar,
    point: std::sync::atomic::AtomicU64,
}

impl Bars {
    fn new(total: u64, samples: u64, quiet: bool) -> Bars {
        let run = common::progress_bar(total, "reliability", quiet);
        Bars {
            quiet,
            samples,
            table: std::sync::Mutex::new(None),
            run,
            point: std::sync::atomic::AtomicU64::new(0),
        }
    }

    fn finish(&self) {
        self.run.finish_and_clear();
    }
}

impl api::Watch for Bars {
    fn table_started(&self, nodes: u64) {
        let bar = common::progress_bar(nodes, "table", self.quiet);
        *self.table.lock().unwrap_or_else(|e| e.into_inner()) = Some(bar);
    }
    fn table_done(&self, t: &TriggerTable) {
        if let Some(bar) = self.table.lock().unwrap_or_else(|e| e.into_inner()).take() {
            bar.finish_and_clear();
        }
        if !self.quiet {
            eprintln!(
                "adaptive trigger table: {} nodes ({} without a passing R_s), {} simulations",
                t.starts.len(),
                t.infeasible_nodes(),
                t.simulations
            );
        }
    }
    fn point_started(&self, i: usize) {
        self.point
            .store(i as u64, std::sync::atomic::Ordering::Relaxed);
        self.run.set_position(i as u64 * self.samples);
    }
    fn tick(&self) {
        match &*self.table.lock().unwrap_or_else(|e| e.into_inner()) {
            Some(bar) => bar.inc(1),
            None => self.run.inc(1),
        }
    }
    fn shard_done(&self, done: u64) {
        let i = self.point.load(std::sync::atomic::Ordering::Relaxed);
        self.run.set_position(i * self.samples + done);
    }
}

/// Failed samples kept for the report (each gets its own run page).
const REPORTED_FAILURES: usize = 20;

/// `divertsim reliability`.
pub fn run(args: &ReliabilityArgs) -> i32 {
    let mut problems = option_problems(args);
    let loaded = load_points(args, &mut problems);
    if let Some((options, _, points)) = &loaded {
        problems.extend(flags_for::<StudyFlags>(api::check(options, points)));
    }
    if let Err(code) = common::check(problems) {
        return code;
    }
    let Some((options, sweep, points)) = loaded else {
        return 2;
    };
    // One run per sample; an adaptive trigger's table searches R_s at each node first.
    let sims = api::estimated_simulations(&points, options.samples);
    if let Err(code) = common::within_budget(
        "reliability",
        sims,
        Some(sims),
        &args.output,
        "use fewer --samples (or sweep points, or table nodes)",
    ) {
        return code;
    }
    let plan = api::plan(&options, &points);
    let print = |s: &str| {
        if !args.output.quiet {
            eprintln!("{s}");
        }
    };

    // The checkpoint: refuse to overwrite an interrupted run, refuse to resume another.
    let fp = fingerprint(&options, &plan, &points);
    let mut store: Box<dyn ShardStore + Send> = Box::new(NoStore);
    let mut checkpoint = None;
    if let Some(out) = &args.output.out {
        let dir = checkpoint_dir(out);
        let meta = dir.join("run.json");
        if dir.exists() {
            if !args.resume {
                eprintln!(
                    "error: an interrupted run is kept in {}: add --resume to continue it, or remove that folder to start over",
                    dir.display()
                );
                return 2;
            }
            let theirs = std::fs::read_to_string(&meta)
                .ok()
                .and_then(|t| serde_json::from_str::<Value>(&t).ok())
                .and_then(|v| v["fingerprint"].as_str().map(str::to_string));
            if theirs.as_deref() != Some(fp.as_str()) {
                eprintln!(
                    "error: the run kept in {} was started with other inputs or options; run the same command to resume it, or remove that folder",
                    dir.display()
                );
                return 2;
            }
        } else {
            if args.resume {
                print("note: nothing to resume; starting the run");
            }
            // Made complete under another name and renamed into place: a kill meanwhile
            // leaves no checkpoint without its fingerprint.
            let fresh = dir.with_extension(format!("new-{}", std::process::id()));
            let made = std::fs::create_dir_all(&fresh)
                .and_then(|_| {
                    std::fs::write(
                        fresh.join("run.json"),
                        serde_json::to_vec_pretty(&json!({
                            "fingerprint": fp,
                            "what": "checkpoint of `divertsim reliability`: finished shards as Parquet; removed when the run completes",
                        }))
                        .unwrap_or_default(),
                    )
                })
                .and_then(|_| std::fs::rename(&fresh, &dir));
            if made.is_err() {
                let _ = std::fs::remove_dir_all(&fresh);
            }
            if let Err(e) = made {
                eprintln!("error: cannot create the checkpoint {}: {e}", dir.display());
                return 1;
            }
        }
        store = Box::new(samples::ShardFiles {
            dir: dir.clone(),
            plan,
        });
        checkpoint = Some(dir);
    }

    let total = plan.samples * points.len() as u64;
    let watch = Bars::new(total, plan.samples, args.output.quiet);
    let outcome =
        divertsim_api::threads::with_threads(args.output.threads.map(usize::from), || {
            api::run(&points, &plan, store.as_ref(), &watch)
        });
    watch.finish();
    let results = match outcome {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return 1;
        }
    };
    let resumed: u64 = results.iter().map(|(r, _)| r.resumed_shards).sum();
    if resumed > 0 {
        print(&format!(
            "resumed: {resumed} shards read back from the checkpoint"
        ));
    }

    // The summary, the table and the text, as every edge gives them.
    let inputs = api::StudyInputs {
        options,
        sweep: sweep.clone(),
        points: points.clone(),
    };
    let study = api::Study {
        points,
        plan,
        sweep,
        results,
    };
    let output = match study
        .points
        .first()
        .map(|p| contract::report::<api::Reliability>(&study, &inputs, &p.loaded))
    {
        Some(Ok(o)) => o,
        Some(Err(e)) => return analysis::exit_code_of::<StudyFlags>(e),
        None => return 3,
    };
    let api::Study {
        points,
        plan,
        sweep,
        results,
    } = study;
    let summary = output.summary;
    if let (Some(dir), Some(ck)) = (&args.output.out, &checkpoint) {
        let mut files = vec![("summary.json".to_string(), common::json_bytes(&summary))];
        files.extend(output.tables);
        files.extend(api::largest_stroke_files(&points, &results));
        if let Some(p) = points.first() {
            files.push(divertsim_api::output::scenario_toml(
                "reliability",
                &p.loaded.file,
            ));
        }
        // The checkpoint goes with the publication, under its lock.
        crate::outdir::retire_on_publish(dir, ck.clone());
        let code = common::write_outputs(dir, files, |staging| {
            let shards: Vec<u64> = results.iter().map(|(r, _)| r.shards).collect();
            let failed = samples::merge_shards(ck, &shards, staging, args.csv, REPORTED_FAILURES)
                .map_err(|e| e.to_string())?;
            draw(staging, &plan, &points, &results, sweep.as_ref())?;
            let plots: Vec<(&str, String)> = divertsim_report::study::PLOTS
                .into_iter()
                .filter_map(|name| Some((name, std::fs::read_to_string(staging.join(name)).ok()?)))
                .collect();
            let pages =
                divertsim_report::study::pages(&points, &results, &failed, &summary, &plots);
            // runs/ is there even when no sample failed (the folder's layout is fixed).
            std::fs::create_dir_all(staging.join("runs")).map_err(|e| e.to_string())?;
            crate::outdir::write_into(staging, &pages)
        });
        if code != 0 {
            return code;
        }
    }
    if args.output.json {
        common::emit_json(&summary);
    } else {
        common::emit(&output.text);
    }
    0
}

/// The study's plots (the figures crate's [`figures::draw_study`]).
fn draw(
    staging: &Path,
    plan: &RunPlan,
    points: &[Point],
    results: &[(PointResult, StartRule)],
    sweep: Option<&api::Sweep>,
) -> Result<(), String> {
    let values: Vec<String> = points.iter().map(|p| p.value.clone()).collect();
    let tallies: Vec<&Tally> = results.iter().map(|(r, _)| &r.tally).collect();
    let setting = match (points.first(), results.first()) {
        (Some(p), Some((_, t))) => setting_line(p, t),
        _ => return Ok(()),
    };
    let study = figures::Study {
        seed: plan.seed,
        setting: &setting,
        values: &values,
        tallies: &tallies,
        sweep_key: sweep.map(|(k, _)| k.as_str()),
    };
    figures::draw_study(staging, &study)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoint_lives_beside_the_output() {
        assert_eq!(
            checkpoint_dir(Path::new("runs/mix1")),
            Path::new("runs/.mix1.reliability-checkpoint")
        );
        assert_eq!(
            checkpoint_dir(Path::new("mix1")),
            Path::new("./.mix1.reliability-checkpoint")
        );
    }
}
