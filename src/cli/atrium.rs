//! `myriad atrium --out FILE`: writes the generated default scene (`assets/atrium.glb`).

use anyhow::Result;
use myriad::scene::{ATRIUM_FILE, atrium};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output .glb file (the shipped copy is assets/atrium.glb).
    #[arg(long, default_value = ATRIUM_FILE)]
    out: PathBuf,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let model = atrium();
    model.save_glb(&args.out)?;
    let bytes = std::fs::metadata(&args.out).map(|m| m.len()).unwrap_or(0);
    super::outputs::say_written(
        &args.out,
        &format!(
            "wrote {} ({} bytes: {} meshes, {} instances, {} triangles as rendered, {} cameras, {} \
             lights)",
            args.out.display(),
            bytes,
            model.meshes.len(),
            model.instances.len(),
            model.triangle_count(),
            model.cameras.len(),
            model.lights.len()
        ),
    );
    Ok(ExitCode::SUCCESS)
}
