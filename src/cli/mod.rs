//! Subcommands of the `myriad` tool, one file each.

mod assign;
mod bench;
mod check;
mod scene;
mod source;
mod validate;

use anyhow::Result;
use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Clustered shading with very many lights: scene files, light assignment, accuracy and speed.
#[derive(Parser, Debug)]
#[command(name = "myriad", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Check a scene file and list every problem in it.
    Validate(validate::Args),
    /// Write a standard benchmark scene (paper, uniform, sphere) as a scene file.
    Scene(scene::Args),
    /// Assign a scene's lights to clusters and write the assignment dump.
    Assign(assign::Args),
    /// Verify an assignment dump against the exact oracle.
    Check(check::Args),
    /// Time every method on a scene and report time against error.
    Bench(bench::Args),
}

/// Runs the parsed command line; `Ok` carries the exit code (non-zero when a check failed).
pub fn run(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Some(Command::Validate(args)) => validate::run(args),
        Some(Command::Scene(args)) => scene::run(args),
        Some(Command::Assign(args)) => assign::run(args),
        Some(Command::Check(args)) => check::run(args),
        Some(Command::Bench(args)) => bench::run(args),
        None => bench::main_job(),
    }
}
