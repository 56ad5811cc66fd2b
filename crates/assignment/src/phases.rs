//! The three axis phases as SoA passes over a block of lights.
//!
//! Each phase is split in two loops: an arithmetic pass over the block's columns with no branches
//! (so the compiler vectorises it), guessing each light's planes, writing the answer where the
//! guess is proven exact, then a scalar pass that searches the plane sets (`search.rs`) for the
//! other lanes only, found from a bit mask. The per-light function `geometry::cluster_box`
//! (test builds only) is the slow twin: a test checks that the passes give exactly its boxes.

use crate::geometry::{self, ClusterBox, ZRange};
use crate::profiling::profile_span;
use crate::search::{self, FramePlanes, SliceCoordinate, SliceGuesser, Slicing};

/// Lights per SoA block inside a task of few lights (a `paper` frame's tasks hold ~125).
pub(crate) const BLOCK: usize = 256;

/// Lights per SoA block inside a task of many (at least [`LARGE_BLOCK_TASK`] lights).
///
/// Only the survivors of the early cull go through the phases, and where nine lights in ten are
/// culled (`sphere`) a block of 256 leaves ~20 of them: two vector iterations and a scalar
/// remainder per pass. Blocks of 1024 make those passes longer (`sphere` 100k `binary`: 5.21 →
/// 4.67 M instructions a frame; `uniform` 100k −2%), but their columns cost a task more: they
/// are zeroed on entry, ~145 KiB of the running thread's stack against ~36 KiB, and no longer
/// fit in L1 beside the rest.
///
/// 1088 (17 words of 64 lanes), not 1024: a column of 1024 four-byte lanes is 4 KiB, the
/// set stride of an 8-way 32 KiB L1 (and of a 12-way 48 KiB one), so lane `b` of every column
/// — a light's `k0, k1, i0, i1, j0, j1, da, db, cx, …`, read together by the emit — fell into
/// the same cache set, more lines than it has ways, and evicted each other before the next 15
/// lanes could use them. A stride of 4352 bytes staggers the columns by four lines each.
/// cachegrind (`uniform` 100k `binary`, the tasks' code, L1 32 KiB 8-way): read misses 24.2 →
/// 3.6 M, write misses 10.0 → 2.5 M, instructions unchanged; `myriad bench`, interleaved
/// rounds, `uniform` 100k `refined` one thread 10.5 → 7.8 ms, two threads 5.4 → 4.2 ms (docs/measured.md,
/// "What made the difference"; on the Intel cores of the H100 machine, with 48 KiB of L1, the two measured alike).
/// Blocks of [`BLOCK`] show no such misses (columns of 1 KiB; 192 or 320 lanes
/// measured the same), and an assertion below keeps the large columns off 4 KiB multiples.
pub(crate) const LARGE_BLOCK: usize = 1088;

// A large block's four-byte columns must not be a whole number of 4 KiB apart (see above).
const _: () = assert!(!(LARGE_BLOCK * 4).is_multiple_of(4096));

/// Tasks of at least this many lights use blocks of [`LARGE_BLOCK`]: below it a task's lights
/// fill few of the large columns, and zeroing them (~145 KiB a task) costs more than the longer
/// passes save.
/// With blocks of 1024, whose columns shared L1 sets (see [`LARGE_BLOCK`]), tasks of 2048 lights
/// ran 13% slower with them (`sphere` 8192, one thread, 45.9 → 52.1 µs) and the threshold was
/// 8192. With 1088, interleaved rounds of `myriad bench` (median of per-round medians), against
/// that threshold: `sphere` 8192 `binary` one thread (tasks of 2048) 75.3 → 69.3 µs, `sphere`
/// 16 384 two threads 84.4 → 70.8 µs, `sphere` 32 768 two threads 150.7 → 131.4 µs, `uniform`
/// 20 000 (tasks of 5000) `binary` two threads 684 → 657 µs and `refined` one thread the same.
pub(crate) const LARGE_BLOCK_TASK: usize = 2048;

/// One block's columns, `B` lights wide. `cx, cy, dc, rad` (view-space centre and padded radius)
/// and `alive` (valid and possibly inside the frustum) are inputs; the phases fill the rest and
/// clear `alive` for lights found outside.
pub(crate) struct Block<const B: usize> {
    pub cx: [f32; B],
    pub cy: [f32; B],
    pub dc: [f32; B],
    pub rad: [f32; B],
    pub alive: [bool; B],
    /// Position of each entry's light in the task's current block (entries are compacted).
    pub source: [u32; B],
    da: [f32; B],
    db: [f32; B],
    band_r: [f32; B],
    smin: [f32; B],
    smax: [f32; B],
    guess0: [u32; B],
    guess1: [u32; B],
    /// The guesses are provably the partition points (`search::exact_margin`).
    exact: [bool; B],
    k0: [u32; B],
    k1: [u32; B],
    i0: [u32; B],
    i1: [u32; B],
    j0: [u32; B],
    j1: [u32; B],
}

impl<const B: usize> Block<B> {
    pub fn new() -> Self {
        Self {
            cx: [0.0; B],
            cy: [0.0; B],
            dc: [0.0; B],
            rad: [0.0; B],
            alive: [false; B],
            source: [0; B],
            da: [0.0; B],
            db: [0.0; B],
            band_r: [0.0; B],
            smin: [0.0; B],
            smax: [0.0; B],
            guess0: [0; B],
            guess1: [0; B],
            exact: [false; B],
            k0: [0; B],
            k1: [0; B],
            i0: [0; B],
            i1: [0; B],
            j0: [0; B],
            j1: [0; B],
        }
    }

    /// Runs the z, x and y phases over the first `n` lights.
    #[inline(always)]
    pub fn run_phases(&mut self, n: usize, planes: &FramePlanes<'_>) {
        {
            profile_span!("phase: z");
            self.z_phase(n, planes);
        }
        {
            profile_span!("phase: x");
            self.x_phase(n, planes);
        }
        profile_span!("phase: y");
        self.y_phase(n, planes);
    }

    /// The box of light `b` (only meaningful while `alive[b]`).
    pub fn cluster_box(&self, b: usize) -> ClusterBox {
        ClusterBox {
            z: ZRange {
                da: self.da[b],
                db: self.db[b],
                k0: self.k0[b],
                k1: self.k1[b],
            },
            i0: self.i0[b],
            i1: self.i1[b],
            j0: self.j0[b],
            j1: self.j1[b],
        }
    }

    /// Depth band, the widest cross-section inside it, then the slices.
    #[inline(always)]
    fn z_phase(&mut self, n: usize, planes: &FramePlanes<'_>) {
        // The pass is built once per slicing: a `match` on it inside the loop kept the loop
        // scalar.
        match planes.slicing() {
            Slicing::Linear(guesser) => self.z_pass(n, planes, guesser),
            Slicing::Log(guesser) => self.z_pass(n, planes, guesser),
        }
        for_each_searched(&mut self.alive, &self.exact, n, |b| {
            self.k0[b] = planes.first_slice_exact(self.da[b], self.guess0[b], false);
            self.k1[b] = planes.slice_exact(self.db[b], self.guess1[b], false);
            true
        });
    }

    /// The z phase's arithmetic pass: branch-free, every number it reads copied into locals
    /// first (read through `planes` inside the loop they would be reloaded after every store:
    /// the compiler cannot tell the block's columns from the plane vectors), so it vectorises.
    #[inline(always)]
    fn z_pass<C: SliceCoordinate>(
        &mut self,
        n: usize,
        planes: &FramePlanes<'_>,
        guesser: SliceGuesser<C>,
    ) {
        let z = &planes.sets.z_depths;
        let (near, far) = (z[0], z[z.len() - 1]);
        let slices = z.len() as u32 - 1;
        // `b < n <= B`: no bounds check left in the loop to keep it scalar.
        let n = n.min(B);
        for b in 0..n {
            let (dc, r) = (self.dc[b], self.rad[b]);
            let da = (dc - r).max(near);
            let db = (dc + r).min(far);
            self.alive[b] &= da <= db;
            self.da[b] = da;
            self.db[b] = db;
            self.band_r[b] = geometry::band_radius(dc, r, da, db);
            let (guess0, exact0) = guesser.guess(da);
            let (guess1, exact1) = guesser.guess(db);
            self.guess0[b] = guess0;
            self.guess1[b] = guess1;
            self.exact[b] = exact0 & exact1;
            self.k0[b] = search::first_slice_of_guess(guess0, slices);
            self.k1[b] = search::slice_of_guess(guess1, slices);
        }
    }

    /// Slope range across the screen's x axis, then the tile columns.
    #[inline(always)]
    fn x_phase(&mut self, n: usize, planes: &FramePlanes<'_>) {
        self.axis_phase(n, Axis::X, planes);
    }

    /// Slope range across the screen's y axis, then the tile rows.
    #[inline(always)]
    fn y_phase(&mut self, n: usize, planes: &FramePlanes<'_>) {
        self.axis_phase(n, Axis::Y, planes);
    }

    /// One screen axis: the slope range (depth-band box ∩ tangents), then the tiles along it.
    #[inline(always)]
    fn axis_phase(&mut self, n: usize, axis: Axis, planes: &FramePlanes<'_>) {
        let Block {
            cx,
            cy,
            dc,
            rad,
            alive,
            da,
            db,
            band_r,
            smin,
            smax,
            guess0: guess0s,
            guess1: guess1s,
            exact,
            i0,
            i1,
            j0,
            j1,
            ..
        } = self;
        let (centre, first, last) = match axis {
            Axis::X => (&*cx, i0, i1),
            Axis::Y => (&*cy, j0, j1),
        };
        for b in 0..n {
            let c = centre[b];
            let (lo, hi) = geometry::box_slopes(c - band_r[b], c + band_r[b], da[b], db[b]);
            let (tlo, thi) = geometry::tangent_slopes(c, dc[b], rad[b]);
            let (min, max) = (lo.max(tlo), hi.min(thi));
            smin[b] = min;
            smax[b] = max;
            let (guess0, guess1, proven) = match axis {
                Axis::X => planes.columns_guess(min, max),
                Axis::Y => planes.rows_guess(min, max),
            };
            (guess0s[b], guess1s[b], exact[b]) = (guess0, guess1, proven);
            // A proven guess is the answer: tiles `guess0 ..< guess1`, none when empty.
            (first[b], last[b]) = (guess0, guess1.wrapping_sub(1));
            alive[b] &= !proven | (guess0 < guess1);
        }
        for_each_searched(alive, exact, n, |b| {
            let guess = (guess0s[b], guess1s[b]);
            let tiles = match axis {
                Axis::X => planes.columns_exact(smin[b], smax[b], guess, false),
                Axis::Y => planes.rows_exact(smin[b], smax[b], guess, false),
            };
            if let Some((f, l)) = tiles {
                (first[b], last[b]) = (f, l);
            }
            tiles.is_some()
        });
    }
}

/// Calls `search(b)` for each lane `b < n` that is alive and whose guesses are not proven exact
/// — about one in 200 on ordinary grids — found 64 lanes at a time from a bit mask, so the
/// proven lanes cost no scalar work at all. A lane whose search returns false dies.
#[inline(always)]
fn for_each_searched(
    alive: &mut [bool],
    exact: &[bool],
    n: usize,
    mut search: impl FnMut(usize) -> bool,
) {
    for (word, (alive, exact)) in alive[..n]
        .chunks_mut(64)
        .zip(exact[..n].chunks(64))
        .enumerate()
    {
        let mut mask = alive
            .iter()
            .zip(exact)
            .enumerate()
            .fold(0u64, |m, (i, (&a, &e))| m | (((a & !e) as u64) << i));
        while mask != 0 {
            let lane = mask.trailing_zeros() as usize;
            alive[lane] = search(word * 64 + lane);
            mask &= mask - 1;
        }
    }
}

/// A screen axis of the x and y phases.
#[derive(Clone, Copy)]
enum Axis {
    X,
    Y,
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{UVec3, Vec3};
    use myriad_cluster_math::{Camera, ClusterGrid, DepthSlicing, PlaneSets};
    use rand::{Rng, SeedableRng};

    #[test]
    fn block_passes_equal_the_per_light_function() {
        // Both widths, and a block filled only in part (the phases run over the first `n`), for
        // every slicing: the z pass is built once per slicing (`Slicing`).
        let slicings = [
            DepthSlicing::Log,
            DepthSlicing::Linear,
            DepthSlicing::LogWithNearSlice {
                first_slice_depth: 2.0,
            },
        ];
        for slicing in slicings {
            block_passes_match::<BLOCK>(BLOCK, slicing);
            block_passes_match::<BLOCK>(37, slicing);
            block_passes_match::<LARGE_BLOCK>(LARGE_BLOCK, slicing);
            block_passes_match::<LARGE_BLOCK>(LARGE_BLOCK - 3, slicing);
        }
    }

    fn block_passes_match<const B: usize>(n: usize, slicing: DepthSlicing) {
        let cam = Camera::new(
            Vec3::ZERO,
            Vec3::NEG_Z,
            Vec3::Y,
            70.0,
            1920,
            1080,
            0.1,
            100.0,
        );
        let grid = ClusterGrid::new(UVec3::new(32, 18, 48), slicing, 0.1, 100.0);
        let sets = PlaneSets::new(&cam, &grid);
        let planes = FramePlanes::new(&sets, &grid);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(9);
        let mut block = Box::new(Block::<B>::new());
        for _ in 0..20 {
            for b in 0..n {
                block.cx[b] = rng.random_range(-150.0..150.0);
                block.cy[b] = rng.random_range(-100.0..100.0);
                block.dc[b] = rng.random_range(-20.0..120.0);
                block.rad[b] = 10f32.powf(rng.random_range(-3.0..2.5));
                block.alive[b] = true;
            }
            let input = (block.cx, block.cy, block.dc, block.rad);
            block.run_phases(n, &planes);
            let mut seen = 0;
            for b in 0..n {
                let expect =
                    geometry::cluster_box(input.0[b], input.1[b], input.2[b], input.3[b], &planes);
                assert_eq!(
                    block.alive[b],
                    expect.is_some(),
                    "{B}-wide block, {slicing:?}, light {b}"
                );
                if let Some(e) = expect {
                    assert_eq!(block.cluster_box(b), e, "{slicing:?}, light {b}");
                    seen += 1;
                }
            }
            assert!(seen > n / 25, "{seen} of {n} lights with a box");
        }
    }
}
