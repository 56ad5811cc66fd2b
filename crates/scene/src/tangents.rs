//! Vertex attributes a glTF file may leave out and the renderer needs: flat normals, and tangents
//! for normal mapping.
//!
//! Why generate them here: glTF says a primitive without normals gets flat normals, and that
//! tangents, when absent, are to be computed (the spec names MikkTSpace). The renderer should get
//! complete vertex arrays and never branch on what a file happened to contain.
//!
//! ## Tangents: per-triangle accumulation (not MikkTSpace)
//! 1. For each triangle with corners `p0, p1, p2` and UVs `t0, t1, t2`, solve
//!    `e1 = du1·T + dv1·B`, `e2 = du2·T + dv2·B` for the UV-space axes `T` (direction of +u) and
//!    `B` (+v), where `e1 = p1 − p0`, `(du1, dv1) = t1 − t0` and likewise for `e2`. The solution
//!    is multiplied by `|det|` of the UV system (only its sign is divided out), so bigger
//!    triangles weigh more: for a mapping of uniform texel density the weight is proportional
//!    to the triangle's area.
//! 2. Add `T` and `B` to the accumulators of the triangle's three vertices.
//! 3. Per vertex: Gram–Schmidt `T` against the normal `n` (`T − n (n·T)`), normalise, and store
//!    the handedness `w = sign((n × T) · B)` (±1), so `B = w · (n × T)` in the shader.
//! 4. A vertex whose accumulated `T` is zero or parallel to `n` (degenerate UVs, or no triangle)
//!    gets an arbitrary unit vector perpendicular to `n`, `w = 1`.
//!
//! This matches MikkTSpace on well-formed, smoothly mapped meshes and differs at UV seams and on
//! mirrored or degenerate triangles (MikkTSpace splits and weights by angle). Normal maps baked
//! with MikkTSpace may show faint seams; exactness was not required.

use glam::{Vec2, Vec3, Vec4};

/// Flat normals for a triangle list: returns the un-shared vertex positions (three per
/// triangle), their normals (the face normal, or +Z for a degenerate triangle), the UVs
/// un-shared the same way (empty when `tex_coords` is empty), and the new indices `0, 1, 2, …`.
pub(crate) fn flat_normals(
    positions: &[Vec3],
    tex_coords: &[Vec2],
    indices: &[u32],
) -> (Vec<Vec3>, Vec<Vec3>, Vec<Vec2>, Vec<u32>) {
    assert!(indices.len().is_multiple_of(3));
    assert!(tex_coords.is_empty() || tex_coords.len() == positions.len());
    let mut out_positions = Vec::with_capacity(indices.len());
    let mut out_normals = Vec::with_capacity(indices.len());
    let mut out_uvs = Vec::with_capacity(if tex_coords.is_empty() {
        0
    } else {
        indices.len()
    });
    for tri in indices.chunks_exact(3) {
        let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a).normalize_or(Vec3::Z);
        for &i in tri {
            out_positions.push(positions[i as usize]);
            out_normals.push(n);
            if !tex_coords.is_empty() {
                out_uvs.push(tex_coords[i as usize]);
            }
        }
    }
    let new_indices = (0..indices.len() as u32).collect();
    (out_positions, out_normals, out_uvs, new_indices)
}

/// Tangents (xyz unit, w = ±1 handedness) for a triangle list, by per-triangle accumulation (see
/// the module docs). `normals` and `tex_coords` have one entry per position; every index is in
/// range.
pub(crate) fn generate_tangents(
    positions: &[Vec3],
    normals: &[Vec3],
    tex_coords: &[Vec2],
    indices: &[u32],
) -> Vec<Vec4> {
    assert_eq!(positions.len(), normals.len());
    assert_eq!(positions.len(), tex_coords.len());
    let mut tangent = vec![Vec3::ZERO; positions.len()];
    let mut bitangent = vec![Vec3::ZERO; positions.len()];
    for tri in indices.chunks_exact(3) {
        let [i0, i1, i2] = [tri[0], tri[1], tri[2]].map(|i| i as usize);
        let e1 = positions[i1] - positions[i0];
        let e2 = positions[i2] - positions[i0];
        let d1 = tex_coords[i1] - tex_coords[i0];
        let d2 = tex_coords[i2] - tex_coords[i0];
        let det = d1.x * d2.y - d2.x * d1.y;
        if det == 0.0 || !det.is_finite() {
            continue; // no UV parametrisation on this triangle
        }
        // (T, B)·|det|: dividing by the sign alone weights the triangle by its size.
        let s = det.signum();
        let t = (e1 * d2.y - e2 * d1.y) * s;
        let b = (e2 * d1.x - e1 * d2.x) * s;
        for i in [i0, i1, i2] {
            tangent[i] += t;
            bitangent[i] += b;
        }
    }
    (0..positions.len())
        .map(|i| {
            let n = normals[i];
            let t = tangent[i] - n * n.dot(tangent[i]);
            let t = if t.length_squared() > 1e-10 * tangent[i].length_squared().max(1e-30) {
                t.normalize_or(n.any_orthonormal_vector())
            } else {
                n.any_orthonormal_vector()
            };
            let w = if n.cross(t).dot(bitangent[i]) < 0.0 {
                -1.0
            } else {
                1.0
            };
            t.extend(w)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_normals_unshare_vertices() {
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let uvs = [Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::ONE];
        // Two triangles sharing the edge 0-1, facing +Z and (Z × X =) +Y.
        let (p, n, t, i) = flat_normals(&positions, &uvs, &[0, 1, 2, 0, 3, 1]);
        assert_eq!(p.len(), 6);
        assert_eq!(i, [0, 1, 2, 3, 4, 5]);
        assert_eq!(&n[..3], &[Vec3::Z; 3]);
        assert_eq!(&n[3..], &[Vec3::Y; 3]);
        assert_eq!(t[4], Vec2::ONE);
        let (_, n, t, _) = flat_normals(&positions, &[], &[0, 0, 0]);
        assert_eq!(n, [Vec3::Z; 3], "degenerate triangle falls back to +Z");
        assert!(t.is_empty());
    }

    #[test]
    fn tangents_follow_u_and_record_handedness() {
        // A quad in the XY plane facing +Z, u along +X and v along +Y.
        let positions = [
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(2.0, 2.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
        ];
        let normals = [Vec3::Z; 4];
        let uvs = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        let indices = [0, 1, 2, 0, 2, 3];
        for t in generate_tangents(&positions, &normals, &uvs, &indices) {
            assert!((t - Vec4::new(1.0, 0.0, 0.0, 1.0)).length() < 1e-6, "{t}");
        }
        // Mirror u: the tangent flips to -X and stays right-handed with B = +Y only via w = -1.
        let mirrored = uvs.map(|t| Vec2::new(1.0 - t.x, t.y));
        for t in generate_tangents(&positions, &normals, &mirrored, &indices) {
            assert!((t - Vec4::new(-1.0, 0.0, 0.0, -1.0)).length() < 1e-6, "{t}");
        }
        // A normal tilted out of the plane: the tangent stays perpendicular to it.
        let tilted = [Vec3::new(0.6, 0.0, 0.8); 4];
        for t in generate_tangents(&positions, &tilted, &uvs, &indices) {
            assert!(t.truncate().dot(tilted[0]).abs() < 1e-6);
            assert!((t.truncate().length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn degenerate_uvs_get_some_perpendicular_tangent() {
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(5.0, 5.0, 5.0)];
        let normals = [Vec3::Z; 4];
        let uvs = [Vec2::ZERO; 4]; // all the same: no parametrisation
        let tangents = generate_tangents(&positions, &normals, &uvs, &[0, 1, 2]);
        for t in tangents {
            assert!(t.truncate().dot(Vec3::Z).abs() < 1e-6);
            assert!((t.truncate().length() - 1.0).abs() < 1e-6);
            assert_eq!(t.w, 1.0);
        }
    }

    /// Positions `origin + u·U + v·V` over a fan of triangles with varied UVs, normals `+Z`:
    /// every tangent should be `U` made unit, with `w = sign((Z × U) · V)`.
    fn affine_fan(u_axis: Vec3, v_axis: Vec3) -> Vec<Vec4> {
        let origin = Vec3::new(1.0, 2.0, 3.0);
        let uvs = [
            Vec2::new(0.2, 0.3),
            Vec2::new(1.1, 0.4),
            Vec2::new(0.9, 1.3),
            Vec2::new(0.1, 1.0),
            Vec2::new(0.3, 0.35),
            Vec2::new(-0.5, 0.6),
            // A triangle of its own, clockwise in UV space.
            Vec2::new(2.0, 2.0),
            Vec2::new(2.1, 3.0),
            Vec2::new(3.0, 2.1),
        ];
        let positions = uvs.map(|t| origin + u_axis * t.x + v_axis * t.y);
        let indices = [0, 1, 2, 0, 2, 3, 1, 4, 3, 5, 0, 3, 6, 7, 8];
        let tangents = generate_tangents(&positions, &[Vec3::Z; 9], &uvs, &indices);
        assert_eq!(tangents.len(), 9);
        tangents
    }

    #[test]
    fn tangents_follow_u_under_any_affine_mapping() {
        let (u, v) = (Vec3::new(2.0, 0.5, 0.0), Vec3::new(0.5, 1.5, 0.0));
        for t in affine_fan(u, v) {
            assert!((t - u.normalize().extend(1.0)).length() < 1e-5, "{t}");
        }
        // v reversed against the same normal: the same tangent, left-handed.
        for t in affine_fan(u, -v) {
            assert!((t - u.normalize().extend(-1.0)).length() < 1e-5, "{t}");
        }
    }

    #[test]
    fn triangles_with_collinear_uvs_add_nothing() {
        // Triangle 0-1-2 maps u to +X; triangle 0-2-3 has all its UVs on one line (u = 0).
        let positions = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let uvs = [
            Vec2::ZERO,
            Vec2::X,
            Vec2::new(0.0, 1.0),
            Vec2::new(0.0, 2.0),
        ];
        let tangents = generate_tangents(&positions, &[Vec3::Z; 4], &uvs, &[0, 1, 2, 0, 2, 3]);
        assert_eq!(tangents.len(), 4);
        for i in [0, 1, 2] {
            assert!(
                tangents[i].truncate().dot(Vec3::X) > 0.99,
                "{}",
                tangents[i]
            );
        }
    }

    #[test]
    fn a_tangent_along_the_normal_falls_back_to_a_perpendicular_one() {
        // The triangle's u direction is the vertex normal itself (not axis-aligned, so the
        // Gram–Schmidt residual is f32 rounding, not zero): step 4 of the module docs.
        for k in 0..50 {
            let a = k as f32 * 0.13;
            let n = Vec3::new(a.cos() * 0.6, a.sin() * 0.6, 0.8).normalize();
            let origin = Vec3::new(1.0, 2.0, 3.0);
            let positions = [
                origin,
                origin + n * 1.7,
                origin + n.any_orthonormal_vector(),
            ];
            let uvs = [Vec2::ZERO, Vec2::X, Vec2::Y];
            for t in generate_tangents(&positions, &[n; 3], &uvs, &[0, 1, 2]) {
                assert!(t.truncate().dot(n).abs() < 1e-3, "normal {n}, tangent {t}");
                assert!((t.truncate().length() - 1.0).abs() < 1e-5);
            }
        }
    }
}
