//! The perspective camera: where it is, where it looks, and how view space maps to clip space.
//!
//! Degenerate orientations are resolved, never propagated as NaN:
//! * `target == position` (no view direction): the camera looks down world −Z.
//! * `up` parallel to the view direction (e.g. looking straight down with `up = +Y`), zero or
//!   non-finite: the fallback up vector is the first of world +Y, +Z, +X (in that order of
//!   preference) that is least aligned with the view direction — so looking straight down/up along Y
//!   uses +Z as "up" on screen.

use glam::{DMat3, DVec3, Mat3, Mat4, Vec2, Vec3};

/// A perspective camera with wgpu's 0..1 clip depth, reversed (1 at `near`, 0 at `far`). View
/// space is right-handed: the camera looks down its −Z, +Y is up on screen, +X right; view
/// depth is the distance along the view direction (−z), as the grid's slices measure it; world
/// coordinates are the scene's units, shared by the camera and the lights. Fields are plain data ([`Camera::problem`] names what makes one unusable); `fov_y` is in
/// radians, while [`Camera::new`] takes degrees, as the scene file does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position in world space.
    pub position: Vec3,
    /// A point the camera looks at.
    pub target: Vec3,
    /// Approximate up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in radians, in (0, π).
    pub fov_y: f32,
    /// Render target width in pixels (≥ 1).
    pub width: u32,
    /// Render target height in pixels (≥ 1).
    pub height: u32,
    /// Near plane view depth (> 0).
    pub near: f32,
    /// Far plane view depth (> near), or `f32::INFINITY` for an infinite far plane (the
    /// reversed-Z projection of engines that clip nothing far away).
    pub far: f32,
}

impl Camera {
    /// A camera with a vertical field of view given in degrees.
    #[allow(clippy::too_many_arguments)] // Mirrors the scene file's camera record field for field.
    pub fn new(
        position: Vec3,
        target: Vec3,
        up: Vec3,
        fov_y_deg: f32,
        width: u32,
        height: u32,
        near: f32,
        far: f32,
    ) -> Self {
        Self {
            position,
            target,
            up,
            fov_y: fov_y_deg.to_radians(),
            width,
            height,
            near,
            far,
        }
    }

    /// Whether `other` is this camera, field for field: what "the same view" means when lists, a
    /// G-buffer or a cache are kept for a camera. `==`, except that NaN equals NaN: a NaN field
    /// (an `up` of `Vec3::ZERO.normalize()`, which the documented fallback makes usable) made
    /// every kept upload "another camera's" under `==`. (`0.0` and `-0.0` stay equal, as the
    /// views they give are: bit equality refused such a camera's kept lists.)
    pub fn same_as(&self, other: &Camera) -> bool {
        let floats = |c: &Camera| {
            let mut all = [0.0; 12];
            all[..3].copy_from_slice(&c.position.to_array());
            all[3..6].copy_from_slice(&c.target.to_array());
            all[6..9].copy_from_slice(&c.up.to_array());
            all[9..].copy_from_slice(&[c.fov_y, c.near, c.far]);
            all
        };
        let same = |(a, b): (f32, f32)| a == b || (a.is_nan() && b.is_nan());
        (self.width, self.height) == (other.width, other.height)
            && floats(self).into_iter().zip(floats(other)).all(same)
    }

    /// What makes this camera unusable, if anything: [`Self::view_problem`], or a depth range
    /// not `0 < near < far` (`far` finite or `+∞`), a near plane below
    /// [`crate::ClusterGrid::MIN_NEAR`], or a finite range whose `near·far` passes `f32::MAX`
    /// (such units leave the shaders' squared distances no room; use smaller ones). For engines
    /// that take cameras from users.
    pub fn problem(&self) -> Option<String> {
        self.view_problem().or_else(|| {
            if !(self.near > 0.0 && self.near.is_finite() && self.near < self.far) {
                return Some(format!(
                    "depth range must satisfy 0 < near < far (far finite or infinite), got [{}, {}]",
                    self.near, self.far
                ));
            }
            if self.near < crate::ClusterGrid::MIN_NEAR {
                return Some(format!(
                    "near plane {:e} is below ClusterGrid::MIN_NEAR ({:e}): grids cannot slice \
                     depth from there, and far below it the depth buffer's values leave f32's \
                     normal range (on Mesa's llvmpipe, pixels went missing below 1e-33)",
                    self.near,
                    crate::ClusterGrid::MIN_NEAR
                ));
            }
            (self.far.is_finite() && !(self.near * self.far).is_finite()).then(|| {
                format!(
                    "depth range [{}, {}]: near·far overflows f32; use smaller units",
                    self.near, self.far
                )
            })
        })
    }

    /// What makes the view and its screen mapping unusable, if anything: a non-finite position
    /// or target, a field of view outside (0, π), a zero width or height, or frustum slopes
    /// (`tan(fov/2)`, times the aspect ratio across) that are not normal f32 numbers. A degenerate `up` or
    /// `target == position` is not a problem: those have the documented fallbacks. The depth
    /// range is not looked at: light assignment slices depth by its grid's range, so a camera with
    /// an infinite far plane (reversed-Z engines) and a finite grid is fine there. The assignment
    /// asserts this, and `0 < near < far` besides where the grid's outer slices are open
    /// ([`crate::OuterSlices`], the default: they reach the camera's near and far planes).
    pub fn view_problem(&self) -> Option<String> {
        if !(self.position.is_finite() && self.target.is_finite()) {
            return Some(format!(
                "position {} and target {} must be finite",
                self.position, self.target
            ));
        }
        if !(self.fov_y > 0.0 && self.fov_y < std::f32::consts::PI) {
            return Some(format!(
                "vertical field of view must lie in (0, π) radians, got {}",
                self.fov_y
            ));
        }
        if self.width == 0 || self.height == 0 {
            return Some(format!(
                "size must be at least 1x1 pixels, got {}x{}",
                self.width, self.height
            ));
        }
        // The frustum's slopes and the projection's scales (their inverses) must be normal f32:
        // a field of view of 1e-36° has a subnormal slope, which GPUs flush to zero, and it
        // rendered a blank image with no error.
        let t = self.tan_half_fov();
        if !(t.x.is_normal() && t.y.is_normal() && t.recip().is_finite()) {
            return Some(format!(
                "field of view {:e}° ({}x{} pixels) gives frustum slopes tan(fov/2) = [{:e}, {:e}], \
                 outside f32's normal range",
                self.fov_y.to_degrees(),
                self.width,
                self.height,
                t.x,
                t.y
            ));
        }
        None
    }

    /// Width over height.
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }

    /// `tan(fov/2)` horizontally and vertically: the view-space slope (x/depth, y/depth) of the
    /// frustum's right and top planes.
    pub fn tan_half_fov(&self) -> Vec2 {
        let ty = (0.5 * self.fov_y).tan();
        Vec2::new(ty * self.aspect(), ty)
    }

    /// Same as [`Self::tan_half_fov`] in f64, for the oracle.
    pub fn tan_half_fov_f64(&self) -> (f64, f64) {
        let ty = (0.5 * self.fov_y as f64).tan();
        (ty * self.width as f64 / self.height as f64, ty)
    }

    /// The orthonormal view basis in world space: `(right, up, forward)`, with the documented
    /// fallbacks for degenerate directions. Computed in f64 so the f32 and f64 paths share it.
    pub fn basis_f64(&self) -> (DVec3, DVec3, DVec3) {
        let mut forward = (self.target.as_dvec3() - self.position.as_dvec3()).normalize_or_zero();
        if !forward.is_finite() || forward == DVec3::ZERO {
            forward = DVec3::NEG_Z;
        }
        let up_hint = self.up.as_dvec3();
        let mut right = forward.cross(up_hint);
        if !right.is_finite() || right.length() <= 1e-6 * up_hint.length() || up_hint == DVec3::ZERO
        {
            let candidates = [DVec3::Y, DVec3::Z, DVec3::X];
            let mut best = candidates[0];
            for c in candidates {
                if forward.dot(c).abs() < forward.dot(best).abs() - 1e-12 {
                    best = c;
                }
            }
            right = forward.cross(best);
        }
        let right = right.normalize();
        let up = right.cross(forward).normalize();
        (right, up, forward)
    }

    /// World-to-view rotation in f64 (rows: right, up, −forward).
    pub fn view_rotation_f64(&self) -> DMat3 {
        let (r, u, f) = self.basis_f64();
        DMat3::from_cols(r, u, -f).transpose()
    }

    /// World-to-view rotation in f32.
    pub fn view_rotation(&self) -> Mat3 {
        self.view_rotation_f64().as_mat3()
    }

    /// `view_from_world` as a matrix. For GPU transforms of geometry near the camera; for lights
    /// prefer [`Self::view_from_world_point`], which subtracts the camera position first.
    pub fn view_from_world(&self) -> Mat4 {
        Mat4::from_mat3(self.view_rotation()) * Mat4::from_translation(-self.position)
    }

    /// `clip_from_view`: right-handed perspective with **reversed Z**, depth 1 at `near` and 0 at
    /// `far` (wgpu's 0..1 range; depth tests compare `Greater`, the depth buffer clears to 0).
    ///
    /// Why reversed: the stored depth is then `n(f − d)/(d(f − n))` ≈ `n/d`, which an f32 (and
    /// `Depth32Float`) keeps to ~7 significant digits at every distance. With depth 0 at `near`
    /// the stored value is `1 − n/d`, and beyond `d ≈ 1.7·10⁷·n` it rounds to exactly 1.0, the
    /// cleared background: with `near = 1e-8` everything past 0.17 m vanished and clustered shading
    /// read no light at all, and with `near = 1e-6` a 30 m courtyard lost its far walls.
    /// `B = f·n/(f − n)` is computed in f64 so the near plane maps to 1 to the last bit. An
    /// infinite far plane is the limit, stored depth exactly `n/d`: `A = 0`, `B = n`.
    pub fn clip_from_view(&self) -> Mat4 {
        let (n, f) = (self.near as f64, self.far as f64);
        let (a, b) = if f.is_infinite() {
            (0.0, n)
        } else {
            (n / (f - n), f * n / (f - n))
        };
        let t = self.tan_half_fov();
        Mat4::from_cols(
            glam::Vec4::new(1.0 / t.x, 0.0, 0.0, 0.0),
            glam::Vec4::new(0.0, 1.0 / t.y, 0.0, 0.0),
            glam::Vec4::new(0.0, 0.0, a as f32, -1.0),
            glam::Vec4::new(0.0, 0.0, b as f32, 0.0),
        )
    }

    /// `clip_from_world = clip_from_view * view_from_world`.
    pub fn clip_from_world(&self) -> Mat4 {
        self.clip_from_view() * self.view_from_world()
    }

    /// A world point in view space, camera-relative: the position is subtracted before rotating, so
    /// a light 5 m from a camera at 10⁶ m keeps millimetre precision.
    pub fn view_from_world_point(&self, world: Vec3) -> Vec3 {
        self.view_rotation() * (world - self.position)
    }

    /// [`Self::view_from_world_point`] in f64: the oracle's view transform.
    pub fn view_from_world_point_f64(&self, world: DVec3) -> DVec3 {
        self.view_rotation_f64() * (world - self.position.as_dvec3())
    }

    /// View depth (positive distance along the view direction) of a wgpu depth-buffer value
    /// produced by [`Self::clip_from_view`] (reversed Z): `depth = f·n / (n + ndc·(f − n))`,
    /// computed as `n / (a + ndc·(1 − a))` with `a = n/f` ([`Self::near_over_far`]), so an
    /// infinite far plane (`a = 0`: `n / ndc`) needs no other formula and no `f·n` can overflow.
    ///
    /// Only positive numbers are added and multiplied, so f32 keeps it to a few ulps of the
    /// stored value's exact depth for any near plane, also where a GPU fuses the multiply-add.
    /// The shading passes (`shaders/common/cluster.wgsl`) use this same formula with the same
    /// `a`, and shade the point at this depth on the pixel's ray, so the cluster a pixel reads
    /// is the cluster of the position it lights. The cleared background (0) is `f` (infinite
    /// for an infinite far plane).
    pub fn view_depth_from_ndc_depth(&self, ndc_depth: f32) -> f32 {
        let a = self.near_over_far();
        self.near / (a + ndc_depth * (1.0 - a))
    }

    /// `near / far` rounded once from f64 (0 for an infinite far plane): the one constant besides
    /// `near` that turns a stored depth into view depth ([`Self::view_depth_from_ndc_depth`]);
    /// the renderer hands it to its shaders.
    pub fn near_over_far(&self) -> f32 {
        (self.near as f64 / self.far as f64) as f32
    }

    /// The exact depth-buffer value of view depth `depth` (the inverse of
    /// [`Self::view_depth_from_ndc_depth`], in f64): `n(f − depth) / (depth(f − n))`, 1 at `near`,
    /// 0 at `far` (`n / depth` for an infinite far plane). For code that compares stored depths
    /// with view depths, such as slice edges.
    pub fn ndc_depth_from_view_depth(&self, depth: f64) -> f64 {
        let (n, f) = (self.near as f64, self.far as f64);
        if f.is_infinite() {
            return n / depth;
        }
        n * (f - depth) / (depth * (f - n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(position: Vec3, target: Vec3, up: Vec3) -> Camera {
        Camera::new(position, target, up, 60.0, 1536, 768, 0.1, 100.0)
    }

    fn assert_orthonormal(c: &Camera) {
        let (r, u, f) = c.basis_f64();
        for v in [r, u, f] {
            assert!((v.length() - 1.0).abs() < 1e-12, "{v:?}");
        }
        assert!(r.dot(u).abs() < 1e-12 && r.dot(f).abs() < 1e-12 && u.dot(f).abs() < 1e-12);
        assert!(c.view_from_world().is_finite());
    }

    #[test]
    fn looks_down_negative_z_in_view_space() {
        let c = cam(Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.0, 2.0, -7.0), Vec3::Y);
        let v = c.view_from_world_point(Vec3::new(1.0, 2.0, -2.0));
        assert!((v - Vec3::new(0.0, 0.0, -5.0)).length() < 1e-6, "{v:?}");
        let m = c
            .view_from_world()
            .transform_point3(Vec3::new(1.0, 2.0, -2.0));
        assert!((m - v).length() < 1e-5);
        // Matches glam's `camera::rh::view::look_at_mat4` in the regular case.
        let glam_view = glam::camera::rh::view::look_at_mat4(c.position, c.target, c.up);
        assert!(glam_view.abs_diff_eq(c.view_from_world(), 1e-6));
    }

    #[test]
    fn up_parallel_to_view_direction_falls_back() {
        for (target, up) in [
            (Vec3::new(0.0, -10.0, 0.0), Vec3::Y),
            (Vec3::new(0.0, 10.0, 0.0), Vec3::Y),
            (Vec3::new(0.0, 0.0, -10.0), Vec3::Z),
            (Vec3::new(5.0, 0.0, 0.0), Vec3::NEG_X),
            (Vec3::new(1.0, 1.0, 1.0), Vec3::ZERO),
            (Vec3::ZERO, Vec3::Y),
            (Vec3::new(0.0, 3.0, 0.0), Vec3::new(f32::NAN, 0.0, 0.0)),
        ] {
            let c = cam(Vec3::ZERO, target, up);
            assert_orthonormal(&c);
        }
        // Looking straight down with up = +Y: screen-up is world +Z.
        let c = cam(Vec3::ZERO, Vec3::new(0.0, -1.0, 0.0), Vec3::Y);
        let (_, u, _) = c.basis_f64();
        assert!((u - DVec3::Z).length() < 1e-12, "{u:?}");
    }

    #[test]
    fn ndc_depth_round_trips_through_projection() {
        // Reversed Z: near stores 1, far 0, and every depth in between round-trips to a few ulps
        // however small the near plane (depth 0 at near lost everything past ~1.7e7·near).
        for (near, far) in [
            (0.1f32, 100.0f32),
            (1e-8, 100.0),
            (1e-12, 1e6),
            (10.0, 1e30),
        ] {
            let c = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 64, 64, near, far);
            let project = |depth: f32| {
                let clip = c.clip_from_view() * glam::Vec4::new(0.3, -0.2, -depth, 1.0);
                clip.z / clip.w
            };
            assert_eq!(project(near), 1.0, "near {near}");
            assert_eq!(project(far), 0.0, "far {far}");
            for t in [1e-6f64, 1e-3, 0.01, 0.3, 0.9, 0.999] {
                let depth = ((near as f64).ln() * (1.0 - t) + (far as f64).ln() * t).exp() as f32;
                let ndc = project(depth);
                assert!(ndc > 0.0 && ndc < 1.0, "{depth} -> {ndc}");
                assert!(
                    (ndc as f64 / c.ndc_depth_from_view_depth(depth as f64) - 1.0).abs() < 1e-5,
                    "{depth} -> {ndc}"
                );
                let back = c.view_depth_from_ndc_depth(ndc);
                assert!(
                    (back - depth).abs() <= 1e-5 * depth,
                    "near {near} far {far}: {depth} -> {ndc} -> {back}"
                );
            }
        }
    }

    /// An infinite far plane (engines' reversed-Z default) is the limit of the finite ones: the
    /// stored depth is `n/d` from the matrix, nothing is clipped far away, the conversion back is
    /// `n / ndc` with the background (0) infinitely far, and the camera is usable.
    #[test]
    fn an_infinite_far_plane_stores_near_over_depth() {
        for near in [1e-12f32, 0.1, 10.0] {
            let c = Camera::new(
                Vec3::ZERO,
                Vec3::NEG_Z,
                Vec3::Y,
                60.0,
                64,
                64,
                near,
                f32::INFINITY,
            );
            assert_eq!(c.problem(), None);
            assert_eq!(c.near_over_far(), 0.0);
            let m = c.clip_from_view();
            assert!(m.is_finite(), "{m:?}");
            assert!(m.determinant() != 0.0);
            for depth in [near, near * 1.5, near * 1e3, near * 1e20, near * 1e30] {
                let clip = m * glam::Vec4::new(0.3, -0.2, -depth, 1.0);
                let ndc = clip.z / clip.w;
                let want = near as f64 / depth as f64;
                assert!(
                    (ndc as f64 / want - 1.0).abs() < 1e-6,
                    "near {near}: {depth} -> {ndc}, want {want}"
                );
                assert_eq!(c.ndc_depth_from_view_depth(depth as f64), want);
                if ndc > 0.0 {
                    let back = c.view_depth_from_ndc_depth(ndc);
                    assert!(
                        (back / depth - 1.0).abs() <= 1e-6,
                        "{depth} -> {ndc} -> {back}"
                    );
                }
            }
            assert_eq!(c.view_depth_from_ndc_depth(1.0), near);
            assert_eq!(c.view_depth_from_ndc_depth(0.0), f32::INFINITY);
        }
    }

    /// The stored depth → view depth conversion stays within a few f32 ulps of the exact value of
    /// the same stored depth, for any near plane, also when a GPU fuses the multiply-add: the
    /// shaders use this formula, and the active-cluster mask allows the GPU only 1e-5 (relative)
    /// of difference from the CPU. The textbook `f·n / (f − ndc·(f − n))` was 2e-2 off here.
    #[test]
    fn view_depth_from_stored_depth_is_accurate_for_any_near_plane() {
        for (near, far) in [
            (0.1f32, 100.0f32),
            (1e-5, 50.0),
            (1e-12, 1e6),
            (1.0, 1e30),
            (1e19, 1e19 * 1.5),
            (0.1, f32::INFINITY),
            (1e-12, f32::INFINITY),
        ] {
            let c = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 64, 64, near, far);
            let (n, f) = (near as f64, far as f64);
            let a = c.near_over_far();
            let mut worst = 0.0f64;
            let mut d = f32::MIN_POSITIVE;
            while d <= 1.0 {
                // `f·n / (n + d·(f − n))`, divided through by `f` so that `f = ∞` is its limit.
                let exact = n / (n / f + d as f64 * (1.0 - n / f));
                let fused = f32::mul_add(d, 1.0 - a, a);
                for got in [c.view_depth_from_ndc_depth(d), near / fused] {
                    worst = worst.max(((got as f64 - exact) / exact).abs());
                }
                // Every binade down to the smallest normal, where the far scene is stored, and
                // dense near 1 (the near plane).
                d = if d < 0.999 { d * 1.37 } else { d.next_up() };
            }
            assert!(worst < 1e-6, "near {near} far {far}: off by {worst:e}");
        }
    }

    /// The frustum slopes are the projection's: a view point at `(tx·d, ty·d, −d)` from
    /// [`Camera::tan_half_fov`] lands on the top right corner of clip space, through
    /// `clip_from_view` and, moved to world space, through `clip_from_world`; the f64 slopes
    /// ([`Camera::tan_half_fov_f64`], what the oracle's cells use) are the same numbers; and a
    /// 2:1 target with a 60° vertical field of view has `ty = tan 30°`, `tx = 2·ty`.
    #[test]
    fn frustum_slopes_match_the_projection_and_aspect() {
        let c = cam(Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 1.0, -5.0), Vec3::Y);
        assert_eq!(c.aspect(), 2.0);
        let t = c.tan_half_fov();
        let ty = 30f64.to_radians().tan();
        assert!(
            (t.y as f64 - ty).abs() < 1e-6 && (t.x as f64 - 2.0 * ty).abs() < 1e-6,
            "{t}"
        );
        let (tx64, ty64) = c.tan_half_fov_f64();
        assert!((tx64 - 2.0 * ty).abs() < 1e-7 && (ty64 - ty).abs() < 1e-7);
        assert!((tx64 - t.x as f64).abs() < 1e-6 && (ty64 - t.y as f64).abs() < 1e-6);
        let world_from_view = c.view_rotation().transpose();
        for (sx, sy) in [(1.0f32, 1.0f32), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
            for depth in [0.5f32, 20.0] {
                let view = Vec3::new(sx * t.x * depth, sy * t.y * depth, -depth);
                let ndc = c.clip_from_view().project_point3(view);
                assert!(
                    (ndc.truncate() - Vec2::new(sx, sy)).length() < 1e-5,
                    "{ndc}"
                );
                let world = c.position + world_from_view * view;
                let ndc_world = c.clip_from_world().project_point3(world);
                assert!((ndc_world - ndc).length() < 1e-4, "{ndc_world} vs {ndc}");
            }
        }
    }

    /// A turned camera's view transform maps the world axes to its own: looking along +X with
    /// `up = +Y`, world +X is view −Z (ahead), +Y stays +Y and +Z is view +X (right) — in f32 and
    /// f64, as a point transform, as `view_from_world` and as the rotation matrices themselves.
    /// (A camera looking down −Z with `up = +Y` has the identity rotation, so it cannot tell.)
    #[test]
    fn a_turned_camera_maps_the_world_axes_to_its_own() {
        let eye = Vec3::new(1.0, 2.0, 3.0);
        let c = cam(eye, eye + Vec3::X * 4.0, Vec3::Y);
        for (world, view) in [
            (Vec3::X, Vec3::NEG_Z),
            (Vec3::Y, Vec3::Y),
            (Vec3::Z, Vec3::X),
        ] {
            let p = eye + world * 5.0;
            let v = c.view_from_world_point(p);
            assert!((v - view * 5.0).length() < 1e-5, "{world}: {v}");
            let v64 = c.view_from_world_point_f64(p.as_dvec3());
            assert!(
                (v64 - view.as_dvec3() * 5.0).length() < 1e-12,
                "{world}: {v64}"
            );
            let m = c.view_from_world().transform_point3(p);
            assert!((m - view * 5.0).length() < 1e-5, "{world}: {m}");
            assert!((c.view_rotation() * world - view).length() < 1e-6);
            let r64 = c.view_rotation_f64() * world.as_dvec3();
            assert!((r64 - view.as_dvec3()).length() < 1e-12, "{world}: {r64}");
        }
    }

    /// `up` only picks the roll: a camera looking down −Z with `up = +X` (rolled 90°) has world
    /// +X as screen up, and an `up` a hair (1e-4 rad) off the view direction still decides the
    /// basis, at any length of `up` — only a truly parallel, zero or non-finite one falls back.
    #[test]
    fn up_sets_the_roll_at_any_length() {
        let rolled = cam(Vec3::ZERO, Vec3::NEG_Z, Vec3::X);
        let (r, u, f) = rolled.basis_f64();
        assert!((u - DVec3::X).length() < 1e-12, "{u:?}");
        assert!((r - DVec3::NEG_Y).length() < 1e-12, "{r:?}");
        assert!((f - DVec3::NEG_Z).length() < 1e-12, "{f:?}");
        // Nearly parallel to the view direction, tilted towards +X: screen up is +X.
        let hint = Vec3::new(1e-4, 0.0, -1.0);
        let unit = cam(Vec3::ZERO, Vec3::NEG_Z, hint).basis_f64();
        assert!((unit.1 - DVec3::X).length() < 1e-6, "{:?}", unit.1);
        for scale in [1e-3f32, 1e3] {
            let scaled = cam(Vec3::ZERO, Vec3::NEG_Z, hint * scale).basis_f64();
            for (a, b) in [(scaled.0, unit.0), (scaled.1, unit.1), (scaled.2, unit.2)] {
                assert!(
                    (a - b).length() < 1e-9,
                    "up scaled by {scale}: {a:?} vs {b:?}"
                );
            }
        }
    }

    /// With no usable `up` the fallback is the world axis least aligned with the view direction,
    /// +Y before +Z before +X on ties: looking along (1, 3, 2) that is +X (|cos| 1/√14 against
    /// 2/√14 for +Z and 3/√14 for +Y), so right is `forward × X`; along (1, 1, 1), all tied,
    /// it is +Y.
    #[test]
    fn fallback_up_is_the_least_aligned_world_axis() {
        for (target, axis) in [
            (Vec3::new(1.0, 3.0, 2.0), DVec3::X),
            (Vec3::new(-2.0, 3.0, 1.0), DVec3::Z),
            (Vec3::new(3.0, 1.0, -2.0), DVec3::Y),
            (Vec3::new(1.0, 1.0, 1.0), DVec3::Y),
        ] {
            for up in [Vec3::ZERO, target, Vec3::splat(f32::NAN)] {
                let (r, u, f) = cam(Vec3::ZERO, target, up).basis_f64();
                let forward = target.as_dvec3().normalize();
                assert!((f - forward).length() < 1e-12, "{f:?}");
                let right = forward.cross(axis).normalize();
                assert!((r - right).length() < 1e-12, "{target} up {up}: {r:?}");
                assert!((u - right.cross(forward)).length() < 1e-12, "{u:?}");
            }
        }
    }

    #[test]
    fn camera_relative_transform_keeps_precision_far_from_origin() {
        let origin = Vec3::new(1.0e6, -2.0e6, 3.0e6);
        let c = cam(origin, origin + Vec3::new(0.0, 0.0, -1.0), Vec3::Y);
        let v = c.view_from_world_point(origin + Vec3::new(0.25, 0.5, -3.0));
        assert!((v - Vec3::new(0.25, 0.5, -3.0)).length() < 1e-6, "{v:?}");
    }
}
