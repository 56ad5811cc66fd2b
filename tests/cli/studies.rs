//! The studies: `paper` (the paper's tables and heat map), `report` (time against error over every
//! scene, grid and method) and `stress` (one frame of very many lights, checked against the
//! oracle).

use super::*;

#[test]
fn paper_reproduces_both_tables_with_json_and_heat_map() {
    if !gpu_available() {
        return;
    }
    // Run in a fresh folder: the scene is Sponza only when ../shared/assets has it from there.
    let dir = work_dir("paper");
    let out_dir = dir.join("results");
    let out = Command::new(env!("CARGO_BIN_EXE_myriad"))
        .current_dir(&dir)
        .args(["paper", "--size", "192x96", "--runs", "2", "--out"])
        .arg(&out_dir)
        .output()
        .expect("cannot run the myriad binary");
    assert!(out.status.success(), "paper failed:\n{}", all_output(&out));
    let text = stdout(&out);
    let sponza = dir.join("../shared/assets/sponza/Sponza.gltf").is_file();
    assert_mentions(
        &text,
        &[
            if sponza {
                "scene: Sponza"
            } else {
                "scene: default scene (atrium)"
            },
            "192x96",
            "Table 1 — 1000 lights",
            "Table 2 — 10 lights",
            "the paper's Table 1",
            "Figure 4",
            "paper_heatmap.png",
            // The grids' depth slicing, and the paper's where it differs.
            "assignment: refined; grids: log depth slicing (the paper: uniform, --depth linear); \
             medians of up to 2 frame(s)",
        ],
    );
    if !sponza {
        assert_mentions(&text, &["not found", "--assets"]);
    }
    // Each table: its three grids and "no clustering", with the paper's row beside ours.
    let paper_rows = [
        ("Table 1", ["9.16", "8.28", "9.10", "156.00"]),
        ("Table 2", ["0.63", "0.64", "0.78", "1.60"]),
    ];
    for (table, paper_totals) in paper_rows {
        let start = text.find(table).unwrap();
        // Our eight columns, one bar, the paper's four: the bar of every line under the
        // title's "| the paper's Table N".
        let bar = |line: &str| line.chars().position(|c| c == '|');
        let title = text[start..].lines().next().unwrap();
        for line in text[start..].lines().skip(1).take(6) {
            assert_eq!(line.matches('|').count(), 1, "{table}: {line:?}");
            assert_eq!(bar(line), bar(title), "{table}: {line:?} under {title:?}");
        }
        let lines: Vec<&str> = text[start..].lines().skip(3).take(4).collect();
        let configs = ["24x12x16", "24x12x32", "24x12x64", "no clustering"];
        for ((line, config), total) in lines.iter().zip(configs).zip(paper_totals) {
            assert!(
                line.starts_with(config),
                "{table}: {line:?} is not {config}"
            );
            assert!(
                line.contains(total),
                "{table}: no paper total {total} in {line:?}"
            );
        }
    }
    // Progress: one result line per configuration (and a start line each), with its frames.
    let err = stderr(&out);
    let results: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("/8] ") && l.contains(": shading "))
        .collect();
    assert_eq!(results.len(), 8, "{err}");
    for line in results {
        assert!(line.contains(" (2 frames)"), "{line}");
    }

    let json = read_json(&out_dir.join("paper.json"));
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 8);
    let timestamps = json["timestamps"].as_bool().unwrap();
    assert_mentions(
        &text,
        &[if timestamps {
            "pass timestamps: yes"
        } else {
            "pass timestamps: no"
        }],
    );
    for (i, row) in rows.iter().enumerate() {
        let lights = if i < 4 { 10 } else { 1000 };
        assert_eq!(row["lights"], lights, "{row}");
        assert_eq!(row["table"], if lights == 10 { 2 } else { 1 }, "{row}");
        let shading = row["shading_ms"].as_f64().unwrap();
        let total = row["total_ms"].as_f64().unwrap();
        assert!(shading > 0.0 && total >= shading, "{row}");
        // The total is our three stages; the G-buffer is a pass of its own where the adapter
        // times passes, else inside the shading's wall clock.
        let gbuffer = row["gbuffer_ms"].as_f64();
        assert_eq!(gbuffer.is_some(), timestamps, "{row}");
        assert_eq!(
            row["shading_source"],
            if timestamps {
                "timestamps"
            } else {
                "wall clock"
            },
            "{row}"
        );
        let stages = row["assign_ms"].as_f64().unwrap() + gbuffer.unwrap_or(0.0) + shading;
        assert!((total - stages).abs() <= 1e-9 * total, "{row}");
        // --runs 2 timed frames each: a frame this small takes far less than the 10 s that
        // would cut a configuration to one.
        assert_eq!(row["frames"], 2, "{row}");
        assert!(row["paper"]["total_ms"].as_f64().unwrap() > 0.0, "{row}");
        if i % 4 < 3 {
            let z = [16, 32, 64][i % 4];
            assert_eq!(row["config"], format!("24x12x{z}"));
            assert_eq!(row["grid"], serde_json::json!([24, 12, z]));
            assert!(row["assign_ms"].as_f64().unwrap() > 0.0, "{row}");
            let pairs = u64_field(row, "pairs");
            assert!(pairs > 0, "{row}");
            // The CSR lists: offsets and counts per cluster, one index per pair.
            assert_eq!(u64_field(row, "list_bytes"), 4 * (2 * 24 * 12 * z + pairs));
            let mean = row["pixels"]["mean_lights"].as_f64().unwrap();
            assert!(mean < lights as f64, "{row}");
        } else {
            assert_eq!(row["config"], "no clustering");
            assert_eq!(row["assign_ms"].as_f64().unwrap(), 0.0);
            assert_eq!(u64_field(row, "list_bytes"), 0);
            assert_eq!(
                row["pixels"]["mean_lights"].as_f64().unwrap(),
                lights as f64
            );
        }
    }
    // No clustering against the best grid, on the paper's total (shading + assignment) for
    // both; ours from the rows, the paper's from its Tables 1 and 2.
    for (table, table_rows, paper) in [
        ("Table 1", &rows[4..], "18.8"),
        ("Table 2", &rows[..4], "2.5"),
    ] {
        let paper_total =
            |r: &Value| r["shading_ms"].as_f64().unwrap() + r["assign_ms"].as_f64().unwrap();
        let best = table_rows[..3]
            .iter()
            .min_by(|a, b| paper_total(a).total_cmp(&paper_total(b)))
            .unwrap();
        let line = text[text.find(table).unwrap()..].lines().nth(7).unwrap();
        assert_eq!(
            line,
            format!(
                "no clustering vs the best grid, shading + assignment: ours {:.1}x ({}), \
                 the paper {paper}x",
                paper_total(&table_rows[3]) / paper_total(best),
                best["config"].as_str().unwrap()
            ),
            "{table}"
        );
    }
    // The light data, left out of the lists as the paper's VRAM leaves it out.
    let light_bytes = size_of::<myriad::gpu::layout::GpuLight>();
    assert_eq!(
        json["light_buffer_bytes"],
        serde_json::json!([[10, 10 * light_bytes], [1000, 1000 * light_bytes]])
    );
    assert_mentions(
        &text,
        &[&format!(
            "({} bytes for 10 lights, {} bytes for 1000 lights)",
            10 * light_bytes,
            1000 * light_bytes
        )],
    );

    // Figure 4: the lights per pixel of the 1000-light 24x12x32 row, on the paper's scale (0–50)
    // unless a pixel has more.
    let heat_map = &json["heat_map"];
    assert_eq!(heat_map["lights"], 1000);
    assert_eq!(heat_map["grid"], serde_json::json!([24, 12, 32]));
    let pixels = &rows[5]["pixels"];
    assert_eq!(heat_map["max_lights_per_pixel"], pixels["max_lights"]);
    assert_eq!(heat_map["mean_lights_per_pixel"], pixels["mean_lights"]);
    let max = u64_field(heat_map, "max_lights_per_pixel");
    assert_eq!(u64_field(heat_map, "scale_max"), max.max(50));
    assert_mentions(
        &text,
        &[&format!(
            "Figure 4 (1000 lights, 24x12x32): at most {max} lights per pixel, {:.1} on average \
             (the paper: fewer than 50); heat map scale 0–{}",
            heat_map["mean_lights_per_pixel"].as_f64().unwrap(),
            max.max(50)
        )],
    );
    let heat = out_dir.join("paper_heatmap.png");
    assert!(heat.is_file(), "no {}", heat.display());
    assert!(std::fs::metadata(&heat).unwrap().len() > 1000);

    // Sponza itself, where this checkout has the shared assets beside it (the run above, in a
    // fresh folder, never does): the paper's own scene and camera.
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets");
    if assets.join("sponza/Sponza.gltf").is_file() {
        let out = myriad_ok(&[
            "paper".as_ref(),
            "--assets".as_ref(),
            assets.as_os_str(),
            "--size".as_ref(),
            "96x48".as_ref(),
            "--runs".as_ref(),
            "1".as_ref(),
            "--out".as_ref(),
            dir.join("sponza").as_os_str(),
        ]);
        assert_mentions(
            &stdout(&out),
            &["scene: Sponza", "camera CameraMain", "Table 1", "Table 2"],
        );
    } else {
        eprintln!("{} has no Sponza: only the atrium run", assets.display());
    }

    // Bad options fail before any rendering, naming the option.
    assert_rejected(&[
        (&["paper", "--runs", "0"], &["--runs", "at least 1"]),
        (&["paper", "--size", "192"], &["--size", "WxH"]),
        (
            &["paper", "--assets", "/nonexistent/assets"],
            &["--assets", "/nonexistent/assets", "no such folder"],
        ),
        (
            &["paper", "--depth", "cubic"],
            &["--depth", "log, linear or log_near:D"],
        ),
    ]);
}

/// `report` and `paper` write sets of files that describe one run: a target that cannot be
/// replaced (here a folder in the place of the last file) is refused before any measuring, and
/// the other files of the set are left as they were.
#[test]
fn report_and_paper_refuse_a_set_they_cannot_write_whole_before_measuring() {
    for (command, files) in [
        ("report", &["report.md", "report.json", "report.svg"][..]),
        ("paper", &["paper_heatmap.png", "paper.json"][..]),
    ] {
        let dir = work_dir(&format!("unwritable_{command}_set"));
        let (last, others) = files.split_last().unwrap();
        for file in others {
            std::fs::write(dir.join(file), b"old").unwrap();
        }
        std::fs::create_dir_all(dir.join(last)).unwrap();
        let out = myriad_fails(&[command, "--out", dir.to_str().unwrap()]);
        assert_mentions(
            &out,
            &[&dir.join(last).display().to_string(), "is a folder"],
        );
        for file in others {
            assert_eq!(
                std::fs::read(dir.join(file)).unwrap(),
                b"old",
                "{command}: {file}"
            );
        }
        // Refused up front: the measuring (minutes for `paper`), whose progress lines count
        // its configurations as "[1/N]", never started.
        assert!(!out.contains("[1/"), "{command} measured first:\n{out}");
        // A file where the folder should be is named as such ("File exists (os error 17)"
        // before).
        let file = dir.join("a_file");
        std::fs::write(&file, b"mine").unwrap();
        let out = myriad_fails(&[command, "--out", file.to_str().unwrap()]);
        assert_mentions(&out, &["a_file", "not a folder"]);
        assert_eq!(std::fs::read(&file).unwrap(), b"mine");
    }
    // A folder that cannot be made (nothing can be created in /proc, not even by root) is
    // refused up front too: `render` and `paper` found out only when writing, after the
    // rendering (audit).
    let nowhere = "/proc/self/myriad-out";
    for command in ["report", "paper", "render"] {
        let out = myriad_fails(&[command, "--out", nowhere]);
        assert_mentions(&out, &["cannot create the folder", nowhere]);
        assert!(
            !out.contains("[1/") && !out.contains("done in"),
            "{command} measured first:\n{out}"
        );
    }
    // The check leaves no folder behind: a run refused after it (here: no GPU backend) leaves
    // none either.
    let dir = work_dir("out_folder_probe");
    let out_dir = dir.join("deeper").join("out");
    let out = Command::new(env!("CARGO_BIN_EXE_myriad"))
        .args(["paper", "--size", "64x32", "--runs", "1", "--out"])
        .arg(&out_dir)
        // A backend this platform lacks: no adapter (as in `render_follows_wgpu_backend…`).
        .env(
            "WGPU_BACKEND",
            if cfg!(target_os = "macos") {
                "dx12"
            } else {
                "metal"
            },
        )
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", all_output(&out));
    assert!(
        !dir.join("deeper").exists(),
        "an output folder without results"
    );
}

#[test]
fn report_covers_every_scene_grid_and_method_and_draws_the_fronts() {
    let dir = work_dir("report");
    let out = myriad_ok(&[
        "report",
        "--lights",
        "500",
        "--grids",
        "8x4x8,16x9x24",
        "--runs",
        "4",
        "--seed",
        "7",
        "--threads",
        "2",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let (scenes, grids, methods) = (
        ["paper", "uniform", "sphere"],
        ["8×4×8", "16×9×24"],
        ["exact", "linear", "binary", "refined", "cone"],
    );

    // report.md, also printed to stdout: one table row per scene × grid × method, no misses.
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert_eq!(stdout(&out), md);
    assert_mentions(&md, &["shading cost", "| scene | grid | method |"]);
    let rows: Vec<Vec<&str>> = md
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| scene") && !l.starts_with("| ---"))
        .map(|l| l.trim_matches('|').split('|').map(str::trim).collect())
        .collect();
    assert_eq!(rows.len(), 3 * 2 * methods.len(), "{md}");
    for scene in scenes {
        for grid in grids {
            for method in methods {
                let row = rows
                    .iter()
                    .find(|r| r[..3] == [scene, grid, method])
                    .unwrap_or_else(|| panic!("no row for {scene} {grid} {method} in:\n{md}"));
                assert_eq!(row[6], "0", "misses in {row:?}");
            }
        }
        assert!(
            rows.iter().any(|r| r[0] == scene && r[8] == "✓"),
            "{scene} has no point on its Pareto front:\n{md}"
        );
    }
    // Progress: one stderr line per scene × grid.
    let progress = stderr(&out);
    for k in 1..=6 {
        assert!(progress.contains(&format!("[{k}/6] ")), "{progress}");
    }

    // report.json: every number, misses 0 everywhere.
    let report = read_json(&dir.join("report.json"));
    let json_rows = report["rows"].as_array().expect("a rows array");
    assert_eq!(json_rows.len(), 3 * 2 * methods.len());
    for r in json_rows {
        assert_eq!(u64_field(r, "misses"), 0, "{r}");
        assert!(r["median_us"].as_f64().is_some_and(|t| t > 0.0), "{r}");
        assert!(u64_field(r, "pairs") > 0, "{r}");
        let exact = json_rows
            .iter()
            .find(|e| e["scene"] == r["scene"] && e["grid"] == r["grid"] && e["method"] == "exact")
            .unwrap();
        assert_eq!(exact["false_positive_ratio"].as_f64(), Some(0.0));
        // Every method lists a superset of the exact lights: never cheaper to shade than exact.
        assert!(
            r["shading_cost"].as_f64().unwrap() >= exact["shading_cost"].as_f64().unwrap(),
            "{r} vs {exact}"
        );
        assert_eq!(r["lit_clusters"], exact["lit_clusters"]);
        assert!(r["false_positive_ratio"].as_f64().unwrap() >= 0.0, "{r}");
        // With no misses, the false positives are the pairs beyond the exact ones.
        let exact_pairs = u64_field(exact, "pairs") as f64;
        let extra = (u64_field(r, "pairs") as f64 - exact_pairs) / exact_pairs;
        assert!(
            (r["false_positive_ratio"].as_f64().unwrap() - extra).abs() < 1e-12,
            "{r} vs {exact}"
        );
        // A lit cluster is one of the grid's, and each holds at least one exact light.
        let grid = r["grid"].as_array().unwrap();
        let clusters: u64 = grid.iter().map(|d| d.as_u64().unwrap()).product();
        let lit = u64_field(r, "lit_clusters");
        assert!(0 < lit && lit <= clusters, "{r}");
        // `exact` takes at most three timed runs (the slow oracle), the others `--runs`.
        let runs = if r["method"] == "exact" { 3 } else { 4 };
        assert_eq!(u64_field(r, "runs"), runs, "{r}");
    }
    // Exact's shading cost is its mean list length over the clusters it lights.
    for exact in json_rows.iter().filter(|r| r["method"] == "exact") {
        let mean = u64_field(exact, "pairs") as f64 / u64_field(exact, "lit_clusters") as f64;
        assert!(
            (exact["shading_cost"].as_f64().unwrap() - mean).abs() < 1e-9,
            "{exact}"
        );
    }
    for (field, value) in [
        ("lights", 500),
        ("seed", 7),
        ("threads", 2),
        ("runs", 4),
        ("exact_runs", 3),
    ] {
        assert_eq!(u64_field(&report, field), value, "{field}");
    }
    assert_mentions(
        &md,
        &[
            "500 lights",
            "seed 7",
            "2 threads",
            "4 timed runs",
            "(3 for exact)",
        ],
    );
    // The Pareto flag: exactly the rows of a scene that no other row of that scene beats in
    // both median time and false-positive ratio (no worse in either, better in one), and the
    // table's ✓ says the same as the JSON.
    let point = |r: &Value| {
        (
            r["median_us"].as_f64().unwrap(),
            r["false_positive_ratio"].as_f64().unwrap(),
        )
    };
    for r in json_rows {
        let p = point(r);
        let dominated = json_rows
            .iter()
            .filter(|q| q["scene"] == r["scene"])
            .any(|q| {
                let q = point(q);
                q.0 <= p.0 && q.1 <= p.1 && (q.0 < p.0 || q.1 < p.1)
            });
        assert_eq!(r["pareto"].as_bool(), Some(!dominated), "{r}");
        let grid: Vec<String> = r["grid"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d.to_string())
            .collect();
        let row = rows
            .iter()
            .find(|m| {
                m[..3]
                    == [
                        r["scene"].as_str().unwrap(),
                        grid.join("×").as_str(),
                        r["method"].as_str().unwrap(),
                    ]
            })
            .unwrap();
        assert_eq!(row[8] == "✓", !dominated, "{row:?} vs {r}");
        // The table's numbers are the JSON's, rounded.
        assert!(rounds(row[3], p.0, 1), "{row:?} vs {r}");
        assert_eq!(row[4], r["pairs"].to_string(), "{row:?} vs {r}");
        assert!(rounds(row[5], p.1, 4), "{row:?} vs {r}");
        let cost = r["shading_cost"].as_f64().unwrap();
        assert!(rounds(row[7], cost, 2), "{row:?} vs {r}");
    }

    // report.svg: an SVG with the method and scene names and one Pareto-front line per scene and
    // error measure (false positives, shading cost)
    // (drawn in the front colour, #FF7F0E; the legend has one more sample of it).
    let svg = std::fs::read_to_string(dir.join("report.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") || svg.starts_with("<?xml"),
        "{}",
        &svg[..svg.len().min(200)]
    );
    assert!(svg.trim_end().ends_with("</svg>"));
    for name in methods.iter().chain(&scenes).chain(&grids) {
        assert!(svg.contains(name), "{name} not in the SVG");
    }
    let fronts = svg
        .lines()
        .filter(|l| l.starts_with("<polyline") && l.contains(r##"stroke="#FF7F0E""##))
        .count();
    assert_eq!(
        fronts,
        1 + 6,
        "legend sample + one front per scene and error measure"
    );
    assert_plot_shows(&svg, json_rows, &scenes, &methods);

    // Bad options fail before measuring anything.
    let out = myriad_fails(&[
        "report",
        "--grids",
        "8x4x8,16x9",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_mentions(&out, &["--grids", "16x9"]);
    let out = myriad_fails(&["report", "--runs", "0", "--out", dir.to_str().unwrap()]);
    assert_mentions(&out, &["--runs"]);
}

/// The value of attribute `name` in one SVG element's line.
fn svg_attr<'a>(line: &'a str, name: &str) -> Option<&'a str> {
    let start = line.find(&format!(" {name}=\""))? + name.len() + 3;
    line[start..].split('"').next()
}

/// A marker or legend sample of `myriad report`'s SVG: its centre, fill and shape.
#[derive(Debug)]
struct SvgMark {
    x: f64,
    y: f64,
    fill: String,
    triangle: bool,
}

/// The filled discs and triangles of an SVG, in drawing order (plotters writes one element a
/// line; a triangle's centre is the mean of its corners).
fn svg_marks(svg: &str) -> Vec<SvgMark> {
    let number = |line: &str, name: &str| svg_attr(line, name).unwrap().parse::<f64>().unwrap();
    svg.lines()
        .filter_map(|line| {
            let fill = svg_attr(line, "fill")?.to_string();
            if line.starts_with("<circle") {
                let (x, y) = (number(line, "cx"), number(line, "cy"));
                Some(SvgMark {
                    x,
                    y,
                    fill,
                    triangle: false,
                })
            } else if line.starts_with("<polygon") {
                let corners: Vec<(f64, f64)> = svg_attr(line, "points")?
                    .split_whitespace()
                    .map(|p| {
                        let (x, y) = p.split_once(',').unwrap();
                        (x.parse().unwrap(), y.parse().unwrap())
                    })
                    .collect();
                let n = corners.len() as f64;
                let x = corners.iter().map(|c| c.0).sum::<f64>() / n;
                let y = corners.iter().map(|c| c.1).sum::<f64>() / n;
                Some(SvgMark {
                    x,
                    y,
                    fill,
                    triangle: true,
                })
            } else {
                None
            }
        })
        .collect()
}

/// `myriad report`'s plot shows its rows: a legend of the methods' colours and the grids'
/// markers, left to right, each sample just before its name; then one panel per scene (columns)
/// and error measure (false positives above, shading cost below), where each row of the scene is
/// a marker in its method's colour and its grid's shape, inside the panel, placed further right
/// for a longer time and higher for a larger error. Two grids given: discs, then triangles.
fn assert_plot_shows(svg: &str, rows: &[Value], scenes: &[&str], methods: &[&str]) {
    const COLOURS: [(&str, &str); 5] = [
        ("exact", "#282828"),
        ("linear", "#D62728"),
        ("binary", "#1F77B4"),
        ("refined", "#2CA02C"),
        ("cone", "#9467BD"),
    ];
    let colour = |method: &str| COLOURS.iter().find(|c| c.0 == method).unwrap().1;
    for axis in [
        "false-positive ratio",
        "shading cost (lights per lit cluster)",
    ] {
        assert!(svg.contains(axis), "no axis {axis:?} in the SVG");
    }
    // The legend: the strip above y = 78. Its names and samples alternate, left to right.
    let texts: Vec<(f64, &str)> = {
        let lines: Vec<&str> = svg.lines().collect();
        lines
            .windows(2)
            .filter(|w| w[0].starts_with("<text") && svg_attr(w[0], "y") == Some("45"))
            .map(|w| (svg_attr(w[0], "x").unwrap().parse().unwrap(), w[1]))
            .collect()
    };
    let names: Vec<&str> = texts.iter().map(|t| t.1).collect();
    assert_eq!(
        names,
        [methods, &["8×4×8", "16×9×24", "Pareto front"]].concat(),
        "legend"
    );
    let marks = svg_marks(svg);
    let (legend, plotted): (Vec<&SvgMark>, Vec<&SvgMark>) = marks.iter().partition(|m| m.y < 78.0);
    assert_eq!(legend.len(), methods.len() + 2, "{legend:?}");
    for (i, (mark, name)) in legend.iter().zip(&texts).enumerate() {
        let gap = name.0 - mark.x;
        assert!(
            (0.0..=14.0).contains(&gap),
            "{name:?} is {gap} px after its sample"
        );
        if i > 0 {
            assert!(
                name.0 >= texts[i - 1].0 + 60.0,
                "{name:?} overlaps {:?}",
                texts[i - 1]
            );
        }
        match methods.get(i) {
            Some(&method) => assert_eq!(mark.fill, colour(method), "{method}"),
            None => assert_eq!(mark.triangle, i == methods.len() + 1, "{name:?}"),
        }
    }
    let front = texts.last().unwrap().0;
    assert!(front < 1400.0, "the legend runs off the plot: {front}");

    // The panels: a 3 × 2 array of 500 × 541 px cells below the legend, each drawn in turn.
    let per_scene = rows.len() / scenes.len();
    assert_eq!(
        plotted.len(),
        2 * rows.len(),
        "one marker per row and panel"
    );
    for (panel, marks) in plotted.chunks(per_scene).enumerate() {
        let (row_of_panels, column) = (panel / scenes.len(), panel % scenes.len());
        let error = ["false_positive_ratio", "shading_cost"][row_of_panels];
        let of_scene: Vec<&Value> = rows
            .iter()
            .filter(|r| r["scene"] == scenes[column])
            .collect();
        let point = |r: &Value| (r["median_us"].as_f64().unwrap(), r[error].as_f64().unwrap());
        let y_max = of_scene.iter().map(|r| point(r).1).fold(0.01, f64::max);
        let first_grid = &of_scene[0]["grid"];
        let cell_x = 500.0 * column as f64;
        let cell_y = 78.0 + 541.0 * row_of_panels as f64;
        // The times spread over the panel's width (they span a decade or more here), not
        // squeezed into a corner.
        let (left, right) = marks
            .iter()
            .fold((f64::MAX, 0.0f64), |(l, r), m| (l.min(m.x), r.max(m.x)));
        assert!(
            right - left > 200.0,
            "panel {panel}: markers from x {left} to {right}"
        );
        for (a, (mark, row)) in marks.iter().zip(&of_scene).enumerate() {
            let what = format!("{} panel {panel}, marker {a}: {mark:?} for {row}", error);
            assert_eq!(mark.fill, colour(row["method"].as_str().unwrap()), "{what}");
            assert_eq!(mark.triangle, row["grid"] != *first_grid, "{what}");
            // Inside the cell's plotting area (right of the y labels, 70 px, above the x labels,
            // 56 px, within its 12 px margin), off its frame.
            assert!(
                (cell_x + 75.0..cell_x + 483.0).contains(&mark.x)
                    && (cell_y..cell_y + 541.0 - 61.0).contains(&mark.y),
                "{what}"
            );
            for (other, next) in marks.iter().zip(&of_scene) {
                let (p, q) = (point(row), point(next));
                if q.0 > p.0 * 1.1 {
                    assert!(other.x > mark.x, "{what}: not left of {next}");
                }
                if q.1 - p.1 > 0.05 * y_max {
                    assert!(other.y < mark.y, "{what}: not below {next}");
                }
            }
        }
    }
}

/// The stage times every `myriad stress --json` report carries.
const STRESS_STAGES: [&str; 9] = [
    "scene_ms",
    "assign_ms",
    "assign_again_ms",
    "gpu_setup_ms",
    "upload_ms",
    "encode_ms",
    "gpu_wall_ms",
    "gpu_readback_ms",
    "check_ms",
];

/// Runs `myriad stress --json` with `args`; the parsed report (the run must succeed).
fn stress_json(args: &[&str]) -> Value {
    let mut all = vec!["stress", "--json"];
    all.extend_from_slice(args);
    let out = myriad_ok(&all);
    serde_json::from_str(&stdout(&out)).expect("stress --json prints one JSON object")
}

fn assert_stress_stages(report: &Value) {
    let stages = &report["stages"];
    for stage in STRESS_STAGES {
        let ms = stages[stage]
            .as_f64()
            .unwrap_or_else(|| panic!("stage {stage} missing in {stages}"));
        assert!(ms >= 0.0 && ms.is_finite(), "{stage}: {ms}");
    }
    assert!(stages["gpu_wall_ms"].as_f64().unwrap() > 0.0);
    // The flag must match the adapter, so the pass checks below cannot be skipped by a report
    // that merely says it has no timestamps.
    let has_timestamps = myriad::gpu::GpuContext::headless_for_tests()
        .expect("no adapter")
        .has_timestamps();
    assert_eq!(report["timestamps"], has_timestamps, "{report}");
    if has_timestamps {
        for pass in ["gpu_gbuffer_ms", "gpu_shading_ms"] {
            assert!(
                stages[pass].as_f64().is_some(),
                "{pass} missing in {stages}"
            );
        }
    }
}

#[test]
fn stress_checks_every_cluster_against_the_oracle() {
    if !gpu_available() {
        return;
    }
    let r = stress_json(&["--lights", "20000", "--size", "64x36"]);
    assert_eq!(r["lights"], 20000);
    assert_eq!(
        (r["width"].as_u64(), r["height"].as_u64()),
        (Some(64), Some(36))
    );
    assert_eq!(r["passed"], true);
    // The GPU shaded with the lists uploaded: read back, every array equal.
    assert_eq!(r["gpu_lists_identical"], true);
    assert_eq!(r["gpu_lists_difference"], Value::Null);
    let check = &r["check"];
    assert_eq!(check["mode"], "full");
    assert_eq!(check["misses"], 0);
    assert_eq!(check["first_miss"], Value::Null);
    assert_eq!(check["clusters_checked"], check["clusters_total"]);
    assert!(u64_field(check, "exact_pairs") > 0);
    let pairs = u64_field(&r["assignment"], "pairs");
    assert!(pairs > 0);
    // Every cluster was checked, so the reported pairs are all of them.
    assert_eq!(u64_field(check, "reported_pairs"), pairs);
    assert!(u64_field(check, "exact_pairs") <= pairs);
    // Lights (32 bytes or more each) and the lists went up.
    assert!(u64_field(&r, "upload_bytes") > 20000 * 32 + 4 * pairs);
    assert_stress_stages(&r);
    // The full check reads the `exact` method's lists, which share the cull and plane searches
    // with the method under test: the same frame with every cluster checked independently of
    // the assignment finds no miss either, and the same exact pairs.
    let r = stress_json(&[
        "--lights",
        "20000",
        "--size",
        "64x36",
        "--exact-up-to",
        "0",
        "--sample",
        "100000000",
    ]);
    let independent = &r["check"];
    assert_eq!(independent["mode"], "independent");
    assert_eq!(independent["misses"], 0);
    assert_eq!(independent["clusters_checked"], check["clusters_total"]);
    assert_eq!(independent["exact_pairs"], check["exact_pairs"]);
    assert_eq!(u64_field(&r["assignment"], "pairs"), pairs);
}

#[test]
fn stress_checks_the_exact_method_independently() {
    if !gpu_available() {
        return;
    }
    // The exact method's lists were compared with themselves, a check that could not fail
    // (audit g1): every cluster goes through the independent oracle instead.
    let r = stress_json(&["--lights", "3000", "--size", "64x36", "--method", "exact"]);
    assert_eq!(r["passed"], true);
    let check = &r["check"];
    assert_eq!(check["mode"], "independent");
    assert_eq!(check["clusters_checked"], check["clusters_total"]);
    assert_eq!(check["misses"], 0);
    let pairs = u64_field(&r["assignment"], "pairs");
    // The exact method lists exactly the pairs the independent oracle finds.
    assert_eq!(u64_field(check, "exact_pairs"), pairs);
    assert_eq!(u64_field(check, "reported_pairs"), pairs);
}

#[test]
fn stress_samples_clusters_above_the_exact_limit() {
    if !gpu_available() {
        return;
    }
    let r = stress_json(&["--sample", "50", "--lights", "250000", "--size", "32x18"]);
    assert_eq!(r["passed"], true);
    let check = &r["check"];
    assert_eq!(check["mode"], "sampled");
    assert_eq!(check["clusters_checked"], 50);
    assert_eq!(check["misses"], 0);
    assert!(u64_field(check, "exact_pairs") > 0, "{check}");
    assert!(u64_field(check, "reported_pairs") >= u64_field(check, "exact_pairs"));
    assert_stress_stages(&r);
}

#[test]
fn stress_coarsens_the_grid_past_its_pair_budget() {
    if !gpu_available() {
        return;
    }
    // The lists are built on the coarser grid the budget allows, warned about, rendered and
    // checked on that grid; the report gives both grids. Its loop limit is for that grid's slices.
    let run = [
        "stress",
        "--lights",
        "3000",
        "--size",
        "64x36",
        "--pair-budget",
        "5000",
    ];
    let out = myriad_ok(&[&run[..], &["--json"]].concat());
    let r: Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(r["grid_requested"], serde_json::json!([24, 12, 16]));
    assert_eq!(r["pair_budget"], 5000);
    let grid: Vec<u64> = r["grid"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert!(grid.len() == 3 && grid[0] < 24 && grid[2] < 16, "{r}");
    let pairs = u64_field(&r["assignment"], "pairs");
    assert!(pairs <= 5000, "{pairs}");
    assert_eq!(r["passed"], true);
    let check = &r["check"];
    assert_eq!(check["misses"], 0);
    assert_eq!(
        u64_field(check, "clusters_total"),
        grid.iter().product::<u64>()
    );
    assert_eq!(u64_field(check, "reported_pairs"), pairs);
    assert_mentions(
        &stderr(&out),
        &[
            "warning: default scene (atrium): the lists need more pairs than the budget of 5000 \
             pairs (--pair-budget) on the 24x12x16 grid; they were built on the coarser",
            "grid, which the report records",
        ],
    );
    assert_stress_stages(&r);
    // The loop limit's share is for the slices the lists were built on, not --grid's 16.
    if let Some(limit) = r["shader_loop_limit"].as_u64() {
        let want = myriad::gpu::loop_budget::max_lights_per_pixel(
            limit,
            myriad::gpu::ShadingMode::Lists,
            grid[2] as u32,
        );
        assert_eq!(u64_field(&r, "max_lights_per_pixel"), want, "{r}");
        assert_ne!(
            want,
            myriad::gpu::loop_budget::max_lights_per_pixel(
                limit,
                myriad::gpu::ShadingMode::Lists,
                16
            )
        );
    }
    // The table's heading gives both grids.
    let table = myriad_ok(&run);
    let heading = format!(
        "default scene (atrium) — 3000 lights, 64x36, grid {}x{}x{} (coarser than --grid \
         24x12x16: the pairs exceeded the budget), method refined, seed 1",
        grid[0], grid[1], grid[2]
    );
    assert_eq!(stdout(&table).lines().next(), Some(heading.as_str()));
}

#[test]
fn stress_rejects_bad_options_clearly() {
    assert_rejected(&[
        (&["stress", "--lights", "0"], &["--lights", "at least 1"]),
        (
            &["stress", "--sample", "0", "--lights", "10"],
            &["--sample", "at least 1"],
        ),
        (&["stress", "--size", "64"], &["--size", "WxH"]),
        (&["stress", "--method", "guess"], &["guess", "refined"]),
        (&["stress", "--lights", "many"], &["--lights", "many"]),
        (
            &["bench", "--preset", "paper", "--threads", "1000000"],
            &["--threads 1000000", "at most 1024"],
        ),
        (
            &[
                "scene",
                "--gltf",
                "assets/atrium.glb",
                "--field",
                "clumps",
                "--clumps",
                "4294967295",
                "--lights",
                "2",
                "--out",
                "unused.json",
            ],
            &[
                "--clumps 4294967295",
                "between 1 and the number of lights (2)",
            ],
        ),
    ]);
}

/// The milliseconds `myriad stress` printed on stderr for `stage` ("stress: STAGE: done in X ms").
fn stress_progress_ms(stderr: &str, stage: &str) -> f64 {
    let prefix = format!("stress: {stage}: done in ");
    let line = stderr
        .lines()
        .find_map(|l| l.strip_prefix(&prefix))
        .unwrap_or_else(|| panic!("no {prefix:?} line in:\n{stderr}"));
    line.strip_suffix(" ms")
        .and_then(|ms| ms.parse().ok())
        .unwrap_or_else(|| panic!("not a time in ms: {line:?}"))
}

#[test]
fn stress_reports_the_stage_times_its_progress_lines_announced() {
    if !gpu_available() {
        return;
    }
    // Each stage is timed once, announced on stderr in ms to 0.1, and reported in the JSON:
    // the two must be one figure in one unit.
    let out = myriad_ok(&["stress", "--json", "--lights", "20000", "--size", "64x36"]);
    let r: Value = serde_json::from_str(&stdout(&out)).expect("stress --json prints JSON");
    let (err, stages) = (stderr(&out), &r["stages"]);
    let ms = |field: &str| {
        stages[field]
            .as_f64()
            .unwrap_or_else(|| panic!("{field} missing in {stages}"))
    };
    let same = |reported: f64, stage: &str| {
        let announced = stress_progress_ms(&err, stage);
        assert!(
            (reported - announced).abs() <= 0.051,
            "{stage}: {reported} ms reported, {announced} ms announced\n{stages}"
        );
    };
    same(ms("scene_ms"), "scene generation");
    same(ms("assign_ms"), "light assignment (first call, allocating)");
    same(
        ms("assign_again_ms"),
        "light assignment (again, buffers reused)",
    );
    same(ms("device_ms"), "GPU device");
    same(ms("gpu_setup_ms"), "GPU setup (geometry, warm-up)");
    same(
        ms("upload_ms") + ms("encode_ms"),
        "upload + encode + submit",
    );
    // The frame's wall time is the wait for the GPU plus the encode and submit before it.
    same(
        ms("gpu_wall_ms") - ms("encode_ms"),
        "GPU render (clustered)",
    );
    same(ms("gpu_readback_ms"), "GPU lists read back");
    same(ms("check_ms"), "oracle check (every cluster, exact lists)");
    // Each stage is announced as it begins, before its time; the note under the upload carries
    // the report's byte count.
    for stage in [
        "GPU device",
        "scene generation",
        "light assignment (first call, allocating)",
        "GPU setup (geometry, warm-up)",
        "upload + encode + submit",
        "GPU render (clustered)",
    ] {
        let begun = err.find(&format!("stress: {stage}…\n"));
        let done = err.find(&format!("stress: {stage}: done in "));
        assert!(
            begun.is_some_and(|b| done.is_some_and(|d| b < d)),
            "{stage}: not announced before its time in:\n{err}"
        );
    }
    let uploaded = format!(
        "stress:   {} bytes uploaded\n",
        u64_field(&r, "upload_bytes")
    );
    assert!(err.contains(&uploaded), "no {uploaded:?} in:\n{err}");
    // The peak resident size held at least what was uploaded, and no more than the machine has.
    #[cfg(target_os = "linux")]
    {
        let peak = u64_field(&r, "peak_memory_bytes");
        let held = u64_field(&r, "upload_bytes").max(u64_field(&r["assignment"], "list_bytes"));
        let info = std::fs::read_to_string("/proc/meminfo").unwrap();
        let total_kib: u64 = info
            .lines()
            .find_map(|l| l.strip_prefix("MemTotal:"))
            .and_then(|l| l.split_whitespace().next()?.parse().ok())
            .expect("MemTotal in /proc/meminfo");
        assert!(
            held <= peak && peak <= total_kib * 1024,
            "peak {peak} bytes; {held} uploaded; {total_kib} KiB in all"
        );
    }
}

#[test]
fn stress_without_json_prints_the_table_and_its_verdict() {
    if !gpu_available() {
        return;
    }
    let out = myriad_ok(&["stress", "--lights", "3000", "--size", "64x36"]);
    let table = stdout(&out);
    assert_mentions(
        &table,
        &[
            "default scene (atrium) — 3000 lights, 64x36, grid 24x12x16, method refined, seed 1",
            "oracle check (full)",
            "4608 of 4608 clusters",
            "0 misses",
            "peak memory (VmHWM): ",
            "GPU lists read back",
            "identical to the uploaded lists",
            "PASS: no light missing from any checked cluster, and the GPU holds the lists as \
             uploaded",
        ],
    );
    // The lists' size in MiB: 4 bytes for each of 2 × 4608 clusters' offset and count, and for
    // each pair.
    let pairs: u64 = table
        .lines()
        .find(|l| l.starts_with("light assignment (first call, allocating)"))
        .and_then(|l| {
            l.split(" pairs;")
                .next()?
                .split_whitespace()
                .last()?
                .parse()
                .ok()
        })
        .unwrap_or_else(|| panic!("no pairs in the first assignment's row:\n{table}"));
    let mib = (4 * (2 * 4608 + pairs)) as f64 / (1024.0 * 1024.0);
    assert_mentions(&table, &[&format!("; lists {mib:.1} MiB")]);
}

#[test]
fn stress_past_the_shader_loop_limit_suggests_a_finer_grid() {
    if !gpu_available() || !adapter_limits_loops() {
        return;
    }
    // One cluster: a pixel would loop over every visible light (about 100 000 of 150 000),
    // past llvmpipe's budget (65 534). Refused, and told how to shorten the lists.
    let out = myriad_fails(&[
        "stress", "--grid", "1x1x1", "--lights", "150000", "--size", "16x16",
    ]);
    assert_mentions(
        &out,
        &["rendering 150000 lights clustered (a finer --grid gives shorter lists)"],
    );
}

/// Whether the table cell `cell` is `value` rounded to `decimals`: written with exactly that many
/// decimals, and within half a unit of the last one. (Not an exact `format!` of the JSON's
/// number: serde_json parses a decimal to within one ULP, so a value on a rounding tie, such as
/// 100.05, can read back just below it and round the other way: seen once in CI.)
fn rounds(cell: &str, value: f64, decimals: usize) -> bool {
    let written = cell.split_once('.').map_or(0, |(_, d)| d.len());
    let half = 0.5 * 10f64.powi(-(decimals as i32));
    written == decimals
        && cell
            .parse::<f64>()
            .is_ok_and(|c| (c - value).abs() <= half * (1.0 + 1e-9))
}

/// A light buffer the device cannot bind is refused before the scene is generated or assigned
/// (it was refused by the warm-up frame, after both, with advice to "cull first", which `stress`
/// cannot): the message names the most lights the device takes.
#[test]
fn stress_refuses_more_lights_than_the_device_binds_first() {
    let Some(ctx) = myriad::gpu::GpuContext::headless_for_tests() else {
        return;
    };
    let record = std::mem::size_of::<myriad::gpu::layout::GpuLight>() as u64;
    let most = ctx.max_list_pairs() * 4 / record;
    let lights = (most + 1).to_string();
    let err = myriad_fails(&["stress", "--lights", &lights, "--size", "64x36"]);
    assert_mentions(
        &err,
        &[
            &format!("--lights {lights}: the lights buffer needs"),
            &format!("at most {most} lights"),
        ],
    );
    assert!(!err.contains("scene generation"), "{err}");
}
