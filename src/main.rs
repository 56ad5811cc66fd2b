//! The `myriad` command-line tool. Run without arguments for the main job; `myriad --help` lists
//! the subcommands.

#![deny(unsafe_code)]

mod cli;

use clap::Parser;
use std::io::Write;
use std::process::ExitCode;

fn main() -> ExitCode {
    exit_2_on_closed_stdout();
    // First in, last out: the session shuts the Tracy client down when `main` returns, by any
    // path (the reason arguments are parsed with `try_parse`: clap's own exit would skip it).
    // SAFETY: bound first, so dropped last, after every other value of `main`; by then every
    // command has returned and the threads it used are idle (scoped, joined, or rayon's
    // workers waiting for work), so nothing records after the shutdown.
    #[allow(unsafe_code)]
    let _profiler = unsafe { myriad::profiling::start() };
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

/// A write to a closed stdout (`myriad check … | true`; `| head -1` only when a write comes after
/// `head` has exited) is a run that could not finish:
/// exit 2 with one line, as an unwritable `--out` does. `println!` panics there, with std's
/// "failed printing to stdout: …", which exited 101 with a backtrace from `check`, `info`,
/// `bench` and `stress` (audit). Every other panic goes to the default hook.
fn exit_2_on_closed_stdout() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        // (`PanicHookInfo::payload_as_str` would do, from Rust 1.91: newer than the MSRV.)
        let payload = info.payload();
        let message = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied());
        if let Some(problem) =
            message.and_then(|message| message.strip_prefix("failed printing to stdout: "))
        {
            // stderr may be closed too: nothing more to say then.
            let _ = writeln!(
                std::io::stderr(),
                "error: cannot write to stdout: {problem}"
            );
            std::process::exit(2);
        }
        default(info);
    }));
}
