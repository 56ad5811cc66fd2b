//! What an engine's job system needs of the crates' types: the ones it keeps across frames can be
//! sent to and shared between its threads, and assigners on several of its threads at once, over
//! one shared camera, grid and set of light columns, list what one assigner lists alone.
//!
//! The `Send`/`Sync` bounds are checked at compile time: a field that took either away (an `Rc`,
//! a `Cell`, a raw pointer) would break every engine that moves these values between threads,
//! so it fails this test's build rather than theirs.

use myriad::assignment::{
    ActiveClusters, AppendStrategy, AssignStats, Assigner, InvalidFrame, LightInput, LightLists,
    Method, OutsideCalls, PacingLimits, Parallelism, SpotInput,
};
use myriad::cluster_math::{
    Camera, CameraMatrixError, ClusterGrid, DepthSlicing, InvalidGrid, OuterSlices, PlaneSets,
    SpotCone,
};
use myriad::gpu::{
    GBuffer, GpuContext, GpuError, GpuScene, HeadlessTarget, PassTimes, Renderer, SceneGeometry,
    ShadingMode,
};
use myriad::render::{LoopReport, PrepassTuner, RenderScene, Skips, StageTimes, Viewer};
use myriad::scene::{Error, LightField, Lights, Model, Preset, Scene, ValidationReport};
use static_assertions::assert_impl_all;

// Frame state an engine keeps per view and hands to its job threads.
assert_impl_all!(Assigner: Send, Sync);
assert_impl_all!(LightLists: Send, Sync);
assert_impl_all!(ActiveClusters: Send, Sync);
assert_impl_all!(LightInput<'static>: Send, Sync, Copy);
assert_impl_all!(SpotInput<'static>: Send, Sync, Copy);
assert_impl_all!(AssignStats: Send, Sync);
assert_impl_all!(Method: Send, Sync, Copy);
assert_impl_all!(AppendStrategy: Send, Sync, Copy);
assert_impl_all!(OutsideCalls: Send, Sync, Copy);
assert_impl_all!(PacingLimits: Send, Sync);
assert_impl_all!(Parallelism: Send, Sync);
// The geometry every thread reads.
assert_impl_all!(Camera: Send, Sync, Copy);
assert_impl_all!(ClusterGrid: Send, Sync);
assert_impl_all!(PlaneSets: Send, Sync);
assert_impl_all!(DepthSlicing: Send, Sync, Copy);
assert_impl_all!(OuterSlices: Send, Sync, Copy);
assert_impl_all!(SpotCone: Send, Sync, Copy);
// Scenes loaded on a streaming thread and handed to the frame.
assert_impl_all!(Scene: Send, Sync);
assert_impl_all!(Lights: Send, Sync);
assert_impl_all!(Model: Send, Sync);
assert_impl_all!(LightField: Send, Sync);
assert_impl_all!(Preset: Send, Sync, Copy);
assert_impl_all!(ValidationReport: Send, Sync);
// The renderer and its resources, made on a loading thread and used on the render thread.
assert_impl_all!(GpuContext: Send, Sync);
assert_impl_all!(Renderer: Send, Sync);
assert_impl_all!(GpuScene: Send, Sync);
assert_impl_all!(SceneGeometry: Send, Sync);
assert_impl_all!(GBuffer: Send, Sync);
assert_impl_all!(HeadlessTarget: Send, Sync);
assert_impl_all!(PassTimes: Send, Sync);
assert_impl_all!(ShadingMode: Send, Sync, Copy);
// The facade's frame drivers.
assert_impl_all!(Viewer: Send, Sync);
assert_impl_all!(Skips: Send, Sync);
assert_impl_all!(PrepassTuner: Send, Sync);
assert_impl_all!(RenderScene: Send, Sync);
assert_impl_all!(StageTimes: Send, Sync);
assert_impl_all!(LoopReport: Send, Sync);
// Errors: `anyhow` and `Box<dyn Error + Send + Sync>` take only these.
assert_impl_all!(Error: Send, Sync, std::error::Error);
assert_impl_all!(GpuError: Send, Sync, std::error::Error);
assert_impl_all!(InvalidFrame: Send, Sync, std::error::Error);
assert_impl_all!(InvalidGrid: Send, Sync, std::error::Error);
assert_impl_all!(CameraMatrixError: Send, Sync, std::error::Error);

/// Four engine threads (plain OS threads, outside any rayon pool, as a job system's are) each
/// assign the same shared frame with an assigner of their own, three frames in a row, every
/// method that splits its work: each frame's lists equal one assigner's on the calling thread.
#[test]
fn assigners_on_several_engine_threads_list_what_one_lists() {
    let scene = Preset::Uniform.generate(20_000, 5);
    let input = myriad::light_input(&scene.lights);
    let (camera, grid) = (&scene.camera, &scene.grid);
    for method in [Method::Binary, Method::Refined, Method::Cone] {
        let mut alone = LightLists::new();
        let stats = Assigner::new().assign(method, &input, camera, grid, &mut alone);
        assert!(
            stats.pairs > 40_000,
            "{method:?}: the frame must be busy enough to interleave: {} pairs",
            stats.pairs
        );
        std::thread::scope(|threads| {
            let runs: Vec<_> = (0..4)
                .map(|_| {
                    threads.spawn(|| {
                        let (mut assigner, mut lists) = (Assigner::new(), LightLists::new());
                        (0..3)
                            .map(|_| {
                                assigner.assign(method, &input, camera, grid, &mut lists);
                                lists.clone()
                            })
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            for (thread, run) in runs.into_iter().enumerate() {
                for (frame, lists) in run.join().unwrap().into_iter().enumerate() {
                    assert!(
                        lists == alone,
                        "{method:?}: thread {thread}, frame {frame} listed other lists"
                    );
                }
            }
        });
    }
}

/// An assigner and its lists built on one thread and moved to another carry on there: the
/// second thread's frame reuses the first's storage and lists what a fresh assigner lists.
#[test]
fn an_assigner_moved_to_another_thread_keeps_working() {
    let scene = Preset::Paper.generate(1000, 2);
    let input = myriad::light_input(&scene.lights);
    let (mut assigner, mut lists) = (Assigner::new(), LightLists::new());
    assigner.assign(
        Method::Refined,
        &input,
        &scene.camera,
        &scene.grid,
        &mut lists,
    );
    let first = lists.clone();
    let (assigner, lists) = std::thread::scope(|threads| {
        threads
            .spawn(move || {
                assigner.assign(
                    Method::Refined,
                    &input,
                    &scene.camera,
                    &scene.grid,
                    &mut lists,
                );
                (assigner, lists)
            })
            .join()
            .unwrap()
    });
    drop(assigner);
    assert!(lists == first, "the moved assigner listed other lists");
}
