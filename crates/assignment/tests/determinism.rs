//! The output is identical for any number of threads, and equals the serial (one-task) result.

mod common;

use common::*;
use glam::UVec3;
use myriad_assignment::{AppendStrategy, Assigner, LightLists, Method};

#[test]
fn identical_lists_for_1_2_3_and_8_threads() {
    let scene = make_scene(&SceneParams {
        seed: 42,
        fov_deg: 70.0,
        aspect: 16.0 / 9.0,
        near: 0.1,
        far_ratio: 1000.0,
        eye_scale: 10.0,
        dims: UVec3::new(16, 9, 24),
        slicing: 1,
        lights: 20_000,
        spots: true,
    });
    for spots in [false, true] {
        for method in [Method::Binary, Method::Refined, Method::Cone] {
            let mut reference: Option<LightLists> = None;
            for threads in [1, 2, 3, 8] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let mut lists = LightLists::new();
                let stats =
                    pool.install(|| scene.assign(&mut Assigner::new(), method, spots, &mut lists));
                assert!(
                    stats.tasks > 1,
                    "{threads} threads should split 20k lights into tasks"
                );
                assert!(stats.pairs > 0);
                match &reference {
                    None => reference = Some(lists),
                    Some(r) => assert!(
                        r == &lists,
                        "{method} with {threads} threads differs from 1 thread"
                    ),
                }
            }
        }
    }
}

#[test]
fn parallel_tasks_agree_with_a_single_serial_task() {
    // 200 lights run as one serial task; the same lights repeated to 20 000 run as many tasks.
    // Each light's clusters must be the same in both.
    let scene = make_scene(&SceneParams {
        seed: 7,
        lights: 200,
        ..SceneParams::WIDE
    });
    let mut big = Columns::default();
    for _ in 0..100 {
        for l in 0..scene.lights.len() {
            big.push(
                glam::Vec3::new(scene.lights.x[l], scene.lights.y[l], scene.lights.z[l]),
                scene.lights.radius[l],
            );
        }
    }
    for method in [Method::Binary, Method::Refined, Method::Cone] {
        let mut small = LightLists::new();
        let mut large = LightLists::new();
        let s = scene.assign(&mut Assigner::new(), method, false, &mut small);
        let b = Assigner::new().assign(
            method,
            &big.input(false),
            &scene.camera,
            &scene.grid,
            &mut large,
        );
        assert_eq!(s.tasks, 1);
        // Below `SERIAL_LIGHTS` the one task runs on the calling thread, even on a first frame
        // (which the pacing would run on the pool).
        assert!(!s.parallel, "{method}: one task, yet on the pool");
        assert!(b.tasks > 1 || rayon::current_num_threads() == 1);
        assert_eq!(b.pairs, 100 * s.pairs);
        for c in 0..small.cluster_count() {
            let expect: Vec<u32> = (0..100u32)
                .flat_map(|rep| small.lights_of(c).iter().map(move |&l| l + rep * 200))
                .collect();
            assert_eq!(large.lights_of(c), &expect[..], "{method} cluster {c}");
        }
    }
}

#[test]
fn both_append_strategies_give_identical_lists() {
    let scene = make_scene(&SceneParams {
        seed: 11,
        fov_deg: 75.0,
        aspect: 1.5,
        near: 0.2,
        far_ratio: 300.0,
        eye_scale: 3.0,
        dims: UVec3::new(24, 12, 16),
        slicing: 2,
        lights: 12_000,
        spots: true,
    });
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        for method in [Method::Binary, Method::Refined, Method::Cone] {
            let mut a = LightLists::new();
            let mut b = LightLists::new();
            pool.install(|| {
                scene.assign(&mut Assigner::new(), method, true, &mut a);
                scene.assign(
                    &mut Assigner::new().with_append_strategy(AppendStrategy::AtomicCounters),
                    method,
                    true,
                    &mut b,
                );
            });
            assert!(a.pair_count() > 0);
            assert!(a == b, "{method}, {threads} threads: strategies differ");
        }
    }
}

#[test]
fn reused_lists_and_assigner_hold_nothing_from_the_previous_frame() {
    let make = |seed, lights, dims| {
        make_scene(&SceneParams {
            seed,
            fov_deg: 65.0,
            aspect: 1.7,
            near: 0.1,
            far_ratio: 800.0,
            eye_scale: 2.0,
            dims,
            slicing: 1,
            lights,
            spots: seed % 2 == 0,
        })
    };
    // Big then small then different grid, each compared with a fresh assignment. Fewer parts
    // than the frame before (a smaller grid, a frame of one task) leave a task's later buckets
    // holding old spans, which the atomic-counter append once read: wrong lists, light indices
    // past the input, or a panic (an audit found it).
    let frames = [
        make(1, 30_000, UVec3::new(16, 9, 24)),
        make(2, 3_000, UVec3::new(16, 9, 24)),
        make(3, 8_000, UVec3::new(8, 8, 8)),
        make(4, 0, UVec3::new(8, 8, 8)),
        make(5, 20_000, UVec3::new(24, 12, 16)),
        make(6, 300, UVec3::new(24, 12, 16)),
        make(7, 2_000, UVec3::new(4, 4, 4)),
    ];
    for strategy in [
        AppendStrategy::PartitionedByDepth,
        AppendStrategy::AtomicCounters,
    ] {
        for method in [Method::Binary, Method::Refined, Method::Linear] {
            let mut assigner = Assigner::new().with_append_strategy(strategy);
            let mut lists = LightLists::new();
            for (f, scene) in frames.iter().enumerate() {
                let spots = f % 2 == 1;
                let input = scene.lights.input(spots);
                assigner.assign(method, &input, &scene.camera, &scene.grid, &mut lists);
                let mut fresh = LightLists::new();
                Assigner::new().assign(method, &input, &scene.camera, &scene.grid, &mut fresh);
                assert!(
                    lists == fresh,
                    "{method} {strategy:?}: frame {f} differs from a fresh assignment"
                );
            }
        }
    }
}

#[test]
fn one_assigner_switching_methods_and_grids_lists_as_fresh_ones_do() {
    // An assigner keeps per-grid tables between frames: the clusters' bounding spheres (spots)
    // and `cone`'s tile cones. A frame of another method on another grid must not leave `cone`
    // reading the previous grid's cones (only `cone` builds them, and only when its own key
    // changes).
    let scene = |seed, dims| {
        make_scene(&SceneParams {
            seed,
            lights: 400,
            dims,
            ..SceneParams::HD
        })
    };
    let (wide, narrow) = (UVec3::new(24, 12, 16), UVec3::new(16, 9, 24));
    let frames = [
        (Method::Binary, scene(1, wide)),
        (Method::Cone, scene(2, narrow)),
        (Method::Refined, scene(3, wide)),
        (Method::Cone, scene(4, wide)),
        (Method::Exact, scene(5, narrow)),
        (Method::Cone, scene(6, narrow)),
    ];
    let mut assigner = Assigner::new();
    let mut lists = LightLists::new();
    for (f, (method, scene)) in frames.iter().enumerate() {
        let input = scene.lights.input(true);
        assigner.assign(*method, &input, &scene.camera, &scene.grid, &mut lists);
        let mut fresh = LightLists::new();
        Assigner::new().assign(*method, &input, &scene.camera, &scene.grid, &mut fresh);
        assert!(
            lists == fresh,
            "{method}: frame {f} differs from a fresh assignment"
        );
    }
}

/// An engine's main thread made worker 0 of its own pool (`ThreadPoolBuilder::use_current_thread`,
/// as "Things to know" in docs/engine-guide.md describes) assigns on that pool, with no hand-off:
/// the frame is split for the pool's seven threads (a count no CI machine's global pool has) and
/// runs on them, and the lists are the ones a one-thread pool writes. The thread is spawned for
/// the test, since a thread that joins a pool stays in it.
#[test]
fn a_thread_that_joined_its_pool_assigns_on_it() {
    let scene = make_scene(&SceneParams {
        seed: 5,
        lights: 8000,
        ..SceneParams::WIDE
    });
    let input = scene.lights.input(false);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    for method in [Method::Binary, Method::Refined] {
        let mut reference = LightLists::new();
        one.install(|| {
            Assigner::new().assign(method, &input, &scene.camera, &scene.grid, &mut reference)
        });
        let (stats, lists) = std::thread::scope(|s| {
            s.spawn(|| {
                let _pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(7)
                    .use_current_thread()
                    .build()
                    .unwrap();
                assert_eq!(rayon::current_thread_index(), Some(0));
                assert_eq!(rayon::current_num_threads(), 7);
                let mut lists = LightLists::new();
                let stats = Assigner::new()
                    .with_parallelism(myriad_assignment::Parallelism::Always)
                    .assign(method, &input, &scene.camera, &scene.grid, &mut lists);
                (stats, lists)
            })
            .join()
            .unwrap()
        });
        assert!(stats.parallel, "{method}: the frame ran on the pool");
        assert_eq!(
            stats.tasks, 28,
            "{method}: four tasks per thread of the joined pool"
        );
        assert!(
            stats.pairs > 0 && lists == reference,
            "{method}: lists differ"
        );
    }
}
