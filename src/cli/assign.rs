//! `myriad assign --scene S --method M [--threads T] [--bare] --out D`: the assignment dump of a
//! scene.

use super::pair_budget::{ASSIGN_BYTES_PER_PAIR, PairBudget};
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
    /// Write DESIGN.md's seven keys only, without the `scene` record that lets `myriad check`
    /// name a dump of another scene (for readers that know only those keys).
    #[arg(long)]
    bare: bool,
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
    let budget = PairBudget::new(args.pair_budget, ASSIGN_BYTES_PER_PAIR);
    let mut assigner = Assigner::new().with_pair_budget(budget.pairs);
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
    if let Some(warning) = budget.coarsening_warning(&name, &stats, &scene.grid, "the dump") {
        eprintln!("{warning}");
    }
    let dump = AssignmentDump::new(&grid, &lists, &scene.lights.source_index);
    let dump = if args.bare {
        dump
    } else {
        dump.stamped(&scene)
    };
    dump.save(&args.out)?;
    // The lights skipped on load are not among the assigned ones: said apart, so the counts add
    // up (they read "3 lights (3 visible, 0 culled, 1 rejected)" for four).
    let skipped = match scene.skipped.len() {
        0 => String::new(),
        n => format!("; {n} skipped on load"),
    };
    super::outputs::say_written(
        &args.out,
        &format!(
            "{name}: {method} assigned {} lights ({} visible, {} culled, {} rejected{skipped}) -> \
             {} pairs; wrote {}",
            stats.lights,
            stats.visible(),
            stats.culled,
            stats.rejected,
            stats.pairs,
            args.out.display()
        ),
    );
    Ok(ExitCode::SUCCESS)
}
