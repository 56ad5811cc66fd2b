//! Rendering glue: scenes and models into the renderer's inputs, a viewer that assigns and
//! renders frames, and the pipelined frame loop.

mod depth_buffer;
#[cfg(test)]
mod frame_marks;
mod geometry;
mod image_difference;
mod pipelined;
mod pixel_stats;
mod prepass_tuner;
mod setup;
mod skips;
mod viewer;

pub use depth_buffer::{fitted_grid, mark_active};
pub use geometry::scene_geometry;
pub use image_difference::max_channel_difference;
pub use pipelined::{FRAMES_IN_FLIGHT, GpuStage, LoopReport, StageTimes, run_frames};
pub use pixel_stats::{PixelStats, pixel_stats};
pub use prepass_tuner::{FramePlan, PrepassDecision, PrepassTuner, TunedFrame, TunerSettings};
pub use setup::{DEFAULT_GRID, RenderScene, blended_bounds};
pub use skips::{SkipFrame, Skips};
pub use viewer::{Shading, Viewer, ViewerFrame, cluster_lists, light_columns};
