//! `myriad stress --lights N`: one frame with very many lights, end to end, every stage timed,
//! the lists proven against the exact oracle and the GPU's copy against them.
//!
//! Why it exists: the benches time the assignment alone and the render tests use at most 100k
//! lights at tiny sizes; nothing else pushes a million lights through scene generation,
//! assignment, upload and a real render in one process and then asks whether the lists the GPU
//! shaded with were *right*. This command does, and exits non-zero on any miss.
//!
//! Stages, each timed, announced on stderr as it starts and ends (an `indicatif` spinner when
//! stderr is a terminal, plain lines otherwise), and summed up in a table on stdout (or one JSON
//! object with `--json`):
//!
//! 1. **scene generation** — the lights and the geometry they are rendered in;
//! 2. **assignment** on the CPU with `--method`, twice: the first call allocates the assigner's
//!    scratch and the lists, the second reuses them (the steady state a frame loop sees). Under a
//!    pair budget (`pair_budget.rs`: `--pair-budget`, or what the memory holds): past it the
//!    grid is coarsened, a warning says so, and the later stages use that grid;
//! 3. **GPU setup** — device, geometry upload, and one warm-up frame with the same lights and
//!    empty lists over the real indices, so that pipeline compilation and the buffers' allocation
//!    do not land in the measured frame. The device is made first of all, before the scene: a light buffer it
//!    cannot bind is refused at once, and its largest binding caps the default pair budget
//!    (`GpuContext::max_list_pairs`; lists past it are built on a coarser grid, which the
//!    renderer takes, instead of being refused after a minute of assignment);
//! 4. **upload** of the measured frame (lights → GPU records, lists, through the staging ring):
//!    bytes and CPU time;
//! 5. **GPU render**, clustered only: pass timestamps where the adapter has them, and the wall
//!    time from encoding to idle. (Brute force and one-slice tiles are not attempted: on llvmpipe
//!    a pixel may loop over at most 65 534 lights and the renderer refuses more —
//!    `GpuError::ShaderLoopLimit`; clustered lists stay far below that); then the lists the
//!    GPU shaded with are read back (`Renderer::read_back_lists`) and compared with the uploaded
//!    ones array by array: the oracle below proves the CPU's lists, this that the GPU got them
//!    whole through the staging ring (at 1M lights, 90 MiB in chunks of their own size);
//! 6. **oracle check** (`oracle_check.rs`): up to `--exact-up-to` lights (200k), **every
//!    cluster** through the `exact` method's lists; above, **`--sample K` clusters** (2000,
//!    seeded), each checked independently against every light in its depth window. A miss names
//!    the cluster and the light. It is not cheaper: on the atrium with 1M lights the sampled
//!    check of 2000 of 4608 clusters took about 2.6× as long as the full one
//!    (`--exact-up-to 2000000`; 4.4 s against 1.7 s on the 2-core machine), because the
//!    `exact` method tests only each light's candidate clusters while a sampled cluster scans
//!    every light in its depth window.
//!    So the split at 200k is about independence, not speed; `--exact-up-to` moves it. With
//!    `--method exact` the lists under test are the `exact` method's own, so every cluster is
//!    checked independently instead (comparing them with themselves could never fail).
//!
//! Peak memory is the process's `VmHWM` (Linux; "unknown" elsewhere).
//!
//! **The scene — a decision.** The `uniform` preset (lights uniform in a 1920×1080 frustum,
//! 32×18×48 grid) is the assignment benches' stress scene, but it has no geometry: its G-buffer
//! would be empty, no pixel would shade a single light, and the render stage would measure
//! nothing. So the lights go where the renderer has surfaces: the default scene
//! ([`RenderScene::default_scene`]: the generated atrium, its 12 authored lights, then lights on
//! its surfaces up to N, radii 0.5–3 m, camera `Main`, 24×12×16 log grid or `--grid`) at
//! `--size` (320×180 by default; the camera is built for that size, same field of view). `--seed`
//! changes the surface lights (1 is the default scene exactly) and the sampled clusters.

use super::assign::parse_method;
use super::grid_options::parse_grid;
use super::oracle_check::{CheckReport, OracleLights, check_all, check_clusters, sample_clusters};
use super::pair_budget::{PairBudget, STRESS_BYTES_PER_PAIR};
use super::progress::Progress;
use super::render::parse_size;
use super::source::check_memory_for;
use anyhow::{Result, ensure};
use myriad::assignment::{Assigner, LightLists, Method};
use myriad::gpu::layout::GpuLight;
use myriad::gpu::{ClusterLists, FrameDesc, GpuContext, GpuError, ListsReadBack};
use myriad::render::{RenderScene, Viewer, cluster_lists, light_columns};
use myriad::scene::DepthSlicing;
use serde::Serialize;
use std::process::ExitCode;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Lights: the atrium's own, then lights on its surfaces up to this many.
    #[arg(long, value_parser = super::light_count, default_value_t = 100_000)]
    lights: usize,
    /// Render size WxH (the atrium's camera is built for it).
    #[arg(long, default_value = "320x180")]
    size: String,
    /// Assignment method: exact, linear, binary, refined or cone.
    #[arg(long, default_value = "refined")]
    method: String,
    /// Cluster grid XxYxZ (log depth slices over the camera's range).
    #[arg(long, default_value = "24x12x16")]
    grid: String,
    /// Seed of the surface lights and of the sampled clusters.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Clusters checked against the oracle when there are more than --exact-up-to lights.
    #[arg(long, default_value_t = 2000)]
    sample: usize,
    /// Up to this many lights every cluster is checked (exact assignment of all lights).
    #[arg(long, default_value_t = 200_000)]
    exact_up_to: usize,
    /// Most cluster–light pairs the lists may hold; past it the grid is halved until they fit
    /// (no light is dropped), and the report gives the coarser grid. Default: what u32 offsets
    /// hold, or fewer where the memory this process may take holds fewer (24 bytes a pair).
    #[arg(long)]
    pair_budget: Option<u64>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
}

/// Milliseconds of each stage.
#[derive(Serialize, Debug, Default)]
struct Stages {
    /// Making the GPU device (first of all).
    device_ms: f64,
    scene_ms: f64,
    assign_ms: f64,
    assign_again_ms: f64,
    /// Geometry upload and the warm-up frame.
    gpu_setup_ms: f64,
    upload_ms: f64,
    encode_ms: f64,
    /// Encoding to GPU idle, wall clock (encode + submit, then the wait).
    gpu_wall_ms: f64,
    /// The upload's buffer copies on the GPU (timestamps between commands).
    gpu_upload_ms: Option<f64>,
    gpu_gbuffer_ms: Option<f64>,
    gpu_shading_ms: Option<f64>,
    gpu_forward_ms: Option<f64>,
    /// Reading the lists back from the GPU and comparing them with the uploaded ones.
    gpu_readback_ms: f64,
    check_ms: f64,
}

/// What the assignment produced.
#[derive(Serialize, Debug)]
struct Assignment {
    pairs: u64,
    visible: u32,
    culled: u32,
    rejected: u32,
    /// The longest list: what one pixel may loop over.
    max_list: u32,
    list_bytes: u64,
}

#[derive(Serialize, Debug)]
struct Report {
    scene: String,
    lights: usize,
    width: u32,
    height: u32,
    /// The grid the lists were built on: `--grid`, or a coarser one when the pairs exceeded the
    /// pair budget (then `grid_requested` differs).
    grid: [u32; 3],
    grid_requested: [u32; 3],
    /// The pair budget the assignment ran under.
    pair_budget: u64,
    method: String,
    seed: u64,
    adapter: String,
    timestamps: bool,
    /// The adapter's per-invocation shader loop limit (llvmpipe), if it has one.
    shader_loop_limit: Option<u64>,
    /// The longest list a pixel may loop over under that limit on this grid
    /// (`myriad_gpu::loop_budget`); `null` without a limit.
    max_lights_per_pixel: Option<u64>,
    stages: Stages,
    assignment: Assignment,
    upload_bytes: u64,
    /// Whether the lists read back from the GPU equal the lists uploaded, array by array.
    gpu_lists_identical: bool,
    /// Where they first differ, when they do.
    gpu_lists_difference: Option<String>,
    check: CheckReport,
    /// VmHWM of this process; `null` where unknown.
    peak_memory_bytes: Option<u64>,
    passed: bool,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let method = parse_method(&args.method)?;
    let (width, height) = parse_size(&args.size)?;
    super::source::check_image_memory(width, height)?;
    let dims = parse_grid("--grid", &args.grid)?;
    ensure!(args.lights >= 1, "--lights must be at least 1");
    ensure!(
        args.lights <= u32::MAX as usize,
        "--lights {}: at most {} (light indices are u32)",
        args.lights,
        u32::MAX
    );
    ensure!(
        args.sample >= 1,
        "--sample must be at least 1 (clusters checked against the oracle)"
    );
    check_memory_for(dims, args.lights)?;
    let progress = Progress::new("stress");
    let mut stages = Stages::default();

    // The device first: what it binds decides how many lights and pairs a frame may have, which
    // is better known before a minute of generation and assignment than after.
    let (ctx, device_seconds) = progress.stage("GPU device", || Ok(GpuContext::headless()?))?;
    let light_bytes = args.lights as u64 * std::mem::size_of::<GpuLight>() as u64;
    let binding = ctx.max_list_pairs() * std::mem::size_of::<u32>() as u64;
    ensure!(
        light_bytes <= binding,
        "--lights {}: the lights buffer needs {light_bytes} bytes, more than {} binds in one \
         storage buffer ({binding} bytes); at most {} lights",
        args.lights,
        ctx.describe(),
        binding / std::mem::size_of::<GpuLight>() as u64
    );

    // 1. Scene.
    // Said before the stage starts: a note inside it would print over the spinner.
    let atrium = myriad::scene::atrium();
    super::source::note_model_scene(&atrium, "default scene (atrium)", None, args.lights);
    let (scene, seconds) = progress.stage("scene generation", || {
        RenderScene::from_model(
            &atrium,
            "default scene (atrium)",
            None,
            args.lights,
            args.seed,
            width,
            height,
        )
        .map(|scene| scene.with_grid(dims, DepthSlicing::Log))
    })?;
    stages.scene_ms = seconds * 1e3;
    progress.note(&format!(
        "{} lights, {} clusters",
        scene.lights.len(),
        scene.grid.cluster_count()
    ));

    // 2. Assignment, cold then warm.
    let input = myriad::light_input(&scene.lights);
    let budget = PairBudget::new(args.pair_budget, STRESS_BYTES_PER_PAIR)
        .capped_by_device(ctx.max_list_pairs());
    let mut assigner = Assigner::new().with_pair_budget(budget.pairs);
    let mut lists = LightLists::new();
    let (_, seconds) = progress.stage("light assignment (first call, allocating)", || {
        Ok(assigner.assign(method, &input, &scene.camera, &scene.grid, &mut lists))
    })?;
    stages.assign_ms = seconds * 1e3;
    let (stats, seconds) = progress.stage("light assignment (again, buffers reused)", || {
        Ok(assigner.assign(method, &input, &scene.camera, &scene.grid, &mut lists))
    })?;
    stages.assign_again_ms = seconds * 1e3;
    drop(assigner);
    let grid = stats.grid_built(&scene.grid);
    let warning = budget.coarsening_warning(&scene.name, &stats, &scene.grid, "the report");
    if let Some(warning) = warning {
        progress.line(warning);
    }
    let assignment = Assignment {
        pairs: stats.pairs,
        visible: stats.visible(),
        culled: stats.culled,
        rejected: stats.rejected,
        max_list: lists.counts.iter().copied().max().unwrap_or(0),
        list_bytes: lists.byte_size() as u64,
    };
    progress.note(&format!(
        "{} pairs, longest list {}",
        assignment.pairs, assignment.max_list
    ));

    // 3. GPU set-up and a warm-up frame (same lights, empty lists).
    let (mut viewer, seconds) = progress.stage("GPU setup (geometry, warm-up)", || {
        let mut viewer = Viewer::new(ctx, &scene)?;
        // Empty lists over as many zero indices: every buffer the measured frame needs is
        // grown here (the indices' is the largest), and no pixel shades a light. Zeros, not the
        // real indices, so that the read-back after the measured frame would see it had the
        // measured upload of the indices been lost.
        let empty = vec![0u32; grid.cluster_count()];
        let zeros = vec![0u32; lists.indices.len()];
        let no_lists = ClusterLists {
            offsets: &empty,
            counts: &empty,
            indices: &zeros,
        };
        let warm_up = FrameDesc {
            settings: viewer.settings,
            ..FrameDesc::clustered(&scene.camera, &grid, light_columns(&scene.lights), no_lists)
        };
        let what = format!("the warm-up frame of {} lights", scene.lights.len());
        let report = render_explained(
            &mut viewer,
            &warm_up,
            &what,
            grid.dims() != scene.grid.dims(),
        )?;
        myriad::profiling::plot_frame_load(scene.lights.len() as u64, None, report.upload_bytes);
        myriad::profiling::frame_mark();
        viewer.ctx.wait_idle()?;
        Ok(viewer)
    })?;
    stages.device_ms = device_seconds * 1e3;
    stages.gpu_setup_ms = seconds * 1e3;
    let adapter = viewer.ctx.describe();
    let timestamps = viewer.ctx.has_timestamps();
    let shader_loop_limit = viewer.ctx.shader_loop_limit();
    let max_lights_per_pixel = viewer
        .ctx
        .max_lights_per_pixel(myriad::gpu::ShadingMode::Lists, grid.dims().z);

    // 4. Upload (+ encode and submit) of the measured frame.
    progress.start("upload + encode + submit");
    let frame = FrameDesc {
        settings: viewer.settings,
        ..FrameDesc::clustered(
            &scene.camera,
            &grid,
            light_columns(&scene.lights),
            cluster_lists(&lists),
        )
    };
    let what = format!("rendering {} lights clustered", scene.lights.len());
    let report = render_explained(&mut viewer, &frame, &what, grid.dims() != scene.grid.dims())?;
    // The GPU may be at work already: the wait below counts from here, not from after the
    // progress lines.
    let submitted = Instant::now();
    myriad::profiling::plot_frame_load(
        u64::from(stats.visible()),
        Some(stats.pairs),
        report.upload_bytes,
    );
    myriad::profiling::frame_mark();
    stages.upload_ms = report.upload_seconds * 1e3;
    stages.encode_ms = report.encode_seconds * 1e3;
    progress.done(
        "upload + encode + submit",
        report.upload_seconds + report.encode_seconds,
    );
    progress.note(&format!("{} bytes uploaded", report.upload_bytes));

    // 5. The GPU's work: submit to idle, wall clock (encode + submit included, as `myriad
    // render` reports it), and the pass timestamps.
    progress.start("GPU render (clustered)");
    viewer.ctx.wait_idle()?;
    let wait_seconds = submitted.elapsed().as_secs_f64();
    progress.done("GPU render (clustered)", wait_seconds);
    stages.gpu_wall_ms = (wait_seconds + report.encode_seconds) * 1e3;
    let passes = viewer.renderer.last_pass_times(&viewer.ctx)?;
    if let Some(p) = passes {
        stages.gpu_upload_ms = p.upload_ms;
        stages.gpu_gbuffer_ms = p.gbuffer_ms;
        stages.gpu_shading_ms = p.shading_ms;
        stages.gpu_forward_ms = p.forward_ms;
    }

    // 5b. What the GPU shaded with: the lists read back, against the ones uploaded.
    let (gpu_lists_difference, seconds) = progress.stage("GPU lists read back", || {
        let back = viewer.renderer.read_back_lists(&viewer.ctx)?;
        Ok(match back {
            Some(back) => lists_difference(&back, &lists),
            None => Some("the renderer holds no lists".to_string()),
        })
    })?;
    stages.gpu_readback_ms = seconds * 1e3;
    drop(viewer);

    // 6. Oracle.
    let full = scene.lights.len() <= args.exact_up_to;
    // The `exact` method's lists cannot check themselves (audit g1: that check always passed):
    // under test, every cluster goes through the independent oracle instead.
    let exact_under_test = method == Method::Exact;
    let stage_name = match (full, exact_under_test) {
        (true, false) => "oracle check (every cluster, exact lists)".to_string(),
        (true, true) => "oracle check (every cluster, independent of the exact method)".to_string(),
        (false, _) => {
            let k = args.sample.min(grid.cluster_count());
            format!("oracle check ({k} sampled clusters)")
        }
    };
    let (check, seconds) = progress.stage(&stage_name, || {
        Ok(if full && !exact_under_test {
            check_all(&scene.lights, &scene.camera, &grid, &lists)
        } else {
            let k = if full { usize::MAX } else { args.sample };
            let clusters = sample_clusters(grid.cluster_count(), k, args.seed);
            let oracle = OracleLights::new(&scene.lights, &scene.camera);
            check_clusters(&oracle, &scene.camera, &grid, &lists, &clusters)
        })
    })?;
    stages.check_ms = seconds * 1e3;
    progress.finish();

    let d = grid.dims();
    let out = Report {
        scene: scene.name.clone(),
        lights: scene.lights.len(),
        width,
        height,
        grid: [d.x, d.y, d.z],
        grid_requested: dims.to_array(),
        pair_budget: budget.pairs,
        method: method.name().to_string(),
        seed: args.seed,
        adapter,
        timestamps,
        shader_loop_limit,
        max_lights_per_pixel,
        stages,
        assignment,
        upload_bytes: report.upload_bytes,
        gpu_lists_identical: gpu_lists_difference.is_none(),
        passed: check.misses == 0 && gpu_lists_difference.is_none(),
        gpu_lists_difference,
        check,
        peak_memory_bytes: peak_memory_bytes(),
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        print_table(&out);
    }
    if let Some(m) = out.check.first_miss {
        eprintln!(
            "error: {} miss(es); e.g. cluster {} (tile {}, {}, slice {}) lacks light {}, which \
             the exact oracle says touches it",
            out.check.misses, m.cluster, m.tile[0], m.tile[1], m.tile[2], m.light
        );
        return Ok(ExitCode::FAILURE);
    }
    if let Some(difference) = &out.gpu_lists_difference {
        eprintln!("error: the lists on the GPU are not the lists uploaded: {difference}");
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

/// Where the lists read back from the GPU first differ from `lists`, or `None` when every
/// array is equal.
fn lists_difference(back: &ListsReadBack, lists: &LightLists) -> Option<String> {
    [
        ("offsets", &back.offsets, &lists.offsets),
        ("counts", &back.counts, &lists.counts),
        ("indices", &back.indices, &lists.indices),
    ]
    .into_iter()
    .find_map(|(name, gpu, cpu)| {
        if gpu.len() != cpu.len() {
            return Some(format!(
                "{name}: {} on the GPU, {} uploaded",
                gpu.len(),
                cpu.len()
            ));
        }
        let i = gpu.iter().zip(cpu).position(|(g, c)| g != c)?;
        Some(format!(
            "{name}[{i}] is {} on the GPU, {} uploaded",
            gpu[i], cpu[i]
        ))
    })
}

/// Renders `frame`; a refusal says `what` was refused and, from [`render_hint`], what `stress`
/// can change.
fn render_explained(
    viewer: &mut Viewer,
    frame: &FrameDesc<'_>,
    what: &str,
    coarsened: bool,
) -> Result<myriad::gpu::FrameReport> {
    let Viewer {
        ctx,
        renderer,
        scene,
        target,
        ..
    } = viewer;
    renderer
        .render(ctx, scene, frame, &target.view)
        .map_err(|e| {
            let hint = render_hint(&e, coarsened);
            anyhow::Error::new(e).context(format!("{what}{hint}"))
        })
}

/// What `stress` can change when the render is refused: the advice after "rendering N lights
/// clustered", or nothing. `coarsened`: the pair budget already coarsened the grid, so a finer
/// `--grid` alone would be coarsened again.
fn render_hint(e: &GpuError, coarsened: bool) -> String {
    match *e {
        GpuError::ShaderLoopLimit { .. } if coarsened => {
            " (a larger --pair-budget keeps a finer grid, with shorter lists; or fewer lights)"
                .into()
        }
        GpuError::ShaderLoopLimit { .. } => " (a finer --grid gives shorter lists)".into(),
        // The budget under which the grid coarsens until the indices fit.
        GpuError::BufferTooLarge {
            what: "light indices",
            limit,
            ..
        } => format!(
            " (--pair-budget {} coarsens the grid until the lists fit this device)",
            GpuContext::list_pairs_in(limit)
        ),
        _ => String::new(),
    }
}

/// Peak resident set size of this process (`VmHWM`), where the OS tells.
fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line
        .trim_start_matches("VmHWM:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib * 1024)
}

fn print_table(r: &Report) {
    let [x, y, z] = r.grid;
    let coarser = if r.grid == r.grid_requested {
        String::new()
    } else {
        let [x, y, z] = r.grid_requested;
        format!(" (coarser than --grid {x}x{y}x{z}: the pairs exceeded the budget)")
    };
    println!(
        "{} — {} lights, {}x{}, grid {x}x{y}x{z}{coarser}, method {}, seed {}",
        r.scene, r.lights, r.width, r.height, r.method, r.seed
    );
    println!(
        "GPU: {}; pass timestamps: {}",
        r.adapter,
        if r.timestamps { "yes" } else { "no" }
    );
    let s = &r.stages;
    let a = &r.assignment;
    let c = &r.check;
    let ms = |v: Option<f64>| v.map_or("—".to_string(), |v| format!("{v:.2}"));
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    println!("{:<42} {:>11}  detail", "stage", "ms");
    let row = |name: &str, value: String, detail: String| {
        println!("{}", format!("{name:<42} {value:>11}  {detail}").trim_end());
    };
    row("GPU device", format!("{:.1}", s.device_ms), String::new());
    row(
        "scene generation",
        format!("{:.1}", s.scene_ms),
        format!("{} lights", r.lights),
    );
    row(
        "light assignment (first call, allocating)",
        format!("{:.2}", s.assign_ms),
        format!(
            "{} pairs; {} visible, {} culled, {} rejected",
            a.pairs, a.visible, a.culled, a.rejected
        ),
    );
    row(
        "light assignment (again, buffers reused)",
        format!("{:.2}", s.assign_again_ms),
        format!(
            "longest list {}{}; lists {:.1} MiB",
            a.max_list,
            r.max_lights_per_pixel
                .map_or(String::new(), |l| format!(" (at most {l} on this adapter)")),
            mib(a.list_bytes)
        ),
    );
    row(
        "GPU setup (geometry, warm-up)",
        format!("{:.1}", s.gpu_setup_ms),
        String::new(),
    );
    row(
        "upload: convert + stage",
        format!("{:.2}", s.upload_ms),
        format!("{:.1} MiB (lights + lists)", mib(r.upload_bytes)),
    );
    row(
        "encode + submit",
        format!("{:.2}", s.encode_ms),
        String::new(),
    );
    row(
        "GPU upload (buffer copies)",
        s.gpu_upload_ms
            .map_or("—".to_string(), |v| format!("{v:.3}")),
        "timestamps between commands".into(),
    );
    row(
        "GPU G-buffer pass",
        ms(s.gpu_gbuffer_ms),
        "timestamps".into(),
    );
    row(
        "GPU shading pass",
        ms(s.gpu_shading_ms),
        "timestamps".into(),
    );
    row(
        "GPU forward pass",
        ms(s.gpu_forward_ms),
        "timestamps".into(),
    );
    row(
        "GPU frame (encode to idle, wall)",
        format!("{:.2}", s.gpu_wall_ms),
        String::new(),
    );
    let pairs = a.pairs;
    row(
        "GPU lists read back",
        format!("{:.1}", s.gpu_readback_ms),
        match &r.gpu_lists_difference {
            None => format!("identical to the uploaded lists ({pairs} pairs)"),
            Some(d) => format!("DIFFERENT from the uploaded lists: {d}"),
        },
    );
    row(
        &format!("oracle check ({})", c.mode),
        format!("{:.1}", s.check_ms),
        format!(
            "{} of {} clusters: {} exact pairs, {} reported, {} misses, {} false positives",
            c.clusters_checked,
            c.clusters_total,
            c.exact_pairs,
            c.reported_pairs,
            c.misses,
            c.false_positives
        ),
    );
    println!(
        "peak memory (VmHWM): {}",
        r.peak_memory_bytes
            .map_or("unknown".to_string(), |b| format!("{:.1} MiB", mib(b)))
    );
    if r.passed {
        println!(
            "PASS: no light missing from any checked cluster, and the GPU holds the lists as \
             uploaded"
        );
    } else if c.misses > 0 {
        println!("FAIL: {} miss(es)", c.misses);
    } else {
        println!("FAIL: the GPU's lists differ from the uploaded ones");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The comparison names the first array and position where the GPU's copy differs, and
    /// finds nothing in an equal copy.
    #[test]
    fn a_difference_in_the_read_back_lists_is_named() {
        let mut lists = LightLists::new();
        lists.offsets = vec![0, 2, 3];
        lists.counts = vec![2, 1, 0];
        lists.indices = vec![4, 7, 4];
        let same = ListsReadBack {
            offsets: lists.offsets.clone(),
            counts: lists.counts.clone(),
            indices: lists.indices.clone(),
        };
        assert_eq!(lists_difference(&same, &lists), None);
        let mut changed = same.clone();
        changed.indices[2] = 5;
        assert_eq!(
            lists_difference(&changed, &lists).as_deref(),
            Some("indices[2] is 5 on the GPU, 4 uploaded")
        );
        let mut short = same.clone();
        short.counts.pop();
        assert_eq!(
            lists_difference(&short, &lists).as_deref(),
            Some("counts: 2 on the GPU, 3 uploaded")
        );
    }

    #[test]
    fn a_refused_render_says_what_to_change() {
        let too_large = |what| GpuError::BufferTooLarge {
            what,
            bytes: 2_915_456_588,
            limit: 134_217_728,
        };
        // The indices fit 2^25 pairs of four bytes: that budget coarsens the grid until they do.
        assert_eq!(
            render_hint(&too_large("light indices"), false),
            " (--pair-budget 33554432 coarsens the grid until the lists fit this device)"
        );
        // The lights' buffer does not depend on the grid, nor on the pairs.
        assert_eq!(render_hint(&too_large("lights"), false), "");
        let loop_limit = GpuError::ShaderLoopLimit {
            mode: myriad::gpu::ShadingMode::Lists,
            lights: 70_000,
            max_lights: 65_530,
            adapter: "llvmpipe".into(),
            limit: 65_535,
        };
        assert_eq!(
            render_hint(&loop_limit, false),
            " (a finer --grid gives shorter lists)"
        );
        // Under a budget that coarsened the grid, a finer --grid would be coarsened again.
        assert_eq!(
            render_hint(&loop_limit, true),
            " (a larger --pair-budget keeps a finer grid, with shorter lists; or fewer lights)"
        );
    }
}
