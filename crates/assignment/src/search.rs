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
//!
//! Most answers need no probe at all. Per frame, [`exact_margin`] measures how far each plane
//! set's closed form strays from its planes; a value whose guessed coordinate keeps further than
//! that from every integer is provably between the two planes the guess names, so the phases'
//! vector passes mark those lanes and their scalar passes skip the walks (about 99.5% of the
//! answers on ordinary grids; `uniform` 100k `binary` 47.5 → 39.3 M instructions a frame).

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

/// How far a plane set's coordinates may stray from the planes' indices: a coordinate `u` of a
/// value that keeps further than this from every integer ([`clear_of_planes`]) lies strictly
/// between the planes `⌊u⌋` and `⌊u⌋ + 1`, so its guessed partition point is exact without
/// reading a plane. `coordinates` are the planes' own coordinates, in order.
///
/// Why: the coordinate (`v·scale + half`, or `half − v·scale`) is monotone in `v` — one f32
/// product and one sum, both rounded monotonically. If plane `i`'s coordinate lies within `δ` of
/// `i` and a value's coordinate `u` satisfies `⌊u⌋ + δ < u < ⌊u⌋ + 1 − δ`, then every plane
/// `i ≤ ⌊u⌋` has a coordinate below `u` and every plane `i > ⌊u⌋` one above it, so by
/// monotonicity each plane is strictly on one side of the value: the partition point is `⌊u⌋ + 1`
/// (clamped) for `<` and `≤` alike, which is what the guesses compute. The margin is the largest
/// such `δ` over the planes, rounded up, plus slack for the guesses' own rounding (the `+ 1.0`
/// of an upper guess, the fraction's two subtractions): at least 2⁻¹⁰, and 4 ulps of the largest
/// index. So a fraction of about 2 · 2⁻¹⁰ of the answers still walks; the rest skip the search.
/// (A throwaway build that trusted every x and y guess unchecked ran `uniform` 100k `binary` in
/// 38 M instructions a frame instead of 47.5 M: the prize this claims, soundly.) Infinite —
/// nothing proved — for an axis of 2²² planes or more, where [`clamp_index`] stops being exact.
fn exact_margin(coordinates: impl Iterator<Item = f32>) -> f32 {
    let (mut planes, mut stray) = (0usize, 0.0f64);
    for (i, u) in coordinates.enumerate() {
        let b = (u as f64 - i as f64).abs();
        stray = if b > stray || b.is_nan() { b } else { stray };
        planes = i + 1;
    }
    if planes >= 1 << 22 {
        return f32::INFINITY;
    }
    let mut margin = stray as f32;
    if (margin as f64) < stray {
        margin = margin.next_up();
    }
    let top = (planes + 2) as f32;
    let slack = (4.0 * (top.next_up() - top)).max(1.0 / 1024.0);
    let margin = margin + slack;
    if margin.is_finite() {
        margin
    } else {
        f32::INFINITY
    }
}

/// Whether `u` keeps further than `margin` from every integer (false for NaN and ±∞).
#[inline]
fn clear_of_planes(u: f32, margin: f32) -> bool {
    let below = u.floor();
    (u - below > margin) & (below + 1.0 - u > margin)
}

/// The largest error of [`log2_approx`] against log₂, with headroom: over every positive normal
/// f32 it is 1.69·10⁻⁴ (an exhaustive sweep of all 254 exponents × 2²³ mantissas, 2026-11-27;
/// the worst at the largest exponents, where the final subtractions round coarsest). A test
/// sweeps the extreme exponents' mantissas on every run.
const LOG2_APPROX_ERROR: f32 = 2.5e-4;

/// [`FramePlanes::slice_exact`]'s answer in a grid of `slices` when `guess` is the partition
/// point (branch-free).
#[inline]
pub(crate) fn slice_of_guess(guess: u32, slices: u32) -> u32 {
    // Not `clamp`, whose check of its bounds would keep the z phase's loop from vectorising.
    guess.max(1).min(slices) - 1
}

/// [`FramePlanes::first_slice_exact`]'s answer in a grid of `slices` when `guess` (of
/// [`SliceGuesser::guess`]) is exact: one edge fewer lies below a band's start than the
/// guess counts (branch-free).
#[inline]
pub(crate) fn first_slice_of_guess(guess: u32, slices: u32) -> u32 {
    guess.saturating_sub(1).min(slices - 1)
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
    Linear(LinearSlices),
    Log(LogSlices),
}

/// A slicing's continuous slice coordinate of a depth: edge `k` of the grid sits near `k`.
///
/// One type per slicing, so that the z phase's pass over a block is built once for each (see
/// [`FramePlanes::slicing`]) with no `match` on the slicing inside its loop.
pub(crate) trait SliceCoordinate: Copy {
    fn of(&self, d: f32) -> f32;
}

/// `t = (d − n)·scale`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LinearSlices {
    near: f32,
    scale: f32,
}

impl SliceCoordinate for LinearSlices {
    #[inline(always)]
    fn of(&self, d: f32) -> f32 {
        (d - self.near) * self.scale
    }
}

/// `t = offset + (log₂ d − log₂ start)·scale` for `d ≥ start`, else 0.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LogSlices {
    start: f32,
    log2_start: f32,
    scale: f32,
    offset: f32,
}

impl SliceCoordinate for LogSlices {
    #[inline(always)]
    fn of(&self, d: f32) -> f32 {
        // Both sides computed and one selected, so that a pass over many depths vectorises.
        let t = self.offset + (log2_approx(d) - self.log2_start) * self.scale;
        if d < self.start { 0.0 } else { t }
    }
}

/// A frame's slice guess for one slicing, with the two numbers of the frame it also reads copied
/// out: a pass over a block holds it in locals and reads nothing else per light.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SliceGuesser<C> {
    coordinate: C,
    /// The sets' depth count (slices + 1).
    edges: usize,
    /// [`FramePlanes`]' `z_margin`.
    margin: f32,
}

impl<C: SliceCoordinate> SliceGuesser<C> {
    /// A guess of the partition point of `d` among the depths, and whether it is provably exact
    /// ([`exact_margin`]). Branch-free.
    #[inline(always)]
    pub fn guess(&self, d: f32) -> (u32, bool) {
        let t = self.coordinate.of(d);
        (
            clamp_index(t + 1.0, self.edges) as u32,
            clear_of_planes(t, self.margin),
        )
    }
}

/// A frame's slice guess, as the type of its slicing ([`FramePlanes::slicing`]).
pub(crate) enum Slicing {
    Linear(SliceGuesser<LinearSlices>),
    Log(SliceGuesser<LogSlices>),
}

/// The plane sets of one frame plus what is needed to guess positions in them.
pub(crate) struct FramePlanes<'a> {
    /// The plane values (the ground truth of every answer).
    pub sets: &'a PlaneSets,
    x_scale: f32,
    y_scale: f32,
    half_x: f32,
    half_y: f32,
    /// [`exact_margin`] of the column coordinates.
    x_margin: f32,
    /// [`exact_margin`] of the row coordinates.
    y_margin: f32,
    /// [`exact_margin`] of the slice coordinates, widened by the log's error ([`Self::new`]).
    z_margin: f32,
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
            DepthSlicing::Linear => SliceGuess::Linear(LinearSlices {
                near: n,
                scale: z / (f - n),
            }),
            DepthSlicing::Log => SliceGuess::Log(LogSlices {
                start: n,
                log2_start: n.log2(),
                scale: z / (f / n).log2(),
                offset: 0.0,
            }),
            DepthSlicing::LogWithNearSlice { first_slice_depth } if d.z > 1 => {
                SliceGuess::Log(LogSlices {
                    start: first_slice_depth,
                    log2_start: first_slice_depth.log2(),
                    scale: (z - 1.0) / (f / first_slice_depth).log2(),
                    offset: 1.0,
                })
            }
            DepthSlicing::LogWithNearSlice { .. } => SliceGuess::Linear(LinearSlices {
                near: n,
                scale: z / (f - n),
            }),
        };
        let mut planes = Self {
            sets,
            x_scale: d.x as f32 / (2.0 * tx),
            y_scale: d.y as f32 / (2.0 * ty),
            half_x: d.x as f32 / 2.0,
            half_y: d.y as f32 / 2.0,
            x_margin: f32::INFINITY,
            y_margin: f32::INFINITY,
            z_margin: f32::INFINITY,
            slice,
        };
        // Both coordinates must be monotone in the slope (a positive, finite scale) for the
        // margins to prove anything; otherwise they stay infinite and every answer is searched.
        if planes.x_scale > 0.0 && planes.x_scale.is_finite() {
            let coordinates = sets.x_slopes.iter().map(|&s| planes.column_coordinate(s));
            planes.x_margin = exact_margin(coordinates);
        }
        if planes.y_scale > 0.0 && planes.y_scale.is_finite() {
            let coordinates = sets.y_slopes.iter().map(|&s| planes.row_coordinate(s));
            planes.y_margin = exact_margin(coordinates);
        }
        planes.z_margin = planes.slice_margin(n, f);
        planes
    }

    /// [`exact_margin`] of the slice coordinates. A linear coordinate is monotone like the
    /// tiles'. The log one ([`log2_approx`]) need not be, so the margin proves against the exact
    /// `T(d) = offset + (log₂ d − log₂ start)·scale` instead: the computed coordinate lies within
    /// `E = scale·LOG2_APPROX_ERROR` plus rounding of `T`, which is monotone, at the planes and
    /// at the value alike, so twice that is added to the planes' own stray. A depth below
    /// `start` has coordinate 0, never clear of a plane, so it is always searched.
    ///
    /// The margin is that of the grid's own edges, from its `near` to its `far`, even where the
    /// sets' outer edges lie beyond them (open outer slices, [`myriad_cluster_math::OuterSlices`]):
    /// for a depth between the two, the guess counts one edge more or fewer below it than the
    /// sets do, and both answers clamp to the same outer slice.
    fn slice_margin(&self, near: f32, far: f32) -> f32 {
        let depths = &self.sets.z_depths;
        let inner = depths[1..depths.len() - 1].iter().copied();
        let edges = std::iter::once(near)
            .chain(inner)
            .chain(std::iter::once(far));
        let stray = exact_margin(edges.map(|d| self.slice_coordinate(d)));
        let ulp = |v: f32| v.next_up() - v;
        let usable = |v: f32| v > 0.0 && v.is_finite();
        match self.slice {
            SliceGuess::Linear(LinearSlices { scale, .. }) if usable(scale) => stray,
            SliceGuess::Log(LogSlices {
                start,
                log2_start,
                scale,
                ..
            }) if usable(scale) && start >= f32::MIN_POSITIVE && log2_start.is_finite() => {
                // Rounding of the three operations after the log (each within an ulp of the
                // largest coordinate, about `Z`) and of `log₂ start` itself.
                let rounding = 4.0 * ulp(depths.len() as f32 + 1.0)
                    + 4.0 * scale * ulp(log2_start.abs() + 1.0);
                let margin = stray + 2.0 * (scale * LOG2_APPROX_ERROR + rounding);
                if margin.is_finite() {
                    margin
                } else {
                    f32::INFINITY
                }
            }
            _ => f32::INFINITY,
        }
    }

    /// Continuous tile column of slope `v`: plane `i` sits near `i` (increasing in `v`).
    #[inline]
    fn column_coordinate(&self, v: f32) -> f32 {
        v * self.x_scale + self.half_x
    }

    /// Continuous tile row of slope `v`: plane `j` sits near `j` (decreasing in `v`).
    #[inline]
    fn row_coordinate(&self, v: f32) -> f32 {
        self.half_y - v * self.y_scale
    }

    /// Continuous slice coordinate of depth `d` (approximate).
    #[inline]
    fn slice_coordinate(&self, d: f32) -> f32 {
        match self.slice {
            SliceGuess::Linear(c) => c.of(d),
            SliceGuess::Log(c) => c.of(d),
        }
    }

    /// The frame's slice guess as the type of its slicing, for a pass over many depths (the z
    /// phase's, which runs once per slicing and so vectorises).
    #[inline]
    pub fn slicing(&self) -> Slicing {
        let (edges, margin) = (self.sets.z_depths.len(), self.z_margin);
        match self.slice {
            SliceGuess::Linear(coordinate) => Slicing::Linear(SliceGuesser {
                coordinate,
                edges,
                margin,
            }),
            SliceGuess::Log(coordinate) => Slicing::Log(SliceGuesser {
                coordinate,
                edges,
                margin,
            }),
        }
    }

    /// The slice holding depth `d`, clamped to `0..Z`: the last slice whose near edge is `<= d`.
    #[cfg(test)]
    pub fn slice_of(&self, d: f32) -> u32 {
        let (guess, proven) = self.slice_guess(d);
        self.slice_exact(d, guess, proven)
    }

    /// Branch-free first half of `Self::slice_of` (a test helper): a guess of the partition
    /// point, and whether it is provably exact ([`exact_margin`]).
    #[cfg(test)]
    pub fn slice_guess(&self, d: f32) -> (u32, bool) {
        match self.slicing() {
            Slicing::Linear(guesser) => guesser.guess(d),
            Slicing::Log(guesser) => guesser.guess(d),
        }
    }

    /// Second half of `Self::slice_of` (a test helper): the exact slice from any guess,
    /// searched unless the guess is `proven` exact. This is the *last* slice a depth band ending
    /// at `d` reaches.
    #[inline]
    pub fn slice_exact(&self, d: f32, guess: u32, proven: bool) -> u32 {
        let z = &self.sets.z_depths;
        let edges_below = if proven {
            guess
        } else {
            partition_from(z, guess as usize, |e| e <= d) as u32
        };
        slice_of_guess(edges_below, self.sets.z_depths.len() as u32 - 1)
    }

    /// The *first* slice a depth band starting at `d` reaches: the first whose far edge is
    /// `>= d`, clamped to `0..Z`, from the same guess as [`Self::slice_exact`].
    ///
    /// It differs from the slice holding `d` only when `d` lies exactly on an edge: then the
    /// closed slice ending there touches the band too, and so do slices of zero thickness (two
    /// equal f32 edges, as a very thin log grid rounds to). No pixel lands in those, but the f64
    /// oracle counts the contact, so skipping them would be a miss.
    #[inline]
    pub fn first_slice_exact(&self, d: f32, guess: u32, proven: bool) -> u32 {
        if proven {
            return first_slice_of_guess(guess, self.sets.z_depths.len() as u32 - 1);
        }
        let z = &self.sets.z_depths;
        let slices = z.len() - 1;
        let guess = (guess as usize).saturating_sub(1);
        partition_from(&z[1..], guess, |e| e < d).min(slices - 1) as u32
    }

    /// [`Self::first_slice_exact`] with its own guess.
    #[cfg(test)]
    pub fn first_slice(&self, d: f32) -> u32 {
        let (guess, proven) = self.slice_guess(d);
        self.first_slice_exact(d, guess, proven)
    }

    /// Tile columns `[first, last]` whose slope span `[s_i, s_{i+1}]` overlaps `[min, max]`.
    #[cfg(test)]
    pub fn columns(&self, min: f32, max: f32) -> Option<(u32, u32)> {
        let (first, after, proven) = self.columns_guess(min, max);
        self.columns_exact(min, max, (first, after), proven)
    }

    /// Branch-free first half of `Self::columns` (a test helper): the guessed partition points,
    /// and whether they are provably exact ([`exact_margin`]), in which case
    /// [`Self::columns_exact`] would return them unchanged and need not run.
    #[inline]
    pub fn columns_guess(&self, min: f32, max: f32) -> (u32, u32, bool) {
        let tiles = self.sets.x_slopes.len() - 1;
        let (lo, hi) = (self.column_coordinate(min), self.column_coordinate(max));
        (
            clamp_index(lo, tiles) as u32,
            clamp_index(hi + 1.0, tiles) as u32,
            clear_of_planes(lo, self.x_margin) & clear_of_planes(hi, self.x_margin),
        )
    }

    /// Second half of `Self::columns` (a test helper): exact from any guess, searched unless the
    /// guess is `proven` exact.
    #[inline]
    pub fn columns_exact(
        &self,
        min: f32,
        max: f32,
        guess: (u32, u32),
        proven: bool,
    ) -> Option<(u32, u32)> {
        let s = &self.sets.x_slopes;
        let tiles = s.len() - 1;
        // First tile whose right edge reaches `min`; tiles up to the last left edge `<= max`.
        let (first, after_last) = if proven {
            (guess.0 as usize, guess.1 as usize)
        } else {
            (
                partition_from(&s[1..], guess.0 as usize, |e| e < min),
                partition_from(&s[..tiles], guess.1 as usize, |e| e <= max),
            )
        };
        (first < after_last).then(|| (first as u32, after_last as u32 - 1))
    }

    /// Tile rows `[first, last]` (top → bottom) whose slope span `[s_{j+1}, s_j]` overlaps
    /// `[min, max]`.
    #[cfg(test)]
    pub fn rows(&self, min: f32, max: f32) -> Option<(u32, u32)> {
        let (first, after, proven) = self.rows_guess(min, max);
        self.rows_exact(min, max, (first, after), proven)
    }

    /// Branch-free first half of `Self::rows` (a test helper), with the same proof of exactness
    /// as [`Self::columns_guess`].
    #[inline]
    pub fn rows_guess(&self, min: f32, max: f32) -> (u32, u32, bool) {
        let rows = self.sets.y_slopes.len() - 1;
        let (top, bottom) = (self.row_coordinate(max), self.row_coordinate(min));
        (
            clamp_index(top, rows) as u32,
            clamp_index(bottom + 1.0, rows) as u32,
            clear_of_planes(top, self.y_margin) & clear_of_planes(bottom, self.y_margin),
        )
    }

    /// Second half of `Self::rows` (a test helper): exact from any guess, searched unless the
    /// guess is `proven` exact.
    #[inline]
    pub fn rows_exact(
        &self,
        min: f32,
        max: f32,
        guess: (u32, u32),
        proven: bool,
    ) -> Option<(u32, u32)> {
        let s = &self.sets.y_slopes;
        let rows = s.len() - 1;
        // First row whose bottom edge is `<= max`; rows up to the last top edge `>= min`.
        let (first, after_last) = if proven {
            (guess.0 as usize, guess.1 as usize)
        } else {
            (
                partition_from(&s[1..], guess.0 as usize, |e| e > max),
                partition_from(&s[..rows], guess.1 as usize, |e| e >= min),
            )
        };
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

    /// A random camera and grid of every slicing (`None` when the drawn near slice does not
    /// fit).
    fn random_frame(rng: &mut rand_pcg::Pcg64, case: usize) -> Option<(Camera, ClusterGrid)> {
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
        let near = 10f32.powf(rng.random_range(-4.0..1.0));
        let far = near * 10f32.powf(rng.random_range(0.01..7.0));
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
            return None;
        }
        Some((cam, ClusterGrid::new(dims, slicing, near, far)))
    }

    /// `v` and the values `2^k` ulps either side of it, up to 2¹⁵: a guess's margin spans
    /// thousands of ulps, so these reach past it on both sides.
    fn around(v: f32) -> impl Iterator<Item = f32> {
        let bits = v.to_bits() as i64;
        std::iter::once(v).chain((0..16).flat_map(move |k| {
            [bits - (1 << k), bits + (1 << k)]
                .into_iter()
                .filter(|b| (0..=u32::MAX as i64).contains(b))
                .map(|b| f32::from_bits(b as u32))
                .filter(|x| x.is_finite())
        }))
    }

    /// Whenever a guess claims to be exact it is the partition point, on values crowding every
    /// plane from both sides (where a wrong claim would sit) and across the range; and on these
    /// ordinary grids the claim holds for most values, so the searches are really skipped.
    #[test]
    fn proven_guesses_are_the_partition_points() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(41);
        let (mut claims, mut drawn) = (0usize, 0usize);
        for case in 0..300 {
            let Some((cam, grid)) = random_frame(&mut rng, case) else {
                continue;
            };
            let sets = PlaneSets::new(&cam, &grid);
            let fp = FramePlanes::new(&sets, &grid);
            let t = cam.tan_half_fov();
            let random: Vec<f32> = (0..200)
                .map(|_| rng.random_range(-1.5f32..1.5) * t.x.max(t.y))
                .collect();
            let crowd = sets.x_slopes.iter().chain(&sets.y_slopes);
            let slopes: Vec<f32> = crowd
                .flat_map(|&s| around(s))
                .chain(random.clone())
                .collect();
            for &v in &slopes {
                let (g0, g1, proven) = fp.columns_guess(v, v);
                if proven {
                    let tiles = sets.x_slopes.len() - 1;
                    let first = sets.x_slopes[1..].partition_point(|&e| e < v);
                    let after = sets.x_slopes[..tiles].partition_point(|&e| e <= v);
                    assert_eq!(
                        (g0 as usize, g1 as usize),
                        (first, after),
                        "x {v} in {grid:?}"
                    );
                }
                let (g0, g1, proven) = fp.rows_guess(v, v);
                if proven {
                    let rows = sets.y_slopes.len() - 1;
                    let first = sets.y_slopes[1..].partition_point(|&e| e > v);
                    let after = sets.y_slopes[..rows].partition_point(|&e| e >= v);
                    assert_eq!(
                        (g0 as usize, g1 as usize),
                        (first, after),
                        "y {v} in {grid:?}"
                    );
                }
            }
            let (near, far) = (grid.near(), grid.far());
            let random: Vec<f32> = (0..200)
                .map(|_| near * (far / near).powf(rng.random_range(0.0f32..1.0)))
                .collect();
            let depths = sets.z_depths.iter().flat_map(|&d| around(d));
            let slices = sets.z_depths.len() - 1;
            for d in depths.chain(random.iter().copied()) {
                // The phases ask only about depths inside `[near, far]` (bands are clamped).
                let d = d.clamp(near, far);
                let (guess, proven) = fp.slice_guess(d);
                if proven {
                    let edges_below = sets.z_depths.partition_point(|&e| e <= d);
                    assert_eq!(guess as usize, edges_below, "depth {d} in {grid:?}");
                    let first = sets.z_depths[1..]
                        .partition_point(|&e| e < d)
                        .min(slices - 1);
                    assert_eq!(fp.first_slice_exact(d, guess, true), first as u32);
                }
            }
            if grid.dims().min_element() >= 8 && far / near < 1e5 {
                for &v in &random {
                    drawn += 3;
                    claims += fp.slice_guess(v).1 as usize;
                }
                let slopes = (0..200).map(|_| rng.random_range(-1.0f32..1.0));
                for v in slopes {
                    claims += fp.columns_guess(v * t.x, v * t.x).2 as usize;
                    claims += fp.rows_guess(v * t.y, v * t.y).2 as usize;
                }
            }
        }
        assert!(
            claims as f64 > 0.97 * drawn as f64,
            "{claims} of {drawn} random guesses proven exact"
        );
    }

    /// Each term of the margins is there: a plane's own stray, the slack, the log's error (the
    /// proptests cannot tell them apart, since any one covers ordinary grids alone).
    #[test]
    fn margins_cover_the_planes_stray_and_the_logs_error() {
        let slack = exact_margin([0.0f32, 1.0, 2.0].into_iter());
        assert!((1.0 / 1024.0..0.002).contains(&slack), "slack {slack}");
        let strayed = exact_margin([0.0f32, 1.25, 2.0].into_iter());
        assert!(
            strayed >= 0.25 + slack * 0.99 && strayed < 0.26,
            "{strayed}"
        );
        assert_eq!(exact_margin([0.0f32, f32::NAN].into_iter()), f32::INFINITY);
        assert_eq!(exact_margin((0..1 << 22).map(|i| i as f32)), f32::INFINITY);
        let cam = Camera::new(
            Vec3::ZERO,
            Vec3::NEG_Z,
            Vec3::Y,
            60.0,
            1920,
            1080,
            0.1,
            100.0,
        );
        for (slicing, dims) in [
            (DepthSlicing::Log, UVec3::new(16, 9, 24)),
            (DepthSlicing::Log, UVec3::new(16, 9, 128)),
            (DepthSlicing::Linear, UVec3::new(16, 9, 24)),
        ] {
            let grid = ClusterGrid::new(dims, slicing, 0.1, 100.0);
            let sets = PlaneSets::new(&cam, &grid);
            let fp = FramePlanes::new(&sets, &grid);
            let log_error = match fp.slice {
                SliceGuess::Log(LogSlices { scale, .. }) => 2.0 * scale * LOG2_APPROX_ERROR,
                SliceGuess::Linear(_) => 0.0,
            };
            assert!(
                fp.z_margin >= log_error + slack,
                "{slicing:?} {dims}: {}",
                fp.z_margin
            );
            assert!(
                fp.z_margin < 0.1,
                "{slicing:?} {dims}: {} proves little",
                fp.z_margin
            );
            assert!((slack..0.002).contains(&fp.x_margin));
            assert!((slack..0.002).contains(&fp.y_margin));
        }
    }

    /// The planes' largest stray is rounded *up* to f32 before the slack is added: plane 1 at
    /// coordinate `0.1` strays by `1 − 0.1f32`, which f32 cannot hold and rounds *down* to
    /// nearest, so a margin rounded to nearest would sit below the stray it must cover.
    #[test]
    fn exact_margin_rounds_the_planes_stray_up() {
        let stray = 1.0 - f64::from(0.1f32);
        let nearest = stray as f32;
        assert!(
            f64::from(nearest) < stray,
            "the stray must round down to nearest"
        );
        // Slack 2⁻¹⁰ (two planes); the sum and this difference are exact in f32.
        let margin = exact_margin([0.0f32, 0.1].into_iter());
        assert_eq!(margin - 1.0 / 1024.0, nearest.next_up());
        assert!(f64::from(margin - 1.0 / 1024.0) >= stray);
    }

    /// Past 2¹² planes the slack is 4 ulps of the largest index a guess may compute, two past
    /// the last plane's (see [`exact_margin`]): 8190 planes reach 8192 = 2¹³, whose ulp is 2⁻¹⁰,
    /// so their slack is 2⁻⁸; one plane fewer stays below 2¹³ (2⁻⁹), and 4093 below 2¹² get
    /// the floor of 2⁻¹⁰.
    #[test]
    fn exact_margin_slack_is_four_ulps_of_the_largest_guess() {
        assert_eq!(exact_margin((0..8190).map(|i| i as f32)), 1.0 / 256.0);
        assert_eq!(exact_margin((0..8189).map(|i| i as f32)), 1.0 / 512.0);
        assert_eq!(exact_margin((0..4093).map(|i| i as f32)), 1.0 / 1024.0);
    }

    /// [`LOG2_APPROX_ERROR`] bounds the approximation on every mantissa of the extreme exponents
    /// (its worst, where the final subtractions round coarsest) and of the unit binades.
    #[test]
    fn log2_approx_stays_within_its_error_bound() {
        let mut worst = 0.0f64;
        for exponent in [-126i32, -1, 0, 1, 126, 127] {
            for mantissa in 0..1u32 << 23 {
                let x = f32::from_bits((((exponent + 127) as u32) << 23) | mantissa);
                worst = worst.max((log2_approx(x) as f64 - (x as f64).log2()).abs());
            }
        }
        assert!(
            worst < 0.8 * LOG2_APPROX_ERROR as f64,
            "log2_approx strays {worst:e} from log2: the bound {LOG2_APPROX_ERROR:e} needs headroom"
        );
    }

    #[test]
    fn guided_search_equals_binary_search() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        for case in 0..300 {
            let Some((cam, grid)) = random_frame(&mut rng, case) else {
                continue;
            };
            let (dims, near, far) = (grid.dims(), grid.near(), grid.far());
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
                    let (g0, g1, _) = fp.columns_guess(lo, hi);
                    let tiles = sets.x_slopes.len() - 1;
                    let first = sets.x_slopes[1..].partition_point(|&e| e < lo);
                    let after = sets.x_slopes[..tiles].partition_point(|&e| e <= hi);
                    assert!(
                        (g0 as usize).abs_diff(first) <= 1 && (g1 as usize).abs_diff(after) <= 1,
                        "x [{lo}, {hi}]: guess ({g0}, {g1}), partition points ({first}, {after})"
                    );
                    let (g0, g1, _) = fp.rows_guess(lo, hi);
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
                let guess = fp.slice_guess(d).0 as usize;
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
