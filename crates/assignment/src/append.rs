//! The lock-free per-cluster append: spans of clusters per light → CSR lists, in three steps.
//!
//! 1. **Count.** Each task owns a contiguous range of lights and a private histogram row (one
//!    counter per cluster, handed out as disjoint `&mut` chunks of one table). Spans are runs of
//!    consecutive clusters, so a row first collects a difference array (+1 at a span's start, −1
//!    just past its end: O(spans), not O(pairs)) and one running sum turns it into counts.
//! 2. **Prefix.** `counts[c]` sums the rows, `offsets` is their exclusive prefix sum, and each row
//!    becomes write cursors: inside a cluster, task `t` starts after the lights of tasks `< t`.
//!    These are plain loops over whole rows (vectorised; O(tasks × clusters)).
//! 3. **Fill.** Each task walks its spans again and writes light indices at its own cursors.
//!
//! No counter is shared, so there is no read-modify-write anywhere; and because tasks are
//! contiguous light ranges merged in order, every cluster's list comes out in ascending light
//! order whatever the number of tasks or threads — the output is deterministic.

use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// A run of clusters `first .. first + len` (one row of a light's box) touched by `light`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Span {
    pub light: u32,
    pub first: u32,
    pub len: u32,
}

/// Histogram rows, `tasks × clusters`, reused across frames.
#[derive(Default)]
pub(crate) struct Histograms {
    cells: Vec<u32>,
    running: Vec<u32>,
    clusters: usize,
    tasks: usize,
}

impl Histograms {
    /// Sizes the table for `tasks × clusters` (storage only grows); rows are zeroed by their
    /// tasks.
    pub fn prepare(&mut self, tasks: usize, clusters: usize) {
        assert!(clusters > 0);
        self.cells.resize(tasks * clusters, 0);
        self.tasks = tasks;
        self.clusters = clusters;
    }

    /// The rows, one disjoint `&mut` chunk per task.
    pub fn rows(&mut self) -> std::slice::ChunksExactMut<'_, u32> {
        self.cells.chunks_exact_mut(self.clusters)
    }

    /// The rows for the thread pool.
    pub fn par_rows(&mut self) -> rayon::slice::ChunksExactMut<'_, u32> {
        self.cells.par_chunks_exact_mut(self.clusters)
    }

    /// Step 2: fills `offsets` and `counts` and turns every row into write cursors. Returns the
    /// total number of pairs.
    pub fn prefix(&mut self, offsets: &mut [u32], counts: &mut [u32]) -> usize {
        let clusters = self.clusters;
        assert!(offsets.len() == clusters && counts.len() == clusters);
        counts.fill(0);
        for row in self.cells.chunks_exact(clusters) {
            for (count, &n) in counts.iter_mut().zip(row) {
                *count += n;
            }
        }
        let mut total = 0u64;
        for (offset, &n) in offsets.iter_mut().zip(counts.iter()) {
            *offset = total as u32;
            total += n as u64;
        }
        assert!(
            total <= u32::MAX as u64,
            "{total} cluster-light pairs do not fit u32 offsets; use a coarser grid or a memory budget"
        );
        self.running.clear();
        self.running.extend_from_slice(offsets);
        for row in self.cells.chunks_exact_mut(clusters) {
            for (cell, at) in row.iter_mut().zip(self.running.iter_mut()) {
                let n = *cell;
                *cell = *at;
                *at += n;
            }
        }
        total as usize
    }
}

/// Step 1 for one task: count every span's clusters into the task's row.
pub(crate) fn count(row: &mut [u32], spans: &[Span]) {
    row.fill(0);
    let clusters = row.len();
    for s in spans {
        row[s.first as usize] = row[s.first as usize].wrapping_add(1);
        let end = (s.first + s.len) as usize;
        if end < clusters {
            row[end] = row[end].wrapping_sub(1);
        }
    }
    let mut running = 0u32;
    for cell in row.iter_mut() {
        running = running.wrapping_add(*cell);
        *cell = running;
    }
}

/// Step 3 for one task: write each span's light at the task's cursors.
pub(crate) fn fill(row: &mut [u32], spans: &[Span], out: &SharedIndices<'_>) {
    for s in spans {
        for cell in &mut row[s.first as usize..(s.first + s.len) as usize] {
            let at = *cell;
            *cell = at + 1;
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
