//! Benchmark of one worst-case search (issue 10): both objectives (largest impulse, smallest
//! divert reserve) at the paper's proposed setting (v 2 m/s, t_c 1.36 s, R_s 0) on the paper
//! preset's machine, default budget (2 × 2,400 simulations), on rayon's default pool (run
//! with `RAYON_NUM_THREADS=2` for the 2-core figure).

use criterion::{criterion_group, criterion_main, Criterion};
use divertsim_core::analysis::design::worst_case::{
    search, PoseBox, SearchSettings, WorstObjective,
};
use divertsim_core::model::params::Scenario;
use divertsim_core::run::sweep::no_progress;
use std::hint::black_box;

fn paper_setting() -> Scenario {
    let mut s = Scenario::paper_machine();
    s.machine.belt_speed = 2.0;
    s.machine.start_position = 0.0;
    s
}

fn bench(c: &mut Criterion) {
    let s = paper_setting();
    let b = PoseBox::paper();
    let settings = SearchSettings::default();
    c.bench_function("worst_case_search_both", |bench| {
        bench.iter(|| {
            for o in [WorstObjective::Impulse, WorstObjective::Reserve] {
                black_box(search(black_box(&s), &b, o, &settings, &no_progress).unwrap());
            }
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).measurement_time(std::time::Duration::from_secs(15));
    targets = bench
}
criterion_main!(benches);
