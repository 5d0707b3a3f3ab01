//! Divert reliability over a parcel mix (issue 11): divert and overload rates with exact
//! 95 % intervals, failure breakdowns, the failure rate binned against every input,
//! optional sweeps over one scenario key, a fixed or per-parcel (adaptive) trigger. The
//! Monte Carlo is `divertsim_core::analysis::population::reliability`: sample i depends only on
//! (seed, i), shards are tallied in order, so a run split over threads, processes or
//! machines ([`run_shard`], [`crate::pieces`]) gives the same result bit for bit.
//!
//! A run on the contract keeps its shards in the hooks' memo as Parquet bytes
//! ([`shard_store`]: the CLI's checkpoint, resumed shard by shard) and its sample table is
//! written from them ([`write_samples`]); a cluster's job hands its gathered shards over
//! as that memo ([`crate::pieces::run_from_pieces`]). The edges own what is drawn and
//! written.

// What the studies share, offered here too as part of this study's interface.
pub use super::population::{
    checked_sweep, finite_or_null, load_points, load_spectrum_json, machine_trigger,
    proportion_json, sample_file, sweep_warning, table_simulations, variant_points, Point, Quiet,
    Sweep, SweepSpec, Swept, Watch, MAX_POINTS,
};
use super::population::{largest_stroke_name, load_spectrum_rows, LOAD_SPECTRUM_COLUMNS};
use crate::config::{Loaded, Problem};
use crate::contract::Error;
use crate::samples::MemoShards;
use divertsim_core::analysis::population::reliability::{
    self as core, Bins, PointResult, RunPlan, SampleRun, ShardStore, StartRule, Tally, INPUTS,
};
use divertsim_core::run::memo::{self, Memo};
use divertsim_core::run::sweep::{no_progress, Progress};
use divertsim_core::stats::binomial::{clopper_pearson, Proportion};
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::io::Write;

/// The options of a run besides the scenario (`divertsim reliability`, Python
/// `reliability`): one declaration, its defaults and help texts those of every edge.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct Options {
    /// Samples to run (per sweep point); with `until_ci`, the most to run; 1 to 1000000000.
    #[schemars(extend("x-value" = "N"))]
    pub samples: u64,
    /// Samples per shard, 100 to 10000000: the unit of checkpointing and of the `until_ci`
    /// decision; the first shard also fixes the bins of the binned rates.
    #[schemars(extend("x-value" = "N"))]
    pub shard: u64,
    /// Seed of the random streams (default: mix.seed, else 1). Sample i depends only on
    /// (seed, i).
    #[schemars(extend("x-value" = "SEED"))]
    pub seed: Option<u64>,
    /// Stop once the 95 % intervals of the divert rate and of the overload rate are both at
    /// most this wide (checked after each shard), in (0, 1), e.g. 0.001.
    #[schemars(extend("x-value" = "WIDTH"))]
    pub until_ci: Option<f64>,
    /// Bins per input for the binned failure rates (about equal counts, edges at the first
    /// shard's quantiles), 1 to 200; the histograms have 40 equal bins.
    #[schemars(extend("x-value" = "N"))]
    pub bins: u64,
    /// Sweep one scenario key: KEY=LO:HI/N (N evenly spaced values, LO and HI included, as
    /// in 1.5:2.3/9), KEY=LO:HI:STEP (from LO in steps of STEP), or KEY=A,B,... (a list,
    /// e.g. machine.trigger=fixed,adaptive); or a mapping of one key to its values. Every
    /// point runs the same samples (same seed).
    #[schemars(extend("x-value" = "KEY=LO:HI/N"))]
    pub sweep: Option<SweepSpec>,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            samples: 10_000,
            shard: 5_000,
            seed: None,
            until_ci: None,
            bins: 10,
            sweep: None,
        }
    }
}

/// Every problem with the options (keys are the option names), and a mix whose first
/// samples cannot be drawn.
pub fn check(o: &Options, points: &[Point]) -> Vec<Problem> {
    let mut p = option_problems(o);
    p.extend(draw_problems(points, o.samples));
    p
}

/// Every problem with the options alone (keys are the option names).
pub fn option_problems(o: &Options) -> Vec<Problem> {
    let mut p = Vec::new();
    if !(1..=1_000_000_000).contains(&o.samples) {
        p.push(Problem::new(
            "samples",
            format!("{} is out of range; allowed: 1 to 1000000000", o.samples),
        ));
    }
    if !(100..=10_000_000).contains(&o.shard) {
        p.push(Problem::new(
            "shard",
            format!("{} is out of range; allowed: 100 to 10000000", o.shard),
        ));
    } else {
        let shards = o.samples.div_ceil(o.shard);
        if shards > MAX_SHARDS {
            p.push(Problem::new(
                "shard",
                format!(
                    "{} gives {shards} shards of {} samples; allowed: at most {MAX_SHARDS} shards (a shard of at least {})",
                    o.shard,
                    o.samples,
                    o.samples.div_ceil(MAX_SHARDS)
                ),
            ));
        }
    }
    if !(1..=200).contains(&o.bins) {
        p.push(Problem::new(
            "bins",
            format!("{} is out of range; allowed: 1 to 200", o.bins),
        ));
    }
    if let Some(w) = o.until_ci {
        if !(w > 0.0 && w < 1.0) {
            p.push(Problem::new(
                "until_ci",
                format!("{w} is out of range; allowed: (0, 1), an interval width"),
            ));
        }
    }
    p
}

/// The run's plan (the seed is the first point's; each point runs with its own).
pub fn plan(o: &Options, points: &[Point]) -> RunPlan {
    RunPlan {
        samples: o.samples,
        shard_size: o.shard,
        seed: points.first().map_or(1, |p| p.seed),
        until_width: o.until_ci,
        confidence: CONFIDENCE,
        bins: o.bins as usize,
    }
}

/// Simulations a run does at most: one per sample, and an adaptive trigger's table
/// searches.
pub fn estimated_simulations(points: &[Point], samples: u64) -> u64 {
    points
        .iter()
        .map(|p| samples + table_simulations(&p.loaded.file.machine))
        .sum()
}

/// A point's trigger: fixed, or the adaptive table (its searches run here).
pub fn trigger_for(p: &Point, watch: &dyn Watch) -> Result<StartRule, Error> {
    machine_trigger(
        &p.loaded.file.machine,
        &p.loaded.mix,
        &p.loaded.scenario,
        p.seed,
        watch,
    )
}

/// The plan of point `p` (its own seed).
pub fn point_plan(plan: &RunPlan, p: &Point) -> RunPlan {
    RunPlan {
        seed: p.seed,
        ..*plan
    }
}

/// Run every point: its trigger (`trigger(i, point)`: built here, or by a cluster's job
/// once for its shards), then its shards in order through `store` (kept shards are read
/// back, new ones saved), stopping early by the plan's interval width, and asking `stop`
/// before each shard ([`Error::Cancelled`] when it said stop).
pub fn run_with(
    points: &[Point],
    plan: &RunPlan,
    store: &dyn ShardStore,
    stop: &dyn Fn() -> bool,
    watch: &dyn Watch,
    trigger: &dyn Fn(usize, &Point) -> Result<StartRule, Error>,
) -> Result<Vec<(PointResult, StartRule)>, Error> {
    let mut results = Vec::new();
    for (i, p) in points.iter().enumerate() {
        let trigger = trigger(i, p)?;
        watch.point_started(i);
        let tick = || watch.tick();
        let mut on_shard = |t: &Tally| {
            watch.shard_done(t.samples);
            watch.shard_tallied(i, t);
        };
        let r = core::run_point(
            &p.loaded.scenario,
            &p.loaded.mix,
            &trigger,
            &point_plan(plan, p),
            i,
            store,
            stop,
            &tick,
            &mut on_shard,
        )
        .map_err(|e| match e {
            core::RunError::Stopped => Error::Cancelled,
            e => Error::failed(e),
        })?;
        results.push((r, trigger));
    }
    Ok(results)
}

/// The samples of shard `k` of point `p` alone (what one worker of a cluster runs): the
/// same samples, bit for bit, as the shard of a whole run.
pub fn run_shard(
    p: &Point,
    trigger: &StartRule,
    plan: &RunPlan,
    k: u64,
    progress: Progress<'_>,
) -> Result<Vec<SampleRun>, Error> {
    let plan = point_plan(plan, p);
    core::run_shard(
        &p.loaded.scenario,
        &p.loaded.mix,
        trigger,
        plan.seed,
        plan.shard_range(k),
        progress,
    )
    .map_err(Error::failed)
}

/// [`run_with`] with nothing kept, nothing reported and no stop.
pub fn run_quietly(
    points: &[Point],
    plan: &RunPlan,
) -> Result<Vec<(PointResult, StartRule)>, Error> {
    run_with(points, plan, &core::NoStore, &|| false, &Quiet, &|_, p| {
        trigger_for(p, &Quiet)
    })
}

/// A point's results so far: its samples, the divert, overload and tipping rates with their
/// intervals, and the failures by reason.
pub fn partial_json(point: usize, t: &Tally) -> Value {
    json!({
        "point": point,
        "samples": t.samples,
        "divert_rate": proportion_json(&t.divert_rate(CONFIDENCE)),
        "overload_rate": proportion_json(&t.overload_rate(CONFIDENCE)),
        "tipping_rate": proportion_json(&t.tipping_rate(CONFIDENCE)),
        "failures_by_reason": t.by_reason,
    })
}

/// The options once checked: the run's options and the sweep's key and values.
pub type StudyChecked = Swept<Options>;

impl StudyChecked {
    /// The points on `scenario`: itself or a variant per swept value (the swept key set on
    /// the resolved scenario, exactly as `--set` would on its file).
    fn points(&self, scenario: &Loaded) -> Result<Vec<Point>, Vec<Problem>> {
        variant_points(scenario, self.sweep.as_ref(), self.options.seed)
    }
}

/// The checked options bound to a scenario ([`crate::contract::Analysis::bind`]): each
/// point loaded once, a records log read once.
#[derive(Debug, Clone)]
pub struct StudyInputs {
    pub options: Options,
    pub sweep: Option<Sweep>,
    pub points: Vec<Point>,
}

/// A finished study: its points, the plan, the sweep and each point's result and trigger.
pub struct Study {
    pub points: Vec<Point>,
    pub plan: RunPlan,
    pub sweep: Option<Sweep>,
    pub results: Vec<(PointResult, StartRule)>,
}

/// Where a run's shards are kept in `memo` (a command's checkpoint, a cluster's pieces): as
/// Parquet bytes, each under its point's and its own key ([`MemoShards`]). A point is named
/// by its swept value, its seed and a digest of its scenario and mix, so that a shard of a
/// run on another scenario never goes under this run's key.
pub fn shard_store<'a>(memo: &'a dyn Memo, points: &[Point], plan: &RunPlan) -> MemoShards<'a> {
    MemoShards {
        memo,
        points: points
            .iter()
            .map(|p| {
                let made_of = memo::key("reliability-point", &(&p.loaded.scenario, &p.loaded.mix));
                (p.value.clone(), p.seed, made_of)
            })
            .collect(),
        plan: *plan,
    }
}

/// A finished study's sample table: its shards as `memo` kept them in the run (a shard it
/// does not hold is run again: the same samples), in order, into `out/samples.parquet`
/// and, with `csv`, `out/samples.csv`; returns the first `keep` failed samples with their
/// point.
pub fn write_samples(
    study: &Study,
    memo: &dyn Memo,
    out: &std::path::Path,
    csv: bool,
    keep: usize,
) -> Result<Vec<(usize, SampleRun)>, Error> {
    let store = shard_store(memo, &study.points, &study.plan);
    let shards: Vec<u64> = study.results.iter().map(|(r, _)| r.shards).collect();
    let shard = |i: usize, k: u64| match store.batches(i, k)? {
        Some(b) => Ok(b),
        None => {
            let (p, (_, trigger)) = (&study.points[i], &study.results[i]);
            let samples = run_shard(p, trigger, &study.plan, k, &no_progress)?;
            Ok(vec![crate::samples::to_batch(i, &samples)?])
        }
    };
    crate::samples::write_table(&shards, shard, out, csv, keep)
}

/// Progress of the contract's hooks as a [`Watch`]: a tick per simulation and, with a live
/// log (a server's page), the rates so far after each shard as one JSON line
/// ([`partial_json`]).
struct Ticks<'a> {
    progress: &'a (dyn Fn() + Sync),
    partials: Option<std::sync::Mutex<Box<dyn std::io::Write + Send>>>,
}

impl Watch for Ticks<'_> {
    fn tick(&self) {
        (self.progress)()
    }
    fn shard_tallied(&self, i: usize, tally: &Tally) {
        if let Some(out) = &self.partials {
            let mut out = out.lock().unwrap_or_else(|e| e.into_inner());
            // A log that cannot be written only loses the partial view.
            let _ = writeln!(out, "{}", partial_json(i, tally));
            let _ = out.flush();
        }
    }
}

/// The reliability study on the analysis contract (the CLI's `reliability`, Python's, a
/// server's): its shards kept in the hooks' memo ([`shard_store`]: a command's checkpoint,
/// resumed shard by shard), from which an edge writes the sample table ([`write_samples`]).
pub struct Reliability;

impl crate::contract::Analysis for Reliability {
    const NAME: &'static str = "reliability";
    const ABOUT: &'static str = "Divert and overload rates over a parcel mix ([mix]) with exact 95 % intervals, the failure breakdowns and the failure rate binned against every input; sweeps of a setting and a fixed or per-parcel trigger";
    const USES_TRIGGER: bool = true;
    type Options = Options;
    type Checked = StudyChecked;
    type Bound = StudyInputs;
    type Output = Study;

    fn warnings(o: &Options) -> Vec<Problem> {
        sweep_warning(o.sweep.as_ref())
    }

    fn validate(o: &Options) -> Result<StudyChecked, Vec<Problem>> {
        let mut problems = option_problems(o);
        let sweep = checked_sweep(o.sweep.as_ref(), &mut problems);
        match problems.is_empty() {
            true => Ok(StudyChecked {
                options: o.clone(),
                sweep,
            }),
            false => Err(problems),
        }
    }

    fn bind(c: StudyChecked, s: &Loaded) -> Result<StudyInputs, Vec<Problem>> {
        let points = c.points(s)?;
        let problems = draw_problems(&points, c.options.samples);
        if !problems.is_empty() {
            return Err(problems);
        }
        Ok(StudyInputs {
            options: c.options,
            sweep: c.sweep,
            points,
        })
    }

    fn work(c: &StudyInputs, _: &Loaded) -> crate::contract::Work {
        let simulations = estimated_simulations(&c.points, c.options.samples);
        crate::contract::Work {
            at_most: Some(simulations),
            at_least: simulations,
            units: simulations,
            unit: "runs",
            smaller: "use fewer `samples` (or sweep points, or table nodes)",
        }
    }

    fn run(
        _: &Loaded,
        c: &StudyInputs,
        hooks: &crate::contract::Hooks,
    ) -> Result<Study, crate::contract::Error> {
        let points = c.points.clone();
        let plan = plan(&c.options, &points);
        let watch = Ticks {
            progress: hooks.progress,
            partials: hooks
                .live
                .and_then(|open| open("partial.jsonl"))
                .map(std::sync::Mutex::new),
        };
        let store = shard_store(hooks.memo, &points, &plan);
        let results = run_with(&points, &plan, &store, hooks.stop, &watch, &|_, p| {
            trigger_for(p, &watch)
        })?;
        Ok(Study {
            points,
            plan,
            sweep: c.sweep.clone(),
            results,
        })
    }

    fn summary(r: &Study, _: &StudyInputs, _: &Loaded) -> Value {
        summary_json(r.sweep.as_ref(), &r.plan, &r.points, &r.results)
    }

    fn described_file<'a>(r: &'a Study, scenario: &'a Loaded) -> &'a crate::config::ScenarioFile {
        // The first point's scenario, as the CLI writes it.
        r.points.first().map_or(&scenario.file, |p| &p.loaded.file)
    }

    fn tables(r: &Study) -> Result<Vec<(String, Vec<u8>)>, crate::contract::Error> {
        Ok(vec![
            (
                "failure_rates.csv".into(),
                failure_rates_csv(&r.points, &r.results),
            ),
            (
                "load_spectrum.csv".into(),
                load_spectrum_csv(&r.points, &r.results),
            ),
        ])
    }

    fn text(r: &Study, _: &StudyInputs, _: &Loaded) -> String {
        text(
            &r.plan,
            &r.points,
            &r.results,
            r.sweep.as_ref().map(|(k, _)| k.as_str()),
        )
    }
}

/// A reliability run's pieces are its points' shards, each kept as the bytes of its
/// Parquet file ([`MemoShards`]); a worker builds a point's trigger once, on first use.
impl crate::pieces::Pieces for Reliability {
    type Prepared = Vec<std::sync::OnceLock<Result<StartRule, Error>>>;

    fn prepare(c: &StudyInputs) -> Result<Self::Prepared, Error> {
        Ok(c.points
            .iter()
            .map(|_| std::sync::OnceLock::new())
            .collect())
    }

    fn pieces(c: &StudyInputs) -> Vec<crate::pieces::Piece> {
        let plan = plan(&c.options, &c.points);
        // The points' digests once, for every key.
        let store = shard_store(&divertsim_core::run::memo::NoMemo, &c.points, &plan);
        (0..c.points.len())
            .flat_map(|point| (0..plan.shards()).map(move |k| (point, k)))
            .map(|(point, k)| crate::pieces::Piece {
                point,
                k,
                key: store.key(point, k),
            })
            .collect()
    }

    fn run_piece(
        c: &StudyInputs,
        triggers: &Self::Prepared,
        point: usize,
        k: u64,
    ) -> Result<Vec<u8>, Error> {
        let plan = plan(&c.options, &c.points);
        let (Some(p), Some(trigger)) = (c.points.get(point), triggers.get(point)) else {
            return Err(crate::pieces::no_piece(
                "point",
                point as u64,
                c.points.len() as u64,
            ));
        };
        if k >= plan.shards() {
            return Err(crate::pieces::no_piece("shard", k, plan.shards()));
        }
        let trigger = trigger
            .get_or_init(|| trigger_for(p, &Quiet))
            .as_ref()
            .map_err(Clone::clone)?;
        let s = run_shard(p, trigger, &plan, k, &no_progress)?;
        crate::samples::to_parquet_bytes(point, &s)
    }
}

pub use divertsim_core::analysis::population::reliability::CONFIDENCE;

/// Largest number of shards of a point (pieces of a checkpoint).
pub const MAX_SHARDS: u64 = 100_000;

/// Every point's first samples must be drawable (a hopeless mix is found before any run).
pub fn draw_problems(points: &[Point], samples: u64) -> Vec<Problem> {
    let mut out = Vec::new();
    for p in points {
        let s = &p.loaded.scenario;
        if let Some(e) = (0..samples.min(1000)).find_map(|i| p.loaded.mix.draw(s, p.seed, i).err())
        {
            let m = Problem::new("mix", e.to_string());
            if !out.contains(&m) {
                out.push(m);
            }
        }
    }
    out
}

pub fn bins_json(b: &Bins) -> Value {
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

pub fn histogram_json(b: &Option<Bins>) -> Value {
    match b {
        None => Value::Null,
        Some(b) => json!({
            "edges": b.edges,
            "counts": b.count,
            "note": "values outside [lo, hi] are counted in the end bins",
        }),
    }
}

/// The scenario file of the stroke with the largest peak drive torque of point `p`:
/// `simulate` on it gives that peak again (to the rounding of φ through degrees).
pub fn largest_stroke_file(p: &Point, t: &Tally) -> Option<crate::config::ScenarioFile> {
    t.loads.largest.as_ref().map(|(_, s)| sample_file(p, s))
}

/// largest_stroke.toml (pointK_largest_stroke.toml in a sweep): each point's stroke with
/// the largest peak drive torque, as a scenario file for `simulate`.
pub fn largest_stroke_files(
    points: &[Point],
    results: &[(PointResult, StartRule)],
) -> Vec<(String, Vec<u8>)> {
    let mut files = Vec::new();
    for (i, (p, (r, _))) in points.iter().zip(results).enumerate() {
        let (Some(file), Some(s)) = (
            largest_stroke_file(p, &r.tally),
            r.tally.loads.largest.as_ref().map(|(_, s)| s),
        ) else {
            continue;
        };
        let name = largest_stroke_name(points.len(), i);
        let heading = format!(
            "Sample {} of a `divertsim reliability` run (seed {}{}): the stroke with the largest \
             peak drive torque, {} N·m. `divertsim simulate` on this file gives it again.",
            s.draw.index,
            p.seed,
            if p.value.is_empty() {
                String::new()
            } else {
                format!(", sweep point {}", p.value)
            },
            s.arm_peak_torque.unwrap_or(f64::NAN)
        );
        if let Ok(text) = crate::config::to_toml(&file, &heading) {
            files.push((name, text.into_bytes()));
        }
    }
    files
}

/// load_spectrum.csv of a study: every point's [`load_spectrum_rows`].
pub fn load_spectrum_csv(points: &[Point], results: &[(PointResult, StartRule)]) -> Vec<u8> {
    let rows: Vec<Vec<String>> = points
        .iter()
        .zip(results)
        .enumerate()
        .flat_map(|(i, (p, (r, _)))| load_spectrum_rows(i, &p.value, &r.tally.loads))
        .collect();
    crate::output::csv_bytes(&LOAD_SPECTRUM_COLUMNS, &rows).unwrap_or_default()
}

pub fn point_json(p: &Point, r: &PointResult, trigger: &StartRule) -> Value {
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
                StartRule::Fixed => json!(m.start_position),
                StartRule::Adaptive(_) => Value::Null,
            },
            "light_barrier_m": m.light_barrier,
            "trigger": trigger.label(),
        },
        "samples": t.samples,
        "stopped_early": r.stopped_early,
        "divert_rate": proportion_json(&divert),
        "failure_rate": proportion_json(&failure),
        "overload_rate": proportion_json(&overload),
        "tipping_rate": proportion_json(&t.tipping_rate(CONFIDENCE)),
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
        "load_spectrum": load_spectrum_json(
            &t.loads,
            "equal bins from 0 to a round ceiling fixed by the first shard; loads above it counted apart; counts per 10^6 strokes for a fatigue assessment",
            t.loads.largest.as_ref().map(|(_, s)| json!({
                "sample": s.draw.index,
                "peak_drive_torque_n_m": s.arm_peak_torque,
                "scenario": largest_stroke_file(p, t).and_then(|f| serde_json::to_value(f).ok()),
            })),
        ),
        "first_failures_note": "the first failed samples (at most 20), in sample order; each scenario runs that sample again with simulate",
        "first_failures": t.first_failures.iter().map(|s| json!({
            "sample": s.draw.index,
            "reason": s.reason(),
            "final_stage": s.final_stage.label(),
            "scenario": serde_json::to_value(sample_file(p, s)).ok(),
        })).collect::<Vec<_>>(),
        "trigger_table": match trigger {
            StartRule::Fixed => Value::Null,
            StartRule::Adaptive(t) => json!({
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

pub fn summary_json(
    sweep: Option<&(String, Vec<String>)>,
    plan: &RunPlan,
    points: &[Point],
    results: &[(PointResult, StartRule)],
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
        "sweep": sweep.map(|(k, v)| json!({"key": k, "values": v})),
        "points": points.iter().zip(results).map(|(p, (r, t))| point_json(p, r, t)).collect::<Vec<_>>(),
        "scenario": scenario,
    })
}

/// failure_rates.csv: one row per point, input and non-empty bin.
pub fn failure_rates_csv(points: &[Point], results: &[(PointResult, StartRule)]) -> Vec<u8> {
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
    crate::output::csv_bytes(
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

/// A short setting line: v, t_c, R_s, trigger (numbers to 4 decimals, for titles).
pub fn setting_line(p: &Point, trigger: &StartRule) -> String {
    let m = &p.loaded.scenario.machine;
    let short = |v: f64| {
        let t = format!("{v:.4}");
        match t.trim_end_matches('0').trim_end_matches('.') {
            "-0" | "" => "0".to_string(),
            t => t.to_string(),
        }
    };
    format!(
        "v = {} m/s, t_c = {} s, R_s = {} m, S_d = {} m, {} trigger",
        short(m.belt_speed),
        short(m.cycle_time),
        short(m.start_position),
        short(m.light_barrier),
        trigger.label()
    )
}

/// An estimate with its interval.
pub fn interval_text(p: &Proportion) -> String {
    format!("{:.5}  [{:.5}, {:.5}]", p.estimate, p.lower, p.upper)
}

/// The readable report of a study: per point, or the sweep over the scenario key `swept`.
pub fn text(
    plan: &RunPlan,
    points: &[Point],
    results: &[(PointResult, StartRule)],
    swept: Option<&str>,
) -> String {
    let mut s = String::new();
    if let Some(key) = swept {
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
    if let (Some(w), false) = (plan.until_width, r.stopped_early) {
        let width = |p: &Proportion| p.upper - p.lower;
        let _ = writeln!(
            s,
            "  NOT narrow enough: the intervals are {:.5} (divert) and {:.5} (overload) wide after all {} samples, not {w}; raise --samples (the work limit --max-sims allows more)",
            width(&t.divert_rate(CONFIDENCE)),
            width(&t.overload_rate(CONFIDENCE)),
            t.samples
        );
    }
    let _ = writeln!(
        s,
        "  tipped over     {}  (the centre of mass went over an edge)",
        interval_text(&t.tipping_rate(CONFIDENCE))
    );
    let _ = writeln!(s, "  capacity        {:.0} parcels/h", t.capacity());
    if let Some((_, l)) = &t.loads.largest {
        let strikes = t.loads.largest_strike();
        let _ = writeln!(
            s,
            "  arm loads       peak drive torque up to {:.2} N·m (sample {}, largest_stroke.toml), strikes up to {:.4} N·m·s on the arm, over {} strokes (load_spectrum.csv)",
            l.arm_peak_torque.unwrap_or(f64::NAN),
            l.draw.index,
            strikes,
            t.loads.strokes
        );
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config;
    use crate::contract::Analysis;
    use divertsim_core::run::sweep::no_progress;
    use std::path::Path;

    fn hub_points(sweep: Option<&(String, Vec<String>)>) -> Vec<Point> {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/mix/hub.toml");
        let load =
            |sets: &[String]| config::load_with(Some(&path), sets, config::LoadOptions::default());
        load_points(&load, sweep, None).expect("the hub mix loads")
    }

    /// The cluster contract: shards run one by one elsewhere, then handed back, give the
    /// run on one machine bit for bit (tally, early stop, summary), whatever the thread
    /// count of either.
    #[test]
    fn shards_run_apart_merge_to_the_single_run() {
        let sweep = (
            "machine.belt_speed".to_string(),
            vec!["1.8".into(), "2.2".into()],
        );
        let points = hub_points(Some(&sweep));
        let options = Options {
            samples: 450,
            shard: 100,
            bins: 4,
            ..Options::default()
        };
        assert!(check(&options, &points).is_empty());
        let plan = plan(&options, &points);
        let whole = crate::threads::with_threads(Some(2), || run_quietly(&points, &plan)).unwrap();
        let memo = divertsim_core::run::memo::InMemory::default();
        let given = shard_store(&memo, &points, &plan);
        for (i, p) in points.iter().enumerate() {
            let trigger = trigger_for(p, &Quiet).unwrap();
            for k in (0..plan.shards()).rev() {
                let s = crate::threads::with_threads(Some(1), || {
                    run_shard(p, &trigger, &plan, k, &no_progress)
                })
                .unwrap();
                given.save(i, k, &s).unwrap();
            }
        }
        let merged = run_with(&points, &plan, &given, &|| false, &Quiet, &|_, p| {
            trigger_for(p, &Quiet)
        })
        .unwrap();
        assert_eq!(merged.len(), 2);
        for ((a, _), (b, _)) in whole.iter().zip(&merged) {
            assert_eq!(a.tally, b.tally);
            assert_eq!(a.shards, b.shards);
            assert_eq!(b.resumed_shards, plan.shards());
        }
        let sj = |r: &[(PointResult, StartRule)]| {
            serde_json::to_string(&summary_json(Some(&sweep), &plan, &points, r)).unwrap()
        };
        assert_eq!(sj(&whole), sj(&merged));
        // The two points differ: the sweep is not a no-op.
        assert_ne!(whole[0].0.tally, whole[1].0.tally);
    }

    /// The CLI's checkpoint: a run on the contract keeps every shard in the hooks' memo; a
    /// run resumed from shards lost in part gives the same study bit for bit, and the sample
    /// table written from the kept shards is the one written from shards run again.
    #[test]
    fn shards_kept_in_the_memo_resume_and_write_the_same_sample_table() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/mix/hub.toml");
        let loaded = config::ScenarioBuilder::file(&path).load().unwrap();
        let options = Options {
            samples: 250,
            shard: 100,
            ..Options::default()
        };
        let bound = Reliability::bind(Reliability::validate(&options).unwrap(), &loaded).unwrap();
        let memo = divertsim_core::run::memo::InMemory::default();
        let hooks = crate::contract::Hooks {
            memo: &memo,
            ..crate::contract::Hooks::none()
        };
        let first = Reliability::run(&loaded, &bound, &hooks).unwrap();
        assert_eq!(memo.keys().len(), 3, "one piece per shard");
        memo.forget(memo.keys()[0]);
        let again = Reliability::run(&loaded, &bound, &hooks).unwrap();
        assert_eq!(again.results[0].0.resumed_shards, 2);
        assert_eq!(again.results[0].0.tally, first.results[0].0.tally);
        let unkept = Reliability::run(&loaded, &bound, &crate::contract::Hooks::none()).unwrap();
        assert_eq!(unkept.results[0].0.tally, first.results[0].0.tally);

        let dir = tempfile::tempdir().unwrap();
        let (kept, rerun) = (dir.path().join("kept"), dir.path().join("rerun"));
        for d in [&kept, &rerun] {
            std::fs::create_dir(d).unwrap();
        }
        let a = write_samples(&first, &memo, &kept, true, 5).unwrap();
        let b = write_samples(&first, &divertsim_core::run::memo::NoMemo, &rerun, true, 5).unwrap();
        assert_eq!(a, b);
        for name in ["samples.parquet", "samples.csv"] {
            let (x, y) = (kept.join(name), rerun.join(name));
            assert_eq!(
                std::fs::read(x).unwrap(),
                std::fs::read(y).unwrap(),
                "{name}"
            );
        }
        let csv = std::fs::read_to_string(kept.join("samples.csv")).unwrap();
        assert_eq!(csv.lines().count(), 251);

        // A piece under a shard's key that holds other samples is refused, named.
        let store = shard_store(&memo, &first.points, &first.plan);
        let other = memo.recall(store.key(0, 1)).unwrap();
        memo.keep(store.key(0, 0), &other);
        let e = Reliability::run(&loaded, &bound, &hooks)
            .err()
            .expect("refused");
        assert!(
            e.to_string().contains("does not hold samples 0..100"),
            "{e}"
        );
    }

    #[test]
    fn option_problems_name_the_option_and_its_range() {
        let points = hub_points(None);
        let bad = Options {
            samples: 0,
            shard: 50,
            bins: 0,
            until_ci: Some(1.5),
            seed: None,
            sweep: None,
        };
        let keys: Vec<String> = check(&bad, &points).into_iter().map(|p| p.key).collect();
        assert_eq!(keys, ["samples", "shard", "bins", "until_ci"]);
    }
}
