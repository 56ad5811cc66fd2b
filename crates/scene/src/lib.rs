//! # myriad-scene — scenes, and the scene file every tool agrees on
//!
//! A scene, for the assignment, is a camera, a cluster grid and lights; for the renderer it is
//! also geometry. This crate reads and writes the JSON scene file (the shared contract of the
//! CLI, the benches and the tests; its format is below), holds lights the way the rest of myriad
//! consumes them — as structure-of-arrays columns ([`Lights`]) — loads glTF 2.0 models
//! ([`Model`]), generates the project's default scene (the atrium) and seeded light fields, and
//! runs the per-frame ECS-style systems on light columns (animate, cull, to view space).
//!
//! ## Modules
//! * [`Lights`] / [`LightRecord`] (`lights.rs`): SoA light columns and their row type. Spot columns
//!   exist only when some light is a spot; point lights then have a zero direction and angle π.
//! * [`Scene`], [`LightPolicy`], [`SkippedLight`] (`scene_file.rs`): reading and writing files.
//! * [`validate_file`], [`ValidationReport`] (`validate.rs`): every problem in a file at once.
//! * [`Model`] and its parts (`model.rs`): meshes of triangle primitives, instances with world
//!   transforms, PBR materials, images, cameras, punctual lights as [`Lights`] columns.
//! * [`Model::load`], [`LoadOptions`] (`gltf_load/`): the glTF 2.0 loader (`.gltf`, `.glb`,
//!   `KHR_lights_punctual`), with bounds-checked accessor reads (`gltf_accessors.rs`) and
//!   generated flat normals and tangents (`tangents.rs`). [`Model::to_glb`] (`glb_write.rs`)
//!   writes untextured models back as reproducible GLB.
//! * [`atrium()`], [`ATRIUM_FILE`] (`atrium.rs`): the generated default scene, shipped as
//!   `assets/atrium.glb`.
//! * [`LightField`], [`Placement`], [`SurfaceSampler`] (`light_fields.rs`): seeded lights in a
//!   box, the frustum, on surfaces, in clumps, on a sphere, with radii from a range or from
//!   intensity ([`radius_from_intensity`]).
//! * [`Preset`] (`presets.rs`): the seeded standard benchmark scenes (`paper`, `uniform`,
//!   `sphere`), each a light field with a camera and grid.
//! * [`systems`]: the frame systems — [`systems::animate_orbits`], [`systems::animate_wander`],
//!   [`systems::cull_lights`], [`systems::lights_to_view`] — plain functions over column slices,
//!   parallel with rayon above a few thousand lights.
//! * [`Error`], [`Problem`], [`Result`] (`error.rs`): one error enum for the crate.
//! * [`printable()`] (`printable.rs`): a file's own text (names, keys) with control characters
//!   escaped, for every message that shows it.
//! * Private: `json.rs` (a JSON tree that keeps duplicate keys and integer kinds, and typed field
//!   readers), `read.rs` (the streaming reader), `checks.rs` (value checks shared by reader and
//!   writer).
//!
//! ## Who validates what
//! This crate is the gate between untrusted files and the rest of myriad. `myriad-cluster-math`
//! trusts its inputs and `assert!`s ([`ClusterGrid::new`] panics on a zero dimension); the
//! assignment crate takes plain slices and trusts them too. So every value read from a file is
//! checked here, before any of those constructors run, and **no input makes the reader panic**:
//! truncated or binary files, wrong types, absurd numbers all become an [`Error`] that names the
//! file, the JSON path (`lights[3].spot.angle_deg`) and what is wrong. Scenes built in code are
//! not checked on construction (misuse is the caller's bug), but [`Scene::problems`] applies the
//! same checks, and [`Scene::to_json_string`] refuses to write a scene that would not read back.
//!
//! ## Reading, step by step
//! 1. **Syntax.** A leading UTF-8 byte-order mark is skipped; a UTF-16 or UTF-32 file (by its
//!    byte-order mark, or ASCII beside zero bytes) is [`Error::Encoding`], named as such rather
//!    than as a syntax error at line 1. serde_json parses the bytes (its recursion limit of 128 bounds the stack). The
//!    `lights` array is streamed: each light is checked and appended to the columns before the
//!    next is parsed. A syntax error, invalid UTF-8, a number beyond the f64 range (`1e999`) or a
//!    top level that is not an object is [`Error::Json`], with line and column.
//! 2. **Structure.** Types, array lengths (`position` must have exactly 3 numbers), required
//!    fields, whole numbers where integers are due (`"width": 1536`, not `1536.0`), and
//!    **unknown or duplicate fields, which are errors**: a typo such as `"raduis"`
//!    would otherwise silently fall back to a default. `null` for an optional field means absent.
//! 3. **Values.** Each number is read as f64 and rounded to f32 once; one that overflows f32
//!    (`1e39`) is an error, not an infinity. Degrees are converted to radians in f64 and then
//!    rounded once. Checks: everything finite; camera `position != target`, `up != 0` and not
//!    parallel to `target − position` (the roll would be the camera's fallback, a guess),
//!    `fov_y_deg` in (0, 180) (and frustum slopes that are normal f32 numbers),
//!    `width, height >= 1`, `1e-12 <= near < far` with `near·far` finite (compared after rounding to f32;
//!    `ClusterGrid::MIN_NEAR` is the floor); grid dimensions `>= 1` with `x·y·z <= u32::MAX` (cluster ids are u32); light
//!    `radius > 0` (a non-zero radius that rounds to 0 in f32, `1e-46`, is named as written),
//!    colour and `intensity >= 0` with colour × intensity finite in f32 (the renderer's radiance),
//!    spot direction non-zero, spot `angle_deg` in (0, 180] and `inner_angle_deg`, when given, in
//!    [0, `angle_deg`). Every problem is collected, never
//!    only the first.
//! 4. **Policy.** Problems with the root, camera or grid are always errors. Invalid lights are an
//!    error with [`LightPolicy::Strict`], or are left out and listed in [`Scene::skipped`] with
//!    [`LightPolicy::SkipInvalid`] — never dropped silently. Kept lights carry their index in the
//!    file's `lights` array in [`Lights::source_index`], so outputs refer to input order.
//!    [`validate_file`] returns all problems instead.
//!
//! ## The format, and this crate's extensions to it
//! ```json
//! { "camera": {"position": [0, 2, 10], "target": [0, 2, 0], "up": [0, 1, 0], "fov_y_deg": 60,
//!              "width": 1536, "height": 768, "near": 0.1, "far": 100},
//!   "grid":   {"x": 24, "y": 12, "z": 16, "depth": "log"},
//!   "lights": [{"position": [1, 2, 3], "radius": 2, "color": [1, 0.5, 0.2], "intensity": 4},
//!              {"position": [0, 5, 0], "radius": 8,
//!               "spot": {"direction": [0, -1, 0], "angle_deg": 30}}] }
//! ```
//! * Defaults: camera `up` = `[0, 1, 0]`; light `color` = `[1, 1, 1]`, `intensity` = 1. All other
//!   fields are required (`"lights": []` is a valid, empty list).
//! * `depth` is `"linear"`, `"log"` or the extension **`"log_near"`** (a near slice, then log
//!   slices; [`DepthSlicing::LogWithNearSlice`]), which requires `"first_slice_depth"`: the view
//!   depth where slice 1 starts, strictly between the camera's `near` and `far` (also for z = 1).
//!   `first_slice_depth` is an error with any other `depth`.
//! * The grid always spans the camera's `[near, far]`.
//! * Spot lights: `spot.angle_deg` is the outer half angle; stored as radians in
//!   [`Lights::spot_angle`] (`>= π` means omnidirectional). The direction need not be unit length
//!   in the file; it is normalized on reading (kept bit for bit when already within 1e-6 of unit).
//! * The extension **`spot.inner_angle_deg`** (optional): where the spot's falloff starts, as
//!   glTF's `innerConeAngle`; stored in [`Lights::spot_inner_angle`]. Without it a spot gets
//!   [`DEFAULT_SPOT_INNER_FRACTION`] (0.8) of its outer angle, and the writer leaves that default
//!   out. It only shades: the assignment bounds a spot by its outer angle.
//!
//! ## Writing
//! [`Scene::to_json_string`] / [`Scene::save`] write one line per light, in `source_index` order,
//! skipped lights omitted. f32 values are written as their shortest round-trip decimals and angles
//! as degrees that convert back to the same radians, so write → read is **bit-exact** for camera,
//! grid and lights. (serde_json reads numbers through f64; that every finite f32 survives its
//! write → f64 → f32 trip was checked exhaustively over all 2³² bit patterns with serde_json
//! 1.0.154; the tests re-check a sample.)
//!
//! ## What it refuses to do
//! It does not guess: no clamping of negative colours, no default camera or grid, no repair of a
//! degenerate camera, no dropping of lights without a record. It does not fix up a scene built in
//! code either; it reports ([`Scene::problems`]) and refuses to write it.
//!
//! The same stance holds for glTF files: the loader ([`Model::load`]) never panics on any input
//! and reports broken files as [`Error::Gltf`] naming the file, the place in the document and the
//! problem. What it leaves out of a valid file (lines and points, skins, animations, extra UV
//! sets) it lists in [`Model::warnings`], never silently; an invalid light is left out, listed in
//! [`Model::skipped_lights`] and warned about, as a scene file's invalid lights are skipped. It does not render, and it does not
//! pick light radii by guesswork: glTF lights without a `range` get the documented
//! inverse-square cut-off ([`LoadOptions::light_cutoff`]).
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod atrium;
mod checks;
mod error;
mod glb_write;
mod gltf_accessors;
mod gltf_load;
mod json;
mod light_fields;
mod lights;
mod model;
mod presets;
mod pressed_faces;
mod printable;
mod profiling;
mod read;
mod read_file;
mod replace_file;
mod replace_files;
mod scene_file;
pub mod systems;
mod tangents;
mod validate;

pub use atrium::{ATRIUM_FILE, atrium, atrium_glb};
pub use error::{Error, Problem, Result};
pub use glb_write::glb_container;
pub use gltf_load::{DEFAULT_LIGHT_CUTOFF, ImageLoading, LoadOptions};
pub use light_fields::{
    ColorRule, FacesLeftOut, LightField, Placement, RadiusRule, SpotRule, SurfaceSampler,
    ViewFaces, radius_from_intensity,
};
pub use lights::{DEFAULT_SPOT_INNER_FRACTION, LightRecord, Lights, default_spot_inner_angle};
pub use model::{
    Aabb, AlphaMode, DirectionalLight, Image, ImagePixels, ImageSource, Instance, Material, Mesh,
    Model, ModelCamera, ModelSummary, PixelFormat, PlacedLight, Primitive, Projection,
    PunctualKind, SkippedPunctualLight, TangentSource, TextureRef,
};
pub use presets::Preset;
pub use printable::printable;
pub use read_file::read_regular_file;
pub use replace_file::replace_file;
pub use replace_files::{ReplaceFilesError, check_replaceable, replace_files};
pub use scene_file::{LightPolicy, Scene, SkippedLight};
pub use validate::{ValidationReport, validate_file, validate_json_slice, validate_json_str};

/// Re-exported: the camera, grid and spot-cone types a [`Scene`] is made of.
pub use myriad_cluster_math::{Camera, ClusterGrid, DepthSlicing, OuterSlices, SpotCone};

/// Re-exported so callers use the same `glam` version as the crate's public types.
pub use myriad_cluster_math::glam;
