//! # divertsim-figures
//!
//! The pictures every edge shows: the top view of one run and overlays of several
//! ([`plot`]), and line charts for the analyses ([`charts`]), as SVG or PNG files or as SVG
//! text, with a bundled font. Depends on the core only; the CLI writes them to files, the
//! Python package shows the top view in a notebook.

pub mod charts;
pub mod plot;
