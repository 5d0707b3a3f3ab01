//! # divertsim (the command-line edge)
//!
//! Arguments ([`cli`], [`commands`], the analyses' flags in [`flags`]), progress
//! ([`progress`]), output directories ([`outdir`], [`checkpoint`]),
//! tables, files and plots of the analyses. Scenarios and every analysis come from
//! `divertsim-api`, pictures from `divertsim-figures`, HTML pages from `divertsim-report`,
//! the physics from `divertsim-core`.

pub mod checkpoint;
pub mod cli;
pub mod commands;
pub mod flags;
pub mod outdir;
pub mod progress;
pub mod studio;
