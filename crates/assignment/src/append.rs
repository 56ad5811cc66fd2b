//! The lock-free per-cluster append: spans of clusters per light → CSR lists, in three steps.
//!
//! 1. **Count.** Each task owns a contiguous range of lights and a private histogram row (one
//!    counter per cluster) in a shared table of relaxed atomics. A task only ever touches its own
//!    row, so the counters are plain loads and stores — no contention, no read-modify-write.
//! 2. **Prefix.** Parallel over blocks of clusters: `offsets[c]` is the exclusive prefix sum over
//!    clusters, and inside a cluster the tasks follow in light order; each task's counter is
//!    replaced by the position where that task starts writing into cluster `c`.
//! 3. **Fill.** Each task walks its spans again and writes light indices at its cursors.
//!
//! Because tasks are contiguous light ranges merged in order, every cluster's list comes out in
//! ascending light order whatever the number of tasks or threads — the output is deterministic.
//!

use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// A run of clusters `first .. first + len` (one row of a light's box) touched by `light`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Span {
    pub light: u32,
    pub first: u32,
    pub len: u32,
}

/// Clusters per block of the parallel prefix sum.
const PREFIX_BLOCK: usize = 4096;

/// Histogram rows, `tasks × clusters`, reused across frames.
#[derive(Default)]
pub(crate) struct Histograms {
    cells: Vec<AtomicU32>,
    block_sums: Vec<u64>,
    clusters: usize,
    tasks: usize,
}

impl Histograms {
    /// Sizes the table for `tasks × clusters`, growing only; rows are zeroed by their tasks.
    pub fn prepare(&mut self, tasks: usize, clusters: usize) {
        let needed = tasks * clusters;
        if self.cells.len() < needed {
            self.cells.resize_with(needed, || AtomicU32::new(0));
        }
        self.tasks = tasks;
        self.clusters = clusters;
    }

    /// Task `t`'s row.
    pub fn row(&self, t: usize) -> &[AtomicU32] {
        &self.cells[t * self.clusters..(t + 1) * self.clusters]
    }

    /// Step 2: fills `offsets` and `counts` and turns every row into write cursors. Returns the
    /// total number of pairs.
    pub fn prefix(&mut self, offsets: &mut [u32], counts: &mut [u32], parallel: bool) -> usize {
        let (tasks, clusters) = (self.tasks, self.clusters);
        assert!(offsets.len() == clusters && counts.len() == clusters);
        let cells = &self.cells[..tasks * clusters];
        // Turns clusters `base..base + offsets.len()` into cursors starting at `start`; returns
        // the running total after them.
        let scan = |base: usize, start: u64, offsets: &mut [u32], counts: &mut [u32]| -> u64 {
            let mut at = start;
            for (i, (offset, count)) in offsets.iter_mut().zip(counts.iter_mut()).enumerate() {
                let c = base + i;
                *offset = at as u32;
                for t in 0..tasks {
                    let cell = &cells[t * clusters + c];
                    let n = cell.load(Relaxed);
                    cell.store(at as u32, Relaxed);
                    at += n as u64;
                }
                *count = (at - *offset as u64) as u32;
            }
            at
        };
        let total = if !parallel {
            scan(0, 0, offsets, counts)
        } else {
            // Pass 1: each block's total; pass 2: scan the blocks from their exclusive bases.
            let blocks = clusters.div_ceil(PREFIX_BLOCK);
            self.block_sums.clear();
            self.block_sums.resize(blocks, 0);
            self.block_sums
                .par_iter_mut()
                .enumerate()
                .for_each(|(b, sum)| {
                    let range = b * PREFIX_BLOCK..((b + 1) * PREFIX_BLOCK).min(clusters);
                    *sum = (0..tasks)
                        .map(|t| {
                            cells[t * clusters..][range.clone()]
                                .iter()
                                .map(|n| n.load(Relaxed) as u64)
                                .sum::<u64>()
                        })
                        .sum();
                });
            let mut running = 0u64;
            for s in self.block_sums.iter_mut() {
                (*s, running) = (running, running + *s);
            }
            if running <= u32::MAX as u64 {
                self.block_sums
                    .par_iter()
                    .zip(
                        offsets
                            .par_chunks_mut(PREFIX_BLOCK)
                            .zip(counts.par_chunks_mut(PREFIX_BLOCK)),
                    )
                    .enumerate()
                    .for_each(|(b, (&start, (offsets, counts)))| {
                        scan(b * PREFIX_BLOCK, start, offsets, counts);
                    });
            }
            running
        };
        assert!(
            total <= u32::MAX as u64,
            "{total} cluster-light pairs do not fit u32 offsets; use a coarser grid or a memory budget"
        );
        total as usize
    }
}

/// Step 1 for one task: count every span's clusters into the task's row. Spans are runs of
/// consecutive clusters, so the row first collects a difference array (+1 at a span's start, −1
/// just past its end: O(spans) instead of O(pairs)) and one running sum turns it into counts.
pub(crate) fn count(row: &[AtomicU32], spans: &[Span]) {
    for cell in row {
        cell.store(0, Relaxed);
    }
    let bump = |at: usize, delta: u32| {
        if let Some(cell) = row.get(at) {
            cell.store(cell.load(Relaxed).wrapping_add(delta), Relaxed);
        }
    };
    for s in spans {
        bump(s.first as usize, 1);
        bump((s.first + s.len) as usize, u32::MAX); // −1 in wrapping arithmetic
    }
    let mut running = 0u32;
    for cell in row {
        running = running.wrapping_add(cell.load(Relaxed));
        cell.store(running, Relaxed);
    }
}

/// Step 3 for one task: write each span's light at the task's cursors.
pub(crate) fn fill(row: &[AtomicU32], spans: &[Span], out: &SharedIndices<'_>) {
    for s in spans {
        for cell in &row[s.first as usize..(s.first + s.len) as usize] {
            let at = cell.load(Relaxed);
            cell.store(at + 1, Relaxed);
            // SAFETY: after `prefix`, task t's cursor for cluster c walks the range
            // [start(t, c), start(t, c) + count(t, c)), and these ranges are disjoint across all
            // (t, c) and lie inside `0..pairs` = `out.len()`. Each task writes only through its own
            // row, once per counted pair, so every index is written by exactly one task, once.
            unsafe { out.write(at as usize, s.light) };
        }
    }
}

/// The measured alternative ([`crate::AppendStrategy::AtomicCounters`]): one shared counter per
/// cluster, `fetch_add` in both passes, then a sort per list for determinism.
#[derive(Default)]
pub(crate) struct AtomicCounters {
    counters: Vec<AtomicU32>,
}

impl AtomicCounters {
    /// Counts, scans, fills and sorts the tasks' spans into `out`; returns the pair count.
    pub fn assign(
        &mut self,
        tasks: &[crate::jobs::TaskOutput],
        clusters: usize,
        parallel: bool,
        out: &mut crate::LightLists,
    ) -> usize {
        if self.counters.len() < clusters {
            self.counters.resize_with(clusters, || AtomicU32::new(0));
        }
        let counters = &self.counters[..clusters];
        counters.iter().for_each(|c| c.store(0, Relaxed));
        let count = |task: &crate::jobs::TaskOutput| {
            for s in &task.spans {
                for c in &counters[s.first as usize..(s.first + s.len) as usize] {
                    c.fetch_add(1, Relaxed);
                }
            }
        };
        if parallel {
            tasks.par_iter().for_each(count);
        } else {
            tasks.iter().for_each(count);
        }
        out.reset(clusters);
        let mut running = 0u64;
        for (c, counter) in counters.iter().enumerate() {
            let n = counter.load(Relaxed);
            out.offsets[c] = running as u32;
            out.counts[c] = n;
            counter.store(running as u32, Relaxed);
            running += n as u64;
        }
        assert!(
            running <= u32::MAX as u64,
            "{running} cluster-light pairs do not fit u32 offsets"
        );
        out.indices.resize(running as usize, 0);
        let shared = SharedIndices::new(&mut out.indices);
        let fill = |task: &crate::jobs::TaskOutput| {
            for s in &task.spans {
                for c in &counters[s.first as usize..(s.first + s.len) as usize] {
                    let at = c.fetch_add(1, Relaxed);
                    // SAFETY: `fetch_add` hands every caller a distinct slot of the cluster's
                    // range [offset, offset + count), which lies inside `0..pairs`.
                    unsafe { shared.write(at as usize, s.light) };
                }
            }
        };
        if parallel {
            tasks.par_iter().for_each(fill);
        } else {
            tasks.iter().for_each(fill);
        }
        sort_lists(&mut out.indices, &out.offsets, 0, 0..clusters, parallel);
        running as usize
    }
}

/// Sorts every cluster's list in `indices` (which starts at pair `base`), splitting the cluster
/// range in halves across the pool.
fn sort_lists(
    indices: &mut [u32],
    offsets: &[u32],
    base: usize,
    clusters: std::ops::Range<usize>,
    parallel: bool,
) {
    if parallel && clusters.len() > 512 {
        let mid = clusters.start + clusters.len() / 2;
        let split = offsets[mid] as usize - base;
        let (left, right) = indices.split_at_mut(split);
        rayon::join(
            || sort_lists(left, offsets, base, clusters.start..mid, true),
            || sort_lists(right, offsets, base + split, mid..clusters.end, true),
        );
        return;
    }
    for c in clusters.clone() {
        let start = offsets[c] as usize - base;
        let end = if c + 1 < offsets.len() {
            offsets[c + 1] as usize - base
        } else {
            indices.len()
        };
        let end = if c + 1 == clusters.end {
            indices.len().min(end)
        } else {
            end
        };
        indices[start..end].sort_unstable();
    }
}

/// The output index array, writable from several tasks at disjoint positions.
pub(crate) struct SharedIndices<'a> {
    ptr: *mut u32,
    len: usize,
    _borrow: std::marker::PhantomData<&'a mut [u32]>,
}

// SAFETY: `SharedIndices` only hands out writes through `write`, whose contract requires that no
// two threads write the same position; the pointer comes from a `&mut [u32]` that outlives it.
unsafe impl Sync for SharedIndices<'_> {}

impl<'a> SharedIndices<'a> {
    pub fn new(slice: &'a mut [u32]) -> Self {
        Self {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
            _borrow: std::marker::PhantomData,
        }
    }

    /// Writes `value` at `at`.
    ///
    /// # Safety
    /// No other thread may read or write position `at` while `self` is alive.
    #[inline]
    pub unsafe fn write(&self, at: usize, value: u32) {
        assert!(
            at < self.len,
            "index {at} outside the {} pairs counted",
            self.len
        );
        // SAFETY: in bounds (checked above); exclusive per the caller's contract.
        unsafe { self.ptr.add(at).write(value) }
    }
}
