//! The WGSL `cluster_of_pixel` (run in a compute pass) equals `ClusterGrid::cluster_of_pixel`
//! for every sample: every tile's first and last pixel, every slice edge and its neighbouring
//! f32 values, depths outside the range, and random samples, over several grids and resolutions.

use glam::UVec3;
use myriad_cluster_math::{ClusterGrid, DepthSlicing};
use myriad_gpu::cluster_check::gpu_cluster_ids;
use myriad_gpu::{GpuContext, GpuError};

fn next_up(x: f32, steps: i32) -> f32 {
    let mut v = x;
    for _ in 0..steps.abs() {
        v = if steps > 0 {
            v.next_up()
        } else {
            v.next_down()
        };
    }
    v
}

fn samples(grid: &ClusterGrid, width: u32, height: u32, seed: u64) -> (Vec<[u32; 2]>, Vec<f32>) {
    let mut depths: Vec<f32> = Vec::new();
    for k in 0..=grid.dims().z {
        let e = grid.slice_start_depth(k);
        depths.extend((-3..=3).map(|s| next_up(e, s)));
    }
    depths.extend([
        0.0,
        -1.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        grid.far() * 10.0,
        f32::MIN_POSITIVE,
        f32::MAX,
    ]);
    let mut xs: Vec<u32> = Vec::new();
    for i in 0..grid.dims().x {
        let r = grid.tile_pixel_columns(i, width);
        if !r.is_empty() {
            xs.extend([r.start, r.end - 1]);
        }
    }
    let mut ys: Vec<u32> = Vec::new();
    for j in 0..grid.dims().y {
        let r = grid.tile_pixel_rows(j, height);
        if !r.is_empty() {
            ys.extend([r.start, r.end - 1]);
        }
    }
    let mut pixels = Vec::new();
    let mut out_depths = Vec::new();
    // Edge pixels × edge depths, pairing them cyclically to keep the count moderate. Every depth
    // goes out at least four times, each time with another pixel. (It was indexed `s * 7`, and
    // the list holds a multiple of seven entries: only each edge's −3 ulps and 0.0 were ever
    // sent, and three mutants of the slice search at exact edges survived: audit.)
    let n = xs.len().max(ys.len()).max(depths.len()) * 4;
    for s in 0..n {
        pixels.push([xs[s % xs.len()], ys[(s / 3) % ys.len()]]);
        out_depths.push(depths[s % depths.len()]);
    }
    for d in &depths {
        assert!(
            out_depths.iter().any(|o| o.to_bits() == d.to_bits()),
            "depth {d} is never sampled"
        );
    }
    // Random samples: a simple LCG (no dependency needed for test noise).
    let mut state = seed;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 33) as u32
    };
    for _ in 0..20_000 {
        let px = next() % width;
        let py = next() % height;
        let t = (next() as f32 / (1u32 << 31) as f32) * 1.2 - 0.1;
        let d = grid.near() + t * (grid.far() - grid.near());
        pixels.push([px, py]);
        out_depths.push(d);
    }
    (pixels, out_depths)
}

#[test]
fn gpu_cluster_index_equals_cpu() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let grids = [
        (
            UVec3::new(24, 12, 16),
            DepthSlicing::Log,
            0.1,
            100.0,
            1536,
            768,
        ),
        (
            UVec3::new(24, 12, 64),
            DepthSlicing::Log,
            0.05,
            3000.0,
            1536,
            768,
        ),
        (
            UVec3::new(16, 9, 24),
            DepthSlicing::Linear,
            1.0,
            50.0,
            1280,
            720,
        ),
        (
            UVec3::new(32, 18, 48),
            DepthSlicing::LogWithNearSlice {
                first_slice_depth: 5.0,
            },
            0.1,
            1000.0,
            1920,
            1080,
        ),
        (UVec3::new(7, 5, 3), DepthSlicing::Log, 0.3, 7.0, 641, 359),
        (
            UVec3::new(13, 11, 1),
            DepthSlicing::Linear,
            0.1,
            10.0,
            100,
            37,
        ),
        (
            UVec3::new(64, 64, 128),
            DepthSlicing::Log,
            1e-3,
            1e6,
            63,
            61,
        ),
        (UVec3::new(1, 1, 2), DepthSlicing::Log, 0.1, 0.2, 1, 1),
    ];
    for (seed, &(dims, slicing, near, far, width, height)) in grids.iter().enumerate() {
        let grid = ClusterGrid::new(dims, slicing, near, far);
        let (pixels, depths) = samples(&grid, width, height, seed as u64 + 1);
        let gpu = gpu_cluster_ids(&ctx, &grid, width, height, &pixels, &depths).unwrap();
        assert_eq!(gpu.len(), pixels.len(), "one id per sample");
        let mut slices_hit = vec![false; dims.z as usize];
        for (s, (p, d)) in pixels.iter().zip(&depths).enumerate() {
            let cpu = grid.cluster_of_pixel(p[0], p[1], *d, width, height);
            assert_eq!(
                gpu[s],
                cpu,
                "grid {dims} {slicing:?} [{near}, {far}] at {width}x{height}: pixel {p:?} depth {d:e} ({:#x})",
                d.to_bits()
            );
            slices_hit[(cpu / (dims.x * dims.y)) as usize] = true;
        }
        // The edge samples reach every slice, so every slice's mapping was compared.
        assert!(
            slices_hit.iter().all(|&hit| hit),
            "grid {dims}: slices never sampled {:?}",
            (0..dims.z)
                .filter(|&k| !slices_hit[k as usize])
                .collect::<Vec<_>>()
        );
    }
}

#[test]
fn nan_depth_maps_to_slice_zero_on_the_gpu_too() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let grid = ClusterGrid::new(UVec3::new(4, 4, 8), DepthSlicing::Log, 0.1, 100.0);
    let pixels = [[5, 5], [0, 0]];
    let depths = [f32::NAN, -f32::NAN];
    let gpu = gpu_cluster_ids(&ctx, &grid, 16, 16, &pixels, &depths).unwrap();
    for (s, p) in pixels.iter().enumerate() {
        assert_eq!(gpu[s], grid.cluster_of_pixel(p[0], p[1], depths[s], 16, 16));
    }
}

/// Targets and samples the shader's arithmetic does not cover are `InvalidInput` errors, as
/// the renderer refuses such frames: an empty target, a sample off the target, and a target
/// whose `2 · pixels · tiles` passes u32 (the last pixel of a target of one tile fewer runs).
#[test]
fn samples_off_the_target_and_targets_past_the_tile_arithmetic_are_refused() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let grid = ClusterGrid::new(UVec3::new(4, 4, 8), DepthSlicing::Log, 0.1, 100.0);
    let check = |grid: &ClusterGrid, (w, h): (u32, u32), pixel: [u32; 2]| {
        gpu_cluster_ids(&ctx, grid, w, h, &[pixel], &[5.0])
    };
    let invalid = |result: Result<Vec<u32>, GpuError>, want: &str| match result {
        Err(GpuError::InvalidInput(e)) => assert!(e.contains(want), "{e}"),
        other => panic!("want {want:?}, got {other:?}"),
    };
    invalid(check(&grid, (0, 16), [0, 0]), "need at least one pixel");
    invalid(check(&grid, (16, 0), [0, 0]), "need at least one pixel");
    invalid(
        check(&grid, (16, 16), [16, 0]),
        "[16, 0] is off the 16x16 target",
    );
    invalid(
        check(&grid, (16, 16), [0, 16]),
        "[0, 16] is off the 16x16 target",
    );
    // 2 · 2²⁰ · 2048 = 2³² passes u32; 2047 tiles do not.
    let wide = 1 << 20;
    let tiles = |x| ClusterGrid::new(UVec3::new(x, 4, 8), DepthSlicing::Log, 0.1, 100.0);
    invalid(check(&tiles(2048), (wide, 16), [0, 0]), "within u32");
    let last = wide - 1;
    let ids = check(&tiles(2047), (wide, 16), [last, 15]).unwrap();
    assert_eq!(ids, [tiles(2047).cluster_of_pixel(last, 15, 5.0, wide, 16)]);
}

/// Sample lists the check cannot run are `InvalidInput` errors, before any GPU work: pixels and
/// depths of different lengths, no samples, and more samples than one dispatch's workgroups
/// (64 a group) can take; exactly as many as that limit allows still run, one id per sample.
#[test]
fn sample_lists_of_unequal_length_none_or_past_one_dispatch_are_refused() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let grid = ClusterGrid::new(UVec3::new(4, 4, 8), DepthSlicing::Log, 0.1, 100.0);
    let invalid = |pixels: &[[u32; 2]], depths: &[f32], want: &str| match gpu_cluster_ids(
        &ctx, &grid, 16, 16, pixels, depths,
    ) {
        Err(GpuError::InvalidInput(e)) => assert!(e.contains(want), "{e}"),
        other => panic!("{} samples: {other:?}", pixels.len()),
    };
    invalid(&[[0, 0], [1, 1]], &[1.0], "2 pixels and 1 depths");
    invalid(&[[0, 0]], &[1.0, 2.0], "1 pixels and 2 depths");
    invalid(&[], &[], "0 pixels and 0 depths");
    let max_groups = ctx.device.limits().max_compute_workgroups_per_dimension as usize;
    let most = max_groups * 64;
    let pixels = vec![[3, 5]; most + 1];
    let depths = vec![50.0; most + 1];
    invalid(
        &pixels,
        &depths,
        &format!("need {} workgroups", max_groups + 1),
    );
    let ids = gpu_cluster_ids(&ctx, &grid, 16, 16, &pixels[..most], &depths[..most]).unwrap();
    let want = grid.cluster_of_pixel(3, 5, 50.0, 16, 16);
    assert_eq!(ids.len(), most);
    assert!(ids.iter().all(|&id| id == want));
}
