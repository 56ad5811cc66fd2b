//! Whole frames through the crate's two `unsafe` abstractions, small enough for Miri: the atomic
//! counters' shared index writes (`append.rs`, `SharedIndices`, reached by tasks filling in
//! parallel on a pool: handed off or inside one) and the type-erased region that a call from
//! outside any pool shares with its helper jobs (`fan_out.rs`, `ErasedRegion`, reached only by
//! the default append joined from outside).
//!
//! Natively these frames take milliseconds and only repeat what `determinism.rs` and
//! `outside_calls.rs` check at larger sizes. Their point is the interpreter, which checks every
//! pointer use of those abstractions for undefined behaviour and every cross-thread access for
//! data races (minutes; docs/reliability.md, "Miri"). Whether a helper job enters a region here is up
//! to the scheduler; `fan_out`'s unit test `a_panicking_item_panics_the_caller` makes one take an
//! item in every run, so run those too:
//!
//! ```text
//! export MIRIFLAGS="-Zmiri-tree-borrows -Zmiri-permissive-provenance -Zmiri-ignore-leaks"
//! cargo +nightly miri test -p myriad-assignment --test unsafe_paths   # 274 s
//! cargo +nightly miri test -p myriad-assignment --lib fan_out          # 5 s
//! ```
//!
//! (Times on the 2-core machine, 2026-11-30, after Miri's first build of the dependencies.)
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
    let stats = scene.assign(
        &mut Assigner::new()
            .with_append_strategy(strategy)
            .with_outside_calls(calls)
            .with_parallelism(Parallelism::Always),
        method,
        true,
        &mut lists,
    );
    assert!(
        stats.parallel && stats.tasks > 1 && stats.pairs > 0,
        "{method}, {strategy:?}, {calls:?}: the frame must split: {stats:?}"
    );
    lists
}

/// 700 points and spots on an 8×6×8 grid, split into tasks, each frame's lists equal one
/// thread's: the default append called from outside any pool (the caller beside its helpers, or
/// handed off) and from inside a three-thread pool; the atomic counters handed off and inside
/// the pool (from outside they are always handed off).
#[test]
fn split_frames_through_the_unsafe_blocks_list_what_one_thread_lists() {
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build_global();
    assert_eq!(rayon::current_num_threads(), 3);
    // Under Miri just past the one-task limit (512 lights), on a small grid: 274 s as it is, where
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
            scene.assign(&mut Assigner::new(), method, true, &mut lists);
            lists
        });
        let runs = [
            (AppendStrategy::PartitionedByDepth, Some(OutsideCalls::Join)),
            (
                AppendStrategy::PartitionedByDepth,
                Some(OutsideCalls::HandOff),
            ),
            (AppendStrategy::PartitionedByDepth, None),
            (AppendStrategy::AtomicCounters, Some(OutsideCalls::HandOff)),
            (AppendStrategy::AtomicCounters, None),
        ];
        for (strategy, outside) in runs {
            let lists = match outside {
                Some(calls) => frame(&scene, method, strategy, calls),
                None => three.install(|| frame(&scene, method, strategy, OutsideCalls::Join)),
            };
            assert!(
                lists == reference,
                "{method}, {strategy:?}, {outside:?} (None: in a pool): the lists differ from one \
                 thread's"
            );
        }
    }
}
