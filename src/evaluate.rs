//! Accuracy and speed of assignment methods: pair-by-pair comparison with the exact method, and
//! the "time against error" measurement behind `myriad bench`.

use myriad_assignment::{
    AssignStats, Assigner, LightInput, LightLists, Method, OutsideCalls, Parallelism,
};
use myriad_cluster_math::{Camera, ClusterGrid};
use serde::Serialize;
use std::time::Instant;

/// How a reported assignment compares with the exact one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Comparison {
    /// Pairs the oracle says touch.
    pub exact_pairs: u64,
    /// Pairs reported.
    pub reported_pairs: u64,
    /// Exact pairs missing from the report (must be 0).
    pub misses: u64,
    /// Reported pairs the oracle rejects.
    pub false_positives: u64,
    /// `false_positives / exact_pairs` (0 when there are no exact pairs).
    pub false_positive_ratio: f64,
}

/// Compares two sets of CSR lists over the same clusters; each list must be ascending.
///
/// How an engine checks its own frames: assign the same columns, camera and grid once more with
/// [`Method::Exact`] (every candidate cluster decided by the f64 oracle; slow, so in a test or a
/// debug toggle, not every frame) and compare. `misses` must be 0; `false_positive_ratio` is the
/// price of the faster method.
///
/// ```
/// use myriad::assignment::{Assigner, LightInput, LightLists, Method};
/// use myriad::cluster_math::glam::{UVec3, Vec3};
/// use myriad::cluster_math::{Camera, ClusterGrid, DepthSlicing};
///
/// let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 1920, 1080, 0.1, 100.0);
/// let grid = ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, camera.near, camera.far);
/// let (x, y, z) = (vec![0.0, 2.0, -1.5], vec![0.0, 1.0, 0.2], vec![-5.0, -20.0, -0.5]);
/// let radius = vec![1.0, 3.0, 0.75];
/// let lights = LightInput::points(&x, &y, &z, &radius);
///
/// let mut assigner = Assigner::new();
/// let (mut lists, mut exact) = (LightLists::new(), LightLists::new());
/// assigner.assign(Method::Refined, &lights, &camera, &grid, &mut lists);
/// assigner.assign(Method::Exact, &lights, &camera, &grid, &mut exact);
///
/// let check = myriad::evaluate::compare(&lists, &exact);
/// assert_eq!(check.misses, 0);
/// assert_eq!(check.reported_pairs, check.exact_pairs + check.false_positives);
/// // Three lights, one of them straddling the camera's plane 1.6 m away: refined lists 138
/// // pairs where 64 touch.
/// assert_eq!((check.exact_pairs, check.false_positives), (64, 74));
/// ```
pub fn compare(reported: &LightLists, exact: &LightLists) -> Comparison {
    assert_eq!(
        reported.cluster_count(),
        exact.cluster_count(),
        "different cluster counts"
    );
    let mut cmp = Comparison::default();
    for c in 0..exact.cluster_count() {
        let (mut a, mut b) = (reported.lights_of(c), exact.lights_of(c));
        cmp.exact_pairs += b.len() as u64;
        cmp.reported_pairs += a.len() as u64;
        let mut reported_sorted;
        if !a.windows(2).all(|w| w[0] < w[1]) {
            reported_sorted = a.to_vec();
            reported_sorted.sort_unstable();
            reported_sorted.dedup();
            a = &reported_sorted;
        }
        let mut hits = 0u64;
        while let (Some(&x), Some(&y)) = (a.first(), b.first()) {
            match x.cmp(&y) {
                std::cmp::Ordering::Less => a = &a[1..],
                std::cmp::Ordering::Greater => b = &b[1..],
                std::cmp::Ordering::Equal => {
                    hits += 1;
                    a = &a[1..];
                    b = &b[1..];
                }
            }
        }
        cmp.misses += exact.lights_of(c).len() as u64 - hits;
    }
    cmp.false_positives = cmp.reported_pairs - (cmp.exact_pairs - cmp.misses);
    cmp.false_positive_ratio = if cmp.exact_pairs > 0 {
        cmp.false_positives as f64 / cmp.exact_pairs as f64
    } else {
        0.0
    };
    cmp
}

/// One method's row of the time-against-error table.
#[derive(Clone, Debug, Serialize)]
pub struct MethodResult {
    /// Method name.
    pub method: String,
    /// Median wall time of one assignment, microseconds.
    pub median_us: f64,
    /// Fastest run, microseconds.
    pub min_us: f64,
    /// Timed runs.
    pub runs: usize,
    /// Cluster–light pairs written.
    pub pairs: u64,
    /// False-positive pairs / exact pairs.
    pub false_positive_ratio: f64,
    /// Exact pairs missing (must be 0).
    pub misses: u64,
    /// Bytes of the CSR output (offsets + counts + indices).
    pub bytes: u64,
    /// Output bytes per second at the median time, GB/s.
    pub effective_gb_s: f64,
    /// Lights visible (not culled or rejected).
    pub visible_lights: u32,
    /// Timed calls whose tasks ran on the pool ([`AssignStats::parallel`]); the rest ran one
    /// after another on the calling thread (a serial frame, or a small frame after idle).
    pub pooled_runs: usize,
}

/// How the calling thread spends the time between two timed calls.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Idle {
    /// Calls back to back.
    #[default]
    None,
    /// Sleeps: the whole process idles, as an engine blocked on vsync.
    Sleep(std::time::Duration),
    /// Spins: the calling thread stays busy, as an engine's frame thread doing other work, while
    /// the pool's other workers idle.
    Busy(std::time::Duration),
}

impl Idle {
    fn wait(self) {
        match self {
            Idle::None => {}
            Idle::Sleep(time) => std::thread::sleep(time),
            Idle::Busy(time) => {
                let start = Instant::now();
                while start.elapsed() < time {
                    std::hint::spin_loop();
                }
            }
        }
    }
}

/// How [`measure`] times a method.
#[derive(Clone, Copy, Debug)]
pub struct Timing {
    /// Timed calls (the median is reported).
    pub runs: usize,
    /// What the calling thread does before each timed call (untimed).
    pub idle: Idle,
    /// When the assigner runs a split frame on the pool.
    pub parallelism: Parallelism,
    /// How a frame called from outside any pool uses the pool (only matters when [`measure`] is
    /// called from outside one).
    pub outside_calls: OutsideCalls,
}

impl Timing {
    /// `runs` calls back to back, the assigner's default pacing.
    pub fn back_to_back(runs: usize) -> Self {
        Self {
            runs,
            idle: Idle::None,
            parallelism: Parallelism::default(),
            outside_calls: OutsideCalls::default(),
        }
    }
}

/// Times `method` (median of `timing.runs` after one warm-up) and compares its output with
/// `exact`. With a non-zero [`Idle`] the calling thread waits before each timed call, as an
/// engine's frames are apart: the pool's other workers go to sleep in between.
///
/// Fails when the lists need more than `max_pairs` pairs on `grid` (past it the assigner builds
/// them on a coarser grid, which the exact lists cannot be compared with; at most what u32
/// offsets hold, 2³² − 1, whatever `max_pairs` says), or when `exact` is not for `grid`.
pub fn measure(
    method: Method,
    lights: &LightInput<'_>,
    camera: &Camera,
    grid: &ClusterGrid,
    exact: &LightLists,
    timing: Timing,
    max_pairs: u64,
) -> anyhow::Result<MethodResult> {
    let Timing {
        runs,
        idle,
        parallelism,
        outside_calls,
    } = timing;
    let mut assigner = Assigner::new()
        .with_parallelism(parallelism)
        .with_outside_calls(outside_calls)
        .with_pair_budget(max_pairs);
    let mut lists = LightLists::new();
    let mut stats: AssignStats = assigner.assign(method, lights, camera, grid, &mut lists);
    anyhow::ensure!(
        stats.coarsened == 0,
        "{method} needs more than {} pairs on the {}x{}x{} grid (it fell back to a coarser one): \
         too many to compare; use a coarser grid or fewer lights",
        max_pairs.min(u64::from(u32::MAX)),
        grid.dims().x,
        grid.dims().y,
        grid.dims().z
    );
    anyhow::ensure!(
        exact.cluster_count() == grid.cluster_count(),
        "the exact lists have {} clusters, the grid {}",
        exact.cluster_count(),
        grid.cluster_count()
    );
    let mut times = Vec::with_capacity(runs);
    let mut pooled_runs = 0;
    for _ in 0..runs.max(1) {
        idle.wait();
        let start = Instant::now();
        stats = assigner.assign(method, lights, camera, grid, &mut lists);
        times.push(start.elapsed().as_secs_f64() * 1e6);
        pooled_runs += usize::from(stats.parallel);
    }
    let median_us = median(&mut times);
    let cmp = compare(&lists, exact);
    let bytes = lists.byte_size() as u64;
    Ok(MethodResult {
        method: method.name().to_string(),
        median_us,
        min_us: times[0],
        runs: times.len(),
        pairs: stats.pairs,
        false_positive_ratio: cmp.false_positive_ratio,
        misses: cmp.misses,
        bytes,
        effective_gb_s: bytes as f64 / (median_us * 1e-6) / 1e9,
        visible_lights: stats.visible(),
        pooled_runs,
    })
}

/// The median of a non-empty list, reordering it: the middle value, or the mean of the middle
/// two of an even count (the upper one alone made `--runs 2`'s median its slower run).
pub fn median(values: &mut [f64]) -> f64 {
    assert!(!values.is_empty(), "the median of no values");
    values.sort_by(f64::total_cmp);
    let mid = values.len() / 2;
    if values.len() % 2 == 1 {
        values[mid]
    } else {
        0.5 * (values[mid - 1] + values[mid])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The middle value of an odd count, the mean of the middle two of an even one, in any
    /// input order.
    #[test]
    fn medians_of_odd_and_even_counts() {
        assert_eq!(median(&mut [3.0]), 3.0);
        assert_eq!(median(&mut [9.0, 1.0, 5.0]), 5.0);
        assert_eq!(median(&mut [10.0, 2.0]), 6.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 100.0]), 3.5);
    }

    fn lists(per_cluster: &[&[u32]]) -> LightLists {
        let mut l = LightLists::default();
        for c in per_cluster {
            l.offsets.push(l.indices.len() as u32);
            l.counts.push(c.len() as u32);
            l.indices.extend_from_slice(c);
        }
        l
    }

    #[test]
    fn counts_misses_and_false_positives() {
        let exact = lists(&[&[1, 2, 3], &[], &[7]]);
        let reported = lists(&[&[1, 3, 4], &[5], &[7]]);
        let c = compare(&reported, &exact);
        assert_eq!(c.exact_pairs, 4);
        assert_eq!(c.reported_pairs, 5);
        assert_eq!(c.misses, 1);
        assert_eq!(c.false_positives, 2);
        assert!((c.false_positive_ratio - 0.5).abs() < 1e-12);
        let same = compare(&exact, &exact);
        assert_eq!((same.misses, same.false_positives), (0, 0));
    }

    #[test]
    fn unsorted_reported_lists_are_compared_as_sets() {
        // A dump may list a cluster's lights in any order: that is no miss. A light listed twice
        // is one hit and one false positive (a renderer would shade it twice).
        let exact = lists(&[&[1, 2, 3], &[4]]);
        let reported = lists(&[&[3, 2, 1], &[4, 4]]);
        let c = compare(&reported, &exact);
        assert_eq!(
            (c.exact_pairs, c.reported_pairs, c.misses, c.false_positives),
            (4, 5, 0, 1)
        );
        // No exact pairs: the ratio is 0, not a division by zero.
        let c = compare(&lists(&[&[5]]), &lists(&[&[]]));
        assert_eq!((c.false_positives, c.false_positive_ratio), (1, 0.0));
    }

    /// Idle time is waited through, asleep or spinning: at least the time asked for.
    #[test]
    fn idling_waits_at_least_its_time() {
        let time = std::time::Duration::from_millis(30);
        for idle in [Idle::Sleep(time), Idle::Busy(time)] {
            let start = Instant::now();
            idle.wait();
            let waited = start.elapsed();
            assert!(waited >= time, "{idle:?} returned after {waited:?}");
        }
    }

    /// `measure` reports microseconds: the three slowest of five timed runs fit in the wall time
    /// of the whole call, and a frame of a thousand lights takes more than 0.1 µs.
    #[test]
    fn measured_times_are_microseconds() {
        let scene = myriad_scene::Preset::Paper.generate(1000, 1);
        let input = crate::light_input(&scene.lights);
        let mut exact = LightLists::new();
        Assigner::new().assign(
            Method::Exact,
            &input,
            &scene.camera,
            &scene.grid,
            &mut exact,
        );
        let start = Instant::now();
        let r = measure(
            Method::Binary,
            &input,
            &scene.camera,
            &scene.grid,
            &exact,
            Timing::back_to_back(5),
            u64::MAX,
        )
        .unwrap();
        let wall_us = start.elapsed().as_secs_f64() * 1e6;
        assert_eq!((r.runs, r.misses), (5, 0), "{r:?}");
        assert!(r.min_us > 0.1 && r.min_us <= r.median_us, "{r:?}");
        assert!(r.median_us * 3.0 <= wall_us, "{r:?} in {wall_us} µs");
    }

    /// Lists past `max_pairs` are built on a coarser grid, which the exact lists cannot be
    /// compared with: refused, naming the method, the limit and the grid. At the limit they pass.
    #[test]
    fn lists_past_the_pair_limit_are_refused() {
        let scene = myriad_scene::Preset::Paper.generate(1000, 1);
        let input = crate::light_input(&scene.lights);
        let mut exact = LightLists::new();
        let (camera, grid) = (&scene.camera, &scene.grid);
        Assigner::new().assign(Method::Exact, &input, camera, grid, &mut exact);
        let refined_under = |max_pairs| {
            let timing = Timing::back_to_back(1);
            measure(
                Method::Refined,
                &input,
                camera,
                grid,
                &exact,
                timing,
                max_pairs,
            )
        };
        let refined = refined_under(u64::MAX).unwrap().pairs;
        assert_eq!(refined_under(refined).unwrap().pairs, refined);
        let e = refined_under(refined - 1).unwrap_err().to_string();
        let d = grid.dims();
        let want = format!(
            "refined needs more than {} pairs on the {}x{}x{} grid",
            refined - 1,
            d.x,
            d.y,
            d.z
        );
        assert!(e.starts_with(&want), "{e}");
    }
}
