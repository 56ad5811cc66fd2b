//! Frames on threads with small stacks: an engine's job threads, or a rayon pool built with a
//! small `stack_size`, list what a thread with a roomy stack lists and do not overflow.
//!
//! A task keeps its SoA blocks on the running thread's stack: ~150 KiB for tasks of 2048 lights
//! or more, ~60 KiB for smaller ones (release). Before a short stack was grown (`stacker`,
//! `jobs::with_stack`), a 100,000-light frame aborted the whole process on threads of 64 and
//! 128 KiB. Each case here runs on a thread of its own, so an overflow kills this test binary:
//! it fails, it cannot pass by accident.
//!
//! The stack sizes sit where a wrong "need" would show. 48 KiB is below a small task's need and
//! 144 KiB below a large one's, each above what a need set too low would leave unchecked (an
//! audit cut the large need to 128 KiB and the small one to 4 KiB and the first version of
//! this test, with 32, 64 and 128 KiB and large tasks only, still passed). 288 KiB is for
//! unoptimised builds, whose large tasks need more than 256 KiB: it overflowed when they asked
//! for release's.

mod common;

use common::*;
use myriad_assignment::{AssignStats, Assigner, LightLists, Method, OutsideCalls, Parallelism};

/// Thread stack sizes tried, in KiB.
const STACKS_KIB: [usize; 6] = [32, 48, 64, 128, 144, 288];

/// Lights of the two scenes: tasks of the large-block size (2048 lights or more: eight tasks of
/// 3000 on a pool of two threads, four tasks a thread), and of the small one (eight of 500).
const LARGE: usize = 24_000;
const SMALL: usize = 4_000;

/// The global pool of this binary: two threads, whatever the machine's cores, so that outside
/// calls cut the frames into eight tasks.
fn global_pool() {
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build_global();
    assert_eq!(rayon::current_num_threads(), 2);
}

/// Parallel frames must have run tasks of the size the scene is for, or this binary tests less
/// than it says.
fn assert_task_size(stats: &AssignStats, lights: usize, what: &str) {
    if stats.parallel {
        let per_task = lights / stats.tasks as usize;
        assert_eq!(
            per_task >= 2048,
            lights == LARGE,
            "{what}: {} tasks of {per_task} lights",
            stats.tasks
        );
    }
}

/// The shared scene generator's lights, their radii capped at 0.5: its huge and
/// camera-containing lights make ~1000 pairs a light, whose append would only slow this test.
fn scene(lights: usize) -> Scene {
    let mut scene = make_scene(&SceneParams {
        seed: 29,
        lights,
        ..SceneParams::HD
    });
    for r in &mut scene.lights.radius {
        *r = r.min(0.5);
    }
    scene
}

fn cases() -> impl Iterator<Item = (Method, bool)> {
    [Method::Binary, Method::Refined, Method::Cone]
        .into_iter()
        .flat_map(|m| [(m, false), (m, true)])
}

/// The lists of one frame per (method, spots), on a thread with a default (2 MiB) stack.
fn reference(scene: &Scene) -> Vec<LightLists> {
    let mut out = Vec::new();
    for (method, spots) in cases() {
        let mut lists = LightLists::new();
        scene.assign(&mut Assigner::new(), method, spots, &mut lists);
        out.push(lists);
    }
    out
}

/// Frames called from a plain thread with a small stack, in both outside-call modes and paced
/// (small frames after idle stay on the caller), list exactly what the reference lists.
#[test]
fn frames_from_threads_with_small_stacks_list_what_a_roomy_thread_lists() {
    global_pool();
    for lights in [LARGE, SMALL] {
        let scene = scene(lights);
        let reference = reference(&scene);
        for stack in STACKS_KIB {
            for (calls, parallelism) in [
                (OutsideCalls::Join, Parallelism::Always),
                (OutsideCalls::HandOff, Parallelism::Always),
                (OutsideCalls::Join, Parallelism::Paced),
            ] {
                let what =
                    format!("{lights} lights, {stack} KiB stack, {calls:?}, {parallelism:?}");
                std::thread::scope(|s| {
                    std::thread::Builder::new()
                        .stack_size(stack << 10)
                        .spawn_scoped(s, || {
                            let mut assigner = Assigner::new()
                                .with_outside_calls(calls)
                                .with_parallelism(parallelism);
                            let mut lists = LightLists::new();
                            for ((method, spots), expected) in cases().zip(&reference) {
                                for frame in 0..2 {
                                    let stats =
                                        scene.assign(&mut assigner, method, spots, &mut lists);
                                    assert!(stats.pairs > 0, "{what}: {method} listed nothing");
                                    assert_task_size(&stats, lights, &what);
                                    assert!(
                                        lists == *expected,
                                        "{what}: {method}, spots {spots}, frame {frame}: lists \
                                         differ"
                                    );
                                }
                            }
                        })
                        .unwrap()
                        .join()
                        .unwrap();
                });
            }
        }
    }
}

/// A rayon pool whose workers have small stacks runs the tasks on them: the same lists.
///
/// Unoptimised, workers of 32 KiB overflow in rayon's own code (its nested joins and a steal
/// through crossbeam-epoch, read off the overflowing stack in gdb), before any task: those
/// builds start at 48 KiB.
#[test]
fn frames_on_a_pool_with_small_worker_stacks_list_what_a_roomy_thread_lists() {
    global_pool();
    let smallest = if cfg!(debug_assertions) { 48 } else { 32 };
    for lights in [LARGE, SMALL] {
        let scene = scene(lights);
        let reference = reference(&scene);
        for stack in STACKS_KIB.into_iter().filter(|&s| s >= smallest) {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(2)
                .stack_size(stack << 10)
                .build()
                .unwrap();
            let what = format!("{lights} lights, workers of {stack} KiB");
            pool.install(|| {
                let mut assigner = Assigner::new().with_parallelism(Parallelism::Always);
                let mut lists = LightLists::new();
                for ((method, spots), expected) in cases().zip(&reference) {
                    let stats = scene.assign(&mut assigner, method, spots, &mut lists);
                    assert!(
                        stats.parallel && stats.tasks > 1,
                        "{what}: {method} ran serially"
                    );
                    assert_task_size(&stats, lights, &what);
                    assert!(
                        lists == *expected,
                        "{what}: {method}, spots {spots}: lists differ"
                    );
                }
            });
        }
    }
}
