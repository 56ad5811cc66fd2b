//! `assign`, `check` and `bench`: every method passes the oracle check through dump files, a
//! broken dump or a missing light is caught, and invalid lights are skipped, counted and never
//! renumbered.

use super::*;

#[test]
fn every_method_passes_the_oracle_check() {
    let dir = work_dir("methods_check");
    let paper = paper_scene(&dir, 300);
    let scene = paper.clone();
    let hand_written = write(&dir, "good.json", GOOD_SCENE);
    for scene in [&scene, &hand_written] {
        let mut pairs = std::collections::HashMap::new();
        for method in ["exact", "linear", "binary", "refined", "cone"] {
            let dump = dir.join(format!("{method}.dump.json"));
            let cmp = assign_and_check(scene, method, &dump);
            let context = format!("{} / {method}: {cmp}", scene.display());
            pairs.insert(method, u64_field(&cmp, "reported_pairs"));
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
            // The dump has the documented shape (docs/cli.md, "`myriad assign`").
            let d = read_json(&dump);
            assert_eq!(d["grid"], serde_json::json!([24, 12, 16]));
            assert_eq!(d["x_edges"].as_array().unwrap().len(), 25);
            assert_eq!(d["y_edges"].as_array().unwrap().len(), 13);
            assert_eq!(d["z_planes"].as_array().unwrap().len(), 17);
            assert_eq!(d["offsets"].as_array().unwrap().len(), 24 * 12 * 16);
            assert_eq!(d["counts"].as_array().unwrap().len(), 24 * 12 * 16);
        }
        // Each method is the one asked for: on the `paper` scene their lists differ as the
        // methods do (an `assign` that ran `binary` for `refined` passed every test: audit).
        if scene == &paper {
            let p = |m: &str| pairs[m];
            assert!(
                p("exact") < p("refined") && p("refined") < p("binary"),
                "pairs by method: {pairs:?}"
            );
            assert!(p("cone") < p("binary"), "pairs by method: {pairs:?}");
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
        assert_eq!(
            cmp["scene_grid"],
            serde_json::json!([24, 12, 16]),
            "{context}"
        );
        assert_eq!(cmp["coarsened"], true, "{context}");
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
    let cmp = check_json(&scene, &full);
    assert_eq!(cmp["grid"], cmp["scene_grid"], "{cmp}");
    assert_eq!(cmp["coarsened"], false, "{cmp}");
    // A grid no coarsening of the scene's reaches is still refused: 20x12x16 halves to
    // 10x6x8, 5x3x4, 2x1x2, 1x1x1, never 6x3x4. (The same lights and camera: the dump's scene
    // record matches, and the grid is what differs.)
    let mut other = read_json(&scene);
    other["grid"]["x"] = Value::from(20);
    let other = write(&dir, "other.json", &other.to_string());
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
        // The dump is named where the verdict is: on stderr and in the JSON.
        let broken = broken.to_str().unwrap();
        assert_eq!(cmp["dump"], broken, "{reference}: {cmp}");
        let named = format!("error: {broken}: 1 miss(es)");
        assert_mentions(&stderr(&out), &[&named, &format!("cluster {c}")]);
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
        // The skipped light is counted apart from the assigned ones.
        assert_mentions(
            &stdout(&out),
            &["assigned 3 lights (3 visible, 0 culled, 0 rejected; 1 skipped on load)"],
        );

        // The dump names lights by their index in the file: 0, 1 and 3, never 2.
        let dump = read_json(&bad_dump);
        assert_eq!(dump_lights(&dump), [0, 1, 3], "{method}");
        let culled_dump = dir.join(format!("with_culled.{method}.json"));
        let out = myriad_ok(&[
            "assign".as_ref(),
            "--scene".as_ref(),
            with_culled.as_os_str(),
            "--method".as_ref(),
            method.as_ref(),
            "--out".as_ref(),
            culled_dump.as_os_str(),
        ]);
        // No pair budget, so no coarser grid, and no warning that says there was one.
        let warned = stderr(&out);
        assert!(!warned.contains("budget"), "{method}: {warned}");
        // The same lists; the scenes they record differ (light 2 is loaded in one only).
        let mut culled = read_json(&culled_dump);
        let lists = |d: &Value| {
            let mut d = d.clone();
            let scene = d.as_object_mut().unwrap().remove("scene");
            (d, scene)
        };
        let ((bad_lists, bad_scene), (culled_lists, culled_scene)) = (lists(&dump), lists(&culled));
        assert_eq!(bad_lists, culled_lists, "{method}");
        assert_eq!(bad_scene.as_ref().unwrap()["lights"], 4, "{method}");
        assert_ne!(bad_scene, culled_scene, "{method}");

        // check compares in file indices too, with either scene: each dump against its own, and
        // one without its scene record (the bare format) against the other. With the record,
        // the other scene is refused as other lights.
        let bare = write(&dir, "bare.json", &bad_lists.to_string());
        for (scene, dump) in [(&with_bad, &bad_dump), (&with_culled, &bare)] {
            let cmp = check_json(scene, dump);
            assert_eq!(u64_field(&cmp, "misses"), 0, "{method}: {cmp}");
            assert!(u64_field(&cmp, "exact_pairs") > 0);
            if method == "exact" {
                assert_eq!(u64_field(&cmp, "false_positives"), 0, "{cmp}");
            }
        }
        culled["scene"] = bad_scene.unwrap();
        let swapped = write(&dir, "swapped.json", &culled.to_string());
        assert_mentions(
            &myriad_fails(&[
                "check".as_ref(),
                "--scene".as_ref(),
                with_culled.as_os_str(),
                "--dump".as_ref(),
                swapped.as_os_str(),
            ]),
            &["swapped.json does not match", "assigned from other lights"],
        );
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
    // passed as a false positive (audit g2). The last two clusters gain light 2: one light, two
    // pairs.
    let mut dump = read_json(&exact_dump);
    let numbers = |key: &str| -> Vec<u64> {
        dump[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .collect()
    };
    let (offsets, counts, indices) = (numbers("offsets"), numbers("counts"), numbers("indices"));
    let mut lists: Vec<Vec<u64>> = offsets
        .iter()
        .zip(&counts)
        .map(|(&o, &n)| indices[o as usize..(o + n) as usize].to_vec())
        .collect();
    let clusters = lists.len();
    lists[clusters - 2].push(2);
    lists[clusters - 1].push(2);
    let mut flat: Vec<u64> = Vec::new();
    let mut new_offsets = Vec::new();
    for list in &lists {
        new_offsets.push(flat.len() as u64);
        flat.extend(list);
    }
    dump["offsets"] = new_offsets.into();
    dump["counts"] = lists
        .iter()
        .map(|l| l.len() as u64)
        .collect::<Vec<_>>()
        .into();
    dump["indices"] = flat.into();
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
    assert_eq!(u64_field(&cmp, "invalid_pairs"), 2, "{cmp}");
    assert_mentions(
        &stderr(&out),
        &["lists 1 invalid light(s)", "in 2 pair(s)", "light 2"],
    );
}

/// A dump written to stdout (`--out /dev/stdout | jq`) is the whole of stdout: the summary line
/// goes to stderr when the output is not a regular file (it was glued to the dump's end).
#[test]
fn a_dump_to_stdout_is_all_of_stdout() {
    let out = myriad(&[
        "assign",
        "--preset",
        "paper",
        "--lights",
        "50",
        "--method",
        "binary",
        "--out",
        "/dev/stdout",
    ]);
    assert!(out.status.success(), "{}", all_output(&out));
    let dump: Value = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("stdout is not one JSON value ({e}):\n{}", stdout(&out)));
    assert_eq!(dump["grid"], serde_json::json!([24, 12, 16]));
    assert_mentions(&stderr(&out), &["assigned 50 lights", "wrote /dev/stdout"]);
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
    // The first index past the last light (a bound one loose let it through to a panic: audit).
    let one_past = edited("one_past.json", &|v| v["indices"][0] = Value::from(4));
    assert_mentions(
        &check(&one_past),
        &[
            &one_past.display().to_string(),
            "indices[0] = 4, but the scene has 4 lights",
        ],
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

/// A dump checked against the wrong scene file — the same preset with another seed, or the
/// same scene with its camera moved — has the very grid and planes of the right one: without
/// the scene record `assign` writes, `check` judged it and reported hundreds of misses. Now it
/// is an error (exit 2) naming the difference; the record's scene itself still passes, and a
/// dump without the record (the bare format) is judged as before.
#[test]
fn check_names_a_dump_of_other_lights_or_another_view() {
    let dir = work_dir("other_scene_dump");
    let scene_of = |name: &str, seed: &str| {
        let path = dir.join(name);
        myriad_ok(&[
            "scene".as_ref(),
            "--preset".as_ref(),
            "paper".as_ref(),
            "--lights".as_ref(),
            "300".as_ref(),
            "--seed".as_ref(),
            seed.as_ref(),
            "--out".as_ref(),
            path.as_os_str(),
        ]);
        path
    };
    let scene = scene_of("seed1.json", "1");
    let reseeded = scene_of("seed2.json", "2");
    let dump = dir.join("seed1.dump.json");
    let cmp = assign_and_check(&scene, "refined", &dump);
    assert_eq!(u64_field(&cmp, "misses"), 0, "{cmp}");
    let d = read_json(&dump);
    assert_eq!(d["scene"]["lights"], 300, "{}", d["scene"]);
    assert_eq!(d["scene"]["camera"]["width"], 1536, "{}", d["scene"]);
    let check = |scene: &Path, dump: &Path| {
        myriad_fails(&[
            "check".as_ref(),
            "--scene".as_ref(),
            scene.as_os_str(),
            "--dump".as_ref(),
            dump.as_os_str(),
        ])
    };
    assert_mentions(
        &check(&reseeded, &dump),
        &[
            &format!("{} does not match", dump.display()),
            "assigned from other lights",
        ],
    );
    // Moved, or only turned: a turned camera keeps the grid's planes, so only the record tells
    // (review: a check that skipped `target` passed every test, and judged such dumps).
    for (field, value, said) in [
        ("position", 0.25, "another view: its camera has position"),
        ("target", 4.5, "another view: its camera has target"),
    ] {
        let mut moved = read_json(&scene);
        moved["camera"][field][1] = Value::from(value);
        let moved = write(&dir, &format!("moved_{field}.json"), &moved.to_string());
        assert_mentions(
            &check(&moved, &dump),
            &[&format!("{} does not match", dump.display()), said],
        );
    }
    // Fewer lights: said as such, before the indices past them are.
    let mut fewer = read_json(&scene);
    fewer["lights"].as_array_mut().unwrap().truncate(250);
    let fewer = write(&dir, "fewer.json", &fewer.to_string());
    assert_mentions(
        &check(&fewer, &dump),
        &["assigned from a scene of 300 lights, this one has 250"],
    );
    // `--bare` writes DESIGN.md's keys only; such a dump names no scene, so the other seed's
    // lights are judged by the oracle, which finds misses (exit 1) — what the record prevents.
    let bare = dir.join("bare.dump.json");
    myriad_ok(&[
        "assign".as_ref(),
        "--scene".as_ref(),
        scene.as_os_str(),
        "--bare".as_ref(),
        "--out".as_ref(),
        bare.as_os_str(),
    ]);
    let mut stamped = d.clone();
    stamped.as_object_mut().unwrap().remove("scene");
    assert_eq!(
        read_json(&bare),
        stamped,
        "--bare: the same dump without `scene`"
    );
    assert_eq!(u64_field(&check_json(&scene, &bare), "misses"), 0);
    let out = myriad(&[
        "check".as_ref(),
        "--scene".as_ref(),
        reseeded.as_os_str(),
        "--dump".as_ref(),
        bare.as_os_str(),
        "--json".as_ref(),
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", all_output(&out));
    let verdict: Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert!(u64_field(&verdict, "misses") > 100, "{verdict}");
}

/// The documented defaults (docs/cli.md): a preset of 1000 lights, seed 1, timed 21 times. (Any
/// of the three could change and every test passed: audit.)
#[test]
fn bench_defaults_are_the_documented_ones() {
    let out = myriad_ok(&[
        "bench",
        "--preset",
        "paper",
        "--json",
        "--methods",
        "binary",
    ]);
    let report: Value = serde_json::from_str(&stdout(&out)).expect("bench --json prints JSON");
    assert_eq!(
        report["scene"].as_str(),
        Some("preset paper (1000 lights, seed 1)")
    );
    assert_eq!(report["lights"].as_u64(), Some(1000));
    assert_eq!(report["methods"][0]["runs"].as_u64(), Some(21), "{report}");
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

/// `--caller`: timed from the main thread, outside any pool — working beside helper jobs on the
/// global pool (`outside`) or handing each frame to it (`hand-off`) — every method lists what a
/// worker's calls list, and the report says where the calls came from. `--threads` cannot pick
/// the global pool's size, which is fixed when the program starts: another count is refused.
#[test]
fn bench_times_calls_from_outside_the_pool() {
    let mut pairs = Vec::new();
    for caller in ["worker", "outside", "hand-off"] {
        let args = [
            "bench",
            "--preset",
            "paper",
            "--lights",
            "800",
            "--methods",
            "binary,refined",
            "--runs",
            "3",
            "--always-parallel",
            "--json",
            "--caller",
            caller,
        ];
        let report: Value = serde_json::from_str(&stdout(&myriad_ok(&args))).unwrap();
        assert_eq!(report["caller"], caller);
        for m in report["methods"].as_array().unwrap() {
            assert_eq!(u64_field(m, "misses"), 0, "{caller}: {m}");
            assert_eq!(u64_field(m, "pooled_runs"), 3, "{caller}: {m}");
            pairs.push(u64_field(m, "pairs"));
        }
    }
    assert!(pairs[0] > 0 && pairs[1] > 0);
    assert_eq!(pairs[..2], pairs[2..4]);
    assert_eq!(pairs[..2], pairs[4..6]);
    let table = stdout(&myriad_ok(&[
        "bench",
        "--preset",
        "paper",
        "--lights",
        "600",
        "--methods",
        "binary",
        "--runs",
        "3",
        "--caller",
        "hand-off",
    ]));
    assert_mentions(
        &table,
        &["called from outside the pool, each frame handed off"],
    );
    let out = myriad_fails(&[
        "bench",
        "--preset",
        "paper",
        "--caller",
        "outside",
        "--threads",
        "97",
    ]);
    assert_mentions(&out, &["--threads 97", "RAYON_NUM_THREADS=97"]);
}

/// The `exact` method, the slow oracle-backed one, is timed at most three times whatever `--runs`
/// asks; every other method takes all the runs asked for.
#[test]
fn bench_times_the_exact_method_at_most_three_times() {
    let out = myriad_ok(&[
        "bench",
        "--preset",
        "paper",
        "--lights",
        "300",
        "--methods",
        "exact,binary",
        "--runs",
        "5",
        "--json",
    ]);
    let report: Value = serde_json::from_str(&stdout(&out)).unwrap();
    let runs: Vec<(String, u64)> = report["methods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            (
                m["method"].as_str().unwrap().to_string(),
                u64_field(m, "runs"),
            )
        })
        .collect();
    assert_eq!(
        runs,
        [("exact".to_string(), 3), ("binary".to_string(), 5)],
        "{report}"
    );
}

/// The text table: the scene line, a header, a row per method, and `binary` and `refined` each
/// compared with `linear` when `linear` ran (never `linear` or `cone`; no comparison without
/// `linear`).
#[test]
fn bench_table_compares_binary_and_refined_with_linear() {
    let table = |methods: &str| {
        stdout(&myriad_ok(&[
            "bench",
            "--preset",
            "paper",
            "--lights",
            "300",
            "--methods",
            methods,
            "--runs",
            "3",
        ]))
    };
    let text = table("linear,binary,refined,cone");
    assert_mentions(
        &text,
        &[
            "300 lights, grid 24x12x16",
            "median µs",
            "fp ratio",
            "on pool",
        ],
    );
    for method in ["linear", "binary", "refined", "cone"] {
        assert!(
            text.lines()
                .any(|l| l.starts_with(method) && l.trim_end().ends_with("/3")),
            "no row for {method}:\n{text}"
        );
    }
    let compared: Vec<&str> = text
        .lines()
        .filter(|l| l.ends_with("x faster than linear") || l.ends_with("x slower than linear"))
        .map(|l| l.split_whitespace().next().unwrap())
        .collect();
    assert_eq!(compared, ["binary", "refined"], "{text}");
    // "0.5x faster" was printed for a slower method: the factor is always at least 1.
    for line in text.lines().filter(|l| l.ends_with("than linear")) {
        let factor: f64 = line
            .split_whitespace()
            .nth(2)
            .unwrap()
            .trim_end_matches('x')
            .parse()
            .unwrap();
        assert!(factor >= 1.0, "{line}");
    }
    let text = table("binary,refined");
    assert!(!text.contains("than linear"), "{text}");
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
            // The warning names the file (audit).
            "bad_12.json: 12 invalid light(s) skipped",
            "light 10 skipped",
            "… and 2 more",
        ],
    );
    assert!(!err.contains("light 11 skipped"), "{err}");
    assert_mentions(&stdout(&out), &["0 rejected; 12 skipped on load"]);
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

/// An audit's scene (a miss hunt, 2026-11-30): a 179.985° view on a 65536×3 target and one needle
/// spot wholly behind the eye. The oracle listed it in two clusters it does not touch (its band
/// grew with the cells' corners), so `check` called the fast methods' right lists misses; now
/// nothing is exact, every method passes, and the text says the ratio has nothing to divide by
/// where the JSON keeps its 0.
#[test]
fn a_needle_spot_behind_the_eye_of_a_nearly_flat_view_is_no_miss() {
    let dir = work_dir("needle_behind_the_eye");
    let scene = write(
        &dir,
        "needle.json",
        r#"{"camera": {"position": [232.95943, -182.32129, -140.78365],
             "target": [211.74008, -493.58524, -240.76201],
             "up": [0.9979002652071821, -0.06166629543554522, -0.019807289231281992],
             "fov_y_deg": 179.98494, "width": 65536, "height": 3,
             "near": 0.004788006, "far": 21310670},
           "grid": {"x": 5, "y": 8, "z": 12, "depth": "linear"},
           "lights": [{"position": [215.73712, 199402.8, -621508.06], "radius": 652470.06,
                       "spot": {"direction": [1, 2.6444755e-05, -5.159902e-09],
                                "angle_deg": 0.00022360485825471512}}]}"#,
    );
    for method in ["exact", "binary", "refined", "cone"] {
        let dump = dir.join(format!("{method}.dump.json"));
        let cmp = assign_and_check(&scene, method, &dump);
        assert_eq!(u64_field(&cmp, "exact_pairs"), 0, "{method}: {cmp}");
        assert_eq!(u64_field(&cmp, "misses"), 0, "{method}: {cmp}");
        if method == "binary" {
            assert!(u64_field(&cmp, "false_positives") > 0, "{cmp}");
            let text = stdout(&myriad_ok(&[
                "check".as_ref(),
                "--scene".as_ref(),
                scene.as_os_str(),
                "--dump".as_ref(),
                dump.as_os_str(),
            ]));
            assert_mentions(&text, &["false-positive ratio  n/a (no exact pairs"]);
        }
    }
}
