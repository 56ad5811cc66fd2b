//! The oracle check of light lists, two ways, shared by `myriad check` and `myriad stress`:
//!
//! * **through the `exact` method** ([`check_all`]): its lists for every cluster, compared pair
//!   by pair. Fast (it tests only each light's candidate clusters), but it finds those candidates
//!   with the same cull and plane-search phases as the fast methods (only more padded);
//! * **independently** ([`OracleLights`], [`check_clusters`]): each checked cluster's cell
//!   against every light in its depth window, with the f64 oracle itself
//!   ([`LightVolume::intersects_cell`] on [`Cell::of_cluster`], the lights read by
//!   [`OracleView::light`] as the `exact` method and the assignment tests' brute force read
//!   them), after a test against the cell's four walls that only drops lights the oracle rejects
//!   too. It shares no code with the assignment but the oracle, so a bug in the shared phases
//!   cannot hide from it; it is slower (a cluster scans its whole depth window).

use super::pair_budget::PairBudget;
use myriad::assignment::{Assigner, LightLists, Method};
use myriad::cluster_math::glam::{DVec3, Vec3};
use myriad::cluster_math::oracle::{Cell, LightVolume, OracleView};
use myriad::cluster_math::{Camera, ClusterGrid};
use myriad::evaluate::compare;
use myriad::scene::Lights;
use rand::SeedableRng;
use rayon::prelude::*;
use serde::Serialize;

/// A light the oracle puts in a cluster but the list lacks.
#[derive(Serialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Miss {
    pub cluster: u32,
    /// (i, j, k) of the cluster.
    pub tile: [u32; 3],
    pub light: u32,
}

/// The oracle check's outcome.
#[derive(Serialize, Debug, Clone, PartialEq)]
pub(crate) struct CheckReport {
    /// "full" (every cluster, exact lists), "independent" (every cluster, independently of the
    /// assignment) or "sampled" (some clusters, independently).
    pub mode: &'static str,
    pub clusters_checked: u64,
    pub clusters_total: u64,
    pub exact_pairs: u64,
    pub reported_pairs: u64,
    pub misses: u64,
    pub false_positives: u64,
    /// The miss in the lowest cluster (lowest light first), if any.
    pub first_miss: Option<Miss>,
}

/// Every cluster: the `exact` method's lists against the reported ones.
pub(crate) fn check_all(
    lights: &Lights,
    camera: &Camera,
    grid: &ClusterGrid,
    lists: &LightLists,
) -> CheckReport {
    let mut exact = LightLists::new();
    Assigner::new().assign(
        Method::Exact,
        &myriad::light_input(lights),
        camera,
        grid,
        &mut exact,
    );
    let cmp = compare(lists, &exact);
    let first_miss = (cmp.misses > 0)
        .then(|| {
            (0..exact.cluster_count()).find_map(|c| {
                let got = lists.lights_of(c);
                exact
                    .lights_of(c)
                    .iter()
                    .find(|l| !got.contains(l))
                    .map(|&light| miss(grid, c as u32, light))
            })
        })
        .flatten();
    CheckReport {
        mode: "full",
        clusters_checked: exact.cluster_count() as u64,
        clusters_total: grid.cluster_count() as u64,
        exact_pairs: cmp.exact_pairs,
        reported_pairs: cmp.reported_pairs,
        misses: cmp.misses,
        false_positives: cmp.false_positives,
        first_miss,
    }
}

pub(crate) fn miss(grid: &ClusterGrid, cluster: u32, light: u32) -> Miss {
    let t = grid.cluster_coords(cluster);
    Miss {
        cluster,
        tile: [t.x, t.y, t.z],
        light,
    }
}

/// `k` distinct cluster ids of `0..count` drawn from `seed`, ascending (all of them when `k`
/// is at least `count`).
pub(crate) fn sample_clusters(count: usize, k: usize, seed: u64) -> Vec<u32> {
    if k >= count {
        return (0..count as u32).collect();
    }
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed ^ 0x5354_5245_5353); // "STRESS"
    let mut picked: Vec<u32> = rand::seq::index::sample(&mut rng, count, k)
        .into_iter()
        .map(|c| c as u32)
        .collect();
    picked.sort_unstable();
    picked
}

/// One valid light in f64 view space.
#[derive(Clone, Copy, Debug)]
struct ViewLight {
    volume: LightVolume,
    /// Centre and radius of the volume's bounding ball, for the cheap filters.
    centre: DVec3,
    radius: f64,
    /// Index into the input columns.
    index: u32,
}

/// The lights as the oracle sees them ([`OracleView::light`], as the `exact` method reads them),
/// sorted by depth, so one cluster's candidates are a window of the array. Invalid lights are
/// left out, since no method may assign them.
pub(crate) struct OracleLights {
    lights: Vec<ViewLight>,
    /// `-centre.z` of each light, ascending.
    depths: Vec<f64>,
    max_radius: f64,
}

impl OracleLights {
    pub(crate) fn new(lights: &Lights, camera: &Camera) -> Self {
        let view = OracleView::new(camera);
        let spots_present = lights.has_spots();
        let valid: Vec<ViewLight> = (0..lights.len())
            .into_par_iter()
            .filter_map(|l| {
                let position = Vec3::new(lights.x[l], lights.y[l], lights.z[l]);
                let spot = spots_present.then(|| {
                    let direction = Vec3::new(
                        lights.spot_dir_x[l],
                        lights.spot_dir_y[l],
                        lights.spot_dir_z[l],
                    );
                    (direction, lights.spot_angle[l])
                });
                let volume = view.light(position, lights.radius[l], spot)?;
                let (centre, radius) = volume.bounding_ball();
                Some(ViewLight {
                    volume,
                    centre,
                    radius,
                    index: l as u32,
                })
            })
            .collect();
        Self::from_view_lights(valid)
    }

    /// `lights` sorted by depth, with their depths and largest radius (the tests build
    /// [`ViewLight`]s in f64 directly, to place them exactly).
    fn from_view_lights(mut lights: Vec<ViewLight>) -> Self {
        lights.par_sort_unstable_by(|a, b| (-a.centre.z).total_cmp(&-b.centre.z));
        Self {
            depths: lights.iter().map(|l| -l.centre.z).collect(),
            max_radius: lights.iter().map(|l| l.radius).fold(0.0, f64::max),
            lights,
        }
    }

    /// The input indices of every light the oracle says touches `cell`, ascending.
    fn touching(&self, cell: &Cell, out: &mut Vec<u32>) {
        out.clear();
        out.extend(
            self.candidates(cell)
                .filter(|light| light.volume.intersects_cell(cell))
                .map(|light| light.index),
        );
        out.sort_unstable();
    }

    /// The lights that pass the cheap filters for `cell`, in depth order: every light the oracle
    /// says touches it, and some it does not.
    fn candidates<'a>(&'a self, cell: &Cell) -> impl Iterator<Item = &'a ViewLight> + 'a {
        // The cell is where four walls through the eye and two depth planes hold it; a ball whose
        // centre lies farther than its radius outside any one of them misses the cell. Outward
        // unit normals of the walls (left, right, bottom, top): inside ⇔ `n·p ≤ 0`.
        let walls = [
            DVec3::new(-1.0, 0.0, -cell.x_slopes[0]).normalize(),
            DVec3::new(1.0, 0.0, cell.x_slopes[1]).normalize(),
            DVec3::new(0.0, -1.0, -cell.y_slopes[0]).normalize(),
            DVec3::new(0.0, 1.0, cell.y_slopes[1]).normalize(),
        ];
        // Slack far above the oracle's own tolerance bands and the rounding here, so these
        // filters only drop lights the oracle rejects too. The oracle accepts a spot whose apex
        // lies up to 64 ulps of a scale beyond its range from the cell, and rounds a ball's
        // distance to a few ulps of one; that scale takes in the cell's corners out to the
        // light's depth plus twice its range, and a corner lies `spread` times its depth from the
        // eye, `spread` passing 1e8 as the field of view nears 180°. So the slack grows with those
        // corners as well as with the light. (Scaled by the light alone it fell short: at a field
        // of view of π less one f32 ulp on a 1920×200 target, in the cell of x slopes
        // [−1.3e8, 0] and depths [1, 3.16], the oracle accepts a spot of range 1e-15 whose apex
        // is 3.8e-6 outside the wall of slope 0 at depth 2.08, a band of 64 ulps of its 2.7e8
        // corner, and the light's slack of 3.1e-6 dropped it; another 5.7e-6 beyond the far
        // plane fell out of the depth window.)
        let slack = |scale: f64| 1e-6 * (1.0 + scale);
        let [near, far] = cell.depths;
        let spread = (1.0
            + cell.x_slopes[0].abs().max(cell.x_slopes[1].abs()).powi(2)
            + cell.y_slopes[0].abs().max(cell.y_slopes[1].abs()).powi(2))
        .sqrt();
        // Depth window: the centre's depth is within the radius of the cell's depth range.
        let window = self.max_radius + slack(spread * far + self.max_radius);
        let lo = self.depths.partition_point(|&d| d < near - window);
        let hi = self.depths.partition_point(|&d| d <= far + window);
        self.lights[lo..hi].iter().filter(move |light| {
            let c = light.centre;
            let depth = -c.z;
            let corners = spread * far.min(depth + 2.0 * light.radius).max(0.0);
            let reach = light.radius + slack(c.abs().element_sum() + light.radius + corners);
            !(depth < near - reach || depth > far + reach || walls.iter().any(|n| n.dot(c) > reach))
        })
    }
}

/// Every cluster's exact list from the independent oracle (ascending column indices): the
/// reference `bench` and `report` measure misses and false positives against.
///
/// Errs when the lists hold more pairs than `budget` (never more than u32 offsets address).
pub(crate) fn independent_lists(
    lights: &Lights,
    camera: &Camera,
    grid: &ClusterGrid,
    budget: &PairBudget,
) -> anyhow::Result<LightLists> {
    independent_lists_up_to(lights, camera, grid, budget, CLUSTERS_PER_CHUNK)
}

/// Clusters whose lists are found in parallel before they are appended to the CSR arrays.
const CLUSTERS_PER_CHUNK: u32 = 4096;

/// [`independent_lists`] with the pair limit and the chunk size as parameters (the tests use
/// small ones).
///
/// Built a chunk of clusters at a time, the chunk's lists appended to the CSR arrays with the
/// running total checked before each append: the memory held is the output plus one chunk, and a
/// frame past `max_pairs` is refused once the total crosses it — before it has used up the
/// machine's memory (16 GiB of indices at the u32 limit; lists for every cluster first, then
/// flattened, took twice the output and ran out of memory before the check).
fn independent_lists_up_to(
    lights: &Lights,
    camera: &Camera,
    grid: &ClusterGrid,
    budget: &PairBudget,
    clusters_per_chunk: u32,
) -> anyhow::Result<LightLists> {
    let max_pairs = budget.pairs.min(u64::from(u32::MAX));
    let oracle = OracleLights::new(lights, camera);
    let clusters = grid.cluster_count() as u32;
    let mut lists = LightLists::new();
    let mut chunk_start = 0;
    while chunk_start < clusters {
        let chunk_end = clusters.min(chunk_start.saturating_add(clusters_per_chunk.max(1)));
        let chunk: Vec<Vec<u32>> = (chunk_start..chunk_end)
            .into_par_iter()
            .map(|c| {
                let t = grid.cluster_coords(c);
                let mut exact = Vec::new();
                oracle.touching(&Cell::of_cluster(camera, grid, t.x, t.y, t.z), &mut exact);
                exact
            })
            .collect();
        let pairs = lists.indices.len() as u64 + chunk.iter().map(|l| l.len() as u64).sum::<u64>();
        anyhow::ensure!(
            pairs <= max_pairs,
            "the oracle finds more than {max_pairs} pairs on the {}x{}x{} grid (the first {} of \
             its {clusters} clusters hold {pairs}), past the pair budget of {}; use a coarser grid \
             or fewer lights",
            grid.dims().x,
            grid.dims().y,
            grid.dims().z,
            chunk_end,
            budget.describe(),
        );
        for list in chunk {
            lists.offsets.push(lists.indices.len() as u32);
            lists.counts.push(list.len() as u32);
            lists.indices.extend(list);
        }
        chunk_start = chunk_end;
    }
    Ok(lists)
}

/// Checks the reported lists of `clusters` against the oracle, light by light.
pub(crate) fn check_clusters(
    oracle: &OracleLights,
    camera: &Camera,
    grid: &ClusterGrid,
    lists: &LightLists,
    clusters: &[u32],
) -> CheckReport {
    #[derive(Default)]
    struct Tally {
        exact: u64,
        reported: u64,
        misses: u64,
        first_miss: Option<(u32, u32)>,
    }
    let tally = clusters
        .par_iter()
        .map_init(Vec::new, |exact, &c| {
            let t = grid.cluster_coords(c);
            let cell = Cell::of_cluster(camera, grid, t.x, t.y, t.z);
            oracle.touching(&cell, exact);
            let mut got = lists.lights_of(c as usize).to_vec();
            got.sort_unstable();
            got.dedup();
            let missing: Vec<u32> = exact
                .iter()
                .copied()
                .filter(|l| got.binary_search(l).is_err())
                .collect();
            Tally {
                exact: exact.len() as u64,
                reported: got.len() as u64,
                misses: missing.len() as u64,
                first_miss: missing.first().map(|&l| (c, l)),
            }
        })
        .reduce(Tally::default, |a, b| Tally {
            exact: a.exact + b.exact,
            reported: a.reported + b.reported,
            misses: a.misses + b.misses,
            first_miss: match (a.first_miss, b.first_miss) {
                (Some(x), Some(y)) => Some(x.min(y)),
                (x, y) => x.or(y),
            },
        });
    let every_cluster = clusters.len() == grid.cluster_count();
    CheckReport {
        mode: if every_cluster {
            "independent"
        } else {
            "sampled"
        },
        clusters_checked: clusters.len() as u64,
        clusters_total: grid.cluster_count() as u64,
        exact_pairs: tally.exact,
        reported_pairs: tally.reported,
        misses: tally.misses,
        false_positives: tally.reported - (tally.exact - tally.misses),
        first_miss: tally.first_miss.map(|(c, l)| miss(grid, c, l)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::pair_budget::COMPARE_BYTES_PER_PAIR;
    use myriad::cluster_math::oracle::{SpotVolume, distance_to_cell};
    use myriad::render::RenderScene;

    /// A small default scene (no GPU needed) and its refined lists.
    fn scene_and_lists(lights: usize) -> (RenderScene, LightLists) {
        let scene = RenderScene::default_scene(lights, 64, 36).unwrap();
        let mut lists = LightLists::new();
        Assigner::new().assign(
            Method::Refined,
            &myriad::light_input(&scene.lights),
            &scene.camera,
            &scene.grid,
            &mut lists,
        );
        (scene, lists)
    }

    /// `lists` without `light` in cluster `cluster`.
    fn without(lists: &LightLists, cluster: usize, light: u32) -> LightLists {
        let mut out = LightLists::new();
        for c in 0..lists.cluster_count() {
            out.offsets.push(out.indices.len() as u32);
            let kept: Vec<u32> = lists
                .lights_of(c)
                .iter()
                .copied()
                .filter(|&l| c != cluster || l != light)
                .collect();
            out.counts.push(kept.len() as u32);
            out.indices.extend(kept);
        }
        out
    }

    #[test]
    fn sampled_oracle_over_every_cluster_equals_the_exact_method() {
        let (scene, lists) = scene_and_lists(3000);
        let oracle = OracleLights::new(&scene.lights, &scene.camera);
        let every = sample_clusters(scene.grid.cluster_count(), usize::MAX, 1);
        let sampled = check_clusters(&oracle, &scene.camera, &scene.grid, &lists, &every);
        let full = check_all(&scene.lights, &scene.camera, &scene.grid, &lists);
        assert!(full.exact_pairs > 10_000, "{full:?}");
        assert_eq!(sampled.misses, 0);
        assert_eq!(
            (
                sampled.exact_pairs,
                sampled.reported_pairs,
                sampled.false_positives
            ),
            (full.exact_pairs, full.reported_pairs, full.false_positives)
        );
    }

    #[test]
    fn sampled_check_finds_a_light_removed_from_a_list() {
        let (scene, lists) = scene_and_lists(3000);
        let oracle = OracleLights::new(&scene.lights, &scene.camera);
        // A cluster and a light the oracle says touch it.
        let mut exact = Vec::new();
        let (cluster, light) = (0..scene.grid.cluster_count() as u32)
            .rev()
            .find_map(|c| {
                let t = scene.grid.cluster_coords(c);
                let cell = Cell::of_cluster(&scene.camera, &scene.grid, t.x, t.y, t.z);
                oracle.touching(&cell, &mut exact);
                exact.get(exact.len() / 2).map(|&l| (c, l))
            })
            .expect("some cluster has lights");
        let broken = without(&lists, cluster as usize, light);
        assert_eq!(broken.pair_count() + 1, lists.pair_count());
        // Sampled with the cluster among others: exactly that miss.
        let clusters = [0, cluster / 2, cluster];
        let ok = check_clusters(&oracle, &scene.camera, &scene.grid, &lists, &clusters);
        assert_eq!((ok.misses, ok.first_miss), (0, None));
        let bad = check_clusters(&oracle, &scene.camera, &scene.grid, &broken, &clusters);
        assert_eq!(bad.misses, 1);
        assert_eq!(bad.first_miss, Some(miss(&scene.grid, cluster, light)));
        // And the full check names the same pair.
        let full = check_all(&scene.lights, &scene.camera, &scene.grid, &broken);
        assert_eq!(full.misses, 1);
        assert_eq!(full.first_miss, Some(miss(&scene.grid, cluster, light)));
    }

    /// With several misses the tallies stay apart (a removed true pair is a miss, never a false
    /// positive, and leaves the exact pair count alone), and the miss named is the one in the
    /// lowest cluster, lowest light first — by the sampled check (whose parallel tally meets the
    /// clusters in any order) and by the full one.
    #[test]
    fn several_misses_name_the_lowest_cluster_and_keep_false_positives_apart() {
        let (scene, lists) = scene_and_lists(3000);
        let oracle = OracleLights::new(&scene.lights, &scene.camera);
        let clusters = scene.grid.cluster_count() as u32;
        // The lowest and the highest cluster with two lights or more the oracle says touch it.
        let mut exact = Vec::new();
        let touched: Vec<(u32, Vec<u32>)> = (0..clusters)
            .filter_map(|c| {
                let t = scene.grid.cluster_coords(c);
                let cell = Cell::of_cluster(&scene.camera, &scene.grid, t.x, t.y, t.z);
                oracle.touching(&cell, &mut exact);
                (exact.len() >= 2).then(|| (c, exact.clone()))
            })
            .collect();
        let (low, low_lights) = touched.first().cloned().expect("a cluster with two lights");
        let (high, high_lights) = touched.last().cloned().unwrap();
        assert!(low < high, "{low} {high}");
        // Two lights out of the high cluster, one (its highest) out of the low one.
        let low_light = *low_lights.last().unwrap();
        let mut broken = without(&lists, high as usize, high_lights[1]);
        broken = without(&broken, high as usize, high_lights[0]);
        broken = without(&broken, low as usize, low_light);
        assert_eq!(broken.pair_count() + 3, lists.pair_count());
        let every: Vec<u32> = (0..clusters).collect();
        let ok = check_clusters(&oracle, &scene.camera, &scene.grid, &lists, &every);
        let bad = check_clusters(&oracle, &scene.camera, &scene.grid, &broken, &every);
        assert!(ok.false_positives > 0 && ok.misses == 0, "{ok:?}");
        assert_eq!(bad.misses, 3, "{bad:?}");
        assert_eq!(
            (bad.exact_pairs, bad.reported_pairs + 3, bad.false_positives),
            (ok.exact_pairs, ok.reported_pairs, ok.false_positives)
        );
        assert_eq!(bad.first_miss, Some(miss(&scene.grid, low, low_light)));
        // The high cluster sampled with others that miss nothing: its lower light.
        let mut sample: Vec<u32> = [0, high / 2, high - 1]
            .into_iter()
            .filter(|&c| c != low)
            .collect();
        sample.push(high);
        let some = check_clusters(&oracle, &scene.camera, &scene.grid, &broken, &sample);
        assert_eq!(
            some.first_miss,
            Some(miss(&scene.grid, high, high_lights[0]))
        );
        assert_eq!((some.misses, some.mode), (2, "sampled"));
        let full = check_all(&scene.lights, &scene.camera, &scene.grid, &broken);
        let full_ok = check_all(&scene.lights, &scene.camera, &scene.grid, &lists);
        assert_eq!(full.misses, 3);
        assert_eq!(full.false_positives, full_ok.false_positives);
        assert_eq!(full.first_miss, Some(miss(&scene.grid, low, low_light)));
    }

    /// Each seed draws its own sample: the first 64 seeds give 64 different ones (a seed mix that
    /// dropped or forced bits would give two seeds the same clusters).
    #[test]
    fn different_seeds_draw_different_samples() {
        let samples: std::collections::HashSet<Vec<u32>> = (0..64)
            .map(|seed| sample_clusters(4608, 20, seed))
            .collect();
        assert_eq!(samples.len(), 64);
    }

    #[test]
    fn independent_lists_equal_the_exact_methods() {
        let (scene, _) = scene_and_lists(2000);
        let budget = PairBudget::new(None, COMPARE_BYTES_PER_PAIR);
        let independent =
            independent_lists(&scene.lights, &scene.camera, &scene.grid, &budget).unwrap();
        let mut exact = LightLists::new();
        Assigner::new().assign(
            Method::Exact,
            &myriad::light_input(&scene.lights),
            &scene.camera,
            &scene.grid,
            &mut exact,
        );
        assert!(exact.pair_count() > 5_000, "{}", exact.pair_count());
        assert_eq!(independent, exact);
    }

    #[test]
    fn independent_lists_past_the_pair_limit_are_refused() {
        let (scene, _) = scene_and_lists(2000);
        let lists = independent_lists(
            &scene.lights,
            &scene.camera,
            &scene.grid,
            &PairBudget::new(None, COMPARE_BYTES_PER_PAIR),
        )
        .unwrap();
        let pairs = lists.pair_count() as u64;
        assert!(pairs > 5_000, "{pairs}");
        let build = |max_pairs, chunk| {
            let budget = PairBudget::new(Some(max_pairs), COMPARE_BYTES_PER_PAIR);
            independent_lists_up_to(&scene.lights, &scene.camera, &scene.grid, &budget, chunk)
        };
        // Chunks of 1000 clusters: the limit is checked part-way, and a chunk ends mid-slice.
        assert!(scene.grid.cluster_count() > 3000, "{:?}", scene.grid.dims());
        assert_eq!(build(pairs, 1000).unwrap(), lists);
        assert_eq!(build(pairs, 1).unwrap(), lists);
        let error = build(pairs - 1, 1000).unwrap_err().to_string();
        assert!(
            error.contains(&format!("more than {} pairs", pairs - 1))
                && error.contains(&format!("budget of {} pairs (--pair-budget)", pairs - 1))
                && error.contains("coarser grid"),
            "{error}"
        );
    }

    /// A light built in f64, as [`OracleLights::new`] would read it.
    fn view_light(volume: LightVolume, index: u32) -> ViewLight {
        let (centre, radius) = volume.bounding_ball();
        ViewLight {
            volume,
            centre,
            radius,
            index,
        }
    }

    /// The largest `t` in `[lo, hi)` that `accepts` while the next f64 above it does not, for
    /// `accepts(lo)` and not `accepts(hi)`, `0 ≤ lo < hi`: bisection on the bits, which order
    /// non-negative f64s as their values.
    fn last_accepted(lo: f64, hi: f64, accepts: impl Fn(f64) -> bool) -> f64 {
        let (mut lo, mut hi) = (lo.to_bits(), hi.to_bits());
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if accepts(f64::from_bits(mid)) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        f64::from_bits(lo)
    }

    /// Cells of real grids, a list per `(camera, grid)`: narrow, usual and wide fields of view;
    /// slices about 0.05, 1, 1e3 and 1e5 deep and out to 1.5e7; corner, edge and inner tiles. And
    /// a field of view of π less one f32 ulp, whose tiles' slopes reach 1e8 to 5e10.
    fn boundary_cells() -> Vec<Vec<Cell>> {
        use myriad::cluster_math::glam::UVec3;
        use myriad::cluster_math::{DepthSlicing, OuterSlices};
        let camera = |fov, width, height| {
            Camera::new(
                Vec3::ZERO,
                Vec3::NEG_Z,
                Vec3::Y,
                fov,
                width,
                height,
                0.1,
                100.0,
            )
        };
        let cameras = [
            camera(2.0, 800, 800),
            camera(60.0, 1920, 1080),
            camera(150.0, 2560, 1080),
        ];
        // The grids' own slices, also where they lie outside the camera's range (closed outer
        // slices: open, the first would reach back to the camera's near plane).
        let closed = |g: ClusterGrid| g.with_outer_slices(OuterSlices::Closed);
        let grids = [
            closed(ClusterGrid::new(
                UVec3::new(16, 9, 16),
                DepthSlicing::Log,
                0.05,
                50.0,
            )),
            closed(ClusterGrid::new(
                UVec3::new(7, 5, 10),
                DepthSlicing::Log,
                1.0,
                1e5,
            )),
            closed(ClusterGrid::new(
                UVec3::new(6, 3, 40),
                DepthSlicing::Log,
                0.5,
                1.5e7,
            )),
        ];
        let mut sets = Vec::new();
        for camera in &cameras {
            for grid in &grids {
                let d = grid.dims();
                let (x, y, z) = (d.x - 1, d.y - 1, d.z - 1);
                let clusters = [
                    (0, 0, 0),
                    (x, y, z),
                    (x / 2, y / 2, z / 2),
                    (x / 2, y, 0),
                    (0, y / 2, z),
                ];
                sets.push(
                    clusters
                        .map(|(i, j, k)| Cell::of_cluster(camera, grid, i, j, k))
                        .to_vec(),
                );
            }
        }
        let grid = closed(ClusterGrid::new(
            UVec3::new(2, 1, 4),
            DepthSlicing::Log,
            1.0,
            100.0,
        ));
        for (width, height) in [(1920, 200), (4096, 1)] {
            let camera = Camera {
                fov_y: f32::from_bits(std::f32::consts::PI.to_bits() - 1),
                ..camera(60.0, width, height)
            };
            let clusters = [(0, 0, 0), (1, 0, 0), (0, 0, 3), (1, 0, 3)];
            sets.push(
                clusters
                    .map(|(i, j, k)| Cell::of_cluster(&camera, &grid, i, j, k))
                    .to_vec(),
            );
        }
        sets
    }

    /// Radii of the placed lights, in units of their cell's near depth: tiny, small, comparable
    /// and large.
    const RADII: [f64; 4] = [1e-15, 1e-4, 0.5, 40.0];

    /// Lights placed around one cell, each with the index of its radius in [`RADII`].
    struct Placed {
        /// `(radius, light the oracle accepts, the same light one f64 farther out, which it
        /// rejects)`.
        boundary: Vec<(usize, ViewLight, ViewLight)>,
        /// `(radius, light)`: more than twice its radius outside one of the six faces.
        outside: Vec<(usize, ViewLight)>,
    }

    /// Balls and spots (a narrow one aimed at the cell, a wide one tilted off the aim; both
    /// reach the cell with their cap) of each radius of [`RADII`], moved out from points on the
    /// cell's six faces, three edges and two corners along the outward normal to the last f64
    /// offset the oracle accepts; and the same more than twice their radius out of each face.
    fn place(cell: &Cell, index: &mut u32) -> Placed {
        let point = |u: f64, v: f64, w: f64| {
            let d = cell.depths[0] + (cell.depths[1] - cell.depths[0]) * w;
            let sx = cell.x_slopes[0] + (cell.x_slopes[1] - cell.x_slopes[0]) * u;
            let sy = cell.y_slopes[0] + (cell.y_slopes[1] - cell.y_slopes[0]) * v;
            DVec3::new(sx * d, sy * d, -d)
        };
        // Outward unit normals: left, right, bottom, top, near, far.
        let normals = [
            -DVec3::new(1.0, 0.0, cell.x_slopes[0]).normalize(),
            DVec3::new(1.0, 0.0, cell.x_slopes[1]).normalize(),
            -DVec3::new(0.0, 1.0, cell.y_slopes[0]).normalize(),
            DVec3::new(0.0, 1.0, cell.y_slopes[1]).normalize(),
            DVec3::Z,
            DVec3::NEG_Z,
        ];
        let out = |faces: &[usize]| faces.iter().map(|&f| normals[f]).sum::<DVec3>().normalize();
        // (point, outward direction, whether it is a face's normal).
        let sites = [
            (point(0.0, 0.5, 0.5), out(&[0]), true),
            (point(1.0, 0.5, 0.5), out(&[1]), true),
            (point(0.5, 0.0, 0.5), out(&[2]), true),
            (point(0.5, 1.0, 0.5), out(&[3]), true),
            (point(0.5, 0.5, 0.0), out(&[4]), true),
            (point(0.5, 0.5, 1.0), out(&[5]), true),
            // The depth planes' normals at their edges: the eye's side of a wide cell.
            (point(0.0, 0.5, 0.0), out(&[4]), true),
            (point(1.0, 0.5, 1.0), out(&[5]), true),
            (point(0.0, 0.5, 0.0), out(&[0, 4]), false),
            (point(0.5, 1.0, 1.0), out(&[3, 5]), false),
            (point(1.0, 0.0, 0.5), out(&[1, 2]), false),
            (point(0.0, 0.0, 0.0), out(&[0, 2, 4]), false),
            (point(1.0, 1.0, 1.0), out(&[1, 3, 5]), false),
        ];
        let extent = cell
            .corners()
            .iter()
            .map(|c| c.length())
            .fold(0.0, f64::max);
        let mut placed = Placed {
            boundary: Vec::new(),
            outside: Vec::new(),
        };
        let mut light = |volume| {
            *index += 1;
            view_light(volume, *index)
        };
        for (p, n, face) in sites {
            let tilted = -n * 0.5f64.cos() + n.any_orthonormal_vector() * 0.5f64.sin();
            for (class, radius) in RADII.map(|r| r * cell.depths[0]).into_iter().enumerate() {
                for (angle, aim) in [(None, -n), (Some(0.25), -n), (Some(1.3), tilted)] {
                    let at = |t: f64| {
                        let centre = p + n * t;
                        match angle {
                            None => LightVolume::Ball { centre, radius },
                            Some(angle) => LightVolume::Spot(SpotVolume {
                                apex: centre,
                                direction: aim,
                                range: radius,
                                angle,
                            }),
                        }
                    };
                    let accepts = |t: f64| at(t).intersects_cell(cell);
                    let far_out = 3.0 * radius + 1e-3 * (1.0 + p.length());
                    assert!(
                        accepts(0.0) && !accepts(far_out),
                        "{cell:?} {p} {n} {radius}"
                    );
                    let t = last_accepted(0.0, far_out, accepts);
                    placed
                        .boundary
                        .push((class, light(at(t)), light(at(t.next_up()))));
                    if face {
                        // Past the slack, which grows with the cell's corners.
                        let margin = 1e-4 * (1.0 + extent + radius);
                        placed
                            .outside
                            .push((class, light(at(2.0 * radius + margin))));
                    }
                }
            }
        }
        placed
    }

    /// The prefilter in front of the oracle ([`OracleLights::candidates`]: four walls, two depth
    /// planes and a depth window, each widened by a slack) may only drop lights the oracle
    /// rejects, and its slack is what keeps the lights on the oracle's boundary, where the
    /// rounding of its own dot products and the oracle's tolerance band for spots (64 ulps of a
    /// scale that takes in the cell's corners) decide. So: balls and spots placed to the last f64
    /// the oracle accepts outside cells' faces, edges and corners, of radii 1e-15 to 40 times
    /// the depth, in cells 0.05 to 1.5e7 deep and of fields of view up to π less one f32 ulp
    /// (where the band outgrew a slack scaled by the light alone, and the prefilter dropped
    /// spots the oracle accepts). Each light alone (the depth window then is its own radius), all
    /// of a camera's lights and those of each radius together: every cell lists exactly the
    /// lights the oracle accepts. And the prefilter does its job: no light well outside a face
    /// reaches the oracle.
    #[test]
    fn the_prefilter_keeps_every_light_on_the_oracles_boundary() {
        let mut index = 0;
        let mut out = Vec::new();
        let (mut boundary, mut beyond_ball, mut outside, mut dropped) = (0, 0, 0, 0);
        for cells in boundary_cells() {
            let placed: Vec<Placed> = cells.iter().map(|cell| place(cell, &mut index)).collect();
            // Each light alone.
            for (cell, placed) in cells.iter().zip(&placed) {
                for &(_, on, beyond) in &placed.boundary {
                    assert!(
                        on.volume.intersects_cell(cell) && !beyond.volume.intersects_cell(cell)
                    );
                    for (light, listed) in [(on, vec![on.index]), (beyond, vec![])] {
                        OracleLights::from_view_lights(vec![light]).touching(cell, &mut out);
                        assert_eq!(out, listed, "{light:?} {cell:?}");
                    }
                    // Where the oracle accepts a light whose bounding ball misses the cell.
                    let (centre, radius) = on.volume.bounding_ball();
                    if distance_to_cell(centre, cell) > radius {
                        beyond_ball += 1;
                    }
                }
                for &(_, light) in &placed.outside {
                    assert!(!light.volume.intersects_cell(cell));
                    let one = OracleLights::from_view_lights(vec![light]);
                    assert_eq!(one.candidates(cell).count(), 0, "{light:?} {cell:?}");
                }
                boundary += placed.boundary.len();
                outside += placed.outside.len();
            }
            // Together: all of them, and those of each radius (a narrower depth window).
            for class in (0..RADII.len()).map(Some).chain([None]) {
                let of_class = |c: usize| class.is_none_or(|k| k == c);
                let lights: Vec<ViewLight> = placed
                    .iter()
                    .flat_map(|p| {
                        let on_boundary = p.boundary.iter().filter(|l| of_class(l.0));
                        let outside = p.outside.iter().filter(|l| of_class(l.0));
                        on_boundary
                            .flat_map(|&(_, on, beyond)| [on, beyond])
                            .chain(outside.map(|&(_, light)| light))
                    })
                    .collect();
                let oracle = OracleLights::from_view_lights(lights.clone());
                for (cell, placed) in cells.iter().zip(&placed) {
                    let mut exact: Vec<u32> = lights
                        .iter()
                        .filter(|l| l.volume.intersects_cell(cell))
                        .map(|l| l.index)
                        .collect();
                    exact.sort_unstable();
                    oracle.touching(cell, &mut out);
                    assert_eq!(out, exact, "{cell:?}");
                    let kept: Vec<u32> = oracle.candidates(cell).map(|l| l.index).collect();
                    for (_, light) in &placed.outside {
                        assert!(!kept.contains(&light.index), "{light:?} {cell:?}");
                    }
                    dropped += lights.len() - kept.len();
                }
            }
        }
        // 53 cells, 156 lights on the boundary and 96 well outside each.
        assert_eq!((boundary, outside), (53 * 156, 53 * 96));
        assert!(beyond_ball > 1000, "{beyond_ball}");
        assert!(dropped > 100_000, "{dropped}");
    }

    /// A spot of `range` (index 1, a narrow cone) aimed along `−n` at `p` on `cell`'s boundary,
    /// `n` pointing out of the cell, its apex moved out past its range to the last f64 offset `t`
    /// the oracle accepts. Asserts that `t` passes `band` (the case is one where the oracle's
    /// tolerance, 64 ulps of a scale, reaches that far) and that the prefilter keeps the light:
    /// the cell lists it.
    fn assert_kept_on_the_band(cell: &Cell, p: DVec3, n: DVec3, range: f64, band: f64) {
        let at = |t: f64| {
            LightVolume::Spot(SpotVolume {
                apex: p + n * (range + t),
                direction: -n,
                range,
                angle: 0.25,
            })
        };
        let accepts = |t: f64| at(t).intersects_cell(cell);
        let extent = cell
            .corners()
            .iter()
            .map(|c| c.length())
            .fold(0.0, f64::max);
        let far_out = 1e-3 * (range + extent);
        assert!(accepts(0.0) && !accepts(far_out), "{cell:?} {p} {n}");
        let t = last_accepted(0.0, far_out, accepts);
        assert!(t > band, "{t} {cell:?}");
        let light = view_light(at(t), 1);
        let mut out = Vec::new();
        OracleLights::from_view_lights(vec![light]).touching(cell, &mut out);
        assert_eq!(out, [1], "{t} {light:?} {cell:?}");
    }

    /// A field of view of π less one f32 ulp on a 4096×1 target (x slopes to 5.5e10), as in
    /// [`boundary_cells`], and its left tile of a 2×1 grid in one slice over `[near, far]`:
    /// x slopes [−5.5e10, 0], y slopes ±1.3e7.
    fn widest_left_cell(near: f32, far: f32) -> Cell {
        use myriad::cluster_math::DepthSlicing;
        use myriad::cluster_math::glam::UVec3;
        let camera = Camera {
            fov_y: f32::from_bits(std::f32::consts::PI.to_bits() - 1),
            ..Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 4096, 1, 0.1, 100.0)
        };
        let grid = ClusterGrid::new(UVec3::new(2, 1, 1), DepthSlicing::Log, near, far);
        let cell = Cell::of_cluster(&camera, &grid, 0, 0, 0);
        assert!(
            cell.x_slopes[0] < -5e10 && cell.x_slopes[1] == 0.0,
            "{cell:?}"
        );
        cell
    }

    /// A spot of range 1e9 behind the eye, aimed at the centre of a usual cell's near face: the
    /// oracle's band is 64 ulps of the range (1.4e-5), more than the slack's 1e-6 floor, and only
    /// the range in the slack's scale covers it (the centre's coordinates alone are the range
    /// less the cell's depth).
    #[test]
    fn the_prefilter_keeps_a_long_spot_behind_the_eye_on_the_band_of_its_range() {
        let cell = Cell {
            x_slopes: [-1.0, 1.0],
            y_slopes: [-0.5, 0.5],
            depths: [1.0, 2.0],
        };
        assert_kept_on_the_band(&cell, DVec3::NEG_Z, DVec3::Z, 1e9, 1e-5);
    }

    /// A spot just outside the wall of slope 0 of the widest cell, 5e8 deep. The oracle's band
    /// there was 64 ulps of the cell's corners at that depth (3.9e5), which the slack covers
    /// with its `spread` times the depth; since a spot beyond one wall is decided by that wall
    /// in the light's own scale (`spot.rs`, step 5), the band is 64 ulps of the light's distance
    /// (7e-6), and the light is still kept at its last accepted offset.
    #[test]
    fn the_prefilter_keeps_a_spot_beside_a_deep_wide_cell_on_the_band_of_its_corners() {
        let cell = widest_left_cell(1e8, 1e9);
        let p = DVec3::new(0.0, 0.0, -5e8);
        assert_kept_on_the_band(&cell, p, DVec3::X, 1.0, 1e-6);
    }

    /// A spot beyond the far plane of the widest cell, 1e9 deep: the band was 64 ulps of the far
    /// corners (7.8e5), covered by the depth window's slack of `spread` times the far depth; the
    /// far wall now decides it in the light's scale (64 ulps of 1e9: 1.4e-5), and the light is
    /// still kept at its last accepted offset.
    #[test]
    fn the_prefilter_keeps_a_spot_beyond_a_deep_wide_cell_in_its_depth_window() {
        let cell = widest_left_cell(1e8, 1e9);
        let p = DVec3::new(0.0, 0.0, -1e9);
        assert_kept_on_the_band(&cell, p, DVec3::NEG_Z, 1.0, 1e-5);
    }

    /// A spot beyond the far plane of a cell of a field of view of 1e-12 (slopes ±9e-13), 2e9
    /// deep: the oracle's band is 64 ulps of the depth (2.8e-5), which the depth window's slack
    /// covers because `spread` is at least 1 (the slopes alone would leave it the 1e-6 floor).
    #[test]
    fn the_prefilter_keeps_a_spot_beyond_a_deep_narrow_cell_in_its_depth_window() {
        use myriad::cluster_math::DepthSlicing;
        use myriad::cluster_math::glam::UVec3;
        let camera = Camera {
            fov_y: 1e-12,
            ..Camera::new(
                Vec3::ZERO,
                Vec3::NEG_Z,
                Vec3::Y,
                60.0,
                1920,
                1080,
                0.1,
                100.0,
            )
        };
        let grid = ClusterGrid::new(UVec3::new(1, 1, 1), DepthSlicing::Log, 1e9, 2e9);
        let cell = Cell::of_cluster(&camera, &grid, 0, 0, 0);
        let p = DVec3::new(0.0, 0.0, -2e9);
        assert_kept_on_the_band(&cell, p, DVec3::NEG_Z, 1.0, 1e-5);
    }

    /// A spot of range 1e9 behind the eye, aimed at the near face of the widest cell, one slice
    /// from 1 to 2e9 deep. The oracle's band there was 64 ulps of the cell's corners (7.8e5),
    /// which the slack covered with `spread` times the depth the light reaches (its centre's
    /// depth plus twice its range); since the oracle decides a spot beyond one of the cell's walls
    /// by that wall alone, in the light's own scale (`spot.rs`, step 5), the band is 64 ulps of
    /// the apex's distance and the range (2.8e-5), and the light is still kept at its last
    /// accepted offset.
    #[test]
    fn the_prefilter_keeps_a_long_spot_behind_the_eye_of_a_deep_wide_cell_on_the_band() {
        let cell = widest_left_cell(1.0, 2e9);
        assert_kept_on_the_band(&cell, DVec3::NEG_Z, DVec3::Z, 1e9, 1e-5);
    }

    #[test]
    fn samples_are_distinct_seeded_and_ascending() {
        let a = sample_clusters(4608, 2000, 7);
        assert_eq!(a.len(), 2000);
        assert!(a.windows(2).all(|w| w[0] < w[1]));
        assert!(a.iter().all(|&c| c < 4608));
        assert_eq!(a, sample_clusters(4608, 2000, 7));
        assert_ne!(a, sample_clusters(4608, 2000, 8));
        assert_eq!(sample_clusters(10, 50, 1), (0..10).collect::<Vec<_>>());
    }
}
