//! Search for the last index at which a monotone predicate holds.
//!
//! Grid and road node times are `t_0 + n h` in floating point: they never
//! decrease with `n`, but far from `t_0` (or with `h` below the spacing of
//! floating-point numbers there) many consecutive indices share one time.
//! A scan one index at a time from an estimate can then run for as many
//! indices as share that time; [`last_index_where`] needs at most about
//! 2 × 64 evaluations whatever the predicate, and two when the estimate is
//! right.

/// The largest `j` in `lo..=hi` with `holds(j)`, where `holds` is true on a
/// prefix of `lo..=hi` and false after it; `lo` when `holds` is false
/// everywhere (`holds(lo)` is never evaluated). The search starts at
/// `guess` (clamped to `lo..=hi`) and doubles its stride away from it, then
/// bisects. `lo <= hi` is required.
pub(crate) fn last_index_where(lo: u64, hi: u64, guess: u64, holds: impl Fn(u64) -> bool) -> u64 {
    debug_assert!(lo <= hi);
    let (lo, hi) = (lo as u128, hi as u128);
    let guess = (guess as u128).clamp(lo, hi);
    let holds = |j: u128| holds(j as u64);
    // Invariant: `below` is `lo` or holds; `above` is `hi + 1` or does not
    // hold; below < above.
    let (mut below, mut above);
    if guess == lo || holds(guess) {
        below = guess;
        let mut stride = 1;
        above = loop {
            let probe = below + stride;
            if probe > hi {
                break hi + 1;
            }
            if !holds(probe) {
                break probe;
            }
            below = probe;
            stride *= 2;
        };
    } else {
        above = guess;
        let mut stride = 1;
        below = loop {
            let probe = above.saturating_sub(stride).max(lo);
            if probe == lo || holds(probe) {
                break probe;
            }
            above = probe;
            stride *= 2;
        };
    }
    while above - below > 1 {
        let middle = below + (above - below) / 2;
        if holds(middle) {
            below = middle;
        } else {
            above = middle;
        }
    }
    below as u64
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    #[test]
    fn finds_the_boundary_from_any_guess() {
        for boundary in [0u64, 1, 2, 7, 1000, u64::MAX - 1, u64::MAX] {
            for guess in [0, 1, 5, 999, 1000, 1001, 1 << 40, u64::MAX] {
                let found = last_index_where(0, u64::MAX, guess, |j| j <= boundary);
                assert_eq!(found, boundary, "boundary {boundary}, guess {guess}");
            }
        }
        // Nothing holds: lo. Everything holds: hi.
        assert_eq!(last_index_where(10, 20, 15, |_| false), 10);
        assert_eq!(last_index_where(10, 20, 15, |_| true), 20);
        assert_eq!(last_index_where(10, 20, 0, |_| true), 20);
    }

    #[test]
    fn evaluations_are_few() {
        let count = Cell::new(0u32);
        let count = &count;
        let counted = |boundary: u64| {
            move |j: u64| {
                count.set(count.get() + 1);
                j <= boundary
            }
        };
        assert_eq!(last_index_where(0, u64::MAX, 500, counted(500)), 500);
        assert_eq!(count.get(), 2);
        count.set(0);
        assert_eq!(
            last_index_where(0, u64::MAX, 0, counted(u64::MAX - 3)),
            u64::MAX - 3
        );
        assert!(count.get() <= 130, "{}", count.get());
        count.set(0);
        assert_eq!(last_index_where(0, u64::MAX, u64::MAX, counted(3)), 3);
        assert!(count.get() <= 130, "{}", count.get());
    }
}
