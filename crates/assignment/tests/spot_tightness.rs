//! Spot lights are assigned tighter than their bounding spheres, and still conservatively.

mod common;

use common::*;
use glam::{UVec3, Vec3};
use myriad_assignment::{Assigner, LightLists, Method};
use myriad_cluster_math::{SpotCone, spot_bounding_sphere};

#[test]
fn spot_lists_are_tighter_than_bounding_spheres_and_cover_the_oracle() {
    let scene = make_scene(&SceneParams {
        seed: 21,
        fov_deg: 70.0,
        aspect: 16.0 / 9.0,
        near: 0.1,
        far_ratio: 400.0,
        eye_scale: 0.0,
        dims: UVec3::new(16, 9, 16),
        slicing: 1,
        lights: 0,
        spots: true,
    });
    // Narrow and medium spots at moderate distance, pointing every way.
    let mut rng_dir = 0u32;
    let mut spots = Columns::default();
    let mut spheres = Columns::default();
    for i in 0..400 {
        let f = i as f32;
        let p = Vec3::new(
            (f * 0.71).sin() * 8.0,
            (f * 0.37).cos() * 4.0,
            -3.0 - (f * 0.13) % 25.0,
        );
        rng_dir = rng_dir.wrapping_mul(1664525).wrapping_add(1013904223);
        let dir = Vec3::new(
            (f * 1.3).sin(),
            (f * 0.7).cos(),
            ((rng_dir >> 8) as f32 / 16_777_216.0) * 2.0 - 1.0,
        )
        .normalize();
        let angle = 0.1 + (i % 7) as f32 * 0.2; // 0.1 .. 1.3 rad
        let range = 2.0 + (i % 5) as f32;
        spots.push_spot(p, range, dir, angle);
        let (c, r) = spot_bounding_sphere(
            p,
            range,
            SpotCone {
                direction: dir,
                angle,
            },
        );
        spheres.push(c, r);
    }
    let truth = brute_force(&spots, true, &scene.camera, &scene.grid);
    for method in [Method::Binary, Method::Refined, Method::Cone] {
        let mut with_cones = LightLists::new();
        let mut as_spheres = LightLists::new();
        let a = Assigner::new().assign(
            method,
            &spots.input(true),
            &scene.camera,
            &scene.grid,
            &mut with_cones,
        );
        let b = Assigner::new().assign(
            method,
            &spheres.input(false),
            &scene.camera,
            &scene.grid,
            &mut as_spheres,
        );
        assert_conservative(method.name(), &with_cones, &truth, "spots");
        // The cone test removes a good share of the bounding spheres' clusters.
        assert!(
            (a.pairs as f64) < 0.8 * b.pairs as f64,
            "{method}: {} pairs with cones vs {} as bounding spheres",
            a.pairs,
            b.pairs
        );
    }
}
