//! Populations of parcels: a mix (distributions or records) and its draws, Monte Carlo
//! reliability over it, and the per-parcel (adaptive) trigger.

pub mod adaptive_trigger;
pub mod mix;
pub mod reliability;
