//! One interface for the one-step methods: the event loop ([`super::integrate_with`])
//! drives the explicit [`super::Dopri5`] and the linearly implicit [`super::Rosenbrock`]
//! through it, and hands the step-size proposal from one to the other where the system's
//! stiffness changes.

use super::{DenseStep, IntegrateError, Options, Stats};

/// An adaptive one-step method with dense output on `[f64; N]` states.
pub trait Stepper<const N: usize> {
    /// Take one accepted step from (t, y) towards `t_end` with the right-hand side `f`,
    /// never past `t_end` (landing on it bitwise when within 1 % of a step).
    fn step<F: Fn(f64, &[f64; N]) -> [f64; N]>(
        &mut self,
        f: F,
        t: f64,
        y: &[f64; N],
        t_end: f64,
    ) -> Result<DenseStep<N>, IntegrateError>;

    /// The step proposed for the next call \[s], if any.
    fn proposed_step(&self) -> Option<f64>;

    /// Set the next step \[s] (ignored unless positive and finite).
    fn set_proposed_step(&mut self, h: f64);

    /// Drop the cached start derivative: the right-hand side changed between steps.
    fn forget_derivative(&mut self);

    /// Work counters since construction.
    fn stats(&self) -> Stats;

    /// The options, which the event loop tightens (`h_max`) near a singularity.
    fn options_mut(&mut self) -> &mut Options;
}

/// The trait's methods are the steppers' own (inherent) methods of the same names.
macro_rules! stepper_of_inherent {
    ($stepper:ident) => {
        impl<const N: usize> Stepper<N> for super::$stepper<N> {
            fn step<F: Fn(f64, &[f64; N]) -> [f64; N]>(
                &mut self,
                f: F,
                t: f64,
                y: &[f64; N],
                t_end: f64,
            ) -> Result<DenseStep<N>, IntegrateError> {
                super::$stepper::step(self, f, t, y, t_end)
            }
            fn proposed_step(&self) -> Option<f64> {
                super::$stepper::proposed_step(self)
            }
            fn set_proposed_step(&mut self, h: f64) {
                super::$stepper::set_proposed_step(self, h)
            }
            fn forget_derivative(&mut self) {
                super::$stepper::forget_derivative(self)
            }
            fn stats(&self) -> Stats {
                super::$stepper::stats(self)
            }
            fn options_mut(&mut self) -> &mut Options {
                &mut self.options
            }
        }
    };
}

stepper_of_inherent!(Dopri5);
stepper_of_inherent!(Rosenbrock);

/// Hand the step-size proposal from the stepper that stops to the one that takes over.
pub fn hand_over<const N: usize>(from: &impl Stepper<N>, to: &mut impl Stepper<N>) {
    if let Some(h) = from.proposed_step() {
        to.set_proposed_step(h);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::{Dopri5, Rosenbrock};

    /// y' = −y from y(0) = 1 to t = 1 through the trait, the proposal handed over halfway:
    /// either stepper, and both in turn, end within 100 × rtol of e^{−1} (the 2(3) stepper's
    /// global error is about 10 × rtol here, DOPRI5's far less).
    fn decay<A: Stepper<1>, B: Stepper<1>>(a: &mut A, b: &mut B) -> f64 {
        let f = |_t: f64, y: &[f64; 1]| [-y[0]];
        let (mut t, mut y) = (0.0, [1.0]);
        while t < 0.5 {
            let s = a.step(f, t, &y, 0.5).unwrap();
            (t, y) = (s.t1, s.y1);
        }
        hand_over(a, b);
        while t < 1.0 {
            let s = b.step(f, t, &y, 1.0).unwrap();
            (t, y) = (s.t1, s.y1);
        }
        assert_eq!(t, 1.0);
        y[0]
    }

    #[test]
    fn both_steppers_integrate_a_decay_through_one_interface() {
        let o = Options {
            rtol: 1e-6,
            atol: 1e-9,
            ..Options::default()
        };
        let exact = (-1.0f64).exp();
        let cases = [
            decay(&mut Dopri5::new(o), &mut Dopri5::new(o)),
            decay(&mut Rosenbrock::new(o), &mut Rosenbrock::new(o)),
            decay(&mut Dopri5::new(o), &mut Rosenbrock::new(o)),
            decay(&mut Rosenbrock::new(o), &mut Dopri5::new(o)),
        ];
        for (k, y) in cases.iter().enumerate() {
            assert!((y - exact).abs() < 1e-4, "case {k}: {y} vs {exact}");
        }
    }
}
