//! The worker pool of a computation: every analysis runs its parallel parts with rayon,
//! order-preserving, so the number of threads changes the time, never the result.

/// Run `f` on a pool of `threads` workers (default: rayon's global pool, one per core).
pub fn with_threads<R: Send>(threads: Option<usize>, f: impl FnOnce() -> R + Send) -> R {
    match threads {
        None => f(),
        Some(n) => match rayon::ThreadPoolBuilder::new().num_threads(n).build() {
            Ok(pool) => pool.install(f),
            // Could not start the workers: the result does not depend on the count anyway.
            Err(_) => f(),
        },
    }
}
