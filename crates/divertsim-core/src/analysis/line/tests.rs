//! The line's named tests: a parcel struck on the return stroke (checked in closed form), a
//! colliding pair, two diverters in a row, and the determinism of segments.

use super::controller::Decision;
use super::flow;
use super::passage::{self, Motion};
use super::stream::Arrival;
use super::*;
use crate::analysis::population::mix::{Draw, MassLaw, Placement, Sizes};
use crate::model::drive::ArmDrive;
use crate::run::study::{execute_quietly, Study, Unkept};
use crate::run::sweep::{no_progress, one_and_many_threads};
use crate::sim::arm_loads::StrokeProfile;
use crate::stats::distribution::Distribution;
use glam::DVec2;

/// A mix of paper-like parcels (also the log's tests').
pub(super) fn mix() -> ParcelMix {
    ParcelMix {
        sizes: Sizes::Drawn {
            length: Distribution::Uniform { min: 0.2, max: 0.5 },
            width: Distribution::Uniform {
                min: 0.1,
                max: 0.26,
            },
            height: Distribution::Fixed(0.1),
        },
        mass: MassLaw::Mass(Distribution::Uniform {
            min: 0.5,
            max: 15.0,
        }),
        placement: Placement::RoomFraction(Distribution::Uniform { min: 0.0, max: 1.0 }),
        angle: Distribution::Normal { mean: 0.0, sd: 0.1 },
        speed: Distribution::Fixed(0.0),
        spin: Distribution::Fixed(0.0),
        phase: Distribution::Fixed(0.0),
        belt_friction: None,
        arm_friction: None,
        restitution: None,
    }
}

pub(super) fn diverter(position: f64, share: f64) -> Diverter {
    Diverter {
        position,
        setting: Scenario::paper_machine(),
        trigger: StartRule::Fixed,
        share,
        changes: Default::default(),
        table: Default::default(),
    }
}

pub(super) fn line(diverters: Vec<Diverter>, gap: f64) -> Line {
    Line {
        diverters,
        induction: Induction::Gaps {
            gap: Distribution::Fixed(gap),
            min: 0.0,
        },
        mix: mix(),
        busy: BusyRule::Skip,
        duration_given: false,
    }
}

/// The paper's compact parcel (0.4 × 0.26 m, 3 kg) at ΔP, φ = 0, riding.
pub(super) fn compact(index: u64, offset: f64) -> Draw {
    Draw {
        index,
        length: 0.4,
        width: 0.26,
        height: 0.15,
        mass: 3.0,
        offset,
        angle: 0.0,
        speed: 0.0,
        spin: 0.0,
        phase: 0.0,
        belt_friction: None,
        arm_friction: 0.38,
        restitution: 0.3,
        rejected: [0; 5],
    }
}

fn arrival(draw: Draw, time: f64, destination: Option<usize>) -> Arrival {
    Arrival {
        draw,
        time,
        headway: 1.0,
        destination,
    }
}

/// Whether the arm segment O→R_z(cos α, sin α) and a footprint intersect: the separating-axis
/// test with the segment as a degenerate polygon (closed form, no simulation).
fn arm_meets(rz: f64, alpha: f64, corners: &[DVec2; 4]) -> bool {
    let tip = rz * DVec2::new(alpha.cos(), alpha.sin());
    let seg = [DVec2::ZERO, tip];
    let e0 = corners[1] - corners[0];
    let e1 = corners[3] - corners[0];
    let axes = [
        DVec2::new(-e0.y, e0.x),
        DVec2::new(-e1.y, e1.x),
        DVec2::new(-tip.y, tip.x),
    ];
    axes.iter().all(|&n| {
        let (a0, a1) = seg
            .iter()
            .map(|p| p.dot(n))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p), h.max(p))
            });
        let (b0, b1) = corners
            .iter()
            .map(|p| p.dot(n))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p), h.max(p))
            });
        a1 >= b0 && b1 >= a0
    })
}

/// The first time in [0, t_c] at which the arm of `setting` (one cycle from t = 0) meets a
/// parcel that rides with its front at the pivot at `front_time`, scanned every 10 µs.
fn first_meeting(setting: &Scenario, draw: &Draw, front_time: f64) -> Option<f64> {
    let m = &setting.machine;
    let drive = ArmDrive::new(&m.drive, m.cycle_time).unwrap();
    let came = passage::inducted(&arrival(*draw, front_time, None), m.belt_speed);
    let rect = crate::geometry::Rect {
        length: draw.length,
        width: draw.width,
    };
    (0..=(m.cycle_time / 1e-5) as usize)
        .map(|k| k as f64 * 1e-5)
        .find(|&t| {
            let (c, phi) = came.riding_pose(&rect, m.belt_speed, t);
            arm_meets(m.arm_length, drive.state(t).angle, &rect.corners(c, phi))
        })
}

#[test]
fn second_parcel_arriving_during_the_return_stroke_is_struck() {
    let l = line(vec![diverter(0.0, 1.0)], 1.0);
    let setting = &l.diverters[0].setting;
    let t_out = ArmDrive::new(&setting.machine.drive, setting.machine.cycle_time)
        .unwrap()
        .out_stroke_time();
    // The first parcel is bound here (its cycle starts at t = 0, R_s = 0); the second, bound
    // straight through, comes 0.75 s later, near the pivot side.
    let second = compact(1, 0.05);
    let meets = first_meeting(setting, &second, 0.75).expect("the arm reaches it");
    assert!(
        meets > t_out && meets < setting.machine.cycle_time,
        "closed form: the arm meets it at {meets} s, not on the return stroke ({t_out} s on)"
    );
    let seg = flow::run_stream(
        &l,
        &[
            arrival(compact(0, 0.22), 0.0, Some(0)),
            arrival(second, 0.75, None),
        ],
    );
    let p = &seg.parcels[1];
    assert_eq!(p.struck, 1, "{p:?}");
    assert!(
        matches!(
            p.outcome,
            LineOutcome::StruckInPassing | LineOutcome::WronglyDiverted
        ),
        "{p:?}"
    );
    // Its run meets the arm where the closed form says: the first strike of the run.
    let run = l.scenario_of(p).expect("a deciding run");
    let r = crate::sim::simulate(&run);
    let first = r.impacts.first().expect("a strike").t + p.run.as_ref().unwrap().time_origin;
    assert!(
        (first - meets).abs() < 2e-5,
        "strike at {first} s, closed form {meets} s"
    );
    assert_eq!(seg.cycles, vec![1]);
}

#[test]
fn a_parcel_no_cycle_can_reach_costs_no_simulation() {
    // Bound straight through, 3 s after the one cycle: never simulated, passed.
    let l = line(vec![diverter(0.0, 1.0)], 1.0);
    let seg = flow::run_stream(
        &l,
        &[
            arrival(compact(0, 0.22), 0.0, Some(0)),
            arrival(compact(1, 0.22), 3.0, None),
        ],
    );
    assert_eq!(seg.simulations, 1);
    assert_eq!(seg.parcels[0].outcome, LineOutcome::Diverted);
    assert_eq!(seg.parcels[1].outcome, LineOutcome::Passed);
    assert!(seg.parcels[1].run.is_none());
}

#[test]
fn overlapping_pair_is_a_collision() {
    // A parcel pushed across the belt slows along it; the next one, 2 cm behind and
    // bound straight through, runs into it.
    let l = line(vec![diverter(0.0, 1.0)], 1.0);
    let (lead, follow) = (compact(0, 0.3), compact(1, 0.3));
    let headway = (0.4 + 0.02) / 2.0;
    let seg = flow::run_stream(
        &l,
        &[arrival(lead, 0.0, Some(0)), arrival(follow, headway, None)],
    );
    for (p, other) in seg.parcels.iter().zip([1, 0]) {
        assert_eq!(p.outcome, LineOutcome::Collision, "{p:?}");
        let c = p.collision.expect("where and when");
        assert_eq!(c.other, other);
        assert!(
            c.depth > neighbours::OVERLAP_TOL && c.time > 0.0 && c.time < 2.0,
            "{c:?}"
        );
    }
    // Two parcels inducted on top of each other collide at once, without any arm.
    let seg = flow::run_stream(
        &l,
        &[
            arrival(compact(0, 0.1), 0.0, None),
            arrival(compact(1, 0.1), 0.1, None),
        ],
    );
    assert!(seg
        .parcels
        .iter()
        .all(|p| p.outcome == LineOutcome::Collision));
    assert_eq!(seg.simulations, 0);
}

#[test]
fn two_diverters_split_fifty_fifty_feed_and_add_up() {
    let l = line(vec![diverter(0.0, 0.5), diverter(4.0, 0.5)], 3.0);
    let seg = run_segment(&l, 7, 0..200).unwrap();
    let mut tally = tally::LineTally::new(2);
    tally.add(&seg);
    assert_eq!(tally.parcels, 200);
    assert!(
        tally.diverters.iter().all(|d| d.bound > 60),
        "{:?}",
        tally.diverters
    );
    // The line's throughput is the sum of the diverters'.
    let sum = tally.throughput(0) + tally.throughput(1);
    assert!((tally.line_throughput() - sum).abs() <= 1e-9 * sum);
    // Every parcel bound for the second diverter came to it past the first (a run of the
    // first's states into the second is checked in the next test), unless the first
    // diverted it or it collided there.
    let mut second = 0;
    for p in seg.parcels.iter().filter(|p| p.destination == Some(1)) {
        match p.outcome {
            LineOutcome::WronglyDiverted | LineOutcome::Collision => {}
            _ => {
                assert_eq!(p.decided_at, Some(1), "{p:?}");
                second += 1;
            }
        }
    }
    assert!(second > 60);
    assert_eq!(
        u64::from(seg.cycles[1]),
        tally.diverters[1].bound - tally.diverters[1].busy
    );
}

#[test]
fn a_struck_parcel_comes_to_the_next_diverter_as_it_left_the_first() {
    // The return-stroke parcel of the first test, now bound for a second diverter 4 m on,
    // whose short arm (0.5 m) cannot divert it: a failure keeps its deciding run.
    let mut short = diverter(4.0, 0.5);
    short.setting.machine.arm_length = 0.5;
    let l = line(vec![diverter(0.0, 0.5), short], 1.0);
    let (lead, second) = (compact(0, 0.22), compact(1, 0.05));
    let arrivals = [arrival(lead, 0.0, Some(0)), arrival(second, 0.75, Some(1))];
    let seg = flow::run_stream(&l, &arrivals);
    let p = &seg.parcels[1];
    assert_eq!(p.struck, 1, "{p:?}");
    assert!(matches!(p.outcome, LineOutcome::NotDiverted(_)), "{p:?}");
    let at_second = p
        .run
        .as_ref()
        .filter(|r| r.diverter == 1)
        .expect("run at the second");
    // Its passage at the first diverter, alone: the arm's one cycle at t = 0.
    let came = passage::inducted(&arrivals[1], l.belt_speed());
    let first = passage::pass(
        &l,
        0,
        &[0.0],
        Decision::NotBound,
        &arrivals[1],
        (came, crate::sim::Recording::VerdictOnly),
    )
    .expect("simulated at the first");
    let after = first.after.expect("still on the belt");
    match after.motion {
        Motion::Moving { time, state } => {
            assert_eq!(at_second.time_origin, time);
            assert_eq!(
                at_second.run.parcel.velocity,
                Some(DVec2::new(state[3], state[4]))
            );
            assert_eq!(at_second.run.parcel.spin, state[5]);
            // Its front, 4 m further on in the second diverter's frame.
            let rect = crate::geometry::Rect {
                length: 0.4,
                width: 0.26,
            };
            let front = rect
                .corners(DVec2::new(state[0], state[1]), state[2])
                .iter()
                .fold(f64::NEG_INFINITY, |m, c| m.max(c.x));
            assert!((at_second.run.start_position - (front - 4.0)).abs() < 1e-12);
        }
        Motion::Riding => {
            assert_eq!(
                (at_second.run.parcel.offset, at_second.run.parcel.angle),
                (after.offset, after.angle)
            );
            let v = l.belt_speed();
            let x0 = at_second.run.start_position;
            assert!((at_second.time_origin - (after.front_time + 4.0 / v + x0 / v)).abs() < 1e-9);
        }
    }
}

#[test]
fn segments_are_the_same_for_any_thread_count() {
    let l = line(vec![diverter(0.0, 0.5), diverter(4.0, 0.3)], 0.6);
    let study = |batch| study::LineSegments {
        batch,
        ..study::LineSegments::new(&l, 3, 90, 30)
    };
    let run = |batch| {
        execute_quietly(&study(batch), study::LineRun::new(2, 3), &Unkept)
            .unwrap()
            .tally
    };
    let (one, many) = one_and_many_threads(|| run(3));
    assert_eq!(one, many);
    assert_eq!(run(1), one);
    assert_eq!(one.tally.parcels, 90);
    // And a segment alone is the segment in the run (the stream's head is kept whole).
    assert_eq!(
        run_segment(&l, 3, 30..60).unwrap().parcels,
        one.kept[30..60]
    );
}

#[test]
fn a_tally_only_run_keeps_the_same_tally_and_no_parcels() {
    let l = line(vec![diverter(0.0, 0.5), diverter(4.0, 0.3)], 0.6);
    let whole = study::LineSegments::new(&l, 5, 120, 25);
    let bare = study::LineSegments {
        tally_only: true,
        ..study::LineSegments::new(&l, 5, 120, 25)
    };
    let run = |s: &study::LineSegments| {
        execute_quietly(s, study::LineRun::new(2, 5), &Unkept)
            .unwrap()
            .tally
    };
    let (whole, bare) = (run(&whole), run(&bare));
    assert_eq!(bare.tally, whole.tally);
    assert_eq!(whole.kept.len(), 120);
    assert!(bare.kept.is_empty());
    assert_eq!(bare.log, study::LineRun::new(2, 5).log);
    assert_ne!(whole.log, bare.log);
}

#[test]
fn a_traced_segment_is_the_segment_with_its_paths() {
    let l = line(vec![diverter(0.0, 0.5), diverter(4.0, 0.5)], 0.8);
    let plain = run_segment(&l, 5, 0..40).unwrap();
    let (traced, trace) = trace_segment(&l, 5, 0..40).unwrap();
    assert_eq!(plain.parcels, traced.parcels);
    assert_eq!(trace.parcels.len(), 40);
    assert_eq!(trace.cycles.len(), 2);
    for (path, p) in trace.parcels.iter().zip(&traced.parcels) {
        assert!(path.keyframes.len() >= 2, "{p:?}");
        assert!(path.keyframes.windows(2).all(|w| w[1][0] >= w[0][0]));
        // Off the belt exactly when it left the line at a diverter.
        let left = matches!(
            p.outcome,
            LineOutcome::Diverted | LineOutcome::WronglyDiverted | LineOutcome::Collision
        );
        assert_eq!(path.gone.is_some(), left, "{p:?}");
    }
}

/// Issue 26: the line's load spectrum counts every stroke of every arm once (an arm's
/// inertia alone where no parcel loaded it), every strike on an arm, and its largest stroke
/// is a run that gives that peak again.
#[test]
fn the_line_counts_every_stroke_and_its_largest_reproduces() {
    let mut l = line(vec![diverter(0.0, 0.5), diverter(4.0, 0.5)], 3.0);
    for d in &mut l.diverters {
        d.setting.machine.arm_inertia = 1.5;
    }
    let seg = run_segment(&l, 7, 0..120).unwrap();
    let mut tally = tally::LineTally::new(2);
    tally.add(&seg);
    let cycles: u64 = seg.cycles.iter().map(|&c| u64::from(c)).sum();
    assert_eq!(tally.loads.strokes, cycles);
    assert_eq!(
        seg.loads
            .stroke_peaks
            .iter()
            .map(Vec::len)
            .collect::<Vec<_>>(),
        seg.cycles.iter().map(|&c| c as usize).collect::<Vec<_>>()
    );
    let torque = tally.loads.torque_spectrum.as_ref().expect("strokes");
    assert_eq!(torque.total(), cycles);
    let strikes = tally
        .loads
        .strike_spectrum
        .as_ref()
        .expect("strikes on the arms");
    assert_eq!(strikes.total(), seg.loads.strike_impulses.len() as u64);
    // A stroke no parcel loaded demands the arm's own inertia torque; the loaded ones
    // their runs' peaks.
    let profile = StrokeProfile::of(&l.diverters[0].setting).unwrap();
    let free = profile.loads(0.0, &[], &[]).peak_torque;
    let peaks: Vec<f64> = seg.loads.stroke_peaks.iter().flatten().copied().collect();
    let unloaded = peaks.iter().filter(|&&p| p == free).count();
    assert!(
        unloaded > 0 && unloaded < peaks.len(),
        "{unloaded} of {}",
        peaks.len()
    );
    let (peak, run) = tally.loads.largest.clone().expect("a loaded stroke");
    assert_eq!(torque.max, peak);
    assert!(peak > free);
    let s = run.scenario(&l.diverters[usize::from(run.diverter)].setting);
    let r = crate::sim::simulate_verdict(&s);
    let again = s
        .run
        .cycle_starts
        .iter()
        .map(|&c| profile.loads(c, &r.arm_torque, &r.arm_strikes).peak_torque)
        .fold(0.0, f64::max);
    assert_eq!(again, peak);
}

/// Issue 50, item 16: the utilisation reached 1.0027 with the `late` rule, the cycles of a
/// segment counted whole although its last ones run past its window. Clipped to the
/// window, an arm busy back to back is busy the whole window and no more; the clipping
/// itself against closed forms.
#[test]
fn utilisation_never_exceeds_one() {
    assert_eq!(flow::in_window(&[0.0, 1.0, 2.0], 1.0, 0.0, 2.5), 2.5);
    assert!((flow::in_window(&[0.2, 1.7], 1.0, 0.5, 2.0) - 1.5).abs() < 1e-15);
    assert_eq!(flow::in_window(&[5.0], 1.0, 0.0, 2.0), 0.0);
    // Every parcel bound here, 0.4 m gaps: the arm starts late, back to back.
    let mut l = line(vec![diverter(0.0, 1.0)], 0.4);
    l.busy = BusyRule::Late { max_delay: 2.0 };
    let segments = segments(&l, 7, 120, 40);
    let mut tally = tally::LineTally::new(1);
    let mut whole = 0.0;
    for s in &segments {
        tally.add(s);
        whole += f64::from(s.cycles[0]) * l.diverters[0].setting.machine.cycle_time;
    }
    let u = tally.utilisation(&l, 0);
    assert!(
        whole / tally.time > 1.0,
        "the reproducer: {}",
        whole / tally.time
    );
    assert!(u <= 1.0 && u > 0.9, "{u}");
}

/// Segments of `size` parcels of the stream of `parcels` from `seed`, one after another.
pub(super) fn segments(l: &Line, seed: u64, parcels: u64, size: u64) -> Vec<Segment> {
    let study = study::LineSegments {
        batch: 1,
        ..study::LineSegments::new(l, seed, parcels, size)
    };
    (0..study.pieces())
        .map(|k| study.run_piece(k, &no_progress).unwrap())
        .collect()
}
