//! # Frame systems: animate, cull, to view space
//!
//! Times the ECS-style systems of `myriad_scene::systems` (one call = one frame's work for all
//! lights) over seeded light fields in the generated atrium, seen from its `Main` camera:
//! lights on the atrium's surfaces (area-weighted, 0.2 m off the surface, 30% spots) for 10k,
//! 100k and 1M lights. Groups:
//! * `animate` — `animate_orbits` (closed form: one `sin_cos` per light) and `animate_wander`
//!   (hash, integrate, bounce);
//! * `cull` — `cull_lights` with point lights only and with 30% spot cones (mask + compacted
//!   index list);
//! * `to_view` — `lights_to_view` of the visible lights;
//! * `gather` — `Lights::gather_into` of the visible lights (every column), what the frame loop
//!   uploads after its cull;
//! * `frame` — all three chained, what a frame costs before assignment.
//!
//! Outputs are reused across iterations (steady state: no allocation). Throughput is lights
//! per second. Run with `cargo bench --bench scene_systems` (filter e.g. `-- cull --quick`).

use criterion::{BenchmarkId, Criterion, Throughput};
use myriad::scene::glam::Vec3;
use myriad::scene::systems::{
    Orbits, ViewLights, Visibility, Wander, animate_orbits, animate_wander, cull_lights,
    lights_to_view,
};
use myriad::scene::{LightField, Lights, Placement, SpotRule, SurfaceSampler, atrium};
use std::hint::black_box;
use std::time::Duration;

const COUNTS: [usize; 3] = [10_000, 100_000, 1_000_000];

/// `n` lights on the atrium's surfaces (seed 1), a share `spots` of them spot lights.
fn surface_lights(surfaces: &SurfaceSampler, n: usize, spots: f32) -> Lights {
    let mut field = LightField::new(Placement::Surfaces {
        surfaces: surfaces.clone(),
        offset: 0.2,
    });
    if spots > 0.0 {
        field = field.with_spots(SpotRule {
            fraction: spots,
            angle_deg: [20.0, 45.0],
        });
    }
    field.generate(n, 1)
}

fn systems(c: &mut Criterion) {
    let model = atrium();
    let camera = model
        .camera(0, 1536, 768)
        .expect("the atrium has a Main camera");
    let surfaces = SurfaceSampler::new(&model);
    let bounds = model.bounds();

    let mut animate = c.benchmark_group("animate");
    animate
        .sample_size(20)
        .measurement_time(Duration::from_secs(2));
    for n in COUNTS {
        let mut lights = surface_lights(&surfaces, n, 0.0);
        animate.throughput(Throughput::Elements(n as u64));
        let orbits = Orbits::around(Vec3::ZERO, &lights.x, &lights.z, [0.2, 1.0], 1);
        let mut time = 0.0f64;
        animate.bench_function(BenchmarkId::new("orbits", n), |b| {
            b.iter(|| {
                time += 1.0 / 60.0;
                animate_orbits(&orbits, time, &mut lights.x, &mut lights.z);
            })
        });
        let mut wander = Wander::new(n, bounds, 1.5, 4.0, 1);
        let mut frame = 0u64;
        animate.bench_function(BenchmarkId::new("wander", n), |b| {
            b.iter(|| {
                frame += 1;
                animate_wander(
                    &mut wander,
                    frame,
                    1.0 / 60.0,
                    &mut lights.x,
                    &mut lights.y,
                    &mut lights.z,
                );
            })
        });
    }
    animate.finish();

    let mut cull = c.benchmark_group("cull");
    cull.sample_size(20)
        .measurement_time(Duration::from_secs(2));
    for n in COUNTS {
        cull.throughput(Throughput::Elements(n as u64));
        for (name, spots) in [("points", 0.0), ("spots30", 0.3)] {
            let lights = surface_lights(&surfaces, n, spots);
            let mut vis = Visibility::new();
            cull_lights(&camera, lights.slices(), &mut vis);
            cull.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter(|| black_box(cull_lights(&camera, lights.slices(), &mut vis)))
            });
        }
    }
    cull.finish();

    let mut view = c.benchmark_group("to_view");
    view.sample_size(20)
        .measurement_time(Duration::from_secs(2));
    for n in COUNTS {
        let lights = surface_lights(&surfaces, n, 0.3);
        let mut vis = Visibility::new();
        let visible = cull_lights(&camera, lights.slices(), &mut vis);
        let mut out = ViewLights::new();
        view.throughput(Throughput::Elements(visible as u64));
        view.bench_function(BenchmarkId::new("visible", n), |b| {
            b.iter(|| lights_to_view(&camera, lights.slices(), Some(&vis.indices), &mut out))
        });
    }
    view.finish();

    let mut gather = c.benchmark_group("gather");
    gather
        .sample_size(20)
        .measurement_time(Duration::from_secs(2));
    for n in COUNTS {
        let lights = surface_lights(&surfaces, n, 0.3);
        let mut vis = Visibility::new();
        let visible = cull_lights(&camera, lights.slices(), &mut vis);
        let mut out = Lights::new();
        gather.throughput(Throughput::Elements(visible as u64));
        gather.bench_function(BenchmarkId::new("visible", n), |b| {
            b.iter(|| {
                lights.gather_into(&vis.indices, &mut out);
                black_box(out.len())
            })
        });
    }
    gather.finish();

    let mut frame_group = c.benchmark_group("frame");
    frame_group
        .sample_size(20)
        .measurement_time(Duration::from_secs(2));
    for n in COUNTS {
        let mut lights = surface_lights(&surfaces, n, 0.3);
        let orbits = Orbits::around(Vec3::ZERO, &lights.x, &lights.z, [0.2, 1.0], 1);
        let (mut vis, mut out) = (Visibility::new(), ViewLights::new());
        let mut time = 0.0f64;
        frame_group.throughput(Throughput::Elements(n as u64));
        frame_group.bench_function(BenchmarkId::new("orbit_cull_view", n), |b| {
            b.iter(|| {
                time += 1.0 / 60.0;
                animate_orbits(&orbits, time, &mut lights.x, &mut lights.z);
                cull_lights(&camera, lights.slices(), &mut vis);
                lights_to_view(&camera, lights.slices(), Some(&vis.indices), &mut out);
                black_box(out.len())
            })
        });
    }
    frame_group.finish();
}

criterion::criterion_group!(benches, systems);
criterion::criterion_main!(benches);
