//! A device lost under the renderer: every later call says so, and nothing panics.
//!
//! Before `device_loss.rs` the first frame after a loss was reported as running out of memory
//! (its staging copy could not be mapped) and the next read-back panicked inside wgpu. The loss
//! here is `Device::destroy`, the one a test can cause; a driver's loss reaches the same
//! callback with reason `Unknown`. Each test makes (and loses) a device of its own, one test per
//! binary: a device destroyed while other threads work on other devices deadlocked NVIDIA's
//! driver (`GpuContext::headless_for_tests` says what was seen).

use myriad::assignment::Method;
use myriad::gpu::wgpu::{self, DeviceLostReason};
use myriad::gpu::{DeviceLoss, GpuContext, GpuError, SKIP_GPU_TESTS_VAR, shared_instance};
use myriad::render::{RenderScene, Shading, Viewer};

/// The loss in `error` (an `anyhow` error from the viewer), which must be `GpuError::DeviceLost`.
fn lost(what: &str, error: Option<anyhow::Error>) -> DeviceLoss {
    let error = error.unwrap_or_else(|| panic!("{what} succeeded on a destroyed device"));
    match error.downcast_ref::<GpuError>() {
        Some(GpuError::DeviceLost(loss)) => loss.clone(),
        _ => panic!("{what}: {error:#}, not a lost device"),
    }
}

/// A second device on the adapter `headless` would choose, with the renderer's limits, as an
/// engine would make its own (with its own lost callback).
fn engine_device() -> Option<(wgpu::Device, wgpu::Queue)> {
    let adapter = pollster::block_on(
        shared_instance().request_adapter(&wgpu::RequestAdapterOptions::default()),
    )
    .ok()?;
    let limits = myriad::gpu::Renderer::required_limits_for(&adapter.limits());
    pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_limits: limits,
        ..Default::default()
    }))
    .ok()
}

#[test]
fn every_call_after_a_loss_reports_it_on_headless_and_engine_devices() {
    if GpuContext::headless().is_err() && std::env::var(SKIP_GPU_TESTS_VAR).as_deref() == Ok("1") {
        return;
    }
    let scene = RenderScene::default_scene(64, 96, 48).unwrap();

    // The headless context records its own loss.
    let mut viewer = Viewer::new(GpuContext::headless().unwrap(), &scene).unwrap();
    viewer
        .frame(&scene, Shading::Clustered, Method::Refined, false)
        .unwrap();
    assert!(viewer.image().unwrap().iter().any(|&c| c > 0));
    assert_eq!(viewer.ctx.device_loss(), None);
    viewer.ctx.device.destroy();
    // No wait in between: the frame's own check polls the device, which reports the loss.
    let loss = lost(
        "a frame",
        viewer
            .frame(&scene, Shading::Clustered, Method::Refined, false)
            .err(),
    );
    assert_eq!(loss.reason, DeviceLostReason::Destroyed);
    lost("the read-back", viewer.image().err());
    lost(
        "prepare",
        viewer.prepare(&scene, Shading::BruteForce, false).err(),
    );
    lost(
        "the depth read-back",
        viewer
            .renderer
            .read_depth(&viewer.ctx)
            .err()
            .map(Into::into),
    );
    lost("a wait", viewer.ctx.wait_idle().err().map(Into::into));
    let message = viewer.image().unwrap_err().to_string();
    assert!(
        message.contains("device was destroyed") && message.contains("make a new device"),
        "{message}"
    );
    // A new renderer on the lost device is refused too, not built with a misleading reason.
    lost(
        "a new renderer",
        myriad::gpu::Renderer::try_new(&viewer.ctx, myriad::gpu::HEADLESS_FORMAT)
            .err()
            .map(Into::into),
    );

    // An engine's device keeps the engine's callback, which records the loss for the renderer.
    let (device, queue) = engine_device().expect("a second device on the same adapter");
    let ctx = GpuContext::from_device(device, queue);
    let recorder = ctx.loss_recorder();
    let (told, heard) = std::sync::mpsc::channel();
    ctx.device.set_device_lost_callback(move |reason, message| {
        recorder.record(reason, message.clone());
        let _ = told.send(reason);
    });
    let mut viewer = Viewer::new(ctx, &scene).unwrap();
    viewer
        .frame(&scene, Shading::Clustered, Method::Refined, false)
        .unwrap();
    viewer.image().unwrap();
    viewer.ctx.device.destroy();
    let loss = lost(
        "an engine's frame",
        viewer
            .frame(&scene, Shading::Clustered, Method::Refined, false)
            .err(),
    );
    assert_eq!(loss.reason, DeviceLostReason::Destroyed);
    assert_eq!(heard.try_recv(), Ok(DeviceLostReason::Destroyed));
    lost("an engine's read-back", viewer.image().err());
}
