//! The forward pass (alpha-blended geometry) shades, with the lists, the image brute force
//! shades: the point it shades is the one whose pixel and depth picked its cluster.
//!
//! It shaded the vertex position interpolated across the triangle, whose f32 rounding grows
//! with the triangle's coordinates, not with the point's distance: on a blended ground quad
//! millions of units across, seen from 1.7 above, that point sat centimetres outside the pixel's
//! cluster, and a light the (correct) list leaves out lit it under brute force — up to 183/255
//! (audit). Drawn opaque, the same scenes never differed: deferred shading rebuilds the point
//! from the pixel's ray and depth (`pixel_point` in `shaders/common/cluster.wgsl`), which the
//! forward pass now does too, from its fragment's own depth.

use myriad::assignment::Method;
use myriad::cluster_math::glam::{UVec3, Vec3};
use myriad::gpu::layout::Vertex;
use myriad::gpu::{Blend, GpuContext};
use myriad::render::{RenderScene, Shading, Viewer, blended_bounds, max_channel_difference};
use myriad::scene::{Camera, ClusterGrid, DepthSlicing, LightRecord, Lights};

/// A small deterministic generator (the test's own; no dependency for a few floats).
struct Lcg(u64);

impl Lcg {
    fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// One alpha-blended quad of half-size `half` in the plane y = 0 around the camera's foot,
/// seen from 1.7 above looking down the way `view` says, with 60 lights just above it.
fn ground_scene(half: f32, view: Vec3, seed: u64) -> RenderScene {
    let eye = Vec3::new(3.0, 1.7, 2.0);
    let camera = Camera::new(
        eye,
        eye + view.normalize(),
        Vec3::Y,
        60.0,
        128,
        64,
        0.1,
        5000.0,
    );
    // The default scene's geometry supplies a material and a draw to repurpose.
    let mut geometry = RenderScene::default_scene(0, 128, 64).unwrap().geometry;
    geometry.vertices = [(-half, -half), (half, -half), (half, half), (-half, half)]
        .iter()
        .map(|&(x, z)| Vertex {
            position: [eye.x + x, 0.0, eye.z + z],
            normal: [0.0, 1.0, 0.0],
            uv: [0.0, 0.0],
        })
        .collect();
    geometry.indices = vec![0, 2, 1, 0, 3, 2];
    geometry.draws.truncate(1);
    geometry.draws[0].first_index = 0;
    geometry.draws[0].index_count = 6;
    let material = &mut geometry.materials[geometry.draws[0].material as usize];
    material.blend = Blend::Blended;
    material.base_color_texture = None;
    material.uniforms.base_color = [0.8, 0.8, 0.8, 0.6];
    material.uniforms.alpha_cutoff = 0.0;

    let mut rng = Lcg(900 + seed);
    let mut lights = Lights::new();
    let heading = (view.x as f64).atan2(-view.z as f64);
    for _ in 0..60 {
        let distance = 10f64.powf(rng.range(0.0, 1.7));
        let angle = heading + rng.range(-0.6, 0.6);
        let position = Vec3::new(
            (eye.x as f64 + distance * angle.sin()) as f32,
            rng.range(0.02, 0.3) as f32,
            (eye.z as f64 - distance * angle.cos()) as f32,
        );
        let radius = (rng.range(0.3, 3.0) * (distance / 10.0).max(0.2)) as f32;
        lights.push(LightRecord::point(position, radius).with_intensity(50.0));
    }
    RenderScene {
        name: format!("blended ground quad {half} across, seed {seed}"),
        blended_bounds: blended_bounds(&geometry),
        geometry,
        camera,
        grid: ClusterGrid::new(UVec3::new(16, 8, 24), DepthSlicing::Log, 0.1, 5000.0),
        lights,
    }
}

/// An opaque surface whose base colour has alpha 0 is drawn: glTF ignores alpha for `OPAQUE`
/// materials, which get a cutoff of 0, and only alpha *below* the cutoff is discarded. (A
/// G-buffer pass discarding at `alpha <= cutoff` dropped such surfaces and passed every test:
/// audit.) Alpha exactly at a mask's cutoff is kept for the same reason.
#[test]
fn alpha_at_the_cutoff_is_drawn_and_below_it_is_not() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let drawn_for = |alpha: f32, cutoff: f32| {
        let mut scene = ground_scene(1e3, Vec3::new(0.0, -0.35, -1.0), 0);
        let draw = scene.geometry.draws[0].material as usize;
        let material = &mut scene.geometry.materials[draw];
        material.blend = Blend::Opaque;
        material.uniforms.base_color[3] = alpha;
        material.uniforms.alpha_cutoff = cutoff;
        scene.blended_bounds = blended_bounds(&scene.geometry);
        let mut viewer = Viewer::new(ctx.clone(), &scene).unwrap();
        viewer
            .frame(&scene, Shading::BruteForce, Method::Refined, false)
            .unwrap();
        let depth = viewer.renderer.read_depth(&viewer.ctx).unwrap().unwrap();
        depth.iter().filter(|&&d| d > 0.0).count()
    };
    let opaque = drawn_for(0.0, 0.0);
    assert!(
        opaque > 128 * 64 / 4,
        "an opaque quad of alpha 0: {opaque} pixels drawn"
    );
    assert_eq!(drawn_for(0.5, 0.5), opaque, "alpha at a mask's cutoff");
    assert_eq!(drawn_for(0.49, 0.5), 0, "alpha below a mask's cutoff");
}

#[test]
fn a_huge_blended_quad_shades_with_lists_as_with_every_light() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let mut worst = Vec::new();
    for half in [1e3f32, 1e6, 3e6] {
        for seed in 0..8u64 {
            let view = Vec3::new(0.1 * seed as f32, -0.35, -1.0);
            let scene = ground_scene(half, view, seed);
            let mut viewer = Viewer::new(ctx.clone(), &scene).unwrap();
            let [brute, clustered] = [Shading::BruteForce, Shading::Clustered].map(|shading| {
                viewer
                    .frame(&scene, shading, Method::Refined, false)
                    .unwrap();
                viewer.image().unwrap()
            });
            // The quad covers the lower part of the view and the lights light some of it.
            let lit = brute.chunks(4).filter(|p| p[0] > 60).count();
            assert!(lit > 50, "{}: {lit} lit pixels", scene.name);
            worst.push((max_channel_difference(&brute, &clustered), scene.name));
        }
    }
    let failing: Vec<_> = worst.iter().filter(|(d, _)| *d > 1).collect();
    assert!(
        failing.is_empty(),
        "clustered differs from brute force: {failing:?}"
    );
}
