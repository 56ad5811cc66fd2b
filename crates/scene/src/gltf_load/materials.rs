//! Step 3's materials and step 4's images: texture references checked against the document,
//! factors clamped to what the spec allows (with warnings), images referenced or decoded.

use super::container::{describe, external_file};
use super::{ImageLoading, Loader, finite_vec3, quoted};
use crate::model::{AlphaMode, Image, ImagePixels, ImageSource, Material, PixelFormat, TextureRef};
use glam::{Vec3, Vec4};
use gltf::json::{self, validation::Checked};
use std::path::Path;

impl Loader<'_> {
    fn texture(&self, index: usize, tex_coord: u32) -> Result<TextureRef, String> {
        let texture = self
            .root
            .textures
            .get(index)
            .ok_or_else(|| format!("texture {index} does not exist"))?;
        let image = texture.source.value();
        if image >= self.root.images.len() {
            return Err(format!("textures[{index}]: image {image} does not exist"));
        }
        // A set other than 0 is kept as written (and warned about by the caller): only
        // TEXCOORD_0 is loaded, and a renderer can tell from `tex_coord`.
        Ok(TextureRef { image, tex_coord })
    }

    pub(super) fn material(&mut self, i: usize, m: &json::Material) -> Result<Material, String> {
        let pbr = &m.pbr_metallic_roughness;
        let tex = |info: &Option<json::texture::Info>| {
            info.as_ref()
                .map(|i| self.texture(i.index.value(), i.tex_coord))
                .transpose()
        };
        let base_color_texture = tex(&pbr.base_color_texture)?;
        let metallic_roughness_texture = tex(&pbr.metallic_roughness_texture)?;
        let emissive_texture = tex(&m.emissive_texture)?;
        let normal_texture = m
            .normal_texture
            .as_ref()
            .map(|n| self.texture(n.index.value(), n.tex_coord))
            .transpose()?;
        let base_color_factor = Vec4::from_array(pbr.base_color_factor.0);
        let factors = [
            pbr.metallic_factor.0,
            pbr.roughness_factor.0,
            m.normal_texture.as_ref().map_or(1.0, |n| n.scale),
        ];
        if !base_color_factor.is_finite() || factors.iter().any(|f| !f.is_finite()) {
            return Err("a factor is not finite".into());
        }
        // The spec bounds these to [0, 1]; a value outside is clamped and reported, like a bad
        // inner cone angle: the material stays usable and the warning says what changed.
        let at = format!("materials[{i}]{}", quoted(&m.name));
        let mut unit = |name: &str, value: f32| {
            let clamped = value.clamp(0.0, 1.0);
            if clamped != value {
                self.model.warnings.push(format!(
                    "{at}: {name} {value} is outside [0, 1]; clamped to {clamped}"
                ));
            }
            clamped
        };
        let base_color_factor = Vec4::from_array(std::array::from_fn(|c| {
            unit(&format!("baseColorFactor[{c}]"), base_color_factor[c])
        }));
        let metallic = unit("metallicFactor", factors[0]);
        let roughness = unit("roughnessFactor", factors[1]);
        let emissive = finite_vec3(m.emissive_factor.0, "emissiveFactor")?;
        let emissive = Vec3::from_array(std::array::from_fn(|c| {
            unit(&format!("emissiveFactor[{c}]"), emissive[c])
        }));
        let alpha_cutoff = m.alpha_cutoff.as_ref().map_or(0.5, |c| c.0);
        let alpha_cutoff = if alpha_cutoff < 0.0 {
            unit("alphaCutoff", alpha_cutoff)
        } else {
            alpha_cutoff
        };
        let strength = m
            .extensions
            .as_ref()
            .and_then(|e| e.emissive_strength.as_ref())
            .map_or(1.0, |s| s.emissive_strength.0);
        let strength = if strength < 0.0 {
            self.model.warnings.push(format!(
                "{at}: emissiveStrength {strength} is negative; clamped to 0"
            ));
            0.0
        } else {
            strength
        };
        let emissive_factor = emissive * strength;
        if !emissive_factor.is_finite() {
            return Err("emissive strength is not finite".into());
        }
        let alpha_mode = match m.alpha_mode {
            Checked::Valid(json::material::AlphaMode::Opaque) => AlphaMode::Opaque,
            Checked::Valid(json::material::AlphaMode::Mask) => AlphaMode::Mask {
                cutoff: alpha_cutoff,
            },
            Checked::Valid(json::material::AlphaMode::Blend) => AlphaMode::Blend,
            Checked::Invalid => return Err("invalid alphaMode".into()),
        };
        let textures = [
            base_color_texture,
            metallic_roughness_texture,
            normal_texture,
            emissive_texture,
        ];
        if textures.iter().flatten().any(|t| t.tex_coord != 0) {
            self.model.warnings.push(format!(
                "materials[{i}]{}: samples a UV set other than TEXCOORD_0, which is not loaded",
                quoted(&m.name)
            ));
        }
        Ok(Material {
            name: m.name.clone(),
            base_color_factor,
            base_color_texture,
            metallic_factor: metallic,
            roughness_factor: roughness,
            metallic_roughness_texture,
            normal_texture,
            normal_scale: factors[2],
            emissive_factor,
            emissive_texture,
            alpha_mode,
            double_sided: m.double_sided,
        })
    }

    pub(super) fn image(
        &self,
        image: &json::Image,
        document: &gltf::Document,
        base: Option<&Path>,
    ) -> Result<Image, String> {
        let mime = image.mime_type.as_ref().map(|m| m.0.clone());
        let source = match (&image.buffer_view, &image.uri) {
            (Some(view), _) => ImageSource::BufferView {
                view: view.value(),
                mime_type: mime.ok_or("a bufferView image needs a mimeType")?,
            },
            (None, Some(uri)) if uri.starts_with("data:") => ImageSource::DataUri {
                mime_type: uri["data:".len()..]
                    .split([';', ','])
                    .next()
                    .filter(|m| !m.is_empty())
                    .map(str::to_string),
                len: uri.len(),
            },
            (None, Some(uri)) => ImageSource::Uri {
                uri: uri.clone(),
                mime_type: mime,
            },
            (None, None) => return Err("has neither uri nor bufferView".into()),
        };
        let pixels = match self.options.images {
            ImageLoading::ReferencesOnly => None,
            ImageLoading::Decode => Some(self.decode(&source, image, document, base)?),
        };
        Ok(Image {
            name: image.name.clone(),
            source,
            pixels,
        })
    }

    fn decode(
        &self,
        source: &ImageSource,
        image: &json::Image,
        document: &gltf::Document,
        base: Option<&Path>,
    ) -> Result<ImagePixels, String> {
        let gltf_source = match source {
            ImageSource::BufferView { view, mime_type } => {
                // The crate's decoder slices the buffer with the view's range unchecked: the
                // view must lie inside its buffer (step 2 checked every view; this keeps the
                // guarantee next to the code that needs it).
                self.data.view_bytes(*view)?;
                let view = document
                    .views()
                    .nth(*view)
                    .ok_or_else(|| format!("bufferViews[{view}] does not exist"))?;
                gltf::image::Source::View { view, mime_type }
            }
            ImageSource::Uri { .. } | ImageSource::DataUri { .. } => {
                let uri = image.uri.as_deref().unwrap_or_default();
                if matches!(source, ImageSource::Uri { .. }) {
                    let Some(base) = base else {
                        return Err(format!(
                            "external file \"{uri}\" cannot be read without a base folder"
                        ));
                    };
                    // The crate reads the file to its end: a regular file only.
                    if let Some(path) = external_file(base, uri)?
                        && !std::fs::metadata(&path).is_ok_and(|m| m.is_file())
                    {
                        return Err(format!(
                            "external file \"{uri}\" ({}) is missing or not a regular file",
                            path.display()
                        ));
                    }
                }
                gltf::image::Source::Uri {
                    uri,
                    mime_type: image.mime_type.as_ref().map(|m| m.0.as_str()),
                }
            }
        };
        // Data URIs need no folder, but the crate wants one to accept a URI at all.
        let base = base.unwrap_or(Path::new("."));
        let data = gltf::image::Data::from_source(gltf_source, Some(base), self.data.buffers)
            .map_err(|e| format!("cannot decode: {}", describe(e)))?;
        use gltf::image::Format as F;
        let format = match data.format {
            F::R8 => PixelFormat::R8,
            F::R8G8 => PixelFormat::R8G8,
            F::R8G8B8 => PixelFormat::R8G8B8,
            F::R8G8B8A8 => PixelFormat::R8G8B8A8,
            F::R16 => PixelFormat::R16,
            F::R16G16 => PixelFormat::R16G16,
            F::R16G16B16 => PixelFormat::R16G16B16,
            F::R16G16B16A16 => PixelFormat::R16G16B16A16,
            F::R32G32B32FLOAT => PixelFormat::R32G32B32Float,
            F::R32G32B32A32FLOAT => PixelFormat::R32G32B32A32Float,
        };
        Ok(ImagePixels {
            width: data.width,
            height: data.height,
            format,
            data: data.pixels,
        })
    }
}
