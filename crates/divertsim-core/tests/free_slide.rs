//! Free flat motion (stage F2) and riding, against the reference slides of docs/model.md §4
//! and analytic solutions.

use approx::assert_relative_eq;
use divertsim_core::model::belt_friction::{FrictionCoefficient, FrictionModel};
use divertsim_core::model::params::{Scenario, TippingRule};
use divertsim_core::sim::{simulate, EventKind, NotDivertedReason, Outcome, SimResult, Stage};
use divertsim_core::GRAVITY;
use glam::DVec2;
use proptest::prelude::*;
use proptest::test_runner::RngSeed;

/// A free parcel (no arm) with belt-relative velocity `v_rel` and spin `omega`.
fn free_scenario(v_rel: DVec2, omega: f64, tolerance: f64) -> Scenario {
    let mut s = Scenario::paper_default();
    s.run.arm = false;
    s.run.tolerance = tolerance;
    s.run.duration = 2.0;
    s.parcel.length = 0.4;
    s.parcel.width = 0.26;
    s.parcel.mass = 5.0;
    s.parcel.offset = 0.2;
    s.machine.belt_width = 10.0; // keep the parcel on the belt whatever it does
    s.materials.belt_friction = FrictionCoefficient::Constant(0.4);
    s.parcel.velocity = Some(DVec2::new(s.machine.belt_speed, 0.0) + v_rel);
    s.parcel.spin = omega;
    // The plane model's friction law is under test: a narrow parcel that would tip (a
    // 0.05 m wide one, 0.15 m tall, on μ_b 0.8) is only flagged (tests/tipping.rs).
    s.limits.tipping = TippingRule::Flag;
    s
}

/// (stop time, displacement relative to the belt, rotation \[deg]) at the ride start.
fn stop_of(s: &Scenario, r: &SimResult) -> (f64, DVec2, f64) {
    let ev = r
        .events
        .iter()
        .find(|e| e.kind == EventKind::RideStart)
        .expect("no ride_start");
    let first = r.trajectory.first().unwrap().state;
    let at = r
        .trajectory
        .iter()
        .find(|p| p.state.t == ev.t && p.stage == Stage::Ride)
        .expect("no sample at the ride start")
        .state;
    let disp = DVec2::new(at.x - first.x - s.machine.belt_speed * ev.t, at.y - first.y);
    (ev.t, disp, (at.phi - first.phi).to_degrees())
}

/// The reference slides of docs/model.md §4 (converged 10-digit values), to 1e-5 relative.
#[test]
fn free_slide_reference_values() {
    let rows = [
        (
            DVec2::new(1.0, 0.0),
            0.0,
            0.2548419725,
            DVec2::new(0.1274209990, 0.0),
            0.0,
        ),
        (
            DVec2::new(0.0, 0.0),
            3.0,
            0.1133017394,
            DVec2::new(0.0, 0.0),
            9.7375704651,
        ),
        (
            DVec2::new(1.0, 0.0),
            3.0,
            0.2876557250,
            DVec2::new(0.1381955570, -0.0016809947),
            27.7658963667,
        ),
        (
            DVec2::new(0.5, 0.5),
            -4.0,
            0.2558383887,
            DVec2::new(0.0588478600, 0.0636685321),
            -30.7525591527,
        ),
    ];
    for (v_rel, omega, t_ref, d_ref, rot_ref) in rows {
        let s = free_scenario(v_rel, omega, 1e-10);
        let r = simulate(&s);
        let (t, d, rot) = stop_of(&s, &r);
        assert_relative_eq!(t, t_ref, max_relative = 1e-5);
        assert_relative_eq!(d.x, d_ref.x, max_relative = 1e-5, epsilon = 1e-9);
        assert_relative_eq!(d.y, d_ref.y, max_relative = 1e-5, epsilon = 1e-9);
        assert_relative_eq!(rot, rot_ref, max_relative = 1e-5, epsilon = 1e-7);
        assert_eq!(r.stages, vec![Stage::F2, Stage::Ride]);
    }
}

/// The Done-when check of issue "The core": 1 m/s faster than a 2 m/s belt, no arm:
/// ride_start at 1/(μ_b g), then riding at belt speed.
#[test]
fn ride_starts_at_v_over_mu_g_and_then_rides() {
    let mut s = Scenario::paper_default();
    s.run.arm = false;
    s.parcel.velocity = Some(DVec2::new(3.0, 0.0));
    let r = simulate(&s);
    let ev = r
        .events
        .iter()
        .find(|e| e.kind == EventKind::RideStart)
        .unwrap();
    assert!((ev.t - 1.0 / (0.4 * GRAVITY)).abs() < 1e-6, "t = {}", ev.t);
    assert_eq!(
        r.outcome,
        Outcome::NotDiverted(NotDivertedReason::LeftOnBelt)
    );
    assert_eq!(r.final_state.vx, 2.0);
    assert_eq!(r.final_state.vy, 0.0);
    assert_eq!(r.final_state.omega, 0.0);
    assert_eq!(r.final_state.t, s.run.duration);
    for p in r.trajectory.iter().filter(|p| p.state.t > ev.t) {
        assert_eq!(p.stage, Stage::Ride);
        assert_eq!(p.state.vx, 2.0);
    }
}

/// Sliding straight across the belt: y(t) = y0 + u t − μ g t²/2 reaches P_max at a known
/// time; the exit event and the verdict follow.
#[test]
fn exit_event_matches_the_analytic_crossing() {
    let mut s = free_scenario(DVec2::new(0.0, 2.5), 0.0, 1e-10);
    s.machine.belt_width = 0.7;
    s.parcel.offset = 0.05;
    let r = simulate(&s);
    assert_eq!(r.outcome, Outcome::Diverted);
    let y0 = r.trajectory[0].state.y;
    let (u, a) = (2.5, 0.4 * GRAVITY);
    let t_exit = (u - (u * u - 2.0 * a * (0.7 - y0)).sqrt()) / a;
    let ev = r.events.iter().find(|e| e.kind == EventKind::Exit).unwrap();
    assert_relative_eq!(ev.t, t_exit, epsilon = 1e-9);
    assert_relative_eq!(r.final_state.y, 0.7, epsilon = 1e-9);
    assert!(r.max_lateral >= 0.7 - 1e-9);
}

/// Riding from the start: a parcel at belt speed stays riding and is left on the belt.
#[test]
fn a_riding_parcel_stays_riding() {
    let mut s = Scenario::paper_default();
    s.run.arm = false;
    let r = simulate(&s);
    assert_eq!(r.stages, vec![Stage::Ride]);
    let first = r.trajectory[0].state;
    assert_relative_eq!(
        r.final_state.x - first.x,
        2.0 * s.run.duration,
        epsilon = 1e-12
    );
}

#[test]
fn same_input_gives_bitwise_same_output() {
    let s = free_scenario(DVec2::new(0.7, -0.3), 2.0, 1e-9);
    assert_eq!(simulate(&s), simulate(&s));
}

#[test]
fn seed_friction_law_also_slides_to_rest() {
    let mut s = free_scenario(DVec2::new(1.0, 0.0), 3.0, 1e-9);
    s.materials.friction_model = FrictionModel::Seed;
    let r = simulate(&s);
    assert_eq!(r.stages, vec![Stage::F2, Stage::Ride]);
    // Pure translation part is the same law: stop no earlier than v/(μg).
    let t = r
        .events
        .iter()
        .find(|e| e.kind == EventKind::RideStart)
        .unwrap()
        .t;
    assert!(t > 1.0 / (0.4 * GRAVITY));
}

/// Kinetic energy relative to the belt, ½m|v_r|² + ½Iω².
fn relative_energy(s: &Scenario, p: &divertsim_core::sim::State) -> f64 {
    let vr = DVec2::new(p.vx - s.machine.belt_speed, p.vy);
    0.5 * s.parcel.mass * vr.length_squared() + 0.5 * s.inertia() * p.omega * p.omega
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, rng_seed: RngSeed::Fixed(0xD1E5), .. ProptestConfig::default() })]

    /// Friction only dissipates: the relative kinetic energy never grows along a free
    /// slide; every slide ends riding, with finite states, before a generous bound.
    #[test]
    fn free_slides_dissipate_and_end_riding(
        vx in -2.0f64..2.0, vy in -2.0f64..2.0, omega in -8.0f64..8.0,
        a in 0.1f64..0.7, b in 0.05f64..0.4, mu in 0.1f64..0.8, phi in -3.1f64..3.1,
    ) {
        let mut s = free_scenario(DVec2::new(vx, vy), omega, 1e-8);
        s.parcel.length = a;
        s.parcel.width = b;
        s.parcel.angle = phi;
        // A slide of at most |v_r|²/(2 μ g) ≈ 4.1 m each way stays on the 10 m belt.
        s.parcel.offset = 5.0;
        s.materials.belt_friction = FrictionCoefficient::Constant(mu);
        s.run.duration = 5.0;
        let r = simulate(&s);
        prop_assert!(matches!(r.outcome, Outcome::NotDiverted(NotDivertedReason::LeftOnBelt)), "{:?}", r.outcome);
        let mut last = f64::INFINITY;
        for p in &r.trajectory {
            let st = p.state;
            prop_assert!([st.x, st.y, st.phi, st.vx, st.vy, st.omega].iter().all(|v| v.is_finite()));
            let e = relative_energy(&s, &st);
            prop_assert!(e <= last * (1.0 + 1e-9) + 1e-12, "energy grew {} -> {}", last, e);
            last = e;
        }
    }
}

/// The reference slides of docs/model.md §4 at the default tolerance (1e-8), where the end of
/// the slide is taken in steps scaled with the time left and closed at 1e-7 m/s of slip (also
/// docs/model.md §4): still within 1e-5 relative of the converged values.
#[test]
fn dynamic_oracles_at_the_default_tolerance() {
    let rows = [
        (
            DVec2::new(1.0, 0.0),
            3.0,
            0.2876557250,
            DVec2::new(0.1381955570, -0.0016809947),
            27.7658963667,
        ),
        (
            DVec2::new(0.5, 0.5),
            -4.0,
            0.2558383887,
            DVec2::new(0.0588478600, 0.0636685321),
            -30.7525591527,
        ),
        (
            DVec2::new(0.0, 0.0),
            3.0,
            0.1133017394,
            DVec2::new(0.0, 0.0),
            9.7375704651,
        ),
    ];
    for (v_rel, omega, t_ref, d_ref, rot_ref) in rows {
        let s = free_scenario(v_rel, omega, 1e-8);
        let r = simulate(&s);
        let (t, d, rot) = stop_of(&s, &r);
        assert_relative_eq!(t, t_ref, max_relative = 1e-5);
        assert_relative_eq!(d.x, d_ref.x, max_relative = 1e-5, epsilon = 1e-9);
        assert_relative_eq!(d.y, d_ref.y, max_relative = 1e-5, epsilon = 1e-9);
        assert_relative_eq!(rot, rot_ref, max_relative = 1e-5, epsilon = 1e-7);
        assert_eq!(r.stages, vec![Stage::F2, Stage::Ride]);
        // The closed end leaves the parcel exactly riding.
        assert_eq!(
            (r.final_state.vx, r.final_state.vy, r.final_state.omega),
            (2.0, 0.0, 0.0)
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, rng_seed: RngSeed::Fixed(0x5107), .. ProptestConfig::default() })]

    /// The end of a slide converges with the tolerance: stop time, displacement and
    /// rotation at rtol 1e-8 agree with rtol 1e-11 to 1e-6 relative (or 1e-10 s, 1e-7 m,
    /// 1e-6 rad absolute: the global error of rtol 1e-8 reaches ~2e-8 m), for any slip
    /// direction, spin and footprint.
    #[test]
    fn slide_ends_converge_with_the_tolerance(
        vx in -1.5f64..1.5, vy in -1.5f64..1.5, omega in -8.0f64..8.0,
        a in 0.1f64..0.7, b in 0.05f64..0.4, phi in -3.1f64..3.1,
    ) {
        let run = |tol: f64| {
            let mut s = free_scenario(DVec2::new(vx, vy), omega, tol);
            s.parcel.length = a;
            s.parcel.width = b;
            s.parcel.angle = phi;
            s.parcel.offset = 1.0;
            let r = simulate(&s);
            stop_of(&s, &r)
        };
        let (t, d, rot) = run(1e-8);
        let (t_ref, d_ref, rot_ref) = run(1e-11);
        let close = |x: f64, y: f64, abs: f64| (x - y).abs() <= abs.max(1e-6 * y.abs());
        prop_assert!(close(t, t_ref, 1e-10), "t {} vs {}", t, t_ref);
        prop_assert!(close(d.x, d_ref.x, 1e-7), "x {} vs {}", d.x, d_ref.x);
        prop_assert!(close(d.y, d_ref.y, 1e-7), "y {} vs {}", d.y, d_ref.y);
        prop_assert!(
            close(rot.to_radians(), rot_ref.to_radians(), 1e-6),
            "rot {} vs {}",
            rot,
            rot_ref
        );
    }
}
