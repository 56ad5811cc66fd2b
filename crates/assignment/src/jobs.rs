//! One task's share of a frame: lights `begin..end` → spans of clusters.
//!
//! A task walks its lights in blocks of [`BLOCK`] and runs the phases as SoA passes over each
//! block, so every pass is a tight loop over a few columns:
//! 0. **view**: reject invalid lights (counted), bring the rest to view space camera-relative, swap a
//!    spot light for its bounding sphere, pad the radius;
//! 1. **z phase** → depth band and slices; 2. **x phase** → tile columns; 3. **y phase** → rows
//!    (binary searches of the plane sets, see `geometry.rs`);
//! 4. **emit**: the box's rows as spans (`binary`), the refined rows (`refined`), each row cut by the
//!    cone test for spot lights, or each candidate cluster checked by the f64 oracle (`exact`).

use crate::append::Span;
use crate::geometry::{self, ClusterBox};
use crate::{LightInput, Method};
use glam::{DVec3, Mat3, Vec3, Vec4};
use myriad_cluster_math::oracle::{self, Cell, SpotVolume};
use myriad_cluster_math::{Camera, ClusterGrid, PlaneSets, SpotCone, spot_bounding_sphere};

/// Lights per SoA block inside a task.
pub(crate) const BLOCK: usize = 256;

/// What the tasks of one frame share, read-only.
pub(crate) struct FrameContext<'a> {
    pub method: Method,
    pub lights: LightInput<'a>,
    pub camera: &'a Camera,
    pub grid: &'a ClusterGrid,
    pub planes: &'a PlaneSets,
    pub view_from_world: Mat3,
    /// View-space bounding spheres of the clusters (for spot cone tests); empty without spots.
    pub cluster_spheres: &'a [Vec4],
}

/// One task's private output.
#[derive(Default)]
pub(crate) struct TaskOutput {
    pub spans: Vec<Span>,
    pub rejected: u32,
    pub culled: u32,
}

/// Spot data kept for the emit pass.
#[derive(Clone, Copy, Default)]
struct SpotView {
    apex: Vec3,
    axis: Vec3,
    cos_sin: (f32, f32),
    range: f32,
    active: bool,
}

/// Whether a light's input values can be assigned at all.
#[inline]
fn is_valid(p: Vec3, r: f32) -> bool {
    p.is_finite() && r.is_finite() && r > 0.0
}

/// Runs lights `begin..end` through all phases into `out` (cleared first).
pub(crate) fn run_task(ctx: &FrameContext<'_>, begin: usize, end: usize, out: &mut TaskOutput) {
    out.spans.clear();
    out.rejected = 0;
    out.culled = 0;
    let eye = ctx.camera.position;
    let mut cx = [0f32; BLOCK];
    let mut cy = [0f32; BLOCK];
    let mut dc = [0f32; BLOCK];
    let mut rad = [0f32; BLOCK];
    let mut live = [false; BLOCK];
    let mut spots = [SpotView::default(); BLOCK];
    let mut boxes = [None::<ClusterBox>; BLOCK];
    let l = &ctx.lights;
    let mut block_start = begin;
    while block_start < end {
        let n = (end - block_start).min(BLOCK);
        // Phase 0: view transform (camera-relative) and validity.
        for b in 0..n {
            let g = block_start + b;
            let p = Vec3::new(l.x[g], l.y[g], l.z[g]);
            let r = l.radius[g];
            live[b] = is_valid(p, r);
            let v = ctx.view_from_world * (p - eye);
            let (mut centre, mut radius) = (v, r);
            spots[b].active = false;
            if let Some(s) = &l.spot {
                let axis = ctx.view_from_world * Vec3::new(s.dir_x[g], s.dir_y[g], s.dir_z[g]);
                let angle = s.angle[g];
                let axis = axis.normalize_or_zero();
                if angle.is_finite() && angle > 0.0 && angle <= std::f32::consts::FRAC_PI_2 && axis != Vec3::ZERO {
                    let (c, rr) = spot_bounding_sphere(v, r, SpotCone { direction: axis, angle });
                    centre = c;
                    radius = rr;
                    spots[b] = SpotView {
                        apex: v,
                        axis,
                        cos_sin: (angle.cos(), angle.sin()),
                        range: r,
                        active: true,
                    };
                }
            }
            cx[b] = centre.x;
            cy[b] = centre.y;
            dc[b] = -centre.z;
            rad[b] = geometry::pad_radius(centre.x, centre.y, -centre.z, radius);
            if ctx.method == Method::Exact {
                // Candidates only: the oracle decides, so a generous margin costs nothing in accuracy.
                rad[b] = rad[b] * 1.001 + 1e-3 * (centre.abs().max_element() + radius);
            }
        }
        // Phases 1–3: z, then x and y (which use the z phase's depth band).
        for b in 0..n {
            boxes[b] = if live[b] {
                geometry::cluster_box(cx[b], cy[b], dc[b], rad[b], ctx.planes)
            } else {
                None
            };
        }
        // Phase 4: emit spans.
        for b in 0..n {
            if !live[b] {
                out.rejected += 1;
                continue;
            }
            let Some(bx) = boxes[b] else {
                out.culled += 1;
                continue;
            };
            let light = (block_start + b) as u32;
            emit(ctx, light, cx[b], cy[b], dc[b], rad[b], &bx, &spots[b], &mut out.spans);
        }
        block_start += n;
    }
}

#[allow(clippy::too_many_arguments)] // The per-light columns of one block, passed by value.
#[inline]
fn emit(
    ctx: &FrameContext<'_>,
    light: u32,
    cx: f32,
    cy: f32,
    dc: f32,
    r: f32,
    bx: &ClusterBox,
    spot: &SpotView,
    spans: &mut Vec<Span>,
) {
    let grid = ctx.grid;
    let mut push_row = |j: u32, k: u32, i0: u32, i1: u32| {
        let first = grid.cluster_id(i0, j, k);
        if spot.active {
            push_filtered(spans, light, first, i1 - i0 + 1, |c| {
                let s = ctx.cluster_spheres[c as usize];
                geometry::cone_may_touch_sphere(spot.apex, spot.axis, spot.cos_sin, spot.range, s.truncate(), s.w)
            });
        } else {
            spans.push(Span {
                light,
                first,
                len: i1 - i0 + 1,
            });
        }
    };
    match ctx.method {
        Method::Binary => {
            for k in bx.z.k0..=bx.z.k1 {
                for j in bx.j0..=bx.j1 {
                    push_row(j, k, bx.i0, bx.i1);
                }
            }
        }
        Method::Refined => {
            for k in bx.z.k0..=bx.z.k1 {
                geometry::refine_slice(cx, cy, dc, r, bx, k, ctx.planes, |j, i0, i1| push_row(j, k, i0, i1));
            }
        }
        Method::Exact => emit_exact(ctx, light, bx, spans),
        Method::Linear => unreachable!("the linear method has its own serial path"),
    }
}

/// Pushes the maximal runs of `first .. first + len` whose clusters pass `keep`.
#[inline]
fn push_filtered(spans: &mut Vec<Span>, light: u32, first: u32, len: u32, mut keep: impl FnMut(u32) -> bool) {
    let mut run_start = None;
    for c in first..first + len {
        match (keep(c), run_start) {
            (true, None) => run_start = Some(c),
            (false, Some(s)) => {
                spans.push(Span { light, first: s, len: c - s });
                run_start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = run_start {
        spans.push(Span {
            light,
            first: s,
            len: first + len - s,
        });
    }
}

/// The `exact` method: every cluster of a generously padded box, tested with the f64 oracle.
fn emit_exact(ctx: &FrameContext<'_>, light: u32, bx: &ClusterBox, spans: &mut Vec<Span>) {
    let g = light as usize;
    let l = &ctx.lights;
    let world = DVec3::new(l.x[g] as f64, l.y[g] as f64, l.z[g] as f64);
    let centre = ctx.camera.view_from_world_point_f64(world);
    let range = l.radius[g] as f64;
    let spot = l.spot.as_ref().and_then(|s| {
        let angle = s.angle[g] as f64;
        let axis = ctx.camera.view_rotation_f64()
            * DVec3::new(s.dir_x[g] as f64, s.dir_y[g] as f64, s.dir_z[g] as f64);
        let axis = axis.normalize_or_zero();
        (angle.is_finite() && angle > 0.0 && angle <= std::f64::consts::FRAC_PI_2 && axis != DVec3::ZERO).then_some(
            SpotVolume {
                apex: centre,
                direction: axis,
                range,
                angle,
            },
        )
    });
    let grid = ctx.grid;
    let camera = ctx.camera;
    for k in bx.z.k0..=bx.z.k1 {
        for j in bx.j0..=bx.j1 {
            let first = grid.cluster_id(bx.i0, j, k);
            push_filtered(spans, light, first, bx.i1 - bx.i0 + 1, |c| {
                let i = bx.i0 + (c - first);
                let cell = Cell::of_cluster(camera, grid, i, j, k);
                match &spot {
                    Some(s) => oracle::spot_intersects_cell(s, &cell),
                    None => oracle::sphere_intersects_cell(centre, range, &cell),
                }
            });
        }
    }
}

/// View-space bounding spheres of every cluster (centre, radius), padded like light radii.
pub(crate) fn cluster_bounding_spheres(camera: &Camera, grid: &ClusterGrid, out: &mut Vec<Vec4>) {
    out.clear();
    let d = grid.dims;
    for k in 0..d.z {
        for j in 0..d.y {
            for i in 0..d.x {
                let cell = Cell::of_cluster(camera, grid, i, j, k);
                let corners = cell.corners();
                let centre = corners.iter().fold(DVec3::ZERO, |a, &c| a + c) / 8.0;
                let radius = corners.iter().map(|c| c.distance(centre)).fold(0.0, f64::max);
                let c = centre.as_vec3();
                let r = geometry::pad_radius(c.x, c.y, -c.z, radius as f32);
                out.push(c.extend(r));
            }
        }
    }
}
