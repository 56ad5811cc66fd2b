//! Render targets: the G-buffer the deferred pass reads, and a headless colour target.

use crate::GpuError;
use crate::out_of_memory::catching;

/// G-buffer formats. Albedo is sRGB-encoded (8 bits are enough after encoding); the normal is
/// octahedral in two 16-bit floats; roughness and metallic in 8-bit unorm; depth in f32 so the
/// view depth reconstructed for the cluster lookup is as precise as the CPU's.
pub const ALBEDO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// See [`ALBEDO_FORMAT`].
pub const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;
/// See [`ALBEDO_FORMAT`].
pub const MATERIAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// The G-buffer's depth (f32, reversed Z: 1 at the near plane, 0 at the far plane and where
/// nothing was drawn): what an engine drawing against [`crate::Renderer::gbuffer`]'s depth builds
/// its pipelines with, comparing `Greater`. Reversed Z keeps ~7 significant digits of depth at
/// every distance (`Camera::clip_from_view`), so the near plane may go down to the grids' floor,
/// `ClusterGrid::MIN_NEAR` (1e-12), which `Camera::problem` enforces: far below it (near 1e-34
/// on llvmpipe) the stored depths left f32's normal range and pixels went missing.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The colour format headless targets use (and read back as RGBA8).
pub const HEADLESS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// The G-buffer textures for one target size.
#[derive(Debug)]
pub struct GBuffer {
    /// Width and height in pixels.
    pub size: (u32, u32),
    /// Albedo (sRGB).
    pub albedo: wgpu::TextureView,
    /// Octahedral normal.
    pub normal: wgpu::TextureView,
    /// Roughness, metallic.
    pub material: wgpu::TextureView,
    /// Depth.
    pub depth: wgpu::TextureView,
    /// The depth texture (read back for lights-per-pixel statistics and active clusters).
    pub depth_texture: wgpu::Texture,
}

impl GBuffer {
    /// Creates the textures for a `width × height` target. A size of 0 or beyond the device's
    /// largest 2D texture is [`GpuError::InvalidInput`] (wgpu would panic on it), one the device
    /// has no memory for [`GpuError::OutOfMemory`].
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Result<Self, GpuError> {
        check_target_size(device, width, height)?;
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        let texture = |label, format| texture_2d(device, label, (width, height), format, usage);
        let view = |label, format| {
            texture(label, format).map(|t| t.create_view(&wgpu::TextureViewDescriptor::default()))
        };
        let depth_texture = texture("gbuffer depth", DEPTH_FORMAT)?;
        Ok(Self {
            size: (width, height),
            albedo: view("gbuffer albedo", ALBEDO_FORMAT)?,
            normal: view("gbuffer normal", NORMAL_FORMAT)?,
            material: view("gbuffer material", MATERIAL_FORMAT)?,
            depth: depth_texture.create_view(&wgpu::TextureViewDescriptor::default()),
            depth_texture,
        })
    }
}

/// A colour texture to render into headless and read back ([`crate::read_rgba8`]).
#[derive(Debug)]
pub struct HeadlessTarget {
    /// The texture (RENDER_ATTACHMENT | COPY_SRC).
    pub texture: wgpu::Texture,
    /// Its default view.
    pub view: wgpu::TextureView,
}

impl HeadlessTarget {
    /// A `width × height` [`HEADLESS_FORMAT`] target. A size of 0 or beyond the device's
    /// largest 2D texture is [`GpuError::InvalidInput`] (wgpu would panic on it), one the device
    /// has no memory for [`GpuError::OutOfMemory`].
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Result<Self, GpuError> {
        check_target_size(device, width, height)?;
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let size = (width, height);
        let texture = texture_2d(device, "headless target", size, HEADLESS_FORMAT, usage)?;
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        Ok(Self { texture, view })
    }
}

/// Whether `device` can make `width × height` render targets.
pub(crate) fn check_target_size(
    device: &wgpu::Device,
    width: u32,
    height: u32,
) -> Result<(), GpuError> {
    let max = device.limits().max_texture_dimension_2d;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(GpuError::InvalidInput(format!(
            "a {width}x{height} target: this device's 2D textures are 1 to {max} pixels a side"
        )));
    }
    Ok(())
}

/// A single-sampled 2D texture without mips: every target here.
fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> Result<wgpu::Texture, GpuError> {
    let what = || format!("the {label} texture ({width}x{height} {format:?})");
    catching(device, what, || {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    })
}
