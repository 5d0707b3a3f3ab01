//! Arm drive: the prescribed arm angle α(t) and its derivatives over one working cycle.
//!
//! Kinds (docs/model.md §2): the crank-rocker four-bar (vector-loop closure, crank at
//! constant speed 2π/t_c starting from the retracted dead centre) and the cam laws
//! (simple harmonic, cycloidal, 3-4-5 polynomial; rise in t_c/2, symmetric return), plus a
//! tabulated α(t) interpolated by a clamped cubic spline. Every kind starts and ends the cycle
//! at rest at α = 0; outside [0, t_c] the arm rests at α = 0.
//!
//! Four-bar conventions (docs/model.md §2): O₂ (crank pivot) at the local origin, O₄ (arm pivot)
//! at (d, 0); loop a e^{iθ₂} + b e^{iθ₃} − c e^{iθ₄} − d = 0; assembly branch σ = −1 (the rocker
//! lies on the +ỹ side of the ground line); the crank turns counter-clockwise,
//! θ₂(t) = θ₂₀ + ω₂ t with ω₂ = 2π/t_c, θ₂₀ the crank angle of the retracted dead centre. On
//! this branch θ₄ is smallest when crank and coupler are extended (|O₂B| = b + a), so the arm
//! is retracted (α = θ₄ − θ₄,min = 0) at the extended dead centre and fully out at the folded
//! one (|O₂B| = b − a). This reproduces the reference table of model.md §2. For a design with time
//! ratio Q ≠ 1 the out-stroke takes the crank angle θ₂,out − θ₂₀ ≠ π, so α_max is reached at
//! [`ArmDrive::out_stroke_time`], not at t_c/2 (mirror the design to swap the strokes).
//!
//! Tables: the clamped spline (zero end slopes) gives a continuous α̇ and a piecewise-linear α̈.
//! A table whose spline would dip below α = 0 (the arm passing behind its retracted position,
//! where the side guide is) is rejected, as is every malformed table.
//!
//! References: docs/model.md §2; R. L. Norton, *Design of Machinery* (vector-loop analysis,
//! Grashof condition, cam laws); C. de Boor, *A Practical Guide to Splines* (clamped spline).

use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// α, α̇, α̈ of the arm at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ArmState {
    /// α: arm angle from the belt axis \[rad]
    pub angle: f64,
    /// α̇: arm angular velocity [rad/s]
    pub rate: f64,
    /// α̈: arm angular acceleration [rad/s²]
    pub accel: f64,
}

/// Link lengths of a crank-rocker four-bar whose rocker is the arm (model.md §2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FourBar {
    /// a: crank length \[m]
    pub crank: f64,
    /// b: coupler length \[m]
    pub coupler: f64,
    /// c: rocker length \[m]
    pub rocker: f64,
    /// d: ground link O₂O₄ \[m]
    pub ground: f64,
}

/// The two dead centres of a crank-rocker (model.md §2), branch σ = −1, local frame with
/// O₂ at the origin and O₄ at (d, 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeadCentres {
    /// θ₂ at the retracted dead centre (crank and coupler extended, α = 0) \[rad], in (−π, π]
    pub crank_retracted: f64,
    /// θ₂ at the out dead centre (crank and coupler folded, α = α_max) \[rad], in
    /// (crank_retracted, crank_retracted + 2π): the out-stroke turns the crank by the difference
    pub crank_out: f64,
    /// θ₄,min: rocker angle at the retracted dead centre \[rad]
    pub rocker_min: f64,
    /// θ₄,max: rocker angle at the out dead centre \[rad]
    pub rocker_max: f64,
}

/// Which motion law drives the arm, with its parameters.
#[derive(Debug, Clone, PartialEq)]
pub enum DriveSpec {
    /// Crank-rocker four-bar, crank at 2π/t_c.
    CrankRocker(FourBar),
    /// Cycloidal rise to `max_swing` \[rad] in t_c/2, symmetric return.
    Cycloidal { max_swing: f64 },
    /// Simple harmonic rise and return.
    Harmonic { max_swing: f64 },
    /// 3-4-5 polynomial rise and return.
    Poly345 { max_swing: f64 },
    /// Tabulated α(t): `times` \[s] strictly increasing from 0, `angles` \[rad], starting and
    /// ending at 0. The time axis is scaled so that the last time equals t_c.
    Table { times: Vec<f64>, angles: Vec<f64> },
}

/// Why a drive cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DriveError {
    #[error("{0}")]
    Invalid(String),
}

/// A drive ready to evaluate: the spec plus the cycle time and anything precomputed.
#[derive(Debug, Clone)]
pub struct ArmDrive {
    /// t_c: cycle time \[s]
    cycle_time: f64,
    /// α_max \[rad]
    max_swing: f64,
    /// Time of α_max from the arm start \[s]
    out_stroke_time: f64,
    /// Proven bounds on |α̇| [rad/s] and |α̈| [rad/s²] over the cycle ([`ArmDrive::rate_bound`]).
    bounds: (f64, f64),
    law: Law,
}

/// A motion law with everything precomputed for allocation-free evaluation.
#[derive(Debug, Clone)]
enum Law {
    CrankRocker(CrankRocker),
    /// Rise 0 → α_max in T_r = t_c/2, then the mirror-image return.
    Cam {
        shape: CamShape,
        /// α_max \[rad]
        max_swing: f64,
        /// T_r = t_c/2 \[s]
        rise_time: f64,
    },
    Table(Spline),
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum CamShape {
    Harmonic,
    Cycloidal,
    Poly345,
}

/// Largest |α| at the ends of a table that still counts as "at rest at 0" \[rad].
const TABLE_END_TOL: f64 = 1e-12;

fn invalid(msg: String) -> DriveError {
    DriveError::Invalid(msg)
}

impl FourBar {
    /// The centred (time ratio 1) design for a swing ψ \[rad] with the given coupler b and
    /// rocker c: a = c sin(ψ/2), d = √(b² + c² cos²(ψ/2)) (model.md §2).
    ///
    /// No validation here: [`ArmDrive::new`] and [`FourBar::swing`] check the result.
    pub fn centred(swing: f64, coupler: f64, rocker: f64) -> FourBar {
        let (s, c) = (0.5 * swing).sin_cos();
        FourBar {
            crank: rocker * s,
            coupler,
            rocker,
            ground: coupler.hypot(rocker * c),
        }
    }

    /// The default design of model.md §2: ψ = 45°, b = 0.3 m, c = 0.15 m.
    pub fn paper_default() -> FourBar {
        FourBar::centred(std::f64::consts::FRAC_PI_4, 0.3, 0.15)
    }

    /// Checks that the links form a Grashof crank-rocker whose crank a is the shortest link:
    /// all lengths finite and > 0, and s + l < p + q. Equality (a change-point linkage) is
    /// rejected too: its links fold flat once per turn, where the transmission angle is 0 or
    /// 180° and the loop velocity is 0/0.
    pub fn validate(&self) -> Result<(), DriveError> {
        let FourBar {
            crank: a,
            coupler: b,
            rocker: c,
            ground: d,
        } = *self;
        for (name, sym, v) in [
            ("crank", 'a', a),
            ("coupler", 'b', b),
            ("rocker", 'c', c),
            ("ground", 'd', d),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(invalid(format!(
                    "four-bar {name} length {sym} = {v} m must be finite and > 0"
                )));
            }
        }
        let links = format!("links a={a} m, b={b} m, c={c} m, d={d} m");
        let others = [("coupler b", b), ("rocker c", c), ("ground d", d)];
        if let Some((name, v)) = others.iter().find(|(_, v)| *v < a) {
            return Err(invalid(format!(
                "{links} do not form a crank-rocker: the crank a must be the shortest link, \
                 but the {name} = {v} m is shorter"
            )));
        }
        let l = others.iter().fold(a, |l, &(_, v)| l.max(v));
        let s = a;
        let pq = a + b + c + d - s - l;
        if s + l > pq {
            return Err(invalid(format!(
                "{links} do not form a crank-rocker: shortest + longest = {} m exceeds the sum \
                 of the other two = {} m (Grashof condition s + l ≤ p + q violated)",
                s + l,
                pq
            )));
        }
        if pq - (s + l) <= 1e-9 * pq {
            return Err(invalid(format!(
                "{links} form a change-point linkage: shortest + longest = {} m equals the sum \
                 of the other two = {} m, so the links fold flat once per turn and the motion \
                 is undefined there; shorten the crank",
                s + l,
                pq
            )));
        }
        Ok(())
    }

    /// ψ₂ − ψ₁: the rocker swing \[rad] from the design relations of model.md §2,
    /// cos ψ₁,₂ = (c² + d² − (b ∓ a)²)/(2cd). Errors if the links are not a crank-rocker.
    pub fn swing(&self) -> Result<f64, DriveError> {
        let dc = self.dead_centres()?;
        Ok(dc.rocker_max - dc.rocker_min)
    }

    /// The dead centres (crank angles θ₂ and rocker extremes θ₄) of model.md §2 on branch
    /// σ = −1. Errors if the links are not a crank-rocker.
    pub fn dead_centres(&self) -> Result<DeadCentres, DriveError> {
        self.validate()?;
        let FourBar {
            crank: a,
            coupler: b,
            rocker: c,
            ground: d,
        } = *self;
        // ψ: angle at O₄ from O₄O₂ to O₄B; the rocker stays on one side, so θ₄ = π − ψ.
        let psi = |ob: f64| {
            ((c * c + d * d - ob * ob) / (2.0 * c * d))
                .clamp(-1.0, 1.0)
                .acos()
        };
        let (psi1, psi2) = (psi(b - a), psi(b + a));
        let rocker_min = PI - psi2;
        let rocker_max = PI - psi1;
        let b_at = |th4: f64| (d + c * th4.cos(), c * th4.sin());
        // Extended: A lies on O₂B; folded: A lies opposite to B.
        let (bx, by) = b_at(rocker_min);
        let crank_retracted = by.atan2(bx);
        let (fx, fy) = b_at(rocker_max);
        let out = (-fy).atan2(-fx);
        let crank_out = crank_retracted + (out - crank_retracted).rem_euclid(TAU);
        Ok(DeadCentres {
            crank_retracted,
            crank_out,
            rocker_min,
            rocker_max,
        })
    }
}

/// Position, velocity and acceleration of the loop at one crank angle.
#[derive(Debug, Clone, Copy)]
struct LoopState {
    /// θ₄ \[rad], continuous along the branch
    theta4: f64,
    /// sin θ₄, cos θ₄
    sin4: f64,
    cos4: f64,
    /// sin(θ₄ − θ₃), cos(θ₄ − θ₃): the transmission angle's sine and cosine
    sin_mu: f64,
    cos_mu: f64,
    /// ω₄ [rad/s]
    omega4: f64,
    /// α₄ [rad/s²]
    alpha4: f64,
}

/// A validated crank-rocker with its dead centres.
#[derive(Debug, Clone)]
struct CrankRocker {
    a: f64,
    b: f64,
    c: f64,
    d: f64,
    /// ω₂ = 2π/t_c [rad/s]
    omega2: f64,
    /// θ₂₀: crank angle of the retracted dead centre \[rad]
    theta2_0: f64,
    /// θ₄,min \[rad], evaluated through the same loop closure so that α(0) = 0 exactly
    theta4_min: f64,
    /// sin θ₄,min, cos θ₄,min
    sin_min: f64,
    cos_min: f64,
}

impl CrankRocker {
    /// Vector-loop closure of model.md §2 at crank angle θ₂, branch σ = −1, α₂ = 0.
    fn solve(&self, theta2: f64) -> LoopState {
        let (a, b, c, d, w2) = (self.a, self.b, self.c, self.d, self.omega2);
        let (s2, c2) = theta2.sin_cos();
        let (ax, ay) = (a * c2, a * s2);
        let (dx, dy) = (ax - d, ay);
        let l = (dx * dx + dy * dy).sqrt();
        // θ₄ = ∠(O₄→A) − γ with cos γ from the triangle O₄AB, γ ∈ [0, π]. Its sine and
        // cosine follow by the difference formulas, without trigonometric calls; θ₄ itself
        // lies in [0, π] (between the dead centres' rocker angles), where atan2 is continuous.
        let (dir_c, dir_s) = (dx / l, dy / l);
        let cos_g = ((c * c + l * l - b * b) / (2.0 * c * l)).clamp(-1.0, 1.0);
        let sin_g = (1.0 - cos_g * cos_g).sqrt();
        let c4 = dir_c * cos_g + dir_s * sin_g;
        let s4 = dir_s * cos_g - dir_c * sin_g;
        let theta4 = s4.atan2(c4);
        // Coupler direction e^{iθ₃} = (B − A)/b; the sines and cosines of the angle
        // differences in the loop equations are cross and dot products of unit vectors (no more
        // trig).
        let (e3x, e3y) = ((d + c * c4 - ax) / b, (c * s4 - ay) / b);
        let sin32 = c2 * e3y - s2 * e3x;
        let cos32 = c2 * e3x + s2 * e3y;
        let sin42 = c2 * s4 - s2 * c4;
        let sin34 = c4 * e3y - s4 * e3x;
        let cos34 = c4 * e3x + s4 * e3y;
        let omega4 = a * w2 * sin32 / (c * sin34);
        let omega3 = a * w2 * sin42 / (b * sin34);
        let alpha4 = (-a * w2 * w2 * cos32 - b * omega3 * omega3 + c * omega4 * omega4 * cos34)
            / (c * sin34);
        LoopState {
            theta4,
            sin4: s4,
            cos4: c4,
            sin_mu: -sin34,
            cos_mu: cos34,
            omega4,
            alpha4,
        }
    }

    fn state(&self, t: f64) -> ArmState {
        self.state_trig(t).0
    }

    /// Bounds on |ω₄| and |α₄| over the whole turn from the transmission angle μ.
    ///
    /// By the law of cosines in the triangle A B O₄, |AO₄|² = L² = b² + c² − 2bc cos μ, and
    /// L² = a² + d² − 2ad cos θ₂ ranges over [(d − a)², (d + a)²]; cos μ falls with L², so μ
    /// stays within [μ₁, μ₂] ⊂ (0, π) of the crank collinear with the ground (θ₂ = 0, π),
    /// and sin μ ≥ s = min(sin μ₁, sin μ₂) (sine is concave on [0, π]). With |sin θ₃₄| = sin μ
    /// and every other sine and cosine of the loop equations at most 1:
    /// |ω₄| ≤ a ω₂/(c s), |ω₃| ≤ a ω₂/(b s), |α₄| ≤ (a ω₂² + b ω₃,max² + c ω₄,max²)/(c s).
    fn bounds(&self) -> (f64, f64) {
        let (a, b, c, d, w2) = (self.a, self.b, self.c, self.d, self.omega2);
        let sin_mu = |l: f64| {
            let cos = ((b * b + c * c - l * l) / (2.0 * b * c)).clamp(-1.0, 1.0);
            (1.0 - cos * cos).sqrt()
        };
        let s = sin_mu(d - a).min(sin_mu(d + a));
        let w4 = a * w2 / (c * s);
        let w3 = a * w2 / (b * s);
        let a4 = (a * w2 * w2 + b * w3 * w3 + c * w4 * w4) / (c * s);
        // Rounding of the evaluation itself: a relative hair above the proven bound.
        (w4 * (1.0 + 1e-12), a4 * (1.0 + 1e-12))
    }

    /// The state with (sin α, cos α), α = θ₄ − θ₄,min by the difference formulas.
    fn state_trig(&self, t: f64) -> (ArmState, (f64, f64)) {
        let ls = self.solve(self.theta2_0 + self.omega2 * t);
        let state = ArmState {
            angle: ls.theta4 - self.theta4_min,
            rate: ls.omega4,
            accel: ls.alpha4,
        };
        let sin = ls.sin4 * self.cos_min - ls.cos4 * self.sin_min;
        let cos = ls.cos4 * self.cos_min + ls.sin4 * self.sin_min;
        (state, (sin, cos))
    }
}

impl CamShape {
    /// The largest |d/dτ| and |d²/dτ²| of the rise law over τ ∈ [0, 1] (model.md §2),
    /// exact: harmonic π/2 at τ = ½ and π²/2 at the ends; cycloidal 2 at τ = ½ and 2π at
    /// τ = ¼, ¾; 3-4-5 polynomial 15/8 at τ = ½ and 10√3/3 at τ = (3 ∓ √3)/6 (the roots of
    /// the jerk 60(1 − 6τ + 6τ²)).
    fn peaks(self) -> (f64, f64) {
        match self {
            CamShape::Harmonic => (0.5 * PI, 0.5 * PI * PI),
            CamShape::Cycloidal => (2.0, TAU),
            CamShape::Poly345 => (15.0 / 8.0, 10.0 * 3f64.sqrt() / 3.0),
        }
    }

    /// (α/α_max, d/dτ, d²/dτ²) of the rise law at τ ∈ [0, 1] (model.md §2).
    fn rise(self, tau: f64) -> (f64, f64, f64) {
        match self {
            CamShape::Harmonic => {
                let (s, c) = (PI * tau).sin_cos();
                (0.5 * (1.0 - c), 0.5 * PI * s, 0.5 * PI * PI * c)
            }
            CamShape::Cycloidal => {
                let (s, c) = (TAU * tau).sin_cos();
                (tau - s / TAU, 1.0 - c, TAU * s)
            }
            CamShape::Poly345 => {
                let t2 = tau * tau;
                (
                    t2 * tau * (10.0 + tau * (-15.0 + 6.0 * tau)),
                    30.0 * t2 * (1.0 - tau) * (1.0 - tau),
                    60.0 * tau * (1.0 + tau * (-3.0 + 2.0 * tau)),
                )
            }
        }
    }
}

/// Clamped cubic spline with zero end slopes, one cubic per knot interval.
#[derive(Debug, Clone)]
struct Spline {
    /// Knot times \[s], scaled so that the first is 0 and the last t_c.
    knots: Vec<f64>,
    /// Per interval i: [α_i, c₁, c₂, c₃] with α = α_i + c₁ s + c₂ s² + c₃ s³, s = t − knots[i].
    coef: Vec<[f64; 4]>,
}

/// The extreme values of a spline: (min α, its time, max α, its time).
struct SplineExtremes {
    min: f64,
    t_min: f64,
    max: f64,
    t_max: f64,
}

impl Spline {
    /// Builds the spline through (x_i, y_i) with S'(x_0) = S'(x_{n−1}) = 0.
    fn new(x: Vec<f64>, y: &[f64]) -> Spline {
        let n = x.len();
        let h: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
        let slope: Vec<f64> = (0..n - 1).map(|i| (y[i + 1] - y[i]) / h[i]).collect();
        // Tridiagonal system for the knot second derivatives M_i (strictly diagonally
        // dominant, so the Thomas algorithm needs no pivoting).
        let mut diag = vec![0.0; n];
        let mut upper = vec![0.0; n];
        let mut rhs = vec![0.0; n];
        diag[0] = 2.0 * h[0];
        upper[0] = h[0];
        rhs[0] = 6.0 * slope[0];
        for i in 1..n - 1 {
            diag[i] = 2.0 * (h[i - 1] + h[i]);
            upper[i] = h[i];
            rhs[i] = 6.0 * (slope[i] - slope[i - 1]);
        }
        diag[n - 1] = 2.0 * h[n - 2];
        rhs[n - 1] = -6.0 * slope[n - 2];
        // Forward elimination: the sub-diagonal of row i is h[i−1].
        for i in 1..n {
            let m = h[i - 1] / diag[i - 1];
            diag[i] -= m * upper[i - 1];
            rhs[i] -= m * rhs[i - 1];
        }
        let mut m2 = vec![0.0; n];
        m2[n - 1] = rhs[n - 1] / diag[n - 1];
        for i in (0..n - 1).rev() {
            m2[i] = (rhs[i] - upper[i] * m2[i + 1]) / diag[i];
        }
        let coef = (0..n - 1)
            .map(|i| {
                [
                    y[i],
                    slope[i] - h[i] * (2.0 * m2[i] + m2[i + 1]) / 6.0,
                    0.5 * m2[i],
                    (m2[i + 1] - m2[i]) / (6.0 * h[i]),
                ]
            })
            .collect();
        Spline { knots: x, coef }
    }

    /// α, α̇, α̈ at t ∈ [0, t_c]: binary search for the interval, no allocation.
    fn state(&self, t: f64) -> ArmState {
        let last = self.coef.len() - 1;
        let i = self
            .knots
            .partition_point(|&k| k <= t)
            .saturating_sub(1)
            .min(last);
        let s = t - self.knots[i];
        let [y, c1, c2, c3] = self.coef[i];
        ArmState {
            angle: y + s * (c1 + s * (c2 + s * c3)),
            rate: c1 + s * (2.0 * c2 + 3.0 * c3 * s),
            accel: 2.0 * c2 + 6.0 * c3 * s,
        }
    }

    /// The largest |S'| and |S''| over the spline, exact from each piece's coefficients:
    /// S' = c₁ + 2c₂ s + 3c₃ s² is a parabola in s ∈ [0, h], largest in magnitude at an end or
    /// at its vertex s = −c₂/(3c₃); S'' = 2c₂ + 6c₃ s is linear, largest at an end.
    fn derivative_bounds(&self) -> (f64, f64) {
        let (mut rate, mut accel) = (0.0f64, 0.0f64);
        for (i, &[_, c1, c2, c3]) in self.coef.iter().enumerate() {
            let h = self.knots[i + 1] - self.knots[i];
            let d1 = |s: f64| c1 + s * (2.0 * c2 + 3.0 * c3 * s);
            rate = rate.max(d1(0.0).abs()).max(d1(h).abs());
            let vertex = -c2 / (3.0 * c3);
            if vertex > 0.0 && vertex < h {
                rate = rate.max(d1(vertex).abs());
            }
            accel = accel
                .max((2.0 * c2).abs())
                .max((2.0 * c2 + 6.0 * c3 * h).abs());
        }
        (rate, accel)
    }

    /// True extremes: the knots and the interior roots of each piece's S'.
    fn extremes(&self) -> SplineExtremes {
        let mut ex = SplineExtremes {
            min: f64::INFINITY,
            t_min: 0.0,
            max: f64::NEG_INFINITY,
            t_max: 0.0,
        };
        let mut visit = |t: f64, v: f64| {
            if v < ex.min {
                ex.min = v;
                ex.t_min = t;
            }
            if v > ex.max {
                ex.max = v;
                ex.t_max = t;
            }
        };
        for (i, &[y, c1, c2, c3]) in self.coef.iter().enumerate() {
            let (x0, x1) = (self.knots[i], self.knots[i + 1]);
            let h = x1 - x0;
            visit(x0, y);
            // S'(s) = c₁ + 2c₂ s + 3c₃ s² = 0, solved in the cancellation-free form.
            let (qa, qb, qc) = (3.0 * c3, 2.0 * c2, c1);
            let disc = qb * qb - 4.0 * qa * qc;
            if disc >= 0.0 {
                let q = -0.5 * (qb + qb.signum() * disc.sqrt());
                for r in [q / qa, qc / q] {
                    if r.is_finite() && r > 0.0 && r < h {
                        visit(x0 + r, y + r * (c1 + r * (c2 + r * c3)));
                    }
                }
            }
        }
        let last = self.coef.len();
        let [y, c1, c2, c3] = self.coef[last - 1];
        let h = self.knots[last] - self.knots[last - 1];
        visit(self.knots[last], y + h * (c1 + h * (c2 + h * c3)));
        ex
    }
}

impl ArmDrive {
    /// Build a drive for one cycle of length `cycle_time` \[s].
    pub fn new(spec: &DriveSpec, cycle_time: f64) -> Result<ArmDrive, DriveError> {
        if !(cycle_time.is_finite() && cycle_time > 0.0) {
            return Err(invalid(format!(
                "cycle_time = {cycle_time} s must be finite and > 0"
            )));
        }
        match spec {
            DriveSpec::CrankRocker(fb) => {
                let dc = fb.dead_centres()?;
                let omega2 = TAU / cycle_time;
                let mut cr = CrankRocker {
                    a: fb.crank,
                    b: fb.coupler,
                    c: fb.rocker,
                    d: fb.ground,
                    omega2,
                    theta2_0: dc.crank_retracted,
                    theta4_min: 0.0,
                    sin_min: 0.0,
                    cos_min: 1.0,
                };
                let retracted = cr.solve(dc.crank_retracted);
                (cr.theta4_min, cr.sin_min, cr.cos_min) =
                    (retracted.theta4, retracted.sin4, retracted.cos4);
                Ok(ArmDrive {
                    cycle_time,
                    max_swing: dc.rocker_max - dc.rocker_min,
                    out_stroke_time: (dc.crank_out - dc.crank_retracted) / omega2,
                    bounds: cr.bounds(),
                    law: Law::CrankRocker(cr),
                })
            }
            DriveSpec::Cycloidal { max_swing } => {
                Self::cam(CamShape::Cycloidal, *max_swing, cycle_time)
            }
            DriveSpec::Harmonic { max_swing } => {
                Self::cam(CamShape::Harmonic, *max_swing, cycle_time)
            }
            DriveSpec::Poly345 { max_swing } => {
                Self::cam(CamShape::Poly345, *max_swing, cycle_time)
            }
            DriveSpec::Table { times, angles } => Self::table(times, angles, cycle_time),
        }
    }

    fn cam(shape: CamShape, max_swing: f64, cycle_time: f64) -> Result<ArmDrive, DriveError> {
        if !(max_swing.is_finite() && max_swing > 0.0 && max_swing <= FRAC_PI_2) {
            return Err(invalid(format!(
                "max_swing = {max_swing} rad is outside (0, π/2]"
            )));
        }
        let rise_time = 0.5 * cycle_time;
        let (rate, accel) = shape.peaks();
        Ok(ArmDrive {
            cycle_time,
            max_swing,
            out_stroke_time: rise_time,
            bounds: (
                max_swing * rate / rise_time,
                max_swing * accel / (rise_time * rise_time),
            ),
            law: Law::Cam {
                shape,
                max_swing,
                rise_time,
            },
        })
    }

    fn table(times: &[f64], angles: &[f64], cycle_time: f64) -> Result<ArmDrive, DriveError> {
        let n = times.len();
        if n != angles.len() {
            return Err(invalid(format!(
                "drive table has {n} times but {} angles",
                angles.len()
            )));
        }
        if n < 4 {
            return Err(invalid(format!(
                "drive table has {n} points; at least 4 are needed"
            )));
        }
        if times[0] != 0.0 {
            return Err(invalid(format!(
                "drive table times[0] = {} s must be exactly 0",
                times[0]
            )));
        }
        for i in 1..n {
            if !times[i].is_finite() {
                return Err(invalid(format!(
                    "drive table times[{i}] = {} s is not finite",
                    times[i]
                )));
            }
            if times[i] <= times[i - 1] {
                return Err(invalid(format!(
                    "drive table times must increase strictly: times[{i}] = {} s is not greater \
                     than times[{}] = {} s",
                    times[i],
                    i - 1,
                    times[i - 1]
                )));
            }
        }
        for (i, &v) in angles.iter().enumerate() {
            if i == 0 || i == n - 1 {
                if v.is_nan() || v.abs() > TABLE_END_TOL {
                    return Err(invalid(format!(
                        "drive table angles[{i}] = {v} rad must be 0 (|α| ≤ {TABLE_END_TOL}): \
                         the arm starts and ends the cycle at rest at α = 0"
                    )));
                }
            } else if !(v.is_finite() && (0.0..=FRAC_PI_2).contains(&v)) {
                return Err(invalid(format!(
                    "drive table angles[{i}] = {v} rad is outside [0, π/2]"
                )));
            }
        }
        let scale = cycle_time / times[n - 1];
        let mut knots: Vec<f64> = times.iter().map(|&t| t * scale).collect();
        knots[n - 1] = cycle_time;
        if let Some(i) = (1..n).find(|&i| knots[i] <= knots[i - 1]) {
            return Err(invalid(format!(
                "drive table times[{}] and times[{i}] coincide after scaling the table to \
                 t_c = {cycle_time} s",
                i - 1
            )));
        }
        let mut y = angles.to_vec();
        y[0] = 0.0;
        y[n - 1] = 0.0;
        let spline = Spline::new(knots, &y);
        let ex = spline.extremes();
        if !ex.max.is_finite() {
            return Err(invalid(
                "drive table spline is not finite (times too close together)".to_string(),
            ));
        }
        // The arm cannot go behind its retracted position (the side guide is there).
        if ex.min < -TABLE_END_TOL {
            let i = spline
                .knots
                .partition_point(|&k| k <= ex.t_min)
                .saturating_sub(1);
            return Err(invalid(format!(
                "the cubic spline through the drive table dips to α = {} rad at t = {} s \
                 (between points {i} and {}), behind the retracted position α = 0; add points \
                 or smooth the table there",
                ex.min,
                ex.t_min,
                i + 1
            )));
        }
        // Nor past 90°, where the table's own points must stay: a clamped spline through a
        // steep ramp followed by a long stretch without points bulges far beyond them.
        if ex.max > FRAC_PI_2 + TABLE_END_TOL {
            let i = spline
                .knots
                .partition_point(|&k| k <= ex.t_max)
                .saturating_sub(1);
            return Err(invalid(format!(
                "the cubic spline through the drive table rises to α = {} rad ({:.1}°) at t = \
                 {} s (between points {i} and {}), beyond α = π/2 (90°); add points or smooth \
                 the table there",
                ex.max,
                ex.max.to_degrees(),
                ex.t_max,
                i + 1
            )));
        }
        Ok(ArmDrive {
            cycle_time,
            max_swing: ex.max,
            out_stroke_time: ex.t_max,
            bounds: spline.derivative_bounds(),
            law: Law::Table(spline),
        })
    }

    /// α, α̇, α̈ at time `t` \[s] from the arm start; at rest at 0 outside [0, t_c].
    pub fn state(&self, t: f64) -> ArmState {
        // Also catches NaN.
        if !(t >= 0.0 && t <= self.cycle_time) {
            return ArmState::default();
        }
        match &self.law {
            Law::CrankRocker(cr) => cr.state(t),
            Law::Cam {
                shape,
                max_swing,
                rise_time,
            } => {
                // The return is the mirror image of the rise: α(t) = α_rise(t_c − t).
                let (tau, sign) = if t <= *rise_time {
                    (t / rise_time, 1.0)
                } else {
                    ((self.cycle_time - t) / rise_time, -1.0)
                };
                let (f, df, ddf) = shape.rise(tau);
                ArmState {
                    angle: max_swing * f,
                    rate: sign * max_swing * df / rise_time,
                    accel: max_swing * ddf / (rise_time * rise_time),
                }
            }
            Law::Table(sp) => sp.state(t),
        }
    }

    /// [`ArmDrive::state`] with (sin α, cos α); for the crank-rocker without a trigonometric
    /// call (equal to `angle.sin_cos()` to rounding).
    pub fn state_trig(&self, t: f64) -> (ArmState, (f64, f64)) {
        match &self.law {
            Law::CrankRocker(cr) if t >= 0.0 && t <= self.cycle_time => cr.state_trig(t),
            _ => {
                let s = self.state(t);
                (s, s.angle.sin_cos())
            }
        }
    }

    /// t_c: the cycle time \[s].
    pub fn cycle_time(&self) -> f64 {
        self.cycle_time
    }

    /// A proven upper bound on |α̇| over the cycle [rad/s]: exact for the cam laws (their
    /// closed-form peaks) and for tables (each spline piece's derivative is a parabola), from
    /// the transmission angle for the crank-rocker (within 10 % of the true peak for the
    /// paper's linkage). The guard culling of the simulation trusts it: an arm moving
    /// faster than its bound between two samples could sweep through a parcel unseen.
    pub fn rate_bound(&self) -> f64 {
        self.bounds.0
    }

    /// A proven upper bound on |α̈| over the cycle [rad/s²] (see [`ArmDrive::rate_bound`];
    /// a table's α̈ is piecewise linear, largest at a knot).
    pub fn accel_bound(&self) -> f64 {
        self.bounds.1
    }

    /// α_max: the largest arm angle over the cycle \[rad].
    pub fn max_swing(&self) -> f64 {
        self.max_swing
    }

    /// Time from the arm start at which α = α_max \[s]: t_c/2 for the cam laws and the centred
    /// crank-rocker, (θ₂,out − θ₂₀)/ω₂ for any crank-rocker, the spline maximum for a table.
    pub fn out_stroke_time(&self) -> f64 {
        self.out_stroke_time
    }

    /// Transmission angle θ₄ − θ₃ of the crank-rocker at time `t` \[rad], in (0, π) on branch
    /// σ = −1 (keep it within 40°–140°); `None` for the other kinds. Outside [0, t_c] the crank
    /// rests at the retracted dead centre.
    pub fn transmission_angle(&self, t: f64) -> Option<f64> {
        match &self.law {
            Law::CrankRocker(cr) => {
                let t = if t > 0.0 { t.min(self.cycle_time) } else { 0.0 };
                let ls = cr.solve(cr.theta2_0 + cr.omega2 * t);
                Some(ls.sin_mu.atan2(ls.cos_mu))
            }
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const TC: f64 = 1.36;

    fn drive(spec: DriveSpec) -> ArmDrive {
        ArmDrive::new(&spec, TC).expect("valid drive")
    }

    fn default_cr() -> ArmDrive {
        drive(DriveSpec::CrankRocker(FourBar::paper_default()))
    }

    /// A non-centred crank-rocker (time ratio Q ≠ 1).
    fn skew_bar() -> FourBar {
        // β ≈ 26.4°, Q ≈ 1.34, swing ≈ 52.9°.
        FourBar {
            crank: 0.05,
            coupler: 0.2,
            rocker: 0.15,
            ground: 0.15,
        }
    }

    fn cycloid_table(n: usize, max_swing: f64, t_end: f64) -> DriveSpec {
        let law = drive(DriveSpec::Cycloidal { max_swing });
        let times: Vec<f64> = (0..n).map(|i| t_end * i as f64 / (n - 1) as f64).collect();
        let angles = (0..n)
            .map(|i| law.state(TC * i as f64 / (n - 1) as f64).angle)
            .collect();
        DriveSpec::Table { times, angles }
    }

    /// A few-point hand-made table (rise, short dwell-like plateau, return).
    fn hand_table() -> DriveSpec {
        DriveSpec::Table {
            times: vec![0.0, 0.2, 0.5, 0.8, 1.0],
            angles: vec![0.0, 0.2, 0.6, 0.3, 0.0],
        }
    }

    /// Every kind, for the property tests.
    fn all_drives() -> Vec<(&'static str, ArmDrive)> {
        vec![
            ("crank-rocker", default_cr()),
            (
                "crank-rocker Q≠1",
                drive(DriveSpec::CrankRocker(skew_bar())),
            ),
            ("cycloidal", drive(DriveSpec::Cycloidal { max_swing: 0.8 })),
            ("harmonic", drive(DriveSpec::Harmonic { max_swing: 0.8 })),
            ("3-4-5", drive(DriveSpec::Poly345 { max_swing: 0.8 })),
            ("cycloid table", drive(cycloid_table(200, 0.8, 2.0))),
            ("hand table", drive(hand_table())),
        ]
    }

    fn err_msg(spec: DriveSpec, tc: f64) -> String {
        match ArmDrive::new(&spec, tc) {
            Err(DriveError::Invalid(m)) => m,
            Ok(_) => panic!("expected an error for {spec:?}"),
        }
    }

    /// Dense scan: (t, value) of the max of f over [0, t_c] on a grid of step dt.
    fn argmax(d: &ArmDrive, dt: f64, f: impl Fn(ArmState) -> f64) -> (f64, f64) {
        let n = (d.cycle_time() / dt).round() as usize;
        (0..=n)
            .map(|i| {
                let t = d.cycle_time() * i as f64 / n as f64;
                (t, f(d.state(t)))
            })
            .fold(
                (0.0, f64::NEG_INFINITY),
                |b, x| if x.1 > b.1 { x } else { b },
            )
    }

    // ---------------------------------------------------------------- four-bar (model.md §2)

    #[test]
    fn paper_default_link_lengths() {
        // a = 57.402515 mm, d = 330.461724 mm: half a unit of the last digit = 5e-10 m.
        let fb = FourBar::paper_default();
        assert!((fb.crank - 57.402515e-3).abs() <= 5e-10, "a = {}", fb.crank);
        assert!(
            (fb.ground - 330.461724e-3).abs() <= 5e-10,
            "d = {}",
            fb.ground
        );
        assert_eq!(fb.coupler, 0.3);
        assert_eq!(fb.rocker, 0.15);
        // Grashof: 0.388 ≤ 0.45 (s + l = a + d, p + q = b + c).
        assert!((fb.crank + fb.ground - 0.388).abs() <= 5e-4);
        assert!((fb.coupler + fb.rocker - 0.45).abs() <= 1e-15);
        // The centred design reproduces its swing exactly.
        let psi = fb.swing().unwrap();
        assert!(
            (psi - std::f64::consts::FRAC_PI_4).abs() <= 1e-14,
            "ψ = {psi}"
        );
    }

    #[test]
    fn rounded_links_give_44_998_degrees() {
        // model.md §2: with 57.40/330.46 mm the swing is 44.998°.
        let fb = FourBar {
            crank: 0.0574,
            coupler: 0.3,
            rocker: 0.15,
            ground: 0.33046,
        };
        let psi = fb.swing().unwrap().to_degrees();
        assert!((psi - 44.998).abs() <= 5e-4, "ψ = {psi}°");
    }

    #[test]
    fn paper_default_dead_centres_and_rocker_range() {
        let dc = FourBar::paper_default().dead_centres().unwrap();
        let deg = |x: f64| x.to_degrees();
        assert!((deg(dc.crank_retracted) - 24.794).abs() <= 5e-4, "{dc:?}");
        assert!((deg(dc.crank_out) - 204.794).abs() <= 5e-4, "{dc:?}");
        assert!((deg(dc.rocker_min) - 92.294).abs() <= 5e-4, "{dc:?}");
        assert!((deg(dc.rocker_max) - 137.294).abs() <= 5e-4, "{dc:?}");
        // Q = 1: the dead centres are exactly half a turn apart.
        assert!((dc.crank_out - dc.crank_retracted - PI).abs() <= 1e-12);
        let d = default_cr();
        assert!((d.out_stroke_time() - 0.68).abs() <= 1e-12);
        assert!((d.max_swing() - std::f64::consts::FRAC_PI_4).abs() <= 1e-14);
        match &d.law {
            Law::CrankRocker(cr) => {
                assert!((cr.omega2 - 4.619989).abs() <= 5e-7, "ω₂ = {}", cr.omega2);
                assert!((deg(cr.theta4_min) - 92.294).abs() <= 5e-4);
            }
            _ => panic!("not a crank-rocker"),
        }
    }

    #[test]
    fn paper_default_table() {
        // model.md §2: t, α [deg], α̇, α̈, transmission angle [deg]. Tolerances: half a unit
        // of the last printed digit.
        #[rustfmt::skip]
        let rows: [(f64, f64, f64, f64, f64); 15] = [
            (0.00, 0.00000, 0.000000, 10.53277, 67.500),
            (0.10, 2.82315, 0.940000, 7.86383, 74.706),
            (0.20, 10.10755, 1.540331, 4.13840, 84.862),
            (0.30, 19.77679, 1.776525, 0.63417, 95.938),
            (0.40, 29.81760, 1.673038, -2.68565, 105.947),
            (0.50, 38.33266, 1.249167, -5.67213, 112.858),
            (0.60, 43.66428, 0.584794, -7.28650, 114.879),
            (0.68, 45.00000, 0.000000, -7.14943, 112.500),
            (0.80, 42.21759, -0.781971, -5.81048, 103.433),
            (0.90, 36.18395, -1.304872, -4.64320, 92.932),
            (1.00, 27.51221, -1.694511, -2.96009, 81.911),
            (1.10, 17.23598, -1.833427, 0.59993, 72.357),
            (1.20, 7.41460, -1.499754, 6.23910, 66.303),
            (1.30, 1.09591, -0.635973, 10.36547, 65.389),
            (1.36, 0.00000, 0.000000, 10.53277, 67.500),
        ];
        let d = default_cr();
        for (t, a, ad, add, mu) in rows {
            let s = d.state(t);
            let m = d.transmission_angle(t).unwrap().to_degrees();
            assert!(
                (s.angle.to_degrees() - a).abs() <= 5e-6,
                "t={t}: α={}°",
                s.angle.to_degrees()
            );
            assert!((s.rate - ad).abs() <= 5e-7, "t={t}: α̇={}", s.rate);
            assert!((s.accel - add).abs() <= 5e-6, "t={t}: α̈={}", s.accel);
            assert!((m - mu).abs() <= 5e-4, "t={t}: μ={m}°");
        }
    }

    #[test]
    fn paper_default_extremes() {
        let d = default_cr();
        let dt = 1e-5;
        let (t_max, v_max) = argmax(&d, dt, |s| s.rate);
        assert!((v_max - 1.78249).abs() <= 5e-6, "max α̇ = {v_max}");
        assert!((t_max - 0.319).abs() <= 5e-4, "at t = {t_max}");
        let a_deg = d.state(t_max).angle.to_degrees();
        assert!((a_deg - 21.70).abs() <= 5e-3, "α = {a_deg}° at max α̇");
        let (t_min, v_min) = argmax(&d, dt, |s| -s.rate);
        assert!((-v_min + 1.83723).abs() <= 5e-6, "min α̇ = {}", -v_min);
        assert!((t_min - 1.087).abs() <= 5e-4, "at t = {t_min}");
        let (_, acc) = argmax(&d, dt, |s| s.accel.abs());
        assert!((acc - 10.68).abs() <= 5e-3, "max |α̈| = {acc}");
        assert!((d.state(0.0).accel - 10.53).abs() <= 5e-3);
        // Transmission angle 65.1°–114.9°.
        let n = 136_000;
        let (lo, hi) = (0..=n)
            .map(|i| {
                d.transmission_angle(TC * i as f64 / n as f64)
                    .unwrap()
                    .to_degrees()
            })
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), m| {
                (lo.min(m), hi.max(m))
            });
        assert!(
            (lo - 65.1).abs() <= 0.05 && (hi - 114.9).abs() <= 0.05,
            "μ ∈ [{lo}, {hi}]"
        );
        // The crank-rocker normalised like the cam laws (model.md §2): 1.54 and 6.29.
        let tr = 0.68;
        let amax = std::f64::consts::FRAC_PI_4;
        assert!((v_max * tr / amax - 1.54).abs() <= 5e-3);
        assert!((acc * tr * tr / amax - 6.29).abs() <= 5e-3);
        // θ₄ range: 92.294° + α ∈ [92.294°, 137.294°] over the sampled cycle.
        let (_, amax_s) = argmax(&d, dt, |s| s.angle);
        assert!((amax_s.to_degrees() - 45.0).abs() <= 1e-6);
    }

    #[test]
    fn skewed_crank_rocker_out_stroke() {
        // Q ≠ 1: the out-stroke is not t_c/2; its time is where α peaks (brute force).
        let fb = skew_bar();
        let d = drive(DriveSpec::CrankRocker(fb));
        let dc = fb.dead_centres().unwrap();
        let beta = dc.crank_out - dc.crank_retracted - PI;
        assert!(
            beta.abs() > 0.4,
            "the test design should be skewed, β = {beta}"
        );
        let q = (PI + beta) / (PI - beta);
        let t_out = d.out_stroke_time();
        assert!((t_out / (TC - t_out) - q).abs() <= 1e-12, "Q = {q}");
        let (t_peak, a_peak) = argmax(&d, 1e-5, |s| s.angle);
        assert!((t_peak - t_out).abs() <= 2e-5, "{t_peak} vs {t_out}");
        assert!((a_peak - d.max_swing()).abs() <= 1e-9);
        let s = d.state(t_out);
        assert!(
            (s.angle - d.max_swing()).abs() <= 1e-12,
            "α(t_out) = {}",
            s.angle
        );
        assert!(s.rate.abs() <= 1e-10, "α̇(t_out) = {}", s.rate);
        assert!((fb.swing().unwrap() - d.max_swing()).abs() <= 1e-15);
    }

    // ---------------------------------------------------------------- cam laws (model.md §2)

    #[test]
    fn cam_law_oracles() {
        // α_max = 45°, T_r = 0.68 s. Oracles printed to 6 decimals: tolerance 5e-7.
        let amax = std::f64::consts::FRAC_PI_4;
        let tr = 0.68;
        let cyc = drive(DriveSpec::Cycloidal { max_swing: amax });
        let p345 = drive(DriveSpec::Poly345 { max_swing: amax });
        let harm = drive(DriveSpec::Harmonic { max_swing: amax });
        for (name, d, vmax, amx) in [
            ("cycloidal", &cyc, 2.309995, 10.672150),
            ("3-4-5", &p345, 2.165620, 9.806441),
            ("harmonic", &harm, 1.814266, 8.381887),
        ] {
            let (_, v) = argmax(d, 1e-6, |s| s.rate);
            let (_, a) = argmax(d, 1e-6, |s| s.accel.abs());
            assert!((v - vmax).abs() <= 5e-7, "{name}: peak α̇ = {v}");
            assert!((a - amx).abs() <= 5e-7, "{name}: peak α̈ = {a}");
            assert!((d.state(tr).angle - amax).abs() <= 1e-15, "{name}");
            assert_eq!(d.out_stroke_time(), tr);
            assert_eq!(d.max_swing(), amax);
            assert_eq!(d.transmission_angle(0.3), None);
        }
        // α(τ = 0.25).
        assert!((cyc.state(0.25 * tr).angle.to_degrees() - 4.088028).abs() <= 5e-7);
        assert!((p345.state(0.25 * tr).angle.to_degrees() - 4.658203).abs() <= 5e-7);
        // α(0.5) = 22.5° for both (and for the harmonic law too, by symmetry).
        for d in [&cyc, &p345, &harm] {
            assert!((d.state(0.5 * tr).angle.to_degrees() - 22.5).abs() <= 1e-12);
        }
        // Normalised peaks (model.md §2): π/2, π²/2; 2, 2π; 15/8, 10√3/3.
        let norm_v = |d: &ArmDrive| argmax(d, 1e-6, |s| s.rate).1 * tr / amax;
        let norm_a = |d: &ArmDrive| argmax(d, 1e-6, |s| s.accel.abs()).1 * tr * tr / amax;
        assert!((norm_v(&harm) - FRAC_PI_2).abs() <= 1e-9);
        assert!((norm_a(&harm) - PI * PI / 2.0).abs() <= 1e-9);
        assert!((norm_v(&cyc) - 2.0).abs() <= 1e-9);
        assert!((norm_a(&cyc) - TAU).abs() <= 1e-9);
        assert!((norm_v(&p345) - 15.0 / 8.0).abs() <= 1e-9);
        assert!((norm_a(&p345) - 10.0 * 3f64.sqrt() / 3.0).abs() <= 1e-9);
    }

    #[test]
    fn cam_return_mirrors_rise() {
        for spec in [
            DriveSpec::Cycloidal { max_swing: 1.0 },
            DriveSpec::Harmonic { max_swing: 1.0 },
            DriveSpec::Poly345 { max_swing: 1.0 },
        ] {
            let d = drive(spec);
            for i in 0..=100 {
                let t = 0.68 * i as f64 / 100.0;
                let (a, b) = (d.state(t), d.state(TC - t));
                assert!((a.angle - b.angle).abs() <= 1e-14);
                assert!((a.rate + b.rate).abs() <= 1e-12);
                assert!((a.accel - b.accel).abs() <= 1e-11);
            }
        }
    }

    // ---------------------------------------------------------------- tables

    #[test]
    fn table_reproduces_sampled_cycloid() {
        // 200 points of the cycloidal law (α_max = 45°): the spline stays within these
        // tolerances of the law over a dense grid (measured: see the report).
        let amax = std::f64::consts::FRAC_PI_4;
        let law = drive(DriveSpec::Cycloidal { max_swing: amax });
        let tab = drive(cycloid_table(200, amax, TC));
        let (mut ea, mut ev, mut eacc) = (0.0f64, 0.0f64, 0.0f64);
        let n = 13_600;
        for i in 0..=n {
            let t = TC * i as f64 / n as f64;
            let (a, b) = (law.state(t), tab.state(t));
            ea = ea.max((a.angle - b.angle).abs());
            ev = ev.max((a.rate - b.rate).abs());
            eacc = eacc.max((a.accel - b.accel).abs());
        }
        // Measured: 6.9e-7 rad, 2.7e-4 rad/s, 0.23 rad/s² (2 % of the peak α̈), all at
        // mid-cycle where the mirrored law has a jerk jump of 8π²α_max/T_r³ that no cubic
        // spline can follow; the cycloid's α̈ itself stays continuous.
        assert!(ea <= 1e-6, "α error {ea}");
        assert!(ev <= 5e-4, "α̇ error {ev}");
        assert!(eacc <= 0.3, "α̈ error {eacc}");
        assert!(
            (tab.max_swing() - amax).abs() <= 1e-6,
            "{}",
            tab.max_swing()
        );
        // The zero end slopes follow the law's rest: no dip behind α = 0.
        let Law::Table(sp) = &tab.law else {
            panic!("not a table")
        };
        assert!(sp.extremes().min >= -1e-15);
        assert!((tab.out_stroke_time() - 0.68).abs() <= 1e-3);
        assert_eq!(tab.transmission_angle(0.3), None);
    }

    #[test]
    fn table_time_axis_is_scaled_to_cycle_time() {
        // The same shape given over 0..1 and over 0..5: identical drives at t_c = 1.36.
        let a = drive(cycloid_table(50, 0.7, 1.0));
        let b = drive(cycloid_table(50, 0.7, 5.0));
        for i in 0..=200 {
            let t = TC * i as f64 / 200.0;
            let (sa, sb) = (a.state(t), b.state(t));
            assert!((sa.angle - sb.angle).abs() <= 1e-13);
            assert!((sa.rate - sb.rate).abs() <= 1e-11);
            assert!((sa.accel - sb.accel).abs() <= 1e-9);
        }
        // Knot k of the table is reached at t = t_c · times[k]/times[last].
        if let DriveSpec::Table { times, angles } = hand_table() {
            let d = ArmDrive::new(
                &DriveSpec::Table {
                    times: times.clone(),
                    angles: angles.clone(),
                },
                2.0,
            )
            .unwrap();
            assert_eq!(d.cycle_time(), 2.0);
            for (t, a) in times.iter().zip(&angles) {
                assert!((d.state(2.0 * t).angle - a).abs() <= 1e-15, "t = {t}");
            }
        }
    }

    #[test]
    fn table_max_swing_is_the_spline_maximum() {
        // The hand table peaks between its knots: max_swing ≥ the largest knot, and equals
        // the dense-grid maximum.
        let d = drive(hand_table());
        let (t, m) = argmax(&d, 1e-6, |s| s.angle);
        assert!(d.max_swing() > 0.6);
        assert!(
            (d.max_swing() - m).abs() <= 1e-10,
            "{} vs {m}",
            d.max_swing()
        );
        assert!((d.out_stroke_time() - t).abs() <= 1e-5);
        assert!(d.state(d.out_stroke_time()).rate.abs() <= 1e-9);
    }

    // ---------------------------------------------------------------- rest outside the cycle

    #[test]
    fn at_rest_outside_the_cycle() {
        for (name, d) in all_drives() {
            for t in [-1.0, -1e-12, TC + 1e-12, 10.0, f64::NAN, f64::INFINITY] {
                assert_eq!(d.state(t), ArmState::default(), "{name} at t = {t}");
            }
            assert_eq!(d.cycle_time(), TC);
        }
        let d = default_cr();
        assert_eq!(d.transmission_angle(-1.0), d.transmission_angle(0.0));
        assert_eq!(d.transmission_angle(9.0), d.transmission_angle(TC));
    }

    // ---------------------------------------------------------------- validation

    #[test]
    fn validation_errors() {
        // Non-Grashof links.
        let m = err_msg(
            DriveSpec::CrankRocker(FourBar {
                crank: 0.1,
                coupler: 0.3,
                rocker: 0.15,
                ground: 0.4,
            }),
            TC,
        );
        assert!(
            m.contains("a=0.1") && m.contains("d=0.4") && m.contains("exceeds the sum"),
            "{m}"
        );
        assert!(m.contains("0.5") && m.contains("0.45"), "{m}");
        // Crank not the shortest.
        let m = err_msg(
            DriveSpec::CrankRocker(FourBar {
                crank: 0.2,
                coupler: 0.3,
                rocker: 0.15,
                ground: 0.3,
            }),
            TC,
        );
        assert!(
            m.contains("shortest link") && m.contains("rocker c = 0.15"),
            "{m}"
        );
        // Change point (s + l = p + q).
        let m = err_msg(
            DriveSpec::CrankRocker(FourBar {
                crank: 0.1,
                coupler: 0.3,
                rocker: 0.2,
                ground: 0.4,
            }),
            TC,
        );
        assert!(m.contains("change-point"), "{m}");
        // Bad lengths.
        for bad in [0.0, -0.1, f64::NAN, f64::INFINITY] {
            let mut fb = FourBar::paper_default();
            fb.rocker = bad;
            let m = err_msg(DriveSpec::CrankRocker(fb), TC);
            assert!(m.contains("rocker length c"), "{m}");
            assert!(fb.swing().is_err());
        }
        // Swing out of range.
        for bad in [0.0, -0.1, FRAC_PI_2 + 1e-9, f64::NAN] {
            for spec in [
                DriveSpec::Cycloidal { max_swing: bad },
                DriveSpec::Harmonic { max_swing: bad },
                DriveSpec::Poly345 { max_swing: bad },
            ] {
                let m = err_msg(spec, TC);
                assert!(m.contains("max_swing") && m.contains("(0, π/2]"), "{m}");
            }
        }
        assert!(ArmDrive::new(
            &DriveSpec::Harmonic {
                max_swing: FRAC_PI_2
            },
            TC
        )
        .is_ok());
        // cycle_time ≤ 0 or not finite, every kind.
        for tc in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            for spec in [
                DriveSpec::CrankRocker(FourBar::paper_default()),
                DriveSpec::Cycloidal { max_swing: 0.5 },
                hand_table(),
            ] {
                let m = err_msg(spec, tc);
                assert!(m.contains("cycle_time"), "{m}");
            }
        }
        let table =
            |times: Vec<f64>, angles: Vec<f64>| err_msg(DriveSpec::Table { times, angles }, TC);
        // Short table.
        let m = table(vec![0.0, 0.5, 1.0], vec![0.0, 0.3, 0.0]);
        assert!(m.contains("3 points") && m.contains("at least 4"), "{m}");
        // Length mismatch.
        let m = table(vec![0.0, 0.5, 0.7, 1.0], vec![0.0, 0.3, 0.0]);
        assert!(m.contains("4 times but 3 angles"), "{m}");
        // Not starting at 0.
        let m = table(vec![0.1, 0.5, 0.7, 1.0], vec![0.0, 0.3, 0.2, 0.0]);
        assert!(m.contains("times[0] = 0.1"), "{m}");
        // Non-monotone times.
        let m = table(vec![0.0, 0.5, 0.5, 1.0], vec![0.0, 0.3, 0.2, 0.0]);
        assert!(
            m.contains("times[2] = 0.5") && m.contains("times[1] = 0.5"),
            "{m}"
        );
        let m = table(vec![0.0, 0.6, 0.5, 1.0], vec![0.0, 0.3, 0.2, 0.0]);
        assert!(m.contains("times[2]") && m.contains("strictly"), "{m}");
        let m = table(vec![0.0, 0.5, f64::NAN, 1.0], vec![0.0, 0.3, 0.2, 0.0]);
        assert!(m.contains("times[2]") && m.contains("not finite"), "{m}");
        // Non-zero ends.
        let m = table(vec![0.0, 0.5, 0.7, 1.0], vec![1e-9, 0.3, 0.2, 0.0]);
        assert!(m.contains("angles[0]") && m.contains("must be 0"), "{m}");
        let m = table(vec![0.0, 0.5, 0.7, 1.0], vec![0.0, 0.3, 0.2, -1e-6]);
        assert!(m.contains("angles[3]") && m.contains("must be 0"), "{m}");
        // Angles out of range or NaN.
        let m = table(vec![0.0, 0.5, 0.7, 1.0], vec![0.0, 0.3, 1.6, 0.0]);
        assert!(
            m.contains("angles[2] = 1.6") && m.contains("[0, π/2]"),
            "{m}"
        );
        let m = table(vec![0.0, 0.5, 0.7, 1.0], vec![0.0, -0.1, 0.2, 0.0]);
        assert!(m.contains("angles[1] = -0.1"), "{m}");
        let m = table(vec![0.0, 0.5, 0.7, 1.0], vec![0.0, f64::NAN, 0.2, 0.0]);
        assert!(m.contains("angles[1] = NaN"), "{m}");
        let m = table(vec![0.0, 0.5, 0.7, 1.0], vec![f64::NAN, 0.3, 0.2, 0.0]);
        assert!(m.contains("angles[0] = NaN"), "{m}");
        // A spline that would swing the arm behind its retracted position.
        let m = table(vec![0.0, 0.1, 0.2, 0.9, 1.0], vec![0.0, 0.0, 1.0, 0.0, 0.0]);
        assert!(m.contains("dips") && m.contains("between points"), "{m}");
        // A spline that bulges beyond 90° between points that stay below it (a ramp to
        // 1.2 rad, then 80 % of the cycle without a point: the spline reaches 183°).
        let m = table(
            vec![0.0, 0.05, 0.1, 0.9, 0.95, 1.0],
            vec![0.0, 0.6, 1.2, 1.2, 0.6, 0.0],
        );
        assert!(
            m.contains("rises to") && m.contains("beyond α = π/2") && m.contains("between points"),
            "{m}"
        );
        // Tiny end values within 1e-12 are accepted (and treated as 0).
        let d = ArmDrive::new(
            &DriveSpec::Table {
                times: vec![0.0, 0.5, 0.7, 1.0],
                angles: vec![1e-13, 0.3, 0.2, -1e-13],
            },
            TC,
        )
        .unwrap();
        assert_eq!(d.state(0.0).angle, 0.0);
        assert!(d.state(TC).angle.abs() <= 1e-15);
    }

    // ---------------------------------------------------------------- properties

    fn fd_check(name: &str, d: &ArmDrive, t: f64) -> Result<(), TestCaseError> {
        let h = 1e-6;
        let (m, p, s) = (d.state(t - h), d.state(t + h), d.state(t));
        let fd_rate = (p.angle - m.angle) / (2.0 * h);
        let fd_acc = (p.rate - m.rate) / (2.0 * h);
        // Truncation O(h²α''') plus round-off ~1e-16·α/h, and O(h·jump of α''') across a
        // spline knot or a cam-law jerk jump.
        prop_assert!(
            (fd_rate - s.rate).abs() <= 1e-6 * (1.0 + s.rate.abs()),
            "{name} t={t}: α̇ {} vs fd {fd_rate}",
            s.rate
        );
        prop_assert!(
            (fd_acc - s.accel).abs() <= 1e-3 * (1.0 + s.accel.abs()),
            "{name} t={t}: α̈ {} vs fd {fd_acc}",
            s.accel
        );
        Ok(())
    }

    fn rest_and_sign_check(name: &str, d: &ArmDrive) -> Result<(), TestCaseError> {
        let tc = d.cycle_time();
        for t in [0.0, tc] {
            let s = d.state(t);
            prop_assert!(s.angle.abs() <= 1e-12, "{name}: α({t}) = {}", s.angle);
            prop_assert!(s.rate.abs() <= 1e-12, "{name}: α̇({t}) = {}", s.rate);
        }
        let n = 2000;
        for i in 0..=n {
            let t = tc * i as f64 / n as f64;
            let a = d.state(t).angle;
            prop_assert!(a >= -1e-12, "{name}: α({t}) = {a}");
            prop_assert!(a <= d.max_swing() + 1e-12, "{name}: α({t}) = {a} > α_max");
        }
        Ok(())
    }

    /// A random strict-Grashof crank-rocker: b, c, d ∈ [0.1, 1] m and a fraction of the
    /// largest admissible crank.
    /// The largest sampled |α̇| and |α̈| over the cycle, on `n` equal steps.
    fn sampled_peaks(d: &ArmDrive, n: usize) -> (f64, f64) {
        (0..=n)
            .map(|k| d.state(d.cycle_time() * k as f64 / n as f64))
            .fold((0.0f64, 0.0f64), |(r, a), s| {
                (r.max(s.rate.abs()), a.max(s.accel.abs()))
            })
    }

    /// The rate and acceleration bounds the guard culling trusts hold for every drive kind,
    /// sampled at 200,001 instants (a table's peak between its knots included); for the cam
    /// laws and tables they are the true peaks; for the crank-rocker they come from its least
    /// transmission angle: 1.06 and 1.43 times the peaks for the paper's linkage, 1.08 and
    /// 2.62 for a skewed one (Q ≠ 1). A sampled bound (49 instants and a margin) was below the
    /// true peak by up to ×100 for a table with a short ramp (issue "Contacts that hold, round
    /// two", fault 3).
    #[test]
    fn rate_and_accel_bounds_hold_for_every_drive_kind() {
        let mut drives = all_drives();
        drives.push((
            "short-ramp table",
            ArmDrive::new(
                &DriveSpec::Table {
                    times: vec![
                        0.0, 0.0757, 0.15145, 0.16148, 0.16316, 0.16483, 0.1665, 0.16817, 0.16985,
                        0.17152, 0.18156, 0.77023, 0.81595, 0.82357, 0.83119, 0.83881, 0.84643,
                        0.85405, 0.86167, 0.90739, 1.13369, 1.36,
                    ],
                    angles: [
                        0.0, 3.0, 6.0, 6.0, 6.8197, 11.5577, 20.214, 28.8703, 33.6083, 34.428,
                        34.428, 34.428, 34.428, 33.6083, 28.8703, 20.214, 11.5577, 6.8197, 6.0,
                        6.0, 3.0, 0.0,
                    ]
                    .iter()
                    .map(|d: &f64| d.to_radians())
                    .collect(),
                },
                1.36,
            )
            .unwrap(),
        ));
        for (name, d) in drives {
            let (rate, accel) = sampled_peaks(&d, 200_000);
            assert!(
                rate <= d.rate_bound(),
                "{name}: α̇ {rate} > bound {}",
                d.rate_bound()
            );
            assert!(
                accel <= d.accel_bound(),
                "{name}: α̈ {accel} > bound {}",
                d.accel_bound()
            );
            let (tight_rate, tight_accel) = if name.starts_with("crank") {
                (1.5, 3.0)
            } else {
                // (A table's α̈ peaks at a knot, which the samples miss by a hair.)
                (1.0 + 1e-6, 1.0 + 1e-4)
            };
            assert!(
                d.rate_bound() <= tight_rate * rate,
                "{name}: α̇ bound {} vs {rate}",
                d.rate_bound()
            );
            assert!(
                d.accel_bound() <= tight_accel * accel,
                "{name}: α̈ bound {} vs {accel}",
                d.accel_bound()
            );
        }
        // model.md §2: the cam laws' peaks in closed form (α_max = 45°, T_r = 0.68 s).
        for (spec, rate, accel) in [
            (
                DriveSpec::Cycloidal {
                    max_swing: std::f64::consts::FRAC_PI_4,
                },
                2.309995,
                10.672150,
            ),
            (
                DriveSpec::Poly345 {
                    max_swing: std::f64::consts::FRAC_PI_4,
                },
                2.165620,
                9.806441,
            ),
            (
                DriveSpec::Harmonic {
                    max_swing: std::f64::consts::FRAC_PI_4,
                },
                1.814266,
                8.381887,
            ),
        ] {
            let d = ArmDrive::new(&spec, 1.36).unwrap();
            assert!((d.rate_bound() - rate).abs() < 5e-7, "{spec:?}");
            assert!((d.accel_bound() - accel).abs() < 5e-6, "{spec:?}");
        }
    }

    fn random_bar() -> impl Strategy<Value = FourBar> {
        (0.1f64..1.0, 0.1f64..1.0, 0.1f64..1.0, 0.05f64..0.95).prop_filter_map(
            "no crank-rocker",
            |(b, c, d, f)| {
                let l = b.max(c).max(d);
                let a_max = b.min(c).min(d).min(b + c + d - 2.0 * l);
                (a_max > 1e-3).then_some(FourBar {
                    crank: f * a_max,
                    coupler: b,
                    rocker: c,
                    ground: d,
                })
            },
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        #[test]
        fn derivatives_match_finite_differences(k in 0usize..7, u in 0.0f64..1.0) {
            let drives = all_drives();
            let (name, d) = &drives[k];
            let h = 1e-6;
            let t = 2.0 * h + u * (d.cycle_time() - 4.0 * h);
            fd_check(name, d, t)?;
        }

        #[test]
        /// Every random crank-rocker's rate and acceleration stay within its proven bounds.
        fn random_crank_rocker_bounds(fb in random_bar(), tc in 0.3f64..5.0) {
            let d = ArmDrive::new(&DriveSpec::CrankRocker(fb), tc).unwrap();
            let (rate, accel) = sampled_peaks(&d, 20_000);
            prop_assert!(rate <= d.rate_bound(), "{fb:?}: α̇ {rate} > {}", d.rate_bound());
            prop_assert!(accel <= d.accel_bound(), "{fb:?}: α̈ {accel} > {}", d.accel_bound());
        }

        #[test]
        fn random_crank_rockers(fb in random_bar(), tc in 0.3f64..5.0, u in 0.0f64..1.0) {
            let d = ArmDrive::new(&DriveSpec::CrankRocker(fb), tc).unwrap();
            let psi = fb.swing().unwrap();
            prop_assert!(psi > 0.0 && psi < PI);
            prop_assert!((d.max_swing() - psi).abs() <= 1e-14);
            rest_and_sign_check("crank-rocker", &d)?;
            // α peaks at the out-stroke time, at rest.
            let s = d.state(d.out_stroke_time());
            prop_assert!((s.angle - psi).abs() <= 1e-9 * (1.0 + psi), "{fb:?}: {} vs {psi}", s.angle);
            prop_assert!(s.rate.abs() <= 1e-7 * psi / tc, "{fb:?}: α̇ = {}", s.rate);
            let mu = d.transmission_angle(u * tc).unwrap();
            prop_assert!(mu > 0.0 && mu < PI, "μ = {mu}");
            let h = 1e-6;
            let t = 2.0 * h + u * (tc - 4.0 * h);
            // Relative FD check: α̇, α̈ scale with the size of the motion.
            let (m, p, st) = (d.state(t - h), d.state(t + h), d.state(t));
            let vs = psi / tc;
            let fd_rate = (p.angle - m.angle) / (2.0 * h);
            let fd_acc = (p.rate - m.rate) / (2.0 * h);
            prop_assert!((fd_rate - st.rate).abs() <= 1e-5 * vs * (1.0 + st.rate.abs() / vs), "{fb:?} t={t}: α̇ {} fd {fd_rate}", st.rate);
            prop_assert!((fd_acc - st.accel).abs() <= 1e-4 * (vs / tc) * (1.0 + st.accel.abs() * tc / vs), "{fb:?} t={t}: α̈ {} fd {fd_acc}", st.accel);
        }

        #[test]
        fn random_cam_laws(k in 0usize..3, amax in 1e-3f64..FRAC_PI_2, tc in 0.2f64..5.0, u in 0.0f64..1.0) {
            let spec = match k {
                0 => DriveSpec::Cycloidal { max_swing: amax },
                1 => DriveSpec::Harmonic { max_swing: amax },
                _ => DriveSpec::Poly345 { max_swing: amax },
            };
            let d = ArmDrive::new(&spec, tc).unwrap();
            rest_and_sign_check("cam", &d)?;
            prop_assert!((d.state(0.5 * tc).angle - amax).abs() <= 1e-15);
            let h = 1e-6 * tc;
            let t = 2.0 * h + u * (tc - 4.0 * h);
            let (m, p, st) = (d.state(t - h), d.state(t + h), d.state(t));
            let vs = amax / tc;
            prop_assert!(((p.angle - m.angle) / (2.0 * h) - st.rate).abs() <= 1e-6 * vs * 10.0);
            prop_assert!(((p.rate - m.rate) / (2.0 * h) - st.accel).abs() <= 1e-4 * vs / tc * 100.0);
        }

        #[test]
        fn random_tables(
            pts in proptest::collection::vec((0.05f64..1.0, 0.0f64..1.4), 2..20),
            tc in 0.3f64..3.0,
            u in 0.0f64..1.0,
        ) {
            let mut times = vec![0.0];
            let mut angles = vec![0.0];
            for (dt, a) in &pts {
                times.push(times.last().unwrap() + dt);
                angles.push(*a);
            }
            times.push(times.last().unwrap() + 0.3);
            angles.push(0.0);
            // About a third of these random tables pass; the others can only fail because
            // their spline dips below 0 or rises beyond 90°, since everything else is valid by
            // construction.
            let built = ArmDrive::new(&DriveSpec::Table { times: times.clone(), angles: angles.clone() }, tc);
            if let Err(DriveError::Invalid(m)) = &built {
                prop_assert!(m.contains("dips") || m.contains("rises to"), "{m}");
            }
            if let Ok(d) = built {
                rest_and_sign_check("table", &d)?;
                let scale = tc / times.last().unwrap();
                for (t, a) in times.iter().zip(&angles) {
                    prop_assert!((d.state(t * scale).angle - a).abs() <= 1e-12);
                }
                let grid_max = (0..=4000).map(|i| d.state(tc * i as f64 / 4000.0).angle).fold(0.0, f64::max);
                prop_assert!(d.max_swing() >= grid_max - 1e-15);
                prop_assert!(d.max_swing() <= grid_max + 1e-3);
                let st = d.state(d.out_stroke_time());
                prop_assert!((st.angle - d.max_swing()).abs() <= 1e-12);
                let h = 1e-7;
                let t = 2.0 * h + u * (tc - 4.0 * h);
                let (m, p, s) = (d.state(t - h), d.state(t + h), d.state(t));
                let fd_rate = (p.angle - m.angle) / (2.0 * h);
                prop_assert!((fd_rate - s.rate).abs() <= 1e-5 * (1.0 + s.rate.abs()), "α̇ {} fd {fd_rate}", s.rate);
                // α̈ is continuous but α''' jumps at knots: the FD error is O(h·jump).
                let fd_acc = (p.rate - m.rate) / (2.0 * h);
                prop_assert!((fd_acc - s.accel).abs() <= 1e-3 * (1.0 + s.accel.abs()), "α̈ {} fd {fd_acc}", s.accel);
            }
        }
    }
}
