//! Every frame the rendering glue draws gets exactly one Tracy frame mark, whichever path drew
//! it: [`Viewer::frame`], both branches of [`Viewer::frame_with_skips`] (a frame reused whole
//! draws too), and both modes of [`run_frames`]. A path that forgets its mark merges its frames
//! into their neighbours in a capture; one that marks twice splits them. Counted with the
//! profiling module's per-thread test counter, so this runs without the `tracy` feature.

use super::{RenderScene, Shading, Skips, Viewer, run_frames};
use crate::profiling::frame_marks_on_this_thread;
use myriad_assignment::Method;
use myriad_gpu::GpuContext;

/// The frame marks `draw` made on this thread.
fn marks(draw: impl FnOnce()) -> u64 {
    let before = frame_marks_on_this_thread();
    draw();
    frame_marks_on_this_thread() - before
}

#[test]
fn every_rendered_frame_is_marked_once() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let scene = RenderScene::default_scene(200, 64, 32).unwrap();
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    for shading in Shading::ALL {
        let drawn = marks(|| {
            viewer
                .frame(&scene, shading, Method::Refined, false)
                .unwrap();
        });
        assert_eq!(drawn, 1, "Viewer::frame, {}", shading.name());
    }
    for (name, skips) in [
        ("no savings", Skips::NONE),
        ("per-frame savings (depth prepass)", Skips::PER_FRAME),
        ("all savings, first frame", Skips::ALL),
        ("all savings, frame reused", Skips::ALL),
    ] {
        let mut reused = false;
        let drawn = marks(|| {
            let frame = viewer
                .frame_with_skips(&scene, Method::Refined, skips)
                .unwrap();
            reused = frame.reused;
        });
        assert_eq!(drawn, 1, "frame_with_skips, {name}");
        assert_eq!(reused, name.ends_with("reused"), "{name}");
    }
    let mut gpu = viewer.gpu_stage();
    for pipelined in [false, true] {
        let drawn = marks(|| {
            run_frames(
                &mut gpu,
                &scene,
                Method::Refined,
                3,
                pipelined,
                true,
                |_, _| Ok(()),
            )
            .unwrap();
        });
        assert_eq!(drawn, 3, "run_frames, pipelined: {pipelined}");
    }
}
