//! End-to-end tests of the `myriad` binary: every subcommand run as a user runs it, through
//! files on disk, checking exit codes, messages and the JSON the tools write.
//!
//! Tests of commands that render (`render`, the main job, `frames`, `paper`, `skips`, `stress`)
//! first ask for an adapter exactly as the library's GPU tests do ([`gpu_available`]): without
//! one they fail with advice, or return early when `MYRIAD_SKIP_GPU_TESTS=1` says so.
//!
//! Each test works in its own folder under cargo's `CARGO_TARGET_TMPDIR`, so tests run in
//! parallel without sharing files. Scenes are small (hundreds of lights). One module per group of
//! subcommands; this file holds what they share: the hand-written scene, folders, running the
//! binary and reading what it writes.

mod assign_check_bench;
mod options;
mod render;
mod scene_files;
mod studies;

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A scene in the scene-file format (README, "Scene files"), written by hand: four valid lights, one of them a spot.
const GOOD_SCENE: &str = r#"{
  "camera": {"position": [0, 2, 10], "target": [0, 2, 0], "up": [0, 1, 0], "fov_y_deg": 60,
             "width": 1536, "height": 768, "near": 0.1, "far": 100},
  "grid":   {"x": 24, "y": 12, "z": 16, "depth": "log"},
  "lights": [{"position": [0, 2, 0], "radius": 2, "color": [1, 0.5, 0.2], "intensity": 4},
             {"position": [3, 1, -5], "radius": 4},
             {"position": [-2, 3, 2], "radius": 1.5, "color": [0, 0, 1], "intensity": 1},
             {"position": [0, 5, 0], "radius": 8, "spot": {"direction": [0, -1, 0], "angle_deg": 30}}]
}"#;

/// The camera and grid of [`GOOD_SCENE`] around a `lights` array.
fn scene_with_lights(lights: &str) -> String {
    format!(
        r#"{{
  "camera": {{"position": [0, 2, 10], "target": [0, 2, 0], "up": [0, 1, 0], "fov_y_deg": 60,
             "width": 1536, "height": 768, "near": 0.1, "far": 100}},
  "grid":   {{"x": 24, "y": 12, "z": 16, "depth": "log"}},
  "lights": [{lights}]
}}"#
    )
}

/// A fresh, empty folder for one test.
fn work_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("cli")
        .join(test);
    if dir.exists() {
        std::fs::remove_dir_all(&dir).unwrap();
    }
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes `text` to `dir/name` and returns the path.
fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Whether the GPU tests may run: an adapter exists (else a panic with advice), or `None` from
/// [`myriad::gpu::GpuContext::headless_for_tests`] because `MYRIAD_SKIP_GPU_TESTS=1`.
fn gpu_available() -> bool {
    myriad::gpu::GpuContext::headless_for_tests().is_some()
}

/// Whether the test adapter stops shader loops (llvmpipe), so frames past its budget must be
/// refused. Tests pick their expectation from this, never from the output they check.
fn adapter_limits_loops() -> bool {
    myriad::gpu::GpuContext::headless_for_tests()
        .expect("no adapter")
        .shader_loop_limit()
        .is_some()
}

/// Runs `myriad` with `args`.
fn myriad<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_myriad"))
        .args(args)
        .output()
        .expect("cannot run the myriad binary")
}

/// Runs `myriad` with `args`, killing it and failing the test if it has not finished within
/// `seconds` (for runs that once hung, such as an input naming a FIFO).
fn myriad_within<S: AsRef<std::ffi::OsStr>>(seconds: u64, args: &[S]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_myriad"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("cannot run the myriad binary");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(seconds);
    while child.try_wait().unwrap().is_none() {
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!(
                "myriad {:?} still ran after {seconds} s",
                args.iter().map(|a| a.as_ref()).collect::<Vec<_>>()
            );
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Both streams, for messages whose stream does not matter to the user.
fn all_output(out: &Output) -> String {
    format!("{}{}", stdout(out), stderr(out))
}

/// Runs `myriad` and asserts it succeeded.
fn myriad_ok<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Output {
    let out = myriad(args);
    assert!(
        out.status.success(),
        "myriad {:?} failed ({}):\n{}",
        args.iter().map(|a| a.as_ref()).collect::<Vec<_>>(),
        out.status,
        all_output(&out)
    );
    out
}

/// Runs `myriad` and asserts it stopped as a run that could not finish (exit code 2: bad input,
/// unreadable or unwritable files, usage errors), not with a panic; returns both streams.
fn myriad_fails<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> String {
    myriad_exits(2, args)
}

/// Runs `myriad` and asserts it exited with `code` (1: a verdict, such as a scene file with
/// problems; 2: an error) and did not panic; returns both streams. A panic exits with 101, and
/// its message may echo the needles a test looks for, so "failed" alone proves too little.
fn myriad_exits<S: AsRef<std::ffi::OsStr>>(code: i32, args: &[S]) -> String {
    let out = myriad(args);
    let text = all_output(&out);
    assert_eq!(
        out.status.code(),
        Some(code),
        "myriad {:?} should have exited with {code}:\n{text}",
        args.iter().map(|a| a.as_ref()).collect::<Vec<_>>(),
    );
    assert!(!text.contains("panicked"), "myriad panicked:\n{text}");
    text
}

fn assert_mentions(text: &str, needles: &[&str]) {
    for needle in needles {
        assert!(text.contains(needle), "expected {needle:?} in:\n{text}");
    }
}

/// Each argument list must fail, with output mentioning each of its needles.
fn assert_rejected(cases: &[(&[&str], &[&str])]) {
    for (args, needles) in cases {
        assert_mentions(&myriad_fails(args), needles);
    }
}

/// `myriad scene --preset paper --lights N` into `dir/paper.json`; its path.
fn paper_scene(dir: &Path, lights: usize) -> PathBuf {
    let scene = dir.join("paper.json");
    myriad_ok(&[
        "scene".as_ref(),
        "--preset".as_ref(),
        "paper".as_ref(),
        "--lights".as_ref(),
        lights.to_string().as_ref(),
        "--out".as_ref(),
        scene.as_os_str(),
    ]);
    scene
}

/// `myriad assign` then `myriad check --json`; returns the parsed comparison.
fn assign_and_check(scene: &Path, method: &str, dump: &Path) -> Value {
    myriad_ok(&[
        "assign".as_ref(),
        "--scene".as_ref(),
        scene.as_os_str(),
        "--method".as_ref(),
        method.as_ref(),
        "--out".as_ref(),
        dump.as_os_str(),
    ]);
    check_json(scene, dump)
}

/// `myriad check --json` (must succeed); the parsed comparison.
fn check_json(scene: &Path, dump: &Path) -> Value {
    let out = myriad_ok(&[
        "check".as_ref(),
        "--scene".as_ref(),
        scene.as_os_str(),
        "--dump".as_ref(),
        dump.as_os_str(),
        "--json".as_ref(),
    ]);
    let cmp: Value =
        serde_json::from_str(&stdout(&out)).expect("check --json prints one JSON object");
    // The ratio is false positives per exact pair, and 0 (not NaN, which JSON cannot hold)
    // without exact pairs.
    let (fp, exact) = (
        u64_field(&cmp, "false_positives"),
        u64_field(&cmp, "exact_pairs"),
    );
    let ratio = cmp["false_positive_ratio"].as_f64();
    let want = if exact > 0 {
        fp as f64 / exact as f64
    } else {
        0.0
    };
    assert_eq!(ratio, Some(want), "{cmp}");
    cmp
}

fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn u64_field(v: &Value, field: &str) -> u64 {
    v[field]
        .as_u64()
        .unwrap_or_else(|| panic!("{field} missing or not an integer in {v}"))
}

/// The scene-file light indices in a dump, as a sorted set.
fn dump_lights(dump: &Value) -> Vec<u64> {
    let mut lights: Vec<u64> = dump["indices"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i.as_u64().unwrap())
        .collect();
    lights.sort_unstable();
    lights.dedup();
    lights
}

/// A `.gltf` of one triangle, slanted so that its bounds have a volume, seen by `cameras` (JSON objects, each placed by a node at z = 3 looking down −z).
fn gltf_with_cameras(dir: &Path, name: &str, cameras: &[&str]) -> PathBuf {
    let mut bytes = Vec::new();
    for c in [0f32, 0.0, 0.0, 4.0, 0.0, 0.0, 0.0, 4.0, 4.0] {
        bytes.extend_from_slice(&c.to_le_bytes());
    }
    let buffer = format!("{name}.bin");
    std::fs::write(dir.join(&buffer), bytes).unwrap();
    let nodes: Vec<String> = (0..cameras.len())
        .map(|i| format!(r#"{{"camera": {i}, "translation": [1, 1, 3]}}"#))
        .collect();
    let camera_nodes: Vec<String> = (1..=cameras.len()).map(|i| i.to_string()).collect();
    let gltf = format!(
        r#"{{"asset": {{"version": "2.0"}}, "buffers": [{{"byteLength": 36, "uri": "{buffer}"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [4, 4, 4]}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
        "cameras": [{}],
        "nodes": [{{"mesh": 0}}, {}], "scenes": [{{"nodes": [0, {}]}}], "scene": 0}}"#,
        cameras.join(", "),
        nodes.join(", "),
        camera_nodes.join(", ")
    );
    write(dir, name, &gltf)
}

const PERSPECTIVE: &str =
    r#""type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.1, "zfar": 50}"#;
const ORTHOGRAPHIC: &str =
    r#""type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 50}"#;
