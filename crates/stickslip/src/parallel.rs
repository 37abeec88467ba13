//! One parallel map for the crate's independent runs (sweep points, stress cells, reproduce's
//! runs, noise realisations): rayon on a pool of the size asked for (`--threads`), results in
//! index order. Each item is computed alone from its own inputs, so the results do not depend
//! on the number of threads or on the scheduling.

use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// `f(0)`, …, `f(count − 1)` on `threads` threads, in index order; `progress(done, count)`
/// after each item.
pub fn map<R: Send>(
    count: usize,
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
    f: impl Fn(usize) -> R + Sync,
) -> Vec<R> {
    match try_map(count, threads, progress, |i| Ok::<R, std::convert::Infallible>(f(i))) {
        Ok(results) => results,
        Err(never) => match never {},
    }
}

/// [`map`] for fallible items: on failures, the error of the lowest failing index (the same
/// whatever the scheduling: an item above a known failure is skipped, every item below it
/// runs).
pub fn try_map<R: Send, E: Send>(
    count: usize,
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
    f: impl Fn(usize) -> Result<R, E> + Sync,
) -> Result<Vec<R>, E> {
    let done = AtomicUsize::new(0);
    let first_failure = AtomicUsize::new(usize::MAX);
    let one = |i: usize| -> Option<Result<R, E>> {
        if i > first_failure.load(Ordering::Relaxed) {
            return None;
        }
        let result = f(i);
        if result.is_err() {
            first_failure.fetch_min(i, Ordering::Relaxed);
        }
        progress(done.fetch_add(1, Ordering::Relaxed) + 1, count);
        Some(result)
    };
    let results: Vec<Option<Result<R, E>>> =
        match rayon::ThreadPoolBuilder::new().num_threads(threads.max(1)).build() {
            Ok(pool) => pool.install(|| (0..count).into_par_iter().map(&one).collect()),
            // No threads to be had: the same items, in order, on this one.
            Err(_) => (0..count).map(&one).collect(),
        };
    // Skipped items all lie above the lowest failure, so the first error in index order is it.
    results.into_iter().flatten().collect()
}
