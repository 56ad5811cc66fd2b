//! Searching the plane sets: where does a slope or a depth fall among the planes?
//!
//! Each answer is a *partition point* — how many planes lie on one side of the value — and must
//! be exact against the f32 plane values, since those are the walls the shader uses. A plain
//! binary search needs log₂(n) dependent loads per answer, and the three axis phases ask six
//! questions per light: on a 2-core machine that alone exceeded the time budget. But the plane
//! sets follow closed forms (tiles are uniform in NDC; slices are linear or logarithmic in depth),
//! so the search starts at the closed-form guess — cheap, and within one plane of the answer —
//! and then steps against the actual plane values until the partition point is exact. The result
//! is identical to a binary search for any guess (tests compare with `partition_point`); only the
//! number of probes changes (1–2 instead of ~6).

use myriad_cluster_math::{ClusterGrid, DepthSlicing, PlaneSets};

/// Partition point of `pred` over `items` (true on a prefix, false after), searched outward from
/// `guess`. Exact for any guess; fast when the guess is close.
///
/// The loops branch on every probe, and the branches are well predicted: a branch-free step
/// either way plus a check of the side moved towards (four loads, each waiting on the last)
/// measured slower — `paper` 1000 serial `binary` 46 → 59 µs, `uniform` 100k 3.0 → 4.7 ms.
#[inline]
pub(crate) fn partition_from(items: &[f32], guess: usize, pred: impl Fn(f32) -> bool) -> usize {
    let mut i = guess.min(items.len());
    while i > 0 && !pred(items[i - 1]) {
        i -= 1;
    }
    while i < items.len() && pred(items[i]) {
        i += 1;
    }
    i
}

/// A float index guess, clamped into `0..=max` (NaN → 0, ±∞ → the ends).
///
/// Clamped and floored as a float, then read from the bits of `t + 2²³` (whose mantissa is then
/// the integer itself): all plain vector arithmetic. A saturating `as usize` took about a dozen
/// instructions per guess — 73 per light, the largest line of the `uniform` 100k profile — and
/// `as i32` still seven. Exact while `max < 2²³` (planes per axis); a grid past that only gets
/// poor guesses, which cost search steps, never a wrong answer (`partition_from` is exact from any
/// guess). Those steps add up: an audit's 1×1×12 000 000 grid took 3.6 s for 2000 lights, against
/// 0.18 s at 8 000 000 slices. Bounding the walk (a bisection after eight steps) made every frame
/// of ordinary grids 17–35% slower (`uniform` 100k `binary`, one thread, interleaved builds), so
/// it was not kept: no real grid comes near 2²³ slices or tiles an axis.
#[inline]
fn clamp_index(t: f32, max: usize) -> usize {
    const TWO_23: f32 = (1u32 << 23) as f32;
    let t = t.max(0.0).min(max as f32).floor();
    ((t + TWO_23).to_bits() & 0x007F_FFFF) as usize
}

/// log₂ from the float's exponent plus a rational fit of the mantissa's log (Mineiro's
/// "fastlog2"; error about 1e-4), branch-free so guesses vectorise. Only used for guesses.
#[inline]
fn log2_approx(x: f32) -> f32 {
    let bits = x.to_bits();
    let mantissa = f32::from_bits((bits & 0x007F_FFFF) | 0x3F00_0000); // in [0.5, 1)
    bits as f32 * (1.0 / (1u32 << 23) as f32)
        - 124.225_52
        - 1.498_030_3 * mantissa
        - 1.725_88 / (0.352_088_7 + mantissa)
}

/// How to guess a depth's slice.
#[derive(Clone, Copy, Debug)]
enum SliceGuess {
    /// `t = (d − n)·scale`.
    Linear { near: f32, scale: f32 },
    /// `t = offset + (log₂ d − log₂ start)·scale` for `d ≥ start`, else 0.
    Log {
        start: f32,
        log2_start: f32,
        scale: f32,
        offset: f32,
    },
}

/// The plane sets of one frame plus what is needed to guess positions in them.
pub(crate) struct FramePlanes<'a> {
    /// The plane values (the ground truth of every answer).
    pub sets: &'a PlaneSets,
    x_scale: f32,
    y_scale: f32,
    half_x: f32,
    half_y: f32,
    slice: SliceGuess,
}

impl<'a> FramePlanes<'a> {
    /// Guessing parameters for `sets`, built from `grid` and the slopes of its outer planes.
    pub fn new(sets: &'a PlaneSets, grid: &ClusterGrid) -> Self {
        let d = grid.dims();
        let tx = sets.x_slopes[d.x as usize];
        let ty = sets.y_slopes[0];
        let (n, f, z) = (grid.near(), grid.far(), d.z as f32);
        let slice = match grid.slicing() {
            DepthSlicing::Linear => SliceGuess::Linear {
                near: n,
                scale: z / (f - n),
            },
            DepthSlicing::Log => SliceGuess::Log {
                start: n,
                log2_start: n.log2(),
                scale: z / (f / n).log2(),
                offset: 0.0,
            },
            DepthSlicing::LogWithNearSlice { first_slice_depth } if d.z > 1 => SliceGuess::Log {
                start: first_slice_depth,
                log2_start: first_slice_depth.log2(),
                scale: (z - 1.0) / (f / first_slice_depth).log2(),
                offset: 1.0,
            },
            DepthSlicing::LogWithNearSlice { .. } => SliceGuess::Linear {
                near: n,
                scale: z / (f - n),
            },
        };
        Self {
            sets,
            x_scale: d.x as f32 / (2.0 * tx),
            y_scale: d.y as f32 / (2.0 * ty),
            half_x: d.x as f32 / 2.0,
            half_y: d.y as f32 / 2.0,
            slice,
        }
    }

    /// Continuous slice coordinate of depth `d` (approximate).
    #[inline]
    fn slice_coordinate(&self, d: f32) -> f32 {
        match self.slice {
            SliceGuess::Linear { near, scale } => (d - near) * scale,
            SliceGuess::Log {
                start,
                log2_start,
                scale,
                offset,
            } => {
                if d < start {
                    0.0
                } else {
                    offset + (log2_approx(d) - log2_start) * scale
                }
            }
        }
    }

    /// The slice holding depth `d`, clamped to `0..Z`: the last slice whose near edge is `<= d`.
    #[cfg(test)]
    pub fn slice_of(&self, d: f32) -> u32 {
        self.slice_exact(d, self.slice_guess(d))
    }

    /// Branch-free first half of [`Self::slice_of`]: a guess of the partition point.
    #[inline]
    pub fn slice_guess(&self, d: f32) -> u32 {
        clamp_index(self.slice_coordinate(d) + 1.0, self.sets.z_depths.len()) as u32
    }

    /// Second half of [`Self::slice_of`]: the exact slice from any guess. This is the *last*
    /// slice a depth band ending at `d` reaches.
    #[inline]
    pub fn slice_exact(&self, d: f32, guess: u32) -> u32 {
        let z = &self.sets.z_depths;
        let slices = z.len() - 1;
        (partition_from(z, guess as usize, |e| e <= d).clamp(1, slices) - 1) as u32
    }

    /// The *first* slice a depth band starting at `d` reaches: the first whose far edge is
    /// `>= d`, clamped to `0..Z`, from the same guess as [`Self::slice_exact`].
    ///
    /// It differs from the slice holding `d` only when `d` lies exactly on an edge: then the
    /// closed slice ending there touches the band too, and so do slices of zero thickness (two
    /// equal f32 edges, as a very thin log grid rounds to). No pixel lands in those, but the f64
    /// oracle counts the contact, so skipping them would be a miss.
    #[inline]
    pub fn first_slice_exact(&self, d: f32, guess: u32) -> u32 {
        let z = &self.sets.z_depths;
        let slices = z.len() - 1;
        let guess = (guess as usize).saturating_sub(1);
        partition_from(&z[1..], guess, |e| e < d).min(slices - 1) as u32
    }

    /// [`Self::first_slice_exact`] with its own guess.
    #[cfg(test)]
    pub fn first_slice(&self, d: f32) -> u32 {
        self.first_slice_exact(d, self.slice_guess(d))
    }

    /// Tile columns `[first, last]` whose slope span `[s_i, s_{i+1}]` overlaps `[min, max]`.
    #[cfg(test)]
    pub fn columns(&self, min: f32, max: f32) -> Option<(u32, u32)> {
        self.columns_exact(min, max, self.columns_guess(min, max))
    }

    /// Branch-free first half of [`Self::columns`].
    #[inline]
    pub fn columns_guess(&self, min: f32, max: f32) -> (u32, u32) {
        let tiles = self.sets.x_slopes.len() - 1;
        let t = |v: f32| v * self.x_scale + self.half_x;
        (
            clamp_index(t(min), tiles) as u32,
            clamp_index(t(max) + 1.0, tiles) as u32,
        )
    }

    /// Second half of [`Self::columns`]: exact from any guess.
    #[inline]
    pub fn columns_exact(&self, min: f32, max: f32, guess: (u32, u32)) -> Option<(u32, u32)> {
        let s = &self.sets.x_slopes;
        let tiles = s.len() - 1;
        // First tile whose right edge reaches `min`; tiles up to the last left edge `<= max`.
        let first = partition_from(&s[1..], guess.0 as usize, |e| e < min);
        let after_last = partition_from(&s[..tiles], guess.1 as usize, |e| e <= max);
        (first < after_last).then(|| (first as u32, after_last as u32 - 1))
    }

    /// Tile rows `[first, last]` (top → bottom) whose slope span `[s_{j+1}, s_j]` overlaps
    /// `[min, max]`.
    #[cfg(test)]
    pub fn rows(&self, min: f32, max: f32) -> Option<(u32, u32)> {
        self.rows_exact(min, max, self.rows_guess(min, max))
    }

    /// Branch-free first half of [`Self::rows`].
    #[inline]
    pub fn rows_guess(&self, min: f32, max: f32) -> (u32, u32) {
        let rows = self.sets.y_slopes.len() - 1;
        let t = |v: f32| self.half_y - v * self.y_scale;
        (
            clamp_index(t(max), rows) as u32,
            clamp_index(t(min) + 1.0, rows) as u32,
        )
    }

    /// Second half of [`Self::rows`]: exact from any guess.
    #[inline]
    pub fn rows_exact(&self, min: f32, max: f32, guess: (u32, u32)) -> Option<(u32, u32)> {
        let s = &self.sets.y_slopes;
        let rows = s.len() - 1;
        // First row whose bottom edge is `<= max`; rows up to the last top edge `>= min`.
        let first = partition_from(&s[1..], guess.0 as usize, |e| e > max);
        let after_last = partition_from(&s[..rows], guess.1 as usize, |e| e >= min);
        (first < after_last).then(|| (first as u32, after_last as u32 - 1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{UVec3, Vec3};
    use myriad_cluster_math::Camera;
    use rand::{Rng, SeedableRng};

    /// The slow twin: the same questions answered by plain binary search.
    fn bisect_columns(s: &[f32], min: f32, max: f32) -> Option<(u32, u32)> {
        let tiles = s.len() - 1;
        let first = s[1..].partition_point(|&e| e < min);
        let after = s[..tiles].partition_point(|&e| e <= max);
        (first < after).then(|| (first as u32, after as u32 - 1))
    }

    fn bisect_rows(s: &[f32], min: f32, max: f32) -> Option<(u32, u32)> {
        let rows = s.len() - 1;
        let first = s[1..].partition_point(|&e| e > max);
        let after = s[..rows].partition_point(|&e| e >= min);
        (first < after).then(|| (first as u32, after as u32 - 1))
    }

    #[test]
    fn partition_from_is_exact_from_any_guess() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        for len in 0..60 {
            let mut items: Vec<f32> = (0..len).map(|_| rng.random_range(-5.0f32..5.0)).collect();
            items.sort_by(f32::total_cmp);
            for _ in 0..20 {
                let v = rng.random_range(-6.0f32..6.0);
                let want = items.partition_point(|&e| e <= v);
                for guess in 0..len + 4 {
                    assert_eq!(
                        partition_from(&items, guess, |e| e <= v),
                        want,
                        "{v} {guess}"
                    );
                }
            }
        }
    }

    #[test]
    fn guided_search_equals_binary_search() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        for case in 0..300 {
            let fov = rng.random_range(0.5f32..179.0);
            let cam = Camera::new(
                Vec3::ZERO,
                Vec3::NEG_Z,
                Vec3::Y,
                fov,
                rng.random_range(1..4000),
                rng.random_range(1..4000),
                0.1,
                100.0,
            );
            let dims = UVec3::new(
                rng.random_range(1..130),
                rng.random_range(1..130),
                rng.random_range(1..130),
            );
            let (near, far) = (10f32.powf(rng.random_range(-4.0..1.0)), 0.0);
            let far = near * 10f32.powf(rng.random_range(0.01..7.0)) + far;
            let slicing = match case % 3 {
                0 => DepthSlicing::Linear,
                1 => DepthSlicing::Log,
                _ => DepthSlicing::LogWithNearSlice {
                    first_slice_depth: near + (far - near) * 0.001,
                },
            };
            if let DepthSlicing::LogWithNearSlice { first_slice_depth } = slicing
                && !(first_slice_depth > near && first_slice_depth < far)
            {
                continue;
            }
            let grid = ClusterGrid::new(dims, slicing, near, far);
            let sets = PlaneSets::new(&cam, &grid);
            let fp = FramePlanes::new(&sets, &grid);
            let t = cam.tan_half_fov();
            let mut probes: Vec<f32> = vec![f32::NEG_INFINITY, f32::INFINITY, 0.0, -0.0];
            probes.extend(
                sets.x_slopes
                    .iter()
                    .flat_map(|&s| [s, s.next_up(), s.next_down()]),
            );
            probes.extend(
                sets.y_slopes
                    .iter()
                    .flat_map(|&s| [s, s.next_up(), s.next_down()]),
            );
            probes.extend((0..200).map(|_| rng.random_range(-1.5f32..1.5) * t.x.max(t.y)));
            for &a in &probes {
                for &b in probes.iter().step_by(7) {
                    let (lo, hi) = (a.min(b), a.max(b));
                    // The closed-form guesses land within one plane of the partition points.
                    let (g0, g1) = fp.columns_guess(lo, hi);
                    let tiles = sets.x_slopes.len() - 1;
                    let first = sets.x_slopes[1..].partition_point(|&e| e < lo);
                    let after = sets.x_slopes[..tiles].partition_point(|&e| e <= hi);
                    assert!(
                        (g0 as usize).abs_diff(first) <= 1 && (g1 as usize).abs_diff(after) <= 1,
                        "x [{lo}, {hi}]: guess ({g0}, {g1}), partition points ({first}, {after})"
                    );
                    let (g0, g1) = fp.rows_guess(lo, hi);
                    let rows = sets.y_slopes.len() - 1;
                    let first = sets.y_slopes[1..].partition_point(|&e| e > hi);
                    let after = sets.y_slopes[..rows].partition_point(|&e| e >= lo);
                    assert!(
                        (g0 as usize).abs_diff(first) <= 1 && (g1 as usize).abs_diff(after) <= 1,
                        "y [{lo}, {hi}]: guess ({g0}, {g1}), partition points ({first}, {after})"
                    );
                    assert_eq!(
                        fp.columns(lo, hi),
                        bisect_columns(&sets.x_slopes, lo, hi),
                        "x [{lo}, {hi}]"
                    );
                    assert_eq!(
                        fp.rows(lo, hi),
                        bisect_rows(&sets.y_slopes, lo, hi),
                        "y [{lo}, {hi}]"
                    );
                }
            }
            let mut depths: Vec<f32> = sets
                .z_depths
                .iter()
                .flat_map(|&d| [d, d.next_up(), d.next_down()])
                .collect();
            depths
                .extend((0..300).map(|_| near * (far / near).powf(rng.random_range(-0.1f32..1.1))));
            // The approximate log must keep guesses close: within one plane of the partition
            // point.
            for d in depths {
                let slices = dims.z;
                let guess = fp.slice_guess(d) as usize;
                let edges_below = sets.z_depths.partition_point(|&e| e <= d);
                assert!(
                    guess.abs_diff(edges_below) <= 1,
                    "depth {d} in {grid:?}: guess {guess}, partition point {edges_below}"
                );
                let want = (sets.z_depths.partition_point(|&e| e <= d) as u32).clamp(1, slices) - 1;
                assert_eq!(fp.slice_of(d), want, "depth {d} in {grid:?}");
                let first = sets.z_depths[1..]
                    .partition_point(|&e| e < d)
                    .min(slices as usize - 1);
                assert_eq!(fp.first_slice(d), first as u32, "depth {d} in {grid:?}");
                if d >= near && d < far {
                    assert_eq!(fp.slice_of(d), grid.slice_of_depth(d));
                }
            }
        }
    }
}
