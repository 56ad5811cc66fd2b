// The normal a fragment is shaded with. Vertex normals can interpolate to zero (a zero normal in
// the mesh, or n and -n across one triangle), and `normalize` of zero is NaN: the G-buffer then
// stores NaN, every light's `n_dot_l` is NaN and the pixel comes out NaN (black in 8 bits, and
// spreading through an engine's HDR post-processing). There the triangle's own normal, from the
// position's screen derivatives, turned toward the camera, stands in.

// The triangle's normal (unnormalised, either side) from the screen derivatives of the position.
// Call it first in the fragment shader, before any `discard` and outside any branch: derivatives
// need the whole 2×2 quad running the same code (after a neighbour's `OpKill` they are undefined).
fn face_normal(rel_position: vec3<f32>) -> vec3<f32> {
    return cross(dpdx(rel_position), dpdy(rel_position));
}

// `face` is `face_normal(rel_position)`, taken at the top of the shader.
fn surface_normal(
    interpolated: vec3<f32>,
    face: vec3<f32>,
    rel_position: vec3<f32>,
    front_facing: bool,
) -> vec3<f32> {
    let len2 = dot(interpolated, interpolated);
    // False for NaN, zero and overflowing lengths.
    if (len2 > 1e-30 && len2 < 1e30) {
        let n = interpolated * inverseSqrt(len2);
        return select(-n, n, front_facing);
    }
    let face_len2 = dot(face, face);
    if (face_len2 > 1e-30 && face_len2 < 1e30) {
        let n = face * inverseSqrt(face_len2);
        // The camera is at the origin of camera-relative space: the visible side faces it.
        return select(n, -n, dot(n, rel_position) > 0.0);
    }
    let to_camera = -rel_position;
    return to_camera * inverseSqrt(max(dot(to_camera, to_camera), 1e-30));
}
