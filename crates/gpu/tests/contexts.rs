//! Headless contexts made, used and dropped on many threads at once, as parallel tests and
//! tools do. On NVIDIA's driver this crashed the process while each context had a wgpu instance
//! of its own (`shared_instance` says what was seen); here every thread's device must work and
//! agree with the CPU, round after round.

use glam::UVec3;
use myriad_cluster_math::{ClusterGrid, DepthSlicing};
use myriad_gpu::cluster_check::gpu_cluster_ids;
use myriad_gpu::{GpuContext, SKIP_GPU_TESTS_VAR, shared_instance};
use std::process::Command;

const THREADS: usize = 8;
const ROUNDS: usize = 3;

#[test]
fn contexts_made_and_dropped_on_many_threads_at_once_all_work() {
    if GpuContext::headless_for_tests().is_none() {
        return;
    }
    let grid = ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, 0.1, 500.0);
    let (width, height) = (1920, 1080);
    let barrier = std::sync::Barrier::new(THREADS);
    std::thread::scope(|scope| {
        for thread in 0..THREADS {
            let (grid, barrier) = (&grid, &barrier);
            scope.spawn(move || {
                for round in 0..ROUNDS {
                    // All threads create (and, at the end of the round, drop) their contexts
                    // together, so creation and teardown overlap.
                    barrier.wait();
                    let ctx = GpuContext::headless().expect("a headless context");
                    let n = 64 + 8 * thread + round;
                    let pixels: Vec<[u32; 2]> = (0..n as u32)
                        .map(|i| [(i * 97 + thread as u32) % width, (i * 31) % height])
                        .collect();
                    let depths: Vec<f32> = (0..n).map(|i| 0.05 + i as f32 * 7.3).collect();
                    let gpu = gpu_cluster_ids(&ctx, grid, width, height, &pixels, &depths)
                        .expect("the compute pass runs");
                    for ((p, d), id) in pixels.iter().zip(&depths).zip(&gpu) {
                        let cpu = grid.cluster_of_pixel(p[0], p[1], *d, width, height);
                        assert_eq!(*id, cpu, "thread {thread} round {round}: {p:?} at {d}");
                    }
                    drop(ctx);
                }
            });
        }
    });
}

/// Every test of a process gets the same device (a clone of one context), whichever thread asks:
/// devices made and dropped by parallel tests deadlocked NVIDIA's driver
/// (`GpuContext::headless_for_tests` says what was seen).
#[test]
fn tests_share_one_device_across_threads() {
    let Some(first) = GpuContext::headless_for_tests() else {
        return;
    };
    let others: Vec<GpuContext> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..THREADS)
            .map(|_| scope.spawn(|| GpuContext::headless_for_tests().unwrap()))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for other in &others {
        assert!(other.device == first.device && other.queue == first.queue);
    }
    // A context of one's own is still a device of its own.
    let own = GpuContext::headless().unwrap();
    assert!(own.device != first.device);
}

/// The instance behind every headless context is one per process, whichever thread asks first.
#[test]
fn every_thread_gets_the_one_shared_instance() {
    let here: *const _ = shared_instance();
    let elsewhere: Vec<usize> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..THREADS)
            .map(|_| scope.spawn(|| shared_instance() as *const _ as usize))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert!(
        elsewhere.iter().all(|&p| p == here as usize),
        "{elsewhere:?}"
    );
}

/// A headless device asks for the timestamp features its adapter has and for nothing else: an
/// adapter without timestamps still gives a device, and no other feature is switched on behind
/// an engine's back (mutation audit: requesting every adapter feature passed every test).
#[test]
fn headless_devices_enable_only_the_timestamp_features_the_adapter_has() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    // The adapter `headless` picks: the same instance and options.
    let adapter = pollster::block_on(shared_instance().request_adapter(
        &wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        },
    ))
    .unwrap();
    assert_eq!(adapter.get_info(), ctx.adapter_info);
    let timestamps =
        wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
    assert_eq!(ctx.device.features(), adapter.features() & timestamps);
    // The test adapter (llvmpipe on CI) has other features, so asking for all would show.
    assert_ne!(adapter.features(), adapter.features() & timestamps);
}

/// Mesa's llvmpipe is recognised by its adapter name or by its driver name alone (each backend
/// fills in one or both), and no other adapter gets a loop limit; the budget per pixel follows
/// (`loop_budget.rs`). The adapter info is written over on a clone of the test context, so
/// this holds on any adapter.
#[test]
fn llvmpipe_is_recognised_by_its_name_or_its_driver() {
    let Some(ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    for (name, driver, limited) in [
        ("llvmpipe (LLVM 19.1.7, 256 bits)", "llvmpipe", true),
        ("llvmpipe (LLVM 19.1.7, 256 bits)", "", true),
        ("Software rasterizer", "llvmpipe", true),
        ("NVIDIA H100", "NVIDIA", false),
    ] {
        let mut info = ctx.clone();
        info.adapter_info.name = name.to_string();
        info.adapter_info.driver = driver.to_string();
        let limit = limited.then_some(65_535);
        assert_eq!(
            info.shader_loop_limit(),
            limit,
            "{name:?}, driver {driver:?}"
        );
        assert_eq!(
            info.max_lights_per_pixel(myriad_gpu::ShadingMode::BruteForce, 16),
            limited.then_some(65_534),
            "{name:?}, driver {driver:?}"
        );
    }
}

/// The one-line description names the adapter, its backend and kind, and its driver, as the
/// loop-limit error and the reports show it.
#[test]
fn describe_names_the_adapter_backend_kind_and_driver() {
    let Some(mut ctx) = GpuContext::headless_for_tests() else {
        return;
    };
    ctx.adapter_info.name = "Adapter X".to_string();
    ctx.adapter_info.backend = wgpu::Backend::Vulkan;
    ctx.adapter_info.device_type = wgpu::DeviceType::Cpu;
    ctx.adapter_info.driver = "drv".to_string();
    ctx.adapter_info.driver_info = "1.2".to_string();
    assert_eq!(ctx.describe(), "Adapter X (Vulkan, Cpu, driver drv 1.2)");
}

/// Set in the environment of this binary's reruns by
/// [`without_an_adapter_gpu_tests_fail_unless_told_to_skip`], which then only says what
/// `headless_for_tests` gave.
const SKIP_POLICY_CHILD: &str = "MYRIAD_TEST_SKIP_POLICY_CHILD";

/// The GPU-test policy: a GPU test gets a context wherever an adapter exists, and without one
/// it fails with advice unless `MYRIAD_SKIP_GPU_TESTS=1` asks to skip (any other value does
/// not). Without an adapter is this binary rerun with `WGPU_BACKEND` naming only a backend
/// this platform lacks (mutation audit: a `None` for every test, which turns each GPU test into
/// an early return, passed every test; so did skipping without being asked, or never).
#[test]
fn without_an_adapter_gpu_tests_fail_unless_told_to_skip() {
    if std::env::var_os(SKIP_POLICY_CHILD).is_some() {
        // The rerun: a panic says itself.
        match GpuContext::headless_for_tests() {
            Some(_) => println!("child: a context"),
            None => println!("child: no context"),
        }
        return;
    }
    let skipping = std::env::var(SKIP_GPU_TESTS_VAR).as_deref() == Ok("1");
    let here = GpuContext::headless_for_tests();
    assert!(
        here.is_some() || skipping,
        "None without {SKIP_GPU_TESTS_VAR}=1"
    );
    let absent = if cfg!(target_os = "macos") {
        "dx12"
    } else {
        "metal"
    };
    for skip in [None, Some("1"), Some("0")] {
        let mut child = Command::new(std::env::current_exe().unwrap());
        child
            .args([
                "--exact",
                "without_an_adapter_gpu_tests_fail_unless_told_to_skip",
                "--nocapture",
            ])
            .env(SKIP_POLICY_CHILD, "1")
            .env("WGPU_BACKEND", absent);
        match skip {
            Some(value) => child.env(SKIP_GPU_TESTS_VAR, value),
            None => child.env_remove(SKIP_GPU_TESTS_VAR),
        };
        let out = child.output().unwrap();
        let all = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        let what = format!("{SKIP_GPU_TESTS_VAR}={skip:?}: {all}");
        if skip == Some("1") {
            assert!(out.status.success(), "{what}");
            assert!(all.contains("child: no context"), "{what}");
            assert!(all.contains("skipping GPU test"), "{what}");
        } else {
            assert!(!out.status.success(), "{what}");
            assert!(!all.contains("child: "), "{what}");
            assert!(all.contains("GPU tests need an adapter"), "{what}");
            assert!(all.contains(SKIP_GPU_TESTS_VAR), "{what}");
        }
    }
}
