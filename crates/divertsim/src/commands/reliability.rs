//! `divertsim reliability`: divert and overload rates over a parcel mix (issue 11), by
//! `divertsim_core::analysis::reliability`: exact 95 % intervals, failure breakdowns, the
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

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use divertsim_core::analysis::adaptive_trigger::TriggerTable;
use divertsim_core::analysis::reliability::{
    run_point, Bins, NoStore, PointResult, RunPlan, SampleRun, ShardStore, Tally, Trigger, INPUTS,
};
use divertsim_core::stats::binomial::{clopper_pearson, Proportion};
use serde_json::{json, Value};

use super::common::{self, OutputArgs, ScenarioArgs};
use divertsim_api::config::mix::TriggerConfig;
use divertsim_api::config::{self, Loaded, Problem};
use divertsim_api::samples;
use divertsim_figures::charts::{self, Chart, Series, Style};

/// Interval confidence.
const CONFIDENCE: f64 = 0.95;
/// Largest number of sweep points.
const MAX_POINTS: usize = 1000;
/// Largest number of shards of a point (checkpoint files).
const MAX_SHARDS: u64 = 100_000;

#[derive(Debug, clap::Args)]
pub struct ReliabilityArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    /// Samples to run (per sweep point); with --until-ci, the most to run.
    #[arg(long, value_name = "N", default_value_t = 10_000,
          value_parser = clap::value_parser!(u64).range(1..=1_000_000_000))]
    pub samples: u64,
    /// Seed of the random streams (default: mix.seed, else 1). Sample i depends only on
    /// (seed, i).
    #[arg(long, value_name = "SEED")]
    pub seed: Option<u64>,
    /// Stop once the 95 % intervals of the divert rate and of the overload rate are both at
    /// most WIDTH wide (checked after each shard), e.g. 0.001.
    #[arg(long, value_name = "WIDTH")]
    pub until_ci: Option<f64>,
    /// Sweep one scenario key: KEY=LO:HI/N (N evenly spaced values, LO and HI included),
    /// KEY=LO:HI:STEP (or a count when it is a whole number larger than HI − LO, as in
    /// 1.5:2.3:9), or KEY=A,B,... (a list, e.g. machine.trigger=fixed,adaptive). Every point
    /// runs the same samples (same seed).
    #[arg(long, value_name = "KEY=LO:HI:N")]
    pub sweep: Option<String>,
    /// Bins per input for the binned failure rates (about equal counts, edges at the first
    /// shard's quantiles); the histograms have 40 equal bins.
    #[arg(long, value_name = "N", default_value_t = 10,
          value_parser = clap::value_parser!(u64).range(1..=200))]
    pub bins: u64,
    /// Samples per shard (at least 100): the unit of checkpointing and of the --until-ci
    /// decision; the first shard also fixes the bins of the binned rates.
    #[arg(long, value_name = "N", default_value_t = 5000,
          value_parser = clap::value_parser!(u64).range(100..=10_000_000))]
    pub shard: u64,
    /// Also write samples.csv (the same table as samples.parquet).
    #[arg(long)]
    pub csv: bool,
    /// Continue the interrupted run of this same command from its checkpoint beside --out.
    #[arg(long)]
    pub resume: bool,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// One point of the run (the only one without a sweep).
struct Point {
    /// The swept value as given ("" without a sweep).
    value: String,
    loaded: Loaded,
    /// The seed of its streams: --seed, else its mix.seed (so `--sweep mix.seed=1,2,3`
    /// runs three sets of parcels).
    seed: u64,
}

/// The swept key and its values as `--set` texts.
fn parse_sweep(text: &str) -> Result<(String, Vec<String>), Problem> {
    let bad = |m: String| Problem {
        key: "--sweep".into(),
        message: m,
    };
    let Some((key, spec)) = text.split_once('=') else {
        return Err(bad(format!(
            "'{text}' is not KEY=LO:HI:N or KEY=A,B,... (e.g. machine.belt_speed=1.5:2.3:9)"
        )));
    };
    let (key, spec) = (key.trim(), spec.trim());
    if key.is_empty() || key.split('.').any(str::is_empty) {
        return Err(bad(format!("'{key}' is not a dotted scenario key")));
    }
    // Numbers in the one grammar (A,B,C or LO:HI/N or LO:HI:STEP); other values (strings
    // such as fixed,adaptive) as a comma list.
    let numeric = spec.contains(':')
        || spec
            .split(',')
            .all(|v| v.trim().parse::<f64>().is_ok_and(f64::is_finite));
    let values: Vec<String> = if numeric {
        let (v, warning) = common::parse_values("--sweep", spec, -1e12, 1e12, "", MAX_POINTS)?;
        if let Some(w) = warning {
            eprintln!("{w}");
        }
        v.iter().map(|x| x.to_string()).collect()
    } else {
        spec.split(',').map(|v| v.trim().to_string()).collect()
    };
    if values.iter().any(String::is_empty) || values.len() > MAX_POINTS {
        return Err(bad(format!(
            "'{spec}': allowed: 1 to {MAX_POINTS} values separated by commas"
        )));
    }
    Ok((key.to_string(), values))
}

/// A 64-bit FNV-1a hash of everything formatted into it: the checkpoint's fingerprint.
struct Fingerprint(u64);

impl std::fmt::Write for Fingerprint {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        for b in s.bytes() {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
        Ok(())
    }
}

fn fingerprint(args: &ReliabilityArgs, plan: &RunPlan, points: &[Point]) -> String {
    let mut h = Fingerprint(0xcbf2_9ce4_8422_2325);
    // Debug prints floats in their shortest exact form: equal text, equal inputs.
    let _ = write!(
        h,
        "{} {:?} {:?} {:?}",
        env!("CARGO_PKG_VERSION"),
        plan,
        args.sweep,
        args.bins
    );
    for p in points {
        let _ = write!(
            h,
            "|{}|{}|{:?}|{:?}|{:?}|{:?}",
            p.value,
            p.seed,
            p.loaded.scenario,
            p.loaded.mix,
            p.loaded.file.machine.trigger,
            p.loaded.file.machine.adaptive
        );
    }
    format!("{:016x}", h.0)
}

/// The checkpoint directory of `--out DIR`.
fn checkpoint_dir(out: &Path) -> PathBuf {
    crate::outdir::beside(out, "reliability-checkpoint")
}

/// Shards kept as Parquet files in the checkpoint directory.
struct ParquetStore {
    dir: PathBuf,
    plan: RunPlan,
}

impl ParquetStore {
    fn path(&self, point: usize, k: u64) -> PathBuf {
        self.dir.join(format!("p{point:04}-s{k:07}.parquet"))
    }
}

impl ShardStore for ParquetStore {
    fn load(&mut self, point: usize, k: u64) -> Result<Option<Vec<SampleRun>>, String> {
        let path = self.path(point, k);
        if !path.exists() {
            return Ok(None);
        }
        let mut out = Vec::new();
        for b in samples::read_file(&path)? {
            out.extend(samples::from_batch(&b)?);
        }
        let want: Vec<u64> = self.plan.shard_range(k).collect();
        if out.iter().map(|s| s.draw.index).ne(want.iter().copied()) {
            return Err(format!(
                "the checkpoint {} does not hold samples {}..{}; remove the checkpoint folder to start over",
                path.display(),
                want.first().copied().unwrap_or(0),
                want.last().map_or(0, |l| l + 1)
            ));
        }
        Ok(Some(out))
    }

    fn save(&mut self, point: usize, k: u64, s: &[SampleRun]) -> Result<(), String> {
        samples::write_file(&self.path(point, k), &samples::to_batch(point, s)?)
    }
}

/// Load every point's scenario (the swept key set last), collecting the problems.
fn load_points(args: &ReliabilityArgs, problems: &mut Vec<Problem>) -> Option<Vec<Point>> {
    let (key, values) = match args.sweep.as_deref().map(parse_sweep) {
        None => (None, vec![String::new()]),
        Some(Ok((k, v))) => (Some(k), v),
        Some(Err(p)) => {
            problems.push(p);
            return None;
        }
    };
    let mut points = Vec::new();
    let mut seen: Vec<Problem> = Vec::new();
    for value in values {
        let mut sets = args.scenario.sets.clone();
        if let Some(k) = &key {
            sets.push(format!("{k}={value}"));
        }
        match config::load_with(
            args.scenario.scenario.as_deref(),
            &sets,
            args.scenario.load_options(),
        ) {
            Ok(loaded) => {
                let seed = args.seed.unwrap_or_else(|| loaded.file.mix.seed());
                points.push(Point {
                    value,
                    loaded,
                    seed,
                })
            }
            Err(e) => {
                for p in e.0 {
                    // A problem every point shares is reported once, at its first point.
                    if seen.contains(&p) {
                        continue;
                    }
                    seen.push(p.clone());
                    let mut p = p;
                    if key.is_some() {
                        p.message = format!("{} (at --sweep point {value})", p.message);
                    }
                    problems.push(p);
                }
            }
        }
    }
    (problems.is_empty()).then_some(points)
}

/// Option problems that need no scenario.
fn option_problems(args: &ReliabilityArgs) -> Vec<Problem> {
    let mut p = common::out_problems(&args.output);
    if let Some(w) = args.until_ci {
        if !(w > 0.0 && w < 1.0) {
            p.push(Problem {
                key: "--until-ci".into(),
                message: format!("{w} is out of range; allowed: (0, 1), an interval width"),
            });
        }
    }
    if args.resume && args.output.out.is_none() {
        p.push(Problem {
            key: "--resume".into(),
            message: "needs --out DIR: the checkpoint is kept beside DIR".into(),
        });
    }
    if args.csv && args.output.out.is_none() {
        p.push(Problem {
            key: "--csv".into(),
            message: "needs --out DIR (samples.csv is written there)".into(),
        });
    }
    p
}

/// Every point's first samples must be drawable (a hopeless mix is found before any run).
fn draw_problems(points: &[Point], samples: u64) -> Vec<Problem> {
    let mut out = Vec::new();
    for p in points {
        let s = &p.loaded.scenario;
        if let Some(e) = (0..samples.min(1000)).find_map(|i| p.loaded.mix.draw(s, p.seed, i).err())
        {
            let m = Problem {
                key: "mix".into(),
                message: e.to_string(),
            };
            if !out.contains(&m) {
                out.push(m);
            }
        }
    }
    out
}

/// `divertsim reliability`.
pub fn run(args: &ReliabilityArgs) -> i32 {
    let mut problems = option_problems(args);
    let points = load_points(args, &mut problems);
    if let Some(points) = &points {
        problems.extend(draw_problems(points, args.samples));
        let shards = args.samples.div_ceil(args.shard);
        if shards > MAX_SHARDS {
            problems.push(Problem {
                key: "--shard".into(),
                message: format!(
                    "{} gives {shards} shards of {} samples; allowed: at most {MAX_SHARDS} shards (a --shard of at least {})",
                    args.shard,
                    args.samples,
                    args.samples.div_ceil(MAX_SHARDS)
                ),
            });
        }
    }
    if let Err(code) = common::check(problems) {
        return code;
    }
    let Some(points) = points else { return 2 };
    // One run per sample; an adaptive trigger's table searches R_s at each node first.
    let sims: u64 = points
        .iter()
        .map(|p| {
            let table = match p.loaded.file.machine.trigger {
                TriggerConfig::Fixed => 0,
                TriggerConfig::Adaptive => {
                    let a = &p.loaded.file.machine.adaptive;
                    let nodes = a.length_nodes * a.aspect_nodes * a.offset_nodes * a.angle_nodes;
                    nodes * a.search().estimated_simulations()
                }
            };
            args.samples + table as u64
        })
        .sum();
    if let Err(code) = common::within_budget(
        "reliability",
        sims,
        &args.output,
        "use fewer --samples (or sweep points, or table nodes)",
    ) {
        return code;
    }
    let plan = RunPlan {
        samples: args.samples,
        shard_size: args.shard,
        seed: points.first().map_or(1, |p| p.seed),
        until_width: args.until_ci,
        confidence: CONFIDENCE,
        bins: args.bins as usize,
    };
    let print = |s: &str| {
        if !args.output.quiet {
            eprintln!("{s}");
        }
    };

    // The checkpoint: refuse to overwrite an interrupted run, refuse to resume another.
    let fp = fingerprint(args, &plan, &points);
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
        store = Box::new(ParquetStore {
            dir: dir.clone(),
            plan,
        });
        checkpoint = Some(dir);
    }

    let total = plan.samples * points.len() as u64;
    let outcome = common::with_threads(args.output.threads, || {
        let mut results = Vec::new();
        for (i, p) in points.iter().enumerate() {
            let setting = &p.loaded.scenario;
            let trigger = match p.loaded.file.machine.trigger {
                TriggerConfig::Fixed => Trigger::Fixed,
                TriggerConfig::Adaptive => {
                    let a = &p.loaded.file.machine.adaptive;
                    let grid = match a.grid(&p.loaded.mix, setting, p.seed) {
                        Ok(g) => g,
                        Err(e) => return Err(e),
                    };
                    let bar = common::progress_bar(grid.len() as u64, "table", args.output.quiet);
                    let tick = || bar.inc(1);
                    let t = TriggerTable::build(setting, grid, &a.search(), &tick);
                    bar.finish_and_clear();
                    print(&format!(
                        "adaptive trigger table: {} nodes ({} without a passing R_s), {} simulations",
                        t.starts.len(),
                        t.infeasible_nodes(),
                        t.simulations
                    ));
                    Trigger::Adaptive(t)
                }
            };
            let bar = common::progress_bar(total, "reliability", args.output.quiet);
            bar.set_position(i as u64 * plan.samples);
            let tick = || bar.inc(1);
            let base = i as u64 * plan.samples;
            let mut on_shard = |done: u64| bar.set_position(base + done);
            let plan = RunPlan {
                seed: p.seed,
                ..plan
            };
            let r = run_point(
                setting,
                &p.loaded.mix,
                &trigger,
                &plan,
                i,
                store.as_mut(),
                &tick,
                &mut on_shard,
            )
            .map_err(|e| e.to_string());
            bar.finish_and_clear();
            results.push((r?, trigger));
        }
        Ok(results)
    });
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

    let summary = match points.first() {
        Some(p) => common::describe(
            summary_json(args, &plan, &points, &results),
            "reliability",
            &p.loaded.file,
        ),
        None => summary_json(args, &plan, &points, &results),
    };
    if let (Some(dir), Some(ck)) = (&args.output.out, &checkpoint) {
        let mut files = vec![
            ("summary.json".to_string(), common::json_bytes(&summary)),
            (
                "failure_rates.csv".to_string(),
                failure_rates_csv(&points, &results),
            ),
        ];
        if let Some(p) = points.first() {
            files.push(common::scenario_toml("reliability", &p.loaded.file));
        }
        // The checkpoint goes with the publication, under its lock.
        crate::outdir::retire_on_publish(dir, ck.clone());
        let code = common::write_outputs(dir, files, |staging| {
            let failed = merge_samples(ck, &results, staging, args.csv)?;
            draw(staging, &plan, &points, &results, args.sweep.as_deref())?;
            write_report(staging, &points, &results, &failed, &summary)
        });
        if code != 0 {
            return code;
        }
    }
    if args.output.json {
        common::emit_json(&summary);
    } else {
        common::emit(&table(&plan, &points, &results, args.sweep.as_deref()));
    }
    0
}

/// The shards, in order, into samples.parquet (one row group each) and samples.csv.
/// Failed samples kept for the report (each gets its own run page).
const REPORTED_FAILURES: usize = 20;

/// The shards, in order, into samples.parquet and samples.csv; returns the first
/// [`REPORTED_FAILURES`] failed samples with their point.
fn merge_samples(
    checkpoint: &Path,
    results: &[(PointResult, Trigger)],
    staging: &Path,
    csv: bool,
) -> Result<Vec<(usize, SampleRun)>, String> {
    let mut failed = Vec::new();
    let mut sink = samples::ParquetSink::create(&staging.join("samples.parquet"))?;
    let mut csv_out = if csv {
        let p = staging.join("samples.csv");
        let mut w = csv::Writer::from_path(&p).map_err(|e| format!("{}: {e}", p.display()))?;
        w.write_record(samples::csv_header())
            .map_err(|e| e.to_string())?;
        Some(w)
    } else {
        None
    };
    for (point, (r, _)) in results.iter().enumerate() {
        for k in 0..r.shards {
            let p = checkpoint.join(format!("p{point:04}-s{k:07}.parquet"));
            for b in samples::read_file(&p)? {
                sink.write(&b)?;
                if failed.len() < REPORTED_FAILURES {
                    failed.extend(
                        samples::from_batch(&b)?
                            .into_iter()
                            .filter(SampleRun::failed)
                            .take(REPORTED_FAILURES - failed.len())
                            .map(|s| (point, s)),
                    );
                }
                if let Some(w) = &mut csv_out {
                    samples::write_csv_rows(w, &b)?;
                }
            }
        }
    }
    if let Some(mut w) = csv_out {
        w.flush().map_err(|e| e.to_string())?;
    }
    sink.close()?;
    Ok(failed)
}

/// report.html: the summary, the breakdown, the plots (inlined SVG) and the first failed
/// samples, each linked to its own animated run (runs/sample_N.html, written here too).
fn write_report(
    staging: &Path,
    points: &[Point],
    results: &[(PointResult, Trigger)],
    failed: &[(usize, SampleRun)],
    summary: &Value,
) -> Result<(), String> {
    use crate::report::{escape, single};
    std::fs::create_dir_all(staging.join("runs")).map_err(|e| e.to_string())?;
    let mut rows = String::new();
    for (point, f) in failed {
        let p = &points[*point];
        let s = f.draw.scenario(&p.loaded.scenario, f.start_position);
        let r = divertsim_core::sim::simulate(&s);
        let d = &f.draw;
        let inputs =
            format!(
            "sample {} of the mix (seed {}{}): parcel {} × {} × {} m, {} kg, ΔP {} m, φ {:.2}°, \
             arrival Δv {} m/s, ω {} rad/s, trigger error {} s; μ_b {}, μ_a {}, e* {}; R_s {} m",
            d.index,
            p.seed,
            if p.value.is_empty() { String::new() } else { format!(", sweep point {}", p.value) },
            d.length, d.width, d.height, d.mass, d.offset, d.angle.to_degrees(), d.speed, d.spin,
            d.phase,
            d.belt_friction.map_or("(scenario's)".to_string(), |m| m.to_string()),
            d.arm_friction, d.restitution, s.machine.start_position
        );
        let name = format!("runs/sample_{}_{}.html", point, d.index);
        std::fs::write(staging.join(&name), single(&s, &r, &inputs)).map_err(|e| e.to_string())?;
        rows += &format!(
            "<tr><td><a href=\"{name}\">{}</a></td><td>{}</td><td>{}</td><td>{:.3} × {:.3}</td><td>{:.3}</td><td>{:.1}</td><td>{:.4}</td><td>{:.3}</td></tr>",
            d.index,
            escape(&p.value),
            f.reason().unwrap_or(""),
            d.length,
            d.width,
            d.offset,
            d.angle.to_degrees(),
            f.reserve,
            f.overload_ratio
        );
    }
    let mut points_html = String::new();
    for (p, (r, trigger)) in points.iter().zip(results) {
        let t = &r.tally;
        let (dv, ov) = (t.divert_rate(CONFIDENCE), t.overload_rate(CONFIDENCE));
        let list = |m: &std::collections::BTreeMap<String, u64>| {
            m.iter()
                .map(|(k, n)| format!("{} {n}", escape(k)))
                .collect::<Vec<_>>()
                .join(", ")
        };
        points_html += &format!(
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.5} [{:.5}, {:.5}]</td><td>{:.5} [{:.5}, {:.5}]</td><td>{:.0}</td><td>{}</td><td>{}</td></tr>",
            escape(&p.value),
            escape(&setting_line(p, trigger)),
            t.samples,
            dv.estimate, dv.lower, dv.upper,
            ov.estimate, ov.lower, ov.upper,
            t.capacity(),
            list(&t.by_reason),
            list(&t.by_final_stage)
        );
    }
    let mut plots = String::new();
    for name in [
        "failure_rate.svg",
        "divert_reserve.svg",
        "overload_ratio.svg",
        "sweep.svg",
    ] {
        if let Ok(svg) = std::fs::read_to_string(staging.join(name)) {
            let svg = svg.find("<svg").map_or("", |i| &svg[i..]);
            plots += &format!(
                "<h2>{}</h2><div style=\"overflow:auto\">{svg}</div>",
                escape(name)
            );
        }
    }
    let html = format!(
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>divertsim reliability</title>\
         <style>body{{font:14px/1.4 system-ui,sans-serif;max-width:1400px;margin:0 auto;padding:12px 18px}}\
         table{{border-collapse:collapse}}td,th{{border:1px solid #dde;padding:2px 8px;text-align:left}}\
         svg{{max-width:100%;height:auto}}</style></head><body>\
         <h1>divertsim reliability</h1><p>{}</p>\
         <h2>Rates (95 % Clopper–Pearson intervals)</h2><table><tr><th>point</th><th>setting</th><th>samples</th>\
         <th>divert rate</th><th>overload rate</th><th>W [1/h]</th><th>failures by reason</th><th>by final stage</th></tr>{points_html}</table>\
         <h2>Failed samples</h2><p>The first {} failed samples; each opens its own animated run.</p>\
         <table><tr><th>sample</th><th>point</th><th>reason</th><th>a × b [m]</th><th>ΔP [m]</th><th>φ [deg]</th><th>reserve [m]</th><th>S/S_fall</th></tr>{rows}</table>\
         {plots}</body></html>",
        escape(summary["tool"].as_str().unwrap_or("")),
        failed.len(),
    );
    std::fs::write(staging.join("report.html"), html).map_err(|e| e.to_string())
}

fn proportion_json(p: &Proportion) -> Value {
    json!({
        "count": p.successes,
        "of": p.trials,
        "estimate": finite_or_null(p.estimate),
        "lower": p.lower,
        "upper": p.upper,
    })
}

fn finite_or_null(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

fn bins_json(b: &Bins) -> Value {
    let rows: Vec<Value> = (0..b.count.len())
        .filter(|&k| b.count[k] > 0)
        .map(|k| {
            let (lo, hi) = b.edges(k);
            let f = clopper_pearson(b.failed[k], b.count[k], CONFIDENCE);
            let o = clopper_pearson(b.overloaded[k], b.count[k], CONFIDENCE);
            json!({
                "lo": lo,
                "hi": hi,
                "samples": b.count[k],
                "failure_rate": proportion_json(&f),
                "overload_rate": proportion_json(&o),
            })
        })
        .collect();
    json!(rows)
}

fn histogram_json(b: &Option<Bins>) -> Value {
    match b {
        None => Value::Null,
        Some(b) => json!({
            "edges": b.edges,
            "counts": b.count,
            "note": "values outside [lo, hi] are counted in the end bins",
        }),
    }
}

fn point_json(p: &Point, r: &PointResult, trigger: &Trigger) -> Value {
    let t = &r.tally;
    let divert = t.divert_rate(CONFIDENCE);
    let failure = clopper_pearson(t.samples - t.diverted, t.samples, CONFIDENCE);
    let overload = t.overload_rate(CONFIDENCE);
    let mut sequences: Vec<(&String, &u64)> = t.by_sequence.iter().collect();
    sequences.sort_by(|a, b| b.1.cmp(a.1).then(a.0.cmp(b.0)));
    let m = &p.loaded.scenario.machine;
    json!({
        "value": p.value,
        "seed": p.seed,
        "setting": {
            "belt_speed_m_s": m.belt_speed,
            "cycle_time_s": m.cycle_time,
            // The adaptive trigger chooses R_s per parcel: no single value.
            "start_position_m": match trigger {
                Trigger::Fixed => json!(m.start_position),
                Trigger::Adaptive(_) => Value::Null,
            },
            "light_barrier_m": m.light_barrier,
            "trigger": trigger.label(),
        },
        "samples": t.samples,
        "stopped_early": r.stopped_early,
        "divert_rate": proportion_json(&divert),
        "failure_rate": proportion_json(&failure),
        "overload_rate": proportion_json(&overload),
        "capacity_per_h": t.capacity(),
        "max_overload_ratio": t.max_overload_ratio,
        "min_divert_reserve_m": finite_or_null(t.min_reserve),
        "failures_by_reason": t.by_reason,
        "failures_by_final_stage": t.by_final_stage,
        "failures_by_stages": sequences.iter().take(20).map(|(s, n)| json!({"stages": s, "count": n})).collect::<Vec<_>>(),
        "rejected_draws": {
            "total": t.rejected_total(),
            "by_reason": t.rejected_by_reason().into_iter().map(|(k, n)| (k.to_string(), json!(n))).collect::<serde_json::Map<_, _>>(),
        },
        "failure_rate_by_input_note": "bins of about equal counts, edges from the first shard; the first bin also takes every smaller value, the last every larger one",
        "failure_rate_by_input": t.input_bins.iter().enumerate().filter_map(|(k, b)| {
            b.as_ref().map(|b| {
                json!({"input": INPUTS[k], "bins": bins_json(b)})
            })
        }).collect::<Vec<_>>(),
        "divert_reserve_histogram_m": histogram_json(&t.reserve_hist),
        "overload_ratio_histogram": histogram_json(&t.overload_hist),
        "trigger_table": match trigger {
            Trigger::Fixed => Value::Null,
            Trigger::Adaptive(t) => json!({
                "nodes": t.starts.len(),
                "nodes_without_passing_start": t.infeasible_nodes(),
                "simulations": t.simulations,
                "grid": {
                    "length_m": t.grid.length,
                    "aspect": t.grid.aspect,
                    "offset_fraction": t.grid.offset_fraction,
                    "angle_deg": t.grid.angle.iter().map(|a| a.to_degrees()).collect::<Vec<_>>(),
                },
            }),
        },
    })
}

fn summary_json(
    args: &ReliabilityArgs,
    plan: &RunPlan,
    points: &[Point],
    results: &[(PointResult, Trigger)],
) -> Value {
    let scenario = points
        .first()
        .and_then(|p| serde_json::to_value(&p.loaded.file).ok())
        .unwrap_or(Value::Null);
    json!({
        "tool": format!("divertsim {}", env!("CARGO_PKG_VERSION")),
        "seed": plan.seed,
        "samples_requested": plan.samples,
        "shard_size": plan.shard_size,
        "until_ci": plan.until_width,
        "confidence": CONFIDENCE,
        "interval": "Clopper-Pearson (exact binomial)",
        "failure": "not diverted, or the run failed numerically",
        "overload": "largest strike impulse above the free fall from limits.drop_height (S/S_fall > 1)",
        "sweep": args.sweep.as_deref().and_then(|s| parse_sweep(s).ok()).map(|(k, v)| json!({"key": k, "values": v})),
        "points": points.iter().zip(results).map(|(p, (r, t))| point_json(p, r, t)).collect::<Vec<_>>(),
        "scenario": scenario,
    })
}

/// failure_rates.csv: one row per point, input and non-empty bin.
fn failure_rates_csv(points: &[Point], results: &[(PointResult, Trigger)]) -> Vec<u8> {
    let mut rows = Vec::new();
    for (i, (p, (r, _))) in points.iter().zip(results).enumerate() {
        for (k, b) in r.tally.input_bins.iter().enumerate() {
            let Some(b) = b else { continue };
            let name = INPUTS[k];
            for j in (0..b.count.len()).filter(|&j| b.count[j] > 0) {
                let (lo, hi) = b.edges(j);
                let f = clopper_pearson(b.failed[j], b.count[j], CONFIDENCE);
                let o = clopper_pearson(b.overloaded[j], b.count[j], CONFIDENCE);
                rows.push(vec![
                    i.to_string(),
                    p.value.clone(),
                    name.to_string(),
                    // The end bins are open: an empty edge.
                    if lo.is_finite() {
                        lo.to_string()
                    } else {
                        String::new()
                    },
                    if hi.is_finite() {
                        hi.to_string()
                    } else {
                        String::new()
                    },
                    b.count[j].to_string(),
                    b.failed[j].to_string(),
                    f.estimate.to_string(),
                    f.lower.to_string(),
                    f.upper.to_string(),
                    b.overloaded[j].to_string(),
                    o.estimate.to_string(),
                    o.lower.to_string(),
                    o.upper.to_string(),
                ]);
            }
        }
    }
    divertsim_api::output::csv_bytes(
        &[
            "point",
            "sweep_value",
            "input",
            "bin_lo",
            "bin_hi",
            "samples",
            "failures",
            "failure_rate",
            "failure_rate_lower",
            "failure_rate_upper",
            "overloads",
            "overload_rate",
            "overload_rate_lower",
            "overload_rate_upper",
        ],
        &rows,
    )
    .unwrap_or_default()
}

/// A short setting line: v, t_c, R_s, trigger.
fn setting_line(p: &Point, trigger: &Trigger) -> String {
    let m = &p.loaded.scenario.machine;
    format!(
        "v = {} m/s, t_c = {} s, R_s = {} m, S_d = {} m, {} trigger",
        m.belt_speed,
        m.cycle_time,
        m.start_position,
        m.light_barrier,
        trigger.label()
    )
}

fn interval_text(p: &Proportion) -> String {
    format!("{:.5}  [{:.5}, {:.5}]", p.estimate, p.lower, p.upper)
}

fn table(
    plan: &RunPlan,
    points: &[Point],
    results: &[(PointResult, Trigger)],
    sweep: Option<&str>,
) -> String {
    let mut s = String::new();
    if let Some(sweep) = sweep {
        let key = parse_sweep(sweep).map(|(k, _)| k).unwrap_or_default();
        let _ = writeln!(
            s,
            "reliability sweep over {key} (seed {}, 95 % Clopper–Pearson intervals)",
            plan.seed
        );
        let _ = writeln!(
            s,
            "{:>14} {:>9}  {:<34} {:<34} {:>10}",
            "value", "samples", "divert rate [95 % CI]", "overload rate [95 % CI]", "W [1/h]"
        );
        for (p, (r, _)) in points.iter().zip(results) {
            let t = &r.tally;
            let _ = writeln!(
                s,
                "{:>14} {:>9}  {:<34} {:<34} {:>10.0}",
                p.value,
                t.samples,
                interval_text(&t.divert_rate(CONFIDENCE)),
                interval_text(&t.overload_rate(CONFIDENCE)),
                t.capacity()
            );
        }
        return s;
    }
    let (Some(p), Some((r, trigger))) = (points.first(), results.first()) else {
        return s;
    };
    let t = &r.tally;
    let _ = writeln!(
        s,
        "reliability over {} samples (seed {}{}): {}",
        t.samples,
        plan.seed,
        if r.stopped_early {
            ", stopped: intervals narrow enough"
        } else {
            ""
        },
        setting_line(p, trigger)
    );
    let drop = p.loaded.scenario.limits.drop_height;
    let _ = writeln!(
        s,
        "  divert rate     {}  (95 % Clopper–Pearson)",
        interval_text(&t.divert_rate(CONFIDENCE))
    );
    let _ = writeln!(
        s,
        "  overload rate   {}  (impulse above the free fall from {drop} m)",
        interval_text(&t.overload_rate(CONFIDENCE))
    );
    let _ = writeln!(s, "  capacity        {:.0} parcels/h", t.capacity());
    let _ = writeln!(
        s,
        "  worst seen      S/S_fall {:.3}, divert reserve {}",
        t.max_overload_ratio,
        if t.min_reserve.is_finite() {
            format!("{:.4} m", t.min_reserve)
        } else {
            "n/a (no run completed)".into()
        }
    );
    let rejected: Vec<String> = t
        .rejected_by_reason()
        .into_iter()
        .filter(|(_, n)| *n > 0)
        .map(|(k, n)| format!("{k} {n}"))
        .collect();
    let _ = writeln!(
        s,
        "  rejected draws  {}{}",
        t.rejected_total(),
        if rejected.is_empty() {
            String::new()
        } else {
            format!(" ({})", rejected.join(", "))
        }
    );
    if t.samples > t.diverted {
        let list = |m: &std::collections::BTreeMap<String, u64>| {
            let mut v: Vec<_> = m.iter().collect();
            v.sort_by(|a, b| b.1.cmp(a.1).then(a.0.cmp(b.0)));
            v.iter()
                .map(|(k, n)| format!("{k} {n}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let _ = writeln!(s, "failures by reason:       {}", list(&t.by_reason));
        let _ = writeln!(s, "failures by final stage:  {}", list(&t.by_final_stage));
        let _ = writeln!(s, "failure rate by input (the bin with the highest rate):");
        for (k, b) in t.input_bins.iter().enumerate() {
            let Some(b) = b else { continue };
            let name = INPUTS[k];
            let worst = (0..b.count.len())
                .filter(|&j| b.count[j] > 0)
                .max_by(|&x, &y| {
                    let rx = b.failed[x] as f64 / b.count[x] as f64;
                    let ry = b.failed[y] as f64 / b.count[y] as f64;
                    rx.total_cmp(&ry).then(y.cmp(&x))
                });
            if let Some(j) = worst {
                let (lo, hi) = b.edges(j);
                let f = clopper_pearson(b.failed[j], b.count[j], CONFIDENCE);
                let _ = writeln!(
                    s,
                    "  {:<17} [{:>9.4}, {:>9.4}]  {}  ({} samples)",
                    name,
                    lo,
                    hi,
                    interval_text(&f),
                    b.count[j]
                );
            }
        }
    }
    s
}

/// Bin centres and one value per non-empty bin.
fn bin_series(b: &Bins, value: impl Fn(usize) -> f64) -> Vec<(f64, f64)> {
    (0..b.count.len())
        .filter(|&k| b.count[k] > 0)
        .map(|k| {
            let (lo, hi) = b.edges(k);
            (0.5 * (lo + hi), value(k))
        })
        .collect()
}

/// A histogram as a step outline.
fn steps(b: &Bins) -> Vec<(f64, f64)> {
    let mut pts = Vec::new();
    for k in 0..b.count.len() {
        let (lo, hi) = b.edges(k);
        let c = b.count[k] as f64;
        pts.push((lo, c));
        pts.push((hi, c));
    }
    pts
}

/// Failure and overload rates against one input, each with its 95 % interval (dashed).
fn rate_chart(title: String, x_label: &str, b: &Bins) -> Chart {
    let mut series = Vec::new();
    let mut top: f64 = 0.0;
    for (label, counts, color) in [
        ("failure rate", &b.failed, 3),
        ("overload rate", &b.overloaded, 0),
    ] {
        let ci = |k: usize| clopper_pearson(counts[k], b.count[k], CONFIDENCE);
        let mut rate = Series::new(label, bin_series(b, |k| ci(k).estimate), Style::LinePoints);
        rate.color = Some(color);
        let mut lo = Series::new("", bin_series(b, |k| ci(k).lower), Style::Dashed);
        lo.color = Some(color);
        let hi_pts = bin_series(b, |k| ci(k).upper);
        top = hi_pts.iter().fold(top, |t, p| t.max(p.1));
        let mut hi = Series::new("", hi_pts, Style::Dashed);
        hi.color = Some(color);
        series.extend([rate, lo, hi]);
    }
    Chart {
        title,
        x_label: x_label.to_string(),
        y_label: "rate (dashed: 95 % interval)".into(),
        series,
        y_range: Some((0.0, (top * 1.15).clamp(0.01, 1.0))),
        ..Chart::default()
    }
}

/// Plots: per point without a sweep (failure rate by input, reserve and overload
/// histograms); the sweep curves with one.
fn draw(
    staging: &Path,
    plan: &RunPlan,
    points: &[Point],
    results: &[(PointResult, Trigger)],
    sweep: Option<&str>,
) -> Result<(), String> {
    let both = |name: &str,
                f: &dyn Fn(&Path) -> Result<(), divertsim_figures::plot::PlotError>|
     -> Result<(), String> {
        for ext in ["svg", "png"] {
            f(&staging.join(format!("{name}.{ext}"))).map_err(|e| format!("{name}.{ext}: {e}"))?;
        }
        Ok(())
    };
    if let Some(sweep) = sweep {
        let key = parse_sweep(sweep).map(|(k, _)| k).unwrap_or_default();
        let numeric: Option<Vec<f64>> =
            points.iter().map(|p| p.value.parse::<f64>().ok()).collect();
        let xs: Vec<f64> = numeric
            .clone()
            .unwrap_or_else(|| (0..points.len()).map(|i| i as f64).collect());
        let x_label = if numeric.is_some() {
            key.clone()
        } else {
            format!(
                "{key}: {}",
                points
                    .iter()
                    .enumerate()
                    .map(|(i, p)| format!("{i} = {}", p.value))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        };
        let curve = |title: &str, f: &dyn Fn(&Tally) -> Proportion, color: usize| {
            let pts = |g: &dyn Fn(&Proportion) -> f64| -> Vec<(f64, f64)> {
                xs.iter()
                    .zip(results)
                    .map(|(x, (r, _))| (*x, g(&f(&r.tally))))
                    .collect()
            };
            let mut est = Series::new(title, pts(&|p| p.estimate), Style::LinePoints);
            est.color = Some(color);
            let mut lo = Series::new("95 % interval", pts(&|p| p.lower), Style::Dashed);
            lo.color = Some(7);
            let mut hi = Series::new("", pts(&|p| p.upper), Style::Dashed);
            hi.color = Some(7);
            Chart {
                title: format!("{title} against {key}"),
                x_label: x_label.clone(),
                y_label: title.to_string(),
                series: vec![est, lo, hi],
                ..Chart::default()
            }
        };
        let charts = [
            curve("divert rate", &|t| t.divert_rate(CONFIDENCE), 0),
            curve("overload rate", &|t| t.overload_rate(CONFIDENCE), 3),
        ];
        let title = format!(
            "{} samples per point, seed {}; at the first point {}; {key} swept",
            results.first().map_or(0, |(r, _)| r.tally.samples),
            plan.seed,
            points
                .first()
                .map_or(String::new(), |p| setting_line(p, &results[0].1))
        );
        return both("sweep", &|p| {
            charts::panels(p, &title, &charts, 2, (700, 500))
        });
    }
    let (Some(p), Some((r, trigger))) = (points.first(), results.first()) else {
        return Ok(());
    };
    let t = &r.tally;
    let setting = setting_line(p, trigger);
    let rate_charts: Vec<Chart> = t
        .input_bins
        .iter()
        .enumerate()
        .filter_map(|(k, b)| {
            b.as_ref().map(|b| {
                let name = INPUTS[k];
                rate_chart(format!("by {name}"), name, b)
            })
        })
        .collect();
    if !rate_charts.is_empty() {
        let title = format!(
            "failure and overload rates by input: {} samples, seed {}; {setting}",
            t.samples, plan.seed
        );
        both("failure_rate", &|path| {
            charts::panels(path, &title, &rate_charts, 3, (560, 400))
        })?;
    }
    let hist = |name: &str,
                b: &Option<Bins>,
                x_label: &str,
                reference: Option<f64>|
     -> Result<(), String> {
        let Some(b) = b else { return Ok(()) };
        let mut chart = Chart {
            title: format!("{} samples, seed {}; {setting}", t.samples, plan.seed),
            x_label: x_label.to_string(),
            y_label: "samples".into(),
            series: vec![Series::new("", steps(b), Style::Line)],
            ..Chart::default()
        };
        if let Some(x) = reference {
            // A vertical reference drawn as a series.
            let top = b.count.iter().copied().max().unwrap_or(1) as f64;
            let mut s = Series::new(
                format!("{x_label} = {x}"),
                vec![(x, 0.0), (x, top)],
                Style::Dashed,
            );
            s.color = Some(3);
            chart.series.push(s);
        }
        both(name, &|path| charts::line_chart(path, &chart))
    };
    hist(
        "divert_reserve",
        &t.reserve_hist,
        "divert reserve d [m] (d ≥ 0 diverted)",
        None,
    )?;
    hist("overload_ratio", &t.overload_hist, "S/S_fall", Some(1.0))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sweep_grammar() {
        let (k, v) = parse_sweep("machine.belt_speed=1.5:2.3:9").unwrap();
        assert_eq!(k, "machine.belt_speed");
        assert_eq!(v.len(), 9);
        assert_eq!((v[0].as_str(), v[8].as_str()), ("1.5", "2.3"));
        assert_eq!(v[1], "1.6");
        let (_, v) = parse_sweep("k.x=0.65:2.3:5").unwrap();
        assert_eq!(v, ["0.65", "1.0625", "1.475", "1.8875", "2.3"]);
        let (_, v) = parse_sweep("machine.trigger = fixed, adaptive").unwrap();
        assert_eq!(v, ["fixed", "adaptive"]);
        for bad in [
            "belt_speed",
            "=1,2",
            "a.b=1:2",
            "a.b=x:2:3",
            "a.b=1,,2",
            "a.b=1:2/2000",
        ] {
            assert_eq!(parse_sweep(bad).unwrap_err().key, "--sweep", "{bad}");
        }
    }

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
