//! (μ/μ_w, λ)-CMA-ES with Deb-rule ranking of the offspring, followed by an optional COBYLA
//! polish. Compact own implementation (the `cmaes` crate takes a scalar objective callback
//! and pulls in nalgebra; ranking by Deb's rules and our batch evaluation need ask/tell).
//!
//! References: N. Hansen, "The CMA evolution strategy: a tutorial", arXiv:1604.00772 (2016)
//! — all parameters and update equations follow its Table 1 and Fig. 7; constraint handling
//! by ranking with Deb's feasibility rules (the CMA-ES update only needs the ranking).
//!
//! Works on the free variables scaled to u ∈ \[0,1]; infeasible-box samples are clipped to
//! the box and the clipped step is used in the update (repair). The eigendecomposition of
//! the covariance is a cyclic Jacobi iteration (the problems have few variables).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::cobyla::{polish, PolishSettings};
use super::operators::normal;
use super::problem::{
    check_positive, check_start, deb_cmp, invalid, Observer, OptimizeError, Problem, SolverResult,
    Tracker, UnitSpace,
};

/// Settings of CMA-ES.
#[derive(Debug, Clone, PartialEq)]
pub struct CmaesSettings {
    /// Initial mean x₀ (default `None`: centre of the bounds).
    pub start: Option<Vec<f64>>,
    /// σ₀: initial step size as a fraction of the bound ranges (default 0.3).
    pub sigma0: f64,
    /// λ: offspring per generation (default `None`: 4 + ⌊3 ln m⌋, m free variables; ≥ 4).
    pub population: Option<usize>,
    /// Maximum generations (default 300).
    pub max_generations: usize,
    /// Stop when σ · max√(eig C) falls below this (scaled variables, default 1e-10).
    pub tol_x: f64,
    /// COBYLA polish of the best point (default `Some(default)`).
    pub polish: Option<PolishSettings>,
    /// Total evaluation budget including the polish (default `None`: λ × max_generations
    /// plus the polish budget).
    pub max_evaluations: Option<usize>,
    /// Random seed (ChaCha8).
    pub seed: u64,
}

impl Default for CmaesSettings {
    fn default() -> Self {
        Self {
            start: None,
            sigma0: 0.3,
            population: None,
            max_generations: 300,
            tol_x: 1e-10,
            polish: Some(PolishSettings::default()),
            max_evaluations: None,
            seed: 0,
        }
    }
}

/// Eigen-decomposition of a symmetric matrix by cyclic Jacobi rotations: returns
/// (eigenvalues, eigenvectors as columns of a row-major m×m matrix).
// Index loops mirror the rotation formulas (rows p and q updated together).
#[allow(clippy::needless_range_loop)]
fn jacobi_eigen(a: &[Vec<f64>]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let m = a.len();
    let mut a = a.to_vec();
    let mut v = vec![vec![0.0; m]; m];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for _sweep in 0..100 {
        let off: f64 = (0..m)
            .flat_map(|i| (0..m).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i][j] * a[i][j])
            .sum();
        let norm: f64 = a.iter().flatten().map(|x| x * x).sum();
        if off <= 1e-30 * norm {
            break;
        }
        for p in 0..m {
            for q in p + 1..m {
                if a[p][q] == 0.0 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..m {
                    let (akp, akq) = (a[k][p], a[k][q]);
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for k in 0..m {
                    let (apk, aqk) = (a[p][k], a[q][k]);
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for row in v.iter_mut() {
                    let (vkp, vkq) = (row[p], row[q]);
                    row[p] = c * vkp - s * vkq;
                    row[q] = s * vkp + c * vkq;
                }
            }
        }
    }
    ((0..m).map(|i| a[i][i]).collect(), v)
}

/// Runs CMA-ES (and the polish). History: one entry per generation (0 = nothing but the
/// first generation's samples), then the polish's entries.
pub fn solve<P: Problem + ?Sized>(
    problem: &P,
    settings: &CmaesSettings,
    observer: &mut dyn Observer,
) -> Result<SolverResult, OptimizeError> {
    let bounds = problem.bounds();
    bounds.validate()?;
    check_positive("sigma0", settings.sigma0)?;
    check_positive("tol_x", settings.tol_x)?;
    if let Some(p) = &settings.polish {
        p.validate()?;
    }
    let x0 = check_start(bounds, settings.start.as_deref(), "start")?;
    let space = UnitSpace::new(bounds);
    let m = space.dim();
    let mf = m.max(1) as f64;
    let lambda = settings
        .population
        .unwrap_or(4 + (3.0 * mf.ln()).floor() as usize);
    if lambda < 4 {
        return Err(invalid("population", "must be ≥ 4"));
    }
    let reserve = settings.polish.as_ref().map_or(0, |p| p.max_evaluations);
    let budget = settings
        .max_evaluations
        .unwrap_or(lambda * settings.max_generations + reserve);
    if budget == 0 {
        return Err(invalid("max_evaluations", "must be ≥ 1"));
    }
    let mut tracker = Tracker::new(problem, observer, budget);
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);

    // Strategy parameters (Hansen 2016, Table 1).
    let mu = lambda / 2;
    let raw: Vec<f64> = (0..mu)
        .map(|i| ((lambda as f64 + 1.0) / 2.0).ln() - ((i + 1) as f64).ln())
        .collect();
    let wsum: f64 = raw.iter().sum();
    let w: Vec<f64> = raw.iter().map(|x| x / wsum).collect();
    let mu_eff = 1.0 / w.iter().map(|x| x * x).sum::<f64>();
    let c_sigma = (mu_eff + 2.0) / (mf + mu_eff + 5.0);
    let d_sigma = 1.0 + 2.0 * (((mu_eff - 1.0) / (mf + 1.0)).sqrt() - 1.0).max(0.0) + c_sigma;
    let c_c = (4.0 + mu_eff / mf) / (mf + 4.0 + 2.0 * mu_eff / mf);
    let c_1 = 2.0 / ((mf + 1.3).powi(2) + mu_eff);
    let c_mu = (1.0 - c_1).min(2.0 * (mu_eff - 2.0 + 1.0 / mu_eff) / ((mf + 2.0).powi(2) + mu_eff));
    let chi_n = mf.sqrt() * (1.0 - 1.0 / (4.0 * mf) + 1.0 / (21.0 * mf * mf));

    let mut mean = space.to_u(&x0);
    let mut sigma = settings.sigma0;
    let mut c = vec![vec![0.0; m]; m];
    for (i, row) in c.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let (mut b, mut d) = (c.clone(), vec![1.0; m]);
    let (mut p_sigma, mut p_c) = (vec![0.0; m], vec![0.0; m]);

    let mut generation = 0;
    if m == 0 {
        tracker.evaluate_batch(0, &[x0]);
        tracker.end_iteration(0);
        generation = 1;
    }
    while m > 0
        && generation < settings.max_generations
        // Keep the polish's budget back, but always run at least one generation.
        && (tracker.remaining() >= lambda + reserve
            || (generation == 0 && tracker.remaining() >= lambda))
        && !tracker.failed()
    {
        // Ask: λ samples u = m + σ B D z, clipped to the box.
        let mut us: Vec<Vec<f64>> = Vec::with_capacity(lambda);
        for _ in 0..lambda {
            let z: Vec<f64> = (0..m).map(|_| normal(&mut rng)).collect();
            let u: Vec<f64> = (0..m)
                .map(|i| {
                    let y: f64 = (0..m).map(|j| b[i][j] * d[j] * z[j]).sum();
                    (mean[i] + sigma * y).clamp(0.0, 1.0)
                })
                .collect();
            us.push(u);
        }
        let xs: Vec<Vec<f64>> = us.iter().map(|u| space.to_x(u)).collect();
        let evals = tracker.evaluate_batch(generation, &xs);
        tracker.end_iteration(generation);
        generation += 1;
        if evals.len() < lambda {
            break;
        }
        // Tell: rank by Deb's rules (stable, so ties keep sample order).
        let mut order: Vec<usize> = (0..lambda).collect();
        order.sort_by(|&a, &b| deb_cmp(&evals[a], &evals[b]));
        let ys: Vec<Vec<f64>> = order[..mu]
            .iter()
            .map(|&k| (0..m).map(|i| (us[k][i] - mean[i]) / sigma).collect())
            .collect();
        let y_w: Vec<f64> = (0..m)
            .map(|i| (0..mu).map(|k| w[k] * ys[k][i]).sum())
            .collect();
        for i in 0..m {
            mean[i] += sigma * y_w[i];
        }
        // C^{-1/2} y_w = B D⁻¹ Bᵀ y_w.
        let bty: Vec<f64> = (0..m)
            .map(|j| (0..m).map(|i| b[i][j] * y_w[i]).sum::<f64>() / d[j])
            .collect();
        let cs = (c_sigma * (2.0 - c_sigma) * mu_eff).sqrt();
        for i in 0..m {
            let inv: f64 = (0..m).map(|j| b[i][j] * bty[j]).sum();
            p_sigma[i] = (1.0 - c_sigma) * p_sigma[i] + cs * inv;
        }
        let ps_norm = p_sigma.iter().map(|x| x * x).sum::<f64>().sqrt();
        let h_sigma = ps_norm / (1.0 - (1.0 - c_sigma).powi(2 * generation as i32)).sqrt()
            < (1.4 + 2.0 / (mf + 1.0)) * chi_n;
        let h = if h_sigma { 1.0 } else { 0.0 };
        let cc = (c_c * (2.0 - c_c) * mu_eff).sqrt();
        for i in 0..m {
            p_c[i] = (1.0 - c_c) * p_c[i] + h * cc * y_w[i];
        }
        let delta_h = (1.0 - h) * c_c * (2.0 - c_c);
        for i in 0..m {
            for j in 0..m {
                let rank_mu: f64 = (0..mu).map(|k| w[k] * ys[k][i] * ys[k][j]).sum();
                c[i][j] = (1.0 - c_1 - c_mu) * c[i][j]
                    + c_1 * (p_c[i] * p_c[j] + delta_h * c[i][j])
                    + c_mu * rank_mu;
            }
        }
        sigma *= ((c_sigma / d_sigma) * (ps_norm / chi_n - 1.0)).exp();
        // Keep σ sane in the unit cube (a huge σ only produces clipped corner samples).
        sigma = sigma.min(1.0);
        let (eig, vecs) = jacobi_eigen(&c);
        b = vecs;
        d = eig.iter().map(|&l| l.max(1e-300).sqrt()).collect();
        let dmax = d.iter().fold(0.0f64, |a, &x| a.max(x));
        if sigma * dmax < settings.tol_x || !sigma.is_finite() {
            break;
        }
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

    /// Jacobi: eigenpairs of a symmetric 3×3 matrix reproduce it (A v = λ v to 1e-12).
    #[test]
    fn jacobi_reconstructs() {
        let a = vec![
            vec![4.0, 1.0, 0.5],
            vec![1.0, 3.0, -0.2],
            vec![0.5, -0.2, 1.0],
        ];
        let (l, v) = jacobi_eigen(&a);
        for k in 0..3 {
            for i in 0..3 {
                let av: f64 = (0..3).map(|j| a[i][j] * v[j][k]).sum();
                assert!((av - l[k] * v[i][k]).abs() < 1e-12);
            }
        }
        let trace: f64 = l.iter().sum();
        assert!((trace - 8.0).abs() < 1e-12);
    }

    /// G06 with polish: f* within 1e-6 relative.
    #[test]
    fn g06_with_polish() {
        let r = solve(&G06::new(), &CmaesSettings::default(), &mut NoObserver).unwrap();
        assert!(r.feasible());
        assert!(
            (r.best.objective() - G06_F).abs() < 1e-6 * G06_F.abs(),
            "{:?}",
            r.best
        );
    }

    /// G06 without polish: CMA-ES alone within 1e-3 relative.
    #[test]
    fn g06_without_polish() {
        let s = CmaesSettings {
            polish: None,
            ..CmaesSettings::default()
        };
        let r = solve(&G06::new(), &s, &mut NoObserver).unwrap();
        assert!(r.feasible());
        assert!(
            (r.best.objective() - G06_F).abs() < 1e-3 * G06_F.abs(),
            "{:?}",
            r.best
        );
    }

    /// Rosenbrock on the unit disk: within 1e-6; G11 within 1e-4.
    #[test]
    fn rosenbrock_disk_and_g11() {
        let r = solve(
            &RosenDisk::new(),
            &CmaesSettings::default(),
            &mut NoObserver,
        )
        .unwrap();
        assert!(r.feasible());
        assert!(
            (r.best.objective() - ROSEN_DISK_F).abs() < 1e-6,
            "{:?}",
            r.best
        );
        let r = solve(&G11::new(), &CmaesSettings::default(), &mut NoObserver).unwrap();
        assert!(r.feasible());
        assert!((r.best.objective() - G11_F).abs() < 1e-4, "{:?}", r.best);
    }

    /// Deterministic across threads; budget respected; fixed variable fixed; log complete.
    #[test]
    fn determinism_budget_fixed() {
        let s = CmaesSettings {
            max_evaluations: Some(150),
            seed: 4,
            ..CmaesSettings::default()
        };
        let run = || {
            let mut log = RecordLog::default();
            let r = solve(&Counting::new(FixedMiddle::new()), &s, &mut log).unwrap();
            (r, log.0)
        };
        let (a, b) = one_and_many_threads(run);
        assert_eq!(a, b);
        assert!(a.0.evaluations <= 150);
        assert_eq!(a.1.len(), a.0.evaluations);
        assert!(a
            .1
            .iter()
            .enumerate()
            .all(|(i, l)| l.index == i && l.x[1] == 0.25));
        let r = solve(
            &FixedMiddle::new(),
            &CmaesSettings::default(),
            &mut NoObserver,
        )
        .unwrap();
        assert!((r.best_x[0] - 1.5).abs() < 1e-5 && (r.best_x[2] - 1.5).abs() < 1e-5);
    }

    /// Bad settings are errors.
    #[test]
    fn bad_settings() {
        for s in [
            CmaesSettings {
                sigma0: -1.0,
                ..CmaesSettings::default()
            },
            CmaesSettings {
                population: Some(2),
                ..CmaesSettings::default()
            },
            CmaesSettings {
                start: Some(vec![1.0]),
                ..CmaesSettings::default()
            },
            CmaesSettings {
                max_evaluations: Some(0),
                ..CmaesSettings::default()
            },
        ] {
            assert!(solve(&G06::new(), &s, &mut NoObserver).is_err());
        }
    }
}
