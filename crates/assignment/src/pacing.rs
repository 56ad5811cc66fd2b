//! Whether a frame runs its tasks on the pool or on the calling thread, decided from when the
//! previous frame of the same [`crate::Assigner`] ended and how much work it was.
//!
//! A parallel frame only pays off if the pool's other workers join it promptly. Between frames
//! they go to sleep, and a sleeping worker (on the 2-vCPU CI machine, one whose vCPU the host has
//! parked) arrives late. Timed with the calling thread busy for 5 ms before each call while the
//! other worker idles (`myriad bench --idle-us 5000 --busy`, 301 calls, three interleaved runs),
//! running every split frame on the pool (`--always-parallel`) against pacing it:
//! * `paper` 1000 `binary` 57.7–77.4 µs against 48.4–48.9 µs; `refined` 82.6–113.4 against
//!   65.7–66.9 µs — one thread's times: two threads were *slower* than one;
//! * `sphere` 1000 `binary` 14.8–19.3 against 6.2–7.0 µs; `uniform` 2000 `refined` 71.5–81.8
//!   against 62.4–67.9 µs;
//! * about 250 µs of work is where a late worker stops costing more than it saves (an earlier
//!   per-call probe: `uniform` 8000, 240 µs serially, ran 228 µs on two threads after idle;
//!   32 000 lights ran 1.6× faster).
//!
//! With the whole process asleep between calls (`--idle-us 2000` without `--busy`) every frame
//! ran 1.5–3× slower than warm and the two choices were within the noise of each other (`paper`
//! 1000 `refined` medians 120–206 µs paced, 110–124 µs always; `sphere` 1000 `binary` 7–10
//! against 11–24 µs). Frames called back to back gain 1.8× on the pool (`paper` 1000 `binary`
//! 26.5 against 46.5 µs) and keep it. So a frame runs in parallel when:
//! * it is this assigner's first, or
//! * the previous one ended less than [`WARM_GAP`] ago: calls come back to back, the workers are
//!   awake (or, after a serial frame, worth waking for the frames that follow), or
//! * this one is expected to be big: the previous frame's work (wall time × the threads it could
//!   use), scaled by this frame's light count over that frame's, is at least
//!   [`COLD_PARALLEL_WORK`] — enough for a late worker still to help. Scaling matters where the
//!   count jumps: an engine's 100k-light frame after a 100-light one ran serially when the rule
//!   read the previous frame's work alone (audit: 5.7 ms against 4.3 ms on the pool, 2 threads);
//!   a previous frame of no lights gives no estimate, and the frame runs on the pool.
//!
//! Only *whether the tasks run on the pool* changes, never how the lights are split into tasks
//! (`plan_tasks`), so the lists are identical either way (as they are for any thread count).

use std::time::{Duration, Instant};

/// Calls closer together than this find the workers still awake. Measured on the CI machine with
/// `paper` 1000 `binary` on the pool, the calling thread busy in between (a per-call probe, as
/// `myriad bench --idle-us N --busy --always-parallel`): 26.3 µs after 5 µs of idle, 40.0 µs
/// after 20 µs, 50.7 µs after 50 µs (serial: 46.5 µs).
pub(crate) const WARM_GAP: Duration = Duration::from_micros(20);

/// Work (wall time × threads used) from which a frame runs in parallel even after idle: where a
/// late worker stopped costing more than it saves (`uniform` 8000 lights, 240 µs serially, ran
/// as fast on two threads after idle; 32 000 lights ran 1.6× faster).
pub(crate) const COLD_PARALLEL_WORK: Duration = Duration::from_micros(250);

/// When a frame split into tasks runs them on the pool ([`crate::Assigner::with_parallelism`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Parallelism {
    /// On the pool unless this frame is expected to be small (under 250 µs of work: the previous
    /// frame's, scaled by the light counts) and the previous one ended over 20 µs ago: the
    /// workers have gone to sleep and would arrive too late to help. The same as
    /// `PacedWith(PacingLimits::MEASURED)`.
    #[default]
    Paced,
    /// Paced with other limits: the defaults were measured on one 2-vCPU machine, and an
    /// engine whose workers wake faster or slower (or that measures its own) can set its own.
    PacedWith(PacingLimits),
    /// Always on the pool: for a job system that keeps its workers awake between frames.
    Always,
}

impl Parallelism {
    /// The pacing limits, or `None` for [`Parallelism::Always`].
    pub fn limits(self) -> Option<PacingLimits> {
        match self {
            Parallelism::Paced => Some(PacingLimits::MEASURED),
            Parallelism::PacedWith(limits) => Some(limits),
            Parallelism::Always => None,
        }
    }
}

/// The two thresholds of the pacing rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PacingLimits {
    /// A frame that starts less than this after the previous one ended runs on the pool: the
    /// workers are still awake.
    pub warm_gap: Duration,
    /// A frame expected to take at least this much work (the previous frame's wall time × the
    /// threads it used, scaled by the ratio of the light counts) runs on the pool even after
    /// idle: enough work for a late worker still to help.
    pub cold_work: Duration,
}

impl PacingLimits {
    /// A 20 µs warm gap and 250 µs of cold work, measured on the 2-vCPU CI machine (the
    /// measurements are in `pacing.rs`'s module docs).
    pub const MEASURED: PacingLimits = PacingLimits {
        warm_gap: WARM_GAP,
        cold_work: COLD_PARALLEL_WORK,
    };
}

impl Default for PacingLimits {
    fn default() -> Self {
        Self::MEASURED
    }
}

/// The previous frame, as far as the decision needs it.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Pacing {
    previous: Option<Frame>,
}

#[derive(Clone, Copy, Debug)]
struct Frame {
    end: Instant,
    work: Duration,
    lights: usize,
}

impl Frame {
    /// This frame's work scaled to `lights` lights; `None` where it had none to scale from.
    fn work_for(&self, lights: usize) -> Option<Duration> {
        if self.lights == 0 {
            return None;
        }
        let nanos = self.work.as_nanos() * lights as u128 / self.lights as u128;
        Some(Duration::from_nanos(
            u64::try_from(nanos).unwrap_or(u64::MAX),
        ))
    }
}

impl Pacing {
    /// Whether a frame of `lights` lights starting `now` should run its tasks in parallel under
    /// `limits`.
    pub fn parallel(&self, now: Instant, lights: usize, limits: PacingLimits) -> bool {
        match self.previous {
            None => true,
            Some(frame) => {
                now.saturating_duration_since(frame.end) < limits.warm_gap
                    || frame
                        .work_for(lights)
                        .is_none_or(|work| work >= limits.cold_work)
            }
        }
    }

    /// Records a frame of `lights` lights that ran from `start` to `end` on `threads` threads (1
    /// when serial).
    pub fn record(&mut self, start: Instant, end: Instant, threads: usize, lights: usize) {
        let wall = end.saturating_duration_since(start);
        self.previous = Some(Frame {
            end,
            work: wall * threads.max(1) as u32,
            lights,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    impl Pacing {
        /// For frames of one light count (1000 here), as the rule was first written.
        fn parallel_measured(&self, now: Instant) -> bool {
            self.parallel(now, 1000, PacingLimits::MEASURED)
        }
    }

    #[test]
    fn other_limits_move_both_thresholds() {
        let t0 = Instant::now();
        let mut pacing = Pacing::default();
        pacing.record(t0, t0 + Duration::from_micros(100), 2, 1000);
        let later = t0 + Duration::from_millis(1);
        // 200 µs of work, 0.9 ms idle: serial under the measured limits...
        assert!(!pacing.parallel_measured(later));
        // ...parallel when less work counts as big, or a longer gap as warm.
        let cold = PacingLimits {
            cold_work: Duration::from_micros(150),
            ..PacingLimits::MEASURED
        };
        assert!(pacing.parallel(later, 1000, cold));
        let warm = PacingLimits {
            warm_gap: Duration::from_millis(2),
            ..PacingLimits::MEASURED
        };
        assert!(pacing.parallel(later, 1000, warm));
        assert_eq!(Parallelism::Paced.limits(), Some(PacingLimits::MEASURED));
        assert_eq!(Parallelism::PacedWith(cold).limits(), Some(cold));
        assert_eq!(Parallelism::Always.limits(), None);
    }

    #[test]
    fn first_frame_is_parallel() {
        assert!(Pacing::default().parallel(Instant::now(), 1000, PacingLimits::MEASURED));
    }

    #[test]
    fn back_to_back_frames_stay_parallel_whatever_their_size() {
        let t0 = Instant::now();
        let mut pacing = Pacing::default();
        // A small serial frame, then a call right after it: wake the workers for what follows.
        pacing.record(t0, t0 + Duration::from_micros(30), 1, 1000);
        assert!(pacing.parallel_measured(t0 + Duration::from_micros(35)));
        pacing.record(t0, t0 + Duration::from_micros(30), 2, 1000);
        assert!(pacing.parallel_measured(t0 + Duration::from_micros(30) + WARM_GAP / 2));
    }

    #[test]
    fn small_frames_after_idle_run_serially() {
        let t0 = Instant::now();
        let mut pacing = Pacing::default();
        // 40 µs on two threads is 80 µs of work at most: not worth a late worker.
        pacing.record(t0, t0 + Duration::from_micros(40), 2, 1000);
        let later = t0 + Duration::from_millis(16);
        assert!(!pacing.parallel_measured(later));
        pacing.record(t0, t0 + Duration::from_micros(200), 1, 1000);
        assert!(!pacing.parallel_measured(later));
        // Just past the gap counts as idle.
        let end = t0 + Duration::from_micros(200);
        assert!(!pacing.parallel_measured(end + WARM_GAP));
    }

    #[test]
    fn big_frames_after_idle_stay_parallel() {
        let t0 = Instant::now();
        let mut pacing = Pacing::default();
        pacing.record(t0, t0 + Duration::from_micros(300), 1, 1000);
        assert!(pacing.parallel_measured(t0 + Duration::from_millis(16)));
        // 130 µs on two threads: up to 260 µs of work.
        pacing.record(t0, t0 + Duration::from_micros(130), 2, 1000);
        assert!(pacing.parallel_measured(t0 + Duration::from_millis(16)));
    }

    #[test]
    fn the_estimate_follows_the_light_count() {
        let t0 = Instant::now();
        let later = t0 + Duration::from_millis(16);
        let mut pacing = Pacing::default();
        // 100 lights in 20 µs: 0.2 µs a light. 100k lights after idle are ~20 ms of work, and
        // run on the pool; 1000 (~200 µs) do not.
        pacing.record(t0, t0 + Duration::from_micros(20), 1, 100);
        assert!(pacing.parallel(later, 100_000, PacingLimits::MEASURED));
        assert!(!pacing.parallel(later, 1000, PacingLimits::MEASURED));
        // And down: a small frame after a big one is small.
        pacing.record(t0, t0 + Duration::from_millis(5), 2, 100_000);
        assert!(!pacing.parallel(later, 100, PacingLimits::MEASURED));
        assert!(pacing.parallel(later, 10_000, PacingLimits::MEASURED));
        // No lights last time: no estimate, so the pool.
        pacing.record(t0, t0 + Duration::from_micros(1), 1, 0);
        assert!(pacing.parallel(later, 10, PacingLimits::MEASURED));
        // A count beyond any work's scale saturates instead of wrapping.
        pacing.record(t0, t0 + Duration::from_secs(1), 1, 1);
        assert!(pacing.parallel(later, usize::MAX, PacingLimits::MEASURED));
    }
}
