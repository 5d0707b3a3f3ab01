//! # divertsim-api
//!
//! The one library API every edge calls (the `divertsim` CLI, the Python package): the
//! scenario contract ([`config`]: files with their base chain, defaults, dotted overrides,
//! validation listing every problem), the presets built from `configs/`, result views
//! ([`output`]), the reliability sample table ([`samples`]), track files ([`tracks`]) and
//! every analysis's orchestration ([`analyses`]). The physics is in `divertsim-core`; the
//! edges keep only arguments, files, tables and pictures.

pub mod analyses;
pub mod config;
pub mod output;
pub mod presets;
pub mod samples;
pub mod tracks;
