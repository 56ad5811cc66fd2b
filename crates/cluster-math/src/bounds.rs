//! Bounding volumes of lights.
//!
//! A spot light is the set of points within `range` of its apex and within `angle` of its axis
//! (the sphere ∩ cone "sector"). Its tightest simple bounding sphere depends on the angle:
//! * `angle ≤ 45°`: the sphere through the apex and the cap rim, centred on the axis at
//!   `range / (2 cos angle)` — it also contains the cap's tip;
//! * `45° < angle ≤ 90°`: the sphere around the cap rim's circle, centred at `range·cos(angle)`
//!   along the axis with radius `range·sin(angle)`;
//! * wider: the light's whole range sphere.

use glam::Vec3;

/// A spot light's cone: unit axis `direction` and outer half `angle` in radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotCone {
    /// Unit axis direction.
    pub direction: Vec3,
    /// Outer half angle in radians, in (0, π].
    pub angle: f32,
}

/// Centre and radius of a sphere containing the spot volume of a light at `apex` with `range`.
pub fn spot_bounding_sphere(apex: Vec3, range: f32, cone: SpotCone) -> (Vec3, f32) {
    let (sin, cos) = cone.angle.sin_cos();
    if cone.angle <= std::f32::consts::FRAC_PI_4 {
        let r = range / (2.0 * cos);
        (apex + cone.direction * r, r)
    } else if cone.angle <= std::f32::consts::FRAC_PI_2 {
        (apex + cone.direction * (range * cos), range * sin)
    } else {
        (apex, range)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// A point of the spot volume: `t` of the range along a direction `theta` off the axis at
    /// azimuth `phi`.
    fn spot_point(apex: Vec3, range: f32, cone: SpotCone, t: f32, theta: f32, phi: f32) -> Vec3 {
        let (u, w) = cone.direction.any_orthonormal_pair();
        let off_axis = u * phi.cos() + w * phi.sin();
        apex + (cone.direction * theta.cos() + off_axis * theta.sin()) * (t * range)
    }

    #[test]
    fn bounding_sphere_contains_the_spot_volume() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        for case in 0..400 {
            let apex = Vec3::new(
                rng.random_range(-5.0..5.0),
                rng.random_range(-5.0..5.0),
                0.0,
            );
            let direction = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize_or(Vec3::X);
            // Needle beams (down to 1e-4 rad) as often as wide ones, and both 45° and 90°.
            let angle = match case % 4 {
                0 => 10f32.powf(rng.random_range(-4.0..-1.0)),
                1 => std::f32::consts::FRAC_PI_4,
                2 => std::f32::consts::FRAC_PI_2,
                _ => rng.random_range(0.01f32..3.1),
            };
            let range = 10f32.powf(rng.random_range(-2.0..2.0));
            let cone = SpotCone { direction, angle };
            let (c, r) = spot_bounding_sphere(apex, range, cone);
            // The sphere is never bigger than the light's range sphere.
            assert!(r <= range * 1.0001);
            let slack = r * 1e-5 + (apex.length() + range) * 1e-6;
            let check = |p: Vec3, what: &str| {
                assert!(
                    (p - c).length() <= r + slack,
                    "{what} {p:?} outside ({c:?}, {r}); apex {apex:?}, range {range}, {cone:?}"
                );
            };
            // The extreme points: apex, cap tip, and the rim where the cone meets the cap.
            let theta_max = angle.min(std::f32::consts::PI);
            check(apex, "apex");
            check(apex + direction * range, "tip");
            for k in 0..16 {
                let phi = k as f32 * std::f32::consts::TAU / 16.0;
                check(spot_point(apex, range, cone, 1.0, theta_max, phi), "rim");
                check(spot_point(apex, range, cone, 0.5, theta_max, phi), "side");
            }
            // And points drawn inside it.
            for _ in 0..100 {
                let t = rng.random_range(0.0f32..=1.0);
                let theta = rng.random_range(0.0f32..=theta_max);
                let phi = rng.random_range(0.0..std::f32::consts::TAU);
                check(spot_point(apex, range, cone, t, theta, phi), "inside");
            }
        }
    }
}
