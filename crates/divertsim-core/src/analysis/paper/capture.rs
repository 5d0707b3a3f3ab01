//! Capture test (paper §4.1, Fig. 5): does the arm catch a parcel riding with the belt, or
//! does the parcel "escape" out of the arm's reach?
//!
//! The paper's kinematic test. While the parcel rides with the belt (before any strike) its
//! corners translate at (v, 0): c_k(t) = c_k(0) + (v t, 0). Seen from the pivot O, a corner has
//! the polar angle γ_k(t) = atan2(y_k, x_k(t)) and the arm's line has the angle α(t)
//! ([`crate::model::drive`]). The arm sweeps counter-clockwise from α = 0 into a parcel lying
//! on its working side (γ > α), so the first point of the parcel its line meets is the point
//! of smallest polar angle, always a corner of the convex footprint:
//! γ_p(t) = min_k γ_k(t), the parcel's *front corner* (for φ = 0 riding at +x: the
//! downstream corner on the pivot side, smallest y). The corner realising the minimum at the
//! crossing is reported (for a rotated parcel the minimum can pass from one corner to
//! another).
//!
//! The line meets the corner when α(t) ≥ γ_p(t) for the first time, t*. The arm is a segment
//! of length R_z, so that is a strike only if the corner is within reach, |c(t*)| ≤ R_z. A
//! corner at constant height y_c lies on the arm line at the distance y_c / sin α, so within
//! reach ⇔ α ≥ α_z = asin(y_c / R_z), the paper's reach angle (none when y_c > R_z).
//! **Captured** if the first crossing lies at or above α_z (the paper: γ_p crosses α above the
//! line α_z); **escaped** otherwise (the line passes the corner beyond the tip, or never meets
//! it within the cycle). The test ignores the arm tip striking an edge and the other corners:
//! the full simulation ([`simulate`](crate::sim::simulate), also run here) settles those, and its first arm strike
//! is reported beside the kinematic answer.
//!
//! Crossing search: g(t) = α(t) − γ_p(t) on a grid of [`SCAN_POINTS`] intervals over
//! [0, t_c] (after t_c the arm rests at α = 0 and cannot reach a corner with y > 0), the
//! first grid point with g ≥ 0 bracketed with its predecessor and refined by bisection to
//! [`TIME_TOL`]. A touch-and-go crossing shorter than one grid interval (t_c/4000, 0.34 ms at
//! t_c = 1.36 s) can be missed; such a graze carries no momentum worth a capture.
//!
//! References: the paper §4.1, Fig. 5; docs/model.md §1 (frame, arm normal), §2 (drive).

use crate::analysis::paper::trigger::scenario_at;
use crate::model::drive::ArmDrive;
use crate::model::params::Scenario;
use crate::run::sweep::{par_map, Progress};
use crate::sim::{simulate_verdict, Impact, Obstacle, Outcome, Stage};
use glam::DVec2;

/// Grid intervals over [0, t_c] for the crossing search.
pub const SCAN_POINTS: usize = 4_000;
/// Bisection tolerance of the crossing time \[s].
pub const TIME_TOL: f64 = 1e-13;

/// Why a capture test cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CaptureError {
    /// The arm drive cannot be built.
    #[error("arm drive: {0}")]
    Drive(String),
    /// Unusable input.
    #[error("{0}")]
    Invalid(String),
}

/// The arm line meeting the front corner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// t*: time from the arm start \[s]
    pub t: f64,
    /// α(t*) = γ_p(t*): arm angle at the crossing \[rad]
    pub alpha: f64,
    /// |c(t*)|: distance of the corner from the pivot \[m]
    pub distance: f64,
    /// Index of the corner (order of `Rect::body_corners`: (+a/2, −b/2) first,
    /// counter-clockwise)
    pub corner: usize,
    /// c(t*): the corner's position \[m]
    pub point: DVec2,
}

/// The kinematic (paper's) capture test for one scenario.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KinematicCapture {
    /// The corner tested: the one at the crossing, else the front corner at t = 0.
    pub corner: usize,
    /// y_c: its (constant) height while riding \[m]
    pub corner_height: f64,
    /// α_z = asin(y_c / R_z): the reach angle \[rad]; `None` when y_c > R_z.
    pub reach_angle: Option<f64>,
    /// The first crossing α = γ_p within the cycle, within reach or not.
    pub crossing: Option<Crossing>,
    /// Whether the crossing is within reach (α(t*) ≥ α_z).
    pub captured: bool,
}

/// One point of the Fig. 5 curves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvePoint {
    /// t \[s]
    pub t: f64,
    /// α(t) \[rad]
    pub alpha: f64,
    /// γ_p(t): polar angle of the front corner \[rad]
    pub gamma: f64,
}

/// What the full simulation says about the same case.
#[derive(Debug, Clone, PartialEq)]
pub struct SimCheck {
    /// The first strike by the arm (face, back or tip), if any.
    pub first_strike: Option<Impact>,
    /// Whether that strike is the tested corner on the arm's working face.
    pub corner_struck_first: bool,
    /// The verdict.
    pub outcome: Outcome,
    /// Stages visited.
    pub stages: Vec<Stage>,
    /// Largest y of the centre \[m].
    pub max_lateral: f64,
}

/// The capture analysis at one belt speed and start position.
#[derive(Debug, Clone, PartialEq)]
pub struct CaptureCase {
    /// v [m/s]
    pub speed: f64,
    /// R_s \[m]
    pub start: f64,
    pub kinematic: KinematicCapture,
    /// α(t) and γ_p(t) over [0, t_c].
    pub curve: Vec<CurvePoint>,
    pub sim: SimCheck,
}

impl CaptureCase {
    /// α(t*) − α_z: how far above the reach angle the arm meets the corner \[rad]
    /// (negative: escaped beyond the tip); `None` without a crossing or a reach angle.
    pub fn margin(&self) -> Option<f64> {
        let k = &self.kinematic;
        Some(k.crossing?.alpha - k.reach_angle?)
    }
}

/// The corners while riding: c_k(t) = c_k(0) + (v t, 0).
struct Riding {
    corners0: [DVec2; 4],
    speed: f64,
}

impl Riding {
    fn new(s: &Scenario) -> Riding {
        Riding {
            corners0: s.footprint().corners(s.initial_centre(), s.parcel.angle),
            speed: s.machine.belt_speed,
        }
    }

    fn corner(&self, k: usize, t: f64) -> DVec2 {
        self.corners0[k] + DVec2::new(self.speed * t, 0.0)
    }

    /// γ_p(t) and the corner realising it (the first on ties).
    fn front(&self, t: f64) -> (f64, usize) {
        let mut best = (f64::INFINITY, 0);
        for k in 0..4 {
            let c = self.corner(k, t);
            let g = c.y.atan2(c.x);
            if g < best.0 {
                best = (g, k);
            }
        }
        best
    }
}

fn drive_of(s: &Scenario) -> Result<ArmDrive, CaptureError> {
    ArmDrive::new(&s.machine.drive, s.machine.cycle_time)
        .map_err(|e| CaptureError::Drive(e.to_string()))
}

fn check(s: &Scenario) -> Result<(), CaptureError> {
    let m = &s.machine;
    let p = &s.parcel;
    let ok = [
        m.belt_speed,
        m.arm_length,
        m.start_position,
        p.length,
        p.width,
        p.offset,
        p.angle,
    ]
    .iter()
    .all(|v| v.is_finite())
        && m.arm_length > 0.0
        && p.length > 0.0
        && p.width > 0.0;
    if ok {
        Ok(())
    } else {
        Err(CaptureError::Invalid(
            "belt speed, arm length, start position and parcel geometry must be finite, \
             lengths > 0"
                .to_string(),
        ))
    }
}

/// The paper's kinematic capture test for a parcel riding with the belt from the scenario's
/// initial pose.
pub fn kinematic_capture(s: &Scenario) -> Result<KinematicCapture, CaptureError> {
    check(s)?;
    let drive = drive_of(s)?;
    let ride = Riding::new(s);
    let tc = drive.cycle_time();
    let g = |t: f64| drive.state(t).angle - ride.front(t).0;
    let mut crossing_t = None;
    let mut prev = 0.0;
    for i in 0..=SCAN_POINTS {
        let t = tc * i as f64 / SCAN_POINTS as f64;
        if g(t) >= 0.0 {
            crossing_t = Some(if i == 0 {
                0.0
            } else {
                // g(prev) < 0 ≤ g(t): bisect to the first instant of g ≥ 0.
                let (mut lo, mut hi) = (prev, t);
                while hi - lo > TIME_TOL {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    if g(mid) >= 0.0 {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                hi
            });
            break;
        }
        prev = t;
    }
    let r_z = s.machine.arm_length;
    let crossing = crossing_t.map(|t| {
        let (_, k) = ride.front(t);
        let point = ride.corner(k, t);
        Crossing {
            t,
            alpha: drive.state(t).angle,
            distance: point.length(),
            corner: k,
            point,
        }
    });
    let corner = crossing.map_or_else(|| ride.front(0.0).1, |c| c.corner);
    let corner_height = ride.corner(corner, 0.0).y;
    let reach_angle = (corner_height.abs() <= r_z).then(|| (corner_height / r_z).asin());
    let captured = crossing.is_some_and(|c| c.distance <= r_z);
    Ok(KinematicCapture {
        corner,
        corner_height,
        reach_angle,
        crossing,
        captured,
    })
}

/// α(t) and γ_p(t) at `n + 1` equally spaced instants over [0, t_c].
pub fn polar_curve(s: &Scenario, n: usize) -> Result<Vec<CurvePoint>, CaptureError> {
    check(s)?;
    let drive = drive_of(s)?;
    let ride = Riding::new(s);
    let tc = drive.cycle_time();
    let n = n.max(1);
    Ok((0..=n)
        .map(|i| {
            let t = tc * i as f64 / n as f64;
            CurvePoint {
                t,
                alpha: drive.state(t).angle,
                gamma: ride.front(t).0,
            }
        })
        .collect())
}

/// The kinematic test, the curves (`curve_points` intervals) and the full simulation for
/// `base` at belt speed `speed` and start `start` (the parcel riding with the belt, as in
/// [`scenario_at`]).
pub fn capture_case(
    base: &Scenario,
    speed: f64,
    start: f64,
    curve_points: usize,
) -> Result<CaptureCase, CaptureError> {
    if !(speed.is_finite() && speed >= 0.0 && start.is_finite()) {
        return Err(CaptureError::Invalid(format!(
            "belt speed {speed} m/s must be finite and ≥ 0, start {start} m finite"
        )));
    }
    let s = scenario_at(base, speed, base.machine.cycle_time, start);
    let kinematic = kinematic_capture(&s)?;
    let curve = polar_curve(&s, curve_points)?;
    let r = simulate_verdict(&s);
    let first_strike = r.impacts.iter().find(|i| i.obstacle.is_arm()).copied();
    let corner_struck_first = match (first_strike, kinematic.crossing) {
        (Some(i), Some(_)) if i.obstacle == Obstacle::ArmFace => {
            let c = Riding::new(&s).corner(kinematic.corner, i.t);
            (DVec2::from(i.point) - c).length() < 1e-6
        }
        _ => false,
    };
    Ok(CaptureCase {
        speed,
        start,
        kinematic,
        curve,
        sim: SimCheck {
            first_strike,
            corner_struck_first,
            outcome: r.outcome,
            stages: r.stages,
            max_lateral: r.max_lateral,
        },
    })
}

/// [`capture_case`] for every (v, R_s) in `cases`, in parallel (one progress tick per case).
pub fn capture_sweep(
    base: &Scenario,
    cases: &[(f64, f64)],
    curve_points: usize,
    progress: Progress<'_>,
) -> Result<Vec<CaptureCase>, CaptureError> {
    par_map(cases, progress, |&(v, rs)| {
        capture_case(base, v, rs, curve_points)
    })
    .into_iter()
    .collect()
}

/// The kinematic verdict at each R_s of `starts` for belt speed `speed`: which start
/// positions let the arm catch the parcel (cheap: no simulation).
pub fn capture_window(
    base: &Scenario,
    speed: f64,
    starts: &[f64],
) -> Result<Vec<(f64, bool)>, CaptureError> {
    starts
        .iter()
        .map(|&rs| {
            let s = scenario_at(base, speed, base.machine.cycle_time, rs);
            kinematic_capture(&s).map(|k| (rs, k.captured))
        })
        .collect()
}

/// Contiguous runs of captured start positions in a [`capture_window`] result, as
/// (first, last) R_s of each run \[m].
pub fn captured_ranges(window: &[(f64, bool)]) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    let mut open: Option<(f64, f64)> = None;
    for &(rs, ok) in window {
        match (ok, open.as_mut()) {
            (true, Some(r)) => r.1 = rs,
            (true, None) => open = Some((rs, rs)),
            (false, Some(_)) => out.extend(open.take()),
            (false, None) => {}
        }
    }
    out.extend(open);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::drive::DriveSpec;
    use crate::model::params::Parcel;
    use proptest::prelude::*;

    /// The paper's Fig. 5 parcel: 0.2 × 0.1 × 0.1 m, 0.5 kg, farthest from the pivot.
    fn smallest(offset: f64) -> Scenario {
        let mut s = Scenario::paper_default();
        s.parcel = Parcel::riding(0.2, 0.1, 0.1, 0.5, offset, 0.0);
        s
    }

    /// A parcel at rest (v = 0) under the harmonic law α = α_max(1 − cos(πt/T))/2, T = t_c/2:
    /// the corner's angle γ is constant, so t* = (T/π) acos(1 − 2γ/α_max).
    #[test]
    fn crossing_time_matches_the_harmonic_closed_form() {
        let mut s = smallest(0.3);
        let amax = 45f64.to_radians();
        s.machine.drive = DriveSpec::Harmonic { max_swing: amax };
        s.machine.belt_speed = 0.0;
        s.machine.start_position = 0.6;
        let k = kinematic_capture(&s).unwrap();
        let gamma = 0.3f64.atan2(0.6);
        let t_half = 0.5 * s.machine.cycle_time;
        let expected = t_half / std::f64::consts::PI * (1.0 - 2.0 * gamma / amax).acos();
        let x = k.crossing.expect("a crossing");
        assert!((x.t - expected).abs() < 1e-10, "{} vs {expected}", x.t);
        assert!((x.alpha - gamma).abs() < 1e-10);
        assert_eq!(x.corner, 0, "the downstream pivot-side corner (+a/2, −b/2)");
        assert!((x.distance - 0.6f64.hypot(0.3)).abs() < 1e-12);
        assert!((k.reach_angle.unwrap() - (0.3f64).asin()).abs() < 1e-15);
        assert!(k.captured);
    }

    /// The kinematic capture time is the simulation's first strike time when the corner is
    /// struck first (the parcel rides until then, in closed form in both).
    #[test]
    fn kinematic_capture_time_agrees_with_the_simulation() {
        for (offset, speed, start) in [(0.3, 1.5, 0.3), (0.6, 1.0, 0.0), (0.45, 2.0, -0.2)] {
            let c = capture_case(&smallest(offset), speed, start, 50).unwrap();
            let x = c.kinematic.crossing.expect("a crossing");
            assert!(c.kinematic.captured, "ΔP {offset}, v {speed}, R_s {start}");
            let strike = c.sim.first_strike.expect("a strike");
            assert!(
                c.sim.corner_struck_first,
                "ΔP {offset}: struck by {:?} at {:?}",
                strike.obstacle, strike.point
            );
            assert!(
                (strike.t - x.t).abs() < 1e-6,
                "ΔP {offset}: kinematic {} vs simulated {}",
                x.t,
                strike.t
            );
        }
    }

    /// Started far downstream at high speed, the smallest parcel's front corner passes the
    /// arm's line beyond the tip: the crossing is below α_z, escaped.
    #[test]
    fn far_corner_escapes_below_the_reach_angle() {
        let c = capture_case(&smallest(0.6), 2.0, 1.0, 50).unwrap();
        let k = &c.kinematic;
        assert!(!k.captured);
        let az = k.reach_angle.unwrap();
        assert!((az - 0.6f64.asin()).abs() < 1e-15);
        match k.crossing {
            Some(x) => {
                assert!(x.alpha < az && x.distance > 1.0);
                assert!(c.margin().unwrap() < 0.0);
            }
            None => assert!(c.margin().is_none()),
        }
    }

    #[test]
    fn curve_starts_at_rest_and_ends_at_the_cycle() {
        let s = trigger_free(smallest(0.6), 1.5, 0.4);
        let c = polar_curve(&s, 100).unwrap();
        assert_eq!(c.len(), 101);
        assert_eq!(c[0].t, 0.0);
        assert_eq!(c[0].alpha, 0.0);
        assert!((c[0].gamma - 0.6f64.atan2(0.4)).abs() < 1e-15);
        assert!((c[100].t - s.machine.cycle_time).abs() < 1e-15);
        // The front corner rides downstream: its angle falls.
        assert!(c.windows(2).all(|w| w[1].gamma < w[0].gamma));
    }

    fn trigger_free(base: Scenario, v: f64, rs: f64) -> Scenario {
        scenario_at(&base, v, base.machine.cycle_time, rs)
    }

    #[test]
    fn ranges_group_contiguous_captures() {
        let w = [
            (0.0, false),
            (0.1, true),
            (0.2, true),
            (0.3, false),
            (0.4, true),
        ];
        assert_eq!(captured_ranges(&w), vec![(0.1, 0.2), (0.4, 0.4)]);
        assert!(captured_ranges(&[(0.0, false)]).is_empty());
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let mut s = smallest(0.6);
        s.parcel.length = f64::NAN;
        assert!(kinematic_capture(&s).is_err());
        assert!(capture_case(&smallest(0.6), f64::INFINITY, 0.0, 10).is_err());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// Captured ⇔ the crossing is at or above α_z = asin(y_c/R_z) (the corner rides at
        /// constant height), and at the crossing the arm angle equals the corner's angle.
        #[test]
        fn captured_iff_crossing_above_reach_angle(
            offset in 0.0f64..0.6,
            speed in 0.3f64..2.5,
            start in -0.5f64..1.5,
            angle_deg in -30.0f64..30.0,
        ) {
            let mut base = smallest(offset);
            base.parcel.angle = angle_deg.to_radians();
            let s = trigger_free(base, speed, start);
            let k = kinematic_capture(&s).unwrap();
            if let Some(x) = k.crossing {
                let c = s.footprint().corners(s.initial_centre(), s.parcel.angle)[x.corner]
                    + DVec2::new(speed * x.t, 0.0);
                prop_assert!((c - x.point).length() < 1e-12);
                if x.t > 0.0 {
                    prop_assert!((c.y.atan2(c.x) - x.alpha).abs() < 1e-8);
                }
                let az = k.reach_angle.unwrap();
                prop_assert!((az - (c.y / s.machine.arm_length).asin()).abs() < 1e-12);
                // Away from the boundary the two descriptions agree.
                if (x.alpha - az).abs() > 1e-9 {
                    prop_assert_eq!(k.captured, x.alpha > az);
                }
            } else {
                prop_assert!(!k.captured);
            }
        }
    }
}
