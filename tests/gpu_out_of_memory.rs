//! A frame whose light lists need more device memory than there is is an error, not a panic, and
//! the renderer recovers from it: wgpu reports running out of memory when a buffer is made, and
//! without an error scope around it that report panics (`myriad stress` under an address-space
//! limit died with exit 101 there, review).
//!
//! On llvmpipe device memory is the process's, so the test lowers its own address-space limit
//! (`prlimit`, util-linux) just before the frame: the 128 MB indices buffer (llvmpipe's largest
//! storage binding) cannot be made in the 48 MB left, while everything else the frame needs can. Its own test binary, since the limit holds for the whole
//! process.

use myriad::assignment::Method;
use myriad::gpu::{ClusterLists, FrameDesc, GpuContext, GpuError};
use myriad::render::{RenderScene, Shading, Viewer};
use std::process::Command;

/// The process's address space in bytes (`VmSize`).
fn address_space() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").expect("a Linux /proc");
    let line = status
        .lines()
        .find(|l| l.starts_with("VmSize:"))
        .expect("VmSize in /proc/self/status");
    let kib: u64 = line
        .split_whitespace()
        .nth(1)
        .and_then(|n| n.parse().ok())
        .expect("VmSize in kB");
    kib * 1024
}

/// Sets this process's soft address-space limit (`None`: unlimited).
fn limit_address_space(bytes: Option<u64>) {
    let soft = bytes.map_or("unlimited".to_string(), |b| b.to_string());
    let status = Command::new("prlimit")
        .arg("--pid")
        .arg(std::process::id().to_string())
        .arg(format!("--as={soft}:unlimited"))
        .status()
        .expect("prlimit (util-linux) runs");
    assert!(status.success(), "prlimit --as={soft}: {status}");
}

#[test]
fn lists_past_the_device_memory_are_an_error_and_the_renderer_recovers() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let lights = 5_400;
    let scene = RenderScene::default_scene(lights, 64, 32).unwrap();
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    viewer
        .frame(&scene, Shading::Clustered, Method::Refined, false)
        .unwrap();
    // Every cluster lists every light: 4608 × 5400 indices, 99.5 MB (a 128 MB buffer).
    let clusters = scene.grid.cluster_count();
    let counts = vec![lights as u32; clusters];
    let offsets: Vec<u32> = (0..clusters as u32).map(|c| c * lights as u32).collect();
    let indices: Vec<u32> = (0..clusters).flat_map(|_| 0..lights as u32).collect();
    let huge = ClusterLists {
        offsets: &offsets,
        counts: &counts,
        indices: &indices,
    };
    let frame = FrameDesc::clustered(
        &scene.camera,
        &scene.grid,
        myriad::render::light_columns(&scene.lights),
        huge,
    );
    let Viewer {
        ctx,
        renderer,
        scene: geometry,
        target,
        ..
    } = &mut viewer;
    limit_address_space(Some(address_space() + (48 << 20)));
    let refused = renderer.render(ctx, geometry, &frame, &target.view);
    limit_address_space(None);
    match refused {
        Err(GpuError::OutOfMemory(message)) => {
            assert!(message.contains("the light indices buffer"), "{message}");
        }
        other => panic!("want an out-of-memory error, got {:?}", other.map(|_| ())),
    }
    // Nothing of that frame is kept: a frame that keeps the lists is refused, and one that
    // uploads them again renders.
    let mut kept = frame;
    (kept.lights, kept.lists) = (None, None);
    assert!(matches!(
        renderer.render(ctx, geometry, &kept, &target.view),
        Err(GpuError::InvalidInput(_))
    ));
    let again = renderer
        .render(ctx, geometry, &frame, &target.view)
        .unwrap();
    assert_eq!(again.lights, lights);
}
