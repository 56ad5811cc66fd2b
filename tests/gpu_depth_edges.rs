//! The active-cluster skip reads the depth prepass back and marks, on the CPU, the clusters the
//! GPU's shading will look up. The GPU turns each stored depth into view depth with its own f32
//! rounding (`view_depth_from_ndc_depth`, free to fuse or reorder; within 1e-6 of the exact
//! depth either way), so a pixel right at a slice
//! edge may land in the other slice there: `mark_active` marks both sides within a band
//! (`EDGE_TOLERANCE`, `src/render/depth_buffer.rs`). This test runs the GPU's own conversion and
//! cluster lookup (the check compute pass, stored-depth mode) over stored depths at and around
//! every slice edge, ±64 f32 steps, plus random ones, for several cameras and slicings, and
//! requires every cluster the GPU picks to be marked. A miss here is a light the skip would
//! drop from that pixel. (On llvmpipe the GPU picks the CPU's cluster for every sample, so
//! there the band is not needed; the test is for the adapters that round differently.)

use myriad::assignment::ActiveClusters;
use myriad::cluster_math::glam::{UVec3, Vec3};
use myriad::gpu::GpuContext;
use myriad::gpu::cluster_check::{SampleDepths, gpu_cluster_ids_of};
use myriad::render::mark_active;
use myriad::scene::{Camera, ClusterGrid, DepthSlicing};

/// Stored depth of view depth `d` (the projection the G-buffer pass writes: reversed Z).
fn stored(camera: &Camera, d: f64) -> f32 {
    camera.ndc_depth_from_view_depth(d) as f32
}

/// Stored depths at every slice edge and the 64 f32 values either side, then `random` more.
fn samples(camera: &Camera, grid: &ClusterGrid, random: usize) -> Vec<f32> {
    let mut depths = Vec::new();
    for k in 0..=grid.dims().z {
        let edge = stored(camera, grid.slice_start_depth(k) as f64);
        let (mut up, mut down) = (edge, edge);
        depths.push(edge);
        for _ in 0..64 {
            up = up.next_up();
            down = down.next_down();
            depths.extend([up, down]);
        }
    }
    // Random view depths, log-uniform over the camera's range (with an infinite far plane, to a
    // hundred times the grid's: beyond it, pixels clamp to the last slice).
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let near = camera.near as f64;
    let far = if camera.far.is_finite() {
        camera.far as f64
    } else {
        grid.far() as f64 * 100.0
    };
    for _ in 0..random {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1);
        let t = (state >> 11) as f64 / (1u64 << 53) as f64;
        depths.push(stored(camera, near * (far / near).powf(t)));
    }
    // Drawn pixels only: 0 is the far plane and the background, above 1 is before the near plane.
    depths.retain(|&d| d > 0.0 && d <= 1.0);
    depths
}

#[test]
fn every_cluster_the_gpu_shades_from_a_depth_buffer_is_marked_active() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    // (camera near, camera far, slicing, slices); the grid spans the camera's range, or
    // [near, 1000] where the far plane is infinite.
    let views = [
        (0.1, 100.0, DepthSlicing::Log, 16),
        (0.1, f32::INFINITY, DepthSlicing::Log, 32),
        (1e-6, f32::INFINITY, DepthSlicing::Linear, 16),
        (0.1, 100.0, DepthSlicing::Linear, 64),
        (0.01, 10_000.0, DepthSlicing::Log, 64),
        (1.0, 1.0e6, DepthSlicing::Log, 32),
        (
            0.05,
            500.0,
            DepthSlicing::LogWithNearSlice {
                first_slice_depth: 5.0,
            },
            24,
        ),
    ];
    let mut differing_from_cpu = 0;
    for (near, far, slicing, z) in views {
        let width = 128;
        let probe = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, width, 1, near, far);
        let grid_far = if far.is_finite() { far } else { 1000.0 };
        let grid = ClusterGrid::new(UVec3::new(8, 4, z), slicing, near, grid_far);
        let depths = samples(&probe, &grid, 20_000);
        // The samples as a depth buffer, row by row (the last row padded with background).
        let height = depths.len().div_ceil(width as usize) as u32;
        let camera = Camera::new(
            Vec3::ZERO,
            Vec3::NEG_Z,
            Vec3::Y,
            60.0,
            width,
            height,
            near,
            far,
        );
        let mut buffer = depths.clone();
        buffer.resize((width * height) as usize, 0.0);
        let pixels: Vec<[u32; 2]> = (0..depths.len() as u32)
            .map(|i| [i % width, i / width])
            .collect();
        let stored_depths = SampleDepths::Stored {
            depths: &depths,
            camera: &camera,
        };
        let gpu = gpu_cluster_ids_of(&ctx, &grid, width, height, &pixels, stored_depths).unwrap();
        let mut mask = ActiveClusters::new(&grid);
        mark_active(&mut mask, &grid, &camera, &buffer, &[]);
        for (i, (&id, &d)) in gpu.iter().zip(&depths).enumerate() {
            let [px, py] = pixels[i];
            let cpu =
                grid.cluster_of_pixel(px, py, camera.view_depth_from_ndc_depth(d), width, height);
            differing_from_cpu += usize::from(cpu != id);
            assert!(
                mask.is_active(id),
                "near {near} far {far} {slicing:?} z {z}: stored depth {d:e} at pixel {px},{py} \
                 is shaded from cluster {id} on the GPU (CPU: {cpu}), which is not marked active"
            );
        }
    }
    // How often the GPU's rounding picks another cluster than the CPU's (the band's reason).
    eprintln!("{differing_from_cpu} samples land in another cluster on the GPU than on the CPU");
}
