//! Headless contexts made, used and dropped on many threads at once, as parallel tests and
//! tools do. On NVIDIA's driver this crashed the process while each context had a wgpu instance
//! of its own (`shared_instance` says what was seen); here every thread's device must work and
//! agree with the CPU, round after round.

use glam::UVec3;
use myriad_cluster_math::{ClusterGrid, DepthSlicing};
use myriad_gpu::cluster_check::gpu_cluster_ids;
use myriad_gpu::{GpuContext, shared_instance};

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
