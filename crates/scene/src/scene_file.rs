//! [`Scene`]: camera, cluster grid and lights, read from and written to the scene-file format.

use crate::checks::{self, CameraParts, GridParts, deg_to_rad, fov_deg_ok, spot_deg_ok};
use crate::error::{Error, Problem, Result};
use crate::json::{Prefix, Sink, show_f32};
use crate::lights::Lights;
use crate::read::{self, DEPTH_LINEAR, DEPTH_LOG, DEPTH_LOG_NEAR, Parsed};
use myriad_cluster_math::{Camera, ClusterGrid, DepthSlicing};
use std::fmt;
use std::io::Write as _;
use std::path::Path;

/// What to do with invalid lights when reading a scene. Camera and grid problems are always
/// errors.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightPolicy {
    /// The first invalid light is an error that names its index and what is wrong.
    #[default]
    Strict,
    /// Invalid lights are left out of [`Scene::lights`] and listed in [`Scene::skipped`].
    SkipInvalid,
}

/// A light that was left out under [`LightPolicy::SkipInvalid`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SkippedLight {
    /// Index in the file's `lights` array.
    pub index: u32,
    /// Every problem with it, `; `-separated, each as `path: message`.
    pub reason: String,
}

impl fmt::Display for SkippedLight {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "light {} skipped: {}", self.index, self.reason)
    }
}

/// A scene: what a scene file describes. Built by reading a file, or in code with [`Scene::new`].
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The camera.
    pub camera: Camera,
    /// The cluster grid, over the camera's `[near, far]`.
    pub grid: ClusterGrid,
    /// The (valid) lights, in file order, each with its index in the file.
    pub lights: Lights,
    /// Lights of the file that were invalid and left out (only with
    /// [`LightPolicy::SkipInvalid`]); empty for scenes built in code.
    pub skipped: Vec<SkippedLight>,
}

impl Scene {
    /// A scene from parts, with nothing skipped. Values are not checked here; see
    /// [`Scene::problems`].
    pub fn new(camera: Camera, grid: ClusterGrid, lights: Lights) -> Self {
        Self {
            camera,
            grid,
            lights,
            skipped: Vec::new(),
        }
    }

    /// Reads and checks a scene file. Errors name the file; see [`Scene::from_json_str`].
    pub fn load(path: impl AsRef<Path>, policy: LightPolicy) -> Result<Self> {
        let path = path.as_ref();
        let bytes = crate::read_regular_file(path).map_err(|source| Error::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_json_slice(&bytes, &path.display().to_string(), policy)
    }

    /// Reads and checks a scene from JSON text; `origin` names it in errors (a file name, or
    /// something like `"<stdin>"`).
    ///
    /// Errors: [`Error::Json`] when the text is not a JSON object; [`Error::Invalid`] with the
    /// first problem otherwise — a camera or grid problem, a missing or unknown field, or (with
    /// [`LightPolicy::Strict`]) the first invalid light, named by its index.
    pub fn from_json_str(text: &str, origin: &str, policy: LightPolicy) -> Result<Self> {
        Self::from_json_slice(text.as_bytes(), origin, policy)
    }

    /// [`Scene::from_json_str`] for bytes (e.g. a file's contents; invalid UTF-8 is an error, not a
    /// panic).
    pub fn from_json_slice(bytes: &[u8], origin: &str, policy: LightPolicy) -> Result<Self> {
        let parsed = read::parse_scene(bytes, origin)?;
        Self::from_parsed(parsed, origin, policy)
    }

    fn from_parsed(parsed: Parsed, origin: &str, policy: LightPolicy) -> Result<Self> {
        let more = parsed.problem_count().saturating_sub(1);
        let invalid = |problem: &Problem| Error::Invalid {
            origin: origin.to_string(),
            problem: problem.clone(),
            more,
        };
        if let Some(first) = parsed.scene_problems.first() {
            return Err(invalid(first));
        }
        if policy == LightPolicy::Strict
            && let Some(first) = parsed.bad_lights.first().and_then(|(_, p)| p.first())
        {
            return Err(invalid(first));
        }
        let (Some(camera), Some(grid)) = (parsed.camera, parsed.grid) else {
            // Unreachable: without scene problems both were built. Kept as an error, not a panic.
            return Err(invalid(&Problem {
                path: "<root>".into(),
                light: None,
                message: "camera or grid could not be built".into(),
            }));
        };
        let skipped = parsed
            .bad_lights
            .into_iter()
            .map(|(index, problems)| SkippedLight {
                index,
                reason: problems
                    .iter()
                    .map(|p| p.to_string())
                    .collect::<Vec<_>>()
                    .join("; "),
            })
            .collect();
        Ok(Self {
            camera,
            grid,
            lights: parsed.lights,
            skipped,
        })
    }

    /// Everything that keeps this scene from being written and read back: the same checks the
    /// reader applies, plus the grid's depth range having to equal the camera's near/far (a
    /// fitted range cannot be expressed in a scene file) and the [`Lights`] invariants. Lights
    /// are located by their `source_index`. Empty for any scene read from a file.
    pub fn problems(&self) -> Vec<Problem> {
        let mut problems = Vec::new();
        let camera = checks::check_camera(
            &CameraParts::from(&self.camera),
            &mut Sink::new(&mut problems, Prefix::Section("camera")),
        );
        let mut sink = Sink::new(&mut problems, Prefix::Section("grid"));
        let g = &self.grid;
        let parts = GridParts {
            dims: g.dims().to_array().map(Some),
            slicing: Some(g.slicing()),
        };
        checks::check_grid(&parts, camera.depth_range, &mut sink);
        if (g.near(), g.far()) != (self.camera.near, self.camera.far) {
            sink.report(
                "",
                format!(
                    "depth range [{}, {}] differs from the camera's near/far [{}, {}]; a scene \
                     file's grid always spans the camera's range",
                    show_f32(g.near()),
                    show_f32(g.far()),
                    show_f32(self.camera.near),
                    show_f32(self.camera.far)
                ),
            );
        }
        problems.extend(self.lights.problems());
        problems
    }

    /// The scene in the scene-file format: one line for the camera, one for the grid, one per
    /// light. Lights are written in `source_index` order (and so are renumbered 0, 1, … in the
    /// written file); skipped lights are not written. Every f32 is written as its shortest
    /// round-trip decimal and angles so that they convert back to the same radians, so reading the
    /// text back gives bit-identical camera, grid and lights.
    ///
    /// Errors with [`Error::Invalid`] (origin `<scene>`) when [`Scene::problems`] finds any.
    pub fn to_json_string(&self) -> Result<String> {
        self.to_json_named("<scene>")
    }

    /// Writes [`Scene::to_json_string`] to `path`, replacing it only once complete
    /// ([`crate::replace_file()`]). Errors name the file.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let text = self.to_json_named(&path.display().to_string())?;
        crate::replace_file(path, text.as_bytes()).map_err(|source| Error::Write {
            path: path.to_path_buf(),
            source,
        })
    }

    fn to_json_named(&self, origin: &str) -> Result<String> {
        let problems = self.problems();
        if let Some(first) = problems.first() {
            return Err(Error::Invalid {
                origin: origin.to_string(),
                problem: first.clone(),
                more: problems.len() - 1,
            });
        }
        let mut out = Vec::with_capacity(256 + 160 * self.lights.len());
        self.write_json(&mut out).map_err(|source| Error::Json {
            origin: origin.to_string(),
            source,
        })?;
        Ok(String::from_utf8_lossy(&out).into_owned())
    }

    fn write_json(&self, out: &mut Vec<u8>) -> serde_json::Result<()> {
        let io = serde_json::Error::io;
        let c = &self.camera;
        out.extend_from_slice(b"{\n  \"camera\": {\"position\": ");
        write_vec3(out, [c.position.x, c.position.y, c.position.z])?;
        out.extend_from_slice(b", \"target\": ");
        write_vec3(out, [c.target.x, c.target.y, c.target.z])?;
        out.extend_from_slice(b", \"up\": ");
        write_vec3(out, [c.up.x, c.up.y, c.up.z])?;
        write!(
            out,
            ", \"fov_y_deg\": {}, \"width\": {}, \"height\": {}, \"near\": ",
            degrees_text(c.fov_y, fov_deg_ok),
            c.width,
            c.height
        )
        .map_err(io)?;
        write_f32(out, c.near)?;
        out.extend_from_slice(b", \"far\": ");
        write_f32(out, c.far)?;
        let g = &self.grid;
        write!(
            out,
            "}},\n  \"grid\": {{\"x\": {}, \"y\": {}, \"z\": {}, \"depth\": ",
            g.dims().x,
            g.dims().y,
            g.dims().z
        )
        .map_err(io)?;
        match g.slicing() {
            DepthSlicing::Linear => write!(out, "\"{DEPTH_LINEAR}\"").map_err(io)?,
            DepthSlicing::Log => write!(out, "\"{DEPTH_LOG}\"").map_err(io)?,
            DepthSlicing::LogWithNearSlice { first_slice_depth } => {
                write!(out, "\"{DEPTH_LOG_NEAR}\", \"first_slice_depth\": ").map_err(io)?;
                write_f32(out, first_slice_depth)?;
            }
        }
        out.extend_from_slice(b"},\n  \"lights\": [");
        let l = &self.lights;
        let mut order: Vec<usize> = (0..l.len()).collect();
        if !l.source_index.is_sorted() {
            order.sort_by_key(|&i| l.source_index[i]);
        }
        for (n, &i) in order.iter().enumerate() {
            out.extend_from_slice(if n == 0 { b"\n    " } else { b",\n    " });
            out.extend_from_slice(b"{\"position\": ");
            write_vec3(out, [l.x[i], l.y[i], l.z[i]])?;
            out.extend_from_slice(b", \"radius\": ");
            write_f32(out, l.radius[i])?;
            out.extend_from_slice(b", \"color\": ");
            write_vec3(out, [l.r[i], l.g[i], l.b[i]])?;
            out.extend_from_slice(b", \"intensity\": ");
            write_f32(out, l.intensity[i])?;
            if l.is_spot(i) {
                out.extend_from_slice(b", \"spot\": {\"direction\": ");
                write_vec3(out, [l.spot_dir_x[i], l.spot_dir_y[i], l.spot_dir_z[i]])?;
                let (outer, inner) = (l.spot_angle[i], l.spot_inner_angle[i]);
                write!(out, ", \"angle_deg\": {}", degrees_text(outer, spot_deg_ok)).map_err(io)?;
                // Only when it is not the default the reader gives a spot without one, so files
                // of spots without inner angles read and write back as they were.
                if inner != crate::default_spot_inner_angle(outer) {
                    let text = degrees_text(inner, |d| d.is_finite() && d >= 0.0);
                    write!(out, ", \"inner_angle_deg\": {text}").map_err(io)?;
                }
                out.push(b'}');
            }
            out.push(b'}');
        }
        out.extend_from_slice(if order.is_empty() {
            b"]\n}\n"
        } else {
            b"\n  ]\n}\n"
        });
        Ok(())
    }
}

fn write_f32(out: &mut Vec<u8>, x: f32) -> serde_json::Result<()> {
    serde_json::to_writer(out, &x)
}

fn write_vec3(out: &mut Vec<u8>, v: [f32; 3]) -> serde_json::Result<()> {
    out.push(b'[');
    write_f32(out, v[0])?;
    out.extend_from_slice(b", ");
    write_f32(out, v[1])?;
    out.extend_from_slice(b", ");
    write_f32(out, v[2])?;
    out.push(b']');
    Ok(())
}

/// Decimal degrees that the reader converts back to exactly `rad` and that pass `valid`: the
/// shortest f32 text when one of the three f32 values nearest to the exact degrees works (the
/// usual case: 60 → "60.0"), else the f64 degrees, whose f64 → radians → f32 trip errs by a few
/// f64 ulps, far below half an f32 ulp.
fn degrees_text(rad: f32, valid: fn(f64) -> bool) -> String {
    // Each candidate is judged by what the reader will make of its text (decimal -> f64 by
    // serde_json), not by its binary value.
    let reads_back = |text: &str| {
        serde_json::from_str::<f64>(text).is_ok_and(|d| valid(d) && deg_to_rad(d) == rad)
    };
    let exact = (rad as f64).to_degrees();
    let c = exact as f32;
    for candidate in [c, c.next_down(), c.next_up()] {
        let text = show_f32(candidate);
        if candidate.is_finite() && reads_back(&text) {
            return text;
        }
    }
    for candidate in [exact, exact.next_down(), exact.next_up()] {
        let text = crate::json::show_f64(candidate);
        if reads_back(&text) {
            return text;
        }
    }
    // Not reached for valid angles: the f64 degrees err by a few f64 ulps, far below half an f32
    // ulp.
    crate::json::show_f64(exact)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lights::LightRecord;
    use glam::{UVec3, Vec3};
    use std::f32::consts::PI;

    fn scene() -> Scene {
        let camera = Camera::new(
            Vec3::new(0.0, 2.0, 10.0),
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::Y,
            60.0,
            1536,
            768,
            0.1,
            100.0,
        );
        let grid = ClusterGrid::new(UVec3::new(24, 12, 16), DepthSlicing::Log, 0.1, 100.0);
        let lights = [
            LightRecord::point(Vec3::new(1.0, 2.0, 3.0), 2.5),
            LightRecord::point(Vec3::new(-0.0, 0.1, 1e-30), 0.3)
                .with_color(Vec3::new(0.2, 0.4, 1.0))
                .with_intensity(3.0)
                .with_spot(Vec3::new(0.0, -1.0, 0.0), 0.7)
                .with_source_index(1),
        ]
        .into_iter()
        .collect();
        Scene::new(camera, grid, lights)
    }

    #[test]
    fn degrees_text_round_trips_and_is_short_for_common_angles() {
        assert_eq!(degrees_text(deg_to_rad(60.0), fov_deg_ok), "60.0");
        assert_eq!(degrees_text(deg_to_rad(180.0), spot_deg_ok), "180.0");
        assert_eq!(degrees_text(PI, spot_deg_ok), "180.0");
        assert_eq!(degrees_text(deg_to_rad(45.5), spot_deg_ok), "45.5");
        for rad in [
            f32::from_bits(1),
            1e-40,
            f32::MIN_POSITIVE,
            1e-20,
            PI.next_down(),
        ] {
            let text = degrees_text(rad, spot_deg_ok);
            let deg: f64 = serde_json::from_str(&text).unwrap();
            assert_eq!(deg_to_rad(deg), rad, "{rad} -> {text}");
        }
        // A sweep over f32 angles, including ones no f32 degree value maps to.
        let mut rad = 1e-6f32;
        while rad < PI {
            let text = degrees_text(rad, fov_deg_ok);
            let deg: f64 = serde_json::from_str(&text).unwrap();
            assert!(fov_deg_ok(deg), "{rad} -> {text}");
            assert_eq!(deg_to_rad(deg), rad, "{rad} -> {text}");
            rad = f32::from_bits(rad.to_bits() + 997);
        }
    }

    #[test]
    fn writes_one_line_per_light_in_source_order() {
        let mut s = scene();
        // Reverse the columns: the writer restores source order.
        let rows: Vec<LightRecord> = s.lights.iter().rev().collect();
        s.lights = rows.into_iter().collect();
        let text = s.to_json_string().unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 8, "{text}");
        assert_eq!(
            lines[1],
            r#"  "camera": {"position": [0.0, 2.0, 10.0], "target": [0.0, 2.0, 0.0], "up": [0.0, 1.0, 0.0], "fov_y_deg": 60.0, "width": 1536, "height": 768, "near": 0.1, "far": 100.0},"#
        );
        assert_eq!(
            lines[2],
            r#"  "grid": {"x": 24, "y": 12, "z": 16, "depth": "log"},"#
        );
        assert_eq!(
            lines[4],
            r#"    {"position": [1.0, 2.0, 3.0], "radius": 2.5, "color": [1.0, 1.0, 1.0], "intensity": 1.0},"#
        );
        assert!(lines[5].contains(r#""spot": {"direction": [0.0, -1.0, 0.0], "angle_deg": "#));
        let back = Scene::from_json_str(&text, "t", LightPolicy::Strict).unwrap();
        assert_eq!(back.lights, scene().lights);
    }

    /// A spot's own inner angle is written and read back; the default one is not written, so a
    /// file of spots without inner angles is written back as it was.
    #[test]
    fn spot_inner_angles_are_written_unless_they_are_the_default() {
        let mut s = scene();
        let text = s.to_json_string().unwrap();
        assert!(!text.contains("inner_angle_deg"), "{text}");
        let spot = s.lights.get(1).with_spot_inner_angle(0.25);
        let point = s.lights.get(0);
        s.lights = [point, spot].into_iter().collect();
        let text = s.to_json_string().unwrap();
        assert!(text.contains(r#""inner_angle_deg": "#), "{text}");
        let back = Scene::from_json_str(&text, "t", LightPolicy::Strict).unwrap();
        assert_eq!(back.lights.spot_inner_angle, [0.0, 0.25]);
        assert_eq!(back.lights, s.lights);
    }

    #[test]
    fn empty_lights_and_log_near_are_written() {
        let mut s = scene();
        s.lights = Lights::new();
        s.grid = ClusterGrid::new(
            UVec3::new(2, 3, 4),
            DepthSlicing::LogWithNearSlice {
                first_slice_depth: 5.0,
            },
            0.1,
            100.0,
        );
        let text = s.to_json_string().unwrap();
        assert!(text.ends_with("\"lights\": []\n}\n"), "{text}");
        assert!(text.contains(r#""depth": "log_near", "first_slice_depth": 5.0}"#));
        assert_eq!(
            Scene::from_json_str(&text, "t", LightPolicy::Strict).unwrap(),
            s
        );
    }

    #[test]
    fn invalid_scenes_are_not_written() {
        let mut s = scene();
        s.lights.radius[0] = f32::NAN;
        s.grid = s.grid.with_depth_range(1.0, 50.0);
        let e = s.to_json_string().unwrap_err().to_string();
        assert!(
            e.starts_with("<scene>: grid: depth range [1.0, 50.0] differs"),
            "{e}"
        );
        assert!(e.ends_with("(and 1 more problem)"), "{e}");
        let problems = s.problems();
        assert_eq!(problems[1].path, "lights[0].radius");
    }

    #[test]
    fn a_scene_built_with_a_bad_camera_is_not_written() {
        // The camera built in code is checked as a read one is: a 0-pixel-wide camera would be
        // written to a file that cannot be read back.
        let mut s = scene();
        s.camera.width = 0;
        let paths: Vec<String> = s.problems().into_iter().map(|p| p.path).collect();
        assert_eq!(paths, ["camera.width"]);
        assert_eq!(
            s.to_json_string().unwrap_err().to_string(),
            "<scene>: camera.width: must be at least 1 pixel, got 0"
        );
    }

    #[test]
    fn a_radius_that_underflows_f32_is_skipped_as_the_file_wrote_it() {
        // 1e-46 is a positive radius in the file, and 0 once rounded to f32: the reason names
        // the file's value, not the "got 0.0" of a zero the file never held.
        let text = scene()
            .to_json_string()
            .unwrap()
            .replace(r#""radius": 0.3"#, r#""radius": 1e-46"#);
        let s = Scene::from_json_str(&text, "my.json", LightPolicy::SkipInvalid).unwrap();
        assert_eq!(s.lights.source_index, [0]);
        assert_eq!(
            s.skipped[0].to_string(),
            "light 1 skipped: lights[1].radius: 1e-46 rounds to 0 in f32 (the smallest positive \
             f32 is about 1.4e-45); must be > 0"
        );
    }

    #[test]
    fn utf16_and_utf32_files_are_named_as_such() {
        let text = scene().to_json_string().unwrap();
        let utf16le: Vec<u8> = text.encode_utf16().flat_map(u16::to_le_bytes).collect();
        let utf16be: Vec<u8> = text.encode_utf16().flat_map(u16::to_be_bytes).collect();
        let utf32le: Vec<u8> = text
            .chars()
            .flat_map(|c| (c as u32).to_le_bytes())
            .collect();
        let utf32be: Vec<u8> = text
            .chars()
            .flat_map(|c| (c as u32).to_be_bytes())
            .collect();
        let with_bom = |bom: &[u8], body: &[u8]| [bom, body].concat();
        let cases = [
            (
                with_bom(&[0xFF, 0xFE], &utf16le),
                "UTF-16 (little-endian, with a byte-order mark)",
            ),
            (
                with_bom(&[0xFE, 0xFF], &utf16be),
                "UTF-16 (big-endian, with a byte-order mark)",
            ),
            (utf16le, "UTF-16 (little-endian)"),
            (utf16be, "UTF-16 (big-endian)"),
            (
                with_bom(&[0xFF, 0xFE, 0, 0], &utf32le),
                "UTF-32 (little-endian, with a byte-order mark)",
            ),
            (utf32le, "UTF-32 (little-endian)"),
            (
                with_bom(&[0, 0, 0xFE, 0xFF], &utf32be),
                "UTF-32 (big-endian, with a byte-order mark)",
            ),
            (utf32be, "UTF-32 (big-endian)"),
        ];
        for (bytes, encoding) in cases {
            let e = Scene::from_json_slice(&bytes, "w.json", LightPolicy::Strict).unwrap_err();
            assert_eq!(
                e.to_string(),
                format!("w.json: the file is {encoding}; scene files are UTF-8 JSON")
            );
            let e = crate::validate_json_slice(&bytes, "w.json").unwrap_err();
            assert!(matches!(e, Error::Encoding { .. }), "{e}");
        }
        // Zero bytes alone, or a non-ASCII byte beside them, name no encoding: not JSON.
        for bytes in [vec![0u8; 16], [0xC3, 0, 0, 0, 0xC3, 0].to_vec()] {
            let e = Scene::from_json_slice(&bytes, "z.json", LightPolicy::Strict).unwrap_err();
            assert!(matches!(e, Error::Json { .. }), "{e}");
        }
        // UTF-8, with or without its byte-order mark, reads.
        let bom = [b"\xEF\xBB\xBF".as_slice(), text.as_bytes()].concat();
        Scene::from_json_slice(&bom, "w.json", LightPolicy::Strict).unwrap();
    }

    #[test]
    fn a_light_whose_radiance_overflows_f32_is_skipped() {
        // Colour and intensity are each finite, their product is not: the renderer would show
        // nothing of the light while the lists hold it.
        let written = scene().to_json_string().unwrap();
        let text = written
            .replace(r#""intensity": 3.0"#, r#""intensity": 1e38"#)
            .replace("[0.2, 0.4, 1.0]", "[0, 1e38, 0]");
        assert_eq!(text.matches("1e38").count(), 2, "{written}");
        let s = Scene::from_json_str(&text, "my.json", LightPolicy::SkipInvalid).unwrap();
        assert_eq!(s.lights.source_index, [0]);
        assert_eq!(
            s.skipped[0].to_string(),
            "light 1 skipped: lights[1].intensity: 1e+38 times color [0.0, 1e+38, 0.0] \
             overflows f32 (at most 3.4028235e+38 a channel)"
        );
    }

    #[test]
    fn strict_fails_on_first_bad_light_and_skip_lists_them() {
        // The writer refuses invalid lights, so break light 1 in the text.
        let text = scene()
            .to_json_string()
            .unwrap()
            .replace(r#""radius": 0.3"#, r#""radius": -2"#);
        let e = Scene::from_json_str(&text, "my.json", LightPolicy::Strict).unwrap_err();
        assert_eq!(
            e.to_string(),
            "my.json: lights[1].radius: must be finite and > 0, got -2.0"
        );
        let s = Scene::from_json_str(&text, "my.json", LightPolicy::SkipInvalid).unwrap();
        assert_eq!(s.lights.len(), 1);
        assert_eq!(s.lights.source_index, [0]);
        assert!(!s.lights.has_spots());
        assert_eq!(
            s.skipped,
            [SkippedLight {
                index: 1,
                reason: "lights[1].radius: must be finite and > 0, got -2.0".into()
            }]
        );
        assert_eq!(
            s.skipped[0].to_string(),
            "light 1 skipped: lights[1].radius: must be finite and > 0, got -2.0"
        );
        // Camera problems are errors under either policy.
        let bad_camera = text.replace(r#""near": 0.1"#, r#""near": 0"#);
        for policy in [LightPolicy::Strict, LightPolicy::SkipInvalid] {
            let e = Scene::from_json_str(&bad_camera, "my.json", policy).unwrap_err();
            assert!(
                e.to_string()
                    .starts_with("my.json: camera.near: must be finite and at least 1e-12")
            );
        }
    }
}
