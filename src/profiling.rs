//! Tracy instrumentation of the frame, compiled only with the `tracy` feature: spans
//! ([`crate::profile_span!`]), frame marks ([`frame_mark`]) and plots ([`crate::profile_plot!`]). With the feature off
//! every one of them expands to nothing, so a default build carries no profiler code (CI checks
//! the release binary for tracy symbols). With it on, start a client first
//! (`tracy_client::Client::start()`, as `myriad` does in `main`).

/// Opens a Tracy span named `$name` until the end of the enclosing block (nothing without the
/// `tracy` feature).
#[macro_export]
macro_rules! profile_span {
    ($name:literal) => {
        #[cfg(feature = "tracy")]
        let _tracy_span = tracy_client::span!($name);
    };
}

/// Marks the end of a frame in Tracy.
#[inline]
pub fn frame_mark() {
    #[cfg(feature = "tracy")]
    if let Some(client) = tracy_client::Client::running() {
        client.frame_mark();
    }
}

/// Plots `value` on the Tracy plot `name` (a static name per call site).
#[macro_export]
macro_rules! profile_plot {
    ($name:literal, $value:expr) => {
        #[cfg(feature = "tracy")]
        if let Some(client) = tracy_client::Client::running() {
            client.plot(tracy_client::plot_name!($name), $value as f64);
        }
        #[cfg(not(feature = "tracy"))]
        let _ = || $value;
    };
}

/// Starts the Tracy client (a no-op without the `tracy` feature). Call once, early in `main`.
pub fn start() {
    #[cfg(feature = "tracy")]
    {
        let _ = tracy_client::Client::start();
    }
}
