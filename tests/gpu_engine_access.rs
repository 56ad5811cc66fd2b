//! What an engine reaches of the renderer beyond a frame: a typed error for a device with too low
//! limits, the G-buffer's depth to draw its own geometry against, pass times after a depth
//! prepass (audit f3), and pipelines built ahead of the frames that use them.

use myriad::assignment::Method;
use myriad::gpu::{GpuContext, GpuError, Renderer, wgpu};
use myriad::render::{RenderScene, Shading, Viewer};

fn viewer_after_one_frame(width: u32, height: u32) -> Option<(RenderScene, Viewer)> {
    let ctx = GpuContext::headless_for_tests()?;
    let scene = RenderScene::default_scene(200, width, height).unwrap();
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    viewer
        .frame(&scene, Shading::Clustered, Method::Refined, false)
        .unwrap();
    Some((scene, viewer))
}

/// An engine's own render target: `size`, `format`, readable back, views of `view_formats` too.
fn engine_target(
    ctx: &GpuContext,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
    view_formats: &[wgpu::TextureFormat],
) -> wgpu::Texture {
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("engine target"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats,
    })
}

#[test]
fn a_device_below_the_required_limits_is_a_device_limits_error() {
    // The adapter's own device is only to see that one exists (or to skip where allowed).
    if GpuContext::headless_for_tests().is_none() {
        return;
    }
    // The process's one instance (`shared_instance` says why), as tests run in parallel.
    let adapter =
        pollster::block_on(myriad::gpu::shared_instance().request_adapter(&Default::default()))
            .unwrap();
    // The downlevel defaults allow four storage buffers per stage; the renderer needs five.
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_limits: wgpu::Limits::downlevel_defaults(),
        ..Default::default()
    }))
    .unwrap();
    let ctx = GpuContext::from_device(device, queue);
    match Renderer::try_new(&ctx, myriad::gpu::HEADLESS_FORMAT) {
        Err(GpuError::DeviceLimits(limits)) => {
            assert!(
                limits.contains("max_storage_buffers_per_shader_stage 4 (needs 5)"),
                "{limits}"
            );
        }
        other => panic!("want DeviceLimits, got {:?}", other.map(|_| ())),
    }
    // `Renderer::new` there neither panics (it did, in wgpu's validation) nor raises an error
    // an engine's own handler would see (under one, frames then blamed their target, engine
    // audit): every call returns the device's limits.
    let errors = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let seen = errors.clone();
    ctx.device
        .on_uncaptured_error(std::sync::Arc::new(move |_| {
            seen.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }));
    let renderer = Renderer::new(&ctx, myriad::gpu::HEADLESS_FORMAT);
    assert_eq!(errors.load(std::sync::atomic::Ordering::Relaxed), 0);
    let scene = RenderScene::default_scene(10, 32, 16).unwrap();
    let short = |result: Result<(), GpuError>, call: &str| match result {
        Err(GpuError::DeviceLimits(limits)) => assert!(
            limits.contains("max_storage_buffers_per_shader_stage 4 (needs 5)"),
            "{call}: {limits}"
        ),
        other => panic!("{call}: want DeviceLimits, got {other:?}"),
    };
    short(
        renderer.upload_scene(&ctx, &scene.geometry).map(drop),
        "upload_scene",
    );
    short(renderer.read_depth(&ctx).map(drop), "read_depth");
    short(renderer.last_pass_times(&ctx).map(drop), "last_pass_times");
}

/// A full-screen triangle at NDC depth `DEPTH` (prepended), drawn red with a `Greater` depth
/// test (the G-buffer is reversed Z) and no depth writes: where the engine's geometry is behind
/// what the frame drew, the frame shows through.
const OVERLAY_WGSL: &str = "
@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    return vec4<f32>(xy, DEPTH, 1.0);
}
@fragment fn fs() -> @location(0) vec4<f32> { return vec4<f32>(1.0, 0.0, 0.0, 1.0); }
";

#[test]
fn an_engine_depth_tests_its_own_geometry_against_the_gbuffer() {
    let Some((scene, viewer)) = viewer_after_one_frame(96, 48) else {
        return;
    };
    let ctx = &viewer.ctx;
    let frame_image = viewer.image().unwrap();
    let gbuffer = viewer.renderer.gbuffer().expect("a frame was drawn");
    assert_eq!(
        gbuffer.size,
        (scene.camera.width, scene.camera.height),
        "the G-buffer is the camera's size"
    );
    let depth = viewer.renderer.read_depth(ctx).unwrap().unwrap();
    // The overlay sits at the median depth of what the frame drew.
    let mut drawn: Vec<f32> = depth.iter().copied().filter(|&d| d > 0.0).collect();
    drawn.sort_by(f32::total_cmp);
    let overlay_depth = drawn[drawn.len() / 2];
    let module = ctx
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("engine overlay"),
            source: wgpu::ShaderSource::Wgsl(
                format!("const DEPTH: f32 = {overlay_depth:?};{OVERLAY_WGSL}").into(),
            ),
        });
    let pipeline = ctx
        .device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("engine overlay"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: myriad::gpu::DEPTH_FORMAT,
                depth_write_enabled: Some(false),
                depth_compare: Some(wgpu::CompareFunction::Greater),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(myriad::gpu::HEADLESS_FORMAT.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("engine overlay"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &viewer.target.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &gbuffer.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.draw(0..3, 0..1);
    }
    ctx.queue.submit([encoder.finish()]);
    let overlaid = viewer.image().unwrap();
    let red = [255u8, 0, 0, 255];
    let (mut in_front, mut behind) = (0, 0);
    for (at, &d) in depth.iter().enumerate() {
        let pixel = &overlaid[4 * at..4 * at + 4];
        // Pixels within an ulp of the overlay's depth could go either way.
        if (d - overlay_depth).abs() <= 1e-6 {
            continue;
        }
        // Reversed Z: a smaller stored depth is farther away.
        if d < overlay_depth {
            assert_eq!(pixel, red, "pixel {at} (depth {d}) should show the overlay");
            behind += 1;
        } else {
            assert_eq!(
                pixel,
                &frame_image[4 * at..4 * at + 4],
                "pixel {at} (depth {d}) is in front of the overlay"
            );
            in_front += 1;
        }
    }
    assert!(
        in_front > 0 && behind > 0,
        "the view must have geometry on both sides of the overlay ({in_front} in front, {behind} behind)"
    );
}

#[test]
fn pass_times_after_a_depth_prepass_include_the_prepass_gbuffer() {
    let Some((scene, mut viewer)) = viewer_after_one_frame(96, 48) else {
        return;
    };
    let ctx = viewer.ctx.clone();
    if !ctx.has_timestamps() {
        // llvmpipe (CI's adapter) has timestamps: the checks below must run there.
        assert!(!ctx.describe().contains("llvmpipe"), "{}", ctx.describe());
        return;
    }
    let lists = viewer.lists().clone();
    let renderer = &mut viewer.renderer;
    ctx.wait_idle().unwrap();
    let frame = renderer.last_pass_times(&ctx).unwrap().unwrap();
    assert!(frame.gbuffer_ms.is_some() && frame.shading_ms.is_some());

    // Right after the prepass: its G-buffer pass alone (not the previous frame's passes).
    renderer
        .render_prepass(&ctx, &viewer.scene, &scene.camera)
        .unwrap();
    ctx.wait_idle().unwrap();
    let prepass = renderer.last_pass_times(&ctx).unwrap().unwrap();
    assert!(prepass.gbuffer_ms.is_some(), "{prepass:?}");
    assert_eq!(prepass.shading_ms, None, "{prepass:?}");
    assert_eq!(prepass.forward_ms, None, "{prepass:?}");

    // Shading the prepass's G-buffer: the G-buffer time is the prepass's, beside the shading's.
    let frame_desc = myriad::gpu::FrameDesc::clustered(
        &scene.camera,
        &scene.grid,
        myriad::render::light_columns(&scene.lights),
        myriad::render::cluster_lists(&lists),
    );
    renderer
        .render_after_prepass(&ctx, &viewer.scene, &frame_desc, &viewer.target.view)
        .unwrap();
    ctx.wait_idle().unwrap();
    let after = renderer.last_pass_times(&ctx).unwrap().unwrap();
    assert_eq!(after.gbuffer_ms, prepass.gbuffer_ms, "{after:?}");
    assert!(after.shading_ms.is_some(), "{after:?}");
}

/// `prepare` builds exactly the pipelines a frame of that kind then uses: the frame builds none
/// while it encodes (an engine's load-time call keeps shader compilation out of its frames), a
/// second `prepare` builds nothing, and kinds that share pipelines (tiled and clustered shading)
/// build them once.
#[test]
fn prepared_pipelines_are_the_ones_frames_use() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let scene = RenderScene::default_scene(200, 96, 48).unwrap();
    // The atrium's spot lamps and blended glass: the spot variants and the forward pass.
    assert!(scene.lights.has_spots() && scene.has_blended());
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    assert_eq!(viewer.renderer.pipelines_built(), 1, "the G-buffer's alone");
    // (shading, heat map, pipelines `prepare` builds: deferred, and forward for a lit image)
    let kinds = [
        (Shading::Clustered, false, 2),
        (Shading::Clustered, true, 1),
        (Shading::BruteForce, false, 2),
        (Shading::Tiled, false, 0),
        (Shading::BruteForce, true, 1),
    ];
    for (shading, heat_map, want) in kinds {
        let what = format!("{shading:?}, heat map {heat_map}");
        assert_eq!(
            viewer.prepare(&scene, shading, heat_map).unwrap(),
            want,
            "{what}"
        );
        let before = viewer.renderer.pipelines_built();
        viewer
            .frame(&scene, shading, Method::Refined, heat_map)
            .unwrap();
        viewer.ctx.wait_idle().unwrap();
        assert_eq!(
            viewer.renderer.pipelines_built(),
            before,
            "{what}: the frame built pipelines while encoding"
        );
        assert_eq!(
            viewer.prepare(&scene, shading, heat_map).unwrap(),
            0,
            "{what}"
        );
    }
    assert_eq!(viewer.renderer.pipelines_built(), 1 + 2 + 1 + 2 + 1);

    // Without lights in the description, the last upload's spot columns decide the variant:
    // the spot variants, already built.
    let lists = viewer.lists().clone();
    let mut frame = myriad::gpu::FrameDesc::clustered(
        &scene.camera,
        &scene.grid,
        myriad::render::light_columns(&scene.lights),
        myriad::render::cluster_lists(&lists),
    );
    frame.lights = None;
    let (ctx, gpu_scene) = (viewer.ctx.clone(), &viewer.scene);
    assert_eq!(viewer.renderer.prepare(&ctx, gpu_scene, &frame).unwrap(), 0);
    // Lights without spot columns are another variant, deferred and forward.
    let mut plain = myriad::scene::Lights::new();
    for light in scene.lights.iter() {
        plain.push(myriad::scene::LightRecord {
            spot: None,
            ..light
        });
    }
    assert!(!plain.has_spots());
    frame.lights = Some(myriad::render::light_columns(&plain));
    assert_eq!(viewer.renderer.prepare(&ctx, gpu_scene, &frame).unwrap(), 2);
}

/// An engine's swap chain is often UNORM without sRGB (`Bgra8Unorm`; on the web the only choice):
/// the shaders then encode sRGB themselves, so the image is the sRGB target's. Written linear, it
/// came out up to 74/255 too dark and the heat map's colours were off their legend (audit). The
/// scene's glass is drawn opaque here: blending into a UNORM target mixes encoded values (as any
/// blending into one does), into an sRGB target linear ones, so the two differ there by design.
#[test]
fn a_unorm_target_gets_the_image_of_an_srgb_target() {
    use myriad::gpu::{Blend, FrameDesc, encodes_srgb};
    use myriad::render::{cluster_lists, light_columns, max_channel_difference};
    let Some((scene, viewer)) = viewer_after_one_frame(96, 48) else {
        return;
    };
    let ctx = &viewer.ctx;
    assert!(scene.geometry.has_blended(), "the atrium has glass");
    let mut opaque = scene.geometry.clone();
    for material in &mut opaque.materials {
        material.blend = Blend::Opaque;
    }
    let opaque = viewer.renderer.upload_scene(ctx, &opaque).unwrap();
    let (width, height) = (scene.camera.width, scene.camera.height);
    let mut images = Vec::new();
    for format in [
        wgpu::TextureFormat::Rgba8UnormSrgb,
        wgpu::TextureFormat::Rgba8Unorm,
    ] {
        assert_eq!(encodes_srgb(format), !format.is_srgb());
        let mut renderer = Renderer::try_new(ctx, format).unwrap();
        let texture = engine_target(ctx, (width, height), format, &[]);
        let view = texture.create_view(&Default::default());
        let mut pair = Vec::new();
        for heat_map in [false, true] {
            let frame = FrameDesc {
                heat_map,
                ..FrameDesc::clustered(
                    &scene.camera,
                    &scene.grid,
                    light_columns(&scene.lights),
                    cluster_lists(viewer.lists()),
                )
            };
            renderer.render(ctx, &opaque, &frame, &view).unwrap();
            pair.push(myriad::gpu::read_rgba8(ctx, &texture).unwrap());
        }
        images.push(pair);
    }
    assert!(!encodes_srgb(wgpu::TextureFormat::Rgba16Float));
    for (kind, (srgb, unorm)) in ["lit", "heat map"]
        .iter()
        .zip(images[0].iter().zip(&images[1]))
    {
        // The view must show more than its background for the comparison to mean anything.
        let distinct: std::collections::HashSet<&[u8]> = srgb.chunks(4).collect();
        assert!(distinct.len() > 5, "{kind}: {} colours", distinct.len());
        // The hardware's encoding and the shader's may round a channel apart.
        let difference = max_channel_difference(srgb, unorm);
        assert!(difference <= 1, "{kind}: {difference}/255 apart");
    }
}

/// An engine shades the same lights into targets of several formats (an HDR view, an sRGB
/// swap chain, an editor thumbnail): one renderer draws them all, each format's pipelines built
/// once, and every image is byte for byte the one a renderer made for that format draws. Before,
/// a renderer drew only into its own format, so each format needed a renderer of its own, with
/// its own copy of the lights, lists and G-buffer.
#[test]
fn one_renderer_draws_into_targets_of_several_formats() {
    use myriad::gpu::{FrameDesc, HEADLESS_FORMAT, read_texels};
    use myriad::render::{cluster_lists, light_columns};
    use wgpu::TextureFormat as F;
    let Some((scene, viewer)) = viewer_after_one_frame(96, 48) else {
        return;
    };
    let ctx = &viewer.ctx;
    // The glass too: the forward pass blends into each format.
    assert!(scene.has_blended());
    let (width, height) = (scene.camera.width, scene.camera.height);
    let target =
        |format, view_formats: &[F]| engine_target(ctx, (width, height), format, view_formats);
    let lists = viewer.lists().clone();
    let frame = FrameDesc::clustered(
        &scene.camera,
        &scene.grid,
        light_columns(&scene.lights),
        cluster_lists(&lists),
    );
    let gpu_scene = &viewer.scene;
    let draw = |renderer: &mut Renderer, view: &wgpu::TextureView| {
        renderer.render(ctx, gpu_scene, &frame, view).unwrap();
    };
    assert_eq!(HEADLESS_FORMAT, F::Rgba8UnormSrgb);
    let mut shared = Renderer::try_new(ctx, HEADLESS_FORMAT).unwrap();
    // Built ahead for a second format: a frame into it builds nothing more.
    assert_eq!(
        shared
            .prepare_for(ctx, gpu_scene, &frame, F::Rgba16Float)
            .unwrap(),
        2,
        "deferred and forward for Rgba16Float"
    );
    let formats = [
        F::Rgba8UnormSrgb,
        F::Rgba16Float,
        F::Rgba8Unorm,
        F::Bgra8UnormSrgb,
    ];
    let mut images = Vec::new();
    for format in formats {
        let texture = target(format, &[]);
        let view = texture.create_view(&Default::default());
        let before = shared.pipelines_built();
        draw(&mut shared, &view);
        let built = shared.pipelines_built() - before;
        // `shared` is new: each format's deferred and forward pipelines are built by its first
        // frame, but Rgba16Float's, prepared above.
        let want = if format == F::Rgba16Float { 0 } else { 2 };
        assert_eq!(
            built, want,
            "{format:?}: pipelines built by its first frame"
        );
        let image = read_texels(ctx, &texture).unwrap();
        // The same frame from a renderer made for the format alone.
        let mut own = Renderer::try_new(ctx, format).unwrap();
        let alone = target(format, &[]);
        draw(&mut own, &alone.create_view(&Default::default()));
        assert!(
            image == read_texels(ctx, &alone).unwrap(),
            "{format:?}: not the image of a renderer made for it"
        );
        images.push((format, texture, image));
    }
    // The images show the scene, and BGRA's is RGBA's swapped (the same hardware encoding).
    // (`a_unorm_target_gets_the_image_of_an_srgb_target` compares Rgba8Unorm's with sRGB's.)
    let srgb = &images[0].2;
    let distinct: std::collections::HashSet<&[u8]> = srgb.chunks(4).collect();
    assert!(distinct.len() > 5, "{} colours", distinct.len());
    let bgra = &images[3].2;
    assert!(
        srgb.chunks(4)
            .zip(bgra.chunks(4))
            .all(|(rgba, bgra)| rgba == [bgra[2], bgra[1], bgra[0], bgra[3]]),
        "Bgra8UnormSrgb is not Rgba8UnormSrgb's image swapped"
    );
    assert_eq!(
        images[1].2.len(),
        srgb.len() * 2,
        "Rgba16Float: 8 bytes a pixel"
    );
    // Back to the first target: drawn again, the same bytes (no format's state leaks into
    // another's frame).
    let (_, first, first_image) = &images[0];
    draw(&mut shared, &first.create_view(&Default::default()));
    assert_eq!(&read_texels(ctx, first).unwrap(), first_image);

    // Views that reinterpret their texture's sRGB-ness are drawn in the view's format: a linear
    // texture seen as sRGB gives the sRGB image, an sRGB texture seen as linear the UNORM one.
    for (texture_format, view_format, want) in [
        (F::Rgba8Unorm, F::Rgba8UnormSrgb, 0),
        (F::Rgba8UnormSrgb, F::Rgba8Unorm, 2),
    ] {
        let texture = target(texture_format, &[view_format]);
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            format: Some(view_format),
            ..Default::default()
        });
        draw(&mut shared, &view);
        assert!(
            read_texels(ctx, &texture).unwrap() == images[want].2,
            "a {texture_format:?} texture seen as {view_format:?}: not {:?}'s image",
            images[want].0
        );
    }
    // A format the passes cannot draw is refused ahead as in a frame.
    let refused = shared.prepare_for(ctx, gpu_scene, &frame, F::Rgba8Uint);
    assert!(
        matches!(&refused, Err(GpuError::InvalidInput(m)) if m.contains("cannot draw into")),
        "{:?}",
        refused.map(drop)
    );
}

/// An engine with two devices (a window's and a headless one) can hand a renderer the other
/// device's context, scene or target by mistake: wgpu panicked inside the frame ("Cannot get
/// non-existent resource", audit); every call refuses it instead, and the renderer still draws
/// on its own device afterwards.
#[test]
fn a_context_or_scene_of_another_device_is_refused() {
    let Some((scene, mut mine)) = viewer_after_one_frame(64, 32) else {
        return;
    };
    let other = Viewer::new(GpuContext::headless().unwrap(), &scene).unwrap();
    assert!(mine.ctx.device != other.ctx.device, "two devices");
    let lists = mine.lists().clone();
    let frame = myriad::gpu::FrameDesc::clustered(
        &scene.camera,
        &scene.grid,
        myriad::render::light_columns(&scene.lights),
        myriad::render::cluster_lists(&lists),
    );
    let refused = |result: Result<(), GpuError>, what: &str, needle: &str| match result {
        Err(GpuError::InvalidInput(message)) => {
            assert!(message.contains(needle), "{what}: {message}")
        }
        other => panic!("{what}: want InvalidInput, got {other:?}"),
    };
    let target = &mine.target.view;
    let (ctx, scene_b) = (&other.ctx, &other.scene);
    let r = &mut mine.renderer;
    let ctx_a = mine.ctx.clone();
    let another = "another device than the one this renderer";
    refused(
        r.render(ctx, &mine.scene, &frame, target).map(drop),
        "render",
        another,
    );
    refused(
        r.render_after_prepass(ctx, &mine.scene, &frame, target)
            .map(drop),
        "render_after_prepass",
        another,
    );
    refused(
        r.render_prepass(ctx, &mine.scene, &scene.camera),
        "prepass",
        another,
    );
    refused(
        r.prepare(ctx, &mine.scene, &frame).map(drop),
        "prepare",
        another,
    );
    refused(r.read_depth(ctx).map(drop), "read_depth", another);
    refused(r.last_pass_times(ctx).map(drop), "last_pass_times", another);
    refused(
        r.upload_scene(ctx, &scene.geometry).map(drop),
        "upload_scene",
        another,
    );
    // The right context with the other device's scene.
    let other_scene = "scene was uploaded on another device";
    refused(
        r.render(&ctx_a, scene_b, &frame, target).map(drop),
        "render",
        other_scene,
    );
    refused(
        r.prepare(&ctx_a, scene_b, &frame).map(drop),
        "prepare",
        other_scene,
    );
    refused(
        r.render_prepass(&ctx_a, scene_b, &scene.camera),
        "prepass",
        other_scene,
    );
    // The right context and scene with the other device's target: the target check's recording
    // refuses it (wgpu 30 names the mismatch; it panicked inside the frame when the format was
    // compared alone).
    refused(
        r.render(&ctx_a, &mine.scene, &frame, &other.target.view)
            .map(drop),
        "render into the other device's target",
        "of this renderer's device",
    );
    // Nothing of that changed the renderer: its own frame still draws.
    mine.renderer
        .render(&ctx_a, &mine.scene, &frame, &mine.target.view)
        .unwrap();
    assert!(mine.renderer.read_depth(&ctx_a).unwrap().is_some());
}

/// An engine's device with timestamp queries but not between commands (`TIMESTAMP_QUERY`
/// alone, as many adapters offer it) times the passes and not the upload's copies: a timestamp
/// written into an encoder is a validation error there. A device with neither times nothing.
/// (Mutation audit: CI's headless device has both features, so a renderer that took encoder
/// timestamps for granted passed every test.)
#[test]
fn pass_times_follow_the_timestamp_features_of_an_engines_device() {
    if GpuContext::headless_for_tests().is_none() {
        return;
    }
    let adapter =
        pollster::block_on(myriad::gpu::shared_instance().request_adapter(&Default::default()))
            .unwrap();
    if !adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
        // llvmpipe (CI's adapter) has timestamps: the checks below must run there.
        assert!(!adapter.get_info().name.contains("llvmpipe"));
        return;
    }
    let scene = RenderScene::default_scene(50, 48, 24).unwrap();
    for features in [wgpu::Features::TIMESTAMP_QUERY, wgpu::Features::empty()] {
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            required_features: features,
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .unwrap();
        let ctx = GpuContext::from_device(device, queue);
        let timed = !features.is_empty();
        assert_eq!(ctx.has_timestamps(), timed, "{features:?}");
        assert!(!ctx.has_encoder_timestamps(), "{features:?}");
        let mut viewer = Viewer::new(ctx.clone(), &scene).unwrap();
        viewer
            .frame(&scene, Shading::Clustered, Method::Refined, false)
            .unwrap();
        ctx.wait_idle().unwrap();
        let times = viewer.renderer.last_pass_times(&ctx).unwrap();
        match times {
            Some(t) if timed => {
                assert!(t.gbuffer_ms.is_some() && t.shading_ms.is_some(), "{t:?}");
                assert_eq!(t.upload_ms, None, "{t:?}");
            }
            other => assert!(!timed && other.is_none(), "{features:?}: {other:?}"),
        }
    }
}

/// Reading back a texture whose copy needs a buffer past the device's `max_buffer_size` is an
/// error naming the sizes, not a wgpu panic (a 32768² RGBA8 target needs 4 GiB).
#[test]
fn a_read_back_past_the_buffer_limit_is_an_error() {
    if GpuContext::headless_for_tests().is_none() {
        return;
    }
    let adapter =
        pollster::block_on(myriad::gpu::shared_instance().request_adapter(&Default::default()))
            .unwrap();
    const LIMIT: u64 = 1 << 20;
    let descriptor = wgpu::DeviceDescriptor {
        required_limits: wgpu::Limits {
            max_buffer_size: LIMIT,
            ..wgpu::Limits::downlevel_defaults()
        },
        ..Default::default()
    };
    let (device, queue) = pollster::block_on(adapter.request_device(&descriptor)).unwrap();
    let ctx = GpuContext::from_device(device, queue);
    let texture = |height: u32| {
        ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("read back"),
            size: wgpu::Extent3d {
                width: 512,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        })
    };
    // 512 × 512 × 4 bytes is exactly the limit; one row more is past it.
    let fits = myriad::gpu::read_rgba8(&ctx, &texture(512)).unwrap();
    assert_eq!(fits.len() as u64, LIMIT);
    match myriad::gpu::read_rgba8(&ctx, &texture(513)) {
        Err(GpuError::InvalidInput(message)) => assert!(
            message.contains("1050624-byte buffer") && message.contains("(1048576 bytes)"),
            "{message}"
        ),
        other => panic!("a read back past the limit: {:?}", other.map(|v| v.len())),
    }
}

/// The engine guide's "In an engine's own frame" steps, word for word with public items, on an
/// engine's own renderer and target: cull and gather, the depth prepass and its read-back, the
/// fitted grid and the active clusters *of the fitted grid*, `assign_active`, and the shading
/// after the prepass — the image of a plain frame of every light. (Followed literally, the
/// guide's first version marked the mask on the unfitted grid, which `assign_active` refuses
/// with a panic; a drop-in review found it.)
#[test]
fn the_guides_skipping_steps_in_an_engines_own_frame_give_the_plain_frames_image() {
    use myriad::assignment::{ActiveClusters, Assigner, LightLists};
    use myriad::gpu::{FrameDesc, HEADLESS_FORMAT};
    use myriad::render::{
        blended_bounds, cluster_lists, fitted_grid, light_columns, mark_active,
        max_channel_difference,
    };
    use myriad::scene::Lights;
    use myriad::scene::systems::{Visibility, cull_lights};
    let Some((scene, viewer)) = viewer_after_one_frame(192, 96) else {
        return;
    };
    let ctx = &viewer.ctx;
    let (camera, grid) = (&scene.camera, &scene.grid);
    let mut renderer = Renderer::try_new(ctx, HEADLESS_FORMAT).unwrap();
    let gpu_scene = renderer.upload_scene(ctx, &scene.geometry).unwrap();
    let texture = engine_target(ctx, (camera.width, camera.height), HEADLESS_FORMAT, &[]);
    let view = texture.create_view(&Default::default());
    let mut assigner = Assigner::new();

    // The plain frame: every light, the whole grid.
    let mut all_lists = LightLists::new();
    let input = myriad::light_input(&scene.lights);
    assigner.assign(Method::Refined, &input, camera, grid, &mut all_lists);
    let plain = FrameDesc::clustered(
        camera,
        grid,
        light_columns(&scene.lights),
        cluster_lists(&all_lists),
    );
    renderer.render(ctx, &gpu_scene, &plain, &view).unwrap();
    let plain_image = myriad::gpu::read_rgba8(ctx, &texture).unwrap();

    // 1. Cull, and gather the visible lights: the lists index these from here on.
    let (mut visibility, mut visible) = (Visibility::default(), Lights::new());
    cull_lights(camera, scene.lights.slices(), &mut visibility);
    scene.lights.gather_into(&visibility.indices, &mut visible);
    assert!(
        visible.len() < scene.lights.len(),
        "the cull must drop some"
    );
    // 2. The depth prepass and its read-back.
    renderer.render_prepass(ctx, &gpu_scene, camera).unwrap();
    let depth = renderer.read_depth(ctx).unwrap().expect("the prepass drew");
    // 3. The fitted grid, then the active clusters of that grid.
    let blended = blended_bounds(&scene.geometry);
    assert!(!blended.is_empty(), "the atrium has glass");
    let fitted = fitted_grid(grid, camera, &depth, &blended);
    let mut mask = ActiveClusters::new(&fitted);
    mark_active(&mut mask, &fitted, camera, &depth, &blended);
    assert!(mask.active_count() < fitted.cluster_count());
    // 4. Assign the visible lights to the active clusters.
    let mut lists = LightLists::new();
    let stats = assigner.assign_active(
        Method::Refined,
        &myriad::light_input(&visible),
        camera,
        &fitted,
        Some(&mask),
        &mut lists,
    );
    let drawn = stats.grid_built(&fitted);
    // Lights skipped as invalid: the cull dropped them, so the assignment saw none.
    let invalid = visibility.invalid() + stats.rejected as usize;
    assert_eq!(invalid, 0, "the atrium's lights are all valid");
    assert!(lists.pair_count() < all_lists.pair_count());
    // 5. Shade after the prepass, with the gathered columns.
    let frame = FrameDesc::clustered(
        camera,
        &drawn,
        light_columns(&visible),
        cluster_lists(&lists),
    );
    renderer
        .render_after_prepass(ctx, &gpu_scene, &frame, &view)
        .unwrap();
    let skipped_image = myriad::gpu::read_rgba8(ctx, &texture).unwrap();
    let difference = max_channel_difference(&plain_image, &skipped_image);
    assert!(difference <= 1, "{difference}/255 off the plain frame");
}
