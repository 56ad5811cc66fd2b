//! One scene on one GPU context: assign (on the CPU, with any method), upload, render, read back.
//! The building block of the main job, the tests and the pipelined loop's sequential reference.

use super::setup::RenderScene;
use crate::light_input;
use anyhow::Result;
use myriad_assignment::{AssignStats, Assigner, LightLists, Method};
use myriad_gpu::{
    ClusterLists, FrameDesc, FrameReport, GpuContext, GpuScene, HEADLESS_FORMAT, HeadlessTarget,
    LightColumns, Renderer, ShadingMode, ShadingSettings, SpotColumns, TextureRgba8,
};
use myriad_scene::{ClusterGrid, DepthSlicing, Lights};
use std::time::Instant;

/// How the lit image picks its lights.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shading {
    /// The scene's cluster grid and its lists.
    Clustered,
    /// 2D tiles: the grid's X×Y tiles with one depth slice over the whole range.
    Tiled,
    /// Every light at every pixel.
    BruteForce,
}

impl Shading {
    /// Every strategy.
    pub const ALL: [Shading; 3] = [Shading::Clustered, Shading::Tiled, Shading::BruteForce];

    /// Name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Shading::Clustered => "clustered",
            Shading::Tiled => "tiled",
            Shading::BruteForce => "brute force",
        }
    }

    /// Which lights the shading passes visit.
    pub fn mode(self) -> ShadingMode {
        match self {
            Shading::BruteForce => ShadingMode::BruteForce,
            Shading::Clustered | Shading::Tiled => ShadingMode::Lists,
        }
    }

    /// The grid this strategy assigns to, for a scene grid.
    pub fn grid(self, scene_grid: &ClusterGrid) -> ClusterGrid {
        match self {
            Shading::Tiled => ClusterGrid::new(
                scene_grid.dims().with_z(1),
                DepthSlicing::Linear,
                scene_grid.near(),
                scene_grid.far(),
            )
            .with_outer_slices(scene_grid.outer_slices()),
            _ => *scene_grid,
        }
    }
}

/// The borrowed GPU view of a scene's light columns.
pub fn light_columns(lights: &Lights) -> LightColumns<'_> {
    LightColumns {
        x: &lights.x,
        y: &lights.y,
        z: &lights.z,
        radius: &lights.radius,
        r: &lights.r,
        g: &lights.g,
        b: &lights.b,
        intensity: &lights.intensity,
        spot: lights.has_spots().then(|| SpotColumns {
            dir_x: &lights.spot_dir_x,
            dir_y: &lights.spot_dir_y,
            dir_z: &lights.spot_dir_z,
            angle: &lights.spot_angle,
            inner_angle: Some(&lights.spot_inner_angle),
        }),
    }
}

/// The GPU's borrowed view of CSR lists.
pub fn cluster_lists(lists: &LightLists) -> ClusterLists<'_> {
    ClusterLists {
        offsets: &lists.offsets,
        counts: &lists.counts,
        indices: &lists.indices,
    }
}

/// A lit (or heat-map) frame of `scene`'s camera and lights with `shading`, on `grid`.
fn frame_desc<'a>(
    scene: &'a RenderScene,
    grid: &'a ClusterGrid,
    shading: Shading,
    heat_map: bool,
    lists: Option<ClusterLists<'a>>,
    settings: ShadingSettings,
) -> FrameDesc<'a> {
    FrameDesc {
        camera: &scene.camera,
        grid,
        mode: shading.mode(),
        heat_map,
        lights: Some(light_columns(&scene.lights)),
        lists,
        settings,
    }
}

/// What one frame did.
#[derive(Clone, Copy, Debug)]
pub struct ViewerFrame {
    /// CPU seconds of the light assignment (0 for brute force).
    pub assign_seconds: f64,
    /// The assignment's statistics (`None` for brute force).
    pub stats: Option<AssignStats>,
    /// Upload and encode report.
    pub report: FrameReport,
    /// The grid the frame was shaded with.
    pub grid: ClusterGrid,
}

/// A scene on a GPU context with a headless target of the camera's size.
pub struct Viewer {
    /// The device.
    pub ctx: GpuContext,
    /// The renderer.
    pub renderer: Renderer,
    /// The uploaded geometry.
    pub scene: GpuScene,
    /// Where frames go.
    pub target: HeadlessTarget,
    pub(super) assigner: Assigner,
    pub(super) lists: LightLists,
    /// Look settings for every frame.
    pub settings: ShadingSettings,
    pub(super) skip_state: super::skips::SkipState,
}

impl Viewer {
    /// Uploads `scene`'s geometry and makes a target of its camera's size.
    pub fn new(ctx: GpuContext, scene: &RenderScene) -> Result<Self> {
        let renderer = Renderer::try_new(&ctx, HEADLESS_FORMAT)?;
        // A model's texture larger than the device samples is scaled down, with a warning.
        let max_side = ctx.device.limits().max_texture_dimension_2d;
        let too_large = |t: &TextureRgba8| t.width.max(t.height) > max_side;
        let fitted = scene.geometry.textures.iter().any(too_large).then(|| {
            let mut geometry = scene.geometry.clone();
            for note in geometry.fit_textures(max_side) {
                eprintln!("warning: {}: {note}", scene.name);
            }
            geometry
        });
        let geometry = fitted.as_ref().unwrap_or(&scene.geometry);
        let gpu_scene = renderer.upload_scene(&ctx, geometry)?;
        let target = HeadlessTarget::new(&ctx.device, scene.camera.width, scene.camera.height)?;
        // Lists past what the device binds are built on a coarser grid rather than refused.
        let assigner = Assigner::new().with_pair_budget(ctx.max_list_pairs());
        Ok(Self {
            ctx,
            renderer,
            scene: gpu_scene,
            target,
            assigner,
            lists: LightLists::new(),
            settings: ShadingSettings::default(),
            skip_state: Default::default(),
        })
    }

    /// Caps the lists at `pairs` cluster–light pairs (and never past what the device binds,
    /// [`GpuContext::max_list_pairs`], the default): past the cap a frame's lists are built on a
    /// coarser grid ([`myriad_assignment::Assigner::with_pair_budget`]), no light dropped.
    pub fn set_pair_budget(&mut self, pairs: u64) {
        self.assigner = Assigner::new().with_pair_budget(pairs.min(self.ctx.max_list_pairs()));
    }

    /// Builds the pipelines [`Viewer::frame`] will use for `shading` and `heat_map` ahead of it
    /// ([`Renderer::prepare`]), so that frame's encoding compiles no shaders; returns how many it
    /// built. The main job calls it before each strategy's frames: brute force's one timed frame
    /// on a slow machine is its warm-up, which would otherwise carry the compilation. An error
    /// where the device was lost, or where the viewer's public `ctx`, `renderer` or `scene` were
    /// replaced by another device's.
    pub fn prepare(
        &mut self,
        scene: &RenderScene,
        shading: Shading,
        heat_map: bool,
    ) -> Result<usize> {
        let grid = shading.grid(&scene.grid);
        let frame = frame_desc(scene, &grid, shading, heat_map, None, self.settings);
        Ok(self.renderer.prepare(&self.ctx, &self.scene, &frame)?)
    }

    /// Assigns (unless brute force), uploads and submits one frame; does not wait for the GPU.
    /// Lists past what the device binds in one buffer ([`GpuContext::max_list_pairs`]) are built
    /// on a coarser grid (`coarser_grid`, until they fit; no light is dropped), which the frame
    /// is shaded with: [`ViewerFrame::grid`] is that grid and `stats` says how often it halved.
    /// The budget covers the light indices only: a grid whose per-cluster offsets or counts,
    /// or lights whose records, pass the device's buffers is refused
    /// ([`myriad_gpu::GpuError::BufferTooLarge`]) after the assignment.
    pub fn frame(
        &mut self,
        scene: &RenderScene,
        shading: Shading,
        method: Method,
        heat_map: bool,
    ) -> Result<ViewerFrame> {
        let mut grid = shading.grid(&scene.grid);
        let (mut assign_seconds, mut stats) = (0.0, None);
        if shading != Shading::BruteForce {
            crate::profile_span!("viewer: assign");
            let start = Instant::now();
            // `try_`: a camera the assignment cannot use is the frame's error, not a panic
            // (near 0 panicked here, audit).
            let s = self.assigner.try_assign(
                method,
                &light_input(&scene.lights),
                &scene.camera,
                &grid,
                &mut self.lists,
            )?;
            assign_seconds = start.elapsed().as_secs_f64();
            grid = s.grid_built(&grid);
            stats = Some(s);
        }
        let lists = (shading != Shading::BruteForce).then(|| cluster_lists(&self.lists));
        let frame = frame_desc(scene, &grid, shading, heat_map, lists, self.settings);
        let report = self
            .renderer
            .render(&self.ctx, &self.scene, &frame, &self.target.view)?;
        crate::profiling::plot_frame_load(
            stats.map_or(scene.lights.len() as u64, |s| u64::from(s.visible())),
            stats.map(|s| s.pairs),
            report.upload_bytes,
        );
        crate::profiling::frame_mark();
        Ok(ViewerFrame {
            assign_seconds,
            stats,
            report,
            grid,
        })
    }

    /// The viewer's device, renderer, geometry, target and settings as the GPU side of
    /// [`super::run_frames`]' loop.
    pub fn gpu_stage(&mut self) -> super::GpuStage<'_> {
        super::GpuStage {
            ctx: &self.ctx,
            renderer: &mut self.renderer,
            scene: &self.scene,
            target: &self.target,
            settings: self.settings,
        }
    }

    /// The target's pixels (RGBA8, sRGB), after the GPU has finished.
    pub fn image(&self) -> Result<Vec<u8>> {
        Ok(myriad_gpu::read_rgba8(&self.ctx, &self.target.texture)?)
    }

    /// The lists the last frame assigned — also when the renderer then refused that frame, so
    /// after an error they may not be what the GPU holds.
    pub fn lists(&self) -> &LightLists {
        &self.lists
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use myriad_scene::glam::UVec3;

    /// Reports and file names tell the strategies apart by these names.
    #[test]
    fn each_strategy_has_its_own_name() {
        let names: Vec<_> = Shading::ALL.iter().map(|s| s.name()).collect();
        assert_eq!(names, ["clustered", "tiled", "brute force"]);
    }

    /// Tiled shading assigns to the scene grid's tiles with one depth slice over the same range;
    /// clustered and brute force keep the scene grid.
    #[test]
    fn tiles_are_the_grid_with_one_slice() {
        let scene = ClusterGrid::new(UVec3::new(24, 12, 16), DepthSlicing::Log, 0.5, 80.0);
        let tiles = Shading::Tiled.grid(&scene);
        assert_eq!(tiles.dims(), UVec3::new(24, 12, 1));
        assert_eq!(tiles.slicing(), DepthSlicing::Linear);
        assert_eq!((tiles.near(), tiles.far()), (0.5, 80.0));
        assert_eq!(Shading::Clustered.grid(&scene), scene);
        assert_eq!(Shading::BruteForce.grid(&scene), scene);
    }
}
