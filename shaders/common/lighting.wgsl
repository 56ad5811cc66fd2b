// Lambert + Blinn-Phong for one point or spot light, and the tone map. Every shading pass
// (clustered, tiled, brute force, forward) calls `shade_light`, so they differ only in which
// lights they visit.

// False for scenes without spot lights: the spot cone code is compiled out of the pipeline.
override HAS_SPOTS: bool = true;

// True when the target stores what the shader writes as it is, with no sRGB encoding on the way
// (an 8- or 10-bit UNORM format such as an engine's `Bgra8Unorm` swap chain): the shader encodes
// sRGB itself, as an sRGB target would in hardware. False for sRGB targets and for float targets,
// which get linear values.
override ENCODE_SRGB: bool = false;

// Distance falloff: inverse square (softened by 1 m² so it stays finite at the light) times a
// window that is 1 at the light and exactly 0 at and beyond `radius` (Karis, "Real Shading in
// Unreal Engine 4", 2013). A light the assignment left out of a cluster (it cannot reach it)
// therefore contributes exactly nothing.
fn distance_falloff(dist2: f32, radius: f32) -> f32 {
    let x = dist2 / (radius * radius);
    let window = max(1.0 - x * x, 0.0);
    return window * window / (dist2 + 1.0);
}

// Angular falloff of a spot: exactly 0 outside the outer cone, 1 inside the inner cone, and
// between them the usual ramp in the cosine, squared. The angle is measured by the squared chord
// between the unit axis and the unit direction to the point, |axis - dir|² = 2 (1 - cos angle):
// a cosine near 1 keeps only a few bits of a small angle in f32 (a 0.014° cone rounds to cos 1),
// where the chord keeps its relative precision, so a narrow spot's edge lies where the
// assignment's cone test puts it and its ramp still reaches full strength.
fn spot_falloff(light: Light, to_point: vec3<f32>) -> f32 {
    if (!HAS_SPOTS || light.spot_chord2_outer > 4.5) {
        return 1.0;
    }
    let chord = light.spot_dir - to_point;
    let chord2 = dot(chord, chord);
    // Negated so that a NaN direction lights nothing.
    if (!(chord2 < light.spot_chord2_outer)) {
        return 0.0;
    }
    let t = min((light.spot_chord2_outer - chord2) * light.spot_ramp_scale, 1.0);
    return t * t;
}

struct Surface {
    // Camera-relative world position.
    position: vec3<f32>,
    normal: vec3<f32>,
    albedo: vec3<f32>,
    roughness: f32,
    metallic: f32,
}

fn shininess(roughness: f32) -> f32 {
    let a = max(roughness * roughness, 0.02);
    return clamp(2.0 / (a * a) - 2.0, 1.0, 4096.0);
}

// Radiance from one light reflected toward the camera (at the origin of camera-relative space).
// Its Rust twin is `myriad_gpu::lighting_check::shade_light`; `crates/gpu/tests/lighting.rs` runs
// this one in a compute pass and compares the two.
fn shade_light(light: Light, s: Surface) -> vec3<f32> {
    let to_light = light.position - s.position;
    let dist2 = dot(to_light, to_light);
    if (dist2 >= light.radius * light.radius) {
        return vec3<f32>(0.0);
    }
    let dist = sqrt(dist2);
    let l = to_light / max(dist, 1e-20);
    let n_dot_l = dot(s.normal, l);
    // Negated so that a NaN normal lights nothing rather than turning the pixel NaN.
    if (!(n_dot_l > 0.0)) {
        return vec3<f32>(0.0);
    }
    let attenuation = distance_falloff(dist2, light.radius) * spot_falloff(light, -l);
    let v = normalize(-s.position);
    // l + v is zero when the light sits right behind the point as the camera sees it (a normal
    // facing away from the camera, at a silhouette): no highlight then, rather than a NaN.
    let halfway = l + v;
    let h = halfway * inverseSqrt(max(dot(halfway, halfway), 1e-30));
    let spec_strength = mix(0.04, 1.0, s.metallic);
    let specular = spec_strength * pow(max(dot(s.normal, h), 0.0), shininess(s.roughness));
    let diffuse = s.albedo * (1.0 - s.metallic);
    let spec_color = mix(vec3<f32>(1.0), s.albedo, s.metallic) * specular;
    return light.color * attenuation * n_dot_l * (diffuse + spec_color);
}

// Exposure and a smooth shoulder; linear, `to_target` encodes it for the target.
fn tone_map(c: vec3<f32>, exposure: f32) -> vec3<f32> {
    return vec3<f32>(1.0) - exp(-c * exposure);
}

// A linear colour as the target wants it written (see `ENCODE_SRGB`).
fn to_target(linear: vec3<f32>) -> vec3<f32> {
    if (ENCODE_SRGB) {
        return linear_to_srgb(linear);
    }
    return linear;
}

// A colour meant as sRGB bytes (the heat map's ramp) as the target wants it written.
fn srgb_to_target(c: vec3<f32>) -> vec3<f32> {
    if (ENCODE_SRGB) {
        return c;
    }
    return srgb_to_linear(c);
}

// Blue -> cyan -> green -> yellow -> red ramp for t in [0, 1] (the heat map and its legend; the
// CPU legend in `legend.rs` uses the same stops).
fn heat_ramp(t: f32) -> vec3<f32> {
    let x = clamp(t, 0.0, 1.0) * 4.0;
    let c0 = vec3<f32>(0.0, 0.0, 0.5);
    let c1 = vec3<f32>(0.0, 0.6, 1.0);
    let c2 = vec3<f32>(0.0, 0.9, 0.2);
    let c3 = vec3<f32>(1.0, 0.9, 0.0);
    let c4 = vec3<f32>(0.9, 0.0, 0.0);
    if (x < 1.0) {
        return mix(c0, c1, x);
    }
    if (x < 2.0) {
        return mix(c1, c2, x - 1.0);
    }
    if (x < 3.0) {
        return mix(c2, c3, x - 2.0);
    }
    return mix(c3, c4, min(x - 3.0, 1.0));
}

// Inverse of the sRGB transfer function: a colour meant as sRGB bytes, written to an sRGB target.
fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(high, low, c <= vec3<f32>(0.04045));
}

// The sRGB transfer function (what an sRGB target applies on write), on values clamped to [0, 1].
fn linear_to_srgb(linear: vec3<f32>) -> vec3<f32> {
    let c = clamp(linear, vec3<f32>(0.0), vec3<f32>(1.0));
    let low = c * 12.92;
    let high = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(high, low, c <= vec3<f32>(0.0031308));
}
