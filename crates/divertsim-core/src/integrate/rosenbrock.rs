//! A linearly implicit (Rosenbrock) 2(3) stepper for stiff stretches, with the same dense
//! output type as [`super::dopri5`].
//!
//! Explicit methods such as DOPRI5 are stable only for steps h ≲ 3.3/|λ| on a decaying mode
//! with rate λ. Coulomb friction at a small slip |w| damps the slip's free directions at
//! |λ| ≈ μg/|w|: a parcel pushed by the arm from riding (slip growing from zero) makes an
//! explicit method crawl at microsecond steps that its accuracy does not need. This stepper
//! is L-stable, so its step is set by accuracy alone.
//!
//! The method is Shampine's ROS2 pair of MATLAB's `ode23s`: with W = I − h d J,
//! d = 1/(2 + √2), J = ∂f/∂y and T = ∂f/∂t (both by forward differences),
//! F₀ = f(t, y), k₁ = W⁻¹(F₀ + h d T), F₁ = f(t + h/2, y + h k₁/2),
//! k₂ = W⁻¹(F₁ − k₁) + k₁, y₁ = y + h k₂, F₂ = f(t + h, y₁),
//! k₃ = W⁻¹(F₂ − e₃₂(k₂ − F₁) − 2(k₁ − F₀) + h d T), e₃₂ = 6 + √2;
//! the error estimate is h(k₁ − 2k₂ + k₃)/6 in the same RMS norm as DOPRI5, the step is
//! controlled by err^(−1/3) (safety 0.9, ratio in [0.2, 5]), and the continuous extension
//! y(t + sh) = y + h[s(1 − s) k₁ + s(s − 2d) k₂]/(1 − 2d) is exact at both ends. F₂ is the
//! next step's F₀ (first same as last).
//!
//! References: L. F. Shampine, M. W. Reichelt, "The MATLAB ODE suite", SIAM J. Sci. Comput.
//! 18 (1997) 1–22, §3 (the formulas above); Hairer & Wanner, *Solving ODEs II*, §IV.7
//! (Rosenbrock methods, L-stability).

// Index loops follow the formulas (rows, columns, components) more clearly than iterators.
#![allow(clippy::needless_range_loop)]

use super::dopri5::{
    all_finite, error_norm, start_derivative, trial_step, DenseStep, Fsal, Options, Stats,
};
use super::IntegrateError;

const SQRT2: f64 = std::f64::consts::SQRT_2;
/// d = 1/(2 + √2)
const D: f64 = 1.0 / (2.0 + SQRT2);
/// e₃₂ = 6 + √2
const E32: f64 = 6.0 + SQRT2;
const SAFE: f64 = 0.9;
const FAC_MIN: f64 = 0.2;
const FAC_MAX: f64 = 5.0;
/// Relative size of the finite-difference increments of J and T.
const FD_REL: f64 = 1.5e-8;

/// The stepper: the options, the proposed next step and the derivative at the last end.
#[derive(Debug, Clone)]
pub struct Rosenbrock<const N: usize> {
    /// Tolerances and limits (`h_init` is the first step when nothing is proposed).
    pub options: Options,
    h_next: Option<f64>,
    fsal: Option<Fsal<N>>,
    stats: Stats,
}

/// LU factors of an N × N matrix with partial pivoting, or `None` if it is singular.
fn lu<const N: usize>(mut a: [[f64; N]; N]) -> Option<([[f64; N]; N], [usize; N])> {
    let mut perm = [0usize; N];
    for (i, p) in perm.iter_mut().enumerate() {
        *p = i;
    }
    for k in 0..N {
        let p = (k..N).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
        if a[p][k] == 0.0 || !a[p][k].is_finite() {
            return None;
        }
        a.swap(k, p);
        perm.swap(k, p);
        for i in k + 1..N {
            let m = a[i][k] / a[k][k];
            a[i][k] = m;
            for j in k + 1..N {
                a[i][j] -= m * a[k][j];
            }
        }
    }
    Some((a, perm))
}

/// Solve with the factors of [`lu`].
fn solve<const N: usize>(f: &([[f64; N]; N], [usize; N]), b: &[f64; N]) -> [f64; N] {
    let (a, perm) = f;
    let mut x = [0.0; N];
    for i in 0..N {
        x[i] = b[perm[i]];
    }
    for i in 0..N {
        for j in 0..i {
            x[i] -= a[i][j] * x[j];
        }
    }
    for i in (0..N).rev() {
        for j in i + 1..N {
            x[i] -= a[i][j] * x[j];
        }
        x[i] /= a[i][i];
    }
    x
}

impl<const N: usize> Rosenbrock<N> {
    /// A fresh stepper.
    pub fn new(options: Options) -> Self {
        Rosenbrock {
            options,
            h_next: None,
            fsal: None,
            stats: Stats::default(),
        }
    }

    /// The step proposed for the next call \[s], if any.
    pub fn proposed_step(&self) -> Option<f64> {
        self.h_next
    }

    /// Set the next step \[s] (ignored unless positive and finite).
    pub fn set_proposed_step(&mut self, h: f64) {
        if h > 0.0 && h.is_finite() {
            self.h_next = Some(h);
        }
    }

    /// Drop the cached start derivative (the right-hand side changed between steps).
    pub fn forget_derivative(&mut self) {
        self.fsal = None;
    }

    /// Work counters since construction.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Take one accepted step from (t, y) towards `t_end`, as [`super::Dopri5::step`] does
    /// (never past `t_end`, landing on it when within 1 %; the same errors).
    pub fn step<F: Fn(f64, &[f64; N]) -> [f64; N]>(
        &mut self,
        f: F,
        t: f64,
        y: &[f64; N],
        t_end: f64,
    ) -> Result<DenseStep<N>, IntegrateError> {
        let o = self.options;
        let f0 = start_derivative(&self.fsal, &f, t, y, t_end, &o, &mut self.stats)?;
        // J and T by forward differences, once per step (kept over rejections).
        let mut jac = [[0.0; N]; N];
        for j in 0..N {
            let dy = FD_REL * y[j].abs().max(1.0);
            let mut yp = *y;
            yp[j] += dy;
            let dy = yp[j] - y[j];
            let fp = f(t, &yp);
            for i in 0..N {
                jac[i][j] = (fp[i] - f0[i]) / dy;
            }
        }
        let dt = FD_REL * t.abs().max(1.0);
        let dt = (t + dt) - t;
        let ft = f(t + dt, y);
        let mut tder = [0.0; N];
        for i in 0..N {
            tder[i] = (ft[i] - f0[i]) / dt;
        }
        self.stats.rhs_evals += N + 1;

        let h_max = if o.h_max > 0.0 {
            o.h_max
        } else {
            f64::INFINITY
        };
        let mut h_ctrl = self
            .h_next
            .or(o.h_init.filter(|h| *h > 0.0 && h.is_finite()))
            .unwrap_or(1e-6)
            .min(h_max);
        let mut rejected_last = false;
        let mut nonfinite_last = false;
        loop {
            let (h, t_new) = trial_step(t, t_end, h_ctrl, h_max, o.h_min, nonfinite_last)?;
            let mut w = [[0.0; N]; N];
            for i in 0..N {
                for j in 0..N {
                    w[i][j] = if i == j { 1.0 } else { 0.0 } - h * D * jac[i][j];
                }
            }
            let Some(factors) = lu(w) else {
                self.stats.rejected += 1;
                rejected_last = true;
                h_ctrl = h * 0.5;
                continue;
            };
            let mut b = [0.0; N];
            for i in 0..N {
                b[i] = f0[i] + h * D * tder[i];
            }
            let k1 = solve(&factors, &b);
            let mut yt = *y;
            for i in 0..N {
                yt[i] = y[i] + 0.5 * h * k1[i];
            }
            let f1 = f(t + 0.5 * h, &yt);
            for i in 0..N {
                b[i] = f1[i] - k1[i];
            }
            let mut k2 = solve(&factors, &b);
            for i in 0..N {
                k2[i] += k1[i];
            }
            let mut y1 = *y;
            for i in 0..N {
                y1[i] = y[i] + h * k2[i];
            }
            let f2 = f(t_new, &y1);
            for i in 0..N {
                b[i] = f2[i] - E32 * (k2[i] - f1[i]) - 2.0 * (k1[i] - f0[i]) + h * D * tder[i];
            }
            let k3 = solve(&factors, &b);
            self.stats.rhs_evals += 2;

            let err = error_norm(|i| h / 6.0 * (k1[i] - 2.0 * k2[i] + k3[i]), y, &y1, &o);
            if err.is_nan() || !all_finite(&y1) || !all_finite(&f2) {
                self.stats.rejected += 1;
                rejected_last = true;
                nonfinite_last = true;
                h_ctrl = h * FAC_MIN;
                continue;
            }
            nonfinite_last = false;
            let fac = (SAFE * err.powf(-1.0 / 3.0)).clamp(FAC_MIN, FAC_MAX);
            if err <= 1.0 {
                let mut h_new = (h * fac).min(h_max);
                if rejected_last {
                    h_new = h_new.min(h);
                }
                self.h_next = Some(h_new);
                self.stats.accepted += 1;
                self.fsal = Some(Fsal {
                    t: t_new,
                    y: y1,
                    f: f2,
                });
                // y0 + θ(r₁ + θ₁ r₂): r₁ = y₁ − y₀, r₂ = −h(k₂ − k₁)/(1 − 2d).
                let mut r = [[0.0; N]; 4];
                for i in 0..N {
                    r[0][i] = y1[i] - y[i];
                    r[1][i] = -h * (k2[i] - k1[i]) / (1.0 - 2.0 * D);
                }
                return Ok(DenseStep::from_parts(t, t_new, *y, y1, h, r));
            }
            self.stats.rejected += 1;
            rejected_last = true;
            h_ctrl = h * fac.min(1.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts(rtol: f64) -> Options {
        Options {
            rtol,
            atol: rtol * 1e-2,
            ..Options::default()
        }
    }

    /// Prothero–Robinson y' = λ(y − cos t) − sin t, y(0) = 1, exact y = cos t, λ = −1e6:
    /// stiff far beyond an explicit method's reach, and every step size is free to be large.
    fn prothero(t: f64, y: &[f64; 1]) -> [f64; 1] {
        [-1e6 * (y[0] - t.cos()) - t.sin()]
    }

    fn run(rtol: f64) -> (f64, usize) {
        let mut r = Rosenbrock::new(opts(rtol));
        let (mut t, mut y) = (0.0, [1.0]);
        let mut worst = 0.0f64;
        while t < 2.0 {
            let s = r.step(prothero, t, &y, 2.0).unwrap();
            for k in 0..=8 {
                let tt = s.t0 + (s.t1 - s.t0) * k as f64 / 8.0;
                worst = worst.max((s.eval(tt)[0] - tt.cos()).abs());
            }
            (t, y) = (s.t1, s.y1);
        }
        assert_eq!(t, 2.0);
        (worst, r.stats().accepted)
    }

    /// On the stiff Prothero–Robinson problem the error of the steps and of the dense output
    /// stays within a few tolerances, in a small fraction of the ≈ 6·10⁵ steps an explicit
    /// method needs for stability alone (|λ| h ≤ 3.3 over 2 s): the step is set by accuracy,
    /// so it grows as the tolerance loosens (2nd order: ∝ rtol^(1/3)).
    #[test]
    fn stiff_prothero_robinson_is_accurate_in_few_steps() {
        let mut last = usize::MAX;
        for rtol in [1e-8, 1e-6, 1e-4] {
            let (err, steps) = run(rtol);
            assert!(err <= 20.0 * rtol, "rtol {rtol:e}: error {err:e}");
            assert!(steps * 20 < 600_000, "rtol {rtol:e}: {steps} steps");
            assert!(
                steps < last,
                "rtol {rtol:e}: {steps} steps, not fewer than {last}"
            );
            last = steps;
        }
    }

    /// Non-stiff accuracy: y' = −y on [0, 5] ends within 10 rtol of e⁻⁵; the error falls
    /// with the tolerance (a 2nd-order method: the steps grow as rtol^(−1/3)).
    #[test]
    fn decay_global_error_scales_with_rtol() {
        let mut last_steps = 0;
        for rtol in [1e-4, 1e-6, 1e-8] {
            let mut r = Rosenbrock::new(opts(rtol));
            let (mut t, mut y) = (0.0, [1.0]);
            while t < 5.0 {
                let s = r.step(|_, y: &[f64; 1]| [-y[0]], t, &y, 5.0).unwrap();
                (t, y) = (s.t1, s.y1);
            }
            let err = (y[0] - (-5.0f64).exp()).abs();
            assert!(err <= 10.0 * rtol, "rtol {rtol:e}: error {err:e}");
            let steps = r.stats().accepted;
            assert!(
                steps > last_steps,
                "steps must grow as the tolerance tightens"
            );
            last_steps = steps;
        }
    }

    /// The LU solve inverts a pivoting-requiring matrix exactly enough.
    #[test]
    fn lu_solves_with_pivoting() {
        let a = [[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [3.0, 0.0, 1.0]];
        let x = [1.0, -2.0, 0.5];
        let mut b = [0.0; 3];
        for i in 0..3 {
            for j in 0..3 {
                b[i] += a[i][j] * x[j];
            }
        }
        let got = solve(&lu(a).unwrap(), &b);
        for i in 0..3 {
            assert!((got[i] - x[i]).abs() < 1e-14, "{got:?}");
        }
        assert!(lu([[1.0, 2.0], [2.0, 4.0]]).is_none());
    }
}
