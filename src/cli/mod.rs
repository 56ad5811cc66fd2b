//! Subcommands of the `myriad` tool, one file each.

mod assign;
mod atrium;
mod bench;
mod check;
mod frames;
mod grid_options;
mod info;
mod list_options;
mod oracle_check;
mod outputs;
mod pair_budget;
mod paper;
mod progress;
mod render;
mod render_skipping;
mod report;
mod scene;
mod skips;
mod source;
mod stress;
mod validate;

pub use source::name_worker_threads;

use anyhow::Result;
use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Clustered shading with very many lights: scene files, light assignment, accuracy and speed.
#[derive(Parser, Debug)]
#[command(
    name = "myriad",
    version,
    about,
    after_help = "Without a command: the main job, `myriad render` with its defaults (the default scene, 1000 lights, 1536x768, into out/)."
)]
pub struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Check a scene file and list every problem in it.
    Validate(validate::Args),
    /// Write a scene file: a standard preset, or a light field placed in a glTF model.
    Scene(scene::Args),
    /// Describe a glTF file: meshes, instances, triangles, materials, lights, cameras, bounds.
    Info(info::Args),
    /// Write the generated default scene (the atrium) as a .glb file.
    Atrium(atrium::Args),
    /// Assign a scene's lights to clusters and write the assignment dump.
    Assign(assign::Args),
    /// Verify an assignment dump against the exact oracle.
    Check(check::Args),
    /// Time every method on a scene and report time against error.
    Bench(bench::Args),
    /// Run the frame loop sequentially and pipelined; per-stage times.
    Frames(frames::Args),
    /// Measure each saving of "skip what the scene does not need", before and after.
    Skips(skips::Args),
    /// The time-against-error study: every method × standard scene × grid; table, JSON, plot.
    Report(report::Args),
    /// One frame with very many lights: every stage timed, the lists checked against the oracle.
    Stress(stress::Args),
    /// Render a scene headless (clustered, tiled, brute force): image, heat map, numbers.
    Render(render::Args),
    /// Reproduce the paper's Tables 1 and 2 (10 and 1000 lights, three grids and brute force) and
    /// its Figure 4 heat map, next to the paper's numbers.
    Paper(paper::Args),
}

/// Runs the parsed command line; `Ok` carries the exit code (non-zero when a check failed).
pub fn run(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Some(Command::Validate(args)) => validate::run(args),
        Some(Command::Scene(args)) => scene::run(args),
        Some(Command::Info(args)) => info::run(args),
        Some(Command::Atrium(args)) => atrium::run(args),
        Some(Command::Assign(args)) => assign::run(args),
        Some(Command::Check(args)) => check::run(args),
        Some(Command::Bench(args)) => bench::run(args),
        Some(Command::Render(args)) => render::run(args),
        Some(Command::Report(args)) => report::run(args),
        Some(Command::Frames(args)) => frames::run(args),
        Some(Command::Skips(args)) => skips::run(args),
        Some(Command::Paper(args)) => paper::run(args),
        Some(Command::Stress(args)) => stress::run(args),
        None => render::main_job(),
    }
}

/// The most timed runs a command takes, as `bench --runs` (each run's time is kept for the
/// median, and the list is sized up front: `report --runs 4294967296` asked for 32 GiB and
/// aborted, audit).
const MAX_RUNS: usize = 1_000_000;

/// Parses a count of timed runs: at least 1 (a median of nothing is not a timing), at most
/// [`MAX_RUNS`].
fn run_count(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(0) => Err("must be at least 1".into()),
        Ok(n) if n > MAX_RUNS => Err(format!("at most {MAX_RUNS}, got {n}")),
        Ok(n) => Ok(n),
        Err(e) => Err(e.to_string()),
    }
}

/// Parses a light count: light indices are u32, so at most `u32::MAX` lights.
fn light_count(text: &str) -> Result<usize, String> {
    let n: usize = text
        .parse()
        .map_err(|e: std::num::ParseIntError| e.to_string())?;
    if n > u32::MAX as usize {
        return Err(format!(
            "light indices are u32, so at most {} lights",
            u32::MAX
        ));
    }
    Ok(n)
}

#[cfg(test)]
mod count_tests {
    #[test]
    fn counts_are_range_checked() {
        assert_eq!(super::run_count("3"), Ok(3));
        assert!(super::run_count("0").unwrap_err().contains("at least 1"));
        assert!(super::run_count("-1").is_err());
        assert_eq!(super::run_count("1000000"), Ok(1_000_000));
        assert!(
            super::run_count("4294967296")
                .unwrap_err()
                .contains("at most 1000000, got 4294967296")
        );
        assert_eq!(super::light_count("0"), Ok(0));
        assert_eq!(super::light_count("4294967295"), Ok(u32::MAX as usize));
        assert!(
            super::light_count("4294967296")
                .unwrap_err()
                .contains("u32")
        );
        assert!(super::light_count("18446744073709551615").is_err());
    }
}
