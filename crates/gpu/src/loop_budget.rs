//! How many lights one pixel may loop over where the adapter caps shader loops.
//!
//! Mesa's llvmpipe ends an invocation's loops after a fixed number of iterations *in all*
//! (`LP_MAX_TGSI_LOOP_ITERATIONS` = 65 535, one counter shared by every loop of the
//! invocation), and a light past that is dropped without any error. Measured on llvmpipe with
//! every light at one point and only the last one bright, the guard below lifted by hand:
//! - one depth slice (no search loop): the last of 65 534 lights is shown, of 65 535 it is lost;
//! - 16 slices, whose `slice_of_depth` binary search (`shaders/common/cluster.wgsl`) runs first
//!   and goes round at most 4 times: 65 530 are shown, 65 531 lose light.
//!
//! So the budget is 65 534 loop iterations, and each time the search goes round takes one light
//! away. A frame that could exceed it at any pixel is refused (never drawn wrong).
//! `tests/gpu_loop_budget.rs` pins both sides with the guard in place: exactly at the budget the
//! last light shows (a bound one too large fails there, the lost light is seen), one light more
//! is refused.

use crate::ShadingMode;

/// The most lights one pixel may loop over in `mode` on a grid of `slices` depth slices, where
/// the adapter's loop counter starts at `limit` (65 535 on llvmpipe).
pub fn max_lights_per_pixel(limit: u64, mode: ShadingMode, slices: u32) -> u64 {
    let search = match mode {
        ShadingMode::Lists => slice_search_rounds(slices),
        ShadingMode::BruteForce => 0,
    };
    limit.saturating_sub(1 + search)
}

/// Worst-case times `slice_of_depth`'s loop goes round for `slices` slices: never when it
/// returns before its loop (one or two slices, or a depth outside the inner edges); otherwise
/// each round halves `lo..hi` (from `1..slices - 1`), at worst keeping the larger half, until
/// one slice is left.
pub fn slice_search_rounds(slices: u32) -> u64 {
    let mut width = slices.saturating_sub(2);
    let mut rounds = 0u64;
    while width > 1 {
        width = width.div_ceil(2);
        rounds += 1;
    }
    rounds
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `slice_of_depth`'s loop as the shader runs it, counting the rounds that go on:
    /// `depth_rank` picks which inner edge the depth sits at or above (`0` below edge 1 …
    /// `slices - 1` beyond the last).
    fn shader_search_rounds(slices: u32, depth_rank: u32) -> u64 {
        if slices == 1 || depth_rank < 1 || depth_rank >= slices - 1 {
            return 0;
        }
        let (mut lo, mut hi, mut rounds) = (1u32, slices - 1, 0);
        loop {
            if hi - lo <= 1 {
                break;
            }
            rounds += 1;
            let mid = (lo + hi) / 2;
            if depth_rank >= mid {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        assert_eq!(lo, depth_rank, "the search finds the slice");
        rounds
    }

    #[test]
    fn the_search_bound_is_the_shader_loops_worst_case() {
        for slices in 1..=300 {
            let worst = (0..slices)
                .map(|rank| shader_search_rounds(slices, rank))
                .max()
                .unwrap();
            assert_eq!(slice_search_rounds(slices), worst, "{slices} slices");
        }
    }

    #[test]
    fn budgets_match_the_llvmpipe_measurements() {
        assert_eq!(max_lights_per_pixel(65_535, ShadingMode::Lists, 1), 65_534);
        assert_eq!(
            max_lights_per_pixel(65_535, ShadingMode::BruteForce, 16),
            65_534
        );
        assert_eq!(max_lights_per_pixel(65_535, ShadingMode::Lists, 16), 65_530);
        assert_eq!(max_lights_per_pixel(3, ShadingMode::Lists, 1000), 0);
    }
}
