//! Reading the uploaded light lists back from the GPU: what the shading passes index, as the
//! device holds it — for a stress run or an engine's debug view to prove that the lists went
//! through the staging ring whole (`myriad stress` compares them with the CPU's, pair by pair).

use super::Renderer;
use crate::out_of_memory::catching;
use crate::readback::map_and_read;
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
        let clusters = uploaded.grid.cluster_count() as u64;
        let word = std::mem::size_of::<u32>() as u64;
        let sizes = [
            clusters * word,
            clusters * word,
            uploaded.pairs as u64 * word,
        ];
        // One read-back buffer, each array at a 4-byte-aligned offset (copies need that much).
        let total: u64 = sizes.iter().sum();
        let device = &ctx.device;
        let what = || format!("the lists' read-back buffer ({total} bytes)");
        let buffer = catching(device, what, || {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("lists read-back"),
                size: total.max(wgpu::COPY_BUFFER_ALIGNMENT),
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            })
        })?;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("lists read-back"),
        });
        let mut at = 0;
        for (source, size) in [&self.offsets, &self.counts, &self.indices]
            .into_iter()
            .zip(sizes)
        {
            if size > 0 {
                encoder.copy_buffer_to_buffer(source.buffer(), 0, &buffer, at, size);
            }
            at += size;
        }
        ctx.queue.submit([encoder.finish()]);
        let bytes = map_and_read(ctx, &buffer)?;
        let words: &[u32] = bytemuck::cast_slice(&bytes[..total as usize]);
        let (offsets, rest) = words.split_at(clusters as usize);
        let (counts, indices) = rest.split_at(clusters as usize);
        Ok(Some(ListsReadBack {
            offsets: offsets.to_vec(),
            counts: counts.to_vec(),
            indices: indices.to_vec(),
        }))
    }
}
