//! Frames on threads with small stacks: an engine's job threads, or a rayon pool built with a
//! small `stack_size`, list what a thread with a roomy stack lists and do not overflow.
//!
//! A task of 2048 lights or more keeps its SoA blocks (~150 KiB) on the running thread's stack.
//! Before the tasks grew their stack where it ran short (`stacker`), a 100,000-light frame
//! aborted the whole process on threads of 64 and 128 KiB. Each case here runs on a thread of its
//! own, so an overflow kills this test binary: it fails, it cannot pass by accident. 288 KiB is
//! for unoptimised builds, whose tasks need more than 256 KiB: it overflowed when the stack a
//! task asks for was release's in every build.

mod common;

use common::*;
use myriad_assignment::{Assigner, LightLists, Method, OutsideCalls, Parallelism};

/// Lights enough for tasks of the large-block size (2048 lights or more) on pools of two threads,
/// four tasks a thread.
const LIGHTS: usize = 24_000;

/// The global pool of this binary: two threads, whatever the machine's cores, so that outside
/// calls cut the frame into eight tasks of 3000 lights.
fn global_pool() {
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build_global();
    assert_eq!(rayon::current_num_threads(), 2);
}

/// Parallel frames must have run tasks of the large-block size, or this binary tests nothing.
fn assert_large_tasks(stats: &myriad_assignment::AssignStats, what: &str) {
    if stats.parallel {
        assert!(
            LIGHTS / stats.tasks as usize >= 2048,
            "{what}: {} tasks, too many for large ones",
            stats.tasks
        );
    }
}

/// The shared scene generator's lights, their radii capped at 0.5: its huge and
/// camera-containing lights make ~1000 pairs a light, whose append would only slow this test.
fn scene() -> Scene {
    let mut scene = make_scene(&SceneParams {
        seed: 29,
        lights: LIGHTS,
        ..SceneParams::HD
    });
    for r in &mut scene.lights.radius {
        *r = r.min(0.5);
    }
    scene
}

/// The lists of one frame per (method, spots), on a thread with a default (2 MiB) stack.
fn reference(scene: &Scene) -> Vec<LightLists> {
    let mut out = Vec::new();
    for (method, spots) in cases() {
        let mut lists = LightLists::new();
        Assigner::new().assign(
            method,
            &scene.lights.input(spots),
            &scene.camera,
            &scene.grid,
            &mut lists,
        );
        out.push(lists);
    }
    out
}

fn cases() -> impl Iterator<Item = (Method, bool)> {
    [Method::Binary, Method::Refined, Method::Cone]
        .into_iter()
        .flat_map(|m| [(m, false), (m, true)])
}

/// Frames called from a plain thread with a small stack, in both outside-call modes and paced
/// (small frames after idle stay on the caller), list exactly what the reference lists.
#[test]
fn frames_from_threads_with_small_stacks_list_what_a_roomy_thread_lists() {
    global_pool();
    let scene = scene();
    let reference = reference(&scene);
    for stack in [32 << 10, 64 << 10, 128 << 10, 288 << 10] {
        for (calls, parallelism) in [
            (OutsideCalls::Join, Parallelism::Always),
            (OutsideCalls::HandOff, Parallelism::Always),
            (OutsideCalls::Join, Parallelism::Paced),
        ] {
            let what = format!("{} KiB stack, {calls:?}, {parallelism:?}", stack >> 10);
            std::thread::scope(|s| {
                std::thread::Builder::new()
                    .stack_size(stack)
                    .spawn_scoped(s, || {
                        let mut assigner = Assigner::new()
                            .with_outside_calls(calls)
                            .with_parallelism(parallelism);
                        let mut lists = LightLists::new();
                        for ((method, spots), expected) in cases().zip(&reference) {
                            for frame in 0..2 {
                                let input = scene.lights.input(spots);
                                let stats = assigner.assign(
                                    method,
                                    &input,
                                    &scene.camera,
                                    &scene.grid,
                                    &mut lists,
                                );
                                assert!(stats.pairs > 0, "{what}: {method} listed nothing");
                                assert_large_tasks(&stats, &what);
                                assert!(
                                    lists == *expected,
                                    "{what}: {method}, spots {spots}, frame {frame}: lists differ"
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

/// A rayon pool whose workers have small stacks runs the tasks on them: the same lists.
#[test]
fn frames_on_a_pool_with_small_worker_stacks_list_what_a_roomy_thread_lists() {
    global_pool();
    let scene = scene();
    let reference = reference(&scene);
    for stack in [32 << 10, 64 << 10, 128 << 10, 288 << 10] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .stack_size(stack)
            .build()
            .unwrap();
        pool.install(|| {
            let mut assigner = Assigner::new().with_parallelism(Parallelism::Always);
            let mut lists = LightLists::new();
            for ((method, spots), expected) in cases().zip(&reference) {
                let stats = assigner.assign(
                    method,
                    &scene.lights.input(spots),
                    &scene.camera,
                    &scene.grid,
                    &mut lists,
                );
                assert!(stats.parallel && stats.tasks > 1, "{method}: ran serially");
                assert_large_tasks(&stats, "a pool of small stacks");
                assert!(
                    lists == *expected,
                    "{} KiB workers: {method}, spots {spots}: lists differ",
                    stack >> 10
                );
            }
        });
    }
}
