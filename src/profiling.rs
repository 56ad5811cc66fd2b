//! Tracy instrumentation of the frame, compiled only with the `tracy` feature: spans
//! ([`crate::profile_span!`]), frame marks ([`frame_mark`]) and plots ([`crate::profile_plot!`]). With the feature off
//! every one of them expands to nothing, so a default build carries no profiler code (CI checks
//! the release binary for tracy symbols). With it on, they record once a client is started
//! ([`start`], as `myriad` does in `main`), and are skipped before.
//!
//! The client's lifetime is the program's ([`Session`]): tracy-client's `manual-lifetime` starts
//! it only when asked and leaves the shutdown to the program. The shutdown is what sends the
//! events still queued, tells the profiler the capture ended and honours `TRACY_NO_EXIT=1`; a
//! program that skips it loses the tail of every capture.

/// Opens a Tracy span named `$name` until the end of the enclosing block, once a client runs
/// (nothing without the facade's `tracy` feature).
///
/// Defined once per state of the facade's feature, so the caller's crate needs neither a
/// `tracy` feature nor `tracy-client` of its own: a `#[cfg]` inside the macro's body would be
/// read in the caller's crate (an engine with its own `tracy` feature failed to compile).
#[cfg(feature = "tracy")]
#[macro_export]
macro_rules! profile_span {
    ($name:literal) => {
        let _tracy_span = $crate::profiling::__tracy::Client::running()
            .map(|client| client.span($crate::profiling::__tracy::span_location!($name), 0));
    };
}

/// Opens a Tracy span named `$name` until the end of the enclosing block, once a client runs
/// (nothing without the facade's `tracy` feature, as here).
#[cfg(not(feature = "tracy"))]
#[macro_export]
macro_rules! profile_span {
    ($name:literal) => {};
}

/// The facade's tracy-client, for its exported macros.
#[cfg(feature = "tracy")]
#[doc(hidden)]
pub use tracy_client as __tracy;

/// Marks the end of a frame in Tracy: once per rendered frame, by whatever rendered it.
#[inline]
pub fn frame_mark() {
    #[cfg(test)]
    FRAME_MARKS.with(|marks| marks.set(marks.get() + 1));
    #[cfg(feature = "tracy")]
    if let Some(client) = tracy_client::Client::running() {
        client.frame_mark();
    }
}

#[cfg(test)]
thread_local! {
    /// Frame marks made on this thread, so tests can count them with or without a client (a
    /// counter per thread: tests run side by side, and frames are marked on the rendering thread).
    static FRAME_MARKS: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// The frame marks this thread has made so far (the renderer glue's tests only).
#[cfg(all(test, feature = "render"))]
pub(crate) fn frame_marks_on_this_thread() -> u64 {
    FRAME_MARKS.with(std::cell::Cell::get)
}

/// Plots a frame's GPU pass times (`Renderer::last_pass_times`) in milliseconds, each pass that
/// ran on its own plot (`GPU G-buffer ms`, `GPU shading ms`, `GPU forward ms`, `GPU upload ms`),
/// once a client runs: the GPU's side of the frame beside the CPU's spans. The loops that read
/// the times anyway call it (`run_frames`, `myriad render`'s timed frames); reading them costs a
/// wait for the GPU, so a loop that does not should not start to for this.
#[cfg(feature = "render")]
pub fn plot_pass_times(times: Option<&myriad_gpu::PassTimes>) {
    let Some(t) = times else {
        return;
    };
    if let Some(ms) = t.gbuffer_ms {
        crate::profile_plot!("GPU G-buffer ms", ms);
    }
    if let Some(ms) = t.shading_ms {
        crate::profile_plot!("GPU shading ms", ms);
    }
    if let Some(ms) = t.forward_ms {
        crate::profile_plot!("GPU forward ms", ms);
    }
    if let Some(ms) = t.upload_ms {
        crate::profile_plot!("GPU upload ms", ms);
    }
}

/// Plots a drawn frame's load once a client runs: `visible lights` (the lights that went to the
/// assignment and the GPU), `cluster-light pairs` (`None` for a frame without lists: brute
/// force, or a skipping frame that reused the last lists) and `bytes uploaded`. Every frame loop
/// of the facade calls it once per drawn frame, beside its frame mark (`run_frames`,
/// `Viewer::frame`, `Viewer::frame_with_skips`, `myriad stress`), so a capture of any command
/// has the three plots.
pub fn plot_frame_load(visible_lights: u64, pairs: Option<u64>, upload_bytes: u64) {
    crate::profile_plot!("visible lights", visible_lights);
    if let Some(pairs) = pairs {
        crate::profile_plot!("cluster-light pairs", pairs);
    }
    crate::profile_plot!("bytes uploaded", upload_bytes);
}

/// Plots `value` on the Tracy plot `name` (a static name per call site) once a client runs.
#[cfg(feature = "tracy")]
#[macro_export]
macro_rules! profile_plot {
    ($name:literal, $value:expr) => {
        if let Some(client) = $crate::profiling::__tracy::Client::running() {
            client.plot($crate::profiling::__tracy::plot_name!($name), $value as f64);
        }
    };
}

/// Plots `value` on the Tracy plot `name` once a client runs (without the facade's `tracy`
/// feature, as here, `value` is type-checked and not evaluated).
#[cfg(not(feature = "tracy"))]
#[macro_export]
macro_rules! profile_plot {
    ($name:literal, $value:expr) => {
        let _ = || $value;
    };
}

/// Starts the Tracy client (nothing without the `tracy` feature) and returns the [`Session`] that
/// shuts it down. Call once, first thing in `main`, and keep the session until `main` returns.
///
/// The client never starts by itself (tracy-client's `manual-lifetime`): a program that does not
/// call this records nothing and opens no socket, whatever features are on. Where the client
/// was already running (an engine started its own `tracy_client::Client`), the session leaves
/// the shutdown to whoever started it.
///
/// # Safety
///
/// The session that starts the client shuts the profiler down when it is dropped, and nothing
/// may record after that: tracy-client still reports the client as running, so a span, plot,
/// frame mark or GPU zone made afterwards — by this crate, by `myriad-assignment`,
/// `myriad-scene` or `myriad-gpu`, or by the caller's own `tracy_client` calls, on any thread —
/// uses the profiler's freed memory. Keep the session alive until every instrumented thread is
/// done and every renderer, viewer and instrumented value is dropped: bind it first in `main`
/// (`let _profiler = unsafe { start() };`, never `let _ = …`, which drops it at once) so it is
/// dropped last. (A safe `start` let `drop(start()); frame_mark();` abort in Tracy's own
/// assertion, and a span open on another thread meanwhile read freed memory: soundness audit.)
/// Without the `tracy` feature nothing is started or shut down, and the call is harmless.
#[allow(unsafe_code)] // The contract above; the shutdown it guards is in `shutdown`.
pub unsafe fn start() -> Session {
    #[cfg(feature = "tracy")]
    {
        use std::sync::atomic::{AtomicBool, Ordering};
        /// Whether some [`start`] has handed out the session that owns the client.
        static OWNED: AtomicBool = AtomicBool::new(false);
        let owns_client =
            !tracy_client::Client::is_running() && !OWNED.swap(true, Ordering::AcqRel);
        let _ = tracy_client::Client::start();
        Session {
            owns_client,
            _same_thread: std::marker::PhantomData,
        }
    }
    #[cfg(not(feature = "tracy"))]
    Session {
        _same_thread: std::marker::PhantomData,
    }
}

/// The running Tracy client, from [`start`] until this is dropped: dropping the session that
/// started the client shuts the profiler down (`___tracy_shutdown_profiler`), which sends what
/// is still queued, ends the capture cleanly and, with `TRACY_NO_EXIT=1`, waits until a profiler
/// has taken the data; after that nothing may record, which is why [`start`] is `unsafe`. Without the `tracy` feature it is an empty value that does nothing.
///
/// Drop it last, at the end of `main` (on every path out: an early `return` or a panic's unwind
/// drops it too), once every instrumented thread is idle: nothing may record after the shutdown
/// (tracy-client still reports the client as running then, and a span would use the freed
/// profiler), and the client cannot start again in the same process. Not `Send`: Tracy must be
/// shut down on the thread that started it.
#[must_use = "dropping the session shuts the profiler down: keep it until the end of `main`"]
pub struct Session {
    /// Whether this session started the client, so its drop shuts it down.
    #[cfg(feature = "tracy")]
    owns_client: bool,
    _same_thread: std::marker::PhantomData<*const ()>,
}

#[cfg(feature = "tracy")]
impl Drop for Session {
    fn drop(&mut self) {
        if self.owns_client {
            shutdown();
        }
    }
}

/// Shuts the profiler down (counted instead in tests, which share one process and client).
#[cfg(feature = "tracy")]
fn shutdown() {
    #[cfg(not(test))]
    // SAFETY: called once, by the session that started the client (`OWNED`), on the thread that
    // started it (`Session` is not `Send`), when nothing records any more: the contract of the
    // `unsafe fn start` that made the session; tracy-client's `Client::start` documents this
    // call as the program's job under `manual-lifetime`.
    #[allow(unsafe_code)]
    unsafe {
        tracy_client::sys::___tracy_shutdown_profiler();
    }
    #[cfg(test)]
    tests::SHUTDOWNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
}

/// Names the calling thread in Tracy (and for the OS, which Tracy also sets), once a client
/// runs; nothing without the `tracy` feature. Threads the program spawns are better named
/// where they are spawned (`std::thread::Builder::name`, rayon's `thread_name`): Tracy reads
/// the OS name of a thread it was not told about. Threads spawned later from this one by code
/// that does not name its own (a driver's) inherit the OS name.
pub fn name_this_thread(name: &str) {
    #[cfg(feature = "tracy")]
    if let Some(client) = tracy_client::Client::running() {
        client.set_thread_name(name);
    }
    #[cfg(not(feature = "tracy"))]
    let _ = name;
}

#[cfg(all(test, feature = "tracy"))]
#[allow(unsafe_code)] // `start`, whose shutdown the tests count instead of making.
mod tests {
    use std::sync::atomic::{AtomicU64, Ordering};

    /// Shutdowns the sessions asked for (the real one would end the tests' shared client).
    pub(super) static SHUTDOWNS: AtomicU64 = AtomicU64::new(0);

    /// The only test that starts the client: others would race it to "before main".
    #[test]
    fn the_client_starts_only_when_asked_and_its_first_session_shuts_it_down() {
        assert!(
            tracy_client::Client::running().is_none(),
            "the tracy client started before main"
        );
        {
            crate::profile_span!("before the client");
            crate::profile_plot!("before the client", 1.0);
        }
        // SAFETY: the shutdown is counted, not made, in the lib's tests (`shutdown`).
        let session = unsafe { super::start() };
        assert!(tracy_client::Client::running().is_some());
        crate::profile_span!("after the client");
        crate::profile_plot!("after the client", 2.0);
        super::name_this_thread("profiling test");
        // A second start finds the client running: its session is not the one to shut it down.
        // SAFETY: as above; and this session does not own the client.
        drop(unsafe { super::start() });
        assert_eq!(SHUTDOWNS.load(Ordering::Relaxed), 0);
        drop(session);
        assert_eq!(SHUTDOWNS.load(Ordering::Relaxed), 1);
    }
}
