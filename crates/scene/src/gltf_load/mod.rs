//! Loading glTF 2.0 files (`.gltf` with its buffers and images, or `.glb`) into a [`Model`].
//!
//! Why this module exists: the `gltf` crate parses and schema-validates the JSON (and splits
//! GLB chunks), but its convenience layer trusts the data after that — accessor reads, image
//! sources, cameras without a projection object and node hierarchies with cycles can all panic
//! or recurse forever. Files are untrusted input, so this loader uses the crate only for parsing,
//! validation and resource fetching (buffers, image decoding) and reads everything else from the
//! validated JSON itself, checking each index, byte range and float. **No input makes it panic**;
//! every failure is an [`Error::Gltf`] naming the file, where in the document and what is wrong
//! (`Sponza.gltf: meshes[3] "Roof" primitives[0]: index 912 (element 40 of the indices) is out of
//! range (POSITION has 900 vertices)`). The test `tests/gltf_robustness.rs` runs it over every glTF 2.0 file of
//! Debian's `assimp-testmodels` (46, in `models/glTF2`; the glTF 1.0 ones are not glTF 2.0).
//!
//! ## Loading, step by step
//! 1. **Container.** A file starting with `glTF` is GLB: its header is checked (version 2, a
//!    declared length equal to the file's), and its first two chunks (a JSON chunk, then an
//!    optional BIN chunk, each inside the file; the JSON's length a multiple of 4 when a chunk
//!    follows; later chunks are ignored, as the spec says), before the `gltf` crate splits them.
//!    A `KHR_lights_punctual` light without a type the extension defines is named here (the
//!    crate fails the whole file on it, under an internal path). Then
//!    `gltf::Gltf::from_slice` parses and validates the JSON (unknown required extensions,
//!    bad enum values and out-of-range indices are errors there), and `asset.version` and
//!    `asset.minVersion` are checked (the crate does not).
//! 2. **Buffers.** Each buffer is fetched (GLB chunk, `data:` URI, or a file in the glTF file's
//!    folder or below; absolute paths, `file:` URIs and `../` above it are refused) and must hold
//!    its declared `byteLength`, of which only that much is read or kept; every buffer view must
//!    lie inside that length.
//! 3. **Materials**, then **meshes**: each triangle primitive's accessors are read with bounds
//!    checks (`gltf_accessors.rs`); strips and fans become lists; indices are checked against the
//!    vertex count; missing normals become flat normals; tangents are generated when the
//!    material has a normal map and the file has none (`tangents.rs`). Points and lines, and
//!    primitives without positions, are left out with a warning.
//! 4. **Images**: always recorded as references; decoded to pixels only with
//!    [`ImageLoading::Decode`] (decoding Sponza's 46 textures takes seconds in a debug build).
//! 5. **Nodes**: the default scene (or scene 0; with no scenes, every node without a parent)
//!    is walked iteratively, composing world transforms (`matrix`, or translation · rotation ·
//!    scale). A node that is its own ancestor is an error; a node reached along several paths (two
//!    parents, or a scene's root that is also a child or is listed twice, all of which the spec
//!    forbids) is drawn once per path, with a warning. Nodes with meshes become [`Instance`](crate::Instance)s,
//!    with cameras [`ModelCamera`](crate::ModelCamera)s, with `KHR_lights_punctual` lights rows of
//!    [`Model::lights`].
//!
//! [`load`] drives the steps; each has a file: `container.rs` (the checks of steps 1 and 2),
//! `materials.rs` (materials, step 4's images), `meshes.rs` (primitives), `nodes.rs` (step 5 and
//! what makes a light usable); `tests.rs` holds the unit tests, one decision each.
//!
//! ## Decisions
//! * **Light radius.** glTF lights may have no `range` (inverse-square falloff forever), but a
//!   clustered light needs a finite one. Without `range`, the radius is where the illuminance of
//!   the brightest channel, `intensity · max(color) / d²`, falls to [`LoadOptions::light_cutoff`]
//!   (see [`radius_from_intensity`](crate::light_fields::radius_from_intensity)).
//! * **Invalid lights are left out, counted and reported, never fatal** — the scene file's
//!   [`LightPolicy::SkipInvalid`](crate::LightPolicy::SkipInvalid), which every command uses.
//!   A light whose values cannot make a light (`range` not finite and > 0, a colour or
//!   intensity that is negative or not finite in f32, or whose product is not, an
//!   `outerConeAngle` outside (0, π], zero
//!   intensity without a `range`) or whose node gives it no direction (a spot or directional
//!   light under a zero scale) is left out of [`Model::lights`] /
//!   [`Model::directional_lights`], listed in
//!   [`Model::skipped_lights`] (one row per node that places it, with
//!   the light's index, name and reason; `myriad info` counts them) and warned about as `nodes[N]
//!   "node": KHR_lights_punctual lights[I] "name": <what is wrong>; left out`. The geometry, the
//!   cameras and the other lights stay usable. Only a node naming a light that does not exist is an
//!   error: then the document itself is broken.
//! * **A spot's inner cone is kept and drawn with.** The outer cone bounds the light for the
//!   assignment ([`Lights::spot_angle`](crate::Lights::spot_angle)); the inner one
//!   ([`Lights::spot_inner_angle`](crate::Lights::spot_inner_angle)) only shades: full strength
//!   inside it, the spec's falloff (in the cosine) to 0 at the outer angle, squared.
//! * **Directions ignore scale.** A spot's or sun's direction and a camera's view and up are the
//!   node's −Z and +Y axes at unit length, however the node scales them (1e-30, 1e20, or
//!   non-uniformly): normalised in f64 where f32 would square the length to 0 or ∞. Only a
//!   transform that maps the axis to zero (a zero scale, a singular matrix) leaves no direction,
//!   and the warning says that.
//! * **Left out, with a warning:** skins (meshes are drawn at their node's transform),
//!   morph targets, animations, UV sets other than `TEXCOORD_0`, vertex colours, and any
//!   extension in `extensionsUsed` but `KHR_lights_punctual` and
//!   `KHR_materials_emissive_strength` (one warning names them all).
//! * **Out-of-range values the spec forbids are clamped and reported**, not fatal, since the
//!   model stays usable: material factors outside [0, 1] (base colour, metallic, roughness,
//!   emissive; a negative `alphaCutoff` or `emissiveStrength` becomes 0), a spot's inner cone
//!   outside [0, outer). A spot's outer cone above the spec's π/2 is kept as it is (the
//!   assignment and the shaders handle cones up to π) and reported. Commands that load a model
//!   print these warnings on stderr; `myriad info` lists them.
//! * **Where the file breaks the glTF 2.0 spec**, the `gltf` crate parses it without a word
//!   (its validation covers the schema's types, enums and indices, not these), so the loader
//!   decides. It **refuses** (an error naming the file and the place) what the spec tells a
//!   loader not to load, and files whose declared lengths contradict their bytes, since then
//!   which bytes are meant is unknown:
//!   - `asset.version` whose major version is not 2, or `asset.minVersion` above 2.0 (the spec:
//!     a loader must not load an asset of a major version, or a minVersion, it does not
//!     support; a later 2.x loads);
//!   - a GLB header `length` other than the file's size (longer: truncated; shorter: bytes that
//!     are not part of the GLB), or a first chunk that is not JSON, a second that is not BIN, a
//!     chunk longer than the bytes after it, a JSON chunk of a length not a multiple of 4 with
//!     a chunk after it (misaligned);
//!   - a buffer view reaching past its buffer's `byteLength`, even where the data behind it
//!     holds more bytes;
//!   - a node `matrix` whose last row is not exactly (0, 0, 0, 1): the spec requires a matrix
//!     decomposable into translation, rotation and scale, and a projective one has no reading
//!     that other loaders share (the mesh's points would be divided by a `w` of their own, or
//!     the row silently dropped, as this loader did before). Exporters write the row exactly.
//!
//!   It **loads and reports** (a warning) what breaks a rule of the spec but has one clear
//!   reading that keeps the model usable, as it clamps material factors:
//!   - a node with both `matrix` and translation/rotation/scale: the matrix is used (as the
//!     `gltf` crate's own `Node::transform` and common loaders do);
//!   - a camera `aspectRatio` that is not > 0: ignored (the aspect always follows the output
//!     size here, see [`ModelCamera::to_camera`](crate::ModelCamera::to_camera));
//!   - sparse indices that do not strictly increase: applied in file order, so a repeated
//!     index takes its last value;
//!   - a buffer holding more than its `byteLength` (beyond the padding to 4 bytes): the rest
//!     is ignored;
//!   - a node `rotation` whose length is not 1 (beyond 1e-5): normalised;
//!   - a mesh with no primitives: it draws nothing.
//! * **Normals** that are not unit length are normalised (with a warning naming the primitive);
//!   a trailing incomplete triangle of a list is dropped (with a warning).

use crate::error::{Error, Result};
use crate::gltf_accessors::BufferData;
use crate::model::{Mesh, Model};
use glam::Vec3;
use gltf::json;
use std::path::Path;

mod container;
mod materials;
mod meshes;
mod nodes;
#[cfg(test)]
mod tests;

use container::{
    check_glb_header, check_json_start, check_version, describe, external_file, prevalidate_json,
};

/// Whether images are decoded when a model is loaded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ImageLoading {
    /// Decode every image to pixels ([`Image::pixels`](crate::Image::pixels) is `Some`).
    #[default]
    Decode,
    /// Record where each image is, decode nothing ([`Image::pixels`](crate::Image::pixels) is
    /// `None`). Much faster; what tools that only need geometry and lights use.
    ReferencesOnly,
}

/// Illuminance (lux) at which a light without a `range` is cut off by default: 0.1 lux, so a
/// 1 cd white light reaches about 3.2 m and a 100 cd one about 32 m.
pub const DEFAULT_LIGHT_CUTOFF: f32 = 0.1;

/// Options for [`Model::load`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadOptions {
    /// Whether to decode images.
    pub images: ImageLoading,
    /// Illuminance below which a light without `range` is cut off (> 0); see the module docs.
    pub light_cutoff: f32,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            images: ImageLoading::Decode,
            light_cutoff: DEFAULT_LIGHT_CUTOFF,
        }
    }
}

impl LoadOptions {
    /// The defaults, but with images only referenced, not decoded.
    pub fn without_images() -> Self {
        Self {
            images: ImageLoading::ReferencesOnly,
            ..Self::default()
        }
    }
}

impl Model {
    /// Loads a `.gltf` or `.glb` file; buffers and images it references are read relative to
    /// the file's folder. Every problem is an [`Error`] naming the file.
    pub fn load(path: impl AsRef<Path>, options: &LoadOptions) -> Result<Model> {
        let path = path.as_ref();
        let bytes = crate::read_regular_file(path).map_err(|source| Error::GltfRead {
            path: path.to_path_buf(),
            source,
        })?;
        let base = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let mut model =
            Self::from_gltf_slice(&bytes, &path.display().to_string(), Some(base), options)?;
        model.files.insert(0, path.to_path_buf());
        Ok(model)
    }

    /// Loads glTF or GLB bytes. `origin` names the data in errors and becomes
    /// [`Model::origin`]; external files (buffers, images) are resolved against `base_dir`, and
    /// are an error when it is `None` (`data:` URIs and GLB chunks always work).
    pub fn from_gltf_slice(
        bytes: &[u8],
        origin: &str,
        base_dir: Option<&Path>,
        options: &LoadOptions,
    ) -> Result<Model> {
        // Messages quote the file's own text (URIs, names, extension names, the gltf crate's
        // paths with their values): escaped once here, where they leave the loader.
        let escaped = |text: String| crate::printable(&text).into_owned();
        match load(bytes, origin, base_dir, options) {
            Ok(mut model) => {
                model.warnings = model.warnings.into_iter().map(escaped).collect();
                Ok(model)
            }
            Err(message) => Err(Error::Gltf {
                origin: origin.to_string(),
                message: escaped(message),
            }),
        }
    }
}

/// The glTF extensions the loader reads; any other in `extensionsUsed` is warned about.
const READ_EXTENSIONS: [&str; 2] = ["KHR_lights_punctual", "KHR_materials_emissive_strength"];

fn load(
    bytes: &[u8],
    origin: &str,
    base: Option<&Path>,
    options: &LoadOptions,
) -> Result<Model, String> {
    if !(options.light_cutoff > 0.0 && options.light_cutoff.is_finite()) {
        return Err(format!(
            "light cut-off must be finite and > 0, got {}",
            options.light_cutoff
        ));
    }
    let json: std::borrow::Cow<'_, [u8]> = if bytes.starts_with(b"glTF") {
        check_glb_header(bytes)?;
        gltf::Glb::from_slice(bytes).map_err(describe)?.json
    } else {
        check_json_start(bytes)?;
        std::borrow::Cow::Borrowed(bytes)
    };
    prevalidate_json(&json)?;
    let gltf::Gltf { document, mut blob } = gltf::Gltf::from_slice(bytes).map_err(describe)?;
    let root = document.as_json();
    check_version(&root.asset)?;
    let mut warnings = Vec::new();

    // 2. Buffers.
    let mut buffers = Vec::with_capacity(root.buffers.len());
    // The external files, for `Model::files`.
    let mut files = Vec::new();
    for (i, buffer) in document.buffers().enumerate() {
        let declared = &root.buffers[i];
        let name = match &declared.uri {
            Some(uri) if uri.starts_with("data:") => " (data URI)".to_string(),
            Some(uri) => format!(" \"{uri}\""),
            None => " (GLB binary chunk)".to_string(),
        };
        if base.is_none()
            && declared
                .uri
                .as_ref()
                .is_some_and(|u| !u.starts_with("data:"))
        {
            return Err(format!(
                "buffers[{i}]{name}: an external file cannot be read without a base folder"
            ));
        }
        // External files are read here, as regular files only: a URI naming a device or a pipe
        // (`/dev/zero`, a FIFO; also percent-encoded) would make the read never end.
        let external = match (base, declared.uri.as_deref()) {
            (Some(base), Some(uri)) => {
                external_file(base, uri).map_err(|e| format!("buffers[{i}]{name}: {e}"))?
            }
            _ => None,
        };
        let data = match external {
            Some(path) => {
                files.push(path.clone());
                // Only the declared length is needed (a shorter file is reported below).
                let mut bytes =
                    crate::read_file::read_regular_file_up_to(&path, declared.byte_length.0)
                        .map_err(|e| {
                            format!("buffers[{i}]{name}: cannot read {}: {e}", path.display())
                        })?;
                // As the gltf crate does: buffers are padded to a multiple of 4 bytes.
                bytes.resize(bytes.len().next_multiple_of(4), 0);
                gltf::buffer::Data(bytes)
            }
            None => gltf::buffer::Data::from_source_and_blob(buffer.source(), base, &mut blob)
                .map_err(|e| format!("buffers[{i}]{name}: {}", describe(e)))?,
        };
        let (held, declared_len) = (data.0.len() as u64, declared.byte_length.0);
        if held < declared_len {
            return Err(format!(
                "buffers[{i}]{name}: declares {declared_len} bytes but holds {held}"
            ));
        }
        // The buffer is its declared `byteLength`: views must lie inside it (checked below), and
        // bytes beyond it are not part of it. Up to 3 more are padding (GLB chunks and the
        // crate's reads are padded to 4 bytes); more than that is reported.
        if held > declared_len.next_multiple_of(4) {
            warnings.push(format!(
                "buffers[{i}]{name}: holds {held} bytes but declares byteLength {declared_len}; \
                 the rest is ignored"
            ));
        }
        let mut data = data;
        data.0.truncate(declared_len as usize); // fits: at most `held`, a usize
        buffers.push(data);
    }
    let data = BufferData {
        root,
        buffers: &buffers,
    };
    data.check_views()?;
    warnings.extend(data.sparse_order_warnings());

    let mut loader = Loader {
        root,
        data,
        model: Model::new(origin),
        options,
    };
    loader.model.warnings = warnings;
    // Image files are the model's too, decoded or not: resolved as the decoder would.
    files.extend(root.images.iter().filter_map(|image| {
        let uri = image.uri.as_deref()?;
        external_file(base?, uri).ok().flatten()
    }));
    loader.model.files = files;
    // 3. Materials and meshes.
    for (i, m) in root.materials.iter().enumerate() {
        let material = loader
            .material(i, m)
            .map_err(|e| format!("materials[{i}]{}: {e}", quoted(&m.name)))?;
        loader.model.materials.push(material);
    }
    for (i, mesh) in root.meshes.iter().enumerate() {
        if mesh.primitives.is_empty() {
            loader.model.warnings.push(format!(
                "meshes[{i}]{}: has no primitives (the spec requires at least one); it draws \
                 nothing",
                quoted(&mesh.name)
            ));
        }
        let mut primitives = Vec::with_capacity(mesh.primitives.len());
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let at = format!("meshes[{i}]{} primitives[{p}]", quoted(&mesh.name));
            if let Some(primitive) = loader.primitive(primitive, &at)? {
                primitives.push(primitive);
            }
        }
        loader.model.meshes.push(Mesh {
            name: mesh.name.clone(),
            primitives,
        });
    }
    // 4. Images.
    for (i, image) in root.images.iter().enumerate() {
        let image = loader
            .image(image, &document, base)
            .map_err(|e| format!("images[{i}]{}: {e}", quoted(&image.name)))?;
        loader.model.images.push(image);
    }
    // 5. Nodes.
    loader.walk_nodes()?;
    // A name shared by cameras picks the first of them (`Model::camera_index`): said, or
    // `--camera Main` in a model of four cameras named Main shows one without a word.
    // One pass with a map, in first-appearance order (a scan per camera took 31 s on 80 000
    // camera nodes, review).
    let mut shared: std::collections::HashMap<&str, (usize, usize)> = Default::default();
    for (i, camera) in loader.model.cameras.iter().enumerate() {
        shared.entry(camera.name.as_str()).or_insert((i, 0)).1 += 1;
    }
    let mut repeated: Vec<(usize, &str, usize)> = shared
        .into_iter()
        .filter(|&(_, (_, count))| count > 1)
        .map(|(name, (first, count))| (first, name, count))
        .collect();
    repeated.sort_unstable();
    let said: Vec<String> = repeated
        .into_iter()
        .map(|(_, name, count)| {
            format!(
                "{count} cameras are named \"{}\"; looked up by that name, the first is used",
                crate::printable(name)
            )
        })
        .collect();
    loader.model.warnings.extend(said);
    let ignored = [
        (
            root.skins.len(),
            "skin(s): skinned meshes are drawn at their node's transform",
        ),
        (
            root.animations.len(),
            "animation(s): the static pose is loaded",
        ),
    ];
    for (n, what) in ignored {
        if n > 0 {
            loader.model.warnings.push(format!("ignored {n} {what}"));
        }
    }
    // Extensions the file uses that the loader does not read: what they change is not drawn
    // (Sponza's breakfast room uses KHR_materials_specular, review). Required ones the `gltf`
    // crate already refused above, unless it reads them itself.
    let unread: Vec<&str> = root
        .extensions_used
        .iter()
        .map(String::as_str)
        .filter(|e| !READ_EXTENSIONS.contains(e))
        .collect();
    if !unread.is_empty() {
        loader.model.warnings.push(format!(
            "extensionsUsed: ignored {} (not read; what they change is not drawn)",
            unread.join(", ")
        ));
    }
    // Finite positions under finite transforms can still overflow f32 in world space (3e38
    // scaled by 10): the bounds, the camera and the light fields would all be infinite.
    let bounds = loader.model.bounds();
    if !bounds.is_empty() && (!bounds.min.is_finite() || !bounds.max.is_finite()) {
        let instance = loader.model.instances.iter().find(|instance| {
            let m = instance.world_from_local;
            loader.model.meshes[instance.mesh]
                .primitives
                .iter()
                .any(|p| {
                    p.indices
                        .iter()
                        .any(|&i| !m.transform_point3(p.positions[i as usize]).is_finite())
                })
        });
        let place = instance.map_or(String::new(), |i| {
            format!("nodes[{}] (meshes[{}]): ", i.node, i.mesh)
        });
        return Err(format!(
            "{place}world-space positions overflow f32 (bounds {:?} .. {:?})",
            bounds.min, bounds.max
        ));
    }
    Ok(loader.model)
}

/// ` "name"` for messages, or nothing.
fn quoted(name: &Option<String>) -> String {
    name.as_ref()
        .map_or(String::new(), |n| format!(" \"{}\"", crate::printable(n)))
}

fn finite_vec3(v: [f32; 3], what: &str) -> Result<Vec3, String> {
    let v = Vec3::from_array(v);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{what} is not finite: {v}"))
    }
}

struct Loader<'a> {
    root: &'a json::Root,
    data: BufferData<'a>,
    model: Model,
    options: &'a LoadOptions,
}
