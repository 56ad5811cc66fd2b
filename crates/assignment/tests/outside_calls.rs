//! Frames called from a thread outside any pool, as an engine's main thread calls them, list what
//! a pool worker lists: with the caller working alongside its spawned helpers
//! (`OutsideCalls::Join`, the default) and with the frame handed to a worker (`HandOff`).
//!
//! This binary's global pool has eight threads (more than the CI machine's cores), so a frame
//! spawns seven helpers per region, which the two cores interleave with the caller in ever
//! different orders; the lists must not change.

mod common;

use common::*;
use myriad_assignment::{ActiveClusters, Assigner, LightLists, Method, OutsideCalls, Parallelism};

const GLOBAL_THREADS: usize = 8;

fn global_pool() {
    // Every test of this binary wants the same pool: the first to get here builds it.
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(GLOBAL_THREADS)
        .build_global();
    assert_eq!(rayon::current_num_threads(), GLOBAL_THREADS);
}

/// Runs `f` on a pool of one thread: the reference every outside call's lists must equal.
fn on_one_thread<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(f)
}

/// Points and spots, every splitting method, full and masked grids: the lists from outside equal
/// a one-thread pool's, frame after frame (the same assigner reused, as an engine does).
#[test]
fn outside_calls_list_what_one_thread_lists() {
    global_pool();
    let scene = make_scene(&SceneParams {
        seed: 11,
        lights: 6000,
        ..SceneParams::HD
    });
    let mut mask = ActiveClusters::new(&scene.grid);
    for c in (0..scene.grid.cluster_count() as u32).filter(|c| c % 3 != 1) {
        mask.mark(c);
    }
    for spots in [false, true] {
        let input = scene.lights.input(spots);
        for method in [Method::Binary, Method::Refined, Method::Cone] {
            for active in [None, Some(&mask)] {
                let mut reference = LightLists::new();
                on_one_thread(|| {
                    Assigner::new().assign_active(
                        method,
                        &input,
                        &scene.camera,
                        &scene.grid,
                        active,
                        &mut reference,
                    )
                });
                for calls in [OutsideCalls::Join, OutsideCalls::HandOff] {
                    let what = format!(
                        "{method}, spots {spots}, masked {}, {calls:?}",
                        active.is_some()
                    );
                    let mut assigner = Assigner::new()
                        .with_outside_calls(calls)
                        .with_parallelism(Parallelism::Always);
                    let mut lists = LightLists::new();
                    for frame in 0..4 {
                        let stats = assigner.assign_active(
                            method,
                            &input,
                            &scene.camera,
                            &scene.grid,
                            active,
                            &mut lists,
                        );
                        assert!(
                            stats.parallel && stats.tasks > 1,
                            "{what}: frame {frame} ran serially"
                        );
                        assert!(
                            stats.pairs > 0 && lists == reference,
                            "{what}: frame {frame}'s lists differ from one thread's"
                        );
                    }
                }
            }
        }
    }
}

/// A pair budget that coarsens the grid: the attempts that overflow it run their tasks region
/// with the caller too, and the lists on the grid that fits equal one thread's.
#[test]
fn outside_calls_under_a_pair_budget_coarsen_as_one_thread_does() {
    global_pool();
    let scene = make_scene(&SceneParams {
        seed: 12,
        lights: 6000,
        ..SceneParams::HD
    });
    let input = scene.lights.input(false);
    let budgeted = || Assigner::new().with_pair_budget(30_000);
    let mut reference = LightLists::new();
    let want = on_one_thread(|| {
        budgeted().assign(
            Method::Refined,
            &input,
            &scene.camera,
            &scene.grid,
            &mut reference,
        )
    });
    assert!(want.coarsened > 0, "the budget should force a coarser grid");
    let mut lists = LightLists::new();
    let got = budgeted().with_parallelism(Parallelism::Always).assign(
        Method::Refined,
        &input,
        &scene.camera,
        &scene.grid,
        &mut lists,
    );
    assert!(got.parallel);
    assert_eq!(
        (got.coarsened, got.grid_dims, got.pairs),
        (want.coarsened, want.grid_dims, want.pairs)
    );
    assert!(lists == reference, "lists differ from one thread's");
}

/// An engine whose global pool is busy with long jobs of its own (asset loading) still gets its
/// frames from its main thread at once: with every worker held, a parallel frame called from
/// outside runs wholly on the caller and returns while the workers are still held, its lists
/// equal to one thread's. (A caller that waited for its helpers to be picked up would return only
/// when the workers' job ended: here after a minute, which the test would see.)
#[test]
fn outside_calls_return_while_every_worker_is_busy() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    use std::time::{Duration, Instant};
    global_pool();
    let scene = make_scene(&SceneParams {
        seed: 13,
        lights: 6000,
        ..SceneParams::HD
    });
    let input = scene.lights.input(true);
    let mut reference = LightLists::new();
    on_one_thread(|| {
        Assigner::new().assign(
            Method::Refined,
            &input,
            &scene.camera,
            &scene.grid,
            &mut reference,
        )
    });

    let held = Arc::new(AtomicUsize::new(0));
    let release = Arc::new(AtomicBool::new(false));
    let released_in_time = Arc::new(AtomicUsize::new(0));
    let done = Arc::new(AtomicUsize::new(0));
    for _ in 0..GLOBAL_THREADS {
        let (held, release) = (Arc::clone(&held), Arc::clone(&release));
        let (in_time, done) = (Arc::clone(&released_in_time), Arc::clone(&done));
        rayon::spawn(move || {
            held.fetch_add(1, Ordering::AcqRel);
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
    while held.load(Ordering::Acquire) < GLOBAL_THREADS {
        std::thread::yield_now();
    }

    let mut assigner = Assigner::new().with_parallelism(Parallelism::Always);
    let mut lists = LightLists::new();
    let frames: Vec<_> = (0..3)
        .map(|_| {
            let stats = assigner.assign(
                Method::Refined,
                &input,
                &scene.camera,
                &scene.grid,
                &mut lists,
            );
            (stats, lists == reference)
        })
        .collect();
    release.store(true, Ordering::Release);
    while done.load(Ordering::Acquire) < GLOBAL_THREADS {
        std::thread::yield_now();
    }
    assert_eq!(
        released_in_time.load(Ordering::Acquire),
        GLOBAL_THREADS,
        "the frames returned only after the workers' job ended"
    );
    for (frame, (stats, same)) in frames.iter().enumerate() {
        assert!(
            stats.parallel && stats.tasks > 1,
            "frame {frame} ran serially"
        );
        assert!(*same, "frame {frame}'s lists differ from one thread's");
    }
}
