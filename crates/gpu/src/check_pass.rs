//! The compute passes that run one WGSL function over many inputs for a test
//! ([`crate::cluster_check`], [`crate::lighting_check`]): inputs bound in order, one output bound
//! after them, `cs_main` dispatched in workgroups of 64, the output read back.

use crate::out_of_memory::catching;
use crate::readback::{map_and_read, readback_buffer};
use crate::shaders::PassShader;
use crate::{GpuContext, GpuError};

/// The workgroups for `items` invocations of 64 each, or [`GpuError::InvalidInput`] when there
/// are none or more than one dispatch holds.
pub(crate) fn workgroups(ctx: &GpuContext, items: usize, what: &str) -> Result<u32, GpuError> {
    let groups = (items as u64).div_ceil(64);
    let max_groups = u64::from(ctx.device.limits().max_compute_workgroups_per_dimension);
    if items == 0 {
        return Err(GpuError::InvalidInput(format!("no {what} to run")));
    }
    if groups > max_groups {
        return Err(GpuError::InvalidInput(format!(
            "{items} {what} need {groups} workgroups, more than the {max_groups} of one dispatch"
        )));
    }
    Ok(groups as u32)
}

/// Whether `bytes` of `what` fit one storage binding on the device, else
/// [`GpuError::InvalidInput`] (wgpu would panic on the binding).
pub(crate) fn check_binding(ctx: &GpuContext, bytes: u64, what: &str) -> Result<(), GpuError> {
    let limit = crate::buffers::storage_capacity(&ctx.device.limits());
    if bytes > limit {
        return Err(GpuError::InvalidInput(format!(
            "{what}: {bytes} bytes, more than one storage binding holds on this device ({limit})"
        )));
    }
    Ok(())
}

/// Runs `shader`'s `cs_main` over `groups` workgroups with `inputs` at bindings `0..n` and an
/// output of `out_bytes` at binding `n`; returns the output's bytes. Blocks until done.
pub(crate) fn run(
    ctx: &GpuContext,
    shader: PassShader,
    inputs: &[&wgpu::Buffer],
    out_bytes: u64,
    groups: u32,
) -> Result<Vec<u8>, GpuError> {
    let device = &ctx.device;
    let label = shader.file_name();
    let what = || format!("the output of {label} ({out_bytes} bytes)");
    let out = catching(device, what, || {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: out_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })
    })?;
    let readback = readback_buffer(device, out_bytes, what)?;
    let module = shader.module(device);
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: None,
        module: &module,
        entry_point: Some("cs_main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let entries: Vec<wgpu::BindGroupEntry<'_>> = inputs
        .iter()
        .copied()
        .chain([&out])
        .enumerate()
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding: binding as u32,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(groups, 1, 1);
    }
    encoder.copy_buffer_to_buffer(&out, 0, &readback, 0, out_bytes);
    ctx.queue.submit([encoder.finish()]);
    map_and_read(ctx, &readback)
}
