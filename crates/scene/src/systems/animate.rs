//! Animation systems: lights orbiting a vertical axis, and lights wandering inside a box.
//!
//! Both move positions in place and are deterministic per light, so they parallelise without
//! changing results. Orbits are a closed-form function of absolute time (no drift, any frame
//! can be computed directly, and time is f64 with each light's turn reduced in f64 before the
//! f32 angle, so the animation neither freezes nor degrades however long a run lasts);
//! wandering is a random walk integrated frame by frame, its random
//! steps drawn from a hash of (seed, frame, light index) instead of a shared generator.

use super::{BLOCK, PARALLEL_MIN, fast_sin_cos};
use crate::model::Aabb;
use glam::Vec3;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;

/// Orbit components, one row per light: light `i` circles the vertical axis through
/// `(center_x[i], ·, center_z[i])` at distance `orbit_radius[i]`, at `angular_speed[i]` rad/s
/// (negative: clockwise seen from above), at angle `phase[i]` at time 0. Its height is not
/// touched.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Orbits {
    /// Axis x.
    pub center_x: Vec<f32>,
    /// Axis z.
    pub center_z: Vec<f32>,
    /// Distance from the axis.
    pub orbit_radius: Vec<f32>,
    /// Radians per second.
    pub angular_speed: Vec<f32>,
    /// Angle at time 0 (radians, measured from +X towards +Z).
    pub phase: Vec<f32>,
}

impl Orbits {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.center_x.len()
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.center_x.is_empty()
    }

    /// Orbits about the vertical axis through `center` that pass through each light's current
    /// position (so time 0 leaves the lights where they are), with speeds uniform in
    /// `[min, max)` rad/s and a random direction, drawn from `seed`.
    pub fn around(center: Vec3, x: &[f32], z: &[f32], speed: [f32; 2], seed: u64) -> Self {
        assert_eq!(x.len(), z.len());
        assert!(speed[0] <= speed[1]);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let mut o = Self::default();
        for (&x, &z) in x.iter().zip(z) {
            let (dx, dz) = (x - center.x, z - center.z);
            let s = if speed[0] < speed[1] {
                rng.random_range(speed[0]..speed[1])
            } else {
                speed[0]
            };
            let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            o.center_x.push(center.x);
            o.center_z.push(center.z);
            o.orbit_radius.push((dx * dx + dz * dz).sqrt());
            o.angular_speed.push(sign * s);
            o.phase.push(dz.atan2(dx));
        }
        o
    }
}

/// One light's orbit position `(x, z)` at `time`: the kernel of [`animate_orbits`].
#[inline(always)] // Into both builds of `orbit_block`.
fn orbit_point(cx: f32, cz: f32, radius: f32, speed: f32, phase: f32, time: f64) -> (f32, f32) {
    let (s, c) = fast_sin_cos(phase + turned_angle(speed, time));
    (cx + radius * c, cz + radius * s)
}

/// `speed · time` reduced to [−π, π], in f64 so that it keeps advancing for any realistic run
/// (an f32 `speed · time` has a step of 0.016 rad at 10⁵ rad, and an f32 time stops at 2²⁴
/// frames). Rounds the turn count by the 1.5·2⁵² trick (no rounding call, so the loop still
/// vectorises); exact while `|speed · time| < 2⁵¹` turns, within 1e-6 rad below 10¹⁰ rad.
#[inline(always)]
fn turned_angle(speed: f32, time: f64) -> f32 {
    const ROUND: f64 = 6_755_399_441_055_744.0; // 1.5 · 2⁵²
    let turns = speed as f64 * time * (1.0 / std::f64::consts::TAU);
    let fraction = turns - ((turns + ROUND) - ROUND);
    (fraction * std::f64::consts::TAU) as f32
}

/// The orbit positions of the block of lights from `start` (`x.len()` of them). Built twice, for
/// AVX2 and for the baseline, the faster picked at run time; both compute the same numbers (no
/// fused multiply-add: Rust never contracts one). `cargo bench --bench scene_systems --
/// frame/`: see `docs/measured.md`.
#[multiversion::multiversion(targets("x86_64+avx+avx2+fma"))]
fn orbit_block(orbits: &Orbits, time: f64, start: usize, x: &mut [f32], z: &mut [f32]) {
    let end = start + x.len();
    let (cx, cz) = (&orbits.center_x[start..end], &orbits.center_z[start..end]);
    let (radius, speed) = (
        &orbits.orbit_radius[start..end],
        &orbits.angular_speed[start..end],
    );
    let (phase, z) = (&orbits.phase[start..end], &mut z[..x.len()]);
    // Re-sliced columns: the loop has no bounds checks and vectorises.
    for k in 0..x.len() {
        (x[k], z[k]) = orbit_point(cx[k], cz[k], radius[k], speed[k], phase[k], time);
    }
}

/// Sets each light's `x` and `z` to its orbit position at `time` (seconds since time 0). The
/// angle `phase + speed · time` is reduced per light in f64, so positions stay within a few
/// micrometres of the exact orbit on a 10 m radius at any time a program can reach.
pub fn animate_orbits(orbits: &Orbits, time: f64, x: &mut [f32], z: &mut [f32]) {
    crate::profiling::profile_span!("animate orbits");
    let n = orbits.len();
    assert!(x.len() == n && z.len() == n, "one orbit per light");
    assert!(
        orbits.center_z.len() == n
            && orbits.orbit_radius.len() == n
            && orbits.angular_speed.len() == n
            && orbits.phase.len() == n
    );
    let block = |start: usize, x: &mut [f32], z: &mut [f32]| orbit_block(orbits, time, start, x, z);
    if n < PARALLEL_MIN {
        block(0, x, z);
    } else {
        (x.par_chunks_mut(BLOCK), z.par_chunks_mut(BLOCK))
            .into_par_iter()
            .enumerate()
            .for_each(|(b, (x, z))| block(b * BLOCK, x, z));
    }
}

/// Wander components: a velocity per light, and the box all lights stay in.
#[derive(Clone, Debug, PartialEq)]
pub struct Wander {
    /// Velocity x (m/s).
    pub vx: Vec<f32>,
    /// Velocity y (m/s).
    pub vy: Vec<f32>,
    /// Velocity z (m/s).
    pub vz: Vec<f32>,
    /// The box lights bounce off (they must start inside it).
    pub bounds: Aabb,
    /// Speed limit (m/s, > 0).
    pub max_speed: f32,
    /// Largest random acceleration per axis (m/s²).
    pub acceleration: f32,
    /// Seed of the random steps.
    pub seed: u64,
}

impl Wander {
    /// `n` lights with random initial velocities of at most `max_speed`, drawn from `seed`.
    pub fn new(n: usize, bounds: Aabb, max_speed: f32, acceleration: f32, seed: u64) -> Self {
        assert!(max_speed > 0.0 && acceleration >= 0.0 && !bounds.is_empty());
        let mut w = Self {
            vx: Vec::with_capacity(n),
            vy: Vec::with_capacity(n),
            vz: Vec::with_capacity(n),
            bounds,
            max_speed,
            acceleration,
            seed,
        };
        for i in 0..n {
            let v = random_unit_cube(frame_key(seed, u64::MAX), i) * (max_speed / 3f32.sqrt());
            w.vx.push(v.x);
            w.vy.push(v.y);
            w.vz.push(v.z);
        }
        w
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.vx.len()
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.vx.is_empty()
    }
}

/// A well-mixed 32-bit hash (two multiply–xorshift rounds; Chris Wellons' "lowbias32"
/// constants). 32-bit so the per-light loop vectorises.
#[inline(always)]
fn hash32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// A well-mixed 64-bit hash (the SplitMix64 finaliser's constants); a bijection on `u64`.
#[inline]
fn hash64(mut x: u64) -> u64 {
    x ^= x >> 30;
    x = x.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x ^= x >> 27;
    x = x.wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// The per-frame key of the random steps: a hash of the seed and the frame number.
///
/// The seed is hashed in all its 64 bits before the frame is added, and the sum hashed again:
/// two (seed, frame) pairs share a key only where their 64-bit mixes happen to meet, never by
/// construction (folding each number to 32 bits first made seed `k << 32` at frame 0 replay
/// seed 0's frame `k`).
fn frame_key(seed: u64, frame: u64) -> u32 {
    let h = hash64(hash64(seed).wrapping_add(frame));
    (h ^ (h >> 32)) as u32
}

/// A point in `[−1, 1)³` determined by the frame key and the light: one hash per axis, its top
/// 24 bits as a fraction.
#[inline(always)]
fn random_unit_cube(key: u32, light: usize) -> Vec3 {
    let base = (light as u32).wrapping_mul(3);
    let unit = |k: u32| {
        let h = hash32(key ^ base.wrapping_add(k));
        (h >> 8) as i32 as f32 * (1.0 / (1u32 << 23) as f32) - 1.0
    };
    Vec3::new(unit(0), unit(1), unit(2))
}

/// The fixed parameters of a [`Wander`], apart from its velocity columns.
#[derive(Clone, Copy)]
struct WanderParams {
    bounds: Aabb,
    max_speed: f32,
    acceleration: f32,
    seed: u64,
}

impl Wander {
    fn params(&self) -> WanderParams {
        WanderParams {
            bounds: self.bounds,
            max_speed: self.max_speed,
            acceleration: self.acceleration,
            seed: self.seed,
        }
    }
}

/// One light's step: the kernel of [`animate_wander`], branch-free (selects only) so the loop
/// vectorises. `key` is [`frame_key`] of the wander's seed and the frame. Returns the new
/// position and velocity.
#[inline(always)] // Into both builds of `wander_block`.
fn wander_step(w: WanderParams, key: u32, dt: f32, i: usize, p: Vec3, v: Vec3) -> (Vec3, Vec3) {
    let v = v + random_unit_cube(key, i) * (w.acceleration * dt);
    let speed = v.length();
    let v = v * if speed > w.max_speed {
        w.max_speed / speed
    } else {
        1.0
    };
    let p = p + v * dt;
    let (lo, hi) = (w.bounds.min, w.bounds.max);
    // Reflect off the walls, then clamp (a step longer than the box stays inside).
    let reflect = |p: f32, v: f32, lo: f32, hi: f32| {
        let (below, above) = (p < lo, p > hi);
        let p = if below {
            2.0 * lo - p
        } else if above {
            2.0 * hi - p
        } else {
            p
        };
        let v = if below {
            v.abs()
        } else if above {
            -v.abs()
        } else {
            v
        };
        (p.max(lo).min(hi), v)
    };
    let (px, vx) = reflect(p.x, v.x, lo.x, hi.x);
    let (py, vy) = reflect(p.y, v.y, lo.y, hi.y);
    let (pz, vz) = reflect(p.z, v.z, lo.z, hi.z);
    (Vec3::new(px, py, pz), Vec3::new(vx, vy, vz))
}

/// One wander step of the block of lights from `start`. Built twice, for AVX2 and for the
/// baseline, as [`orbit_block`] is.
#[multiversion::multiversion(targets("x86_64+avx+avx2+fma"))]
fn wander_block(
    params: WanderParams,
    key: u32,
    dt: f32,
    start: usize,
    (x, y, z, vx, vy, vz): WanderBlock<'_>,
) {
    let n = x.len();
    let (y, z, vx, vy, vz) = (
        &mut y[..n],
        &mut z[..n],
        &mut vx[..n],
        &mut vy[..n],
        &mut vz[..n],
    );
    for k in 0..n {
        let (p, v) = wander_step(
            params,
            key,
            dt,
            start + k,
            Vec3::new(x[k], y[k], z[k]),
            Vec3::new(vx[k], vy[k], vz[k]),
        );
        (x[k], y[k], z[k]) = (p.x, p.y, p.z);
        (vx[k], vy[k], vz[k]) = (v.x, v.y, v.z);
    }
}

/// Position and velocity columns of one block of lights.
type WanderBlock<'a> = (
    &'a mut [f32],
    &'a mut [f32],
    &'a mut [f32],
    &'a mut [f32],
    &'a mut [f32],
    &'a mut [f32],
);

/// Advances every light by one frame of `dt` seconds: a random acceleration (from the hash of
/// seed, `frame` and index), the speed limit, the move, and a bounce off the box. Frames must
/// be numbered by the caller (0, 1, 2, …) for the walk to be reproducible.
pub fn animate_wander(
    wander: &mut Wander,
    frame: u64,
    dt: f32,
    x: &mut [f32],
    y: &mut [f32],
    z: &mut [f32],
) {
    crate::profiling::profile_span!("animate wander");
    let n = wander.len();
    assert!(
        x.len() == n && y.len() == n && z.len() == n,
        "one wanderer per light"
    );
    assert!(wander.vy.len() == n && wander.vz.len() == n);
    let params = wander.params();
    let key = frame_key(params.seed, frame);
    let block = |start: usize, cols: WanderBlock<'_>| wander_block(params, key, dt, start, cols);
    let (vx, vy, vz) = (&mut wander.vx, &mut wander.vy, &mut wander.vz);
    if n < PARALLEL_MIN {
        block(0, (x, y, z, vx, vy, vz));
    } else {
        (
            x.par_chunks_mut(BLOCK),
            y.par_chunks_mut(BLOCK),
            z.par_chunks_mut(BLOCK),
            vx.par_chunks_mut(BLOCK),
            vy.par_chunks_mut(BLOCK),
            vz.par_chunks_mut(BLOCK),
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(b, cols)| block(b * BLOCK, cols));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    #[test]
    fn orbits_start_in_place_and_keep_their_radius() {
        let center = Vec3::new(1.0, 0.0, -2.0);
        let x0: Vec<f32> = (0..20_000).map(|i| (i % 97) as f32 * 0.1 - 3.0).collect();
        let z0: Vec<f32> = (0..20_000).map(|i| (i % 89) as f32 * 0.1 - 4.0).collect();
        let orbits = Orbits::around(center, &x0, &z0, [0.5, 1.5], 3);
        let (mut x, mut z) = (x0.clone(), z0.clone());
        animate_orbits(&orbits, 0.0, &mut x, &mut z);
        for i in 0..x.len() {
            assert!((x[i] - x0[i]).abs() < 1e-5 && (z[i] - z0[i]).abs() < 1e-5);
        }
        animate_orbits(&orbits, 2.5, &mut x, &mut z);
        let mut moved = 0;
        for i in 0..x.len() {
            let r = ((x[i] - center.x).powi(2) + (z[i] - center.z).powi(2)).sqrt();
            assert!((r - orbits.orbit_radius[i]).abs() < 1e-4);
            // Parallel driver = serial kernel.
            let o = &orbits;
            let serial = orbit_point(
                o.center_x[i],
                o.center_z[i],
                o.orbit_radius[i],
                o.angular_speed[i],
                o.phase[i],
                2.5,
            );
            assert_eq!((x[i], z[i]), serial);
            moved += ((x[i] - x0[i]).abs() > 1e-3) as usize;
        }
        assert!(moved > 19_000, "{moved}");
        assert!(orbits.angular_speed.iter().any(|&s| s < 0.0));
        assert!(
            orbits
                .angular_speed
                .iter()
                .all(|&s| (0.5..1.5).contains(&s.abs()))
        );
    }

    /// From 2²⁴ frames on, an f32 frame time no longer advances, and long before that an f32
    /// angle moves in coarse steps: positions must keep tracking the f64 orbit.
    #[test]
    fn orbits_keep_moving_after_two_to_the_24_frames() {
        let orbits = Orbits {
            center_x: vec![0.0; 3],
            center_z: vec![0.0; 3],
            orbit_radius: vec![10.0; 3],
            angular_speed: vec![0.1, -0.5, 1.5],
            phase: vec![0.0, 1.0, -2.0],
        };
        let dt = 1.0 / 60.0;
        for frame in [(1u64 << 24) + 1, 1 << 30, 1 << 36] {
            let (mut x, mut z) = ([0.0; 3], [0.0; 3]);
            let mut previous = None;
            for k in 0..3 {
                let time = (frame + k) as f64 * dt;
                animate_orbits(&orbits, time, &mut x, &mut z);
                for i in 0..3 {
                    let o = &orbits;
                    let angle = o.phase[i] as f64 + o.angular_speed[i] as f64 * time;
                    let (es, ec) = angle.sin_cos();
                    let error = (x[i] as f64 - 10.0 * ec).hypot(z[i] as f64 - 10.0 * es);
                    assert!(error < 1e-4, "frame {frame}+{k}, light {i}: {error} m");
                }
                assert_ne!(previous, Some((x, z)), "frame {frame}+{k} did not move");
                previous = Some((x, z));
            }
        }
    }

    #[test]
    fn orbit_quarter_turn() {
        let orbits = Orbits {
            center_x: vec![0.0],
            center_z: vec![0.0],
            orbit_radius: vec![2.0],
            angular_speed: vec![std::f32::consts::FRAC_PI_2],
            phase: vec![0.0],
        };
        let (mut x, mut z) = ([2.0], [0.0]);
        animate_orbits(&orbits, 1.0, &mut x, &mut z);
        assert!(x[0].abs() < 1e-6 && (z[0] - 2.0).abs() < 1e-6);
    }

    fn wander_frames(n: usize, threads: usize) -> (Vec<f32>, Vec<f32>, Vec<f32>, Wander) {
        let bounds = Aabb::new(Vec3::new(-5.0, 0.0, -3.0), Vec3::new(5.0, 4.0, 3.0));
        let mut w = Wander::new(n, bounds, 2.0, 8.0, 11);
        let mut x: Vec<f32> = (0..n).map(|i| (i % 10) as f32 - 4.5).collect();
        let mut y = vec![2.0; n];
        let mut z = vec![0.0; n];
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            for frame in 0..50 {
                animate_wander(&mut w, frame, 0.1, &mut x, &mut y, &mut z);
            }
        });
        (x, y, z, w)
    }

    #[test]
    fn wanderers_stay_in_the_box_respect_the_speed_limit_and_are_reproducible() {
        let n = 3 * BLOCK + 17;
        let (x, y, z, w) = wander_frames(n, 1);
        let (x2, y2, z2, w2) = wander_frames(n, 3);
        assert_eq!(
            (&x, &y, &z, &w),
            (&x2, &y2, &z2, &w2),
            "thread count changed the walk"
        );
        let mut moved = 0;
        for i in 0..n {
            let p = Vec3::new(x[i], y[i], z[i]);
            assert!(w.bounds.contains(p), "{p}");
            let v = Vec3::new(w.vx[i], w.vy[i], w.vz[i]);
            assert!(v.length() <= 2.0 * (1.0 + 1e-6), "{v}");
            moved += (p - Vec3::new((i % 10) as f32 - 4.5, 2.0, 0.0))
                .length()
                .min(1.0) as usize;
        }
        assert!(moved > n / 2, "{moved} of {n} moved a metre");
        // The serial kernel reproduces one more parallel step.
        let (mut x3, mut y3, mut z3, mut w3) = (x.clone(), y.clone(), z.clone(), w.clone());
        animate_wander(&mut w3, 50, 0.1, &mut x3, &mut y3, &mut z3);
        for i in [0, BLOCK, n - 1] {
            let (p, v) = wander_step(
                w.params(),
                frame_key(w.seed, 50),
                0.1,
                i,
                Vec3::new(x[i], y[i], z[i]),
                Vec3::new(w.vx[i], w.vy[i], w.vz[i]),
            );
            assert_eq!(p, Vec3::new(x3[i], y3[i], z3[i]));
            assert_eq!(v, Vec3::new(w3.vx[i], w3.vy[i], w3.vz[i]));
        }
    }

    #[test]
    fn random_steps_are_spread_over_the_cube() {
        let mut sum = Vec3::ZERO;
        let (mut lo, mut hi) = (Vec3::splat(1.0), Vec3::splat(-1.0));
        for i in 0..10_000 {
            let r = random_unit_cube(frame_key(5, 7), i);
            assert!(r.cmpge(Vec3::splat(-1.0)).all() && r.cmplt(Vec3::splat(1.0)).all());
            sum += r;
            lo = lo.min(r);
            hi = hi.max(r);
        }
        assert!((sum / 10_000.0).abs().max_element() < 0.03, "{sum}");
        assert!(lo.max_element() < -0.99 && hi.min_element() > 0.99);
    }

    #[test]
    fn orbit_speeds_are_drawn_from_the_range_or_fixed_when_it_is_empty() {
        let x: Vec<f32> = (0..1000).map(|i| i as f32 * 0.01).collect();
        let z = vec![1.0; 1000];
        let drawn = Orbits::around(Vec3::ZERO, &x, &z, [0.5, 1.5], 4);
        let speeds: Vec<f32> = drawn.angular_speed.iter().map(|s| s.abs()).collect();
        assert!(speeds.iter().any(|&s| s < 0.6) && speeds.iter().any(|&s| s > 1.4));
        let fixed = Orbits::around(Vec3::ZERO, &x, &z, [2.0, 2.0], 4);
        assert!(fixed.angular_speed.iter().all(|&s| s.abs() == 2.0));
        assert!(fixed.angular_speed.iter().any(|&s| s < 0.0));
        assert_eq!((fixed.len(), fixed.is_empty()), (1000, false));
        assert!(Orbits::default().is_empty());
    }

    #[test]
    fn a_wanderer_moves_by_its_velocity_and_bounces_off_each_wall() {
        let w = Wander::new(2, Aabb::new(Vec3::ZERO, Vec3::splat(10.0)), 5.0, 0.0, 1);
        assert_eq!((w.len(), w.is_empty()), (2, false));
        assert!(Wander::new(0, w.bounds, 5.0, 0.0, 1).is_empty());
        let step = |p: Vec3, v: Vec3| wander_step(w.params(), 0, 0.1, 0, p, v);
        let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-5;
        // In the middle: a straight step, the velocity unchanged.
        let (p, v) = step(Vec3::new(5.0, 5.0, 5.0), Vec3::new(1.0, -2.0, 0.5));
        assert!(close(p, Vec3::new(5.1, 4.8, 5.05)), "{p}");
        assert_eq!(v, Vec3::new(1.0, -2.0, 0.5));
        // 0.05 from the low walls, moving out at 1 m/s: reflected to 0.05 inside, moving in.
        let (p, v) = step(Vec3::splat(0.05), Vec3::splat(-1.0));
        assert!(close(p, Vec3::splat(0.05)), "{p}");
        assert_eq!(v, Vec3::splat(1.0));
        // The same at the high walls.
        let (p, v) = step(Vec3::splat(9.95), Vec3::splat(1.0));
        assert!(close(p, Vec3::splat(9.95)), "{p}");
        assert_eq!(v, Vec3::splat(-1.0));
    }

    #[test]
    fn random_accelerations_are_the_hashed_steps_times_acceleration_and_dt() {
        let bounds = Aabb::new(Vec3::splat(-100.0), Vec3::splat(100.0));
        let w = Wander::new(1000, bounds, 50.0, 8.0, 3);
        let key = frame_key(w.seed, 7);
        let mut largest = 0.0f32;
        for i in 0..1000 {
            let (p, v) = wander_step(w.params(), key, 0.1, i, Vec3::ZERO, Vec3::ZERO);
            assert!((v - random_unit_cube(key, i) * 0.8).abs().max_element() < 1e-6);
            assert!((p - v * 0.1).abs().max_element() < 1e-6);
            largest = largest.max(v.abs().max_element());
        }
        // Up to 8 m/s² · 0.1 s per axis, and close to it.
        assert!(largest <= 0.8 + 1e-6 && largest > 0.75, "{largest}");
    }

    #[test]
    fn frame_keys_differ_between_frames_and_between_seeds() {
        let high = (1..8u64).flat_map(|k| (0..8).map(move |j| (k << 32) | j));
        let values: Vec<u64> = (0..16).chain(high).chain([u64::MAX]).collect();
        for &a in &values {
            let frames: HashSet<u32> = values.iter().map(|&f| frame_key(a, f)).collect();
            let seeds: HashSet<u32> = values.iter().map(|&s| frame_key(s, a)).collect();
            assert_eq!(
                (frames.len(), seeds.len()),
                (values.len(), values.len()),
                "{a}"
            );
        }
    }

    #[test]
    fn a_seed_high_bits_do_not_replay_another_seed_at_another_frame() {
        // Seed `k << 32` at frame `j` against seed `j'` at frame `k`, and every other mix of
        // small and high-bit numbers: all (seed, frame) pairs have keys of their own.
        let high = (1..8u64).flat_map(|k| (0..8).map(move |j| (k << 32) | j));
        let values: Vec<u64> = (0..16).chain(high).chain([u64::MAX]).collect();
        let mut keys: Vec<u32> = values
            .iter()
            .flat_map(|&s| values.iter().map(move |&f| frame_key(s, f)))
            .collect();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!(keys.len(), values.len() * values.len());
    }

    #[test]
    fn the_hash_is_a_bijection_on_the_first_million_inputs() {
        let mut hashes: Vec<u32> = (0..1u32 << 20).map(hash32).collect();
        hashes.sort_unstable();
        hashes.dedup();
        assert_eq!(hashes.len(), 1 << 20);
    }

    #[test]
    fn the_hash_flips_each_output_bit_for_about_half_the_inputs_when_one_bit_flips() {
        // Strict avalanche: for every input bit and output bit, over 4096 inputs.
        let mut flips = [[0u32; 32]; 32];
        for k in 0..4096u32 {
            let x = k.wrapping_mul(0x9e37_79b9);
            let h = hash32(x);
            for (i, row) in flips.iter_mut().enumerate() {
                let d = h ^ hash32(x ^ (1 << i));
                for (o, count) in row.iter_mut().enumerate() {
                    *count += (d >> o) & 1;
                }
            }
        }
        for (i, row) in flips.iter().enumerate() {
            for (o, &count) in row.iter().enumerate() {
                assert!(
                    (1700..2400).contains(&count),
                    "bit {i} -> {o}: {count} of 4096"
                );
            }
        }
    }
}
