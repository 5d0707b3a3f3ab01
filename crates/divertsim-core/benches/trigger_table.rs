//! Cost of one lookup of the adaptive trigger's table (issue 11: "evaluated in microseconds,
//! as a controller could"): the default 5 × 3 × 5 × 5 grid, a parcel between nodes on every
//! axis. The node values are synthetic (the lookup does not depend on them).

use criterion::{criterion_group, criterion_main, Criterion};
use divertsim_core::analysis::design::capacity::linspace;
use divertsim_core::analysis::population::adaptive_trigger::{TableGrid, TriggerTable};
use divertsim_core::model::params::Scenario;
use std::hint::black_box;
use std::time::Duration;

fn lookup(c: &mut Criterion) {
    let grid = TableGrid {
        length: linspace(0.2, 0.7, 5),
        aspect: linspace(0.15, 1.0, 3),
        offset_fraction: linspace(0.0, 1.0, 5),
        angle: linspace(-0.4, 0.4, 5),
    };
    let n = grid.len();
    let table = TriggerTable {
        grid,
        starts: (0..n).map(|i| (i as f64 * 0.618).fract()).collect(),
        feasible: vec![true; n],
        simulations: 0,
    };
    let setting = Scenario::paper_default();
    let mut g = c.benchmark_group("trigger_table");
    g.measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_secs(1));
    g.bench_function("start_for", |b| {
        b.iter(|| {
            table.start_for(
                black_box(0.43),
                black_box(0.21),
                black_box(0.17),
                black_box(0.05),
                &setting,
            )
        })
    });
    g.finish();
}

criterion_group!(benches, lookup);
criterion_main!(benches);
