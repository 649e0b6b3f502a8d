//! Small parallel helpers shared by the kernels.

use rayon::prelude::*;

/// Items per rayon task in scans: large enough that scheduling costs nothing.
const SCAN_CHUNK: usize = 1 << 14;

/// Runs `work` from a worker of the pool it belongs in, entered once, so that its parallel
/// loops run there directly: a caller outside the pool would otherwise hand each loop over
/// and wait for it.
///
/// With a one-thread global pool even the single hand-over and the wake-ups around it cost
/// a large share of one small transform (research/performance.md). The calling thread is then
/// made, once, the worker of a one-thread pool of its own (rayon's `use_current_thread`)
/// and runs the work itself. Every later parallel loop it calls runs in place as well,
/// which is what the one-thread global pool would have done on its one worker.
pub fn in_pool<R: Send>(work: impl FnOnce() -> R + Send) -> R {
    if rayon::current_thread_index().is_some() || (rayon::current_num_threads() == 1 && adopt_calling_thread()) {
        work()
    } else {
        rayon::scope(|_| work())
    }
}

/// Makes the calling thread the worker of a one-thread pool of its own; false where that
/// cannot be done.
fn adopt_calling_thread() -> bool {
    thread_local! {
        // Kept for the thread's life: the thread stays the pool's worker until it exits.
        static OWN_POOL: Option<rayon::ThreadPool> =
            rayon::ThreadPoolBuilder::new().num_threads(1).use_current_thread().build().ok();
    }
    OWN_POOL.with(|pool| pool.is_some()) && rayon::current_thread_index().is_some()
}

/// Index of the first item for which `bad` holds, searched in parallel.
///
/// Rayon's `par_iter().position_first` splits down to single items and pays for a task
/// per item (research/performance.md); scanning fixed-size chunks costs what a sequential loop
/// does, per core.
pub fn position_first<T: Sync>(items: &[T], bad: impl Fn(&T) -> bool + Sync) -> Option<usize> {
    items
        .par_chunks(SCAN_CHUNK)
        .enumerate()
        .find_map_first(|(chunk_index, chunk)| chunk.iter().position(&bad).map(|i| chunk_index * SCAN_CHUNK + i))
}

#[cfg(test)]
mod tests {
    #[test]
    fn finds_the_first_match_across_chunks() {
        let mut items = vec![0u8; 100_000];
        assert_eq!(super::position_first(&items, |&x| x == 1), None);
        items[70_000] = 1;
        items[90_000] = 1;
        assert_eq!(super::position_first(&items, |&x| x == 1), Some(70_000));
    }
}
