//! How fast the pool's first two threads pass data to each other: the context a parallel timing
//! needs.
//!
//! A parallel frame hands data between cores twice: every task writes its spans, and any thread
//! may then count and fill a part from them. So its speedup depends on what a cache line costs to
//! move from one core to the other, and on a shared virtual machine that cost is not fixed. On
//! the 2-vCPU CI-like VM it moved between about 50 ns and 400 ns per round trip from one minute
//! to the next, and `paper` 1000 `binary` on two threads followed it: 26–28 µs at 50–60 ns,
//! 51–53 µs (above its serial 46 µs) at ~400 ns, with the same binary (docs/measured.md, "The link between the vCPUs"). `myriad bench`
//! therefore measures the link before and after its timings and prints it with them.
//!
//! Two probes, both on the current rayon pool's threads 0 and 1 (via `rayon::broadcast`, so they
//! are the very workers the frames run on):
//! * **round trip**: one atomic counter bounced between the two threads;
//! * **hand-off**: one thread writes [`HANDOFF_BYTES`] (a store per cache line), the other reads
//!   them all back, and the turn passes back — about one thread's share of the spans of a
//!   `paper` 1000 `binary` frame.
//!
//! Both spin. A pool with more threads than free cores could leave the partner descheduled for a
//! whole time slice, so each probe stops at [`PROBE_LIMIT`] and reports what it timed so far.

use serde::Serialize;
use std::hint::spin_loop;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::time::{Duration, Instant};

/// Bytes written by one thread and read by the other per hand-off.
pub const HANDOFF_BYTES: usize = 64 * 1024;

/// Longest a probe spins before it stops and reports what it has.
pub const PROBE_LIMIT: Duration = Duration::from_millis(50);

const ROUND_TRIPS: u32 = 4000;
const HANDOFFS: u32 = 200;
/// u32 slots per 64-byte cache line: one store (and one load) per line.
const LINE_STRIDE: usize = 16;

/// The link between the pool's threads 0 and 1, as measured.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CoreLink {
    /// Nanoseconds for a counter to go to the other thread and back (the mean of the rounds).
    pub round_trip_ns: f64,
    /// Microseconds per hand-off of [`HANDOFF_BYTES`] (written, read on the other thread, turn
    /// passed back).
    pub handoff_us: f64,
}

/// Measures the link on the current rayon pool; `None` when it has a single thread.
pub fn measure() -> Option<CoreLink> {
    if rayon::current_num_threads() < 2 {
        return None;
    }
    let round_trip_ns = probe(ROUND_TRIPS, PROBE_LIMIT, |_| ()) * 1e9;
    let lines = handoff_lines();
    let handoff_us = probe(HANDOFFS, PROBE_LIMIT, |turn| {
        std::hint::black_box(hand_off(&lines, turn));
    }) * 1e6;
    Some(CoreLink {
        round_trip_ns,
        handoff_us,
    })
}

/// [`HANDOFF_BYTES`] of `u32` slots, all 0.
fn handoff_lines() -> Vec<AtomicU32> {
    (0..HANDOFF_BYTES / 4).map(|_| AtomicU32::new(0)).collect()
}

/// A turn of the hand-off: `Write(i)` stores `i` in the first slot of each cache line of `lines`
/// (and returns 0); `Read` loads those slots back and returns their (wrapping) sum, for the
/// caller to keep.
fn hand_off(lines: &[AtomicU32], turn: Turn) -> u32 {
    match turn {
        Turn::Write(i) => {
            for slot in lines.iter().step_by(LINE_STRIDE) {
                slot.store(i, Ordering::Relaxed);
            }
            0
        }
        Turn::Read => lines
            .iter()
            .step_by(LINE_STRIDE)
            .fold(0u32, |a, s| a.wrapping_add(s.load(Ordering::Relaxed))),
    }
}

/// What a thread does when the turn reaches it: thread 0 writes (round `i`), thread 1 reads.
enum Turn {
    Write(u32),
    Read,
}

/// Seconds per round of `rounds` turns passed 0 → 1 → 0, each doing `work` first; stops early at
/// `limit` ([`PROBE_LIMIT`]).
fn probe(rounds: u32, limit: Duration, work: impl Fn(Turn) + Sync) -> f64 {
    let baton = AtomicU32::new(0);
    let arrived = AtomicU32::new(0);
    let stop = AtomicBool::new(false);
    let timed = rayon::broadcast(|ctx| {
        if ctx.index() > 1 {
            return None;
        }
        // Both threads running before the clock starts (a sleeping worker takes a while to wake).
        arrived.fetch_add(1, Ordering::AcqRel);
        while arrived.load(Ordering::Acquire) < 2 {
            spin_loop();
        }
        let start = Instant::now();
        let mut done = 0;
        for i in 0..rounds {
            let (wait_for, pass) = if ctx.index() == 0 {
                (2 * i, 2 * i + 1)
            } else {
                (2 * i + 1, 2 * i + 2)
            };
            let mut spins = 0u32;
            while baton.load(Ordering::Acquire) != wait_for {
                spin_loop();
                spins = spins.wrapping_add(1);
                if spins.is_multiple_of(1024)
                    && (stop.load(Ordering::Relaxed) || start.elapsed() > limit)
                {
                    stop.store(true, Ordering::Relaxed);
                    return (ctx.index() == 0).then(|| (start.elapsed(), done));
                }
            }
            work(if ctx.index() == 0 {
                Turn::Write(i)
            } else {
                Turn::Read
            });
            baton.store(pass, Ordering::Release);
            done = i + 1;
        }
        if ctx.index() == 0 {
            // The last round ends when the turn is back.
            while baton.load(Ordering::Acquire) != 2 * rounds && !stop.load(Ordering::Relaxed) {
                spin_loop();
            }
            return Some((start.elapsed(), done));
        }
        None
    });
    let (elapsed, rounds) = timed
        .into_iter()
        .flatten()
        .next()
        .expect("thread 0 reports its timing");
    elapsed.as_secs_f64() / rounds.max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    }

    #[test]
    fn a_single_thread_has_no_link() {
        assert_eq!(pool(1).install(measure), None);
    }

    #[test]
    fn two_threads_report_a_plausible_link() {
        let pool = pool(2);
        let called = Instant::now();
        let link = pool.install(measure).expect("two threads have a link");
        let outside = called.elapsed();
        // A round trip is at least two cache-line transfers (tens of ns on any machine), a
        // hand-off a thousand stores and loads besides (far more than a nanosecond), and either
        // at most the call (not the probe's limit: on a loaded machine a probe can stop well
        // past it, with no round done).
        assert!(
            link.round_trip_ns > 1.0 && link.round_trip_ns <= outside.as_nanos() as f64,
            "{link:?} in {outside:?}"
        );
        assert!(
            link.handoff_us > 1e-3 && link.handoff_us <= outside.as_secs_f64() * 1e6,
            "{link:?} in {outside:?}"
        );
        // (Which probe takes longer is a timing, not a property: on a shared machine the
        // scheduler's slices decide it — a 9.4 µs round trip beside a 2.4 µs hand-off failed CI
        // once. `myriad bench` prints both.)
    }

    /// Spins through a turn of `d`, so that two turns at once would overlap.
    fn busy(d: Duration) {
        let begun = Instant::now();
        while begun.elapsed() < d {
            spin_loop();
        }
    }

    /// A turn as the tests record it: the thread that took it, `Some(i)` for `Turn::Write(i)` or
    /// `None` for `Turn::Read`, and when it began and ended.
    type Taken = (usize, Option<u32>, Instant, Instant);

    /// Probes `rounds` rounds on two threads, up to `limit`, each turn taking `pause(turn)`: the
    /// turns in the order they were taken, the seconds per round the probe reported, and how
    /// long the call took seen from outside.
    fn traced_probe(
        rounds: u32,
        limit: Duration,
        pause: impl Fn(&Turn) + Sync,
    ) -> (Vec<Taken>, f64, Duration) {
        let turns = Mutex::new(Vec::new());
        let pool = pool(2);
        let called = Instant::now();
        let per_round = pool.install(|| {
            probe(rounds, limit, |turn| {
                let begun = Instant::now();
                // Held through the turn: a turn taken while another is under way finds it taken.
                let mut turns = turns.try_lock().expect("one turn at a time");
                pause(&turn);
                let what = match turn {
                    Turn::Write(i) => Some(i),
                    Turn::Read => None,
                };
                let thread = rayon::current_thread_index().unwrap();
                turns.push((thread, what, begun, Instant::now()));
            })
        });
        let outside = called.elapsed();
        (turns.into_inner().unwrap(), per_round, outside)
    }

    /// Thread 0 writing round `i`, then thread 1 reading it, for each of `rounds` rounds.
    fn rounds_of_turns(rounds: u32) -> Vec<(usize, Option<u32>)> {
        (0..rounds)
            .flat_map(|i| [(0, Some(i)), (1, None)])
            .collect()
    }

    #[test]
    fn the_turn_goes_from_thread_0_to_thread_1_and_back_and_each_round_is_timed_whole() {
        // A limit no descheduled thread reaches, even on a loaded machine: every round runs.
        let limit = Duration::from_secs(10);
        let (turns, per_round, outside) =
            traced_probe(2, limit, |_| busy(Duration::from_millis(2)));
        let taken: Vec<_> = turns
            .iter()
            .map(|&(thread, what, ..)| (thread, what))
            .collect();
        // Thread 0 writes round 0, thread 1 reads it, and so on, one turn at a time.
        assert_eq!(taken, rounds_of_turns(2));
        // The time reported for the two rounds spans the turns, the last ending when the turn is
        // back, and lies within the call.
        let spanned = turns[3].3 - turns[0].2;
        let timed = per_round * 2.0;
        assert!(
            timed >= spanned.as_secs_f64() - 1e-9 && timed <= outside.as_secs_f64() + 1e-9,
            "{timed} s for two rounds, turns over {spanned:?}, {outside:?} in all"
        );
    }

    #[test]
    fn a_partner_that_keeps_the_turn_past_the_limit_stops_the_probe_with_thread_0s_time() {
        // Thread 1 keeps its first turn for twenty times the limit.
        let kept = 20 * PROBE_LIMIT;
        let (turns, per_round, _) = traced_probe(3, PROBE_LIMIT, |turn| {
            if matches!(turn, Turn::Read) {
                std::thread::sleep(kept);
            }
        });
        let taken: Vec<_> = turns
            .iter()
            .map(|&(thread, what, ..)| (thread, what))
            .collect();
        // Thread 0 stops waiting at the limit instead of waiting the turn out, and thread 1,
        // once it passes the turn back, finds the probe stopped: no second round.
        let first_round = rounds_of_turns(1);
        assert!(
            !taken.is_empty() && first_round.starts_with(&taken),
            "{taken:?}"
        );
        // The time is thread 0's: it stopped long before the turn came back, and, once it had
        // passed the turn (which only a thread 0 descheduled past the limit would not have
        // done), at the limit.
        assert!(per_round < kept.as_secs_f64(), "{per_round}");
        if taken == first_round {
            assert!(per_round >= PROBE_LIMIT.as_secs_f64(), "{per_round}");
        }
    }

    #[test]
    fn a_hand_off_stores_and_loads_one_slot_in_each_of_the_1024_cache_lines_of_64_kib() {
        let lines = handoff_lines();
        assert_eq!(lines.len() * 4, 64 * 1024);
        assert_eq!(hand_off(&lines, Turn::Write(3)), 0);
        for (k, slot) in lines.iter().enumerate() {
            let stored = if k % 16 == 0 { 3 } else { 0 };
            assert_eq!(slot.load(Ordering::Relaxed), stored, "slot {k}");
        }
        assert_eq!(hand_off(&lines, Turn::Read), 3 * 1024);
    }
}
