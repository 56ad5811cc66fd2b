//! The scene a dump was assigned from, recorded in the dump so that `myriad check` can tell a
//! dump of another view or of other lights from a wrong one.
//!
//! The dump format (DESIGN.md) names only the grid and its planes, which `check_against`
//! compares. A dump of the same preset with another seed, or of a scene whose camera moved but
//! kept its field of view and depth range, has the very same planes: checked against the wrong
//! scene it reported thousands of "misses", a verdict on the assignment that was really a
//! mix-up of files. `myriad assign` therefore writes an optional `scene` record — the camera as
//! loaded and the lights' count and checksum — and `check` compares it first, before the grid,
//! naming what differs. A dump without the record (`myriad assign --bare`, an earlier
//! `myriad assign`, another tool) is checked as before.
//!
//! The checksum covers what the assignment reads, as it reads it: each loaded light's file
//! index, position and range, and a spot's cone. Colours, intensities and inner angles are left
//! out on purpose (they change no list), and so are the invalid lights skipped on loading,
//! beyond their share of the count (nothing lists them). Values that mean the same light hash
//! the same: `-0` as `0`, and a cone of angle `π` or with a zero axis — a point light, in the
//! assignment and the renderer alike — as no cone, so a scene whose spots are all such is a
//! point-light scene. CRC-32 (`crc32fast`) because the record must read the same in every build
//! that checks it: it guards against mix-ups, not against forgery. It is written as 8 hex digits
//! and read in either case; anything else makes the dump invalid on loading.

use anyhow::{Result, bail, ensure};
use myriad_cluster_math::Camera;
use myriad_scene::{Lights, Scene};
use serde::{Deserialize, Serialize};

/// What a dump was assigned from (the dump's optional `scene` key).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneStamp {
    /// The scene's camera as loaded.
    pub camera: StampCamera,
    /// The scene file's lights, the invalid ones skipped on loading included: the range of the
    /// dump's indices.
    pub lights: u64,
    /// CRC-32 of the loaded lights' geometry (module docs); in JSON 8 hex digits, written
    /// lower-case.
    #[serde(with = "hex_u32")]
    pub lights_crc32: u32,
}

/// A camera as the dump records it: the scene file's record, with the field of view in the
/// radians the loader turned its degrees into (exact in JSON, where degrees would round).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StampCamera {
    /// Eye position.
    pub position: [f32; 3],
    /// The point looked at.
    pub target: [f32; 3],
    /// Up direction.
    pub up: [f32; 3],
    /// Vertical field of view, radians.
    pub fov_y_rad: f32,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Near plane's view depth.
    pub near: f32,
    /// Far plane's view depth.
    pub far: f32,
}

impl StampCamera {
    /// `camera`'s record, or `None` where a number is not finite (an engine's infinite far
    /// plane): JSON has no infinity, and such a camera comes from no scene file.
    fn of(camera: &Camera) -> Option<Self> {
        let c = camera;
        let finite = [c.position, c.target, c.up].iter().all(|v| v.is_finite())
            && [c.fov_y, c.near, c.far].iter().all(|v| v.is_finite());
        finite.then(|| Self {
            position: c.position.to_array(),
            target: c.target.to_array(),
            up: c.up.to_array(),
            fov_y_rad: c.fov_y,
            width: c.width,
            height: c.height,
            near: c.near,
            far: c.far,
        })
    }

    /// The first field in which `self` (the dump's) differs from `other` (the scene's), named
    /// with both values.
    fn first_difference(&self, other: &Self) -> Option<String> {
        let vectors = [
            ("position", self.position, other.position),
            ("target", self.target, other.target),
            ("up", self.up, other.up),
        ];
        if let Some((name, a, b)) = vectors.into_iter().find(|(_, a, b)| a != b) {
            return Some(format!("{name} {a:?}, the scene's {b:?}"));
        }
        let numbers = [
            ("fov_y_rad", self.fov_y_rad, other.fov_y_rad),
            ("near", self.near, other.near),
            ("far", self.far, other.far),
        ];
        if let Some((name, a, b)) = numbers.into_iter().find(|(_, a, b)| a != b) {
            return Some(format!("{name} {a}, the scene's {b}"));
        }
        let size = |c: &Self| format!("{}x{}", c.width, c.height);
        (size(self) != size(other))
            .then(|| format!("size {}, the scene's {}", size(self), size(other)))
    }
}

impl SceneStamp {
    /// The record of `scene`, or `None` where its camera has a number JSON cannot hold.
    pub fn of(scene: &Scene) -> Option<Self> {
        Some(Self {
            camera: StampCamera::of(&scene.camera)?,
            lights: (scene.lights.len() + scene.skipped.len()) as u64,
            lights_crc32: lights_crc32(&scene.lights),
        })
    }

    /// Checks that `scene` is the one this record was made from; the error names the first
    /// difference: the light count, the camera, then the lights' positions, ranges or cones.
    pub fn check(&self, scene: &Scene) -> Result<()> {
        let lights = (scene.lights.len() + scene.skipped.len()) as u64;
        ensure!(
            self.lights == lights,
            "the dump was assigned from a scene of {} lights, this one has {lights}",
            self.lights
        );
        let Some(camera) = StampCamera::of(&scene.camera) else {
            bail!("the scene's camera has a number that is not finite: no dump records it");
        };
        if let Some(difference) = self.camera.first_difference(&camera) {
            bail!("the dump was assigned from another view: its camera has {difference}");
        }
        let crc = lights_crc32(&scene.lights);
        ensure!(
            self.lights_crc32 == crc,
            "the dump was assigned from other lights: their checksum is {:08x}, this scene's \
             {crc:08x} (the same count of lights in other places, sizes, cones or order: another \
             seed, or an edited file?)",
            self.lights_crc32
        );
        Ok(())
    }
}

/// CRC-32 of what the assignment reads of `lights` (module docs): per light its file index,
/// position and radius, then for a spot a marker word and its axis and angle, as little-endian
/// words.
fn lights_crc32(lights: &Lights) -> u32 {
    // No file index (there are fewer than `u32::MAX` lights) and no loaded value (its bits are
    // a NaN's): a cone's words cannot be read as the next light's.
    const SPOT: u32 = u32::MAX;
    // `+ 0.0` turns `-0` into `0`, which the assignment cannot tell apart.
    let bits = |v: f32| (v + 0.0).to_bits();
    let mut crc = crc32fast::Hasher::new();
    let mut words = Vec::with_capacity(10);
    for l in 0..lights.len() {
        words.clear();
        words.push(lights.source_index[l]);
        words.extend([lights.x[l], lights.y[l], lights.z[l], lights.radius[l]].map(bits));
        // A cone bounds the light only below `π` and with an axis (`Lights::is_spot`).
        if lights.is_spot(l) && lights.spot_angle[l] < std::f32::consts::PI {
            words.push(SPOT);
            words.extend(
                [
                    lights.spot_dir_x[l],
                    lights.spot_dir_y[l],
                    lights.spot_dir_z[l],
                    lights.spot_angle[l],
                ]
                .map(bits),
            );
        }
        for w in &words {
            crc.update(&w.to_le_bytes());
        }
    }
    crc.finalize()
}

/// The checksum's JSON form: exactly 8 hex digits, written lower-case, read in either case.
mod hex_u32 {
    use serde::{Deserialize, Deserializer, Serializer, de::Error};

    pub fn serialize<S: Serializer>(value: &u32, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&format!("{value:08x}"))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
        let text = String::deserialize(d)?;
        let hex = text.len() == 8 && text.bytes().all(|b| b.is_ascii_hexdigit());
        hex.then(|| u32::from_str_radix(&text, 16).ok())
            .flatten()
            .ok_or_else(|| D::Error::custom(format!("{text:?} is not 8 hex digits")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use myriad_cluster_math::glam::Vec3;
    use myriad_scene::{LightPolicy, LightRecord, SpotCone};

    const SCENE: &str = r#"{
      "camera": {"position": [0, 1, 5], "target": [0, 1, 0], "up": [0, 1, 0], "fov_y_deg": 60,
                 "width": 320, "height": 180, "near": 0.1, "far": 50},
      "grid": {"x": 8, "y": 4, "z": 8, "depth": "log"},
      "lights": [{"position": [0, 0, -5], "radius": 1},
                 {"position": [0, 0, -5], "radius": -1},
                 {"position": [1, 0, -8], "radius": 2, "color": [1, 0, 0]}]
    }"#;

    fn scene() -> Scene {
        Scene::from_json_str(SCENE, "stamp test", LightPolicy::SkipInvalid).unwrap()
    }

    #[test]
    fn a_stamp_survives_json_and_matches_its_own_scene() {
        let stamp = SceneStamp::of(&scene()).unwrap();
        assert_eq!(stamp.lights, 3, "the skipped light counts");
        let text = serde_json::to_string(&stamp).unwrap();
        let back: SceneStamp = serde_json::from_str(&text).unwrap();
        assert_eq!(back, stamp);
        back.check(&scene()).unwrap();
        // The degrees of the file came back as the loader's radians, to the bit.
        assert_eq!(back.camera.fov_y_rad, scene().camera.fov_y);
    }

    #[test]
    fn another_view_is_named_by_its_first_difference() {
        let stamp = SceneStamp::of(&scene()).unwrap();
        let mut moved = scene();
        moved.camera.position.x = 0.5;
        let e = stamp.check(&moved).unwrap_err().to_string();
        assert_eq!(
            e,
            "the dump was assigned from another view: its camera has position [0.0, 1.0, 5.0], \
             the scene's [0.5, 1.0, 5.0]"
        );
        let mut wider = scene();
        wider.camera.width = 640;
        let e = stamp.check(&wider).unwrap_err().to_string();
        assert!(e.ends_with("size 320x180, the scene's 640x180"), "{e}");
        // Every field is compared: a turned camera keeps the grid's planes, so for `target`
        // and `up` this record is the only guard (review: dropping either passed every test).
        type Edit = (&'static str, fn(&mut Camera));
        let edits: [Edit; 6] = [
            ("target", |c| c.target.y = 1.5),
            ("up", |c| c.up = Vec3::new(0.1, 1.0, 0.0)),
            ("fov_y_rad", |c| c.fov_y *= 0.5),
            ("near", |c| c.near = 0.2),
            ("far", |c| c.far = 60.0),
            ("size", |c| c.height = 200),
        ];
        for (field, edit) in edits {
            let mut other = scene();
            edit(&mut other.camera);
            let e = stamp.check(&other).unwrap_err().to_string();
            assert!(
                e.starts_with(&format!(
                    "the dump was assigned from another view: its camera has {field} "
                )),
                "{field}: {e}"
            );
        }
    }

    #[test]
    fn other_lights_of_the_same_count_fail_the_checksum_and_colours_do_not() {
        let stamp = SceneStamp::of(&scene()).unwrap();
        for edit in [
            (|l: &mut Lights| l.x[1] += 1e-6) as fn(&mut Lights),
            |l| l.y[0] = 0.5,
            |l| l.z[1] = -8.5,
            |l| l.radius[0] = 1.5,
            |l| l.source_index.swap(0, 1),
        ] {
            let mut other = scene();
            edit(&mut other.lights);
            let e = stamp.check(&other).unwrap_err().to_string();
            assert!(
                e.starts_with("the dump was assigned from other lights"),
                "{e}"
            );
        }
        let mut recoloured = scene();
        recoloured.lights.g[1] = 0.25;
        recoloured.lights.intensity[0] = 7.0;
        stamp.check(&recoloured).unwrap();
        // A cone is part of the geometry: its angle and each of its axis' components.
        let with_cone = |direction: Vec3, angle: f32| {
            let mut s = scene();
            let record = s.lights.get(0);
            s.lights.push(LightRecord {
                spot: Some(SpotCone { direction, angle }),
                ..record
            });
            s
        };
        let stamp = SceneStamp::of(&with_cone(Vec3::NEG_Z, 0.5)).unwrap();
        for (direction, angle) in [
            (Vec3::NEG_Z, 0.6),
            (Vec3::new(0.1, 0.0, -1.0), 0.5),
            (Vec3::new(0.0, 0.1, -1.0), 0.5),
            (Vec3::new(0.0, 0.0, -2.0), 0.5),
        ] {
            let e = stamp
                .check(&with_cone(direction, angle))
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with("the dump was assigned from other lights"),
                "{direction} {angle}: {e}"
            );
        }
    }

    #[test]
    fn the_same_lights_written_otherwise_pass() {
        // `-0` is `0` to the assignment.
        let stamp = SceneStamp::of(&scene()).unwrap();
        let mut signed = scene();
        signed.lights.x[0] = -0.0;
        signed.lights.y[1] = -0.0;
        stamp.check(&signed).unwrap();
        // A cone of `π`, or with no axis, is a point light: the scene is a point-light scene.
        let mut points = scene();
        let record = points.lights.get(0);
        points.lights.push(record);
        let stamp = SceneStamp::of(&points).unwrap();
        for spot in [
            SpotCone {
                direction: Vec3::NEG_Z,
                angle: std::f32::consts::PI,
            },
            SpotCone {
                direction: Vec3::ZERO,
                angle: 0.5,
            },
        ] {
            let mut coned = scene();
            coned.lights.push(LightRecord {
                spot: Some(spot),
                ..record
            });
            assert!(coned.lights.has_spots());
            stamp.check(&coned).unwrap();
        }
    }

    #[test]
    fn the_checksum_reads_in_either_case_and_nothing_else() {
        let stamp = SceneStamp::of(&scene()).unwrap();
        let text = serde_json::to_string(&stamp).unwrap();
        let lower = format!("{:08x}", stamp.lights_crc32);
        assert!(
            text.contains(&format!("\"lights_crc32\":\"{lower}\"")),
            "{text}"
        );
        let upper = text.replace(&lower, &lower.to_uppercase());
        let back: SceneStamp = serde_json::from_str(&upper).unwrap();
        back.check(&scene()).unwrap();
        for bad in ["zz", "1234567", "123456789", "+1234567", ""] {
            let broken = text.replace(&lower, bad);
            let e = serde_json::from_str::<SceneStamp>(&broken)
                .unwrap_err()
                .to_string();
            assert!(e.contains("is not 8 hex digits"), "{bad}: {e}");
        }
    }

    #[test]
    fn another_count_of_lights_is_said_first() {
        let stamp = SceneStamp::of(&scene()).unwrap();
        let mut more = scene();
        more.lights.push(more.lights.get(0));
        let e = stamp.check(&more).unwrap_err().to_string();
        assert_eq!(
            e,
            "the dump was assigned from a scene of 3 lights, this one has 4"
        );
    }

    #[test]
    fn an_infinite_far_plane_is_not_stamped() {
        let mut s = scene();
        s.camera.far = f32::INFINITY;
        assert_eq!(SceneStamp::of(&s), None);
    }
}
