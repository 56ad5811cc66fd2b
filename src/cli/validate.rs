//! `myriad validate --scene FILE`: every problem of a scene file, one per line.

use anyhow::Result;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The scene file to check.
    #[arg(long)]
    scene: PathBuf,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let report = myriad::scene::validate_file(&args.scene)?;
    println!("{report}");
    Ok(if report.is_valid() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
