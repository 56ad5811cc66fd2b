//! `myriad skips`: what each saving of [`Skips`] buys, alone and all together, on the default
//! scene and on Sponza (when `../shared/assets/sponza` is there): assignment time, pairs, bytes
//! uploaded and GPU shading time before and after, plus what it costs (the depth prepass) and
//! proof that the image did not change.

use super::assign::parse_method;
use super::list_options::refuse_repeats;
use super::render::parse_size;
use super::render_skipping::settle_tuner;
use super::source::check_memory_for;
use anyhow::Result;
use myriad::gpu::GpuContext;
use myriad::render::{
    DEFAULT_GRID, PrepassDecision, RenderScene, SkipFrame, Skips, Viewer, max_channel_difference,
};
use myriad::scene::LoadOptions;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Where Sponza is when the shared assets are checked out next to the repository.
const SPONZA: &str = "../shared/assets/sponza/Sponza.gltf";

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Models to measure [default: the atrium, and Sponza when ../shared/assets has it].
    #[arg(long)]
    gltf: Vec<PathBuf>,
    /// Lights per scene.
    #[arg(long, value_parser = super::light_count, default_value_t = 1000)]
    lights: usize,
    /// Image size WxH.
    #[arg(long, default_value = "1536x768")]
    size: String,
    /// Assignment method.
    #[arg(long, default_value = "refined")]
    method: String,
    /// Timed frames per configuration (medians).
    #[arg(long, value_parser = super::run_count, default_value_t = 3)]
    runs: usize,
    /// Print JSON instead of tables.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize, Clone, Debug)]
struct Measured {
    cpu_ms: f64,
    prepass_ms: f64,
    mask_ms: f64,
    /// GPU G-buffer pass inside the frame (0 when a prepass drew it).
    gbuffer_ms: f64,
    pairs: u64,
    lights_assigned: usize,
    upload_bytes: u64,
    shading_ms: Option<f64>,
    max_image_difference: u8,
}

#[derive(Serialize)]
struct Row {
    saving: &'static str,
    before: Measured,
    after: Measured,
    active_clusters: Option<usize>,
    clusters: usize,
    fitted_range: Option<[f32; 2]>,
    /// With `tune`: the prepass tuner's choice, settled by untimed probes before the timed frames.
    prepass_decision: Option<PrepassDecision>,
}

#[derive(Serialize)]
struct SceneReport {
    scene: String,
    lights: usize,
    has_spots: bool,
    has_blended: bool,
    rows: Vec<Row>,
}

/// Median (0 for no samples: the untimed reference frame).
fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    myriad::evaluate::median(&mut v)
}

/// Samples of one configuration, frame by frame.
#[derive(Default)]
struct Samples {
    cpu: Vec<f64>,
    prepass: Vec<f64>,
    mask: Vec<f64>,
    shading: Vec<f64>,
    gbuffer: Vec<f64>,
    last: Option<SkipFrame>,
}

impl Samples {
    /// Renders one frame with `skips` and records it (`timed` false: a warm-up, which also fills
    /// the reuse cache, so timed `reuse` frames find nothing changed).
    fn frame(
        &mut self,
        viewer: &mut Viewer,
        scene: &RenderScene,
        method: myriad::assignment::Method,
        skips: Skips,
        timed: bool,
    ) -> Result<()> {
        let frame = viewer.frame_with_skips(scene, method, skips)?;
        viewer.ctx.wait_idle()?;
        // Once a run: every configuration would coarsen alike.
        static COARSENED: std::sync::Once = std::sync::Once::new();
        if let Some(warning) = super::pair_budget::device_coarsened_warning(
            &scene.name,
            scene.grid.dims(),
            frame.grid.dims(),
            viewer.ctx.max_list_pairs(),
        ) {
            COARSENED.call_once(|| eprintln!("{warning}"));
        }
        if timed {
            self.cpu.push(
                (frame.cull_seconds + frame.assign_seconds + frame.report.upload_seconds) * 1e3,
            );
            self.prepass.push(frame.prepass_seconds * 1e3);
            self.mask.push(frame.mask_seconds * 1e3);
            if let Some(p) = viewer.renderer.last_pass_times(&viewer.ctx)? {
                self.shading
                    .push(p.shading_ms.unwrap_or(0.0) + p.forward_ms.unwrap_or(0.0));
                self.gbuffer.push(p.gbuffer_ms.unwrap_or(0.0));
            }
        }
        self.last = Some(frame);
        Ok(())
    }

    /// Medians, and the image's largest difference from `reference`.
    fn summary(
        self,
        viewer: &Viewer,
        reference: Option<&[u8]>,
    ) -> Result<(Measured, SkipFrame, Vec<u8>)> {
        let frame = self.last.expect("frames ran");
        let image = viewer.image()?;
        let max_image_difference = reference.map_or(0, |r| max_channel_difference(r, &image));
        Ok((
            Measured {
                cpu_ms: median(self.cpu),
                prepass_ms: median(self.prepass),
                mask_ms: median(self.mask),
                gbuffer_ms: median(self.gbuffer),
                pairs: frame.stats.map_or(0, |s| s.pairs),
                lights_assigned: frame.lights_assigned,
                upload_bytes: frame.report.upload_bytes,
                shading_ms: (!self.shading.is_empty()).then(|| median(self.shading)),
                max_image_difference,
            },
            frame,
            image,
        ))
    }
}

fn savings() -> Vec<(&'static str, Skips)> {
    let none = Skips::NONE;
    vec![
        ("1. frustum cull", Skips { cull: true, ..none }),
        (
            "2. active clusters",
            Skips {
                active_clusters: true,
                ..none
            },
        ),
        (
            "3. fitted depth range",
            Skips {
                fitted_depth: true,
                ..none
            },
        ),
        (
            "4. nothing moved: reuse",
            Skips {
                reuse_unchanged: true,
                ..none
            },
        ),
        (
            "5. feature variants",
            Skips {
                feature_variants: true,
                ..none
            },
        ),
        (
            "1-3 and 5 (no reuse)",
            Skips {
                reuse_unchanged: false,
                ..Skips::ALL
            },
        ),
        ("1-3 and 5, tuned", Skips::TUNED),
        ("all five", Skips::ALL),
    ]
}

fn scene_report(
    ctx: &GpuContext,
    scene: &RenderScene,
    method: myriad::assignment::Method,
    runs: usize,
) -> Result<SceneReport> {
    // The reference image: every saving off.
    let mut viewer = Viewer::new(ctx.clone(), scene)?;
    let mut warm = Samples::default();
    warm.frame(&mut viewer, scene, method, Skips::NONE, false)?;
    let (_, _, reference) = warm.summary(&viewer, None)?;
    let mut rows = Vec::new();
    for (name, skips) in savings() {
        // Before and after frames alternate, so drift in the machine's load hits both alike.
        let mut fresh = Viewer::new(ctx.clone(), scene)?;
        let prepass_decision = settle_tuner(&mut fresh, scene, method, skips)?.decision;
        let (mut before, mut after) = (Samples::default(), Samples::default());
        for run in 0..=runs {
            before.frame(&mut viewer, scene, method, Skips::NONE, run > 0)?;
            after.frame(&mut fresh, scene, method, skips, run > 0)?;
        }
        let (before, _, _) = before.summary(&viewer, None)?;
        let (after, frame, _) = after.summary(&fresh, Some(&reference))?;
        rows.push(Row {
            saving: name,
            before,
            after,
            active_clusters: frame.active_clusters,
            clusters: frame.grid.cluster_count(),
            // Tuned off, the frames ran without the prepass, so without fitting.
            fitted_range: (skips.fitted_depth && frame.tuning.is_none_or(|t| t.plan.use_prepass))
                .then(|| [frame.grid.near(), frame.grid.far()]),
            prepass_decision,
        });
    }
    Ok(SceneReport {
        scene: format!(
            "{} ({}x{})",
            scene.name, scene.camera.width, scene.camera.height
        ),
        lights: scene.lights.len(),
        has_spots: scene.lights.has_spots(),
        has_blended: scene.has_blended(),
        rows,
    })
}

/// A `--gltf` path compared by the file it names: `a.glb` and `./a.glb` (or a link to it) are one
/// model, which would be measured and reported twice.
struct SameFile<'a> {
    /// The path as given, which the error names.
    spelled: &'a Path,
    /// The path with links and `.`/`..` resolved; as given where it does not resolve (a missing
    /// file is refused, by name, when it is loaded).
    resolved: PathBuf,
}

impl PartialEq for SameFile<'_> {
    fn eq(&self, other: &Self) -> bool {
        self.resolved == other.resolved
    }
}

fn same_files(paths: &[PathBuf]) -> Vec<SameFile<'_>> {
    paths
        .iter()
        .map(|p| SameFile {
            spelled: p,
            resolved: p.canonicalize().unwrap_or_else(|_| p.clone()),
        })
        .collect()
}

pub fn run(args: Args) -> Result<ExitCode> {
    let method = parse_method(&args.method)?;
    let (width, height) = parse_size(&args.size)?;
    super::source::check_image_memory(width, height)?;
    refuse_repeats("--gltf", &same_files(&args.gltf), |f| {
        f.spelled.display().to_string()
    })?;
    check_memory_for(DEFAULT_GRID, args.lights)?;
    let ctx = GpuContext::headless()?;
    let mut scenes = Vec::new();
    if args.gltf.is_empty() {
        scenes.push(super::source::noted_default_scene(
            args.lights,
            width,
            height,
        )?);
        let sponza = PathBuf::from(SPONZA);
        if sponza.is_file() {
            let model = super::source::load_model(&sponza, &LoadOptions::default(), &[])?;
            super::source::note_model_scene(&model, "Sponza", None, args.lights);
            scenes.push(RenderScene::from_model(
                &model,
                "Sponza",
                None,
                args.lights,
                1,
                width,
                height,
            )?);
        } else {
            eprintln!("note: {SPONZA} not found; measuring the default scene only");
        }
    } else {
        for path in &args.gltf {
            let model = super::source::load_model(path, &LoadOptions::default(), &[])?;
            let name = path.display().to_string();
            super::source::note_model_scene(&model, &name, None, args.lights);
            scenes.push(RenderScene::from_model(
                &model,
                &name,
                None,
                args.lights,
                1,
                width,
                height,
            )?);
        }
    }
    let mut reports = Vec::new();
    for scene in &scenes {
        reports.push(scene_report(&ctx, scene, method, args.runs)?);
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&reports)?);
    } else {
        println!(
            "GPU: {}; method {}; medians of {} frames",
            ctx.describe(),
            method.name(),
            args.runs
        );
        for r in &reports {
            print!("{}", table(r));
        }
    }
    if !args.json {
        println!(
            "\nCPU = frustum cull + assignment + light/list upload staging. GPU shading = the \
             deferred shading and forward passes (timestamps). G-buffer|prepass = the G-buffer pass \
             in the frame (timestamps), or, with a prepass, that pass drawn first plus its depth \
             read-back (wall clock; the frame then does not draw it again). mask = depth buffer -> fitted range \
             and active clusters on the CPU. Δimage = largest channel difference from the image \
             with no saving (of 255). \"all five\" and \"reuse\" time frames after an \
             identical first one. \"tuned\" keeps 2 and 3 only while timed probe frames show \
             their depth prepass pays (the probes run first, untimed). Before and after frames \
             alternate; medians."
        );
    }
    let changed = reports
        .iter()
        .flat_map(|r| &r.rows)
        .any(|row| row.after.max_image_difference > 1);
    if changed {
        eprintln!("error: a saving changed the image by more than 1/255");
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

/// The table `skips` prints for one scene: a line per saving, then its notes.
fn table(r: &SceneReport) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "\n{} — {} lights (spots: {}, blended geometry: {})",
        r.scene,
        r.lights,
        if r.has_spots { "yes" } else { "no" },
        if r.has_blended { "yes" } else { "no" }
    );
    let ms = |v: Option<f64>| v.map_or("—".to_string(), |v| format!("{v:.1}"));
    let header = [
        "saving (before → after)",
        "CPU cull+assign+up ms",
        "pairs",
        "upload KiB",
        "GPU shading ms",
        "G-buffer|prepass ms",
        "mask ms",
        "Δimage",
    ]
    .map(String::from);
    let cells: Vec<[String; 8]> = r
        .rows
        .iter()
        .map(|row| {
            let (b, a) = (&row.before, &row.after);
            [
                row.saving.to_string(),
                format!("{:.3} → {:.3}", b.cpu_ms, a.cpu_ms),
                format!("{} → {}", b.pairs, a.pairs),
                format!(
                    "{:.1} → {:.1}",
                    b.upload_bytes as f64 / 1024.0,
                    a.upload_bytes as f64 / 1024.0
                ),
                format!("{} → {}", ms(b.shading_ms), ms(a.shading_ms)),
                format!(
                    "{:.1} → {:.1}",
                    b.gbuffer_ms,
                    if a.prepass_ms > 0.0 {
                        a.prepass_ms
                    } else {
                        a.gbuffer_ms
                    }
                ),
                format!("{:.2}", a.mask_ms),
                a.max_image_difference.to_string(),
            ]
        })
        .collect();
    // The widths the 1000-light table has, grown where a cell needs more (100k lights' pair
    // counts), so that two spaces at least part every column.
    let mut widths = [25, 19, 17, 19, 19, 19, 9, 6];
    for row in std::iter::once(&header).chain(&cells) {
        for (w, cell) in widths.iter_mut().zip(row).skip(1) {
            *w = (*w).max(cell.chars().count() + 1);
        }
    }
    let line = |row: &[String; 8]| {
        let mut text = format!("{:<w$}", row[0], w = widths[0]);
        for (cell, &w) in row.iter().zip(&widths).skip(1) {
            let _ = write!(text, " {cell:>w$}");
        }
        text
    };
    let _ = writeln!(out, "{}", line(&header));
    for (row, cells) in r.rows.iter().zip(&cells) {
        let (b, a) = (&row.before, &row.after);
        let _ = writeln!(out, "{}", line(cells));
        let mut notes = Vec::new();
        if a.lights_assigned != b.lights_assigned {
            notes.push(format!(
                "lights assigned {} → {}",
                b.lights_assigned, a.lights_assigned
            ));
        }
        if let Some(active) = row.active_clusters {
            notes.push(format!("{active} of {} clusters active", row.clusters));
        }
        if let Some([n, f]) = row.fitted_range {
            notes.push(format!("depth range fitted to [{n:.3}, {f:.3}]"));
        }
        if let Some(d) = row.prepass_decision {
            notes.push(format!("tuned: {d}"));
        }
        if !notes.is_empty() {
            let _ = writeln!(out, "{:<25} {}", "", notes.join("; "));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn measured(pairs: u64, upload_bytes: u64) -> Measured {
        Measured {
            cpu_ms: 123.456,
            prepass_ms: 0.0,
            mask_ms: 12.5,
            gbuffer_ms: 1234.5,
            pairs,
            lights_assigned: 100_000,
            upload_bytes,
            shading_ms: Some(12345.6),
            max_image_difference: 0,
        }
    }

    /// At 100k lights the pair counts filled the column's 17 places and one space parted the
    /// columns; every column now grows to its widest cell, and the header lines up with the rows.
    #[test]
    fn two_spaces_part_every_column_at_100k_lights() {
        let report = SceneReport {
            scene: "atrium".into(),
            lights: 100_000,
            has_spots: true,
            has_blended: true,
            rows: vec![Row {
                saving: "2. active clusters",
                before: measured(2_253_398, 13_840_000),
                after: measured(1_073_768, 9_100_000),
                active_clusters: Some(696),
                clusters: 4608,
                fitted_range: None,
                prepass_decision: None,
            }],
        };
        let text = table(&report);
        let lines: Vec<&str> = text.lines().skip(2).collect();
        let (header, row) = (lines[0], lines[1]);
        assert!(row.contains("  2253398 → 1073768  "), "{row}");
        assert_eq!(
            header.chars().count(),
            row.chars().count(),
            "{header}\n{row}"
        );
        // Past the first column, each cell ends where its header does.
        let ends = |line: &str| {
            let chars: Vec<char> = line.chars().collect();
            (26..chars.len())
                .filter(|&i| chars[i] != ' ' && chars.get(i + 1).is_none_or(|&c| c == ' '))
                .filter(|&i| chars.get(i + 2).is_none_or(|&c| c == ' '))
                .collect::<Vec<_>>()
        };
        assert_eq!(ends(header), ends(row), "{header}\n{row}");
        assert_eq!(ends(row).len(), 7, "{row}");
        assert!(lines[2].contains("696 of 4608 clusters active"));
    }
}
