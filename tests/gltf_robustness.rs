//! The glTF loader never panics: it is run over every `.gltf` and `.glb` file of Debian's
//! `assimp-testmodels` package (`/usr/share/assimp/models/glTF2/`, installed by `.ci/run`) —
//! broken files (infinities, indices out of range, missing buffers, schema failures, node
//! cycles, wrong JSON types) and good ones. Each load runs under `catch_unwind`; any panic fails
//! the test, and every error must name the file it came from.
//!
//! Without the folder the test fails in CI (the `CI` environment variable is set) and is skipped
//! with a loud note elsewhere.

use myriad::scene::{LoadOptions, Model};
use std::path::{Path, PathBuf};

const MODELS: &str = "/usr/share/assimp/models/glTF2";

fn gltf_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            gltf_files(&path, out);
        } else if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
        {
            out.push(path);
        }
    }
}

#[test]
fn every_assimp_test_model_loads_or_fails_cleanly() {
    let dir = Path::new(MODELS);
    if !dir.is_dir() {
        assert!(
            std::env::var_os("CI").is_none(),
            "{MODELS} is missing: CI must install it (`apt-get install -y assimp-testmodels`, \
             see .ci/run)"
        );
        eprintln!(
            "SKIPPED: {MODELS} is missing, so the loader's robustness over broken files is NOT \
             tested here. Install it with `apt-get install -y assimp-testmodels`."
        );
        return;
    }
    let mut files = Vec::new();
    gltf_files(dir, &mut files);
    assert!(
        files.len() >= 40,
        "only {} files under {MODELS}",
        files.len()
    );

    // Quiet the default hook while probing, so a panic shows once, in our report.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut panics = Vec::new();
    let mut unnamed = Vec::new();
    let (mut loaded, mut failed) = (0, 0);
    for path in &files {
        for options in [LoadOptions::default(), LoadOptions::without_images()] {
            match std::panic::catch_unwind(|| Model::load(path, &options)) {
                Err(payload) => {
                    let message = payload
                        .downcast_ref::<String>()
                        .cloned()
                        .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                        .unwrap_or_default();
                    panics.push(format!("{}: {message}", path.display()));
                }
                Ok(Ok(model)) => {
                    loaded += 1;
                    // A loaded model keeps the loader's invariants.
                    for p in model.meshes.iter().flat_map(|m| &m.primitives) {
                        assert_eq!(p.normals.len(), p.positions.len(), "{}", path.display());
                        assert_eq!(p.indices.len() % 3, 0);
                        assert!(p.indices.iter().all(|&i| (i as usize) < p.positions.len()));
                        assert!(p.positions.iter().all(|v| v.is_finite()));
                    }
                    assert!(model.lights.problems().is_empty());
                }
                Ok(Err(e)) => {
                    failed += 1;
                    let text = e.to_string();
                    eprintln!("{text}");
                    if !text.contains(&path.display().to_string()) {
                        unnamed.push(text);
                    }
                }
            }
        }
    }
    std::panic::set_hook(hook);
    eprintln!(
        "{} files: {loaded} loads succeeded, {failed} failed with an error",
        files.len()
    );
    assert!(
        panics.is_empty(),
        "the loader panicked on:\n{}",
        panics.join("\n")
    );
    assert!(
        unnamed.is_empty(),
        "errors without the file name:\n{}",
        unnamed.join("\n")
    );
    // The set holds both good and broken files: both outcomes must occur.
    assert!(loaded > 0 && failed > 0, "{loaded} loaded, {failed} failed");
}
