//! # Append strategies: partitioned by depth vs shared atomic counters
//!
//! The lock-free per-cluster append can be built two ways (`myriad_assignment::AppendStrategy`):
//! * `PartitionedByDepth` (the default): spans are bucketed by parts (depth slices); per part, in
//!   parallel, a count as a difference array, a scan into list starts and a fill into the part's
//!   own slice of the output — no atomics, no cache line written by two threads, ascending lists
//!   by construction;
//! * `AtomicCounters`: one shared counter per cluster with `fetch_add` in the count and the fill
//!   passes, then a sort of each list to make the output deterministic.
//!
//! Both produce identical lists (tested in `crates/assignment/tests/determinism.rs`); this bench
//! times whole `refined` assignments with each, called from a worker of a pool with one worker
//! per core (as a frame job runs them), over the standard scenes: `cargo bench --bench append`.
//! (Called from outside any pool, the two would also differ in how they get onto it: the
//! partitioned append works beside helper jobs on the calling thread, the atomic one is handed
//! to a worker.)

use criterion::{BenchmarkId, Criterion, Throughput};
use myriad::assignment::{AppendStrategy, Assigner, LightLists, Method};
use myriad::scene::Preset;
use std::hint::black_box;
use std::time::Duration;

fn append_strategies(c: &mut Criterion) {
    let mut group = c.benchmark_group("append");
    group
        .sample_size(20)
        .measurement_time(Duration::from_secs(3));
    let pool = rayon::ThreadPoolBuilder::new()
        .build()
        .expect("cannot start a rayon pool");
    for (preset, lights) in [
        (Preset::Paper, 1_000),
        (Preset::Paper, 20_000),
        (Preset::Uniform, 100_000),
        (Preset::Sphere, 100_000),
    ] {
        let scene = preset.generate(lights, 1);
        let input = myriad::light_input(&scene.lights);
        group.throughput(Throughput::Elements(lights as u64));
        for (name, strategy) in [
            ("partitioned", AppendStrategy::PartitionedByDepth),
            ("atomic", AppendStrategy::AtomicCounters),
        ] {
            let mut assigner = Assigner::new().with_append_strategy(strategy);
            let mut lists = LightLists::new();
            let id = BenchmarkId::new(name, format!("{}-{lights}", preset.name()));
            group.bench_function(id, |b| {
                pool.install(|| {
                    let mut run = || {
                        let lists = &mut lists;
                        assigner.assign(
                            Method::Refined,
                            black_box(&input),
                            &scene.camera,
                            &scene.grid,
                            lists,
                        )
                    };
                    run();
                    b.iter(|| black_box(run()));
                })
            });
        }
    }
    group.finish();
}

criterion::criterion_group!(benches, append_strategies);
criterion::criterion_main!(benches);
