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
//! range (POSITION has 900 vertices)`). The test `tests/gltf_robustness.rs` runs it over every file of Debian's
//! `assimp-testmodels`.
//!
//! ## Loading, step by step
//! 1. **Container.** A file starting with `glTF` is GLB: its header is checked (version 2, a
//!    declared length equal to the file's) before the `gltf` crate splits the chunks. Then
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
//!    scale). A node that is its own ancestor is an error; a node reached along several paths is
//!    drawn once per path (instancing). Nodes with meshes become [`Instance`]s, with cameras
//!    [`ModelCamera`]s, with `KHR_lights_punctual` lights rows of [`Model::lights`].
//!
//! ## Decisions
//! * **Light radius.** glTF lights may have no `range` (inverse-square falloff forever), but a
//!   clustered light needs a finite one. Without `range`, the radius is where the illuminance of
//!   the brightest channel, `intensity · max(color) / d²`, falls to [`LoadOptions::light_cutoff`]
//!   (see [`radius_from_intensity`]).
//! * **Invalid lights are left out, counted and reported, never fatal** — the scene file's
//!   [`LightPolicy::SkipInvalid`](crate::LightPolicy::SkipInvalid), which every command uses.
//!   A light whose values cannot make a light (`range` not finite and > 0, a colour or
//!   intensity that is negative or not finite in f32, an `outerConeAngle` outside (0, π], zero
//!   intensity without a `range`) or whose node gives it no direction (a spot or directional
//!   light under a zero scale) is left out of [`Model::lights`] / [`Model::directional_lights`],
//!   listed in [`Model::skipped_lights`] (one row per node that places it, with the light's
//!   index, name and reason; `myriad info` counts them) and warned about as
//!   `nodes[N] "node": KHR_lights_punctual lights[I] "name": <what is wrong>; left out`. The
//!   geometry, the cameras and the other lights stay usable. Only a node naming a light that
//!   does not exist is an error: then the document itself is broken.
//! * **Directions ignore scale.** A spot's or sun's direction and a camera's view and up are the
//!   node's −Z and +Y axes at unit length, however the node scales them (1e-30, 1e20, or
//!   non-uniformly): normalised in f64 where f32 would square the length to 0 or ∞. Only a
//!   transform that maps the axis to zero (a zero scale, a singular matrix) leaves no direction,
//!   and the warning says that.
//! * **Left out, with a warning:** skins (meshes are drawn at their node's transform),
//!   morph targets, animations, UV sets other than `TEXCOORD_0`, vertex colours.
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
//!     are not part of the GLB);
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
//!     size here, see [`ModelCamera::to_camera`]);
//!   - sparse indices that do not strictly increase: applied in file order, so a repeated
//!     index takes its last value;
//!   - a buffer holding more than its `byteLength` (beyond the padding to 4 bytes): the rest
//!     is ignored.
//! * **Normals** that are not unit length are normalised (with a warning naming the primitive);
//!   a trailing incomplete triangle of a list is dropped (with a warning).

use crate::error::{Error, Result};
use crate::gltf_accessors::BufferData;
use crate::light_fields::radius_from_intensity;
use crate::lights::LightRecord;
use crate::model::{
    Aabb, AlphaMode, DirectionalLight, Image, ImagePixels, ImageSource, Instance, Material, Mesh,
    Model, ModelCamera, PixelFormat, PlacedLight, Primitive, Projection, PunctualKind,
    SkippedPunctualLight, TangentSource, TextureRef,
};
use crate::tangents::{flat_normals, generate_tangents};
use glam::{Mat4, Quat, Vec3, Vec4};
use gltf::json::{self, validation::Checked};
use std::path::Path;

/// How many node visits a hierarchy may expand to (a node reached along several paths counts
/// once per path): a guard against files whose shared children multiply exponentially.
const MAX_NODE_VISITS: usize = 1 << 22;

/// Whether images are decoded when a model is loaded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ImageLoading {
    /// Decode every image to pixels ([`Image::pixels`] is `Some`).
    #[default]
    Decode,
    /// Record where each image is, decode nothing ([`Image::pixels`] is `None`). Much faster;
    /// what tools that only need geometry and lights use.
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
        Self::from_gltf_slice(&bytes, &path.display().to_string(), Some(base), options)
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
        load(bytes, origin, base_dir, options).map_err(|message| Error::Gltf {
            origin: origin.to_string(),
            message,
        })
    }
}

/// Step 1's GLB header check: what the `gltf` crate's own parsing assumes.
fn check_glb_header(bytes: &[u8]) -> Result<(), String> {
    if bytes.len() < 20 {
        return Err(format!(
            "truncated GLB: {} bytes, a header and a chunk header need 20",
            bytes.len()
        ));
    }
    let word =
        |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let version = word(4);
    if version != 2 {
        return Err(format!(
            "GLB version {version}; only version 2 is supported"
        ));
    }
    // The header's length is the whole file's: shorter (bytes after the GLB) is as malformed as
    // longer (a truncated file), and the Khronos validator rejects both.
    let length = word(8) as usize;
    if length != bytes.len() {
        return Err(format!(
            "GLB header declares {length} bytes, but the file has {}",
            bytes.len()
        ));
    }
    Ok(())
}

/// The spec's rule for loaders: an asset whose major `version` is not 2, or whose `minVersion` is
/// above the 2.0 this loader implements, must not be loaded (a later minor version of 2 may be:
/// it only adds what a 2.0 reader can ignore). The `gltf` crate does not check either.
fn check_version(asset: &json::Asset) -> Result<(), String> {
    let parse = |v: &str| {
        let (major, minor) = v.split_once('.')?;
        let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
        (digits(major) && digits(minor)).then(|| (major.parse::<u64>(), minor.parse::<u64>()))
    };
    match parse(&asset.version) {
        Some((Ok(2), _)) => {}
        Some(_) => {
            return Err(format!(
                "asset.version \"{}\": only glTF 2.x is supported",
                asset.version
            ));
        }
        None => {
            return Err(format!(
                "asset.version \"{}\" is not MAJOR.MINOR",
                asset.version
            ));
        }
    }
    if let Some(min) = &asset.min_version {
        match parse(min) {
            Some((Ok(2), Ok(0))) => {}
            Some(_) => {
                return Err(format!(
                    "asset.minVersion \"{min}\": this loader implements glTF 2.0 only"
                ));
            }
            None => return Err(format!("asset.minVersion \"{min}\" is not MAJOR.MINOR")),
        }
    }
    Ok(())
}

/// The `gltf` crate's error, made readable (validation errors listed, at most 5).
/// Checks the gltf crate cannot be trusted with (found by `myriad-fuzz gltf`), made on the raw
/// JSON before it parses it:
/// * an integer of 2³² or more anywhere: gltf-json reads indices as u32 and would silently wrap
///   `4294967296` to index 0 (no file this loader can handle needs such a number);
/// * a primitive whose `POSITION` names an accessor that does not exist: gltf-json 1.4.1's
///   validation indexes `accessors` with it unchecked and panics.
fn prevalidate_json(json: &[u8]) -> Result<(), String> {
    let value: serde_json::Value =
        serde_json::from_slice(json).map_err(|e| format!("not valid glTF JSON: {e}"))?;
    fn find_huge(v: &serde_json::Value, path: &mut Vec<String>) -> Option<String> {
        match v {
            serde_json::Value::Number(n) if n.as_u64().is_some_and(|u| u > u32::MAX as u64) => {
                Some(format!(
                    "{}: {n} is out of range (at most {})",
                    path.join(""),
                    u32::MAX
                ))
            }
            serde_json::Value::Array(items) => items.iter().enumerate().find_map(|(i, item)| {
                path.push(format!("[{i}]"));
                let found = find_huge(item, path);
                path.pop();
                found
            }),
            serde_json::Value::Object(fields) => fields.iter().find_map(|(key, item)| {
                path.push(format!(".{key}"));
                let found = find_huge(item, path);
                path.pop();
                found
            }),
            _ => None,
        }
    }
    if let Some(problem) = find_huge(&value, &mut Vec::new()) {
        return Err(problem);
    }
    let accessors = value["accessors"].as_array().map_or(0, Vec::len) as u64;
    let meshes = value["meshes"]
        .as_array()
        .map(Vec::as_slice)
        .unwrap_or_default();
    for (m, mesh) in meshes.iter().enumerate() {
        let primitives = mesh["primitives"]
            .as_array()
            .map(Vec::as_slice)
            .unwrap_or_default();
        for (p, primitive) in primitives.iter().enumerate() {
            if let Some(index) = primitive["attributes"]["POSITION"].as_u64()
                && index >= accessors
            {
                return Err(format!(
                    "meshes[{m}].primitives[{p}].attributes.POSITION: accessor {index} does not exist ({accessors} accessors)"
                ));
            }
        }
    }
    Ok(())
}

fn describe(e: gltf::Error) -> String {
    match e {
        gltf::Error::Validation(errors) => {
            let mut shown: Vec<String> = errors
                .iter()
                .map(|(path, error)| format!("{path}: {error}"))
                .collect();
            // An unsupported required extension (Draco, say) explains the errors it causes
            // elsewhere (accessors without buffer views): list it first.
            shown.sort_by_key(|s| !s.starts_with("extensionsRequired"));
            shown.truncate(5);
            let more = match errors.len().saturating_sub(5) {
                0 => String::new(),
                n => format!(" (and {n} more)"),
            };
            format!("invalid glTF: {}{more}", shown.join("; "))
        }
        gltf::Error::Deserialize(e) => format!("not valid glTF JSON: {e}"),
        other => other.to_string(),
    }
}

/// Rejects a file that is neither GLB nor JSON by how it starts, so a GLB with a damaged magic
/// (or an image renamed `.glb`) is not reported as a JSON syntax error.
fn check_json_start(bytes: &[u8]) -> Result<(), String> {
    let text = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match text.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => Ok(()),
        None => Err("empty: neither GLB nor glTF JSON".to_string()),
        Some(_) => Err(format!(
            "neither GLB (which starts with the magic \"glTF\") nor glTF JSON (an object, \
             starting with '{{'): it starts with {}",
            bytes[..bytes.len().min(4)].escape_ascii()
        )),
    }
}

/// The file an external (non-data) URI names: percent-decoded and relative to `base`. `None` for
/// data URIs and schemes other than `file:` (the crate reports those). An escape that does not
/// decode to UTF-8 is an error here (the crate would panic on it).
///
/// A model reads files only from its own folder and the folders below it: absolute paths,
/// `file:` URIs and paths that climb above the folder (`../`) are refused. The gltf crate would
/// follow them anywhere, so an untrusted model could read `/etc/passwd` as vertices; a portable
/// asset keeps its files beside it, as the glTF specification's examples do. (The check is on the
/// path's text; links inside the model's folder are followed as the file system resolves them.)
fn external_file(base: &Path, uri: &str) -> Result<Option<std::path::PathBuf>, String> {
    if uri.contains(':') {
        let file = uri
            .get(..5)
            .is_some_and(|s| s.eq_ignore_ascii_case("file:"));
        return if file {
            Err(format!(
                "URI \"{uri}\": file: URIs are not read; name the file by a path relative to the \
                 glTF file"
            ))
        } else {
            Ok(None)
        };
    }
    let decoded = urlencoding::decode(uri)
        .map_err(|_| format!("URI \"{uri}\" does not percent-decode to UTF-8"))?;
    let path = Path::new(&*decoded);
    let outside = || {
        format!(
            "URI \"{uri}\" names a file outside the glTF file's folder; only files in that folder \
             and below are read"
        )
    };
    if path.has_root() {
        return Err(outside());
    }
    let mut depth = 0usize;
    for part in path.components() {
        match part {
            std::path::Component::ParentDir => {
                depth = depth.checked_sub(1).ok_or_else(outside)?;
            }
            std::path::Component::Normal(_) => depth += 1,
            _ => {}
        }
    }
    Ok(Some(base.join(path)))
}

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
    // 3. Materials and meshes.
    for (i, m) in root.materials.iter().enumerate() {
        let material = loader
            .material(i, m)
            .map_err(|e| format!("materials[{i}]{}: {e}", quoted(&m.name)))?;
        loader.model.materials.push(material);
    }
    for (i, mesh) in root.meshes.iter().enumerate() {
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

/// A triangle strip as a list. glTF: triangle `i` is `(i, i + 1 + i % 2, i + 2 − i % 2)`, so every
/// triangle keeps the first one's winding.
fn strip_to_list(stream: &[u32]) -> Vec<u32> {
    (0..stream.len().saturating_sub(2))
        .flat_map(|i| {
            let odd = i % 2;
            [stream[i], stream[i + 1 + odd], stream[i + 2 - odd]]
        })
        .collect()
}

/// A triangle fan as a list. glTF: triangle `i` is `(i + 1, i + 2, 0)`.
fn fan_to_list(stream: &[u32]) -> Vec<u32> {
    (0..stream.len().saturating_sub(2))
        .flat_map(|i| [stream[i + 1], stream[i + 2], stream[0]])
        .collect()
}

/// ` "name"` for messages, or nothing.
fn quoted(name: &Option<String>) -> String {
    name.as_ref().map_or(String::new(), |n| format!(" \"{n}\""))
}

/// Why a light or camera whose node maps its axis to nothing has no direction.
const NO_AXIS: &str =
    "its node's transform maps the -Z axis to zero (a zero scale or a singular matrix)";

/// `v` at unit length, or zero only when `v` is zero. A node's scale scales the axes a light or
/// camera points along (1e-30, 1e20, or [1, 1, 1e-30]) but not their direction (the
/// `KHR_lights_punctual` spec: scale does not affect a light). f32's `normalize_or_zero`
/// squares the length, which underflows below about 1e-19 and overflows above about 1e19 and
/// then gives zero, as if there were no direction; f64 holds the square of every f32, so it
/// takes over there. Ordinary vectors keep f32's result bit for bit.
fn unit_or_zero(v: Vec3) -> Vec3 {
    match v.normalize_or_zero() {
        Vec3::ZERO => v.as_dvec3().normalize_or_zero().as_vec3(),
        unit => unit,
    }
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

    fn material(&mut self, i: usize, m: &json::Material) -> Result<Material, String> {
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

    fn attribute(
        &self,
        p: &json::mesh::Primitive,
        semantic: json::mesh::Semantic,
    ) -> Option<usize> {
        p.attributes
            .get(&Checked::Valid(semantic))
            .map(|index| index.value())
    }

    /// One primitive as a triangle list, or `None` (with a warning) when it draws no triangles.
    fn primitive(
        &mut self,
        p: &json::mesh::Primitive,
        at: &str,
    ) -> Result<Option<Primitive>, String> {
        use json::mesh::{Mode, Semantic};
        let Checked::Valid(mode) = p.mode else {
            return Err(format!("{at}: invalid mode"));
        };
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            self.model
                .warnings
                .push(format!("{at}: mode {mode:?} draws no triangles; left out"));
            return Ok(None);
        }
        let Some(position_accessor) = self.attribute(p, Semantic::Positions) else {
            self.model
                .warnings
                .push(format!("{at}: no POSITION attribute; left out"));
            return Ok(None);
        };
        fn read<T>(at: &str, what: &str, r: Result<T, String>) -> Result<T, String> {
            r.map_err(|e| format!("{at} {what}: {e}"))
        }
        let positions = read(at, "POSITION", self.data.vec3(position_accessor))?;
        let n = positions.len();
        let same_count = |what: &str, len: usize| {
            if len == n {
                Ok(())
            } else {
                Err(format!(
                    "{at}: {what} has {len} elements but POSITION has {n}"
                ))
            }
        };
        let mut normals = match self.attribute(p, Semantic::Normals) {
            Some(a) => Some(read(at, "NORMAL", self.data.vec3(a))?),
            None => None,
        };
        let mut tex_coords = match self.attribute(p, Semantic::TexCoords(0)) {
            Some(a) => read(at, "TEXCOORD_0", self.data.tex_coords(a))?,
            None => Vec::new(),
        };
        let mut tangents = match self.attribute(p, Semantic::Tangents) {
            Some(a) => read(at, "TANGENT", self.data.vec4(a))?,
            None => Vec::new(),
        };
        if let Some(normals) = &normals {
            same_count("NORMAL", normals.len())?;
        }
        if !tex_coords.is_empty() {
            same_count("TEXCOORD_0", tex_coords.len())?;
        }
        if !tangents.is_empty() {
            same_count("TANGENT", tangents.len())?;
        }
        let stream: Vec<u32> = match p.indices {
            Some(a) => read(at, "indices", self.data.indices(a.value()))?,
            None => {
                let n32 = u32::try_from(n)
                    .map_err(|_| format!("{at}: {n} vertices without indices are too many"))?;
                (0..n32).collect()
            }
        };
        if let Some((e, &bad)) = stream.iter().enumerate().find(|&(_, &i)| i as usize >= n) {
            return Err(format!(
                "{at}: index {bad} (element {e} of the indices) is out of range (POSITION has {n} vertices)"
            ));
        }
        let mut indices = match mode {
            Mode::Triangles => {
                if !stream.len().is_multiple_of(3) {
                    self.model.warnings.push(format!(
                        "{at}: {} indices are not whole triangles; the last {} dropped",
                        stream.len(),
                        stream.len() % 3
                    ));
                }
                let whole = stream.len() - stream.len() % 3;
                let mut s = stream;
                s.truncate(whole);
                s
            }
            Mode::TriangleStrip => strip_to_list(&stream),
            // Mode::TriangleFan, the only remaining triangle mode.
            _ => fan_to_list(&stream),
        };
        let mut positions = positions;
        match &mut normals {
            Some(normals) => {
                let mut fixed = 0;
                for v in normals.iter_mut() {
                    if (v.length_squared() - 1.0).abs() > 2e-3 {
                        *v = v.normalize_or(Vec3::Z);
                        fixed += 1;
                    }
                }
                if fixed > 0 {
                    self.model.warnings.push(format!(
                        "{at}: {fixed} normal(s) were not unit length and were normalised"
                    ));
                }
            }
            None => {
                // glTF: without normals, flat normals; tangents are then ignored.
                let (p, nr, t, i) = flat_normals(&positions, &tex_coords, &indices);
                positions = p;
                normals = Some(nr);
                tex_coords = t;
                indices = i;
                tangents.clear();
            }
        }
        let normals = normals.unwrap_or_default();
        let material = p.material.map(|m| m.value());
        let wants_tangents = material
            .and_then(|m| self.model.materials.get(m))
            .is_some_and(|m| m.normal_texture.is_some());
        let tangent_source = if !tangents.is_empty() {
            TangentSource::File
        } else if wants_tangents && !tex_coords.is_empty() {
            tangents = generate_tangents(&positions, &normals, &tex_coords, &indices);
            TangentSource::Generated
        } else {
            if wants_tangents {
                self.model.warnings.push(format!(
                    "{at}: the material has a normal map but the primitive has no TEXCOORD_0; no tangents"
                ));
            }
            TangentSource::None
        };
        if p.targets.as_ref().is_some_and(|t| !t.is_empty()) {
            self.model
                .warnings
                .push(format!("{at}: morph targets ignored"));
        }
        Ok(Some(Primitive {
            bounds: Aabb::from_points(positions.iter().copied()),
            positions,
            normals,
            tex_coords,
            tangents,
            tangent_source,
            indices,
            material,
        }))
    }

    fn image(
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

    /// A node's own transform, checked to be finite and, given as a `matrix`, affine.
    fn local_transform(node: &json::Node) -> Result<Mat4, String> {
        let m = match node.matrix {
            Some(m) => {
                // Column-major: the last row is elements 3, 7, 11 and 15.
                let last_row = [m[3], m[7], m[11], m[15]];
                if last_row != [0.0, 0.0, 0.0, 1.0] {
                    return Err(format!(
                        "matrix has last row {last_row:?}, not [0, 0, 0, 1]: the spec requires \
                         a matrix made of translation, rotation and scale"
                    ));
                }
                Mat4::from_cols_array(&m)
            }
            None => {
                let t = Vec3::from_array(node.translation.unwrap_or([0.0; 3]));
                let s = Vec3::from_array(node.scale.unwrap_or([1.0; 3]));
                let q = node.rotation.as_ref().map_or([0.0, 0.0, 0.0, 1.0], |r| r.0);
                let q = Quat::from_array(q);
                let len = q.length();
                if !(len > 0.0 && len.is_finite()) {
                    return Err(format!("rotation {q} is not a unit quaternion"));
                }
                Mat4::from_scale_rotation_translation(s, q / len, t)
            }
        };
        if m.is_finite() {
            Ok(m)
        } else {
            Err("transform is not finite".into())
        }
    }

    /// Step 5: the iterative walk of the node hierarchy.
    fn walk_nodes(&mut self) -> Result<(), String> {
        let nodes = &self.root.nodes;
        let locals = nodes
            .iter()
            .enumerate()
            .map(|(i, n)| {
                Self::local_transform(n).map_err(|e| format!("nodes[{i}]{}: {e}", quoted(&n.name)))
            })
            .collect::<Result<Vec<_>, _>>()?;
        for (i, n) in nodes.iter().enumerate() {
            let trs = [
                ("translation", n.translation.is_some()),
                ("rotation", n.rotation.is_some()),
                ("scale", n.scale.is_some()),
            ];
            let given: Vec<&str> = trs.iter().filter(|t| t.1).map(|t| t.0).collect();
            if n.matrix.is_some() && !given.is_empty() {
                self.model.warnings.push(format!(
                    "nodes[{i}]{}: has both matrix and {} (the spec allows one or the other); \
                     the matrix is used",
                    quoted(&n.name),
                    given.join(", ")
                ));
            }
        }
        let scene = self
            .root
            .scene
            .map(|s| s.value())
            .or((!self.root.scenes.is_empty()).then_some(0));
        let roots: Vec<usize> = match scene {
            Some(s) => self
                .root
                .scenes
                .get(s)
                .ok_or_else(|| format!("scene {s} does not exist"))?
                .nodes
                .iter()
                .map(|n| n.value())
                .collect(),
            None => {
                let mut has_parent = vec![false; nodes.len()];
                for child in nodes.iter().flat_map(|n| n.children.iter().flatten()) {
                    if let Some(flag) = has_parent.get_mut(child.value()) {
                        *flag = true;
                    }
                }
                let roots: Vec<usize> = (0..nodes.len()).filter(|&i| !has_parent[i]).collect();
                if !nodes.is_empty() {
                    self.model.warnings.push(format!(
                        "no scene: drawing the {} node(s) without a parent",
                        roots.len()
                    ));
                }
                roots
            }
        };
        enum Step {
            Enter(usize, Mat4),
            Leave(usize),
        }
        let mut on_path = vec![false; nodes.len()];
        let mut stack: Vec<Step> = roots
            .iter()
            .rev()
            .map(|&n| Step::Enter(n, Mat4::IDENTITY))
            .collect();
        let mut visits = 0usize;
        while let Some(step) = stack.pop() {
            let (n, parent) = match step {
                Step::Leave(n) => {
                    on_path[n] = false;
                    continue;
                }
                Step::Enter(n, parent) => (n, parent),
            };
            let node = nodes
                .get(n)
                .ok_or_else(|| format!("node {n} does not exist"))?;
            let at = format!("nodes[{n}]{}", quoted(&node.name));
            if on_path[n] {
                return Err(format!(
                    "{at} is its own ancestor (a cycle in the node hierarchy)"
                ));
            }
            visits += 1;
            if visits > MAX_NODE_VISITS {
                return Err(format!(
                    "the node hierarchy expands to more than {MAX_NODE_VISITS} node instances"
                ));
            }
            let world = parent * locals[n];
            if !world.is_finite() {
                return Err(format!("{at}: world transform is not finite"));
            }
            if let Some(mesh) = node.mesh {
                let mesh = mesh.value();
                if mesh >= self.model.meshes.len() {
                    return Err(format!("{at}: mesh {mesh} does not exist"));
                }
                self.model.instances.push(Instance {
                    mesh,
                    world_from_local: world,
                    node: n,
                    name: node.name.clone(),
                });
            }
            if let Some(camera) = node.camera {
                self.camera(camera.value(), n, node, world)
                    .map_err(|e| format!("{at}: {e}"))?;
            }
            if let Some(light) = node
                .extensions
                .as_ref()
                .and_then(|e| e.khr_lights_punctual.as_ref())
            {
                self.light(light.light.value(), n, node, world)
                    .map_err(|e| format!("{at}: {e}"))?;
            }
            on_path[n] = true;
            stack.push(Step::Leave(n));
            for child in node.children.iter().flatten().rev() {
                stack.push(Step::Enter(child.value(), world));
            }
        }
        Ok(())
    }

    fn camera(
        &mut self,
        index: usize,
        node: usize,
        n: &json::Node,
        world: Mat4,
    ) -> Result<(), String> {
        let c = self
            .root
            .cameras
            .get(index)
            .ok_or_else(|| format!("camera {index} does not exist"))?;
        let at = format!("cameras[{index}]{}", quoted(&c.name));
        let projection = match c.type_ {
            Checked::Valid(json::camera::Type::Perspective) => {
                let p = c.perspective.as_ref().ok_or_else(|| {
                    format!("{at}: type perspective without a perspective object")
                })?;
                if !(p.yfov > 0.0 && p.yfov < std::f32::consts::PI) {
                    return Err(format!("{at}: yfov {} is not in (0, π)", p.yfov));
                }
                if !(p.znear > 0.0 && p.znear.is_finite()) {
                    return Err(format!("{at}: znear {} is not finite and > 0", p.znear));
                }
                // An infinite projection (no zfar) gets a far plane beyond znear, which f32
                // cannot hold past f32::MAX.
                if p.zfar.is_none() && !(p.znear < f32::MAX) {
                    return Err(format!(
                        "{at}: znear {:e} without a zfar leaves no room for a far plane (it must \
                         be below f32::MAX)",
                        p.znear
                    ));
                }
                if let Some(f) = p.zfar
                    && !(f > p.znear && f.is_finite())
                {
                    return Err(format!(
                        "{at}: zfar {f} is not finite and > znear {}",
                        p.znear
                    ));
                }
                // The spec requires aspectRatio > 0. Only the output size sets the aspect here,
                // so a bad one changes nothing; it is dropped and reported.
                let aspect_ratio = p.aspect_ratio.filter(|a| *a > 0.0 && a.is_finite());
                if let Some(a) = p.aspect_ratio
                    && aspect_ratio.is_none()
                {
                    self.model.warnings.push(format!(
                        "{at}: aspectRatio {a} is not finite and > 0; ignored (the aspect \
                         follows the output size)"
                    ));
                }
                Projection::Perspective {
                    yfov: p.yfov,
                    znear: p.znear,
                    zfar: p.zfar,
                    aspect_ratio,
                }
            }
            Checked::Valid(json::camera::Type::Orthographic) => {
                let o = c.orthographic.as_ref().ok_or_else(|| {
                    format!("{at}: type orthographic without an orthographic object")
                })?;
                let ok = o.xmag.is_finite()
                    && o.xmag != 0.0
                    && o.ymag.is_finite()
                    && o.ymag != 0.0
                    && o.znear >= 0.0
                    && o.zfar > o.znear
                    && o.zfar.is_finite();
                if !ok {
                    return Err(format!(
                        "{at}: orthographic xmag {}, ymag {}, znear {}, zfar {} are not valid",
                        o.xmag, o.ymag, o.znear, o.zfar
                    ));
                }
                Projection::Orthographic {
                    xmag: o.xmag,
                    ymag: o.ymag,
                    znear: o.znear,
                    zfar: o.zfar,
                }
            }
            Checked::Invalid => return Err(format!("{at}: invalid type")),
        };
        let position = world.transform_point3(Vec3::ZERO);
        let forward = unit_or_zero(world.transform_vector3(Vec3::NEG_Z));
        let up = world.transform_vector3(Vec3::Y);
        let up = unit_or_zero(up - forward * forward.dot(up));
        let degenerate = if forward == Vec3::ZERO {
            Some(NO_AXIS)
        } else if up == Vec3::ZERO {
            Some("its node's transform maps the up axis (+Y) to zero or onto the view axis")
        } else {
            None
        };
        if let Some(why) = degenerate {
            self.model.warnings.push(format!(
                "{at}: {why}, so the camera has no view direction; left out"
            ));
            return Ok(());
        }
        let name = c
            .name
            .clone()
            .or_else(|| n.name.clone())
            .unwrap_or_else(|| format!("camera {index}"));
        self.model.cameras.push(ModelCamera {
            name,
            node,
            position,
            forward,
            up,
            projection,
        });
        Ok(())
    }

    /// A node's `KHR_lights_punctual` light: a row of [`Model::lights`] (point, spot) or a
    /// [`DirectionalLight`]. A light whose values cannot make a light is left out, listed in
    /// [`Model::skipped_lights`] and warned about (see "Invalid lights" in the module docs); only
    /// a light index that does not exist is an error, since then the document itself is broken.
    fn light(
        &mut self,
        index: usize,
        node: usize,
        n: &json::Node,
        world: Mat4,
    ) -> Result<(), String> {
        let light = self
            .root
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .and_then(|l| l.lights.get(index))
            .ok_or_else(|| format!("KHR_lights_punctual light {index} does not exist"))?;
        let at = format!("KHR_lights_punctual lights[{index}]{}", quoted(&light.name));
        let name = light.name.clone().or_else(|| n.name.clone());
        match self.usable_light(light, &at, world) {
            Ok(Usable::Directional { direction, color }) => {
                self.model.directional_lights.push(DirectionalLight {
                    name,
                    direction,
                    color,
                    intensity: light.intensity,
                });
            }
            Ok(Usable::Clustered {
                record,
                kind,
                range,
            }) => {
                let row = self.model.lights.len() as u32;
                self.model.lights.push(record.with_source_index(row));
                self.model.placed_lights.push(PlacedLight {
                    name,
                    node,
                    light: index,
                    kind,
                    range,
                });
            }
            Err(reason) => {
                self.model.warnings.push(format!(
                    "nodes[{node}]{}: {at}: {reason}; left out",
                    quoted(&n.name)
                ));
                self.model.skipped_lights.push(SkippedPunctualLight {
                    name,
                    node,
                    light: index,
                    reason,
                });
            }
        }
        Ok(())
    }

    /// What `light`, placed by a node with transform `world`, becomes; `Err` says why it cannot
    /// be a light. Values the loader repairs (an inner cone outside the outer) are warned about
    /// here, under `at`.
    fn usable_light(
        &mut self,
        light: &json::extensions::scene::khr_lights_punctual::Light,
        at: &str,
        world: Mat4,
    ) -> Result<Usable, String> {
        use json::extensions::scene::khr_lights_punctual::Type;
        let color = finite_vec3(light.color, "color")?;
        if color.min_element() < 0.0 || !(light.intensity >= 0.0 && light.intensity.is_finite()) {
            return Err(format!(
                "color {color} and intensity {} must be finite and >= 0",
                light.intensity
            ));
        }
        let direction = unit_or_zero(world.transform_vector3(Vec3::NEG_Z));
        let kind = match light.type_ {
            Checked::Valid(Type::Directional) => {
                if direction == Vec3::ZERO {
                    return Err(format!("{NO_AXIS}, so the light has no direction"));
                }
                return Ok(Usable::Directional { direction, color });
            }
            Checked::Valid(Type::Point) => PunctualKind::Point,
            Checked::Valid(Type::Spot) => {
                let spot = light
                    .spot
                    .as_ref()
                    .ok_or("type spot without a spot object")?;
                let outer = spot.outer_cone_angle;
                if !(outer > 0.0 && outer <= std::f32::consts::PI) {
                    return Err(format!("outerConeAngle {outer} is not in (0, π]"));
                }
                if outer > std::f32::consts::FRAC_PI_2 {
                    // The spec stops at π/2; the assignment, the oracle and the shaders handle
                    // cones up to π (a spot wider than a hemisphere), so the light is kept as is.
                    self.model.warnings.push(format!(
                        "{at}: outerConeAngle {outer} is above the spec's π/2; kept as a cone \
                         wider than a hemisphere"
                    ));
                }
                let mut inner = spot.inner_cone_angle;
                // The spec wants 0 <= inner < outer. Only the outer cone bounds the light, so a
                // bad inner angle is kept usable (clamped) and reported, not fatal.
                if !(inner >= 0.0 && inner < outer) {
                    let clamped = inner.clamp(0.0, outer * 0.999);
                    self.model.warnings.push(format!(
                        "{at}: innerConeAngle {inner} is not in [0, outerConeAngle {outer}); \
                         clamped to {clamped}"
                    ));
                    inner = clamped;
                }
                PunctualKind::Spot {
                    inner_cone_angle: inner,
                    outer_cone_angle: outer,
                }
            }
            Checked::Invalid => return Err("invalid type".into()),
        };
        let range = match light.range {
            Some(r) if r > 0.0 && r.is_finite() => Some(r),
            Some(r) => return Err(format!("range {r} is not finite and > 0")),
            None => None,
        };
        let radius = range.unwrap_or_else(|| {
            radius_from_intensity(
                light.intensity * color.max_element(),
                self.options.light_cutoff,
            )
        });
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(format!(
                "no range, and its intensity gives the radius {radius} (lights nothing, or \
                 everything)"
            ));
        }
        let position = world.transform_point3(Vec3::ZERO);
        let mut record = LightRecord::point(position, radius)
            .with_color(color)
            .with_intensity(light.intensity);
        if let PunctualKind::Spot {
            outer_cone_angle, ..
        } = kind
        {
            if direction == Vec3::ZERO {
                return Err(format!("{NO_AXIS}, so the light has no direction"));
            }
            record = record.with_spot(direction, outer_cone_angle);
        }
        Ok(Usable::Clustered {
            record,
            kind,
            range,
        })
    }
}

/// What a valid `KHR_lights_punctual` light becomes (see `Loader::usable_light`).
enum Usable {
    /// A sun: only a direction.
    Directional { direction: Vec3, color: Vec3 },
    /// A point or spot light, ready for [`Model::lights`] but for its `source_index`.
    Clustered {
        record: LightRecord,
        kind: PunctualKind,
        range: Option<f32>,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-triangle glTF with an embedded buffer; `extra` is spliced into the root object.
    fn triangle_gltf(indices: [u16; 3], extra: &str) -> String {
        let mut bytes: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
        bytes.extend([0, 0]);
        let uri = format!("data:application/octet-stream;base64,{}", base64(&bytes));
        format!(
            r#"{{"asset": {{"version": "2.0"}},
  "buffers": [{{"byteLength": {}, "uri": "{uri}"}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 6}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]}},
                {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}],
  "meshes": [{{"name": "tri", "primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}]
  {extra}}}"#,
            bytes.len()
        )
    }

    /// Standard base64 (test helper; the loader uses the `gltf` crate's decoder).
    fn base64(bytes: &[u8]) -> String {
        const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = String::new();
        for chunk in bytes.chunks(3) {
            let b = [
                chunk[0],
                *chunk.get(1).unwrap_or(&0),
                *chunk.get(2).unwrap_or(&0),
            ];
            let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
            for k in 0..4 {
                if k <= chunk.len() {
                    out.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
                } else {
                    out.push('=');
                }
            }
        }
        out
    }

    fn load_str(text: &str) -> Result<Model> {
        Model::from_gltf_slice(text.as_bytes(), "t.gltf", None, &LoadOptions::default())
    }

    #[test]
    fn loads_a_triangle_with_instances_cameras_and_lights() {
        let extra = r#",
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {"KHR_lights_punctual": {"lights": [
      {"type": "point", "intensity": 40, "color": [1, 0.5, 0.5]},
      {"type": "spot", "intensity": 5, "range": 7, "spot": {"outerConeAngle": 0.5}},
      {"type": "directional", "intensity": 3},
      {"type": "point", "intensity": 0}]}},
  "cameras": [{"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.1}}],
  "scenes": [{"nodes": [0, 3, 8]}],
  "nodes": [{"translation": [10, 0, 0], "children": [1, 2]},
            {"mesh": 0},
            {"mesh": 0, "translation": [0, 5, 0], "name": "up"},
            {"children": [4, 5, 6, 7]},
            {"camera": 0, "name": "Eye", "translation": [0, 0, 5]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [1, 2, 3]},
            {"extensions": {"KHR_lights_punctual": {"light": 1}}, "rotation": [-0.7071068, 0, 0, 0.7071068]},
            {"extensions": {"KHR_lights_punctual": {"light": 2}}},
            {"extensions": {"KHR_lights_punctual": {"light": 3}}, "name": "dark"}]"#;
        let model = load_str(&triangle_gltf([0, 1, 2], extra)).unwrap();
        assert_eq!(model.meshes.len(), 1);
        assert_eq!(model.instances.len(), 2);
        assert_eq!(model.triangle_count(), 2);
        let b = model.bounds();
        assert_eq!(b.min, Vec3::new(10.0, 0.0, 0.0));
        assert_eq!(b.max, Vec3::new(11.0, 6.0, 0.0));
        // No normals in the file: flat normals, facing +Z.
        assert_eq!(model.meshes[0].primitives[0].normals, [Vec3::Z; 3]);
        assert_eq!(model.cameras.len(), 1);
        assert_eq!(model.cameras[0].name, "Eye");
        assert_eq!(model.cameras[0].position, Vec3::new(0.0, 0.0, 5.0));
        let camera = model.camera(0, 800, 600).unwrap();
        assert_eq!((camera.width, camera.near), (800, 0.1));
        assert_eq!(model.lights.len(), 2);
        // Point light: radius from intensity 40 × max colour 1 at the default cut-off.
        let expected = (40.0f32 / DEFAULT_LIGHT_CUTOFF).sqrt();
        assert!((model.lights.radius[0] - expected).abs() < 1e-4);
        assert_eq!(model.lights.get(0).position, Vec3::new(1.0, 2.0, 3.0));
        // Spot light: range kept, axis = node's -Z rotated -90° about X = straight down.
        let spot = model.lights.get(1);
        assert_eq!(spot.radius, 7.0);
        let cone = spot.spot.unwrap();
        assert!(
            (cone.direction - Vec3::NEG_Y).length() < 1e-5,
            "{}",
            cone.direction
        );
        assert_eq!(cone.angle, 0.5);
        assert!(model.lights.problems().is_empty());
        assert_eq!(model.placed_lights[1].range, Some(7.0));
        assert_eq!(model.directional_lights.len(), 1);
        assert_eq!(model.directional_lights[0].direction, Vec3::NEG_Z);
        // A light of intensity 0 without range lights nothing: left out, counted, warned about.
        assert_eq!(model.warnings.len(), 1, "{:?}", model.warnings);
        assert!(
            model.warnings[0]
                .starts_with("nodes[8] \"dark\": KHR_lights_punctual lights[3]: no range"),
            "{:?}",
            model.warnings
        );
        assert_eq!(model.skipped_lights.len(), 1);
        assert_eq!(model.skipped_lights[0].node, 8);
        assert_eq!(model.skipped_lights[0].light, 3);
        assert_eq!(model.summary().skipped_lights, 1);
    }

    #[test]
    fn invalid_lights_are_left_out_counted_and_reported() {
        // Each bad light is skipped on its own: the triangle, the camera and the good light
        // stay (these used to make the whole file an error).
        let bad = [
            (
                r#"{"type": "point", "range": 0}"#,
                "range 0 is not finite and > 0",
            ),
            (
                r#"{"type": "point", "range": -3}"#,
                "range -3 is not finite and > 0",
            ),
            (
                r#"{"type": "point", "intensity": -1, "range": 2}"#,
                "intensity -1 must be finite and >= 0",
            ),
            (
                r#"{"type": "point", "intensity": 1e39, "range": 2}"#,
                "intensity inf must be finite and >= 0",
            ),
            (
                r#"{"type": "point", "color": [1, -1, 1], "range": 2, "name": "red"}"#,
                "color [1, -1, 1] and intensity 1",
            ),
            (
                r#"{"type": "spot", "range": 2, "spot": {"outerConeAngle": 0}}"#,
                "outerConeAngle 0 is not in (0, π]",
            ),
            (
                r#"{"type": "directional", "intensity": -2}"#,
                "intensity -2 must be finite and >= 0",
            ),
        ];
        let lights: Vec<&str> = bad.iter().map(|(light, _)| *light).collect();
        let nodes: Vec<String> = (0..bad.len())
            .map(|i| format!(r#"{{"extensions": {{"KHR_lights_punctual": {{"light": {i}}}}}}}"#))
            .collect();
        let good = bad.len();
        let extra = format!(
            r#",
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [{}, {{"type": "point", "range": 4}}]}}}},
  "scenes": [{{"nodes": [{}]}}],
  "nodes": [{}, {{"extensions": {{"KHR_lights_punctual": {{"light": {good}}}}}}}, {{"mesh": 0}}]"#,
            lights.join(", "),
            (0..good + 2)
                .map(|i| i.to_string())
                .collect::<Vec<_>>()
                .join(", "),
            nodes.join(", "),
        );
        let model = load_str(&triangle_gltf([0, 1, 2], &extra)).unwrap();
        assert_eq!(model.triangle_count(), 1);
        assert_eq!(model.lights.len(), 1);
        assert_eq!(model.lights.radius[0], 4.0);
        assert_eq!(model.placed_lights[0].light, good);
        assert!(model.directional_lights.is_empty());
        assert_eq!(
            model.skipped_lights.len(),
            bad.len(),
            "{:?}",
            model.warnings
        );
        assert_eq!(model.summary().skipped_lights, bad.len());
        assert_eq!(model.warnings.len(), bad.len(), "{:?}", model.warnings);
        for (i, (skipped, (_, why))) in model.skipped_lights.iter().zip(bad).enumerate() {
            assert_eq!((skipped.node, skipped.light), (i, i));
            assert!(skipped.reason.contains(why), "{skipped:?}");
            let name = if i == 4 { " \"red\"" } else { "" };
            let warning = &model.warnings[i];
            assert!(
                warning.starts_with(&format!(
                    "nodes[{i}]: KHR_lights_punctual lights[{i}]{name}: "
                )) && warning.contains(why)
                    && warning.ends_with("; left out"),
                "{warning}"
            );
        }
        assert_eq!(model.skipped_lights[4].name.as_deref(), Some("red"));
    }

    #[test]
    fn tiny_and_huge_node_scales_keep_directions_and_zero_scales_are_named() {
        // A spot, a sun and a camera under one node scale, each rotated by `rotation`.
        let with = |scale: &str, rotation: &str| {
            let extra = format!(
                r#",
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [
      {{"type": "spot", "range": 7, "spot": {{"outerConeAngle": 0.5}}}},
      {{"type": "directional"}}]}}}},
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 1.0, "znear": 0.1}}}}],
  "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"scale": {scale}, "children": [1, 2, 3]}},
            {{"extensions": {{"KHR_lights_punctual": {{"light": 0}}}}, "rotation": {rotation}}},
            {{"extensions": {{"KHR_lights_punctual": {{"light": 1}}}}, "rotation": {rotation}}},
            {{"camera": 0, "rotation": {rotation}}}]"#
            );
            load_str(&triangle_gltf([0, 1, 2], &extra)).unwrap()
        };
        // f32 normalising squares these lengths to 0 or ∞: the nodes used to be "degenerate".
        // Uniform scales, with the nodes turned to look down -Y (up -Z); and the audit's
        // non-uniform case, unrotated (down -Z, up +Y).
        let down = "[-0.7071068, 0, 0, 0.7071068]";
        let ahead = "[0, 0, 0, 1]";
        for (scale, rotation, forward, up) in [
            ("[1e-30, 1e-30, 1e-30]", down, Vec3::NEG_Y, Vec3::NEG_Z),
            ("[1e-40, 1e-40, 1e-40]", down, Vec3::NEG_Y, Vec3::NEG_Z),
            ("[1e20, 1e20, 1e20]", down, Vec3::NEG_Y, Vec3::NEG_Z),
            ("[3e38, 3e38, 3e38]", down, Vec3::NEG_Y, Vec3::NEG_Z),
            ("[1, 1, 1e-30]", ahead, Vec3::NEG_Z, Vec3::Y),
            ("[1, 1, 1e30]", ahead, Vec3::NEG_Z, Vec3::Y),
        ] {
            let model = with(scale, rotation);
            let near = |a: Vec3, b: Vec3| (a - b).length() < 1e-4;
            assert!(model.warnings.is_empty(), "{scale}: {:?}", model.warnings);
            let spot = model.lights.get(0).spot.expect("the spot is kept");
            assert!(near(spot.direction, forward), "{scale}: {}", spot.direction);
            assert_eq!(model.directional_lights.len(), 1, "{scale}");
            let sun = model.directional_lights[0].direction;
            assert!(near(sun, forward), "{scale}: {sun}");
            assert_eq!(model.cameras.len(), 1, "{scale}");
            let camera = &model.cameras[0];
            assert!(near(camera.forward, forward), "{scale}: {}", camera.forward);
            assert!(near(camera.up, up), "{scale}: {}", camera.up);
        }
        // A zero scale really leaves no direction: left out, and the message says why.
        let model = with("[1, 1, 0]", ahead);
        assert!(model.lights.is_empty() && model.directional_lights.is_empty());
        assert!(model.cameras.is_empty());
        assert_eq!(model.skipped_lights.len(), 2, "{:?}", model.warnings);
        let axis_to_zero =
            "its node's transform maps the -Z axis to zero (a zero scale or a singular matrix)";
        assert_eq!(
            model.warnings,
            [
                format!(
                    "nodes[1]: KHR_lights_punctual lights[0]: {axis_to_zero}, so the light has no direction; left out"
                ),
                format!(
                    "nodes[2]: KHR_lights_punctual lights[1]: {axis_to_zero}, so the light has no direction; left out"
                ),
                format!(
                    "cameras[0]: {axis_to_zero}, so the camera has no view direction; left out"
                ),
            ]
        );
    }

    #[test]
    fn a_spot_inner_cone_outside_the_outer_is_clamped_and_reported() {
        let extra = r#",
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {"KHR_lights_punctual": {"lights": [
      {"type": "spot", "range": 7, "spot": {"innerConeAngle": 0.6, "outerConeAngle": 0.5}}]}},
  "scenes": [{"nodes": [0]}],
  "nodes": [{"extensions": {"KHR_lights_punctual": {"light": 0}}}]"#;
        let model = load_str(&triangle_gltf([0, 1, 2], extra)).unwrap();
        assert_eq!(model.lights.len(), 1);
        let PunctualKind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } = model.placed_lights[0].kind
        else {
            panic!("not a spot: {:?}", model.placed_lights[0].kind);
        };
        assert_eq!(outer_cone_angle, 0.5);
        assert!(inner_cone_angle < 0.5 && inner_cone_angle > 0.49);
        assert_eq!(model.warnings.len(), 1, "{:?}", model.warnings);
        assert!(
            model.warnings[0].contains("innerConeAngle 0.6 is not in [0, outerConeAngle 0.5)"),
            "{:?}",
            model.warnings
        );
    }

    #[test]
    fn a_spot_wider_than_the_spec_is_kept_and_reported() {
        let extra = r#",
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {"KHR_lights_punctual": {"lights": [
      {"type": "spot", "range": 7, "spot": {"outerConeAngle": 2.5}}]}},
  "scenes": [{"nodes": [0]}],
  "nodes": [{"extensions": {"KHR_lights_punctual": {"light": 0}}}]"#;
        let model = load_str(&triangle_gltf([0, 1, 2], extra)).unwrap();
        assert_eq!(model.lights.get(0).spot.unwrap().angle, 2.5);
        assert_eq!(model.warnings.len(), 1, "{:?}", model.warnings);
        assert!(
            model.warnings[0].contains("outerConeAngle 2.5 is above the spec's π/2"),
            "{:?}",
            model.warnings
        );
    }

    #[test]
    fn material_factors_outside_the_unit_range_are_clamped_and_reported() {
        let extra = r#",
  "materials": [{"name": "hot", "alphaMode": "MASK", "alphaCutoff": -0.5,
      "emissiveFactor": [2, 0.5, -1],
      "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": -2}},
      "pbrMetallicRoughness": {"baseColorFactor": [1.5, 0.5, -0.25, 1],
                               "metallicFactor": 3, "roughnessFactor": -1}},
      {"name": "fine", "emissiveFactor": [1, 0, 0],
       "pbrMetallicRoughness": {"baseColorFactor": [0, 0.5, 1, 0.5],
                                "metallicFactor": 1, "roughnessFactor": 0}}],
  "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}]"#;
        let model = load_str(&triangle_gltf([0, 1, 2], extra)).unwrap();
        let hot = &model.materials[0];
        assert_eq!(hot.base_color_factor, Vec4::new(1.0, 0.5, 0.0, 1.0));
        assert_eq!((hot.metallic_factor, hot.roughness_factor), (1.0, 0.0));
        assert_eq!(hot.emissive_factor, Vec3::ZERO);
        assert_eq!(hot.alpha_mode, AlphaMode::Mask { cutoff: 0.0 });
        let expected = [
            "baseColorFactor[0] 1.5 is outside [0, 1]; clamped to 1",
            "baseColorFactor[2] -0.25 is outside [0, 1]; clamped to 0",
            "metallicFactor 3 is outside [0, 1]; clamped to 1",
            "roughnessFactor -1 is outside [0, 1]; clamped to 0",
            "emissiveFactor[0] 2 is outside [0, 1]; clamped to 1",
            "emissiveFactor[2] -1 is outside [0, 1]; clamped to 0",
            "alphaCutoff -0.5 is outside [0, 1]; clamped to 0",
            "emissiveStrength -2 is negative; clamped to 0",
        ];
        assert_eq!(model.warnings.len(), expected.len(), "{:?}", model.warnings);
        for (w, e) in model.warnings.iter().zip(expected) {
            assert_eq!(w, &format!("materials[0] \"hot\": {e}"));
        }
        // In-range factors pass untouched.
        let fine = &model.materials[1];
        assert_eq!(fine.base_color_factor, Vec4::new(0.0, 0.5, 1.0, 0.5));
        assert_eq!((fine.metallic_factor, fine.roughness_factor), (1.0, 0.0));
    }

    #[test]
    fn strips_and_fans_become_lists() {
        assert_eq!(
            strip_to_list(&[10, 11, 12, 13, 14]),
            [10, 11, 12, 11, 13, 12, 12, 13, 14]
        );
        assert_eq!(fan_to_list(&[10, 11, 12, 13]), [11, 12, 10, 12, 13, 10]);
        assert!(strip_to_list(&[1, 2]).is_empty() && fan_to_list(&[]).is_empty());
        // Through the loader: one triangle either way, winding kept.
        for mode in [5, 6] {
            let text = triangle_gltf([0, 1, 2], "").replace(
                r#""indices": 1}"#,
                &format!(r#""indices": 1, "mode": {mode}}}"#),
            );
            let text = text.replace(
                r#""meshes""#,
                r#""nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "meshes""#,
            );
            let model = load_str(&text).unwrap();
            let p = &model.meshes[0].primitives[0];
            assert_eq!(p.triangle_count(), 1, "mode {mode}");
            // Winding kept: flat normal still +Z.
            assert_eq!(p.normals[0], Vec3::Z, "mode {mode}");
        }
    }

    #[test]
    fn broken_documents_are_errors_naming_the_problem() {
        let cycle = triangle_gltf(
            [0, 1, 2],
            r#", "scenes": [{"nodes": [0]}], "nodes": [{"children": [1]}, {"children": [0]}]"#,
        );
        let out_of_range = triangle_gltf([0, 1, 7], r#", "nodes": [{"mesh": 0}]"#);
        let cases = [
            (cycle, "nodes[0] is its own ancestor"),
            (
                out_of_range,
                "meshes[0] \"tri\" primitives[0]: index 7 (element 2 of the indices) is out of range",
            ),
            ("{".to_string(), "not valid glTF JSON"),
            (
                "glTX\u{2}\0\0\0".to_string(),
                "neither GLB (which starts with the magic \"glTF\") nor glTF JSON (an object, \
                 starting with '{'): it starts with glTX",
            ),
            (" \n\t".to_string(), "empty: neither GLB nor glTF JSON"),
            (
                r#"{"asset": {"version": "2.0"}, "nodes": [{"mesh": 3}]}"#.to_string(),
                "invalid glTF: nodes[0].mesh",
            ),
            (
                r#"{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 4, "uri": "missing.bin"}]}"#
                    .to_string(),
                "buffers[0] \"missing.bin\": an external file cannot be read without a base folder",
            ),
            (
                r#"{"asset": {"version": "2.0"}, "cameras": [{"type": "perspective"}], "nodes": [{"camera": 0}]}"#
                    .to_string(),
                "invalid glTF: cameras[0]: Missing data",
            ),
        ];
        for (text, expected) in cases {
            let e = load_str(&text).unwrap_err().to_string();
            assert!(e.starts_with("t.gltf: "), "{e}");
            assert!(e.contains(expected), "expected {expected:?} in {e}");
        }
        for glb in [
            &b"glTF"[..],
            b"glTF\x01\0\0\0\x14\0\0\0\0\0\0\0\0\0\0\0",
            b"glTF\x02\0\0\0\xff\xff\0\0\0\0\0\0\0\0\0\0",
        ] {
            let e = Model::from_gltf_slice(glb, "x.glb", None, &LoadOptions::default())
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("x.glb: ") && e.contains("GLB"), "{e}");
        }
    }

    /// `json` as a GLB with one JSON chunk (padded with spaces) and the given header length
    /// (`None`: the true one).
    fn glb(json: &str, declared: Option<u32>) -> Vec<u8> {
        let mut chunk = json.as_bytes().to_vec();
        chunk.resize(chunk.len().next_multiple_of(4), b' ');
        let total = 12 + 8 + chunk.len() as u32;
        let mut out = b"glTF".to_vec();
        for word in [2, declared.unwrap_or(total), chunk.len() as u32, 0x4E4F534A] {
            out.extend(u32::to_le_bytes(word));
        }
        out.extend(chunk);
        out
    }

    #[test]
    fn spec_violations_are_refused_or_reported() {
        let text = triangle_gltf(
            [0, 1, 2],
            r#", "scenes": [{"nodes": [0, 1]}], "nodes": [{"mesh": 0}, {}]"#,
        );
        // Refused: what the spec tells a loader not to load, and containers or buffers whose
        // declared lengths contradict their bytes.
        let refused = [
            (
                text.replace(r#""version": "2.0""#, r#""version": "3.0""#),
                "asset.version \"3.0\": only glTF 2.x is supported",
            ),
            (
                text.replace(
                    r#""version": "2.0""#,
                    r#""version": "2.0", "minVersion": "2.1""#,
                ),
                "asset.minVersion \"2.1\": this loader implements glTF 2.0 only",
            ),
            (
                text.replace(r#""version": "2.0""#, r#""version": "two""#),
                "asset.version \"two\" is not MAJOR.MINOR",
            ),
            (
                text.replace(r#""byteLength": 44"#, r#""byteLength": 10"#),
                "bufferViews[0]: bytes 0..0+36 lie outside buffer 0 (10 bytes)",
            ),
            (
                text.replace(
                    r#""nodes": [{"mesh": 0}, {}]"#,
                    r#""nodes": [{"mesh": 0}, {"name": "proj",
                      "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0]}]"#,
                ),
                "nodes[1] \"proj\": matrix has last row [0.0, 0.0, 0.0, 0.0], not [0, 0, 0, 1]",
            ),
            (
                text.replace(
                    r#""nodes": [{"mesh": 0}, {}]"#,
                    r#""nodes": [{"mesh": 0, "matrix": [1, 0, 0, 0.5, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}, {}]"#,
                ),
                "nodes[0]: matrix has last row [0.5, 0.0, 0.0, 1.0], not [0, 0, 0, 1]",
            ),
        ];
        for (text, expected) in refused {
            let e = load_str(&text).unwrap_err().to_string();
            assert!(e.starts_with("t.gltf: ") && e.contains(expected), "{e}");
        }
        // A later minor version of 2 loads.
        let minor = text.replace(
            r#""version": "2.0""#,
            r#""version": "2.7", "minVersion": "2.0""#,
        );
        assert_eq!(load_str(&minor).unwrap().triangle_count(), 1);
        // The GLB header's length must be the file's, shorter as well as longer.
        let load_glb =
            |bytes: &[u8]| Model::from_gltf_slice(bytes, "t.glb", None, &LoadOptions::default());
        let good = glb(&text, None);
        assert_eq!(load_glb(&good).unwrap().triangle_count(), 1);
        let short = glb(&text, Some(20));
        let e = load_glb(&short).unwrap_err().to_string();
        assert_eq!(
            e,
            format!(
                "t.glb: GLB header declares 20 bytes, but the file has {}",
                short.len()
            )
        );

        // Reported: the file breaks a rule, but one reading is clear and the model stays usable.
        let reported = [
            (
                text.replace(
                    r#""nodes": [{"mesh": 0}, {}]"#,
                    r#""nodes": [{}, {"mesh": 0, "name": "both", "translation": [0, 7, 0], "scale": [2, 2, 2],
                      "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 5, 0, 0, 1]}]"#,
                ),
                "nodes[1] \"both\": has both matrix and translation, scale (the spec allows one or \
                 the other); the matrix is used",
            ),
            (
                text.replace(
                    r#""nodes": [{"mesh": 0}, {}]"#,
                    r#""nodes": [{"mesh": 0}, {"camera": 0}],
                    "cameras": [{"type": "perspective",
                                 "perspective": {"yfov": 1, "znear": 0.1, "aspectRatio": 0}}]"#,
                ),
                "cameras[0]: aspectRatio 0 is not finite and > 0; ignored (the aspect follows the \
                 output size)",
            ),
            (
                text.replace(
                    r#""nodes": [{"mesh": 0}, {}]"#,
                    r#""nodes": [{"mesh": 0}, {"camera": 0}],
                    "cameras": [{"type": "perspective",
                                 "perspective": {"yfov": 1, "znear": 0.1, "aspectRatio": -2}}]"#,
                ),
                "cameras[0]: aspectRatio -2 is not finite and > 0; ignored (the aspect follows the \
                 output size)",
            ),
            (
                triangle_gltf([2, 1, 0], r#", "scenes": [{"nodes": [0, 1]}], "nodes": [{"mesh": 0}, {}]"#).replace(
                    r#""max": [1, 1, 0]}"#,
                    r#""max": [1, 1, 0], "sparse": {"count": 3,
                        "indices": {"bufferView": 1, "componentType": 5123},
                        "values": {"bufferView": 0}}}"#,
                ),
                "accessors[0]: sparse indices must strictly increase, but element 1 is 1 after 2; \
                 applied in file order (a repeated index takes its last value)",
            ),
            (
                r#"{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 4,
                    "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAA"}]}"#
                    .to_string(),
                "buffers[0] (data URI): holds 12 bytes but declares byteLength 4; the rest is \
                 ignored",
            ),
        ];
        for (text, expected) in &reported {
            let model = load_str(text).unwrap();
            assert_eq!(&model.warnings, &[*expected]);
            assert_eq!(model.triangle_count(), model.instances.len());
        }
        // The matrix wins over the TRS given beside it.
        let both = load_str(&reported[0].0).unwrap();
        assert_eq!(both.bounds().min, Vec3::new(5.0, 0.0, 0.0));
        assert_eq!(both.bounds().max, Vec3::new(6.0, 1.0, 0.0));
    }

    #[test]
    fn missing_files_name_the_path() {
        let e = Model::load("/no/such/model.gltf", &LoadOptions::default()).unwrap_err();
        assert_eq!(e.to_string(), "cannot read glTF file /no/such/model.gltf");
        let source = std::error::Error::source(&e).expect("the OS error is the source");
        assert!(source.to_string().contains("No such file"), "{source}");
    }
}
