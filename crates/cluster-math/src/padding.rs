//! The one allowance for f32 rounding in "does this light's sphere touch that volume".
//!
//! Every fast f32 test of a light against planes (the assignment's phases, the frame systems'
//! frustum cull) brings the centre to view space and compares dot products with the radius. Each
//! step rounds by about 1e-7 of the magnitudes in play, so a light the f64 oracle sees touching a
//! plane by less than that could be judged outside and lost. Growing the radius by
//! [`RADIUS_PAD`] of the light's view-space extent absorbs all of it, and with one shared pad the
//! cull in front of the assignment can never drop a light the assignment would keep. (A light
//! whose padded radius overflows f32 — a radius near `f32::MAX`, an offset from the camera past
//! it — cannot be judged in f32: the assignment decides it in f64, and the scene cull keeps it.)

/// Relative padding of light radii: 4e-6 of the light's view-space extent, about 34–67 f32 ulps
/// of it (a ulp is 2⁻²³–2⁻²⁴ of a value).
pub const RADIUS_PAD: f32 = 4.0e-6;

/// The light's radius grown so that f32 rounding can never shrink its footprint below the exact
/// f64 one: `r + RADIUS_PAD·(|cx| + |cy| + |dc| + r)`, for a view-space centre `(cx, cy)` at
/// depth `dc` (the sum bounds the length `|c|` from above).
#[inline]
pub fn pad_radius(cx: f32, cy: f32, dc: f32, r: f32) -> f32 {
    let extent = cx.abs() + cy.abs() + dc.abs() + r;
    r + RADIUS_PAD * extent
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pad_is_a_fixed_fraction_of_the_view_space_extent() {
        // |cx| + |cy| + |dc| + r = 3 + 4 + 12 + 1 = 20, whatever the signs.
        assert_eq!(pad_radius(-3.0, 4.0, 12.0, 1.0), 1.0 + RADIUS_PAD * 20.0);
        assert_eq!(pad_radius(3.0, -4.0, -12.0, 1.0), 1.0 + RADIUS_PAD * 20.0);
        // At the eye only the radius itself is padded.
        assert_eq!(pad_radius(0.0, 0.0, 0.0, 2.0), 2.0 * (1.0 + RADIUS_PAD));
    }

    #[test]
    fn a_small_far_light_is_padded_by_many_ulps_of_its_depth() {
        // A light 1e-3 wide a million units deep: each f32 step of its transform rounds by half
        // an ulp of 1e6 (0.03), thirty times its radius; the pad must dwarf that.
        let (depth, r) = (1.0e6f32, 1.0e-3f32);
        let ulp = depth.next_up() - depth;
        let pad = pad_radius(0.0, 0.0, depth, r) - r;
        assert!(pad >= 32.0 * ulp, "pad {pad} vs ulp {ulp}");
        assert!(
            pad <= 128.0 * ulp,
            "pad {pad} is not a few dozen ulps of {depth}"
        );
    }
}
