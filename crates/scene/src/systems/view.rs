//! Lights to view space: the last frame system, gathering the visible lights into view-space
//! columns for the assignment and the shaders.
//!
//! Why its own pass: positions are brought to view space **camera-relative** — the eye is
//! subtracted in world space before rotating, exactly as [`Camera::view_from_world_point`]
//! does — so a light 5 m from a camera at 10⁶ m keeps millimetre precision, which a 4×4
//! `view_from_world` matrix in f32 would lose. The output rows are compacted (only the
//! visible lights, when an index list is given) and keep their source index, so results
//! computed on them refer back to the input columns.

use super::{BLOCK, LightSlices, PARALLEL_MIN};
use glam::Vec3;
use myriad_cluster_math::Camera;
use rayon::prelude::*;

/// View-space light columns (right-handed, camera looking down −Z), one row per selected light.
/// The spot columns are empty when the input has none.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ViewLights {
    /// View-space x.
    pub x: Vec<f32>,
    /// View-space y.
    pub y: Vec<f32>,
    /// View-space z (negative in front of the camera).
    pub z: Vec<f32>,
    /// Range, unchanged.
    pub radius: Vec<f32>,
    /// View-space spot axis x.
    pub spot_dir_x: Vec<f32>,
    /// View-space spot axis y.
    pub spot_dir_y: Vec<f32>,
    /// View-space spot axis z.
    pub spot_dir_z: Vec<f32>,
    /// Outer half angle, unchanged.
    pub spot_angle: Vec<f32>,
    /// Each row's index in the input columns.
    pub source: Vec<u32>,
}

impl ViewLights {
    /// Empty columns.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }
}

/// Writes the lights named by `indices` (all lights, in order, when `None`) to `out` in view
/// space. Indices must be in range. Parallel in blocks above [`super::PARALLEL_MIN`] rows; the
/// result does not depend on the thread count.
pub fn lights_to_view(
    camera: &Camera,
    lights: LightSlices<'_>,
    indices: Option<&[u32]>,
    out: &mut ViewLights,
) {
    crate::profiling::profile_span!("lights to view");
    lights.assert_consistent();
    let n = lights.len();
    let rows = indices.map_or(n, <[u32]>::len);
    if let Some(indices) = indices {
        assert!(
            indices.iter().all(|&i| (i as usize) < n),
            "index out of range"
        );
    }
    let rotation = camera.view_rotation();
    let eye = camera.position;
    let spot_rows = if lights.spot.is_some() { rows } else { 0 };
    for column in [&mut out.x, &mut out.y, &mut out.z, &mut out.radius] {
        column.resize(rows, 0.0);
    }
    for column in [
        &mut out.spot_dir_x,
        &mut out.spot_dir_y,
        &mut out.spot_dir_z,
        &mut out.spot_angle,
    ] {
        column.resize(spot_rows, 0.0);
    }
    out.source.resize(rows, 0);
    match indices {
        Some(indices) => out.source.copy_from_slice(indices),
        None => {
            for (k, s) in out.source.iter_mut().enumerate() {
                *s = k as u32;
            }
        }
    }
    // Positions and radii of the rows `source` (gathered: rows need not be contiguous). The
    // arithmetic is `Camera::view_from_world_point`'s, which the tests hold it to bit for bit.
    let positions = |source: &[u32], x: &mut [f32], y: &mut [f32], z: &mut [f32], r: &mut [f32]| {
        let m = source.len();
        let (x, y, z, r) = (&mut x[..m], &mut y[..m], &mut z[..m], &mut r[..m]);
        for k in 0..m {
            let i = source[k] as usize;
            let p = rotation * (Vec3::new(lights.x[i], lights.y[i], lights.z[i]) - eye);
            (x[k], y[k], z[k], r[k]) = (p.x, p.y, p.z, lights.radius[i]);
        }
    };
    let axes = |source: &[u32], dx: &mut [f32], dy: &mut [f32], dz: &mut [f32], a: &mut [f32]| {
        let Some(s) = &lights.spot else { return };
        let m = source.len();
        let (dx, dy, dz, a) = (&mut dx[..m], &mut dy[..m], &mut dz[..m], &mut a[..m]);
        for k in 0..m {
            let i = source[k] as usize;
            let d = rotation * Vec3::new(s.dir_x[i], s.dir_y[i], s.dir_z[i]);
            (dx[k], dy[k], dz[k], a[k]) = (d.x, d.y, d.z, s.angle[i]);
        }
    };
    if rows < PARALLEL_MIN {
        positions(
            &out.source,
            &mut out.x,
            &mut out.y,
            &mut out.z,
            &mut out.radius,
        );
        axes(
            &out.source,
            &mut out.spot_dir_x,
            &mut out.spot_dir_y,
            &mut out.spot_dir_z,
            &mut out.spot_angle,
        );
    } else {
        (
            out.source.par_chunks(BLOCK),
            out.x.par_chunks_mut(BLOCK),
            out.y.par_chunks_mut(BLOCK),
            out.z.par_chunks_mut(BLOCK),
            out.radius.par_chunks_mut(BLOCK),
        )
            .into_par_iter()
            .for_each(|(s, x, y, z, r)| positions(s, x, y, z, r));
        if spot_rows > 0 {
            (
                out.source.par_chunks(BLOCK),
                out.spot_dir_x.par_chunks_mut(BLOCK),
                out.spot_dir_y.par_chunks_mut(BLOCK),
                out.spot_dir_z.par_chunks_mut(BLOCK),
                out.spot_angle.par_chunks_mut(BLOCK),
            )
                .into_par_iter()
                .for_each(|(s, dx, dy, dz, a)| axes(s, dx, dy, dz, a));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lights::{LightRecord, Lights};
    use crate::systems::{Visibility, cull_lights};

    fn lights(n: usize) -> Lights {
        (0..n)
            .map(|i| {
                let t = i as f32;
                let light = LightRecord::point(
                    Vec3::new((t * 0.37).sin() * 30.0, (t * 0.11).cos() * 5.0, -(t % 50.0)),
                    1.0 + (i % 7) as f32,
                );
                if i % 3 == 0 {
                    light.with_spot(Vec3::new(0.0, -0.6, 0.8), 0.4)
                } else {
                    light
                }
            })
            .collect()
    }

    #[test]
    fn matches_the_cameras_view_transform_bit_for_bit() {
        let camera = Camera::new(
            Vec3::new(1.0e5, 2.0, -3.0e5),
            Vec3::new(1.0e5 + 1.0, 1.5, -3.0e5 - 2.0),
            Vec3::Y,
            60.0,
            1920,
            1080,
            0.1,
            100.0,
        );
        let mut world = lights(3 * BLOCK + 5);
        for x in &mut world.x {
            *x += 1.0e5;
        }
        for z in &mut world.z {
            *z -= 3.0e5;
        }
        let mut out = ViewLights::new();
        lights_to_view(&camera, world.slices(), None, &mut out);
        assert_eq!(out.len(), world.len());
        let rotation = camera.view_rotation();
        for i in 0..world.len() {
            let l = world.get(i);
            let v = camera.view_from_world_point(l.position);
            assert_eq!(Vec3::new(out.x[i], out.y[i], out.z[i]), v);
            assert_eq!(out.radius[i], l.radius);
            assert_eq!(out.source[i], i as u32);
            let d = l.spot.map_or(Vec3::ZERO, |c| rotation * c.direction);
            assert_eq!(
                Vec3::new(out.spot_dir_x[i], out.spot_dir_y[i], out.spot_dir_z[i]),
                d
            );
            assert_eq!(out.spot_angle[i], world.spot_angle[i]);
        }
    }

    #[test]
    fn gathers_the_visible_lights_in_order() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 50.0, 800, 600, 0.5, 30.0);
        let world = lights(20_000);
        let mut vis = Visibility::new();
        let visible = cull_lights(&camera, world.slices(), &mut vis);
        assert!(visible > 100 && visible < 20_000);
        let mut out = ViewLights::new();
        lights_to_view(&camera, world.slices(), Some(&vis.indices), &mut out);
        assert_eq!(out.source, vis.indices);
        for (k, &i) in vis.indices.iter().enumerate() {
            let v = camera.view_from_world_point(world.get(i as usize).position);
            assert_eq!(Vec3::new(out.x[k], out.y[k], out.z[k]), v);
            // Visible lights reach depths in front of the far plane.
            assert!(-out.z[k] - out.radius[k] <= 30.0);
        }
        // Point lights only: the spot columns stay empty.
        let points: Lights = world
            .iter()
            .map(|mut l| {
                l.spot = None;
                l
            })
            .collect();
        lights_to_view(&camera, points.slices(), Some(&vis.indices[..10]), &mut out);
        assert_eq!(out.len(), 10);
        assert!(out.spot_angle.is_empty() && out.spot_dir_x.is_empty());
    }

    #[test]
    fn rows_are_counted() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 50.0, 800, 600, 0.5, 30.0);
        let mut out = ViewLights::new();
        assert!(out.is_empty());
        lights_to_view(&camera, lights(3).slices(), None, &mut out);
        assert_eq!((out.len(), out.is_empty()), (3, false));
    }

    #[test]
    #[should_panic]
    fn columns_of_different_lengths_are_refused() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 50.0, 800, 600, 0.5, 30.0);
        let world = lights(3);
        let radius = [1.0; 4];
        let slices = LightSlices {
            radius: &radius,
            ..world.slices()
        };
        lights_to_view(&camera, slices, None, &mut ViewLights::new());
    }
}
