//! Lights as structure-of-arrays columns: one `Vec<f32>` per component, one row per light.
//!
//! Columns are what the assignment and upload stages consume (`&[f32]` slices, no per-light
//! structs). [`LightRecord`] is the row type for building and inspecting lights one at a time.
//!
//! Spot columns exist only when needed: a scene without spot lights carries no spot data at all
//! ([`Lights::has_spots`] is false and the five spot columns are empty). Once any light is a spot,
//! every row has spot data and point lights are marked by a zero direction and an angle of π.
//!
//! A spot's inner angle (full strength inside it, then the renderer's falloff to 0 at the outer
//! angle) only shades: it bounds nothing, so the assignment never reads it. Scene-file spots
//! without one, and spots built with [`LightRecord::with_spot`], get
//! [`DEFAULT_SPOT_INNER_FRACTION`] of the outer angle; glTF spots keep their `innerConeAngle`.

use crate::checks::{self, Angle, LightParts, SpotParts, UNIT_TOLERANCE};
use crate::error::Problem;
use crate::json::{Prefix, Sink, show_f32};
use glam::Vec3;
use myriad_cluster_math::SpotCone;
use std::f32::consts::PI;

/// The inner angle of a spot that does not give one, as a fraction of its outer angle (the
/// renderer's fixed fraction before inner angles were kept; `myriad-gpu`'s `SPOT_INNER_FRACTION`
/// for columns without inner angles).
pub const DEFAULT_SPOT_INNER_FRACTION: f32 = 0.8;

/// [`DEFAULT_SPOT_INNER_FRACTION`] of `outer`: the inner angle a spot gets when none is given;
/// 0 for the few subnormal angles where that product rounds back to `outer` (an inner angle must
/// lie below the outer one).
pub fn default_spot_inner_angle(outer: f32) -> f32 {
    let inner = DEFAULT_SPOT_INNER_FRACTION * outer;
    if inner < outer { inner } else { 0.0 }
}

/// Lights as SoA columns. All non-spot columns have the same length ([`Lights::len`]); the spot
/// columns are either all empty (no spot lights) or all of that length.
///
/// Invariants of a valid set (checked by [`Lights::problems`], guaranteed for lights read from a
/// scene file; [`Lights::push`] does not check them): every value is finite, `radius > 0`,
/// colour and intensity `>= 0`, spot directions are unit length (within 1e-6), spot angles in
/// `(0, π]` and a spot's inner angle in `[0, angle)`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Lights {
    /// World-space position, x.
    pub x: Vec<f32>,
    /// World-space position, y.
    pub y: Vec<f32>,
    /// World-space position, z.
    pub z: Vec<f32>,
    /// Range: the light affects nothing farther than this from its position (> 0).
    pub radius: Vec<f32>,
    /// Linear colour, red (>= 0).
    pub r: Vec<f32>,
    /// Linear colour, green (>= 0).
    pub g: Vec<f32>,
    /// Linear colour, blue (>= 0).
    pub b: Vec<f32>,
    /// Intensity multiplier (>= 0).
    pub intensity: Vec<f32>,
    /// Spot axis, x (unit length; 0 for point lights). Empty when no light is a spot.
    pub spot_dir_x: Vec<f32>,
    /// Spot axis, y. Empty when no light is a spot.
    pub spot_dir_y: Vec<f32>,
    /// Spot axis, z. Empty when no light is a spot.
    pub spot_dir_z: Vec<f32>,
    /// Outer half angle of the spot cone in radians, in `(0, π]`; an angle `>= π` means
    /// omnidirectional, and point lights have exactly [`std::f32::consts::PI`]. Empty when no
    /// light is a spot.
    pub spot_angle: Vec<f32>,
    /// Inner half angle of the spot cone in radians, in `[0, spot_angle)`: full strength inside
    /// it, falling to 0 at `spot_angle` (shading only; nothing is bounded by it). 0 for point
    /// lights. Empty when no light is a spot.
    pub spot_inner_angle: Vec<f32>,
    /// Each light's index in the scene file's `lights` array (or whatever numbering the builder
    /// chose), so outputs can refer to input order even when invalid lights were skipped.
    pub source_index: Vec<u32>,
}

/// One light as a row: what [`Lights::push`] takes and [`Lights::get`] returns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightRecord {
    /// World-space position.
    pub position: Vec3,
    /// Range (> 0).
    pub radius: f32,
    /// Linear colour (each component >= 0).
    pub color: Vec3,
    /// Intensity multiplier (>= 0).
    pub intensity: f32,
    /// The spot cone (unit axis, outer half angle in radians), or `None` for a point light.
    pub spot: Option<SpotCone>,
    /// The spot's inner half angle in radians, in `[0, outer)` (0 for a point light).
    pub spot_inner_angle: f32,
    /// Index in the source (the scene file's `lights` array).
    pub source_index: u32,
}

impl LightRecord {
    /// A white point light of intensity 1 with source index 0.
    pub fn point(position: Vec3, radius: f32) -> Self {
        Self {
            position,
            radius,
            color: Vec3::ONE,
            intensity: 1.0,
            spot: None,
            spot_inner_angle: 0.0,
            source_index: 0,
        }
    }

    /// The same light with colour `color`.
    pub fn with_color(self, color: Vec3) -> Self {
        Self { color, ..self }
    }

    /// The same light with intensity `intensity`.
    pub fn with_intensity(self, intensity: f32) -> Self {
        Self { intensity, ..self }
    }

    /// The same light as a spot with unit axis `direction` and outer half angle `angle` (radians),
    /// its inner angle [`DEFAULT_SPOT_INNER_FRACTION`] of that (so set another inner angle after
    /// this, with [`Self::with_spot_inner_angle`]).
    pub fn with_spot(self, direction: Vec3, angle: f32) -> Self {
        Self {
            spot: Some(SpotCone { direction, angle }),
            spot_inner_angle: default_spot_inner_angle(angle),
            ..self
        }
    }

    /// The same light with the spot's inner half angle `inner` (radians, in `[0, outer)`).
    pub fn with_spot_inner_angle(self, inner: f32) -> Self {
        Self {
            spot_inner_angle: inner,
            ..self
        }
    }

    /// The same light with source index `source_index`.
    pub fn with_source_index(self, source_index: u32) -> Self {
        Self {
            source_index,
            ..self
        }
    }
}

impl Lights {
    /// No lights.
    pub fn new() -> Self {
        Self::default()
    }

    /// No lights, with room for `n` in the non-spot columns.
    pub fn with_capacity(n: usize) -> Self {
        Self {
            x: Vec::with_capacity(n),
            y: Vec::with_capacity(n),
            z: Vec::with_capacity(n),
            radius: Vec::with_capacity(n),
            r: Vec::with_capacity(n),
            g: Vec::with_capacity(n),
            b: Vec::with_capacity(n),
            intensity: Vec::with_capacity(n),
            source_index: Vec::with_capacity(n),
            ..Self::default()
        }
    }

    /// Number of lights.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are no lights.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Whether the spot columns are present (some light is, or was pushed as, a spot light).
    pub fn has_spots(&self) -> bool {
        !self.spot_angle.is_empty()
    }

    /// Whether light `i` is a spot light (has a non-zero spot direction).
    pub fn is_spot(&self, i: usize) -> bool {
        self.has_spots()
            && (self.spot_dir_x[i] != 0.0 || self.spot_dir_y[i] != 0.0 || self.spot_dir_z[i] != 0.0)
    }

    /// Appends a light. The first spot light creates the spot columns, filled for the earlier
    /// (point) lights with a zero direction and angle π. Does not validate; see
    /// [`Lights::problems`].
    pub fn push(&mut self, light: LightRecord) {
        // Decided before the backfill: with no earlier lights the backfilled columns are empty.
        let with_spots = light.spot.is_some() || self.has_spots();
        if light.spot.is_some() && !self.has_spots() {
            let n = self.len();
            self.spot_dir_x = vec![0.0; n];
            self.spot_dir_y = vec![0.0; n];
            self.spot_dir_z = vec![0.0; n];
            self.spot_angle = vec![PI; n];
            self.spot_inner_angle = vec![0.0; n];
        }
        self.x.push(light.position.x);
        self.y.push(light.position.y);
        self.z.push(light.position.z);
        self.radius.push(light.radius);
        self.r.push(light.color.x);
        self.g.push(light.color.y);
        self.b.push(light.color.z);
        self.intensity.push(light.intensity);
        self.source_index.push(light.source_index);
        if with_spots {
            let (d, angle, inner) = match light.spot {
                Some(s) => (s.direction, s.angle, light.spot_inner_angle),
                None => (Vec3::ZERO, PI, 0.0),
            };
            self.spot_dir_x.push(d.x);
            self.spot_dir_y.push(d.y);
            self.spot_dir_z.push(d.z);
            self.spot_angle.push(angle);
            self.spot_inner_angle.push(inner);
        }
    }

    /// Light `i` as a row. Panics if `i >= len()` (or the columns have inconsistent lengths).
    pub fn get(&self, i: usize) -> LightRecord {
        let spot = self.is_spot(i).then(|| SpotCone {
            direction: Vec3::new(self.spot_dir_x[i], self.spot_dir_y[i], self.spot_dir_z[i]),
            angle: self.spot_angle[i],
        });
        let spot_inner_angle = if spot.is_some() {
            self.spot_inner_angle[i]
        } else {
            0.0
        };
        LightRecord {
            position: Vec3::new(self.x[i], self.y[i], self.z[i]),
            radius: self.radius[i],
            color: Vec3::new(self.r[i], self.g[i], self.b[i]),
            intensity: self.intensity[i],
            spot,
            spot_inner_angle,
            source_index: self.source_index[i],
        }
    }

    /// All lights as rows, in column order.
    pub fn iter(&self) -> impl DoubleEndedIterator<Item = LightRecord> + ExactSizeIterator + '_ {
        (0..self.len()).map(|i| self.get(i))
    }

    /// Removes all lights (and the spot columns), keeping the allocations.
    pub fn clear(&mut self) {
        for column in self.columns_mut() {
            column.clear();
        }
        self.source_index.clear();
    }

    /// The lights at `indices` (each below [`Lights::len`]), in that order, into `out`, reusing
    /// its storage: the visible subset a frame uploads, say. Spot columns come along when
    /// present.
    ///
    /// From [`crate::systems::PARALLEL_MIN`] rows the columns are gathered in parallel, one
    /// job per column (`cargo bench --bench scene_systems -- gather`, two interleaved runs on 2
    /// vCPUs: the atrium's visible share of 100k lights 455 / 395 µs against 780 / 558 µs on one
    /// thread, of 1M lights 5.4 / 5.5 ms against 9.7 / 9.2 ms).
    pub fn gather_into(&self, indices: &[u32], out: &mut Lights) {
        use rayon::prelude::*;
        let gather = |(src, dst): (&Vec<f32>, &mut Vec<f32>)| {
            dst.clear();
            if !src.is_empty() {
                dst.extend(indices.iter().map(|&i| src[i as usize]));
            }
        };
        let (src, dst) = (self.columns(), out.columns_mut());
        if indices.len() >= crate::systems::PARALLEL_MIN {
            src.into_par_iter().zip(dst).for_each(gather);
        } else {
            src.into_iter().zip(dst).for_each(gather);
        }
        out.source_index.clear();
        out.source_index
            .extend(indices.iter().map(|&i| self.source_index[i as usize]));
    }

    fn columns(&self) -> [&Vec<f32>; 13] {
        [
            &self.x,
            &self.y,
            &self.z,
            &self.radius,
            &self.r,
            &self.g,
            &self.b,
            &self.intensity,
            &self.spot_dir_x,
            &self.spot_dir_y,
            &self.spot_dir_z,
            &self.spot_angle,
            &self.spot_inner_angle,
        ]
    }

    fn columns_mut(&mut self) -> [&mut Vec<f32>; 13] {
        [
            &mut self.x,
            &mut self.y,
            &mut self.z,
            &mut self.radius,
            &mut self.r,
            &mut self.g,
            &mut self.b,
            &mut self.intensity,
            &mut self.spot_dir_x,
            &mut self.spot_dir_y,
            &mut self.spot_dir_z,
            &mut self.spot_angle,
            &mut self.spot_inner_angle,
        ]
    }

    /// Everything that makes this set invalid (see the type's invariants), each problem located
    /// as `lights[source_index].field`. Inconsistent column lengths are one problem at `lights`.
    pub fn problems(&self) -> Vec<Problem> {
        let mut problems = Vec::new();
        let n = self.len();
        let base = [
            ("y", self.y.len()),
            ("z", self.z.len()),
            ("radius", self.radius.len()),
            ("r", self.r.len()),
            ("g", self.g.len()),
            ("b", self.b.len()),
            ("intensity", self.intensity.len()),
            ("source_index", self.source_index.len()),
        ];
        let spot = [
            ("spot_dir_x", self.spot_dir_x.len()),
            ("spot_dir_y", self.spot_dir_y.len()),
            ("spot_dir_z", self.spot_dir_z.len()),
            ("spot_angle", self.spot_angle.len()),
            ("spot_inner_angle", self.spot_inner_angle.len()),
        ];
        let spot_len = if self.has_spots() { n } else { 0 };
        let bad: Vec<String> = base
            .iter()
            .filter(|(_, len)| *len != n)
            .chain(spot.iter().filter(|(_, len)| *len != spot_len))
            .map(|(name, len)| format!("{name} has {len}"))
            .collect();
        if !bad.is_empty() {
            Sink::new(&mut problems, Prefix::Root).report(
                "lights",
                format!(
                    "column lengths differ: x has {n} rows, {} (spot columns must be empty or \
                     match x)",
                    bad.join(", ")
                ),
            );
            return problems;
        }
        for i in 0..n {
            let mut sink = Sink::new(&mut problems, Prefix::Light(self.source_index[i]));
            let spot = if self.has_spots() {
                let d = Vec3::new(self.spot_dir_x[i], self.spot_dir_y[i], self.spot_dir_z[i]);
                let angle = self.spot_angle[i];
                if d == Vec3::ZERO {
                    if angle != PI {
                        sink.report(
                            "spot_angle",
                            format!(
                                "a point light (zero spot direction) must have spot_angle π, got {}",
                                show_f32(angle)
                            ),
                        );
                    }
                    None
                } else {
                    let len = checks::length_f64(d);
                    if d.is_finite() && (len - 1.0).abs() > UNIT_TOLERANCE {
                        sink.report(
                            "spot.direction",
                            format!("must be unit length (within 1e-6), got length {len}"),
                        );
                    }
                    Some(SpotParts {
                        direction: Some(d),
                        angle: Some(Angle::from_rad(angle)),
                        inner: Some(Angle::from_rad(self.spot_inner_angle[i])),
                    })
                }
            } else {
                None
            };
            let parts = LightParts {
                position: Some(Vec3::new(self.x[i], self.y[i], self.z[i])),
                radius: Some(self.radius[i]),
                color: Some(Vec3::new(self.r[i], self.g[i], self.b[i])),
                intensity: Some(self.intensity[i]),
                spot,
            };
            checks::check_light(&parts, self.source_index[i], &mut sink);
        }
        problems
    }
}

impl FromIterator<LightRecord> for Lights {
    fn from_iter<I: IntoIterator<Item = LightRecord>>(iter: I) -> Self {
        let mut lights = Lights::new();
        lights.extend(iter);
        lights
    }
}

impl Extend<LightRecord> for Lights {
    fn extend<I: IntoIterator<Item = LightRecord>>(&mut self, iter: I) {
        for light in iter {
            self.push(light);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_lights_have_no_spot_columns() {
        let lights: Lights = (0..3)
            .map(|i| LightRecord::point(Vec3::splat(i as f32), 1.0).with_source_index(i))
            .collect();
        assert_eq!(lights.len(), 3);
        assert!(!lights.is_empty() && !lights.has_spots() && !lights.is_spot(1));
        assert!(lights.spot_dir_x.is_empty() && lights.spot_angle.is_empty());
        assert_eq!(lights.source_index, [0, 1, 2]);
        assert!(lights.problems().is_empty());
    }

    #[test]
    fn first_spot_backfills_the_spot_columns() {
        let mut lights = Lights::new();
        lights.push(LightRecord::point(Vec3::ZERO, 1.0));
        lights.push(LightRecord::point(Vec3::X, 2.0).with_source_index(4));
        let spot = LightRecord::point(Vec3::Y, 3.0)
            .with_color(Vec3::new(1.0, 0.5, 0.25))
            .with_intensity(2.0)
            .with_spot(Vec3::NEG_Y, 0.5)
            .with_source_index(7);
        lights.push(spot);
        lights.push(LightRecord::point(Vec3::Z, 4.0));
        assert!(lights.has_spots());
        for column in [
            &lights.spot_dir_x,
            &lights.spot_dir_y,
            &lights.spot_dir_z,
            &lights.spot_angle,
        ] {
            assert_eq!(column.len(), 4);
        }
        assert_eq!(lights.spot_angle, [PI, PI, 0.5, PI]);
        assert_eq!(lights.spot_dir_y, [0.0, 0.0, -1.0, 0.0]);
        assert_eq!(lights.get(2), spot);
        assert_eq!(lights.get(1).spot, None);
        assert_eq!(lights.get(1).source_index, 4);
        let rows: Vec<LightRecord> = lights.iter().collect();
        assert_eq!(rows.iter().copied().collect::<Lights>(), lights);
        assert!(lights.problems().is_empty());
        lights.clear();
        assert!(lights.is_empty() && !lights.has_spots() && lights.source_index.is_empty());
    }

    #[test]
    fn gather_into_picks_rows_in_order_and_reuses_the_output() {
        let mut lights = Lights::new();
        for i in 0..5 {
            let light = LightRecord::point(Vec3::new(i as f32, 1.0, 2.0), 0.5 + i as f32)
                .with_intensity(10.0 * i as f32)
                .with_source_index(100 + i);
            lights.push(if i == 3 {
                light.with_spot(Vec3::Y, 0.4)
            } else {
                light
            });
        }
        // Stale content of a larger earlier frame must not survive.
        let mut out: Lights = (0..9)
            .map(|i| LightRecord::point(Vec3::splat(i as f32), 9.0))
            .collect();
        lights.gather_into(&[1, 3, 4], &mut out);
        assert_eq!(out.len(), 3);
        assert!(out.problems().is_empty(), "{:?}", out.problems());
        assert_eq!(out.get(0), lights.get(1));
        assert_eq!(out.get(1), lights.get(3));
        assert!(out.is_spot(1) && !out.is_spot(2));
        assert_eq!(out.get(2), lights.get(4));
        // Point lights only: no spot columns appear; no indices: no lights.
        let points: Lights = lights.iter().filter(|l| l.spot.is_none()).collect();
        points.gather_into(&[0, 2], &mut out);
        assert!(!out.has_spots() && out.len() == 2);
        assert_eq!(out.get(1), points.get(2));
        points.gather_into(&[], &mut out);
        assert!(out.is_empty() && out.source_index.is_empty());
        // Enough rows for the parallel path: the same rows, in order.
        let n = 3 * crate::systems::PARALLEL_MIN;
        let many: Lights = (0..n)
            .map(|i| {
                let light = LightRecord::point(Vec3::new(i as f32, 0.0, -1.0), 1.0)
                    .with_source_index(i as u32);
                if i % 7 == 0 {
                    light.with_spot(Vec3::NEG_Z, 0.3)
                } else {
                    light
                }
            })
            .collect();
        let odd: Vec<u32> = (1..n as u32).step_by(2).collect();
        many.gather_into(&odd, &mut out);
        assert_eq!(out.len(), odd.len());
        assert!(
            odd.iter()
                .enumerate()
                .all(|(k, &i)| out.get(k) == many.get(i as usize))
        );
    }

    #[test]
    fn problems_name_source_index_and_field() {
        let mut lights = Lights::new();
        lights.push(LightRecord::point(Vec3::ZERO, -1.0).with_source_index(9));
        lights.push(
            LightRecord::point(Vec3::ZERO, 1.0)
                .with_spot(Vec3::new(0.0, 2.0, 0.0), 0.5)
                .with_source_index(11),
        );
        lights.push(
            LightRecord::point(Vec3::ZERO, 1.0)
                .with_spot(Vec3::Y, 4.0)
                .with_source_index(12),
        );
        lights.push(
            LightRecord::point(Vec3::ZERO, 1.0)
                .with_spot(Vec3::Y, 0.5)
                .with_spot_inner_angle(0.5)
                .with_source_index(13),
        );
        lights.spot_angle[0] = 1.0;
        let shown: Vec<String> = lights.problems().iter().map(|p| p.to_string()).collect();
        assert_eq!(shown.len(), 5, "{shown:#?}");
        assert!(
            shown[4].starts_with("lights[13].spot.inner_angle_deg: must be in [0, angle_deg"),
            "{}",
            shown[4]
        );
        assert!(shown[0].starts_with("lights[9].spot_angle: a point light"));
        assert_eq!(
            shown[1],
            "lights[9].radius: must be finite and > 0, got -1.0"
        );
        assert_eq!(
            shown[2],
            "lights[11].spot.direction: must be unit length (within 1e-6), got length 2"
        );
        assert!(
            shown[3].starts_with("lights[12].spot.angle_deg: must be in (0, 180] degrees"),
            "{}",
            shown[3]
        );
    }

    #[test]
    fn inconsistent_columns_are_one_problem_not_a_panic() {
        let mut lights: Lights = [LightRecord::point(Vec3::ZERO, 1.0)].into_iter().collect();
        lights.radius.push(2.0);
        lights.spot_angle.push(1.0);
        let problems = lights.problems();
        assert_eq!(problems.len(), 1);
        assert_eq!(problems[0].path, "lights");
        assert!(problems[0].message.contains("radius has 2"), "{problems:?}");
        assert!(
            problems[0].message.contains("spot_dir_x has 0"),
            "{problems:?}"
        );
    }
}
