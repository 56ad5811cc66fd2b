//! Bind group layouts and render pipelines, with the shader variants each frame needs.
//!
//! Variants are WGSL pipeline-overridable constants, not string edits: `MODE` (light lists or
//! every light), `HEAT_MAP`, and `HAS_SPOTS` (false compiles the spot-cone code out); and, per
//! output format, `ENCODE_SRGB` ([`encodes_srgb`] of the format). One renderer draws into
//! targets of any format it can (an engine's HDR view and its sRGB editor thumbnail share the
//! lights, lists and G-buffer), so the format is part of each final pass's key. Each
//! combination is built once, on first use, and cached — or ahead of the first frame that needs
//! it, through `Renderer::prepare`, since building one compiles shaders: the main job's brute-force
//! frame on llvmpipe encoded in 12.5 ms with its two pipelines built on the way and in 0.22 ms
//! with them prepared. An engine wants that at load time, not as a hitch in the frame where a
//! heat map or the first spot light appears.

use crate::layout::Vertex;
use crate::profiling::profile_span;
use crate::shaders::PassShader;
use crate::targets::{ALBEDO_FORMAT, DEPTH_FORMAT, MATERIAL_FORMAT, NORMAL_FORMAT};
use std::collections::HashMap;

/// Whether the shading passes encode sRGB themselves for a target of `format`: a UNORM format
/// without sRGB (an engine's `Bgra8Unorm` or `Rgb10a2Unorm` swap chain) stores what the shader
/// writes as it is, so written linear the image came out up to 74/255 too dark (audit). sRGB
/// formats encode in hardware; float formats (`Rgba16Float`, …) get linear values for the
/// engine's own post-processing. On a UNORM target the forward pass blends encoded values, as
/// any blending into such a target does.
pub fn encodes_srgb(format: wgpu::TextureFormat) -> bool {
    use wgpu::TextureFormat as F;
    !format.is_srgb()
        && !matches!(
            format,
            F::R16Float
                | F::Rg16Float
                | F::Rgba16Float
                | F::R32Float
                | F::Rg32Float
                | F::Rgba32Float
                | F::Rg11b10Ufloat
        )
}

/// The shaders' `ENCODE_SRGB` for a target of `format`.
fn encode_srgb_constant(format: wgpu::TextureFormat) -> f64 {
    f64::from(u8::from(encodes_srgb(format)))
}

/// Why the final passes cannot draw into textures of `format` on `device`, or `None` when they
/// can: the shading passes write a float colour and the forward pass blends it, so the format
/// must sample as float, be a render attachment and blend. Checked before any pipeline of the
/// format is built (one built for another format would be a wgpu validation error).
pub(crate) fn drawable_format(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
) -> Option<String> {
    let features = format.guaranteed_format_features(device.features());
    let float = matches!(
        format.sample_type(None, Some(device.features())),
        Some(wgpu::TextureSampleType::Float { .. })
    );
    let drawable = float
        && features
            .allowed_usages
            .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
        && features
            .flags
            .contains(wgpu::TextureFormatFeatureFlags::BLENDABLE);
    (!drawable).then(|| {
        format!(
            "the renderer cannot draw into {format:?}: it needs a float colour format that this \
             device can render to and blend (e.g. Rgba8UnormSrgb, Bgra8UnormSrgb, Rgba16Float)"
        )
    })
}

/// Which lights a pixel visits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ShadingMode {
    /// Only the lights of the pixel's cluster, from the uploaded lists: clustered shading, or 2D
    /// tiled shading when the grid has one depth slice.
    Lists,
    /// Every light for every pixel (the reference and the baseline).
    BruteForce,
}

impl ShadingMode {
    fn constant(self) -> f64 {
        match self {
            ShadingMode::Lists => 0.0,
            ShadingMode::BruteForce => 1.0,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct DeferredKey {
    format: wgpu::TextureFormat,
    mode: ShadingMode,
    heat_map: bool,
    has_spots: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct ForwardKey {
    format: wgpu::TextureFormat,
    mode: ShadingMode,
    has_spots: bool,
}

/// Layouts, modules and the pipeline cache.
#[derive(Debug)]
pub(crate) struct Pipelines {
    /// The format the renderer was made for: what [`crate::Renderer::prepare`] builds for.
    output_format: wgpu::TextureFormat,
    pub frame_layout: wgpu::BindGroupLayout,
    pub deferred_inputs_layout: wgpu::BindGroupLayout,
    pub lights_layout: wgpu::BindGroupLayout,
    pub material_layout: wgpu::BindGroupLayout,
    deferred_module: wgpu::ShaderModule,
    forward_module: wgpu::ShaderModule,
    pub gbuffer: wgpu::RenderPipeline,
    deferred: HashMap<DeferredKey, wgpu::RenderPipeline>,
    forward: HashMap<ForwardKey, wgpu::RenderPipeline>,
    /// Render pipelines built so far, the G-buffer's included.
    built: usize,
}

fn uniform_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn storage_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn texture_entry(binding: u32, sample_type: wgpu::TextureSampleType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

const UNFILTERED: wgpu::TextureSampleType = wgpu::TextureSampleType::Float { filterable: false };

fn color_target(
    format: wgpu::TextureFormat,
    blend: Option<wgpu::BlendState>,
) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend,
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// What differs between the renderer's pipelines; [`build_pipeline`] fills in the rest.
struct PipelineSpec<'a> {
    label: &'static str,
    bind_groups: &'a [Option<&'a wgpu::BindGroupLayout>],
    module: &'a wgpu::ShaderModule,
    vertex_entry: &'static str,
    vertex_buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    depth: Option<wgpu::DepthStencilState>,
    targets: &'a [Option<wgpu::ColorTargetState>],
    /// Pipeline-overridable constants of the fragment stage.
    constants: &'a [(&'a str, f64)],
}

fn build_pipeline(device: &wgpu::Device, spec: PipelineSpec<'_>) -> wgpu::RenderPipeline {
    // A span of its own: a frame that builds one shows where its hitch came from.
    profile_span!("build pipeline");
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(spec.label),
        bind_group_layouts: spec.bind_groups,
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(spec.label),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: spec.module,
            entry_point: Some(spec.vertex_entry),
            compilation_options: Default::default(),
            buffers: spec.vertex_buffers,
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: spec.depth,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: spec.module,
            entry_point: Some("fs_main"),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: spec.constants,
                zero_initialize_workgroup_memory: false,
            },
            targets: spec.targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// Depth-tested against the G-buffer depth (`Greater`: reversed Z, see
/// `Camera::clip_from_view`), writing it or not.
fn depth_test(write: bool) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(wgpu::CompareFunction::Greater),
        stencil: Default::default(),
        bias: Default::default(),
    })
}

impl Pipelines {
    /// The format the renderer was made for.
    pub fn output_format(&self) -> wgpu::TextureFormat {
        self.output_format
    }

    pub fn new(device: &wgpu::Device, output_format: wgpu::TextureFormat) -> Self {
        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frame"),
            entries: &[uniform_entry(0, vf)],
        });
        let deferred_inputs_layout =
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("deferred inputs"),
                entries: &[
                    uniform_entry(0, vf),
                    texture_entry(1, UNFILTERED),
                    texture_entry(2, UNFILTERED),
                    texture_entry(3, UNFILTERED),
                    texture_entry(4, wgpu::TextureSampleType::Depth),
                ],
            });
        let lights_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lights and lists"),
            entries: &[
                storage_entry(0),
                storage_entry(1),
                storage_entry(2),
                storage_entry(3),
                storage_entry(4),
            ],
        });
        let material_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("material"),
            entries: &[
                uniform_entry(0, wgpu::ShaderStages::FRAGMENT),
                texture_entry(1, wgpu::TextureSampleType::Float { filterable: true }),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let gbuffer_module = PassShader::GBuffer.module(device);
        let deferred_module = PassShader::Deferred.module(device);
        let forward_module = PassShader::Forward.module(device);

        let gbuffer = build_pipeline(
            device,
            PipelineSpec {
                label: "gbuffer",
                bind_groups: &[Some(&frame_layout), Some(&material_layout)],
                module: &gbuffer_module,
                vertex_entry: "vs_main",
                vertex_buffers: &[Some(Vertex::LAYOUT)],
                depth: depth_test(true),
                targets: &[
                    color_target(ALBEDO_FORMAT, None),
                    color_target(NORMAL_FORMAT, None),
                    color_target(MATERIAL_FORMAT, None),
                ],
                constants: &[],
            },
        );
        Self {
            output_format,
            frame_layout,
            deferred_inputs_layout,
            lights_layout,
            material_layout,
            deferred_module,
            forward_module,
            gbuffer,
            deferred: HashMap::new(),
            forward: HashMap::new(),
            built: 1,
        }
    }

    /// Render pipelines built so far, the G-buffer's included.
    pub fn built(&self) -> usize {
        self.built
    }

    /// The deferred pipeline for this combination, built on first use. `format` must be one
    /// [`drawable_format`] accepts.
    pub fn deferred(
        &mut self,
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
        mode: ShadingMode,
        heat_map: bool,
        has_spots: bool,
    ) -> &wgpu::RenderPipeline {
        let key = DeferredKey {
            format,
            mode,
            heat_map,
            has_spots,
        };
        if !self.deferred.contains_key(&key) {
            let constants = [
                ("MODE", mode.constant()),
                ("HEAT_MAP", f64::from(u8::from(heat_map))),
                ("HAS_SPOTS", f64::from(u8::from(has_spots))),
                ("ENCODE_SRGB", encode_srgb_constant(format)),
            ];
            let pipeline = build_pipeline(
                device,
                PipelineSpec {
                    label: "deferred",
                    bind_groups: &[
                        Some(&self.deferred_inputs_layout),
                        Some(&self.lights_layout),
                    ],
                    module: &self.deferred_module,
                    vertex_entry: "vs_fullscreen",
                    vertex_buffers: &[],
                    depth: None,
                    targets: &[color_target(format, None)],
                    constants: &constants,
                },
            );
            self.deferred.insert(key, pipeline);
            self.built += 1;
        }
        &self.deferred[&key]
    }

    /// The forward pipeline for this combination, built on first use. `format` must be one
    /// [`drawable_format`] accepts.
    pub fn forward(
        &mut self,
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
        mode: ShadingMode,
        has_spots: bool,
    ) -> &wgpu::RenderPipeline {
        let key = ForwardKey {
            format,
            mode,
            has_spots,
        };
        if !self.forward.contains_key(&key) {
            let constants = [
                ("MODE", mode.constant()),
                ("HAS_SPOTS", f64::from(u8::from(has_spots))),
                ("ENCODE_SRGB", encode_srgb_constant(format)),
            ];
            let pipeline = build_pipeline(
                device,
                PipelineSpec {
                    label: "forward",
                    bind_groups: &[
                        Some(&self.frame_layout),
                        Some(&self.lights_layout),
                        Some(&self.material_layout),
                    ],
                    module: &self.forward_module,
                    vertex_entry: "vs_main",
                    vertex_buffers: &[Some(Vertex::LAYOUT)],
                    depth: depth_test(false),
                    targets: &[color_target(format, Some(wgpu::BlendState::ALPHA_BLENDING))],
                    constants: &constants,
                },
            );
            self.forward.insert(key, pipeline);
            self.built += 1;
        }
        &self.forward[&key]
    }
}
