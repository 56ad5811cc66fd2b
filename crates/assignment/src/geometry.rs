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
//!    conservative bounds — the exact tangent planes from the eye (computed in f64) and the box
//!    `[c ± R] × [da, db]` of the sphere's part inside the band — and then the tiles whose plane
//!    slopes overlap that range, by binary search of the x- and y-plane sets.
//! 3. **refinement** (method `refined`): per slice, the sphere shrunk to the slab is bounded by a
//!    cylinder of radius `R_k`; per row of that slice, the row's y-band cuts the cylinder's
//!    half-width to `w = sqrt(R_k² − dy²)`, and only the x tiles of `[cx ± w]` are kept.

/// Relative padding of light radii: a few hundred f32 ulps of the light's distance and size.
pub(crate) const PAD: f32 = 4.0e-6;

/// The light's radius grown so that f32 rounding can never shrink its footprint below the exact
/// f64 one: `r + PAD·(|c| + r)`.
#[inline]
pub(crate) fn pad_radius(cx: f32, cy: f32, dc: f32, r: f32) -> f32 {
    let extent = cx.abs() + cy.abs() + dc.abs() + r;
    r + PAD * extent
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

/// z phase: `None` when the sphere misses `[near, far]`. `z_depths` are the Z+1 slice edges.
#[inline]
pub(crate) fn z_phase(dc: f32, r: f32, z_depths: &[f32]) -> Option<ZRange> {
    let slices = z_depths.len() as u32 - 1;
    let da = (dc - r).max(z_depths[0]);
    let db = (dc + r).min(z_depths[slices as usize]);
    if !(da <= db) {
        return None;
    }
    // Number of edges at or below a depth, minus one: the slice that starts at or before it.
    let slice_of = |d: f32| (z_depths.partition_point(|&e| e <= d) as u32).clamp(1, slices) - 1;
    Some(ZRange {
        da,
        db,
        k0: slice_of(da),
        k1: slice_of(db),
    })
}

/// Half-width of the sphere's cross-section at the depth in `[da, db]` nearest its centre — the
/// radius of the cylinder that bounds the sphere's part inside the band.
#[inline]
pub(crate) fn band_radius(dc: f32, r: f32, da: f32, db: f32) -> f32 {
    let dist = if dc < da {
        da - dc
    } else if dc > db {
        dc - db
    } else {
        return r;
    };
    ((r - dist).max(0.0) * (r + dist)).sqrt()
}

/// Slope range `[min, max]` of the points `(x, d)` with `x ∈ [lo, hi]`, `d ∈ [da, db]`, `da > 0`.
#[inline]
pub(crate) fn box_slopes(lo: f32, hi: f32, da: f32, db: f32) -> (f32, f32) {
    ((lo / da).min(lo / db), (hi / da).max(hi / db))
}

/// Slope range of the tangent planes from the eye to a circle of radius `r` at `(c, dc)` in the
/// plane spanned by one screen axis and depth; ±∞ where a tangent does not point forward. Computed
/// in f64 (the formula cancels badly in f32 near grazing angles) and rounded outward.
#[inline]
pub(crate) fn tangent_slopes(c: f32, dc: f32, r: f32) -> (f32, f32) {
    let (c, dc, r) = (c as f64, dc as f64, r as f64);
    let l2 = c * c + dc * dc;
    let r2 = r * r;
    if l2 <= r2 * (1.0 + 1e-9) {
        return (f32::NEG_INFINITY, f32::INFINITY);
    }
    let h = (l2 - r2).sqrt();
    let den_max = dc * h - c * r;
    let den_min = dc * h + c * r;
    let max = if den_max > 0.0 {
        ((c * h + dc * r) / den_max) as f32
    } else {
        f32::INFINITY
    };
    let min = if den_min > 0.0 {
        ((c * h - dc * r) / den_min) as f32
    } else {
        f32::NEG_INFINITY
    };
    (min.next_down(), max.next_up())
}

/// Tiles `[first, last]` of an increasing plane-slope set whose slope span overlaps `[min, max]`,
/// by binary search; `None` when no tile does. Tile `t` spans `[slopes[t], slopes[t + 1]]`.
#[inline]
pub(crate) fn tiles_increasing(slopes: &[f32], min: f32, max: f32) -> Option<(u32, u32)> {
    let tiles = slopes.len() - 1;
    // First tile whose right edge reaches min; last tile whose left edge is at or before max.
    let first = slopes[1..].partition_point(|&s| s < min);
    let after_last = slopes[..tiles].partition_point(|&s| s <= max);
    (first < after_last).then(|| (first as u32, after_last as u32 - 1))
}

/// Rows `[first, last]` of a decreasing (top → bottom) plane-slope set whose span overlaps
/// `[min, max]`. Row `j` spans `[slopes[j + 1], slopes[j]]`.
#[inline]
pub(crate) fn tiles_decreasing(slopes: &[f32], min: f32, max: f32) -> Option<(u32, u32)> {
    let rows = slopes.len() - 1;
    // First row whose bottom edge is at or below max; last row whose top edge reaches min.
    let first = slopes[1..].partition_point(|&s| s > max);
    let after_last = slopes[..rows].partition_point(|&s| s >= min);
    (first < after_last).then(|| (first as u32, after_last as u32 - 1))
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

/// The three axis phases for one padded view-space sphere. `None`: outside the frustum.
#[inline]
pub(crate) fn cluster_box(
    cx: f32,
    cy: f32,
    dc: f32,
    r: f32,
    planes: &myriad_cluster_math::PlaneSets,
) -> Option<ClusterBox> {
    let z = z_phase(dc, r, &planes.z_depths)?;
    let big_r = band_radius(dc, r, z.da, z.db);
    let (bx0, bx1) = box_slopes(cx - big_r, cx + big_r, z.da, z.db);
    let (tx0, tx1) = tangent_slopes(cx, dc, r);
    let (i0, i1) = tiles_increasing(&planes.x_slopes, bx0.max(tx0), bx1.min(tx1))?;
    let (by0, by1) = box_slopes(cy - big_r, cy + big_r, z.da, z.db);
    let (ty0, ty1) = tangent_slopes(cy, dc, r);
    let (j0, j1) = tiles_decreasing(&planes.y_slopes, by0.max(ty0), by1.min(ty1))?;
    Some(ClusterBox { z, i0, i1, j0, j1 })
}

/// Refinement of one slice `k` of a light's box: calls `row(j, i0, i1)` for every row of the slice
/// the sphere (shrunk to the slab) can touch, with the tightened x tile span.
#[inline]
pub(crate) fn refine_slice(
    cx: f32,
    cy: f32,
    dc: f32,
    r: f32,
    b: &ClusterBox,
    k: u32,
    planes: &myriad_cluster_math::PlaneSets,
    mut row: impl FnMut(u32, u32, u32),
) {
    let ka = planes.z_depths[k as usize].max(b.z.da);
    let kb = planes.z_depths[k as usize + 1].min(b.z.db);
    if !(ka <= kb) {
        return;
    }
    let rk = band_radius(dc, r, ka, kb);
    let (sy0, sy1) = box_slopes(cy - rk, cy + rk, ka, kb);
    let Some((j0, j1)) = tiles_decreasing(&planes.y_slopes, sy0, sy1) else {
        return;
    };
    let (j0, j1) = (j0.max(b.j0), j1.min(b.j1));
    for j in j0..=j1 {
        let top = planes.y_slopes[j as usize];
        let bottom = planes.y_slopes[j as usize + 1];
        let y_lo = (bottom * ka).min(bottom * kb);
        let y_hi = (top * ka).max(top * kb);
        let dy = (y_lo - cy).max(cy - y_hi).max(0.0);
        if dy > rk {
            continue;
        }
        let w = ((rk - dy) * (rk + dy)).sqrt();
        let (sx0, sx1) = box_slopes(cx - w, cx + w, ka, kb);
        if let Some((i0, i1)) = tiles_increasing(&planes.x_slopes, sx0, sx1) {
            let (i0, i1) = (i0.max(b.i0), i1.min(b.i1));
            if i0 <= i1 {
                row(j, i0, i1);
            }
        }
    }
}

/// Conservative cone-vs-sphere test for spot lights: may a spot (apex, unit axis, cos/sin of the
/// half angle ≤ 90°, range) touch the sphere (centre, radius)? False only when the sphere lies
/// entirely outside the cone's angle, behind its apex, or beyond its range.
#[inline]
pub(crate) fn cone_may_touch_sphere(
    apex: glam::Vec3,
    axis: glam::Vec3,
    cos_sin: (f32, f32),
    range: f32,
    centre: glam::Vec3,
    radius: f32,
) -> bool {
    let v = centre - apex;
    let len2 = v.length_squared();
    let along = v.dot(axis);
    if along < -radius || len2 > (range + radius) * (range + radius) {
        return false;
    }
    // Distance from the centre to the cone's surface when outside it (a lower bound otherwise).
    let across = (len2 - along * along).max(0.0).sqrt();
    let (cos, sin) = cos_sin;
    cos * across - along * sin <= radius
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tile_search_matches_linear_scan() {
        let slopes: Vec<f32> = (0..=10).map(|i| -1.0 + 0.2 * i as f32).collect();
        let down: Vec<f32> = slopes.iter().rev().copied().collect();
        let probes = [-2.0f32, -1.0, -0.95, -0.8, -0.1, 0.0, 0.3, 0.99, 1.0, 1.5];
        for &a in &probes {
            for &b in &probes {
                let expect: Vec<u32> = (0..10u32)
                    .filter(|&t| slopes[t as usize + 1] >= a && slopes[t as usize] <= b)
                    .collect();
                let got = tiles_increasing(&slopes, a, b);
                assert_eq!(got.map(|(f, l)| (f..=l).collect::<Vec<_>>()).unwrap_or_default(), expect);
                let expect_rows: Vec<u32> = (0..10u32)
                    .filter(|&t| down[t as usize] >= a && down[t as usize + 1] <= b)
                    .collect();
                let got = tiles_decreasing(&down, a, b);
                assert_eq!(got.map(|(f, l)| (f..=l).collect::<Vec<_>>()).unwrap_or_default(), expect_rows);
            }
        }
    }

    #[test]
    fn tangent_slopes_bound_the_circle() {
        for &(c, dc, r) in &[(0.0f32, 10.0f32, 1.0f32), (5.0, 10.0, 1.0), (-3.0, 2.0, 1.5), (10.0, -1.0, 5.0)] {
            let (lo, hi) = tangent_slopes(c, dc, r);
            for step in 0..3600 {
                let a = step as f32 / 3600.0 * std::f32::consts::TAU;
                let (x, d) = (c + r * a.cos(), dc + r * a.sin());
                if d > 1e-3 {
                    let s = x / d;
                    assert!(s >= lo - 1e-4 * s.abs() && s <= hi + 1e-4 * s.abs(), "{c},{dc},{r}: {s} not in [{lo},{hi}]");
                }
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
}
