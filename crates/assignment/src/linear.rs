//! The paper's Algorithm 1 (Örtegren, "Implicit Clustered Deferred Shading"), single-threaded: the
//! baseline every other method is measured against.
//!
//! Per light: if the sphere is inside the outer frustum, step through the x-planes from the left
//! until the sphere reaches left of a plane (that gives the first tile), keep stepping until the
//! sphere lies entirely left of a plane (the last tile); the same for y and z. The light is then
//! pushed onto each covered cluster's own temporary list (the paper's "clusters store their own
//! light indices temporarily"), and the lists are concatenated into CSR at the end.
//!
//! The sphere-plane distance `n·c ≥ −r` is exact and monotone along a plane set only for spheres
//! entirely in front of the eye; a sphere reaching the eye plane gets the full x and y range (the
//! paper's algorithm is silent on this case, and conservative is the only correct choice).

use crate::geometry::{self, ZRange};
use crate::{ActiveClusters, LightInput, LightLists};
use glam::Vec3;
use myriad_cluster_math::{Camera, ClusterGrid, PlaneSets, SpotCone, spot_bounding_sphere};

/// Per-cluster temporary lists, reused across frames.
#[derive(Default)]
pub(crate) struct LinearScratch {
    lists: Vec<Vec<u32>>,
    x_normals: Vec<Vec3>,
    y_normals: Vec<Vec3>,
}

/// What one run counted, as [`crate::AssignStats`] reports it.
pub(crate) struct LinearCounts {
    pub rejected: u32,
    pub culled: u32,
    pub beyond_far: u32,
    pub before_near: u32,
    pub reach: Option<f32>,
}

/// Counts of one run, or `Err(pairs)` without writing `out` when the pairs exceed `budget`. Under an `active` mask only the active clusters' lists are kept, and
/// only their pairs count against the budget.
#[allow(clippy::too_many_arguments)] // One frame's inputs, scratch and output.
pub(crate) fn assign_linear(
    scratch: &mut LinearScratch,
    lights: &LightInput<'_>,
    camera: &Camera,
    grid: &ClusterGrid,
    planes: &PlaneSets,
    active: Option<&ActiveClusters>,
    budget: u64,
    out: &mut LightLists,
) -> Result<LinearCounts, u64> {
    let clusters = grid.cluster_count();
    let view_from_world = camera.view_rotation();
    // Only ever grown: shrinking to a smaller grid would drop the per-cluster lists' buffers,
    // and the next larger grid (or the first try of a frame under a pair budget) would
    // allocate them all again.
    if scratch.lists.len() < clusters {
        scratch.lists.resize_with(clusters, Vec::new);
    }
    for list in &mut scratch.lists[..clusters] {
        list.clear();
    }
    scratch.x_normals.clear();
    scratch
        .x_normals
        .extend((0..planes.x_slopes.len()).map(|i| planes.x_plane_normal(i)));
    scratch.y_normals.clear();
    scratch
        .y_normals
        .extend((0..planes.y_slopes.len()).map(|j| planes.y_plane_normal(j)));
    let (xn, yn) = (&scratch.x_normals, &scratch.y_normals);
    let (nx, ny) = (grid.dims().x, grid.dims().y);
    let (mut rejected, mut culled) = (0, 0);
    // Where the camera sees past the grid's depth edges: lights its near or far plane alone
    // culls, and the lights' reach (see `AssignStats::beyond_far`), with the same padded spheres
    // as the tasks' cull.
    let camera_depths = crate::assigner::sees_outside(camera, grid);
    let (mut beyond_far, mut before_near, mut reach) = (0, 0, 0f32);
    for g in 0..lights.len() {
        let p = Vec3::new(lights.x[g], lights.y[g], lights.z[g]);
        let r = lights.radius[g];
        if !(p.is_finite() && r.is_finite() && r > 0.0) {
            rejected += 1;
            continue;
        }
        let mut c = view_from_world * (p - camera.position);
        let mut radius = r;
        if let Some(s) = &lights.spot {
            let axis =
                geometry::spot_view_axis(view_from_world, s.dir_x[g], s.dir_y[g], s.dir_z[g]);
            let angle = s.angle[g];
            if angle.is_finite() && angle > 0.0 && axis != Vec3::ZERO {
                (c, radius) = spot_bounding_sphere(
                    c,
                    r,
                    SpotCone {
                        direction: axis,
                        angle,
                    },
                );
            }
        }
        let dc = -c.z;
        let r = geometry::pad_radius(c.x, c.y, dc, radius);
        if !(c.is_finite() && r.is_finite()) {
            // The view-space sphere overflowed f32 (coordinates and radius near `f32::MAX`):
            // culled in f64, or given the whole grid, as the other methods do.
            let world = p.as_dvec3();
            if geometry::may_touch_frustum_f64(
                camera,
                &planes.z_depths,
                world,
                lights.radius[g].into(),
            ) {
                for list in &mut scratch.lists[..clusters] {
                    list.push(g as u32);
                }
            } else {
                culled += 1;
            }
            continue;
        }
        // Outer frustum: all six planes.
        let sideways = xn[0].dot(c) < -r
            || xn[nx as usize].dot(c) > r
            || yn[0].dot(c) > r
            || yn[ny as usize].dot(c) < -r;
        let z = linear_z(dc, r, &planes.z_depths).filter(|_| !sideways);
        if let Some((near, far)) = camera_depths
            && !sideways
            && dc + r >= near
            && dc - r <= far
        {
            reach = reach.max(dc + r);
            beyond_far += u32::from(dc - r > grid.far());
            before_near += u32::from(dc + r < grid.near());
        }
        let Some(z) = z else {
            culled += 1;
            continue;
        };
        let (i0, i1, j0, j1) = if dc - r > 0.0 {
            // x: first tile whose right plane the sphere reaches left of, then step on.
            let (i0, i1) = step_planes(nx, |i| xn[i].dot(c) <= r, |i| xn[i].dot(c) >= -r);
            // y rows run top → bottom; the normals point up, so "below plane" is n·c ≤ r.
            let (j0, j1) = step_planes(ny, |j| yn[j].dot(c) >= -r, |j| yn[j].dot(c) <= r);
            (i0, i1, j0, j1)
        } else {
            // The sphere reaches the eye's depth, where every side plane meets: the paper's
            // stepping (monotonic tile by tile only in front of the eye) does not apply, so every
            // tile of its slices. Loose, never a miss; `binary` bounds such lights per side. The
            // padding grows with the distance, so a small light far to the side of a very wide
            // view lands here too (fov 179.99999°, a 0.05 light 10⁵ off axis: 1,440 pairs where
            // `binary` lists 5; hunt, 2026-11-30) — kept, as the paper's baseline.
            (0, nx - 1, 0, ny - 1)
        };
        if i0 > i1 || j0 > j1 {
            culled += 1;
            continue;
        }
        for k in z.k0..=z.k1 {
            for j in j0..=j1 {
                for i in i0..=i1 {
                    scratch.lists[grid.cluster_id(i, j, k) as usize].push(g as u32);
                }
            }
        }
    }
    // Under a mask, the inactive clusters' lists are emptied first, so only active pairs count
    // against the budget and reach the output. (Testing the mask per cluster in the loops below
    // made every unmasked `linear` frame 10% slower: `paper` 1000, 96 → 106 µs.)
    if let Some(a) = active {
        for (c, list) in scratch.lists[..clusters].iter_mut().enumerate() {
            if !a.is_active(c as u32) {
                list.clear();
            }
        }
    }
    let total: u64 = scratch.lists[..clusters]
        .iter()
        .map(|l| l.len() as u64)
        .sum();
    if total > budget {
        return Err(total);
    }
    out.reset(clusters);
    let mut at = 0u32;
    for (c, list) in scratch.lists[..clusters].iter().enumerate() {
        out.offsets[c] = at;
        out.counts[c] = list.len() as u32;
        at += list.len() as u32;
        out.indices.extend_from_slice(list);
    }
    Ok(LinearCounts {
        rejected,
        culled,
        beyond_far,
        before_near,
        reach: crate::assigner::sees_past(camera, grid).then_some(reach),
    })
}

/// Steps through planes 1..=n for the first tile `t` whose far plane `t + 1` satisfies
/// `reaches_before(t + 1)`, then on while the sphere still reaches past plane `t + 1`
/// (`reaches_after`). Returns `(first, last)`; `first > last` when the first tile found is
/// reached only from before. A sphere that reaches no tile's far plane gives `(n, n)`: callers
/// test the frustum first, which culls every such sphere, so that case is never asked (checking
/// it here cost `paper` 1000 1–3% more instructions).
fn step_planes(
    n: u32,
    reaches_before: impl Fn(usize) -> bool,
    reaches_after: impl Fn(usize) -> bool,
) -> (u32, u32) {
    let mut first = n;
    for t in 0..n {
        if reaches_before(t as usize + 1) {
            first = t;
            break;
        }
    }
    let mut last = first;
    while last + 1 < n && reaches_after(last as usize + 1) {
        last += 1;
    }
    if first < n && !reaches_after(first as usize) {
        return (1, 0);
    }
    (first, last)
}

/// z planes stepped from the near plane, as in the paper.
fn linear_z(dc: f32, r: f32, z: &[f32]) -> Option<ZRange> {
    let slices = z.len() as u32 - 1;
    let da = (dc - r).max(z[0]);
    let db = (dc + r).min(z[slices as usize]);
    if !(da <= db) {
        return None;
    }
    // The first slice whose far edge reaches `da` (a closed slice ending exactly at `da`, or one
    // of zero thickness there, touches the light too).
    let mut k0 = 0;
    while k0 + 1 < slices && z[k0 as usize + 1] < da {
        k0 += 1;
    }
    let mut k1 = k0;
    while k1 + 1 < slices && z[k1 as usize + 1] <= db {
        k1 += 1;
    }
    Some(ZRange { da, db, k0, k1 })
}
