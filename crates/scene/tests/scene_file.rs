//! Scene files end to end: a hand-written file in the documented format (the crate's docs), bit-exact round trips, every
//! documented error, and a sweep of malformed inputs that must never panic.

use myriad_scene::glam::{UVec3, Vec3};
use myriad_scene::{
    Camera, ClusterGrid, DepthSlicing, Error, LightPolicy, LightRecord, Lights, Scene,
    validate_file, validate_json_slice, validate_json_str,
};
use std::f32::consts::PI;
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn hand_written_text() -> String {
    std::fs::read_to_string(data("hand_written.json")).unwrap()
}

/// `text` with the first `from` replaced by `to`; panics if `from` is absent (a broken test).
fn edit(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "test edit: {from:?} not in the text");
    text.replacen(from, to, 1)
}

/// Small deterministic generator (xorshift64*), so no RNG dependency is needed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn f32_in(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * ((self.next() >> 40) as f32 / (1u64 << 24) as f32)
    }
    /// Any finite f32 bit pattern.
    fn any_finite_f32(&mut self) -> f32 {
        loop {
            let x = f32::from_bits(self.next() as u32);
            if x.is_finite() {
                return x;
            }
        }
    }
}

fn camera_bits(c: &Camera) -> Vec<u32> {
    let mut v: Vec<u32> = [c.position, c.target, c.up]
        .iter()
        .flat_map(|p| p.to_array())
        .map(f32::to_bits)
        .collect();
    v.extend([
        c.fov_y.to_bits(),
        c.width,
        c.height,
        c.near.to_bits(),
        c.far.to_bits(),
    ]);
    v
}

fn grid_bits(g: &ClusterGrid) -> Vec<u32> {
    let mut v = g.dims().to_array().to_vec();
    v.extend([g.near().to_bits(), g.far().to_bits()]);
    match g.slicing() {
        DepthSlicing::Linear => v.push(0),
        DepthSlicing::Log => v.push(1),
        DepthSlicing::LogWithNearSlice { first_slice_depth } => {
            v.extend([2, first_slice_depth.to_bits()])
        }
    }
    v
}

fn light_columns_bits(l: &Lights) -> Vec<Vec<u32>> {
    let bits = |c: &Vec<f32>| c.iter().map(|x| x.to_bits()).collect::<Vec<u32>>();
    vec![
        bits(&l.x),
        bits(&l.y),
        bits(&l.z),
        bits(&l.radius),
        bits(&l.r),
        bits(&l.g),
        bits(&l.b),
        bits(&l.intensity),
        bits(&l.spot_dir_x),
        bits(&l.spot_dir_y),
        bits(&l.spot_dir_z),
        bits(&l.spot_angle),
        bits(&l.spot_inner_angle),
        l.source_index.clone(),
    ]
}

/// Camera, grid and every light column equal bit for bit (so -0.0 vs 0.0 counts as different).
fn assert_bit_identical(a: &Scene, b: &Scene) {
    assert_eq!(camera_bits(&a.camera), camera_bits(&b.camera), "camera");
    assert_eq!(grid_bits(&a.grid), grid_bits(&b.grid), "grid");
    assert_eq!(
        light_columns_bits(&a.lights),
        light_columns_bits(&b.lights),
        "lights"
    );
}

#[test]
fn hand_written_design_md_file_loads_as_written() {
    let path = data("hand_written.json");
    let s = Scene::load(&path, LightPolicy::Strict).unwrap();
    let c = s.camera;
    assert_eq!(c.position, Vec3::new(0.0, 2.0, 10.0));
    assert_eq!(c.target, Vec3::new(0.0, 2.0, 0.0));
    assert_eq!(c.up, Vec3::Y);
    assert_eq!(c.fov_y, 60f64.to_radians() as f32);
    assert!((c.fov_y - 60f32.to_radians()).abs() <= f32::EPSILON);
    assert_eq!((c.width, c.height, c.near, c.far), (1536, 768, 0.1, 100.0));
    assert_eq!(s.grid.dims(), UVec3::new(24, 12, 16));
    assert_eq!(s.grid.slicing(), DepthSlicing::Log);
    assert_eq!((s.grid.near(), s.grid.far()), (0.1, 100.0));

    let l = &s.lights;
    assert_eq!(l.len(), 4);
    assert_eq!(l.source_index, [0, 1, 2, 3]);
    assert_eq!(l.x, [0.0, -4.25, 6.0, 1000.0]);
    assert_eq!(l.y, [1.0, 0.5, 8.0, -0.002]);
    assert_eq!(l.z, [-5.0, -12.0, -20.0, 15.0]);
    assert_eq!(l.radius, [2.5, 0.3, 10.0, 0.01]);
    assert_eq!(l.r, [1.0, 0.2, 1.0, 0.0]);
    assert_eq!(l.g, [0.9, 0.4, 1.0, 0.0]);
    assert_eq!(l.b, [0.8, 1.0, 1.0, 0.0]);
    assert_eq!(l.intensity, [3.0, 1.0, 0.5, 0.0]);
    assert!(l.has_spots());
    assert_eq!(l.spot_dir_x, [0.0; 4]);
    assert_eq!(l.spot_dir_y, [0.0, 0.0, -1.0, 0.0]);
    assert_eq!(l.spot_dir_z, [0.0; 4]);
    assert_eq!(l.spot_angle, [PI, PI, 30f64.to_radians() as f32, PI]);
    assert_eq!(
        (0..4).map(|i| l.is_spot(i)).collect::<Vec<_>>(),
        [false, false, true, false]
    );
    assert!(s.skipped.is_empty());
    assert!(s.problems().is_empty());

    let report = validate_file(&path).unwrap();
    assert!(report.is_valid());
    assert_eq!(
        report.to_string(),
        format!("{}: valid; lights: 4 ok, 0 bad", path.display())
    );
}

#[test]
fn hand_written_file_round_trips_bit_for_bit_through_a_file() {
    let s = Scene::load(data("hand_written.json"), LightPolicy::Strict).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("written.json");
    s.save(&out).unwrap();
    let back = Scene::load(&out, LightPolicy::Strict).unwrap();
    assert_bit_identical(&s, &back);
    assert_eq!(back, s);
    // Written text is stable: writing the re-read scene gives the same bytes.
    assert_eq!(
        back.to_json_string().unwrap(),
        std::fs::read_to_string(&out).unwrap()
    );
    // And it is still the documented format: plain serde_json sees the documented keys.
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["grid"]["depth"], "log");
    assert_eq!(v["camera"]["fov_y_deg"], 60.0);
    assert_eq!(v["lights"][2]["spot"]["angle_deg"], 30.0);
    assert_eq!(v["lights"].as_array().unwrap().len(), 4);
}

#[test]
fn a_utf8_byte_order_mark_is_skipped() {
    let s = Scene::load(data("hand_written.json"), LightPolicy::Strict).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bom.json");
    let mut bytes = b"\xEF\xBB\xBF".to_vec();
    bytes.extend_from_slice(hand_written_text().as_bytes());
    std::fs::write(&out, bytes).unwrap();
    let back = Scene::load(&out, LightPolicy::Strict).unwrap();
    assert_bit_identical(&s, &back);
}

fn random_scene(rng: &mut Rng, lights: usize, spots: bool) -> Scene {
    let near = rng.f32_in(0.001, 1.0);
    let far = near + rng.f32_in(0.5, 1000.0);
    let camera = Camera {
        position: Vec3::new(rng.any_finite_f32(), rng.f32_in(-9.0, 9.0), -0.0),
        target: Vec3::new(rng.f32_in(-1.0, 1.0), 1e-40, 3.0e38),
        up: Vec3::new(rng.f32_in(-1.0, 1.0), 1.0, rng.f32_in(-1.0, 1.0)),
        fov_y: rng.f32_in(1e-3, 3.1),
        width: (rng.next() % 5000) as u32 + 1,
        height: (rng.next() % 5000) as u32 + 1,
        near,
        far,
    };
    let slicing = match rng.next() % 3 {
        0 => DepthSlicing::Linear,
        1 => DepthSlicing::Log,
        _ => DepthSlicing::LogWithNearSlice {
            first_slice_depth: near + (far - near) * rng.f32_in(0.01, 0.99),
        },
    };
    let dims = UVec3::new(
        (rng.next() % 64) as u32 + 1,
        (rng.next() % 64) as u32 + 1,
        (rng.next() % 64) as u32 + 1,
    );
    let grid = ClusterGrid::new(dims, slicing, near, far);
    let mut l = Lights::new();
    for i in 0..lights {
        let green = rng.any_finite_f32().abs();
        // Any finite colour, and an intensity that keeps colour × intensity finite in f32 (an
        // infinite product is an invalid light: the renderer would show nothing of it).
        let intensity = match rng.f32_in(0.0, 1e6) {
            i if (green * i).is_finite() => i,
            _ => rng.f32_in(0.0, 1.0),
        };
        let mut light = LightRecord::point(
            Vec3::new(
                rng.any_finite_f32(),
                rng.f32_in(-100.0, 100.0),
                rng.any_finite_f32(),
            ),
            rng.f32_in(1e-6, 50.0),
        )
        .with_color(Vec3::new(rng.f32_in(0.0, 1.0), green, 0.0))
        .with_intensity(intensity)
        .with_source_index(i as u32);
        if spots && rng.next().is_multiple_of(2) {
            let d = Vec3::new(
                rng.f32_in(-1.0, 1.0),
                rng.f32_in(-1.0, 1.0),
                rng.f32_in(-1.0, 1.0),
            )
            .normalize_or(Vec3::NEG_Z);
            let angle = if rng.next().is_multiple_of(8) {
                PI
            } else {
                rng.f32_in(1e-6, PI)
            };
            light = light.with_spot(d, angle);
            // Half keep the default inner angle (not written), the rest one of their own: any
            // angle below the outer one, 0 and -0.0 among them.
            light = match rng.next() % 6 {
                0..=2 => light,
                3 => light.with_spot_inner_angle(0.0),
                4 => light.with_spot_inner_angle(-0.0),
                _ => light.with_spot_inner_angle(rng.f32_in(0.0, angle).min(angle.next_down())),
            };
        }
        l.push(light);
    }
    Scene::new(camera, grid, l)
}

#[test]
fn random_scenes_round_trip_bit_for_bit() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for case in 0..200 {
        let s = random_scene(&mut rng, case % 17, case % 3 != 0);
        assert!(s.problems().is_empty(), "{:?}", s.problems());
        let text = s.to_json_string().unwrap();
        let back = Scene::from_json_str(&text, "random", LightPolicy::Strict)
            .unwrap_or_else(|e| panic!("case {case}: {e}\n{text}"));
        assert_bit_identical(&s, &back);
        assert_eq!(back.to_json_string().unwrap(), text, "case {case}");
    }
}

#[test]
fn sampled_f32_bit_patterns_round_trip_exactly() {
    // An exhaustive run over all 2^32 patterns was done once (see the crate docs); this re-checks
    // every 4099th finite pattern plus the edge values, through the real writer and reader.
    let mut values: Vec<f32> = (0..=u32::MAX)
        .step_by(4099)
        .map(f32::from_bits)
        .filter(|x| x.is_finite())
        .collect();
    values.extend([
        0.0,
        -0.0,
        f32::MIN_POSITIVE,
        f32::from_bits(1),
        -f32::from_bits(1),
        f32::MAX,
        f32::MIN,
        f32::EPSILON,
        0.1,
        1.0 / 3.0,
    ]);
    let camera = Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 60.0, 8, 8, 0.1, 10.0);
    let grid = ClusterGrid::new(UVec3::ONE, DepthSlicing::Linear, 0.1, 10.0);
    let lights: Lights = values
        .chunks(3)
        .enumerate()
        .map(|(i, c)| {
            let p = Vec3::new(c[0], c[c.len() / 2], c[c.len() - 1]);
            LightRecord::point(p, 1.0).with_source_index(i as u32)
        })
        .collect();
    let s = Scene::new(camera, grid, lights);
    let back =
        Scene::from_json_str(&s.to_json_string().unwrap(), "f32", LightPolicy::Strict).unwrap();
    assert!(s.lights.len() > 300_000);
    assert_bit_identical(&s, &back);
}

#[test]
fn lights_are_written_in_source_order_and_skipped_lights_are_dropped() {
    let text = edit(&hand_written_text(), r#""radius":0.3"#, r#""radius":-0.3"#);
    let s = Scene::from_json_str(&text, "h.json", LightPolicy::SkipInvalid).unwrap();
    assert_eq!(s.lights.source_index, [0, 2, 3]);
    assert_eq!(s.skipped.len(), 1);
    assert_eq!(s.skipped[0].index, 1);
    assert_eq!(
        s.skipped[0].reason,
        "lights[1].radius: must be finite and > 0, got -0.3"
    );
    // Shuffle the columns; the writer restores source order and renumbers 0, 1, 2.
    let mut shuffled = s.clone();
    shuffled.lights = s.lights.iter().rev().collect();
    let back = Scene::from_json_str(
        &shuffled.to_json_string().unwrap(),
        "w",
        LightPolicy::Strict,
    )
    .unwrap();
    assert_eq!(back.lights.source_index, [0, 1, 2]);
    assert_eq!(back.lights.x, s.lights.x);
    assert_eq!(back.lights.spot_angle, s.lights.spot_angle);
    assert!(back.skipped.is_empty());
}

#[test]
fn load_errors_name_the_file_and_the_light() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad_lights.json");
    let text = edit(
        &hand_written_text(),
        r#""angle_deg":30"#,
        r#""angle_deg":0"#,
    );
    let text = edit(&text, r#""intensity":0}"#, r#""intensity":-1}"#);
    std::fs::write(&path, &text).unwrap();

    let e = Scene::load(&path, LightPolicy::Strict).unwrap_err();
    assert!(matches!(e, Error::Invalid { more: 1, .. }), "{e:?}");
    assert_eq!(
        e.to_string(),
        format!(
            "{}: lights[2].spot.angle_deg: must be in (0, 180] degrees, got 0.0 \
             (and 1 more problem)",
            path.display()
        )
    );
    let Error::Invalid { problem, .. } = &e else {
        unreachable!()
    };
    assert_eq!(problem.light, Some(2));

    let s = Scene::load(&path, LightPolicy::SkipInvalid).unwrap();
    assert_eq!(s.lights.source_index, [0, 1]);
    assert!(!s.lights.has_spots(), "the only spot was skipped");
    let skipped: Vec<u32> = s.skipped.iter().map(|k| k.index).collect();
    assert_eq!(skipped, [2, 3]);
    assert!(
        s.skipped[1]
            .reason
            .contains("lights[3].intensity: must be finite and >= 0")
    );

    let report = validate_file(&path).unwrap();
    assert_eq!(
        (report.lights_total, report.lights_ok(), report.lights_bad),
        (4, 2, 2)
    );
    let shown = report.to_string();
    let lines: Vec<&str> = shown.lines().collect();
    assert_eq!(lines.len(), 3, "{shown}");
    assert!(
        lines
            .iter()
            .all(|l| l.starts_with(&path.display().to_string()))
    );
    assert!(lines[2].ends_with("invalid, 2 problems; lights: 2 ok, 2 bad"));

    let missing = dir.path().join("missing.json");
    let e = Scene::load(&missing, LightPolicy::Strict).unwrap_err();
    assert!(matches!(e, Error::Read { .. }));
    assert!(e.to_string().contains("missing.json"), "{e}");
    let e = Scene::load(data("hand_written.json"), LightPolicy::Strict)
        .unwrap()
        .save(dir.path().join("no/such/dir/out.json"))
        .unwrap_err();
    assert!(matches!(e, Error::Write { .. }));
    assert!(e.to_string().contains("no/such/dir/out.json"), "{e}");
}

/// (edit from, edit to, expected path of the first problem, a fragment of its message).
const INVALID_EDITS: &[(&str, &str, &str, &str)] = &[
    // Camera.
    (
        r#""near":0.1"#,
        r#""near":0"#,
        "camera.near",
        "must be finite and at least 1e-12 (below it the f32 assignment underflows), got 0.0",
    ),
    (
        r#""near":0.1"#,
        r#""near":-1"#,
        "camera.near",
        "at least 1e-12",
    ),
    (
        r#""near":0.1"#,
        r#""near":1e-22"#,
        "camera.near",
        "got 1e-22",
    ),
    (
        r#""near":0.1"#,
        r#""near":100"#,
        "camera.far",
        "greater than camera.near (100.0), got 100.0",
    ),
    (
        r#""far":100"#,
        r#""far":1e39"#,
        "camera.far",
        "out of the f32 range",
    ),
    (
        r#""fov_y_deg":60"#,
        r#""fov_y_deg":180"#,
        "camera.fov_y_deg",
        "(0, 180)",
    ),
    (
        r#""fov_y_deg":60"#,
        r#""fov_y_deg":0"#,
        "camera.fov_y_deg",
        "(0, 180)",
    ),
    (
        r#""fov_y_deg":60"#,
        r#""fov_y_deg":"60""#,
        "camera.fov_y_deg",
        "expected a number, got a string",
    ),
    (
        r#""width":1536"#,
        r#""width":0"#,
        "camera.width",
        "at least 1",
    ),
    (
        r#""height":768"#,
        r#""height":-768"#,
        "camera.height",
        "whole number",
    ),
    (
        r#""height":768"#,
        r#""height":768.5"#,
        "camera.height",
        "whole number in 0..=4294967295, got 768.5",
    ),
    (
        r#""height":768"#,
        r#""height":7.68e2"#,
        "camera.height",
        "without a fraction or exponent (e.g. 768), got 768.0",
    ),
    (
        r#""target":[0,2,0]"#,
        r#""target":[0,2,10]"#,
        "camera.target",
        "must differ from camera.position",
    ),
    (
        r#""position":[0,2,10]"#,
        r#""position":[0,2]"#,
        "camera.position",
        "array of 3 numbers, got an array of 2",
    ),
    (
        r#""position":[0,2,10]"#,
        r#""position":[0,2,10,1]"#,
        "camera.position",
        "got an array of 4",
    ),
    (
        r#""position":[0,2,10]"#,
        r#""position":null"#,
        "camera.position",
        "got null",
    ),
    (
        r#""up":[0,1,0]"#,
        r#""up":[0,0,0]"#,
        "camera.up",
        "non-zero",
    ),
    // Parallel to the view (−Z here): the camera's fallback would pick a roll (audit).
    (
        r#""up":[0,1,0]"#,
        r#""up":[0,0,-3]"#,
        "camera.up",
        "parallel to the view direction",
    ),
    (
        r#""up":[0,1,0]"#,
        r#""upp":[0,1,0]"#,
        "camera.upp",
        "unknown field",
    ),
    (
        r#""far":100}"#,
        r#""far":100, "near":1}"#,
        "camera.near",
        "duplicate field",
    ),
    // Grid.
    (r#""x":24"#, r#""x":0"#, "grid.x", "at least 1, got 0"),
    (
        r#""x":24, "y":12"#,
        r#""x":65536, "y":65536"#,
        "grid",
        "65536 × 65536 × 16 = 68719476736 clusters; cluster ids are u32",
    ),
    (
        r#""z":16"#,
        r#""z":4294967296"#,
        "grid.z",
        "at most 4294967295",
    ),
    (
        r#""depth":"log""#,
        r#""depth":"cubic""#,
        "grid.depth",
        r#"unknown depth slicing "cubic""#,
    ),
    (
        r#""depth":"log""#,
        r#""depth":"log_near""#,
        "grid.first_slice_depth",
        "missing required field",
    ),
    (
        r#""depth":"log""#,
        r#""depth":"log_near", "first_slice_depth":0.05"#,
        "grid.first_slice_depth",
        "strictly between camera.near (0.1) and camera.far (100.0), got 0.05",
    ),
    (
        r#""depth":"log""#,
        r#""depth":"log_near", "first_slice_depth":100"#,
        "grid.first_slice_depth",
        "strictly between",
    ),
    (
        r#""depth":"log""#,
        r#""depth":"linear", "first_slice_depth":1"#,
        "grid.first_slice_depth",
        "only allowed with",
    ),
    (
        r#""depth":"log""#,
        r#""depth":"log","x":24"#,
        "grid.x",
        "duplicate field",
    ),
    // Root.
    (r#""grid":"#, r#""grdi":"#, "grid", "missing required field"),
    (
        r#""lights": ["#,
        r#""extra": 1, "lights": ["#,
        "extra",
        "unknown field",
    ),
    // Lights (Strict reports the first bad one).
    (
        r#""radius":2.5"#,
        r#""radius":0"#,
        "lights[0].radius",
        "must be finite and > 0, got 0.0",
    ),
    (
        r#""radius":2.5"#,
        r#""radius":1e39"#,
        "lights[0].radius",
        "out of the f32 range",
    ),
    (
        r#""radius":2.5"#,
        r#""raduis":2.5"#,
        "lights[0].raduis",
        "unknown field",
    ),
    (
        r#""position":[0,1,-5]"#,
        r#""position":[0,1]"#,
        "lights[0].position",
        "array of 3 numbers",
    ),
    (
        r#""position":[0,1,-5]"#,
        r#""position":[0,1,"-5"]"#,
        "lights[0].position[2]",
        "expected a number",
    ),
    (
        r#""color":[1,0.9,0.8]"#,
        r#""color":[1,-0.9,0.8]"#,
        "lights[0].color",
        "finite and >= 0",
    ),
    (
        r#""intensity":3"#,
        r#""intensity":-3"#,
        "lights[0].intensity",
        "finite and >= 0, got -3.0",
    ),
    (
        r#""direction":[0,-1,0]"#,
        r#""direction":[0,0,0]"#,
        "lights[2].spot.direction",
        "non-zero",
    ),
    (
        r#""angle_deg":30"#,
        r#""angle_deg":181"#,
        "lights[2].spot.angle_deg",
        "(0, 180]",
    ),
    (
        r#""angle_deg":30"#,
        r#""angle_deg":-30"#,
        "lights[2].spot.angle_deg",
        "(0, 180]",
    ),
    (
        r#""angle_deg":30"#,
        r#""angle":30"#,
        "lights[2].spot.angle",
        "unknown field",
    ),
    (
        r#""spot": {"direction":[0,-1,0], "angle_deg":30}"#,
        r#""spot": 1"#,
        "lights[2].spot",
        "expected an object, got a number",
    ),
    (
        r#"{"position":[0,1,-5]"#,
        r#"[],{"position":[0,1,-5]"#,
        "lights[0]",
        "expected an object, got an array",
    ),
];

#[test]
fn every_documented_invalid_value_is_an_error_naming_file_path_and_problem() {
    let base = hand_written_text();
    for &(from, to, path, fragment) in INVALID_EDITS {
        let text = edit(&base, from, to);
        let e = Scene::from_json_str(&text, "edited.json", LightPolicy::Strict)
            .expect_err(&format!("{from} -> {to} should be rejected"));
        let Error::Invalid {
            origin, problem, ..
        } = &e
        else {
            panic!("{from} -> {to}: expected Error::Invalid, got {e}");
        };
        assert_eq!(origin, "edited.json");
        assert_eq!(problem.path, path, "{from} -> {to}: {e}");
        assert!(
            problem.message.contains(fragment),
            "{from} -> {to}: {e}\n  (wanted {fragment:?})"
        );
        assert!(e.to_string().starts_with(&format!("edited.json: {path}: ")));
        let is_light = path.starts_with("lights[");
        assert_eq!(problem.light.is_some(), is_light, "{path}");
        // Light problems can be skipped; scene problems cannot.
        let skip = Scene::from_json_str(&text, "edited.json", LightPolicy::SkipInvalid);
        assert_eq!(skip.is_ok(), is_light, "{from} -> {to}");
        // validate lists the same first problem.
        let report = validate_json_str(&text, "edited.json").unwrap();
        assert_eq!(&report.problems[0], problem);
    }
}

/// An unknown key is named by its first 80 bytes (cut at a character's boundary) and its
/// length: a key of megabytes made an error line of megabytes.
#[test]
fn a_long_unknown_key_is_named_shortened() {
    let base = hand_written_text();
    for (key, shown) in [
        ("k".repeat(80), "k".repeat(80)),
        ("k".repeat(81), format!("{}… (81 bytes)", "k".repeat(80))),
        // Two bytes a character: the cut falls on 80, a boundary; one byte on, it backs off.
        (
            "é".repeat(10_000),
            format!("{}… (20000 bytes)", "é".repeat(40)),
        ),
        (
            format!("k{}", "é".repeat(10_000)),
            format!("k{}… (20001 bytes)", "é".repeat(39)),
        ),
    ] {
        let text = edit(
            &base,
            r#""lights": ["#,
            &format!(r#""{key}": 1, "lights": ["#),
        );
        let e = Scene::from_json_str(&text, "edited.json", LightPolicy::Strict).unwrap_err();
        let Error::Invalid { problem, .. } = &e else {
            panic!("expected Error::Invalid, got {e}");
        };
        assert_eq!(problem.path, shown);
        assert!(problem.message.contains("unknown field"), "{e}");
    }
}

#[test]
fn a_section_of_the_wrong_type_is_one_problem() {
    let text = hand_written_text();
    let start = text.find(r#""camera": "#).unwrap() + r#""camera": "#.len();
    let end = start + text[start..].find('}').unwrap() + 1;
    for (junk, kind) in [("7", "a number"), ("[]", "an array"), ("null", "null")] {
        let edited = format!("{}{junk}{}", &text[..start], &text[end..]);
        let report = validate_json_str(&edited, "t.json").unwrap();
        assert_eq!(report.problems.len(), 1, "{report}");
        assert_eq!(
            report.problems[0].to_string(),
            format!("camera: expected an object, got {kind}")
        );
        // The lights are still checked.
        assert_eq!(report.lights_ok(), 4);
    }
}

#[test]
fn numbers_beyond_f64_and_broken_syntax_are_json_errors_with_position() {
    let base = hand_written_text();
    for (text, fragment) in [
        (
            edit(&base, r#""far":100"#, r#""far":1e999"#),
            "number out of range",
        ),
        (
            edit(&base, r#""radius":2.5"#, r#""radius":-1e400"#),
            "number out of range",
        ),
        (
            edit(&base, r#""far":100"#, r#""far":NaN"#),
            "expected value",
        ),
        (
            edit(&base, r#""far":100"#, r#""far":Infinity"#),
            "expected value",
        ),
        (base[..base.len() / 2].to_string(), "EOF"),
        (String::new(), "EOF"),
        ("   \n ".to_string(), "EOF"),
        ("[]".to_string(), "expected a scene object"),
        ("null".to_string(), "expected a scene object"),
        ("\"scene\"".to_string(), "expected a scene object"),
        (format!("{base} {{}}"), "trailing characters"),
        (
            format!("{}{}", "[".repeat(200), "]".repeat(200)),
            "expected a scene object",
        ),
        (
            format!(r#"{{"camera": {}{}}}"#, "[".repeat(200), "]".repeat(200)),
            "recursion limit",
        ),
    ] {
        let e = Scene::from_json_str(&text, "in.json", LightPolicy::SkipInvalid).unwrap_err();
        assert!(matches!(e, Error::Json { .. }), "{e}");
        assert_eq!(e.to_string(), "in.json: cannot parse scene JSON");
        let shown = chain(&e);
        assert!(shown.contains(fragment), "{shown} (wanted {fragment:?})");
        assert!(shown.contains("line "), "{shown}");
        assert!(validate_json_str(&text, "in.json").is_err());
    }
    // Invalid UTF-8 inside a string, as bytes from a file.
    let mut bytes = edit(&base, r#""depth":"log""#, r#""depth":"lo?""#).into_bytes();
    let at = bytes.iter().position(|&b| b == b'?').unwrap();
    bytes[at] = 0xff;
    let e = Scene::from_json_slice(&bytes, "utf8.json", LightPolicy::Strict).unwrap_err();
    assert!(matches!(e, Error::Json { .. }), "{e}");
}

/// Loads `bytes` every way and checks the ways agree: validation is clean exactly when a strict
/// load succeeds; a failed strict load reports validation's first problem; a lenient load
/// succeeds exactly when every problem is a light's, and keeps exactly the lights validation
/// calls ok.
fn check_consistent(bytes: &[u8]) {
    let strict = Scene::from_json_slice(bytes, "x", LightPolicy::Strict);
    let lenient = Scene::from_json_slice(bytes, "x", LightPolicy::SkipInvalid);
    match validate_json_slice(bytes, "x") {
        Err(e) => {
            // Not JSON, or JSON in UTF-16/32: the same error every way.
            assert!(
                matches!(e, Error::Json { .. } | Error::Encoding { .. }),
                "{e}"
            );
            for load in [strict, lenient] {
                let other = load.expect_err("validation failed");
                assert_eq!(
                    std::mem::discriminant(&other),
                    std::mem::discriminant(&e),
                    "{other}"
                );
            }
        }
        Ok(report) => {
            assert_eq!(report.is_valid(), strict.is_ok());
            if let Err(Error::Invalid { problem, more, .. }) = &strict {
                assert_eq!(problem, &report.problems[0]);
                assert_eq!(more + 1, report.problems.len());
            }
            let lights_only = report.problems.iter().all(|p| p.light.is_some());
            assert_eq!(
                lenient.is_ok(),
                lights_only,
                "problems {:?}; lenient load: {:?}",
                report.problems,
                lenient.as_ref().err()
            );
            if let Ok(s) = &lenient {
                assert_eq!(s.lights.len(), report.lights_ok());
                assert_eq!(s.skipped.len(), report.lights_bad);
                assert!(s.problems().is_empty(), "a loaded scene is always writable");
                let again =
                    Scene::from_json_str(&s.to_json_string().unwrap(), "y", LightPolicy::Strict)
                        .unwrap();
                assert_eq!(again.lights.len(), s.lights.len());
            }
        }
    }
}

#[test]
fn every_truncation_of_the_hand_written_file_is_handled() {
    let text = hand_written_text();
    for end in 0..text.len() {
        check_consistent(&text.as_bytes()[..end]);
    }
    check_consistent(text.as_bytes());
}

#[test]
fn every_value_replaced_by_every_kind_of_junk_is_handled() {
    let text = hand_written_text();
    let replacements = [
        "0",
        "-1",
        "1e39",
        "-1e-50",
        "4294967296",
        "1.5",
        "\"x\"",
        "null",
        "true",
        "[]",
        "[1,2,3]",
        "{}",
        r#"{"direction":[1,0,0],"angle_deg":45}"#,
        "[1e38,1e38,1e38]",
        "[[0,0,0]]",
    ];
    // Every number, string, array and object value position: after each ':' up to the end of its
    // value (a naive scanner is enough for this file, which has no ':' inside strings).
    let bytes = text.as_bytes();
    let mut cases = 0;
    for (colon, _) in text.match_indices(':') {
        let start = colon + 1;
        let mut depth = 0i32;
        let mut end = start;
        while end < bytes.len() {
            match bytes[end] {
                b'[' | b'{' => depth += 1,
                b']' | b'}' if depth == 0 => break,
                b']' | b'}' => depth -= 1,
                b',' if depth == 0 => break,
                _ => {}
            }
            end += 1;
        }
        for r in replacements {
            let edited = format!("{}{}{}", &text[..start], r, &text[end..]);
            check_consistent(edited.as_bytes());
            cases += 1;
        }
    }
    assert!(cases > 500, "{cases}");
}

#[test]
fn binary_garbage_never_panics() {
    let mut rng = Rng(42);
    let alphabet = b"{}[]:,\"0123456789.eE+-truefalsnl \n\\/camerpositgdhx";
    for len in 0..400 {
        let random: Vec<u8> = (0..len).map(|_| rng.next() as u8).collect();
        check_consistent(&random);
        let jsonish: Vec<u8> = (0..len)
            .map(|_| alphabet[(rng.next() % alphabet.len() as u64) as usize])
            .collect();
        check_consistent(&jsonish);
    }
    // Garbage spliced into the middle of a valid file.
    let text = hand_written_text().into_bytes();
    for _ in 0..500 {
        let mut t = text.clone();
        let at = (rng.next() % t.len() as u64) as usize;
        t[at] = rng.next() as u8;
        check_consistent(&t);
    }
}

#[test]
fn optional_fields_accept_null_as_absent() {
    let text = edit(&hand_written_text(), r#""up":[0,1,0]"#, r#""up":null"#);
    let text = edit(
        &text,
        r#""color":[1,0.9,0.8], "intensity":3"#,
        r#""color":null, "intensity":null, "spot":null"#,
    );
    let s = Scene::from_json_str(&text, "n", LightPolicy::Strict).unwrap();
    assert_eq!(s.camera.up, Vec3::Y);
    assert_eq!(s.lights.get(0).color, Vec3::ONE);
    assert_eq!(s.lights.get(0).intensity, 1.0);
    assert!(!s.lights.is_spot(0));
}

/// The error and its sources, joined by ": " (how `anyhow`'s `{:#}` prints it).
fn chain(e: &dyn std::error::Error) -> String {
    let mut shown = e.to_string();
    let mut next = e.source();
    while let Some(source) = next {
        shown = format!("{shown}: {source}");
        next = source.source();
    }
    shown
}

fn scene_with_up(up: &str) -> String {
    format!(
        r#"{{"camera": {{"position":[0,2,10], "target":[0,2,0], "up":{up}, "fov_y_deg":60,
            "width":64, "height":32, "near":0.1, "far":100}},
          "grid": {{"x":4, "y":2, "z":8, "depth":"log"}}, "lights": []}}"#
    )
}

/// `camera.up` is refused exactly when `Camera::basis_f64` would replace it by a world axis
/// (its test is relative to |up|): checked on nearly parallel hints of very different lengths
/// (mutation audit: only an exactly parallel `up` was tested).
#[test]
fn a_nearly_parallel_up_is_judged_relative_to_its_length() {
    // (up, parallel?) for a view along −Z: the perpendicular part over |up| decides.
    for (up, parallel) in [
        ("[0, 1e-4, -1000]", true), // 1e-7 relative: the camera would pick its own roll
        ("[0, 5e-4, -1e-3]", false), // 0.45 relative: a usable (if short) up hint
        ("[0, 1, -3]", false),
        ("[0, 0, -3]", true),
    ] {
        let text = scene_with_up(up);
        let report = validate_json_str(&text, "up.json").unwrap();
        let flagged = report
            .problems
            .iter()
            .any(|p| p.path == "camera.up" && p.message.contains("parallel"));
        assert_eq!(flagged, parallel, "up {up}: {report}");
        assert_eq!(
            Scene::from_json_str(&text, "up.json", LightPolicy::Strict).is_ok(),
            !parallel,
            "up {up}"
        );
    }
}
