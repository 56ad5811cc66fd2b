//! # The frame pipeline: animate → cull → assign on a worker, upload → render on the GPU
//!
//! The design brief's "frame pipeline" bench (the brief is not in this repository). Times `myriad::render::run_frames` — the loop of
//! `myriad frames` — over [`FRAMES`] frames of the default scene (the atrium, its lights orbiting
//! the camera's target, frustum-culled before assignment and upload) at 64×32, `refined`, for
//! 1k, 10k and 100k lights, as two loops of the same frames:
//! * `frame_pipeline/<lights>/sequential` — each frame's CPU stage, then its upload and render;
//! * `frame_pipeline/<lights>/pipelined` — frame N+1's CPU stage on a worker thread while frame
//!   N uploads and renders (two buffer sets in circulation, crossbeam channels).
//!
//! Throughput is in frames, so criterion prints frames per second; the ratio of the two loops is
//! what the pipelining buys on this machine (on llvmpipe, whose rendering takes the same cores as
//! the CPU stage, less than on a GPU). One renderer serves every run, so the GPU side's pipelines
//! and buffers are built in the warm-up, not timed; the CPU side is not steady state: each timed
//! loop starts its own stage (a fresh `Assigner`, the first frame's copy of the light columns, and
//! for the pipelined loop its worker thread), and with [`FRAMES`] frames the pipeline's fill and
//! drain are a large part of the loop, so the ratio understates what pipelining buys over a
//! long run. It needs a GPU adapter (Mesa's llvmpipe counts); without
//! one it says so and times nothing, as `myriad frames` fails there. Run with
//! `cargo bench --bench frame_pipeline` (about a minute on 2 cores under llvmpipe, where a
//! 100k-light frame shades for ~0.4 s even at 64×32: llvmpipe's shading, not the assignment,
//! sets these times; 320×180 took 5 s a frame).

use criterion::{BenchmarkId, Criterion, SamplingMode, Throughput};
use myriad::assignment::Method;
use myriad::gpu::{GpuContext, HEADLESS_FORMAT, HeadlessTarget, Renderer};
use myriad::render::{GpuStage, RenderScene, run_frames};
use std::time::Duration;

/// Frames per timed loop.
const FRAMES: usize = 4;
/// Light counts.
const LIGHTS: [usize; 3] = [1_000, 10_000, 100_000];
/// Render size.
const SIZE: (u32, u32) = (64, 32);

fn frame_pipeline(c: &mut Criterion) {
    let ctx = match GpuContext::headless() {
        Ok(ctx) => ctx,
        Err(e) => {
            eprintln!("frame_pipeline: no GPU adapter, nothing timed ({e})");
            return;
        }
    };
    let mut group = c.benchmark_group("frame_pipeline");
    group
        .sampling_mode(SamplingMode::Flat)
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4))
        .throughput(Throughput::Elements(FRAMES as u64));
    for lights in LIGHTS {
        let scene = RenderScene::default_scene(lights, SIZE.0, SIZE.1).expect("the default scene");
        let mut renderer = Renderer::try_new(&ctx, HEADLESS_FORMAT).expect("a renderer");
        let gpu_scene = renderer
            .upload_scene(&ctx, &scene.geometry)
            .expect("the atrium's geometry");
        let target = HeadlessTarget::new(&ctx.device, SIZE.0, SIZE.1).expect("a target");
        for pipelined in [false, true] {
            let name = if pipelined { "pipelined" } else { "sequential" };
            group.bench_function(BenchmarkId::new(lights.to_string(), name), |b| {
                let mut stage = GpuStage {
                    ctx: &ctx,
                    renderer: &mut renderer,
                    scene: &gpu_scene,
                    target: &target,
                    settings: Default::default(),
                };
                b.iter(|| {
                    let report = run_frames(
                        &mut stage,
                        &scene,
                        Method::Refined,
                        FRAMES,
                        pipelined,
                        true,
                        |_, _| Ok(()),
                    )
                    .expect("the frames render");
                    assert_eq!(report.frames.len(), FRAMES);
                    report
                });
            });
        }
    }
    group.finish();
}

criterion::criterion_group!(benches, frame_pipeline);
criterion::criterion_main!(benches);
