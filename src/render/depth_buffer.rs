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

use myriad_assignment::ActiveClusters;
use myriad_scene::{Aabb, Camera, ClusterGrid, DepthSlicing};
use rayon::prelude::*;

/// Relative widening of the fitted range and of the slice-edge tolerance.
const DEPTH_TOLERANCE: f32 = 1e-4;
const EDGE_TOLERANCE: f32 = 1e-5;

/// View-depth extent of a world box seen by `camera` (corners), or `None` when it lies wholly
/// behind the near plane or beyond the far plane.
fn box_depths(camera: &Camera, b: &Aabb) -> Option<(f32, f32, [f32; 4])> {
    let (tan_x, tan_y) = (camera.tan_half_fov().x, camera.tan_half_fov().y);
    let (mut dmin, mut dmax) = (f32::INFINITY, f32::NEG_INFINITY);
    let mut ndc = [
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::INFINITY,
        f32::NEG_INFINITY,
    ];
    let mut in_front = true;
    for corner in b.corners() {
        let v = camera.view_from_world_point(corner);
        let d = -v.z;
        dmin = dmin.min(d);
        dmax = dmax.max(d);
        if d <= camera.near {
            in_front = false;
        } else {
            let (x, y) = (v.x / (d * tan_x), v.y / (d * tan_y));
            ndc = [ndc[0].min(x), ndc[1].max(x), ndc[2].min(y), ndc[3].max(y)];
        }
    }
    if dmax < camera.near || dmin > camera.far {
        return None;
    }
    if !in_front {
        ndc = [-1.0, 1.0, -1.0, 1.0];
    }
    Some((dmin.max(camera.near), dmax.min(camera.far), ndc))
}

/// The scene grid over the depth range that holds every covered pixel and every blended draw.
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
    let near = (lo * (1.0 - DEPTH_TOLERANCE)).max(grid.near());
    let mut far = (hi * (1.0 + DEPTH_TOLERANCE)).min(grid.far());
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
    ClusterGrid::new(grid.dims(), slicing, near, far)
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
/// 1e-5 relative) and of every blended draw's screen box.
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
    use myriad_scene::glam::{UVec3, Vec3};

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
}
