//! How many cluster–light pairs a command lets its lists hold, and what it says when a frame
//! needs more.
//!
//! Why: the assigner's own limit is what u32 offsets hold (2³² − 1 pairs, 16 GiB of indices),
//! far past the memory of most machines. Lights big enough to cover the whole grid reach it: a
//! stress audit's 100k lights of radius 10⁴ on 32×18×16 made 921.6 M pairs, and the commands
//! aborted in the allocator (exit 134) instead of coarsening the grid (`assign`, `stress`) or
//! saying the frame is too big to compare (`bench`, `report`). So each command's default budget
//! is what the memory this process may take holds at that command's peak bytes a pair, capped at
//! what u32 offsets hold; `--pair-budget` sets it where a command takes one.

use super::source::memory_limit_bytes;
use myriad::assignment::AssignStats;
use myriad::cluster_math::ClusterGrid;
use myriad::cluster_math::glam::UVec3;

/// What a pair costs `assign` at its peak, with room: the lists' index, the dump's copy of it and
/// the JSON text. A stress audit measured 12.5 GB (`refined`) and 16.7 GB (`linear`, whose
/// per-cluster lists come first) for 921.6 M pairs: 13.6 and 18.1 bytes a pair.
pub const ASSIGN_BYTES_PER_PAIR: u64 = 24;

/// What a pair costs `bench` and `report` at their peak, with room: the oracle's lists and one
/// method's at a time (8 bytes), and `linear`'s per-cluster lists. Measured: 1.22 GB peak
/// (`/usr/bin/time -v`) for 92.16 M pairs of every method, 13.3 bytes a pair.
pub const COMPARE_BYTES_PER_PAIR: u64 = 16;

/// What a pair costs `stress` at its peak, with room: the lists (4 bytes); then the upload's
/// staging copy and, on a software adapter, the GPU buffer in the same memory (8), and while the
/// GPU's lists are compared, their read-back buffer and the array read from it (8: 20 in all);
/// after the GPU is dropped, the `exact` method's lists for the full check (4). Measured: 3.49 GB
/// peak for 728 M pairs before the upload, 4.8 bytes a pair; the read-back raised a million
/// lights' run (22.9 M pairs) from 634 to 809 MiB, 8 bytes a pair.
pub const STRESS_BYTES_PER_PAIR: u64 = 24;

/// What u32 offsets hold: the assigner's own limit.
const OFFSET_LIMIT: u64 = u32::MAX as u64;

/// A command's pair budget and where it came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PairBudget {
    pub pairs: u64,
    pub source: BudgetSource,
    /// The command's peak bytes a pair, which the memory's share was divided by.
    bytes_per_pair: u64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BudgetSource {
    /// `--pair-budget`.
    Requested,
    /// What the memory available holds at the command's peak bytes a pair.
    Memory,
    /// What u32 offsets hold (the memory is unknown, or holds more).
    Offsets,
    /// What the GPU binds in one storage buffer (the renderer's lists must fit one).
    Device,
}

impl PairBudget {
    /// `requested`, or the default: what u32 offsets hold, capped by what the memory available
    /// holds at `bytes_per_pair` (the command's peak).
    pub fn new(requested: Option<u64>, bytes_per_pair: u64) -> Self {
        Self::from_memory(requested, bytes_per_pair, memory_limit_bytes())
    }

    /// [`PairBudget::new`] with the memory available given (`None`: unknown).
    fn from_memory(requested: Option<u64>, bytes_per_pair: u64, memory: Option<u64>) -> Self {
        let (pairs, source) = match (requested, memory.map(|bytes| bytes / bytes_per_pair)) {
            // The assigner holds at most what u32 offsets do, whatever is asked.
            (Some(pairs), _) => (pairs.min(OFFSET_LIMIT), BudgetSource::Requested),
            (None, Some(pairs)) if pairs < OFFSET_LIMIT => (pairs, BudgetSource::Memory),
            (None, _) => (OFFSET_LIMIT, BudgetSource::Offsets),
        };
        Self {
            pairs,
            source,
            bytes_per_pair,
        }
    }

    /// The budget, lowered to `device_pairs` (what the GPU binds,
    /// `GpuContext::max_list_pairs`) where that is less and the budget was not asked for: the
    /// lists are then built on a coarser grid the renderer takes, rather than refused by it after
    /// the assignment.
    pub fn capped_by_device(self, device_pairs: u64) -> Self {
        if self.source == BudgetSource::Requested || device_pairs >= self.pairs {
            return self;
        }
        Self {
            pairs: device_pairs,
            source: BudgetSource::Device,
            ..self
        }
    }

    /// The budget and why it is what it is, for a message: "N pairs (what …)".
    pub fn describe(&self) -> String {
        let pairs = self.pairs;
        match self.source {
            BudgetSource::Requested => format!("{pairs} pairs (--pair-budget)"),
            BudgetSource::Memory => format!(
                "{pairs} pairs (what the memory available holds at {} bytes a pair)",
                self.bytes_per_pair
            ),
            BudgetSource::Offsets => format!("{pairs} pairs (what u32 offsets hold)"),
            BudgetSource::Device => {
                format!("{pairs} pairs (what the GPU binds in one storage buffer)")
            }
        }
    }

    /// The warning for a frame whose lists were built on a coarser grid than `requested`
    /// ([`AssignStats::grid_built`]); `None` when they were not. `name` is the scene's and
    /// `recorded_by` what the output records the grid in ("the dump", "the report"). For
    /// commands that take `--pair-budget`.
    pub fn coarsening_warning(
        &self,
        name: &str,
        stats: &AssignStats,
        requested: &ClusterGrid,
        recorded_by: &str,
    ) -> Option<String> {
        let over = if stats.over_budget {
            " (still over the budget: every visible light in one cluster)"
        } else {
            ""
        };
        let hint = match self.source {
            BudgetSource::Memory => "; --pair-budget sets the budget",
            BudgetSource::Requested | BudgetSource::Offsets | BudgetSource::Device => "",
        };
        coarsened_warning(
            name,
            requested.dims(),
            stats.grid_built(requested).dims(),
            &format!("the budget of {}", self.describe()),
            &format!(", which {recorded_by} records{over}{hint}"),
        )
    }
}

/// The one warning every command gives when lists were built on a coarser grid than the one
/// asked for: "warning: NAME: the lists need more pairs than LIMIT on the A grid; they were built
/// on the coarser B grid" and `tail`. `None` when `built` is `requested`.
pub fn coarsened_warning(
    name: &str,
    requested: UVec3,
    built: UVec3,
    limit: &str,
    tail: &str,
) -> Option<String> {
    (requested != built).then(|| {
        format!(
            "warning: {name}: the lists need more pairs than {limit} on the {}x{}x{} grid; they \
             were built on the coarser {}x{}x{} grid{tail}",
            requested.x, requested.y, requested.z, built.x, built.y, built.z
        )
    })
}

/// [`coarsened_warning`] for lists past what the device binds in one buffer
/// (`GpuContext::max_list_pairs`), which the viewer and the frame loop coarsen to fit.
pub fn device_coarsened_warning(
    name: &str,
    requested: UVec3,
    built: UVec3,
    max_pairs: u64,
) -> Option<String> {
    coarsened_warning(
        name,
        requested,
        built,
        &format!("this device binds in one buffer ({max_pairs} pairs)"),
        " and shaded on it",
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use myriad::scene::DepthSlicing;

    /// The device's binding caps a default budget, never one asked for (that one coarsens to
    /// what was asked, and the renderer says if the device still cannot bind it).
    #[test]
    fn the_device_caps_a_default_budget_only() {
        let llvmpipe = 1 << 25;
        let memory = PairBudget::from_memory(None, 24, Some(24 << 30));
        let b = memory.capped_by_device(llvmpipe);
        assert_eq!((b.pairs, b.source), (llvmpipe, BudgetSource::Device));
        assert_eq!(
            b.describe(),
            "33554432 pairs (what the GPU binds in one storage buffer)"
        );
        // A device that binds more leaves the memory's budget.
        assert_eq!(memory.capped_by_device(u64::MAX), memory);
        let asked = PairBudget::from_memory(Some(1 << 30), 24, Some(24 << 30));
        assert_eq!(asked.capped_by_device(llvmpipe), asked);
    }

    #[test]
    fn the_default_follows_the_memory_up_to_what_offsets_hold() {
        let gib = 1u64 << 30;
        let b = PairBudget::from_memory(None, 24, Some(24 * gib));
        assert_eq!(b.pairs, gib);
        assert_eq!(b.source, BudgetSource::Memory);
        assert_eq!(
            b.describe(),
            "1073741824 pairs (what the memory available holds at 24 bytes a pair)"
        );
        // A terabyte holds more than u32 offsets: their limit stands.
        let b = PairBudget::from_memory(None, 16, Some(1 << 40));
        assert_eq!((b.pairs, b.source), (OFFSET_LIMIT, BudgetSource::Offsets));
        // Exactly what offsets hold: their limit, as the reason.
        let b = PairBudget::from_memory(None, 16, Some(16 * OFFSET_LIMIT + 15));
        assert_eq!((b.pairs, b.source), (OFFSET_LIMIT, BudgetSource::Offsets));
        let b = PairBudget::from_memory(None, 16, Some(16 * OFFSET_LIMIT - 1));
        assert_eq!(
            (b.pairs, b.source),
            (OFFSET_LIMIT - 1, BudgetSource::Memory)
        );
        let b = PairBudget::from_memory(None, 16, None);
        assert_eq!((b.pairs, b.source), (OFFSET_LIMIT, BudgetSource::Offsets));
        // Asked for, it is taken as it is, whatever the memory, up to what offsets hold.
        let b = PairBudget::from_memory(Some(7), 24, Some(24));
        assert_eq!((b.pairs, b.source), (7, BudgetSource::Requested));
        let b = PairBudget::from_memory(Some(5_000_000_000), 24, None);
        assert_eq!((b.pairs, b.source), (OFFSET_LIMIT, BudgetSource::Requested));
        // Past what offsets hold no budget helps: no hint to raise it.
        let grid = ClusterGrid::new(UVec3::new(2, 2, 2), DepthSlicing::Log, 0.1, 100.0);
        let stats = AssignStats {
            coarsened: 1,
            ..AssignStats::default()
        };
        let w = PairBudget::from_memory(None, 24, None)
            .coarsening_warning("s", &stats, &grid, "the dump")
            .unwrap();
        assert!(w.ends_with("which the dump records"), "{w}");
    }

    #[test]
    fn the_warning_names_both_grids_and_the_budget() {
        let grid = ClusterGrid::new(UVec3::new(32, 18, 16), DepthSlicing::Log, 0.1, 100.0);
        let mut stats = AssignStats::default();
        let budget = PairBudget::from_memory(None, 24, Some(24_000));
        assert_eq!(
            budget.coarsening_warning("s.json", &stats, &grid, "the dump"),
            None
        );
        stats.coarsened = 1;
        let w = budget
            .coarsening_warning("s.json", &stats, &grid, "the dump")
            .unwrap();
        assert_eq!(
            w,
            "warning: s.json: the lists need more pairs than the budget of 1000 pairs (what \
             the memory available holds at 24 bytes a pair) on the 32x18x16 grid; they were \
             built on the coarser 16x9x8 grid, which the dump records; --pair-budget sets the \
             budget"
        );
        stats.over_budget = true;
        let requested = PairBudget::from_memory(Some(5), 24, None);
        let w = requested
            .coarsening_warning("s.json", &stats, &grid, "the report")
            .unwrap();
        assert!(
            w.contains("than the budget of 5 pairs (--pair-budget) on")
                && w.ends_with(
                    "which the report records (still over the budget: every visible \
                                light in one cluster)"
                ),
            "{w}"
        );
    }

    #[test]
    fn the_device_warning_names_its_limit() {
        let (want, got) = (UVec3::new(96, 48, 64), UVec3::new(48, 24, 32));
        assert_eq!(device_coarsened_warning("a", want, want, 9), None);
        assert_eq!(
            device_coarsened_warning("a", want, got, 33_554_432).unwrap(),
            "warning: a: the lists need more pairs than this device binds in one buffer \
             (33554432 pairs) on the 96x48x64 grid; they were built on the coarser 48x24x32 grid \
             and shaded on it"
        );
    }
}
