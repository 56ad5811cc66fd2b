//! Writing a [`Model`] as binary glTF (`.glb`): how the project's generated scenes become assets
//! that any glTF viewer opens and that [`Model::load`] reads back.
//!
//! Why a writer of our own (rather than building the `gltf` crate's JSON types): the output
//! must be **byte-for-byte reproducible** — `assets/atrium.glb` is committed, and a test
//! regenerates it and compares the bytes, so the asset cannot drift from the code. That needs a
//! fixed field order and f32 values written as their shortest round-trip decimals; small serde
//! structs declared here give both (serde_json writes `f32` fields with ryu's f32 formatting).
//!
//! What is written: meshes (positions with min/max, normals, `TEXCOORD_0` and tangents when
//! present, `u16` indices when they fit, else `u32`), one node per instance (its
//! `world_from_local` as a matrix, omitted when identity), materials' factors, alpha mode and
//! sidedness, cameras (a node each, oriented from position/forward/up) and point and spot
//! lights (`KHR_lights_punctual`, a node each; `range` only where [`PlacedLight::range`] is set).
//! Directional lights are written too. Every node is a root of the one scene. **Not written**:
//! textures and images (an error if a material uses one: this writer is for generated,
//! untextured scenes), and anything the loader drops (skins, animations).
//!
//! Layout: one buffer (the GLB binary chunk); one buffer view per accessor, each 4-byte
//! aligned; GLB chunks padded to 4 bytes (JSON with spaces, binary with zeros).

use crate::error::{Error, Result};
use crate::model::{AlphaMode, Model, PlacedLight, Projection, PunctualKind};
use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use serde::Serialize;
use std::path::Path;

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Root {
    asset: Asset,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    extensions_used: Vec<&'static str>,
    scene: u32,
    scenes: Vec<SceneNodes>,
    nodes: Vec<Node>,
    meshes: Vec<MeshJson>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    materials: Vec<MaterialJson>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    cameras: Vec<CameraJson>,
    accessors: Vec<Accessor>,
    buffer_views: Vec<BufferView>,
    buffers: Vec<Buffer>,
    #[serde(skip_serializing_if = "Option::is_none")]
    extensions: Option<RootExtensions>,
}

#[derive(Serialize)]
struct Asset {
    version: &'static str,
    generator: &'static str,
}

#[derive(Serialize)]
struct SceneNodes {
    nodes: Vec<u32>,
}

#[derive(Serialize, Default)]
#[serde(rename_all = "camelCase")]
struct Node {
    #[serde(skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    mesh: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    camera: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    matrix: Option<[f32; 16]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    extensions: Option<NodeExtensions>,
}

#[derive(Serialize)]
struct NodeExtensions {
    #[serde(rename = "KHR_lights_punctual")]
    lights: LightRef,
}

#[derive(Serialize)]
struct LightRef {
    light: u32,
}

#[derive(Serialize)]
struct RootExtensions {
    #[serde(rename = "KHR_lights_punctual")]
    lights: LightList,
}

#[derive(Serialize)]
struct LightList {
    lights: Vec<LightJson>,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct LightJson {
    #[serde(skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    #[serde(rename = "type")]
    kind: &'static str,
    color: [f32; 3],
    intensity: f32,
    #[serde(skip_serializing_if = "Option::is_none")]
    range: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    spot: Option<SpotJson>,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct SpotJson {
    inner_cone_angle: f32,
    outer_cone_angle: f32,
}

#[derive(Serialize)]
struct MeshJson {
    #[serde(skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    primitives: Vec<PrimitiveJson>,
}

#[derive(Serialize)]
struct PrimitiveJson {
    attributes: Attributes,
    indices: u32,
    #[serde(skip_serializing_if = "Option::is_none")]
    material: Option<u32>,
}

#[derive(Serialize)]
struct Attributes {
    #[serde(rename = "POSITION")]
    position: u32,
    #[serde(rename = "NORMAL")]
    normal: u32,
    #[serde(rename = "TEXCOORD_0", skip_serializing_if = "Option::is_none")]
    tex_coord: Option<u32>,
    #[serde(rename = "TANGENT", skip_serializing_if = "Option::is_none")]
    tangent: Option<u32>,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct MaterialJson {
    #[serde(skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    pbr_metallic_roughness: Pbr,
    #[serde(skip_serializing_if = "Option::is_none")]
    emissive_factor: Option<[f32; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    alpha_mode: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    alpha_cutoff: Option<f32>,
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    double_sided: bool,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Pbr {
    base_color_factor: [f32; 4],
    metallic_factor: f32,
    roughness_factor: f32,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct CameraJson {
    name: String,
    #[serde(rename = "type")]
    kind: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    perspective: Option<PerspectiveJson>,
    #[serde(skip_serializing_if = "Option::is_none")]
    orthographic: Option<OrthographicJson>,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct PerspectiveJson {
    #[serde(skip_serializing_if = "Option::is_none")]
    aspect_ratio: Option<f32>,
    yfov: f32,
    #[serde(skip_serializing_if = "Option::is_none")]
    zfar: Option<f32>,
    znear: f32,
}

#[derive(Serialize)]
struct OrthographicJson {
    xmag: f32,
    ymag: f32,
    zfar: f32,
    znear: f32,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Accessor {
    buffer_view: u32,
    component_type: u32,
    count: usize,
    #[serde(rename = "type")]
    kind: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    min: Option<[f32; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    max: Option<[f32; 3]>,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct BufferView {
    buffer: u32,
    byte_offset: usize,
    byte_length: usize,
    target: u32,
}

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Buffer {
    byte_length: usize,
}

/// Accumulates the binary chunk and its views and accessors.
#[derive(Default)]
struct Bin {
    bytes: Vec<u8>,
    views: Vec<BufferView>,
    accessors: Vec<Accessor>,
}

impl Bin {
    /// Appends `data` as a new view and accessor; returns the accessor index.
    fn push(
        &mut self,
        data: &[u8],
        target: u32,
        component_type: u32,
        count: usize,
        kind: &'static str,
        bounds: Option<(Vec3, Vec3)>,
    ) -> u32 {
        let view = self.views.len() as u32;
        self.views.push(BufferView {
            buffer: 0,
            byte_offset: self.bytes.len(),
            byte_length: data.len(),
            target,
        });
        self.bytes.extend_from_slice(data);
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        self.accessors.push(Accessor {
            buffer_view: view,
            component_type,
            count,
            kind,
            min: bounds.map(|b| b.0.to_array()),
            max: bounds.map(|b| b.1.to_array()),
        });
        self.accessors.len() as u32 - 1
    }

    fn floats(&mut self, values: &[f32], count: usize, kind: &'static str) -> u32 {
        self.push(&le_bytes(values), ARRAY_BUFFER, FLOAT, count, kind, None)
    }
}

fn le_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// A matrix whose −Z axis is `forward`, +Y is `up` (orthonormalised) and origin `position`: the
/// node transform glTF cameras and spot lights look along.
fn looking(position: Vec3, forward: Vec3) -> Mat4 {
    let z = -forward.normalize();
    let x = z.any_orthonormal_vector();
    let y = z.cross(x);
    Mat4::from_cols(
        x.extend(0.0),
        y.extend(0.0),
        z.extend(0.0),
        position.extend(1.0),
    )
}

fn camera_matrix(position: Vec3, forward: Vec3, up: Vec3) -> Mat4 {
    let right = forward.cross(up).normalize();
    let up = right.cross(forward).normalize();
    let rotation = Mat3::from_cols(right, up, -forward);
    Mat4::from_cols(
        rotation.x_axis.extend(0.0),
        rotation.y_axis.extend(0.0),
        rotation.z_axis.extend(0.0),
        position.extend(1.0),
    )
}

fn flatten2(v: &[Vec2]) -> Vec<f32> {
    v.iter().flat_map(|p| p.to_array()).collect()
}

fn flatten3(v: &[Vec3]) -> Vec<f32> {
    v.iter().flat_map(|p| p.to_array()).collect()
}

fn flatten4(v: &[Vec4]) -> Vec<f32> {
    v.iter().flat_map(|p| p.to_array()).collect()
}

impl Model {
    /// The model as GLB bytes (see the module docs for what is written). Deterministic: the same
    /// model always gives the same bytes. Errors with [`Error::Gltf`] (origin: the model's
    /// origin) when a material uses a texture, or the model breaks its own invariants (a
    /// primitive's attribute lengths differ, an instance names a missing mesh).
    pub fn to_glb(&self) -> Result<Vec<u8>> {
        self.glb_bytes().map_err(|message| Error::Gltf {
            origin: self.origin.clone(),
            message: format!("cannot write GLB: {message}"),
        })
    }

    /// Writes [`Model::to_glb`] to `path`, replacing it only once complete
    /// ([`crate::replace_file()`]). Errors name the file.
    pub fn save_glb(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let bytes = self.to_glb()?;
        crate::replace_file(path, &bytes).map_err(|source| Error::GltfWrite {
            path: path.to_path_buf(),
            source,
        })
    }

    fn glb_bytes(&self) -> Result<Vec<u8>, String> {
        let mut bin = Bin::default();
        let mut materials = Vec::with_capacity(self.materials.len());
        for (i, m) in self.materials.iter().enumerate() {
            let textured = [
                m.base_color_texture,
                m.metallic_roughness_texture,
                m.normal_texture,
                m.emissive_texture,
            ]
            .iter()
            .any(Option::is_some);
            if textured {
                return Err(format!(
                    "materials[{i}] uses a texture; this writer writes untextured scenes only"
                ));
            }
            let (alpha_mode, alpha_cutoff) = match m.alpha_mode {
                AlphaMode::Opaque => (None, None),
                AlphaMode::Mask { cutoff } => (Some("MASK"), Some(cutoff)),
                AlphaMode::Blend => (Some("BLEND"), None),
            };
            materials.push(MaterialJson {
                name: m.name.clone(),
                pbr_metallic_roughness: Pbr {
                    base_color_factor: m.base_color_factor.to_array(),
                    metallic_factor: m.metallic_factor,
                    roughness_factor: m.roughness_factor,
                },
                emissive_factor: (m.emissive_factor != Vec3::ZERO)
                    .then(|| m.emissive_factor.to_array()),
                alpha_mode,
                alpha_cutoff,
                double_sided: m.double_sided,
            });
        }
        let mut meshes = Vec::with_capacity(self.meshes.len());
        for (mi, mesh) in self.meshes.iter().enumerate() {
            let mut primitives = Vec::with_capacity(mesh.primitives.len());
            for (pi, p) in mesh.primitives.iter().enumerate() {
                let n = p.positions.len();
                let lengths_ok = p.normals.len() == n
                    && (p.tex_coords.is_empty() || p.tex_coords.len() == n)
                    && (p.tangents.is_empty() || p.tangents.len() == n)
                    && p.indices.iter().all(|&i| (i as usize) < n)
                    && p.indices.len().is_multiple_of(3)
                    && p.material.is_none_or(|m| m < self.materials.len());
                if !lengths_ok {
                    return Err(format!(
                        "meshes[{mi}] primitives[{pi}]: attribute lengths, indices or material \
                         are inconsistent"
                    ));
                }
                let bounds = (
                    p.positions.iter().copied().fold(Vec3::INFINITY, Vec3::min),
                    p.positions
                        .iter()
                        .copied()
                        .fold(Vec3::NEG_INFINITY, Vec3::max),
                );
                let position = bin.push(
                    &le_bytes(&flatten3(&p.positions)),
                    ARRAY_BUFFER,
                    FLOAT,
                    n,
                    "VEC3",
                    Some(bounds),
                );
                let normal = bin.floats(&flatten3(&p.normals), n, "VEC3");
                let tex_coord = (!p.tex_coords.is_empty())
                    .then(|| bin.floats(&flatten2(&p.tex_coords), n, "VEC2"));
                let tangent =
                    (!p.tangents.is_empty()).then(|| bin.floats(&flatten4(&p.tangents), n, "VEC4"));
                let indices = if n <= u16::MAX as usize + 1 {
                    let bytes: Vec<u8> = p
                        .indices
                        .iter()
                        .flat_map(|&i| (i as u16).to_le_bytes())
                        .collect();
                    bin.push(
                        &bytes,
                        ELEMENT_ARRAY_BUFFER,
                        UNSIGNED_SHORT,
                        p.indices.len(),
                        "SCALAR",
                        None,
                    )
                } else {
                    let bytes: Vec<u8> = p.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
                    bin.push(
                        &bytes,
                        ELEMENT_ARRAY_BUFFER,
                        UNSIGNED_INT,
                        p.indices.len(),
                        "SCALAR",
                        None,
                    )
                };
                primitives.push(PrimitiveJson {
                    attributes: Attributes {
                        position,
                        normal,
                        tex_coord,
                        tangent,
                    },
                    indices,
                    material: p.material.map(|m| m as u32),
                });
            }
            meshes.push(MeshJson {
                name: mesh.name.clone(),
                primitives,
            });
        }
        let mut nodes = Vec::new();
        for instance in &self.instances {
            if instance.mesh >= self.meshes.len() {
                return Err(format!(
                    "an instance draws mesh {}, which does not exist",
                    instance.mesh
                ));
            }
            nodes.push(Node {
                name: instance.name.clone(),
                mesh: Some(instance.mesh as u32),
                matrix: (instance.world_from_local != Mat4::IDENTITY)
                    .then(|| instance.world_from_local.to_cols_array()),
                ..Node::default()
            });
        }
        let mut cameras = Vec::with_capacity(self.cameras.len());
        for (i, c) in self.cameras.iter().enumerate() {
            let (perspective, orthographic, kind) = match c.projection {
                Projection::Perspective {
                    yfov,
                    znear,
                    zfar,
                    aspect_ratio,
                } => (
                    Some(PerspectiveJson {
                        aspect_ratio,
                        yfov,
                        zfar,
                        znear,
                    }),
                    None,
                    "perspective",
                ),
                Projection::Orthographic {
                    xmag,
                    ymag,
                    znear,
                    zfar,
                } => (
                    None,
                    Some(OrthographicJson {
                        xmag,
                        ymag,
                        zfar,
                        znear,
                    }),
                    "orthographic",
                ),
            };
            cameras.push(CameraJson {
                name: c.name.clone(),
                kind,
                perspective,
                orthographic,
            });
            nodes.push(Node {
                name: Some(c.name.clone()),
                camera: Some(i as u32),
                matrix: Some(camera_matrix(c.position, c.forward, c.up).to_cols_array()),
                ..Node::default()
            });
        }
        if self.placed_lights.len() != self.lights.len() {
            return Err("lights and placed_lights have different lengths".into());
        }
        let mut lights = Vec::with_capacity(self.lights.len());
        for (i, (light, placed)) in self.lights.iter().zip(&self.placed_lights).enumerate() {
            let PlacedLight {
                name, range, kind, ..
            } = placed;
            let (kind_name, spot, matrix) = match (kind, light.spot) {
                (PunctualKind::Point, None) => {
                    ("point", None, Mat4::from_translation(light.position))
                }
                // The cone as the light columns hold it (what is drawn and assigned), where
                // `placed_lights` only records what the source said: an edited column is written.
                (PunctualKind::Spot { .. }, Some(cone)) => (
                    "spot",
                    Some(SpotJson {
                        inner_cone_angle: light.spot_inner_angle,
                        outer_cone_angle: cone.angle,
                    }),
                    looking(light.position, cone.direction),
                ),
                _ => {
                    return Err(format!(
                        "lights[{i}]: its kind and its spot columns disagree"
                    ));
                }
            };
            lights.push(LightJson {
                name: name.clone(),
                kind: kind_name,
                color: light.color.to_array(),
                intensity: light.intensity,
                range: *range,
                spot,
            });
            nodes.push(Node {
                name: name.clone(),
                matrix: Some(matrix.to_cols_array()),
                extensions: Some(NodeExtensions {
                    lights: LightRef { light: i as u32 },
                }),
                ..Node::default()
            });
        }
        for d in &self.directional_lights {
            nodes.push(Node {
                name: d.name.clone(),
                matrix: Some(looking(Vec3::ZERO, d.direction).to_cols_array()),
                extensions: Some(NodeExtensions {
                    lights: LightRef {
                        light: lights.len() as u32,
                    },
                }),
                ..Node::default()
            });
            lights.push(LightJson {
                name: d.name.clone(),
                kind: "directional",
                color: d.color.to_array(),
                intensity: d.intensity,
                range: None,
                spot: None,
            });
        }
        let has_lights = !lights.is_empty();
        let root = Root {
            asset: Asset {
                version: "2.0",
                generator: "myriad-scene",
            },
            extensions_used: if has_lights {
                vec!["KHR_lights_punctual"]
            } else {
                Vec::new()
            },
            scene: 0,
            scenes: vec![SceneNodes {
                nodes: (0..nodes.len() as u32).collect(),
            }],
            nodes,
            meshes,
            materials,
            cameras,
            accessors: std::mem::take(&mut bin.accessors),
            buffer_views: std::mem::take(&mut bin.views),
            buffers: vec![Buffer {
                byte_length: bin.bytes.len(),
            }],
            extensions: has_lights.then_some(RootExtensions {
                lights: LightList { lights },
            }),
        };
        let json = serde_json::to_vec(&root).map_err(|e| e.to_string())?;
        Ok(glb_container(json, bin.bytes))
    }
}

/// The GLB container: 12-byte header, JSON chunk (padded with spaces), binary chunk (padded
/// with zeros). Public for tools that edit a GLB's chunks and pack them again (the fuzz
/// harness's mutator).
pub fn glb_container(mut json: Vec<u8>, mut bin: Vec<u8>) -> Vec<u8> {
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lights::LightRecord;
    use crate::model::{Aabb, Instance, Material, Mesh, ModelCamera, Primitive, TangentSource};
    use crate::{LoadOptions, TextureRef};

    fn quad_model() -> Model {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let mut model = Model::new("quad");
        model.materials.push(Material {
            name: Some("glass".into()),
            base_color_factor: Vec4::new(0.2, 0.3, 0.4, 0.25),
            metallic_factor: 0.0,
            roughness_factor: 0.1,
            alpha_mode: AlphaMode::Blend,
            double_sided: true,
            ..Material::default()
        });
        model.meshes.push(Mesh {
            name: Some("quad".into()),
            primitives: vec![Primitive {
                bounds: Aabb::from_points(positions.iter().copied()),
                normals: vec![Vec3::Z; 4],
                tex_coords: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
                tangents: vec![Vec4::new(1.0, 0.0, 0.0, 1.0); 4],
                tangent_source: TangentSource::File,
                positions,
                indices: vec![0, 1, 2, 0, 2, 3],
                material: Some(0),
            }],
        });
        for (node, x) in [(0, 0.0), (1, 3.0)] {
            model.instances.push(Instance {
                mesh: 0,
                world_from_local: Mat4::from_translation(Vec3::new(x, 0.0, 0.0)),
                node,
                name: Some(format!("quad{node}")),
            });
        }
        model.cameras.push(ModelCamera {
            name: "Eye".into(),
            node: 2,
            position: Vec3::new(1.0, 2.0, 8.0),
            forward: Vec3::new(0.0, -0.6, -0.8),
            up: Vec3::new(0.0, 0.8, -0.6),
            projection: Projection::Perspective {
                yfov: 1.0,
                znear: 0.1,
                zfar: Some(40.0),
                aspect_ratio: None,
            },
        });
        model
            .lights
            .push(LightRecord::point(Vec3::new(0.5, 0.5, 1.0), 4.0).with_intensity(3.0));
        model.placed_lights.push(PlacedLight {
            name: Some("lamp".into()),
            node: 3,
            light: 0,
            kind: PunctualKind::Point,
            range: Some(4.0),
        });
        let down = Vec3::new(0.0, -1.0, 0.0);
        model.lights.push(
            LightRecord::point(Vec3::new(2.0, 5.0, 0.0), 9.0)
                .with_spot(down, 0.6)
                .with_spot_inner_angle(0.3)
                .with_source_index(1),
        );
        model.placed_lights.push(PlacedLight {
            name: Some("spot".into()),
            node: 4,
            light: 1,
            kind: PunctualKind::Spot {
                inner_cone_angle: 0.3,
                outer_cone_angle: 0.6,
            },
            range: Some(9.0),
        });
        model
            .directional_lights
            .push(crate::model::DirectionalLight {
                name: Some("sun".into()),
                direction: Vec3::new(0.0, -0.6, 0.8),
                color: Vec3::new(1.0, 0.9, 0.8),
                intensity: 5.0,
            });
        model
    }

    #[test]
    fn written_glb_reads_back() {
        let model = quad_model();
        let bytes = model.to_glb().unwrap();
        assert_eq!(&bytes[..4], b"glTF");
        assert_eq!(bytes.len() % 4, 0);
        assert_eq!(model.to_glb().unwrap(), bytes, "deterministic");
        let back =
            Model::from_gltf_slice(&bytes, "quad.glb", None, &LoadOptions::default()).unwrap();
        assert_eq!(back.meshes, model.meshes);
        assert_eq!(back.materials, model.materials);
        assert_eq!(back.instances.len(), 2);
        for (a, b) in back.instances.iter().zip(&model.instances) {
            assert_eq!(
                (a.mesh, &a.name, a.world_from_local),
                (b.mesh, &b.name, b.world_from_local)
            );
        }
        assert_eq!(back.cameras.len(), 1);
        let (a, b) = (&back.cameras[0], &model.cameras[0]);
        assert_eq!(
            (&a.name, a.position, a.projection),
            (&b.name, b.position, b.projection)
        );
        assert!((a.forward - b.forward).length() < 1e-6 && (a.up - b.up).length() < 1e-6);
        assert_eq!(back.lights.len(), 2);
        for i in 0..2 {
            let (a, b) = (back.lights.get(i), model.lights.get(i));
            assert_eq!(
                (a.position, a.radius, a.color, a.intensity),
                (b.position, b.radius, b.color, b.intensity)
            );
            match (a.spot, b.spot) {
                (Some(x), Some(y)) => {
                    assert!((x.direction - y.direction).length() < 1e-6);
                    assert_eq!(x.angle, y.angle);
                }
                (None, None) => {}
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(back.placed_lights[1].kind, model.placed_lights[1].kind);
        let (a, b) = (&back.directional_lights[0], &model.directional_lights[0]);
        assert_eq!(
            (&a.name, a.color, a.intensity),
            (&b.name, b.color, b.intensity)
        );
        assert!((a.direction - b.direction).length() < 1e-6);
    }

    #[test]
    fn textured_or_inconsistent_models_are_refused() {
        let mut model = quad_model();
        model.materials[0].normal_texture = Some(TextureRef {
            image: 0,
            tex_coord: 0,
        });
        let e = model.to_glb().unwrap_err().to_string();
        assert!(
            e.starts_with("quad: cannot write GLB: materials[0] uses a texture"),
            "{e}"
        );
        // An index one past the last vertex, a material one past the last.
        let mut model = quad_model();
        model.meshes[0].primitives[0].indices[0] = 4;
        let e = model.to_glb().unwrap_err().to_string();
        assert!(e.contains("meshes[0] primitives[0]"), "{e}");
        let mut model = quad_model();
        model.meshes[0].primitives[0].material = Some(1);
        let e = model.to_glb().unwrap_err().to_string();
        assert!(e.contains("meshes[0] primitives[0]"), "{e}");
    }

    /// The JSON chunk of a GLB.
    fn json_chunk(glb: &[u8]) -> serde_json::Value {
        let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        assert_eq!(&glb[16..20], b"JSON");
        serde_json::from_slice(&glb[20..20 + len]).unwrap()
    }

    #[test]
    fn nodes_are_named_and_buffer_views_are_four_byte_aligned() {
        let json = json_chunk(&quad_model().to_glb().unwrap());
        let names: Vec<&str> = json["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n["name"].as_str().unwrap())
            .collect();
        assert_eq!(names, ["quad0", "quad1", "Eye", "lamp", "spot", "sun"]);
        let views = json["bufferViews"].as_array().unwrap();
        assert!(views.len() >= 5);
        for view in views {
            assert_eq!(view["byteOffset"].as_u64().unwrap() % 4, 0, "{view}");
        }
    }

    #[test]
    fn indices_are_16_bit_up_to_65536_vertices_and_32_bit_above() {
        for (n, component_type) in [
            (4, UNSIGNED_SHORT),
            (65_536, UNSIGNED_SHORT),
            (65_537, UNSIGNED_INT),
        ] {
            let positions: Vec<Vec3> = (0..n)
                .map(|i| Vec3::new(i as f32, (i % 2) as f32, 0.0))
                .collect();
            let mut model = Model::new("strip");
            model.meshes.push(Mesh {
                name: None,
                primitives: vec![Primitive {
                    bounds: Aabb::from_points(positions.iter().copied()),
                    normals: vec![Vec3::Z; n],
                    tex_coords: Vec::new(),
                    tangents: Vec::new(),
                    tangent_source: TangentSource::None,
                    positions,
                    indices: vec![0, 1, n as u32 - 1],
                    material: None,
                }],
            });
            let glb = model.to_glb().unwrap();
            let json = json_chunk(&glb);
            let indices = json["meshes"][0]["primitives"][0]["indices"]
                .as_u64()
                .unwrap() as usize;
            assert_eq!(
                json["accessors"][indices]["componentType"], component_type,
                "{n}"
            );
            let back =
                Model::from_gltf_slice(&glb, "strip.glb", None, &LoadOptions::default()).unwrap();
            assert_eq!(back.meshes[0].primitives[0].indices, [0, 1, n as u32 - 1]);
        }
    }

    #[test]
    fn emissive_factors_are_written() {
        let mut model = quad_model();
        model.materials[0].emissive_factor = Vec3::new(1.0, 0.5, 0.0);
        let bytes = model.to_glb().unwrap();
        let back =
            Model::from_gltf_slice(&bytes, "quad.glb", None, &LoadOptions::default()).unwrap();
        assert_eq!(back.materials, model.materials);
    }

    #[test]
    fn save_glb_writes_the_bytes_of_to_glb() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("quad.glb");
        let model = quad_model();
        model.save_glb(&path).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), model.to_glb().unwrap());
    }
}
