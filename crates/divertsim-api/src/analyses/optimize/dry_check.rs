//! Checking a method's settings before any simulation: the solver started on a free
//! stand-in problem of the same shape, stopped at its first evaluation.

use super::*;

/// A stand-in problem of the same shape that costs nothing (see [`dry_check`]).
struct Free<'a> {
    bounds: &'a Bounds,
    objectives: usize,
    constraints: usize,
}

impl Problem for Free<'_> {
    fn bounds(&self) -> &Bounds {
        self.bounds
    }
    fn objective_count(&self) -> usize {
        self.objectives
    }
    fn constraint_count(&self) -> usize {
        self.constraints
    }
    /// A wrongly shaped evaluation: the solver has passed its own checks by the time it
    /// evaluates, and the shape error stops it at its first batch, so the dry run costs
    /// one population whatever the generations (a full dry run of 10⁴ × 10⁴ allocated
    /// gigabytes before the work limit was checked).
    fn evaluate(&self, _: &[f64]) -> Evaluation {
        Evaluation {
            objectives: Vec::new(),
            constraints: Vec::new(),
        }
    }
}

/// Validate a method's settings before any simulation: start the solver on a free stand-in
/// problem of the same shape as `problem`, so that its own checks (population, budget,
/// start, ...) report at once, and stop it at its first evaluation. An `InvalidSetting`
/// error names the solver setting (`population`, `max_evaluations`, `start`, ...).
pub fn dry_check(problem: &impl Problem, settings: &MethodSettings) -> Result<(), OptimizeError> {
    let free = Free {
        bounds: problem.bounds(),
        objectives: problem.objective_count(),
        constraints: problem.constraint_count(),
    };
    let mut none = NoObserver;
    let started = match settings {
        MethodSettings::Ga(s) => ga::solve(&free, s, &mut none).map(|_| ()),
        MethodSettings::Gradient(s) => gradient::solve(&free, s, &mut none).map(|_| ()),
        MethodSettings::De(s) => de::solve(&free, s, &mut none).map(|_| ()),
        MethodSettings::Cmaes(s) => cmaes::solve(&free, s, &mut none).map(|_| ()),
        MethodSettings::Nsga2(s) => nsga2::solve(&free, s, &mut none).map(|_| ()),
    };
    match started {
        // The stand-in's shape error: the settings passed every check.
        Err(OptimizeError::EvaluationShape { .. }) => Ok(()),
        other => other,
    }
}
