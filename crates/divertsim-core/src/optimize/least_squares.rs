//! Robust nonlinear least squares: Levenberg–Marquardt on a Huber loss, by iteratively
//! reweighted least squares, inside box bounds.
//!
//! Minimises L(x) = Σ ρ(r_i(x)) with ρ(r) = r²/2 for |r| ≤ δ and δ(|r| − δ/2) beyond (Huber
//! 1964): quadratic for residuals the size of the noise, linear for outliers, so a few points
//! the model cannot follow (a model that is not quite the one that made the data) pull the
//! fit less than under squares. Each iteration weights the residuals w_i = min(1, δ/|r_i|)
//! and takes a Levenberg–Marquardt step (JᵀWJ + λ diag(JᵀWJ)) Δ = −JᵀWr, with a
//! forward-difference Jacobian (columns in parallel, results in order) and the step clamped
//! to the box; λ falls by 3 after a step that lowers L and rises by 4 after one that does
//! not (Nielsen's rule, simplified). Stops when L falls by less than `tolerance` relatively,
//! after `max_iterations`, or when λ exceeds 1e12.
//!
//! References: Madsen, Nielsen & Tingleff, *Methods for non-linear least squares problems*
//! (2004) §3.2; Huber, Ann. Math. Statist. 35 (1964) 73–101.

use rayon::prelude::*;

use super::problem::Bounds;

/// Settings of the local fit.
#[derive(Debug, Clone, PartialEq)]
pub struct LeastSquaresSettings {
    /// δ: the Huber threshold, in residual units (> 0; `f64::INFINITY` for plain squares).
    pub huber: f64,
    /// Largest number of iterations (each one Jacobian).
    pub max_iterations: usize,
    /// Forward-difference step as a fraction of each variable's box width.
    pub difference_step: f64,
    /// Relative decrease of L below which the fit stops.
    pub tolerance: f64,
}

impl Default for LeastSquaresSettings {
    fn default() -> Self {
        LeastSquaresSettings {
            huber: f64::INFINITY,
            max_iterations: 50,
            difference_step: 1e-4,
            tolerance: 1e-10,
        }
    }
}

/// The fit.
#[derive(Debug, Clone, PartialEq)]
pub struct LeastSquaresResult {
    pub x: Vec<f64>,
    /// L at x.
    pub loss: f64,
    pub residuals: Vec<f64>,
    pub iterations: usize,
    /// Residual-vector evaluations made.
    pub evaluations: usize,
}

/// ρ(r) summed: the Huber loss with threshold δ.
pub fn huber_loss(r: &[f64], delta: f64) -> f64 {
    r.iter()
        .map(|&v| {
            let a = v.abs();
            if a <= delta {
                0.5 * v * v
            } else {
                delta * (a - 0.5 * delta)
            }
        })
        .sum()
}

/// Solve A x = b for a small symmetric positive definite A (Gaussian elimination with
/// partial pivoting); `None` if singular.
pub(crate) fn solve_dense(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for col in 0..n {
        let piv = (col..n).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < 1e-300 || !a[piv][col].is_finite() {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        let pivot_row = a[col].clone();
        for row in col + 1..n {
            let f = a[row][col] / pivot_row[col];
            for (v, pv) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                *v -= f * pv;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| a[i][k] * x[k]).sum();
        x[i] = (b[i] - s) / a[i][i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Minimise Σ ρ(r(x)) from `x0` inside `bounds` (module notes). `residuals` must return a
/// vector of the same length at every x; non-finite residuals count as a failed trial step.
pub fn solve<F>(
    residuals: F,
    x0: &[f64],
    bounds: &Bounds,
    settings: &LeastSquaresSettings,
) -> LeastSquaresResult
where
    F: Fn(&[f64]) -> Vec<f64> + Sync,
{
    let clamp = |x: &mut Vec<f64>| {
        for (i, v) in x.iter_mut().enumerate() {
            *v = v.clamp(bounds.lower[i], bounds.upper[i]);
        }
    };
    let loss_of = |r: &[f64]| {
        if r.iter().all(|v| v.is_finite()) {
            huber_loss(r, settings.huber)
        } else {
            f64::INFINITY
        }
    };
    let p = x0.len();
    let mut x = x0.to_vec();
    clamp(&mut x);
    let mut r = residuals(&x);
    let mut loss = loss_of(&r);
    let mut evaluations = 1;
    let mut lambda = 1e-3;
    let mut iterations = 0;
    while iterations < settings.max_iterations && loss.is_finite() && loss > 0.0 {
        iterations += 1;
        // Forward differences, each column pointing into the box.
        let cols: Vec<(f64, Vec<f64>)> = (0..p)
            .into_par_iter()
            .map(|j| {
                let width = bounds.upper[j] - bounds.lower[j];
                let mut h = settings.difference_step * width.max(1e-12);
                if x[j] + h > bounds.upper[j] {
                    h = -h;
                }
                let mut xj = x.clone();
                xj[j] += h;
                (h, residuals(&xj))
            })
            .collect();
        evaluations += p;
        let w: Vec<f64> = r
            .iter()
            .map(|v| {
                let a = v.abs();
                if a <= settings.huber {
                    1.0
                } else {
                    settings.huber / a
                }
            })
            .collect();
        // J_ij = (r_i(x + h e_j) − r_i(x))/h.
        let jac: Vec<Vec<f64>> = cols
            .iter()
            .map(|(h, rj)| rj.iter().zip(&r).map(|(a, b)| (a - b) / h).collect())
            .collect();
        if jac.iter().flatten().any(|v| !v.is_finite()) {
            break;
        }
        let mut a = vec![vec![0.0; p]; p];
        let mut g = vec![0.0; p];
        for i in 0..p {
            for k in 0..p {
                a[i][k] = (0..r.len()).map(|n| jac[i][n] * w[n] * jac[k][n]).sum();
            }
            g[i] = (0..r.len()).map(|n| jac[i][n] * w[n] * r[n]).sum();
        }
        let mut improved = false;
        while lambda < 1e12 {
            let mut m = a.clone();
            for (i, row) in m.iter_mut().enumerate() {
                row[i] += lambda * a[i][i].max(1e-12);
            }
            let Some(step) = solve_dense(m, g.iter().map(|v| -v).collect()) else {
                lambda *= 4.0;
                continue;
            };
            let mut trial: Vec<f64> = x.iter().zip(&step).map(|(a, b)| a + b).collect();
            clamp(&mut trial);
            let rt = residuals(&trial);
            evaluations += 1;
            let lt = loss_of(&rt);
            if lt < loss {
                let decrease = (loss - lt) / loss;
                x = trial;
                r = rt;
                loss = lt;
                lambda = (lambda / 3.0).max(1e-12);
                improved = decrease > settings.tolerance;
                break;
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    LeastSquaresResult {
        x,
        loss,
        residuals: r,
        iterations,
        evaluations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exponential decay y = a e^{−b t}: recovers (a, b) from exact data.
    #[test]
    fn fits_an_exponential() {
        let ts: Vec<f64> = (0..30).map(|i| i as f64 * 0.1).collect();
        let data: Vec<f64> = ts.iter().map(|t| 2.5 * (-1.3 * t).exp()).collect();
        let f = |x: &[f64]| -> Vec<f64> {
            ts.iter()
                .zip(&data)
                .map(|(t, y)| x[0] * (-x[1] * t).exp() - y)
                .collect()
        };
        let b = Bounds::new(vec![0.1, 0.1], vec![10.0, 10.0]).unwrap();
        let r = solve(f, &[1.0, 0.5], &b, &LeastSquaresSettings::default());
        assert!(
            (r.x[0] - 2.5).abs() < 1e-6 && (r.x[1] - 1.3).abs() < 1e-6,
            "{:?}",
            r.x
        );
    }

    /// One gross outlier: the Huber fit stays near the truth, plain squares do not.
    #[test]
    fn huber_resists_an_outlier() {
        let xs: Vec<f64> = (0..20).map(|i| i as f64).collect();
        let mut ys: Vec<f64> = xs.iter().map(|x| 1.0 + 0.5 * x).collect();
        ys[10] += 50.0;
        let f = |p: &[f64]| -> Vec<f64> {
            xs.iter()
                .zip(&ys)
                .map(|(x, y)| p[0] + p[1] * x - y)
                .collect()
        };
        let b = Bounds::new(vec![-10.0, -10.0], vec![10.0, 10.0]).unwrap();
        let robust = solve(
            f,
            &[0.0, 0.0],
            &b,
            &LeastSquaresSettings {
                huber: 0.5,
                ..LeastSquaresSettings::default()
            },
        );
        let plain = solve(f, &[0.0, 0.0], &b, &LeastSquaresSettings::default());
        assert!((robust.x[1] - 0.5).abs() < 0.02, "{:?}", robust.x);
        assert!((plain.x[0] - 1.0).abs() > (robust.x[0] - 1.0).abs());
    }

    #[test]
    fn stays_inside_the_box() {
        let f = |x: &[f64]| vec![x[0] - 5.0];
        let b = Bounds::new(vec![0.0], vec![1.0]).unwrap();
        let r = solve(f, &[0.5], &b, &LeastSquaresSettings::default());
        assert_eq!(r.x[0], 1.0);
    }
}
