//! The cluster grid: how the view frustum is cut into X×Y×Z cells, and the mappings between pixels,
//! depths and cluster ids.
//!
//! Two rules keep every consumer consistent:
//! 1. **Pixel → tile is integer arithmetic.** Pixel `px` (centre at `px + 0.5`) is in tile
//!    `⌊(2·px + 1)·X / (2·W)⌋`: exact for every resolution, whether or not X divides W.
//! 2. **Depth → slice is checked against the edge table.** The slice edges are defined once, by
//!    [`ClusterGrid::slice_start_depth`] (computed in f64, rounded to f32). [`ClusterGrid::slice_of_depth`]
//!    estimates the slice with the closed-form inverse and then corrects the estimate against those
//!    edges, so `slice_start_depth(k) <= d < slice_start_depth(k + 1)` holds exactly for every f32
//!    depth inside the range — the GPU shader gets the same slice by a plain binary search of the
//!    uploaded edge table (comparisons only, no estimate).
//!
//! Depths outside the grid's range clamp: below `near` (or NaN) → slice 0, at or beyond `far` →
//! slice Z−1. So the pixels nearer than `near` read the first slice and those past `far` the last,
//! and by default ([`OuterSlices::Open`]) those two slices reach the camera's near and far planes
//! for the assignment too: they list the lights out there, and no pixel the camera sees misses a
//! light, however short the grid (an engine's infinite projection with a grid of 50 m, or a grid
//! starting at 1 m to spend no slices on the first metre). A range fitted to the depth buffer,
//! which holds every shaded depth, is [`OuterSlices::Closed`]: the lights wholly outside it are
//! listed nowhere.

use glam::UVec3;
use std::ops::Range;

/// How view depth is cut into Z slices. With `n`, `f` the grid's near/far and `k` in `0..=Z`:
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DepthSlicing {
    /// `d_k = n + (f − n)·k/Z`.
    Linear,
    /// `d_k = n·(f/n)^(k/Z)`.
    Log,
    /// Slice 0 is `[n, first_slice_depth]`; slices 1..Z are logarithmic over
    /// `[first_slice_depth, f]`: `d_k = s·(f/s)^((k−1)/(Z−1))` for `k ≥ 1`. Avoids wasting many thin
    /// slices right in front of the camera where little geometry lives (as bevy and filament do).
    /// With Z = 1 it is a single slice `[n, f]`.
    LogWithNearSlice {
        /// View depth of the boundary between slice 0 and slice 1; `n < first_slice_depth < f`.
        first_slice_depth: f32,
    },
}

/// Where the first slice starts and the last one ends for the assignment, when the camera sees
/// nearer or farther than the grid.
///
/// Pixels nearer than the grid's near depth clamp to its first slice and pixels past its far
/// depth to its last ([`ClusterGrid::slice_of_depth`], and the GPU's cluster index alike), so the
/// lights they need must be listed there. Bevy clamps its lights' slices the same way; the
/// choice here is whether that is wanted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OuterSlices {
    /// The first slice reaches back to the camera's near plane and the last on to its far plane
    /// (infinite for an infinite projection): a light in view but wholly outside the grid's
    /// range is listed in the outer slice's clusters its sphere covers. Never wrong for any
    /// pixel of a camera the renderer accepts (near at least [`ClusterGrid::MIN_NEAR`]); the
    /// cost is longer lists in the outer slices when many lights lie outside the grid. The
    /// assignment then reads the camera's near and far, so they must be its real planes
    /// (`0 < near < far`, far possibly infinite; a placeholder is refused). The default.
    #[default]
    Open,
    /// The outer slices end at the grid's near and far depths, and the lights wholly outside
    /// them are culled (by the bounding sphere the cull tests, which for a wide spot reaches
    /// past its cone: such a spot may stay listed, a false positive). For a range that holds
    /// every shaded depth (fitted to the depth buffer): the lights outside it would only
    /// lengthen the outer slices' lists. The camera's near and far are not read.
    Closed,
}

/// Why [`ClusterGrid::try_new`] refused a grid.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InvalidGrid(pub String);

impl std::fmt::Display for InvalidGrid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for InvalidGrid {}

/// A cluster grid of `dims.x × dims.y × dims.z` cells over the view depth range `[near, far]`.
///
/// Every field is private and read through a getter: [`Self::try_new`] checks them together
/// (dimensions ≥ 1 whose product fits a u32 cluster id, a first slice inside the range), and a
/// grid edited field by field (`grid.dims.x = width / 64` on a narrow window) would skip those
/// checks into empty lists, panics or an allocation of a wrapped-around size. The checks do not
/// bound memory: a valid grid may have up to 2³² − 1 clusters, and an assignment keeps about 8
/// bytes a cluster (offsets and counts), 16 more with spot lights (cluster spheres) and 5 more
/// with an active-cluster mask — pick dimensions for the memory you have. A different grid is a
/// new one:
/// `ClusterGrid::try_new(dims, grid.slicing(), grid.near(), grid.far())`, with
/// `.with_outer_slices(grid.outer_slices())` to keep its [`OuterSlices`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClusterGrid {
    dims: UVec3,
    slicing: DepthSlicing,
    near: f32,
    far: f32,
    outer_slices: OuterSlices,
}

impl ClusterGrid {
    /// The smallest near depth a grid accepts, in any unit. The assignment works in f32, and
    /// below it the squared lengths of a light at the near plane (its view-space coordinates and
    /// padded radius, `4e-6` of its extent) leave f32's normal range: at near ≈ 1e-21 lists lost
    /// lights that the same scene scaled up kept. At `1e-12` they stay normal, and a scene scaled
    /// down to it gets the lists of the unscaled one (`crates/assignment/tests/stability.rs`).
    pub const MIN_NEAR: f32 = 1e-12;

    /// The clusters of a grid of `dims`, in u128: three u32 factors pass u64 (a 2^22 × 2^21 ×
    /// 2^21 grid wrapped to 0 clusters and was accepted, audit). Every check of a grid's size
    /// against u32 cluster ids counts with this.
    pub fn clusters_in(dims: UVec3) -> u128 {
        dims.x as u128 * dims.y as u128 * dims.z as u128
    }

    /// A grid over the depth range `[near, far]`, its outer slices [`OuterSlices::Open`]. Panics
    /// on zero dimensions or an invalid range (with [`Self::try_new`]'s message).
    pub fn new(dims: UVec3, slicing: DepthSlicing, near: f32, far: f32) -> Self {
        Self::try_new(dims, slicing, near, far).unwrap_or_else(|e| panic!("{e}"))
    }

    /// [`Self::new`] for grids from user settings: an error that says what is wrong instead of
    /// a panic.
    pub fn try_new(
        dims: UVec3,
        slicing: DepthSlicing,
        near: f32,
        far: f32,
    ) -> Result<Self, InvalidGrid> {
        if dims.min_element() < 1 {
            return Err(InvalidGrid(format!(
                "cluster grid dimensions must be >= 1: {dims}"
            )));
        }
        if !(near.is_finite() && far.is_finite() && near > 0.0 && near < far) {
            // An engine's infinite projection gives `camera.far = ∞`, which a grid cannot take:
            // its slices must end (say so, rather than "0 < near < far", which ∞ satisfies).
            let finite = if near.is_finite() && far.is_finite() {
                ""
            } else {
                " with both finite (a camera with an infinite far plane needs a grid with a \
                 finite far; its open last slice lists the lights beyond, and the assignment's \
                 `AssignStats::reach` says where they end)"
            };
            return Err(InvalidGrid(format!(
                "cluster grid depth range must satisfy 0 < near < far{finite}: [{near}, {far}]"
            )));
        }
        if let DepthSlicing::LogWithNearSlice { first_slice_depth } = slicing
            && !(dims.z == 1 && !first_slice_depth.is_nan()
                || (first_slice_depth > near && first_slice_depth < far))
        {
            return Err(InvalidGrid(format!(
                "first_slice_depth {first_slice_depth} must lie inside ({near}, {far})"
            )));
        }
        if near < Self::MIN_NEAR {
            return Err(InvalidGrid(format!(
                "cluster grid near depth must be at least {:e} (ClusterGrid::MIN_NEAR; the f32 \
                 assignment underflows below it), got {near:e}",
                Self::MIN_NEAR
            )));
        }
        // Cluster ids are u32 in the output lists.
        if Self::clusters_in(dims) > u32::MAX as u128 {
            return Err(InvalidGrid(format!(
                "cluster grid {dims} has more clusters than fit in a u32 id"
            )));
        }
        Ok(Self {
            dims,
            slicing,
            near,
            far,
            outer_slices: OuterSlices::Open,
        })
    }

    /// The same grid with its outer slices as `outer_slices` says (see [`OuterSlices`]).
    pub fn with_outer_slices(self, outer_slices: OuterSlices) -> Self {
        Self {
            outer_slices,
            ..self
        }
    }

    /// Whether the outer slices reach the camera's near and far planes for the assignment:
    /// [`OuterSlices::Open`] unless set otherwise.
    pub fn outer_slices(&self) -> OuterSlices {
        self.outer_slices
    }

    /// The depth where the assignment's first slice starts, seen through `camera`: the camera's
    /// near plane (no nearer than [`Self::MIN_NEAR`], where the f32 assignment stops being
    /// exact; the renderer refuses such a camera) where the grid is [`OuterSlices::Open`] and
    /// the camera sees nearer than the grid's `near`, otherwise `near`. Only the assignment and
    /// the oracle's first cells use it: the slice edges, and so the pixels' clusters, start at
    /// `near`.
    pub fn first_slice_start(&self, camera: &crate::Camera) -> f32 {
        match self.outer_slices {
            OuterSlices::Open if camera.near < self.near => camera.near.max(Self::MIN_NEAR),
            _ => self.near,
        }
    }

    /// The depth where the assignment's last slice ends, seen through `camera`: the camera's far
    /// plane (∞ for an infinite projection) where the grid is [`OuterSlices::Open`] and the
    /// camera sees past the grid's `far`, otherwise `far`. Only the assignment and the oracle's
    /// last cells use it: the slice edges, and so the pixels' clusters, end at `far`.
    pub fn last_slice_end(&self, camera: &crate::Camera) -> f32 {
        match self.outer_slices {
            OuterSlices::Open if camera.far > self.far => camera.far,
            _ => self.far,
        }
    }

    /// The same grid (its [`OuterSlices`] too) over a different depth range (a fitted, dynamic
    /// near/far). Panics where [`Self::try_with_depth_range`] returns an error.
    pub fn with_depth_range(self, near: f32, far: f32) -> Self {
        self.try_with_depth_range(near, far)
            .unwrap_or_else(|e| panic!("{e}"))
    }

    /// [`Self::with_depth_range`] for ranges measured at run time: an error instead of a panic
    /// when `near`/`far` are no range (equal, reversed, non-finite, below [`Self::MIN_NEAR`]) or
    /// no longer hold a `LogWithNearSlice` grid's first slice edge (a depth prepass of a scene
    /// wholly nearer than it; `myriad::render::fitted_grid` then falls back to `Log`).
    pub fn try_with_depth_range(self, near: f32, far: f32) -> Result<Self, InvalidGrid> {
        Self::try_new(self.dims, self.slicing, near, far)
            .map(|g| g.with_outer_slices(self.outer_slices))
    }

    /// Tiles across (X), tiles down (Y), depth slices (Z); each ≥ 1, their product ≤ `u32::MAX`.
    pub fn dims(&self) -> UVec3 {
        self.dims
    }

    /// How depth is sliced.
    pub fn slicing(&self) -> DepthSlicing {
        self.slicing
    }

    /// Near edge of slice 0.
    pub fn near(&self) -> f32 {
        self.near
    }

    /// Far edge of slice Z−1.
    pub fn far(&self) -> f32 {
        self.far
    }

    /// X·Y·Z.
    pub fn cluster_count(&self) -> usize {
        self.dims.x as usize * self.dims.y as usize * self.dims.z as usize
    }

    /// Cluster id of tile `(i, j)` in slice `k`: `i + X·(j + Y·k)`. Unchecked outside debug
    /// builds (the assignment's emit calls it per box row): a tile off the grid gives another
    /// cluster's id, or a wrapped one. [`Self::checked_cluster_id`] checks.
    #[inline]
    pub fn cluster_id(&self, i: u32, j: u32, k: u32) -> u32 {
        debug_assert!(i < self.dims.x && j < self.dims.y && k < self.dims.z);
        i + self.dims.x * (j + self.dims.y * k)
    }

    /// [`Self::cluster_id`], or `None` for a tile or slice off the grid: for ids from an
    /// engine's own data (marking `myriad-assignment`'s `ActiveClusters`, say),
    /// where a wrong id would be another cluster's, silently.
    pub fn checked_cluster_id(&self, i: u32, j: u32, k: u32) -> Option<u32> {
        (i < self.dims.x && j < self.dims.y && k < self.dims.z).then(|| self.cluster_id(i, j, k))
    }

    /// Inverse of [`Self::cluster_id`], for `id < self.cluster_count()` (larger ids give
    /// coordinates outside the grid).
    pub fn cluster_coords(&self, id: u32) -> UVec3 {
        let (x, y) = (self.dims.x, self.dims.y);
        UVec3::new(id % x, (id / x) % y, id / (x * y))
    }

    /// NDC x of the left edge of tile `i` (`i` in `0..=X`): `−1 + 2i/X`.
    ///
    /// # Panics
    /// When `i > X`.
    pub fn x_edge_ndc(&self, i: u32) -> f32 {
        ndc_edge_from_left(i, self.dims.x)
    }

    /// NDC y of the top edge of tile row `j` (`j` in `0..=Y`, counted from the top): `1 − 2j/Y`.
    ///
    /// # Panics
    /// When `j > Y`.
    pub fn y_edge_ndc(&self, j: u32) -> f32 {
        -ndc_edge_from_left(j, self.dims.y)
    }

    /// View depth where slice `k` starts (`k` in `0..=Z`; `k = Z` gives `far`).
    ///
    /// # Panics
    /// When `k > Z`.
    pub fn slice_start_depth(&self, k: u32) -> f32 {
        let z = self.dims.z;
        assert!(k <= z, "slice edge {k} out of range 0..={z}");
        if k == 0 {
            return self.near;
        }
        if k == z {
            return self.far;
        }
        let (n, f) = (self.near as f64, self.far as f64);
        let t = k as f64 / z as f64;
        let d = match self.slicing {
            DepthSlicing::Linear => n + (f - n) * t,
            DepthSlicing::Log => n * (f / n).powf(t),
            DepthSlicing::LogWithNearSlice { first_slice_depth } => {
                let s = first_slice_depth as f64;
                s * (f / s).powf((k - 1) as f64 / (z - 1) as f64)
            }
        };
        d as f32
    }

    /// Depth range `[start, end)` of slice `k`.
    ///
    /// # Panics
    /// When `k >= Z`.
    pub fn slice_depth_range(&self, k: u32) -> (f32, f32) {
        (self.slice_start_depth(k), self.slice_start_depth(k + 1))
    }

    /// Writes the Z+1 slice edges (near → far) into `out`, reusing its storage.
    pub fn fill_slice_edges(&self, out: &mut Vec<f32>) {
        out.clear();
        out.extend((0..=self.dims.z).map(|k| self.slice_start_depth(k)));
    }

    /// The slice holding view depth `depth`, clamped to `0..Z` (NaN → 0).
    pub fn slice_of_depth(&self, depth: f32) -> u32 {
        let z = self.dims.z;
        // `!(a >= b)` also catches NaN.
        if z == 1 || !(depth >= self.slice_start_depth(1)) {
            return 0;
        }
        if depth >= self.slice_start_depth(z - 1) {
            return z - 1;
        }
        let mut k = self.slice_estimate(depth).min(z - 1);
        while depth < self.slice_start_depth(k) {
            k -= 1;
        }
        while depth >= self.slice_start_depth(k + 1) {
            k += 1;
        }
        k
    }

    /// Closed-form inverse of the slicing, possibly off by one at edges.
    fn slice_estimate(&self, depth: f32) -> u32 {
        let (d, n, f, z) = (
            depth as f64,
            self.near as f64,
            self.far as f64,
            self.dims.z as f64,
        );
        let s = match self.slicing {
            DepthSlicing::Linear => (d - n) / (f - n) * z,
            DepthSlicing::Log => (d / n).ln() / (f / n).ln() * z,
            DepthSlicing::LogWithNearSlice { first_slice_depth } => {
                let s = first_slice_depth as f64;
                1.0 + (d / s).ln() / (f / s).ln() * (z - 1.0)
            }
        };
        s.max(0.0) as u32
    }

    /// Tile column of pixel column `px` for a target `width` pixels wide.
    ///
    /// # Panics
    /// When `px >= width` (a pixel outside the target, `width` 0 included): no tile holds it.
    #[inline]
    pub fn tile_x_of_pixel(&self, px: u32, width: u32) -> u32 {
        tile_of_pixel(px, width, self.dims.x)
    }

    /// Tile row (from the top) of pixel row `py` for a target `height` pixels high.
    ///
    /// # Panics
    /// When `py >= height`.
    #[inline]
    pub fn tile_y_of_pixel(&self, py: u32, height: u32) -> u32 {
        tile_of_pixel(py, height, self.dims.y)
    }

    /// The pixel columns whose centres lie in tile column `i` (may be empty when X > width).
    pub fn tile_pixel_columns(&self, i: u32, width: u32) -> Range<u32> {
        pixel_range_of_tile(i, width, self.dims.x)
    }

    /// The pixel rows whose centres lie in tile row `j`.
    pub fn tile_pixel_rows(&self, j: u32, height: u32) -> Range<u32> {
        pixel_range_of_tile(j, height, self.dims.y)
    }

    /// Cluster id of pixel `(px, py)` at view depth `depth` on a `width × height` target.
    /// Panics when the pixel lies outside the target (a programming error: no cluster holds it).
    pub fn cluster_of_pixel(&self, px: u32, py: u32, depth: f32, width: u32, height: u32) -> u32 {
        self.cluster_id(
            self.tile_x_of_pixel(px, width),
            self.tile_y_of_pixel(py, height),
            self.slice_of_depth(depth),
        )
    }
}

/// `−1 + 2i/n`, written as one rounding of an exact integer ratio.
fn ndc_edge_from_left(i: u32, n: u32) -> f32 {
    assert!(i <= n, "edge {i} out of range 0..={n}");
    ((2 * i as i64 - n as i64) as f64 / n as f64) as f32
}

/// `⌊(2p + 1)·tiles / (2·pixels)⌋`: the tile whose NDC span holds the pixel centre.
#[inline]
fn tile_of_pixel(p: u32, pixels: u32, tiles: u32) -> u32 {
    // A pixel outside the target would give another cluster's id, silently.
    assert!(p < pixels, "pixel {p} outside 0..{pixels}");
    match (2 * p as u64 + 1).checked_mul(tiles as u64) {
        Some(n) => (n / (2 * pixels as u64)) as u32,
        // Past u64 only when pixels and tiles are both beyond ~3e9 (it wrapped, audit).
        None => (((2 * p as u128 + 1) * tiles as u128) / (2 * pixels as u128)) as u32,
    }
}

/// Pixels `p` with `tile_of_pixel(p) == t`: `(2p+1)·T >= 2tP` and `(2p+1)·T < 2(t+1)P`. In u128:
/// `2tP` passes u64 for pixels and tiles both beyond ~3e9.
fn pixel_range_of_tile(t: u32, pixels: u32, tiles: u32) -> Range<u32> {
    let first = |t: u128| -> u128 {
        // Smallest p with (2p + 1)·T >= 2tP, i.e. p >= (2tP − T) / 2T.
        let num = (2 * t * pixels as u128).saturating_sub(tiles as u128);
        num.div_ceil(2 * tiles as u128)
    };
    let start = first(t as u128).min(pixels as u128) as u32;
    let end = first(t as u128 + 1).min(pixels as u128) as u32;
    start..end
}
