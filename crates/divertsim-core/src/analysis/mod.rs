//! Experiments built on the simulator: sweeps, trigger calibration, capture, capacity and
//! overload (the paper's §4 analyses).

pub mod adaptive_trigger;
pub mod calibration;
pub mod capacity;
pub mod capture;
pub mod design;
pub mod memo;
pub mod mix;
pub mod overload;
pub mod reliability;
pub mod robust;
pub mod settings_problem;
pub mod sweep;
pub mod track;
pub mod trigger;
pub mod worst_case;

/// Fixtures the analysis tests share.
#[cfg(test)]
pub(crate) mod test_support {
    use super::worst_case::Pose;
    use crate::model::belt_friction::FrictionCoefficient;
    use crate::model::params::Scenario;

    /// The paper preset's machine (configs/paper/machine.toml: R_z 1.15 m, μ_b 0.5,
    /// μ_a 0.38) on the built-in scenario.
    pub fn paper_machine() -> Scenario {
        let mut s = Scenario::paper_default();
        s.machine.arm_length = 1.15;
        s.materials.belt_friction = FrictionCoefficient::Constant(0.5);
        s.materials.arm_friction = 0.38;
        s
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
        }
    }
}
