//! Optimisation: problems with bounded variables, objectives and inequality constraints
//! g(x) ≤ 0, and the solvers that search them.
//!
//! The solvers are problem-agnostic; divertsim plugs in the diverter problem (maximise the
//! sorting capacity over belt speed v, cycle time t_c and start position R_s subject to
//! "every limiting parcel diverted" and an impulse limit). The founding paper (§4.3) used a
//! genetic algorithm ([`ga`]) and steepest descent with an exterior penalty ([`gradient`]);
//! [`de`], [`cmaes`] (each with an optional [`cobyla`] polish) and the multi-objective
//! [`nsga2`] are added, [`pattern`] (compass search) refines on landscapes with jumps, and
//! [`least_squares`] fits residuals robustly (Levenberg–Marquardt on a Huber loss). All share [`problem`]: Deb's feasibility rules, parallel batch
//! evaluation with results independent of the thread count, an evaluation log observer and
//! evaluation budgets.

pub mod cmaes;
pub mod cobyla;
pub mod de;
pub mod ga;
pub mod gradient;
pub mod least_squares;
pub mod nsga2;
mod operators;
pub mod pattern;
pub mod problem;
#[cfg(test)]
mod test_problems;

pub use problem::{
    deb_cmp, Bounds, Evaluation, IterationSummary, NoObserver, Observer, OptimizeError, Problem,
    Record, RecordLog, SolverResult,
};
