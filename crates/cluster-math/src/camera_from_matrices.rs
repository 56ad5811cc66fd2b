//! A [`Camera`] from an engine's own view and projection matrices.
//!
//! Engines keep a camera as two matrices, not as a position, a target and a field of view. The
//! clusters must be the ones the engine's pixels fall in, so this reads the matrices back into the
//! camera they describe and refuses the ones no [`Camera`] can describe, instead of assigning
//! lights to a frustum that differs from the one on screen:
//!
//! * **Off-centre projections** (a TAA jitter, a stereo eye's asymmetric frustum): tiles here are
//!   uniform in a symmetric NDC, so a shifted frustum would put every tile's lights a fraction of
//!   a tile off. Pass the unjittered projection (engines keep it for exactly this kind of use).
//! * **Mirrored pairs**: a [`Camera`]'s view is right-handed (`right = forward × up` in world
//!   space). A left-handed pair, such as glam's `camera::lh` view and projection, maps world
//!   space to the screen with the opposite orientation; no position, target and up reproduce it.
//!   Mirror the world instead: multiply the view matrix by `Mat4::from_scale(vec3(-1, 1, 1))` on
//!   the right and negate the lights' x the same way; the pixels and clusters are then the same.
//!   A y-down projection read as y-up ([`ClipSpace`]) looks mirrored too, and the matrices cannot
//!   tell the two apart, so the error names both fixes.
//! * **Orthographic, sheared or non-rigid** matrices (a scaled view matrix would scale light radii
//!   too), and an aspect ratio other than the target's `width / height`.
//!
//! The clip depth's direction is read off the matrix (reversed or not; an infinite far plane, or
//! one the depth never reaches, gives `far = f32::INFINITY`, which the assignment accepts with a
//! finite grid and the renderer draws with the infinite reversed-Z projection); its range, 0..1 or
//! −1..1, and whether NDC y points up or down on screen cannot be, so the caller names them
//! ([`ClipSpace`]). Everything is computed in f64; for inputs in this crate's own convention
//! (reversed-Z 0..1, y up) the result's own matrices equal them to f32 rounding (tested; its
//! [`Camera::clip_from_view`] is always that convention), and the depth range and field of view are checked as the f32 camera
//! keeps them (a near plane of 1e-50 or a field of view 1e-9 short of π is refused, not rounded
//! to 0 or π).

use glam::{DMat4, DVec3, DVec4, Mat4};

use crate::Camera;

/// The NDC conventions a projection matrix was built for: its depth range and which way its y
/// points on screen. Pixels are counted from the top-left corner either way; with y down, NDC
/// y = −1 is the top row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClipSpace {
    /// Depth 0..1, y up: wgpu, Direct3D, Metal (glam's `camera::rh::proj::directx`), and this
    /// crate's own [`Camera::clip_from_view`].
    ZeroToOneYUp,
    /// Depth 0..1, y down: raw Vulkan (glam's `camera::rh::proj::vulkan`).
    ZeroToOneYDown,
    /// Depth −1..1, y up: OpenGL (glam's `camera::rh::proj::opengl`).
    MinusOneToOneYUp,
}

/// Why [`Camera::from_matrices`] cannot describe a pair of matrices.
#[derive(Clone, Debug, PartialEq)]
pub enum CameraMatrixError {
    /// An entry is NaN or infinite.
    NonFinite,
    /// The projection is not a perspective of the form `x' = sx·x, y' = sy·y, z' = A·z + B,
    /// w' = ±z` (orthographic, sheared, or zero scales; or scales so large or small that the
    /// field of view is 0 or π in f32); the entry named differs.
    NotPerspective(&'static str),
    /// The projection's centre is shifted (a jitter or an asymmetric frustum), by this much in NDC.
    OffCenter {
        /// NDC shift, x and y.
        shift: [f64; 2],
    },
    /// The projection's depth does not map a positive depth range onto the clip range (one that
    /// stays positive and non-empty in f32).
    DepthRange {
        /// Near plane the matrix implies.
        near: f64,
        /// Far plane the matrix implies.
        far: f64,
    },
    /// The view matrix is not a rotation and a translation: scaled, sheared or projective.
    NotRigid {
        /// Largest deviation of its rotation part from orthonormal, or of its last row from
        /// `(0, 0, 0, 1)`.
        deviation: f64,
    },
    /// The pair maps the world to the screen mirrored against a right-handed [`Camera`].
    Mirrored,
    /// The projection's `sy / sx` is not the target's `width / height`.
    AspectMismatch {
        /// `sy / sx`.
        projection: f64,
        /// `width / height`.
        target: f64,
    },
    /// A zero width or height.
    EmptyTarget,
    /// The camera's position is too large for a finite f32 target point in front of it.
    PositionTooLarge,
    /// The matrices describe a camera that [`Camera::problem`] refuses (a near plane below
    /// [`crate::ClusterGrid::MIN_NEAR`], or a depth range whose `near·far` passes `f32::MAX`):
    /// its message. Refused here rather than by the first grid or frame built on it.
    Unusable(String),
}

impl std::fmt::Display for CameraMatrixError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NonFinite => write!(f, "a matrix entry is NaN or infinite"),
            Self::NotPerspective(entry) => write!(
                f,
                "the projection is not a symmetric perspective (x' = sx·x, y' = sy·y, z' = A·z + B, \
                 w' = ±z): {entry}"
            ),
            Self::OffCenter { shift } => write!(
                f,
                "the projection is off-centre by ({}, {}) in NDC (a jitter or an asymmetric \
                 frustum): clusters are tiles of a centred frustum, so pass the unjittered \
                 projection",
                shift[0], shift[1]
            ),
            Self::DepthRange { near, far } => write!(
                f,
                "the projection's depth maps [{near}, {far}] onto the clip range, not a range \
                 with 0 < near < far (is the ClipSpace right?)"
            ),
            Self::NotRigid { deviation } => write!(
                f,
                "the view matrix is not a rotation and a translation (off by {deviation:e}): \
                 scale the world, not the view"
            ),
            Self::Mirrored => write!(
                f,
                "the view and projection are mirrored against a right-handed camera: a \
                 projection that flips y (Vulkan's y-down convention, e.g. glam's \
                 camera::rh::proj::vulkan) needs ClipSpace::ZeroToOneYDown; a left-handed pair \
                 needs its view matrix multiplied by Mat4::from_scale(vec3(-1.0, 1.0, 1.0)) on \
                 the right and the lights' x negated. (The matrices cannot tell the two apart: \
                 the wrong fix gives a camera upside down.)"
            ),
            Self::AspectMismatch { projection, target } => write!(
                f,
                "the projection's aspect ratio {projection} differs from the target's width / \
                 height {target}"
            ),
            Self::EmptyTarget => write!(f, "the target must be at least 1x1 pixels"),
            Self::PositionTooLarge => write!(
                f,
                "the camera's position is too large for f32 (no finite point in front of it)"
            ),
            Self::Unusable(problem) => write!(f, "the matrices' camera is unusable: {problem}"),
        }
    }
}

impl std::error::Error for CameraMatrixError {}

/// Relative tolerance for entries that must be zero and for the aspect ratio: f32 matrices built
/// from the same numbers agree far closer; a jitter of a thousandth of a pixel at 1920 wide is
/// 1e-6 of NDC, so anything refused here would shift clusters visibly more than rounding does.
/// The centre's shift is held to it in NDC itself (a hundredth of a pixel at 1920 wide), not
/// relative to the projection's scales.
const RELATIVE_TOLERANCE: f64 = 1e-5;

/// Tolerance for the view matrix's rotation part being orthonormal: f32 rotations composed from
/// many steps drift by ~1e-6; a scale of 1.0001 is already a different camera.
const RIGID_TOLERANCE: f64 = 1e-4;

impl Camera {
    /// The camera that `clip_from_view · view_from_world` describes for a `width × height` target,
    /// or why no [`Camera`] describes it (see the module's docs: off-centre, mirrored,
    /// orthographic, non-rigid, or an aspect ratio other than `width / height`).
    ///
    /// Either depth direction is accepted (reversed or not, read off the matrix) and either
    /// handedness of view space, as long as the pair is not mirrored; `clip_space` names the NDC
    /// conventions the projection was built for. An infinite far plane gives `far =
    /// f32::INFINITY`: assignment slices depth by a finite [`crate::ClusterGrid`], and the
    /// renderer draws with it ([`Camera::clip_from_view`] is then the infinite reversed-Z
    /// projection). A far plane read
    /// from a matrix whose depth is not reversed is only as good as the matrix keeps it: there
    /// `far = B / (1 − a)` with `a ≈ 1`, so an f32 matrix of near 0.1 and far 500 gives it to
    /// ~1e-4 (the near plane, and every plane of a reversed matrix, to f32 rounding).
    ///
    /// ```
    /// use myriad_cluster_math::{Camera, ClipSpace, glam::Vec3};
    /// use myriad_cluster_math::glam::camera::rh::{proj::directx, view};
    /// let view = view::look_at_mat4(Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y);
    /// let projection = directx::perspective(1.0, 16.0 / 9.0, 0.1, 500.0);
    /// let camera = Camera::from_matrices(view, projection, ClipSpace::ZeroToOneYUp, 1920, 1080)?;
    /// assert!((camera.near - 0.1).abs() < 1e-6 && (camera.far / 500.0 - 1.0).abs() < 1e-3);
    /// # Ok::<(), myriad_cluster_math::CameraMatrixError>(())
    /// ```
    pub fn from_matrices(
        view_from_world: Mat4,
        clip_from_view: Mat4,
        clip_space: ClipSpace,
        width: u32,
        height: u32,
    ) -> Result<Camera, CameraMatrixError> {
        if width == 0 || height == 0 {
            return Err(CameraMatrixError::EmptyTarget);
        }
        if !(view_from_world.is_finite() && clip_from_view.is_finite()) {
            return Err(CameraMatrixError::NonFinite);
        }
        let projection = read_projection(clip_from_view.as_dmat4(), clip_space)?;
        let view = read_view(view_from_world.as_dmat4())?;

        // World directions along which view depth, NDC x and NDC y grow.
        let forward = view.rows[2] * projection.w_sign;
        let right = view.rows[0] * projection.sx.signum();
        let up = view.rows[1] * projection.sy.signum();
        if forward.cross(up).dot(right) < 0.0 {
            return Err(CameraMatrixError::Mirrored);
        }
        let target_aspect = width as f64 / height as f64;
        let aspect = projection.sy.abs() / projection.sx.abs();
        if (aspect / target_aspect - 1.0).abs() > RELATIVE_TOLERANCE {
            return Err(CameraMatrixError::AspectMismatch {
                projection: aspect,
                target: target_aspect,
            });
        }

        // The target sits far enough ahead that f32 rounding of the point barely turns the view:
        // one unit ahead of a camera at 10⁶ would round the direction by ~0.06 rad.
        let reach = 1024.0 * view.position.abs().max_element().max(1.0);
        let target = view.position + forward * reach;
        let (position, target) = (view.position.as_vec3(), target.as_vec3());
        if !(position.is_finite() && target.is_finite()) {
            return Err(CameraMatrixError::PositionTooLarge);
        }
        let camera = Camera {
            position,
            target,
            up: up.as_vec3(),
            fov_y: projection.fov_y,
            width,
            height,
            near: projection.near,
            far: projection.far,
        };
        match camera.problem() {
            Some(problem) => Err(CameraMatrixError::Unusable(problem)),
            None => Ok(camera),
        }
    }
}

/// What a symmetric perspective projection says, normalised so `w' = w_sign · z`; the camera's
/// own numbers in f32.
struct Projection {
    sx: f64,
    sy: f64,
    w_sign: f64,
    fov_y: f32,
    near: f32,
    far: f32,
}

fn read_projection(m: DMat4, clip_space: ClipSpace) -> Result<Projection, CameraMatrixError> {
    use CameraMatrixError::NotPerspective;
    // Any non-zero multiple of a projection matrix gives the same NDC: scale w' to ±z.
    let w_scale = m.z_axis.w;
    if w_scale == 0.0 {
        return Err(NotPerspective("w' does not depend on z (orthographic?)"));
    }
    let mut m = m * (1.0 / w_scale.abs());
    if clip_space == ClipSpace::ZeroToOneYDown {
        // The same pixels as y up with the projection's y negated.
        m = DMat4::from_scale(glam::DVec3::new(1.0, -1.0, 1.0)) * m;
    }
    let (sx, sy) = (m.x_axis.x, m.y_axis.y);
    if sx == 0.0 || sy == 0.0 {
        return Err(NotPerspective("a zero x or y scale"));
    }
    let scale = sx.abs().max(sy.abs()).max(1.0);
    let zero = |value: f64| value.abs() <= RELATIVE_TOLERANCE * scale;
    if !(zero(m.x_axis.w) && zero(m.y_axis.w) && zero(m.w_axis.w)) {
        return Err(NotPerspective("w' depends on x, y or 1, not on z alone"));
    }
    if !(zero(m.x_axis.y) && zero(m.x_axis.z) && zero(m.y_axis.x) && zero(m.y_axis.z)) {
        return Err(NotPerspective(
            "x' or y' or z' mixes x and y (shear, rotation, or an oblique near plane)",
        ));
    }
    if !(zero(m.w_axis.x) && zero(m.w_axis.y)) {
        return Err(NotPerspective("x' or y' has a constant term"));
    }
    // The centre's shift is NDC itself, whatever the scales: held to a fixed tolerance, not one
    // that grows with a narrow field of view's scales (at 0.02 rad, 1e-3 of NDC: a half-pixel
    // TAA jitter at 1920 wide went through as centred, audit).
    let centred = |shift: f64| shift.abs() <= RELATIVE_TOLERANCE;
    if !(centred(m.z_axis.x) && centred(m.z_axis.y)) {
        // NDC x = sx·x / (w_sign·z) + shift_x·…: the centre's offset is z_axis.xy · w_sign.
        let shift = [m.z_axis.x * m.z_axis.w, m.z_axis.y * m.z_axis.w];
        return Err(CameraMatrixError::OffCenter { shift });
    }
    // z_ndc = (A·z + B) / (w_sign·z); with depth d = w_sign·z, z_ndc = a + B/d, a = A·w_sign.
    let w_sign = m.z_axis.w.signum();
    let (a, b) = (m.z_axis.z * w_sign, m.w_axis.z);
    let low = match clip_space {
        ClipSpace::ZeroToOneYUp | ClipSpace::ZeroToOneYDown => 0.0,
        ClipSpace::MinusOneToOneYUp => -1.0,
    };
    // Reversed when NDC depth falls with distance (B > 0): near maps to 1, far to `low`.
    let (ndc_near, ndc_far) = if b > 0.0 { (1.0, low) } else { (low, 1.0) };
    // NDC depth runs monotonically from ±∞ at the eye to `a` at infinity, so it reaches the far
    // plane's value at a positive depth only if `a` lies beyond it. Where it never does (an
    // infinite far plane: `a` exactly at the value, or a rounding short of it, or a projection
    // that leaves part of the depth range unused), nothing far away is clipped: far is infinite.
    // The near plane must be reached, or no depth at all is visible.
    let (near, far) = (b / (ndc_near - a), b / (ndc_far - a));
    let far = if far > 0.0 { far } else { f64::INFINITY };
    // Checked as the camera keeps them, in f32: a near plane under 1e-45 rounds to 0 there, near
    // and far closer than its resolution to one plane, and a field of view within 1e-7 of π to π.
    let (near_f32, far_f32) = (near as f32, far as f32);
    if !(near_f32 > 0.0 && near_f32.is_finite() && far_f32 > near_f32) {
        return Err(CameraMatrixError::DepthRange { near, far });
    }
    let fov_y = (2.0 * (1.0 / sy.abs()).atan()) as f32;
    if !(fov_y > 0.0 && fov_y < std::f32::consts::PI) {
        return Err(NotPerspective(
            "a field of view of 0 or π in f32 (x and y scales too large or too small)",
        ));
    }
    Ok(Projection {
        sx,
        sy,
        w_sign,
        fov_y,
        near: near_f32,
        far: far_f32,
    })
}

/// A rigid view matrix's rotation rows (world directions of view x, y, z) and the eye position.
struct View {
    rows: [DVec3; 3],
    position: DVec3,
}

fn read_view(m: DMat4) -> Result<View, CameraMatrixError> {
    let rows = [0, 1, 2].map(|i| m.row(i).truncate());
    let mut deviation = (m.row(3) - DVec4::W).abs().max_element();
    for i in 0..3 {
        for j in 0..3 {
            let expected = if i == j { 1.0 } else { 0.0 };
            deviation = deviation.max((rows[i].dot(rows[j]) - expected).abs());
        }
    }
    if deviation > RIGID_TOLERANCE {
        return Err(CameraMatrixError::NotRigid { deviation });
    }
    // view = M·world + t, so the eye (view origin) is −M⁻¹·t: −Mᵀ·t only where M is exactly
    // orthonormal, and the check above lets a scale of 1 ± 1e-4 through, which moved the eye
    // by that much of its distance from the origin (a view scaled 1.00004 at z = 10⁴ read the
    // eye 0.8 off, audit), though such a scale moves no pixel.
    let t = m.w_axis.truncate();
    let position = -(glam::DMat3::from_mat4(m).inverse() * t);
    Ok(View { rows, position })
}
