//! Experiments built on the simulator: sweeps, trigger calibration, capture, capacity and
//! overload (the paper's §4 analyses).

pub mod capture;
pub mod capacity;
pub mod design;
pub mod overload;
pub mod sweep;
pub mod trigger;
