//! The frame: upload what changed, G-buffer, deferred shading (clustered, tiled, brute force or
//! heat map), forward pass for blended geometry, pass timestamps.

mod lists_readback;
mod passes;
mod target_check;

pub use lists_readback::ListsReadBack;

use crate::buffers::{GrowableBuffer, stage};
use crate::frame_input::{ClusterLists, LightColumns, fill_gpu_lights};
use crate::layout::{FrameUniforms, GpuLight};
use crate::pipelines::{Pipelines, ShadingMode, drawable_format};
use crate::profiling::{end_span, profile_span};
use crate::scene::{GpuScene, SceneGeometry};
use crate::targets::GBuffer;
use crate::timing::{PassTimer, PassTimes};
use crate::{GpuContext, GpuError};
use glam::{DMat4, Mat4};
use myriad_cluster_math::{Camera, ClusterGrid};
use std::time::Instant;

/// Staging chunk size: a frame of 10k lights and their lists fits in one or two chunks; larger
/// uploads get chunks of their own size.
const STAGING_CHUNK_BYTES: u64 = 4 << 20;

/// Look and heat-map settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingSettings {
    /// Ambient term as a fraction of albedo.
    pub ambient: f32,
    /// Exposure before tone mapping.
    pub exposure: f32,
    /// Lights per pixel at the top of the heat-map ramp; `None` = the largest list (or the light
    /// count for brute force).
    pub heat_max: Option<u32>,
    /// Run every shader path and pass even when the frame does not need it (the spot-cone code
    /// without spot lights, the forward pass without blended geometry): the baseline that
    /// measures what skipping them saves. Normally false.
    pub force_all_features: bool,
}

impl Default for ShadingSettings {
    fn default() -> Self {
        Self {
            ambient: 0.03,
            exposure: 1.0,
            heat_max: None,
            force_all_features: false,
        }
    }
}

/// One frame's inputs.
#[derive(Clone, Copy, Debug)]
pub struct FrameDesc<'a> {
    /// The camera; its `width × height` must be the target's size.
    pub camera: &'a Camera,
    /// The grid the lists were built for (its depth range may be fitted, narrower than the
    /// camera's; pixels nearer than its near read its first slice and pixels beyond its far its
    /// last, which list the lights out there unless the grid is `OuterSlices::Closed`: see
    /// `myriad_cluster_math::OuterSlices` and the assignment's `AssignStats::beyond_far`,
    /// `before_near` and `reach`).
    pub grid: &'a ClusterGrid,
    /// Which lights each pixel visits.
    pub mode: ShadingMode,
    /// Write lights-per-pixel instead of the lit image.
    pub heat_map: bool,
    /// This frame's lights, or `None` to keep the last upload (allowed only while the camera
    /// position is unchanged, to within 4 f32 steps of its coordinates, the rounding of an eye
    /// read back from a turned view matrix: records are camera-relative).
    pub lights: Option<LightColumns<'a>>,
    /// This frame's lists, or `None` to keep the last upload (allowed only for the same grid and
    /// camera as that upload's: lists belong to one view). Needed for [`ShadingMode::Lists`].
    ///
    /// Kept lists must also be the ones assigned for the lights uploaded now: a frame may upload
    /// lights and keep the lists when only colours or intensities changed (what the viewer's
    /// skipping frames do), never when positions, ranges or cones did. The renderer checks the
    /// grid, the camera and that the lists name no light past the upload, but not the lights'
    /// geometry (that would hash every light of every upload): lists kept across a brute-force
    /// frame that uploaded other lights shade with `Ok` and the wrong lights (audit).
    pub lists: Option<ClusterLists<'a>>,
    /// Look settings.
    pub settings: ShadingSettings,
}

impl<'a> FrameDesc<'a> {
    /// A clustered (or, with a one-slice grid, tiled) frame that uploads `lights` and `lists`,
    /// lit image, default look: the common case, to adjust with struct update syntax.
    pub fn clustered(
        camera: &'a Camera,
        grid: &'a ClusterGrid,
        lights: LightColumns<'a>,
        lists: ClusterLists<'a>,
    ) -> Self {
        Self {
            camera,
            grid,
            mode: ShadingMode::Lists,
            heat_map: false,
            lights: Some(lights),
            lists: Some(lists),
            settings: ShadingSettings::default(),
        }
    }
}

/// What a frame cost on the CPU side, and what it moved.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameReport {
    /// Bytes written through the staging ring (lights, lists, slice edges).
    pub upload_bytes: u64,
    /// CPU seconds converting lights and writing the staging buffers.
    pub upload_seconds: f64,
    /// CPU seconds encoding and submitting the passes.
    pub encode_seconds: f64,
    /// Lights uploaded.
    pub lights: usize,
    /// Lights with invalid values, uploaded as records that light nothing. More than the
    /// assignment's `AssignStats::rejected` where only the appearance is invalid (a negative or
    /// NaN colour or intensity, a NaN spot angle): the assignment, which reads positions and
    /// radii, lists such a light and the renderer shows nothing of it.
    pub skipped_lights: usize,
    /// Whether the forward pass ran.
    pub forward_pass: bool,
}

/// The renderer: pipelines, G-buffer, light and list buffers, the staging ring, the timer.
///
/// It belongs to the device of the context it was made with: every call takes that context and
/// the scenes it uploaded, and refuses another device's with [`GpuError::InvalidInput`]. (A
/// target texture cannot be asked for its device: one of another device is refused by the
/// target check's recording, `target_check.rs`.)
#[derive(Debug)]
pub struct Renderer {
    /// The device everything below lives on: a call with another device's context or scene is
    /// refused ([`Renderer::check_device`]) where wgpu would panic on a resource it does not know.
    device: wgpu::Device,
    pipelines: Pipelines,
    gbuffer: Option<GBuffer>,
    /// The camera the G-buffer was last drawn for, by a frame or a prepass (`None` while it
    /// holds nothing): [`Renderer::render_after_prepass`] shades it only for that camera.
    gbuffer_camera: Option<Camera>,
    frame_buffer: wgpu::Buffer,
    frame_group: wgpu::BindGroup,
    deferred_inputs: Option<wgpu::BindGroup>,
    lights: GrowableBuffer,
    offsets: GrowableBuffer,
    counts: GrowableBuffer,
    indices: GrowableBuffer,
    slice_edges: GrowableBuffer,
    lights_group: Option<wgpu::BindGroup>,
    belt: wgpu::util::StagingBelt,
    timer: PassTimer,
    scratch_lights: Vec<GpuLight>,
    scratch_edges: Vec<f32>,
    scratch_draws: Vec<crate::scene::Draw>,
    light_count: usize,
    lights_camera: Option<[f32; 3]>,
    lists_uploaded: Option<UploadedLists>,
    edges_uploaded: Option<ClusterGrid>,
    /// The last target the shading passes validated against (`target_check.rs`).
    checked_target: Option<target_check::CheckedTarget>,
    has_spots: bool,
    /// Set anew by every frame that uploads lights or lists (see
    /// [`Renderer::upload_generation`]).
    uploads: u64,
    /// Why wgpu refused what [`Renderer::new`] made (a device below
    /// [`Renderer::required_limits`]): every call returns it as [`GpuError::DeviceLimits`].
    refused: Option<String>,
}

impl Renderer {
    /// The device limits the renderer needs: wgpu's downlevel defaults, with five storage buffers
    /// per shader stage (the shading passes read the lights, offsets, counts, indices and slice
    /// edges in the fragment stage; the downlevel defaults allow four); [`Renderer::try_new`]
    /// checks them. The minimum, not what to ask for: a device made with exactly these renders
    /// targets of at most 2048 pixels a side and binds lists of at most 128 MiB (32 M pairs).
    /// An engine creating its device for the renderer requests
    /// [`Renderer::required_limits_for`] its adapter's limits (or more).
    pub fn required_limits() -> wgpu::Limits {
        wgpu::Limits {
            max_storage_buffers_per_shader_stage: 5,
            ..wgpu::Limits::downlevel_defaults()
        }
    }

    /// [`Renderer::required_limits`] raised to what an adapter offers (`adapter`: its
    /// `Adapter::limits()`) where the renderer's reach grows with the limit: the largest
    /// texture (the target and the G-buffer; 2048 pixels a side in the minimum, 16 384 on
    /// llvmpipe) and the largest storage binding and buffer (the light lists: 128 MiB in the
    /// minimum). Following the minimum, an engine's 2560×1440 target was refused by wgpu
    /// (session 38's drop-in review); these limits draw anything the adapter can.
    pub fn required_limits_for(adapter: &wgpu::Limits) -> wgpu::Limits {
        let min = Self::required_limits();
        wgpu::Limits {
            max_texture_dimension_1d: adapter
                .max_texture_dimension_1d
                .max(min.max_texture_dimension_1d),
            max_texture_dimension_2d: adapter
                .max_texture_dimension_2d
                .max(min.max_texture_dimension_2d),
            max_storage_buffer_binding_size: adapter
                .max_storage_buffer_binding_size
                .max(min.max_storage_buffer_binding_size),
            max_buffer_size: adapter.max_buffer_size.max(min.max_buffer_size),
            ..min
        }
    }

    /// [`Renderer::new`] after checking the device against [`Renderer::required_limits`]
    /// ([`GpuError::DeviceLimits`] naming every limit that is too low) and `output_format` (a
    /// float colour format the device can render to and blend): an error now, where `new` gives
    /// a renderer whose calls return it (or refuse that format's targets).
    pub fn try_new(ctx: &GpuContext, output_format: wgpu::TextureFormat) -> Result<Self, GpuError> {
        ctx.check_not_lost()?;
        if let Some(short) = limits_shortfall(&ctx.device) {
            return Err(GpuError::DeviceLimits(short));
        }
        if let Some(problem) = drawable_format(&ctx.device, output_format) {
            return Err(GpuError::InvalidInput(problem));
        }
        Ok(Self::new(ctx, output_format))
    }

    /// A renderer made for textures of `output_format` (the headless target's
    /// [`crate::HEADLESS_FORMAT`], or an engine's): [`Renderer::prepare`] builds its pipelines
    /// for that format. It draws into targets of any other format it can as well (the same
    /// lights, lists and G-buffer shaded into an HDR view and an sRGB thumbnail), each format's
    /// pipelines built on first use or ahead with [`Renderer::prepare_for`]. sRGB formats get
    /// sRGB, encoded in hardware; UNORM formats without sRGB get it too, encoded by the shaders
    /// ([`crate::encodes_srgb`]); float formats get the linear tone-mapped colour.
    ///
    /// On a device below [`Renderer::required_limits`] where wgpu refuses the renderer's layouts
    /// or pipelines, every call of the renderer returns [`GpuError::DeviceLimits`] naming the
    /// limits (it panicked here in wgpu's validation; under an engine's own error handler the
    /// frames blamed their target). [`Renderer::try_new`] refuses such a device up front, and
    /// also one whose storage bindings are below the 128 MiB `new` leaves to each frame's checks.
    pub fn new(ctx: &GpuContext, output_format: wgpu::TextureFormat) -> Self {
        let device = &ctx.device;
        // Everything made here is made under an error scope: on a device wgpu refuses them on
        // (limits below `required_limits`), the renderer keeps the reason and every call returns
        // it, instead of a panic here or, under an engine's own error handler, frames that
        // blamed their target (engine audit).
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let pipelines = Pipelines::new(device, output_format);
        let frame_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame uniforms"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &pipelines.frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_buffer.as_entire_binding(),
            }],
        });
        let refused = target_check::ready(scope.pop()).flatten().map(|error| {
            let short = limits_shortfall(device).unwrap_or_else(|| "none below them".into());
            format!("{short}; wgpu refused the renderer's layouts and pipelines: {error}")
        });
        Self {
            device: device.clone(),
            gbuffer: None,
            gbuffer_camera: None,
            frame_group,
            frame_buffer,
            deferred_inputs: None,
            lights: GrowableBuffer::new(device, "lights"),
            offsets: GrowableBuffer::new(device, "cluster offsets"),
            counts: GrowableBuffer::new(device, "cluster counts"),
            indices: GrowableBuffer::new(device, "light indices"),
            slice_edges: GrowableBuffer::new(device, "slice edges"),
            lights_group: None,
            belt: wgpu::util::StagingBelt::new(device.clone(), STAGING_CHUNK_BYTES),
            timer: PassTimer::new(ctx),
            scratch_lights: Vec::new(),
            scratch_edges: Vec::new(),
            scratch_draws: Vec::new(),
            light_count: 0,
            lights_camera: None,
            lists_uploaded: None,
            uploads: 0,
            edges_uploaded: None,
            checked_target: None,
            has_spots: false,
            pipelines,
            refused,
        }
    }

    /// Uploads scene geometry for this renderer's pipelines. Geometry the device has no memory
    /// for is [`GpuError::OutOfMemory`].
    pub fn upload_scene(
        &self,
        ctx: &GpuContext,
        geometry: &SceneGeometry,
    ) -> Result<GpuScene, GpuError> {
        self.check_device(ctx, None)?;
        geometry.check().map_err(GpuError::InvalidInput)?;
        geometry
            .check_limits(&ctx.device.limits())
            .map_err(GpuError::InvalidInput)?;
        GpuScene::new(
            &ctx.device,
            &ctx.queue,
            &self.pipelines.material_layout,
            geometry,
        )
    }

    /// Builds ahead the pipelines [`Renderer::render`] will use for `frame` on `scene` drawn into
    /// a target of the renderer's [`Renderer::output_format`], so that the first such frame does
    /// not compile shaders while it encodes (an engine calls this at load time, once per kind of
    /// frame it will draw: lit, heat map, brute force): the deferred shading variant of the
    /// frame's mode, heat map and spot lights (spot columns in `frame.lights`, or in the last
    /// upload when it keeps them), and the forward pass's when the frame has one (`scene` has
    /// blended geometry, or every feature is forced). Nothing is uploaded or checked, and
    /// `frame.lists` is not read. Returns how many pipelines it built: 0 when they all were
    /// already; an error for a context or scene of another device (and as
    /// [`Renderer::prepare_for`] says).
    pub fn prepare(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        frame: &FrameDesc<'_>,
    ) -> Result<usize, GpuError> {
        self.prepare_for(ctx, scene, frame, self.output_format())
    }

    /// [`Renderer::prepare`] for targets whose views are of `format` (another format than the
    /// renderer's own: an engine's second view). An error also for a format the renderer
    /// cannot draw into, as [`Renderer::try_new`] names it.
    pub fn prepare_for(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        frame: &FrameDesc<'_>,
        format: wgpu::TextureFormat,
    ) -> Result<usize, GpuError> {
        self.check_device(ctx, Some(scene))?;
        if let Some(problem) = drawable_format(&ctx.device, format) {
            return Err(GpuError::InvalidInput(problem));
        }
        let before = self.pipelines.built();
        let has_spots = self.shades_spots(frame);
        self.pipelines
            .deferred(&ctx.device, format, frame.mode, frame.heat_map, has_spots);
        if has_forward_pass(scene, frame) {
            self.pipelines
                .forward(&ctx.device, format, frame.mode, has_spots);
        }
        Ok(self.pipelines.built() - before)
    }

    /// Refuses a context (and scene) of another device than the one this renderer was made on:
    /// the renderer's pipelines and buffers exist only there, and wgpu panics on them elsewhere
    /// ("Cannot get non-existent resource", audit). And every call of a renderer made with
    /// [`Renderer::new`] on a device below the required limits.
    fn check_device(&self, ctx: &GpuContext, scene: Option<&GpuScene>) -> Result<(), GpuError> {
        ctx.check_not_lost()?;
        if let Some(refused) = &self.refused {
            return Err(GpuError::DeviceLimits(refused.clone()));
        }
        if ctx.device != self.device {
            return Err(GpuError::InvalidInput(
                "the context is of another device than the one this renderer was made on (a \
                 renderer, its scenes and its targets belong to one device)"
                    .into(),
            ));
        }
        if scene.is_some_and(|scene| scene.device != self.device) {
            return Err(GpuError::InvalidInput(
                "the scene was uploaded on another device than this renderer's (upload it with \
                 this renderer's upload_scene)"
                    .into(),
            ));
        }
        Ok(())
    }

    /// Whether `frame` shades with the spot-cone code: its lights have spot columns (or, when it
    /// keeps the last upload, those had), or every feature is forced. Before the frame's upload
    /// as after it — the target check, which runs first, once built the variants of the
    /// *previous* upload, so a first frame with spot lights compiled two pipelines it never used.
    fn shades_spots(&self, frame: &FrameDesc<'_>) -> bool {
        frame.lights.map_or(self.has_spots, |c| c.spot.is_some())
            || frame.settings.force_all_features
    }

    /// Render pipelines built so far, the G-buffer's included: a frame that finds this number
    /// higher after it than before built some while encoding ([`Renderer::prepare`] builds them
    /// ahead).
    pub fn pipelines_built(&self) -> usize {
        self.pipelines.built()
    }

    /// The last frame's depth buffer (one f32 per pixel, reversed Z: 1 at the near plane, 0 where
    /// nothing was drawn; `Camera::view_depth_from_ndc_depth` turns it into view depth); waits for
    /// the GPU. `None` before the first frame.
    pub fn read_depth(&self, ctx: &GpuContext) -> Result<Option<Vec<f32>>, GpuError> {
        self.check_device(ctx, None)?;
        self.gbuffer
            .as_ref()
            .map(|g| crate::readback::read_depth(ctx, &g.depth_texture))
            .transpose()
    }

    /// The G-buffer the last frame or prepass drew, at the camera's size (`None` before the
    /// first): an engine can depth-test what it draws after the frame against its `depth`
    /// ([`crate::DEPTH_FORMAT`], reversed Z: 1 at the near plane, 0 where nothing was drawn, so
    /// its pipelines compare `Greater`), or sample
    /// its normals. It stays until a frame of another size replaces it; drawing into it changes
    /// what a following [`Renderer::render_after_prepass`] shades.
    pub fn gbuffer(&self) -> Option<&GBuffer> {
        self.gbuffer.as_ref()
    }

    /// The colour format the renderer was made for: what [`Renderer::prepare`] builds for.
    /// Targets of other formats it can draw into are accepted too (see [`Renderer::new`]).
    pub fn output_format(&self) -> wgpu::TextureFormat {
        self.pipelines.output_format()
    }

    /// Which upload of lights or lists the renderer holds: a new value with every frame that
    /// uploads either, 0 before the first. A caller that keeps what it last uploaded (to send
    /// nothing when nothing changed) compares this with the value after its own upload: if
    /// another frame uploaded in between, the GPU no longer holds its data. The values are
    /// unique across every renderer of the process, so a renderer replaced by another (the
    /// viewer's public `renderer`) never matches a value the old one gave: each renderer
    /// counted from 0, and after one upload on the new renderer a viewer's skipping frame took
    /// another frame's lights and lists for its own and reused them, with `Ok` (audit).
    pub fn upload_generation(&self) -> u64 {
        self.uploads
    }

    /// Bytes of the storage buffers that hold lights and lists `[lights, offsets, counts,
    /// indices]`. They grow (to the next power of two) when a frame needs more and never shrink,
    /// so an engine can see what its light load costs in GPU memory.
    pub fn list_buffer_bytes(&self) -> [u64; 4] {
        [&self.lights, &self.offsets, &self.counts, &self.indices].map(|b| b.capacity())
    }

    /// GPU times of the last frame's passes (waits for the GPU); `None` where the device has no
    /// timestamp queries.
    pub fn last_pass_times(&self, ctx: &GpuContext) -> Result<Option<PassTimes>, GpuError> {
        self.check_device(ctx, None)?;
        self.timer.read(ctx)
    }

    /// Tracy GPU zones this renderer has emitted (the `tracy` feature): each timed pass of a
    /// frame becomes one, on a GPU track of its own, when [`Renderer::last_pass_times`] reads
    /// the frame's times while a Tracy client runs. A profiling session can check its GPU track
    /// is fed; 0 before the client starts and on devices without timestamp queries.
    #[cfg(feature = "tracy")]
    pub fn gpu_zones_emitted(&self) -> u64 {
        self.timer.zones_emitted()
    }

    /// How often this renderer tied the GPU clock of its Tracy zones to the CPU's (the `tracy`
    /// feature): once when its first zones are emitted, then again before emitting zones a
    /// second or more after the last tie, or at once when the GPU clock went back (a GPU that
    /// resets it in a low-power state), so a long capture's GPU track stays on the CPU's
    /// timeline. 0 before the client starts.
    #[cfg(feature = "tracy")]
    pub fn gpu_clock_ties(&self) -> u64 {
        self.timer.clock_ties()
    }

    /// Whether Tracy refused this renderer a GPU context (the `tracy` feature): it gives a
    /// process 255, and a renderer made past them draws and times its frames with no GPU track
    /// (the reason a capture's GPU track can be empty). Asked once, with the first zones; a
    /// refusal is final.
    #[cfg(feature = "tracy")]
    pub fn gpu_context_refused(&self) -> bool {
        self.timer.context_refused()
    }

    /// Records, encodes and submits one frame into `target` (a single-sample view of mip 0 of a
    /// texture of the camera's size, in a format the renderer can draw into: its
    /// [`Renderer::output_format`] or another, see [`Renderer::new`]; a view may reinterpret its
    /// texture's sRGB-ness). Returns without waiting for the GPU. A target wgpu would reject (a
    /// mip of another size, a view format its texture does not allow) is an error: the first
    /// frame into each target checks it, and finds the view's format (`target_check.rs`).
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        frame: &FrameDesc<'_>,
        target: &wgpu::TextureView,
    ) -> Result<FrameReport, GpuError> {
        self.render_frame(ctx, scene, frame, target, true)
    }

    /// Draws only the G-buffer for `camera` (a depth prepass: read it with
    /// [`Renderer::read_depth`]) and submits. A following [`Renderer::render_after_prepass`] with
    /// the same camera shades it without drawing the geometry again.
    pub fn render_prepass(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        camera: &Camera,
    ) -> Result<(), GpuError> {
        self.check_device(ctx, Some(scene))?;
        check_camera(camera)?;
        let (width, height) = (camera.width, camera.height);
        self.ensure_gbuffer(&ctx.device, width, height)?;
        // A camera can pass `check_camera` with a near below the grids' floor. The prepass reads
        // no lists: its one-cluster grid only fills the frame's uniforms, so an infinite far
        // plane may stand at f32's largest value there.
        let grid = ClusterGrid::try_new(
            glam::UVec3::ONE,
            myriad_cluster_math::DepthSlicing::Linear,
            camera.near,
            camera.far.min(f32::MAX),
        )
        .map_err(|e| GpuError::InvalidInput(e.to_string()))?;
        let frame = FrameDesc {
            camera,
            grid: &grid,
            mode: ShadingMode::BruteForce,
            heat_map: false,
            lights: None,
            lists: None,
            settings: ShadingSettings::default(),
        };
        let uniforms = frame_uniforms(&frame, self.light_count as u32, 0);
        ctx.queue
            .write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(&uniforms));
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("prepass"),
            });
        profile_span!("prepass: encode and submit");
        self.timer.begin_frame(false);
        self.encode_gbuffer(&mut encoder, scene);
        // Resolved now, so `last_pass_times` after a prepass reports it (and not the ticks of
        // the frame before).
        self.timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        self.gbuffer_camera = Some(*camera);
        Ok(())
    }

    /// [`Renderer::render`] without the G-buffer pass: shades the G-buffer the last
    /// [`Renderer::render_prepass`] drew, which must have been for the same camera (else
    /// [`GpuError::InvalidInput`]: its pixels are another view's).
    pub fn render_after_prepass(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        frame: &FrameDesc<'_>,
        target: &wgpu::TextureView,
    ) -> Result<FrameReport, GpuError> {
        self.render_frame(ctx, scene, frame, target, false)
    }

    /// A G-buffer of the camera's size (checked against the device's limits first).
    fn ensure_gbuffer(
        &mut self,
        device: &wgpu::Device,
        width: u32,
        height: u32,
    ) -> Result<(), GpuError> {
        if self.gbuffer.as_ref().map(|g| g.size) != Some((width, height)) {
            let gbuffer = GBuffer::new(device, width, height)?;
            self.deferred_inputs = Some(self.deferred_bind_group(device, &gbuffer));
            self.gbuffer = Some(gbuffer);
            self.gbuffer_camera = None;
        }
        Ok(())
    }

    fn render_frame(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        frame: &FrameDesc<'_>,
        target: &wgpu::TextureView,
        draw_gbuffer: bool,
    ) -> Result<FrameReport, GpuError> {
        self.check_device(ctx, Some(scene))?;
        let device = &ctx.device;
        check_camera(frame.camera)?;
        let (width, height) = (frame.camera.width, frame.camera.height);
        // The view's format (its texture's, or that one's sRGB twin) is found by the target
        // check below; the texture's own must be one the passes can draw.
        let texture = target.texture();
        if !texture
            .usage()
            .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
        {
            return Err(GpuError::InvalidInput(format!(
                "the target is a {:?} texture with {:?} usage; the renderer draws into \
                 RENDER_ATTACHMENT textures",
                texture.format(),
                texture.usage(),
            )));
        }
        if let Some(problem) = drawable_format(device, texture.format()) {
            return Err(GpuError::InvalidInput(problem));
        }
        if texture.sample_count() != 1 {
            return Err(GpuError::InvalidInput(format!(
                "the target has {} samples per pixel; the renderer draws single-sample targets \
                 (resolve into one afterwards)",
                texture.sample_count()
            )));
        }
        let target_size = texture.size();
        if (target_size.width, target_size.height) != (width, height) {
            return Err(GpuError::InvalidInput(format!(
                "camera is {width}x{height} but the target's texture is {}x{} (the renderer draws \
                 into mip 0 of a texture of the camera's size: a viewport or a lower mip of a \
                 larger texture is not drawn into)",
                target_size.width, target_size.height
            )));
        }
        let dims = frame.grid.dims();
        if 2 * width as u64 * dims.x as u64 > u32::MAX as u64
            || 2 * height as u64 * dims.y as u64 > u32::MAX as u64
        {
            return Err(GpuError::InvalidInput(format!(
                "target {width}x{height} with {}x{} tiles overflows the shader's u32 tile arithmetic",
                dims.x, dims.y
            )));
        }
        // Every input is checked before anything is staged, so a refused frame leaves the
        // renderer as it was (lights, lists and counts of the last accepted frame).
        let clusters = frame.grid.cluster_count();
        let light_count = match &frame.lights {
            Some(columns) => {
                columns.check().map_err(GpuError::InvalidInput)?;
                let bytes = (columns.len() * std::mem::size_of::<GpuLight>()) as u64;
                self.lights.check_fits(device, bytes)?;
                columns.len()
            }
            None => self.light_count,
        };
        if let Some(lists) = &frame.lists {
            lists
                .check(clusters, light_count)
                .map_err(GpuError::InvalidInput)?;
            for (buffer, data) in [
                (&self.offsets, lists.offsets),
                (&self.counts, lists.counts),
                (&self.indices, lists.indices),
            ] {
                buffer.check_fits(device, std::mem::size_of_val(data) as u64)?;
            }
        }
        if self.edges_uploaded != Some(*frame.grid) {
            // One f32 per slice boundary, as `fill_slice_edges` writes them below.
            let edges = (frame.grid.dims().z as u64 + 1) * std::mem::size_of::<f32>() as u64;
            self.slice_edges.check_fits(device, edges)?;
        }
        let camera_position = frame.camera.position.to_array();
        if frame.lights.is_none()
            && self.light_count > 0
            && !self
                .lights_camera
                .is_some_and(|kept| same_eye(kept, camera_position))
        {
            return Err(GpuError::InvalidInput(
                "the camera moved, so the camera-relative lights must be uploaded again".into(),
            ));
        }
        // Kept lists belong to the grid they were built for, all of it: the same dimensions
        // over another depth range or slicing are other clusters. And they must not name
        // lights beyond the ones uploaded now (the light buffer never shrinks, so the shader
        // would read the records of lights that are gone).
        if frame.mode == ShadingMode::Lists && frame.lists.is_none() {
            match self.lists_uploaded {
                // And to the camera they were assigned for: the same grid seen from elsewhere is
                // other clusters in the world (such a frame shaded with Ok, audit).
                Some(kept) if kept.grid == *frame.grid && !kept.camera.same_as(frame.camera) => {
                    return Err(GpuError::InvalidInput(
                        "the kept lists were assigned for another camera (its position, \
                         orientation, field of view, size or depth range changed): lists belong \
                         to one view, so upload lists assigned for this camera"
                            .into(),
                    ));
                }
                Some(kept) if kept.grid == *frame.grid => {
                    if kept.lights_named > light_count {
                        return Err(GpuError::InvalidInput(format!(
                            "the kept lists name light {}, but the frame has {light_count} \
                             lights: upload lists built for these lights",
                            kept.lights_named - 1
                        )));
                    }
                }
                _ => return Err(missing_lists(frame.grid)),
            }
        }
        // Checked before anything is staged, so a refused frame changes nothing, and after the
        // inputs' own checks and the kept lists', so lists of another grid's shape — given or
        // kept — are named as such (they were refused for a loop limit, audit).
        if let Some(max_lights) = ctx.max_lights_per_pixel(frame.mode, dims.z)
            && !frame.heat_map
        {
            let lights = match frame.mode {
                ShadingMode::BruteForce => {
                    frame.lights.map_or(self.light_count, |c| c.len()) as u64
                }
                ShadingMode::Lists => frame
                    .lists
                    .map(|l| l.max_count())
                    .or(self.lists_uploaded.map(|u| u.max_count))
                    .unwrap_or(0) as u64,
            };
            if lights > max_lights {
                return Err(GpuError::ShaderLoopLimit {
                    mode: frame.mode,
                    lights,
                    max_lights,
                    adapter: ctx.describe(),
                    limit: ctx.shader_loop_limit().unwrap_or_default(),
                });
            }
        }
        if !draw_gbuffer && self.gbuffer.as_ref().map(|g| g.size) != Some((width, height)) {
            return Err(GpuError::InvalidInput(
                "render_after_prepass needs a prepass of the same size first".into(),
            ));
        }
        // Shading another camera's G-buffer rebuilds every pixel's position with the wrong
        // view: a wrong image returned as Ok (audit).
        if !draw_gbuffer && !self.gbuffer_camera.is_some_and(|c| c.same_as(frame.camera)) {
            return Err(GpuError::InvalidInput(
                "render_after_prepass shades the G-buffer the prepass drew, for another camera \
                 (its position, orientation, field of view or depth range differ): run the \
                 prepass with this frame's camera"
                    .into(),
            ));
        }
        // The last checks that can fail: the G-buffer's size against the device (a new size's
        // G-buffer changes nothing a later frame relies on), and the target against the passes.
        self.ensure_gbuffer(device, width, height)?;
        let forward_pass = has_forward_pass(scene, frame);
        let format = self.check_target(device, frame, target, forward_pass)?;
        profile_span!("upload lights and lists", upload);
        let upload_start = Instant::now();
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("frame"),
        });
        // A frame after a prepass keeps the prepass's G-buffer timestamps (its queries stay as
        // the prepass wrote them and are resolved again with this frame's).
        self.timer.begin_frame(!draw_gbuffer);
        self.timer.upload_start(&mut encoder);
        let (mut report, rebind_lights, max_count) =
            match self.upload(device, frame, &mut encoder, camera_position) {
                Ok(uploaded) => uploaded,
                Err(error @ GpuError::OutOfMemory(_)) => {
                    // Earlier buffers may have been replaced and staged into this frame's
                    // encoder, which is dropped: nothing uploaded is known to be there.
                    self.forget_uploads(device);
                    return Err(error);
                }
                Err(error) => return Err(error),
            };

        self.timer.upload_end(&mut encoder, report.upload_bytes > 0);
        let uniforms = frame_uniforms(frame, self.light_count as u32, max_count);
        ctx.queue
            .write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(&uniforms));
        self.belt.finish();
        report.upload_seconds = upload_start.elapsed().as_secs_f64();
        end_span!(upload);

        profile_span!("encode and submit");
        let encode_start = Instant::now();
        if rebind_lights {
            self.lights_group = Some(self.lights_bind_group(device));
        }
        if draw_gbuffer {
            self.encode_gbuffer(&mut encoder, scene);
            self.gbuffer_camera = Some(*frame.camera);
        }
        self.encode_shading(device, &mut encoder, frame, target, format);
        report.forward_pass = forward_pass;
        if report.forward_pass {
            self.encode_forward(device, &mut encoder, scene, frame, target, format);
        }
        self.timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        self.belt.recall();
        report.encode_seconds = encode_start.elapsed().as_secs_f64();
        Ok(report)
    }

    /// The frame's uploads into `encoder`: its lights, lists and slice edges, each buffer grown
    /// as needed. Returns the report so far, whether the lights' bind group must be rebuilt, and
    /// the longest list a pixel loops over.
    fn upload(
        &mut self,
        device: &wgpu::Device,
        frame: &FrameDesc<'_>,
        encoder: &mut wgpu::CommandEncoder,
        camera_position: [f32; 3],
    ) -> Result<(FrameReport, bool, u32), GpuError> {
        let mut report = FrameReport::default();
        let mut rebind_lights = self.lights_group.is_none();

        // Lights.
        if let Some(columns) = &frame.lights {
            report.skipped_lights = fill_gpu_lights(
                columns,
                frame.camera.position.as_dvec3(),
                &mut self.scratch_lights,
            );
            let bytes = std::mem::size_of_val(self.scratch_lights.as_slice()) as u64;
            rebind_lights |= self.lights.reserve(device, bytes)?;
            report.upload_bytes += stage(
                device,
                &mut self.belt,
                encoder,
                &self.lights,
                &self.scratch_lights,
            )?;
            self.light_count = columns.len();
            self.lights_camera = Some(camera_position);
            self.has_spots = columns.spot.is_some();
        }
        report.lights = self.light_count;

        // Lists and slice edges.
        if let Some(lists) = &frame.lists {
            for (buffer, data) in [
                (&mut self.offsets, lists.offsets),
                (&mut self.counts, lists.counts),
                (&mut self.indices, lists.indices),
            ] {
                rebind_lights |= buffer.reserve(device, std::mem::size_of_val(data) as u64)?;
                report.upload_bytes += stage(device, &mut self.belt, encoder, buffer, data)?;
            }
            self.lists_uploaded = Some(UploadedLists {
                grid: *frame.grid,
                camera: *frame.camera,
                max_count: lists.max_count(),
                lights_named: lists.lights_named(),
                pairs: lists.indices.len(),
            });
        }
        // Once per frame, however much it uploads, from one counter for the whole process.
        if frame.lights.is_some() || frame.lists.is_some() {
            static UPLOADS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
            self.uploads = UPLOADS.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        }
        let max_count = match (frame.mode, self.lists_uploaded) {
            (ShadingMode::BruteForce, _) => self.light_count as u32,
            (ShadingMode::Lists, Some(kept)) => kept.max_count,
            (ShadingMode::Lists, None) => unreachable!("checked above: lists for this grid"),
        };
        if self.edges_uploaded != Some(*frame.grid) {
            frame.grid.fill_slice_edges(&mut self.scratch_edges);
            let bytes = std::mem::size_of_val(self.scratch_edges.as_slice()) as u64;
            rebind_lights |= self.slice_edges.reserve(device, bytes)?;
            report.upload_bytes += stage(
                device,
                &mut self.belt,
                encoder,
                &self.slice_edges,
                &self.scratch_edges,
            )?;
            self.edges_uploaded = Some(*frame.grid);
        }
        Ok((report, rebind_lights, max_count))
    }

    /// After a device buffer could not be grown: no lights, lists or slice edges are known to be
    /// on the GPU, and the staging belt, which staged some of them into the dropped encoder,
    /// starts anew.
    fn forget_uploads(&mut self, device: &wgpu::Device) {
        self.light_count = 0;
        self.lights_camera = None;
        self.lists_uploaded = None;
        self.edges_uploaded = None;
        self.lights_group = None;
        self.belt = wgpu::util::StagingBelt::new(device.clone(), STAGING_CHUNK_BYTES);
    }
}

/// The limits of `device` below [`Renderer::required_limits`], named with what each needs; `None`
/// when it meets them all.
fn limits_shortfall(device: &wgpu::Device) -> Option<String> {
    let mut short = Vec::new();
    Renderer::required_limits().check_limits_with_fail_fn(
        &device.limits(),
        false,
        |name, needed, allowed| short.push(format!("{name} {allowed} (needs {needed})")),
    );
    (!short.is_empty()).then(|| short.join(", "))
}

/// What the last accepted lists were built for: a frame that keeps them is checked against it.
#[derive(Clone, Copy, Debug)]
struct UploadedLists {
    /// The whole grid (dimensions, depth range, slicing).
    grid: ClusterGrid,
    /// The camera of the frame that uploaded them (the view the lists were assigned for).
    camera: Camera,
    /// The longest list (the shader loop-limit guard).
    max_count: u32,
    /// One more than the largest light index.
    lights_named: usize,
    /// Light indices uploaded.
    pairs: usize,
}

/// The error of a clustered frame without lists for its grid (none uploaded, or for another grid).
fn missing_lists(grid: &ClusterGrid) -> GpuError {
    let d = grid.dims();
    GpuError::InvalidInput(format!(
        "clustered shading needs light lists for this grid ({}x{}x{}, {} clusters, depth [{}, {}] \
         sliced {:?}): none were uploaded, or the kept ones were built for another grid",
        d.x,
        d.y,
        d.z,
        grid.cluster_count(),
        grid.near(),
        grid.far(),
        grid.slicing()
    ))
}

/// Refuses a camera the renderer cannot draw with: [`Camera::problem`] (a non-finite eye, a field
/// of view outside (0, π), a zero size, or a depth range not `0 < near < far`). An infinite far
/// plane is drawn with the infinite reversed-Z projection (`Camera::clip_from_view`); the lists'
/// grid stays finite, and pixels beyond its far edge read its last slice. Such a camera rendered
/// a blank image with `Ok`, and the prepass panicked.
fn check_camera(camera: &Camera) -> Result<(), GpuError> {
    match camera.problem() {
        Some(problem) => Err(GpuError::InvalidInput(format!(
            "unusable camera: {problem}"
        ))),
        None => Ok(()),
    }
}

/// Whether `frame` draws the forward pass: blended geometry to draw (or every feature forced),
/// and a lit image (a heat map is the deferred pass alone).
fn has_forward_pass(scene: &GpuScene, frame: &FrameDesc<'_>) -> bool {
    (scene.has_blended() || frame.settings.force_all_features) && !frame.heat_map
}

/// The uniform block for a frame. The inverse projection is taken in f64 so reconstructed
/// positions are as good as the depth buffer allows.
pub fn frame_uniforms(frame: &FrameDesc<'_>, light_count: u32, max_count: u32) -> FrameUniforms {
    let camera = frame.camera;
    let clip_from_world_rel = camera.clip_from_view() * Mat4::from_mat3(camera.view_rotation());
    let inverse =
        DMat4::from_cols_array(&clip_from_world_rel.to_cols_array().map(f64::from)).inverse();
    let dims = frame.grid.dims();
    FrameUniforms {
        clip_from_world_rel: clip_from_world_rel.to_cols_array_2d(),
        world_rel_from_clip: inverse.as_mat4().to_cols_array_2d(),
        camera_position: camera.position.extend(1.0).to_array(),
        target_size: [camera.width, camera.height],
        light_count,
        heat_max: frame.settings.heat_max.unwrap_or(max_count).max(1),
        grid_dims: [dims.x, dims.y, dims.z, 0],
        camera_near: camera.near,
        camera_near_over_far: camera.near_over_far(),
        ambient: frame.settings.ambient,
        exposure: frame.settings.exposure,
    }
}
/// Whether kept camera-relative lights, uploaded from an eye at `kept`, may be drawn from `now`:
/// the same point to within 4 f32 steps of its coordinates. An engine that only turns its camera
/// and reads it back through `Camera::from_matrices` gets the eye as `−M⁻¹t`, whose rounding moves
/// it a step or two between frames; the lights would then be off by as much, far inside the
/// assignment's padding (4e-6 of a light's view-space extent).
fn same_eye(kept: [f32; 3], now: [f32; 3]) -> bool {
    kept.iter().zip(&now).all(|(&a, &b)| {
        let size = a.abs().max(b.abs());
        (a - b).abs() <= 4.0 * (size.next_up() - size)
    })
}
