//! `assign_active` equals `assign` on every active cluster and leaves every other cluster empty,
//! for every method and append strategy, serial and parallel, with masks from empty to full.

mod common;

use common::*;
use myriad_assignment::{ActiveClusters, AppendStrategy, Assigner, LightLists, Method};
use rand::{Rng, SeedableRng};

fn check(method: Method, strategy: AppendStrategy, lights: usize, density: f64, seed: u64) {
    let scene = make_scene(&SceneParams {
        seed,
        lights,
        ..SceneParams::HD
    });
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let mut mask = ActiveClusters::new(&scene.grid);
    for c in 0..scene.grid.cluster_count() as u32 {
        if rng.random_bool(density) {
            mask.mark(c);
        }
    }
    let input = scene.lights.input(true);
    let mut full = LightLists::new();
    let mut masked = LightLists::new();
    let mut assigner = Assigner::new().with_append_strategy(strategy);
    assigner.assign(method, &input, &scene.camera, &scene.grid, &mut full);
    let stats = assigner.assign_active(
        method,
        &input,
        &scene.camera,
        &scene.grid,
        Some(&mask),
        &mut masked,
    );
    masked.assert_well_formed(lights);
    let mut expected_pairs = 0;
    for c in 0..scene.grid.cluster_count() {
        if mask.is_active(c as u32) {
            assert_eq!(
                masked.lights_of(c),
                full.lights_of(c),
                "{method:?} {strategy:?}: active cluster {c}"
            );
            expected_pairs += full.counts[c] as u64;
        } else {
            assert!(
                masked.lights_of(c).is_empty(),
                "{method:?}: inactive cluster {c} has lights"
            );
        }
    }
    assert_eq!(stats.pairs, expected_pairs);
    assert_eq!(masked.pair_count() as u64, expected_pairs);
}

#[test]
fn masked_lists_are_the_full_lists_on_active_clusters() {
    for method in [Method::Binary, Method::Refined, Method::Linear] {
        for strategy in [
            AppendStrategy::PartitionedByDepth,
            AppendStrategy::AtomicCounters,
        ] {
            for (lights, density, seed) in [
                (500, 0.3, 1),
                (6000, 0.05, 2),
                (6000, 0.0, 3),
                (6000, 1.0, 4),
            ] {
                check(method, strategy, lights, density, seed);
            }
        }
    }
    check(
        Method::Exact,
        AppendStrategy::PartitionedByDepth,
        300,
        0.2,
        5,
    );
}

#[test]
fn a_budget_that_fits_the_masked_pairs_keeps_the_grid_and_the_mask() {
    // Only the active clusters' pairs count against the budget. `linear` and the atomic-counter
    // append once counted every cluster's: a budget of exactly the masked pairs coarsened the
    // grid (to 3x1x2 for `linear`) and dropped the mask (an audit found it).
    let scene = make_scene(&SceneParams {
        seed: 9,
        lights: 4000,
        ..SceneParams::HD
    });
    let mut rng = rand_pcg::Pcg64::seed_from_u64(9);
    let mut mask = ActiveClusters::new(&scene.grid);
    for c in 0..scene.grid.cluster_count() as u32 {
        if rng.random_bool(0.1) {
            mask.mark(c);
        }
    }
    let input = scene.lights.input(true);
    for method in Method::ALL {
        for strategy in [
            AppendStrategy::PartitionedByDepth,
            AppendStrategy::AtomicCounters,
        ] {
            let assign = |assigner: &mut Assigner, lists: &mut LightLists| {
                let (camera, grid) = (&scene.camera, &scene.grid);
                assigner.assign_active(method, &input, camera, grid, Some(&mask), lists)
            };
            let mut free = LightLists::new();
            let stats = assign(
                &mut Assigner::new().with_append_strategy(strategy),
                &mut free,
            );
            assert!(stats.pairs > 100, "{method} {strategy:?}: {stats:?}");
            let mut capped = LightLists::new();
            let mut assigner = Assigner::new()
                .with_append_strategy(strategy)
                .with_pair_budget(stats.pairs);
            let capped_stats = assign(&mut assigner, &mut capped);
            assert_eq!(capped_stats, stats, "{method} {strategy:?}");
            assert!(capped == free, "{method} {strategy:?}");
        }
    }
}
