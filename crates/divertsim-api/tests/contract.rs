//! Every analysis in the registry keeps the contract: each option documented with its
//! default in the schema (what the CLI's flags and Python's keywords are made of), unknown
//! options refused by name before any work, the work limit enforced, and a stop honoured.

use divertsim_api::analyses::registry::{find, REGISTRY};
use divertsim_api::config::{self, Loaded, Problems};
use divertsim_api::contract::{Error, Hooks};
use serde_json::json;

fn default_scenario(extra: &[String]) -> Result<Loaded, Problems> {
    config::load(None, extra)
}

#[test]
fn every_option_has_help_and_a_default() {
    assert!(REGISTRY.len() >= 5);
    for e in REGISTRY {
        let schema = (e.schema)();
        let props = schema["properties"].as_object().expect(e.name);
        assert!(!props.is_empty(), "{}", e.name);
        for (k, p) in props {
            let help = p["description"].as_str().unwrap_or("");
            assert!(help.len() > 10, "{}.{k} has no help", e.name);
            assert!(p.get("default").is_some(), "{}.{k} has no default", e.name);
        }
        assert!(!e.about.is_empty() && !e.about.ends_with('.'), "{}", e.name);
        assert!(find(e.name).is_some());
    }
}

#[test]
fn unknown_options_are_refused_by_name_before_any_work() {
    for e in REGISTRY {
        let out = (e.execute)(&default_scenario, &json!({"bogus": 1}), 1, &Hooks::none());
        let Err(Error::Invalid(p)) = out else {
            panic!("{}: an unknown option is refused", e.name);
        };
        assert_eq!(p[0].key, "bogus");
        assert!(p[0].message.contains("allowed:"), "{}", p[0].message);
    }
}

#[test]
fn the_work_limit_and_a_stop_refuse_a_run_before_it_starts() {
    // Searches cost simulations: one simulation allowed is refused with the option named.
    let e = find("worst_case").unwrap();
    let Err(Error::Invalid(p)) = (e.execute)(&default_scenario, &json!({}), 1, &Hooks::none())
    else {
        panic!("over the work limit");
    };
    assert_eq!(p[0].key, "max_sims");
    assert!(p[0].message.contains("search_budget"), "{}", p[0].message);
    let stop = || true;
    let hooks = Hooks {
        stop: &stop,
        ..Hooks::none()
    };
    let out = (e.execute)(&default_scenario, &json!({}), u64::MAX, &hooks);
    assert!(matches!(out, Err(Error::Cancelled)), "{out:?}");
}

#[test]
fn a_report_has_its_summary_tables_and_text() {
    let e = find("overload").unwrap();
    let r = (e.execute)(
        &default_scenario,
        &json!({"speeds": [1.0, 2.0]}),
        u64::MAX,
        &Hooks::none(),
    )
    .unwrap();
    assert_eq!(r.summary["divertsim"]["command"], "overload");
    assert_eq!(r.tables[0].0, "overload.csv");
    assert!(r.text.starts_with("the paper's worst case:"), "{}", r.text);
    assert!(r.text.contains("the searched worst case"), "{}", r.text);
    assert!(r.text.contains("S_fall"), "{}", r.text);
}

/// `execute` announces its units before it starts (a server's progress total), then ticks
/// exactly that many times.
#[test]
fn execute_announces_the_units_it_then_ticks() {
    use std::sync::atomic::{AtomicU64, Ordering};
    let e = find("reliability").unwrap();
    let (ticks, announced) = (AtomicU64::new(0), AtomicU64::new(0));
    let progress = || {
        // Every tick comes after the announcement.
        assert!(announced.load(Ordering::SeqCst) > 0);
        ticks.fetch_add(1, Ordering::SeqCst);
    };
    let more = |n: u64| {
        announced.fetch_add(n, Ordering::SeqCst);
    };
    let hooks = Hooks {
        progress: &progress,
        more: &more,
        ..Hooks::none()
    };
    (e.execute)(
        &default_scenario,
        &json!({"samples": 300, "shard": 100}),
        u64::MAX,
        &hooks,
    )
    .unwrap();
    // One unit per run of the fixed trigger's 300 samples.
    assert_eq!(announced.load(Ordering::SeqCst), 300);
    assert_eq!(ticks.load(Ordering::SeqCst), 300);
}

/// A live log kept in memory: the names it was opened with and the JSON lines written.
#[derive(Clone, Default)]
struct Captured {
    names: std::sync::Arc<std::sync::Mutex<Vec<String>>>,
    bytes: std::sync::Arc<std::sync::Mutex<Vec<u8>>>,
}

impl std::io::Write for Captured {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.bytes.lock().unwrap().extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Captured {
    /// The live log that writes here (a live log outlives the call: it owns its sink).
    fn live(&self) -> impl Fn(&str) -> Option<Box<dyn std::io::Write + Send>> + Sync {
        let me = self.clone();
        move |name: &str| {
            me.names.lock().unwrap().push(name.to_string());
            Some(Box::new(me.clone()) as Box<dyn std::io::Write + Send>)
        }
    }

    fn lines(&self) -> Vec<serde_json::Value> {
        let text = String::from_utf8(self.bytes.lock().unwrap().clone()).unwrap();
        text.lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect()
    }
}

/// With a live log, reliability writes its rates so far after each shard (a page shows them
/// as they come); the last line is the final result's.
#[test]
fn reliability_writes_its_rates_so_far_after_each_shard() {
    let log = Captured::default();
    let live = log.live();
    let hooks = Hooks {
        live: Some(&live),
        ..Hooks::none()
    };
    let e = find("reliability").unwrap();
    let r = (e.execute)(
        &default_scenario,
        &json!({"samples": 300, "shard": 100}),
        u64::MAX,
        &hooks,
    )
    .unwrap();
    assert_eq!(*log.names.lock().unwrap(), ["partial.jsonl"]);
    let lines = log.lines();
    let samples: Vec<u64> = lines
        .iter()
        .map(|l| l["samples"].as_u64().unwrap())
        .collect();
    assert_eq!(samples, [100, 200, 300]);
    let last = lines.last().unwrap();
    let point = &r.summary["points"][0];
    for k in [
        "divert_rate",
        "overload_rate",
        "tipping_rate",
        "failures_by_reason",
    ] {
        assert_eq!(last[k], point[k], "{k}");
    }
}

/// The line writes its rates so far after each batch of segments too; the last line is the
/// final result's.
#[test]
fn line_writes_its_rates_so_far_after_each_batch() {
    let log = Captured::default();
    let live = log.live();
    // One thread: batches of 4 segments, so 8 segments are 2 batches.
    let hooks = Hooks {
        live: Some(&live),
        threads: Some(1),
        ..Hooks::none()
    };
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/paper/line.toml");
    let load = |extra: &[String]| config::load(Some(&path), extra);
    let r = (find("line").unwrap().execute)(
        &load,
        &json!({"parcels": 400, "segment": 50}),
        u64::MAX,
        &hooks,
    )
    .unwrap();
    let lines = log.lines();
    let parcels: Vec<u64> = lines
        .iter()
        .map(|l| l["parcels"].as_u64().unwrap())
        .collect();
    assert_eq!(parcels, [200, 400]);
    let point = &r.summary["points"][0];
    for k in [
        "throughput_per_h",
        "missort_rate",
        "struck_rate",
        "overload_rate",
        "tipped_rate",
    ] {
        assert_eq!(lines[1][k], point[k], "{k}");
    }
}

/// The typed run of analysis `A` on the paper machine with JSON `options` under the work
/// limit `max_sims`: its work as announced, and its output or error.
fn run_limited<A: divertsim_api::contract::Analysis>(
    options: serde_json::Value,
    max_sims: u64,
) -> (divertsim_api::contract::Work, Result<A::Output, Error>, u64) {
    use divertsim_api::contract::{self, Limit};
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../configs/paper/machine.toml"
    );
    // The analysis's own default case (the paper's figure parcel), as the CLI applies it.
    let sets: Vec<String> = A::DEFAULT_SETS.iter().map(|s| s.to_string()).collect();
    let loaded = config::load(Some(std::path::Path::new(path)), &sets).unwrap();
    let o: A::Options = contract::options_from_json(&options).unwrap();
    let checked = A::bind(A::validate(&o).unwrap(), &loaded).unwrap();
    let work = A::work(&checked, &loaded);
    let limit = Limit {
        max_sims,
        key: "max_sims",
        at_most: work.at_most,
        smaller: work.smaller,
    };
    let out = contract::run_stoppable::<A>(&loaded, &checked, &Hooks::none(), &limit);
    let sims = out.as_ref().ok().and_then(A::simulations).unwrap_or(0);
    (work, out, sims)
}

/// Issue 50, item 6: the work announced before a run brackets what it runs (the least it
/// runs whatever its verdicts, the most it can run), for both worst cases of a capacity map
/// and for a trigger curve, whose counts depend on the verdicts.
#[test]
fn the_announced_work_brackets_the_simulations_run() {
    use divertsim_api::analyses::capacity::Capacity;
    use divertsim_api::analyses::trigger::TriggerCalibration;
    let grid = |worst: &str| {
        json!({"cycle_times": "1.2,1.4", "light_barriers": "0.2,0.6", "speeds": "1.2,1.8",
               "start_step": 0.15, "worst": worst, "search_budget": 200, "rounds": 2})
    };
    for worst in ["paper", "search"] {
        let (work, out, sims) = run_limited::<Capacity>(grid(worst), u64::MAX);
        assert!(out.is_ok(), "{worst}: {:?}", out.err());
        assert!(
            work.at_least > 0 && work.at_least <= sims,
            "{worst}: {work:?} ran {sims}"
        );
        match worst {
            // A robust map's searches and rounds are not bounded before it runs.
            "search" => assert_eq!(work.at_most, None),
            _ => assert!(sims <= work.at_most.unwrap(), "{work:?} ran {sims}"),
        }
    }
    let (work, out, sims) =
        run_limited::<TriggerCalibration>(json!({"speeds": "0.8,1.6"}), u64::MAX);
    assert!(out.is_ok(), "{:?}", out.err());
    assert!(
        work.at_least <= sims && sims <= work.at_most.unwrap(),
        "{work:?} ran {sims}"
    );
}

/// Issue 50, item 6: the work limit is on the simulations a run really does. A limit above
/// the least a run needs but below what it runs lets it start and stops it once its count
/// passes the limit, with the option named; a limit at its real count lets it finish. The
/// count is the run's own (the meter of its worker pool counts exactly what the analysis
/// reports).
#[test]
fn a_work_limit_stops_a_run_on_its_real_count_not_its_estimate() {
    use divertsim_api::analyses::capacity::Capacity;
    let options = json!({"cycle_times": "1.2,1.4", "light_barriers": "0.2,0.6",
                         "speeds": "1.2,1.8", "start_step": 0.15, "worst": "paper"});
    let (work, out, sims) = run_limited::<Capacity>(options.clone(), u64::MAX);
    assert!(out.is_ok());
    let at_most = work.at_most.unwrap();
    assert!(
        work.at_least < sims && sims < at_most,
        "{work:?} ran {sims}"
    );
    // Exactly the real count: it finishes.
    let (_, out, again) = run_limited::<Capacity>(options.clone(), sims);
    assert!(out.is_ok(), "{:?}", out.err());
    assert_eq!(again, sims);
    // Below it (above the least): it starts and is stopped, the option named.
    let (_, out, _) = run_limited::<Capacity>(options, sims - 1);
    let Err(Error::Invalid(p)) = out else {
        panic!("the run passed its limit");
    };
    assert_eq!(p[0].key, "max_sims");
    assert!(p[0].message.contains("stopped after"), "{}", p[0].message);
    assert!(p[0]
        .message
        .contains(&divertsim_api::analyses::count_text(at_most)));
}

/// The list grammar's warnings reach every edge through the registry, keyed by the option:
/// a whole-number STEP read as a step is said; a list given as numbers, a plain step and an
/// option outside the grammar are not.
#[test]
fn a_list_options_step_that_reads_like_a_count_is_a_warning_of_its_option() {
    use divertsim_api::analyses::registry::warnings;
    let w = warnings(
        "capacity",
        &json!({"speeds": "0.5:2.5:2", "cycle_times": [1.2]}),
    );
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].key, "speeds");
    assert!(
        w[0].message
            .contains("`speeds` '0.5:2.5:2' is read as LO:HI:STEP"),
        "{w:?}"
    );
    assert!(warnings("trigger", &json!({"speeds": "1:2:0.5"})).is_empty());
    assert!(warnings("optimize", &json!({"method": "2"})).is_empty());
    assert!(warnings("nothing", &json!({"speeds": "0:10:5"})).is_empty());
}

/// Issue 48, item 3: the contract says which analyses read files named in their options (an
/// edge that reads no file beyond the scenario's, the studio, serves only the others); an
/// options type with a file list (`tracks`) says so, and no other does.
#[test]
fn an_analysis_that_reads_files_named_in_its_options_says_so() {
    for e in REGISTRY {
        let schema = (e.schema)();
        let names_files = schema["properties"]
            .as_object()
            .is_some_and(|p| p.contains_key("tracks"));
        assert_eq!(e.reads_files, names_files, "{}", e.name);
    }
    let reading: Vec<&str> = REGISTRY
        .iter()
        .filter(|e| e.reads_files)
        .map(|e| e.name)
        .collect();
    assert_eq!(reading, ["compare", "calibrate"]);
}
