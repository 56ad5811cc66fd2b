//! The output: per-cluster light lists in CSR form (the paper's Figure 3).

/// Light lists for every cluster: cluster `c`'s lights are
/// `indices[offsets[c] .. offsets[c] + counts[c]]`, ascending, as indices into the input columns.
///
/// Reuse one value across frames: the assignment refills it and only grows its vectors.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LightLists {
    /// Exclusive prefix sum of `counts`, one per cluster.
    pub offsets: Vec<u32>,
    /// Number of lights in each cluster.
    pub counts: Vec<u32>,
    /// Concatenated light indices, cluster after cluster.
    pub indices: Vec<u32>,
}

impl LightLists {
    /// An empty value (no storage yet).
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of clusters described.
    pub fn cluster_count(&self) -> usize {
        self.counts.len()
    }

    /// Total cluster–light pairs.
    pub fn pair_count(&self) -> usize {
        self.indices.len()
    }

    /// The lights of cluster `c`.
    ///
    /// # Panics
    /// When `c` is not a cluster of the lists (`c >= offsets.len()`), or the lists are not CSR
    /// (a list running past `indices`).
    pub fn lights_of(&self, c: usize) -> &[u32] {
        let start = self.offsets[c] as usize;
        &self.indices[start..start + self.counts[c] as usize]
    }

    /// Bytes of the three arrays as uploaded to the GPU.
    pub fn byte_size(&self) -> usize {
        Self::byte_size_for(self.counts.len(), self.indices.len())
    }

    /// Bytes of the lists for `clusters` clusters and `pairs` pairs: `4·(2·clusters + pairs)`.
    /// With a pair budget ([`crate::Assigner::with_pair_budget`]) this bounds a frame's output
    /// before it is computed: `byte_size_for(grid.cluster_count(), budget)` (a coarsened grid only
    /// has fewer clusters) — except a frame whose lights exceed the budget even on one cluster
    /// ([`crate::AssignStats::over_budget`]), which holds one pair per light in view: bound
    /// every frame with `byte_size_for(grid.cluster_count(), budget.max(lights))`.
    pub const fn byte_size_for(clusters: usize, pairs: usize) -> usize {
        4 * (2 * clusters + pairs)
    }

    /// Resets to `clusters` empty lists, keeping the storage.
    pub(crate) fn reset(&mut self, clusters: usize) {
        self.offsets.clear();
        self.offsets.resize(clusters, 0);
        self.counts.clear();
        self.counts.resize(clusters, 0);
        self.indices.clear();
    }

    /// Sizes `offsets` and `counts` for `clusters` without clearing anything: for writers that
    /// overwrite every entry, and that size `indices` themselves (a steady-state frame then
    /// writes no memory twice).
    pub(crate) fn resize_for(&mut self, clusters: usize) {
        self.offsets.resize(clusters, 0);
        self.counts.resize(clusters, 0);
    }

    /// Checks the CSR invariants (panics naming the first broken one); for tests and for callers
    /// who build or edit lists themselves. `assign` does not call it.
    pub fn assert_well_formed(&self, light_count: usize) {
        assert_eq!(
            self.offsets.len(),
            self.counts.len(),
            "offsets and counts differ in length"
        );
        let mut running = 0u64;
        for c in 0..self.counts.len() {
            assert_eq!(self.offsets[c] as u64, running, "offset of cluster {c}");
            running += self.counts[c] as u64;
            assert!(
                running <= self.indices.len() as u64,
                "cluster {c} ends past the {} indices",
                self.indices.len()
            );
            let lights = self.lights_of(c);
            assert!(
                lights.windows(2).all(|w| w[0] < w[1]),
                "cluster {c} not ascending"
            );
            if let Some(&l) = lights.iter().find(|&&l| l as usize >= light_count) {
                panic!("cluster {c} lists light {l} of {light_count}");
            }
        }
        assert_eq!(
            running as usize,
            self.indices.len(),
            "counts add up to fewer pairs than indices holds"
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn byte_size_counts_offsets_counts_and_indices() {
        assert_eq!(LightLists::byte_size_for(0, 0), 0);
        assert_eq!(LightLists::byte_size_for(3, 0), 24);
        assert_eq!(LightLists::byte_size_for(3, 5), 44);
        let lists = LightLists {
            offsets: vec![0, 2, 2],
            counts: vec![2, 0, 3],
            indices: vec![4, 7, 1, 2, 9],
        };
        assert_eq!(lists.byte_size(), 44);
        assert_eq!((lists.cluster_count(), lists.pair_count()), (3, 5));
        assert_eq!(lists.lights_of(0), [4, 7]);
        assert_eq!(lists.lights_of(1), [] as [u32; 0]);
        assert_eq!(lists.lights_of(2), [1, 2, 9]);
    }

    /// The panic message of `lists.assert_well_formed(lights)`, or `None` where it passes.
    fn broken_invariant(lists: &LightLists, lights: usize) -> Option<String> {
        let payload = std::panic::catch_unwind(|| lists.assert_well_formed(lights)).err()?;
        Some(match payload.downcast::<String>() {
            Ok(message) => *message,
            Err(payload) => payload.downcast_ref::<&str>().unwrap().to_string(),
        })
    }

    #[test]
    fn assert_well_formed_names_each_broken_invariant() {
        // Every test of the assigners leans on this check; one that passed broken lists would
        // make them all check nothing (mutation audit: no test fed it bad lists).
        let good = LightLists {
            offsets: vec![0, 2, 2],
            counts: vec![2, 0, 3],
            indices: vec![4, 7, 1, 2, 9],
        };
        assert_eq!(broken_invariant(&good, 10), None);
        let cases = [
            (
                vec![0, 2],
                vec![2, 0, 3],
                vec![4, 7, 1, 2, 9],
                10,
                "differ in length",
            ),
            (
                vec![0, 2, 3],
                vec![2, 0, 3],
                vec![4, 7, 1, 2, 9],
                10,
                "offset of cluster 2",
            ),
            (
                vec![0, 2, 2],
                vec![2, 0, 3],
                vec![7, 4, 1, 2, 9],
                10,
                "cluster 0 not ascending",
            ),
            (
                vec![0, 2, 2],
                vec![2, 0, 3],
                vec![4, 4, 1, 2, 9],
                10,
                "cluster 0 not ascending",
            ),
            (
                vec![0, 2, 2],
                vec![2, 0, 3],
                vec![4, 7, 1, 2, 9],
                9,
                "cluster 2 lists light 9 of 9",
            ),
            (
                vec![0, 2, 2],
                vec![2, 0, 3],
                vec![4, 7, 1, 2],
                10,
                "cluster 2 ends past the 4",
            ),
            (
                vec![0, 2, 2],
                vec![2, 0, 3],
                vec![4, 7, 1, 2, 9, 11],
                12,
                "fewer pairs",
            ),
        ];
        for (offsets, counts, indices, lights, needle) in cases {
            let lists = LightLists {
                offsets,
                counts,
                indices,
            };
            let message = broken_invariant(&lists, lights)
                .unwrap_or_else(|| panic!("{lists:?} passed as well formed"));
            assert!(message.contains(needle), "{message:?} for {lists:?}");
        }
    }
}
