//! Hostile input that `crates/scene/tests/scene_file.rs` and the loader's unit tests do not
//! already cover: oversized scene files (200k lights here; 2M with `--ignored`), deep nesting,
//! megabyte-long numbers and strings, absurd counts that are *valid* (a 4-billion-pixel-wide
//! camera, a u32::MAX-cluster grid), and hand-written hostile glTF files (accessor counts of 2^31
//! over a 36-byte buffer, cycles in the node graph, out-of-range and huge indices, offsets past
//! 2^53, external buffers that are FIFOs). Each must give a clear error (or load, where the input
//! is in fact valid), never panic and never hang: every case runs on its own thread under
//! `catch_unwind` with a time limit ([`guarded`]).

use myriad::assignment::{Assigner, LightLists, Method};
use myriad::scene::{Error, LightPolicy, LoadOptions, Model, Scene, validate_json_slice};
use std::path::PathBuf;
use std::sync::mpsc;
use std::time::Duration;

/// Runs `f` on a thread; fails the test if it panics or runs past `limit`.
fn guarded<T: Send + 'static>(
    what: &str,
    limit: Duration,
    f: impl FnOnce() -> T + Send + 'static,
) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
        let _ = tx.send(r);
    });
    match rx.recv_timeout(limit) {
        Ok(Ok(v)) => v,
        Ok(Err(_)) => panic!("{what}: panicked"),
        Err(_) => panic!("{what}: still running after {limit:?} (a hang)"),
    }
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("myriad-hostile-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const CAMERA: &str = r#""camera": {"position":[0,2,10], "target":[0,2,0], "up":[0,1,0],
  "fov_y_deg":60, "width":1536, "height":768, "near":0.1, "far":100}"#;
const GRID: &str = r#""grid": {"x":24, "y":12, "z":16, "depth":"log"}"#;

/// A scene file with `lights` generated lights, written straight into a byte vector.
fn big_scene(lights: usize) -> Vec<u8> {
    use std::io::Write;
    let mut out = Vec::with_capacity(lights * 100 + 512);
    write!(out, "{{ {CAMERA},\n {GRID},\n \"lights\": [").unwrap();
    for i in 0..lights {
        let f = i as f32;
        writeln!(
            out,
            "{}{{\"position\":[{},{},{}],\"radius\":{},\"color\":[1,0.5,0.25],\"intensity\":2}}",
            if i == 0 { "" } else { "," },
            (f * 0.37).sin() * 20.0,
            (f * 0.11).cos() * 5.0 + 2.0,
            -(f % 97.0),
            0.1 + (f * 0.05).sin().abs(),
        )
        .unwrap();
    }
    out.extend_from_slice(b"] }\n");
    out
}

fn oversized_scene_file(lights: usize, limit: Duration) {
    let bytes = big_scene(lights);
    let dir = temp_dir(&format!("big{lights}"));
    let path = dir.join("big.json");
    std::fs::write(&path, &bytes).unwrap();
    let p = path.clone();
    let scene = guarded("big scene file", limit, move || {
        Scene::load(&p, LightPolicy::Strict)
    })
    .unwrap();
    assert_eq!(scene.lights.len(), lights);
    // Cut off mid-light: an error with a position, never a partial scene.
    let cut = &bytes[..bytes.len() * 2 / 3];
    std::fs::write(&path, cut).unwrap();
    let p = path.clone();
    let e = guarded("truncated big file", limit, move || {
        Scene::load(&p, LightPolicy::SkipInvalid)
    })
    .unwrap_err();
    assert!(matches!(e, Error::Json { .. }), "{e}");
    assert!(e.to_string().contains("big.json"), "{e}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn oversized_scene_file_200k_lights() {
    oversized_scene_file(200_000, Duration::from_secs(30));
}

#[test]
#[ignore = "slow: writes and reads a ~200 MB scene file (2M lights); run with --ignored"]
fn oversized_scene_file_2m_lights() {
    oversized_scene_file(2_000_000, Duration::from_secs(300));
}

fn scene_with(camera: &str, grid: &str, lights: &str) -> String {
    format!("{{ {camera}, {grid}, \"lights\": [{lights}] }}")
}

#[test]
fn deep_nesting_and_huge_tokens_are_errors() {
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("100k nested arrays", {
            let mut v = b"{\"lights\": ".to_vec();
            v.extend(std::iter::repeat_n(b'[', 100_000));
            v.extend(std::iter::repeat_n(b']', 100_000));
            v.push(b'}');
            v
        }),
        ("100k nested objects in a light", {
            let mut v = format!("{{ {CAMERA}, {GRID}, \"lights\": [").into_bytes();
            for _ in 0..100_000 {
                v.extend_from_slice(b"{\"a\":");
            }
            v.extend(std::iter::repeat_n(b'}', 100_000));
            v.extend_from_slice(b"] }");
            v
        }),
        (
            "a 1 MB number",
            scene_with(
                CAMERA,
                GRID,
                &format!(
                    "{{\"position\":[0,0,-5],\"radius\":1{}}}",
                    "0".repeat(1 << 20)
                ),
            )
            .into_bytes(),
        ),
        (
            "a 4 MB key",
            scene_with(CAMERA, GRID, &format!("{{\"{}\": 1}}", "k".repeat(4 << 20))).into_bytes(),
        ),
        ("a lone 64 MB string", {
            let mut v = b"\"".to_vec();
            v.extend(std::iter::repeat_n(b'x', 64 << 20));
            v.push(b'"');
            v
        }),
    ];
    for (what, bytes) in cases {
        let bytes = std::sync::Arc::new(bytes);
        let b = bytes.clone();
        let strict = guarded(what, Duration::from_secs(20), move || {
            Scene::from_json_slice(&b, "hostile.json", LightPolicy::Strict).map(|_| ())
        });
        let e = strict.expect_err(what);
        assert!(e.to_string().contains("hostile.json"), "{what}: {e}");
        // Validation agrees: a parse error naming the file, or a report of an invalid scene.
        let b = bytes.clone();
        let validated = guarded(what, Duration::from_secs(20), move || {
            validate_json_slice(&b, "hostile.json").map(|report| report.is_valid())
        });
        match validated {
            Err(e) => assert!(e.to_string().contains("hostile.json"), "{what}: {e}"),
            Ok(valid) => assert!(!valid, "{what}: validation calls it a valid scene"),
        }
    }
}

#[test]
fn absurd_but_valid_counts_load_and_assign_without_panic() {
    // Width 2^32 − 1 (aspect 4e9): valid; the side planes are almost flat, nothing may panic
    // and the assignment must stay within the grid.
    let camera = r#""camera": {"position":[0,2,10], "target":[0,2,0], "up":[0,1,0],
      "fov_y_deg":60, "width":4294967295, "height":1, "near":0.1, "far":100}"#;
    let text = scene_with(
        camera,
        r#""grid": {"x":8, "y":1, "z":4, "depth":"linear"}"#,
        r#"{"position":[0,2,5],"radius":1},{"position":[1e9,2,0],"radius":1e3},
           {"position":[0,2,-20],"radius":3}"#,
    );
    let scene = Scene::from_json_str(&text, "wide.json", LightPolicy::Strict).unwrap();
    let input = myriad::light_input(&scene.lights);
    let mut lists = LightLists::new();
    for method in Method::ALL {
        Assigner::new().assign(method, &input, &scene.camera, &scene.grid, &mut lists);
        lists.assert_well_formed(scene.lights.len());
        assert_eq!(lists.cluster_count(), 32, "{method}");
    }
    // The largest grid the format allows (65535 × 65537 × 1 = u32::MAX clusters) reads as valid:
    // sizing the assignment for it (34 GB of offsets and counts) is the memory budget's job, not
    // the reader's. One more cluster, and a 1e9 × 1e9 grid, are errors.
    let ok = scene_with(
        CAMERA,
        r#""grid": {"x":65535, "y":65537, "z":1, "depth":"log"}"#,
        "",
    );
    let scene = Scene::from_json_str(&ok, "max.json", LightPolicy::Strict).unwrap();
    assert_eq!(scene.grid.cluster_count(), u32::MAX as usize);
    for grid in [
        r#""grid": {"x":65536, "y":65536, "z":1, "depth":"log"}"#,
        r#""grid": {"x":1000000000, "y":1000000000, "z":1, "depth":"log"}"#,
        r#""grid": {"x":1e9, "y":1e9, "z":1, "depth":"log"}"#,
        r#""grid": {"x":-1, "y":1, "z":1, "depth":"log"}"#,
        r#""grid": {"x":18446744073709551616, "y":1, "z":1, "depth":"log"}"#,
    ] {
        let e = Scene::from_json_str(&scene_with(CAMERA, grid, ""), "g.json", LightPolicy::Strict)
            .unwrap_err();
        assert!(e.to_string().contains("g.json"), "{grid}: {e}");
    }
}

#[test]
fn wrong_types_at_the_top_level() {
    for text in [
        "[]",
        "null",
        "42",
        "\"scene\"",
        r#"{"camera": [], "grid": [], "lights": {}}"#,
        r#"{"lights": "many"}"#,
        "\u{feff}{}",
    ] {
        let e = Scene::from_json_str(text, "t.json", LightPolicy::SkipInvalid).unwrap_err();
        assert!(e.to_string().contains("t.json"), "{text}: {e}");
    }
}

/// A valid one-triangle glTF with its 36-byte position buffer as a data URI; `edit` swaps
/// pieces of it for hostile ones.
const TRIANGLE: &str = r#"{"asset":{"version":"2.0"},
 "buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
 "bufferViews":[{"buffer":0,"byteLength":36}],
 "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","max":[1,1,0],"min":[0,0,0]}],
 "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
 "nodes":[{"mesh":0}],
 "scenes":[{"nodes":[0]}],"scene":0}"#;

fn gltf_edit(pairs: &[(&str, &str)]) -> String {
    let mut s = TRIANGLE.to_string();
    for (from, to) in pairs {
        assert!(s.contains(from), "{from}");
        s = s.replacen(from, to, 1);
    }
    s
}

/// Loads `text` from a file in `dir` under the guard; returns the result as a string.
fn load_gltf(dir: &std::path::Path, name: &str, text: String) -> Result<Model, String> {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    guarded(name, Duration::from_secs(20), move || {
        Model::load(&path, &LoadOptions::without_images()).map_err(|e| e.to_string())
    })
}

#[test]
fn hand_written_hostile_gltf_files_are_errors() {
    let dir = temp_dir("gltf");
    let base = load_gltf(&dir, "base.gltf", TRIANGLE.to_string()).unwrap();
    assert_eq!(base.triangle_count(), 1);
    let errors: Vec<(&str, &str, String)> = vec![
        (
            "count 2^31",
            "count 2147483648 of 12-byte elements is more than",
            gltf_edit(&[(r#""count":3"#, r#""count":2147483648"#)]),
        ),
        (
            "count u32::MAX",
            "count 4294967295 of 12-byte elements",
            gltf_edit(&[(r#""count":3"#, r#""count":4294967295"#)]),
        ),
        (
            "count 2^64",
            "accessors[0].count: 18446744073709551615 is out of range",
            gltf_edit(&[(r#""count":3"#, r#""count":18446744073709551615"#)]),
        ),
        (
            "count -1",
            "not valid glTF JSON: invalid value: integer `-1`",
            gltf_edit(&[(r#""count":3"#, r#""count":-1"#)]),
        ),
        (
            "byteOffset 2^53",
            "accessors[0].byteOffset: 9007199254740992 is out of range",
            gltf_edit(&[(
                r#""bufferView":0,"#,
                r#""bufferView":0,"byteOffset":9007199254740992,"#,
            )]),
        ),
        (
            "view past buffer",
            "bufferViews[0]: bytes 4294967295..4294967295+36 lie outside buffer 0",
            gltf_edit(&[(
                r#""byteLength":36}]"#,
                r#""byteLength":36,"byteOffset":4294967295}]"#,
            )]),
        ),
        (
            "stride 0 with count 2^30",
            "count 1073741824 of 12-byte elements",
            gltf_edit(&[
                (
                    r#""byteLength":36}]"#,
                    r#""byteLength":36,"byteStride":4}]"#,
                ),
                (r#""count":3"#, r#""count":1073741824"#),
            ]),
        ),
        (
            "buffer declares 2^40 bytes",
            "buffers[0].byteLength: 1099511627776 is out of range",
            gltf_edit(&[(
                r#""byteLength":36,"uri""#,
                r#""byteLength":1099511627776,"uri""#,
            )]),
        ),
        (
            "accessor index 2^32",
            "POSITION: 4294967296 is out of range",
            gltf_edit(&[(r#""POSITION":0"#, r#""POSITION":4294967296"#)]),
        ),
        (
            "node is its own child",
            "nodes[0] is its own ancestor",
            gltf_edit(&[(r#"{"mesh":0}"#, r#"{"mesh":0,"children":[0]}"#)]),
        ),
        (
            "two-node cycle",
            "nodes[0] is its own ancestor",
            gltf_edit(&[(
                r#""nodes":[{"mesh":0}]"#,
                r#""nodes":[{"mesh":0,"children":[1]},{"children":[0]}]"#,
            )]),
        ),
        (
            "scene names node 2^31",
            "scenes[0].nodes[0]: Index out of bounds",
            gltf_edit(&[(r#""nodes":[0]"#, r#""nodes":[2147483648]"#)]),
        ),
        (
            "mesh index huge",
            "nodes[0].mesh: Index out of bounds",
            gltf_edit(&[(r#"{"mesh":0}"#, r#"{"mesh":99999999}"#)]),
        ),
        (
            "indices past the vertices",
            "index 4294967295 (element 0 of the indices) is out of range",
            gltf_edit(&[
                (
                    r#""bufferViews":[{"buffer":0,"byteLength":36}],"#,
                    r#""bufferViews":[{"buffer":0,"byteLength":36},{"buffer":1,"byteLength":12}],"#,
                ),
                (
                    r#""type":"VEC3","max":[1,1,0],"min":[0,0,0]}]"#,
                    r#""type":"VEC3","max":[1,1,0],"min":[0,0,0]},
                       {"bufferView":1,"componentType":5125,"count":3,"type":"SCALAR"}]"#,
                ),
                (
                    r#"AAAAgD8AAAAA"}]"#,
                    r#"AAAAgD8AAAAA"},{"byteLength":12,"uri":"data:application/octet-stream;base64,/////wAAAAD/////"}]"#,
                ),
                (
                    r#""attributes":{"POSITION":0}"#,
                    r#""attributes":{"POSITION":0},"indices":1"#,
                ),
            ]),
        ),
        (
            "translation 1e39",
            "nodes[0]: transform is not finite",
            gltf_edit(&[(r#"{"mesh":0}"#, r#"{"mesh":0,"translation":[1e39,0,0]}"#)]),
        ),
        (
            "scale -inf-ish",
            "nodes[0]: transform is not finite",
            gltf_edit(&[(r#"{"mesh":0}"#, r#"{"mesh":0,"scale":[-1e308,1,1]}"#)]),
        ),
        (
            "matrix of 3 numbers",
            "invalid length 3, expected an array of length 16",
            gltf_edit(&[(r#"{"mesh":0}"#, r#"{"mesh":0,"matrix":[1,0,0]}"#)]),
        ),
        (
            "wrong type for count",
            "invalid type: string \"3\", expected u64",
            gltf_edit(&[(r#""count":3"#, r#""count":"3""#)]),
        ),
        (
            "no asset",
            "missing field `asset`",
            gltf_edit(&[(r#""asset":{"version":"2.0"},"#, "")]),
        ),
    ];
    // Every hostile file is refused, with a message naming the file and what is wrong in it
    // (not any error: a broken edit would fail as JSON). "accessor index 2^32" used to load
    // as index 0, see `index_2_pow_32_is_an_error`.
    for (what, fragment, text) in errors {
        let e = match load_gltf(&dir, "hostile.gltf", text) {
            Err(e) => e,
            Ok(m) => panic!("{what}: loaded ({} triangles)", m.triangle_count()),
        };
        assert!(
            e.contains("hostile.gltf") && e.contains(fragment),
            "{what}: expected the file and {fragment:?} in: {e}"
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn exponential_node_graph_is_refused_quickly() {
    // 40 levels, each node naming the next level's node twice: 2^40 paths.
    let mut nodes = vec![r#"{"mesh":0}"#.to_string()];
    for level in 1..40 {
        nodes.push(format!(r#"{{"children":[{0},{0}]}}"#, level - 1));
    }
    let text = gltf_edit(&[
        (
            r#""nodes":[{"mesh":0}]"#,
            &format!(r#""nodes":[{}]"#, nodes.join(",")),
        ),
        (r#""nodes":[0]"#, r#""nodes":[39]"#),
    ]);
    let dir = temp_dir("dag");
    // `load_gltf` is a hang guard (20 s): walking the 2^40 paths would never end.
    let r = load_gltf(&dir, "dag.gltf", text);
    let e = r.expect_err("2^39 instances accepted");
    assert!(
        e.contains("dag.gltf") && e.contains("more than 4194304 node instances"),
        "{e}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// The file's own text in the loader's errors and warnings — a URI, an extension's name — has
/// its control characters escaped: printed raw, an escape sequence reached the terminal (review).
#[test]
fn control_characters_of_the_file_are_escaped_in_errors_and_warnings() {
    let dir = temp_dir("escaped_text");
    let raw = |text: &str| text.chars().any(|c| c.is_control());
    let missing = gltf_edit(&[(
        "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA",
        r"x\u001b[31mRED\r\nerror: fake.bin",
    )]);
    let error = load_gltf(&dir, "uri.gltf", missing).unwrap_err();
    assert!(!raw(&error), "{error:?}");
    assert!(
        error.contains(r"x\u{1b}[31mRED\r\nerror: fake.bin"),
        "{error}"
    );
    let extension = gltf_edit(&[(
        r#"{"asset":{"version":"2.0"},"#,
        r#"{"asset":{"version":"2.0"},"extensionsUsed":["EXT_\u001b[2Jclear"],"#,
    )]);
    let model = load_gltf(&dir, "extension.gltf", extension).unwrap();
    let warning = model.warnings.join("\n");
    assert!(!raw(&warning), "{warning:?}");
    assert!(warning.contains(r"EXT_\u{1b}[2Jclear"), "{warning}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// Many camera nodes with distinct names: the check for shared names is one pass (a scan per
/// camera took 31 s on 80 000 of them; 150 000 would take minutes), and a shared name is said.
#[test]
fn many_named_cameras_load_quickly_and_shared_names_are_warned_about() {
    let count = 150_000;
    let mut nodes = vec![r#"{"mesh":0}"#.to_string()];
    for i in 0..count {
        nodes.push(format!(r#"{{"camera":0,"name":"c{i}"}}"#));
    }
    nodes.push(r#"{"camera":0,"name":"Twin"}"#.into());
    nodes.push(r#"{"camera":0,"name":"Twin"}"#.into());
    let roots: Vec<String> = (0..nodes.len()).map(|i| i.to_string()).collect();
    let text = gltf_edit(&[
        (
            r#""nodes":[{"mesh":0}]"#,
            &format!(
                r#""cameras":[{{"type":"perspective","perspective":{{"yfov":1,"znear":0.1}}}}],
                "nodes":[{}]"#,
                nodes.join(",")
            ),
        ),
        (
            r#""nodes":[0]"#,
            &format!(r#""nodes":[{}]"#, roots.join(",")),
        ),
    ]);
    let dir = temp_dir("many_cameras");
    // `load_gltf` is a hang guard (20 s).
    let model = load_gltf(&dir, "cameras.gltf", text).unwrap();
    assert_eq!(model.cameras.len(), count + 2);
    let shared: Vec<&String> = model
        .warnings
        .iter()
        .filter(|w| w.contains("cameras are named"))
        .collect();
    assert_eq!(
        shared,
        ["2 cameras are named \"Twin\"; looked up by that name, the first is used"]
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// Regression (found by this suite): an index of exactly 2^32 (`"POSITION": 4294967296`) used
/// to load as index 0 — the `gltf` crate (1.4.1) reads indices as u32 and wraps. The loader now
/// refuses any integer ≥ 2^32, naming where it is.
#[test]
fn index_2_pow_32_is_an_error() {
    let dir = temp_dir("wrap");
    let text = gltf_edit(&[(r#""POSITION":0"#, r#""POSITION":4294967296"#)]);
    let r = load_gltf(&dir, "wrap.gltf", text);
    std::fs::remove_dir_all(dir).unwrap();
    let message = format!("{:?}", r.expect_err("index 2^32 accepted as index 0"));
    assert!(
        message.contains("POSITION") && message.contains("4294967296"),
        "{message}"
    );
}

/// Regression (found by `myriad-fuzz gltf`): gltf-json 1.4.1's validation hook (`mesh.rs:151`)
/// indexes `root.accessors` without a bounds check, so a primitive whose POSITION names an
/// accessor that does not exist panicked inside `gltf::Gltf::from_slice`. The loader now checks
/// those indices on the raw JSON first and returns an error.
#[test]
fn position_of_missing_accessor_is_an_error() {
    let text =
        r#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]}"#;
    let r = guarded("missing accessor", Duration::from_secs(10), move || {
        Model::from_gltf_slice(
            text.as_bytes(),
            "m.gltf",
            None,
            &LoadOptions::without_images(),
        )
        .map(|_| ())
        .map_err(|e| e.to_string())
    });
    let e = r.expect_err("a POSITION naming no accessor loaded");
    assert!(
        e.contains("m.gltf") && e.contains("POSITION: accessor 0 does not exist"),
        "{e}"
    );
}

/// A buffer URI naming a device (`/dev/zero` would be read forever) or a folder is refused,
/// however it is spelled (percent-encoded, relative); absolute paths, `file:` URIs and paths
/// above the model's folder are refused whatever they name.
#[test]
fn buffer_uris_naming_devices_or_folders_are_refused() {
    let dir = temp_dir("devices");
    let uris = [
        ("/dev/zero", "outside the glTF file's folder"),
        (".", "not a regular file"),
        ("/", "outside the glTF file's folder"),
        ("/dev/%7Aero", "outside the glTF file's folder"),
        ("../../../../../../../../../../dev/zer%6F", "outside"),
        ("file:///dev/zero", "file: URIs are not read"),
        ("FILE:relative.bin", "file: URIs are not read"),
    ];
    for (uri, expected) in uris {
        let text = format!(
            r#"{{"asset": {{"version": "2.0"}}, "buffers": [{{"byteLength": 16, "uri": "{uri}"}}]}}"#
        );
        let path = dir.join("device.gltf");
        std::fs::write(&path, &text).unwrap();
        let r = guarded("device uri", Duration::from_secs(20), move || {
            Model::load(&path, &LoadOptions::without_images())
                .map(|_| ())
                .map_err(|e| e.to_string())
        });
        let message = r.expect_err(uri);
        assert!(message.contains(expected), "{uri}: {message}");
        assert!(message.contains(uri), "{uri}: {message}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// A model reads files from its own folder and below: an absolute path or a `../` above the folder
/// to a perfectly readable file is refused (an untrusted model must not read `/etc/passwd` as
/// vertices), `../` inside the folder is followed, and only a buffer's declared length is read,
/// however large the file its URI names.
#[test]
fn buffer_files_are_relative_and_read_only_to_their_declared_length() {
    let dir = temp_dir("buffer_files");
    let sub = dir.join("model");
    std::fs::create_dir_all(&sub).unwrap();
    // Three vertices of a triangle, then 8 GiB of sparse zeros.
    let mut bytes = Vec::new();
    for v in [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in v {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    let buffer = dir.join("huge.bin");
    std::fs::write(&buffer, &bytes).unwrap();
    std::fs::File::options()
        .write(true)
        .open(&buffer)
        .unwrap()
        .set_len(8 << 30)
        .unwrap();
    let gltf = |uri: &str| {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "buffers": [{{"byteLength": 36, "uri": "{uri}"}}],
            "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
            "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]}}],
            "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
            "nodes": [{{"mesh": 0}}], "scenes": [{{"nodes": [0]}}], "scene": 0}}"#
        )
    };
    let path = dir.join("relative.gltf");
    std::fs::write(&path, gltf("model/../huge.bin")).unwrap();
    let loaded = path.clone();
    let model = guarded("relative buffer", Duration::from_secs(20), move || {
        Model::load(&loaded, &LoadOptions::without_images()).map_err(|e| e.to_string())
    })
    .expect("a relative buffer file loads");
    assert_eq!(model.triangle_count(), 1);
    // The files it is made of: itself, then the buffer, as resolved.
    assert_eq!(model.files, [path, dir.join("model/../huge.bin")]);
    for uri in [buffer.display().to_string(), "../huge.bin".to_string()] {
        let path = sub.join("outside.gltf");
        std::fs::write(&path, gltf(&uri)).unwrap();
        let message = Model::load(&path, &LoadOptions::without_images())
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("outside the glTF file's folder") && message.contains(&uri),
            "{message}"
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// An image URI naming a device is refused before the decoder reads it; an escape that does not
/// decode to UTF-8 is an error, not a panic in the gltf crate.
#[test]
fn image_uris_naming_devices_and_bad_escapes_are_errors() {
    let dir = temp_dir("image_devices");
    let triangle = r#""buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
        "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0,
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}]"#;
    for (uri, expected) in [
        ("/dev/zero", "outside the glTF file's folder"),
        ("/dev/%7Aero", "outside the glTF file's folder"),
        ("../../../../../../../../../../dev/zer%6F", "outside"),
        ("sub/../../x.png", "outside"),
        ("%FF.png", "does not percent-decode to UTF-8"),
    ] {
        let text = format!(
            r#"{{"asset": {{"version": "2.0"}}, {triangle}, "images": [{{"uri": "{uri}"}}]}}"#
        );
        let path = dir.join("image.gltf");
        std::fs::write(&path, &text).unwrap();
        let r = guarded("image uri", Duration::from_secs(20), move || {
            Model::load(&path, &LoadOptions::default())
                .map(|_| ())
                .map_err(|e| e.to_string())
        });
        let message = r.expect_err(uri);
        assert!(message.contains(expected), "{uri}: {message}");
    }
    let buffer =
        r#"{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 4, "uri": "%FF.bin"}]}"#;
    let path = dir.join("buffer.gltf");
    std::fs::write(&path, buffer).unwrap();
    let message = Model::load(&path, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(message.contains("does not percent-decode"), "{message}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// Valid glTF whose world space overflows f32, whose bounds are finite but farther apart than
/// f32 can measure, or whose only triangle has no area: errors or finite values, never a panic.
#[test]
fn overflowing_and_degenerate_models_are_errors_not_panics() {
    let dir = temp_dir("overflow");
    // A vertex at 1 scaled by 3e38 and moved by 3e38 more: +inf in world space.
    let overflow = gltf_edit(&[(
        r#""nodes":[{"mesh":0}]"#,
        r#""nodes":[{"mesh":0,"scale":[3e38,1,1],"translation":[3e38,0,0]}]"#,
    )]);
    let e = load_gltf(&dir, "overflow.gltf", overflow).unwrap_err();
    assert!(e.contains("nodes[0]") && e.contains("overflow f32"), "{e}");

    // Corners 4e38 apart (each finite) and a camera without zfar: the far plane is clamped to
    // f32::MAX, not infinite, so a grid can be built on it.
    let huge = gltf_edit(&[(
        r#""nodes":[{"mesh":0}],
 "scenes":[{"nodes":[0]}]"#,
        r#""nodes":[{"mesh":0,"scale":[3e38,3e38,1]},{"camera":0}],
 "cameras":[{"type":"perspective","perspective":{"yfov":1.0,"znear":0.1}}],
 "scenes":[{"nodes":[0,1]}]"#,
    )]);
    let model = load_gltf(&dir, "huge.gltf", huge).unwrap();
    let camera = model.camera(0, 64, 32).unwrap();
    assert!(
        camera.far.is_finite() && camera.far > 1e38,
        "{}",
        camera.far
    );
    let grid = myriad::cluster_math::ClusterGrid::new(
        myriad::cluster_math::glam::UVec3::new(4, 2, 8),
        myriad::cluster_math::DepthSlicing::Log,
        camera.near,
        camera.far,
    );
    assert_eq!(grid.cluster_count(), 64);
    // znear at f32::MAX without zfar leaves no far plane above it: refused at load (the grid
    // once panicked on near == far).
    let no_room = gltf_edit(&[(
        r#""nodes":[{"mesh":0}],
 "scenes":[{"nodes":[0]}]"#,
        r#""nodes":[{"mesh":0},{"camera":0}],
 "cameras":[{"type":"perspective","perspective":{"yfov":1.0,"znear":3.4028235e38}}],
 "scenes":[{"nodes":[0,1]}]"#,
    )]);
    let e = load_gltf(&dir, "no_room.gltf", no_room).unwrap_err();
    assert!(e.contains("znear") && e.contains("no room"), "{e}");

    // A mesh scaled to nothing: no surface to put lights on is an error naming the model.
    let flat = gltf_edit(&[(
        r#""nodes":[{"mesh":0}],
 "scenes":[{"nodes":[0]}]"#,
        r#""nodes":[{"mesh":0,"scale":[0,0,0]},{"camera":0}],
 "cameras":[{"type":"perspective","perspective":{"yfov":1.0,"znear":0.1,"zfar":100}}],
 "scenes":[{"nodes":[0,1]}]"#,
    )]);
    let model = load_gltf(&dir, "flat.gltf", flat).unwrap();
    let e = myriad::render::RenderScene::from_model(&model, "flat.gltf", None, 10, 1, 16, 8)
        .expect_err("no surfaces");
    let e = format!("{e:#}");
    assert!(e.contains("flat.gltf") && e.contains("no surfaces"), "{e}");
    std::fs::remove_dir_all(dir).unwrap();
}
