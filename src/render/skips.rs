//! Skip what a frame does not need (issue "Skip what a scene doesn't need"), each saving behind
//! its own switch ([`Skips`]) so it can be measured alone and shown not to change the image:
//!
//! 1. **cull** — lights outside the view frustum (`myriad_scene::systems::cull_lights`, sphere
//!    or cone against the six planes) never reach the assignment or the GPU: only the visible
//!    rows are gathered, assigned and uploaded (so brute force would also shade fewer).
//! 2. **active clusters** — a depth prepass (the G-buffer pass, run first and read back) marks
//!    the clusters that hold an opaque pixel; the screen boxes of alpha-blended draws mark the
//!    clusters the forward pass may shade. Lists are built only there
//!    ([`myriad_assignment::Assigner::assign_active`]); the G-buffer is not drawn twice.
//! 3. **fitted depth** — the grid's near/far become the prepass's nearest and farthest pixel
//!    (and the blended draws' depth extent), widened by 1e-4 relative so GPU rounding of the
//!    reconstructed depth cannot put a pixel outside, and never beyond the scene grid's range.
//! 4. **reuse unchanged** — with the camera and every light column unchanged since the last
//!    frame, nothing is culled, assigned or uploaded; when only colours or intensities changed,
//!    the lights are re-uploaded and the lists kept (dirty tracking per column). Geometry is
//!    assumed static.
//! 5. **feature variants** — without spot lights the pipelines are built with `HAS_SPOTS = false`
//!    and without blended geometry the forward pass does not run; turning this off forces both
//!    (`ShadingSettings::force_all_features`) to measure the difference.
//!
//! What the depth buffer says (the fitted range, the active clusters) is worked out in
//! `depth_buffer.rs`.

use super::depth_buffer::{fitted_grid, mark_active};
use super::prepass_tuner::{PrepassDecision, PrepassTuner, TunedFrame, TunerSettings};
use super::setup::RenderScene;
use super::viewer::{Viewer, cluster_lists, light_columns};
use crate::light_input;
use anyhow::{Context, Result};
use myriad_assignment::{ActiveClusters, AssignStats, Method};
use myriad_gpu::{FrameDesc, FrameReport, ShadingMode, ShadingSettings};
use myriad_scene::systems::{Visibility, cull_lights};
use myriad_scene::{Camera, ClusterGrid, Lights};
use std::time::Instant;

/// Which savings a frame applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Skips {
    /// Frustum-cull lights before assignment and upload.
    pub cull: bool,
    /// Lists only for clusters with geometry (depth prepass + blended boxes).
    pub active_clusters: bool,
    /// Grid depth range fitted to the visible geometry.
    pub fitted_depth: bool,
    /// Reuse last frame's lists and uploads when nothing changed.
    pub reuse_unchanged: bool,
    /// No spot code without spots, no forward pass without blended geometry.
    pub feature_variants: bool,
    /// Apply `active_clusters` and `fitted_depth` only while timed frames show that their depth
    /// prepass pays ([`PrepassTuner`]); without either, nothing to decide.
    pub tune_prepass: bool,
}

impl Skips {
    /// Every saving off: the baseline.
    pub const NONE: Skips = Skips {
        cull: false,
        active_clusters: false,
        fitted_depth: false,
        reuse_unchanged: false,
        feature_variants: false,
        tune_prepass: false,
    };
    /// Every saving on, always (no tuning).
    pub const ALL: Skips = Skips {
        cull: true,
        active_clusters: true,
        fitted_depth: true,
        reuse_unchanged: true,
        feature_variants: true,
        tune_prepass: false,
    };

    /// The savings that leave a frame's work the same when nothing moved: every one but
    /// [`reuse_unchanged`](Self::reuse_unchanged). What `myriad render` applies by default,
    /// since it times the same static frame again and again, which reuse would turn into no
    /// work at all.
    pub const PER_FRAME: Skips = Skips {
        reuse_unchanged: false,
        ..Skips::ALL
    };

    /// [`PER_FRAME`](Self::PER_FRAME) with the prepass savings tuned: what to run where the
    /// GPU is not known in advance.
    pub const TUNED: Skips = Skips {
        tune_prepass: true,
        ..Skips::PER_FRAME
    };

    /// The name of each saving in [`Skips::from_str`](std::str::FromStr), with its switch.
    pub const NAMES: [&'static str; 5] = ["cull", "active", "depth", "reuse", "variants"];
    /// The name of [`tune_prepass`](Self::tune_prepass) in the same lists: a policy over two
    /// savings rather than a saving, so not in [`NAMES`](Self::NAMES).
    pub const TUNE: &'static str = "tune";

    fn switch(&mut self, name: &str) -> Option<&mut bool> {
        Some(match name {
            "cull" => &mut self.cull,
            "active" => &mut self.active_clusters,
            "depth" => &mut self.fitted_depth,
            "reuse" => &mut self.reuse_unchanged,
            "variants" => &mut self.feature_variants,
            Skips::TUNE => &mut self.tune_prepass,
            _ => return None,
        })
    }

    /// The names of the savings switched on, in [`Skips::NAMES`] order, then
    /// [`Skips::TUNE`] when tuned.
    pub fn names(self) -> Vec<&'static str> {
        let mut copy = self;
        Skips::NAMES
            .into_iter()
            .chain([Skips::TUNE])
            .filter(|name| copy.switch(name).is_some_and(|on| *on))
            .collect()
    }

    fn needs_prepass(self) -> bool {
        self.active_clusters || self.fitted_depth
    }

    /// Whether frames with these savings are tuned: [`Self::tune_prepass`] with `active` or
    /// `depth` to decide on (without either there is no prepass to keep or drop).
    pub fn tunes_prepass(self) -> bool {
        self.tune_prepass && self.needs_prepass()
    }

    /// These savings without the two that need the prepass (and without tuning them).
    fn without_prepass(self) -> Skips {
        Skips {
            active_clusters: false,
            fitted_depth: false,
            tune_prepass: false,
            ..self
        }
    }
}

/// `"cull,active,depth"`, `"all"` or `"none"`: the savings named in [`Skips::NAMES`], comma
/// separated, each at most once.
impl std::str::FromStr for Skips {
    type Err = String;

    fn from_str(text: &str) -> Result<Skips, String> {
        match text.trim() {
            "all" => return Ok(Skips::ALL),
            "none" => return Ok(Skips::NONE),
            _ => {}
        }
        let mut skips = Skips::NONE;
        for name in text.split(',').map(str::trim) {
            match skips.switch(name) {
                Some(on) if !*on => *on = true,
                Some(_) => return Err(format!("saving {name:?} named twice in {text:?}")),
                None => {
                    return Err(format!(
                        "unknown saving {name:?} in {text:?}: expected \"all\", \"none\" or a \
                         comma-separated list of {} (and {:?} to apply active and depth only \
                         where they pay)",
                        Skips::NAMES.join(", "),
                        Skips::TUNE
                    ));
                }
            }
        }
        if skips.tune_prepass && !skips.needs_prepass() {
            return Err(format!(
                "{:?} in {text:?} decides whether \"active\" and \"depth\" pay for their depth \
                 prepass: name at least one of them",
                Skips::TUNE
            ));
        }
        Ok(skips)
    }
}

/// What a frame with [`Skips`] did.
#[derive(Clone, Copy, Debug)]
pub struct SkipFrame {
    /// Nothing changed: no cull, assignment or upload of lights or lists.
    pub reused: bool,
    /// Only colours/intensities changed: lights re-uploaded, lists kept.
    pub appearance_only: bool,
    /// Lights in the scene.
    pub lights: usize,
    /// Lights that went to the assignment and the GPU.
    pub lights_assigned: usize,
    /// Lights skipped as invalid (a position or radius that is not finite, a radius that is not
    /// positive): dropped and counted by the cull ([`Visibility::invalid`]) with
    /// [`Skips::cull`], by the assignment (`stats.rejected`) without it; a reused frame repeats
    /// the count of the frame whose lists it keeps.
    pub lights_invalid: usize,
    /// CPU seconds of the frustum cull and gather.
    pub cull_seconds: f64,
    /// Seconds of the depth prepass on the GPU and its read-back (the G-buffer pass moves here
    /// from the frame; the read-back is the added cost).
    pub prepass_seconds: f64,
    /// CPU seconds turning the depth buffer into the fitted range and the active-cluster mask.
    pub mask_seconds: f64,
    /// CPU seconds of the assignment.
    pub assign_seconds: f64,
    /// The assignment's statistics (`None` when reused).
    pub stats: Option<AssignStats>,
    /// Upload and encode report.
    pub report: FrameReport,
    /// The grid shaded with (fitted when asked).
    pub grid: ClusterGrid,
    /// Active clusters, when masked.
    pub active_clusters: Option<usize>,
    /// With [`Skips::tune_prepass`]: what the tuner planned for this frame and its choice after
    /// it.
    pub tuning: Option<TunedFrame>,
}

/// What the last frame left for the next one.
#[derive(Clone, Debug)]
struct Cache {
    skips: Skips,
    camera: Camera,
    base_grid: ClusterGrid,
    grid: ClusterGrid,
    lights: Lights,
    method: Method,
    /// The frame's active clusters (with `active`), which a reused frame still shades with.
    active_clusters: Option<usize>,
    /// The frame's [`SkipFrame::lights_invalid`]: the lights' geometry is unchanged in a reused
    /// frame, and so is which of them are invalid.
    lights_invalid: usize,
    /// The renderer's upload generation after this frame: any other upload since (a plain
    /// [`Viewer::frame`], say) means the GPU's lights and lists are no longer these.
    generation: u64,
}

/// Scratch and cache of the skipping frame path, kept in the [`Viewer`].
#[derive(Debug, Default)]
pub struct SkipState {
    visibility: Visibility,
    visible: Lights,
    mask: Option<ActiveClusters>,
    cache: Option<Cache>,
    tuner: PrepassTuner,
}

impl Viewer {
    /// One clustered frame with `skips` applied; submits without waiting for the GPU. Marks the
    /// frame for Tracy, reused or not.
    pub fn frame_with_skips(
        &mut self,
        scene: &RenderScene,
        method: Method,
        skips: Skips,
    ) -> Result<SkipFrame> {
        let settings = ShadingSettings {
            force_all_features: !skips.feature_variants,
            ..self.settings
        };
        let mut state = std::mem::take(&mut self.skip_state);
        let result = if skips.tunes_prepass() {
            self.tuned_frame(scene, method, skips, settings, &mut state)
        } else {
            self.skipping_frame(scene, method, skips, settings, &mut state)
        };
        // A refused frame may have culled into the state (`visibility`, `visible`) that the
        // cache's reuse path reads, though the GPU never got its lights: the cache goes with
        // it. (Kept, a later frame of the cached camera whose lights only changed colour
        // gathered them through the refused frame's visible set and shaded them in another
        // light's clusters, with Ok, audit.)
        if result.is_err() {
            state.cache = None;
        }
        self.skip_state = state;
        if let Ok(frame) = &result {
            crate::profiling::plot_frame_load(
                frame.lights_assigned as u64,
                frame.stats.map(|s| s.pairs),
                frame.report.upload_bytes,
            );
            crate::profiling::frame_mark();
        }
        result
    }

    /// Starts the prepass tuner of [`Skips::tune_prepass`] over with `settings` (the default:
    /// [`TunerSettings::default`]).
    pub fn set_prepass_tuner(&mut self, settings: TunerSettings) {
        self.skip_state.tuner = PrepassTuner::new(settings);
    }

    /// The settings the prepass tuner runs with.
    pub fn prepass_tuner_settings(&self) -> TunerSettings {
        self.skip_state.tuner.settings()
    }

    /// The prepass tuner's choice in force (`None` before its first probe ends).
    pub fn prepass_decision(&self) -> Option<PrepassDecision> {
        self.skip_state.tuner.decision()
    }

    /// A frame with the prepass savings applied as the tuner plans. A probe frame waits for the
    /// GPU, so its time is the whole frame's: cull, prepass and read-back, mask, assignment,
    /// upload and every pass.
    fn tuned_frame(
        &mut self,
        scene: &RenderScene,
        method: Method,
        skips: Skips,
        settings: ShadingSettings,
        state: &mut SkipState,
    ) -> Result<SkipFrame> {
        let plan = state.tuner.plan();
        let applied = if plan.use_prepass {
            skips
        } else {
            skips.without_prepass()
        };
        // A probe is timed from an idle GPU: the frames held between rounds submit without
        // waiting, and the first probe of a round timed the last one's GPU work too.
        if plan.probe {
            self.ctx.wait_idle()?;
        }
        let start = Instant::now();
        let mut frame = self.skipping_frame(scene, method, applied, settings, state)?;
        // A reused frame ran neither side's work: it times nothing, and the probe waits.
        let ran = !frame.reused && !frame.appearance_only;
        if plan.probe && ran {
            crate::profile_span!("prepass tuner: probe waits for the GPU");
            self.ctx.wait_idle()?;
            state.tuner.record(plan, start.elapsed().as_secs_f64());
        } else if !plan.probe {
            state.tuner.record(plan, 0.0);
        }
        frame.tuning = Some(TunedFrame {
            plan,
            decision: state.tuner.decision(),
        });
        Ok(frame)
    }

    fn skipping_frame(
        &mut self,
        scene: &RenderScene,
        method: Method,
        skips: Skips,
        settings: ShadingSettings,
        state: &mut SkipState,
    ) -> Result<SkipFrame> {
        let lights = &scene.lights;
        let mut frame = SkipFrame {
            reused: false,
            appearance_only: false,
            lights: lights.len(),
            lights_assigned: lights.len(),
            lights_invalid: 0,
            cull_seconds: 0.0,
            prepass_seconds: 0.0,
            mask_seconds: 0.0,
            assign_seconds: 0.0,
            stats: None,
            report: FrameReport::default(),
            grid: scene.grid,
            active_clusters: None,
            tuning: None,
        };
        // 4. Dirty tracking.
        if let Some(cache) = state.cache.as_ref().filter(|c| {
            skips.reuse_unchanged
                && c.generation == self.renderer.upload_generation()
                && c.method == method
                && c.skips == skips
                && c.camera.same_as(&scene.camera)
                && c.base_grid == scene.grid
                && !geometry_dirty(&c.lights, lights)
        }) {
            crate::profile_span!("skipping frame: reused");
            let appearance = appearance_dirty(&cache.lights, lights);
            frame.grid = cache.grid;
            // The lists (and their mask) are the cached frame's; `skips` printed no active
            // count for a reused frame although it shaded with the mask (audit).
            frame.active_clusters = cache.active_clusters;
            frame.lights_invalid = cache.lights_invalid;
            frame.lights_assigned = if skips.cull {
                state.visible.len()
            } else {
                lights.len()
            };
            if appearance {
                if skips.cull {
                    lights.gather_into(&state.visibility.indices, &mut state.visible);
                }
                frame.appearance_only = true;
            } else {
                frame.reused = true;
            }
            let upload =
                appearance.then(|| light_columns(if skips.cull { &state.visible } else { lights }));
            let desc = FrameDesc {
                camera: &scene.camera,
                grid: &frame.grid,
                mode: ShadingMode::Lists,
                heat_map: false,
                lights: upload,
                lists: None,
                settings,
            };
            frame.report =
                self.renderer
                    .render(&self.ctx, &self.scene, &desc, &self.target.view)?;
            if appearance {
                let cache = state.cache.as_mut().expect("cache present");
                cache.lights.clone_from(lights);
                cache.generation = self.renderer.upload_generation();
            }
            return Ok(frame);
        }

        // 1. Cull.
        crate::profile_span!("skipping frame");
        let start = Instant::now();
        if skips.cull {
            cull_lights(&scene.camera, lights.slices(), &mut state.visibility);
            lights.gather_into(&state.visibility.indices, &mut state.visible);
            frame.lights_assigned = state.visible.len();
            frame.lights_invalid = state.visibility.invalid();
        }
        frame.cull_seconds = start.elapsed().as_secs_f64();

        // 2–3. Depth prepass: fitted range and active clusters.
        let start = Instant::now();
        let mut grid = scene.grid;
        if skips.needs_prepass() {
            let depth = {
                crate::profile_span!("depth prepass and read-back");
                self.renderer
                    .render_prepass(&self.ctx, &self.scene, &scene.camera)?;
                self.renderer
                    .read_depth(&self.ctx)?
                    .context("prepass drew")?
            };
            frame.prepass_seconds = start.elapsed().as_secs_f64();
            crate::profile_span!("fitted depth and active clusters");
            let start = Instant::now();
            if skips.fitted_depth {
                grid = fitted_grid(&scene.grid, &scene.camera, &depth, &scene.blended_bounds);
            }
            if skips.active_clusters {
                let mask = state.mask.get_or_insert_with(|| ActiveClusters::new(&grid));
                mark_active(mask, &grid, &scene.camera, &depth, &scene.blended_bounds);
                frame.active_clusters = Some(mask.active_count());
            }
            frame.mask_seconds = start.elapsed().as_secs_f64();
        }

        // Assign.
        let assigned = if skips.cull { &state.visible } else { lights };
        let start = Instant::now();
        let mask = if skips.active_clusters {
            state.mask.as_ref()
        } else {
            None
        };
        let stats = self.assigner.try_assign_active(
            method,
            &light_input(assigned),
            &scene.camera,
            &grid,
            mask,
            &mut self.lists,
        )?;
        frame.assign_seconds = start.elapsed().as_secs_f64();
        if stats.coarsened > 0 {
            // Lists past the pair budget are built unmasked on the coarser grid: no cluster
            // count of the mask describes them.
            frame.active_clusters = None;
        }
        frame.grid = stats.grid_built(&grid);
        frame.lights_invalid += stats.rejected as usize;
        frame.stats = Some(stats);

        let desc = FrameDesc {
            settings,
            ..FrameDesc::clustered(
                &scene.camera,
                &frame.grid,
                light_columns(assigned),
                cluster_lists(&self.lists),
            )
        };
        frame.report = if skips.needs_prepass() {
            self.renderer
                .render_after_prepass(&self.ctx, &self.scene, &desc, &self.target.view)?
        } else {
            self.renderer
                .render(&self.ctx, &self.scene, &desc, &self.target.view)?
        };
        if skips.reuse_unchanged {
            let cache = state.cache.get_or_insert_with(|| Cache {
                skips,
                camera: scene.camera,
                base_grid: scene.grid,
                grid: frame.grid,
                lights: Lights::new(),
                method,
                active_clusters: None,
                lights_invalid: 0,
                generation: 0,
            });
            cache.skips = skips;
            cache.active_clusters = frame.active_clusters;
            cache.lights_invalid = frame.lights_invalid;
            cache.method = method;
            cache.generation = self.renderer.upload_generation();
            cache.camera = scene.camera;
            cache.base_grid = scene.grid;
            cache.grid = frame.grid;
            cache.lights.clone_from(lights);
        } else {
            state.cache = None;
        }
        Ok(frame)
    }
}

/// Whether positions, radii or spot cones differ (the lists depend on them).
fn geometry_dirty(a: &Lights, b: &Lights) -> bool {
    differ(&a.x, &b.x)
        || differ(&a.y, &b.y)
        || differ(&a.z, &b.z)
        || differ(&a.radius, &b.radius)
        || differ(&a.spot_dir_x, &b.spot_dir_x)
        || differ(&a.spot_dir_y, &b.spot_dir_y)
        || differ(&a.spot_dir_z, &b.spot_dir_z)
        || differ(&a.spot_angle, &b.spot_angle)
}

/// Whether colours, intensities or spots' inner angles differ (only the upload depends on them).
fn appearance_dirty(a: &Lights, b: &Lights) -> bool {
    differ(&a.r, &b.r)
        || differ(&a.g, &b.g)
        || differ(&a.b, &b.b)
        || differ(&a.intensity, &b.intensity)
        || differ(&a.spot_inner_angle, &b.spot_inner_angle)
}

/// Whether two columns differ bit for bit. Not `!=`: a NaN never equals itself, so one light
/// with a NaN (an invalid light, skipped and counted) made every frame of an unchanged scene
/// dirty, and none was ever reused (audit). Compared 64 values at a time without an exit
/// inside a run, so the compiler vectorises it: an unchanged column of 1M lights, which every
/// reused frame compares whole (13 columns), took 1.19 ms with `!=`, 0.51 ms bit for bit with
/// an exit per value, 0.26 ms this way (a standalone `rustc -O` timing, best of 50).
fn differ(a: &[f32], b: &[f32]) -> bool {
    a.len() != b.len()
        || a.chunks(64).zip(b.chunks(64)).any(|(x, y)| {
            x.iter()
                .zip(y)
                .fold(false, |d, (p, q)| d | (p.to_bits() != q.to_bits()))
        })
}

#[cfg(test)]
mod tests {
    use super::{Lights, Skips, appearance_dirty, geometry_dirty};

    #[test]
    fn savings_parse_by_name_and_print_back() {
        assert_eq!("all".parse::<Skips>(), Ok(Skips::ALL));
        assert_eq!("none".parse::<Skips>(), Ok(Skips::NONE));
        let per_frame: Skips = "cull, active,depth,variants".parse().unwrap();
        assert_eq!(per_frame, Skips::PER_FRAME);
        assert_eq!(per_frame.names(), ["cull", "active", "depth", "variants"]);
        assert_eq!(Skips::ALL.names(), Skips::NAMES);
        assert!(Skips::NONE.names().is_empty());
        let tuned: Skips = "cull,active,depth,variants,tune".parse().unwrap();
        assert_eq!(tuned, Skips::TUNED);
        assert_eq!(
            tuned.names(),
            ["cull", "active", "depth", "variants", "tune"]
        );
        let reuse: Skips = "reuse".parse().unwrap();
        assert_eq!(
            reuse,
            Skips {
                reuse_unchanged: true,
                ..Skips::NONE
            }
        );
    }

    #[test]
    fn tune_needs_a_saving_to_decide_on() {
        for text in ["tune", "cull,tune", "reuse,variants,tune"] {
            let e = text.parse::<Skips>().unwrap_err();
            assert!(e.contains("name at least one of them"), "{text}: {e}");
        }
        for text in ["active,tune", "depth,reuse,tune"] {
            assert!(text.parse::<Skips>().unwrap().tunes_prepass(), "{text}");
        }
        let untuned = Skips {
            tune_prepass: true,
            ..Skips::NONE
        };
        assert!(!untuned.tunes_prepass(), "built by hand: nothing to tune");
    }

    #[test]
    fn unknown_or_repeated_savings_are_refused_by_name() {
        let unknown = "cull,shadows".parse::<Skips>().unwrap_err();
        assert!(
            unknown.contains("\"shadows\"") && unknown.contains("variants"),
            "{unknown}"
        );
        let twice = "depth,depth".parse::<Skips>().unwrap_err();
        assert!(twice.contains("twice"), "{twice}");
        assert!("".parse::<Skips>().is_err());
    }

    /// A change of any one position, radius or spot-cone column makes the cached lists stale
    /// (full frame); a change of any one colour or intensity column only the uploaded lights
    /// (lists kept); identical lights are neither. One column at a time, so a check that needs
    /// two columns to change together shows.
    #[test]
    fn each_light_column_change_is_seen_as_geometry_or_appearance() {
        // The atrium's 12 lights (spots among them) a hundred times: runs of 64 to compare.
        let atrium = myriad_scene::atrium().lights;
        let lights: Lights = (0..100).flat_map(|_| atrium.iter()).collect();
        assert!(lights.has_spots(), "the spot columns are compared too");
        assert!(!geometry_dirty(&lights, &lights.clone()));
        assert!(!appearance_dirty(&lights, &lights.clone()));
        // A NaN is the same NaN in both frames: unchanged, not dirty.
        let mut with_nan = lights.clone();
        (with_nan.radius[2], with_nan.x[5], with_nan.r[7]) = (f32::NAN, f32::NAN, f32::NAN);
        assert!(!geometry_dirty(&with_nan, &with_nan.clone()));
        assert!(!appearance_dirty(&with_nan, &with_nan.clone()));
        type Column = fn(&mut Lights) -> &mut Vec<f32>;
        let geometric: [(&str, Column); 8] = [
            ("x", |l| &mut l.x),
            ("y", |l| &mut l.y),
            ("z", |l| &mut l.z),
            ("radius", |l| &mut l.radius),
            ("spot_dir_x", |l| &mut l.spot_dir_x),
            ("spot_dir_y", |l| &mut l.spot_dir_y),
            ("spot_dir_z", |l| &mut l.spot_dir_z),
            ("spot_angle", |l| &mut l.spot_angle),
        ];
        let appearance: [(&str, Column); 5] = [
            ("r", |l| &mut l.r),
            ("g", |l| &mut l.g),
            ("b", |l| &mut l.b),
            ("intensity", |l| &mut l.intensity),
            ("spot_inner_angle", |l| &mut l.spot_inner_angle),
        ];
        // A value in the first run of 64 compared together, one in a middle run, and the last
        // (in the short run at the end, the atrium's light count not being a multiple of 64).
        let last = lights.len() - 1;
        assert_ne!(lights.len() % 64, 0);
        for at in [3, 64 * 5 + 17, last] {
            let changed = |column: Column| {
                let mut changed = lights.clone();
                column(&mut changed)[at] += 0.25;
                changed
            };
            for (name, column) in geometric {
                let changed = changed(column);
                assert!(geometry_dirty(&lights, &changed), "{name} at {at}");
                assert!(!appearance_dirty(&lights, &changed), "{name} at {at}");
            }
            for (name, column) in appearance {
                let changed = changed(column);
                assert!(appearance_dirty(&lights, &changed), "{name} at {at}");
                assert!(!geometry_dirty(&lights, &changed), "{name} at {at}");
            }
        }
    }

    /// Frames the tuner plans without the prepass keep every other saving and drop the two that
    /// need it, and the tuning of them.
    #[test]
    fn without_the_prepass_only_active_depth_and_tuning_are_dropped() {
        let tuned = Skips {
            tune_prepass: true,
            ..Skips::ALL
        };
        let expected = Skips {
            cull: true,
            reuse_unchanged: true,
            feature_variants: true,
            ..Skips::NONE
        };
        assert_eq!(tuned.without_prepass(), expected);
    }
}
