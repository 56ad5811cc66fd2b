//! The `myriad` binary built with the `tracy` feature, captured over Tracy's own wire protocol by
//! a minimal server (`capture.rs`) as the profiler would capture it: what a profiling session
//! receives, not only what the code hands the client. The frame loop's spans arrive named and
//! nested on their threads, with the threads named; one frame mark per drawn frame; the plots;
//! and the renderer's GPU track: a named GPU context whose clock is tied to the CPU's, and one
//! GPU zone per timed pass and frame, each with both timestamps, lasting what the frame's
//! `GPU … ms` plot says; the same for the main job (`myriad render`) with its depth prepass.

mod capture;
mod protocol;

use std::process::{Command, Stdio};
use std::time::Duration;

/// A port no other test of this run is using: bound, read, released.
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// Held by each captured run: one at a time. Two at once (the test harness runs this binary's
/// tests in parallel) had the other run's llvmpipe threads hold both cores of the 2-vCPU
/// machine, so that a pool worker sometimes ran no task in any frame (no worker in the capture,
/// 1 run of 60) and a GPU clock tie waited long enough to put a pass's zone after its frame.
static ONE_CAPTURE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Runs `myriad` with `args` under a capture, and returns what the capture received and what the
/// command printed. The command must succeed.
fn captured_run(args: &[&str]) -> (capture::Capture, String) {
    // A failed run poisons the lock; the next one still runs alone.
    let _alone = ONE_CAPTURE_AT_A_TIME
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let port = free_port();
    let child = Command::new(env!("CARGO_BIN_EXE_myriad"))
        .args(args)
        .env("TRACY_NO_EXIT", "1")
        .env("TRACY_PORT", port.to_string())
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var("XDG_RUNTIME_DIR").unwrap_or("/tmp".into()),
        )
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let captured = capture::capture(port, Duration::from_secs(120));
    let output = child.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        output.status.success(),
        "myriad {args:?} failed:\n{stdout}\n{stderr}"
    );
    let c = captured.unwrap_or_else(|e| panic!("capture: {e}\n{stdout}\n{stderr}"));
    (c, stdout)
}

#[test]
fn a_profiler_receives_the_frame_loop_named_nested_and_timed() {
    let frames = 4;
    // Enough lights that every frame runs its tasks on the pool (pacing runs a frame under
    // 250 µs of work serially after idle) and outlasts a sleeping worker's wake-up: with 3000,
    // the calling thread sometimes did every task of all 8 frames itself and no pool worker
    // appeared in the capture (4 runs of 40).
    let lights = 20_000;
    let (c, _) = captured_run(&[
        "frames",
        "--lights",
        &lights.to_string(),
        "--size",
        "128x64",
        "--frames",
        &frames.to_string(),
    ]);
    let drawn = 2 * frames; // `frames` runs its loop sequentially, then pipelined
    assert_eq!(c.program, "myriad");
    assert!(c.nesting_errors.is_empty(), "{:?}", c.nesting_errors);
    assert_eq!(c.frame_marks, drawn, "one frame mark per drawn frame");

    // Threads: Tracy names the thread that started the client "Main thread" (whatever the OS
    // calls it); the pipelined loop's worker and the pool's threads by their own names.
    let threads: Vec<&str> = c.thread_names.values().map(String::as_str).collect();
    for name in ["Main thread", "cpu stage"] {
        assert!(threads.contains(&name), "no thread {name:?} in {threads:?}");
    }
    assert!(
        threads.iter().any(|t| t.starts_with("rayon ")),
        "no rayon worker named in {threads:?}"
    );

    // Spans: once per drawn frame for the frame's stages, on the threads that run them.
    let on = |name: &str| c.zone_threads.get(name).cloned().unwrap_or_default();
    for name in [
        "animate orbits",
        "cull lights",
        "gather visible lights",
        "cpu stage: animate and assign",
        "assign on one grid",
        "append",
        "upload lights and lists",
        "encode and submit",
        "encode pass: G-buffer",
        "encode pass: deferred shading",
        "encode pass: forward",
        "wait for GPU",
    ] {
        assert_eq!(c.zones.get(name), Some(&drawn), "{name}: {:?}", c.zones);
    }
    assert!(on("cpu stage: animate and assign").contains("cpu stage"));
    assert!(on("wait for GPU").iter().all(|t| t == "Main thread"));
    assert!(
        on("assign task").iter().any(|t| t.starts_with("rayon ")),
        "no assign task on a pool worker: {:?}",
        on("assign task")
    );
    let tasks = c.zones["assign task"];
    assert!(tasks >= 2 * drawn, "{tasks} tasks in {drawn} frames");
    let blocks = c.zones["phase: view and cull"];
    assert!(blocks >= tasks);
    for phase in ["phase: z", "phase: x", "phase: y", "phase: emit"] {
        assert_eq!(c.zones.get(phase), Some(&blocks), "{phase}");
    }
    assert!(c.zones.get("build pipeline").is_some_and(|&n| n >= 1));

    // Plots: one value per drawn frame each.
    for name in [
        "visible lights",
        "cluster-light pairs",
        "bytes uploaded",
        "GPU upload ms",
        "GPU G-buffer ms",
        "GPU shading ms",
        "GPU forward ms",
    ] {
        let values = c.plots.get(name).map(Vec::len);
        assert_eq!(values, Some(drawn), "plot {name}: {:?}", c.plots.keys());
    }
    assert!(
        c.plots["visible lights"]
            .iter()
            .all(|&v| v > 0.0 && v <= lights as f64)
    );
    assert!(c.plots["cluster-light pairs"].iter().all(|&v| v > 0.0));

    // The GPU track: one context, named, with a positive clock period.
    assert_eq!(c.gpu_contexts.len(), 1, "{:?}", c.gpu_contexts);
    let gpu = &c.gpu_contexts[&0];
    assert_eq!(gpu.name.as_deref(), Some("myriad renderer"));
    assert!(gpu.period_ns > 0.0);
    assert_eq!(c.stray_gpu_times, 0, "GPU times for no zone");

    // A zone per timed pass and frame, in the order the GPU ran them, each with both
    // timestamps; each lasts what its frame's plot says (both are the same two timestamps).
    let passes = [
        ("GPU: upload copies", "GPU upload ms"),
        ("GPU: G-buffer pass", "GPU G-buffer ms"),
        ("GPU: shading pass", "GPU shading ms"),
        ("GPU: forward pass", "GPU forward ms"),
    ];
    assert_eq!(
        c.gpu_zones.len(),
        passes.len() * drawn,
        "{:#?}",
        c.gpu_zones
    );
    let mut previous_end = i64::MIN;
    for (i, zone) in c.gpu_zones.iter().enumerate() {
        let (frame, (name, plot)) = (i / passes.len(), passes[i % passes.len()]);
        assert_eq!(zone.name, name, "zone {i}");
        let (begin, end) = (zone.begin.unwrap(), zone.end.unwrap());
        assert!(previous_end <= begin && begin <= end, "zone {i}: {zone:?}");
        previous_end = end;
        let ms = (end - begin) as f64 * gpu.period_ns as f64 / 1e6;
        let plotted = c.plots[plot][frame];
        assert!(
            (ms - plotted).abs() <= 1e-6 + 1e-6 * plotted,
            "{name} of frame {frame}: {ms} ms as a zone, {plotted} ms plotted"
        );
    }

    // The clock tie: on the CPU's timeline, as the profiler draws them, each frame's GPU zones
    // lie between the start of the main thread's `encode and submit` (which submits them) and
    // the end of its `wait for GPU`. The tie is off by at most half its own wait; llvmpipe's
    // frames here last milliseconds, so a tie off by the wait, or a drifting one, shows.
    let on_main = |name: &str| -> Vec<&capture::CpuZone> {
        c.cpu_zones
            .iter()
            .filter(|z| z.name == name && z.thread == "Main thread")
            .collect()
    };
    let (submits, waits) = (on_main("encode and submit"), on_main("wait for GPU"));
    for (frame, zones) in c.gpu_zones.chunks(passes.len()).enumerate() {
        let from = submits[frame].begin_ns;
        let to = waits[frame].end_ns.unwrap();
        for zone in zones {
            let (begin, end) = (zone.cpu_begin_ns.unwrap(), zone.cpu_end_ns.unwrap());
            assert!(
                from <= begin && end <= to,
                "frame {frame}: {} at {:.3}..{:.3} ms, outside its submission and wait \
                 {:.3}..{:.3} ms (from the first submission)",
                zone.name,
                (begin - submits[0].begin_ns) / 1e6,
                (end - submits[0].begin_ns) / 1e6,
                (from - submits[0].begin_ns) / 1e6,
                (to - submits[0].begin_ns) / 1e6,
            );
        }
    }
}

/// The main job (`myriad render`, four shading columns, the skips column's depth prepass
/// included): its spans nest, each timed frame's wait is a span, each timed frame has its four
/// GPU zones (the skips column's G-buffer is the prepass's, drawn before the frame's upload),
/// lasting what the frame's plots say, and on the CPU's timeline each frame's zones lie after
/// the previous timed frame's wait and within its own.
#[test]
fn a_profiler_receives_the_main_job_with_its_prepass() {
    let out = std::env::temp_dir().join(format!("myriad-tracy-render-{}", std::process::id()));
    let (c, stdout) = captured_run(&[
        "render",
        "--lights",
        "300",
        "--size",
        "160x80",
        "--runs",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    let _ = std::fs::remove_dir_all(&out);
    assert!(c.nesting_errors.is_empty(), "{:?}", c.nesting_errors);
    assert_eq!(c.stray_gpu_times, 0);
    // Four columns, a warm-up and two timed frames each.
    let timed = 4 * 3;
    for name in [
        "depth prepass and read-back",
        "prepass: encode and submit",
        "fitted depth and active clusters",
        "skipping frame",
        "viewer: assign",
        "encode and submit",
    ] {
        assert!(c.zones.contains_key(name), "no span {name}: {:?}", c.zones);
    }
    assert_eq!(c.zones.get("wait for GPU"), Some(&timed), "{stdout}");
    assert!(c.frame_marks >= timed, "{} frame marks", c.frame_marks);
    // The frame's load, plotted once per drawn frame (the viewer's and the skipping frames'
    // plotted bytes uploaded alone until `plot_frame_load`); pairs for the frames with lists:
    // all but brute force's warm-up and timed frames, and any skipping frame that reused its
    // lists.
    for name in ["visible lights", "bytes uploaded"] {
        assert_eq!(
            c.plots.get(name).map(Vec::len),
            Some(c.frame_marks),
            "plot {name}: {:?}",
            c.plots.keys()
        );
    }
    assert!(
        c.plots["visible lights"]
            .iter()
            .all(|&v| v > 0.0 && v <= 300.0)
    );
    let pairs = c.plots.get("cluster-light pairs").map_or(0, Vec::len);
    assert!(
        (2 * 3..=c.frame_marks - 3).contains(&pairs),
        "{pairs} frames with pairs of {} drawn",
        c.frame_marks
    );
    assert!(c.plots["cluster-light pairs"].iter().all(|&v| v > 0.0));
    let passes = [
        ("GPU: upload copies", "GPU upload ms"),
        ("GPU: G-buffer pass", "GPU G-buffer ms"),
        ("GPU: shading pass", "GPU shading ms"),
        ("GPU: forward pass", "GPU forward ms"),
    ];
    for (_, plot) in passes {
        assert_eq!(c.plots.get(plot).map(Vec::len), Some(timed), "{plot}");
    }
    assert_eq!(c.gpu_zones.len(), passes.len() * timed);
    let gpu = &c.gpu_contexts[&0];
    let waits: Vec<_> = c
        .cpu_zones
        .iter()
        .filter(|z| z.name == "wait for GPU")
        .collect();
    let mut previous_end = i64::MIN;
    for (frame, zones) in c.gpu_zones.chunks(passes.len()).enumerate() {
        let mut names: Vec<&str> = zones.iter().map(|z| z.name.as_str()).collect();
        names.sort_unstable();
        let mut want: Vec<&str> = passes.iter().map(|p| p.0).collect();
        want.sort_unstable();
        assert_eq!(names, want, "frame {frame}");
        let after = frame
            .checked_sub(1)
            .map_or(f64::MIN, |k| waits[k].end_ns.unwrap());
        let until = waits[frame].end_ns.unwrap();
        for zone in zones {
            let (begin, end) = (zone.begin.unwrap(), zone.end.unwrap());
            assert!(previous_end <= begin && begin <= end, "{zone:?}");
            previous_end = end;
            let plot = passes.iter().find(|p| p.0 == zone.name).unwrap().1;
            let ms = (end - begin) as f64 * gpu.period_ns as f64 / 1e6;
            let plotted = c.plots[plot][frame];
            assert!(
                (ms - plotted).abs() <= 1e-6 + 1e-6 * plotted,
                "{} of frame {frame}: {ms} ms as a zone, {plotted} ms plotted",
                zone.name
            );
            let (on_cpu_begin, on_cpu_end) = (zone.cpu_begin_ns.unwrap(), zone.cpu_end_ns.unwrap());
            assert!(
                after <= on_cpu_begin && on_cpu_end <= until,
                "frame {frame}: {} outside the time after the last wait and until its own end \
                 ({:.3} ms early, {:.3} ms late)",
                zone.name,
                (after - on_cpu_begin) / 1e6,
                (on_cpu_end - until) / 1e6
            );
        }
    }
}
