//! Steady-state frames allocate nothing: a counting global allocator watches a third frame after
//! two warm-up frames with the same sizes, on `linear`, `binary`, `refined` and `cone` (not `exact`, the slow
//! oracle-backed reference, which is not meant for per-frame use), called inside a thread pool
//! and from outside one (where the assigner hands the frame to the global pool).

mod common;

use common::*;
use myriad_assignment::{Assigner, LightLists, Method};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

struct Counting;

static COUNTING: AtomicBool = AtomicBool::new(false);
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards every call to the system allocator unchanged; only counts calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
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
        if COUNTING.load(Ordering::Relaxed) {
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

#[test]
fn steady_state_frames_do_not_allocate() {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let scene = make_scene(&SceneParams {
        seed: 3,
        lights: 10_000,
        ..SceneParams::HD
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    for (spots, in_pool) in [(false, true), (true, true), (true, false)] {
        for method in [
            Method::Linear,
            Method::Binary,
            Method::Refined,
            Method::Cone,
        ] {
            let mut assigner = Assigner::new();
            let mut lists = LightLists::new();
            let input = scene.lights.input(spots);
            let frame = |a: &mut Assigner, l: &mut LightLists| {
                let mut assign = || a.assign(method, &input, &scene.camera, &scene.grid, l);
                if in_pool {
                    pool.install(assign)
                } else {
                    assign()
                }
            };
            frame(&mut assigner, &mut lists);
            frame(&mut assigner, &mut lists);
            ALLOCATIONS.store(0, Ordering::SeqCst);
            COUNTING.store(true, Ordering::SeqCst);
            let stats = frame(&mut assigner, &mut lists);
            COUNTING.store(false, Ordering::SeqCst);
            assert!(stats.pairs > 0 && stats.tasks > 1 || method == Method::Linear);
            assert_eq!(
                ALLOCATIONS.load(Ordering::SeqCst),
                0,
                "{method} (spots: {spots}, in a pool: {in_pool}) allocated in a steady-state frame"
            );
        }
    }
}

/// Steady state also holds when the grid changes from frame to frame: one assigner alternating
/// between two views' grids, and a pair budget that coarsens the grid within every frame. Each
/// method's scratch grows to the largest grid and stays (a `linear` that shrank its per-cluster
/// lists with the grid dropped their buffers and rebuilt them: 18 833 allocations per pair of
/// frames, audit f2).
#[test]
fn frames_on_changing_grids_do_not_allocate_once_warm() {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
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
            let mut assigner = Assigner::new();
            if let Some(pairs) = budget {
                assigner = assigner.with_pair_budget(pairs);
            }
            let mut lists = LightLists::new();
            let two_frames = |a: &mut Assigner, l: &mut LightLists| {
                let big = a.assign(method, &input, &scene.camera, &scene.grid, l);
                let coarse = a.assign(method, &input, &scene.camera, &small, l);
                (big, coarse)
            };
            two_frames(&mut assigner, &mut lists);
            two_frames(&mut assigner, &mut lists);
            ALLOCATIONS.store(0, Ordering::SeqCst);
            COUNTING.store(true, Ordering::SeqCst);
            let (big, _) = two_frames(&mut assigner, &mut lists);
            COUNTING.store(false, Ordering::SeqCst);
            assert_eq!(big.coarsened > 0, budget.is_some(), "{method} {budget:?}");
            assert_eq!(
                ALLOCATIONS.load(Ordering::SeqCst),
                0,
                "{method} (pair budget {budget:?}) allocated on alternating grids"
            );
        }
    }
}
