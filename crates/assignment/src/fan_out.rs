//! How a frame's parallel regions reach the pool's threads: from a worker by rayon's own
//! splitting, from a thread outside any pool by working alongside jobs it spawns.
//!
//! A thread outside the pool (an engine's main thread, a benchmark loop) cannot start rayon's
//! `join` or `par_iter` itself: rayon injects the whole region into the pool and puts the caller
//! to sleep until a worker has finished it. That costs two cross-thread wake-ups per region and
//! leaves the caller's core idle. Instead, the caller spawns one helper job per other thread of
//! the pool (`rayon::spawn`) and works on the region's items itself, taking them one at a time
//! from a shared queue, as the helpers do once a worker runs them. The region starts at once; a
//! helper that arrives late only finds less left to do.
//!
//! When the queue is empty the caller *closes* the region and spins until the helpers already
//! inside it have finished their items (a short wait: at most one item each). It never waits for
//! a helper that has not started: when every worker is busy with someone else's long job (an
//! engine's asset loading on the global pool), the caller does the whole region itself and
//! returns, where waiting for its helpers to be picked up would have held the frame until a
//! worker came free. A helper that starts after the close finds it closed and returns at once.
//!
//! That is why the helpers borrow nothing: they are `'static` jobs holding an [`Arc`] of the
//! region's control block, and reach the caller's items and work (which live on the caller's
//! stack) through a type-erased pointer that they follow only while counted inside an open
//! region. The caller does not leave [`with_caller`] — not even by unwinding — until it has
//! closed the region and every counted helper has left, so the pointer never dangles while
//! followed (see [`Control`]). A panic in a helper's item is caught there and raised again on
//! the caller, as a scope would.
//!
//! The price is small heap allocations: the control block once per region and one per helper
//! (rayon boxes each spawned job), at most 2 × threads per frame called from outside the pool,
//! plus a block of rayon's injection queue in a frame whose spawns pass a multiple of 63.
//! A frame job on a worker allocates nothing, and [`crate::OutsideCalls::HandOff`] keeps outside
//! calls allocation-free too, at the hand-off's cost. Measured on the 2-vCPU CI machine in the
//! `targets` bench (`paper/*-from-outside`): see [`crate::OutsideCalls`].

use std::any::Any;
use std::panic::{self, AssertUnwindSafe};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

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
/// Returns once every item is done, without waiting for helpers no worker has started.
///
/// No more helpers are spawned than there can be items besides the caller's first (the upper
/// bound of `items.size_hint()`): on a many-core pool a small frame's four tasks would otherwise
/// wake every worker for nothing. Returns the helpers spawned.
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
    let region = Region {
        items: Mutex::new(items),
        work,
    };
    if helpers == 0 {
        region.drain();
        return 0;
    }
    let control = Arc::new(Control {
        region: ErasedRegion {
            data: std::ptr::from_ref(&region).cast(),
            drain: drain_erased::<I, F>,
        },
        inside: AtomicUsize::new(0),
        panic: Mutex::new(None),
    });
    {
        // Closes the region and waits for the helpers inside it however this block is left,
        // unwinding included: only then may `region` go.
        let _close = CloseOnExit(&control);
        for _ in 0..helpers {
            let control = Arc::clone(&control);
            rayon::spawn(move || control.help());
        }
        region.drain();
    }
    let panicked = control
        .panic
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .take();
    if let Some(payload) = panicked {
        panic::resume_unwind(payload);
    }
    helpers
}

/// The items of one region and the work on each: on the caller's stack.
struct Region<I, F> {
    items: Mutex<I>,
    work: F,
}

impl<I: Iterator, F: Fn(I::Item)> Region<I, F> {
    /// Takes and works on items until none are left.
    fn drain(&self) {
        while let Some(item) = self.take() {
            (self.work)(item);
        }
    }

    fn take(&self) -> Option<I::Item> {
        // A panic in `work` never holds this lock (it is released before `work` runs), so a
        // poisoned lock only means another thread panicked in `next`: that panic is raised.
        self.items
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .next()
    }
}

/// A [`Region`] with its types erased, so that `'static` helper jobs can hold it.
struct ErasedRegion {
    data: *const (),
    /// [`drain_erased`] for the region's types.
    drain: unsafe fn(*const ()),
}

// SAFETY: `data` points to a `Region<I, F>` whose `I: Send` and `F: Sync` (`with_caller`'s
// bounds), so sharing it between threads is sound; helpers follow it only while it lives
// (`Control::help`).
unsafe impl Send for ErasedRegion {}
// SAFETY: as for `Send`: the region itself is `Sync`.
unsafe impl Sync for ErasedRegion {}

/// # Safety
/// `data` must point to a live `Region<I, F>`.
unsafe fn drain_erased<I: Iterator, F: Fn(I::Item)>(data: *const ()) {
    // SAFETY: the caller's promise.
    unsafe { (*data.cast::<Region<I, F>>()).drain() }
}

/// What a region's caller and its helpers share, on the heap so that a helper that starts late
/// can still read it after the caller has returned.
///
/// `inside` counts the helpers inside the region, its top bit set once the caller has closed it.
/// A helper enters with one `fetch_add`: if the bit was clear, it is counted before the close, and
/// the caller waits for it to leave; if set, it leaves without following `region`. The count and
/// the bit live in one atomic, so every entry is ordered before or after the close.
struct Control {
    region: ErasedRegion,
    inside: AtomicUsize,
    /// The first panic of a helper's item, raised again on the caller.
    panic: Mutex<Option<Box<dyn Any + Send>>>,
}

/// `Control::inside`'s bit: the region is closed.
const CLOSED: usize = 1 << (usize::BITS - 1);

impl Control {
    /// A helper job: works on the region's items if it is still open.
    fn help(&self) {
        if self.inside.fetch_add(1, Ordering::Acquire) & CLOSED != 0 {
            self.inside.fetch_sub(1, Ordering::Relaxed);
            return;
        }
        // SAFETY: counted inside an open region: the caller is still in `with_caller`, which
        // does not leave (nor drop the region) until this helper has left.
        let drained = panic::catch_unwind(AssertUnwindSafe(|| unsafe {
            (self.region.drain)(self.region.data)
        }));
        if let Err(payload) = drained {
            self.panic
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .get_or_insert(payload);
        }
        // Release: the items this helper worked on are visible to the caller once it sees the
        // count drop.
        self.inside.fetch_sub(1, Ordering::Release);
    }

    /// Closes the region to helpers not yet inside and spins until those inside have left.
    /// Called once the queue is empty, so each is finishing at most one item; after a while it
    /// yields its core instead of spinning, in case a helper's thread is waiting for one.
    fn close_and_wait(&self) {
        self.inside.fetch_or(CLOSED, Ordering::Relaxed);
        let mut spins = 0u32;
        while self.inside.load(Ordering::Acquire) != CLOSED {
            if spins < SPINS_BEFORE_YIELDING {
                spins += 1;
                std::hint::spin_loop();
            } else {
                std::thread::yield_now();
            }
        }
    }
}

/// Closes its region when dropped: at the region's end, however it ended.
struct CloseOnExit<'a>(&'a Control);

impl Drop for CloseOnExit<'_> {
    fn drop(&mut self) {
        self.0.close_and_wait();
    }
}

/// Spins of [`Control::close_and_wait`] before it starts yielding (a few microseconds).
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

    /// With every worker of the global pool held by someone else's long job, the caller does the
    /// whole region itself and returns while the workers are still held: it never waits for a
    /// helper to be picked up. The helpers it spawned run once the workers are free, find the
    /// region closed and leave without touching it (its items and work are long gone by then).
    #[test]
    fn returns_without_waiting_for_helpers_no_worker_has_started() {
        use std::sync::atomic::AtomicBool;
        use std::time::{Duration, Instant};
        let workers = rayon::current_num_threads();
        let (held, release) = (
            Arc::new(AtomicUsize::new(0)),
            Arc::new(AtomicBool::new(false)),
        );
        let (released_in_time, blockers_done) =
            (Arc::new(AtomicUsize::new(0)), Arc::new(AtomicUsize::new(0)));
        for _ in 0..workers {
            let (held, release) = (Arc::clone(&held), Arc::clone(&release));
            let (in_time, done) = (Arc::clone(&released_in_time), Arc::clone(&blockers_done));
            rayon::spawn(move || {
                held.fetch_add(1, Ordering::AcqRel);
                // Held until the test releases it, or a minute: a caller that waited for its
                // helpers would only return after that.
                let deadline = Instant::now() + Duration::from_secs(60);
                while !release.load(Ordering::Acquire) && Instant::now() < deadline {
                    std::thread::sleep(Duration::from_millis(1));
                }
                if release.load(Ordering::Acquire) {
                    in_time.fetch_add(1, Ordering::AcqRel);
                }
                done.fetch_add(1, Ordering::AcqRel);
            });
        }
        while held.load(Ordering::Acquire) < workers {
            std::thread::yield_now();
        }
        // Every worker is held: the region runs on this thread alone.
        let mut slots = vec![None; 16];
        let spawned = with_caller(slots.iter_mut(), workers, |slot| {
            *slot = Some(rayon::current_thread_index());
        });
        release.store(true, Ordering::Release);
        assert_eq!(spawned, workers);
        assert!(slots.iter().all(|s| *s == Some(None)), "{slots:?}");
        while blockers_done.load(Ordering::Acquire) < workers {
            std::thread::yield_now();
        }
        assert_eq!(
            released_in_time.load(Ordering::Acquire),
            workers,
            "the caller returned only after the workers' long job ended"
        );
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

    /// The caller panics in its own item while a helper is inside one, writing into the
    /// caller's slots: the caller does not unwind past `with_caller` (dropping the region the
    /// helper reads) before the helper leaves, so every slot a helper started is finished when
    /// the panic arrives (soundness audit; also run under Miri, which sees a use of the dropped
    /// region directly).
    #[test]
    fn a_caller_that_panics_waits_for_the_helper_inside_an_item() {
        use std::sync::atomic::AtomicBool;
        for _ in 0..3 {
            let helper_in = AtomicBool::new(false);
            let mut slots = vec![0u64; 6];
            let r = std::panic::catch_unwind(AssertUnwindSafe(|| {
                with_caller(slots.iter_mut().enumerate(), 2, |(i, slot)| {
                    if rayon::current_thread_index().is_some() {
                        helper_in.store(true, Ordering::Release);
                        for k in 0..50 {
                            *slot += k;
                            std::thread::yield_now();
                        }
                    } else {
                        while !helper_in.load(Ordering::Acquire) {
                            std::thread::yield_now();
                        }
                        panic!("caller item {i}");
                    }
                })
            }));
            assert!(r.is_err());
            // Every slot a helper touched is complete: the caller waited for it.
            assert!(
                slots.iter().all(|&s| s == 0 || s == (0..50).sum::<u64>()),
                "{slots:?}"
            );
        }
    }

    /// Many tiny regions whose helpers mostly arrive after the caller has returned (and its
    /// stack frame, which held the region, has been reused): a late helper does not follow the
    /// erased pointer. Natively this can hardly fail; it is there for Miri, which reports the
    /// use-after-free if a helper does (`cargo +nightly miri test -p myriad-assignment --lib
    /// fan_out`, run by hand: 8 tests in about 15 s; soundness audit).
    #[test]
    fn late_helpers_never_touch_a_region_whose_caller_returned() {
        for round in 0..40u32 {
            let mut slots = [0u32; 3];
            with_caller(slots.iter_mut(), 4, |s| *s = round + 1);
            assert!(slots.iter().all(|&s| s == round + 1));
        }
    }

    /// Both a helper and the caller panic: the caller's panic is the one raised, and the
    /// helper's payload is dropped with the control block, perhaps on a worker (soundness
    /// audit).
    #[test]
    fn a_helper_and_the_caller_panicking_together_raise_one_panic() {
        use std::sync::atomic::AtomicBool;
        for _ in 0..3 {
            let took = [AtomicBool::new(false), AtomicBool::new(false)];
            let r = std::panic::catch_unwind(AssertUnwindSafe(|| {
                with_caller(0..6, 2, |_| {
                    let helper = rayon::current_thread_index().is_some();
                    took[helper as usize].store(true, Ordering::Release);
                    while !took[!helper as usize].load(Ordering::Acquire) {
                        std::thread::yield_now();
                    }
                    panic!("both {helper}");
                })
            }));
            assert!(r.is_err());
        }
    }
}
