//! The frame driver: plans the tasks, runs the phases in parallel, and owns every reusable buffer.

use crate::ActiveClusters;
use crate::append::{self, Parts};
use crate::cone::{self, TileCone};
use crate::fan_out::{self, FanOut};
use crate::jobs::{self, FrameContext, TaskOutput};
use crate::linear::{self, LinearScratch};
use crate::pacing::{Pacing, Parallelism};
use crate::profiling::profile_span;
use crate::search::FramePlanes;
use crate::{LightInput, LightLists};
use crossbeam::utils::CachePadded;
use glam::Vec4;
use myriad_cluster_math::{Camera, ClusterGrid, OuterSlices, PlaneSets};
use rayon::prelude::*;
use std::time::Instant;

/// Light assignment methods; all are conservative (never miss a light that touches a cluster).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Every candidate cluster tested with the exact f64 oracle: zero false positives, slow.
    ///
    /// The reference of pairs, not of pixels: its lists are the cells the light's exact volume
    /// touches, with no allowance for a renderer's f32 rounding. The renderer rebuilds a pixel's
    /// point within about 2e-7 of its distance of the pixel's cell (up to 1.7e-7 measured on
    /// llvmpipe, at pixel centres on tile planes), so a light that ends that close outside a
    /// cell can light the pixel under brute force and not with `exact`'s lists (5–8/255 at
    /// intensity 1e6, audit). The other methods pad every radius by
    /// [`myriad_cluster_math::RADIUS_PAD`] (4e-6 of the light's extent, 20–40 times that stray)
    /// and do not: render with them.
    Exact,
    /// The paper's Algorithm 1: planes stepped one by one, single-threaded, per-cluster lists.
    Linear,
    /// Binary search of the x-, y- and z-plane sets; the light's whole box of clusters.
    Binary,
    /// Binary's box tightened per slice and per row (sphere shrunk to the slab).
    Refined,
    /// Binary's box cut per tile by spherical-sliced cone tests (seed 004): a tile is kept when
    /// the ball's cone from the eye meets the tile's, and only in the slices the ball's
    /// distance range within the tile reaches (`cone.rs`).
    Cone,
}

impl Method {
    /// Every method, the reference first.
    pub const ALL: [Method; 5] = [
        Method::Exact,
        Method::Linear,
        Method::Binary,
        Method::Refined,
        Method::Cone,
    ];

    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Method::Exact => "exact",
            Method::Linear => "linear",
            Method::Binary => "binary",
            Method::Refined => "refined",
            Method::Cone => "cone",
        }
    }

    /// Parses [`Method::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// How the per-cluster lists are appended (see `append.rs`). Both give identical output.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum AppendStrategy {
    /// Spans bucketed by parts (groups of depth slices); per part, in parallel: counts as
    /// difference arrays, then, after one prefix sum, a fill into the part's own slice of the
    /// output. No shared counters, no atomics, no cache line written by two threads. The
    /// default: faster on every scene `benches/append.rs` measures.
    #[default]
    PartitionedByDepth,
    /// One shared counter per cluster, `fetch_add` in the count and the fill passes, then a sort
    /// of every list to make the order deterministic. Kept to measure against. Its frames called
    /// from outside the pool are always handed off ([`OutsideCalls::HandOff`]'s waits
    /// included): the caller-works path exists for the default append only.
    AtomicCounters,
}

/// How a parallel frame called from a thread outside any rayon pool (an engine's main thread)
/// runs. Calls from a pool's worker, or from a thread that joined its pool
/// (`ThreadPoolBuilder::use_current_thread`), always start their parallel regions on the spot.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OutsideCalls {
    /// The calling thread works on the frame's tasks and parts itself, alongside one helper job
    /// per other thread of the global pool, spawned as each region starts (`fan_out.rs`): the
    /// frame starts at once and the caller only waits for the helpers' last items, spinning. A
    /// helper no worker has started by the time the caller has done the rest is not waited for:
    /// with every worker busy on a long job of the engine's own, the frame runs wholly on the
    /// caller and returns. It costs small heap allocations: one per helper (rayon boxes a
    /// spawned job) and one per region with helpers (their shared control block), at most
    /// 2 × threads per frame, fewer where a region has fewer items to share, and rayon's
    /// injection queue takes one block per 63 jobs spawned into it (one more allocation in the
    /// frame that passes a multiple of 63). The default: the faster (`paper` 1000 on 2 vCPUs, criterion
    /// medians of the `targets` bench, three runs: `binary` 25.1–25.8 µs against 30.9–34.2 µs
    /// handed off, `refined` 38.7–39.8 against 44.2–50.1 µs; 21–23 and 36–44 µs on a worker).
    ///
    /// With [`AppendStrategy::PartitionedByDepth`] (the default append) only; with
    /// [`AppendStrategy::AtomicCounters`] the frame is handed off. Helpers no worker has started
    /// stay queued on the pool until one frees (each returns at once then): 100,000 frames while
    /// both workers of a 2-thread pool were held busy grew the process by 24 MB (audit).
    ///
    /// The caller runs tasks on its own stack, and a task of 2048 lights or more keeps blocks of
    /// about 150 KiB there (a smaller one about 60 KiB; twice that unoptimised). Where the calling
    /// thread has less than a frame needs left, the frame runs on a 1 MiB stack mapped for it
    /// (`stacker`; `jobs::with_stack`): one grow a frame, 65–100 µs measured (a pool worker
    /// short of stack grows per task). Threads of small stacks work (tested down to 32 KiB);
    /// Rust's spawned threads (2 MiB) never grow.
    #[default]
    Join,
    /// The whole frame moves onto a pool worker in one hand-off and the calling thread sleeps
    /// until it is done: two cross-thread wake-ups per frame, but nothing allocated per frame
    /// (only rayon's injection queue allocates, a block per 63 jobs injected by anyone: one
    /// per 63 frames here). For an engine that must keep off the allocator in steady state.
    ///
    /// It waits for a free worker, so a frame handed off while every worker of the global pool
    /// waits on the calling thread never starts: workers blocked on a lock the caller holds, or
    /// a global pool whose only thread is a member that is not inside rayon (a pool of one built
    /// with `use_current_thread` on another thread; the frame ran when that thread next yielded
    /// to rayon, audit). `Join` with the default append does not wait for such workers.
    HandOff,
}

/// What one assignment did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AssignStats {
    /// Lights in the input.
    pub lights: u32,
    /// Lights skipped because their position or radius was not finite, or the radius not positive.
    pub rejected: u32,
    /// Valid lights the frustum test rejected, or whose z, x and y searches then found no
    /// cluster range (a box the method's own bounds leave empty, so methods whose boxes differ
    /// may count differently). Not every light that reaches no cluster: one kept by
    /// those (conservative, padded) tests may still list nowhere, e.g. a spot whose cone misses
    /// every cluster its sphere touches, or a light only in inactive clusters; those count as
    /// [`visible`](Self::visible).
    pub culled: u32,
    /// Cluster–light pairs written.
    pub pairs: u64,
    /// Tasks the lights were split into (1 = one serial task).
    pub tasks: u32,
    /// Whether the tasks ran on the pool (called from outside any pool: on the calling thread
    /// beside helper jobs on the pool, [`OutsideCalls`]); `false`: one after another on the
    /// calling thread alone, as a small frame after idle does (see [`Assigner::assign`]). The
    /// lists are the same either way.
    pub parallel: bool,
    /// Dimensions of the grid the lists were built for: the requested grid's, unless the pair
    /// budget forced a coarser one (see [`Assigner::with_pair_budget`]).
    pub grid_dims: [u32; 3],
    /// How many times the grid was coarsened ([`coarser_grid`]) to fit the pair budget.
    pub coarsened: u32,
    /// The pairs exceed the budget even on a 1×1×1 grid; the lists were written anyway (one
    /// cluster holding every visible light), because no light is ever dropped.
    pub over_budget: bool,
    /// In a frame whose camera sees past the grid's far edge (`camera.far` beyond the grid's
    /// far, as with an engine's infinite projection and a finite grid): the lights in view that
    /// lie wholly past that edge. The renderer shades the pixels beyond the grid with its last
    /// slice's lights. Where the grid's outer slices are [`OuterSlices::Open`] (the default) these
    /// lights are listed there and nothing is missing; where they are [`OuterSlices::Closed`] they are
    /// culled (and counted in [`culled`](Self::culled)), and their light is missing from those
    /// pixels. 0 when the grid reaches the camera's far plane (nothing is computed then). A grid
    /// whose far is [`reach`](Self::reach) has none. (Lights whose view-space sphere overflows
    /// f32, near `f32::MAX`, are not counted.)
    pub beyond_far: u32,
    /// When the camera sees past the grid's far edge: the farthest view depth the lights in the
    /// camera's view reach (the far side of their padded sphere, a spot's bounding sphere), 0 when
    /// none is in view; the far of a grid that would have no light beyond it, for the next
    /// frame's grid (its slices then cut the lights' whole depth range, instead of one last
    /// slice holding every light past the grid; a [`OuterSlices::Closed`] grid that follows it
    /// misses a light that moves past it for one frame, counted in
    /// [`beyond_far`](Self::beyond_far)). Lights in view wholly before the grid's near count
    /// like any other, also where the grid is closed (a frame with only those in view gives a
    /// reach below the grid's near). `None` when the grid reaches the camera's far plane.
    pub reach: Option<f32>,
    /// In a frame whose camera sees nearer than the grid's near edge (`camera.near` below the
    /// grid's near, as with a range fitted to the depth buffer): the lights in view that lie
    /// wholly nearer than that edge, the near-side twin of [`beyond_far`](Self::beyond_far).
    /// Pixels nearer than the grid's near read its first slice. Where the grid's outer slices
    /// are [`OuterSlices::Open`] (the default) these lights are listed there and nothing is
    /// missing; where they are [`OuterSlices::Closed`] they are culled (and counted in
    /// [`culled`](Self::culled)), and their light is missing from any pixel nearer than the
    /// grid, which a range fitted to the depth buffer has none of. 0 when the grid starts at the
    /// camera's near plane (nothing is computed then). (Lights whose view-space sphere overflows
    /// f32 are not counted.)
    pub before_near: u32,
}

impl AssignStats {
    /// Lights that reached at least the emit phase.
    pub fn visible(&self) -> u32 {
        self.lights - self.rejected - self.culled
    }

    /// The grid the lists were built for: `requested` (the grid passed to
    /// [`Assigner::assign`]), made [`coarser_grid`] as many times as the pair budget forced.
    pub fn grid_built(&self, requested: &ClusterGrid) -> ClusterGrid {
        (0..self.coarsened).fold(*requested, |g, _| coarser_grid(&g))
    }
}

/// Below this many lights the frame runs as one task on the calling thread (below two tasks'
/// worth there is nothing to split). A parallel frame opens two pool regions (phases, append).
/// Measured with `myriad bench` on the 2-core CI machine, medians of interleaved runs with the
/// pool's workers awake (as in a frame loop that keeps the pool busy), serial → parallel:
/// `paper` 500 lights 52 → 27 µs, 1000 lights `binary` 62 → 36 µs and `refined` 87 → 49 µs;
/// `uniform` 500 lights 27 → 21 µs, 1000 lights 42 → 25 µs. When the workers have gone to sleep
/// between frames they arrive too late for a small frame, which then runs its tasks serially
/// (see `pacing.rs` for when, and the measurements).
pub const SERIAL_LIGHTS: usize = 512;
/// Lights per task at least, so a task's fixed costs (its bucket set, a rayon job) stay small next
/// to the lights' work.
const LIGHTS_PER_TASK: usize = 256;

/// Stack a frame's caller must find free before it works on the frame's tasks itself (serially,
/// or beside its helpers from outside the pool): a large task's need and room for the frame's
/// own calls above it. A thread with less runs the frame on a grown stack, once per frame rather
/// than once per task (`jobs::with_stack`).
const FRAME_STACK: usize = jobs::LARGE_TASK_STACK + (32 << 10);

/// What makes a frame's input unusable: what [`Assigner::assign_active`] panics with and
/// [`Assigner::try_assign_active`] returns.
fn frame_problem(
    lights: &LightInput<'_>,
    camera: &Camera,
    grid: &ClusterGrid,
    active: Option<&ActiveClusters>,
) -> Option<String> {
    if let Some(problem) = camera.view_problem() {
        return Some(format!("light assignment needs a valid camera: {problem}"));
    }
    // Open outer slices reach the camera's near and far planes, so those must be real: a
    // placeholder far of 0 or NaN closed the last slice silently, and its lights went missing
    // (engine audit).
    if grid.outer_slices() == OuterSlices::Open && !(camera.near > 0.0 && camera.near < camera.far)
    {
        return Some(format!(
            "the grid's outer slices are open (OuterSlices::Open, the default), so the \
             assignment reads the camera's depth range, which must satisfy 0 < near < far (far \
             may be infinite): got [{}, {}]; give the camera its real near and far planes, or \
             close the grid's outer slices (OuterSlices::Closed) to slice by its range alone",
            camera.near, camera.far
        ));
    }
    if let Some(problem) = lights.problem() {
        return Some(problem.into());
    }
    let active = active?;
    let [a, g] = [active.dims(), grid.dims()];
    if a != g {
        return Some(format!(
            "active-cluster mask is for a {}x{}x{} grid, not this {}x{}x{} one",
            a.x, a.y, a.z, g.x, g.y, g.z
        ));
    }
    (!active.is_for(grid)).then(|| {
        format!(
            "active-cluster mask is for another {}x{}x{} grid (another depth range or slicing: \
             its cluster ids are other cells); build it for this grid",
            g.x, g.y, g.z
        )
    })
}

/// Why [`Assigner::try_assign`] refused a frame: the message [`Assigner::assign`] would panic
/// with.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InvalidFrame(pub String);

impl std::fmt::Display for InvalidFrame {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for InvalidFrame {}

/// Runs light assignment and keeps all of its scratch storage between frames, so steady-state
/// frames allocate nothing (called from outside any pool, rayon's job boxes aside: see
/// [`OutsideCalls`]). One `Assigner` per concurrent frame; it uses the current rayon pool
/// (install your own with `ThreadPool::install` to pick the thread count). A thread that calls it
/// every frame from outside any pool, as an engine's main thread does, works on each parallel
/// frame itself alongside helper jobs it spawns on the global pool ([`OutsideCalls::Join`]:
/// a few small allocations: rayon's boxed jobs) or hands the frame to a worker
/// ([`OutsideCalls::HandOff`]: no allocation, two cross-thread wake-ups); made a member of the
/// pool (`ThreadPoolBuilder::use_current_thread`) it starts its frames as a worker does (docs/engine-guide.md,
/// "Things to know", has the three timed side by side).
#[derive(Default)]
pub struct Assigner {
    planes: PlaneSets,
    /// One output per task, each on cache lines of its own (`CachePadded`, 128 bytes on x86-64:
    /// the adjacent-line prefetcher pairs lines). Tasks of one frame run on different threads
    /// and write their outputs' counters and bucket headers on every light; unpadded, two
    /// neighbours' 80-byte outputs share a line, and whether two tasks' bucket arrays do was up
    /// to the allocator. On the 2-vCPU host it measured the same either way (`myriad bench`,
    /// `paper` 1000, interleaved builds; one thread: `binary` 101.2–102.2 → 96.6–99.1 µs; two
    /// threads, four runs each: `binary` 93.7–110.2 → 96.1–109.2 µs, `refined` 138.4–147.2 →
    /// 131.7–148.2 µs): it is kept because it costs nothing and makes "no line written by two
    /// threads" hold by construction.
    tasks: Vec<CachePadded<TaskOutput>>,
    /// Where each part's pairs start (see `append::part_bases`).
    part_bases: Vec<u64>,
    /// The active mask's prefix count (see `ActiveClusters::view`).
    active_before: Vec<u32>,
    cluster_spheres: Vec<Vec4>,
    spheres_key: Option<(glam::Vec2, ClusterGrid, [f32; 2])>,
    /// The `cone` method's tile cones (`cone.rs`), kept while the field of view and the tiling
    /// stay the same; empty for grids of more than [`cone::MAX_CACHED_TILES`] tiles.
    tile_cones: Vec<TileCone>,
    cones_key: Option<((f64, f64), u32, u32)>,
    linear: LinearScratch,
    append: AppendStrategy,
    /// When the previous frame ended and how big it was: whether the next runs in parallel.
    pacing: Pacing,
    parallelism: Parallelism,
    outside_calls: OutsideCalls,
    atomic: append::AtomicCounters,
    pair_budget: Option<u64>,
}

impl Assigner {
    /// An assigner with no storage yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Selects how lists are appended (the default is the faster one; this exists to measure).
    pub fn with_append_strategy(mut self, strategy: AppendStrategy) -> Self {
        self.append = strategy;
        self
    }

    /// Selects when a frame split into tasks runs them on the pool (the default paces them; see
    /// [`Assigner::assign`]).
    pub fn with_parallelism(mut self, parallelism: Parallelism) -> Self {
        self.parallelism = parallelism;
        self
    }

    /// Selects how a frame called from a thread outside any rayon pool uses the pool (the
    /// default: the calling thread works alongside helpers it spawns; see [`OutsideCalls`]).
    pub fn with_outside_calls(mut self, outside_calls: OutsideCalls) -> Self {
        self.outside_calls = outside_calls;
        self
    }

    /// Caps the lists at `pairs` cluster–light pairs (`8·clusters + 4·pairs` bytes of CSR). A
    /// frame that would exceed it is assigned again on [`coarser_grid`]s until it fits — fewer,
    /// bigger clusters, so more false positives but never a missed light — and
    /// [`AssignStats::grid_dims`] / [`AssignStats::coarsened`] say so. Deterministic: the same
    /// input always degrades the same way. Without a budget the limit is what u32 offsets hold.
    /// The one frame that passes the cap is one whose lights exceed it even on a single cluster:
    /// that frame lists them all there, and [`AssignStats::over_budget`] says so (no light is
    /// dropped to keep a cap).
    pub fn with_pair_budget(mut self, pairs: u64) -> Self {
        self.pair_budget = Some(pairs);
        self
    }

    /// Assigns `lights` to the clusters of `grid` seen by `camera` with `method`, refilling `out`.
    /// The lists are for `grid`, or for a coarser grid when the pair budget demands it: check
    /// [`AssignStats::coarsened`] (and get that grid from [`AssignStats::grid_built`]).
    ///
    /// From [`SERIAL_LIGHTS`] lights the frame is split into tasks, which run on the current
    /// rayon pool — unless the previous call of this assigner ended more than 20 µs ago and this
    /// frame is expected to be small (under about 250 µs of work: the previous frame's, scaled by
    /// the ratio of the light counts): then the pool's workers are asleep and would arrive too
    /// late to help, so the tasks run one after another on the calling thread
    /// ([`AssignStats::parallel`]; the measurements are in `pacing.rs`). Calls back to back, as
    /// in a benchmark loop or several views in a row, and big frames run in parallel;
    /// [`Parallelism::Always`] runs every split frame in parallel, and
    /// [`Parallelism::PacedWith`] sets other limits.
    ///
    /// # Panics
    ///
    /// On a camera [`Camera::view_problem`] rejects (a NaN field of view, a zero size, …): no
    /// method could place a light in its frustum, so any lists would be wrong. Check it first
    /// when the camera comes from user input. Depth is sliced by `grid`'s range, and where the
    /// grid's outer slices are [`OuterSlices::Open`] (the default) they reach the camera's near
    /// and far planes, so the camera's depth range must then satisfy `0 < near < far` (an
    /// infinite far plane is fine; a placeholder is not); a [`OuterSlices::Closed`] grid reads
    /// neither. Also when `lights`' columns differ in length, or hold more than `u32::MAX`
    /// lights (light indices are u32). [`Assigner::try_assign`] returns these as errors.
    pub fn assign(
        &mut self,
        method: Method,
        lights: &LightInput<'_>,
        camera: &Camera,
        grid: &ClusterGrid,
        out: &mut LightLists,
    ) -> AssignStats {
        self.assign_active(method, lights, camera, grid, None, out)
    }

    /// [`Assigner::assign`] that returns an error where `assign` panics (a camera
    /// [`Camera::view_problem`] rejects, or whose depth range an open grid cannot use, columns
    /// of different lengths, more than `u32::MAX` lights), for engines whose cameras and light
    /// counts come from data. `out` is untouched on an error.
    pub fn try_assign(
        &mut self,
        method: Method,
        lights: &LightInput<'_>,
        camera: &Camera,
        grid: &ClusterGrid,
        out: &mut LightLists,
    ) -> Result<AssignStats, InvalidFrame> {
        self.try_assign_active(method, lights, camera, grid, None, out)
    }

    /// What [`Assigner::try_assign`] would refuse about this frame, without assigning it: a loop
    /// whose camera and grid stay fixed checks them once, up front.
    pub fn check_frame(
        lights: &LightInput<'_>,
        camera: &Camera,
        grid: &ClusterGrid,
    ) -> Result<(), InvalidFrame> {
        match frame_problem(lights, camera, grid, None) {
            Some(problem) => Err(InvalidFrame(problem)),
            None => Ok(()),
        }
    }

    /// [`Assigner::assign_active`] that returns an error where it panics (as
    /// [`Assigner::try_assign`], and a mask for another grid).
    pub fn try_assign_active(
        &mut self,
        method: Method,
        lights: &LightInput<'_>,
        camera: &Camera,
        grid: &ClusterGrid,
        active: Option<&ActiveClusters>,
        out: &mut LightLists,
    ) -> Result<AssignStats, InvalidFrame> {
        if let Some(problem) = frame_problem(lights, camera, grid, active) {
            return Err(InvalidFrame(problem));
        }
        Ok(self.assign_active(method, lights, camera, grid, active, out))
    }

    /// [`Assigner::assign`] for only the `active` clusters (see [`ActiveClusters`]): every other
    /// cluster gets an empty list, and neither counting nor filling visits it (a light's row of
    /// clusters with no active one is dropped as it is emitted). `None` is every cluster. When
    /// the pair budget coarsens the grid, the mask no longer fits and is dropped: the coarser
    /// lists are full.
    ///
    /// # Panics
    ///
    /// As [`Assigner::assign`], and when `active` is for another grid.
    pub fn assign_active(
        &mut self,
        method: Method,
        lights: &LightInput<'_>,
        camera: &Camera,
        grid: &ClusterGrid,
        active: Option<&ActiveClusters>,
        out: &mut LightLists,
    ) -> AssignStats {
        if let Some(problem) = frame_problem(lights, camera, grid, active) {
            panic!("{problem}");
        }
        let frame = Frame {
            method,
            lights,
            camera,
            grid: *grid,
            active,
        };
        let start = Instant::now();
        let parallel = method != Method::Linear
            && self
                .parallelism
                .limits()
                .is_none_or(|limits| self.pacing.parallel(start, lights.len(), limits));
        let split = plan_tasks(lights.len(), method) > 1;
        let stats = if parallel && split && rayon::current_thread_index().is_none() {
            match (self.outside_calls, self.append) {
                // Called from outside the pool (an engine's main thread, a benchmark loop): work
                // on the frame alongside helpers spawned on the pool (`fan_out.rs`)...
                (OutsideCalls::Join, AppendStrategy::PartitionedByDepth) => {
                    let helpers = rayon::current_num_threads() - 1;
                    jobs::with_stack(FRAME_STACK, || {
                        self.assign_frame(frame, FanOut::WithCaller { helpers }, out)
                    })
                }
                // ...or move the whole frame onto a worker in one hand-off. Otherwise each
                // parallel region would inject its jobs and park this thread until they finish
                // — a cross-thread wake-up per region.
                _ => rayon::scope(|_| self.assign_frame(frame, FanOut::Pool, out)),
            }
        } else if parallel {
            self.assign_frame(frame, FanOut::Pool, out)
        } else {
            jobs::with_stack(FRAME_STACK, || {
                self.assign_frame(frame, FanOut::Serial, out)
            })
        };
        let threads = if stats.parallel {
            (stats.tasks as usize).min(rayon::current_num_threads())
        } else {
            1
        };
        self.pacing
            .record(start, Instant::now(), threads, lights.len());
        stats
    }

    /// One frame, its tasks on the pool when `parallel` (and there are several): the grid
    /// coarsened until the pairs fit the budget.
    fn assign_frame(
        &mut self,
        frame: Frame<'_>,
        fan_out: FanOut,
        out: &mut LightLists,
    ) -> AssignStats {
        let budget = self
            .pair_budget
            .unwrap_or(u32::MAX as u64)
            .min(u32::MAX as u64);
        let mut attempt_frame = frame;
        let mut coarsened = 0;
        loop {
            // One cluster holds at most every light (< 2³² by `assert_consistent`): always fits.
            let last_resort = attempt_frame.grid.dims() == glam::UVec3::ONE;
            let limit = if last_resort { u32::MAX as u64 } else { budget };
            if let Ok(mut stats) = self.assign_once(&attempt_frame, fan_out, limit, out) {
                stats.grid_dims = attempt_frame.grid.dims().to_array();
                stats.coarsened = coarsened;
                stats.over_budget = stats.pairs > budget;
                return stats;
            }
            // The mask is for the caller's grid: a coarser grid's lists are full.
            attempt_frame.grid = coarser_grid(&attempt_frame.grid);
            attempt_frame.active = None;
            coarsened += 1;
        }
    }

    /// One attempt on one grid: `Err(pairs)` (nothing written) when the pairs exceed `budget`.
    fn assign_once(
        &mut self,
        frame: &Frame<'_>,
        fan_out: FanOut,
        budget: u64,
        out: &mut LightLists,
    ) -> Result<AssignStats, u64> {
        let Frame {
            method,
            lights,
            camera,
            ref grid,
            active,
        } = *frame;
        profile_span!("assign on one grid");
        lights.assert_consistent();
        let n = lights.len();
        self.planes.update(camera, grid);
        let view_from_world = camera.view_rotation();
        let mut stats = AssignStats {
            lights: n as u32,
            ..AssignStats::default()
        };
        if method == Method::Linear {
            let counts = linear::assign_linear(
                &mut self.linear,
                lights,
                camera,
                grid,
                &self.planes,
                active,
                budget,
                out,
            )?;
            stats.rejected = counts.rejected;
            stats.culled = counts.culled;
            stats.beyond_far = counts.beyond_far;
            stats.before_near = counts.before_near;
            stats.reach = counts.reach;
            stats.pairs = out.indices.len() as u64;
            stats.tasks = 1;
            return Ok(stats);
        }
        if lights.spot.is_some() && method != Method::Exact {
            // The outer slices' spheres follow the camera's near and far where they are open.
            let ends = [grid.first_slice_start(camera), grid.last_slice_end(camera)];
            let key = (camera.tan_half_fov(), *grid, ends);
            if self.spheres_key != Some(key) {
                jobs::cluster_bounding_spheres(camera, grid, &mut self.cluster_spheres);
                self.spheres_key = Some(key);
            }
        }
        let tan_half_fov = camera.tan_half_fov_f64();
        if method == Method::Cone {
            let d = grid.dims();
            let key = (tan_half_fov, d.x, d.y);
            if self.cones_key != Some(key) {
                let tiles = d.x as usize * d.y as usize;
                if tiles <= cone::MAX_CACHED_TILES {
                    cone::tile_cones(tan_half_fov, d, &mut self.tile_cones);
                } else {
                    self.tile_cones = Vec::new();
                }
                self.cones_key = Some(key);
            }
        }
        let clusters = grid.cluster_count();
        let tasks = plan_tasks(n, method);
        if self.tasks.len() < tasks {
            self.tasks.resize_with(tasks, CachePadded::default);
        }
        let parts = plan_parts(grid, tasks);
        let view = active.map(|a| a.view(&mut self.active_before));
        let cull = jobs::FrustumCull::of_grid(&self.planes, grid);
        let ctx = FrameContext {
            active: view,
            method,
            exact: (method == Method::Exact).then(|| jobs::ExactFrame::new(camera, budget)),
            parts: parts.count,
            slice_shift: parts.slice_shift,
            lights: *lights,
            camera,
            grid,
            planes: FramePlanes::new(&self.planes, grid),
            view_from_world,
            cluster_spheres: &self.cluster_spheres,
            tile_cones: if method == Method::Cone {
                &self.tile_cones
            } else {
                &[]
            },
            tan_half_fov,
            cull,
            outside_cull: sees_outside(camera, grid).map(|(near, far)| cull.with_depths(near, far)),
        };
        let fan_out = if tasks > 1 { fan_out } else { FanOut::Serial };
        let gather = |(t, task): (usize, &mut CachePadded<TaskOutput>)| {
            let (begin, end) = (t * n / tasks, (t + 1) * n / tasks);
            jobs::run_task(&ctx, begin, end, task);
        };
        for_each_task(&mut self.tasks[..tasks], fan_out, gather);
        // `exact` stops as soon as its running count passes the budget (see `ExactFrame`).
        if let Some(exact) = &ctx.exact
            && exact.over_budget()
        {
            return Err(exact.pairs.load(std::sync::atomic::Ordering::Relaxed));
        }
        let work = &self.tasks[..tasks];
        let pairs = match self.append {
            AppendStrategy::PartitionedByDepth => {
                let total = append::part_bases(work, parts, &mut self.part_bases);
                if total > budget {
                    return Err(total);
                }
                append::build_lists(
                    work,
                    parts,
                    fan_out,
                    view.as_ref(),
                    &self.part_bases,
                    clusters,
                    out,
                );
                total as usize
            }
            AppendStrategy::AtomicCounters => {
                let (stride, active) = (parts.row_stride, view.as_ref());
                self.atomic.assign(
                    work,
                    parts.count,
                    stride,
                    clusters,
                    active,
                    fan_out.parallel(),
                    budget,
                    out,
                )?
            }
        };
        for task in work {
            stats.rejected += task.rejected;
            stats.culled += task.culled;
            stats.beyond_far += task.beyond_far;
            stats.before_near += task.before_near;
        }
        if sees_past(camera, grid) {
            stats.reach = Some(work.iter().map(|t| t.reach).fold(0.0, f32::max));
        }
        stats.pairs = pairs as u64;
        stats.tasks = tasks as u32;
        stats.parallel = fan_out.parallel();
        Ok(stats)
    }
}

/// Whether `camera` sees past the far edge of `grid` (then lights can lie beyond the grid yet in
/// view: [`AssignStats::beyond_far`]).
pub(crate) fn sees_past(camera: &Camera, grid: &ClusterGrid) -> bool {
    camera.far > grid.far()
}

/// Whether `camera` sees nearer than the near edge of `grid` (then lights can lie before the
/// grid yet in view: [`AssignStats::before_near`]). A camera near that is not a positive number
/// (a placeholder, which only a closed grid accepts) sees nothing there.
pub(crate) fn sees_before(camera: &Camera, grid: &ClusterGrid) -> bool {
    camera.near > 0.0 && camera.near < grid.near()
}

/// Where the camera sees past either depth edge of `grid`: the near and far of its view there,
/// for the cull that counts the lights outside the grid ([`AssignStats::before_near`],
/// [`AssignStats::beyond_far`]). A far side the grid covers keeps the grid's own depth. The
/// near is the camera's where it sees nearer than the grid, clamped as an open first slice's
/// start is ([`ClusterGrid::first_slice_start`]), so that what an open grid lists before its
/// near and what is counted there are the same lights; the camera's too where it clips beyond
/// the grid's near (the lights in front of it are not in view, and counted in no reach); else
/// the grid's (a placeholder near).
pub(crate) fn sees_outside(camera: &Camera, grid: &ClusterGrid) -> Option<(f32, f32)> {
    let (before, past) = (sees_before(camera, grid), sees_past(camera, grid));
    (before || past).then(|| {
        let near = if before {
            camera.near.max(ClusterGrid::MIN_NEAR)
        } else if camera.near > grid.near() && camera.near.is_finite() {
            camera.near
        } else {
            grid.near()
        };
        (near, if past { camera.far } else { grid.far() })
    })
}

/// One frame's inputs, as [`Assigner::assign_active`] received them (the grid by value: a pair
/// budget swaps in coarser ones).
#[derive(Clone, Copy)]
struct Frame<'a> {
    method: Method,
    lights: &'a LightInput<'a>,
    camera: &'a Camera,
    grid: ClusterGrid,
    active: Option<&'a ActiveClusters>,
}

/// The grid a pair budget falls back to: every dimension halved (rounding down, at least 1),
/// same depth range, slicing and [`OuterSlices`]. Repeating it reaches 1×1×1.
pub fn coarser_grid(grid: &ClusterGrid) -> ClusterGrid {
    let dims = (grid.dims() / 2).max(glam::UVec3::ONE);
    ClusterGrid::new(dims, grid.slicing(), grid.near(), grid.far())
        .with_outer_slices(grid.outer_slices())
}

/// Splits the clusters into parts of whole depth slices: one part when serial; else one per slice,
/// which the append groups into pieces of about equal work (the pairs crowd into a few slices).
/// A part holds a power of two of slices, so a slice's part is a shift, not a division, in the
/// emit's innermost loop.
fn plan_parts(grid: &ClusterGrid, tasks: usize) -> Parts {
    let slices = grid.dims().z as usize;
    // At most 2³¹ slices a part: `k >> slice_shift` takes a u32 slice, so the shift stays
    // under 32 (a grid of over 2³¹ slices needs two parts).
    let slices_per_part = if tasks > 1 {
        1
    } else {
        slices.next_power_of_two().min(1 << 31)
    };
    let per_slice = grid.dims().x as usize * grid.dims().y as usize;
    Parts {
        count: slices.div_ceil(slices_per_part),
        clusters: slices_per_part * per_slice,
        slice_shift: slices_per_part.trailing_zeros(),
        row_stride: grid.dims().x,
    }
}

/// Runs `f` over the tasks as `fan_out` says. On the pool: one job per task (`with_max_len(1)`),
/// so the pool's work stealing moves single tasks between workers (without it rayon's splitter
/// hands each worker one contiguous piece of tasks, run in one go). With the caller: one task at a
/// time from a shared queue, the same grain.
fn for_each_task<F>(tasks: &mut [CachePadded<TaskOutput>], fan_out: FanOut, f: F)
where
    F: Fn((usize, &mut CachePadded<TaskOutput>)) + Sync + Send,
{
    match fan_out {
        FanOut::Pool => tasks.par_iter_mut().enumerate().with_max_len(1).for_each(f),
        FanOut::WithCaller { helpers } => {
            fan_out::with_caller(tasks.iter_mut().enumerate(), helpers, f);
        }
        FanOut::Serial => tasks.iter_mut().enumerate().for_each(f),
    }
}

/// How many contiguous light ranges to split a frame into: four per thread (at least
/// [`LIGHTS_PER_TASK`] lights each), each its own stealable job (see [`for_each_task`]), so a
/// worker that finishes early takes whole tasks off a slower one.
///
/// Measured on the 2-vCPU CI machine while its second vCPU ran about 1.4× slower than the first:
/// with two tasks per thread the fast worker sat idle for the last 0.6 ms of a 2.2 ms `uniform`
/// 100k task phase (an instrumented build), because rayon's splitter had handed each worker two
/// tasks as one piece. Four per thread, one job each, against two per thread in one process,
/// alternating calls (`refined`, medians of 200 calls each, three runs): `uniform` 100k
/// −1% / 0% / −3%, `sphere` 100k −11% / −15% / 0%; on one thread, +0.3% and −0.4% (the overhead).
/// Eight per thread gained more in a single run (`uniform` 100k −10%) but cost 2–4% on one
/// thread (`uniform` +1.9%, `sphere` +3.6%).
fn plan_tasks(lights: usize, method: Method) -> usize {
    if lights < SERIAL_LIGHTS && method != Method::Exact {
        return 1;
    }
    let threads = rayon::current_num_threads();
    let by_work = lights.div_ceil(LIGHTS_PER_TASK).max(1);
    (4 * threads).min(by_work).max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The names the command line and the reports use: each method's own, shown by `Display`,
    /// and parsed back by `from_name` (and nothing else is).
    #[test]
    fn method_names_display_and_parse_back() {
        let names = Method::ALL.map(Method::name);
        assert_eq!(names, ["exact", "linear", "binary", "refined", "cone"]);
        for method in Method::ALL {
            assert_eq!(method.to_string(), method.name());
            assert_eq!(Method::from_name(method.name()), Some(method));
        }
        for name in ["", "Binary", "binary ", "exact1", "all"] {
            assert_eq!(Method::from_name(name), None, "{name:?}");
        }
    }

    /// `SERIAL_LIGHTS` is where a frame starts to split (`exact` splits at any size), into
    /// tasks of at least `LIGHTS_PER_TASK` lights, four per thread at most.
    #[test]
    fn frames_split_from_serial_lights_into_four_tasks_per_thread_at_most() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        pool.install(|| {
            for method in [Method::Binary, Method::Refined, Method::Cone] {
                assert_eq!(plan_tasks(0, method), 1);
                assert_eq!(plan_tasks(SERIAL_LIGHTS - 1, method), 1, "{method}");
                assert_eq!(plan_tasks(SERIAL_LIGHTS, method), 2, "{method}");
                assert_eq!(plan_tasks(1000, method), 4, "{method}");
                assert_eq!(plan_tasks(100_000, method), 12, "{method}");
            }
            assert_eq!(plan_tasks(0, Method::Exact), 1);
            assert_eq!(plan_tasks(1, Method::Exact), 1);
            assert_eq!(plan_tasks(300, Method::Exact), 2);
            assert_eq!(plan_tasks(100_000, Method::Exact), 12);
        });
    }

    /// A serial frame is one part of all its slices (a power of two of them, so a slice's part
    /// is a shift); a split frame has a part per slice, for the append to group by work.
    #[test]
    fn parts_are_all_slices_when_serial_and_one_slice_each_when_split() {
        let grid = ClusterGrid::new(
            glam::UVec3::new(4, 3, 5),
            myriad_cluster_math::DepthSlicing::Log,
            0.1,
            100.0,
        );
        let serial = plan_parts(&grid, 1);
        let shape = |p: Parts| (p.count, p.clusters, p.slice_shift, p.row_stride);
        assert_eq!(shape(serial), (1, 8 * 12, 3, 4));
        for tasks in [2, 12] {
            assert_eq!(
                shape(plan_parts(&grid, tasks)),
                (5, 12, 0, 4),
                "{tasks} tasks"
            );
        }
    }

    /// A pair budget degrades one step at a time: every dimension halved (rounding down, at
    /// least 1), the same depth range and slicing, down to 1×1×1 and no further.
    #[test]
    fn coarser_grids_halve_every_dimension_down_to_one_cluster() {
        let slicing = myriad_cluster_math::DepthSlicing::LogWithNearSlice {
            first_slice_depth: 0.5,
        };
        let grid = ClusterGrid::new(glam::UVec3::new(16, 9, 24), slicing, 0.1, 300.0);
        let mut dims = vec![];
        let mut g = grid;
        for _ in 0..6 {
            g = coarser_grid(&g);
            assert_eq!((g.slicing(), g.near(), g.far()), (slicing, 0.1, 300.0));
            dims.push(g.dims().to_array());
        }
        let want = [
            [8, 4, 12],
            [4, 2, 6],
            [2, 1, 3],
            [1, 1, 1],
            [1, 1, 1],
            [1, 1, 1],
        ];
        assert_eq!(dims, want);
    }
}
