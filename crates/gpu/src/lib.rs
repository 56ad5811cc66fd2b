//! # myriad-gpu — the wgpu renderer
//!
//! Everything that names `wgpu` lives here: the G-buffer pass, full-screen deferred shading that
//! visits only the lights of each pixel's cluster (or every light, the brute-force reference, or
//! a one-slice grid's lists, 2D tiled shading), the clustered forward pass for alpha-blended
//! materials, the lights-per-pixel heat map, light and list uploads through a ring of staging
//! buffers, pass timestamps, headless targets and PNG read-back.
//!
//! It works on the caller's `wgpu::Device`/`Queue` ([`GpuContext::from_device`]), so an engine
//! can drop it in, or creates its own headless adapter (`GpuContext::headless`, feature
//! `headless`) for the CLI and tests. It depends on `myriad-cluster-math` (the pixel → cluster mapping must be the CPU's, bit
//! for bit: `shaders/common/cluster.wgsl` is tested against `ClusterGrid::cluster_of_pixel`) and on
//! nothing that knows scenes or assignment methods: light columns and CSR lists arrive as plain
//! slices ([`LightColumns`], [`ClusterLists`]).
//!
//! ## Features
//! - `headless` (default): `GpuContext::headless`, which creates a device of its own (through
//!   `pollster`).
//! - `image` (default): PNG read-back (`save_png`, `encode_png`) and
//!   `SceneGeometry::fit_textures`, through `image`.
//!
//! (Plain names, not links, for what a feature adds: these docs build without the features too,
//! as an engine that turns them off builds them.)
//! - `tracy`: Tracy spans for upload and encoding (each pass's CPU-side encode on its own) and
//!   for each pipeline build, and each timed pass as a Tracy GPU zone (`tracy_zones.rs`).
//!
//! An engine that brings its device and does its own image I/O can set
//! `default-features = false` and depends on neither `pollster` nor `image`.
//!
//! ```no_run
//! use myriad_gpu::{GpuContext, HeadlessTarget, Renderer, HEADLESS_FORMAT};
//! # #[cfg(feature = "headless")] {
//! let ctx = GpuContext::headless()?; // `GpuContext::from_device` without the feature
//! let mut renderer = Renderer::new(&ctx, HEADLESS_FORMAT);
//! let target = HeadlessTarget::new(&ctx.device, 640, 360)?;
//! // renderer.upload_scene(..) and, for each kind of frame to come, renderer.prepare(..) (its
//! // pipelines, so no frame compiles shaders); then renderer.render(&ctx, &scene, &frame,
//! // &target.view) per frame.
//! # }
//! # Ok::<(), myriad_gpu::GpuError>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod buffers;
mod check_pass;
pub mod cluster_check;
mod context;
mod device_loss;
mod error;
mod frame_input;
pub mod layout;
pub mod legend;
pub mod lighting_check;
pub mod loop_budget;
mod out_of_memory;
mod pipelines;
mod profiling;
mod readback;
mod renderer;
mod scene;
pub mod shaders;
mod targets;
mod timing;
#[cfg(feature = "tracy")]
mod tracy_zones;

#[cfg(feature = "headless")]
pub use context::shared_instance;
pub use context::{GpuContext, SKIP_GPU_TESTS_VAR};
pub use device_loss::{DeviceLoss, DeviceLossRecorder};
pub use error::GpuError;
pub use frame_input::{
    ClusterLists, LightColumns, SPOT_INNER_FRACTION, SpotColumns, fill_gpu_lights,
};
/// The glam version of the public types ([`Draw::center`], the camera's vectors).
pub use myriad_cluster_math::glam;
pub use pipelines::{ShadingMode, encodes_srgb};
#[cfg(feature = "image")]
pub use readback::{encode_png, save_png};
pub use readback::{read_depth, read_rgba8, read_texels};
pub use renderer::{
    FrameDesc, FrameReport, ListsReadBack, Renderer, ShadingSettings, frame_uniforms,
};
pub use scene::{Blend, Draw, GpuScene, MaterialDesc, SceneGeometry, TextureRgba8};
pub use targets::{DEPTH_FORMAT, GBuffer, HEADLESS_FORMAT, HeadlessTarget};
pub use timing::PassTimes;
/// The wgpu version this crate is built against (30), for callers that want to match it.
pub use wgpu;
