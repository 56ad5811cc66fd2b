//! Tests of one task: `emit` per method and `run_task` light by light.

use super::*;
use crate::cone::{self, LightCone};
use glam::UVec3;
use myriad_cluster_math::DepthSlicing;
use rand::{Rng, SeedableRng};

/// Slices per part in [`context`]'s frames: 4, so a span pushed to the wrong part shows.
const SLICE_SHIFT: u32 = 2;

/// A 70° 1536 × 768 camera at the origin looking down −z, a 24 × 12 × 16 log grid over
/// 0.1–60 and its plane sets (the geometry tests' frame).
fn frame() -> (Camera, ClusterGrid, PlaneSets) {
    let (near, far) = (0.1, 60.0);
    let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 70.0, 1536, 768, near, far);
    let grid = ClusterGrid::new(UVec3::new(24, 12, 16), DepthSlicing::Log, near, far);
    let sets = PlaneSets::new(&camera, &grid);
    (camera, grid, sets)
}

/// `method`'s frame context over [`frame`], point lights only, no mask, four slices to a
/// part; `tile_cones` empty makes the `cone` method compute each tile's cone where needed.
fn context<'a>(
    method: Method,
    camera: &'a Camera,
    grid: &'a ClusterGrid,
    sets: &'a PlaneSets,
    tile_cones: &'a [TileCone],
) -> FrameContext<'a> {
    let d = grid.dims();
    FrameContext {
        method,
        lights: LightInput::points(&[], &[], &[], &[]),
        camera,
        grid,
        planes: FramePlanes::new(sets, grid),
        view_from_world: camera.view_rotation(),
        cluster_spheres: &[],
        tile_cones,
        tan_half_fov: camera.tan_half_fov_f64(),
        exact: None,
        active: None,
        parts: d.z.div_ceil(1 << SLICE_SHIFT) as usize,
        slice_shift: SLICE_SHIFT,
        cull: FrustumCull {
            sides: [glam::Vec2::ZERO; 4],
            near: camera.near,
            far: camera.far,
        },
        outside_cull: None,
    }
}

/// [`context`] with the early cull `Assigner` gives its tasks ([`FrustumCull::of_grid`]).
fn culling_context<'a>(
    method: Method,
    camera: &'a Camera,
    grid: &'a ClusterGrid,
    sets: &'a PlaneSets,
) -> FrameContext<'a> {
    let mut ctx = context(method, camera, grid, sets, &[]);
    ctx.cull = FrustumCull::of_grid(sets, grid);
    ctx
}

/// Runs lights `begin..end` of `ctx` as one task: its `(light, cluster)` pairs, ascending,
/// then its counts of rejected and of culled lights.
fn task_pairs(ctx: &FrameContext<'_>, begin: usize, end: usize) -> (Vec<(u32, u32)>, u32, u32) {
    let mut out = TaskOutput::default();
    run_task(ctx, begin, end, &mut out);
    let pairs = listed_pairs(&out.buckets[..ctx.parts], ctx.grid.dims().x);
    (pairs, out.rejected, out.culled)
}

/// Which build of the phases a test runs.
#[derive(Clone, Copy)]
enum Build {
    /// The tasks' dispatchers: their AVX2 + FMA builds on a CPU that has them.
    Dispatched,
    /// `run_blocks` inlined into this test module, which is compiled for the target's baseline
    /// (SSE2 on x86-64).
    Baseline,
}

/// [`task_pairs`] in blocks of `B` lights, [`BLOCK`] or [`LARGE_BLOCK`], whatever the task's
/// length (`run_task` picks the width by the length), through `build`.
fn task_pairs_in_blocks<const B: usize>(
    ctx: &FrameContext<'_>,
    begin: usize,
    end: usize,
    build: Build,
) -> (Vec<(u32, u32)>, u32, u32) {
    let mut out = TaskOutput::default();
    out.reset(ctx);
    match (build, B) {
        (Build::Baseline, _) => run_blocks::<B>(ctx, begin, end, &mut out),
        (Build::Dispatched, BLOCK) => run_small_blocks(ctx, begin, end, &mut out),
        (Build::Dispatched, LARGE_BLOCK) => run_large_blocks(ctx, begin, end, &mut out),
        _ => unreachable!("no task runs blocks of {B}"),
    }
    let pairs = listed_pairs(&out.buckets[..ctx.parts], ctx.grid.dims().x);
    (pairs, out.rejected, out.culled)
}

/// Checks a task's `(pairs, rejected, culled)` ([`task_pairs`]) against the expected ones, pair
/// for pair; `context` goes with a wrong culled count.
fn assert_task_output(
    got: (Vec<(u32, u32)>, u32, u32),
    want: (&[(u32, u32)], u32, u32),
    context: &str,
) {
    assert_eq!(got.1, want.1, "rejected");
    assert_eq!(got.2, want.2, "culled: {context}");
    assert!(
        got.0 == want.0,
        "{} pairs listed, {} expected",
        got.0.len(),
        want.0.len()
    );
}

/// Every `(light, cluster)` pair the spans of `buckets` list, ascending (`width`: the grid's
/// tiles across, a span's row stride).
fn listed_pairs(buckets: &[CachePadded<Bucket>], width: u32) -> Vec<(u32, u32)> {
    let mut pairs = Vec::new();
    for bucket in buckets {
        for span in &bucket.spans {
            for start in span.row_starts(width) {
                pairs.extend((start..start + span.len()).map(|c| (span.light, c)));
            }
        }
    }
    pairs.sort_unstable();
    pairs
}

/// The clusters light 7 (a point light) is listed in after `emit`, ascending.
fn emitted(ctx: &FrameContext<'_>, sphere: (f32, f32, f32, f32), bx: &ClusterBox) -> Vec<u32> {
    emitted_spot(ctx, sphere, bx, &SpotView::default())
}

/// The clusters light 7 is listed in after `emit`, ascending. Checks on the way that every
/// span is light 7's, lies in the part of its slice, and that no cluster is listed twice.
fn emitted_spot(
    ctx: &FrameContext<'_>,
    sphere: (f32, f32, f32, f32),
    bx: &ClusterBox,
    spot: &SpotView,
) -> Vec<u32> {
    let (cx, cy, dc, r) = sphere;
    let d = ctx.grid.dims();
    let mut gaps = vec![0.0; geometry::refine_scratch_len(d)];
    let mut columns = vec![ConeColumn::default(); d.x as usize];
    let mut spans_of = |plain: bool| {
        let mut buckets: Vec<CachePadded<Bucket>> = Vec::new();
        buckets.resize_with(ctx.parts, CachePadded::default);
        emit(
            ctx,
            ctx.method,
            plain,
            7,
            cx,
            cy,
            dc,
            r,
            bx,
            spot,
            &mut buckets,
            &mut gaps,
            &mut columns,
        );
        buckets
    };
    let buckets = spans_of(false);
    if !spot.active && ctx.active.is_none() {
        // The copy of the emit for frames without spots or a mask pushes the same spans.
        let plain = spans_of(true);
        for (part, (a, b)) in buckets.iter().zip(&plain).enumerate() {
            assert_eq!(a.spans, b.spans, "part {part}: the plain emit differs");
            assert_eq!(
                a.pairs, b.pairs,
                "part {part}: the plain emit's pairs differ"
            );
        }
    }
    let mut clusters = Vec::new();
    for (part, bucket) in buckets.iter().enumerate() {
        for span in &bucket.spans {
            assert_eq!(span.light, 7);
            for start in span.row_starts(d.x) {
                for c in start..start + span.len() {
                    let k = ctx.grid.cluster_coords(c).z;
                    assert_eq!((k >> SLICE_SHIFT) as usize, part, "cluster {c}");
                    clusters.push(c);
                }
            }
        }
    }
    clusters.sort_unstable();
    let listed = clusters.len();
    clusters.dedup();
    assert_eq!(clusters.len(), listed, "a cluster listed twice");
    clusters
}

/// The clusters of `bx` that pass `keep(i, j, k)`, ascending.
fn box_clusters(
    grid: &ClusterGrid,
    bx: &ClusterBox,
    mut keep: impl FnMut(u32, u32, u32) -> bool,
) -> Vec<u32> {
    let mut out = Vec::new();
    for k in bx.z.k0..=bx.z.k1 {
        for j in bx.j0..=bx.j1 {
            for i in bx.i0..=bx.i1 {
                if keep(i, j, k) {
                    out.push(grid.cluster_id(i, j, k));
                }
            }
        }
    }
    out
}

/// Each method's `emit` lists, per light, exactly what its definition keeps of the light's
/// box: `binary` the whole box; `refined` the rows of `refine_slice` on boxes at least two
/// tiles wide and tall, else the whole box; `cone` the clusters whose slice, closed, meets
/// the tile's depth range from `LightCone::depth_bounds` — from the cached tile cones and
/// from cones made on the fly alike. Lights straddle the near and far planes too, so that
/// tiles whose range lies wholly before the box's first slice or past its last (the slice
/// walks' ends, and an empty column at slice 0) occur. The oracle suites cannot see a method
/// that lists a superset (a slice walk stopping early, an empty column kept, `refined` or
/// `cone` cutting a box they should keep whole); this can.
#[test]
fn emit_lists_exactly_each_methods_definition() {
    let (camera, grid, sets) = frame();
    let d = grid.dims();
    let mut cached = Vec::new();
    cone::tile_cones(camera.tan_half_fov_f64(), d, &mut cached);
    let planes = FramePlanes::new(&sets, &grid);
    let z = &sets.z_depths;
    let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
    let (mut boxes, mut kept, mut cut, mut empty_at_0, mut past_far) = (0, 0, 0, 0, 0);
    while boxes < 1500 {
        // Depths 0–64, denser near the eye, so that the near and far planes are crossed.
        let dc = 64.0 * rng.random::<f32>().powi(2);
        let (cx, cy) = (rng.random_range(-dc..=dc), rng.random_range(-dc..=dc) * 0.5);
        let r = 10f32.powf(rng.random_range(-1.5..1.0));
        let Some(bx) = geometry::cluster_box(cx, cy, dc, r, &planes) else {
            continue;
        };
        boxes += 1;
        let sphere = (cx, cy, dc, r);
        let all = box_clusters(&grid, &bx, |_, _, _| true);
        let binary = context(Method::Binary, &camera, &grid, &sets, &[]);
        assert_eq!(
            emitted(&binary, sphere, &bx),
            all,
            "binary {sphere:?} {bx:?}"
        );

        let refined = context(Method::Refined, &camera, &grid, &sets, &[]);
        let want = if bx.i1 > bx.i0 && bx.j1 > bx.j0 {
            let mut rows = Vec::new();
            let mut gaps = vec![0.0; geometry::refine_scratch_len(d)];
            for k in bx.z.k0..=bx.z.k1 {
                let whole = geometry::refine_slice(
                    cx,
                    cy,
                    dc,
                    r,
                    &bx,
                    k,
                    &planes,
                    &mut gaps,
                    |j, i0, i1| rows.extend((i0..=i1).map(|i| grid.cluster_id(i, j, k))),
                );
                if whole {
                    rows.extend(box_clusters(&grid, &bx, |_, _, kk| kk == k));
                }
            }
            rows.sort_unstable();
            rows
        } else {
            all.clone()
        };
        assert_eq!(
            emitted(&refined, sphere, &bx),
            want,
            "refined {sphere:?} {bx:?}"
        );

        let light = LightCone::new(cx, cy, dc, r);
        let want = box_clusters(&grid, &bx, |i, j, k| {
            let (lo, hi) = light.depth_bounds(&cached[(j * d.x + i) as usize]);
            let (near, far) = (f64::from(z[k as usize]), f64::from(z[k as usize + 1]));
            let keep = lo <= hi && far >= lo && near <= hi;
            empty_at_0 += (bx.z.k0 == 0 && k == 0 && lo > hi) as usize;
            past_far += (k == d.z - 1 && lo > far) as usize;
            keep
        });
        for tiles in [&cached[..], &[]] {
            let cone = context(Method::Cone, &camera, &grid, &sets, tiles);
            let got = emitted(&cone, sphere, &bx);
            assert_eq!(
                got,
                want,
                "cone {sphere:?} {bx:?}, cached tiles: {}",
                tiles.len()
            );
        }
        kept += want.len();
        cut += all.len() - want.len();
    }
    assert!(kept > cut && cut > 10_000, "cone kept {kept}, cut {cut}");
    assert!(
        empty_at_0 > 10 && past_far > 10,
        "empty columns at slice 0: {empty_at_0}, ranges past the far plane: {past_far}"
    );
}

/// An overflowed light (see `run_task`'s phase 0c) is listed once in every cluster of the
/// grid by every box method: an infinite radius must keep `refined` and `cone` from cutting.
#[test]
fn an_overflowed_light_is_listed_in_the_whole_grid() {
    let (camera, grid, sets) = frame();
    let mut cached = Vec::new();
    cone::tile_cones(camera.tan_half_fov_f64(), grid.dims(), &mut cached);
    for method in [Method::Binary, Method::Refined, Method::Cone] {
        let ctx = context(method, &camera, &grid, &sets, &cached);
        let mut out = TaskOutput::default();
        out.buckets.resize_with(ctx.parts, CachePadded::default);
        out.gaps.resize(2 * grid.dims().x as usize, 0.0);
        out.cone_columns
            .resize(grid.dims().x as usize, ConeColumn::default());
        emit_overflowed(&ctx, 7, &SpotView::default(), &mut out);
        let whole = ctx.whole_grid_box();
        assert_eq!((whole.z.da, whole.z.db), (camera.near, camera.far));
        let listed = listed_pairs(&out.buckets, grid.dims().x);
        let every: Vec<_> = (0..grid.cluster_count() as u32).map(|c| (7, c)).collect();
        assert_eq!(listed, every, "{method:?}");
    }
}

/// A spot light's rows keep exactly the clusters of its bounding sphere's box that
/// `cone_may_touch_sphere` keeps, and every cluster whose bounding sphere is not finite
/// (there the cone cannot be tested). The oracle suites cannot see a spot listed as its whole
/// box, or a cluster without a finite sphere kept whatever it is; this can.
#[test]
fn spot_rows_keep_the_clusters_the_cone_may_touch() {
    let (camera, grid, sets) = frame();
    let mut spheres = Vec::new();
    cluster_bounding_spheres(&camera, &grid, &mut spheres);
    // One cluster every 7 loses its finite sphere: kept by every spot whose box holds it.
    for s in spheres.iter_mut().step_by(7) {
        s.w = f32::INFINITY;
    }
    let planes = FramePlanes::new(&sets, &grid);
    let mut ctx = context(Method::Binary, &camera, &grid, &sets, &[]);
    ctx.cluster_spheres = &spheres;
    let mut rng = rand_pcg::Pcg64::seed_from_u64(12);
    let (mut boxes, mut kept, mut cut, mut unsure) = (0, 0, 0, 0);
    while boxes < 400 {
        let d = 40.0 * rng.random::<f32>();
        let apex = Vec3::new(rng.random_range(-d..=d), rng.random_range(-d..=d) * 0.5, -d);
        let axis = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize_or(Vec3::NEG_Z);
        let angle = rng.random_range(0.05..1.5f32);
        let range = 10f32.powf(rng.random_range(-0.5..1.2));
        let direction = axis;
        let (c, r) = spot_bounding_sphere(apex, range, SpotCone { direction, angle });
        let r = geometry::pad_radius(c.x, c.y, -c.z, r);
        let Some(bx) = geometry::cluster_box(c.x, c.y, -c.z, r, &planes) else {
            continue;
        };
        boxes += 1;
        let spot = SpotView {
            apex,
            axis,
            cos_sin: (angle.cos(), angle.sin()),
            range,
            active: true,
        };
        let want = box_clusters(&grid, &bx, |i, j, k| {
            let s = spheres[grid.cluster_id(i, j, k) as usize];
            if !s.is_finite() {
                unsure += 1;
                return true;
            }
            let keep =
                geometry::cone_may_touch_sphere(apex, axis, spot.cos_sin, range, s.truncate(), s.w);
            (kept, cut) = (kept + keep as usize, cut + !keep as usize);
            keep
        });
        let got = emitted_spot(&ctx, (c.x, c.y, -c.z, r), &bx, &spot);
        assert_eq!(
            got, want,
            "spot at {apex}, axis {axis}, {angle} rad, range {range}: box {bx:?}"
        );
    }
    assert!(
        kept > 10_000 && cut > 10_000 && unsure > 1000,
        "kept {kept}, cut {cut}, kept without a finite sphere {unsure}"
    );
}

/// A task (`binary`) lists each valid point light in exactly the clusters of its box, and
/// counts every other light once: an invalid one as rejected, a valid one as culled whether the
/// early six-plane cull drops it or the phases then find it no box. Lights that straddle the far
/// plane just outside a side plane are of the second kind: they reach past the side plane only
/// beyond the far plane, so they pass the cull, yet inside the depth range their cross-section
/// lies outside. They are listed nowhere either way, so the oracle suites cannot see them
/// miscounted; this can. Three blocks, in a task that starts past light 0, check that light
/// numbers and counts carry from block to block — for both block widths. The first block also
/// holds a light with an infinite coordinate (rejected) and two whose view-space spheres overflow
/// f32 (phase 0c): one in front, listed in the whole grid, one behind, culled. The next block has,
/// at the same positions, a light that passes the cull but gets no box and one with a box, and
/// no invalid light: they must not inherit the overflow.
#[test]
fn a_task_lists_each_lights_box_and_counts_every_other_light_once() {
    lists_each_lights_box_and_counts_every_other_light_once::<BLOCK>();
    lists_each_lights_box_and_counts_every_other_light_once::<LARGE_BLOCK>();
}

fn lists_each_lights_box_and_counts_every_other_light_once<const B: usize>() {
    let (camera, grid, sets) = frame();
    let planes = FramePlanes::new(&sets, &grid);
    let t = camera.tan_half_fov();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(13);
    let (mut x, mut y, mut z, mut radius) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    // From light 100: two whole blocks and 88 lights of a third.
    let begin = 100;
    let second_block = begin + B;
    for n in 0..second_block + B + 88 {
        let r = 10f32.powf(rng.random_range(-1.0..0.8));
        let (sx, sy) = (
            rng.random_range(-1.3..1.3f32),
            rng.random_range(-1.3..1.3f32),
        );
        let (px, py, depth) = if n % 3 == 0 {
            // Across the far plane (60), just past a side plane there: many pass the early
            // cull yet have no box.
            let depth = 60.0 + r * rng.random_range(0.2..0.9f32);
            let past = r * rng.random_range(0.2..0.9f32);
            let (px, py) = match n % 4 {
                0 => (t.x * 60.0 + past, sy * t.y * depth),
                1 => (-t.x * 60.0 - past, sy * t.y * depth),
                2 => (sx * t.x * depth, t.y * 60.0 + past),
                _ => (sx * t.x * depth, -t.y * 60.0 - past),
            };
            (px, py, depth)
        } else {
            // Depths 0–70, out to 1.3 times the frustum's width and height: lights inside,
            // outside and across it.
            let depth = 70.0 * rng.random::<f32>();
            (sx * t.x * depth, sy * t.y * depth, depth)
        };
        x.push(px);
        y.push(py);
        z.push(-depth);
        // Invalid radii in the first block only: a block whose lights all pass the view
        // test leaves its overflow flags as they were.
        radius.push(match n % 50 {
            0 if n < second_block => 0.0,
            1 if n < second_block => f32::NAN,
            _ => r,
        });
    }
    // The first block's 3rd, 9th and 20th lights, then the second block's 3rd and 9th.
    let (huge_front, huge_behind, infinite) = (begin + 3, begin + 9, begin + 20);
    let (no_box, boxed) = (second_block + 3, second_block + 9);
    let mut put = |l: usize, p: Vec3, r: f32| (x[l], y[l], z[l], radius[l]) = (p.x, p.y, p.z, r);
    put(huge_front, Vec3::new(0.0, 0.0, -3.0e38), 3.3e38);
    put(huge_behind, Vec3::new(0.0, 0.0, 3.0e38), 1.0e38);
    put(infinite, Vec3::new(f32::INFINITY, 0.0, -5.0), 1.0);
    put(no_box, Vec3::new(t.x * 60.8 + 0.3, 0.0, -60.8), 1.0);
    put(boxed, Vec3::new(0.0, 0.0, -10.0), 1.0);
    let mut ctx = culling_context(Method::Binary, &camera, &grid, &sets);
    ctx.lights = LightInput::points(&x, &y, &z, &radius);
    let end = x.len();
    let (mut want, mut rejected, mut culled_early, mut culled_late) = (Vec::new(), 0, 0, 0);
    for l in begin..end {
        if !(radius[l] > 0.0) || !x[l].is_finite() {
            rejected += 1;
            continue;
        }
        if l == huge_front {
            want.extend((0..grid.cluster_count() as u32).map(|c| (l as u32, c)));
            continue;
        }
        if l == huge_behind {
            culled_early += 1;
            continue;
        }
        let v = ctx.view_from_world * Vec3::new(x[l], y[l], z[l]);
        let r = geometry::pad_radius(v.x, v.y, -v.z, radius[l]);
        assert!(r.is_finite(), "light {l}");
        if !ctx.cull.may_touch(v.x, v.y, -v.z, r) {
            culled_early += 1;
            continue;
        }
        let bx = geometry::cluster_box(v.x, v.y, -v.z, r, &planes);
        if l == no_box || l == boxed {
            assert!(ctx.cull.may_touch(v.x, v.y, -v.z, r), "light {l}");
            assert_eq!(bx.is_some(), l == boxed, "light {l}");
        }
        match bx {
            Some(bx) => want.extend(
                box_clusters(&grid, &bx, |_, _, _| true)
                    .iter()
                    .map(|&c| (l as u32, c)),
            ),
            None => culled_late += 1,
        }
    }
    want.sort_unstable();
    assert_task_output(
        task_pairs_in_blocks::<B>(&ctx, begin, end, Build::Dispatched),
        (&want, rejected, culled_early + culled_late),
        &format!("{B}-wide blocks: {culled_early} by the early cull, {culled_late} without a box"),
    );
    // Two invalid radii in every 50 lights of the first block, and the infinite coordinate.
    let invalid = (begin..second_block).filter(|n| n % 50 < 2).count() as u32 + 1;
    assert!(
        rejected == invalid
            && culled_early as usize > B / 3
            && culled_late as usize > B / 12
            && want.len() > 10_000,
        "rejected {rejected}, culled early {culled_early}, without a box {culled_late}, pairs {}",
        want.len()
    );
}

/// The two block widths, and the two builds of each (the dispatched one — AVX2 + FMA where the
/// CPU has them — and the baseline), list the same pairs and count the same lights, for a task
/// that starts mid-block and ends in a partial block, spot lights and invalid lights among
/// them. The builds differ in vector width only (`run_small_blocks`' docs): this runs them
/// side by side.
#[test]
fn both_block_widths_and_both_builds_give_the_same_task_output() {
    let (camera, grid, sets) = frame();
    let t = camera.tan_half_fov();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(15);
    let n = 3 * LARGE_BLOCK + 77;
    let (mut x, mut y, mut z, mut radius) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut dx, mut dy, mut dz, mut angle) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for l in 0..n {
        let depth = 70.0 * rng.random::<f32>();
        x.push(rng.random_range(-1.3..1.3f32) * t.x * depth);
        y.push(rng.random_range(-1.3..1.3f32) * t.y * depth);
        z.push(-depth);
        radius.push(match l % 97 {
            0 => f32::NAN,
            1 => -1.0,
            _ => 10f32.powf(rng.random_range(-1.0..0.8)),
        });
        let d = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        dx.push(d.x);
        dy.push(d.y);
        dz.push(d.z);
        // Every third light a point light (angle π), the others spots of 5–80°.
        angle.push(if l % 3 == 0 {
            std::f32::consts::PI
        } else {
            rng.random_range(5f32..80.0).to_radians()
        });
    }
    for method in [Method::Binary, Method::Refined, Method::Cone] {
        for spots in [false, true] {
            let mut ctx = culling_context(method, &camera, &grid, &sets);
            ctx.lights = LightInput::points(&x, &y, &z, &radius);
            let mut spheres = Vec::new();
            if spots {
                ctx.lights.spot = Some(crate::SpotInput {
                    dir_x: &dx,
                    dir_y: &dy,
                    dir_z: &dz,
                    angle: &angle,
                });
                cluster_bounding_spheres(&camera, &grid, &mut spheres);
                ctx.cluster_spheres = &spheres;
            }
            let (begin, end) = (123, n);
            let small = task_pairs_in_blocks::<BLOCK>(&ctx, begin, end, Build::Dispatched);
            let large = task_pairs_in_blocks::<LARGE_BLOCK>(&ctx, begin, end, Build::Dispatched);
            let what = format!("{method}, spots {spots}");
            let small_baseline = task_pairs_in_blocks::<BLOCK>(&ctx, begin, end, Build::Baseline);
            let large_baseline =
                task_pairs_in_blocks::<LARGE_BLOCK>(&ctx, begin, end, Build::Baseline);
            assert_task_output(large, (&small.0, small.1, small.2), &what);
            for (build, got) in [("small", small_baseline), ("large", large_baseline)] {
                let what = format!("{what}, baseline build of the {build} blocks");
                assert_task_output(got, (&small.0, small.1, small.2), &what);
            }
            assert!(
                small.0.len() > 10_000 && small.1 > 50 && small.2 > 100,
                "{what}: pairs {}, rejected {}, culled {}",
                small.0.len(),
                small.1,
                small.2
            );
        }
    }
}

/// A task's last word of `n` lights, 33 ≤ n < 64, whose first `64 − n` lights alone pass the
/// early cull: its mask has the bits of a whole word of `64 − n` lights, yet the other lights —
/// a zero radius in view (rejected, though its padded radius would give it a box) and a light
/// behind the eye (culled) — must stay out. The task lists exactly what its first `64 − n`
/// lights list alone, and counts each of the others once.
#[test]
fn a_word_whose_first_lights_alone_survive_lists_none_of_the_others() {
    let (camera, grid, sets) = frame();
    for n in 33..64 {
        let live = 64 - n;
        let (mut x, mut y, mut z, mut radius) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let (mut rejected, mut culled) = (0, 0);
        for l in 0..n {
            let (p, r) = if l < live {
                (Vec3::new(0.3 * l as f32 - 3.0, 0.5, -5.0 - l as f32), 1.0)
            } else if l % 2 == 0 {
                rejected += 1;
                (Vec3::new(0.2 * l as f32 - 6.0, 0.0, -10.0), 0.0)
            } else {
                culled += 1;
                (Vec3::new(0.0, 0.0, 10.0), 1.0)
            };
            x.push(p.x);
            y.push(p.y);
            z.push(p.z);
            radius.push(r);
        }
        let mut ctx = culling_context(Method::Binary, &camera, &grid, &sets);
        ctx.lights = LightInput::points(&x, &y, &z, &radius);
        let (alone, none_rejected, none_culled) = task_pairs(&ctx, 0, live);
        assert!(
            (none_rejected, none_culled) == (0, 0) && alone.len() >= live,
            "{live} lights alone: rejected {none_rejected}, culled {none_culled}, pairs {}",
            alone.len()
        );
        assert_task_output(
            task_pairs(&ctx, 0, n),
            (&alone, rejected, culled),
            &format!("a word of {n} lights, the first {live} in view"),
        );
    }
}

/// Spot columns whose lights are all point lights (angle `π`) change nothing: `run_task` lists
/// the same pairs and counts the same rejected and culled lights as without the columns. With
/// spot columns phase 0b recomputes which lights are sound and which may touch the frustum: a
/// light phase 0a found invalid (a zero, negative or NaN radius at a finite position, whose
/// padded radius is finite) must stay out and be rejected, and a valid one must keep its own
/// box rather than fall to phase 0c and the whole grid. The oracle suites give invalid lights
/// only without spot columns, and cannot see a valid light listed in the whole grid (still
/// conservative); this can.
#[test]
fn point_lights_in_spot_columns_are_listed_and_counted_as_without_them() {
    let (camera, grid, sets) = frame();
    let t = camera.tan_half_fov();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(14);
    let (mut x, mut y, mut z, mut radius) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for n in 0..300 {
        // Depths 0–70, out to 1.3 times the frustum's width and height.
        let depth = 70.0 * rng.random::<f32>();
        x.push(rng.random_range(-1.3..1.3f32) * t.x * depth);
        y.push(rng.random_range(-1.3..1.3f32) * t.y * depth);
        z.push(-depth);
        radius.push(match n % 10 {
            0 => 0.0,
            1 => -1.0,
            2 => f32::NAN,
            _ => 10f32.powf(rng.random_range(-1.0..0.8)),
        });
    }
    let n = x.len();
    let (zeros, down, angle) = (vec![0.0; n], vec![-1.0; n], vec![std::f32::consts::PI; n]);
    let mut ctx = culling_context(Method::Binary, &camera, &grid, &sets);
    ctx.lights = LightInput::points(&x, &y, &z, &radius);
    let (want, want_rejected, want_culled) = task_pairs(&ctx, 0, n);
    ctx.lights.spot = Some(crate::SpotInput {
        dir_x: &zeros,
        dir_y: &zeros,
        dir_z: &down,
        angle: &angle,
    });
    assert_task_output(
        task_pairs(&ctx, 0, n),
        (&want, want_rejected, want_culled),
        "with spot columns",
    );
    assert!(
        want_rejected == 90 && want_culled > 20 && want.len() > 1000,
        "rejected {want_rejected}, culled {want_culled}, pairs {}",
        want.len()
    );
}

/// Each cluster's bounding sphere is centred on the centroid of its cell's eight corners and
/// reaches the farthest of them, padded like a light's radius: it holds the cell and is no
/// larger than that. (A sphere around another centre still holds the cell, so the oracle
/// suites cannot see it; a spot's rows then keep clusters its cone misses.)
#[test]
fn cluster_spheres_are_centred_on_their_cells() {
    let (camera, grid, _) = frame();
    let mut spheres = Vec::new();
    cluster_bounding_spheres(&camera, &grid, &mut spheres);
    assert_eq!(spheres.len(), grid.cluster_count());
    let d = grid.dims();
    for (i, j, k) in [(0, 0, 0), (5, 3, 2), (23, 11, 15), (12, 6, 8), (0, 11, 9)] {
        let cell = Cell::of_cluster(&camera, &grid, i, j, k);
        let corners = cell.corners();
        let centroid = corners.iter().sum::<DVec3>() / 8.0;
        let farthest = corners
            .iter()
            .map(|c| c.distance(centroid))
            .fold(0.0, f64::max);
        let s = spheres[grid.cluster_id(i, j, k) as usize];
        let context = format!("cluster ({i}, {j}, {k}) of {d}: {s}, centroid {centroid}");
        assert!(
            (s.truncate().as_dvec3() - centroid).length() <= 1e-6 * centroid.length(),
            "{context}"
        );
        let padded = geometry::pad_radius(s.x, s.y, -s.z, farthest as f32);
        assert!(
            s.w >= farthest as f32 && s.w <= padded * (1.0 + 1e-6),
            "{context}: radius {}, farthest corner {farthest}",
            s.w
        );
    }
}

/// `exact` keeps a running count of its pairs and skips its remaining lights once the count
/// passes the frame's budget (the frame is then retried on a coarser grid), instead of testing
/// every cluster of every light first: a task of 40 large lights under a budget of 10 pairs
/// stops after its first light, which passed it.
#[test]
fn exact_stops_once_its_pairs_pass_the_budget() {
    let (camera, grid, sets) = frame();
    let n = 40;
    let (x, y, r) = (vec![0.0; n], vec![0.0; n], vec![5.0; n]);
    let z: Vec<f32> = (0..n).map(|i| -10.0 - i as f32 * 0.5).collect();
    let run = |lights: usize, budget: u64| {
        let mut ctx = culling_context(Method::Exact, &camera, &grid, &sets);
        ctx.lights = LightInput::points(&x, &y, &z, &r);
        ctx.exact = Some(ExactFrame::new(&camera, budget));
        let mut out = TaskOutput::default();
        run_task(&ctx, 0, lights, &mut out);
        let written: u64 = out.buckets[..ctx.parts].iter().map(|b| b.pairs).sum();
        let exact = ctx.exact.as_ref().unwrap();
        assert_eq!(
            exact.pairs.load(Ordering::Relaxed),
            written,
            "budget {budget}"
        );
        (written, exact.over_budget())
    };
    let (all, over) = run(n, u64::MAX);
    let (first, _) = run(1, u64::MAX);
    assert!(!over && first > 10 && all > 5 * first, "{first} of {all}");
    assert_eq!(run(n, 10), (first, true), "only the first light was tested");
    // A budget the frame fits is never hit.
    assert_eq!(run(n, all), (all, false));
}
