//! GPU pass times from timestamp queries, where the device has them.
//!
//! Each pass writes a timestamp at its start and end; the pairs are resolved into a buffer and
//! copied to a mappable one in the same submission. [`PassTimer::read`] maps it after the GPU
//! is done. Without `TIMESTAMP_QUERY` the timer does nothing and times are `None`.
//!
//! The upload's copies (staging ring → storage buffers) are not a pass: they are timed by
//! timestamps written into the encoder before and after them, which needs
//! `TIMESTAMP_QUERY_INSIDE_ENCODERS` too. Without it, or in a frame that copied nothing, the
//! upload time is `None`; what the CPU spends staging is `FrameReport::upload_seconds` either way.
//!
//! With the `tracy` feature, reading a frame's times also hands them to Tracy as GPU zones
//! (`tracy_zones.rs`), each pass once.

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
/// Query slots: a pair per pass, then the upload's pair.
const UPLOAD_QUERY: u32 = PASSES * 2;
const QUERIES: u32 = UPLOAD_QUERY + 2;

/// GPU milliseconds per pass (`None` for a pass that did not run).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassTimes {
    /// G-buffer pass.
    pub gbuffer_ms: Option<f64>,
    /// Shading pass.
    pub shading_ms: Option<f64>,
    /// Forward pass.
    pub forward_ms: Option<f64>,
    /// The upload's buffer copies (`None` without `TIMESTAMP_QUERY_INSIDE_ENCODERS`, or when the
    /// frame copied nothing).
    pub upload_ms: Option<f64>,
}

impl PassTimes {
    /// Sum of the GPU work that was timed: the passes that ran and the upload's copies.
    pub fn total_ms(&self) -> f64 {
        [
            self.gbuffer_ms,
            self.shading_ms,
            self.forward_ms,
            self.upload_ms,
        ]
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
    /// Whether timestamps may be written between commands (the upload's pair).
    inside_encoders: bool,
    /// Whether this frame's upload wrote its pair (and copied something).
    uploaded: bool,
    /// The Tracy GPU zones, and which of this frame's were emitted (a mutex: reading takes
    /// `&self`, and the renderer stays `Sync`).
    #[cfg(feature = "tracy")]
    zones: std::sync::Mutex<ZoneState>,
}

/// The renderer's Tracy GPU context and which of the frame's timed pieces are zones already.
#[cfg(feature = "tracy")]
#[derive(Debug, Default)]
struct ZoneState {
    zones: crate::tracy_zones::GpuZones,
    handed: Handed,
}

/// One timed piece of a frame for Tracy: which (`None`: the upload's copies), and its start and
/// end ticks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(not(feature = "tracy"), allow(dead_code))] // Built without the feature for its test.
pub(crate) struct TimedZone {
    pub pass: Option<TimedPass>,
    pub start: u64,
    pub end: u64,
}

/// Which of a frame's timed pieces were handed to Tracy already: each once, however often the
/// frame's times are read.
#[derive(Debug, Default)]
#[cfg_attr(not(feature = "tracy"), allow(dead_code))] // Built without the feature for its test.
struct Handed {
    passes: [bool; PASSES as usize],
    upload: bool,
}

#[cfg_attr(not(feature = "tracy"), allow(dead_code))]
impl Handed {
    /// The pieces of this frame that ran (`ran` per pass, `uploaded`) and are not handed over
    /// yet, each with its pair of `ticks` (the resolved queries, in query order), now marked as
    /// handed. At most the three passes and the upload: on the stack, no allocation per read.
    /// Returns them and how many there are.
    fn take_new(
        &mut self,
        ran: &[bool; PASSES as usize],
        uploaded: bool,
        ticks: &[u64],
    ) -> ([TimedZone; PASSES as usize + 1], usize) {
        let mut zones = [TimedZone {
            pass: None,
            start: 0,
            end: 0,
        }; PASSES as usize + 1];
        let mut n = 0;
        for pass in [TimedPass::GBuffer, TimedPass::Shading, TimedPass::Forward] {
            let i = pass as usize;
            if ran[i] && !self.passes[i] {
                self.passes[i] = true;
                zones[n] = TimedZone {
                    pass: Some(pass),
                    start: ticks[2 * i],
                    end: ticks[2 * i + 1],
                };
                n += 1;
            }
        }
        if uploaded && !self.upload {
            self.upload = true;
            let i = UPLOAD_QUERY as usize;
            zones[n] = TimedZone {
                pass: None,
                start: ticks[i],
                end: ticks[i + 1],
            };
            n += 1;
        }
        (zones, n)
    }
}

impl PassTimer {
    pub fn new(ctx: &GpuContext) -> Self {
        let queries = ctx.has_timestamps().then(|| {
            let bytes = QUERIES as u64 * 8;
            Queries {
                set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pass timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: QUERIES,
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
            inside_encoders: ctx.has_encoder_timestamps(),
            uploaded: false,
            #[cfg(feature = "tracy")]
            zones: Default::default(),
        }
    }

    /// Tracy GPU zones emitted so far (`tracy` feature).
    #[cfg(feature = "tracy")]
    pub fn zones_emitted(&self) -> u64 {
        self.zones.lock().expect("zone state").zones.emitted()
    }

    /// How often the Tracy GPU context's clock was tied to the CPU's (`tracy` feature).
    #[cfg(feature = "tracy")]
    pub fn clock_ties(&self) -> u64 {
        self.zones.lock().expect("zone state").zones.clock_ties()
    }

    /// Whether Tracy refused a GPU context (`tracy` feature).
    #[cfg(feature = "tracy")]
    pub fn context_refused(&self) -> bool {
        self.zones.lock().expect("zone state").zones.refused()
    }

    /// Marks a new frame: no pass has run and nothing was uploaded yet, except the G-buffer
    /// pass when `keep_gbuffer` (a frame shading the G-buffer a prepass drew and timed).
    pub fn begin_frame(&mut self, keep_gbuffer: bool) {
        let gbuffer = keep_gbuffer && self.ran[TimedPass::GBuffer as usize];
        self.ran = [false; PASSES as usize];
        self.ran[TimedPass::GBuffer as usize] = gbuffer;
        self.uploaded = false;
        #[cfg(feature = "tracy")]
        {
            // A kept G-buffer's zone was its prepass's.
            let handed = &mut self.zones.get_mut().expect("zone state").handed;
            let kept = gbuffer && handed.passes[TimedPass::GBuffer as usize];
            handed.passes = [false; PASSES as usize];
            handed.passes[TimedPass::GBuffer as usize] = kept;
            handed.upload = false;
        }
    }

    /// Writes the timestamp before the upload's copies (where the device allows it).
    pub fn upload_start(&self, encoder: &mut wgpu::CommandEncoder) {
        if let (Some(q), true) = (&self.queries, self.inside_encoders) {
            encoder.write_timestamp(&q.set, UPLOAD_QUERY);
        }
    }

    /// Writes the timestamp after the upload's copies; `copied` says whether there were any.
    pub fn upload_end(&mut self, encoder: &mut wgpu::CommandEncoder, copied: bool) {
        if let (Some(q), true) = (&self.queries, self.inside_encoders) {
            encoder.write_timestamp(&q.set, UPLOAD_QUERY + 1);
            self.uploaded = copied;
        }
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
            // The upload's pair only where it is written (no device sees an unwritten query
            // it did not see before this pair existed).
            let used = if self.inside_encoders {
                QUERIES
            } else {
                UPLOAD_QUERY
            };
            encoder.resolve_query_set(&q.set, 0..used, &q.resolve, 0);
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
        let between =
            |first: usize| ticks[first + 1].saturating_sub(ticks[first]) as f64 * period_ns / 1e6;
        let ms = |pass: TimedPass| {
            let i = pass as usize;
            self.ran[i].then(|| between(2 * i))
        };
        #[cfg(feature = "tracy")]
        self.emit_zones(ctx, ticks)?;
        Ok(Some(PassTimes {
            gbuffer_ms: ms(TimedPass::GBuffer),
            shading_ms: ms(TimedPass::Shading),
            forward_ms: ms(TimedPass::Forward),
            upload_ms: self.uploaded.then(|| between(UPLOAD_QUERY as usize)),
        }))
    }

    /// Hands this frame's timed pieces not yet handed over to Tracy as GPU zones.
    #[cfg(feature = "tracy")]
    fn emit_zones(&self, ctx: &GpuContext, ticks: &[u64]) -> Result<(), GpuError> {
        let mut state = self.zones.lock().expect("zone state");
        let (mut zones, n) = state.handed.take_new(&self.ran, self.uploaded, ticks);
        state.zones.emit(ctx, &mut zones[..n])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each piece becomes a zone with its own pair of ticks (pass `p` at queries `2p`, `2p + 1`,
    /// the upload at the pair after the passes'), in pass order then the upload, and each only
    /// once: a second read of the same frame hands over nothing, a piece that ran later in the
    /// frame only itself. Ticks are all different, so a pair taken from the wrong slots, or its
    /// start and end swapped, shows.
    #[test]
    fn each_piece_is_handed_once_with_its_own_ticks() {
        let ticks: Vec<u64> = (0..QUERIES as u64).map(|q| 1000 + 37 * q * q).collect();
        let zone = |pass: Option<TimedPass>, first: usize| TimedZone {
            pass,
            start: ticks[first],
            end: ticks[first + 1],
        };
        let mut handed = Handed::default();
        let (zones, n) = handed.take_new(&[true, true, false], true, &ticks);
        assert_eq!(
            zones[..n],
            [
                zone(Some(TimedPass::GBuffer), 0),
                zone(Some(TimedPass::Shading), 2),
                zone(None, UPLOAD_QUERY as usize),
            ]
        );
        assert_eq!(handed.take_new(&[true, true, false], true, &ticks).1, 0);
        let (zones, n) = handed.take_new(&[true, true, true], true, &ticks);
        assert_eq!(zones[..n], [zone(Some(TimedPass::Forward), 4)]);
        let mut fresh = Handed::default();
        let (zones, n) = fresh.take_new(&[false, false, true], false, &ticks);
        assert_eq!(zones[..n], [zone(Some(TimedPass::Forward), 4)]);
    }
}
