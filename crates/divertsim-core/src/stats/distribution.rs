//! One-dimensional distributions, sampled by inversion: every draw is Q(u) for one uniform
//! u in (0, 1), so each drawn quantity consumes exactly one random number. Changing one
//! quantity's distribution then leaves every other quantity's draws unchanged (common random
//! numbers across the points of a sweep).

use super::special::{normal_cdf, normal_quantile};

/// A distribution of one real quantity, in the units of that quantity.
#[derive(Debug, Clone, PartialEq)]
pub enum Distribution {
    /// Always `value`.
    Fixed(f64),
    /// Uniform on [min, max].
    Uniform { min: f64, max: f64 },
    /// Normal with mean and standard deviation sd > 0.
    Normal { mean: f64, sd: f64 },
    /// Normal(mean, sd) restricted to [min, max] (min < max).
    TruncatedNormal {
        mean: f64,
        sd: f64,
        min: f64,
        max: f64,
    },
    /// Lognormal: ln x is Normal(ln median, sigma), median > 0, sigma > 0.
    LogNormal { median: f64, sigma: f64 },
    /// One of `values`, with probabilities proportional to `weights` (same length, > 0).
    Discrete { values: Vec<f64>, weights: Vec<f64> },
}

impl Distribution {
    /// Every problem with the parameters, as (parameter, message).
    pub fn problems(&self) -> Vec<(&'static str, String)> {
        let mut p = Vec::new();
        let mut finite = |name: &'static str, v: f64| {
            if !v.is_finite() {
                p.push((name, format!("{v} is not a finite number")));
            }
        };
        match self {
            Distribution::Fixed(v) => finite("value", *v),
            Distribution::Uniform { min, max } => {
                finite("min", *min);
                finite("max", *max);
            }
            Distribution::Normal { mean, sd } => {
                finite("mean", *mean);
                finite("sd", *sd);
            }
            Distribution::TruncatedNormal { mean, sd, min, max } => {
                finite("mean", *mean);
                finite("sd", *sd);
                finite("min", *min);
                finite("max", *max);
            }
            Distribution::LogNormal { median, sigma } => {
                finite("median", *median);
                finite("sigma", *sigma);
            }
            Distribution::Discrete { values, weights } => {
                for v in values {
                    finite("values", *v);
                }
                for w in weights {
                    finite("weights", *w);
                }
            }
        }
        if !p.is_empty() {
            return p;
        }
        match self {
            Distribution::Fixed(_) => {}
            Distribution::Uniform { min, max } => {
                if min > max {
                    p.push((
                        "max",
                        format!("{max} is below min {min}; allowed: max ≥ min"),
                    ));
                }
            }
            Distribution::Normal { sd, .. } | Distribution::TruncatedNormal { sd, .. }
                if *sd <= 0.0 =>
            {
                p.push(("sd", format!("{sd} is out of range; allowed: > 0")));
            }
            Distribution::Normal { .. } => {}
            Distribution::TruncatedNormal { mean, sd, min, max } => {
                if min >= max {
                    p.push((
                        "max",
                        format!("{max} is not above min {min}; allowed: max > min"),
                    ));
                } else {
                    let (a, b) = ((min - mean) / sd, (max - mean) / sd);
                    if normal_cdf(b) - normal_cdf(a) < 1e-12
                        && normal_cdf(-a) - normal_cdf(-b) < 1e-12
                    {
                        p.push((
                            "min",
                            format!(
                                "[{min}, {max}] lies more than 7 sd from the mean {mean}: \
                                 allowed: an interval the normal gives weight to"
                            ),
                        ));
                    }
                }
            }
            Distribution::LogNormal { median, sigma } => {
                if *median <= 0.0 {
                    p.push(("median", format!("{median} is out of range; allowed: > 0")));
                }
                if *sigma <= 0.0 {
                    p.push(("sigma", format!("{sigma} is out of range; allowed: > 0")));
                }
            }
            Distribution::Discrete { values, weights } => {
                if values.is_empty() {
                    p.push(("values", "is empty; allowed: 1 or more values".to_string()));
                }
                if weights.len() != values.len() {
                    p.push((
                        "weights",
                        format!(
                            "has {} entries for {} values; allowed: one weight per value",
                            weights.len(),
                            values.len()
                        ),
                    ));
                } else if weights.iter().any(|w| *w < 0.0) || weights.iter().sum::<f64>() <= 0.0 {
                    p.push((
                        "weights",
                        "allowed: weights ≥ 0 with a positive sum".to_string(),
                    ));
                }
            }
        }
        p
    }

    /// The quantile Q(u) for u in (0, 1): the value a draw with uniform u takes.
    pub fn quantile(&self, u: f64) -> f64 {
        match self {
            Distribution::Fixed(v) => *v,
            Distribution::Uniform { min, max } => min + (max - min) * u,
            Distribution::Normal { mean, sd } => mean + sd * normal_quantile(u),
            Distribution::TruncatedNormal { mean, sd, min, max } => {
                // Inversion on whichever side keeps the tail probabilities accurate.
                let (a, b) = ((min - mean) / sd, (max - mean) / sd);
                let z = if a > 0.0 {
                    // Both ends above the mean: invert the upper tail Φ(−z).
                    let (qa, qb) = (normal_cdf(-a), normal_cdf(-b));
                    -normal_quantile(qa - u * (qa - qb))
                } else {
                    let (pa, pb) = (normal_cdf(a), normal_cdf(b));
                    normal_quantile(pa + u * (pb - pa))
                };
                (mean + sd * z).clamp(*min, *max)
            }
            Distribution::LogNormal { median, sigma } => {
                median * (sigma * normal_quantile(u)).exp()
            }
            Distribution::Discrete { values, weights } => {
                let total: f64 = weights.iter().sum();
                let target = u * total;
                let mut acc = 0.0;
                for (v, w) in values.iter().zip(weights) {
                    acc += w;
                    if target < acc {
                        return *v;
                    }
                }
                // u × total rounded up to the total: the last value with weight.
                values
                    .iter()
                    .zip(weights)
                    .rev()
                    .find(|(_, w)| **w > 0.0)
                    .map(|(v, _)| *v)
                    .unwrap_or(f64::NAN)
            }
        }
    }

    /// The smallest and largest value a draw can take (±∞ for unbounded tails).
    pub fn support(&self) -> (f64, f64) {
        match self {
            Distribution::Fixed(v) => (*v, *v),
            Distribution::Uniform { min, max } | Distribution::TruncatedNormal { min, max, .. } => {
                (*min, *max)
            }
            Distribution::Normal { .. } => (f64::NEG_INFINITY, f64::INFINITY),
            Distribution::LogNormal { .. } => (0.0, f64::INFINITY),
            Distribution::Discrete { values, weights } => values
                .iter()
                .zip(weights)
                .filter(|(_, w)| **w > 0.0)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (v, _)| {
                    (lo.min(*v), hi.max(*v))
                }),
        }
    }

    /// The distribution of k·X for k > 0 (a change of unit, e.g. degrees to radians).
    pub fn scaled(&self, k: f64) -> Distribution {
        match self {
            Distribution::Fixed(v) => Distribution::Fixed(v * k),
            Distribution::Uniform { min, max } => Distribution::Uniform {
                min: min * k,
                max: max * k,
            },
            Distribution::Normal { mean, sd } => Distribution::Normal {
                mean: mean * k,
                sd: sd * k,
            },
            Distribution::TruncatedNormal { mean, sd, min, max } => Distribution::TruncatedNormal {
                mean: mean * k,
                sd: sd * k,
                min: min * k,
                max: max * k,
            },
            Distribution::LogNormal { median, sigma } => Distribution::LogNormal {
                median: median * k,
                sigma: *sigma,
            },
            Distribution::Discrete { values, weights } => Distribution::Discrete {
                values: values.iter().map(|v| v * k).collect(),
                weights: weights.clone(),
            },
        }
    }
}

/// A uniform in (0, 1) from 64 random bits: the top 52 bits, offset by half a step so that
/// neither end is reached (Φ⁻¹ stays finite) and every value is exact.
pub fn open_unit(bits: u64) -> f64 {
    ((bits >> 12) as f64 + 0.5) * (1.0 / (1u64 << 52) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Many draws' mean and standard deviation: the uniforms on a fine regular grid (a
    /// quadrature of the quantile function), so the check is deterministic.
    fn moments(d: &Distribution) -> (f64, f64) {
        let n = 200_000;
        let xs: Vec<f64> = (0..n)
            .map(|i| d.quantile((i as f64 + 0.5) / n as f64))
            .collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        (mean, var.sqrt())
    }

    #[test]
    fn moments_match_closed_forms() {
        let (m, s) = moments(&Distribution::Uniform { min: 2.0, max: 5.0 });
        assert_relative_eq!(m, 3.5, max_relative = 1e-9);
        assert_relative_eq!(s, 3.0 / 12f64.sqrt(), max_relative = 1e-6);
        let (m, s) = moments(&Distribution::Normal { mean: 1.0, sd: 0.2 });
        assert_relative_eq!(m, 1.0, max_relative = 1e-9);
        assert_relative_eq!(s, 0.2, max_relative = 1e-3);
        // Lognormal: mean = median e^{σ²/2}.
        let (m, _) = moments(&Distribution::LogNormal {
            median: 2.0,
            sigma: 0.3,
        });
        assert_relative_eq!(m, 2.0 * (0.045f64).exp(), max_relative = 1e-4);
        // Truncated to [mean, ∞)-like half: mean + sd √(2/π) for the half normal.
        let (m, _) = moments(&Distribution::TruncatedNormal {
            mean: 0.0,
            sd: 1.0,
            min: 0.0,
            max: 40.0,
        });
        assert_relative_eq!(m, (2.0 / std::f64::consts::PI).sqrt(), max_relative = 1e-4);
        // Far in the upper tail: still inside and ordered.
        let t = Distribution::TruncatedNormal {
            mean: 0.0,
            sd: 1.0,
            min: 6.0,
            max: 7.0,
        };
        let (lo, hi) = (t.quantile(1e-9), t.quantile(1.0 - 1e-9));
        assert!(
            (6.0..7.0).contains(&lo) && lo < hi && hi <= 7.0,
            "{lo} {hi}"
        );
    }

    #[test]
    fn discrete_follows_its_weights() {
        let d = Distribution::Discrete {
            values: vec![1.0, 2.0, 3.0],
            weights: vec![1.0, 0.0, 3.0],
        };
        let n = 4000;
        let threes = (0..n)
            .filter(|i| d.quantile((*i as f64 + 0.5) / n as f64) == 3.0)
            .count();
        assert_eq!(threes, 3000);
        assert_eq!(d.quantile(1.0 - 1e-17), 3.0);
        assert_eq!(d.support(), (1.0, 3.0));
    }

    #[test]
    fn bad_parameters_are_named() {
        let names = |d: Distribution| d.problems().into_iter().map(|(k, _)| k).collect::<Vec<_>>();
        assert_eq!(names(Distribution::Normal { mean: 0.0, sd: 0.0 }), ["sd"]);
        assert_eq!(names(Distribution::Uniform { min: 1.0, max: 0.0 }), ["max"]);
        assert_eq!(
            names(Distribution::LogNormal {
                median: -1.0,
                sigma: f64::NAN
            }),
            ["sigma"]
        );
        assert_eq!(
            names(Distribution::Discrete {
                values: vec![1.0],
                weights: vec![1.0, 2.0]
            }),
            ["weights"]
        );
        assert!(Distribution::Fixed(3.0).problems().is_empty());
    }

    #[test]
    fn open_unit_never_reaches_the_ends() {
        assert!(open_unit(0) > 0.0);
        assert!(open_unit(u64::MAX) < 1.0);
        assert!(normal_quantile(open_unit(u64::MAX)).is_finite());
    }
}
