//! Tipping over whole runs (issue 26; docs/model.md §12a): the verdict, its time and edge,
//! the flag mode, the arm face band, and the bound that the belt's friction puts on the
//! margin when every other force acts at the centre of mass's height.

use divertsim_core::model::belt_friction::FrictionCoefficient;
use divertsim_core::model::params::{Scenario, TippingRule};
use divertsim_core::model::tipping::TipCause;
use divertsim_core::sim::{
    simulate, simulate_verdict, EventKind, NotDivertedReason, Outcome, SimResult,
};
use divertsim_core::stats::splitmix::SplitMix64;

/// A tall, narrow carton on the built-in default machine: 0.2 × 0.1 m, 0.4 m tall, 4 kg.
fn tall() -> Scenario {
    let mut s = Scenario::paper_default();
    s.parcel.length = 0.2;
    s.parcel.width = 0.1;
    s.parcel.height = 0.4;
    s.parcel.mass = 4.0;
    s
}

fn mu(s: &Scenario) -> f64 {
    match &s.materials.belt_friction {
        FrictionCoefficient::Constant(m) => *m,
        FrictionCoefficient::Table(_) => panic!("a constant μ_b"),
    }
}

/// The run ends where it tipped: the last event is `tipped`, at the record's time, and the
/// final state is there.
fn assert_ends_tipped(r: &SimResult) {
    assert_eq!(r.outcome, Outcome::NotDiverted(NotDivertedReason::Tipped));
    assert!(r.tipping.tipped(), "{:?}", r.tipping);
    let last = r.events.last().expect("events");
    assert_eq!(last.kind, EventKind::Tipped);
    assert_eq!(last.t, r.tipping.t);
    assert_eq!(r.final_state.t, r.tipping.t);
}

/// Sliding sideways after the strike with μ_b h_c = 0.4 × 0.2 m > b/2 = 0.05 m, the tall
/// carton tips over its long side by the belt's friction; with μ_b h_c < b/2 it cannot.
#[test]
fn tall_narrow_parcel_tips_by_the_belts_friction() {
    let s = tall();
    assert!(mu(&s) * 0.2 > 0.05);
    let r = simulate(&s);
    assert_ends_tipped(&r);
    assert_eq!(r.tipping.cause, Some(TipCause::Forces));
    assert!(r.tipping.edge.is_some());
    // The verdict run is the flag run up to the tipping instant.
    let mut flagged = s.clone();
    flagged.limits.tipping = TippingRule::Flag;
    let f = simulate(&flagged);
    assert!(f.tipping.margin <= r.tipping.margin);
    assert!(f.tipping.t <= r.tipping.t || f.tipping.margin < r.tipping.margin);
    let before: Vec<_> = f.events.iter().filter(|e| e.t < r.tipping.t).collect();
    let verdict: Vec<_> = r.events.iter().filter(|e| e.t < r.tipping.t).collect();
    assert_eq!(before, verdict);
    // Flagged, it runs to the plane model's verdict.
    assert_ne!(f.outcome, Outcome::NotDiverted(NotDivertedReason::Tipped));
    assert!(f.events.iter().all(|e| e.kind != EventKind::Tipped));

    let mut slippery = s;
    slippery.materials.belt_friction = FrictionCoefficient::Constant(0.2);
    let r = simulate(&slippery);
    assert_ne!(r.outcome, Outcome::NotDiverted(NotDivertedReason::Tipped));
    assert!(
        r.tipping.margin >= 0.05 / (0.2 * 0.2) * (1.0 - 1e-9),
        "{:?}",
        r.tipping
    );
}

/// With the arm's force at the centre of mass's height (the default face band on a box
/// with h_c = h/2), the zero-moment point moves only by the belt's friction, at most
/// μ_b h_c: over whole runs the margin never falls below min(a, b)/2 / (μ_b h_c), and a
/// strike never tips. Random parcels and machines, as the whole-run property tests draw
/// them.
#[test]
fn belt_friction_bounds_the_margin_over_whole_runs() {
    let mut rng = SplitMix64(26);
    let mut loaded = 0;
    for _ in 0..300 {
        let mut s = Scenario::paper_default();
        let (a, b) = (rng.uniform(0.1, 0.7), rng.uniform(0.06, 0.4));
        s.parcel.length = a.max(b);
        s.parcel.width = a.min(b);
        s.parcel.height = rng.uniform(0.05, 0.6);
        s.parcel.mass = rng.uniform(0.3, 15.0);
        s.parcel.offset = rng.uniform(0.0, 0.7 - s.parcel.width);
        s.machine.belt_speed = rng.uniform(0.3, 2.5);
        s.machine.start_position = rng.uniform(-0.3, 0.9);
        let mu_b = rng.uniform(0.2, 0.7);
        s.materials.belt_friction = FrictionCoefficient::Constant(mu_b);
        s.materials.arm_friction = rng.uniform(0.0, 0.6);
        s.materials.restitution = rng.uniform(0.0, 0.8);
        s.limits.tipping = TippingRule::Flag;
        let r = simulate_verdict(&s);
        let bound = 0.5 * s.parcel.width / (mu_b * 0.5 * s.parcel.height);
        assert!(
            r.tipping.margin >= bound * (1.0 - 1e-9),
            "margin {:?} below the friction bound {bound} for {s:?}",
            r.tipping
        );
        assert_ne!(r.tipping.cause, Some(TipCause::Strike), "{s:?}");
        if r.tipping.margin.is_finite() {
            loaded += 1;
        }
    }
    assert!(
        loaded > 250,
        "only {loaded} runs loaded the parcel sideways"
    );
}

/// A face band above the centre of mass (z_c > h_c) lets a strike tip a box: the run ends
/// at the strike, after the `impact` event, with no stage after it.
#[test]
fn a_strike_above_the_centre_of_mass_can_tip() {
    let mut s = Scenario::paper_default();
    s.parcel.length = 0.3;
    s.parcel.width = 0.15;
    s.parcel.height = 0.3;
    s.parcel.mass = 5.0;
    s.machine.arm_face_bottom = 0.25;
    s.machine.arm_face_top = 0.5;
    let r = simulate(&s);
    assert_ends_tipped(&r);
    assert_eq!(r.tipping.cause, Some(TipCause::Strike));
    let n = r.events.len();
    assert_eq!(r.events[n - 2].kind, EventKind::Impact);
    assert_eq!(r.events[n - 2].t, r.tipping.t);
    assert_eq!(r.impacts.last().map(|i| i.t), Some(r.tipping.t));
    assert_eq!(
        r.stages.last().map(|st| st.label()),
        Some(r.impacts.last().unwrap().stage.label())
    );
    // The same box struck at its centre of mass's height slides on.
    s.machine.arm_face_bottom = 0.0;
    s.machine.arm_face_top = f64::INFINITY;
    let r = simulate(&s);
    assert_ne!(r.tipping.cause, Some(TipCause::Strike));
}

/// A parcel no taller than the arm face's bottom passes under the arm: no strike, no
/// contact, reason `under_arm`.
#[test]
fn a_parcel_below_the_arm_face_passes_under_it() {
    let mut s = Scenario::paper_default();
    s.parcel.height = 0.05;
    s.machine.arm_face_bottom = 0.08;
    let r = simulate(&s);
    assert_eq!(r.outcome, Outcome::NotDiverted(NotDivertedReason::UnderArm));
    assert!(r.impacts.is_empty());
    assert_eq!(r.tipping.margin, f64::INFINITY);
    // One millimetre taller than the bottom, the arm's face meets it.
    s.parcel.height = 0.081;
    let r = simulate(&s);
    assert_ne!(r.outcome, Outcome::NotDiverted(NotDivertedReason::UnderArm));
    assert!(!r.impacts.is_empty());
}
