//! The `myriad` command-line tool. Run without arguments for the main job; `myriad --help` lists
//! the subcommands.

mod cli;

use clap::Parser;

fn main() -> std::process::ExitCode {
    myriad::profiling::start();
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(code) => code,
        Err(err) => {
            eprintln!("error: {err:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
