//! The pair budget: frames that would write more pairs than allowed are assigned on coarser grids,
//! deterministically, still covering the oracle, and say so; nothing is ever dropped.

mod common;

use common::*;
use glam::UVec3;
use myriad_assignment::{AppendStrategy, AssignStats, Assigner, LightLists, Method, coarser_grid};
use myriad_cluster_math::ClusterGrid;

fn scene() -> Scene {
    make_scene(&SceneParams {
        seed: 77,
        fov_deg: 70.0,
        aspect: 1.6,
        near: 0.1,
        far_ratio: 300.0,
        eye_scale: 1.0,
        dims: UVec3::new(16, 10, 12),
        slicing: 2,
        lights: 3_000,
        spots: true,
    })
}

fn coarsened(grid: &ClusterGrid, steps: u32) -> ClusterGrid {
    (0..steps).fold(*grid, |g, _| coarser_grid(&g))
}

#[test]
fn over_budget_frames_coarsen_the_grid_and_stay_conservative() {
    let scene = scene();
    for method in [
        Method::Binary,
        Method::Refined,
        Method::Cone,
        Method::Linear,
        Method::Exact,
    ] {
        let input = scene.lights.input(true);
        let mut full = LightLists::new();
        let free = Assigner::new().assign(method, &input, &scene.camera, &scene.grid, &mut full);
        assert_eq!(free.coarsened, 0);
        assert_eq!(free.grid_dims, scene.grid.dims().to_array());
        assert!(!free.over_budget);

        let budget = free.pairs / 3;
        let mut lists = LightLists::new();
        let mut assigner = Assigner::new().with_pair_budget(budget);
        let stats = assigner.assign(method, &input, &scene.camera, &scene.grid, &mut lists);
        assert!(
            stats.coarsened > 0,
            "{method}: {} pairs fit a budget of {budget}?",
            free.pairs
        );
        assert!(
            stats.pairs <= budget && !stats.over_budget,
            "{method}: {stats:?}"
        );
        let grid = coarsened(&scene.grid, stats.coarsened);
        assert_eq!(stats.grid_dims, grid.dims().to_array());
        // What callers rebuild the grid the lists are for from.
        assert_eq!(stats.grid_built(&scene.grid), grid, "{method}");
        assert_eq!(lists.cluster_count(), grid.cluster_count());
        // Never a missed light on the grid actually used, and the same as assigning on it directly.
        let truth = brute_force(&scene.lights, true, &scene.camera, &grid);
        assert_conservative(method.name(), &lists, &truth, "coarsened");
        let mut direct = LightLists::new();
        Assigner::new().assign(method, &input, &scene.camera, &grid, &mut direct);
        assert!(
            direct == lists,
            "{method}: degraded lists differ from a direct assignment"
        );
        // Deterministic: again, and on another thread count.
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        let mut again = LightLists::new();
        let again_stats = pool.install(|| {
            Assigner::new().with_pair_budget(budget).assign(
                method,
                &input,
                &scene.camera,
                &scene.grid,
                &mut again,
            )
        });
        assert_eq!(again_stats.coarsened, stats.coarsened);
        assert!(again == lists);
        // The other append strategy coarsens alike, on one thread and on several. (Its first
        // attempt fills more buckets than the coarser one: it once read the stale ones and
        // panicked, an audit found.)
        if matches!(method, Method::Binary | Method::Refined) {
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let mut atomic = LightLists::new();
                let atomic_stats = pool.install(|| {
                    Assigner::new()
                        .with_pair_budget(budget)
                        .with_append_strategy(AppendStrategy::AtomicCounters)
                        .assign(method, &input, &scene.camera, &scene.grid, &mut atomic)
                });
                let outcome = |s: AssignStats| (s.pairs, s.coarsened, s.grid_dims, s.over_budget);
                assert_eq!(
                    outcome(atomic_stats),
                    outcome(stats),
                    "{method}, {threads} threads"
                );
                assert!(atomic == lists, "{method}, {threads} threads");
            }
        }
    }
}

#[test]
fn an_impossible_budget_ends_on_one_cluster_with_every_visible_light() {
    let scene = scene();
    let input = scene.lights.input(true);
    let mut lists = LightLists::new();
    let stats = Assigner::new().with_pair_budget(0).assign(
        Method::Refined,
        &input,
        &scene.camera,
        &scene.grid,
        &mut lists,
    );
    assert_eq!(stats.grid_dims, [1, 1, 1]);
    assert!(stats.over_budget);
    assert_eq!(lists.cluster_count(), 1);
    // Every light whose volume reaches the frustum is in the one cluster (a spot light's box can
    // survive the phases while its cone misses the frustum, so pairs ≤ visible).
    assert!(
        stats.pairs > 0 && stats.pairs <= stats.visible() as u64,
        "{stats:?}"
    );
    let truth = brute_force(
        &scene.lights,
        true,
        &scene.camera,
        &coarsened(&scene.grid, stats.coarsened),
    );
    assert_conservative("refined", &lists, &truth, "1x1x1");
}
