//! Shared helpers of the core's test programs.

pub mod physical;
pub mod wide;
