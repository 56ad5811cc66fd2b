//! Tests of the append: exact CSR lists against an independent build, and the span pieces of
//! long rows and tall boxes.

use super::*;
use crate::LightLists;
use crate::active::ActiveClusters;
use glam::UVec3;
use myriad_cluster_math::{ClusterGrid, DepthSlicing};
use rand::{Rng, SeedableRng};

/// Every `(light, cluster)` pair the spans of `bucket` list, in push order (`stride`: the
/// row stride).
fn bucket_pairs(bucket: &Bucket, stride: u32) -> Vec<(u32, u32)> {
    let mut pairs = Vec::new();
    for s in &bucket.spans {
        assert!((1..=SPAN_MAX).contains(&s.len()) && (1..=SPAN_MAX).contains(&s.rows()));
        for first in s.row_starts(stride) {
            pairs.extend((first..first + s.len()).map(|c| (s.light, c)));
        }
    }
    pairs
}

/// The lists `tasks` describe, built the obvious way: each cluster's lights in task order,
/// then span order, only active clusters under `flags`.
fn reference(
    tasks: &[CachePadded<TaskOutput>],
    parts: usize,
    stride: u32,
    clusters: usize,
    flags: Option<&[bool]>,
) -> LightLists {
    let mut lists = vec![Vec::new(); clusters];
    for task in tasks {
        for bucket in &task.buckets[..parts] {
            for (light, c) in bucket_pairs(bucket, stride) {
                if flags.is_none_or(|f| f[c as usize]) {
                    lists[c as usize].push(light);
                }
            }
        }
    }
    let mut out = LightLists::default();
    for list in lists {
        out.offsets.push(out.indices.len() as u32);
        out.counts.push(list.len() as u32);
        out.indices.extend(list);
    }
    out
}

/// A 5 × 3 × 7 frame's tiles across, rows and slices.
const DIMS: (u32, u32, u32) = (5, 3, 7);

/// Three tasks of ten lights each, every light a random box of clusters pushed slice by
/// slice into the bucket of its part (`slices_per_part` slices to a part) as the tasks do:
/// whole boxes with [`Bucket::push_rows`] unmasked, row by row with [`Bucket::push`] under
/// `mask`. One extra bucket past the frame's parts holds a stale span, as a reused task's
/// may.
fn random_tasks(
    seed: u64,
    slices_per_part: u32,
    mask: Option<&ActiveView<'_>>,
) -> Vec<CachePadded<TaskOutput>> {
    let (w, h, z) = DIMS;
    let parts = z.div_ceil(slices_per_part) as usize;
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let mut tasks = Vec::new();
    for t in 0..3u32 {
        let mut task = CachePadded::new(TaskOutput::default());
        task.buckets.resize_with(parts + 1, CachePadded::default);
        task.buckets[parts].push(999, 0, 1, None);
        for light in 10 * t..10 * t + 10 {
            let corner = |rng: &mut rand_pcg::Pcg64, n: u32| {
                let (a, b) = (rng.random_range(0..n), rng.random_range(0..n));
                (a.min(b), a.max(b))
            };
            let ((i0, i1), (j0, j1), (k0, k1)) = (
                corner(&mut rng, w),
                corner(&mut rng, h),
                corner(&mut rng, z),
            );
            for k in k0..=k1 {
                let bucket = &mut task.buckets[(k / slices_per_part) as usize];
                let (first, len, rows) = (i0 + w * (j0 + h * k), i1 - i0 + 1, j1 - j0 + 1);
                match mask {
                    None if rng.random() => bucket.push_rows(light, first, len, rows, w),
                    _ => {
                        for r in 0..rows {
                            bucket.push(light, first + r * w, len, mask);
                        }
                    }
                }
            }
        }
        tasks.push(task);
    }
    tasks
}

/// `build_lists` and the atomic counters give exactly the obvious lists (offsets, counts
/// and indices, each list in task order) for random boxes: one part or several, the last
/// one short (7 slices in parts of 2, or one part of 8 slices as a serial frame plans it),
/// serial and split over pools of 1, 4 and 8 threads, with and without a mask, into lists
/// that start out holding another frame's garbage; and the atomic counters take a budget
/// of exactly the frame's pairs but refuse one less. The public tests compare the
/// strategies, thread counts and masks with each other and the lists with an oracle that
/// tolerates extra pairs, never against an independent exact build from known spans.
#[test]
fn both_strategies_build_exactly_the_listed_pairs() {
    let (w, h, z) = DIMS;
    let clusters = (w * h * z) as usize;
    let grid = ClusterGrid::new(UVec3::new(w, h, z), DepthSlicing::Linear, 1.0, 2.0);
    let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
    let mut active = ActiveClusters::new(&grid);
    for c in 0..clusters as u32 {
        if rng.random_bool(0.6) {
            active.mark(c);
        }
    }
    let mut before = Vec::new();
    let view = active.view(&mut before);
    for threads in [1, 4, 8] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        for slices_per_part in [1, 2, 8] {
            let parts = Parts {
                count: z.div_ceil(slices_per_part) as usize,
                clusters: (slices_per_part * w * h) as usize,
                slice_shift: slices_per_part.trailing_zeros(),
                row_stride: w,
            };
            for masked in [false, true] {
                let mask = masked.then_some(&view);
                let tasks = random_tasks(
                    threads as u64 + 10 * slices_per_part as u64,
                    slices_per_part,
                    mask,
                );
                let want = reference(&tasks, parts.count, w, clusters, mask.map(|m| m.flags));
                let helpers = threads - 1;
                for fan_out in [FanOut::Serial, FanOut::Pool, FanOut::WithCaller { helpers }] {
                    let what = format!(
                        "{threads} threads, {slices_per_part} slices a part, masked {masked}, {fan_out:?}"
                    );
                    let mut bases = vec![5; 3];
                    let total = part_bases(&tasks, parts, &mut bases);
                    assert_eq!(total as usize, want.indices.len(), "{what}");
                    assert_eq!(bases.len(), parts.count + 1, "{what}");
                    let mut out = LightLists {
                        offsets: vec![77; 3 * clusters],
                        counts: vec![77; 2],
                        indices: vec![77; 2 * want.indices.len() + 3],
                    };
                    let mut build =
                        || build_lists(&tasks, parts, fan_out, mask, &bases, clusters, &mut out);
                    // With the caller: from this thread, outside the pool, as `Assigner` does.
                    if fan_out == FanOut::Pool {
                        pool.install(build);
                    } else {
                        build();
                    }
                    assert_eq!(out.offsets, want.offsets, "{what}");
                    assert_eq!(out.counts, want.counts, "{what}");
                    assert_eq!(out.indices, want.indices, "{what}");
                    let mut atomic = AtomicCounters::default();
                    let mut out = LightLists::default();
                    let assign = |atomic: &mut AtomicCounters, budget, out: &mut LightLists| {
                        pool.install(|| {
                            atomic.assign(
                                &tasks,
                                parts.count,
                                w,
                                clusters,
                                mask,
                                fan_out.parallel(),
                                budget,
                                out,
                            )
                        })
                    };
                    assert_eq!(
                        assign(&mut atomic, total - 1, &mut out),
                        Err(total),
                        "{what}"
                    );
                    assert_eq!(
                        assign(&mut atomic, total, &mut out),
                        Ok(total as usize),
                        "{what}"
                    );
                    assert_eq!(out.offsets, want.offsets, "{what}");
                    assert_eq!(out.counts, want.counts, "{what}");
                    assert_eq!(out.indices, want.indices, "{what}");
                }
            }
        }
    }
}

/// Rows longer than [`SPAN_MAX`] clusters, and boxes of more rows than it, go in pieces of
/// at most `SPAN_MAX` that list exactly the clusters pushed (unmasked: every one, and the
/// bucket's pair count adds them up; masked: only active clusters count), and a masked row
/// or piece without an active cluster is dropped, as [`Bucket::push`] promises. The public
/// tests see the pieces only through whole frames on 70 000-wide or -high grids, whose
/// lists cannot show a dropped piece kept: the append skips its inactive clusters, so
/// keeping it costs time, not correctness. This checks the bucket itself.
#[test]
fn long_rows_and_tall_boxes_go_in_pieces_of_whole_clusters() {
    let max = SPAN_MAX;
    // (first, len, rows, stride): a long row, a tall box, two long rows, one row more than
    // a span holds, a row and a box of exactly as many.
    let pushes = [
        (3, 2 * max + 7, 1, 0),
        (1, 2, 2 * max + 5, 3),
        (2, max + 2, 2, 2 * max),
        (0, 1, max + 1, 1),
        (5, max, 1, 0),
        (6, 3, max, 4),
    ];
    for (first, len, rows, stride) in pushes {
        let what = format!("{len} clusters × {rows} rows from {first}, stride {stride}");
        let mut want = Vec::new();
        for r in 0..rows {
            let start = first + r * stride;
            want.extend((start..start + len).map(|c| (9, c)));
        }
        let mut bucket = Bucket::default();
        bucket.push_rows(9, first, len, rows, stride);
        assert_eq!(bucket.pairs, want.len() as u64, "{what}");
        let mut got = bucket_pairs(&bucket, stride);
        assert_eq!(got.len(), want.len(), "{what}");
        got.sort_unstable();
        want.sort_unstable();
        assert_eq!(got, want, "{what}");
        if rows == 1 {
            let mut row = Bucket::default();
            row.push(9, first, len, None);
            assert_eq!(row.pairs, len as u64, "{what}");
            assert_eq!(row.spans, bucket.spans, "{what}");
        }
    }
    // Masked: a row of 2·SPAN_MAX + 7 clusters whose first piece has one active cluster
    // (its last), the second none and the third two.
    let (first, len) = (3, 2 * max + 7);
    let clusters = first + len + 1;
    let grid = ClusterGrid::new(UVec3::new(clusters, 1, 1), DepthSlicing::Linear, 1.0, 2.0);
    let mut active = ActiveClusters::new(&grid);
    for c in [
        2,
        first + max - 1,
        first + 2 * max,
        first + len - 1,
        first + len,
    ] {
        active.mark(c);
    }
    let mut before = Vec::new();
    let view = active.view(&mut before);
    let mut bucket = Bucket::default();
    bucket.push(4, first, len, Some(&view));
    assert_eq!(bucket.pairs, 3);
    let pieces: Vec<(u32, u32, u32)> = bucket
        .spans
        .iter()
        .map(|s| (s.first, s.len(), s.rows()))
        .collect();
    assert_eq!(pieces, [(first, max, 1), (first + 2 * max, 7, 1)]);
    assert!(bucket.spans.iter().all(|s| s.light == 4));
    // A short row without an active cluster leaves the bucket as it was.
    let mut row = Bucket::default();
    row.push(4, first + max, 5, Some(&view));
    assert_eq!((row.spans.len(), row.pairs), (0, 0));
}

/// The atomic counters' lists come out in ascending light order whatever order the fill
/// visits the lights in (mutation audit: `sort_lists`, and its split over the pool, went
/// untested: the tests' fills already ran in light order, so a sort that did nothing or sorted
/// the wrong ranges passed). One task pushes the lights in descending order over 1280
/// clusters, so the parallel sort splits twice and sorts ranges that start past pair 0.
#[test]
fn atomic_counters_sort_every_list_whatever_the_fill_order() {
    let clusters = 1280usize;
    let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
    let mut task = CachePadded::new(TaskOutput::default());
    task.buckets.resize_with(1, CachePadded::default);
    let mut lists = vec![Vec::new(); clusters];
    for light in (0..200u32).rev() {
        let len = rng.random_range(1..120u32);
        let first = rng.random_range(0..clusters as u32 - len);
        task.buckets[0].push(light, first, len, None);
        for c in first..first + len {
            lists[c as usize].push(light);
        }
    }
    let mut want = LightLists::default();
    for mut list in lists {
        list.sort_unstable();
        want.offsets.push(want.indices.len() as u32);
        want.counts.push(list.len() as u32);
        want.indices.extend(list);
    }
    let tasks = vec![task];
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .unwrap();
    for parallel in [false, true] {
        let mut atomic = AtomicCounters::default();
        let mut out = LightLists::default();
        let pairs = pool
            .install(|| atomic.assign(&tasks, 1, 1, clusters, None, parallel, u64::MAX, &mut out));
        assert_eq!(pairs, Ok(want.indices.len()), "parallel {parallel}");
        assert_eq!(out.offsets, want.offsets, "parallel {parallel}");
        assert_eq!(out.counts, want.counts, "parallel {parallel}");
        assert_eq!(out.indices, want.indices, "parallel {parallel}");
    }
}

/// The pieces a caller outside the pool and its helpers take ([`Pieces`]): runs of consecutive
/// parts covering every part once, each ending at the first part where its work reaches the
/// grain (the last one at the frame's end), each with exactly its parts' clusters and pairs;
/// with a grain of 0 (a frame of fewer clusters and pairs than four a thread) one part a piece
/// (mutation audit: `Pieces::next` went untested — lists do not change with how the parts are
/// grouped — so a search from the piece's own first part, which at grain 0 ends every piece
/// where it starts and never reaches the end of the frame, passed, as did a comparison that
/// cut every piece after one part or made the whole frame one piece for the caller alone).
#[test]
fn pieces_are_runs_of_parts_of_a_grain_of_work_with_their_arrays() {
    // Five parts of four clusters, the last one short (two): 18 clusters; the parts' pairs
    // 10, 0, 3, 30 and 1. The work before part `p` (pairs before it + 4p) is
    // 0, 14, 18, 25, 59 and 64 at the end.
    let parts = Parts {
        count: 5,
        clusters: 4,
        slice_shift: 0,
        row_stride: 4,
    };
    let bases = [0u64, 10, 10, 13, 43, 44];
    let (clusters, pairs) = (18u32, 44u32);
    let whole: Vec<std::ops::Range<usize>> = std::iter::once(0..5).collect();
    for (grain, want) in [
        (0, vec![0..1, 1..2, 2..3, 3..4, 4..5]),
        (14, vec![0..1, 1..4, 4..5]),
        (15, vec![0..2, 2..4, 4..5]),
        (59, vec![0..4, 4..5]),
        (1000, whole),
    ] {
        let job = PartJob {
            tasks: &[],
            parts,
            bases: &bases,
            parallel: false,
            grain,
            active: None,
        };
        // Each array holds its own positions, so a piece shows which slice of it it got.
        let mut counts: Vec<u32> = (0..clusters).collect();
        let mut offsets: Vec<u32> = (100..100 + clusters).collect();
        let mut indices: Vec<u32> = (0..pairs).collect();
        let pieces = Pieces {
            job: &job,
            next: 0,
            rest: Some(Chunk {
                counts: &mut counts,
                offsets: &mut offsets,
                indices: &mut indices,
            }),
        };
        // One more than the parts: a piece past the frame's end, or an endless run of empty
        // ones, shows up here instead of hanging the test.
        let got: Vec<_> = pieces.take(parts.count + 1).collect();
        let ranges: Vec<_> = got.iter().map(|(range, _)| range.clone()).collect();
        assert_eq!(ranges, want, "grain {grain}");
        for (range, chunk) in &got {
            let first = (range.start * parts.clusters) as u32;
            let last = ((range.end * parts.clusters) as u32).min(clusters);
            let (lo, hi) = (bases[range.start] as u32, bases[range.end] as u32);
            let what = format!("grain {grain}, parts {range:?}");
            assert_eq!(chunk.counts.to_vec(), Vec::from_iter(first..last), "{what}");
            let offsets = Vec::from_iter(100 + first..100 + last);
            assert_eq!(chunk.offsets.to_vec(), offsets, "{what}");
            assert_eq!(chunk.indices.to_vec(), Vec::from_iter(lo..hi), "{what}");
        }
    }
}
