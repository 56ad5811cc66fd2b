//! # myriad-cluster-math — the geometry every other crate agrees on
//!
//! Clustered shading only works if the CPU that assigns lights and the GPU that shades pixels agree,
//! bit for bit, on which cluster a pixel belongs to and where each cluster's walls are. This crate is
//! the single place that agreement is written down. It depends on `glam` only and holds no state
//! beyond plain `Copy` values and reusable buffers.
//!
//! ## What lives here
//! * [`Camera`]: position/target/up, vertical field of view, resolution, near/far, and the matrices
//!   `view_from_world` and `clip_from_view` (wgpu depth range 0..1, reversed Z: 1 at near, 0 at far). Lights are brought to view space
//!   *camera-relative* ([`Camera::view_from_world_point`]) so huge world coordinates lose no precision.
//!   [`Camera::from_matrices`] reads one back from an engine's own view and projection matrices.
//! * [`ClusterGrid`]: X×Y×Z clusters. Tiles are uniform in NDC; depth is cut by [`DepthSlicing`]
//!   (linear, logarithmic, or logarithmic with a special first slice). The grid's depth range is
//!   its own: usually the camera's near/far, or a fitted (dynamic) range; a grid shorter than the
//!   camera's view lists the lights outside it in its outer slices ([`OuterSlices`]).
//! * Mappings, all mutually consistent and exhaustively tested: pixel → tile (integer arithmetic, exact
//!   for any resolution), view depth → slice (formula estimate corrected against the edge table, so it
//!   agrees with [`ClusterGrid::slice_start_depth`] to the last bit), slice → depth range, and
//!   `(pixel, depth)` → cluster id `c = i + X·(j + Y·k)`.
//! * [`PlaneSets`]: the view-space x-, y- and z-plane sets the assignment crate searches.
//! * [`spot_bounding_sphere`]: the tightest simple sphere around a spot light's volume.
//! * [`pad_radius`]: the radius allowance for f32 rounding shared by every f32 light test (the
//!   assignment and the frame systems' cull), so neither drops a light the other keeps.
//! * [`oracle`]: the exact f64 reference tests (sphere vs cell, spot volume vs cell). They define what
//!   "a light touches a cluster" means; every fast method in `myriad-assignment` is proven
//!   conservative against them.
//!
//! ## What it refuses to do
//! It does not read user files (that is `myriad-scene`'s job, which turns bad files into errors).
//! `ClusterGrid::new` panics on a bad grid (a zero size, `near >= far`), a programming error; for
//! values from user settings, [`ClusterGrid::try_new`] returns [`InvalidGrid`],
//! [`Camera::problem`] names what makes a camera unusable, and [`Camera::from_matrices`] returns
//! [`CameraMatrixError`].
//!
//! ## Conventions
//! Right-handed view space, camera looking down −Z, +Y up (glam's `camera::rh::view::look_at_mat4`). "View depth" is the
//! positive distance along the view direction, `depth = -z_view`. Tile `i` spans NDC
//! x ∈ [−1+2i/X, −1+2(i+1)/X] (left to right); tile row `j` spans NDC y ∈ [1−2(j+1)/Y, 1−2j/Y]
//! (top to bottom). Pixel `(px, py)` counts from the top-left corner and is sampled at its centre.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod bounds;
mod camera;
mod camera_from_matrices;
mod grid;
pub mod oracle;
mod padding;
mod planes;

pub use bounds::{SpotCone, spot_bounding_sphere};
pub use camera::Camera;
pub use camera_from_matrices::{CameraMatrixError, ClipSpace};
pub use grid::{ClusterGrid, DepthSlicing, InvalidGrid, OuterSlices};
pub use padding::{RADIUS_PAD, pad_radius};
pub use planes::PlaneSets;

/// Re-exported so callers use the same `glam` version as the crate's public types.
pub use glam;
