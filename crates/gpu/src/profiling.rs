//! Tracy spans that cost nothing when the `tracy` feature is off: `profile_span!("name")` opens
//! a span until the end of the enclosing block (or until `end_span!(guard)`, given a guard's
//! name), or expands to nothing at all. With the feature on, spans are recorded once the program
//! has started a `tracy_client::Client` (the `myriad` binary does in `main`); before that they
//! are skipped. The client never starts by itself (tracy-client's `manual-lifetime`).

macro_rules! profile_span {
    ($name:literal) => {
        #[cfg(feature = "tracy")]
        let _tracy_span = tracy_client::Client::running()
            .map(|client| client.span(tracy_client::span_location!($name), 0));
    };
    // A span held by `$guard`, for [`end_span!`] to close before the end of the block.
    ($name:literal, $guard:ident) => {
        #[cfg(feature = "tracy")]
        let $guard = tracy_client::Client::running()
            .map(|client| client.span(tracy_client::span_location!($name), 0));
    };
}

/// Closes the span `profile_span!("name", guard)` opened (nothing without the `tracy` feature).
macro_rules! end_span {
    ($guard:ident) => {
        #[cfg(feature = "tracy")]
        drop($guard);
    };
}

pub(crate) use {end_span, profile_span};
