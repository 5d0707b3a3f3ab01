//! COBYLA (Constrained Optimization BY Linear Approximations) — a derivative-free constrained
//! local method, used as the polish after DE and CMA-ES and available on its own.
//!
//! Wraps the `cobyla` crate (a pure-Rust translation of NLopt 2.7.1's COBYLA; M. J. D.
//! Powell, "A direct search optimization method that models the objective and constraint
//! functions by linear interpolation", in *Advances in Optimization and Numerical Analysis*,
//! Kluwer 1994, 51–67). COBYLA works here on the free variables scaled to the unit cube, so
//! `rho_begin` and `xtol` are fractions of the bound ranges. The crate asks for the objective
//! and each constraint separately at the same point; a small cache turns that into one
//! problem evaluation per point. COBYLA is sequential and deterministic: no seed is needed.

use std::cell::RefCell;

use super::problem::{
    check_positive, check_start, invalid, Evaluation, Observer, OptimizeError, Problem,
    SolverResult, Tracker, UnitSpace,
};

/// Settings of a COBYLA polish (the local phase after a global solver).
#[derive(Debug, Clone, PartialEq)]
pub struct PolishSettings {
    /// ρ_beg: initial trust-region radius as a fraction of the bound ranges (default 0.05).
    pub rho_begin: f64,
    /// Stop when a step changes every scaled variable by less than this (default 1e-9).
    pub xtol: f64,
    /// Evaluation budget of the polish (default 300).
    pub max_evaluations: usize,
    /// δ: COBYLA is given the tightened constraints g_i + δ ≤ 0 [constraint units] (default
    /// 1e-8). COBYLA approaches active constraints from either side to within round-off;
    /// without the margin a vertex optimum such as G06's ends 1e-11 infeasible, which Deb's
    /// strict rules reject.
    pub constraint_margin: f64,
}

impl Default for PolishSettings {
    fn default() -> Self {
        Self {
            rho_begin: 0.05,
            xtol: 1e-9,
            max_evaluations: 300,
            constraint_margin: 1e-8,
        }
    }
}

impl PolishSettings {
    pub(crate) fn validate(&self) -> Result<(), OptimizeError> {
        check_positive("polish.rho_begin", self.rho_begin)?;
        if self.rho_begin > 1.0 {
            return Err(invalid(
                "polish.rho_begin",
                "must be ≤ 1 (fraction of range)",
            ));
        }
        check_positive("polish.xtol", self.xtol)?;
        if !(self.constraint_margin.is_finite() && self.constraint_margin >= 0.0) {
            return Err(invalid(
                "polish.constraint_margin",
                "must be finite and ≥ 0",
            ));
        }
        if self.max_evaluations == 0 {
            return Err(invalid("polish.max_evaluations", "must be ≥ 1"));
        }
        Ok(())
    }
}

/// Settings of a stand-alone COBYLA run.
#[derive(Debug, Clone, PartialEq)]
pub struct CobylaSettings {
    /// Starting point x₀ (default `None`: centre of the bounds); must lie inside the bounds.
    pub start: Option<Vec<f64>>,
    /// Trust-region and budget settings (defaults as [`PolishSettings`] except ρ_beg = 0.1
    /// and 1000 evaluations).
    pub local: PolishSettings,
}

impl Default for CobylaSettings {
    fn default() -> Self {
        Self {
            start: None,
            local: PolishSettings {
                rho_begin: 0.1,
                max_evaluations: 1000,
                ..PolishSettings::default()
            },
        }
    }
}

/// Runs COBYLA from `settings.start`. History: one entry per m + 1 evaluations (a simplex's
/// worth; m = number of free variables), iteration 0 being the starting point.
pub fn solve<P: Problem + ?Sized>(
    problem: &P,
    settings: &CobylaSettings,
    observer: &mut dyn Observer,
) -> Result<SolverResult, OptimizeError> {
    let bounds = problem.bounds();
    bounds.validate()?;
    settings.local.validate()?;
    let x0 = check_start(bounds, settings.start.as_deref(), "start")?;
    let mut tracker = Tracker::new(problem, observer, settings.local.max_evaluations);
    polish(&mut tracker, &x0, &settings.local, 0);
    tracker.finish()
}

struct PolishState<'t, 'a, P: Problem + ?Sized> {
    tracker: &'t mut Tracker<'a, P>,
    /// Last points evaluated (u, evaluation): COBYLA asks f and each g_i at the same point.
    cache: Vec<(Vec<f64>, Evaluation)>,
    count: usize,
    iteration: usize,
    group: usize,
}

/// Large finite stand-in for a NaN/inf objective (COBYLA's linear algebra needs finite values).
const BIG: f64 = 1e30;

impl<P: Problem + ?Sized> PolishState<'_, '_, P> {
    /// Evaluation at scaled point u (cached); `None` when the budget is spent.
    fn at(&mut self, space: &UnitSpace, u: &[f64]) -> Option<Evaluation> {
        if let Some((_, e)) = self.cache.iter().find(|(cu, _)| cu.as_slice() == u) {
            return Some(e.clone());
        }
        // New iteration every `group` evaluations, so the history has useful granularity.
        if self.count > 0 && self.count.is_multiple_of(self.group) {
            self.tracker.end_iteration(self.iteration);
            self.iteration += 1;
        }
        let e = self.tracker.evaluate_one(self.iteration, &space.to_x(u))?;
        self.count += 1;
        if self.cache.len() >= 2 {
            self.cache.remove(0);
        }
        self.cache.push((u.to_vec(), e.clone()));
        Some(e)
    }
}

/// Polishes from `x0` with COBYLA, recording evaluations in `tracker` from iteration
/// `iteration` on (and closing the last iteration). Returns the next free iteration number.
pub(crate) fn polish<P: Problem + ?Sized>(
    tracker: &mut Tracker<'_, P>,
    x0: &[f64],
    settings: &PolishSettings,
    iteration: usize,
) -> usize {
    let space = UnitSpace::new(tracker.problem.bounds());
    let m = space.dim();
    let budget = settings.max_evaluations.min(tracker.remaining());
    if budget == 0 || tracker.failed() {
        return iteration;
    }
    if m == 0 {
        // Nothing to move: the point itself is the answer.
        tracker.evaluate_one(iteration, x0);
        tracker.end_iteration(iteration);
        return iteration + 1;
    }
    let n_con = tracker.problem.constraint_count();
    let state = RefCell::new(PolishState {
        tracker,
        cache: Vec::with_capacity(2),
        count: 0,
        iteration,
        group: m + 1,
    });
    let objective = |u: &[f64], _: &mut ()| -> f64 {
        match state.borrow_mut().at(&space, u) {
            Some(e) if e.objective().is_finite() => e.objective(),
            _ => BIG,
        }
    };
    // The crate wants c_i(u) ≥ 0 feasible: c_i = −(g_i + δ).
    let margin = settings.constraint_margin;
    let constraints: Vec<_> = (0..n_con)
        .map(|i| {
            let (state, space) = (&state, &space);
            move |u: &[f64], _: &mut ()| -> f64 {
                match state.borrow_mut().at(space, u) {
                    Some(e) => match e.constraints.get(i) {
                        Some(g) if g.is_finite() => -(g + margin),
                        _ => -BIG,
                    },
                    None => -BIG,
                }
            }
        })
        .collect();
    let u0 = space.to_u(x0);
    let bounds01 = vec![(0.0, 1.0); m];
    let stop = cobyla::StopTols {
        xtol_abs: vec![settings.xtol; m],
        ..cobyla::StopTols::default()
    };
    // The outcome is not needed: the tracker kept the best point under Deb's rules.
    let _ = cobyla::minimize(
        objective,
        &u0,
        &bounds01,
        &constraints,
        (),
        budget,
        cobyla::RhoBeg::All(settings.rho_begin),
        Some(stop),
    );
    drop(constraints);
    let st = state.into_inner();
    let last = st.iteration;
    if st.count > 0 {
        st.tracker.end_iteration(last);
    }
    last + 1
}

#[cfg(test)]
mod tests {
    use super::super::problem::{NoObserver, RecordLog};
    use super::super::test_problems::*;
    use super::*;

    /// From the centre of G06's box (infeasible), COBYLA reaches f* within 1e-6 relative.
    #[test]
    fn g06_from_centre() {
        let p = Counting::new(G06::new());
        let r = solve(&p, &CobylaSettings::default(), &mut NoObserver).unwrap();
        assert!(r.feasible(), "{r:?}");
        assert!(
            (r.best.objective() - G06_F).abs() < 1e-6 * G06_F.abs(),
            "{} after {}",
            r.best.objective(),
            r.evaluations
        );
        assert_eq!(p.calls(), r.evaluations);
    }

    /// Rosenbrock on the unit disk from (−1, 1): the boundary optimum within 1e-4.
    #[test]
    fn rosenbrock_disk() {
        let s = CobylaSettings {
            start: Some(vec![-1.0, 1.0]),
            local: PolishSettings {
                max_evaluations: 3000,
                ..CobylaSettings::default().local
            },
        };
        let r = solve(&RosenDisk::new(), &s, &mut NoObserver).unwrap();
        assert!(r.feasible());
        assert!(
            (r.best.objective() - ROSEN_DISK_F).abs() < 1e-4,
            "{:?}",
            r.best
        );
        assert!(
            (r.best_x[0] - ROSEN_DISK_X[0]).abs() < 1e-3,
            "{:?}",
            r.best_x
        );
    }

    /// Fixed variables stay fixed; budget respected; log in index order; deterministic.
    #[test]
    fn fixed_budget_log_determinism() {
        let s = CobylaSettings {
            start: Some(vec![0.0, 0.25, 0.0]),
            local: PolishSettings {
                max_evaluations: 40,
                ..CobylaSettings::default().local
            },
        };
        let run = || {
            let mut log = RecordLog::default();
            let r = solve(&FixedMiddle::new(), &s, &mut log).unwrap();
            (r, log.0)
        };
        let (r, log) = run();
        assert!(r.evaluations <= 40);
        assert_eq!(log.len(), r.evaluations);
        assert!(log.iter().enumerate().all(|(i, l)| l.index == i));
        assert!(log.iter().all(|l| l.x[1] == 0.25));
        assert_eq!(run(), (r, log));
        // With a larger budget the optimum (1.5, 0.25, 1.5) is reached.
        let s2 = CobylaSettings {
            start: Some(vec![0.0, 0.25, 0.0]),
            ..CobylaSettings::default()
        };
        let r2 = solve(&FixedMiddle::new(), &s2, &mut NoObserver).unwrap();
        assert!((r2.best_x[0] - 1.5).abs() < 1e-4 && (r2.best_x[2] - 1.5).abs() < 1e-4);
    }

    /// Bad settings and starts are errors.
    #[test]
    fn bad_settings() {
        let p = G06::new();
        for s in [
            CobylaSettings {
                start: Some(vec![0.0, 0.0]),
                ..CobylaSettings::default()
            },
            CobylaSettings {
                start: Some(vec![14.0]),
                ..CobylaSettings::default()
            },
            CobylaSettings {
                local: PolishSettings {
                    rho_begin: 0.0,
                    ..PolishSettings::default()
                },
                ..CobylaSettings::default()
            },
            CobylaSettings {
                local: PolishSettings {
                    max_evaluations: 0,
                    ..PolishSettings::default()
                },
                ..CobylaSettings::default()
            },
        ] {
            assert!(matches!(
                solve(&p, &s, &mut NoObserver),
                Err(OptimizeError::InvalidSetting { .. })
            ));
        }
    }
}
