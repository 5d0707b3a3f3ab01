//! Compass (pattern) search: a derivative-free local refinement that needs no continuity.
//!
//! From x₀, poll x ± Δ_i e_i along every free variable (one parallel batch); move to the best
//! poll point if it beats the incumbent by Deb's rules, otherwise halve Δ. Stops when every
//! Δ_i is below `min_step` of its range or the budget is spent. Unlike COBYLA it builds no
//! model, so it refines on landscapes with jumps (a strike that appears or vanishes), where
//! it converges to a point no poll direction improves at the final step size.
//!
//! Reference: T. G. Kolda, R. M. Lewis, V. Torczon, "Optimization by direct search: new
//! perspectives on some classical and modern methods", SIAM Review 45 (2003) 385–482 (§3,
//! compass search).

use super::problem::{
    check_start, deb_cmp, invalid, Observer, OptimizeError, Problem, SolverResult, Tracker,
    UnitSpace,
};
use std::cmp::Ordering;

/// Settings of a compass search.
#[derive(Debug, Clone, PartialEq)]
pub struct PatternSettings {
    /// Starting point (default `None`: the centre of the bounds); inside the bounds.
    pub start: Option<Vec<f64>>,
    /// Initial step as a fraction of each variable's range (default 0.05; in (0, 1]).
    pub initial_step: f64,
    /// Stop when the step is below this fraction of the ranges (default 1e-4).
    pub min_step: f64,
    /// Evaluation budget, the start included (default 200; ≥ 1).
    pub max_evaluations: usize,
}

impl Default for PatternSettings {
    fn default() -> Self {
        Self {
            start: None,
            initial_step: 0.05,
            min_step: 1e-4,
            max_evaluations: 200,
        }
    }
}

/// Runs the compass search. History: one entry per poll.
pub fn solve<P: Problem + ?Sized>(
    problem: &P,
    settings: &PatternSettings,
    observer: &mut dyn Observer,
) -> Result<SolverResult, OptimizeError> {
    let bounds = problem.bounds();
    bounds.validate()?;
    if !(settings.initial_step > 0.0 && settings.initial_step <= 1.0) {
        return Err(invalid("initial_step", "must be in (0, 1]"));
    }
    if !(settings.min_step > 0.0 && settings.min_step <= settings.initial_step) {
        return Err(invalid("min_step", "must be in (0, initial_step]"));
    }
    if settings.max_evaluations == 0 {
        return Err(invalid("max_evaluations", "must be ≥ 1"));
    }
    let x0 = check_start(bounds, settings.start.as_deref(), "start")?;
    let space = UnitSpace::new(bounds);
    let mut tracker = Tracker::new(problem, observer, settings.max_evaluations);
    let mut u = space.to_u(&x0);
    let Some(mut best) = tracker.evaluate_batch(0, &[x0]).pop() else {
        return tracker.finish();
    };
    tracker.end_iteration(0);
    let mut step = settings.initial_step;
    let mut iteration = 1;
    while step >= settings.min_step && tracker.remaining() > 0 && !tracker.failed() {
        let mut polls: Vec<Vec<f64>> = Vec::with_capacity(2 * space.dim());
        let mut us: Vec<Vec<f64>> = Vec::with_capacity(2 * space.dim());
        for i in 0..space.dim() {
            for sign in [1.0, -1.0] {
                let mut v = u.clone();
                v[i] = (v[i] + sign * step).clamp(0.0, 1.0);
                if v[i] != u[i] {
                    polls.push(space.to_x(&v));
                    us.push(v);
                }
            }
        }
        if polls.is_empty() {
            break;
        }
        let evals = tracker.evaluate_batch(iteration, &polls);
        tracker.end_iteration(iteration);
        iteration += 1;
        // The first best poll point in poll order: deterministic.
        let mut winner: Option<usize> = None;
        for (k, e) in evals.iter().enumerate() {
            let reference = winner.map_or(&best, |w| &evals[w]);
            if deb_cmp(e, reference) == Ordering::Less {
                winner = Some(k);
            }
        }
        match winner {
            Some(k) => {
                best = evals[k].clone();
                u = us[k].clone();
            }
            None => step *= 0.5,
        }
    }
    tracker.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimize::{Bounds, Evaluation, NoObserver};

    struct Steps {
        bounds: Bounds,
    }

    /// A staircase bowl: f = Σ floor(10 |x_i − 0.3|) + |x_i − 0.3| (discontinuous everywhere
    /// on a grid), minimum 0 at 0.3.
    impl Problem for Steps {
        fn bounds(&self) -> &Bounds {
            &self.bounds
        }
        fn constraint_count(&self) -> usize {
            0
        }
        fn evaluate(&self, x: &[f64]) -> Evaluation {
            let f = x
                .iter()
                .map(|v| (10.0 * (v - 0.3).abs()).floor() + (v - 0.3).abs())
                .sum();
            Evaluation {
                objectives: vec![f],
                constraints: vec![],
            }
        }
    }

    #[test]
    fn finds_the_bottom_of_a_staircase() {
        let p = Steps {
            bounds: Bounds::new(vec![-1.0; 3], vec![1.0; 3]).unwrap(),
        };
        let s = PatternSettings {
            start: Some(vec![0.9, -0.8, 0.1]),
            max_evaluations: 2000,
            ..PatternSettings::default()
        };
        let r = solve(&p, &s, &mut NoObserver).unwrap();
        for v in &r.best_x {
            assert!((v - 0.3).abs() < 1e-3, "{:?}", r.best_x);
        }
        assert!(r.evaluations <= 2000);
    }

    #[test]
    fn keeps_fixed_variables_and_the_budget() {
        let p = Steps {
            bounds: Bounds::new(vec![-1.0, 0.5], vec![1.0, 0.5]).unwrap(),
        };
        let s = PatternSettings {
            max_evaluations: 7,
            ..PatternSettings::default()
        };
        let mut log = crate::optimize::RecordLog::default();
        let r = solve(&p, &s, &mut log).unwrap();
        assert_eq!(r.evaluations, 7);
        assert!(log.0.iter().all(|r| r.x[1] == 0.5));
        assert!(solve(
            &p,
            &PatternSettings {
                initial_step: 0.0,
                ..PatternSettings::default()
            },
            &mut NoObserver
        )
        .is_err());
    }
}
