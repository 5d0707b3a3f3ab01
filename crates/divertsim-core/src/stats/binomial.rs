//! The Clopper–Pearson interval of a binomial proportion: the "exact" interval, found by
//! inverting two one-sided binomial tests. For k successes in n trials at confidence 1 − α:
//!
//!   lower = B⁻¹(α/2; k, n − k + 1)  (0 when k = 0),
//!   upper = B⁻¹(1 − α/2; k + 1, n − k)  (1 when k = n),
//!
//! with B⁻¹ the Beta quantile. Its coverage is at least 1 − α for every true proportion
//! (conservative), which is why a reliability claim uses it rather than the normal
//! approximation, which undercovers near 0 and 1, where divert rates live.
//!
//! Reference: Clopper & Pearson (1934), Biometrika 26, 404–413.

use super::special::beta_quantile;

/// A proportion with its interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Proportion {
    /// k: successes
    pub successes: u64,
    /// n: trials
    pub trials: u64,
    /// k/n (NaN for n = 0)
    pub estimate: f64,
    /// Lower end of the interval (0 for n = 0)
    pub lower: f64,
    /// Upper end of the interval (1 for n = 0)
    pub upper: f64,
}

impl Proportion {
    /// upper − lower.
    pub fn width(&self) -> f64 {
        self.upper - self.lower
    }
}

/// The Clopper–Pearson interval of k successes in n trials at `confidence` (e.g. 0.95), in
/// (0, 1). With n = 0 the interval is [0, 1] and the estimate NaN; k > n is clamped to n.
pub fn clopper_pearson(successes: u64, trials: u64, confidence: f64) -> Proportion {
    let k = successes.min(trials);
    let n = trials;
    if n == 0 {
        return Proportion {
            successes: 0,
            trials: 0,
            estimate: f64::NAN,
            lower: 0.0,
            upper: 1.0,
        };
    }
    let alpha = 1.0 - confidence;
    let (kf, nf) = (k as f64, n as f64);
    let lower = if k == 0 {
        0.0
    } else {
        beta_quantile(alpha / 2.0, kf, nf - kf + 1.0)
    };
    let upper = if k == n {
        1.0
    } else {
        beta_quantile(1.0 - alpha / 2.0, kf + 1.0, nf - kf)
    };
    Proportion {
        successes: k,
        trials: n,
        estimate: kf / nf,
        lower,
        upper,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// (k, n, lower, upper) from scipy.stats.beta.ppf (R's binom.test gives the same).
    const REFERENCE: [(u64, u64, f64, f64); 7] = [
        (5, 20, 0.08657146910143461, 0.49104587170795744),
        (50, 100, 0.39832112950330095, 0.601678870496699),
        (682, 925, 0.707668264079039, 0.7654065582415253),
        (0, 10, 0.0, 0.3084971078187607),
        (10, 10, 0.6915028921812392, 1.0),
        (1, 1_000_000, 2.5317807663794178e-08, 5.571630655166939e-06),
        (999_000, 1_000_000, 0.9989360818926848, 0.9990609987920499),
    ];

    #[test]
    fn matches_reference_intervals() {
        for (k, n, lo, hi) in REFERENCE {
            let p = clopper_pearson(k, n, 0.95);
            assert_relative_eq!(p.lower, lo, max_relative = 1e-9);
            assert_relative_eq!(p.upper, hi, max_relative = 1e-9);
            assert_eq!(p.estimate, k as f64 / n as f64);
        }
    }

    #[test]
    fn closed_forms_at_the_ends() {
        // k = 0: upper = 1 − (α/2)^(1/n); k = n: lower = (α/2)^(1/n).
        for n in [1_u64, 7, 1000, 1_000_000] {
            let p = clopper_pearson(0, n, 0.95);
            assert_eq!(p.lower, 0.0);
            assert_relative_eq!(
                p.upper,
                1.0 - 0.025_f64.powf(1.0 / n as f64),
                max_relative = 1e-9
            );
            let q = clopper_pearson(n, n, 0.95);
            assert_relative_eq!(
                q.lower,
                0.025_f64.powf(1.0 / n as f64),
                max_relative = 1e-12
            );
            assert_eq!(q.upper, 1.0);
        }
        let none = clopper_pearson(0, 0, 0.95);
        assert!(none.estimate.is_nan());
        assert_eq!((none.lower, none.upper), (0.0, 1.0));
    }

    /// The exact coverage of the interval at a true p: the sum of the binomial
    /// probabilities of the k whose interval contains p. Clopper–Pearson's defining
    /// property: never below the confidence.
    #[test]
    fn coverage_is_at_least_the_confidence() {
        for n in [10_u64, 37, 200] {
            let intervals: Vec<Proportion> = (0..=n).map(|k| clopper_pearson(k, n, 0.95)).collect();
            for i in 1..50 {
                let p = i as f64 / 50.0;
                let coverage: f64 = (0..=n)
                    .filter(|&k| {
                        let iv = intervals[k as usize];
                        iv.lower <= p && p <= iv.upper
                    })
                    .map(|k| binomial_pmf(k, n, p))
                    .sum();
                assert!(
                    coverage >= 0.95 - 1e-12,
                    "n {n}, p {p}: coverage {coverage}"
                );
            }
        }
    }

    fn binomial_pmf(k: u64, n: u64, p: f64) -> f64 {
        use crate::stats::special::ln_gamma;
        let (k, n) = (k as f64, n as f64);
        (ln_gamma(n + 1.0) - ln_gamma(k + 1.0) - ln_gamma(n - k + 1.0)
            + k * p.ln()
            + (n - k) * (-p).ln_1p())
        .exp()
    }
}
