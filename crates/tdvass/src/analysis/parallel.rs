//! Work spread over the machine's cores: the stability map's columns.

use crate::error::{Error, Result};

/// `f` of every item, in order, computed on all available cores (std
/// scoped threads taking the next item as they finish one); the first
/// error in item order, or a worker's panic as an error of `what`.
pub(super) fn in_parallel<T: Send>(
    items: &[f64],
    what: &'static str,
    f: impl Fn(f64) -> Result<T> + Sync,
) -> Result<Vec<T>> {
    let workers = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(items.len().max(1));
    let next = std::sync::atomic::AtomicUsize::new(0);
    let finished: Vec<Vec<(usize, Result<T>)>> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|_| {
                scope.spawn(|| {
                    let mut done = Vec::new();
                    loop {
                        let index = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        if index >= items.len() {
                            break done;
                        }
                        done.push((index, f(items[index])));
                    }
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|handle| {
                handle.join().unwrap_or_else(|_| {
                    vec![(
                        usize::MAX,
                        Err(Error::Numerical {
                            what,
                            reason: "a worker thread panicked".to_string(),
                        }),
                    )]
                })
            })
            .collect()
    });
    let mut results: Vec<Option<Result<T>>> = (0..items.len()).map(|_| None).collect();
    for (index, result) in finished.into_iter().flatten() {
        if index == usize::MAX {
            result?;
        } else {
            results[index] = Some(result);
        }
    }
    results
        .into_iter()
        .map(|result| {
            result.unwrap_or_else(|| {
                Err(Error::Numerical {
                    what,
                    reason: "an item was not computed".to_string(),
                })
            })
        })
        .collect()
}
