//! The arm's side of whole runs (issue 26; docs/model.md §12b): a stroke that touches
//! nothing demands the arm's inertia torque alone and no net work, and a stroke that
//! diverts a parcel does work on it.

use divertsim_core::model::drive::ArmDrive;
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::{simulate, simulate_verdict, NotDivertedReason, Outcome};

/// A parcel lower than the arm's face: the arm swings over it, I_arm α̈ is all it needs.
#[test]
fn a_stroke_over_a_low_parcel_demands_the_arms_inertia_alone() {
    let mut s = Scenario::paper_default();
    s.parcel.height = 0.05;
    s.machine.arm_face_bottom = 0.08;
    s.machine.arm_inertia = 4.0;
    let r = simulate(&s);
    assert_eq!(r.outcome, Outcome::NotDiverted(NotDivertedReason::UnderArm));
    let loads = r.arm_loads(&s).expect("an arm");
    let d = ArmDrive::new(&s.machine.drive, s.machine.cycle_time).unwrap();
    let n = 100_000;
    let peak = (0..=n)
        .map(|k| (4.0 * d.state(s.machine.cycle_time * k as f64 / n as f64).accel).abs())
        .fold(0.0, f64::max);
    assert!(
        (loads.peak_torque - peak).abs() < 1e-3 * peak,
        "{loads:?}, {peak}"
    );
    assert_eq!(loads.peak_contact_torque, 0.0);
    assert!(loads.energy.abs() < 1e-6 * peak, "{loads:?}");
    assert!(loads.rms_torque > 0.0 && loads.rms_torque < loads.peak_torque);
}

/// The default parcel, struck and pushed off: the drive does positive work on it, the
/// strikes load the arm, and a massless arm's peak drive torque is the parcel's. The
/// figures are the same with and without the trajectory.
#[test]
fn a_divert_costs_the_drive_work_and_loads_the_arm() {
    let s = Scenario::paper_default();
    let r = simulate(&s);
    assert_eq!(r.outcome, Outcome::Diverted);
    let loads = r.arm_loads(&s).expect("an arm");
    assert!(loads.energy > 0.0, "{loads:?}");
    assert!(loads.max_strike_angular_impulse > 0.0);
    assert_eq!(loads.peak_torque, loads.peak_contact_torque);
    assert_eq!(Some(loads), simulate_verdict(&s).arm_loads(&s));
    // The arm's own inertia adds its torque.
    let mut heavy = s.clone();
    heavy.machine.arm_inertia = 5.0;
    let h = simulate(&heavy).arm_loads(&heavy).unwrap();
    assert!(h.peak_torque > loads.peak_torque && h.rms_torque > loads.rms_torque);
    // No arm, no loads.
    let mut free = s;
    free.run.arm = false;
    assert_eq!(simulate(&free).arm_loads(&free), None);
}
