// Test pass: evaluates `shade_light` (common/lighting.wgsl) for many (light, surface) cases, so a
// test can compare each result with its Rust twin, `myriad_gpu::lighting_check::shade_light`, and
// feed it the inputs a rendered frame can hardly be made to produce exactly (a light right behind
// the point on the view ray, a zero or NaN normal, a light at the point).

@group(0) @binding(0) var<storage, read> cases: array<ShadeCase>;
@group(0) @binding(1) var<storage, read_write> radiance: array<vec4<f32>>;

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&cases)) {
        return;
    }
    let c = cases[i];
    let surface = Surface(c.position, c.normal, c.albedo, c.roughness, c.metallic);
    radiance[i] = vec4<f32>(shade_light(c.light, surface), 0.0);
}
