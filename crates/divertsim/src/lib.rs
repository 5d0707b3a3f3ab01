//! # divertsim (application crate)
//!
//! Everything that touches the outside world: the scenario file format and its validation
//! ([`config`]), output writers ([`output`]), plots ([`plot`]) and the command line
//! ([`cli`]). The physics lives in `divertsim-core`.

pub mod charts;
pub mod checkpoint;
pub mod cli;
pub mod commands;
pub mod config;
pub mod outdir;
pub mod output;
pub mod plot;
pub mod presets;
pub mod report;
pub mod samples;
pub mod tracks;
