//! `myriad report`: the time-against-error study over every assignment method, every standard
//! scene and several grid sizes, as a markdown table, a JSON file and an SVG plot.
//!
//! Why it exists: `myriad bench` answers for one scene on one grid, but choosing a method and a
//! grid is a trade-off that only shows across many of them. A finer grid shortens each cluster's
//! list (less shading work per pixel) but costs assignment time, and the cheap methods' boxes
//! fit some grids and scenes worse than others. So this command measures the whole table in one
//! run — `myriad::evaluate::measure` for each method against the exact lists of the same scene and
//! grid — marks each scene's **Pareto front** (the configurations no other one beats in both time
//! and false-positive ratio), and draws it. Every row is also a correctness check: a single
//! missed light makes the command fail, after it has written its files.
//!
//! The plot uses `plotters`' SVG backend only: text becomes SVG `<text>` elements that the viewer
//! sets in its own fonts, so nothing here needs system fonts or a rasteriser.

use super::grid_options::parse_grid;
use super::list_options::refuse_repeats;
use super::oracle_check::independent_lists;
use super::pair_budget::{COMPARE_BYTES_PER_PAIR, PairBudget};
use super::source::{check_memory_for, thread_pool};
use anyhow::{Context, Result, ensure};
use myriad::assignment::{Assigner, LightLists, Method};
use myriad::cluster_math::glam::UVec3;
use myriad::evaluate::{MethodResult, Timing, measure};
use myriad::scene::{ClusterGrid, Preset, check_replaceable, replace_files};
use plotters::coord::Shift;
use plotters::drawing::DrawingAreaErrorKind;
use plotters::prelude::*;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

/// The grids measured when `--grids` is not given: the three presets' own grids and the paper
/// preset's 24×12 tiles with 32 and 64 slices.
const DEFAULT_GRIDS: &str = "16x9x24,24x12x16,24x12x32,24x12x64,32x18x48";

/// Timed runs of `exact` at most: it tests every candidate cluster with the f64 oracle, so it is
/// by far the slowest method (as in `myriad bench`).
const EXACT_RUNS: usize = 3;

/// What the "shading cost" column means; written into the report and the JSON.
const SHADING_COST: &str = "shading cost = the mean list length, under the method, of the \
clusters that at least one light really touches (the clusters the exact lists leave non-empty): \
the lights a pixel in such a cluster evaluates. The set of clusters is the same for every method \
of a scene and grid, so the column compares methods directly; for exact it is the mean length of \
the non-empty exact lists.";

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Lights in each standard scene (paper, uniform, sphere).
    #[arg(long, value_parser = super::light_count, default_value_t = 10_000)]
    lights: usize,
    /// Seed of the generated scenes.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Comma-separated grids, each XxYxZ.
    #[arg(long, value_delimiter = ',', default_value = DEFAULT_GRIDS)]
    grids: Vec<String>,
    /// Timed runs per method and grid, after one warm-up (the median is reported; exact, the
    /// slow oracle, does at most 3). With the defaults the whole study takes about 10 s on 2 cores.
    #[arg(long, value_parser = super::run_count, default_value_t = 21)]
    runs: usize,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Folder for report.md, report.json and report.svg.
    #[arg(long, default_value = "out")]
    out: PathBuf,
}

/// Everything the command measured (`report.json`).
#[derive(Serialize)]
struct Report {
    lights: usize,
    seed: u64,
    threads: usize,
    runs: usize,
    exact_runs: usize,
    shading_cost_definition: &'static str,
    rows: Vec<Row>,
}

/// One scene × grid × method.
#[derive(Serialize)]
struct Row {
    scene: &'static str,
    grid: [u32; 3],
    #[serde(flatten)]
    result: MethodResult,
    /// Clusters the exact lists leave non-empty.
    lit_clusters: u64,
    /// See [`SHADING_COST`].
    shading_cost: f64,
    /// On the scene's Pareto front of (median time, false-positive ratio).
    pareto: bool,
}

pub fn run(args: Args) -> Result<ExitCode> {
    ensure!(args.runs >= 1, "--runs must be at least 1");
    let grids = args
        .grids
        .iter()
        .map(|g| parse_grid("--grids", g.trim()))
        .collect::<Result<Vec<UVec3>>>()?;
    ensure!(!grids.is_empty(), "--grids: give at least one grid");
    refuse_repeats("--grids", &grids, |d| format!("{}x{}x{}", d.x, d.y, d.z))?;
    for &dims in &grids {
        check_memory_for(dims, args.lights)?;
    }
    super::outputs::create_out_folder(&args.out)?;
    let paths = [
        args.out.join("report.md"),
        args.out.join("report.json"),
        args.out.join("report.svg"),
    ];
    // The three files describe one run: a target none can replace is said before the
    // measurement, and all three are written at the end as one set, or none.
    check_replaceable(&paths.each_ref().map(|p| p.as_path()))?;

    let pool = thread_pool(args.threads)?;
    let mut report = pool.install(|| measure_all(&args, &grids))?;
    mark_pareto_fronts(&mut report.rows);

    let markdown = markdown(&report);
    print!("{markdown}");
    let json = serde_json::to_string_pretty(&report)?;
    let svg = plot(&report)?;
    replace_files(&[
        (&paths[0], markdown.as_bytes()),
        (&paths[1], json.as_bytes()),
        (&paths[2], svg.as_bytes()),
    ])?;
    eprintln!(
        "wrote {}, {} and {}",
        paths[0].display(),
        paths[1].display(),
        paths[2].display()
    );

    let missed: Vec<String> = report
        .rows
        .iter()
        .filter(|r| r.result.misses > 0)
        .map(|r| format!("{} {} {}", r.scene, grid_name(r.grid), r.result.method))
        .collect();
    if missed.is_empty() {
        Ok(ExitCode::SUCCESS)
    } else {
        eprintln!(
            "error: lights the oracle says touch a cluster were missed by: {}",
            missed.join(", ")
        );
        Ok(ExitCode::FAILURE)
    }
}

/// Measures every preset × grid × method on the current rayon pool; one stderr line per
/// preset × grid.
fn measure_all(args: &Args, grids: &[UVec3]) -> Result<Report> {
    let start = Instant::now();
    let total = Preset::ALL.len() * grids.len();
    let mut rows = Vec::with_capacity(total * Method::ALL.len());
    let mut done = 0;
    // Every method's lists must fit the memory beside the oracle's: past it, a clear error.
    let budget = PairBudget::new(None, COMPARE_BYTES_PER_PAIR);
    for preset in Preset::ALL {
        let scene = preset.generate(args.lights, args.seed);
        let input = myriad::light_input(&scene.lights);
        let camera = &scene.camera;
        for &dims in grids {
            let grid = ClusterGrid::new(
                dims,
                scene.grid.slicing(),
                scene.grid.near(),
                scene.grid.far(),
            );
            // The reference shares no code with the assignment but the f64 oracle.
            let exact = independent_lists(&scene.lights, camera, &grid, &budget)?;
            let mut lists = LightLists::new();
            let mut times = Vec::new();
            for method in Method::ALL {
                let runs = match method {
                    Method::Exact => args.runs.min(EXACT_RUNS),
                    _ => args.runs,
                };
                let result = measure(
                    method,
                    &input,
                    camera,
                    &grid,
                    &exact,
                    Timing::back_to_back(runs),
                    budget.pairs,
                )
                .with_context(|| format!("the pair budget is {}", budget.describe()))?;
                // `measure` keeps its lists to itself; one more assignment gives them back for the
                // shading cost.
                Assigner::new().assign(method, &input, camera, &grid, &mut lists);
                let (shading_cost, lit_clusters) = shading_cost(&lists, &exact);
                times.push(format!("{method} {:.0} µs", result.median_us));
                rows.push(Row {
                    scene: preset.name(),
                    grid: dims.to_array(),
                    result,
                    lit_clusters,
                    shading_cost,
                    pareto: false,
                });
            }
            done += 1;
            eprintln!(
                "[{done}/{total}] {} {}: {} ({:.1} s)",
                preset.name(),
                grid_name(dims.to_array()),
                times.join(", "),
                start.elapsed().as_secs_f64()
            );
        }
    }
    Ok(Report {
        lights: args.lights,
        seed: args.seed,
        threads: rayon::current_num_threads(),
        runs: args.runs,
        exact_runs: args.runs.min(EXACT_RUNS),
        shading_cost_definition: SHADING_COST,
        rows,
    })
}

/// The shading cost of `lists` (see [`SHADING_COST`]) and the number of clusters it averages
/// over; 0 when no light touches any cluster.
fn shading_cost(lists: &LightLists, exact: &LightLists) -> (f64, u64) {
    let mut lit = 0u64;
    let mut lights = 0u64;
    for c in 0..exact.cluster_count() {
        if exact.counts[c] > 0 {
            lit += 1;
            lights += u64::from(lists.counts[c]);
        }
    }
    let mean = if lit > 0 {
        lights as f64 / lit as f64
    } else {
        0.0
    };
    (mean, lit)
}

/// Indices of the points that no other point dominates, by increasing time (then error). A point
/// `q` dominates `p` when it is no slower and no worse (`q.0 <= p.0`, `q.1 <= p.1`) and better in at
/// least one of the two. Equal points do not dominate each other, so both stay on the front.
/// Points are `(time, error)`; a NaN never dominates and is never dominated.
fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let dominates =
        |q: (f64, f64), p: (f64, f64)| q.0 <= p.0 && q.1 <= p.1 && (q.0 < p.0 || q.1 < p.1);
    let mut front: Vec<usize> = (0..points.len())
        .filter(|&i| !points.iter().any(|&q| dominates(q, points[i])))
        .collect();
    front.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
            .then(a.cmp(&b))
    });
    front
}

/// Sets `pareto` on the rows on their scene's front of (median time, false-positive ratio).
fn mark_pareto_fronts(rows: &mut [Row]) {
    for preset in Preset::ALL {
        let of_scene: Vec<usize> = (0..rows.len())
            .filter(|&i| rows[i].scene == preset.name())
            .collect();
        let points: Vec<(f64, f64)> = of_scene.iter().map(|&i| point(&rows[i])).collect();
        for k in pareto_front(&points) {
            rows[of_scene[k]].pareto = true;
        }
    }
}

fn point(row: &Row) -> (f64, f64) {
    (row.result.median_us, row.result.false_positive_ratio)
}

fn grid_name([x, y, z]: [u32; 3]) -> String {
    format!("{x}×{y}×{z}")
}

/// `report.md`: a header saying what was measured, then one row per scene × grid × method.
fn markdown(report: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Time against error: every method, scene and grid\n");
    let _ = writeln!(
        s,
        "`myriad report`: {} lights per standard scene (seed {}), {} threads; median of {} timed \
         runs after a warm-up ({} for exact). False-positive ratio = pairs the exact oracle \
         rejects / exact pairs; misses = exact pairs a method left out (must be 0). Pareto: ✓ = \
         no other method × grid of the same scene is both at least as fast and at least as \
         accurate, and better in one of the two.\n",
        report.lights, report.seed, report.threads, report.runs, report.exact_runs
    );
    let _ = writeln!(
        s,
        "{}\n",
        SHADING_COST.replace("shading cost =", "Shading cost:")
    );
    let _ = writeln!(
        s,
        "| scene | grid | method | median µs | pairs | fp ratio | misses | shading cost | Pareto |"
    );
    let _ = writeln!(
        s,
        "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | :---: |"
    );
    for r in &report.rows {
        let m = &r.result;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.1} | {} | {:.4} | {} | {:.2} | {} |",
            r.scene,
            grid_name(r.grid),
            m.method,
            m.median_us,
            m.pairs,
            m.false_positive_ratio,
            m.misses,
            r.shading_cost,
            if r.pareto { "✓" } else { "" }
        );
    }
    s
}

/// The colour of a method's points (and legend entry).
fn method_colour(method: &str) -> RGBColor {
    match method {
        "exact" => RGBColor(40, 40, 40),
        "linear" => RGBColor(214, 39, 40),
        "binary" => RGBColor(31, 119, 180),
        "refined" => RGBColor(44, 160, 44),
        "cone" => RGBColor(148, 103, 189),
        _ => RGBColor(140, 86, 75),
    }
}

/// Colour of the Pareto-front lines (tests look for a polyline of this colour per scene).
const FRONT_COLOUR: RGBColor = RGBColor(255, 127, 14);

/// Width × height of the SVG.
const PLOT_SIZE: (u32, u32) = (1500, 1160);

/// The two error measures the plot puts against time, one row of panels each.
#[derive(Clone, Copy)]
enum Error {
    FalsePositives,
    ShadingCost,
}

impl Error {
    fn of(self, row: &Row) -> f64 {
        match self {
            Error::FalsePositives => row.result.false_positive_ratio,
            Error::ShadingCost => row.shading_cost,
        }
    }

    fn axis(self) -> &'static str {
        match self {
            Error::FalsePositives => "false-positive ratio",
            Error::ShadingCost => "shading cost (lights per lit cluster)",
        }
    }
}

/// Marker shapes, one per grid in the order given (cycling past five grids).
#[derive(Clone, Copy)]
enum Marker {
    Disc,
    Triangle,
    Square,
    Cross,
    Ring,
}

impl Marker {
    fn for_grid(index: usize) -> Self {
        [
            Marker::Disc,
            Marker::Triangle,
            Marker::Square,
            Marker::Cross,
            Marker::Ring,
        ][index % 5]
    }

    /// Draws the marker at `at`, in the coordinates of `area`.
    fn draw<DB: DrawingBackend, CT: CoordTranslate>(
        self,
        area: &DrawingArea<DB, CT>,
        at: CT::From,
        colour: RGBColor,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
    where
        CT::From: Clone,
    {
        let (fill, line) = (colour.filled(), colour.stroke_width(2));
        let at = EmptyElement::at(at);
        match self {
            Marker::Disc => area.draw(&(at + Circle::new((0, 0), 5, fill))),
            Marker::Triangle => area.draw(&(at + TriangleMarker::new((0, 0), 7, fill))),
            Marker::Square => area.draw(&(at + Rectangle::new([(-4, -4), (4, 4)], fill))),
            Marker::Cross => area.draw(&(at + Cross::new((0, 0), 5, line))),
            Marker::Ring => area.draw(&(at + Circle::new((0, 0), 5, line))),
        }
    }
}

/// `report.svg`: one panel per scene and error measure, assignment time (log) against the
/// false-positive ratio (top row) and against the shading cost (bottom row, [`SHADING_COST`]);
/// colour = method, marker = grid; each panel's Pareto front as a line.
fn plot(report: &Report) -> Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, PLOT_SIZE).into_drawing_area();
        root.fill(&WHITE)?;
        let (top, panels) = root.split_vertically(78);
        legend(&top, report)?;
        let areas = panels.split_evenly((2, Preset::ALL.len()));
        let errors = [Error::FalsePositives, Error::ShadingCost];
        for (row_of_panels, error) in areas.chunks(Preset::ALL.len()).zip(errors) {
            for (area, preset) in row_of_panels.iter().zip(Preset::ALL) {
                let rows: Vec<&Row> = report
                    .rows
                    .iter()
                    .filter(|r| r.scene == preset.name())
                    .collect();
                panel(area, preset.name(), report.lights, &rows, error)?;
            }
        }
        root.present()?;
    }
    Ok(svg)
}

/// The strip above the panels: title, methods by colour, grids by marker, the front's line.
fn legend(area: &DrawingArea<SVGBackend<'_>, Shift>, report: &Report) -> Result<()> {
    let title = format!(
        "Assignment time against error (false positives, shading cost) — {} lights per scene, \
         {} threads",
        report.lights, report.threads
    );
    area.draw(&Text::new(title, (20, 10), ("sans-serif", 20).into_font()))?;
    let font = ("sans-serif", 15).into_font();
    let mut x = 20;
    for method in Method::ALL {
        let colour = method_colour(method.name());
        area.draw(&Circle::new((x + 6, 52), 6, colour.filled()))?;
        area.draw(&Text::new(method.name(), (x + 18, 45), font.clone()))?;
        x += 100;
    }
    x += 30;
    let mut grids: Vec<[u32; 3]> = Vec::new();
    for r in &report.rows {
        if !grids.contains(&r.grid) {
            grids.push(r.grid);
        }
    }
    for (i, &g) in grids.iter().enumerate() {
        Marker::for_grid(i).draw(area, (x + 6, 52), RGBColor(90, 90, 90))?;
        area.draw(&Text::new(grid_name(g), (x + 18, 45), font.clone()))?;
        x += 110;
    }
    x += 20;
    area.draw(&PathElement::new(
        vec![(x, 52), (x + 30, 52)],
        FRONT_COLOUR.stroke_width(3),
    ))?;
    area.draw(&Text::new("Pareto front", (x + 38, 45), font))?;
    Ok(())
}

/// One scene's panel for one error measure.
fn panel(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    scene: &str,
    lights: usize,
    rows: &[&Row],
    error: Error,
) -> Result<()> {
    let points: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| (r.result.median_us, error.of(r)))
        .collect();
    let (t_min, t_max) = points.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
        (lo.min(p.0), hi.max(p.0))
    });
    let (t_min, t_max) = if t_min.is_finite() && t_min > 0.0 {
        (t_min / 1.6, t_max * 1.6)
    } else {
        (1.0, 10.0)
    };
    let y_max = points.iter().fold(0.0f64, |m, p| m.max(p.1)).max(0.01);
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("{scene} ({lights} lights)"),
            ("sans-serif", 18).into_font(),
        )
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(58)
        .build_cartesian_2d(
            (t_min..t_max)
                .log_scale()
                .with_key_points(time_ticks(t_min, t_max)),
            -0.04 * y_max..1.1 * y_max,
        )?;
    chart
        .configure_mesh()
        .x_desc("assignment time, µs (median; log scale)")
        .y_desc(error.axis())
        .x_label_formatter(&|t| format_us(*t))
        .y_label_formatter(&|r| format_ratio(*r))
        .label_style(("sans-serif", 13).into_font())
        .axis_desc_style(("sans-serif", 14).into_font())
        .light_line_style(RGBColor(244, 244, 244))
        .bold_line_style(RGBColor(220, 220, 220))
        .draw()?;

    let front: Vec<(f64, f64)> = pareto_front(&points)
        .into_iter()
        .map(|i| points[i])
        .collect();
    chart.draw_series(LineSeries::new(front, FRONT_COLOUR.stroke_width(3)))?;

    let mut grids: Vec<[u32; 3]> = Vec::new();
    for r in rows {
        if !grids.contains(&r.grid) {
            grids.push(r.grid);
        }
    }
    for (r, &p) in rows.iter().zip(&points) {
        let marker = Marker::for_grid(grids.iter().position(|&g| g == r.grid).unwrap_or(0));
        marker.draw(chart.plotting_area(), p, method_colour(&r.result.method))?;
    }
    Ok(())
}

/// Ticks of the time axis: 1, 2, 5, 10, 20, 50, … inside `[lo, hi]` (plotters' own log ticks
/// start at the first power of ten, which leaves a narrow range unlabelled).
fn time_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let mut ticks = Vec::new();
    let mut decade = 10f64.powf(lo.log10().floor());
    while decade <= hi {
        for m in [1.0, 2.0, 5.0] {
            let t = decade * m;
            if (lo..=hi).contains(&t) {
                ticks.push(t);
            }
        }
        decade *= 10.0;
    }
    ticks
}

/// Tick labels of the ratio axis: at most four decimals, no trailing zeros (`0`, `0.25`, `0.005`).
fn format_ratio(r: f64) -> String {
    let s = format!("{r:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// Tick labels of the time axis: `50`, `200`, `1k`, `20k`, `1.5M`.
fn format_us(t: f64) -> String {
    let trimmed = |v: f64| {
        let s = format!("{v:.1}");
        s.strip_suffix(".0").map(str::to_string).unwrap_or(s)
    };
    if t >= 1e6 {
        format!("{}M", trimmed(t / 1e6))
    } else if t >= 1e3 {
        format!("{}k", trimmed(t / 1e3))
    } else {
        trimmed(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_drops_dominated_points_and_orders_by_time() {
        // (time, error): 2 is slower and worse than 0; 3 is slower than 1 with the same error.
        let points = [
            (10.0, 0.5),
            (100.0, 0.0),
            (5.0, 0.9),
            (20.0, 0.6),
            (150.0, 0.0),
        ];
        assert_eq!(pareto_front(&points), vec![2, 0, 1]);
        // A point worse in one coordinate only is still on the front.
        let points = [(1.0, 1.0), (2.0, 0.5), (3.0, 0.25)];
        assert_eq!(pareto_front(&points), vec![0, 1, 2]);
    }

    #[test]
    fn pareto_front_keeps_both_of_two_equal_points() {
        // 0 and 2 tie exactly: neither dominates the other, both stay; 1 ties 0 in time but is
        // worse, so it goes; 3 ties 2 in error but is slower, so it goes.
        let points = [
            (10.0, 0.2),
            (10.0, 0.3),
            (10.0, 0.2),
            (12.0, 0.2),
            (50.0, 0.0),
        ];
        assert_eq!(pareto_front(&points), vec![0, 2, 4]);
        assert_eq!(pareto_front(&[(1.0, 1.0), (1.0, 1.0)]), vec![0, 1]);
        assert_eq!(pareto_front(&[]), Vec::<usize>::new());
        assert_eq!(pareto_front(&[(3.0, 0.1)]), vec![0]);
    }

    #[test]
    fn shading_cost_averages_over_the_clusters_the_exact_lists_light() {
        let lists = |per_cluster: &[&[u32]]| {
            let mut l = LightLists::default();
            for c in per_cluster {
                l.offsets.push(l.indices.len() as u32);
                l.counts.push(c.len() as u32);
                l.indices.extend_from_slice(c);
            }
            l
        };
        let exact = lists(&[&[1, 2], &[], &[3], &[]]);
        // Extra lights in lit clusters count; a list in a cluster no light touches does not.
        let method = lists(&[&[1, 2, 5], &[4], &[3, 4, 6], &[]]);
        assert_eq!(shading_cost(&method, &exact), (3.0, 2));
        assert_eq!(shading_cost(&exact, &exact), (1.5, 2));
        let empty = lists(&[&[], &[]]);
        assert_eq!(shading_cost(&empty, &empty), (0.0, 0));
    }

    #[test]
    fn time_labels_are_short() {
        assert_eq!(format_us(50.0), "50");
        assert_eq!(format_us(2_000.0), "2k");
        assert_eq!(format_us(1_500_000.0), "1.5M");
        assert_eq!(format_us(0.5), "0.5");
        assert_eq!(time_ticks(3.0, 130.0), [5.0, 10.0, 20.0, 50.0, 100.0]);
        assert_eq!(format_ratio(0.0), "0");
        assert_eq!(format_ratio(0.25), "0.25");
        assert_eq!(format_ratio(0.005), "0.005");
    }
}
