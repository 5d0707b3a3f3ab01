//! Problem definition shared by all solvers: box bounds, evaluations with objectives to
//! minimise and inequality constraints g_i(x) ≤ 0, the evaluation log (records and
//! observers), solver results, and the bookkeeping every solver uses.
//!
//! Constraint handling default is Deb's feasibility rules (K. Deb, "An efficient constraint
//! handling method for genetic algorithms", Comput. Methods Appl. Mech. Engrg. 186 (2000)
//! 311–338): a feasible point beats an infeasible one, of two infeasible points the smaller
//! total violation wins, of two feasible points the smaller objective wins.
//!
//! Determinism: solvers evaluate a batch in parallel with rayon (`par_iter().map().collect()`
//! keeps order) and only afterwards report the batch to the observer and update the best point
//! in index order, so every result is bitwise identical for any number of threads.

use std::cmp::Ordering;

use rayon::prelude::*;
use thiserror::Error;

/// Errors of the solvers: bad settings or a bad problem definition (never a panic).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum OptimizeError {
    /// Lower and upper bound vectors of different lengths, or no variables at all.
    #[error("bounds: lower has {lower} entries, upper has {upper} (need equal lengths ≥ 1)")]
    BoundsLength {
        /// Length of `lower`.
        lower: usize,
        /// Length of `upper`.
        upper: usize,
    },
    /// A bound is NaN or infinite (the solvers sample inside the box, so it must be finite).
    #[error("bounds: variable {index} has a non-finite bound [{lower}, {upper}]")]
    NonFiniteBound {
        /// Variable index.
        index: usize,
        /// Its lower bound.
        lower: f64,
        /// Its upper bound.
        upper: f64,
    },
    /// lower > upper.
    #[error("bounds: variable {index} has lower {lower} > upper {upper}")]
    InvertedBound {
        /// Variable index.
        index: usize,
        /// Its lower bound.
        lower: f64,
        /// Its upper bound.
        upper: f64,
    },
    /// A setting is out of its allowed range.
    #[error("invalid setting `{name}`: {reason}")]
    InvalidSetting {
        /// Setting name as in the settings struct.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// The problem's evaluation returned a different number of objectives or constraints than
    /// it declares.
    #[error("evaluation returned {objectives} objectives and {constraints} constraints, expected {expected_objectives} and {expected_constraints}")]
    EvaluationShape {
        /// Returned objective count.
        objectives: usize,
        /// Returned constraint count.
        constraints: usize,
        /// Declared objective count.
        expected_objectives: usize,
        /// Declared constraint count.
        expected_constraints: usize,
    },
}

/// Shorthand for an invalid-setting error.
pub(crate) fn invalid(name: &'static str, reason: impl Into<String>) -> OptimizeError {
    OptimizeError::InvalidSetting {
        name,
        reason: reason.into(),
    }
}

/// Box bounds of the decision variables. A variable with `lower == upper` is fixed: every
/// solver keeps it at that value.
#[derive(Debug, Clone, PartialEq)]
pub struct Bounds {
    /// Lower bounds, one per variable [variable units].
    pub lower: Vec<f64>,
    /// Upper bounds, one per variable [variable units].
    pub upper: Vec<f64>,
}

impl Bounds {
    /// Bounds from lower and upper vectors, validated.
    pub fn new(lower: Vec<f64>, upper: Vec<f64>) -> Result<Self, OptimizeError> {
        let b = Self { lower, upper };
        b.validate()?;
        Ok(b)
    }

    /// The variables of `x` on a bound, within `rel` of their range: (index, true for the
    /// upper bound). A fixed variable (lower = upper) is on neither. An optimum there may
    /// lie past the box.
    pub fn on_bounds(&self, x: &[f64], rel: f64) -> Vec<(usize, bool)> {
        let mut out = Vec::new();
        for (i, ((&lo, &hi), &v)) in self.lower.iter().zip(&self.upper).zip(x).enumerate() {
            let span = hi - lo;
            if span <= 0.0 {
                continue;
            }
            if hi - v <= rel * span {
                out.push((i, true));
            } else if v - lo <= rel * span {
                out.push((i, false));
            }
        }
        out
    }

    /// Checks equal non-zero lengths, finite values and lower ≤ upper.
    pub fn validate(&self) -> Result<(), OptimizeError> {
        if self.lower.len() != self.upper.len() || self.lower.is_empty() {
            return Err(OptimizeError::BoundsLength {
                lower: self.lower.len(),
                upper: self.upper.len(),
            });
        }
        for (index, (&lower, &upper)) in self.lower.iter().zip(&self.upper).enumerate() {
            if !lower.is_finite() || !upper.is_finite() {
                return Err(OptimizeError::NonFiniteBound {
                    index,
                    lower,
                    upper,
                });
            }
            if lower > upper {
                return Err(OptimizeError::InvertedBound {
                    index,
                    lower,
                    upper,
                });
            }
        }
        Ok(())
    }

    /// Number of variables.
    pub fn dim(&self) -> usize {
        self.lower.len()
    }

    /// Whether variable `i` is fixed (lower == upper).
    pub fn is_fixed(&self, i: usize) -> bool {
        self.lower[i] == self.upper[i]
    }

    /// Indices of the free (not fixed) variables.
    pub fn free_indices(&self) -> Vec<usize> {
        (0..self.dim()).filter(|&i| !self.is_fixed(i)).collect()
    }

    /// Clamps `x` into the box in place (fixed variables become exactly their value).
    pub fn clamp(&self, x: &mut [f64]) {
        for ((xi, &lo), &hi) in x.iter_mut().zip(&self.lower).zip(&self.upper) {
            *xi = xi.clamp(lo, hi);
        }
    }

    /// Centre of the box.
    pub fn centre(&self) -> Vec<f64> {
        self.lower
            .iter()
            .zip(&self.upper)
            .map(|(&l, &u)| if l == u { l } else { 0.5 * (l + u) })
            .collect()
    }
}

/// One evaluation: objectives to MINIMISE and constraints g_i(x) ≤ 0 feasible, given as
/// continuous margins (the larger g_i, the worse) so that solvers can steer towards
/// feasibility.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Evaluation {
    /// Objective values f_k(x), minimised.
    pub objectives: Vec<f64>,
    /// Constraint values g_i(x); feasible when all ≤ 0.
    pub constraints: Vec<f64>,
}

impl Evaluation {
    /// Whether every constraint holds (violation exactly zero, no NaN/inf anywhere).
    pub fn feasible(&self) -> bool {
        self.violation() == 0.0
    }

    /// Total violation Σ max(0, g_i). A NaN or infinite value anywhere (objectives included)
    /// gives `f64::INFINITY`: such a point is never feasible and loses to every finite one.
    pub fn violation(&self) -> f64 {
        if self
            .objectives
            .iter()
            .chain(&self.constraints)
            .any(|v| !v.is_finite())
        {
            return f64::INFINITY;
        }
        self.constraints.iter().map(|&g| g.max(0.0)).sum()
    }

    /// First objective f_0(x), the one single-objective solvers minimise (`+∞` if absent).
    pub fn objective(&self) -> f64 {
        self.objectives.first().copied().unwrap_or(f64::INFINITY)
    }
}

/// Deb's feasibility rules on the first objective: `Less` means `a` is better than `b`.
/// A total order (NaN objectives only occur with infinite violation, then ties are `Equal`).
pub fn deb_cmp(a: &Evaluation, b: &Evaluation) -> Ordering {
    let (va, vb) = (a.violation(), b.violation());
    match (va == 0.0, vb == 0.0) {
        (true, true) => a.objective().total_cmp(&b.objective()),
        (true, false) => Ordering::Less,
        (false, true) => Ordering::Greater,
        (false, false) => va.total_cmp(&vb),
    }
}

/// A minimisation problem with box bounds and inequality constraints.
pub trait Problem: Sync {
    /// Box bounds of the decision variables.
    fn bounds(&self) -> &Bounds;
    /// Number of objectives (1 for single-objective solvers).
    fn objective_count(&self) -> usize {
        1
    }
    /// Number of constraints g_i.
    fn constraint_count(&self) -> usize;
    /// Evaluates x (always inside the bounds when called by a solver).
    fn evaluate(&self, x: &[f64]) -> Evaluation;
    /// A first-objective value that is good enough: once a feasible point below it is
    /// found, the solver stops (at the end of its batch, so the result does not depend on
    /// the thread count). `None` (the default): search the whole budget. A search for *any*
    /// violation of a limit, rather than the worst, sets it (issue 28).
    fn target(&self) -> Option<f64> {
        None
    }
}

/// Every evaluation a solver made, in order: the log the CLI writes.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Evaluation index, 0-based, consecutive.
    pub index: usize,
    /// Generation / iteration the evaluation belongs to (0 = initial population or start).
    pub iteration: usize,
    /// Decision variables.
    pub x: Vec<f64>,
    /// Result of the evaluation.
    pub evaluation: Evaluation,
}

/// Observer called after every evaluation, in index order, on the calling thread.
pub trait Observer {
    /// Called once per evaluation.
    fn record(&mut self, r: &Record);
}

impl<F: FnMut(&Record)> Observer for F {
    fn record(&mut self, r: &Record) {
        self(r)
    }
}

/// Observer that ignores everything.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoObserver;

impl Observer for NoObserver {
    fn record(&mut self, _r: &Record) {}
}

/// Observer that keeps every record (the full evaluation log).
#[derive(Debug, Clone, Default)]
pub struct RecordLog(pub Vec<Record>);

impl Observer for RecordLog {
    fn record(&mut self, r: &Record) {
        self.0.push(r.clone());
    }
}

/// Progress summary of one generation / iteration, for plots of objective and variables
/// against generation.
#[derive(Debug, Clone, PartialEq)]
pub struct IterationSummary {
    /// Generation / iteration number (0 = initial population or starting point).
    pub iteration: usize,
    /// Evaluations made so far (cumulative).
    pub evaluations: usize,
    /// Best point so far (Deb's rules).
    pub best_x: Vec<f64>,
    /// Its first objective.
    pub best_objective: f64,
    /// Its total violation (0 when feasible).
    pub best_violation: f64,
    /// Mean total violation of this iteration's evaluations (infinite ones included).
    pub mean_violation: f64,
    /// Feasible evaluations in this iteration.
    pub feasible_in_iteration: usize,
    /// Evaluations in this iteration.
    pub evaluations_in_iteration: usize,
}

/// Result of a single-objective solver run.
#[derive(Debug, Clone, PartialEq)]
pub struct SolverResult {
    /// Best point found (Deb's rules over every evaluation).
    pub best_x: Vec<f64>,
    /// Its evaluation.
    pub best: Evaluation,
    /// Total evaluations made.
    pub evaluations: usize,
    /// Index of the first feasible evaluation, if any.
    pub first_feasible: Option<usize>,
    /// Number of feasible evaluations.
    pub feasible_count: usize,
    /// One summary per generation / iteration.
    pub history: Vec<IterationSummary>,
}

impl SolverResult {
    /// Whether the best point is feasible.
    pub fn feasible(&self) -> bool {
        self.best.feasible()
    }
}

/// Bookkeeping shared by the solvers: evaluates batches in parallel, reports records to the
/// observer in index order, tracks the best point, counts and the per-iteration history, and
/// enforces the evaluation budget.
pub(crate) struct Tracker<'a, P: Problem + ?Sized> {
    pub problem: &'a P,
    observer: &'a mut dyn Observer,
    budget: usize,
    evaluations: usize,
    best: Option<(Vec<f64>, Evaluation)>,
    first_feasible: Option<usize>,
    feasible_count: usize,
    history: Vec<IterationSummary>,
    // Running statistics of the current iteration.
    iter_count: usize,
    iter_violation: f64,
    iter_feasible: usize,
    shape_error: Option<OptimizeError>,
    /// A feasible point below [`Problem::target`] was found: no budget is left.
    reached: bool,
}

impl<'a, P: Problem + ?Sized> Tracker<'a, P> {
    pub fn new(problem: &'a P, observer: &'a mut dyn Observer, budget: usize) -> Self {
        Self {
            problem,
            observer,
            budget,
            evaluations: 0,
            best: None,
            first_feasible: None,
            feasible_count: 0,
            history: Vec::new(),
            iter_count: 0,
            iter_violation: 0.0,
            iter_feasible: 0,
            shape_error: None,
            reached: false,
        }
    }

    /// Evaluations still allowed.
    pub fn remaining(&self) -> usize {
        if self.reached {
            return 0;
        }
        self.budget.saturating_sub(self.evaluations)
    }

    /// Set when the problem returned a wrongly shaped evaluation; solvers stop then.
    pub fn failed(&self) -> bool {
        self.shape_error.is_some()
    }

    /// Best point so far.
    pub fn best(&self) -> Option<&(Vec<f64>, Evaluation)> {
        self.best.as_ref()
    }

    /// Evaluates at most `remaining()` points of `xs` (in parallel), records them in order and
    /// returns their evaluations (possibly fewer than `xs.len()` when the budget runs out).
    pub fn evaluate_batch(&mut self, iteration: usize, xs: &[Vec<f64>]) -> Vec<Evaluation> {
        let n = xs.len().min(self.remaining());
        if n == 0 || self.failed() {
            return Vec::new();
        }
        let problem = self.problem;
        let evals: Vec<Evaluation> = xs[..n]
            .par_iter()
            .panic_fuse() // a caller's stop unwinding from one evaluation skips the rest
            .map(|x| problem.evaluate(x))
            .collect();
        for (x, e) in xs.iter().zip(&evals) {
            self.note(iteration, x, e);
        }
        evals
    }

    /// Evaluates one point serially (for sequential methods such as COBYLA).
    pub fn evaluate_one(&mut self, iteration: usize, x: &[f64]) -> Option<Evaluation> {
        if self.remaining() == 0 || self.failed() {
            return None;
        }
        let e = self.problem.evaluate(x);
        self.note(iteration, x, &e);
        Some(e)
    }

    fn note(&mut self, iteration: usize, x: &[f64], e: &Evaluation) {
        let index = self.evaluations;
        self.evaluations += 1;
        if self.shape_error.is_none()
            && (e.objectives.len() != self.problem.objective_count()
                || e.constraints.len() != self.problem.constraint_count())
        {
            self.shape_error = Some(OptimizeError::EvaluationShape {
                objectives: e.objectives.len(),
                constraints: e.constraints.len(),
                expected_objectives: self.problem.objective_count(),
                expected_constraints: self.problem.constraint_count(),
            });
        }
        let v = e.violation();
        self.iter_count += 1;
        self.iter_violation += v;
        if v == 0.0 {
            if self.problem.target().is_some_and(|t| e.objective() < t) {
                self.reached = true;
            }
            self.feasible_count += 1;
            self.iter_feasible += 1;
            self.first_feasible.get_or_insert(index);
        }
        let better = match &self.best {
            None => true,
            Some((_, b)) => deb_cmp(e, b) == Ordering::Less,
        };
        if better {
            self.best = Some((x.to_vec(), e.clone()));
        }
        let record = Record {
            index,
            iteration,
            x: x.to_vec(),
            evaluation: e.clone(),
        };
        self.observer.record(&record);
    }

    /// Closes an iteration: pushes its summary to the history.
    pub fn end_iteration(&mut self, iteration: usize) {
        if let Some((bx, be)) = &self.best {
            self.history.push(IterationSummary {
                iteration,
                evaluations: self.evaluations,
                best_x: bx.clone(),
                best_objective: be.objective(),
                best_violation: be.violation(),
                mean_violation: if self.iter_count > 0 {
                    self.iter_violation / self.iter_count as f64
                } else {
                    f64::NAN
                },
                feasible_in_iteration: self.iter_feasible,
                evaluations_in_iteration: self.iter_count,
            });
        }
        self.iter_count = 0;
        self.iter_violation = 0.0;
        self.iter_feasible = 0;
    }

    /// The final result (error if the problem misbehaved or nothing was evaluated).
    pub fn finish(self) -> Result<SolverResult, OptimizeError> {
        if let Some(e) = self.shape_error {
            return Err(e);
        }
        let (best_x, best) = self
            .best
            .ok_or_else(|| invalid("max_evaluations", "no evaluation was possible"))?;
        Ok(SolverResult {
            best_x,
            best,
            evaluations: self.evaluations,
            first_feasible: self.first_feasible,
            feasible_count: self.feasible_count,
            history: self.history,
        })
    }
}

/// Map between the free variables scaled to the unit cube u ∈ \[0,1]^m and the full
/// decision vector x (fixed variables keep their value). Gradient, CMA-ES and COBYLA work in
/// u so that step sizes are relative to the bound ranges.
#[derive(Debug, Clone)]
pub(crate) struct UnitSpace {
    lower: Vec<f64>,
    upper: Vec<f64>,
    free: Vec<usize>,
}

impl UnitSpace {
    pub fn new(bounds: &Bounds) -> Self {
        Self {
            lower: bounds.lower.clone(),
            upper: bounds.upper.clone(),
            free: bounds.free_indices(),
        }
    }

    /// Number of free variables m.
    pub fn dim(&self) -> usize {
        self.free.len()
    }

    /// x from u (u clamped to \[0,1]).
    pub fn to_x(&self, u: &[f64]) -> Vec<f64> {
        let mut x = self.lower.clone();
        for (&i, &ui) in self.free.iter().zip(u) {
            let t = ui.clamp(0.0, 1.0);
            // Interpolate from both ends so that u = 1 gives the upper bound exactly.
            x[i] = (1.0 - t) * self.lower[i] + t * self.upper[i];
            x[i] = x[i].clamp(self.lower[i], self.upper[i]);
        }
        x
    }

    /// u from x (fixed variables dropped).
    pub fn to_u(&self, x: &[f64]) -> Vec<f64> {
        self.free
            .iter()
            .map(|&i| ((x[i] - self.lower[i]) / (self.upper[i] - self.lower[i])).clamp(0.0, 1.0))
            .collect()
    }
}

/// Checks a starting point: right length, finite, inside the bounds (fixed variables are
/// overwritten with their value). Returns the point to use.
pub(crate) fn check_start(
    bounds: &Bounds,
    start: Option<&[f64]>,
    name: &'static str,
) -> Result<Vec<f64>, OptimizeError> {
    let Some(s) = start else {
        return Ok(bounds.centre());
    };
    if s.len() != bounds.dim() {
        return Err(invalid(
            name,
            format!("has {} entries, the problem {}", s.len(), bounds.dim()),
        ));
    }
    let mut x = s.to_vec();
    for (i, xi) in x.iter_mut().enumerate() {
        if bounds.is_fixed(i) {
            *xi = bounds.lower[i];
        } else if !xi.is_finite() || *xi < bounds.lower[i] || *xi > bounds.upper[i] {
            return Err(invalid(
                name,
                format!(
                    "entry {i} = {xi} is outside [{}, {}]",
                    bounds.lower[i], bounds.upper[i]
                ),
            ));
        }
    }
    Ok(x)
}

/// Checks that a probability lies in [0, 1].
pub(crate) fn check_probability(name: &'static str, p: f64) -> Result<(), OptimizeError> {
    if (0.0..=1.0).contains(&p) {
        Ok(())
    } else {
        Err(invalid(name, format!("{p} is not in [0, 1]")))
    }
}

/// Checks that a value is finite and > 0.
pub(crate) fn check_positive(name: &'static str, v: f64) -> Result<(), OptimizeError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(invalid(name, format!("{v} must be finite and > 0")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ev(obj: f64, g: &[f64]) -> Evaluation {
        Evaluation {
            objectives: vec![obj],
            constraints: g.to_vec(),
        }
    }

    #[test]
    fn violation_and_feasibility() {
        assert_eq!(ev(1.0, &[-1.0, 0.0]).violation(), 0.0);
        assert!(ev(1.0, &[-1.0, 0.0]).feasible());
        assert_eq!(ev(1.0, &[0.5, -2.0, 0.25]).violation(), 0.75);
        assert!(!ev(1.0, &[0.5]).feasible());
        assert_eq!(ev(1.0, &[f64::NAN]).violation(), f64::INFINITY);
        assert_eq!(ev(f64::NAN, &[-1.0]).violation(), f64::INFINITY);
        assert_eq!(ev(1.0, &[f64::NEG_INFINITY]).violation(), f64::INFINITY);
        assert!(!ev(f64::INFINITY, &[]).feasible());
    }

    #[test]
    fn deb_rules() {
        let feas_good = ev(1.0, &[-1.0]);
        let feas_bad = ev(2.0, &[-1.0]);
        let infeas_small = ev(-100.0, &[0.1]);
        let infeas_big = ev(-200.0, &[0.2]);
        let nan = ev(f64::NAN, &[0.0]);
        assert_eq!(deb_cmp(&feas_good, &feas_bad), Ordering::Less);
        assert_eq!(deb_cmp(&feas_bad, &infeas_small), Ordering::Less);
        assert_eq!(deb_cmp(&infeas_small, &infeas_big), Ordering::Less);
        assert_eq!(deb_cmp(&infeas_big, &nan), Ordering::Less);
        assert_eq!(deb_cmp(&nan, &feas_good), Ordering::Greater);
    }

    /// Issue 50, item 2: an optimum on (or within 1e-3 of) a bound is found, with its end;
    /// a fixed variable is on none.
    #[test]
    fn a_point_on_its_bounds_is_found() {
        let b = Bounds::new(vec![1.0, 1.0, 0.0, 0.5], vec![2.3, 1.5, 0.9, 0.5]).unwrap();
        assert_eq!(
            b.on_bounds(&[1.0432, 1.4998, 0.6, 0.5], 1e-3),
            vec![(1, true)]
        );
        assert_eq!(b.on_bounds(&[1.0, 1.2, 0.4, 0.5], 1e-3), vec![(0, false)]);
        assert_eq!(
            b.on_bounds(&[1.5, 1.2, 0.0009, 0.5], 1e-3),
            vec![(2, false)],
            "0.0009 of 0.9 is 1e-3 of the range: on the bound"
        );
        assert!(b.on_bounds(&[1.5, 1.2, 0.4, 0.5], 1e-3).is_empty());
    }

    #[test]
    fn bounds_validation() {
        assert!(Bounds::new(vec![0.0], vec![1.0]).is_ok());
        assert!(Bounds::new(vec![1.0], vec![1.0]).is_ok());
        assert!(matches!(
            Bounds::new(vec![2.0], vec![1.0]),
            Err(OptimizeError::InvertedBound { index: 0, .. })
        ));
        assert!(matches!(
            Bounds::new(vec![0.0, f64::NAN], vec![1.0, 1.0]),
            Err(OptimizeError::NonFiniteBound { index: 1, .. })
        ));
        assert!(matches!(
            Bounds::new(vec![0.0], vec![]),
            Err(OptimizeError::BoundsLength { .. })
        ));
        assert!(Bounds::new(vec![], vec![]).is_err());
    }

    #[test]
    fn unit_space_round_trip_and_fixed() {
        let b = Bounds::new(vec![1.0, 5.0, -2.0], vec![3.0, 5.0, 2.0]).unwrap();
        let s = UnitSpace::new(&b);
        assert_eq!(s.dim(), 2);
        let x = s.to_x(&[0.25, 1.0]);
        assert_eq!(x, vec![1.5, 5.0, 2.0]);
        assert_eq!(s.to_u(&x), vec![0.25, 1.0]);
        // Out-of-cube u is clamped to the box.
        assert_eq!(s.to_x(&[-1.0, 2.0]), vec![1.0, 5.0, 2.0]);
    }
}
