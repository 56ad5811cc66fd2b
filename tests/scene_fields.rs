//! Light fields and frame systems across crates: `myriad scene --gltf … --field …` writes
//! reproducible, valid scene files that the rest of the tool chain consumes, and the frame
//! systems' culling agrees with the assignment's exact oracle (a light culled by the systems
//! is never assigned to any cluster).

use myriad::assignment::{Assigner, LightLists, Method};
use myriad::scene::glam::{UVec3, Vec3};
use myriad::scene::systems::{
    Orbits, ViewLights, Visibility, animate_orbits, cull_lights, lights_to_view,
};
use myriad::scene::{
    ClusterGrid, DepthSlicing, LightField, LightPolicy, LoadOptions, Model, Placement, Scene,
    SpotRule, SurfaceSampler,
};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn myriad(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_myriad"))
        .args(args)
        .output()
        .expect("cannot run the myriad binary")
}

fn atrium_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/atrium.glb")
}

fn work_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("scene_fields")
        .join(test);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `myriad scene --gltf assets/atrium.glb` with `extra` options, writing `out`.
fn scene_from_atrium(out: &Path, extra: &[&str]) -> Scene {
    let atrium = atrium_path();
    let mut args = vec![
        "scene".as_ref(),
        "--gltf".as_ref(),
        atrium.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ];
    args.extend(extra.iter().map(std::ffi::OsStr::new));
    let o = myriad(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    Scene::load(out, LightPolicy::Strict).unwrap()
}

#[test]
fn every_field_writes_a_reproducible_valid_scene() {
    let dir = work_dir("every_field");
    let model = Model::load(atrium_path(), &LoadOptions::without_images()).unwrap();
    let main = model.camera(0, 1536, 768).unwrap();
    let bounds = model.bounds();
    for field in ["surfaces", "box", "frustum", "clumps", "sphere"] {
        let a = dir.join(format!("{field}_a.json"));
        let b = dir.join(format!("{field}_b.json"));
        let c = dir.join(format!("{field}_c.json"));
        let opts = ["--field", field, "--lights", "500", "--seed", "3"];
        let scene = scene_from_atrium(&a, &opts);
        scene_from_atrium(&b, &opts);
        scene_from_atrium(&c, &["--field", field, "--lights", "500", "--seed", "4"]);
        assert_eq!(
            std::fs::read(&a).unwrap(),
            std::fs::read(&b).unwrap(),
            "{field}"
        );
        assert_ne!(
            std::fs::read(&a).unwrap(),
            std::fs::read(&c).unwrap(),
            "{field}"
        );
        assert_eq!(scene.lights.len(), 500);
        // The camera is the model's first camera, `Main`, and the grid the default.
        assert_eq!(scene.camera, main, "{field}");
        assert_eq!(scene.grid.dims().to_array(), [24, 12, 16]);
        if field == "surfaces" || field == "box" {
            let grown = myriad::scene::Aabb::new(bounds.min - 0.2001, bounds.max + 0.2001);
            for l in scene.lights.iter() {
                assert!(grown.contains(l.position), "{field}: {}", l.position);
            }
        }
        if field == "sphere" {
            // On the sphere around the model's bounds: its centre, half their diagonal.
            let radius = 0.5 * bounds.size().length();
            for l in scene.lights.iter() {
                let off = (l.position - bounds.center()).length() - radius;
                assert!(off.abs() <= 1e-4 * radius, "{}: {off}", l.position);
            }
        }
    }
}

#[test]
fn options_choose_camera_grid_radii_and_spots() {
    let dir = work_dir("options");
    let scene = scene_from_atrium(
        &dir.join("s.json"),
        &[
            "--camera",
            "Overview",
            "--width",
            "800",
            "--height",
            "600",
            "--grid",
            "16x9x24",
            "--depth",
            "linear",
            "--cutoff",
            "0.5",
            "--intensity",
            "1..9",
            "--spots",
            "1",
            "--spot-angles",
            "30..30",
            "--lights",
            "200",
        ],
    );
    let model = Model::load(atrium_path(), &LoadOptions::without_images()).unwrap();
    let overview = model
        .camera(model.camera_index("Overview").unwrap(), 800, 600)
        .unwrap();
    assert_eq!(scene.camera, overview);
    assert_eq!(scene.grid.dims().to_array(), [16, 9, 24]);
    for l in scene.lights.iter() {
        assert!((1.0..9.0).contains(&l.intensity));
        let expected = (l.intensity * l.color.max_element() / 0.5).sqrt();
        assert!(
            (l.radius - expected).abs() <= 1e-5 * expected,
            "{} vs {expected}",
            l.radius
        );
        let cone = l.spot.expect("every light a spot");
        assert!((cone.angle.to_degrees() - 30.0).abs() < 1e-3);
    }
    // Bad values are errors naming the problem.
    let atrium = atrium_path();
    let bad = myriad(&[
        "scene".as_ref(),
        "--gltf".as_ref(),
        atrium.as_os_str(),
        "--camera".as_ref(),
        "Nope".as_ref(),
        "--out".as_ref(),
        dir.join("x.json").as_os_str(),
    ]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("no camera named \"Nope\""));
}

#[test]
fn culled_lights_are_never_assigned() {
    let model = Model::load(atrium_path(), &LoadOptions::without_images()).unwrap();
    let camera = model.camera(0, 1536, 768).unwrap();
    let grid = ClusterGrid::new(
        UVec3::new(24, 12, 16),
        DepthSlicing::Log,
        camera.near,
        camera.far,
    );
    let field = LightField::new(Placement::Surfaces {
        surfaces: SurfaceSampler::new(&model),
        offset: 0.3,
    })
    .with_spots(SpotRule {
        fraction: 0.4,
        angle_deg: [15.0, 60.0],
    });
    let mut lights = field.generate(3000, 9);
    // Half a second of orbiting about the courtyard's centre.
    let orbits = Orbits::around(Vec3::ZERO, &lights.x, &lights.z, [0.2, 1.0], 2);
    animate_orbits(&orbits, 0.5, &mut lights.x, &mut lights.z);

    let mut vis = Visibility::new();
    let visible = cull_lights(&camera, lights.slices(), &mut vis);
    assert!(visible > 300 && visible < 3000, "{visible}");
    let mut lists = LightLists::new();
    Assigner::new().assign(
        Method::Exact,
        &myriad::light_input(&lights),
        &camera,
        &grid,
        &mut lists,
    );
    let mut assigned = vec![false; lights.len()];
    for &i in &lists.indices {
        assigned[i as usize] = true;
    }
    for (i, (&assigned, &visible)) in assigned.iter().zip(&vis.mask).enumerate() {
        assert!(
            !assigned || visible,
            "light {i} was culled but touches a cluster"
        );
    }
    // The culled set is not trivially empty, and most kept lights do touch clusters.
    let kept_and_assigned = (0..lights.len())
        .filter(|&i| vis.mask[i] && assigned[i])
        .count();
    assert!(
        kept_and_assigned as f64 > 0.8 * visible as f64,
        "{kept_and_assigned} of {visible}"
    );

    // View space rows of the survivors: camera-relative positions, source indices kept.
    let mut view = ViewLights::new();
    lights_to_view(&camera, lights.slices(), Some(&vis.indices), &mut view);
    assert_eq!(view.len(), visible);
    for k in 0..view.len() {
        let i = view.source[k] as usize;
        let p = camera.view_from_world_point(lights.get(i).position);
        assert_eq!([view.x[k], view.y[k], view.z[k]], p.to_array());
    }
}

#[test]
fn model_lights_are_written_first_when_asked_for() {
    let dir = work_dir("model_lights");
    let model = Model::load(atrium_path(), &LoadOptions::without_images()).unwrap();
    let own = model.lights.len();
    assert!(own > 0 && model.lights.iter().any(|l| l.spot.is_some()));
    let with = scene_from_atrium(
        &dir.join("with.json"),
        &["--model-lights", "--lights", "20"],
    );
    let without = scene_from_atrium(&dir.join("without.json"), &["--lights", "20"]);
    assert_eq!(with.lights.len(), own + 20);
    assert_eq!(without.lights.len(), 20);
    for (written, original) in with.lights.iter().zip(model.lights.iter()) {
        assert!(
            (written.position - original.position).length()
                <= 1e-5 * (1.0 + original.position.length())
        );
        assert_eq!(written.radius, original.radius);
        assert_eq!(written.color, original.color);
        assert_eq!(written.intensity, original.intensity);
        match (written.spot, original.spot) {
            (Some(a), Some(b)) => {
                assert!((a.direction - b.direction).length() < 1e-5);
                assert!((a.angle - b.angle).abs() < 1e-6);
            }
            (None, None) => {}
            other => panic!("spot changed: {other:?}"),
        }
    }
    // The field after them is the one written without them.
    let field: Vec<Vec3> = with.lights.iter().skip(own).map(|l| l.position).collect();
    let alone: Vec<Vec3> = without.lights.iter().map(|l| l.position).collect();
    assert_eq!(field, alone);
}

#[test]
fn a_light_count_past_memory_is_refused_before_generating() {
    // Checked on the count to be written (the model's own lights plus the field's) before the
    // field is generated: generating 2³² − 1 lights would itself abort the process.
    let dir = work_dir("past_memory");
    let out_file = dir.join("s.json");
    let atrium = atrium_path();
    for extra in [&[][..], &["--model-lights"][..]] {
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "scene".as_ref(),
            "--gltf".as_ref(),
            atrium.as_os_str(),
            "--lights".as_ref(),
            "4294967295".as_ref(),
            "--out".as_ref(),
            out_file.as_os_str(),
        ];
        args.extend(extra.iter().map(std::ffi::OsStr::new));
        let o = myriad(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        assert!(
            err.contains("GiB") && err.contains("memory"),
            "{extra:?}: {err}"
        );
        assert!(!out_file.exists());
    }
}
