//! The `myriad` command-line tool. Run without arguments for the main job; `myriad --help` lists
//! the subcommands.

mod cli;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    // First in, last out: the session shuts the Tracy client down when `main` returns, by any
    // path (the reason arguments are parsed with `try_parse`: clap's own exit would skip it).
    let _profiler = myriad::profiling::start();
    myriad::profiling::name_this_thread("myriad main");
    cli::name_worker_threads();
    let args = match cli::Cli::try_parse() {
        Ok(args) => args,
        // Help, version or a usage error: printed and exited with as `Cli::parse` would.
        Err(err) => {
            let _ = err.print();
            return ExitCode::from(err.exit_code() as u8);
        }
    };
    // As `diff` and `grep`: 1 is a verdict (a check found a miss, a scene file has problems),
    // 2 is a run that could not finish (bad input, unreadable or unwritable files, no adapter),
    // like clap's usage errors. A script can tell "the lists are wrong" from "the check broke".
    match cli::run(args) {
        Ok(code) => code,
        Err(err) => {
            eprintln!("error: {err:#}");
            ExitCode::from(2)
        }
    }
}
