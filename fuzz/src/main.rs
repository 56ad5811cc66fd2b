//! # myriad-fuzz — a stable-toolchain random/mutation fuzz harness
//!
//! **Not coverage-guided.** cargo-fuzz/libFuzzer need a nightly toolchain and instrumentation;
//! this harness runs on stable: a seeded PRNG drives a byte mutator over a small built-in corpus
//! (and a generator of random scenes), so a run is reproducible from `--seed`, and any failing
//! input is written to `fuzz/artifacts/<target>-<iteration>.bin` (the assignment target prints
//! its sub-seed instead: `--subseed S` runs that one input again). It finds panics, hangs (an
//! input running over 20 s ends the run: `watchdog.rs`) and, for the assignment, misses against
//! the f64 oracle. `--inputs N` stops after N inputs (with `--seconds` as well, whichever comes
//! first): a run of a fixed number of inputs checks the same ones on any machine.
//!
//! ```sh
//! cargo run --release -p myriad-fuzz -- scene  --seconds 600 [--seed 1] [--inputs N]
//! cargo run --release -p myriad-fuzz -- gltf   --seconds 600
//! cargo run --release -p myriad-fuzz -- assign --seconds 600 [--subseed S]
//! ```
//!
//! Targets:
//! * `scene`: `Scene::from_json_slice` (strict and lenient) and `validate_json_slice` on mutated
//!   scene files; checks they agree (validation clean ⇔ strict load succeeds).
//! * `gltf`: `Model::from_gltf_slice` on mutated glTF JSON and GLB (`assets/atrium.glb` and a
//!   hand-written triangle); every 64th input also goes through a temp file and `Model::load`,
//!   which must agree. A GLB is mostly mutated chunk by chunk and packed again with lengths that
//!   match (`mutate_glb`): mutated whole, nearly every input changed its length and stopped at
//!   the header's length check. The run prints how many inputs loaded.
//! * `assign`: random camera (fov 0.5–179°, aspect 0.1–10, near 1e-4–10, far/near to 1e5, eye up
//!   to 1e6 away, any orientation), small grid (≤ 8×6×8) and 1–60 lights (points and spots) →
//!   every `Method` conservative against the oracle (`crates/assignment/tests/common`). One input
//!   in 64 is a split frame instead: 512–1511 lights, grid ≤ 16×9×16, tasks on a three-worker
//!   pool, spans bucketed by depth parts.

#![forbid(unsafe_code)]

#[path = "../../crates/assignment/tests/common/mod.rs"]
mod common;
mod watchdog;

use glam::UVec3;
use myriad::assignment::{Assigner, LightLists, Method, Parallelism, SERIAL_LIGHTS};
use myriad::scene::{LightPolicy, LoadOptions, Model, Scene, validate_json_slice};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

const SCENE: &str = include_str!("../../crates/scene/tests/data/hand_written.json");
const ATRIUM: &[u8] = include_bytes!("../../assets/atrium.glb");
const TRIANGLE: &str = r#"{"asset":{"version":"2.0"},
 "buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
 "bufferViews":[{"buffer":0,"byteLength":36}],
 "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","max":[1,1,0],"min":[0,0,0]}],
 "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
 "nodes":[{"mesh":0,"children":[1]},{"translation":[1,2,3]}],
 "cameras":[{"type":"perspective","perspective":{"yfov":1,"znear":0.1,"zfar":100}}],
 "extensionsUsed":["KHR_lights_punctual"],
 "extensions":{"KHR_lights_punctual":{"lights":[{"type":"spot","range":5,"spot":{"outerConeAngle":0.5}}]}},
 "scenes":[{"nodes":[0]}],"scene":0}"#;

/// Tokens the mutator splices in: numbers at the edges of f32/f64/u32, JSON fragments.
const TOKENS: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1e39",
    "1e-50",
    "1e308",
    "1e999",
    "4294967295",
    "4294967296",
    "2147483648",
    "18446744073709551616",
    "NaN",
    "Infinity",
    "null",
    "true",
    "\"\"",
    "[]",
    "{}",
    "[0,0,0]",
    "[1e38,1e38,1e38]",
    "\"log\"",
    "\"log_near\"",
    "\"linear\"",
    ",",
    ":",
    "[",
    "]",
    "{",
    "}",
    "\"",
    "\\u0000",
    "\"spot\":{\"direction\":[0,0,0],\"angle_deg\":180}",
    "\"spot\":{\"direction\":[0,-1,0],\"angle_deg\":30,\"inner_angle_deg\":29.999999}",
    "\"inner_angle_deg\":1e-50",
    "\"angle_deg\":1e-43",
    "\"children\":[0]",
    "\"count\":2147483648",
    "\"byteOffset\":4294967295",
    "\"indices\":0",
    "\"matrix\":[0]",
];

fn mutate(rng: &mut Pcg64, input: &[u8]) -> Vec<u8> {
    let mut v = input.to_vec();
    for _ in 0..rng.random_range(1..=6) {
        let len = v.len();
        let at = if len == 0 {
            0
        } else {
            rng.random_range(0..len)
        };
        match rng.random_range(0..8) {
            0 if len > 0 => v[at] = rng.random(),
            1 if len > 0 => v[at] ^= 1 << rng.random_range(0..8),
            2 => {
                let end = (at + rng.random_range(0..64)).min(len);
                v.drain(at..end);
            }
            3 => {
                let t = TOKENS[rng.random_range(0..TOKENS.len())].as_bytes();
                v.splice(at..at, t.iter().copied());
            }
            4 => {
                // Replace a run of digits (a number) by a token.
                let end = (at..len)
                    .find(|&i| !v[i].is_ascii_digit() && v[i] != b'.')
                    .unwrap_or(len);
                let t = TOKENS[rng.random_range(0..TOKENS.len())].as_bytes();
                v.splice(at..end, t.iter().copied());
            }
            5 if len > 0 => {
                // Duplicate a chunk.
                let end = (at + rng.random_range(1..256)).min(len);
                let chunk = v[at..end].to_vec();
                let to = rng.random_range(0..=len);
                v.splice(to..to, chunk);
            }
            6 => v.truncate(at),
            _ if len > 0 => {
                // Overwrite four bytes with an extreme u32 (binary chunks, GLB headers).
                let x: u32 = [0, 1, u32::MAX, 0x8000_0000, rng.random()][rng.random_range(0..5)];
                for (k, b) in x.to_le_bytes().iter().enumerate() {
                    if at + k < len {
                        v[at + k] = *b;
                    }
                }
            }
            _ => {}
        }
    }
    v
}

/// A GLB's JSON and BIN chunks, when `bytes` is one whose chunk lengths hold together.
fn glb_chunks(bytes: &[u8]) -> Option<(&[u8], &[u8])> {
    let word = |at: usize| -> Option<usize> {
        let b = bytes.get(at..at + 4)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    if bytes.get(..4)? != b"glTF" {
        return None;
    }
    let json_len = word(12)?;
    let json = bytes.get(20..20 + json_len)?;
    let bin_at = 20 + json_len;
    let bin_len = word(bin_at)?;
    let bin = bytes.get(bin_at + 8..bin_at + 8 + bin_len)?;
    Some((json, bin))
}

/// `bytes` mutated: a GLB (seven times in eight) chunk by chunk — its JSON by [`mutate`], its
/// BIN by in-place changes that keep its length — and packed again with matching lengths, so
/// the loader gets past the container's checks; anything else byte by byte.
fn mutate_glb(rng: &mut Pcg64, bytes: &[u8]) -> Vec<u8> {
    let Some((json, bin)) = glb_chunks(bytes).filter(|_| !rng.random_bool(1.0 / 8.0)) else {
        return mutate(rng, bytes);
    };
    let json = if rng.random_bool(0.8) {
        mutate(rng, json)
    } else {
        json.to_vec()
    };
    let mut bin = bin.to_vec();
    if !bin.is_empty() && rng.random_bool(0.3) {
        for _ in 0..rng.random_range(1..=4) {
            let at = rng.random_range(0..bin.len());
            bin[at] = rng.random();
        }
    }
    myriad::scene::glb_container(json, bin)
}

fn save_artifact(target: &str, iteration: u64, bytes: &[u8]) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("artifacts");
    std::fs::create_dir_all(&dir).expect("artifacts folder");
    let path = dir.join(format!("{target}-{iteration}.bin"));
    std::fs::write(&path, bytes).expect("write artifact");
    path
}

fn scene_once(bytes: &[u8]) {
    let strict = Scene::from_json_slice(bytes, "fuzz.json", LightPolicy::Strict);
    let lenient = Scene::from_json_slice(bytes, "fuzz.json", LightPolicy::SkipInvalid);
    if let Ok(report) = validate_json_slice(bytes, "fuzz.json") {
        assert_eq!(report.is_valid(), strict.is_ok(), "validate vs strict load");
        if let Ok(s) = &lenient {
            assert_eq!(
                s.lights.len(),
                report.lights_ok(),
                "lenient lights vs report"
            );
            assert!(s.problems().is_empty(), "a loaded scene must be writable");
        }
    } else {
        assert!(
            strict.is_err() && lenient.is_err(),
            "JSON error only in validation"
        );
    }
}

/// Loads `bytes` as a glTF or GLB; returns whether it loaded. Through a file as well where
/// `through_file` is given, which must agree.
fn gltf_once(bytes: &[u8], through_file: Option<&std::path::Path>) -> bool {
    let options = LoadOptions::without_images();
    let loaded = Model::from_gltf_slice(bytes, "fuzz.gltf", None, &options).is_ok();
    if let Some(dir) = through_file {
        let path = dir.join("fuzz.gltf");
        std::fs::write(&path, bytes).expect("temp file");
        let from_file = Model::load(&path, &options).is_ok();
        assert_eq!(
            from_file, loaded,
            "loaded from a file {from_file}, from memory {loaded}"
        );
    }
    loaded
}

/// The pools `assign` inputs run on: one worker (a single task) and three (a split frame).
struct Pools {
    one: rayon::ThreadPool,
    three: rayon::ThreadPool,
}

impl Pools {
    fn new() -> Self {
        let pool = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("cannot start a rayon pool")
        };
        Self {
            one: pool(1),
            three: pool(3),
        }
    }
}

fn assign_once(rng: &mut Pcg64, pools: &Pools) -> String {
    let eye_scale = match rng.random_range(0..3) {
        0 => 0.0,
        1 => 10f32.powf(rng.random_range(0.0..3.0)),
        _ => 1.0e6,
    };
    // One input in 64 splits the frame into tasks (more lights than `SERIAL_LIGHTS`, on a
    // pool of three workers, never paced off it): depth parts filled in parallel.
    let split = rng.random_bool(1.0 / 64.0);
    let (max_dims, lights) = if split {
        (
            UVec3::new(17, 10, 17),
            rng.random_range(SERIAL_LIGHTS..SERIAL_LIGHTS + 1000),
        )
    } else {
        (UVec3::new(9, 7, 9), rng.random_range(1..61))
    };
    let params = common::SceneParams {
        seed: rng.random(),
        fov_deg: rng.random_range(0.5..179.0),
        aspect: 10f32.powf(rng.random_range(-1.0..1.0)),
        near: 10f32.powf(rng.random_range(-4.0..1.0)),
        far_ratio: 10f32.powf(rng.random_range(0.2..5.0)),
        eye_scale,
        dims: UVec3::new(
            rng.random_range(1..max_dims.x),
            rng.random_range(1..max_dims.y),
            rng.random_range(1..max_dims.z),
        ),
        slicing: rng.random_range(0..3),
        lights,
        spots: rng.random_bool(0.5),
    };
    let context = format!("{params:?}");
    let scene = common::make_scene(&params);
    let truth = common::brute_force(&scene.lights, params.spots, &scene.camera, &scene.grid);
    let pool = if split { &pools.three } else { &pools.one };
    pool.install(|| {
        let mut assigner = Assigner::new().with_parallelism(Parallelism::Always);
        let mut lists = LightLists::new();
        for method in Method::ALL {
            let stats = assigner.assign(
                method,
                &scene.lights.input(params.spots),
                &scene.camera,
                &scene.grid,
                &mut lists,
            );
            let (_, extra) = common::assert_conservative(method.name(), &lists, &truth, &context);
            assert_eq!(stats.pairs as usize, lists.indices.len(), "{context}");
            if method == Method::Exact {
                assert_eq!(extra, 0, "exact has {extra} false positives ({context})");
            }
            let pooled = stats.parallel && stats.tasks > 1;
            assert!(
                method == Method::Linear || pooled == split,
                "{}: split {split}, ran on the pool {pooled} ({context})",
                method.name()
            );
        }
    });
    context
}

struct Args {
    target: String,
    seconds: f64,
    seed: u64,
    /// Stop after this many inputs.
    inputs: u64,
    /// Run this one `assign` input (a sub-seed a failure printed) and stop.
    subseed: Option<u64>,
}

fn parse_args() -> Result<Args, String> {
    let mut it = std::env::args().skip(1);
    let target = it.next().ok_or(
        "usage: myriad-fuzz <scene|gltf|assign> [--seconds N] [--seed S] [--inputs N] \
             [--subseed S]",
    )?;
    let (mut seconds, mut seed, mut inputs, mut subseed) = (10.0, 1, u64::MAX, None);
    while let Some(flag) = it.next() {
        let value = it.next().ok_or(format!("{flag} needs a value"))?;
        match flag.as_str() {
            "--seconds" => seconds = value.parse().map_err(|e| format!("--seconds: {e}"))?,
            "--seed" => seed = value.parse().map_err(|e| format!("--seed: {e}"))?,
            "--inputs" => inputs = value.parse().map_err(|e| format!("--inputs: {e}"))?,
            "--subseed" => {
                subseed = Some(value.parse().map_err(|e| format!("--subseed: {e}"))?);
            }
            _ => return Err(format!("unknown option {flag}")),
        }
    }
    if subseed.is_some() && target != "assign" {
        return Err("--subseed replays an assign input".into());
    }
    Ok(Args {
        target,
        seconds,
        seed,
        inputs,
        subseed,
    })
}

fn main() {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    // Panics are caught and reported per input; keep their messages short.
    std::panic::set_hook(Box::new(|info| eprintln!("panic: {info}")));
    let mut rng = Pcg64::seed_from_u64(args.seed);
    let corpus: Vec<Vec<u8>> = match args.target.as_str() {
        "scene" => vec![SCENE.as_bytes().to_vec(), b"{}".to_vec()],
        "gltf" => vec![TRIANGLE.as_bytes().to_vec(), ATRIUM.to_vec()],
        "assign" => Vec::new(),
        other => {
            eprintln!("unknown target {other}: scene, gltf or assign");
            std::process::exit(2);
        }
    };
    let pools = Pools::new();
    if let Some(subseed) = args.subseed {
        let context = assign_once(&mut Pcg64::seed_from_u64(subseed), &pools);
        println!("assign: sub-seed {subseed} passed: {context}");
        return;
    }
    let temp = std::env::temp_dir().join(format!("myriad-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&temp).expect("temp folder");
    let limit = Duration::from_secs_f64(args.seconds);
    // A hang or pathological-time detector, not a speed test: far above any input's normal time
    // (milliseconds), so a loaded CI machine cannot trip it.
    let slow = Duration::from_secs(20);
    let watch = watchdog::Watch::start(args.target.clone(), args.seed, slow, save_artifact);
    let start = Instant::now();
    let (mut iterations, mut failures, mut slowest) = (0u64, 0u64, Duration::ZERO);
    let mut loaded = 0u64;
    let no_input = Arc::new(Vec::new());
    while start.elapsed() < limit && iterations < args.inputs {
        let t = Instant::now();
        let (input, subseed, outcome) = if args.target == "assign" {
            let subseed = rng.random();
            watch.begin(iterations, &no_input, subseed);
            let outcome = catch_unwind(AssertUnwindSafe(|| {
                assign_once(&mut Pcg64::seed_from_u64(subseed), &pools);
            }));
            (Arc::clone(&no_input), subseed, outcome)
        } else {
            // Mostly mutate the corpus; sometimes mutate a mutant further.
            let base = &corpus[rng.random_range(0..corpus.len())];
            let gltf = args.target == "gltf";
            let change = |rng: &mut Pcg64, bytes: &[u8]| {
                if gltf {
                    mutate_glb(rng, bytes)
                } else {
                    mutate(rng, bytes)
                }
            };
            let mut input = change(&mut rng, base);
            if rng.random_bool(0.3) {
                input = change(&mut rng, &input);
            }
            let input = Arc::new(input);
            watch.begin(iterations, &input, 0);
            let through = (iterations % 64 == 0).then_some(temp.as_path());
            let outcome = catch_unwind(AssertUnwindSafe(|| match args.target.as_str() {
                "scene" => scene_once(&input),
                _ => loaded += u64::from(gltf_once(&input, through)),
            }));
            (input, 0, outcome)
        };
        watch.end();
        let took = t.elapsed();
        slowest = slowest.max(took);
        if outcome.is_err() || took > slow {
            failures += 1;
            let what = if outcome.is_err() {
                "panic"
            } else {
                "slow input"
            };
            if args.target == "assign" {
                eprintln!(
                    "{what} at iteration {iterations} (seed {}, sub-seed {subseed}: --subseed \
                     {subseed} runs it alone)",
                    args.seed
                );
            } else {
                let path = save_artifact(&args.target, iterations, &input);
                eprintln!("{what} at iteration {iterations}: saved {}", path.display());
            }
        }
        iterations += 1;
    }
    let _ = std::fs::remove_dir_all(&temp);
    let loads = if args.target == "gltf" {
        format!(" ({loaded} loaded)")
    } else {
        String::new()
    };
    println!(
        "{}: {iterations} inputs{loads} in {:.1} s (seed {}), {failures} failures, slowest input \
         {:.1} ms",
        args.target,
        start.elapsed().as_secs_f64(),
        args.seed,
        slowest.as_secs_f64() * 1e3
    );
    if failures > 0 {
        std::process::exit(1);
    }
}
