// Test pass: evaluates `cluster_of_pixel` for many (pixel, view depth) samples so a test can
// compare every result with the CPU's `ClusterGrid::cluster_of_pixel`; or for (pixel, stored
// depth) samples, converted to view depth as the shading passes do, so a test can check the
// CPU's depth-buffer analysis against the GPU's own rounding.

@group(0) @binding(0) var<uniform> check: ClusterCheck;
@group(0) @binding(1) var<storage, read> sample_pixels: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> sample_depths: array<f32>;
@group(0) @binding(3) var<storage, read> slice_edges: array<f32>;
@group(0) @binding(4) var<storage, read_write> cluster_ids: array<u32>;

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= check.sample_count) {
        return;
    }
    var depth = sample_depths[i];
    if (check.from_stored_depth == 1u) {
        // `near_far`: the near plane and near / far (0 for an infinite far plane).
        depth = view_depth_from_ndc_depth(depth, check.near_far.x, check.near_far.y);
    }
    cluster_ids[i] = cluster_of_pixel(
        sample_pixels[i],
        depth,
        check.target_size,
        check.grid_dims.xyz,
    );
}
