//! GPU pass times from timestamp queries, where the device has them.
//!
//! Each pass writes a timestamp at its start and end; the pairs are resolved into a buffer and
//! copied to a mappable one in the same submission. [`PassTimer::read`] maps it after the GPU
//! is done. Without `TIMESTAMP_QUERY` the timer does nothing and times are `None`.

use crate::readback::map_and_read;
use crate::{GpuContext, GpuError};

/// The timed passes, in query order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimedPass {
    /// The G-buffer pass.
    GBuffer = 0,
    /// Full-screen deferred shading (or the heat map).
    Shading = 1,
    /// The forward pass for blended geometry.
    Forward = 2,
}

const PASSES: u32 = 3;

/// GPU milliseconds per pass (`None` for a pass that did not run).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassTimes {
    /// G-buffer pass.
    pub gbuffer_ms: Option<f64>,
    /// Shading pass.
    pub shading_ms: Option<f64>,
    /// Forward pass.
    pub forward_ms: Option<f64>,
}

impl PassTimes {
    /// Sum of the passes that ran.
    pub fn total_ms(&self) -> f64 {
        [self.gbuffer_ms, self.shading_ms, self.forward_ms]
            .into_iter()
            .flatten()
            .sum()
    }
}

#[derive(Debug)]
struct Queries {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
}

/// Timestamp queries for the frame's passes.
#[derive(Debug)]
pub(crate) struct PassTimer {
    queries: Option<Queries>,
    ran: [bool; PASSES as usize],
}

impl PassTimer {
    pub fn new(ctx: &GpuContext) -> Self {
        let queries = ctx.has_timestamps().then(|| {
            let bytes = PASSES as u64 * 2 * 8;
            Queries {
                set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pass timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: PASSES * 2,
                }),
                resolve: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamp resolve"),
                    size: bytes,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
                readback: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamp readback"),
                    size: bytes,
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                    mapped_at_creation: false,
                }),
            }
        });
        Self {
            queries,
            ran: [false; PASSES as usize],
        }
    }

    /// Marks a new frame: no pass has run yet.
    pub fn begin_frame(&mut self) {
        self.ran = [false; PASSES as usize];
    }

    /// The timestamp writes for `pass` (and records that it ran).
    pub fn writes(&mut self, pass: TimedPass) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        self.ran[pass as usize] = true;
        self.queries
            .as_ref()
            .map(|q| wgpu::RenderPassTimestampWrites {
                query_set: &q.set,
                beginning_of_pass_write_index: Some(pass as u32 * 2),
                end_of_pass_write_index: Some(pass as u32 * 2 + 1),
            })
    }

    /// Resolves this frame's queries into the read-back buffer.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(q) = &self.queries {
            encoder.resolve_query_set(&q.set, 0..PASSES * 2, &q.resolve, 0);
            encoder.copy_buffer_to_buffer(&q.resolve, 0, &q.readback, 0, q.resolve.size());
        }
    }

    /// The last frame's pass times; waits for the GPU. `None` without timestamp support.
    pub fn read(&self, ctx: &GpuContext) -> Result<Option<PassTimes>, GpuError> {
        let Some(q) = &self.queries else {
            return Ok(None);
        };
        let bytes = map_and_read(ctx, &q.readback)?;
        let ticks: &[u64] = bytemuck::cast_slice(&bytes);
        let period_ns = ctx.queue.get_timestamp_period() as f64;
        let ms = |pass: TimedPass| {
            let i = pass as usize;
            self.ran[i]
                .then(|| ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * period_ns / 1e6)
        };
        Ok(Some(PassTimes {
            gbuffer_ms: ms(TimedPass::GBuffer),
            shading_ms: ms(TimedPass::Shading),
            forward_ms: ms(TimedPass::Forward),
        }))
    }
}
