//! Exact spot-volume vs cell test (GJK on support functions). Implementation pending.

use super::Cell;
use glam::DVec3;

/// A spot light's volume in view space: points within `range` of `apex` and within `angle` of the
/// unit axis `direction`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotVolume {
    /// Apex (the light's position).
    pub apex: DVec3,
    /// Unit axis.
    pub direction: DVec3,
    /// Range (radius of the light's sphere).
    pub range: f64,
    /// Outer half angle in radians.
    pub angle: f64,
}

/// Whether the closed spot volume touches the closed cell.
pub fn spot_intersects_cell(spot: &SpotVolume, cell: &Cell) -> bool {
    let _ = (spot, cell);
    todo!()
}
