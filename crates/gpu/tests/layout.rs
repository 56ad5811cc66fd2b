//! CPU-only: each GPU-visible struct in `layout.rs` has the size and member offsets naga computes
//! for its WGSL twin in `shaders/common/layout.wgsl`.

use myriad_gpu::layout::{
    ClusterCheckUniforms, FrameUniforms, GpuLight, MaterialUniforms, ShadeCase, WGSL_STRUCTS,
};
use myriad_gpu::shaders::COMMON;
use std::mem::{offset_of, size_of};

fn wgsl_struct(module: &naga::Module, name: &str) -> (u32, Vec<(String, u32)>) {
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(name)
            && let naga::TypeInner::Struct { members, span } = &ty.inner
        {
            return (
                *span,
                members
                    .iter()
                    .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                    .collect(),
            );
        }
    }
    panic!("struct {name} not found in layout.wgsl");
}

fn module() -> naga::Module {
    let (name, source) = COMMON[0];
    assert_eq!(name, "common/layout.wgsl");
    naga::front::wgsl::parse_str(source).expect("layout.wgsl parses")
}

macro_rules! rust_offsets {
    ($ty:ty: $($field:ident),+) => {
        vec![$((stringify!($field).to_string(), offset_of!($ty, $field) as u32)),+]
    };
}

#[test]
fn structs_match_naga_layout() {
    let module = module();
    type Offsets = Vec<(String, u32)>;
    let cases: Vec<(&str, usize, Offsets)> = vec![
        (
            "Frame",
            size_of::<FrameUniforms>(),
            rust_offsets!(FrameUniforms: clip_from_world_rel, world_rel_from_clip, camera_position, target_size,
                light_count, heat_max, grid_dims, camera_near, camera_near_over_far, ambient, exposure),
        ),
        (
            "Light",
            size_of::<GpuLight>(),
            rust_offsets!(GpuLight: position, radius, color, spot_chord2_outer, spot_dir, spot_ramp_scale),
        ),
        (
            "Material",
            size_of::<MaterialUniforms>(),
            rust_offsets!(MaterialUniforms: base_color, emissive, roughness, metallic, alpha_cutoff, _pad0, _pad1),
        ),
        (
            "ClusterCheck",
            size_of::<ClusterCheckUniforms>(),
            rust_offsets!(ClusterCheckUniforms: target_size, sample_count, from_stored_depth, grid_dims, near_far),
        ),
        (
            "ShadeCase",
            size_of::<ShadeCase>(),
            rust_offsets!(ShadeCase: light, position, roughness, normal, metallic, albedo, _pad),
        ),
    ];
    assert_eq!(
        cases.len(),
        WGSL_STRUCTS.len(),
        "every listed struct is checked"
    );
    for (name, size, rust) in cases {
        let (span, wgsl) = wgsl_struct(&module, name);
        assert_eq!(
            span as usize, size,
            "{name}: WGSL size {span}, Rust size {size}"
        );
        assert_eq!(
            wgsl, rust,
            "{name}: member names/offsets differ (WGSL left, Rust right)"
        );
        assert_eq!(size % 16, 0, "{name}: size {size} is not a multiple of 16");
    }
    for (name, size) in WGSL_STRUCTS {
        assert_eq!(wgsl_struct(&module, name).0 as usize, size);
    }
}

#[test]
fn the_check_sees_a_shifted_field() {
    // The comparison can fail: insert a field in the WGSL and the offsets move.
    let source = COMMON[0]
        .1
        .replace("    radius: f32,\n", "    radius: f32,\n    extra: f32,\n");
    let module = naga::front::wgsl::parse_str(&source).unwrap();
    let (_, wgsl) = wgsl_struct(&module, "Light");
    let rust = rust_offsets!(GpuLight: position, radius, color, spot_chord2_outer, spot_dir, spot_ramp_scale);
    assert_ne!(wgsl, rust);
}
