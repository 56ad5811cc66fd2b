//! Whether the depth prepass pays for itself, decided by timing frames both ways.
//!
//! Active clusters and fitted depth ([`super::Skips`]) need a depth prepass and its read-back.
//! Where shading dominates — a software rasteriser, long lists, many lights per pixel — they save
//! more than they cost: on llvmpipe, Sponza's frame loses 12%. On a fast GPU they cost more: on an
//! H100 the prepass and read-back added 1.5–1.8 ms and the CPU mask 0.4–1.0 ms, to save at most
//! 0.3 ms of shading (docs/results.md, "On a real GPU"). Which side a frame falls on depends on the GPU,
//! the scene and the view, none of which the renderer can predict, so it is measured instead:
//!
//! 1. **Probe**: frames alternate without and with the prepass (without first) until each side
//!    has [`TunerSettings::probe_frames`] timings — each a whole frame, start to GPU idle.
//! 2. **Decide**: keep the side in use (at first: no prepass, the simpler frame) unless the
//!    other's median is cheaper by more than [`TunerSettings::margin`]. Medians, because one
//!    frame of a probe may carry a pipeline build or a hiccup of a shared machine; the margin,
//!    so that noise between two equal sides does not flip the choice back and forth.
//! 3. **Hold** the choice for [`TunerSettings::hold_frames`] frames, unmeasured, then probe
//!    again: the camera moves, lights come and go, and the balance with them.
//!
//! The tuner only keeps counts and timings; [`super::Viewer::frame_with_skips`] asks it for each
//! frame's plan and, on probe frames, waits for the GPU and reports the frame's time.

/// How the tuner probes and how long it keeps a choice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TunerSettings {
    /// Timed frames per side in a probe (at least 1).
    pub probe_frames: usize,
    /// Frames a choice is kept before probing again.
    pub hold_frames: usize,
    /// Fraction by which the other side must be cheaper to change the choice, in `[0, 1)`.
    pub margin: f64,
}

impl Default for TunerSettings {
    /// Three frames a side (a median that one slow frame cannot move), then five seconds at
    /// 60 frames per second, and a 5% margin (the spread of repeated frames on a shared machine).
    fn default() -> Self {
        Self {
            probe_frames: 3,
            hold_frames: 300,
            margin: 0.05,
        }
    }
}

/// What the tuner wants of the next frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FramePlan {
    /// Run the depth prepass (and so the savings that need it).
    pub use_prepass: bool,
    /// Time this frame, start to GPU idle, and report it with [`PrepassTuner::record`].
    pub probe: bool,
}

/// The outcome of the last probe.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PrepassDecision {
    /// Whether frames run the prepass until the next probe.
    pub use_prepass: bool,
    /// Median frame time with the prepass, seconds.
    pub with_seconds: f64,
    /// Median frame time without it, seconds.
    pub without_seconds: f64,
    /// Timed frames per side behind the medians.
    pub frames_per_side: usize,
}

/// `depth prepass on (frames 373.21 ms with it, 397.52 ms without, medians of 3 probes each)`:
/// the choice and the measurement behind it, as `myriad render` and `myriad skips` print it.
impl std::fmt::Display for PrepassDecision {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "depth prepass {} (frames {:.2} ms with it, {:.2} ms without, medians of {} probes each)",
            if self.use_prepass { "on" } else { "off" },
            self.with_seconds * 1e3,
            self.without_seconds * 1e3,
            self.frames_per_side
        )
    }
}

/// What the tuner did with one frame ([`super::SkipFrame::tuning`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TunedFrame {
    /// The plan the frame ran.
    pub plan: FramePlan,
    /// The choice in force after it.
    pub decision: Option<PrepassDecision>,
}

/// Probes, decides and holds (see the module docs).
#[derive(Clone, Debug)]
pub struct PrepassTuner {
    settings: TunerSettings,
    with: Vec<f64>,
    without: Vec<f64>,
    /// Frames left to hold the decision; probing while 0.
    hold_left: usize,
    decision: Option<PrepassDecision>,
}

impl Default for PrepassTuner {
    fn default() -> Self {
        Self::new(TunerSettings::default())
    }
}

impl PrepassTuner {
    /// A tuner that starts by probing. Panics when `probe_frames` is 0 or `margin` is outside
    /// `[0, 1)`: no decision could come of them.
    pub fn new(settings: TunerSettings) -> Self {
        assert!(
            settings.probe_frames > 0,
            "a probe needs at least one frame a side"
        );
        assert!(
            (0.0..1.0).contains(&settings.margin),
            "margin {} outside [0, 1)",
            settings.margin
        );
        Self {
            settings,
            with: Vec::with_capacity(settings.probe_frames),
            without: Vec::with_capacity(settings.probe_frames),
            hold_left: 0,
            decision: None,
        }
    }

    /// The settings it was made with.
    pub fn settings(&self) -> TunerSettings {
        self.settings
    }

    /// The plan for the next frame.
    pub fn plan(&self) -> FramePlan {
        match self.decision {
            Some(d) if self.hold_left > 0 => FramePlan {
                use_prepass: d.use_prepass,
                probe: false,
            },
            // The side with fewer timings; without first.
            _ => FramePlan {
                use_prepass: self.with.len() < self.without.len(),
                probe: true,
            },
        }
    }

    /// Reports a frame run to `plan`: `seconds` is its time for a probe frame (ignored
    /// otherwise). A probe timing that is not a finite, non-negative number is dropped, and the
    /// frame is probed again.
    pub fn record(&mut self, plan: FramePlan, seconds: f64) {
        if !plan.probe {
            self.hold_left = self.hold_left.saturating_sub(1);
            return;
        }
        if !(seconds.is_finite() && seconds >= 0.0) {
            return;
        }
        let side = if plan.use_prepass {
            &mut self.with
        } else {
            &mut self.without
        };
        if side.len() < self.settings.probe_frames {
            side.push(seconds);
        }
        let n = self.settings.probe_frames;
        if self.with.len() == n && self.without.len() == n {
            self.decide();
        }
    }

    /// The choice in force (`None` until the first probe ends).
    pub fn decision(&self) -> Option<PrepassDecision> {
        self.decision
    }

    fn decide(&mut self) {
        let with_seconds = median(&mut self.with);
        let without_seconds = median(&mut self.without);
        let current = self.decision.is_some_and(|d| d.use_prepass);
        let (kept, other) = if current {
            (with_seconds, without_seconds)
        } else {
            (without_seconds, with_seconds)
        };
        let switch = other < kept * (1.0 - self.settings.margin);
        self.decision = Some(PrepassDecision {
            use_prepass: current != switch,
            with_seconds,
            without_seconds,
            frames_per_side: self.settings.probe_frames,
        });
        self.with.clear();
        self.without.clear();
        self.hold_left = self.settings.hold_frames;
    }
}

use crate::evaluate::median;

#[cfg(test)]
mod tests {
    use super::*;

    const QUICK: TunerSettings = TunerSettings {
        probe_frames: 3,
        hold_frames: 4,
        margin: 0.05,
    };

    /// Runs frames through `tuner`, timing each as `cost(use_prepass)`, and returns the plans.
    fn run(tuner: &mut PrepassTuner, frames: usize, cost: impl Fn(bool) -> f64) -> Vec<FramePlan> {
        (0..frames)
            .map(|_| {
                let plan = tuner.plan();
                tuner.record(plan, cost(plan.use_prepass));
                plan
            })
            .collect()
    }

    #[test]
    fn a_probe_alternates_sides_without_first_then_decides() {
        let mut tuner = PrepassTuner::new(QUICK);
        let plans = run(&mut tuner, 6, |p| if p { 8.0 } else { 10.0 });
        let sides: Vec<bool> = plans.iter().map(|p| p.use_prepass).collect();
        assert_eq!(sides, [false, true, false, true, false, true]);
        assert!(plans.iter().all(|p| p.probe));
        let d = tuner.decision().expect("decided after three frames a side");
        assert!(d.use_prepass);
        assert_eq!((d.with_seconds, d.without_seconds), (8.0, 10.0));
        assert_eq!(d.frames_per_side, 3);
    }

    #[test]
    fn the_prepass_is_kept_off_when_it_costs_more_or_saves_less_than_the_margin() {
        let mut dearer = PrepassTuner::new(QUICK);
        run(&mut dearer, 6, |p| if p { 12.0 } else { 10.0 });
        assert!(!dearer.decision().unwrap().use_prepass);
        // 4% cheaper is inside the 5% margin: the simpler frame stays.
        let mut marginal = PrepassTuner::new(QUICK);
        run(&mut marginal, 6, |p| if p { 9.6 } else { 10.0 });
        assert!(!marginal.decision().unwrap().use_prepass);
        // 6% cheaper is outside it.
        let mut enough = PrepassTuner::new(QUICK);
        run(&mut enough, 6, |p| if p { 9.4 } else { 10.0 });
        assert!(enough.decision().unwrap().use_prepass);
    }

    #[test]
    fn medians_ignore_one_slow_frame_a_side() {
        let mut tuner = PrepassTuner::new(QUICK);
        // The first frame with the prepass builds its pipelines: 50 instead of 8.
        let mut first_with = true;
        for _ in 0..6 {
            let plan = tuner.plan();
            let seconds = match plan.use_prepass {
                true if first_with => {
                    first_with = false;
                    50.0
                }
                true => 8.0,
                false => 10.0,
            };
            tuner.record(plan, seconds);
        }
        let d = tuner.decision().unwrap();
        assert!(d.use_prepass, "{d:?}");
        assert_eq!(d.with_seconds, 8.0);
    }

    #[test]
    fn a_choice_is_held_unmeasured_then_probed_again() {
        let mut tuner = PrepassTuner::new(QUICK);
        run(&mut tuner, 6, |p| if p { 8.0 } else { 10.0 });
        let held = run(&mut tuner, 4, |_| f64::NAN);
        assert!(held.iter().all(|p| p.use_prepass && !p.probe), "{held:?}");
        // The balance turned while held: the next probe finds it and switches.
        let probe = run(&mut tuner, 6, |p| if p { 12.0 } else { 10.0 });
        assert!(probe.iter().all(|p| p.probe));
        let d = tuner.decision().unwrap();
        assert!(!d.use_prepass);
        assert_eq!((d.with_seconds, d.without_seconds), (12.0, 10.0));
        assert!(!tuner.plan().use_prepass && !tuner.plan().probe);
    }

    #[test]
    fn a_choice_in_force_needs_the_margin_to_change() {
        let mut tuner = PrepassTuner::new(QUICK);
        run(&mut tuner, 6, |p| if p { 8.0 } else { 10.0 });
        run(&mut tuner, 4, |_| 0.0);
        // Now without is 3% cheaper: inside the margin, the prepass stays on.
        run(&mut tuner, 6, |p| if p { 10.0 } else { 9.7 });
        assert!(tuner.decision().unwrap().use_prepass);
    }

    #[test]
    fn timings_that_are_not_times_are_dropped_and_probed_again() {
        let mut tuner = PrepassTuner::new(QUICK);
        for bad in [f64::NAN, f64::INFINITY, -1.0] {
            let plan = tuner.plan();
            tuner.record(plan, bad);
            assert_eq!(tuner.plan(), plan, "the same frame is asked for again");
        }
        run(&mut tuner, 6, |p| if p { 8.0 } else { 10.0 });
        assert_eq!(tuner.decision().unwrap().with_seconds, 8.0);
    }

    #[test]
    fn with_no_hold_every_frame_is_a_probe() {
        let mut tuner = PrepassTuner::new(TunerSettings {
            hold_frames: 0,
            ..QUICK
        });
        let plans = run(&mut tuner, 12, |p| if p { 8.0 } else { 10.0 });
        assert!(plans.iter().all(|p| p.probe));
        assert!(tuner.decision().unwrap().use_prepass);
    }

    #[test]
    fn the_settings_it_was_made_with_are_kept() {
        assert_eq!(PrepassTuner::new(QUICK).settings(), QUICK);
        assert_eq!(PrepassTuner::default().settings(), TunerSettings::default());
    }

    #[test]
    fn a_decision_prints_the_choice_and_its_medians_in_milliseconds() {
        let on = PrepassDecision {
            use_prepass: true,
            with_seconds: 0.37321,
            without_seconds: 0.39752,
            frames_per_side: 3,
        };
        assert_eq!(
            on.to_string(),
            "depth prepass on (frames 373.21 ms with it, 397.52 ms without, medians of 3 probes each)"
        );
        let off = PrepassDecision {
            use_prepass: false,
            with_seconds: 0.012,
            without_seconds: 0.0105,
            frames_per_side: 5,
        };
        assert_eq!(
            off.to_string(),
            "depth prepass off (frames 12.00 ms with it, 10.50 ms without, medians of 5 probes each)"
        );
    }

    #[test]
    fn with_no_margin_equal_sides_keep_the_simpler_frame() {
        let mut tuner = PrepassTuner::new(TunerSettings {
            margin: 0.0,
            ..QUICK
        });
        run(&mut tuner, 6, |_| 10.0);
        assert!(!tuner.decision().unwrap().use_prepass);
    }

    #[test]
    fn timings_beyond_a_full_side_are_ignored() {
        let mut tuner = PrepassTuner::new(QUICK);
        let without = FramePlan {
            use_prepass: false,
            probe: true,
        };
        let with = FramePlan {
            use_prepass: true,
            ..without
        };
        // Five frames reported without the prepass: the last two find the side full.
        for seconds in [10.0, 10.0, 10.0, 1.0, 1.0] {
            tuner.record(without, seconds);
        }
        for _ in 0..3 {
            tuner.record(with, 12.0);
        }
        let d = tuner.decision().expect("three frames a side decide");
        assert_eq!((d.with_seconds, d.without_seconds), (12.0, 10.0));
        assert!(!d.use_prepass);
    }

    #[test]
    fn the_median_is_the_middle_frame_or_the_mean_of_two() {
        for (probe_frames, with_times, median) in [
            (1, &[7.0][..], 7.0),
            (2, &[9.0, 8.0][..], 8.5),
            (5, &[5.0, 1.0, 4.0, 2.0, 3.0][..], 3.0),
        ] {
            let mut tuner = PrepassTuner::new(TunerSettings {
                probe_frames,
                ..QUICK
            });
            let mut with_times = with_times.iter();
            for _ in 0..2 * probe_frames {
                let plan = tuner.plan();
                let seconds = if plan.use_prepass {
                    *with_times
                        .next()
                        .expect("no more probes than frames a side")
                } else {
                    10.0
                };
                tuner.record(plan, seconds);
            }
            let d = tuner.decision().expect("decided after a probe");
            assert_eq!(d.with_seconds, median, "{probe_frames} frames a side");
            assert_eq!(d.without_seconds, 10.0);
            assert_eq!(d.frames_per_side, probe_frames);
        }
    }

    #[test]
    #[should_panic(expected = "at least one frame")]
    fn a_probe_of_no_frames_is_refused() {
        PrepassTuner::new(TunerSettings {
            probe_frames: 0,
            ..QUICK
        });
    }

    #[test]
    #[should_panic(expected = "outside [0, 1)")]
    fn a_margin_of_one_is_refused() {
        PrepassTuner::new(TunerSettings {
            margin: 1.0,
            ..QUICK
        });
    }
}
