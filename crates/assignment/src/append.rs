//! The lock-free per-cluster append: spans of clusters per light → CSR lists.
//!
//! The clusters are split into *parts*: groups of consecutive depth slices, so each part is a
//! contiguous range of cluster ids and, after the prefix sum, a contiguous range of the output.
//! Every span is one row of one slice, so it lies inside a single part, and the tasks already
//! bucket their spans by part while emitting them. Then:
//!
//! 1. **Count**, in parallel over parts: a part walks the tasks' buckets for it in task order and
//!    counts into its own chunk of `counts` — as a difference array (+1 at a span's start, −1
//!    just past its end: O(spans), not O(pairs)) closed by one running sum.
//! 2. **Prefix**: `offsets` is the exclusive prefix sum of `counts` (one pass over the clusters).
//! 3. **Fill**, in parallel over parts: a part walks the same buckets again, in the same order, and
//!    writes light indices at per-cluster cursors into *its own* slice of `indices`.
//!
//! Nothing is shared between threads while it is written: each part owns disjoint chunks of
//! `counts`, of the cursors and of `indices` (plain `&mut` splits — no atomics, no `unsafe`, and
//! no cache line written by two threads, which an earlier per-task fill suffered from: a
//! cluster's list of ~10 entries is one cache line, and all tasks wrote into it). Lists come out
//! in ascending light order, because tasks are contiguous light ranges walked in order: the
//! output is identical for any number of tasks, parts or threads.

use crate::ActiveClusters;
use crate::jobs::TaskOutput;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// A run of clusters `first .. first + len` (one row of a light's box) touched by `light`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Span {
    pub light: u32,
    pub first: u32,
    pub len: u32,
}

/// How the clusters are split into parts.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Parts {
    /// Number of parts.
    pub count: usize,
    /// Clusters per part (the last part may have fewer).
    pub clusters: usize,
}

/// Step 1: counts every part's spans into `counts`; returns the total number of pairs, so the
/// caller can check it against its budget before anything is written.
pub(crate) fn count_all(
    tasks: &[TaskOutput],
    parts: Parts,
    parallel: bool,
    active: Option<&ActiveClusters>,
    counts: &mut [u32],
) -> u64 {
    crate::profiling::profile_span!("append count");
    let count_part =
        |(p, counts): (usize, &mut [u32])| count(tasks, p, p * parts.clusters, active, counts);
    if parallel {
        counts
            .par_chunks_mut(parts.clusters)
            .enumerate()
            .for_each(count_part);
    } else {
        counts
            .chunks_mut(parts.clusters)
            .enumerate()
            .for_each(count_part);
    }
    counts.iter().map(|&n| n as u64).sum()
}

/// Steps 2–3: `offsets` from `counts`, then every part's fill. `total` (from [`count_all`]) must
/// fit u32 offsets. `cursors` is reused scratch.
#[allow(clippy::too_many_arguments)] // The output's three arrays, the scratch and the plan.
pub(crate) fn fill_all(
    tasks: &[TaskOutput],
    parts: Parts,
    parallel: bool,
    active: Option<&ActiveClusters>,
    total: u64,
    counts: &[u32],
    offsets: &mut [u32],
    indices: &mut Vec<u32>,
    cursors: &mut Vec<u32>,
) {
    crate::profiling::profile_span!("append fill");
    assert!(
        total <= u32::MAX as u64,
        "{total} pairs do not fit u32 offsets"
    );
    let mut running = 0u32;
    for (offset, &n) in offsets.iter_mut().zip(counts) {
        *offset = running;
        running += n;
    }
    // Every entry is about to be written: only growth needs filling (`resize` leaves the rest).
    indices.resize(total as usize, 0);
    cursors.clear();
    cursors.extend_from_slice(offsets);
    let job = FillJob {
        tasks,
        parts,
        offsets,
        parallel,
        active,
    };
    job.fill(0..parts.count, indices, 0, cursors);
}

/// Step 1 for one part: count its spans into its chunk of `counts` (clusters from `base`).
/// With an `active` mask, spans in rows without an active cluster are skipped and inactive
/// clusters end with a count of 0.
fn count(
    tasks: &[TaskOutput],
    part: usize,
    base: usize,
    active: Option<&ActiveClusters>,
    counts: &mut [u32],
) {
    counts.fill(0);
    let len = counts.len();
    let row_width = active.map_or(1, |a| a.dims().x) as usize;
    for task in tasks {
        for s in &task.buckets[part] {
            if let Some(a) = active
                && !a.row_has_any(s.first as usize / row_width)
            {
                continue;
            }
            let start = s.first as usize - base;
            counts[start] = counts[start].wrapping_add(1);
            let end = start + s.len as usize;
            if end < len {
                counts[end] = counts[end].wrapping_sub(1);
            }
        }
    }
    let mut running = 0u32;
    for n in counts.iter_mut() {
        running = running.wrapping_add(*n);
        *n = running;
    }
    if let Some(a) = active {
        for (n, &on) in counts.iter_mut().zip(&a.flags()[base..base + len]) {
            *n = if on { *n } else { 0 };
        }
    }
}

/// Step 3, split recursively over the parts so each gets its own `&mut` slices.
struct FillJob<'a> {
    tasks: &'a [TaskOutput],
    parts: Parts,
    offsets: &'a [u32],
    parallel: bool,
    active: Option<&'a ActiveClusters>,
}

impl FillJob<'_> {
    /// Fills parts `range`, whose pairs are `indices` (starting at pair `base`) and whose
    /// clusters' cursors are `cursors`.
    fn fill(
        &self,
        range: std::ops::Range<usize>,
        indices: &mut [u32],
        base: usize,
        cursors: &mut [u32],
    ) {
        if range.len() > 1 {
            let mid = range.start + range.len() / 2;
            let first_cluster = mid * self.parts.clusters;
            let split = self.offsets[first_cluster] as usize - base;
            let (left, right) = indices.split_at_mut(split);
            let (left_cursors, right_cursors) =
                cursors.split_at_mut((mid - range.start) * self.parts.clusters);
            if self.parallel {
                rayon::join(
                    || self.fill(range.start..mid, left, base, left_cursors),
                    || self.fill(mid..range.end, right, base + split, right_cursors),
                );
            } else {
                self.fill(range.start..mid, left, base, left_cursors);
                self.fill(mid..range.end, right, base + split, right_cursors);
            }
            return;
        }
        let part = range.start;
        let first_cluster = part * self.parts.clusters;
        match self.active {
            None => {
                for task in self.tasks {
                    for s in &task.buckets[part] {
                        let start = s.first as usize - first_cluster;
                        for cursor in &mut cursors[start..start + s.len as usize] {
                            indices[*cursor as usize - base] = s.light;
                            *cursor += 1;
                        }
                    }
                }
            }
            Some(active) => {
                let (flags, row_width) = (active.flags(), active.dims().x as usize);
                for task in self.tasks {
                    for s in &task.buckets[part] {
                        let first = s.first as usize;
                        if !active.row_has_any(first / row_width) {
                            continue;
                        }
                        let (start, len) = (first - first_cluster, s.len as usize);
                        let on = &flags[first..first + len];
                        for (cursor, &on) in cursors[start..start + len].iter_mut().zip(on) {
                            if on {
                                indices[*cursor as usize - base] = s.light;
                                *cursor += 1;
                            }
                        }
                    }
                }
            }
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
    /// Counts, scans, fills and sorts the tasks' spans into `out`; returns the pair count, or
    /// `Err(pairs)` without writing when they exceed `budget`.
    pub fn assign(
        &mut self,
        tasks: &[crate::jobs::TaskOutput],
        clusters: usize,
        parallel: bool,
        budget: u64,
        out: &mut crate::LightLists,
    ) -> Result<usize, u64> {
        if self.counters.len() < clusters {
            self.counters.resize_with(clusters, || AtomicU32::new(0));
        }
        let counters = &self.counters[..clusters];
        counters.iter().for_each(|c| c.store(0, Relaxed));
        let count = |task: &crate::jobs::TaskOutput| {
            for s in task.buckets.iter().flatten() {
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
        let total: u64 = counters.iter().map(|c| c.load(Relaxed) as u64).sum();
        if total > budget {
            return Err(total);
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
            for s in task.buckets.iter().flatten() {
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
        Ok(running as usize)
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
