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
//! written by an empty compute pass, waited for, then handed to `Client::new_gpu_context`), and
//! tied again (`GpuContext::sync_gpu_time`) before emitting
//! zones once [`TIE_INTERVAL`] has passed since the last tie, or at once when a zone starts
//! before the last one emitted ended: the GPU clock went back, as GPUs that reset it in a
//! low-power state do (Tracy's docs name AMD's). Without it a long capture's GPU track drifts off
//! the CPU's timeline, or jumps, after such a reset. Why once a second and not every frame: each
//! tie is a submission the CPU waits for; zones are emitted where a frame's times were just
//! waited for (the GPU is idle then), so a tie a second costs the frame loop one short wait a
//! second, and a drift of a few parts per million stays under a microsecond between ties.
//!
//! Where a tie puts the two clocks: Tracy pairs the GPU time it is given with its CPU clock at
//! the call, which comes after the timestamp's read-back. Handing it the raw timestamp (what
//! Tracy's own Vulkan context does without calibrated timestamps) puts the GPU track late by the
//! whole wait — submission, the GPU's write, the copy and the mapping. The GPU wrote the
//! timestamp somewhere within that wait, so the tie takes the middle of it as the write's CPU
//! time and hands Tracy the timestamp moved on from there to the call ([`ClockReading`]): off by
//! half the wait at most, and by nothing on average.

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
    /// Tracy refused a context (its 255 a process are taken): no zones from this renderer, and
    /// no more tries (each read the GPU clock, three blocking round trips, every frame).
    refused: bool,
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

    /// Whether Tracy refused the context.
    pub fn refused(&self) -> bool {
        self.refused
    }

    /// Emits `zones` (the upload's copies when `pass` is `None`) in order of their start, once a
    /// client runs; nothing otherwise.
    pub fn emit(&mut self, ctx: &GpuContext, zones: &mut [TimedZone]) -> Result<(), GpuError> {
        let Some(client) = Client::running() else {
            return Ok(());
        };
        if zones.is_empty() || self.refused {
            return Ok(());
        }
        // Tracy wants the timestamps in increasing order.
        zones.sort_unstable_by_key(|z| z.start);
        let period = ctx.queue.get_timestamp_period();
        if self.context.is_none() {
            let now = gpu_timestamp_now(ctx)?.ticks_at(Instant::now(), period);
            let kind = match ctx.adapter_info.backend {
                wgpu::Backend::Vulkan => GpuContextType::Vulkan,
                wgpu::Backend::Dx12 => GpuContextType::Direct3D12,
                wgpu::Backend::Gl => GpuContextType::OpenGL,
                _ => GpuContextType::Invalid,
            };
            // Tracy allows 255 contexts a process; past them the frame goes without zones.
            match client.new_gpu_context(Some("myriad renderer"), kind, now, period) {
                Ok(context) => self.context = Some(context),
                Err(_) => {
                    self.refused = true;
                    return Ok(());
                }
            }
            self.tied(Instant::now());
        } else if let Some(context) = &self.context {
            let since = self.tied_at.map(|at| at.elapsed());
            if tie_due(since, self.last_end, zones[0].start) {
                let reading = gpu_timestamp_now(ctx)?;
                context.sync_gpu_time(reading.ticks_at(Instant::now(), period));
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

/// A GPU timestamp read back, and the CPU instants that bound when the GPU wrote it.
#[derive(Clone, Copy, Debug)]
struct ClockReading {
    ticks: u64,
    submitted: Instant,
    read: Instant,
}

impl ClockReading {
    /// The GPU clock's reading at `at` (not before [`Self::read`]), in ticks of `period`
    /// nanoseconds: the timestamp moved on from the middle of its submission and read-back to
    /// `at`. Saturates at `i64::MAX` (Tracy takes signed ticks).
    fn ticks_at(&self, at: Instant, period: f32) -> i64 {
        let written = self.submitted + self.read.saturating_duration_since(self.submitted) / 2;
        let since_ns = at.saturating_duration_since(written).as_nanos() as f64;
        let on = (since_ns / f64::from(period.max(f32::MIN_POSITIVE))).round() as u64;
        self.ticks.saturating_add(on).min(i64::MAX as u64) as i64
    }
}

/// How many readings a tie takes, keeping the one read back soonest after its submission.
const TIE_READINGS: usize = 3;

/// The GPU clock now, as precisely as [`TIE_READINGS`] readings give it: the one with the
/// shortest wait, whose middle is the nearest to when the GPU wrote it. One reading was not
/// enough: the device's first timestamp submission waited ~3 ms on llvmpipe, and the tie taken
/// from it put a frame's GPU zones 1.5 ms after that frame's wait had ended, on the CPU's
/// timeline (`tests/tracy_capture`, 2 runs of 17).
fn gpu_timestamp_now(ctx: &GpuContext) -> Result<ClockReading, GpuError> {
    let mut best = gpu_timestamp_once(ctx)?;
    for _ in 1..TIE_READINGS {
        let reading = gpu_timestamp_once(ctx)?;
        if reading.read - reading.submitted < best.read - best.submitted {
            best = reading;
        }
    }
    Ok(best)
}

/// One reading of the GPU clock: a timestamp written at the start of an empty compute pass,
/// waited for.
fn gpu_timestamp_once(ctx: &GpuContext) -> Result<ClockReading, GpuError> {
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
    let submitted = Instant::now();
    ctx.queue.submit([encoder.finish()]);
    let bytes = map_and_read(ctx, &readback)?;
    Ok(ClockReading {
        ticks: u64::from_le_bytes(bytes[..8].try_into().expect("8 bytes")),
        submitted,
        read: Instant::now(),
    })
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

    #[test]
    fn a_tie_moves_the_timestamp_on_from_the_middle_of_its_wait() {
        let submitted = Instant::now();
        let reading = ClockReading {
            ticks: 1_000,
            submitted,
            read: submitted + Duration::from_micros(100),
        };
        let ms = |n| submitted + Duration::from_micros(n);
        // Written at 50 µs (the wait's middle); at the read, 50 µs on: 50,000 ns of 1 ns ticks.
        assert_eq!(reading.ticks_at(ms(100), 1.0), 51_000);
        // 30 µs later, with ticks of 10 ns: 80 µs = 8,000 ticks on.
        assert_eq!(reading.ticks_at(ms(130), 10.0), 9_000);
        // Exact in integer ticks past 2^53 (a clock running for years); never before the write,
        // whatever `at` is; a huge reading saturates.
        let late = ClockReading {
            ticks: (1 << 60) + 1,
            ..reading
        };
        assert_eq!(late.ticks_at(ms(100), 1.0), (1 << 60) + 50_001);
        assert_eq!(reading.ticks_at(submitted, 1.0), 1_000);
        let huge = ClockReading {
            ticks: u64::MAX,
            ..reading
        };
        assert_eq!(huge.ticks_at(ms(100), 1.0), i64::MAX);
    }
}
