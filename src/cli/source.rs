//! Where a command's scene comes from: a scene file or a generated preset; and thread pools.

use anyhow::{Context, Result, bail, ensure};
use myriad::cluster_math::glam::UVec3;
use myriad::render::RenderScene;
use myriad::scene::{ClusterGrid, LightPolicy, LoadOptions, Model, Preset, Scene};
use std::path::{Path, PathBuf};

/// `--scene FILE` or `--preset P [--lights N] [--seed K]`.
#[derive(clap::Args, Debug)]
pub struct SceneSource {
    /// Scene file (JSON; format in the README, "Scene files").
    #[arg(long, conflicts_with = "preset")]
    pub scene: Option<PathBuf>,
    /// Generate a standard scene instead: paper, uniform or sphere.
    #[arg(long)]
    pub preset: Option<String>,
    /// Lights in the generated scene [default: 1000].
    #[arg(long, value_parser = super::light_count, requires = "preset")]
    pub lights: Option<usize>,
    /// Seed of the generated scene [default: 1].
    #[arg(long, requires = "preset")]
    pub seed: Option<u64>,
}

impl SceneSource {
    /// Loads or generates the scene. Invalid lights in a file are skipped and reported on stderr.
    pub fn load(&self) -> Result<(Scene, String)> {
        match (&self.scene, &self.preset) {
            (Some(path), _) => {
                // clap does not enforce `requires = "preset"` once `--scene` (which conflicts with
                // `--preset`) is given, so say it here rather than ignore the options.
                ensure!(
                    self.lights.is_none() && self.seed.is_none(),
                    "--lights and --seed only apply to --preset, not to --scene {}",
                    path.display()
                );
                let scene = Scene::load(path, LightPolicy::SkipInvalid)?;
                report_skipped(path, &scene);
                check_memory(&scene.grid, scene.lights.len())
                    .with_context(|| format!("{}: grid too large here", path.display()))?;
                Ok((scene, path.display().to_string()))
            }
            (None, Some(name)) => {
                let preset = parse_preset(name)?;
                let (lights, seed) = (self.lights.unwrap_or(1000), self.seed.unwrap_or(1));
                check_memory(&preset.view().1, lights)
                    .with_context(|| format!("--preset {name} --lights {lights}"))?;
                Ok((
                    preset.generate(lights, seed),
                    format!("preset {} ({lights} lights, seed {seed})", preset.name()),
                ))
            }
            (None, None) => bail!("give a scene: --scene FILE or --preset paper|uniform|sphere"),
        }
    }
}

/// Parses a preset name with a helpful error.
pub fn parse_preset(name: &str) -> Result<Preset> {
    Preset::from_name(name).with_context(|| {
        let names: Vec<_> = Preset::ALL.iter().map(|p| p.name()).collect();
        format!(
            "unknown preset {name:?}; expected one of {}",
            names.join(", ")
        )
    })
}

/// Says on stderr how many lights of the file at `path` were invalid and left out.
pub fn report_skipped(path: &Path, scene: &Scene) {
    if scene.skipped.is_empty() {
        return;
    }
    eprintln!(
        "warning: {}: {} invalid light(s) skipped:",
        path.display(),
        scene.skipped.len()
    );
    for s in scene.skipped.iter().take(10) {
        eprintln!("  {s}");
    }
    if scene.skipped.len() > 10 {
        eprintln!("  … and {} more", scene.skipped.len() - 10);
    }
}

/// Loads a glTF model and says on stderr what the loader changed or left out (`Model::warnings`:
/// clamped material factors, lights without a usable radius, …), so `render`, `scene`, `paper`
/// and `skips` lose nothing silently. `info` lists the warnings itself.
///
/// Refuses when one of the command's `outputs` is one of the model's files (`Model::files`):
/// the glTF file was checked before the load, but its external buffers and images were not,
/// and `render --out` replaced a `.gltf`'s buffer named `heatmap.png` with the heat map
/// (hostile-input hunt, session 38). Checked here, before any work on the model.
pub fn load_model(path: &Path, options: &LoadOptions, outputs: &[&Path]) -> Result<Model> {
    let model = Model::load(path, options)?;
    let files: Vec<&Path> = model.files.iter().map(PathBuf::as_path).collect();
    for output in outputs {
        super::outputs::refuse_overwriting_model_files(output, path, &files)?;
    }
    for w in &model.warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    Ok(model)
}

/// Says on stderr what a model's scene (`RenderScene::from_model` with `camera` and `lights`)
/// leaves out, so no command drops part of a model silently: the model's own lights past
/// `--lights`, and a first camera that is orthographic (the scene then shows a view down the
/// bounds' long axis; `scene` names that view in its summary line instead).
pub fn note_model_scene(model: &Model, name: &str, camera: Option<&str>, lights: usize) {
    if lights < model.lights.len() {
        eprintln!(
            "note: {name}: {lights} lights keep only the first {lights} of the model's {} own \
             lights",
            model.lights.len()
        );
    }
    if camera.is_none()
        && let Some(first) = model.cameras.first()
        && model.camera(0, 1, 1).is_none()
    {
        eprintln!(
            "note: {name}: its first camera {:?} is orthographic; showing a view down the bounds' \
             long axis instead (--camera NAME picks a perspective one)",
            first.name
        );
    }
}

/// The default scene (`RenderScene::default_scene`: the atrium, seed 1) with `lights` lights at
/// `width × height`, after [`note_model_scene`]'s notes; the atrium is generated once.
pub fn noted_default_scene(lights: usize, width: u32, height: u32) -> Result<RenderScene> {
    let atrium = myriad::scene::atrium();
    let name = "default scene (atrium)";
    note_model_scene(&atrium, name, None, lights);
    RenderScene::from_model(&atrium, name, None, lights, 1, width, height)
}

/// The most worker threads `--threads` may ask for (more only costs memory and start-up).
const MAX_THREADS: usize = 1024;

/// A rayon pool with `threads` threads (0 = one per core).
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool> {
    ensure!(
        threads <= MAX_THREADS,
        "--threads {threads}: at most {MAX_THREADS} worker threads"
    );
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(worker_name)
        .build()
        // rayon's error prints its io::Error and also returns it as its source: one copy only.
        .map_err(|e| match threads {
            0 => anyhow::anyhow!("cannot start the worker threads: {e}"),
            n => anyhow::anyhow!("cannot start {n} worker threads: {e}"),
        })
}

/// Names the threads of rayon's global pool, which the commands without `--threads` use (and
/// starts them: the pool is otherwise built on first use, unnamed). A named thread is told apart
/// in Tracy, a debugger or `top`; unnamed, every one is "myriad".
pub fn name_worker_threads() {
    // Fails only when the global pool already exists (it does not before `main`'s first use),
    // and then the threads merely keep their names.
    let _ = rayon::ThreadPoolBuilder::new()
        .thread_name(worker_name)
        .build_global();
}

/// A rayon worker's thread name (short: Linux keeps 15 bytes of it).
fn worker_name(index: usize) -> String {
    format!("rayon {index}")
}

/// Bytes per light an assignment of a scene file's lights needs at the least: its columns and
/// records. (`myriad assign` of `sphere` scenes, 9 lights in 10 culled, peaked 155 bytes a light
/// more from 0.5M to 2M lights.)
pub const ASSIGNED_BYTES_PER_LIGHT: u64 = 64;

/// Bytes per light the commands that generate, assign and render their lights (`frames`,
/// `stress`, `render`, `skips`, `report`) need at the least: the generated columns (52 bytes),
/// the assigner's per-light scratch (~40), and the 48-byte GPU record three times over (the
/// renderer's staging copy, the staging ring, the buffer — host memory on llvmpipe), before a
/// single pair. Measured peaks are higher still (VmHWM 2026-11-28: `stress` +532 bytes a light
/// from 250k to 1M lights, `frames` +1,141); 64 bytes a light let a 10M-light `stress` pass
/// the check under a 1.5 GB cap and abort in its allocator (audit).
pub const GENERATED_BYTES_PER_LIGHT: u64 = 256;

/// Bytes a frame of a `dims` grid takes per cluster before a single pair, with room: the CSR
/// `offsets` and `counts`, the assigner's per-cluster scratch, the dump's copy and its JSON text
/// (`assign`), the oracle's lists beside each method's (`bench`). Measured peaks (`/usr/bin/time`,
/// 2 lights, 5 M clusters): `assign` 21 bytes a cluster on a 500×100×100 grid, `bench` 40, `check`
/// 20. 16 bytes let a 1e9×1×1 grid pass the check and take 24 GB before the OS killed it, and a
/// 2e8×1×1 grid abort in the allocator under a 6 GB cap (hostile-input audit).
pub const BYTES_PER_CLUSTER: u64 = 48;

/// Bytes a grid takes per plane of each axis, with room: edges, plane sets and their text. On a
/// grid long in one axis they dominate: 5e6×1×1 measured 52 bytes a cluster for `assign` and
/// 64 for `bench`, 1×1×5e6 41 and 47.
pub const BYTES_PER_AXIS_PLANE: u64 = 32;

/// Bytes a frame of a `dims` grid with `lights` lights needs before a single pair:
/// [`BYTES_PER_CLUSTER`] and [`BYTES_PER_AXIS_PLANE`] for the grid, per light `bytes_per_light`
/// ([`ASSIGNED_BYTES_PER_LIGHT`], [`GENERATED_BYTES_PER_LIGHT`]).
pub fn minimum_frame_bytes(dims: UVec3, lights: usize, bytes_per_light: u64) -> u64 {
    let clusters = u64::from(dims.x) * u64::from(dims.y) * u64::from(dims.z);
    let planes = u64::from(dims.x) + u64::from(dims.y) + u64::from(dims.z) + 3;
    (BYTES_PER_CLUSTER * clusters)
        .saturating_add(BYTES_PER_AXIS_PLANE * planes)
        .saturating_add(bytes_per_light.saturating_mul(lights as u64))
}

/// Refuses a grid and light count whose minimum frame does not fit in the memory this process
/// may still take ([`memory_limit_bytes`]). Without this, a valid scene file of a few bytes with
/// a 65535×65535 grid makes the process grow until the OS kills it.
pub fn check_memory(grid: &ClusterGrid, lights: usize) -> Result<()> {
    check_memory_needed(
        grid.dims(),
        lights,
        minimum_frame_bytes(grid.dims(), lights, ASSIGNED_BYTES_PER_LIGHT),
    )
}

/// [`check_memory`] before the scene exists, for the commands that generate their lights
/// (`render`, `frames`, `stress`, `skips`, `report`): they check the count they were given
/// against the grid they will use *before* generating, since generating `--lights 4294967295`
/// is itself the allocation that aborts the process (audit: "memory allocation of 17179869132
/// bytes failed"), with [`GENERATED_BYTES_PER_LIGHT`].
pub fn check_memory_for(dims: UVec3, lights: usize) -> Result<()> {
    check_memory_needed(
        dims,
        lights,
        minimum_frame_bytes(dims, lights, GENERATED_BYTES_PER_LIGHT),
    )
}

/// Bytes a rendered pixel takes at the peak, with room: the G-buffer and the target (host memory
/// on a software adapter), the read-backs of the image, the heat map and the depth, and the PNG
/// encoding. Measured: `render --size 16384x16384` peaked at 11.7 GB, 43.6 bytes a pixel, and
/// under an 8 GB cap aborted in its allocator (exit 134, hostile-input audit).
pub const BYTES_PER_PIXEL: u64 = 64;

/// Refuses an image of `width`×`height` whose pixels do not fit in the memory this process may
/// still take, at [`BYTES_PER_PIXEL`], before any of it is allocated.
pub fn check_image_memory(width: u32, height: u32) -> Result<()> {
    // Saturating: a scene file's camera may be 2^32 − 1 pixels a side.
    let needed = BYTES_PER_PIXEL.saturating_mul(u64::from(width) * u64::from(height));
    if let Some(available) = memory_limit_bytes() {
        ensure!(
            needed <= available,
            "a {width}x{height} image needs at least {:.1} GiB ({BYTES_PER_PIXEL} bytes a pixel: \
             the G-buffer, the target and their read-backs), but only {:.1} GiB of memory is \
             available to this process (MemAvailable, or the headroom under its address-space \
             limit); use a smaller --size",
            needed as f64 / (1u64 << 30) as f64,
            available as f64 / (1u64 << 30) as f64
        );
    }
    Ok(())
}

fn check_memory_needed(dims: UVec3, lights: usize, needed: u64) -> Result<()> {
    if let Some(available) = memory_limit_bytes() {
        ensure!(
            needed <= available,
            "a {}x{}x{} grid with {lights} lights needs at least {:.1} GiB, but only {:.1} GiB of \
             memory is available to this process (MemAvailable, or the headroom under its \
             address-space limit)",
            dims.x,
            dims.y,
            dims.z,
            needed as f64 / (1u64 << 30) as f64,
            available as f64 / (1u64 << 30) as f64
        );
    }
    Ok(())
}

/// The memory this process may still take, in bytes: Linux's `MemAvailable`, or less under an
/// address-space cap (`ulimit -v`: the soft limit less what is mapped now), which the check used
/// to ignore — under one, a run the check passed aborted in its allocator with exit 134 instead
/// of failing with 2 (audit). `None` where neither is known (no check then).
pub fn memory_limit_bytes() -> Option<u64> {
    let available = available_memory_bytes();
    let headroom = address_space_headroom_bytes();
    match (available, headroom) {
        (Some(a), Some(h)) => Some(a.min(h)),
        (a, h) => a.or(h),
    }
}

/// `MemAvailable` from `/proc/meminfo`, in bytes.
fn available_memory_bytes() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The soft address-space limit (`/proc/self/limits`, "Max address space") less this process's
/// mapped size (`VmSize` in `/proc/self/status`); `None` when unlimited or unknown.
fn address_space_headroom_bytes() -> Option<u64> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    let soft: u64 = line
        .trim_start_matches("Max address space")
        .split_whitespace()
        .next()?
        .parse()
        .ok()?; // "unlimited" does not parse: no cap.
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let mapped_kib: u64 = status
        .lines()
        .find(|l| l.starts_with("VmSize:"))?
        .split_whitespace()
        .nth(1)?
        .parse()
        .ok()?;
    Some(soft.saturating_sub(mapped_kib * 1024))
}

#[cfg(test)]
mod tests {
    use super::*;
    use myriad::scene::DepthSlicing;

    #[test]
    fn a_grid_beyond_any_memory_is_refused_and_a_normal_one_is_not() {
        let grid = |x, y, z| ClusterGrid::new(UVec3::new(x, y, z), DepthSlicing::Log, 0.1, 100.0);
        // 2^32 - 2^17 + 1 clusters: 192 GiB before a single pair.
        let huge = grid(65_535, 65_535, 1);
        let needed = minimum_frame_bytes(huge.dims(), 10, ASSIGNED_BYTES_PER_LIGHT);
        assert_eq!(needed, 206_156_333_168 + 640);
        match memory_limit_bytes() {
            Some(available) if available < needed => {
                let e = check_memory(&huge, 10).unwrap_err().to_string();
                assert!(
                    e.contains("65535x65535x1") && e.contains("needs at least 192.0 GiB"),
                    "{e}"
                );
            }
            _ => check_memory(&huge, 10).unwrap(),
        }
        // Long in one axis: its planes count too. A 1e9×1×1 grid needs 80 GB (it took 24 GB
        // before the OS killed it, past a check that asked for 16).
        let long = UVec3::new(1_000_000_000, 1, 1);
        assert_eq!(
            minimum_frame_bytes(long, 2, ASSIGNED_BYTES_PER_LIGHT),
            80_000_000_288
        );
        // Measured peaks (`/usr/bin/time`, 5 M clusters) stay under the estimate: `bench` on
        // 5e6×1×1 took 321,576 KiB, `assign` 262,144; on 1×1×5e6 236,988 and 209,180.
        for dims in [UVec3::new(5_000_000, 1, 1), UVec3::new(1, 1, 5_000_000)] {
            assert!(minimum_frame_bytes(dims, 2, ASSIGNED_BYTES_PER_LIGHT) >= 321_576 * 1024);
        }
        check_memory(&grid(32, 18, 48), 100_000).unwrap();
        // A light count alone, before any grid or light exists (`frames`, `stress`, `render`):
        // u32::MAX lights need 1 TiB.
        let lights = u32::MAX as usize;
        let dims = UVec3::new(24, 12, 16);
        let needed = minimum_frame_bytes(dims, lights, GENERATED_BYTES_PER_LIGHT);
        assert_eq!(needed, 221_184 + 1_760 + 256 * u64::from(u32::MAX));
        if memory_limit_bytes().is_some_and(|a| a < needed) {
            let e = check_memory_for(dims, lights).unwrap_err();
            assert!(e.to_string().contains("needs at least 1024.0 GiB"), "{e}");
        }
    }

    #[test]
    fn an_image_of_any_camera_size_is_checked_without_overflow() {
        // A scene file's camera may be u32::MAX pixels a side: 64 · w · h overflows u64, and
        // wrapped it could pass. Saturated, it is refused wherever the memory is known.
        if memory_limit_bytes().is_some() {
            let e = check_image_memory(u32::MAX, u32::MAX)
                .unwrap_err()
                .to_string();
            // Saturated at u64::MAX bytes: 2^34 GiB.
            assert!(
                e.contains("a 4294967295x4294967295 image needs at least 17179869184.0 GiB"),
                "{e}"
            );
            // 2^31 a side wraps to exactly 0 unsaturated.
            check_image_memory(1 << 31, 1 << 31).unwrap_err();
        }
        check_image_memory(1536, 768).unwrap();
    }

    #[test]
    fn the_memory_limit_is_at_most_what_linux_calls_available() {
        // On Linux both figures exist; the limit never exceeds either.
        if let Some(available) = available_memory_bytes() {
            assert!(memory_limit_bytes().unwrap() <= available);
        }
        if let Some(headroom) = address_space_headroom_bytes() {
            assert!(memory_limit_bytes().unwrap() <= headroom);
        }
    }

    /// This process's mapped size (`VmSize`), in bytes.
    #[cfg(target_os = "linux")]
    fn mapped_bytes() -> u64 {
        let status = std::fs::read_to_string("/proc/self/status").unwrap();
        let line = status.lines().find(|l| l.starts_with("VmSize:")).unwrap();
        let kib: u64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
        kib * 1024
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn the_headroom_under_an_address_space_cap_leaves_out_what_is_mapped() {
        // Run again under `ulimit -v` (this process has no cap to measure): the headroom is
        // the cap less what is mapped now, in bytes. With the cap alone, a run the check passed
        // aborted in its allocator (audit).
        const CAP_KIB: u64 = 4_000_000;
        const CHILD: &str = "MYRIAD_TEST_UNDER_ADDRESS_SPACE_CAP";
        let name = "the_headroom_under_an_address_space_cap_leaves_out_what_is_mapped";
        if std::env::var_os(CHILD).is_some() {
            let cap = CAP_KIB * 1024;
            let before = mapped_bytes();
            let headroom = address_space_headroom_bytes().expect("a cap is set");
            let after = mapped_bytes();
            // What is mapped is tens of megabytes at the least (code, stacks, the allocator's
            // arenas); a megabyte of slack for what the reads themselves map.
            let slack = 1 << 20;
            assert!(
                headroom + slack >= cap - after && headroom <= cap - before + slack,
                "headroom {headroom} under a {cap}-byte cap with {before}..{after} bytes mapped"
            );
            assert!(memory_limit_bytes().unwrap() <= headroom);
            return;
        }
        let test = format!("{}::{name}", module_path!().split_once("::").unwrap().1);
        let out = std::process::Command::new("sh")
            .args(["-c", &format!(r#"ulimit -v {CAP_KIB} && exec "$0" "$@""#)])
            .arg(std::env::current_exe().unwrap())
            .args(["--exact", &test, "--test-threads", "1"])
            .env(CHILD, "1")
            .output()
            .unwrap();
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(out.status.success(), "{text}");
        assert!(
            text.contains("1 passed"),
            "the test did not run capped:\n{text}"
        );
    }

    #[test]
    fn thread_counts_are_bounded() {
        let e = thread_pool(MAX_THREADS + 1).unwrap_err().to_string();
        assert!(e.contains("at most 1024"), "{e}");
        assert_eq!(thread_pool(2).unwrap().current_num_threads(), 2);
    }
}
