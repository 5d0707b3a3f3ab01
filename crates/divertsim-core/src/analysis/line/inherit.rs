//! A line's further diverters inherit the first diverter's machine (docs/model.md §12): each
//! states only the machine values in which it differs, [`MachineChanges`], in SI. The belt
//! (speed and width) is the line's, never a diverter's own. A setting of the first machine
//! (the line objective's v, t_c, R_s, S_d) reaches every diverter that does not state its
//! own value, as a scenario file's `[machine]` reaches its `[[line.diverters]]`.

use crate::model::drive::DriveSpec;
use crate::model::params::{default_duration, Machine, NearSide, Scenario};
use crate::model::trigger::Trigger;

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
    /// need: after the last start, t_c + 2 s.
    pub fn setting(&self, first: &Scenario, duration_given: bool) -> Scenario {
        let mut s = first.clone();
        s.machine = self.apply(&first.machine);
        if !duration_given {
            s.run.duration =
                cycles_end(&s.run.cycle_starts) + default_duration(s.machine.cycle_time);
        }
        s
    }
}

/// When the last stated cycle starts, or 0 \[s].
pub fn cycles_end(starts: &[f64]) -> f64 {
    starts.last().copied().unwrap_or(0.0).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert_eq!(
            s.run.duration,
            cycles_end(&first.run.cycle_starts) + 1.2 + 2.0
        );
        assert_eq!(c.setting(&first, true).run.duration, first.run.duration);
    }
}
