//! Criterion benchmarks of whole runs (issue 16): each scene of `scene_set.rs`, full
//! (`simulate`, with the dense trajectory) and verdict-only (`simulate_verdict`, what batch
//! work uses), and the fixed mix of 1,000 random scenarios (verdict-only, one thread; the
//! figure per scenario is the time per iteration / 1,000).
//!
//! `cargo bench -p divertsim --bench scenes`; figures in BENCHMARKS.md.

mod scene_set;
use scene_set as scenes;

use criterion::{criterion_group, criterion_main, Criterion};
use divertsim_core::sim::{simulate, simulate_verdict};
use std::hint::black_box;
use std::time::Duration;

fn singles(c: &mut Criterion) {
    let mut g = c.benchmark_group("scene");
    g.sample_size(40).measurement_time(Duration::from_secs(3));
    for (name, s) in scenes::scenes() {
        g.bench_function(format!("{name}/full"), |b| {
            b.iter(|| simulate(black_box(&s)))
        });
        g.bench_function(format!("{name}/verdict"), |b| {
            b.iter(|| simulate_verdict(black_box(&s)))
        });
    }
    g.finish();
}

fn mix(c: &mut Criterion) {
    let mix = scenes::mix();
    let mut g = c.benchmark_group("mix");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    g.bench_function("1000/verdict", |b| {
        b.iter(|| {
            for s in &mix {
                black_box(simulate_verdict(black_box(s)));
            }
        })
    });
    g.finish();
}

criterion_group!(benches, singles, mix);
criterion_main!(benches);
