//! Every struct the GPU reads, in one place, laid out exactly as its WGSL twin in
//! `shaders/common/layout.wgsl`.
//!
//! Why one module: a field added on one side only is the classic silent GPU bug (every later
//! field shifts). `tests/layout.rs` parses the WGSL with naga and checks each struct's size and
//! every member offset against `std::mem::offset_of!` here, so such a mismatch fails the build's
//! tests instead of rendering garbage.
//!
//! Rules: `#[repr(C)]`, only `f32`/`u32` and arrays of them, WGSL `vec3` followed by a scalar
//! (the 16-byte alignment of `vec3` is filled by that scalar), sizes multiples of 16.

use bytemuck::{Pod, Zeroable};

/// Per-frame constants (`Frame` in WGSL; uniform buffer, group 0 binding 0 of every pass).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct FrameUniforms {
    /// Clip space from camera-relative world space, column major.
    pub clip_from_world_rel: [[f32; 4]; 4],
    /// Inverse of `clip_from_world_rel`.
    pub world_rel_from_clip: [[f32; 4]; 4],
    /// Camera position in world space; `w` unused.
    pub camera_position: [f32; 4],
    /// Render target size in pixels.
    pub target_size: [u32; 2],
    /// Number of lights in the light buffer.
    pub light_count: u32,
    /// Light count at the top of the heat-map ramp.
    pub heat_max: u32,
    /// Cluster grid X, Y, Z; `w` unused.
    pub grid_dims: [u32; 4],
    /// Camera near plane.
    pub camera_near: f32,
    /// `near / far` (`Camera::near_over_far`; 0 for an infinite far plane): with `camera_near`,
    /// what turns a stored depth into view depth. Not the far plane itself, which may be
    /// infinite, a value WGSL lets a shader compiler assume never occurs.
    pub camera_near_over_far: f32,
    /// Constant ambient term, as a fraction of albedo.
    pub ambient: f32,
    /// Exposure before tone mapping.
    pub exposure: f32,
}

/// One light, camera-relative (`Light` in WGSL; storage buffer).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    /// World position minus camera position.
    pub position: [f32; 3],
    /// Range: zero contribution at and beyond it.
    pub radius: f32,
    /// Linear colour times intensity.
    pub color: [f32; 3],
    /// The outer half angle θ as the squared chord `|axis − edge|² = 2(1 − cos θ)` between unit
    /// vectors ([`spot_chord2`]), in [0, 4]; [`GpuLight::POINT_CHORD2_OUTER`] for point lights.
    /// Not the cosine: near 1 an f32 cosine keeps few bits of a small angle (a 0.014° cone's
    /// is exactly 1), the chord its relative precision.
    pub spot_chord2_outer: f32,
    /// Unit spot axis (zero for point lights).
    pub spot_dir: [f32; 3],
    /// `1 / (spot_chord2_outer − the inner angle's squared chord)`, the falloff's slope (0 for
    /// point lights), computed in f64 and capped at `f32::MAX`.
    pub spot_ramp_scale: f32,
}

impl GpuLight {
    /// `spot_chord2_outer` of a point light: above every squared chord (at most 4), so every
    /// direction is lit.
    pub const POINT_CHORD2_OUTER: f32 = 8.0;
}

/// The squared chord `2(1 − cos θ) = 4 sin²(θ/2)` of a half angle θ, in f64: the shader's
/// measure of a spot's angle ([`GpuLight::spot_chord2_outer`]).
pub fn spot_chord2(angle: f64) -> f64 {
    let s = (angle / 2.0).sin();
    4.0 * s * s
}

/// Material constants (`Material` in WGSL; one uniform buffer per material).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MaterialUniforms {
    /// Linear base colour and alpha.
    pub base_color: [f32; 4],
    /// Emitted colour (kept for completeness; the G-buffer does not store it yet).
    pub emissive: [f32; 3],
    /// Perceptual roughness in [0, 1].
    pub roughness: f32,
    /// Metalness in [0, 1].
    pub metallic: f32,
    /// Alpha-test threshold (0 = none).
    pub alpha_cutoff: f32,
    /// Padding to 16 bytes.
    pub _pad0: u32,
    /// Padding to 16 bytes.
    pub _pad1: u32,
}

/// Parameters of the cluster-index check pass (`ClusterCheck` in WGSL).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ClusterCheckUniforms {
    /// Target size in pixels.
    pub target_size: [u32; 2],
    /// Number of samples.
    pub sample_count: u32,
    /// 1: the sample depths are stored depth-buffer values, turned into view depth on the GPU
    /// with `view_depth_from_ndc_depth` and `near_far` first (the shading passes' path); 0: they
    /// are view depths.
    pub from_stored_depth: u32,
    /// Grid X, Y, Z; `w` unused.
    pub grid_dims: [u32; 4],
    /// The camera's near plane and `near / far` (for `from_stored_depth`, as
    /// [`FrameUniforms::camera_near_over_far`]); `zw` unused.
    pub near_far: [f32; 4],
}

/// One case of the lighting check pass (`ShadeCase` in WGSL): a light and the surface point it
/// shades, both camera-relative, as `shade_light` in `shaders/common/lighting.wgsl` takes them
/// ([`crate::lighting_check`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ShadeCase {
    /// The light, as the renderer uploads it.
    pub light: GpuLight,
    /// The surface point: world position minus camera position.
    pub position: [f32; 3],
    /// Perceptual roughness in [0, 1].
    pub roughness: f32,
    /// Unit normal (any value: the shader must stay finite for a zero or NaN one).
    pub normal: [f32; 3],
    /// Metallic in [0, 1].
    pub metallic: f32,
    /// Linear albedo.
    pub albedo: [f32; 3],
    /// Padding to 16 bytes.
    pub _pad: f32,
}

/// One vertex of the scene geometry, world space (vertex buffer, not a WGSL struct: its layout
/// is [`Vertex::LAYOUT`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Vertex {
    /// World-space position.
    pub position: [f32; 3],
    /// World-space unit normal.
    pub normal: [f32; 3],
    /// Texture coordinate 0.
    pub uv: [f32; 2],
}

impl Vertex {
    const ATTRIBUTES: [wgpu::VertexAttribute; 3] =
        wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2];

    /// The vertex buffer layout the G-buffer and forward pipelines use.
    pub const LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Vertex>() as wgpu::BufferAddress,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &Self::ATTRIBUTES,
    };
}

/// The WGSL struct names and their Rust sizes, for the layout test.
pub const WGSL_STRUCTS: [(&str, usize); 5] = [
    ("Frame", std::mem::size_of::<FrameUniforms>()),
    ("Light", std::mem::size_of::<GpuLight>()),
    ("Material", std::mem::size_of::<MaterialUniforms>()),
    ("ClusterCheck", std::mem::size_of::<ClusterCheckUniforms>()),
    ("ShadeCase", std::mem::size_of::<ShadeCase>()),
];
