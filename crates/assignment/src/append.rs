//! The lock-free per-cluster append: spans of clusters per light → CSR lists.
//!
//! The clusters are split into *parts*: groups of consecutive depth slices, so each part is a
//! contiguous range of cluster ids and, after the prefix sum, a contiguous range of the output.
//! Every span holds rows of one slice, so it lies inside a single part, and the tasks already
//! bucket their spans by part while emitting them — adding up each bucket's pairs as they go
//! ([`Bucket::push`]). So where every part's lists start in the output is known as soon as the
//! tasks are done (a prefix sum over parts × tasks, [`part_bases`]), and each part is then built
//! whole, in parallel over parts, with no second pass over the frame:
//!
//! 1. **count**: walk the tasks' buckets for the part in task order and count into its own chunk
//!    of `counts` as a difference array (+1 at a span's start, −1 just past its end: O(spans),
//!    not O(pairs));
//! 2. **scan**: one pass over the part's clusters closes the difference array and writes each
//!    list's start into `offsets` (the part's base + a running sum);
//! 3. **fill**: walk the same buckets again, in the same order, writing light indices into *its
//!    own* slice of `indices`, with `offsets` as the per-cluster cursors (relative to the part's
//!    slice, so a pair is a load, a store and an increment), while it is all in cache. Storing a
//!    row first and bumping its cursors in a second, vectorised pass cost 13% more instructions on
//!    `paper` 1000 `binary` (its rows are 2–5 clusters long) and 23% more time serially;
//! 4. **close**: the cursors now hold each list's end, so `counts` is the difference of
//!    neighbouring ends and `offsets` the previous end — a pass without a dependency chain.
//!
//! The scan is a serial chain (two running sums) and stores once per cluster. When it also wrote
//! the counts and separate cursors (three stores per cluster), the append took 21 µs of the
//! `uniform` 250-light frame, whose 27 648 clusters hold only 737 pairs.
//!
//! Nothing is shared between threads while it is written: each part owns disjoint chunks of
//! `counts`, `offsets` and `indices` (plain `&mut` splits — no atomics, no `unsafe`,
//! and no cache line written by two threads, which an earlier per-task fill suffered from: a
//! cluster's list of ~10 entries is one cache line, and all tasks wrote into it). Lists come out
//! in ascending light order, because tasks are contiguous light ranges walked in order: the
//! output is identical for any number of tasks, parts or threads.
//!
//! (It replaced a count over all parts, a prefix sum over all clusters, then a fill over all
//! parts: more passes over the clusters, and two pool regions per frame instead of one.
//! `myriad bench`, serial: `uniform` 250 lights 28 → 19.5 µs, 1000 lights 50 → 42 µs.)

use crate::active::ActiveView;
use crate::fan_out::{self, FanOut};
use crate::jobs::TaskOutput;
use crossbeam::utils::CachePadded;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// A run of `len` clusters from `first`, repeated on `rows` consecutive rows of one slice (each
/// [`Parts::row_stride`] clusters after the last), all touched by `light`: one row of a light's
/// box, or its whole box in one slice.
///
/// Whole boxes travel as one span, not one per row, because the spans are the data that crosses
/// between threads — written by the task of a light range, read by the part of a slice range.
/// `binary` on `paper` 1000 pushes 6,458 rows as 1,448 spans, and with 2 threads its frame took
/// 56–66 µs instead of 71–77 µs (`myriad bench --threads 2`, interleaved builds; `refined`, whose
/// rows are cut one by one, unchanged — it now sends the slices its refinement keeps whole, of
/// three rows or more, as such spans too: see `jobs::emit`). The price is a rows loop per span in the append, paid
/// where boxes are one row tall: `uniform` 100k ran 3.6% more instructions (docs/measured.md).
/// Folding `refined`'s equal neighbouring rows into one span too made it 20% slower. `len` and
/// `rows` are 16 bits each, so a span stays 12 bytes; the rare longer ones are pushed in pieces
/// ([`Bucket::push`], [`Bucket::push_rows`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Span {
    pub light: u32,
    pub first: u32,
    /// Clusters per row, in `1..=SPAN_MAX`.
    len: u16,
    /// Rows, in `1..=SPAN_MAX`.
    rows: u16,
}

/// The longest row and the most rows one span holds.
pub(crate) const SPAN_MAX: u32 = u16::MAX as u32;

impl Span {
    /// `rows` rows of `len` clusters from `first`; both in `1..=SPAN_MAX`.
    #[inline]
    fn new(light: u32, first: u32, len: u32, rows: u32) -> Self {
        debug_assert!((1..=SPAN_MAX).contains(&len) && (1..=SPAN_MAX).contains(&rows));
        Self {
            light,
            first,
            len: len as u16,
            rows: rows as u16,
        }
    }

    /// Clusters per row.
    #[inline]
    pub fn len(&self) -> u32 {
        self.len.into()
    }

    /// Rows.
    #[inline]
    pub fn rows(&self) -> u32 {
        self.rows.into()
    }

    /// The first cluster of each row, `stride` apart.
    #[inline]
    pub fn row_starts(&self, stride: u32) -> impl Iterator<Item = u32> + use<> {
        let (first, rows) = (self.first, self.rows());
        (0..rows).map(move |r| first + r * stride)
    }
}

/// One task's spans in one part, and the pairs they hold.
#[derive(Default)]
pub(crate) struct Bucket {
    pub spans: Vec<Span>,
    /// Pairs of the spans (active clusters only, under a mask).
    pub pairs: u64,
}

impl Bucket {
    /// Empties the bucket, keeping its storage.
    pub fn clear(&mut self) {
        self.spans.clear();
        self.pairs = 0;
    }

    /// Adds the row `first .. first + len` of `light` (`len ≥ 1`). Under a mask only its
    /// active clusters count, and a piece without any is dropped here: no later pass visits it.
    #[inline]
    pub fn push(&mut self, light: u32, first: u32, len: u32, active: Option<&ActiveView<'_>>) {
        debug_assert!(len >= 1, "an empty row of light {light} at cluster {first}");
        if len > SPAN_MAX {
            self.push_long(light, first, len, active);
            return;
        }
        let pairs = match active {
            // `len ≥ 1`, so no test of the pairs: callgrind, instructions a frame, `refined`
            // (a push per refined row) `paper` 1000 1.413 → 1.397 M, `uniform` 100k 33.2 →
            // 32.8 M; `binary` 0.908 → 0.907 M.
            None => len,
            Some(a) => {
                let pairs = a.count(first, len);
                if pairs == 0 {
                    return;
                }
                pairs
            }
        };
        self.pairs += pairs as u64;
        self.spans.push(Span::new(light, first, len, 1));
    }

    /// [`Self::push`] of a row longer than a span holds, in pieces.
    #[cold]
    #[inline(never)]
    fn push_long(&mut self, light: u32, first: u32, len: u32, active: Option<&ActiveView<'_>>) {
        let end = first + len;
        let mut at = first;
        while at < end {
            let piece = (end - at).min(SPAN_MAX);
            let pairs = match active {
                None => piece,
                Some(a) => a.count(at, piece),
            };
            if pairs > 0 {
                self.pairs += pairs as u64;
                self.spans.push(Span::new(light, at, piece, 1));
            }
            at += piece;
        }
    }

    /// Adds `rows` rows of `len` clusters (both ≥ 1), the first starting at cluster `first` and
    /// each next one `stride` further — a light's whole box in one slice, unmasked. `stride`
    /// must be the frame's [`Parts::row_stride`].
    #[inline]
    pub fn push_rows(&mut self, light: u32, first: u32, len: u32, rows: u32, stride: u32) {
        if (len | rows) <= SPAN_MAX {
            self.pairs += rows as u64 * len as u64;
            self.spans.push(Span::new(light, first, len, rows));
            return;
        }
        self.push_rows_long(light, first, len, rows, stride);
    }

    /// [`Self::push_rows`] of rows longer, or more of them, than a span holds, in pieces.
    #[cold]
    #[inline(never)]
    fn push_rows_long(&mut self, light: u32, first: u32, len: u32, rows: u32, stride: u32) {
        if len > SPAN_MAX {
            for r in 0..rows {
                self.push_long(light, first + r * stride, len, None);
            }
            return;
        }
        self.pairs += rows as u64 * len as u64;
        let mut done = 0;
        while done < rows {
            let piece = (rows - done).min(SPAN_MAX);
            self.spans
                .push(Span::new(light, first + done * stride, len, piece));
            done += piece;
        }
    }
}

/// How the clusters are split into parts.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Parts {
    /// Number of parts.
    pub count: usize,
    /// Clusters per part (the last part may have fewer).
    pub clusters: usize,
    /// log₂ of the slices per part: slice `k` lies in part `k >> slice_shift`.
    pub slice_shift: u32,
    /// Clusters from one row of a slice to the next (the grid's tiles across): a [`Span`]'s
    /// rows are this far apart.
    pub row_stride: u32,
}

/// Where each part's lists start in `indices`: `bases[p]` for part `p`, and the total pairs last
/// (`bases` gets `parts + 1` entries). Returns the total, so the caller can check it against its
/// budget before anything is written.
pub(crate) fn part_bases(
    tasks: &[CachePadded<TaskOutput>],
    parts: Parts,
    bases: &mut Vec<u64>,
) -> u64 {
    bases.clear();
    let mut total = 0u64;
    for p in 0..parts.count {
        bases.push(total);
        total += tasks.iter().map(|t| t.buckets[p].pairs).sum::<u64>();
    }
    bases.push(total);
    total
}

/// Builds every part's lists into `out` (sized for `clusters` clusters): count, scan, fill and
/// close, part by part, in parallel over parts unless `fan_out` is serial. `bases` comes from
/// [`part_bases`], whose total must fit u32 offsets.
pub(crate) fn build_lists(
    tasks: &[CachePadded<TaskOutput>],
    parts: Parts,
    fan_out: FanOut,
    active: Option<&ActiveView<'_>>,
    bases: &[u64],
    clusters: usize,
    out: &mut crate::LightLists,
) {
    crate::profiling::profile_span!("append");
    let total = bases[parts.count];
    assert!(
        total <= u32::MAX as u64,
        "{total} pairs do not fit u32 offsets"
    );
    out.resize_for(clusters);
    // Every entry is about to be written: only growth needs filling (`resize` leaves the rest).
    out.indices.resize(total as usize, 0);
    let job = PartJob {
        tasks,
        parts,
        bases,
        parallel: fan_out == FanOut::Pool,
        // About four pieces of work per thread, for the work stealing to even out.
        grain: (total + clusters as u64) / (4 * rayon::current_num_threads() as u64),
        active: active.map(|a| a.flags),
    };
    let chunk = Chunk {
        counts: &mut out.counts,
        offsets: &mut out.offsets,
        indices: &mut out.indices,
    };
    match fan_out {
        FanOut::WithCaller { helpers } => {
            let pieces = Pieces {
                job: &job,
                next: 0,
                rest: Some(chunk),
            };
            fan_out::with_caller(pieces, helpers, |(range, chunk)| {
                job.run_parts(range, chunk)
            });
        }
        FanOut::Pool | FanOut::Serial => job.run(0..parts.count, chunk),
    }
}

/// Runs of consecutive parts of about [`PartJob::grain`] work each, with their arrays: the
/// pieces a caller outside the pool and its helpers take one at a time (`fan_out.rs`), as
/// rayon's workers steal the halves of [`PartJob::run`].
struct Pieces<'j, 'a> {
    job: &'j PartJob<'j>,
    next: usize,
    rest: Option<Chunk<'a>>,
}

impl<'a> Iterator for Pieces<'_, 'a> {
    type Item = (std::ops::Range<usize>, Chunk<'a>);

    fn next(&mut self) -> Option<Self::Item> {
        let job = self.job;
        let (start, count) = (self.next, job.parts.count);
        if start == count {
            return None;
        }
        let end = (start + 1..count)
            .find(|&p| job.work(p) - job.work(start) >= job.grain)
            .unwrap_or(count);
        let rest = self.rest.take()?;
        let clusters = ((end - start) * job.parts.clusters).min(rest.counts.len());
        let pairs = (job.bases[end] - job.bases[start]) as usize;
        let (piece, rest) = rest.split_at(clusters, pairs);
        self.rest = Some(rest);
        self.next = end;
        Some((start..end, piece))
    }

    /// At most one piece per part left.
    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = self.job.parts.count - self.next;
        (left.min(1), Some(left))
    }
}

/// The output arrays of a range of parts.
struct Chunk<'a> {
    counts: &'a mut [u32],
    offsets: &'a mut [u32],
    indices: &'a mut [u32],
}

impl<'a> Chunk<'a> {
    /// Splits after `clusters` clusters and `pairs` pairs.
    fn split_at(self, clusters: usize, pairs: usize) -> (Chunk<'a>, Chunk<'a>) {
        let (c0, c1) = self.counts.split_at_mut(clusters);
        let (o0, o1) = self.offsets.split_at_mut(clusters);
        let (i0, i1) = self.indices.split_at_mut(pairs);
        (
            Chunk {
                counts: c0,
                offsets: o0,
                indices: i0,
            },
            Chunk {
                counts: c1,
                offsets: o1,
                indices: i1,
            },
        )
    }
}

/// Steps 1–4, split recursively over the parts so each gets its own `&mut` slices.
struct PartJob<'a> {
    tasks: &'a [CachePadded<TaskOutput>],
    parts: Parts,
    bases: &'a [u64],
    parallel: bool,
    /// Work below which a range of parts is not split further (see [`PartJob::work`]).
    grain: u64,
    /// The mask's per-cluster flags.
    active: Option<&'a [bool]>,
}

impl PartJob<'_> {
    /// Builds parts `range`, whose arrays are `chunk`.
    fn run(&self, range: std::ops::Range<usize>, chunk: Chunk<'_>) {
        let (start, end) = (range.start, range.end);
        if self.parallel && range.len() > 1 && self.work(end) - self.work(start) > self.grain {
            // Halve the work, not the parts: the pairs crowd into the far slices (`uniform` 1M:
            // 87% of them in the last 8 of 48 slices).
            let half = (self.work(start) + self.work(end)) / 2;
            let mid = (start + 1..end)
                .find(|&p| self.work(p) >= half)
                .unwrap_or(end - 1);
            let clusters = (mid - start) * self.parts.clusters;
            let pairs = (self.bases[mid] - self.bases[start]) as usize;
            let (left, right) = chunk.split_at(clusters, pairs);
            rayon::join(|| self.run(start..mid, left), || self.run(mid..end, right));
            return;
        }
        self.run_parts(range, chunk);
    }

    /// Builds parts `range`, whose arrays are `chunk`, one after another.
    fn run_parts(&self, range: std::ops::Range<usize>, chunk: Chunk<'_>) {
        let mut rest = chunk;
        for part in range {
            let clusters = self.parts.clusters.min(rest.counts.len());
            let pairs = (self.bases[part + 1] - self.bases[part]) as usize;
            let (this, next) = rest.split_at(clusters, pairs);
            self.part(part, this);
            rest = next;
        }
    }

    /// Work before part `p`: its pairs (a scattered store each) plus its clusters (a scan step
    /// each) — a cost model good enough to balance the halves.
    fn work(&self, p: usize) -> u64 {
        self.bases[p] + (p * self.parts.clusters) as u64
    }

    /// One part: count, scan, fill, close.
    fn part(&self, part: usize, chunk: Chunk<'_>) {
        let Chunk {
            counts,
            offsets,
            indices,
        } = chunk;
        let first_cluster = part * self.parts.clusters;
        let buckets = || self.tasks.iter().map(move |t| &t.buckets[part].spans);
        // 1. Count, as a difference array closed by the scan.
        counts.fill(0);
        let len = counts.len();
        let stride = self.parts.row_stride;
        for spans in buckets() {
            for s in spans {
                let run = s.len() as usize;
                let mut start = s.first as usize - first_cluster;
                let mut rows = s.rows();
                // A loop that tests at its end: with a separate path for one-row spans, or a
                // `for` over the rows, `uniform` 100k's append ran 8–19% more instructions.
                loop {
                    counts[start] = counts[start].wrapping_add(1);
                    let end = start + run;
                    if end < len {
                        counts[end] = counts[end].wrapping_sub(1);
                    }
                    rows -= 1;
                    if rows == 0 {
                        break;
                    }
                    start += stride as usize;
                }
            }
        }
        // 2. Scan: each list's start, relative to the part's slice of `indices` (the close adds
        // the part's base back), so the fill indexes with the cursor itself.
        let base = self.bases[part] as u32;
        let mut running = 0u32;
        let mut at = 0u32;
        match self.active {
            None => {
                for (&n, offset) in counts.iter().zip(offsets.iter_mut()) {
                    running = running.wrapping_add(n);
                    *offset = at;
                    at += running;
                }
            }
            Some(flags) => {
                let flags = &flags[first_cluster..first_cluster + len];
                for ((&n, offset), &on) in counts.iter().zip(offsets.iter_mut()).zip(flags) {
                    running = running.wrapping_add(n);
                    *offset = at;
                    at += if on { running } else { 0 };
                }
            }
        }
        assert_eq!(
            at as usize,
            indices.len(),
            "part {part}: the spans hold {at} pairs, their buckets said {}",
            indices.len()
        );
        // 3. Fill, with the offsets as cursors.
        match self.active {
            None => {
                for spans in buckets() {
                    for s in spans {
                        let (light, run) = (s.light, s.len() as usize);
                        let mut start = s.first as usize - first_cluster;
                        let mut rows = s.rows();
                        loop {
                            for cursor in &mut offsets[start..start + run] {
                                indices[*cursor as usize] = light;
                                *cursor += 1;
                            }
                            rows -= 1;
                            if rows == 0 {
                                break;
                            }
                            start += stride as usize;
                        }
                    }
                }
            }
            Some(flags) => {
                for spans in buckets() {
                    for s in spans {
                        let len = s.len() as usize;
                        for first in s.row_starts(stride) {
                            let first = first as usize;
                            let start = first - first_cluster;
                            let on = &flags[first..first + len];
                            for (cursor, &on) in offsets[start..start + len].iter_mut().zip(on) {
                                if on {
                                    indices[*cursor as usize] = s.light;
                                    *cursor += 1;
                                }
                            }
                        }
                    }
                }
            }
        }
        // 4. Close: every cursor is its list's end, and a list starts where the previous ends.
        let mut start = 0;
        for (n, offset) in counts.iter_mut().zip(offsets.iter_mut()) {
            let end = *offset;
            (*n, *offset) = (end - start, base + start);
            start = end;
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
    /// Counts, scans, fills and sorts the spans of the tasks' first `parts` buckets (the later
    /// ones may hold an earlier frame's spans) into `out`, only in `active` clusters when a mask
    /// is given; returns the pair count, or `Err(pairs)` without writing when they exceed
    /// `budget`.
    #[allow(clippy::too_many_arguments)] // One frame's tasks, grid size, mask and output.
    pub fn assign(
        &mut self,
        tasks: &[CachePadded<TaskOutput>],
        parts: usize,
        row_stride: u32,
        clusters: usize,
        active: Option<&ActiveView<'_>>,
        parallel: bool,
        budget: u64,
        out: &mut crate::LightLists,
    ) -> Result<usize, u64> {
        crate::profiling::profile_span!("append (atomic counters)");
        if self.counters.len() < clusters {
            self.counters.resize_with(clusters, || AtomicU32::new(0));
        }
        let counters = &self.counters[..clusters];
        counters.iter().for_each(|c| c.store(0, Relaxed));
        let flags = active.map(|a| a.flags);
        // The clusters of a span that take its light: all of them, or the active ones.
        let clusters_of = move |s: &Span| {
            let len = s.len() as usize;
            s.row_starts(row_stride)
                .flat_map(move |first| first as usize..first as usize + len)
                .filter(move |&c| flags.is_none_or(|f| f[c]))
        };
        let count = |task: &CachePadded<TaskOutput>| {
            for s in frame_spans(task, parts) {
                for c in clusters_of(s) {
                    counters[c].fetch_add(1, Relaxed);
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
        let fill = |task: &CachePadded<TaskOutput>| {
            for s in frame_spans(task, parts) {
                for c in clusters_of(s) {
                    let at = counters[c].fetch_add(1, Relaxed);
                    // SAFETY: `fetch_add` hands every caller a distinct slot of the cluster's
                    // range [offset, offset + count), which lies inside `0..pairs`: the fill
                    // walks the same spans as the count did (`frame_spans`, `clusters_of`), so a
                    // cluster gets exactly `count` of them, starting at its offset; and no count
                    // wrapped, since a cluster lists each light once and there are at most
                    // `u32::MAX` lights (`LightInput::problem`, checked before any frame): the
                    // ranges never overlap.
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

/// The spans of a task's first `parts` buckets: this frame's.
fn frame_spans(task: &TaskOutput, parts: usize) -> impl Iterator<Item = &Span> {
    task.buckets[..parts].iter().flat_map(|b| &b.spans)
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
        // The last list of a half ends where the next half's first starts: `offsets[mid]`.
        let end = if c + 1 < offsets.len() {
            offsets[c + 1] as usize - base
        } else {
            indices.len()
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

#[cfg(test)]
mod tests;
