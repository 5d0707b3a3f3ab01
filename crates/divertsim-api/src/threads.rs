//! The worker pool of a computation: every analysis runs its parallel parts with rayon,
//! order-preserving, so the number of threads changes the time, never the result.

use crate::config::Problem;
use divertsim_core::sim::meter;
use std::sync::atomic::AtomicU64;
use std::sync::Arc;

/// The most worker threads a run may ask for (the CLI's `--threads`, Python's `threads`):
/// beyond it a pool costs memory and start-up time and gains nothing.
pub const MAX_THREADS: usize = 1024;

/// The problem with a requested thread count (named `key`), if any: `None` is one per core.
pub fn check(threads: Option<usize>, key: &str) -> Option<Problem> {
    match threads {
        Some(n) if !(1..=MAX_THREADS).contains(&n) => Some(Problem::new(
            key,
            format!("{n} is out of range; allowed: 1 to {MAX_THREADS} (or none: one per core)"),
        )),
        _ => None,
    }
}

/// Run `f` on a pool of `threads` workers (default: rayon's global pool, one per core).
pub fn with_threads<R: Send>(threads: Option<usize>, f: impl FnOnce() -> R + Send) -> R {
    match threads {
        None => f(),
        Some(n) => match rayon::ThreadPoolBuilder::new()
            .num_threads(n.clamp(1, MAX_THREADS))
            .build()
        {
            Ok(pool) => pool.install(f),
            // Could not start the workers: the result does not depend on the count anyway.
            Err(_) => f(),
        },
    }
}

/// Run `f` on a pool of `threads` workers (`None`: one per core) whose simulations are
/// counted into `count` (see [`divertsim_core::sim::meter`]): a work limit reads it between
/// pieces of work. The pool is the run's own, so that no other run's work is counted.
pub fn with_counted_threads<R: Send>(
    threads: Option<usize>,
    count: &Arc<AtomicU64>,
    f: impl FnOnce() -> R + Send,
) -> R {
    let attached = count.clone();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.map_or(0, |n| n.clamp(1, MAX_THREADS)))
        .start_handler(move |_| meter::attach(Some(attached.clone())))
        .exit_handler(|_| meter::attach(None))
        .build();
    match pool {
        Ok(pool) => pool.install(f),
        // Could not start the workers: run here, counted here.
        Err(_) => counted_here(count, f),
    }
}

/// Run `f` on this thread with its simulations counted into `count`, and detach the count
/// again even when `f` unwinds (a caller's stop), so that this thread's later runs are not
/// counted.
fn counted_here<R>(count: &Arc<AtomicU64>, f: impl FnOnce() -> R) -> R {
    struct Detach;
    impl Drop for Detach {
        fn drop(&mut self) {
            meter::attach(None);
        }
    }
    meter::attach(Some(count.clone()));
    let _detach = Detach;
    f()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regression: a run counted on the caller's thread (no pool could start) that unwound
    /// left the count attached, and the thread's later runs were counted into it.
    #[test]
    fn a_count_on_the_callers_thread_is_detached_when_its_run_unwinds() {
        let count = Arc::new(AtomicU64::new(0));
        let s = divertsim_core::model::params::Scenario::paper_default();
        counted_here(&count, || divertsim_core::sim::simulate_verdict(&s));
        assert_eq!(count.load(std::sync::atomic::Ordering::Relaxed), 1);
        let unwound = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            counted_here(&count, || -> () { panic!("stopped") })
        }));
        assert!(unwound.is_err());
        divertsim_core::sim::simulate_verdict(&s);
        assert_eq!(count.load(std::sync::atomic::Ordering::Relaxed), 1);
    }

    #[test]
    fn thread_counts_outside_one_to_max_are_problems_naming_the_key() {
        assert!(check(None, "threads").is_none());
        assert!(check(Some(1), "threads").is_none());
        assert!(check(Some(MAX_THREADS), "threads").is_none());
        let p = check(Some(0), "threads").unwrap();
        assert_eq!(p.key, "threads");
        assert!(p.message.contains("1 to 1024"), "{}", p.message);
        assert!(check(Some(1_000_000), "threads").is_some());
    }
}
