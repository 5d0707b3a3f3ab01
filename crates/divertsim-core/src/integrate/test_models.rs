//! Test models with analytic solutions, shared by the stepper and event tests.

use super::{Direction, HybridSystem};

/// y' = −y; y(t) = y0 e^{−(t − t0)}.
pub struct Decay;

impl HybridSystem<1> for Decay {
    fn rhs(&self, _t: f64, y: &[f64; 1]) -> [f64; 1] {
        [-y[0]]
    }
    fn begin_step_changes_rhs(&self) -> bool {
        false
    }
}

/// Harmonic oscillator x' = v, v' = −ω² x, optionally with the guard x − c.
pub struct Oscillator {
    /// ω [rad/s].
    pub omega: f64,
    /// Guard threshold c and direction.
    pub threshold: Option<(f64, Direction)>,
}

impl Oscillator {
    pub fn free(omega: f64) -> Self {
        Oscillator {
            omega,
            threshold: None,
        }
    }
    /// Exact state at t from (x0, v0) at 0.
    pub fn exact(&self, t: f64, y0: [f64; 2]) -> [f64; 2] {
        let w = self.omega;
        let (s, c) = (w * t).sin_cos();
        [y0[0] * c + y0[1] / w * s, -y0[0] * w * s + y0[1] * c]
    }
}

impl HybridSystem<2> for Oscillator {
    fn rhs(&self, _t: f64, y: &[f64; 2]) -> [f64; 2] {
        [y[1], -self.omega * self.omega * y[0]]
    }
    fn guard_count(&self) -> usize {
        usize::from(self.threshold.is_some())
    }
    fn guard(&self, _i: usize, _t: f64, y: &[f64; 2]) -> f64 {
        y[0] - self.threshold.map_or(0.0, |(c, _)| c)
    }
    fn guard_direction(&self, _i: usize) -> Direction {
        self.threshold.map_or(Direction::Either, |(_, d)| d)
    }
}

/// Plane rotation y' = ω (−y₁, y₀): |y| is conserved, y(t) = R(ωt) y0.
pub struct Rotation {
    /// ω [rad/s].
    pub omega: f64,
}

impl Rotation {
    pub fn exact(&self, t: f64, y0: [f64; 2]) -> [f64; 2] {
        let (s, c) = (self.omega * t).sin_cos();
        [c * y0[0] - s * y0[1], s * y0[0] + c * y0[1]]
    }
}

impl HybridSystem<2> for Rotation {
    fn rhs(&self, _t: f64, y: &[f64; 2]) -> [f64; 2] {
        [-self.omega * y[1], self.omega * y[0]]
    }
}

/// y' = y², y(0) = 1: y = 1/(1 − t), blows up at t = 1.
pub struct BlowUp;

impl HybridSystem<1> for BlowUp {
    fn rhs(&self, _t: f64, y: &[f64; 1]) -> [f64; 1] {
        [y[0] * y[0]]
    }
}

/// Bouncing ball: h' = v, v' = −g, guard 0 = h (Falling).
pub struct BouncingBall {
    /// g [m/s²].
    pub g: f64,
}

impl BouncingBall {
    /// Analytic impact times from rest at height h0 with restitution e.
    pub fn impact_times(&self, h0: f64, e: f64, n: usize) -> Vec<f64> {
        let t1 = (2.0 * h0 / self.g).sqrt();
        let v1 = self.g * t1;
        let mut out = vec![t1];
        let mut v = v1;
        for _ in 1..n {
            v *= e;
            let last = *out.last().unwrap_or(&0.0);
            out.push(last + 2.0 * v / self.g);
        }
        out
    }
}

impl HybridSystem<2> for BouncingBall {
    fn rhs(&self, _t: f64, y: &[f64; 2]) -> [f64; 2] {
        [y[1], -self.g]
    }
    fn guard_count(&self) -> usize {
        1
    }
    fn guard(&self, _i: usize, _t: f64, y: &[f64; 2]) -> f64 {
        y[0]
    }
    fn guard_direction(&self, _i: usize) -> Direction {
        Direction::Falling
    }
    fn begin_step_changes_rhs(&self) -> bool {
        false
    }
}

/// y' = 0 with guards that are functions of t only (exact event times).
pub struct TimeGuards<F: Fn(usize, f64) -> f64> {
    pub guards: F,
    pub directions: Vec<Direction>,
}

impl<F: Fn(usize, f64) -> f64> HybridSystem<1> for TimeGuards<F> {
    fn rhs(&self, _t: f64, _y: &[f64; 1]) -> [f64; 1] {
        [0.0]
    }
    fn guard_count(&self) -> usize {
        self.directions.len()
    }
    fn guard(&self, i: usize, t: f64, _y: &[f64; 1]) -> f64 {
        (self.guards)(i, t)
    }
    fn guard_direction(&self, i: usize) -> Direction {
        self.directions[i]
    }
}

/// y' = −y before `t_bad`, NaN from then on.
pub struct NanAfter {
    pub t_bad: f64,
}

impl HybridSystem<1> for NanAfter {
    fn rhs(&self, t: f64, y: &[f64; 1]) -> [f64; 1] {
        if t >= self.t_bad {
            [f64::NAN]
        } else {
            [-y[0]]
        }
    }
}

/// The free oscillator that records every `begin_step` call.
pub struct Recording {
    pub inner: Oscillator,
    pub calls: Vec<(f64, [f64; 2])>,
}

impl HybridSystem<2> for Recording {
    fn rhs(&self, t: f64, y: &[f64; 2]) -> [f64; 2] {
        self.inner.rhs(t, y)
    }
    fn begin_step(&mut self, t: f64, y: &[f64; 2]) {
        self.calls.push((t, *y));
    }
}
