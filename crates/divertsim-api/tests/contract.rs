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
