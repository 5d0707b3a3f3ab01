//! Feasibility-first differential evolution: DE/rand/1/bin or DE/current-to-best/1/bin with
//! Deb's feasibility rules in the one-to-one selection, optional jDE self-adaptation of F and
//! CR, followed by an optional constrained COBYLA polish of the best point.
//!
//! References: R. Storn, K. Price, "Differential evolution — a simple and efficient heuristic
//! for global optimization over continuous spaces", J. Global Optim. 11 (1997) 341–359;
//! J. Brest et al., "Self-adapting control parameters in differential evolution" (jDE), IEEE
//! Trans. Evol. Comput. 10 (2006) 646–657; K. Deb (2000) feasibility rules; J. Lampinen, "A
//! constraint handling approach for the differential evolution algorithm", CEC 2002.
//!
//! Each generation's trial vectors are built from the current population (synchronous DE)
//! and evaluated as one parallel batch.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::cobyla::{polish, PolishSettings};
use super::operators::uniform_point;
use super::problem::{
    check_probability, deb_cmp, invalid, Evaluation, Observer, OptimizeError, Problem,
    SolverResult, Tracker,
};

/// Mutation strategy of DE.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeStrategy {
    /// v = x_r1 + F (x_r2 − x_r3): explorative.
    RandOneBin,
    /// v = x_i + F (x_best − x_i) + F (x_r1 − x_r2): faster, greedier.
    CurrentToBestOneBin,
}

/// Settings of differential evolution.
#[derive(Debug, Clone, PartialEq)]
pub struct DeSettings {
    /// Population size NP (default 40; ≥ 4).
    pub population: usize,
    /// Generations after the initial one (default 150).
    pub generations: usize,
    /// Mutation strategy (default DE/rand/1/bin).
    pub strategy: DeStrategy,
    /// F: differential weight, initial value when self-adaptive (default 0.5; in (0, 2]).
    pub f: f64,
    /// CR: crossover probability, initial value when self-adaptive (default 0.9).
    pub cr: f64,
    /// jDE self-adaptation of F ∈ [0.1, 1] and CR ∈ [0, 1] per individual, τ₁ = τ₂ = 0.1
    /// (default true).
    pub self_adaptive: bool,
    /// COBYLA polish of the best point after the DE phase (default `Some(default)`).
    pub polish: Option<PolishSettings>,
    /// Total evaluation budget including the polish (default `None`: NP × (generations + 1)
    /// plus the polish budget). The DE phase stops early enough to leave the polish its
    /// budget; must be ≥ NP.
    pub max_evaluations: Option<usize>,
    /// Random seed (ChaCha8).
    pub seed: u64,
}

impl Default for DeSettings {
    fn default() -> Self {
        Self {
            population: 40,
            generations: 150,
            strategy: DeStrategy::RandOneBin,
            f: 0.5,
            cr: 0.9,
            self_adaptive: true,
            polish: Some(PolishSettings::default()),
            max_evaluations: None,
            seed: 0,
        }
    }
}

impl DeSettings {
    fn validate(&self) -> Result<(), OptimizeError> {
        if self.population < 4 {
            return Err(invalid("population", "must be ≥ 4"));
        }
        if !(self.f.is_finite() && self.f > 0.0 && self.f <= 2.0) {
            return Err(invalid("f", format!("{} is not in (0, 2]", self.f)));
        }
        check_probability("cr", self.cr)?;
        if let Some(p) = &self.polish {
            p.validate()?;
        }
        if let Some(m) = self.max_evaluations {
            if m < self.population {
                return Err(invalid("max_evaluations", "must be ≥ population"));
            }
        }
        Ok(())
    }
}

/// jDE adaptation rates τ₁, τ₂ and the F range [F_l, F_l + F_u] (Brest et al. 2006).
const TAU: f64 = 0.1;
const F_LOW: f64 = 0.1;
const F_SPAN: f64 = 0.9;

/// `k` distinct indices in 0..n, all different from `exclude`.
fn distinct(n: usize, exclude: usize, rng: &mut ChaCha8Rng) -> [usize; 3] {
    let mut out = [exclude; 3];
    for k in 0..3 {
        loop {
            let c = rng.random_range(0..n);
            if c != exclude && !out[..k].contains(&c) {
                out[k] = c;
                break;
            }
        }
    }
    out
}

/// Runs DE (and the polish). History: one entry per generation, then the polish's entries.
pub fn solve<P: Problem + ?Sized>(
    problem: &P,
    settings: &DeSettings,
    observer: &mut dyn Observer,
) -> Result<SolverResult, OptimizeError> {
    settings.validate()?;
    let bounds = problem.bounds();
    bounds.validate()?;
    let np = settings.population;
    let reserve = settings.polish.as_ref().map_or(0, |p| p.max_evaluations);
    let budget = settings
        .max_evaluations
        .unwrap_or(np * (settings.generations + 1) + reserve);
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let mut tracker = Tracker::new(problem, observer, budget);
    let dim = bounds.dim();
    let free = bounds.free_indices();

    let mut pop: Vec<Vec<f64>> = (0..np).map(|_| uniform_point(bounds, &mut rng)).collect();
    let mut evals: Vec<Evaluation> = tracker.evaluate_batch(0, &pop);
    tracker.end_iteration(0);
    let mut fs = vec![settings.f; np];
    let mut crs = vec![settings.cr; np];

    let mut generation = 1;
    // Each generation needs NP evaluations; the polish's share of the budget is kept back.
    while generation <= settings.generations
        && tracker.remaining() >= np + reserve
        && !tracker.failed()
        && evals.len() == np
    {
        let best = (0..np)
            .min_by(|&a, &b| deb_cmp(&evals[a], &evals[b]))
            .unwrap_or(0);
        let mut trials: Vec<Vec<f64>> = Vec::with_capacity(np);
        let mut trial_params: Vec<(f64, f64)> = Vec::with_capacity(np);
        for i in 0..np {
            let (f, cr) = if settings.self_adaptive {
                let f = if rng.random::<f64>() < TAU {
                    F_LOW + F_SPAN * rng.random::<f64>()
                } else {
                    fs[i]
                };
                let cr = if rng.random::<f64>() < TAU {
                    rng.random::<f64>()
                } else {
                    crs[i]
                };
                (f, cr)
            } else {
                (settings.f, settings.cr)
            };
            let [r1, r2, r3] = distinct(np, i, &mut rng);
            let j_rand = if free.is_empty() {
                usize::MAX
            } else {
                free[rng.random_range(0..free.len())]
            };
            let mut t = pop[i].clone();
            for j in 0..dim {
                if bounds.is_fixed(j) {
                    continue;
                }
                let cross = j == j_rand || rng.random::<f64>() < cr;
                if !cross {
                    continue;
                }
                let v = match settings.strategy {
                    DeStrategy::RandOneBin => pop[r1][j] + f * (pop[r2][j] - pop[r3][j]),
                    DeStrategy::CurrentToBestOneBin => {
                        pop[i][j] + f * (pop[best][j] - pop[i][j]) + f * (pop[r1][j] - pop[r2][j])
                    }
                };
                // Out of the box: halfway between the parent and the violated bound (keeps
                // the search density near the boundary, where constrained optima often are).
                t[j] = if v < bounds.lower[j] {
                    0.5 * (pop[i][j] + bounds.lower[j])
                } else if v > bounds.upper[j] {
                    0.5 * (pop[i][j] + bounds.upper[j])
                } else {
                    v
                };
            }
            trials.push(t);
            trial_params.push((f, cr));
        }
        let trial_evals = tracker.evaluate_batch(generation, &trials);
        tracker.end_iteration(generation);
        if trial_evals.len() < np {
            break;
        }
        for (i, (t, te)) in trials.into_iter().zip(trial_evals).enumerate() {
            // Ties go to the trial so the population can drift along plateaus.
            if deb_cmp(&te, &evals[i]).is_le() {
                pop[i] = t;
                evals[i] = te;
                (fs[i], crs[i]) = trial_params[i];
            }
        }
        generation += 1;
    }

    if let Some(p) = &settings.polish {
        if let Some((x, _)) = tracker.best().cloned() {
            polish(&mut tracker, &x, p, generation);
        }
    }
    tracker.finish()
}

#[cfg(test)]
mod tests {
    use super::super::problem::{NoObserver, RecordLog};
    use super::super::test_problems::*;
    use super::*;

    /// G06: DE + polish reaches f* within 1e-6 relative and x* within 1e-4.
    #[test]
    fn g06_with_polish() {
        let r = solve(&G06::new(), &DeSettings::default(), &mut NoObserver).unwrap();
        assert!(r.feasible());
        assert!(
            (r.best.objective() - G06_F).abs() < 1e-6 * G06_F.abs(),
            "{}",
            r.best.objective()
        );
        assert!((r.best_x[0] - G06_X[0]).abs() < 1e-4, "{:?}", r.best_x);
        assert!((r.best_x[1] - G06_X[1]).abs() < 1e-4, "{:?}", r.best_x);
    }

    /// G06 with a target: good enough at f < −6,000.
    struct TargetedG06(G06);

    impl Problem for TargetedG06 {
        fn bounds(&self) -> &crate::optimize::Bounds {
            self.0.bounds()
        }
        fn constraint_count(&self) -> usize {
            self.0.constraint_count()
        }
        fn evaluate(&self, x: &[f64]) -> Evaluation {
            self.0.evaluate(x)
        }
        fn target(&self) -> Option<f64> {
            Some(-6000.0)
        }
    }

    /// Issue 28: a target ends DE with the generation that first holds a feasible point
    /// below it (whole generations, so the result does not depend on the thread count),
    /// and the polish is not run; without it DE runs its whole budget.
    #[test]
    fn a_target_ends_the_search_with_its_generation() {
        let settings = DeSettings::default();
        let whole = solve(&G06::new(), &settings, &mut NoObserver).unwrap();
        let mut log = RecordLog::default();
        let early = solve(&TargetedG06(G06::new()), &settings, &mut log).unwrap();
        assert!(early.feasible() && early.best.objective() < -6000.0);
        assert_eq!(early.evaluations % settings.population, 0);
        assert!(
            early.evaluations < whole.evaluations / 2,
            "{}",
            early.evaluations
        );
        // The first record below the target is in the last generation.
        let first = log
            .0
            .iter()
            .find(|r| r.evaluation.feasible() && r.evaluation.objective() < -6000.0)
            .unwrap();
        assert_eq!(first.iteration, log.0.last().unwrap().iteration);
        // The same run as the untargeted one up to there.
        let mut all = RecordLog::default();
        solve(&G06::new(), &settings, &mut all).unwrap();
        assert_eq!(log.0[..], all.0[..log.0.len()]);
    }

    /// G06 without polish, current-to-best, fixed F/CR: within 1 % (DE alone).
    #[test]
    fn g06_current_to_best_no_polish() {
        let s = DeSettings {
            strategy: DeStrategy::CurrentToBestOneBin,
            self_adaptive: false,
            polish: None,
            ..DeSettings::default()
        };
        let r = solve(&G06::new(), &s, &mut NoObserver).unwrap();
        assert!(r.feasible());
        assert_eq!(r.evaluations, 40 * 151);
        assert!(
            (r.best.objective() - G06_F).abs() < 1e-2 * G06_F.abs(),
            "{}",
            r.best.objective()
        );
    }

    /// G08 (multimodal): global optimum within 1e-9 absolute.
    #[test]
    fn g08_global() {
        let r = solve(&G08::new(), &DeSettings::default(), &mut NoObserver).unwrap();
        assert!(r.feasible());
        assert!((r.best.objective() - G08_F).abs() < 1e-9, "{:?}", r.best);
    }

    /// G11 (equality as |h| ≤ 1e-4): within 1e-4 of 0.7499.
    #[test]
    fn g11_curve() {
        let r = solve(&G11::new(), &DeSettings::default(), &mut NoObserver).unwrap();
        assert!(r.feasible());
        assert!((r.best.objective() - G11_F).abs() < 1e-4, "{:?}", r.best);
    }

    /// Rosenbrock on the unit disk: boundary optimum within 1e-5.
    #[test]
    fn rosenbrock_disk() {
        let r = solve(&RosenDisk::new(), &DeSettings::default(), &mut NoObserver).unwrap();
        assert!(r.feasible());
        assert!(
            (r.best.objective() - ROSEN_DISK_F).abs() < 1e-5,
            "{:?}",
            r.best
        );
    }

    fn small() -> DeSettings {
        DeSettings {
            population: 12,
            generations: 15,
            seed: 9,
            polish: Some(PolishSettings {
                max_evaluations: 30,
                ..PolishSettings::default()
            }),
            ..DeSettings::default()
        }
    }

    /// Same seed → bitwise identical log and result on 1 and 4 threads.
    #[test]
    fn deterministic_across_threads() {
        let run = || {
            let mut log = RecordLog::default();
            let r = solve(&G06::new(), &small(), &mut log).unwrap();
            (r, log.0)
        };
        let (a, b) = one_and_many_threads(run);
        assert_eq!(a, b);
        assert_eq!(a.1.len(), a.0.evaluations);
        assert!(a.1.iter().enumerate().all(|(i, r)| r.index == i));
    }

    /// Budgets: default = NP (G + 1) + polish; explicit total budget never exceeded; the
    /// problem is called exactly as often as the observer sees.
    #[test]
    fn budget_respected() {
        let p = Counting::new(G06::new());
        let r = solve(&p, &small(), &mut NoObserver).unwrap();
        assert!(r.evaluations <= 12 * 16 + 30);
        assert!(r.evaluations > 12 * 16);
        for m in [12, 50, 101] {
            let p = Counting::new(G06::new());
            let s = DeSettings {
                max_evaluations: Some(m),
                ..small()
            };
            let r = solve(&p, &s, &mut NoObserver).unwrap();
            assert!(r.evaluations <= m, "{} > {m}", r.evaluations);
            assert_eq!(p.calls(), r.evaluations);
        }
    }

    /// Fixed variables stay fixed (DE and polish); optimum of the reduced problem found.
    #[test]
    fn fixed_variable_stays_fixed() {
        let mut log = RecordLog::default();
        let r = solve(&FixedMiddle::new(), &DeSettings::default(), &mut log).unwrap();
        assert!(log.0.iter().all(|rec| rec.x[1] == 0.25));
        assert!((r.best_x[0] - 1.5).abs() < 1e-5 && (r.best_x[2] - 1.5).abs() < 1e-5);
    }

    /// Bad settings are errors.
    #[test]
    fn bad_settings() {
        for s in [
            DeSettings {
                population: 3,
                ..DeSettings::default()
            },
            DeSettings {
                f: 0.0,
                ..DeSettings::default()
            },
            DeSettings {
                cr: -0.1,
                ..DeSettings::default()
            },
            DeSettings {
                max_evaluations: Some(5),
                ..DeSettings::default()
            },
            DeSettings {
                polish: Some(PolishSettings {
                    xtol: f64::NAN,
                    ..PolishSettings::default()
                }),
                ..DeSettings::default()
            },
        ] {
            assert!(solve(&G06::new(), &s, &mut NoObserver).is_err());
        }
    }
}
