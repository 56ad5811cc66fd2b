//! `myriad scene`: a reproducible scene file, either a standard preset
//! (`--preset P --lights N --seed K --out S`) or a light field placed in a glTF model
//! (`--gltf M --field F --lights N --seed K --out S`).

use super::grid_options::{check_slicing, parse_grid, parse_slicing};
use super::source::{check_memory, parse_preset};
use anyhow::{Context, Result, bail, ensure};
use myriad::scene::{
    ClusterGrid, LightField, Lights, LoadOptions, Placement, RadiusRule, Scene, SpotRule,
    SurfaceSampler, ViewFaces, printable,
};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The light fields `--field` accepts.
const FIELDS: [&str; 5] = ["surfaces", "box", "frustum", "clumps", "sphere"];

#[derive(clap::Args, Debug)]
#[command(group = clap::ArgGroup::new("source").required(true).args(["preset", "gltf"]))]
// `--offset -1` reaches the field's own check ("must be finite and >= 0"), where clap said only
// "unexpected argument '-1' found" (hostile-input hunt, session 38). Ranges (`--radii -1..2`)
// are not numbers: those take `--radii=-1..2`, so that a forgotten value is still clap's
// "a value is required" rather than the next option read as the range (review).
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// A standard scene: paper, uniform or sphere.
    #[arg(long)]
    preset: Option<String>,
    /// Place a light field in this glTF model (.gltf or .glb), e.g. assets/atrium.glb.
    #[arg(long)]
    gltf: Option<PathBuf>,
    /// The light field: surfaces (on the model's triangles, area-weighted), box (uniform in the
    /// model's bounds), frustum (uniform in the camera's view volume), clumps (balls around
    /// random points of the bounds) or sphere (on the bounds' circumscribed sphere)
    /// [default: surfaces].
    #[arg(long, conflicts_with = "preset")]
    field: Option<String>,
    /// The model's camera to use, by name [default: its first camera; with none, a view down
    /// the bounds' long axis].
    #[arg(long, conflicts_with = "preset")]
    camera: Option<String>,
    /// Render width in pixels [default: 1536].
    #[arg(long, conflicts_with = "preset", value_parser = clap::value_parser!(u32).range(1..))]
    width: Option<u32>,
    /// Render height in pixels [default: 768].
    #[arg(long, conflicts_with = "preset", value_parser = clap::value_parser!(u32).range(1..))]
    height: Option<u32>,
    /// Cluster grid as XxYxZ [default: 24x12x16].
    #[arg(long, conflicts_with = "preset")]
    grid: Option<String>,
    /// Depth slicing: log, linear or log_near:D (a first slice to D metres, then log slices)
    /// [default: log].
    #[arg(long, conflicts_with = "preset")]
    depth: Option<String>,
    /// Light radii, uniform in MIN..MAX metres [default: 0.5..3].
    #[arg(long, conflicts_with_all = ["preset", "cutoff"])]
    radii: Option<String>,
    /// Instead of --radii: each radius from its intensity, where intensity·max(colour)/d²
    /// falls to this cut-off.
    #[arg(long, conflicts_with = "preset")]
    cutoff: Option<f32>,
    /// Light intensities, uniform in MIN..MAX (one number: constant) [default: 1].
    #[arg(long, conflicts_with = "preset")]
    intensity: Option<String>,
    /// Fraction of the lights that are spot lights, 0 to 1 [default: 0].
    #[arg(long, conflicts_with = "preset")]
    spots: Option<f32>,
    /// Spot outer half angles in degrees, MIN..MAX [default: 20..45].
    #[arg(long, conflicts_with = "preset")]
    spot_angles: Option<String>,
    /// surfaces: distance of the lights from the surface in metres [default: 0.2].
    #[arg(long, conflicts_with = "preset")]
    offset: Option<f32>,
    /// surfaces: place lights on every face, also those whose lights would lie outside the
    /// model's bounds [default, with the camera inside the bounds: only faces whose lights stay
    /// inside, none on the outside of its outer walls].
    #[arg(long, conflicts_with = "preset")]
    all_faces: bool,
    /// clumps: number of clumps [default: 16].
    #[arg(long, conflicts_with = "preset")]
    clumps: Option<usize>,
    /// clumps: radius of each clump in metres [default: 1].
    #[arg(long, conflicts_with = "preset")]
    spread: Option<f32>,
    /// Number of lights (of the field, with --gltf).
    #[arg(long, value_parser = super::light_count, default_value_t = 1000)]
    lights: usize,
    /// With --gltf: also write the model's own KHR_lights_punctual point and spot lights
    /// (first, with their colours, intensities and cones), before the field's --lights.
    #[arg(long, conflicts_with = "preset")]
    model_lights: bool,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output scene file.
    #[arg(long)]
    out: PathBuf,
}

/// `"a..b"` as `[a, b]`, or `"a"` as `[a, a]`.
fn parse_range(text: &str, what: &str) -> Result<[f32; 2]> {
    let parse = |s: &str| {
        s.trim()
            .parse::<f32>()
            .with_context(|| format!("{what}: {s:?} is not a number (expected MIN..MAX)"))
    };
    match text.split_once("..") {
        Some((a, b)) => Ok([parse(a)?, parse(b)?]),
        None => {
            let v = parse(text)?;
            Ok([v, v])
        }
    }
}

fn gltf_scene(args: &Args, path: &Path) -> Result<(Scene, String)> {
    let (width, height) = (args.width.unwrap_or(1536), args.height.unwrap_or(768));
    let field_name = args.field.as_deref().unwrap_or("surfaces");
    let model = super::source::load_model(path, &LoadOptions::without_images(), &[&args.out])?;
    let bounds = model.bounds();
    if bounds.is_empty() {
        bail!(
            "{}: draws no triangles, so there is nothing to place lights in",
            path.display()
        );
    }
    let (camera, camera_name) = match &args.camera {
        Some(name) => {
            let index = model.camera_index(name).with_context(|| {
                format!(
                    "{}: no camera named {name:?}; it has {}",
                    path.display(),
                    model.camera_names()
                )
            })?;
            let camera = model.camera(index, width, height).with_context(|| {
                format!(
                    "{}: camera {name:?} is orthographic; a perspective one is needed",
                    path.display()
                )
            })?;
            (camera, name.clone())
        }
        None => model
            .camera_or_view(0, width, height)
            .expect("the bounds are not empty"),
    };
    // A model's camera name is the file's text: printed with its control characters escaped.
    let camera_name = printable(&camera_name).into_owned();
    let slicing = parse_slicing(args.depth.as_deref().unwrap_or("log"))?;
    let dims = parse_grid("--grid", args.grid.as_deref().unwrap_or("24x12x16"))?;
    check_slicing(slicing, dims.z, camera.near, camera.far)?;
    let grid = ClusterGrid::try_new(dims, slicing, camera.near, camera.far)
        .with_context(|| format!("{}: camera {camera_name}", path.display()))?;
    // An option of another field would be ignored, silently (audit g2): refused instead.
    for (given, option, field) in [
        (args.offset.is_some(), "--offset", "surfaces"),
        (args.all_faces, "--all-faces", "surfaces"),
        (args.clumps.is_some(), "--clumps", "clumps"),
        (args.spread.is_some(), "--spread", "clumps"),
    ] {
        ensure!(
            !given || field_name == field,
            "{option} only applies to --field {field}, not to --field {field_name}"
        );
    }
    ensure!(
        args.spot_angles.is_none() || args.spots.is_some_and(|f| f != 0.0),
        "--spot-angles only applies with --spots F (a fraction of spot lights above 0)"
    );
    // What the surface field left out, said in the summary line.
    let mut faces_left_out = String::new();
    let placement = match field_name {
        "surfaces" => {
            let offset = args.offset.unwrap_or(0.2);
            let surfaces = if args.all_faces {
                SurfaceSampler::new(&model)
            } else {
                let (kept, left_out) =
                    SurfaceSampler::for_view_counted(&model, camera.position, offset);
                let (mut said, mut lack_of_any) = (Vec::new(), String::new());
                if left_out.pressed > 0 {
                    said.push(format!(
                        "{} pressed flat against others, like a wall's foot on a floor, with \
                         lights that would lie inside the solid",
                        left_out.pressed
                    ));
                }
                if left_out.touching > 0 {
                    said.push(format!(
                        "the parts of {} more where they touch another",
                        left_out.touching
                    ));
                }
                if left_out.unchecked > 0 {
                    lack_of_any += &format!(
                        " ({} faces not searched for where they touch others: too many faces \
                         crowd their planes from both sides; their lights may lie inside what \
                         they rest on)",
                        left_out.unchecked
                    );
                }
                match left_out.view {
                    ViewFaces::SeenFromInside { left_out } if left_out > 0 => {
                        said.push(format!(
                            "{left_out} turned away from the camera, which is inside the \
                             model's bounds, with lights that would lie outside them"
                        ));
                    }
                    // Said, or the lights may all lie outside while the summary reads as if the
                    // faces had been chosen (hostile-input hunt, session 38).
                    ViewFaces::EveryForLackOfAny => {
                        let every = if left_out.pressed > 0 {
                            "every other"
                        } else {
                            "every"
                        };
                        lack_of_any += &format!(
                            " (on {every} face: at --offset {offset} none is turned towards the \
                             camera or keeps its lights inside the model's bounds, where the \
                             camera is)"
                        );
                    }
                    _ => {}
                }
                if !said.is_empty() {
                    let turned_away = match left_out.view {
                        ViewFaces::SeenFromInside { left_out } => left_out,
                        _ => 0,
                    };
                    let faces = kept.triangle_count() + left_out.pressed + turned_away;
                    faces_left_out = format!(
                        " (of {faces} faces left out: {}; --all-faces keeps every face)",
                        said.join("; ")
                    );
                }
                faces_left_out += &lack_of_any;
                kept
            };
            Placement::Surfaces { surfaces, offset }
        }
        "box" => Placement::Box(bounds),
        "frustum" => Placement::Frustum(camera),
        "clumps" => Placement::Clumps {
            within: bounds,
            clumps: {
                let clumps = args.clumps.unwrap_or(16);
                ensure!(
                    (1..=args.lights.max(1)).contains(&clumps),
                    "--clumps {clumps}: between 1 and the number of lights ({})",
                    args.lights
                );
                clumps
            },
            spread: args.spread.unwrap_or(1.0),
        },
        "sphere" => Placement::Sphere {
            center: bounds.center(),
            radius: 0.5 * bounds.size().length(),
        },
        other => bail!(
            "unknown light field {other:?}; expected one of {}",
            FIELDS.join(", ")
        ),
    };
    let radius = match args.cutoff {
        Some(cutoff) => RadiusRule::FromIntensity { cutoff },
        None => {
            let [min, max] = parse_range(args.radii.as_deref().unwrap_or("0.5..3"), "--radii")?;
            RadiusRule::Uniform { min, max }
        }
    };
    let [i0, i1] = parse_range(args.intensity.as_deref().unwrap_or("1"), "--intensity")?;
    let mut field = LightField::new(placement)
        .with_radius(radius)
        .with_intensity(i0, i1);
    // `--spots 0` means no spots (and draws nothing), the same as leaving it out.
    if let Some(fraction) = args.spots.filter(|&f| f != 0.0) {
        let angles = args.spot_angles.as_deref().unwrap_or("20..45");
        field = field.with_spots(SpotRule {
            fraction,
            angle_deg: parse_range(angles, "--spot-angles")?,
        });
    }
    if let Some(problem) = field.problem() {
        bail!(
            "{}: cannot generate the {field_name} light field: {problem}",
            path.display()
        );
    }
    let own = if args.model_lights {
        model.lights.len()
    } else {
        0
    };
    check_memory(&grid, own.saturating_add(args.lights))?;
    // Light indices are u32 (a scene file's lights are numbered in order): past the memory
    // check only on a machine of some 275 GB.
    ensure!(
        own.checked_add(args.lights)
            .is_some_and(|n| n <= u32::MAX as usize),
        "{own} of the model's own lights + --lights {} pass the {} lights a scene can number",
        args.lights,
        u32::MAX
    );
    let mut lights = Lights::new();
    for light in model.lights.iter().take(own) {
        lights.push(light);
    }
    // Numbered after the model's (a scene file lists its lights in that order).
    for (k, light) in field.generate(args.lights, args.seed).iter().enumerate() {
        lights.push(light.with_source_index((own + k) as u32));
    }
    // A scene file holds point and spot lights: the model's directional ones (suns) are not
    // written, and said so.
    let suns = match model.directional_lights.len() {
        0 => String::new(),
        n if args.model_lights => format!(
            "; {n} directional light{} of the model not written: a scene file holds point and \
             spot lights",
            if n == 1 { "" } else { "s" }
        ),
        _ => String::new(),
    };
    let what = format!(
        "{}{} lights, field {}{faces_left_out} in {}, camera {camera_name}, seed {}{suns}",
        if args.model_lights {
            format!("{own} of the model's own + ")
        } else {
            String::new()
        },
        args.lights,
        field_name,
        path.display(),
        args.seed
    );
    // A model can give a camera no scene file may hold (a node scaled to zero puts the target
    // on the eye): blame the model, not the output file.
    let scene = Scene::new(camera, grid, lights);
    if let Some(problem) = scene.problems().first() {
        bail!(
            "{}: the scene made from it (camera {camera_name}) is not valid: {problem}",
            path.display()
        );
    }
    Ok((scene, what))
}

pub fn run(args: Args) -> Result<ExitCode> {
    if let Some(model) = &args.gltf {
        super::outputs::refuse_overwriting_inputs(&args.out, &[model])?;
    }
    let (scene, what) = match (&args.preset, &args.gltf) {
        (Some(name), _) => {
            let preset = parse_preset(name)?;
            check_memory(&preset.view().1, args.lights)?;
            let what = format!(
                "{} preset, {} lights, seed {}",
                preset.name(),
                args.lights,
                args.seed
            );
            (preset.generate(args.lights, args.seed), what)
        }
        (None, Some(path)) => gltf_scene(&args, path)?,
        (None, None) => bail!("give --preset P or --gltf FILE"),
    };
    scene.save(&args.out)?;
    super::outputs::say_written(&args.out, &format!("wrote {} ({what})", args.out.display()));
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse() {
        assert_eq!(parse_range("0.5..3", "r").unwrap(), [0.5, 3.0]);
        assert_eq!(parse_range("2", "r").unwrap(), [2.0, 2.0]);
        assert!(parse_range("a..3", "r").is_err());
    }
}
