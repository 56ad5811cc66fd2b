//! A small JSON tree and the typed field readers the scene reader is built from.
//!
//! Why not `serde_json::Value` or `#[derive(Deserialize)]`? Derive stops at the first error and
//! reports a line/column, not a JSON path; `Value` silently keeps only the last of duplicate keys.
//! [`Json`] keeps object entries in order (duplicates included), integers apart from floats, and is
//! built by serde_json's parser, so its recursion limit (128) still guards the stack. The readers
//! below never stop early: each reports its problem into a [`Sink`] and returns `None`, so a caller
//! can collect every problem in a scene.

use crate::error::Problem;
use glam::Vec3;
use serde::de::{self, Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};
use std::fmt;

/// A parsed JSON value.
#[derive(Debug)]
pub(crate) enum Json {
    Null,
    Bool,
    Number(Number),
    String(String),
    Array(Vec<Json>),
    /// Entries in document order, duplicates kept.
    Object(Vec<(String, Json)>),
}

/// A JSON number as serde_json classified it.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Number {
    /// A non-negative integer that fits in u64.
    Unsigned(u64),
    /// A negative integer that fits in i64.
    Negative(i64),
    /// Anything else (fraction, exponent, or an integer too large for 64 bits); always finite,
    /// serde_json rejects numbers beyond the f64 range.
    Float(f64),
}

impl Number {
    fn to_f64(self) -> f64 {
        match self {
            Number::Unsigned(u) => u as f64,
            Number::Negative(i) => i as f64,
            Number::Float(f) => f,
        }
    }
}

impl fmt::Display for Number {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Number::Unsigned(u) => write!(f, "{u}"),
            Number::Negative(i) => write!(f, "{i}"),
            Number::Float(x) => f.write_str(&show_f64(x)),
        }
    }
}

impl Json {
    /// "a number", "an array", … for messages.
    pub(crate) fn kind(&self) -> &'static str {
        match self {
            Json::Null => "null",
            Json::Bool => "a boolean",
            Json::Number(_) => "a number",
            Json::String(_) => "a string",
            Json::Array(_) => "an array",
            Json::Object(_) => "an object",
        }
    }
}

impl<'de> Deserialize<'de> for Json {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(JsonVisitor)
    }
}

struct JsonVisitor;

impl<'de> Visitor<'de> for JsonVisitor {
    type Value = Json;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("any JSON value")
    }
    fn visit_unit<E: de::Error>(self) -> Result<Json, E> {
        Ok(Json::Null)
    }
    fn visit_none<E: de::Error>(self) -> Result<Json, E> {
        Ok(Json::Null)
    }
    fn visit_bool<E: de::Error>(self, _: bool) -> Result<Json, E> {
        Ok(Json::Bool)
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Json, E> {
        Ok(Json::Number(Number::Unsigned(v)))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Json, E> {
        Ok(Json::Number(if v >= 0 {
            Number::Unsigned(v as u64)
        } else {
            Number::Negative(v)
        }))
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Json, E> {
        Ok(Json::Number(Number::Float(v)))
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<Json, E> {
        Ok(Json::String(v.to_owned()))
    }
    fn visit_string<E: de::Error>(self, v: String) -> Result<Json, E> {
        Ok(Json::String(v))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Json, A::Error> {
        let mut items = Vec::new();
        while let Some(item) = seq.next_element()? {
            items.push(item);
        }
        Ok(Json::Array(items))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Json, A::Error> {
        let mut entries = Vec::new();
        while let Some((key, value)) = map.next_entry::<String, Json>()? {
            entries.push((key, value));
        }
        Ok(Json::Object(entries))
    }
}

/// f64 for messages: shortest round-trip text (`1e39`, `0.1`), `inf`/`NaN` when not finite.
pub(crate) fn show_f64(x: f64) -> String {
    if x.is_finite() {
        serde_json::to_string(&x).unwrap_or_else(|_| x.to_string())
    } else {
        x.to_string()
    }
}

/// f32 for messages, like [`show_f64`].
pub(crate) fn show_f32(x: f32) -> String {
    if x.is_finite() {
        serde_json::to_string(&x).unwrap_or_else(|_| x.to_string())
    } else {
        x.to_string()
    }
}

/// A vector for messages: `[1.0, -2.0, inf]`.
pub(crate) fn show_vec3(v: Vec3) -> String {
    format!("[{}, {}, {}]", show_f32(v.x), show_f32(v.y), show_f32(v.z))
}

/// Where problems go, and the path prefix they get: `camera`, `grid`, `lights[3]` or the root.
pub(crate) struct Sink<'p> {
    problems: &'p mut Vec<Problem>,
    prefix: Prefix,
}

/// The most bytes of a problem's path that a [`Sink`] keeps.
const PATH_SHOWN: usize = 80;

/// The path prefix of a [`Sink`].
#[derive(Clone, Copy)]
pub(crate) enum Prefix {
    /// The document root (problems about top-level fields).
    Root,
    /// A top-level section such as `camera`.
    Section(&'static str),
    /// `lights[i]`.
    Light(u32),
}

impl<'p> Sink<'p> {
    pub(crate) fn new(problems: &'p mut Vec<Problem>, prefix: Prefix) -> Self {
        Self { problems, prefix }
    }

    /// Problems reported so far (to tell whether a step added any).
    pub(crate) fn count(&self) -> usize {
        self.problems.len()
    }

    /// Records a problem at `at`, a path relative to the prefix (`""` for the prefix itself).
    /// A path longer than [`PATH_SHOWN`] bytes (an unknown key is the file's own text) is
    /// shortened, so one bad key cannot make a message of megabytes.
    pub(crate) fn report(&mut self, at: &str, message: impl Into<String>) {
        let shortened;
        // An unknown key is the file's text: its control characters are escaped.
        let escaped = crate::printable(at);
        let at = escaped.as_ref();
        let at = if at.len() > PATH_SHOWN {
            let mut end = PATH_SHOWN;
            while !at.is_char_boundary(end) {
                end -= 1;
            }
            shortened = format!("{}… ({} bytes)", &at[..end], at.len());
            shortened.as_str()
        } else {
            at
        };
        let (path, light) = match self.prefix {
            Prefix::Root if at.is_empty() => ("<root>".to_string(), None),
            Prefix::Root => (at.to_string(), None),
            Prefix::Section(s) => (join(s, at), None),
            Prefix::Light(i) => (join(&format!("lights[{i}]"), at), Some(i)),
        };
        self.problems.push(Problem {
            path,
            light,
            message: message.into(),
        });
    }
}

/// `a` + `.` + `b`, without the dot before an index or when either side is empty.
pub(crate) fn join(a: &str, b: &str) -> String {
    if a.is_empty() {
        b.to_string()
    } else if b.is_empty() {
        a.to_string()
    } else if b.starts_with('[') {
        format!("{a}{b}")
    } else {
        format!("{a}.{b}")
    }
}

/// A JSON object whose keys have been checked against the allowed set.
pub(crate) struct Object<'j> {
    entries: &'j [(String, Json)],
    at: String,
}

impl<'j> Object<'j> {
    /// `j` as an object whose keys must all be in `allowed`. Reports unknown and duplicate keys
    /// (the first occurrence of a duplicate is used); returns `None` after reporting when `j` is no
    /// object at all.
    pub(crate) fn new(
        j: &'j Json,
        at: &str,
        allowed: &[&str],
        sink: &mut Sink<'_>,
    ) -> Option<Self> {
        let Json::Object(entries) = j else {
            sink.report(at, format!("expected an object, got {}", j.kind()));
            return None;
        };
        for (n, (key, _)) in entries.iter().enumerate() {
            let path = join(at, key);
            if !allowed.contains(&key.as_str()) {
                let list: Vec<String> = allowed.iter().map(|k| format!("\"{k}\"")).collect();
                sink.report(
                    &path,
                    format!("unknown field; expected one of {}", list.join(", ")),
                );
            } else if entries[..n].iter().any(|(k, _)| k == key) {
                sink.report(&path, "duplicate field (the first one is used)");
            }
        }
        Some(Self {
            entries,
            at: at.to_string(),
        })
    }

    /// Path of field `key` relative to the sink's prefix.
    pub(crate) fn path(&self, key: &str) -> String {
        join(&self.at, key)
    }

    /// A required field; reports it missing.
    pub(crate) fn required(&self, key: &str, sink: &mut Sink<'_>) -> Option<&'j Json> {
        let value = self.lookup(key);
        if value.is_none() {
            sink.report(&self.path(key), "missing required field");
        }
        value
    }

    /// An optional field; absent and `null` both give `None`.
    pub(crate) fn optional(&self, key: &str) -> Option<&'j Json> {
        self.lookup(key).filter(|j| !matches!(j, Json::Null))
    }

    fn lookup(&self, key: &str) -> Option<&'j Json> {
        self.entries.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }
}

/// A number as f64 (exactly as parsed).
pub(crate) fn to_f64(j: &Json, at: &str, sink: &mut Sink<'_>) -> Option<f64> {
    match j {
        Json::Number(n) => Some(n.to_f64()),
        other => {
            sink.report(at, format!("expected a number, got {}", other.kind()));
            None
        }
    }
}

/// A number rounded once to f32; reports numbers beyond the f32 range (e.g. `1e39`), which would
/// otherwise become infinite.
pub(crate) fn to_f32(j: &Json, at: &str, sink: &mut Sink<'_>) -> Option<f32> {
    let x = to_f64(j, at, sink)?;
    let y = x as f32;
    if y.is_finite() {
        Some(y)
    } else {
        let shown = match j {
            Json::Number(n) => n.to_string(),
            _ => show_f64(x),
        };
        sink.report(
            at,
            format!("{shown} is out of the f32 range (magnitude at most 3.4028235e38)"),
        );
        None
    }
}

/// [`to_f32`] for a value that must not be zero (a radius): a non-zero number too small for f32
/// (`1e-46`) is reported as the file wrote it, rather than later as "must be > 0, got 0.0" for a
/// zero the file never held.
pub(crate) fn to_f32_nonzero(j: &Json, at: &str, sink: &mut Sink<'_>) -> Option<f32> {
    let y = to_f32(j, at, sink)?;
    match j {
        Json::Number(n) if y == 0.0 && n.to_f64() != 0.0 => {
            sink.report(
                at,
                format!(
                    "{n} rounds to 0 in f32 (the smallest positive f32 is about 1.4e-45); must be \
                     > 0"
                ),
            );
            None
        }
        _ => Some(y),
    }
}

/// An array of exactly three numbers, each rounded to f32.
pub(crate) fn to_vec3(j: &Json, at: &str, sink: &mut Sink<'_>) -> Option<Vec3> {
    let items = match j {
        Json::Array(items) if items.len() == 3 => items,
        Json::Array(items) => {
            sink.report(
                at,
                format!(
                    "expected an array of 3 numbers, got an array of {}",
                    items.len()
                ),
            );
            return None;
        }
        other => {
            sink.report(
                at,
                format!("expected an array of 3 numbers, got {}", other.kind()),
            );
            return None;
        }
    };
    let mut out = [0.0f32; 3];
    let mut ok = true;
    for (i, item) in items.iter().enumerate() {
        match to_f32(item, &format!("{at}[{i}]"), sink) {
            Some(x) => out[i] = x,
            None => ok = false,
        }
    }
    ok.then(|| Vec3::from_array(out))
}

/// A whole number in `0..=u32::MAX`.
pub(crate) fn to_u32(j: &Json, at: &str, sink: &mut Sink<'_>) -> Option<u32> {
    match j {
        Json::Number(Number::Unsigned(u)) => match u32::try_from(*u) {
            Ok(v) => Some(v),
            Err(_) => {
                sink.report(at, format!("must be at most {}, got {u}", u32::MAX));
                None
            }
        },
        // `1536.0` or `1.536e3`: whole, but written with a fraction or an exponent, which the
        // format refuses for integer fields; "expected a whole number, got 1536.0" contradicted
        // itself (audit).
        Json::Number(Number::Float(f))
            if f.fract() == 0.0 && *f >= 0.0 && *f <= u32::MAX as f64 =>
        {
            sink.report(
                at,
                format!(
                    "expected a whole number written without a fraction or exponent (e.g. {}), \
                     got {f:?}",
                    *f as u32,
                ),
            );
            None
        }
        Json::Number(n) => {
            sink.report(
                at,
                format!("expected a whole number in 0..={}, got {n}", u32::MAX),
            );
            None
        }
        other => {
            sink.report(at, format!("expected a whole number, got {}", other.kind()));
            None
        }
    }
}

/// A string.
pub(crate) fn to_str<'j>(j: &'j Json, at: &str, sink: &mut Sink<'_>) -> Option<&'j str> {
    match j {
        Json::String(s) => Some(s),
        other => {
            sink.report(at, format!("expected a string, got {}", other.kind()));
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Json {
        serde_json::from_str(text).unwrap()
    }

    #[test]
    fn tree_keeps_order_duplicates_and_integer_kinds() {
        let j = parse(r#"{"b": 1, "a": -2, "b": 2.5, "c": [null, true, "s"]}"#);
        let Json::Object(entries) = &j else { panic!() };
        let keys: Vec<&str> = entries.iter().map(|(k, _)| k.as_str()).collect();
        assert_eq!(keys, ["b", "a", "b", "c"]);
        assert!(matches!(entries[0].1, Json::Number(Number::Unsigned(1))));
        assert!(matches!(entries[1].1, Json::Number(Number::Negative(-2))));
        assert!(matches!(entries[2].1, Json::Number(Number::Float(f)) if f == 2.5));
    }

    #[test]
    fn object_reports_unknown_and_duplicate_keys_with_paths() {
        let j = parse(r#"{"radius": 1, "raduis": 2, "radius": 3}"#);
        let mut problems = Vec::new();
        let mut sink = Sink::new(&mut problems, Prefix::Light(7));
        let obj = Object::new(&j, "", &["radius", "position"], &mut sink).unwrap();
        // The first of duplicates wins.
        assert!(matches!(
            obj.required("radius", &mut sink),
            Some(Json::Number(Number::Unsigned(1)))
        ));
        assert!(obj.required("position", &mut sink).is_none());
        let shown: Vec<String> = problems.iter().map(|p| p.to_string()).collect();
        assert_eq!(shown.len(), 3, "{shown:?}");
        assert!(shown[0].starts_with("lights[7].raduis: unknown field; expected one of"));
        assert!(shown[1].starts_with("lights[7].radius: duplicate field"));
        assert_eq!(shown[2], "lights[7].position: missing required field");
        assert!(problems.iter().all(|p| p.light == Some(7)));
    }

    /// An unknown key is the file's own text: a terminal escape or a line break in it is shown
    /// escaped, so a message cannot clear the screen or forge a line of its own (docs/cli.md says
    /// so; only glTF names were tested: audit).
    #[test]
    fn unknown_keys_are_shown_with_their_control_characters_escaped() {
        let j = parse(r#"{"\u001b[2J\r\nerror: fake": 1}"#);
        let mut problems = Vec::new();
        let mut sink = Sink::new(&mut problems, Prefix::Section("camera"));
        Object::new(&j, "", &["fov_y_deg"], &mut sink).unwrap();
        let shown: Vec<String> = problems.iter().map(|p| p.to_string()).collect();
        assert_eq!(shown.len(), 1, "{shown:?}");
        assert!(
            !shown[0].chars().any(char::is_control),
            "raw control characters: {:?}",
            shown[0]
        );
        assert!(
            shown[0].starts_with("camera.\\u{1b}[2J\\r\\nerror: fake: unknown field"),
            "{:?}",
            shown[0]
        );
    }

    #[test]
    fn readers_report_type_length_and_range_problems() {
        let mut problems = Vec::new();
        let mut sink = Sink::new(&mut problems, Prefix::Section("camera"));
        assert!(to_vec3(&parse("[1, 2]"), "position", &mut sink).is_none());
        assert!(to_vec3(&parse(r#"[1, "2", 1e39]"#), "target", &mut sink).is_none());
        assert!(to_u32(&parse("-3"), "width", &mut sink).is_none());
        assert!(to_u32(&parse("24.0"), "width", &mut sink).is_none());
        assert!(to_u32(&parse("4294967296"), "width", &mut sink).is_none());
        assert!(to_str(&parse("5"), "depth", &mut sink).is_none());
        assert_eq!(to_u32(&parse("4294967295"), "x", &mut sink), Some(u32::MAX));
        assert_eq!(
            to_vec3(&parse("[1, -0, 2.5e-3]"), "p", &mut sink),
            Some(Vec3::new(1.0, -0.0, 2.5e-3))
        );
        let shown: Vec<String> = problems.iter().map(|p| p.to_string()).collect();
        assert_eq!(
            shown,
            [
                "camera.position: expected an array of 3 numbers, got an array of 2",
                "camera.target[1]: expected a number, got a string",
                "camera.target[2]: 1e+39 is out of the f32 range (magnitude at most 3.4028235e38)",
                "camera.width: expected a whole number in 0..=4294967295, got -3",
                "camera.width: expected a whole number written without a fraction or exponent \
                 (e.g. 24), got 24.0",
                "camera.width: must be at most 4294967295, got 4294967296",
                "camera.depth: expected a string, got a number",
            ]
        );
    }

    #[test]
    fn a_radius_too_small_for_f32_is_named_as_written() {
        let mut problems = Vec::new();
        let mut sink = Sink::new(&mut problems, Prefix::Light(3));
        assert!(to_f32_nonzero(&parse("1e-46"), "radius", &mut sink).is_none());
        assert!(to_f32_nonzero(&parse("-1e-46"), "radius", &mut sink).is_none());
        // Zero itself, and the smallest f32 subnormal, are left to the range checks.
        assert_eq!(to_f32_nonzero(&parse("0"), "radius", &mut sink), Some(0.0));
        assert_eq!(
            to_f32_nonzero(&parse("1.5e-45"), "radius", &mut sink),
            Some(f32::from_bits(1))
        );
        assert!(to_f32_nonzero(&parse("1e39"), "radius", &mut sink).is_none());
        let shown: Vec<String> = problems.iter().map(|p| p.to_string()).collect();
        assert_eq!(
            shown,
            [
                "lights[3].radius: 1e-46 rounds to 0 in f32 (the smallest positive f32 is about \
                 1.4e-45); must be > 0",
                "lights[3].radius: -1e-46 rounds to 0 in f32 (the smallest positive f32 is about \
                 1.4e-45); must be > 0",
                "lights[3].radius: 1e+39 is out of the f32 range (magnitude at most 3.4028235e38)",
            ]
        );
    }

    #[test]
    fn root_paths() {
        let mut problems = Vec::new();
        let mut sink = Sink::new(&mut problems, Prefix::Root);
        sink.report("", "a");
        sink.report("camera", "b");
        assert_eq!(problems[0].path, "<root>");
        assert_eq!(problems[1].path, "camera");
        assert_eq!(join("lights[1]", "[2]"), "lights[1][2]");
    }
}
