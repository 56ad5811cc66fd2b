//! `myriad stress --lights N`: one frame with very many lights, end to end, every stage timed
//! and the lists proven against the exact oracle.
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
//!    scratch and the lists, the second reuses them (the steady state a frame loop sees);
//! 3. **GPU setup** — device, geometry upload, and one warm-up frame with the same lights and
//!    empty lists, so that pipeline compilation and the light buffer's allocation do not land in
//!    the measured frame;
//! 4. **upload** of the measured frame (lights → GPU records, lists, through the staging ring):
//!    bytes and CPU time;
//! 5. **GPU render**, clustered only: pass timestamps where the adapter has them, and the wall
//!    time from submit to idle. (Brute force and one-slice tiles are not attempted: on llvmpipe
//!    a pixel may loop over at most 65 535 lights and the renderer refuses more —
//!    `GpuError::ShaderLoopLimit`; clustered lists stay far below that);
//! 6. **oracle check**, two ways:
//!    * up to `--exact-up-to` lights (200k), **every cluster**: the `exact` method's lists and
//!      [`myriad::evaluate::compare`];
//!    * above, **`--sample K` clusters** (2000, seeded), each checked on its own: every light is
//!      tested against the cluster's cell with the f64 oracle itself
//!      ([`LightVolume::intersects_cell`] on [`Cell::of_cluster`], the lights read by
//!      [`OracleView::light`] as the `exact` method and the assignment tests' brute force read
//!      them), after a depth window and a test against the cell's
//!      four walls, which only drop lights the oracle rejects too (their slack is far wider
//!      than the oracle's tolerance). Every light the oracle accepts must be in the list.
//!
//!    A miss names the cluster and the light. Why two: the `exact` method finds its candidate
//!    clusters with the same cull and plane-search phases as the fast methods (only more
//!    padded), so a bug there could hide from a comparison with it; the sampled check shares no
//!    code with the assignment but the oracle. It is not cheaper: on the atrium with 1M lights
//!    the sampled check of 2000 of 4608 clusters took about 2.6× as long as the full one
//!    (`--exact-up-to 2000000`; 4.4 s against 1.7 s on the 2-core machine), because the
//!    `exact` method tests only each light's candidate clusters while a sampled cluster scans
//!    every light in its depth window.
//!    So the split at 200k is about independence, not speed; `--exact-up-to` moves it.
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
use super::progress::Progress;
use super::render::parse_size;
use anyhow::{Result, ensure};
use myriad::assignment::{Assigner, LightLists, Method};
use myriad::cluster_math::glam::{DVec3, Vec3};
use myriad::cluster_math::oracle::{Cell, LightVolume, OracleView};
use myriad::cluster_math::{Camera, ClusterGrid};
use myriad::evaluate::compare;
use myriad::gpu::{ClusterLists, FrameDesc, GpuContext, GpuError};
use myriad::render::{RenderScene, Viewer, cluster_lists, grid_of, light_columns};
use myriad::scene::{DepthSlicing, Lights};
use rand::SeedableRng;
use rayon::prelude::*;
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
    /// Assignment method: exact, linear, binary or refined.
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
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
}

/// Milliseconds of each stage.
#[derive(Serialize, Debug, Default)]
struct Stages {
    scene_ms: f64,
    assign_ms: f64,
    assign_again_ms: f64,
    gpu_setup_ms: f64,
    upload_ms: f64,
    encode_ms: f64,
    /// Submit to GPU idle, wall clock (includes encode + submit).
    gpu_wall_ms: f64,
    gpu_gbuffer_ms: Option<f64>,
    gpu_shading_ms: Option<f64>,
    gpu_forward_ms: Option<f64>,
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

/// A light the oracle puts in a cluster but the list lacks.
#[derive(Serialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Miss {
    cluster: u32,
    /// (i, j, k) of the cluster.
    tile: [u32; 3],
    light: u32,
}

/// The oracle check's outcome.
#[derive(Serialize, Debug, Clone, PartialEq)]
pub(crate) struct CheckReport {
    /// "full" (every cluster, exact lists) or "sampled".
    mode: &'static str,
    clusters_checked: u64,
    clusters_total: u64,
    exact_pairs: u64,
    reported_pairs: u64,
    misses: u64,
    false_positives: u64,
    /// The miss in the lowest cluster (lowest light first), if any.
    first_miss: Option<Miss>,
}

#[derive(Serialize, Debug)]
struct Report {
    scene: String,
    lights: usize,
    width: u32,
    height: u32,
    grid: [u32; 3],
    method: String,
    seed: u64,
    adapter: String,
    timestamps: bool,
    /// The adapter's per-pixel loop limit (llvmpipe), if it has one.
    shader_loop_limit: Option<u64>,
    stages: Stages,
    assignment: Assignment,
    upload_bytes: u64,
    check: CheckReport,
    /// VmHWM of this process; `null` where unknown.
    peak_memory_bytes: Option<u64>,
    passed: bool,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let method = parse_method(&args.method)?;
    let (width, height) = parse_size(&args.size)?;
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
    let progress = Progress::new("stress");
    let mut stages = Stages::default();

    // 1. Scene.
    let (scene, seconds) = progress.stage("scene generation", || {
        RenderScene::from_model(
            &myriad::scene::atrium(),
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
    let mut assigner = Assigner::new();
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
    let grid = grid_of(&stats, &scene.grid);
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
    let (mut viewer, seconds) =
        progress.stage("GPU setup (device, geometry, warm-up frame)", || {
            let ctx = GpuContext::headless()?;
            let mut viewer = Viewer::new(ctx, &scene)?;
            let empty = vec![0u32; grid.cluster_count()];
            let no_lists = ClusterLists {
                offsets: &empty,
                counts: &empty,
                indices: &[],
            };
            let warm_up = FrameDesc {
                settings: viewer.settings,
                ..FrameDesc::clustered(&scene.camera, &grid, light_columns(&scene.lights), no_lists)
            };
            viewer
                .renderer
                .render(&viewer.ctx, &viewer.scene, &warm_up, &viewer.target.view)?;
            viewer.ctx.wait_idle()?;
            Ok(viewer)
        })?;
    stages.gpu_setup_ms = seconds * 1e3;
    let adapter = viewer.ctx.describe();
    let timestamps = viewer.ctx.has_timestamps();
    let shader_loop_limit = viewer.ctx.shader_loop_limit();

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
    let report = viewer
        .renderer
        .render(&viewer.ctx, &viewer.scene, &frame, &viewer.target.view)
        .map_err(|e| {
            let hint = match e {
                GpuError::ShaderLoopLimit { .. } => " (a finer --grid gives shorter lists)",
                _ => "",
            };
            anyhow::Error::new(e).context(format!(
                "rendering {} lights clustered{hint}",
                scene.lights.len()
            ))
        })?;
    stages.upload_ms = report.upload_seconds * 1e3;
    stages.encode_ms = report.encode_seconds * 1e3;
    progress.done(
        "upload + encode + submit",
        report.upload_seconds + report.encode_seconds,
    );
    progress.note(&format!("{} bytes uploaded", report.upload_bytes));

    // 5. The GPU's work: submit to idle, wall clock (encode + submit included, as `myriad
    // render` reports it), and the pass timestamps.
    let (wait_seconds, _) = progress.stage("GPU render (clustered)", || {
        let start = Instant::now();
        viewer.ctx.wait_idle()?;
        Ok(start.elapsed().as_secs_f64())
    })?;
    stages.gpu_wall_ms = (wait_seconds + report.encode_seconds) * 1e3;
    let passes = viewer.renderer.last_pass_times(&viewer.ctx)?;
    if let Some(p) = passes {
        stages.gpu_gbuffer_ms = p.gbuffer_ms;
        stages.gpu_shading_ms = p.shading_ms;
        stages.gpu_forward_ms = p.forward_ms;
    }
    drop(viewer);

    // 6. Oracle.
    let full = scene.lights.len() <= args.exact_up_to;
    let stage_name = if full {
        "oracle check (every cluster, exact lists)".to_string()
    } else {
        let k = args.sample.min(grid.cluster_count());
        format!("oracle check ({k} sampled clusters)")
    };
    let (check, seconds) = progress.stage(&stage_name, || {
        Ok(if full {
            check_all(&scene.lights, &scene.camera, &grid, &lists)
        } else {
            let clusters = sample_clusters(grid.cluster_count(), args.sample, args.seed);
            let oracle = OracleLights::new(&scene.lights, &scene.camera);
            check_clusters(&oracle, &scene.camera, &grid, &lists, &clusters)
        })
    })?;
    stages.check_ms = seconds * 1e3;
    progress.finish();

    let d = grid.dims;
    let out = Report {
        scene: scene.name.clone(),
        lights: scene.lights.len(),
        width,
        height,
        grid: [d.x, d.y, d.z],
        method: method.name().to_string(),
        seed: args.seed,
        adapter,
        timestamps,
        shader_loop_limit,
        stages,
        assignment,
        upload_bytes: report.upload_bytes,
        passed: check.misses == 0,
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
    Ok(ExitCode::SUCCESS)
}

/// Every cluster: the `exact` method's lists against the reported ones.
fn check_all(
    lights: &Lights,
    camera: &Camera,
    grid: &ClusterGrid,
    lists: &LightLists,
) -> CheckReport {
    let mut exact = LightLists::new();
    Assigner::new().assign(
        Method::Exact,
        &myriad::light_input(lights),
        camera,
        grid,
        &mut exact,
    );
    let cmp = compare(lists, &exact);
    let first_miss = (cmp.misses > 0)
        .then(|| {
            (0..exact.cluster_count()).find_map(|c| {
                let got = lists.lights_of(c);
                exact
                    .lights_of(c)
                    .iter()
                    .find(|l| !got.contains(l))
                    .map(|&light| miss(grid, c as u32, light))
            })
        })
        .flatten();
    CheckReport {
        mode: "full",
        clusters_checked: exact.cluster_count() as u64,
        clusters_total: grid.cluster_count() as u64,
        exact_pairs: cmp.exact_pairs,
        reported_pairs: cmp.reported_pairs,
        misses: cmp.misses,
        false_positives: cmp.false_positives,
        first_miss,
    }
}

fn miss(grid: &ClusterGrid, cluster: u32, light: u32) -> Miss {
    let t = grid.cluster_coords(cluster);
    Miss {
        cluster,
        tile: [t.x, t.y, t.z],
        light,
    }
}

/// `k` distinct cluster ids of `0..count` drawn from `seed`, ascending (all of them when `k`
/// is at least `count`).
pub(crate) fn sample_clusters(count: usize, k: usize, seed: u64) -> Vec<u32> {
    if k >= count {
        return (0..count as u32).collect();
    }
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed ^ 0x5354_5245_5353); // "STRESS"
    let mut picked: Vec<u32> = rand::seq::index::sample(&mut rng, count, k)
        .into_iter()
        .map(|c| c as u32)
        .collect();
    picked.sort_unstable();
    picked
}

/// One valid light in f64 view space.
#[derive(Clone, Copy, Debug)]
struct ViewLight {
    volume: LightVolume,
    /// Centre and radius of the volume's bounding ball, for the cheap filters.
    centre: DVec3,
    radius: f64,
    /// Index into the input columns.
    index: u32,
}

/// The lights as the oracle sees them ([`OracleView::light`], as the `exact` method reads them),
/// sorted by depth, so one cluster's candidates are a window of the array. Invalid lights are
/// left out, since no method may assign them.
pub(crate) struct OracleLights {
    lights: Vec<ViewLight>,
    /// `-centre.z` of each light, ascending.
    depths: Vec<f64>,
    max_radius: f64,
}

impl OracleLights {
    pub(crate) fn new(lights: &Lights, camera: &Camera) -> Self {
        let view = OracleView::new(camera);
        let spots_present = lights.has_spots();
        let mut sorted: Vec<ViewLight> = (0..lights.len())
            .into_par_iter()
            .filter_map(|l| {
                let position = Vec3::new(lights.x[l], lights.y[l], lights.z[l]);
                let spot = spots_present.then(|| {
                    let direction = Vec3::new(
                        lights.spot_dir_x[l],
                        lights.spot_dir_y[l],
                        lights.spot_dir_z[l],
                    );
                    (direction, lights.spot_angle[l])
                });
                let volume = view.light(position, lights.radius[l], spot)?;
                let (centre, radius) = volume.bounding_ball();
                Some(ViewLight {
                    volume,
                    centre,
                    radius,
                    index: l as u32,
                })
            })
            .collect();
        sorted.par_sort_unstable_by(|a, b| (-a.centre.z).total_cmp(&-b.centre.z));
        Self {
            depths: sorted.iter().map(|l| -l.centre.z).collect(),
            max_radius: sorted.iter().map(|l| l.radius).fold(0.0, f64::max),
            lights: sorted,
        }
    }

    /// The input indices of every light the oracle says touches `cell`, ascending.
    fn touching(&self, cell: &Cell, out: &mut Vec<u32>) {
        out.clear();
        // The cell is where four walls through the eye and two depth planes hold it; a ball whose
        // centre lies farther than its radius outside any one of them misses the cell. Outward
        // unit normals of the walls (left, right, bottom, top): inside ⇔ `n·p ≤ 0`.
        let walls = [
            DVec3::new(-1.0, 0.0, -cell.x_slopes[0]).normalize(),
            DVec3::new(1.0, 0.0, cell.x_slopes[1]).normalize(),
            DVec3::new(0.0, -1.0, -cell.y_slopes[0]).normalize(),
            DVec3::new(0.0, 1.0, cell.y_slopes[1]).normalize(),
        ];
        // Slack far above the oracle's own tolerance bands (1e-12 of the local scale for spots,
        // 64 ulps for balls) and the rounding here, so these filters only drop lights the oracle
        // rejects too.
        let slack = |scale: f64| 1e-6 * (1.0 + scale);
        let [near, far] = cell.depths;
        // Depth window: the centre's depth is within the radius of the cell's depth range.
        let window = self.max_radius + slack(far + self.max_radius);
        let lo = self.depths.partition_point(|&d| d < near - window);
        let hi = self.depths.partition_point(|&d| d <= far + window);
        for light in &self.lights[lo..hi] {
            let c = light.centre;
            let reach = light.radius + slack(c.abs().element_sum() + light.radius);
            let depth = -c.z;
            if depth < near - reach || depth > far + reach || walls.iter().any(|n| n.dot(c) > reach)
            {
                continue;
            }
            if light.volume.intersects_cell(cell) {
                out.push(light.index);
            }
        }
        out.sort_unstable();
    }
}

/// Checks the reported lists of `clusters` against the oracle, light by light.
pub(crate) fn check_clusters(
    oracle: &OracleLights,
    camera: &Camera,
    grid: &ClusterGrid,
    lists: &LightLists,
    clusters: &[u32],
) -> CheckReport {
    #[derive(Default)]
    struct Tally {
        exact: u64,
        reported: u64,
        misses: u64,
        first_miss: Option<(u32, u32)>,
    }
    let tally = clusters
        .par_iter()
        .map_init(Vec::new, |exact, &c| {
            let t = grid.cluster_coords(c);
            let cell = Cell::of_cluster(camera, grid, t.x, t.y, t.z);
            oracle.touching(&cell, exact);
            let mut got = lists.lights_of(c as usize).to_vec();
            got.sort_unstable();
            got.dedup();
            let missing: Vec<u32> = exact
                .iter()
                .copied()
                .filter(|l| got.binary_search(l).is_err())
                .collect();
            Tally {
                exact: exact.len() as u64,
                reported: got.len() as u64,
                misses: missing.len() as u64,
                first_miss: missing.first().map(|&l| (c, l)),
            }
        })
        .reduce(Tally::default, |a, b| Tally {
            exact: a.exact + b.exact,
            reported: a.reported + b.reported,
            misses: a.misses + b.misses,
            first_miss: match (a.first_miss, b.first_miss) {
                (Some(x), Some(y)) => Some(x.min(y)),
                (x, y) => x.or(y),
            },
        });
    CheckReport {
        mode: "sampled",
        clusters_checked: clusters.len() as u64,
        clusters_total: grid.cluster_count() as u64,
        exact_pairs: tally.exact,
        reported_pairs: tally.reported,
        misses: tally.misses,
        false_positives: tally.reported - (tally.exact - tally.misses),
        first_miss: tally.first_miss.map(|(c, l)| miss(grid, c, l)),
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
    println!(
        "{} — {} lights, {}x{}, grid {x}x{y}x{z}, method {}, seed {}",
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
            r.shader_loop_limit
                .map_or(String::new(), |l| format!(" (adapter loop limit {l})")),
            mib(a.list_bytes)
        ),
    );
    row(
        "GPU setup (device, geometry, warm-up)",
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
        "GPU frame (submit to idle, wall)",
        format!("{:.2}", s.gpu_wall_ms),
        String::new(),
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
        println!("PASS: no light missing from any checked cluster");
    } else {
        println!("FAIL: {} miss(es)", c.misses);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small default scene (no GPU needed) and its refined lists.
    fn scene_and_lists(lights: usize) -> (RenderScene, LightLists) {
        let scene = RenderScene::default_scene(lights, 64, 36).unwrap();
        let mut lists = LightLists::new();
        Assigner::new().assign(
            Method::Refined,
            &myriad::light_input(&scene.lights),
            &scene.camera,
            &scene.grid,
            &mut lists,
        );
        (scene, lists)
    }

    /// `lists` without `light` in cluster `cluster`.
    fn without(lists: &LightLists, cluster: usize, light: u32) -> LightLists {
        let mut out = LightLists::new();
        for c in 0..lists.cluster_count() {
            out.offsets.push(out.indices.len() as u32);
            let kept: Vec<u32> = lists
                .lights_of(c)
                .iter()
                .copied()
                .filter(|&l| c != cluster || l != light)
                .collect();
            out.counts.push(kept.len() as u32);
            out.indices.extend(kept);
        }
        out
    }

    #[test]
    fn sampled_oracle_over_every_cluster_equals_the_exact_method() {
        let (scene, lists) = scene_and_lists(3000);
        let oracle = OracleLights::new(&scene.lights, &scene.camera);
        let every = sample_clusters(scene.grid.cluster_count(), usize::MAX, 1);
        let sampled = check_clusters(&oracle, &scene.camera, &scene.grid, &lists, &every);
        let full = check_all(&scene.lights, &scene.camera, &scene.grid, &lists);
        assert!(full.exact_pairs > 10_000, "{full:?}");
        assert_eq!(sampled.misses, 0);
        assert_eq!(
            (
                sampled.exact_pairs,
                sampled.reported_pairs,
                sampled.false_positives
            ),
            (full.exact_pairs, full.reported_pairs, full.false_positives)
        );
    }

    #[test]
    fn sampled_check_finds_a_light_removed_from_a_list() {
        let (scene, lists) = scene_and_lists(3000);
        let oracle = OracleLights::new(&scene.lights, &scene.camera);
        // A cluster and a light the oracle says touch it.
        let mut exact = Vec::new();
        let (cluster, light) = (0..scene.grid.cluster_count() as u32)
            .rev()
            .find_map(|c| {
                let t = scene.grid.cluster_coords(c);
                let cell = Cell::of_cluster(&scene.camera, &scene.grid, t.x, t.y, t.z);
                oracle.touching(&cell, &mut exact);
                exact.get(exact.len() / 2).map(|&l| (c, l))
            })
            .expect("some cluster has lights");
        let broken = without(&lists, cluster as usize, light);
        assert_eq!(broken.pair_count() + 1, lists.pair_count());
        // Sampled with the cluster among others: exactly that miss.
        let clusters = [0, cluster / 2, cluster];
        let ok = check_clusters(&oracle, &scene.camera, &scene.grid, &lists, &clusters);
        assert_eq!((ok.misses, ok.first_miss), (0, None));
        let bad = check_clusters(&oracle, &scene.camera, &scene.grid, &broken, &clusters);
        assert_eq!(bad.misses, 1);
        assert_eq!(bad.first_miss, Some(miss(&scene.grid, cluster, light)));
        // And the full check names the same pair.
        let full = check_all(&scene.lights, &scene.camera, &scene.grid, &broken);
        assert_eq!(full.misses, 1);
        assert_eq!(full.first_miss, Some(miss(&scene.grid, cluster, light)));
    }

    #[test]
    fn samples_are_distinct_seeded_and_ascending() {
        let a = sample_clusters(4608, 2000, 7);
        assert_eq!(a.len(), 2000);
        assert!(a.windows(2).all(|w| w[0] < w[1]));
        assert!(a.iter().all(|&c| c < 4608));
        assert_eq!(a, sample_clusters(4608, 2000, 7));
        assert_ne!(a, sample_clusters(4608, 2000, 8));
        assert_eq!(sample_clusters(10, 50, 1), (0..10).collect::<Vec<_>>());
    }
}
