//! Variation operators of the real-coded evolutionary solvers (GA, NSGA-II): simulated binary
//! crossover (SBX), BLX-α crossover, polynomial and Gaussian mutation, and uniform
//! initialisation. All respect the box and leave fixed variables (lower == upper) untouched.
//!
//! References: K. Deb, R. B. Agrawal, "Simulated binary crossover for continuous search
//! space", Complex Systems 9 (1995) 115–148; K. Deb, M. Goyal, "A combined genetic adaptive
//! search (GeneAS) for engineering design", Computer Science and Informatics 26 (1996) 30–45
//! (polynomial mutation); the bounded forms follow Deb's NSGA-II reference code. L. J.
//! Eshelman, J. D. Schaffer, "Real-coded genetic algorithms and interval-schemata" (1993)
//! (BLX-α).

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::problem::Bounds;

/// Uniform random point in the box.
pub(crate) fn uniform_point(bounds: &Bounds, rng: &mut ChaCha8Rng) -> Vec<f64> {
    bounds
        .lower
        .iter()
        .zip(&bounds.upper)
        .map(|(&l, &u)| {
            if l == u {
                l
            } else {
                (l + rng.random::<f64>() * (u - l)).min(u)
            }
        })
        .collect()
}

/// Standard normal deviate (Box–Muller; own so that no distribution crate is needed).
pub(crate) fn normal(rng: &mut ChaCha8Rng) -> f64 {
    // 1 − U ∈ (0, 1] keeps the logarithm finite.
    let u1 = 1.0 - rng.random::<f64>();
    let u2 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Bounded SBX with distribution index η_c on a pair of parents, in place. Each free variable
/// is crossed with probability ½ (as in Deb's code); children are swapped with probability ½.
pub(crate) fn sbx(bounds: &Bounds, eta: f64, a: &mut [f64], b: &mut [f64], rng: &mut ChaCha8Rng) {
    for i in 0..a.len() {
        let (yl, yu) = (bounds.lower[i], bounds.upper[i]);
        if yl == yu || rng.random::<f64>() > 0.5 || (a[i] - b[i]).abs() <= 1e-14 * (yu - yl) {
            continue;
        }
        let (y1, y2) = (a[i].min(b[i]), a[i].max(b[i]));
        let r: f64 = rng.random();
        let betaq = |beta: f64| {
            let alpha = 2.0 - beta.powf(-(eta + 1.0));
            if r <= 1.0 / alpha {
                (r * alpha).powf(1.0 / (eta + 1.0))
            } else {
                (1.0 / (2.0 - r * alpha)).powf(1.0 / (eta + 1.0))
            }
        };
        let bq1 = betaq(1.0 + 2.0 * (y1 - yl) / (y2 - y1));
        let bq2 = betaq(1.0 + 2.0 * (yu - y2) / (y2 - y1));
        let c1 = (0.5 * ((y1 + y2) - bq1 * (y2 - y1))).clamp(yl, yu);
        let c2 = (0.5 * ((y1 + y2) + bq2 * (y2 - y1))).clamp(yl, yu);
        if rng.random::<f64>() < 0.5 {
            a[i] = c2;
            b[i] = c1;
        } else {
            a[i] = c1;
            b[i] = c2;
        }
    }
}

/// BLX-α crossover in place: each child variable uniform in the parents' interval widened by
/// α times its length on both sides, clamped to the box.
pub(crate) fn blx(bounds: &Bounds, alpha: f64, a: &mut [f64], b: &mut [f64], rng: &mut ChaCha8Rng) {
    for i in 0..a.len() {
        let (yl, yu) = (bounds.lower[i], bounds.upper[i]);
        if yl == yu {
            continue;
        }
        let (lo, hi) = (a[i].min(b[i]), a[i].max(b[i]));
        let d = hi - lo;
        let (lo, hi) = (lo - alpha * d, hi + alpha * d);
        a[i] = (lo + rng.random::<f64>() * (hi - lo)).clamp(yl, yu);
        b[i] = (lo + rng.random::<f64>() * (hi - lo)).clamp(yl, yu);
    }
}

/// Bounded polynomial mutation with distribution index η_m; each free variable mutates with
/// probability `p`.
pub(crate) fn polynomial_mutation(
    bounds: &Bounds,
    eta: f64,
    p: f64,
    x: &mut [f64],
    rng: &mut ChaCha8Rng,
) {
    for (i, xi) in x.iter_mut().enumerate() {
        let (yl, yu) = (bounds.lower[i], bounds.upper[i]);
        if yl == yu || rng.random::<f64>() >= p {
            continue;
        }
        let y = *xi;
        let (d1, d2) = ((y - yl) / (yu - yl), (yu - y) / (yu - yl));
        let r: f64 = rng.random();
        let pw = 1.0 / (eta + 1.0);
        let dq = if r <= 0.5 {
            let val = 2.0 * r + (1.0 - 2.0 * r) * (1.0 - d1).powf(eta + 1.0);
            val.powf(pw) - 1.0
        } else {
            let val = 2.0 * (1.0 - r) + 2.0 * (r - 0.5) * (1.0 - d2).powf(eta + 1.0);
            1.0 - val.powf(pw)
        };
        *xi = (y + dq * (yu - yl)).clamp(yl, yu);
    }
}

/// Gaussian mutation: each free variable mutates with probability `p` by a normal step of
/// standard deviation `scale` × (upper − lower), then is clamped to the box.
pub(crate) fn gaussian_mutation(
    bounds: &Bounds,
    scale: f64,
    p: f64,
    x: &mut [f64],
    rng: &mut ChaCha8Rng,
) {
    for (i, xi) in x.iter_mut().enumerate() {
        let (yl, yu) = (bounds.lower[i], bounds.upper[i]);
        if yl == yu || rng.random::<f64>() >= p {
            continue;
        }
        *xi = (*xi + scale * (yu - yl) * normal(rng)).clamp(yl, yu);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use rand::SeedableRng;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        /// Every operator keeps children in the box and fixed variables fixed.
        #[test]
        fn operators_respect_bounds(seed in 0u64..10_000, a0 in 0.0f64..1.0, b0 in 0.0f64..1.0,
                                    a2 in 0.0f64..1.0, b2 in 0.0f64..1.0) {
            let bounds = Bounds::new(vec![-1.0, 2.0, 10.0], vec![1.0, 2.0, 20.0]).unwrap();
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let mk = |t0: f64, t2: f64| vec![-1.0 + 2.0 * t0, 2.0, 10.0 + 10.0 * t2];
            let (mut a, mut b) = (mk(a0, a2), mk(b0, b2));
            sbx(&bounds, 15.0, &mut a, &mut b, &mut rng);
            blx(&bounds, 0.5, &mut a, &mut b, &mut rng);
            polynomial_mutation(&bounds, 20.0, 1.0, &mut a, &mut rng);
            gaussian_mutation(&bounds, 0.5, 1.0, &mut b, &mut rng);
            let u = uniform_point(&bounds, &mut rng);
            for x in [&a, &b, &u] {
                for ((xi, lo), hi) in x.iter().zip(&bounds.lower).zip(&bounds.upper) {
                    prop_assert!(xi >= lo && xi <= hi);
                }
                prop_assert_eq!(x[1], 2.0);
            }
        }
    }

    /// Box–Muller deviates have mean ≈ 0 and variance ≈ 1 (n = 20000: 4σ tolerances).
    #[test]
    fn normal_moments() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let n = 20_000;
        let v: Vec<f64> = (0..n).map(|_| normal(&mut rng)).collect();
        let mean = v.iter().sum::<f64>() / n as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 4.0 / (n as f64).sqrt(), "mean {mean}");
        assert!(
            (var - 1.0).abs() < 4.0 * (2.0 / n as f64).sqrt(),
            "var {var}"
        );
    }

    /// SBX preserves the parents' mean on an unbounded-like interval (symmetric spread).
    #[test]
    fn sbx_children_mean_equals_parents_mean_away_from_bounds() {
        let bounds = Bounds::new(vec![-1e6], vec![1e6]).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..100 {
            let (mut a, mut b) = (vec![1.0], vec![2.0]);
            sbx(&bounds, 15.0, &mut a, &mut b, &mut rng);
            assert!((a[0] + b[0] - 3.0).abs() < 1e-9, "{a:?} {b:?}");
        }
    }
}
