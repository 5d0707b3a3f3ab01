//! Event location on the dense output and the integrate-until-event loop.

use super::{DenseStep, Options, IntegrateError};

/// Which sign change of a guard counts as an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// From negative to positive.
    Rising,
    /// From positive to negative.
    Falling,
    /// Either way.
    Either,
}

/// A system with a right-hand side and guard functions.
pub trait HybridSystem<const N: usize> {
    /// dy/dt at (t, y).
    fn rhs(&self, t: f64, y: &[f64; N]) -> [f64; N];
    /// Number of guard functions.
    fn guard_count(&self) -> usize {
        0
    }
    /// Value of guard `i` at (t, y).
    fn guard(&self, i: usize, t: f64, y: &[f64; N]) -> f64 {
        let _ = (i, t, y);
        0.0
    }
    /// Crossing direction that counts for guard `i`.
    fn guard_direction(&self, i: usize) -> Direction {
        let _ = i;
        Direction::Either
    }
    /// Called before every step with the step's initial point; a system may update internal
    /// references here (it stays fixed during the step).
    fn begin_step(&mut self, t: f64, y: &[f64; N]) {
        let _ = (t, y);
    }
}

/// A located event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventHit {
    /// Which guard.
    pub index: usize,
    /// Left root: the latest time found where the guard has not flipped yet [s].
    pub t: f64,
}

/// Why `integrate` stopped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StopReason {
    /// Reached `t_end`.
    End,
    /// A guard event.
    Event(EventHit),
}

/// Where `integrate` stopped.
#[derive(Debug, Clone, PartialEq)]
pub struct Stop<const N: usize> {
    pub t: f64,
    pub y: [f64; N],
    pub reason: StopReason,
    /// Accepted steps taken.
    pub steps: usize,
}

/// Integrate from (t0, y0) until `t_end` or the first event, whichever comes first. The
/// observer sees every accepted step, the last one truncated at the event.
pub fn integrate<const N: usize, S: HybridSystem<N>, O: FnMut(&DenseStep<N>)>(
    system: &mut S,
    t0: f64,
    y0: [f64; N],
    t_end: f64,
    options: &Options,
    observer: O,
) -> Result<Stop<N>, IntegrateError> {
    let _ = (system, t0, y0, t_end, options, observer);
    todo!("helper: integrator")
}
