//! The device the renderer works on: the caller's own (an engine) or one this crate creates for
//! headless use (the CLI, tests).

use crate::GpuError;
use crate::device_loss::{DeviceLoss, DeviceLossRecorder};

/// A wgpu device and queue plus what the renderer needs to know about them.
#[derive(Clone, Debug)]
pub struct GpuContext {
    /// The device every resource is created on.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter the device came from.
    pub adapter_info: wgpu::AdapterInfo,
    /// Where the device's loss is recorded (`device_loss.rs`); shared by every clone.
    loss: DeviceLossRecorder,
}

impl GpuContext {
    /// Wraps an engine's device and queue (the adapter is asked of the device, so an engine on
    /// llvmpipe gets the same loop-limit guard as the CLI). Timestamp queries are used when the device was
    /// created with [`wgpu::Features::TIMESTAMP_QUERY`] (the passes), and with
    /// [`wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS`] too (the upload's copies).
    ///
    /// The device's lost callback stays the engine's: to have the renderer's calls return
    /// [`GpuError::DeviceLost`] after a loss, call [`DeviceLossRecorder::record`] from that
    /// callback (see [`GpuContext::loss_recorder`]), or [`GpuContext::track_device_loss`] when
    /// the engine sets none.
    pub fn from_device(device: wgpu::Device, queue: wgpu::Queue) -> Self {
        Self {
            adapter_info: device.adapter_info(),
            device,
            queue,
            loss: DeviceLossRecorder::default(),
        }
    }

    /// Sets the device's lost callback to record the loss in this context, replacing any
    /// callback the device had (wgpu keeps one). `GpuContext::headless` does this itself.
    pub fn track_device_loss(&self) {
        self.loss.watch(&self.device);
    }

    /// The record this context's checks read: an engine that keeps its own device-lost callback
    /// calls [`DeviceLossRecorder::record`] on it from there. It holds no device.
    pub fn loss_recorder(&self) -> DeviceLossRecorder {
        self.loss.clone()
    }

    /// The device's loss, once recorded (see [`GpuContext::track_device_loss`]).
    pub fn device_loss(&self) -> Option<DeviceLoss> {
        self.loss.loss()
    }

    /// [`GpuError::DeviceLost`] when the device is known to be lost. It polls the device first,
    /// without waiting, so that a loss wgpu has noticed but not yet reported reaches the lost
    /// callback now; the renderer checks this before every call that touches the device (0.22 µs
    /// a check on llvmpipe's idle device, 10,000 in a loop).
    pub fn check_not_lost(&self) -> Result<(), GpuError> {
        // A poll's own error is not this check's business: the call that follows meets it.
        let _ = self.device.poll(wgpu::PollType::Poll);
        self.loss_error()
    }

    /// [`GpuError::DeviceLost`] if a loss is recorded, without polling.
    fn loss_error(&self) -> Result<(), GpuError> {
        match self.loss.loss() {
            Some(loss) => Err(GpuError::DeviceLost(loss)),
            None => Ok(()),
        }
    }

    #[cfg(feature = "headless")]
    /// Creates a headless device on the best adapter wgpu finds (a real GPU, else a software
    /// one such as Mesa's llvmpipe), with timestamp queries (in passes and between commands)
    /// when the adapter has them and the
    /// adapter's own limits (so large light lists fit). Its device's loss is recorded
    /// ([`GpuContext::track_device_loss`]): after one, the renderer's calls return
    /// [`GpuError::DeviceLost`].
    ///
    /// Every context this makes comes from one wgpu instance per process ([`shared_instance`]),
    /// so it is safe to call from several threads at once (parallel tests do). Keep one device
    /// per process where you can: NVIDIA's driver deadlocked when a device was destroyed while
    /// other threads worked on other devices ([`GpuContext::headless_for_tests`] says what was
    /// seen).
    pub fn headless() -> Result<Self, GpuError> {
        let adapter = pollster::block_on(shared_instance().request_adapter(
            &wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: None,
                apply_limit_buckets: false,
            },
        ))
        .map_err(|e| GpuError::NoAdapter {
            detail: match std::env::var("WGPU_BACKEND") {
                Ok(backends) => format!("{e}; WGPU_BACKEND={backends} chose the backends"),
                Err(_) => e.to_string(),
            },
        })?;
        let info = adapter.get_info();
        let wanted =
            wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("myriad"),
            required_features: adapter.features() & wanted,
            required_limits: adapter.limits(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| GpuError::RequestDevice {
            adapter: info.name.clone(),
            detail: e.to_string(),
        })?;
        let ctx = Self {
            device,
            queue,
            adapter_info: info,
            loss: DeviceLossRecorder::default(),
        };
        ctx.track_device_loss();
        Ok(ctx)
    }

    /// The loop limit of one shader invocation on this adapter, where it is known to be limited:
    /// Mesa's llvmpipe stops after 65 535 iterations over all loops
    /// (`LP_MAX_TGSI_LOOP_ITERATIONS`; `loop_budget.rs` says what fits). `None` for other
    /// adapters.
    pub fn shader_loop_limit(&self) -> Option<u64> {
        let info = &self.adapter_info;
        (info.name.contains("llvmpipe") || info.driver.contains("llvmpipe")).then_some(65_535)
    }

    /// The most lights one pixel may loop over in `mode` with `slices` depth slices on this
    /// adapter; `None` where loops are not known to be limited.
    pub fn max_lights_per_pixel(&self, mode: crate::ShadingMode, slices: u32) -> Option<u64> {
        self.shader_loop_limit()
            .map(|limit| crate::loop_budget::max_lights_per_pixel(limit, mode, slices))
    }

    /// The most cluster–light pairs one frame's lists may hold on this device: the largest
    /// storage buffer it can create and bind (the smaller of its `max_storage_buffer_binding_size`
    /// and `max_buffer_size`, in whole 4-byte words) over the 4 bytes of an index. Give it to the assigner's pair budget
    /// (`myriad_assignment::Assigner::with_pair_budget`) and a frame past it is built on a coarser
    /// grid, which the renderer takes, instead of being refused with
    /// [`GpuError::BufferTooLarge`] after the assignment (128 MiB on llvmpipe: 33.5 M pairs).
    pub fn max_list_pairs(&self) -> u64 {
        Self::list_pairs_in(crate::buffers::storage_capacity(&self.device.limits()))
    }

    /// The cluster–light pairs whose indices (u32) fit in a storage binding of `bytes`.
    pub fn list_pairs_in(bytes: u64) -> u64 {
        bytes / std::mem::size_of::<u32>() as u64
    }

    /// Whether passes can be timed with timestamp queries.
    pub fn has_timestamps(&self) -> bool {
        self.device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// Whether timestamps can also be written between commands, which times the upload's
    /// copies ([`crate::PassTimes::upload_ms`]).
    pub fn has_encoder_timestamps(&self) -> bool {
        self.device.features().contains(
            wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS,
        )
    }

    /// A one-line description of the adapter ("NVIDIA H100 (Vulkan, DiscreteGpu)").
    pub fn describe(&self) -> String {
        let info = &self.adapter_info;
        format!(
            "{} ({:?}, {:?}, driver {} {})",
            info.name, info.backend, info.device_type, info.driver, info.driver_info
        )
    }

    /// Blocks until the GPU has finished all submitted work; [`GpuError::DeviceLost`] when the
    /// device is lost (before or while waiting: the wait is when wgpu reports it).
    pub fn wait_idle(&self) -> Result<(), GpuError> {
        self.loss_error()?;
        let waited = self.device.poll(wgpu::PollType::wait_indefinitely());
        self.loss_error()?;
        waited.map(|_| ()).map_err(GpuError::Wait)
    }
}

/// The one wgpu instance of this process behind [`GpuContext::headless`], created on first use
/// and never dropped. It takes wgpu's environment variables (`WGPU_BACKEND` to choose among the
/// backends built in — Vulkan, Metal, DX12 — and the rest), as wgpu's
/// `InstanceDescriptor::new_without_display_handle_from_env` reads them.
///
/// Why one: each instance loads the Vulkan loader and the driver, and dropping its last device
/// unloads them again. Instances made and dropped on several threads at once crashed NVIDIA's
/// driver (580.159, H100): the CLI's test binary, whose GPU tests each made and dropped a context
/// of their own, died of a segmentation fault in 3 runs of 3 at 8 test threads and passed
/// serially, while gdb reported the process's shared-library list changing under it; the test
/// `contexts_made_and_dropped_on_many_threads_at_once_all_work` (8 threads, 3 rounds) failed 5
/// runs of 5 that way (2 segmentation faults, 2 hangs, 1 abort at exit after the test itself had
/// passed). With the instance shared the
/// driver stays loaded and only devices come and go: 5 runs of 5 passed, and the CLI's tests 7 of
/// 7 at 8 and 16 threads.
#[cfg(feature = "headless")]
pub fn shared_instance() -> &'static wgpu::Instance {
    static INSTANCE: std::sync::OnceLock<wgpu::Instance> = std::sync::OnceLock::new();
    INSTANCE.get_or_init(|| {
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env())
    })
}

/// Set to `1` to let GPU tests pass (with a note on stderr) where no adapter exists at all.
/// Without it, a GPU test on a machine without any adapter fails and says how to get one.
pub const SKIP_GPU_TESTS_VAR: &str = "MYRIAD_SKIP_GPU_TESTS";

#[cfg(feature = "headless")]
impl GpuContext {
    /// For tests: the process's one headless test context (a clone of it: the same device and
    /// queue); `None` only when there is no adapter *and* [`SKIP_GPU_TESTS_VAR`] is `1`;
    /// otherwise a missing adapter panics with the reason.
    ///
    /// Why one device for every test in a process, made once and never dropped: on NVIDIA's
    /// driver (580.159, H200) a device destroyed while other threads work on other devices of
    /// the same process can deadlock. `tests/gpu_render.rs`, whose tests each made and dropped a
    /// device, stalled in 5 of 9 runs at 4 and 16 test threads (0 of 1 serially); the stacks of
    /// a stalled run (eu-stack) had one thread inside `vkDestroyDevice` waiting on the driver, a
    /// second `vkDestroyDevice` waiting for the Vulkan loader's lock, and threads dropping a queue
    /// and a render pipeline parked on the driver's own lock. With the one shared device, 12 runs
    /// of 12 of that binary and 2 of 2 of every other GPU test binary passed at 16 threads. An
    /// engine has one device too. Tests that need a device of their own (other limits, another
    /// device's resources) still make one.
    pub fn headless_for_tests() -> Option<Self> {
        static SHARED: std::sync::OnceLock<Result<GpuContext, String>> = std::sync::OnceLock::new();
        match SHARED.get_or_init(|| Self::headless().map_err(|e| e.to_string())) {
            Ok(ctx) => Some(ctx.clone()),
            Err(e) if std::env::var(SKIP_GPU_TESTS_VAR).as_deref() == Ok("1") => {
                eprintln!("skipping GPU test ({SKIP_GPU_TESTS_VAR}=1): {e}");
                None
            }
            Err(e) => panic!(
                "GPU tests need an adapter: {e}. Set {SKIP_GPU_TESTS_VAR}=1 to skip them explicitly."
            ),
        }
    }
}
