//! Step 1 and 2's checks of the container: the GLB header, the asset version, the JSON before
//! the `gltf` crate parses it, its errors in words, and where an external file may be.

use gltf::json;
use std::path::Path;

/// Step 1's GLB header check: what the `gltf` crate's own parsing assumes.
pub(super) fn check_glb_header(bytes: &[u8]) -> Result<(), String> {
    if bytes.len() < 20 {
        return Err(format!(
            "truncated GLB: {} bytes, a header and a chunk header need 20",
            bytes.len()
        ));
    }
    let word =
        |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let version = word(4);
    if version != 2 {
        return Err(format!(
            "GLB version {version}; only version 2 is supported"
        ));
    }
    // The header's length is the whole file's: shorter (bytes after the GLB) is as malformed as
    // longer (a truncated file), and the Khronos validator rejects both.
    let length = word(8) as usize;
    if length != bytes.len() {
        return Err(format!(
            "GLB header declares {length} bytes, but the file has {}",
            bytes.len()
        ));
    }
    check_glb_chunks(bytes)
}

/// The first two chunks after the 12-byte header: a JSON chunk, its length inside the file (and a
/// multiple of 4 when another chunk follows, which must start aligned; the JSON is padded with
/// spaces), then optionally a BIN chunk inside the file. Chunks after those are ignored, as the
/// spec tells loaders (extensions may add them). The `gltf` crate refuses these files in words
/// that name nothing: "unknown chunk type" for a JSON length one off, "JSON chunk length exceeds
/// that of slice" (hostile-input audit).
fn check_glb_chunks(bytes: &[u8]) -> Result<(), String> {
    const JSON: u32 = u32::from_le_bytes(*b"JSON");
    const BIN: u32 = u32::from_le_bytes(*b"BIN\0");
    let word =
        |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let shown = |kind: u32| kind.to_le_bytes().escape_ascii().to_string();
    // The header check saw at least 20 bytes: the JSON chunk's header is there.
    let (json_length, kind) = (word(12) as usize, word(16));
    if kind != JSON {
        return Err(format!(
            "GLB chunk 0 at byte 12 has type \"{}\", not JSON",
            shown(kind)
        ));
    }
    let after_json = bytes.len() - 20;
    if json_length > after_json {
        return Err(format!(
            "the GLB's JSON chunk (at byte 12) declares {json_length} bytes, but only \
             {after_json} follow its header"
        ));
    }
    let at = 20 + json_length;
    if at == bytes.len() {
        return Ok(());
    }
    if !json_length.is_multiple_of(4) {
        return Err(format!(
            "the GLB's JSON chunk declares {json_length} bytes, not a multiple of 4, so the chunk \
             after it (at byte {at}) is misaligned (chunks are 4-byte aligned; the JSON is padded \
             with spaces)"
        ));
    }
    let left = bytes.len() - at;
    if left < 8 {
        return Err(format!(
            "GLB chunk 1 at byte {at}: {left} bytes left, a chunk header needs 8"
        ));
    }
    let (bin_length, kind) = (word(at) as usize, word(at + 4));
    if kind != BIN {
        return Err(format!(
            "GLB chunk 1 at byte {at} has type \"{}\", not BIN",
            shown(kind)
        ));
    }
    if bin_length > left - 8 {
        return Err(format!(
            "the GLB's BIN chunk (at byte {at}) declares {bin_length} bytes, but only {} follow \
             its header",
            left - 8
        ));
    }
    Ok(())
}

/// The spec's rule for loaders: an asset whose major `version` is not 2, or whose `minVersion` is
/// above the 2.0 this loader implements, must not be loaded (a later minor version of 2 may be:
/// it only adds what a 2.0 reader can ignore). The `gltf` crate does not check either.
pub(super) fn check_version(asset: &json::Asset) -> Result<(), String> {
    let parse = |v: &str| {
        let (major, minor) = v.split_once('.')?;
        let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
        (digits(major) && digits(minor)).then(|| (major.parse::<u64>(), minor.parse::<u64>()))
    };
    match parse(&asset.version) {
        Some((Ok(2), _)) => {}
        Some(_) => {
            return Err(format!(
                "asset.version \"{}\": only glTF 2.x is supported",
                asset.version
            ));
        }
        None => {
            return Err(format!(
                "asset.version \"{}\" is not MAJOR.MINOR",
                asset.version
            ));
        }
    }
    if let Some(min) = &asset.min_version {
        match parse(min) {
            Some((Ok(2), Ok(0))) => {}
            Some(_) => {
                return Err(format!(
                    "asset.minVersion \"{min}\": this loader implements glTF 2.0 only"
                ));
            }
            None => return Err(format!("asset.minVersion \"{min}\" is not MAJOR.MINOR")),
        }
    }
    Ok(())
}

/// The `gltf` crate's error, made readable (validation errors listed, at most 5).
/// Checks the gltf crate cannot be trusted with (found by `myriad-fuzz gltf`), made on the raw
/// JSON before it parses it:
/// * an integer of 2³² or more anywhere: gltf-json reads indices as u32 and would silently wrap
///   `4294967296` to index 0 (no file this loader can handle needs such a number);
/// * a primitive whose `POSITION` names an accessor that does not exist: gltf-json 1.4.1's
///   validation indexes `accessors` with it unchecked and panics.
pub(super) fn prevalidate_json(json: &[u8]) -> Result<(), String> {
    let value: serde_json::Value =
        serde_json::from_slice(json).map_err(|e| format!("not valid glTF JSON: {e}"))?;
    fn find_huge(v: &serde_json::Value, path: &mut Vec<String>) -> Option<String> {
        match v {
            serde_json::Value::Number(n) if n.as_u64().is_some_and(|u| u > u32::MAX as u64) => {
                Some(format!(
                    "{}: {n} is out of range (at most {})",
                    path.join(""),
                    u32::MAX
                ))
            }
            serde_json::Value::Array(items) => items.iter().enumerate().find_map(|(i, item)| {
                path.push(format!("[{i}]"));
                let found = find_huge(item, path);
                path.pop();
                found
            }),
            serde_json::Value::Object(fields) => fields.iter().find_map(|(key, item)| {
                path.push(format!(".{key}"));
                let found = find_huge(item, path);
                path.pop();
                found
            }),
            _ => None,
        }
    }
    if let Some(problem) = find_huge(&value, &mut Vec::new()) {
        return Err(problem);
    }
    // A light type the extension does not define fails the crate's parse of the whole file,
    // under its internal name for the path ("extensions.khrLightsPunctual.lights[7].type: Invalid
    // value"): said here in the file's own terms.
    let lights = value["extensions"]["KHR_lights_punctual"]["lights"]
        .as_array()
        .map(Vec::as_slice)
        .unwrap_or_default();
    for (i, light) in lights.iter().enumerate() {
        let Some(kind) = light.get("type") else {
            return Err(format!(
                "extensions.KHR_lights_punctual.lights[{i}]: has no type (\"directional\", \
                 \"point\" or \"spot\")"
            ));
        };
        if !matches!(kind.as_str(), Some("directional" | "point" | "spot")) {
            return Err(format!(
                "extensions.KHR_lights_punctual.lights[{i}].type: {kind} is not a type the \
                 extension defines (\"directional\", \"point\" or \"spot\")"
            ));
        }
    }
    let accessors = value["accessors"].as_array().map_or(0, Vec::len) as u64;
    let meshes = value["meshes"]
        .as_array()
        .map(Vec::as_slice)
        .unwrap_or_default();
    for (m, mesh) in meshes.iter().enumerate() {
        let primitives = mesh["primitives"]
            .as_array()
            .map(Vec::as_slice)
            .unwrap_or_default();
        for (p, primitive) in primitives.iter().enumerate() {
            if let Some(index) = primitive["attributes"]["POSITION"].as_u64()
                && index >= accessors
            {
                return Err(format!(
                    "meshes[{m}].primitives[{p}].attributes.POSITION: accessor {index} does not exist ({accessors} accessors)"
                ));
            }
        }
    }
    Ok(())
}

pub(super) fn describe(e: gltf::Error) -> String {
    match e {
        gltf::Error::Validation(errors) => {
            let mut shown: Vec<String> = errors
                .iter()
                .map(|(path, error)| format!("{path}: {error}"))
                .collect();
            // An unsupported required extension (Draco, say) explains the errors it causes
            // elsewhere (accessors without buffer views): list it first.
            shown.sort_by_key(|s| !s.starts_with("extensionsRequired"));
            shown.truncate(5);
            let more = match errors.len().saturating_sub(5) {
                0 => String::new(),
                n => format!(" (and {n} more)"),
            };
            format!("invalid glTF: {}{more}", shown.join("; "))
        }
        gltf::Error::Deserialize(e) => format!("not valid glTF JSON: {e}"),
        other => other.to_string(),
    }
}

/// Rejects a file that is neither GLB nor JSON by how it starts, so a GLB with a damaged magic
/// (or an image renamed `.glb`) is not reported as a JSON syntax error.
pub(super) fn check_json_start(bytes: &[u8]) -> Result<(), String> {
    let text = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match text.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => Ok(()),
        None => Err("empty: neither GLB nor glTF JSON".to_string()),
        Some(_) => Err(format!(
            "neither GLB (which starts with the magic \"glTF\") nor glTF JSON (an object, \
             starting with '{{'): it starts with {}",
            bytes[..bytes.len().min(4)].escape_ascii()
        )),
    }
}

/// The file an external (non-data) URI names: percent-decoded and relative to `base`. `None` for
/// data URIs and schemes other than `file:` (the crate reports those). An escape that does not
/// decode to UTF-8 is an error here (the crate would panic on it).
///
/// A model reads files only from its own folder and the folders below it: absolute paths,
/// `file:` URIs and paths that climb above the folder (`../`) are refused. The gltf crate would
/// follow them anywhere, so an untrusted model could read `/etc/passwd` as vertices; a portable
/// asset keeps its files beside it, as the glTF specification's examples do. (The check is on the
/// path's text; links inside the model's folder are followed as the file system resolves them.)
pub(super) fn external_file(base: &Path, uri: &str) -> Result<Option<std::path::PathBuf>, String> {
    if uri.contains(':') {
        let file = uri
            .get(..5)
            .is_some_and(|s| s.eq_ignore_ascii_case("file:"));
        return if file {
            Err(format!(
                "URI \"{uri}\": file: URIs are not read; name the file by a path relative to the \
                 glTF file"
            ))
        } else {
            Ok(None)
        };
    }
    let decoded = urlencoding::decode(uri)
        .map_err(|_| format!("URI \"{uri}\" does not percent-decode to UTF-8"))?;
    let path = Path::new(&*decoded);
    let outside = || {
        format!(
            "URI \"{uri}\" names a file outside the glTF file's folder; only files in that folder \
             and below are read"
        )
    };
    if path.has_root() {
        return Err(outside());
    }
    let mut depth = 0usize;
    for part in path.components() {
        match part {
            std::path::Component::ParentDir => {
                depth = depth.checked_sub(1).ok_or_else(outside)?;
            }
            std::path::Component::Normal(_) => depth += 1,
            _ => {}
        }
    }
    Ok(Some(base.join(path)))
}
