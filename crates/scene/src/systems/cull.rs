//! Frustum culling of lights: which lights' volumes can touch the view frustum.
//!
//! Why before assignment: a light entirely outside the frustum lights no visible pixel, and the
//! cheapest work is the work not done (the project brief: "skip what a scene doesn't need"). The
//! test is **conservative**: it may keep a light that misses the frustum (near the frustum's
//! edges and corners, where six plane tests cannot see that a sphere passes outside), never
//! drop one that touches it. For that the radius is padded against f32 rounding exactly as the
//! assignment pads it ([`myriad_cluster_math::pad_radius`]): unpadded, lights grazing a side
//! plane from inside were dropped that the assignment (and the f64 oracle) put in a cluster
//! (5 625 of 46 067 such lights, audit f2).
//!
//! A valid light whose view-space sphere overflows f32 — a radius near `f32::MAX` (an engine's
//! "infinite range"), or an offset from the camera beyond ~1.7·10³⁸ — cannot be judged by the
//! plane tests and is kept: the assignment decides such lights in f64. The same pass finds the
//! invalid lights (a non-finite position or radius, a radius not positive), which are dropped
//! and counted ([`Visibility::invalid`]). Both come from one test the block loop makes anyway
//! (`r > 0` and a finite padded radius); only a block holding a light that fails it is looked
//! at again. (Until 2026-12-01 such lights were culled uncounted, and a radius of `f32::MAX`
//! was culled where the assignment lists it everywhere: review.)
//!
//! ## The test, per light
//! 1. The centre goes to view space camera-relative: `R · (p − eye)`.
//! 2. Six planes with outward unit normals `n` and offsets `d` (a point is outside when
//!    `n·x > d`): near `(0, 0, 1)`, `−near`; far `(0, 0, −1)`, `far`; the four sides through the
//!    eye, `(±1, 0, tx)/√(1+tx²)` and `(0, ±1, ty)/√(1+ty²)`, offset 0, where `tx`, `ty` are the
//!    tangents of the half fields of view.
//!
//! Per block of lights, the sphere test runs first over every light in a branch-free loop the
//! compiler vectorises; only spots that pass it get the (scalar) cone test, which can only
//! tighten the answer since the cone lies inside its sphere.
//! 3. A light is culled when its volume lies entirely outside one plane: the smallest value of
//!    `n·x` over the volume exceeds `d`. For a sphere that is `n·c − r > d`. For a spot light —
//!    the sector of points within range `r` of the apex `a` and within angle `θ` of the axis
//!    `u` — it is `n·a − r·m − pad > d` with `m = max(0, cos(max(0, α − θ)))`, where `α` is the
//!    angle between `−n` and `u`: the farthest the sector reaches against `n` is along the cone
//!    direction closest to `−n`, and not behind the apex; `pad` is the sphere's f32 allowance,
//!    added whatever the cone's reach. This is exact per plane, so a spot
//!    pointing away from the frustum is culled even when its range sphere reaches in. A point
//!    light in a mixed set (angle π) gets `m = 1`, the sphere test; so does a spot whose axis or
//!    angle bounds nothing (a zero or non-finite axis, an angle ≤ 0, NaN or wider than 90°, whose
//!    sector is not convex), as in the oracle and the assignment. Axes
//!    need not be unit length: each is scaled by its largest component, then normalised.

use super::{BLOCK, LightSlices, PARALLEL_MIN, fast_sin_cos};
use glam::{Mat3, Vec3};
use myriad_cluster_math::{Camera, pad_radius};
use rayon::prelude::*;

/// The output of [`cull_lights`], reused frame to frame.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Visibility {
    /// `mask[i]`: whether light `i` may touch the frustum.
    pub mask: Vec<bool>,
    /// Indices of the visible lights, ascending.
    pub indices: Vec<u32>,
    /// Visible lights per block (scratch of the compaction).
    counts: Vec<u32>,
    /// Invalid lights per block.
    invalid_counts: Vec<u32>,
    /// Invalid lights of the last cull: see [`Self::invalid`].
    invalid: usize,
}

impl Visibility {
    /// Empty outputs.
    pub fn new() -> Self {
        Self::default()
    }

    /// Lights the last [`cull_lights`] dropped as invalid: a position or radius that is not
    /// finite, or a radius that is not positive — what the assignment counts as
    /// `AssignStats::rejected` when it is handed such a light. Counted here because a cull that
    /// drops them leaves the assignment nothing to count: without this number they would
    /// vanish from a frame's statistics (audit). Never part of [`Self::indices`].
    pub fn invalid(&self) -> usize {
        self.invalid
    }
}

/// The camera's planes in view space.
#[derive(Clone, Copy, Debug)]
struct Frustum {
    eye: Vec3,
    view_from_world: Mat3,
    near: f32,
    far: f32,
    /// Tangents of the half fields of view.
    tan_x: f32,
    tan_y: f32,
    /// `√(1 + tan²)`: the side planes' normal lengths before normalising.
    len_x: f32,
    len_y: f32,
    /// Outward unit normals of the right, left, top and bottom planes (all through the eye).
    sides: [Vec3; 4],
}

impl Frustum {
    fn new(camera: &Camera) -> Self {
        let t = camera.tan_half_fov();
        let (len_x, len_y) = ((1.0 + t.x * t.x).sqrt(), (1.0 + t.y * t.y).sqrt());
        Self {
            eye: camera.position,
            view_from_world: camera.view_rotation(),
            near: camera.near,
            far: camera.far,
            tan_x: t.x,
            tan_y: t.y,
            len_x,
            len_y,
            sides: [
                Vec3::new(1.0, 0.0, t.x) / len_x,
                Vec3::new(-1.0, 0.0, t.x) / len_x,
                Vec3::new(0.0, 1.0, t.y) / len_y,
                Vec3::new(0.0, -1.0, t.y) / len_y,
            ],
        }
    }

    /// Step 3 for the light's range sphere, centre `p` (world), radius `r`: selects and
    /// comparisons only, so the block loop vectorises. The side planes are tested without
    /// normalising: `|x| − tan·depth ≤ r·√(1 + tan²)`.
    ///
    /// Returns `(visible, sound)`. `sound`: `r > 0` and the padded radius finite, which holds
    /// for every valid light ([`is_valid`]) whose view-space sphere fits f32 — the padded
    /// radius sums every view coordinate, so a non-finite input makes it non-finite — and for
    /// no invalid one. A light that is not sound is not `visible` here (an infinite radius
    /// passed every plane): [`test_block`] then counts it if invalid and keeps it if valid. A few operations a light: testing [`is_valid`] itself here made the point
    /// cull 23% slower (`cull/points/1000000` 0.96–1.01 → 1.19–1.26 ms, three interleaved runs
    /// of `cargo bench --bench scene_systems`), this about 5% (→ 1.05–1.09 ms).
    #[inline(always)] // Into both builds of `test_block`.
    fn sphere_visible(&self, p: Vec3, r: f32) -> (bool, bool) {
        let c = self.view_from_world * (p - self.eye);
        let depth = -c.z;
        let padded = pad_radius(c.x, c.y, depth, r);
        let sound = (r > 0.0) & padded.is_finite();
        let r = padded;
        let visible = (depth + r >= self.near)
            & (depth - r <= self.far)
            & (c.x.abs() - self.tan_x * depth <= r * self.len_x)
            & (c.y.abs() - self.tan_y * depth <= r * self.len_y);
        (visible & sound, sound)
    }

    /// Step 3 for a spot cone with apex `p`, range `r`, axis `axis` (any length) and half angle
    /// `angle`: the sector's exact reach against each plane. Branch-free (selects only), so a
    /// loop over a block vectorises. Meaningful for what [`is_cone`] accepts; callers treat the
    /// rest as point lights.
    // Left out of line by the AVX2 build of `test_block` with a plain `#[inline]`: the cone loop
    // then ran a call per light, 4.5× slower than the baseline build.
    #[inline(always)]
    fn cone_visible(&self, p: Vec3, r: f32, axis: Vec3, angle: f32) -> bool {
        let c = self.view_from_world * (p - self.eye);
        // The pad is added to every plane's reach, not to the range: a cone pointing out of a
        // plane reaches 0 against it, and scaling the pad by that lost the apex's own rounding.
        let pad = pad_radius(c.x, c.y, -c.z, r) - r;
        let axis = self.view_from_world * unit_axis(axis);
        let (sin_t, cos_t) = fast_sin_cos(angle);
        // Whether the sector lies entirely outside the plane with outward unit normal n and
        // offset d; its reach against n is r, or r·cos(α − θ) (≥ 0) when α > θ. sin α comes from
        // the cross product: √(1 − cos²α) is 0 in f32 within 2.4e-4 rad of the normal, the
        // whole reach of a cone near 90° tilted that little into the frustum (audit g3).
        let outside = |n: Vec3, d: f32| {
            let cos_a = -n.dot(axis);
            let sin_a = n.cross(axis).length();
            let tilted = r * (cos_a * cos_t + sin_a * sin_t).max(0.0);
            let reach = if cos_a >= cos_t { r } else { tilted };
            n.dot(c) - reach - pad > d
        };
        let [right, left, top, bottom] = self.sides;
        !(outside(Vec3::Z, -self.near)
            | outside(Vec3::NEG_Z, self.far)
            | outside(right, 0.0)
            | outside(left, 0.0)
            | outside(top, 0.0)
            | outside(bottom, 0.0))
    }

    /// The per-light kernel, the slow twin of the block passes in [`cull_lights`] (the tests
    /// hold them equal): whether light `i` may touch the frustum. Its sphere must pass, and a
    /// spot's cone too (the cone lies inside the sphere, so this only tightens).
    #[cfg(test)]
    fn visible(&self, lights: &LightSlices<'_>, i: usize) -> bool {
        let p = Vec3::new(lights.x[i], lights.y[i], lights.z[i]);
        let r = lights.radius[i];
        let (sphere, sound) = self.sphere_visible(p, r);
        is_valid(p, r)
            && (!sound
                || sphere
                    && lights.spot.as_ref().is_none_or(|s| {
                        let axis = Vec3::new(s.dir_x[i], s.dir_y[i], s.dir_z[i]);
                        !is_cone(axis, s.angle[i]) || self.cone_visible(p, r, axis, s.angle[i])
                    }))
    }
}

/// Whether a spot entry bounds a cone: an angle in (0, π/2] (not NaN; in f64, as the oracle
/// decides: f32's `FRAC_PI_2` rounds above π/2) and an axis [`unit_axis`] can normalise.
/// Anything else shines all round, as the assignment and the oracle treat it; a cone wider than
/// 90° was culled when it pointed away although both keep its ball (audit g1).
#[inline]
fn is_cone(axis: Vec3, angle: f32) -> bool {
    let largest = axis.abs().max_element();
    (angle > 0.0) & (angle < std::f32::consts::FRAC_PI_2) & (largest > 0.0) & axis.is_finite()
}

/// `axis` at unit length, for any finite non-zero length: divided by its largest component
/// first, so neither a tiny axis (whose squared length underflows) nor a huge one (overflows)
/// loses its direction. Degenerate axes give NaN; [`is_cone`] excludes them.
#[inline]
fn unit_axis(axis: Vec3) -> Vec3 {
    let scaled = axis / axis.abs().max_element();
    scaled / scaled.length()
}

/// Whether a light can be assigned at all: a finite position and a finite, positive radius
/// (the assignment's own test, [`Visibility::invalid`]). Branch-free, for the block loop.
#[inline(always)]
fn is_valid(p: Vec3, r: f32) -> bool {
    // `&`, not glam's `is_finite` (`&&`): no branch in the vectorised loop.
    (r > 0.0) & (r < f32::INFINITY) & p.x.is_finite() & p.y.is_finite() & p.z.is_finite()
}

/// The sphere test over the block of lights from `start` (`mask.len()` of them), then the cone
/// test for its spots, into `mask`; returns how many of the block's lights are invalid
/// ([`is_valid`]: they are never visible). Built twice, for AVX2 (eight lanes) and for the
/// baseline (SSE2, four), the faster picked at run time; both compute the same numbers (no
/// fused multiply-add: Rust never contracts one).
#[multiversion::multiversion(targets("x86_64+avx+avx2+fma"))]
fn test_block(frustum: &Frustum, lights: &LightSlices<'_>, start: usize, mask: &mut [bool]) -> u32 {
    let end = start + mask.len();
    let (x, y, z, r) = (
        &lights.x[start..end],
        &lights.y[start..end],
        &lights.z[start..end],
        &lights.radius[start..end],
    );
    // Counted in u32: a usize sum halves the vector width.
    let mut unsound = 0u32;
    for j in 0..mask.len() {
        let (visible, sound) = frustum.sphere_visible(Vec3::new(x[j], y[j], z[j]), r[j]);
        mask[j] = visible;
        unsound += !sound as u32;
    }
    if let Some(s) = &lights.spot {
        let (dx, dy, dz, angle) = (
            &s.dir_x[start..end],
            &s.dir_y[start..end],
            &s.dir_z[start..end],
            &s.angle[start..end],
        );
        // Over every light of the block (vectorised), not just the spots: cheaper than a
        // branch per light when spots are mixed in.
        for j in 0..mask.len() {
            let axis = Vec3::new(dx[j], dy[j], dz[j]);
            let p = Vec3::new(x[j], y[j], z[j]);
            let cone = frustum.cone_visible(p, r[j], axis, angle[j]);
            mask[j] &= !is_cone(axis, angle[j]) | cone;
        }
    }
    // The unsound lights, in the rare block that has one: the invalid are counted (and stay
    // culled); the valid, whose view-space sphere overflowed f32 (a radius near `f32::MAX`,
    // an offset from the camera past it), are kept whatever the plane or cone tests said of
    // their overflowed numbers: the assignment decides them in f64.
    let mut invalid = 0;
    if unsound > 0 {
        for j in 0..mask.len() {
            let p = Vec3::new(x[j], y[j], z[j]);
            if !is_valid(p, r[j]) {
                invalid += 1;
            } else if !frustum.sphere_visible(p, r[j]).1 {
                mask[j] = true;
            }
        }
    }
    invalid
}

/// Culls `lights` against `camera`'s frustum into `out`: `out.mask[i]` for every light and
/// `out.indices`, the visible ones ascending. Returns how many are visible. Invalid lights
/// (a non-finite position or radius, a radius not positive) are never visible, and are counted
/// in [`Visibility::invalid`]. Parallel in blocks above [`super::PARALLEL_MIN`] lights; the
/// result does not depend on the thread count.
///
/// The frustum is the camera's, from its near to its far plane: a cluster grid reaching nearer
/// or farther than the camera (an engine's own grid) has cells no pixel lies in, and a light
/// only in those is culled although it touches them — assigned after this cull, such lists
/// are the exact ones within the camera's view.
pub fn cull_lights(camera: &Camera, lights: LightSlices<'_>, out: &mut Visibility) -> usize {
    crate::profiling::profile_span!("cull lights");
    lights.assert_consistent();
    let n = lights.len();
    let frustum = Frustum::new(camera);
    let blocks = n.div_ceil(BLOCK);
    out.mask.resize(n, false);
    out.indices.resize(n, 0);
    out.counts.resize(blocks, 0);
    out.invalid_counts.resize(blocks, 0);
    // One block, in three passes: the sphere test over every light (vectorised), the cone
    // test for the spots that passed it, then the block's visible indices written at the start
    // of its own region of `indices`, and counted.
    let block = |b: usize, mask: &mut [bool], indices: &mut [u32], counts: (&mut u32, &mut u32)| {
        let start = b * BLOCK;
        *counts.1 = test_block(&frustum, &lights, start, mask);
        let mut k = 0;
        for (j, &m) in mask.iter().enumerate() {
            indices[k] = (start + j) as u32;
            k += m as usize;
        }
        *counts.0 = k as u32;
    };
    if n < PARALLEL_MIN {
        for (b, (((mask, indices), count), invalid)) in out
            .mask
            .chunks_mut(BLOCK)
            .zip(out.indices.chunks_mut(BLOCK))
            .zip(out.counts.iter_mut())
            .zip(out.invalid_counts.iter_mut())
            .enumerate()
        {
            block(b, mask, indices, (count, invalid));
        }
    } else {
        (
            out.mask.par_chunks_mut(BLOCK),
            out.indices.par_chunks_mut(BLOCK),
            out.counts.par_iter_mut(),
            out.invalid_counts.par_iter_mut(),
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(b, (mask, indices, count, invalid))| {
                block(b, mask, indices, (count, invalid))
            });
    }
    out.invalid = out.invalid_counts.iter().map(|&n| n as usize).sum();
    // Compaction: move each block's run down to the write cursor (never past its own start).
    let mut cursor = 0;
    for (b, &count) in out.counts.iter().enumerate() {
        let start = b * BLOCK;
        out.indices
            .copy_within(start..start + count as usize, cursor);
        cursor += count as usize;
    }
    out.indices.truncate(cursor);
    cursor
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lights::{LightRecord, Lights};
    use rand::{Rng, SeedableRng};

    fn camera() -> Camera {
        Camera::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(4.0, 1.0, -20.0),
            Vec3::Y,
            60.0,
            1600,
            900,
            0.5,
            40.0,
        )
    }

    /// Whether `p` is strictly inside the frustum (the definition the cull must respect).
    fn inside(camera: &Camera, p: Vec3) -> bool {
        let v = camera.view_from_world_point(p);
        let t = camera.tan_half_fov();
        let d = -v.z;
        d > camera.near && d < camera.far && v.x.abs() < t.x * d && v.y.abs() < t.y * d
    }

    fn random_lights(n: usize, seed: u64, spots: bool) -> Lights {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        (0..n)
            .map(|i| {
                let p = Vec3::new(
                    rng.random_range(-60.0..60.0),
                    rng.random_range(-40.0..40.0),
                    rng.random_range(-70.0..30.0),
                );
                let light =
                    LightRecord::point(p, rng.random_range(0.1..12.0)).with_source_index(i as u32);
                if spots && rng.random_bool(0.7) {
                    let d = Vec3::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    )
                    .normalize_or(Vec3::X);
                    light.with_spot(d, rng.random_range(0.05..3.0))
                } else {
                    light
                }
            })
            .collect()
    }

    /// A point of the light's volume: sphere, or spot sector.
    fn sample_volume(light: &LightRecord, rng: &mut impl Rng) -> Option<Vec3> {
        let v = Vec3::new(
            rng.random_range(-1.0f32..1.0),
            rng.random_range(-1.0f32..1.0),
            rng.random_range(-1.0f32..1.0),
        );
        if v.length() > 1.0 {
            return None;
        }
        if let Some(cone) = light.spot
            && v.length() > 0.0
            && v.normalize().dot(cone.direction) < cone.angle.cos()
        {
            return None;
        }
        Some(light.position + v * light.radius)
    }

    #[test]
    fn conservative_against_sampled_volumes() {
        let camera = camera();
        let mut rng = rand_pcg::Pcg64::seed_from_u64(99);
        for spots in [false, true] {
            let lights = random_lights(3000, 5, spots);
            let mut vis = Visibility::new();
            let visible = cull_lights(&camera, lights.slices(), &mut vis);
            assert!(visible > 50 && visible < 2900, "{visible}");
            for (i, light) in lights.iter().enumerate() {
                if vis.mask[i] {
                    continue;
                }
                for _ in 0..400 {
                    if let Some(p) = sample_volume(&light, &mut rng) {
                        assert!(!inside(&camera, p), "light {i} culled but {p} is visible");
                    }
                }
            }
        }
    }

    /// Spheres grazing the frustum from outside by 0–1e-4 of their distance, on random cameras,
    /// plus spots whose axis or angle bound nothing: every light the f64 oracle sees touching
    /// the frustum (a 1×1×1 grid's one cell) is kept. Unpadded, the cull dropped thousands.
    /// A random camera for the grazing tests: anywhere, any direction, fields of view 5–150°.
    fn random_camera(rng: &mut rand_pcg::Pcg64) -> Camera {
        let eye = Vec3::new(
            rng.random_range(-50.0..50.0),
            rng.random_range(-50.0..50.0),
            rng.random_range(-50.0..50.0),
        );
        let look = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let fov = rng.random_range(5.0..150.0);
        let (near, far) = (rng.random_range(0.01..1.0), rng.random_range(20.0..500.0));
        Camera::new(eye, eye + look, Vec3::Y, fov, 1920, 1080, near, far)
    }

    /// A random point on face `face % 6` of `camera`'s frustum (right, left, top, bottom, near,
    /// far) and that face's outward unit normal, in view space (f64).
    fn face_point(
        rng: &mut rand_pcg::Pcg64,
        camera: &Camera,
        face: usize,
    ) -> (glam::DVec3, glam::DVec3) {
        let t = camera.tan_half_fov().as_dvec2();
        let (near, far) = (camera.near as f64, camera.far as f64);
        let depth = rng.random_range(near..far);
        let (u, v) = (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        let (p, normal) = match face % 6 {
            0 => (
                glam::DVec3::new(t.x * depth, v * t.y * depth, -depth),
                glam::DVec3::new(1.0, 0.0, t.x),
            ),
            1 => (
                glam::DVec3::new(-t.x * depth, v * t.y * depth, -depth),
                glam::DVec3::new(-1.0, 0.0, t.x),
            ),
            2 => (
                glam::DVec3::new(u * t.x * depth, t.y * depth, -depth),
                glam::DVec3::new(0.0, 1.0, t.y),
            ),
            3 => (
                glam::DVec3::new(u * t.x * depth, -t.y * depth, -depth),
                glam::DVec3::new(0.0, -1.0, t.y),
            ),
            4 => (
                glam::DVec3::new(u * t.x * near, v * t.y * near, -near),
                glam::DVec3::Z,
            ),
            _ => (
                glam::DVec3::new(u * t.x * far, v * t.y * far, -far),
                glam::DVec3::NEG_Z,
            ),
        };
        (p, normal.normalize())
    }

    /// Culls `lights` and counts, of those the f64 oracle sees touching `camera`'s frustum,
    /// how many touch and how many the cull dropped.
    fn touching_and_dropped(camera: &Camera, lights: &Lights) -> (usize, usize) {
        use myriad_cluster_math::oracle::{Cell, OracleView};
        use myriad_cluster_math::{ClusterGrid, DepthSlicing};
        let grid = ClusterGrid::new(
            glam::UVec3::ONE,
            DepthSlicing::Linear,
            camera.near,
            camera.far,
        );
        let cell = Cell::of_cluster(camera, &grid, 0, 0, 0);
        let oracle = OracleView::new(camera);
        let mut vis = Visibility::new();
        cull_lights(camera, lights.slices(), &mut vis);
        let (mut touching, mut dropped) = (0, 0);
        for (i, light) in lights.iter().enumerate() {
            let spot = light.spot.map(|s| (s.direction, s.angle));
            let volume = oracle.light(light.position, light.radius, spot).unwrap();
            if volume.intersects_cell(&cell) {
                touching += 1;
                dropped += usize::from(!vis.mask[i]);
            }
        }
        (touching, dropped)
    }

    /// Over `cameras` random cameras, `per_camera` lights each made by `light` from a random point
    /// on face `i % 6` and that face's outward normal (view space, f64; `light` also gets the
    /// rng, the camera, its world-from-view rotation and `i`): how many the f64 oracle sees
    /// touching each camera's frustum, and how many of those the cull dropped.
    fn face_lights_touching_and_dropped(
        seed: u64,
        cameras: usize,
        per_camera: usize,
        mut light: impl FnMut(
            &mut rand_pcg::Pcg64,
            &Camera,
            glam::DMat3,
            usize,
            glam::DVec3,
            glam::DVec3,
        ) -> LightRecord,
    ) -> (usize, usize) {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let (mut touching, mut dropped) = (0, 0);
        for _ in 0..cameras {
            let camera = random_camera(&mut rng);
            let world_from_view = camera.view_rotation_f64().transpose();
            let mut lights = Lights::new();
            for i in 0..per_camera {
                let (p, normal) = face_point(&mut rng, &camera, i);
                lights.push(light(&mut rng, &camera, world_from_view, i, p, normal));
            }
            let (t, d) = touching_and_dropped(&camera, &lights);
            (touching, dropped) = (touching + t, dropped + d);
        }
        (touching, dropped)
    }

    #[test]
    fn lights_grazing_the_frustum_are_kept_when_the_oracle_sees_them_touch() {
        let (touching, dropped) = face_lights_touching_and_dropped(
            17,
            60,
            400,
            |rng, camera, world_from_view, i, p, normal| {
                // A point on one of the six faces, then out along its normal by r·(1 − ε).
                let eye = camera.position;
                let r = rng.random_range(0.01..5.0f64);
                let p = p + normal * r * (1.0 - rng.random_range(0.0..1e-4));
                let world = (eye.as_dvec3() + world_from_view * p).as_vec3();
                let light = LightRecord::point(world, r as f32);
                match i % 7 {
                    // Spots that bound nothing: zero axis, NaN or non-positive angle.
                    0 => light.with_spot(Vec3::ZERO, 0.3),
                    1 => light.with_spot(Vec3::X, f32::NAN),
                    2 => light.with_spot(Vec3::Y, 0.0),
                    // A tiny axis pointing back at the frustum is a real cone.
                    3 => light.with_spot(-(world - eye) * 1e-30, 0.4),
                    _ => light,
                }
            },
        );
        assert!(touching > 5000, "only {touching} grazing lights touch");
        assert_eq!(dropped, 0, "{dropped} of {touching} touching lights culled");
    }

    /// A spot of range `r` and half angle `half_angle` whose edge nearest a face's inward
    /// normal −n reaches `r·sin(tilt)` past its apex's plane: its axis makes α = θ + π/2 − tilt
    /// with −n, turned about n by a random angle.
    struct Leaning {
        r: f64,
        half_angle: f64,
        tilt: f64,
    }

    impl Leaning {
        /// The spot with its apex `out(rng) · r·sin(tilt)` outside the face point `p` (view
        /// space, outward unit `normal`), in world space.
        fn light(
            &self,
            rng: &mut rand_pcg::Pcg64,
            camera: &Camera,
            world_from_view: glam::DMat3,
            p: glam::DVec3,
            normal: glam::DVec3,
            out: impl FnOnce(&mut rand_pcg::Pcg64) -> f64,
        ) -> LightRecord {
            let alpha = self.half_angle + std::f64::consts::FRAC_PI_2 - self.tilt;
            let phi = rng.random_range(0.0..std::f64::consts::TAU);
            let t0 = normal.any_orthonormal_vector();
            let tangent = t0 * phi.cos() + normal.cross(t0) * phi.sin();
            let axis = -normal * alpha.cos() + tangent * alpha.sin();
            let apex = p + normal * out(rng) * self.r * self.tilt.sin();
            let world = camera.position.as_dvec3() + world_from_view * apex;
            LightRecord::point(world.as_vec3(), self.r as f32)
                .with_spot((world_from_view * axis).as_vec3(), self.half_angle as f32)
        }
    }

    #[test]
    fn cones_grazing_the_frustum_are_kept_when_the_oracle_sees_them_touch() {
        // Audit g3: a spot with its apex just outside a face, its axis the face's outward normal
        // tilted so that the cone's edge reaches in by r·sin ε, was culled (√(1 − cos²α) was 0
        // in f32, and the pad was scaled by the cone's reach, 0 for a cone pointing out).
        use std::f64::consts::FRAC_PI_2;
        let (touching, dropped) = face_lights_touching_and_dropped(
            29,
            40,
            300,
            |rng, camera, world_from_view, _, p, normal| {
                let r = rng.random_range(0.05..50.0f64);
                let half_angle = rng.random_range(0.01..FRAC_PI_2 - 1e-6);
                let tilt = 10f64.powf(rng.random_range(-6.0..-2.0));
                let cone = Leaning {
                    r,
                    half_angle,
                    tilt,
                };
                cone.light(rng, camera, world_from_view, p, normal, |rng| {
                    rng.random_range(-0.5..2.0)
                })
            },
        );
        assert!(touching > 1000, "only {touching} grazing cones touch");
        assert_eq!(dropped, 0, "{dropped} of {touching} touching cones culled");
    }

    /// Audit g3's own case, which the uniform angles above almost never draw: a cone within
    /// 1.2e-4 of 90° whose axis leans a hair past the face, so the angle α between −n and the
    /// axis is within 2.4e-4 of π, where √(1 − cos²α) is 0 in f32. With that formula back in
    /// place of the cross product, 1,957 of these 8,847 touching cones were culled (mutation
    /// audit).
    #[test]
    fn wide_cones_leaning_a_hair_into_a_face_are_kept() {
        use std::f64::consts::FRAC_PI_2;
        let (touching, dropped) = face_lights_touching_and_dropped(
            33,
            40,
            300,
            |rng, camera, world_from_view, _, p, normal| {
                let r = rng.random_range(5.0..50.0f64);
                let half_angle = FRAC_PI_2 - rng.random_range(1e-6..1.2e-4);
                let tilt = rng.random_range(1e-5..1e-4);
                let cone = Leaning {
                    r,
                    half_angle,
                    tilt,
                };
                cone.light(rng, camera, world_from_view, p, normal, |_| 0.5)
            },
        );
        assert!(touching > 5000, "only {touching} leaning cones touch");
        assert_eq!(dropped, 0, "{dropped} of {touching} touching cones culled");
    }

    #[test]
    fn cones_pointing_straight_out_from_a_face_are_kept() {
        // Apex on a face (f64), axis its outward normal: the cone reaches nothing past the apex
        // against that face, so only the pad keeps the f32 test from dropping it.
        let (touching, dropped) = face_lights_touching_and_dropped(
            31,
            40,
            300,
            |rng, camera, world_from_view, _, p, normal| {
                let r = rng.random_range(0.05..50.0f64);
                let world = camera.position.as_dvec3() + world_from_view * p;
                LightRecord::point(world.as_vec3(), r as f32)
                    .with_spot((world_from_view * normal).as_vec3(), 0.3)
            },
        );
        assert!(touching > 1000, "only {touching} cones touch");
        assert_eq!(dropped, 0, "{dropped} of {touching} touching cones culled");
    }

    #[test]
    fn parallel_equals_serial_kernel_and_compaction_is_ordered() {
        let camera = camera();
        let lights = random_lights(5 * BLOCK + 123, 8, true);
        let mut vis = Visibility::new();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        let visible = pool.install(|| cull_lights(&camera, lights.slices(), &mut vis));
        let frustum = Frustum::new(&camera);
        let serial: Vec<u32> = (0..lights.len())
            .filter(|&i| frustum.visible(&lights.slices(), i))
            .map(|i| i as u32)
            .collect();
        assert_eq!(vis.indices, serial);
        assert_eq!(visible, serial.len());
        assert_eq!(vis.mask.iter().filter(|&&m| m).count(), visible);
        // Reuse with fewer lights: outputs shrink, nothing stale remains.
        let few = random_lights(10, 8, false);
        let v2 = cull_lights(&camera, few.slices(), &mut vis);
        assert_eq!((vis.mask.len(), vis.indices.len()), (10, v2));
    }

    /// A valid light whose view-space sphere overflows f32 — a radius of `f32::MAX`, an
    /// engine's "infinite range" — is kept, whatever its cone says, and not counted as invalid:
    /// the assignment lists it (in f64). The first cut of the invalid count culled it uncounted
    /// (review); before that count it was kept.
    #[test]
    fn valid_lights_whose_sphere_overflows_f32_are_kept_and_not_counted() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 100, 100, 0.1, 100.0);
        let at = |z: f32, r: f32| LightRecord::point(Vec3::new(0.0, 0.0, z), r);
        let lights: Lights = [
            at(-10.0, f32::MAX),
            at(-10.0, f32::MAX * 0.9999999),
            at(10.0, f32::MAX),
            at(-10.0, f32::MAX).with_spot(Vec3::Z, 0.3),
            at(-10.0, f32::NAN),
            at(-10.0, 1.0),
            at(10.0, 1.0),
        ]
        .into_iter()
        .collect();
        let mut vis = Visibility::new();
        cull_lights(&camera, lights.slices(), &mut vis);
        assert_eq!(vis.mask, [true, true, true, true, false, true, false]);
        assert_eq!(vis.invalid(), 1);
        let frustum = Frustum::new(&camera);
        assert!((0..lights.len()).all(|i| frustum.visible(&lights.slices(), i) == vis.mask[i]));
        // In a parallel run too, among ordinary lights.
        let n = PARALLEL_MIN + 5;
        let random = random_lights(n, 43, true);
        let many: Lights = (0..n)
            .map(|i| match i % 97 {
                5 => at(-10.0, f32::MAX),
                6 => at(-10.0, f32::NAN),
                _ => random.get(i),
            })
            .collect();
        cull_lights(&camera, many.slices(), &mut vis);
        assert_eq!(vis.invalid(), (0..n).filter(|i| i % 97 == 6).count());
        assert!((0..n).filter(|i| i % 97 == 5).all(|i| vis.mask[i]));
        assert!((0..n).all(|i| frustum.visible(&many.slices(), i) == vis.mask[i]));
    }

    #[test]
    fn invalid_lights_are_dropped_and_counted_whatever_their_place() {
        // Each invalid light sits where a valid one would be visible (in the middle of the
        // view), or reaches everything (an infinite radius, which every plane test passes).
        // Before the count, NaN and negative radii and non-finite positions were culled
        // uncounted while an infinite or zero radius was kept (for the assignment to count),
        // so a frame's statistics lost some of them (audit).
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 100, 100, 0.1, 100.0);
        let at = |x: f32, y: f32, z: f32, r: f32| LightRecord::point(Vec3::new(x, y, z), r);
        let invalid = [
            at(0.0, 0.0, -10.0, f32::NAN),
            at(0.0, 0.0, -10.0, -50.0),
            at(0.0, 0.0, -10.0, -1.0),
            at(0.0, 0.0, -10.0, 0.0),
            at(0.0, 0.0, -10.0, f32::INFINITY),
            at(f32::NAN, 0.0, -10.0, 1.0),
            at(0.0, f32::INFINITY, -10.0, 1.0),
            at(0.0, 0.0, f32::NEG_INFINITY, 1.0),
            at(1e30, 0.0, -10.0, f32::NAN),
        ];
        for spots in [false, true] {
            // The invalid lights spread among valid ones, over several blocks, serial and
            // parallel (past `PARALLEL_MIN`).
            for n in [40, 3 * BLOCK + 17, PARALLEL_MIN + 5] {
                let random = random_lights(n, 41, spots);
                let is_invalid: Vec<bool> = (0..n).map(|i| i % 7 == 3).collect();
                // `far`: the invalid lights replaced by a valid light behind the camera.
                let with = |far: bool| -> Lights {
                    (0..n)
                        .map(|i| {
                            if !is_invalid[i] {
                                return random.get(i);
                            }
                            let bad = if far {
                                at(0.0, 0.0, 1e4, 1.0)
                            } else {
                                invalid[(i / 7) % invalid.len()]
                            };
                            let bad = if spots && i % 2 == 0 {
                                bad.with_spot(Vec3::NEG_Z, 0.4)
                            } else {
                                bad
                            };
                            bad.with_source_index(i as u32)
                        })
                        .collect()
                };
                let lights = with(false);
                let mut vis = Visibility::new();
                let visible = cull_lights(&camera, lights.slices(), &mut vis);
                let expected = is_invalid.iter().filter(|&&b| b).count();
                assert_eq!(vis.invalid(), expected, "{n} lights, spots {spots}");
                assert_eq!(visible, vis.indices.len());
                // The valid lights' verdicts are their own: the same as with the invalid ones
                // replaced by a light behind the camera.
                let mut reference = Visibility::new();
                cull_lights(&camera, with(true).slices(), &mut reference);
                assert_eq!(vis.indices, reference.indices, "{n} lights, spots {spots}");
                assert_eq!(reference.invalid(), 0);
                // The per-light twin agrees.
                let frustum = Frustum::new(&camera);
                assert!((0..n).all(|i| frustum.visible(&lights.slices(), i) == vis.mask[i]));
            }
        }
        // Recounted every call, not accumulated.
        let mut vis = Visibility::new();
        let bad: Lights = invalid.into_iter().collect();
        assert_eq!(cull_lights(&camera, bad.slices(), &mut vis), 0);
        assert_eq!(vis.invalid(), invalid.len());
        let good: Lights = [at(0.0, 0.0, -10.0, 1.0)].into_iter().collect();
        assert_eq!(cull_lights(&camera, good.slices(), &mut vis), 1);
        assert_eq!(vis.invalid(), 0);
    }

    #[test]
    fn exact_cases_spheres_and_cones() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 90.0, 100, 100, 1.0, 10.0);
        let point = |z: f32, r: f32| LightRecord::point(Vec3::new(0.0, 0.0, z), r);
        let lights: Lights = [
            point(-0.5, 0.49),  // in front of the near plane (depth 1), not reaching it
            point(-0.5, 0.51),  // reaches across the near plane
            point(-10.5, 0.49), // beyond far
            point(-10.5, 0.51),
            // Behind the camera, range 5 reaches into the frustum, but pointing backwards.
            LightRecord::point(Vec3::new(0.0, 0.0, 2.0), 5.0).with_spot(Vec3::Z, 0.3),
            // The same spot pointing forwards.
            LightRecord::point(Vec3::new(0.0, 0.0, 2.0), 5.0).with_spot(Vec3::NEG_Z, 0.3),
            // Off to the right (x = 8 at depth 5, side plane at x = 5), pointing away/towards.
            LightRecord::point(Vec3::new(8.0, 0.0, -5.0), 4.0).with_spot(Vec3::X, 0.5),
            LightRecord::point(Vec3::new(8.0, 0.0, -5.0), 4.0).with_spot(Vec3::NEG_X, 0.5),
            // Wider than 90° the oracle and the assignment take the ball (audit g1): kept.
            LightRecord::point(Vec3::new(0.0, 0.0, 2.0), 5.0)
                .with_spot(Vec3::Z, 100f32.to_radians()),
            // f32's π/2 lies above π/2: a ball too; the f32 just below it is a cone.
            LightRecord::point(Vec3::new(0.0, 0.0, 3.5), 5.0)
                .with_spot(Vec3::Z, std::f32::consts::FRAC_PI_2),
            LightRecord::point(Vec3::new(0.0, 0.0, 3.5), 5.0)
                .with_spot(Vec3::Z, std::f32::consts::FRAC_PI_2.next_down()),
        ]
        .into_iter()
        .collect();
        let mut vis = Visibility::new();
        cull_lights(&camera, lights.slices(), &mut vis);
        assert_eq!(
            vis.mask,
            [
                false, true, false, true, false, true, false, true, true, true, false
            ]
        );
        // Without the spot columns the cones are spheres: the backward spot is kept.
        let spheres = LightSlices {
            spot: None,
            ..lights.slices()
        };
        cull_lights(&camera, spheres, &mut vis);
        assert!(vis.mask[4]);
    }

    #[test]
    fn spots_pointing_out_through_one_or_two_faces_are_culled() {
        // Each range sphere reaches into the frustum; each cone lies entirely outside the faces
        // named, and only those, so every single plane's verdict decides its light.
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 90.0, 100, 100, 1.0, 10.0);
        let spot = |p: [f32; 3], r: f32, axis: [f32; 3], angle: f32| {
            LightRecord::point(Vec3::from(p), r).with_spot(Vec3::from(axis), angle)
        };
        let lights: Lights = [
            // Near only: the apex half a metre in front of the eye, pointing backwards.
            spot([0.0, 0.0, -0.5], 5.0, [0.0, 0.0, 1.0], 0.3),
            // Far only: the apex half a metre beyond it, pointing further away.
            spot([0.0, 0.0, -10.5], 4.0, [0.0, 0.0, -1.0], 0.3),
            // Right only, wide: its edge reaches 0.83 of the apex's 2.12 back towards the plane.
            spot([8.0, 0.0, -5.0], 4.0, [1.0, 0.0, 0.0], 1.0),
            // The same, tilted up: an axis that is not along a coordinate axis; reach 1.83.
            spot([8.0, 0.0, -5.0], 4.0, [1.0, 1.0, 0.0], 1.0),
            // Left, top and bottom only.
            spot([-8.0, 0.0, -5.0], 4.0, [-1.0, 0.0, 0.0], 0.5),
            spot([0.0, 8.0, -5.0], 4.0, [0.0, 1.0, 0.0], 0.5),
            spot([0.0, -8.0, -5.0], 4.0, [0.0, -1.0, 0.0], 0.5),
            // Two faces at once: far and right, left and top.
            spot([14.0, 0.0, -12.0], 5.0, [0.924, 0.0, -0.383], 0.3),
            spot([-8.0, 8.0, -5.0], 4.0, [-1.0, 1.0, 0.0], 0.3),
        ]
        .into_iter()
        .collect();
        let mut vis = Visibility::new();
        cull_lights(&camera, lights.slices(), &mut vis);
        assert_eq!(vis.mask, [false; 9]);
        let spheres = LightSlices {
            spot: None,
            ..lights.slices()
        };
        cull_lights(&camera, spheres, &mut vis);
        assert_eq!(vis.mask, [true; 9]);
    }

    #[test]
    fn a_spot_whose_axis_has_a_nan_component_is_its_ball() {
        // A non-finite axis bounds nothing: the oracle and the assignment normalise it to zero
        // and take the range's ball, which here reaches across the near plane.
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 90.0, 100, 100, 1.0, 10.0);
        let nan = f32::NAN;
        let lights: Lights = [
            Vec3::new(nan, 0.0, 1.0),
            Vec3::new(0.0, nan, 1.0),
            Vec3::new(nan, nan, 1.0),
            Vec3::new(0.0, 1.0, nan),
        ]
        .into_iter()
        .map(|axis| LightRecord::point(Vec3::new(0.0, 0.0, -0.5), 5.0).with_spot(axis, 0.3))
        .collect();
        let (touching, dropped) = touching_and_dropped(&camera, &lights);
        assert_eq!((touching, dropped), (4, 0));
    }
}
