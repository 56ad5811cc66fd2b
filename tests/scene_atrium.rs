//! The shipped default scene, `assets/atrium.glb`: it is exactly what the generator makes
//! (so the asset cannot drift from the code), the loader reads it back to the generated model,
//! and `myriad atrium` writes the same bytes.
//!
//! If the byte comparison fails after a deliberate change to `crates/scene/src/atrium.rs`,
//! regenerate the asset with `cargo run --release -- atrium --out assets/atrium.glb`.

use myriad::scene::{ATRIUM_FILE, AlphaMode, LoadOptions, Model, atrium, atrium_glb};
use std::path::{Path, PathBuf};
use std::process::Command;

fn shipped() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(ATRIUM_FILE)
}

#[test]
fn shipped_asset_equals_the_generator_byte_for_byte() {
    let committed = std::fs::read(shipped()).expect("assets/atrium.glb is part of the repository");
    let generated = atrium_glb().unwrap();
    assert!(
        committed == generated,
        "assets/atrium.glb ({} bytes) differs from the generator's output ({} bytes); \
         regenerate it with `cargo run --release -- atrium --out assets/atrium.glb`",
        committed.len(),
        generated.len()
    );
    assert!(committed.len() < 1 << 20, "{} bytes", committed.len());
}

#[test]
fn loader_reads_back_the_generated_model() {
    let loaded = Model::load(shipped(), &LoadOptions::default()).unwrap();
    let made = atrium();
    assert_eq!(loaded.meshes, made.meshes);
    assert_eq!(loaded.materials, made.materials);
    assert_eq!(loaded.instances, made.instances);
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    assert_eq!(loaded.bounds(), made.bounds());
    assert_eq!(loaded.triangle_count(), made.triangle_count());
    assert_eq!(loaded.cameras.len(), made.cameras.len());
    for (a, b) in loaded.cameras.iter().zip(&made.cameras) {
        assert_eq!(
            (&a.name, a.node, a.position, a.projection),
            (&b.name, b.node, b.position, b.projection)
        );
        assert!((a.forward - b.forward).length() < 1e-6, "{}", a.name);
        assert!((a.up - b.up).length() < 1e-6, "{}", a.name);
    }
    assert_eq!(loaded.lights.len(), made.lights.len());
    for i in 0..made.lights.len() {
        let (a, b) = (loaded.lights.get(i), made.lights.get(i));
        assert_eq!(
            (a.position, a.radius, a.color, a.intensity),
            (b.position, b.radius, b.color, b.intensity)
        );
        assert_eq!(a.spot.is_some(), b.spot.is_some());
        if let (Some(x), Some(y)) = (a.spot, b.spot) {
            assert!((x.direction - y.direction).length() < 1e-6);
            assert_eq!(x.angle, y.angle);
        }
    }
    assert_eq!(loaded.placed_lights, made.placed_lights);
    // What the issue asks of the default scene.
    let size = loaded.bounds().size();
    assert!(
        (28.0..=32.0).contains(&size.x)
            && (12.0..=14.0).contains(&size.y)
            && (14.0..=16.0).contains(&size.z),
        "{size}"
    );
    let blended = loaded
        .materials
        .iter()
        .filter(|m| m.alpha_mode == AlphaMode::Blend)
        .count();
    assert!(blended >= 2);
    assert!(loaded.materials.len() >= 5);
    assert!(loaded.cameras.len() >= 3);
}

#[test]
fn the_atrium_command_writes_the_same_bytes() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("scene_atrium");
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("atrium.glb");
    let status = Command::new(env!("CARGO_BIN_EXE_myriad"))
        .args(["atrium".as_ref(), "--out".as_ref(), out.as_os_str()])
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    assert!(String::from_utf8_lossy(&status.stdout).starts_with("wrote "));
    assert_eq!(
        std::fs::read(&out).unwrap(),
        std::fs::read(shipped()).unwrap()
    );
}
