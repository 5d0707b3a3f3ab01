//! Every analysis of divertsim as library functions: options in, results out, no files and no
//! printing. The CLI (`crates/divertsim`) and the Python package (`crates/divertsim-py`) are
//! thin edges over these; each module also gives its tidy tables (CSV with unit-suffixed
//! columns) and its JSON summary, so that both edges show the same columns.

pub mod calibration;
pub mod capacity;
pub mod capture;
pub mod cells;
pub mod check;
pub mod line;
pub mod line_tables;
pub mod measurement;
pub mod optimize;
pub mod overload;
pub mod paths;
pub mod population;
pub mod poses;
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

/// The problem of a run that needs at least `at_least` simulations when the limit is
/// `max_sims` (named `key`: `--max-sims` or `max_sims`), checked before any work is
/// allocated: a refusal on work the run would really do, never on its upper bound (a run
/// that may need more is stopped when it does, [`past_limit`]); `smaller` says how to ask
/// for less.
pub fn over_budget(
    what: &str,
    at_least: u64,
    max_sims: u64,
    key: &str,
    smaller: &str,
) -> Option<config::Problem> {
    (at_least > max_sims).then(|| config::Problem::new(key, format!(
            "{what} would run at least {} simulations, more than the limit {}: {smaller}, or raise {key}",
            count_text(at_least),
            count_text(max_sims)
        )))
}

/// The problem of a run stopped after `done` simulations, past the limit `max_sims`
/// (named `key`); `at_most` is its upper bound where known (how far to raise the limit to
/// be sure).
pub fn past_limit(
    what: &str,
    done: u64,
    at_most: Option<u64>,
    max_sims: u64,
    key: &str,
    smaller: &str,
) -> config::Problem {
    config::Problem::new(
        key,
        format!(
            "{what} stopped after {} simulations, past the limit {}{}: {smaller}, or raise {key}",
            count_text(done),
            count_text(max_sims),
            at_most.map_or(String::new(), |n| format!(
                " (it runs at most {})",
                count_text(n)
            ))
        ),
    )
}

/// What a run's work reads before it starts: its simulations when they are known
/// (`at_least` = `at_most`), else the range they fall in (the count depends on the
/// verdicts), or with no bound known its least.
pub fn work_text(what: &str, at_least: u64, at_most: Option<u64>) -> String {
    match (at_least, at_most) {
        (_, Some(0)) => format!("{what}: closed form, no simulation"),
        (l, Some(u)) if l >= u => format!("{what}: {} simulations", count_text(u)),
        (l, Some(u)) => format!(
            "{what}: {} to {} simulations (the count depends on the verdicts)",
            count_text(l),
            count_text(u)
        ),
        (l, None) => format!(
            "{what}: at least {} simulations (more as the verdicts ask; announced as they start)",
            count_text(l)
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_grouped() {
        for (n, t) in [
            (0, "0"),
            (999, "999"),
            (1000, "1,000"),
            (10_000_000, "10,000,000"),
            (123_456_789, "123,456,789"),
        ] {
            assert_eq!(count_text(n), t);
        }
    }
}
