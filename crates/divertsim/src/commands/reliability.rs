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

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use divertsim_api::analyses::reliability::{self as api, setting_line, Point, CONFIDENCE};
use divertsim_api::analyses::request;
use divertsim_api::contract::{self, Error};
use divertsim_core::analysis::population::adaptive_trigger::TriggerTable;
use divertsim_core::analysis::population::reliability::{
    Bins, NoStore, PointResult, RunPlan, SampleRun, ShardStore, Tally, Trigger,
};
use serde_json::{json, Value};

use super::analysis::{flags_for, Flagged, OptionArgs};
use super::common::{self, OutputArgs, ScenarioArgs};
use divertsim_api::config::{self, Problem};
use divertsim_api::samples;
use divertsim_figures::charts;
use divertsim_figures::reliability as figures;

/// The flags of the reliability options ([`api::Options`]: names, help texts, defaults).
#[derive(Debug, Clone, Copy)]
pub struct Study;

impl Flagged for Study {
    type Options = api::Options;
}

/// Divert and overload rates over a parcel mix.
#[derive(Debug, clap::Args)]
pub struct ReliabilityArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub options: OptionArgs<Study>,
    /// Also write samples.csv (the same table as samples.parquet).
    #[arg(long)]
    pub csv: bool,
    /// Continue the interrupted run of this same command from its checkpoint beside --out.
    #[arg(long)]
    pub resume: bool,
    #[command(flatten)]
    pub output: OutputArgs,
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

fn fingerprint(options: &api::Options, plan: &RunPlan, points: &[Point]) -> String {
    let mut h = Fingerprint(0xcbf2_9ce4_8422_2325);
    // Debug prints floats in their shortest exact form: equal text, equal inputs.
    let _ = write!(
        h,
        "{} {:?} {:?} {:?}",
        env!("CARGO_PKG_VERSION"),
        plan,
        options.sweep,
        options.bins
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
            problems.extend(flags_for::<Study>(p));
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
            problems.extend(flags_for::<Study>(vec![p]));
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

/// `divertsim reliability`.
pub fn run(args: &ReliabilityArgs) -> i32 {
    let mut problems = option_problems(args);
    let loaded = load_points(args, &mut problems);
    if let Some((options, _, points)) = &loaded {
        problems.extend(flags_for::<Study>(api::check(options, points)));
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
        store = Box::new(ParquetStore {
            dir: dir.clone(),
            plan,
        });
        checkpoint = Some(dir);
    }

    let total = plan.samples * points.len() as u64;
    let watch = Bars::new(total, plan.samples, args.output.quiet);
    let outcome =
        divertsim_api::threads::with_threads(args.output.threads.map(usize::from), || {
            api::run(&points, &plan, store.as_mut(), &watch)
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

    // The summary and the table, as every edge gives them.
    let output = match request::reliability_output(&points, &plan, sweep.as_ref(), &results) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            return 1;
        }
    };
    let summary = output.summary;
    if let (Some(dir), Some(ck)) = (&args.output.out, &checkpoint) {
        let mut files = vec![("summary.json".to_string(), common::json_bytes(&summary))];
        files.extend(output.tables);
        if let Some(p) = points.first() {
            files.push(divertsim_api::output::scenario_toml(
                "reliability",
                &p.loaded.file,
            ));
        }
        // The checkpoint goes with the publication, under its lock.
        crate::outdir::retire_on_publish(dir, ck.clone());
        let code = common::write_outputs(dir, files, |staging| {
            let failed = merge_samples(ck, &results, staging, args.csv)?;
            draw(staging, &plan, &points, &results, sweep.as_ref())?;
            write_report(staging, &points, &results, &failed, &summary)
        });
        if code != 0 {
            return code;
        }
    }
    if args.output.json {
        common::emit_json(&summary);
    } else {
        let swept = sweep.as_ref().map(|(k, _)| k.as_str());
        common::emit(&api::text(&plan, &points, &results, swept));
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

/// Plots: per point without a sweep (failure rate by input, reserve and overload
/// histograms); the sweep curves with one.
fn draw(
    staging: &Path,
    plan: &RunPlan,
    points: &[Point],
    results: &[(PointResult, Trigger)],
    sweep: Option<&api::Sweep>,
) -> Result<(), String> {
    let both = |name: &str,
                f: &dyn Fn(&Path) -> Result<(), divertsim_figures::plot::PlotError>|
     -> Result<(), String> {
        for ext in ["svg", "png"] {
            f(&staging.join(format!("{name}.{ext}"))).map_err(|e| format!("{name}.{ext}: {e}"))?;
        }
        Ok(())
    };
    if let Some((key, _)) = sweep {
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
        let tallies: Vec<&Tally> = results.iter().map(|(r, _)| &r.tally).collect();
        let charts = figures::sweep_charts(key, &x_label, &xs, &tallies);
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
    let rate_charts = figures::input_rate_charts(t);
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
        let title = format!("{} samples, seed {}; {setting}", t.samples, plan.seed);
        let chart = figures::histogram(title, b, x_label, reference);
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
