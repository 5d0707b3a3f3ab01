//! Neighbours: whether two consecutive parcels' footprints overlap along their paths.
//!
//! Detected, not resolved: the event engine has one parcel, an arm and a guide, and no
//! parcel–parcel contact. Where two footprints overlap by more than [`OVERLAP_TOL`], both
//! parcels get the outcome `collision` with its time and place, and leave the line (what
//! follows a real jam is not modelled).
//!
//! Two parcels riding with the belt keep their relative pose, so a riding pair is checked
//! at one instant. A pair in which the arm touched either parcel is checked along both
//! paths while their spans at this diverter overlap: a simulated parcel's path is its run's
//! trajectory (run again with its samples, ≤ 5 ms apart; the run is deterministic, so it is
//! the same run), before and after the run its riding path when it rides; an unsimulated
//! parcel rides. The footprints are compared by the separating-axis test.

use super::passage::{Carried, Motion, Visit};
use super::{Collision, Line};
use crate::geometry::Rect;
use crate::sim::{simulate_with, Recording, Sample};
use glam::DVec2;

/// Smallest overlap of two footprints that counts as a collision \[m]: well above the
/// interpolation error of sampled paths, well below any parcel.
pub const OVERLAP_TOL: f64 = 1e-3;
/// Slack of the screen along the belt \[m]: a run's range of x is taken at its samples, at
/// most 5 ms apart, between which a parcel moves a few millimetres.
const SCREEN_MARGIN: f64 = 0.05;
/// Largest time step of the check where no run gives samples \[s].
const STEP: f64 = 0.005;

/// A collision between the segment's parcels `first` and `second` (indices in the segment).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub first: usize,
    pub second: usize,
    pub at: Collision,
}

/// Depth of the overlap of two rectangles (centre, φ): the smallest overlap of their
/// projections over the four edge normals; ≤ 0 when they are apart.
pub fn overlap_depth(a: &Rect, pa: (DVec2, f64), b: &Rect, pb: (DVec2, f64)) -> f64 {
    let ca = a.corners(pa.0, pa.1);
    let cb = b.corners(pb.0, pb.1);
    let axes = [
        pa.1,
        pa.1 + std::f64::consts::FRAC_PI_2,
        pb.1,
        pb.1 + std::f64::consts::FRAC_PI_2,
    ]
    .map(|t| DVec2::new(t.cos(), t.sin()));
    let span = |cs: &[DVec2; 4], n: DVec2| {
        cs.iter()
            .map(|c| c.dot(n))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p), hi.max(p))
            })
    };
    axes.iter()
        .map(|&n| {
            let (a0, a1) = span(&ca, n);
            let (b0, b1) = span(&cb, n);
            a1.min(b1) - a0.max(b0)
        })
        .fold(f64::INFINITY, f64::min)
}

/// A parcel's path at this diverter: its trajectory while run, riding around it.
struct Path<'a> {
    rect: Rect,
    before: Option<Carried>,
    samples: std::borrow::Cow<'a, [Sample]>,
    origin: f64,
    end: f64,
    after: Option<Carried>,
}

impl<'a> Path<'a> {
    fn of(visit: &'a Visit, line: &Line, d: usize) -> Path<'a> {
        let riding = |c: Carried| (c.motion == Motion::Riding).then_some(c);
        match &visit.run {
            None => Path {
                rect: visit.rect,
                before: riding(visit.came),
                samples: std::borrow::Cow::Borrowed(&[]),
                origin: f64::INFINITY,
                end: f64::INFINITY,
                after: None,
            },
            Some(run) => {
                // The run's own trajectory when it kept one, else the same run again.
                let samples = match run.result.trajectory.is_empty() {
                    false => std::borrow::Cow::Borrowed(run.result.trajectory.as_slice()),
                    true => {
                        let s = run.inputs.scenario(&line.diverters[d].setting);
                        std::borrow::Cow::Owned(simulate_with(&s, Recording::Full).trajectory)
                    }
                };
                Path {
                    rect: visit.rect,
                    before: riding(visit.came),
                    samples,
                    origin: run.origin,
                    end: run.end,
                    after: run.after.and_then(riding),
                }
            }
        }
    }

    /// Centre and φ at segment time t, where known.
    fn pose(&self, v: f64, t: f64) -> Option<(DVec2, f64)> {
        if t < self.origin {
            return self.before.map(|c| c.riding_pose(&self.rect, v, t));
        }
        if t > self.end {
            return self.after.map(|c| c.riding_pose(&self.rect, v, t));
        }
        let local = t - self.origin;
        let k = self.samples.partition_point(|s| s.state.t <= local);
        let (a, b) = match (
            k.checked_sub(1).and_then(|i| self.samples.get(i)),
            self.samples.get(k),
        ) {
            (Some(a), Some(b)) => (a, b),
            (Some(a), None) => (a, a),
            (None, Some(b)) => (b, b),
            (None, None) => return None,
        };
        let w = if b.state.t > a.state.t {
            ((local - a.state.t) / (b.state.t - a.state.t)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let lerp = |p: f64, q: f64| p + w * (q - p);
        Some((
            DVec2::new(lerp(a.state.x, b.state.x), lerp(a.state.y, b.state.y)),
            lerp(a.state.phi, b.state.phi),
        ))
    }

    /// The segment times over which the parcel's position is known to change other than by
    /// riding: its run's span.
    fn span(&self) -> Option<(f64, f64)> {
        self.origin.is_finite().then_some((self.origin, self.end))
    }
}

/// Whether a visit rode with the belt throughout (not run, or run untouched from riding to
/// riding): its position is then known in closed form at every time.
fn rides_throughout(x: &Visit) -> bool {
    let rides = |c: &Carried| c.motion == Motion::Riding;
    rides(&x.came)
        && x.run
            .as_ref()
            .is_none_or(|r| !r.touched && r.after.as_ref().is_some_and(rides))
}

/// The segment times of a visit's run when its path is not known in closed form.
fn span_of(x: &Visit) -> Option<(f64, f64)> {
    match rides_throughout(x) {
        true => None,
        false => x.run.as_ref().map(|r| (r.origin, r.end)),
    }
}

/// Bounds on the x a visit's footprint covers over segment times [lo, hi]: its run's range
/// of the centre ± half the diagonal, riding before and after it; `None` where unknown (a
/// parcel moving on its own outside its run).
fn along_bounds(x: &Visit, lo: f64, hi: f64, v: f64) -> Option<(f64, f64)> {
    let half_diagonal = 0.5 * x.rect.length.hypot(x.rect.width);
    let riding = |c: Carried, t0: f64, t1: f64| -> Option<(f64, f64)> {
        (c.motion == Motion::Riding).then(|| {
            let ext = 2.0 * x.rect.half_extents(c.angle).x;
            (v * (t0 - c.front_time) - ext, v * (t1 - c.front_time))
        })
    };
    let join = |a: (f64, f64), b: (f64, f64)| (a.0.min(b.0), a.1.max(b.1));
    match &x.run {
        _ if rides_throughout(x) => riding(x.came, lo, hi),
        None => riding(x.came, lo, hi),
        Some(r) => {
            let (a, b) = r.result.along_range;
            let mut range = (a - half_diagonal, b + half_diagonal);
            if lo < r.origin {
                range = join(range, riding(x.came, lo, r.origin)?);
            }
            // After the run: riding on, or off the belt (diverted, or off the near side),
            // where there is nothing to meet.
            if let (true, Some(after)) = (hi > r.end, r.after) {
                range = join(range, riding(after, r.end, hi)?);
            }
            Some(range)
        }
    }
}

/// Whether two visits' footprints can come near each other while either is run: their
/// bounds along the belt overlap over the runs' spans (a cheap test before any run is made
/// again with its samples).
fn may_meet(a: &Visit, b: &Visit, v: f64) -> bool {
    let spans: Vec<(f64, f64)> = [span_of(a), span_of(b)].into_iter().flatten().collect();
    let lo = spans.iter().map(|s| s.0).fold(f64::INFINITY, f64::min);
    let hi = spans.iter().map(|s| s.1).fold(f64::NEG_INFINITY, f64::max);
    match (along_bounds(a, lo, hi, v), along_bounds(b, lo, hi, v)) {
        (Some(x), Some(y)) => x.0 <= y.1 + SCREEN_MARGIN && y.0 <= x.1 + SCREEN_MARGIN,
        _ => true,
    }
}

/// The collisions at diverter `d` among its `visits` (in arrival order), at most one per
/// parcel, and the runs made again with their samples for it: [`check_pair`] along the
/// stream, a pair skipped when either parcel already collided.
pub fn check(line: &Line, d: usize, visits: &[Visit]) -> (Vec<Hit>, u64) {
    let mut reruns = 0;
    let mut hits: Vec<Hit> = Vec::new();
    let taken = |hits: &[Hit], k: usize| hits.iter().any(|h| h.first == k || h.second == k);
    for pair in visits.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        if taken(&hits, a.track) || taken(&hits, b.track) {
            continue;
        }
        let (hit, n) = check_pair(line, d, a, b);
        reruns += n;
        hits.extend(hit);
    }
    (hits, reruns)
}

/// Whether consecutive visits `a` and `b` at diverter `d` collide, and the runs made again
/// with their samples for it (0 to 2). Only the two visits are read: the stream checks each
/// pair as its second parcel passes, and keeps no other run.
pub fn check_pair(line: &Line, d: usize, a: &Visit, b: &Visit) -> (Option<Hit>, u64) {
    let mut reruns = 0;
    let v = line.belt_speed();
    let position = line.diverters[d].position;
    let touched = |x: &Visit| x.run.as_ref().is_some_and(|r| r.touched);
    let both_ride = a.came.motion == Motion::Riding && b.came.motion == Motion::Riding;
    let mut found = None;
    if both_ride {
        // Riding together: one instant tells.
        let t = b.came.front_time;
        let (pa, pb) = (
            a.came.riding_pose(&a.rect, v, t),
            b.came.riding_pose(&b.rect, v, t),
        );
        let depth = overlap_depth(&a.rect, pa, &b.rect, pb);
        if depth > OVERLAP_TOL {
            found = Some((t, pa.0, pb.0, depth));
        }
    }
    if found.is_none() && (touched(a) || touched(b)) && may_meet(a, b, v) {
        let (pa, pb) = (Path::of(a, line, d), Path::of(b, line, d));
        let rerun = |x: &Visit| {
            x.run
                .as_ref()
                .is_some_and(|r| r.result.trajectory.is_empty())
        };
        reruns += u64::from(rerun(a)) + u64::from(rerun(b));
        let spans: Vec<(f64, f64)> = [pa.span(), pb.span()].into_iter().flatten().collect();
        let lo = spans.iter().map(|s| s.0).fold(f64::INFINITY, f64::min);
        let hi = spans.iter().map(|s| s.1).fold(f64::NEG_INFINITY, f64::max);
        let mut times: Vec<f64> = [&pa, &pb]
            .iter()
            .filter(|p| p.span().is_some())
            .flat_map(|p| p.samples.iter().map(|s| p.origin + s.state.t))
            .collect();
        let n = ((hi - lo) / STEP).ceil().clamp(0.0, 1e6) as usize;
        times.extend((0..=n).map(|i| lo + (hi - lo) * i as f64 / n.max(1) as f64));
        times.sort_by(f64::total_cmp);
        for t in times {
            if let (Some(x), Some(y)) = (pa.pose(v, t), pb.pose(v, t)) {
                let depth = overlap_depth(&a.rect, x, &b.rect, y);
                if depth > OVERLAP_TOL {
                    found = Some((t, x.0, y.0, depth));
                    break;
                }
            }
        }
    }
    let hit = found.map(|(time, ca, cb, depth)| {
        let mid = 0.5 * (ca + cb);
        Hit {
            first: a.track,
            second: b.track,
            at: Collision {
                diverter: d as u8,
                time,
                x: position + mid.x,
                y: mid.y,
                other: 0,
                depth,
            },
        }
    });
    (hit, reruns)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overlap_depth_of_aligned_and_turned_boxes() {
        let r = Rect {
            length: 0.4,
            width: 0.2,
        };
        // Side by side along x, 0.1 m apart; then overlapping by 0.05 m.
        let apart = overlap_depth(&r, (DVec2::ZERO, 0.0), &r, (DVec2::new(0.5, 0.0), 0.0));
        assert!((apart + 0.1).abs() < 1e-12, "{apart}");
        let deep = overlap_depth(&r, (DVec2::ZERO, 0.0), &r, (DVec2::new(0.35, 0.0), 0.0));
        assert!((deep - 0.05).abs() < 1e-12, "{deep}");
        // A box turned 45° whose corner reaches 0.02 m into the other's side.
        let h = 0.5 * (0.4f64.hypot(0.2));
        let turned_angle = (0.2f64).atan2(0.4);
        let corner = overlap_depth(
            &r,
            (DVec2::ZERO, 0.0),
            &r,
            (DVec2::new(0.2 + h - 0.02, 0.0), turned_angle),
        );
        assert!((corner - 0.02).abs() < 1e-9, "{corner}");
    }
}
