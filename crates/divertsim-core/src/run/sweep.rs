//! Parallel sweeps: evaluate a function over a list of inputs on rayon's workers, keeping the
//! input order, so the results are bitwise identical for any number of threads.

use rayon::prelude::*;

/// Called once per finished item (from any worker thread), e.g. to advance a progress bar.
pub type Progress<'a> = &'a (dyn Fn() + Sync);

/// A progress callback that does nothing.
pub fn no_progress() {}

/// Halvings that narrow a bracket of width `step` to `tolerance`, plus the last evaluation:
/// the cost of one bisected root, for the analyses' work estimates.
pub fn bisection_steps(step: f64, tolerance: f64) -> usize {
    (step / tolerance).log2().ceil().clamp(0.0, 200.0) as usize + 1
}

/// Points of a scan of [lo, hi] at spacing at most `step`, both ends included.
pub fn scan_points(lo: f64, hi: f64, step: f64) -> usize {
    ((hi - lo) / step).ceil().clamp(1.0, 1e9) as usize + 1
}

/// `f` applied to every item, in parallel, results in input order.
///
/// Determinism: each result depends only on its own item, and `collect` on an indexed
/// parallel iterator preserves order, so the output does not depend on scheduling.
///
/// An unwinding item (a caller's stop, raised from its progress tick) ends the map at once:
/// the items not yet started are skipped instead of each running before it meets the stop.
pub fn par_map<T, R, F>(items: &[T], progress: Progress<'_>, f: F) -> Vec<R>
where
    T: Sync,
    R: Send,
    F: Fn(&T) -> R + Sync,
{
    items
        .par_iter()
        .panic_fuse()
        .map(|item| {
            let r = f(item);
            progress();
            r
        })
        .collect()
}

/// Runs `f` on a one-thread rayon pool and on a four-thread pool, returning both results:
/// the tests' check that a result does not depend on the number of threads.
#[cfg(test)]
pub(crate) fn one_and_many_threads<T: Send>(f: impl Fn() -> T + Sync + Send) -> (T, T) {
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    };
    (pool(1).install(&f), pool(4).install(&f))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    #[test]
    fn keeps_order_and_counts_progress() {
        let items: Vec<u64> = (0..1000).collect();
        let done = AtomicUsize::new(0);
        let tick = || {
            done.fetch_add(1, Ordering::Relaxed);
        };
        let out = par_map(&items, &tick, |&i| i * i);
        assert_eq!(out, items.iter().map(|i| i * i).collect::<Vec<_>>());
        assert_eq!(done.load(Ordering::Relaxed), 1000);
    }

    #[test]
    fn same_result_on_one_thread() {
        let items: Vec<f64> = (0..200).map(|i| i as f64 * 0.1).collect();
        let f = |x: &f64| (x.sin() * 1e3).exp().ln();
        let (one, many) = one_and_many_threads(|| par_map(&items, &no_progress, f));
        assert_eq!(
            many.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            one.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
    }
}
