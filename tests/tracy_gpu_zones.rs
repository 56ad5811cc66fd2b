//! With the `tracy` feature, a frame's timed GPU pieces (G-buffer, shading and forward passes, the
//! upload's copies) become Tracy GPU zones when the frame's times are read while a client runs:
//! one zone each, however often the times are read, none before the client starts, and a
//! G-buffer kept from a depth prepass counts once; the GPU clock is tied to the CPU's again a
//! second later. (What a profiler then draws is Tracy's; this checks what the renderer hands it.)

use myriad::assignment::Method;
use myriad::gpu::{GpuContext, PassTimes};
use myriad::render::{RenderScene, Shading, Skips, Viewer};

/// The timed pieces of a frame's times.
fn timed(times: &PassTimes) -> u64 {
    [
        times.gbuffer_ms,
        times.shading_ms,
        times.forward_ms,
        times.upload_ms,
    ]
    .iter()
    .flatten()
    .count() as u64
}

#[test]
fn each_timed_pass_of_a_read_frame_is_one_gpu_zone_once_the_client_runs() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    if !ctx.has_timestamps() {
        assert!(!ctx.describe().contains("llvmpipe"), "{}", ctx.describe());
        eprintln!(
            "no timestamp queries on {}: no zones to check",
            ctx.describe()
        );
        return;
    }
    let scene = RenderScene::default_scene(200, 96, 48).unwrap();
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    let read = |viewer: &Viewer| {
        viewer
            .renderer
            .last_pass_times(&viewer.ctx)
            .unwrap()
            .expect("timestamps")
    };
    viewer
        .frame(&scene, Shading::Clustered, Method::Refined, false)
        .unwrap();
    assert!(timed(&read(&viewer)) >= 2);
    assert_eq!(
        viewer.renderer.gpu_zones_emitted(),
        0,
        "zones before the client"
    );

    // SAFETY: nothing records after the session drops: the viewers (the renderers' GPU zones)
    // are dropped first, and this binary's only test is this one.
    let session = unsafe { myriad::profiling::start() };
    let mut zones = 0;
    for skips in [Skips::NONE, Skips::ALL, Skips::NONE] {
        // `Skips::ALL` draws the G-buffer as a depth prepass, then shades it in a second frame.
        let frame = viewer
            .frame_with_skips(&scene, Method::Refined, skips)
            .unwrap();
        let times = read(&viewer);
        zones += timed(&times);
        assert!(
            times.gbuffer_ms.is_some() && times.shading_ms.is_some(),
            "{times:?}"
        );
        assert_eq!(
            viewer.renderer.gpu_zones_emitted(),
            zones,
            "{skips:?} (reused: {}): {times:?}",
            frame.reused
        );
        // Read again: the same frame, no new zone.
        read(&viewer);
        assert_eq!(viewer.renderer.gpu_zones_emitted(), zones);
    }
    // A frame whose times are never read leaves no zone; the next one read counts its own.
    viewer
        .frame(&scene, Shading::BruteForce, Method::Refined, false)
        .unwrap();
    viewer
        .frame(&scene, Shading::Clustered, Method::Refined, false)
        .unwrap();
    zones += timed(&read(&viewer));
    assert_eq!(viewer.renderer.gpu_zones_emitted(), zones);

    // The GPU clock was tied to the CPU's when the first zones were emitted, and is tied again
    // before the first zones emitted a second or more after that (once per read at most).
    let ties = viewer.renderer.gpu_clock_ties();
    assert!(ties >= 1, "tied when the context was made");
    std::thread::sleep(std::time::Duration::from_millis(1100));
    viewer
        .frame(&scene, Shading::Clustered, Method::Refined, false)
        .unwrap();
    zones += timed(&read(&viewer));
    assert_eq!(viewer.renderer.gpu_zones_emitted(), zones);
    assert_eq!(viewer.renderer.gpu_clock_ties(), ties + 1);

    // Tracy gives a process 255 GPU contexts. With every one taken, a new renderer's frames
    // still draw and read their times, with no zones and no clock tie, and it says it was
    // refused (and asks no more: each ask costs three blocking clock reads); the renderer that
    // has its context keeps emitting. (Here, not in a test of its own: contexts are never given back,
    // and a second test would share this process's client.)
    let client = || myriad::profiling::__tracy::Client::running().expect("started above");
    let mut taken = 0;
    while client()
        .new_gpu_context(
            Some("taken"),
            myriad::profiling::__tracy::GpuContextType::Invalid,
            0,
            1.0,
        )
        .is_ok()
    {
        taken += 1;
        assert!(taken <= 255, "Tracy gave more than 255 GPU contexts");
    }
    assert!(taken < 255, "the viewer's own context is one of the 255");
    let mut refused = Viewer::new(viewer.ctx.clone(), &scene).unwrap();
    for _ in 0..3 {
        refused
            .frame(&scene, Shading::Clustered, Method::Refined, false)
            .unwrap();
        assert!(timed(&read(&refused)) >= 2, "the times are still read");
        assert_eq!(refused.renderer.gpu_zones_emitted(), 0);
        assert_eq!(refused.renderer.gpu_clock_ties(), 0);
        assert!(refused.renderer.gpu_context_refused());
    }
    assert!(!viewer.renderer.gpu_context_refused());
    viewer
        .frame(&scene, Shading::Clustered, Method::Refined, false)
        .unwrap();
    zones += timed(&read(&viewer));
    assert_eq!(viewer.renderer.gpu_zones_emitted(), zones);
    drop((viewer, refused));
    drop(session);
}
