// The cluster of a pixel, computed exactly as `ClusterGrid::cluster_of_pixel` does on the CPU.
//
// Pixel -> tile is the same integer formula, floor((2p + 1) * tiles / (2 * pixels)), in u32 (the
// renderer and the cluster check (`cluster_check.rs`) check that 2 * pixels * tiles fits). Depth -> slice is a binary search of the same f32
// edge table the CPU builds (`ClusterGrid::fill_slice_edges`): only comparisons, so no GPU
// rounding can move a pixel to another slice. The pass that includes this file declares
// `slice_edges: array<f32>` (grid Z + 1 values, near to far).

fn tile_of_pixel(p: u32, pixels: u32, tiles: u32) -> u32 {
    return ((2u * p + 1u) * tiles) / (2u * pixels);
}

// Slice of view depth `depth` for a grid of `z` slices: the largest k in 0..z with
// slice_edges[k] <= depth; below the first inner edge (or NaN) gives 0, beyond the last gives z - 1.
fn slice_of_depth(depth: f32, z: u32) -> u32 {
    // `!(a >= b)` is also true for NaN, as on the CPU.
    if (z == 1u || !(depth >= slice_edges[1])) {
        return 0u;
    }
    if (depth >= slice_edges[z - 1u]) {
        return z - 1u;
    }
    // Invariant: slice_edges[lo] <= depth < slice_edges[hi].
    var lo = 1u;
    var hi = z - 1u;
    loop {
        if (hi - lo <= 1u) {
            break;
        }
        let mid = (lo + hi) / 2u;
        if (depth >= slice_edges[mid]) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

fn cluster_of_pixel(pixel: vec2<u32>, depth: f32, target_size: vec2<u32>, dims: vec3<u32>) -> u32 {
    let i = tile_of_pixel(pixel.x, target_size.x, dims.x);
    let j = tile_of_pixel(pixel.y, target_size.y, dims.y);
    let k = slice_of_depth(depth, dims.z);
    return i + dims.x * (j + dims.y * k);
}

// View depth (distance along the view axis) of a reversed-Z depth-buffer value (1 at near, 0 at
// far), exactly the CPU's `Camera::view_depth_from_ndc_depth` formula, `f·n / (n + ndc·(f − n))`
// divided through by f: `near_over_far` is n/f, 0 for an infinite far plane. It only adds and
// multiplies positive numbers, so it stays within a few ulps of the true depth however small the
// near plane is.
fn view_depth_from_ndc_depth(ndc_depth: f32, near: f32, near_over_far: f32) -> f32 {
    return near / (near_over_far + ndc_depth * (1.0 - near_over_far));
}

// The point a pixel shades (camera-relative) and the view depth that picks its cluster.
struct PixelPoint {
    position: vec3<f32>,
    view_depth: f32,
}

// The pixel's ray at its view depth, from the pixel's centre (`frag_xy`, the fragment's position
// builtin) and its reversed-Z depth: the ray through the near-plane point (well conditioned),
// scaled from the near depth to the pixel's. Unprojecting the depth itself through the inverse
// matrix would cancel like the textbook depth formula and land up to percents off the cluster it
// is shaded from. Deferred shading takes the depth from the G-buffer, the forward pass from its
// own fragment: both shade the point whose depth and pixel picked the cluster, so the point
// stays in (within f32 rounding of) that cluster, which the lists' padding covers. The forward
// pass shaded its interpolated vertex position instead, whose rounding grows with the
// triangle's coordinates: on a blended quad 2e6 across it sat centimetres outside its cluster
// and lights its list rightly leaves out lit it under brute force (audit, up to 183/255).
fn pixel_point(frag_xy: vec2<f32>, ndc_depth: f32, f: Frame) -> PixelPoint {
    let size = vec2<f32>(f.target_size);
    let ndc = vec2<f32>(frag_xy.x / size.x * 2.0 - 1.0, 1.0 - frag_xy.y / size.y * 2.0);
    let view_depth = view_depth_from_ndc_depth(ndc_depth, f.camera_near, f.camera_near_over_far);
    let on_near = f.world_rel_from_clip * vec4<f32>(ndc, 1.0, 1.0);
    return PixelPoint(on_near.xyz / on_near.w * (view_depth / f.camera_near), view_depth);
}
