//! A camera that sees past the grid's far edge (an engine's infinite projection with a finite
//! grid): the lights wholly past the grid's far are counted (`AssignStats::beyond_far`),
//! identically by every method and thread count, and `AssignStats::reach` is the far of a grid
//! that has none of them beyond it. An engine audit found those lights silently missing from
//! the pixels beyond the grid (which read its last slice); a grid's last slice is now open by
//! default (`OuterSlices::Open`) and lists them, and a closed one culls them. The same holds on
//! the near side, for a grid that starts beyond the camera's near plane
//! (`AssignStats::before_near`).

mod common;

use common::*;
use glam::{UVec3, Vec3};
use myriad_assignment::{AssignStats, Assigner, LightLists, Method};
use myriad_cluster_math::{Camera, ClusterGrid, DepthSlicing, OuterSlices};
use rand::{Rng, SeedableRng};
use std::ops::Range;

/// What [`lights_in_view`] drew: the lights, how many lie wholly past the grid's far and wholly
/// before its near, and the farthest depth any of them reaches.
struct Drawn {
    lights: Columns,
    beyond: u32,
    before: u32,
    reach: f32,
}

/// `n` point lights well inside the view's sides at `depths` (radii `radii`), none within 0.05 of
/// `grid`'s far plane with its sphere's near side nor of its near plane with its far side, so
/// that the padding cannot move a light across either.
fn lights_in_view(
    camera: &Camera,
    n: usize,
    (depths, radii): (Range<f32>, Range<f32>),
    grid: &ClusterGrid,
    seed: u64,
) -> Drawn {
    let (right, up, forward) = view_basis(camera);
    let (tx, ty) = camera.tan_half_fov().into();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let mut drawn = Drawn {
        lights: Columns::default(),
        beyond: 0,
        before: 0,
        reach: 0.0,
    };
    while drawn.lights.len() < n {
        let depth = rng.random_range(depths.clone());
        let r = rng.random_range(radii.clone());
        if (depth - r - grid.far()).abs() < 0.05 || (depth + r - grid.near()).abs() < 0.05 {
            continue;
        }
        // Within half the view's width and height: every side plane keeps the whole sphere
        // when it is this deep, and at least partly when it is shallower.
        let x = rng.random_range(-0.5..0.5) * tx * depth;
        let y = rng.random_range(-0.5..0.5) * ty * depth;
        let p = camera.position + forward * depth + right * x + up * y;
        drawn.lights.push(p, r);
        drawn.beyond += u32::from(depth - r > grid.far());
        drawn.before += u32::from(depth + r < grid.near());
        drawn.reach = drawn.reach.max(depth + r);
    }
    drawn
}

/// Depths and radii of lights reaching far past a grid out to 40.
const FAR_FIELD: (Range<f32>, Range<f32>) = (1.0..150.0, 0.3..3.0);

fn camera(far: f32) -> Camera {
    Camera::new(
        Vec3::new(3.0, 2.0, 1.0),
        Vec3::new(3.5, 1.0, -20.0),
        Vec3::Y,
        60.0,
        1280,
        720,
        0.1,
        far,
    )
}

/// A camera at the origin looking down −Z (its view transform is exact) over `[near, far]`.
fn axis_camera(near: f32, far: f32) -> Camera {
    Camera::new(
        Vec3::ZERO,
        Vec3::NEG_Z,
        Vec3::Y,
        60.0,
        1920,
        1080,
        near,
        far,
    )
}

/// A camera whose near plane lies beyond the grid's near clips the lights in front of it:
/// `reach` counts the lights in view only (a light wholly nearer than the camera's near gave
/// the reach; the grid's open first slice still lists it, conservatively).
#[test]
fn reach_leaves_out_lights_nearer_than_the_cameras_near() {
    let camera = Camera {
        near: 1.0,
        ..camera(f32::INFINITY)
    };
    let grid = ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, 0.1, 50.0);
    let (_, _, forward) = view_basis(&camera);
    let mut lights = Columns::default();
    lights.push(camera.position + forward * 0.5, 0.2);
    for method in Method::ALL {
        let mut lists = LightLists::new();
        let stats = assign(method, &lights, false, &camera, &grid, &mut lists);
        assert_eq!(stats.reach, Some(0.0), "{method}: only a clipped light");
        let mut with_one_in_view = lights.clone();
        with_one_in_view.push(camera.position + forward * 3.0, 0.5);
        let stats = assign(method, &with_one_in_view, false, &camera, &grid, &mut lists);
        let reach = stats.reach.expect("the camera sees past the grid");
        assert!(
            (3.5..3.5 * (1.0 + 1e-5)).contains(&reach),
            "{method}: {reach}"
        );
    }
}

/// One frame of `method` by a fresh assigner, into `lists`.
fn assign(
    method: Method,
    lights: &Columns,
    spots: bool,
    camera: &Camera,
    grid: &ClusterGrid,
    lists: &mut LightLists,
) -> AssignStats {
    Assigner::new().assign(method, &lights.input(spots), camera, grid, lists)
}

#[test]
fn lights_past_the_grid_but_in_view_are_counted_by_every_method_and_reach_covers_them() {
    for (far, edge) in [f32::INFINITY, 400.0]
        .into_iter()
        .flat_map(|far| [(far, OuterSlices::Open), (far, OuterSlices::Closed)])
    {
        let camera = camera(far);
        let grid = ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, 0.1, 40.0)
            .with_outer_slices(edge);
        let last_slice = grid.dims().x * grid.dims().y * (grid.dims().z - 1);
        // 300 lights run as one task; 6000 as several (tasks count their own and are summed).
        for (n, seed) in [(300, 1), (6000, 2)] {
            let drawn = lights_in_view(&camera, n, FAR_FIELD, &grid, seed);
            let (mut lights, beyond, reach) = (drawn.lights, drawn.beyond, drawn.reach);
            // Invalid lights past the grid are rejected, never counted as beyond it (a radius
            // of 0 or −1 at a finite position passed the camera's cull unless checked).
            let (_, _, forward) = view_basis(&camera);
            for r in [0.0, -1.0, f32::NAN] {
                lights.push(camera.position + forward * 80.0, r);
            }
            assert!(
                beyond > n as u32 / 2,
                "the draw puts most lights past the grid"
            );
            for method in Method::ALL {
                let mut lists = LightLists::new();
                let stats = assign(method, &lights, false, &camera, &grid, &mut lists);
                let what = format!("{method}, far {far}, {edge:?}, {n} lights");
                assert_eq!(stats.rejected, 3, "{what}");
                assert_eq!(stats.beyond_far, beyond, "{what}");
                // Open: every light in view is listed, those past the grid in its last slice
                // only. Closed: those are culled and listed nowhere.
                let listed = |l: u32| {
                    let clusters = (0..grid.cluster_count() as u32)
                        .filter(|&c| lists.lights_of(c as usize).contains(&l));
                    clusters.fold(None, |first: Option<u32>, c| {
                        Some(first.map_or(c, |f| f.min(c)))
                    })
                };
                for l in 0..n {
                    let p = Vec3::new(lights.x[l], lights.y[l], lights.z[l]);
                    let depth = (p - camera.position).dot(forward);
                    if depth - lights.radius[l] > grid.far() + 0.01 {
                        match (edge, listed(l as u32)) {
                            (OuterSlices::Open, Some(first)) => {
                                assert!(
                                    first >= last_slice,
                                    "{what}: light {l} before the last slice"
                                );
                            }
                            (OuterSlices::Closed, None) => {}
                            (_, got) => panic!("{what}: light {l} past the grid listed at {got:?}"),
                        }
                    }
                }
                match edge {
                    OuterSlices::Open => assert_eq!(stats.visible(), n as u32, "{what}: {stats:?}"),
                    OuterSlices::Closed => assert!(stats.culled >= beyond, "{what}: {stats:?}"),
                }
                let got = stats.reach.expect("the camera sees past the grid");
                // The padded sphere's far side: the exact reach, or a hair beyond it.
                assert!(
                    got >= reach && got <= reach * (1.0 + 1e-5),
                    "{what}: reach {got}, want {reach}"
                );
                // A grid out to that reach leaves no light beyond it and lists every light.
                let covering = ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, 0.1, got)
                    .with_outer_slices(edge);
                let stats = assign(method, &lights, false, &camera, &covering, &mut lists);
                assert_eq!(stats.beyond_far, 0, "{what}: {stats:?}");
                assert_eq!(stats.visible(), n as u32, "{what}: {stats:?}");
                assert_eq!(stats.rejected, 3, "{what}: {stats:?}");
                assert_eq!(
                    stats.reach,
                    Some(got),
                    "{what}: the same lights reach as far"
                );
            }
        }
    }
}

#[test]
fn a_grid_that_reaches_the_cameras_far_counts_nothing_beyond_it() {
    let camera = camera(60.0);
    let grid = ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, 0.1, 60.0);
    let lights = lights_in_view(&camera, 2000, FAR_FIELD, &grid, 3).lights;
    for method in Method::ALL {
        let stats = assign(
            method,
            &lights,
            false,
            &camera,
            &grid,
            &mut LightLists::new(),
        );
        assert!(stats.culled > 0, "{method}: lights past the camera's far");
        assert_eq!(
            (stats.beyond_far, stats.before_near, stats.reach),
            (0, 0, None),
            "{method}"
        );
    }
}

/// Spot lights are counted with the bounding sphere the cull uses, the same by every method
/// (their reference is `linear`'s, the paper's algorithm, computed apart), for any thread count.
#[test]
fn spots_and_thread_counts_give_the_same_counts() {
    let camera = camera(f32::INFINITY);
    // Nearer than the camera sees too, so that both counts are compared.
    let grid = ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, 4.0, 40.0);
    let mut lights = lights_in_view(&camera, 3000, (0.2..150.0, 0.1..3.0), &grid, 4).lights;
    let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
    for i in 0..lights.len() {
        let dir = random_dir(&mut rng);
        (lights.dir_x[i], lights.dir_y[i], lights.dir_z[i]) = (dir.x, dir.y, dir.z);
        lights.angle[i] = rng.random_range(0.1..1.5);
    }
    let reference = assign(
        Method::Linear,
        &lights,
        true,
        &camera,
        &grid,
        &mut LightLists::new(),
    );
    assert!(reference.beyond_far > 100, "{reference:?}");
    assert!(reference.before_near > 10, "{reference:?}");
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        for method in [Method::Binary, Method::Refined, Method::Cone] {
            let stats = pool.install(|| {
                assign(
                    method,
                    &lights,
                    true,
                    &camera,
                    &grid,
                    &mut LightLists::new(),
                )
            });
            let what = format!("{method}, {threads} threads");
            assert_eq!(stats.beyond_far, reference.beyond_far, "{what}");
            assert_eq!(stats.before_near, reference.before_near, "{what}");
            assert_eq!(stats.reach, reference.reach, "{what}");
        }
    }
}

/// The radius of a light on the view axis at `depth` whose padded sphere's near side
/// (`sign` −1) or far side (+1) lies exactly at `plane` (both builds of the tasks pad as
/// `pad_radius` does: neither fuses a multiply-add).
fn radius_touching(depth: f32, plane: f32, sign: f32) -> f32 {
    let side = |r: f32| depth + sign * myriad_cluster_math::pad_radius(0.0, 0.0, depth, r);
    let mut r = (plane - depth).abs();
    while sign * (side(r) - plane) < 0.0 {
        r = r.next_up();
    }
    while sign * (side(r) - plane) > 0.0 {
        r = r.next_down();
    }
    assert_eq!(side(r), plane, "no radius lands exactly on the plane");
    r
}

/// `lights` assigned by every method through `camera` onto `grid(outer)` for both kinds of outer
/// slices, each frame's stats given to `check`.
fn every_frame(
    lights: &Columns,
    camera: &Camera,
    grid: impl Fn(OuterSlices) -> ClusterGrid,
    check: impl Fn(OuterSlices, Method, AssignStats),
) {
    for outer in [OuterSlices::Open, OuterSlices::Closed] {
        let grid = grid(outer);
        for method in Method::ALL {
            let stats = assign(method, lights, false, camera, &grid, &mut LightLists::new());
            check(outer, method, stats);
        }
    }
}

/// A light whose padded sphere ends exactly on the grid's far plane touches the last slice:
/// a closed grid keeps it, so it is not beyond the grid (`beyond_far` counts lights wholly past
/// it, the ones a closed grid culls), by every method.
#[test]
fn a_light_touching_the_far_plane_is_not_beyond_it() {
    let camera = axis_camera(0.1, f32::INFINITY);
    let (depth, far) = (50.0, 40.0);
    let mut lights = Columns::default();
    // The view transform of this camera is exact: depth 50 stays 50.
    lights.push(
        Vec3::new(0.0, 0.0, -depth),
        radius_touching(depth, far, -1.0),
    );
    let grid = |outer| {
        ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, 0.1, far)
            .with_outer_slices(outer)
    };
    every_frame(&lights, &camera, grid, |outer, method, stats| {
        let what = format!("{method}, {outer:?}: {stats:?}");
        assert_eq!((stats.beyond_far, stats.culled), (0, 0), "{what}");
    });
}

/// The near-side twin of the test above: a light whose padded sphere ends exactly on the grid's
/// near plane touches the first slice, so it is not before the grid.
#[test]
fn a_light_touching_the_near_plane_is_not_before_it() {
    let camera = axis_camera(0.1, 60.0);
    let (depth, near) = (2.0, 5.0);
    let r = radius_touching(depth, near, 1.0);
    let mut lights = Columns::default();
    lights.push(Vec3::new(0.0, 0.0, -depth), r);
    // And one a little smaller, wholly before the grid: counted, and culled by a closed grid.
    // (One a step smaller, `r.next_down()`, can round to the same padded far side.)
    lights.push(Vec3::new(0.0, 0.0, -depth), r * 0.9999);
    let grid = |outer| {
        ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, near, 60.0)
            .with_outer_slices(outer)
    };
    every_frame(&lights, &camera, grid, |outer, method, stats| {
        let what = format!("{method}, {outer:?}: {stats:?}");
        let culled = u32::from(outer == OuterSlices::Closed);
        assert_eq!((stats.before_near, stats.culled), (1, culled), "{what}");
    });
}

/// A camera that sees nearer than the grid (a depth range fitted to the depth buffer, a grid
/// starting at 5 m): the lights wholly nearer than the grid's near are counted
/// (`AssignStats::before_near`) by every method, listed in the first slice only where it is
/// open and culled where it is closed; with the far side seen too, both counts are right.
#[test]
fn lights_before_the_grid_but_in_view_are_counted_by_every_method() {
    for (camera_far, grid_far) in [(60.0, 60.0), (f32::INFINITY, 40.0)] {
        for edge in [OuterSlices::Open, OuterSlices::Closed] {
            let camera = camera(camera_far);
            let grid = ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, 5.0, grid_far)
                .with_outer_slices(edge);
            let first_slice = grid.dims().x * grid.dims().y;
            for (n, seed) in [(300, 6), (6000, 7)] {
                let drawn = lights_in_view(&camera, n, (0.2..50.0, 0.05..2.0), &grid, seed);
                let mut lights = drawn.lights;
                // Invalid lights before the grid are rejected, never counted.
                let (right, up, forward) = view_basis(&camera);
                for r in [0.0, -1.0, f32::NAN] {
                    lights.push(camera.position + forward * 1.0, r);
                }
                // Lights before the grid but out of view are culled, never counted: beside or
                // above the view, wholly nearer than the camera's near plane, behind the eye.
                let (tx, ty) = camera.tan_half_fov().into();
                let eye = camera.position;
                lights.push(eye + forward * 2.0 + right * (2.0 * tx * 2.0 + 0.5), 0.2);
                lights.push(eye + forward * 2.0 - up * (2.0 * ty * 2.0 + 0.5), 0.2);
                lights.push(eye + forward * 0.05, 0.02);
                lights.push(eye - forward * 1.0, 0.5);
                assert!(drawn.before > n as u32 / 20, "{}", drawn.before);
                assert!(drawn.beyond > 0 || grid_far == camera_far);
                for method in Method::ALL {
                    let mut lists = LightLists::new();
                    let stats = assign(method, &lights, false, &camera, &grid, &mut lists);
                    let what = format!("{method}, far {camera_far}, {edge:?}, {n} lights");
                    assert_eq!(stats.rejected, 3, "{what}");
                    assert!(stats.culled >= 4, "{what}: {stats:?}");
                    assert_eq!(stats.before_near, drawn.before, "{what}");
                    assert_eq!(stats.beyond_far, drawn.beyond, "{what}");
                    assert_eq!(stats.reach.is_some(), camera_far > grid_far, "{what}");
                    // Each light before the grid, by itself: a method that listed some of them
                    // in many tiles and dropped others passed a count of pairs.
                    let mut listed_before = std::collections::BTreeSet::new();
                    for c in 0..grid.cluster_count() {
                        for &l in lists.lights_of(c) {
                            let p = Vec3::new(
                                lights.x[l as usize],
                                lights.y[l as usize],
                                lights.z[l as usize],
                            );
                            let depth = (p - camera.position).dot(forward);
                            if depth + lights.radius[l as usize] < grid.near() - 0.01 {
                                assert!(
                                    c < first_slice as usize,
                                    "{what}: light {l} before the grid listed in cluster {c}"
                                );
                                listed_before.insert(l);
                            }
                        }
                    }
                    let before: std::collections::BTreeSet<u32> = (0..n as u32)
                        .filter(|&l| {
                            let i = l as usize;
                            let p = Vec3::new(lights.x[i], lights.y[i], lights.z[i]);
                            let depth = (p - camera.position).dot(forward);
                            depth + lights.radius[i] < grid.near()
                        })
                        .collect();
                    assert_eq!(before.len() as u32, drawn.before, "{what}");
                    match edge {
                        OuterSlices::Open => {
                            assert_eq!(listed_before, before, "{what}");
                            assert_eq!(stats.visible(), n as u32, "{what}: {stats:?}");
                        }
                        OuterSlices::Closed => {
                            assert!(listed_before.is_empty(), "{what}: {listed_before:?}");
                            let outside = drawn.before + drawn.beyond;
                            assert!(stats.culled >= outside, "{what}: {stats:?}");
                        }
                    }
                }
            }
        }
    }
}

/// Open outer slices read the camera's near and far, so a placeholder depth range (an engine that
/// builds its `Camera` for the assignment alone) is refused instead of silently closing the
/// last slice: with `far: 0.0` a light past the grid was missing from its pixels with `Ok`
/// (engine audit). A closed grid reads neither and takes such a camera.
#[test]
fn an_open_grid_refuses_a_placeholder_depth_range() {
    let grid = ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, 1.0, 50.0);
    let mut lights = Columns::default();
    lights.push(Vec3::new(0.0, 0.0, -100.0), 10.0);
    lights.push(Vec3::new(0.0, 0.0, -20.0), 1.0);
    let past = grid.cluster_of_pixel(960, 540, 100.0, 1920, 1080) as usize;
    let mut lists = LightLists::new();
    let good = Assigner::new().try_assign(
        Method::Refined,
        &lights.input(false),
        &axis_camera(0.1, f32::INFINITY),
        &grid,
        &mut lists,
    );
    assert!(good.is_ok(), "{good:?}");
    assert_eq!(lists.lights_of(past), &[0]);
    for (near, far) in [
        (0.1, 0.0),
        (0.1, f32::NAN),
        (f32::NAN, f32::NAN),
        (0.0, 100.0),
        (-1.0, 100.0),
        (60.0, 60.0),
        (f32::INFINITY, f32::INFINITY),
    ] {
        let what = format!("near {near}, far {far}");
        let mut lists = LightLists::new();
        let input = lights.input(false);
        let camera = axis_camera(near, far);
        let assign_on = |grid: &ClusterGrid, lists: &mut LightLists| {
            Assigner::new().try_assign(Method::Refined, &input, &camera, grid, lists)
        };
        let err = assign_on(&grid, &mut lists).expect_err(&what);
        assert!(
            err.0.contains("OuterSlices::Closed") && err.0.contains(&format!("[{near}, {far}]")),
            "{what}: {err}"
        );
        assert_eq!(lists.cluster_count(), 0, "{what}: the output is untouched");
        let closed = grid.with_outer_slices(OuterSlices::Closed);
        let stats = assign_on(&closed, &mut lists).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!(
            (stats.visible(), lists.lights_of(past)),
            (1, &[][..]),
            "{what}"
        );
    }
}
