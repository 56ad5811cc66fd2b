//! # Light-assignment benches: scaling over grids × light counts × methods, and the targets
//!
//! Run everything with `cargo bench --bench assignment` (about 5 minutes on a 2-core machine, by
//! the settings in [`timing`]), or a part by criterion's filter:
//! `cargo bench --bench assignment -- targets`, `-- scaling/32x18x48/refined`; add `--quick` for
//! rough numbers fast (the whole bench in under a minute).
//!
//! ## Groups
//! * **`scaling/XxYxZ`** — the `uniform` preset's camera (1920×1080, 60°, near 0.1, far 100) and its
//!   seeded lights (uniform in the frustum's volume, radii 0.2–1.5), with the grid overridden to each
//!   of 24×12×16, 16×9×24 and 32×18×48 (log slicing over the camera's near/far), and
//!   10, 1 000, 10 000, 100 000 and 1 000 000 lights. Benchmark ids are `method/lights`.
//!   Every method runs at every size, the oracle-backed `exact` and the single-threaded
//!   `linear` included: at 1M lights a run of either takes a tenth of a second or more, so the
//!   biggest cells take flat sampling, 10 samples of as many runs each as the measurement time
//!   holds (see [`timing`]).
//! * **`targets`** — exactly the issue's target configurations, with each preset's own grid:
//!   `paper` 1000 lights (`linear`, `binary`, `refined`; the paper's 1.04 ms reference),
//!   `uniform` 100k `refined` on a pool of two workers and on a 1-thread pool (thread
//!   scaling; every `targets` pool has two workers, [`TARGET_THREADS`], on any host, as the
//!   issue's 2-core machine), `uniform` 1M `refined`, `sphere` 100k (`binary`, `refined`; the single-threaded
//!   engine reference of 1.5–2.1 ms). These run as a frame job would, on a pool worker (the timed
//!   loop inside `ThreadPool::install`); `paper/*-from-outside` time the same calls from the
//!   benchmark's own thread, which works alongside helper jobs it spawns on rayon's pool
//!   (`OutsideCalls::Join`), `paper/*-from-outside-hand-off` with `OutsideCalls::HandOff`, which
//!   pays the hand-off to rayon's pool and back every frame, and
//!   `paper/*-from-pool-member` from a thread that joined its pool (`use_current_thread`), as an
//!   engine's main thread can.
//!   `scaling` calls from outside too.
//! * **`far_edge`** — what counting the lights past the grid's far edge costs: `uniform` 100k
//!   `refined` on one worker, with the camera's far at the grid's and infinite, and with a grid
//!   out to half the camera's far, open and closed (see [`far_edge`]).
//!
//! ## What is timed
//! One `Assigner::assign` call into a reused `LightLists`: the steady state of a frame, where the
//! assigner's scratch and the output vectors have already grown (a warm-up call runs before
//! timing), so the lists and scratch are not allocated in the timed calls. (Calls from outside
//! any pool, `scaling`'s and `*-from-outside`, still pay rayon's boxed helper jobs, a few small
//! allocations a frame: `OutsideCalls::Join`'s documented cost. Criterion rebuilds the assigner
//! and repeats the warm-up once per sample.) Throughput is reported in lights per second.
//! Scenes are generated from a fixed seed, so every run sees the same lights; each scene is made
//! only when a benchmark that needs it runs (filters skip the 1M-light generation).
//!
//! Sample sizes shrink as inputs grow (see [`timing`]) so the whole bench stays within minutes:
//! 50 samples for small inputs, 20 around 100k lights, 10 for the biggest.

use criterion::{
    BenchmarkGroup, BenchmarkId, Criterion, SamplingMode, Throughput, measurement::WallTime,
};
use myriad::assignment::{Assigner, LightLists, Method, OutsideCalls};
use myriad::cluster_math::{ClusterGrid, DepthSlicing, OuterSlices, glam::UVec3};
use myriad::scene::{Preset, Scene};
use std::cell::OnceCell;
use std::hint::black_box;
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Seed of every generated scene.
const SEED: u64 = 1;
/// Grids of the scaling groups, all with log slicing.
const GRIDS: [[u32; 3]; 3] = [[24, 12, 16], [16, 9, 24], [32, 18, 48]];
/// Light counts of the scaling groups.
const LIGHT_COUNTS: [usize; 5] = [10, 1_000, 10_000, 100_000, 1_000_000];
/// Methods of the scaling groups.
const METHODS: [Method; 5] = [
    Method::Linear,
    Method::Binary,
    Method::Refined,
    Method::Cone,
    Method::Exact,
];

/// Sample size, warm-up and measurement time for one benchmark, by its rough cost per run.
fn timing(group: &mut BenchmarkGroup<'_, WallTime>, method: Method, lights: usize) {
    // The oracle costs a few times what the fast methods do per light (2–4x at 10k lights here).
    // `cone`'s per-tile tests cost several times `refined`'s per light (4–15x here), and
    // `linear`, one thread through every plane, as much (its 1M cell takes a tenth of a second
    // and more, which the module docs give flat sampling).
    let weight = match method {
        Method::Exact | Method::Cone | Method::Linear => 4 * lights,
        _ => lights,
    };
    let (samples, warm_up, measurement) = match weight {
        0..=10_000 => (50, 0.5, 2.0),
        10_001..=100_000 => (20, 0.5, 2.0),
        100_001..=1_000_000 => (10, 0.5, 3.0),
        _ => (10, 1.0, 5.0),
    };
    // Runs of a tenth of a second and more: the same number of runs in every sample, not
    // criterion's rising 1..=10·k iterations (55k runs).
    let sampling = if weight > 1_000_000 {
        SamplingMode::Flat
    } else {
        SamplingMode::Auto
    };
    group
        .sampling_mode(sampling)
        .sample_size(samples)
        .warm_up_time(Duration::from_secs_f64(warm_up))
        .measurement_time(Duration::from_secs_f64(measurement));
}

/// Where the timed calls come from.
#[derive(Clone, Copy)]
enum Caller<'a> {
    /// A worker of this pool, as a frame job of an engine's job system: the whole timed loop runs
    /// inside `ThreadPool::install`, so the assignment's parallel regions start on the spot.
    Worker(&'a rayon::ThreadPool),
    /// The benchmark's own thread, outside any pool, as an engine's main thread: with
    /// `OutsideCalls::Join` (the default) it works on each parallel frame alongside helper jobs
    /// it spawns on rayon's global pool; with `HandOff` the frame is handed to a worker and this
    /// thread woken when it is done.
    Outside(OutsideCalls),
}

/// A thread of the benchmark's own that is also worker 0 of a pool of one worker per core
/// (`ThreadPoolBuilder::use_current_thread`): an engine's main thread made a member of its job
/// pool, as "Things to know" in docs/engine-guide.md suggests. Its calls start their parallel regions on the
/// spot, as a worker's do, with no hand-off. It owns its scene, assigner and lists (a thread
/// that joins a pool stays in it, so the timed loop runs there, not on criterion's thread).
struct PoolMember {
    requests: mpsc::Sender<(Method, u64)>,
    elapsed: mpsc::Receiver<Duration>,
}

impl PoolMember {
    /// Starts the thread, which joins its pool and generates `lights` lights of `preset`.
    fn start(preset: Preset, lights: usize) -> Self {
        let (requests, calls) = mpsc::channel::<(Method, u64)>();
        let (times, elapsed) = mpsc::channel();
        std::thread::spawn(move || {
            let _pool = rayon::ThreadPoolBuilder::new()
                .num_threads(TARGET_THREADS)
                .use_current_thread()
                .build()
                .expect("cannot start a rayon pool with this thread in it");
            let scene = preset.generate(lights, SEED);
            let input = myriad::light_input(&scene.lights);
            let mut assigner = Assigner::new();
            let mut lists = LightLists::new();
            for (method, iterations) in calls {
                let mut run = || {
                    let lists = &mut lists;
                    assigner.assign(method, black_box(&input), &scene.camera, &scene.grid, lists)
                };
                run();
                let start = Instant::now();
                for _ in 0..iterations {
                    black_box(run());
                }
                if times.send(start.elapsed()).is_err() {
                    return;
                }
            }
        });
        Self { requests, elapsed }
    }

    /// Time of `iterations` calls of `method` in a row on the member thread (after one untimed).
    fn time(&self, method: Method, iterations: u64) -> Duration {
        self.requests
            .send((method, iterations))
            .expect("the pool member thread stopped");
        self.elapsed.recv().expect("the pool member thread stopped")
    }
}

/// Times `method` on `lights` lights of `preset` (generated on first use into `scene`, then kept
/// for the other benchmarks) with the preset's grid or `grid`, called by `caller`: one reused
/// `Assigner` and `LightLists`, warmed up before timing.
fn bench_assign(
    group: &mut BenchmarkGroup<'_, WallTime>,
    id: BenchmarkId,
    method: Method,
    (preset, lights, scene): (Preset, usize, &OnceCell<Scene>),
    grid: Option<ClusterGrid>,
    caller: Caller<'_>,
) {
    timing(group, method, lights);
    group.throughput(Throughput::Elements(lights as u64));
    group.bench_function(id, |b| {
        let scene = scene.get_or_init(|| preset.generate(lights, SEED));
        let grid = grid.unwrap_or(scene.grid);
        let input = myriad::light_input(&scene.lights);
        let mut assigner = match caller {
            Caller::Outside(calls) => Assigner::new().with_outside_calls(calls),
            Caller::Worker(_) => Assigner::new(),
        };
        let mut lists = LightLists::new();
        let mut timed = || {
            let mut run = || {
                let lists = &mut lists;
                assigner.assign(method, black_box(&input), &scene.camera, &grid, lists)
            };
            run();
            b.iter(|| black_box(run()));
        };
        match caller {
            Caller::Worker(pool) => pool.install(timed),
            Caller::Outside(_) => timed(),
        }
        black_box(&lists);
    });
}

fn scaling(c: &mut Criterion) {
    let (camera, _) = Preset::Uniform.view();
    let scenes: Vec<OnceCell<Scene>> = LIGHT_COUNTS.iter().map(|_| OnceCell::new()).collect();
    for [x, y, z] in GRIDS {
        let grid = ClusterGrid::new(
            UVec3::new(x, y, z),
            DepthSlicing::Log,
            camera.near,
            camera.far,
        );
        let mut group = c.benchmark_group(format!("scaling/{x}x{y}x{z}"));
        for (&lights, scene) in LIGHT_COUNTS.iter().zip(&scenes) {
            for method in METHODS {
                let id = BenchmarkId::new(method.name(), lights);
                let source = (Preset::Uniform, lights, scene);
                let caller = Caller::Outside(OutsideCalls::Join);
                bench_assign(&mut group, id, method, source, Some(grid), caller);
            }
        }
        group.finish();
    }
}

/// Workers of the `targets` pools: the targets are for a 2-core machine, so two on any
/// host (one worker per core on a bigger one would time another machine's frame).
const TARGET_THREADS: usize = 2;

fn targets(c: &mut Criterion) {
    let mut group = c.benchmark_group("targets");
    // Two workers, as the targets' machine has; and one worker, for the thread scaling.
    let pool = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("cannot start a rayon pool")
    };
    let (all_cores, one_thread) = (pool(TARGET_THREADS), pool(1));
    let worker = Caller::Worker(&all_cores);
    // A parallel timing follows the link between the workers' cores, which a shared machine
    // changes from minute to minute (docs/results.md, "Measured"): print it with the timings.
    let link = || all_cores.install(myriad::core_link::measure);
    eprintln!("targets: thread link before {:?}", link());

    let paper = (Preset::Paper, 1_000, &OnceCell::new());
    for method in [Method::Linear, Method::Binary, Method::Refined] {
        let id = BenchmarkId::new(format!("paper/{}", method.name()), 1_000);
        bench_assign(&mut group, id, method, paper, None, worker);
    }
    // The same from outside any pool, the caller working alongside helpers (the default) and
    // handing the frame off: what a 1000-light frame pays for being called from outside.
    for method in [Method::Binary, Method::Refined] {
        for (calls, suffix) in [
            (OutsideCalls::Join, ""),
            (OutsideCalls::HandOff, "-hand-off"),
        ] {
            let name = format!("paper/{}-from-outside{suffix}", method.name());
            let id = BenchmarkId::new(name, 1_000);
            bench_assign(&mut group, id, method, paper, None, Caller::Outside(calls));
        }
    }
    // And from a thread that joined the pool, as an engine's main thread can: no hand-off.
    let member = PoolMember::start(Preset::Paper, 1_000);
    for method in [Method::Binary, Method::Refined] {
        let id = BenchmarkId::new(format!("paper/{}-from-pool-member", method.name()), 1_000);
        timing(&mut group, method, 1_000);
        group.throughput(Throughput::Elements(1_000));
        group.bench_function(id, |b| b.iter_custom(|n| member.time(method, n)));
    }

    let uniform_100k = (Preset::Uniform, 100_000, &OnceCell::new());
    let id = BenchmarkId::new("uniform/refined", 100_000);
    bench_assign(&mut group, id, Method::Refined, uniform_100k, None, worker);
    let id = BenchmarkId::new("uniform/refined-1-thread", 100_000);
    let single = Caller::Worker(&one_thread);
    bench_assign(&mut group, id, Method::Refined, uniform_100k, None, single);

    let uniform_1m = (Preset::Uniform, 1_000_000, &OnceCell::new());
    let id = BenchmarkId::new("uniform/refined", 1_000_000);
    bench_assign(&mut group, id, Method::Refined, uniform_1m, None, worker);

    let sphere = (Preset::Sphere, 100_000, &OnceCell::new());
    for method in [Method::Binary, Method::Refined] {
        let id = BenchmarkId::new(format!("sphere/{}", method.name()), 100_000);
        bench_assign(&mut group, id, method, sphere, None, worker);
    }
    group.finish();
    eprintln!("targets: thread link after {:?}", link());
}

/// What counting the lights past the grid's far edge costs (`AssignStats::beyond_far` and
/// `reach`, a pass only in frames whose camera sees past the grid): `uniform` 100k `refined` on
/// one worker with the preset's grid, under the preset's camera (far 100, the grid's: nothing
/// counted) and under the same camera with an infinite far plane (an engine's infinite
/// projection: every light is also tested against it). Then what an open last slice costs
/// (`OuterSlices`): the preset's grid cut to half the camera's far, open (the lights past it listed
/// in its last slice) and closed (culled).
fn far_edge(c: &mut Criterion) {
    let mut group = c.benchmark_group("far_edge");
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("cannot start a rayon pool");
    let scene = OnceCell::new();
    for (name, far, half_grid) in [
        ("uniform/refined-grid-to-camera-far", None, None),
        (
            "uniform/refined-camera-sees-past",
            Some(f32::INFINITY),
            None,
        ),
        (
            "uniform/refined-half-grid-open",
            None,
            Some(OuterSlices::Open),
        ),
        (
            "uniform/refined-half-grid-closed",
            None,
            Some(OuterSlices::Closed),
        ),
    ] {
        timing(&mut group, Method::Refined, 100_000);
        group.throughput(Throughput::Elements(100_000));
        let mut told = false;
        group.bench_function(BenchmarkId::new(name, 100_000), |b| {
            let scene: &Scene = scene.get_or_init(|| Preset::Uniform.generate(100_000, SEED));
            let camera = myriad::cluster_math::Camera {
                far: far.unwrap_or(scene.camera.far),
                ..scene.camera
            };
            let grid = match half_grid {
                Some(edge) => {
                    let g = scene.grid;
                    g.with_depth_range(g.near(), camera.far / 2.0)
                        .with_outer_slices(edge)
                }
                None => scene.grid,
            };
            let input = myriad::light_input(&scene.lights);
            let (mut assigner, mut lists) = (Assigner::new(), LightLists::new());
            one_thread.install(|| {
                let mut run = || {
                    let input = black_box(&input);
                    assigner.assign(Method::Refined, input, &camera, &grid, &mut lists)
                };
                let stats = run();
                assert_eq!(stats.reach.is_some(), far.is_some() || half_grid.is_some());
                if !std::mem::replace(&mut told, true) {
                    eprintln!(
                        "far_edge/{name}: {} pairs, {} culled, {} beyond the grid",
                        stats.pairs, stats.culled, stats.beyond_far
                    );
                }
                b.iter(|| black_box(run()));
            });
        });
    }
    group.finish();
}

criterion::criterion_group!(benches, targets, scaling, far_edge);
criterion::criterion_main!(benches);
