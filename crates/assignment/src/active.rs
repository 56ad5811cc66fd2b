//! Active clusters: the clusters a frame actually shades (Olsson et al., "Clustered Deferred and
//! Forward Shading", 2012: *find unique clusters*). Lists are only needed there; every other
//! cluster can stay empty.
//!
//! The caller builds the mask — from a depth buffer (every covered pixel's cluster) and from the
//! screen boxes of transparent geometry (the forward pass shades clusters the depth buffer does
//! not show) — and passes it to [`crate::Assigner::assign_active`]. The assignment then counts
//! and writes pairs only for active clusters: a light's row of clusters with no active one is
//! dropped as it is emitted (an O(1) test against a prefix count of the flags, [`ActiveView`]).
//! A cluster outside the mask ends with an empty list, so the mask must cover every cluster the
//! frame shades: that is the caller's contract, and the one way this can lose a light.

use glam::UVec3;
use myriad_cluster_math::{ClusterGrid, OuterSlices};

/// One flag per cluster of a grid.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ActiveClusters {
    dims: UVec3,
    /// The grid the flags are for, its outer slices open (see [`ActiveClusters::is_for`]);
    /// `None` for a mask of no grid (`default()`).
    grid: Option<ClusterGrid>,
    cluster: Vec<bool>,
    active: usize,
}

impl ActiveClusters {
    /// No active cluster, for `grid`'s dimensions.
    pub fn new(grid: &ClusterGrid) -> Self {
        let mut mask = Self::default();
        mask.reset(grid);
        mask
    }

    /// Clears the mask for `grid`, keeping the storage.
    pub fn reset(&mut self, grid: &ClusterGrid) {
        self.dims = grid.dims();
        self.grid = Some(grid.with_outer_slices(OuterSlices::Open));
        self.cluster.clear();
        self.cluster.resize(grid.cluster_count(), false);
        self.active = 0;
    }

    /// Grid dimensions the mask is for.
    pub fn dims(&self) -> UVec3 {
        self.dims
    }

    /// Whether the mask's cluster ids are `grid`'s: the grid it was made or last reset for, or
    /// one differing only in its outer slices (open or closed, the same cells hold the same
    /// pixels). A grid of the same dimensions over another depth range or slicing is not: its
    /// cluster ids are other cells (a mask from the full range's grid used on the fitted one
    /// left clusters that the frame shades without their lights).
    pub fn is_for(&self, grid: &ClusterGrid) -> bool {
        self.grid == Some(grid.with_outer_slices(OuterSlices::Open))
    }

    /// Marks cluster `id` active. Panics when `id` is not a cluster of the mask's grid.
    #[inline]
    pub fn mark(&mut self, id: u32) {
        let c = id as usize;
        if !self.cluster[c] {
            self.cluster[c] = true;
            self.active += 1;
        }
    }

    /// Marks every cluster with tile column in `x`, row in `y` and slice in `z` (inclusive
    /// ranges, clamped to the grid). Marks nothing on a mask of no grid (`default()`).
    pub fn mark_box(&mut self, x: [u32; 2], y: [u32; 2], z: [u32; 2]) {
        if self.cluster.is_empty() {
            return;
        }
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
        self.active = self.cluster.len();
    }

    /// Whether cluster `id` is active. Panics when `id` is not a cluster of the mask's grid.
    #[inline]
    pub fn is_active(&self, id: u32) -> bool {
        self.cluster[id as usize]
    }

    /// The mask with its prefix count, built into `before` (reused scratch) for one frame.
    pub(crate) fn view<'a>(&'a self, before: &'a mut Vec<u32>) -> ActiveView<'a> {
        before.clear();
        before.push(0);
        let mut running = 0u32;
        before.extend(self.cluster.iter().map(|&on| {
            running += on as u32;
            running
        }));
        ActiveView {
            flags: &self.cluster,
            before,
        }
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

/// A frame's read-only view of the mask: the flags, and how many clusters before each id are
/// active, so a run of clusters' active count costs two loads.
#[derive(Clone, Copy)]
pub(crate) struct ActiveView<'a> {
    /// One flag per cluster.
    pub flags: &'a [bool],
    /// `before[c]`: active clusters among ids `0..c` (one entry more than clusters).
    before: &'a [u32],
}

impl ActiveView<'_> {
    /// Active clusters among ids `first .. first + len`.
    #[inline]
    pub fn count(&self, first: u32, len: u32) -> u32 {
        self.before[(first + len) as usize] - self.before[first as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use myriad_cluster_math::DepthSlicing;

    #[test]
    fn a_box_marks_exactly_its_clusters() {
        // A box away from row 0 and slice 0, clamped at the grid's far corner.
        let grid = ClusterGrid::new(UVec3::new(4, 3, 3), DepthSlicing::Linear, 1.0, 2.0);
        let mut m = ActiveClusters::new(&grid);
        assert_eq!((m.dims(), m.cluster_count()), (grid.dims(), 36));
        m.mark_box([2, 7], [1, 2], [1, 9]);
        let mut want = Vec::new();
        for k in 1..3 {
            for j in 1..3 {
                for i in 2..4 {
                    want.push(grid.cluster_id(i, j, k));
                }
            }
        }
        want.sort_unstable();
        let got: Vec<u32> = (0..grid.cluster_count() as u32)
            .filter(|&c| m.is_active(c))
            .collect();
        assert_eq!(got, want);
        assert_eq!(m.active_count(), want.len());
    }

    #[test]
    fn marks_clusters_rows_and_boxes() {
        let grid = ClusterGrid::new(UVec3::new(4, 3, 2), DepthSlicing::Linear, 1.0, 2.0);
        let mut m = ActiveClusters::new(&grid);
        assert_eq!(m.active_count(), 0);
        m.mark(grid.cluster_id(1, 2, 1));
        m.mark(grid.cluster_id(1, 2, 1));
        assert_eq!(m.active_count(), 1);
        assert!(m.is_active(grid.cluster_id(1, 2, 1)));
        let mut before = Vec::new();
        let row = grid.cluster_id(0, 2, 1);
        assert_eq!(m.view(&mut before).count(row, 4), 1);
        assert_eq!(m.view(&mut before).count(grid.cluster_id(0, 2, 0), 4), 0);
        m.mark_box([0, 9], [0, 0], [0, 0]);
        assert_eq!(m.active_count(), 5);
        assert_eq!(m.view(&mut before).count(0, 24), 5);
        assert_eq!(m.view(&mut before).count(1, 2), 2);
        m.mark_all();
        assert_eq!(m.active_count(), 24);
        m.reset(&grid);
        assert_eq!(m.active_count(), 0);
        // A mask of no grid has nothing to mark.
        let mut empty = ActiveClusters::default();
        empty.mark_box([0, 3], [0, 3], [0, 3]);
        assert_eq!(empty.active_count(), 0);
    }
}
