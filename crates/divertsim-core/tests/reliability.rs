//! Reliability over a parcel mix against verdicts known in closed form, and the coverage of
//! its intervals.
//!
//! The mix: the built-in parcel in its built-in pose (diverted at the built-in setting), with
//! a trigger phase error that is 0 with probability p and +10 s otherwise. Ten seconds late,
//! the arm starts when the parcel's front is v·10 = 20 m downstream of the pivot, far beyond
//! the arm's reach R_z = 1 m: it can never touch the parcel, which rides away (not diverted).
//! So each sample's verdict is known from its drawn phase alone, and the number diverted is
//! binomial(n, p).

use divertsim_core::analysis::population::mix::{MassLaw, ParcelMix, Placement, Sizes};
use divertsim_core::analysis::population::reliability::{
    run_point, run_shard, NoStore, RunPlan, StartRule,
};
use divertsim_core::model::params::Scenario;
use divertsim_core::run::sweep::no_progress;
use divertsim_core::sim::Outcome;
use divertsim_core::stats::distribution::Distribution;

const P_ON_TIME: f64 = 0.7;

fn known_mix(s: &Scenario) -> ParcelMix {
    let p = &s.parcel;
    ParcelMix {
        sizes: Sizes::Drawn {
            length: Distribution::Fixed(p.length),
            width: Distribution::Fixed(p.width),
            height: Distribution::Fixed(p.height),
        },
        mass: MassLaw::Mass(Distribution::Fixed(p.mass)),
        placement: Placement::Offset(Distribution::Fixed(p.offset)),
        angle: Distribution::Fixed(0.0),
        speed: Distribution::Fixed(0.0),
        spin: Distribution::Fixed(0.0),
        phase: Distribution::Discrete {
            values: vec![0.0, 10.0],
            weights: vec![P_ON_TIME, 1.0 - P_ON_TIME],
        },
        belt_friction: None,
        arm_friction: None,
        restitution: None,
    }
}

#[test]
fn each_verdict_matches_the_closed_form() {
    let s = Scenario::paper_default();
    let runs = run_shard(
        &s,
        &known_mix(&s),
        &StartRule::Fixed,
        9,
        0..200,
        &no_progress,
    )
    .unwrap();
    let mut on_time = 0;
    for r in &runs {
        if r.draw.phase == 0.0 {
            on_time += 1;
            assert_eq!(r.outcome, Outcome::Diverted, "sample {}", r.draw.index);
        } else {
            assert!(
                matches!(r.outcome, Outcome::NotDiverted(_)),
                "sample {}",
                r.draw.index
            );
            assert_eq!(r.strikes, 0);
            assert_eq!(r.max_impulse, 0.0);
        }
    }
    // Both kinds occur, in about the right proportion.
    assert!((100..180).contains(&on_time), "{on_time} of 200 on time");
}

/// Over 200 independent runs (seeds) of 50 samples, the 95 % interval of the divert rate
/// covers the true p = 0.7 in at least 95 % of runs in expectation (Clopper–Pearson is
/// conservative: its exact coverage at n = 50, p = 0.7 is 0.9695). The count of covering
/// runs is then binomial(200, 0.9695): fewer than 182 has probability 1.5e-5 (0.6 % even at
/// the nominal 0.95), so a failure means the interval or the counting is wrong, not bad luck.
/// The seeds are fixed, so the test is deterministic.
#[test]
fn interval_covers_the_known_rate() {
    let s = Scenario::paper_default();
    let mix = known_mix(&s);
    let mut covered = 0;
    let mut diverted_total = 0;
    for seed in 0..200 {
        let plan = RunPlan {
            samples: 50,
            shard_size: 25,
            seed,
            until_width: None,
            confidence: 0.95,
            bins: 4,
        };
        let r = run_point(
            &s,
            &mix,
            &StartRule::Fixed,
            &plan,
            0,
            &NoStore,
            &|| false,
            &no_progress,
            &mut |_| {},
        )
        .unwrap();
        let rate = r.tally.divert_rate(0.95);
        assert_eq!(rate.trials, 50);
        diverted_total += rate.successes;
        if rate.lower <= P_ON_TIME && P_ON_TIME <= rate.upper {
            covered += 1;
        }
        // The built-in parcel's strike is at 0.48 of the free fall and the late ones are never
        // struck: no overload in any run.
        assert_eq!(r.tally.overloaded, 0);
    }
    assert!(
        covered >= 182,
        "the interval covered p in only {covered} of 200 runs"
    );
    // And the pooled estimate is consistent with p (10 000 draws: sd 0.0046).
    let pooled = diverted_total as f64 / 10_000.0;
    assert!((pooled - P_ON_TIME).abs() < 0.02, "pooled {pooled}");
}
