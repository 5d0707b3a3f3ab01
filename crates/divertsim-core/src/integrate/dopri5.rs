//! Dormand–Prince 5(4) with step-size control and 4th-order dense output.
//!
//! The method is the 7-stage, FSAL ("first same as last") pair of Dormand & Prince, advancing
//! with the 5th-order solution ("local extrapolation"). The error estimate is the difference to
//! the embedded 4th-order solution, measured in Hairer's RMS norm with the per-component scale
//! sc = atol + rtol·max(|y₀|, |y₁|). The step-size controller is the PI (Lund-stabilised)
//! controller of Hairer's `DOPRI5` code (β = 0.04, safety 0.9, step ratio limited to
//! [0.2, 10]); the first step is chosen by Hairer's `HINIT`. The continuous extension is
//! Hairer's 4th-order `CONTD5` polynomial (coefficients d₁..d₇, Shampine's dense output).
//!
//! Only forward integration (t_end > t) is supported.
//!
//! References: J. R. Dormand, P. J. Prince, "A family of embedded Runge–Kutta formulae",
//! J. Comput. Appl. Math. 6 (1980) 19–26; Hairer, Nørsett & Wanner, *Solving ODEs I*, 2nd ed.,
//! §II.4 (step control, starting step size), §II.5 (Table 5.2, DOPRI5), §II.6 (dense output,
//! DOPRI5 continuous extension); Hairer's Fortran code `dopri5.f` (2004) for the controller
//! constants; G. Söderlind, "Automatic control and adaptive time-stepping", Numer. Algorithms
//! 31 (2002) for the PI controller.

use super::IntegrateError;

/// Tolerances and limits of the integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Relative tolerance (dimensionless).
    pub rtol: f64,
    /// Absolute tolerance (units of the state components).
    pub atol: f64,
    /// Largest step \[s]. Non-positive or NaN means unbounded.
    pub h_max: f64,
    /// Smallest step before giving up \[s]. A final step shortened to land on `t_end` may be
    /// shorter.
    pub h_min: f64,
    /// First step \[s]; `None` (or a non-positive value) picks one automatically (Hairer's
    /// `HINIT`, two extra right-hand-side evaluations).
    pub h_init: Option<f64>,
    /// Bound on accepted + rejected steps in one call of `integrate`.
    pub max_steps: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            rtol: 1e-8,
            atol: 1e-10,
            h_max: f64::INFINITY,
            h_min: 1e-14,
            h_init: None,
            max_steps: 200_000,
        }
    }
}

// Butcher tableau of DOPRI5 (Hairer, Nørsett & Wanner, Table II.5.2).
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
// Error coefficients: 5th-order weights minus 4th-order weights.
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
// Dense output (Hairer's dopri5.f, Shampine 1986).
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

// Step-size controller (Hairer's dopri5.f defaults).
/// Safety factor.
const SAFE: f64 = 0.9;
/// Smallest step ratio h_new/h.
const FAC_MIN: f64 = 0.2;
/// Largest step ratio h_new/h.
const FAC_MAX: f64 = 10.0;
/// PI stabilisation exponent β (0 gives the classical I controller).
const BETA: f64 = 0.04;
/// exponent 1/5 − 0.75 β of the current error.
const EXPO1: f64 = 0.2 - BETA * 0.75;
/// ln of the floor (1e-4) of the remembered previous error.
const LN_ERR_OLD_MIN: f64 = -9.210_340_371_976_182;

/// One accepted step with its continuous extension.
///
/// The interpolant is Hairer's `CONTD5`: with θ = (t − t0)/h and θ₁ = 1 − θ,
/// y(t) ≈ y0 + θ(r₁ + θ₁(r₂ + θ(r₃ + θ₁ r₄))); it is 4th order, C¹ across steps, and exact at
/// both ends of the step it was built on.
#[derive(Debug, Clone)]
pub struct DenseStep<const N: usize> {
    /// Start of the step \[s].
    pub t0: f64,
    /// End of the step (or of its truncated part) \[s].
    pub t1: f64,
    /// State at `t0`.
    pub y0: [f64; N],
    /// State at `t1`.
    pub y1: [f64; N],
    /// Length of the step the interpolant was built on \[s] (≥ t1 − t0 after truncation).
    h: f64,
    /// Interpolation coefficients r₁..r₄ (`rcont2..rcont5` in dopri5.f).
    r: [[f64; N]; 4],
}

impl<const N: usize> DenseStep<N> {
    /// A step from its parts: the interpolant y0 + θ(r₁ + θ₁(r₂ + θ(r₃ + θ₁ r₄))) on a step of
    /// length `h` (for another stepper's continuous extension written in this form).
    pub(crate) fn from_parts(
        t0: f64,
        t1: f64,
        y0: [f64; N],
        y1: [f64; N],
        h: f64,
        r: [[f64; N]; 4],
    ) -> Self {
        DenseStep {
            t0,
            t1,
            y0,
            y1,
            h,
            r,
        }
    }

    /// The interpolated state at `t` ∈ [t0, t1] (outside, the polynomial is extrapolated).
    /// Returns `y1` exactly at `t == t1` and `y0` at `t == t0`.
    #[inline]
    pub fn eval(&self, t: f64) -> [f64; N] {
        if t == self.t1 {
            return self.y1;
        }
        let th = (t - self.t0) / self.h;
        let th1 = 1.0 - th;
        let [r1, r2, r3, r4] = &self.r;
        let mut out = self.y0;
        for i in 0..N {
            out[i] += th * (r1[i] + th1 * (r2[i] + th * (r3[i] + th1 * r4[i])));
        }
        out
    }

    /// The time derivative of the interpolant at `t` (a 3rd-order approximation of dy/dt;
    /// exact f(t0, y0) at `t0` and f(t1, y1) at the end of an untruncated step).
    #[inline]
    pub fn derivative(&self, t: f64) -> [f64; N] {
        let th = (t - self.t0) / self.h;
        let th1 = 1.0 - th;
        let [r1, r2, r3, r4] = &self.r;
        let mut out = [0.0; N];
        for i in 0..N {
            // P = y0 + θ S, S = r1 + θ1 R, R = r2 + θ Q, Q = r3 + θ1 r4; d/dθ by the chain rule.
            let q = r3[i] + th1 * r4[i];
            let dq = -r4[i];
            let rr = r2[i] + th * q;
            let drr = q + th * dq;
            let s = r1[i] + th1 * rr;
            let ds = -rr + th1 * drr;
            out[i] = (s + th * ds) / self.h;
        }
        out
    }

    /// The same interpolant restricted to [t0, t] (t is clamped into [t0, t1]); `y1` becomes
    /// `eval(t)`.
    #[inline]
    pub fn truncated(&self, t: f64) -> DenseStep<N> {
        let t = if t < self.t0 {
            self.t0
        } else if t > self.t1 {
            self.t1
        } else {
            t
        };
        let y1 = self.eval(t);
        DenseStep {
            t0: self.t0,
            t1: t,
            y0: self.y0,
            y1,
            h: self.h,
            r: self.r,
        }
    }

    /// Length of the step the interpolant was built on \[s].
    #[inline]
    pub fn full_step(&self) -> f64 {
        self.h
    }

    /// Bounds on the interpolant's first and second time derivatives over the whole step it
    /// was built on (θ ∈ [0, 1]), from its coefficients: with P = y0 + r₁θ + r₂θθ₁ + r₃θ²θ₁ +
    /// r₄θ²θ₁², |P'| ≤ |r₁| + |r₂| + |r₃| + |r₄|/(3√3) and |P''| ≤ 2|r₂| + 4|r₃| + 2|r₄| (per
    /// unit θ). These hold for the polynomial the event locator samples, whatever the
    /// solution does.
    pub fn bounds(&self) -> StepBounds<N> {
        let h = self.h;
        let [r1, r2, r3, r4] = &self.r;
        let mut b = StepBounds {
            h: self.t1 - self.t0,
            start_rate: [0.0; N],
            rate: [0.0; N],
            accel: [0.0; N],
        };
        for i in 0..N {
            let accel = (2.0 * r2[i].abs() + 4.0 * r3[i].abs() + 2.0 * r4[i].abs()) / (h * h);
            let start = (r1[i] + r2[i]) / h;
            let coef = (r1[i].abs() + r2[i].abs() + r3[i].abs() + 0.2 * r4[i].abs()) / h;
            b.start_rate[i] = start;
            b.rate[i] = coef.min(start.abs() + accel * h);
            b.accel[i] = accel;
        }
        b
    }
}

/// Bounds on how fast the interpolant of one step moves ([`DenseStep::bounds`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepBounds<const N: usize> {
    /// Length of the step (of its truncated part) \[s].
    pub h: f64,
    /// dP/dt at the step's start, per component.
    pub start_rate: [f64; N],
    /// Bound on |dP/dt| over the step, per component.
    pub rate: [f64; N],
    /// Bound on |d²P/dt²| over the step, per component.
    pub accel: [f64; N],
}

/// Work counters of a [`Dopri5`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected trial steps (error too large or non-finite values).
    pub rejected: usize,
    /// Right-hand-side evaluations.
    pub rhs_evals: usize,
}

/// The last accepted end point and its derivative, reused as the first stage of the next step
/// ("first same as last") when the next step starts exactly there.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Fsal<const N: usize> {
    pub(crate) t: f64,
    pub(crate) y: [f64; N],
    pub(crate) f: [f64; N],
}

/// The checks every stepper makes before a step from (t, y) towards `t_end`, and f(t, y):
/// the remembered end-point derivative if (t, y) is bitwise that end point, else a new
/// evaluation (counted in `stats`).
pub(crate) fn start_derivative<const N: usize, F: Fn(f64, &[f64; N]) -> [f64; N]>(
    fsal: &Option<Fsal<N>>,
    f: &F,
    t: f64,
    y: &[f64; N],
    t_end: f64,
    options: &Options,
    stats: &mut Stats,
) -> Result<[f64; N], IntegrateError> {
    if !t.is_finite() || t_end.is_nan() || !all_finite(y) {
        return Err(IntegrateError::NonFinite { t });
    }
    if t_end <= t {
        return Err(IntegrateError::StepTooSmall {
            t,
            h_min: options.h_min,
        });
    }
    let f0 = match fsal {
        Some(c) if c.t == t && c.y == *y => c.f,
        _ => {
            stats.rhs_evals += 1;
            f(t, y)
        }
    };
    if !all_finite(&f0) {
        return Err(IntegrateError::NonFinite { t });
    }
    Ok(f0)
}

/// The trial step (h, t_new) for the controller's `h_ctrl` from t: stretched or shortened to
/// land exactly on `t_end` when within 1 % of it (never beyond `h_max`), rather than leave a
/// sliver. Errors when the step falls below `h_min` or the resolution of t (`NonFinite` if the
/// last trial produced non-finite values).
pub(crate) fn trial_step(
    t: f64,
    t_end: f64,
    h_ctrl: f64,
    h_max: f64,
    h_min: f64,
    nonfinite_last: bool,
) -> Result<(f64, f64), IntegrateError> {
    let remaining = t_end - t;
    let last = 1.01 * h_ctrl >= remaining && remaining <= h_max;
    let h = if last { remaining } else { h_ctrl };
    if h_ctrl < h_min || h_ctrl.is_nan() || h_ctrl <= 0.0 || t + h == t {
        return Err(if nonfinite_last {
            IntegrateError::NonFinite { t }
        } else {
            IntegrateError::StepTooSmall { t, h_min }
        });
    }
    Ok((h, if last { t_end } else { t + h }))
}

/// Hairer's RMS error norm of the estimate `e` with the scale atol + rtol·max(|y₀|, |y₁|).
pub(crate) fn error_norm<const N: usize>(
    e: impl Fn(usize) -> f64,
    y0: &[f64; N],
    y1: &[f64; N],
    options: &Options,
) -> f64 {
    let mut sum = 0.0;
    for i in 0..N {
        let sk = options.atol + options.rtol * y0[i].abs().max(y1[i].abs());
        sum += scaled(e(i), sk).powi(2);
    }
    (sum / N.max(1) as f64).sqrt()
}

/// The stepper: holds the options and the step-size controller state.
///
/// Between calls it keeps the proposed next step, the previous error (PI controller) and the
/// derivative at the last end point. That derivative is reused only if the next step starts
/// at bitwise the same (t, y); if the caller changes the right-hand side between steps
/// without changing (t, y), it must call [`Dopri5::forget_derivative`] (or [`Dopri5::reset`]).
#[derive(Debug, Clone)]
pub struct Dopri5<const N: usize> {
    /// Tolerances and limits.
    pub options: Options,
    /// Proposed next step \[s].
    h_next: Option<f64>,
    /// Previous accepted error (PI controller memory).
    /// ln of the previous accepted error (PI controller memory; logs save a `powf`).
    ln_err_old: f64,
    fsal: Option<Fsal<N>>,
    stats: Stats,
}

#[inline]
pub(crate) fn all_finite<const N: usize>(y: &[f64; N]) -> bool {
    y.iter().all(|v| v.is_finite())
}

/// e/sc without 0/0 (atol = 0 with a zero component).
#[inline]
fn scaled(e: f64, sc: f64) -> f64 {
    if sc > 0.0 {
        e / sc
    } else if e == 0.0 {
        0.0
    } else {
        f64::INFINITY
    }
}

impl<const N: usize> Dopri5<N> {
    /// A fresh stepper (no proposed step, no cached derivative).
    pub fn new(options: Options) -> Self {
        Dopri5 {
            options,
            h_next: None,
            ln_err_old: LN_ERR_OLD_MIN,
            fsal: None,
            stats: Stats::default(),
        }
    }

    /// Drop all cached state: the proposed step, the controller memory and the cached
    /// derivative. The next step starts as if the stepper were new (counters are kept).
    pub fn reset(&mut self) {
        self.h_next = None;
        self.ln_err_old = LN_ERR_OLD_MIN;
        self.fsal = None;
    }

    /// Drop only the cached end-point derivative (FSAL), keeping the step-size proposal: use
    /// when the right-hand side changes between steps.
    pub fn forget_derivative(&mut self) {
        self.fsal = None;
    }

    /// Multiply the proposed next step by `factor` (> 0; anything else is ignored), e.g. when
    /// the caller knows that the solution's time scale has changed by that factor.
    pub fn scale_proposed_step(&mut self, factor: f64) {
        if let Some(h) = self.h_next.as_mut() {
            if factor > 0.0 && factor.is_finite() {
                *h *= factor;
            }
        }
    }

    /// Set the next step \[s] (ignored unless positive and finite), e.g. when taking over from
    /// another stepper.
    pub fn set_proposed_step(&mut self, h: f64) {
        if h > 0.0 && h.is_finite() {
            self.h_next = Some(h);
        }
    }

    /// The step the controller proposes for the next call \[s], if any.
    pub fn proposed_step(&self) -> Option<f64> {
        self.h_next
    }

    /// Work counters since construction.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Largest allowed step \[s].
    #[inline]
    fn h_max(&self) -> f64 {
        let h = self.options.h_max;
        if h > 0.0 {
            h
        } else {
            f64::INFINITY
        }
    }

    /// Hairer's `HINIT`: a first step from the size of y, f and an estimate of the second
    /// derivative, so that the local error of a 4th-order step is about 0.01 (in tolerance units).
    fn initial_step<F: Fn(f64, &[f64; N]) -> [f64; N]>(
        &mut self,
        f: &F,
        t: f64,
        y: &[f64; N],
        f0: &[f64; N],
        h_max: f64,
    ) -> f64 {
        let (rtol, atol) = (self.options.rtol, self.options.atol);
        let mut dnf = 0.0;
        let mut dny = 0.0;
        for i in 0..N {
            let sk = atol + rtol * y[i].abs();
            dnf += scaled(f0[i], sk).powi(2);
            dny += scaled(y[i], sk).powi(2);
        }
        let mut h = if dnf <= 1e-10 || dny <= 1e-10 || !(dnf.is_finite() && dny.is_finite()) {
            1e-6
        } else {
            (dny / dnf).sqrt() * 0.01
        };
        h = h.min(h_max);
        // Explicit Euler trial step to estimate the second derivative.
        let mut y1 = *y;
        for i in 0..N {
            y1[i] += h * f0[i];
        }
        let f1 = f(t + h, &y1);
        self.stats.rhs_evals += 1;
        let mut der2 = 0.0;
        for i in 0..N {
            let sk = atol + rtol * y[i].abs();
            der2 += scaled(f1[i] - f0[i], sk).powi(2);
        }
        let der2 = der2.sqrt() / h;
        // (f64::max would silently drop a NaN.)
        let der12 = if der2.is_finite() {
            der2.max(dnf.sqrt())
        } else {
            f64::INFINITY
        };
        let h1 = if !der12.is_finite() {
            // The trial step left the domain of f: stay with the small trial step.
            h
        } else if der12 <= 1e-15 {
            (h * 1e-3).max(1e-6)
        } else {
            (0.01 / der12).powf(1.0 / 5.0)
        };
        (100.0 * h).min(h1).min(h_max)
    }

    /// Take one accepted step from (t, y) towards `t_end` with the right-hand side `f`.
    ///
    /// The step never passes `t_end`; a step that would end within 1 % of a step before
    /// `t_end` is stretched to land on it exactly (then `t1 == t_end` bitwise).
    ///
    /// Errors: `NonFinite` if (t, y) or f(t, y) is not finite, or if trial steps keep producing
    /// non-finite values until the step falls below `h_min`; `StepTooSmall` if the controller
    /// asks for a step below `h_min` (or below the resolution of t), and also if
    /// `t_end <= t` (nothing to step over).
    pub fn step<F: Fn(f64, &[f64; N]) -> [f64; N]>(
        &mut self,
        f: F,
        t: f64,
        y: &[f64; N],
        t_end: f64,
    ) -> Result<DenseStep<N>, IntegrateError> {
        let o = self.options;
        let k1 = start_derivative(&self.fsal, &f, t, y, t_end, &o, &mut self.stats)?;
        let h_max = self.h_max();
        let mut h_ctrl = match self.h_next {
            Some(h) => h,
            None => match o.h_init {
                Some(h) if h > 0.0 && h.is_finite() => h,
                _ => self.initial_step(&f, t, y, &k1, h_max),
            },
        };
        h_ctrl = h_ctrl.min(h_max);
        let mut rejected_last = false;
        let mut nonfinite_last = false;

        loop {
            let (h, t_new) = trial_step(t, t_end, h_ctrl, h_max, o.h_min, nonfinite_last)?;

            let mut yt = *y;
            for i in 0..N {
                yt[i] = y[i] + h * A21 * k1[i];
            }
            let k2 = f(t + C2 * h, &yt);
            for i in 0..N {
                yt[i] = y[i] + h * (A31 * k1[i] + A32 * k2[i]);
            }
            let k3 = f(t + C3 * h, &yt);
            for i in 0..N {
                yt[i] = y[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
            }
            let k4 = f(t + C4 * h, &yt);
            for i in 0..N {
                yt[i] = y[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
            }
            let k5 = f(t + C5 * h, &yt);
            for i in 0..N {
                yt[i] = y[i]
                    + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]);
            }
            let k6 = f(t_new, &yt);
            let mut y1 = *y;
            for i in 0..N {
                y1[i] = y[i]
                    + h * (A71 * k1[i] + A73 * k3[i] + A74 * k4[i] + A75 * k5[i] + A76 * k6[i]);
            }
            let k7 = f(t_new, &y1);
            self.stats.rhs_evals += 6;

            let err = error_norm(
                |i| {
                    h * (E1 * k1[i]
                        + E3 * k3[i]
                        + E4 * k4[i]
                        + E5 * k5[i]
                        + E6 * k6[i]
                        + E7 * k7[i])
                },
                y,
                &y1,
                &o,
            );

            if err.is_nan() || !all_finite(&y1) || !all_finite(&k7) {
                // A trial step left the domain of f (or overflowed): shrink hard and retry.
                self.stats.rejected += 1;
                rejected_last = true;
                nonfinite_last = true;
                h_ctrl = h * FAC_MIN;
                continue;
            }
            let ln_err = err.ln();
            if err <= 1.0 {
                let fac =
                    // err^EXPO1 / err_old^BETA / SAFE
                    ((EXPO1 * ln_err - BETA * self.ln_err_old).exp() / SAFE)
                        .clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
                let mut h_new = (h / fac).min(h_max);
                if rejected_last {
                    h_new = h_new.min(h);
                }
                self.ln_err_old = ln_err.max(LN_ERR_OLD_MIN);
                self.h_next = Some(h_new);
                self.stats.accepted += 1;
                self.fsal = Some(Fsal {
                    t: t_new,
                    y: y1,
                    f: k7,
                });
                let mut r = [[0.0; N]; 4];
                for i in 0..N {
                    let ydiff = y1[i] - y[i];
                    let bspl = h * k1[i] - ydiff;
                    r[0][i] = ydiff;
                    r[1][i] = bspl;
                    r[2][i] = ydiff - h * k7[i] - bspl;
                    r[3][i] = h
                        * (D1 * k1[i]
                            + D3 * k3[i]
                            + D4 * k4[i]
                            + D5 * k5[i]
                            + D6 * k6[i]
                            + D7 * k7[i]);
                }
                return Ok(DenseStep {
                    t0: t,
                    t1: t_new,
                    y0: *y,
                    y1,
                    h,
                    r,
                });
            }
            // Rejected: shrink by the I controller only (no PI memory on rejection).
            self.stats.rejected += 1;
            rejected_last = true;
            nonfinite_last = false;
            let fac11 = (EXPO1 * ln_err).exp();
            h_ctrl = h / (fac11 / SAFE).min(1.0 / FAC_MIN);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_models::*;
    use super::super::{integrate, HybridSystem};
    use super::*;
    use proptest::prelude::*;
    use std::cell::Cell;

    fn opts(rtol: f64) -> Options {
        Options {
            rtol,
            atol: rtol * 1e-2,
            ..Options::default()
        }
    }

    /// A stepper forced to take exactly steps of size h (tolerance so loose nothing is
    /// rejected, h_max = h).
    fn fixed(h: f64) -> Dopri5<2> {
        Dopri5::new(Options {
            rtol: 1e3,
            atol: 1e3,
            h_max: h,
            h_init: Some(h),
            ..Options::default()
        })
    }

    fn max_err2(a: [f64; 2], b: [f64; 2]) -> f64 {
        (a[0] - b[0]).abs().max((a[1] - b[1]).abs())
    }

    /// Global error of y' = −y on [0, 5] stays below 10·rtol (scale max|y| = 1).
    #[test]
    fn decay_global_error_scales_with_rtol() {
        for rtol in [1e-4, 1e-6, 1e-8, 1e-10, 1e-12] {
            let s = integrate(&mut Decay, 0.0, [1.0], 5.0, &opts(rtol), |_| {}).unwrap();
            assert_eq!(s.t, 5.0);
            let err = (s.y[0] - (-5.0f64).exp()).abs();
            assert!(err <= 10.0 * rtol, "rtol {rtol:e}: error {err:e}");
        }
    }

    /// Harmonic oscillator (ω = 2, three periods) and plane rotation (ω = 1, ≈ 3 turns): the
    /// global error is ≤ 10·rtol·scale, and the interpolant at interior points of every step is
    /// as accurate as the step ends.
    #[test]
    fn oscillator_and_rotation_global_and_dense_error() {
        for rtol in [1e-4, 1e-6, 1e-8, 1e-10, 1e-12] {
            let osc = Oscillator::free(2.0);
            let y0 = [1.0, 0.0];
            let mut dense_err = 0.0f64;
            let mut last_t1 = 0.0;
            let s = integrate(
                &mut Oscillator::free(2.0),
                0.0,
                y0,
                10.0,
                &opts(rtol),
                |st| {
                    assert_eq!(st.t0, last_t1, "observer steps are contiguous");
                    last_t1 = st.t1;
                    for k in 1..10 {
                        let t = st.t0 + (st.t1 - st.t0) * f64::from(k) / 10.0;
                        let (y, ex) = (st.eval(t), osc.exact(t, y0));
                        // v scales with ω: compare v/ω.
                        dense_err =
                            dense_err.max((y[0] - ex[0]).abs().max((y[1] - ex[1]).abs() / 2.0));
                    }
                },
            )
            .unwrap();
            let ex = osc.exact(10.0, y0);
            let err = (s.y[0] - ex[0]).abs().max((s.y[1] - ex[1]).abs() / 2.0);
            assert!(err <= 10.0 * rtol, "oscillator rtol {rtol:e}: {err:e}");
            assert!(
                dense_err <= 10.0 * rtol,
                "dense rtol {rtol:e}: {dense_err:e}"
            );

            let rot = Rotation { omega: 1.0 };
            let s = integrate(
                &mut Rotation { omega: 1.0 },
                0.0,
                [1.0, 0.0],
                20.0,
                &opts(rtol),
                |_| {},
            )
            .unwrap();
            let ex = rot.exact(20.0, [1.0, 0.0]);
            let err = (s.y[0] - ex[0]).hypot(s.y[1] - ex[1]);
            assert!(err <= 10.0 * rtol, "rotation rtol {rtol:e}: {err:e}");
        }
    }

    /// One step of the 5th-order solution has a local error O(h⁶): halving h divides it by
    /// ≈ 64. (The embedded 4th-order estimate and the dense output have O(h⁵): ≈ 32.)
    #[test]
    fn single_step_local_error_orders() {
        let osc = Oscillator::free(1.0);
        let y0 = [1.0, 0.3];
        let f = |t: f64, y: &[f64; 2]| osc.rhs(t, y);
        let local = |h: f64| {
            let st = fixed(h).step(f, 0.0, &y0, 10.0).unwrap();
            assert_eq!(st.t1, h);
            let end = max_err2(st.y1, osc.exact(h, y0));
            let mid = max_err2(st.eval(0.5 * h), osc.exact(0.5 * h, y0));
            (end, mid)
        };
        let (e1, m1) = local(0.2);
        let (e2, m2) = local(0.1);
        let order_end = (e1 / e2).log2();
        let order_mid = (m1 / m2).log2();
        assert!((5.6..6.4).contains(&order_end), "local order {order_end}");
        assert!(
            (4.6..5.4).contains(&order_mid),
            "dense local order {order_mid}"
        );
    }

    /// With fixed steps the global error is O(h⁵): halving h divides it by ≈ 32.
    #[test]
    fn fixed_step_global_order_five() {
        let osc = Oscillator::free(1.0);
        let y0 = [1.0, 0.0];
        let global = |h: f64| {
            let mut st = fixed(h);
            let (mut t, mut y) = (0.0, y0);
            while t < 2.0 {
                let d = st.step(|t, y| osc.rhs(t, y), t, &y, 2.0).unwrap();
                (t, y) = (d.t1, d.y1);
            }
            assert_eq!(t, 2.0);
            max_err2(y, osc.exact(2.0, y0))
        };
        let ratio = global(0.1) / global(0.05);
        assert!((26.0..38.0).contains(&ratio), "ratio {ratio}");
    }

    /// The end derivative of the interpolant is the rhs at the step end, its start derivative
    /// the rhs at the start, and a truncated step keeps the same interpolant.
    #[test]
    fn dense_derivative_and_truncation() {
        let osc = Oscillator::free(3.0);
        let f = |t: f64, y: &[f64; 2]| osc.rhs(t, y);
        let mut st = Dopri5::new(opts(1e-8));
        let d = st.step(f, 0.0, &[1.0, 0.5], 10.0).unwrap();
        assert!(max_err2(d.derivative(d.t0), f(d.t0, &d.y0)) < 1e-12);
        assert!(max_err2(d.derivative(d.t1), f(d.t1, &d.y1)) < 1e-12);
        // Central difference of the interpolant in the middle.
        let (tm, eps) = (0.5 * (d.t0 + d.t1), 1e-6);
        let (p, m) = (d.eval(tm + eps), d.eval(tm - eps));
        let fd = [(p[0] - m[0]) / (2.0 * eps), (p[1] - m[1]) / (2.0 * eps)];
        assert!(max_err2(d.derivative(tm), fd) < 1e-7);
        let tr = d.truncated(tm);
        assert_eq!((tr.t0, tr.t1, tr.y0), (d.t0, tm, d.y0));
        assert_eq!(tr.y1, d.eval(tm));
        let tq = d.t0 + 0.3 * (tm - d.t0);
        assert_eq!(tr.eval(tq), d.eval(tq));
        assert_eq!(d.eval(d.t1), d.y1);
        assert_eq!(d.eval(d.t0), d.y0);
    }

    /// The stepper lands exactly on t_end, never passes it, and respects h_max.
    #[test]
    fn never_past_t_end_and_respects_h_max() {
        let osc = Oscillator::free(1.0);
        let mut st = Dopri5::new(Options {
            h_max: 0.07,
            ..opts(1e-6)
        });
        let (mut t, mut y, t_end) = (0.0, [1.0, 0.0], 1.234_567);
        let mut n = 0;
        while t < t_end {
            let d = st.step(|t, y| osc.rhs(t, y), t, &y, t_end).unwrap();
            assert!(d.t1 <= t_end && d.t1 - d.t0 <= 0.07 * (1.0 + 1e-12));
            (t, y, n) = (d.t1, d.y1, n + 1);
        }
        assert_eq!(t, t_end);
        assert!(n >= 18);
        // Nothing left to step over.
        assert!(matches!(
            st.step(|t, y| osc.rhs(t, y), t, &y, t_end),
            Err(IntegrateError::StepTooSmall { .. })
        ));
    }

    /// The end derivative is reused (6 rhs calls per step) only when the next step starts at
    /// the cached point; a different y, `forget_derivative` or `reset` re-evaluates it.
    #[test]
    fn fsal_reuse_only_at_cached_point() {
        let calls = Cell::new(0usize);
        let f = |_t: f64, y: &[f64; 2]| {
            calls.set(calls.get() + 1);
            [y[1], -y[0]]
        };
        // Loose tolerance and a small first step: no rejections, so the counts are exact.
        let mut st = Dopri5::new(Options {
            h_init: Some(0.01),
            ..opts(1e-3)
        });
        let d = st.step(f, 0.0, &[1.0, 0.0], 10.0).unwrap();
        assert_eq!(calls.replace(0), 7);
        let d2 = st.step(f, d.t1, &d.y1, 10.0).unwrap();
        assert_eq!(calls.replace(0), 6);
        let mut y = d2.y1;
        y[0] += 1e-9;
        let d3 = st.step(f, d2.t1, &y, 10.0).unwrap();
        assert_eq!(calls.replace(0), 7);
        st.forget_derivative();
        let d4 = st.step(f, d3.t1, &d3.y1, 10.0).unwrap();
        assert_eq!(calls.replace(0), 7);
        st.reset();
        assert_eq!(st.proposed_step(), None);
        st.step(f, d4.t1, &d4.y1, 10.0).unwrap();
        // Fresh start derivative; the first step is h_init again.
        assert_eq!(calls.replace(0), 7);
        assert_eq!(st.proposed_step().map(|h| h > 0.01), Some(true));
        let s = st.stats();
        assert_eq!((s.accepted, s.rejected), (5, 0));
        assert_eq!(s.rhs_evals, 7 + 6 + 7 + 7 + 7);
        // Automatic first step (HINIT) costs one more evaluation.
        let mut auto = Dopri5::new(opts(1e-3));
        auto.step(f, 0.0, &[1.0, 0.0], 10.0).unwrap();
        assert_eq!(calls.replace(0), 8 + 6 * auto.stats().rejected);
    }

    /// y' = y² blows up at t = 1: integrating to t = 2 ends in an error near t = 1, quickly.
    #[test]
    fn blow_up_is_an_error_not_a_hang() {
        let r = integrate(&mut BlowUp, 0.0, [1.0], 2.0, &Options::default(), |_| {});
        match r {
            Err(IntegrateError::StepTooSmall { t, .. }) | Err(IntegrateError::NonFinite { t }) => {
                assert!((t - 1.0).abs() < 1e-6, "t = {t}")
            }
            other => panic!("expected an error, got {other:?}"),
        }
        // Without h_min the resolution of t still stops it.
        let o = Options {
            h_min: 0.0,
            ..Options::default()
        };
        assert!(integrate(&mut BlowUp, 0.0, [1.0], 2.0, &o, |_| {}).is_err());
    }

    /// NaN from the rhs: at the start → NonFinite at once; later → NonFinite where it starts.
    #[test]
    fn non_finite_rhs_is_reported() {
        let o = Options::default();
        let r = integrate(&mut NanAfter { t_bad: 0.0 }, 0.0, [1.0], 1.0, &o, |_| {});
        assert_eq!(r, Err(IntegrateError::NonFinite { t: 0.0 }));
        match integrate(&mut NanAfter { t_bad: 0.5 }, 0.0, [1.0], 1.0, &o, |_| {}) {
            Err(IntegrateError::NonFinite { t }) => assert!((0.5 - t) < 1e-10 && t < 0.5),
            other => panic!("expected NonFinite, got {other:?}"),
        }
        let r = integrate(&mut Decay, 0.0, [f64::NAN], 1.0, &o, |_| {});
        assert_eq!(r, Err(IntegrateError::NonFinite { t: 0.0 }));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Random oscillators, initial states and tolerances: global error ≤ 10·rtol·scale.
        #[test]
        fn random_oscillators_meet_tolerance(
            omega in 0.2f64..5.0,
            x0 in -2.0f64..2.0,
            v0 in -2.0f64..2.0,
            t_end in 0.1f64..10.0,
            lg in 4i32..11,
        ) {
            let rtol = 10f64.powi(-lg);
            let osc = Oscillator::free(omega);
            let scale = x0.hypot(v0 / omega).max(1e-3);
            let o = Options { rtol, atol: rtol * scale, ..Options::default() };
            let s = integrate(&mut Oscillator::free(omega), 0.0, [x0, v0], t_end, &o, |_| {}).unwrap();
            let ex = osc.exact(t_end, [x0, v0]);
            let err = (s.y[0] - ex[0]).abs().max((s.y[1] - ex[1]).abs() / omega);
            // The error grows with the number of periods; allow for it.
            let periods = 1.0 + omega * t_end / std::f64::consts::TAU;
            prop_assert!(err <= 10.0 * rtol * scale * periods, "err {:e}", err);
        }
    }
}
