//! Scene geometry on the GPU: one vertex and one index buffer for everything (world space), a
//! draw per primitive, and a bind group per material.
//!
//! The renderer takes plain arrays ([`SceneGeometry`]) rather than a glTF model so that it does
//! not depend on `myriad-scene`; the facade flattens a model into them.

use crate::GpuError;
use crate::layout::{MaterialUniforms, Vertex};
use crate::out_of_memory::{buffer_init, catching, texture_init};
use glam::Vec3;

/// One draw: a range of the index buffer with one material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Draw {
    /// First index in [`SceneGeometry::indices`].
    pub first_index: u32,
    /// Number of indices (a multiple of 3).
    pub index_count: u32,
    /// Index into [`SceneGeometry::materials`].
    pub material: u32,
    /// Centre of the draw's bounds (sorting blended draws back to front).
    pub center: Vec3,
}

/// How a material's alpha is used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Blend {
    /// Opaque, or alpha-tested against `alpha_cutoff`: drawn into the G-buffer.
    Opaque,
    /// Alpha-blended: drawn by the clustered forward pass.
    Blended,
}

/// A material: its constants, blending and optional base-colour texture.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialDesc {
    /// The uniform block.
    pub uniforms: MaterialUniforms,
    /// G-buffer or forward pass.
    pub blend: Blend,
    /// Index into [`SceneGeometry::textures`].
    pub base_color_texture: Option<u32>,
}

/// An sRGB RGBA8 texture, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureRgba8 {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width·height·4` bytes.
    pub pixels: Vec<u8>,
}

impl TextureRgba8 {
    /// Whether `pixels` holds `width·height·4` bytes, counted in u128: in u64 a 2^31 × 2^31
    /// texture needs 2^64 bytes, which wrapped to 0 and passed with no pixels, and
    /// `SceneGeometry::fit_textures` then panicked (audit).
    fn bytes_match_size(&self) -> bool {
        self.pixels.len() as u128 == self.width as u128 * self.height as u128 * 4
    }
}

/// Everything the renderer draws, flattened.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneGeometry {
    /// World-space vertices.
    pub vertices: Vec<Vertex>,
    /// Triangle-list indices into `vertices`.
    pub indices: Vec<u32>,
    /// Draws, any order.
    pub draws: Vec<Draw>,
    /// Materials the draws name.
    pub materials: Vec<MaterialDesc>,
    /// Textures the materials name.
    pub textures: Vec<TextureRgba8>,
}

impl SceneGeometry {
    /// Whether any draw uses a blended material (the forward pass runs only then). A draw whose
    /// material is out of range counts as not blended ([`Self::check`] refuses it).
    pub fn has_blended(&self) -> bool {
        self.draws.iter().any(|d| {
            self.materials
                .get(d.material as usize)
                .is_some_and(|m| m.blend == Blend::Blended)
        })
    }

    /// Checks that every index, material and texture reference is in range, and that every
    /// texture's bytes match its size — the unreferenced ones too, since all are uploaded.
    pub fn check(&self) -> Result<(), String> {
        if let Some(&i) = self
            .indices
            .iter()
            .find(|&&i| i as usize >= self.vertices.len())
        {
            return Err(format!("index {i} >= vertex count {}", self.vertices.len()));
        }
        for (n, d) in self.draws.iter().enumerate() {
            let end = d.first_index as u64 + d.index_count as u64;
            if end > self.indices.len() as u64 || d.index_count % 3 != 0 {
                return Err(format!(
                    "draw {n} covers indices {}..{end} of {}",
                    d.first_index,
                    self.indices.len()
                ));
            }
            if d.material as usize >= self.materials.len() {
                return Err(format!(
                    "draw {n} names material {} of {}",
                    d.material,
                    self.materials.len()
                ));
            }
        }
        for (n, m) in self.materials.iter().enumerate() {
            if let Some(t) = m.base_color_texture
                && t as usize >= self.textures.len()
            {
                return Err(format!(
                    "material {n} names texture {t} of {}",
                    self.textures.len()
                ));
            }
        }
        for (t, tex) in self.textures.iter().enumerate() {
            if !tex.bytes_match_size() || tex.width == 0 || tex.height == 0 {
                return Err(format!(
                    "texture {t} is {}x{} with {} bytes",
                    tex.width,
                    tex.height,
                    tex.pixels.len()
                ));
            }
        }
        Ok(())
    }

    /// Checks the sizes against what `limits` allow: every texture's sides against
    /// `max_texture_dimension_2d`, the vertex and index buffers against `max_buffer_size`. Past
    /// them wgpu raises a validation error, which panics in its default handler, so the upload
    /// refuses them first (`fit_textures`, feature `image`, scales textures down instead).
    pub fn check_limits(&self, limits: &wgpu::Limits) -> Result<(), String> {
        let max_side = limits.max_texture_dimension_2d;
        if let Some((n, t)) = self
            .textures
            .iter()
            .enumerate()
            .find(|(_, t)| t.width.max(t.height) > max_side)
        {
            return Err(format!(
                "texture {n} is {}x{}, larger than this device's {max_side}-pixel limit \
                 (SceneGeometry::fit_textures scales textures down to fit)",
                t.width, t.height
            ));
        }
        for (what, bytes) in [
            ("vertex", std::mem::size_of_val(self.vertices.as_slice())),
            ("index", std::mem::size_of_val(self.indices.as_slice())),
        ] {
            if bytes as u64 > limits.max_buffer_size {
                return Err(format!(
                    "the {what} buffer needs {bytes} bytes, more than this device's buffer limit \
                     ({} bytes)",
                    limits.max_buffer_size
                ));
            }
        }
        Ok(())
    }

    #[cfg(feature = "image")]
    /// Scales every texture with a side above `max_side` down to fit (aspect kept, each side at
    /// least 1 pixel; a triangle filter on the sRGB values) and returns one note per texture
    /// scaled. A renderer must take what the device can sample; a smaller texture is the
    /// usual engine answer to one that is too large.
    pub fn fit_textures(&mut self, max_side: u32) -> Vec<String> {
        let max_side = max_side.max(1);
        let mut notes = Vec::new();
        for (n, t) in self.textures.iter_mut().enumerate() {
            let side = t.width.max(t.height);
            // A texture whose bytes do not match its size is left for `check` to report.
            if side <= max_side || !t.bytes_match_size() {
                continue;
            }
            let scale = |v: u32| ((v as u64 * max_side as u64 / side as u64) as u32).max(1);
            let (width, height) = (scale(t.width), scale(t.height));
            let image =
                image::RgbaImage::from_raw(t.width, t.height, std::mem::take(&mut t.pixels))
                    .expect("the byte count was checked");
            let small = image::imageops::resize(
                &image,
                width,
                height,
                image::imageops::FilterType::Triangle,
            );
            notes.push(format!(
                "texture {n} scaled from {}x{} to {width}x{height} (the device's limit is \
                 {max_side} pixels a side)",
                t.width, t.height
            ));
            *t = TextureRgba8 {
                width,
                height,
                pixels: small.into_raw(),
            };
        }
        notes
    }
}

/// The scene's GPU resources, on the device of the renderer that uploaded it.
#[derive(Debug)]
pub struct GpuScene {
    /// The device its buffers live on: a renderer refuses a scene of another device.
    pub(crate) device: wgpu::Device,
    pub(crate) vertex_buffer: wgpu::Buffer,
    pub(crate) index_buffer: wgpu::Buffer,
    pub(crate) opaque: Vec<Draw>,
    pub(crate) blended: Vec<Draw>,
    pub(crate) material_groups: Vec<wgpu::BindGroup>,
    triangles: usize,
}

impl GpuScene {
    /// Uploads `geometry`; `material_layout` is the renderer's material bind group layout.
    /// Geometry or textures past the device's memory are [`GpuError::OutOfMemory`].
    pub(crate) fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        material_layout: &wgpu::BindGroupLayout,
        geometry: &SceneGeometry,
    ) -> Result<Self, GpuError> {
        // Buffers may not be empty; a scene with no geometry still gets valid (unused) ones.
        let vertices: &[Vertex] = if geometry.vertices.is_empty() {
            &[Vertex::default()]
        } else {
            &geometry.vertices
        };
        let indices: &[u32] = if geometry.indices.is_empty() {
            &[0, 0, 0]
        } else {
            &geometry.indices
        };
        let vertex_buffer = buffer_init(
            device,
            queue,
            "scene vertices",
            bytemuck::cast_slice(vertices),
            wgpu::BufferUsages::VERTEX,
        )?;
        let index_buffer = buffer_init(
            device,
            queue,
            "scene indices",
            bytemuck::cast_slice(indices),
            wgpu::BufferUsages::INDEX,
        )?;
        let textures = geometry
            .textures
            .iter()
            .map(|t| upload_texture(device, queue, t))
            .collect::<Result<Vec<_>, _>>()?;
        let white = upload_texture(
            device,
            queue,
            &TextureRgba8 {
                width: 1,
                height: 1,
                pixels: vec![255; 4],
            },
        )?;
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("material sampler"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        // Every material's uniforms in one buffer, each at an offset a uniform binding may
        // start at: one allocation and one upload for any number of materials.
        let size = std::mem::size_of::<MaterialUniforms>();
        let stride =
            size.next_multiple_of(device.limits().min_uniform_buffer_offset_alignment as usize);
        let mut bytes = vec![0u8; stride * geometry.materials.len()];
        for (m, at) in geometry
            .materials
            .iter()
            .zip(bytes.chunks_exact_mut(stride))
        {
            at[..size].copy_from_slice(bytemuck::bytes_of(&m.uniforms));
        }
        let uniforms = buffer_init(
            device,
            queue,
            "materials",
            &bytes,
            wgpu::BufferUsages::UNIFORM,
        )?;
        let material_groups = geometry
            .materials
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let texture = m
                    .base_color_texture
                    .map_or(&white, |t| &textures[t as usize]);
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("material"),
                    layout: material_layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                buffer: &uniforms,
                                offset: (i * stride) as u64,
                                size: wgpu::BufferSize::new(size as u64),
                            }),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: wgpu::BindingResource::TextureView(texture),
                        },
                        wgpu::BindGroupEntry {
                            binding: 2,
                            resource: wgpu::BindingResource::Sampler(&sampler),
                        },
                    ],
                })
            })
            .collect();
        let (blended, opaque): (Vec<Draw>, Vec<Draw>) = geometry
            .draws
            .iter()
            .partition(|d| geometry.materials[d.material as usize].blend == Blend::Blended);
        Ok(Self {
            device: device.clone(),
            vertex_buffer,
            index_buffer,
            opaque,
            blended,
            material_groups,
            triangles: geometry.indices.len() / 3,
        })
    }

    /// Whether the forward pass has anything to draw.
    pub fn has_blended(&self) -> bool {
        !self.blended.is_empty()
    }

    /// Triangles uploaded.
    pub fn triangle_count(&self) -> usize {
        self.triangles
    }

    /// Blended draws sorted far to near from `camera` (stable for equal distances), into
    /// `out` (reused frame to frame).
    pub(crate) fn blended_back_to_front(&self, camera: Vec3, out: &mut Vec<Draw>) {
        out.clear();
        out.extend_from_slice(&self.blended);
        out.sort_by(|a, b| {
            b.center
                .distance_squared(camera)
                .total_cmp(&a.center.distance_squared(camera))
        });
    }
}

/// A base-colour texture holding `texture`'s pixels.
fn upload_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &TextureRgba8,
) -> Result<wgpu::TextureView, GpuError> {
    let size = wgpu::Extent3d {
        width: texture.width,
        height: texture.height,
        depth_or_array_layers: 1,
    };
    let what = || {
        format!(
            "a {}x{} base-colour texture ({} bytes)",
            texture.width,
            texture.height,
            texture.pixels.len()
        )
    };
    // Made, then written (wgpu's `create_texture_with_data` does both, and writing into a
    // texture that could not be made is a second, uncaught error).
    let made = catching(device, what, || {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some("base colour"),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8UnormSrgb,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        })
    })?;
    texture_init(device, queue, &made, &texture.pixels, &what)?;
    Ok(made.create_view(&wgpu::TextureViewDescriptor::default()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Four vertices, two triangles in one opaque draw, one opaque and one blended material,
    /// and a 2×2 texture the opaque material names: every reference in range.
    fn valid() -> SceneGeometry {
        let material = |blend| MaterialDesc {
            uniforms: MaterialUniforms::default(),
            blend,
            base_color_texture: None,
        };
        SceneGeometry {
            vertices: vec![Vertex::default(); 4],
            indices: vec![0, 1, 2, 2, 1, 3],
            draws: vec![Draw {
                first_index: 0,
                index_count: 6,
                material: 0,
                center: Vec3::ZERO,
            }],
            materials: vec![
                MaterialDesc {
                    base_color_texture: Some(0),
                    ..material(Blend::Opaque)
                },
                material(Blend::Blended),
            ],
            textures: vec![texture(2, 2)],
        }
    }

    fn texture(width: u32, height: u32) -> TextureRgba8 {
        TextureRgba8 {
            width,
            height,
            pixels: vec![200; (width * height * 4) as usize],
        }
    }

    fn draw(first_index: u32, index_count: u32, material: u32) -> Draw {
        Draw {
            first_index,
            index_count,
            material,
            center: Vec3::ZERO,
        }
    }

    /// `has_blended` is true only when a draw uses a blended material: a blended material no
    /// draw names does not count, nor does a draw naming a material out of range.
    #[test]
    fn has_blended_counts_only_drawn_blended_materials() {
        let mut geometry = valid();
        assert!(!geometry.has_blended(), "the blended material is not drawn");
        geometry.draws.push(draw(0, 3, 1));
        assert!(geometry.has_blended());
        geometry.draws[1].material = 7;
        assert!(
            !geometry.has_blended(),
            "out of range counts as not blended"
        );
    }

    /// Each reference `check` guards is refused just past its bound and accepted at it: the
    /// last vertex, a draw ending at the last index, the last material and the last texture.
    #[test]
    fn check_accepts_references_up_to_their_bounds_and_refuses_one_past() {
        assert_eq!(valid().check(), Ok(()));
        let with = |change: &dyn Fn(&mut SceneGeometry)| {
            let mut geometry = valid();
            change(&mut geometry);
            geometry.check()
        };
        // Indices against the vertex count.
        assert_eq!(with(&|g| g.indices[5] = 3), Ok(()));
        let e = with(&|g| g.indices[5] = 4).unwrap_err();
        assert!(e.contains("index 4 >= vertex count 4"), "{e}");
        // A draw's range against the indices: ending at the last one is fine.
        assert_eq!(with(&|g| g.draws[0] = draw(3, 3, 0)), Ok(()));
        let e = with(&|g| g.draws[0] = draw(6, 3, 0)).unwrap_err();
        assert!(e.contains("draw 0 covers indices 6..9 of 6"), "{e}");
        let e = with(&|g| g.draws[0] = draw(3, 6, 0)).unwrap_err();
        assert!(e.contains("draw 0 covers indices 3..9 of 6"), "{e}");
        // Whole triangles only, even inside the index buffer.
        let e = with(&|g| g.draws[0] = draw(0, 4, 0)).unwrap_err();
        assert!(e.contains("draw 0 covers indices 0..4 of 6"), "{e}");
        // Materials.
        assert_eq!(with(&|g| g.draws[0].material = 1), Ok(()));
        let e = with(&|g| g.draws[0].material = 2).unwrap_err();
        assert!(e.contains("draw 0 names material 2 of 2"), "{e}");
        // Textures, named by a material or not.
        assert_eq!(
            with(&|g| g.materials[1].base_color_texture = Some(0)),
            Ok(())
        );
        let e = with(&|g| g.materials[1].base_color_texture = Some(1)).unwrap_err();
        assert!(e.contains("material 1 names texture 1 of 1"), "{e}");
        for (width, height, bytes) in [(2, 2, 12), (2, 2, 20), (0, 2, 0), (2, 0, 0)] {
            let e = with(&|g| {
                g.textures.push(TextureRgba8 {
                    width,
                    height,
                    pixels: vec![0; bytes],
                })
            })
            .unwrap_err();
            let want = format!("texture 1 is {width}x{height} with {bytes} bytes");
            assert!(e.contains(&want), "{e}");
        }
    }

    /// `check_limits` accepts a texture side and buffer sizes equal to the device's limits and
    /// refuses one more.
    #[test]
    fn check_limits_accepts_sizes_at_the_limit_and_refuses_beyond() {
        let geometry = valid();
        let vertex_bytes = std::mem::size_of_val(geometry.vertices.as_slice()) as u64;
        let limits = wgpu::Limits {
            max_texture_dimension_2d: 2,
            max_buffer_size: vertex_bytes,
            ..wgpu::Limits::default()
        };
        assert_eq!(geometry.check_limits(&limits), Ok(()));
        let mut tall = geometry.clone();
        tall.textures.push(texture(1, 3));
        let e = tall.check_limits(&limits).unwrap_err();
        assert!(e.contains("texture 1 is 1x3"), "{e}");
        let mut more = geometry.clone();
        more.vertices.push(Vertex::default());
        let e = more.check_limits(&limits).unwrap_err();
        assert!(e.contains("the vertex buffer needs"), "{e}");
        let mut indices = geometry.clone();
        indices.indices.resize(vertex_bytes as usize / 4 + 1, 0);
        let e = indices.check_limits(&limits).unwrap_err();
        assert!(e.contains("the index buffer needs"), "{e}");
    }

    /// `fit_textures` scales only textures with a side above the limit, to the limit on their
    /// long side with the aspect kept (a short side rounds down, to at least 1 pixel), one note
    /// each; a texture at the limit, or one whose bytes do not match its size, is left as it is.
    #[test]
    fn fit_textures_scales_only_oversized_textures_keeping_the_aspect() {
        let mut geometry = valid();
        let mut odd = texture(8, 8);
        odd.pixels.pop();
        geometry.textures = vec![texture(8, 6), texture(4, 4), texture(1, 9), odd.clone()];
        let notes = geometry.fit_textures(4);
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(
            notes[0].starts_with("texture 0 scaled from 8x6 to 4x3"),
            "{notes:?}"
        );
        assert!(
            notes[1].starts_with("texture 2 scaled from 1x9 to 1x4"),
            "{notes:?}"
        );
        let sizes: Vec<_> = geometry
            .textures
            .iter()
            .map(|t| (t.width, t.height, t.pixels.len()))
            .collect();
        assert_eq!(sizes, [(4, 3, 48), (4, 4, 64), (1, 4, 16), (8, 8, 255)]);
        assert!(geometry.textures[0].pixels.iter().all(|&p| p == 200));
        assert_eq!(geometry.textures[3], odd);
    }

    /// A texture whose byte count passes u64 (2^31 × 2^31 × 4 = 2^64) does not match its empty
    /// pixels: `check` refuses it and `fit_textures` leaves it (it passed as 0 bytes, and the
    /// scaling panicked).
    #[test]
    fn a_texture_whose_byte_count_passes_u64_is_refused_not_scaled() {
        let mut geometry = valid();
        let huge = TextureRgba8 {
            width: 1 << 31,
            height: 1 << 31,
            pixels: Vec::new(),
        };
        geometry.textures = vec![huge.clone()];
        let e = geometry.check().unwrap_err();
        assert!(e.contains("2147483648x2147483648 with 0 bytes"), "{e}");
        assert!(geometry.fit_textures(8192).is_empty());
        assert_eq!(geometry.textures, [huge]);
    }
}
