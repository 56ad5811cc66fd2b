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
use myriad::scene::{
    Error, LightField, Lights, Model, Preset, ReplaceFilesError, Scene, ValidationReport,
};
use static_assertions::assert_impl_all;
use std::sync::Barrier;

/// Each type is `Send + Sync`, or this file does not build.
macro_rules! send_and_sync {
    ($($t:ty),* $(,)?) => { $(assert_impl_all!($t: Send, Sync);)* };
}

// Frame state an engine keeps per view and hands to its job threads, and its settings.
send_and_sync!(
    Assigner,
    LightLists,
    ActiveClusters,
    AssignStats,
    Method,
    AppendStrategy
);
send_and_sync!(OutsideCalls, PacingLimits, Parallelism);
// The inputs every thread reads: borrowed columns and the geometry, passed by value.
send_and_sync!(
    LightInput<'static>,
    SpotInput<'static>,
    Camera,
    ClusterGrid,
    PlaneSets
);
send_and_sync!(DepthSlicing, OuterSlices, SpotCone);
assert_impl_all!(LightInput<'static>: Copy);
assert_impl_all!(SpotInput<'static>: Copy);
assert_impl_all!(Camera: Copy);
// Scenes loaded on a streaming thread and handed to the frame.
send_and_sync!(Scene, Lights, Model, LightField, Preset, ValidationReport);
// The renderer and its resources, made on a loading thread and used on the render thread.
send_and_sync!(
    GpuContext,
    Renderer,
    GpuScene,
    SceneGeometry,
    GBuffer,
    HeadlessTarget
);
send_and_sync!(PassTimes, ShadingMode);
// The facade's frame drivers.
send_and_sync!(
    Viewer,
    Skips,
    PrepassTuner,
    RenderScene,
    StageTimes,
    LoopReport
);
// Errors: `anyhow` and `Box<dyn Error + Send + Sync>` take only these.
send_and_sync!(
    Error,
    ReplaceFilesError,
    GpuError,
    InvalidFrame,
    InvalidGrid,
    CameraMatrixError
);
assert_impl_all!(Error: std::error::Error);
assert_impl_all!(ReplaceFilesError: std::error::Error);
assert_impl_all!(GpuError: std::error::Error);
assert_impl_all!(InvalidFrame: std::error::Error);
assert_impl_all!(InvalidGrid: std::error::Error);
assert_impl_all!(CameraMatrixError: std::error::Error);

/// Four engine threads (plain OS threads, outside any rayon pool, as a job system's are), let go
/// together, each assign the same shared frame with an assigner of their own, three frames in a
/// row, with each fast method (`exact` splits its work too, but is too slow for this): each
/// frame's lists equal one assigner's on the calling thread.
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
        let start = Barrier::new(4);
        std::thread::scope(|threads| {
            let runs: Vec<_> = (0..4)
                .map(|_| {
                    threads.spawn(|| {
                        let (mut assigner, mut lists) = (Assigner::new(), LightLists::new());
                        start.wait();
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
/// second thread's frame lists what the first thread's did, into the lists' same buffer.
#[test]
fn an_assigner_moved_to_another_thread_keeps_working() {
    let scene = Preset::Paper.generate(1000, 2);
    let input = myriad::light_input(&scene.lights);
    let frame = |assigner: &mut Assigner, lists: &mut LightLists| {
        assigner.assign(Method::Refined, &input, &scene.camera, &scene.grid, lists)
    };
    let (mut assigner, mut lists) = (Assigner::new(), LightLists::new());
    frame(&mut assigner, &mut lists);
    let (first, storage) = (lists.clone(), lists.indices.as_ptr());
    let moved = std::thread::scope(|threads| {
        threads
            .spawn(move || {
                frame(&mut assigner, &mut lists);
                lists
            })
            .join()
            .unwrap()
    });
    assert!(moved == first, "the moved assigner listed other lists");
    assert_eq!(
        moved.indices.as_ptr(),
        storage,
        "the lists were reallocated"
    );
}
