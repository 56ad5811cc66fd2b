//! What a frame hands the renderer: borrowed light columns and CSR light lists (no scene or
//! assignment types, so this crate depends on neither), and their conversion to GPU records.

use crate::layout::{GpuLight, spot_chord2};
use glam::DVec3;

/// Spot columns, one row per light (point lights: angle >= π).
#[derive(Clone, Copy, Debug)]
pub struct SpotColumns<'a> {
    /// Axis, x (any length: normalised on upload; a zero axis makes a point light).
    pub dir_x: &'a [f32],
    /// Axis, y.
    pub dir_y: &'a [f32],
    /// Axis, z.
    pub dir_z: &'a [f32],
    /// Outer half angle, radians.
    pub angle: &'a [f32],
    /// Inner half angle, radians, in `[0, angle)`: full strength inside it, the falloff to 0 at
    /// `angle` outside (shading only: the lists are bounded by `angle`). `None`:
    /// [`SPOT_INNER_FRACTION`] of `angle` for every spot.
    pub inner_angle: Option<&'a [f32]>,
}

/// A frame's lights as SoA columns, world space (the scene's units: the shading's falloff takes
/// them as metres); all columns have the same length. A light's radiance at distance `d` is
/// `colour × intensity × window(d / radius)² / (d² + 1)`, the window `max(1 − (d/radius)⁴, 0)`
/// (`shaders/common/lighting.wgsl`): exactly 0 at and past `radius`, which is what the
/// assignment bounds.
#[derive(Clone, Copy, Debug)]
pub struct LightColumns<'a> {
    /// Position x.
    pub x: &'a [f32],
    /// Position y.
    pub y: &'a [f32],
    /// Position z.
    pub z: &'a [f32],
    /// Range, in the positions' units: the light reaches nothing at or past this distance.
    pub radius: &'a [f32],
    /// Linear colour, red.
    pub r: &'a [f32],
    /// Linear colour, green.
    pub g: &'a [f32],
    /// Linear colour, blue.
    pub b: &'a [f32],
    /// Intensity multiplier of the colour (unitless; the falloff above carries the distance).
    pub intensity: &'a [f32],
    /// Spot columns, when any light is a spot.
    pub spot: Option<SpotColumns<'a>>,
}

impl LightColumns<'_> {
    /// Number of lights.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are no lights.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Whether every column has [`Self::len`] rows.
    pub fn check(&self) -> Result<(), String> {
        let n = self.len();
        let lens = [
            self.y.len(),
            self.z.len(),
            self.radius.len(),
            self.r.len(),
            self.g.len(),
            self.b.len(),
            self.intensity.len(),
        ];
        let spot_lens = self.spot.map(|s| {
            [
                s.dir_x.len(),
                s.dir_y.len(),
                s.dir_z.len(),
                s.angle.len(),
                s.inner_angle.map_or(n, <[f32]>::len),
            ]
        });
        match lens
            .iter()
            .chain(spot_lens.iter().flatten())
            .find(|&&l| l != n)
        {
            Some(l) => Err(format!(
                "light columns differ in length: {n} positions, a column of {l}"
            )),
            None => Ok(()),
        }
    }
}

/// Cluster light lists in CSR form: cluster `c` has `indices[offsets[c]..offsets[c] + counts[c]]`.
#[derive(Clone, Copy, Debug)]
pub struct ClusterLists<'a> {
    /// Start of each cluster's run in `indices`.
    pub offsets: &'a [u32],
    /// Lights per cluster.
    pub counts: &'a [u32],
    /// Light indices (into the uploaded light columns).
    pub indices: &'a [u32],
}

impl ClusterLists<'_> {
    /// Checks the lists against the grid's cluster count and the number of lights: every run
    /// inside `indices`, every index a light.
    pub fn check(&self, clusters: usize, lights: usize) -> Result<(), String> {
        if self.offsets.len() != clusters || self.counts.len() != clusters {
            return Err(format!(
                "light lists describe {} offsets and {} counts for a grid of {clusters} clusters",
                self.offsets.len(),
                self.counts.len()
            ));
        }
        let total = self.indices.len() as u64;
        if let Some(c) =
            (0..clusters).find(|&c| self.offsets[c] as u64 + self.counts[c] as u64 > total)
        {
            return Err(format!("cluster {c}'s list runs past the {total} indices"));
        }
        if self.lights_named() > lights {
            return Err(format!(
                "light index {} in the lists, but only {lights} lights",
                self.lights_named() - 1
            ));
        }
        Ok(())
    }

    /// How many lights the lists need: one more than the largest index (0 without indices).
    pub fn lights_named(&self) -> usize {
        self.indices.iter().max().map_or(0, |&i| i as usize + 1)
    }

    /// The largest list.
    pub fn max_count(&self) -> u32 {
        self.counts.iter().copied().max().unwrap_or(0)
    }
}

/// Fraction of the outer cone angle where a spot reaches full strength, for spot columns without
/// inner angles ([`SpotColumns::inner_angle`] `None`).
pub const SPOT_INNER_FRACTION: f32 = 0.8;

/// Converts the columns to camera-relative GPU records in `out` (reusing its storage).
/// Positions are differenced in f64, so lights far from the origin keep their precision near the
/// camera. Invalid rows (non-finite values, radius <= 0, negative colour, a spot's inner angle
/// outside `[0, angle)`) become records that
/// light nothing (radius 0 at the camera) — the assignment skips the rows whose position or
/// radius is invalid, and lists those whose appearance alone is — and are counted in the return
/// value.
///
/// # Panics
/// When the columns differ in length, with [`LightColumns::check`]'s message (the renderer checks
/// them first and returns [`crate::GpuError::InvalidInput`] instead).
pub fn fill_gpu_lights(
    columns: &LightColumns<'_>,
    camera: DVec3,
    out: &mut Vec<GpuLight>,
) -> usize {
    if let Err(problem) = columns.check() {
        panic!("fill_gpu_lights: {problem}");
    }
    out.clear();
    out.reserve(columns.len());
    let mut skipped = 0;
    for i in 0..columns.len() {
        let position = DVec3::new(
            columns.x[i] as f64,
            columns.y[i] as f64,
            columns.z[i] as f64,
        );
        let color = [columns.r[i], columns.g[i], columns.b[i]].map(|c| c * columns.intensity[i]);
        let radius = columns.radius[i];
        let mut light = GpuLight {
            position: (position - camera).as_vec3().to_array(),
            radius,
            color,
            spot_chord2_outer: GpuLight::POINT_CHORD2_OUTER,
            spot_dir: [0.0; 3],
            spot_ramp_scale: 0.0,
        };
        let mut valid = position.is_finite()
            && radius.is_finite()
            && radius > 0.0
            && color.iter().all(|c| c.is_finite() && *c >= 0.0);
        if let Some(s) = &columns.spot {
            let angle = s.angle[i];
            let inner = s
                .inner_angle
                .map_or(angle * SPOT_INNER_FRACTION, |inner| inner[i]);
            let dir = [s.dir_x[i], s.dir_y[i], s.dir_z[i]];
            valid &= angle.is_finite() && angle > 0.0 && dir.iter().all(|d| d.is_finite());
            // Normalised here, as `myriad-assignment` does (its axis "need not be normalised"):
            // the shader measures the angle by the chord between this axis and a unit direction,
            // so a longer one would cut the cone off at cluster edges. A zero axis bounds nothing: the light
            // shines all round, as the assignment treats it. In f64, as there: an f32 axis
            // shorter than ~1e-19 has a squared length that underflows to zero, and the light
            // would shine all round here while the lists hold only its cone's clusters.
            let axis = glam::DVec3::from_array(dir.map(f64::from))
                .normalize_or_zero()
                .as_vec3();
            if angle < std::f32::consts::PI && axis != glam::Vec3::ZERO {
                valid &= inner >= 0.0 && inner < angle;
                let (outer, ramp_scale) = spot_ramp(angle, inner);
                light.spot_chord2_outer = outer;
                light.spot_ramp_scale = ramp_scale;
                light.spot_dir = axis.to_array();
            }
        }
        if !valid {
            skipped += 1;
            light = GpuLight::default();
        }
        out.push(light);
    }
    skipped
}

/// A spot's outer squared chord and its falloff's slope ([`GpuLight::spot_chord2_outer`],
/// [`GpuLight::spot_ramp_scale`]) for outer and inner half angles `outer > inner >= 0`, in f64: at
/// 0.05° the two chords differ by 2.7e-7, a few f32 steps of either one, so the difference is
/// not taken in f32. The slope is capped at `f32::MAX`, where the angles are too close for f32
/// (a cone under ~1e-19 rad, whose chord is no longer a normal f32 either, lights nothing).
fn spot_ramp(outer: f32, inner: f32) -> (f32, f32) {
    let chord2_outer = spot_chord2(outer as f64);
    let ramp = chord2_outer - spot_chord2(inner as f64);
    let scale = (1.0 / ramp).min(f32::MAX as f64);
    (chord2_outer as f32, scale as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spot_axes_are_normalised_and_a_zero_axis_is_a_point_light() {
        let one = [1.0f32; 4];
        let columns = LightColumns {
            x: &[0.0; 4],
            y: &[0.0; 4],
            z: &[0.0; 4],
            radius: &[2.0; 4],
            r: &one,
            g: &one,
            b: &one,
            intensity: &one,
            spot: Some(SpotColumns {
                dir_x: &[0.0, 0.0, 0.0, 3e-30],
                dir_y: &[-3.0, 0.0, 1.0, 0.0],
                dir_z: &[0.0, 0.0, 0.0, 0.0],
                angle: &[0.5, 0.5, std::f32::consts::PI, 0.5],
                inner_angle: None,
            }),
        };
        let mut out = Vec::new();
        assert_eq!(fill_gpu_lights(&columns, DVec3::ZERO, &mut out), 0);
        assert_eq!(out[0].spot_dir, [0.0, -1.0, 0.0]);
        assert_eq!(out[0].spot_chord2_outer, spot_chord2(0.5) as f32);
        // An axis whose f32 squared length underflows is still a direction (the assignment
        // normalises in f64 and cuts the lists to the cone).
        assert_eq!(out[3].spot_dir, [1.0, 0.0, 0.0]);
        assert_eq!(out[3].spot_chord2_outer, spot_chord2(0.5) as f32);
        for point in &out[1..3] {
            assert_eq!(point.spot_chord2_outer, GpuLight::POINT_CHORD2_OUTER);
        }
    }

    #[test]
    fn invalid_lights_are_counted_and_become_dark_records_at_the_camera() {
        let nan = f32::NAN;
        let inf = f32::INFINITY;
        // Row 0 is valid; each other row has one bad value: a NaN position, an infinite, zero
        // or negative radius, a negative or NaN colour, an infinite intensity.
        let columns = LightColumns {
            x: &[1.0, nan, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            y: &[2.0; 8],
            z: &[3.0; 8],
            radius: &[2.0, 1.0, inf, 0.0, -1.0, 1.0, 1.0, 1.0],
            r: &[0.5, 1.0, 1.0, 1.0, 1.0, -0.5, nan, 1.0],
            g: &[0.25; 8],
            b: &[1.0; 8],
            intensity: &[2.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, inf],
            spot: None,
        };
        // Stale records from an earlier frame are replaced, not appended to.
        let mut out = vec![GpuLight::default(); 3];
        let camera = DVec3::new(0.5, -1.0, 10.0);
        assert_eq!(fill_gpu_lights(&columns, camera, &mut out), 7);
        assert_eq!(out.len(), 8);
        assert_eq!(
            out[0],
            GpuLight {
                position: [0.5, 3.0, -7.0],
                radius: 2.0,
                color: [1.0, 0.5, 2.0],
                spot_chord2_outer: GpuLight::POINT_CHORD2_OUTER,
                spot_dir: [0.0; 3],
                spot_ramp_scale: 0.0,
            }
        );
        for (i, skipped) in out.iter().enumerate().skip(1) {
            assert_eq!(*skipped, GpuLight::default(), "row {i}");
        }
    }

    #[test]
    fn spots_with_a_bad_angle_or_axis_are_counted_and_become_dark_records() {
        let nan = f32::NAN;
        let one = [1.0f32; 8];
        // Row 0 is a valid spot, row 6 a valid point light (angle π); rows 1–5 have a NaN,
        // infinite, zero or negative angle or a NaN axis; row 7 a good spot on a NaN radius.
        let columns = LightColumns {
            x: &[0.0; 8],
            y: &[0.0; 8],
            z: &[0.0; 8],
            radius: &[1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, nan],
            r: &one,
            g: &one,
            b: &one,
            intensity: &one,
            spot: Some(SpotColumns {
                dir_x: &[0.0, 1.0, 1.0, 1.0, 1.0, nan, 0.0, 1.0],
                dir_y: &[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                dir_z: &[-2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                angle: &[
                    0.5,
                    nan,
                    f32::INFINITY,
                    0.0,
                    -0.5,
                    0.5,
                    std::f32::consts::PI,
                    0.5,
                ],
                inner_angle: None,
            }),
        };
        let mut out = Vec::new();
        assert_eq!(fill_gpu_lights(&columns, DVec3::ZERO, &mut out), 6);
        assert_eq!(
            out[0],
            GpuLight {
                position: [0.0; 3],
                radius: 1.0,
                color: [1.0; 3],
                spot_chord2_outer: spot_chord2(0.5) as f32,
                spot_dir: [0.0, 0.0, -1.0],
                // Full strength inside 0.8 of the outer angle.
                spot_ramp_scale: (1.0 / (spot_chord2(0.5) - spot_chord2(0.4f32 as f64))) as f32,
            }
        );
        assert_eq!(
            out[6],
            GpuLight {
                position: [0.0; 3],
                radius: 1.0,
                color: [1.0; 3],
                spot_chord2_outer: GpuLight::POINT_CHORD2_OUTER,
                spot_dir: [0.0; 3],
                spot_ramp_scale: 0.0,
            }
        );
        for i in [1, 2, 3, 4, 5, 7] {
            assert_eq!(out[i], GpuLight::default(), "row {i}");
        }
    }

    /// `spot_falloff` of `shaders/common/lighting.wgsl`, step by step in f32 as the GPU runs it.
    fn shader_spot_falloff(light: &GpuLight, to_point: glam::Vec3) -> f32 {
        let chord = glam::Vec3::from(light.spot_dir) - to_point;
        let chord2 = chord.dot(chord);
        if !(chord2 < light.spot_chord2_outer) {
            return 0.0;
        }
        let t = ((light.spot_chord2_outer - chord2) * light.spot_ramp_scale).min(1.0);
        t * t
    }

    /// A spot's falloff in f32, from 5e-6 rad (the assignment's cone test allows about 4e-6 rad
    /// of slack) to wide: full strength on and near the axis, nothing just outside the cone.
    /// With the cosines the records once held, a 0.5° spot reached 14.5% on its axis, one under
    /// 0.014° (cosine 1 in f32) lit nothing, and the edge of a 0.05° one sat a few f32 steps of
    /// the cosine — tenths of its angle — from where the lists put it.
    #[test]
    fn narrow_and_wide_spots_keep_their_edge_and_reach_full_strength() {
        // Down −z, where the f32 axis and directions are exact, and a tilted axis, where every
        // component rounds.
        let axes = [glam::DVec3::NEG_Z, glam::DVec3::new(0.36, -0.48, -0.8)];
        for (axis, outer) in axes
            .into_iter()
            .flat_map(|a| [5e-6f32, 1e-4, 8.7e-4, 0.01, 0.3, 1.2, 2.0, 3.0].map(|o| (a, o)))
        {
            let dir = axis.as_vec3();
            let columns = LightColumns {
                x: &[0.0],
                y: &[0.0],
                z: &[0.0],
                radius: &[1.0],
                r: &[1.0],
                g: &[1.0],
                b: &[1.0],
                intensity: &[1.0],
                spot: Some(SpotColumns {
                    dir_x: &[dir.x],
                    dir_y: &[dir.y],
                    dir_z: &[dir.z],
                    angle: &[outer],
                    inner_angle: None,
                }),
            };
            let mut out = Vec::new();
            assert_eq!(fill_gpu_lights(&columns, DVec3::ZERO, &mut out), 0);
            let light = out[0];
            // A unit direction at `angle` from the axis (-z), in the x–z plane, rounded to f32
            // as the shader's `-l` is.
            let across = axis.any_orthonormal_vector();
            let at = |angle: f32| {
                let a = angle as f64;
                (axis * a.cos() + across * a.sin()).as_vec3()
            };
            let falloff = |fraction: f32| shader_spot_falloff(&light, at(outer * fraction));
            for fraction in [0.0, 0.3, 0.79] {
                assert_eq!(
                    falloff(fraction),
                    1.0,
                    "{axis}, outer {outer}: {fraction} of it"
                );
            }
            // Half way along the ramp: the cosine's ramp, squared, as with cosines in f64.
            let cos = |f: f64| (outer as f64 * f).cos();
            let want = ((cos(0.9) - cos(1.0)) / (cos(0.8) - cos(1.0))).powi(2);
            let got = falloff(0.9) as f64;
            // f32 directions put ~1e-7 rad of rounding on every angle: relative to a 5e-6 rad
            // cone, a few percent (and ~40 times under the assignment's slack).
            let slack = 1e-7 / outer as f64;
            assert!(
                (got - want).abs() < (1e-2 + 5.0 * slack) * want,
                "{axis}, outer {outer}: {got} half way along the ramp, want {want}"
            );
            let edge = (1e-3 + 2.0 * slack) as f32;
            assert!(
                falloff(1.0 - edge) > 0.0,
                "{axis}, outer {outer}: dark inside its edge"
            );
            assert_eq!(
                falloff(1.0 + edge),
                0.0,
                "{axis}, outer {outer}: lit outside its edge"
            );
            assert_eq!(
                shader_spot_falloff(&light, -at(0.0)),
                0.0,
                "{axis}, outer {outer}"
            );
        }
    }

    /// A spot's own inner angle sets where its falloff starts (glTF's `innerConeAngle`); one
    /// outside `[0, angle)` makes a dark record, counted like the other invalid values.
    #[test]
    fn spot_inner_angles_start_the_falloff_and_bad_ones_are_counted() {
        let nan = f32::NAN;
        let n = 6;
        let columns = LightColumns {
            x: &[0.0; 6],
            y: &[0.0; 6],
            z: &[0.0; 6],
            radius: &[1.0; 6],
            r: &[1.0; 6],
            g: &[1.0; 6],
            b: &[1.0; 6],
            intensity: &[1.0; 6],
            spot: Some(SpotColumns {
                dir_x: &[0.0; 6],
                dir_y: &[0.0; 6],
                dir_z: &[-1.0; 6],
                angle: &[0.5, 0.5, 0.5, 0.5, 0.5, std::f32::consts::PI],
                // 0 and 0.3 are good; NaN, negative and the outer angle itself are not; the
                // last row is a point light (angle π), whose inner angle is not read.
                inner_angle: Some(&[0.0, 0.3, nan, -0.1, 0.5, nan]),
            }),
        };
        let mut out = Vec::new();
        assert_eq!(fill_gpu_lights(&columns, DVec3::ZERO, &mut out), 3);
        assert_eq!(out.len(), n);
        for (i, inner) in [(0, 0.0f64), (1, 0.3f32 as f64)] {
            let want = (1.0 / (spot_chord2(0.5) - spot_chord2(inner))) as f32;
            assert_eq!(out[i].spot_ramp_scale, want, "row {i}");
            assert_eq!(out[i].spot_chord2_outer, spot_chord2(0.5) as f32);
        }
        // Full strength up to the inner angle, not to 0.8 of the outer one (0.4).
        let at = |a: f64| glam::DVec3::new(a.sin(), 0.0, -a.cos()).as_vec3();
        assert_eq!(shader_spot_falloff(&out[1], at(0.29)), 1.0);
        assert!(shader_spot_falloff(&out[1], at(0.35)) < 1.0);
        assert!(shader_spot_falloff(&out[0], at(0.2)) < 1.0);
        for (i, bad) in out.iter().enumerate().take(5).skip(2) {
            assert_eq!(*bad, GpuLight::default(), "row {i}");
        }
        assert_eq!(out[5].spot_chord2_outer, GpuLight::POINT_CHORD2_OUTER);
    }

    #[test]
    fn light_columns_of_unequal_length_are_refused() {
        let two = [1.0f32; 2];
        let columns = LightColumns {
            x: &two,
            y: &two,
            z: &two,
            radius: &two,
            r: &two,
            g: &two,
            b: &[1.0],
            intensity: &two,
            spot: None,
        };
        assert_eq!(
            columns.check(),
            Err("light columns differ in length: 2 positions, a column of 1".to_string())
        );
        let spot = SpotColumns {
            dir_x: &two,
            dir_y: &two,
            dir_z: &two,
            angle: &[0.5; 3],
            inner_angle: None,
        };
        let spots = LightColumns {
            b: &two,
            spot: Some(spot),
            ..columns
        };
        assert_eq!(
            spots.check(),
            Err("light columns differ in length: 2 positions, a column of 3".to_string())
        );
        let equal = LightColumns {
            spot: Some(SpotColumns {
                angle: &two,
                ..spot
            }),
            ..spots
        };
        assert_eq!(equal.check(), Ok(()));
        let short_inner = LightColumns {
            spot: Some(SpotColumns {
                angle: &two,
                inner_angle: Some(&[0.1]),
                ..spot
            }),
            ..spots
        };
        assert_eq!(
            short_inner.check(),
            Err("light columns differ in length: 2 positions, a column of 1".to_string())
        );
        assert_eq!((equal.len(), equal.is_empty()), (2, false));
        let none = LightColumns {
            x: &[],
            y: &[],
            z: &[],
            radius: &[],
            r: &[],
            g: &[],
            b: &[],
            intensity: &[],
            spot: None,
        };
        assert_eq!((none.len(), none.is_empty()), (0, true));
    }

    #[test]
    fn cluster_lists_are_checked_against_the_grid_and_the_lights() {
        // Cluster 0 holds light 2, cluster 1 lights 0 and 1: the last run ends exactly at the
        // end of the indices, and the largest index is the last light.
        let lists = ClusterLists {
            offsets: &[0, 1],
            counts: &[1, 2],
            indices: &[2, 0, 1],
        };
        assert_eq!(lists.check(2, 3), Ok(()));
        assert_eq!(lists.check(2, 4), Ok(()), "lights no list names are fine");
        assert_eq!((lists.lights_named(), lists.max_count()), (3, 2));
        assert_eq!(
            lists.check(2, 2),
            Err("light index 2 in the lists, but only 2 lights".to_string())
        );
        let past_the_end = ClusterLists {
            counts: &[1, 3],
            ..lists
        };
        assert_eq!(
            past_the_end.check(2, 3),
            Err("cluster 1's list runs past the 3 indices".to_string())
        );
        let other_grid = ClusterLists {
            offsets: &[0, 1, 3],
            ..lists
        };
        assert_eq!(
            other_grid.check(2, 3),
            Err("light lists describe 3 offsets and 2 counts for a grid of 2 clusters".to_string())
        );
        let empty = ClusterLists {
            offsets: &[0],
            counts: &[0],
            indices: &[],
        };
        assert_eq!(empty.check(1, 0), Ok(()));
        assert_eq!((empty.lights_named(), empty.max_count()), (0, 0));
    }
}
