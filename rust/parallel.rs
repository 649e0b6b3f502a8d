//! Small parallel helpers shared by the kernels.

use rayon::prelude::*;

/// Items per rayon task in scans: large enough that scheduling costs nothing.
const SCAN_CHUNK: usize = 1 << 14;

/// Index of the first item for which `bad` holds, searched in parallel.
///
/// Rayon's `par_iter().position_first` splits down to single items and costs ~10 ns per
/// item; scanning fixed-size chunks costs what a sequential loop does, per core.
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
