//! Runs the shaders' `shade_light` (`shaders/common/lighting.wgsl`) in a compute pass over many
//! (light, surface) cases, and its Rust twin [`shade_light`], so tests can compare the GPU's
//! lighting with the CPU's case by case — including inputs a rendered frame can hardly be made to
//! hit exactly (a light right behind the point on the view ray, a zero or NaN normal, a light at
//! the point, a surface on the light's range).

use crate::layout::ShadeCase;
use crate::out_of_memory::{buffer_init, catching};
use crate::readback::map_and_read;
use crate::shaders::PassShader;
use crate::{GpuContext, GpuError};
use glam::Vec3;

/// The radiance `shade_light` returns on the GPU for each case. Blocks until done. No cases, or
/// more than one dispatch holds, is a [`GpuError::InvalidInput`].
pub fn gpu_shade_light(ctx: &GpuContext, cases: &[ShadeCase]) -> Result<Vec<[f32; 3]>, GpuError> {
    let device = &ctx.device;
    let groups = (cases.len() as u64).div_ceil(64);
    let max_groups = u64::from(device.limits().max_compute_workgroups_per_dimension);
    if cases.is_empty() || groups > max_groups {
        return Err(GpuError::InvalidInput(format!(
            "{} cases: need 1 to {} (64 per workgroup, {max_groups} workgroups)",
            cases.len(),
            64 * max_groups
        )));
    }
    let input = buffer_init(
        device,
        "lighting check cases",
        bytemuck::cast_slice(cases),
        wgpu::BufferUsages::STORAGE,
    )?;
    let bytes = cases.len() as u64 * 16;
    let buffer = |label: &'static str, usage| {
        let what = || format!("the {label} buffer ({bytes} bytes)");
        catching(device, what, || {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage,
                mapped_at_creation: false,
            })
        })
    };
    let out = buffer(
        "lighting check radiance",
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    )?;
    let readback = buffer(
        "lighting check readback",
        wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
    )?;
    let module = PassShader::LightingCheck.module(device);
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("lighting check"),
        layout: None,
        module: &module,
        entry_point: Some("cs_main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("lighting check"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: input.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: out.as_entire_binding(),
            },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(groups as u32, 1, 1);
    }
    encoder.copy_buffer_to_buffer(&out, 0, &readback, 0, bytes);
    ctx.queue.submit([encoder.finish()]);
    let data = map_and_read(ctx, &readback)?;
    let texels: &[[f32; 4]] = bytemuck::cast_slice(&data);
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
