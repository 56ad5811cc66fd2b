//! `refined` and `cone` drop the corner clusters of `binary`'s boxes that a point light's ball
//! never reaches: their lists are subsets of `binary`'s, still cover the oracle, and hold far
//! fewer false positives on big lights close to the camera (the `paper` scene's case, where
//! `binary` lists about half again the exact pairs). The conservative suites cannot see a
//! tightening step that stops cutting; this test can.

mod common;

use common::*;
use myriad_assignment::{Assigner, LightLists, Method};
use rand::{Rng, SeedableRng};

#[test]
fn refined_and_cone_cut_binarys_boxes_and_stay_conservative() {
    let scene = make_scene(&SceneParams {
        seed: 5,
        // Log slices, as `paper`'s grid: thin near the camera, where the big lights are.
        slicing: 1,
        ..SceneParams::WIDE
    });
    let (right, up, forward) = view_basis(&scene.camera);
    let t = scene.camera.tan_half_fov();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(77);
    let mut lights = Columns::default();
    for _ in 0..600 {
        // Inside the view, 1.5–30 m deep, radii 0.5–3 m: several tiles and slices each.
        let depth = rng.random_range(1.5f32..30.0);
        let sx = rng.random_range(-1.0f32..1.0) * t.x * depth;
        let sy = rng.random_range(-1.0f32..1.0) * t.y * depth;
        let centre = scene.camera.position + right * sx + up * sy + forward * depth;
        lights.push(centre, rng.random_range(0.5f32..3.0));
    }
    let truth = brute_force(&lights, false, &scene.camera, &scene.grid);
    let lists_of = |method: Method| {
        let mut lists = LightLists::new();
        Assigner::new().assign(
            method,
            &lights.input(false),
            &scene.camera,
            &scene.grid,
            &mut lists,
        );
        lists
    };
    let binary = lists_of(Method::Binary);
    let (exact, binary_extra) = assert_conservative("binary", &binary, &truth, "big lights");
    let binary_fp = binary_extra as f64 / exact as f64;
    assert!(
        binary_fp > 0.3,
        "the scene must leave binary's box corners to cut: {binary_fp:.3}"
    );
    for (method, limit) in [(Method::Refined, 0.12), (Method::Cone, 0.12)] {
        let lists = lists_of(method);
        let (_, extra) = assert_conservative(method.name(), &lists, &truth, "big lights");
        for c in 0..truth.len() {
            let wide = binary.lights_of(c);
            for light in lists.lights_of(c) {
                assert!(
                    wide.binary_search(light).is_ok(),
                    "{method}: light {light} in cluster {c}, outside binary's box"
                );
            }
        }
        let fp = extra as f64 / exact as f64;
        assert!(
            fp <= limit,
            "{method}: false-positive ratio {fp:.3} (binary {binary_fp:.3}, {exact} exact pairs)"
        );
    }
}
