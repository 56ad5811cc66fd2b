//! The `cone` method: spherical-sliced cone tests (seed 004, "Improve Tile-based Light Culling
//! with Spherical-sliced Cone"), adapted to clusters bounded by planar depth slices.
//!
//! Why it exists: it is the other published way to be tighter than a light's box, next to
//! `refined`'s per-slice disc, and the time-against-error table compares them. It starts from
//! `binary`'s box and decides per *tile* (column `i`, row `j`) of it:
//!
//! 1. **Cone test.** The tile's frustum lies inside a circular cone from the eye ([`TileCone`]:
//!    axis = the normalised sum of its four edge directions, half-angle α = the widest angle from
//!    the axis to them; a cone is convex, so holding the four edges it holds the frustum). The
//!    light's ball lies inside the cone of half-angle β = asin(r / L) around the direction to its
//!    centre (L = the centre's distance from the eye). The two meet only if the angle γ between
//!    the axes is at most α + β.
//! 2. **Spherical slicing.** Every direction of the tile cone is at least δ = max(γ − α, 0) from
//!    the centre's direction, and along a direction φ from it the ball spans distances
//!    `L·cos φ ± sqrt(r² − L²·sin² φ)` — the far end falls and the near end rises as φ grows
//!    (while the eye is outside the ball), so the ball's part inside the tile lies at distances
//!    `[L·cos δ − s, L·cos δ + s]`, `s = sqrt(r² − L²·sin² δ)`. An eye inside the ball gives
//!    `[0, L + r]` and keeps every tile.
//! 3. **To planar slices.** A point of the tile at distance t has depth `t·q`, with
//!    `q = depth / distance = 1 / sqrt(1 + sx² + sy²)` over the tile's slopes: smallest at its
//!    outermost corner, largest at its slope nearest 0. So the ball's part inside the tile lies at
//!    depths `[t_lo·q_min, t_hi·q_max]`; the slices that range reaches (within the box's depth
//!    band) are kept for that tile.
//!
//! The seed compares cosines; near an angle of 0 a cosine resolves angles only to √ε
//! (3·10⁻⁴ rad in f32), wider than the tiles of a narrow view. Here every angle is carried as its
//! sine *and* cosine, in f64: `sin γ = |u × t|` and `cos γ = u · t` are both accurate at every
//! angle, δ = γ − α comes from the difference formulas, and δ ≤ β is decided on `sin δ ≤ sin β`
//! (both in [0, π/2], where the sine is monotone) — no inverse trigonometry and no cancellation
//! of `1 − cos`. The tile edges are the f64 oracle's ([`Cell::of_tile`]). The light's centre and
//! radius arrive padded ([`crate::geometry::pad_radius`]: 4·10⁻⁶ of its extent), which covers the
//! f32 view transform; the f64 steps here add margins far above their own rounding
//! ([`ANGLE_MARGIN`], [`DEPTH_MARGIN`]). (A first version computed the angles with `atan2`,
//! `asin` and `sin_cos`: identical lists on `paper` 1000, several times slower.)

use glam::{DVec3, UVec3};
use myriad_cluster_math::oracle::Cell;

/// Radians added to every tile cone's half-angle: f64 rounding of the angles is ~10⁻¹⁶ rad.
pub(crate) const ANGLE_MARGIN: f64 = 1e-9;
/// Relative widening of each tile's depth range: its f64 steps round by ~10⁻¹⁵.
pub(crate) const DEPTH_MARGIN: f64 = 1e-9;
/// Tiles up to which a frame's tile cones are computed once and kept (48 bytes each, 12 MiB at
/// most); a grid with more tiles computes each cone where it is needed.
pub(crate) const MAX_CACHED_TILES: usize = 1 << 18;

/// The cone from the eye around one tile's frustum, and its range of `depth / distance`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TileCone {
    /// Unit axis (view space, the eye at the origin).
    pub axis: DVec3,
    /// Cosine and sine of the half-angle α, [`ANGLE_MARGIN`] included.
    pub cos_half: f64,
    pub sin_half: f64,
    /// Smallest `depth / distance` of the tile's directions (its outermost corner), rounded down.
    pub q_min: f64,
    /// Largest `depth / distance` of the tile's directions, rounded up.
    pub q_max: f64,
}

/// The angle between two non-zero vectors, accurate at every angle.
#[inline]
fn angle_between(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

impl TileCone {
    /// The cone of tile `(i, j)` of grid `dims` under `tan_half_fov` (from
    /// [`myriad_cluster_math::Camera::tan_half_fov_f64`]).
    pub fn of_tile(tan_half_fov: (f64, f64), dims: UVec3, i: u32, j: u32) -> Self {
        let cell = Cell::of_tile(tan_half_fov, dims.x, dims.y, i, j, [1.0, 1.0]);
        let [x0, x1] = cell.x_slopes;
        let [y0, y1] = cell.y_slopes;
        let edges = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)].map(|(x, y)| DVec3::new(x, y, -1.0));
        let axis = edges
            .iter()
            .fold(DVec3::ZERO, |sum, e| sum + e.normalize())
            .normalize();
        let half_angle = edges
            .iter()
            .map(|&e| angle_between(axis, e))
            .fold(0.0, f64::max)
            + ANGLE_MARGIN;
        let (sin_half, cos_half) = half_angle.sin_cos();
        let q = |x: f64, y: f64| 1.0 / (1.0 + x * x + y * y).sqrt();
        let q_min = q(x0.abs().max(x1.abs()), y0.abs().max(y1.abs()));
        let q_max = q(0f64.clamp(x0, x1), 0f64.clamp(y0, y1));
        Self {
            axis,
            cos_half,
            sin_half,
            q_min: q_min * (1.0 - DEPTH_MARGIN),
            q_max: q_max * (1.0 + DEPTH_MARGIN),
        }
    }
}

/// Every tile cone of a grid, row by row (`j · X + i`).
pub(crate) fn tile_cones(tan_half_fov: (f64, f64), dims: UVec3, out: &mut Vec<TileCone>) {
    out.clear();
    for j in 0..dims.y {
        for i in 0..dims.x {
            out.push(TileCone::of_tile(tan_half_fov, dims, i, j));
        }
    }
}

/// A light's ball seen from the eye: what the per-tile tests need of it, computed once.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightCone {
    /// Distance of the centre from the eye.
    distance: f64,
    radius: f64,
    /// Unit direction to the centre (zero when the eye is inside the ball).
    direction: DVec3,
    /// Sine of the half-angle β of the ball's cone, `r / L` (unused when the eye is inside).
    sin_half: f64,
    /// Whether the eye is inside (or on) the ball: then every tile is met.
    eye_inside: bool,
}

impl LightCone {
    /// The padded view-space sphere with centre `(cx, cy)` at depth `dc` and radius `r`.
    pub fn new(cx: f32, cy: f32, dc: f32, r: f32) -> Self {
        let centre = DVec3::new(cx.into(), cy.into(), -f64::from(dc));
        let distance = centre.length();
        let radius = f64::from(r);
        let eye_inside = !(distance > radius);
        Self {
            distance,
            radius,
            direction: if eye_inside {
                DVec3::ZERO
            } else {
                centre / distance
            },
            sin_half: if eye_inside { 1.0 } else { radius / distance },
            eye_inside,
        }
    }

    /// The view depths `[lo, hi]` the ball reaches inside `tile`'s cone, or `None` when it
    /// misses the cone.
    #[cfg(test)]
    pub fn depth_range(&self, tile: &TileCone) -> Option<(f64, f64)> {
        let (lo, hi) = self.depth_bounds(tile);
        (lo <= hi).then_some((lo, hi))
    }

    /// The depth range (as `depth_range`, the tests' form) without a branch on the outcome:
    /// `(lo, hi)` with `lo ≤ hi`, or `(∞, −∞)` when the ball misses the cone. A row's tiles are
    /// computed in one go, so their square roots overlap instead of each waiting behind the
    /// previous tile's slice walks.
    #[inline(always)]
    pub fn depth_bounds(&self, tile: &TileCone) -> (f64, f64) {
        let (near, far) = if self.eye_inside {
            (0.0, self.distance + self.radius)
        } else {
            // γ: the angle between the axes; δ = γ − α, by the difference formulas.
            let cos_gamma = self.direction.dot(tile.axis);
            let sin_gamma = self.direction.cross(tile.axis).length();
            let sin_delta = sin_gamma * tile.cos_half - cos_gamma * tile.sin_half;
            let cos_delta = cos_gamma * tile.cos_half + sin_gamma * tile.sin_half;
            // δ ≤ 0: the centre's direction is inside the tile cone, the nearest direction is
            // itself. Otherwise the cones meet when δ ≤ β < π/2: a negative cosine is past π/2,
            // and below it the sine orders the angles.
            let inside = sin_delta <= 0.0;
            let missed = !inside && (cos_delta < 0.0 || sin_delta > self.sin_half);
            let (sin, cos) = if inside {
                (0.0, 1.0)
            } else {
                (sin_delta, cos_delta)
            };
            let base = self.distance * cos;
            let across = self.distance * sin;
            let half_chord = ((self.radius - across).max(0.0) * (self.radius + across)).sqrt();
            if missed {
                return (f64::INFINITY, f64::NEG_INFINITY);
            }
            ((base - half_chord).max(0.0), base + half_chord)
        };
        (
            near * tile.q_min * (1.0 - DEPTH_MARGIN),
            far * tile.q_max * (1.0 + DEPTH_MARGIN),
        )
    }
}

/// One tile column of the row being cut: its depth range, then the slices it keeps.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ConeColumn {
    /// [`LightCone::depth_bounds`] for the column's tile.
    pub lo: f64,
    pub hi: f64,
    /// The box's slices `[first, last]` the range reaches (`first > last`: none).
    pub first: u32,
    pub last: u32,
}

#[cfg(test)]
mod tests {
    use super::*;
    use myriad_cluster_math::oracle::sphere_intersects_cell;

    /// Calls `check(cone, cell)` for every tile of three grids — an ordinary view, a 10⁻³-rad
    /// narrow one, and one about 179° wide (half-field tangents 114.6 × 11.46) — each tile's
    /// cell at depth 1.
    fn each_tile(mut check: impl FnMut(&TileCone, &Cell)) {
        for (fov, dims) in [
            ((0.6f64, 0.35f64), UVec3::new(24, 12, 16)),
            ((1e-3, 1e-3), UVec3::new(128, 128, 1)),
            ((114.6, 11.46), UVec3::new(7, 5, 1)),
        ] {
            for j in 0..dims.y {
                for i in 0..dims.x {
                    let tile = TileCone::of_tile(fov, dims, i, j);
                    check(&tile, &Cell::of_tile(fov, dims.x, dims.y, i, j, [1.0, 1.0]));
                }
            }
        }
    }

    /// The tile cone holds its frustum: sampled directions across each tile, corners and edges
    /// included, lie within its half-angle, and their depth/distance within `[q_min, q_max]`.
    #[test]
    fn tile_cones_hold_their_tiles() {
        each_tile(|tile, cell| {
            for a in 0..=8 {
                for b in 0..=8 {
                    let t = |lo: f64, hi: f64, s: u32| lo + (hi - lo) * s as f64 / 8.0;
                    let x = t(cell.x_slopes[0], cell.x_slopes[1], a);
                    let y = t(cell.y_slopes[0], cell.y_slopes[1], b);
                    let d = DVec3::new(x, y, -1.0);
                    let half = tile.sin_half.atan2(tile.cos_half);
                    assert!(angle_between(tile.axis, d) <= half);
                    let q = 1.0 / d.length();
                    assert!(tile.q_min <= q && q <= tile.q_max, "{q} {tile:?}");
                }
            }
        });
    }

    /// The tile cone is tight as well: its half-angle is the widest angle from its axis to the
    /// tile's four edges plus [`ANGLE_MARGIN`] (measured here, not with `angle_between`), and its
    /// axis lies inside the tile. (Holding the tile alone let every half-angle grow to 1 rad.)
    #[test]
    fn tile_cones_are_tight_around_their_tiles() {
        each_tile(|tile, cell| {
            let [x0, x1] = cell.x_slopes;
            let [y0, y1] = cell.y_slopes;
            let widest = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]
                .map(|(x, y)| {
                    let e = DVec3::new(x, y, -1.0);
                    tile.axis.cross(e).length().atan2(tile.axis.dot(e))
                })
                .into_iter()
                .fold(0.0, f64::max);
            let half = tile.sin_half.atan2(tile.cos_half);
            assert!(
                (half - widest - ANGLE_MARGIN).abs() <= 1e-12,
                "{cell:?}: half-angle {half}, widest edge {widest}"
            );
            let (sx, sy) = (-tile.axis.x / tile.axis.z, -tile.axis.y / tile.axis.z);
            assert!(
                x0 < sx && sx < x1 && y0 < sy && sy < y1,
                "{cell:?}: axis {}",
                tile.axis
            );
        });
    }

    /// A ball that meets a cell of the tile has that cell's depths inside the ball's depth range
    /// for the tile (the range is what keeps slices), and a ball far off the tile misses it.
    #[test]
    fn depth_ranges_cover_every_cell_the_ball_meets() {
        let fov = (0.7f64, 0.4f64);
        let dims = UVec3::new(8, 6, 1);
        let mut met = 0;
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..40_000 {
            let c = DVec3::new(
                next() * 12.0 - 6.0,
                next() * 8.0 - 4.0,
                -(next() * 14.0 - 2.0),
            );
            let r = next() * next() * 4.0 + 1e-3;
            let light = LightCone::new(c.x as f32, c.y as f32, (-c.z) as f32, r as f32);
            let (c, r) = (
                DVec3::new(c.x as f32 as f64, c.y as f32 as f64, c.z as f32 as f64),
                r as f32 as f64,
            );
            // Mostly the tile the centre projects into or a neighbour, so contacts are common.
            let depth = (-c.z).max(1e-3);
            let mut near_tile = |slope: f64, tan: f64, n: u32, top_down: bool| {
                let ndc = (slope / depth / tan).clamp(-1.0, 1.0);
                let ndc = if top_down { -ndc } else { ndc };
                let t = ((ndc + 1.0) / 2.0 * n as f64) as i64 + (next() * 3.0) as i64 - 1;
                t.clamp(0, n as i64 - 1) as u32
            };
            let (i, j) = (
                near_tile(c.x, fov.0, 8, false),
                near_tile(c.y, fov.1, 6, true),
            );
            let tile = TileCone::of_tile(fov, dims, i, j);
            // A slab of the tile at a random depth, thin or thick.
            let d0 = next() * 12.0 + 0.05;
            let slab = [d0 as f32, (d0 + next() * next() * 3.0) as f32];
            let cell = Cell::of_tile(fov, dims.x, dims.y, i, j, slab);
            if sphere_intersects_cell(c, r, &cell) {
                met += 1;
                let (lo, hi) = light.depth_range(&tile).expect("the ball meets the tile");
                assert!(
                    lo <= slab[1] as f64 && hi >= slab[0] as f64,
                    "{c} {r} tile ({i}, {j}) slab {slab:?}: range {lo}..{hi}"
                );
            }
        }
        assert!(met > 3000, "only {met} contacts sampled");
        // Off to the side by far more than its radius: no contact.
        let aside = LightCone::new(50.0, 0.0, 10.0, 1.0);
        let centre_tile = TileCone::of_tile(fov, dims, 4, 3);
        assert_eq!(aside.depth_range(&centre_tile), None);
        // The eye inside: every tile, from depth 0 to past the ball.
        let around = LightCone::new(0.1, 0.0, 0.2, 1.0);
        let (lo, hi) = around.depth_range(&centre_tile).unwrap();
        assert_eq!(lo, 0.0);
        assert!(hi >= 1.0);
    }

    /// The depth ranges are the spherical slicing's, not merely wide enough: against the same
    /// steps written with the angles themselves (`atan2`, `asin`, δ = max(γ − α, 0)), each
    /// range agrees to 1e-10 of the light's extent and a miss is a miss. (Covering the oracle's
    /// contacts alone let a range grow: a half chord of `r + across`, a δ too small.)
    #[test]
    fn depth_ranges_are_the_spherical_slicings() {
        let fov = (0.7f64, 0.4f64);
        let dims = UVec3::new(8, 6, 1);
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut met, mut missed) = (0, 0);
        for _ in 0..20_000 {
            let (cx, cy, dc) = (
                (next() * 12.0 - 6.0) as f32,
                (next() * 8.0 - 4.0) as f32,
                (next() * 16.0 - 2.0) as f32,
            );
            let r = (next() * next() * 4.0 + 1e-3) as f32;
            let (i, j) = ((next() * 8.0) as u32, (next() * 6.0) as u32);
            let tile = TileCone::of_tile(fov, dims, i, j);
            let got = LightCone::new(cx, cy, dc, r).depth_range(&tile);
            let centre = DVec3::new(cx.into(), cy.into(), -f64::from(dc));
            let (l, r) = (centre.length(), f64::from(r));
            let scaled = |near: f64, far: f64| {
                (
                    near * tile.q_min * (1.0 - DEPTH_MARGIN),
                    far * tile.q_max * (1.0 + DEPTH_MARGIN),
                )
            };
            let want = if l <= r {
                Some(scaled(0.0, l + r))
            } else {
                let gamma = angle_between(centre, tile.axis);
                let (alpha, beta) = (tile.sin_half.atan2(tile.cos_half), (r / l).asin());
                let delta = (gamma - alpha).max(0.0);
                // Grazing contacts (δ ≈ β) are too sensitive for a comparison at 1e-10.
                if (delta - beta).abs() < 1e-3 {
                    continue;
                }
                (delta <= beta).then(|| {
                    let half_chord = (r * r - (l * delta.sin()).powi(2)).sqrt();
                    let base = l * delta.cos();
                    scaled((base - half_chord).max(0.0), base + half_chord)
                })
            };
            let context = format!("light ({cx}, {cy}, {dc}, r {r}), tile ({i}, {j})");
            match (got, want) {
                (Some((lo, hi)), Some((want_lo, want_hi))) => {
                    let tolerance = 1e-10 * (l + r);
                    assert!(
                        (lo - want_lo).abs() <= tolerance && (hi - want_hi).abs() <= tolerance,
                        "{context}: {lo}..{hi}, want {want_lo}..{want_hi}"
                    );
                    met += 1;
                }
                (None, None) => missed += 1,
                _ => panic!("{context}: {got:?}, want {want:?}"),
            }
        }
        assert!(met > 1500 && missed > 2000, "{met} met, {missed} missed");
    }

    /// Each range is widened by [`DEPTH_MARGIN`] beyond the exact depths (the tile's `q` and the
    /// range each add one), and by no more than a few margins: a light in front of the tile (its centre's direction inside the tile's
    /// cone) reaches from `(L − r)·q` at the tile's outermost corner to `(L + r)·q` at its
    /// slope nearest 0, and an eye inside the ball from 0.
    #[test]
    fn depth_ranges_are_widened_by_their_margin() {
        let fov = (0.7f64, 0.4f64);
        let dims = UVec3::new(8, 6, 1);
        let q = |x: f64, y: f64| 1.0 / (1.0 + x * x + y * y).sqrt();
        let widened = |got: f64, exact: f64, sign: f64| {
            // `got = exact·(1 + sign·m)` with m between one and three margins.
            let m = sign * (got / exact - 1.0);
            (DEPTH_MARGIN..=3.0 * DEPTH_MARGIN).contains(&m)
        };
        for (i, j) in [(0, 0), (3, 2), (4, 3), (7, 5), (2, 4)] {
            let tile = TileCone::of_tile(fov, dims, i, j);
            let cell = Cell::of_tile(fov, dims.x, dims.y, i, j, [1.0, 1.0]);
            let [x0, x1] = cell.x_slopes;
            let [y0, y1] = cell.y_slopes;
            let q_min = q(x0.abs().max(x1.abs()), y0.abs().max(y1.abs()));
            let q_max = q(0f64.clamp(x0, x1), 0f64.clamp(y0, y1));
            for (depth, r) in [(5.0f32, 1.0f32), (20.0, 0.25), (3.0, 2.5), (0.5, 1.5)] {
                // The centre on the middle of the tile's slopes.
                let (sx, sy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
                let (cx, cy) = (
                    (sx * f64::from(depth)) as f32,
                    (sy * f64::from(depth)) as f32,
                );
                let light = LightCone::new(cx, cy, depth, r);
                let l = DVec3::new(cx.into(), cy.into(), depth.into()).length();
                let r = f64::from(r);
                let (lo, hi) = light.depth_range(&tile).unwrap();
                let context = format!("tile ({i}, {j}), light at depth {depth}, r {r}: {lo}..{hi}");
                if l > r {
                    assert!(widened(lo, (l - r) * q_min, -1.0), "near end, {context}");
                } else {
                    assert_eq!(lo, 0.0, "{context}");
                }
                assert!(widened(hi, (l + r) * q_max, 1.0), "far end, {context}");
            }
        }
    }
}
