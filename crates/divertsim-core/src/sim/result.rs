//! What a simulation returns: stages, events, trajectory samples, the verdict.

/// A stage of the hybrid process (the paper's F1–F6 plus riding).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Stage {
    /// Riding with the belt: no slip, no spin (docs/model.md §4).
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
    /// A side flush on the arm and a corner on the guide (not in the paper).
    F5Guide,
    /// Corners on the side guide only: sliding along the guide (not in the paper).
    Guide,
    /// The arm tip on a parcel edge (the paper mentions tip strikes but has no stage).
    Tip,
    /// The arm tip on an edge and a corner on the guide.
    TipGuide,
    /// A corner on the arm face and the arm tip on an edge: typically a side that lay
    /// flush on the arm, its leading corner past the tip, supported by its trailing corner
    /// and the tip (not in the paper).
    ArmTip,
    /// Any other combination of contacts.
    Contact,
}

impl Stage {
    /// Every stage.
    pub const ALL: [Stage; 13] = [
        Stage::Ride,
        Stage::F1,
        Stage::F2,
        Stage::F3,
        Stage::F4,
        Stage::F5,
        Stage::F6,
        Stage::F5Guide,
        Stage::Guide,
        Stage::Tip,
        Stage::TipGuide,
        Stage::ArmTip,
        Stage::Contact,
    ];

    /// The stage of a label.
    pub fn from_label(label: &str) -> Option<Stage> {
        Stage::ALL.into_iter().find(|s| s.label() == label)
    }

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
            Stage::F5Guide => "F5+guide",
            Stage::Guide => "guide",
            Stage::Tip => "tip",
            Stage::TipGuide => "tip+guide",
            Stage::ArmTip => "arm+tip",
            Stage::Contact => "contact",
        }
    }

    /// The stage in a few words, for a legend beside the codes.
    pub fn meaning(self) -> &'static str {
        match self {
            Stage::Ride => "riding with the belt",
            Stage::F1 => "first strike",
            Stage::F2 => "free slide on the belt",
            Stage::F3 => "another strike",
            Stage::F4 => "turning about a corner on the arm",
            Stage::F5 => "sliding along the arm",
            Stage::F6 => "on the arm and the side guide",
            Stage::F5Guide => "along the arm, a corner on the guide",
            Stage::Guide => "along the side guide",
            Stage::Tip => "the arm tip on an edge",
            Stage::TipGuide => "the arm tip on an edge, a corner on the guide",
            Stage::ArmTip => "a corner on the arm and the tip on an edge",
            Stage::Contact => "other contacts",
        }
    }
}

/// A one-line legend of the stages in `stages` (each once, in order of appearance):
/// "F1 first strike, F2 free slide on the belt, …".
pub fn stage_legend(stages: &[Stage]) -> String {
    let mut seen: Vec<Stage> = Vec::new();
    for s in stages {
        if !seen.contains(s) {
            seen.push(*s);
        }
    }
    seen.iter()
        .map(|s| format!("{} {}", s.label(), s.meaning()))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The parcel's planar state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct State {
    /// t \[s] from the arm start
    pub t: f64,
    /// x of the centre G \[m]
    pub x: f64,
    /// y of the centre G \[m]
    pub y: f64,
    /// φ \[rad]
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
    /// α \[rad] at this instant.
    pub arm_angle: f64,
    /// The stage in force (at an event instant: the stage being left).
    pub stage: Stage,
    /// Points where force is transmitted (up to two active contacts) \[m].
    pub contacts: [Option<[f64; 2]>; 2],
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
    /// A strike (F1 the first, F3 later ones); details in `SimResult::impacts`.
    Impact,
    /// A contact starts carrying force without an impact (persistent contact).
    ContactStart,
    /// A contact's normal force reaches zero: it lets go.
    Release,
    /// A sliding contact stops slipping: it sticks or reverses.
    SlipStop,
    /// A sticking contact starts to slide.
    StickBreak,
    /// A contact point reaches the end of its obstacle (the arm tip, the pivot, the guide
    /// end, a parcel corner).
    ContactEnd,
    /// The parcel is out of the arm's reach, riding downstream.
    Escape,
    /// The centre crosses the open pivot-side belt edge y = 0: the parcel falls off.
    OffNearSide,
    /// The tipping margin fell below 1: the parcel topples (`SimResult::tipping`).
    Tipped,
    /// The parcel is wedged between the arm and the guide: the machine jams
    /// (`SimResult::jam`).
    Jammed,
}

impl EventKind {
    /// The label used in outputs.
    pub fn label(self) -> &'static str {
        match self {
            EventKind::ArmStart => "arm_start",
            EventKind::ArmEnd => "arm_end",
            EventKind::RideStart => "ride_start",
            EventKind::Exit => "exit",
            EventKind::Impact => "impact",
            EventKind::ContactStart => "contact_start",
            EventKind::Release => "release",
            EventKind::SlipStop => "slip_stop",
            EventKind::StickBreak => "stick_break",
            EventKind::ContactEnd => "contact_end",
            EventKind::Escape => "escape",
            EventKind::OffNearSide => "off_near_side",
            EventKind::Tipped => "tipped",
            EventKind::Jammed => "jammed",
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum NotDivertedReason {
    /// The parcel passed beyond the arm's reach.
    Escaped,
    /// The parcel is riding on the belt after the arm's cycle (or with no arm).
    LeftOnBelt,
    /// The run reached its duration before a verdict.
    DurationReached,
    /// The centre left the belt across the open pivot-side edge, downstream of the pivot.
    OffNearSide,
    /// The parcel tipped over (its tipping margin fell below 1).
    Tipped,
    /// The parcel is no taller than the arm face's bottom: the arm passes over it.
    UnderArm,
    /// The parcel is wedged between the arm and the guide: no motion of its own lets the
    /// arm go on, and the machine jams (docs/model.md §6b; `SimResult::jam`).
    Jammed,
}

impl NotDivertedReason {
    /// Every reason.
    pub const ALL: [NotDivertedReason; 7] = [
        NotDivertedReason::Escaped,
        NotDivertedReason::LeftOnBelt,
        NotDivertedReason::DurationReached,
        NotDivertedReason::OffNearSide,
        NotDivertedReason::Tipped,
        NotDivertedReason::UnderArm,
        NotDivertedReason::Jammed,
    ];

    /// The reason of a label.
    pub fn from_label(label: &str) -> Option<NotDivertedReason> {
        NotDivertedReason::ALL
            .into_iter()
            .find(|r| r.label() == label)
    }

    /// What the reason means, in words.
    pub fn words(self) -> &'static str {
        match self {
            NotDivertedReason::Escaped => "it passed beyond the arm's reach",
            NotDivertedReason::LeftOnBelt => {
                "it rides on along the belt after the arm's cycle, short of the far edge"
            }
            NotDivertedReason::DurationReached => "the run's time ran out before a verdict",
            NotDivertedReason::OffNearSide => "it left the belt over the open pivot-side edge",
            NotDivertedReason::Tipped => {
                "it tipped over: the arm's push, a strike or the belt's friction toppled it"
            }
            NotDivertedReason::UnderArm => "it is too low for the arm's face, which passes over it",
            NotDivertedReason::Jammed => {
                "it is wedged between the arm and the guide, and the machine jams"
            }
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            NotDivertedReason::Escaped => "escaped",
            NotDivertedReason::LeftOnBelt => "left_on_belt",
            NotDivertedReason::DurationReached => "duration_reached",
            NotDivertedReason::OffNearSide => "off_near_side",
            NotDivertedReason::Tipped => "tipped",
            NotDivertedReason::UnderArm => "under_arm",
            NotDivertedReason::Jammed => "jammed",
        }
    }
}

/// Where and when a parcel jammed: held between the arm and the guide by contacts that no
/// impulse and no force of finite size can settle (docs/model.md §6b). The parcel's pose
/// then is the run's `final_state`.
#[derive(Debug, Clone, PartialEq)]
pub struct Jam {
    /// When \[s].
    pub t: f64,
    /// The contacts that hold it: the obstacle and the contact point (x, y) \[m].
    pub contacts: Vec<(Obstacle, [f64; 2])>,
    /// How the run met the lock: the strikes that did not settle, the active set that did
    /// not exist, or the integration that broke down (the failure it would have been).
    pub cause: String,
}

impl Jam {
    /// Where the parcel is held, in words, each obstacle once: `between the arm's back face
    /// at (0.588, 0.120) m and the guide at (0.838, 0.000) m and (0.588, 0.000) m`.
    pub fn place(&self) -> String {
        // The obstacles in the order they first appear, each with its points.
        let mut held: Vec<(Obstacle, Vec<String>)> = Vec::new();
        for (o, p) in &self.contacts {
            let at = format!("({:.3}, {:.3}) m", p[0], p[1]);
            match held.iter_mut().find(|(h, _)| h == o) {
                Some((_, points)) => points.push(at),
                None => held.push((*o, vec![at])),
            }
        }
        let parts: Vec<String> = held
            .iter()
            .map(|(o, points)| format!("the {} at {}", o.words(), points.join(" and ")))
            .collect();
        match parts.split_last() {
            Some((last, rest)) if !rest.is_empty() => {
                format!("between {} and {last}", rest.join(", "))
            }
            _ => format!("against {}", parts.join("")),
        }
    }
}

/// The verdict.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
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

    /// The label with its reason: `not_diverted (stalled)`, `failed (…)`, `diverted`.
    pub fn verdict(&self) -> String {
        match self.reason() {
            Some(r) => format!("{} ({r})", self.label()),
            None => self.label().to_string(),
        }
    }

    /// [`Outcome::verdict`] without a failure's message (which can be long): for the cells
    /// of a table.
    pub fn short_verdict(&self) -> String {
        match self {
            Outcome::Failed(_) => self.label().to_string(),
            _ => self.verdict(),
        }
    }
}

/// Which obstacle a contact or impact involves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Obstacle {
    /// A parcel corner on the arm's working face.
    ArmFace,
    /// A parcel corner on the arm's back face.
    ArmBack,
    /// The arm tip on a parcel edge.
    ArmTip,
    /// A parcel corner on the side guide.
    Guide,
}

impl Obstacle {
    pub fn label(self) -> &'static str {
        match self {
            Obstacle::ArmFace => "arm_face",
            Obstacle::ArmBack => "arm_back",
            Obstacle::ArmTip => "arm_tip",
            Obstacle::Guide => "guide",
        }
    }

    /// The obstacle in words: `arm's back face`.
    pub fn words(self) -> &'static str {
        match self {
            Obstacle::ArmFace => "arm's working face",
            Obstacle::ArmBack => "arm's back face",
            Obstacle::ArmTip => "arm's tip",
            Obstacle::Guide => "guide",
        }
    }

    /// Whether the arm takes the load (for its fatigue).
    pub fn is_arm(self) -> bool {
        !matches!(self, Obstacle::Guide)
    }
}

/// One strike: all impulses applied at one instant (several contacts of a flush or
/// multi-point strike are summed), docs/model.md §5.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impact {
    /// t \[s]
    pub t: f64,
    /// F1 (first strike) or F3.
    pub stage: Stage,
    /// The obstacle of the first-struck contact.
    pub obstacle: Obstacle,
    /// Contact point \[m] (of the first-struck contact).
    pub point: [f64; 2],
    /// Normal impulse p_f on the parcel, along the first contact's normal [N·s].
    pub normal_impulse: f64,
    /// Tangential impulse p_t along the first contact's tangent [N·s].
    pub tangential_impulse: f64,
    /// S = |P|: magnitude of the total impulse on the parcel [N·s].
    pub impulse: f64,
    /// −u_n,0: normal approach speed at the first contact [m/s].
    pub approach_speed: f64,
    /// W_c: work of the normal force in compression (≤ 0), summed \[J].
    pub compression_work: f64,
    /// Kinetic energy lost relative to the obstacle's contact point motion (≥ 0) \[J].
    pub dissipated: f64,
    /// Whether it was a low-speed strike turned into a persistent contact (no rebound).
    pub persistent: bool,
}

/// The overload summary of a run (docs/model.md §5).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Overload {
    /// Largest impulse S over all strikes [N·s] (0 without strikes).
    pub max_impulse: f64,
    /// S_fall = m(1 + e*)√(2 g H₀) [N·s].
    pub fall_impulse: f64,
    /// max S / S_fall.
    pub overload_ratio: f64,
    /// H_eq = (S/(m(1 + e*)))²/(2g) \[m].
    pub equivalent_drop_height: f64,
    /// max |W_c| / (m g H₀): the peak-force criterion of model.md §5 (equal contact stiffness).
    pub energy_ratio: f64,
    /// Largest impulse taken by the arm in one strike [N·s].
    pub arm_max_impulse: f64,
    /// Sum of the impulses taken by the arm over the run [N·s].
    pub arm_total_impulse: f64,
}

impl Overload {
    /// The words every picture and report of a run heads with when a strike exceeds the
    /// free fall (S/S_fall > 1), `None` otherwise (issue 50: an over-limit strike is flagged
    /// where a user looks).
    pub fn exceeds_text(&self) -> Option<String> {
        (self.overload_ratio > 1.0).then(|| {
            format!(
                "EXCEEDS the free fall: S/S_fall = {:.2}",
                self.overload_ratio
            )
        })
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
    /// Largest y of the centre over the run \[m].
    pub max_lateral: f64,
    /// Smallest and largest x of the centre over the run \[m] (over the samples
    /// [`SimResult::max_lateral`] is taken at): where along the belt the run stayed.
    pub along_range: (f64, f64),
    /// Every strike, in time order.
    pub impacts: Vec<Impact>,
    /// The overload figures.
    pub overload: Overload,
    /// The contact forces seen along the run, for the invariants' checks.
    pub contact_check: ContactCheck,
    /// The smallest tipping margin over the run, when and over which edge
    /// ([`crate::model::tipping`]); a margin below 1 tips the parcel.
    pub tipping: TipRecord,
    /// (t, M_c): the parcel's torque on the arm about the pivot at the accepted steps while
    /// the arm moves \[s, N·m] (0 without an arm contact; empty without an arm).
    pub arm_torque: Vec<(f64, f64)>,
    /// (t, J_c): each strike's angular impulse on the arm about the pivot \[s, N·m·s].
    pub arm_strikes: Vec<(f64, f64)>,
    /// Where and when the parcel jammed, if it did (`not_diverted (jammed)`).
    pub jam: Option<Jam>,
}

impl SimResult {
    /// The loads on the arm's side of the run's stroke ([`crate::sim::arm_loads`]): of the
    /// cycles in which the parcel loaded the arm, the one with the largest peak drive
    /// torque (the first of equals; without a load, the first cycle), for the arm of
    /// `scenario`; `None` without an arm. Computed on demand: batch work that does not ask
    /// for it does not pay for it.
    pub fn arm_loads(
        &self,
        scenario: &crate::model::params::Scenario,
    ) -> Option<crate::sim::arm_loads::ArmLoads> {
        let profile = crate::sim::arm_loads::StrokeProfile::of(scenario)?;
        Some(self.arm_loads_with(scenario, &profile))
    }

    /// [`SimResult::arm_loads`] with the machine's profile built once for many runs
    /// (`profile` must be [`StrokeProfile::of`](crate::sim::arm_loads::StrokeProfile::of)
    /// the scenario's machine).
    pub fn arm_loads_with(
        &self,
        scenario: &crate::model::params::Scenario,
        profile: &crate::sim::arm_loads::StrokeProfile,
    ) -> crate::sim::arm_loads::ArmLoads {
        self.arm_loads_scaled(scenario, profile, 1.0)
    }

    /// [`SimResult::arm_loads_with`] with the parcel's forces scaled by `scale` (the same
    /// run at `scale` times the mass: [`crate::sim::arm_loads::StrokeProfile::loads_scaled`]).
    pub fn arm_loads_scaled(
        &self,
        scenario: &crate::model::params::Scenario,
        profile: &crate::sim::arm_loads::StrokeProfile,
        scale: f64,
    ) -> crate::sim::arm_loads::ArmLoads {
        let starts = &scenario.run.cycle_starts;
        let first = starts.first().copied().unwrap_or(0.0);
        let tc = scenario.machine.cycle_time;
        let within = |t: f64, s: f64| t >= s && t < s + tc;
        let loaded = |s: f64| {
            self.arm_torque.iter().any(|m| m.1 != 0.0 && within(m.0, s))
                || self.arm_strikes.iter().any(|j| within(j.0, s))
        };
        let mut best: Option<crate::sim::arm_loads::ArmLoads> = None;
        for &s in starts.iter().filter(|&&s| loaded(s)) {
            let l = profile.loads_scaled(s, &self.arm_torque, &self.arm_strikes, scale);
            if best.is_none_or(|b| l.peak_torque > b.peak_torque) {
                best = Some(l);
            }
        }
        best.unwrap_or_else(|| {
            profile.loads_scaled(first, &self.arm_torque, &self.arm_strikes, scale)
        })
    }

    /// M_d at every trajectory sample \[N·m]: the drive's torque on the arm about the pivot
    /// in the cycle the sample lies in, I_arm α̈ − M_c (0 while the arm rests between
    /// cycles; strikes are impulses, not in it). `None` without an arm.
    pub fn drive_torque_series(
        &self,
        scenario: &crate::model::params::Scenario,
    ) -> Option<Vec<f64>> {
        let profile = crate::sim::arm_loads::StrokeProfile::of(scenario)?;
        let starts = &scenario.run.cycle_starts;
        Some(
            self.trajectory
                .iter()
                .map(|s| {
                    let t = s.state.t;
                    let k = starts.partition_point(|&c| c <= t);
                    match k {
                        0 => 0.0,
                        _ => profile.drive_torque(starts[k - 1], &self.arm_torque, t),
                    }
                })
                .collect(),
        )
    }
}

pub use crate::model::tipping::TipRecord;

/// Extremes of the contact forces over a run's contact segments, taken at every accepted
/// integrator step (the validity of model.md §6: λ_n ≥ 0, sticking friction inside the cone,
/// sliding friction against the slip). All zero for a run without contacts.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactCheck {
    /// The most negative normal force of an active contact, relative to the weight m g
    /// (0 if none was negative). A pulling contact would make this clearly negative; the
    /// release guard fires at −1e-9.
    pub min_normal_force: f64,
    /// The largest excess of a sticking contact's friction over the cone, |λ_t| − μ λ_n,
    /// relative to m g (0 if none).
    pub max_cone_excess: f64,
    /// The largest power of a sliding contact's friction, λ_t u_t \[W] (0 if none was
    /// positive: friction only dissipates).
    pub max_friction_power: f64,
    /// The largest |g| of an active contact \[m]: how far a persistent contact drifted from
    /// its obstacle (0 if none).
    pub max_gap_drift: f64,
}

impl ContactCheck {
    /// The worse of two records.
    pub fn merge(self, o: ContactCheck) -> ContactCheck {
        ContactCheck {
            min_normal_force: self.min_normal_force.min(o.min_normal_force),
            max_cone_excess: self.max_cone_excess.max(o.max_cone_excess),
            max_friction_power: self.max_friction_power.max(o.max_friction_power),
            max_gap_drift: self.max_gap_drift.max(o.max_gap_drift),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_verdict_names_the_reason_and_a_short_one_drops_a_failures_message() {
        let left = Outcome::NotDiverted(NotDivertedReason::LeftOnBelt);
        let why = NotDivertedReason::LeftOnBelt.label();
        assert_eq!(left.verdict(), format!("not_diverted ({why})"));
        assert_eq!(left.short_verdict(), left.verdict());
        assert_eq!(Outcome::Diverted.verdict(), "diverted");
        let failed = Outcome::Failed("step size underflow".into());
        assert_eq!(failed.verdict(), "failed (step size underflow)");
        assert_eq!(failed.short_verdict(), "failed");
    }
}
