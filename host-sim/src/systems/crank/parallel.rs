//! Independent simulations on several threads (rayon), the results in the items' order.
//!
//! The crank's estimators and studies run many simulations that share nothing; their callers
//! name a thread count (`--threads`, [`super::estimate::ukf::UkfOptions::threads`]), so the work
//! runs in a rayon pool of that size rather than the global one. Each result is computed by the
//! same code whichever thread takes it, and `collect` keeps the items' order, so the results do
//! not depend on the thread count.

use rayon::prelude::*;

/// `f(k, item)` for every item, on `threads` threads (at least one), in the items' order.
pub(crate) fn map_in_order<T: Sync, R: Send>(threads: usize, items: &[T], f: impl Fn(usize, &T) -> R + Sync) -> Vec<R> {
    let run = || items.par_iter().enumerate().map(|(k, item)| f(k, item)).collect();
    match rayon::ThreadPoolBuilder::new().num_threads(threads.max(1)).build() {
        Ok(pool) => pool.install(run),
        // No pool of that size (threads could not be spawned): the global pool.
        Err(_) => run(),
    }
}
