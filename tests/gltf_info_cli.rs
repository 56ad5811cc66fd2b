//! `myriad info --gltf FILE [--json]` end to end: the numbers it prints are the loader's, it
//! exits 0 on good files and 2 (a run that could not finish) with a message naming the file on
//! bad ones.

use myriad::scene::{LoadOptions, Model, Projection};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn myriad(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_myriad"))
        .args(args)
        .output()
        .expect("cannot run the myriad binary")
}

fn work_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("gltf_info")
        .join(test);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn atrium_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/atrium.glb")
}

fn info_json(path: &Path) -> Value {
    let out = myriad(&[
        "info".as_ref(),
        "--gltf".as_ref(),
        path.as_os_str(),
        "--json".as_ref(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

#[test]
fn info_reports_what_the_loader_sees() {
    let path = atrium_path();
    let model = Model::load(&path, &LoadOptions::without_images()).unwrap();
    let s = model.summary();
    let v = info_json(&path);
    assert_eq!(v["meshes"], s.meshes);
    assert_eq!(v["instances"], s.instances);
    assert_eq!(v["triangles"], s.triangles);
    assert_eq!(v["stored_triangles"], s.stored_triangles);
    assert_eq!(v["materials"], s.materials);
    assert_eq!(v["blended_materials"], s.blended_materials);
    assert_eq!(v["lights"]["point"], s.point_lights);
    assert_eq!(v["lights"]["spot"], s.spot_lights);
    assert_eq!(v["lights"]["skipped"], s.skipped_lights);
    let names: Vec<&str> = v["cameras"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, s.cameras);
    // Each perspective camera's field of view in degrees, to 4 decimals.
    let mut perspective = 0;
    for (camera, shown) in model.cameras.iter().zip(v["cameras"].as_array().unwrap()) {
        if let Projection::Perspective { yfov, .. } = camera.projection {
            let deg = shown["yfov_deg"].as_f64().unwrap();
            let want = f64::from(yfov).to_degrees();
            assert!(
                (deg - want).abs() <= 5e-5,
                "{}: {deg} vs {want}",
                camera.name
            );
            perspective += 1;
        }
    }
    assert!(perspective > 0, "the atrium has perspective cameras");
    for (k, bound) in [("min", s.bounds.min), ("max", s.bounds.max)] {
        // Written as the f32's shortest decimal: it reads back to the same f32.
        let shown: Vec<f32> = v["bounds"][k]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap() as f32)
            .collect();
        assert_eq!(shown, bound.to_array());
    }
    // The table shows the same counts.
    let out = myriad(&["info".as_ref(), "--gltf".as_ref(), path.as_os_str()]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains(&format!("instances   {}", s.instances)),
        "{text}"
    );
    assert!(
        text.contains("cameras     4: Main, Gallery, Overview, Courtyard"),
        "{text}"
    );
    assert!(
        text.contains("[-15.000, -0.200, -7.500] .. [15.000, 13.000, 7.500]"),
        "{text}"
    );
    // The atrium loads without warnings, and the table has no warnings line then.
    assert!(model.warnings.is_empty(), "{:?}", model.warnings);
    assert!(!text.contains("warnings"), "{text}");
}

#[test]
fn info_on_sponza_counts_instanced_triangles() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/sponza/Sponza.gltf");
    if !path.exists() {
        eprintln!(
            "NOTE: {} is absent; `myriad info` is checked on the shipped atrium only",
            path.display()
        );
        let v = info_json(&atrium_path());
        assert!(v["triangles"].as_u64().unwrap() > v["stored_triangles"].as_u64().unwrap());
        return;
    }
    let v = info_json(&path);
    assert_eq!(v["triangles"], 262_087);
    assert_eq!(v["instances"], 170);
    assert_eq!(v["meshes"], 44);
    assert_eq!(v["cameras"][0]["name"], "CameraMain");
    let out = myriad(&["info".as_ref(), "--gltf".as_ref(), path.as_os_str()]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("262,087 as rendered"));
}

#[test]
fn bad_input_exits_2_naming_the_file() {
    let dir = work_dir("bad_input");
    let truncated = dir.join("truncated.glb");
    let bytes = std::fs::read(atrium_path()).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let cycle = dir.join("cycle.gltf");
    std::fs::write(
        &cycle,
        r#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}],
            "nodes": [{"children": [1]}, {"children": [0]}]}"#,
    )
    .unwrap();
    let not_json = dir.join("garbage.gltf");
    std::fs::write(&not_json, b"\x00\x01binary garbage").unwrap();
    let missing = dir.join("missing.glb");
    for (path, expected) in [
        (&truncated, "GLB header declares"),
        (&cycle, "is its own ancestor"),
        (&not_json, "nor glTF JSON"),
        (&missing, "cannot read glTF file"),
    ] {
        for json in [false, true] {
            let mut args = vec!["info".as_ref(), "--gltf".as_ref(), path.as_os_str()];
            if json {
                args.push("--json".as_ref());
            }
            let out = myriad(&args);
            assert_eq!(out.status.code(), Some(2), "{}", path.display());
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(err.starts_with("error: "), "{err}");
            assert!(err.contains(&path.display().to_string()), "{err}");
            assert!(err.contains(expected), "{err}");
            assert!(out.stdout.is_empty());
        }
    }
}

/// A texture `render` would refuse (missing, or not an image) passes a plain `info`, which only
/// references images, and fails `info --decode-images`, naming the file and the image.
#[test]
fn decoding_images_finds_the_textures_render_would_refuse() {
    let dir = work_dir("decode_images");
    std::fs::write(dir.join("broken.png"), b"not a png at all").unwrap();
    for (name, uri, expected) in [
        (
            "missing.gltf",
            "nowhere.png",
            "is missing or not a regular file",
        ),
        ("broken.gltf", "broken.png", "cannot decode"),
    ] {
        let path = dir.join(name);
        let text = format!(
            r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
  "materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}}}}}],
  "textures": [{{"source": 0}}],
  "images": [{{"uri": "{uri}"}}],
{TRIANGLE}}}"#
        );
        std::fs::write(&path, text).unwrap();
        let plain = myriad(&["info".as_ref(), "--gltf".as_ref(), path.as_os_str()]);
        let out = String::from_utf8_lossy(&plain.stdout);
        assert_eq!(plain.status.code(), Some(0), "{out}");
        assert!(out.contains("images      1 (not decoded; --decode-images checks them)"));
        let decoded = myriad(&[
            "info".as_ref(),
            "--gltf".as_ref(),
            path.as_os_str(),
            "--decode-images".as_ref(),
        ]);
        let err = String::from_utf8_lossy(&decoded.stderr);
        assert_eq!(decoded.status.code(), Some(2), "{err}");
        assert!(
            err.contains(&path.display().to_string()) && err.contains(expected),
            "{err}"
        );
    }
    // A model whose images all decode reports so.
    let good = myriad(&[
        "info".as_ref(),
        "--gltf".as_ref(),
        atrium_path().as_os_str(),
        "--decode-images".as_ref(),
        "--json".as_ref(),
    ]);
    assert_eq!(good.status.code(), Some(0));
    let v: Value = serde_json::from_slice(&good.stdout).unwrap();
    assert_eq!(v["images_decoded"], true, "{v}");
}

/// The `accessors`, `bufferViews` and `buffers` of one triangle (positions and u16 indices in
/// a data URI), for the hand-written glTF files below.
const TRIANGLE: &str = r#"  "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA="}],
  "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]"#;

/// `myriad scene --gltf path` succeeds, writes `scene_file` and prints `warning` on stderr,
/// naming the file.
fn scene_prints_the_warning(path: &Path, scene_file: &Path, warning: &str) {
    let out = myriad(&[
        "scene".as_ref(),
        "--gltf".as_ref(),
        path.as_os_str(),
        "--lights".as_ref(),
        "10".as_ref(),
        "--out".as_ref(),
        scene_file.as_os_str(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains(&format!("warning: {}: {warning}", path.display())),
        "{err}"
    );
}

#[test]
fn commands_that_load_a_model_print_what_the_loader_changed() {
    // One triangle whose material asks for roughness 2: the loader clamps it to 1 and says so;
    // `info` lists the warning, `scene` (like `render`, `paper`, `skips`) prints it on stderr.
    let dir = work_dir("loader_warnings");
    let path = dir.join("rough.gltf");
    std::fs::write(
        &path,
        format!(
            r#"{{"asset": {{"version": "2.0"}},
{TRIANGLE},
  "materials": [{{"pbrMetallicRoughness": {{"roughnessFactor": 2}}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
  "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}]}}"#
        ),
    )
    .unwrap();
    let warning = "materials[0]: roughnessFactor 2 is outside [0, 1]; clamped to 1";
    let info = info_json(&path);
    assert_eq!(info["warnings"], serde_json::json!([warning]), "{info}");
    let scene_file = dir.join("rough.scene");
    scene_prints_the_warning(&path, &scene_file, warning);
    assert!(scene_file.is_file());
}

/// A glTF of one triangle and two `KHR_lights_punctual` lights on nodes of their own: `first`
/// (JSON), then a good point light of range 3.
fn triangle_lit_by(first: &str) -> String {
    format!(
        r#"{{"asset": {{"version": "2.0"}},
{TRIANGLE},
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [
      {first}, {{"type": "point", "range": 3}}]}}}},
  "scenes": [{{"nodes": [0, 1, 2]}}],
  "nodes": [{{"mesh": 0}},
            {{"extensions": {{"KHR_lights_punctual": {{"light": 0}}}}, "translation": [0, 0, 1]}},
            {{"extensions": {{"KHR_lights_punctual": {{"light": 1}}}}, "translation": [0, 0, 1]}}]}}"#
    )
}

#[test]
fn model_lights_say_which_directional_lights_are_not_written() {
    // A scene file holds point and spot lights: `scene --model-lights` writes the point light
    // and says that the sun is not written (it was dropped without a word).
    let dir = work_dir("directional_light");
    let path = dir.join("sun.gltf");
    std::fs::write(
        &path,
        triangle_lit_by(r#"{"type": "directional", "name": "sun"}"#),
    )
    .unwrap();
    let out = dir.join("sun.scene");
    let o = myriad(&[
        "scene".as_ref(),
        "--gltf".as_ref(),
        path.as_os_str(),
        "--model-lights".as_ref(),
        "--lights".as_ref(),
        "2".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains("(1 of the model's own + 2 lights")
            && stdout.contains("1 directional light of the model not written"),
        "{stdout}"
    );
    let scene = myriad::scene::Scene::load(&out, myriad::scene::LightPolicy::Strict).unwrap();
    assert_eq!(scene.lights.len(), 3);
}

#[test]
fn an_invalid_light_is_left_out_and_counted_not_fatal() {
    // One triangle, a good point light and one with `range: 0`. The bad light used to make the
    // whole file an error, `info` included; now it is skipped, counted and warned about, like an
    // invalid light in a scene file.
    let dir = work_dir("invalid_light");
    let path = dir.join("range_0.gltf");
    std::fs::write(
        &path,
        triangle_lit_by(r#"{"type": "point", "range": 0, "name": "dead"}"#),
    )
    .unwrap();
    let warning =
        "nodes[1]: KHR_lights_punctual lights[0] \"dead\": range 0 is not finite and > 0; left out";
    let info = info_json(&path);
    assert_eq!(info["triangles"], 1, "{info}");
    assert_eq!(info["lights"]["point"], 1, "{info}");
    assert_eq!(info["lights"]["skipped"], 1, "{info}");
    assert_eq!(info["warnings"], serde_json::json!([warning]), "{info}");
    let out = myriad(&["info".as_ref(), "--gltf".as_ref(), path.as_os_str()]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("lights      1 point, 0 spot, 0 directional; 1 invalid, left out"),
        "{text}"
    );
    // Commands that use the model say so on stderr, naming the file.
    let scene_file = dir.join("range_0.scene");
    scene_prints_the_warning(&path, &scene_file, warning);
}
