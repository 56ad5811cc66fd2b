//! The crate's one error type, and [`Problem`]: a single thing wrong with a scene, located by its JSON
//! path.

use std::fmt;
use std::path::PathBuf;

/// `Result` with this crate's [`Error`] as the default error type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong reading or writing scenes. Every variant names the file (or, for
/// text parsed from memory, the origin name the caller gave).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The file could not be read. The operating system's reason is the error's
    /// [`source`](std::error::Error::source), not repeated in the message (so a printer of the chain, such
    /// as `anyhow`'s `{:#}`, shows it once).
    #[error("cannot read scene file {}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// The file could not be written. The reason is the error's source.
    #[error("cannot write scene file {}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// The text is not JSON (syntax error, truncated text, invalid UTF-8, a number too large for an
    /// f64, nesting deeper than 128), or its top level is not an object. The error's source is
    /// serde_json's message, with the line and column.
    #[error("{origin}: cannot parse scene JSON")]
    Json {
        /// File path or caller-given origin name.
        origin: String,
        /// The parser's error, with line and column.
        source: serde_json::Error,
    },
    /// The text is UTF-16 or UTF-32 (a byte-order mark, or ASCII interleaved with zero bytes),
    /// which some editors save: said plainly rather than as a JSON syntax error at line 1.
    #[error("{origin}: the file is {encoding}; scene files are UTF-8 JSON")]
    Encoding {
        /// File path or caller-given origin name.
        origin: String,
        /// What the file looks like ("UTF-16 (little-endian)", …).
        encoding: &'static str,
    },
    /// The JSON parsed but describes an invalid scene. Holds the first problem (in the order camera,
    /// grid, then lights by index); use [`crate::validate_file`] to list them all.
    #[error("{origin}: {problem}{}", more_problems(*more))]
    Invalid {
        /// File path or caller-given origin name.
        origin: String,
        /// The first problem found.
        problem: Problem,
        /// How many further problems the scene has (0 when this was the only one).
        more: usize,
    },
    /// A glTF file (`.gltf` or `.glb`) could not be read from disk. The operating system's
    /// reason is the error's [`source`](std::error::Error::source), not repeated in the message.
    #[error("cannot read glTF file {}", path.display())]
    GltfRead {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// A glTF file could not be written. The reason is the error's source.
    #[error("cannot write glTF file {}", path.display())]
    GltfWrite {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// A glTF file is broken or uses something this crate cannot load (syntax or schema errors,
    /// indices or byte ranges out of bounds, non-finite values, node cycles, missing buffers, an
    /// undecodable image), or a model cannot be written as glTF. `message` says where in the
    /// document (`meshes[2] "Roof" primitives[0]: …`) and what is wrong.
    #[error("{origin}: {message}")]
    Gltf {
        /// File path or caller-given origin name.
        origin: String,
        /// Where in the document, and what is wrong.
        message: String,
    },
}

fn more_problems(more: usize) -> String {
    match more {
        0 => String::new(),
        1 => " (and 1 more problem)".to_string(),
        n => format!(" (and {n} more problems)"),
    }
}

/// One thing wrong with a scene: where (a JSON path such as `camera.near` or
/// `lights[3].spot.angle_deg`) and what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problem {
    /// JSON path of the offending value: `camera.near`, `grid`, `lights[3].position[1]`. Lights are
    /// indexed by their position in the file's `lights` array. The document root is `<root>`.
    pub path: String,
    /// Index in the file's `lights` array when the problem belongs to one light, else `None`.
    pub light: Option<u32>,
    /// What is wrong, e.g. `must be finite and > 0, got -1`.
    pub message: String,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.path, self.message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_error_names_origin_path_and_count_of_the_rest() {
        let problem = Problem {
            path: "lights[3].radius".into(),
            light: Some(3),
            message: "must be finite and > 0, got -1".into(),
        };
        let e = Error::Invalid {
            origin: "a.json".into(),
            problem: problem.clone(),
            more: 2,
        };
        assert_eq!(
            e.to_string(),
            "a.json: lights[3].radius: must be finite and > 0, got -1 (and 2 more problems)"
        );
        let e = Error::Invalid {
            origin: "a.json".into(),
            problem,
            more: 0,
        };
        assert!(e.to_string().ends_with("got -1"));
    }

    #[test]
    fn io_errors_name_the_path() {
        let e = Error::Read {
            path: "/no/such/scene.json".into(),
            source: std::io::Error::from(std::io::ErrorKind::NotFound),
        };
        assert_eq!(e.to_string(), "cannot read scene file /no/such/scene.json");
        let reason = std::error::Error::source(&e).expect("the io error is the source");
        assert_eq!(reason.to_string(), "entity not found");
    }
}
