//! Numerical integration of ordinary differential equations with events. Knows nothing of
//! parcels or arms.
//!
//! [`dopri5`]: adaptive Dormand–Prince 5(4) (Dormand & Prince 1980; Hairer, Nørsett & Wanner,
//! *Solving ODEs I*, §II.4–II.6) on fixed-size `[f64; N]` states, with 4th-order dense output.
//! [`rosenbrock`]: a linearly implicit 2(3) stepper (Shampine & Reichelt 1997) for stiff
//! stretches, with the same dense output type; the event loop switches to it where the system
//! reports a stiffness that would hold an explicit step below its accuracy.
//! [`stepper`]: the one interface both steppers give the event loop.
//! [`events`]: location of sign changes of several guard functions, each with a crossing
//! direction, on the dense output (Illinois root finding), sampling interior points of every
//! step so that a touch-and-leave inside a step is not missed; the located time is the
//! "left root": the guard has not yet flipped there.

pub mod dopri5;
pub mod events;
pub mod rosenbrock;
pub mod stepper;
#[cfg(test)]
mod test_models;

pub use dopri5::{DenseStep, Dopri5, Options, Stats, StepBounds};
pub use events::{
    integrate, integrate_with, locate_event, Direction, EventHit, HybridSystem, Stop, StopReason,
    EVENT_TIME_TOL, INTERIOR_SAMPLES,
};
pub use rosenbrock::Rosenbrock;
pub use stepper::Stepper;

/// Why integration could not go on.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IntegrateError {
    #[error("step size fell below {h_min:e} s at t = {t} s")]
    StepTooSmall { t: f64, h_min: f64 },
    #[error("more than {max_steps} steps")]
    TooManySteps { max_steps: usize },
    #[error("non-finite state or derivative at t = {t} s")]
    NonFinite { t: f64 },
}
