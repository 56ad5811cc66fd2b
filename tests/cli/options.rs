//! Options every subcommand shares the parsing of: a bad value fails before any work, with a
//! message that names the option and what it takes.

use super::*;

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

#[cfg(target_os = "linux")]
/// `MemAvailable` from `/proc/meminfo` in bytes (the figure the memory check uses), if known.
fn available_memory_bytes() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

// Linux: the memory check reads /proc/meminfo, so there the test must reach it.
#[cfg(target_os = "linux")]
#[test]
fn a_light_count_beyond_memory_is_refused_before_generating() {
    // u32::MAX lights need 1 TiB at 256 bytes a light: refused up front, as `assign` and
    // `scene` refuse them. Generating them first aborted with "memory allocation of 17179869132
    // bytes failed" under an address-space cap, and ground on without one.
    let needed = 256 * u64::from(u32::MAX);
    let available = available_memory_bytes().expect("MemAvailable in /proc/meminfo");
    if available >= needed {
        eprintln!(
            "note: not run: {available} bytes are available, at least the {needed} that \
             u32::MAX lights need, so nothing here would be refused"
        );
        return;
    }
    let max = u32::MAX.to_string();
    let runs: [&[&str]; 5] = [
        &[
            "frames", "--frames", "2", "--size", "16x16", "--lights", &max,
        ],
        &["stress", "--size", "16x16", "--lights", &max],
        &["render", "--size", "16x16", "--runs", "1", "--lights", &max],
        &["skips", "--size", "16x16", "--lights", &max],
        &["report", "--grids", "4x4x4", "--lights", &max],
    ];
    for args in runs {
        // Under a 6 GB address-space cap, so that a regression aborts at once instead of
        // swapping the machine; the check itself needs next to nothing.
        let capped = [
            &[
                "-c",
                r#"ulimit -v 6000000 && exec "$0" "$@""#,
                env!("CARGO_BIN_EXE_myriad"),
            ][..],
            args,
        ]
        .concat();
        let out = Command::new("sh").args(&capped).output().unwrap();
        let text = all_output(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}:\n{text}");
        assert!(!text.contains("panicked"), "{text}");
        assert_mentions(&text, &[&format!("{max} lights needs at least"), "GiB"]);
    }
}

#[cfg(unix)]
#[test]
fn a_light_count_beyond_an_address_space_cap_is_refused() {
    // 10M lights under a 1.5 GB cap: the check looked only at MemAvailable and counted 64 bytes
    // a light, so it passed and the run aborted in its allocator (exit 134, audit); now the cap's
    // headroom counts, at 256 bytes a light (2.4 GiB here), whatever the machine's memory.
    let out = Command::new("sh")
        .args([
            "-c",
            r#"ulimit -v 1500000 && exec "$0" "$@""#,
            env!("CARGO_BIN_EXE_myriad"),
            "stress",
            "--size",
            "32x18",
            "--lights",
            "10000000",
        ])
        .output()
        .unwrap();
    let text = all_output(&out);
    assert_eq!(out.status.code(), Some(2), "{text}");
    assert!(!text.contains("panicked"), "{text}");
    assert_mentions(
        &text,
        &[
            "10000000 lights needs at least 2.4 GiB",
            "address-space limit",
        ],
    );
}

#[test]
fn a_list_option_naming_an_item_twice_is_refused() {
    // `report --grids 4x4x4,4x4x4` timed and reported every row twice, where `bench --methods`
    // already refused a repeat; compared as parsed, so a second spelling is a repeat too.
    let dir = work_dir("list_repeats");
    let out = dir.join("report");
    let out = out.to_str().unwrap();
    assert_rejected(&[
        (
            &["report", "--grids", "4x4x4,4x4x4", "--out", out],
            &["--grids lists 4x4x4 twice"],
        ),
        (
            &["report", "--grids", "4x4x4,2x2x2,04x4x4", "--out", out],
            &["--grids lists 4x4x4 twice"],
        ),
        (
            &[
                "skips",
                "--gltf",
                "assets/atrium.glb",
                "--gltf",
                "assets/atrium.glb",
            ],
            &["--gltf lists assets/atrium.glb twice"],
        ),
        (
            // Two spellings of one file are one model, measured once.
            &[
                "skips",
                "--gltf",
                "assets/atrium.glb",
                "--gltf",
                "./assets/../assets/atrium.glb",
            ],
            &["--gltf lists ./assets/../assets/atrium.glb twice"],
        ),
    ]);
    assert!(!dir.join("report").exists(), "nothing is written");
}

#[test]
fn skips_takes_two_different_models_for_two_not_a_repeat() {
    // Two files are two models: the run goes on to load both, and stops at the one that is not
    // there, by its name (not "lists it twice"); without an adapter it stops before loading.
    let absent = work_dir("skips_two_models").join("absent.glb");
    let absent = absent.to_str().unwrap();
    let text = myriad_fails(&["skips", "--gltf", "assets/atrium.glb", "--gltf", absent]);
    assert!(!text.contains("twice"), "{text}");
    if gpu_available() {
        assert_mentions(&text, &[absent]);
    }
}

/// The names of the threads of process `pid` (Linux: `/proc/PID/task/*/comm`).
#[cfg(target_os = "linux")]
fn thread_names(pid: u32) -> Vec<String> {
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return Vec::new();
    };
    tasks
        .filter_map(|task| std::fs::read_to_string(task.ok()?.path().join("comm")).ok())
        .map(|name| name.trim_end().to_string())
        .collect()
}

#[cfg(target_os = "linux")]
#[test]
fn the_worker_threads_are_started_and_named_before_any_work() {
    // The global pool's workers are named "rayon N" (Tracy, a debugger or `top` tell them
    // apart; unnamed, every one is "myriad"), and started first thing, before the command runs.
    // `scene --out FIFO` waits for the FIFO's reader, which holds the run alive to be looked at.
    let dir = work_dir("worker_thread_names");
    let fifo = dir.join("scene.fifo");
    let made = Command::new("mkfifo").arg(&fifo).status();
    assert!(
        made.is_ok_and(|s| s.success()),
        "mkfifo (coreutils) made no FIFO"
    );
    let mut child = Command::new(env!("CARGO_BIN_EXE_myriad"))
        .args(["scene", "--preset", "uniform", "--lights", "10", "--out"])
        .arg(&fifo)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("cannot run the myriad binary");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
    let mut names = thread_names(child.id());
    while !names.iter().any(|n| n == "rayon 0") && std::time::Instant::now() < deadline {
        assert!(
            child.try_wait().unwrap().is_none(),
            "myriad scene stopped before writing its FIFO"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
        names = thread_names(child.id());
    }
    // Read the scene, which lets the run finish.
    let scene = std::fs::read(&fifo).unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        scene.starts_with(b"{"),
        "{:?}",
        &scene[..20.min(scene.len())]
    );
    assert!(names.iter().any(|n| n == "rayon 0"), "{names:?}");
}

/// A closed stdout (`myriad bench … | true`) is a run that could not finish: exit 2 and one line
/// on stderr, as an unwritable `--out` gives. `println!` panicked there: exit 101 and a backtrace
/// from `check`, `info`, `bench` and `stress` (audit).
#[test]
fn a_closed_stdout_exits_2_with_one_line() {
    let dir = work_dir("a_closed_stdout_exits_2_with_one_line");
    let scene = write(&dir, "good.json", GOOD_SCENE);
    let atrium = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/atrium.glb");
    for args in [
        vec!["bench", "--methods", "binary", "--runs", "3", "--scene"],
        vec!["info", "--gltf"],
    ] {
        // A pipe whose reading end is closed before the run starts: its first write fails.
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let mut command = Command::new(env!("CARGO_BIN_EXE_myriad"));
        command.args(&args);
        command.arg(if args[0] == "info" { &atrium } else { &scene });
        let out = command
            .stdout(writer)
            .stderr(std::process::Stdio::piped())
            .output()
            .unwrap();
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(
            err.trim(),
            "error: cannot write to stdout: Broken pipe (os error 32)",
            "{args:?}"
        );
    }
}

#[cfg(unix)]
#[test]
fn lists_beyond_the_memory_coarsen_the_grid_instead_of_aborting() {
    // 20 000 lights of radius 10⁴ cover every cluster of the 24×12×16 grid: 92 M pairs, about
    // 2.2 GB at the peak of `assign`. Under a 1.5 GB cap the default pair budget follows the
    // memory available, so the grid coarsens (as under an explicit `--pair-budget`) where the
    // run aborted in its allocator (exit 134, stress audit).
    let dir = work_dir("memory_budget");
    let light = r#"{"position": [0, 2, 0], "radius": 10000}"#;
    let lights = vec![light; 20_000].join(", ");
    let scene = write(&dir, "huge.json", &scene_with_lights(&lights));
    let dump = dir.join("huge.dump.json");
    let out = Command::new("sh")
        .args([
            "-c".as_ref(),
            r#"ulimit -v 1500000 && exec "$0" "$@""#.as_ref(),
            env!("CARGO_BIN_EXE_myriad").as_ref(),
            "assign".as_ref(),
            "--scene".as_ref(),
            scene.as_os_str(),
            "--out".as_ref(),
            dump.as_os_str(),
        ])
        .output()
        .unwrap();
    let text = all_output(&out);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert_mentions(
        &text,
        &[
            "what the memory available holds",
            "they were built on the coarser",
        ],
    );
    // The coarser lists are right: every light in every cluster of the grid the dump records.
    let check = myriad(&[
        "check".as_ref(),
        "--scene".as_ref(),
        scene.as_os_str(),
        "--dump".as_ref(),
        dump.as_os_str(),
    ]);
    assert_eq!(check.status.code(), Some(0), "{}", all_output(&check));
}

#[cfg(unix)]
#[test]
fn bench_refuses_lists_beyond_the_memory_clearly() {
    // The scene of the test above: 92 M exact pairs, which `bench` holds beside each method's
    // (1.22 GB at its peak). Under a 1.2 GB cap the default pair budget follows the memory, and
    // the oracle's lists stop at it with exit 2 and the reason, where the allocator would abort.
    let dir = work_dir("bench_memory_budget");
    let light = r#"{"position": [0, 2, 0], "radius": 10000}"#;
    let lights = vec![light; 20_000].join(", ");
    let scene = write(&dir, "huge.json", &scene_with_lights(&lights));
    let out = Command::new("sh")
        .args([
            "-c".as_ref(),
            r#"ulimit -v 1200000 && exec "$0" "$@""#.as_ref(),
            env!("CARGO_BIN_EXE_myriad").as_ref(),
            "bench".as_ref(),
            "--scene".as_ref(),
            scene.as_os_str(),
            "--runs".as_ref(),
            "1".as_ref(),
        ])
        .output()
        .unwrap();
    let text = all_output(&out);
    assert_eq!(out.status.code(), Some(2), "{text}");
    assert_mentions(
        &text,
        &[
            "error: the oracle finds more than",
            "on the 24x12x16 grid",
            "what the memory available holds at 16 bytes a pair",
            "use a coarser grid or fewer lights",
        ],
    );
}

#[cfg(unix)]
#[test]
fn grids_long_in_one_axis_are_refused_before_they_exhaust_the_memory() {
    // 2e8 clusters in one row or one column of slices: the axis' planes and the dump's copy
    // cost more than the 16 bytes a cluster the check once asked for, and under a 6 GB cap
    // `assign` and `bench` aborted in the allocator (exit 134, hostile-input audit).
    let dir = work_dir("long_grids");
    for (name, grid) in [
        ("x", r#""x": 200000000, "y": 1, "z": 1"#),
        ("z", r#""x": 1, "y": 1, "z": 200000000"#),
    ] {
        let text = GOOD_SCENE.replace(r#""x": 24, "y": 12, "z": 16"#, grid);
        assert_ne!(text, GOOD_SCENE);
        let scene = write(&dir, &format!("{name}.json"), &text);
        let dump = dir.join("dump.json");
        let commands: [(&str, &[&std::ffi::OsStr]); 2] = [
            ("assign", &["--out".as_ref(), dump.as_os_str()]),
            ("bench", &[]),
        ];
        for (command, options) in commands {
            let out = Command::new("sh")
                .args([
                    "-c".as_ref(),
                    r#"ulimit -v 6000000 && exec "$0" "$@""#.as_ref(),
                    env!("CARGO_BIN_EXE_myriad").as_ref(),
                    command.as_ref(),
                    "--scene".as_ref(),
                    scene.as_os_str(),
                ])
                .args(options)
                .output()
                .unwrap();
            let text = all_output(&out);
            assert_eq!(out.status.code(), Some(2), "{command} {name}: {text}");
            assert!(!dump.exists(), "a refused assign wrote its dump");
            assert_mentions(&text, &["grid too large here", "needs at least 14.9 GiB"]);
        }
    }
}

#[cfg(unix)]
#[test]
fn images_beyond_the_memory_are_refused_before_any_is_allocated() {
    // 16384×16384 pixels took 11.7 GB at the peak of `render`; under an 8 GB cap it aborted in
    // the allocator reading the depth back (exit 134, hostile-input audit).
    let dir = work_dir("big_images");
    for command in ["render", "stress", "frames", "skips"] {
        let out = Command::new("sh")
            .args([
                "-c",
                r#"ulimit -v 8000000 && exec "$0" "$@""#,
                env!("CARGO_BIN_EXE_myriad"),
                command,
                "--size",
                "16384x16384",
                "--lights",
                "10",
            ])
            .current_dir(&dir)
            .output()
            .unwrap();
        let text = all_output(&out);
        assert_eq!(out.status.code(), Some(2), "{command}: {text}");
        assert_mentions(
            &text,
            &[
                "a 16384x16384 image needs at least 16.0 GiB",
                "use a smaller --size",
            ],
        );
    }
    // Nothing was written where `render` would have put its images.
    assert!(!dir.join("out").exists());
}
