//! A glTF [`Model`] flattened into the renderer's [`SceneGeometry`]: every instance's primitives
//! transformed to world space in one vertex/index array, a draw per primitive, materials with
//! their alpha mode, base-colour images converted to sRGB RGBA8.

use myriad_gpu::layout::{MaterialUniforms, Vertex};
use myriad_gpu::{Blend, Draw, MaterialDesc, SceneGeometry, TextureRgba8};
use myriad_scene::glam::{Mat3, Vec2, Vec3};
use myriad_scene::{AlphaMode, ImagePixels, Material, Model, PixelFormat};
use std::collections::HashMap;

/// Flattens `model`. Images without decoded pixels (loaded as references only) are left out and
/// their materials use the base colour factor alone.
pub fn scene_geometry(model: &Model) -> SceneGeometry {
    let mut geometry = SceneGeometry::default();
    let mut texture_of_image: HashMap<usize, Option<u32>> = HashMap::new();
    let default_material = Material::default();
    let material_count = model.materials.len();
    for material in model
        .materials
        .iter()
        .chain(std::iter::once(&default_material))
    {
        let texture = material.base_color_texture.and_then(|t| {
            *texture_of_image.entry(t.image).or_insert_with(|| {
                let pixels = model.images.get(t.image)?.pixels.as_ref()?;
                geometry.textures.push(to_rgba8(pixels));
                Some(geometry.textures.len() as u32 - 1)
            })
        });
        geometry.materials.push(material_desc(material, texture));
    }
    for instance in &model.instances {
        let Some(mesh) = model.meshes.get(instance.mesh) else {
            continue;
        };
        let world = instance.world_from_local;
        let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
        for primitive in &mesh.primitives {
            if primitive.indices.is_empty() {
                continue;
            }
            let base = geometry.vertices.len() as u32;
            let mut bounds_min = Vec3::splat(f32::INFINITY);
            let mut bounds_max = Vec3::splat(f32::NEG_INFINITY);
            for (v, &p) in primitive.positions.iter().enumerate() {
                let position = world.transform_point3(p);
                bounds_min = bounds_min.min(position);
                bounds_max = bounds_max.max(position);
                let normal = primitive
                    .normals
                    .get(v)
                    .map(|&n| (normal_matrix * n).normalize_or_zero())
                    .unwrap_or(Vec3::Y);
                let uv = primitive.tex_coords.get(v).copied().unwrap_or(Vec2::ZERO);
                geometry.vertices.push(Vertex {
                    position: position.to_array(),
                    normal: normal.to_array(),
                    uv: uv.to_array(),
                });
            }
            let first_index = geometry.indices.len() as u32;
            geometry
                .indices
                .extend(primitive.indices.iter().map(|&i| base + i));
            geometry.draws.push(Draw {
                first_index,
                index_count: primitive.indices.len() as u32,
                material: primitive
                    .material
                    .filter(|&m| m < material_count)
                    .unwrap_or(material_count) as u32,
                center: (bounds_min + bounds_max) * 0.5,
            });
        }
    }
    geometry
}

fn material_desc(material: &Material, texture: Option<u32>) -> MaterialDesc {
    let (blend, alpha_cutoff) = match material.alpha_mode {
        AlphaMode::Opaque => (Blend::Opaque, 0.0),
        AlphaMode::Mask { cutoff } => (Blend::Opaque, cutoff),
        AlphaMode::Blend => (Blend::Blended, 0.0),
    };
    MaterialDesc {
        uniforms: MaterialUniforms {
            base_color: material.base_color_factor.to_array(),
            emissive: material.emissive_factor.to_array(),
            roughness: material.roughness_factor.clamp(0.0, 1.0),
            metallic: material.metallic_factor.clamp(0.0, 1.0),
            alpha_cutoff,
            _pad0: 0,
            _pad1: 0,
        },
        blend,
        base_color_texture: texture,
    }
}

/// Converts decoded pixels of any channel layout to RGBA8 (16-bit: high byte; float: clamped to
/// [0, 1] and scaled, taken as already sRGB-encoded like the 8-bit forms).
fn to_rgba8(pixels: &ImagePixels) -> TextureRgba8 {
    let n = pixels.width as usize * pixels.height as usize;
    let d = &pixels.data;
    let (channels, bytes_per_channel) = match pixels.format {
        PixelFormat::R8 => (1, 1),
        PixelFormat::R8G8 => (2, 1),
        PixelFormat::R8G8B8 => (3, 1),
        PixelFormat::R8G8B8A8 => (4, 1),
        PixelFormat::R16 => (1, 2),
        PixelFormat::R16G16 => (2, 2),
        PixelFormat::R16G16B16 => (3, 2),
        PixelFormat::R16G16B16A16 => (4, 2),
        PixelFormat::R32G32B32Float => (3, 4),
        PixelFormat::R32G32B32A32Float => (4, 4),
    };
    let channel = |i: usize, c: usize| -> u8 {
        let at = (i * channels + c) * bytes_per_channel;
        match bytes_per_channel {
            1 => d.get(at).copied().unwrap_or(255),
            2 => d.get(at + 1).copied().unwrap_or(255),
            _ => d
                .get(at..at + 4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .map_or(255, |v| (v.clamp(0.0, 1.0) * 255.0).round() as u8),
        }
    };
    let mut out = Vec::with_capacity(n * 4);
    for i in 0..n {
        let rgba = match channels {
            1 => {
                let g = channel(i, 0);
                [g, g, g, 255]
            }
            2 => {
                let g = channel(i, 0);
                [g, g, g, channel(i, 1)]
            }
            3 => [channel(i, 0), channel(i, 1), channel(i, 2), 255],
            _ => [channel(i, 0), channel(i, 1), channel(i, 2), channel(i, 3)],
        };
        out.extend_from_slice(&rgba);
    }
    TextureRgba8 {
        width: pixels.width,
        height: pixels.height,
        pixels: out,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use myriad_scene::glam::Mat4;
    use myriad_scene::{
        Aabb, Image, ImageSource, Instance, Mesh, Primitive, TangentSource, TextureRef,
    };

    #[test]
    fn atrium_flattens_with_blended_draws_and_every_triangle() {
        let model = myriad_scene::atrium();
        let geometry = scene_geometry(&model);
        geometry.check().unwrap();
        assert_eq!(geometry.indices.len() / 3, model.triangle_count());
        assert!(geometry.has_blended(), "the atrium has glass and cloth");
        assert_eq!(geometry.materials.len(), model.materials.len() + 1);
        let bounds = model.bounds();
        for v in &geometry.vertices {
            let p = Vec3::from_array(v.position);
            assert!(
                bounds.contains(p) || (p - p.clamp(bounds.min, bounds.max)).length() < 1e-3,
                "{p} outside {bounds:?}"
            );
            let n = Vec3::from_array(v.normal);
            assert!((n.length() - 1.0).abs() < 1e-3);
        }
    }

    #[test]
    fn pixel_formats_convert() {
        let grey16 = ImagePixels {
            width: 1,
            height: 1,
            format: PixelFormat::R16,
            data: vec![0x34, 0x12],
        };
        assert_eq!(to_rgba8(&grey16).pixels, vec![0x12, 0x12, 0x12, 255]);
        let float = ImagePixels {
            width: 1,
            height: 1,
            format: PixelFormat::R32G32B32Float,
            data: [0.5f32, 2.0, -1.0]
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect(),
        };
        assert_eq!(to_rgba8(&float).pixels, vec![128, 255, 0, 255]);
    }

    /// A 2 × 4 quad in the local z = 0 plane (two triangles) drawn with `material`.
    fn quad(material: Option<usize>) -> Primitive {
        let positions = vec![
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(2.0, 4.0, 0.0),
            Vec3::new(0.0, 4.0, 0.0),
        ];
        Primitive {
            bounds: Aabb::from_points(positions.iter().copied()),
            normals: vec![Vec3::Z; positions.len()],
            positions,
            tex_coords: Vec::new(),
            tangents: Vec::new(),
            tangent_source: TangentSource::None,
            indices: vec![0, 1, 2, 0, 2, 3],
            material,
        }
    }

    /// An image named by materials; `pixels` `None` as when loaded as a reference only.
    fn image(pixels: Option<ImagePixels>) -> Image {
        Image {
            name: None,
            source: ImageSource::Uri {
                uri: "texture.png".into(),
                mime_type: None,
            },
            pixels,
        }
    }

    /// Each decoded image becomes one texture, numbered in the order materials first use it: a
    /// material names the texture its image became (shared by every material of that image), and
    /// an image without pixels gives its materials none.
    #[test]
    fn materials_name_the_texture_their_image_became() {
        let pixels = |v: u8| ImagePixels {
            width: 1,
            height: 1,
            format: PixelFormat::R8,
            data: vec![v],
        };
        let mut model = Model::new("textured");
        model.images = vec![
            image(None),
            image(Some(pixels(10))),
            image(Some(pixels(20))),
        ];
        let textured = |index: usize| Material {
            base_color_texture: Some(TextureRef {
                image: index,
                tex_coord: 0,
            }),
            ..Material::default()
        };
        model.materials = vec![textured(0), textured(2), textured(1), textured(2)];
        let geometry = scene_geometry(&model);
        geometry.check().unwrap();
        let named: Vec<_> = geometry
            .materials
            .iter()
            .map(|m| m.base_color_texture)
            .collect();
        // The four materials, then the default one for primitives without a material.
        assert_eq!(named, [None, Some(0), Some(1), Some(0), None]);
        let greys: Vec<u8> = geometry.textures.iter().map(|t| t.pixels[0]).collect();
        assert_eq!(greys, [20, 10], "texture 0 is image 2, texture 1 image 1");
    }

    /// A draw's centre (what blended draws are sorted by) is the middle of its world-space
    /// bounds: the instance's transform applied.
    #[test]
    fn a_draw_is_centred_on_its_world_space_bounds() {
        let mut model = Model::new("quad");
        model.meshes.push(Mesh {
            name: None,
            primitives: vec![quad(None)],
        });
        model.instances.push(Instance {
            mesh: 0,
            world_from_local: Mat4::from_translation(Vec3::new(10.0, 0.0, -6.0)),
            node: 0,
            name: None,
        });
        let geometry = scene_geometry(&model);
        geometry.check().unwrap();
        assert_eq!(geometry.draws.len(), 1);
        // World bounds (10, 0, -6)..(12, 4, -6).
        assert_eq!(geometry.draws[0].center, Vec3::new(11.0, 2.0, -6.0));
    }

    /// Every 8-, 16- and 32-bit layout converts pixel by pixel, not only its first pixel: grey
    /// spreads to RGB, a missing alpha is opaque, 16-bit keeps the high byte, floats are clamped
    /// and scaled. Two pixels in a column, so a pixel count of `width / height` or a stride
    /// error shows.
    #[test]
    fn every_pixel_of_each_layout_converts() {
        let convert = |format, data: Vec<u8>| {
            let pixels = ImagePixels {
                width: 1,
                height: 2,
                format,
                data,
            };
            let texture = to_rgba8(&pixels);
            assert_eq!((texture.width, texture.height), (1, 2), "{format:?}");
            texture.pixels
        };
        assert_eq!(
            convert(PixelFormat::R8, vec![10, 20]),
            [10, 10, 10, 255, 20, 20, 20, 255]
        );
        assert_eq!(
            convert(PixelFormat::R8G8, vec![10, 200, 20, 100]),
            [10, 10, 10, 200, 20, 20, 20, 100]
        );
        assert_eq!(
            convert(PixelFormat::R8G8B8, vec![1, 2, 3, 4, 5, 6]),
            [1, 2, 3, 255, 4, 5, 6, 255]
        );
        assert_eq!(
            convert(PixelFormat::R8G8B8A8, vec![1, 2, 3, 4, 5, 6, 7, 8]),
            [1, 2, 3, 4, 5, 6, 7, 8]
        );
        let wide: Vec<u8> = [0x11u8, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88]
            .iter()
            .flat_map(|&high| [0x0f, high])
            .collect();
        assert_eq!(
            convert(PixelFormat::R16G16B16A16, wide),
            [0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88]
        );
        let floats: Vec<u8> = [0.0f32, 0.25, 1.0, 0.5, 1.5, -0.5, 0.2, 1.0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        assert_eq!(
            convert(PixelFormat::R32G32B32A32Float, floats),
            [0, 64, 255, 128, 255, 0, 51, 255]
        );
    }
}
