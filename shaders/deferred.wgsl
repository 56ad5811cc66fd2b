// Full-screen deferred shading. One shader, three light-selection strategies chosen by the
// pipeline constant MODE:
//   0 = light lists: the pixel's cluster (clustered shading; with a one-slice grid this is 2D
//       tiled shading) and only that cluster's lights;
//   1 = brute force: every light for every pixel (the baseline and the reference image).
// HEAT_MAP = true writes the number of lights evaluated at each pixel as a colour ramp instead
// (the paper's Figure 4).

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var gbuffer_albedo: texture_2d<f32>;
@group(0) @binding(2) var gbuffer_normal: texture_2d<f32>;
@group(0) @binding(3) var gbuffer_material: texture_2d<f32>;
@group(0) @binding(4) var gbuffer_depth: texture_depth_2d;

@group(1) @binding(0) var<storage, read> lights: array<Light>;
@group(1) @binding(1) var<storage, read> cluster_offsets: array<u32>;
@group(1) @binding(2) var<storage, read> cluster_counts: array<u32>;
@group(1) @binding(3) var<storage, read> light_indices: array<u32>;
@group(1) @binding(4) var<storage, read> slice_edges: array<f32>;

override MODE: u32 = 0u;
override HEAT_MAP: bool = false;

const BACKGROUND: vec3<f32> = vec3<f32>(0.02, 0.02, 0.03);

@vertex
fn vs_fullscreen(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    // One triangle covering the screen: (-1,-1), (3,-1), (-1,3).
    let x = f32((index << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(index & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) frag_coord: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<u32>(frag_coord.xy);
    let depth = textureLoad(gbuffer_depth, pixel, 0);
    // Reversed Z (`Camera::clip_from_view`): the buffer clears to 0, the far plane.
    if (depth <= 0.0) {
        if (HEAT_MAP) {
            return vec4<f32>(srgb_to_target(heat_ramp(0.0)), 1.0);
        }
        return vec4<f32>(to_target(BACKGROUND), 1.0);
    }
    // The shaded point is the pixel's ray at the view depth that also picks its cluster.
    let point = pixel_point(frag_coord.xy, depth, frame);
    let view_depth = point.view_depth;

    var s: Surface;
    s.position = point.position;
    s.normal = octahedral_decode(textureLoad(gbuffer_normal, pixel, 0).xy);
    s.albedo = textureLoad(gbuffer_albedo, pixel, 0).rgb;
    let params = textureLoad(gbuffer_material, pixel, 0);
    s.roughness = params.x;
    s.metallic = params.y;

    var color = frame.ambient * s.albedo;
    var evaluated = 0u;
    if (MODE == 1u) {
        evaluated = frame.light_count;
        if (!HEAT_MAP) {
            for (var i = 0u; i < frame.light_count; i++) {
                color += shade_light(lights[i], s);
            }
        }
    } else {
        let cluster = cluster_of_pixel(pixel, view_depth, frame.target_size, frame.grid_dims.xyz);
        let start = cluster_offsets[cluster];
        evaluated = cluster_counts[cluster];
        if (!HEAT_MAP) {
            for (var i = 0u; i < evaluated; i++) {
                color += shade_light(lights[light_indices[start + i]], s);
            }
        }
    }
    if (HEAT_MAP) {
        let t = f32(evaluated) / f32(max(frame.heat_max, 1u));
        return vec4<f32>(srgb_to_target(heat_ramp(t)), 1.0);
    }
    return vec4<f32>(to_target(tone_map(color, frame.exposure)), 1.0);
}
