//! The assignment's input: plain SoA light columns, borrowed from the caller.

/// World-space light columns, one entry per light; all slices must have the same length
/// ([`Assigner::assign`](crate::Assigner::assign) panics otherwise).
///
/// Lights whose position or radius is not finite, or whose radius is not positive, are skipped
/// and counted in [`crate::AssignStats::rejected`]; they never reach the output.
#[derive(Clone, Copy, Debug)]
pub struct LightInput<'a> {
    /// World-space x of each light's position.
    pub x: &'a [f32],
    /// World-space y.
    pub y: &'a [f32],
    /// World-space z.
    pub z: &'a [f32],
    /// Range: the light contributes nothing beyond this distance.
    pub radius: &'a [f32],
    /// Spot cones, or `None` when every light is a point light.
    pub spot: Option<SpotInput<'a>>,
}

/// Spot-light columns, parallel to [`LightInput`]'s; point lights in a mixed scene carry an angle
/// of `π` (see [`SpotInput::angle`]).
#[derive(Clone, Copy, Debug)]
pub struct SpotInput<'a> {
    /// World-space x of each cone's axis (need not be normalised).
    pub dir_x: &'a [f32],
    /// World-space y of the axis.
    pub dir_y: &'a [f32],
    /// World-space z of the axis.
    pub dir_z: &'a [f32],
    /// Outer half angle in radians. Angles of π/2 or more (`std::f32::consts::FRAC_PI_2`
    /// included: as an f32 it is a hair wider than 90°), and `π`, the convention for "point
    /// light" in a mixed column, are assigned as point lights; a zero or non-finite axis likewise.
    pub angle: &'a [f32],
}

impl<'a> LightInput<'a> {
    /// Point lights from four columns.
    pub fn points(x: &'a [f32], y: &'a [f32], z: &'a [f32], radius: &'a [f32]) -> Self {
        Self {
            x,
            y,
            z,
            radius,
            spot: None,
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

    /// What makes these columns unusable, if anything: columns of different lengths, or more
    /// lights than u32 indices reach. (Bad *values* — NaN, negative radii — are not a problem
    /// here: such lights are skipped and counted in [`crate::AssignStats::rejected`].)
    pub fn problem(&self) -> Option<&'static str> {
        let n = self.x.len();
        if !(self.y.len() == n && self.z.len() == n && self.radius.len() == n) {
            return Some("light columns differ in length");
        }
        if let Some(s) = &self.spot
            && !(s.dir_x.len() == n
                && s.dir_y.len() == n
                && s.dir_z.len() == n
                && s.angle.len() == n)
        {
            return Some("spot columns differ in length from the light columns");
        }
        (n > u32::MAX as usize).then_some("more lights than fit in a u32 index")
    }

    /// Panics unless all columns have the same length (a programming error, not bad data).
    pub(crate) fn assert_consistent(&self) {
        if let Some(problem) = self.problem() {
            panic!("{problem}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_have_no_spot_columns_and_count_their_lights() {
        let (x, y, z, r) = ([1.0, 2.0], [0.0; 2], [-5.0; 2], [1.0; 2]);
        let two = LightInput::points(&x, &y, &z, &r);
        assert!(two.spot.is_none());
        assert_eq!((two.len(), two.is_empty()), (2, false));
        let none = LightInput::points(&[], &[], &[], &[]);
        assert_eq!((none.len(), none.is_empty()), (0, true));
    }
}
