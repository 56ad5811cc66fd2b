// Clustered forward shading of alpha-blended geometry, drawn back to front over the deferred
// image with depth testing (no depth writes) against the G-buffer depth. It reads the same light
// lists as the deferred pass and selects lights with the same MODE constant.

@group(0) @binding(0) var<uniform> frame: Frame;

@group(1) @binding(0) var<storage, read> lights: array<Light>;
@group(1) @binding(1) var<storage, read> cluster_offsets: array<u32>;
@group(1) @binding(2) var<storage, read> cluster_counts: array<u32>;
@group(1) @binding(3) var<storage, read> light_indices: array<u32>;
@group(1) @binding(4) var<storage, read> slice_edges: array<f32>;

@group(2) @binding(0) var<uniform> material: Material;
@group(2) @binding(1) var base_color_texture: texture_2d<f32>;
@group(2) @binding(2) var material_sampler: sampler;

override MODE: u32 = 0u;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) rel_position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    let rel = v.position - frame.camera_position.xyz;
    out.clip = frame.clip_from_world_rel * vec4<f32>(rel, 1.0);
    out.rel_position = rel;
    out.normal = v.normal;
    out.uv = v.uv;
    return out;
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front_facing: bool) -> @location(0) vec4<f32> {
    let face = face_normal(in.rel_position);
    let base = material.base_color * textureSample(base_color_texture, material_sampler, in.uv);
    // The shaded point is the pixel's ray at the fragment's own depth, as deferred shading
    // rebuilds it from the G-buffer's (`pixel_point`): the point whose depth picks the cluster.
    let point = pixel_point(in.clip.xy, in.clip.z, frame);
    var s: Surface;
    s.position = point.position;
    s.normal = surface_normal(in.normal, face, point.position, front_facing);
    s.albedo = base.rgb;
    s.roughness = material.roughness;
    s.metallic = material.metallic;

    var color = frame.ambient * s.albedo;
    if (MODE == 1u) {
        for (var i = 0u; i < frame.light_count; i++) {
            color += shade_light(lights[i], s);
        }
    } else {
        let pixel = vec2<u32>(in.clip.xy);
        let cluster = cluster_of_pixel(pixel, point.view_depth, frame.target_size, frame.grid_dims.xyz);
        let start = cluster_offsets[cluster];
        let count = cluster_counts[cluster];
        for (var i = 0u; i < count; i++) {
            color += shade_light(lights[light_indices[start + i]], s);
        }
    }
    return vec4<f32>(to_target(tone_map(color, frame.exposure)), base.a);
}
