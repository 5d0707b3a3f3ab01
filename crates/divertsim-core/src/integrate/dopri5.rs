//! Dormand–Prince 5(4) with step-size control and 4th-order dense output.
//!
//! References: J. R. Dormand, P. J. Prince, "A family of embedded Runge–Kutta formulae",
//! J. Comput. Appl. Math. 6 (1980) 19–26; Hairer, Nørsett & Wanner, *Solving ODEs I*, 2nd ed.,
//! §II.4 (step control), §II.6 (dense output, DOPRI5 continuous extension).

use super::IntegrateError;

/// Tolerances and limits of the integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    /// Largest step [s].
    pub h_max: f64,
    /// Smallest step before giving up [s].
    pub h_min: f64,
    /// First step; `None` picks one automatically.
    pub h_init: Option<f64>,
    /// Bound on accepted + rejected steps in one call of `integrate`.
    pub max_steps: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options { rtol: 1e-8, atol: 1e-10, h_max: f64::INFINITY, h_min: 1e-14, h_init: None, max_steps: 200_000 }
    }
}

/// One accepted step with its continuous extension.
#[derive(Debug, Clone)]
pub struct DenseStep<const N: usize> {
    pub t0: f64,
    pub t1: f64,
    pub y0: [f64; N],
    pub y1: [f64; N],
    _private: (),
}

impl<const N: usize> DenseStep<N> {
    /// The interpolated state at `t` ∈ [t0, t1].
    pub fn eval(&self, t: f64) -> [f64; N] {
        let _ = t;
        todo!("helper: integrator")
    }
}

/// The stepper: holds the options and the step-size controller state.
#[derive(Debug, Clone)]
pub struct Dopri5<const N: usize> {
    pub options: Options,
}

impl<const N: usize> Dopri5<N> {
    pub fn new(options: Options) -> Self {
        Dopri5 { options }
    }

    /// Take one accepted step from (t, y) towards `t_end` with the right-hand side `f`.
    pub fn step<F: Fn(f64, &[f64; N]) -> [f64; N]>(
        &mut self,
        f: F,
        t: f64,
        y: &[f64; N],
        t_end: f64,
    ) -> Result<DenseStep<N>, IntegrateError> {
        let _ = (f, t, y, t_end);
        todo!("helper: integrator")
    }
}
