//! The assignment dump: the JSON file `myriad assign` writes and `myriad check` reads
//! (format in DESIGN.md, "Assignment dump").

use anyhow::{Context, Result, bail, ensure};
use myriad_assignment::LightLists;
use myriad_cluster_math::ClusterGrid;
use serde::{Deserialize, Serialize};
use std::path::Path;

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
}

impl AssignmentDump {
    /// Builds a dump; `source_index[l]` maps the assignment's light `l` to its scene-file index.
    pub fn new(grid: &ClusterGrid, lists: &LightLists, source_index: &[u32]) -> Self {
        let d = grid.dims;
        let mut z_planes = Vec::new();
        grid.fill_slice_edges(&mut z_planes);
        Self {
            grid: [d.x, d.y, d.z],
            x_edges: (0..=d.x).map(|i| grid.x_edge_ndc(i)).collect(),
            y_edges: (0..=d.y).map(|j| grid.y_edge_ndc(j)).collect(),
            z_planes,
            offsets: lists.offsets.clone(),
            counts: lists.counts.clone(),
            indices: lists
                .indices
                .iter()
                .map(|&l| source_index[l as usize])
                .collect(),
        }
    }

    /// Reads and checks a dump file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read dump {}", path.display()))?;
        let dump: Self = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a valid assignment dump", path.display()))?;
        dump.validate()
            .with_context(|| format!("{}: inconsistent assignment dump", path.display()))?;
        Ok(dump)
    }

    /// Writes the dump as JSON.
    pub fn save(&self, path: &Path) -> Result<()> {
        let text = serde_json::to_string(self)?;
        std::fs::write(path, text).with_context(|| format!("cannot write dump {}", path.display()))
    }

    /// Structural checks: sizes agree and every list lies inside `indices`.
    pub fn validate(&self) -> Result<()> {
        let [x, y, z] = self.grid;
        ensure!(
            x >= 1 && y >= 1 && z >= 1,
            "grid dimensions must be >= 1, got {:?}",
            self.grid
        );
        let clusters = x as u64 * y as u64 * z as u64;
        ensure!(
            self.x_edges.len() as u64 == x as u64 + 1,
            "x_edges needs {} values",
            x + 1
        );
        ensure!(
            self.y_edges.len() as u64 == y as u64 + 1,
            "y_edges needs {} values",
            y + 1
        );
        ensure!(
            self.z_planes.len() as u64 == z as u64 + 1,
            "z_planes needs {} values",
            z + 1
        );
        ensure!(
            self.offsets.len() as u64 == clusters,
            "offsets needs {clusters} values"
        );
        ensure!(
            self.counts.len() as u64 == clusters,
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
        Ok(())
    }

    /// The lists of the dump (indices in scene-file space).
    pub fn lists(&self) -> LightLists {
        LightLists {
            offsets: self.offsets.clone(),
            counts: self.counts.clone(),
            indices: self.indices.clone(),
        }
    }
}
