//! Reading a rendered texture back to the CPU and saving it as PNG.

use crate::out_of_memory::catching;
use crate::{GpuContext, GpuError};

/// Copies an RGBA8 (`Rgba8Unorm` or `Rgba8UnormSrgb`) texture into a tightly packed
/// `width·height·4` byte vector, rows top to bottom. Blocks until the GPU is done.
///
/// Any other format (a `Bgra8` swap chain's came back with its channels swapped), or a texture
/// without `COPY_SRC` usage, is an [`GpuError::InvalidInput`].
pub fn read_rgba8(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<u8>, GpuError> {
    use wgpu::TextureFormat::{Rgba8Unorm, Rgba8UnormSrgb};
    if !matches!(texture.format(), Rgba8Unorm | Rgba8UnormSrgb) {
        return Err(GpuError::InvalidInput(format!(
            "read_rgba8 reads Rgba8Unorm or Rgba8UnormSrgb textures, not {:?}",
            texture.format()
        )));
    }
    copy_texels(ctx, texture, 4, wgpu::TextureAspect::All)
}

/// Copies a colour texture of any uncompressed format into its texels as they are stored,
/// tightly packed, rows top to bottom (an engine's `Rgba16Float` view or `Bgra8UnormSrgb`
/// swap-chain image; [`read_rgba8`] is this for the two RGBA8 formats). Depth and compressed
/// formats are refused ([`read_depth`] reads depth).
pub fn read_texels(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<u8>, GpuError> {
    let format = texture.format();
    match format.block_copy_size(None) {
        Some(bytes) if format.block_dimensions() == (1, 1) && !format.is_depth_stencil_format() => {
            copy_texels(ctx, texture, bytes, wgpu::TextureAspect::All)
        }
        _ => Err(GpuError::InvalidInput(format!(
            "read_texels reads uncompressed colour textures, not {format:?}"
        ))),
    }
}

/// Copies a `Depth32Float` texture into one f32 per pixel, rows top to bottom.
pub fn read_depth(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<f32>, GpuError> {
    if texture.format() != wgpu::TextureFormat::Depth32Float {
        return Err(GpuError::InvalidInput(format!(
            "read_depth reads Depth32Float textures, not {:?}",
            texture.format()
        )));
    }
    let bytes = copy_texels(ctx, texture, 4, wgpu::TextureAspect::DepthOnly)?;
    Ok(bytemuck::cast_slice(&bytes).to_vec())
}

/// Copies a single-mip 2D texture of `texel_bytes` per texel, tightly packed.
fn copy_texels(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    texel_bytes: u32,
    aspect: wgpu::TextureAspect,
) -> Result<Vec<u8>, GpuError> {
    ctx.check_not_lost()?;
    // Layers overran the buffer sized for one, and multisampled textures cannot be copied.
    if texture.sample_count() != 1
        || texture.depth_or_array_layers() != 1
        || texture.dimension() != wgpu::TextureDimension::D2
    {
        return Err(GpuError::InvalidInput(format!(
            "only single-sample, single-layer 2D textures are read back; this one is {:?} with \
             {} layers and {} samples",
            texture.dimension(),
            texture.depth_or_array_layers(),
            texture.sample_count()
        )));
    }
    if !texture.usage().contains(wgpu::TextureUsages::COPY_SRC) {
        return Err(GpuError::InvalidInput(
            "the texture to read back lacks COPY_SRC usage".into(),
        ));
    }
    let (width, height) = (texture.width(), texture.height());
    let row = width * texel_bytes;
    let padded_row =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    // In u64: a 32768² RGBA8 target is 4 GiB, past u32 (and past many devices' buffers, where
    // wgpu would panic instead of returning an error).
    let size = u64::from(padded_row) * u64::from(height);
    let limit = ctx.device.limits().max_buffer_size;
    if size > limit {
        return Err(GpuError::InvalidInput(format!(
            "reading back a {width} × {height} texture needs a {size}-byte buffer, more than \
             this device's max_buffer_size ({limit} bytes)"
        )));
    }
    let what = || format!("the read-back buffer of a {width} × {height} texture ({size} bytes)");
    let buffer = readback_buffer(&ctx.device, size, what)?;
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("readback"),
        });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            aspect,
            ..texture.as_image_copy()
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row),
                rows_per_image: Some(height),
            },
        },
        texture.size(),
    );
    ctx.queue.submit([encoder.finish()]);
    let bytes = map_and_read(ctx, &buffer)?;
    let mut out = Vec::with_capacity(row as usize * height as usize);
    for y in 0..height as usize {
        let start = y * padded_row as usize;
        out.extend_from_slice(&bytes[start..start + row as usize]);
    }
    Ok(out)
}

/// A `COPY_DST | MAP_READ` buffer of `size` bytes (at least 4) to copy GPU data into and map;
/// running out of memory for it is [`GpuError::OutOfMemory`] naming `what`.
pub(crate) fn readback_buffer(
    device: &wgpu::Device,
    size: u64,
    what: impl FnOnce() -> String,
) -> Result<wgpu::Buffer, GpuError> {
    catching(device, what, || {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("read-back"),
            size: size.max(wgpu::COPY_BUFFER_ALIGNMENT),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        })
    })
}

/// Maps a `MAP_READ` buffer, waits, and returns a copy of its contents.
pub(crate) fn map_and_read(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    map_and_read_with(ctx, buffer, <[u8]>::to_vec)
}

/// Maps a `MAP_READ` buffer, waits, and returns what `read` makes of its contents (without the
/// whole copy [`map_and_read`] makes first: a million lights' lists are 90 MiB).
pub(crate) fn map_and_read_with<T>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    read: impl FnOnce(&[u8]) -> T,
) -> Result<T, GpuError> {
    // On a lost device `map_async` raises a validation error, which wgpu's default handler
    // turns into a panic: a known loss is an error before it.
    ctx.check_not_lost()?;
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |result| {
        let _ = tx.send(result);
    });
    ctx.wait_idle()?;
    rx.recv()
        .map_err(|e| GpuError::Readback(e.to_string()))?
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    let view = slice
        .get_mapped_range()
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    let out = read(&view);
    drop(view);
    buffer.unmap();
    Ok(out)
}

#[cfg(feature = "image")]
/// Saves tightly packed RGBA8 pixels as a PNG, creating the parent directory. It writes in
/// place; to replace an existing file only once the new one is whole, write [`encode_png`]'s
/// bytes to a temporary file and rename it (the `myriad` tool does, with
/// `myriad_scene::replace_files`, so an image and the files written beside it are replaced as a
/// set).
pub fn save_png(
    path: &std::path::Path,
    rgba: &[u8],
    width: u32,
    height: u32,
) -> Result<(), image::ImageError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(image::ImageError::IoError)?;
    }
    image::save_buffer(path, rgba, width, height, image::ExtendedColorType::Rgba8)
}

#[cfg(feature = "image")]
/// Tightly packed RGBA8 pixels as the bytes of a PNG file. A buffer whose length is not
/// `4 · width · height` is an error (the encoder itself would panic).
pub fn encode_png(rgba: &[u8], width: u32, height: u32) -> Result<Vec<u8>, image::ImageError> {
    use image::ImageEncoder;
    use image::error::{ParameterError, ParameterErrorKind};
    if rgba.len() as u64 != 4 * width as u64 * height as u64 {
        return Err(image::ImageError::Parameter(ParameterError::from_kind(
            ParameterErrorKind::DimensionMismatch,
        )));
    }
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png).write_image(
        rgba,
        width,
        height,
        image::ExtendedColorType::Rgba8,
    )?;
    Ok(png)
}

#[cfg(all(test, feature = "image"))]
mod tests {
    use super::*;

    #[test]
    fn encoded_png_decodes_to_the_same_pixels() {
        let rgba: Vec<u8> = (0..3 * 2 * 4).map(|v| (v * 11) as u8).collect();
        let png = encode_png(&rgba, 3, 2).unwrap();
        let back = image::load_from_memory(&png).unwrap().to_rgba8();
        assert_eq!(back.dimensions(), (3, 2));
        assert_eq!(back.into_raw(), rgba);
        assert!(
            encode_png(&rgba, 4, 2).is_err(),
            "a size that disagrees with the pixels"
        );
    }

    /// `save_png` creates the missing directories above the file and writes a PNG that decodes
    /// to the same pixels.
    #[test]
    fn saved_png_creates_its_directories_and_decodes_to_the_same_pixels() {
        let rgba: Vec<u8> = (0..2 * 3 * 4).map(|v| (v * 7) as u8).collect();
        let dir = std::env::temp_dir().join(format!("myriad-gpu-save-png-{}", std::process::id()));
        let path = dir.join("nested").join("image.png");
        let _ = std::fs::remove_dir_all(&dir);
        save_png(&path, &rgba, 2, 3).unwrap();
        let back = image::open(&path).unwrap().to_rgba8();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(back.dimensions(), (2, 3));
        assert_eq!(back.into_raw(), rgba);
    }
}
