//! `myriad scene --preset P --lights N --seed K --out S`: a reproducible benchmark scene file.

use super::source::parse_preset;
use anyhow::Result;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// paper, uniform or sphere.
    #[arg(long)]
    preset: String,
    /// Number of lights.
    #[arg(long, default_value_t = 1000)]
    lights: usize,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output scene file.
    #[arg(long)]
    out: PathBuf,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let preset = parse_preset(&args.preset)?;
    let scene = preset.generate(args.lights, args.seed);
    scene.save(&args.out)?;
    println!(
        "wrote {} ({} preset, {} lights, seed {})",
        args.out.display(),
        preset.name(),
        args.lights,
        args.seed
    );
    Ok(ExitCode::SUCCESS)
}
