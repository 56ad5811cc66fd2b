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

    #[test]
    fn bounding_sphere_contains_sampled_spot_volume() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        for _ in 0..200 {
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
            let angle = rng.random_range(0.01f32..3.1);
            let range = rng.random_range(0.1f32..10.0);
            let (c, r) = spot_bounding_sphere(apex, range, SpotCone { direction, angle });
            // The sphere is never bigger than the light's range sphere.
            assert!(r <= range * 1.0001);
            for _ in 0..500 {
                let p = apex
                    + Vec3::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    ) * range;
                let v = p - apex;
                let inside = v.length() <= range
                    && (v.length() == 0.0 || v.normalize().dot(direction) >= angle.cos());
                if inside {
                    assert!(
                        (p - c).length() <= r * 1.0001 + 1e-5,
                        "{p:?} outside ({c:?}, {r})"
                    );
                }
            }
        }
    }
}
