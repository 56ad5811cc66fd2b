//! Tracy instrumentation of the frame, compiled only with the `tracy` feature: spans
//! ([`crate::profile_span!`]), frame marks ([`frame_mark`]) and plots ([`crate::profile_plot!`]). With the feature off
//! every one of them expands to nothing, so a default build carries no profiler code (CI checks
//! the release binary for tracy symbols). With it on, they record once a client is started
//! ([`start`], as `myriad` does in `main`), and are skipped before.

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

/// Marks the end of a frame in Tracy.
#[inline]
pub fn frame_mark() {
    #[cfg(feature = "tracy")]
    if let Some(client) = tracy_client::Client::running() {
        client.frame_mark();
    }
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

/// Starts the Tracy client (a no-op without the `tracy` feature). Call once, early in `main`.
///
/// The client never starts by itself (tracy-client's `manual-lifetime`): a program that does not
/// call this records nothing and opens no socket, whatever features are on.
pub fn start() {
    #[cfg(feature = "tracy")]
    {
        let _ = tracy_client::Client::start();
    }
}

#[cfg(all(test, feature = "tracy"))]
mod tests {
    #[test]
    fn the_client_starts_only_when_asked_and_spans_before_it_are_skipped() {
        assert!(
            tracy_client::Client::running().is_none(),
            "the tracy client started before main"
        );
        {
            crate::profile_span!("before the client");
            crate::profile_plot!("before the client", 1.0);
        }
        super::start();
        assert!(tracy_client::Client::running().is_some());
        crate::profile_span!("after the client");
        crate::profile_plot!("after the client", 2.0);
    }
}
