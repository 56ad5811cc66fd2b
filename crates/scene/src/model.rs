//! [`Model`]: the geometry, materials, cameras and lights of a 3D scene, as the renderer and the
//! light fields need them.
//!
//! Why a type of our own rather than the `gltf` crate's document: a loaded model must be plain,
//! checked data (every index in range, every float finite, triangles only) so that nothing
//! downstream re-validates or panics, and the same type has to describe scenes that never were a
//! glTF file (the generated atrium is built as a `Model` first and only then written to `.glb`).
//!
//! Layout, following glTF:
//! * [`Mesh`]es hold [`Primitive`]s: local-space vertex arrays (positions, normals, UVs, tangents)
//!   and a triangle list, each with one material. Strips and fans are already converted to lists.
//! * [`Instance`]s place a mesh in the world (`world_from_local`), one per node that has a mesh,
//!   so a mesh used by several nodes is stored once and drawn several times.
//! * [`Material`]s are metallic-roughness PBR with an alpha mode; textures are [`TextureRef`]s into
//!   [`Model::images`], whose pixels are decoded only when asked for.
//! * Cameras ([`ModelCamera`]) keep their name and world pose; [`Model::camera`] turns one into a
//!   [`Camera`] for a given resolution.
//! * Point and spot lights are [`Lights`] columns in world space (what the assignment consumes),
//!   with [`PlacedLight`] rows saying where each came from. Directional lights cannot be
//!   clustered (they reach everything) and are kept apart in [`Model::directional_lights`].

use crate::lights::Lights;
use glam::{DVec3, Mat4, Vec2, Vec3, Vec4};
use myriad_cluster_math::Camera;

/// An axis-aligned box. [`Aabb::EMPTY`] (min = +∞, max = −∞) is the identity of [`Aabb::union`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box: contains nothing, and `EMPTY.union(b) == b`.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    /// The box spanning `min` to `max`.
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The smallest box holding every point of `points` ([`Aabb::EMPTY`] for none).
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Self {
        let mut b = Self::EMPTY;
        for p in points {
            b.extend(p);
        }
        b
    }

    /// Whether the box holds no point.
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    /// Grows the box to hold `p`.
    pub fn extend(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The smallest box holding both.
    pub fn union(self, other: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// `max - min` (negative for the empty box).
    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }

    /// The centre point.
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Whether `p` lies inside or on the boundary.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// The eight corners.
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            Vec3::new(a.x, a.y, a.z),
            Vec3::new(b.x, a.y, a.z),
            Vec3::new(a.x, b.y, a.z),
            Vec3::new(b.x, b.y, a.z),
            Vec3::new(a.x, a.y, b.z),
            Vec3::new(b.x, a.y, b.z),
            Vec3::new(a.x, b.y, b.z),
            Vec3::new(b.x, b.y, b.z),
        ]
    }
}

/// Where a primitive's tangents came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TangentSource {
    /// No tangents: the material has no normal map (or the primitive has no UVs to derive them).
    None,
    /// Read from the file's `TANGENT` attribute.
    File,
    /// Generated at load time by per-triangle accumulation (see `tangents.rs`).
    Generated,
}

/// One draw: vertex arrays in the mesh's local space and a triangle list.
///
/// Invariants of a loaded primitive: `normals` has one entry per position, `tex_coords` and
/// `tangents` are empty or have one entry per position, every index is `< positions.len()`,
/// `indices.len()` is a multiple of 3, and every value is finite.
#[derive(Clone, Debug, PartialEq)]
pub struct Primitive {
    /// Vertex positions (local space).
    pub positions: Vec<Vec3>,
    /// Unit vertex normals. Files without normals get flat normals (the glTF rule), which
    /// un-shares the vertices: three per triangle.
    pub normals: Vec<Vec3>,
    /// `TEXCOORD_0`, or empty. Other UV sets are not loaded.
    pub tex_coords: Vec<Vec2>,
    /// Tangents `xyz` with the bitangent sign in `w` (±1), or empty; see [`Primitive::tangent_source`].
    pub tangents: Vec<Vec4>,
    /// Where [`Primitive::tangents`] came from.
    pub tangent_source: TangentSource,
    /// Triangle list: three vertex indices per triangle, counter-clockwise front faces.
    pub indices: Vec<u32>,
    /// Index into [`Model::materials`], or `None` for glTF's default material.
    pub material: Option<usize>,
    /// Bounds of `positions` (local space).
    pub bounds: Aabb,
}

impl Primitive {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Triangle `t`'s three local-space corners. Panics if `t >= triangle_count()`.
    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        let i = &self.indices[3 * t..3 * t + 3];
        [
            self.positions[i[0] as usize],
            self.positions[i[1] as usize],
            self.positions[i[2] as usize],
        ]
    }
}

/// A mesh: primitives drawn together wherever an [`Instance`] places the mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// The name in the file, if any.
    pub name: Option<String>,
    /// The triangle primitives (points and lines are not loaded).
    pub primitives: Vec<Primitive>,
}

impl Mesh {
    /// Triangles of one drawing of this mesh.
    pub fn triangle_count(&self) -> usize {
        self.primitives.iter().map(Primitive::triangle_count).sum()
    }

    /// Bounds of all primitives (local space).
    pub fn bounds(&self) -> Aabb {
        self.primitives
            .iter()
            .fold(Aabb::EMPTY, |b, p| b.union(p.bounds))
    }
}

/// One drawing of a mesh: a glTF node with a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// Index into [`Model::meshes`].
    pub mesh: usize,
    /// The node's world transform (its parents' transforms applied).
    pub world_from_local: Mat4,
    /// Index of the node in the file (or in the generator's numbering).
    pub node: usize,
    /// The node's name, if any.
    pub name: Option<String>,
}

/// How a material's alpha is used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored.
    Opaque,
    /// Fully opaque where alpha `>= cutoff`, else fully transparent.
    Mask {
        /// The threshold (glTF default 0.5).
        cutoff: f32,
    },
    /// Blended over what is behind: needs the forward pass, sorted back to front.
    Blend,
}

/// A material's use of a texture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureRef {
    /// Index into [`Model::images`].
    pub image: usize,
    /// Which UV set it is sampled with (only set 0 is loaded).
    pub tex_coord: u32,
}

/// A metallic-roughness PBR material (glTF's core material model).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// The name in the file, if any.
    pub name: Option<String>,
    /// Linear RGBA multiplier of the base colour.
    pub base_color_factor: Vec4,
    /// Base colour texture (sRGB), if any.
    pub base_color_texture: Option<TextureRef>,
    /// Metalness multiplier in [0, 1].
    pub metallic_factor: f32,
    /// Roughness multiplier in [0, 1].
    pub roughness_factor: f32,
    /// Metallic (blue) and roughness (green) texture, if any.
    pub metallic_roughness_texture: Option<TextureRef>,
    /// Tangent-space normal map, if any. Primitives using it get tangents.
    pub normal_texture: Option<TextureRef>,
    /// Scale of the normal map's x and y.
    pub normal_scale: f32,
    /// Linear emitted colour (with `KHR_materials_emissive_strength` applied).
    pub emissive_factor: Vec3,
    /// Emission texture, if any.
    pub emissive_texture: Option<TextureRef>,
    /// How alpha is used.
    pub alpha_mode: AlphaMode,
    /// Whether back faces are drawn (and lit with the flipped normal).
    pub double_sided: bool,
}

impl Default for Material {
    /// glTF's default material: white, fully metallic, fully rough, opaque, single-sided.
    fn default() -> Self {
        Self {
            name: None,
            base_color_factor: Vec4::ONE,
            base_color_texture: None,
            metallic_factor: 1.0,
            roughness_factor: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            emissive_factor: Vec3::ZERO,
            emissive_texture: None,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
        }
    }
}

/// Where an image's encoded bytes live.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ImageSource {
    /// A file next to the glTF file (the URI as written, percent-encoding included).
    Uri {
        /// The URI.
        uri: String,
        /// The declared MIME type, if any.
        mime_type: Option<String>,
    },
    /// A `data:` URI inside the JSON.
    DataUri {
        /// The MIME type in the URI, if any.
        mime_type: Option<String>,
        /// Length of the URI text.
        len: usize,
    },
    /// A buffer view (typical of `.glb`).
    BufferView {
        /// Index of the view in the file.
        view: usize,
        /// The declared MIME type.
        mime_type: String,
    },
}

/// Channel layout of decoded pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelFormat {
    /// 8-bit grey.
    R8,
    /// 8-bit grey and alpha.
    R8G8,
    /// 8-bit RGB.
    R8G8B8,
    /// 8-bit RGBA.
    R8G8B8A8,
    /// 16-bit grey.
    R16,
    /// 16-bit grey and alpha.
    R16G16,
    /// 16-bit RGB.
    R16G16B16,
    /// 16-bit RGBA.
    R16G16B16A16,
    /// 32-bit float RGB.
    R32G32B32Float,
    /// 32-bit float RGBA.
    R32G32B32A32Float,
}

/// Decoded pixels of an image, rows top to bottom, no padding.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImagePixels {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Channel layout.
    pub format: PixelFormat,
    /// The pixel bytes (little-endian for 16- and 32-bit channels).
    pub data: Vec<u8>,
}

/// An image used by textures.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// The name in the file, if any.
    pub name: Option<String>,
    /// Where its bytes live.
    pub source: ImageSource,
    /// The decoded pixels, or `None` when loaded with [`crate::ImageLoading::ReferencesOnly`].
    pub pixels: Option<ImagePixels>,
}

/// A camera's projection as the file gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Perspective projection.
    Perspective {
        /// Vertical field of view in radians, in (0, π).
        yfov: f32,
        /// Near plane distance (> 0).
        znear: f32,
        /// Far plane distance (> znear), or `None` for an infinite projection.
        zfar: Option<f32>,
        /// Width over height the author intended, if given. Ignored by [`ModelCamera::to_camera`],
        /// where the resolution decides the aspect (the vertical field of view is kept).
        aspect_ratio: Option<f32>,
    },
    /// Orthographic projection (cannot become a [`Camera`], which is perspective only).
    Orthographic {
        /// Half width of the view volume.
        xmag: f32,
        /// Half height of the view volume.
        ymag: f32,
        /// Near plane distance (>= 0).
        znear: f32,
        /// Far plane distance (> znear).
        zfar: f32,
    },
}

/// A camera placed in the world by a node.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelCamera {
    /// The camera's name, else its node's name, else `camera N` (N = camera index in the file).
    pub name: String,
    /// Index of the node that places it.
    pub node: usize,
    /// Eye position in world space.
    pub position: Vec3,
    /// Unit view direction in world space (the node's −Z).
    pub forward: Vec3,
    /// Unit up direction in world space (the node's +Y, made orthogonal to `forward`).
    pub up: Vec3,
    /// The projection.
    pub projection: Projection,
}

impl ModelCamera {
    /// This camera as a [`Camera`] rendering `width`×`height` pixels, or `None` for an
    /// orthographic camera. The vertical field of view is kept and the aspect follows the
    /// resolution. An infinite far plane (`zfar` absent) becomes `far_if_infinite`, which must
    /// be greater than `znear`.
    pub fn to_camera(&self, width: u32, height: u32, far_if_infinite: f32) -> Option<Camera> {
        match self.projection {
            Projection::Perspective {
                yfov, znear, zfar, ..
            } => Some(Camera {
                position: self.position,
                target: self.position + self.forward,
                up: self.up,
                fov_y: yfov,
                width,
                height,
                near: znear,
                far: zfar.unwrap_or(far_if_infinite),
            }),
            Projection::Orthographic { .. } => None,
        }
    }
}

/// What kind of punctual light a [`PlacedLight`] is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PunctualKind {
    /// Emits in all directions.
    Point,
    /// Emits in a cone; angles in radians from the axis.
    Spot {
        /// Where the falloff starts (stored in [`Lights::spot_inner_angle`]).
        inner_cone_angle: f32,
        /// Where the light ends (stored in [`Lights::spot_angle`]).
        outer_cone_angle: f32,
    },
}

/// Where one row of [`Model::lights`] came from.
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedLight {
    /// The light's name, else its node's name, if any.
    pub name: Option<String>,
    /// Index of the node that places it.
    pub node: usize,
    /// Index of the light in the file's `KHR_lights_punctual` array.
    pub light: usize,
    /// Point or spot.
    pub kind: PunctualKind,
    /// The file's `range`, if it gave one; otherwise the radius in [`Model::lights`] was derived
    /// from the intensity (see [`crate::radius_from_intensity`]).
    pub range: Option<f32>,
}

/// A `KHR_lights_punctual` light that a node places but the loader left out: its values cannot
/// make a light (a `range` that is not > 0, a negative or non-finite colour or intensity, a bad
/// cone angle, no range and zero intensity) or its node gives it no direction. One row per node
/// that places it, like [`PlacedLight`]; the same sentence is in [`Model::warnings`].
#[derive(Clone, Debug, PartialEq)]
pub struct SkippedPunctualLight {
    /// The light's name, else its node's name, if any.
    pub name: Option<String>,
    /// Index of the node that places it.
    pub node: usize,
    /// Index of the light in the file's `KHR_lights_punctual` array.
    pub light: usize,
    /// What is wrong with it.
    pub reason: String,
}

/// A directional light (sun): no position, reaches everything, so it is not clustered.
#[derive(Clone, Debug, PartialEq)]
pub struct DirectionalLight {
    /// The light's name, else its node's name, if any.
    pub name: Option<String>,
    /// Unit direction the light travels in (the node's −Z), world space.
    pub direction: Vec3,
    /// Linear colour.
    pub color: Vec3,
    /// Illuminance in lux.
    pub intensity: f32,
}

/// Geometry, materials, cameras and lights of a 3D scene: a loaded glTF file or a generated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// Where it came from (the file path, or a generator's name); errors and reports use it.
    pub origin: String,
    /// The meshes, in file order.
    pub meshes: Vec<Mesh>,
    /// Every drawing of a mesh, in scene-traversal order.
    pub instances: Vec<Instance>,
    /// The materials, in file order.
    pub materials: Vec<Material>,
    /// The images, in file order.
    pub images: Vec<Image>,
    /// The cameras placed by nodes, in scene-traversal order.
    pub cameras: Vec<ModelCamera>,
    /// Point and spot lights placed by nodes, world space, `source_index` = row number.
    pub lights: Lights,
    /// One row per light in [`Model::lights`]: where it came from.
    pub placed_lights: Vec<PlacedLight>,
    /// Directional lights placed by nodes.
    pub directional_lights: Vec<DirectionalLight>,
    /// Lights placed by nodes but left out as invalid (each also in [`Model::warnings`]).
    pub skipped_lights: Vec<SkippedPunctualLight>,
    /// Things the loader left out or changed, one sentence each (e.g. a primitive of lines).
    pub warnings: Vec<String>,
    /// The files the model is made of: the glTF file itself ([`Model::load`]), then the external
    /// buffer and image files its URIs name, resolved against its folder, in file order — the
    /// images whether or not this load decoded them. Empty for a generated model. A program that
    /// writes files must not write over any of them (`myriad render --out` once replaced a
    /// model's `heatmap.png` buffer with the heat map).
    pub files: Vec<std::path::PathBuf>,
}

impl Model {
    /// An empty model named `origin`.
    pub fn new(origin: impl Into<String>) -> Self {
        Self {
            origin: origin.into(),
            meshes: Vec::new(),
            instances: Vec::new(),
            materials: Vec::new(),
            images: Vec::new(),
            cameras: Vec::new(),
            lights: Lights::new(),
            placed_lights: Vec::new(),
            directional_lights: Vec::new(),
            skipped_lights: Vec::new(),
            warnings: Vec::new(),
            files: Vec::new(),
        }
    }

    /// Triangles as rendered: every instance counts its mesh's triangles.
    pub fn triangle_count(&self) -> usize {
        self.instances
            .iter()
            .map(|i| self.meshes[i.mesh].triangle_count())
            .sum()
    }

    /// Triangles stored (each mesh once, used or not).
    pub fn stored_triangle_count(&self) -> usize {
        self.meshes.iter().map(Mesh::triangle_count).sum()
    }

    /// Vertices stored (each mesh once).
    pub fn stored_vertex_count(&self) -> usize {
        self.meshes
            .iter()
            .flat_map(|m| &m.primitives)
            .map(|p| p.positions.len())
            .sum()
    }

    /// Number of primitives over all meshes.
    pub fn primitive_count(&self) -> usize {
        self.meshes.iter().map(|m| m.primitives.len()).sum()
    }

    /// World-space bounds of everything drawn: every vertex of every instance, transformed
    /// (exact, not a box of transformed boxes). [`Aabb::EMPTY`] when nothing is drawn. Lights and
    /// cameras are not included.
    pub fn bounds(&self) -> Aabb {
        let mut bounds = Aabb::EMPTY;
        for instance in &self.instances {
            let m = instance.world_from_local;
            for primitive in &self.meshes[instance.mesh].primitives {
                // Vertices that no triangle uses are not drawn and do not count.
                for &i in &primitive.indices {
                    bounds.extend(m.transform_point3(primitive.positions[i as usize]));
                }
            }
        }
        bounds
    }

    /// Every drawn triangle in world space, instance by instance, with its material.
    pub fn world_triangles(&self) -> impl Iterator<Item = ([Vec3; 3], Option<usize>)> + '_ {
        self.instances.iter().flat_map(move |instance| {
            let m = instance.world_from_local;
            self.meshes[instance.mesh]
                .primitives
                .iter()
                .flat_map(move |p| {
                    (0..p.triangle_count())
                        .map(move |t| (p.triangle(t).map(|v| m.transform_point3(v)), p.material))
                })
        })
    }

    /// Index of the first camera named `name`.
    pub fn camera_index(&self, name: &str) -> Option<usize> {
        self.cameras.iter().position(|c| c.name == name)
    }

    /// The cameras' names for a message: `Main, Gallery` (each made printable, see
    /// [`crate::printable()`]), or `none`. Every command that reports a camera name it did not
    /// find lists them this way.
    pub fn camera_names(&self) -> String {
        if self.cameras.is_empty() {
            return "none".to_string();
        }
        let names: Vec<_> = self
            .cameras
            .iter()
            .map(|c| crate::printable(&c.name))
            .collect();
        names.join(", ")
    }

    /// Camera `index` as a [`Camera`] at `width`×`height` (see [`ModelCamera::to_camera`]); an
    /// infinite far plane becomes the distance to the farthest corner of [`Model::bounds`]
    /// (plus 1%), at least `1000 × znear`, at most `f32::MAX`. `None` if there is no such camera or it is
    /// orthographic.
    pub fn camera(&self, index: usize, width: u32, height: u32) -> Option<Camera> {
        let c = self.cameras.get(index)?;
        let far = match c.projection {
            Projection::Perspective {
                znear, zfar: None, ..
            } => {
                let bounds = self.bounds();
                // In f64: corners near ±f32::MAX are finite but their distances overflow f32.
                let farthest = if bounds.is_empty() {
                    0.0
                } else {
                    bounds
                        .corners()
                        .iter()
                        .map(|&p| (p.as_dvec3() - c.position.as_dvec3()).length())
                        .fold(0.0f64, f64::max)
                };
                (1.01 * farthest)
                    .max(1000.0 * znear as f64)
                    .min(f32::MAX as f64) as f32
            }
            _ => 0.0, // unused: finite far or orthographic
        };
        c.to_camera(width, height, far)
    }

    /// Camera `index` if it is a perspective camera, else a view of the bounds
    /// ([`Model::view_of_bounds`]); the `String` names which. `None` only when neither exists
    /// (no such camera and nothing drawn). Every command that needs a model's view uses this, so
    /// they agree on what a model without a camera shows.
    pub fn camera_or_view(
        &self,
        index: usize,
        width: u32,
        height: u32,
    ) -> Option<(Camera, String)> {
        match self.camera(index, width, height) {
            Some(camera) => Some((camera, self.cameras[index].name.clone())),
            None => self.view_of_bounds(width, height).map(|camera| {
                // A model with no camera at all says so, rather than naming a camera 0 that
                // nobody asked for (audit).
                let why = if self.cameras.is_empty() {
                    "the model has no camera".to_string()
                } else if index < self.cameras.len() {
                    format!("camera {index} is orthographic")
                } else {
                    format!("camera {index} does not exist")
                };
                (camera, format!("a view down the bounds' long axis ({why})"))
            }),
        }
    }

    /// A view for a model without a (perspective) camera: from just inside one end of the
    /// bounds' longer horizontal axis, at a sixth of the height, looking down that axis slightly
    /// upwards (the `paper` preset's view of its courtyard), 60° vertical field of view. `None`
    /// when nothing is drawn. The far plane reaches past the far corner (in f64, clamped to
    /// `f32::MAX`).
    pub fn view_of_bounds(&self, width: u32, height: u32) -> Option<Camera> {
        let b = self.bounds();
        if b.is_empty() {
            return None;
        }
        // In f64: bounds spanning most of f32's range have a size that overflows f32.
        let (min, max) = (b.min.as_dvec3(), b.max.as_dvec3());
        let (size, c) = (max - min, 0.5 * (min + max));
        let eye_y = min.y + size.y / 6.0;
        let (position, target) = if size.x >= size.z {
            (
                DVec3::new(min.x + 0.05 * size.x, eye_y, c.z),
                DVec3::new(max.x, eye_y + 0.1 * size.y, c.z),
            )
        } else {
            (
                DVec3::new(c.x, eye_y, min.z + 0.05 * size.z),
                DVec3::new(c.x, eye_y + 0.1 * size.y, max.z),
            )
        };
        let (position, target) = (position.as_vec3(), target.as_vec3());
        let far = (1.1 * size.length()).clamp(1.0, f32::MAX as f64) as f32;
        Some(Camera::new(
            position,
            target,
            Vec3::Y,
            60.0,
            width,
            height,
            0.1,
            far,
        ))
    }

    /// Counts for reports: see [`ModelSummary`].
    pub fn summary(&self) -> ModelSummary {
        let count_alpha =
            |f: fn(&AlphaMode) -> bool| self.materials.iter().filter(|m| f(&m.alpha_mode)).count();
        ModelSummary {
            meshes: self.meshes.len(),
            primitives: self.primitive_count(),
            instances: self.instances.len(),
            triangles: self.triangle_count(),
            stored_triangles: self.stored_triangle_count(),
            stored_vertices: self.stored_vertex_count(),
            materials: self.materials.len(),
            blended_materials: count_alpha(|a| matches!(a, AlphaMode::Blend)),
            masked_materials: count_alpha(|a| matches!(a, AlphaMode::Mask { .. })),
            images: self.images.len(),
            point_lights: self
                .placed_lights
                .iter()
                .filter(|l| l.kind == PunctualKind::Point)
                .count(),
            spot_lights: self
                .placed_lights
                .iter()
                .filter(|l| matches!(l.kind, PunctualKind::Spot { .. }))
                .count(),
            directional_lights: self.directional_lights.len(),
            skipped_lights: self.skipped_lights.len(),
            cameras: self.cameras.iter().map(|c| c.name.clone()).collect(),
            bounds: self.bounds(),
        }
    }
}

/// Counts describing a [`Model`] (what `myriad info` prints).
#[derive(Clone, Debug, PartialEq)]
pub struct ModelSummary {
    /// Meshes stored.
    pub meshes: usize,
    /// Primitives over all meshes.
    pub primitives: usize,
    /// Mesh instances drawn.
    pub instances: usize,
    /// Triangles as rendered (instances counted).
    pub triangles: usize,
    /// Triangles stored (each mesh once).
    pub stored_triangles: usize,
    /// Vertices stored (each mesh once).
    pub stored_vertices: usize,
    /// Materials.
    pub materials: usize,
    /// Materials with [`AlphaMode::Blend`].
    pub blended_materials: usize,
    /// Materials with [`AlphaMode::Mask`].
    pub masked_materials: usize,
    /// Images.
    pub images: usize,
    /// Point lights placed.
    pub point_lights: usize,
    /// Spot lights placed.
    pub spot_lights: usize,
    /// Directional lights placed.
    pub directional_lights: usize,
    /// Lights placed but left out as invalid ([`Model::skipped_lights`]).
    pub skipped_lights: usize,
    /// Camera names, in traversal order.
    pub cameras: Vec<String>,
    /// World bounds of everything drawn.
    pub bounds: Aabb,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_quad() -> Primitive {
        let positions = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::Y,
            Vec3::splat(100.0), // unused by the triangles: must not count in bounds
        ];
        Primitive {
            bounds: Aabb::from_points(positions.iter().copied()),
            normals: vec![Vec3::Z; 5],
            positions,
            tex_coords: Vec::new(),
            tangents: Vec::new(),
            tangent_source: TangentSource::None,
            indices: vec![0, 1, 2, 0, 2, 3],
            material: None,
        }
    }

    #[test]
    fn counts_and_bounds_follow_instances() {
        let mut model = Model::new("test");
        model.meshes.push(Mesh {
            name: Some("quad".into()),
            primitives: vec![unit_quad()],
        });
        assert_eq!(model.bounds(), Aabb::EMPTY);
        assert!(model.bounds().is_empty());
        for (node, x) in [(0, 0.0), (1, 5.0), (2, -3.0)] {
            model.instances.push(Instance {
                mesh: 0,
                world_from_local: Mat4::from_translation(Vec3::new(x, 0.0, 2.0)),
                node,
                name: None,
            });
        }
        assert_eq!(model.triangle_count(), 6);
        assert_eq!(model.stored_triangle_count(), 2);
        assert_eq!(model.stored_vertex_count(), 5);
        let b = model.bounds();
        assert_eq!(b.min, Vec3::new(-3.0, 0.0, 2.0));
        assert_eq!(b.max, Vec3::new(6.0, 1.0, 2.0));
        assert_eq!(model.world_triangles().count(), 6);
        let (first, material) = model.world_triangles().next().unwrap();
        assert_eq!(first[1], Vec3::new(1.0, 0.0, 2.0));
        assert_eq!(material, None);
        let s = model.summary();
        assert_eq!((s.meshes, s.instances, s.triangles), (1, 3, 6));
    }

    /// A model drawing the unit quad once per transform.
    fn quads_at(transforms: &[Mat4]) -> Model {
        let mut model = Model::new("test");
        model.meshes.push(Mesh {
            name: None,
            primitives: vec![unit_quad()],
        });
        for (node, &world_from_local) in transforms.iter().enumerate() {
            model.instances.push(Instance {
                mesh: 0,
                world_from_local,
                node,
                name: None,
            });
        }
        model
    }

    #[test]
    fn a_model_without_a_camera_is_viewed_down_its_long_axis() {
        assert!(Model::new("empty").camera_or_view(0, 8, 4).is_none());
        // A courtyard 30 long in x, 12 high, 15 deep.
        let wall = |z: f32| {
            Mat4::from_translation(Vec3::new(-15.0, 0.0, z))
                * Mat4::from_scale(Vec3::new(30.0, 12.0, 1.0))
        };
        let model = quads_at(&[wall(-7.5), wall(7.5)]);
        let b = model.bounds();
        let (c, name) = model.camera_or_view(0, 800, 400).unwrap();
        assert!(name.ends_with("(the model has no camera)"), "{name}");
        assert!(b.contains(c.position));
        assert!(c.target.x > c.position.x + 20.0);
        assert!(c.far > b.size().length());
        assert_eq!((c.width, c.height), (800, 400));
        // Bounds whose size overflows f32 still give a finite camera inside them.
        let huge = quads_at(&[
            Mat4::from_translation(Vec3::splat(-3.0e38)),
            Mat4::from_translation(Vec3::splat(3.0e38)),
        ]);
        assert!(!huge.bounds().size().is_finite());
        let c = huge.view_of_bounds(8, 4).unwrap();
        assert!(c.position.is_finite() && c.target.is_finite());
        assert!(huge.bounds().contains(c.position));
        assert_eq!(c.far, f32::MAX);
    }

    #[test]
    fn aabb_union_contains_and_corners() {
        let a = Aabb::new(Vec3::ZERO, Vec3::ONE);
        assert_eq!(Aabb::EMPTY.union(a), a);
        assert!(a.contains(Vec3::splat(0.5)) && !a.contains(Vec3::splat(1.5)));
        assert_eq!(a.corners().len(), 8);
        assert_eq!(Aabb::from_points(a.corners()), a);
        assert_eq!(a.center(), Vec3::splat(0.5));
    }

    #[test]
    fn cameras_convert_with_the_resolution_and_a_finite_far() {
        let mut model = quads_at(&[Mat4::IDENTITY]);
        model.cameras.push(ModelCamera {
            name: "Infinite".into(),
            node: 1,
            position: Vec3::new(0.0, 0.0, 10.0),
            forward: Vec3::NEG_Z,
            up: Vec3::Y,
            projection: Projection::Perspective {
                yfov: 1.0,
                znear: 0.001,
                zfar: None,
                aspect_ratio: Some(1.5),
            },
        });
        model.cameras.push(ModelCamera {
            name: "Ortho".into(),
            node: 2,
            position: Vec3::ZERO,
            forward: Vec3::NEG_Z,
            up: Vec3::Y,
            projection: Projection::Orthographic {
                xmag: 1.0,
                ymag: 1.0,
                znear: 0.0,
                zfar: 10.0,
            },
        });
        let c = model.camera(0, 640, 480).unwrap();
        assert_eq!((c.width, c.height, c.fov_y, c.near), (640, 480, 1.0, 0.001));
        // Farthest drawn corner: (1, 1, 0) from (0, 0, 10).
        let farthest = Vec3::new(1.0, 1.0, -10.0).length();
        assert!((c.far - 1.01 * farthest).abs() < 1e-4, "{}", c.far);
        assert_eq!(c.target, Vec3::new(0.0, 0.0, 9.0));
        assert_eq!(model.camera(1, 640, 480), None);
        assert_eq!(model.camera(2, 640, 480), None);
        assert_eq!(model.camera_index("Ortho"), Some(1));
    }

    /// A perspective camera named `name` at `position` looking along `forward`, with no far plane.
    fn infinite_camera(name: &str, position: Vec3, forward: Vec3) -> ModelCamera {
        ModelCamera {
            name: name.into(),
            node: 0,
            position,
            forward,
            up: Vec3::Y,
            projection: Projection::Perspective {
                yfov: 1.0,
                znear: 0.001,
                zfar: None,
                aspect_ratio: None,
            },
        }
    }

    #[test]
    fn a_box_inverted_along_any_one_axis_is_empty() {
        assert!(!Aabb::new(Vec3::ZERO, Vec3::ONE).is_empty());
        // A single point is a box that holds it.
        assert!(!Aabb::new(Vec3::ONE, Vec3::ONE).is_empty());
        for axis in 0..3 {
            let mut max = Vec3::ONE;
            max[axis] = -1.0;
            let b = Aabb::new(Vec3::ZERO, max);
            assert!(b.is_empty(), "inverted along axis {axis}: {b:?}");
        }
    }

    #[test]
    fn the_centre_is_halfway_between_the_corners() {
        let b = Aabb::new(Vec3::new(2.0, -4.0, 1.0), Vec3::new(6.0, 0.0, 1.0));
        assert_eq!(b.center(), Vec3::new(4.0, -2.0, 1.0));
    }

    #[test]
    fn an_infinite_far_plane_reaches_just_past_the_farthest_corner_from_the_camera() {
        // The quad spans (0..1, 0..1, 0); seen from (3, 0, 0) its farthest corner is (0, 1, 0).
        let mut model = quads_at(&[Mat4::IDENTITY]);
        model.cameras.push(infinite_camera(
            "Side",
            Vec3::new(3.0, 0.0, 0.0),
            Vec3::NEG_X,
        ));
        let c = model.camera(0, 64, 64).unwrap();
        let farthest = Vec3::new(-3.0, 1.0, 0.0).length();
        assert!((c.far - 1.01 * farthest).abs() < 1e-5, "{}", c.far);
    }

    #[test]
    fn cameras_are_found_by_name_the_first_of_equal_names_winning() {
        let mut model = Model::new("test");
        for name in ["A", "B", "A"] {
            model
                .cameras
                .push(infinite_camera(name, Vec3::ZERO, Vec3::NEG_Z));
        }
        assert_eq!(model.camera_index("A"), Some(0));
        assert_eq!(model.camera_index("B"), Some(1));
        assert_eq!(model.camera_index("C"), None);
    }

    #[test]
    fn the_view_without_a_camera_says_whether_the_camera_is_orthographic_or_missing() {
        let mut model = quads_at(&[Mat4::IDENTITY]);
        model.cameras.push(ModelCamera {
            name: "Ortho".into(),
            node: 1,
            position: Vec3::new(0.0, 0.0, 5.0),
            forward: Vec3::NEG_Z,
            up: Vec3::Y,
            projection: Projection::Orthographic {
                xmag: 1.0,
                ymag: 1.0,
                znear: 0.0,
                zfar: 10.0,
            },
        });
        model.cameras.push(infinite_camera(
            "Persp",
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::NEG_Z,
        ));
        let view = model.view_of_bounds(64, 32).unwrap();
        let (c, why) = model.camera_or_view(0, 64, 32).unwrap();
        assert_eq!(c, view);
        assert!(why.contains("camera 0 is orthographic"), "{why}");
        let (c, why) = model.camera_or_view(5, 64, 32).unwrap();
        assert_eq!(c, view);
        assert!(why.contains("camera 5 does not exist"), "{why}");
        let (c, why) = model.camera_or_view(1, 64, 32).unwrap();
        assert_eq!(why, "Persp");
        assert_eq!(c.position, Vec3::new(0.0, 0.0, 5.0));
    }

    /// Asserts that `a` and `b` agree to within 1e-4 in every coordinate.
    fn assert_near(a: Vec3, b: Vec3) {
        assert!((a - b).abs().max_element() < 1e-4, "{a} is not {b}");
    }

    #[test]
    fn the_view_of_the_bounds_stands_inside_the_near_end_of_the_long_axis_at_a_sixth_of_the_height()
    {
        // Two 30 × 12 quads at z = 3 and z = 9: bounds (2, 1, 3)..(32, 13, 9), long in x.
        let x_long = quads_at(&[3.0, 9.0].map(|z| {
            Mat4::from_translation(Vec3::new(2.0, 1.0, z))
                * Mat4::from_scale(Vec3::new(30.0, 12.0, 1.0))
        }));
        let size = Vec3::new(30.0, 12.0, 6.0);
        let c = x_long.view_of_bounds(64, 32).unwrap();
        // 5% of the length in from the low end, a sixth of the height up, centred across.
        assert_near(c.position, Vec3::new(2.0 + 1.5, 1.0 + 2.0, 6.0));
        // Towards the far end, rising by a tenth of the height.
        assert_near(c.target, Vec3::new(32.0, 3.0 + 1.2, 6.0));
        assert!((c.far - 1.1 * size.length()).abs() < 1e-4, "{}", c.far);

        // Two 6 × 12 quads at z = 2 and z = 32: bounds (3, 1, 2)..(9, 13, 32), long in z.
        let z_long = quads_at(&[2.0, 32.0].map(|z| {
            Mat4::from_translation(Vec3::new(3.0, 1.0, z))
                * Mat4::from_scale(Vec3::new(6.0, 12.0, 1.0))
        }));
        let c = z_long.view_of_bounds(64, 32).unwrap();
        assert_near(c.position, Vec3::new(6.0, 3.0, 2.0 + 1.5));
        assert_near(c.target, Vec3::new(6.0, 3.0 + 1.2, 32.0));
    }

    #[test]
    fn the_summary_counts_primitives_and_each_kind_of_placed_light() {
        let mut model = quads_at(&[Mat4::IDENTITY]);
        model.meshes.push(Mesh {
            name: None,
            primitives: vec![unit_quad(), unit_quad()],
        });
        let placed = |kind| PlacedLight {
            name: None,
            node: 0,
            light: 0,
            kind,
            range: None,
        };
        let spot = PunctualKind::Spot {
            inner_cone_angle: 0.1,
            outer_cone_angle: 0.2,
        };
        model.placed_lights = vec![placed(spot), placed(PunctualKind::Point), placed(spot)];
        assert_eq!(model.primitive_count(), 3);
        let s = model.summary();
        assert_eq!(s.primitives, 3);
        assert_eq!((s.point_lights, s.spot_lights), (1, 2));
    }
}
