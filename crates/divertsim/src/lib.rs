//! divertsim application library: output helpers shared by the command-line tool.

pub mod plot;
