//! What a simulation returns: stages, events, trajectory samples, the verdict.

/// A stage of the hybrid process (the paper's F1–F6 plus riding).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stage {
    /// Riding with the belt: no slip, no spin (physics.md §3.5).
    Ride,
    /// F1: first oblique strike of the arm on the parcel.
    F1,
    /// F2: free flat sliding on the belt.
    F2,
    /// F3: a later strike.
    F3,
    /// F4: one corner on the arm.
    F4,
    /// F5: a side flush on the arm.
    F5,
    /// F6: a corner on the arm and a corner on the side guide.
    F6,
}

impl Stage {
    /// The label used in outputs.
    pub fn label(self) -> &'static str {
        match self {
            Stage::Ride => "ride",
            Stage::F1 => "F1",
            Stage::F2 => "F2",
            Stage::F3 => "F3",
            Stage::F4 => "F4",
            Stage::F5 => "F5",
            Stage::F6 => "F6",
        }
    }
}

/// The parcel's planar state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct State {
    /// t [s] from the arm start
    pub t: f64,
    /// x of the centre G [m]
    pub x: f64,
    /// y of the centre G [m]
    pub y: f64,
    /// φ [rad]
    pub phi: f64,
    /// ẋ [m/s]
    pub vx: f64,
    /// ẏ [m/s]
    pub vy: f64,
    /// ω = φ̇ [rad/s]
    pub omega: f64,
}

/// One trajectory point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub state: State,
    /// α [rad] at this instant.
    pub arm_angle: f64,
    /// The stage in force (at an event instant: the stage being left).
    pub stage: Stage,
}

/// What happened at an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventKind {
    /// The arm starts its cycle (t = 0).
    ArmStart,
    /// The arm's cycle ends (t = t_c).
    ArmEnd,
    /// Slip and spin relative to the belt reach zero: the parcel rides.
    RideStart,
    /// The centre crosses the far belt edge y = P_max.
    Exit,
}

impl EventKind {
    /// The label used in outputs.
    pub fn label(self) -> &'static str {
        match self {
            EventKind::ArmStart => "arm_start",
            EventKind::ArmEnd => "arm_end",
            EventKind::RideStart => "ride_start",
            EventKind::Exit => "exit",
        }
    }
}

/// A timed event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    pub t: f64,
    pub kind: EventKind,
}

/// Why a parcel was not diverted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NotDivertedReason {
    /// The parcel passed beyond the arm's reach.
    Escaped,
    /// The parcel is riding on the belt after the arm's cycle (or with no arm).
    LeftOnBelt,
    /// The run reached its duration before a verdict.
    DurationReached,
}

impl NotDivertedReason {
    pub fn label(self) -> &'static str {
        match self {
            NotDivertedReason::Escaped => "escaped",
            NotDivertedReason::LeftOnBelt => "left_on_belt",
            NotDivertedReason::DurationReached => "duration_reached",
        }
    }
}

/// The verdict.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// The centre crossed the far belt edge.
    Diverted,
    /// Not diverted, and why.
    NotDiverted(NotDivertedReason),
    /// Numerical trouble, with a reason.
    Failed(String),
}

impl Outcome {
    pub fn label(&self) -> &'static str {
        match self {
            Outcome::Diverted => "diverted",
            Outcome::NotDiverted(_) => "not_diverted",
            Outcome::Failed(_) => "failed",
        }
    }

    /// The reason, if any.
    pub fn reason(&self) -> Option<String> {
        match self {
            Outcome::Diverted => None,
            Outcome::NotDiverted(r) => Some(r.label().to_string()),
            Outcome::Failed(r) => Some(r.clone()),
        }
    }
}

/// Everything a run produces.
#[derive(Debug, Clone, PartialEq)]
pub struct SimResult {
    pub outcome: Outcome,
    /// Stages visited in order, consecutive repeats merged.
    pub stages: Vec<Stage>,
    pub events: Vec<Event>,
    /// Dense-output points and exactly the event instants, in time order.
    pub trajectory: Vec<Sample>,
    pub final_state: State,
    /// Largest y of the centre over the run [m].
    pub max_lateral: f64,
}
