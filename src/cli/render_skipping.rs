//! The main job's fourth column: clustered shading with [`Skips`] applied (by default every
//! saving but reuse), timed like the other strategies and checked against the plain clustered
//! image, so `myriad render` shows what skipping what the scene does not need buys on the scene
//! it renders, and proves it changes nothing.

use super::progress::Progress;
use super::render::{FrameSamples, StrategyResult, timed_frames};
use anyhow::{Context, Result};
use myriad::assignment::Method;
use myriad::render::{
    PrepassDecision, RenderScene, SkipFrame, Skips, Viewer, max_channel_difference, pixel_stats,
};
use serde::Serialize;

/// Name of the column in the table and of the strategy in `stats.json`.
pub const SHADING: &str = "clustered+skips";

/// The clustered frame with savings, next to the plain one.
#[derive(Serialize, Debug)]
pub struct WithSkips {
    /// The savings applied ([`Skips::NAMES`]).
    pub savings: Vec<&'static str>,
    /// Medians as for the other strategies; `assign_ms` holds cull + assignment.
    pub result: StrategyResult,
    /// Lights that reached the assignment and the GPU (after the cull).
    pub lights_assigned: usize,
    /// Clusters that got lists (with `active`), of `clusters`.
    pub active_clusters: Option<usize>,
    pub clusters: usize,
    /// The grid's near and far after fitting (with `depth`).
    pub fitted_depth_range: Option<[f32; 2]>,
    /// Depth prepass on the GPU and its read-back, wall clock (with `active` or `depth`).
    pub prepass_ms: f64,
    /// Depth buffer → fitted range and active clusters, on the CPU.
    pub mask_ms: f64,
    /// With `tune`: the tuner's choice the timed frames ran (its probes are the warm-up).
    pub prepass_decision: Option<PrepassDecision>,
    /// Largest channel difference (of 255) from the plain clustered image.
    pub max_image_difference: u8,
}

/// What [`settle_tuner`] leaves: the tuner's choice and the last untimed frame that assigned.
#[derive(Default)]
pub struct Settled {
    pub decision: Option<PrepassDecision>,
    /// With `reuse`, the timed frames after the probes may all reuse these lists.
    pub assigned: Option<SkipFrame>,
}

/// When `skips` tunes the prepass ([`Skips::tunes_prepass`]): renders untimed frames until the
/// viewer's prepass tuner has decided (its probes plus one frame that did not count, at most),
/// so timed frames after it all run the choice it settled on. Returns that choice and the last
/// of those frames that assigned; nothing without tuning.
pub fn settle_tuner(
    viewer: &mut Viewer,
    scene: &RenderScene,
    method: Method,
    skips: Skips,
) -> Result<Settled> {
    let mut settled = Settled::default();
    if !skips.tunes_prepass() {
        return Ok(settled);
    }
    let frames = 2 * viewer.prepass_tuner_settings().probe_frames + 1;
    for _ in 0..frames {
        if viewer.prepass_decision().is_some() {
            break;
        }
        let frame = viewer.frame_with_skips(scene, method, skips)?;
        viewer.ctx.wait_idle()?;
        if frame.stats.is_some() {
            settled.assigned = Some(frame);
        }
    }
    settled.decision = Some(
        viewer
            .prepass_decision()
            .context("the prepass tuner decided within its probe frames")?,
    );
    Ok(settled)
}

/// Times `runs` frames with `skips` (after one untimed frame, which also builds the pipeline
/// variants) and compares the last image with `clustered_image`.
pub fn measure(
    viewer: &mut Viewer,
    scene: &RenderScene,
    method: Method,
    skips: Skips,
    runs: usize,
    clustered_image: &[u8],
    progress: &Progress,
) -> Result<WithSkips> {
    // Tuned: the probes first, untimed, so the timed frames all run the choice they settle on.
    let settled = settle_tuner(viewer, scene, method, skips)?;
    let mut samples = FrameSamples::new(viewer);
    let (mut prepass, mut mask) = (vec![], vec![]);
    // With `reuse`, the timed frames may all keep the lists the probes built.
    let mut assigned: Option<SkipFrame> = settled.assigned;
    let mut last: Option<SkipFrame> = None;
    let warm_ups = timed_frames(SHADING, runs, progress, || {
        let frame = viewer.frame_with_skips(scene, method, skips)?;
        let cpu_seconds = frame.cull_seconds + frame.assign_seconds;
        samples.wait_and_record(viewer, cpu_seconds, &frame.report)?;
        prepass.push(frame.prepass_seconds * 1e3);
        mask.push(frame.mask_seconds * 1e3);
        // With `reuse`, frames after the first assign nothing: the lists are the first one's.
        if frame.stats.is_some() {
            assigned = Some(frame);
        }
        last = Some(frame);
        Ok(())
    })?;
    samples.drop_warm_ups(warm_ups);
    prepass.drain(..warm_ups);
    mask.drain(..warm_ups);
    let frame = last.context("at least one frame")?;
    let assigned = assigned.context("the first frame assigns")?;
    if let Some(warning) = super::pair_budget::device_coarsened_warning(
        &format!("{}: {SHADING}", scene.name),
        scene.grid.dims(),
        frame.grid.dims(),
        viewer.ctx.max_list_pairs(),
    ) {
        progress.line(warning);
    }
    let image = viewer.image()?;
    let max_image_difference = max_channel_difference(clustered_image, &image);
    let depth = viewer
        .renderer
        .read_depth(&viewer.ctx)?
        .context("a frame was rendered")?;
    let pixels = pixel_stats(
        &depth,
        &scene.camera,
        &frame.grid,
        &viewer.lists().counts,
        scene.lights.len(),
    );
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(0.0)
    };
    Ok(WithSkips {
        savings: skips.names(),
        result: samples.result(
            SHADING,
            assigned.report.upload_bytes,
            assigned.stats.map_or(0, |s| s.pairs),
            [&scene.grid, &frame.grid],
            pixels,
        ),
        lights_assigned: assigned.lights_assigned,
        active_clusters: assigned.active_clusters,
        clusters: frame.grid.cluster_count(),
        // Tuned off, the frames ran without the prepass, so without fitting.
        fitted_depth_range: (skips.fitted_depth && frame.tuning.is_none_or(|t| t.plan.use_prepass))
            .then(|| [frame.grid.near(), frame.grid.far()]),
        prepass_decision: skips
            .tunes_prepass()
            .then(|| viewer.prepass_decision())
            .flatten(),
        prepass_ms: median(prepass),
        mask_ms: median(mask),
        max_image_difference,
    })
}
