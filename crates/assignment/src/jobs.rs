//! One task's share of a frame: lights `begin..end` → spans of clusters.
//!
//! A task walks its lights in blocks of [`BLOCK`] (or [`LARGE_BLOCK`], for tasks of many lights)
//! and runs the phases as SoA passes over each block, so every pass is a tight loop over a few
//! columns:
//! 0. **view and cull**: bring the lights to view space camera-relative, pad the radius and test
//!    the frustum's six planes in one pass (an invalid light fails it too, and is counted as
//!    rejected); a spot light swaps its range sphere for the spot's bounding sphere; the survivors
//!    are compacted into the block's columns;
//! 1. **z phase** → depth band and slices; 2. **x phase** → tile columns; 3. **y phase** → rows
//!    (binary searches of the plane sets, see `geometry.rs`);
//! 4. **emit**: the box's rows as spans (`binary`), the refined rows (`refined`), each row cut by the
//!    cone test for spot lights, or each candidate cluster checked by the f64 oracle (`exact`).
//!    The emit loop is compiled once per frame-constant pair (method; plain = no spots, no mask)
//!    for `binary` and `refined`, so neither is tested per light ([`emit_block`]).

use crate::active::ActiveView;
use crate::append::Bucket;
use crate::cone::{ConeColumn, LightCone, TileCone};
use crate::geometry::{self, ClusterBox, ZRange};
use crate::phases::{BLOCK, Block, LARGE_BLOCK, LARGE_BLOCK_TASK};
use crate::search::FramePlanes;
use crate::{LightInput, Method};
use crossbeam::utils::CachePadded;
use glam::{DVec3, Mat3, Vec2, Vec3, Vec4};
use myriad_cluster_math::oracle::{Cell, OracleView};
use myriad_cluster_math::{Camera, ClusterGrid, PlaneSets, SpotCone, spot_bounding_sphere};
use std::sync::atomic::{AtomicU64, Ordering};

/// What the tasks of one frame share, read-only.
pub(crate) struct FrameContext<'a> {
    pub method: Method,
    pub lights: LightInput<'a>,
    pub camera: &'a Camera,
    pub grid: &'a ClusterGrid,
    pub planes: FramePlanes<'a>,
    pub view_from_world: Mat3,
    /// View-space bounding spheres of the clusters (for spot cone tests); empty without spots.
    pub cluster_spheres: &'a [Vec4],
    /// The `cone` method's tile cones, row by row; empty when the grid has too many tiles to
    /// keep them (each is then computed where it is needed) or for the other methods.
    pub tile_cones: &'a [TileCone],
    /// The camera's `tan` of the half fields of view, in f64 (for tile cones made on the fly).
    pub tan_half_fov: (f64, f64),
    /// The f64 view transform and projection of the `exact` method, computed once per frame
    /// (`None` for the other methods, which never need them).
    pub exact: Option<ExactFrame>,
    /// The active-cluster mask, if any: spans without an active cluster are dropped as emitted.
    pub active: Option<ActiveView<'a>>,
    /// Number of parts (groups of consecutive slices) the spans are bucketed by.
    pub parts: usize,
    /// log₂ of the slices per part: slice `k` is in part `k >> slice_shift`.
    pub slice_shift: u32,
    /// The cheap early cull's six planes.
    pub cull: FrustumCull,
    /// The same cull with the camera's own near and far plane, when the camera sees nearer or
    /// farther than the grid's depth edges: lights it keeps that lie wholly past the grid's far
    /// or before its near are counted ([`crate::AssignStats::beyond_far`],
    /// [`crate::AssignStats::before_near`]; `cull` keeps them too where the grid's outer slices
    /// are open). `None` otherwise, and nothing is computed.
    pub outside_cull: Option<FrustumCull>,
}

/// The frustum's six planes as plain numbers, for the early cull: copied into each task so the
/// cull loop reads no slice (an indexed `z_depths` in the loop kept it scalar, 3× slower on
/// `sphere`, where nine lights in ten are culled).
#[derive(Clone, Copy)]
pub(crate) struct FrustumCull {
    /// The left, right, top and bottom planes (x-plane 0 and X, y-plane 0 and Y), each as the two
    /// components of its unit normal (pointing right or up) that are not zero: `(x, z)` for the
    /// x-planes, `(y, z)` for the y-planes. The third is exactly zero ([`PlaneSets`] normalises
    /// `(1, 0, slope)` and `(0, 1, slope)`), so leaving it out changes no test and saves the cull
    /// loop a multiply and an add per plane.
    pub sides: [Vec2; 4],
    /// Where the first slice starts and the last one ends (the sets' first and last depth: the
    /// grid's near and far, or beyond them where its outer slices are open).
    pub near: f32,
    pub far: f32,
}

impl FrustumCull {
    /// The grid's outer planes (its first and last x- and y-planes) and the sets' first and last
    /// depth (beyond the grid's range where its outer slices are open).
    pub fn of_grid(sets: &PlaneSets, grid: &ClusterGrid) -> Self {
        let d = grid.dims();
        let (left, right) = (sets.x_plane_normal(0), sets.x_plane_normal(d.x as usize));
        let (top, bottom) = (sets.y_plane_normal(0), sets.y_plane_normal(d.y as usize));
        debug_assert!([left.y, right.y, top.x, bottom.x] == [0.0; 4]);
        Self {
            sides: [
                Vec2::new(left.x, left.z),
                Vec2::new(right.x, right.z),
                Vec2::new(top.y, top.z),
                Vec2::new(bottom.y, bottom.z),
            ],
            near: sets.z_depths[0],
            far: sets.z_depths[sets.z_depths.len() - 1],
        }
    }

    /// This cull with its near and far planes at `near` and `far` instead of the grid's.
    pub fn with_depths(self, near: f32, far: f32) -> Self {
        Self { near, far, ..self }
    }

    /// Whether the padded sphere may touch the frustum: the six plane tests of the paper's
    /// "light is inside outer frustum", which are necessary conditions for any sphere.
    #[inline(always)]
    fn may_touch(&self, cx: f32, cy: f32, depth: f32, r: f32) -> bool {
        let [left, right, top, bottom] = self.sides;
        let (x, y) = (Vec2::new(cx, -depth), Vec2::new(cy, -depth));
        (left.dot(x) >= -r)
            & (right.dot(x) <= r)
            & (top.dot(y) <= r)
            & (bottom.dot(y) >= -r)
            & (depth + r >= self.near)
            & (depth - r <= self.far)
    }
}

impl FrameContext<'_> {
    /// The whole grid as one box: what an overflowed light is given (see `run_blocks`).
    fn whole_grid_box(&self) -> ClusterBox {
        let d = self.grid.dims();
        let z = &self.planes.sets.z_depths;
        ClusterBox {
            z: ZRange {
                da: z[0],
                db: z[z.len() - 1],
                k0: 0,
                k1: d.z - 1,
            },
            i0: 0,
            i1: d.x - 1,
            j0: 0,
            j1: d.y - 1,
        }
    }
}

/// What the `exact` method needs of the camera, in f64, and its running pair count.
pub(crate) struct ExactFrame {
    pub view: OracleView,
    pub tan_half_fov: (f64, f64),
    /// Pairs the tasks have written so far, all together.
    pub pairs: AtomicU64,
    /// The frame's pair budget: once `pairs` passes it, the tasks skip their remaining lights
    /// and the frame is retried on a coarser grid. The other methods find their total after
    /// the tasks, for almost nothing; `exact` tests every cluster of a box with the f64 oracle,
    /// and finishing a grid the budget refuses took 156 s for 5000 large lights on a
    /// 128×72×64 grid under a budget of 10⁶ pairs (`refined`: 0.03 s), and past 11 minutes for
    /// 100k (stress audit).
    pub budget: u64,
}

impl ExactFrame {
    pub fn new(camera: &Camera, budget: u64) -> Self {
        Self {
            view: OracleView::new(camera),
            tan_half_fov: camera.tan_half_fov_f64(),
            pairs: AtomicU64::new(0),
            budget,
        }
    }

    /// Whether the pairs written so far already pass the budget.
    pub fn over_budget(&self) -> bool {
        self.pairs.load(Ordering::Relaxed) > self.budget
    }
}

/// One task's private output: its spans, bucketed by *part* (a group of consecutive depth
/// slices, see `append.rs`), so that each part can later be counted and filled on its own.
#[derive(Default)]
pub(crate) struct TaskOutput {
    /// One per part, each on cache lines of its own: every span pushed writes its bucket's
    /// length and pair count, and two tasks' buckets must not share a line (see `assigner.rs`).
    pub buckets: Vec<CachePadded<Bucket>>,
    /// Scratch of the refinement: a squared gap per tile column, a room per tile row.
    gaps: Vec<f32>,
    /// Scratch of the `cone` method: one row of the box, column by column.
    cone_columns: Vec<ConeColumn>,
    pub rejected: u32,
    pub culled: u32,
    /// Lights `outside_cull` keeps that lie wholly past the grid's far (counted when it is set).
    pub beyond_far: u32,
    /// Lights `outside_cull` keeps that lie wholly before the grid's near.
    pub before_near: u32,
    /// The farthest depth (padded sphere's far side) of the lights `outside_cull` keeps; 0 for
    /// none.
    pub reach: f32,
}

impl TaskOutput {
    /// Empties the buckets and counts, and sizes the scratch for `ctx`'s grid and method.
    fn reset(&mut self, ctx: &FrameContext<'_>) {
        if self.buckets.len() < ctx.parts {
            self.buckets.resize_with(ctx.parts, CachePadded::default);
        }
        for bucket in &mut self.buckets[..ctx.parts] {
            bucket.clear();
        }
        self.rejected = 0;
        self.culled = 0;
        self.beyond_far = 0;
        self.before_near = 0;
        self.reach = 0.0;
        self.gaps
            .resize(geometry::refine_scratch_len(ctx.grid.dims()), 0.0);
        if ctx.method == Method::Cone {
            self.cone_columns
                .resize(ctx.grid.dims().x as usize, ConeColumn::default());
        }
    }
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

impl SpotView {
    /// No spot: what a plain frame's emit is given.
    const NONE: Self = Self {
        apex: Vec3::ZERO,
        axis: Vec3::ZERO,
        cos_sin: (1.0, 0.0),
        range: 0.0,
        active: false,
    };
}

/// Stack a task in blocks of [`LARGE_BLOCK`] must find free when it starts: its SoA columns sit on
/// the running thread's stack. Frames of such tasks (every method, points and spots, the thread's
/// whole stack counted) overflowed threads of 144 KiB and ran on 160 KiB in release builds;
/// unoptimised, whose frames keep every temporary, they overflowed 256 KiB and ran on 320.
/// (Keyed on `debug_assertions`, the usual stand-in for "unoptimised": a build optimised with
/// debug assertions on asks for more than it needs; one unoptimised without them, for too little.)
pub(crate) const LARGE_TASK_STACK: usize = if cfg!(debug_assertions) {
    512 << 10
} else {
    256 << 10
};

/// Stack a task in blocks of [`BLOCK`] must find free when it starts: measured as for
/// [`LARGE_TASK_STACK`], it overflowed 48 KiB and ran on 64 KiB (release), overflowed 96 KiB
/// and ran on 128 KiB (unoptimised).
const SMALL_TASK_STACK: usize = if cfg!(debug_assertions) {
    192 << 10
} else {
    96 << 10
};

/// The stack `f` runs on where the running thread's is shorter than it needs: mapped for it and
/// unmapped after.
const GROWN_STACK: usize = 1 << 20;

/// Runs `f` on this thread's stack if at least `need` bytes of it are left, else on a stack of
/// [`GROWN_STACK`] mapped for it (`stacker::grow`): an engine's job threads, or a rayon pool
/// built with a small `stack_size`, would otherwise overflow and abort the process. A grow costs
/// a map, the faults of the pages `f` touches and an unmap (65–100 µs measured for a large
/// task, by an audit on a loaded 2-vCPU host), so the caller of a frame grows once for the
/// whole frame (`Assigner::assign_active`) and only a pool worker short of stack grows per task.
///
/// Where `stacker` cannot tell how much is left (platforms whose thread bounds it does not read:
/// Android, iOS, wasm) `f` runs in place, as it always did, rather than paying a grow for every
/// task on every thread. The first call on a thread reads its stack bounds
/// (`pthread_getattr_np` on Linux, which allocates through libc and, on the main thread, reads
/// `/proc/self/maps`): once per thread. A fiber whose stack lies below its thread's counts as
/// short and grows; one above it is not protected.
pub(crate) fn with_stack<R>(need: usize, f: impl FnOnce() -> R) -> R {
    match stacker::remaining_stack() {
        Some(left) if left < need => stacker::grow(GROWN_STACK, f),
        _ => f(),
    }
}

/// Runs lights `begin..end` through all phases into `out` (cleared first).
///
/// A task of at least [`LARGE_BLOCK_TASK`] lights walks them in blocks of [`LARGE_BLOCK`], a
/// smaller one in blocks of [`BLOCK`]. Each width is a function of its own (both inlined into one
/// function made a single 46 KB body, with each width's hot loops placed among the other's).
///
/// Its blocks live on the stack (heap columns kept between frames measured slower, see
/// docs/measured.md), ~150 KiB of it for large blocks: it runs [`with_stack`] of what it needs.
/// Threads with the usual stacks (2 MiB for Rust's spawned threads and rayon's workers, 8 MiB for
/// a main thread) never grow: the check is a thread-local read and a compare.
pub(crate) fn run_task(ctx: &FrameContext<'_>, begin: usize, end: usize, out: &mut TaskOutput) {
    let large = end - begin >= LARGE_BLOCK_TASK;
    let need = if large {
        LARGE_TASK_STACK
    } else {
        SMALL_TASK_STACK
    };
    with_stack(need, || {
        crate::profiling::profile_span!("assign task");
        out.reset(ctx);
        if large {
            run_large_blocks(ctx, begin, end, out);
        } else {
            run_small_blocks(ctx, begin, end, out);
        }
    });
}

/// [`run_blocks`] in blocks of [`BLOCK`] lights.
///
/// Compiled twice, as is [`run_large_blocks`]: for AVX2 + FMA (8-wide passes; picked at run time
/// when the CPU has them) and for the baseline target. The two differ only in vector width: Rust
/// never contracts `a·b + c` into a fused multiply-add, and this code calls no `mul_add`, so
/// both round alike and give the same boxes (the AVX2 builds hold no `vfmadd`, read in the
/// release binary's assembly on 2026-11-30). A unit test runs the two side by side
/// (`both_block_widths_and_both_builds_give_the_same_task_output`).
#[multiversion::multiversion(targets("x86_64+avx+avx2+fma"))]
fn run_small_blocks(ctx: &FrameContext<'_>, begin: usize, end: usize, out: &mut TaskOutput) {
    run_blocks::<BLOCK>(ctx, begin, end, out);
}

/// [`run_blocks`] in blocks of [`LARGE_BLOCK`] lights (built as [`run_small_blocks`] is).
#[multiversion::multiversion(targets("x86_64+avx+avx2+fma"))]
fn run_large_blocks(ctx: &FrameContext<'_>, begin: usize, end: usize, out: &mut TaskOutput) {
    run_blocks::<LARGE_BLOCK>(ctx, begin, end, out);
}

/// The phases over lights `begin..end`, `B` lights a block.
#[inline(always)] // Into each build of the two callers.
fn run_blocks<const B: usize>(
    ctx: &FrameContext<'_>,
    begin: usize,
    end: usize,
    out: &mut TaskOutput,
) {
    let eye = ctx.camera.position;
    let mut block = Block::<B>::new();
    // Pre-cull columns of the current block, indexed by position in the block.
    let (mut vx, mut vy, mut vd, mut vr) = ([0f32; B], [0f32; B], [0f32; B], [0f32; B]);
    let (mut ok, mut inside, mut overflowed) = ([false; B], [false; B], [false; B]);
    let mut spots = [SpotView::default(); B];
    let l = &ctx.lights;
    let m = ctx.view_from_world;
    let cull = ctx.cull;
    let mut block_start = begin;
    while block_start < end {
        let n = (end - block_start).min(B);
        // Each phase of the block is a span of its own: fine-grained (a few µs each), and nothing
        // at all without the `tracy` feature.
        crate::profiling::profile_span!("phase: view and cull", view_and_cull);
        // Phase 0a: camera-relative view transform, padding and the early frustum cull, branch-free
        // over the block's columns so that it vectorises. Validity costs nothing here: the padded
        // radius sums |cx| + |cy| + |dc| + r, and each of cx, cy, dc takes every input coordinate
        // (a non-finite one makes them all NaN or infinite, even times a zero matrix entry), so
        // `r > 0` with a finite padded radius holds exactly when every input is finite, `r > 0`
        // and the view-space sphere fits f32. The rare others are sorted out below (phase 0c).
        let (xs, ys, zs) = (
            &l.x[block_start..][..n],
            &l.y[block_start..][..n],
            &l.z[block_start..][..n],
        );
        let rs = &l.radius[block_start..][..n];
        // Counted in u32: a usize sum halves the vector width.
        let mut sound = 0u32;
        for b in 0..n {
            let (px, py, pz, r) = (xs[b] - eye.x, ys[b] - eye.y, zs[b] - eye.z, rs[b]);
            let x = m.x_axis.x * px + m.y_axis.x * py + m.z_axis.x * pz;
            let y = m.x_axis.y * px + m.y_axis.y * py + m.z_axis.y * pz;
            let z = m.x_axis.z * px + m.y_axis.z * py + m.z_axis.z * pz;
            let padded = geometry::pad_radius(x, y, -z, r);
            vx[b] = x;
            vy[b] = y;
            vd[b] = -z;
            vr[b] = padded;
            let fine = (r > 0.0) & padded.is_finite();
            ok[b] = fine;
            inside[b] = fine & cull.may_touch(x, y, -z, padded);
            sound += fine as u32;
        }
        // Phase 0b: spot lights trade their range sphere for the spot volume's bounding sphere,
        // and are culled again with it. One whose range sphere overflowed stays with phase 0c
        // even if its bounding sphere fits: conservative, and only near `f32::MAX`.
        if let Some(s) = &l.spot {
            for b in 0..n {
                let g = block_start + b;
                let angle = s.angle[g];
                let axis = geometry::spot_view_axis(m, s.dir_x[g], s.dir_y[g], s.dir_z[g]);
                spots[b].active = false;
                // Strictly below f32's π/2, which is a hair *above* the real π/2: the f64 oracle
                // (and `emit_exact`) treat that angle as "wider than 90°", i.e. as the whole ball.
                if angle > 0.0 && angle < std::f32::consts::FRAC_PI_2 && axis != Vec3::ZERO {
                    let apex = Vec3::new(vx[b], vy[b], -vd[b]);
                    let range = l.radius[g];
                    let (c, r) = spot_bounding_sphere(
                        apex,
                        range,
                        SpotCone {
                            direction: axis,
                            angle,
                        },
                    );
                    (vx[b], vy[b], vd[b]) = (c.x, c.y, -c.z);
                    vr[b] = geometry::pad_radius(c.x, c.y, -c.z, r);
                    spots[b] = SpotView {
                        apex,
                        axis,
                        cos_sin: (angle.cos(), angle.sin()),
                        range,
                        active: true,
                    };
                }
            }
            sound = 0;
            for b in 0..n {
                let fine = ok[b] & vr[b].is_finite();
                ok[b] = fine;
                inside[b] = fine & cull.may_touch(vx[b], vy[b], vd[b], vr[b]);
                sound += fine as u32;
            }
        }
        // Where the camera sees past the grid's depth edges, which lights the grid's near or far
        // plane alone culls, and how far the lights in view reach: a pass of its own,
        // branch-free, only in such frames.
        if let Some(wide) = &ctx.outside_cull {
            let edges = (ctx.grid.near(), ctx.grid.far());
            count_outside_grid(wide, edges, &ok[..n], [&vx, &vy, &vd, &vr], n, out);
        }
        // Phase 0c, only for a block with a light that failed the test above: an invalid light is
        // rejected (counted); a valid one whose view-space sphere overflowed f32 (coordinates and
        // radius near `f32::MAX`) cannot go through the f32 phases: it is culled in f64 or, if it
        // may touch the frustum, given the whole grid (the `exact` method still tests each
        // cluster in f64). Rare and conservative; it once counted such lights as culled, a miss.
        let mut rejected = 0;
        let sound = sound as usize;
        let any_overflowed = sound < n && {
            overflowed[..n].fill(false);
            for b in (0..n).filter(|&b| !ok[b]) {
                let g = block_start + b;
                let r = l.radius[g];
                let valid = l.x[g].is_finite()
                    & l.y[g].is_finite()
                    & l.z[g].is_finite()
                    & r.is_finite()
                    & (r > 0.0);
                if !valid {
                    rejected += 1;
                    continue;
                }
                overflowed[b] = true;
                let world = DVec3::new(l.x[g].into(), l.y[g].into(), l.z[g].into());
                let z = &ctx.planes.sets.z_depths;
                inside[b] = geometry::may_touch_frustum_f64(ctx.camera, z, world, r.into());
                // Finite stand-ins for the f32 phases, whose box is then ignored.
                (vx[b], vy[b], vd[b], vr[b]) = (0.0, 0.0, 1.0, 1.0);
                spots[b].active = false;
            }
            rejected < n - sound
        };
        let mut alive = 0;
        for (word, flags) in inside[..n].chunks(64).enumerate() {
            let mut mask = flags
                .iter()
                .enumerate()
                .fold(0u64, |m, (i, &f)| m | ((f as u64) << i));
            let (from, len) = (word * 64, flags.len());
            // A word whose lights all survive (most of them, when the lights fill the view) is
            // copied column by column, vectorised, instead of light by light. cachegrind, a
            // frame on one thread, lists byte-identical: `uniform` 100k `binary` 29.1 → 27.7 M
            // instructions, `refined` 36.7 → 35.2 M; `sphere` 100k (nine in ten culled) +0.8%.
            if mask == u64::MAX >> (64 - len) {
                block.cx[alive..][..len].copy_from_slice(&vx[from..][..len]);
                block.cy[alive..][..len].copy_from_slice(&vy[from..][..len]);
                block.dc[alive..][..len].copy_from_slice(&vd[from..][..len]);
                block.rad[alive..][..len].copy_from_slice(&vr[from..][..len]);
                block.alive[alive..][..len].fill(true);
                for (i, s) in block.source[alive..][..len].iter_mut().enumerate() {
                    *s = (from + i) as u32;
                }
                alive += len;
                continue;
            }
            while mask != 0 {
                let b = from + mask.trailing_zeros() as usize;
                mask &= mask - 1;
                block.cx[alive] = vx[b];
                block.cy[alive] = vy[b];
                block.dc[alive] = vd[b];
                block.rad[alive] = vr[b];
                block.alive[alive] = true;
                block.source[alive] = b as u32;
                alive += 1;
            }
        }
        if any_overflowed {
            // Their stand-in spheres must not give them a box: the emit below sees them as dead
            // and only then asks whether they overflowed, off the path of every other light.
            for b in 0..alive {
                block.alive[b] &= !overflowed[block.source[b] as usize];
            }
        }
        out.rejected += rejected as u32;
        out.culled += (n - rejected - alive) as u32;
        if ctx.method == Method::Exact {
            // Candidates only: the oracle decides, so a wider box costs nothing in accuracy.
            for b in 0..alive {
                let extent =
                    block.cx[b].abs() + block.cy[b].abs() + block.dc[b].abs() + block.rad[b];
                block.rad[b] = block.rad[b] * 1.001 + 1e-3 * extent;
            }
        }
        crate::profiling::end_span!(view_and_cull);
        // Phases 1–3: z, then x and y (which use the z phase's depth band).
        block.run_phases(alive, &ctx.planes);
        // Phase 4: emit spans. The method and whether the frame is plain (no spot columns, no
        // mask) are the same for every light of a frame, so the common frames get a copy of the
        // emit with both as constants (see `emit_block`).
        // A macro, not a closure: LLVM once left such a closure out of line, outside the
        // multiversioned task and so without AVX2, and `uniform` 100k ran 12% more instructions
        // (cachegrind) after an unrelated change elsewhere in this function.
        macro_rules! emit_all {
            ($method:expr, $plain:expr) => {
                emit_block(
                    ctx,
                    $method,
                    $plain,
                    &block,
                    alive,
                    block_start,
                    any_overflowed,
                    &overflowed,
                    &spots,
                    out,
                )
            };
        }
        let plain = l.spot.is_none() && ctx.active.is_none();
        match (ctx.method, plain) {
            (Method::Binary, true) => emit_all!(Method::Binary, true),
            (Method::Binary, false) => emit_all!(Method::Binary, false),
            (Method::Refined, true) => emit_all!(Method::Refined, true),
            (Method::Refined, false) => emit_all!(Method::Refined, false),
            (other, _) => emit_all!(other, false),
        }
        block_start += n;
    }
}

/// The lights of a block that `wide` (the cull with the camera's near and far planes) keeps and
/// that lie wholly past `grid_far` or wholly before `grid_near` (the lights a closed grid's cull
/// drops), and how far the ones it keeps reach, into `out`. A function of its
/// own, never inlined: written in `run_blocks`, the frames that never run it (a grid out to the
/// camera's far) ran 3.5% slower on `uniform` 100k (`myriad bench --threads 1`, interleaved).
/// Where it runs it costs 0–5% of a `uniform` 100k frame on one thread (`cargo bench --bench
/// assignment -- far_edge`, two runs). It runs as well in frames that only see nearer than the
/// grid (a fitted near), the same loop at the same cost a light; those were not timed apart.
#[inline(never)]
fn count_outside_grid<const B: usize>(
    wide: &FrustumCull,
    (grid_near, grid_far): (f32, f32),
    ok: &[bool],
    [vx, vy, vd, vr]: [&[f32; B]; 4],
    n: usize,
    out: &mut TaskOutput,
) {
    // The reach as the bits of a float that is never negative (a kept light's far side is past
    // the near plane): their order is the floats' own, and an integer maximum vectorises where
    // `f32::max` (NaN-aware) does not.
    let (mut beyond, mut before, mut reach) = (0u32, 0u32, out.reach.to_bits());
    let spheres = vx[..n]
        .iter()
        .zip(&vy[..n])
        .zip(vd[..n].iter().zip(&vr[..n]));
    for (&ok, ((&x, &y), (&d, &r))) in ok.iter().zip(spheres) {
        let seen = ok & wide.may_touch(x, y, d, r);
        beyond += (seen & (d - r > grid_far)) as u32;
        before += (seen & (d + r < grid_near)) as u32;
        reach = reach.max(if seen { (d + r).to_bits() } else { 0 });
    }
    out.beyond_far += beyond;
    out.before_near += before;
    out.reach = f32::from_bits(reach);
}

/// Phase 4 of one block: each live light's spans.
///
/// `method` is the frame's and `plain` says that the frame has no spot columns and no
/// active-cluster mask (so no light is a spot and every cluster counts). Both are constants in the
/// copies `run_blocks` makes for `binary` and `refined`: the method's `match` and the per-row spot
/// and mask tests then fold away, and the per-light loop keeps fewer values live. cachegrind, a
/// frame on one thread, lists byte-identical: `uniform` 100k `binary` 34.5 → 29.1 M instructions
/// (−16%), `refined` 41.0 → 36.7 M (−11%); `sphere` 100k 4.30 → 3.90 M and 4.31 → 3.95 M;
/// `paper` 1000 0.962 → 0.911 M and 1.629 → 1.596 M. The method alone as a constant gave
/// `uniform` 100k 31.2 and 39.4 M; the same split into a function with the method a variable,
/// nothing.
#[allow(clippy::too_many_arguments)] // One block's columns and the frame's two constants.
#[inline(always)] // A copy per (method, plain) pair, each a constant in it.
fn emit_block<const B: usize>(
    ctx: &FrameContext<'_>,
    method: Method,
    plain: bool,
    block: &Block<B>,
    alive: usize,
    block_start: usize,
    any_overflowed: bool,
    overflowed: &[bool; B],
    spots: &[SpotView; B],
    out: &mut TaskOutput,
) {
    crate::profiling::profile_span!("phase: emit");
    for b in 0..alive {
        let source = block.source[b] as usize;
        let light = (block_start + source) as u32;
        if !block.alive[b] {
            if any_overflowed && overflowed[source] {
                emit_overflowed(ctx, light, &spots[source], out);
            } else {
                out.culled += 1;
            }
            continue;
        }
        let bx = block.cluster_box(b);
        let (cx, cy, dc, r) = (block.cx[b], block.cy[b], block.dc[b], block.rad[b]);
        // A plain frame has no spots: not indexing `spots` spares each light a bounds check
        // (cachegrind, a frame on one thread: `uniform` 100k `binary` 27.7 → 27.4 M).
        let spot = if plain {
            &SpotView::NONE
        } else {
            &spots[source]
        };
        emit(
            ctx,
            method,
            plain,
            light,
            cx,
            cy,
            dc,
            r,
            &bx,
            spot,
            &mut out.buckets[..ctx.parts],
            &mut out.gaps,
            &mut out.cone_columns,
        );
    }
}

/// A light whose view-space sphere overflowed f32 (see phase 0c): the whole grid, unrefined (an
/// infinite radius keeps `refined` from cutting it). Out of line: rare, and it keeps the hot
/// loop small.
#[cold]
#[inline(never)]
fn emit_overflowed(ctx: &FrameContext<'_>, light: u32, spot: &SpotView, out: &mut TaskOutput) {
    let whole = ctx.whole_grid_box();
    let buckets = &mut out.buckets[..ctx.parts];
    emit(
        ctx,
        ctx.method,
        false,
        light,
        0.0,
        0.0,
        0.0,
        f32::INFINITY,
        &whole,
        spot,
        buckets,
        &mut out.gaps,
        &mut out.cone_columns,
    );
}

/// `method` is the frame's; `plain` says the frame has no spots and no mask (see
/// [`emit_block`]): the caller guarantees `!spot.active` and `ctx.active.is_none()` then.
#[allow(clippy::too_many_arguments)] // The per-light columns of one block, passed by value.
#[inline(always)] // Into the AVX2 + FMA builds of `run_blocks`.
fn emit(
    ctx: &FrameContext<'_>,
    method: Method,
    plain: bool,
    light: u32,
    cx: f32,
    cy: f32,
    dc: f32,
    r: f32,
    bx: &ClusterBox,
    spot: &SpotView,
    buckets: &mut [CachePadded<Bucket>],
    gaps: &mut [f32],
    cone_columns: &mut [ConeColumn],
) {
    debug_assert!(!plain || (!spot.active && ctx.active.is_none()));
    let grid = ctx.grid;
    let push_row = |bucket: &mut Bucket, first: u32, len: u32| {
        if !plain && spot.active {
            push_spot_row(ctx, spot, bucket, light, first, len);
        } else {
            bucket.push(
                light,
                first,
                len,
                if plain { None } else { ctx.active.as_ref() },
            );
        }
    };
    // Only boxes at least two tiles wide and two tall are refined: that is where the corner
    // clusters a sphere misses are. A box one tile wide or tall can only lose a row or column in
    // the slices at the ends of its depth band, rarely; skipping those costs a little accuracy
    // (`uniform` 100k: false positives 2.6% → 3.3%; `paper` 1000: 7.5% → 8.3%) for 14% less time
    // (`myriad bench`, 1 thread).
    let refine = method == Method::Refined && bx.i1 > bx.i0 && bx.j1 > bx.j0 && r.is_finite();
    let width = grid.dims().x;
    // An infinite radius (an overflowed light) keeps the whole box, as for `refined`.
    let cone = method == Method::Cone && r.is_finite();
    match method {
        _ if cone => emit_cone(ctx, cx, cy, dc, r, bx, buckets, cone_columns, push_row),
        Method::Binary | Method::Refined | Method::Cone if !refine => {
            let (len, rows) = (bx.i1 - bx.i0 + 1, bx.j1 - bx.j0 + 1);
            for k in bx.z.k0..=bx.z.k1 {
                let bucket = &mut buckets[(k >> ctx.slice_shift) as usize];
                let first = grid.cluster_id(bx.i0, bx.j0, k);
                // A point light without a mask pushes its whole box without per-row checks
                // (`paper` 1000 `binary` serial 53 → 47 µs; the same for the refined rows, and
                // this test hoisted out of the `match`, measured slower).
                if !plain && (spot.active || ctx.active.is_some()) {
                    for r in 0..rows {
                        push_row(bucket, first + r * width, len);
                    }
                } else {
                    bucket.push_rows(light, first, len, rows, width);
                }
            }
        }
        // `refine` holds only for `refined`.
        Method::Binary | Method::Refined | Method::Cone => {
            let mut refiner = geometry::BoxRefiner::new(bx, &ctx.planes, gaps);
            let z = &ctx.planes.sets.z_depths[bx.z.k0 as usize..=bx.z.k1 as usize + 1];
            for (k, edges) in (bx.z.k0..).zip(z.windows(2)) {
                let bucket = &mut buckets[(k >> ctx.slice_shift) as usize];
                let slice_first = grid.cluster_id(0, 0, k);
                let whole = refiner.slice(cx, cy, dc, r, (edges[0], edges[1]), |j, i0, i1| {
                    push_row(bucket, slice_first + j * width + i0, i1 - i0 + 1)
                });
                // A slice kept whole goes out as the unrefined box's does: one span of rows, but
                // only from three rows up (a span's rows loop mispredicts where boxes are one or
                // two rows tall). `myriad bench --threads 1`, interleaved builds: `paper` 1000
                // 65 → 61 µs (all rows as one span: the same), `uniform` 100k unchanged (all rows
                // as one span: 4% slower); two threads 35.8 → 34.0 µs and −2%. (The same seven
                // lines as the unrefined box's: as one closure for both, `refined` ran 6% more
                // instructions, cachegrind.)
                if whole {
                    let (len, rows) = (bx.i1 - bx.i0 + 1, bx.j1 - bx.j0 + 1);
                    let first = grid.cluster_id(bx.i0, bx.j0, k);
                    if rows < 3 || (!plain && (spot.active || ctx.active.is_some())) {
                        for r in 0..rows {
                            push_row(bucket, first + r * width, len);
                        }
                    } else {
                        bucket.push_rows(light, first, len, rows, width);
                    }
                }
            }
        }
        Method::Exact => {
            let exact = ctx
                .exact
                .as_ref()
                .expect("the exact method's frame has its f64 view");
            emit_exact(ctx, exact, light, bx, buckets)
        }
        Method::Linear => unreachable!("the linear method has its own serial path"),
    }
}

/// The `cone` method's box (`cone.rs`): per row of the box, each tile's depth range from its
/// cone test, then the slices it reaches, then per slice the maximal runs of tiles that keep it.
#[allow(clippy::too_many_arguments)] // One light's columns, passed by value.
#[inline(never)]
fn emit_cone(
    ctx: &FrameContext<'_>,
    cx: f32,
    cy: f32,
    dc: f32,
    r: f32,
    bx: &ClusterBox,
    buckets: &mut [CachePadded<Bucket>],
    columns: &mut [ConeColumn],
    mut push_row: impl FnMut(&mut Bucket, u32, u32),
) {
    let grid = ctx.grid;
    let dims = grid.dims();
    let light = LightCone::new(cx, cy, dc, r);
    let z = &ctx.planes.sets.z_depths;
    let (k0, k1) = (bx.z.k0, bx.z.k1);
    let width = bx.i1 - bx.i0 + 1;
    let columns = &mut columns[..width as usize];
    for j in bx.j0..=bx.j1 {
        // Every tile's depth range first: arithmetic with no branch on its outcome, so the
        // tiles' square roots overlap.
        for (column, i) in columns.iter_mut().zip(bx.i0..=bx.i1) {
            // Read in place: a copy of the cached cone to the stack, read back in wider loads
            // than it was stored with, stalled store forwarding on every tile.
            (column.lo, column.hi) = match ctx.tile_cones.get((j * dims.x + i) as usize) {
                Some(tile) => light.depth_bounds(tile),
                None => light.depth_bounds(&TileCone::of_tile(ctx.tan_half_fov, dims, i, j)),
            };
        }
        // The box's slices `[k0, k1]` that each range reaches (a closed slice touches it when
        // its far edge is ≥ lo and its near edge ≤ hi), walked in from both ends: most tiles
        // keep them all, and walks beat searches over a box's few slices.
        // The slices every column keeps, `[all_from, all_to]`, are pushed as whole rows.
        let (mut any, mut all_from, mut all_to) = (false, k0, k1);
        for column in columns.iter_mut() {
            // `first .. end`, exclusive, so that an empty range cannot wrap below 0.
            let (mut first, mut end) = (k0, k1 + 1);
            if column.lo <= column.hi {
                while first < end && f64::from(z[first as usize + 1]) < column.lo {
                    first += 1;
                }
                while end > first && f64::from(z[end as usize - 1]) > column.hi {
                    end -= 1;
                }
            } else {
                end = first;
            }
            (column.first, column.last) = if first < end {
                (first, end - 1)
            } else {
                (1, 0)
            };
            any |= first < end;
            // An empty column's `(1, 0)` empties `[all_from, all_to]`.
            all_from = all_from.max(column.first);
            all_to = all_to.min(column.last);
        }
        if !any {
            continue;
        }
        for k in k0..=k1 {
            let bucket = &mut buckets[(k >> ctx.slice_shift) as usize];
            let row_first = grid.cluster_id(bx.i0, j, k);
            if all_from <= k && k <= all_to {
                push_row(bucket, row_first, width);
                continue;
            }
            let keeps_k = |c: u32| {
                let column = &columns[(c - row_first) as usize];
                column.first <= k && k <= column.last
            };
            for_each_run(row_first, width, keeps_k, |s, n| push_row(bucket, s, n));
        }
    }
}

/// A spot light's row, cut to the clusters its cone may touch (kept out of line: the point-light
/// path through `emit` stays small enough to inline).
#[inline(never)]
fn push_spot_row(
    ctx: &FrameContext<'_>,
    spot: &SpotView,
    bucket: &mut Bucket,
    light: u32,
    first: u32,
    len: u32,
) {
    push_filtered(ctx, bucket, light, first, len, |c| {
        let s = ctx.cluster_spheres[c as usize];
        // A cluster whose corners lie past f32's range (a wide view under a far plane near
        // `f32::MAX`) has no finite bounding sphere: it is kept, as the cone cannot be tested.
        !s.is_finite()
            || geometry::cone_may_touch_sphere(
                spot.apex,
                spot.axis,
                spot.cos_sin,
                spot.range,
                s.truncate(),
                s.w,
            )
    });
}

/// Pushes the maximal runs of `first .. first + len` whose clusters pass `keep`.
#[inline]
fn push_filtered(
    ctx: &FrameContext<'_>,
    bucket: &mut Bucket,
    light: u32,
    first: u32,
    len: u32,
    keep: impl FnMut(u32) -> bool,
) {
    for_each_run(first, len, keep, |first, len| {
        bucket.push(light, first, len, ctx.active.as_ref());
    });
}

/// Calls `run(start, len)` for each maximal run of `first .. first + len` whose clusters pass
/// `keep`.
#[inline]
fn for_each_run(
    first: u32,
    len: u32,
    mut keep: impl FnMut(u32) -> bool,
    mut run: impl FnMut(u32, u32),
) {
    let mut run_start = None;
    for c in first..first + len {
        match (keep(c), run_start) {
            (true, None) => run_start = Some(c),
            (false, Some(s)) => {
                run(s, c - s);
                run_start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = run_start {
        run(s, first + len - s);
    }
}

/// The `exact` method: every cluster of a generously padded box, tested with the f64 oracle.
fn emit_exact(
    ctx: &FrameContext<'_>,
    exact: &ExactFrame,
    light: u32,
    bx: &ClusterBox,
    buckets: &mut [CachePadded<Bucket>],
) {
    if exact.over_budget() {
        return; // The frame is retried on a coarser grid.
    }
    let g = light as usize;
    let l = &ctx.lights;
    let spot = l.spot.as_ref().map(|s| {
        let direction = Vec3::new(s.dir_x[g], s.dir_y[g], s.dir_z[g]);
        (direction, s.angle[g])
    });
    let position = Vec3::new(l.x[g], l.y[g], l.z[g]);
    // Phase 0 passed only valid lights.
    let Some(volume) = exact.view.light(position, l.radius[g], spot) else {
        return;
    };
    let grid = ctx.grid;
    let z = &ctx.planes.sets.z_depths;
    let mut added = 0;
    for k in bx.z.k0..=bx.z.k1 {
        let depths = [z[k as usize], z[k as usize + 1]];
        for j in bx.j0..=bx.j1 {
            let first = grid.cluster_id(bx.i0, j, k);
            let bucket = &mut buckets[(k >> ctx.slice_shift) as usize];
            let before = bucket.pairs;
            push_filtered(ctx, bucket, light, first, bx.i1 - bx.i0 + 1, |c| {
                let i = bx.i0 + (c - first);
                let (x, y) = (grid.dims().x, grid.dims().y);
                let cell = Cell::of_tile(exact.tan_half_fov, x, y, i, j, depths);
                volume.intersects_cell(&cell)
            });
            added += bucket.pairs - before;
        }
    }
    exact.pairs.fetch_add(added, Ordering::Relaxed);
}

/// View-space bounding spheres of every cluster (centre, radius), padded like light radii.
pub(crate) fn cluster_bounding_spheres(camera: &Camera, grid: &ClusterGrid, out: &mut Vec<Vec4>) {
    out.clear();
    let d = grid.dims();
    for k in 0..d.z {
        for j in 0..d.y {
            for i in 0..d.x {
                let cell = Cell::of_cluster(camera, grid, i, j, k);
                let corners = cell.corners();
                let centre = corners.iter().fold(DVec3::ZERO, |a, &c| a + c) / 8.0;
                let radius = corners
                    .iter()
                    .map(|c| c.distance(centre))
                    .fold(0.0, f64::max);
                let c = centre.as_vec3();
                let r = geometry::pad_radius(c.x, c.y, -c.z, radius as f32);
                out.push(c.extend(r));
            }
        }
    }
}

#[cfg(test)]
mod tests;
