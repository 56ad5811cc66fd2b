//! The frame's GPU passes as Tracy GPU zones (the `tracy` feature), on a GPU track beside the
//! CPU's spans, so a profile shows where the GPU works while the CPU assigns the next frame.
//!
//! Why the zones are emitted when the timestamps are read, not when the passes are encoded: a
//! zone whose timestamps never arrive stalls Tracy's GPU track, and a frame's timestamps are
//! only read when someone asks for them (`Renderer::last_pass_times`, which waits for the GPU;
//! the pipelined loop and `myriad render`'s timed frames do every frame). Emitting at read time
//! gives every zone its timestamps at once, and frames nobody reads leave no zone. Each pass's
//! zone is emitted once, however often its times are read. The cost is the zones' CPU-side
//! times (the read, not the encoding): Tracy's GPU track draws the GPU's own timestamps.
//!
//! The GPU clock is tied to the CPU's when a renderer's first zones are emitted (a timestamp
//! written by an empty compute pass, waited for, then handed to `Client::new_gpu_context` — off by
//! the wait's latency at most), and tied again (`GpuContext::sync_gpu_time`) before emitting
//! zones once [`TIE_INTERVAL`] has passed since the last tie, or at once when a zone starts
//! before the last one emitted ended: the GPU clock went back, as GPUs that reset it in a
//! low-power state do (Tracy's docs name AMD's). Without it a long capture's GPU track drifts off
//! the CPU's timeline, or jumps, after such a reset. Why once a second and not every frame: each
//! tie is a submission the CPU waits for; zones are emitted where a frame's times were just
//! waited for (the GPU is idle then), so a tie a second costs the frame loop one short wait a
//! second, and a drift of a few parts per million stays under a microsecond between ties.

use crate::readback::map_and_read;
use crate::timing::{TimedPass, TimedZone};
use crate::{GpuContext, GpuError};
use std::time::{Duration, Instant};
use tracy_client::{Client, GpuContextType, span_location};

/// How long the GPU clock goes without being tied to the CPU's again, while zones are emitted.
pub(crate) const TIE_INTERVAL: Duration = Duration::from_secs(1);

/// The renderer's Tracy GPU context, once a client runs and a frame's times are read.
#[derive(Default)]
pub(crate) struct GpuZones {
    context: Option<tracy_client::GpuContext>,
    emitted: u64,
    /// When the GPU clock was last tied to the CPU's, and how often it was.
    tied_at: Option<Instant>,
    ties: u64,
    /// The end tick of the last zone emitted.
    last_end: u64,
}

impl std::fmt::Debug for GpuZones {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuZones")
            .field("context", &self.context.is_some())
            .field("emitted", &self.emitted)
            .field("ties", &self.ties)
            .finish()
    }
}

impl GpuZones {
    /// Zones emitted so far.
    pub fn emitted(&self) -> u64 {
        self.emitted
    }

    /// How often the GPU clock was tied to the CPU's: when the context was made, then again.
    pub fn clock_ties(&self) -> u64 {
        self.ties
    }

    /// Emits `zones` (the upload's copies when `pass` is `None`) in order of their start, once a
    /// client runs; nothing otherwise.
    pub fn emit(&mut self, ctx: &GpuContext, zones: &mut [TimedZone]) -> Result<(), GpuError> {
        let Some(client) = Client::running() else {
            return Ok(());
        };
        if zones.is_empty() {
            return Ok(());
        }
        // Tracy wants the timestamps in increasing order.
        zones.sort_unstable_by_key(|z| z.start);
        if self.context.is_none() {
            let now = gpu_timestamp_now(ctx)?;
            let period = ctx.queue.get_timestamp_period();
            let kind = match ctx.adapter_info.backend {
                wgpu::Backend::Vulkan => GpuContextType::Vulkan,
                wgpu::Backend::Dx12 => GpuContextType::Direct3D12,
                wgpu::Backend::Gl => GpuContextType::OpenGL,
                _ => GpuContextType::Invalid,
            };
            // Tracy allows 255 contexts a process; past them the frame goes without zones.
            match client.new_gpu_context(Some("myriad renderer"), kind, now as i64, period) {
                Ok(context) => self.context = Some(context),
                Err(_) => return Ok(()),
            }
            self.tied(Instant::now());
        } else if let Some(context) = &self.context {
            let since = self.tied_at.map(|at| at.elapsed());
            if tie_due(since, self.last_end, zones[0].start) {
                context.sync_gpu_time(gpu_timestamp_now(ctx)? as i64);
                self.tied(Instant::now());
            }
        }
        let Some(context) = &self.context else {
            return Ok(());
        };
        for &mut zone in zones {
            let location = match zone.pass {
                None => span_location!("GPU: upload copies"),
                Some(TimedPass::GBuffer) => span_location!("GPU: G-buffer pass"),
                Some(TimedPass::Shading) => span_location!("GPU: shading pass"),
                Some(TimedPass::Forward) => span_location!("GPU: forward pass"),
            };
            // Over 32767 spans awaiting their timestamps at once: none await here, so never.
            let Ok(mut span) = context.span(location) else {
                continue;
            };
            span.end_zone();
            span.upload_timestamp_start(zone.start as i64);
            span.upload_timestamp_end(zone.end.max(zone.start) as i64);
            self.emitted += 1;
            self.last_end = self.last_end.max(zone.end);
        }
        Ok(())
    }

    fn tied(&mut self, at: Instant) {
        self.tied_at = Some(at);
        self.ties += 1;
        // A tie starts a new timeline: the zones before it no longer bound the next ones.
        self.last_end = 0;
    }
}

/// Whether the GPU clock is tied again before emitting zones from `first_start` on: when
/// [`TIE_INTERVAL`] has passed since the last tie (`since`, `None`: never tied), or the clock went
/// back (the first zone starts before the last emitted ended at `last_end`).
fn tie_due(since: Option<Duration>, last_end: u64, first_start: u64) -> bool {
    since.is_none_or(|since| since >= TIE_INTERVAL) || first_start < last_end
}

/// The GPU clock now: a timestamp written at the start of an empty compute pass, waited for.
fn gpu_timestamp_now(ctx: &GpuContext) -> Result<u64, GpuError> {
    let device = &ctx.device;
    let set = device.create_query_set(&wgpu::QuerySetDescriptor {
        label: Some("tracy clock"),
        ty: wgpu::QueryType::Timestamp,
        count: 1,
    });
    let buffer = |usage| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tracy clock"),
            size: 8,
            usage,
            mapped_at_creation: false,
        })
    };
    let resolve = buffer(wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC);
    let readback = buffer(wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ);
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("tracy clock"),
    });
    drop(encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some("tracy clock"),
        timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
            query_set: &set,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: None,
        }),
    }));
    encoder.resolve_query_set(&set, 0..1, &resolve, 0);
    encoder.copy_buffer_to_buffer(&resolve, 0, &readback, 0, 8);
    ctx.queue.submit([encoder.finish()]);
    let bytes = map_and_read(ctx, &readback)?;
    Ok(u64::from_le_bytes(bytes[..8].try_into().expect("8 bytes")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_clock_is_tied_again_after_the_interval_or_when_it_went_back() {
        let just = Some(Duration::from_millis(5));
        // Never tied, or the interval passed: tie.
        assert!(tie_due(None, 0, 10));
        assert!(tie_due(Some(TIE_INTERVAL), 100, 200));
        assert!(tie_due(Some(TIE_INTERVAL * 3), 100, 200));
        // Within the interval and the clock moving on (a zone may start where the last ended).
        assert!(!tie_due(just, 100, 200));
        assert!(!tie_due(just, 100, 100));
        assert!(!tie_due(Some(TIE_INTERVAL - Duration::from_nanos(1)), 0, 0));
        // The clock went back: tie now.
        assert!(tie_due(just, 100, 99));
        assert!(tie_due(just, u64::MAX, 0));
    }
}
