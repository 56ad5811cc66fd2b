//! Allocations that can be large, made so that running out of memory is
//! [`GpuError::OutOfMemory`] instead of a panic or a lost device.
//!
//! wgpu raises running out of device or host memory as an error on the device, and an error no
//! scope catches goes to the uncaptured-error handler, which panics by default: an engine that
//! loads a scene too big for its GPU, or a frame of a million lights' lists, would lose the
//! process. Every buffer and texture whose size the caller's data decides (a scene's geometry,
//! textures and materials, the G-buffer and targets at the caller's size, the frame's storage
//! buffers and their staging copies, read-backs) is made here inside an out-of-memory error scope.
//!
//! Contents whose size the data decides are never handed to wgpu's own upload helpers (`create_buffer_init`, a buffer mapped
//! at creation that the GPU cannot map, `Queue::write_texture`): those stage through an internal
//! buffer whose allocation failure wgpu-core treats as fatal and answers by losing the device
//! (every later call then silently does nothing). Data goes instead through a staging buffer of
//! our own, `MAP_WRITE | COPY_SRC` and mapped at creation — an allocation whose failure is an
//! ordinary, recoverable out-of-memory error — and a copy on the queue ([`buffer_init`],
//! [`texture_init`]).
//!
//! What this cannot catch: a driver that reports host memory exhaustion as a lost device (that
//! is [`GpuError::DeviceLost`] where the loss is recorded, `device_loss.rs`), and any backend
//! whose error scopes do not resolve at once (the web; there an error still reaches the device's
//! handler, as without the scope).

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

/// A `MAP_WRITE | COPY_SRC` buffer of `size` bytes (at least `contents`' length, a multiple of
/// 4) holding `contents` and zeros after them.
fn staging(
    device: &wgpu::Device,
    what: &dyn Fn() -> String,
    contents: &[u8],
    size: u64,
) -> Result<wgpu::Buffer, GpuError> {
    let staging_what = || format!("the staging copy of {}", what());
    let buffer = catching(device, staging_what, || {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("upload staging"),
            size,
            usage: wgpu::BufferUsages::MAP_WRITE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: true,
        })
    })?;
    {
        let mut view = buffer
            .get_mapped_range_mut(..)
            .map_err(|error| GpuError::OutOfMemory(format!("{}: {error}", staging_what())))?;
        view.slice(..contents.len()).copy_from_slice(contents);
        view.slice(contents.len()..).fill(0);
    }
    buffer.unmap();
    Ok(buffer)
}

/// A buffer holding `contents` (zero-padded to whole 4-byte words, at least one), with `usage`
/// plus `COPY_DST`: made, then filled from a staging buffer by a copy submitted on `queue`.
pub(crate) fn buffer_init(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    label: &'static str,
    contents: &[u8],
    usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer, GpuError> {
    let size = (contents.len() as u64)
        .next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
        .max(wgpu::COPY_BUFFER_ALIGNMENT);
    let what = || format!("the {label} buffer ({size} bytes)");
    let buffer = catching(device, what, || {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    })?;
    let source = staging(device, &what, contents, size)?;
    let mut encoder =
        device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
    encoder.copy_buffer_to_buffer(&source, 0, &buffer, 0, size);
    queue.submit([encoder.finish()]);
    Ok(buffer)
}

/// Fills `texture` (2D, one mip level, 4 bytes a texel, `COPY_DST`) with `texels`, rows top to
/// bottom, tightly packed: through a staging buffer whose rows are padded to wgpu's 256-byte copy
/// alignment, and a copy submitted on `queue`. `what` names the texture in an error.
pub(crate) fn texture_init(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    texels: &[u8],
    what: &dyn Fn() -> String,
) -> Result<(), GpuError> {
    let (width, height) = (texture.width(), texture.height());
    let row = 4 * width as usize;
    assert_eq!(
        texels.len(),
        row * height as usize,
        "{}: texel bytes",
        what()
    );
    let padded_row = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT as usize);
    let mut padded;
    let contents = if padded_row == row {
        texels
    } else {
        padded = vec![0u8; padded_row * height as usize];
        for (to, from) in padded
            .chunks_exact_mut(padded_row)
            .zip(texels.chunks_exact(row))
        {
            to[..row].copy_from_slice(from);
        }
        &padded[..]
    };
    let source = staging(device, what, contents, contents.len() as u64)?;
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("texture upload"),
    });
    encoder.copy_buffer_to_texture(
        wgpu::TexelCopyBufferInfo {
            buffer: &source,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row as u32),
                rows_per_image: Some(height),
            },
        },
        texture.as_image_copy(),
        texture.size(),
    );
    queue.submit([encoder.finish()]);
    Ok(())
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
