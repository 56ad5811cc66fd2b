//! Reading the uploaded light lists back from the GPU: what the shading passes index, as the
//! device holds it — for a stress run or an engine's debug view to prove that the lists went
//! through the staging ring whole (`myriad stress` compares them with the CPU's, pair by pair).

use super::Renderer;
use crate::readback::{map_and_read_with, readback_buffer};
use crate::{ClusterLists, GpuContext, GpuError};

/// A copy of the lists on the GPU ([`Renderer::read_back_lists`]), CSR as uploaded.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ListsReadBack {
    /// Each cluster's first index.
    pub offsets: Vec<u32>,
    /// Each cluster's light count.
    pub counts: Vec<u32>,
    /// The light indices.
    pub indices: Vec<u32>,
}

impl ListsReadBack {
    /// The copy as [`ClusterLists`], to compare with (or upload as) the lists it came from.
    pub fn lists(&self) -> ClusterLists<'_> {
        ClusterLists {
            offsets: &self.offsets,
            counts: &self.counts,
            indices: &self.indices,
        }
    }
}

impl Renderer {
    /// The lists the last upload left on the GPU (kept by later frames that upload none); `None`
    /// when there are none (before the first, or after a frame that ran out of memory). Waits for
    /// the GPU.
    pub fn read_back_lists(&self, ctx: &GpuContext) -> Result<Option<ListsReadBack>, GpuError> {
        self.check_device(ctx, None)?;
        let Some(uploaded) = self.lists_uploaded else {
            return Ok(None);
        };
        let word = std::mem::size_of::<u32>() as u64;
        let clusters = uploaded.grid.cluster_count() as u64;
        let arrays = [
            (&self.offsets, clusters * word),
            (&self.counts, clusters * word),
            (&self.indices, uploaded.pairs as u64 * word),
        ];
        // A read-back buffer per array: each is no larger than the buffer it copies, so within
        // the device's buffer limit (one for all three could pass it).
        let device = &ctx.device;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("lists read-back"),
        });
        let mut copies = Vec::with_capacity(arrays.len());
        for (source, bytes) in arrays {
            let what = || format!("the read-back of the {} ({bytes} bytes)", source.label());
            let copy = readback_buffer(device, bytes, what)?;
            if bytes > 0 {
                encoder.copy_buffer_to_buffer(source.buffer(), 0, &copy, 0, bytes);
            }
            copies.push((copy, bytes as usize));
        }
        ctx.queue.submit([encoder.finish()]);
        // Each array copied straight out of its mapping (`pod_collect_to_vec` whatever the
        // mapping's alignment).
        let mut read = copies.iter().map(|(copy, bytes)| {
            map_and_read_with(ctx, copy, |mapped| {
                bytemuck::pod_collect_to_vec::<u8, u32>(&mapped[..*bytes])
            })
        });
        let mut next = || read.next().expect("three arrays");
        Ok(Some(ListsReadBack {
            offsets: next()?,
            counts: next()?,
            indices: next()?,
        }))
    }
}
