//! # myriad-gpu — the wgpu renderer (not yet built)
//!
//! This crate will hold everything that names `wgpu`: the G-buffer pass, clustered deferred and
//! forward shading over the CPU-built light lists, the brute-force and tiled baselines, the heat
//! map, pipelined uploads through a ring of buffers, headless render targets and GPU timing
//! (issue "GPU renderer"). It will work on the caller's `wgpu::Device`/`Queue`, so an engine can
//! drop it in, and can also create its own headless adapter for the CLI.
//!
//! Until then it only fixes the crate's place in the graph: it depends on `myriad-cluster-math`
//! (the cluster index of a pixel must be computed exactly as the CPU computes it) and on nothing
//! that knows about scenes or assignment methods.
#![forbid(unsafe_code)]
