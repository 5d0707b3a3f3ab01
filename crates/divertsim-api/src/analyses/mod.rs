//! Every analysis of divertsim as library functions: options in, results out, no files and no
//! printing. The CLI (`crates/divertsim`) and the Python package (`crates/divertsim-py`) are
//! thin edges over these; each module also gives its tidy tables (CSV with unit-suffixed
//! columns) and its JSON summary, so that both edges show the same columns.

pub mod calibration;
pub mod capacity;
pub mod capture;
pub mod optimize;
pub mod overload;
pub mod paths;
pub mod reliability;
pub mod replicate;
pub mod request;
pub mod runs;
pub mod trigger;
pub mod worst_case;

use crate::config::mix::TriggerConfig;
use crate::config::{self, Loaded};

/// `machine.trigger = "adaptive"` is a problem for a command that does not use it.
pub fn fixed_trigger_only(loaded: Loaded) -> Result<Loaded, config::Problems> {
    if loaded.file.machine.trigger == TriggerConfig::Adaptive {
        return Err(config::Problems(vec![config::Problem {
            key: "machine.trigger".into(),
            message: "\"adaptive\" is used by `simulate` and `reliability`; this command sets R_s \
                      itself: use \"fixed\""
                .into(),
        }]));
    }
    Ok(loaded)
}
