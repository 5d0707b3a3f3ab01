//! # divertsim (the command-line edge)
//!
//! Arguments ([`cli`], [`commands`]), output directories ([`outdir`], [`checkpoint`]),
//! tables, files, plots of the analyses and HTML reports ([`report`]). Scenarios and every
//! analysis come from `divertsim-api`, pictures from `divertsim-figures`, the physics from
//! `divertsim-core`.

pub mod checkpoint;
pub mod cli;
pub mod commands;
pub mod line_page;
pub mod outdir;
pub mod report;
pub mod studio;
pub mod study_page;
