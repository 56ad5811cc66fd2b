//! Active clusters: the clusters a frame actually shades (Olsson et al., "Clustered Deferred and
//! Forward Shading", 2012: *find unique clusters*). Lists are only needed there; every other
//! cluster can stay empty.
//!
//! The caller builds the mask — from a depth buffer (every covered pixel's cluster) and from the
//! screen boxes of transparent geometry (the forward pass shades clusters the depth buffer does
//! not show) — and passes it to [`crate::Assigner::assign_active`]. The assignment then counts
//! and writes pairs only for active clusters, skipping whole rows of a slice that hold none. A
//! cluster outside the mask ends with an empty list, so the mask must cover every cluster the
//! frame shades: that is the caller's contract, and the one way this can lose a light.

use glam::UVec3;
use myriad_cluster_math::ClusterGrid;

/// One flag per cluster of a grid, plus one per (slice, row) that says whether the row has any.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ActiveClusters {
    dims: UVec3,
    cluster: Vec<bool>,
    row: Vec<bool>,
    active: usize,
}

impl ActiveClusters {
    /// No active cluster, for `grid`'s dimensions.
    pub fn new(grid: &ClusterGrid) -> Self {
        let mut mask = Self::default();
        mask.reset(grid);
        mask
    }

    /// Clears the mask for `grid`'s dimensions, keeping the storage.
    pub fn reset(&mut self, grid: &ClusterGrid) {
        self.dims = grid.dims;
        self.cluster.clear();
        self.cluster.resize(grid.cluster_count(), false);
        self.row.clear();
        self.row.resize((grid.dims.y * grid.dims.z) as usize, false);
        self.active = 0;
    }

    /// Grid dimensions the mask is for.
    pub fn dims(&self) -> UVec3 {
        self.dims
    }

    /// Marks cluster `id` active.
    #[inline]
    pub fn mark(&mut self, id: u32) {
        let c = id as usize;
        if !self.cluster[c] {
            self.cluster[c] = true;
            self.row[c / self.dims.x as usize] = true;
            self.active += 1;
        }
    }

    /// Marks every cluster with tile column in `x`, row in `y` and slice in `z` (inclusive
    /// ranges, clamped to the grid).
    pub fn mark_box(&mut self, x: [u32; 2], y: [u32; 2], z: [u32; 2]) {
        let d = self.dims - UVec3::ONE;
        for k in z[0].min(d.z)..=z[1].min(d.z) {
            for j in y[0].min(d.y)..=y[1].min(d.y) {
                for i in x[0].min(d.x)..=x[1].min(d.x) {
                    self.mark(i + self.dims.x * (j + self.dims.y * k));
                }
            }
        }
    }

    /// Marks every cluster.
    pub fn mark_all(&mut self) {
        self.cluster.fill(true);
        self.row.fill(true);
        self.active = self.cluster.len();
    }

    /// Whether cluster `id` is active.
    #[inline]
    pub fn is_active(&self, id: u32) -> bool {
        self.cluster[id as usize]
    }

    /// Whether any cluster of row `row` (= `j + Y·k`) is active.
    #[inline]
    pub(crate) fn row_has_any(&self, row: usize) -> bool {
        self.row[row]
    }

    /// Per-cluster flags.
    pub(crate) fn flags(&self) -> &[bool] {
        &self.cluster
    }

    /// Number of active clusters.
    pub fn active_count(&self) -> usize {
        self.active
    }

    /// Number of clusters of the grid.
    pub fn cluster_count(&self) -> usize {
        self.cluster.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use myriad_cluster_math::DepthSlicing;

    #[test]
    fn marks_clusters_rows_and_boxes() {
        let grid = ClusterGrid::new(UVec3::new(4, 3, 2), DepthSlicing::Linear, 1.0, 2.0);
        let mut m = ActiveClusters::new(&grid);
        assert_eq!(m.active_count(), 0);
        m.mark(grid.cluster_id(1, 2, 1));
        m.mark(grid.cluster_id(1, 2, 1));
        assert_eq!(m.active_count(), 1);
        assert!(m.is_active(grid.cluster_id(1, 2, 1)));
        assert!(m.row_has_any(2 + 3));
        assert!(!m.row_has_any(2));
        m.mark_box([0, 9], [0, 0], [0, 0]);
        assert_eq!(m.active_count(), 5);
        m.mark_all();
        assert_eq!(m.active_count(), 24);
        m.reset(&grid);
        assert_eq!(m.active_count(), 0);
    }
}
