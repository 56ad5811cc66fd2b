//! Using myriad's light assignment from an engine: the engine keeps its own light type and its
//! own camera matrices, hands the assigner plain SoA columns, a camera read from those matrices
//! and a cluster grid every frame, and gets back CSR light lists ready to upload.
//!
//! Only `myriad-cluster-math` and `myriad-assignment` are used (no scene files, no facade), as an
//! engine that depends on just those two crates would. Run with
//! `cargo run --release --example engine_integration`.

use myriad_assignment::{Assigner, LightInput, LightLists, Method};
use myriad_cluster_math::glam::{UVec3, Vec3, camera};
use myriad_cluster_math::{Camera, ClipSpace, ClusterGrid, DepthSlicing};

/// The engine's own light record (array of structs).
struct EngineLight {
    position: Vec3,
    range: f32,
}

/// SoA columns the engine keeps (and reuses) for the assigner.
#[derive(Default)]
struct LightColumns {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    radius: Vec<f32>,
}

impl LightColumns {
    /// Refills the columns from the engine's lights, keeping their storage.
    fn fill(&mut self, lights: &[EngineLight]) {
        self.x.clear();
        self.y.clear();
        self.z.clear();
        self.radius.clear();
        for l in lights {
            self.x.push(l.position.x);
            self.y.push(l.position.y);
            self.z.push(l.position.z);
            self.radius.push(l.range);
        }
    }

    fn input(&self) -> LightInput<'_> {
        LightInput::points(&self.x, &self.y, &self.z, &self.radius)
    }
}

fn main() {
    // The engine's own camera, as the two matrices it renders with: at the origin looking down
    // −Z, 60° vertical field of view, a reversed-Z projection with an infinite far plane.
    let view = camera::rh::view::look_at_mat4(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y);
    let projection = camera::rh::proj::directx::perspective_infinite_reverse(
        60f32.to_radians(),
        1920.0 / 1080.0,
        0.1,
    );
    // Read back into a `Camera` (an error would say why: a jittered projection, a left-handed
    // pair, a size other than the projection's aspect ratio...).
    let camera = match Camera::from_matrices(view, projection, ClipSpace::ZeroToOneYUp, 1920, 1080)
    {
        Ok(camera) => camera,
        Err(why) => {
            eprintln!("this view is no camera the clusters can be built for: {why}");
            std::process::exit(1);
        }
    };
    // The far plane is infinite; the grid slices depth over a finite range of its own: a
    // 16×9×24 grid with log slices, first out to 50 m. Pixels past its far edge read its last
    // slice, which is open (`OuterSlices::Open`, the default): it lists the lights out there too,
    // so none is missing. The stats count them (`beyond_far`) and say how far the lights reach,
    // which the next frame's grid follows, so its slices cut the lights' whole depth range.
    let mut grid = ClusterGrid::new(UVec3::new(16, 9, 24), DepthSlicing::Log, camera.near, 50.0);

    // 10 000 lights on a deterministic spiral in front of the camera.
    let mut lights: Vec<EngineLight> = (0..10_000)
        .map(|i| {
            let t = i as f32 * 0.01;
            EngineLight {
                position: Vec3::new(
                    8.0 * t.cos(),
                    4.0 * (3.0 * t).sin(),
                    -2.0 - 0.009 * i as f32,
                ),
                range: 0.5 + (i % 7) as f32 * 0.25,
            }
        })
        .collect();

    // Created once; reused every frame so steady-state frames allocate no storage for the lists
    // or the assigner's scratch (called from outside any pool, `OutsideCalls::Join` still boxes
    // a few small rayon jobs a frame; `with_outside_calls(OutsideCalls::HandOff)` avoids them).
    let mut assigner = Assigner::new();
    // The grid the lists were last built on: a pixel reads them through it, not through the
    // next frame's grid below.
    let mut built = grid;
    let mut lists = LightLists::new();
    let mut columns = LightColumns::default();

    for frame in 0..3 {
        // The engine animates its lights...
        for l in &mut lights {
            l.position.y += 0.1;
        }
        // ...and hands the assigner this frame's columns. It runs on the current rayon pool;
        // called from this main thread, outside any pool, it works on the frame itself beside
        // helper jobs on rayon's global pool (`OutsideCalls::Join`; with `OutsideCalls::HandOff`
        // it hands the whole frame to a worker instead, allocating nothing).
        columns.fill(&lights);
        // `try_assign`: a frame the assigner cannot take (columns of different lengths, a mask
        // of another grid) is an error, and the lists stay as they were.
        let stats = match assigner.try_assign(
            Method::Refined,
            &columns.input(),
            &camera,
            &grid,
            &mut lists,
        ) {
            Ok(stats) => stats,
            Err(why) => {
                eprintln!("frame {frame} not assigned: {why}");
                continue;
            }
        };
        built = stats.grid_built(&grid);
        println!(
            "frame {frame}: {} lights, {} visible, {} culled, {} beyond the grid's far {:.1} (in its \
             last slice) -> {} cluster-light pairs, {} KiB to upload",
            stats.lights,
            stats.visible(),
            stats.culled,
            stats.beyond_far,
            grid.far(),
            stats.pairs,
            lists.byte_size() / 1024
        );
        // Next frame's grid reaches as far as this frame's lights did (with a little room for
        // them to move), like Bevy's "max light range" far; a light that moves past it anyway is
        // listed in the open last slice, and counted.
        if let Some(reach) = stats.reach {
            let far = (reach * 1.05).max(camera.near * 2.0);
            let dims = UVec3::new(16, 9, 24);
            match ClusterGrid::try_new(dims, DepthSlicing::Log, camera.near, far) {
                Ok(next) => grid = next,
                // A reach too far for f32 (`far` infinite): keep this frame's grid.
                Err(why) => eprintln!("frame {frame}: grid kept: {why}"),
            }
        }
    }

    // What the shader does per pixel: pixel + view depth -> cluster -> its lights.
    let (px, py, depth) = (960, 540, 20.0);
    let cluster = built.cluster_of_pixel(px, py, depth, camera.width, camera.height);
    let here = lists.lights_of(cluster as usize);
    println!(
        "pixel ({px}, {py}) at depth {depth}: cluster {cluster}, {} lights, first {:?}",
        here.len(),
        &here[..here.len().min(5)]
    );
    // Upload: `lists.offsets`, `lists.counts` and `lists.indices` are plain `u32` arrays.
}
