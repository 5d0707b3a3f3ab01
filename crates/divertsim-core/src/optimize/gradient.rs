//! Steepest descent with an exterior penalty — the paper's deterministic method ("the
//! quickest fall with the exterior punishment function", §4.3), which may start outside the
//! feasible set.
//!
//! Penalty function P(x) = f(x) + r Σ max(0, g_i(x) + δ)², with r multiplied by a growth
//! factor after each outer iteration (sequential unconstrained minimisation, Fiacco &
//! McCormick 1968). Inner iterations: central finite-difference gradient in the free variables
//! scaled to u ∈ \[0,1] (one parallel batch of 2m evaluations), projected steepest-descent step
//! with Armijo backtracking (Bertsekas, *Nonlinear Programming*, 2nd ed., §2.3 — the Armijo
//! rule along the projection arc). The first trial step is the Barzilai–Borwein step (IMA J.
//! Numer. Anal. 8 (1988) 141–148), which copes with the ill-conditioning a large r causes;
//! a nonmonotone Armijo backtracking (reference = max of the last 10 penalty values)
//! guarantees convergence.
//!
//! An exterior penalty approaches the constraint boundary from outside (violation ~ 1/r);
//! the small margin δ makes the penalty minimiser strictly feasible once r is large enough.
//! The method is deterministic (no random numbers).

use super::problem::{
    check_positive, check_start, invalid, Evaluation, Observer, OptimizeError, Problem,
    SolverResult, Tracker, UnitSpace,
};

/// Settings of the penalty steepest-descent method.
#[derive(Debug, Clone, PartialEq)]
pub struct GradientSettings {
    /// Starting point x₀ (default `None`: centre of the bounds); must lie inside the bounds
    /// but may be infeasible.
    pub start: Option<Vec<f64>>,
    /// r₀: initial penalty factor (default 1).
    pub penalty_initial: f64,
    /// Growth factor of r per outer iteration (default 10; > 1).
    pub penalty_growth: f64,
    /// Outer (penalty) iterations (default 12).
    pub outer_iterations: usize,
    /// Maximum inner (descent) iterations per outer iteration (default 200).
    pub inner_iterations: usize,
    /// h: finite-difference step as a fraction of each variable's range (default 1e-6).
    pub fd_step: f64,
    /// Armijo sufficient-decrease constant c (default 1e-4; in (0, 1)).
    pub armijo: f64,
    /// Maximum step halvings per line search (default 40).
    pub max_backtracks: usize,
    /// Inner stop: ‖proj(u − ∇P) − u‖∞ below this (scaled variables, default 1e-9).
    pub tolerance: f64,
    /// δ: constraint margin of the penalty [constraint units] (default 1e-6).
    pub constraint_margin: f64,
    /// Evaluation budget (default 20 000).
    pub max_evaluations: usize,
}

impl Default for GradientSettings {
    fn default() -> Self {
        Self {
            start: None,
            penalty_initial: 1.0,
            penalty_growth: 10.0,
            outer_iterations: 12,
            inner_iterations: 200,
            fd_step: 1e-6,
            armijo: 1e-4,
            max_backtracks: 40,
            tolerance: 1e-9,
            constraint_margin: 1e-6,
            max_evaluations: 20_000,
        }
    }
}

impl GradientSettings {
    fn validate(&self) -> Result<(), OptimizeError> {
        check_positive("penalty_initial", self.penalty_initial)?;
        if !(self.penalty_growth.is_finite() && self.penalty_growth > 1.0) {
            return Err(invalid("penalty_growth", "must be finite and > 1"));
        }
        if self.outer_iterations == 0 || self.inner_iterations == 0 {
            return Err(invalid("outer_iterations", "outer and inner must be ≥ 1"));
        }
        check_positive("fd_step", self.fd_step)?;
        if self.fd_step > 0.1 {
            return Err(invalid("fd_step", "must be ≤ 0.1 (fraction of range)"));
        }
        if !(self.armijo > 0.0 && self.armijo < 1.0) {
            return Err(invalid("armijo", "must be in (0, 1)"));
        }
        check_positive("tolerance", self.tolerance)?;
        if !(self.constraint_margin.is_finite() && self.constraint_margin >= 0.0) {
            return Err(invalid("constraint_margin", "must be finite and ≥ 0"));
        }
        if self.max_evaluations == 0 {
            return Err(invalid("max_evaluations", "must be ≥ 1"));
        }
        Ok(())
    }
}

/// P = f + r Σ max(0, g + δ)² (+∞ for NaN/inf anywhere).
fn penalty(e: &Evaluation, r: f64, margin: f64) -> f64 {
    if !e.violation().is_finite() {
        return f64::INFINITY;
    }
    e.objective()
        + r * e
            .constraints
            .iter()
            .map(|&g| (g + margin).max(0.0).powi(2))
            .sum::<f64>()
}

/// Memory of the nonmonotone Armijo rule (Grippo, Lampariello, Lucidi, SIAM J. Numer. Anal.
/// 23 (1986) 707–716), as in the spectral projected gradient method (Birgin, Martínez, Raydan,
/// SIAM J. Optim. 10 (2000) 1196–1211): BB steps are only effective if a temporary increase
/// of P is allowed.
const NONMONOTONE: usize = 10;

fn project(u: &mut [f64]) {
    for v in u {
        *v = v.clamp(0.0, 1.0);
    }
}

/// Runs penalty steepest descent. History: one entry per inner iteration (iteration 0 is the
/// starting point).
pub fn solve<P: Problem + ?Sized>(
    problem: &P,
    settings: &GradientSettings,
    observer: &mut dyn Observer,
) -> Result<SolverResult, OptimizeError> {
    settings.validate()?;
    let bounds = problem.bounds();
    bounds.validate()?;
    let x0 = check_start(bounds, settings.start.as_deref(), "start")?;
    let space = UnitSpace::new(bounds);
    let m = space.dim();
    let mut tracker = Tracker::new(problem, observer, settings.max_evaluations);
    let delta = settings.constraint_margin;

    let mut u = space.to_u(&x0);
    let Some(mut e) = tracker.evaluate_batch(0, &[x0]).pop() else {
        return tracker.finish();
    };
    tracker.end_iteration(0);
    let mut iteration = 1;
    let mut r = settings.penalty_initial;
    let h = settings.fd_step;
    let mut alpha = 1e-2;

    'outer: for _ in 0..settings.outer_iterations {
        if m == 0 {
            break;
        }
        let mut p = penalty(&e, r, delta);
        // BB memory: previous step and gradient (reset when r changes).
        let mut prev: Option<(Vec<f64>, Vec<f64>)> = None;
        // Nonmonotone Armijo reference: max of the last NONMONOTONE penalty values (GLL).
        let mut recent: Vec<f64> = vec![p];
        let u_outer = u.clone();
        for _ in 0..settings.inner_iterations {
            // Central differences, one-sided where the box cuts the stencil.
            let mut pts = Vec::with_capacity(2 * m);
            let mut widths = Vec::with_capacity(m);
            for j in 0..m {
                let (mut up, mut dn) = (u.clone(), u.clone());
                up[j] = (u[j] + h).min(1.0);
                dn[j] = (u[j] - h).max(0.0);
                widths.push(up[j] - dn[j]);
                pts.push(space.to_x(&up));
                pts.push(space.to_x(&dn));
            }
            if tracker.remaining() < 2 * m + 1 {
                break 'outer;
            }
            let fd = tracker.evaluate_batch(iteration, &pts);
            if fd.len() < 2 * m {
                break 'outer;
            }
            let grad: Vec<f64> = (0..m)
                .map(|j| {
                    (penalty(&fd[2 * j], r, delta) - penalty(&fd[2 * j + 1], r, delta)) / widths[j]
                })
                .collect();
            if grad.iter().any(|g| !g.is_finite()) {
                // A NaN/inf neighbour: no usable gradient here.
                tracker.end_iteration(iteration);
                iteration += 1;
                break;
            }
            // Stationarity of the box-constrained penalty problem.
            let pg = u
                .iter()
                .zip(&grad)
                .map(|(&ui, &g)| ((ui - g).clamp(0.0, 1.0) - ui).abs())
                .fold(0.0, f64::max);
            if pg < settings.tolerance {
                tracker.end_iteration(iteration);
                iteration += 1;
                break;
            }
            if let Some((s, g_old)) = &prev {
                let sy: f64 = s
                    .iter()
                    .zip(&grad)
                    .zip(g_old)
                    .map(|((s, g), go)| s * (g - go))
                    .sum();
                let ss: f64 = s.iter().map(|s| s * s).sum();
                if sy > 0.0 {
                    alpha = ss / sy;
                }
            }
            // Never try to move more than half the box in one step.
            let gmax = grad.iter().fold(0.0f64, |a, g| a.max(g.abs()));
            alpha = alpha.min(0.5 / gmax);
            let mut accepted = None;
            for _ in 0..=settings.max_backtracks {
                let mut ut: Vec<f64> = u
                    .iter()
                    .zip(&grad)
                    .map(|(&ui, &g)| ui - alpha * g)
                    .collect();
                project(&mut ut);
                let decrease: f64 = grad
                    .iter()
                    .zip(&ut)
                    .zip(&u)
                    .map(|((g, t), ui)| g * (t - ui))
                    .sum();
                let Some(et) = tracker.evaluate_one(iteration, &space.to_x(&ut)) else {
                    break;
                };
                let pt = penalty(&et, r, delta);
                let p_ref = recent.iter().copied().fold(p, f64::max);
                if pt <= p_ref + settings.armijo * decrease {
                    accepted = Some((ut, et, pt));
                    break;
                }
                alpha *= 0.5;
            }
            tracker.end_iteration(iteration);
            iteration += 1;
            let Some((ut, et, pt)) = accepted else {
                break; // no descent possible at this r: go to the next penalty level
            };
            let s: Vec<f64> = ut.iter().zip(&u).map(|(a, b)| a - b).collect();
            prev = Some((s, grad));
            u = ut;
            e = et;
            p = pt;
            if recent.len() >= NONMONOTONE {
                recent.remove(0);
            }
            recent.push(p);
        }
        // Converged: feasible and the penalty level no longer moves the point.
        let moved = u
            .iter()
            .zip(&u_outer)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        if e.feasible() && moved < settings.tolerance {
            break;
        }
        r *= settings.penalty_growth;
    }
    tracker.finish()
}

#[cfg(test)]
mod tests {
    use super::super::problem::{NoObserver, RecordLog};
    use super::super::test_problems::*;
    use super::*;

    /// min x² + y² s.t. x + y ≥ 1 from the infeasible (−1.5, −1.5): feasible, x within 1e-5
    /// of (½, ½), f within 1e-5 of ½.
    #[test]
    fn half_plane_from_infeasible_start() {
        let s = GradientSettings {
            start: Some(vec![-1.5, -1.5]),
            ..GradientSettings::default()
        };
        let p = Counting::new(HalfPlane::new());
        let mut log = RecordLog::default();
        let r = solve(&p, &s, &mut log).unwrap();
        assert!(!log.0[0].evaluation.feasible());
        assert!(r.feasible());
        assert!(
            (r.best_x[0] - 0.5).abs() < 1e-5 && (r.best_x[1] - 0.5).abs() < 1e-5,
            "{r:?}"
        );
        assert!((r.best.objective() - 0.5).abs() < 1e-5);
        assert_eq!(p.calls(), r.evaluations);
        assert_eq!(log.0.len(), r.evaluations);
        assert!(log.0.iter().enumerate().all(|(i, l)| l.index == i));
    }

    /// G06 from an infeasible start (20, 10): reaches the vertex optimum within 1e-4
    /// relative (steepest descent on a penalty is slow near a vertex; the margin keeps it
    /// feasible).
    #[test]
    fn g06_from_infeasible_start() {
        let s = GradientSettings {
            start: Some(vec![20.0, 10.0]),
            ..GradientSettings::default()
        };
        let r = solve(&G06::new(), &s, &mut NoObserver).unwrap();
        assert!(r.feasible(), "{:?}", r.best);
        assert!(
            (r.best.objective() - G06_F).abs() < 1e-4 * G06_F.abs(),
            "{} after {}",
            r.best.objective(),
            r.evaluations
        );
    }

    /// Rosenbrock on the disk from the centre (feasible, inside): within 1e-3.
    #[test]
    fn rosenbrock_disk() {
        let s = GradientSettings {
            start: Some(vec![-1.0, 0.5]),
            ..GradientSettings::default()
        };
        let r = solve(&RosenDisk::new(), &s, &mut NoObserver).unwrap();
        assert!(r.feasible(), "{:?}", r.best);
        assert!((r.best.objective() - ROSEN_DISK_F).abs() < 1e-3, "{:?}", r);
    }

    /// Fixed variable stays fixed; budget respected; deterministic across thread counts.
    #[test]
    fn fixed_budget_determinism() {
        let s = GradientSettings {
            start: Some(vec![-2.0, 0.25, -2.0]),
            max_evaluations: 300,
            ..GradientSettings::default()
        };
        let run = || {
            let mut log = RecordLog::default();
            let r = solve(&FixedMiddle::new(), &s, &mut log).unwrap();
            (r, log.0)
        };
        let (a, b) = one_and_many_threads(run);
        assert_eq!(a, b);
        assert!(a.0.evaluations <= 300);
        assert!(a.1.iter().all(|l| l.x[1] == 0.25));
        assert!((a.0.best_x[0] - 1.5).abs() < 1e-4, "{:?}", a.0.best_x);
    }

    /// Bad settings are errors.
    #[test]
    fn bad_settings() {
        let p = HalfPlane::new();
        for s in [
            GradientSettings {
                start: Some(vec![3.0, 0.0]),
                ..GradientSettings::default()
            },
            GradientSettings {
                penalty_growth: 1.0,
                ..GradientSettings::default()
            },
            GradientSettings {
                fd_step: 0.0,
                ..GradientSettings::default()
            },
            GradientSettings {
                armijo: 1.0,
                ..GradientSettings::default()
            },
            GradientSettings {
                max_evaluations: 0,
                ..GradientSettings::default()
            },
        ] {
            assert!(solve(&p, &s, &mut NoObserver).is_err());
        }
    }
}
