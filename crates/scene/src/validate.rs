//! `myriad validate`: every problem in a scene file, not just the first.

use crate::error::{Error, Problem, Result};
use crate::read::{self, Parsed};
use std::fmt;
use std::path::Path;

/// Everything wrong with a scene file. Its [`Display`](fmt::Display) prints one line per problem
/// (`origin: path: message`) and then a summary line; a CLI prints it and exits non-zero unless
/// [`ValidationReport::is_valid`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ValidationReport {
    /// The file path or caller-given origin name.
    pub origin: String,
    /// All problems: root, camera and grid problems first, then lights by index.
    pub problems: Vec<Problem>,
    /// Number of elements in the file's `lights` array.
    pub lights_total: usize,
    /// Number of those with at least one problem.
    pub lights_bad: usize,
}

impl ValidationReport {
    fn from_parsed(parsed: &Parsed, origin: &str) -> Self {
        Self {
            origin: origin.to_string(),
            problems: parsed.all_problems().cloned().collect(),
            lights_total: parsed.light_count,
            lights_bad: parsed.bad_lights.len(),
        }
    }

    /// Whether the file has no problems at all (it loads with [`crate::LightPolicy::Strict`]).
    pub fn is_valid(&self) -> bool {
        self.problems.is_empty()
    }

    /// Number of valid lights.
    pub fn lights_ok(&self) -> usize {
        self.lights_total - self.lights_bad
    }
}

impl fmt::Display for ValidationReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for p in &self.problems {
            writeln!(f, "{}: {p}", self.origin)?;
        }
        let n = self.problems.len();
        let verdict = match n {
            0 => "valid".to_string(),
            1 => "invalid, 1 problem".to_string(),
            n => format!("invalid, {n} problems"),
        };
        write!(
            f,
            "{}: {verdict}; lights: {} ok, {} bad",
            self.origin,
            self.lights_ok(),
            self.lights_bad
        )
    }
}

/// Reads a scene file and lists every problem in it. `Err` only when there is nothing to check:
/// the file cannot be read ([`Error::Read`]) or is not a JSON object ([`Error::Json`], with line
/// and column).
pub fn validate_file(path: impl AsRef<Path>) -> Result<ValidationReport> {
    let path = path.as_ref();
    let bytes = crate::read_regular_file(path).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })?;
    validate_json_slice(&bytes, &path.display().to_string())
}

/// [`validate_file`] for JSON text; `origin` names it in the report.
pub fn validate_json_str(text: &str, origin: &str) -> Result<ValidationReport> {
    validate_json_slice(text.as_bytes(), origin)
}

/// [`validate_file`] for JSON bytes.
pub fn validate_json_slice(bytes: &[u8], origin: &str) -> Result<ValidationReport> {
    let parsed = read::parse_scene(bytes, origin)?;
    Ok(ValidationReport::from_parsed(&parsed, origin))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_lists_every_problem_and_a_summary() {
        let text = r#"{
          "camera": {"position": [0, 0, 0], "target": [0, 0, 0], "fov_y_deg": 200,
                     "width": 0, "height": 10, "near": 1, "far": 1},
          "grid": {"x": 24, "y": 12, "z": 16, "depth": "cubic"},
          "lights": [
            {"position": [0, 0, 0], "radius": 1},
            {"position": [0, 0, 0], "radius": 0, "intensity": -1},
            {"position": [0, 0, 0], "radius": 1, "spot": {"direction": [1, 0, 0], "angle_deg": 181}}
          ]
        }"#;
        let r = validate_json_str(text, "bad.json").unwrap();
        assert!(!r.is_valid());
        assert_eq!((r.lights_total, r.lights_ok(), r.lights_bad), (3, 1, 2));
        let shown = r.to_string();
        let lines: Vec<&str> = shown.lines().collect();
        assert_eq!(
            lines,
            [
                "bad.json: camera.target: must differ from camera.position (both are [0.0, 0.0, 0.0]; the view direction is undefined)",
                "bad.json: camera.fov_y_deg: must be in (0, 180) degrees, got 200.0",
                "bad.json: camera.width: must be at least 1 pixel, got 0",
                "bad.json: camera.far: must be greater than camera.near (1.0), got 1.0",
                r#"bad.json: grid.depth: unknown depth slicing "cubic"; expected "linear", "log" or "log_near""#,
                "bad.json: lights[1].radius: must be finite and > 0, got 0.0",
                "bad.json: lights[1].intensity: must be finite and >= 0, got -1.0",
                "bad.json: lights[2].spot.angle_deg: must be in (0, 180] degrees, got 181.0",
                "bad.json: invalid, 8 problems; lights: 1 ok, 2 bad",
            ]
        );
    }

    #[test]
    fn valid_report() {
        let text = r#"{"camera": {"position": [0, 0, 1], "target": [0, 0, 0], "fov_y_deg": 60,
            "width": 4, "height": 4, "near": 0.5, "far": 9}, "grid": {"x": 1, "y": 1, "z": 1,
            "depth": "linear"}, "lights": [{"position": [0, 0, 0], "radius": 1}]}"#;
        let r = validate_json_str(text, "ok.json").unwrap();
        assert!(r.is_valid());
        assert_eq!(r.to_string(), "ok.json: valid; lights: 1 ok, 0 bad");
    }

    #[test]
    fn syntax_errors_are_errors_with_line_and_column() {
        let e = validate_json_str("{\n  \"camera\": [1,\n", "cut.json").unwrap_err();
        assert_eq!(e.to_string(), "cut.json: cannot parse scene JSON");
        let reason = std::error::Error::source(&e).expect("serde_json's error is the source");
        assert!(reason.to_string().contains("line 3"), "{reason}");
        let e = validate_file("/definitely/not/here.json").unwrap_err();
        assert!(matches!(e, Error::Read { .. }));
        assert!(e.to_string().contains("/definitely/not/here.json"));
    }
}
