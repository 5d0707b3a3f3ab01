//! Cost of one segment of the sorter line (issue 25: "10⁶ parcels through a line of two
//! diverters on 2 cores in ≤ 3 min"): 1,000 parcels of the paper's class through two
//! paper-machine diverters 4 m apart, half the parcels for each, clear gaps 1 m ± 16 %
//! (configs/paper/line_two.toml). A million parcels are 1,000 such segments, run in parallel.

use criterion::{criterion_group, criterion_main, Criterion};
use divertsim_core::analysis::line::{run_segment, BusyRule, Diverter, Induction, Line};
use divertsim_core::analysis::population::mix::{MassLaw, ParcelMix, Placement, Sizes};
use divertsim_core::analysis::population::reliability::StartRule;
use divertsim_core::model::params::Scenario;
use divertsim_core::stats::distribution::Distribution;
use std::hint::black_box;
use std::time::Duration;

fn paper_class() -> ParcelMix {
    let uniform = |min: f64, max: f64| Distribution::Uniform { min, max };
    ParcelMix {
        sizes: Sizes::Drawn {
            length: uniform(0.2, 0.7),
            width: uniform(0.1, 0.26),
            height: uniform(0.1, 0.3),
        },
        mass: MassLaw::Mass(uniform(0.5, 15.0)),
        placement: Placement::RoomFraction(uniform(0.0, 1.0)),
        angle: Distribution::TruncatedNormal {
            mean: 0.0,
            sd: 10f64.to_radians(),
            min: -30f64.to_radians(),
            max: 30f64.to_radians(),
        },
        speed: Distribution::Fixed(0.0),
        spin: Distribution::Fixed(0.0),
        phase: Distribution::TruncatedNormal {
            mean: 0.0,
            sd: 0.005,
            min: -0.01,
            max: 0.01,
        },
        belt_friction: None,
        arm_friction: None,
        restitution: None,
    }
}

fn segment(c: &mut Criterion) {
    let diverter = |position| Diverter {
        position,
        setting: Scenario::paper_machine(),
        trigger: StartRule::Fixed,
        share: 0.5,
        changes: Default::default(),
        table: Default::default(),
    };
    let line = Line {
        diverters: vec![diverter(0.0), diverter(4.0)],
        induction: Induction::Gaps {
            gap: Distribution::Normal {
                mean: 1.0,
                sd: 0.16,
            },
            min: 0.1,
        },
        mix: paper_class(),
        busy: BusyRule::Skip,
        duration_given: false,
    };
    let mut g = c.benchmark_group("line");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(20))
        .warm_up_time(Duration::from_secs(2));
    g.bench_function("segment_1000_parcels_two_diverters", |b| {
        b.iter(|| run_segment(&line, 11, black_box(0..1000)).unwrap())
    });
    g.finish();
}

criterion_group!(benches, segment);
criterion_main!(benches);
