//! Cost per call of the belt friction wrench (docs/model.md §3): exact law with the ICR inside
//! the footprint, outside it (closed form), far away (asymptotic branch), the frame-axes
//! entry point, and the seed law.

use criterion::{criterion_group, criterion_main, Criterion};
use divertsim_core::model::belt_friction::{BeltFriction, FrictionCoefficient, FrictionModel};
use glam::DVec2;
use std::hint::black_box;
use std::time::Duration;

fn friction(c: &mut Criterion) {
    let law = |model| {
        BeltFriction::new(
            0.4,
            0.26,
            5.0 * 9.81,
            FrictionCoefficient::Constant(0.4),
            model,
        )
    };
    let exact = law(FrictionModel::Exact);
    let seed = law(FrictionModel::Seed);
    let mut g = c.benchmark_group("belt_friction");
    g.measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_secs(1));
    g.bench_function("exact_icr_inside", |b| {
        b.iter(|| exact.wrench_body(black_box(DVec2::new(0.11, 0.05)), black_box(1.0)))
    });
    g.bench_function("exact_icr_outside", |b| {
        b.iter(|| exact.wrench_body(black_box(DVec2::new(0.5, 0.2)), black_box(1.5)))
    });
    g.bench_function("exact_asymptotic", |b| {
        b.iter(|| exact.wrench_body(black_box(DVec2::new(6.0, 8.0)), black_box(0.1)))
    });
    g.bench_function("exact_frame_axes", |b| {
        b.iter(|| {
            exact.wrench(
                black_box(DVec2::new(-0.5, 0.4)),
                black_box(2.0),
                black_box(0.5),
            )
        })
    });
    g.bench_function("seed", |b| {
        b.iter(|| seed.wrench_body(black_box(DVec2::new(0.5, 0.2)), black_box(1.5)))
    });
    g.finish();
}

criterion_group!(benches, friction);
criterion_main!(benches);
