//! Per-light geometry of the three axis phases and the refinement, as plain functions.
//!
//! Conventions: view space, depth `d = −z > 0` in front of the eye. A light arrives here as its
//! view-space centre `(cx, cy, dc)` (dc = depth of the centre) and a *padded* radius (see
//! [`pad_radius`]), which absorbs every f32 rounding error of the transform and of the comparisons
//! below, so the f32 paths stay conservative against the f64 oracle.
//!
//! 1. **z phase**: the depth band `[da, db]` the sphere occupies inside `[near, far]`, and the slices
//!    it touches, by binary search of the z-plane set (the slice edges).
//! 2. **x and y phases**: the range of slopes (`x/d`, `y/d`) the sphere covers, by intersecting two
//!    conservative bounds — the exact tangent planes from the eye and the box
//!    `[c ± R] × [da, db]` of the sphere's part inside the band — and then the tiles whose plane
//!    slopes overlap that range, by searching the x- and y-plane sets (`search.rs`).
//! 3. **refinement** (method `refined`): per slice, the sphere shrunk to the slab is bounded by a
//!    cylinder of radius `R_k`; a cluster of the slab is kept when its column's and row's gaps to
//!    the centre satisfy `dx² + dy² ≤ R_k²` (the x tiles of `[cx ± sqrt(R_k² − dy²)]`), decided per
//!    row by counting, against the per-slice squared column gaps — no square root, division or
//!    plane search per row.

use crate::search::FramePlanes;
use glam::DVec3;
use myriad_cluster_math::Camera;

/// Relative padding of light radii ([`myriad_cluster_math::RADIUS_PAD`], shared with the frame
/// systems' frustum cull): 4e-6 of the light's view-space extent.
pub(crate) use myriad_cluster_math::{RADIUS_PAD as PAD, pad_radius};

/// A spot light's unit axis in view space, from its world axis `(x, y, z)` of any length.
///
/// Normalised in f64 first: an f32 axis about 1e-20 long has a subnormal squared length, which
/// f32 normalised to 0.8–1.02, and every method, `exact` included, then bounded a distorted cone
/// (misses of up to 44 of 63 clusters, found by an audit; the f64 oracle normalises in f64). A
/// zero or non-finite axis gives zero, which callers treat as a point light, as the oracle does.
#[inline]
pub(crate) fn spot_view_axis(view_from_world: glam::Mat3, x: f32, y: f32, z: f32) -> glam::Vec3 {
    let unit = DVec3::new(x.into(), y.into(), z.into()).normalize_or_zero();
    (view_from_world * unit.as_vec3()).normalize_or_zero()
}

/// Depth band and slices touched by a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ZRange {
    /// Nearest depth of the sphere inside `[near, far]`.
    pub da: f32,
    /// Farthest depth of the sphere inside `[near, far]`.
    pub db: f32,
    /// First slice.
    pub k0: u32,
    /// Last slice (inclusive).
    pub k1: u32,
}

/// z phase: `None` when the sphere misses `[near, far]`. (Slow twin of the block pass.)
#[cfg(test)]
pub(crate) fn z_phase(dc: f32, r: f32, planes: &FramePlanes<'_>) -> Option<ZRange> {
    let z = &planes.sets.z_depths;
    let da = (dc - r).max(z[0]);
    let db = (dc + r).min(z[z.len() - 1]);
    if !(da <= db) {
        return None;
    }
    Some(ZRange {
        da,
        db,
        k0: planes.first_slice(da),
        k1: planes.slice_of(db),
    })
}

/// Whether a world-space sphere may touch the frustum (six plane tests, as the early cull), in f64:
/// for the rare finite light whose view-space sphere does not fit in f32 (coordinates and radius
/// near `f32::MAX`), which the f32 phases cannot take. `z_depths` are the frame's slice edges.
#[cold]
pub(crate) fn may_touch_frustum_f64(
    camera: &Camera,
    z_depths: &[f32],
    world: DVec3,
    r: f64,
) -> bool {
    let v = camera.view_from_world_point_f64(world);
    let d = -v.z;
    let (tx, ty) = camera.tan_half_fov_f64();
    let (near, far) = (
        f64::from(z_depths[0]),
        f64::from(z_depths[z_depths.len() - 1]),
    );
    // Padded by 1e-9 of the extent, far above f64's rounding here, so tangency is kept.
    let r = r + 1e-9 * (v.length() + r);
    // Signed distances to the inside of each side plane: x ≥ −tx·d, x ≤ tx·d, the same for y.
    let (sx, sy) = ((1.0 + tx * tx).sqrt(), (1.0 + ty * ty).sqrt());
    (v.x + tx * d) / sx >= -r
        && (tx * d - v.x) / sx >= -r
        && (v.y + ty * d) / sy >= -r
        && (ty * d - v.y) / sy >= -r
        && d + r >= near
        && d - r <= far
}

/// Half-width of the sphere's cross-section at the depth in `[da, db]` nearest its centre — the
/// radius of the cylinder that bounds the sphere's part inside the band.
#[inline]
pub(crate) fn band_radius(dc: f32, r: f32, da: f32, db: f32) -> f32 {
    // Selects, not branches: the z phase's pass over a block vectorises. Inside the band the
    // cut is computed and thrown away (it may be NaN there).
    let (before, past) = (dc < da, dc > db);
    let dist = if before { da - dc } else { dc - db };
    let cut = ((r - dist).max(0.0) * (r + dist)).sqrt();
    if before | past { cut } else { r }
}

/// Slope range `[min, max]` of the points `(x, d)` with `x ∈ [lo, hi]`, `d ∈ [da, db]`, `da > 0`.
#[inline]
pub(crate) fn box_slopes(lo: f32, hi: f32, da: f32, db: f32) -> (f32, f32) {
    // The extreme slopes sit at the near depth for the far side of zero and at the far depth for
    // the near side; division is correctly rounded and monotone, so this equals the min/max over
    // all four corners with two divisions instead of four.
    let min = lo / if lo >= 0.0 { db } else { da };
    let max = hi / if hi >= 0.0 { da } else { db };
    (min, max)
}

/// Slope range of the tangent planes from the eye to a circle of radius `r` at `(c, dc)` in the
/// plane spanned by one screen axis and depth; ±∞ where a tangent does not point forward.
///
/// Computed in f32 and branch-free (the block pass vectorises it), which is accurate enough only
/// while the eye is clearly outside the circle: with distance `L ≥ 1.1 r`, the tangent length
/// `h = sqrt((L − r)(L + r))` has a relative error of at most ~6 ulps (the factored form avoids
/// the cancellation of `L² − r²`), so the tangent directions are off by at most ~2·10⁻⁶ rad —
/// inside the radius padding (`PAD` = 4·10⁻⁶ of the distance). Closer than that the bound is
/// dropped (±∞) and the depth-band box bound alone applies, which is conservative.
#[inline]
pub(crate) fn tangent_slopes(c: f32, dc: f32, r: f32) -> (f32, f32) {
    let l = (c * c + dc * dc).sqrt();
    let far_enough = l >= 1.1 * r;
    let h = ((l - r).max(0.0) * (l + r)).sqrt();
    let den_max = dc * h - c * r;
    let den_min = dc * h + c * r;
    let max = (c * h + dc * r) / den_max;
    let min = (c * h - dc * r) / den_min;
    let max = if far_enough & (den_max > 0.0) {
        max.next_up()
    } else {
        f32::INFINITY
    };
    let min = if far_enough & (den_min > 0.0) {
        min.next_down()
    } else {
        f32::NEG_INFINITY
    };
    (min, max)
}

/// A light's cluster box after the three axis phases.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ClusterBox {
    pub z: ZRange,
    pub i0: u32,
    pub i1: u32,
    pub j0: u32,
    pub j1: u32,
}

/// The three axis phases for one padded view-space sphere. `None`: outside the frustum. The slow
/// twin of `phases::Block::run_phases`, which must give the same boxes.
#[cfg(test)]
pub(crate) fn cluster_box(
    cx: f32,
    cy: f32,
    dc: f32,
    r: f32,
    planes: &FramePlanes<'_>,
) -> Option<ClusterBox> {
    let z = z_phase(dc, r, planes)?;
    let big_r = band_radius(dc, r, z.da, z.db);
    let (bx0, bx1) = box_slopes(cx - big_r, cx + big_r, z.da, z.db);
    let (tx0, tx1) = tangent_slopes(cx, dc, r);
    let (i0, i1) = planes.columns(bx0.max(tx0), bx1.min(tx1))?;
    let (by0, by1) = box_slopes(cy - big_r, cy + big_r, z.da, z.db);
    let (ty0, ty1) = tangent_slopes(cy, dc, r);
    let (j0, j1) = planes.rows(by0.max(ty0), by1.min(ty1))?;
    Some(ClusterBox { z, i0, i1, j0, j1 })
}

/// `max` of two numbers that are never NaN, as one `maxss` (`f32::max` adds a NaN test and a
/// blend); every input of [`BoxRefiner::slice`] is finite.
#[inline(always)]
fn fmax(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// `min` of two numbers that are never NaN, as one `minss`.
#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// Scratch [`BoxRefiner`] needs for a grid of `dims`: a squared gap per tile column and a room
/// per tile row.
pub(crate) fn refine_scratch_len(dims: glam::UVec3) -> usize {
    dims.x as usize + dims.y as usize
}

/// Refinement of one slice `k` of a light's box: calls `row(j, i0, i1)` for every row of the slice
/// the sphere (shrunk to the slab) can touch, with the tightened x tile span — or returns `true`
/// without calling it when the slab's disc reaches the box's farthest corner, so that every
/// cluster of the box's slice is kept (the caller then pushes the slice whole, as one span of
/// rows). `gaps` is scratch of at least [`refine_scratch_len`]. The emit refines a box's slices
/// with one [`BoxRefiner`]; this is the same for one slice.
#[cfg(test)]
#[allow(clippy::too_many_arguments)] // One light's columns, as the emit passes them.
#[must_use = "`true` keeps the box's whole slice, and `row` was called for none of its rows"]
pub(crate) fn refine_slice(
    cx: f32,
    cy: f32,
    dc: f32,
    r: f32,
    b: &ClusterBox,
    k: u32,
    planes: &FramePlanes<'_>,
    gaps: &mut [f32],
    row: impl FnMut(u32, u32, u32),
) -> bool {
    let z = &planes.sets.z_depths;
    let edges = (z[k as usize], z[k as usize + 1]);
    BoxRefiner::new(b, planes, gaps).slice(cx, cy, dc, r, edges, row)
}

/// One light's box, refined slice by slice ([`BoxRefiner::slice`]).
///
/// A cluster `(i, j)` of the slab is kept when `dx² ≤ R_k² − dy²`, where `dx` (`dy`) is the distance
/// from the centre to the column's (row's) band of x (y) over the slab's depths `[ka, kb]` — the
/// same test as intersecting the row's half-width `w = sqrt(R_k² − dy²)` with the columns' slopes,
/// without a square root, a division or a search per row. Columns left of the centre are ordered
/// by distance (their gaps fall as `i` grows, rounding included: products and `max` are monotone),
/// and so are those right of it, so the kept columns of a row are the box's columns less a prefix
/// and a suffix: the leading (trailing) run of per-slice squared gaps above the row's room. (Walking
/// those runs replaced counting the whole columns branch-free: `paper` 1000 serial 75 → 65 µs,
/// `uniform` 100k 3% slower, `myriad bench --threads 1`, interleaved builds.) In f32 the
/// radius padding grows `(R_k − dy)(R_k + dy)` by about `2·R_k·PAD·|c|`, far above the few ulps
/// the squares and products round by. (It replaced a square root and a plane search per row:
/// identical lists on `paper` 1000 and `uniform` 100k/1M, `paper` 1000 `refined` 1.35× faster.)
///
/// The box's plane slopes and the scratch are sliced, and its corner planes read, once a box
/// rather than once a slice (their bounds checks and reloads were ~25 of the ~130 instructions a
/// `paper` 1000 slice spent before its rows); and each column has one squared gap, whichever side
/// of the centre it lies on, from plane products shared by the columns on both sides of each
/// plane (two arrays of gaps, each computed from both edges of every column, before). callgrind,
/// `myriad bench --threads 1`, the assignment's instructions a frame, lists byte-identical:
/// `paper` 1000 `refined` 1.537 → 1.482 M (the gaps) → 1.413 M (once a box), `uniform` 100k
/// 34.9 → 33.4 → 33.2 M; `binary` unchanged.
pub(crate) struct BoxRefiner<'a> {
    /// The `columns + 1` x slopes of the box's column edges.
    xs: &'a [f32],
    /// The `rows + 1` y slopes of the box's row edges.
    ys: &'a [f32],
    /// Scratch: a squared gap per column.
    gaps: &'a mut [f32],
    /// Scratch: a room per row.
    rooms: &'a mut [f32],
    /// The slopes of the inner edges of the first and last columns, and the edges of the first
    /// and last rows (top, bottom): what the whole-slice test reads.
    x_first: f32,
    x_last: f32,
    y_first: (f32, f32),
    y_last: (f32, f32),
    i0: u32,
    i1: u32,
    j0: u32,
    da: f32,
    db: f32,
}

impl<'a> BoxRefiner<'a> {
    /// The box `b`, with `scratch` of at least [`refine_scratch_len`].
    #[inline(always)]
    pub(crate) fn new(b: &ClusterBox, planes: &FramePlanes<'a>, scratch: &'a mut [f32]) -> Self {
        let sets = planes.sets;
        let columns = (b.i1 - b.i0 + 1) as usize;
        let rows = (b.j1 - b.j0 + 1) as usize;
        let xs = &sets.x_slopes[b.i0 as usize..][..columns + 1];
        let ys = &sets.y_slopes[b.j0 as usize..][..rows + 1];
        let (gaps, rest) = scratch.split_at_mut(columns);
        Self {
            xs,
            ys,
            gaps,
            rooms: &mut rest[..rows],
            x_first: xs[1],
            x_last: xs[columns - 1],
            y_first: (ys[0], ys[1]),
            y_last: (ys[rows - 1], ys[rows]),
            i0: b.i0,
            i1: b.i1,
            j0: b.j0,
            da: b.z.da,
            db: b.z.db,
        }
    }

    /// Refinement of the box's slice between the depths `(z0, z1)` (its edges): calls
    /// `row(j, i0, i1)` for every row of the slice the sphere (shrunk to the slab) can touch,
    /// with the tightened x tile span — or returns `true` without calling it when the slab's disc
    /// reaches the box's farthest corner, so that every cluster of the box's slice is kept (the
    /// caller then pushes the slice whole, as one span of rows).
    #[allow(clippy::too_many_arguments)] // One light's columns, passed by value in the hot loop.
    #[inline(always)]
    #[must_use = "`true` keeps the box's whole slice, and `row` was called for none of its rows"]
    pub(crate) fn slice(
        &mut self,
        cx: f32,
        cy: f32,
        dc: f32,
        r: f32,
        (z0, z1): (f32, f32),
        mut row: impl FnMut(u32, u32, u32),
    ) -> bool {
        let ka = fmax(z0, self.da);
        let kb = fmin(z1, self.db);
        if !(ka <= kb) {
            return false;
        }
        let rk = band_radius(dc, r, ka, kb);
        // The farthest column and row sit at the box's ends (the gaps fall towards the centre).
        // When the slab's disc reaches that corner nothing can be cut: the whole slice, no
        // per-row work.
        let row_gap = |(top, bottom): (f32, f32)| {
            let y_lo = fmin(bottom * ka, bottom * kb);
            let y_hi = fmax(top * ka, top * kb);
            fmax(fmax(y_lo - cy, cy - y_hi), 0.0)
        };
        let dy = fmax(row_gap(self.y_first), row_gap(self.y_last));
        let (x_first, x_last) = (self.x_first, self.x_last);
        let gap_first = cx - fmax(x_first * ka, x_first * kb);
        let gap_last = fmin(x_last * ka, x_last * kb) - cx;
        let dx = fmax(fmax(gap_first, gap_last), 0.0);
        if dy <= rk && dx * dx <= (rk - dy) * (rk + dy) {
            return true;
        }
        let (xs, ys) = (self.xs, self.ys);
        let gaps = &mut *self.gaps;
        let columns = gaps.len() as u32;
        // Each column's squared gap to the centre, whichever side it lies on (0 for a column the
        // centre lies in: no column lies wholly left and wholly right of it). Each plane's
        // products serve the columns on both sides of it.
        let (a, b) = (xs[0] * ka, xs[0] * kb);
        let mut lo = fmin(a, b);
        for (gap, &s1) in gaps.iter_mut().zip(&xs[1..]) {
            let (a, b) = (s1 * ka, s1 * kb);
            let dx = fmax(fmax(cx - fmax(a, b), lo - cx), 0.0);
            *gap = dx * dx;
            lo = fmin(a, b);
        }
        // Each row's room first, branch-free (`−1` for a row the disc misses), so that the walks
        // below hold nothing of the slab's geometry in registers.
        let (a, b) = (ys[0] * ka, ys[0] * kb);
        let mut y_hi = fmax(a, b);
        for (room, &bottom) in self.rooms.iter_mut().zip(&ys[1..]) {
            let (a, b) = (bottom * ka, bottom * kb);
            let y_lo = fmin(a, b);
            let dy = fmax(fmax(y_lo - cy, cy - y_hi), 0.0);
            *room = if dy > rk { -1.0 } else { (rk - dy) * (rk + dy) };
            y_hi = fmax(a, b);
        }
        let gaps = &*gaps;
        for (j, &room) in (self.j0..).zip(self.rooms.iter()) {
            // `dy ≤ rk` gives `room ≥ 0`, and the rows it fails were given −1.
            if room < 0.0 {
                continue;
            }
            // The gaps fall towards the centre from both ends, so the kept columns are one run
            // between a cut prefix and a cut suffix. A walk that passes the centre's columns (a
            // centre beside the box) has every gap beyond above the room too, and then the two
            // walks together cut the whole row.
            let cut_left = gaps.iter().take_while(|&&g| g > room).count() as u32;
            let cut_right = gaps.iter().rev().take_while(|&&g| g > room).count() as u32;
            // (A row cut from both sides to nothing is skipped before `i1` could wrap below 0.)
            if cut_left + cut_right < columns {
                row(j, self.i0 + cut_left, self.i1 - cut_right);
            }
        }
        false
    }
}

/// Conservative cone-vs-sphere test for spot lights: may a spot (apex, unit axis, cos/sin of the
/// half angle ≤ 90°, range) touch the sphere (centre, radius)? False only when the sphere lies
/// entirely outside the cone's angle, behind its apex, or beyond its range.
///
/// Rounding: the apex, axis and range arrive unpadded (f32 view-space values whose error grows
/// with their size), so the sphere is grown by [`PAD`] of every magnitude in play. Without that
/// slack the stability proptest found `binary` rejecting a cluster the cone reaches (a camera
/// 80 km from the origin, a 1e9 depth range, 1.4 cm clusters). The distance across the axis is the
/// length of the perpendicular vector, not `√(|v|² − along²)`, whose cancellation costs about
/// `|v|·√ε` for a small sphere nearly on the axis of a far apex.
#[inline]
pub(crate) fn cone_may_touch_sphere(
    apex: glam::Vec3,
    axis: glam::Vec3,
    cos_sin: (f32, f32),
    range: f32,
    centre: glam::Vec3,
    radius: f32,
) -> bool {
    // In f64: clusters of a far plane near f32::MAX have centres and radii whose squares, and
    // even whose distances to the apex, overflow f32 (an infinite `across` rejected such
    // clusters; found by an audit with far = 3.4e38). The inputs are f32, so f64 holds every
    // product exactly enough and the padding below still covers the f32 inputs' own error.
    let (apex, axis, centre) = (apex.as_dvec3(), axis.as_dvec3(), centre.as_dvec3());
    let (range, radius) = (f64::from(range), f64::from(radius));
    let slack =
        f64::from(PAD) * (apex.abs().element_sum() + centre.abs().element_sum() + range + radius);
    let r = radius + slack;
    let v = centre - apex;
    let along = v.dot(axis);
    let reach = range + r;
    if along < -r || v.length_squared() > reach * reach {
        return false;
    }
    // Distance from the centre to the cone's surface when outside it (a lower bound otherwise).
    let across = (v - axis * along).length();
    let (cos, sin) = (f64::from(cos_sin.0), f64::from(cos_sin.1));
    cos * across - along * sin <= r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tangent_slopes_bound_the_circle() {
        for &(c, dc, r) in &[
            (0.0f32, 10.0f32, 1.0f32),
            (5.0, 10.0, 1.0),
            (-3.0, 2.0, 1.5),
            (10.0, -1.0, 5.0),
        ] {
            let (lo, hi) = tangent_slopes(c, dc, r);
            for step in 0..3600 {
                let a = step as f32 / 3600.0 * std::f32::consts::TAU;
                let (x, d) = (c + r * a.cos(), dc + r * a.sin());
                if d > 1e-3 {
                    let s = x / d;
                    assert!(
                        s >= lo - 1e-4 * s.abs() && s <= hi + 1e-4 * s.abs(),
                        "{c},{dc},{r}: {s} not in [{lo},{hi}]"
                    );
                }
            }
        }
    }

    /// A circle `(c, dc, r)` for the tangent tests: radius 1e-4–1e4, its centre in a random
    /// direction at `10^e` radii from the eye, `e` drawn from `log_distance`.
    fn random_circle(
        rng: &mut rand_pcg::Pcg64,
        log_distance: std::ops::Range<f32>,
    ) -> (f32, f32, f32) {
        use rand::Rng;
        let r = 10f32.powf(rng.random_range(-4.0..4.0));
        let l = r * 10f32.powf(rng.random_range(log_distance));
        let a = rng.random_range(-std::f32::consts::PI..std::f32::consts::PI);
        (l * a.sin(), l * a.cos(), r)
    }

    /// The two tangents from the eye to the circle of radius `r` around `(c, dc)` (the eye
    /// outside it), in f64: `[(num, den)]` of the largest slope's, then the smallest's, each
    /// slope `num / den`. `(num, den) / L²` is the tangent's unit direction, so `den / L²` is
    /// its depth.
    fn exact_tangents(c: f64, dc: f64, r: f64) -> [(f64, f64); 2] {
        let l = (c * c + dc * dc).sqrt();
        let h = ((l - r) * (l + r)).sqrt();
        [
            (c * h + dc * r, dc * h - c * r),
            (c * h - dc * r, dc * h + c * r),
        ]
    }

    /// What the phases rely on: with the radius padded as every light's is, the f32 slopes
    /// contain the exact (f64) tangent slopes of the unpadded circle — no tolerance — from far
    /// away down to the eye inside the circle (then the bound must be dropped: ±∞), and when a
    /// tangent turns backwards (its slope must then be unbounded too).
    #[test]
    fn padded_tangent_slopes_contain_the_exact_ones() {
        use rand::SeedableRng;
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        let (mut bounded, mut dropped) = (0, 0);
        for _ in 0..200_000 {
            // Distance from the eye: 0.3–1e4 radii, plenty of them close to 1.1 r.
            let (c, dc, r) = random_circle(&mut rng, -0.5..4.0);
            let padded = pad_radius(c, 0.0, dc, r);
            let (lo, hi) = tangent_slopes(c, dc, padded);
            let (c64, dc64, r64) = (c as f64, dc as f64, r as f64);
            let l64 = (c64 * c64 + dc64 * dc64).sqrt();
            if l64 <= r64 {
                assert_eq!((lo, hi), (f32::NEG_INFINITY, f32::INFINITY), "eye inside");
                dropped += 1;
                continue;
            }
            let [(num_max, den_max), (num_min, den_min)] = exact_tangents(c64, dc64, r64);
            let context = format!("c {c}, dc {dc}, r {r} (padded {padded}): [{lo}, {hi}]");
            if den_max > 0.0 {
                let exact = num_max / den_max;
                assert!(hi as f64 >= exact, "max {exact}: {context}");
                bounded += hi.is_finite() as usize;
            } else {
                assert_eq!(hi, f32::INFINITY, "backward max tangent: {context}");
            }
            if den_min > 0.0 {
                let exact = num_min / den_min;
                assert!(lo as f64 <= exact, "min {exact}: {context}");
            } else {
                assert_eq!(lo, f32::NEG_INFINITY, "backward min tangent: {context}");
            }
        }
        assert!(
            bounded > 50_000 && dropped > 1000,
            "{bounded} bounded, {dropped} dropped"
        );
    }

    /// The slopes are tight as well as conservative: unpadded, they point within 1e-5 rad of the
    /// exact (f64) tangents wherever the eye is at least 1.1 r from the centre and the tangent
    /// clearly points forward (depth above 1e-3 of its direction), and they are dropped (±∞)
    /// closer than 1.1 r, as documented. (Containment alone let a wrong term loosen a bound,
    /// and the 1.1 r threshold move.)
    #[test]
    fn tangent_slopes_are_the_exact_tangents_from_1_1_radii_out() {
        use rand::SeedableRng;
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        let (mut checked, mut dropped) = (0, 0);
        for _ in 0..100_000 {
            // Distance from the eye: 0.6–1000 radii, plenty of them close to 1.1 r.
            let (c, dc, r) = random_circle(&mut rng, -0.2..3.0);
            let (lo, hi) = tangent_slopes(c, dc, r);
            let (c64, dc64, r64) = (c as f64, dc as f64, r as f64);
            let l64 = (c64 * c64 + dc64 * dc64).sqrt();
            let context = format!("c {c}, dc {dc}, r {r}: [{lo}, {hi}]");
            if l64 < 1.1 * r64 * (1.0 - 1e-6) {
                assert_eq!((lo, hi), (f32::NEG_INFINITY, f32::INFINITY), "{context}");
                dropped += 1;
                continue;
            }
            if l64 < 1.1 * r64 * (1.0 + 1e-6) {
                continue;
            }
            let [(num_max, den_max), (num_min, den_min)] = exact_tangents(c64, dc64, r64);
            for (got, num, den, unbounded) in [
                (hi, num_max, den_max, f32::INFINITY),
                (lo, num_min, den_min, f32::NEG_INFINITY),
            ] {
                let depth = den / (l64 * l64);
                if depth > 1e-3 {
                    let error = ((got as f64).atan() - (num / den).atan()).abs();
                    assert!(error <= 1e-5, "{error} rad off the tangent: {context}");
                    checked += 1;
                } else if depth < -1e-3 {
                    assert_eq!(got, unbounded, "backward tangent: {context}");
                }
            }
        }
        assert!(
            checked > 80_000 && dropped > 5000,
            "{checked} checked, {dropped} dropped"
        );
    }

    /// `refine_slice` keeps exactly the clusters of its definition, tested cluster by cluster:
    /// `dy ≤ R_k` and `dx² ≤ (R_k − dy)(R_k + dy)`, with `dx`, `dy` the column's and row's gaps
    /// over the slab. Walking the cut runs (and the whole-slice shortcut) must neither keep more
    /// nor fewer clusters than that.
    #[test]
    fn refine_slice_keeps_exactly_the_clusters_of_its_definition() {
        use rand::SeedableRng;
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let (kept, cut, whole_slices) = refine_matches_definition(1.0, 3000, &mut rng);
        // The draw must exercise both the cuts and the whole-slice shortcut.
        assert!(
            cut > 1000 && kept > cut && whole_slices > 100,
            "kept {kept}, cut {cut}, slices kept whole {whole_slices}"
        );
    }

    /// Draws `draws` lights in a 70° 1536×768 view with a 24×12×16 log grid, every length (near,
    /// far, depths, radii) times `scale`, and checks every slice of each light's box:
    /// `refine_slice` keeps exactly [`kept_by_definition`]'s clusters. Returns the clusters kept,
    /// the clusters cut and the slices kept whole.
    fn refine_matches_definition(
        scale: f32,
        draws: usize,
        rng: &mut rand_pcg::Pcg64,
    ) -> (usize, usize, usize) {
        use crate::search::FramePlanes;
        use glam::{UVec3, Vec3};
        use myriad_cluster_math::{ClusterGrid, DepthSlicing, PlaneSets};
        use rand::Rng;
        let (near, far) = (0.1 * scale, 60.0 * scale);
        let cam = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 70.0, 1536, 768, near, far);
        let grid = ClusterGrid::new(UVec3::new(24, 12, 16), DepthSlicing::Log, near, far);
        let sets = PlaneSets::new(&cam, &grid);
        let planes = FramePlanes::new(&sets, &grid);
        let mut gaps = vec![0.0; refine_scratch_len(grid.dims())];
        let (mut kept, mut cut, mut whole_slices) = (0usize, 0usize, 0usize);
        for _ in 0..draws {
            let dc = rng.random_range(0.5..50.0f32) * scale;
            let (cx, cy) = (rng.random_range(-dc..dc), rng.random_range(-dc..dc) * 0.5);
            let r = 10f32.powf(rng.random_range(-1.0..1.0)) * scale;
            let Some(b) = cluster_box(cx, cy, dc, r, &planes) else {
                continue;
            };
            for k in b.z.k0..=b.z.k1 {
                let got = refined_clusters(cx, cy, dc, r, &b, k, &planes, &mut gaps);
                let want = kept_by_definition(cx, cy, dc, r, &b, k, &sets);
                assert_eq!(
                    got, want,
                    "scale {scale}: light ({cx}, {cy}, {dc}, r {r}), slice {k}, box {b:?}"
                );
                let area = ((b.i1 - b.i0 + 1) * (b.j1 - b.j0 + 1)) as usize;
                kept += got.len();
                cut += area - got.len();
                whole_slices += (got.len() == area) as usize;
            }
        }
        (kept, cut, whole_slices)
    }

    /// The clusters `(j, i)` of slice `k` of box `b` that `refine_slice` keeps, row by row: the
    /// rows it calls back with, or every row of the box when it keeps the slice whole.
    #[allow(clippy::too_many_arguments)] // The same light, box and slice as `refine_slice` takes.
    fn refined_clusters(
        cx: f32,
        cy: f32,
        dc: f32,
        r: f32,
        b: &ClusterBox,
        k: u32,
        planes: &FramePlanes<'_>,
        gaps: &mut [f32],
    ) -> Vec<(u32, u32)> {
        let mut got = Vec::new();
        let whole = refine_slice(cx, cy, dc, r, b, k, planes, gaps, |j, i0, i1| {
            got.extend((i0..=i1).map(|i| (j, i)))
        });
        if whole {
            assert!(got.is_empty(), "a slice kept whole also called `row`");
            got.extend((b.j0..=b.j1).flat_map(|j| (b.i0..=b.i1).map(move |i| (j, i))));
        }
        got
    }

    /// The clusters `(j, i)` of slice `k` of box `b` that `refine_slice`'s definition keeps:
    /// `dy ≤ R_k` and `dx² ≤ (R_k − dy)(R_k + dy)`, tested cluster by cluster.
    #[allow(clippy::too_many_arguments)] // The same light, box and slice as `refine_slice` takes.
    fn kept_by_definition(
        cx: f32,
        cy: f32,
        dc: f32,
        r: f32,
        b: &ClusterBox,
        k: u32,
        sets: &myriad_cluster_math::PlaneSets,
    ) -> Vec<(u32, u32)> {
        let ka = sets.z_depths[k as usize].max(b.z.da);
        let kb = sets.z_depths[k as usize + 1].min(b.z.db);
        let mut want = Vec::new();
        if ka <= kb {
            let rk = band_radius(dc, r, ka, kb);
            for j in b.j0..=b.j1 {
                let (top, bottom) = (sets.y_slopes[j as usize], sets.y_slopes[j as usize + 1]);
                let dy = ((bottom * ka).min(bottom * kb) - cy)
                    .max(cy - (top * ka).max(top * kb))
                    .max(0.0);
                for i in b.i0..=b.i1 {
                    let (s0, s1) = (sets.x_slopes[i as usize], sets.x_slopes[i as usize + 1]);
                    let dx = (cx - (s1 * ka).max(s1 * kb))
                        .max((s0 * ka).min(s0 * kb) - cx)
                        .max(0.0);
                    if dy <= rk && dx * dx <= (rk - dy) * (rk + dy) {
                        want.push((j, i));
                    }
                }
            }
        }
        want
    }

    /// A 25 × 11 × 16 grid (odd, so the middle row and column contain the view axis strictly)
    /// and its plane sets.
    fn odd_grid() -> (
        myriad_cluster_math::ClusterGrid,
        myriad_cluster_math::PlaneSets,
    ) {
        use glam::{UVec3, Vec3};
        use myriad_cluster_math::{ClusterGrid, DepthSlicing, PlaneSets};
        let cam = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 70.0, 1536, 768, 0.1, 60.0);
        let grid = ClusterGrid::new(UVec3::new(25, 11, 16), DepthSlicing::Log, 0.1, 60.0);
        let sets = PlaneSets::new(&cam, &grid);
        (grid, sets)
    }

    /// The whole grid's columns and rows over the depth band `[dc − r, dc + r]`.
    fn whole_box(grid: &myriad_cluster_math::ClusterGrid, dc: f32, r: f32) -> ClusterBox {
        let d = grid.dims();
        ClusterBox {
            z: ZRange {
                da: dc - r,
                db: dc + r,
                k0: 0,
                k1: d.z - 1,
            },
            i0: 0,
            i1: d.x - 1,
            j0: 0,
            j1: d.y - 1,
        }
    }

    /// Ties are kept: a column exactly `R_k` from the centre (`dx² = R_k²` on the row through
    /// the centre, where `dy = 0`) satisfies `dx² ≤ R_k² − dy²` and must not be cut, from the
    /// left or the right, while the columns beyond it are. (Cutting on `≥` instead of `>` passed
    /// every random draw.)
    #[test]
    fn refine_slice_keeps_a_column_exactly_r_k_away() {
        let (grid, sets) = odd_grid();
        let planes = FramePlanes::new(&sets, &grid);
        let mut gaps = vec![0.0; refine_scratch_len(grid.dims())];
        let (mid_row, columns) = (grid.dims().y / 2, grid.dims().x);
        let mut ties = 0;
        for k in [4u32, 9, 13] {
            let (z0, z1) = (sets.z_depths[k as usize], sets.z_depths[k as usize + 1]);
            // The sphere lies inside the slice: its slab is its own band and `R_k = r`, a power of
            // two, so most edges plus `r` are exact.
            let (dc, r) = (
                0.5 * (z0 + z1),
                2f32.powi((0.125 * (z1 - z0)).log2().floor() as i32),
            );
            let b = whole_box(&grid, dc, r);
            let (ka, kb) = (z0.max(b.z.da), z1.min(b.z.db));
            assert_eq!(band_radius(dc, r, ka, kb), r);
            for c in 1..columns - 1 {
                for left in [true, false] {
                    // The centre `r` right of column `c`'s right edge, or `r` left of its left
                    // edge, nudged by ulps until the f32 gap is exactly `r`.
                    let (s0, s1) = (sets.x_slopes[c as usize], sets.x_slopes[c as usize + 1]);
                    let edge = if left {
                        (s1 * ka).max(s1 * kb)
                    } else {
                        (s0 * ka).min(s0 * kb)
                    };
                    let gap = |cx: f32| if left { cx - edge } else { edge - cx };
                    let guess = if left { edge + r } else { edge - r };
                    let Some(cx) = (0..8)
                        .flat_map(|n| {
                            let (mut up, mut down) = (guess, guess);
                            for _ in 0..n {
                                (up, down) = (up.next_up(), down.next_down());
                            }
                            [up, down]
                        })
                        .find(|&cx| gap(cx) == r)
                    else {
                        continue;
                    };
                    let got = refined_clusters(cx, 0.0, dc, r, &b, k, &planes, &mut gaps);
                    let context = format!("slice {k}, column {c}, left {left}, cx {cx}");
                    assert_eq!(
                        got,
                        kept_by_definition(cx, 0.0, dc, r, &b, k, &sets),
                        "{context}"
                    );
                    let mid: Vec<u32> = got
                        .iter()
                        .filter(|&&(j, _)| j == mid_row)
                        .map(|&(_, i)| i)
                        .collect();
                    let end = if left { mid.first() } else { mid.last() };
                    assert_eq!(end, Some(&c), "{context}: the row through the centre");
                    ties += 1;
                }
            }
        }
        assert!(ties > 120, "only {ties} exact ties found");
    }

    /// A slab the sphere only touches (its far point exactly on the slice's near edge, so
    /// `ka = kb` and `R_k = 0`) keeps the cluster the touching point lies in: `dy = R_k = 0`
    /// satisfies `dy ≤ R_k`.
    #[test]
    fn refine_slice_keeps_the_point_where_a_sphere_touches_a_slice() {
        let (grid, sets) = odd_grid();
        let planes = FramePlanes::new(&sets, &grid);
        let mut gaps = vec![0.0; refine_scratch_len(grid.dims())];
        let d = grid.dims();
        for k in 1..d.z {
            let z = sets.z_depths[k as usize];
            // Powers of two below the slice's depth: `dc + r` and `z − dc` are exact.
            let r = 2f32.powi((z * 0.25).log2().floor() as i32);
            let dc = z - r;
            assert!(dc + r == z && z - dc == r, "slice {k}");
            let b = whole_box(&grid, dc, r);
            let got = refined_clusters(0.0, 0.0, dc, r, &b, k, &planes, &mut gaps);
            assert_eq!(
                got,
                vec![(d.y / 2, d.x / 2)],
                "slice {k}: the touching point's cluster"
            );
            assert_eq!(got, kept_by_definition(0.0, 0.0, dc, r, &b, k, &sets));
        }
    }

    /// The definition holds at every scale of the scene (near plane, depths and radii from 1e-3
    /// to 1e3 of the first test's): slopes times depths are not confused with sums anywhere,
    /// whole-slice shortcut included (the slabs nearer than depth 1 are where they differ).
    #[test]
    fn refine_slice_keeps_the_clusters_of_its_definition_at_every_scale() {
        use rand::SeedableRng;
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let mut cut = 0usize;
        for scale in [1e-3f32, 1e-2, 0.1, 10.0, 1e3] {
            cut += refine_matches_definition(scale, 400, &mut rng).1;
        }
        assert!(cut > 1000, "only {cut} clusters cut");
    }

    /// The f64 cull of overflowing lights tests all six planes: a sphere past any one of them by a
    /// millionth of its radius or more is rejected, one reaching into it is kept, and so is one
    /// that only touches a plane (within 1e-9 of the extent past it: the documented tangency
    /// padding).
    #[test]
    fn may_touch_frustum_f64_tests_every_plane_and_keeps_tangency() {
        use glam::Vec3;
        // View space is world space: the eye at the origin looking down −z with +y up. The
        // slopes (about 1.75 across, 0.7 up) differ, and neither is 0, 1 or 2, so each side
        // plane's normal has its own length.
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 70.0, 250, 100, 1.0, 50.0);
        let (tx, ty) = camera.tan_half_fov_f64();
        let (sx, sy) = ((1.0 + tx * tx).sqrt(), (1.0 + ty * ty).sqrt());
        let z_depths = [1.0f32, 5.0, 50.0];
        let (r, d) = (0.5f64, 10.0f64);
        // The centre of a sphere of radius `r` whose signed distance past each plane is `s·r`.
        let past = |s: f64| {
            [
                ("right", DVec3::new(tx * d + s * r * sx, 0.0, -d)),
                ("left", DVec3::new(-tx * d - s * r * sx, 0.0, -d)),
                ("top", DVec3::new(0.0, ty * d + s * r * sy, -d)),
                ("bottom", DVec3::new(0.0, -ty * d - s * r * sy, -d)),
                ("near", DVec3::new(0.0, 0.0, -(1.0 - s * r))),
                ("far", DVec3::new(0.0, 0.0, -(50.0 + s * r))),
            ]
        };
        for (s, want) in [
            (1.1, false),
            (1.0 + 1e-6, false),
            (1.0 + 1e-9, true),
            (1.0 - 1e-6, true),
            (0.9, true),
        ] {
            for (plane, centre) in past(s) {
                assert_eq!(
                    may_touch_frustum_f64(&camera, &z_depths, centre, r),
                    want,
                    "{plane} plane, centre {centre} ({s} radii past it)"
                );
            }
        }
        // Well inside, and far outside everything.
        assert!(may_touch_frustum_f64(
            &camera,
            &z_depths,
            DVec3::new(1.0, -1.0, -20.0),
            r
        ));
        assert!(!may_touch_frustum_f64(
            &camera,
            &z_depths,
            DVec3::new(0.0, 0.0, 20.0),
            r
        ));
    }

    /// The spot cone's sphere test is conservative and tight to its padding on each of its three
    /// sides: behind the apex, past the range and outside the angle. A sphere reaching a tenth of
    /// its radius across a side is kept, one a millionth of its radius past it too (inside the
    /// [`PAD`] slack, here about 1e-4), and one past it by a thousandth of its radius (5e-4) or
    /// more is rejected.
    #[test]
    fn cone_may_touch_sphere_is_tight_on_every_side() {
        use glam::Vec3;
        let apex = Vec3::new(1.0, 2.0, -3.0);
        let axis = Vec3::new(0.6, 0.0, -0.8);
        // A unit vector across the axis.
        let side = Vec3::new(0.8, 0.0, 0.6);
        let angle = 0.5f32;
        let (sin, cos) = angle.sin_cos();
        let (range, r) = (10.0f32, 0.5f32);
        // The centre of a sphere whose distance past each side is `s·r` (within the angle for the
        // first two, on the axis for the angle's side).
        let past = |s: f32| {
            let along = 4.0;
            // Past the slanted side at `along`: `across·cos − along·sin = s·r`.
            let across = (s * r + along * sin) / cos;
            [
                ("behind the apex", apex - axis * (s * r)),
                ("past the range", apex + axis * (range + s * r)),
                ("outside the angle", apex + axis * along + side * across),
            ]
        };
        for (s, want) in [
            (1.01, false),
            (1.001, false),
            (1.0 + 1e-6, true),
            (0.9, true),
            (0.0, true),
        ] {
            for (what, centre) in past(s) {
                assert_eq!(
                    cone_may_touch_sphere(apex, axis, (cos, sin), range, centre, r),
                    want,
                    "{what}: centre {centre} ({s} radii past it)"
                );
            }
        }
        // Every magnitude widens the slack, the radius and the range included: with them
        // dominating, a sphere past the apex (past the range) by 0.75 of `PAD` × the magnitudes
        // in play is kept, and one past it by 1.25 of that is rejected.
        for (what, range, r, side) in [
            ("a huge sphere behind the apex", 1.0f32, 1.0e3f32, -1.0f32),
            ("a sphere past a long range", 1.0e3, 1.0, 1.0),
            ("a huge sphere past a long range", 1.0e3, 1.0e3, 1.0),
        ] {
            let reach = if side < 0.0 { r } else { range + r };
            let magnitudes = reach + range + r;
            for (k, want) in [(0.75, true), (1.25, false)] {
                let centre = Vec3::X * side * (reach + k * PAD * magnitudes);
                assert_eq!(
                    cone_may_touch_sphere(Vec3::ZERO, Vec3::X, (cos, sin), range, centre, r),
                    want,
                    "{what}: centre {centre}, {k} of the slack past it"
                );
            }
        }
    }

    #[test]
    fn band_radius_is_the_widest_cross_section() {
        assert_eq!(band_radius(5.0, 2.0, 4.0, 6.0), 2.0);
        let r = band_radius(5.0, 2.0, 6.0, 7.0);
        assert!((r - 3.0f32.sqrt()).abs() < 1e-6);
        assert_eq!(band_radius(5.0, 2.0, 7.0, 8.0), 0.0);
    }

    /// A band nearer than the centre (the slices in front of a sphere's middle) is bounded by
    /// the cross-section at its far edge, as a band beyond the centre is by the one at its near
    /// edge: the same distance from the centre gives the same radius on either side, and one
    /// distance that differs from the centre's depth and the band's edge in every operation
    /// (`dc − db`, not `dc + db` or `dc / db`) gives its own exact value.
    #[test]
    fn band_radius_of_a_band_in_front_of_the_centre() {
        assert_eq!(band_radius(5.0, 2.0, 3.0, 4.0), 3.0f32.sqrt());
        assert_eq!(
            band_radius(5.0, 2.0, 3.0, 4.0),
            band_radius(5.0, 2.0, 6.0, 7.0)
        );
        // Distance 1.5 of radius 2.5: (2.5 − 1.5)(2.5 + 1.5) = 4.
        assert_eq!(band_radius(6.0, 2.5, 1.0, 4.5), 2.0);
        assert_eq!(band_radius(6.0, 2.5, 2.0, 6.0), 2.5);
        assert_eq!(band_radius(6.0, 2.5, 9.0, 10.0), 0.0);
    }

    /// A centre on the band's edge is inside the band: the radius comes back exactly, even for a
    /// radius whose square underflows f32 (`sqrt(r·r)` would give 0 for this one).
    #[test]
    fn band_radius_of_a_centre_on_the_band_edge_is_the_radius() {
        let r = 1e-30f32;
        assert_eq!((r * r).sqrt(), 0.0);
        assert_eq!(band_radius(1.0, r, 1.0, 2.0), r);
        assert_eq!(band_radius(2.0, r, 1.0, 2.0), r);
    }

    /// A spot's view-space axis is its world axis turned into view space and made unit, whatever
    /// its length (one 1e-20 long, whose f32 square is subnormal, included); a zero axis gives
    /// zero, which callers treat as a point light.
    #[test]
    fn spot_view_axis_turns_and_normalises_the_axis() {
        use glam::{Mat3, Vec3};
        // World x, y, z to view y, z, x.
        let turn = Mat3::from_cols(Vec3::Y, Vec3::Z, Vec3::X);
        assert_eq!(spot_view_axis(Mat3::IDENTITY, 0.0, 0.0, -2.0), Vec3::NEG_Z);
        assert_eq!(spot_view_axis(turn, 1e-20, 0.0, 0.0), Vec3::Y);
        assert_eq!(spot_view_axis(turn, 0.0, 0.0, 5e3), Vec3::X);
        assert_eq!(spot_view_axis(turn, 0.0, -7.0, 0.0), Vec3::NEG_Z);
        assert_eq!(spot_view_axis(turn, 0.0, 0.0, 0.0), Vec3::ZERO);
    }

    /// The box's slope range takes each side at the depth where its slope is extreme: a side
    /// left of the eye at the near depth, right of it at the far depth, and the reverse for the
    /// right side — exactly, with values that tell near from far and left from right.
    #[test]
    fn box_slopes_take_each_side_at_its_extreme_depth() {
        // Straddling the view axis: both sides at the near depth.
        assert_eq!(box_slopes(-2.0, 3.0, 1.0, 4.0), (-2.0, 3.0));
        // Wholly right of it: the left side at the far depth.
        assert_eq!(box_slopes(1.0, 2.0, 1.0, 4.0), (0.25, 2.0));
        // Wholly left of it: the right side at the far depth.
        assert_eq!(box_slopes(-3.0, -1.0, 2.0, 4.0), (-1.5, -0.25));
        // A side on the axis has slope 0 at any depth.
        assert_eq!(box_slopes(0.0, 0.0, 2.0, 4.0), (0.0, 0.0));
    }
}
