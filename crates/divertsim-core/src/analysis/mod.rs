//! Experiments built on the simulator, by kind of work (the run infrastructure they share,
//! memo and parallel sweeps, is [`crate::run`]):
//! - [`paper`]: the paper's §4 analyses: trigger calibration R_s(v), capture, the
//!   closed-form overload, the capacity map;
//! - [`design`]: the design set of limiting parcels, the pose box and the searched worst
//!   case, robust settings, the machine-settings problem;
//! - [`population`]: parcel mixes, reliability over a mix, the per-parcel trigger;
//! - [`measurement`]: measured tracks and calibration of values from them.

pub mod design;
pub mod line;
pub mod measurement;
pub mod paper;
pub mod population;

/// Fixtures the analysis tests share.
#[cfg(test)]
pub(crate) mod test_support {
    use crate::analysis::design::worst_case::Pose;

    use crate::model::params::Scenario;

    /// The paper preset's machine (configs/paper/machine.toml: R_z 1.15 m, μ_b 0.5,
    /// μ_a 0.38) on the built-in scenario.
    pub fn paper_machine() -> Scenario {
        Scenario::paper_machine()
    }

    /// A small parcel at the far side, turned −8°, late by 10 ms: struck harder than the
    /// free fall at v = 2 m/s, R_s = 0 on [`paper_machine`].
    pub fn far_side_pose() -> Pose {
        Pose {
            length: 0.2,
            width: 0.12,
            mass: 15.0,
            angle_deg: -8.0,
            offset: 0.55,
            phase: 0.01,
            belt_speed_scale: 1.0,
            belt_friction_scale: 1.0,
            arm_friction: 0.38,
            restitution: 0.3,
            height: None,
        }
    }
}
