//! The shader loop budget (`myriad_gpu::loop_budget`) at its edge: a pixel may loop over exactly
//! as many lights as the renderer allows and still show the last one, and one more is refused.
//!
//! Every light sits at one point and covers the whole view; all but the last have zero colour,
//! so a frame that drops any tail of the loop loses the only light that shows. The frame must equal
//! the frame of the last light alone. On adapters without a loop limit the same frames are
//! checked at the llvmpipe budget (nothing may be refused there).

use myriad::assignment::Method;
use myriad::cluster_math::glam::Vec3;
use myriad::cluster_math::{ClusterGrid, DepthSlicing, glam::UVec3};
use myriad::gpu::{GpuContext, GpuError, ShadingMode, loop_budget};
use myriad::render::{RenderScene, Shading, Viewer, max_channel_difference};
use myriad::scene::{LightRecord, Lights};

const LLVMPIPE_LOOP_LIMIT: u64 = 65_535;

/// `count` lights at one point near the eye, covering the view; only the last one bright.
fn dark_lights_then_one(scene: &RenderScene, count: usize) -> Lights {
    let position = scene.camera.position + Vec3::Y * 0.5;
    let mut lights = Lights::with_capacity(count);
    for i in 0..count {
        let bright = i + 1 == count;
        let light = LightRecord::point(position, 500.0)
            .with_color(if bright { Vec3::ONE } else { Vec3::ZERO })
            .with_intensity(if bright { 40.0 } else { 0.0 })
            .with_source_index(i as u32);
        lights.push(light);
    }
    lights
}

/// Renders `lights` lights (all but the last dark) with `shading` on a 1×1×`slices` grid: at the
/// budget the image equals the last light's alone; one past it is refused where loops are capped.
fn check_edge(ctx: &GpuContext, shading: Shading, slices: u32) {
    let (w, h) = (48, 24);
    let mut scene = RenderScene::default_scene(0, w, h).unwrap();
    let (near, far) = (scene.camera.near, scene.camera.far);
    scene.grid = ClusterGrid::new(UVec3::new(1, 1, slices), DepthSlicing::Log, near, far);
    let mode = match shading {
        Shading::BruteForce => ShadingMode::BruteForce,
        _ => ShadingMode::Lists,
    };
    let limited = ctx.max_lights_per_pixel(mode, slices);
    let most = limited
        .unwrap_or_else(|| loop_budget::max_lights_per_pixel(LLVMPIPE_LOOP_LIMIT, mode, slices));
    let label = format!("{} on 1x1x{slices}", shading.name());

    scene.lights = dark_lights_then_one(&scene, 1);
    let mut viewer = Viewer::new(ctx.clone(), &scene).unwrap();
    viewer
        .frame(&scene, shading, Method::Binary, false)
        .unwrap();
    let alone = viewer.image().unwrap();
    // Above the background's 39, 39, 49 (a threshold of 40 counted the background as lit).
    let lit = alone
        .chunks(4)
        .filter(|p| p[..3].iter().any(|&c| c > 60))
        .count();
    assert!(lit > (w * h / 4) as usize, "{label}: only {lit} lit pixels");

    scene.lights = dark_lights_then_one(&scene, most as usize);
    let frame = viewer
        .frame(&scene, shading, Method::Binary, false)
        .unwrap();
    if matches!(shading, Shading::BruteForce) {
        assert!(
            frame.stats.is_none(),
            "{label}: brute force assigns nothing"
        );
    } else {
        let stats = frame.stats.expect("a clustered frame assigns");
        let longest = viewer.lists().counts.iter().copied().max().unwrap();
        assert_eq!(
            longest as u64, most,
            "{label}: every light in every cluster ({stats:?})"
        );
    }
    let at_budget = viewer.image().unwrap();
    let worst = max_channel_difference(&alone, &at_budget);
    assert!(
        worst <= 1,
        "{label}: {most} lights differ from the last alone by {worst}"
    );

    scene.lights = dark_lights_then_one(&scene, most as usize + 1);
    let past = viewer.frame(&scene, shading, Method::Binary, false);
    match limited {
        Some(max_lights) => {
            let err = past.expect_err("one light past the budget is refused");
            let refused = err.chain().any(|e| {
                matches!(
                    e.downcast_ref::<GpuError>(),
                    Some(GpuError::ShaderLoopLimit { lights, max_lights: m, .. })
                        if *lights == max_lights + 1 && *m == max_lights
                )
            });
            assert!(refused, "{label}: {err:#}");
            eprintln!("{label}: {most} lights shown, one more refused: {err:#}");
        }
        None => {
            past.unwrap();
            let worst = max_channel_difference(&alone, &viewer.image().unwrap());
            assert!(worst <= 1, "{label}: {} lights differ by {worst}", most + 1);
        }
    }
}

#[test]
fn a_pixel_shows_every_light_up_to_the_budget_and_no_more_are_drawn() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    check_edge(&ctx, Shading::Clustered, 1);
    check_edge(&ctx, Shading::Clustered, 16);
    check_edge(&ctx, Shading::Clustered, 37);
    // 16 inner slices, a power of two: a search started one slice lower (`lo = 0`) goes round
    // once more here, where on 16 and 37 slices it does not, and loses the last light (audit).
    check_edge(&ctx, Shading::Clustered, 18);
    check_edge(&ctx, Shading::BruteForce, 16);
}

/// Lists of another grid's shape whose longest list is past the loop budget (lists a pair budget
/// coarsened to 1×1×1, passed with the grid first asked for) are refused for their shape: the
/// loop budget was checked first and named a finer grid as the cure (engine audit).
#[test]
fn lists_of_another_shape_are_refused_for_their_shape_before_the_loop_budget() {
    use myriad::gpu::FrameDesc;
    use myriad::render::light_columns;
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let mut scene = RenderScene::default_scene(0, 48, 24).unwrap();
    let (near, far) = (scene.camera.near, scene.camera.far);
    scene.grid = ClusterGrid::new(UVec3::new(2, 2, 2), DepthSlicing::Log, near, far);
    // Past the budget of the frame's grid (2 slices), so that checking the budget first refuses.
    let most = ctx
        .max_lights_per_pixel(ShadingMode::Lists, 2)
        .unwrap_or_else(|| {
            loop_budget::max_lights_per_pixel(LLVMPIPE_LOOP_LIMIT, ShadingMode::Lists, 2)
        });
    let n = most as usize + 1;
    scene.lights = dark_lights_then_one(&scene, n);
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    let indices: Vec<u32> = (0..n as u32).collect();
    let one_cluster = myriad::gpu::ClusterLists {
        offsets: &[0],
        counts: &[n as u32],
        indices: &indices,
    };
    let frame = FrameDesc::clustered(
        &scene.camera,
        &scene.grid,
        light_columns(&scene.lights),
        one_cluster,
    );
    let result = viewer
        .renderer
        .render(&viewer.ctx, &viewer.scene, &frame, &viewer.target.view);
    match result {
        Err(GpuError::InvalidInput(message)) => assert!(
            message
                .contains("light lists describe 1 offsets and 1 counts for a grid of 8 clusters"),
            "{message}"
        ),
        other => panic!("want the lists' shape refused, got {:?}", other.map(drop)),
    }
}
