//! Lights evaluated per pixel, from the depth buffer and the lists: the numbers behind the heat
//! map and the "lighting calculations skipped" figure.
//!
//! A pixel with geometry (stored depth > 0: reversed Z clears to 0) evaluates every light of its cluster (clustered, tiled) or
//! every light (brute force); background pixels evaluate none in either case.

use myriad_scene::{Camera, ClusterGrid};
use serde::Serialize;

/// Lights-per-pixel summary of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PixelStats {
    /// Pixels with geometry.
    pub covered_pixels: u64,
    /// Light evaluations over all covered pixels.
    pub evaluations: u64,
    /// The same frame shaded brute force: covered pixels × lights.
    pub brute_force_evaluations: u64,
    /// Mean lights evaluated per covered pixel.
    pub mean_lights: f64,
    /// Most lights evaluated at one pixel.
    pub max_lights: u32,
    /// Fraction of the brute-force evaluations not done.
    pub skipped_fraction: f64,
}

/// Counts evaluations for a `camera.width × camera.height` depth buffer shaded with lists whose
/// per-cluster sizes are `counts` (for `grid`), out of `lights` lights.
pub fn pixel_stats(
    depth: &[f32],
    camera: &Camera,
    grid: &ClusterGrid,
    counts: &[u32],
    lights: usize,
) -> PixelStats {
    let (w, h) = (camera.width, camera.height);
    assert_eq!(depth.len(), (w * h) as usize, "depth buffer size");
    let mut s = PixelStats::default();
    for py in 0..h {
        for px in 0..w {
            let d = depth[(py * w + px) as usize];
            if d <= 0.0 {
                continue; // Reversed Z: nothing drawn.
            }
            let view_depth = camera.view_depth_from_ndc_depth(d);
            let n = counts[grid.cluster_of_pixel(px, py, view_depth, w, h) as usize];
            s.covered_pixels += 1;
            s.evaluations += n as u64;
            s.max_lights = s.max_lights.max(n);
        }
    }
    s.brute_force_evaluations = s.covered_pixels * lights as u64;
    if s.covered_pixels > 0 {
        s.mean_lights = s.evaluations as f64 / s.covered_pixels as f64;
    }
    if s.brute_force_evaluations > 0 {
        s.skipped_fraction = 1.0 - s.evaluations as f64 / s.brute_force_evaluations as f64;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use myriad_scene::DepthSlicing;
    use myriad_scene::glam::{UVec3, Vec3};

    #[test]
    fn counts_per_covered_pixel() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 4, 2, 0.1, 10.0);
        let grid = ClusterGrid::new(UVec3::new(2, 1, 2), DepthSlicing::Linear, 0.1, 10.0);
        // Clusters: (0,0,0)=0, (1,0,0)=1, (0,0,1)=2, (1,0,1)=3.
        let counts = [1, 2, 3, 4];
        // Row 0: near left, near left, near right, background; row 1: background but the last
        // pixel, deep into the second slice. Stored depths are reversed Z: 1 at near, 0 for
        // nothing drawn.
        let near = 1.0;
        let far = camera.ndc_depth_from_view_depth(9.0) as f32;
        let depth = [near, near, near, 0.0, 0.0, 0.0, 0.0, far];
        let s = pixel_stats(&depth, &camera, &grid, &counts, 10);
        assert_eq!(s.covered_pixels, 4);
        assert_eq!(s.evaluations, 1 + 1 + 2 + 4);
        assert_eq!(s.max_lights, 4);
        assert_eq!(s.brute_force_evaluations, 40);
        assert!((s.skipped_fraction - (1.0 - 8.0 / 40.0)).abs() < 1e-12);
    }

    #[test]
    fn the_mean_is_evaluations_per_covered_pixel() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 2, 1, 0.1, 10.0);
        let grid = ClusterGrid::new(UVec3::new(2, 1, 1), DepthSlicing::Linear, 0.1, 10.0);
        // Left pixel in a cluster of 1 light, right one in a cluster of 6: 7 over 2 pixels.
        let s = pixel_stats(&[1.0, 1.0], &camera, &grid, &[1, 6], 8);
        assert_eq!((s.covered_pixels, s.evaluations, s.max_lights), (2, 7, 6));
        assert_eq!(s.mean_lights, 3.5);
        assert_eq!(s.skipped_fraction, 1.0 - 7.0 / 16.0);
    }

    #[test]
    fn a_frame_of_background_counts_nothing_and_skips_nothing() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 2, 2, 0.1, 10.0);
        let grid = ClusterGrid::new(UVec3::new(2, 1, 2), DepthSlicing::Linear, 0.1, 10.0);
        let s = pixel_stats(&[0.0; 4], &camera, &grid, &[1, 2, 3, 4], 10);
        // No pixel, so no mean and no saving: zeros, not 0 / 0.
        assert_eq!(s, PixelStats::default());
    }
}
