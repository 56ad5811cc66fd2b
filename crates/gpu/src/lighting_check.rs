//! Runs the shaders' `shade_light` (`shaders/common/lighting.wgsl`) in a compute pass over many
//! (light, surface) cases, and its Rust twin [`shade_light`], so tests can compare the GPU's
//! lighting with the CPU's case by case — including inputs a rendered frame can hardly be made to
//! hit exactly (a light right behind the point on the view ray, a zero or NaN normal, a light at
//! the point, a surface on the light's range).

use crate::check_pass;
use crate::layout::ShadeCase;
use crate::out_of_memory::buffer_init;
use crate::shaders::PassShader;
use crate::{GpuContext, GpuError};
use glam::Vec3;

/// The radiance `shade_light` returns on the GPU for each case. Blocks until done. No cases, or
/// more than one dispatch or one storage binding holds, is a [`GpuError::InvalidInput`].
pub fn gpu_shade_light(ctx: &GpuContext, cases: &[ShadeCase]) -> Result<Vec<[f32; 3]>, GpuError> {
    let groups = check_pass::workgroups(ctx, cases.len(), "cases")?;
    check_pass::check_binding(ctx, std::mem::size_of_val(cases) as u64, "the cases")?;
    let input = buffer_init(
        &ctx.device,
        &ctx.queue,
        "lighting check cases",
        bytemuck::cast_slice(cases),
        wgpu::BufferUsages::STORAGE,
    )?;
    let bytes = cases.len() as u64 * 16;
    let data = check_pass::run(ctx, PassShader::LightingCheck, &[&input], bytes, groups)?;
    let texels: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&data);
    Ok(texels.iter().map(|t| [t[0], t[1], t[2]]).collect())
}

/// `shade_light` of `shaders/common/lighting.wgsl`, step by step in f32 (with the shader's spot
/// code compiled in): the radiance the light reflects from the surface toward the camera, at
/// the origin of camera-relative space. Exactly zero at and beyond the light's range, outside a
/// spot's cone, and on a surface facing away from the light or with a zero or NaN normal.
pub fn shade_light(case: &ShadeCase) -> [f32; 3] {
    let light = &case.light;
    let position = Vec3::from(case.position);
    let normal = Vec3::from(case.normal);
    let to_light = Vec3::from(light.position) - position;
    let dist2 = to_light.dot(to_light);
    if dist2 >= light.radius * light.radius {
        return [0.0; 3];
    }
    let dist = dist2.sqrt();
    let l = to_light / dist.max(1e-20);
    let n_dot_l = normal.dot(l);
    if !(n_dot_l > 0.0) {
        return [0.0; 3];
    }
    let attenuation = distance_falloff(dist2, light.radius) * spot_falloff(light, -l);
    let v = (-position).normalize();
    let halfway = l + v;
    let h = halfway * halfway.dot(halfway).max(1e-30).sqrt().recip();
    let spec_strength = lerp(0.04, 1.0, case.metallic);
    let specular = spec_strength * normal.dot(h).max(0.0).powf(shininess(case.roughness));
    let albedo = Vec3::from(case.albedo);
    let diffuse = albedo * (1.0 - case.metallic);
    let spec_color = Vec3::ONE.lerp(albedo, case.metallic) * specular;
    (Vec3::from(light.color) * attenuation * n_dot_l * (diffuse + spec_color)).to_array()
}

/// `distance_falloff` of `lighting.wgsl`.
fn distance_falloff(dist2: f32, radius: f32) -> f32 {
    let x = dist2 / (radius * radius);
    let window = (1.0 - x * x).max(0.0);
    window * window / (dist2 + 1.0)
}

/// `spot_falloff` of `lighting.wgsl`.
fn spot_falloff(light: &crate::layout::GpuLight, to_point: Vec3) -> f32 {
    if light.spot_chord2_outer > 4.5 {
        return 1.0;
    }
    let chord = Vec3::from(light.spot_dir) - to_point;
    let chord2 = chord.dot(chord);
    if !(chord2 < light.spot_chord2_outer) {
        return 0.0;
    }
    let t = ((light.spot_chord2_outer - chord2) * light.spot_ramp_scale).min(1.0);
    t * t
}

/// `shininess` of `lighting.wgsl`.
fn shininess(roughness: f32) -> f32 {
    let a = (roughness * roughness).max(0.02);
    (2.0 / (a * a) - 2.0).clamp(1.0, 4096.0)
}

/// WGSL's `mix`.
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}
