//! Scene generation and the brute-force oracle shared by the assignment tests.
#![allow(dead_code)] // Each test binary uses a different part of this module.

use glam::{UVec3, Vec3};
use myriad_assignment::{AssignStats, Assigner, LightInput, LightLists, Method, SpotInput};
use myriad_cluster_math::oracle::{Cell, OracleView};
use myriad_cluster_math::{Camera, ClusterGrid, DepthSlicing};
use rand::{Rng, SeedableRng};

/// Owned SoA light columns for tests.
#[derive(Clone, Debug, Default)]
pub struct Columns {
    pub x: Vec<f32>,
    pub y: Vec<f32>,
    pub z: Vec<f32>,
    pub radius: Vec<f32>,
    pub dir_x: Vec<f32>,
    pub dir_y: Vec<f32>,
    pub dir_z: Vec<f32>,
    pub angle: Vec<f32>,
}

impl Columns {
    pub fn push(&mut self, p: Vec3, r: f32) {
        self.push_spot(p, r, Vec3::Z, std::f32::consts::PI);
    }

    pub fn push_spot(&mut self, p: Vec3, r: f32, dir: Vec3, angle: f32) {
        self.x.push(p.x);
        self.y.push(p.y);
        self.z.push(p.z);
        self.radius.push(r);
        self.dir_x.push(dir.x);
        self.dir_y.push(dir.y);
        self.dir_z.push(dir.z);
        self.angle.push(angle);
    }

    pub fn len(&self) -> usize {
        self.x.len()
    }

    pub fn input(&self, with_spots: bool) -> LightInput<'_> {
        LightInput {
            x: &self.x,
            y: &self.y,
            z: &self.z,
            radius: &self.radius,
            spot: with_spots.then(|| SpotInput {
                dir_x: &self.dir_x,
                dir_y: &self.dir_y,
                dir_z: &self.dir_z,
                angle: &self.angle,
            }),
        }
    }
}

/// The oracle's lists: for every cluster, the lights that touch it (ascending), and how many
/// lights there were. Derefs to the per-cluster lists.
pub struct Truth {
    pub lists: Vec<Vec<u32>>,
    pub lights: usize,
}

impl std::ops::Deref for Truth {
    type Target = [Vec<u32>];
    fn deref(&self) -> &[Vec<u32>] {
        &self.lists
    }
}

/// For every cluster, the lights the f64 oracle says touch it, by testing every (light, cluster).
pub fn brute_force(lights: &Columns, spots: bool, camera: &Camera, grid: &ClusterGrid) -> Truth {
    let d = grid.dims();
    let cells: Vec<Cell> = (0..grid.cluster_count() as u32)
        .map(|c| {
            let v = grid.cluster_coords(c);
            Cell::of_cluster(camera, grid, v.x, v.y, v.z)
        })
        .collect();
    let mut out = vec![Vec::new(); (d.x * d.y * d.z) as usize];
    let view = OracleView::new(camera);
    for l in 0..lights.len() {
        let position = Vec3::new(lights.x[l], lights.y[l], lights.z[l]);
        let spot = spots.then(|| {
            let direction = Vec3::new(lights.dir_x[l], lights.dir_y[l], lights.dir_z[l]);
            (direction, lights.angle[l])
        });
        let Some(volume) = view.light(position, lights.radius[l], spot) else {
            continue;
        };
        for (c, cell) in cells.iter().enumerate() {
            if volume.intersects_cell(cell) {
                out[c].push(l as u32);
            }
        }
    }
    Truth {
        lists: out,
        lights: lights.len(),
    }
}

/// Checks that `lists` is well formed (one list per cluster of the truth, ascending, every index
/// a light that exists) and `lists ⊇ truth`; returns (exact pairs, false-positive pairs).
pub fn assert_conservative(
    name: &str,
    lists: &LightLists,
    truth: &Truth,
    context: &str,
) -> (usize, usize) {
    assert_eq!(
        lists.cluster_count(),
        truth.len(),
        "{name}: one list per cluster ({context})"
    );
    lists.assert_well_formed(truth.lights);
    let mut exact = 0;
    let mut extra = 0;
    for (c, want) in truth.iter().enumerate() {
        let got = lists.lights_of(c);
        for l in want {
            assert!(
                got.binary_search(l).is_ok(),
                "{name}: light {l} missing from cluster {c} ({context}); got {got:?}, want {want:?}"
            );
        }
        exact += want.len();
        extra += got.len() - want.len();
    }
    (exact, extra)
}

/// A random camera + grid + lights scene with adversarial placements, from a seed.
pub struct Scene {
    pub camera: Camera,
    pub grid: ClusterGrid,
    pub lights: Columns,
}

impl Scene {
    /// One frame of this scene by `assigner` into `lists`, spot cones included when `spots`:
    /// the call most tests make.
    pub fn assign(
        &self,
        assigner: &mut Assigner,
        method: Method,
        spots: bool,
        lists: &mut LightLists,
    ) -> AssignStats {
        assigner.assign(
            method,
            &self.lights.input(spots),
            &self.camera,
            &self.grid,
            lists,
        )
    }
}

/// A scene of point lights `(position, radius)` seen by `camera` through a `dims` grid.
pub fn scene_of_points(
    camera: Camera,
    dims: UVec3,
    slicing: DepthSlicing,
    lights: &[(Vec3, f32)],
) -> Scene {
    let grid = ClusterGrid::new(dims, slicing, camera.near, camera.far);
    let mut columns = Columns::default();
    for &(p, r) in lights {
        columns.push(p, r);
    }
    Scene {
        camera,
        grid,
        lights: columns,
    }
}

/// The camera's right, up and forward axes in f32.
pub fn view_basis(camera: &Camera) -> (Vec3, Vec3, Vec3) {
    let (r, u, f) = camera.basis_f64();
    (r.as_vec3(), u.as_vec3(), f.as_vec3())
}

pub fn random_dir(rng: &mut impl Rng) -> Vec3 {
    loop {
        let v = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
            return v.normalize();
        }
    }
}

/// Depth slicing by code: 0 linear, 1 log, 2 log with a near slice ending a tenth of the way
/// (in log depth) from `near` to `far`.
pub fn slicing_of(code: u8, near: f32, far: f32) -> DepthSlicing {
    match code % 3 {
        0 => DepthSlicing::Linear,
        1 => DepthSlicing::Log,
        _ => DepthSlicing::LogWithNearSlice {
            first_slice_depth: near * (far / near).powf(0.1),
        },
    }
}

#[derive(Clone, Debug)]
pub struct SceneParams {
    pub seed: u64,
    pub fov_deg: f32,
    pub aspect: f32,
    pub near: f32,
    pub far_ratio: f32,
    pub eye_scale: f32,
    pub dims: UVec3,
    pub slicing: u8,
    pub lights: usize,
    pub spots: bool,
}

impl SceneParams {
    /// A wide 2:1 view from the origin on the paper's 24×12×16 linear grid, point lights only.
    pub const WIDE: Self = Self {
        seed: 0,
        fov_deg: 60.0,
        aspect: 2.0,
        near: 0.5,
        far_ratio: 200.0,
        eye_scale: 0.0,
        dims: UVec3::new(24, 12, 16),
        slicing: 0,
        lights: 0,
        spots: false,
    };
    /// A 16:9 view from near the origin on a 16×9×24 log grid, with spot lights.
    pub const HD: Self = Self {
        seed: 0,
        fov_deg: 65.0,
        aspect: 16.0 / 9.0,
        near: 0.1,
        far_ratio: 500.0,
        eye_scale: 5.0,
        dims: UVec3::new(16, 9, 24),
        slicing: 1,
        lights: 0,
        spots: true,
    };
}

pub fn make_scene(p: &SceneParams) -> Scene {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(p.seed);
    let eye = random_dir(&mut rng) * p.eye_scale * rng.random_range(0.0f32..1.0);
    // Any orientation, including straight up and down.
    let forward = match rng.random_range(0..6) {
        0 => Vec3::Y,
        1 => Vec3::NEG_Y,
        _ => random_dir(&mut rng),
    };
    let height = 64u32;
    let width = ((height as f32 * p.aspect).round() as u32).max(1);
    let far = p.near * p.far_ratio;
    let camera = Camera::new(
        eye,
        eye + forward,
        Vec3::Y,
        p.fov_deg,
        width,
        height,
        p.near,
        far,
    );
    let grid = ClusterGrid::new(p.dims, slicing_of(p.slicing, p.near, far), p.near, far);
    let (right, up, fwd) = view_basis(&camera);
    let t = camera.tan_half_fov();
    let mut lights = Columns::default();
    for _ in 0..p.lights {
        // Depth: log-uniform over [near/10, far*2], sometimes behind the camera.
        let depth = if rng.random_bool(0.1) {
            -rng.random_range(0.0..far)
        } else {
            (p.near * 0.1) * (20.0 * p.far_ratio).powf(rng.random_range(0.0f32..1.0))
        };
        let mut sx = rng.random_range(-1.3f32..1.3);
        let mut sy = rng.random_range(-1.3f32..1.3);
        // Straddle tile planes exactly.
        if rng.random_bool(0.3) {
            sx = -1.0 + 2.0 * rng.random_range(0..=p.dims.x) as f32 / p.dims.x as f32;
        }
        if rng.random_bool(0.3) {
            sy = -1.0 + 2.0 * rng.random_range(0..=p.dims.y) as f32 / p.dims.y as f32;
        }
        let mut view = Vec3::new(sx * t.x * depth.abs(), sy * t.y * depth.abs(), -depth);
        // Sit on a slice edge.
        if rng.random_bool(0.2) {
            let k = rng.random_range(0..=p.dims.z);
            view.z = -grid.slice_start_depth(k);
        }
        let scale = view.length().max(p.near);
        let radius = match rng.random_range(0..4) {
            // Radii from tiny to huge relative to the distance.
            0 => scale * 10f32.powf(rng.random_range(-4.0..-1.0)),
            1 => scale * 10f32.powf(rng.random_range(-1.0..0.5)),
            // Containing the camera.
            2 => view.length() * rng.random_range(1.0f32..3.0),
            // Absolute 1e-4 .. 1e3.
            _ => 10f32.powf(rng.random_range(-4.0..3.0)),
        };
        let world = eye + right * view.x + up * view.y - fwd * view.z;
        let dir = random_dir(&mut rng);
        let angle = if p.spots && rng.random_bool(0.7) {
            // (This stream is pinned by a regression seed in `conservative.rs`; needle angles
            // are drawn by `conservative.rs`'s `needle_spots_cover_the_oracle`.)
            rng.random_range(0.01f32..1.6)
        } else {
            std::f32::consts::PI
        };
        lights.push_spot(world, radius, dir, angle);
    }
    Scene {
        camera,
        grid,
        lights,
    }
}
