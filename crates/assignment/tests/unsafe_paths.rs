//! Whole frames through the crate's two `unsafe` blocks, small enough for Miri: the atomic
//! counters' shared index writes (`append.rs`, `SharedIndices`) and the type-erased region that
//! calls from outside any pool share with their helper jobs (`fan_out.rs`, `ErasedRegion`).
//!
//! Natively these frames take milliseconds and only repeat what `determinism.rs` and
//! `outside_calls.rs` check at larger sizes. Their point is the interpreter, which checks every
//! pointer use of those blocks for undefined behaviour and every cross-thread access for data
//! races (a few minutes; README, "Reliability"):
//!
//! ```text
//! MIRIFLAGS="-Zmiri-tree-borrows -Zmiri-permissive-provenance -Zmiri-ignore-leaks" \
//!     cargo +nightly miri test -p myriad-assignment --test unsafe_paths
//! ```
//!
//! (Tree borrows and permissive provenance for crossbeam-epoch, which rayon's deques use and
//! which breaks the stricter stacked-borrows model on its own; leaks because rayon's global pool
//! never joins its threads.)

mod common;

use common::*;
use glam::UVec3;
use myriad_assignment::{AppendStrategy, Assigner, LightLists, Method, OutsideCalls, Parallelism};

/// One frame of `method` with `strategy` by a fresh assigner that always splits its lights.
fn frame(
    scene: &Scene,
    method: Method,
    strategy: AppendStrategy,
    calls: OutsideCalls,
) -> LightLists {
    let mut lists = LightLists::new();
    let stats = Assigner::new()
        .with_append_strategy(strategy)
        .with_outside_calls(calls)
        .with_parallelism(Parallelism::Always)
        .assign(
            method,
            &scene.lights.input(true),
            &scene.camera,
            &scene.grid,
            &mut lists,
        );
    assert!(
        stats.parallel && stats.tasks > 1 && stats.pairs > 0,
        "{method}, {strategy:?}, {calls:?}: the frame must split: {stats:?}"
    );
    lists
}

/// 700 points and spots on an 8×6×8 grid, split into tasks: with either append strategy, called
/// from outside any pool (the caller beside its helpers, or handed off) and from inside a
/// three-thread pool, the lists equal one thread's.
#[test]
fn split_frames_through_the_unsafe_blocks_list_what_one_thread_lists() {
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build_global();
    // Under Miri just past the one-task limit (512 lights), on a small grid: 349 s as it is, where
    // a release build takes milliseconds.
    let (lights, dims) = if cfg!(miri) {
        (520, UVec3::new(4, 3, 4))
    } else {
        (700, UVec3::new(8, 6, 8))
    };
    let scene = make_scene(&SceneParams {
        seed: 5,
        lights,
        dims,
        ..SceneParams::HD
    });
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let three = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    for method in [Method::Binary, Method::Refined] {
        let reference = one.install(|| {
            let mut lists = LightLists::new();
            Assigner::new().assign(
                method,
                &scene.lights.input(true),
                &scene.camera,
                &scene.grid,
                &mut lists,
            );
            lists
        });
        for strategy in [
            AppendStrategy::PartitionedByDepth,
            AppendStrategy::AtomicCounters,
        ] {
            let join = frame(&scene, method, strategy, OutsideCalls::Join);
            let hand_off = frame(&scene, method, strategy, OutsideCalls::HandOff);
            let pooled = three.install(|| frame(&scene, method, strategy, OutsideCalls::Join));
            for (how, lists) in [
                ("joined", join),
                ("handed off", hand_off),
                ("pooled", pooled),
            ] {
                assert!(
                    lists == reference,
                    "{method}, {strategy:?}, {how}: the lists differ from one thread's"
                );
            }
        }
    }
}
