//! Throughput of `analyses::runs` over 10,000 scenarios on 2 threads: the Rust counterpart of
//! `crates/divertsim-py/bench/bench_simulate_many.py`, with the same scenarios (same
//! formula, same f64 arithmetic: see that script's docstring).
//!
//! `cargo run --release -p divertsim-api --example throughput [-- N THREADS]`
//!
//! Prints the median of 3 timed runs of: `simulate_verdicts` (what a table of runs needs,
//! and what the Python package's `simulate_many` runs), `simulate_many` (full trajectories),
//! the loading alone (validation), and the whole Python path in Rust (load every scenario
//! from its overrides, then run).

use divertsim_api::analyses::runs::{run_many, simulate_many, simulate_verdicts};
use divertsim_api::config::{Loaded, ScenarioBuilder};
use divertsim_api::threads::with_threads;
use divertsim_core::model::params::Scenario;
use divertsim_core::run::sweep::par_map;
use divertsim_core::sim::{Outcome, Recording, SimResult};
use std::time::Instant;

const A: [f64; 4] = [
    0.618_033_988_749_894_9,
    0.754_877_666_246_692_7,
    0.569_840_290_998_053_2,
    0.819_172_513_396_164_5,
];

fn u(i: usize, k: usize) -> f64 {
    let x = (i + 1) as f64 * A[k];
    x - x.floor()
}

/// The overrides of scenario i.
fn overrides(i: usize) -> Vec<(String, toml::Value)> {
    let f = |k: &str, v: f64| (k.to_string(), toml::Value::Float(v));
    vec![
        f("machine.belt_speed", 1.0 + 1.6 * u(i, 0)),
        f("parcel.offset", 0.25 * u(i, 1)),
        f("parcel.angle_deg", -30.0 + 60.0 * u(i, 2)),
        f("parcel.mass", 0.5 + 14.5 * u(i, 3)),
    ]
}

fn load_all(jobs: &[Vec<(String, toml::Value)>]) -> Vec<Loaded> {
    par_map(jobs, &|| {}, |sets| {
        ScenarioBuilder::new()
            .values(sets)
            .load()
            .unwrap_or_else(|p| panic!("invalid scenario: {p}"))
    })
}

fn median_of_3(label: &str, n: usize, threads: usize, mut f: impl FnMut() -> Vec<SimResult>) {
    let mut times = Vec::new();
    let mut last = Vec::new();
    for _ in 0..3 {
        let t0 = Instant::now();
        last = f();
        times.push(t0.elapsed().as_secs_f64());
    }
    let mut sorted = times.clone();
    sorted.sort_by(f64::total_cmp);
    let med = sorted[1];
    let diverted = last
        .iter()
        .filter(|r| r.outcome == Outcome::Diverted)
        .count();
    let sum_x: f64 = last.iter().map(|r| r.final_state.x).sum();
    println!(
        "rust {label}: {n} scenarios on {threads} threads: median {med:.3} s of {} -> {:.0} scenarios/s",
        times.iter().map(|t| format!("{t:.3}")).collect::<Vec<_>>().join(", "),
        n as f64 / med
    );
    println!("check: {diverted} diverted, sum of final x = {sum_x:.12e} m");
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(10_000);
    let threads: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(2);
    let jobs: Vec<Vec<(String, toml::Value)>> = (0..n).map(overrides).collect();
    let loaded = with_threads(Some(threads), || load_all(&jobs));
    let scenarios: Vec<Scenario> = loaded.iter().map(|l| l.scenario.clone()).collect();
    let _ = simulate_verdicts(&scenarios[..50.min(n)], Some(threads)); // warm-up

    median_of_3("simulate_verdicts", n, threads, || {
        simulate_verdicts(&scenarios, Some(threads))
    });
    median_of_3("simulate_many (full trajectories)", n, threads, || {
        simulate_many(&scenarios, Some(threads))
    });
    let mut load_times: Vec<f64> = (0..3)
        .map(|_| {
            let t0 = Instant::now();
            let l = with_threads(Some(threads), || load_all(&jobs));
            assert_eq!(l.len(), n);
            t0.elapsed().as_secs_f64()
        })
        .collect();
    load_times.sort_by(f64::total_cmp);
    println!(
        "rust load only (validation of every scenario): median {:.3} s -> {:.1} µs per scenario per thread",
        load_times[1],
        load_times[1] * 1e6 * threads as f64 / n as f64
    );
    median_of_3("load + run_many (the Python path)", n, threads, || {
        with_threads(Some(threads), || {
            let loaded = load_all(&jobs);
            run_many(&loaded, None, Recording::VerdictOnly)
                .into_iter()
                .map(|r| r.result)
                .collect()
        })
    });
}
