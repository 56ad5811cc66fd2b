//! Using myriad's renderer from an engine: the engine owns the wgpu device, queue and target
//! texture; it hands the renderer flat geometry once, and per frame its light columns and the
//! CSR lists from `myriad-assignment`. Only `myriad-cluster-math`, `myriad-assignment` and
//! `myriad-gpu` are used, as an engine depending on just those would.
//!
//! Run with `cargo run --release --example gpu_integration` (needs a Vulkan, Metal or DX12
//! adapter; Mesa's software Vulkan works). It is also a test (`test = true` in `Cargo.toml`, so
//! `cargo test` runs the `tests` module below): the engine-owned device path must render what
//! brute force renders, and keep the adapter's loop guard.

use myriad_assignment::{Assigner, LightInput, LightLists, Method};
use myriad_cluster_math::glam::camera::rh::{proj::directx, view};
use myriad_cluster_math::glam::{UVec3, Vec3};
use myriad_cluster_math::{Camera, ClipSpace, ClusterGrid, DepthSlicing};
use myriad_gpu::layout::{MaterialUniforms, Vertex};
use myriad_gpu::wgpu;
use myriad_gpu::{
    Blend, ClusterLists, Draw, FrameDesc, FrameReport, GpuContext, GpuError, LightColumns,
    MaterialDesc, Renderer, SceneGeometry, ShadingMode, ShadingSettings,
};

const SIZE: (u32, u32) = (320, 180);
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// What the engine owns: its device and queue (here a headless one), a render target, and the
/// assigner and lists it keeps from frame to frame (their storage grows once, then is reused).
struct Engine {
    ctx: GpuContext,
    target: wgpu::Texture,
    assigner: Assigner,
    lists: LightLists,
}

/// The engine's wgpu instance: one per process, kept for its lifetime. Devices may come and go,
/// but instances made and dropped on several threads at once (this file's tests run in
/// parallel) crashed NVIDIA's driver (`myriad_gpu::shared_instance` says what was seen).
fn engine_instance() -> &'static wgpu::Instance {
    static INSTANCE: std::sync::OnceLock<wgpu::Instance> = std::sync::OnceLock::new();
    INSTANCE
        .get_or_init(|| wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle()))
}

/// The engine's device and queue: one for the process, as an engine has (this file's tests share
/// it; devices made and dropped on several threads at once can deadlock NVIDIA's driver,
/// `GpuContext::headless_for_tests` says what was seen).
fn engine_device() -> Result<&'static (wgpu::Device, wgpu::Queue), String> {
    static DEVICE: std::sync::OnceLock<Result<(wgpu::Device, wgpu::Queue), String>> =
        std::sync::OnceLock::new();
    DEVICE
        .get_or_init(|| {
            let adapter =
                pollster::block_on(engine_instance().request_adapter(&Default::default()))
                    .map_err(|e| e.to_string())?;
            // What the renderer needs of the device, raised to the adapter's texture and
            // buffer sizes (the bare minimum caps targets at 2048 pixels a side).
            let descriptor = wgpu::DeviceDescriptor {
                required_limits: Renderer::required_limits_for(&adapter.limits()),
                ..Default::default()
            };
            pollster::block_on(adapter.request_device(&descriptor)).map_err(|e| e.to_string())
        })
        .as_ref()
        .map_err(Clone::clone)
}

impl Engine {
    fn new() -> Result<Self, Box<dyn std::error::Error>> {
        let (device, queue) = engine_device()?.clone();
        let target = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("engine target"),
            size: wgpu::Extent3d {
                width: SIZE.0,
                height: SIZE.1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        // Hand the renderer the engine's device.
        let ctx = GpuContext::from_device(device, queue);
        // Lists past what the device binds are built on a coarser grid, which the frame must
        // then be drawn with, rather than refused by the renderer after the assignment.
        let assigner = Assigner::new().with_pair_budget(ctx.max_list_pairs());
        Ok(Self {
            ctx,
            target,
            assigner,
            lists: LightLists::new(),
        })
    }
}

/// The engine's geometry, handed over once: a 40 m floor.
fn floor() -> SceneGeometry {
    let up = [0.0, 1.0, 0.0];
    let corner = |x: f32, z: f32| Vertex {
        position: [x, 0.0, z],
        normal: up,
        uv: [0.0, 0.0],
    };
    SceneGeometry {
        vertices: vec![
            corner(-20.0, 5.0),
            corner(20.0, 5.0),
            corner(20.0, -35.0),
            corner(-20.0, -35.0),
        ],
        indices: vec![0, 1, 2, 0, 2, 3],
        draws: vec![Draw {
            first_index: 0,
            index_count: 6,
            material: 0,
            center: Vec3::new(0.0, 0.0, -15.0),
        }],
        materials: vec![MaterialDesc {
            uniforms: MaterialUniforms {
                base_color: [0.8, 0.8, 0.8, 1.0],
                roughness: 0.6,
                ..Default::default()
            },
            blend: Blend::Opaque,
            base_color_texture: None,
        }],
        textures: vec![],
    }
}

/// The engine's lights as SoA columns: rows of 8 coloured lights above the floor.
struct Lights {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    radius: Vec<f32>,
    rgb: [Vec<f32>; 3],
    intensity: Vec<f32>,
}

impl Lights {
    fn rows(n: usize) -> Self {
        Self {
            x: (0..n).map(|i| (i % 8) as f32 * 4.0 - 14.0).collect(),
            y: vec![0.8; n],
            z: (0..n).map(|i| -((i / 8) as f32) * 4.0 - 2.0).collect(),
            radius: vec![3.0; n],
            rgb: [0, 1, 2].map(|c| (0..n).map(|i| f32::from(u8::from(i % 3 == c))).collect()),
            intensity: vec![4.0; n],
        }
    }

    fn columns(&self) -> LightColumns<'_> {
        LightColumns {
            x: &self.x,
            y: &self.y,
            z: &self.z,
            radius: &self.radius,
            r: &self.rgb[0],
            g: &self.rgb[1],
            b: &self.rgb[2],
            intensity: &self.intensity,
            spot: None,
        }
    }
}

/// The engine's camera, from its own matrices: a look-at view and the infinite reversed-Z
/// projection most engines use. `Camera::from_matrices` reads them back (`far` is infinite); the
/// lists' grid slices the depths the scene spans, 0.1 to 60.
fn view() -> (Camera, ClusterGrid) {
    let view_from_world = view::look_at_mat4(
        Vec3::new(0.0, 6.0, 6.0),
        Vec3::new(0.0, 0.0, -14.0),
        Vec3::Y,
    );
    let aspect = SIZE.0 as f32 / SIZE.1 as f32;
    let clip_from_view = directx::perspective_infinite_reverse(60f32.to_radians(), aspect, 0.1);
    let camera = Camera::from_matrices(
        view_from_world,
        clip_from_view,
        ClipSpace::ZeroToOneYUp,
        SIZE.0,
        SIZE.1,
    )
    .expect("a centred, right-handed perspective");
    assert!(camera.far.is_infinite());
    let grid = ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, camera.near, 60.0);
    (camera, grid)
}

/// One frame: assign on the CPU (for `ShadingMode::Lists`), then render into the engine's
/// target; returns the report, the pairs assigned and the target's pixels.
fn frame(
    engine: &mut Engine,
    renderer: &mut Renderer,
    scene: &myriad_gpu::GpuScene,
    lights: &Lights,
    mode: ShadingMode,
) -> Result<(FrameReport, u64, Vec<u8>), GpuError> {
    frame_with(
        engine,
        renderer,
        scene,
        lights,
        mode,
        ShadingSettings::default(),
    )
}

/// [`frame`] with other shading settings.
fn frame_with(
    engine: &mut Engine,
    renderer: &mut Renderer,
    scene: &myriad_gpu::GpuScene,
    lights: &Lights,
    mode: ShadingMode,
    settings: ShadingSettings,
) -> Result<(FrameReport, u64, Vec<u8>), GpuError> {
    let (camera, grid) = view();
    let (pairs, grid) = if mode == ShadingMode::Lists {
        let input = LightInput::points(&lights.x, &lights.y, &lights.z, &lights.radius);
        let stats = engine
            .assigner
            .try_assign(Method::Refined, &input, &camera, &grid, &mut engine.lists)
            .map_err(|e| GpuError::InvalidInput(e.to_string()))?;
        (stats.pairs, stats.grid_built(&grid))
    } else {
        (0, grid)
    };
    let lists = &engine.lists;
    let report = renderer.render(
        &engine.ctx,
        scene,
        &FrameDesc {
            camera: &camera,
            grid: &grid,
            mode,
            heat_map: false,
            lights: Some(lights.columns()),
            lists: (mode == ShadingMode::Lists).then_some(ClusterLists {
                offsets: &lists.offsets,
                counts: &lists.counts,
                indices: &lists.indices,
            }),
            settings,
        },
        &engine.target.create_view(&Default::default()),
    )?;
    let pixels = myriad_gpu::read_rgba8(&engine.ctx, &engine.target)?;
    Ok((report, pairs, pixels))
}

/// Pixels that a light visibly brightens (any channel above 80).
fn lit_pixels(pixels: &[u8]) -> usize {
    pixels
        .chunks(4)
        .filter(|p| p[0].max(p[1]).max(p[2]) > 80)
        .count()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut engine = Engine::new()?;
    // `try_new`: a device below the renderer's limits is an error that names them.
    let mut renderer = Renderer::try_new(&engine.ctx, FORMAT)?;
    let scene = renderer.upload_scene(&engine.ctx, &floor())?;
    let lights = Lights::rows(64);
    // At load time: the shading pipelines of the frames to come, so no frame compiles shaders.
    let (camera, grid) = view();
    let prepared = renderer.prepare(
        &engine.ctx,
        &scene,
        &FrameDesc {
            camera: &camera,
            grid: &grid,
            mode: ShadingMode::Lists,
            heat_map: false,
            lights: Some(lights.columns()),
            lists: None,
            settings: ShadingSettings::default(),
        },
    )?;
    let built_before = renderer.pipelines_built();
    // Three frames through the engine's one assigner and lists (grown in the first, reused in
    // the others).
    for n in 0..3 {
        let (report, pairs, pixels) = frame(
            &mut engine,
            &mut renderer,
            &scene,
            &lights,
            ShadingMode::Lists,
        )?;
        println!(
            "frame {n}: {} lights, {pairs} pairs, {} bytes uploaded; {} of {} pixels lit; \
             {prepared} pipeline(s) built at load time, {} during the frames",
            lights.x.len(),
            report.upload_bytes,
            lit_pixels(&pixels),
            SIZE.0 * SIZE.1,
            renderer.pipelines_built() - built_before
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_engines_own_device_renders_what_brute_force_renders() {
        // Like the library's GPU tests: an adapter is required unless explicitly skipped.
        if GpuContext::headless_for_tests().is_none() {
            return;
        }
        let mut engine = Engine::new().unwrap();
        let mut renderer = Renderer::new(&engine.ctx, FORMAT);
        let scene = renderer.upload_scene(&engine.ctx, &floor()).unwrap();
        let lights = Lights::rows(64);
        let (report, pairs, clustered) = frame(
            &mut engine,
            &mut renderer,
            &scene,
            &lights,
            ShadingMode::Lists,
        )
        .unwrap();
        assert_eq!(report.lights, 64);
        assert!(pairs > 64, "{pairs} pairs");
        let (_, _, brute) = frame(
            &mut engine,
            &mut renderer,
            &scene,
            &lights,
            ShadingMode::BruteForce,
        )
        .unwrap();
        let worst = clustered
            .iter()
            .zip(&brute)
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap();
        assert!(
            worst <= 1,
            "clustered differs from brute force by {worst}/255"
        );
        // The floor has no blended material: no forward pass, unless every feature is forced,
        // and then the same image.
        assert!(!report.forward_pass);
        let everything = ShadingSettings {
            force_all_features: true,
            ..Default::default()
        };
        let (forced, _, all_features) = frame_with(
            &mut engine,
            &mut renderer,
            &scene,
            &lights,
            ShadingMode::Lists,
            everything,
        )
        .unwrap();
        assert!(forced.forward_pass);
        assert_eq!(all_features, clustered);
        // The 64 lights light a good part of the floor, and not all of the image.
        let lit = lit_pixels(&clustered);
        let all = (SIZE.0 * SIZE.1) as usize;
        assert!(lit > all / 10 && lit < all, "{lit} of {all} pixels lit");
    }

    #[test]
    fn a_refused_frame_changes_nothing() {
        if GpuContext::headless_for_tests().is_none() {
            return;
        }
        let mut engine = Engine::new().unwrap();
        let mut renderer = Renderer::new(&engine.ctx, FORMAT);
        let scene = renderer.upload_scene(&engine.ctx, &floor()).unwrap();
        let (few, many) = (Lights::rows(8), Lights::rows(64));
        let (report, _, before) =
            frame(&mut engine, &mut renderer, &scene, &few, ShadingMode::Lists).unwrap();
        assert_eq!(report.lights, 8);
        // 64 lights with lists one cluster short: refused.
        let (camera, grid) = view();
        let mut lists = LightLists::new();
        let input = LightInput::points(&many.x, &many.y, &many.z, &many.radius);
        Assigner::new().assign(Method::Refined, &input, &camera, &grid, &mut lists);
        let target = engine.target.create_view(&Default::default());
        let columns = many.columns();
        let desc = |lights: bool, clusters: usize| FrameDesc {
            camera: &camera,
            grid: &grid,
            mode: ShadingMode::Lists,
            heat_map: false,
            lights: lights.then_some(columns),
            lists: Some(ClusterLists {
                offsets: &lists.offsets[..clusters],
                counts: &lists.counts[..clusters],
                indices: &lists.indices,
            }),
            settings: Default::default(),
        };
        let short = grid.cluster_count() - 1;
        let refused = renderer.render(&engine.ctx, &scene, &desc(true, short), &target);
        assert!(
            matches!(refused, Err(GpuError::InvalidInput(_))),
            "{refused:?}"
        );
        // The renderer still holds the 8 lights: the 64-light lists do not fit them, and the
        // 8-light frame renders as before.
        let all = grid.cluster_count();
        let stale = renderer.render(&engine.ctx, &scene, &desc(false, all), &target);
        assert!(matches!(stale, Err(GpuError::InvalidInput(_))), "{stale:?}");
        let (report, _, after) =
            frame(&mut engine, &mut renderer, &scene, &few, ShadingMode::Lists).unwrap();
        assert_eq!(report.lights, 8);
        assert_eq!(after, before);
    }

    #[test]
    fn an_engines_own_device_keeps_the_loop_guard() {
        let Some(headless) = GpuContext::headless_for_tests() else {
            return;
        };
        let mut engine = Engine::new().unwrap();
        assert_eq!(
            engine.ctx.shader_loop_limit(),
            headless.shader_loop_limit(),
            "{} vs {}",
            engine.ctx.describe(),
            headless.describe()
        );
        let Some(max) = engine.ctx.max_lights_per_pixel(ShadingMode::BruteForce, 24) else {
            eprintln!("{}: shader loops are not limited", engine.ctx.describe());
            return;
        };
        // One light more than a brute-force pixel may loop over is refused, before any upload.
        let mut renderer = Renderer::new(&engine.ctx, FORMAT);
        let scene = renderer.upload_scene(&engine.ctx, &floor()).unwrap();
        let lights = Lights::rows(max as usize + 1);
        match frame(
            &mut engine,
            &mut renderer,
            &scene,
            &lights,
            ShadingMode::BruteForce,
        ) {
            Err(GpuError::ShaderLoopLimit { lights, .. }) => assert_eq!(lights, max + 1),
            other => panic!("expected a refusal, got {:?}", other.map(|r| r.0.lights)),
        }
    }
}
