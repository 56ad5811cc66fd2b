//! Small frames after idle run their tasks on the calling thread, whether it is a worker of the
//! pool or not; the lists do not change.
//! (The decision itself is unit-tested in `pacing.rs`; this checks the assigner acts on it. The
//! limits are set so that "small" does not depend on how fast this build or machine is.)

mod common;

use common::*;
use myriad_assignment::{Assigner, LightLists, Method, PacingLimits, Parallelism};
use std::time::Duration;

/// A generated wide scene of `lights` lights with radii capped at 5 cm: the generator's radii
/// reach 1000× the near plane, and small lights make a small frame.
fn small_lights(seed: u64, lights: usize) -> (Scene, Columns) {
    let scene = make_scene(&SceneParams {
        seed,
        lights,
        ..SceneParams::WIDE
    });
    let mut small = Columns::default();
    for l in 0..scene.lights.len() {
        let p = glam::Vec3::new(scene.lights.x[l], scene.lights.y[l], scene.lights.z[l]);
        small.push(p, scene.lights.radius[l].min(0.05));
    }
    (scene, small)
}

#[test]
fn a_small_frame_after_idle_runs_serially_with_the_same_lists() {
    let (scene, lights) = small_lights(11, 1500);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    // From a worker (`install`), and from outside the pool, where a parallel frame first moves
    // onto a worker: a serial one must not.
    for (method, on_pool) in [
        (Method::Binary, true),
        (Method::Refined, true),
        (Method::Binary, false),
        (Method::Refined, false),
    ] {
        let input = lights.input(false);
        // Any frame is small (under a second of work); 5 ms apart is idle.
        let limits = PacingLimits {
            warm_gap: Duration::from_micros(20),
            cold_work: Duration::from_secs(1),
        };
        let mut assigner = Assigner::new().with_parallelism(Parallelism::PacedWith(limits));
        let mut frame = |lists: &mut LightLists| {
            let mut assign = || assigner.assign(method, &input, &scene.camera, &scene.grid, lists);
            if on_pool {
                pool.install(assign)
            } else {
                assign()
            }
        };
        let mut first = LightLists::new();
        let stats = frame(&mut first);
        assert!(stats.tasks > 1, "1500 lights are split into tasks");
        assert!(stats.pairs > 1000, "{method}: only {} pairs", stats.pairs);
        assert!(stats.parallel, "an assigner's first frame runs on the pool");
        let tasks = stats.tasks;
        // The idle time between calls is 5 ms; only a frame stalled for half a second would
        // count as big, and a few tries are allowed for that.
        let mut serial = None;
        for _ in 0..5 {
            std::thread::sleep(Duration::from_millis(5));
            let mut lists = LightLists::new();
            let stats = frame(&mut lists);
            assert_eq!(
                stats.tasks, tasks,
                "where the tasks run never changes the split"
            );
            if !stats.parallel {
                serial = Some(lists);
                break;
            }
        }
        let serial = serial.unwrap_or_else(|| {
            panic!("{method}, on the pool {on_pool}: a small frame after 5 ms idle runs serially")
        });
        assert!(
            serial == first,
            "{method}, on the pool {on_pool}: serial and parallel lists differ"
        );
    }
}

#[test]
fn an_assigner_set_to_always_runs_every_split_frame_on_the_pool_after_idle_too() {
    // 600 lights of 5 cm: split into tasks, and far under the default pacing's 250 µs of work,
    // so a paced assigner would run them serially after idle.
    let (scene, lights) = small_lights(12, 600);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let input = lights.input(false);
    let mut assigner = Assigner::new().with_parallelism(Parallelism::Always);
    let mut lists = LightLists::new();
    for frame in 0..5 {
        std::thread::sleep(Duration::from_millis(5));
        let stats = pool.install(|| {
            assigner.assign(
                Method::Binary,
                &input,
                &scene.camera,
                &scene.grid,
                &mut lists,
            )
        });
        assert!(stats.tasks > 1, "600 lights are split into tasks");
        assert!(stats.parallel, "frame {frame} after 5 ms idle ran serially");
    }
}

#[test]
fn a_big_frame_after_a_small_one_runs_on_the_pool_after_idle_too() {
    // An engine's frames vary: 1500 lights after 1 (or after none) are ≥ 1500× the work, so
    // they must not run serially because the frame before was small (audit: a 100k-light frame
    // after a 100-light one ran on one thread). Any call takes over 67 ns, so 1500 lights are
    // estimated past the 100 µs set here on any machine; 0 lights give no estimate at all.
    let (scene, lights) = small_lights(13, 1500);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let limits = PacingLimits {
        warm_gap: Duration::from_micros(20),
        cold_work: Duration::from_micros(100),
    };
    let mut assigner = Assigner::new().with_parallelism(Parallelism::PacedWith(limits));
    let mut lists = LightLists::new();
    let mut frame = |lights: &Columns| {
        std::thread::sleep(Duration::from_millis(5));
        pool.install(|| {
            assigner.assign(
                Method::Binary,
                &lights.input(false),
                &scene.camera,
                &scene.grid,
                &mut lists,
            )
        })
    };
    let mut one = Columns::default();
    one.push(glam::Vec3::new(0.0, 0.0, -5.0), 0.05);
    for before in [one, Columns::default()] {
        let small = frame(&before);
        assert!(small.tasks <= 1, "{} lights are not split", before.x.len());
        let big = frame(&lights);
        assert!(big.tasks > 1, "1500 lights are split into tasks");
        assert!(
            big.parallel,
            "1500 lights after {} and 5 ms idle ran serially",
            before.x.len()
        );
    }
}
