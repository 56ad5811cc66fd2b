//! View-space plane sets: the walls between clusters, in the form the assignment searches.
//!
//! Every x-plane passes through the eye and contains the view-space y axis, so it is fully described
//! by its *slope* `s = x / depth` (NDC edge × `tan(fov_x/2)`); likewise every y-plane by `y / depth`.
//! A point `p` (depth `d = −p.z > 0`) lies right of x-plane `i` iff `p.x ≥ s_i·d`. Slopes increase
//! left → right for x; for y they are stored top → bottom (decreasing), matching tile row order.
//! z-planes are the slice edges (view depths, near → far), the first where the assignment's first
//! slice starts and the last where its last slice ends ([`ClusterGrid::first_slice_start`],
//! [`ClusterGrid::last_slice_end`]: beyond the grid's range for a [`crate::OuterSlices::Open`] grid
//! under a camera that sees nearer or farther). [`PlaneSets::x_plane_normal`] and
//! friends give the same planes as unit normals for algorithms that want `n·p` distances (the paper's
//! Algorithm 1).

use crate::{Camera, ClusterGrid};
use glam::Vec3;

/// The x-, y- and z-plane sets of a grid seen through a camera. Reuse one value across frames:
/// [`PlaneSets::update`] refills the vectors without allocating once they have grown.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlaneSets {
    /// X+1 slopes `x/depth` of the tile column edges, left → right (increasing).
    pub x_slopes: Vec<f32>,
    /// Y+1 slopes `y/depth` of the tile row edges, top → bottom (decreasing).
    pub y_slopes: Vec<f32>,
    /// Z+1 view depths of the slice edges, near → far (non-decreasing); the first is
    /// [`ClusterGrid::first_slice_start`] and the last [`ClusterGrid::last_slice_end`], which may
    /// be ∞.
    pub z_depths: Vec<f32>,
}

impl PlaneSets {
    /// Plane sets for `grid` seen through `camera`.
    pub fn new(camera: &Camera, grid: &ClusterGrid) -> Self {
        let mut sets = Self::default();
        sets.update(camera, grid);
        sets
    }

    /// Recomputes the sets in place.
    pub fn update(&mut self, camera: &Camera, grid: &ClusterGrid) {
        let t = camera.tan_half_fov();
        self.x_slopes.clear();
        self.x_slopes
            .extend((0..=grid.dims().x).map(|i| grid.x_edge_ndc(i) * t.x));
        self.y_slopes.clear();
        self.y_slopes
            .extend((0..=grid.dims().y).map(|j| grid.y_edge_ndc(j) * t.y));
        grid.fill_slice_edges(&mut self.z_depths);
        // The outer slices reach the camera's near and far planes where the grid is open.
        if let Some(first) = self.z_depths.first_mut() {
            *first = grid.first_slice_start(camera);
        }
        if let Some(last) = self.z_depths.last_mut() {
            *last = grid.last_slice_end(camera);
        }
    }

    /// Unit normal of x-plane `i`, pointing right: `n·p ≥ 0` ⇔ `p` is right of the plane.
    pub fn x_plane_normal(&self, i: usize) -> Vec3 {
        Vec3::new(1.0, 0.0, self.x_slopes[i]).normalize()
    }

    /// Unit normal of y-plane `j`, pointing up: `n·p ≥ 0` ⇔ `p` is above the plane.
    pub fn y_plane_normal(&self, j: usize) -> Vec3 {
        Vec3::new(0.0, 1.0, self.y_slopes[j]).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::DepthSlicing;
    use glam::UVec3;

    #[test]
    fn normals_agree_with_slopes() {
        let cam = Camera::new(
            Vec3::ZERO,
            Vec3::NEG_Z,
            Vec3::Y,
            70.0,
            1920,
            1080,
            0.1,
            50.0,
        );
        let grid = ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, 0.1, 50.0);
        let sets = PlaneSets::new(&cam, &grid);
        assert_eq!(sets.x_slopes.len(), 17);
        assert_eq!(sets.y_slopes.len(), 10);
        assert_eq!(sets.z_depths.len(), 25);
        for (i, s) in sets.x_slopes.iter().enumerate() {
            let n = sets.x_plane_normal(i);
            // A point exactly on the plane at depth 3 has zero distance.
            let on = Vec3::new(s * 3.0, 0.7, -3.0);
            assert!(n.dot(on).abs() < 1e-5);
            assert!(n.dot(on + Vec3::X * 0.01) > 0.0);
        }
        for (j, s) in sets.y_slopes.iter().enumerate() {
            let n = sets.y_plane_normal(j);
            let on = Vec3::new(-0.4, s * 2.0, -2.0);
            assert!(n.dot(on).abs() < 1e-5);
            assert!(n.dot(on + Vec3::Y * 0.01) > 0.0);
        }
        assert!(sets.x_slopes.windows(2).all(|w| w[0] < w[1]));
        assert!(sets.y_slopes.windows(2).all(|w| w[0] > w[1]));
        // The outer planes are the frustum sides.
        let t = cam.tan_half_fov();
        assert_eq!(sets.x_slopes[16], t.x);
        assert_eq!(sets.y_slopes[0], t.y);
    }
}
