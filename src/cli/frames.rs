//! `myriad frames`: the frame loop run sequentially and pipelined (assignment of frame N+1 on a
//! worker thread while frame N uploads and renders), with per-stage times, to show what the
//! pipelining saves.

use super::assign::parse_method;
use super::pair_budget::device_coarsened_warning;
use super::render::parse_size;
use super::source::check_memory_for;
use anyhow::Result;
use myriad::cluster_math::glam::UVec3;
use myriad::gpu::{GpuContext, HEADLESS_FORMAT, HeadlessTarget, Renderer};
use myriad::render::{DEFAULT_GRID, GpuStage, LoopReport, run_frames};
use serde::Serialize;
use std::process::ExitCode;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Lights (the atrium's own, then lights on its surfaces), orbiting the view's centre.
    #[arg(long, value_parser = super::light_count, default_value_t = 100_000)]
    lights: usize,
    /// Frames per loop, 2 to 1 000 000 (each frame's stage times are kept for the summary).
    #[arg(long, value_parser = super::run_count, default_value_t = 30)]
    frames: usize,
    /// Image size WxH.
    #[arg(long, default_value = "320x160")]
    size: String,
    /// Assignment method.
    #[arg(long, default_value = "refined")]
    method: String,
    /// Assign and upload every light, not only those the frustum cull keeps.
    #[arg(long)]
    no_cull: bool,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Summary {
    pipelined: bool,
    frames: usize,
    frame_ms: f64,
    stage_sum_ms: f64,
    animate_ms: f64,
    cull_ms: f64,
    lights_uploaded: f64,
    assign_ms: f64,
    upload_ms: f64,
    upload_bytes: f64,
    encode_ms: f64,
    gpu_wait_ms: f64,
    gpu_passes_ms: Option<f64>,
    /// Frames whose lists were built on a coarser grid than the scene's (more pairs than the
    /// device binds in one buffer), and the coarsest such grid.
    coarsened_frames: usize,
    coarsest_grid: Option<[u32; 3]>,
}

/// Clusters of a grid of `dims`.
fn cluster_count(dims: &[u32; 3]) -> u64 {
    dims.iter().map(|&d| u64::from(d)).product()
}

/// `r`'s means; `grid` is the scene's.
fn summary(r: &LoopReport, grid: [u32; 3]) -> Summary {
    let coarser: Vec<[u32; 3]> = r
        .frames
        .iter()
        .map(|f| f.grid_dims)
        .filter(|&g| g != grid)
        .collect();
    // The first frame builds pipelines and buffers: leave it out of the means.
    let steady = LoopReport {
        pipelined: r.pipelined,
        frames: r.frames[1..].to_vec(),
        ..Default::default()
    };
    let ms = |f: &dyn Fn(&myriad::render::StageTimes) -> f64| steady.mean(f) * 1e3;
    let passes: Vec<f64> = steady
        .frames
        .iter()
        .filter_map(|f| f.gpu_passes.map(|p| p.total_ms()))
        .collect();
    Summary {
        pipelined: r.pipelined,
        frames: r.frames.len(),
        frame_ms: r.steady_frame_seconds().unwrap_or(0.0) * 1e3,
        stage_sum_ms: ms(&|f| f.sum_seconds()),
        animate_ms: ms(&|f| f.animate_seconds),
        cull_ms: ms(&|f| f.cull_seconds),
        lights_uploaded: steady.mean(|f| f.lights_uploaded as f64),
        assign_ms: ms(&|f| f.assign_seconds),
        upload_ms: ms(&|f| f.upload_seconds),
        upload_bytes: steady.mean(|f| f.upload_bytes as f64),
        encode_ms: ms(&|f| f.encode_seconds),
        gpu_wait_ms: ms(&|f| f.gpu_wait_seconds),
        gpu_passes_ms: (!passes.is_empty())
            .then(|| passes.iter().sum::<f64>() / passes.len() as f64),
        coarsened_frames: coarser.len(),
        coarsest_grid: coarser.into_iter().min_by_key(cluster_count),
    }
}

pub fn run(args: Args) -> Result<ExitCode> {
    anyhow::ensure!(
        args.frames >= 2,
        "--frames must be at least 2 (the first is a warm-up)"
    );
    let method = parse_method(&args.method)?;
    let (width, height) = parse_size(&args.size)?;
    super::source::check_image_memory(width, height)?;
    check_memory_for(DEFAULT_GRID, args.lights)?;
    let scene = super::source::noted_default_scene(args.lights, width, height)?;
    let ctx = GpuContext::headless()?;
    let mut renderer = Renderer::new(&ctx, HEADLESS_FORMAT);
    let gpu_scene = renderer.upload_scene(&ctx, &scene.geometry)?;
    let target = HeadlessTarget::new(&ctx.device, width, height)?;
    let mut results = Vec::new();
    for pipelined in [false, true] {
        let mut stage = GpuStage {
            ctx: &ctx,
            renderer: &mut renderer,
            scene: &gpu_scene,
            target: &target,
            settings: Default::default(),
        };
        let report = run_frames(
            &mut stage,
            &scene,
            method,
            args.frames,
            pipelined,
            !args.no_cull,
            |_, _| Ok(()),
        )?;
        results.push(summary(&report, scene.grid.dims().to_array()));
    }
    // Once for both loops: the coarsest grid any frame was shaded on.
    let coarsest = results
        .iter()
        .flat_map(|r| r.coarsest_grid)
        .min_by_key(cluster_count);
    if let Some(warning) = coarsest.and_then(|grid| {
        device_coarsened_warning(
            &scene.name,
            scene.grid.dims(),
            UVec3::from_array(grid),
            ctx.max_list_pairs(),
        )
    }) {
        eprintln!("{warning}");
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&results)?);
        return Ok(ExitCode::SUCCESS);
    }
    println!(
        "{} — {} lights orbiting, {width}x{height}, method {}, {}, {} frames per loop, GPU: {}",
        scene.name,
        scene.lights.len(),
        method.name(),
        if args.no_cull {
            "every light assigned and uploaded"
        } else {
            "frustum-culled before assignment and upload"
        },
        args.frames,
        ctx.describe()
    );
    println!(
        "{:<34} {:>12} {:>12}",
        "mean per frame (ms)", "sequential", "pipelined"
    );
    let row = |name: &str, f: &dyn Fn(&Summary) -> String| {
        println!("{name:<34} {:>12} {:>12}", f(&results[0]), f(&results[1]));
    };
    row("animate lights (CPU)", &|s| format!("{:.3}", s.animate_ms));
    row("cull + gather (CPU)", &|s| format!("{:.3}", s.cull_ms));
    row("lights assigned and uploaded", &|s| {
        format!("{:.0}", s.lights_uploaded)
    });
    row("light assignment (CPU)", &|s| format!("{:.3}", s.assign_ms));
    row("upload: convert + stage (CPU)", &|s| {
        format!("{:.3}", s.upload_ms)
    });
    row("upload (KiB)", &|s| {
        format!("{:.1}", s.upload_bytes / 1024.0)
    });
    row("encode + submit (CPU)", &|s| format!("{:.3}", s.encode_ms));
    row("wait for GPU", &|s| format!("{:.3}", s.gpu_wait_ms));
    row("GPU passes + copies (timestamps)", &|s| {
        s.gpu_passes_ms.map_or("—".into(), |v| format!("{v:.3}"))
    });
    row("sum of the stages", &|s| format!("{:.3}", s.stage_sum_ms));
    row("frame time (wall, frame end to end)", &|s| {
        format!("{:.3}", s.frame_ms)
    });
    let p = &results[1];
    println!(
        "pipelined frame time is {:.1}% of its stage sum ({:.3} vs {:.3} ms) and {:.2}x the sequential frame time",
        100.0 * p.frame_ms / p.stage_sum_ms,
        p.frame_ms,
        p.stage_sum_ms,
        p.frame_ms / results[0].frame_ms
    );
    Ok(ExitCode::SUCCESS)
}
