//! The assignment dump: the JSON file `myriad assign` writes and `myriad check` reads
//! (format in docs/cli.md, "`myriad assign`": `grid`, the plane edges and the CSR lists).
//!
//! The reader is strict where the format's description is silent, by decision: an unknown key is an error (a
//! misspelt `offests` would otherwise leave the lists unchecked behind a default), and counts and
//! indices must be JSON integers (`4.0` is refused: a fractional index has no meaning, and
//! accepting some floats invites `4.5`). Key order is free, as in any JSON object. One key is
//! ours beyond DESIGN.md's format and optional: `scene`, the scene the lists were assigned from
//! ([`SceneStamp`], written by [`AssignmentDump::stamped`], compared by
//! [`AssignmentDump::check_scene`]), so that a dump checked against the wrong scene file is
//! named as such rather than judged. Dumps without it (those of `myriad assign` before it was
//! added, of `myriad assign --bare`, of other tools) are read and checked as before; a reader
//! as strict as this one but older, or one that knows only DESIGN.md's seven keys, refuses a
//! dump that carries it, which is what `--bare` is for.
//!
//! ## Index spaces
//! A dump names lights by their index in the scene file's `lights` array, not by column of the
//! loaded [`Lights`](myriad_scene::Lights): with [`LightPolicy::SkipInvalid`](myriad_scene::LightPolicy)
//! the invalid lights are not loaded, so every later light's column is smaller than its file
//! index. Hence the two counts below: [`AssignmentDump::check_against`] takes the file's light
//! count (loaded + skipped), and lists compared with an assignment of the loaded columns (as
//! [`crate::evaluate::compare`] does) come from [`AssignmentDump::lists_of_columns`], not
//! [`AssignmentDump::lists`] — whose file indices, compared with columns, read as misses.
//!
//! ```
//! use myriad::assignment::{Assigner, LightLists, Method};
//! use myriad::dump::AssignmentDump;
//! use myriad::scene::{LightPolicy, Scene};
//!
//! let text = r#"{
//!   "camera": {"position": [0, 0, 0], "target": [0, 0, -1], "up": [0, 1, 0], "fov_y_deg": 60,
//!              "width": 320, "height": 180, "near": 0.1, "far": 50},
//!   "grid": {"x": 8, "y": 4, "z": 8, "depth": "log"},
//!   "lights": [{"position": [0, 0, -5], "radius": 1},
//!              {"position": [0, 0, -5], "radius": -1},
//!              {"position": [1, 0, -8], "radius": 2}]
//! }"#;
//! let scene = Scene::from_json_str(text, "inline scene", LightPolicy::SkipInvalid)?;
//! assert_eq!((scene.lights.len(), scene.skipped.len()), (2, 1));
//! let mut lists = LightLists::new();
//! let input = myriad::light_input(&scene.lights);
//! Assigner::new().assign(Method::Refined, &input, &scene.camera, &scene.grid, &mut lists);
//!
//! let dump = AssignmentDump::new(&scene.grid, &lists, &scene.lights.source_index);
//! assert!(dump.indices.contains(&2)); // the file's third light, the second column
//! dump.check_against(&scene.grid, scene.lights.len() + scene.skipped.len())?;
//! let back = dump.lists_of_columns(&scene.lights.source_index)?;
//! assert_eq!(back, lists);
//! let mut exact = LightLists::new();
//! Assigner::new().assign(Method::Exact, &input, &scene.camera, &scene.grid, &mut exact);
//! assert_eq!(myriad::evaluate::compare(&back, &exact).misses, 0);
//! # Ok::<(), anyhow::Error>(())
//! ```

use anyhow::{Context, Result, bail, ensure};
use myriad_assignment::LightLists;
use myriad_cluster_math::ClusterGrid;
use myriad_cluster_math::glam::UVec3;
use serde::{Deserialize, Serialize};
use std::path::Path;

mod stamp;

pub use stamp::{SceneStamp, StampCamera};

/// A grid's edges and its CSR light lists; light indices refer to the scene file's `lights` array.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AssignmentDump {
    /// `[X, Y, Z]`.
    pub grid: [u32; 3],
    /// X+1 NDC x edges, left → right.
    pub x_edges: Vec<f32>,
    /// Y+1 NDC y edges, top → bottom.
    pub y_edges: Vec<f32>,
    /// Z+1 view depths, near → far.
    pub z_planes: Vec<f32>,
    /// Per cluster: start in `indices`.
    pub offsets: Vec<u32>,
    /// Per cluster: number of lights.
    pub counts: Vec<u32>,
    /// Light indices into the scene file.
    pub indices: Vec<u32>,
    /// The scene the lists were assigned from ([`Self::stamped`]); absent from a dump of the
    /// bare format, which names no scene.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<SceneStamp>,
}

impl AssignmentDump {
    /// Builds a dump; `source_index[l]` maps the assignment's light `l` to its scene-file index.
    pub fn new(grid: &ClusterGrid, lists: &LightLists, source_index: &[u32]) -> Self {
        let d = grid.dims();
        let mut z_planes = Vec::new();
        grid.fill_slice_edges(&mut z_planes);
        Self {
            grid: [d.x, d.y, d.z],
            x_edges: (0..=d.x).map(|i| grid.x_edge_ndc(i) + 0.0).collect(),
            // `+ 0.0` writes the middle edge as 0, not -0.
            y_edges: (0..=d.y).map(|j| grid.y_edge_ndc(j) + 0.0).collect(),
            z_planes,
            offsets: lists.offsets.clone(),
            counts: lists.counts.clone(),
            indices: lists
                .indices
                .iter()
                .map(|&l| source_index[l as usize])
                .collect(),
            scene: None,
        }
    }

    /// The dump with a record of the scene it was assigned from ([`SceneStamp`]), which
    /// [`Self::check_scene`] compares; unchanged where the camera has a number JSON cannot hold
    /// (an infinite far plane).
    pub fn stamped(mut self, scene: &myriad_scene::Scene) -> Self {
        self.scene = SceneStamp::of(scene);
        self
    }

    /// Checks that the dump was assigned from `scene`, where it records its scene: the light
    /// count, the camera, then the lights' checksum; the error names the first difference. A
    /// dump that records none passes (only [`Self::check_against`]'s grid and indices speak
    /// for it).
    pub fn check_scene(&self, scene: &myriad_scene::Scene) -> Result<()> {
        self.scene.as_ref().map_or(Ok(()), |s| s.check(scene))
    }

    /// Reads and checks a dump file.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = myriad_scene::read_regular_file(path)
            .with_context(|| format!("cannot read dump {}", path.display()))?;
        // A leading UTF-8 byte-order mark (an editor's) is skipped, as scene files' is.
        let bytes = match bytes.strip_prefix(b"\xEF\xBB\xBF") {
            Some(rest) => rest.to_vec(),
            None => bytes,
        };
        let text = String::from_utf8(bytes)
            .with_context(|| format!("{}: not a valid assignment dump", path.display()))?;
        let dump: Self = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a valid assignment dump", path.display()))?;
        dump.validate()
            .with_context(|| format!("{}: inconsistent assignment dump", path.display()))?;
        Ok(dump)
    }

    /// Writes the dump as JSON, replacing `path` only once complete.
    pub fn save(&self, path: &Path) -> Result<()> {
        // One line, ended: a dump printed to a terminal or a pipe ends where the next output starts.
        let mut text = serde_json::to_string(self)?;
        text.push('\n');
        myriad_scene::replace_file(path, text.as_bytes())
            .with_context(|| format!("cannot write dump {}", path.display()))
    }

    /// Structural checks: sizes agree and every list lies inside `indices`.
    pub fn validate(&self) -> Result<()> {
        let [x, y, z] = self.grid;
        ensure!(
            x >= 1 && y >= 1 && z >= 1,
            "grid dimensions must be >= 1, got {:?}",
            self.grid
        );
        let clusters = ClusterGrid::clusters_in(UVec3::new(x, y, z));
        ensure!(
            self.x_edges.len() as u64 == x as u64 + 1,
            "x_edges needs {} values",
            x as u64 + 1
        );
        ensure!(
            self.y_edges.len() as u64 == y as u64 + 1,
            "y_edges needs {} values",
            y as u64 + 1
        );
        ensure!(
            self.z_planes.len() as u64 == z as u64 + 1,
            "z_planes needs {} values",
            z as u64 + 1
        );
        ensure!(
            self.offsets.len() as u128 == clusters,
            "offsets needs {clusters} values"
        );
        ensure!(
            self.counts.len() as u128 == clusters,
            "counts needs {clusters} values"
        );
        for (c, (&o, &n)) in self.offsets.iter().zip(&self.counts).enumerate() {
            if o as u64 + n as u64 > self.indices.len() as u64 {
                bail!(
                    "cluster {c}: offset {o} + count {n} exceeds the {} indices",
                    self.indices.len()
                );
            }
        }
        self.validate_partition()
    }

    /// The lists must partition `indices` (CSR, in any cluster order): no two non-empty lists
    /// share an index slot, and every slot belongs to a list. `myriad assign` writes them so;
    /// aliased lists or stray indices would make the reported pairs mean something else.
    fn validate_partition(&self) -> Result<()> {
        let mut ranges: Vec<(u32, u32, usize)> = (self.offsets.iter().zip(&self.counts))
            .enumerate()
            .filter(|(_, (_, n))| **n > 0)
            .map(|(c, (&o, &n))| (o, n, c))
            .collect();
        ranges.sort_unstable();
        let mut covered = 0u64;
        let mut previous: Option<usize> = None;
        for (o, n, c) in ranges {
            if (o as u64) < covered {
                bail!(
                    "cluster {c}'s list (indices[{o}..{}]) overlaps cluster {}'s",
                    o as u64 + n as u64,
                    previous.expect("an earlier list covers the slot")
                );
            }
            if o as u64 > covered {
                bail!("indices[{covered}..{o}] belong to no cluster's list");
            }
            covered = o as u64 + n as u64;
            previous = Some(c);
        }
        ensure!(
            covered == self.indices.len() as u64,
            "indices[{covered}..{}] belong to no cluster's list",
            self.indices.len()
        );
        Ok(())
    }

    /// Checks that the dump belongs to a scene with `grid` and `lights` lights: the same grid,
    /// the same edges and planes (to [`PLANE_ULPS`] units in the last place: `myriad assign`
    /// writes the grid's own f32 values, which JSON round-trips, but a tool that evaluates
    /// the format's formulas (docs/cli.md) in f64 and rounds lands an ulp or two away, and a dump of another
    /// camera or slicing lands far more), every index a light of the scene, and no light twice in a cluster
    /// (a renderer would shade it twice). The first difference is the error; an inconsistent
    /// dump (see [`Self::validate`]) is one too.
    pub fn check_against(&self, grid: &ClusterGrid, lights: usize) -> Result<()> {
        // `load` validated it; a dump deserialized or built another way may not be.
        self.validate()?;
        let d = grid.dims();
        ensure!(
            self.grid == [d.x, d.y, d.z],
            "grid {:?} does not match the scene's {}x{}x{}",
            self.grid,
            d.x,
            d.y,
            d.z
        );
        let reference = Self::new(grid, &LightLists::new(), &[]);
        for (name, got, want) in [
            ("x_edges", &self.x_edges, &reference.x_edges),
            ("y_edges", &self.y_edges, &reference.y_edges),
            ("z_planes", &self.z_planes, &reference.z_planes),
        ] {
            if let Some(i) = (0..want.len()).find(|&i| !same_plane(got[i], want[i])) {
                bail!(
                    "{name}[{i}] is {}, but the scene's grid has {} (another camera or depth slicing?)",
                    got[i],
                    want[i]
                );
            }
        }
        if let Some(k) = self.indices.iter().position(|&l| l as usize >= lights) {
            bail!(
                "indices[{k}] = {}, but the scene has {lights} lights",
                self.indices[k]
            );
        }
        let mut seen = Vec::new();
        for (c, (&o, &n)) in self.offsets.iter().zip(&self.counts).enumerate() {
            seen.clear();
            seen.extend_from_slice(&self.indices[o as usize..o as usize + n as usize]);
            seen.sort_unstable();
            if let Some(w) = seen.windows(2).find(|w| w[0] == w[1]) {
                bail!("cluster {c} lists light {} more than once", w[0]);
            }
        }
        Ok(())
    }

    /// The lists of the dump with each scene-file index turned into the column of the loaded
    /// lights that holds it (`source_index`: [`myriad_scene::Lights::source_index`], each column's
    /// file index) — the inverse of [`Self::new`]'s mapping, for comparing with an assignment of
    /// those columns. A pair naming a file light that has no column (one skipped when the scene
    /// was loaded: an assignment never lists one) is an error naming it.
    pub fn lists_of_columns(&self, source_index: &[u32]) -> Result<LightLists> {
        // Sized by the columns, not by the dump's indices: an unchecked dump may name light
        // 4 294 967 295, and a table that long is 16 GiB.
        let file_lights = source_index.iter().map(|&i| i as usize + 1).max();
        let mut column_of = vec![u32::MAX; file_lights.unwrap_or(0)];
        for (column, &file_index) in source_index.iter().enumerate() {
            column_of[file_index as usize] = column as u32;
        }
        let mut lists = self.lists();
        for (k, l) in lists.indices.iter_mut().enumerate() {
            let column = column_of.get(*l as usize).copied().unwrap_or(u32::MAX);
            ensure!(
                column != u32::MAX,
                "indices[{k}] names light {l} of the scene file, which has no column among the \
                 loaded lights (skipped when the scene was loaded?)"
            );
            *l = column;
        }
        Ok(lists)
    }

    /// The lists of the dump (indices in scene-file space; see [`Self::lists_of_columns`]).
    pub fn lists(&self) -> LightLists {
        LightLists {
            offsets: self.offsets.clone(),
            counts: self.counts.clone(),
            indices: self.indices.clone(),
        }
    }
}

/// How far, in units in the last place, a dump's edge or plane may be from the grid's own value
/// ([`AssignmentDump::check_against`]).
pub const PLANE_ULPS: u32 = 4;

/// Are `got` and `want` within [`PLANE_ULPS`] of each other? Measured on the ordered integer
/// line of f32 values, so it holds the same at any magnitude, and across zero (an NDC edge of 0
/// computed as −1e-17 is a long way off in ulps: such an edge is written as the grid writes it,
/// and −0 equals 0).
fn same_plane(got: f32, want: f32) -> bool {
    // The f32 values in order as integers: negatives mirrored below the positives.
    let line = |v: f32| {
        let bits = v.to_bits() as i32;
        if bits < 0 { i32::MIN - bits } else { bits }
    };
    got == want
        || (got.is_finite() && want.is_finite() && line(got).abs_diff(line(want)) <= PLANE_ULPS)
}

#[cfg(test)]
mod tests {
    use super::*;
    use myriad_cluster_math::DepthSlicing;
    use myriad_cluster_math::glam::UVec3;

    fn grid() -> ClusterGrid {
        ClusterGrid::new(UVec3::new(4, 3, 2), DepthSlicing::Log, 0.1, 100.0)
    }

    /// A dump of `grid()` with one light in cluster 5.
    fn one_pair() -> AssignmentDump {
        let mut lists = LightLists::new();
        lists.counts = vec![0; 24];
        lists.counts[5] = 1;
        lists.offsets = vec![0; 24];
        lists.offsets[6..].fill(1);
        lists.indices = vec![0];
        AssignmentDump::new(&grid(), &lists, &[0])
    }

    #[test]
    fn a_dump_saved_by_an_editor_with_a_byte_order_mark_loads() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("d.json");
        one_pair().save(&path).unwrap();
        let text = std::fs::read(&path).unwrap();
        std::fs::write(&path, [b"\xEF\xBB\xBF".as_slice(), &text].concat()).unwrap();
        let back = AssignmentDump::load(&path).unwrap();
        assert_eq!(back.indices, one_pair().indices);
        assert_eq!(back.offsets, one_pair().offsets);
    }

    #[test]
    fn the_largest_grid_a_file_can_name_is_an_error_that_counts_right() {
        let mut dump = one_pair();
        dump.grid = [u32::MAX, 1, 1];
        let e = dump.validate().unwrap_err().to_string();
        assert_eq!(e, "x_edges needs 4294967296 values");
        // A product past u64 is not 0 clusters (it wrapped, and empty lists passed).
        let mut dump = one_pair();
        dump.grid = [4_194_304, 2_097_152, 2_097_152];
        dump.x_edges = vec![0.0; 4_194_305];
        dump.y_edges = vec![0.0; 2_097_153];
        dump.z_planes = vec![0.0; 2_097_153];
        (dump.offsets, dump.counts, dump.indices) = (vec![], vec![], vec![]);
        let e = dump.validate().unwrap_err().to_string();
        assert_eq!(e, "offsets needs 18446744073709551616 values");
    }

    #[test]
    fn an_empty_lists_offset_is_free() {
        // Cluster 5 lists lights 0 and 1; cluster 7, empty, has its offset inside that list and
        // cluster 0, empty, at the end of `indices`: a CSR partition all the same, since an
        // empty list owns no slot.
        let mut dump = one_pair();
        dump.counts[5] = 2;
        dump.indices = vec![0, 1];
        dump.offsets[6..].fill(2);
        dump.offsets[7] = 1;
        dump.offsets[0] = 2;
        dump.validate().unwrap();
        dump.check_against(&grid(), 2).unwrap();
        // A non-empty list there is an overlap.
        dump.counts[7] = 1;
        let e = dump.validate().unwrap_err().to_string();
        assert_eq!(e, "cluster 7's list (indices[1..2]) overlaps cluster 5's");
    }

    /// A plane an ulp or a few off (another tool's f64 formula, rounded) is the same plane; one
    /// further off is another grid's, named with both values.
    #[test]
    fn planes_a_few_ulps_off_are_the_grids_and_further_ones_are_not() {
        let step = |v: f32, ulps: i32| f32::from_bits((v.to_bits() as i32 + ulps) as u32);
        for ulps in [-4, -1, 1, 4] {
            let mut dump = one_pair();
            dump.z_planes[2] = step(dump.z_planes[2], ulps);
            dump.x_edges[0] = step(dump.x_edges[0], -ulps);
            dump.check_against(&grid(), 1).unwrap();
        }
        for ulps in [-5, 5, 1000] {
            let mut dump = one_pair();
            let want = dump.z_planes[2];
            dump.z_planes[2] = step(want, ulps);
            let e = dump.check_against(&grid(), 1).unwrap_err().to_string();
            let got = dump.z_planes[2];
            assert_eq!(
                e,
                format!(
                    "z_planes[2] is {got}, but the scene's grid has {want} (another camera or depth slicing?)"
                )
            );
        }
        // Across zero, and the signs of zero.
        assert!(same_plane(0.0, -0.0) && same_plane(f32::from_bits(1), -f32::from_bits(1)));
        assert!(!same_plane(1e-17, 0.0) && !same_plane(f32::NAN, f32::NAN));
    }

    /// File indices become columns; a listed light without a column (skipped on loading) is an
    /// error naming it, not a silent index past the columns.
    #[test]
    fn lists_of_columns_map_file_indices_and_refuse_a_skipped_light() {
        let mut dump = one_pair();
        dump.indices = vec![3];
        // Columns 0 and 1 hold the file's lights 1 and 3 (0 and 2 were skipped).
        let lists = dump.lists_of_columns(&[1, 3]).unwrap();
        assert_eq!(lists.indices, vec![1]);
        assert_eq!(
            (lists.offsets, lists.counts),
            (dump.offsets.clone(), dump.counts.clone())
        );
        let e = dump.lists_of_columns(&[1, 2]).unwrap_err().to_string();
        assert!(
            e.starts_with("indices[0] names light 3 of the scene file"),
            "{e}"
        );
        let e = dump.lists_of_columns(&[]).unwrap_err().to_string();
        assert!(e.contains("light 3"), "{e}");
        // An index no column can have, before any check: an error, not a 16 GiB table.
        dump.indices = vec![u32::MAX];
        let e = dump.lists_of_columns(&[1, 3]).unwrap_err().to_string();
        assert!(e.contains(&format!("light {}", u32::MAX)), "{e}");
    }

    #[test]
    fn checking_an_inconsistent_dump_is_an_error_not_a_panic() {
        one_pair().check_against(&grid(), 1).unwrap();
        let mut short_edges = one_pair();
        short_edges.x_edges.pop();
        let mut list_past_the_end = one_pair();
        list_past_the_end.offsets[5] = 7;
        for (dump, fragment) in [
            (short_edges, "x_edges needs 5 values"),
            (list_past_the_end, "exceeds the 1 indices"),
        ] {
            let e = dump.check_against(&grid(), 1).unwrap_err().to_string();
            assert!(e.contains(fragment), "{e}");
        }
    }

    #[test]
    fn a_slot_between_two_lists_that_no_list_owns_is_an_error() {
        // Cluster 5 lists light 0 at indices[0] and cluster 6 light 1 at indices[2]; indices[1]
        // belongs to neither, though the last list ends where `indices` does.
        let mut dump = one_pair();
        dump.indices = vec![0, 1, 1];
        dump.counts[6] = 1;
        dump.offsets[6] = 2;
        dump.offsets[7..].fill(3);
        let e = dump.validate().unwrap_err().to_string();
        assert_eq!(e, "indices[1..2] belong to no cluster's list");
        // Without the stray slot the lists are a partition.
        dump.indices.remove(1);
        dump.offsets[6] = 1;
        dump.offsets[7..].fill(2);
        dump.check_against(&grid(), 2).unwrap();
    }

    #[test]
    fn an_unknown_key_or_a_whole_number_written_as_a_float_is_not_a_dump() {
        let text = serde_json::to_string(&one_pair()).unwrap();
        let read =
            |text: &str| serde_json::from_str::<AssignmentDump>(text).map_err(|e| e.to_string());
        assert_eq!(read(&text), Ok(one_pair()));
        // A misspelt key beside the real one is refused, not ignored.
        let e = read(&text.replacen('{', r#"{"offests":[],"#, 1)).unwrap_err();
        assert!(e.contains("unknown field `offests`"), "{e}");
        // So is a count of 1.0.
        let float = text.replacen("[0,0,0,0,0,1,", "[0,0,0,0,0,1.0,", 1);
        assert_ne!(float, text);
        let e = read(&float).unwrap_err();
        assert!(e.contains("floating point `1.0`"), "{e}");
    }
}
