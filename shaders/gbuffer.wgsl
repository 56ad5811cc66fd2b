// G-buffer pass: opaque and alpha-tested geometry writes albedo, an octahedral-encoded normal and
// material parameters; position is reconstructed later from the depth buffer.

@group(0) @binding(0) var<uniform> frame: Frame;

@group(1) @binding(0) var<uniform> material: Material;
@group(1) @binding(1) var base_color_texture: texture_2d<f32>;
@group(1) @binding(2) var material_sampler: sampler;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) rel_position: vec3<f32>,
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    let rel = v.position - frame.camera_position.xyz;
    out.clip = frame.clip_from_world_rel * vec4<f32>(rel, 1.0);
    out.normal = v.normal;
    out.uv = v.uv;
    out.rel_position = rel;
    return out;
}

struct GBufferOut {
    @location(0) albedo: vec4<f32>,
    @location(1) normal: vec2<f32>,
    @location(2) material: vec4<f32>,
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front_facing: bool) -> GBufferOut {
    // Before the discard: derivatives (see `face_normal`).
    let face = face_normal(in.rel_position);
    // Materials without a texture bind a 1x1 white one, so the sample is unconditional.
    let color = material.base_color * textureSample(base_color_texture, material_sampler, in.uv);
    if (color.a < material.alpha_cutoff) {
        discard;
    }
    let n = surface_normal(in.normal, face, in.rel_position, front_facing);
    var out: GBufferOut;
    out.albedo = vec4<f32>(color.rgb, 1.0);
    out.normal = octahedral_encode(n);
    out.material = vec4<f32>(material.roughness, material.metallic, 0.0, 1.0);
    return out;
}
