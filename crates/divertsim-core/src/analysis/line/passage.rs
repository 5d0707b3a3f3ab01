//! One parcel through one diverter: whether a stroke can reach it, its run, and the state it
//! hands to the next diverter.
//!
//! **A passage.** A parcel riding with the belt is reached by the arm only while its
//! footprint is within x ∈ [0, R_z] of the pivot (the arm sweeps 0 ≤ α ≤ α_max ≤ 90° there).
//! When no cycle of the arm overlaps that window, it passes untouched and costs no
//! simulation. Otherwise it is run against every cycle near it (`run.cycle_starts`), from
//! the moment its front is at min(0, its own R_s): the whole parcel is then behind the
//! pivot, where no arm can be inside it. A parcel that is not riding when it comes (a
//! scattered arrival speed or spin, or disturbed upstream) is run from the state it has.
//!
use super::controller::Decision;
use super::stream::Arrival;
use super::{Line, RunInputs};
use crate::geometry::Rect;
use crate::model::params::{Parcel, ParcelRun};
use crate::sim::{simulate_with, Outcome, Recording, SimResult, Stage};
use glam::DVec2;

/// Slack around the arm's reach window \[m]: a corner within it of x = 0 or of R_z counts
/// as reachable.
const REACH_MARGIN: f64 = 0.01;
/// Time a run goes on after the last cycle near it and the parcel's passage \[s] (the
/// slide-out of the paper's runs).
const SLIDE_OUT: f64 = 2.0;
/// A final state within this of the belt's velocity (relative, and in spin × 1 m) rides.
const RIDING_TOL: f64 = 1e-9;

/// How a parcel moves as it comes to a diverter (in that diverter's frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    /// With the belt, in its pose: every position is known in closed form.
    Riding,
    /// Its own motion: (x, y, φ, ẋ, ẏ, ω) at segment time `time`.
    Moving { time: f64, state: [f64; 6] },
}

/// A parcel coming to a diverter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Carried {
    /// When its front passes the pivot's x (exact when riding; as if riding from its state
    /// otherwise: what the light barrier's timing assumes) \[s]
    pub front_time: f64,
    /// ΔP and φ (at `front_time` when riding, at the state's time otherwise)
    pub offset: f64,
    pub angle: f64,
    pub motion: Motion,
}

impl Carried {
    /// The same parcel in the frame of a diverter `shift` \[m] further down the belt.
    pub fn shifted(self, shift: f64, v: f64) -> Carried {
        let motion = match self.motion {
            Motion::Riding => Motion::Riding,
            Motion::Moving { time, mut state } => {
                state[0] -= shift;
                Motion::Moving { time, state }
            }
        };
        Carried {
            front_time: self.front_time + shift / v,
            motion,
            ..self
        }
    }

    /// Centre and φ at segment time t when riding.
    pub fn riding_pose(&self, rect: &Rect, v: f64, t: f64) -> (DVec2, f64) {
        let e = rect.half_extents(self.angle);
        (
            DVec2::new(v * (t - self.front_time) - e.x, self.offset + e.y),
            self.angle,
        )
    }
}

/// The pose (ΔP, φ) and front x of a state's footprint.
fn pose_of(rect: &Rect, y: &[f64; 6]) -> (f64, f64, f64) {
    let cs = rect.corners(DVec2::new(y[0], y[1]), y[2]);
    let offset = cs.iter().map(|c| c.y).fold(f64::INFINITY, f64::min);
    let front = cs.iter().map(|c| c.x).fold(f64::NEG_INFINITY, f64::max);
    (offset, y[2], front)
}

/// How a parcel first comes to the line (to the first diverter): riding, or with the mix's
/// arrival speed and spin when its front is at the pivot's x.
pub(super) fn inducted(a: &Arrival, v: f64) -> Carried {
    let d = &a.draw;
    let motion = if d.speed == 0.0 && d.spin == 0.0 {
        Motion::Riding
    } else {
        let e = Rect {
            length: d.length,
            width: d.width,
        }
        .half_extents(d.angle);
        Motion::Moving {
            time: a.time,
            state: [-e.x, d.offset + e.y, d.angle, v + d.speed, 0.0, d.spin],
        }
    };
    Carried {
        front_time: a.time,
        offset: d.offset,
        angle: d.angle,
        motion,
    }
}

/// A parcel's run at one diverter.
#[derive(Debug, Clone)]
pub struct Run {
    pub inputs: RunInputs,
    pub result: SimResult,
    /// Segment times of the run's start and end \[s]
    pub origin: f64,
    pub end: f64,
    /// Whether the arm touched it (a strike, or a held contact).
    pub touched: bool,
    /// The parcel after the run if it is still on the belt (this diverter's frame).
    pub after: Option<Carried>,
}

/// One parcel's passage at one diverter (what the neighbour check needs).
#[derive(Debug, Clone)]
pub struct Visit {
    /// Its index among the segment's parcels.
    pub track: usize,
    pub rect: Rect,
    pub came: Carried,
    pub run: Option<Run>,
}

/// Whether the arm took part in a run.
fn touched_by_arm(r: &SimResult) -> bool {
    // A parcel that jams at the arm's first strike has no impact recorded.
    r.jam.is_some()
        || r.impacts.iter().any(|i| i.obstacle.is_arm())
        || r.stages
            .iter()
            .any(|s| !matches!(s, Stage::Ride | Stage::F2 | Stage::Guide))
}

/// The passage of parcel `came` (drawn as `a`) at diverter `d`, whose arm runs `cycles`
/// (increasing, none overlapping: those near it are found by bisection, so a passage costs
/// no more in a long segment); its run records `recording` (its trajectory when a neighbour
/// is near: the neighbour check then needs no second run).
pub(super) fn pass(
    line: &Line,
    d: usize,
    cycles: &[f64],
    decision: Decision,
    a: &Arrival,
    (came, recording): (Carried, Recording),
) -> Option<Run> {
    let div = &line.diverters[d];
    let m = &div.setting.machine;
    let (v, t_c) = (m.belt_speed, m.cycle_time);
    let rect = Rect {
        length: a.draw.length,
        width: a.draw.width,
    };
    let ext = 2.0 * rect.half_extents(came.angle).x;
    let leaves = came.front_time + (ext + m.arm_length + REACH_MARGIN) / v;
    let (origin, start_position, offset, angle, velocity, spin) = match came.motion {
        Motion::Riding => {
            let enters = came.front_time - REACH_MARGIN / v;
            let served = matches!(decision, Decision::Served { .. });
            // The cycles are in order: the first one not over when it enters is the
            // earliest that can reach it.
            let next = cycles.partition_point(|&s| s + t_c <= enters);
            if !served && !cycles.get(next).is_some_and(|&s| s < leaves) {
                return None;
            }
            let x0 = match decision {
                Decision::Served { front, .. } => front.min(0.0),
                _ => 0.0,
            };
            (
                came.front_time + x0 / v,
                x0,
                came.offset,
                came.angle,
                None,
                0.0,
            )
        }
        Motion::Moving { time, state } => {
            let (offset, angle, front) = pose_of(&rect, &state);
            (
                time,
                front,
                offset,
                angle,
                Some([state[3], state[4]]),
                state[5],
            )
        }
    };
    // Every cycle that is not over at the origin and starts before the parcel is past;
    // a cycle long over stands for "no cycle" (the core wants one at least).
    let near = cycles.partition_point(|&s| s + t_c <= origin)
        ..cycles.partition_point(|&s| s < leaves.max(origin));
    let near: Vec<f64> = cycles
        .get(near)
        .unwrap_or_default()
        .iter()
        .map(|&s| s - origin)
        .collect();
    let cycle_starts = if near.is_empty() {
        vec![-2.0 * t_c]
    } else {
        near
    };
    let last_end = cycle_starts.last().map_or(0.0, |s| s + t_c);
    let duration = last_end.max(leaves - origin).max(0.0) + SLIDE_OUT;
    let parcel = Parcel::riding(
        a.draw.length,
        a.draw.width,
        a.draw.height,
        a.draw.mass,
        offset,
        angle,
    )
    .moving(velocity.map(|[x, y]| DVec2::new(x, y)), spin);
    let inputs = RunInputs {
        diverter: d as u8,
        run: ParcelRun {
            parcel,
            belt_friction: a.draw.belt_friction,
            arm_friction: a.draw.arm_friction,
            restitution: a.draw.restitution,
            start_position,
            cycle_starts: Some(cycle_starts),
            duration,
        },
        time_origin: origin,
    };
    let scenario = inputs.scenario(&div.setting);
    let result = simulate_with(&scenario, recording);
    let f = result.final_state;
    // A jammed parcel goes no further: the arm holds it at this diverter (the line's stop
    // that follows a real jam is not modelled).
    let leaves_line = match result.outcome {
        Outcome::Diverted | Outcome::Failed(_) => true,
        Outcome::NotDiverted(r) => matches!(
            r,
            crate::sim::NotDivertedReason::OffNearSide | crate::sim::NotDivertedReason::Jammed
        ),
    };
    let after = (!leaves_line).then(|| {
        let y = [f.x, f.y, f.phi, f.vx, f.vy, f.omega];
        let (offset, angle, front) = pose_of(&rect, &y);
        let t = origin + f.t;
        let riding = (f.vx - v).abs() <= RIDING_TOL * v.abs().max(1.0)
            && f.vy.abs() <= RIDING_TOL
            && f.omega.abs() <= RIDING_TOL;
        Carried {
            front_time: t - front / v,
            offset,
            angle,
            motion: if riding {
                Motion::Riding
            } else {
                Motion::Moving { time: t, state: y }
            },
        }
    });
    Some(Run {
        touched: touched_by_arm(&result),
        end: origin + f.t,
        origin,
        inputs,
        result,
        after,
    })
}
