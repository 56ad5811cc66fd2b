//! Runs the shaders' `cluster_of_pixel` (`shaders/common/cluster.wgsl`) in a compute pass over
//! many (pixel, view depth) samples, so tests can compare the GPU's answer with
//! `ClusterGrid::cluster_of_pixel` sample by sample.

use crate::check_pass;
use crate::layout::ClusterCheckUniforms;
use crate::out_of_memory::buffer_init;
use crate::shaders::PassShader;
use crate::{GpuContext, GpuError};
use myriad_cluster_math::{Camera, ClusterGrid};

/// What the sample depths of a check are.
#[derive(Clone, Copy, Debug)]
pub enum SampleDepths<'a> {
    /// View depths, as `ClusterGrid::cluster_of_pixel` takes them.
    View(&'a [f32]),
    /// Depth-buffer values of `camera`'s projection, turned into view depth on the GPU exactly
    /// as the shading passes do (`view_depth_from_ndc_depth`, from its near plane and
    /// `Camera::near_over_far`).
    Stored {
        /// The stored depths.
        depths: &'a [f32],
        /// The camera that drew them (its depth range is what matters).
        camera: &'a Camera,
    },
}

/// The cluster id the GPU computes for each `(pixel, view depth)` sample on a `width × height`
/// target. Blocks until done. A sample off the target, an empty target, or one whose tile
/// arithmetic would pass u32 is a [`GpuError::InvalidInput`], as the renderer refuses them.
pub fn gpu_cluster_ids(
    ctx: &GpuContext,
    grid: &ClusterGrid,
    width: u32,
    height: u32,
    pixels: &[[u32; 2]],
    depths: &[f32],
) -> Result<Vec<u32>, GpuError> {
    gpu_cluster_ids_of(ctx, grid, width, height, pixels, SampleDepths::View(depths))
}

/// [`gpu_cluster_ids`] for view or stored depths ([`SampleDepths`]).
pub fn gpu_cluster_ids_of(
    ctx: &GpuContext,
    grid: &ClusterGrid,
    width: u32,
    height: u32,
    pixels: &[[u32; 2]],
    samples: SampleDepths<'_>,
) -> Result<Vec<u32>, GpuError> {
    let (depths, from_stored_depth, near_far) = match samples {
        SampleDepths::View(d) => (d, 0, [0.0; 4]),
        SampleDepths::Stored { depths, camera } => {
            (depths, 1, [camera.near, camera.near_over_far(), 0.0, 0.0])
        }
    };
    if pixels.len() != depths.len() || pixels.is_empty() {
        return Err(GpuError::InvalidInput(format!(
            "{} pixels and {} depths (need the same, non-zero count)",
            pixels.len(),
            depths.len()
        )));
    }
    // What the renderer checks of a frame before its shaders run this code: a target of at
    // least one pixel, `2 · pixels · tiles` in u32, and here also every sample on the target
    // (the shader's tile formula assumes it).
    let dims = grid.dims();
    if width == 0
        || height == 0
        || 2 * u64::from(width) * u64::from(dims.x) > u64::from(u32::MAX)
        || 2 * u64::from(height) * u64::from(dims.y) > u64::from(u32::MAX)
    {
        return Err(GpuError::InvalidInput(format!(
            "a {width}x{height} target with {}x{} tiles: need at least one pixel, and \
             2 · pixels · tiles within u32 along each side",
            dims.x, dims.y
        )));
    }
    if let Some(p) = pixels.iter().find(|p| p[0] >= width || p[1] >= height) {
        return Err(GpuError::InvalidInput(format!(
            "sample pixel {p:?} is off the {width}x{height} target"
        )));
    }
    let device = &ctx.device;
    let groups = check_pass::workgroups(ctx, pixels.len(), "samples")?;
    let mut edges = Vec::new();
    grid.fill_slice_edges(&mut edges);
    let uniforms = ClusterCheckUniforms {
        target_size: [width, height],
        sample_count: pixels.len() as u32,
        from_stored_depth,
        grid_dims: [grid.dims().x, grid.dims().y, grid.dims().z, 0],
        near_far,
    };
    let init =
        |label, contents: &[u8], usage| buffer_init(device, &ctx.queue, label, contents, usage);
    let storage = wgpu::BufferUsages::STORAGE;
    let params = init(
        "check params",
        bytemuck::bytes_of(&uniforms),
        wgpu::BufferUsages::UNIFORM,
    )?;
    let pixel_buffer = init("check pixels", bytemuck::cast_slice(pixels), storage)?;
    let depth_buffer = init("check depths", bytemuck::cast_slice(depths), storage)?;
    let edge_buffer = init("check edges", bytemuck::cast_slice(&edges), storage)?;
    let inputs = [&params, &pixel_buffer, &depth_buffer, &edge_buffer];
    let bytes = pixels.len() as u64 * 4;
    let data = check_pass::run(ctx, PassShader::ClusterIndexCheck, &inputs, bytes, groups)?;
    Ok(bytemuck::pod_collect_to_vec(&data))
}
