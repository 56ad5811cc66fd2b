//! `myriad bench`: the time-against-error table, with the thread link measured around it.

use super::assign::parse_method;
use super::list_options::refuse_repeats;
use super::oracle_check::independent_lists;
use super::pair_budget::{COMPARE_BYTES_PER_PAIR, PairBudget};
use super::source::{SceneSource, thread_pool};
use anyhow::{Context, Result};
use myriad::assignment::{Method, OutsideCalls, Parallelism};
use myriad::core_link::{self, CoreLink, HANDOFF_BYTES};
use myriad::evaluate::{Idle, MethodResult, Timing, measure};
use myriad::scene::Scene;
use serde::Serialize;
use std::process::ExitCode;
use std::time::Duration;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    source: SceneSource,
    /// Comma-separated methods (default: all).
    #[arg(long, value_delimiter = ',')]
    methods: Vec<String>,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Timed runs per method (the median is reported), 1 to 1 000 000.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000), default_value_t = 21)]
    runs: u32,
    /// Wait this many microseconds before each timed call, as an engine's frames are apart (the
    /// pool's workers fall asleep in between; 0 = calls back to back). The thread sleeps, unless
    /// --busy.
    /// At most 1 000 000 (a second).
    #[arg(long, value_parser = clap::value_parser!(u64).range(..=1_000_000), default_value_t = 0)]
    idle_us: u64,
    /// Spin through --idle-us instead of sleeping: the calling thread stays busy, as an engine's
    /// frame thread doing other work.
    #[arg(long, requires = "idle_us")]
    busy: bool,
    /// Run every frame split into tasks on the pool, never paced onto the calling thread.
    #[arg(long)]
    always_parallel: bool,
    /// Where the timed calls come from: a pool worker, as a frame job runs (`worker`); or this
    /// process's main thread, outside any pool, as an engine's main thread calls, working beside
    /// helper jobs on rayon's global pool (`outside`, the assigner's default) or handing each
    /// frame to it (`hand-off`). From outside, the global pool has one thread per core unless
    /// the environment's RAYON_NUM_THREADS says otherwise, and --threads must be 0 or that count.
    #[arg(long, value_enum, default_value_t = Caller::Worker)]
    caller: Caller,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
}

/// `--caller`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
enum Caller {
    Worker,
    Outside,
    HandOff,
}

#[derive(Serialize)]
struct Report {
    scene: String,
    /// The lights timed: the file's valid ones.
    lights: usize,
    /// Invalid lights in the scene file, skipped when it was loaded (and listed on stderr).
    lights_skipped: usize,
    grid: [u32; 3],
    threads: usize,
    /// Where the timed calls came from (`--caller`).
    caller: Caller,
    /// The pool's thread-to-thread link just before and just after the timings (absent on one
    /// thread): a parallel timing means little without it on a shared machine.
    core_link: Option<LinkBeforeAfter>,
    methods: Vec<MethodResult>,
}

#[derive(Serialize)]
struct LinkBeforeAfter {
    before: CoreLink,
    after: CoreLink,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let methods = if args.methods.is_empty() {
        Method::ALL.to_vec()
    } else {
        let methods: Vec<Method> = args
            .methods
            .iter()
            .map(|m| parse_method(m))
            .collect::<Result<_>>()?;
        refuse_repeats("--methods", &methods, |m| m.name().to_string())?;
        methods
    };
    let (scene, name) = args.source.load()?;
    let time = Duration::from_micros(args.idle_us);
    let idle = match (args.idle_us, args.busy) {
        (0, _) => Idle::None,
        (_, false) => Idle::Sleep(time),
        (_, true) => Idle::Busy(time),
    };
    let parallelism = if args.always_parallel {
        Parallelism::Always
    } else {
        Parallelism::Paced
    };
    let timing = Timing {
        runs: args.runs as usize,
        idle,
        parallelism,
        outside_calls: match args.caller {
            Caller::HandOff => OutsideCalls::HandOff,
            Caller::Worker | Caller::Outside => OutsideCalls::Join,
        },
    };
    let report = bench(&scene, name, &methods, args.threads, args.caller, timing)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_table(&report);
    }
    Ok(exit_code(&report))
}

fn bench(
    scene: &Scene,
    name: String,
    methods: &[Method],
    threads: usize,
    caller: Caller,
    timing: Timing,
) -> Result<Report> {
    let input = myriad::light_input(&scene.lights);
    // Every method's lists must fit the memory beside the oracle's: past it, a clear error.
    let budget = PairBudget::new(None, COMPARE_BYTES_PER_PAIR);
    let run = || {
        // The reference shares no code with the assignment but the f64 oracle.
        let exact = independent_lists(&scene.lights, &scene.camera, &scene.grid, &budget)?;
        let before = core_link::measure();
        let methods = methods
            .iter()
            .map(|&m| {
                // The oracle-backed method is slow on big scenes: fewer runs.
                let runs = if matches!(m, Method::Exact) {
                    timing.runs.min(3)
                } else {
                    timing.runs
                };
                let timing = Timing { runs, ..timing };
                let pairs = budget.pairs;
                measure(m, &input, &scene.camera, &scene.grid, &exact, timing, pairs)
                    .with_context(|| format!("the pair budget is {}", budget.describe()))
            })
            .collect::<Result<_>>()?;
        let core_link = before
            .zip(core_link::measure())
            .map(|(before, after)| LinkBeforeAfter { before, after });
        let d = scene.grid.dims();
        Ok(Report {
            scene: name,
            lights: scene.lights.len(),
            lights_skipped: scene.skipped.len(),
            grid: [d.x, d.y, d.z],
            threads: rayon::current_num_threads(),
            caller,
            core_link,
            methods,
        })
    };
    if caller == Caller::Worker {
        return thread_pool(threads)?.install(run);
    }
    // From this thread, outside any pool: the assigner uses rayon's global pool, built (and its
    // threads named) when the program started.
    let global = rayon::current_num_threads();
    anyhow::ensure!(
        threads == 0 || threads == global,
        "--threads {threads} with --caller {}: calls from outside a pool use rayon's global \
         pool, which has {global} threads here; set RAYON_NUM_THREADS={threads} instead",
        clap::ValueEnum::to_possible_value(&caller)
            .map_or_else(String::new, |v| v.get_name().to_string())
    );
    run()
}

fn print_table(report: &Report) {
    let [x, y, z] = report.grid;
    let skipped = match report.lights_skipped {
        0 => String::new(),
        n => format!(" (and {n} invalid, skipped)"),
    };
    println!(
        "{} — {} lights{skipped}, grid {x}x{y}x{z}, {} threads{}",
        report.scene,
        report.lights,
        report.threads,
        match report.caller {
            Caller::Worker => "",
            Caller::Outside => ", called from outside the pool",
            Caller::HandOff => ", called from outside the pool, each frame handed off",
        }
    );
    if let Some(LinkBeforeAfter { before, after }) = &report.core_link {
        println!(
            "thread link: round trip {:.0} / {:.0} ns, {} KiB hand-off {:.1} / {:.1} µs (before / after)",
            before.round_trip_ns,
            after.round_trip_ns,
            HANDOFF_BYTES / 1024,
            before.handoff_us,
            after.handoff_us
        );
    }
    println!(
        "{:<8} {:>12} {:>12} {:>10} {:>9} {:>7} {:>11} {:>8} {:>11}",
        "method", "median µs", "min µs", "pairs", "fp ratio", "misses", "bytes", "GB/s", "on pool"
    );
    for m in &report.methods {
        println!(
            "{:<8} {:>12.1} {:>12.1} {:>10} {:>9.4} {:>7} {:>11} {:>8.2} {:>11}",
            m.method,
            m.median_us,
            m.min_us,
            m.pairs,
            m.false_positive_ratio,
            m.misses,
            m.bytes,
            m.effective_gb_s,
            format!("{}/{}", m.pooled_runs, m.runs)
        );
    }
    if let Some(linear) = report.methods.iter().find(|m| m.method == "linear") {
        for m in report
            .methods
            .iter()
            .filter(|m| m.method == "binary" || m.method == "refined")
        {
            // On a few lights the split methods' fixed costs can lose to `linear`: say so
            // (a 3-light scene printed "binary is 0.5x faster", audit).
            let speedup = linear.median_us / m.median_us;
            if speedup >= 1.0 {
                println!("{} is {speedup:.1}x faster than linear", m.method);
            } else {
                println!("{} is {:.1}x slower than linear", m.method, 1.0 / speedup);
            }
        }
    }
}

fn exit_code(report: &Report) -> ExitCode {
    if report.methods.iter().any(|m| m.misses > 0) {
        eprintln!("error: a method missed lights the oracle says touch a cluster");
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(misses: &[u64]) -> Report {
        Report {
            scene: "test".into(),
            lights: 1,
            lights_skipped: 0,
            grid: [1, 1, 1],
            threads: 1,
            caller: Caller::Worker,
            core_link: None,
            methods: misses
                .iter()
                .map(|&misses| MethodResult {
                    method: "binary".into(),
                    median_us: 1.0,
                    min_us: 1.0,
                    runs: 1,
                    pairs: 1,
                    false_positive_ratio: 0.0,
                    misses,
                    bytes: 12,
                    effective_gb_s: 0.0,
                    visible_lights: 1,
                    pooled_runs: 0,
                })
                .collect(),
        }
    }

    /// Any method that misses a pair fails the run (no method here can be made to miss from the
    /// command line: they are all right).
    #[test]
    fn a_method_with_a_miss_fails_the_run() {
        assert_eq!(exit_code(&report(&[0, 0])), ExitCode::SUCCESS);
        assert_eq!(exit_code(&report(&[0, 1])), ExitCode::FAILURE);
        assert_eq!(exit_code(&report(&[2])), ExitCode::FAILURE);
    }
}
