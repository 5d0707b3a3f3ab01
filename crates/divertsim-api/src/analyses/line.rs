//! The sorter line (issue 25): a stream of parcels through one or more diverters, each
//! parcel's physics against the arms' real timelines, the outcome of every parcel and the
//! throughput the line delivers, with optional sweeps of one scenario key over the same
//! parcels. The work is `divertsim_core::analysis::line`; the scenario's `[line]` section
//! says what the line is ([`crate::config::line`]).
//!
//! Segments are kept in the caller's memo as they finish, so an interrupted run resumes
//! where it stopped and gives the same bytes.
//!
//! **Memory.** Each finished segment is reduced at once to the compact parcel log
//! ([`ParcelLog`], 24 bytes a parcel) and the few parcels kept whole ([`KEPT_FIRST`],
//! [`KEPT_FAILURES`]): a run holds its segments in flight (a few hundred bytes a parcel,
//! [`divertsim_core::analysis::line`]) and its log, nothing that grows with the runs.

use super::line_tables::{diverters_csv, parcels_parquet, points_csv, TableRow};
use super::population::{
    checked_sweep, finite_or_null, largest_stroke_name, load_spectrum_json, load_spectrum_rows,
    proportion_json, sweep_warning, table_simulations, variant_points, Point, Sweep, SweepSpec,
    Swept, LOAD_SPECTRUM_COLUMNS,
};
use crate::analyses::cells::pct;
use crate::config::line::{diverter_scenarios, machine_changes, read_arrivals, BusyRuleConfig};
use crate::config::mix::TriggerConfig;
use crate::config::{Loaded, Problem, ScenarioFile};
use crate::contract::{Analysis, Error, Hooks, Work};
use divertsim_core::analysis::line::log::ParcelLog;
use divertsim_core::analysis::line::study::{LineRun, LineSegments};
use divertsim_core::analysis::line::tally::LineTally;
use divertsim_core::analysis::line::{
    BusyRule, Diverter, Induction, Line, LineOutcome, LineParcel, MachineChanges, RunInputs,
    Segment,
};
use divertsim_core::analysis::population::reliability::{StartRule, CONFIDENCE};
use divertsim_core::run::memo::{self, Memo, NoMemo};
use divertsim_core::run::study::{execute, Control, InMemo, Study, StudyError};
use divertsim_core::run::sweep::no_progress;
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::io::Write;

/// The options of a line run besides the scenario (`divertsim line`, Python `line`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct Options {
    /// Parcels in the stream (per sweep point), 1 to 100000000.
    #[schemars(extend("x-value" = "N"))]
    pub parcels: u64,
    /// Parcels per segment, 10 to 1000000: each segment starts with an empty belt and every
    /// arm at rest, runs on its own core and is the unit of `--resume`.
    #[schemars(extend("x-value" = "N"))]
    pub segment: u64,
    /// Seed of the random streams (default: mix.seed, else 1). Parcel i depends only on
    /// (seed, i): every sweep point sees the same parcels.
    #[schemars(extend("x-value" = "SEED"))]
    pub seed: Option<u64>,
    /// Sweep one scenario key over the same parcels: KEY=LO:HI/N, KEY=LO:HI:STEP or
    /// KEY=A,B,... (e.g. line.gap_target=0.25:4/16, machine.belt_speed=1.6,2.0); or a mapping of
    /// one key to its values.
    #[schemars(extend("x-value" = "KEY=LO:HI/N"))]
    pub sweep: Option<SweepSpec>,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            parcels: 10_000,
            segment: 1_000,
            seed: None,
            sweep: None,
        }
    }
}

/// A point of a line run: its scenario, every diverter's file, and the line (adaptive
/// triggers still to build).
#[derive(Debug, Clone)]
pub struct LinePoint {
    pub point: Point,
    /// Each diverter's scenario file, in order down the belt.
    pub files: Vec<ScenarioFile>,
    pub line: Line,
}

/// The checked options.
pub type LineChecked = Swept<Options>;

/// The checked options bound to a scenario ([`Analysis::bind`]): its points, each loaded
/// and its line built once.
#[derive(Debug, Clone)]
pub struct LineInputs {
    pub options: Options,
    pub sweep: Option<Sweep>,
    pub points: Vec<LinePoint>,
}

/// The line of a loaded point (fixed triggers; adaptive ones are built in the run).
pub fn line_of(loaded: &Loaded) -> Result<(Vec<ScenarioFile>, Line), Vec<Problem>> {
    line_with(loaded, induction_of(loaded)?)
}

/// The induction of a loaded point's `[line]`: its gaps, or its arrival log read.
pub fn induction_of(loaded: &Loaded) -> Result<Induction, Vec<Problem>> {
    let l = &loaded.file.line;
    Ok(match &l.arrivals {
        Some(path) => Induction::Times(
            read_arrivals(std::path::Path::new(path))
                .map_err(|e| vec![Problem::new("line.arrivals", format!("{path}: {e}"))])?
                .into(),
        ),
        None => {
            let (gap, min) = l.gap();
            Induction::Gaps { gap, min }
        }
    })
}

/// [`line_of`] with the induction given (read once for many variants of a scenario whose
/// `[line]` they do not change).
pub fn line_with(
    loaded: &Loaded,
    induction: Induction,
) -> Result<(Vec<ScenarioFile>, Line), Vec<Problem>> {
    let l = &loaded.file.line;
    let scenarios = diverter_scenarios(&loaded.file)?;
    let shares = std::iter::once(l.share).chain(l.diverters.iter().map(|d| d.share));
    let positions = std::iter::once(0.0).chain(l.diverters.iter().map(|d| d.position));
    let own = std::iter::once(None).chain(l.diverters.iter().map(|d| Some(&d.machine)));
    let mut files = Vec::new();
    let mut diverters = Vec::new();
    for ((((file, setting), share), position), own) in
        scenarios.into_iter().zip(shares).zip(positions).zip(own)
    {
        diverters.push(Diverter {
            position,
            changes: own.map_or_else(MachineChanges::default, |t| {
                machine_changes(t, &setting.machine)
            }),
            table: file.machine.adaptive.nodes(),
            setting,
            trigger: StartRule::Fixed,
            share,
        });
        files.push(file);
    }
    Ok((
        files,
        Line {
            diverters,
            induction,
            mix: loaded.mix.clone(),
            busy: match l.busy_rule {
                BusyRuleConfig::Skip => BusyRule::Skip,
                BusyRuleConfig::Late => BusyRule::Late {
                    max_delay: l.max_delay,
                },
                BusyRuleConfig::Barrier => BusyRule::Barrier,
            },
            duration_given: loaded.file.run.duration.is_some(),
        },
    ))
}

impl LineChecked {
    /// The points on `scenario`: itself or a variant per swept value.
    fn points(&self, scenario: &Loaded) -> Result<Vec<LinePoint>, Vec<Problem>> {
        let points = variant_points(scenario, self.sweep.as_ref(), self.options.seed)?;
        let mut out = Vec::new();
        let mut problems = Vec::new();
        for point in points {
            match line_of(&point.loaded) {
                Ok((files, line)) => out.push(LinePoint { point, files, line }),
                Err(p) => problems.extend(p),
            }
        }
        match problems.is_empty() {
            true => Ok(out),
            false => Err(problems),
        }
    }
}

pub use divertsim_core::analysis::line::study::{KEPT_FAILURES, KEPT_FIRST};

/// One point's result.
#[derive(Debug, Clone)]
pub struct LineResult {
    pub point: LinePoint,
    pub tally: LineTally,
    /// Every parcel, in stream order, compact: the parcel log (line_parcels.parquet).
    pub log: ParcelLog,
    /// The parcels kept whole, with the run that decided a failure, in stream order: the
    /// first [`KEPT_FIRST`] of the stream and the first [`KEPT_FAILURES`] failures of each
    /// outcome (a bounded few, whatever the stream's length).
    pub parcels: Vec<LineParcel>,
}

/// A finished line run.
#[derive(Debug, Clone)]
pub struct LineStudy {
    pub sweep: Option<Sweep>,
    pub options: Options,
    pub results: Vec<LineResult>,
}

/// Segments of a point.
pub fn segments(o: &Options) -> u64 {
    o.parcels.div_ceil(o.segment.max(1))
}

/// The `line` analysis.
pub struct LineAnalysis;

impl Analysis for LineAnalysis {
    const NAME: &'static str = "line";
    const ABOUT: &'static str = "A sorter line ([line]): a stream of parcels with gaps through one or more diverters, every parcel's physics against the arms' real strokes; throughput, each outcome's rate (diverted, arm_busy, struck_in_passing, collision, …) and the parcel log";
    const USES_TRIGGER: bool = true;
    type Options = Options;
    type Checked = LineChecked;
    type Bound = LineInputs;
    type Output = LineStudy;

    fn warnings(o: &Options) -> Vec<Problem> {
        sweep_warning(o.sweep.as_ref())
    }

    fn validate(o: &Options) -> Result<LineChecked, Vec<Problem>> {
        let mut problems = Vec::new();
        if !(1..=100_000_000).contains(&o.parcels) {
            problems.push(Problem::new(
                "parcels",
                format!("{} is out of range; allowed: 1 to 100000000", o.parcels),
            ));
        }
        if !(10..=1_000_000).contains(&o.segment) {
            problems.push(Problem::new(
                "segment",
                format!("{} is out of range; allowed: 10 to 1000000", o.segment),
            ));
        }
        let sweep = checked_sweep(o.sweep.as_ref(), &mut problems);
        match problems.is_empty() {
            true => Ok(LineChecked {
                options: o.clone(),
                sweep,
            }),
            false => Err(problems),
        }
    }

    fn bind(c: LineChecked, s: &Loaded) -> Result<LineInputs, Vec<Problem>> {
        let points = c.points(s)?;
        // A mix that puts no parcel on the belt is found before any run.
        let problems: Vec<Problem> = points
            .iter()
            .filter_map(|p| {
                p.line
                    .mix
                    .draw(&p.line.diverters[0].setting, p.point.seed, 0)
                    .err()
                    .map(|e| Problem::new("mix", e.to_string()))
            })
            .collect();
        if !problems.is_empty() {
            return Err(problems);
        }
        Ok(LineInputs {
            options: c.options,
            sweep: c.sweep,
            points,
        })
    }

    fn work(c: &LineInputs, _: &Loaded) -> Work {
        let points = &c.points;
        // At most one run per parcel and diverter (most parcels pass most arms unsimulated).
        let simulations = points
            .iter()
            .map(|p| {
                c.options.parcels * p.line.diverters.len() as u64
                    + p.files
                        .iter()
                        .map(|f| table_simulations(&f.machine))
                        .sum::<u64>()
            })
            .sum();
        // A parcel is simulated only where it meets an arm: the tables' searches are the
        // work certain.
        let tables = points
            .iter()
            .flat_map(|p| &p.files)
            .map(|f| table_simulations(&f.machine))
            .sum();
        Work {
            at_most: Some(simulations),
            at_least: tables,
            units: segments(&c.options) * points.len() as u64,
            unit: "segments",
            smaller: "use fewer `parcels` (or sweep points)",
        }
    }

    fn run(_: &Loaded, c: &LineInputs, hooks: &Hooks) -> Result<LineStudy, Error> {
        let o = &c.options;
        let mut results = Vec::new();
        // With a live log (a server's page), the rates so far after each batch of segments.
        let mut partials = hooks.live.and_then(|open| open("partial.jsonl"));
        for (i, p) in prepare(c)?.into_iter().enumerate() {
            // Batches of segments in parallel; a stop is honoured between batches, and within
            // a segment before each parcel's passage. Kept under the point as bound.
            let study = segments_of(&p, o);
            let store = segment_store(hooks.memo, &c.points[i], o);
            let mut batch_done = |t: &LineRun| {
                if let Some(out) = partials.as_mut() {
                    // A log that cannot be written only loses the partial view.
                    let _ = writeln!(out, "{}", partial_json(i, &t.tally));
                    let _ = out.flush();
                }
            };
            let run = execute(
                &study,
                LineRun::new(p.line.diverters.len(), p.point.seed),
                &store,
                &mut Control {
                    stop: hooks.stop,
                    piece_done: hooks.progress,
                    inside: &|| hooks.stop_point(),
                    batch_done: &mut batch_done,
                },
            )
            .map_err(study_error)?
            .tally;
            results.push(LineResult {
                point: p,
                tally: run.tally,
                log: run.log,
                parcels: run.kept,
            });
        }
        Ok(LineStudy {
            sweep: c.sweep.clone(),
            options: o.clone(),
            results,
        })
    }

    fn summary(r: &LineStudy, _: &LineInputs, _: &Loaded) -> Value {
        json!({
            "parcels": r.options.parcels,
            "segment": r.options.segment,
            "sweep": r.sweep.as_ref().map(|(k, _)| k),
            "confidence": CONFIDENCE,
            "points": r.results.iter().map(point_json).collect::<Vec<_>>(),
        })
    }

    fn described_file<'a>(r: &'a LineStudy, scenario: &'a Loaded) -> &'a ScenarioFile {
        r.results
            .first()
            .map_or(&scenario.file, |p| &p.point.point.loaded.file)
    }

    fn tables(r: &LineStudy) -> Result<Vec<(String, Vec<u8>)>, Error> {
        let rows: Vec<TableRow> = r
            .results
            .iter()
            .map(|p| TableRow {
                value: &p.point.point.value,
                line: &p.point.line,
                tally: &p.tally,
                log: &p.log,
            })
            .collect();
        let spectra: Vec<Vec<String>> = r
            .results
            .iter()
            .enumerate()
            .flat_map(|(i, p)| {
                let t = &p.tally;
                let value = &p.point.point.value;
                load_spectrum_rows(i, value, &t.loads)
            })
            .collect();
        Ok(vec![
            ("line.csv".into(), points_csv(&rows)?),
            ("line_diverters.csv".into(), diverters_csv(&rows)?),
            ("line_parcels.parquet".into(), parcels_parquet(&rows)?),
            (
                "load_spectrum.csv".into(),
                crate::output::csv_bytes(&LOAD_SPECTRUM_COLUMNS, &spectra).map_err(Error::io)?,
            ),
        ])
    }

    fn text(r: &LineStudy, _: &LineInputs, _: &Loaded) -> String {
        text(r)
    }

    fn simulations(r: &LineStudy) -> Option<u64> {
        Some(r.results.iter().map(|p| p.tally.simulations).sum())
    }
}

/// Build the adaptive trigger tables of a point's diverters (their searches run here).
pub fn build_triggers(p: &mut LinePoint) -> Result<(), Error> {
    p.line
        .build_triggers(p.point.seed, &no_progress)
        .map_err(|e| Error::Failed(e.to_string()))
}

/// The points of a bound run, each with its adaptive triggers built: what every
/// segment of a point needs (a cluster's job prepares them once).
pub fn prepare(c: &LineInputs) -> Result<Vec<LinePoint>, Error> {
    let mut points = c.points.clone();
    for p in &mut points {
        build_triggers(p)?;
    }
    Ok(points)
}

/// What every segment of point `p` depends on, as a memo key: its line and its diverters'
/// files as bound (an adaptive trigger's table is a function of them, so the key is known
/// before any table is built), its seed and the run's parcels and segment.
pub fn line_key(p: &LinePoint, o: &Options) -> u64 {
    memo::key(
        "line",
        &(&p.line, &p.files, p.point.seed, o.parcels, o.segment),
    )
}

/// Point `p`'s stream as a study: its segments.
pub fn segments_of<'a>(p: &'a LinePoint, o: &Options) -> LineSegments<'a> {
    LineSegments::new(&p.line, p.point.seed, o.parcels, o.segment)
}

/// What the line's segments are, in their memo keys.
// With the version of its record: the memo's encoding does not describe itself, so a
// segment kept in another record shape (before RunInputs held a ParcelRun) is never
// decoded as this one; it is simply not found, and run again.
const SEGMENT_KIND: &str = "line-segment-2";

/// Where point `p`'s segments are kept in `memo`: each under [`segment_key`].
pub fn segment_store<'a>(memo: &'a dyn Memo, p: &LinePoint, o: &Options) -> InMemo<'a> {
    InMemo {
        memo,
        kind: SEGMENT_KIND,
        study: line_key(p, o),
    }
}

/// The memo key of segment `k` of the point whose [`line_key`] is `line`.
pub fn segment_key(line: u64, k: u64) -> u64 {
    InMemo {
        memo: &NoMemo,
        kind: SEGMENT_KIND,
        study: line,
    }
    .key(k)
}

/// Segment `k` of point `p`, run here.
pub fn segment(p: &LinePoint, o: &Options, k: u64) -> Result<Segment, Error> {
    segments_of(p, o)
        .run_piece(k, &no_progress)
        .map_err(Error::failed)
}

/// A line run's pieces are its points' segments, each kept in the memo's encoding; a job
/// builds the points' adaptive triggers once.
impl crate::pieces::Pieces for LineAnalysis {
    type Prepared = Vec<LinePoint>;

    fn prepare(c: &LineInputs) -> Result<Vec<LinePoint>, Error> {
        prepare(c)
    }

    fn pieces(c: &LineInputs) -> Vec<crate::pieces::Piece> {
        let n = segments(&c.options);
        c.points
            .iter()
            .enumerate()
            .flat_map(|(point, p)| {
                let line = line_key(p, &c.options);
                (0..n).map(move |k| crate::pieces::Piece {
                    point,
                    k,
                    key: segment_key(line, k),
                })
            })
            .collect()
    }

    fn run_piece(
        c: &LineInputs,
        points: &Vec<LinePoint>,
        point: usize,
        k: u64,
    ) -> Result<Vec<u8>, Error> {
        let o = &c.options;
        let Some(p) = points.get(point) else {
            return Err(crate::pieces::no_piece(
                "point",
                point as u64,
                points.len() as u64,
            ));
        };
        if k >= segments(o) {
            return Err(crate::pieces::no_piece("segment", k, segments(o)));
        }
        memo::encode(&segment(p, o, k)?)
            .ok_or_else(|| Error::Failed("a segment could not be encoded".into()))
    }
}

/// A study's failure as the contract's error (a stop is [`Error::Cancelled`]).
pub fn study_error(e: StudyError<impl std::fmt::Display>) -> Error {
    match e {
        StudyError::Stopped => Error::Cancelled,
        StudyError::Piece(e) => Error::failed(e),
        StudyError::Store(e) => Error::failed(e),
    }
}

/// A point's results so far: its parcels, the arrival rate and throughput, and the missort,
/// struck, overload and tipped rates with their intervals.
pub fn partial_json(point: usize, t: &LineTally) -> Value {
    json!({
        "point": point,
        "parcels": t.parcels,
        "arrival_rate_per_h": finite_or_null(t.arrival_rate()),
        "throughput_per_h": finite_or_null(t.line_throughput()),
        "missort_rate": proportion_json(&t.missort_rate(CONFIDENCE)),
        "struck_rate": proportion_json(&t.struck_rate(CONFIDENCE)),
        "overload_rate": proportion_json(&t.overload_rate(CONFIDENCE)),
        "tipped_rate": proportion_json(&tipped_rate(t)),
    })
}

/// The share of the stream that tipped, with its interval.
fn tipped_rate(t: &LineTally) -> divertsim_core::stats::binomial::Proportion {
    divertsim_core::stats::binomial::clopper_pearson(
        t.reasons.get("tipped").copied().unwrap_or(0),
        t.parcels,
        CONFIDENCE,
    )
}

fn point_json(r: &LineResult) -> Value {
    let t = &r.tally;
    let line = &r.point.line;
    let outcomes: serde_json::Map<String, Value> = LineOutcome::KINDS
        .iter()
        .map(|k| (k.to_string(), proportion_json(&t.rate(k, CONFIDENCE))))
        .collect();
    json!({
        "value": r.point.point.value,
        "seed": r.point.point.seed,
        "parcels": t.parcels,
        "time_s": t.time,
        "arrival_rate_per_h": finite_or_null(t.arrival_rate()),
        "arrivals_log_replays": line.induction.replays(t.parcels).map(|(_, k)| k),
        "throughput_per_h": finite_or_null(t.line_throughput()),
        "outcomes": outcomes,
        "not_diverted_reasons": t.reasons,
        "missort_rate": proportion_json(&t.missort_rate(CONFIDENCE)),
        "struck_rate": proportion_json(&t.struck_rate(CONFIDENCE)),
        "overload_rate": proportion_json(&t.overload_rate(CONFIDENCE)),
        "tipped_rate": proportion_json(&tipped_rate(t)),
        "load_spectrum": load_spectrum_json(
            &t.loads,
            "every stroke of every arm (an arm's own inertia where no parcel loaded it); equal bins from 0 to a round ceiling fixed by the first segment with a load; loads above it counted apart; counts per 10^6 strokes",
            t.loads.largest.as_ref().map(|(peak, run)| json!({
                "diverter": run.diverter + 1,
                "peak_drive_torque_n_m": peak,
                "scenario": run_file(r, run).and_then(|f| serde_json::to_value(f).ok()),
            })),
        ),
        "simulations": t.simulations,
        "diverters": line.diverters.iter().enumerate().map(|(d, div)| {
            let c = &t.diverters[d];
            json!({
                "diverter": d + 1,
                "position_m": div.position,
                "share": div.share,
                "bound": c.bound,
                "diverted": c.diverted,
                "arm_busy": c.busy,
                "not_diverted": c.not_diverted,
                "wrongly_diverted_here": c.wrongly_diverted,
                "divert_rate": proportion_json(&t.divert_rate(d, CONFIDENCE)),
                "throughput_per_h": finite_or_null(t.throughput(d)),
                "paper_capacity_per_h": finite_or_null(div.paper_capacity()),
                "cycles": c.cycles,
                "utilisation": finite_or_null(t.utilisation(line, d)),
            })
        }).collect::<Vec<_>>(),
    })
}

/// What each outcome means, for the report's legend.
pub const OUTCOME_LEGEND: [(&str, &str); 8] = [
    ("diverted", "into its own chute"),
    ("passed", "bound straight through and never touched"),
    (
        "arm_busy",
        "its arm was still in a cycle at the planned start: not served",
    ),
    (
        "not_diverted",
        "served, but the physics left it on the belt (see the reasons)",
    ),
    (
        "struck_in_passing",
        "touched by a stroke not meant for it, and not diverted",
    ),
    (
        "wrongly_diverted",
        "pushed into a chute it was not bound for",
    ),
    (
        "collision",
        "its footprint overlapped a neighbour's (detected, not resolved)",
    ),
    ("failed", "a run failed numerically"),
];

/// The readable report: with a sweep, first one line per point (issue 50: the full tables
/// of every point follow), a point with collisions marked as outside the model.
pub fn text(r: &LineStudy) -> String {
    let mut s = String::new();
    if let Some((key, _)) = &r.sweep {
        let _ = writeln!(
            s,
            "sweep of {key}: one line per point (the full tables follow)\n\n  {:>12}  {:>10}  {:>12}  {:>9}  {:>9}  {:>9}  {:>9}  {:>9}",
            "value", "arrivals/h", "throughput/h", "arm_busy", "missort", "tipped", "overload", "collision"
        );
        let mut outside = false;
        for res in &r.results {
            let t = &res.tally;
            let collisions = t.rate("collision", CONFIDENCE).estimate;
            outside |= collisions > 0.0;
            let _ = writeln!(
                s,
                "  {:>12}  {:>10.0}  {:>12.0}  {:>9}  {:>9}  {:>9}  {:>9}  {:>9}{}",
                res.point.point.value,
                t.arrival_rate(),
                t.line_throughput(),
                pct(t.rate("arm_busy", CONFIDENCE).estimate, 3),
                pct(t.missort_rate(CONFIDENCE).estimate, 3),
                pct(tipped_rate(t).estimate, 3),
                pct(t.overload_rate(CONFIDENCE).estimate, 3),
                pct(collisions, 3),
                if collisions > 0.0 { "  *" } else { "" }
            );
        }
        if outside {
            let _ = writeln!(
                s,
                "  * parcels collided: contact between parcels is detected, not resolved, so \
                 these points are outside the model"
            );
        }
        let _ = writeln!(s);
    }
    for res in &r.results {
        let t = &res.tally;
        let line = &res.point.line;
        if let Some((key, _)) = &r.sweep {
            let _ = writeln!(s, "== {key} = {} ==", res.point.point.value);
        }
        let _ = writeln!(
            s,
            "line: {} parcels over {:.1} s of stream (arrival rate {:.0}/h) through {} diverter{}",
            t.parcels,
            t.time,
            t.arrival_rate(),
            line.diverters.len(),
            if line.diverters.len() == 1 { "" } else { "s" }
        );
        if let Some((headways, k)) = line.induction.replays(t.parcels) {
            let _ = writeln!(
                s,
                "arrivals: the log's {headways} headways are replayed {k:.2} times in order (the stream is longer than the log; give a longer log or fewer --parcels for a stream without repeats)"
            );
        }
        let _ = writeln!(
            s,
            "throughput: {:.0} parcels/h diverted into their own chute ({} of arrivals)",
            t.line_throughput(),
            pct(t.line_throughput() / t.arrival_rate(), 3)
        );
        let _ = writeln!(
            s,
            "\n  outcome              parcels     rate        95 % interval   meaning"
        );
        for (k, meaning) in OUTCOME_LEGEND {
            let p = t.rate(k, CONFIDENCE);
            let _ = writeln!(
                s,
                "  {k:<20} {:>8}   {:>9}   [{}, {}]   {meaning}",
                p.successes,
                pct(p.estimate, 3),
                pct(p.lower, 3),
                pct(p.upper, 3)
            );
        }
        if !t.reasons.is_empty() {
            let reasons: Vec<String> = t.reasons.iter().map(|(r, n)| format!("{r} {n}")).collect();
            let _ = writeln!(s, "  not_diverted by reason: {}", reasons.join(", "));
        }
        let m = t.missort_rate(CONFIDENCE);
        let _ = writeln!(
            s,
            "  missorted (not where bound): {} [{}, {}]; struck by a stroke not theirs: {}; \
             struck harder than the {} m drop: {}",
            pct(m.estimate, 3),
            pct(m.lower, 3),
            pct(m.upper, 3),
            pct(t.struck_rate(CONFIDENCE).estimate, 3),
            line.diverters[0].setting.limits.drop_height,
            pct(t.overload_rate(CONFIDENCE).estimate, 3)
        );
        if let Some((peak, run)) = &t.loads.largest {
            let _ = writeln!(
                s,
                "  arm loads: {} strokes, peak drive torque up to {peak:.2} N·m (diverter {}, largest_stroke.toml), strikes up to {:.4} N·m·s on an arm (load_spectrum.csv)",
                t.loads.strokes,
                run.diverter + 1,
                t.loads.largest_strike()
            );
        }
        let _ = writeln!(
            s,
            "\n  diverter  at [m]  share  bound  diverted  arm_busy  divert rate   throughput/h  paper W/h  utilisation"
        );
        for (d, div) in line.diverters.iter().enumerate() {
            let c = &t.diverters[d];
            let _ = writeln!(
                s,
                "  {:>8}  {:>6.2}  {:>5.2}  {:>5}  {:>8}  {:>8}  {:>11}  {:>12.0}  {:>9.0}  {:>10}",
                d + 1,
                div.position,
                div.share,
                c.bound,
                c.diverted,
                c.busy,
                pct(t.divert_rate(d, CONFIDENCE).estimate, 3),
                t.throughput(d),
                div.paper_capacity(),
                pct(t.utilisation(line, d), 3)
            );
        }
        let _ = writeln!(
            s,
            "  (paper W = 3600/((R_s − S_d)/v + t_c): one parcel per cycle, no stream; throughput \
             is what the stream delivers)\n"
        );
    }
    s
}

/// The scenario file of parcel `p`'s deciding run at point `r`: its diverter's file with
/// the run's parcel, start, cycles and run length (`run.cycle_starts`), so that `simulate`
/// shows that one parcel's run (φ goes through degrees, so to rounding); `None` when the
/// parcel was not simulated where its outcome was decided.
pub fn parcel_file(r: &LineResult, p: &LineParcel) -> Option<ScenarioFile> {
    run_file(r, p.run.as_ref()?)
}

/// The scenario file of a run at point `r` ([`parcel_file`]).
pub fn run_file(r: &LineResult, inputs: &RunInputs) -> Option<ScenarioFile> {
    use crate::config::{standalone, BeltFrictionConfig, ParcelConfig};
    let mut f = standalone(r.point.files.get(usize::from(inputs.diverter))?);
    let run = &inputs.run;
    let p = &run.parcel;
    f.machine.start_position = run.start_position;
    f.machine.light_barrier = f.machine.light_barrier.min(run.start_position);
    f.machine.trigger = TriggerConfig::Fixed;
    f.parcel = ParcelConfig {
        length: p.length,
        width: p.width,
        height: p.height,
        com_height: p.com_height,
        mass: p.mass,
        offset: p.offset,
        angle_deg: p.angle.to_degrees(),
        velocity: p.velocity.map(|v| [v.x, v.y]),
        spin: p.spin,
    };
    if let Some(mu) = run.belt_friction {
        f.materials.belt_friction = BeltFrictionConfig::Constant(mu);
    }
    f.materials.arm_friction = run.arm_friction;
    f.materials.restitution = run.restitution;
    if let Some(c) = &run.cycle_starts {
        f.run.cycle_starts = c.clone();
    }
    f.run.duration = Some(run.duration);
    f.line = Default::default();
    Some(f)
}

/// largest_stroke.toml (pointK_largest_stroke.toml in a sweep): each point's run behind
/// its largest stroke peak, as a scenario file for `simulate` (whose `arm_loads` is the
/// run's first loaded cycle; the file's `run.cycle_starts` has every cycle of the run).
pub fn largest_stroke_files(r: &LineStudy) -> Vec<(String, Vec<u8>)> {
    let mut files = Vec::new();
    for (i, res) in r.results.iter().enumerate() {
        let Some((peak, run)) = &res.tally.loads.largest else {
            continue;
        };
        let Some(file) = run_file(res, run) else {
            continue;
        };
        let name = largest_stroke_name(r.results.len(), i);
        let heading = format!(
            "A parcel's run at diverter {} of a `divertsim line` run: the stroke with the \
             largest peak drive torque, {peak} N·m. `divertsim simulate` on this file runs it.",
            run.diverter + 1
        );
        if let Ok(text) = crate::config::to_toml(&file, &heading) {
            files.push((name, text.into_bytes()));
        }
    }
    files
}

/// The parcels whose outcome is a failure (not where they were bound), in stream order,
/// among those kept whole: every one of the first [`KEPT_FIRST`] parcels, and the first
/// [`KEPT_FAILURES`] of each outcome (so the first n of a kind, or the first n overall, for
/// any n up to [`KEPT_FAILURES`]).
pub fn failures(r: &LineResult) -> impl Iterator<Item = &LineParcel> {
    r.parcels.iter().filter(|p| !p.outcome.correct())
}

/// The first `parcels` of point `r`'s stream (at most [`KEPT_FIRST`], the parcels `r`
/// keeps whole) as they moved: the first segment run again, their runs keeping their
/// trajectories: for an animated view of the line.
pub fn trace(
    r: &LineResult,
    o: &Options,
    parcels: u64,
) -> Result<divertsim_core::analysis::line::trace::Trace, Error> {
    let p = &r.point;
    let n = o.segment.min(o.parcels);
    let view = parcels.min(KEPT_FIRST) as usize;
    let (_, mut t) = divertsim_core::analysis::line::trace_view(&p.line, p.point.seed, 0..n, view)
        .map_err(Error::failed)?;
    t.parcels.truncate(view);
    Ok(t)
}
