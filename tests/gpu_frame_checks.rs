//! What a frame checks and reports that the image alone does not show (found missing by a
//! mutation audit of `crates/gpu/src/renderer/mod.rs`): the tile count at which the shader's u32
//! tile arithmetic would overflow, kept lights and the camera they were uploaded for, the exact
//! bytes a frame stages and the upload generation it bumps, and a frame refused for its lights
//! leaving even the last frame's pass times as they were.

use myriad::assignment::{Assigner, LightLists, Method};
use myriad::cluster_math::glam::UVec3;
use myriad::gpu::layout::GpuLight;
use myriad::gpu::{
    FrameDesc, GpuContext, GpuError, GpuScene, HEADLESS_FORMAT, HeadlessTarget, Renderer,
    ShadingMode, ShadingSettings, read_rgba8, wgpu,
};
use myriad::render::{
    RenderScene, Shading, Viewer, cluster_lists, light_columns, max_channel_difference, run_frames,
};
use myriad::scene::{Camera, ClusterGrid, DepthSlicing};

/// A brute-force frame of `camera` on `grid` that uploads `lights` (or keeps the last upload).
fn brute_force<'a>(
    camera: &'a Camera,
    grid: &'a ClusterGrid,
    lights: Option<myriad::gpu::LightColumns<'a>>,
) -> FrameDesc<'a> {
    FrameDesc {
        camera,
        grid,
        mode: ShadingMode::BruteForce,
        heat_map: false,
        lights,
        lists: None,
        settings: ShadingSettings::default(),
    }
}

/// A device whose storage bindings hold at most `limit` bytes, with timestamps where the
/// adapter has them.
fn binding_limited(limit: u64) -> GpuContext {
    let adapter =
        pollster::block_on(myriad::gpu::shared_instance().request_adapter(&Default::default()))
            .unwrap();
    let timestamps =
        wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
    let descriptor = wgpu::DeviceDescriptor {
        required_features: adapter.features() & timestamps,
        required_limits: wgpu::Limits {
            max_storage_buffer_binding_size: limit,
            ..Renderer::required_limits()
        },
        ..Default::default()
    };
    let (device, queue) = pollster::block_on(adapter.request_device(&descriptor)).unwrap();
    GpuContext::from_device(device, queue)
}

/// A renderer on `ctx` with `scene`'s geometry uploaded, and a target of its camera's size.
fn renderer_for(ctx: &GpuContext, scene: &RenderScene) -> (Renderer, GpuScene, HeadlessTarget) {
    let renderer = Renderer::new(ctx, HEADLESS_FORMAT);
    let geometry = renderer.upload_scene(ctx, &scene.geometry).unwrap();
    let (width, height) = (scene.camera.width, scene.camera.height);
    let target = HeadlessTarget::new(&ctx.device, width, height).unwrap();
    (renderer, geometry, target)
}

/// `scene`'s lists for its own camera and grid.
fn assigned(scene: &RenderScene) -> LightLists {
    let mut lists = LightLists::new();
    Assigner::new().assign(
        Method::Refined,
        &myriad::light_input(&scene.lights),
        &scene.camera,
        &scene.grid,
        &mut lists,
    );
    lists
}

/// Lists of `pairs` pairs over `clusters` clusters, spread as evenly as they go (the first
/// clusters one more), naming lights `0..lights` in turn: well formed, if not any light's real
/// clusters.
fn lists_of(clusters: usize, pairs: usize, lights: u32) -> LightLists {
    let mut lists = LightLists::new();
    for c in 0..clusters {
        let count = pairs / clusters + usize::from(c < pairs % clusters);
        lists.offsets.push(lists.indices.len() as u32);
        lists.counts.push(count as u32);
        lists.indices.extend((0..count as u32).map(|i| i % lights));
    }
    lists
}

/// A device's binding limit need not be whole 4-byte words (wgpu reports a desktop Vulkan
/// driver's as `i32::MAX`): lists filling the words under it are drawn, their buffer grown to
/// fit the limit — not to the next power of two clamped to the limit and rounded up past it,
/// which made wgpu panic on a bind group over the limit — and one pair more is refused, naming
/// the limit in whole words.
#[test]
fn lists_up_to_a_binding_limit_of_no_whole_words_are_drawn() {
    if GpuContext::headless_for_tests().is_none() {
        return;
    }
    const LIMIT: u64 = (256 << 10) + 7;
    let ctx = binding_limited(LIMIT);
    assert_eq!(ctx.max_list_pairs(), LIMIT / 4);
    let scene = RenderScene::default_scene(100, 32, 16)
        .unwrap()
        .with_grid(UVec3::new(16, 8, 16), DepthSlicing::Log);
    let (mut renderer, geometry, target) = renderer_for(&ctx, &scene);
    let clusters = scene.grid.cluster_count();
    // 65 537 pairs: 2¹⁸ + 4 bytes, whose next power of two is past the limit.
    let most = (LIMIT / 4) as usize;
    let fitting = lists_of(clusters, most, 100);
    let frame = FrameDesc::clustered(
        &scene.camera,
        &scene.grid,
        light_columns(&scene.lights),
        cluster_lists(&fitting),
    );
    renderer
        .render(&ctx, &geometry, &frame, &target.view)
        .unwrap();
    ctx.wait_idle().unwrap();
    let one_more = lists_of(clusters, most + 1, 100);
    let frame = FrameDesc {
        lists: Some(cluster_lists(&one_more)),
        ..frame
    };
    match renderer.render(&ctx, &geometry, &frame, &target.view) {
        Err(GpuError::BufferTooLarge { what, bytes, limit }) => {
            assert_eq!(
                (what, bytes, limit),
                ("light indices", 4 * (most as u64 + 1), LIMIT - 3)
            );
        }
        other => panic!("one pair past the limit: {other:?}"),
    }
}

/// Kept lists of another grid are refused as such even where they would also pass the shader's
/// loop limit on the frame's grid: a cluster of 65 534 lights fits llvmpipe's budget with two
/// slices, not with 64 (six rounds of the slice search), and the frame on the 64-slice grid was
/// refused for the loop limit ("use a finer grid"), not for having no lists of its grid.
#[test]
fn kept_lists_of_another_grid_are_refused_as_such_before_the_loop_limit() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    const CROWD: usize = 65_534;
    let scene = RenderScene::default_scene(CROWD, 32, 16)
        .unwrap()
        .with_grid(UVec3::new(8, 4, 2), DepthSlicing::Log);
    let mut lists = LightLists::new();
    for c in 0..scene.grid.cluster_count() {
        let count = if c == 0 { CROWD } else { 0 };
        lists.offsets.push(lists.indices.len() as u32);
        lists.counts.push(count as u32);
        lists.indices.extend(0..count as u32);
    }
    let (mut renderer, geometry, target) = renderer_for(&ctx, &scene);
    let frame = FrameDesc::clustered(
        &scene.camera,
        &scene.grid,
        light_columns(&scene.lights),
        cluster_lists(&lists),
    );
    renderer
        .render(&ctx, &geometry, &frame, &target.view)
        .unwrap();
    let finer = scene
        .clone()
        .with_grid(UVec3::new(8, 4, 64), DepthSlicing::Log);
    if let Some(max) = ctx.max_lights_per_pixel(ShadingMode::Lists, 64) {
        assert!(max < CROWD as u64, "{max} lights fit 64 slices here");
    }
    let kept = FrameDesc {
        grid: &finer.grid,
        lists: None,
        ..frame
    };
    match renderer.render(&ctx, &geometry, &kept, &target.view) {
        Err(GpuError::InvalidInput(message)) => {
            assert!(
                message.contains("needs light lists for this grid"),
                "{message}"
            )
        }
        other => panic!("kept lists of another grid: {:?}", other.map(|_| ())),
    }
}

/// The shader works out a pixel's tile as `2 · pixel · tiles` in u32: a target of the device's
/// largest side is refused with the first tile count along that side whose `2 · side · tiles`
/// passes `u32::MAX` (a wide target and a tall one, each overflowing along one side only), and
/// drawn with one tile fewer.
#[test]
fn tiles_that_overflow_the_shaders_u32_arithmetic_are_refused_from_the_first() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let side = ctx.device.limits().max_texture_dimension_2d;
    let first = u32::try_from(u32::MAX as u64 / (2 * side as u64) + 1).unwrap();
    assert!(2 * side as u64 * first as u64 > u32::MAX as u64);
    assert!(2 * side as u64 * (first as u64 - 1) <= u32::MAX as u64);
    let scene = RenderScene::default_scene(1, 8, 8).unwrap();
    let mut renderer = Renderer::try_new(&ctx, HEADLESS_FORMAT).unwrap();
    let geometry = renderer.upload_scene(&ctx, &scene.geometry).unwrap();
    for wide in [true, false] {
        let (width, height) = if wide { (side, 1) } else { (1, side) };
        let camera = Camera {
            width,
            height,
            ..scene.camera
        };
        let target = HeadlessTarget::new(&ctx.device, width, height).unwrap();
        for tiles in [first - 1, first] {
            let dims = if wide {
                UVec3::new(tiles, 1, 1)
            } else {
                UVec3::new(1, tiles, 1)
            };
            let grid = ClusterGrid::new(
                dims,
                DepthSlicing::Linear,
                scene.grid.near(),
                scene.grid.far(),
            );
            let frame = brute_force(&camera, &grid, Some(light_columns(&scene.lights)));
            let result = renderer.render(&ctx, &geometry, &frame, &target.view);
            let label = format!("{width}x{height} with {dims} tiles");
            if tiles < first {
                let lights = scene.lights.len();
                assert_eq!(result.map(|r| r.lights).ok(), Some(lights), "{label}");
            } else {
                match result {
                    Err(GpuError::InvalidInput(message)) => assert!(
                        message.contains("overflows the shader's u32 tile arithmetic"),
                        "{label}: {message}"
                    ),
                    other => panic!("{label}: want it refused, got {:?}", other.map(|_| ())),
                }
            }
        }
    }
}

/// Kept lights are camera-relative records: a frame that keeps them is refused once the camera
/// has moved, and drawn from the camera they were uploaded for. Before anything is uploaded there
/// is nothing to keep, so a frame without lights draws from any camera.
#[test]
fn kept_lights_are_drawn_only_from_the_camera_they_were_uploaded_for() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let scene = RenderScene::default_scene(20, 32, 16).unwrap();
    let mut renderer = Renderer::try_new(&ctx, HEADLESS_FORMAT).unwrap();
    let geometry = renderer.upload_scene(&ctx, &scene.geometry).unwrap();
    let target = HeadlessTarget::new(&ctx.device, 32, 16).unwrap();
    let mut render = |camera: &Camera, lights| {
        renderer.render(
            &ctx,
            &geometry,
            &brute_force(camera, &scene.grid, lights),
            &target.view,
        )
    };
    let report = render(&scene.camera, None).expect("no lights yet: nothing to keep");
    assert_eq!(report.lights, 0);
    let report = render(&scene.camera, Some(light_columns(&scene.lights))).unwrap();
    assert_eq!(report.lights, 20);
    let mut moved = scene.camera;
    moved.position.x += 0.5;
    moved.target.x += 0.5;
    match render(&moved, None) {
        Err(GpuError::InvalidInput(message)) => {
            assert!(message.contains("the camera moved"), "{message}")
        }
        other => panic!("want the kept lights refused, got {:?}", other.map(|_| ())),
    }
    let report = render(&scene.camera, None).expect("the lights' own camera");
    assert_eq!(report.lights, 20);
    // The eye a step or two off, as `Camera::from_matrices` reads a turned camera's back: the
    // same eye (it was "the camera moved" to an engine that only turned its camera).
    let mut rounded = scene.camera;
    rounded.position.x = rounded.position.x.next_up().next_up();
    rounded.position.z = rounded.position.z.next_down();
    assert_eq!(render(&rounded, None).unwrap().lights, 20);
    // Uploaded again from the moved camera, they are that camera's.
    render(&moved, Some(light_columns(&scene.lights))).unwrap();
    assert_eq!(render(&moved, None).unwrap().lights, 20);
}

/// `upload_bytes` is exactly what was staged (48 bytes a light, 4 an offset, count or index, 4 a
/// slice edge), piece by piece: a frame with all three, the lists alone, the lights alone, and a
/// grid's slice edges alone. The upload generation counts the frames that uploaded lights or
/// lists, once a frame (as its doc says; a frame with both was once counted twice): 0 on a new
/// renderer, one more after each such frame, the same after one that uploads neither.
#[test]
fn the_report_counts_exactly_the_bytes_each_frame_staged() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    assert_eq!(std::mem::size_of::<GpuLight>(), 48);
    let scene = RenderScene::default_scene(30, 32, 16).unwrap();
    let lists = assigned(&scene);
    assert!(!lists.indices.is_empty());
    let mut renderer = Renderer::try_new(&ctx, HEADLESS_FORMAT).unwrap();
    let geometry = renderer.upload_scene(&ctx, &scene.geometry).unwrap();
    let target = HeadlessTarget::new(&ctx.device, 32, 16).unwrap();
    let lights_bytes = 48 * scene.lights.len() as u64;
    let lists_bytes = 4 * (lists.offsets.len() + lists.counts.len() + lists.indices.len()) as u64;
    let edges_bytes = |grid: &ClusterGrid| 4 * (grid.dims().z as u64 + 1);
    let tiles = ClusterGrid::new(
        scene.grid.dims().with_z(1),
        DepthSlicing::Linear,
        scene.grid.near(),
        scene.grid.far(),
    );
    let clustered = FrameDesc::clustered(
        &scene.camera,
        &scene.grid,
        light_columns(&scene.lights),
        cluster_lists(&lists),
    );
    let frames = [
        (
            "lights, lists and slice edges",
            clustered,
            lights_bytes + lists_bytes + edges_bytes(&scene.grid),
        ),
        (
            "the lists alone",
            FrameDesc {
                lights: None,
                ..clustered
            },
            lists_bytes,
        ),
        (
            "the lights alone",
            brute_force(
                &scene.camera,
                &scene.grid,
                Some(light_columns(&scene.lights)),
            ),
            lights_bytes,
        ),
        (
            "another grid's slice edges alone",
            brute_force(&scene.camera, &tiles, None),
            edges_bytes(&tiles),
        ),
    ];
    let mut generation = renderer.upload_generation();
    assert_eq!(generation, 0);
    let mut seen = vec![generation];
    for (what, frame, want) in frames {
        let report = renderer
            .render(&ctx, &geometry, &frame, &target.view)
            .unwrap();
        assert_eq!(report.upload_bytes, want, "{what}");
        // A new value exactly when the frame uploads; never one given before.
        let now = renderer.upload_generation();
        if frame.lights.is_some() || frame.lists.is_some() {
            assert!(!seen.contains(&now), "{what}: generation {now} again");
            seen.push(now);
            generation = now;
        }
        assert_eq!(now, generation, "{what}");
    }
}

/// A frame with more lights than one storage binding holds is refused before it changes
/// anything: the error names the light buffer and its bytes, the upload generation stays, and the
/// last frame's pass times still read as that frame's (a refusal after the frame's timing had
/// begun read back a frame of no passes).
#[test]
fn a_frame_refused_for_its_lights_leaves_the_last_frames_times() {
    if GpuContext::headless_for_tests().is_none() {
        return;
    }
    const LIMIT: u64 = 256 << 10;
    let ctx = binding_limited(LIMIT);
    if ctx.describe().contains("llvmpipe") {
        assert!(ctx.has_timestamps(), "{}", ctx.describe());
    }
    let too_many = (LIMIT / 48 + 1) as usize;
    let scene = RenderScene::default_scene(100, 32, 16).unwrap();
    let crowd = RenderScene::default_scene(too_many, 32, 16).unwrap();
    assert_eq!(crowd.lights.len(), too_many);
    let (mut renderer, geometry, target) = renderer_for(&ctx, &scene);
    let lists = assigned(&scene);
    let frame = FrameDesc::clustered(
        &scene.camera,
        &scene.grid,
        light_columns(&scene.lights),
        cluster_lists(&lists),
    );
    renderer
        .render(&ctx, &geometry, &frame, &target.view)
        .unwrap();
    ctx.wait_idle().unwrap();
    let times = renderer.last_pass_times(&ctx).unwrap();
    if ctx.has_timestamps() {
        let t = times.expect("an adapter with timestamps times every frame");
        assert!(t.gbuffer_ms.is_some() && t.shading_ms.is_some(), "{t:?}");
    }
    let generation = renderer.upload_generation();
    // The kept lists name only the first lights: the frame is refused for its light buffer alone.
    let refused = FrameDesc {
        lights: Some(light_columns(&crowd.lights)),
        lists: None,
        ..frame
    };
    match renderer.render(&ctx, &geometry, &refused, &target.view) {
        Err(GpuError::BufferTooLarge { what, bytes, limit }) => {
            assert_eq!(
                (what, bytes, limit),
                ("lights", 48 * too_many as u64, LIMIT)
            );
        }
        other => panic!("want the lights refused, got {:?}", other.map(|_| ())),
    }
    assert_eq!(renderer.upload_generation(), generation);
    assert_eq!(renderer.last_pass_times(&ctx).unwrap(), times);
}

/// A device that binds 128 MiB of light indices (2^25 pairs) and a scene whose lists on its own
/// grid pass that: 3000 lights eight times their size, on a grid of 37k clusters. (The renderer's
/// limits need 128 MiB; llvmpipe has exactly that, a real GPU gigabytes.)
fn past_the_binding() -> (GpuContext, RenderScene) {
    let ctx = binding_limited(128 << 20);
    assert_eq!(ctx.max_list_pairs(), 1 << 25);
    let mut scene = RenderScene::default_scene(3000, 64, 36)
        .unwrap()
        .with_grid(UVec3::new(64, 36, 16), DepthSlicing::Log);
    for r in &mut scene.lights.radius {
        *r *= 8.0;
    }
    let on_scene_grid = assigned(&scene).pair_count() as u64;
    assert!(on_scene_grid > 1 << 25, "{on_scene_grid} pairs fit");
    (ctx, scene)
}

/// Lists past what the device binds are built on a coarser grid, which the viewer shades with,
/// instead of the frame being refused after its assignment: the image is brute force's
/// ([`past_the_binding`]).
#[test]
fn a_viewer_coarsens_lists_past_what_the_device_binds() {
    if GpuContext::headless_for_tests().is_none() {
        return;
    }
    let (ctx, scene) = past_the_binding();
    let max_pairs = ctx.max_list_pairs();
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    let frame = viewer
        .frame(&scene, Shading::Clustered, Method::Refined, false)
        .unwrap();
    let stats = frame.stats.unwrap();
    assert!(stats.coarsened > 0 && !stats.over_budget, "{stats:?}");
    assert!(stats.pairs <= max_pairs, "{stats:?}");
    assert_eq!(frame.grid, stats.grid_built(&scene.grid));
    let clustered = viewer.image().unwrap();
    viewer
        .frame(&scene, Shading::BruteForce, Method::Refined, false)
        .unwrap();
    let brute = viewer.image().unwrap();
    let lit = clustered.iter().filter(|&&c| c > 0 && c < 255).count();
    assert!(
        lit > clustered.len() / 4,
        "{lit} channels lit: too few to compare"
    );
    assert!(max_channel_difference(&clustered, &brute) <= 1);
}

/// The frame loop (`myriad frames`) coarsens as the viewer does: on the same device and scene,
/// every frame of the sequential and of the pipelined loop is built on a coarser grid within
/// the device's binding, says so in its `grid_dims`, and the first frame (its lights not yet
/// moved) is brute force's image.
#[test]
fn the_frame_loop_coarsens_lists_past_what_the_device_binds() {
    if GpuContext::headless_for_tests().is_none() {
        return;
    }
    let (ctx, scene) = past_the_binding();
    let max_pairs = ctx.max_list_pairs();
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    viewer
        .frame(&scene, Shading::BruteForce, Method::Refined, false)
        .unwrap();
    let brute = viewer.image().unwrap();
    let mut images = [Vec::new(), Vec::new()];
    for (pipelined, images) in [false, true].into_iter().zip(&mut images) {
        let mut stage = viewer.gpu_stage();
        let report = run_frames(
            &mut stage,
            &scene,
            Method::Refined,
            2,
            pipelined,
            false,
            |_, gpu| {
                images.push(read_rgba8(gpu.ctx, &gpu.target.texture)?);
                Ok(())
            },
        )
        .unwrap();
        for (n, frame) in report.frames.iter().enumerate() {
            let built = UVec3::from_array(frame.grid_dims);
            assert!(
                built.cmplt(scene.grid.dims()).all() && frame.pairs <= max_pairs,
                "pipelined {pipelined}, frame {n}: {} pairs on {built}",
                frame.pairs
            );
        }
    }
    assert!(images[0] == images[1], "the loops rendered other images");
    let lit = brute.iter().filter(|&&c| c > 0 && c < 255).count();
    assert!(
        lit > brute.len() / 4,
        "{lit} channels lit: too few to compare"
    );
    let d = max_channel_difference(&images[0][0], &brute);
    assert!(
        d <= 1,
        "the first frame differs from brute force by {d}/255"
    );
}
