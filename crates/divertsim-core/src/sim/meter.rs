//! A run's live simulation count, for a work limit that stops a run on the work it really
//! does rather than on an estimate made before it (an analysis's count depends on its
//! verdicts: a failing check ends a grid point early, a robust map searches only its
//! feasible cells).
//!
//! A caller attaches a shared counter to the threads that do its work (each worker of its
//! pool, when the pool starts it); every [`super::simulate_with`] on such a thread adds
//! one. Threads with no counter attached count nothing. The count changes no result: it is
//! only read by the caller, between pieces of work.

use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

thread_local! {
    static COUNTER: RefCell<Option<Arc<AtomicU64>>> = const { RefCell::new(None) };
}

/// Count this thread's simulations into `counter` from now on (`None`: stop counting).
pub fn attach(counter: Option<Arc<AtomicU64>>) {
    COUNTER.with(|c| *c.borrow_mut() = counter);
}

/// One simulation on this thread (a no-op without an attached counter).
pub(crate) fn count_one() {
    COUNTER.with(|c| {
        if let Some(n) = c.borrow().as_ref() {
            n.fetch_add(1, Ordering::Relaxed);
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Only the simulations of a thread with the counter attached are counted, and
    /// detaching stops the count.
    #[test]
    fn a_meter_counts_the_simulations_of_its_threads_only() {
        let n = Arc::new(AtomicU64::new(0));
        let scenario = crate::model::params::Scenario::paper_machine();
        super::super::simulate_verdict(&scenario);
        assert_eq!(n.load(Ordering::Relaxed), 0);
        attach(Some(n.clone()));
        super::super::simulate_verdict(&scenario);
        super::super::simulate(&scenario);
        std::thread::scope(|s| {
            s.spawn(|| super::super::simulate_verdict(&scenario));
        });
        assert_eq!(
            n.load(Ordering::Relaxed),
            2,
            "another thread is not counted"
        );
        attach(None);
        super::super::simulate_verdict(&scenario);
        assert_eq!(n.load(Ordering::Relaxed), 2);
    }
}
