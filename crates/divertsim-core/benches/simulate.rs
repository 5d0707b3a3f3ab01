//! Benchmarks of whole runs: one free slide (1 m/s relative speed, spin 3 rad/s, exact
//! friction law, no arm) and the built-in default scenario (the whole scraping process).
//!
//! Instruction counts (robust to machine noise): with `DIVERTSIM_BENCH_RUNS=n` and
//! `DIVERTSIM_BENCH_CASE=slide|default` the binary runs that case n times and exits, without
//! criterion; run it under `valgrind --tool=callgrind` for two values of n and divide the
//! difference of the totals by the difference of the runs.

use criterion::{criterion_group, Criterion};
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::simulate;
use glam::DVec2;
use std::hint::black_box;

fn free_slide() -> Scenario {
    let mut s = Scenario::paper_default();
    s.run.arm = false;
    s.parcel.velocity = Some(DVec2::new(s.machine.belt_speed + 1.0, 0.0));
    s.parcel.spin = 3.0;
    s
}

fn bench(c: &mut Criterion) {
    let slide = free_slide();
    c.bench_function("free_slide_exact", |b| {
        b.iter(|| simulate(black_box(&slide)))
    });
    let default = Scenario::paper_default();
    c.bench_function("default_scenario", |b| {
        b.iter(|| simulate(black_box(&default)))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(50).measurement_time(std::time::Duration::from_secs(4));
    targets = bench
}
fn main() {
    if let Ok(runs) = std::env::var("DIVERTSIM_BENCH_RUNS") {
        let runs: usize = runs.parse().unwrap_or(1);
        let scenario = match std::env::var("DIVERTSIM_BENCH_CASE").as_deref() {
            Ok("default") => Scenario::paper_default(),
            _ => free_slide(),
        };
        for _ in 0..runs {
            black_box(simulate(black_box(&scenario)));
        }
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
