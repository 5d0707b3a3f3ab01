//! Measured paths: a marker tracked on video, mapped from pixels to the machine frame, and
//! compared with a simulation (the paper's Figs 13–15).
//!
//! **Camera.** A pixel (u, v) maps to the machine frame by a plane homography H (the belt is
//! a plane): (x, y, 1)ᵀ ∝ H (u, v, 1)ᵀ. A camera square to the belt is the special case of a
//! scale, an origin and axis directions ([`CameraMap::square`]); an oblique one is fitted
//! exactly through four reference points with known machine coordinates
//! ([`CameraMap::from_points`], the direct linear transform). A position read to the nearest
//! pixel carries a uniform error of ±0.5 px, standard deviation 1/√12 px per axis, carried to
//! metres through the map's Jacobian at that pixel.
//!
//! **The simulated marker.** The marker sits at a fixed offset from the centre in the
//! parcel's own axes: P(t) = G(t) + R(φ(t)) o. Before the arm starts (t < 0) the parcel rides
//! with its initial velocity (P moves at that velocity, φ fixed); after the run's end it
//! continues with its final velocity (for a diverted parcel the run stops as the centre
//! crosses the far edge, while a video may follow it onto the skid a little longer).
//!
//! **Alignment.** Video time and simulation time differ by an unknown offset t₀ (the arm
//! start on the video): t_sim = t_video − t₀. t₀ minimises the sum of squared distances
//! between the measured and simulated marker positions: a scan at 5 ms over every offset
//! at which the track overlaps the run, then golden-section refinement to 1e-9 s. Times
//! are taken relative to the track's first one (a video clock in Unix time keeps its
//! resolution); a span longer than 100 s is scanned coarser first and refined around the
//! best offset, and a track of more than 2,048 points is scanned on 2,048 of them, so the
//! work is bounded by a constant plus a multiple of the track's length.
//!
//! **Comparison.** At the aligned times: RMS and largest error along the belt (x) and
//! across it (y), the discrete Fréchet distance between the two polylines (Eiter & Mannila
//! 1994), the measured and simulated verdicts, and the belt speed seen on the track before the
//! first strike. The measured verdict is **diverted** when the marker reaches the far edge
//! y = P_max; **not diverted** when it does not and, over the track's last
//! [`AT_REST_WINDOW`], it no longer moves across the belt (|ẏ| ≤ [`AT_REST_SPEED`]: riding
//! on); otherwise **unknown**: the track ends while the parcel still moves towards the far
//! edge (it left the camera's field of view), and a track cannot tell what came next.

use crate::model::params::Scenario;
use crate::sim::{EventKind, Outcome, SimResult, Stage};
use glam::DVec2;

/// A pixel-to-machine mapping.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraMap {
    /// H, row-major: (x, y, w) = H (u, v, 1), machine point (x/w, y/w).
    pub h: [f64; 9],
}

/// Why a camera map cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CameraError {
    #[error("the scale must be finite and > 0 px/m")]
    Scale,
    #[error("the axis directions must be finite, non-zero and not parallel")]
    Axes,
    #[error("the four reference points are degenerate (three on a line, or repeated)")]
    Degenerate,
}

impl CameraMap {
    /// A camera square to the belt: `px_per_m` pixels per metre, the machine origin at pixel
    /// `origin`, machine +x along pixel direction `x_axis`, +y along `y_axis`.
    pub fn square(
        px_per_m: f64,
        origin: [f64; 2],
        x_axis: [f64; 2],
        y_axis: [f64; 2],
    ) -> Result<CameraMap, CameraError> {
        if !(px_per_m.is_finite() && px_per_m > 0.0) {
            return Err(CameraError::Scale);
        }
        let ex = DVec2::from(x_axis);
        let ey = DVec2::from(y_axis);
        let det = ex.perp_dot(ey);
        if !(ex.is_finite() && ey.is_finite())
            || ex.length() == 0.0
            || ey.length() == 0.0
            || det.abs() < 1e-9 * ex.length() * ey.length()
        {
            return Err(CameraError::Axes);
        }
        let (ex, ey) = (ex.normalize(), ey.normalize());
        // px − origin = s (x ex + y ey) ⇒ (x, y) = M⁻¹ (px − origin)/s, M = [ex ey].
        let det = ex.perp_dot(ey);
        let inv = [ey.y / det, -ey.x / det, -ex.y / det, ex.x / det];
        let k = 1.0 / px_per_m;
        let (a, b, c, d) = (inv[0] * k, inv[1] * k, inv[2] * k, inv[3] * k);
        let (u0, v0) = (origin[0], origin[1]);
        Ok(CameraMap {
            h: [
                a,
                b,
                -(a * u0 + b * v0),
                c,
                d,
                -(c * u0 + d * v0),
                0.0,
                0.0,
                1.0,
            ],
        })
    }

    /// The homography through four (pixel, machine point) pairs (direct linear transform,
    /// h₃₃ = 1).
    pub fn from_points(pairs: &[([f64; 2], [f64; 2]); 4]) -> Result<CameraMap, CameraError> {
        // Unknowns h11..h32; each pair gives two rows.
        let mut a = [[0.0f64; 9]; 8];
        for (k, ([u, v], [x, y])) in pairs.iter().enumerate() {
            a[2 * k] = [*u, *v, 1.0, 0.0, 0.0, 0.0, -u * x, -v * x, *x];
            a[2 * k + 1] = [0.0, 0.0, 0.0, *u, *v, 1.0, -u * y, -v * y, *y];
        }
        let sol = solve8(a).ok_or(CameraError::Degenerate)?;
        let map = CameraMap {
            h: [
                sol[0], sol[1], sol[2], sol[3], sol[4], sol[5], sol[6], sol[7], 1.0,
            ],
        };
        // Three collinear points give a singular but solvable-looking system: check that
        // every pair maps back.
        for ([u, v], [x, y]) in pairs {
            let p = map.to_machine([*u, *v]);
            if !(p.is_finite()
                && (p - DVec2::new(*x, *y)).length() < 1e-6 * (1.0 + x.abs() + y.abs()))
            {
                return Err(CameraError::Degenerate);
            }
        }
        Ok(map)
    }

    /// The machine point of pixel (u, v) \[m].
    pub fn to_machine(&self, px: [f64; 2]) -> DVec2 {
        let h = &self.h;
        let (u, v) = (px[0], px[1]);
        let w = h[6] * u + h[7] * v + h[8];
        DVec2::new(
            (h[0] * u + h[1] * v + h[2]) / w,
            (h[3] * u + h[4] * v + h[5]) / w,
        )
    }

    /// The pixel of a machine point (the inverse map).
    pub fn to_pixel(&self, p: DVec2) -> [f64; 2] {
        let inv = invert3(&self.h);
        let w = inv[6] * p.x + inv[7] * p.y + inv[8];
        [
            (inv[0] * p.x + inv[1] * p.y + inv[2]) / w,
            (inv[3] * p.x + inv[4] * p.y + inv[5]) / w,
        ]
    }

    /// The standard deviation \[m] along x and y of a position read to the nearest pixel at
    /// pixel `px`: 1/√12 px per pixel axis, through the map's Jacobian.
    pub fn quantisation_sigma(&self, px: [f64; 2]) -> DVec2 {
        let e = 1e-3;
        let p = self.to_machine(px);
        let du = (self.to_machine([px[0] + e, px[1]]) - p) / e;
        let dv = (self.to_machine([px[0], px[1] + e]) - p) / e;
        let s = 1.0 / 12f64.sqrt();
        DVec2::new(
            s * (du.x * du.x + dv.x * dv.x).sqrt(),
            s * (du.y * du.y + dv.y * dv.y).sqrt(),
        )
    }
}

/// Gaussian elimination with partial pivoting on an 8 × 8 system (augmented 8 × 9).
fn solve8(mut a: [[f64; 9]; 8]) -> Option<[f64; 8]> {
    let scale = a
        .iter()
        .flat_map(|r| r.iter())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    for col in 0..8 {
        let piv = (col..8).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        let p = a[piv][col].abs();
        if p.is_nan() || p <= 1e-12 * scale {
            return None;
        }
        a.swap(col, piv);
        let pivot_row = a[col];
        for (row, r) in a.iter_mut().enumerate() {
            if row != col {
                let f = r[col] / pivot_row[col];
                for (v, pv) in r[col..].iter_mut().zip(&pivot_row[col..]) {
                    *v -= f * pv;
                }
            }
        }
    }
    let mut x = [0.0; 8];
    for i in 0..8 {
        x[i] = a[i][8] / a[i][i];
    }
    Some(x)
}

/// The inverse of a 3 × 3 matrix (row-major), by its adjugate.
fn invert3(m: &[f64; 9]) -> [f64; 9] {
    let c = |i: usize, j: usize| m[3 * i + j];
    let cof = [
        c(1, 1) * c(2, 2) - c(1, 2) * c(2, 1),
        c(0, 2) * c(2, 1) - c(0, 1) * c(2, 2),
        c(0, 1) * c(1, 2) - c(0, 2) * c(1, 1),
        c(1, 2) * c(2, 0) - c(1, 0) * c(2, 2),
        c(0, 0) * c(2, 2) - c(0, 2) * c(2, 0),
        c(0, 2) * c(1, 0) - c(0, 0) * c(1, 2),
        c(1, 0) * c(2, 1) - c(1, 1) * c(2, 0),
        c(0, 1) * c(2, 0) - c(0, 0) * c(2, 1),
        c(0, 0) * c(1, 1) - c(0, 1) * c(1, 0),
    ];
    let det = c(0, 0) * cof[0] + c(0, 1) * cof[3] + c(0, 2) * cof[6];
    cof.map(|v| v / det)
}

/// A measured marker path in the machine frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Track {
    /// Video time of each point \[s], increasing.
    pub times: Vec<f64>,
    /// Marker position \[m].
    pub points: Vec<DVec2>,
    /// Standard deviation of each position along x and y \[m].
    pub sigma: Vec<DVec2>,
}

/// The simulated marker path of a run, evaluable at any time.
#[derive(Debug, Clone)]
pub struct MarkerPath {
    /// (t, marker position, marker velocity) at every trajectory sample, t increasing.
    samples: Vec<(f64, DVec2, DVec2)>,
    /// Velocity of the marker before the run (riding) and after it (final state).
    before: DVec2,
    after: DVec2,
    /// Time of the first strike or contact (the end of the free ride) \[s].
    pub first_touch: f64,
    /// The run's end \[s].
    pub end: f64,
}

impl MarkerPath {
    /// The path of the marker at `offset` (parcel axes) \[m] in a full run (with trajectory).
    pub fn new(scenario: &Scenario, result: &SimResult, offset: DVec2) -> MarkerPath {
        let at =
            |x: f64, y: f64, phi: f64| DVec2::new(x, y) + DVec2::from_angle(phi).rotate(offset);
        // The marker's velocity: v_G + ω ẑ × R(φ) o.
        let vel = |vx: f64, vy: f64, omega: f64, phi: f64| {
            let r = DVec2::from_angle(phi).rotate(offset);
            DVec2::new(vx, vy) + omega * r.perp()
        };
        let mut samples: Vec<(f64, DVec2, DVec2)> = Vec::with_capacity(result.trajectory.len());
        for s in &result.trajectory {
            let st = &s.state;
            let here = (
                st.t,
                at(st.x, st.y, st.phi),
                vel(st.vx, st.vy, st.omega, st.phi),
            );
            // An event instant appears twice (before and after a strike): both are kept, so
            // the segment into the strike ends with the velocity before it and the one out
            // of it starts with the velocity after it.
            if samples.last().is_none_or(|l| st.t >= l.0) {
                samples.push(here);
            }
        }
        let f = &result.final_state;
        if samples.is_empty() {
            samples.push((f.t, at(f.x, f.y, f.phi), vel(f.vx, f.vy, f.omega, f.phi)));
        }
        let v0 = scenario.initial_velocity();
        let before = vel(v0.x, v0.y, scenario.parcel.spin, scenario.parcel.angle);
        let after = vel(f.vx, f.vy, f.omega, f.phi);
        // The free ride ends at the first strike or contact, or at the first sample in any
        // other stage (a parcel lying on the arm is in contact from t = 0).
        let first_event = result
            .events
            .iter()
            .find(|e| matches!(e.kind, EventKind::Impact | EventKind::ContactStart))
            .map_or(f.t, |e| e.t);
        let first_stage = result
            .trajectory
            .iter()
            .find(|s| s.stage != Stage::Ride)
            .map_or(f.t, |s| s.state.t);
        let first_touch = first_event.min(first_stage);
        MarkerPath {
            end: samples.last().map_or(0.0, |s| s.0),
            samples,
            before,
            after,
            first_touch,
        }
    }

    /// The marker at simulation time t \[m]: cubic Hermite interpolation between the
    /// trajectory samples (positions and velocities), so the interpolation error, O(h⁴),
    /// stays far below a pixel even over the long steps of free sliding. Across a strike
    /// the velocity jumps at a sample, which the piecewise interpolation respects.
    pub fn at(&self, t: f64) -> DVec2 {
        let (t0, p0, _) = self.samples[0];
        if t <= t0 {
            return p0 + self.before * (t - t0);
        }
        let (tn, pn, _) = self.samples[self.samples.len() - 1];
        if t >= tn {
            return pn + self.after * (t - tn);
        }
        let i = self.samples.partition_point(|s| s.0 <= t).max(1) - 1;
        let (ta, pa, va) = self.samples[i];
        let (tb, pb, vb) = self.samples[(i + 1).min(self.samples.len() - 1)];
        let h = tb - ta;
        if h <= 0.0 {
            return pa;
        }
        let s = (t - ta) / h;
        let (s2, s3) = (s * s, s * s * s);
        pa * (2.0 * s3 - 3.0 * s2 + 1.0)
            + va * (h * (s3 - 2.0 * s2 + s))
            + pb * (-2.0 * s3 + 3.0 * s2)
            + vb * (h * (s3 - s2))
    }
}

/// Most track points one scan offset is scored on: a longer track is scored on this many
/// evenly spread points while scanning, and on every point in the final refinement.
const SCAN_POINTS: usize = 2048;
/// Most offsets of the first scan: over a span longer than 5 ms × this, the scan starts
/// coarser and is refined around its best offset, down to 5 ms.
const SCAN_OFFSETS: usize = 20_000;
/// Offsets of each refinement level around the best so far.
const REFINE_OFFSETS: usize = 64;
/// The finest scan spacing \[s] and the golden section's target width \[s].
const SCAN_STEP: f64 = 0.005;
const GOLDEN_WIDTH: f64 = 1e-9;
/// Golden-section steps at most: 0.01 s narrows to 1e-9 s in 34; the cap ends the search
/// where the times' float spacing is coarser than the target.
const GOLDEN_STEPS: usize = 100;

/// The track's times relative to its first one \[s] (so that video clocks in Unix time keep
/// their sub-millisecond resolution) and its points; `stride` keeps every stride-th.
struct Scored<'a> {
    times: Vec<f64>,
    points: Vec<DVec2>,
    path: &'a MarkerPath,
    /// Point evaluations so far: the alignment's work.
    work: std::cell::Cell<u64>,
}

impl<'a> Scored<'a> {
    fn new(track: &Track, path: &'a MarkerPath, first: f64, stride: usize) -> Scored<'a> {
        let keep = |i: &usize| i.is_multiple_of(stride);
        Scored {
            times: (0..track.times.len())
                .filter(keep)
                .map(|i| track.times[i] - first)
                .collect(),
            points: (0..track.points.len())
                .filter(keep)
                .map(|i| track.points[i])
                .collect(),
            path,
            work: std::cell::Cell::new(0),
        }
    }

    /// Σ |measured − simulated|² at relative offset s (t₀ = first + s).
    fn error(&self, s: f64) -> f64 {
        self.work.set(self.work.get() + self.times.len() as u64);
        self.times
            .iter()
            .zip(&self.points)
            .map(|(&t, p)| (self.path.at(t - s) - *p).length_squared())
            .sum()
    }
}

/// What is known of the arm start on a video: its time t₀, to within ± `within` \[s] (0: t₀
/// exactly, no search).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmStart {
    /// t₀ \[s], video time.
    pub time: f64,
    /// Half-width of the window t₀ lies in \[s].
    pub within: f64,
}

/// The offset t₀ (video time of the arm start) that aligns the track with the path
/// (module notes).
pub fn align(track: &Track, path: &MarkerPath) -> f64 {
    align_counted(track, path).0
}

/// [`align`] with what is known of the arm start: `Some` pins t₀ (within 0) or bounds the
/// search to its window.
pub fn align_pinned(track: &Track, path: &MarkerPath, pin: Option<ArmStart>) -> f64 {
    match pin {
        Some(p) if p.within <= 0.0 => p.time,
        _ => align_window(track, path, pin).0,
    }
}

/// [`align`] and its work: the number of point evaluations, at most a constant plus a
/// multiple of the track's length whatever its times (Unix time, hours between frames).
pub fn align_counted(track: &Track, path: &MarkerPath) -> (f64, u64) {
    align_window(track, path, None)
}

/// [`align_counted`] with t₀ kept inside the window of `pin`.
fn align_window(track: &Track, path: &MarkerPath, pin: Option<ArmStart>) -> (f64, u64) {
    let (Some(&first), Some(&last)) = (track.times.first(), track.times.last()) else {
        return (pin.map_or(0.0, |p| p.time), 0);
    };
    let n = track.times.len().min(track.points.len());
    let coarse = Scored::new(track, path, first, n.div_ceil(SCAN_POINTS).max(1));
    let fine = Scored::new(track, path, first, 1);
    // Every offset at which the track overlaps the run (with 0.5 s to spare either side),
    // relative to the first time, within the pin's window.
    let (mut lo, mut hi) = (-path.end - 0.5, (last - first) + 0.5);
    if let Some(p) = pin {
        lo = lo.max(p.time - p.within - first);
        hi = hi.min(p.time + p.within - first);
        if hi <= lo {
            return (p.time, 0);
        }
    }
    let window = (lo, hi);
    if !((hi - lo).is_finite() && hi > lo) {
        return (first, 0);
    }
    // The scan: one pass over the whole range at 5 ms, or a coarser pass refined around its
    // best offset until the spacing is 5 ms.
    let scan = |lo: f64, hi: f64, count: usize| -> (f64, f64) {
        let mut best = (f64::INFINITY, lo);
        for k in 0..=count {
            let s = lo + (hi - lo) * k as f64 / count as f64;
            let e = coarse.error(s);
            if e < best.0 {
                best = (e, s);
            }
        }
        best
    };
    let count = (((hi - lo) / SCAN_STEP).ceil() as usize).clamp(1, SCAN_OFFSETS);
    let mut step = (hi - lo) / count as f64;
    let mut best = scan(lo, hi, count).1;
    // Each level narrows the spacing 32-fold: 64 levels reach 5 ms from any finite span.
    for _ in 0..64 {
        if step <= SCAN_STEP * (1.0 + 1e-9) {
            break;
        }
        let (a, b) = (best - step, best + step);
        let count = ((2.0 * step / SCAN_STEP).ceil() as usize).clamp(2, REFINE_OFFSETS);
        step = (b - a) / count as f64;
        best = scan(a, b, count).1;
    }
    // Golden section on the bracket around the best scan point, on every point.
    let best_error = fine.error(best);
    let (mut a, mut b) = (best - step, best + step);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut fc, mut fd) = (fine.error(c), fine.error(d));
    for _ in 0..GOLDEN_STEPS {
        if b - a <= GOLDEN_WIDTH {
            break;
        }
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = fine.error(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = fine.error(d);
        }
    }
    let s = 0.5 * (a + b);
    let s = if fine.error(s) <= best_error { s } else { best };
    let s = s.clamp(window.0, window.1);
    (first + s, coarse.work.get() + fine.work.get())
}

/// The residuals (measured − simulated) at offset t₀, x then y per point \[m].
pub fn residuals(track: &Track, path: &MarkerPath, t0: f64) -> Vec<DVec2> {
    track
        .times
        .iter()
        .zip(&track.points)
        .map(|(&t, p)| *p - path.at(t - t0))
        .collect()
}

/// Most cells of the Fréchet table: longer polylines are coupled within a band around the
/// diagonal (see [`frechet`]).
const FRECHET_CELLS: usize = 50_000_000;

/// The discrete Fréchet distance between two polylines \[m] (Eiter & Mannila 1994).
///
/// Exact while the table (|a| × |b| cells) has at most 5·10⁷ cells. Beyond, the couplings
/// are those within a band around the diagonal (|i − j·|a|/|b|| ≤ w, the band as wide as
/// the cell budget allows, at least 16): an upper bound of the exact distance, and the
/// distance itself whenever the best coupling stays near the diagonal, as it does for a
/// track and its simulated positions sampled at the same instants. The work is linear in
/// the length.
pub fn frechet(a: &[DVec2], b: &[DVec2]) -> f64 {
    if a.is_empty() || b.is_empty() {
        return f64::NAN;
    }
    let (n, m) = (a.len(), b.len());
    let band = if n.saturating_mul(m) <= FRECHET_CELLS {
        m
    } else {
        (FRECHET_CELLS / n).max(16)
    };
    let mut prev = vec![f64::INFINITY; m];
    let mut cur = vec![f64::INFINITY; m];
    // The previous row's band: cells outside it are infinite (never coupled).
    let mut before = (1, 0);
    for (i, p) in a.iter().enumerate() {
        // Row i's columns within the band around the diagonal point i·m/n.
        let centre = if n > 1 { i * (m - 1) / (n - 1) } else { 0 };
        let (j0, j1) = if band >= m {
            (0, m - 1)
        } else {
            (centre.saturating_sub(band), (centre + band).min(m - 1))
        };
        let up = |prev: &[f64], j: usize| {
            if (before.0..=before.1).contains(&j) {
                prev[j]
            } else {
                f64::INFINITY
            }
        };
        for j in j0..=j1 {
            let d = (*p - b[j]).length();
            let left = if j > j0 { cur[j - 1] } else { f64::INFINITY };
            cur[j] = match (i, j) {
                (0, 0) => d,
                (0, _) => left.max(d),
                (_, 0) => up(&prev, 0).max(d),
                _ => up(&prev, j).min(up(&prev, j - 1)).min(left).max(d),
            };
        }
        before = (j0, j1);
        std::mem::swap(&mut prev, &mut cur);
    }
    if (before.0..=before.1).contains(&(m - 1)) {
        prev[m - 1]
    } else {
        f64::INFINITY
    }
}

/// A track compared with a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// t₀: the video time of the arm start \[s].
    pub offset: f64,
    /// Points compared.
    pub points: usize,
    /// Points whose aligned time lies after the run's end (compared with its
    /// continuation at the final velocity).
    pub after_end: usize,
    /// RMS and largest |error| along the belt (x) \[m].
    pub rms_x: f64,
    pub max_x: f64,
    /// RMS and largest |error| across the belt (y) \[m].
    pub rms_y: f64,
    pub max_y: f64,
    /// RMS of the distance \[m].
    pub rms: f64,
    /// Discrete Fréchet distance between the measured and simulated polylines \[m].
    pub frechet: f64,
    /// What the track shows of the verdict (module notes).
    pub measured: MeasuredVerdict,
    /// Whether the run diverts.
    pub simulated_diverted: bool,
    /// Belt speed seen on the track before the first strike (slope of x over the points
    /// before it, at least 3) [m/s]; `None` if too few, or if the parcel does not arrive
    /// riding with the belt.
    pub measured_speed: Option<f64>,
}

impl Comparison {
    /// Whether the verdicts agree; `None` when the track cannot tell.
    pub fn verdicts_agree(&self) -> Option<bool> {
        match self.measured {
            MeasuredVerdict::Unknown => None,
            m => Some((m == MeasuredVerdict::Diverted) == self.simulated_diverted),
        }
    }
}

/// The verdict a track shows (module notes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeasuredVerdict {
    /// The marker reaches the far edge.
    Diverted,
    /// It does not, and at the track's end it rides on (no longer moves across).
    NotDiverted,
    /// The track ends while the parcel still moves towards the far edge.
    Unknown,
}

impl MeasuredVerdict {
    pub fn label(self) -> &'static str {
        match self {
            MeasuredVerdict::Diverted => "diverted",
            MeasuredVerdict::NotDiverted => "not_diverted",
            MeasuredVerdict::Unknown => "unknown",
        }
    }

    /// `Some(diverted)` when known.
    pub fn diverted(self) -> Option<bool> {
        match self {
            MeasuredVerdict::Unknown => None,
            m => Some(m == MeasuredVerdict::Diverted),
        }
    }
}

/// The span at a track's end over which a parcel must not move across to count as riding
/// on, not diverted \[s].
pub const AT_REST_WINDOW: f64 = 0.1;
/// The largest lateral speed of a parcel riding on [m/s]: well above the drift a marker's
/// quantisation gives over [`AT_REST_WINDOW`], well below a push or a slide.
pub const AT_REST_SPEED: f64 = 0.05;

/// The verdict `track` shows for a belt `belt_width` wide (module notes).
pub fn measured_verdict(track: &Track, belt_width: f64) -> MeasuredVerdict {
    if track.points.iter().any(|p| p.y >= belt_width) {
        return MeasuredVerdict::Diverted;
    }
    let n = track.times.len().min(track.points.len());
    let Some(&end) = track.times[..n].last() else {
        return MeasuredVerdict::Unknown;
    };
    // The lateral speed over the last window: the least-squares slope of y(t), from at
    // least three points.
    let tail: Vec<(f64, f64)> = track.times[..n]
        .iter()
        .zip(&track.points[..n])
        .filter(|(t, _)| end - **t <= AT_REST_WINDOW)
        .map(|(t, p)| (*t, p.y))
        .collect();
    if tail.len() < 3 {
        return MeasuredVerdict::Unknown;
    }
    let k = tail.len() as f64;
    let mt = tail.iter().map(|e| e.0).sum::<f64>() / k;
    let my = tail.iter().map(|e| e.1).sum::<f64>() / k;
    let sxy: f64 = tail.iter().map(|e| (e.0 - mt) * (e.1 - my)).sum();
    let sxx: f64 = tail.iter().map(|e| (e.0 - mt).powi(2)).sum();
    match sxx > 0.0 && (sxy / sxx).abs() <= AT_REST_SPEED {
        true => MeasuredVerdict::NotDiverted,
        false => MeasuredVerdict::Unknown,
    }
}

/// Compare a track with a full run of `scenario` (marker at `offset` in the parcel axes).
pub fn compare(
    track: &Track,
    scenario: &Scenario,
    result: &SimResult,
    offset: DVec2,
) -> Comparison {
    compare_pinned(track, scenario, result, offset, None)
}

/// [`compare`] with what is known of the arm start ([`align_pinned`]).
pub fn compare_pinned(
    track: &Track,
    scenario: &Scenario,
    result: &SimResult,
    offset: DVec2,
    pin: Option<ArmStart>,
) -> Comparison {
    let path = MarkerPath::new(scenario, result, offset);
    let t0 = align_pinned(track, &path, pin);
    let r = residuals(track, &path, t0);
    let n = r.len().max(1) as f64;
    let rms = |f: &dyn Fn(&DVec2) -> f64| (r.iter().map(|e| f(e).powi(2)).sum::<f64>() / n).sqrt();
    let max = |f: &dyn Fn(&DVec2) -> f64| r.iter().map(|e| f(e).abs()).fold(0.0, f64::max);
    let simulated: Vec<DVec2> = track.times.iter().map(|&t| path.at(t - t0)).collect();
    // Belt speed before the first touch: least-squares slope of x(t).
    let early: Vec<(f64, f64)> = track
        .times
        .iter()
        .zip(&track.points)
        .filter(|(t, _)| **t - t0 < path.first_touch)
        .map(|(t, p)| (*t, p.x))
        .collect();
    let measured_speed = (early.len() >= 3 && scenario.parcel.velocity.is_none()).then(|| {
        let k = early.len() as f64;
        let mt = early.iter().map(|e| e.0).sum::<f64>() / k;
        let mx = early.iter().map(|e| e.1).sum::<f64>() / k;
        let sxy: f64 = early.iter().map(|e| (e.0 - mt) * (e.1 - mx)).sum();
        let sxx: f64 = early.iter().map(|e| (e.0 - mt).powi(2)).sum();
        sxy / sxx
    });
    Comparison {
        offset: t0,
        points: r.len(),
        after_end: track.times.iter().filter(|&&t| t - t0 > path.end).count(),
        rms_x: rms(&|e| e.x),
        max_x: max(&|e| e.x),
        rms_y: rms(&|e| e.y),
        max_y: max(&|e| e.y),
        rms: rms(&|e| e.length()),
        frechet: frechet(&track.points, &simulated),
        measured: measured_verdict(track, scenario.machine.belt_width),
        simulated_diverted: result.outcome == Outcome::Diverted,
        measured_speed,
    }
}

/// A synthetic track of a run, as a camera would record it: the marker at `offset` sampled
/// at `fps` from `lead` seconds before the arm start to `tail` seconds after the run's end
/// (the continuation at the final velocity: a diverted parcel crossing the far edge), the
/// video clock starting at the first frame (so the arm starts at video time `lead`), mapped
/// to pixels and rounded to whole pixels when `round` (else exact). Returns (time, pixel)
/// pairs.
#[allow(clippy::too_many_arguments)]
pub fn synthesize(
    scenario: &Scenario,
    result: &SimResult,
    offset: DVec2,
    camera: &CameraMap,
    fps: f64,
    lead: f64,
    tail: f64,
    round: bool,
) -> Vec<(f64, [f64; 2])> {
    let path = MarkerPath::new(scenario, result, offset);
    let frames = ((lead + path.end + tail) * fps).floor().max(0.0) as usize;
    (0..=frames)
        .map(|k| {
            let t = k as f64 / fps;
            let mut px = camera.to_pixel(path.at(t - lead));
            if round {
                px = px.map(f64::round);
            }
            (t, px)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::simulate;
    use approx::assert_relative_eq;

    fn paper_camera() -> CameraMap {
        // 304 px per 0.6 m, origin at pixel (40, 440), x to the right, y up the image.
        CameraMap::square(304.0 / 0.6, [40.0, 440.0], [1.0, 0.0], [0.0, -1.0]).unwrap()
    }

    #[test]
    fn square_camera_and_its_homography_agree() {
        let c = paper_camera();
        let p = c.to_machine([344.0, 440.0]);
        assert_relative_eq!(p.x, 0.6, epsilon = 1e-12);
        assert_relative_eq!(p.y, 0.0, epsilon = 1e-12);
        let q = c.to_machine([40.0, 136.0]);
        assert_relative_eq!(q.y, 0.6, epsilon = 1e-12);
        // The same map from four points.
        let pts = [[40.0, 440.0], [600.0, 440.0], [600.0, 60.0], [40.0, 60.0]];
        let pairs = pts.map(|px| (px, c.to_machine(px).to_array()));
        let h = CameraMap::from_points(&pairs).unwrap();
        for px in [[100.0, 200.0], [333.0, 17.0]] {
            assert!((h.to_machine(px) - c.to_machine(px)).length() < 1e-9);
            let back = h.to_pixel(h.to_machine(px));
            assert!((back[0] - px[0]).abs() < 1e-9 && (back[1] - px[1]).abs() < 1e-9);
        }
        // Quantisation: 0.6/304/√12 m per axis.
        let s = c.quantisation_sigma([200.0, 200.0]);
        assert_relative_eq!(s.x, 0.6 / 304.0 / 12f64.sqrt(), max_relative = 1e-6);
    }

    #[test]
    fn oblique_camera_maps_its_reference_points() {
        let pairs = [
            ([102.0, 410.0], [0.0, 0.0]),
            ([590.0, 380.0], [1.0, 0.0]),
            ([540.0, 90.0], [1.0, 0.7]),
            ([150.0, 70.0], [0.0, 0.7]),
        ];
        let c = CameraMap::from_points(&pairs).unwrap();
        for (px, m) in pairs {
            assert!((c.to_machine(px) - DVec2::from(m)).length() < 1e-9);
        }
        let line = [
            ([0.0, 0.0], [0.0, 0.0]),
            ([1.0, 1.0], [1.0, 0.0]),
            ([2.0, 2.0], [2.0, 0.0]),
            ([0.0, 5.0], [0.0, 1.0]),
        ];
        assert!(CameraMap::from_points(&line).is_err());
        assert!(CameraMap::square(0.0, [0.0, 0.0], [1.0, 0.0], [0.0, 1.0]).is_err());
        assert!(CameraMap::square(1.0, [0.0, 0.0], [1.0, 0.0], [2.0, 0.0]).is_err());
    }

    #[test]
    fn frechet_of_simple_polylines() {
        let a = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(2.0, 0.0),
        ];
        let b = [DVec2::new(0.0, 1.0), DVec2::new(2.0, 1.0)];
        assert_relative_eq!(frechet(&a, &b), 2f64.sqrt());
        assert_eq!(frechet(&a, &a), 0.0);
    }

    /// A synthetic track of a run, unrounded, aligns back to its true offset and compares
    /// with errors at the interpolation level; rounded, at the pixel level.
    #[test]
    fn synthetic_track_aligns_and_compares() {
        let s = Scenario::paper_default();
        let r = simulate(&s);
        let cam = paper_camera();
        for (round, tol) in [(false, 2e-4), (true, 2e-3)] {
            let frames = synthesize(&s, &r, DVec2::ZERO, &cam, 25.0, 0.3, 0.1, round);
            let track = Track {
                times: frames.iter().map(|f| f.0).collect(),
                points: frames.iter().map(|f| cam.to_machine(f.1)).collect(),
                sigma: frames.iter().map(|f| cam.quantisation_sigma(f.1)).collect(),
            };
            let c = compare(&track, &s, &r, DVec2::ZERO);
            assert!((c.offset - 0.3).abs() < 2e-3, "offset {}", c.offset);
            assert!(c.rms < tol, "rms {}", c.rms);
            assert_eq!(c.verdicts_agree(), Some(true));
            let v = c.measured_speed.unwrap();
            assert!((v - 2.0).abs() < 0.02, "speed {v}");
        }
    }

    /// Issue 27 (C10): a track that leaves the camera's field of view before the far edge
    /// is no measurement of "not diverted". The paper default's diverted run, cut where the
    /// marker is half-way from its start to the far edge, gives `Unknown` and no verdict disagreement; a parcel
    /// riding on at the end (not diverted) and one reaching the far edge keep their verdicts.
    #[test]
    fn a_track_cut_before_the_far_edge_gives_no_false_verdict() {
        let s = Scenario::paper_default();
        let r = simulate(&s);
        assert_eq!(r.outcome, Outcome::Diverted);
        let cam = paper_camera();
        let frames = synthesize(&s, &r, DVec2::ZERO, &cam, 100.0, 0.3, 0.1, false);
        let whole = Track {
            times: frames.iter().map(|f| f.0).collect(),
            points: frames.iter().map(|f| cam.to_machine(f.1)).collect(),
            sigma: frames.iter().map(|f| cam.quantisation_sigma(f.1)).collect(),
        };
        let p_max = s.machine.belt_width;
        assert_eq!(measured_verdict(&whole, p_max), MeasuredVerdict::Diverted);
        let half = 0.5 * (whole.points[0].y + p_max);
        let keep = whole.points.iter().take_while(|p| p.y < half).count();
        let cut = Track {
            times: whole.times[..keep].to_vec(),
            points: whole.points[..keep].to_vec(),
            sigma: whole.sigma[..keep].to_vec(),
        };
        assert!(keep > 10 && keep < whole.points.len());
        assert_eq!(measured_verdict(&cut, p_max), MeasuredVerdict::Unknown);
        let c = compare(&cut, &s, &r, DVec2::ZERO);
        assert_eq!(c.measured, MeasuredVerdict::Unknown);
        assert_eq!(c.verdicts_agree(), None);
        // Riding on at the end: the same track, every point shifted to ride along at the
        // belt speed after a lateral stop half-way.
        let stop = keep;
        let riding = Track {
            times: whole.times.clone(),
            points: whole
                .times
                .iter()
                .enumerate()
                .map(|(i, &t)| {
                    let j = i.min(stop);
                    let p = whole.points[j];
                    DVec2::new(p.x + 2.0 * (t - whole.times[j]), p.y)
                })
                .collect(),
            sigma: whole.sigma.clone(),
        };
        assert_eq!(
            measured_verdict(&riding, p_max),
            MeasuredVerdict::NotDiverted
        );
    }

    /// Issue 27 (C13): a known arm start pins t₀; a window keeps the search inside it, even
    /// where the free search would find a better-looking offset elsewhere.
    #[test]
    fn a_pinned_arm_start_fixes_or_bounds_the_alignment() {
        let s = Scenario::paper_default();
        let r = simulate(&s);
        let cam = paper_camera();
        let frames = synthesize(&s, &r, DVec2::ZERO, &cam, 25.0, 0.3, 0.1, false);
        let track = Track {
            times: frames.iter().map(|f| f.0).collect(),
            points: frames.iter().map(|f| cam.to_machine(f.1)).collect(),
            sigma: frames.iter().map(|f| cam.quantisation_sigma(f.1)).collect(),
        };
        let path = MarkerPath::new(&s, &r, DVec2::ZERO);
        let free = align(&track, &path);
        assert!((free - 0.3).abs() < 1e-6, "{free}");
        let exact = ArmStart {
            time: 0.25,
            within: 0.0,
        };
        assert_eq!(align_pinned(&track, &path, Some(exact)), 0.25);
        let window = ArmStart {
            time: 0.2,
            within: 0.05,
        };
        let t0 = align_pinned(&track, &path, Some(window));
        assert!((0.15..=0.25).contains(&t0), "{t0}");
        assert!(
            (t0 - 0.25).abs() < 1e-6,
            "the window's edge nearest the truth: {t0}"
        );
        let wide = ArmStart {
            time: 0.3,
            within: 0.1,
        };
        assert!((align_pinned(&track, &path, Some(wide)) - free).abs() < 1e-9);
        let c = compare_pinned(&track, &s, &r, DVec2::ZERO, Some(exact));
        assert_eq!(c.offset, 0.25);
        assert!(c.rms > 0.01, "a wrong pin shows in the fit: {}", c.rms);
    }

    /// Regression (review of issue 14): the sample before a strike was dropped, so the
    /// segment into the strike bent with the velocity after it.
    #[test]
    fn marker_path_keeps_the_velocity_before_a_strike() {
        let s = Scenario::paper_default();
        let r = simulate(&s);
        let ti = r.impacts[0].t;
        let before = r
            .trajectory
            .iter()
            .rfind(|x| x.state.t < ti)
            .map(|x| x.state)
            .unwrap();
        let path = MarkerPath::new(&s, &r, DVec2::ZERO);
        let d = 1e-7;
        let v = (path.at(ti - d) - path.at(ti - 2.0 * d)) / d;
        // The pre-strike velocity, not the post-strike one (which differs by about 1 m/s).
        let pre = r
            .trajectory
            .iter()
            .find(|x| x.state.t == ti)
            .map(|x| DVec2::new(x.state.vx, x.state.vy))
            .unwrap();
        assert!(
            (v - pre).length() < 1e-3,
            "{v} against {pre} (sample before at {})",
            before.t
        );
    }

    /// Regression (review of issue 14): offsets were scanned only around the track's middle,
    /// so a long lead-in before the arm start was never aligned.
    #[test]
    fn alignment_finds_a_long_lead() {
        let s = Scenario::paper_default();
        let r = simulate(&s);
        let cam = paper_camera();
        let frames = synthesize(&s, &r, DVec2::ZERO, &cam, 25.0, 4.0, 0.0, false);
        let track = Track {
            times: frames.iter().map(|f| f.0).collect(),
            points: frames.iter().map(|f| cam.to_machine(f.1)).collect(),
            sigma: vec![DVec2::ZERO; frames.len()],
        };
        let path = MarkerPath::new(&s, &r, DVec2::ZERO);
        assert!((align(&track, &path) - 4.0).abs() < 1e-6);
    }

    #[test]
    fn marker_offset_rotates_with_the_parcel() {
        let s = Scenario::paper_default();
        let r = simulate(&s);
        let o = DVec2::new(0.1, 0.0);
        let path = MarkerPath::new(&s, &r, o);
        let last = r.trajectory.last().unwrap().state;
        let p = path.at(last.t);
        let want = DVec2::new(last.x, last.y) + DVec2::from_angle(last.phi).rotate(o);
        assert!((p - want).length() < 1e-12);
        // Before the arm start the marker rides with the belt.
        let p0 = path.at(0.0);
        assert!((path.at(-0.5) - (p0 - DVec2::new(1.0, 0.0))).length() < 1e-12);
    }

    /// Hostile input round three: a video clock in Unix time hung `compare` and
    /// `calibrate` (the golden section's 1e-9 s target is below the float spacing at
    /// 1.7e9 s). The same track with its clock shifted aligns to the same offset.
    #[test]
    fn track_in_unix_time_aligns_like_its_relative_copy() {
        let s = Scenario::paper_default();
        let r = simulate(&s);
        let cam = paper_camera();
        let frames = synthesize(&s, &r, DVec2::ZERO, &cam, 25.0, 1.0, 0.2, false);
        let track = |origin: f64| Track {
            times: frames.iter().map(|f| f.0 + origin).collect(),
            points: frames.iter().map(|f| cam.to_machine(f.1)).collect(),
            sigma: vec![DVec2::ZERO; frames.len()],
        };
        let path = MarkerPath::new(&s, &r, DVec2::ZERO);
        let plain = align(&track(0.0), &path);
        assert!((plain - 1.0).abs() < 1e-6, "{plain}");
        for origin in [1.7e9, -3.2e7, 1e12] {
            let t0 = align(&track(origin), &path);
            // The shifted times themselves are rounded to their float spacing.
            let spacing = f64::EPSILON * origin.abs() * 4.0;
            assert!(
                (t0 - origin - plain).abs() < 1e-6 + spacing,
                "origin {origin}: {t0}"
            );
        }
    }

    /// A track fuzz test (hostile input round three): random clocks (Unix time, negative,
    /// 10¹²), frame rates from one frame in 10⁶ s to 10⁵ fps, lengths 1–3,000 and one of
    /// 10⁶ points, positions on the path, noisy or garbage, repeated times. Every alignment
    /// returns a finite offset, and its work (point evaluations) is bounded by a multiple
    /// of the track's length.
    #[test]
    fn track_fuzz_alignment_work_is_bounded_by_the_tracks_length() {
        let s = Scenario::paper_default();
        let r = simulate(&s);
        let path = MarkerPath::new(&s, &r, DVec2::ZERO);
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let origins = [0.0, 1.7e9, 1_700_000_000.123, -3.2e7, 1e12, 4.5e15];
        let rates = [1e-6, 1e-3, 0.5, 25.0, 1000.0, 1e5];
        let levels = 64 + 1;
        let bound = |n: usize| {
            let scanned = n.min(SCAN_POINTS) as u64;
            (SCAN_OFFSETS as u64 + 1 + levels * (REFINE_OFFSETS as u64 + 1)) * scanned
                + (GOLDEN_STEPS as u64 + 3) * n as u64
        };
        for case in 0..61 {
            let n = if case == 60 {
                1_000_000
            } else {
                1 + (next() * 3000.0) as usize
            };
            let origin = origins[case % origins.len()];
            let fps = rates[(case / origins.len()) % rates.len()];
            let lead = next() * 2.0;
            let times: Vec<f64> = (0..n)
                .map(|i| {
                    let t = origin + i as f64 / fps;
                    // Now and then a repeated time stamp.
                    if i > 0 && case % 7 == 3 && i % 5 == 0 {
                        origin + (i - 1) as f64 / fps
                    } else {
                        t
                    }
                })
                .collect();
            let points: Vec<DVec2> = times
                .iter()
                .map(|&t| match case % 3 {
                    0 => path.at(t - origin - lead),
                    1 => path.at(t - origin - lead) + DVec2::new(next() - 0.5, next() - 0.5) * 1e-3,
                    _ => DVec2::new(next() * 1e3 - 500.0, next() * 1e3 - 500.0),
                })
                .collect();
            let track = Track {
                sigma: vec![DVec2::ZERO; n],
                times,
                points,
            };
            let (t0, work) = align_counted(&track, &path);
            assert!(t0.is_finite(), "case {case}: offset {t0}");
            assert!(
                work <= bound(n),
                "case {case}: {work} evaluations for {n} points (bound {})",
                bound(n)
            );
            // Where the track overlaps the run, exact positions give the exact offset.
            let span = (n - 1) as f64 / fps;
            if case % 3 == 0 && fps >= 25.0 && origin.abs() < 1e10 && lead + 0.1 < span {
                assert!(
                    (t0 - origin - lead).abs() < 1e-5,
                    "case {case}: n {n} fps {fps} lead {lead}: {}",
                    t0 - origin
                );
            }
        }
    }

    /// The banded Fréchet distance of long polylines: the exact one where the table fits,
    /// an upper bound of it beyond, and linear work for a 10⁶-point track.
    #[test]
    fn frechet_of_long_polylines_is_banded_and_exact_on_the_diagonal() {
        let a: Vec<DVec2> = (0..3000)
            .map(|i| DVec2::new(i as f64 * 0.01, 0.0))
            .collect();
        let b: Vec<DVec2> = a.iter().map(|p| *p + DVec2::new(0.0, 0.002)).collect();
        assert!((frechet(&a, &b) - 0.002).abs() < 1e-15);
        let long: Vec<DVec2> = (0..1_000_000)
            .map(|i| DVec2::new(i as f64 * 1e-3, 0.0))
            .collect();
        let shifted: Vec<DVec2> = long.iter().map(|p| *p + DVec2::new(0.0, 0.001)).collect();
        assert!((frechet(&long, &shifted) - 0.001).abs() < 1e-15);
    }
}
