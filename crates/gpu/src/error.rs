//! What can go wrong on the GPU side, each with a message that says what to do.
//!
//! What the renderer checks itself comes back here: inputs that do not fit, buffers past the
//! device's binding limit, loop budgets, limits, a lost device (`device_loss.rs`), read-back and
//! waits, and running out of memory where the caller's data decides a size (`out_of_memory.rs`).
//! wgpu's other errors do not: wgpu hands them to the device's uncaptured-error handler (an
//! engine's device keeps its own; wgpu's default panics with the message), as for every other
//! call an engine makes on that device. The renderer checks ahead what would reach it — sizes
//! against limits, targets against the pipelines (`renderer/target_check.rs`, inside a
//! validation error scope) — so a frame it accepts does not.

/// Errors of the renderer.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// wgpu found no adapter at all (no GPU driver, no software Vulkan).
    #[error(
        "no GPU adapter found ({detail}). On Debian/Ubuntu, Mesa's software Vulkan driver gives one \
         without a GPU: `apt-get install -y mesa-vulkan-drivers`"
    )]
    NoAdapter {
        /// What wgpu said.
        detail: String,
    },
    /// The adapter refused to create a device.
    #[error("the GPU adapter {adapter:?} refused to create a device: {detail}")]
    RequestDevice {
        /// Adapter name.
        adapter: String,
        /// What wgpu said.
        detail: String,
    },
    /// A buffer would exceed what the device can bind; nothing is truncated, the frame is refused.
    #[error(
        "the {what} buffer needs {bytes} bytes, more than this device can bind in one storage \
         buffer ({limit} bytes); {}",
        if *what == "lights" {
            "fewer lights per frame (cull first), or a device created with a larger \
             max_storage_buffer_binding_size"
        } else {
            "use a coarser grid or a pair budget (`Assigner::with_pair_budget`), or a device \
             created with a larger max_storage_buffer_binding_size"
        }
    )]
    BufferTooLarge {
        /// Which buffer.
        what: &'static str,
        /// Bytes needed.
        bytes: u64,
        /// The most a storage buffer may hold on the device: the smaller of its
        /// `max_storage_buffer_binding_size` and `max_buffer_size`, in whole 4-byte words.
        limit: u64,
    },
    /// A pixel would loop over more lights than the adapter's shader compiler allows: Mesa's
    /// llvmpipe ends any shader invocation's loops after 65 535 iterations in all, which would
    /// silently drop the remaining lights (see `loop_budget.rs` for the accounting). Refused
    /// instead.
    #[error(
        "a pixel would evaluate {lights} lights, but {adapter} stops shader loops after {limit} \
         iterations in all, room for at most {max_lights} lights per pixel here (lights past that would be \
         silently dropped); {}",
        loop_limit_advice(*.mode)
    )]
    ShaderLoopLimit {
        /// The refused pass: brute force loops over every light, lists over one cluster's.
        mode: crate::ShadingMode,
        /// Lights one pixel would visit.
        lights: u64,
        /// The most lights a pixel may visit in this pass on this adapter.
        max_lights: u64,
        /// The adapter.
        adapter: String,
        /// Its loop limit, over all loops of an invocation.
        limit: u64,
    },
    /// The device was created with limits below [`crate::Renderer::required_limits`] (each
    /// limit named, with what it is and what the renderer needs). Request those limits when
    /// creating the device; every adapter the renderer runs on has them.
    #[error(
        "the device's limits are below the renderer's (Renderer::required_limits): {0}; create \
         the device with at least those limits"
    )]
    DeviceLimits(String),
    /// Inputs the renderer cannot use or that do not fit together: a frame's (list sizes vs
    /// grid, target size vs camera), a scene's geometry, an output format it cannot draw into, a
    /// context of another device than the renderer's.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// The device ran out of memory growing one of the frame's buffers, or the host ran out of
    /// memory for the staging copy of its lights and lists (wgpu's out-of-memory error, which
    /// would otherwise panic): nothing was drawn, and the next frame must upload its lights and
    /// lists again.
    #[error(
        "the GPU ran out of memory for {0}; nothing was drawn: fewer lights, a coarser grid or a \
         pair budget need less"
    )]
    OutOfMemory(String),
    /// Mapping a read-back buffer failed.
    #[error("reading back from the GPU failed: {0}")]
    Readback(String),
    /// The device was lost (a driver reset, a hung GPU, `Device::destroy`): nothing more can be
    /// drawn or read on it. Make a new device and renderer, and upload the scene again. Only
    /// reported where the loss is recorded (`device_loss.rs`: the headless context does it,
    /// an engine's device through its own callback).
    #[error(
        "the GPU device was {0}; nothing more can be drawn on it: make a new device and renderer \
         (and upload the scene again)"
    )]
    DeviceLost(crate::DeviceLoss),
    /// Waiting for the GPU to finish its work failed (wgpu's `PollError`).
    #[error("waiting for the GPU failed: {0}")]
    Wait(#[from] wgpu::PollError),
}

/// What to change when a pass would pass the adapter's loop limit.
fn loop_limit_advice(mode: crate::ShadingMode) -> &'static str {
    match mode {
        crate::ShadingMode::BruteForce => {
            "use light lists (clustered shading) or fewer lights per pass"
        }
        crate::ShadingMode::Lists => "use a finer cluster grid (shorter lists) or fewer lights",
    }
}

#[cfg(test)]
mod tests {
    use super::GpuError;

    #[test]
    fn a_buffer_too_large_says_what_would_help_for_that_buffer() {
        let message = |what| {
            GpuError::BufferTooLarge {
                what,
                bytes: 200,
                limit: 100,
            }
            .to_string()
        };
        // The light buffer's size depends on the light count alone: no grid helps it.
        assert!(message("lights").contains("fewer lights"));
        assert!(!message("lights").contains("coarser grid"));
        assert!(message("light indices").contains("coarser grid"));
    }
}
