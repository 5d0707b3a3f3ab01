//! Every analysis of divertsim as library functions: options in, results out, no files and no
//! printing. The CLI (`crates/divertsim`) and the Python package (`crates/divertsim-py`) are
//! thin edges over these; each module also gives its tidy tables (CSV with unit-suffixed
//! columns) and its JSON summary, so that both edges show the same columns.

pub mod calibration;
pub mod capacity;
pub mod capture;
pub mod check;
pub mod line;
pub mod line_tables;
pub mod measurement;
pub mod optimize;
pub mod overload;
pub mod paths;
pub mod registry;
pub mod reliability;
pub mod replicate;
pub mod runs;
pub mod trigger;
pub mod worst_case;

use crate::config::mix::TriggerConfig;
use crate::config::{self, Loaded};

/// `machine.trigger = "adaptive"` is a problem for a command that does not use it.
pub fn fixed_trigger_only(loaded: Loaded) -> Result<Loaded, config::Problems> {
    if loaded.file.machine.trigger == TriggerConfig::Adaptive {
        return Err(config::Problems(vec![config::Problem::new(
            "machine.trigger",
            "\"adaptive\" is used by `simulate` and `reliability`; this command sets R_s \
                      itself: use \"fixed\"",
        )]));
    }
    Ok(loaded)
}

/// The default work limit of a run (CLI `--max-sims`, Python `max_sims`): about 3–30
/// core-hours at 1–10 ms per simulation.
pub const DEFAULT_MAX_SIMS: u64 = 10_000_000;

/// A count with thousands separators: 12,345,678.
pub fn count_text(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// The problem of a run estimated to need `estimate` simulations when the limit is
/// `max_sims` (named `key`: `--max-sims` or `max_sims`), checked before any work is
/// allocated; `smaller` says how to ask for less.
pub fn over_budget(
    what: &str,
    estimate: u64,
    max_sims: u64,
    key: &str,
    smaller: &str,
) -> Option<config::Problem> {
    (estimate > max_sims).then(|| config::Problem::new(key, format!(
            "{what} would run about {} simulations, more than the limit {}: {smaller}, or raise {key}",
            count_text(estimate),
            count_text(max_sims)
        )))
}
