//! Every saving of `Skips` leaves the image unchanged: the clustered image with each saving alone,
//! and with all of them, equals the image with none, from several cameras; unchanged frames are
//! reused without uploading lights or lists, and changed colours or positions are picked up.

use myriad::assignment::Method;
use myriad::cluster_math::glam::{UVec3, Vec3};
use myriad::gpu::layout::Vertex;
use myriad::gpu::{GpuContext, HEADLESS_FORMAT, Renderer};
use myriad::render::{
    FramePlan, RenderScene, Shading, Skips, TunerSettings, Viewer, blended_bounds,
    max_channel_difference, run_frames,
};
use myriad::scene::{Camera, ClusterGrid, DepthSlicing, LightRecord, Lights, atrium};

fn singles() -> Vec<(&'static str, Skips)> {
    let none = Skips::NONE;
    vec![
        ("cull", Skips { cull: true, ..none }),
        (
            "active clusters",
            Skips {
                active_clusters: true,
                ..none
            },
        ),
        (
            "fitted depth",
            Skips {
                fitted_depth: true,
                ..none
            },
        ),
        (
            "reuse unchanged",
            Skips {
                reuse_unchanged: true,
                ..none
            },
        ),
        (
            "feature variants",
            Skips {
                feature_variants: true,
                ..none
            },
        ),
        ("all", Skips::ALL),
    ]
}

fn render(
    viewer: &mut Viewer,
    scene: &RenderScene,
    skips: Skips,
) -> (Vec<u8>, myriad::render::SkipFrame) {
    let frame = viewer
        .frame_with_skips(scene, Method::Refined, skips)
        .unwrap();
    (viewer.image().unwrap(), frame)
}

/// The scene's lights without its spot lights (to exercise the spot-free shader variant).
fn without_spots(lights: &Lights) -> Lights {
    let mut out = Lights::new();
    for l in lights.iter().filter(|l| l.spot.is_none()) {
        out.push(l);
    }
    out
}

#[test]
fn each_saving_leaves_the_image_unchanged() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let model = atrium();
    let mut viewer: Option<Viewer> = None;
    // (glTF camera, near plane or 0 for the camera's own, infinite far plane). The fourth: the
    // main camera with a near plane 10⁵ times closer than the scene (the fitted range and the
    // active clusters come from a depth buffer whose f32 values are coarse there); the last, an
    // engine's infinite far plane over the scene's finite grid.
    let views = [
        ("Main", 0.0, false),
        ("Overview", 0.0, false),
        ("Courtyard", 0.0, false),
        ("Main", 1e-5, false),
        ("Courtyard", 0.0, true),
    ];
    for (camera, near, infinite_far) in views {
        for spots in [true, false] {
            let mut scene =
                RenderScene::from_model(&model, "atrium", Some(camera), 1000, 1, 256, 128).unwrap();
            if near > 0.0 {
                scene.camera.near = near;
                let grid = &scene.grid;
                scene.grid = ClusterGrid::new(grid.dims(), grid.slicing(), near, grid.far());
            }
            if infinite_far {
                scene.camera.far = f32::INFINITY;
            }
            if !spots {
                scene.lights = without_spots(&scene.lights);
                assert!(!scene.lights.has_spots());
            }
            let v = match viewer.as_mut() {
                Some(v) => v,
                None => viewer.insert(Viewer::new(ctx.clone(), &scene).unwrap()),
            };
            let (reference, base) = render(v, &scene, Skips::NONE);
            assert!(base.active_clusters.is_none());
            for (name, skips) in singles() {
                let (image, frame) = render(v, &scene, skips);
                let d = max_channel_difference(&image, &reference);
                assert!(
                    d <= 1,
                    "{camera} (near {near}, infinite far {infinite_far}), spots {spots}: {name} \
                     changes the image by {d}/255"
                );
                if skips.cull {
                    assert!(
                        frame.lights_assigned < frame.lights,
                        "{camera}: nothing culled"
                    );
                }
                if skips.active_clusters {
                    let active = frame.active_clusters.unwrap();
                    assert!(
                        active > 0 && active < frame.grid.cluster_count(),
                        "{camera}: {active} active"
                    );
                    assert!(frame.stats.unwrap().pairs < base.stats.unwrap().pairs);
                }
                if skips.fitted_depth {
                    assert!(
                        frame.grid.far() < scene.grid.far()
                            || frame.grid.near() > scene.grid.near()
                    );
                }
            }
        }
    }
}

#[test]
fn unchanged_frames_are_reused_and_changes_are_seen() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let mut scene = RenderScene::default_scene(1000, 192, 96).unwrap();
    let mut viewer = Viewer::new(ctx.clone(), &scene).unwrap();
    let (first, f1) = render(&mut viewer, &scene, Skips::ALL);
    assert!(!f1.reused && f1.report.upload_bytes > 0);
    let (second, f2) = render(&mut viewer, &scene, Skips::ALL);
    assert!(f2.reused, "nothing changed, so the frame is reused");
    assert_eq!(f2.report.upload_bytes, 0, "a reused frame uploads nothing");
    assert!(f2.stats.is_none());
    assert_eq!(first, second);
    // It shaded with the first frame's mask, and says how many clusters that kept.
    assert!(f1.active_clusters.is_some());
    assert_eq!(f2.active_clusters, f1.active_clusters);

    // A colour change: lights re-uploaded, lists kept; the image equals a fresh render.
    for i in 0..scene.lights.len() {
        scene.lights.r[i] *= 0.5;
    }
    let (recoloured, f3) = render(&mut viewer, &scene, Skips::ALL);
    assert!(f3.appearance_only && !f3.reused);
    assert!(f3.report.upload_bytes > 0 && f3.stats.is_none());
    let mut fresh = Viewer::new(ctx.clone(), &scene).unwrap();
    let (expected, _) = render(&mut fresh, &scene, Skips::NONE);
    assert!(max_channel_difference(&recoloured, &expected) <= 1);
    assert_ne!(recoloured, first);

    // A moved light: full path again.
    scene.lights.y[100] += 0.5;
    let (_, f4) = render(&mut viewer, &scene, Skips::ALL);
    assert!(!f4.reused && !f4.appearance_only && f4.stats.is_some());

    // Another grid, then a turned camera, with the lights unchanged, each the only change from
    // the frame before: each is a frame of its own (reusing the lists would shade with another
    // grid's or view's clusters; neither was tested: audit), and each image equals a fresh
    // render's.
    let (_, f5) = render(&mut viewer, &scene, Skips::ALL);
    assert!(f5.reused, "unchanged again");
    let regridded = scene
        .clone()
        .with_grid(UVec3::new(16, 9, 24), DepthSlicing::Log);
    let mut turned = regridded.clone();
    turned.camera.target += myriad::cluster_math::glam::Vec3::new(0.5, 0.0, 0.0);
    assert_ne!(regridded.grid, scene.grid);
    for (what, changed) in [("another grid", &regridded), ("turned camera", &turned)] {
        let (image, frame) = render(&mut viewer, changed, Skips::ALL);
        assert!(
            !frame.reused && !frame.appearance_only && frame.stats.is_some(),
            "{what}: the lists were reused"
        );
        let mut fresh = Viewer::new(ctx.clone(), changed).unwrap();
        let (expected, _) = render(&mut fresh, changed, Skips::NONE);
        let worst = max_channel_difference(&image, &expected);
        assert!(worst <= 1, "{what}: differs from a fresh render by {worst}");
        assert!(
            render(&mut viewer, changed, Skips::ALL).1.reused,
            "{what}: then reused"
        );
    }
}

/// A refused frame drops the reuse cache: it had culled its own visible set into the state the
/// reuse path reads, so a later frame of the cached camera whose lights only changed colour
/// gathered them through that set and shaded them in other lights' clusters, with Ok.
#[test]
fn a_refused_frame_in_between_invalidates_the_reuse_cache() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let mut scene = RenderScene::default_scene(1000, 192, 96).unwrap();
    let mut viewer = Viewer::new(ctx.clone(), &scene).unwrap();
    render(&mut viewer, &scene, Skips::ALL);
    // The same lights seen by a wider camera (another visible set), refused after the cull:
    // the viewer's target is still 192 × 96.
    let mut wider = scene.clone();
    wider.camera.width = 384;
    let refused = viewer.frame_with_skips(&wider, Method::Refined, Skips::ALL);
    assert!(refused.is_err(), "{:?}", refused.map(|f| f.lights_assigned));
    for i in 0..scene.lights.len() {
        scene.lights.g[i] *= 0.5;
    }
    let (recoloured, frame) = render(&mut viewer, &scene, Skips::ALL);
    assert!(
        !frame.reused && !frame.appearance_only,
        "the cache outlived a refused frame"
    );
    let mut fresh = Viewer::new(ctx, &scene).unwrap();
    let (expected, _) = render(&mut fresh, &scene, Skips::NONE);
    assert!(max_channel_difference(&recoloured, &expected) <= 1);
}

#[test]
fn a_plain_frame_in_between_invalidates_the_reuse_cache() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let scene = RenderScene::default_scene(1000, 192, 96).unwrap();
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    let (skipping, _) = render(&mut viewer, &scene, Skips::ALL);
    // A plain frame uploads every light and the full grid's lists over the cached ones …
    viewer
        .frame(&scene, Shading::Clustered, Method::Refined, false)
        .unwrap();
    // … so the next skipping frame must not reuse what the GPU no longer holds.
    let (again, frame) = render(&mut viewer, &scene, Skips::ALL);
    assert!(
        !frame.reused && !frame.appearance_only,
        "stale cache reused"
    );
    assert!(max_channel_difference(&skipping, &again) <= 1);
    // Another method is another set of lists: not reused either.
    let other = viewer
        .frame_with_skips(&scene, Method::Binary, Skips::ALL)
        .unwrap();
    assert!(!other.reused, "lists of another method reused");
}

/// A viewer whose renderer is replaced (an engine rebuilding it on the same device) does not
/// take what the new renderer holds for the cached frame's data: each renderer counted its
/// uploads from 0, so one upload on the new one matched the cached count and the next skipping
/// frame was reused over another frame's lights and lists (145/255 off, with `Ok`; audit).
#[test]
fn a_replaced_renderer_does_not_match_the_reuse_cache() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let scene = RenderScene::default_scene(500, 128, 64).unwrap();
    let mut other = scene.clone();
    for i in 0..other.lights.len() {
        other.lights.r[i] *= 0.3;
        other.lights.y[i] += 0.7;
    }
    let mut fresh = Viewer::new(ctx.clone(), &scene).unwrap();
    let (expected, _) = render(&mut fresh, &scene, Skips::NONE);
    for skips in [
        Skips {
            reuse_unchanged: true,
            ..Skips::NONE
        },
        Skips {
            cull: true,
            reuse_unchanged: true,
            ..Skips::NONE
        },
    ] {
        let mut viewer = Viewer::new(ctx.clone(), &scene).unwrap();
        render(&mut viewer, &scene, skips);
        viewer.renderer = Renderer::try_new(&ctx, HEADLESS_FORMAT).unwrap();
        viewer.scene = viewer.renderer.upload_scene(&ctx, &scene.geometry).unwrap();
        viewer
            .frame(&other, Shading::Clustered, Method::Refined, false)
            .unwrap();
        let (image, frame) = render(&mut viewer, &scene, skips);
        assert!(
            !frame.reused,
            "{:?}: reused another renderer's upload",
            skips.names()
        );
        assert!(
            max_channel_difference(&image, &expected) <= 1,
            "{:?}",
            skips.names()
        );
    }
}

/// A camera the assignment cannot use (near 0) is the frame's error, with or without skips and
/// in the frame loop, and the viewer draws the next good frame as if it had not happened: it
/// panicked inside the assignment where no depth prepass refused it first (audit).
#[test]
fn an_unusable_camera_is_an_error_not_a_panic() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let scene = RenderScene::default_scene(100, 128, 64).unwrap();
    let mut bad = scene.clone();
    bad.camera.near = 0.0;
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    let (expected, _) = render(&mut viewer, &scene, Skips::NONE);
    let plain = viewer.frame(&bad, Shading::Clustered, Method::Refined, false);
    assert!(plain.is_err(), "a plain frame took near 0");
    for skips in [
        Skips::NONE,
        Skips {
            cull: true,
            ..Skips::NONE
        },
        Skips::ALL,
    ] {
        let e = viewer
            .frame_with_skips(&bad, Method::Refined, skips)
            .map(|_| ())
            .unwrap_err();
        assert!(e.to_string().contains("near"), "{:?}: {e:#}", skips.names());
    }
    let mut stage = viewer.gpu_stage();
    for pipelined in [false, true] {
        let looped = run_frames(
            &mut stage,
            &bad,
            Method::Refined,
            2,
            pipelined,
            false,
            |_, _| Ok(()),
        );
        assert!(
            looped.is_err(),
            "the frame loop took near 0 (pipelined: {pipelined})"
        );
    }
    let (after, _) = render(&mut viewer, &scene, Skips::NONE);
    assert!(max_channel_difference(&after, &expected) <= 1);
}

#[test]
fn tuned_frames_probe_both_sides_hold_the_choice_and_leave_the_image_unchanged() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let scene = RenderScene::default_scene(1000, 192, 96).unwrap();
    let mut plain = Viewer::new(ctx.clone(), &scene).unwrap();
    let (expected, _) = render(&mut plain, &scene, Skips::NONE);
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    viewer.set_prepass_tuner(TunerSettings {
        probe_frames: 2,
        hold_frames: 3,
        margin: 0.05,
    });
    let mut plans = vec![];
    for _ in 0..(4 + 3 + 4) {
        let (image, frame) = render(&mut viewer, &scene, Skips::TUNED);
        let tuning = frame.tuning.expect("a tuned frame says what it ran");
        // The frame ran its plan: masked and fitted with the prepass, neither without.
        assert_eq!(frame.active_clusters.is_some(), tuning.plan.use_prepass);
        assert_eq!(frame.prepass_seconds > 0.0, tuning.plan.use_prepass);
        assert!(
            max_channel_difference(&image, &expected) <= 1,
            "{:?} changed the image",
            tuning.plan
        );
        plans.push(tuning.plan);
    }
    let probe = |use_prepass| FramePlan {
        use_prepass,
        probe: true,
    };
    // Four probe frames, without first; then the choice held three frames, unmeasured; then a
    // new probe.
    assert_eq!(
        plans[..4],
        [probe(false), probe(true), probe(false), probe(true)]
    );
    let decision = viewer.prepass_decision().expect("decided");
    assert!(decision.with_seconds > 0.0 && decision.without_seconds > 0.0);
    let held: Vec<_> = plans[4..7].iter().collect();
    assert!(
        held.iter()
            .all(|p| !p.probe && p.use_prepass == held[0].use_prepass),
        "{plans:?}"
    );
    assert!(plans[7..].iter().all(|p| p.probe), "{plans:?}");
    // Without a saving that needs the prepass there is nothing to tune.
    let cull_only = Skips {
        cull: true,
        tune_prepass: true,
        ..Skips::NONE
    };
    let (_, frame) = render(&mut viewer, &scene, cull_only);
    assert!(frame.tuning.is_none());
}

/// A probe frame that is reused whole ran neither side's work: it must not count as a timing,
/// and the probe waits, planning the same frame again. The margin of 0.99 makes the first
/// decision "without the prepass" whatever the timings, so the probe after the held frames starts
/// on the side the cached frame already has, and nothing changes, so every frame from there on
/// is reused. The tuner keeps the settings it was given.
#[test]
fn a_reused_probe_frame_is_not_timed_and_the_probe_waits() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let scene = RenderScene::default_scene(1000, 192, 96).unwrap();
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    let settings = TunerSettings {
        probe_frames: 1,
        hold_frames: 2,
        margin: 0.99,
    };
    viewer.set_prepass_tuner(settings);
    assert_eq!(viewer.prepass_tuner_settings(), settings);
    let skips = Skips {
        tune_prepass: true,
        ..Skips::ALL
    };
    let frames: Vec<_> = (0..7)
        .map(|_| render(&mut viewer, &scene, skips).1)
        .collect();
    let plans: Vec<FramePlan> = frames.iter().map(|f| f.tuning.unwrap().plan).collect();
    let plan = |use_prepass, probe| FramePlan { use_prepass, probe };
    // One probe frame a side, then the decision held two frames (the second reused).
    assert_eq!(
        plans[..4],
        [
            plan(false, true),
            plan(true, true),
            plan(false, false),
            plan(false, false)
        ]
    );
    assert!(!frames[2].reused && frames[3].reused);
    // The next probe starts without the prepass, like the cached frame: reused, so untimed, so
    // planned again.
    for (n, frame) in frames.iter().enumerate().skip(4) {
        assert_eq!(plans[n], plan(false, true), "frame {n}: {plans:?}");
        assert!(frame.reused, "frame {n}");
    }
    assert!(!viewer.prepass_decision().unwrap().use_prepass);
}

/// Skipping frames shade with the viewer's settings: at twice the exposure a frame with no
/// savings is the plain frame at twice the exposure, not the default look.
#[test]
fn skipping_frames_shade_with_the_viewers_settings() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let scene = RenderScene::default_scene(1000, 192, 96).unwrap();
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    let (default_look, _) = render(&mut viewer, &scene, Skips::NONE);
    viewer.settings.exposure = 2.0;
    viewer
        .frame(&scene, Shading::Clustered, Method::Refined, false)
        .unwrap();
    let plain = viewer.image().unwrap();
    assert!(max_channel_difference(&plain, &default_look) > 8);
    let (skipping, _) = render(&mut viewer, &scene, Skips::NONE);
    let d = max_channel_difference(&skipping, &plain);
    assert!(
        d <= 1,
        "the skipping frame differs from the plain one by {d}/255"
    );
}

/// Without the `variants` saving a frame forces every shader path (the spot-cone code on a
/// scene without spot lights), and with it builds only what the scene needs: after each, the
/// pipelines of that kind of frame are already built, and the spot-free scene's frame left the
/// forced ones unbuilt.
#[test]
fn without_feature_variants_every_shader_path_is_built() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let mut scene = RenderScene::default_scene(1000, 192, 96).unwrap();
    scene.lights = without_spots(&scene.lights);
    let mut forced = Viewer::new(ctx.clone(), &scene).unwrap();
    render(&mut forced, &scene, Skips::NONE);
    forced.settings.force_all_features = true;
    assert_eq!(
        forced.prepare(&scene, Shading::Clustered, false).unwrap(),
        0,
        "a frame without `variants` left shader paths unbuilt"
    );
    let mut varied = Viewer::new(ctx, &scene).unwrap();
    let variants = Skips {
        feature_variants: true,
        ..Skips::NONE
    };
    render(&mut varied, &scene, variants);
    assert_eq!(
        varied.prepare(&scene, Shading::Clustered, false).unwrap(),
        0,
        "a frame with `variants` did not build the spot-free paths"
    );
    varied.settings.force_all_features = true;
    assert!(
        varied.prepare(&scene, Shading::Clustered, false).unwrap() > 0,
        "a frame with `variants` built the spot paths a scene without spots does not need"
    );
}

/// Past the pair budget the lists are built unmasked on a coarser grid, so the frame reports no
/// active-cluster count (the mask's count described clusters the lists no longer have) and the
/// image still equals the image without savings.
#[test]
fn coarsened_lists_report_no_active_cluster_count() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let scene = RenderScene::default_scene(300, 192, 96).unwrap();
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    let active = Skips {
        active_clusters: true,
        ..Skips::NONE
    };
    let (reference, _) = render(&mut viewer, &scene, Skips::NONE);
    let (_, full) = render(&mut viewer, &scene, active);
    assert!(
        full.active_clusters.is_some_and(|n| n > 0),
        "{:?}",
        full.active_clusters
    );
    viewer.set_pair_budget(200);
    let (image, coarse) = render(&mut viewer, &scene, active);
    let stats = coarse.stats.as_ref().unwrap();
    assert!(stats.coarsened > 0, "{stats:?}");
    assert_ne!(coarse.grid.dims(), scene.grid.dims());
    assert_eq!(coarse.active_clusters, None);
    let worst = max_channel_difference(&image, &reference);
    assert!(
        worst <= 1,
        "coarsened lists differ from the full ones by {worst}/255"
    );
}

/// Invalid lights (a NaN, negative, zero or infinite radius, a non-finite position) are skipped
/// and counted in every frame path: the cull drops them and now counts them, where before
/// those it dropped vanished from the frame's numbers while the ones it kept (an infinite or
/// zero radius) were counted by the assignment (audit). The image is the one without them.
#[test]
fn invalid_lights_are_counted_in_every_frame_path() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let mut scene = RenderScene::default_scene(1000, 192, 96).unwrap();
    // The first lights in view, so that a cull that kept a light by its position would see it.
    let mut valid_view = Viewer::new(ctx.clone(), &scene).unwrap();
    let (_, plain) = render(&mut valid_view, &scene, Skips::NONE);
    assert_eq!(plain.lights_invalid, 0);
    let l = &mut scene.lights;
    l.radius[10] = f32::NAN;
    l.radius[20] = -2.0;
    l.radius[30] = 0.0;
    l.radius[40] = f32::INFINITY;
    l.x[50] = f32::INFINITY;
    l.z[60] = f32::NAN;
    let invalid = 6;
    // The same scene with those six lights out of reach of every pixel instead.
    let mut reference = scene.clone();
    for i in [10, 20, 30, 40, 50, 60] {
        let l = &mut reference.lights;
        (l.x[i], l.y[i], l.z[i], l.radius[i]) = (0.0, 1e6, 0.0, 1e-3);
    }
    let mut fresh = Viewer::new(ctx.clone(), &reference).unwrap();
    let (expected, _) = render(&mut fresh, &reference, Skips::NONE);

    let mut viewer = Viewer::new(ctx.clone(), &scene).unwrap();
    for (name, skips) in singles() {
        let (image, frame) = render(&mut viewer, &scene, skips);
        assert_eq!(frame.lights_invalid, invalid, "{name}");
        assert!(max_channel_difference(&image, &expected) <= 1, "{name}");
    }
    // Reused: the count of the frame whose lists it keeps.
    let (_, frame) = render(&mut viewer, &scene, Skips::ALL);
    assert!(frame.reused);
    assert_eq!(frame.lights_invalid, invalid);

    let mut stage = viewer.gpu_stage();
    for pipelined in [false, true] {
        for cull in [false, true] {
            let looped = run_frames(
                &mut stage,
                &scene,
                Method::Refined,
                3,
                pipelined,
                cull,
                |_, _| Ok(()),
            )
            .unwrap();
            for f in &looped.frames {
                assert_eq!(
                    f.lights_invalid, invalid,
                    "pipelined {pipelined}, cull {cull}"
                );
            }
        }
    }
}

/// A wall facing the camera at view depth `depth` (the camera at the origin looking down −Z), with
/// 300 lights that just reach it from in front and from behind, on a 16×8×24 log grid.
fn wall_scene(depth: f32, grid: ClusterGrid) -> RenderScene {
    let (w, h) = (128, 64);
    let mut scene = RenderScene::default_scene(0, w, h).unwrap();
    let half = depth * 2.0;
    let geometry = &mut scene.geometry;
    geometry.vertices = [(-half, -half), (half, -half), (half, half), (-half, half)]
        .iter()
        .map(|&(x, y)| Vertex {
            position: [x, y, -depth],
            normal: [0.0, 0.0, 1.0],
            uv: [0.0, 0.0],
        })
        .collect();
    geometry.indices = vec![0, 1, 2, 0, 2, 3];
    geometry.draws.truncate(1);
    geometry.draws[0].first_index = 0;
    geometry.draws[0].index_count = 6;
    let material = &mut geometry.materials[geometry.draws[0].material as usize];
    material.base_color_texture = None;
    material.uniforms.base_color = [0.8, 0.8, 0.8, 1.0];
    material.blend = myriad::gpu::Blend::Opaque;
    scene.blended_bounds = blended_bounds(&scene.geometry);
    scene.camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, w, h, 0.1, 1000.0);
    scene.grid = grid;
    let mut lights = Lights::new();
    let mut state = 12345u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f32 / (1u64 << 53) as f32
    };
    for i in 0..300 {
        let (x, y) = ((next() - 0.5) * 1.6 * depth, (next() - 0.5) * 0.8 * depth);
        let radius = depth * (0.02 + 0.2 * next());
        let gap = radius * (0.9 + 0.1 * next());
        let z = if i % 2 == 0 {
            -depth + gap
        } else {
            -depth - gap
        };
        // Brighter with distance, as the falloff is over the light's distance, not its range.
        let intensity = 2.0 * (1.0 + radius * radius);
        lights.push(LightRecord::point(Vec3::new(x, y, z), radius).with_intensity(intensity));
    }
    scene.lights = lights;
    scene
}

/// A wall exactly on a slice edge, or one f32 step either side of it, is every pixel's depth: the
/// fitted depth range shrinks to that one value and the mask to the clusters around it, and the
/// image must still be the brute-force one. (A cluster depth off by 1e-4 in the shading pass
/// sent those pixels to clusters the mask had left empty, and no scene of the suite had one
/// depth everywhere: audit.)
#[test]
fn a_wall_on_a_slice_edge_renders_with_every_saving_as_brute_force() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let grid = ClusterGrid::new(UVec3::new(16, 8, 24), DepthSlicing::Log, 0.1, 1000.0);
    for k in [3, 10, 17] {
        let edge = grid.slice_start_depth(k);
        for depth in [edge.next_down(), edge, edge.next_up()] {
            let scene = wall_scene(depth, grid);
            let mut viewer = Viewer::new(ctx.clone(), &scene).unwrap();
            viewer
                .frame(&scene, Shading::BruteForce, Method::Refined, false)
                .unwrap();
            let brute = viewer.image().unwrap();
            let lit = brute
                .chunks(4)
                .filter(|p| p[..3].iter().any(|&c| c > 60))
                .count();
            assert!(
                lit > 128 * 64 / 20,
                "wall at {depth}: only {lit} lit pixels"
            );
            let (image, frame) = render(&mut viewer, &scene, Skips::ALL);
            assert!(frame.active_clusters.is_some(), "wall at {depth}: no mask");
            let worst = max_channel_difference(&image, &brute);
            assert!(
                worst <= 1,
                "wall at {depth} (slice edge {k}): every saving differs from brute force by {worst}"
            );
        }
    }
}
