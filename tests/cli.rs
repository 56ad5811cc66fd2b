//! End-to-end tests of the `myriad` binary: every subcommand run as a user runs it, through
//! files on disk, checking exit codes, messages and the JSON the tools write.
//!
//! Tests of commands that render (`render`, the main job, `frames`, `paper`, `skips`, `stress`)
//! first ask for an adapter exactly as the library's GPU tests do ([`gpu_available`]): without
//! one they fail with advice, or return early when `MYRIAD_SKIP_GPU_TESTS=1` says so.
//!
//! Each test works in its own folder under cargo's `CARGO_TARGET_TMPDIR`, so tests run in
//! parallel without sharing files. Scenes are small (hundreds of lights): the whole file runs in
//! well under a second of tool time.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A scene in the DESIGN.md format, written by hand: four valid lights, one of them a spot.
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

/// Runs `myriad` with `args`.
/// Whether the GPU tests may run: an adapter exists (else a panic with advice), or `None` from
/// [`myriad::gpu::GpuContext::headless_for_tests`] because `MYRIAD_SKIP_GPU_TESTS=1`.
fn gpu_available() -> bool {
    myriad::gpu::GpuContext::headless_for_tests().is_some()
}

fn myriad<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_myriad"))
        .args(args)
        .output()
        .expect("cannot run the myriad binary")
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

/// Runs `myriad` and asserts it failed; returns both streams.
fn myriad_fails<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> String {
    let out = myriad(args);
    assert!(
        !out.status.success(),
        "myriad {:?} should have failed:\n{}",
        args.iter().map(|a| a.as_ref()).collect::<Vec<_>>(),
        all_output(&out)
    );
    all_output(&out)
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

#[test]
fn validate_accepts_a_hand_written_scene() {
    let dir = work_dir("validate_good");
    let scene = write(&dir, "good.json", GOOD_SCENE);
    let out = myriad_ok(&["validate".as_ref(), "--scene".as_ref(), scene.as_os_str()]);
    assert_mentions(
        &stdout(&out),
        &[&scene.display().to_string(), "valid", "4 ok, 0 bad"],
    );
}

#[test]
fn validate_names_file_light_and_problem() {
    let dir = work_dir("validate_bad");
    // Two problems at once: near >= far on the camera, and a negative radius on light 2.
    let text = GOOD_SCENE
        .replace(r#""near": 0.1, "far": 100"#, r#""near": 100, "far": 10"#)
        .replace(r#""radius": 1.5"#, r#""radius": -1"#);
    assert_ne!(text, GOOD_SCENE);
    let scene = write(&dir, "bad.json", &text);
    let out = myriad_fails(&["validate".as_ref(), "--scene".as_ref(), scene.as_os_str()]);
    assert_mentions(
        &out,
        &[
            &scene.display().to_string(),
            "lights[2].radius",
            "-1",
            "camera.far",
            "near",
        ],
    );
    // Every problem is reported, not just the first.
    assert_mentions(&out, &["2 problems", "1 bad"]);
}

#[test]
fn validate_reports_unreadable_and_missing_files() {
    let dir = work_dir("validate_unreadable");
    let truncated = write(&dir, "truncated.json", &GOOD_SCENE[..GOOD_SCENE.len() / 2]);
    let out = myriad_fails(&[
        "validate".as_ref(),
        "--scene".as_ref(),
        truncated.as_os_str(),
    ]);
    assert_mentions(
        &out,
        &[&truncated.display().to_string(), "cannot parse", "line "],
    );
    let missing = dir.join("missing.json");
    let dump = dir.join("dump.json");
    for command in [
        &["validate"][..],
        &["bench"],
        &["assign", "--out", dump.to_str().unwrap()],
    ] {
        let mut args: Vec<&std::ffi::OsStr> = command.iter().map(|a| a.as_ref()).collect();
        args.extend(["--scene".as_ref(), missing.as_os_str()]);
        let out = myriad_fails(&args);
        assert_mentions(&out, &[&missing.display().to_string(), "cannot read"]);
        // The operating system's reason is printed once: the message does not repeat its source.
        assert_eq!(out.matches("(os error").count(), 1, "{command:?}: {out}");
    }
}

#[test]
fn generated_scenes_validate() {
    let dir = work_dir("scene_validates");
    for preset in ["paper", "uniform", "sphere"] {
        let scene = dir.join(format!("{preset}.json"));
        let out = myriad_ok(&[
            "scene".as_ref(),
            "--preset".as_ref(),
            preset.as_ref(),
            "--lights".as_ref(),
            "200".as_ref(),
            "--seed".as_ref(),
            "7".as_ref(),
            "--out".as_ref(),
            scene.as_os_str(),
        ]);
        assert_mentions(&stdout(&out), &[&scene.display().to_string()]);
        let out = myriad_ok(&["validate".as_ref(), "--scene".as_ref(), scene.as_os_str()]);
        assert_mentions(&stdout(&out), &["200 ok, 0 bad"]);
        assert_eq!(read_json(&scene)["lights"].as_array().unwrap().len(), 200);
    }
}

#[test]
fn every_method_passes_the_oracle_check() {
    let dir = work_dir("methods_check");
    let scene = paper_scene(&dir, 300);
    let hand_written = write(&dir, "good.json", GOOD_SCENE);
    for scene in [&scene, &hand_written] {
        for method in ["exact", "linear", "binary", "refined", "cone"] {
            let dump = dir.join(format!("{method}.dump.json"));
            let cmp = assign_and_check(scene, method, &dump);
            let context = format!("{} / {method}: {cmp}", scene.display());
            assert_eq!(u64_field(&cmp, "misses"), 0, "{context}");
            assert!(u64_field(&cmp, "exact_pairs") > 0, "{context}");
            assert!(
                u64_field(&cmp, "reported_pairs") >= u64_field(&cmp, "exact_pairs"),
                "{context}"
            );
            if method == "exact" {
                assert_eq!(u64_field(&cmp, "false_positives"), 0, "{context}");
                assert_eq!(cmp["false_positive_ratio"].as_f64(), Some(0.0), "{context}");
            }
            // The dump has the DESIGN.md shape.
            let d = read_json(&dump);
            assert_eq!(d["grid"], serde_json::json!([24, 12, 16]));
            assert_eq!(d["x_edges"].as_array().unwrap().len(), 25);
            assert_eq!(d["y_edges"].as_array().unwrap().len(), 13);
            assert_eq!(d["z_planes"].as_array().unwrap().len(), 17);
            assert_eq!(d["offsets"].as_array().unwrap().len(), 24 * 12 * 16);
            assert_eq!(d["counts"].as_array().unwrap().len(), 24 * 12 * 16);
        }
    }
}

#[test]
fn a_coarsened_grid_is_recorded_in_the_dump_and_checked() {
    // Past its pair budget the assigner halves the grid; the dump must describe the grid its lists
    // belong to (it once kept the scene's header, and `check` rejected the dump), and `check`
    // must verify it on that grid.
    let dir = work_dir("coarsened_dump");
    let scene = paper_scene(&dir, 300);
    for method in ["exact", "linear", "binary", "refined", "cone"] {
        let dump = dir.join(format!("{method}.dump.json"));
        let out = myriad_ok(&[
            "assign".as_ref(),
            "--scene".as_ref(),
            scene.as_os_str(),
            "--method".as_ref(),
            method.as_ref(),
            "--pair-budget".as_ref(),
            "1000".as_ref(),
            "--out".as_ref(),
            dump.as_os_str(),
        ]);
        assert_mentions(&stderr(&out), &["24x12x16", "coarser", "6x3x4"]);
        let d = read_json(&dump);
        assert_eq!(d["grid"], serde_json::json!([6, 3, 4]), "{method}");
        assert_eq!(d["offsets"].as_array().unwrap().len(), 6 * 3 * 4);
        assert_eq!(d["z_planes"].as_array().unwrap().len(), 5);
        let indices = d["indices"].as_array().unwrap().len();
        assert!(indices <= 1000, "{method}: {indices} pairs over the budget");
        let cmp = check_json(&scene, &dump);
        let context = format!("{method}: {cmp}");
        assert_eq!(cmp["grid"], serde_json::json!([6, 3, 4]), "{context}");
        assert_eq!(u64_field(&cmp, "misses"), 0, "{context}");
        assert!(u64_field(&cmp, "exact_pairs") > 0, "{context}");
    }
    // The text report says which grid it checked when it is not the scene's.
    let check_text = |dump: &Path| {
        stdout(&myriad_ok(&[
            "check".as_ref(),
            "--scene".as_ref(),
            scene.as_os_str(),
            "--dump".as_ref(),
            dump.as_os_str(),
        ]))
    };
    let text = check_text(&dir.join("refined.dump.json"));
    assert_mentions(
        &text,
        &["6x3x4 (coarser than the scene's", "misses                0"],
    );
    let full = dir.join("full.dump.json");
    assign_and_check(&scene, "refined", &full);
    let text = check_text(&full);
    assert!(!text.contains("coarser"), "{text}");
    // A grid no coarsening of the scene's reaches is still refused: 20x12x16 halves to
    // 10x6x8, 5x3x4, 2x1x2, 1x1x1, never 6x3x4.
    let other = write(
        &dir,
        "other.json",
        &GOOD_SCENE.replace(r#""x": 24"#, r#""x": 20"#),
    );
    let dump = dir.join("binary.dump.json");
    let err = myriad_fails(&[
        "check".as_ref(),
        "--scene".as_ref(),
        other.as_os_str(),
        "--dump".as_ref(),
        dump.as_os_str(),
    ]);
    assert_mentions(
        &err,
        &["binary.dump.json", "does not match the scene's 20x12x16"],
    );
}

#[test]
fn check_finds_a_removed_light_with_either_reference() {
    let dir = work_dir("check_references");
    let scene = dir.join("paper.json");
    let scene_arg = scene.to_str().unwrap();
    myriad_ok(&[
        "scene", "--preset", "paper", "--lights", "300", "--out", scene_arg,
    ]);
    // The exact method's lists: every pair is a true one, so any removal is a miss.
    let dump = dir.join("exact.dump.json");
    let whole = assign_and_check(&scene, "exact", &dump);
    // The middle y edge is written as 0, not -0.
    let mut d = read_json(&dump);
    assert_eq!(d["y_edges"][6].to_string(), "0.0");
    // One light taken out of one list (the lists stay CSR).
    let counts: Vec<u64> = serde_json::from_value(d["counts"].clone()).unwrap();
    let c = counts.iter().position(|&n| n >= 1).unwrap();
    let at = d["offsets"][c].as_u64().unwrap() as usize;
    let removed = d["indices"].as_array_mut().unwrap().remove(at);
    d["counts"][c] = Value::from(counts[c] - 1);
    for later in c + 1..counts.len() {
        let o = d["offsets"][later].as_u64().unwrap();
        d["offsets"][later] = Value::from(o - 1);
    }
    let broken = write(&dir, "broken.dump.json", &d.to_string());
    let check = |dump: &Path, reference: &str| {
        let dump = dump.to_str().unwrap();
        myriad(&[
            "check",
            "--scene",
            scene_arg,
            "--dump",
            dump,
            "--json",
            "--reference",
            reference,
        ])
    };
    for reference in ["independent", "exact-method"] {
        let out = check(&dump, reference);
        assert!(out.status.success(), "{reference}: {}", all_output(&out));
        let cmp: Value = serde_json::from_str(&stdout(&out)).unwrap();
        assert_eq!(cmp["reference"], reference);
        for field in ["exact_pairs", "reported_pairs", "misses", "false_positives"] {
            assert_eq!(cmp[field], whole[field], "{reference}: {field}");
        }
        let out = check(&broken, reference);
        assert!(!out.status.success(), "{reference}: a miss must fail");
        let cmp: Value = serde_json::from_str(&stdout(&out)).unwrap();
        assert_eq!(cmp["misses"], 1, "{reference}: {cmp}");
        assert_eq!(cmp["first_miss"]["cluster"], c, "{reference}: {cmp}");
        assert_eq!(cmp["first_miss"]["light"], removed, "{reference}: {cmp}");
        assert_mentions(&stderr(&out), &["1 miss(es)", &format!("cluster {c}")]);
    }
}

#[test]
fn invalid_lights_are_skipped_and_indices_stay_file_indices() {
    let dir = work_dir("skipped_lights");
    let l0 = r#"{"position": [0, 2, 0], "radius": 2}"#;
    let l1 = r#"{"position": [3, 1, -5], "radius": 4}"#;
    let l3 = r#"{"position": [-1, 1, 0], "radius": 3}"#;
    // Light 2 is invalid in one file; in the other it is valid but behind the camera (culled).
    let with_bad = write(
        &dir,
        "with_bad.json",
        &scene_with_lights(&format!(
            r#"{l0}, {l1}, {{"position": [2, 2, 0], "radius": -1}}, {l3}"#
        )),
    );
    let with_culled = write(
        &dir,
        "with_culled.json",
        &scene_with_lights(&format!(
            r#"{l0}, {l1}, {{"position": [0, 2, 50], "radius": 1}}, {l3}"#
        )),
    );

    for method in ["exact", "refined"] {
        let bad_dump = dir.join(format!("with_bad.{method}.json"));
        let out = myriad_ok(&[
            "assign".as_ref(),
            "--scene".as_ref(),
            with_bad.as_os_str(),
            "--method".as_ref(),
            method.as_ref(),
            "--out".as_ref(),
            bad_dump.as_os_str(),
        ]);
        assert_mentions(&stderr(&out), &["skipped", "light 2", "radius"]);
        // The skipped light is counted among the rejected ones.
        assert_mentions(
            &stdout(&out),
            &["assigned 3 lights (3 visible, 0 culled, 1 rejected)"],
        );

        // The dump names lights by their index in the file: 0, 1 and 3, never 2.
        let dump = read_json(&bad_dump);
        assert_eq!(dump_lights(&dump), [0, 1, 3], "{method}");
        let culled_dump = dir.join(format!("with_culled.{method}.json"));
        myriad_ok(&[
            "assign".as_ref(),
            "--scene".as_ref(),
            with_culled.as_os_str(),
            "--method".as_ref(),
            method.as_ref(),
            "--out".as_ref(),
            culled_dump.as_os_str(),
        ]);
        assert_eq!(dump, read_json(&culled_dump), "{method}");

        // check compares in file indices too, with either scene.
        for scene in [&with_bad, &with_culled] {
            let cmp = check_json(scene, &bad_dump);
            assert_eq!(u64_field(&cmp, "misses"), 0, "{method}: {cmp}");
            assert!(u64_field(&cmp, "exact_pairs") > 0);
            if method == "exact" {
                assert_eq!(u64_field(&cmp, "false_positives"), 0, "{cmp}");
            }
        }
    }

    // Negative control: renumbering light 3 as 2 (what a dump in kept-light order would say)
    // must fail the check.
    let exact_dump = dir.join("with_bad.exact.json");
    let mut dump = read_json(&exact_dump);
    for index in dump["indices"].as_array_mut().unwrap() {
        if *index == 3 {
            *index = 2.into();
        }
    }
    let renumbered = write(&dir, "renumbered.json", &dump.to_string());
    let out = myriad(&[
        "check".as_ref(),
        "--scene".as_ref(),
        with_bad.as_os_str(),
        "--dump".as_ref(),
        renumbered.as_os_str(),
        "--json".as_ref(),
    ]);
    assert!(!out.status.success(), "{}", all_output(&out));
    let cmp: Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert!(u64_field(&cmp, "misses") > 0, "{cmp}");
    // The miss names light 3 by its index in the file, not by its column (2) among the loaded
    // lights.
    assert_eq!(cmp["first_miss"]["light"], 3, "{cmp}");

    // Listing the invalid light as well as every right one is no miss, but still wrong: it
    // passed as a false positive (audit g2). The last cluster gains light 2.
    let mut dump = read_json(&exact_dump);
    let last = dump["counts"].as_array().unwrap().len() - 1;
    let count = dump["counts"][last].as_u64().unwrap();
    dump["counts"][last] = (count + 1).into();
    dump["indices"].as_array_mut().unwrap().push(2.into());
    let with_invalid = write(&dir, "with_invalid.json", &dump.to_string());
    let out = myriad(&[
        "check".as_ref(),
        "--scene".as_ref(),
        with_bad.as_os_str(),
        "--dump".as_ref(),
        with_invalid.as_os_str(),
        "--json".as_ref(),
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", all_output(&out));
    let cmp: Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(u64_field(&cmp, "misses"), 0, "{cmp}");
    assert_eq!(u64_field(&cmp, "invalid_lights_listed"), 1, "{cmp}");
    assert_mentions(&stderr(&out), &["1 invalid light", "light 2"]);
}

#[test]
fn check_rejects_broken_dumps_naming_the_file() {
    let dir = work_dir("broken_dumps");
    let scene = write(&dir, "good.json", GOOD_SCENE);
    let dump = dir.join("dump.json");
    assign_and_check(&scene, "refined", &dump);
    let text = std::fs::read_to_string(&dump).unwrap();
    let check = |dump: &Path| {
        myriad_fails(&[
            "check".as_ref(),
            "--scene".as_ref(),
            scene.as_os_str(),
            "--dump".as_ref(),
            dump.as_os_str(),
        ])
    };

    let truncated = write(&dir, "truncated.json", &text[..text.len() / 2]);
    let out = check(&truncated);
    assert_mentions(
        &out,
        &[
            &truncated.display().to_string(),
            "not a valid assignment dump",
        ],
    );

    let garbage = write(&dir, "garbage.json", "this is not JSON");
    assert_mentions(&check(&garbage), &[&garbage.display().to_string()]);

    // Well-formed dumps that do not belong to the scene, or would shade a light twice.
    let good: Value = serde_json::from_str(&text).unwrap();
    let edited = |name: &str, edit: &dyn Fn(&mut Value)| {
        let mut v = good.clone();
        edit(&mut v);
        write(&dir, name, &v.to_string())
    };
    let planes = edited("planes.json", &|v| {
        let z = v["z_planes"][1].as_f64().unwrap();
        v["z_planes"][1] = Value::from(z * 1.01);
    });
    assert_mentions(
        &check(&planes),
        &[
            &planes.display().to_string(),
            "z_planes[1]",
            "does not match",
        ],
    );
    let beyond = edited("beyond.json", &|v| v["indices"][0] = Value::from(999));
    assert_mentions(
        &check(&beyond),
        &[&beyond.display().to_string(), "indices[0] = 999", "lights"],
    );
    let counts: Vec<u64> = serde_json::from_value(good["counts"].clone()).unwrap();
    let offsets: Vec<u64> = serde_json::from_value(good["offsets"].clone()).unwrap();
    let c = counts.iter().position(|&n| n >= 2).expect("a list of two");
    let twice = edited("twice.json", &|v| {
        let o = offsets[c] as usize;
        v["indices"][o + 1] = v["indices"][o].clone();
    });
    assert_mentions(
        &check(&twice),
        &[
            &twice.display().to_string(),
            &format!("cluster {c}"),
            "more than once",
        ],
    );

    // Well-formed JSON whose lists run past the end of `indices`.
    let mut value = read_json(&dump);
    value["counts"][0] = 1_000_000.into();
    let inconsistent = write(&dir, "inconsistent.json", &value.to_string());
    assert_mentions(
        &check(&inconsistent),
        &[&inconsistent.display().to_string(), "inconsistent"],
    );

    // Lists that alias each other, or indices no list owns: not CSR, so not a dump.
    let d = counts
        .iter()
        .rposition(|&n| n >= 1)
        .expect("a last non-empty list");
    assert_ne!(c, d);
    let aliased = edited("aliased.json", &|v| {
        v["offsets"][d] = v["offsets"][c].clone()
    });
    assert_mentions(
        &check(&aliased),
        &[&aliased.display().to_string(), "overlaps", "inconsistent"],
    );
    let stray = edited("stray.json", &|v| {
        v["indices"].as_array_mut().unwrap().push(Value::from(0))
    });
    assert_mentions(
        &check(&stray),
        &[&stray.display().to_string(), "belong to no cluster's list"],
    );

    // A dump of another grid.
    let other = dir.join("other.json");
    myriad_ok(&[
        "assign".as_ref(),
        "--preset".as_ref(),
        "uniform".as_ref(),
        "--lights".as_ref(),
        "50".as_ref(),
        "--out".as_ref(),
        other.as_os_str(),
    ]);
    assert_mentions(
        &check(&other),
        &[&other.display().to_string(), "does not match"],
    );

    let missing = dir.join("missing.json");
    assert_mentions(
        &check(&missing),
        &[&missing.display().to_string(), "cannot read dump"],
    );
}

#[test]
fn bench_json_reports_every_method_without_misses() {
    let out = myriad_ok(&[
        "bench", "--preset", "paper", "--lights", "300", "--json", "--runs", "3",
    ]);
    let report: Value = serde_json::from_str(&stdout(&out)).expect("bench --json prints JSON");
    assert_eq!(report["lights"].as_u64(), Some(300));
    let methods = report["methods"].as_array().expect("a methods array");
    let names: Vec<&str> = methods
        .iter()
        .map(|m| m["method"].as_str().expect("method name"))
        .collect();
    assert_eq!(names, ["exact", "linear", "binary", "refined", "cone"]);
    for m in methods {
        assert!(m["median_us"].as_f64().is_some_and(|t| t > 0.0), "{m}");
        assert!(u64_field(m, "pairs") > 0, "{m}");
        assert!(
            m["false_positive_ratio"].as_f64().is_some_and(|r| r >= 0.0),
            "{m}"
        );
        assert_eq!(u64_field(m, "misses"), 0, "{m}");
        // The throughput is the output's bytes over the median time, in GB/s; the fastest run
        // took no longer than the median.
        let bytes = u64_field(m, "bytes") as f64;
        let median = m["median_us"].as_f64().unwrap();
        let gb_s = m["effective_gb_s"].as_f64().unwrap();
        assert!((gb_s - bytes / median / 1e3).abs() <= 1e-9 * gb_s, "{m}");
        assert!(m["min_us"].as_f64().is_some_and(|t| t <= median), "{m}");
    }
    let exact = &methods[0];
    assert_eq!(exact["false_positive_ratio"].as_f64(), Some(0.0));
    // 300 lights are one task (below SERIAL_LIGHTS) and `linear` is serial: never on the pool.
    for m in &methods[1..] {
        assert_eq!(u64_field(m, "runs"), 3, "{m}");
        assert_eq!(u64_field(m, "pooled_runs"), 0, "{m}");
    }
    // One thread has no link between threads to report.
    let one: Value = serde_json::from_str(&stdout(&myriad_ok(&[
        "bench",
        "--preset",
        "paper",
        "--lights",
        "300",
        "--methods",
        "binary",
        "--threads",
        "1",
        "--runs",
        "3",
        "--json",
    ])))
    .unwrap();
    assert!(one["core_link"].is_null(), "{}", one["core_link"]);

    // A chosen subset of methods on a scene file.
    let dir = work_dir("bench_json");
    let scene = write(&dir, "good.json", GOOD_SCENE);
    let out = myriad_ok(&[
        "bench".as_ref(),
        "--scene".as_ref(),
        scene.as_os_str(),
        "--methods".as_ref(),
        "binary,refined".as_ref(),
        "--runs".as_ref(),
        "3".as_ref(),
        "--json".as_ref(),
    ]);
    let report: Value = serde_json::from_str(&stdout(&out)).unwrap();
    let names: Vec<&str> = report["methods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["method"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["binary", "refined"]);

    // Frames apart, slept through or spun through, paced or always on the pool: the same lists.
    let mut pairs = Vec::new();
    for extra in [
        &["--idle-us", "200"][..],
        &["--idle-us", "200", "--busy"],
        &["--idle-us", "200", "--busy", "--always-parallel"],
    ] {
        let mut args = vec![
            "bench",
            "--preset",
            "paper",
            "--lights",
            "800",
            "--threads",
            "2",
        ];
        args.extend(["--methods", "binary,refined", "--runs", "3", "--json"]);
        args.extend(extra);
        let report: Value = serde_json::from_str(&stdout(&myriad_ok(&args))).unwrap();
        // Two threads: the link between them is measured before and after the timings.
        for when in ["before", "after"] {
            let link = &report["core_link"][when];
            for field in ["round_trip_ns", "handoff_us"] {
                assert!(link[field].as_f64().is_some_and(|v| v > 0.0), "{link}");
            }
        }
        for m in report["methods"].as_array().unwrap() {
            assert_eq!(u64_field(m, "misses"), 0, "{extra:?}: {m}");
            pairs.push(u64_field(m, "pairs"));
            // 800 lights on two threads are split into tasks: always on the pool when asked.
            if extra.contains(&"--always-parallel") {
                assert_eq!(u64_field(m, "pooled_runs"), 3, "{extra:?}: {m}");
            }
        }
    }
    assert!(pairs[0] > 0 && pairs[1] > 0);
    assert_eq!(pairs[..2], pairs[2..4]);
    assert_eq!(pairs[..2], pairs[4..6]);
    let out = myriad_fails(&["bench", "--preset", "paper", "--busy"]);
    assert_mentions(&out, &["--idle-us"]);
}

#[test]
fn bad_options_fail_with_a_helpful_message() {
    let dir = work_dir("bad_options");
    let scene = write(&dir, "good.json", GOOD_SCENE);
    let out_file = dir.join("out.json");

    let out = myriad_fails(&[
        "assign".as_ref(),
        "--scene".as_ref(),
        scene.as_os_str(),
        "--method".as_ref(),
        "fancy".as_ref(),
        "--out".as_ref(),
        out_file.as_os_str(),
    ]);
    assert_mentions(
        &out,
        &[
            "unknown method",
            "fancy",
            "exact",
            "linear",
            "binary",
            "refined",
        ],
    );
    assert!(!out_file.exists(), "no dump is written for a bad method");

    let out = myriad_fails(&["bench", "--preset", "paper", "--methods", "refined,bogus"]);
    assert_mentions(&out, &["unknown method", "bogus"]);
    // Counts past what a run can hold aborted on a 32 GiB allocation or slept forever, and a
    // method listed twice was timed twice (audit g2).
    assert_rejected(&[
        (
            &["bench", "--preset", "paper", "--runs", "4294967296"],
            &["--runs", "1..=1000000"],
        ),
        (
            &[
                "bench",
                "--preset",
                "paper",
                "--idle-us",
                "18446744073709551615",
            ],
            &["--idle-us", "0..=1000000"],
        ),
        (
            &[
                "bench",
                "--preset",
                "paper",
                "--methods",
                "binary,refined,binary",
            ],
            &["--methods lists binary twice"],
        ),
    ]);

    let out = myriad_fails(&[
        "scene".as_ref(),
        "--preset".as_ref(),
        "nope".as_ref(),
        "--out".as_ref(),
        out_file.as_os_str(),
    ]);
    assert_mentions(
        &out,
        &["unknown preset", "nope", "paper", "uniform", "sphere"],
    );
    assert!(!out_file.exists());

    let out = myriad_fails(&["bench", "--preset", "nope"]);
    assert_mentions(&out, &["unknown preset", "nope"]);

    // No scene at all, and an unknown flag (clap's own message).
    let out = myriad_fails(&["bench"]);
    assert_mentions(&out, &["--scene", "--preset"]);
    let out = myriad_fails(&["check", "--frobnicate"]);
    assert_mentions(&out, &["--frobnicate"]);
}

#[test]
fn no_arguments_runs_the_main_job() {
    if !gpu_available() {
        return;
    }
    // The main job writes into ./out: run it in a fresh folder.
    let dir = work_dir("main_job");
    let out = Command::new(env!("CARGO_BIN_EXE_myriad"))
        .current_dir(&dir)
        .output()
        .expect("cannot run the myriad binary");
    assert!(
        out.status.success(),
        "main job failed:\n{}",
        all_output(&out)
    );
    let text = stdout(&out);
    assert_mentions(
        &text,
        &[
            "default scene",
            "1000 lights",
            "1536x768",
            "CPU light assignment",
            "GPU shading pass",
            "lighting calculations skipped",
            "faster than brute-force deferred",
            "outside the view frustum",
        ],
    );
    for file in ["frame.png", "heatmap.png", "stats.json"] {
        assert!(dir.join("out").join(file).is_file(), "no out/{file}");
    }
    let stats: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/stats.json")).unwrap())
            .unwrap();
    assert_eq!(stats["lights"], 1000);
    let strategies = stats["strategies"].as_array().unwrap();
    assert_eq!(strategies.len(), 3);
    let clustered = &strategies[0];
    assert_eq!(clustered["shading"], "clustered");
    assert!(clustered["pairs"].as_u64().unwrap() > 0);
    let mean = clustered["pixels"]["mean_lights"].as_f64().unwrap();
    assert!(mean > 0.0 && mean < 1000.0, "{mean}");
    assert_eq!(
        strategies[2]["pixels"]["mean_lights"].as_f64().unwrap(),
        1000.0
    );
    // Beside them, clustered shading with every saving but reuse, which must not change the
    // image and must do less: lights culled, clusters masked, so fewer pairs.
    let skipping = &stats["with_skips"];
    assert_eq!(
        skipping["savings"],
        serde_json::json!(["cull", "active", "depth", "variants"])
    );
    assert!(skipping["max_image_difference"].as_u64().unwrap() <= 1);
    let lights_assigned = skipping["lights_assigned"].as_u64().unwrap();
    assert_eq!(
        lights_assigned,
        1000 - stats["lights_culled"].as_u64().unwrap()
    );
    let active = skipping["active_clusters"].as_u64().unwrap();
    assert!(active > 0 && active < skipping["clusters"].as_u64().unwrap());
    let skip_pairs = skipping["result"]["pairs"].as_u64().unwrap();
    assert!(
        skip_pairs > 0 && skip_pairs < clustered["pairs"].as_u64().unwrap(),
        "{skip_pairs} pairs with skips"
    );
    assert_mentions(&text, &["clustered+skips", "clusters active"]);
}

#[test]
fn render_rejects_bad_options_clearly() {
    assert_rejected(&[
        (&["render", "--size", "0x10"], &["--size", "WxH"]),
        (&["render", "--grid", "24x12"], &["--grid", "XxYxZ"]),
        (
            &["render", "--depth", "cubic"],
            &["--depth", "log, linear or log_near:D"],
        ),
        (&["render", "--method", "magic"], &["magic", "refined"]),
        (
            &["render", "--camera", "Nowhere", "--size", "64x32"],
            &["Nowhere", "Main"],
        ),
        (
            &["render", "--gltf", "/nonexistent/model.glb"],
            &["/nonexistent/model.glb"],
        ),
        (
            &["render", "--skips", "cull,shadows"],
            &["--skips", "\"shadows\"", "variants"],
        ),
    ]);
}

#[test]
fn scene_rejects_a_missing_source_and_a_zero_size_clearly() {
    let dir = work_dir("scene_source");
    let out_file = dir.join("s.scene");
    let out_path = out_file.to_str().unwrap();
    let out = myriad_fails(&["scene", "--lights", "10", "--out", out_path]);
    assert_mentions(&out, &["--preset", "--gltf"]);
    let atrium = format!("{}/assets/atrium.glb", env!("CARGO_MANIFEST_DIR"));
    for flag in ["--width", "--height"] {
        let out = myriad_fails(&["scene", "--gltf", &atrium, flag, "0", "--out", out_path]);
        assert_mentions(&out, &[flag, "0 is not in 1.."]);
    }
    // Options of another light field were silently ignored (audit g2).
    let base = ["scene", "--gltf", &atrium, "--out", out_path];
    assert_rejected(&[
        (
            &[&base[..], &["--field", "box", "--clumps", "3"]].concat(),
            &["--clumps only applies to --field clumps"],
        ),
        (
            &[&base[..], &["--spread", "2"]].concat(),
            &[
                "--spread only applies to --field clumps",
                "--field surfaces",
            ],
        ),
        (
            &[&base[..], &["--field", "frustum", "--offset", "1"]].concat(),
            &["--offset only applies to --field surfaces"],
        ),
        (
            &[&base[..], &["--spot-angles", "10..20"]].concat(),
            &["--spot-angles only applies with --spots"],
        ),
    ]);
    assert!(!out_file.exists(), "nothing is written for refused options");
    let far_slice = "log_near:5000";
    let out = myriad_fails(&[
        "scene", "--gltf", &atrium, "--depth", far_slice, "--out", out_path,
    ]);
    assert_mentions(&out, &["log_near:5000", "strictly between", "far (50)"]);
    // A cut-off that makes radii overflow is named as the cause.
    let out = myriad_fails(&[
        "scene", "--gltf", &atrium, "--cutoff", "1e-45", "--out", out_path,
    ]);
    assert_mentions(&out, &["atrium.glb", "cut-off", "too small"]);
    // A model whose only node is scaled to nothing gives no usable camera: the model is blamed,
    // not the output file.
    let flat = write(
        &dir,
        "flat.gltf",
        r#"{"asset": {"version": "2.0"},
        "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": [{"mesh": 0, "matrix": [0,0,0,0, 0,0,0,0, 0,0,0,0, 0,0,0,1]}],
        "scenes": [{"nodes": [0]}], "scene": 0}"#,
    );
    let out = myriad_fails(&[
        "scene".as_ref(),
        "--gltf".as_ref(),
        flat.as_os_str(),
        "--field".as_ref(),
        "box".as_ref(),
        "--out".as_ref(),
        out_file.as_os_str(),
    ]);
    assert_mentions(&out, &["flat.gltf", "camera.target"]);
    assert!(!out.contains("s.scene"), "{out}");
    assert!(!out_file.exists(), "nothing is written on bad options");
}

#[test]
fn preset_options_without_a_preset_are_rejected() {
    let dir = work_dir("preset_options");
    let scene = dir.join("s.json");
    let out = myriad(&[
        "scene",
        "--preset",
        "paper",
        "--lights",
        "10",
        "--out",
        scene.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let out = myriad(&[
        "assign",
        "--scene",
        scene.to_str().unwrap(),
        "--lights",
        "5",
        "--out",
        dir.join("d.json").to_str().unwrap(),
    ]);
    assert!(
        !out.status.success(),
        "--lights without --preset must be an error"
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("--preset"));
}

#[test]
fn frames_compares_sequential_and_pipelined_loops() {
    if !gpu_available() {
        return;
    }
    let out = myriad_ok(&[
        "frames", "--lights", "3000", "--size", "64x32", "--frames", "4", "--json",
    ]);
    let loops: Value = serde_json::from_str(&stdout(&out)).unwrap();
    let loops = loops.as_array().unwrap();
    assert_eq!(loops.len(), 2);
    assert_eq!(loops[0]["pipelined"], false);
    assert_eq!(loops[1]["pipelined"], true);
    for l in loops {
        assert_eq!(l["frames"], 4);
        assert!(l["assign_ms"].as_f64().unwrap() > 0.0);
        assert!(l["frame_ms"].as_f64().unwrap() > 0.0);
        // Culled by default: some of the orbiting lights are outside the view.
        let uploaded = l["lights_uploaded"].as_f64().unwrap();
        assert!(uploaded > 0.0 && uploaded < 3000.0, "{uploaded}");
        assert!(l["cull_ms"].as_f64().unwrap() > 0.0);
        assert!(l["upload_bytes"].as_f64().unwrap() > uploaded * 48.0);
    }
    let out = myriad_ok(&[
        "frames",
        "--lights",
        "3000",
        "--size",
        "64x32",
        "--frames",
        "2",
        "--no-cull",
    ]);
    assert_mentions(
        &stdout(&out),
        &[
            "every light assigned and uploaded",
            "lights assigned and uploaded",
        ],
    );
    let out = myriad_fails(&["frames", "--frames", "1"]);
    assert_mentions(&out, &["--frames", "at least 2"]);
}

#[test]
fn outputs_never_replace_their_inputs_or_fifos() {
    let dir = work_dir("outputs_vs_inputs");
    let scene = paper_scene(&dir, 30);
    let original = std::fs::read(&scene).unwrap();
    // The scene named again as the dump, directly or through a link: refused before any work,
    // and the scene is intact (it was replaced by its own dump).
    let link = dir.join("link.json");
    #[cfg(unix)]
    std::os::unix::fs::symlink(&scene, &link).unwrap();
    #[cfg(not(unix))]
    std::fs::copy(&scene, &link).unwrap();
    for out in [&scene, &link] {
        let text = myriad_fails(&[
            "assign".as_ref(),
            "--scene".as_ref(),
            scene.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
        ]);
        assert_mentions(&text, &["is the input", "refusing to overwrite"]);
        assert_eq!(std::fs::read(&scene).unwrap(), original);
    }
    // The model named again as the scene file: refused, the model intact.
    let model = dir.join("model.glb");
    myriad_ok(&["atrium".as_ref(), "--out".as_ref(), model.as_os_str()]);
    let glb = std::fs::read(&model).unwrap();
    let text = myriad_fails(&[
        "scene".as_ref(),
        "--gltf".as_ref(),
        model.as_os_str(),
        "--out".as_ref(),
        model.as_os_str(),
    ]);
    assert_mentions(&text, &["is the input"]);
    assert_eq!(std::fs::read(&model).unwrap(), glb);
    // A FIFO is written into, not renamed over (the same path as a device: `--out /dev/null`
    // as root turned the device into a regular file).
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let fifo = dir.join("fifo");
        let made = Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|s| s.success()) {
            let (sent, received) = std::sync::mpsc::channel();
            let reader_path = fifo.clone();
            std::thread::spawn(move || {
                let _ = sent.send(std::fs::read(&reader_path));
            });
            myriad_ok(&[
                "assign".as_ref(),
                "--scene".as_ref(),
                scene.as_os_str(),
                "--out".as_ref(),
                fifo.as_os_str(),
            ]);
            let dump = received
                .recv_timeout(std::time::Duration::from_secs(60))
                .expect("the dump reached the FIFO's reader")
                .unwrap();
            assert!(
                dump.starts_with(b"{\"grid\""),
                "{:?}",
                &dump[..20.min(dump.len())]
            );
            let kind = std::fs::symlink_metadata(&fifo).unwrap().file_type();
            assert!(kind.is_fifo(), "the FIFO became {kind:?}");
        }
    }
}

#[test]
fn a_failed_render_leaves_the_old_output_set_whole() {
    if !gpu_available() {
        return;
    }
    let out_dir = work_dir("render_all_or_nothing").join("out");
    let dir = out_dir.to_str().unwrap();
    let rest = [
        "--size", "64x32", "--runs", "1", "--skips", "none", "--out", dir,
    ];
    let render = |lights: &str, extra: &[&str]| {
        let args = ["render", "--preset", "uniform", "--lights", lights];
        myriad(&[&args[..], extra, &rest].concat())
    };
    assert!(render("50", &[]).status.success());
    let names = ["frame.png", "heatmap.png", "stats.json"];
    let read_all = || names.map(|n| std::fs::read(out_dir.join(n)).unwrap());
    let old = read_all();
    let stats: Value = serde_json::from_slice(&old[2]).unwrap();
    assert_eq!(stats["strategies"][0]["shading"], "clustered");
    assert!(
        stats["with_skips"].is_null(),
        "--skips none: no such column"
    );
    // One cluster holding all 100 000 lights passes llvmpipe's shader loop limit: clustered
    // shading is refused, the run fails and must write nothing. A GPU without that limit renders
    // the whole set instead.
    let out = render("100000", &["--grid", "1x1x1"]);
    if out.status.success() {
        let stats: Value = serde_json::from_slice(&read_all()[2]).unwrap();
        assert_eq!(stats["grid"], serde_json::json!([1, 1, 1]));
    } else {
        assert_mentions(&all_output(&out), &["stops shader loops"]);
        assert!(read_all() == old, "the old output set was changed");
    }
}

#[test]
fn render_skips_a_baseline_the_adapter_cannot_draw_and_keeps_the_rest() {
    if !gpu_available() {
        return;
    }
    let out_dir = work_dir("render_skips_baseline").join("out");
    let out = myriad_ok(&[
        "render",
        "--preset",
        "uniform",
        "--lights",
        "100000",
        "--size",
        "64x32",
        "--runs",
        "1",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    let stats = read_json(&out_dir.join("stats.json"));
    let drawn: Vec<&str> = stats["strategies"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["shading"].as_str().unwrap())
        .collect();
    let skipped = stats["skipped"].as_array().unwrap();
    if skipped.is_empty() {
        // A GPU without a loop limit draws all three.
        assert_eq!(drawn, ["clustered", "tiled", "brute force"]);
        assert!(stats["speedup_vs_brute_force"].as_f64().unwrap() > 0.0);
    } else {
        // llvmpipe: brute force over 100 000 lights per pixel is refused and skipped, said so.
        assert_eq!(drawn, ["clustered", "tiled"]);
        assert_eq!(skipped[0]["shading"], "brute force");
        assert!(
            skipped[0]["reason"]
                .as_str()
                .unwrap()
                .contains("stops shader loops")
        );
        assert!(stats["speedup_vs_brute_force"].is_null());
        assert_mentions(
            &all_output(&out),
            &["brute force skipped", "stops shader loops"],
        );
    }
    assert!(out_dir.join("frame.png").is_file() && out_dir.join("heatmap.png").is_file());
}

#[test]
fn render_takes_scene_files_presets_and_sizes() {
    if !gpu_available() {
        return;
    }
    let dir = work_dir("render_sources");
    let scene = dir.join("uniform.json");
    myriad_ok(&[
        "scene",
        "--preset",
        "uniform",
        "--lights",
        "300",
        "--out",
        scene.to_str().unwrap(),
    ]);
    let out_dir = dir.join("out");
    let out = myriad_ok(&[
        "render",
        "--scene",
        scene.to_str().unwrap(),
        "--size",
        "96x54",
        "--grid",
        "8x4x6",
        "--runs",
        "1",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert_mentions(
        &stdout(&out),
        &[
            "uniform.json in default scene",
            "300 lights",
            "96x54",
            "grid 8x4x6",
        ],
    );
    let stats: Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("stats.json")).unwrap())
            .unwrap();
    assert_eq!(stats["lights"], 300);
    assert_eq!(stats["grid"], serde_json::json!([8, 4, 6]));
    let out = myriad_ok(&[
        "render",
        "--preset",
        "paper",
        "--lights",
        "200",
        "--size",
        "64x32",
        "--runs",
        "1",
        "--skips",
        "cull,active,depth,variants,tune",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert_mentions(
        &stdout(&out),
        &[
            "preset paper (200 lights, seed 1)",
            "64x32",
            "grid 24x12x16",
            "tuned: depth prepass",
        ],
    );
    // Tuned, the column reports the timed choice, and its frames ran it: with the prepass off,
    // no clusters were masked and no depth range fitted.
    let stats: Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("stats.json")).unwrap())
            .unwrap();
    let skipping = &stats["with_skips"];
    assert_eq!(
        skipping["savings"],
        serde_json::json!(["cull", "active", "depth", "variants", "tune"])
    );
    let decision = &skipping["prepass_decision"];
    assert_eq!(decision["frames_per_side"], 3);
    for side in ["with_seconds", "without_seconds"] {
        assert!(decision[side].as_f64().unwrap() > 0.0, "{decision}");
    }
    let on = decision["use_prepass"].as_bool().unwrap();
    assert_eq!(skipping["active_clusters"].is_u64(), on, "{skipping}");
    assert_eq!(skipping["fitted_depth_range"].is_array(), on, "{skipping}");
    assert!(skipping["max_image_difference"].as_u64().unwrap() <= 1);
    // A scene file fixes its own lights; a preset has no model cameras.
    let out = myriad_fails(&[
        "render",
        "--scene",
        scene.to_str().unwrap(),
        "--lights",
        "5",
    ]);
    assert_mentions(&out, &["--lights", "--scene"]);
    let out = myriad_fails(&["render", "--preset", "paper", "--camera", "Main"]);
    assert_mentions(&out, &["--camera", "--preset"]);
}

#[test]
fn paper_reproduces_both_tables_with_json_and_heat_map() {
    if !gpu_available() {
        return;
    }
    // Run in a fresh folder: the scene is Sponza only when ../shared/assets has it from there.
    let dir = work_dir("paper");
    let out_dir = dir.join("results");
    let out = Command::new(env!("CARGO_BIN_EXE_myriad"))
        .current_dir(&dir)
        .args(["paper", "--size", "192x96", "--runs", "1", "--out"])
        .arg(&out_dir)
        .output()
        .expect("cannot run the myriad binary");
    assert!(out.status.success(), "paper failed:\n{}", all_output(&out));
    let text = stdout(&out);
    let sponza = dir.join("../shared/assets/sponza/Sponza.gltf").is_file();
    assert_mentions(
        &text,
        &[
            if sponza {
                "scene: Sponza"
            } else {
                "scene: default scene (atrium)"
            },
            "192x96",
            "Table 1 — 1000 lights",
            "Table 2 — 10 lights",
            "the paper's Table 1",
            "Figure 4",
            "paper_heatmap.png",
        ],
    );
    if !sponza {
        assert_mentions(&text, &["not found", "--assets"]);
    }
    // Each table: its three grids and "no clustering", with the paper's row beside ours.
    let paper_rows = [
        ("Table 1", ["9.16", "8.28", "9.10", "156.00"]),
        ("Table 2", ["0.63", "0.64", "0.78", "1.60"]),
    ];
    for (table, paper_totals) in paper_rows {
        let start = text.find(table).unwrap();
        let lines: Vec<&str> = text[start..].lines().skip(3).take(4).collect();
        let configs = ["24x12x16", "24x12x32", "24x12x64", "no clustering"];
        for ((line, config), total) in lines.iter().zip(configs).zip(paper_totals) {
            assert!(
                line.starts_with(config),
                "{table}: {line:?} is not {config}"
            );
            assert!(
                line.contains(total),
                "{table}: no paper total {total} in {line:?}"
            );
        }
    }
    // Progress: one result line per configuration (and a start line each).
    let err = stderr(&out);
    let results = err
        .lines()
        .filter(|l| l.contains("/8] ") && l.contains(": shading "))
        .count();
    assert_eq!(results, 8, "{err}");

    let json = read_json(&out_dir.join("paper.json"));
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 8);
    for (i, row) in rows.iter().enumerate() {
        let lights = if i < 4 { 10 } else { 1000 };
        assert_eq!(row["lights"], lights, "{row}");
        assert_eq!(row["table"], if lights == 10 { 2 } else { 1 }, "{row}");
        let shading = row["shading_ms"].as_f64().unwrap();
        let total = row["total_ms"].as_f64().unwrap();
        assert!(shading > 0.0 && total >= shading, "{row}");
        assert!(row["paper"]["total_ms"].as_f64().unwrap() > 0.0, "{row}");
        if i % 4 < 3 {
            let z = [16, 32, 64][i % 4];
            assert_eq!(row["config"], format!("24x12x{z}"));
            assert_eq!(row["grid"], serde_json::json!([24, 12, z]));
            assert!(row["assign_ms"].as_f64().unwrap() > 0.0, "{row}");
            let pairs = u64_field(row, "pairs");
            assert!(pairs > 0, "{row}");
            // The CSR lists: offsets and counts per cluster, one index per pair.
            assert_eq!(u64_field(row, "list_bytes"), 4 * (2 * 24 * 12 * z + pairs));
            let mean = row["pixels"]["mean_lights"].as_f64().unwrap();
            assert!(mean < lights as f64, "{row}");
        } else {
            assert_eq!(row["config"], "no clustering");
            assert_eq!(row["assign_ms"].as_f64().unwrap(), 0.0);
            assert_eq!(u64_field(row, "list_bytes"), 0);
            assert_eq!(
                row["pixels"]["mean_lights"].as_f64().unwrap(),
                lights as f64
            );
        }
    }
    assert_eq!(json["heat_map"]["grid"], serde_json::json!([24, 12, 32]));
    let heat = out_dir.join("paper_heatmap.png");
    assert!(heat.is_file(), "no {}", heat.display());
    assert!(std::fs::metadata(&heat).unwrap().len() > 1000);

    // Sponza itself, where this checkout has the shared assets beside it (the run above, in a
    // fresh folder, never does): the paper's own scene and camera.
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets");
    if assets.join("sponza/Sponza.gltf").is_file() {
        let out = myriad_ok(&[
            "paper".as_ref(),
            "--assets".as_ref(),
            assets.as_os_str(),
            "--size".as_ref(),
            "96x48".as_ref(),
            "--runs".as_ref(),
            "1".as_ref(),
            "--out".as_ref(),
            dir.join("sponza").as_os_str(),
        ]);
        assert_mentions(
            &stdout(&out),
            &["scene: Sponza", "camera CameraMain", "Table 1", "Table 2"],
        );
    } else {
        eprintln!("{} has no Sponza: only the atrium run", assets.display());
    }

    // Bad options fail before any rendering, naming the option.
    assert_rejected(&[
        (&["paper", "--runs", "0"], &["--runs", "at least 1"]),
        (&["paper", "--size", "192"], &["--size", "WxH"]),
        (
            &["paper", "--assets", "/nonexistent/assets"],
            &["--assets", "/nonexistent/assets", "no such folder"],
        ),
        (
            &["paper", "--depth", "cubic"],
            &["--depth", "log, linear or log_near:D"],
        ),
    ]);
}

#[test]
fn report_covers_every_scene_grid_and_method_and_draws_the_fronts() {
    let dir = work_dir("report");
    let out = myriad_ok(&[
        "report",
        "--lights",
        "500",
        "--grids",
        "8x4x8,16x9x24",
        "--runs",
        "3",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let (scenes, grids, methods) = (
        ["paper", "uniform", "sphere"],
        ["8×4×8", "16×9×24"],
        ["exact", "linear", "binary", "refined", "cone"],
    );

    // report.md, also printed to stdout: one table row per scene × grid × method, no misses.
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert_eq!(stdout(&out), md);
    assert_mentions(&md, &["shading cost", "| scene | grid | method |"]);
    let rows: Vec<Vec<&str>> = md
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| scene") && !l.starts_with("| ---"))
        .map(|l| l.trim_matches('|').split('|').map(str::trim).collect())
        .collect();
    assert_eq!(rows.len(), 3 * 2 * methods.len(), "{md}");
    for scene in scenes {
        for grid in grids {
            for method in methods {
                let row = rows
                    .iter()
                    .find(|r| r[..3] == [scene, grid, method])
                    .unwrap_or_else(|| panic!("no row for {scene} {grid} {method} in:\n{md}"));
                assert_eq!(row[6], "0", "misses in {row:?}");
            }
        }
        assert!(
            rows.iter().any(|r| r[0] == scene && r[8] == "✓"),
            "{scene} has no point on its Pareto front:\n{md}"
        );
    }
    // Progress: one stderr line per scene × grid.
    let progress = stderr(&out);
    for k in 1..=6 {
        assert!(progress.contains(&format!("[{k}/6] ")), "{progress}");
    }

    // report.json: every number, misses 0 everywhere.
    let report = read_json(&dir.join("report.json"));
    let json_rows = report["rows"].as_array().expect("a rows array");
    assert_eq!(json_rows.len(), 3 * 2 * methods.len());
    for r in json_rows {
        assert_eq!(u64_field(r, "misses"), 0, "{r}");
        assert!(r["median_us"].as_f64().is_some_and(|t| t > 0.0), "{r}");
        assert!(u64_field(r, "pairs") > 0, "{r}");
        let exact = json_rows
            .iter()
            .find(|e| e["scene"] == r["scene"] && e["grid"] == r["grid"] && e["method"] == "exact")
            .unwrap();
        assert_eq!(exact["false_positive_ratio"].as_f64(), Some(0.0));
        // Every method lists a superset of the exact lights: never cheaper to shade than exact.
        assert!(
            r["shading_cost"].as_f64().unwrap() >= exact["shading_cost"].as_f64().unwrap(),
            "{r} vs {exact}"
        );
        assert_eq!(r["lit_clusters"], exact["lit_clusters"]);
        assert!(r["false_positive_ratio"].as_f64().unwrap() >= 0.0, "{r}");
    }

    // report.svg: an SVG with the method and scene names and one Pareto-front line per scene and
    // error measure (false positives, shading cost)
    // (drawn in the front colour, #FF7F0E; the legend has one more sample of it).
    let svg = std::fs::read_to_string(dir.join("report.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") || svg.starts_with("<?xml"),
        "{}",
        &svg[..svg.len().min(200)]
    );
    assert!(svg.trim_end().ends_with("</svg>"));
    for name in methods.iter().chain(&scenes).chain(&grids) {
        assert!(svg.contains(name), "{name} not in the SVG");
    }
    let fronts = svg
        .lines()
        .filter(|l| l.starts_with("<polyline") && l.contains(r##"stroke="#FF7F0E""##))
        .count();
    assert_eq!(
        fronts,
        1 + 6,
        "legend sample + one front per scene and error measure"
    );

    // Bad options fail before measuring anything.
    let out = myriad_fails(&[
        "report",
        "--grids",
        "8x4x8,16x9",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_mentions(&out, &["--grids", "16x9"]);
    let out = myriad_fails(&["report", "--runs", "0", "--out", dir.to_str().unwrap()]);
    assert_mentions(&out, &["--runs"]);
}

#[test]
fn skips_measures_every_saving_and_the_image_stays() {
    if !gpu_available() {
        return;
    }
    let atrium = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/atrium.glb");
    let out = myriad_ok(&[
        "skips",
        "--gltf",
        atrium.to_str().unwrap(),
        "--size",
        "96x48",
        "--runs",
        "1",
        "--json",
    ]);
    let reports: Value = serde_json::from_str(&stdout(&out)).unwrap();
    let rows = reports[0]["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 8);
    for row in rows {
        assert!(
            row["after"]["max_image_difference"].as_u64().unwrap() <= 1,
            "{row}"
        );
    }
    let by_name = |prefix: &str| {
        rows.iter()
            .find(|r| r["saving"].as_str().unwrap().starts_with(prefix))
            .unwrap()
    };
    let cull = by_name("1.");
    assert!(cull["after"]["lights_assigned"].as_u64() < cull["before"]["lights_assigned"].as_u64());
    let active = by_name("2.");
    assert!(active["after"]["pairs"].as_u64() < active["before"]["pairs"].as_u64());
    let reuse = by_name("4.");
    assert_eq!(reuse["after"]["upload_bytes"], 0);
    assert_eq!(reuse["after"]["pairs"], 0);
    // Only the tuned row decides about the prepass, from probes of both kinds of frame.
    for row in rows {
        let tuned = row["saving"].as_str().unwrap().ends_with("tuned");
        assert_eq!(row["prepass_decision"].is_object(), tuned, "{row}");
    }
    let decision = &by_name("1-3 and 5, tuned")["prepass_decision"];
    assert!(
        decision["with_seconds"].as_f64().unwrap() > 0.0,
        "{decision}"
    );
    assert!(
        decision["without_seconds"].as_f64().unwrap() > 0.0,
        "{decision}"
    );
    assert_eq!(decision["frames_per_side"], 3);
    assert!(decision["use_prepass"].is_boolean(), "{decision}");
}

/// The stage times every `myriad stress --json` report carries.
const STRESS_STAGES: [&str; 8] = [
    "scene_ms",
    "assign_ms",
    "assign_again_ms",
    "gpu_setup_ms",
    "upload_ms",
    "encode_ms",
    "gpu_wall_ms",
    "check_ms",
];

/// Runs `myriad stress --json` with `args`; the parsed report (the run must succeed).
fn stress_json(args: &[&str]) -> Value {
    let mut all = vec!["stress", "--json"];
    all.extend_from_slice(args);
    let out = myriad_ok(&all);
    serde_json::from_str(&stdout(&out)).expect("stress --json prints one JSON object")
}

fn assert_stress_stages(report: &Value) {
    let stages = &report["stages"];
    for stage in STRESS_STAGES {
        let ms = stages[stage]
            .as_f64()
            .unwrap_or_else(|| panic!("stage {stage} missing in {stages}"));
        assert!(ms >= 0.0 && ms.is_finite(), "{stage}: {ms}");
    }
    assert!(stages["gpu_wall_ms"].as_f64().unwrap() > 0.0);
    if report["timestamps"] == true {
        for pass in ["gpu_gbuffer_ms", "gpu_shading_ms"] {
            assert!(
                stages[pass].as_f64().is_some(),
                "{pass} missing in {stages}"
            );
        }
    }
}

#[test]
fn stress_checks_every_cluster_against_the_oracle() {
    if !gpu_available() {
        return;
    }
    let r = stress_json(&["--lights", "20000", "--size", "64x36"]);
    assert_eq!(r["lights"], 20000);
    assert_eq!(
        (r["width"].as_u64(), r["height"].as_u64()),
        (Some(64), Some(36))
    );
    assert_eq!(r["passed"], true);
    let check = &r["check"];
    assert_eq!(check["mode"], "full");
    assert_eq!(check["misses"], 0);
    assert_eq!(check["first_miss"], Value::Null);
    assert_eq!(check["clusters_checked"], check["clusters_total"]);
    assert!(u64_field(check, "exact_pairs") > 0);
    let pairs = u64_field(&r["assignment"], "pairs");
    assert!(pairs > 0);
    // Every cluster was checked, so the reported pairs are all of them.
    assert_eq!(u64_field(check, "reported_pairs"), pairs);
    assert!(u64_field(check, "exact_pairs") <= pairs);
    // Lights (32 bytes or more each) and the lists went up.
    assert!(u64_field(&r, "upload_bytes") > 20000 * 32 + 4 * pairs);
    assert_stress_stages(&r);
}

#[test]
fn stress_checks_the_exact_method_independently() {
    if !gpu_available() {
        return;
    }
    // The exact method's lists were compared with themselves, a check that could not fail
    // (audit g1): every cluster goes through the independent oracle instead.
    let r = stress_json(&["--lights", "3000", "--size", "64x36", "--method", "exact"]);
    assert_eq!(r["passed"], true);
    let check = &r["check"];
    assert_eq!(check["mode"], "independent");
    assert_eq!(check["clusters_checked"], check["clusters_total"]);
    assert_eq!(check["misses"], 0);
    let pairs = u64_field(&r["assignment"], "pairs");
    // The exact method lists exactly the pairs the independent oracle finds.
    assert_eq!(u64_field(check, "exact_pairs"), pairs);
    assert_eq!(u64_field(check, "reported_pairs"), pairs);
}

#[test]
fn stress_samples_clusters_above_the_exact_limit() {
    if !gpu_available() {
        return;
    }
    let r = stress_json(&["--sample", "50", "--lights", "250000", "--size", "32x18"]);
    assert_eq!(r["passed"], true);
    let check = &r["check"];
    assert_eq!(check["mode"], "sampled");
    assert_eq!(check["clusters_checked"], 50);
    assert_eq!(check["misses"], 0);
    assert!(u64_field(check, "exact_pairs") > 0, "{check}");
    assert!(u64_field(check, "reported_pairs") >= u64_field(check, "exact_pairs"));
    assert_stress_stages(&r);
}

#[test]
fn stress_rejects_bad_options_clearly() {
    assert_rejected(&[
        (&["stress", "--lights", "0"], &["--lights", "at least 1"]),
        (
            &["stress", "--sample", "0", "--lights", "10"],
            &["--sample", "at least 1"],
        ),
        (&["stress", "--size", "64"], &["--size", "WxH"]),
        (&["stress", "--method", "guess"], &["guess", "refined"]),
        (&["stress", "--lights", "many"], &["--lights", "many"]),
        (
            &["bench", "--preset", "paper", "--threads", "1000000"],
            &["--threads 1000000", "at most 1024"],
        ),
        (
            &[
                "scene",
                "--gltf",
                "assets/atrium.glb",
                "--field",
                "clumps",
                "--clumps",
                "4294967295",
                "--lights",
                "2",
                "--out",
                "unused.json",
            ],
            &[
                "--clumps 4294967295",
                "between 1 and the number of lights (2)",
            ],
        ),
    ]);
}

#[test]
fn skipped_invalid_lights_are_counted_in_bench_output() {
    let dir = work_dir("skipped_counted");
    let scene = write(
        &dir,
        "one_bad.json",
        &scene_with_lights(
            r#"{"position": [0, 2, 0], "radius": 2}, {"position": [1, 2, 0], "radius": -1},
               {"position": [0, 1, -3], "radius": 1}"#,
        ),
    );
    let out = myriad_ok(&[
        "bench".as_ref(),
        "--scene".as_ref(),
        scene.as_os_str(),
        "--methods".as_ref(),
        "binary".as_ref(),
        "--runs".as_ref(),
        "1".as_ref(),
        "--json".as_ref(),
    ]);
    let report: Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(report["lights"].as_u64(), Some(2), "{report}");
    assert_eq!(report["lights_skipped"].as_u64(), Some(1), "{report}");
    assert_mentions(
        &all_output(&out),
        &["1 invalid light(s) skipped", "lights[1].radius"],
    );
}

#[test]
fn many_skipped_lights_are_counted_and_the_list_stops_after_ten() {
    let dir = work_dir("many_skipped");
    // One good light, then `bad` lights with a negative radius (file indices 1..=bad).
    let assign = |bad: usize| {
        let lights: Vec<String> = std::iter::once(r#"{"position": [0, 2, 0], "radius": 2}"#.into())
            .chain((0..bad).map(|i| format!(r#"{{"position": [{i}, 2, 0], "radius": -1}}"#)))
            .collect();
        let scene = write(
            &dir,
            &format!("bad_{bad}.json"),
            &scene_with_lights(&lights.join(", ")),
        );
        let dump = dir.join(format!("bad_{bad}.dump.json"));
        myriad_ok(&[
            "assign".as_ref(),
            "--scene".as_ref(),
            scene.as_os_str(),
            "--out".as_ref(),
            dump.as_os_str(),
        ])
    };
    let out = assign(12);
    let err = stderr(&out);
    assert_mentions(
        &err,
        &[
            "12 invalid light(s) skipped",
            "light 10 skipped",
            "… and 2 more",
        ],
    );
    assert!(!err.contains("light 11 skipped"), "{err}");
    assert_mentions(&stdout(&out), &["12 rejected"]);
    // Exactly ten: all listed, no summary line.
    let err = stderr(&assign(10));
    assert_mentions(&err, &["10 invalid light(s) skipped", "light 10 skipped"]);
    assert!(!err.contains("more"), "{err}");
}

#[test]
fn check_of_a_scene_no_light_touches_has_a_zero_ratio() {
    // Every light behind the camera: no exact pairs, and the ratio is 0, not 0 / 0.
    let dir = work_dir("no_pairs");
    let scene = write(
        &dir,
        "behind.json",
        &scene_with_lights(r#"{"position": [0, 2, 50], "radius": 1}"#),
    );
    let cmp = assign_and_check(&scene, "refined", &dir.join("dump.json"));
    assert_eq!(u64_field(&cmp, "exact_pairs"), 0, "{cmp}");
    assert_eq!(cmp["false_positive_ratio"], 0.0, "{cmp}");
}
