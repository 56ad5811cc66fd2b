//! A hang detector: the input being run, and a thread that ends the process when one runs past
//! the limit.
//!
//! The loop's own check of each input's time only runs once the input returns, so an input that
//! never returns (the `/dev/zero` read the hostile-input suite once found) would stall the run —
//! and CI with it — instead of failing it. The watchdog saves what the loop would have saved (the
//! input as an artifact, or the `assign` target's sub-seed) and exits with status 1.

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// What is running now, shared with the watchdog thread.
pub struct Watch {
    epoch: Instant,
    /// Milliseconds from `epoch` at which the current input started; `u64::MAX` between inputs.
    started_ms: AtomicU64,
    iteration: AtomicU64,
    /// The `assign` target's sub-seed of the current input.
    subseed: AtomicU64,
    input: Mutex<Arc<Vec<u8>>>,
}

impl Watch {
    /// Starts the watchdog thread for `target`: an input running longer than `limit` ends the
    /// process after `save` has written its artifact (it returns what to print).
    pub fn start(
        target: String,
        seed: u64,
        limit: Duration,
        save: fn(&str, u64, &[u8]) -> std::path::PathBuf,
    ) -> Arc<Self> {
        let watch = Arc::new(Self {
            epoch: Instant::now(),
            started_ms: AtomicU64::new(u64::MAX),
            iteration: AtomicU64::new(0),
            subseed: AtomicU64::new(0),
            input: Mutex::new(Arc::new(Vec::new())),
        });
        let seen = Arc::clone(&watch);
        std::thread::spawn(move || {
            loop {
                std::thread::sleep(Duration::from_millis(250));
                let started = seen.started_ms.load(Relaxed);
                if started == u64::MAX || seen.now_ms() < started + limit.as_millis() as u64 {
                    continue;
                }
                let iteration = seen.iteration.load(Relaxed);
                let secs = limit.as_secs();
                if target == "assign" {
                    let subseed = seen.subseed.load(Relaxed);
                    eprintln!(
                        "hang (over {secs} s) at iteration {iteration} (seed {seed}, sub-seed \
                         {subseed}: --subseed {subseed} runs it alone)"
                    );
                } else {
                    let input = Arc::clone(&seen.input.lock().expect("the input's lock"));
                    let path = save(&target, iteration, &input);
                    eprintln!(
                        "hang (over {secs} s) at iteration {iteration}: saved {}",
                        path.display()
                    );
                }
                std::process::exit(1);
            }
        });
        watch
    }

    fn now_ms(&self) -> u64 {
        self.epoch.elapsed().as_millis() as u64
    }

    /// Input `iteration` (its bytes, or the `assign` target's sub-seed) starts now.
    pub fn begin(&self, iteration: u64, input: &Arc<Vec<u8>>, subseed: u64) {
        *self.input.lock().expect("the input's lock") = Arc::clone(input);
        self.iteration.store(iteration, Relaxed);
        self.subseed.store(subseed, Relaxed);
        self.started_ms.store(self.now_ms(), Relaxed);
    }

    /// The current input returned.
    pub fn end(&self) {
        self.started_ms.store(u64::MAX, Relaxed);
    }
}
