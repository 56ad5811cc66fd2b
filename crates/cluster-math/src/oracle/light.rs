//! How the oracle reads a light: from the f32 columns every method gets to an f64 view-space
//! volume, in one place.
//!
//! Everything that judges a method against the oracle (the `exact` method itself, `myriad check`
//! and `myriad stress`, the conservativeness tests) must read a light the same way, or it judges
//! a different light: which lights are invalid, where the centre lands in f64, and when a spot
//! counts as a ball (a cone wider than 90° in f64, a zero or non-finite axis). Before this type
//! each of them spelled those rules out on its own.

use super::{Cell, SpotVolume, sphere_intersects_cell, spot_intersects_cell};
use crate::Camera;
use glam::{DMat3, DVec3, Vec3};
use std::f64::consts::FRAC_PI_2;

/// A light's volume in f64 view space, as the oracle tests it against cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightVolume {
    /// A point light (or a spot that is not a cone of at most 90°): the closed ball.
    Ball {
        /// Centre in view space.
        centre: DVec3,
        /// Radius (the light's range).
        radius: f64,
    },
    /// A spot light whose half angle is at most 90°.
    Spot(SpotVolume),
}

impl LightVolume {
    /// Whether the volume touches the closed `cell` ([`sphere_intersects_cell`] or
    /// [`spot_intersects_cell`]).
    pub fn intersects_cell(&self, cell: &Cell) -> bool {
        match self {
            Self::Ball { centre, radius } => sphere_intersects_cell(*centre, *radius, cell),
            Self::Spot(spot) => spot_intersects_cell(spot, cell),
        }
    }

    /// Centre and radius of a ball that holds the volume: the light's own sphere (for a spot,
    /// the apex and range).
    pub fn bounding_ball(&self) -> (DVec3, f64) {
        match self {
            Self::Ball { centre, radius } => (*centre, *radius),
            Self::Spot(spot) => (spot.apex, spot.range),
        }
    }
}

/// The camera's f64 view transform, computed once per frame, that turns a light's f32 columns
/// into its [`LightVolume`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OracleView {
    view_from_world: DMat3,
    eye: DVec3,
}

impl OracleView {
    /// The view of `camera`.
    pub fn new(camera: &Camera) -> Self {
        Self {
            view_from_world: camera.view_rotation_f64(),
            eye: camera.position.as_dvec3(),
        }
    }

    /// The volume of a light at world `position` with `range`, and for a spot light its world
    /// `(direction, half angle in radians)`.
    ///
    /// `None` for an invalid light (a non-finite position or range, a range ≤ 0): no method may
    /// assign it. A spot whose half angle is not in `(0, π/2]` in f64, or whose axis is zero or
    /// not finite, is its range's ball.
    pub fn light(
        &self,
        position: Vec3,
        range: f32,
        spot: Option<(Vec3, f32)>,
    ) -> Option<LightVolume> {
        let world = position.as_dvec3();
        let radius = range as f64;
        if !(world.is_finite() && radius.is_finite() && radius > 0.0) {
            return None;
        }
        let centre = self.view_from_world * (world - self.eye);
        let ball = LightVolume::Ball { centre, radius };
        let Some((direction, angle)) = spot else {
            return Some(ball);
        };
        let axis = (self.view_from_world * direction.as_dvec3()).normalize_or_zero();
        let angle = angle as f64;
        if angle > 0.0 && angle <= FRAC_PI_2 && axis != DVec3::ZERO {
            Some(LightVolume::Spot(SpotVolume {
                apex: centre,
                direction: axis,
                range: radius,
                angle,
            }))
        } else {
            Some(ball)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(1.0, 2.0, -10.0),
            Vec3::Y,
            60.0,
            1536,
            768,
            0.1,
            100.0,
        )
    }

    #[test]
    fn invalid_lights_have_no_volume() {
        let view = OracleView::new(&camera());
        let at = Vec3::new(0.0, 0.0, -5.0);
        assert!(view.light(at, 1.0, None).is_some());
        assert_eq!(view.light(at, 0.0, None), None);
        assert_eq!(view.light(at, -1.0, None), None);
        assert_eq!(view.light(at, f32::NAN, None), None);
        assert_eq!(view.light(at, f32::INFINITY, None), None);
        assert_eq!(view.light(Vec3::new(f32::NAN, 0.0, 0.0), 1.0, None), None);
        assert_eq!(
            view.light(Vec3::new(0.0, f32::INFINITY, 0.0), 1.0, None),
            None
        );
    }

    #[test]
    fn the_centre_is_the_f64_view_transform() {
        let cam = camera();
        let view = OracleView::new(&cam);
        let at = Vec3::new(3.5, -1.25, -7.0);
        let Some(LightVolume::Ball { centre, radius }) = view.light(at, 2.0, None) else {
            panic!("a valid point light is a ball");
        };
        assert_eq!(centre, cam.view_from_world_point_f64(at.as_dvec3()));
        assert_eq!(radius, 2.0);
        // The camera looks down −z from (1, 2, 3): the light is 10 in front, 2.5 right, 3.25 down.
        assert!((centre - DVec3::new(2.5, -3.25, -10.0)).length() < 1e-12);
    }

    #[test]
    fn spots_outside_the_cone_rules_are_balls() {
        let view = OracleView::new(&camera());
        let at = Vec3::new(0.0, 0.0, -5.0);
        let down = Vec3::NEG_Y;
        let is_spot = |spot| matches!(view.light(at, 3.0, Some(spot)), Some(LightVolume::Spot(_)));
        assert!(is_spot((down, 0.5)));
        assert!(is_spot((down * 7.0, 0.5)), "the axis is normalised");
        // Exactly π/2 in f64 is still a cone; f32's π/2 rounds above it and is a ball.
        assert!(is_spot((down, std::f64::consts::FRAC_PI_2 as f32 - 1e-6)));
        assert!(!is_spot((down, std::f32::consts::FRAC_PI_2)));
        assert!(!is_spot((down, 2.0)));
        assert!(!is_spot((down, 0.0)));
        assert!(!is_spot((down, -0.5)));
        assert!(!is_spot((down, f32::NAN)));
        assert!(!is_spot((Vec3::ZERO, 0.5)));
        assert!(!is_spot((Vec3::new(f32::NAN, 0.0, 0.0), 0.5)));
        let Some(LightVolume::Spot(spot)) = view.light(at, 3.0, Some((down * 7.0, 0.5))) else {
            panic!("a spot");
        };
        assert!((spot.direction - DVec3::NEG_Y).length() < 1e-12);
        assert_eq!((spot.range, spot.angle), (3.0, 0.5f32 as f64));
        assert_eq!(
            view.light(at, 3.0, Some((down, 0.5)))
                .unwrap()
                .bounding_ball(),
            (spot.apex, 3.0)
        );
    }

    #[test]
    fn intersects_cell_follows_the_volume() {
        let cell = Cell {
            x_slopes: [-0.1, 0.1],
            y_slopes: [-0.1, 0.1],
            depths: [4.0, 6.0],
        };
        // A ball beside the cell reaches it; a spot there pointing away does not.
        let centre = DVec3::new(1.5, 0.0, -5.0);
        let ball = LightVolume::Ball {
            centre,
            radius: 1.2,
        };
        assert!(ball.intersects_cell(&cell));
        let spot = |direction| {
            LightVolume::Spot(SpotVolume {
                apex: centre,
                direction,
                range: 1.2,
                angle: 0.3,
            })
        };
        assert!(!spot(DVec3::X).intersects_cell(&cell));
        let towards = spot(DVec3::NEG_X);
        assert!(towards.intersects_cell(&cell));
    }
}
