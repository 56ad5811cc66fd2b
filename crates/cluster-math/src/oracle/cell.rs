//! Exact point-to-cell distance in f64.

use crate::{Camera, ClusterGrid};
use glam::DVec3;

/// A cluster cell in view space: points `p` with depth `d = −p.z` in `depths`, `p.x / d` in
/// `x_slopes` and `p.y / d` in `y_slopes` (each `[low, high]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    /// `[left, right]` slopes `x / depth`.
    pub x_slopes: [f64; 2],
    /// `[bottom, top]` slopes `y / depth`.
    pub y_slopes: [f64; 2],
    /// `[near, far]` view depths, `0 < near <= far` (`far` may be ∞: an open last slice under an
    /// infinite projection; the tests against lights cut it to the light's depth first).
    pub depths: [f64; 2],
}

impl Cell {
    /// The cell of cluster `(i, j, k)` of `grid` seen through `camera`. The first slice's cell
    /// starts at [`ClusterGrid::first_slice_start`] and the last slice's ends at
    /// [`ClusterGrid::last_slice_end`]: beyond the grid's range (perhaps at ∞) where the grid is
    /// [`crate::OuterSlices::Open`] and the camera sees nearer or farther.
    ///
    /// # Panics
    /// When `k >= Z` (`i` and `j` off the grid give cells outside the frustum, unchecked).
    pub fn of_cluster(camera: &Camera, grid: &ClusterGrid, i: u32, j: u32, k: u32) -> Self {
        let (mut d0, mut d1) = grid.slice_depth_range(k);
        if k == 0 {
            d0 = grid.first_slice_start(camera);
        }
        if k + 1 == grid.dims().z {
            d1 = grid.last_slice_end(camera);
        }
        Self::of_tile(
            camera.tan_half_fov_f64(),
            grid.dims().x,
            grid.dims().y,
            i,
            j,
            [d0, d1],
        )
    }

    /// The cell of tile `(i, j)` of an `x × y` tiling with `tan_half_fov = (tx, ty)` (from
    /// [`Camera::tan_half_fov_f64`]) between the slice edges `depths` — [`Self::of_cluster`] with
    /// the per-frame values hoisted out, for callers that build many cells.
    pub fn of_tile(
        tan_half_fov: (f64, f64),
        x: u32,
        y: u32,
        i: u32,
        j: u32,
        depths: [f32; 2],
    ) -> Self {
        let (tx, ty) = tan_half_fov;
        let ndc = |e: u32, n: u32| (2.0 * e as f64 - n as f64) / n as f64;
        Self {
            x_slopes: [ndc(i, x) * tx, ndc(i + 1, x) * tx],
            // Row j counts from the top: its top edge is NDC 1 − 2j/Y.
            y_slopes: [-ndc(j + 1, y) * ty, -ndc(j, y) * ty],
            depths: [depths[0] as f64, depths[1] as f64],
        }
    }

    /// Corner `(a, b, c)` with each index 0 (low) or 1 (high) in x slope, y slope and depth.
    pub fn corner(&self, a: usize, b: usize, c: usize) -> DVec3 {
        let d = self.depths[c];
        DVec3::new(self.x_slopes[a] * d, self.y_slopes[b] * d, -d)
    }

    /// All eight corners.
    pub fn corners(&self) -> [DVec3; 8] {
        std::array::from_fn(|n| self.corner(n & 1, (n >> 1) & 1, n >> 2))
    }

    /// Whether `p` is inside the closed cell.
    pub fn contains(&self, p: DVec3) -> bool {
        self.planes().iter().all(|(n, o)| n.dot(p) - o <= 0.0)
    }

    /// The six bounding planes as (outward unit normal, offset): inside ⇔ `n·p − offset ≤ 0`.
    /// Order: left, right, bottom, top, near, far. (Slopes past ~1e154 overflow the normal's
    /// length and give a zero normal; a non-finite slope or depth a non-finite plane.)
    pub(super) fn planes(&self) -> [(DVec3, f64); 6] {
        // p.x ≥ s·d  ⇔  p.x + s·p.z ≥ 0; outward normal of the left wall is −(1, 0, s)/|…|.
        let side = |v: DVec3| v.normalize();
        [
            (side(-DVec3::new(1.0, 0.0, self.x_slopes[0])), 0.0),
            (side(DVec3::new(1.0, 0.0, self.x_slopes[1])), 0.0),
            (side(-DVec3::new(0.0, 1.0, self.y_slopes[0])), 0.0),
            (side(DVec3::new(0.0, 1.0, self.y_slopes[1])), 0.0),
            (DVec3::Z, -self.depths[0]),
            (DVec3::NEG_Z, self.depths[1]),
        ]
    }
}

/// Exact distance from `p` to the closed cell (0 when inside). A cell whose far depth is ∞ is
/// first cut where its closest point to `p` cannot lie (see the body).
pub fn distance_to_cell(p: DVec3, cell: &Cell) -> f64 {
    if cell.depths[1] == f64::INFINITY {
        // Infinite corners make `0 · ∞` and `∞ / ∞` NaN, which `f64::min` drops: the four edges
        // along depth went missing and a point beside one was called too far (a miss, for a
        // direct caller; the light tests cut first). The closest point is no farther from `p`
        // than the near face's corner `c`, so it lies no deeper than `depth(p) + |c − p|`: cut
        // there, with room to spare.
        let c = cell.corner(0, 0, 0);
        let reach = 2.0 * (c - p).length() + 1.0;
        let far = cell.depths[0].max(-p.z) + reach;
        if far.is_finite() {
            let cut = Cell {
                depths: [cell.depths[0], far],
                ..*cell
            };
            return distance_to_cell(p, &cut);
        }
    }
    let planes = cell.planes();
    let signed: [f64; 6] = std::array::from_fn(|f| planes[f].0.dot(p) - planes[f].1);
    if signed.iter().all(|&s| s <= 0.0) {
        return 0.0;
    }
    // Each face's vertices as (x-slope index, y-slope index, depth index), in loop order.
    const FACES: [[(usize, usize, usize); 4]; 6] = [
        [(0, 0, 0), (0, 1, 0), (0, 1, 1), (0, 0, 1)], // left
        [(1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)], // right
        [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)], // bottom
        [(0, 1, 0), (1, 1, 0), (1, 1, 1), (0, 1, 1)], // top
        [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], // near
        [(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)], // far
    ];
    let mut best = f64::INFINITY;
    for (f, face) in FACES.iter().enumerate() {
        // Only faces whose outside p is on can hold the closest point.
        if signed[f] <= 0.0 {
            continue;
        }
        let projected = p - planes[f].0 * signed[f];
        let inside_others = (0..6)
            .filter(|&g| g != f)
            .all(|g| planes[g].0.dot(projected) - planes[g].1 <= 0.0);
        if inside_others {
            best = best.min(signed[f]);
        }
        for e in 0..4 {
            let (a, b) = (face[e], face[(e + 1) % 4]);
            let (a, b) = (cell.corner(a.0, a.1, a.2), cell.corner(b.0, b.1, b.2));
            best = best.min(distance_to_segment(p, a, b));
        }
    }
    best
}

/// Whether the closed ball (`centre`, `radius`) touches the closed cell.
///
/// The ball lies between the depths `d − r` and `d + r` (`d` its centre's depth), so the cell is
/// first cut to that band, widened by one more radius and a few ulps of `d` (the cut cannot move
/// the answer; the widening covers the rounding of `d ± 2r`). The cut keeps every length local to
/// the light: `distance_to_cell` is accurate to a few ulps of the cell's largest corner, and an
/// uncut slice reaching 10⁹ or 10³⁰ deep made that error larger than the light itself — a ball
/// 0.07 from a cell was called 0.15 away (a miss of `exact`, unseen by `check`), another 2.3
/// away was called touching.
pub fn sphere_intersects_cell(centre: DVec3, radius: f64, cell: &Cell) -> bool {
    let depth = -centre.z;
    let reach = 2.0 * radius + 4.0 * f64::EPSILON * depth.abs();
    let near = cell.depths[0].max(depth - reach);
    let far = cell.depths[1].min(depth + reach);
    if near > far {
        // The ball ends more than a radius before the cell's near wall or beyond its far wall.
        return false;
    }
    let cut = Cell {
        depths: [near, far],
        ..*cell
    };
    distance_to_cell(centre, &cut) <= radius
}

fn distance_to_segment(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t).distance(p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oracle::cell_point;
    use rand::{Rng, SeedableRng};

    #[test]
    fn distance_matches_dense_boundary_sampling() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        const N: usize = 48;
        for _ in 0..60 {
            let cell = crate::oracle::random_cell(&mut rng, 1.0);
            // Dense samples on the six faces (the closest point of a convex set to an outside point
            // is on its boundary).
            let mut samples = Vec::new();
            for a in 0..=N {
                for b in 0..=N {
                    let (u, v) = (a as f64 / N as f64, b as f64 / N as f64);
                    for fixed in [0.0, 1.0] {
                        samples.push(cell_point(&cell, fixed, u, v));
                        samples.push(cell_point(&cell, u, fixed, v));
                        samples.push(cell_point(&cell, u, v, fixed));
                    }
                }
            }
            let extent = cell
                .corners()
                .iter()
                .map(|c| c.length())
                .fold(0.0, f64::max);
            for _ in 0..40 {
                let p = DVec3::new(
                    rng.random_range(-1.5..1.5),
                    rng.random_range(-1.5..1.5),
                    rng.random_range(-1.5..0.3),
                ) * extent;
                let exact = distance_to_cell(p, &cell);
                let sampled = samples
                    .iter()
                    .map(|s| s.distance(p))
                    .fold(f64::INFINITY, f64::min);
                if cell.contains(p) {
                    assert_eq!(exact, 0.0);
                    continue;
                }
                // Exact is a lower bound of every sampled distance, and the dense sampling gets
                // close to it (sample spacing bounds the gap).
                let spacing = cell
                    .corners()
                    .iter()
                    .map(|c| c.distance(cell.corner(0, 0, 0)))
                    .fold(0.0, f64::max)
                    / N as f64;
                assert!(
                    exact <= sampled + 1e-9 * extent,
                    "exact {exact} > sampled {sampled}"
                );
                assert!(
                    sampled - exact <= spacing,
                    "exact {exact} far below sampled {sampled}"
                );
            }
        }
    }

    #[test]
    fn interior_points_have_zero_distance_and_spheres_touching_faces_intersect() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(12);
        for _ in 0..200 {
            let cell = crate::oracle::random_cell(&mut rng, 1.0);
            let p = cell_point(
                &cell,
                rng.random_range(0.0..1.0),
                rng.random_range(0.0..1.0),
                rng.random_range(0.0..1.0),
            );
            assert_eq!(distance_to_cell(p, &cell), 0.0);
            // Just outside the near face by `gap`: a sphere of radius gap touches, a smaller misses.
            let q = cell_point(&cell, 0.5, 0.5, 0.0);
            let gap = 0.25 * cell.depths[0];
            let outside = q + DVec3::Z * gap;
            let dist = distance_to_cell(outside, &cell);
            assert!((dist - gap).abs() <= 1e-12 * (1.0 + gap), "{dist} vs {gap}");
            assert!(sphere_intersects_cell(outside, gap * (1.0 + 1e-9), &cell));
            assert!(!sphere_intersects_cell(outside, gap * 0.999, &cell));
        }
    }

    #[test]
    fn a_ball_centred_inside_a_cell_touches_it_however_small() {
        // The depth cut must not shrink below the ball: a light far smaller than an ulp of its
        // depth (or of radius zero) whose centre lies in the cell still touches it.
        let mut rng = rand_pcg::Pcg64::seed_from_u64(14);
        for n in 0..200 {
            let cell = crate::oracle::random_cell(&mut rng, [1.0, 1e3, 1e6][n % 3]);
            let p = cell_point(
                &cell,
                rng.random_range(0.1..0.9),
                rng.random_range(0.1..0.9),
                rng.random_range(0.1..0.9),
            );
            assert!(cell.contains(p), "{p} inside {cell:?}");
            for r in [
                0.0,
                f64::MIN_POSITIVE,
                1e-300,
                1e-20,
                1e-3 * f64::EPSILON * -p.z,
            ] {
                assert!(sphere_intersects_cell(p, r, &cell), "{p} r {r} {cell:?}");
            }
        }
    }

    /// A cell open to infinite depth, with a zero slope (the middle column's edge): a point
    /// beside its edges along depth is as far as from the same cell cut deep enough. Uncut, the
    /// corners `0 · ∞` were NaN and those edges were lost.
    #[test]
    fn an_infinite_cell_keeps_its_edges_along_depth() {
        let open = Cell {
            x_slopes: [0.0, 0.5],
            y_slopes: [0.0, 0.25],
            depths: [1.0, f64::INFINITY],
        };
        let deep = Cell {
            depths: [1.0, 1e9],
            ..open
        };
        for p in [
            DVec3::new(-0.3, -0.2, -5.0),
            DVec3::new(-2.0, 3.0, -40.0),
            DVec3::new(7.0, -1.0, -2.0),
            DVec3::new(0.1, 0.1, 3.0),
            DVec3::new(-1e5, 0.0, -1e6),
        ] {
            let (got, want) = (distance_to_cell(p, &open), distance_to_cell(p, &deep));
            assert!(
                (got - want).abs() <= 1e-9 * want.max(1.0),
                "{p}: {got} against {want}"
            );
        }
        // A point inside the open cell, past any finite cut one might have picked.
        assert_eq!(distance_to_cell(DVec3::new(1e11, 1e10, -1e12), &open), 0.0);
    }

    /// Random open cells and points: the distance equals the distance to the same cell cut far
    /// deeper than the open cell's own cut (4 × the corner's distance instead of 2 ×). The
    /// fixed points above left the cut's depth unpinned: a cut at a quarter of the corner's
    /// distance called the first case below 84.0 away instead of 77.8 — a ball of radius 80
    /// there not touching, a light missing from `exact`'s open last slice (mutation audit).
    #[test]
    fn an_infinite_cell_is_as_far_as_the_same_cell_cut_well_past_its_closest_point() {
        let check = |p: DVec3, open: Cell| {
            let corner = open.corner(0, 0, 0);
            let far = open.depths[0].max(-p.z) + 4.0 * (corner - p).length() + 10.0;
            let cut = Cell {
                depths: [open.depths[0], far],
                ..open
            };
            let (got, want) = (distance_to_cell(p, &open), distance_to_cell(p, &cut));
            assert!(
                (got - want).abs() <= 1e-9 * want.max(1.0),
                "{p}, {open:?}: {got} against {want}"
            );
        };
        check(
            DVec3::new(113.85380394105331, -31.522886710542906, 11.288005347125136),
            Cell {
                x_slopes: [-48.335969104140474, 1.319010776857065],
                y_slopes: [-35.01383204669804, 49.799448006834915],
                depths: [0.08070471989922934, f64::INFINITY],
            },
        );
        let mut rng = rand_pcg::Pcg64::seed_from_u64(23);
        let slopes = |rng: &mut rand_pcg::Pcg64| {
            let scale = 10f64.powf(rng.random_range(-2.0..2.0));
            let (a, b) = (
                rng.random_range(-1.0..1.0) * scale,
                rng.random_range(-1.0..1.0) * scale,
            );
            [a.min(b), a.max(b)]
        };
        for _ in 0..200_000 {
            let open = Cell {
                x_slopes: slopes(&mut rng),
                y_slopes: slopes(&mut rng),
                depths: [10f64.powf(rng.random_range(-3.0..3.0)), f64::INFINITY],
            };
            let scale = 10f64.powf(rng.random_range(-2.0..4.0));
            let p = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..0.3),
            ) * scale;
            check(p, open);
        }
    }

    #[test]
    fn a_cell_of_zero_thickness_is_touched_like_its_face() {
        // Slices of a very thin log grid can have equal f32 edges: such a cell is its near face,
        // and a ball reaching that face touches it.
        let mut rng = rand_pcg::Pcg64::seed_from_u64(15);
        for _ in 0..200 {
            let mut cell = crate::oracle::random_cell(&mut rng, 1.0);
            cell.depths[1] = cell.depths[0];
            let on_face = cell_point(
                &cell,
                rng.random_range(0.1..0.9),
                rng.random_range(0.1..0.9),
                0.0,
            );
            let gap = rng.random_range(0.01..1.0) * cell.depths[0];
            for side in [-1.0, 1.0] {
                let centre = on_face + DVec3::Z * (side * gap);
                assert!(sphere_intersects_cell(centre, gap * (1.0 + 1e-9), &cell));
                assert!(!sphere_intersects_cell(centre, gap * 0.999, &cell));
            }
            assert!(sphere_intersects_cell(on_face, 1e-9 * gap, &cell));
        }
    }

    /// The cell of tile `(i, j, k)` under a camera at the origin looking down −z.
    fn cell_at(
        fov: f32,
        dims: [u32; 3],
        slicing: crate::DepthSlicing,
        depth: [f32; 2],
        tile: [u32; 3],
    ) -> Cell {
        let cam = Camera::new(
            glam::Vec3::ZERO,
            glam::Vec3::NEG_Z,
            glam::Vec3::Y,
            fov,
            1536,
            768,
            depth[0],
            depth[1],
        );
        let grid = ClusterGrid::new(glam::UVec3::from_array(dims), slicing, depth[0], depth[1]);
        Cell::of_cluster(&cam, &grid, tile[0], tile[1], tile[2])
    }

    #[test]
    fn slices_reaching_very_deep_do_not_blur_small_lights() {
        use crate::DepthSlicing::{Linear, Log};
        // Found by audit (each distance recomputed in exact rational arithmetic); the uncut cell's
        // far corners put errors larger than the light into the distance.
        let ball =
            |x: f32, y: f32, z: f32, r: f32| (DVec3::new(x.into(), y.into(), z.into()), r as f64);
        // 0.0679 from the cell, radius 0.08: touches (was computed 0.149 away).
        let (c, r) = ball(-0.05, 0.05, -1.0, 0.08);
        let cell = cell_at(60.0, [24, 12, 16], Linear, [0.1, 1e30], [12, 4, 0]);
        assert!(sphere_intersects_cell(c, r, &cell));
        // 2.31 from the cell, radius 0.3: misses (was computed 0.052 away).
        let (c, r) = ball(0.01, 0.01, -0.05, 0.3);
        let cell = cell_at(170.0, [24, 12, 16], Linear, [0.1, 1e30], [0, 0, 0]);
        assert!(!sphere_intersects_cell(c, r, &cell));
        // One slice from 1e-6 to 1e9: 9.80e-7 from the cell, radius 1e-6, touches (was 1.0006e-6).
        let (c, r) = ball(-6.06e-6, 1e-7, -1.6e-6, 1e-6);
        let cell = cell_at(120.0, [1, 50, 1], Log, [1e-6, 1e9], [0, 15, 0]);
        assert!(sphere_intersects_cell(c, r, &cell));
    }

    /// A centre for a ball of radius `r` around the near end of the cell, inside or outside it
    /// (up to two radii off in depth).
    fn centre_near_the_near_end(rng: &mut rand_pcg::Pcg64, cell: &Cell, r: f64) -> DVec3 {
        cell_point(
            cell,
            rng.random_range(-0.3..1.3),
            rng.random_range(-0.3..1.3),
            rng.random_range(-0.1..0.05),
        ) + DVec3::new(0.0, 0.0, rng.random_range(-2.0..2.0) * r)
    }

    #[test]
    fn a_far_wall_beyond_the_ball_does_not_change_the_answer() {
        // The ball cannot reach past depth d + r, so moving the far wall from just beyond it to
        // 10⁹…10³⁰ must not change whether they touch.
        let mut rng = rand_pcg::Pcg64::seed_from_u64(13);
        let mut touching = 0;
        for n in 0..4000 {
            let cell = crate::oracle::random_cell(&mut rng, 1.0);
            let r = 10f64.powf(rng.random_range(-3.0..0.5));
            let p = centre_near_the_near_end(&mut rng, &cell, r);
            let near_far = (-p.z + 2.0 * r).max(cell.depths[0]) * 1.5;
            let local = Cell {
                depths: [cell.depths[0], near_far],
                ..cell
            };
            let deep = Cell {
                depths: [cell.depths[0], [1e9, 1e20, 1e30][n % 3]],
                ..cell
            };
            let want = distance_to_cell(p, &local) <= r;
            touching += want as usize;
            assert_eq!(
                sphere_intersects_cell(p, r, &deep),
                want,
                "{p} r {r} {deep:?}"
            );
        }
        assert!((500..3500).contains(&touching), "{touching} of 4000 touch");
    }

    #[test]
    fn a_tiny_light_is_judged_at_its_own_scale_however_deep_the_cell() {
        // The cut keeps lengths local to the light only if it ends about a radius past the ball:
        // one that reached a fixed length further (2 or 4, or 4ε / depth) kept errors of ulps of
        // that length, larger than these lights. Cells and lights about 1e-16 across, the cell's
        // far wall from 1e9 to 1e30: the answer is the one of the cell cut just beyond the ball.
        let mut rng = rand_pcg::Pcg64::seed_from_u64(16);
        let (mut touching, mut close) = (0, 0);
        for n in 0..4000 {
            let cell = crate::oracle::random_cell(&mut rng, 1e-16);
            let r = 1e-16 * 10f64.powf(rng.random_range(-1.0..0.5));
            let p = centre_near_the_near_end(&mut rng, &cell, r);
            let local = Cell {
                depths: [cell.depths[0], (-p.z + 2.0 * r).max(cell.depths[0]) * 1.5],
                ..cell
            };
            let deep = Cell {
                depths: [cell.depths[0], [1e9, 1e20, 1e30][n % 3]],
                ..cell
            };
            let distance = distance_to_cell(p, &local);
            let want = distance <= r;
            touching += want as usize;
            close += ((distance - r).abs() < 0.05 * r) as usize;
            assert_eq!(
                sphere_intersects_cell(p, r, &deep),
                want,
                "{p} r {r} {deep:?}: {distance} from the cut cell"
            );
        }
        assert!(
            (500..3500).contains(&touching) && close > 20,
            "{touching} of 4000 touch, {close} within 5% of touching"
        );
    }

    #[test]
    fn a_cell_shrunk_to_a_point_is_at_the_distance_of_that_point() {
        // Every edge of the cell has length zero: the distance is the one to its only point.
        let cell = Cell {
            x_slopes: [0.25, 0.25],
            y_slopes: [-0.5, -0.5],
            depths: [4.0, 4.0],
        };
        let point = cell.corner(0, 0, 0);
        assert_eq!(point, DVec3::new(1.0, -2.0, -4.0));
        assert_eq!(distance_to_cell(point, &cell), 0.0);
        for offset in [
            DVec3::new(3.0, 0.0, 0.0),
            DVec3::new(0.0, -1.5, 0.0),
            DVec3::new(0.0, 0.0, 2.0),
            DVec3::new(-1.0, 2.0, -2.0),
        ] {
            let d = distance_to_cell(point + offset, &cell);
            assert!(
                (d - offset.length()).abs() <= 1e-12,
                "{offset}: {d}, want {}",
                offset.length()
            );
            assert!(sphere_intersects_cell(
                point + offset,
                offset.length() * 1.001,
                &cell
            ));
            assert!(!sphere_intersects_cell(
                point + offset,
                offset.length() * 0.999,
                &cell
            ));
        }
    }

    #[test]
    fn cell_of_cluster_matches_grid_edges() {
        use crate::DepthSlicing;
        use glam::{UVec3, Vec3};
        let cam = Camera::new(
            Vec3::ZERO,
            Vec3::NEG_Z,
            Vec3::Y,
            60.0,
            1536,
            768,
            0.1,
            100.0,
        );
        let grid = ClusterGrid::new(UVec3::new(24, 12, 16), DepthSlicing::Log, 0.1, 100.0);
        let c = Cell::of_cluster(&cam, &grid, 0, 0, 0);
        let (tx, ty) = cam.tan_half_fov_f64();
        assert_eq!(c.x_slopes[0], -tx);
        assert_eq!(c.y_slopes[1], ty);
        assert_eq!(c.depths[0], 0.1f32 as f64);
        let last = Cell::of_cluster(&cam, &grid, 23, 11, 15);
        assert_eq!(last.x_slopes[1], tx);
        assert_eq!(last.y_slopes[0], -ty);
        assert_eq!(last.depths[1], 100.0);
    }
}
