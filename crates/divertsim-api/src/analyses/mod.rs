//! Every analysis of divertsim as library functions: options in, results out, no files and no
//! printing. The CLI (`crates/divertsim`) and the Python package (`crates/divertsim-py`) are
//! thin edges over these; each module also gives its tidy tables (CSV with unit-suffixed
//! columns) and its JSON summary, so that both edges show the same columns.

pub mod capacity;
pub mod capture;
pub mod optimize;
pub mod overload;
pub mod paths;
pub mod reliability;
pub mod replicate;
pub mod runs;
pub mod trigger;
pub mod worst_case;
