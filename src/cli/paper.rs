//! `myriad paper`: the paper's Tables 1 and 2 and its Figure 4, measured here and printed next to
//! the paper's own figures.
//!
//! Why a command of its own: the project exists to implement and beat Örtegren's "Implicit
//! Clustered Deferred Shading" (seed 000), so its results must be reproducible with one command
//! and compared row for row — 10 and 1000 lights, grids 24×12×16, 24×12×32, 24×12×64 and
//! brute-force deferred shading ("no clustering"), with shading time, light-assignment time, total
//! and the memory of the light lists. `myriad render` answers a different question (one grid,
//! clustered against tiled against brute force, per stage).
//!
//! The scene is the paper's, Crytek Sponza at 1536×768, when `--assets` (default
//! `../shared/assets`) holds `sponza/Sponza.gltf`; otherwise the generated atrium, and the output
//! says which. The lights are the model's own, then lights on its surfaces
//! ([`RenderScene::from_model`]). The paper's numbers are hard-coded below as data (its Tables 1
//! and 2); they come from a 2013 laptop (i7-3630QM, GTX 660M, DirectX 11), so only ratios
//! compare, and on Mesa's llvmpipe (a CPU rasteriser) our GPU times are far larger.
//!
//! Two differences from the paper are deliberate and printed: our "total" also counts the
//! G-buffer pass (the paper's total is shading + assignment; the speed-up line uses the paper's
//! definition on both sides), and the grid's depth slicing is logarithmic by default where the
//! paper spaced its planes uniformly (`--depth linear` for that).

use super::assign::parse_method;
use super::grid_options::{check_slicing, parse_slicing};
use super::pair_budget::device_coarsened_warning;
use super::progress::Progress;
use super::render::parse_size;
use anyhow::{Context, Result, bail};
use myriad::assignment::Method;
use myriad::cluster_math::ClusterGrid;
use myriad::cluster_math::glam::UVec3;
use myriad::gpu::layout::GpuLight;
use myriad::gpu::legend::with_heat_legend;
use myriad::gpu::{GpuContext, PassTimes, encode_png};
use myriad::render::{PixelStats, RenderScene, Shading, Viewer, pixel_stats};
use myriad::scene::{LoadOptions, Model, check_replaceable, replace_files};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// Where Sponza lies under the assets folder.
const SPONZA: &str = "sponza/Sponza.gltf";
/// After the warm-up frame, a configuration whose frames take longer than this (seconds) is
/// measured over a single timed frame.
const SLOW_FRAME_SECONDS: f64 = 10.0;
/// Light counts of the paper's tables, in the order they are measured and printed.
const LIGHT_COUNTS: [usize; 2] = [10, 1000];
/// Depth slices of the paper's three grids (24×12×Z).
const Z_SLICES: [u32; 3] = [16, 32, 64];
/// The grid of the Figure 4 heat map. The paper does not say which grid its figure used; its
/// middle one (the fastest in total at 1000 lights) is taken.
const HEAT_MAP_Z: u32 = 32;
/// Lights per pixel at the top of the heat map's ramp, as in the paper's Figure 4 ("black is 0
/// lights and white is 50 lights"); raised to the frame's maximum if that is higher.
const PAPER_HEAT_MAX: u32 = 50;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Folder of the shared assets; Sponza is used when it has sponza/Sponza.gltf
    /// [default: ../shared/assets, else the generated atrium].
    #[arg(long)]
    assets: Option<PathBuf>,
    /// The model's camera, by name [default: its first].
    #[arg(long)]
    camera: Option<String>,
    /// Image size WxH (the paper's is 1536x768).
    #[arg(long, default_value = "1536x768")]
    size: String,
    /// Timed frames per configuration (medians are reported; after one untimed warm-up frame,
    /// a configuration whose frames take over 10 s gets one timed frame).
    #[arg(long, value_parser = super::run_count, default_value_t = 3)]
    runs: usize,
    /// Assignment method: exact, linear (the paper's Algorithm 1), binary, refined or cone.
    #[arg(long, default_value = "refined")]
    method: String,
    /// Depth slicing of the grids: log, linear (the paper's uniform spacing) or log_near:D.
    #[arg(long, default_value = "log")]
    depth: String,
    /// Seed of the surface lights.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output folder for paper_heatmap.png and paper.json.
    #[arg(long, default_value = "out")]
    out: PathBuf,
}

/// One row of the paper's Tables 1 and 2 as printed there (milliseconds; VRAM in the paper's
/// kB). `assign_ms` is `None` where the paper prints "-".
#[derive(Serialize, Debug, Clone, Copy)]
struct PaperRow {
    shading_ms: f64,
    assign_ms: Option<f64>,
    total_ms: f64,
    vram_kb: f64,
}

const fn paper_row(
    shading_ms: f64,
    assign_ms: Option<f64>,
    total_ms: f64,
    vram_kb: f64,
) -> PaperRow {
    PaperRow {
        shading_ms,
        assign_ms,
        total_ms,
        vram_kb,
    }
}

/// Örtegren, "Implicit Clustered Deferred Shading" (seed 000), Table 1, "Results from 1000
/// lights": rows 24x12x16, 24x12x32, 24x12x64, No clustering (Crytek Sponza, 1536×768,
/// i7-3630QM + GTX 660M).
const PAPER_TABLE_1: [PaperRow; 4] = [
    paper_row(8.12, Some(1.04), 9.16, 137.0),
    paper_row(6.08, Some(2.2), 8.28, 273.0),
    paper_row(5.97, Some(3.13), 9.1, 546.0),
    paper_row(156.0, None, 156.0, 0.0),
];

/// The same paper, Table 2, "Results from 10 lights", same rows.
const PAPER_TABLE_2: [PaperRow; 4] = [
    paper_row(0.53, Some(0.1), 0.63, 27.0),
    paper_row(0.5, Some(0.14), 0.64, 54.0),
    paper_row(0.5, Some(0.28), 0.78, 109.0),
    paper_row(1.6, None, 1.6, 0.0),
];

/// The paper's table for a light count, and its number.
fn paper_table(lights: usize) -> (u32, &'static [PaperRow; 4]) {
    if lights == 10 {
        (2, &PAPER_TABLE_2)
    } else {
        (1, &PAPER_TABLE_1)
    }
}

/// One measured configuration next to the paper's row.
#[derive(Serialize, Debug)]
struct Row {
    /// The paper's table this row belongs to (1: 1000 lights, 2: 10 lights).
    table: u32,
    lights: usize,
    /// "24x12x16", …, or "no clustering".
    config: String,
    /// The cluster grid, `None` for brute force.
    grid: Option<[u32; 3]>,
    /// Timed frames behind the medians.
    frames: usize,
    /// Median GPU shading pass + forward pass (timestamps), or the frame's wall time from submit
    /// to idle when the device has no timestamps (see `shading_source`).
    shading_ms: f64,
    /// "timestamps" or "wall clock".
    shading_source: &'static str,
    /// Median CPU light assignment (0 without clustering).
    assign_ms: f64,
    /// Median GPU G-buffer pass; `None` without timestamps (then it is inside `shading_ms`).
    gbuffer_ms: Option<f64>,
    /// `assign_ms + gbuffer_ms + shading_ms`.
    total_ms: f64,
    /// Bytes of the CSR light lists (offsets, counts, indices) as uploaded; 0 without clustering.
    list_bytes: u64,
    /// Cluster–light pairs.
    pairs: u64,
    /// Lights evaluated per pixel.
    pixels: PixelStats,
    /// The paper's figures for the same row.
    paper: PaperRow,
}

#[derive(Serialize, Debug)]
struct HeatMap {
    path: String,
    lights: usize,
    grid: [u32; 3],
    /// Lights per pixel at the top of the ramp.
    scale_max: u32,
    max_lights_per_pixel: u32,
    mean_lights_per_pixel: f64,
}

#[derive(Serialize, Debug)]
struct Report {
    scene: String,
    /// Whether the scene is the paper's (Sponza).
    sponza: bool,
    camera: String,
    width: u32,
    height: u32,
    adapter: String,
    timestamps: bool,
    method: String,
    depth_slicing: String,
    runs: usize,
    /// Bytes of the light data on the GPU (not in `list_bytes`, as the paper's VRAM column
    /// leaves it out too), per light count.
    light_buffer_bytes: Vec<(usize, u64)>,
    rows: Vec<Row>,
    heat_map: HeatMap,
}

/// The model to measure: Sponza from the assets folder, or the atrium.
struct Source {
    model: Model,
    name: String,
    sponza: bool,
    note: Option<String>,
}

/// The scene: Sponza from `assets` if it is there, else the atrium. `outputs`: the files the run
/// writes, which must not be Sponza's own.
fn find_source(assets: Option<&Path>, outputs: &[&Path]) -> Result<Source> {
    let (dir, explicit) = match assets {
        Some(dir) => (dir.to_path_buf(), true),
        None => (PathBuf::from("../shared/assets"), false),
    };
    if explicit && !dir.is_dir() {
        bail!(
            "--assets {}: no such folder (it should hold {SPONZA})",
            dir.display()
        );
    }
    let sponza = dir.join(SPONZA);
    if sponza.is_file() {
        let model = super::source::load_model(&sponza, &LoadOptions::default(), outputs)?;
        return Ok(Source {
            model,
            name: format!("Sponza ({})", sponza.display()),
            sponza: true,
            note: None,
        });
    }
    Ok(Source {
        model: myriad::scene::atrium(),
        name: "default scene (atrium)".into(),
        sponza: false,
        note: Some(format!(
            "{} {}, so not the paper's scene (Crytek Sponza); pass --assets DIR",
            sponza.display(),
            if sponza.exists() {
                "is not a file"
            } else {
                "not found"
            }
        )),
    })
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied()
}

/// Median times of one configuration.
struct Timed {
    frames: usize,
    shading_ms: f64,
    shading_source: &'static str,
    assign_ms: f64,
    gbuffer_ms: Option<f64>,
    pairs: u64,
    /// The grid the last frame's lists were built on (the scene's, or coarser past what the
    /// device binds).
    grid: ClusterGrid,
}

/// A frame's "shading" column from its pass times: the shading pass plus the forward pass of
/// blended geometry where it ran; `None` where the shading pass was not timed.
fn shading_column(p: &PassTimes) -> Option<f64> {
    p.shading_ms.map(|s| s + p.forward_ms.unwrap_or(0.0))
}

/// Whether a configuration has its frames once `timed` frames are timed (the warm-up frame
/// before them is not) and the last frame took `frame_seconds`: after `runs` timed frames, or
/// after the first timed one if it took over [`SLOW_FRAME_SECONDS`] (a slow warm-up alone
/// proves nothing: it also builds pipelines and buffers).
fn timing_done(timed: usize, runs: usize, frame_seconds: f64) -> bool {
    timed >= runs || (timed >= 1 && frame_seconds > SLOW_FRAME_SECONDS)
}

/// Renders one untimed warm-up frame (pipelines, buffers), then `runs` timed frames (one if a
/// frame takes longer than [`SLOW_FRAME_SECONDS`]); every frame assigns its lights anew.
fn time_frames(
    viewer: &mut Viewer,
    scene: &RenderScene,
    shading: Shading,
    method: Method,
    runs: usize,
) -> Result<Timed> {
    let (mut assign, mut wall, mut gbuffer, mut shade) = (vec![], vec![], vec![], vec![]);
    let mut frame_index = 0;
    let pairs = loop {
        let started = Instant::now();
        let frame = viewer.frame(scene, shading, method, false)?;
        let submitted = Instant::now();
        viewer.ctx.wait_idle()?;
        let frame_seconds = started.elapsed().as_secs_f64();
        if frame_index > 0 {
            assign.push(frame.assign_seconds * 1e3);
            wall.push((submitted.elapsed().as_secs_f64() + frame.report.encode_seconds) * 1e3);
            if let Some(p) = viewer.renderer.last_pass_times(&viewer.ctx)? {
                gbuffer.extend(p.gbuffer_ms);
                shade.extend(shading_column(&p));
            }
        }
        let pairs = (frame.stats.map_or(0, |s| s.pairs), frame.grid);
        let timed = frame_index;
        frame_index += 1;
        if timing_done(timed, runs, frame_seconds) {
            break pairs;
        }
    };
    let (pairs, grid) = pairs;
    let frames = wall.len();
    // Timestamps only count when every timed frame had them.
    let (shading_ms, shading_source, gbuffer_ms) = if shade.len() == frames {
        (median(shade), "timestamps", median(gbuffer))
    } else {
        (median(wall), "wall clock", None)
    };
    Ok(Timed {
        frames,
        shading_ms: shading_ms.context("no timed frame")?,
        shading_source,
        assign_ms: median(assign).context("no timed frame")?,
        gbuffer_ms,
        pairs,
        grid,
    })
}

/// Lights per pixel of the frame just rendered on `grid` (depth read back; every light for brute
/// force).
fn frame_pixels(
    viewer: &Viewer,
    scene: &RenderScene,
    grid: &ClusterGrid,
    shading: Shading,
) -> Result<PixelStats> {
    let depth = viewer
        .renderer
        .read_depth(&viewer.ctx)?
        .context("a frame was rendered")?;
    let lights = scene.lights.len();
    Ok(if shading == Shading::BruteForce {
        let all = vec![lights as u32; grid.cluster_count()];
        pixel_stats(&depth, &scene.camera, grid, &all, lights)
    } else {
        pixel_stats(&depth, &scene.camera, grid, &viewer.lists().counts, lights)
    })
}

pub fn run(args: Args) -> Result<ExitCode> {
    let (width, height) = parse_size(&args.size)?;
    super::source::check_image_memory(width, height)?;
    let method = parse_method(&args.method)?;
    let slicing = parse_slicing(&args.depth)?;
    if args.runs == 0 {
        bail!("--runs 0: expected at least 1 timed frame per configuration");
    }
    let heat_path = args.out.join("paper_heatmap.png");
    let json_path = args.out.join("paper.json");
    let source = find_source(args.assets.as_deref(), &[&heat_path, &json_path])?;
    let camera = match &args.camera {
        Some(name) => name.clone(),
        // The view `RenderScene::from_model` takes: the first camera, or (orthographic or
        // none) a view of the bounds, named as such.
        None => source
            .model
            .camera_or_view(0, width, height)
            .map_or_else(|| "(none)".into(), |(_, name)| name),
    };
    super::source::note_model_scene(
        &source.model,
        &source.name,
        args.camera.as_deref(),
        LIGHT_COUNTS[0],
    );
    let scenes: Vec<RenderScene> = LIGHT_COUNTS
        .iter()
        .map(|&n| {
            RenderScene::from_model(
                &source.model,
                &source.name,
                args.camera.as_deref(),
                n,
                args.seed,
                width,
                height,
            )
        })
        .collect::<Result<_>>()?;
    for (scene, &z) in scenes
        .iter()
        .flat_map(|s| Z_SLICES.iter().map(move |z| (s, z)))
    {
        check_slicing(slicing, z, scene.grid.near(), scene.grid.far())?;
    }

    // The heat map and the JSON describe one run: a target neither can replace (a folder, a
    // read-only file) is said before the minutes of rendering, and both are written at the end
    // as one set.
    super::outputs::check_out_folder_writable(&args.out)?;
    check_replaceable(&[&heat_path, &json_path])?;

    let ctx = GpuContext::headless()?;
    let adapter = ctx.describe();
    let timestamps = ctx.has_timestamps();
    let mut viewer = Viewer::new(ctx, &scenes[0])?;

    let configs: Vec<Option<u32>> = Z_SLICES.iter().map(|&z| Some(z)).chain([None]).collect();
    let total_rows = LIGHT_COUNTS.len() * configs.len();
    let mut heat_map = None;
    let mut rows = Vec::new();
    let progress = Progress::new("paper");
    for (base, &lights) in scenes.iter().zip(&LIGHT_COUNTS) {
        let (table, paper) = paper_table(lights);
        for (config, paper) in configs.iter().zip(paper) {
            let (scene, shading, name) = match *config {
                Some(z) => {
                    let dims = UVec3::new(24, 12, z);
                    (
                        base.clone().with_grid(dims, slicing),
                        Shading::Clustered,
                        format!("24x12x{z}"),
                    )
                }
                None => (base.clone(), Shading::BruteForce, "no clustering".into()),
            };
            progress.start(&format!(
                "[{}/{total_rows}] {lights} lights, {name}",
                rows.len() + 1
            ));
            let t = time_frames(&mut viewer, &scene, shading, method, args.runs)?;
            if let Some(warning) = device_coarsened_warning(
                &format!("{}: {name}", scene.name),
                scene.grid.dims(),
                t.grid.dims(),
                viewer.ctx.max_list_pairs(),
            ) {
                progress.line(warning);
            }
            let pixels = frame_pixels(&viewer, &scene, &t.grid, shading)?;
            let clustered = shading == Shading::Clustered;
            let list_bytes = if clustered {
                viewer.lists().byte_size() as u64
            } else {
                0
            };
            let row = Row {
                table,
                lights,
                config: name,
                grid: clustered.then(|| t.grid.dims().to_array()),
                frames: t.frames,
                shading_ms: t.shading_ms,
                shading_source: t.shading_source,
                assign_ms: t.assign_ms,
                gbuffer_ms: t.gbuffer_ms,
                total_ms: t.assign_ms + t.gbuffer_ms.unwrap_or(0.0) + t.shading_ms,
                list_bytes,
                pairs: t.pairs,
                pixels,
                paper: *paper,
            };
            progress.line(format!(
                "[{}/{total_rows}] {lights} lights, {}: shading {:.2} ms, assignment {}, \
                 total {:.2} ms, lists {} bytes ({} frame{})",
                rows.len() + 1,
                row.config,
                row.shading_ms,
                if clustered {
                    format!("{:.3} ms", row.assign_ms)
                } else {
                    "none".into()
                },
                row.total_ms,
                row.list_bytes,
                row.frames,
                if row.frames == 1 { "" } else { "s" }
            ));
            if clustered && lights == 1000 && *config == Some(HEAT_MAP_Z) {
                heat_map = Some(render_heat_map(
                    &mut viewer,
                    &scene,
                    method,
                    &pixels,
                    &heat_path,
                )?);
            }
            rows.push(row);
        }
    }
    let (heat_map, heat_png) = heat_map.context("the heat-map configuration was measured")?;
    let light_buffer_bytes = LIGHT_COUNTS
        .iter()
        .map(|&n| (n, (n * size_of::<GpuLight>()) as u64))
        .collect();
    let report = Report {
        scene: source.name.clone(),
        sponza: source.sponza,
        camera,
        width,
        height,
        adapter,
        timestamps,
        method: method.name().into(),
        depth_slicing: args.depth.clone(),
        runs: args.runs,
        light_buffer_bytes,
        rows,
        heat_map,
    };
    super::outputs::create_out_folder(&args.out)?;
    let json = serde_json::to_string_pretty(&report)?;
    replace_files(&[(&heat_path, &heat_png), (&json_path, json.as_bytes())])?;
    print_report(&report, source.note.as_deref());
    println!("wrote {} and {}", heat_path.display(), json_path.display());
    Ok(ExitCode::SUCCESS)
}

/// Renders the heat map of the lists just built (the paper's Figure 4) with its legend; returns
/// its description and the PNG, which the run writes with its JSON.
fn render_heat_map(
    viewer: &mut Viewer,
    scene: &RenderScene,
    method: Method,
    pixels: &PixelStats,
    path: &Path,
) -> Result<(HeatMap, Vec<u8>)> {
    let scale_max = PAPER_HEAT_MAX.max(pixels.max_lights);
    let saved = viewer.settings;
    viewer.settings.heat_max = Some(scale_max);
    let frame = viewer.frame(scene, Shading::Clustered, method, true);
    viewer.settings = saved;
    let grid = frame?.grid;
    viewer.ctx.wait_idle()?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let (image, legend_h) = with_heat_legend(&viewer.image()?, w, h, scale_max);
    let png = encode_png(&image, w, legend_h)
        .with_context(|| format!("cannot encode {}", path.display()))?;
    let described = HeatMap {
        path: path.display().to_string(),
        lights: scene.lights.len(),
        grid: grid.dims().to_array(),
        scale_max,
        max_lights_per_pixel: pixels.max_lights,
        mean_lights_per_pixel: pixels.mean_lights,
    };
    Ok((described, png))
}

fn print_report(r: &Report, note: Option<&str>) {
    println!(
        "scene: {}, camera {}, {}x{}",
        r.scene,
        myriad::scene::printable(&r.camera),
        r.width,
        r.height
    );
    if let Some(note) = note {
        println!("note: {note}");
    }
    println!(
        "GPU: {}; pass timestamps: {}",
        r.adapter,
        if r.timestamps {
            "yes"
        } else {
            "no (shading = wall clock, G-buffer included)"
        }
    );
    println!(
        "assignment: {}; grids: {} depth slicing{}; medians of up to {} frame(s)",
        r.method,
        r.depth_slicing,
        if r.depth_slicing == "log" {
            " (the paper: uniform, --depth linear)"
        } else {
            ""
        },
        r.runs
    );
    let ms = |v: Option<f64>| v.map_or("—".to_string(), |v| format!("{v:.2}"));
    for &lights in LIGHT_COUNTS.iter().rev() {
        let (table, _) = paper_table(lights);
        println!();
        let head = format!("Table {table} — {lights} lights: ours (median of each column)");
        println!("{head:<82}| the paper's Table {table}");
        table_line([
            "# clusters",
            "shading",
            "assign",
            "G-buffer",
            "total",
            "lists",
            "pairs",
            "lts/px",
            "shading",
            "assign",
            "total",
            "VRAM",
        ]);
        table_line([
            "", "ms", "ms", "ms", "ms", "KiB", "", "mean", "ms", "ms", "ms", "kB",
        ]);
        for row in r.rows.iter().filter(|row| row.lights == lights) {
            let clustered = row.grid.is_some();
            table_line([
                &row.config,
                &format!("{:.2}", row.shading_ms),
                &if clustered {
                    format!("{:.3}", row.assign_ms)
                } else {
                    "—".into()
                },
                &ms(row.gbuffer_ms),
                &format!("{:.2}", row.total_ms),
                &format!("{:.1}", row.list_bytes as f64 / 1024.0),
                &row.pairs.to_string(),
                &format!("{:.1}", row.pixels.mean_lights),
                &format!("{:.2}", row.paper.shading_ms),
                &row.paper
                    .assign_ms
                    .map_or("—".into(), |a| format!("{a:.2}")),
                &format!("{:.2}", row.paper.total_ms),
                &format!("{}", row.paper.vram_kb),
            ]);
        }
        print_speedup(r, lights);
    }
    println!();
    let light_bytes = r
        .light_buffer_bytes
        .iter()
        .map(|(n, b)| format!("{b} bytes for {n} lights"))
        .collect::<Vec<_>>()
        .join(", ");
    let source = if r.timestamps {
        "timestamp queries"
    } else {
        "no timestamps: wall clock from submit to idle, G-buffer included"
    };
    for (column, meaning) in [
        (
            "shading",
            format!("GPU shading pass + forward pass ({source})"),
        ),
        (
            "assign",
            format!(
                "CPU light assignment ({}), every frame; none without clustering",
                r.method
            ),
        ),
        ("G-buffer", "GPU G-buffer pass".into()),
        (
            "total",
            "assign + G-buffer + shading (the paper's total is shading + assignment)".into(),
        ),
        (
            "lists",
            format!(
                "the CSR light lists as uploaded, 4·(2·clusters + pairs) bytes; like the paper's VRAM, without the light data ({light_bytes})"
            ),
        ),
        ("pairs", "cluster-light pairs".into()),
        ("lts/px", "lights evaluated per covered pixel, mean".into()),
        (
            "the paper",
            "Crytek Sponza, 1536x768, i7-3630QM + GTX 660M, DirectX 11 (Örtegren, Tables 1 and 2)"
                .into(),
        ),
    ] {
        println!("  {column:<10} {meaning}");
    }
    let h = &r.heat_map;
    println!(
        "Figure 4 ({} lights, {}x{}x{}): at most {} lights per pixel, {:.1} on average \
         (the paper: fewer than 50); heat map scale 0–{}",
        h.lights,
        h.grid[0],
        h.grid[1],
        h.grid[2],
        h.max_lights_per_pixel,
        h.mean_lights_per_pixel,
        h.scale_max
    );
}

/// One line of a results table: our eight columns, a bar, the paper's four.
fn table_line(cells: [&str; 12]) {
    const WIDTHS: [usize; 12] = [14, 9, 8, 9, 9, 9, 8, 8, 8, 7, 7, 6];
    let mut line = String::new();
    for (i, (cell, width)) in cells.iter().zip(WIDTHS).enumerate() {
        if i == 0 {
            line += &format!("{cell:<width$}");
        } else {
            line += &format!(" {cell:>width$}");
        }
        if i == 7 {
            line += " |";
        }
    }
    println!("{line}");
}

/// Brute force against the best grid, on the paper's "total" (shading + assignment) for both.
fn print_speedup(r: &Report, lights: usize) {
    let paper_total = |row: &Row| row.shading_ms + row.assign_ms;
    let rows: Vec<&Row> = r.rows.iter().filter(|row| row.lights == lights).collect();
    let Some(brute) = rows.iter().find(|row| row.grid.is_none()) else {
        return;
    };
    let Some(best) = rows
        .iter()
        .filter(|row| row.grid.is_some())
        .min_by(|a, b| paper_total(a).total_cmp(&paper_total(b)))
    else {
        return;
    };
    let (_, paper) = paper_table(lights);
    let paper_best = paper[..3]
        .iter()
        .map(|p| p.total_ms)
        .fold(f64::INFINITY, f64::min);
    println!(
        "no clustering vs the best grid, shading + assignment: ours {:.1}x ({}), the paper {:.1}x",
        paper_total(brute) / paper_total(best),
        best.config,
        paper[3].total_ms / paper_best
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shading_column_adds_the_forward_pass_to_the_shading_pass() {
        let passes = |shading_ms, forward_ms| PassTimes {
            gbuffer_ms: Some(4.0),
            shading_ms,
            forward_ms,
            upload_ms: Some(0.25),
        };
        assert_eq!(shading_column(&passes(Some(2.0), Some(0.5))), Some(2.5));
        assert_eq!(shading_column(&passes(Some(2.0), None)), Some(2.0));
        assert_eq!(shading_column(&passes(None, Some(0.5))), None);
    }

    #[test]
    fn timing_stops_after_the_runs_or_after_one_timed_frame_over_ten_seconds() {
        // Fast frames: `runs` timed frames after the warm-up.
        for runs in [1, 3] {
            for timed in 0..runs {
                assert!(!timing_done(timed, runs, 0.5), "{timed} of {runs}");
            }
            assert!(timing_done(runs, runs, 0.5), "{runs}");
        }
        // A slow first timed frame is the only one; a slow warm-up still gets one timed frame.
        assert!(timing_done(1, 3, 10.5));
        assert!(!timing_done(0, 3, 60.0));
        // "Over 10 s": exactly 10 s is not slow.
        assert!(!timing_done(1, 3, SLOW_FRAME_SECONDS));
    }
}
