//! A line's further diverters inherit the first diverter's machine (docs/model.md §12): each
//! states only the machine values in which it differs, [`MachineChanges`], in SI. The belt
//! (speed and width) is the line's, never a diverter's own. A setting of the first machine
//! (the line objective's v, t_c, R_s, S_d) reaches every diverter that does not state its
//! own value ([`Line::with_first_machine`]), as a scenario file's `[machine]` reaches its
//! `[[line.diverters]]`.
//!
//! A new first machine can make the line impossible where the file that gave it was not:
//! a diverter whose light barrier now lies downstream of its arm start, a working area
//! inside the reach of the arm before it, a drive without a cycle of the new t_c, the
//! stated cycles (`run.cycle_starts`) closer than the first machine's t_c, an arm across
//! the parcel at t = 0. [`Line::refusal`] names the first such fault. A scenario file is
//! refused for the same faults, each under its key (the api's `config::validate`, and
//! `config::convert` and `config::load` for the drive and the arm at t = 0); the api's
//! `tests/line_inherit.rs` pins the two to the same verdict.
use super::Line;
use crate::analysis::population::adaptive_trigger::TriggerTable;
use crate::analysis::population::mix::MixError;
use crate::analysis::population::reliability::StartRule;
use crate::model::drive::{ArmDrive, DriveSpec};
use crate::model::params::{run_length, Machine, NearSide, Scenario};
use crate::model::trigger::Trigger;
use crate::run::sweep::Progress;
use crate::sim::{arm_across_parcel_at_start, starts_in_cycle};

/// The machine values a further diverter states over the first diverter's; `None`: the
/// first's.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MachineChanges {
    /// R_z \[m]
    pub arm_length: Option<f64>,
    /// t_c \[s]
    pub cycle_time: Option<f64>,
    /// R_s \[m]
    pub start_position: Option<f64>,
    /// S_d \[m]
    pub light_barrier: Option<f64>,
    /// α(t)
    pub drive: Option<DriveSpec>,
    pub near_side: Option<NearSide>,
    pub trigger: Option<Trigger>,
    /// \[m]
    pub arm_face_bottom: Option<f64>,
    /// \[m]
    pub arm_face_top: Option<f64>,
    /// J_a \[kg·m²]
    pub arm_inertia: Option<f64>,
}

impl MachineChanges {
    /// The diverter's machine: the first's, with these values over it.
    pub fn apply(&self, first: &Machine) -> Machine {
        Machine {
            belt_width: first.belt_width,
            belt_speed: first.belt_speed,
            arm_length: self.arm_length.unwrap_or(first.arm_length),
            cycle_time: self.cycle_time.unwrap_or(first.cycle_time),
            start_position: self.start_position.unwrap_or(first.start_position),
            light_barrier: self.light_barrier.unwrap_or(first.light_barrier),
            drive: self.drive.clone().unwrap_or_else(|| first.drive.clone()),
            near_side: self.near_side.unwrap_or(first.near_side),
            trigger: self
                .trigger
                .clone()
                .unwrap_or_else(|| first.trigger.clone()),
            arm_face_bottom: self.arm_face_bottom.unwrap_or(first.arm_face_bottom),
            arm_face_top: self.arm_face_top.unwrap_or(first.arm_face_top),
            arm_inertia: self.arm_inertia.unwrap_or(first.arm_inertia),
        }
    }

    /// The diverter's setting: the first's scenario with its machine ([`Self::apply`]);
    /// with `duration_given` false (no run length stated), the run as long as its own cycles
    /// need ([`run_length`]).
    pub fn setting(&self, first: &Scenario, duration_given: bool) -> Scenario {
        let mut s = first.clone();
        s.machine = self.apply(&first.machine);
        if !duration_given {
            s.run.duration = run_length(&s.run.cycle_starts, s.machine.cycle_time);
        }
        s
    }
}

/// Where a diverter's working area starts, from its pivot: its light barrier or its arm
/// start when upstream of the pivot, else the pivot itself \[m, ≤ 0].
pub fn working_area_start(light_barrier: f64, start_position: f64) -> f64 {
    light_barrier.min(start_position).min(0.0)
}

/// Why a line's setting cannot run (the first fault, diverters in order; `diverter` is an
/// index, 0 for the first, and its text counts from 1 as every report does).
#[derive(Debug, Clone, PartialEq)]
pub enum LineRefusal {
    /// S_d > R_s: the arm would start before the parcel is seen.
    BarrierDownstream { diverter: usize },
    /// The drive does not make a cycle of this t_c.
    Drive { diverter: usize, message: String },
    /// A stated cycle starts before the one before it has ended (the first machine's t_c).
    CyclesOverlap,
    /// The first machine's setting is no number a machine has: v, R_s or S_d not finite,
    /// v < 0 or t_c not > 0.
    OutOfRange,
    /// The working area begins inside the reach of the arm before it.
    Crowded { diverter: usize },
    /// A cycle under way at t = 0 puts the first arm across the parcel.
    ArmAcrossParcel,
}

impl std::fmt::Display for LineRefusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LineRefusal::BarrierDownstream { diverter } => write!(
                f,
                "diverter {}: the light barrier lies downstream of the arm start",
                diverter + 1
            ),
            LineRefusal::Drive { diverter, message } => {
                write!(f, "diverter {}: {message}", diverter + 1)
            }
            LineRefusal::CyclesOverlap => {
                write!(
                    f,
                    "a stated cycle starts before the one before it has ended"
                )
            }
            LineRefusal::OutOfRange => {
                write!(f, "the setting needs finite values, v ≥ 0 and t_c > 0")
            }
            LineRefusal::Crowded { diverter } => write!(
                f,
                "diverter {}: its working area begins inside the reach of the arm before it",
                diverter + 1
            ),
            LineRefusal::ArmAcrossParcel => {
                write!(
                    f,
                    "a cycle under way at t = 0 puts the arm across the parcel"
                )
            }
        }
    }
}

impl Line {
    /// The line with its first machine `first` (the belt's speed with it): every diverter's
    /// setting made again from it and its own changes, its start rule back to fixed (an
    /// adaptive table is built for a setting: [`Line::build_triggers`]). Everything but the
    /// machine (materials, run settings, limits) is the first diverter's, for every
    /// diverter, as in a line a scenario file gives.
    pub fn with_first_machine(&self, first: Machine) -> Line {
        let mut base = self.diverters[0].setting.clone();
        base.machine = first;
        let mut line = self.clone();
        for d in &mut line.diverters {
            d.setting = d.changes.setting(&base, self.duration_given);
            d.trigger = StartRule::Fixed;
        }
        line
    }

    /// The first reason this line's setting cannot run, if any (module notes).
    pub fn refusal(&self) -> Option<LineRefusal> {
        let first = &self.diverters[0].setting.machine;
        let finite = [
            first.belt_speed,
            first.cycle_time,
            first.start_position,
            first.light_barrier,
        ]
        .iter()
        .all(|v| v.is_finite());
        if !finite || first.belt_speed < 0.0 || first.cycle_time <= 0.0 {
            return Some(LineRefusal::OutOfRange);
        }
        let mut previous: Option<(f64, f64)> = None;
        for (k, d) in self.diverters.iter().enumerate() {
            let m = &d.setting.machine;
            if m.light_barrier > m.start_position {
                return Some(LineRefusal::BarrierDownstream { diverter: k });
            }
            if let Err(e) = ArmDrive::new(&m.drive, m.cycle_time) {
                return Some(LineRefusal::Drive {
                    diverter: k,
                    message: e.to_string(),
                });
            }
            // The stated cycles are the file's, checked against the first machine's t_c: a
            // line run gives every run its own cycles, and a file states no further ones.
            let starts = &d.setting.run.cycle_starts;
            if k == 0
                && starts
                    .windows(2)
                    .any(|w| starts_in_cycle(w[0], w[1], m.cycle_time))
            {
                return Some(LineRefusal::CyclesOverlap);
            }
            if let Some((position, reach)) = previous {
                let from = d.position + working_area_start(m.light_barrier, m.start_position);
                if from < position + reach {
                    return Some(LineRefusal::Crowded { diverter: k });
                }
            }
            previous = Some((d.position, m.arm_length));
        }
        arm_across_parcel_at_start(&self.diverters[0].setting).map(|_| LineRefusal::ArmAcrossParcel)
    }

    /// Build the adaptive trigger tables of the diverters whose machine has one (each over
    /// its own [`super::Diverter::table`] nodes, the grid drawn from the line's mix with
    /// `seed`); the others keep the fixed rule.
    pub fn build_triggers(&mut self, seed: u64, progress: Progress<'_>) -> Result<(), MixError> {
        for d in &mut self.diverters {
            d.trigger = match &d.setting.machine.trigger {
                Trigger::Fixed => StartRule::Fixed,
                Trigger::Adaptive(search) => {
                    let grid = d.table.grid(&self.mix, &d.setting, seed)?;
                    StartRule::Adaptive(TriggerTable::build(&d.setting, grid, search, progress))
                }
            };
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::line::Line;

    /// No change is the first machine; each value stated wins; the belt stays the line's.
    #[test]
    fn a_diverter_inherits_what_it_does_not_state() {
        let first = Scenario::paper_default();
        assert_eq!(
            MachineChanges::default().apply(&first.machine),
            first.machine
        );
        let c = MachineChanges {
            cycle_time: Some(1.2),
            start_position: Some(0.1),
            near_side: Some(NearSide::Guide),
            ..MachineChanges::default()
        };
        let m = c.apply(&first.machine);
        assert_eq!(
            (m.cycle_time, m.start_position, m.near_side),
            (1.2, 0.1, NearSide::Guide)
        );
        assert_eq!(m.belt_speed, first.machine.belt_speed);
        assert_eq!(m.arm_length, first.machine.arm_length);
        let s = c.setting(&first, false);
        assert_eq!(s.run.duration, run_length(&first.run.cycle_starts, 1.2));
        assert_eq!(run_length(&[-0.5], 1.2), 3.2);
        assert_eq!(run_length(&[0.0, 1.5], 1.2), 1.5 + 3.2);
        assert_eq!(c.setting(&first, true).run.duration, first.run.duration);
    }

    /// Two paper machines 3 m apart, the second stating its own R_s.
    fn two() -> Line {
        let mut second = super::super::tests::diverter(3.0, 0.5);
        second.changes.start_position = Some(0.3);
        second.setting.machine.start_position = 0.3;
        super::super::tests::line(vec![super::super::tests::diverter(0.0, 0.5), second], 1.0)
    }

    /// A new first machine reaches what a diverter does not state, leaves what it states,
    /// makes each run as long as its new cycle needs, and takes the built tables away.
    #[test]
    fn a_new_first_machine_reaches_every_diverter_that_does_not_state_it() {
        let mut line = two();
        line.diverters[1].trigger = StartRule::Adaptive(TriggerTable {
            grid: crate::analysis::population::adaptive_trigger::TableGrid {
                length: vec![0.4],
                aspect: vec![0.5],
                offset_fraction: vec![0.0],
                angle: vec![0.0],
            },
            starts: vec![0.1],
            feasible: vec![true],
            simulations: 0,
        });
        let mut first = line.diverters[0].setting.machine.clone();
        first.belt_speed = 1.5;
        first.cycle_time = 1.1;
        first.start_position = 0.1;
        let at = line.with_first_machine(first.clone());
        assert_eq!(at.diverters[0].setting.machine, first);
        let second = &at.diverters[1].setting.machine;
        assert_eq!((second.belt_speed, second.cycle_time), (1.5, 1.1));
        assert_eq!(second.start_position, 0.3);
        for d in &at.diverters {
            assert_eq!(d.setting.run.duration, run_length(&[0.0], 1.1));
            assert_eq!(d.trigger, StartRule::Fixed);
        }
        let given = Line {
            duration_given: true,
            ..line.clone()
        };
        let kept = line.diverters[0].setting.run.duration;
        assert_eq!(
            given.with_first_machine(first).diverters[1]
                .setting
                .run
                .duration,
            kept
        );
    }

    /// Each fault a new first machine can make is named, diverters in order.
    #[test]
    fn a_setting_the_line_cannot_run_is_refused_with_its_fault() {
        let line = two();
        assert_eq!(line.refusal(), None);
        let at = |f: &dyn Fn(&mut Machine)| {
            let mut m = line.diverters[0].setting.machine.clone();
            f(&mut m);
            line.with_first_machine(m).refusal()
        };
        // The second states R_s = 0.3 and takes the first's S_d.
        assert_eq!(
            at(&|m| m.light_barrier = 0.35),
            Some(LineRefusal::BarrierDownstream { diverter: 0 })
        );
        assert_eq!(
            at(&|m| {
                m.start_position = 0.5;
                m.light_barrier = 0.4
            }),
            Some(LineRefusal::BarrierDownstream { diverter: 1 })
        );
        // Its working area from 3 − 1.2 m lies inside the first arm's reach of 2 m.
        assert_eq!(
            at(&|m| {
                m.arm_length = 2.0;
                m.light_barrier = -1.2
            }),
            Some(LineRefusal::Crowded { diverter: 1 })
        );
        let mut cycles = line.clone();
        for d in &mut cycles.diverters {
            d.setting.run.cycle_starts = vec![0.0, 1.5];
        }
        assert_eq!(cycles.refusal(), None);
        let mut m = line.diverters[0].setting.machine.clone();
        m.cycle_time = 1.6;
        assert_eq!(
            cycles.with_first_machine(m).refusal(),
            Some(LineRefusal::CyclesOverlap)
        );
        // The stated cycles are checked against the first machine's t_c alone.
        let mut own = cycles.clone();
        own.diverters[1].changes.cycle_time = Some(2.0);
        let own = own.with_first_machine(line.diverters[0].setting.machine.clone());
        assert_eq!(own.diverters[1].setting.machine.cycle_time, 2.0);
        assert_eq!(own.refusal(), None);
        for bad in [f64::NAN, -1.0] {
            assert_eq!(at(&|m| m.belt_speed = bad), Some(LineRefusal::OutOfRange));
        }
        assert_eq!(at(&|m| m.cycle_time = 0.0), Some(LineRefusal::OutOfRange));
        assert_eq!(working_area_start(-0.2, 0.1), -0.2);
        assert_eq!(
            LineRefusal::Crowded { diverter: 1 }.to_string(),
            "diverter 2: its working area begins inside the reach of the arm before it"
        );
        assert_eq!(working_area_start(0.2, 0.3), 0.0);
    }

    /// Regression (review of the line in the core): a further diverter stating its own
    /// slower cycle, with two stated cycles closer than it, was refused at every setting;
    /// a file checks the stated cycles against the first machine's t_c alone.
    #[test]
    fn a_further_diverters_own_slower_cycle_is_not_refused() {
        let mut line = two();
        for d in &mut line.diverters {
            d.setting.run.cycle_starts = vec![0.0, 1.5];
        }
        line.diverters[1].changes.cycle_time = Some(2.0);
        let at = line.with_first_machine(line.diverters[0].setting.machine.clone());
        assert_eq!(at.diverters[1].setting.machine.cycle_time, 2.0);
        assert_eq!(at.refusal(), None);
    }
}
