//! Storage buffers that grow, and the upload of a frame's lights and light lists through a ring of
//! staging buffers ([`wgpu::util::StagingBelt`]: mapped chunks written by the CPU, copied on the
//! GPU timeline, and handed back for reuse once that submission has finished).
//!
//! Nothing is ever truncated: a buffer too small for this frame is replaced by one of the next
//! power of two (and the bind groups that name it are rebuilt); a size beyond what the device can
//! bind is an error ([`GpuError::BufferTooLarge`]), never a cut list.

use crate::GpuError;
use std::num::NonZeroU64;

/// The smallest buffer created: storage bindings may not be empty.
const MIN_BYTES: u64 = 256;

/// A `STORAGE | COPY_DST` buffer that is replaced by a larger one when needed.
#[derive(Debug)]
pub struct GrowableBuffer {
    label: &'static str,
    buffer: wgpu::Buffer,
}

impl GrowableBuffer {
    /// An empty buffer of [`MIN_BYTES`].
    pub fn new(device: &wgpu::Device, label: &'static str) -> Self {
        Self {
            label,
            buffer: Self::create(device, label, MIN_BYTES),
        }
    }

    fn create(device: &wgpu::Device, label: &'static str, size: u64) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// The current buffer.
    pub fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }

    /// Current capacity in bytes.
    pub fn capacity(&self) -> u64 {
        self.buffer.size()
    }

    /// Whether `bytes` fit in one binding on `device` (what [`GrowableBuffer::reserve`] would
    /// refuse), without touching the buffer: a frame checks every buffer before changing any.
    pub fn check_fits(&self, device: &wgpu::Device, bytes: u64) -> Result<(), GpuError> {
        let limit = device.limits().max_storage_buffer_binding_size;
        if bytes > limit {
            return Err(GpuError::BufferTooLarge {
                what: self.label,
                bytes,
                limit,
            });
        }
        Ok(())
    }

    /// Makes room for `bytes`; returns true when the buffer was replaced (its contents are lost
    /// and bind groups naming it must be rebuilt).
    pub fn reserve(&mut self, device: &wgpu::Device, bytes: u64) -> Result<bool, GpuError> {
        self.check_fits(device, bytes)?;
        let limit = device.limits().max_storage_buffer_binding_size;
        if bytes <= self.buffer.size() {
            return Ok(false);
        }
        let size = bytes
            .next_power_of_two()
            .clamp(MIN_BYTES, limit.max(MIN_BYTES));
        let size = size
            .max(bytes)
            .next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
        self.buffer = Self::create(device, self.label, size);
        Ok(true)
    }
}

/// Writes `data` into `target` at offset 0 through the staging belt; returns the bytes staged.
/// Empty data stages nothing.
pub fn stage<T: bytemuck::Pod>(
    belt: &mut wgpu::util::StagingBelt,
    encoder: &mut wgpu::CommandEncoder,
    target: &GrowableBuffer,
    data: &[T],
) -> u64 {
    let bytes: &[u8] = bytemuck::cast_slice(data);
    let padded = (bytes.len() as u64).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
    let Some(size) = NonZeroU64::new(padded) else {
        return 0;
    };
    debug_assert!(padded <= target.capacity(), "reserve before staging");
    let mut view = belt.write_buffer(encoder, target.buffer(), 0, size);
    view.slice(..bytes.len()).copy_from_slice(bytes);
    view.slice(bytes.len()..).fill(0);
    padded
}
