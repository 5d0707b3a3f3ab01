//! Allocations of whole verdict runs (issue 28), counted by `allocation-counter`'s global
//! allocator in this test binary: the integration's step loop allocates nothing, so a run's
//! allocations follow its events (contact changes, strikes), not its steps. Batch work
//! (maps, searches, a mix of 10⁶ parcels) then pays a few allocations per event only.

use divertsim_core::model::params::Scenario;
use divertsim_core::sim::{simulate, simulate_verdict, SimResult};
use glam::DVec2;

/// The run of `s` and the allocations it made.
fn counted(s: &Scenario) -> (SimResult, u64) {
    let mut run = None;
    let info = allocation_counter::measure(|| {
        run = Some(simulate_verdict(std::hint::black_box(s)));
    });
    (run.expect("the closure ran"), info.count_total)
}

fn scenes() -> Vec<(&'static str, Scenario)> {
    let mut slide = Scenario::paper_default();
    slide.run.arm = false;
    slide.parcel.velocity = Some(DVec2::new(slide.machine.belt_speed + 1.0, 0.0));
    slide.parcel.spin = 3.0;
    let mut slender = Scenario::paper_default();
    slender.parcel.length = 0.7;
    slender.parcel.width = 0.1;
    slender.parcel.height = 0.1;
    slender.parcel.mass = 1.5;
    slender.parcel.offset = 0.0;
    vec![
        ("free slide", slide),
        ("default", Scenario::paper_default()),
        ("flush slender", slender),
    ]
}

/// A free slide ten thousand times tighter takes a third more steps (counted by the full
/// run's trajectory, a sample per step) and not one allocation more.
#[test]
fn a_runs_allocations_do_not_grow_with_its_steps() {
    let (_, slide) = scenes().remove(0);
    let mut loose = slide.clone();
    loose.run.tolerance = 1e-6;
    let mut tight = slide;
    tight.run.tolerance = 1e-10;
    let steps = |s: &Scenario| simulate(s).trajectory.len();
    let (steps_loose, steps_tight) = (steps(&loose), steps(&tight));
    assert!(
        10 * steps_tight > 13 * steps_loose,
        "{steps_tight} vs {steps_loose} steps"
    );
    assert_eq!(counted(&tight).1, counted(&loose).1);
}

/// Every scene allocates at most a couple of dozen times per integration segment (the
/// stage records, the contact sets an event settles, the segment's guard list), whatever
/// its tolerance.
#[test]
fn a_runs_allocations_follow_its_segments() {
    for (name, s) in scenes() {
        for tolerance in [1e-6, 1e-8, 1e-10] {
            let mut s = s.clone();
            s.run.tolerance = tolerance;
            let (r, n) = counted(&s);
            // Events and stage changes: each ends an integration segment.
            let segments = (r.events.len() + r.stages.len()) as u64;
            assert!(
                n <= 24 * (segments + 2),
                "{name} at {tolerance}: {n} allocations for {segments} segments"
            );
        }
    }
}
