//! Divert reliability over a parcel mix: Monte Carlo runs of [`crate::analysis::population::mix`] samples, tallied
//! into rates with exact (Clopper–Pearson) intervals, failure breakdowns and binned failure
//! rates, in shards that a store can keep so an interrupted run resumes where it stopped.
//!
//! **Determinism.** Sample i depends only on (seed, i) ([`crate::analysis::population::mix`]); a shard is the
//! samples [k·S, (k+1)·S) run in parallel with their order kept; shards are tallied in order.
//! Every total, and so the summary, is the same for any thread count, and whether the shards
//! were computed in this process or read back from a store.
//!
//! **Counting.** A sample *fails* when it is not diverted (any reason) or its run failed
//! numerically; it is *overloaded* when its largest strike exceeds the free fall from H₀
//! (S/S_fall > 1). The divert rate and the overload rate carry 95 % Clopper–Pearson intervals
//! (the exact binomial interval, conservative: coverage ≥ 95 % at every true rate).
//!
//! **Early stop.** With `until_width`, the run stops after the first shard at which both
//! intervals are at most that wide: a decision at shard ends only, so it is deterministic.
//! Stopping on the data makes the sample size random, so the stated 95 % is then nominal:
//! Clopper–Pearson's conservatism usually covers the small loss, but it is no longer a
//! guarantee.
//!
//! **Bins.** The failure rate against each input is binned on edges fixed by the first
//! shard: its quantiles, so the bins hold about equal numbers of samples and every bin's
//! interval says something even for a skewed input; the histograms of the reserve and of
//! S/S_fall use equal widths over the first shard's range. Later values outside the edges
//! fall in the end bins, so the tally needs no second pass and memory stays bounded.
//!
//! **Capacity.** With a fixed trigger W = 3600/((R_s − S_d)/v + t_c); with a per-parcel
//! trigger, each parcel occupies the machine (R_s,i − S_d)/v + t_c, and W = 3600/mean.

use crate::analysis::design::design_set::divert_overshoot;
use crate::analysis::population::adaptive_trigger::TriggerTable;
use crate::analysis::population::mix::{Draw, MixError, ParcelMix, Rejection};
use crate::model::params::Scenario;
use crate::run::study::{execute, Control, PieceStore, Study, StudyError};
use crate::run::sweep::{no_progress, par_map, Progress};
use crate::sim::arm_loads::StrokeProfile;
use crate::sim::{simulate_verdict, Outcome, Stage};
use crate::stats::binomial::{clopper_pearson, Proportion};
use crate::stats::loads::StrokeLoads;
use std::collections::BTreeMap;

/// The histograms, in `stats/` since every study counts with them.
pub use crate::stats::histogram::{per_million_strokes, round_up, Bins, Spectrum, SPECTRUM_BINS};

/// The rule that gives each parcel its R_s in a run: the machine's trigger
/// ([`crate::model::trigger::Trigger`], the policy with its search settings) once its
/// table is built.
#[derive(Debug, Clone, PartialEq)]
pub enum StartRule {
    /// The setting's R_s for every parcel.
    Fixed,
    /// The parcel's own R_s from the table.
    Adaptive(TriggerTable),
}

impl StartRule {
    /// "fixed" or "adaptive".
    pub fn label(&self) -> &'static str {
        match self {
            StartRule::Fixed => "fixed",
            StartRule::Adaptive(_) => "adaptive",
        }
    }

    /// R_s for a drawn parcel (before its phase error) \[m].
    pub fn start_for(&self, d: &Draw, setting: &Scenario) -> f64 {
        match self {
            StartRule::Fixed => setting.machine.start_position,
            StartRule::Adaptive(t) => t.start_for(d.length, d.width, d.offset, d.angle, setting),
        }
    }
}

/// One sample's inputs and outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleRun {
    pub draw: Draw,
    /// R_s the trigger chose, before the phase error \[m]
    pub start_position: f64,
    pub outcome: Outcome,
    /// The stage the run ended in.
    pub final_stage: Stage,
    /// The stages, in order.
    pub stages: Vec<Stage>,
    /// Number of strikes.
    pub strikes: u32,
    /// Largest y of the centre \[m]
    pub max_lateral: f64,
    /// d: divert reserve \[m] (≥ 0 iff diverted, see [`divert_overshoot`])
    pub reserve: f64,
    /// Largest strike impulse S [N·s]
    pub max_impulse: f64,
    /// S/S_fall [-]
    pub overload_ratio: f64,
    /// The smallest tipping margin of the run [-] (infinite if nothing loaded the parcel
    /// sideways; below 1 an edge lifted).
    pub tipping_margin: f64,
    /// Whether it tipped over (its centre of mass passed over an edge).
    pub tipped_over: bool,
    /// max |M_d|: the stroke's peak drive torque on the arm about the pivot \[N·m]
    /// ([`crate::sim::arm_loads`]; `None` without an arm or for a run that failed).
    pub arm_peak_torque: Option<f64>,
    /// |J_c| of each strike on the arm about the pivot, in time order \[N·m·s].
    pub arm_strike_impulses: Vec<f64>,
}

impl SampleRun {
    /// Not diverted, or failed numerically.
    pub fn failed(&self) -> bool {
        self.outcome != Outcome::Diverted
    }

    /// Struck harder than the free fall from H₀.
    pub fn overloaded(&self) -> bool {
        self.overload_ratio > 1.0
    }

    /// It tipped over (a `tipped` verdict, or a flag under `limits.tipping = "flag"`).
    pub fn tipped(&self) -> bool {
        self.tipped_over
    }

    /// The failure's reason label ("escaped", …, "numerical"), `None` when diverted.
    pub fn reason(&self) -> Option<&'static str> {
        match &self.outcome {
            Outcome::Diverted => None,
            Outcome::NotDiverted(r) => Some(r.label()),
            Outcome::Failed(_) => Some("numerical"),
        }
    }

    /// (R_s,i − S_d)/v + t_c: how long this parcel occupies the machine \[s].
    pub fn occupancy(&self, setting: &Scenario) -> f64 {
        let m = &setting.machine;
        let barrier = m.light_barrier.min(self.start_position);
        (self.start_position - barrier) / m.belt_speed + m.cycle_time
    }
}

/// Run sample `index`; `profile` is [`StrokeProfile::of`] the setting (the arm's loads are
/// NaN without it).
pub fn run_sample(
    setting: &Scenario,
    mix: &ParcelMix,
    trigger: &StartRule,
    seed: u64,
    index: u64,
    profile: Option<&StrokeProfile>,
) -> Result<SampleRun, MixError> {
    let draw = mix.draw(setting, seed, index)?;
    let start = trigger.start_for(&draw, setting);
    let s = draw.scenario(setting, start);
    let r = simulate_verdict(&s);
    let failed = matches!(r.outcome, Outcome::Failed(_));
    let finite = |v: f64| if failed || !v.is_finite() { 0.0 } else { v };
    let arm_peak_torque = match profile {
        Some(p) if !failed => Some(r.arm_loads_with(&s, p).peak_torque),
        _ => None,
    };
    Ok(SampleRun {
        arm_peak_torque,
        arm_strike_impulses: if failed {
            Vec::new()
        } else {
            r.arm_strikes.iter().map(|j| j.1.abs()).collect()
        },
        draw,
        start_position: start,
        final_stage: r.stages.last().copied().unwrap_or(Stage::Ride),
        strikes: r.impacts.len() as u32,
        max_lateral: r.max_lateral,
        reserve: divert_overshoot(&s, &r),
        max_impulse: finite(r.overload.max_impulse),
        overload_ratio: finite(r.overload.overload_ratio),
        tipping_margin: r.tipping.margin,
        tipped_over: r.tipping.tipped(),
        stages: r.stages,
        outcome: r.outcome,
    })
}

/// Run samples `range` in parallel, in order.
pub fn run_shard(
    setting: &Scenario,
    mix: &ParcelMix,
    trigger: &StartRule,
    seed: u64,
    range: std::ops::Range<u64>,
    progress: Progress<'_>,
) -> Result<Vec<SampleRun>, MixError> {
    let indices: Vec<u64> = range.collect();
    let profile = StrokeProfile::of(setting);
    par_map(&indices, progress, |&i| {
        run_sample(setting, mix, trigger, seed, i, profile.as_ref())
    })
    .into_iter()
    .collect()
}

/// The inputs of a sample, once: (its column in the sample table, in the unit it is stored
/// in; its name in the binned rates, in the unit it is shown in). Only the angle differs:
/// stored in radians, shown in degrees.
pub const INPUT_NAMES: [(&str, &str); 13] = [
    ("length_m", "length_m"),
    ("width_m", "width_m"),
    ("height_m", "height_m"),
    ("mass_kg", "mass_kg"),
    ("offset_m", "offset_m"),
    ("angle_rad", "angle_deg"),
    ("speed_m_s", "speed_m_s"),
    ("spin_rad_s", "spin_rad_s"),
    ("phase_s", "phase_s"),
    ("belt_friction", "belt_friction"),
    ("arm_friction", "arm_friction"),
    ("restitution", "restitution"),
    ("start_position_m", "start_position_m"),
];

/// The shown names of [`INPUT_NAMES`].
const fn shown_names() -> [&'static str; 13] {
    let mut out = [""; 13];
    let mut i = 0;
    while i < out.len() {
        out[i] = INPUT_NAMES[i].1;
        i += 1;
    }
    out
}

/// The binned inputs' names with their shown units ([`INPUT_NAMES`]).
pub const INPUTS: [&str; 13] = shown_names();

/// The inputs of a sample as stored, in [`INPUT_NAMES`] order (`None`: μ_b where the mix
/// does not scatter it).
pub fn stored_inputs(s: &SampleRun) -> [Option<f64>; 13] {
    let d = &s.draw;
    [
        Some(d.length),
        Some(d.width),
        Some(d.height),
        Some(d.mass),
        Some(d.offset),
        Some(d.angle),
        Some(d.speed),
        Some(d.spin),
        Some(d.phase),
        d.belt_friction,
        Some(d.arm_friction),
        Some(d.restitution),
        Some(s.start_position),
    ]
}

/// The inputs of a sample as shown, in [`INPUTS`] order (NaN where the mix does not
/// scatter μ_b).
pub fn inputs(s: &SampleRun) -> [f64; 13] {
    let mut x = stored_inputs(s).map(|v| v.unwrap_or(f64::NAN));
    x[5] = x[5].to_degrees();
    x
}

/// Reserve values a histogram shows: failed runs' −1000 m sentinel left out.
fn shown_reserve(s: &SampleRun) -> f64 {
    if matches!(s.outcome, Outcome::Failed(_)) {
        f64::NAN
    } else {
        s.reserve
    }
}

/// Everything counted over the samples of one run (one point of a sweep).
#[derive(Debug, Clone, PartialEq)]
pub struct Tally {
    /// Bins per input, fixed by the first shard ([`Tally::add`]).
    pub bins_per_input: usize,
    /// Whether a (non-empty) shard has fixed the bin edges.
    pub edges_fixed: bool,
    pub samples: u64,
    pub diverted: u64,
    pub overloaded: u64,
    /// Failures by reason label.
    pub by_reason: BTreeMap<String, u64>,
    /// Failures by the stage the run ended in.
    pub by_final_stage: BTreeMap<String, u64>,
    /// Failures by stage sequence ("ride>F1>F2>ride").
    pub by_sequence: BTreeMap<String, u64>,
    /// Rejected draws per reason, in [`Rejection::ALL`] order.
    pub rejected: [u64; 5],
    /// Σ occupancy \[s] (see the module notes on capacity).
    pub occupancy: f64,
    /// Largest S/S_fall seen.
    pub max_overload_ratio: f64,
    /// Smallest reserve seen (failed runs aside) \[m].
    pub min_reserve: f64,
    /// Binned rates per input ([`INPUTS`] order); `None` for an input constant in the
    /// first shard.
    pub input_bins: Vec<Option<Bins>>,
    /// Histogram of the divert reserve d \[m].
    pub reserve_hist: Option<Bins>,
    /// Histogram of S/S_fall.
    pub overload_hist: Option<Bins>,
    /// Samples whose tipping margin fell below 1 (verdict or flag).
    pub tipped: u64,
    /// The strokes whose arm loads were computed (an arm, a run that did not fail; each
    /// peak is [`SampleRun::arm_peak_torque`]) and the sample with the largest.
    pub loads: StrokeLoads<SampleRun>,
    /// The first [`FIRST_FAILURES`] failed samples, in sample order: each one a run to look
    /// at (the studio's clickable failures; the same whatever the thread count).
    pub first_failures: Vec<SampleRun>,
}

/// Failed samples a tally keeps ([`Tally::first_failures`]).
pub const FIRST_FAILURES: usize = 20;

/// The confidence of every interval a reliability study reports (exact Clopper–Pearson).
pub const CONFIDENCE: f64 = 0.95;

/// Bins of the reserve and overload histograms.
pub const HISTOGRAM_BINS: usize = 40;

/// Stages joined by '>'.
pub fn sequence_label(stages: &[Stage]) -> String {
    stages
        .iter()
        .map(|s| s.label())
        .collect::<Vec<_>>()
        .join(">")
}

impl Tally {
    /// An empty tally with `bins` bins per input.
    pub fn new(bins: usize) -> Tally {
        Tally {
            bins_per_input: bins.max(1),
            edges_fixed: false,
            samples: 0,
            diverted: 0,
            overloaded: 0,
            by_reason: BTreeMap::new(),
            by_final_stage: BTreeMap::new(),
            by_sequence: BTreeMap::new(),
            rejected: [0; 5],
            occupancy: 0.0,
            max_overload_ratio: 0.0,
            min_reserve: f64::INFINITY,
            input_bins: Vec::new(),
            reserve_hist: None,
            overload_hist: None,
            tipped: 0,
            loads: StrokeLoads::default(),
            first_failures: Vec::new(),
        }
    }

    /// Count a shard's samples, in order. The first shard added fixes the bin edges.
    pub fn add(&mut self, setting: &Scenario, shard: &[SampleRun]) {
        if !self.edges_fixed && !shard.is_empty() {
            self.edges_fixed = true;
            let n = self.bins_per_input;
            let all: Vec<[f64; 13]> = shard.iter().map(inputs).collect();
            self.input_bins = (0..INPUTS.len())
                .map(|k| Bins::equal_count(all.iter().map(|x| x[k]), n))
                .collect();
            self.reserve_hist = Bins::equal_width(shard.iter().map(shown_reserve), HISTOGRAM_BINS);
            self.overload_hist = Bins::equal_width(
                shard
                    .iter()
                    .map(|s| s.overload_ratio)
                    .chain(std::iter::once(0.0)),
                HISTOGRAM_BINS,
            );
        }
        self.loads.count(
            shard.iter().filter_map(|s| s.arm_peak_torque),
            shard
                .iter()
                .flat_map(|s| s.arm_strike_impulses.iter().copied()),
        );
        for s in shard {
            let (failed, overloaded) = (s.failed(), s.overloaded());
            self.samples += 1;
            self.tipped += u64::from(s.tipped());
            if let Some(peak) = s.arm_peak_torque {
                self.loads.offer(peak, || s.clone());
            }
            self.diverted += u64::from(!failed);
            self.overloaded += u64::from(overloaded);
            if let Some(r) = s.reason() {
                if self.first_failures.len() < FIRST_FAILURES {
                    self.first_failures.push(s.clone());
                }
                *self.by_reason.entry(r.to_string()).or_default() += 1;
                *self
                    .by_final_stage
                    .entry(s.final_stage.label().to_string())
                    .or_default() += 1;
                *self
                    .by_sequence
                    .entry(sequence_label(&s.stages))
                    .or_default() += 1;
            }
            for (k, n) in s.draw.rejected.iter().enumerate() {
                self.rejected[k] += u64::from(*n);
            }
            self.occupancy += s.occupancy(setting);
            self.max_overload_ratio = self.max_overload_ratio.max(s.overload_ratio);
            let shown = shown_reserve(s);
            if shown.is_finite() {
                self.min_reserve = self.min_reserve.min(shown);
            }
            let x = inputs(s);
            for (b, v) in self.input_bins.iter_mut().zip(x) {
                if let Some(b) = b {
                    b.add(v, failed, overloaded);
                }
            }
            if let Some(h) = &mut self.reserve_hist {
                if shown.is_finite() {
                    h.add(shown, failed, overloaded);
                }
            }
            if let Some(h) = &mut self.overload_hist {
                h.add(s.overload_ratio, failed, overloaded);
            }
        }
    }

    /// The divert rate and its interval.
    pub fn divert_rate(&self, confidence: f64) -> Proportion {
        clopper_pearson(self.diverted, self.samples, confidence)
    }

    /// The overload rate (S > S_fall) and its interval.
    pub fn overload_rate(&self, confidence: f64) -> Proportion {
        clopper_pearson(self.overloaded, self.samples, confidence)
    }

    /// The tipping rate (margin below 1) and its interval.
    pub fn tipping_rate(&self, confidence: f64) -> Proportion {
        clopper_pearson(self.tipped, self.samples, confidence)
    }

    /// W [parcels/h] from the mean occupancy (0 without samples).
    pub fn capacity(&self) -> f64 {
        if self.samples == 0 || self.occupancy.is_nan() || self.occupancy <= 0.0 {
            0.0
        } else {
            3600.0 * self.samples as f64 / self.occupancy
        }
    }

    /// Draws rejected in all.
    pub fn rejected_total(&self) -> u64 {
        self.rejected.iter().sum()
    }

    /// Rejected draws by reason label.
    pub fn rejected_by_reason(&self) -> Vec<(&'static str, u64)> {
        Rejection::ALL
            .iter()
            .zip(self.rejected)
            .map(|(r, n)| (r.label(), n))
            .collect()
    }

    /// Whether both intervals are at most `width` wide.
    pub fn narrow_enough(&self, width: f64, confidence: f64) -> bool {
        self.samples > 0
            && self.divert_rate(confidence).width() <= width
            && self.overload_rate(confidence).width() <= width
    }
}

/// How many samples, in what shards, and when to stop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunPlan {
    /// Largest number of samples.
    pub samples: u64,
    /// Samples per shard (the unit of checkpointing and of the early-stop decision).
    pub shard_size: u64,
    pub seed: u64,
    /// Stop once both 95 % intervals are at most this wide.
    pub until_width: Option<f64>,
    /// Interval confidence (0.95).
    pub confidence: f64,
    /// Bins per input.
    pub bins: usize,
}

impl RunPlan {
    /// The number of shards at most.
    pub fn shards(&self) -> u64 {
        self.samples.div_ceil(self.shard_size.max(1))
    }

    /// The sample range of shard k.
    pub fn shard_range(&self, k: u64) -> std::ops::Range<u64> {
        let s = self.shard_size.max(1);
        (k * s).min(self.samples)..((k + 1) * s).min(self.samples)
    }
}

/// Where shards are kept between runs (a checkpoint directory, or nothing); called from
/// any worker thread.
pub trait ShardStore: Sync {
    /// The samples of shard `k` of point `point` if a complete copy is kept.
    fn load(&self, point: usize, k: u64) -> Result<Option<Vec<SampleRun>>, String>;
    /// Keep shard `k` of point `point` (complete, or not at all).
    fn save(&self, point: usize, k: u64, samples: &[SampleRun]) -> Result<(), String>;
}

/// A store that keeps nothing.
pub struct NoStore;

impl ShardStore for NoStore {
    fn load(&self, _: usize, _: u64) -> Result<Option<Vec<SampleRun>>, String> {
        Ok(None)
    }
    fn save(&self, _: usize, _: u64, _: &[SampleRun]) -> Result<(), String> {
        Ok(())
    }
}

/// The shards of one point of a [`ShardStore`], as the study engine's store.
struct PointShards<'a> {
    store: &'a dyn ShardStore,
    point: usize,
}

impl PieceStore<Vec<SampleRun>> for PointShards<'_> {
    fn load(&self, k: u64) -> Result<Option<Vec<SampleRun>>, String> {
        self.store.load(self.point, k)
    }
    fn save(&self, k: u64, samples: &Vec<SampleRun>) -> Result<(), String> {
        self.store.save(self.point, k, samples)
    }
}

/// Why a run stopped short.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Mix(#[from] MixError),
    #[error("{0}")]
    Store(String),
    /// The caller's stop said so (between shards).
    #[error("interrupted")]
    Stopped,
}

impl From<StudyError<MixError>> for RunError {
    fn from(e: StudyError<MixError>) -> RunError {
        match e {
            StudyError::Piece(e) => RunError::Mix(e),
            StudyError::Store(e) => RunError::Store(e),
            StudyError::Stopped => RunError::Stopped,
        }
    }
}

/// The result of one point.
#[derive(Debug, Clone, PartialEq)]
pub struct PointResult {
    pub tally: Tally,
    /// Shards tallied (read back or computed).
    pub shards: u64,
    /// Shards read back from the store.
    pub resumed_shards: u64,
    /// Whether the interval criterion stopped it before `samples`.
    pub stopped_early: bool,
}

/// One point's reliability as a study: shard k is the samples `plan.shard_range(k)` (each
/// run in parallel inside the shard, so shards go one at a time), folded into a [`Tally`];
/// enough once both intervals are narrower than the plan's width.
pub struct ReliabilityStudy<'a> {
    pub setting: &'a Scenario,
    pub mix: &'a ParcelMix,
    pub trigger: &'a StartRule,
    pub plan: &'a RunPlan,
}

impl Study for ReliabilityStudy<'_> {
    type Piece = Vec<SampleRun>;
    type Part = Vec<SampleRun>;
    type Tally = Tally;
    type Error = MixError;

    fn pieces(&self) -> u64 {
        self.plan.shards()
    }
    fn batch(&self) -> u64 {
        1
    }
    fn run_piece(&self, k: u64, progress: Progress<'_>) -> Result<Vec<SampleRun>, MixError> {
        run_shard(
            self.setting,
            self.mix,
            self.trigger,
            self.plan.seed,
            self.plan.shard_range(k),
            progress,
        )
    }
    fn part(&self, _: u64, samples: Vec<SampleRun>) -> Vec<SampleRun> {
        samples
    }
    fn fold(&self, tally: &mut Tally, samples: Vec<SampleRun>) {
        tally.add(self.setting, &samples);
    }
    fn enough(&self, t: &Tally) -> bool {
        self.plan.until_width.is_some_and(|w| {
            t.samples < self.plan.samples && t.narrow_enough(w, self.plan.confidence)
        })
    }
}

/// Run one point: every shard in order, each read back from `store` if kept there, else run
/// and saved; stop at `plan.samples` or when the intervals are narrow enough, or with
/// [`RunError::Stopped`] when `stop` says so before a shard. `progress` ticks once per
/// sample; `on_shard(tally so far)` is called after each shard (the rates so far).
#[allow(clippy::too_many_arguments)]
pub fn run_point(
    setting: &Scenario,
    mix: &ParcelMix,
    trigger: &StartRule,
    plan: &RunPlan,
    point: usize,
    store: &dyn ShardStore,
    stop: &dyn Fn() -> bool,
    progress: Progress<'_>,
    on_shard: &mut dyn FnMut(&Tally),
) -> Result<PointResult, RunError> {
    let study = ReliabilityStudy {
        setting,
        mix,
        trigger,
        plan,
    };
    let r = execute(
        &study,
        Tally::new(plan.bins),
        &PointShards { store, point },
        &mut Control {
            stop,
            piece_done: &no_progress,
            inside: progress,
            batch_done: on_shard,
        },
    )?;
    Ok(PointResult {
        tally: r.tally,
        shards: r.pieces,
        resumed_shards: r.resumed,
        stopped_early: r.stopped_early,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::population::mix::{MassLaw, Placement, Sizes};
    use crate::run::sweep::no_progress;
    use crate::stats::distribution::Distribution;

    fn small_mix() -> ParcelMix {
        ParcelMix {
            sizes: Sizes::Drawn {
                length: Distribution::Uniform { min: 0.2, max: 0.5 },
                width: Distribution::Uniform {
                    min: 0.1,
                    max: 0.26,
                },
                height: Distribution::Fixed(0.1),
            },
            mass: MassLaw::Mass(Distribution::Uniform {
                min: 0.5,
                max: 15.0,
            }),
            placement: Placement::RoomFraction(Distribution::Uniform { min: 0.0, max: 1.0 }),
            angle: Distribution::Normal { mean: 0.0, sd: 0.1 },
            speed: Distribution::Fixed(0.0),
            spin: Distribution::Fixed(0.0),
            phase: Distribution::Normal {
                mean: 0.0,
                sd: 0.005,
            },
            belt_friction: None,
            arm_friction: None,
            restitution: None,
        }
    }

    fn plan(samples: u64, shard: u64) -> RunPlan {
        RunPlan {
            samples,
            shard_size: shard,
            seed: 11,
            until_width: None,
            confidence: 0.95,
            bins: 5,
        }
    }

    #[test]
    fn same_tally_for_any_thread_count_and_shard_store() {
        let s = Scenario::paper_default();
        let mix = small_mix();
        let p = plan(48, 16);
        let run = || {
            run_point(
                &s,
                &mix,
                &StartRule::Fixed,
                &p,
                0,
                &NoStore,
                &|| false,
                &no_progress,
                &mut |_| {},
            )
            .unwrap()
        };
        let (one, many) = crate::run::sweep::one_and_many_threads(run);
        assert_eq!(many, one);
        assert_eq!(many.tally.samples, 48);
        // A store that hands back the shards gives the same tally.
        struct Memory(std::sync::Mutex<BTreeMap<u64, Vec<SampleRun>>>);
        impl ShardStore for Memory {
            fn load(&self, _: usize, k: u64) -> Result<Option<Vec<SampleRun>>, String> {
                Ok(self.0.lock().unwrap().get(&k).cloned())
            }
            fn save(&self, _: usize, k: u64, s: &[SampleRun]) -> Result<(), String> {
                self.0.lock().unwrap().insert(k, s.to_vec());
                Ok(())
            }
        }
        let mut m = Memory(Default::default());
        let from_store = |m: &mut Memory| {
            run_point(
                &s,
                &mix,
                &StartRule::Fixed,
                &p,
                0,
                m,
                &|| false,
                &no_progress,
                &mut |_| {},
            )
            .unwrap()
        };
        let first = from_store(&mut m);
        m.0.lock().unwrap().remove(&2);
        let again = from_store(&mut m);
        assert_eq!(first.tally, many.tally);
        assert_eq!(again.tally, many.tally);
        assert_eq!(again.resumed_shards, 2);
    }

    #[test]
    fn tally_counts_add_up() {
        let s = Scenario::paper_default();
        let runs = run_shard(&s, &small_mix(), &StartRule::Fixed, 3, 0..40, &no_progress).unwrap();
        let mut t = Tally::new(4);
        t.add(&s, &runs);
        let failures: u64 = t.by_reason.values().sum();
        assert_eq!(t.diverted + failures, 40);
        assert_eq!(t.by_final_stage.values().sum::<u64>(), failures);
        for b in t.input_bins.iter().flatten() {
            assert_eq!(b.count.iter().sum::<u64>(), 40);
            assert_eq!(b.failed.iter().sum::<u64>(), failures);
        }
        // Height is fixed: no bins for it.
        assert!(t.input_bins[2].is_none());
        let fixed_w = crate::analysis::design::design_set::capacity(
            &crate::analysis::design::design_set::DesignPoint {
                belt_speed: s.machine.belt_speed,
                cycle_time: s.machine.cycle_time,
                start_position: s.machine.start_position,
                light_barrier: s.machine.light_barrier,
            },
        );
        assert!((t.capacity() - fixed_w).abs() < 1e-9 * fixed_w);
    }

    #[test]
    fn load_spectra_count_every_stroke_and_strike_and_keep_the_largest() {
        let s = Scenario::paper_default();
        let runs = run_shard(&s, &small_mix(), &StartRule::Fixed, 3, 0..40, &no_progress).unwrap();
        let mut t = Tally::new(4);
        t.add(&s, &runs[..20]);
        t.add(&s, &runs[20..]);
        assert_eq!(t.loads.strokes, 40);
        let torque = t
            .loads
            .torque_spectrum
            .as_ref()
            .expect("strokes load the arm");
        assert_eq!(torque.total(), 40);
        let strikes: usize = runs.iter().map(|r| r.arm_strike_impulses.len()).sum();
        assert!(strikes > 0);
        assert_eq!(
            t.loads.strike_spectrum.as_ref().unwrap().total(),
            strikes as u64
        );
        let (_, largest) = t.loads.largest.as_ref().unwrap();
        let max = runs
            .iter()
            .map(|r| r.arm_peak_torque.unwrap())
            .fold(0.0, f64::max);
        assert_eq!((largest.arm_peak_torque, torque.max), (Some(max), max));
        assert_eq!(t.loads.per_million(4), 1e5);
        // Each sample's peak is its run's own: the sample's scenario, simulated whole.
        let d = &largest.draw;
        let again = crate::sim::simulate(&d.scenario(&s, largest.start_position));
        let own = again
            .arm_loads(&d.scenario(&s, largest.start_position))
            .unwrap();
        assert_eq!(Some(own.peak_torque), largest.arm_peak_torque);
    }

    /// Regression (review of issue 11): an empty first shard fixed "no bins" for good.
    #[test]
    fn an_empty_first_shard_does_not_lose_the_bins() {
        let s = Scenario::paper_default();
        let runs = run_shard(&s, &small_mix(), &StartRule::Fixed, 3, 0..30, &no_progress).unwrap();
        let mut t = Tally::new(4);
        t.add(&s, &[]);
        t.add(&s, &runs);
        assert!(t.input_bins[0].is_some());
        let mut u = Tally::new(4);
        u.add(&s, &runs);
        assert_eq!(t.input_bins, u.input_bins);
    }

    #[test]
    fn early_stop_happens_at_a_shard_end() {
        let s = Scenario::paper_default();
        let mut p = plan(400, 20);
        p.until_width = Some(0.9);
        let r = run_point(
            &s,
            &small_mix(),
            &StartRule::Fixed,
            &p,
            0,
            &NoStore,
            &|| false,
            &no_progress,
            &mut |_| {},
        )
        .unwrap();
        assert!(r.stopped_early);
        assert_eq!(r.tally.samples % 20, 0);
        assert!(r.tally.samples < 400);
    }
}
