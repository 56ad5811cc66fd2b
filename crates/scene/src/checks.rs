//! Value checks shared by the reader (values parsed from a file) and the writer / [`crate::Scene::problems`]
//! (values built in code), so a scene that passes them is exactly a scene that can be written and
//! read back.
//!
//! Every part is an `Option`: `None` means "absent or already reported by the structural reader", and
//! checks that need it are skipped, so one mistake is reported once. A check returns the finished
//! value only when every part is present and it reported nothing.

use crate::json::{Sink, show_f32, show_f64, show_vec3};
use crate::lights::LightRecord;
use glam::{UVec3, Vec3};
use myriad_cluster_math::{Camera, ClusterGrid, DepthSlicing, SpotCone};
use std::f32::consts::PI;

/// A spot direction whose length is within this of 1 is kept bit for bit; others are normalized.
/// The same tolerance is required of directions built in code.
pub(crate) const UNIT_TOLERANCE: f64 = 1e-6;

/// An angle: the degrees as written in a file (absent for values built in code) and the radians
/// that are stored.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Angle {
    pub deg: Option<f64>,
    pub rad: f32,
}

impl Angle {
    /// From degrees read from a file: converted in f64 and rounded to f32 once.
    pub(crate) fn from_deg(deg: f64) -> Self {
        Self {
            deg: Some(deg),
            rad: deg_to_rad(deg),
        }
    }

    /// From stored radians.
    pub(crate) fn from_rad(rad: f32) -> Self {
        Self { deg: None, rad }
    }

    fn shown_deg(&self) -> String {
        match self.deg {
            Some(d) => show_f64(d),
            None => format!(
                "{} ({} rad)",
                show_f64((self.rad as f64).to_degrees()),
                show_f32(self.rad)
            ),
        }
    }
}

/// The reader's degrees → radians conversion (f64, one rounding to f32).
pub(crate) fn deg_to_rad(deg: f64) -> f32 {
    deg.to_radians() as f32
}

/// Valid `fov_y_deg` as written: (0, 180).
pub(crate) fn fov_deg_ok(deg: f64) -> bool {
    deg.is_finite() && deg > 0.0 && deg < 180.0
}

/// Valid `angle_deg` as written: (0, 180].
pub(crate) fn spot_deg_ok(deg: f64) -> bool {
    deg.is_finite() && deg > 0.0 && deg <= 180.0
}

/// (The aspect ratio's part is `Camera::view_problem`'s, which the scene's camera passes too.)
fn fov_rad_ok(rad: f32) -> bool {
    let t = (0.5 * rad).tan();
    rad.is_finite() && rad > 0.0 && rad < PI && t.is_normal() && t.recip().is_finite()
}

/// Why a field of view within (0, 180) degrees as written is refused: its f32 radians, or their
/// half-angle tangent, left the usable range. Empty unless degrees were written and are in range.
fn fov_rounding(a: &Angle) -> String {
    if !a.deg.is_some_and(fov_deg_ok) {
        return String::new();
    }
    if !(a.rad > 0.0 && a.rad < PI) {
        return format!(", which is {} rad in f32", show_f32(a.rad));
    }
    format!(
        ", whose half-angle tangent {:e} is outside f32's normal range",
        (0.5 * a.rad).tan()
    )
}

/// Why a spot angle within (0, 180] degrees as written is refused: its radians round to 0.
fn spot_rounding(a: &Angle) -> String {
    match a.deg {
        Some(d) if spot_deg_ok(d) && a.rad == 0.0 => ", which is 0 rad in f32".to_string(),
        _ => String::new(),
    }
}

fn spot_rad_ok(rad: f32) -> bool {
    rad.is_finite() && rad > 0.0 && rad <= PI
}

/// The parts of a camera.
#[derive(Default)]
pub(crate) struct CameraParts {
    pub position: Option<Vec3>,
    pub target: Option<Vec3>,
    pub up: Option<Vec3>,
    pub fov_y: Option<Angle>,
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub near: Option<f32>,
    pub far: Option<f32>,
}

impl From<&Camera> for CameraParts {
    fn from(c: &Camera) -> Self {
        Self {
            position: Some(c.position),
            target: Some(c.target),
            up: Some(c.up),
            fov_y: Some(Angle::from_rad(c.fov_y)),
            width: Some(c.width),
            height: Some(c.height),
            near: Some(c.near),
            far: Some(c.far),
        }
    }
}

/// What [`check_camera`] found.
pub(crate) struct CameraCheck {
    /// The camera, when every part is present and valid.
    pub camera: Option<Camera>,
    /// `(near, far)` when both are present and valid, even if other camera parts are not (so the
    /// grid's `first_slice_depth` can still be checked).
    pub depth_range: Option<(f32, f32)>,
}

/// Checks a camera; `sink` has the `camera` prefix.
pub(crate) fn check_camera(p: &CameraParts, sink: &mut Sink<'_>) -> CameraCheck {
    let start = sink.count();
    for (name, v) in [("position", p.position), ("target", p.target), ("up", p.up)] {
        if let Some(v) = v
            && !v.is_finite()
        {
            sink.report(name, format!("must be finite, got {}", show_vec3(v)));
        }
    }
    if let Some(up) = p.up
        && up == Vec3::ZERO
    {
        sink.report("up", "must be non-zero");
    }
    // Parallel to the view direction, `Camera` picks a world axis as up (its documented fallback);
    // a scene file does not guess its camera's roll, as it refuses a zero `up` (audit: accepted
    // silently). The test is `Camera::basis_f64`'s, so exactly the cameras it would repair.
    if let (Some(pos), Some(target), Some(up)) = (p.position, p.target, p.up)
        && pos.is_finite()
        && target.is_finite()
        && up.is_finite()
        && pos != target
        && up != Vec3::ZERO
    {
        let forward = (target.as_dvec3() - pos.as_dvec3()).normalize_or_zero();
        let up = up.as_dvec3();
        if forward != glam::DVec3::ZERO && forward.cross(up).length() <= 1e-6 * up.length() {
            sink.report(
                "up",
                format!(
                    "{} is parallel to the view direction (camera.target − camera.position), so \
                     the camera's roll is undefined",
                    show_vec3(up.as_vec3())
                ),
            );
        }
    }
    if let (Some(pos), Some(target)) = (p.position, p.target)
        && pos.is_finite()
        && pos == target
    {
        sink.report(
            "target",
            format!(
                "must differ from camera.position (both are {}; the view direction is undefined)",
                show_vec3(pos)
            ),
        );
    }
    if let Some(a) = p.fov_y
        && !(a.deg.is_none_or(fov_deg_ok) && fov_rad_ok(a.rad))
    {
        sink.report(
            "fov_y_deg",
            format!(
                "must be in (0, 180) degrees, got {}{}",
                a.shown_deg(),
                fov_rounding(&a)
            ),
        );
    }
    for (name, v) in [("width", p.width), ("height", p.height)] {
        if v == Some(0) {
            sink.report(name, "must be at least 1 pixel, got 0");
        }
    }
    // The grid is sliced over the camera's depth range, so its floor is the grid's.
    let near_ok = p
        .near
        .filter(|&n| n.is_finite() && n >= ClusterGrid::MIN_NEAR);
    if let Some(n) = p.near
        && near_ok.is_none()
    {
        sink.report(
            "near",
            format!(
                "must be finite and at least {:e} (below it the f32 assignment underflows), got {}",
                ClusterGrid::MIN_NEAR,
                show_f32(n)
            ),
        );
    }
    let mut depth_range = None;
    if let Some(f) = p.far {
        if !f.is_finite() {
            sink.report("far", format!("must be finite, got {}", show_f32(f)));
        } else if let Some(n) = near_ok {
            if f > n && !(n * f).is_finite() {
                // The renderer's reversed-Z projection and squared distances need near·far in
                // f32 (`Camera::problem`): `render` refused such a camera after `validate`,
                // `assign` and `check` had accepted it (audit).
                sink.report(
                    "far",
                    format!(
                        "near·far = {:.3e} overflows f32 (near {}, far {}); use smaller units",
                        n as f64 * f as f64,
                        show_f32(n),
                        show_f32(f)
                    ),
                );
            } else if f > n {
                depth_range = Some((n, f));
            } else {
                sink.report(
                    "far",
                    format!(
                        "must be greater than camera.near ({}), got {}",
                        show_f32(n),
                        show_f32(f)
                    ),
                );
            }
        }
    }
    let camera = if sink.count() == start {
        match (
            p.position,
            p.target,
            p.up,
            p.fov_y,
            p.width,
            p.height,
            depth_range,
        ) {
            (
                Some(position),
                Some(target),
                Some(up),
                Some(fov),
                Some(width),
                Some(height),
                Some((near, far)),
            ) => {
                let camera = Camera {
                    position,
                    target,
                    up,
                    fov_y: fov.rad,
                    width,
                    height,
                    near,
                    far,
                };
                // What the checks above do not name field by field (frustum slopes outside
                // f32's normal range across a very wide or tall target): a scene file's camera
                // is one every command can use.
                match camera.problem() {
                    Some(problem) => {
                        sink.report("", problem);
                        None
                    }
                    None => Some(camera),
                }
            }
            _ => None,
        }
    } else {
        None
    };
    CameraCheck {
        camera,
        depth_range,
    }
}

/// The parts of a cluster grid.
#[derive(Default)]
pub(crate) struct GridParts {
    pub dims: [Option<u32>; 3],
    pub slicing: Option<DepthSlicing>,
}

/// Checks a grid against the camera's depth range (when known); `sink` has the `grid` prefix.
pub(crate) fn check_grid(
    p: &GridParts,
    depth_range: Option<(f32, f32)>,
    sink: &mut Sink<'_>,
) -> Option<ClusterGrid> {
    let start = sink.count();
    for (name, d) in ["x", "y", "z"].into_iter().zip(p.dims) {
        if d == Some(0) {
            sink.report(name, "must be at least 1, got 0");
        }
    }
    if let [Some(x), Some(y), Some(z)] = p.dims {
        let clusters = ClusterGrid::clusters_in(UVec3::new(x, y, z));
        if clusters > u32::MAX as u128 {
            sink.report(
                "",
                format!(
                    "{x} × {y} × {z} = {clusters} clusters; cluster ids are u32, so at most {}",
                    u32::MAX
                ),
            );
        }
    }
    if let Some(DepthSlicing::LogWithNearSlice {
        first_slice_depth: s,
    }) = p.slicing
    {
        if !s.is_finite() {
            sink.report(
                "first_slice_depth",
                format!("must be finite, got {}", show_f32(s)),
            );
        } else if let Some((n, f)) = depth_range
            && !(s > n && s < f)
        {
            sink.report(
                "first_slice_depth",
                format!(
                    "must lie strictly between camera.near ({}) and camera.far ({}), got {}",
                    show_f32(n),
                    show_f32(f),
                    show_f32(s)
                ),
            );
        }
    }
    if sink.count() != start {
        return None;
    }
    match (p.dims, p.slicing, depth_range) {
        // `try_new`: whatever its checks find that the ones above missed is the file's error,
        // not a panic (a grid whose product wrapped u64 reached `new`, audit).
        ([Some(x), Some(y), Some(z)], Some(slicing), Some((near, far))) => {
            match ClusterGrid::try_new(UVec3::new(x, y, z), slicing, near, far) {
                Ok(grid) => Some(grid),
                Err(e) => {
                    sink.report("", e.to_string());
                    None
                }
            }
        }
        _ => None,
    }
}

/// The parts of a spot cone.
pub(crate) struct SpotParts {
    pub direction: Option<Vec3>,
    pub angle: Option<Angle>,
    /// `None`: not given, so [`crate::default_spot_inner_angle`] of the outer angle.
    pub inner: Option<Angle>,
}

/// The parts of a light. `spot: None` is a point light.
pub(crate) struct LightParts {
    pub position: Option<Vec3>,
    pub radius: Option<f32>,
    pub color: Option<Vec3>,
    pub intensity: Option<f32>,
    pub spot: Option<SpotParts>,
}

/// Checks one light; `sink` has the `lights[i]` prefix. The returned record's spot direction is
/// unit length (normalized in f64 unless already within [`UNIT_TOLERANCE`] of 1).
pub(crate) fn check_light(
    p: &LightParts,
    source_index: u32,
    sink: &mut Sink<'_>,
) -> Option<LightRecord> {
    let start = sink.count();
    if let Some(v) = p.position
        && !v.is_finite()
    {
        sink.report("position", format!("must be finite, got {}", show_vec3(v)));
    }
    if let Some(r) = p.radius
        && !(r.is_finite() && r > 0.0)
    {
        sink.report(
            "radius",
            format!("must be finite and > 0, got {}", show_f32(r)),
        );
    }
    if let Some(c) = p.color
        && !(c.is_finite() && c.min_element() >= 0.0)
    {
        sink.report(
            "color",
            format!("components must be finite and >= 0, got {}", show_vec3(c)),
        );
    }
    if let Some(i) = p.intensity
        && !(i.is_finite() && i >= 0.0)
    {
        sink.report(
            "intensity",
            format!("must be finite and >= 0, got {}", show_f32(i)),
        );
    }
    // The renderer shades with colour × intensity in f32: an infinite product would show nothing
    // of the light (it skips it) while the lists hold it (hostile-input audit: such a light
    // passed `validate` and was dark in `render`).
    if let (Some(c), Some(i)) = (p.color, p.intensity)
        && sink.count() == start
        && !(c * i).is_finite()
    {
        sink.report(
            "intensity",
            format!(
                "{} times color {} overflows f32 (at most {} a channel)",
                show_f32(i),
                show_vec3(c),
                show_f32(f32::MAX)
            ),
        );
    }
    let mut spot = None;
    if let Some(s) = &p.spot {
        if let Some(d) = s.direction
            && !(d.is_finite() && d != Vec3::ZERO)
        {
            sink.report(
                "spot.direction",
                format!("must be finite and non-zero, got {}", show_vec3(d)),
            );
        }
        let outer_ok = s
            .angle
            .is_some_and(|a| a.deg.is_none_or(spot_deg_ok) && spot_rad_ok(a.rad));
        if let Some(a) = s.angle
            && !outer_ok
        {
            sink.report(
                "spot.angle_deg",
                format!(
                    "must be in (0, 180] degrees, got {}{}",
                    a.shown_deg(),
                    spot_rounding(&a)
                ),
            );
        }
        // In [0, outer), in the file's degrees and in the radians kept: the shader's falloff
        // runs from the inner angle to the outer one.
        // (Against a valid outer angle only: a bad one is reported once, above.)
        if let (Some(inner), Some(outer), true) = (s.inner, s.angle, outer_ok) {
            let below = |a: f64, b: f64| a.is_finite() && a >= 0.0 && a < b;
            let deg_ok = match (inner.deg, outer.deg) {
                (Some(i), Some(o)) => below(i, o),
                _ => true,
            };
            if !(deg_ok && below(inner.rad as f64, outer.rad as f64)) {
                // Below the outer angle as written, but not once both are f32 radians.
                let rounding = if deg_ok && inner.deg.is_some() {
                    format!(
                        ", which is {} rad in f32, as angle_deg is",
                        show_f32(inner.rad)
                    )
                } else {
                    String::new()
                };
                sink.report(
                    "spot.inner_angle_deg",
                    format!(
                        "must be in [0, angle_deg {}) degrees, got {}{rounding}",
                        outer.shown_deg(),
                        inner.shown_deg()
                    ),
                );
            }
        }
        spot = match (s.direction, s.angle) {
            (Some(d), Some(a)) => Some(SpotCone {
                direction: unit_direction(d),
                angle: a.rad,
            }),
            _ => None,
        };
    }
    if sink.count() != start {
        return None;
    }
    match (p.position, p.radius, p.color, p.intensity) {
        (Some(position), Some(radius), Some(color), Some(intensity))
            if p.spot.is_none() || spot.is_some() =>
        {
            let spot_inner_angle = match (&p.spot, spot) {
                (Some(SpotParts { inner: Some(a), .. }), Some(_)) => a.rad,
                (_, Some(cone)) => crate::default_spot_inner_angle(cone.angle),
                (_, None) => 0.0,
            };
            Some(LightRecord {
                position,
                radius,
                color,
                intensity,
                spot,
                spot_inner_angle,
                source_index,
            })
        }
        _ => None,
    }
}

/// `|d|` computed in f64 (no underflow for tiny f32 components).
pub(crate) fn length_f64(d: Vec3) -> f64 {
    d.as_dvec3().length()
}

/// `d` as a unit vector: unchanged when its length is already within [`UNIT_TOLERANCE`] of 1 (so
/// written directions read back bit for bit), else divided by its length in f64.
pub(crate) fn unit_direction(d: Vec3) -> Vec3 {
    let len = length_f64(d);
    if (len - 1.0).abs() <= UNIT_TOLERANCE || len == 0.0 || !len.is_finite() {
        d
    } else {
        (d.as_dvec3() / len).as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Problem;
    use crate::json::Prefix;

    fn camera_parts() -> CameraParts {
        CameraParts {
            position: Some(Vec3::new(0.0, 1.0, 5.0)),
            target: Some(Vec3::ZERO),
            up: Some(Vec3::Y),
            fov_y: Some(Angle::from_deg(60.0)),
            width: Some(640),
            height: Some(480),
            near: Some(0.1),
            far: Some(100.0),
        }
    }

    fn camera_problems(p: &CameraParts) -> (CameraCheck, Vec<Problem>) {
        let mut problems = Vec::new();
        let check = check_camera(p, &mut Sink::new(&mut problems, Prefix::Section("camera")));
        (check, problems)
    }

    /// Every camera a scene file accepts is one `Camera::problem` accepts (the renderer's test):
    /// `validate`, `assign` and `check` took near 10 with far 1e38, which `render` then refused
    /// after setting up the GPU (hunt). And a value refused for its f32 rounding says so, where
    /// the message showed a number inside the range it asked for.
    #[test]
    fn scene_cameras_are_usable_cameras_and_rounding_is_named() {
        let shown = |p: &CameraParts| -> Vec<String> {
            let (check, problems) = camera_problems(p);
            assert!(check.camera.is_none() || problems.is_empty());
            problems.iter().map(|p| p.to_string()).collect()
        };
        let mut p = camera_parts();
        (p.near, p.far) = (Some(10.0), Some(1e38));
        assert_eq!(
            shown(&p),
            [
                "camera.far: near·far = 1.000e39 overflows f32 (near 10.0, far 1e+38); use smaller units"
            ]
        );
        let mut p = camera_parts();
        p.fov_y = Some(Angle::from_deg(179.999_999));
        assert_eq!(
            shown(&p),
            [
                "camera.fov_y_deg: must be in (0, 180) degrees, got 179.999999, which is 3.1415927 \
              rad in f32"
            ]
        );
        p.fov_y = Some(Angle::from_deg(1e-36));
        let text = shown(&p);
        assert!(
            text.len() == 1 && text[0].contains("half-angle tangent 8.7"),
            "{text:?}"
        );
        // A vertical slope that is a normal f32, made subnormal across by a 1-pixel-wide target
        // of 4e9 rows: not a field the checks name, so `Camera::problem`'s text, at `camera`.
        p.fov_y = Some(Angle::from_deg(1e-30));
        (p.width, p.height) = (Some(1), Some(4_000_000_000));
        let text = shown(&p);
        assert!(
            text.len() == 1 && text[0].starts_with("camera: field of view"),
            "{text:?}"
        );
    }

    #[test]
    fn valid_camera_passes_and_fov_is_converted_once_in_f64() {
        let (check, problems) = camera_problems(&camera_parts());
        assert!(problems.is_empty(), "{problems:?}");
        let c = check.camera.unwrap();
        assert_eq!(c.fov_y, 60f64.to_radians() as f32);
        assert_eq!(check.depth_range, Some((0.1, 100.0)));
    }

    #[test]
    fn every_camera_problem_is_reported_not_just_the_first() {
        let mut p = camera_parts();
        p.target = p.position;
        p.up = Some(Vec3::ZERO);
        p.fov_y = Some(Angle::from_deg(180.0));
        p.width = Some(0);
        p.near = Some(-1.0);
        p.far = Some(f32::INFINITY);
        let (check, problems) = camera_problems(&p);
        assert!(check.camera.is_none() && check.depth_range.is_none());
        let paths: Vec<&str> = problems.iter().map(|p| p.path.as_str()).collect();
        assert_eq!(
            paths,
            [
                "camera.up",
                "camera.target",
                "camera.fov_y_deg",
                "camera.width",
                "camera.near",
                "camera.far"
            ]
        );
        assert_eq!(
            problems[2].message,
            "must be in (0, 180) degrees, got 180.0"
        );
    }

    #[test]
    fn near_below_the_grid_floor_is_a_problem() {
        let mut p = camera_parts();
        p.near = Some(1e-22);
        p.far = Some(1e-16);
        let (check, problems) = camera_problems(&p);
        assert!(check.camera.is_none());
        assert_eq!(problems.len(), 1, "{problems:?}");
        assert_eq!(problems[0].path, "camera.near");
        assert_eq!(
            problems[0].message,
            "must be finite and at least 1e-12 (below it the f32 assignment underflows), got 1e-22"
        );
        (p.near, p.far) = (Some(ClusterGrid::MIN_NEAR), Some(1e-6));
        let (check, problems) = camera_problems(&p);
        assert!(
            check.camera.is_some() && problems.is_empty(),
            "{problems:?}"
        );
    }

    #[test]
    fn far_must_exceed_near_after_rounding_to_f32() {
        let mut p = camera_parts();
        // Distinct in f64, equal in f32.
        p.near = Some(0.1f64 as f32);
        p.far = Some((0.1f64 + 1e-12) as f32);
        let (check, problems) = camera_problems(&p);
        assert!(check.camera.is_none());
        assert_eq!(problems.len(), 1);
        assert_eq!(problems[0].path, "camera.far");
        assert!(
            problems[0]
                .message
                .contains("greater than camera.near (0.1)")
        );
    }

    #[test]
    fn fov_just_below_180_that_rounds_to_pi_is_rejected() {
        let mut p = camera_parts();
        p.fov_y = Some(Angle::from_deg(179.999_999_9));
        assert_eq!(p.fov_y.unwrap().rad, PI);
        let (_, problems) = camera_problems(&p);
        assert_eq!(problems.len(), 1, "{problems:?}");
        // A tiny angle that rounds to 0 rad is rejected too.
        p.fov_y = Some(Angle::from_deg(1e-300));
        let (_, problems) = camera_problems(&p);
        assert_eq!(problems.len(), 1, "{problems:?}");
    }

    #[test]
    fn angles_built_in_code_are_checked_in_radians() {
        // No degrees to check (a camera or light built in code): the radians alone decide.
        let mut p = camera_parts();
        // 7 rad has a positive tan(fov / 2) but is not in (0, π); the smallest subnormal is
        // positive but halves to 0, so tan(fov / 2) is 0 and the projection divides by it.
        // 1e-36° halves to a subnormal slope, which GPUs flush to zero (a blank image).
        for rad in [
            7.0,
            f32::from_bits(1),
            1e-36f32.to_radians(),
            PI,
            0.0,
            -1.0,
            f32::NAN,
        ] {
            p.fov_y = Some(Angle::from_rad(rad));
            let (check, problems) = camera_problems(&p);
            assert!(check.camera.is_none(), "{rad}");
            let paths: Vec<&str> = problems.iter().map(|p| p.path.as_str()).collect();
            assert_eq!(paths, ["camera.fov_y_deg"], "{rad}");
        }
        p.fov_y = Some(Angle::from_rad(7.0));
        assert_eq!(
            camera_problems(&p).1[0].message,
            "must be in (0, 180) degrees, got 401.07045659157626 (7.0 rad)"
        );
        p.fov_y = Some(Angle::from_rad(PI.next_down()));
        assert!(camera_problems(&p).0.camera.is_some());

        let mut l = light_parts();
        for rad in [0.0, -0.0, PI.next_up(), f32::NAN] {
            l.spot = Some(SpotParts {
                direction: Some(Vec3::Z),
                angle: Some(Angle::from_rad(rad)),
                inner: None,
            });
            let (r, problems) = light_problems(&l);
            assert!(r.is_none(), "{rad}");
            let shown: Vec<String> = problems.iter().map(|p| p.to_string()).collect();
            assert_eq!(shown.len(), 1, "{rad}: {shown:?}");
            assert!(
                shown[0].starts_with("lights[5].spot.angle_deg: must be in (0, 180] degrees"),
                "{shown:?}"
            );
        }
        l.spot = Some(SpotParts {
            direction: Some(Vec3::Z),
            angle: Some(Angle::from_rad(PI)),
            inner: None,
        });
        assert!(light_problems(&l).0.is_some());
    }

    fn grid_problems(
        p: &GridParts,
        range: Option<(f32, f32)>,
    ) -> (Option<ClusterGrid>, Vec<Problem>) {
        let mut problems = Vec::new();
        let g = check_grid(
            p,
            range,
            &mut Sink::new(&mut problems, Prefix::Section("grid")),
        );
        (g, problems)
    }

    #[test]
    fn grid_checks() {
        let ok = GridParts {
            dims: [Some(24), Some(12), Some(16)],
            slicing: Some(DepthSlicing::Log),
        };
        let (g, problems) = grid_problems(&ok, Some((0.1, 100.0)));
        assert!(problems.is_empty());
        assert_eq!(g.unwrap().dims(), UVec3::new(24, 12, 16));
        // Without a valid camera range there is no grid, but no extra problem either.
        assert_eq!(grid_problems(&ok, None), (None, vec![]));

        let zero = GridParts {
            dims: [Some(0), Some(12), Some(0)],
            slicing: Some(DepthSlicing::Linear),
        };
        let (g, problems) = grid_problems(&zero, Some((0.1, 100.0)));
        assert!(g.is_none());
        let paths: Vec<&str> = problems.iter().map(|p| p.path.as_str()).collect();
        assert_eq!(paths, ["grid.x", "grid.z"]);

        let huge = GridParts {
            dims: [Some(65536), Some(65536), Some(1)],
            slicing: Some(DepthSlicing::Linear),
        };
        let (g, problems) = grid_problems(&huge, Some((0.1, 100.0)));
        assert!(g.is_none());
        assert_eq!(problems[0].path, "grid");
        assert!(
            problems[0].message.contains("4294967296 clusters"),
            "{problems:?}"
        );
        // Products that pass u64 are counted whole: 2^22 · 2^21 · 2^21 is 2^64, which wrapped
        // to 0 clusters, passed, and panicked in `ClusterGrid::new` (audit); all-maximal
        // dimensions overflowed the multiplication itself in a debug build.
        for (dims, count) in [
            (
                [4_194_304, 2_097_152, 2_097_152],
                "18446744073709551616 clusters",
            ),
            ([u32::MAX; 3], "79228162458924105385300197375 clusters"),
        ] {
            let wrapped = GridParts {
                dims: dims.map(Some),
                slicing: Some(DepthSlicing::Log),
            };
            let (g, problems) = grid_problems(&wrapped, Some((0.1, 100.0)));
            assert!(g.is_none());
            assert!(problems[0].message.contains(count), "{problems:?}");
        }
        // The largest grid that fits is accepted.
        let max = GridParts {
            dims: [Some(u32::MAX), Some(1), Some(1)],
            slicing: Some(DepthSlicing::Linear),
        };
        assert!(grid_problems(&max, Some((0.1, 100.0))).0.is_some());

        for s in [0.1, 100.0, 0.05, 1000.0, f32::NAN] {
            let near = GridParts {
                dims: [Some(4), Some(4), Some(4)],
                slicing: Some(DepthSlicing::LogWithNearSlice {
                    first_slice_depth: s,
                }),
            };
            let (g, problems) = grid_problems(&near, Some((0.1, 100.0)));
            assert!(g.is_none(), "{s}");
            assert_eq!(problems.len(), 1);
            assert_eq!(problems[0].path, "grid.first_slice_depth");
        }
    }

    fn light_parts() -> LightParts {
        LightParts {
            position: Some(Vec3::new(1.0, 2.0, 3.0)),
            radius: Some(2.0),
            color: Some(Vec3::ONE),
            intensity: Some(1.0),
            spot: None,
        }
    }

    fn light_problems(p: &LightParts) -> (Option<LightRecord>, Vec<Problem>) {
        let mut problems = Vec::new();
        let r = check_light(p, 5, &mut Sink::new(&mut problems, Prefix::Light(5)));
        (r, problems)
    }

    #[test]
    fn a_spot_angle_that_rounds_to_zero_says_so() {
        let mut p = light_parts();
        p.spot = Some(SpotParts {
            direction: Some(Vec3::Z),
            angle: Some(Angle::from_deg(1e-44)),
            inner: None,
        });
        let (r, problems) = light_problems(&p);
        assert!(r.is_none());
        let shown: Vec<String> = problems.iter().map(|p| p.to_string()).collect();
        assert_eq!(
            shown,
            [
                "lights[5].spot.angle_deg: must be in (0, 180] degrees, got 1e-44, which is 0 rad in f32"
            ]
        );
    }

    #[test]
    fn light_checks_report_each_field() {
        let (r, problems) = light_problems(&light_parts());
        assert!(problems.is_empty());
        assert_eq!(r.unwrap().source_index, 5);

        let mut p = light_parts();
        p.position = Some(Vec3::new(f32::NAN, 0.0, 0.0));
        p.radius = Some(0.0);
        p.color = Some(Vec3::new(1.0, -0.5, 0.0));
        p.intensity = Some(f32::INFINITY);
        p.spot = Some(SpotParts {
            direction: Some(Vec3::ZERO),
            angle: Some(Angle::from_deg(0.0)),
            inner: None,
        });
        let (r, problems) = light_problems(&p);
        assert!(r.is_none());
        let shown: Vec<String> = problems.iter().map(|p| p.to_string()).collect();
        assert_eq!(
            shown,
            [
                "lights[5].position: must be finite, got [NaN, 0.0, 0.0]",
                "lights[5].radius: must be finite and > 0, got 0.0",
                "lights[5].color: components must be finite and >= 0, got [1.0, -0.5, 0.0]",
                "lights[5].intensity: must be finite and >= 0, got inf",
                "lights[5].spot.direction: must be finite and non-zero, got [0.0, 0.0, 0.0]",
                "lights[5].spot.angle_deg: must be in (0, 180] degrees, got 0.0",
            ]
        );
        assert!(problems.iter().all(|p| p.light == Some(5)));
    }

    #[test]
    fn spot_direction_is_normalized_and_180_degrees_is_allowed() {
        let mut p = light_parts();
        p.spot = Some(SpotParts {
            direction: Some(Vec3::new(0.0, -3.0, 4.0)),
            angle: Some(Angle::from_deg(180.0)),
            inner: None,
        });
        let (r, problems) = light_problems(&p);
        assert!(problems.is_empty(), "{problems:?}");
        let spot = r.unwrap().spot.unwrap();
        assert_eq!(spot.direction, Vec3::new(0.0, -0.6, 0.8));
        assert_eq!(spot.angle, PI);
        // Tiny but non-zero directions normalize without underflow.
        let tiny = unit_direction(Vec3::new(1e-40, 0.0, 0.0));
        assert_eq!(tiny, Vec3::X);
        // Already-unit directions are kept bit for bit.
        let d = Vec3::new(0.3, 0.4, 0.5).normalize();
        assert_eq!(unit_direction(d).to_array(), d.to_array());
        for deg in [180.000_001, -1.0, f64::NAN] {
            p.spot = Some(SpotParts {
                direction: Some(Vec3::Z),
                angle: Some(Angle::from_deg(deg)),
                inner: None,
            });
            assert_eq!(light_problems(&p).1.len(), 1, "{deg}");
        }
    }
}
