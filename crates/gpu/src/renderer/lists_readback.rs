//! Reading the uploaded light lists back from the GPU: what the shading passes index, as the
//! device holds it — for a stress run or an engine's debug view to prove that the lists went
//! through the staging ring whole (`myriad stress` compares them with the CPU's, pair by pair).

use super::Renderer;
use crate::out_of_memory::catching;
use crate::readback::map_and_read_with;
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
        let starts = [0, sizes[0], sizes[0] + sizes[1]];
        let sources = [&self.offsets, &self.counts, &self.indices];
        for ((source, start), size) in sources.into_iter().zip(starts).zip(sizes) {
            if size > 0 {
                encoder.copy_buffer_to_buffer(source.buffer(), 0, &buffer, start, size);
            }
        }
        ctx.queue.submit([encoder.finish()]);
        // Each array copied straight out of the mapping (`pod_collect_to_vec` whatever the
        // mapping's alignment).
        let read = |bytes: &[u8]| {
            let [offsets, counts, indices] = [0, 1, 2].map(|i| {
                let range = starts[i] as usize..(starts[i] + sizes[i]) as usize;
                bytemuck::pod_collect_to_vec::<u8, u32>(&bytes[range])
            });
            ListsReadBack {
                offsets,
                counts,
                indices,
            }
        };
        Ok(Some(map_and_read_with(ctx, &buffer, read)?))
    }
}
