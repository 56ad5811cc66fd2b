//! The pipelined frame loop (assignment on a worker thread, uploads through the staging ring)
//! renders exactly the frames the sequential loop renders, and moving lights change the image.

use myriad::assignment::Method;
use myriad::gpu::{GpuContext, HEADLESS_FORMAT, HeadlessTarget, Renderer, read_rgba8};
use myriad::render::{GpuStage, RenderScene, run_frames};

fn frames(ctx: &GpuContext, scene: &RenderScene, pipelined: bool, count: usize) -> Vec<Vec<u8>> {
    let mut renderer = Renderer::new(ctx, HEADLESS_FORMAT);
    let gpu_scene = renderer.upload_scene(ctx, &scene.geometry).unwrap();
    let target = HeadlessTarget::new(&ctx.device, scene.camera.width, scene.camera.height).unwrap();
    let mut stage = GpuStage {
        ctx,
        renderer: &mut renderer,
        scene: &gpu_scene,
        target: &target,
        settings: Default::default(),
    };
    let mut images = Vec::new();
    let report = run_frames(
        &mut stage,
        scene,
        Method::Refined,
        count,
        pipelined,
        |_, gpu| {
            images.push(read_rgba8(gpu.ctx, &gpu.target.texture)?);
            Ok(())
        },
    )
    .unwrap();
    assert_eq!(report.frames.len(), count);
    assert!(
        report
            .frames
            .iter()
            .all(|f| f.pairs > 0 && f.upload_bytes > 0)
    );
    images
}

#[test]
fn pipelined_frames_equal_sequential_frames() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let scene = RenderScene::default_scene(3000, 160, 80).unwrap();
    let sequential = frames(&ctx, &scene, false, 5);
    let pipelined = frames(&ctx, &scene, true, 5);
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
