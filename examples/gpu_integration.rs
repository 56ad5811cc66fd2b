//! Using myriad's renderer from an engine: the engine owns the wgpu device, queue and target
//! texture; it hands the renderer flat geometry once, and per frame its light columns and the
//! CSR lists from `myriad-assignment`. Only `myriad-cluster-math`, `myriad-assignment` and
//! `myriad-gpu` are used, as an engine depending on just those would.
//!
//! Run with `cargo run --release --example gpu_integration` (needs a Vulkan, Metal or DX12
//! adapter; Mesa's software Vulkan works).

use myriad_assignment::{Assigner, LightInput, LightLists, Method};
use myriad_cluster_math::glam::{UVec3, Vec3};
use myriad_cluster_math::{Camera, ClusterGrid, DepthSlicing};
use myriad_gpu::layout::{MaterialUniforms, Vertex};
use myriad_gpu::wgpu;
use myriad_gpu::{
    Blend, ClusterLists, Draw, FrameDesc, GpuContext, LightColumns, MaterialDesc, Renderer,
    SceneGeometry, ShadingMode,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The engine's own device (here a headless one) and its own render target.
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&Default::default()))?;
    let (width, height) = (320, 180);
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let target = device.create_texture(&wgpu::TextureDescriptor {
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
        view_formats: &[],
    });
    let view = target.create_view(&Default::default());

    // Hand the renderer the engine's device, and its geometry once: a 40 m floor.
    let ctx = GpuContext::from_device(device, queue);
    let mut renderer = Renderer::new(&ctx, format);
    let up = [0.0, 1.0, 0.0];
    let corner = |x: f32, z: f32| Vertex {
        position: [x, 0.0, z],
        normal: up,
        uv: [0.0, 0.0],
    };
    let geometry = SceneGeometry {
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
    };
    let scene = renderer.upload_scene(&ctx, &geometry)?;

    // The engine's lights as SoA columns: a row of 64 coloured lights above the floor.
    let n = 64;
    let x: Vec<f32> = (0..n).map(|i| (i % 8) as f32 * 4.0 - 14.0).collect();
    let y = vec![0.8; n];
    let z: Vec<f32> = (0..n).map(|i| -((i / 8) as f32) * 4.0 - 2.0).collect();
    let radius = vec![3.0; n];
    let (r, g, b): (Vec<f32>, Vec<f32>, Vec<f32>) = (0..n)
        .map(|i| {
            (
                (i % 3 == 0) as u8 as f32,
                (i % 3 == 1) as u8 as f32,
                (i % 3 == 2) as u8 as f32,
            )
        })
        .fold(
            (vec![], vec![], vec![]),
            |(mut r, mut g, mut b), (a, c, d)| {
                r.push(a);
                g.push(c);
                b.push(d);
                (r, g, b)
            },
        );
    let intensity = vec![4.0; n];

    let camera = Camera::new(
        Vec3::new(0.0, 6.0, 6.0),
        Vec3::new(0.0, 0.0, -14.0),
        Vec3::Y,
        60.0,
        width,
        height,
        0.1,
        60.0,
    );
    let grid = ClusterGrid::new(
        UVec3::new(16, 9, 24),
        DepthSlicing::Log,
        camera.near,
        camera.far,
    );

    // Per frame: assign on the CPU, then render with the lists.
    let mut assigner = Assigner::new();
    let mut lists = LightLists::new();
    let stats = assigner.assign(
        Method::Refined,
        &LightInput::points(&x, &y, &z, &radius),
        &camera,
        &grid,
        &mut lists,
    );
    let report = renderer.render(
        &ctx,
        &scene,
        &FrameDesc {
            camera: &camera,
            grid: &grid,
            mode: ShadingMode::Lists,
            heat_map: false,
            lights: Some(LightColumns {
                x: &x,
                y: &y,
                z: &z,
                radius: &radius,
                r: &r,
                g: &g,
                b: &b,
                intensity: &intensity,
                spot: None,
            }),
            lists: Some(ClusterLists {
                offsets: &lists.offsets,
                counts: &lists.counts,
                indices: &lists.indices,
            }),
            settings: Default::default(),
        },
        &view,
    )?;
    let pixels = myriad_gpu::read_rgba8(&ctx, &target)?;
    let lit = pixels
        .chunks(4)
        .filter(|p| p[0].max(p[1]).max(p[2]) > 80)
        .count();
    println!(
        "{} lights, {} pairs, {} bytes uploaded; {lit} of {} pixels lit",
        n,
        stats.pairs,
        report.upload_bytes,
        width * height
    );
    Ok(())
}
