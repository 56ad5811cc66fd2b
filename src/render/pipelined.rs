//! The frame loop, two ways, so one measurement can show what pipelining buys:
//!
//! * **sequential** — per frame, on one thread: animate the lights, cull, assign, upload, render,
//!   wait for the GPU;
//! * **pipelined** — a worker thread animates, culls and assigns frame N+1 while the main thread
//!   uploads and renders frame N. The two talk over crossbeam channels: the worker sends finished
//!   frames (lights + lists) on a bounded channel, the main thread sends the buffers back once
//!   the GPU has copied them, so after the first frames nothing is allocated and at most
//!   [`FRAMES_IN_FLIGHT`] frames exist at once. The GPU side uploads through the renderer's
//!   staging ring.
//!
//! Both produce the same frames (the lights at frame N depend only on N), so the images match;
//! `tests/gpu_pipeline.rs` checks that. With `cull` (the scene systems' frustum cull,
//! [`cull_lights`]) only the lights that may touch the view are gathered, assigned and uploaded:
//! the ECS-style frame of ARCHITECTURE.md, animate → cull → assign → upload. The assignment
//! drops an outside light in its first test anyway; what the cull saves is the upload (at 100k
//! orbiting lights in the atrium a quarter of the lights, 9% of the bytes: the lists are most of
//! them) and the GPU's copies of it. The per-stage times are what each stage took; the
//! frame time is the wall time from one frame end to the next (the first frame, which builds
//! pipelines and buffers, left out).

use super::setup::RenderScene;
use super::viewer::{cluster_lists, light_columns};
use crate::light_input;
use anyhow::{Context, Result};
use crossbeam::channel;
use myriad_assignment::{AssignStats, Assigner, LightLists, Method};
use myriad_gpu::{
    FrameDesc, GpuContext, GpuScene, HeadlessTarget, PassTimes, Renderer, ShadingSettings,
};
use myriad_scene::Lights;
use myriad_scene::systems::{Orbits, Visibility, animate_orbits, cull_lights};
use std::time::Instant;

/// Frames the worker may be ahead of the renderer (buffer sets in circulation).
pub const FRAMES_IN_FLIGHT: usize = 2;

/// Seconds of animation between frames. Frame times are f64 (`index · FRAME_DT`): an f32 time
/// stops advancing at 2²⁴ frames (78 hours at 60 fps).
const FRAME_DT: f64 = 1.0 / 60.0;

/// What one frame's stages took.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimes {
    /// CPU: animating the lights.
    pub animate_seconds: f64,
    /// CPU: frustum cull and gather of the visible lights (0 without `cull`).
    pub cull_seconds: f64,
    /// Lights assigned and uploaded (the visible ones with `cull`).
    pub lights_uploaded: usize,
    /// Lights skipped as invalid (a position or radius that is not finite, a radius that is not
    /// positive): dropped and counted by the cull ([`Visibility::invalid`]) with `cull`, by the
    /// assignment (its `rejected`) without it. Never uploaded.
    pub lights_invalid: usize,
    /// CPU: light assignment.
    pub assign_seconds: f64,
    /// CPU: converting and staging lights and lists.
    pub upload_seconds: f64,
    /// Bytes staged.
    pub upload_bytes: u64,
    /// CPU: encoding and submitting.
    pub encode_seconds: f64,
    /// Waiting for the GPU to finish the frame.
    pub gpu_wait_seconds: f64,
    /// GPU pass times from timestamps, where available.
    pub gpu_passes: Option<PassTimes>,
    /// Cluster–light pairs.
    pub pairs: u64,
    /// The grid the lists were built and shaded on: the scene's, or a coarser one where they
    /// held more pairs than the device binds in one buffer ([`GpuContext::max_list_pairs`]).
    pub grid_dims: [u32; 3],
}

impl StageTimes {
    /// Sum of the stages (what a frame costs when nothing overlaps).
    pub fn sum_seconds(&self) -> f64 {
        self.animate_seconds
            + self.cull_seconds
            + self.assign_seconds
            + self.upload_seconds
            + self.encode_seconds
            + self.gpu_wait_seconds
    }
}

/// A run of frames.
#[derive(Clone, Debug, Default)]
pub struct LoopReport {
    /// Whether assignment ran on the worker.
    pub pipelined: bool,
    /// Whether lights were culled before assignment and upload.
    pub culled: bool,
    /// Per frame.
    pub frames: Vec<StageTimes>,
    /// Wall seconds for all frames.
    pub wall_seconds: f64,
    /// When each frame finished (GPU idle), seconds since the loop started.
    pub finished_at: Vec<f64>,
}

impl LoopReport {
    /// Wall time per frame.
    pub fn frame_seconds(&self) -> f64 {
        self.wall_seconds / self.frames.len().max(1) as f64
    }

    /// Wall time per frame after the first (which builds pipelines and buffers): the steady
    /// state, from the end of frame 0 to the end of the last frame.
    pub fn steady_frame_seconds(&self) -> Option<f64> {
        let (first, last) = (self.finished_at.first()?, self.finished_at.last()?);
        (self.finished_at.len() >= 2).then(|| (last - first) / (self.finished_at.len() - 1) as f64)
    }

    /// Mean of a stage over the frames.
    pub fn mean(&self, stage: impl Fn(&StageTimes) -> f64) -> f64 {
        self.frames.iter().map(stage).sum::<f64>() / self.frames.len().max(1) as f64
    }
}

/// The lights of one frame with their lists, travelling between the threads.
struct FrameWork {
    index: usize,
    lights: Lights,
    /// The visible lights, gathered (with `cull`).
    visible: Lights,
    culled: bool,
    /// Lights the cull dropped as invalid (0 without `cull`).
    culled_invalid: usize,
    lists: LightLists,
    stats: AssignStats,
    animate_seconds: f64,
    cull_seconds: f64,
    assign_seconds: f64,
}

impl FrameWork {
    /// The lights the lists index: what the frame assigns and uploads.
    fn assigned(&self) -> &Lights {
        if self.culled {
            &self.visible
        } else {
            &self.lights
        }
    }
}

/// Animates lights and assigns them: the CPU half of a frame, owned by whichever thread runs it.
struct CpuStage<'a> {
    scene: &'a RenderScene,
    orbits: Orbits,
    assigner: Assigner,
    method: Method,
    /// `Some` to cull: the cull's output, reused frame to frame.
    visibility: Option<Visibility>,
}

impl<'a> CpuStage<'a> {
    /// `max_pairs`: the device's [`GpuContext::max_list_pairs`], past which a frame's lists are
    /// built on a coarser grid.
    fn new(scene: &'a RenderScene, method: Method, cull: bool, max_pairs: u64) -> Self {
        let center = scene.camera.target;
        let orbits = Orbits::around(center, &scene.lights.x, &scene.lights.z, [0.1, 0.5], 7);
        Self {
            scene,
            orbits,
            assigner: Assigner::new().with_pair_budget(max_pairs),
            method,
            visibility: cull.then(Visibility::new),
        }
    }

    /// Fills `work` with frame `index`: lights at time `index·dt`, and their lists.
    fn run(&mut self, index: usize, work: &mut FrameWork) {
        crate::profile_span!("cpu stage: animate and assign");
        let start = Instant::now();
        work.index = index;
        // Only x and z move, and orbits are absolute in time: a buffer copies the scene's lights
        // once and is then rewritten in those two columns (a copy of every column each frame
        // cost 1.2 ms at 100k lights against 0.2 ms of animation, and was timed as "animate").
        if work.lights.len() != self.scene.lights.len() {
            work.lights.clone_from(&self.scene.lights);
        }
        let lights = &mut work.lights;
        animate_orbits(
            &self.orbits,
            index as f64 * FRAME_DT,
            &mut lights.x,
            &mut lights.z,
        );
        work.animate_seconds = start.elapsed().as_secs_f64();
        work.culled = self.visibility.is_some();
        work.cull_seconds = 0.0;
        work.culled_invalid = 0;
        if let Some(visibility) = &mut self.visibility {
            let start = Instant::now();
            cull_lights(&self.scene.camera, work.lights.slices(), visibility);
            work.culled_invalid = visibility.invalid();
            crate::profile_span!("gather visible lights");
            work.lights
                .gather_into(&visibility.indices, &mut work.visible);
            work.cull_seconds = start.elapsed().as_secs_f64();
        }
        let start = Instant::now();
        let assigned = if work.culled {
            &work.visible
        } else {
            &work.lights
        };
        work.stats = self.assigner.assign(
            self.method,
            &light_input(assigned),
            &self.scene.camera,
            &self.scene.grid,
            &mut work.lists,
        );
        work.assign_seconds = start.elapsed().as_secs_f64();
    }
}

fn empty_work() -> FrameWork {
    FrameWork {
        index: 0,
        lights: Lights::new(),
        visible: Lights::new(),
        culled: false,
        culled_invalid: 0,
        lists: LightLists::new(),
        stats: AssignStats::default(),
        animate_seconds: 0.0,
        cull_seconds: 0.0,
        assign_seconds: 0.0,
    }
}

/// The GPU half of a frame.
pub struct GpuStage<'a> {
    /// The device.
    pub ctx: &'a GpuContext,
    /// The renderer.
    pub renderer: &'a mut Renderer,
    /// The geometry.
    pub scene: &'a GpuScene,
    /// The target.
    pub target: &'a HeadlessTarget,
    /// Look.
    pub settings: ShadingSettings,
}

impl GpuStage<'_> {
    /// Uploads, renders and waits for frame `work`.
    fn run(&mut self, scene: &RenderScene, work: &FrameWork) -> Result<StageTimes> {
        let grid = work.stats.grid_built(&scene.grid);
        let frame = FrameDesc {
            settings: self.settings,
            ..FrameDesc::clustered(
                &scene.camera,
                &grid,
                light_columns(work.assigned()),
                cluster_lists(&work.lists),
            )
        };
        let report = self
            .renderer
            .render(self.ctx, self.scene, &frame, &self.target.view)?;
        crate::profiling::plot_frame_load(
            u64::from(work.stats.visible()),
            Some(work.stats.pairs),
            report.upload_bytes,
        );
        let start = Instant::now();
        crate::profile_span!("wait for GPU");
        self.ctx.wait_idle()?;
        let gpu_wait_seconds = start.elapsed().as_secs_f64();
        let gpu_passes = self.renderer.last_pass_times(self.ctx)?;
        crate::profiling::plot_pass_times(gpu_passes.as_ref());
        Ok(StageTimes {
            animate_seconds: work.animate_seconds,
            cull_seconds: work.cull_seconds,
            lights_uploaded: work.assigned().len(),
            lights_invalid: work.culled_invalid + work.stats.rejected as usize,
            assign_seconds: work.assign_seconds,
            upload_seconds: report.upload_seconds,
            upload_bytes: report.upload_bytes,
            encode_seconds: report.encode_seconds,
            gpu_wait_seconds,
            gpu_passes,
            pairs: work.stats.pairs,
            grid_dims: grid.dims().to_array(),
        })
    }
}

/// Runs `frames` frames of `scene` with its lights orbiting the camera's target, frustum-culled
/// before assignment and upload when `cull`. `on_frame` sees each finished frame's index (the
/// target holds its image), e.g. to read it back. As [`Viewer::frame`](super::Viewer::frame),
/// lists past what the device binds in one buffer are built and shaded on a coarser grid
/// ([`StageTimes::grid_dims`]).
///
/// The sequential loop assigns on the rayon pool current where it is called. The pipelined
/// loop's CPU stage runs on its own thread, whose assignment uses rayon's **global** pool: rayon
/// gives no handle to "the pool the caller is installed in" that another thread could enter. An
/// engine that confines myriad to its own pool runs the sequential loop there, or the assigner
/// itself on its own job system (`examples/engine_integration.rs`).
pub fn run_frames(
    gpu: &mut GpuStage<'_>,
    scene: &RenderScene,
    method: Method,
    frames: usize,
    pipelined: bool,
    cull: bool,
    mut on_frame: impl FnMut(usize, &GpuStage<'_>) -> Result<()>,
) -> Result<LoopReport> {
    let mut report = LoopReport {
        pipelined,
        culled: cull,
        ..Default::default()
    };
    // The loop's camera and grid never change: checked once here, as the CPU stage's assignment
    // would otherwise panic on them (on its worker thread, in the pipelined loop).
    myriad_assignment::Assigner::check_frame(
        &light_input(&scene.lights),
        &scene.camera,
        &scene.grid,
    )?;
    let max_pairs = gpu.ctx.max_list_pairs();
    let start = Instant::now();
    if !pipelined {
        let mut cpu = CpuStage::new(scene, method, cull, max_pairs);
        let mut work = empty_work();
        for index in 0..frames {
            cpu.run(index, &mut work);
            report.frames.push(gpu.run(scene, &work)?);
            report.finished_at.push(start.elapsed().as_secs_f64());
            crate::profiling::frame_mark();
            on_frame(index, gpu)?;
        }
    } else {
        std::thread::scope(|s| -> Result<()> {
            // Created inside the scope so that, should rendering fail, both ends the main
            // thread holds are dropped before the scope joins the worker, which then stops.
            let (ready_tx, ready_rx) = channel::bounded::<FrameWork>(FRAMES_IN_FLIGHT);
            let (free_tx, free_rx) = channel::bounded::<FrameWork>(FRAMES_IN_FLIGHT);
            for _ in 0..FRAMES_IN_FLIGHT {
                free_tx.send(empty_work()).expect("channel has room");
            }
            // Named, so Tracy and debuggers tell it from the rayon workers it hands jobs to: for
            // the OS, and told to Tracy too, which otherwise reads the OS name only when the
            // profiler asks, and finds none once the thread has ended (a short capture showed
            // it as a number: `tests/tracy_capture`).
            std::thread::Builder::new()
                .name("cpu stage".into())
                .spawn_scoped(s, move || {
                    crate::profiling::name_this_thread("cpu stage");
                    let mut cpu = CpuStage::new(scene, method, cull, max_pairs);
                    for index in 0..frames {
                        // The renderer hung up (an error): stop.
                        let Ok(mut work) = free_rx.recv() else { return };
                        cpu.run(index, &mut work);
                        if ready_tx.send(work).is_err() {
                            return;
                        }
                    }
                })
                .context("cannot start the assignment worker")?;
            for index in 0..frames {
                let work = ready_rx
                    .recv()
                    .context("the assignment worker stopped early")?;
                debug_assert_eq!(work.index, index);
                report.frames.push(gpu.run(scene, &work)?);
                report.finished_at.push(start.elapsed().as_secs_f64());
                crate::profiling::frame_mark();
                on_frame(index, gpu)?;
                // The GPU has copied this frame's data: its buffers can carry another frame.
                let _ = free_tx.send(work);
            }
            Ok(())
        })?;
    }
    report.wall_seconds = start.elapsed().as_secs_f64();
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// After its first frame a buffer is animated in place: columns that do not move keep what
    /// the buffer holds (no copy of every column per frame), and the moving ones equal a fresh
    /// buffer's.
    #[test]
    fn the_cpu_stage_rewrites_only_the_animated_columns() {
        let scene = RenderScene::default_scene(2000, 64, 32).unwrap();
        let mut cpu = CpuStage::new(&scene, Method::Refined, false, u64::MAX);
        let mut work = empty_work();
        cpu.run(4, &mut work);
        work.lights.intensity[7] = -1.0;
        cpu.run(5, &mut work);
        assert_eq!(
            work.lights.intensity[7], -1.0,
            "the frame copied the scene's lights again"
        );
        let mut fresh = empty_work();
        cpu.run(5, &mut fresh);
        assert_eq!(
            (&work.lights.x, &work.lights.z),
            (&fresh.lights.x, &fresh.lights.z)
        );
        assert_ne!(work.lights.x, scene.lights.x, "frame 5 moved the lights");
    }

    /// Past 2²⁴ frames an f32 frame time stops advancing: the lights must still move.
    #[test]
    fn lights_keep_moving_past_two_to_the_24_frames() {
        let scene = RenderScene::default_scene(2000, 64, 32).unwrap();
        let mut cpu = CpuStage::new(&scene, Method::Refined, false, u64::MAX);
        let (mut a, mut b) = (empty_work(), empty_work());
        let frame = (1 << 24) + 1;
        cpu.run(frame, &mut a);
        cpu.run(frame + 1, &mut b);
        let moved = (0..scene.lights.len())
            .filter(|&i| (a.lights.x[i], a.lights.z[i]) != (b.lights.x[i], b.lights.z[i]))
            .count();
        assert!(moved > scene.lights.len() / 2, "{moved} lights moved");
    }

    /// Frame N shows the lights at N / 60 s: frame 60 equals the scene systems' orbits animated
    /// to one second.
    #[test]
    fn frame_sixty_is_one_second_of_orbiting() {
        let scene = RenderScene::default_scene(2000, 64, 32).unwrap();
        let mut cpu = CpuStage::new(&scene, Method::Refined, false, u64::MAX);
        let mut work = empty_work();
        cpu.run(60, &mut work);
        let (mut x, mut z) = (scene.lights.x.clone(), scene.lights.z.clone());
        animate_orbits(&cpu.orbits, 1.0, &mut x, &mut z);
        for i in 0..scene.lights.len() {
            let off = (work.lights.x[i] - x[i])
                .abs()
                .max((work.lights.z[i] - z[i]).abs());
            assert!(off < 1e-4, "light {i} is {off} m from its place at 1 s");
        }
        assert_ne!(x, scene.lights.x, "one second moved the lights");
    }

    /// A frame's stage sum adds each of the six timed stages once; a loop's frame time is its
    /// wall time per frame, its steady frame time the span from the first frame's end to the last
    /// one's per frame after the first, and a stage's mean is over the frames.
    #[test]
    fn loop_times_are_sums_spans_and_means_over_frames() {
        // Powers of two: a stage dropped, subtracted or multiplied changes the sum.
        let frame = |s: f64| StageTimes {
            animate_seconds: s,
            cull_seconds: 2.0 * s,
            assign_seconds: 4.0 * s,
            upload_seconds: 8.0 * s,
            encode_seconds: 16.0 * s,
            gpu_wait_seconds: 32.0 * s,
            ..StageTimes::default()
        };
        assert_eq!(frame(1.0).sum_seconds(), 63.0);
        let report = LoopReport {
            frames: vec![frame(1.0), frame(2.0), frame(3.0), frame(6.0)],
            wall_seconds: 2.0,
            finished_at: vec![1.0, 1.5, 2.5, 4.0],
            ..LoopReport::default()
        };
        assert_eq!(report.frame_seconds(), 0.5);
        assert_eq!(report.steady_frame_seconds(), Some(1.0));
        assert_eq!(report.mean(|f| f.animate_seconds), 3.0);
        let one_frame = LoopReport {
            finished_at: vec![1.0],
            ..report
        };
        assert_eq!(
            one_frame.steady_frame_seconds(),
            None,
            "no span after one frame"
        );
    }
}
