//! A frame whose light lists need more device memory than there is is an error, not a panic, and
//! the renderer recovers from it: wgpu reports running out of memory when a buffer is made, and
//! without an error scope around it that report panics (`myriad stress` under an address-space
//! limit died with exit 101 there, review).
//!
//! On llvmpipe device memory is the process's, so the test lowers its own address-space limit
//! (`prlimit`, util-linux) just before the frame: the 128 MB indices buffer (llvmpipe's largest
//! storage binding) cannot be made in the 48 MB left — less than one block of the Vulkan
//! allocator, which grows by blocks of 64 MB or more — while the frame's small buffers come out
//! of blocks the frames before the limit made. The same limit runs the host out of memory for a
//! frame's staging copy, which the belt maps before the GPU copies it. Its own test binary, since
//! the limit holds for the whole process, and the tests take turns ([`LIMIT`]): each one's
//! allocations must happen under its own limit, which a guard lifts again even when the test
//! fails ([`AddressLimit`]).
//!
//! On a GPU with memory of its own an address-space limit does not run the device out of memory:
//! these tests run on a software adapter (CI's llvmpipe) and say so and return elsewhere.

use myriad::assignment::Method;
use myriad::gpu::{
    ClusterLists, FrameDesc, GBuffer, GpuContext, GpuError, HeadlessTarget, TextureRgba8,
};
use myriad::render::{RenderScene, Shading, Viewer};
use std::process::Command;
use std::sync::{Mutex, MutexGuard};

/// Held by a test for its whole run: the address-space limit is the process's.
static LIMIT: Mutex<()> = Mutex::new(());

/// Headroom left above the address space in use when a limit is set: every small buffer and
/// staging chunk of a frame fits in it, a 100 MB one does not.
const HEADROOM: u64 = 48 << 20;

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

/// This process's soft address-space limit, as `/proc/self/limits` gives it ("unlimited" or
/// bytes).
fn soft_address_limit() -> String {
    let limits = std::fs::read_to_string("/proc/self/limits").expect("a Linux /proc");
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))
        .expect("Max address space in /proc/self/limits");
    line["Max address space".len()..]
        .split_whitespace()
        .next()
        .expect("a soft limit")
        .to_string()
}

/// Sets this process's soft address-space limit, leaving the hard one as it is.
fn set_soft_address_limit(soft: &str) {
    let status = Command::new("prlimit")
        .arg("--pid")
        .arg(std::process::id().to_string())
        .arg(format!("--as={soft}:"))
        .status()
        .expect("prlimit (util-linux) runs");
    assert!(status.success(), "prlimit --as={soft}: {status}");
}

/// The address space limited to what is in use plus [`HEADROOM`] (or another headroom) while it
/// lives; the limit
/// before it is restored on drop, also when the test panics inside.
struct AddressLimit {
    before: String,
}

impl AddressLimit {
    fn new(ctx: &GpuContext) -> Self {
        Self::with_headroom(ctx, HEADROOM)
    }

    /// First waits for the device: wgpu frees dropped buffers (an earlier test's hundreds of
    /// megabytes) only when it is polled, and freed inside the window they would widen it.
    fn with_headroom(ctx: &GpuContext, headroom: u64) -> Self {
        ctx.wait_idle().expect("the device is idle");
        let before = soft_address_limit();
        set_soft_address_limit(&(address_space() + headroom).to_string());
        Self { before }
    }
}

impl Drop for AddressLimit {
    fn drop(&mut self) {
        set_soft_address_limit(&self.before);
    }
}

/// The shared device when it is a software adapter, whose device memory is this process's; `None`,
/// said on stderr, on a GPU with memory of its own (or without an adapter).
fn software_device() -> Option<GpuContext> {
    let ctx = GpuContext::headless_for_tests()?;
    if ctx.adapter_info.device_type != myriad::gpu::wgpu::DeviceType::Cpu {
        eprintln!(
            "not run on {}: an address-space limit runs only a software adapter out of memory",
            ctx.describe()
        );
        return None;
    }
    Some(ctx)
}

/// This test's turn ([`LIMIT`], held until the guard drops), then the default scene with `lights`
/// lights at 64×32 on the software device; `None` without one.
fn atrium_viewer(lights: usize) -> Option<(MutexGuard<'static, ()>, RenderScene, Viewer)> {
    let turn = LIMIT.lock().unwrap_or_else(|e| e.into_inner());
    let ctx = software_device()?;
    let scene = RenderScene::default_scene(lights, 64, 32).unwrap();
    let viewer = Viewer::new(ctx, &scene).unwrap();
    Some((turn, scene, viewer))
}

#[test]
fn lists_past_the_device_memory_are_an_error_and_the_renderer_recovers() {
    let lights = 5_400;
    let Some((_turn, scene, mut viewer)) = atrium_viewer(lights) else {
        return;
    };
    viewer
        .frame(&scene, Shading::Clustered, Method::Refined, false)
        .unwrap();
    // Every cluster lists every light: 4608 × 5400 indices, 99.5 MB (a 128 MB buffer).
    let huge = FullLists::new(scene.grid.cluster_count(), lights as u32);
    let frame = FrameDesc::clustered(
        &scene.camera,
        &scene.grid,
        myriad::render::light_columns(&scene.lights),
        huge.lists(),
    );
    let Viewer {
        ctx,
        renderer,
        scene: geometry,
        target,
        ..
    } = &mut viewer;
    let limit = AddressLimit::new(ctx);
    let refused = renderer.render(ctx, geometry, &frame, &target.view);
    drop(limit);
    match refused {
        Err(GpuError::OutOfMemory(message)) => {
            assert!(message.contains("the light indices buffer"), "{message}");
        }
        other => panic!("want an out-of-memory error, got {:?}", other.map(|_| ())),
    }
    // Nothing of that frame is kept: no lists to read back, a frame that keeps the lists is
    // refused, and one that uploads them again renders.
    assert_eq!(renderer.read_back_lists(ctx).unwrap(), None);
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

/// Every cluster lists lights `0..per_cluster`: the largest lists a frame can hold.
struct FullLists {
    offsets: Vec<u32>,
    counts: Vec<u32>,
    indices: Vec<u32>,
}

impl FullLists {
    fn new(clusters: usize, per_cluster: u32) -> Self {
        Self {
            counts: vec![per_cluster; clusters],
            offsets: (0..clusters as u32).map(|c| c * per_cluster).collect(),
            indices: (0..clusters).flat_map(|_| 0..per_cluster).collect(),
        }
    }

    fn lists(&self) -> ClusterLists<'_> {
        ClusterLists {
            offsets: &self.offsets,
            counts: &self.counts,
            indices: &self.indices,
        }
    }
}

/// The device buffer already holds the frame, but its staging copy needs a new chunk of host
/// memory the process does not have: an error, not a panic inside wgpu's `StagingBelt` (it
/// was, review), and the next frame renders.
#[test]
fn staging_past_the_host_memory_is_an_error_and_the_renderer_recovers() {
    let lights = 6_500;
    let Some((_turn, scene, mut viewer)) = atrium_viewer(lights) else {
        return;
    };
    let clusters = scene.grid.cluster_count();
    // 4608 × 5400 indices (99.5 MB) grow the indices buffer to 128 MB and stage through a
    // 99.5 MB chunk; 4608 × 6500 (119.8 MB) then fit the buffer but no chunk the belt has.
    let first = FullLists::new(clusters, 5_400);
    let second = FullLists::new(clusters, lights as u32);
    let columns = myriad::render::light_columns(&scene.lights);
    let Viewer {
        ctx,
        renderer,
        scene: geometry,
        target,
        ..
    } = &mut viewer;
    let frame = |lists| FrameDesc::clustered(&scene.camera, &scene.grid, columns, lists);
    renderer
        .render(ctx, geometry, &frame(first.lists()), &target.view)
        .unwrap();
    ctx.wait_idle().unwrap();
    let limit = AddressLimit::new(ctx);
    let refused = renderer.render(ctx, geometry, &frame(second.lists()), &target.view);
    drop(limit);
    match refused {
        Err(GpuError::OutOfMemory(message)) => {
            assert!(
                message.contains("the staging copy of the light indices buffer"),
                "{message}"
            );
        }
        other => panic!("want an out-of-memory error, got {:?}", other.map(|_| ())),
    }
    let again = renderer
        .render(ctx, geometry, &frame(second.lists()), &target.view)
        .unwrap();
    assert_eq!(again.lights, lights);
}

/// Geometry, textures and targets larger than the memory left are errors too, and nothing the
/// renderer holds is lost: wgpu's `create_buffer_init` and `create_texture_with_data` panicked
/// on the mapped buffer or the texture they could not make (an engine loading a scene too big
/// for its GPU lost the process).
#[test]
fn scenes_and_targets_past_the_memory_are_errors() {
    let Some((_turn, scene, viewer)) = atrium_viewer(10) else {
        return;
    };
    // 3.2 M vertices (102 MB) and a 4096² texture (67 MB), each alone past the headroom.
    let mut huge_vertices = scene.geometry.clone();
    let vertex = huge_vertices.vertices[0];
    huge_vertices.vertices.resize(3_200_000, vertex);
    let mut huge_texture = scene.geometry.clone();
    let side = 4096;
    huge_texture.textures.push(TextureRgba8 {
        width: side,
        height: side,
        pixels: vec![128; (side * side * 4) as usize],
    });
    let (ctx, renderer) = (&viewer.ctx, &viewer.renderer);
    let limit = AddressLimit::new(ctx);
    let vertices = renderer.upload_scene(ctx, &huge_vertices).map(|_| ());
    let texture = renderer.upload_scene(ctx, &huge_texture).map(|_| ());
    let gbuffer = GBuffer::new(&ctx.device, side, side).map(|_| ());
    let target = HeadlessTarget::new(&ctx.device, 8192, 8192).map(|_| ());
    drop(limit);
    // Room for the 102 MB vertex buffer but not for its staging copy as well: wgpu's own
    // `create_buffer_init` staged through a buffer of its own whose failure lost the device
    // (every later call silently did nothing); the renderer's staging copy is an error. How
    // much room that takes depends on the blocks the allocator already holds (a freed buffer's
    // block may be reused without growing the address space), so the room is swept: every
    // attempt is made or refused as out of memory, and one is refused for the staging copy.
    let mut staged = Vec::new();
    for room in (112..=272).step_by(16) {
        let limit = AddressLimit::with_headroom(ctx, room << 20);
        let made = renderer.upload_scene(ctx, &huge_vertices).map(|_| ());
        drop(limit);
        staged.push((room, made));
    }
    let staging_refused = |m: &str| m.contains("the staging copy of the scene vertices buffer");
    for (room, made) in &staged {
        assert!(
            matches!(made, Ok(()) | Err(GpuError::OutOfMemory(_))),
            "{room} MiB of room: {made:?}"
        );
    }
    assert!(
        staged
            .iter()
            .any(|(_, made)| matches!(made, Err(GpuError::OutOfMemory(m)) if staging_refused(m))),
        "no room between 112 and 272 MiB refused the staging copy alone: {staged:?}"
    );
    for (refused, what) in [
        (vertices, "the scene vertices buffer"),
        (texture, "a 4096x4096 base-colour texture"),
        (gbuffer, "the gbuffer"),
        (target, "the headless target texture"),
    ] {
        match refused {
            Err(GpuError::OutOfMemory(message)) => {
                assert!(message.contains(what), "want {what:?} in {message:?}")
            }
            other => panic!("{what}: want an out-of-memory error, got {other:?}"),
        }
    }
    // With the memory back, the same uploads succeed and the viewer still renders.
    let uploaded = renderer.upload_scene(ctx, &huge_vertices).unwrap();
    assert_eq!(uploaded.triangle_count(), scene.geometry.indices.len() / 3);
    renderer.upload_scene(ctx, &huge_texture).unwrap();
    let mut viewer = viewer;
    viewer
        .frame(&scene, Shading::Clustered, Method::Refined, false)
        .unwrap();
}
