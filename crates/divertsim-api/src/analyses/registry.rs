//! The analyses on the contract ([`crate::contract`]), by name: what the Python package,
//! a server or any edge that takes an analysis by name looks up, and [`run`], the one entry
//! with loose options (a name, the scenario through a loader, the options as JSON with the
//! names of the CLI's flags in snake case; unknown or mistyped options and out-of-range
//! values come back as problems naming the option).

use crate::config::Problem;
use crate::contract::{entry, Entry, Error, Hooks, Loader, Report};
use serde_json::Value;

/// The analyses on the contract.
pub const REGISTRY: &[Entry] = &[
    entry::<super::trigger::TriggerCalibration>(),
    entry::<super::capture::Capture>(),
    entry::<super::overload::Overload>(),
    entry::<super::worst_case::WorstCaseSearch>(),
    entry::<super::check::Check>(),
    entry::<super::capacity::Capacity>(),
    entry::<super::optimize::Optimize>(),
    entry::<super::reliability::Reliability>(),
    entry::<super::line::LineAnalysis>(),
    entry::<super::measurement::Compare>(),
    entry::<super::measurement::Calibrate>(),
];

/// The registry's entry of `name`.
pub fn find(name: &str) -> Option<&'static Entry> {
    REGISTRY.iter().find(|e| e.name == name)
}

/// Scenario overrides an analysis applies to the built-in default scenario (when no
/// scenario is given), as the CLI does: the paper's figure parcel of trigger and capture.
pub fn default_sets(name: &str) -> &'static [&'static str] {
    find(name).map_or(&[], |e| e.default_sets)
}

/// Asked between pieces of work (a reliability shard; before a run starts): `true` stops
/// the run with [`Error::Cancelled`]. The Python edge answers from its signal handler.
pub type Stop<'a> = &'a (dyn Fn() -> bool + Sync);

/// Never stops.
pub fn never_stop() -> bool {
    false
}

/// The `max_sims` option (default [`super::DEFAULT_MAX_SIMS`]) and the other options.
pub fn max_sims_option(options: &Value) -> Result<(u64, Value), Error> {
    let mut options = options.clone();
    let max_sims = match options.as_object_mut().and_then(|m| m.remove("max_sims")) {
        None | Some(Value::Null) => super::DEFAULT_MAX_SIMS,
        Some(v) => match v.as_u64() {
            Some(n) if n >= 1 => n,
            _ => {
                return Err(Error::Invalid(vec![Problem::new(
                    "max_sims",
                    format!("{v} is not a count; allowed: an integer >= 1"),
                )]))
            }
        },
    };
    Ok((max_sims, options))
}

/// Run analysis `name` on the scenario of `load` with `options` (a JSON object; besides the
/// analysis's own options, `max_sims`: the work limit, default [`super::DEFAULT_MAX_SIMS`]);
/// `stop` is asked between pieces of work.
pub fn run(name: &str, load: Loader<'_>, options: &Value, stop: Stop<'_>) -> Result<Report, Error> {
    let (max_sims, options) = max_sims_option(options)?;
    let Some(entry) = find(name) else {
        let names: Vec<&str> = REGISTRY.iter().map(|e| e.name).collect();
        return Err(Error::Invalid(vec![Problem::new(
            "analysis",
            format!("no analysis '{name}'; allowed: {}", names.join(", ")),
        )]));
    };
    let hooks = Hooks {
        stop,
        ..Hooks::none()
    };
    (entry.execute)(load, &options, max_sims, &hooks)
}

/// The list grammar's warnings on the options of analysis `name`
/// ([`crate::contract::option_warnings`]); none for an unknown analysis (its run says so).
pub fn warnings(name: &str, options: &Value) -> Vec<Problem> {
    find(name).map_or_else(Vec::new, |entry| (entry.warnings)(options))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config;
    use serde_json::json;

    /// [`super::run`] that never stops.
    fn run(name: &str, load: Loader<'_>, options: &Value) -> Result<Report, Error> {
        super::run(name, load, options, &never_stop)
    }

    /// Hostile input round three: Python's `capacity` took a 7×10¹⁰-simulation grid that
    /// the CLI refuses; the request checks the same work limit before allocating anything.
    #[test]
    fn python_work_limit_refuses_a_huge_capacity_grid_before_allocating() {
        let load = default_loader("capacity");
        let huge = json!({
            "cycle_times": "0.2:10/1000",
            "light_barriers": "-5:5/1000",
            "speeds": "0.05:10/1000",
        });
        let Err(Error::Invalid(p)) = run("capacity", &load, &huge) else {
            panic!("a 10^9-cell grid is refused");
        };
        assert_eq!(p[0].key, "max_sims", "{p:?}");
        assert!(
            p[0].message.contains("more than the limit 10,000,000"),
            "{p:?}"
        );
        // The limit is an option: a small one refuses the default trigger too.
        let mut small = json!({"max_sims": 3});
        let Err(Error::Invalid(p)) = run("trigger", &default_loader("trigger"), &small) else {
            panic!("the trigger needs more than 3 simulations");
        };
        assert_eq!(p[0].key, "max_sims");
        small["max_sims"] = json!(0);
        let Err(Error::Invalid(p)) = run("trigger", &default_loader("trigger"), &small) else {
            panic!("max_sims 0 is refused");
        };
        assert!(p[0].message.contains("integer >= 1"), "{p:?}");
    }

    /// A caller's stop is honoured before a run starts and between reliability shards.
    #[test]
    fn python_interrupt_stops_a_request() {
        let hub =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/mix/hub.toml");
        let load = move |extra: &[String]| config::load(Some(&hub), extra);
        let stop = || true;
        let out = super::run("trigger", &default_loader("trigger"), &Value::Null, &stop);
        assert_eq!(out.err(), Some(Error::Cancelled));
        let calls = std::sync::atomic::AtomicUsize::new(0);
        // Let the run start, then stop at the second shard.
        let later = || calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed) >= 2;
        let out = super::run(
            "reliability",
            &load,
            &json!({"samples": 400, "shard": 100}),
            &later,
        );
        assert_eq!(out.err(), Some(Error::Cancelled));
    }

    fn default_loader(
        name: &'static str,
    ) -> impl Fn(&[String]) -> Result<config::Loaded, config::Problems> {
        move |extra: &[String]| {
            let sets: Vec<String> = default_sets(name)
                .iter()
                .map(|s| s.to_string())
                .chain(extra.iter().cloned())
                .collect();
            config::load(None, &sets)
        }
    }

    #[test]
    fn unknown_and_mistyped_options_are_problems_naming_the_option() {
        let load = default_loader("trigger");
        let Err(Error::Invalid(p)) = run("trigger", &load, &json!({"speedz": [1.0]})) else {
            panic!("an unknown option is refused");
        };
        assert_eq!(p[0].key, "speedz");
        assert!(p[0].message.contains("allowed: reference_cycle"), "{p:?}");
        let Err(Error::Invalid(p)) = run("trigger", &load, &json!({"scan_step": "wide"})) else {
            panic!("a mistyped option is refused");
        };
        assert_eq!(p[0].key, "scan_step");
        let Err(Error::Invalid(p)) = run(
            "trigger",
            &load,
            &json!({"speeds": [25.0], "tolerance": 0.5}),
        ) else {
            panic!("out-of-range values are refused");
        };
        let keys: Vec<&str> = p.iter().map(|p| p.key.as_str()).collect();
        assert_eq!(keys, ["speeds", "tolerance"]);
        assert!(p[0].message.contains("(0, 20] m/s"));
        let Err(Error::Invalid(p)) = run("nothing", &load, &Value::Null) else {
            panic!("an unknown analysis is refused");
        };
        assert!(p[0].message.contains("allowed: trigger, capture"));
    }

    /// The request gives the CLI's numbers: the same compute and table functions.
    #[test]
    fn trigger_request_runs_the_calibration_with_its_table() {
        // The paper's machine and Fig. 6 parcel (the built-in default machine diverts the
        // reference run).
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/paper/fig06.toml");
        let load = |extra: &[String]| config::load(Some(&path), extra);
        let out = run("trigger", &load, &json!({"speeds": [0.65, 1.5]})).unwrap();
        assert_eq!(out.summary["divertsim"]["command"], "trigger");
        assert_eq!(out.summary["points"].as_array().unwrap().len(), 2);
        let csv = String::from_utf8(out.tables[0].1.clone()).unwrap();
        assert!(csv.starts_with("belt_speed_m_s,start_position_m"));
        assert_eq!(csv.lines().count(), 3);
        // The reference speed reproduces the reference R_s = 0.8 m.
        let r0 = out.summary["points"][0]["start_position"].as_f64().unwrap();
        assert!((r0 - 0.8).abs() < 2e-3, "{r0}");
    }

    #[test]
    fn optimize_request_checks_then_runs_the_method() {
        let load = default_loader("optimize");
        let Err(Error::Invalid(p)) = run(
            "optimize",
            &load,
            &json!({"method": "annealing", "bounds": {"speed": [1, 2]}, "worst": "paper", "rounds": 0}),
        ) else {
            panic!("bad options are refused");
        };
        let keys: Vec<&str> = p.iter().map(|p| p.key.as_str()).collect();
        assert_eq!(keys, ["method", "bounds.speed", "rounds"]);
        let Err(Error::Invalid(p)) = run(
            "optimize",
            &load,
            &json!({"method": "ga", "generations": 0, "start": [2.0, 1.3, 0.1], "polish": false,
                    "worst": "paper"}),
        ) else {
            panic!("options that do not apply are refused");
        };
        let keys: Vec<&str> = p.iter().map(|p| p.key.as_str()).collect();
        assert_eq!(keys, ["generations", "start", "polish"]);
        let out = run(
            "optimize",
            &load,
            &json!({"method": "ga", "population": 6, "generations": 2, "worst": "paper",
                    "bounds": {"belt_speed": [1.5, 2.0], "light_barrier": 0.0}}),
        )
        .unwrap();
        assert_eq!(out.summary["divertsim"]["command"], "optimize");
        let names: Vec<&str> = out.tables.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["evaluations.csv", "history.csv"]);
        let evaluations = String::from_utf8(out.tables[0].1.clone()).unwrap();
        assert!(evaluations.lines().count() > 6, "{evaluations}");
    }

    #[test]
    fn grouped_options_keep_their_names_and_null_is_the_default() {
        let load = default_loader("capacity");
        for (options, key) in [
            (json!({"search_budget": "x"}), "search_budget"),
            (json!({"rounds": -1}), "rounds"),
            (json!({"speeds": "fast"}), "speeds"),
        ] {
            let Err(Error::Invalid(p)) = run("capacity", &load, &options) else {
                panic!("{options} is refused");
            };
            assert_eq!(p[0].key, key, "{p:?}");
        }
        // The CLI's default grid, from the same grammar: 0.65:2.3:0.05 gives 0.7 exactly.
        let t: crate::analyses::trigger::TriggerOptions =
            crate::contract::options_from_json(&json!({"speeds": null})).unwrap();
        let speeds = t
            .speeds
            .resolve("speeds", crate::analyses::trigger::SPEED_LIST)
            .unwrap();
        assert_eq!(speeds.len(), 34);
        assert_eq!(speeds[1], 0.7);
    }
}
