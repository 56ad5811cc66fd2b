//! Tells the crate where its WGSL sources are, as `MYRIAD_SHADER_DIR`.
//!
//! The shaders live in the workspace's top-level `shaders/` (where editors, naga's CLI and the
//! design expect them). The crate reaches them through `crates/gpu/shaders`, a symlink to that
//! folder, so that `cargo package` and `cargo vendor` carry real copies and a packaged or
//! vendored crate builds on its own. A checkout without symlinks (Git for Windows' default
//! writes the link as a small text file) falls back to the top-level folder itself.

use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let beside = manifest.join("shaders");
    let dir = if beside.join("gbuffer.wgsl").is_file() {
        beside
    } else {
        manifest.join("../../shaders")
    };
    assert!(
        dir.join("gbuffer.wgsl").is_file(),
        "myriad-gpu: no WGSL sources in {} (nor beside the crate)",
        dir.display()
    );
    // A folder is scanned for changes to any file in it.
    println!("cargo::rerun-if-changed={}", dir.display());
    println!("cargo::rustc-env=MYRIAD_SHADER_DIR={}", dir.display());
}
