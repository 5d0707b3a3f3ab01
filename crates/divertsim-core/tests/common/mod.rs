//! Shared helpers of the core's test programs.

pub mod wide;
