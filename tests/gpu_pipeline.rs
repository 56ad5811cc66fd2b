//! The pipelined frame loop (assignment on a worker thread, uploads through the staging ring)
//! renders exactly the frames the sequential loop renders, and moving lights change the image;
//! culling the lights before assignment and upload sends fewer and changes no image.

use myriad::assignment::Method;
use myriad::gpu::{
    GpuContext, HEADLESS_FORMAT, HeadlessTarget, Renderer, ShadingSettings, read_rgba8,
};
use myriad::render::{GpuStage, LoopReport, RenderScene, max_channel_difference, run_frames};

fn frames(
    ctx: &GpuContext,
    scene: &RenderScene,
    pipelined: bool,
    cull: bool,
    count: usize,
) -> (Vec<Vec<u8>>, LoopReport) {
    frames_with(
        ctx,
        scene,
        pipelined,
        cull,
        count,
        ShadingSettings::default(),
    )
}

/// `frames` with the GPU stage shading with `settings`.
fn frames_with(
    ctx: &GpuContext,
    scene: &RenderScene,
    pipelined: bool,
    cull: bool,
    count: usize,
    settings: ShadingSettings,
) -> (Vec<Vec<u8>>, LoopReport) {
    let mut renderer = Renderer::new(ctx, HEADLESS_FORMAT);
    let gpu_scene = renderer.upload_scene(ctx, &scene.geometry).unwrap();
    let target = HeadlessTarget::new(&ctx.device, scene.camera.width, scene.camera.height).unwrap();
    let mut stage = GpuStage {
        ctx,
        renderer: &mut renderer,
        scene: &gpu_scene,
        target: &target,
        settings,
    };
    let mut images = Vec::new();
    let report = run_frames(
        &mut stage,
        scene,
        Method::Refined,
        count,
        pipelined,
        cull,
        |_, gpu| {
            images.push(read_rgba8(gpu.ctx, &gpu.target.texture)?);
            Ok(())
        },
    )
    .unwrap();
    assert_eq!(report.frames.len(), count);
    // One image a frame: the callers compare them pairwise, and a zip of empty lists compares
    // nothing.
    assert_eq!(images.len(), count);
    assert!(
        report
            .frames
            .iter()
            .all(|f| f.pairs > 0 && f.upload_bytes > 0)
    );
    (images, report)
}

#[test]
fn pipelined_frames_equal_sequential_frames() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let scene = RenderScene::default_scene(3000, 160, 80).unwrap();
    let (sequential, _) = frames(&ctx, &scene, false, false, 5);
    let (pipelined, _) = frames(&ctx, &scene, true, false, 5);
    for (n, (a, b)) in sequential.iter().zip(&pipelined).enumerate() {
        assert!(
            a == b,
            "frame {n} differs between the sequential and the pipelined loop"
        );
    }
    assert!(
        sequential[0] != sequential[4],
        "the lights move, so frames differ"
    );
}

#[test]
fn culled_frames_upload_fewer_lights_and_look_the_same() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let scene = RenderScene::default_scene(3000, 160, 80).unwrap();
    let (all, every) = frames(&ctx, &scene, false, false, 4);
    let (culled, sequential) = frames(&ctx, &scene, false, true, 4);
    let (culled_pipelined, pipelined) = frames(&ctx, &scene, true, true, 4);
    assert!(!every.culled && sequential.culled && pipelined.culled);
    for n in 0..4 {
        assert!(
            culled[n] == culled_pipelined[n],
            "culled frame {n} differs between the loops"
        );
        let d = max_channel_difference(&all[n], &culled[n]);
        assert!(d <= 1, "culling changed frame {n} by {d}/255");
        let (a, c) = (&every.frames[n], &sequential.frames[n]);
        assert_eq!(a.lights_uploaded, scene.lights.len());
        assert!(
            c.lights_uploaded < a.lights_uploaded && c.upload_bytes < a.upload_bytes,
            "frame {n}: {} of {} lights, {} of {} bytes uploaded",
            c.lights_uploaded,
            a.lights_uploaded,
            c.upload_bytes,
            a.upload_bytes
        );
        assert_eq!(c.lights_uploaded, pipelined.frames[n].lights_uploaded);
        assert!(c.cull_seconds > 0.0 && a.cull_seconds == 0.0);
    }
}

/// Both loops shade with the GPU stage's settings and say which loop ran: at twice the exposure
/// each frame is brighter than the same frame at the default exposure.
#[test]
fn the_loops_shade_with_the_stages_settings() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let scene = RenderScene::default_scene(1000, 160, 80).unwrap();
    let brighter = ShadingSettings {
        exposure: 2.0,
        ..ShadingSettings::default()
    };
    for pipelined in [false, true] {
        let (plain, report) = frames(&ctx, &scene, pipelined, true, 2);
        assert_eq!(report.pipelined, pipelined);
        let (bright, _) = frames_with(&ctx, &scene, pipelined, true, 2, brighter);
        for n in 0..2 {
            let d = max_channel_difference(&plain[n], &bright[n]);
            assert!(
                d > 8,
                "pipelined {pipelined}, frame {n}: exposure 2 changed {d}/255"
            );
            let sum = |image: &[u8]| image.iter().map(|&v| u64::from(v)).sum::<u64>();
            assert!(
                sum(&bright[n]) > sum(&plain[n]),
                "pipelined {pipelined}, frame {n}"
            );
        }
    }
}
