//! Steady-state frames allocate nothing: a counting global allocator watches [`FRAMES`] frames
//! after two warm-up frames with the same sizes, on `linear`, `binary`, `refined` and `cone` (not
//! `exact`, the slow oracle-backed reference, which is not meant for per-frame use), called inside
//! a thread pool: not one allocation.
//!
//! From outside any pool a frame *injects* jobs into rayon's global pool, and the injection queue
//! (crossbeam's `Injector`) is a list of blocks of 63 jobs: one block is allocated per 63 jobs
//! injected, whoever injects them. So calls from outside are held to that amortised bound, over
//! many frames: with `OutsideCalls::HandOff` (one job a frame) at most one block per 63 frames;
//! with the default `OutsideCalls::Join` exactly the helper jobs the frame spawns (rayon boxes
//! each: one per other thread of the pool and region, capped by the region's items) and one
//! control block per region that has helpers, plus those blocks. Both are a fixed
//! number per frame, whatever the lights or the grid; the lists and scratch never grow.
//!
//! Only the threads that run frames count (the test's own and the pools' workers): the test
//! harness's threads allocate as they report other tests' results, and did so inside a counted
//! window now and then under load (15 and 2 stray allocations in 13 runs of a test whose frames
//! allocate none).

mod common;

use common::*;
use myriad_assignment::{
    Assigner, LightLists, Method, OutsideCalls, PacingLimits, Parallelism, SERIAL_LIGHTS,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

struct Counting;

static COUNTING: AtomicBool = AtomicBool::new(false);
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// Whether this thread's allocations count ([`count_here`]). Constant-initialised and
    /// without a destructor, so reading it allocates nothing and works at any point of a thread.
    static COUNTED_HERE: Cell<bool> = const { Cell::new(false) };
}

/// Whether an allocation now counts.
fn counts() -> bool {
    COUNTING.load(Ordering::Relaxed) && COUNTED_HERE.get()
}

/// Counts this thread's allocations from now on.
fn count_here() {
    COUNTED_HERE.set(true);
}

/// Counts the allocations of every thread of the global pool, and of `pool`'s.
fn count_on_the_pools(pool: Option<&rayon::ThreadPool>) {
    rayon::broadcast(|_| count_here());
    if let Some(pool) = pool {
        pool.broadcast(|_| count_here());
    }
}

// SAFETY: forwards every call to the system allocator unchanged; only counts calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if counts() {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: same contract as our caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as our caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if counts() {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: same contract as our caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The count is process-wide: the tests take turns, so one's allocations are not the other's.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// Frames counted per case: enough for the injection queue's per-63-jobs blocks to average out.
/// `linear` (single-threaded: it never touches the pool) is counted over one.
const FRAMES: usize = 32;

/// Frames to count for `method`.
fn frames_for(method: Method) -> usize {
    if method == Method::Linear { 1 } else { FRAMES }
}

/// Jobs one block of rayon's injection queue holds (crossbeam-deque's `BLOCK_CAP`).
const JOBS_PER_INJECTOR_BLOCK: usize = 63;

/// Allocations `frame` makes over `frames` calls, after two uncounted ones.
fn allocations_over_frames<R>(frames: usize, mut frame: impl FnMut() -> R) -> (usize, R) {
    count_here();
    frame();
    frame();
    ALLOCATIONS.store(0, Ordering::SeqCst);
    COUNTING.store(true, Ordering::SeqCst);
    let mut last = frame();
    for _ in 1..frames {
        last = frame();
    }
    COUNTING.store(false, Ordering::SeqCst);
    (ALLOCATIONS.load(Ordering::SeqCst), last)
}

/// The most allocations [`FRAMES`] frames that each inject `jobs` jobs into the global pool may
/// make: `exact` a frame, plus the injection queue's blocks.
fn bound(exact: usize, jobs: usize) -> usize {
    FRAMES * exact + (FRAMES * jobs).div_ceil(JOBS_PER_INJECTOR_BLOCK) + 1
}

#[test]
fn steady_state_frames_do_not_allocate() {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let scene = make_scene(&SceneParams {
        seed: 3,
        lights: 4_000,
        ..SceneParams::HD
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    count_on_the_pools(Some(&pool));
    // A parallel frame from outside runs two regions, the tasks and the append's parts (one per
    // depth slice), each spawning one helper per other thread of the global pool, but no more
    // than the region has items besides the caller's first, and their shared control block.
    let others = rayon::current_num_threads() - 1;
    let parts = scene.grid.dims().z as usize;
    for (spots, in_pool, calls) in [
        (false, true, None),
        (true, true, None),
        (true, false, Some(OutsideCalls::HandOff)),
        (true, false, Some(OutsideCalls::Join)),
        (false, false, Some(OutsideCalls::Join)),
    ] {
        for method in [
            Method::Linear,
            Method::Binary,
            Method::Refined,
            Method::Cone,
        ] {
            let mut assigner = Assigner::new().with_outside_calls(calls.unwrap_or_default());
            let mut lists = LightLists::new();
            let input = scene.lights.input(spots);
            let frame = || assigner.assign(method, &input, &scene.camera, &scene.grid, &mut lists);
            // In a pool, every frame on a worker (one `install` around them all, as a frame job
            // loop runs): nothing is injected into a pool's queue.
            let (allocations, stats) = if in_pool {
                pool.install(|| allocations_over_frames(frames_for(method), frame))
            } else {
                allocations_over_frames(frames_for(method), frame)
            };
            assert!(
                stats.pairs > 0 && stats.tasks > 1 && stats.parallel || method == Method::Linear
            );
            let what = format!("{method} (spots: {spots}, in a pool: {in_pool}, {calls:?})");
            let (least, most) = match (calls, method) {
                (_, Method::Linear) | (None, _) => (0, 0),
                (Some(OutsideCalls::HandOff), _) => (0, bound(0, 1)),
                (Some(OutsideCalls::Join), _) => {
                    let tasks = stats.tasks as usize;
                    let helpers = [others.min(tasks - 1), others.min(parts - 1)];
                    let helper_jobs: usize = helpers.iter().sum();
                    // Each helper is a boxed job; a region with helpers also has its control
                    // block, which they share.
                    let per_frame = helper_jobs + helpers.iter().filter(|&&h| h > 0).count();
                    (FRAMES * per_frame, bound(per_frame, helper_jobs))
                }
            };
            assert!(
                (least..=most).contains(&allocations),
                "{what}: {allocations} allocations in {} steady-state frames, not {least}..={most}",
                frames_for(method)
            );
        }
    }
}

/// Steady state also holds when the grid changes from frame to frame: one assigner alternating
/// between two views' grids, and a pair budget that coarsens the grid within every frame (called
/// from outside any pool with `OutsideCalls::HandOff`, so no helper job is counted). Each
/// method's scratch grows to the largest grid and stays (a `linear` that shrank its per-cluster
/// lists with the grid dropped their buffers and rebuilt them: 18 833 allocations per pair of
/// frames, audit f2).
#[test]
fn frames_on_changing_grids_do_not_allocate_once_warm() {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    count_on_the_pools(None);
    let scene = make_scene(&SceneParams {
        seed: 5,
        lights: 10_000,
        ..SceneParams::HD
    });
    let small = myriad_assignment::coarser_grid(&myriad_assignment::coarser_grid(&scene.grid));
    let input = scene.lights.input(false);
    for method in [
        Method::Linear,
        Method::Binary,
        Method::Refined,
        Method::Cone,
    ] {
        for budget in [None, Some(20_000)] {
            let mut assigner = Assigner::new().with_outside_calls(OutsideCalls::HandOff);
            if let Some(pairs) = budget {
                assigner = assigner.with_pair_budget(pairs);
            }
            let mut lists = LightLists::new();
            let two_frames = |a: &mut Assigner, l: &mut LightLists| {
                let big = a.assign(method, &input, &scene.camera, &scene.grid, l);
                let coarse = a.assign(method, &input, &scene.camera, &small, l);
                (big, coarse)
            };
            let (allocations, (big, _)) = allocations_over_frames(frames_for(method), || {
                two_frames(&mut assigner, &mut lists)
            });
            assert_eq!(big.coarsened > 0, budget.is_some(), "{method} {budget:?}");
            // Each parallel attempt hands one job to the pool: two frames, each on up to five
            // grids (the budget's coarsening), are at most ten.
            let most = if method == Method::Linear {
                0
            } else {
                bound(0, 10)
            };
            assert!(
                allocations <= most,
                "{method} (pair budget {budget:?}): {allocations} allocations in {} pairs of frames on alternating grids",
                frames_for(method)
            );
        }
    }
}

/// Frames that stay on the calling thread allocate nothing when called from outside any pool,
/// with either [`OutsideCalls`]: a frame too small to split (one task: nothing to share, even
/// under `Parallelism::Always`) and a split frame the pacing runs serially (as a small frame
/// after idle). Neither spawns a helper nor injects a job into the pool: over 64 frames, more
/// than one block of the injection queue, a single injected job a frame would allocate a block
/// (mutation audit: a one-task frame sent down the outside-call path, and a serial frame whose
/// append split its parts over `rayon::join`, passed every test: their lists are the same).
#[test]
fn frames_that_stay_on_the_calling_thread_allocate_nothing_from_outside() {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let split = make_scene(&SceneParams {
        seed: 9,
        lights: 1_500,
        ..SceneParams::HD
    });
    let one_task = make_scene(&SceneParams {
        seed: 9,
        lights: SERIAL_LIGHTS - 1,
        ..SceneParams::HD
    });
    // After the first frame (parallel: there is no frame before it to judge by) every frame is
    // serial: no gap is short enough to count as warm, no frame big enough to count as work.
    let serial = Parallelism::PacedWith(PacingLimits {
        warm_gap: Duration::ZERO,
        cold_work: Duration::MAX,
    });
    // The global pool's threads allocate as they start: have them all started (and idle) first.
    count_on_the_pools(None);
    let frames = JOBS_PER_INJECTOR_BLOCK + 1;
    for calls in [OutsideCalls::Join, OutsideCalls::HandOff] {
        for (scene, parallelism, tasks) in [
            (&one_task, Parallelism::Always, "one task"),
            (&split, serial, "serial"),
        ] {
            for method in [Method::Binary, Method::Refined] {
                let what = format!("{method}, {tasks}, {calls:?}");
                let mut assigner = Assigner::new()
                    .with_outside_calls(calls)
                    .with_parallelism(parallelism);
                let mut lists = LightLists::new();
                let input = scene.lights.input(true);
                let (allocations, stats) = allocations_over_frames(frames, || {
                    assigner.assign(method, &input, &scene.camera, &scene.grid, &mut lists)
                });
                assert!(stats.pairs > 0 && !stats.parallel, "{what}: {stats:?}");
                assert_eq!(stats.tasks > 1, tasks == "serial", "{what}: {stats:?}");
                assert_eq!(
                    allocations, 0,
                    "{what}: {allocations} allocations in {frames} frames"
                );
            }
        }
    }
}
