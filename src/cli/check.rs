//! `myriad check --scene S --dump D [--json]`: a dump against the exact oracle.

use super::source::SceneSource;
use anyhow::{Context, Result};
use myriad::assignment::{Assigner, LightLists, Method};
use myriad::dump::AssignmentDump;
use myriad::evaluate::compare;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    source: SceneSource,
    /// The dump written by `myriad assign`.
    #[arg(long)]
    dump: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let (scene, name) = args.source.load()?;
    let dump = AssignmentDump::load(&args.dump)?;
    // Indices refer to the scene file's lights, skipped invalid ones included.
    let file_lights = scene.lights.len() + scene.skipped.len();
    dump.check_against(&scene.grid, file_lights)
        .with_context(|| format!("{} does not match {name}", args.dump.display()))?;
    let mut exact = LightLists::new();
    Assigner::new().assign(
        Method::Exact,
        &myriad::light_input(&scene.lights),
        &scene.camera,
        &scene.grid,
        &mut exact,
    );
    // The dump refers to scene-file indices; so must the reference.
    for l in &mut exact.indices {
        *l = scene.lights.source_index[*l as usize];
    }
    let cmp = compare(&dump.lists(), &exact);
    if args.json {
        println!("{}", serde_json::to_string(&cmp)?);
    } else {
        println!("{name} vs {}:", args.dump.display());
        println!("  exact pairs           {}", cmp.exact_pairs);
        println!("  reported pairs        {}", cmp.reported_pairs);
        println!("  misses                {}", cmp.misses);
        println!("  false positives       {}", cmp.false_positives);
        println!("  false-positive ratio  {:.4}", cmp.false_positive_ratio);
    }
    Ok(if cmp.misses == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
