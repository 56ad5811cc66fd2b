//! `validate`, `scene` and the presets: a scene file is checked, named and generated as a user
//! expects, and a bad one is refused with the file, the light and the problem.

use super::*;

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
    // A file that parses but has problems is a verdict (1), not a run that broke (2).
    let out = myriad_exits(
        1,
        &["validate".as_ref(), "--scene".as_ref(), scene.as_os_str()],
    );
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

/// A grid of 2^22 × 2^21 × 2^21 clusters, 2^64: the product wrapped to 0 in u64, passed the
/// reader's check and panicked in `ClusterGrid::new` (exit 101, a backtrace) in every command
/// that reads a scene (audit).
#[test]
fn a_grid_whose_cluster_count_passes_u64_is_a_problem_not_a_panic() {
    let dir = work_dir("validate_wrapping_grid");
    let text = GOOD_SCENE.replace(
        r#""x": 24, "y": 12, "z": 16"#,
        r#""x": 4194304, "y": 2097152, "z": 2097152"#,
    );
    assert_ne!(text, GOOD_SCENE);
    let scene = write(&dir, "wrapping.json", &text);
    let out = myriad_exits(
        1,
        &["validate".as_ref(), "--scene".as_ref(), scene.as_os_str()],
    );
    assert_mentions(
        &out,
        &["18446744073709551616 clusters", "at most 4294967295"],
    );
    let dump = dir.join("dump.json");
    for command in ["assign", "bench"] {
        let mut args = vec![command.as_ref(), "--scene".as_ref(), scene.as_os_str()];
        if command == "assign" {
            args.extend(["--out".as_ref(), dump.as_os_str()]);
        }
        let out = myriad_exits(2, &args);
        assert_mentions(
            &out,
            &[
                &scene.display().to_string(),
                "18446744073709551616 clusters",
            ],
        );
    }
    let report = dir.join("report");
    let out = myriad_exits(
        2,
        &[
            "report".as_ref(),
            "--grids".as_ref(),
            "4194304x2097152x2097152".as_ref(),
            "--out".as_ref(),
            report.as_os_str(),
        ],
    );
    assert_mentions(&out, &["--grids", "18446744073709551616 clusters"]);
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
fn surface_lights_stay_inside_the_atrium_and_out_of_its_solids_unless_all_faces_are_asked_for() {
    let dir = work_dir("scene_all_faces");
    let atrium = format!("{}/assets/atrium.glb", env!("CARGO_MANIFEST_DIR"));
    // The atrium's bounds (outer walls, the floor slab's underside, the walls' tops).
    let inside = |p: &Value| {
        let c: Vec<f64> = (0..3).map(|i| p[i].as_f64().unwrap()).collect();
        c[0].abs() <= 15.0 && (-0.2..=13.0).contains(&c[1]) && c[2].abs() <= 7.5
    };
    // Inside the floor slab, below its top and down to its underside (lifted off a wall's or a
    // plinth's foot: y = −0.2).
    let in_slab = |p: &Value| {
        let c: Vec<f64> = (0..3).map(|i| p[i].as_f64().unwrap()).collect();
        c[0].abs() < 15.0 && (-0.201..-1e-3).contains(&c[1]) && c[2].abs() < 7.5
    };
    let outside_count = |extra: &[&str]| {
        let scene = dir.join("s.scene");
        let args = [
            &["scene", "--gltf", &atrium, "--lights", "1000"][..],
            extra,
            &["--out", scene.to_str().unwrap()],
        ]
        .concat();
        let said = stdout(&myriad_ok(&args));
        let lights = read_json(&scene)["lights"].as_array().unwrap().clone();
        assert_eq!(lights.len(), 1000);
        let outside = lights.iter().filter(|l| !inside(&l["position"])).count();
        let buried = lights.iter().filter(|l| in_slab(&l["position"])).count();
        (said, outside, buried)
    };
    let (said, outside, buried) = outside_count(&[]);
    assert_eq!((outside, buried), (0, 0), "{said}");
    assert_mentions(
        &said,
        &[
            "of 11048 faces left out: 4706 pressed flat against others",
            "; the parts of 330 more where they touch another;",
            "; 34 turned away from the camera",
            "--all-faces keeps every face",
        ],
    );
    let (said, outside, buried) = outside_count(&["--all-faces"]);
    assert!(outside > 200, "{outside} of 1000 outside with --all-faces");
    assert!(
        buried > 0,
        "none of 1000 in the floor slab with --all-faces"
    );
    assert!(!said.contains("left out"), "{said}");
    // An offset that lifts every face's lights out of the atrium: only the faces turned
    // towards the camera are used, and that is said (the choice went silent before).
    let (said, _, _) = outside_count(&["--offset", "31"]);
    assert_mentions(&said, &["; 3064 turned away from the camera"]);
}

#[test]
fn a_models_names_reach_the_terminal_escaped_and_shared_names_are_said() {
    let dir = work_dir("model_names");
    let hostile = r#"Ma\u001b[2J\u001b[31mIN\r\nerror: fake"#;
    let model = gltf_with_cameras(
        &dir,
        "names.gltf",
        &[
            &format!(r#"{{"name": "{hostile}", {PERSPECTIVE}}}"#),
            &format!(r#"{{"name": "Twin", {PERSPECTIVE}}}"#),
            &format!(r#"{{"name": "Twin", {PERSPECTIVE}}}"#),
        ],
    );
    let out = myriad_ok(&["info".as_ref(), "--gltf".as_ref(), model.as_os_str()]);
    let text = all_output(&out);
    assert!(!text.contains('\u{1b}') && !text.contains('\r'), "{text:?}");
    assert_mentions(
        &text,
        &[
            "Ma\\u{1b}[2J\\u{1b}[31mIN\\r\\nerror: fake",
            "2 cameras are named \"Twin\"; looked up by that name, the first is used",
        ],
    );
    let out_file = dir.join("s.json");
    let text = myriad_fails(&[
        "scene".as_ref(),
        "--gltf".as_ref(),
        model.as_os_str(),
        "--camera".as_ref(),
        "nope".as_ref(),
        "--out".as_ref(),
        out_file.as_os_str(),
    ]);
    assert!(!text.contains('\u{1b}') && !text.contains('\r'), "{text:?}");
    assert_mentions(&text, &["no camera named \"nope\"", "\\u{1b}[2J"]);
    // Its first camera, by default: named in the summary line, escaped.
    let out = myriad_ok(&[
        "scene".as_ref(),
        "--gltf".as_ref(),
        model.as_os_str(),
        "--lights".as_ref(),
        "3".as_ref(),
        "--out".as_ref(),
        out_file.as_os_str(),
    ]);
    let text = all_output(&out);
    assert!(!text.contains('\u{1b}') && !text.contains('\r'), "{text:?}");
    assert_mentions(&text, &["camera Ma\\u{1b}[2J"]);
}

#[test]
fn an_orthographic_camera_chosen_by_name_is_refused_naming_the_model() {
    let dir = work_dir("ortho_by_name");
    let model = gltf_with_cameras(
        &dir,
        "ortho.gltf",
        &[&format!(r#"{{"name": "Flat", {ORTHOGRAPHIC}}}"#)],
    );
    let out_file = dir.join("s.json");
    let text = myriad_fails(&[
        "scene".as_ref(),
        "--gltf".as_ref(),
        model.as_os_str(),
        "--camera".as_ref(),
        "Flat".as_ref(),
        "--out".as_ref(),
        out_file.as_os_str(),
    ]);
    assert_mentions(
        &text,
        &["ortho.gltf: camera \"Flat\" is orthographic", "perspective"],
    );
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
            &[&base[..], &["--field", "box", "--all-faces"]].concat(),
            &["--all-faces only applies to --field surfaces"],
        ),
        // Negative values reach the field's own checks, not clap's "unexpected argument".
        (
            &[&base[..], &["--offset", "-1"]].concat(),
            &["surface offset must be finite and >= 0, got -1"],
        ),
        (
            &[&base[..], &["--radii=-1..2"]].concat(),
            &["radii must satisfy 0 < min <= max, got -1..2"],
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
