//! Faces pressed flat against another face: the bottom of a wall standing on a floor, a column's
//! foot on a slab. No eye sees them, and a surface light lifted off one lies inside the solid it
//! rests on — in the default atrium, 23 % of a surface field's lights sat inside its floor slab,
//! beams, spandrels and column plinths before these faces were left out.
//!
//! A face is *pressed* when other faces, coplanar with it and turned the opposite way (within
//! [`PLANE_TOLERANCE`] of its plane, normals within about 0.8° of opposite), cover all of it: two
//! solids touching along it. All of it, not its centre or its corners: a column standing half
//! over an opening keeps its foot, whose exposed half an eye below sees, and a floor keeps its
//! top though walls stand on its corners. A face covered in part keeps the rest: its
//! [`Rest`]s tell the sampler where no light goes. Faces whose covering faces overlap one
//! another (their areas would count twice), or that rest on more than [`MOST_COVERING`], are
//! not proven covered: they stay, and their rests keep the lights off the covered parts.
//!
//! The exact mirror of a face — the same three corners, wound the other way — never counts as
//! what it rests on: that is how a model draws a two-sided sheet (a banner, a leaf), both sides
//! visible. The test is only that: a sheet whose back is triangulated otherwise is taken for two
//! solids touching and loses both sides, and two solids touching along faces of the same three
//! corners are taken for a sheet and keep theirs. Telling them apart needs the solids (is there
//! volume behind each face?), which a triangle soup does not give.
//!
//! Candidates are found through a hash of each face's plane, coarsely keyed ([`PlaneKey`]), so a
//! model of 262k faces (Sponza) takes one pass; an offset that falls on a bin's edge is also
//! looked up in the neighbouring bins. A pressed face the key misses (a plane a little tilted,
//! far from the origin, whose offsets there differ by more than a bin) is kept: the rule only
//! ever leaves out faces it has proven covered, and keeping one is what every face had before.

use glam::{DVec3, Vec3};
use std::collections::HashMap;

/// How far a corner may lie off another face's plane and still rest on it, relative to the
/// face's largest coordinate (at least 1 m): about 16 f32 steps there, room for the rounding of
/// instance transforms, far below any modelled gap — a 4 cm panel 4 km from the origin keeps
/// its two faces apart (8 mm).
const PLANE_TOLERANCE: f64 = 2e-6;

/// Two normals at least this opposite (`n₁ · n₂ ≤ −this`) face each other: about 0.8°.
const OPPOSITE: f64 = 0.9999;

/// How close another component of a normal must come to its largest for a lookup to try that
/// axis too: the normals that pass the [`OPPOSITE`] test differ by under 0.0142 in each
/// component, so the axis the other face is filed under (its largest component) is within
/// 2 × 0.0142 of this one's largest.
const AXIS_TIE: f64 = 0.03;

/// Candidate tests (a face against one in the bin it looks up) in all: a model whose faces
/// crowd one plane from both sides (a ground of 100k triangles exported twice, once each way)
/// would take their square. Past it, faces are kept whole, as before the rule
/// ([`Contacts::unchecked`]).
const CANDIDATE_TESTS: usize = 1 << 26;

/// The most faces a face may rest on for [`covered`] to test their overlaps pairwise.
const MOST_COVERING: usize = 128;

/// A face's plane, coarsely: the axis its normal points most along, with its sign (0–5), and its
/// offset from the origin in bins. A coarse key keeps lookups few (a finer one on all three
/// components, with its neighbours, took 1.8 s on Sponza's 262k faces); the exact tests sort the
/// candidates it gives.
type PlaneKey = (u8, i64);

/// An axis with a sign, 0–5.
fn signed_axis(n: DVec3, i: usize) -> u8 {
    2 * i as u8 + u8::from(n[i] < 0.0)
}

/// The axis (with sign) a normal points most along: what it is filed under.
fn main_axis(n: DVec3) -> u8 {
    let a = n.abs();
    let i = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    signed_axis(n, i)
}

/// The axes (with sign) a lookup for a face turned like `n` tries: the largest component's, and
/// any other within [`AXIS_TIE`] of it.
fn near_main_axes(n: DVec3) -> impl Iterator<Item = u8> {
    let a = n.abs();
    let top = a.max_element();
    (0..3)
        .filter(move |&i| a[i] >= top - AXIS_TIE)
        .map(move |i| signed_axis(n, i))
}

/// A face another one rests on, with what it takes to test a point against it.
#[derive(Clone, Debug)]
pub(crate) struct Rest {
    corners: [Vec3; 3],
    /// Its plane: unit normal and offset from the origin.
    plane: (DVec3, f64),
    tolerance: f64,
}

impl Rest {
    /// Whether `p` (a point of the face resting on this one) touches this face.
    pub(crate) fn holds(&self, p: Vec3) -> bool {
        lies_on(p.as_dvec3(), &self.corners, self.plane, self.tolerance)
    }
}

/// Where faces touch others: for each triangle, whether it is pressed (covered all over, see the
/// module docs) and the faces it rests on (covering part of it, or all).
#[derive(Clone, Debug, Default)]
pub(crate) struct Contacts {
    pub pressed: Vec<bool>,
    pub rests: Vec<Vec<Rest>>,
    /// The last faces, kept whole without a search once [`CANDIDATE_TESTS`] ran out.
    pub unchecked: usize,
}

/// The contacts of these triangles. `normals` are their unit normals on their counter-clockwise
/// front side.
pub(crate) fn contacts(corners: &[[Vec3; 3]], normals: &[Vec3]) -> Contacts {
    contacts_within(corners, normals, CANDIDATE_TESTS)
}

/// [`contacts`] with a budget of `tests` candidate tests.
fn contacts_within(corners: &[[Vec3; 3]], normals: &[Vec3], tests: usize) -> Contacts {
    debug_assert_eq!(corners.len(), normals.len());
    // How far a point may lie off a plane and still be on it, near a face: relative to the
    // face's own coordinates (f32 spacing grows with them), at least [`PLANE_TOLERANCE`] metres.
    let tolerance_at = |t: &[Vec3; 3]| {
        let size = t
            .iter()
            .map(|p| p.abs().max_element())
            .fold(1.0f32, f32::max);
        PLANE_TOLERANCE * f64::from(size)
    };
    let largest = corners
        .iter()
        .map(tolerance_at)
        .fold(PLANE_TOLERANCE, f64::max);
    // Offsets are binned four of the largest tolerances wide, so a match sits in its bin or the
    // next one.
    let bin = 4.0 * largest;
    let planes: Vec<(DVec3, f64)> = corners
        .iter()
        .zip(normals)
        .map(|(t, n)| {
            let n = n.as_dvec3();
            (n, n.dot(t[0].as_dvec3()))
        })
        .collect();
    let offset_bin = |d: f64| (d / bin).round() as i64;
    let mut by_plane: HashMap<PlaneKey, Vec<u32>> = HashMap::new();
    for (t, &(n, d)) in planes.iter().enumerate() {
        by_plane
            .entry((main_axis(n), offset_bin(d)))
            .or_default()
            .push(t as u32);
    }
    let mut candidates = Vec::new();
    let mut contacts = Contacts::default();
    let mut tests_left = tests;
    for f in 0..corners.len() {
        let (n, d) = planes[f];
        let tolerance = tolerance_at(&corners[f]);
        // The faces it could rest on: turned the other way, in the same plane.
        let kd = offset_bin(-d);
        candidates.clear();
        for axis in near_main_axes(-n) {
            for dd in -1..=1 {
                let Some(faces) = by_plane.get(&(axis, kd + dd)) else {
                    continue;
                };
                if faces.len() > tests_left {
                    tests_left = 0;
                    continue;
                }
                tests_left -= faces.len();
                candidates.extend(faces.iter().map(|&g| g as usize).filter(|&g| {
                    // In its plane where this face lies, not only at the origin (normals may
                    // differ by a little).
                    let (m, e) = planes[g];
                    n.dot(m) <= -OPPOSITE
                        && corners[f]
                            .iter()
                            .all(|p| (m.dot(p.as_dvec3()) - e).abs() <= tolerance)
                        && !mirrors(&corners[f], &corners[g])
                }));
            }
        }
        if tests_left == 0 {
            // Out of budget: this face and the rest are kept whole, as before the rule.
            contacts.unchecked = corners.len() - f;
            contacts.pressed.resize(corners.len(), false);
            contacts.rests.resize(corners.len(), Vec::new());
            break;
        }
        // Only faces with a part of this one's area on them: one that merely shares an
        // edge or a corner holds no light back.
        let [a, b, c] = corners[f].map(|v| v.as_dvec3());
        let area = polygon_area(&[a, b, c]);
        candidates
            .retain(|&g| polygon_area(&clip(&[a, b, c], &corners[g], planes[g].0)) > area * 1e-9);
        contacts.pressed.push(
            !candidates.is_empty()
                && covered(&corners[f], &candidates, corners, &planes, tolerance),
        );
        contacts.rests.push(
            candidates
                .iter()
                .map(|&g| Rest {
                    corners: corners[g],
                    plane: planes[g],
                    tolerance,
                })
                .collect(),
        );
    }
    contacts
}

/// Whether the faces `on` (coplanar with `t`, turned the other way, each holding part of it)
/// cover triangle `t`: the parts of `t` on each, which must not overlap one another, add up to
/// all of its area, and its corners, edge midpoints and centre each lie on one of them.
/// Overlapping faces would count an area twice, so a face resting on such is not proven
/// covered (it keeps its uncovered parts through its rests either way); neither is one resting
/// on more than [`MOST_COVERING`] faces (the pairwise test grows with their square).
fn covered(
    t: &[Vec3; 3],
    on: &[usize],
    corners: &[[Vec3; 3]],
    planes: &[(DVec3, f64)],
    tolerance: f64,
) -> bool {
    if on.len() > MOST_COVERING {
        return false;
    }
    let [a, b, c] = t.map(|v| v.as_dvec3());
    let area = polygon_area(&[a, b, c]);
    let parts: Vec<Vec<DVec3>> = on
        .iter()
        .map(|&g| clip(&[a, b, c], &corners[g], planes[g].0))
        .collect();
    let overlap = |i: usize, j: usize| {
        !parts[i].is_empty() && {
            let both = clip(&parts[i], &corners[on[j]], planes[on[j]].0);
            polygon_area(&both) > area * 1e-9
        }
    };
    if (0..on.len()).any(|i| (i + 1..on.len()).any(|j| overlap(i, j))) {
        return false;
    }
    let inside: f64 = parts.iter().map(|p| polygon_area(p)).sum();
    let points = [
        a,
        b,
        c,
        (a + b) / 2.0,
        (b + c) / 2.0,
        (c + a) / 2.0,
        (a + b + c) / 3.0,
    ];
    inside >= area * (1.0 - 1e-4)
        && points.iter().all(|&p| {
            on.iter()
                .any(|&g| lies_on(p, &corners[g], planes[g], tolerance))
        })
}

/// The part of the convex polygon `polygon` inside triangle `t` (unit normal `normal`, its
/// counter-clockwise side), both in one plane: clipped by each edge's inward half-space
/// (Sutherland–Hodgman).
fn clip(polygon: &[DVec3], t: &[Vec3; 3], normal: DVec3) -> Vec<DVec3> {
    let mut points = polygon.to_vec();
    let t = t.map(|v| v.as_dvec3());
    for k in 0..3 {
        let (from, to) = (t[k], t[(k + 1) % 3]);
        let inward = normal.cross(to - from);
        let side = |p: DVec3| inward.dot(p - from);
        let mut kept = Vec::with_capacity(points.len() + 1);
        for (i, &p) in points.iter().enumerate() {
            let q = points[(i + 1) % points.len()];
            let (sp, sq) = (side(p), side(q));
            if sp >= 0.0 {
                kept.push(p);
            }
            if (sp >= 0.0) != (sq >= 0.0) {
                kept.push(p + (q - p) * (sp / (sp - sq)));
            }
        }
        points = kept;
        if points.len() < 3 {
            return Vec::new();
        }
    }
    points
}

/// The area of a planar polygon given by its corners in order.
fn polygon_area(polygon: &[DVec3]) -> f64 {
    let n = polygon.len();
    let twice: DVec3 = (0..n).map(|i| polygon[i].cross(polygon[(i + 1) % n])).sum();
    0.5 * twice.length()
}

/// Whether `b` holds the same three corners as `a` (in any order): one sheet's two sides.
fn mirrors(a: &[Vec3; 3], b: &[Vec3; 3]) -> bool {
    a.iter().all(|p| b.contains(p))
}

/// Whether `p` lies on triangle `t` (plane `(normal, offset)`): within `tolerance` of its plane,
/// and inside it or on its edges once dropped onto it.
fn lies_on(p: DVec3, t: &[Vec3; 3], (normal, offset): (DVec3, f64), tolerance: f64) -> bool {
    if (normal.dot(p) - offset).abs() > tolerance {
        return false;
    }
    let [a, b, c] = t.map(|v| v.as_dvec3());
    let (u, v, w) = (b - a, c - a, p - a);
    let (uu, uv, vv, wu, wv) = (u.dot(u), u.dot(v), v.dot(v), w.dot(u), w.dot(v));
    let den = uu * vv - uv * uv;
    if !(den > 0.0) {
        return false;
    }
    // Barycentric coordinates, with an edge tolerance relative to the triangle's size: a wall's
    // corner on the floor's edge counts as on the floor.
    let s = (vv * wu - uv * wv) / den;
    let r = (uu * wv - uv * wu) / den;
    let slack = 1e-6;
    s >= -slack && r >= -slack && s + r <= 1.0 + slack
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two triangles of an axis-aligned rectangle at height `y`, facing up or down.
    fn rect(x0: f32, z0: f32, x1: f32, z1: f32, y: f32, up: bool) -> Vec<[Vec3; 3]> {
        let (a, b, c, d) = (
            Vec3::new(x0, y, z0),
            Vec3::new(x1, y, z0),
            Vec3::new(x1, y, z1),
            Vec3::new(x0, y, z1),
        );
        // Counter-clockwise seen from +y is (a, d, c): its normal is +y.
        if up {
            vec![[a, d, c], [a, c, b]]
        } else {
            vec![[a, c, d], [a, b, c]]
        }
    }

    /// The faces' counter-clockwise unit normals.
    fn normals_of(faces: &[[Vec3; 3]]) -> Vec<Vec3> {
        faces
            .iter()
            .map(|t| (t[1] - t[0]).cross(t[2] - t[0]).normalize())
            .collect()
    }

    fn pressed(faces: &[[Vec3; 3]]) -> Vec<bool> {
        contacts(faces, &normals_of(faces)).pressed
    }

    #[test]
    fn a_foot_on_a_floor_is_pressed_and_the_floor_is_not() {
        let mut faces = rect(-15.0, -7.5, 15.0, 7.5, 0.0, true);
        faces.extend(rect(-1.0, -1.0, 1.0, 0.5, 0.0, false));
        assert_eq!(pressed(&faces), [false, false, true, true]);
    }

    #[test]
    fn a_foot_on_the_floors_edge_is_pressed() {
        let mut faces = rect(-15.0, -7.5, 15.0, 7.5, 0.0, true);
        faces.extend(rect(14.0, -7.5, 15.0, 7.5, 0.0, false));
        assert_eq!(pressed(&faces), [false, false, true, true]);
    }

    #[test]
    fn a_foot_half_over_an_opening_is_kept() {
        let mut faces = rect(-15.0, -7.5, 0.0, 7.5, 0.0, true);
        faces.extend(rect(-1.0, -1.0, 1.0, 1.0, 0.0, false));
        assert_eq!(pressed(&faces), [false, false, false, false]);
    }

    #[test]
    fn a_foot_a_hair_above_the_floor_is_pressed_and_one_a_millimetre_above_is_not() {
        for (lift, expected) in [(1e-6f32, true), (1e-3, false)] {
            let mut faces = rect(-15.0, -7.5, 15.0, 7.5, 0.0, true);
            faces.extend(rect(-1.0, -1.0, 1.0, 1.0, lift, false));
            assert_eq!(
                pressed(&faces),
                [false, false, expected, expected],
                "lifted {lift}"
            );
        }
    }

    #[test]
    fn faces_turned_the_same_way_do_not_press() {
        let mut faces = rect(-15.0, -7.5, 15.0, 7.5, 0.0, true);
        faces.extend(rect(-1.0, -1.0, 1.0, 1.0, 0.0, true));
        assert_eq!(pressed(&faces), [false; 4]);
    }

    #[test]
    fn a_sliver_on_the_floor_presses_only_when_its_normal_is_within_the_opposite_test() {
        // A sliver 0.1 mm deep, tilted about x: its corners stay within the plane tolerance, so
        // the normals decide (0.5°: opposite enough; 1°: not).
        for (degrees, expected) in [(0.5f32, true), (1.0, false)] {
            let (s, c) = degrees.to_radians().sin_cos();
            let p = |x: f32, z: f32| Vec3::new(x, z * s, z * c);
            let mut faces = rect(-15.0, -7.5, 15.0, 7.5, 0.0, true);
            faces.push([p(-1.0, 0.0), p(1.0, 1e-4), p(-1.0, 1e-4)]);
            assert_eq!(pressed(&faces), [false, false, expected], "{degrees}°");
        }
    }

    #[test]
    fn planes_that_meet_at_the_origin_but_not_where_the_faces_are_do_not_press() {
        // A foot at y = 0 about x = 100, and under it a floor tilted 0.5° about z through the
        // origin: the same plane offset, normals within the opposite test, 0.87 m apart there.
        let foot = rect(99.0, -1.0, 101.0, 1.0, 0.0, false);
        let (s, c) = 0.5f32.to_radians().sin_cos();
        let tilted = |v: Vec3| Vec3::new(v.x * c, -v.x * s, v.z);
        let floor: Vec<[Vec3; 3]> = rect(90.0, -5.0, 110.0, 5.0, 0.0, true)
            .into_iter()
            .map(|t| t.map(tilted))
            .collect();
        let faces: Vec<[Vec3; 3]> = foot.into_iter().chain(floor).collect();
        assert_eq!(pressed(&faces), [false; 4]);
    }

    #[test]
    fn a_foot_on_two_overlapping_floors_is_not_proven_covered_but_rests_on_both() {
        // Two floors overlapping over x ∈ [−1, 1]: their parts of the foot add up to more than
        // its area, which proves nothing; the foot stays, resting on both.
        let mut faces = rect(-15.0, -7.5, 1.0, 7.5, 0.0, true);
        faces.extend(rect(-1.0, -7.5, 15.0, 7.5, 0.0, true));
        faces.extend(rect(-2.0, -1.0, 2.0, 1.0, 0.0, false));
        let normals = normals_of(&faces);
        let found = contacts(&faces, &normals);
        assert_eq!(found.pressed, [false; 6]);
        assert!(found.rests[4].len() >= 2 && found.rests[5].len() >= 2);
        assert!(
            found.rests[4]
                .iter()
                .any(|r| r.holds(Vec3::new(-1.5, 0.0, 0.0)))
        );
        assert!(
            found.rests[4]
                .iter()
                .any(|r| r.holds(Vec3::new(1.5, 0.0, 0.0)))
        );
    }

    #[test]
    fn past_the_budget_the_remaining_faces_are_kept_unsearched() {
        // A ground of 16 triangles exported once each way, triangulated differently (so no face
        // is another's mirror): each side covers the other.
        let mut faces = Vec::new();
        for k in 0..8 {
            let x = k as f32;
            faces.extend(rect(x, 0.0, x + 1.0, 1.0, 0.0, true));
        }
        for k in 0..8 {
            let x = k as f32;
            let corner = |dx: f32, dz: f32| Vec3::new(x + dx, 0.0, dz);
            let (a, b, c, d) = (
                corner(0.0, 0.0),
                corner(1.0, 0.0),
                corner(1.0, 1.0),
                corner(0.0, 1.0),
            );
            // Facing down, split along the other diagonal.
            faces.extend([[a, b, d], [b, c, d]]);
        }
        let normals = normals_of(&faces);
        let all = contacts_within(&faces, &normals, usize::MAX);
        assert_eq!(all.unchecked, 0);
        assert!(all.pressed.iter().all(|&p| p));
        // Each face tests the 16 of the other side: 4 faces' worth, then the budget is out.
        let some = contacts_within(&faces, &normals, 4 * 16 + 8);
        assert_eq!(some.unchecked, 28);
        assert_eq!(some.pressed[..4], [true; 4]);
        assert!(some.pressed[4..].iter().all(|&p| !p));
        assert!(some.rests[4..].iter().all(|r| r.is_empty()));
    }

    #[test]
    fn the_two_sides_of_a_sheet_are_kept() {
        let mut faces = rect(-1.0, -1.0, 1.0, 1.0, 2.0, true);
        faces.extend(rect(-1.0, -1.0, 1.0, 1.0, 2.0, false));
        assert_eq!(pressed(&faces), [false; 4]);
    }

    #[test]
    fn two_stacked_boxes_press_their_touching_faces_far_from_the_origin() {
        // Far out, where f32 spacing is ~1 mm: the tolerance scales with the model.
        let far = 20_000.0;
        let mut faces = rect(far - 5.0, -5.0, far + 5.0, 5.0, 3.0, true);
        faces.extend(rect(far - 2.0, -2.0, far + 2.0, 2.0, 3.0, false));
        assert_eq!(pressed(&faces), [false, false, true, true]);
    }
}
