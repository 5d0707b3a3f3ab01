//! Regression tests of the issue "Contacts that hold": the four faults of contact-pair
//! selection and of the event/force law, each with its reproducer, plus the issue's
//! acceptance cases (flush parcels without strikes on both machines, fig06's release).

use divertsim_core::model::belt_friction::FrictionCoefficient;
use divertsim_core::model::params::{NearSide, Scenario};
use divertsim_core::sim::{simulate, EventKind, NotDivertedReason, Outcome, SimResult, Stage};
use glam::DVec2;

/// The paper preset's machine (configs/paper/machine.toml): R_z 1.15 m, μ_b 0.5, μ_a 0.38.
fn preset() -> Scenario {
    Scenario::paper_machine()
}

fn flush(mut s: Scenario, (a, b, m): (f64, f64, f64), v: f64) -> Scenario {
    s.parcel.length = a;
    s.parcel.width = b;
    s.parcel.mass = m;
    s.parcel.offset = 0.0;
    s.parcel.angle = 0.0;
    s.machine.start_position = 0.8; // lying on the retracted arm
    s.machine.belt_speed = v;
    s.run.duration = s.machine.cycle_time + 2.0;
    s
}

fn assert_no_strike(r: &SimResult, what: &str) {
    assert!(
        !matches!(r.outcome, Outcome::Failed(_)),
        "{what}: {:?}",
        r.outcome
    );
    assert!(
        r.impacts.is_empty(),
        "{what}: struck {} times, first at t = {} with {} m/s; stages {:?}",
        r.impacts.len(),
        r.impacts[0].t,
        r.impacts[0].approach_speed,
        r.stages
    );
    assert_eq!(r.stages[0], Stage::F5, "{what}: {:?}", r.stages);
    assert!(!r.stages.contains(&Stage::F1), "{what}: {:?}", r.stages);
}

/// Fault 1, the reproducer: a 0.4 × 0.26 parcel flush on the arm slides over the tip. It
/// used to be struck at t ≈ 0.1025 s on its leading face (S = 0.556 S_fall) although the tip
/// only begins to support the face lying on the arm.
#[test]
fn false_strike_when_sliding_off_the_tip() {
    let mut s = Scenario::paper_default();
    s.parcel.offset = 0.0;
    s.parcel.length = 0.4;
    s.machine.start_position = 0.8;
    let r = simulate(&s);
    assert_no_strike(&r, "reproducer");
    // The tip takes over the face on the arm: the contact continues past the tip.
    assert!(
        r.stages.contains(&Stage::ArmTip),
        "no hand-off to the tip: {:?}",
        r.stages
    );
}

/// Fault 1, the acceptance sweep: a flush parcel (ΔP = 0, φ = 0) of each paper size, at
/// belt speeds from 0.65 to 2.3 m/s, on the default machine and on the paper preset, is
/// never struck: the stages start with F5 and contain no F1.
#[test]
fn flush_parcels_slide_over_the_tip_without_a_strike() {
    let sizes = [(0.2, 0.1, 0.5), (0.7, 0.1, 1.5), (0.4, 0.26, 3.0)];
    for (name, machine) in [("default", Scenario::paper_default()), ("preset", preset())] {
        for size in sizes {
            for k in 0..=11 {
                let v = 0.65 + 0.15 * f64::from(k);
                let r = simulate(&flush(machine.clone(), size, v));
                assert_no_strike(&r, &format!("{name} {size:?} v = {v}"));
            }
        }
    }
}

/// Fault 2: on the return stroke the receding arm used to pull the slender parcel of fig06
/// (λ_n down to −96 N, kinetic energy from 0.32 to 10.4 J), strike it at 1.17 s and leave it
/// at y = 0.43 m. With one force law it lets go at about 0.81 s, is never struck after the
/// arm's largest swing, and rides on within 0.01 m of its peak lateral position.
#[test]
fn receding_arm_pulls_the_parcel() {
    let mut s = flush(preset(), (0.7, 0.1, 1.5), 0.65);
    s.machine.cycle_time = 1.36;
    s.run.duration = 3.36;
    let r = simulate(&s);
    assert_eq!(
        r.outcome,
        Outcome::NotDiverted(NotDivertedReason::LeftOnBelt),
        "{:?}",
        r.stages
    );
    let half = 0.5 * s.machine.cycle_time;
    assert!(
        r.impacts.iter().all(|i| i.t < half),
        "struck after the largest swing: {:?}",
        r.impacts.iter().map(|i| i.t).collect::<Vec<_>>()
    );
    let release = r
        .events
        .iter()
        .filter(|e| e.kind == EventKind::RideStart)
        .map(|e| e.t)
        .next()
        .expect("rides");
    assert!((release - 0.81).abs() < 0.01, "rides from {release} s");
    assert!(
        (r.final_state.y - r.max_lateral).abs() < 0.01,
        "final y {} vs peak {}",
        r.final_state.y,
        r.max_lateral
    );
    assert!(
        r.contact_check.min_normal_force >= -1e-7,
        "{:?}",
        r.contact_check
    );
}

/// Fault 3: a parcel pushed off the open pivot-side edge downstream of the pivot ends the
/// run (`off_near_side`); with `near_side = guide` the guide holds it instead.
#[test]
fn a_parcel_pushed_off_the_pivot_side_edge() {
    let mut s = Scenario::paper_default();
    s.parcel.velocity = Some(DVec2::new(2.0, -1.0));
    s.machine.start_position = 0.5;
    s.run.arm = false;
    s.materials.belt_friction = FrictionCoefficient::Constant(0.1);
    let r = simulate(&s);
    assert_eq!(
        r.outcome,
        Outcome::NotDiverted(NotDivertedReason::OffNearSide)
    );
    assert_eq!(
        r.events.last().map(|e| e.kind),
        Some(EventKind::OffNearSide)
    );
    assert!(r.final_state.y.abs() < 1e-9, "{:?}", r.final_state);

    s.machine.near_side = NearSide::Guide;
    let r = simulate(&s);
    assert_eq!(
        r.outcome,
        Outcome::NotDiverted(NotDivertedReason::LeftOnBelt)
    );
    assert!(r.stages.contains(&Stage::Guide), "{:?}", r.stages);
    let lowest = r
        .trajectory
        .iter()
        .map(|p| p.state.y)
        .fold(f64::INFINITY, f64::min);
    // The parcel's centre stays half its width above the guide.
    assert!(
        lowest > 0.5 * s.parcel.width - 1e-6,
        "centre down to y = {lowest}"
    );
}

/// Fault 4: valid scenarios that failed. Each reproducer of the issue, on the built-in
/// default, now runs to a verdict with finite figures.
#[test]
fn valid_scenarios_that_failed() {
    let base = Scenario::paper_default;
    let mut cases = Vec::new();
    // A parcel at rest touching the retracted arm at t = 0, frictionless arm.
    let mut s = base();
    s.machine.belt_speed = 0.0;
    s.machine.arm_length = 1.1;
    s.machine.start_position = 1.2;
    s.parcel.width = 0.1;
    s.parcel.angle = 1f64.to_radians();
    s.parcel.offset = 0.0;
    s.materials.arm_friction = 0.0;
    cases.push(s);
    // A tall parcel across a 84° swing, e* = 0, μ_a = 1.
    let mut s = base();
    s.machine.arm_length = 0.8;
    s.machine.cycle_time = 6.6;
    s.machine.drive = divertsim_core::model::drive::DriveSpec::CrankRocker(
        divertsim_core::model::drive::FourBar::centred(84f64.to_radians(), 0.3, 0.15),
    );
    s.parcel.length = 0.1;
    s.parcel.width = 1.0;
    s.parcel.angle = 90f64.to_radians();
    s.parcel.offset = 0.0;
    s.materials.arm_friction = 1.0;
    s.materials.restitution = 0.0;
    cases.push(s);
    // Spinning fast on a frictionless, still belt for 29 s.
    let mut s = base();
    s.machine.belt_speed = 0.0;
    s.machine.start_position = 2.0;
    s.parcel.offset = 0.0;
    s.parcel.spin = 74.0;
    s.materials.belt_friction = FrictionCoefficient::Constant(0.0);
    s.run.duration = 29.0;
    cases.push(s);
    // An hour of frictionless sliding: the step budget follows the duration.
    let mut s = base();
    s.run.arm = false;
    s.run.duration = 3600.0;
    s.materials.belt_friction = FrictionCoefficient::Constant(0.0);
    s.parcel.velocity = Some(DVec2::new(2.5, 0.0));
    cases.push(s);
    for (i, s) in cases.iter().enumerate() {
        let r = simulate(s);
        assert!(
            !matches!(r.outcome, Outcome::Failed(_)),
            "case {i}: {:?}",
            r.outcome
        );
        let o = r.overload;
        for v in [
            o.max_impulse,
            o.overload_ratio,
            o.energy_ratio,
            o.equivalent_drop_height,
            r.max_lateral,
        ] {
            assert!(v.is_finite(), "case {i}: {o:?}");
        }
    }
}

/// A corner at the arm's root as the arm starts from rest (the paper's Fig. 8 case: the
/// slender parcel at ΔP = 0, R_s = 0) is pushed from t = 0 (F6). It used to ride first and be
/// met 0.46 ms later by a 7 µm/s "strike", labelled F1.
#[test]
fn a_corner_at_the_arm_root_is_pushed_from_the_start() {
    let mut s = flush(preset(), (0.7, 0.1, 1.5), 2.0);
    s.machine.start_position = 0.0;
    let r = simulate(&s);
    assert_eq!(r.outcome, Outcome::Diverted, "{:?}", r.stages);
    assert_eq!(r.stages[0], Stage::F6, "{:?}", r.stages);
    assert!(r.impacts[0].t > 0.3, "first strike at {} s", r.impacts[0].t);
}

/// Every input at the edges of the validated ranges runs to a verdict (never `failed`) with
/// finite figures: the smallest parcel and mass, the fastest cycle, the fastest belt, the
/// largest spin and initial velocities, the extreme tolerances, the shortest and longest
/// arms, the frictions' and restitution's ends, the heaviest parcel against the smallest
/// drop reference, and the largest swing at the fastest cycle.
#[test]
fn valid_inputs_at_the_range_edges_run_to_a_verdict() {
    type Edit = fn(&mut Scenario);
    let edits: [(&str, Edit); 16] = [
        ("smallest parcel", |s| {
            s.parcel.length = 1e-3;
            s.parcel.width = 1e-3;
            s.parcel.mass = 1e-3;
        }),
        ("fastest cycle", |s| s.machine.cycle_time = 0.1),
        ("fastest cycle at the edge", |s| {
            s.machine.cycle_time = 0.1;
            s.parcel.offset = 0.0;
        }),
        ("fastest belt", |s| s.machine.belt_speed = 20.0),
        ("largest spin", |s| s.parcel.spin = 100.0),
        ("largest spin at the edge", |s| {
            s.parcel.spin = -100.0;
            s.parcel.offset = 0.0;
        }),
        ("fast towards the far side", |s| {
            s.parcel.velocity = Some(DVec2::new(20.0, 20.0))
        }),
        ("fast towards the guide", |s| {
            s.parcel.velocity = Some(DVec2::new(-20.0, -20.0))
        }),
        ("tightest tolerance", |s| s.run.tolerance = 1e-12),
        ("loosest tolerance", |s| s.run.tolerance = 1e-4),
        ("shortest arm", |s| s.machine.arm_length = 0.01),
        ("longest arm", |s| {
            s.machine.arm_length = 10.0;
            s.machine.belt_width = 10.0;
        }),
        ("roughest, most elastic arm", |s| {
            s.materials.arm_friction = 1.3;
            s.materials.restitution = 1.0;
        }),
        ("frictionless plastic arm, flush", |s| {
            s.materials.arm_friction = 0.0;
            s.materials.restitution = 0.0;
            s.parcel.offset = 0.0;
            s.machine.start_position = 0.8;
        }),
        ("heaviest parcel, smallest drop", |s| {
            s.parcel.mass = 1000.0;
            s.limits.drop_height = 1e-3;
        }),
        ("largest swing, fastest cycle", |s| {
            s.machine.drive = divertsim_core::model::drive::DriveSpec::CrankRocker(
                divertsim_core::model::drive::FourBar::centred(90f64.to_radians(), 0.3, 0.15),
            );
            s.machine.cycle_time = 0.1;
        }),
    ];
    for (name, edit) in edits {
        let mut s = Scenario::paper_default();
        edit(&mut s);
        s.run.duration = s.machine.cycle_time + 2.0;
        let r = simulate(&s);
        assert!(
            !matches!(r.outcome, Outcome::Failed(_)),
            "{name}: {:?}",
            r.outcome
        );
        let o = r.overload;
        let f = r.final_state;
        for v in [
            o.max_impulse,
            o.fall_impulse,
            o.overload_ratio,
            o.energy_ratio,
            o.equivalent_drop_height,
            o.arm_max_impulse,
            o.arm_total_impulse,
            r.max_lateral,
            f.x,
            f.y,
            f.phi,
            f.vx,
            f.vy,
            f.omega,
        ] {
            assert!(v.is_finite(), "{name}: {o:?} {f:?}");
        }
    }
}
