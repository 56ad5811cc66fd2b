//! `myriad assign --scene S --method M [--threads T] --out D`: the assignment dump of a scene.

use super::source::{SceneSource, thread_pool};
use anyhow::{Context, Result};
use myriad::assignment::{Assigner, LightLists, Method};
use myriad::dump::AssignmentDump;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    source: SceneSource,
    /// exact, linear, binary, refined or cone.
    #[arg(long, default_value = "refined")]
    method: String,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Output dump file (JSON).
    #[arg(long)]
    out: PathBuf,
    /// Most cluster–light pairs the lists may hold; past it the grid is halved until they fit
    /// (no light is dropped). The dump then records the coarser grid. Default: what u32 offsets
    /// hold, or fewer where the memory this process may take holds fewer (24 bytes a pair).
    #[arg(long)]
    pair_budget: Option<u64>,
}

/// What a pair costs `assign` at its peak: the lists' index, the dump's copy of it and the JSON
/// text, with room. A stress audit measured 12.5 GB (`refined`) and 16.7 GB (`linear`, whose
/// per-cluster lists come first) for 921.6 M pairs, 13.6 and 18.1 bytes a pair: under the
/// default budget of what u32 offsets hold such a scene aborted in the allocator (exit 134)
/// where memory was short, instead of coarsening its grid.
const PEAK_BYTES_PER_PAIR: u64 = 24;

/// `--pair-budget`, or the default: what u32 offsets hold, capped by the memory available.
fn pair_budget(requested: Option<u64>) -> Option<u64> {
    requested.or_else(|| {
        let memory = super::source::memory_limit_bytes()?;
        Some((memory / PEAK_BYTES_PER_PAIR).min(u64::from(u32::MAX)))
    })
}

/// Parses a method name with a helpful error.
pub fn parse_method(name: &str) -> Result<Method> {
    Method::from_name(name).with_context(|| {
        let names: Vec<_> = Method::ALL.iter().map(|m| m.name()).collect();
        format!(
            "unknown method {name:?}; expected one of {}",
            names.join(", ")
        )
    })
}

pub fn run(args: Args) -> Result<ExitCode> {
    let method = parse_method(&args.method)?;
    if let Some(input) = &args.source.scene {
        super::outputs::refuse_overwriting_inputs(&args.out, &[input])?;
    }
    let (scene, name) = args.source.load()?;
    let pool = thread_pool(args.threads)?;
    let mut lists = LightLists::new();
    let mut assigner = Assigner::new();
    let budget = pair_budget(args.pair_budget);
    if let Some(pairs) = budget {
        assigner = assigner.with_pair_budget(pairs);
    }
    let stats = pool.install(|| {
        assigner.assign(
            method,
            &myriad::light_input(&scene.lights),
            &scene.camera,
            &scene.grid,
            &mut lists,
        )
    });
    // The dump describes the grid the lists belong to, which the budget may have coarsened.
    let grid = stats.grid_built(&scene.grid);
    if stats.coarsened > 0 {
        let (want, got) = (scene.grid.dims(), grid.dims());
        eprintln!(
            "warning: {name}: the pairs exceed the budget{} on the {}x{}x{} grid; the lists were built on the coarser {}x{}x{} grid, which the dump records{}",
            match (args.pair_budget, budget) {
                (None, Some(pairs)) if pairs < u64::from(u32::MAX) => format!(
                    " ({pairs} pairs: what the memory available holds at {PEAK_BYTES_PER_PAIR} \
                     bytes a pair; --pair-budget sets it)"
                ),
                _ => String::new(),
            },
            want.x,
            want.y,
            want.z,
            got.x,
            got.y,
            got.z,
            if stats.over_budget {
                " (still over the budget: every visible light in one cluster)"
            } else {
                ""
            }
        );
    }
    AssignmentDump::new(&grid, &lists, &scene.lights.source_index).save(&args.out)?;
    println!(
        "{name}: {method} assigned {} lights ({} visible, {} culled, {} rejected) -> {} pairs; wrote {}",
        stats.lights,
        stats.visible(),
        stats.culled,
        stats.rejected as usize + scene.skipped.len(),
        stats.pairs,
        args.out.display()
    );
    Ok(ExitCode::SUCCESS)
}
