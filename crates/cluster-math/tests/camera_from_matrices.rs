//! `Camera::from_matrices`: an engine's matrices read back into the camera they describe, so its
//! pixels and the clusters agree; and each pair no camera can describe refused with its reason.

use glam::camera::{lh, rh};
use glam::{Mat4, Vec3, vec3};
use myriad_cluster_math::{Camera, CameraMatrixError, ClipSpace};
use proptest::prelude::*;

/// NDC (x, y, depth) of a world point under `clip_from_world`.
fn ndc(clip_from_world: Mat4, world: Vec3) -> Vec3 {
    let clip = clip_from_world * world.extend(1.0);
    clip.truncate() / clip.w
}

/// Points in front of a camera at the origin looking down −Z, spread over the frustum and depth.
fn points_in_front(eye: Vec3, forward: Vec3, right: Vec3, up: Vec3) -> Vec<Vec3> {
    let mut points = Vec::new();
    for depth in [0.5f32, 3.0, 40.0] {
        for (x, y) in [(0.0, 0.0), (0.3, -0.2), (-0.25, 0.15), (0.1, 0.3)] {
            points.push(eye + forward * depth + right * (x * depth) + up * (y * depth));
        }
    }
    points
}

/// Each point lands at the same NDC x and y under the engine's matrices as its image under
/// `to_camera_world` does under the camera (depth conventions may differ between the two).
fn assert_same_screen(
    engine: Mat4,
    camera: &Camera,
    points: &[Vec3],
    to_camera_world: impl Fn(Vec3) -> Vec3,
) {
    for &p in points {
        let want = ndc(engine, p);
        let got = ndc(camera.clip_from_world(), to_camera_world(p));
        assert!(
            (want.truncate() - got.truncate()).abs().max_element() < 1e-4,
            "point {p}: engine NDC {want}, camera NDC {got}"
        );
    }
}

#[test]
fn glam_right_handed_pairs_give_the_camera_they_describe() {
    let eye = vec3(3.0, 4.0, -7.0);
    let view = rh::view::look_at_mat4(eye, vec3(0.0, 1.0, 2.0), Vec3::Y);
    let forward = (vec3(0.0, 1.0, 2.0) - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let points = points_in_front(eye, forward, right, up);
    let fov = 50f32.to_radians();
    let aspect = 1920.0 / 1080.0;

    let cases = [
        (
            rh::proj::directx::perspective(fov, aspect, 0.1, 500.0),
            ClipSpace::ZeroToOneYUp,
            500.0,
        ),
        (
            rh::proj::opengl::perspective(fov, aspect, 0.1, 500.0),
            ClipSpace::MinusOneToOneYUp,
            500.0,
        ),
        (
            rh::proj::directx::perspective_infinite(fov, aspect, 0.1),
            ClipSpace::ZeroToOneYUp,
            f32::INFINITY,
        ),
        (
            rh::proj::directx::perspective_infinite_reverse(fov, aspect, 0.1),
            ClipSpace::ZeroToOneYUp,
            f32::INFINITY,
        ),
    ];
    for (projection, depth, far) in cases {
        let camera = Camera::from_matrices(view, projection, depth, 1920, 1080)
            .unwrap_or_else(|e| panic!("{projection}: {e}"));
        assert!(
            (camera.position - eye).abs().max_element() < 1e-5,
            "{camera:?}"
        );
        assert!((camera.fov_y - fov).abs() < 1e-6, "{camera:?}");
        assert!((camera.near - 0.1).abs() < 1e-6, "{camera:?}");
        if far.is_finite() {
            assert!((camera.far / far - 1.0).abs() < 1e-4, "{camera:?}");
        } else {
            assert_eq!(camera.far, far, "{projection}");
        }
        // Infinite far planes too: the renderer draws with them.
        assert!(camera.problem().is_none(), "{camera:?}");
        assert_same_screen(projection * view, &camera, &points, |p| p);
    }
    // The crate's own projection is glam's infinite reversed-Z one for such a camera, entry for
    // entry: what an engine's depth buffer holds is what the renderer's holds.
    let infinite = rh::proj::directx::perspective_infinite_reverse(fov, aspect, 0.1);
    let camera =
        Camera::from_matrices(view, infinite, ClipSpace::ZeroToOneYUp, 1920, 1080).unwrap();
    let ours = camera.clip_from_view();
    for (got, want) in ours.to_cols_array().iter().zip(infinite.to_cols_array()) {
        assert!(
            (got - want).abs() <= 1e-6 * want.abs().max(1.0),
            "{ours} against {infinite}"
        );
    }
}

#[test]
fn a_y_down_projection_is_the_same_camera_when_named_so() {
    let view = rh::view::look_at_mat4(vec3(1.0, 5.0, 2.0), vec3(0.0, 0.0, -3.0), Vec3::Y);
    let (fov, aspect) = (1.1, 1536.0 / 768.0);
    let y_up = rh::proj::directx::perspective(fov, aspect, 0.2, 90.0);
    let y_down = rh::proj::vulkan::perspective(fov, aspect, 0.2, 90.0);
    let want = Camera::from_matrices(view, y_up, ClipSpace::ZeroToOneYUp, 1536, 768).unwrap();
    let got = Camera::from_matrices(view, y_down, ClipSpace::ZeroToOneYDown, 1536, 768).unwrap();
    assert_close(&got, &want);
    // Read as y up, the Vulkan matrix shows the world upside down and mirrored: refused, and
    // the message names the right fix first. (It named only the left-handed one, whose mirrored
    // world then gave a camera upside down with Ok: an engine audit followed it.)
    let refused = Camera::from_matrices(view, y_down, ClipSpace::ZeroToOneYUp, 1536, 768);
    assert_eq!(refused, Err(CameraMatrixError::Mirrored));
    let message = refused.unwrap_err().to_string();
    assert!(
        message.contains("y-down") && message.contains("ClipSpace::ZeroToOneYDown"),
        "{message}"
    );
}

#[test]
fn this_crates_own_matrices_round_trip_at_the_edges() {
    let cameras = [
        Camera::new(
            Vec3::ZERO,
            Vec3::NEG_Z,
            Vec3::Y,
            60.0,
            1920,
            1080,
            0.1,
            100.0,
        ),
        // Narrow and wide fields of view, extreme depth ranges, tall and 1-pixel targets.
        Camera::new(
            vec3(1.0, 2.0, 3.0),
            vec3(4.0, 2.0, -9.0),
            Vec3::Y,
            0.01,
            640,
            480,
            1e-3,
            1e6,
        ),
        Camera::new(
            vec3(-5.0, 0.0, 2.0),
            vec3(0.0, 0.0, 2.0),
            Vec3::Z,
            179.0,
            300,
            900,
            1e-6,
            1.0,
        ),
        Camera::new(
            Vec3::ZERO,
            vec3(0.0, -1.0, 0.0),
            Vec3::Y,
            45.0,
            1,
            1,
            0.5,
            2.0,
        ),
        // Looking straight down (the fallback up), and a rolled camera.
        Camera::new(
            vec3(0.0, 10.0, 0.0),
            Vec3::ZERO,
            Vec3::Y,
            70.0,
            1536,
            768,
            0.05,
            80.0,
        ),
        Camera::new(
            Vec3::ZERO,
            Vec3::X,
            vec3(0.0, 1.0, 1.0),
            70.0,
            800,
            600,
            0.05,
            80.0,
        ),
    ];
    for original in cameras {
        let camera = Camera::from_matrices(
            original.view_from_world(),
            original.clip_from_view(),
            ClipSpace::ZeroToOneYUp,
            original.width,
            original.height,
        )
        .unwrap_or_else(|e| panic!("{original:?}: {e}"));
        assert_close(&camera, &original);
        let (r, u, f) = original.basis_f64();
        let points = points_in_front(original.position, f.as_vec3(), r.as_vec3(), u.as_vec3());
        assert_same_screen(original.clip_from_world(), &camera, &points, |p| p);
    }
}

fn assert_close(camera: &Camera, original: &Camera) {
    let scale = original.position.abs().max_element().max(1.0);
    assert!(
        (camera.position - original.position).abs().max_element() <= 1e-6 * scale,
        "position {} vs {}",
        camera.position,
        original.position
    );
    let rotation = (camera.view_rotation_f64() - original.view_rotation_f64()).abs();
    let rotation_error = [rotation.x_axis, rotation.y_axis, rotation.z_axis]
        .iter()
        .map(|c| c.max_element())
        .fold(0.0, f64::max);
    assert!(
        rotation_error < 2e-6,
        "rotation off by {rotation_error}: {camera:?} vs {original:?}"
    );
    assert!(
        (camera.fov_y / original.fov_y - 1.0).abs() < 1e-5,
        "{camera:?} vs {original:?}"
    );
    assert!(
        (camera.near / original.near - 1.0).abs() < 1e-5,
        "{camera:?} vs {original:?}"
    );
    assert!(
        (camera.far / original.far - 1.0).abs() < 1e-3,
        "{camera:?} vs {original:?}"
    );
    assert_eq!(
        (camera.width, camera.height),
        (original.width, original.height)
    );
}

/// A narrow field of view has large scales, but the centre's shift is NDC all the same: a
/// half-pixel TAA jitter is refused at 0.02 rad as at 60°, and a tenth of it too.
#[test]
fn a_jitter_is_refused_however_narrow_the_view() {
    for fov in [0.02f32, 0.002] {
        let projection = rh::proj::directx::perspective(fov, 16.0 / 9.0, 0.1, 1000.0);
        let view = rh::view::look_at_mat4(vec3(1.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y);
        let read = |projection| {
            Camera::from_matrices(view, projection, ClipSpace::ZeroToOneYUp, 1920, 1080)
        };
        assert!(read(projection).is_ok(), "fov {fov}");
        for pixels in [0.5, 0.05] {
            let mut jittered = projection;
            jittered.z_axis.x = pixels * 2.0 / 1920.0;
            assert!(
                matches!(read(jittered), Err(CameraMatrixError::OffCenter { .. })),
                "fov {fov}, {pixels} px: {:?}",
                read(jittered)
            );
        }
    }
}

/// A view matrix scaled by a rounding's worth (accepted as rigid: it moves no pixel) gives the
/// eye where it is: read as −Rᵀ·t, a scale of 1.00004 at 10⁴ from the origin put it 0.8 off.
#[test]
fn a_view_scaled_by_rounding_keeps_the_eye() {
    let eye = vec3(0.0, 0.0, 10_000.0);
    let original = Camera::new(eye, Vec3::ZERO, Vec3::Y, 60.0, 1920, 1080, 0.1, 1000.0);
    for scale in [1.00004f32, 0.99996] {
        let view = Mat4::from_scale(Vec3::splat(scale)) * original.view_from_world();
        let camera = Camera::from_matrices(
            view,
            original.clip_from_view(),
            ClipSpace::ZeroToOneYUp,
            1920,
            1080,
        )
        .unwrap();
        assert!(
            camera.position.distance(eye) < 2e-3,
            "scale {scale}: eye read at {}",
            camera.position
        );
    }
}

#[test]
fn huge_world_coordinates_keep_the_view_direction() {
    // One unit ahead of a camera at 10⁶ would round the target by 0.06 m: a turned view.
    for position in [vec3(1e6, -2e6, 3e5), vec3(3e7, 0.0, 0.0)] {
        let original = Camera::new(
            position,
            position + vec3(0.3, 0.1, -1.0),
            Vec3::Y,
            60.0,
            1920,
            1080,
            0.1,
            1000.0,
        );
        let camera = Camera::from_matrices(
            original.view_from_world(),
            original.clip_from_view(),
            ClipSpace::ZeroToOneYUp,
            1920,
            1080,
        )
        .unwrap();
        assert_close(&camera, &original);
    }
}

#[test]
fn a_left_handed_pair_is_refused_as_mirrored_and_the_mirrored_world_works() {
    let (eye, at) = (vec3(2.0, 3.0, -6.0), vec3(0.0, 1.0, 0.0));
    let view = lh::view::look_at_mat4(eye, at, Vec3::Y);
    let projection = lh::proj::directx::perspective(1.0, 4.0 / 3.0, 0.1, 100.0);
    assert_eq!(
        Camera::from_matrices(view, projection, ClipSpace::ZeroToOneYUp, 800, 600),
        Err(CameraMatrixError::Mirrored)
    );
    // The fix the error names: mirror world x for the view matrix and for the points (lights).
    let mirror = Mat4::from_scale(vec3(-1.0, 1.0, 1.0));
    let camera =
        Camera::from_matrices(view * mirror, projection, ClipSpace::ZeroToOneYUp, 800, 600)
            .unwrap();
    let forward = (at - eye).normalize();
    let right = Vec3::Y.cross(forward).normalize();
    let up = forward.cross(right);
    let points = points_in_front(eye, forward, right, up);
    assert_same_screen(projection * view, &camera, &points, |p| {
        vec3(-p.x, p.y, p.z)
    });
}

#[test]
fn flipping_both_screen_axes_is_a_roll_and_one_alone_a_mirror() {
    let original = Camera::new(
        vec3(1.0, 1.0, 1.0),
        Vec3::ZERO,
        Vec3::Y,
        60.0,
        640,
        480,
        0.1,
        50.0,
    );
    let view = original.view_from_world();
    let flip = |x: f32, y: f32| Mat4::from_scale(vec3(x, y, 1.0)) * original.clip_from_view();
    let rolled = Camera::from_matrices(view, flip(-1.0, -1.0), ClipSpace::ZeroToOneYUp, 640, 480)
        .expect("a half turn about the view axis is a camera");
    let (r, u, f) = original.basis_f64();
    let points = points_in_front(original.position, f.as_vec3(), r.as_vec3(), u.as_vec3());
    assert_same_screen(flip(-1.0, -1.0) * view, &rolled, &points, |p| p);
    assert!(
        (rolled.up.normalize() + u.as_vec3()).length() < 1e-5,
        "{rolled:?}"
    );
    for (x, y) in [(1.0, -1.0), (-1.0, 1.0)] {
        assert_eq!(
            Camera::from_matrices(view, flip(x, y), ClipSpace::ZeroToOneYUp, 640, 480),
            Err(CameraMatrixError::Mirrored),
            "flip ({x}, {y})"
        );
    }
}

#[test]
fn matrices_no_camera_describes_are_refused_with_the_reason() {
    let original = Camera::new(
        vec3(1.0, 2.0, 3.0),
        Vec3::ZERO,
        Vec3::Y,
        60.0,
        640,
        480,
        0.1,
        50.0,
    );
    let (view, projection) = (original.view_from_world(), original.clip_from_view());
    let read = |view: Mat4, projection: Mat4| {
        Camera::from_matrices(view, projection, ClipSpace::ZeroToOneYUp, 640, 480)
    };

    // A TAA jitter of half a pixel: the NDC shift is reported.
    let mut jittered = projection;
    jittered.z_axis.x = 1.0 / 640.0;
    match read(view, jittered) {
        Err(CameraMatrixError::OffCenter { shift }) => {
            assert!(
                (shift[0] + 1.0 / 640.0).abs() < 1e-9 && shift[1] == 0.0,
                "{shift:?}"
            )
        }
        other => panic!("{other:?}"),
    }
    let orthographic = rh::proj::directx::orthographic(-1.0, 1.0, -0.75, 0.75, 0.1, 50.0);
    assert!(matches!(
        read(view, orthographic),
        Err(CameraMatrixError::NotPerspective(_))
    ));
    for (column, row) in [(0, 3), (1, 3), (3, 3), (0, 2), (1, 2), (0, 1)] {
        let mut mixed = projection;
        mixed.col_mut(column)[row] = 0.25;
        assert!(
            matches!(read(view, mixed), Err(CameraMatrixError::NotPerspective(_))),
            "entry of column {column}, row {row}: {:?}",
            read(view, mixed)
        );
    }
    for (column, row) in [(3, 0), (3, 1)] {
        let mut constant = projection;
        constant.col_mut(column)[row] = 0.25;
        assert!(matches!(
            read(view, constant),
            Err(CameraMatrixError::NotPerspective(_))
        ));
    }
    for scale in [(0.0, 1.0), (1.0, 0.0)] {
        let zeroed = Mat4::from_scale(vec3(scale.0, scale.1, 1.0)) * projection;
        assert!(matches!(
            read(view, zeroed),
            Err(CameraMatrixError::NotPerspective(_))
        ));
    }
    // A jitter under a thousandth of a pixel is rounding, not an off-centre projection.
    let mut rounding = projection;
    rounding.z_axis.x = 1e-5;
    assert!(read(view, rounding).is_ok());
    let mut sheared = projection;
    sheared.y_axis.x = 0.3;
    assert!(matches!(
        read(view, sheared),
        Err(CameraMatrixError::NotPerspective(_))
    ));

    let scaled = Mat4::from_scale(Vec3::splat(2.0)) * view;
    assert!(matches!(
        read(scaled, projection),
        Err(CameraMatrixError::NotRigid { .. })
    ));
    let mut projective = view;
    projective.x_axis.w = 0.01;
    assert!(matches!(
        read(projective, projection),
        Err(CameraMatrixError::NotRigid { .. })
    ));

    assert!(matches!(
        Camera::from_matrices(view, projection, ClipSpace::ZeroToOneYUp, 480, 480),
        Err(CameraMatrixError::AspectMismatch { .. })
    ));
    assert_eq!(
        Camera::from_matrices(view, projection, ClipSpace::ZeroToOneYUp, 0, 480),
        Err(CameraMatrixError::EmptyTarget)
    );
    // Infinite far planes a rounding away from exact: still infinite, not a negative far.
    let mut rounded = rh::proj::directx::perspective_infinite(1.0, 640.0 / 480.0, 0.1);
    rounded.z_axis.z *= 1.0 - f32::EPSILON;
    let mut rounded_reverse =
        rh::proj::directx::perspective_infinite_reverse(1.0, 640.0 / 480.0, 0.1);
    rounded_reverse.z_axis.z = -1e-9;
    // Depth that never falls to 0 (its limit at infinity is 0.5): nothing far is clipped.
    let mut half_used = rh::proj::directx::perspective_infinite_reverse(1.0, 640.0 / 480.0, 0.1);
    half_used.z_axis.z = -0.5;
    // (Depth 1, the near plane, is at 0.1 / (1 − 0.5) there.)
    for (projection, near) in [(rounded, 0.1), (rounded_reverse, 0.1), (half_used, 0.2)] {
        let camera = read(view, projection).unwrap_or_else(|e| panic!("{projection}: {e}"));
        assert_eq!(camera.far, f32::INFINITY, "{projection}");
        assert!((camera.near - near).abs() < 1e-6, "{camera:?}");
    }
    // An eye so far out that no f32 point lies in front of it.
    let far_out = Mat4::from_translation(vec3(-1e38, 0.0, 0.0));
    assert_eq!(
        read(far_out, projection),
        Err(CameraMatrixError::PositionTooLarge)
    );
    let mut nan = view;
    nan.w_axis.y = f32::NAN;
    assert_eq!(read(nan, projection), Err(CameraMatrixError::NonFinite));

    // No depth at all (B = 0: every depth maps to one NDC value), and a range behind the eye.
    let mut flat = projection;
    flat.w_axis.z = 0.0;
    assert!(matches!(
        read(view, flat),
        Err(CameraMatrixError::DepthRange { .. })
    ));
    let mut behind = projection;
    behind.z_axis.z = -2.0;
    assert!(matches!(
        read(view, behind),
        Err(CameraMatrixError::DepthRange { .. })
    ));
    // Near and far swapped is the usual way to build a reversed-Z projection: read as one.
    let swapped = rh::proj::directx::perspective(original.fov_y, 640.0 / 480.0, 50.0, 0.1);
    let camera = read(view, swapped).unwrap();
    assert!(
        (camera.near - 0.1).abs() < 1e-6 && (camera.far - 50.0).abs() < 1e-4,
        "{camera:?}"
    );
    // A scaled projection is the same projection.
    let camera = read(view, projection * 3.0).unwrap();
    assert_close(&camera, &original);
    // Every refusal says what is wrong in words.
    let message = read(view, jittered).unwrap_err().to_string();
    assert!(message.contains("unjittered"), "{message}");
}

#[test]
fn a_depth_range_too_thin_to_tell_near_from_far_is_refused() {
    // Reversed depth, NDC depth = A + B/d with A = 1e20 and B = 1e19: near B/(1 + A) and far B/A
    // are one number in f64. That is no depth range, not a camera whose near and far coincide.
    let mut projection =
        Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 640, 480, 0.1, 50.0).clip_from_view();
    projection.z_axis.z = 1e20;
    projection.w_axis.z = 1e19;
    match Camera::from_matrices(
        Mat4::IDENTITY,
        projection,
        ClipSpace::ZeroToOneYUp,
        640,
        480,
    ) {
        Err(CameraMatrixError::DepthRange { near, far }) => {
            assert!(
                (near / 0.1 - 1.0).abs() < 1e-6 && near == far,
                "[{near}, {far}]"
            )
        }
        other => panic!("{other:?}"),
    }
}

/// The checks hold for the f32 camera returned, not only for the f64 reading of the matrices
/// (mutation audit: matrices it rounded into a camera with no depth range, or a field of view
/// `view_problem` refuses, which the assignment panics on, were accepted).
#[test]
fn an_accepted_camera_keeps_the_range_and_view_that_were_checked() {
    let projection =
        Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 640, 480, 0.1, 50.0).clip_from_view();
    // Near and far 1e-10 apart at 0.1 (f32 resolution there: 7e-9): one f32 plane.
    let mut thin = projection;
    thin.z_axis.z = 1e9;
    thin.w_axis.z = 1e8;
    // A near plane of 1e-50 (an infinite reversed projection scaled by 1e30): 0 in f32.
    let mut tiny_near =
        rh::proj::directx::perspective_infinite_reverse(1.0, 640.0 / 480.0, 0.1) * 1e30;
    tiny_near.w_axis.z = 1e-20;
    // A field of view 2e-9 short of π: π in f32, outside (0, π).
    let mut wide = projection;
    wide.x_axis.x = 0.75e-9;
    wide.y_axis.y = 1e-9;
    // One of 2e-48 (scales of 1e48 once w' is ±z): 0 in f32.
    let mut narrow = projection * 1e-10;
    narrow.x_axis.x = 0.75e38;
    narrow.y_axis.y = 1e38;
    // A near plane of 1e-13, a normal f32 below `ClusterGrid::MIN_NEAR`, and a range whose
    // near·far passes f32::MAX: cameras `Camera::problem` refuses, which were returned as `Ok`
    // for the first grid or frame to refuse (API review).
    let below_min_near = rh::proj::directx::perspective_infinite_reverse(1.0, 640.0 / 480.0, 1e-13);
    // (Built in f64: glam's own product near·far overflows f32 first.)
    let mut overflowing_range = projection;
    let (near, far) = (1e19f64, 1e21f64);
    overflowing_range.z_axis.z = (far / (near - far)) as f32;
    overflowing_range.w_axis.z = (near * far / (near - far)) as f32;
    let accepted_broken: Vec<String> = [
        ("thin", thin),
        ("tiny near", tiny_near),
        ("wide", wide),
        ("narrow", narrow),
        ("below MIN_NEAR", below_min_near),
        ("near·far overflows", overflowing_range),
    ]
    .into_iter()
    .filter_map(|(what, projection)| {
        let camera = Camera::from_matrices(
            Mat4::IDENTITY,
            projection,
            ClipSpace::ZeroToOneYUp,
            640,
            480,
        )
        .ok()?;
        camera
            .problem()
            .map(|problem| format!("{what}: {camera:?}: {problem}"))
    })
    .collect();
    assert!(accepted_broken.is_empty(), "{accepted_broken:#?}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]
    #[test]
    fn any_usable_camera_round_trips(
        position in prop::array::uniform3(-1e4f32..1e4),
        direction in prop::array::uniform3(-1f32..1.0),
        up in prop::array::uniform3(-1f32..1.0),
        fov_deg in 0.05f32..178.0,
        width in 1u32..4096,
        height in 1u32..4096,
        near_exp in -5f32..2.0,
        range_exp in 0.1f32..7.0,
    ) {
        let direction = Vec3::from(direction);
        prop_assume!(direction.length() > 1e-2);
        let position = Vec3::from(position);
        let near = 10f32.powf(near_exp);
        let original = Camera::new(
            position,
            position + direction,
            Vec3::from(up),
            fov_deg,
            width,
            height,
            near,
            near * 10f32.powf(range_exp),
        );
        prop_assume!(original.problem().is_none());
        let camera = Camera::from_matrices(
            original.view_from_world(),
            original.clip_from_view(),
            ClipSpace::ZeroToOneYUp,
            width,
            height,
        );
        let camera = camera.map_err(|e| TestCaseError::fail(format!("{original:?}: {e}")))?;
        assert_close(&camera, &original);
    }
}
