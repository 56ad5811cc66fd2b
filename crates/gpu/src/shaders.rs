//! The WGSL sources, compiled into the crate, and how a pass's module is put together.
//!
//! WGSL has no `#include`, so each pass's module is the shared helpers of `shaders/common/` it
//! needs ([`PassShader::helpers`], in [`COMMON`] order) followed by the pass's own file. A helper
//! may rely on globals its includer declares (`cluster.wgsl` reads `slice_edges`). Keeping the text in `shaders/` (not in
//! Rust strings) lets editors, naga's CLI and the validation test see real `.wgsl` files.
//! `build.rs` says where that folder is (`MYRIAD_SHADER_DIR`): the workspace's top-level
//! `shaders/`, reached through the crate's own `shaders` link so the packaged crate carries it.

/// The shared helpers, in the order they are prepended: structs first, then functions.
pub const COMMON: [(&str, &str); 5] = [
    (
        "common/layout.wgsl",
        include_str!(concat!(env!("MYRIAD_SHADER_DIR"), "/common/layout.wgsl")),
    ),
    (
        "common/cluster.wgsl",
        include_str!(concat!(env!("MYRIAD_SHADER_DIR"), "/common/cluster.wgsl")),
    ),
    (
        "common/octahedral.wgsl",
        include_str!(concat!(
            env!("MYRIAD_SHADER_DIR"),
            "/common/octahedral.wgsl"
        )),
    ),
    (
        "common/lighting.wgsl",
        include_str!(concat!(env!("MYRIAD_SHADER_DIR"), "/common/lighting.wgsl")),
    ),
    (
        "common/surface_normal.wgsl",
        include_str!(concat!(
            env!("MYRIAD_SHADER_DIR"),
            "/common/surface_normal.wgsl"
        )),
    ),
];

/// One pass's own WGSL file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PassShader {
    /// `gbuffer.wgsl`.
    GBuffer,
    /// `deferred.wgsl` (clustered, tiled, brute force, heat map).
    Deferred,
    /// `forward.wgsl`.
    Forward,
    /// `cluster_index_check.wgsl` (test pass).
    ClusterIndexCheck,
    /// `lighting_check.wgsl` (test pass).
    LightingCheck,
}

impl PassShader {
    /// Every pass.
    pub const ALL: [PassShader; 5] = [
        PassShader::GBuffer,
        PassShader::Deferred,
        PassShader::Forward,
        PassShader::ClusterIndexCheck,
        PassShader::LightingCheck,
    ];

    /// File name under `shaders/`.
    pub fn file_name(self) -> &'static str {
        match self {
            PassShader::GBuffer => "gbuffer.wgsl",
            PassShader::Deferred => "deferred.wgsl",
            PassShader::Forward => "forward.wgsl",
            PassShader::ClusterIndexCheck => "cluster_index_check.wgsl",
            PassShader::LightingCheck => "lighting_check.wgsl",
        }
    }

    /// The pass file's own text.
    pub fn own_source(self) -> &'static str {
        match self {
            PassShader::GBuffer => {
                include_str!(concat!(env!("MYRIAD_SHADER_DIR"), "/gbuffer.wgsl"))
            }
            PassShader::Deferred => {
                include_str!(concat!(env!("MYRIAD_SHADER_DIR"), "/deferred.wgsl"))
            }
            PassShader::Forward => {
                include_str!(concat!(env!("MYRIAD_SHADER_DIR"), "/forward.wgsl"))
            }
            PassShader::ClusterIndexCheck => {
                include_str!(concat!(
                    env!("MYRIAD_SHADER_DIR"),
                    "/cluster_index_check.wgsl"
                ))
            }
            PassShader::LightingCheck => {
                include_str!(concat!(env!("MYRIAD_SHADER_DIR"), "/lighting_check.wgsl"))
            }
        }
    }

    /// Indices into [`COMMON`] of the helpers this pass includes.
    pub fn helpers(self) -> &'static [usize] {
        match self {
            PassShader::GBuffer => &[0, 2, 4],
            PassShader::Deferred => &[0, 1, 2, 3],
            PassShader::Forward => &[0, 1, 2, 3, 4],
            PassShader::ClusterIndexCheck => &[0, 1],
            PassShader::LightingCheck => &[0, 3],
        }
    }

    /// The whole module: the common helpers, then the pass.
    pub fn source(self) -> String {
        let mut text = String::new();
        for &(name, body) in self.helpers().iter().map(|&i| &COMMON[i]) {
            text.push_str("// ---- ");
            text.push_str(name);
            text.push('\n');
            text.push_str(body);
            text.push('\n');
        }
        text.push_str("// ---- ");
        text.push_str(self.file_name());
        text.push('\n');
        text.push_str(self.own_source());
        text
    }

    /// Compiles the module on `device`.
    pub fn module(self, device: &wgpu::Device) -> wgpu::ShaderModule {
        device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(self.file_name()),
            source: wgpu::ShaderSource::Wgsl(self.source().into()),
        })
    }
}
