//! Measurements: camera tracks of real parcels compared with simulated paths, and the
//! calibration of model values from them.

pub mod calibration;
pub mod track;
