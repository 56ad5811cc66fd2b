//! Allocations that can be large, made so that running out of memory is
//! [`GpuError::OutOfMemory`] instead of a panic.
//!
//! wgpu raises running out of device or host memory as an error on the device, and an error no
//! scope catches goes to the uncaptured-error handler, which panics by default: an engine that
//! loads a scene too big for its GPU, or a frame of a million lights' lists, would lose the
//! process. Every buffer and texture whose size the caller's data decides (a scene's geometry and
//! textures, the G-buffer and targets at the caller's size, the frame's storage buffers and their
//! staging copies) is made here inside an out-of-memory error scope. Small fixed objects
//! (pipelines, uniform blocks) are not: they cost the same for any scene.

use crate::GpuError;

/// Runs `make` inside an out-of-memory error scope on `device`; an error it raised is
/// [`GpuError::OutOfMemory`] naming `what` (what was being made, and its size).
pub(crate) fn catching<T>(
    device: &wgpu::Device,
    what: impl FnOnce() -> String,
    make: impl FnOnce() -> T,
) -> Result<T, GpuError> {
    let scope = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let made = make();
    match ready(scope.pop()).flatten() {
        Some(error) => Err(GpuError::OutOfMemory(format!("{}: {error}", what()))),
        None => Ok(made),
    }
}

/// A buffer holding `contents` (wgpu's `create_buffer_init`, which panics when the mapped buffer
/// cannot be made).
pub(crate) fn buffer_init(
    device: &wgpu::Device,
    label: &'static str,
    contents: &[u8],
    usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer, GpuError> {
    // Mapped buffers come in whole 4-byte words; the tail past `contents` is zero.
    let size = (contents.len() as u64)
        .next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
        .max(wgpu::COPY_BUFFER_ALIGNMENT);
    let what = || format!("the {label} buffer ({size} bytes)");
    let buffer = catching(device, what, || {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage,
            mapped_at_creation: true,
        })
    })?;
    {
        let mut view = buffer
            .get_mapped_range_mut(..)
            .map_err(|error| GpuError::OutOfMemory(format!("{}: {error}", what())))?;
        view.slice(..contents.len()).copy_from_slice(contents);
        view.slice(contents.len()..).fill(0);
    }
    buffer.unmap();
    Ok(buffer)
}

/// The output of `future` if it is ready when first polled, else `None`. wgpu's error scopes
/// resolve at once on native backends (an error is raised as the call is made), so a frame can
/// read one without an executor.
pub(crate) fn ready<F: std::future::Future>(future: F) -> Option<F::Output> {
    let mut future = std::pin::pin!(future);
    let mut context = std::task::Context::from_waker(std::task::Waker::noop());
    match future.as_mut().poll(&mut context) {
        std::task::Poll::Ready(output) => Some(output),
        std::task::Poll::Pending => None,
    }
}
