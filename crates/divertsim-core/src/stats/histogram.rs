//! Histograms of Monte Carlo studies: [`Bins`] on fixed edges (equal width or equal count)
//! with a sample's failed and overloaded flags counted per bin, and [`Spectrum`], a load
//! spectrum whose bins the first batch fixes, with the loads above its ceiling kept apart.
//! Both fold batches in order, so a study's result does not depend on how it was cut.
//! Numerics only: the values are whatever a study counts (an input, a load).

/// Bins on fixed edges e_0 < e_1 < … < e_n; values outside [e_0, e_n] fall in the end bins.
#[derive(Debug, Clone, PartialEq)]
pub struct Bins {
    /// The n + 1 edges, increasing.
    pub edges: Vec<f64>,
    /// Samples per bin.
    pub count: Vec<u64>,
    /// Failures per bin.
    pub failed: Vec<u64>,
    /// Overloads per bin.
    pub overloaded: Vec<u64>,
}

impl Bins {
    fn with_edges(edges: Vec<f64>) -> Bins {
        let n = edges.len() - 1;
        Bins {
            edges,
            count: vec![0; n],
            failed: vec![0; n],
            overloaded: vec![0; n],
        }
    }

    /// n equal bins over the range of the finite values; None if they are all equal.
    pub fn equal_width(values: impl Iterator<Item = f64>, n: usize) -> Option<Bins> {
        let (lo, hi) = values
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        (lo < hi).then(|| {
            let n = n.max(1);
            let mut edges: Vec<f64> = (0..n)
                .map(|k| lo + (hi - lo) * k as f64 / n as f64)
                .collect();
            edges.push(hi);
            Bins::with_edges(edges)
        })
    }

    /// Up to n bins of about equal counts: edges at the k/n quantiles of the finite values
    /// (repeated edges merged, so a discrete quantity gets a bin per value range); None if
    /// the values are all equal. Equal counts keep every bin's interval informative for a
    /// skewed quantity (a lognormal mass would put nearly all samples in one equal-width
    /// bin).
    pub fn equal_count(values: impl Iterator<Item = f64>, n: usize) -> Option<Bins> {
        let mut v: Vec<f64> = values.filter(|v| v.is_finite()).collect();
        v.sort_by(f64::total_cmp);
        let (&lo, &hi) = (v.first()?, v.last()?);
        if lo >= hi {
            return None;
        }
        let n = n.max(1);
        let mut edges = vec![lo];
        for k in 1..n {
            let e = v[k * (v.len() - 1) / n];
            if e > *edges.last().unwrap_or(&lo) && e < hi {
                edges.push(e);
            }
        }
        edges.push(hi);
        Some(Bins::with_edges(edges))
    }

    /// The bin of x (NaN in the first).
    pub fn index(&self, x: f64) -> usize {
        let n = self.count.len();
        // The number of inner edges at or below x.
        let k = self.edges[1..n].partition_point(|&e| e <= x);
        k.min(n - 1)
    }

    /// The edges of bin k.
    pub fn edges(&self, k: usize) -> (f64, f64) {
        (self.edges[k], self.edges[k + 1])
    }

    /// The first and last edge.
    pub fn range(&self) -> (f64, f64) {
        (self.edges[0], self.edges[self.edges.len() - 1])
    }

    /// Count a sample at x, failed and/or overloaded.
    pub fn add(&mut self, x: f64, failed: bool, overloaded: bool) {
        let k = self.index(x);
        self.count[k] += 1;
        self.failed[k] += u64::from(failed);
        self.overloaded[k] += u64::from(overloaded);
    }
}

/// A load spectrum: counts of a load in equal bins from 0 up to a round ceiling fixed by
/// the first shard (1.5 × its largest value, rounded up to 1, 2, 2.5 or 5 × 10ᵏ), with the
/// loads above the ceiling counted apart, so the largest ones are never folded into a bin
/// that hides them.
#[derive(Debug, Clone, PartialEq)]
pub struct Spectrum {
    /// The bins' upper edges; the first bin starts at 0.
    pub upper: Vec<f64>,
    /// Loads per bin.
    pub count: Vec<u64>,
    /// Loads above the last edge.
    pub above: u64,
    /// The largest load seen.
    pub max: f64,
}

/// Bins of a load spectrum.
pub const SPECTRUM_BINS: usize = 40;

/// `count` per 10⁶ of `strokes` (0 without strokes): a load spectrum's unit.
pub fn per_million_strokes(count: u64, strokes: u64) -> f64 {
    if strokes == 0 {
        0.0
    } else {
        count as f64 * 1e6 / strokes as f64
    }
}

/// The smallest of 1, 2, 2.5, 5 × 10ᵏ at or above x > 0.
pub fn round_up(x: f64) -> f64 {
    let k = x.log10().floor();
    let base = 10f64.powf(k);
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * base)
        .find(|&v| v >= x * (1.0 - 1e-12))
        .unwrap_or(10.0 * base)
}

impl Spectrum {
    /// Bins for loads like `first` (None if none is positive and finite).
    pub fn for_values(first: impl Iterator<Item = f64>) -> Option<Spectrum> {
        let max = first.filter(|v| v.is_finite()).fold(0.0, f64::max);
        (max > 0.0).then(|| {
            let ceiling = round_up(1.5 * max);
            Spectrum {
                upper: (1..=SPECTRUM_BINS)
                    .map(|k| ceiling * k as f64 / SPECTRUM_BINS as f64)
                    .collect(),
                count: vec![0; SPECTRUM_BINS],
                above: 0,
                max: 0.0,
            }
        })
    }

    /// Count `values` into `slot`, fixing its bins from them first while it has none: the
    /// first shard (or line segment) with a load fixes them, the batches coming in order.
    pub fn count_into(slot: &mut Option<Spectrum>, values: impl Iterator<Item = f64> + Clone) {
        if slot.is_none() {
            *slot = Spectrum::for_values(values.clone());
        }
        if let Some(sp) = slot {
            values.for_each(|x| sp.add(x));
        }
    }

    /// Count a load (NaN ignored).
    pub fn add(&mut self, x: f64) {
        if !x.is_finite() {
            return;
        }
        self.max = self.max.max(x);
        match self.upper.iter().position(|&e| x <= e) {
            Some(k) => self.count[k] += 1,
            None => self.above += 1,
        }
    }

    /// The lower edge of bin k.
    pub fn lower(&self, k: usize) -> f64 {
        if k == 0 {
            0.0
        } else {
            self.upper[k - 1]
        }
    }

    /// Loads counted in all.
    pub fn total(&self) -> u64 {
        self.count.iter().sum::<u64>() + self.above
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spectra_round_their_ceiling_and_count_what_lies_above() {
        assert_eq!(round_up(0.7), 1.0);
        assert_eq!(round_up(1.2), 2.0);
        assert_eq!(round_up(2.2), 2.5);
        assert_eq!(round_up(36.0), 50.0);
        assert_eq!(round_up(50.0), 50.0);
        let mut sp = Spectrum::for_values([1.0, 3.0, f64::NAN].into_iter()).unwrap();
        assert_eq!(*sp.upper.last().unwrap(), 5.0);
        for x in [0.0, 0.125, 0.13, 5.0, 7.0, f64::NAN] {
            sp.add(x);
        }
        assert_eq!(
            (sp.count[0], sp.count[1], sp.above, sp.total()),
            (2, 1, 1, 5)
        );
        assert_eq!(sp.max, 7.0);
        assert!(Spectrum::for_values([0.0, f64::NAN].into_iter()).is_none());
    }

    #[test]
    fn bins_split_skewed_and_discrete_values_sensibly() {
        // A skewed sample: equal counts keep the bins populated.
        let skewed: Vec<f64> = (1..=1000).map(|i| (i as f64 / 100.0).exp()).collect();
        let b = Bins::equal_count(skewed.iter().copied(), 10).unwrap();
        assert_eq!(b.count.len(), 10);
        let mut b2 = b.clone();
        for &x in &skewed {
            b2.add(x, false, false);
        }
        assert!(
            b2.count.iter().all(|&c| (90..=110).contains(&c)),
            "{:?}",
            b2.count
        );
        // Outside the edges: the end bins; NaN: the first.
        assert_eq!(b.index(-1.0), 0);
        assert_eq!(b.index(1e9), 9);
        // Three values: merged edges, at most three bins, each value in its own.
        let d = Bins::equal_count([1.0, 2.0, 3.0].repeat(50).into_iter(), 10).unwrap();
        assert!(d.count.len() <= 3);
        assert_ne!(d.index(1.0), d.index(3.0));
        assert!(Bins::equal_count([2.0; 5].into_iter(), 4).is_none());
        let w = Bins::equal_width([0.0, 4.0].into_iter(), 4).unwrap();
        assert_eq!(w.edges, [0.0, 1.0, 2.0, 3.0, 4.0]);
        assert_eq!((w.index(1.0), w.index(0.99)), (1, 0));
    }
}
