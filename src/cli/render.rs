//! `myriad render` and the main job: render a scene headless with clustered, tiled and
//! brute-force deferred shading, write the lit image, the heat map and the numbers.

use super::assign::parse_method;
use super::grid_options::{check_slicing, parse_grid, parse_slicing};
use super::pair_budget::device_coarsened_warning;
use super::progress::Progress;
use super::render_skipping::{self, WithSkips};
use super::source::{check_memory, check_memory_for};
use anyhow::{Context, Result, bail};
use myriad::assignment::Method;
use myriad::cluster_math::ClusterGrid;
use myriad::cluster_math::glam::UVec3;
use myriad::gpu::legend::with_heat_legend;
use myriad::gpu::{FrameReport, GpuContext, GpuError, PassTimes, encode_png};
use myriad::render::{
    DEFAULT_GRID, PixelStats, RenderScene, Shading, Skips, Viewer, max_channel_difference,
    pixel_stats,
};
use myriad::scene::{LoadOptions, check_replaceable, replace_files};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// glTF model to render (.gltf or .glb) [default: the generated atrium].
    #[arg(long)]
    gltf: Option<PathBuf>,
    /// Take camera, grid and lights from this scene file, drawn in the model's geometry.
    #[arg(long, conflicts_with_all = ["preset", "camera", "lights", "seed"])]
    scene: Option<PathBuf>,
    /// Take camera, grid and lights from a standard preset (paper, uniform, sphere), drawn in the
    /// model's geometry (the `paper` courtyard matches the atrium's size).
    #[arg(long, conflicts_with_all = ["camera"])]
    preset: Option<String>,
    /// The model's camera, by name [default: its first].
    #[arg(long)]
    camera: Option<String>,
    /// Lights: the model's own, then lights on its surfaces up to this many (with --preset: the
    /// preset's lights) [default: 1000].
    #[arg(long, value_parser = super::light_count)]
    lights: Option<usize>,
    /// Seed of the generated lights [default: 1].
    #[arg(long)]
    seed: Option<u64>,
    /// Assignment method: exact, linear, binary, refined or cone.
    #[arg(long, default_value = "refined")]
    method: String,
    /// Cluster grid XxYxZ [default: 24x12x16, or the scene's].
    #[arg(long)]
    grid: Option<String>,
    /// Depth slicing: log, linear or log_near:D (a first slice to D metres, then log slices)
    /// [default: log, or the scene's].
    #[arg(long)]
    depth: Option<String>,
    /// Image size WxH [default: 1536x768, or the scene's camera].
    #[arg(long)]
    size: Option<String>,
    /// Output folder for frame.png, heatmap.png and stats.json.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Timed frames per shading strategy, after a warm-up frame (the median is reported; fewer
    /// once a strategy's frames pass 20 s, and a warm-up that alone takes 20 s is the one).
    #[arg(long, value_parser = super::run_count, default_value_t = 5)]
    runs: usize,
    /// Savings for the `clustered+skips` column: "none" (no such column), "all", or a comma
    /// list of cull, active, depth, reuse, variants (see `myriad skips`), and "tune" to keep
    /// active and depth only if timed frames show that their depth prepass pays [default: all
    /// but reuse, which would turn the repeated frames of a still scene into no work at all].
    #[arg(long)]
    skips: Option<Skips>,
}

impl Default for Args {
    fn default() -> Self {
        Self {
            gltf: None,
            scene: None,
            preset: None,
            camera: None,
            lights: None,
            seed: None,
            method: "refined".into(),
            grid: None,
            depth: None,
            size: None,
            out: "out".into(),
            runs: 5,
            skips: None,
        }
    }
}

/// `"1536x768"` as (width, height).
pub fn parse_size(text: &str) -> Result<(u32, u32)> {
    match text
        .split_once('x')
        .map(|(w, h)| (w.parse::<u32>(), h.parse::<u32>()))
    {
        Some((Ok(w), Ok(h))) if (1..=16384).contains(&w) && (1..=16384).contains(&h) => Ok((w, h)),
        _ => bail!("--size {text:?}: expected WxH with each side in 1..=16384, e.g. 1536x768"),
    }
}

/// Median stage times of one shading strategy.
#[derive(Serialize, Debug, Clone)]
pub(super) struct StrategyResult {
    pub shading: &'static str,
    pub frames: usize,
    /// The one timed frame was the warm-up (a frame over the time budget, see
    /// [`timed_frames`]); its pipelines were built before it all the same.
    pub warm_up_timed: bool,
    /// Pipelines its frames built while encoding, the warm-up's included: 0 where they were
    /// prepared ahead ([`Viewer::prepare`]), as the main job does for each strategy it compares.
    pub pipelines_built_in_frames: usize,
    pub assign_ms: f64,
    pub upload_bytes: u64,
    pub upload_ms: f64,
    pub encode_ms: f64,
    /// The upload's buffer copies on the GPU (timestamps between commands, where the adapter has
    /// them).
    pub gpu_upload_ms: Option<f64>,
    pub gpu_gbuffer_ms: Option<f64>,
    pub gpu_shading_ms: Option<f64>,
    pub gpu_forward_ms: Option<f64>,
    /// Submit to GPU idle, wall clock.
    pub gpu_frame_wall_ms: f64,
    pub pairs: u64,
    /// The grid the frames were shaded with: the scene's (its tiles' for tiled), or a coarser
    /// one where the lists held more pairs than the device binds in one buffer
    /// (`GpuContext::max_list_pairs`; a warning says so).
    pub grid: [u32; 3],
    /// Whether `grid` is coarser than the one asked for.
    pub grid_coarsened: bool,
    pub pixels: PixelStats,
}

#[derive(Serialize, Debug)]
struct Stats {
    scene: String,
    adapter: String,
    timestamps: bool,
    width: u32,
    height: u32,
    grid: [u32; 3],
    method: String,
    lights: usize,
    /// Invalid lights in the `--scene` file, skipped when it was loaded (listed on stderr).
    lights_skipped_in_file: usize,
    lights_rejected: u32,
    lights_culled: u32,
    strategies: Vec<StrategyResult>,
    /// Baselines (tiled, brute force) the adapter refused to draw, with the reason: a pixel
    /// would loop over more lights than its shaders may (llvmpipe's loop limit). Clustered
    /// shading is never skipped: its refusal fails the run.
    skipped: Vec<SkippedStrategy>,
    speedup_vs_brute_force: Option<f64>,
    /// What the speedup compares: `"shading pass"` (the passes' GPU timestamps) or, on an
    /// adapter without timestamps, `"frame wall"` (submit to idle, the G-buffer and every other
    /// pass included).
    speedup_measure: &'static str,
    /// The largest channel difference (of 255) of each strategy's lit image from brute force's,
    /// which shades every light with every pixel: a light a strategy's lists missed, or a pixel
    /// placed in the wrong cluster, shows here. The run fails above 1 (float rounding). `None`
    /// where brute force was skipped.
    max_difference_from_brute_force: Option<std::collections::BTreeMap<&'static str, u8>>,
    /// Clustered shading with savings (`--skips`), beside the three strategies.
    with_skips: Option<WithSkips>,
}

/// The most a strategy's image may differ from brute force's, per channel (of 255): the lights
/// are summed in the same order, so only the GPU's rounding differs.
const MAX_DIFFERENCE_FROM_BRUTE_FORCE: u8 = 1;

#[derive(Serialize, Debug)]
struct SkippedStrategy {
    shading: &'static str,
    reason: String,
}

/// Whether `e` is the renderer refusing a frame for the adapter's shader loop limit.
fn is_loop_limit(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        matches!(
            c.downcast_ref::<GpuError>(),
            Some(GpuError::ShaderLoopLimit { .. })
        )
    })
}

fn median(mut v: Vec<f64>) -> f64 {
    myriad::evaluate::median(&mut v)
}

fn median_opt(v: Vec<Option<f64>>) -> Option<f64> {
    let v: Vec<f64> = v.into_iter().flatten().collect();
    (!v.is_empty()).then(|| median(v))
}

/// Time of frames per strategy after which no further timed frame is rendered.
const FRAMES_BUDGET: Duration = Duration::from_secs(20);

/// The frames of one strategy (its pipelines built before, [`Viewer::prepare`]): a warm-up
/// frame first touches the buffers and the driver's state, then `runs` timed frames, fewer once
/// [`FRAMES_BUDGET`] has passed (at least one). `frame()` renders one frame and records its
/// samples, the warm-up's too; the result is how many leading frames to drop from them: the
/// warm-up (1), or none (0) when the warm-up alone took the whole budget. A frame that slow —
/// brute force on the CI's software rasteriser: ~52 s at 1536×768 and 1000 lights — is its own
/// sample: what a warm-up adds (buffers grown and touched for the first time) is far under a
/// percent of it, the passes are timed on the GPU, and one more such frame had doubled the main
/// job's brute-force column (107 of its 141 s).
pub(super) fn timed_frames(
    name: &str,
    runs: usize,
    progress: &Progress,
    frame: impl FnMut() -> Result<()>,
) -> Result<usize> {
    frames_within(FRAMES_BUDGET, name, runs, progress, frame)
}

/// [`timed_frames`] with a budget of `budget`.
fn frames_within(
    budget: Duration,
    name: &str,
    runs: usize,
    progress: &Progress,
    mut frame: impl FnMut() -> Result<()>,
) -> Result<usize> {
    let started = Instant::now();
    let over_budget = || started.elapsed() > budget;
    progress.start(&format!("{name}: warm-up frame"));
    frame()?;
    if over_budget() {
        return Ok(0);
    }
    for run in 1..=runs {
        // Not over after the warm-up, so the first timed frame always runs.
        if over_budget() {
            break;
        }
        progress.start(&format!("{name}: frame {run} of {runs}"));
        frame()?;
    }
    Ok(1)
}

/// Per-frame samples of one strategy, to medians.
pub(super) struct FrameSamples {
    /// The renderer's pipeline count before the first frame ([`Renderer::pipelines_built`]).
    ///
    /// [`Renderer::pipelines_built`]: myriad::gpu::Renderer::pipelines_built
    pipelines_before: usize,
    /// The renderer's pipeline count after the last frame recorded.
    pipelines_after: usize,
    assign: Vec<f64>,
    upload: Vec<f64>,
    encode: Vec<f64>,
    wall: Vec<f64>,
    /// Per frame, where the adapter timed its passes.
    passes: Vec<Option<PassTimes>>,
    /// The samples are the warm-up frame's.
    warm_up_timed: bool,
}

impl FrameSamples {
    /// No samples yet; the frames to come render with `viewer`.
    pub fn new(viewer: &Viewer) -> Self {
        let pipelines = viewer.renderer.pipelines_built();
        Self {
            pipelines_before: pipelines,
            pipelines_after: pipelines,
            assign: Vec::new(),
            upload: Vec::new(),
            encode: Vec::new(),
            wall: Vec::new(),
            passes: Vec::new(),
            warm_up_timed: false,
        }
    }

    /// Waits for the frame just submitted and records it: `cpu_seconds` of light assignment, its
    /// upload report, submit to idle (wall clock) and the GPU's pass times.
    pub fn wait_and_record(
        &mut self,
        viewer: &Viewer,
        cpu_seconds: f64,
        report: &FrameReport,
    ) -> Result<()> {
        let t = Instant::now();
        {
            myriad::profile_span!("wait for GPU");
            viewer.ctx.wait_idle()?;
        }
        self.assign.push(cpu_seconds * 1e3);
        self.upload.push(report.upload_seconds * 1e3);
        self.encode.push(report.encode_seconds * 1e3);
        self.wall
            .push((t.elapsed().as_secs_f64() + report.encode_seconds) * 1e3);
        let passes = viewer.renderer.last_pass_times(&viewer.ctx)?;
        myriad::profiling::plot_pass_times(passes.as_ref());
        self.passes.push(passes);
        self.pipelines_after = viewer.renderer.pipelines_built();
        Ok(())
    }

    /// Forgets the first `warm_ups` frames recorded, as [`timed_frames`] says: the warm-up, or
    /// none when the warm-up is the timed frame.
    pub fn drop_warm_ups(&mut self, warm_ups: usize) {
        self.assign.drain(..warm_ups);
        self.upload.drain(..warm_ups);
        self.encode.drain(..warm_ups);
        self.wall.drain(..warm_ups);
        self.passes.drain(..warm_ups);
        self.warm_up_timed = warm_ups == 0;
    }

    /// The medians, with what the last frame uploaded and assigned.
    pub fn result(
        self,
        shading: &'static str,
        upload_bytes: u64,
        pairs: u64,
        [requested, grid]: [&ClusterGrid; 2],
        pixels: PixelStats,
    ) -> StrategyResult {
        let passes = |f: fn(&PassTimes) -> Option<f64>| {
            median_opt(self.passes.iter().flatten().map(f).collect())
        };
        StrategyResult {
            shading,
            frames: self.wall.len(),
            warm_up_timed: self.warm_up_timed,
            pipelines_built_in_frames: self.pipelines_after - self.pipelines_before,
            assign_ms: median(self.assign.clone()),
            upload_bytes,
            upload_ms: median(self.upload.clone()),
            encode_ms: median(self.encode.clone()),
            gpu_upload_ms: passes(|p| p.upload_ms),
            gpu_gbuffer_ms: passes(|p| p.gbuffer_ms),
            gpu_shading_ms: passes(|p| p.shading_ms),
            gpu_forward_ms: passes(|p| p.forward_ms),
            gpu_frame_wall_ms: median(self.wall.clone()),
            pairs,
            grid: grid.dims().to_array(),
            grid_coarsened: grid.dims() != requested.dims(),
            pixels,
        }
    }
}

fn measure(
    viewer: &mut Viewer,
    scene: &RenderScene,
    shading: Shading,
    method: Method,
    runs: usize,
    progress: &Progress,
) -> Result<StrategyResult> {
    let mut last = None;
    viewer.prepare(scene, shading, false)?;
    let mut samples = FrameSamples::new(viewer);
    let warm_ups = timed_frames(shading.name(), runs, progress, || {
        let frame = viewer.frame(scene, shading, method, false)?;
        samples.wait_and_record(viewer, frame.assign_seconds, &frame.report)?;
        last = Some(frame);
        Ok(())
    })?;
    samples.drop_warm_ups(warm_ups);
    let frame = last.context("at least one frame")?;
    let requested = shading.grid(&scene.grid);
    if let Some(warning) = device_coarsened_warning(
        &format!("{}: {}", scene.name, shading.name()),
        requested.dims(),
        frame.grid.dims(),
        viewer.ctx.max_list_pairs(),
    ) {
        progress.line(warning);
    }
    let depth = viewer
        .renderer
        .read_depth(&viewer.ctx)?
        .context("a frame was rendered")?;
    let lights = scene.lights.len();
    let pixels = match shading {
        Shading::BruteForce => {
            let all = vec![lights as u32; frame.grid.cluster_count()];
            pixel_stats(&depth, &scene.camera, &frame.grid, &all, lights)
        }
        _ => pixel_stats(
            &depth,
            &scene.camera,
            &frame.grid,
            &viewer.lists().counts,
            lights,
        ),
    };
    Ok(samples.result(
        shading.name(),
        frame.report.upload_bytes,
        frame.stats.map_or(0, |s| s.pairs),
        [&requested, &frame.grid],
        pixels,
    ))
}

/// The files `render` writes into its `--out` folder.
const OUTPUTS: [&str; 3] = ["frame.png", "heatmap.png", "stats.json"];

pub fn run(args: Args) -> Result<ExitCode> {
    let method = parse_method(&args.method)?;
    let inputs: Vec<&std::path::Path> = [&args.gltf, &args.scene]
        .into_iter()
        .flatten()
        .map(|p| p.as_path())
        .collect();
    let outputs = OUTPUTS.map(|output| args.out.join(output));
    for output in &outputs {
        super::outputs::refuse_overwriting_inputs(output, &inputs)?;
    }
    // A folder or a read-only file in the set's place: said now, not after the render.
    super::outputs::check_out_folder_writable(&args.out)?;
    check_replaceable(&outputs.each_ref().map(|p| p.as_path()))?;
    let (scene, lights_skipped_in_file) = load_scene(&args)?;
    let (width, height) = (scene.camera.width, scene.camera.height);
    let dims = scene.grid.dims();

    let ctx = GpuContext::headless()?;
    let adapter = ctx.describe();
    let timestamps = ctx.has_timestamps();
    // Named: a scene file's camera sets the size, and "a 20000x2 target" alone did not say whose.
    let mut viewer = Viewer::new(ctx, &scene).with_context(|| {
        format!(
            "{} at {width}x{height}{}",
            scene.name,
            if args.size.is_none() {
                " (--size WxH renders another size)"
            } else {
                ""
            }
        )
    })?;

    let mut strategies = Vec::new();
    let mut first_stats = None;
    // The images are kept until every strategy has run: a failure later (brute force past a
    // driver's loop limit, say) then leaves the old output set as it was, not half replaced.
    let mut images = Vec::new();
    // Tiled's and brute force's lit images (clustered's is `images[0]`).
    let mut lit_images: Vec<(Shading, Vec<u8>)> = Vec::new();
    let progress = Progress::new("render");
    let mut skipped = Vec::new();
    let skips = args.skips.unwrap_or(Skips::PER_FRAME);
    let mut with_skips = None;
    for shading in Shading::ALL {
        let started = Instant::now();
        let result = match measure(&mut viewer, &scene, shading, method, args.runs, &progress) {
            Ok(result) => result,
            // A refused frame changed nothing on the GPU: the other strategies go on.
            Err(e) if shading != Shading::Clustered && is_loop_limit(&e) => {
                eprintln!("note: {} skipped: {e:#}", shading.name());
                skipped.push(SkippedStrategy {
                    shading: shading.name(),
                    reason: format!("{e:#}"),
                });
                continue;
            }
            Err(e) => return Err(e),
        };
        progress.done(shading.name(), started.elapsed().as_secs_f64());
        if shading != Shading::Clustered {
            // Its last timed frame, lit: compared with brute force's below.
            lit_images.push((shading, viewer.image()?));
        }
        if shading == Shading::Clustered {
            first_stats = viewer.frame(&scene, shading, method, false)?.stats;
            viewer.ctx.wait_idle()?;
            images.push(("frame.png", viewer.image()?, height));
            // The heat map, with its legend.
            let heat_max = viewer
                .lists()
                .counts
                .iter()
                .copied()
                .max()
                .unwrap_or(0)
                .max(1);
            viewer.frame(&scene, shading, method, true)?;
            let (heat, h) = with_heat_legend(&viewer.image()?, width, height, heat_max);
            images.push(("heatmap.png", heat, h));
            if skips != Skips::NONE {
                let started = Instant::now();
                match render_skipping::measure(
                    &mut viewer,
                    &scene,
                    method,
                    skips,
                    args.runs,
                    &images[0].1,
                    &progress,
                ) {
                    Ok(measured) => {
                        progress.done(render_skipping::SHADING, started.elapsed().as_secs_f64());
                        with_skips = Some(measured);
                    }
                    // Fitted depth slices differently: a cluster may then pass a loop limit
                    // that the plain grid stayed under. The plain clustered frame stands.
                    Err(e) if is_loop_limit(&e) => {
                        eprintln!("note: {} skipped: {e:#}", render_skipping::SHADING);
                        skipped.push(SkippedStrategy {
                            shading: render_skipping::SHADING,
                            reason: format!("{e:#}"),
                        });
                    }
                    Err(e) => return Err(e),
                }
            }
        }
        strategies.push(result);
    }
    let assign_stats = first_stats.context("clustered frame has statistics")?;
    let max_difference_from_brute_force = lit_images
        .iter()
        .find(|(s, _)| *s == Shading::BruteForce)
        .map(|(_, brute)| {
            let mut others = vec![(Shading::Clustered, &images[0].1)];
            others.extend(
                lit_images
                    .iter()
                    .filter(|(s, _)| *s != Shading::BruteForce)
                    .map(|(s, image)| (*s, image)),
            );
            others
                .into_iter()
                .map(|(s, image)| (s.name(), max_channel_difference(image, brute)))
                .collect()
        });
    let time_of = |name: &str| {
        let s = strategies.iter().find(|s| s.shading == name)?;
        Some(s.gpu_shading_ms.unwrap_or(s.gpu_frame_wall_ms))
    };
    let speedup = match (
        time_of(Shading::Clustered.name()),
        time_of(Shading::BruteForce.name()),
    ) {
        (Some(clustered), Some(brute)) if clustered > 0.0 => Some(brute / clustered),
        _ => None,
    };
    let stats = Stats {
        scene: scene.name.clone(),
        adapter,
        timestamps,
        width,
        height,
        grid: dims.to_array(),
        method: method.name().to_string(),
        lights: scene.lights.len(),
        lights_skipped_in_file,
        lights_rejected: assign_stats.rejected,
        lights_culled: assign_stats.culled,
        strategies,
        skipped,
        speedup_vs_brute_force: speedup,
        speedup_measure: if timestamps {
            "shading pass"
        } else {
            "frame wall"
        },
        max_difference_from_brute_force,
        with_skips,
    };
    // The three files describe one run: all of them are replaced, or none.
    let mut files = Vec::new();
    for (name, rgba, h) in &images {
        let png = encode_png(rgba, width, *h).with_context(|| format!("cannot encode {name}"))?;
        files.push((args.out.join(name), png));
    }
    let json_path = args.out.join("stats.json");
    files.push((
        json_path.clone(),
        serde_json::to_string_pretty(&stats)?.into_bytes(),
    ));
    super::outputs::create_out_folder(&args.out)?;
    let set: Vec<(&Path, &[u8])> = files.iter().map(|(p, b)| (p.as_path(), &b[..])).collect();
    replace_files(&set)?;
    print_table(&stats);
    println!(
        "wrote {}, {} and {}",
        args.out.join("frame.png").display(),
        args.out.join("heatmap.png").display(),
        json_path.display()
    );
    let differing: Vec<String> = stats
        .max_difference_from_brute_force
        .iter()
        .flatten()
        .filter(|&(_, &d)| d > MAX_DIFFERENCE_FROM_BRUTE_FORCE)
        .map(|(s, d)| format!("{s} by {d}/255"))
        .collect();
    if !differing.is_empty() {
        eprintln!(
            "error: the image differs from brute force's (every light at every pixel): {} (at \
             most {MAX_DIFFERENCE_FROM_BRUTE_FORCE} allowed)",
            differing.join(", ")
        );
        return Ok(ExitCode::FAILURE);
    }
    if let Some(w) = stats
        .with_skips
        .as_ref()
        .filter(|w| w.max_image_difference > 1)
    {
        eprintln!(
            "error: the savings {} changed the clustered image by {}/255 (at most 1 allowed)",
            w.savings.join(","),
            w.max_image_difference
        );
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

/// The scene to render: geometry from `--gltf` (or the atrium), camera/grid/lights from
/// `--scene`, `--preset` or the model (its camera, its lights plus surface lights), then the
/// size, grid and slicing options. Also returns how many invalid lights the scene file had
/// (skipped).
fn load_scene(args: &Args) -> Result<(RenderScene, usize)> {
    let (model, model_name) = match &args.gltf {
        Some(path) => {
            let outputs = OUTPUTS.map(|output| args.out.join(output));
            let outputs = outputs.each_ref().map(|p| p.as_path());
            (
                super::source::load_model(path, &LoadOptions::default(), &outputs)?,
                path.display().to_string(),
            )
        }
        None => (
            myriad::scene::atrium(),
            "default scene (atrium)".to_string(),
        ),
    };
    let size = args.size.as_deref().map(parse_size).transpose()?;
    let mut skipped = 0;
    let mut scene = match (&args.scene, &args.preset) {
        (Some(path), _) => {
            let file = myriad::scene::Scene::load(path, myriad::scene::LightPolicy::SkipInvalid)?;
            super::source::report_skipped(path, &file);
            check_memory(&file.grid, file.lights.len())
                .with_context(|| format!("{}: grid too large here", path.display()))?;
            skipped = file.skipped.len();
            let name = format!("{} in {model_name}", path.display());
            RenderScene::from_scene(&model, &name, file)
        }
        (None, Some(preset)) => {
            let preset = super::source::parse_preset(preset)?;
            let (lights, seed) = (args.lights.unwrap_or(1000), args.seed.unwrap_or(1));
            check_memory(&preset.view().1, lights)?;
            let name = format!(
                "preset {} ({lights} lights, seed {seed}) in {model_name}",
                preset.name()
            );
            RenderScene::from_scene(&model, &name, preset.generate(lights, seed))
        }
        (None, None) => {
            let (w, h) = size.unwrap_or((1536, 768));
            let lights = args.lights.unwrap_or(1000);
            // Before generating them: placing the lights is the allocation that aborts.
            let dims = match &args.grid {
                Some(g) => parse_grid("--grid", g)?,
                None => DEFAULT_GRID,
            };
            check_memory_for(dims, lights)?;
            super::source::note_model_scene(&model, &model_name, args.camera.as_deref(), lights);
            RenderScene::from_model(
                &model,
                &model_name,
                args.camera.as_deref(),
                lights,
                args.seed.unwrap_or(1),
                w,
                h,
            )?
        }
    };
    // A camera from a scene file or a preset, over a model of the user's: it may well not be
    // inside it (the `paper` preset's eye is 0.28 m under Sponza's floor, review).
    if args.gltf.is_some() && (args.scene.is_some() || args.preset.is_some()) {
        let bounds = model.bounds();
        let eye = scene.camera.position;
        if !bounds.is_empty() && !bounds.contains(eye) {
            eprintln!(
                "warning: {}: the camera at [{}, {}, {}] is outside {model_name}'s bounds \
                 [{}, {}, {}] .. [{}, {}, {}]: the image shows the model from outside it",
                scene.name,
                eye.x,
                eye.y,
                eye.z,
                bounds.min.x,
                bounds.min.y,
                bounds.min.z,
                bounds.max.x,
                bounds.max.y,
                bounds.max.z
            );
        }
    }
    if let Some((w, h)) = size {
        scene = scene.with_size(w, h);
    }
    if args.grid.is_some() || args.depth.is_some() {
        let dims: UVec3 = match &args.grid {
            Some(g) => parse_grid("--grid", g)?,
            None => scene.grid.dims(),
        };
        let slicing = match &args.depth {
            Some(d) => parse_slicing(d)?,
            None => scene.grid.slicing(),
        };
        check_slicing(slicing, dims.z, scene.grid.near(), scene.grid.far())?;
        check_memory_for(dims, scene.lights.len())?;
        scene = scene.with_grid(dims, slicing);
    }
    super::source::check_image_memory(scene.camera.width, scene.camera.height)?;
    Ok((scene, skipped))
}

fn print_table(s: &Stats) {
    let [x, y, z] = s.grid;
    println!(
        "{} — {} lights, {}x{}, grid {x}x{y}x{z}, method {}",
        s.scene, s.lights, s.width, s.height, s.method
    );
    println!(
        "GPU: {}; pass timestamps: {}",
        s.adapter,
        if s.timestamps {
            "yes"
        } else {
            "no (wall clock only)"
        }
    );
    let ms = |v: Option<f64>| v.map_or("—".to_string(), |v| format!("{v:.2}"));
    // The columns: the strategies, with clustered+skips right after clustered.
    let mut columns: Vec<&StrategyResult> = s.strategies.iter().collect();
    if let Some(w) = &s.with_skips {
        columns.insert(1.min(columns.len()), &w.result);
    }
    let is_skipping = |r: &StrategyResult| r.shading == render_skipping::SHADING;
    let row = |name: &str, f: &dyn Fn(&StrategyResult) -> String| {
        let cells: String = columns.iter().map(|r| format!(" {:>15}", f(r))).collect();
        println!("{name:<34}{cells}");
    };
    row("stage (median ms)", &|r| r.shading.to_string());
    row("CPU light assignment", &|r| format!("{:.3}", r.assign_ms));
    if let Some(w) = &s.with_skips {
        row("depth prepass + read-back (wall)", &|r| {
            if is_skipping(r) && w.prepass_ms > 0.0 {
                format!("{:.2}", w.prepass_ms)
            } else {
                "—".to_string()
            }
        });
        row("depth → fitted range + mask", &|r| {
            if is_skipping(r) && w.mask_ms > 0.0 {
                format!("{:.3}", w.mask_ms)
            } else {
                "—".to_string()
            }
        });
    }
    row("upload (KiB)", &|r| {
        format!("{:.1}", r.upload_bytes as f64 / 1024.0)
    });
    row("upload: convert + stage", &|r| {
        format!("{:.3}", r.upload_ms)
    });
    row("encode + submit", &|r| format!("{:.3}", r.encode_ms));
    row("GPU upload (buffer copies)", &|r| {
        r.gpu_upload_ms
            .map_or("—".to_string(), |v| format!("{v:.3}"))
    });
    row("GPU G-buffer pass", &|r| ms(r.gpu_gbuffer_ms));
    row("GPU shading pass", &|r| ms(r.gpu_shading_ms));
    row("GPU forward pass", &|r| ms(r.gpu_forward_ms));
    // The skipping column's G-buffer is drawn by its depth prepass, outside this frame's wall
    // time: marked, so the row does not read as the same work done faster (audit).
    let prepass_drew = |r: &StrategyResult| {
        is_skipping(r) && s.with_skips.as_ref().is_some_and(|w| w.prepass_ms > 0.0)
    };
    row("GPU frame (encode to idle, wall)", &|r| {
        let mark = if prepass_drew(r) { "†" } else { "" };
        format!("{:.2}{mark}", r.gpu_frame_wall_ms)
    });
    row("cluster-light pairs", &|r| r.pairs.to_string());
    if columns.iter().any(|r| r.grid_coarsened) {
        // Lists past what the device binds were built on a coarser grid (a warning said so).
        row("grid of the lists (* coarser)", &|r| {
            let [x, y, z] = r.grid;
            let coarser = if r.grid_coarsened { "*" } else { "" };
            format!("{x}x{y}x{z}{coarser}")
        });
    }
    row("lights per pixel: mean", &|r| {
        format!("{:.1}", r.pixels.mean_lights)
    });
    row("lights per pixel: max", &|r| {
        r.pixels.max_lights.to_string()
    });
    row("lighting calculations skipped", &|r| {
        format!("{:.1}%", r.pixels.skipped_fraction * 100.0)
    });
    println!(
        "lights: {}{} ({} rejected as invalid, {} outside the view frustum, dropped by the assignment's first test; the strategies upload them all{})",
        s.lights,
        match s.lights_skipped_in_file {
            0 => String::new(),
            n => format!(" and {n} invalid in the scene file, skipped"),
        },
        s.lights_rejected,
        s.lights_culled,
        // Only where that column runs and culls (it said so under `--skips none`, audit).
        match &s.with_skips {
            Some(w) if w.savings.contains(&"cull") =>
                format!(", {} culls them first", render_skipping::SHADING),
            _ => String::new(),
        }
    );
    if let Some(w) = &s.with_skips {
        let mut notes = vec![format!("savings {}", w.savings.join(", "))];
        if w.lights_assigned != s.lights {
            notes.push(format!("{} lights assigned", w.lights_assigned));
        }
        if w.prepass_ms > 0.0 {
            notes.push(
                "† its G-buffer is drawn by the depth prepass (its own row), not in the frame's \
                 wall time"
                    .to_string(),
            );
        }
        if let Some(active) = w.active_clusters {
            notes.push(format!("{active} of {} clusters active", w.clusters));
        }
        if let Some([n, f]) = w.fitted_depth_range {
            notes.push(format!("depth range fitted to [{n:.3}, {f:.3}]"));
        }
        if let Some(d) = w.prepass_decision {
            notes.push(format!("tuned: {d}"));
        }
        if w.savings.contains(&"reuse") {
            // The column's medians are frames that reused the first one's lists and uploads;
            // the upload and pair rows are that first frame's (audit: unlabelled before).
            notes.push(
                "with reuse its timed frames kept the frame that assigned: no assignment, \
                 prepass or upload of their own; its upload and pairs rows are that frame's"
                    .to_string(),
            );
        }
        notes.push(format!(
            "largest difference from the clustered image {}/255",
            w.max_image_difference
        ));
        println!("{}: {}", render_skipping::SHADING, notes.join("; "));
    }
    for r in columns.iter().filter(|r| r.warm_up_timed) {
        println!(
            "{}: one frame, its warm-up (it alone took over {} s)",
            r.shading,
            FRAMES_BUDGET.as_secs()
        );
    }
    for skip in &s.skipped {
        println!("{} skipped: {}", skip.shading, skip.reason);
    }
    if let Some(differences) = &s.max_difference_from_brute_force {
        let each: Vec<String> = differences
            .iter()
            .map(|(s, d)| format!("{s} {d}/255"))
            .collect();
        println!(
            "largest difference from the brute-force image (every light at every pixel): {}",
            each.join(", ")
        );
    }
    if let Some(x) = s.speedup_vs_brute_force {
        let with_skips = s
            .with_skips
            .as_ref()
            .zip(
                s.strategies
                    .iter()
                    .find(|r| r.shading == Shading::BruteForce.name()),
            )
            .and_then(|(w, brute)| Some(brute.gpu_shading_ms? / w.result.gpu_shading_ms?))
            .map_or(String::new(), |y| {
                format!("; {} with {}", times(y), render_skipping::SHADING)
            });
        println!("{}", speedup_sentence(x, s.speedup_measure, &with_skips));
    }
}

/// The main job's last line. Below 1 it says "slower": a few lights can cost clustered shading
/// more than they save ("0.8x faster", audit).
fn speedup_sentence(ratio: f64, measure: impl std::fmt::Display, with_skips: &str) -> String {
    let (ratio, word) = if ratio >= 1.0 {
        (ratio, "faster")
    } else {
        (1.0 / ratio, "slower")
    };
    format!(
        "clustered deferred shading is {ratio:.1}x {word} than brute-force deferred ({measure}){with_skips}"
    )
}

/// `ratio` as "N.Nx", or "N.Nx slower" below 1.
fn times(ratio: f64) -> String {
    if ratio >= 1.0 {
        format!("{ratio:.1}x")
    } else {
        format!("{:.1}x slower", 1.0 / ratio)
    }
}

/// The main job: the default scene with 1000 lights at 1536×768 into `out/`.
pub fn main_job() -> Result<ExitCode> {
    run(Args::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_speedup_below_one_says_slower() {
        assert_eq!(
            speedup_sentence(42.6, "shading pass", "; 45.6x with clustered+skips"),
            "clustered deferred shading is 42.6x faster than brute-force deferred (shading pass); \
             45.6x with clustered+skips"
        );
        assert_eq!(
            speedup_sentence(0.8, "frame wall", ""),
            "clustered deferred shading is 1.2x slower than brute-force deferred (frame wall)"
        );
        assert_eq!(times(0.5), "2.0x slower");
        assert_eq!(times(2.0), "2.0x");
    }

    /// Renders with frames of `frame` each under `budget`: how many frames were rendered, and
    /// how many leading ones `frames_within` said to drop.
    fn frames_of(frame: Duration, budget: Duration, runs: usize) -> (usize, usize) {
        let mut rendered = 0;
        let progress = Progress::new("test");
        let drop = frames_within(budget, "test", runs, &progress, || {
            std::thread::sleep(frame);
            rendered += 1;
            Ok(())
        })
        .unwrap();
        (rendered, drop)
    }

    /// Fast frames: the warm-up, dropped, then every timed frame asked for.
    #[test]
    fn fast_frames_run_all_after_a_dropped_warm_up() {
        assert_eq!(
            frames_of(Duration::ZERO, Duration::from_secs(60), 5),
            (6, 1)
        );
    }

    /// Frames that pass the budget between them: at least one timed frame after the warm-up,
    /// none started once the budget is spent. (A sleep never ends early: the warm-up and the
    /// first timed frame together take over the budget.)
    #[test]
    fn slow_frames_stop_after_one_timed_frame() {
        let budget = Duration::from_millis(1000);
        assert_eq!(frames_of(budget * 3 / 5, budget, 5), (2, 1));
    }

    /// A warm-up that alone takes the budget is the one sample: nothing is dropped and no other
    /// frame is rendered.
    #[test]
    fn a_warm_up_over_the_budget_stands_as_the_timed_frame() {
        let budget = Duration::from_millis(50);
        assert_eq!(frames_of(budget * 2, budget, 5), (1, 0));
    }

    /// An error in a frame ends the frames with that error.
    #[test]
    fn a_failed_frame_is_the_result() {
        let progress = Progress::new("test");
        let mut calls = 0;
        let result = frames_within(Duration::from_secs(60), "test", 5, &progress, || {
            calls += 1;
            if calls == 3 {
                bail!("frame {calls} failed");
            }
            Ok(())
        });
        assert_eq!(result.unwrap_err().to_string(), "frame 3 failed");
        assert_eq!(calls, 3);
    }
}
