//! Degenerate scenes through [`Assigner::assign`] with every method: 0 and 1 lights, every light
//! outside the frustum, 100k lights in one cluster, one light covering everything, grids 1×1×1,
//! 128×128×128 and wider or taller than 65 535 tiles, resolutions 1×1 and 16384×16384, spot lights
//! under a far plane near `f32::MAX` (also in clusters whose bounding sphere overflows f32), slices
//! of zero thickness (equal f32 edges), lights whose view-space sphere overflows f32, and cameras
//! no method can use. Each checks the CSR invariants
//! ([`LightLists::assert_well_formed`]), the counts the scene implies, and conservativeness
//! against the f64 oracle — over every cluster where that is affordable, over a seeded sample of
//! clusters for the 2M-cluster grid.

mod common;

use common::*;
use glam::{UVec3, Vec3};
use myriad_assignment::{AppendStrategy, AssignStats, Assigner, LightLists, Method, SERIAL_LIGHTS};
use myriad_cluster_math::oracle::{Cell, OracleView};
use myriad_cluster_math::{Camera, ClusterGrid, DepthSlicing};
use rand::{Rng, SeedableRng};

fn camera(width: u32, height: u32) -> Camera {
    Camera::new(
        Vec3::new(1.0, 2.0, 3.0),
        Vec3::new(1.0, 2.0, 2.0),
        Vec3::Y,
        60.0,
        width,
        height,
        0.1,
        100.0,
    )
}

fn assign(
    method: Method,
    lights: &Columns,
    camera: &Camera,
    grid: &ClusterGrid,
) -> (LightLists, AssignStats) {
    let mut lists = LightLists::new();
    let stats = Assigner::new().assign(method, &lights.input(false), camera, grid, &mut lists);
    lists.assert_well_formed(lights.len());
    assert_eq!(lists.cluster_count(), grid.cluster_count(), "{method}");
    assert_eq!(stats.pairs as usize, lists.indices.len(), "{method}");
    (lists, stats)
}

/// World position of a view-space point.
fn world_of(camera: &Camera, view: Vec3) -> Vec3 {
    let (r, u, f) = camera.basis_f64();
    let v = r * view.x as f64 + u * view.y as f64 - f * view.z as f64;
    (camera.position.as_dvec3() + v).as_vec3()
}

/// Random lights in and around the frustum, radii 0.01–5.
fn random_lights(camera: &Camera, count: usize, seed: u64) -> Columns {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let t = camera.tan_half_fov();
    let mut lights = Columns::default();
    for _ in 0..count {
        let d = rng.random_range(-5.0f32..110.0);
        let view = Vec3::new(
            rng.random_range(-1.2f32..1.2) * t.x * d.abs(),
            rng.random_range(-1.2f32..1.2) * t.y * d.abs(),
            -d,
        );
        lights.push(world_of(camera, view), rng.random_range(0.01f32..5.0));
    }
    lights
}

/// Every method on spot lights, against the oracle over every cluster; some pair must exist.
fn assert_spots_conservative(lights: &Columns, camera: &Camera, grid: &ClusterGrid, context: &str) {
    let truth = brute_force(lights, true, camera, grid);
    for method in Method::ALL {
        let mut lists = LightLists::new();
        Assigner::new().assign(method, &lights.input(true), camera, grid, &mut lists);
        let (exact, _) = assert_conservative(method.name(), &lists, &truth, context);
        assert!(exact > 0, "{context}: the oracle sees no pair");
    }
}

/// Oracle check of the clusters in `sample` only: each list holds every light the oracle says
/// touches that cluster.
fn assert_conservative_on(
    name: &str,
    lists: &LightLists,
    lights: &Columns,
    camera: &Camera,
    grid: &ClusterGrid,
    sample: impl Iterator<Item = u32>,
) {
    let view = OracleView::new(camera);
    for c in sample {
        let v = grid.cluster_coords(c);
        let cell = Cell::of_cluster(camera, grid, v.x, v.y, v.z);
        let got = lists.lights_of(c as usize);
        for l in 0..lights.len() {
            let position = Vec3::new(lights.x[l], lights.y[l], lights.z[l]);
            let volume = view.light(position, lights.radius[l], None);
            if volume.is_some_and(|v| v.intersects_cell(&cell)) {
                assert!(
                    got.binary_search(&(l as u32)).is_ok(),
                    "{name}: light {l} missing from cluster {c} {v}"
                );
            }
        }
    }
}

#[test]
fn no_lights() {
    let cam = camera(1536, 768);
    let grid = ClusterGrid::new(UVec3::new(24, 12, 16), DepthSlicing::Log, 0.1, 100.0);
    for method in Method::ALL {
        let (lists, stats) = assign(method, &Columns::default(), &cam, &grid);
        assert_eq!(stats.lights, 0);
        assert!(lists.indices.is_empty(), "{method}");
        assert!(lists.counts.iter().all(|&c| c == 0), "{method}");
        assert!(lists.offsets.iter().all(|&o| o == 0), "{method}");
    }
}

#[test]
fn one_light() {
    let cam = camera(1536, 768);
    let grid = ClusterGrid::new(UVec3::new(24, 12, 16), DepthSlicing::Log, 0.1, 100.0);
    let mut lights = Columns::default();
    lights.push(world_of(&cam, Vec3::new(0.3, -0.2, -7.0)), 1.5);
    let truth = brute_force(&lights, false, &cam, &grid);
    let want: usize = truth.iter().map(Vec::len).sum();
    assert!(want > 1);
    for method in Method::ALL {
        let (lists, stats) = assign(method, &lights, &cam, &grid);
        assert_eq!(stats.visible(), 1, "{method}");
        let (exact, extra) = assert_conservative(method.name(), &lists, &truth, "one light");
        assert_eq!(exact, want);
        if method == Method::Exact {
            assert_eq!(extra, 0);
        }
    }
}

#[test]
fn every_light_outside_the_frustum() {
    let cam = camera(1536, 768);
    let grid = ClusterGrid::new(UVec3::new(24, 12, 16), DepthSlicing::Log, 0.1, 100.0);
    let t = cam.tan_half_fov();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
    let mut lights = Columns::default();
    for n in 0..5000 {
        let r = rng.random_range(0.01f32..2.0);
        let d = rng.random_range(1.0f32..90.0);
        let view = match n % 6 {
            0 => Vec3::new(0.0, 0.0, r * 1.5 + 0.01), // behind, not reaching the eye
            1 => Vec3::new(0.0, 0.0, -(100.0 + r * 1.5 + 0.01)), // beyond far
            2 => Vec3::new(-(t.x * d + r * 2.0), 0.0, -d), // left
            3 => Vec3::new(t.x * d + r * 2.0, 0.0, -d), // right
            4 => Vec3::new(0.0, t.y * d + r * 2.0, -d), // above
            _ => Vec3::new(0.3, -(t.y * d + r * 2.0), -d), // below
        };
        lights.push(world_of(&cam, view), r);
    }
    let truth = brute_force(&lights, false, &cam, &grid);
    assert!(truth.iter().all(Vec::is_empty), "the scene must be outside");
    for method in Method::ALL {
        let (lists, stats) = assign(method, &lights, &cam, &grid);
        assert_eq!(stats.rejected, 0, "{method}");
        assert!(
            lists.indices.is_empty(),
            "{method}: {} pairs {:?}",
            lists.indices.len(),
            &lists.indices[..lists.indices.len().min(20)]
        );
        // Outside by well over the radius padding (4e-6 of the distance), so every frustum test
        // culls them (lights within the padding may count as visible with no pairs).
        assert_eq!(stats.culled, 5000, "{method}");
    }
}

#[test]
fn hundred_thousand_lights_in_one_cluster() {
    let cam = camera(1536, 768);
    let dims = UVec3::new(24, 12, 16);
    let grid = ClusterGrid::new(dims, DepthSlicing::Log, 0.1, 100.0);
    // Centre of cluster (10, 5, 9), lights of radius 1e-4 jittered by 1e-3 around it.
    let (i, j, k) = (10u32, 5u32, 9u32);
    let (d0, d1) = grid.slice_depth_range(k);
    let d = 0.5 * (d0 + d1);
    let t = cam.tan_half_fov();
    let sx = 0.5 * (grid.x_edge_ndc(i) + grid.x_edge_ndc(i + 1)) * t.x;
    let sy = 0.5 * (grid.y_edge_ndc(j) + grid.y_edge_ndc(j + 1)) * t.y;
    let centre = Vec3::new(sx * d, sy * d, -d);
    let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
    let mut lights = Columns::default();
    let n = 100_000;
    for _ in 0..n {
        let jitter = Vec3::new(
            rng.random_range(-1e-3f32..1e-3),
            rng.random_range(-1e-3f32..1e-3),
            rng.random_range(-1e-3f32..1e-3),
        );
        lights.push(world_of(&cam, centre + jitter), 1e-4);
    }
    let c = grid.cluster_id(i, j, k) as usize;
    for method in Method::ALL {
        let (lists, stats) = assign(method, &lights, &cam, &grid);
        assert_eq!(stats.visible(), n as u32, "{method}");
        assert_eq!(lists.counts[c] as usize, n, "{method}");
        assert_eq!(lists.indices.len(), n, "{method}: only that cluster");
        assert!(
            lists
                .lights_of(c)
                .iter()
                .enumerate()
                .all(|(a, &b)| a as u32 == b),
            "{method}: every light, ascending"
        );
    }
}

#[test]
fn one_light_covering_everything() {
    let cam = camera(1536, 768);
    let grid = ClusterGrid::new(UVec3::new(24, 12, 16), DepthSlicing::Log, 0.1, 100.0);
    for r in [200.0f32, 1.0e6, 3.0e38] {
        let mut lights = Columns::default();
        lights.push(cam.position, r);
        for method in Method::ALL {
            let (lists, _) = assign(method, &lights, &cam, &grid);
            assert!(
                lists.counts.iter().all(|&c| c == 1),
                "{method}, radius {r}: every cluster has the light"
            );
        }
    }
}

/// Grids 70 000 tiles wide and 70 000 tall (past any 16-bit tile index, and past the rows and
/// the row length one span of the append holds; one slice: 70k–210k clusters, checked cluster by
/// cluster against the oracle): one light covering everything plus random ones lose nothing.
/// The 3-wide grid's box is split into spans of rows 3 clusters apart.
#[test]
fn grids_wider_and_taller_than_16_bits() {
    let cam = camera(1536, 768);
    for dims in [
        UVec3::new(70_000, 1, 1),
        UVec3::new(1, 70_000, 1),
        UVec3::new(3, 70_000, 1),
    ] {
        let grid = ClusterGrid::new(dims, DepthSlicing::Log, 0.1, 100.0);
        let mut lights = random_lights(&cam, 40, 17);
        lights.push(cam.position, 500.0);
        let truth = brute_force(&lights, false, &cam, &grid);
        for method in [Method::Binary, Method::Refined] {
            let (lists, _) = assign(method, &lights, &cam, &grid);
            let (exact, _) = assert_conservative(method.name(), &lists, &truth, "wide grid");
            assert!(
                exact >= 70_000,
                "{method}: the big light alone fills every cluster"
            );
            let big = (lights.len() - 1) as u32;
            assert!(
                (0..grid.cluster_count()).all(|c| lists.lights_of(c).contains(&big)),
                "{method} {dims}: the covering light is in every cluster"
            );
        }
    }
}

/// Rows longer than a span holds on several rows and slices of a 70 000 × 2 × 2 grid: the covering
/// light's box (70 000 clusters × 2 rows per slice) is pushed as pieces row by row, and under a
/// mask (or refined, or as a spot) each 70 000-cluster row is pushed in pieces whose inactive
/// clusters do not count. Every method, both append strategies, masked and not: no oracle light
/// is lost, the covering light is in every cluster, the strategies agree, and the masked lists
/// are the full lists on the active clusters (and empty elsewhere).
#[test]
fn rows_longer_than_16_bits_on_several_rows_and_slices() {
    let cam = camera(1536, 768);
    let grid = ClusterGrid::new(UVec3::new(70_000, 2, 2), DepthSlicing::Log, 0.1, 100.0);
    let mut lights = random_lights(&cam, 12, 23);
    lights.push(cam.position, 500.0);
    let big = (lights.len() - 1) as u32;
    let truth = brute_force(&lights, false, &cam, &grid);
    // Half the clusters at random, and none past cluster 65 535 of the second row of slice 0:
    // that row's last piece has no active cluster.
    let mut rng = rand_pcg::Pcg64::seed_from_u64(29);
    let mut mask = myriad_assignment::ActiveClusters::new(&grid);
    for c in 0..grid.cluster_count() as u32 {
        let v = grid.cluster_coords(c);
        if rng.random_bool(0.5) && !(v.y == 1 && v.z == 0 && v.x >= 65_535) {
            mask.mark(c);
        }
    }
    let input = lights.input(false);
    // The same lights followed by enough behind the eye to split the frame into tasks, and the
    // clusters into one part per slice: the lists must not change.
    let mut padded = lights.clone();
    for i in 0..2 * SERIAL_LIGHTS {
        padded.push(world_of(&cam, Vec3::new(i as f32, 0.0, 50.0)), 1.0);
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    for method in [Method::Binary, Method::Refined, Method::Cone, Method::Exact] {
        let (lists, stats) = assign(method, &lights, &cam, &grid);
        assert_conservative(method.name(), &lists, &truth, "70 000 × 2 × 2");
        assert!(
            (0..grid.cluster_count()).all(|c| lists.lights_of(c).contains(&big)),
            "{method}: the covering light is in every cluster"
        );
        let mut split = LightLists::new();
        let split_stats = pool.install(|| {
            Assigner::new().assign(method, &padded.input(false), &cam, &grid, &mut split)
        });
        assert!(split_stats.tasks > 1, "{method}: {split_stats:?}");
        assert!(split == lists, "{method}: tasks and parts change the lists");
        for strategy in [
            AppendStrategy::PartitionedByDepth,
            AppendStrategy::AtomicCounters,
        ] {
            let mut assigner = Assigner::new().with_append_strategy(strategy);
            let mut full = LightLists::new();
            assigner.assign(method, &input, &cam, &grid, &mut full);
            assert!(
                full == lists,
                "{method} {strategy:?}: the strategies differ"
            );
            let mut masked = LightLists::new();
            let masked_stats =
                assigner.assign_active(method, &input, &cam, &grid, Some(&mask), &mut masked);
            masked.assert_well_formed(lights.len());
            let mut pairs = 0u64;
            for c in 0..grid.cluster_count() {
                if mask.is_active(c as u32) {
                    assert_eq!(
                        masked.lights_of(c),
                        lists.lights_of(c),
                        "{method} {strategy:?}: active cluster {c}"
                    );
                    pairs += lists.counts[c] as u64;
                } else {
                    assert!(
                        masked.lights_of(c).is_empty(),
                        "{method} {strategy:?}: inactive cluster {c} has lights"
                    );
                }
            }
            assert!(pairs < stats.pairs, "{method}: the mask drops pairs");
            assert_eq!(masked_stats.pairs, pairs, "{method} {strategy:?}");
            assert_eq!(masked.pair_count() as u64, pairs, "{method} {strategy:?}");
        }
    }
}

/// A grid with more tiles than the `cone` method keeps cones for (2^18): each tile's cone is
/// made where it is needed, and the lists still cover the oracle.
#[test]
fn cone_method_past_its_cached_tiles() {
    let cam = camera(1920, 1080);
    let grid = ClusterGrid::new(UVec3::new(730, 360, 2), DepthSlicing::Log, 0.1, 100.0);
    let mut lights = random_lights(&cam, 12, 23);
    lights.push(cam.position, 0.5);
    let truth = brute_force(&lights, false, &cam, &grid);
    let (lists, _) = assign(Method::Cone, &lights, &cam, &grid);
    let (exact, _) = assert_conservative("cone", &lists, &truth, "730x360 tiles");
    assert!(exact > 10_000, "{exact} pairs");
}

#[test]
fn grid_of_one_cluster() {
    let cam = camera(640, 480);
    for slicing in [
        DepthSlicing::Linear,
        DepthSlicing::Log,
        DepthSlicing::LogWithNearSlice {
            first_slice_depth: 1.0,
        },
    ] {
        let grid = ClusterGrid::new(UVec3::ONE, slicing, 0.1, 100.0);
        let lights = random_lights(&cam, 500, 11);
        let truth = brute_force(&lights, false, &cam, &grid);
        for method in Method::ALL {
            let (lists, _) = assign(method, &lights, &cam, &grid);
            let (exact, extra) = assert_conservative(method.name(), &lists, &truth, "1x1x1");
            assert!(exact > 0);
            if method == Method::Exact {
                assert_eq!(extra, 0);
            }
        }
    }
}

#[test]
fn grid_of_128_cubed() {
    // 2,097,152 clusters. Fast methods and exact; the oracle on a seeded sample of clusters plus
    // the eight corners.
    let cam = camera(1920, 1080);
    let grid = ClusterGrid::new(UVec3::splat(128), DepthSlicing::Log, 0.1, 100.0);
    let lights = random_lights(&cam, 300, 5);
    let clusters = grid.cluster_count() as u32;
    let mut rng = rand_pcg::Pcg64::seed_from_u64(9);
    let mut sample: Vec<u32> = (0..1500).map(|_| rng.random_range(0..clusters)).collect();
    for &i in &[0u32, 127] {
        for &j in &[0u32, 127] {
            for &k in &[0u32, 127] {
                sample.push(grid.cluster_id(i, j, k));
            }
        }
    }
    let mut pairs = Vec::new();
    for method in Method::ALL {
        let (lists, _) = assign(method, &lights, &cam, &grid);
        assert_conservative_on(
            method.name(),
            &lists,
            &lights,
            &cam,
            &grid,
            sample.iter().copied(),
        );
        pairs.push((method, lists.indices.len()));
    }
    let exact = pairs[0].1;
    assert!(exact > 0);
    for (method, p) in pairs {
        assert!(p >= exact, "{method}: {p} pairs < exact {exact}");
    }
}

#[test]
fn resolutions_one_pixel_and_16k_square() {
    for (w, h) in [(1u32, 1u32), (16384, 16384), (1, 16384), (16384, 1)] {
        let cam = camera(w, h);
        let grid = ClusterGrid::new(UVec3::new(16, 9, 12), DepthSlicing::Log, 0.1, 100.0);
        let lights = random_lights(&cam, 200, w as u64 * 31 + h as u64);
        let truth = brute_force(&lights, false, &cam, &grid);
        for method in Method::ALL {
            let (lists, _) = assign(method, &lights, &cam, &grid);
            let (_, extra) =
                assert_conservative(method.name(), &lists, &truth, &format!("{w}x{h}"));
            if method == Method::Exact {
                assert_eq!(extra, 0);
            }
        }
        // The pixel → cluster mapping stays in range at the corners.
        for (px, py) in [(0, 0), (w - 1, h - 1), (w / 2, h / 2)] {
            for depth in [0.0f32, 0.1, 50.0, 100.0, 1e9, f32::NAN] {
                let c = grid.cluster_of_pixel(px, py, depth, w, h);
                assert!(
                    (c as usize) < grid.cluster_count(),
                    "{w}x{h} ({px},{py}) {depth}"
                );
            }
        }
    }
}

#[test]
fn spot_lights_under_a_far_plane_near_f32_max() {
    // Clusters whose centres lie ~1e37 from the light: their distances to the apex overflow f32
    // (the cone test once rejected them as infinitely far from the axis; an audit found it).
    for far in [1.0e30f32, 3.4e38] {
        for slicing in [DepthSlicing::Linear, DepthSlicing::Log] {
            let camera = Camera::new(
                Vec3::new(0.0, 2.0, 10.0),
                Vec3::new(0.0, 2.0, 0.0),
                Vec3::Y,
                60.0,
                64,
                32,
                1.0e-3,
                far,
            );
            let grid = ClusterGrid::new(UVec3::new(24, 12, 16), slicing, camera.near, far);
            let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
            let mut lights = Columns::default();
            lights.push_spot(
                Vec3::new(0.0, 5.0, 0.0),
                8.0,
                Vec3::NEG_Y,
                30f32.to_radians(),
            );
            for _ in 0..40 {
                let position = Vec3::new(
                    rng.random_range(-20.0f32..20.0),
                    rng.random_range(-10.0f32..10.0),
                    rng.random_range(-30.0f32..9.0),
                );
                let radius = rng.random_range(0.5f32..1.0e6);
                let angle = rng.random_range(0.05f32..1.5);
                lights.push_spot(position, radius, random_dir(&mut rng), angle);
            }
            let context = format!("far {far:e}, {slicing:?}");
            assert_spots_conservative(&lights, &camera, &grid, &context);
        }
    }
}

#[test]
fn zero_thickness_slices_of_a_very_thin_log_grid() {
    // near 5, far 5.00001 in 64 log slices: f32 rounds many adjacent slice edges to one value, so
    // some slices have no thickness. No pixel lands in them, but the closed cells touch the
    // lights, and the f64 oracle counts that (every method once skipped them; an audit found it).
    for slicing in [DepthSlicing::Log, DepthSlicing::Linear] {
        let (near, far) = (5.0f32, 5.00001f32);
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 64, 64, near, far);
        let grid = ClusterGrid::new(UVec3::new(2, 2, 64), slicing, near, far);
        let z = myriad_cluster_math::PlaneSets::new(&camera, &grid).z_depths;
        assert!(
            z.windows(2).any(|w| w[0] == w[1]),
            "{slicing:?}: the grid must have zero-thickness slices to test them: {z:?}"
        );
        let mut lights = Columns::default();
        lights.push(Vec3::new(0.0, 0.0, -5.000005), 1.0);
        // Small lights whose depth band starts or ends exactly on each distinct slice edge.
        let mut edges = z.clone();
        edges.dedup();
        for (n, &e) in edges.iter().enumerate() {
            let r = 1.0e-6;
            let x = (n as f32 - 4.0) * 0.3;
            lights.push(Vec3::new(x, 0.5, -(e + r)), r);
            lights.push(Vec3::new(x, -0.5, -(e - r)), r);
        }
        let truth = brute_force(&lights, false, &camera, &grid);
        for method in Method::ALL {
            let (lists, _) = assign(method, &lights, &camera, &grid);
            let context = format!("{slicing:?}, z {z:?}");
            let (exact, _) = assert_conservative(method.name(), &lists, &truth, &context);
            assert!(exact > 0, "{context}: the oracle sees no pair");
        }
    }
}

#[test]
fn lights_whose_view_space_sphere_overflows_f32() {
    // Camera at the origin looking along +x+y, far near f32::MAX: a light at (3e38, 3e38, 0)
    // lies ~4.2e38 from the eye, past f32's range once rotated into view space, yet its radius
    // reaches into the frustum (it was once counted as culled). One behind the camera must still
    // be culled.
    let far = 3.0e38f32;
    let camera = Camera::new(
        Vec3::ZERO,
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::Z,
        60.0,
        64,
        32,
        1.0,
        far,
    );
    let grid = ClusterGrid::new(UVec3::new(8, 4, 8), DepthSlicing::Linear, 1.0, far);
    let mut lights = Columns::default();
    lights.push(Vec3::new(3.0e38, 3.0e38, 0.0), 3.3e38);
    lights.push(Vec3::new(-3.0e38, -3.0e38, 0.0), 1.0e38);
    lights.push(Vec3::new(3.0e38, 3.0e38, 0.0), 1.0e30);
    lights.push(Vec3::new(1.0e37, 1.0e37, 0.0), 1.0e36);
    let truth = brute_force(&lights, false, &camera, &grid);
    assert!(truth.iter().any(|l| l.contains(&0)), "light 0 must touch");
    assert!(!truth.iter().any(|l| l.contains(&1)), "light 1 lies behind");
    for method in Method::ALL {
        let (lists, stats) = assign(method, &lights, &camera, &grid);
        let (exact, extra) = assert_conservative(method.name(), &lists, &truth, "overflow");
        assert!(exact > 0);
        assert_eq!(stats.rejected, 0, "{method}: every light is valid");
        // Exactly: the light behind and the one past the far plane (a count that wrapped below
        // zero would pass `>= 1`).
        assert_eq!(
            stats.culled, 2,
            "{method}: the lights behind and beyond are culled"
        );
        if method == Method::Exact {
            assert_eq!(extra, 0, "exact tests each cluster in f64");
        }
    }
}

#[test]
fn a_light_whose_padded_radius_alone_overflows_f32_is_culled_in_f64() {
    // Radius f32::MAX, centre finite but behind, left of and below a narrow view, over f32::MAX
    // from the eye: only the padded radius overflows, and the f64 test must still cull the
    // light (an f32 path with an infinite radius would list it everywhere). The same radius in
    // front of the eye covers every cluster.
    let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 10.0, 64, 64, 1.0, 1.0e3);
    let grid = ClusterGrid::new(UVec3::new(4, 4, 4), DepthSlicing::Linear, 1.0, 1.0e3);
    let m = f32::MAX;
    let mut lights = Columns::default();
    lights.push(Vec3::new(-0.99 * m, -0.99 * m, 0.99 * m), m);
    lights.push(Vec3::new(0.0, 0.0, -10.0), m);
    let truth = brute_force(&lights, false, &camera, &grid);
    assert!(
        truth.iter().all(|l| l == &[1]),
        "light 0 misses, light 1 covers"
    );
    for method in Method::ALL {
        let (lists, stats) = assign(method, &lights, &camera, &grid);
        assert_conservative(method.name(), &lists, &truth, "padded radius overflows");
        assert_eq!((stats.culled, stats.pairs), (1, 64), "{method}: {stats:?}");
    }
}

#[test]
fn try_assign_returns_each_panic_of_assign_as_an_error_and_leaves_the_lists() {
    // For engines whose cameras and light counts come from data: what `assign` panics on,
    // `try_assign` returns, with the same message, and `out` keeps the last good frame.
    let good = camera(64, 32);
    let grid = ClusterGrid::new(UVec3::new(8, 4, 4), DepthSlicing::Log, 0.1, 100.0);
    let lights = random_lights(&good, 50, 3);
    let mut assigner = Assigner::new();
    let mut lists = LightLists::new();
    let stats = assigner
        .try_assign(
            Method::Refined,
            &lights.input(false),
            &good,
            &grid,
            &mut lists,
        )
        .unwrap();
    let (want, want_stats) = assign(Method::Refined, &lights, &good, &grid);
    assert_eq!((&lists, stats.pairs), (&want, want_stats.pairs));
    let mut short = lights.input(false);
    short.radius = &short.radius[1..];
    let mut short_spot = lights.input(true);
    short_spot.spot.as_mut().unwrap().angle = &[];
    let other_grid = ClusterGrid::new(UVec3::new(4, 4, 4), DepthSlicing::Log, 0.1, 100.0);
    let mask = myriad_assignment::ActiveClusters::new(&other_grid);
    // The same dimensions over another depth range: other cells under the same ids.
    let other_range = ClusterGrid::new(UVec3::new(8, 4, 4), DepthSlicing::Log, 0.1, 90.0);
    let mut other_range_mask = myriad_assignment::ActiveClusters::new(&other_range);
    other_range_mask.mark_all();
    let no_height = Camera { height: 0, ..good };
    let full = lights.input(false);
    let cases = [
        (&full, &no_height, None, "needs a valid camera"),
        (&short, &good, None, "light columns differ in length"),
        (&short_spot, &good, None, "spot columns differ"),
        (
            &full,
            &good,
            Some(&mask),
            "mask is for a 4x4x4 grid, not this 8x4x4 one",
        ),
        (
            &full,
            &good,
            Some(&other_range_mask),
            "mask is for another 8x4x4 grid (another depth range or slicing",
        ),
    ];
    for (input, cam, active, needle) in cases {
        let e = assigner
            .try_assign_active(Method::Binary, input, cam, &grid, active, &mut lists)
            .unwrap_err();
        assert!(e.to_string().contains(needle), "{e}");
        assert_eq!(lists, want, "{needle}: the lists changed");
        let panic = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let mut out = LightLists::new();
            Assigner::new().assign_active(Method::Binary, input, cam, &grid, active, &mut out)
        }))
        .expect_err("assign panics where try_assign refuses");
        let message = panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap();
        assert!(message.contains(needle), "{message}");
    }
}

#[test]
fn every_method_refuses_an_unusable_camera_with_one_clear_message() {
    // Once `linear` indexed out of bounds on a NaN field of view while the other methods culled
    // every light (and a zero height listed every light everywhere in `linear`).
    let good = camera(64, 32);
    let grid = ClusterGrid::new(UVec3::new(8, 4, 4), DepthSlicing::Log, 0.1, 100.0);
    let lights = random_lights(&good, 50, 3);
    for bad in [
        Camera {
            fov_y: f32::NAN,
            ..good
        },
        Camera { height: 0, ..good },
        Camera {
            position: Vec3::NAN,
            ..good
        },
    ] {
        for method in Method::ALL {
            let r = std::panic::catch_unwind(|| {
                let mut lists = LightLists::new();
                Assigner::new().assign(method, &lights.input(false), &bad, &grid, &mut lists)
            });
            let panic = r.expect_err("an unusable camera is refused");
            let message = panic.downcast_ref::<String>().expect("a formatted message");
            assert!(
                message.contains("needs a valid camera"),
                "{method}: {message}"
            );
        }
    }
    // An infinite far plane is not a problem: depth is sliced by the grid's own range.
    let infinite_far = Camera {
        far: f32::INFINITY,
        ..good
    };
    let truth = brute_force(&lights, false, &infinite_far, &grid);
    for method in Method::ALL {
        let (lists, _) = assign(method, &lights, &infinite_far, &grid);
        let (exact, _) = assert_conservative(method.name(), &lists, &truth, "infinite far");
        assert!(exact > 0);
    }
    // A mask is for its grid's cells whether the outer slices are open or closed.
    let mut mask = myriad_assignment::ActiveClusters::new(&grid);
    mask.mark_all();
    let closed = grid.with_outer_slices(myriad_cluster_math::OuterSlices::Closed);
    let mut masked = LightLists::new();
    Assigner::new()
        .try_assign_active(
            Method::Refined,
            &lights.input(false),
            &good,
            &closed,
            Some(&mask),
            &mut masked,
        )
        .unwrap();
    let mut unmasked = LightLists::new();
    Assigner::new()
        .try_assign(
            Method::Refined,
            &lights.input(false),
            &good,
            &closed,
            &mut unmasked,
        )
        .unwrap();
    assert_eq!(masked, unmasked);
}

#[test]
fn spot_lights_in_clusters_whose_bounding_sphere_overflows_f32() {
    // fov 170° under a far plane of 3e38: the last slices' corners lie past f32's range, so
    // their bounding spheres are infinite and the cone test rejected them (an audit found it).
    let far = 3.0e38f32;
    let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 170.0, 16, 16, 1.0, far);
    for dims in [UVec3::new(2, 2, 9), UVec3::new(4, 4, 16)] {
        let grid = ClusterGrid::new(dims, DepthSlicing::Log, 1.0, far);
        let mut lights = Columns::default();
        lights.push_spot(
            Vec3::new(0.0, 0.0, -10.0),
            1.0e35,
            Vec3::NEG_Z,
            45f32.to_radians(),
        );
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        for _ in 0..30 {
            let position = Vec3::new(
                rng.random_range(-1.0e30f32..1.0e30),
                rng.random_range(-1.0e30f32..1.0e30),
                -rng.random_range(1.0f32..1.0e36),
            );
            let radius = 10f32.powf(rng.random_range(30.0f32..38.0));
            let angle = rng.random_range(0.05f32..1.5);
            lights.push_spot(position, radius, random_dir(&mut rng), angle);
        }
        assert_spots_conservative(&lights, &camera, &grid, &format!("{dims}"));
    }
}

#[test]
fn spots_with_angles_outside_zero_to_90_degrees_or_no_axis_are_the_ranges_ball() {
    // The oracle takes a spot whose half angle is not in (0°, 90°] (zero, negative, NaN, infinite
    // or wider), or whose axis is zero or not finite, as its range's ball, so every method must
    // list the whole ball. A zero or negative angle's "bounding sphere", or one about a zero axis,
    // is smaller than the ball: it would miss clusters the ball reaches.
    let camera = camera(1536, 768);
    let grid = ClusterGrid::new(UVec3::new(24, 12, 16), DepthSlicing::Log, 0.1, 100.0);
    let t = camera.tan_half_fov();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
    let mut lights = Columns::default();
    let angles = [
        0.0f32,
        -0.0,
        -0.4,
        -std::f32::consts::PI,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        2.0,
    ];
    let axes = [Vec3::ZERO, Vec3::NAN, Vec3::new(0.0, f32::INFINITY, 1.0)];
    let cases = angles
        .iter()
        .map(|&a| (a, None))
        .chain(axes.iter().map(|&axis| (0.3, Some(axis))))
        .collect::<Vec<_>>();
    for (angle, axis) in cases {
        for _ in 0..6 {
            let d = rng.random_range(1.0f32..60.0);
            let view = Vec3::new(
                rng.random_range(-0.8f32..0.8) * t.x * d,
                rng.random_range(-0.8f32..0.8) * t.y * d,
                -d,
            );
            let range = rng.random_range(0.5f32..6.0);
            let axis = axis.unwrap_or_else(|| random_dir(&mut rng));
            lights.push_spot(world_of(&camera, view), range, axis, angle);
        }
    }
    let balls = brute_force(&lights, false, &camera, &grid);
    let truth = brute_force(&lights, true, &camera, &grid);
    assert!(truth.lists == balls.lists, "the oracle must see balls");
    assert_spots_conservative(&lights, &camera, &grid, "angles outside (0°, 90°], no axis");
}

#[test]
fn spot_axes_of_any_length() {
    // The axis need not be unit. About 1e-22 long, its f32 squared length is subnormal and an f32
    // normalisation came out 0.8–1.02 long: every method, `exact` included, missed up to 44 of
    // the 63 clusters of this spot (an audit found it). Long axes must work as well.
    let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 1536, 768, 0.1, 60.0);
    let grid = ClusterGrid::new(UVec3::new(24, 12, 16), DepthSlicing::Log, 0.1, 60.0);
    let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
    for scale in [
        1.0e-22f32, 7.0e-23, 4.0e-23, 3.0e-23, 1.0e-30, 1.0e-40, 1.0e30, 1.0e38,
    ] {
        let mut lights = Columns::default();
        let half_angle = 5f32.to_radians();
        lights.push_spot(
            Vec3::new(0.3, 0.2, -1.0),
            50.0,
            Vec3::NEG_Z * scale,
            half_angle,
        );
        for _ in 0..20 {
            let apex = Vec3::new(
                rng.random_range(-3.0f32..3.0),
                rng.random_range(-2.0f32..2.0),
                -rng.random_range(0.5f32..20.0),
            );
            let angle = rng.random_range(0.02f32..1.2);
            lights.push_spot(apex, 30.0, random_dir(&mut rng) * scale, angle);
        }
        assert_spots_conservative(&lights, &camera, &grid, &format!("axis x {scale:e}"));
    }
}

/// Columns of different lengths are a programming error that [`Assigner::assign`] documents as a
/// panic, with every method: a longer radius or angle column would otherwise be read only up to
/// `x`'s length, unnoticed.
#[test]
fn columns_of_different_lengths_panic_with_every_method() {
    let cam = camera(64, 64);
    let grid = ClusterGrid::new(UVec3::new(4, 4, 4), DepthSlicing::Log, 0.1, 100.0);
    let mut lights = Columns::default();
    for x in [-1.0, 0.0, 1.0] {
        lights.push(world_of(&cam, Vec3::new(x, 0.0, -5.0)), 1.0);
    }
    let mut long_radius = lights.clone();
    long_radius.radius.push(1.0);
    let mut long_angle = lights.clone();
    long_angle.angle.push(0.5);
    let cases = [
        (&long_radius, false, "light columns differ in length"),
        (&long_angle, true, "spot columns differ in length"),
    ];
    for method in Method::ALL {
        for (columns, spots, want) in cases {
            let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                let mut lists = LightLists::new();
                Assigner::new().assign(method, &columns.input(spots), &cam, &grid, &mut lists);
            }));
            let Err(payload) = outcome else {
                panic!("{method}: assigned mismatched columns ({want})");
            };
            let message = payload
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| payload.downcast_ref::<&str>().copied())
                .unwrap_or_default();
            assert!(
                message.contains(want),
                "{method}: panicked with {message:?}"
            );
        }
    }
}
