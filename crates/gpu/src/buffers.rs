//! Storage buffers that grow, and the upload of a frame's lights and light lists through a ring of
//! staging buffers ([`wgpu::util::StagingBelt`]: mapped chunks written by the CPU, copied on the
//! GPU timeline, and handed back for reuse once that submission has finished).
//!
//! Nothing is ever truncated: a buffer too small for this frame is replaced by one of the next
//! power of two (and the bind groups that name it are rebuilt); a size beyond what the device can
//! bind is an error ([`GpuError::BufferTooLarge`]), never a cut list.

use crate::GpuError;
use crate::out_of_memory::catching;
use std::num::NonZeroU64;

/// The smallest buffer created: storage bindings may not be empty.
const MIN_BYTES: u64 = 256;

/// A `STORAGE | COPY_DST | COPY_SRC` buffer that is replaced by a larger one when needed.
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
            // COPY_SRC: the renderer reads its lists back on request (`read_back_lists`).
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })
    }

    /// What the buffer holds, for messages ("light indices").
    pub fn label(&self) -> &'static str {
        self.label
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
        let limit = storage_capacity(&device.limits());
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
        if bytes <= self.buffer.size() {
            return Ok(false);
        }
        let size = grown_size(bytes, storage_capacity(&device.limits()));
        // A frame of a million lights' lists on a GPU with little memory.
        let what = || format!("the {} buffer of {size} bytes", self.label);
        self.buffer = catching(device, what, || Self::create(device, self.label, size))?;
        Ok(true)
    }
}

/// The most bytes a storage buffer may hold and still be created and bound whole on a device
/// with `limits`: the smaller of its binding and buffer limits, rounded down to the 4 bytes that
/// copies and storage bindings come in.
///
/// Both limits matter, and neither is a multiple of 4 by rule: wgpu reports a Vulkan device's
/// binding limit as at most `i32::MAX` (2³¹ − 1, where desktop drivers sit), and a device may
/// be created with a binding limit above its buffer limit. Sized from the binding limit alone,
/// a list of 1–2 GiB passed the check, grew to 2³¹ bytes and made wgpu panic (a buffer or
/// binding over the limit) instead of returning [`GpuError::BufferTooLarge`].
pub fn storage_capacity(limits: &wgpu::Limits) -> u64 {
    let limit = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    limit & !(wgpu::COPY_BUFFER_ALIGNMENT - 1)
}

/// The size a buffer grows to for `bytes` (at most `capacity`, a [`storage_capacity`]): the
/// next power of two, so a growing scene replaces it rarely, but never past `capacity`, at
/// least [`MIN_BYTES`], and a multiple of 4.
fn grown_size(bytes: u64, capacity: u64) -> u64 {
    debug_assert!(bytes <= capacity, "checked by `check_fits`");
    bytes
        .next_power_of_two()
        .clamp(MIN_BYTES, capacity.max(MIN_BYTES))
        .max(bytes)
        .next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
}

/// Writes `data` into `target` at offset 0 through the staging belt; returns the bytes staged.
/// Empty data stages nothing.
///
/// A frame larger than any free chunk of the belt gets a new mapped chunk of its size, host
/// memory the process may not have (a million lights' lists are hundreds of megabytes). wgpu
/// raises that as an out-of-memory error, and `StagingBelt::write_buffer` then panics on the
/// chunk it could not map; so the chunk is allocated here inside an error scope, and running out
/// is [`GpuError::OutOfMemory`]. The belt then holds a chunk that was never made: the caller
/// replaces the belt (the renderer's `forget_uploads`).
pub fn stage<T: bytemuck::Pod>(
    device: &wgpu::Device,
    belt: &mut wgpu::util::StagingBelt,
    encoder: &mut wgpu::CommandEncoder,
    target: &GrowableBuffer,
    data: &[T],
) -> Result<u64, GpuError> {
    let bytes: &[u8] = bytemuck::cast_slice(data);
    let padded = (bytes.len() as u64).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
    let Some(size) = NonZeroU64::new(padded) else {
        return Ok(0);
    };
    debug_assert!(padded <= target.capacity(), "reserve before staging");
    let what = || {
        format!(
            "the staging copy of the {} buffer ({padded} bytes of host memory)",
            target.label
        )
    };
    let alignment = const { NonZeroU64::new(wgpu::COPY_BUFFER_ALIGNMENT).unwrap() };
    let slice = catching(device, what, || belt.allocate(size, alignment))?;
    let mut view = slice
        .get_mapped_range_mut()
        .map_err(|error| GpuError::OutOfMemory(format!("{}: {error}", what())))?;
    view.slice(..bytes.len()).copy_from_slice(bytes);
    view.slice(bytes.len()..).fill(0);
    drop(view);
    encoder.copy_buffer_to_buffer(slice.buffer(), slice.offset(), target.buffer(), 0, padded);
    Ok(padded)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A device whose storage bindings hold `binding` bytes and whose buffers `buffer`.
    fn limits(binding: u64, buffer: u64) -> wgpu::Limits {
        wgpu::Limits {
            max_storage_buffer_binding_size: binding,
            max_buffer_size: buffer,
            ..wgpu::Limits::default()
        }
    }

    /// The capacity is the smaller limit, rounded down to 4 bytes: a desktop Vulkan driver's
    /// `i32::MAX` binding limit gives 2³¹ − 4, and a binding limit above the buffer limit
    /// gives the buffer limit.
    #[test]
    fn capacity_is_the_smaller_limit_in_whole_words() {
        let i32_max = i32::MAX as u64;
        assert_eq!(storage_capacity(&limits(i32_max, 1 << 40)), i32_max - 3);
        assert_eq!(storage_capacity(&limits(1 << 30, 1 << 28)), 1 << 28);
        assert_eq!(storage_capacity(&limits(1 << 27, 1 << 28)), 1 << 27);
        assert_eq!(storage_capacity(&limits(1001, 1 << 28)), 1000);
    }

    /// Every size a buffer can be asked for grows to one that fits the device, holds the
    /// bytes and is a multiple of 4 — in particular between 1 GiB and the limit, where the
    /// next power of two (2³¹) is past a 2³¹ − 1 binding limit.
    #[test]
    fn grown_buffers_fit_the_device_and_hold_the_bytes() {
        let i32_max = i32::MAX as u64;
        for limits in [
            limits(i32_max, 1 << 40),
            limits(i32_max, i32_max),
            limits(1 << 30, 1 << 28),
            limits(1 << 27, 1 << 28),
            limits(1001, 1 << 28),
        ] {
            let capacity = storage_capacity(&limits);
            let asked = [1, 3, 255, 257, 1000, 1 << 20, (1 << 20) + 1]
                .into_iter()
                .chain([capacity / 2 + 1, capacity - 5, capacity - 1, capacity]);
            for bytes in asked.filter(|&b| b <= capacity) {
                let size = grown_size(bytes, capacity);
                assert!(size >= bytes, "{bytes} bytes grew to {size}");
                assert!(
                    size <= capacity.max(MIN_BYTES),
                    "{bytes} bytes grew to {size}, past the capacity {capacity}"
                );
                assert_eq!(size % wgpu::COPY_BUFFER_ALIGNMENT, 0, "{bytes} → {size}");
                assert!(size >= MIN_BYTES.min(capacity), "{bytes} → {size}");
            }
        }
        // Small requests still grow by powers of two.
        assert_eq!(grown_size(1000, 1 << 27), 1024);
        assert_eq!(grown_size(1, 1 << 27), MIN_BYTES);
    }
}
