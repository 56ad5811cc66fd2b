//! How a frame's parallel regions reach the pool's threads: from a worker by rayon's own
//! splitting, from a thread outside any pool by working alongside jobs it spawns.
//!
//! A thread outside the pool (an engine's main thread, a benchmark loop) cannot start rayon's
//! `join` or `par_iter` itself: rayon injects the whole region into the pool and puts the caller
//! to sleep until a worker has finished it. That costs two cross-thread wake-ups per region and
//! leaves the caller's core idle. Instead, the caller spawns one helper job per other thread of
//! the pool (`rayon::in_place_scope`) and works on the region's items itself, taking them one at
//! a time from a shared queue, as the helpers do once a worker runs them. The region starts at
//! once; a helper that arrives late only finds less left to do.
//!
//! When the queue is empty the caller spins until the items the helpers took are done (a short
//! wait: at most one item each) before it leaves the scope, so it does not go to sleep on the
//! scope's latch while the last item finishes. A helper that no worker has started by then still
//! has to run (it finds the queue empty) before the scope can end: under [`crate::Parallelism`]'s
//! default pacing a frame only runs in parallel when the workers are awake or the frame is big,
//! so that wait is rare. The same holds when every worker is busy with someone else's long job:
//! the caller does the whole region itself and then waits for a worker to pick up its helpers
//! (which find nothing left) — where a hand-off waits for such a worker to run the whole frame.
//! (Helpers that borrow nothing, so that the caller could return without them, would need the
//! frame's borrowed inputs behind `unsafe` lifetime erasure; not done.)
//!
//! The price is one small heap allocation per helper (rayon boxes each spawned job): at most
//! 2 × (threads − 1) per frame called from outside the pool. A frame job on a worker allocates nothing, and
//! [`crate::OutsideCalls::HandOff`] keeps outside calls allocation-free too, at the hand-off's
//! cost. Measured on the 2-vCPU CI machine in the `targets` bench (`paper/*-from-outside`):
//! see [`crate::OutsideCalls`].

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};

/// How a frame's parallel regions (its tasks, then the append's parts) are run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum FanOut {
    /// One after another on the calling thread.
    Serial,
    /// By rayon's `join`/`par_iter` on the current pool: the caller is one of its workers (or the
    /// whole frame was handed to one).
    Pool,
    /// The caller is outside any pool: it works on each region's items alongside `helpers` jobs
    /// spawned on the global pool.
    WithCaller { helpers: usize },
}

impl FanOut {
    /// Whether the region may run on several threads.
    pub fn parallel(self) -> bool {
        self != FanOut::Serial
    }
}

/// Runs `work` on every item of `items`, on this thread (which is outside any pool) and on up to
/// `helpers` jobs spawned on the global pool, each taking the next item from the shared queue
/// until it is empty. Items are taken in order, but which thread runs which depends on timing:
/// `work` must give the same result wherever an item runs (each of ours writes only its item).
///
/// No more helpers are spawned than there can be items besides the caller's first (the upper
/// bound of `items.size_hint()`): on a many-core pool a small frame's four tasks would otherwise
/// wake every worker, and the caller would wait for each to pick up its empty helper. Returns
/// the helpers spawned.
pub(crate) fn with_caller<I, F>(items: I, helpers: usize, work: F) -> usize
where
    I: Iterator + Send,
    F: Fn(I::Item) + Sync,
{
    let at_most = items
        .size_hint()
        .1
        .map_or(usize::MAX, |n| n.saturating_sub(1));
    let helpers = helpers.min(at_most);
    let queue = Queue {
        items: Mutex::new(items),
        taken: AtomicUsize::new(0),
        done: AtomicUsize::new(0),
    };
    rayon::in_place_scope(|scope| {
        for _ in 0..helpers {
            scope.spawn(|_| queue.drain(&work));
        }
        queue.drain(&work);
        queue.wait_for_taken();
    });
    helpers
}

/// The items of one region and how many have been taken and finished.
struct Queue<I> {
    items: Mutex<I>,
    taken: AtomicUsize,
    done: AtomicUsize,
}

impl<I: Iterator> Queue<I> {
    /// Takes and works on items until none are left.
    fn drain(&self, work: &impl Fn(I::Item)) {
        while let Some(item) = self.take() {
            // Counted as done even if `work` panics, so the caller's wait still ends (and the
            // scope then re-raises the panic).
            let _done = Done(&self.done);
            work(item);
        }
    }

    fn take(&self) -> Option<I::Item> {
        // A panic in `work` never holds this lock (it is released before `work` runs), so a
        // poisoned lock only means another thread panicked elsewhere: the scope re-raises that.
        let mut items = self.items.lock().unwrap_or_else(PoisonError::into_inner);
        let item = items.next()?;
        // Counted under the lock: once a thread has found the queue empty, `taken` is final.
        self.taken.fetch_add(1, Ordering::Relaxed);
        Some(item)
    }

    /// Spins until every item taken has been worked on. Called once the queue is empty, so the
    /// others are each finishing at most one item; after a while it yields its core instead of
    /// spinning, in case a helper's thread is waiting for one.
    fn wait_for_taken(&self) {
        let taken = self.taken.load(Ordering::Relaxed);
        let mut spins = 0u32;
        while self.done.load(Ordering::Acquire) < taken {
            if spins < SPINS_BEFORE_YIELDING {
                spins += 1;
                std::hint::spin_loop();
            } else {
                std::thread::yield_now();
            }
        }
    }
}

/// Adds one to its counter when dropped: an item's end, however it ended.
struct Done<'a>(&'a AtomicUsize);

impl Drop for Done<'_> {
    fn drop(&mut self) {
        self.0.fetch_add(1, Ordering::Release);
    }
}

/// Spins of [`Queue::wait_for_taken`] before it starts yielding (a few microseconds).
const SPINS_BEFORE_YIELDING: u32 = 4096;

#[cfg(test)]
mod tests {
    use super::*;

    /// Every item is worked on exactly once, whatever the number of helpers (more helpers than
    /// items included), and each item's own result lands in its own slot.
    #[test]
    fn every_item_runs_once() {
        for helpers in [0, 1, 3, 40] {
            let mut slots = vec![0u32; 97];
            let runs = AtomicUsize::new(0);
            with_caller(slots.iter_mut().enumerate(), helpers, |(i, slot)| {
                *slot += i as u32 + 1;
                runs.fetch_add(1, Ordering::Relaxed);
            });
            assert_eq!(runs.into_inner(), 97, "{helpers} helpers");
            assert!(
                slots.iter().enumerate().all(|(i, &s)| s == i as u32 + 1),
                "{helpers} helpers"
            );
        }
    }

    /// Helpers are spawned only for items the caller might not get to: none for one item or
    /// none, one fewer than the items at most, and as many as asked where the items are more
    /// (or their count unknown).
    #[test]
    fn no_more_helpers_than_items_besides_the_callers() {
        let nothing = |_| {};
        assert_eq!(with_caller(0..0, 7, nothing), 0);
        assert_eq!(with_caller(0..1, 7, nothing), 0);
        assert_eq!(with_caller(0..3, 7, nothing), 2);
        assert_eq!(with_caller(0..8, 7, nothing), 7);
        assert_eq!(with_caller(0..100, 7, nothing), 7);
        assert_eq!(with_caller((0..3).filter(|_| true), 7, nothing), 2);
        assert_eq!(
            with_caller(std::iter::repeat_n(0, 5).skip_while(|_| false), 2, nothing),
            2
        );
    }

    /// The caller does not return before the helpers' items are done, even when they are slow.
    #[test]
    fn returns_after_the_slowest_item() {
        let finished = AtomicUsize::new(0);
        with_caller(0..4, 3, |i| {
            std::thread::sleep(std::time::Duration::from_millis(5 * i));
            finished.fetch_add(1, Ordering::Release);
        });
        assert_eq!(finished.load(Ordering::Acquire), 4);
    }

    /// A panic in an item reaches the caller, whether the caller ran it or a helper did (a
    /// helper's panic must not leave the caller waiting for an item that never finishes).
    #[test]
    fn a_panicking_item_panics_the_caller() {
        use std::sync::atomic::AtomicBool;
        for on_a_helper in [false, true] {
            // [the caller, a helper] has taken an item.
            let ran = [AtomicBool::new(false), AtomicBool::new(false)];
            let result = std::panic::catch_unwind(|| {
                with_caller(0..8, 2, |i| {
                    let helper = rayon::current_thread_index().is_some();
                    ran[helper as usize].store(true, Ordering::Release);
                    assert!(helper != on_a_helper, "item {i} fails");
                    // Hold this item until the other side has taken one, so both sides run
                    // (and the failing one fails) whoever took the first item.
                    while !ran[!helper as usize].load(Ordering::Acquire) {
                        std::thread::yield_now();
                    }
                })
            });
            assert!(result.is_err(), "a panic on a helper: {on_a_helper}");
        }
    }
}
