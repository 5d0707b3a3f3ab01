//! # divertsim-figures
//!
//! The pictures every edge shows: the top view of one run and overlays of several
//! ([`plot`]), and line charts for the analyses ([`charts`]), the capacity heat map ([`capacity`]) and
//! the optimisation history and Pareto front ([`optimize`]), the reliability study's
//! rate charts and histograms ([`reliability`]), as SVG or PNG files or as SVG
//! text, with a bundled font. Depends on the core only; the CLI writes them to files, the
//! Python package shows the top view in a notebook.

pub mod capacity;
pub mod charts;
pub mod line;
pub mod optimize;
pub mod plot;
pub mod reliability;
pub mod tracks;
