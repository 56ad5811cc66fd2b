//! Exhaustive consistency of the grid mappings: pixel → tile, depth → slice, slice → depth range and
//! (pixel, depth) → cluster id, over every slice edge (±1 and ±2 ulp), every pixel of every
//! resolution 1..=64 × 1..=64, and a few large resolutions.

use glam::{UVec3, Vec3};
use myriad_cluster_math::{Camera, ClusterGrid, DepthSlicing};

fn grids() -> Vec<ClusterGrid> {
    let mut out = Vec::new();
    for (near, far) in [(0.1f32, 100.0f32), (1e-4, 1e7), (5.0, 5.001), (0.5, 3.0)] {
        for z in [1u32, 2, 3, 16, 24, 64, 128] {
            let first = near + (far - near) * 0.01;
            for slicing in [
                DepthSlicing::Linear,
                DepthSlicing::Log,
                DepthSlicing::LogWithNearSlice {
                    first_slice_depth: first,
                },
            ] {
                if let DepthSlicing::LogWithNearSlice { first_slice_depth } = slicing
                    && !(first_slice_depth > near && first_slice_depth < far)
                {
                    continue;
                }
                out.push(ClusterGrid::new(UVec3::new(24, 12, z), slicing, near, far));
            }
        }
    }
    out
}

/// Checks `edge(s) <= d < edge(s + 1)` for depths inside the range, and the clamping outside it.
fn check_depth(grid: &ClusterGrid, d: f32) {
    let s = grid.slice_of_depth(d);
    let z = grid.dims().z;
    assert!(s < z);
    if d >= grid.near() && d < grid.far() {
        let (lo, hi) = grid.slice_depth_range(s);
        assert!(
            lo <= d && d < hi,
            "{grid:?}: depth {d} mapped to slice {s} = [{lo}, {hi})"
        );
        // Consistent with a plain binary search over the edge table.
        let mut edges = Vec::new();
        grid.fill_slice_edges(&mut edges);
        let by_search = edges.partition_point(|&e| e <= d) as u32 - 1;
        assert_eq!(s, by_search.min(z - 1), "{grid:?} depth {d}");
    } else if !(d >= grid.near()) {
        assert_eq!(s, 0, "{grid:?}: depth {d} below near must clamp to 0");
    } else {
        assert_eq!(
            s,
            z - 1,
            "{grid:?}: depth {d} at/after far must clamp to Z-1"
        );
    }
}

#[test]
fn every_slice_edge_and_its_neighbours_map_consistently() {
    for grid in grids() {
        let z = grid.dims().z;
        let mut edges = Vec::new();
        grid.fill_slice_edges(&mut edges);
        assert_eq!(edges.len() as u32, z + 1);
        assert_eq!(edges[0], grid.near());
        assert_eq!(edges[z as usize], grid.far());
        assert!(
            edges.windows(2).all(|w| w[0] <= w[1]),
            "{grid:?}: {edges:?}"
        );
        for k in 0..=z {
            let e = grid.slice_start_depth(k);
            let mut d = e;
            let mut below = e;
            for _ in 0..3 {
                check_depth(&grid, d);
                check_depth(&grid, below);
                d = d.next_up();
                below = below.next_down();
            }
            // An edge starts its own slice unless the slice is empty in f32.
            if k < z && grid.slice_start_depth(k + 1) > e {
                assert_eq!(grid.slice_of_depth(e), k, "{grid:?} edge {k} = {e}");
            }
        }
        for k in 0..z {
            let (lo, hi) = grid.slice_depth_range(k);
            assert_eq!(lo, grid.slice_start_depth(k));
            assert_eq!(hi, grid.slice_start_depth(k + 1));
            if hi > lo {
                // Midpoints map back to their slice.
                assert_eq!(grid.slice_of_depth(lo + (hi - lo) * 0.5), k);
            }
        }
    }
}

#[test]
fn depths_outside_the_range_clamp() {
    for grid in grids() {
        for d in [
            0.0,
            -1.0,
            f32::NEG_INFINITY,
            f32::NAN,
            grid.near() * 0.5,
            grid.far(),
            grid.far() * 2.0,
            f32::INFINITY,
            f32::MAX,
        ] {
            check_depth(&grid, d);
        }
    }
}

#[test]
fn dense_depth_sweep_is_monotone_and_consistent() {
    for grid in grids() {
        let (n, f) = (grid.near() as f64, grid.far() as f64);
        let mut last = 0;
        for step in 0..=20_000 {
            let d = (n * (f / n).powf(step as f64 / 20_000.0)) as f32;
            check_depth(&grid, d);
            let s = grid.slice_of_depth(d);
            assert!(s >= last, "{grid:?}: slice decreased at depth {d}");
            last = s;
        }
    }
}

/// The pixel centre's NDC position is inside its tile's NDC span (exact rational arithmetic).
fn check_axis(
    pixels: u32,
    tiles: u32,
    tile_of: impl Fn(u32) -> u32,
    range_of: impl Fn(u32) -> std::ops::Range<u32>,
) {
    let mut covered = 0u32;
    for t in 0..tiles {
        let r = range_of(t);
        assert_eq!(
            r.start, covered,
            "pixels {pixels} tiles {tiles}: tile {t} starts at {}",
            r.start
        );
        for p in r.clone() {
            assert_eq!(tile_of(p), t);
        }
        covered = r.end;
    }
    assert_eq!(covered, pixels, "tiles do not cover all {pixels} pixels");
    for p in 0..pixels {
        let t = tile_of(p) as u64;
        assert!(t < tiles as u64);
        // NDC from the leading edge: (2p + 1)/P ∈ [2t/T, 2(t+1)/T)  ⇔  (2p+1)·T ∈ [2tP, 2(t+1)P).
        let lhs = (2 * p as u64 + 1) * tiles as u64;
        assert!(lhs >= 2 * t * pixels as u64 && lhs < 2 * (t + 1) * pixels as u64);
    }
}

#[test]
fn every_pixel_of_small_resolutions_maps_into_its_tile() {
    let tile_counts = [1u32, 2, 3, 5, 7, 8, 12, 16, 24, 32, 33, 64, 100];
    for pixels in 1..=64u32 {
        for &tiles in &tile_counts {
            let grid =
                ClusterGrid::new(UVec3::new(tiles, tiles, 1), DepthSlicing::Linear, 0.1, 1.0);
            check_axis(
                pixels,
                tiles,
                |p| grid.tile_x_of_pixel(p, pixels),
                |t| grid.tile_pixel_columns(t, pixels),
            );
            check_axis(
                pixels,
                tiles,
                |p| grid.tile_y_of_pixel(p, pixels),
                |t| grid.tile_pixel_rows(t, pixels),
            );
        }
    }
}

#[test]
fn every_pixel_and_depth_of_small_resolutions_gives_the_composed_cluster_id() {
    let grid = ClusterGrid::new(UVec3::new(7, 5, 6), DepthSlicing::Log, 0.1, 50.0);
    let depths: Vec<f32> = (0..=6)
        .map(|k| grid.slice_start_depth(k))
        .chain([0.05, 60.0, 1.0])
        .collect();
    for w in 1..=64u32 {
        for h in 1..=64u32 {
            for py in 0..h {
                for px in 0..w {
                    for &d in &depths {
                        let c = grid.cluster_of_pixel(px, py, d, w, h);
                        let coords = grid.cluster_coords(c);
                        assert_eq!(coords.x, grid.tile_x_of_pixel(px, w));
                        assert_eq!(coords.y, grid.tile_y_of_pixel(py, h));
                        assert_eq!(coords.z, grid.slice_of_depth(d));
                        assert_eq!(grid.cluster_id(coords.x, coords.y, coords.z), c);
                        assert!((c as usize) < grid.cluster_count());
                    }
                }
            }
        }
    }
}

#[test]
fn large_resolutions_map_every_pixel_row_and_column() {
    for (w, h) in [
        (1536u32, 768u32),
        (1920, 1080),
        (3840, 2160),
        (16384, 16384),
        (1, 16384),
    ] {
        for (x, y) in [(24u32, 12u32), (32, 18), (16, 9), (128, 128)] {
            let grid = ClusterGrid::new(UVec3::new(x, y, 1), DepthSlicing::Linear, 0.1, 1.0);
            check_axis(
                w,
                x,
                |p| grid.tile_x_of_pixel(p, w),
                |t| grid.tile_pixel_columns(t, w),
            );
            check_axis(
                h,
                y,
                |p| grid.tile_y_of_pixel(p, h),
                |t| grid.tile_pixel_rows(t, h),
            );
        }
    }
}

/// Pixel and tile counts both beyond ~3e9: `(2p + 1)·tiles` and `2·t·pixels` pass u64 (they
/// wrapped: pixel 4294967294 of 4294967295 gave tile 2147483645 of u32::MAX, audit). Checked
/// against the defining inequality in u128, at the ends and where the products first overflow.
#[test]
fn pixels_and_tiles_beyond_u64_products_map_exactly() {
    for (pixels, tiles) in [
        (u32::MAX, u32::MAX),
        (4_000_000_000, 3_500_000_000),
        (u32::MAX, 3_037_000_500),
        (3_037_000_500, u32::MAX),
    ] {
        let grid = ClusterGrid::new(UVec3::new(tiles, 1, 1), DepthSlicing::Linear, 0.1, 1.0);
        for p in [0, 1, pixels / 2, pixels - 2, pixels - 1] {
            let t = grid.tile_x_of_pixel(p, pixels) as u128;
            let lhs = (2 * p as u128 + 1) * tiles as u128;
            assert!(
                lhs >= 2 * t * pixels as u128 && lhs < 2 * (t + 1) * pixels as u128,
                "pixel {p} of {pixels}, {tiles} tiles: tile {t}"
            );
            let columns = grid.tile_pixel_columns(t as u32, pixels);
            assert!(
                columns.contains(&p),
                "tile {t}: {columns:?} lacks pixel {p}"
            );
        }
    }
    assert_eq!(
        ClusterGrid::new(UVec3::new(u32::MAX, 1, 1), DepthSlicing::Linear, 0.1, 1.0)
            .tile_x_of_pixel(u32::MAX - 1, u32::MAX),
        u32::MAX - 1
    );
}

#[test]
fn tile_edges_match_design_formula() {
    let grid = ClusterGrid::new(UVec3::new(24, 12, 16), DepthSlicing::Log, 0.1, 100.0);
    for i in 0..=24 {
        let expected = -1.0 + 2.0 * i as f64 / 24.0;
        assert!((grid.x_edge_ndc(i) as f64 - expected).abs() <= 1e-7);
    }
    for j in 0..=12 {
        let expected = 1.0 - 2.0 * j as f64 / 12.0;
        assert!((grid.y_edge_ndc(j) as f64 - expected).abs() <= 1e-7);
    }
    for k in 0..=16 {
        let expected = 0.1 * (1000.0f64).powf(k as f64 / 16.0);
        let got = grid.slice_start_depth(k) as f64;
        assert!(
            (got - expected).abs() <= 1e-6 * expected,
            "{k}: {got} vs {expected}"
        );
    }
    let lin = ClusterGrid::new(UVec3::new(1, 1, 10), DepthSlicing::Linear, 1.0, 11.0);
    for k in 0..=10 {
        assert_eq!(lin.slice_start_depth(k), 1.0 + k as f32);
    }
    let near_slice = ClusterGrid::new(
        UVec3::new(1, 1, 5),
        DepthSlicing::LogWithNearSlice {
            first_slice_depth: 1.0,
        },
        0.1,
        10_000.0,
    );
    assert_eq!(near_slice.slice_start_depth(1), 1.0);
    assert!((near_slice.slice_start_depth(2) - 10.0).abs() < 1e-5);
    assert!((near_slice.slice_start_depth(3) - 100.0).abs() < 1e-4);
}

/// Where the assignment's outer slices end: the camera's near and far planes (∞ too) for an open
/// grid under a camera that sees nearer or farther, the grid's near and far otherwise — in
/// `PlaneSets`' first and last depths and in the oracle's outer cells alike; the pixels' slice
/// edges and clusters stay the grid's.
#[test]
fn open_outer_slices_reach_the_cameras_near_and_far_planes() {
    use myriad_cluster_math::oracle::Cell;
    use myriad_cluster_math::{OuterSlices, PlaneSets};
    let grid = ClusterGrid::new(UVec3::new(4, 3, 5), DepthSlicing::Log, 0.5, 40.0);
    assert_eq!(grid.outer_slices(), OuterSlices::Open);
    let closed = grid.with_outer_slices(OuterSlices::Closed);
    assert_ne!(grid, closed);
    // A new depth range keeps them.
    assert_eq!(
        closed.with_depth_range(0.2, 30.0).outer_slices(),
        OuterSlices::Closed
    );
    let far_cases = [
        (f32::INFINITY, f32::INFINITY),
        (400.0, 400.0),
        (40.0, 40.0),
        (25.0, 40.0),
    ];
    // A camera near below `MIN_NEAR` opens the first slice only that far.
    let near_cases = [
        (0.1, 0.1),
        (0.5, 0.5),
        (0.7, 0.5),
        (1e-20, ClusterGrid::MIN_NEAR),
    ];
    for ((camera_far, open_end), (camera_near, open_start)) in far_cases.into_iter().zip(near_cases)
    {
        let camera = Camera::new(
            Vec3::ZERO,
            Vec3::NEG_Z,
            Vec3::Y,
            60.0,
            640,
            480,
            camera_near,
            camera_far,
        );
        let what = format!("near {camera_near}, far {camera_far}");
        assert_eq!(grid.first_slice_start(&camera), open_start, "{what}");
        assert_eq!(grid.last_slice_end(&camera), open_end, "{what}");
        assert_eq!(closed.first_slice_start(&camera), 0.5, "{what}");
        assert_eq!(closed.last_slice_end(&camera), 40.0, "{what}");
        for (g, start, end) in [(&grid, open_start, open_end), (&closed, 0.5, 40.0)] {
            let sets = PlaneSets::new(&camera, g);
            let mut edges = Vec::new();
            g.fill_slice_edges(&mut edges);
            assert_eq!(
                sets.z_depths[1..5],
                edges[1..5],
                "only the outer edges move"
            );
            assert_eq!([sets.z_depths[0], sets.z_depths[5]], [start, end], "{what}");
            assert_eq!([edges[0], edges[5]], [0.5, 40.0]);
            let first = Cell::of_cluster(&camera, g, 1, 2, 0);
            assert_eq!(first.depths, [f64::from(start), f64::from(edges[1])]);
            let last = Cell::of_cluster(&camera, g, 1, 2, 4);
            assert_eq!(last.depths, [f64::from(edges[4]), f64::from(end)]);
            let inner = Cell::of_cluster(&camera, g, 1, 2, 3);
            assert_eq!(inner.depths, [f64::from(edges[3]), f64::from(edges[4])]);
            // Pixels outside the grid read its outer slices, open or closed.
            assert_eq!([g.slice_of_depth(0.01), g.slice_of_depth(1e6)], [0, 4]);
        }
    }
}
