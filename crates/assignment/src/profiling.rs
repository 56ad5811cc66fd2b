//! Tracy spans that cost nothing when the `tracy` feature is off: `profile_span!("name")` opens
//! a span until the end of the enclosing block, or expands to nothing at all. With the feature
//! on, the program must have started a `tracy_client::Client` (the `myriad` binary does).

macro_rules! profile_span {
    ($name:literal) => {
        #[cfg(feature = "tracy")]
        let _tracy_span = tracy_client::span!($name);
    };
}

pub(crate) use profile_span;
