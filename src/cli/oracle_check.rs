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
        let mut sorted: Vec<ViewLight> = (0..lights.len())
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
        sorted.par_sort_unstable_by(|a, b| (-a.centre.z).total_cmp(&-b.centre.z));
        Self {
            depths: sorted.iter().map(|l| -l.centre.z).collect(),
            max_radius: sorted.iter().map(|l| l.radius).fold(0.0, f64::max),
            lights: sorted,
        }
    }

    /// The input indices of every light the oracle says touches `cell`, ascending.
    fn touching(&self, cell: &Cell, out: &mut Vec<u32>) {
        out.clear();
        // The cell is where four walls through the eye and two depth planes hold it; a ball whose
        // centre lies farther than its radius outside any one of them misses the cell. Outward
        // unit normals of the walls (left, right, bottom, top): inside ⇔ `n·p ≤ 0`.
        let walls = [
            DVec3::new(-1.0, 0.0, -cell.x_slopes[0]).normalize(),
            DVec3::new(1.0, 0.0, cell.x_slopes[1]).normalize(),
            DVec3::new(0.0, -1.0, -cell.y_slopes[0]).normalize(),
            DVec3::new(0.0, 1.0, cell.y_slopes[1]).normalize(),
        ];
        // Slack far above the oracle's own tolerance bands (1e-12 of the local scale for spots,
        // 64 ulps for balls) and the rounding here, so these filters only drop lights the oracle
        // rejects too.
        let slack = |scale: f64| 1e-6 * (1.0 + scale);
        let [near, far] = cell.depths;
        // Depth window: the centre's depth is within the radius of the cell's depth range.
        let window = self.max_radius + slack(far + self.max_radius);
        let lo = self.depths.partition_point(|&d| d < near - window);
        let hi = self.depths.partition_point(|&d| d <= far + window);
        for light in &self.lights[lo..hi] {
            let c = light.centre;
            let reach = light.radius + slack(c.abs().element_sum() + light.radius);
            let depth = -c.z;
            if depth < near - reach || depth > far + reach || walls.iter().any(|n| n.dot(c) > reach)
            {
                continue;
            }
            if light.volume.intersects_cell(cell) {
                out.push(light.index);
            }
        }
        out.sort_unstable();
    }
}

/// Every cluster's exact list from the independent oracle (ascending column indices): the
/// reference `bench` and `report` measure misses and false positives against.
///
/// Errs when the lists hold more pairs than u32 offsets can address.
pub(crate) fn independent_lists(
    lights: &Lights,
    camera: &Camera,
    grid: &ClusterGrid,
) -> anyhow::Result<LightLists> {
    independent_lists_up_to(lights, camera, grid, u32::MAX as u64, CLUSTERS_PER_CHUNK)
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
    max_pairs: u64,
    clusters_per_chunk: u32,
) -> anyhow::Result<LightLists> {
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
             its {clusters} clusters hold {pairs}), more than CSR lists with u32 offsets hold; use \
             a coarser grid or fewer lights",
            grid.dims().x,
            grid.dims().y,
            grid.dims().z,
            chunk_end,
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
        let independent = independent_lists(&scene.lights, &scene.camera, &scene.grid).unwrap();
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
        let lists = independent_lists(&scene.lights, &scene.camera, &scene.grid).unwrap();
        let pairs = lists.pair_count() as u64;
        assert!(pairs > 5_000, "{pairs}");
        let build = |max_pairs, chunk| {
            independent_lists_up_to(&scene.lights, &scene.camera, &scene.grid, max_pairs, chunk)
        };
        // Chunks of 1000 clusters: the limit is checked part-way, and a chunk ends mid-slice.
        assert!(scene.grid.cluster_count() > 3000, "{:?}", scene.grid.dims());
        assert_eq!(build(pairs, 1000).unwrap(), lists);
        assert_eq!(build(pairs, 1).unwrap(), lists);
        let error = build(pairs - 1, 1000).unwrap_err().to_string();
        assert!(
            error.contains(&format!("more than {} pairs", pairs - 1))
                && error.contains("coarser grid"),
            "{error}"
        );
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
