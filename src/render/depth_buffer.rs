//! What a depth buffer (a prepass, read back) says about the frame: the depth range that holds
//! every drawn pixel ([`fitted_grid`]) and the clusters that hold one ([`mark_active`]), plus the
//! screen boxes of alpha-blended draws, which the depth buffer does not show but the forward pass
//! shades.
//!
//! Exactness: pixel → cluster on the GPU uses its own f32 rounding of the view depth, so a pixel
//! whose depth lies within 1e-5 (relative) of a slice edge marks the clusters on both sides, and
//! the fitted range is widened by 1e-4. The conversion (`Camera::view_depth_from_ndc_depth`, the
//! same formula in WGSL) is within 1e-6 of the exact depth of the stored value, fused or not, for
//! any near plane (tested in `myriad-cluster-math`), so the band has ten times the room it needs.
//! (The textbook formula it replaced was 5e-5 off at near 0.1, far 100: over the band.)
//! A blended draw is not in the depth buffer: its box's depths are computed here, exactly but
//! for the f32 camera-relative subtraction the vertex shader also makes, and widened by the
//! GPU's rounding, which grows with a point's distance from the camera, not its depth
//! ([`BOX_ROUNDING`]).

use myriad_assignment::ActiveClusters;
use myriad_scene::{Aabb, Camera, ClusterGrid, DepthSlicing, OuterSlices};
use rayon::prelude::*;

/// Relative widening of the fitted range and of the slice-edge tolerance.
const DEPTH_TOLERANCE: f32 = 1e-4;
const EDGE_TOLERANCE: f32 = 1e-5;

/// How far a blended fragment's view depth may lie from the exact depth of its point, per unit
/// of the point's distance from the camera. The forward pass transforms camera-relative f32
/// vertices by an f32 matrix, so its rounding grows with that distance, not with the depth:
/// at a field of view near 180° a point at depth 2 can lie 400 units to the side. With the
/// box's depths in f32 and only the bands relative to depth, a fragment 1.1e-4 (relative)
/// nearer than its corner's f32 depth read a cluster the mask had left empty (179.5°, 4000 ×
/// 100; audit). 1e-6 is about eight f32 units in the last place, several times what a 3-term
/// dot product and the rotation's own f32 rounding can add.
const BOX_ROUNDING: f64 = 1e-6;

/// View-depth extent of a world box seen by `camera`, widened by what the GPU's rounding can
/// move a fragment of the box ([`BOX_ROUNDING`]), and its NDC extent (the whole screen when the
/// box reaches behind the near plane); `None` when it lies wholly behind the near plane or
/// beyond the far plane.
///
/// The corners are made camera-relative in f32, as the vertex shader makes each vertex (f32
/// subtraction rounds monotonically, so every vertex of the box stays inside these corners),
/// then rotated in f64: the depths are exact but for that subtraction.
fn box_depths(camera: &Camera, b: &Aabb) -> Option<(f32, f32, [f32; 4])> {
    let rotation = camera.view_rotation_f64();
    let (tan_x, tan_y) = camera.tan_half_fov_f64();
    let (near, far) = (camera.near as f64, camera.far as f64);
    let (mut dmin, mut dmax) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut ndc = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut in_front = true;
    for corner in b.corners() {
        let rel = (corner - camera.position).as_dvec3();
        let v = rotation * rel;
        let (d, slack) = (-v.z, BOX_ROUNDING * rel.length());
        dmin = dmin.min(d - slack);
        dmax = dmax.max(d + slack);
        if d - slack <= near {
            in_front = false;
        } else {
            let (x, y) = (v.x / (d * tan_x), v.y / (d * tan_y));
            ndc = [ndc[0].min(x), ndc[1].max(x), ndc[2].min(y), ndc[3].max(y)];
        }
    }
    if dmax < near || dmin > far {
        return None;
    }
    if !in_front {
        ndc = [-1.0, 1.0, -1.0, 1.0];
    }
    Some((
        f32_down(dmin.max(near)),
        f32_up(dmax.min(far)),
        ndc.map(|t| t as f32),
    ))
}

/// The largest f32 at or below `x`.
fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x { f.next_down() } else { f }
}

/// The smallest f32 at or above `x`.
fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x { f.next_up() } else { f }
}

/// The scene grid over the depth range that holds every covered pixel and every blended draw
/// (`blended`: their world bounds, [`crate::render::blended_bounds`]; the depth buffer does not
/// hold them).
pub fn fitted_grid(
    grid: &ClusterGrid,
    camera: &Camera,
    depth: &[f32],
    blended: &[Aabb],
) -> ClusterGrid {
    // View depth falls as the stored depth grows (reversed Z, 0 where nothing was drawn), so the
    // extremes of the raw values are enough.
    let (raw_lo, raw_hi) = depth
        .par_chunks(1 << 16)
        .map(|chunk| {
            chunk
                .iter()
                .filter(|&&d| d > 0.0)
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &d| {
                    (lo.min(d), hi.max(d))
                })
        })
        .reduce(
            || (f32::INFINITY, f32::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    if raw_lo <= raw_hi {
        lo = camera.view_depth_from_ndc_depth(raw_hi);
        hi = camera.view_depth_from_ndc_depth(raw_lo);
    }
    for b in blended {
        if let Some((dmin, dmax, _)) = box_depths(camera, b) {
            lo = lo.min(dmin);
            hi = hi.max(dmax);
        }
    }
    if !(lo <= hi) {
        return *grid; // Nothing visible: any range will do.
    }
    let nearest = lo * (1.0 - DEPTH_TOLERANCE);
    let near = nearest.max(grid.near());
    let deepest = hi * (1.0 + DEPTH_TOLERANCE);
    let mut far = deepest.min(grid.far());
    if !(far > near) {
        far = (near * (1.0 + DEPTH_TOLERANCE)).max(near.next_up());
    }
    let slicing = match grid.slicing() {
        DepthSlicing::LogWithNearSlice { first_slice_depth }
            if !(first_slice_depth > near && first_slice_depth < far) =>
        {
            DepthSlicing::Log
        }
        s => s,
    };
    // Where every shaded depth lies inside the fitted range, no pixel reads an outer slice from
    // outside it: the lights wholly outside need no list (`OuterSlices::Closed`). Pixels outside
    // a shorter scene grid keep its outer slices.
    let outer = if grid.near() <= nearest && deepest <= grid.far() {
        OuterSlices::Closed
    } else {
        grid.outer_slices()
    };
    ClusterGrid::new(grid.dims(), slicing, near, far).with_outer_slices(outer)
}

/// The grid's slice edges as keys of stored depth-buffer values, each with the band around it
/// where the GPU's own rounding of the view depth could put a pixel on either side
/// ([`EDGE_TOLERANCE`], relative). The key of a stored depth `d` is `−d`: the projection is
/// reversed Z, so view depth grows as the stored depth falls, and as its key grows.
struct SliceEdgesNdc {
    /// Key of edge k·(1 − tolerance) and of edge k·(1 + tolerance), k = 0..=Z.
    below: Vec<f32>,
    above: Vec<f32>,
    z: u32,
}

/// The key [`SliceEdgesNdc`] orders a stored depth by: increasing with view depth.
#[inline]
fn depth_key(stored: f32) -> f32 {
    -stored
}

impl SliceEdgesNdc {
    fn new(grid: &ClusterGrid, camera: &Camera) -> Self {
        let stored = |d: f64| depth_key(camera.ndc_depth_from_view_depth(d) as f32);
        let z = grid.dims().z;
        let edge = |k: u32| grid.slice_start_depth(k) as f64;
        let tol = EDGE_TOLERANCE as f64;
        // Rounded outwards to f32, so the bands only ever grow.
        Self {
            below: (0..=z)
                .map(|k| stored(edge(k) * (1.0 - tol)).next_down())
                .collect(),
            above: (0..=z)
                .map(|k| stored(edge(k) * (1.0 + tol)).next_up())
                .collect(),
            z,
        }
    }

    /// The slices a pixel of depth key `d` may belong to, and the interval of keys that gives
    /// the same answer.
    #[inline]
    fn slices_of(&self, d: f32) -> ((u32, u32), (f32, f32)) {
        let last = self.z - 1;
        // Inner edges 1..Z−1 only: below the first or beyond the last clamps like the shader.
        let inner_below = &self.below[1..self.z as usize];
        let inner_above = &self.above[1..self.z as usize];
        // Slices whose lower band starts at or below d, and those whose upper band is passed.
        let lo = inner_above.partition_point(|&e| e <= d) as u32;
        let hi = (inner_below.partition_point(|&e| e <= d) as u32).min(last);
        let run_lo = if lo == 0 {
            f32::NEG_INFINITY
        } else {
            inner_above[lo as usize - 1]
        };
        let run_hi = inner_below
            .get(hi as usize)
            .copied()
            .unwrap_or(f32::INFINITY);
        let run_lo = if hi > 0 {
            run_lo.max(inner_below[hi as usize - 1])
        } else {
            run_lo
        };
        let run_hi = inner_above
            .get(lo as usize)
            .copied()
            .map_or(run_hi, |e| run_hi.min(e));
        ((lo, hi), (run_lo, run_hi))
    }
}

/// Marks the clusters of every covered pixel (both sides of a slice edge within
/// 1e-5 relative) and of every blended draw's screen box (`blended`: their world bounds,
/// [`crate::render::blended_bounds`]). The mask is reset for `grid` first, so one mask serves
/// every frame's grid; assign with that same grid (after [`fitted_grid`], the fitted one).
pub fn mark_active(
    mask: &mut ActiveClusters,
    grid: &ClusterGrid,
    camera: &Camera,
    depth: &[f32],
    blended: &[Aabb],
) {
    mask.reset(grid);
    let (w, h) = (camera.width as usize, camera.height as usize);
    let edges = SliceEdgesNdc::new(grid, camera);
    let tile_x: Vec<u32> = (0..w as u32)
        .map(|px| grid.tile_x_of_pixel(px, w as u32))
        .collect();
    // Rows in parallel, each band into its own flags, then one merge.
    let rows_per_band = (h / (4 * rayon::current_num_threads())).max(1);
    let flags = depth
        .par_chunks(rows_per_band * w)
        .enumerate()
        .map(|(band, pixels)| {
            let mut flags = vec![false; grid.cluster_count()];
            for (r, row) in pixels.chunks(w).enumerate() {
                let py = (band * rows_per_band + r) as u32;
                let j = grid.tile_y_of_pixel(py, h as u32);
                let row_base = grid.dims().x * j;
                // The slice range of the previous pixel, valid while the depth stays in `run`.
                let mut run = (f32::NAN, f32::NAN);
                let mut slices = (0, 0);
                for (px, &stored) in row.iter().enumerate() {
                    if stored <= 0.0 {
                        continue; // Reversed Z: nothing drawn.
                    }
                    let d = depth_key(stored);
                    if !(d >= run.0 && d < run.1) {
                        (slices, run) = edges.slices_of(d);
                    }
                    for k in slices.0..=slices.1 {
                        let layer = grid.dims().x * grid.dims().y * k;
                        flags[(tile_x[px] + row_base + layer) as usize] = true;
                    }
                }
            }
            flags
        })
        .reduce(
            || vec![false; grid.cluster_count()],
            |mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, &y)| *x |= y);
                a
            },
        );
    for (c, &on) in flags.iter().enumerate() {
        if on {
            mask.mark(c as u32);
        }
    }
    let dims = grid.dims();
    for b in blended {
        let Some((dmin, dmax, ndc)) = box_depths(camera, b) else {
            continue;
        };
        let tile = |t: f32, n: u32| ((t.clamp(0.0, 1.0) * n as f32) as u32).min(n - 1);
        // One tile of margin each way: the corner projection is rounded differently on the GPU.
        let x = [
            tile((ndc[0] + 1.0) / 2.0, dims.x).saturating_sub(1),
            tile((ndc[1] + 1.0) / 2.0, dims.x) + 1,
        ];
        let y = [
            tile((1.0 - ndc[3]) / 2.0, dims.y).saturating_sub(1),
            tile((1.0 - ndc[2]) / 2.0, dims.y) + 1,
        ];
        let z = [
            grid.slice_of_depth(dmin * (1.0 - EDGE_TOLERANCE)),
            grid.slice_of_depth(dmax * (1.0 + EDGE_TOLERANCE)),
        ];
        mask.mark_box(x, y, z);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use myriad_scene::glam::{UVec3, Vec3, Vec4};

    /// Every covered pixel's cluster, computed the slow obvious way, is marked; and a pixel near
    /// a slice edge marks both sides.
    #[test]
    fn fast_marking_covers_every_pixel_cluster() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 97, 61, 0.1, 100.0);
        for (dims, slicing) in [
            (UVec3::new(24, 12, 16), DepthSlicing::Log),
            (UVec3::new(7, 5, 33), DepthSlicing::Linear),
            (UVec3::new(3, 3, 1), DepthSlicing::Log),
        ] {
            let grid = ClusterGrid::new(dims, slicing, 0.1, 100.0);
            let stored = |v: f32| camera.ndc_depth_from_view_depth(v as f64) as f32;
            // Stored depths (reversed Z): background, random, and exactly at every slice edge.
            let mut state = 7u64;
            let mut next = || {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
                (state >> 40) as f32 / (1u64 << 24) as f32
            };
            let edges: Vec<f32> = (0..=dims.z)
                .map(|k| stored(grid.slice_start_depth(k)))
                .collect();
            let depth: Vec<f32> = (0..97 * 61)
                .map(|i| match i % 5 {
                    0 => 0.0, // Reversed Z: nothing drawn.
                    1 => edges[i % edges.len()],
                    // Log-uniform in view depth over [near, far).
                    _ => stored(0.1 * 1000f32.powf(next())),
                })
                .collect();
            let mut mask = ActiveClusters::new(&grid);
            mark_active(&mut mask, &grid, &camera, &depth, &[]);
            let mut expected = std::collections::BTreeSet::new();
            for py in 0..61u32 {
                for px in 0..97u32 {
                    let d = depth[(py * 97 + px) as usize];
                    if d <= 0.0 {
                        continue;
                    }
                    let v = camera.view_depth_from_ndc_depth(d);
                    for scale in [1.0, 1.0 - 5e-6, 1.0 + 5e-6] {
                        let c = grid.cluster_of_pixel(px, py, v * scale, 97, 61);
                        assert!(
                            mask.is_active(c),
                            "{dims}: pixel ({px}, {py}) depth {d} cluster {c}"
                        );
                        expected.insert(c);
                    }
                }
            }
            // Not everything: a cluster marked beyond the pixels' own is the depth neighbour of
            // one of them in the same tile (the edge band around a slice boundary).
            let (tiles, total) = (dims.x * dims.y, dims.x * dims.y * dims.z);
            let mut extra = 0;
            for c in (0..total).filter(|&c| mask.is_active(c) && !expected.contains(&c)) {
                let near_own = (c >= tiles && expected.contains(&(c - tiles)))
                    || (c + tiles < total && expected.contains(&(c + tiles)));
                assert!(near_own, "{dims}: cluster {c} marked far from any pixel's");
                extra += 1;
            }
            assert_eq!(mask.active_count(), expected.len() + extra);
        }
    }

    /// A 64 × 48 camera at the origin looking down −Z (its view transform is exact: a world
    /// point at z = −d is at view depth d), near 0.1, far 100.
    fn camera() -> Camera {
        Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 64, 48, 0.1, 100.0)
    }

    fn stored(camera: &Camera, view_depth: f32) -> f32 {
        camera.ndc_depth_from_view_depth(view_depth as f64) as f32
    }

    fn aabb(min: [f32; 3], max: [f32; 3]) -> Aabb {
        Aabb {
            min: Vec3::from(min),
            max: Vec3::from(max),
        }
    }

    /// Every drawn pixel's view depth lies inside the fitted grid's range.
    fn assert_holds_every_drawn_depth(fitted: &ClusterGrid, camera: &Camera, depth: &[f32]) {
        for &d in depth.iter().filter(|&&d| d > 0.0) {
            let v = camera.view_depth_from_ndc_depth(d);
            assert!(
                fitted.near() <= v && v <= fitted.far(),
                "stored {d} (view depth {v}) outside [{}, {}]",
                fitted.near(),
                fitted.far()
            );
        }
    }

    #[test]
    fn the_fitted_range_holds_every_drawn_depth_and_little_more() {
        let camera = camera();
        let grid = ClusterGrid::new(UVec3::new(16, 12, 16), DepthSlicing::Log, 0.1, 100.0);
        // Background between drawn pixels from 2 to 30; boxes behind the camera and beyond the
        // far plane are not seen and must not widen the range.
        let depth: Vec<f32> = [0.0, 2.0, 0.0, 7.3, 30.0, 11.0, 0.0]
            .iter()
            .map(|&v| if v == 0.0 { 0.0 } else { stored(&camera, v) })
            .collect();
        let unseen = [
            aabb([-1.0, -1.0, 1.0], [1.0, 1.0, 2.0]),
            aabb([-1.0, -1.0, -300.0], [1.0, 1.0, -200.0]),
        ];
        let fitted = fitted_grid(&grid, &camera, &depth, &unseen);
        assert_holds_every_drawn_depth(&fitted, &camera, &depth);
        let (lo, hi) = (
            camera.view_depth_from_ndc_depth(depth[1]),
            camera.view_depth_from_ndc_depth(depth[4]),
        );
        assert!(
            fitted.near() >= lo * (1.0 - 2.0 * DEPTH_TOLERANCE),
            "{fitted:?}"
        );
        assert!(
            fitted.far() <= hi * (1.0 + 2.0 * DEPTH_TOLERANCE),
            "{fitted:?}"
        );
        assert_eq!(
            (fitted.dims(), fitted.slicing()),
            (grid.dims(), grid.slicing())
        );
        // No pixel lies past the fitted range: the lights beyond it need no list.
        assert_eq!(fitted.outer_slices(), OuterSlices::Closed);
        // Pixels outside a scene grid shorter than the view (to 20, the pixel at 30 beyond it;
        // from 3, the pixel at 2 nearer) read its outer slices: the fitted grid keeps that grid's,
        // open or closed.
        for short in [
            grid.with_depth_range(0.1, 20.0),
            grid.with_depth_range(3.0, 100.0),
        ] {
            for outer in [OuterSlices::Open, OuterSlices::Closed] {
                let short = short.with_outer_slices(outer);
                let fitted = fitted_grid(&short, &camera, &depth, &unseen);
                assert_eq!(fitted.outer_slices(), outer, "{short:?}");
            }
        }
        // A pixel exactly at the near plane (stored 1) and one at the far plane (the smallest
        // stored value that is not background): the fitted range is the whole grid, no wider.
        let edges = [0.0, 1.0, f32::from_bits(1), 0.0];
        let fitted = fitted_grid(&grid, &camera, &edges, &[]);
        assert_holds_every_drawn_depth(&fitted, &camera, &edges);
        assert_eq!((fitted.near(), fitted.far()), (grid.near(), grid.far()));
    }

    #[test]
    fn nothing_drawn_keeps_the_grid() {
        let camera = camera();
        let grid = ClusterGrid::new(UVec3::new(16, 12, 16), DepthSlicing::Log, 0.1, 100.0);
        let cleared = [0.0, -0.0, 0.0, -0.0];
        assert_eq!(fitted_grid(&grid, &camera, &cleared, &[]), grid);
    }

    #[test]
    fn blended_draws_widen_the_fitted_range_to_their_depths() {
        let camera = camera();
        let grid = ClusterGrid::new(UVec3::new(16, 12, 16), DepthSlicing::Log, 0.1, 100.0);
        let depth = [0.0, stored(&camera, 5.0), stored(&camera, 6.0), 0.0];
        // A box from 20 to 40 deep, wholly in front of the camera, alone and with the pixels.
        let deep = aabb([-1.0, -1.0, -40.0], [1.0, 1.0, -20.0]);
        for pixels in [&[0.0; 4][..], &depth[..]] {
            let fitted = fitted_grid(&grid, &camera, pixels, &[deep]);
            assert_holds_every_drawn_depth(&fitted, &camera, pixels);
            assert!(fitted.far() >= 40.0 && fitted.far() <= 40.0 * (1.0 + 2.0 * DEPTH_TOLERANCE));
            let nearest = if pixels[1] > 0.0 { 5.0 } else { 20.0 };
            assert!(fitted.near() <= nearest, "{fitted:?}");
            assert!(fitted.near() >= nearest * (1.0 - 2.0 * DEPTH_TOLERANCE));
        }
        // A box through the near plane is seen from the near plane on.
        let through = aabb([-1.0, -1.0, -3.0], [1.0, 1.0, 1.0]);
        let fitted = fitted_grid(&grid, &camera, &depth, &[through]);
        assert_eq!(fitted.near(), camera.near);
        assert_holds_every_drawn_depth(&fitted, &camera, &depth);
    }

    /// Everything drawn lies in front of the grid's near edge, so the widened range collapses onto
    /// it: the fitted range is still a range, `DEPTH_TOLERANCE` wide.
    #[test]
    fn a_range_collapsed_onto_the_grids_near_edge_is_widened_by_the_tolerance() {
        let camera = camera();
        let s = stored(&camera, 0.5);
        let g = camera.view_depth_from_ndc_depth(s) * (1.0 + DEPTH_TOLERANCE);
        let grid = ClusterGrid::new(UVec3::new(4, 4, 8), DepthSlicing::Log, g, 100.0);
        let fitted = fitted_grid(&grid, &camera, &[0.0, s, s], &[]);
        assert_eq!(fitted.near(), g);
        assert!(
            fitted.far() >= g * (1.0 + 0.5 * DEPTH_TOLERANCE)
                && fitted.far() <= g * (1.0 + 2.0 * DEPTH_TOLERANCE),
            "{fitted:?}"
        );
    }

    /// A near-slice edge strictly inside the fitted range is kept; one outside it or exactly on
    /// either fitted bound leaves no first slice to keep, and the grid falls back to `Log`.
    #[test]
    fn a_first_slice_edge_not_strictly_inside_the_fitted_range_falls_back_to_log() {
        let camera = camera();
        let depth = [0.0, stored(&camera, 2.0), stored(&camera, 30.0)];
        let lo = camera.view_depth_from_ndc_depth(depth[1]);
        let hi = camera.view_depth_from_ndc_depth(depth[2]);
        let near_slice = |first_slice_depth| DepthSlicing::LogWithNearSlice { first_slice_depth };
        for (first, kept) in [
            (5.0, true),
            (1.0, false),
            (50.0, false),
            (lo * (1.0 - DEPTH_TOLERANCE), false),
            (hi * (1.0 + DEPTH_TOLERANCE), false),
        ] {
            let grid = ClusterGrid::new(UVec3::new(4, 4, 8), near_slice(first), 0.1, 100.0);
            let fitted = fitted_grid(&grid, &camera, &depth, &[]);
            let expected = if kept {
                near_slice(first)
            } else {
                DepthSlicing::Log
            };
            assert_eq!(fitted.slicing(), expected, "first slice edge {first}");
            assert_holds_every_drawn_depth(&fitted, &camera, &depth);
        }
    }

    /// A blended box's nearest corner drawn at a pixel on the screen's left or right edge, at a
    /// field of view near 180°: the corner lies hundreds of units to the side at a depth of a
    /// few, and the GPU's f32 rounding of its depth grows with that distance. Its fragment's
    /// depth — exact, and as an f32 vertex transform like the shader's computes it — must lie in
    /// the fitted range and in a marked cluster, also a hair from a slice edge. With the box's depths in f32 and bands relative
    /// to depth only, 7 of 20,000 such corners read an unmarked cluster and 3,435 lay nearer
    /// than the closed fitted grid (179.5°, 4000 × 100; audit).
    #[test]
    fn blended_fragments_seen_almost_side_on_stay_in_the_fitted_and_marked_clusters() {
        use myriad_scene::glam::{DVec3, Mat4};
        for (fov, w, h, corners) in [(179.5, 4000, 100, 1500), (179.9, 1920, 1080, 150)] {
            let camera = Camera::new(
                Vec3::new(3.0, 1.5, -2.0),
                Vec3::new(4.0, -1.4, -3.4),
                Vec3::Y,
                fov,
                w,
                h,
                0.1,
                1000.0,
            );
            let grid = ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, 0.1, 1000.0);
            let world_from_view = camera.view_rotation_f64().transpose();
            let forward = world_from_view * DVec3::NEG_Z;
            let eye = camera.position.as_dvec3();
            let (tx, ty) = camera.tan_half_fov_f64();
            // What the vertex shader multiplies camera-relative positions by.
            let clip_from_rel = camera.clip_from_view() * Mat4::from_mat3(camera.view_rotation());
            // Two opaque pixels, at depths 1 and 50, or none: the box alone sets the range.
            let mut opaque = vec![0.0f32; (w * h) as usize];
            opaque[0] = stored(&camera, 1.0);
            opaque[1] = stored(&camera, 50.0);
            let empty = vec![0.0f32; (w * h) as usize];
            // The slice edges of the grid fitted to the opaque pixels, which the boxes (1.5 to
            // 41 deep) do not widen: the corners are put within 1e-4 of them.
            let edges: Vec<f64> = {
                let fitted = fitted_grid(&grid, &camera, &opaque, &[]);
                (1..24)
                    .map(|k| fitted.slice_start_depth(k) as f64)
                    .collect()
            };
            let mut state = 11u64;
            let mut next = || {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64
            };
            let (mut outside_fitted, mut unmarked) = (0, 0);
            for n in 0..corners {
                let on_edges = n % 4 != 0;
                let depth = if on_edges { &opaque } else { &empty };
                let px = if n % 2 == 0 { n % 3 } else { w - 1 - n % 3 };
                let py = (next() * h as f64) as u32 % h;
                let (nx, ny) = (
                    2.0 * (px as f64 + 0.5) / w as f64 - 1.0,
                    1.0 - 2.0 * (py as f64 + 0.5) / h as f64,
                );
                let d = if on_edges {
                    let edge = edges[(next() * edges.len() as f64) as usize % edges.len()];
                    edge * (1.0 + 2e-4 * (next() - 0.5))
                } else {
                    1.5 * (40.0f64 / 1.5).powf(next())
                };
                let corner = eye + world_from_view * DVec3::new(nx * tx * d, ny * ty * d, -d);
                let corner32 = corner.as_vec3();
                // The box reaches away from the camera from that corner.
                let (mut min, mut max) = (corner32, corner32);
                for axis in 0..3 {
                    if forward[axis] >= 0.0 {
                        max[axis] = (corner[axis] + 0.01 * d) as f32;
                    } else {
                        min[axis] = (corner[axis] - 0.01 * d) as f32;
                    }
                }
                let b = Aabb { min, max };
                let fitted = fitted_grid(&grid, &camera, depth, &[b]);
                let mut mask = ActiveClusters::new(&fitted);
                mark_active(&mut mask, &fitted, &camera, depth, &[b]);
                let exact = -camera.view_from_world_point_f64(corner32.as_dvec3()).z;
                let exact = stored(&camera, exact as f32);
                let clip = clip_from_rel * Vec4::from((corner32 - camera.position, 1.0));
                for stored_depth in [exact, clip.z / clip.w] {
                    let v = camera.view_depth_from_ndc_depth(stored_depth);
                    if fitted.outer_slices() == OuterSlices::Closed
                        && !(v >= fitted.near() && v <= fitted.far())
                    {
                        outside_fitted += 1;
                    }
                    if !mask.is_active(fitted.cluster_of_pixel(px, py, v, w, h)) {
                        unmarked += 1;
                    }
                }
            }
            assert_eq!(
                (outside_fitted, unmarked),
                (0, 0),
                "{fov}°, {w} × {h}: fragments outside the fitted range, in unmarked clusters"
            );
        }
    }

    /// The tile of an NDC coordinate, computed from the camera's projection matrix.
    fn tile_of_ndc(t: f32, n: u32) -> u32 {
        ((t * n as f32) as u32).min(n - 1)
    }

    #[test]
    fn a_blended_box_marks_its_screen_box_with_a_tile_of_margin_and_no_more() {
        let camera = camera();
        let grid = ClusterGrid::new(UVec3::new(16, 12, 16), DepthSlicing::Log, 0.1, 100.0);
        // From 7 to 17 deep, right of and below the centre, its corners well inside tiles and
        // slices (edges at 4.87, 7.50, 11.5, 17.8).
        let b = aabb([2.0, -1.5, -17.0], [3.0, -0.5, -7.0]);
        let mut mask = ActiveClusters::new(&grid);
        mark_active(&mut mask, &grid, &camera, &[0.0; 64 * 48], &[b]);
        let clip_from_world = camera.clip_from_world();
        let (mut x, mut y) = (
            [f32::INFINITY, f32::NEG_INFINITY],
            [f32::INFINITY, f32::NEG_INFINITY],
        );
        for corner in b.corners() {
            let clip = clip_from_world * Vec4::from((corner, 1.0));
            let (nx, ny) = (clip.x / clip.w, clip.y / clip.w);
            x = [x[0].min(nx), x[1].max(nx)];
            y = [y[0].min(ny), y[1].max(ny)];
        }
        let dims = grid.dims();
        let i = [
            tile_of_ndc((x[0] + 1.0) / 2.0, dims.x) - 1,
            tile_of_ndc((x[1] + 1.0) / 2.0, dims.x) + 1,
        ];
        let j = [
            tile_of_ndc((1.0 - y[1]) / 2.0, dims.y) - 1,
            tile_of_ndc((1.0 - y[0]) / 2.0, dims.y) + 1,
        ];
        let k = [grid.slice_of_depth(7.0), grid.slice_of_depth(17.0)];
        assert_eq!((i, j, k), ([8, 13], [5, 9], [9, 11]), "the box as set up");
        for c in 0..grid.cluster_count() as u32 {
            let p = grid.cluster_coords(c);
            let inside = (i[0]..=i[1]).contains(&p.x)
                && (j[0]..=j[1]).contains(&p.y)
                && (k[0]..=k[1]).contains(&p.z);
            assert_eq!(mask.is_active(c), inside, "cluster {p}");
        }
    }

    #[test]
    fn a_blended_box_face_on_a_slice_edge_marks_both_sides_of_it() {
        let camera = camera();
        let grid = ClusterGrid::new(UVec3::new(16, 12, 16), DepthSlicing::Log, 0.1, 100.0);
        let (front, back) = (grid.slice_start_depth(10), grid.slice_start_depth(12));
        let b = aabb([-0.5, -0.5, -back], [0.5, 0.5, -front]);
        let mut mask = ActiveClusters::new(&grid);
        mark_active(&mut mask, &grid, &camera, &[0.0; 64 * 48], &[b]);
        // The centre tile: slice 12 holds the back face, slice 9 the GPU's rounding of the front.
        let (ci, cj) = (grid.tile_x_of_pixel(32, 64), grid.tile_y_of_pixel(24, 48));
        let marked: Vec<u32> = (0..16)
            .filter(|&k| mask.is_active(grid.cluster_id(ci, cj, k)))
            .collect();
        assert_eq!(marked, [9, 10, 11, 12]);
    }

    #[test]
    fn blended_boxes_mark_nothing_wholly_behind_or_beyond_and_everything_they_touch() {
        let camera = camera();
        let grid = ClusterGrid::new(UVec3::new(16, 12, 16), DepthSlicing::Log, 0.1, 100.0);
        let dims = grid.dims();
        let background = vec![0.0; 64 * 48];
        let marked = |b: Aabb| {
            let mut mask = ActiveClusters::new(&grid);
            mark_active(&mut mask, &grid, &camera, &background, &[b]);
            mask
        };
        let every_tile_of_slices = |mask: &ActiveClusters, first: u32, last: u32| {
            (first..=last).all(|k| {
                (0..dims.y).all(|j| (0..dims.x).all(|i| mask.is_active(grid.cluster_id(i, j, k))))
            })
        };
        // Wholly behind the camera, wholly beyond the far plane: never seen.
        assert_eq!(
            marked(aabb([-1.0, -1.0, 1.0], [1.0, 1.0, 2.0])).active_count(),
            0
        );
        assert_eq!(
            marked(aabb([-1.0, -1.0, -300.0], [1.0, 1.0, -200.0])).active_count(),
            0
        );
        // Around the camera, 5 deep: it covers the whole screen from the near plane on.
        let around = marked(aabb([-1.0, -1.0, -5.0], [1.0, 1.0, 1.0]));
        assert!(every_tile_of_slices(&around, 0, grid.slice_of_depth(5.0)));
        // Behind the camera up to the near plane exactly: its face on the near plane is drawn.
        let at_near = marked(aabb([-1.0, -1.0, -camera.near], [1.0, 1.0, 1.0]));
        assert!(every_tile_of_slices(&at_near, 0, 0));
        // From the far plane exactly on: its face on the far plane is in the last slice.
        let at_far = marked(aabb([-1.0, -1.0, -200.0], [1.0, 1.0, -camera.far]));
        let (ci, cj) = (grid.tile_x_of_pixel(32, 64), grid.tile_y_of_pixel(24, 48));
        assert!(at_far.is_active(grid.cluster_id(ci, cj, dims.z - 1)));
    }

    /// One row of pixels, one tile each, in a row-by-row walk that reuses the previous pixel's
    /// slices while the depth stays in their run: each pixel gets the slices of its own depth,
    /// exactly, whichever pixel came before it, on either side of a band's end.
    #[test]
    fn each_pixel_marks_its_own_slices_whatever_the_pixel_before_it() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 8, 1, 0.1, 100.0);
        let grid = ClusterGrid::new(UVec3::new(8, 1, 16), DepthSlicing::Log, 0.1, 100.0);
        let edges = SliceEdgesNdc::new(&grid, &camera);
        let k = 10;
        let edge = grid.slice_start_depth(k);
        let inside_before = (grid.slice_start_depth(k - 1) * edge).sqrt();
        let depth = [
            stored(&camera, edge),          // On the edge: both sides.
            stored(&camera, inside_before), // Well inside slice k − 1.
            stored(&camera, inside_before),
            -edges.below[k as usize], // Where the edge's band starts: both sides.
            -edges.above[k as usize], // Where it ends: slice k only.
            0.0,
            0.0,
            0.0,
        ];
        let mut mask = ActiveClusters::new(&grid);
        mark_active(&mut mask, &grid, &camera, &depth, &[]);
        let slices: Vec<Vec<u32>> = (0..8)
            .map(|i| {
                (0..16)
                    .filter(|&z| mask.is_active(grid.cluster_id(i, 0, z)))
                    .collect()
            })
            .collect();
        let (both, before, after) = (vec![k - 1, k], vec![k - 1], vec![k]);
        assert_eq!(
            slices,
            [
                both.clone(),
                before.clone(),
                before,
                both,
                after,
                vec![],
                vec![],
                vec![]
            ]
        );
    }
}
