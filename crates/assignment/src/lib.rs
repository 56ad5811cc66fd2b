//! # myriad-assignment — which lights touch which clusters, fast and never wrong
//!
//! Input: plain SoA light columns ([`LightInput`]: world positions, radii, optional spot cones), a
//! [`Camera`](myriad_cluster_math::Camera) and a [`ClusterGrid`](myriad_cluster_math::ClusterGrid).
//! Output: [`LightLists`] in CSR form — `offsets`, `counts`, `indices` — the layout of the paper's
//! Figure 3, written into caller-owned storage that is reused from frame to frame.
//! This crate knows nothing of scenes, files or GPUs.
//!
//! ## Example (the README's, run as a test)
//!
//! ```
//! use myriad_assignment::{Assigner, LightInput, LightLists, Method};
//! use myriad_cluster_math::glam::{UVec3, Vec3}; // the glam version of the public types
//! use myriad_cluster_math::{Camera, ClusterGrid, DepthSlicing};
//!
//! let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 1920, 1080, 0.1, 100.0);
//! let grid = ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, camera.near, camera.far);
//!
//! // SoA columns: world-space positions and ranges, one entry per light.
//! let (x, y, z) = (vec![0.0, 2.0], vec![0.0, 1.0], vec![-5.0, -20.0]);
//! let radius = vec![1.0, 3.0];
//!
//! let mut assigner = Assigner::new(); // keep both across frames:
//! let mut lists = LightLists::new(); // no list storage allocated in steady state (see `Assigner`)
//! let stats = assigner.assign(
//!     Method::Refined,
//!     &LightInput::points(&x, &y, &z, &radius),
//!     &camera,
//!     &grid,
//!     &mut lists,
//! );
//! assert_eq!(stats.pairs, 57);
//!
//! // What the shader does per pixel: pixel + view depth -> cluster -> its lights.
//! let c = grid.cluster_of_pixel(960, 540, 5.0, camera.width, camera.height);
//! assert_eq!(lists.lights_of(c as usize), &[0]);
//! // Upload lists.offsets, lists.counts and lists.indices: plain u32 arrays.
//! ```
//!
//! ## Methods ([`Method`]), all conservative
//! | method | how | cost |
//! | --- | --- | --- |
//! | `exact` | every candidate cluster checked with the f64 oracle | the reference; slow |
//! | `linear` | the paper's Algorithm 1: planes stepped one by one | the baseline to beat |
//! | `binary` | the x-, y-, z-plane sets searched (a binary search's partition points, found from the closed-form guess in 0–2 probes: `search.rs`) → a box of clusters | fast |
//! | `refined` | binary's box tightened per slice and row | fast, few false positives |
//! | `cone` | binary's box cut per tile by spherical-sliced cone tests (seed 004) | tighter than `refined` on `sphere`, on `paper` only for some seeds and grids (docs/results.md); 1.3–2.7× `refined`'s time |
//!
//! ## A frame, step by step (`binary`, `refined`, `cone`, `exact`)
//! 1. **Plan**: split the lights into contiguous ranges, one task each (one task below
//!    [`SERIAL_LIGHTS`], except for `exact`, which is split at any size).
//! 2. **Axis phases, in parallel** (`jobs.rs`, `phases.rs`, `search.rs`; `geometry.rs` is their
//!    per-light twin): per block of lights, SoA passes —
//!    camera-relative view transform and validity, z phase, x phase, y phase (searches of the
//!    plane sets — the paper's proposed *binary frustum reduction*, threaded — started at the
//!    closed-form guess so they finish in one or two probes, `search.rs`) — then the light's
//!    rows of clusters as spans, tightened (`refined`), cut by cone tests (spot lights) or checked
//!    by the oracle (`exact`).
//! 3. **Lock-free append** (`append.rs`): spans are bucketed by parts (depth slices), which add
//!    up their pairs, so each part's place in the output is known; then per part, in parallel
//!    over runs of equal work, a count (difference array), a scan into list starts, a fill
//!    into the part's own slice of the output, and a close (each list's count and start from
//!    the cursors' ends). Lists come out in ascending light order, so the
//!    output is identical for any number of threads.
//!
//! ## Correctness
//! f32 paths pad every radius by `4e-6·(|x| + |y| + |depth| + r)` (tens of f32 ulps of the
//! light's distance and size), which covers the
//! rounding of the view transform and of every comparison; the tests prove each method is a
//! superset of the f64 oracle ([`myriad_cluster_math::oracle`]) on random and hostile scenes.
//! Invalid lights (non-finite position or radius, radius ≤ 0) are skipped and counted in
//! [`AssignStats::rejected`], never written.

#![warn(missing_docs)]

mod active;
mod append;
mod assigner;
mod cone;
mod fan_out;
mod geometry;
mod input;
mod jobs;
mod linear;
mod lists;
mod pacing;
mod phases;
mod profiling;
mod search;

pub use active::ActiveClusters;
pub use assigner::{
    AppendStrategy, AssignStats, Assigner, InvalidFrame, Method, OutsideCalls, SERIAL_LIGHTS,
    coarser_grid,
};
pub use input::{LightInput, SpotInput};
pub use lists::LightLists;
pub use pacing::{PacingLimits, Parallelism};
