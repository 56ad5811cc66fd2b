// GPU-visible structs shared by every pass. Their Rust twins live in `crates/gpu/src/layout.rs`,
// and a test checks sizes and member offsets of both against naga's layouter.

// Per-frame constants (uniform buffer, group 0 binding 0 in every pass).
struct Frame {
    // Clip space from camera-relative world space (world position minus camera position).
    clip_from_world_rel: mat4x4<f32>,
    // Inverse of `clip_from_world_rel`: the deferred pass unprojects near-plane points with it
    // (pixel rays; see deferred.wgsl for why not the stored depth).
    world_rel_from_clip: mat4x4<f32>,
    // Camera position in world space (xyz); w unused.
    camera_position: vec4<f32>,
    // Render target size in pixels.
    target_size: vec2<u32>,
    // Number of lights in the light buffer.
    light_count: u32,
    // Light count that maps to the top of the heat-map ramp.
    heat_max: u32,
    // Cluster grid: tiles across, tiles down, depth slices; w unused.
    grid_dims: vec4<u32>,
    // Camera near plane, and near over far (0 for an infinite far plane): the depth buffer's
    // range.
    camera_near: f32,
    camera_near_over_far: f32,
    // Constant ambient term, as a fraction of albedo.
    ambient: f32,
    // Exposure applied before tone mapping.
    exposure: f32,
}

// One light, camera-relative (storage buffer, read only).
struct Light {
    // Position minus camera position.
    position: vec3<f32>,
    // Range: the contribution is exactly zero at and beyond this distance.
    radius: f32,
    // Linear colour times intensity.
    color: vec3<f32>,
    // The cone's edge as a squared chord: |axis - edge direction|² = 2 (1 - cos outer angle), in
    // [0, 4]; 8 for point lights (every direction lit).
    spot_chord2_outer: f32,
    // Unit spot axis (zero for point lights).
    spot_dir: vec3<f32>,
    // 1 / (spot_chord2_outer - the inner angle's squared chord): the falloff's slope.
    spot_ramp_scale: f32,
}

// Material constants (uniform buffer, one per material).
struct Material {
    base_color: vec4<f32>,
    emissive: vec3<f32>,
    roughness: f32,
    metallic: f32,
    // Fragments with alpha below this are discarded (0 = no alpha test).
    alpha_cutoff: f32,
    _pad0: u32,
    _pad1: u32,
}

// Parameters of the cluster-index check (`cluster_index_check.wgsl`, a test pass).
struct ClusterCheck {
    target_size: vec2<u32>,
    sample_count: u32,
    from_stored_depth: u32,
    grid_dims: vec4<u32>,
    near_far: vec4<f32>,
}

// One case of the lighting check pass (`lighting_check.wgsl`): a light and the surface point it
// shades, camera-relative. Its Rust twin is `ShadeCase`.
struct ShadeCase {
    light: Light,
    position: vec3<f32>,
    roughness: f32,
    normal: vec3<f32>,
    metallic: f32,
    albedo: vec3<f32>,
    _pad: f32,
}

// One scene vertex, world space (vertex buffer of the G-buffer and forward passes; its Rust twin
// is `Vertex`, whose attribute layout `Vertex::LAYOUT` names these locations).
struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}
