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
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    for spots in [false, true] {
        let input = scene.lights.input(spots);
        for method in [Method::Binary, Method::Refined, Method::Cone] {
            for active in [None, Some(&mask)] {
                let mut reference = LightLists::new();
                one.install(|| {
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
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let want = one.install(|| {
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
