//! `myriad check --scene S --dump D [--json] [--reference R]`: a dump against the exact oracle.
//!
//! By default every cluster is checked **independently** of the assignment code: its cell
//! against every light in its depth window with the f64 oracle (`oracle_check.rs`). A bug in
//! the cull or plane searches that the `exact` method shares with the fast methods cannot hide
//! from that. `--reference exact-method` compares with the `exact` method's lists instead:
//! the same numbers when both are right, and faster on very large scenes.
//!
//! Exit status: 1 is the verdict "this dump misses a light" (or lists a light skipped on
//! loading); 2 is a dump that cannot be checked against this scene at all — another grid or
//! depth range, a light index past the scene's lights, or a cluster listing a light twice. The
//! last is malformed rather than wrong: the dump format's lists are sets (docs/cli.md), and a
//! list with a repeat cannot be counted in pairs the way the verdict's numbers are. A dump
//! `myriad assign` wrote records its scene (camera, light count, the lights' checksum:
//! [`myriad::dump::SceneStamp`]), so a dump of another view or other lights is also a 2, named;
//! a dump of the bare format records none, and one of another view or other lights on the same
//! grid and depth range is then judged as this scene's.

use super::oracle_check::{self, CheckReport, OracleLights, check_all, check_clusters};
use super::source::SceneSource;
use anyhow::{Context, Result};
use myriad::assignment::{LightLists, coarser_grid};
use myriad::cluster_math::ClusterGrid;
use myriad::dump::AssignmentDump;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    source: SceneSource,
    /// The dump written by `myriad assign`.
    #[arg(long)]
    dump: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// What the dump is compared with: `independent` (every cluster against the f64 oracle,
    /// sharing no code with the assignment) or `exact-method` (the `exact` method's lists).
    #[arg(long, value_enum, default_value_t = Reference::Independent)]
    reference: Reference,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
enum Reference {
    Independent,
    ExactMethod,
}

/// What `check --json` prints.
#[derive(Serialize, Debug)]
struct CheckOutput {
    /// The scene checked against: its file, or the preset it was generated from.
    scene: String,
    /// The dump's file, as given.
    dump: String,
    reference: Reference,
    /// The grid checked: the scene's, or the coarser one a pair budget made `assign` use.
    grid: [u32; 3],
    /// The scene's own grid; `grid` differs from it when the dump is of a coarser one.
    scene_grid: [u32; 3],
    /// `grid != scene_grid`: the dump was built on a coarser grid (a pair budget's fallback).
    coarsened: bool,
    exact_pairs: u64,
    reported_pairs: u64,
    misses: u64,
    false_positives: u64,
    /// `false_positives / exact_pairs` (0 when there are no exact pairs).
    false_positive_ratio: f64,
    /// The miss in the lowest cluster (lowest light first, as a scene-file index), if any.
    first_miss: Option<oracle_check::Miss>,
    /// Lights the scene file holds but that are invalid (skipped on loading) which the dump lists
    /// anyway: none in a right dump.
    invalid_lights_listed: u64,
    /// The pairs that list them (one such light in 8 clusters is 8 pairs).
    invalid_pairs: u64,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let (scene, name) = args.source.load()?;
    let dump = AssignmentDump::load(&args.dump)?;
    // Indices refer to the scene file's lights, skipped invalid ones included.
    let file_lights = scene.lights.len() + scene.skipped.len();
    let grid = grid_of_dump(&scene.grid, dump.grid);
    // The recorded scene first: it names a mix-up of files (another seed, a moved camera,
    // another light count) that the grid's planes do not show — the oracle would report it as
    // misses, the index check as an index past the lights. Then the grid and the indices.
    dump.check_scene(&scene)
        .and_then(|()| dump.check_against(&grid, file_lights))
        .with_context(|| format!("{} does not match {name}", args.dump.display()))?;
    // The checks work on the loaded lights' columns. A skipped (invalid) light maps to no
    // column: an assignment never lists one (its NaN or negative radius touches nothing), so a
    // dump that does is wrong whatever the oracle says (audit g2: it passed as a false positive).
    let mut column_of = vec![u32::MAX; file_lights];
    for (column, &file_index) in scene.lights.source_index.iter().enumerate() {
        column_of[file_index as usize] = column as u32;
    }
    let mut lists: LightLists = dump.lists();
    let invalid = invalid_lights_listed(&lists, &column_of);
    for l in &mut lists.indices {
        *l = column_of[*l as usize];
    }
    let report: CheckReport = match args.reference {
        Reference::Independent => {
            let oracle = OracleLights::new(&scene.lights, &scene.camera);
            let every: Vec<u32> = (0..grid.cluster_count() as u32).collect();
            check_clusters(&oracle, &scene.camera, &grid, &lists, &every)
        }
        Reference::ExactMethod => check_all(&scene.lights, &scene.camera, &grid, &lists),
    };
    let out = CheckOutput {
        scene: name.clone(),
        dump: args.dump.display().to_string(),
        reference: args.reference,
        grid: grid.dims().to_array(),
        scene_grid: scene.grid.dims().to_array(),
        coarsened: grid.dims() != scene.grid.dims(),
        invalid_lights_listed: invalid.lights,
        invalid_pairs: invalid.count,
        exact_pairs: report.exact_pairs,
        reported_pairs: report.reported_pairs,
        misses: report.misses,
        false_positives: report.false_positives,
        false_positive_ratio: if report.exact_pairs > 0 {
            report.false_positives as f64 / report.exact_pairs as f64
        } else {
            0.0
        },
        first_miss: report.first_miss.map(|m| oracle_check::Miss {
            light: scene.lights.source_index[m.light as usize],
            ..m
        }),
    };
    if args.json {
        println!("{}", serde_json::to_string(&out)?);
    } else {
        let reference = match out.reference {
            Reference::Independent => "the f64 oracle, every cluster (independent)",
            Reference::ExactMethod => "the exact method's lists",
        };
        println!("{name} vs {} (against {reference}):", out.dump);
        if out.coarsened {
            let [x, y, z] = out.grid;
            println!(
                "  grid                  {x}x{y}x{z} (coarser than the scene's, as a pair budget makes it)"
            );
        }
        println!("  exact pairs           {}", out.exact_pairs);
        println!("  reported pairs        {}", out.reported_pairs);
        println!("  misses                {}", out.misses);
        println!("  false positives       {}", out.false_positives);
        if out.exact_pairs == 0 && out.false_positives > 0 {
            // Every reported pair is false, and there is nothing to divide by: the JSON's 0
            // (kept a number for readers that expect one) would read as "perfect" here.
            println!("  false-positive ratio  n/a (no exact pairs to divide by)");
        } else {
            println!("  false-positive ratio  {:.4}", out.false_positive_ratio);
        }
    }
    if let Some(m) = out.first_miss {
        eprintln!(
            "error: {}: {} miss(es); e.g. cluster {} (tile {}, {}, slice {}) lacks light {} \
             (scene-file index), which the oracle says touches it",
            out.dump, out.misses, m.cluster, m.tile[0], m.tile[1], m.tile[2], m.light
        );
    }
    if let Some((cluster, light)) = invalid.first {
        eprintln!(
            "error: {}: the dump lists {} invalid light(s), skipped when the scene was loaded, in \
             {} pair(s); e.g. cluster {cluster} lists light {light} (scene-file index)",
            out.dump, invalid.lights, invalid.count
        );
    }
    Ok(if out.misses == 0 && invalid.count == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// How many pairs of `lists` (scene-file indices) name a light without a column, how many
/// lights they name, and the first.
struct InvalidListed {
    /// Pairs.
    count: u64,
    /// Distinct lights (one invalid light listed in 8 clusters is 8 pairs and 1 light).
    lights: u64,
    /// (cluster, scene-file index) of the first.
    first: Option<(u32, u32)>,
}

fn invalid_lights_listed(lists: &LightLists, column_of: &[u32]) -> InvalidListed {
    let mut found = InvalidListed {
        count: 0,
        lights: 0,
        first: None,
    };
    let mut seen = vec![false; column_of.len()];
    for (cluster, (&offset, &count)) in lists.offsets.iter().zip(&lists.counts).enumerate() {
        let start = offset as usize;
        for &light in &lists.indices[start..start + count as usize] {
            if column_of[light as usize] == u32::MAX {
                found.count += 1;
                if !std::mem::replace(&mut seen[light as usize], true) {
                    found.lights += 1;
                }
                found.first.get_or_insert((cluster as u32, light));
            }
        }
    }
    found
}

/// The grid a dump of `dims` was built for: the scene's, or one of the coarser grids a pair budget
/// falls back to ([`coarser_grid`]). An unrelated size gives the scene's grid, which the dump's
/// own check then rejects with the mismatch.
fn grid_of_dump(scene: &ClusterGrid, dims: [u32; 3]) -> ClusterGrid {
    let mut grid = *scene;
    while grid.dims().to_array() != dims {
        let coarser = coarser_grid(&grid);
        if coarser.dims() == grid.dims() {
            return *scene;
        }
        grid = coarser;
    }
    grid
}
