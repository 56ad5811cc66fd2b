//! What a frame hands the renderer: borrowed light columns and CSR light lists (no scene or
//! assignment types, so this crate depends on neither), and their conversion to GPU records.

use crate::layout::GpuLight;
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
        let spot_lens = self
            .spot
            .map(|s| [s.dir_x.len(), s.dir_y.len(), s.dir_z.len(), s.angle.len()]);
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

/// Fraction of the outer cone angle where a spot reaches full strength.
pub const SPOT_INNER_FRACTION: f32 = 0.8;

/// Converts the columns to camera-relative GPU records in `out` (reusing its storage).
/// Positions are differenced in f64, so lights far from the origin keep their precision near the
/// camera. Invalid rows (non-finite values, radius <= 0, negative colour) become records that
/// light nothing (radius 0 at the camera) — the assignment skips the same rows — and are counted
/// in the return value.
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
            spot_cos_outer: GpuLight::POINT_COS_OUTER,
            spot_dir: [0.0; 3],
            spot_cos_inner: 1.0,
        };
        let mut valid = position.is_finite()
            && radius.is_finite()
            && radius > 0.0
            && color.iter().all(|c| c.is_finite() && *c >= 0.0);
        if let Some(s) = &columns.spot {
            let angle = s.angle[i];
            let dir = [s.dir_x[i], s.dir_y[i], s.dir_z[i]];
            valid &= angle.is_finite() && angle > 0.0 && dir.iter().all(|d| d.is_finite());
            // Normalised here, as `myriad-assignment` does (its axis "need not be normalised"):
            // the shader compares the cosine against a dot product with this axis, so a longer
            // one would cut the cone off at cluster edges. A zero axis bounds nothing: the light
            // shines all round, as the assignment treats it. In f64, as there: an f32 axis
            // shorter than ~1e-19 has a squared length that underflows to zero, and the light
            // would shine all round here while the lists hold only its cone's clusters.
            let axis = glam::DVec3::from_array(dir.map(f64::from))
                .normalize_or_zero()
                .as_vec3();
            if angle < std::f32::consts::PI && axis != glam::Vec3::ZERO {
                light.spot_cos_outer = angle.cos();
                light.spot_cos_inner = (angle * SPOT_INNER_FRACTION).cos();
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
            }),
        };
        let mut out = Vec::new();
        assert_eq!(fill_gpu_lights(&columns, DVec3::ZERO, &mut out), 0);
        assert_eq!(out[0].spot_dir, [0.0, -1.0, 0.0]);
        assert_eq!(out[0].spot_cos_outer, 0.5f32.cos());
        // An axis whose f32 squared length underflows is still a direction (the assignment
        // normalises in f64 and cuts the lists to the cone).
        assert_eq!(out[3].spot_dir, [1.0, 0.0, 0.0]);
        assert_eq!(out[3].spot_cos_outer, 0.5f32.cos());
        for point in &out[1..3] {
            assert_eq!(point.spot_cos_outer, GpuLight::POINT_COS_OUTER);
        }
    }
}
