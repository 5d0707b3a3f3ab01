//! Cancellation through the contract (hostile input round four): a studio cancel of
//! capacity, both optimize objectives, worst_case, trigger or overload returned, but the work
//! ran on and held a study slot. Every analysis now ends with `Cancelled` at its next piece
//! of work once `Hooks::stop` says so ([`divertsim_api::contract::run_stoppable`]).

use divertsim_api::analyses::registry::{default_sets, find};
use divertsim_api::config::{self, Loaded, Problems};
use divertsim_api::contract::{Error, Hooks};
use serde_json::{json, Value};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// How long a study runs before it is cancelled, and how soon it must end after that.
const RUN_FOR: Duration = Duration::from_secs(5);
const END_WITHIN: Duration = Duration::from_secs(2);

/// Options that keep each analysis busy for far longer than [`RUN_FOR`] on any machine.
fn long_options(name: &str) -> Value {
    match name {
        "trigger" => json!({"speeds": "0.5:2.5/2000"}),
        "capture" => json!({"speeds": "0.5:2.5/2000"}),
        "overload" => json!({"speeds": "0.5:2.5/500", "worst": "search"}),
        "worst_case" => json!({"search_budget": 10_000_000}),
        "check" => json!({"search_budget": 10_000_000}),
        "capacity" => json!({"speeds": "0.5:2.5/200"}),
        "optimize" => json!({"budget": 1_000_000}),
        "optimize_line" => json!({"objective": "line", "parcels": 1_000_000}),
        "reliability" => json!({"samples": 100_000_000}),
        "line" => json!({"parcels": 100_000_000}),
        other => panic!("no long options for {other}"),
    }
}

/// Start `name` with `options` on a thread, stop it after [`RUN_FOR`], and return how long
/// it took to end after the stop (`None`: not within 30 s; the thread is left behind).
fn cancel_after_start(
    name: &'static str,
    analysis: &'static str,
    options: Value,
) -> Option<Duration> {
    let entry = find(analysis).unwrap();
    let stop = std::sync::Arc::new(AtomicBool::new(false));
    let (tx, rx) = mpsc::channel();
    let flag = stop.clone();
    std::thread::spawn(move || {
        let sets: Vec<String> = default_sets(analysis)
            .iter()
            .map(|s| s.to_string())
            .collect();
        let load = move |extra: &[String]| -> Result<Loaded, Problems> {
            let all: Vec<String> = sets.iter().chain(extra).cloned().collect();
            config::load(None, &all)
        };
        let stopped = || flag.load(Ordering::Relaxed);
        let hooks = Hooks {
            stop: &stopped,
            threads: Some(2),
            ..Hooks::none()
        };
        let out = (entry.execute)(&load, &options, u64::MAX, &hooks);
        let _ = tx.send(out.map(|_| ()));
    });
    match rx.recv_timeout(RUN_FOR) {
        Err(mpsc::RecvTimeoutError::Timeout) => {}
        other => panic!("{name} ended before it was cancelled: {other:?}"),
    }
    stop.store(true, Ordering::Relaxed);
    let asked = Instant::now();
    let out = rx.recv_timeout(Duration::from_secs(30)).ok()?;
    assert!(matches!(out, Err(Error::Cancelled)), "{name}: {out:?}");
    Some(asked.elapsed())
}

/// For each analysis the studio serves (and the optimiser's line objective), a stop 5 s
/// after the start ends the run within 2 s.
#[test]
fn every_analysis_ends_within_two_seconds_of_a_stop() {
    let cases: [(&str, &str); 10] = [
        ("trigger", "trigger"),
        ("capture", "capture"),
        ("overload", "overload"),
        ("worst_case", "worst_case"),
        ("check", "check"),
        ("capacity", "capacity"),
        ("optimize", "optimize"),
        ("optimize_line", "optimize"),
        ("reliability", "reliability"),
        ("line", "line"),
    ];
    let mut slow = Vec::new();
    for (name, analysis) in cases {
        match cancel_after_start(name, analysis, long_options(name)) {
            Some(took) => {
                eprintln!("{name}: ended {:.3} s after the stop", took.as_secs_f64());
                if took > END_WITHIN {
                    slow.push(format!("{name}: {:.1} s", took.as_secs_f64()));
                }
            }
            None => slow.push(format!("{name}: not within 30 s")),
        }
    }
    assert!(
        slow.is_empty(),
        "ended later than {END_WITHIN:?} after the stop: {slow:?}"
    );
}
