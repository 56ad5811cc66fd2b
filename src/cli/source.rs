//! Where a command's scene comes from: a scene file or a generated preset; and thread pools.

use anyhow::{Context, Result, bail, ensure};
use myriad::scene::{LightPolicy, Preset, Scene};
use std::path::PathBuf;

/// `--scene FILE` or `--preset P [--lights N] [--seed K]`.
#[derive(clap::Args, Debug)]
pub struct SceneSource {
    /// Scene file (JSON, see DESIGN.md).
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
                report_skipped(&scene);
                Ok((scene, path.display().to_string()))
            }
            (None, Some(name)) => {
                let preset = parse_preset(name)?;
                let (lights, seed) = (self.lights.unwrap_or(1000), self.seed.unwrap_or(1));
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

/// Says on stderr how many lights of a file were invalid and left out.
pub fn report_skipped(scene: &Scene) {
    if scene.skipped.is_empty() {
        return;
    }
    eprintln!("warning: {} invalid light(s) skipped:", scene.skipped.len());
    for s in scene.skipped.iter().take(10) {
        eprintln!("  {s}");
    }
    if scene.skipped.len() > 10 {
        eprintln!("  … and {} more", scene.skipped.len() - 10);
    }
}

/// A rayon pool with `threads` threads (0 = one per core).
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        // rayon's error prints its io::Error and also returns it as its source: one copy only.
        .map_err(|e| match threads {
            0 => anyhow::anyhow!("cannot start the worker threads: {e}"),
            n => anyhow::anyhow!("cannot start {n} worker threads: {e}"),
        })
}
