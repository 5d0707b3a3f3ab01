//! The arm's loads over a study's strokes, as every study counts them (reliability's shards,
//! the line's segments): the strokes, the spectra of their peak drive torques and of the
//! strikes' angular impulses on the arm, and the stroke with the largest peak torque with
//! what runs it again (docs/model.md §12b–§12c).
//!
//! The spectra's bins are fixed by the first pieces with a load ([`Spectrum::count_into`]),
//! the pieces folded in order, so the counts are the same for any number of threads.

use super::histogram::{per_million_strokes, Spectrum};

/// The loads of a study's strokes; `R` is what runs the largest stroke again (a sample, a
/// line run).
#[derive(Debug, Clone, PartialEq)]
pub struct StrokeLoads<R> {
    /// Strokes counted (each with a peak drive torque).
    pub strokes: u64,
    /// max |M_d| of each stroke \[N·m].
    pub torque_spectrum: Option<Spectrum>,
    /// Angular impulse of each strike on the arm \[N·m·s].
    pub strike_spectrum: Option<Spectrum>,
    /// The largest peak drive torque \[N·m] and its stroke (the first of equal peaks).
    pub largest: Option<(f64, R)>,
}

impl<R> Default for StrokeLoads<R> {
    fn default() -> Self {
        StrokeLoads {
            strokes: 0,
            torque_spectrum: None,
            strike_spectrum: None,
            largest: None,
        }
    }
}

impl<R> StrokeLoads<R> {
    /// Count a piece's strokes by their peak drive torques, and its strikes' impulses.
    pub fn count(
        &mut self,
        peaks: impl Iterator<Item = f64> + Clone,
        strikes: impl Iterator<Item = f64> + Clone,
    ) {
        self.strokes += peaks.clone().count() as u64;
        Spectrum::count_into(&mut self.torque_spectrum, peaks);
        Spectrum::count_into(&mut self.strike_spectrum, strikes);
    }

    /// Offer a stroke with peak drive torque `peak`: it becomes the largest when its peak
    /// exceeds the largest so far (`run` is called only then).
    pub fn offer(&mut self, peak: f64, run: impl FnOnce() -> R) {
        let largest = self.largest.as_ref().map_or(f64::NEG_INFINITY, |(p, _)| *p);
        if peak > largest {
            self.largest = Some((peak, run()));
        }
    }

    /// `count` as a number per 10⁶ strokes (0 with no stroke).
    pub fn per_million(&self, count: u64) -> f64 {
        per_million_strokes(count, self.strokes)
    }

    /// The largest strike's angular impulse on an arm \[N·m·s] (0 with none).
    pub fn largest_strike(&self) -> f64 {
        self.strike_spectrum.as_ref().map_or(0.0, |sp| sp.max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Strokes and strikes counted in order; the largest stroke is the first of the largest
    /// peaks, and its run is made only when it is kept.
    #[test]
    fn stroke_loads_count_strokes_and_keep_the_first_largest() {
        let mut l = StrokeLoads::<usize>::default();
        l.count([3.0, 5.0].into_iter(), [0.1, 0.2, 0.05].into_iter());
        l.count([5.0, 1.0, 2.0].into_iter(), std::iter::empty());
        assert_eq!(l.strokes, 5);
        assert_eq!(l.torque_spectrum.as_ref().unwrap().total(), 5);
        assert_eq!(l.strike_spectrum.as_ref().unwrap().total(), 3);
        assert_eq!(l.largest_strike(), 0.2);
        let mut made = 0;
        for (i, peak) in [3.0, 5.0, 5.0, 1.0].into_iter().enumerate() {
            l.offer(peak, || {
                made += 1;
                i
            });
        }
        assert_eq!(l.largest, Some((5.0, 1)));
        assert_eq!(made, 2);
        assert_eq!(l.per_million(1), 2e5);
        assert_eq!(StrokeLoads::<()>::default().per_million(3), 0.0);
    }
}
