//! Experiments built on the simulator: sweeps, trigger calibration, capture, capacity and
//! overload (the paper's §4 analyses).

pub mod capacity;
pub mod capture;
pub mod design;
pub mod overload;
pub mod robust;
pub mod settings_problem;
pub mod sweep;
pub mod trigger;
pub mod worst_case;
