//! The arm's cycles at any times (`run.cycle_starts`): a run is the same physics wherever its
//! cycle starts, and the cycles of a line add strokes without changing the one before.

use divertsim_core::model::params::Scenario;
use divertsim_core::sim::{simulate, Outcome};

/// The paper's run with the arm's cycle at `delay` and the parcel v·delay further upstream:
/// the same run, `delay` later.
fn delayed(delay: f64) -> Scenario {
    let mut s = Scenario::paper_machine();
    s.machine.start_position -= s.machine.belt_speed * delay;
    s.run.cycle_starts = vec![delay];
    s.run.duration += delay;
    s
}

#[test]
fn a_cycle_started_later_is_the_same_run_later() {
    let base = simulate(&Scenario::paper_machine());
    assert_eq!(base.outcome, Outcome::Diverted);
    for delay in [0.25, 1.0, 3.7] {
        let r = simulate(&delayed(delay));
        assert_eq!(r.outcome, base.outcome);
        assert_eq!(r.impacts.len(), base.impacts.len());
        for (a, b) in r.impacts.iter().zip(&base.impacts) {
            assert!(
                (a.t - delay - b.t).abs() < 1e-6,
                "{} vs {}",
                a.t - delay,
                b.t
            );
            assert!((a.impulse - b.impulse).abs() < 1e-6 * b.impulse);
        }
        let (f, g) = (r.final_state, base.final_state);
        assert!((f.t - delay - g.t).abs() < 1e-6 && (f.y - g.y).abs() < 1e-6);
        assert_eq!(r.stages, base.stages);
    }
}

#[test]
fn a_cycle_under_way_at_the_start_is_the_rest_of_that_cycle() {
    // Started 0.5 s before t = 0: the arm is out when the run begins; a parcel still far
    // upstream then meets the arm's state α(t + 0.5).
    let mut s = Scenario::paper_machine();
    s.machine.start_position = -1.5;
    s.run.cycle_starts = vec![-0.5];
    let r = simulate(&s);
    let arm = r.trajectory.first().unwrap().arm_angle;
    let one = Scenario::paper_machine();
    let drive =
        divertsim_core::model::drive::ArmDrive::new(&one.machine.drive, one.machine.cycle_time)
            .unwrap();
    assert!((arm - drive.state(0.5).angle).abs() < 1e-12);
    // It ends when that cycle does: no arm start is recorded.
    assert!(r
        .events
        .iter()
        .all(|e| e.kind != divertsim_core::sim::EventKind::ArmStart));
}

#[test]
fn a_second_cycle_after_the_parcel_has_gone_changes_nothing() {
    let base = simulate(&Scenario::paper_machine());
    let mut s = Scenario::paper_machine();
    s.run.cycle_starts = vec![0.0, 5.0];
    s.run.duration = 8.0;
    let r = simulate(&s);
    assert_eq!(r.outcome, base.outcome);
    assert_eq!(r.impacts, base.impacts);
    assert_eq!(r.final_state, base.final_state);
}

#[test]
fn overlapping_or_empty_cycles_are_a_failed_run_not_a_panic() {
    for starts in [vec![], vec![0.0, 1.0], vec![f64::NAN]] {
        let mut s = Scenario::paper_machine();
        s.run.cycle_starts = starts.clone();
        let r = simulate(&s);
        assert!(
            matches!(&r.outcome, Outcome::Failed(m) if m.contains("run.cycle_starts")),
            "{starts:?}: {:?}",
            r.outcome
        );
    }
}
