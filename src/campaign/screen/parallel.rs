//! Order-preserving parallel map on scoped threads (the screening stage uses every core).

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Maps `f` over `items` on `threads` threads; results keep the items' order. `on_done` runs after each
/// item (for progress). Items not started when `stop` becomes true are skipped (`None`).
pub fn parallel_map<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    stop: &AtomicBool,
    on_done: &(dyn Fn(usize) + Sync),
    f: impl Fn(&T) -> R + Sync,
) -> Vec<Option<R>> {
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<R>>> = Mutex::new((0..items.len()).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..threads.max(1).min(items.len().max(1)) {
            scope.spawn(|| {
                loop {
                    if stop.load(Ordering::Relaxed) {
                        break;
                    }
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(item) = items.get(i) else { break };
                    let r = f(item);
                    if let Ok(mut guard) = results.lock() {
                        guard[i] = Some(r);
                    }
                    on_done(done.fetch_add(1, Ordering::Relaxed) + 1);
                }
            });
        }
    });
    results.into_inner().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Threads to use: every core the process may run on.
pub fn available_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_order_and_counts_progress() {
        let items: Vec<u64> = (0..1000).collect();
        let seen = AtomicUsize::new(0);
        let out = parallel_map(
            &items,
            4,
            &AtomicBool::new(false),
            &|_| {
                seen.fetch_add(1, Ordering::Relaxed);
            },
            |x| x * 2,
        );
        assert_eq!(out, items.iter().map(|x| Some(x * 2)).collect::<Vec<_>>());
        assert_eq!(seen.load(Ordering::Relaxed), 1000);
    }

    #[test]
    fn stop_skips_the_rest() {
        let stop = AtomicBool::new(true);
        let out = parallel_map(&[1, 2, 3], 2, &stop, &|_| {}, |x| x + 1);
        assert!(out.iter().all(Option::is_none));
    }
}
