//! ECS-style frame systems: the per-frame work on lights before assignment — animate, cull
//! against the view frustum, bring the survivors to view space.
//!
//! Why "ECS-style" and not an ECS: the components are plain columns (`&[f32]` per field, one
//! row per light, as in [`crate::Lights`]) and each system is a plain function over slices
//! that writes into caller-owned outputs. An engine calls them with its own columns; there is
//! no world, no registry, no scheduler, nothing to adopt. Chained, they are the first stage of
//! a frame (ARCHITECTURE.md, "A frame, as data flows", step 1):
//!
//! 1. [`animate_orbits`] / [`animate_wander`] move lights (positions updated in place).
//! 2. [`cull_lights`] tests each light's volume — its sphere, or for a spot its cone (the
//!    sphere sector, tested exactly against each plane) — against the six frustum planes and
//!    writes a visibility mask and the compacted list of visible indices ([`Visibility`]).
//! 3. [`lights_to_view`] transforms the visible lights to view space, camera-relative
//!    (position subtracted before rotating, as [`Camera::view_from_world_point`] does), into
//!    [`ViewLights`] columns that remember each row's source index.
//!
//! ## Threads, and the slow twin
//! Each system is a per-light kernel (a private function of one light) driven over blocks of
//! [`BLOCK`] lights. Below [`PARALLEL_MIN`] lights it runs on the calling thread (rayon's
//! fork-join costs a few microseconds, more than 8k lights of these kernels); above, the
//! blocks run as rayon tasks on the current pool. The kernels are pure functions of their
//! light (wander's random steps come from a hash of seed, frame and index, not from a shared
//! generator), so the output is **identical for any thread count**, and the tests check the
//! parallel drivers against a plain serial loop over the kernels.
//!
//! ## Allocation
//! Outputs are caller-owned and reused: after the first frame at a given light count, no
//! system allocates.

mod animate;
mod cull;
mod view;

pub use animate::{Orbits, Wander, animate_orbits, animate_wander};
pub use cull::{Visibility, cull_lights};
pub use view::{ViewLights, lights_to_view};

#[cfg(doc)]
use myriad_cluster_math::Camera;

use crate::lights::Lights;

/// `(sin x, cos x)` in f32 for `|x| < 10⁶`, within about 2e-7 (plus the reduction error of
/// about `|x|·1e-15`) of the true values, written with plain arithmetic and selects so that the
/// loops calling it vectorise (the platform's `sin_cos` is an opaque call per light, several
/// times slower). Steps: `q = round(x · 2/π)` (by the 1.5·2²³ trick, no rounding call);
/// `r = x − q·π/2` with π/2 split in three parts (Cody–Waite), so `|r| ≤ π/4`; Taylor
/// polynomials for sin (to r⁹) and cos (to r¹⁰), whose truncation errors on [−π/4, π/4] are
/// below 2e-9; the quadrant `q mod 4` swaps and negates.
#[inline(always)] // Into the AVX2 builds of the systems' blocks as well.
pub(crate) fn fast_sin_cos(x: f32) -> (f32, f32) {
    const ROUND: f32 = 12_582_912.0; // 1.5 · 2²³
    const PIO2_1: f32 = 1.570_312_5; // π/2 = PIO2_1 + PIO2_2 + PIO2_3, first parts exact
    const PIO2_2: f32 = 4.837_513e-4;
    const PIO2_3: f32 = 7.549_79e-8;
    let q = (x * std::f32::consts::FRAC_2_PI + ROUND) - ROUND;
    let r = ((x - q * PIO2_1) - q * PIO2_2) - q * PIO2_3;
    let z = r * r;
    let sin_r =
        r + r * z * (-1.0 / 6.0 + z * (1.0 / 120.0 + z * (-1.0 / 5040.0 + z * (1.0 / 362_880.0))));
    let cos_r = 1.0
        + z * (-0.5
            + z * (1.0 / 24.0
                + z * (-1.0 / 720.0 + z * (1.0 / 40_320.0 + z * (-1.0 / 3_628_800.0)))));
    let q = q as i32;
    let (s, c) = if q & 1 != 0 {
        (cos_r, sin_r)
    } else {
        (sin_r, cos_r)
    };
    let s = if q & 2 != 0 { -s } else { s };
    let c = if (q + 1) & 2 != 0 { -c } else { c };
    (s, c)
}

/// Lights per block: the unit of work of the parallel drivers.
pub const BLOCK: usize = 4096;

/// From this many lights on, systems run their blocks in parallel on the current rayon pool.
pub const PARALLEL_MIN: usize = 2 * BLOCK;

/// Borrowed SoA light columns: what the systems read. All columns have the same length; the
/// spot columns follow [`Lights`]' convention (a point light in a mixed set has a zero axis and
/// angle π).
#[derive(Clone, Copy, Debug)]
pub struct LightSlices<'a> {
    /// World-space x.
    pub x: &'a [f32],
    /// World-space y.
    pub y: &'a [f32],
    /// World-space z.
    pub z: &'a [f32],
    /// Range (> 0).
    pub radius: &'a [f32],
    /// Spot columns, when some light is a spot.
    pub spot: Option<SpotSlices<'a>>,
}

/// Borrowed spot columns: axis and outer half angle (radians; `>= π` omnidirectional). The axis
/// need not be unit length: the cull normalises it, `lights_to_view` rotates it as given.
#[derive(Clone, Copy, Debug)]
pub struct SpotSlices<'a> {
    /// Axis x.
    pub dir_x: &'a [f32],
    /// Axis y.
    pub dir_y: &'a [f32],
    /// Axis z.
    pub dir_z: &'a [f32],
    /// Outer half angle.
    pub angle: &'a [f32],
}

impl LightSlices<'_> {
    /// Number of lights.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are no lights.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Panics unless every column has the same length.
    fn assert_consistent(&self) {
        let n = self.len();
        assert!(self.y.len() == n && self.z.len() == n && self.radius.len() == n);
        if let Some(s) = &self.spot {
            assert!(
                s.dir_x.len() == n
                    && s.dir_y.len() == n
                    && s.dir_z.len() == n
                    && s.angle.len() == n
            );
        }
    }
}

impl Lights {
    /// The columns as [`LightSlices`] (spot columns when [`Lights::has_spots`]).
    pub fn slices(&self) -> LightSlices<'_> {
        LightSlices {
            x: &self.x,
            y: &self.y,
            z: &self.z,
            radius: &self.radius,
            spot: self.has_spots().then(|| SpotSlices {
                dir_x: &self.spot_dir_x,
                dir_y: &self.spot_dir_y,
                dir_z: &self.spot_dir_z,
                angle: &self.spot_angle,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lights::LightRecord;
    use glam::Vec3;
    use myriad_cluster_math::Camera;

    #[test]
    fn fast_sin_cos_is_accurate() {
        let mut worst = 0.0f64;
        let mut x = -2000.0f32;
        while x < 2000.0 {
            let (s, c) = fast_sin_cos(x);
            let (es, ec) = (x as f64).sin_cos();
            worst = worst.max((s as f64 - es).abs()).max((c as f64 - ec).abs());
            x += 0.0137;
        }
        assert!(worst < 5e-7, "{worst}");
        for k in -8..=8 {
            let x = k as f32 * std::f32::consts::FRAC_PI_4;
            let (s, c) = fast_sin_cos(x);
            assert!(
                (s - x.sin()).abs() < 3e-7 && (c - x.cos()).abs() < 3e-7,
                "{x}"
            );
        }
    }

    #[test]
    fn fast_sin_cos_is_within_1e_7_over_a_period() {
        // The polynomials' truncation error is below 2e-9: what remains is f32 rounding.
        let mut worst = 0.0f64;
        let mut x = -4.0f32;
        while x < 4.0 {
            let (s, c) = fast_sin_cos(x);
            let (es, ec) = (x as f64).sin_cos();
            worst = worst.max((s as f64 - es).abs()).max((c as f64 - ec).abs());
            x += 1e-4;
        }
        assert!(worst < 1e-7, "{worst}");
    }

    #[test]
    fn slices_know_their_length() {
        let lights: Lights = [LightRecord::point(Vec3::ZERO, 1.0)].into_iter().collect();
        assert_eq!(
            (lights.slices().len(), lights.slices().is_empty()),
            (1, false)
        );
        assert!(Lights::new().slices().is_empty());
    }

    #[test]
    #[should_panic]
    fn columns_of_different_lengths_are_refused() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 64, 64, 0.1, 10.0);
        let lights: Lights = [LightRecord::point(Vec3::new(0.0, 0.0, -2.0), 1.0)]
            .into_iter()
            .collect();
        let y = [0.0; 2];
        let slices = LightSlices {
            y: &y,
            ..lights.slices()
        };
        cull_lights(&camera, slices, &mut Visibility::new());
    }
}
