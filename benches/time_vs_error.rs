//! # Time against error: every assignment method's speed beside its accuracy
//!
//! The design brief's "time against error" (the brief is not in this repository) as a criterion
//! bench. For each scene — the three
//! presets with their own grids: `paper` 1000 lights, `uniform` 10 000, `sphere` 100 000 — every
//! method first runs once and is compared pair by pair with `exact` (`myriad::evaluate::compare`).
//! `exact` shares the cull and the box phases with the other methods (it tests each cluster of
//! the box in f64), so this comparison alone cannot see a light both drop: the test suites hold
//! every method, `exact` included, to the independent brute-force oracle, and `myriad bench`
//! compares with lists from that oracle, not from `exact`. A method that misses a pair is not timed: the bench
//! panics naming it, since a fast wrong answer has no place on the table. The error side is
//! printed as a table (pairs, false positives over exact pairs) and written to
//! `<target>/criterion/time_vs_error/error.json`; criterion then times each method as
//! `time_vs_error/<preset>_<lights>/<method>`, so its report holds the other side, with its
//! statistics and its history between runs.
//!
//! `myriad bench --preset P --lights N` prints the same two sides as one table (its medians from
//! repeated calls in one process); this bench is the one to compare builds with.
//!
//! What is timed is what `benches/assignment.rs` times: one steady-state `Assigner::assign` into a
//! reused `LightLists`, called from the benchmark's thread (rayon's global pool runs it), after a
//! warm-up call. Run with `cargo bench --bench time_vs_error` (about a minute on 2 cores; add
//! `--quick` for rough numbers, or a filter such as `-- paper`).

use criterion::{BenchmarkId, Criterion, SamplingMode, Throughput};
use myriad::assignment::{Assigner, LightLists, Method};
use myriad::evaluate::{Comparison, compare};
use myriad::scene::{Preset, Scene};
use serde::Serialize;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

/// Seed of every generated scene.
const SEED: u64 = 1;
/// The scenes: the presets, each with its own camera and grid.
const SCENES: [(Preset, usize); 3] = [
    (Preset::Paper, 1_000),
    (Preset::Uniform, 10_000),
    (Preset::Sphere, 100_000),
];
/// Every method, the reference first.
const METHODS: [Method; 5] = [
    Method::Exact,
    Method::Linear,
    Method::Binary,
    Method::Refined,
    Method::Cone,
];

/// One row of the error side.
#[derive(Serialize)]
struct ErrorRow {
    scene: String,
    method: &'static str,
    #[serde(flatten)]
    comparison: Comparison,
}

/// The scene's name in benchmark ids and the table.
fn scene_name(preset: Preset, lights: usize) -> String {
    format!("{}_{lights}", preset.name())
}

/// Each method's lists on `scene` compared with `exact`'s; panics on a miss.
fn errors(scene_id: &str, scene: &Scene) -> Vec<ErrorRow> {
    let input = myriad::light_input(&scene.lights);
    let mut assigner = Assigner::new();
    let run = |assigner: &mut Assigner, method| {
        let mut lists = LightLists::new();
        assigner.assign(method, &input, &scene.camera, &scene.grid, &mut lists);
        lists
    };
    let exact = run(&mut assigner, Method::Exact);
    METHODS
        .iter()
        .map(|&method| {
            let comparison = compare(&run(&mut assigner, method), &exact);
            assert_eq!(
                comparison.misses,
                0,
                "{scene_id}: {} misses {} of {} exact pairs",
                method.name(),
                comparison.misses,
                comparison.exact_pairs
            );
            ErrorRow {
                scene: scene_id.to_string(),
                method: method.name(),
                comparison,
            }
        })
        .collect()
}

/// Where criterion writes (`CARGO_TARGET_DIR`, else the workspace's `target/`).
fn criterion_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target"))
        .join("criterion")
}

fn time_vs_error(c: &mut Criterion) {
    let mut table = Vec::new();
    let mut group = c.benchmark_group("time_vs_error");
    for (preset, lights) in SCENES {
        let id = scene_name(preset, lights);
        let scene = preset.generate(lights, SEED);
        let rows = errors(&id, &scene);
        println!("{id}: method, pairs, false positives / exact pairs (misses: 0 for every method)");
        for row in &rows {
            println!(
                "  {:<8} {:>9} {:>7.1}%",
                row.method,
                row.comparison.reported_pairs,
                100.0 * row.comparison.false_positive_ratio
            );
        }
        table.extend(rows);
        let input = myriad::light_input(&scene.lights);
        group.throughput(Throughput::Elements(lights as u64));
        for method in METHODS {
            // `exact` and `cone` cost several times the others per light (benches/assignment.rs),
            // and single-threaded `linear` the most of all on `sphere` 100k (4.8 ms a call, where
            // criterion's 30 rising samples would take 2.2 s of a 2 s budget).
            let slow =
                matches!(method, Method::Exact | Method::Cone | Method::Linear) && lights >= 10_000;
            group
                .sampling_mode(if slow {
                    SamplingMode::Flat
                } else {
                    SamplingMode::Auto
                })
                .sample_size(if slow { 10 } else { 30 })
                .warm_up_time(Duration::from_millis(500))
                .measurement_time(Duration::from_secs(2));
            group.bench_function(BenchmarkId::new(&id, method.name()), |b| {
                let mut assigner = Assigner::new();
                let mut lists = LightLists::new();
                let mut run = || {
                    assigner.assign(
                        method,
                        black_box(&input),
                        &scene.camera,
                        &scene.grid,
                        &mut lists,
                    )
                };
                run();
                b.iter(|| black_box(run()));
            });
        }
    }
    group.finish();
    let path = criterion_dir().join("time_vs_error").join("error.json");
    let written = std::fs::create_dir_all(path.parent().unwrap())
        .and_then(|()| std::fs::write(&path, serde_json::to_string_pretty(&table).unwrap() + "\n"));
    match written {
        Ok(()) => println!("error side written to {}", path.display()),
        Err(e) => eprintln!("could not write {}: {e}", path.display()),
    }
}

criterion::criterion_group!(benches, time_vs_error);
criterion::criterion_main!(benches);
