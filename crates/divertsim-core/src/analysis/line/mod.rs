//! A sorter line: a stream of parcels with gaps, one or more diverters along one belt, each
//! with its own arm, controller and chute; every parcel's physics against the arm's real
//! timeline, consecutive parcels' footprints checked, and the throughput the line delivers.
//!
//! The paper (and every other analysis) assumes one parcel in the arm's working area per
//! cycle; a hub's line does not. One file per stage:
//! - [`stream`]: the induction: arrival times from drawn gaps (or a log's headways), each
//!   parcel's destination and the parcel itself from the mix;
//! - [`inherit`]: the further diverters' machines from the first's, and the faults a new
//!   first machine can make;
//! - [`controller`]: when each arm starts, from what a controller sees (the light barrier
//!   and, with the adaptive trigger, the dimensioner), and what it does when the arm is
//!   still busy ([`BusyRule`]);
//! - [`passage`]: one parcel through one diverter: no simulation when no cycle can reach it,
//!   else the run against every cycle near it (`run.cycle_starts`), and the state it hands
//!   to the next diverter;
//! - [`flow`]: the stream through every diverter in turn, the hand-over and each parcel's
//!   outcome;
//! - [`neighbours`]: consecutive parcels' footprints along their paths (detected, not
//!   resolved: a parcel–parcel contact is not part of the event engine);
//! - [`objective`]: the line as the optimiser's problem, in SI;
//! - [`tally`]: outcome rates with Clopper–Pearson intervals, throughput, arm utilisation;
//! - [`log`]: the parcel log kept compact (each parcel's outcome; its inputs drawn again);
//! - [`study`]: a point's stream as a study of segments, and what a run keeps of it;
//! - [`trace`]: a stretch of the stream as it moved, for the animated line view.
//!
//! **Frames and times.** The line's x runs along the belt from the first diverter's pivot;
//! diverter d's pivot is at X_d. A parcel's *arrival* is when its front passes the first
//! pivot riding with the belt. Each diverter works in its own frame (the core's, pivot at
//! the origin), so every run is an ordinary scenario with `run.cycle_starts`.
//!
//! **Segments.** The stream runs in independent segments of consecutive parcels, each
//! starting with an empty belt and every arm at rest. Parcel i depends only on (seed, i)
//! (the mix's stream i and the line's own stream i), a segment only on its parcels, and
//! segments are run in parallel with their order kept: results are bitwise the same for any
//! number of threads, and a segment can be recalled from a store.
//!
//! **Memory.** A segment holds its parcels' inputs and tracks (a few hundred bytes each)
//! and at most two runs at a time ([`flow`]): its memory does not grow with the runs'
//! trajectories, whatever its length. A finished run keeps its [`log::ParcelLog`] (24 bytes
//! a parcel).
//!
//! References: the paper's §4.2 capacity W = 3600/((R_s − S_d)/v + t_c), which this
//! replaces for a stream; docs/model.md for every law of a run.

pub mod controller;
pub mod flow;
pub mod inherit;
pub mod log;
pub mod neighbours;
pub mod objective;
pub mod passage;
pub mod stream;
pub mod study;
pub mod tally;
pub mod trace;

use crate::analysis::population::adaptive_trigger::TableNodes;
use crate::analysis::population::mix::{MixError, ParcelMix};
use crate::analysis::population::reliability::StartRule;
use crate::model::params::{ParcelRun, Scenario};
use crate::sim::NotDivertedReason;
use serde::{Deserialize, Serialize};

pub use inherit::{LineRefusal, MachineChanges};
pub use stream::Induction;

/// One diverter of the line.
#[derive(Debug, Clone, PartialEq)]
pub struct Diverter {
    /// X_d: the pivot's position along the line, from the first diverter's pivot \[m]
    pub position: f64,
    /// The diverter's machine with the line's materials, run settings and limits (its
    /// parcel is a placeholder; the belt is the line's).
    pub setting: Scenario,
    /// How its arm is started for a parcel bound here.
    pub trigger: StartRule,
    /// The share of all parcels bound for this chute [-].
    pub share: f64,
    /// The machine values it states over the first diverter's (none for the first): what a
    /// new first machine leaves it ([`Line::with_first_machine`]).
    pub changes: MachineChanges,
    /// The nodes of its adaptive trigger table, when its machine has one.
    pub table: TableNodes,
}

impl Diverter {
    /// The paper's capacity W = 3600/((R_s − S_d)/v + t_c) of this diverter alone \[1/h]: one
    /// parcel per cycle, no stream.
    pub fn paper_capacity(&self) -> f64 {
        let m = &self.setting.machine;
        3600.0 / ((m.start_position - m.light_barrier) / m.belt_speed + m.cycle_time)
    }
}

/// What a controller does with a parcel bound for its chute when the arm's cycle for an
/// earlier parcel has not ended at the planned start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BusyRule {
    /// Do not serve it: the outcome is `arm_busy` (it goes on down the line). The default:
    /// what a controller does that plans each stroke at the light barrier.
    Skip,
    /// Start as soon as the arm is free if that is at most `max_delay` \[s] late (the parcel
    /// has moved v·delay past its planned R_s); else skip it.
    Late { max_delay: f64 },
    /// Skip a parcel whose front passes the light barrier while the arm is in a cycle: a
    /// controller that handles one parcel at a time, from barrier to the cycle's end, as
    /// the paper's W assumes.
    Barrier,
}

/// A sorter line.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// The diverters in order along the belt (X_d increasing); the first one's machine
    /// gives the belt (v, P_max).
    pub diverters: Vec<Diverter>,
    pub induction: Induction,
    pub mix: ParcelMix,
    pub busy: BusyRule,
    /// Whether the run's length is stated; else each diverter's runs last as its own cycles
    /// need (`model::params::run_length`).
    pub duration_given: bool,
}

impl Line {
    /// v: the belt speed [m/s].
    pub fn belt_speed(&self) -> f64 {
        self.diverters[0].setting.machine.belt_speed
    }

    /// The scenario file of parcel `p`'s deciding run (`None` when it was not simulated
    /// there): the diverter's setting with the run's parcel, start and cycles.
    pub fn scenario_of(&self, p: &LineParcel) -> Option<Scenario> {
        let run = p.run.as_ref()?;
        let d = self.diverters.get(usize::from(run.diverter))?;
        Some(run.scenario(&d.setting))
    }
}

/// A parcel's outcome on the line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum LineOutcome {
    /// Diverted into its own chute.
    Diverted,
    /// Bound straight through and never touched by an arm.
    Passed,
    /// Bound for a chute whose arm was still in a cycle at the planned start (and not
    /// diverted there anyway).
    ArmBusy,
    /// Served by its arm but not diverted, for the physical reason.
    NotDiverted(NotDivertedReason),
    /// Touched by a cycle it was not bound for, and not diverted into a wrong chute (bound
    /// straight through, or knocked off the near side on the way).
    StruckInPassing,
    /// Diverted into a chute it was not bound for.
    WronglyDiverted,
    /// Its footprint overlapped a neighbour's.
    Collision,
    /// A run failed numerically.
    Failed,
}

impl LineOutcome {
    /// Every outcome kind, in report order (not_diverted once, whatever its reason).
    pub const KINDS: [&'static str; 8] = [
        "diverted",
        "passed",
        "arm_busy",
        "not_diverted",
        "struck_in_passing",
        "wrongly_diverted",
        "collision",
        "failed",
    ];

    /// The outcome's label (one of [`LineOutcome::KINDS`]).
    pub fn label(self) -> &'static str {
        Self::KINDS[self.kind()]
    }

    /// Index into [`LineOutcome::KINDS`].
    pub fn kind(self) -> usize {
        match self {
            LineOutcome::Diverted => 0,
            LineOutcome::Passed => 1,
            LineOutcome::ArmBusy => 2,
            LineOutcome::NotDiverted(_) => 3,
            LineOutcome::StruckInPassing => 4,
            LineOutcome::WronglyDiverted => 5,
            LineOutcome::Collision => 6,
            LineOutcome::Failed => 7,
        }
    }

    /// The physical reason of `not_diverted`.
    pub fn reason(self) -> Option<&'static str> {
        match self {
            LineOutcome::NotDiverted(r) => Some(r.label()),
            _ => None,
        }
    }

    /// Whether the parcel ended where it was bound (its chute, or the line's end untouched).
    pub fn correct(self) -> bool {
        matches!(self, LineOutcome::Diverted | LineOutcome::Passed)
    }
}

/// Where and when two neighbours' footprints overlapped.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Collision {
    /// The diverter in whose working area it happened.
    pub diverter: u8,
    /// Segment time \[s]
    pub time: f64,
    /// Line x and y of the midpoint between the two centres \[m]
    pub x: f64,
    pub y: f64,
    /// The other parcel's index.
    pub other: u64,
    /// Depth of the overlap \[m]
    pub depth: f64,
}

/// What rebuilds a parcel's deciding run as a scenario of its diverter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunInputs {
    pub diverter: u8,
    /// The run in the diverter's frame: the parcel as it arrives (pose, velocity, spin), its
    /// material values, R_s (the front's x at t = 0), the arm's cycles and the run's length.
    pub run: ParcelRun,
    /// Segment time of t = 0 \[s]
    pub time_origin: f64,
}

impl RunInputs {
    /// The run as a scenario of the diverter's `setting`.
    pub fn scenario(&self, setting: &Scenario) -> Scenario {
        self.run.scenario(setting)
    }
}

/// One parcel's inputs and outcome on the line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LineParcel {
    /// i: its index in the stream
    pub index: u64,
    /// When its front passes the first pivot, riding (segment time) \[s]
    pub arrival: f64,
    /// The time to the next parcel's arrival \[s]
    pub headway: f64,
    /// The diverter it is bound for; `None`: straight through.
    pub destination: Option<u8>,
    /// a ≥ b, h \[m], m \[kg], ΔP \[m], φ \[rad] as inducted.
    pub length: f64,
    pub width: f64,
    pub height: f64,
    pub mass: f64,
    pub offset: f64,
    pub angle: f64,
    pub outcome: LineOutcome,
    /// The diverter where the outcome was decided; `None`: at the line's end.
    pub decided_at: Option<u8>,
    /// Diverters whose arm touched it in a cycle not started for it.
    pub struck: u8,
    /// Largest S/S_fall over all its strikes [-]
    pub overload_ratio: f64,
    /// Largest strike impulse S [N·s]
    pub max_impulse: f64,
    pub collision: Option<Collision>,
    /// The deciding run of a failure (an outcome other than diverted or passed) that was
    /// simulated where its outcome was decided (boxed: most parcels have none).
    pub run: Option<Box<RunInputs>>,
}

impl Segment {
    /// The segment's time: the sum of its parcels' headways \[s].
    pub fn duration(&self) -> f64 {
        self.parcels.iter().map(|p| p.headway).sum()
    }
}

impl LineParcel {
    /// The inputs of arrival `a` as inducted (its outcome still `passed`, untouched): what
    /// the stream and its log both fill in from the draw.
    pub fn of_arrival(a: &stream::Arrival) -> LineParcel {
        let d = &a.draw;
        LineParcel {
            index: d.index,
            arrival: a.time,
            headway: a.headway,
            destination: a.destination.map(|d| d as u8),
            length: d.length,
            width: d.width,
            height: d.height,
            mass: d.mass,
            offset: d.offset,
            angle: d.angle,
            outcome: LineOutcome::Passed,
            decided_at: None,
            struck: 0,
            overload_ratio: 0.0,
            max_impulse: 0.0,
            collision: None,
            run: None,
        }
    }

    /// Struck harder than the free fall from H₀.
    pub fn overloaded(&self) -> bool {
        self.overload_ratio > 1.0
    }
}

/// The parcels of one segment, with what the tally needs besides them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    pub parcels: Vec<LineParcel>,
    /// Cycles started per diverter.
    pub cycles: Vec<u32>,
    /// Time each arm spends in cycles within the segment's window as the stream passes it,
    /// [X_d/v, X_d/v + duration) \[s] (issue 50: cycles·t_c can run past the window, and
    /// made the utilisation exceed 1). Empty in a segment kept before it (then cycles·t_c).
    #[serde(default)]
    pub busy: Vec<f64>,
    /// Simulations run (the neighbour check's runs again with samples included).
    pub simulations: u64,
    /// The arms' side of the segment's strokes (issue 26).
    #[serde(default)]
    pub loads: SegmentLoads,
}

/// The arms' side of a segment's strokes (issue 26; docs/model.md §12c): each stroke's peak
/// drive torque and each strike's angular impulse on an arm.
///
/// A stroke's peak is the largest of the peaks of the runs that loaded it (each run with the
/// arm's inertia), or the free stroke's I_arm α̈ where no parcel did. Two parcels loading
/// one stroke at the same instant would add their torques; the line runs each parcel apart,
/// so that case counts the larger of the two.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SegmentLoads {
    /// Per diverter, each cycle's peak drive torque \[N·m], in the order they started.
    pub stroke_peaks: Vec<Vec<f64>>,
    /// |J_c| of every strike on an arm, diverter by diverter, run by run \[N·m·s].
    pub strike_impulses: Vec<f64>,
    /// The run behind the largest stroke peak: (peak \[N·m], its inputs).
    pub largest: Option<(f64, Box<RunInputs>)>,
}

/// Run parcels `range` as one segment: an empty belt and every arm at rest at its start.
pub fn run_segment(
    line: &Line,
    seed: u64,
    range: std::ops::Range<u64>,
) -> Result<Segment, MixError> {
    run_segment_stoppable(line, seed, range, &|| {})
}

/// [`run_segment`], `stop_point` called before each parcel's passage of each diverter
/// ([`flow::run_stream_stoppable`]).
pub fn run_segment_stoppable(
    line: &Line,
    seed: u64,
    range: std::ops::Range<u64>,
    stop_point: &(dyn Fn() + Sync),
) -> Result<Segment, MixError> {
    let arrivals = stream::arrivals(line, seed, range)?;
    Ok(flow::run_stream_stoppable(line, &arrivals, stop_point))
}

/// Run parcels `range` as one segment, as [`run_segment`], with every parcel's path and
/// every arm's cycles (each run keeps its trajectory: slower, for a view of the stream).
pub fn trace_segment(
    line: &Line,
    seed: u64,
    range: std::ops::Range<u64>,
) -> Result<(Segment, trace::Trace), MixError> {
    let arrivals = stream::arrivals(line, seed, range)?;
    let mut t = trace::Trace::default();
    let s = flow::run_stream_traced(line, &arrivals, Some(&mut t));
    Ok((s, t))
}

/// [`trace_segment`] recording only the first `view` parcels' paths (with every arm's
/// cycles): the parcels beyond them run as in [`run_segment`], so that a long segment's
/// stretch costs the paths of the parcels shown, not of the segment.
pub fn trace_view(
    line: &Line,
    seed: u64,
    range: std::ops::Range<u64>,
    view: usize,
) -> Result<(Segment, trace::Trace), MixError> {
    let arrivals = stream::arrivals(line, seed, range)?;
    let mut t = trace::Trace::default();
    let s = flow::run_stream_viewed(line, &arrivals, &mut t, view);
    Ok((s, t))
}

#[cfg(test)]
mod tests;
