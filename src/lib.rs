//! # myriad — clustered shading with very many dynamic lights
//!
//! The facade: re-exports the four crates under short names (three without the `render` feature) and holds the pieces the `myriad`
//! command-line tool shares with tests and benches: the assignment dump format, the evaluation
//! code (accuracy and time against error), the render glue (`render`: `Viewer`, `run_frames`,
//! `Skips`), `light_input`, `core_link` and the Tracy profiling.
//!
//! | crate | re-exported as | what it is |
//! | --- | --- | --- |
//! | `myriad-cluster-math` | [`cluster_math`] | camera, cluster grid, mappings, plane sets, the f64 oracle |
//! | `myriad-assignment` | [`assignment`] | light → cluster assignment into CSR lists |
//! | `myriad-scene` | [`scene`] | scene files, glTF loading, the generated atrium, light fields, frame systems |
//! | `myriad-gpu` | `gpu` (feature `render`) | the wgpu renderer |
//!
//! Glue between them lives here and only here: the crates never depend on each other beyond
//! `cluster-math` (see ARCHITECTURE.md).
//!
//! ## Features
//! - `render` (in the default `cli`): the renderer glue — the `render` module, the `gpu`
//!   re-export, `profiling::plot_pass_times` — and with it `myriad-gpu`, wgpu and naga (`image`
//!   comes either way, with the glTF loader of `myriad-scene`).
//!   Without it the facade is what joins scene and assignment ([`light_input`], [`dump`],
//!   [`evaluate`], [`core_link`], [`profiling`]): an engine that renders itself but takes
//!   myriad's lights and lists builds no GPU crate (`default-features = false`).
//! - `cli` (default): the `myriad` binary and what only it uses.
//! - `tracy`: Tracy spans, frame marks and plots (see [`profiling`]).
// No `unsafe` code but in `profiling.rs`: the profiler's shutdown (a call made with the `tracy`
// feature only) and the `unsafe fn start` whose contract makes it sound.
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub use myriad_assignment as assignment;
pub use myriad_cluster_math as cluster_math;
#[cfg(feature = "render")]
pub use myriad_gpu as gpu;
pub use myriad_scene as scene;

pub mod core_link;
pub mod dump;
pub mod evaluate;
pub mod profiling;
#[cfg(feature = "render")]
pub mod render;

use myriad_assignment::{LightInput, SpotInput};
use myriad_scene::Lights;

/// The assignment's view of a scene's light columns (spot columns only when some light is a spot).
pub fn light_input(lights: &Lights) -> LightInput<'_> {
    LightInput {
        x: &lights.x,
        y: &lights.y,
        z: &lights.z,
        radius: &lights.radius,
        spot: lights.has_spots().then(|| SpotInput {
            dir_x: &lights.spot_dir_x,
            dir_y: &lights.spot_dir_y,
            dir_z: &lights.spot_dir_z,
            angle: &lights.spot_angle,
        }),
    }
}
