//! What the math crate refuses, and how: invalid grids ([`ClusterGrid::try_new`] errors, `new`
//! panics with the same message), unusable cameras ([`Camera::problem`]) and pixels outside the
//! target — each the kind of value an engine may take from user settings.

use glam::{UVec3, Vec3};
use myriad_cluster_math::{Camera, ClusterGrid, DepthSlicing};

#[test]
fn invalid_grids_are_errors_from_try_new_and_panics_from_new() {
    let log = DepthSlicing::Log;
    let near_slice = DepthSlicing::LogWithNearSlice {
        first_slice_depth: 50.0,
    };
    for (dims, slicing, near, far, needle) in [
        (UVec3::new(0, 12, 16), log, 0.1, 100.0, "dimensions"),
        (UVec3::new(24, 12, 16), log, 0.0, 100.0, "0 < near < far"),
        (UVec3::new(24, 12, 16), log, 1.0, 1.0, "0 < near < far"),
        (
            UVec3::new(24, 12, 16),
            log,
            f32::NAN,
            100.0,
            "0 < near < far",
        ),
        (
            UVec3::new(24, 12, 16),
            log,
            0.1,
            f32::INFINITY,
            "with both finite (a camera with an infinite far plane needs a grid with a finite far",
        ),
        (
            UVec3::new(24, 12, 16),
            near_slice,
            0.1,
            20.0,
            "first_slice_depth",
        ),
        (UVec3::new(65536, 65536, 2), log, 0.1, 100.0, "u32 id"),
        (UVec3::new(2, 65536, 65536), log, 0.1, 100.0, "u32 id"),
        (UVec3::new(65536, 2, 65536), log, 0.1, 100.0, "u32 id"),
        // The product passes u64 too: it wrapped to 0 clusters and was accepted (audit).
        (
            UVec3::new(1 << 22, 1 << 21, 1 << 21),
            log,
            0.1,
            100.0,
            "u32 id",
        ),
        (
            UVec3::new(1 << 22, 1 << 22, 1 << 20),
            log,
            0.1,
            100.0,
            "u32 id",
        ),
        (UVec3::splat(u32::MAX), log, 0.1, 100.0, "u32 id"),
        (UVec3::new(24, 12, 16), log, 1e-22, 1e-16, "at least 1e-12"),
        (
            UVec3::new(24, 12, 16),
            log,
            ClusterGrid::MIN_NEAR.next_down(),
            1.0,
            "MIN_NEAR",
        ),
    ] {
        let e = ClusterGrid::try_new(dims, slicing, near, far).unwrap_err();
        assert!(
            e.to_string().contains(needle),
            "{dims} [{near}, {far}]: {e}"
        );
        let panic = std::panic::catch_unwind(|| ClusterGrid::new(dims, slicing, near, far))
            .expect_err("new panics where try_new fails");
        let message = panic.downcast_ref::<String>().expect("a formatted message");
        assert_eq!(message, &e.to_string());
    }
    assert!(ClusterGrid::try_new(UVec3::new(24, 12, 16), log, ClusterGrid::MIN_NEAR, 1e-6).is_ok());
    // The largest grid: 65 535 × 65 537 = u32::MAX clusters, the last id u32::MAX − 1.
    let largest = ClusterGrid::try_new(UVec3::new(65535, 65537, 1), log, 0.1, 100.0).unwrap();
    assert_eq!(largest.cluster_count(), u32::MAX as usize);
    // The first slice edge must lie strictly inside the range: at `near` or `far` one slice
    // would have zero thickness.
    for edge in [0.1, 100.0] {
        let at_edge = DepthSlicing::LogWithNearSlice {
            first_slice_depth: edge,
        };
        let e = ClusterGrid::try_new(UVec3::new(24, 12, 16), at_edge, 0.1, 100.0).unwrap_err();
        assert!(e.to_string().contains("first_slice_depth"), "{edge}: {e}");
    }
    // With one slice the edge is not used, but a NaN one is still refused: the grid would not
    // equal itself, and every "is this mask, this upload for this grid" check would fail on it
    // (`ActiveClusters::is_for` panicked the assignment, API review).
    let nan_edge = DepthSlicing::LogWithNearSlice {
        first_slice_depth: f32::NAN,
    };
    for z in [1, 16] {
        let e = ClusterGrid::try_new(UVec3::new(24, 12, z), nan_edge, 0.1, 100.0).unwrap_err();
        assert!(
            e.to_string().contains("first_slice_depth NaN"),
            "Z = {z}: {e}"
        );
    }
    let unused_edge = DepthSlicing::LogWithNearSlice {
        first_slice_depth: 1e6,
    };
    assert!(ClusterGrid::try_new(UVec3::new(24, 12, 1), unused_edge, 0.1, 100.0).is_ok());
    let ok = ClusterGrid::try_new(UVec3::new(24, 12, 16), near_slice, 0.1, 100.0).unwrap();
    assert_eq!(
        ok,
        ClusterGrid::new(UVec3::new(24, 12, 16), near_slice, 0.1, 100.0)
    );
    // A measured depth range: a scene wholly nearer than the first slice edge, or all at one
    // depth, is an error from `try_with_depth_range` (`with_depth_range` panics with it).
    for (near, far, fragment) in [(0.2, 4.0, "first_slice_depth"), (3.0, 3.0, "near < far")] {
        let e = ok.try_with_depth_range(near, far).unwrap_err().to_string();
        assert!(e.contains(fragment), "[{near}, {far}]: {e}");
    }
    let fitted = ok.try_with_depth_range(0.5, 80.0).unwrap();
    assert_eq!((fitted.dims(), fitted.slicing()), (ok.dims(), ok.slicing()));
    assert_eq!((fitted.near(), fitted.far()), (0.5, 80.0));
}

#[test]
fn camera_problems_are_named() {
    let good = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 64, 32, 0.1, 100.0);
    assert_eq!(good.problem(), None);
    // Degenerate directions have fallbacks: not problems.
    let same_point = Camera {
        target: Vec3::ZERO,
        up: Vec3::ZERO,
        ..good
    };
    assert_eq!(same_point.problem(), None);
    for (camera, needle) in [
        (
            Camera {
                fov_y: f32::NAN,
                ..good
            },
            "field of view",
        ),
        (Camera { fov_y: 0.0, ..good }, "field of view"),
        (
            Camera {
                fov_y: std::f32::consts::PI,
                ..good
            },
            "field of view",
        ),
        (Camera { height: 0, ..good }, "at least 1x1"),
        (Camera { width: 0, ..good }, "at least 1x1"),
        // Slopes below f32's normal range: 1e-36° (a blank image on llvmpipe, exit 0), and a
        // normal vertical slope made subnormal across by a 1-pixel-wide target.
        (
            Camera {
                fov_y: 1e-36f32.to_radians(),
                ..good
            },
            "outside f32's normal range",
        ),
        (
            Camera {
                fov_y: 3e-38,
                width: 1,
                height: 1000,
                ..good
            },
            "outside f32's normal range",
        ),
        (
            Camera {
                position: Vec3::NAN,
                ..good
            },
            "finite",
        ),
        (
            Camera {
                target: Vec3::INFINITY,
                ..good
            },
            "finite",
        ),
        (Camera { near: 0.0, ..good }, "0 < near < far"),
        // An empty depth range (near == far) is refused too, not only a reversed one.
        (
            Camera {
                near: 100.0,
                ..good
            },
            "0 < near < far",
        ),
        // Depth from the depth buffer would be infinite (audit g3).
        (
            Camera {
                near: 1e19,
                far: 1e20,
                ..good
            },
            "overflows f32",
        ),
        (
            Camera {
                far: f32::NAN,
                ..good
            },
            "0 < near < far",
        ),
        (
            Camera {
                near: f32::INFINITY,
                far: f32::INFINITY,
                ..good
            },
            "0 < near < far",
        ),
        // The grids' floor: the renderer drew wrong or no pixels below ~1e-33 (audit).
        (
            Camera {
                near: ClusterGrid::MIN_NEAR.next_down(),
                ..good
            },
            "ClusterGrid::MIN_NEAR",
        ),
    ] {
        let problem = camera.problem().expect("a problem");
        assert!(problem.contains(needle), "{camera:?}: {problem}");
        // The view alone ignores the depth range (assignment slices by the grid's).
        let depth = ["0 < near < far", "overflows f32", "ClusterGrid::MIN_NEAR"].contains(&needle);
        assert_eq!(camera.view_problem().is_none(), depth, "{camera:?}");
    }
    // The floor itself is allowed, as grids allow it (mutation audit: `<=` passed the suite).
    let at_floor = Camera {
        near: ClusterGrid::MIN_NEAR,
        ..good
    };
    assert_eq!(at_floor.problem(), None);
    // An infinite far plane (reversed-Z engines, `Camera::from_matrices`) renders: the stored
    // depth is `near / depth` (`Camera::clip_from_view`); no `near·far` to overflow.
    for near in [ClusterGrid::MIN_NEAR, 0.1, 1e19] {
        let infinite = Camera {
            near,
            far: f32::INFINITY,
            ..good
        };
        assert_eq!(infinite.problem(), None, "near {near}");
    }
}

#[test]
fn a_pixel_outside_the_target_is_refused() {
    let grid = ClusterGrid::new(UVec3::new(4, 4, 4), DepthSlicing::Log, 0.1, 100.0);
    for (x, y, w, h) in [(64, 0, 64, 32), (0, 32, 64, 32), (0, 0, 0, 32)] {
        let r = std::panic::catch_unwind(|| grid.cluster_of_pixel(x, y, 1.0, w, h));
        assert!(r.is_err(), "pixel ({x}, {y}) of {w}x{h}");
    }
    assert!(grid.cluster_of_pixel(63, 31, 1.0, 64, 32) < grid.cluster_count() as u32);
}

#[test]
fn checked_cluster_ids_refuse_tiles_off_the_grid() {
    let grid = ClusterGrid::new(UVec3::new(4, 3, 2), DepthSlicing::Log, 0.1, 100.0);
    assert_eq!(grid.checked_cluster_id(3, 2, 1), Some(23));
    assert_eq!(
        grid.checked_cluster_id(1, 2, 0),
        Some(grid.cluster_id(1, 2, 0))
    );
    // Unchecked, (4, 0, 0) is cluster (0, 1, 0)'s id.
    for (i, j, k) in [(4, 0, 0), (0, 3, 0), (0, 0, 2), (u32::MAX, 0, 0)] {
        assert_eq!(grid.checked_cluster_id(i, j, k), None, "({i}, {j}, {k})");
    }
}

#[test]
fn a_camera_is_the_same_as_itself_even_with_a_nan_up() {
    let camera = Camera::new(Vec3::ONE, Vec3::ZERO, Vec3::NAN, 60.0, 640, 480, 0.1, 100.0);
    assert!(camera.problem().is_none());
    assert_ne!(camera, camera, "NaN ≠ NaN: why `same_as` exists");
    assert!(camera.same_as(&camera));
    let signed_zero = Camera {
        target: Vec3::new(-0.0, 0.0, -0.0),
        ..camera
    };
    assert!(camera.same_as(&signed_zero), "-0.0 is 0.0");
    for change in [
        |c: &mut Camera| c.position.x += 1e-6,
        |c: &mut Camera| c.target.y = 0.5,
        |c: &mut Camera| c.up = Vec3::Y,
        |c: &mut Camera| c.fov_y *= 1.0 + f32::EPSILON,
        |c: &mut Camera| c.width += 1,
        |c: &mut Camera| c.height -= 1,
        |c: &mut Camera| c.near = 0.2,
        |c: &mut Camera| c.far = f32::INFINITY,
    ] {
        let mut other = camera;
        change(&mut other);
        assert!(!camera.same_as(&other), "{other:?}");
    }
}
