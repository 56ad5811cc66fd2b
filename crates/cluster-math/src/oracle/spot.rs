//! Exact f64 spot-volume vs cell test: GJK on support functions with certified bounds, and an
//! exact feature search where GJK stalls.
//!
//! # Why it exists
//! Every fast spot-light assignment method in `myriad-assignment` must be *conservative*: it may
//! add a spot light to a cluster it does not touch, but it must never miss one it does. This
//! function is the reference those methods are checked against, so it answers the geometric
//! question itself, not a bounding-volume approximation of it. It is slow by design (f64, an
//! iterative algorithm per light–cell pair: about a microsecond) and is meant for the `exact`
//! method, benches and tests.
//!
//! # What is tested
//! The spot volume `S` is the closed set
//! `{p : |p − apex| ≤ range and (p = apex or ∠(p − apex, direction) ≤ angle)}`,
//! i.e. the light's ball cut by its outer cone. The cell `C` is the closed convex cluster cell of
//! [`Cell`]. Touching counts as intersecting (both sets are closed).
//!
//! * For `angle ≤ 90°`, `S` is convex: it is the convex hull of the apex and the spherical cap
//!   `{apex + range·u : ∠(u, direction) ≤ angle}` (every point of `S` lies on a segment from the
//!   apex to a cap point). Two convex sets are disjoint iff some direction `u` separates them,
//!   i.e. iff the *gap* `min_{c∈C} u·c − max_{s∈S} u·s` is positive; for any unit `u` the gap is a
//!   lower bound of their distance, and its maximum over `u` equals the distance. Both support
//!   functions are exact and cheap here.
//! * For `angle > 90°`, `S` is not convex. myriad treats spot lights wider than 90° as point
//!   lights (glTF's `KHR_lights_punctual` caps the outer cone angle at 90° anyway; see also
//!   `spot_bounding_sphere`), so the oracle falls back to the ball test
//!   [`sphere_intersects_cell`](super::sphere_intersects_cell): a superset, hence still a valid
//!   reference for *conservative* methods.
//!
//! # Exactness
//! The answer is exact except in a band of width `tol = 1e-12 · scale` (`scale` = the largest of
//! `range`, `|apex|` and the magnitudes of the corners of the cell cut off one range beyond the
//! ball's far depth — local to the light, however deep the cell reaches), where it errs on the
//! side of "intersects"; the ball test (step 2) uses a band of 64 ulps of `scale` instead, and
//! the wall test (step 5) one of 64 ulps of `|apex| + range` (narrower than `tol`: that step
//! rounds with the light's coordinates alone):
//! * `false` is only returned with a *certificate*: a direction whose gap exceeds `tol` (up to f64
//!   rounding of two support values, orders of magnitude below `tol`), a wall of the cell the
//!   volume lies beyond by more than its band, or the ball's miss.
//! * `true` comes with a certificate too — a point of `C − S` (a convex combination of support
//!   points) within `tol` of the origin, GJK's bounds pinning the distance below
//!   `tol + 1e-14·scale`, a cell point found inside `S` — or, after the feature search, from the
//!   fact that no candidate of a provably complete set of separating directions separates.
//!
//! The tests check the band: spots touching a cell at a face, edge or corner, by their cap or rim
//! (narrow cones, tiny ranges, coordinates up to 1e7 included) are always `true`, and the same
//! spots moved three tolerances away are always `false`.
//!
//! # Algorithm
//! 1. **Empty volume**: a negative or NaN `range` gives the empty set, a non-finite apex a light
//!    that is nowhere: `false`.
//! 2. **Ball reject** (exact): if the apex is farther than `range + tol` from the cell (by the
//!    exact [`distance_to_cell`]), the ball misses the cell and so does `S`: `false`.
//! 3. **Apex accept** (exact): if the apex is in the cell, `true`.
//! 4. **Degenerate cones**: `angle < 0` leaves only the apex (already known to be outside):
//!    `false`. `angle > 90°`, a NaN angle, a zero or non-finite `direction` or an infinite `range`:
//!    the ball test, which step 2 already passed: `true`. (A non-unit `direction` is normalised.)
//! 5. **Walls** (exact): if the volume lies beyond one of the cell's six planes (its support
//!    along the wall's inward normal is outside it) by more than 64 ulps of `|apex| + range`:
//!    `false`. The side walls pass through the eye and the depth walls are `z = −depth`, so
//!    these gaps round with the light's coordinates alone, however far the cell's corners reach
//!    (see `tol` above: near 180° of field of view they reach 10⁶–10⁹ times their depth out, and
//!    GJK's band with them).
//! 6. **GJK** on `D = C − S` with support `s_D(−u) = s_C(−u) − s_S(u)` (the point of `D` lowest
//!    along `u`):
//!    * `s_C(v)` is the cell corner maximising `v·c`;
//!    * `s_S(u)` is the better (along `u`) of the apex and the cap's support point: `apex + range·û`
//!      when `∠(u, direction) ≤ angle`, otherwise the rim point
//!      `apex + range·(cos(angle)·direction + sin(angle)·ŵ)`, `ŵ` being the unit component of `u`
//!      orthogonal to `direction` (projected out twice, so it stays orthogonal when `u` is nearly
//!      parallel to the axis; any orthogonal unit vector when `u` is exactly antiparallel).
//!
//!    Start from `v = centroid(C) − apex ∈ D` and repeat (at most [`MAX_ITERATIONS`] times):
//!    1. `upper = |v|` bounds the distance from above; if `upper ≤ tol`: `true`.
//!    2. Take the unit search direction `u` along `v` and `w = s_D(−u)`: `u·w` is the gap of `u`,
//!       a lower bound; keep the best. If it exceeds `tol`: `false`.
//!    3. If `upper − lower ≤ 1e-14·scale` the distance is pinned inside the band: `true`.
//!    4. Add `w` to the simplex and replace `v` by the point of the simplex's hull closest to the
//!       origin, by brute force over all sub-simplices with barycentric coordinates from signed
//!       lengths, areas and volumes. The point is evaluated as a convex combination, so it is a
//!       genuine point of `D` however ill-conditioned the simplex; the search direction is taken
//!       from the triangle's normal (or the point made exactly perpendicular to the segment),
//!       which stays accurate when `|v|` is tiny next to the points. A tetrahedron enclosing the
//!       origin ends in step 1; otherwise the simplex shrinks to the best face (≤ 3 points).
//!    5. If `|v|` did not decrease, GJK has stalled; go to step 7 (also when iterations run out).
//!       This happens for near-touching contacts of a long cell edge with the curved volume,
//!       where GJK's far support points make progress vanish.
//! 7. **Feature search** (exact). If the sets are disjoint, the cell's point closest to `S` lies
//!    on a face, an edge or at a corner, and the best separating direction points from `S` to it:
//!    * a face: the face's outward normal;
//!    * a corner: from the corner's closest point of `S` (apex, cap, side or rim) to the corner;
//!    * an edge: the same from the edge's point closest to `S`, found by bisection on the sign of
//!      the derivative of the (convex) distance along the edge.
//!
//!    Every such direction is also tried made exactly perpendicular to the flat directions of the
//!    features in contact (the cell edge, the cone's generator, the rim's tangent), because a
//!    direction off by even 1e-8 rad there makes a far support point collapse the gap. If any gap
//!    exceeds `tol`: `false`; a corner or edge point found inside `S`, or no separation: `true`.
//!    GJK and this search are independent; the tests check they agree.

use super::{Cell, distance_to_cell};
use glam::DVec3;
use std::f64::consts::FRAC_PI_2;

/// A spot light's volume in view space: points within `range` of `apex` and within `angle` of the
/// unit axis `direction`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotVolume {
    /// Apex (the light's position).
    pub apex: DVec3,
    /// Unit axis.
    pub direction: DVec3,
    /// Range (radius of the light's sphere).
    pub range: f64,
    /// Outer half angle in radians.
    pub angle: f64,
}

/// Relative width of the band in which the oracle may answer "intersects" for sets that are in
/// fact (barely) apart.
const TOLERANCE: f64 = 1e-12;
/// Relative rounding bound of the exact ball test (`distance_to_cell`): 64 ulps of the scale.
const BALL_ROUNDING: f64 = 64.0 * f64::EPSILON;
/// Relative gap between GJK's upper and lower distance bounds at which it stops refining.
const CONVERGENCE: f64 = 1e-14;
/// GJK iteration cap; hitting it hands over to the feature search.
const MAX_ITERATIONS: usize = 128;

/// Whether the closed spot volume touches the closed cell (see the module docs for the exact
/// semantics, the tolerance band and the treatment of angles above 90°).
pub fn spot_intersects_cell(spot: &SpotVolume, cell: &Cell) -> bool {
    classify(spot, cell, Engine::GjkThenFeatures).0
}

/// Which algorithm decides step 6 (tests run the feature search alone to cross-check GJK).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Engine {
    /// GJK, and the feature search only when GJK stalls (the public behaviour).
    GjkThenFeatures,
    /// The feature search alone.
    #[cfg(test)]
    FeaturesOnly,
}

/// Which step decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Route {
    /// Steps 1–5: exact quick checks and the ball fallback.
    Quick,
    /// Step 6: GJK's certificates.
    Gjk,
    /// Step 7: the feature search.
    Features,
}

/// Steps 1–7 of the module docs: the answer and the step that gave it.
fn classify(spot: &SpotVolume, cell: &Cell, engine: Engine) -> (bool, Route) {
    // 1. Empty volume, or one that is nowhere.
    if !(spot.range >= 0.0) || !spot.apex.is_finite() {
        return (false, Route::Quick);
    }
    // The volume lies inside its ball, so the cell beyond the ball's far depth does not matter:
    // cut it off there (with a margin of one more range, so the cut never makes a flat cell that
    // GJK would find degenerate). Same answer, but later lengths — and so the tolerance band —
    // stay local to the light instead of scaling with the cell's far corners: a cell reaching
    // 10⁷ deep would otherwise make `tol` 10⁻⁵ absolute, and a tiny light 10⁻⁵ outside it would
    // wrongly count as touching.
    let far = cell.depths[1].min(-spot.apex.z + 2.0 * spot.range);
    if !(far >= cell.depths[0]) {
        return (false, Route::Quick);
    }
    let clipped = Cell {
        depths: [cell.depths[0], far],
        ..*cell
    };
    let cell = &clipped;
    // 2. The ball misses the cell. `distance_to_cell` is accurate to a few ulps of the largest
    // coordinate involved, so this test gets a band of that size rather than `tol`.
    let scale = length_scale(spot, cell);
    let tol = TOLERANCE * scale;
    let ball_tol = BALL_ROUNDING * scale;
    let apex_distance = distance_to_cell(spot.apex, cell);
    if !(apex_distance <= spot.range + ball_tol) {
        return (false, Route::Quick);
    }
    // 3. The apex belongs to the volume.
    if apex_distance == 0.0 {
        return (true, Route::Quick);
    }
    // 4. Degenerate cones.
    if spot.angle < 0.0 {
        return (false, Route::Quick);
    }
    let axis = spot.direction.normalize_or_zero();
    if axis == DVec3::ZERO || !(spot.angle <= FRAC_PI_2) || !spot.range.is_finite() {
        return (true, Route::Quick);
    }
    let (sin_angle, cos_angle) = spot.angle.sin_cos();
    let convex = ConvexSpot {
        apex: spot.apex,
        axis,
        range: spot.range,
        cos_angle,
        sin_angle,
    };
    // 5. The cell's walls (exact): a volume wholly beyond one of the cell's six planes misses it.
    // Each wall is tested in the light's own scale — the side walls pass through the eye, the
    // depth walls are `z = −depth` — where GJK's band grows with the cell's corners, which a
    // field of view near 180° puts 10⁶–10⁹ times as far out as they are deep (audits: a needle
    // spot wholly behind the eye, 0.013 from a cell whose band was 200 wide, and spots beside
    // the top or a side wall, 1.3e-5 from a cell whose band was 1.4e-5, were listed).
    if convex.beyond_a_wall_of(cell) {
        return (false, Route::Quick);
    }
    let corners = cell.corners();
    // 6. GJK.
    if engine == Engine::GjkThenFeatures
        && let Some(answer) = gjk(&convex, &corners, scale)
    {
        return (answer, Route::Gjk);
    }
    // 7. The feature search.
    (
        feature_search(&convex, cell, &corners, tol),
        Route::Features,
    )
}

/// The length scale of the tolerance: the largest of the range, `|apex|` and the cell's corners'
/// magnitudes.
fn length_scale(spot: &SpotVolume, cell: &Cell) -> f64 {
    cell.corners()
        .iter()
        .fold(spot.apex.length().max(spot.range), |m, c| m.max(c.length()))
}

/// A spot volume with `angle ≤ 90°` (convex), ready for support and projection queries.
struct ConvexSpot {
    apex: DVec3,
    /// Unit axis.
    axis: DVec3,
    range: f64,
    cos_angle: f64,
    sin_angle: f64,
}

impl ConvexSpot {
    /// Whether the volume lies wholly on the outer side of one of `cell`'s six planes, by more
    /// than 64 ulps of `|apex| + range`: its point nearest that side (its support along the
    /// inward normal) is beyond it. The normals are the walls' own (the side walls' from the f64
    /// slopes, rounded by normalising: a tilt of an ulp, which moves a point of the volume by an
    /// ulp of its length, inside the margin), so a `true` is a certificate of separation.
    fn beyond_a_wall_of(&self, cell: &Cell) -> bool {
        let margin = BALL_ROUNDING * (self.apex.length() + self.range);
        // `u` the outward unit normal, `c` the offset: the cell lies in `u·p ≤ c`. Non-finite
        // walls (an infinite far depth) and zero normals separate nothing.
        cell.planes()
            .into_iter()
            .any(|(u, c)| u.is_finite() && c.is_finite() && u.dot(self.support(-u)) > c + margin)
    }

    /// The unit direction of `v`'s component perpendicular to the axis (any unit perpendicular
    /// when there is none). Projected out twice: when `v` is nearly along the axis, one pass
    /// leaves a residue that is not perpendicular to it, and normalising that would be garbage.
    fn perpendicular(&self, v: DVec3) -> DVec3 {
        let once = v - self.axis * v.dot(self.axis);
        match (once - self.axis * once.dot(self.axis)).try_normalize() {
            // A residue of rounding along the axis, normalised, is the axis itself (`v` exactly
            // along an axis that normalising left an ulp short of unit length: an audit found
            // the rim put on the axis, and the volume's support overshooting by half its range).
            Some(w) if w.dot(self.axis).abs() <= 1e-6 => w,
            _ => self.axis.any_orthonormal_vector(),
        }
    }

    /// A point of the volume maximising `u·p`, for a unit `u`.
    fn support(&self, u: DVec3) -> DVec3 {
        let along = u.dot(self.axis);
        let cap_direction = if along >= self.cos_angle {
            // `u` lies inside the cone: the cap's farthest point is straight along `u`.
            u
        } else {
            // Otherwise the best cap point is on the rim, in the half-plane of the axis and `u`.
            self.axis * self.cos_angle + self.perpendicular(u) * self.sin_angle
        };
        // The volume is the hull of the apex and the cap: the better of the two.
        if u.dot(cap_direction) >= 0.0 {
            self.apex + cap_direction * self.range
        } else {
            self.apex
        }
    }

    /// The gradient of the distance to the volume at `p`: the unit vector from the volume's closest
    /// point towards `p`, or `None` when `p` lies in the (closed) volume.
    ///
    /// By symmetry about the axis the closest point lies in the half-plane through the axis and
    /// `p`, where the volume is a circular sector: inside the cone the closest point is on the cap
    /// (radially), outside it on the side segment from the apex to the rim.
    fn descent(&self, p: DVec3) -> Option<DVec3> {
        let q = p - self.apex;
        let r = q.length();
        if r == 0.0 {
            return None;
        }
        if q.dot(self.axis) >= r * self.cos_angle {
            // Inside the cone: in the volume, or beyond the cap.
            return (r > self.range).then_some(q / r);
        }
        let azimuth = self.perpendicular(q);
        let generator = self.axis * self.cos_angle + azimuth * self.sin_angle;
        let along = q.dot(generator);
        if along <= 0.0 {
            // Closest to the apex.
            return Some(q / r);
        }
        if along < self.range {
            // Closest to the side: its outward normal, unless rounding put `p` on the surface.
            let normal = azimuth * self.cos_angle - self.axis * self.sin_angle;
            return (q.dot(normal) > 0.0).then_some(normal);
        }
        // Closest to the rim.
        (q - generator * self.range).try_normalize()
    }

    /// Candidate separating directions (cell on the high side) for a cell point `p` outside the
    /// volume, on the cell edge `edge` when given.
    ///
    /// If `p` is the cell's point closest to the volume, the best separating direction points from
    /// the volume's closest point to `p`. Which part of the volume holds that point (apex, cap,
    /// side, rim) is numerically ambiguous near the parts' borders, and the direction has to be
    /// *exactly* perpendicular to every flat direction of the features in contact (the cell edge,
    /// the side's generator, the rim's tangent) or far support points make the gap collapse. So
    /// every part's direction is offered, each also made exactly perpendicular to those flat
    /// directions (projection, or the cross product when two must be honoured at once). Every
    /// candidate's gap is a valid lower bound, so extra candidates cost time, never correctness.
    fn candidates(&self, p: DVec3, edge: Option<DVec3>) -> [Option<DVec3>; 12] {
        let q = p - self.apex;
        let azimuth = self.perpendicular(q);
        let generator = self.axis * self.cos_angle + azimuth * self.sin_angle;
        let tangent = self.axis.cross(azimuth);
        let rim = (q - generator * self.range).try_normalize();
        let bases = [
            // Cap or apex.
            q.try_normalize(),
            // Side.
            Some(azimuth * self.cos_angle - self.axis * self.sin_angle),
            // Rim, raw and perpendicular to the rim.
            rim,
            rim.and_then(|d| without(d, tangent)),
        ];
        let mut out = [None; 12];
        out[..4].copy_from_slice(&bases);
        if let Some(edge) = edge {
            for (slot, base) in out[4..8].iter_mut().zip(bases) {
                *slot = base.and_then(|d| without(d, edge));
            }
            let across_side = edge.cross(generator).try_normalize();
            let across_rim = edge.cross(tangent).try_normalize();
            out[8] = across_side;
            out[9] = across_side.map(|d| -d);
            out[10] = across_rim;
            out[11] = across_rim.map(|d| -d);
        }
        out
    }
}

/// The corner of the cell maximising `v·c`.
fn cell_support(corners: &[DVec3; 8], v: DVec3) -> DVec3 {
    corners
        .iter()
        .fold((corners[0], corners[0].dot(v)), |best, &c| {
            let value = c.dot(v);
            if value > best.1 { (c, value) } else { best }
        })
        .0
}

/// The width of the gap between the sets along unit `u` (the cell on the high side):
/// `min_C u·c − max_S u·s`. Positive means `u` separates them; for *any* `u` it is a lower bound
/// of their distance.
fn gap(spot: &ConvexSpot, corners: &[DVec3; 8], u: DVec3) -> f64 {
    u.dot(cell_support(corners, -u)) - u.dot(spot.support(u))
}

/// Step 6 of the module docs: GJK on `C − S` with certified lower and upper distance bounds.
/// `None` when it stalls or runs out of iterations.
fn gjk(spot: &ConvexSpot, corners: &[DVec3; 8], scale: f64) -> Option<bool> {
    let (tol, converged) = (TOLERANCE * scale, CONVERGENCE * scale);
    // The point of D = C − S lowest along `u`.
    let lowest = |u: DVec3| cell_support(corners, -u) - spot.support(u);

    let centroid = corners.iter().sum::<DVec3>() / 8.0;
    let mut v = centroid - spot.apex;
    let mut hint = v;
    let mut simplex = Simplex::single(v);
    let mut lower = f64::NEG_INFINITY;
    for _ in 0..MAX_ITERATIONS {
        let upper = v.length();
        if upper <= tol {
            return Some(true);
        }
        let u = hint.try_normalize().unwrap_or(v / upper);
        let w = lowest(u);
        lower = lower.max(u.dot(w));
        if lower > tol {
            return Some(false);
        }
        if upper - lower <= converged {
            return Some(true);
        }
        simplex.push(w);
        let reduced = closest_to_origin(&simplex);
        if reduced.enclosed_norm <= tol {
            return Some(true);
        }
        if !(reduced.point.length() < upper) {
            return None;
        }
        v = reduced.point;
        hint = reduced.hint;
        simplex = reduced.simplex;
    }
    None
}

/// The twelve edges of a cell as pairs of indices into [`Cell::corners`] (differing in one bit).
const EDGES: [(usize, usize); 12] = [
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7),
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

/// Bisection steps along an edge (the parameter interval shrinks to nothing well before).
const BISECTION_STEPS: usize = 80;

/// The cell's outward unit face normals (left, right, bottom, top, near, far).
fn outward_normals(cell: &Cell) -> [DVec3; 6] {
    let [x0, x1] = cell.x_slopes;
    let [y0, y1] = cell.y_slopes;
    [
        -DVec3::new(1.0, 0.0, x0).normalize(),
        DVec3::new(1.0, 0.0, x1).normalize(),
        -DVec3::new(0.0, 1.0, y0).normalize(),
        DVec3::new(0.0, 1.0, y1).normalize(),
        DVec3::Z,
        DVec3::NEG_Z,
    ]
}

/// `u` without its component along `x`, normalised (`u` itself when `x` is zero).
fn without(u: DVec3, x: DVec3) -> Option<DVec3> {
    match x.try_normalize() {
        Some(x) => (u - x * u.dot(x)).try_normalize(),
        None => Some(u),
    }
}

/// Where the distance to the volume is smallest along a cell edge.
enum EdgeSearch {
    /// At an end: the corners cover it.
    AtEnd,
    /// A point of the edge lies in the volume.
    Inside,
    /// At this interior point.
    Interior(DVec3),
}

/// Minimises the (convex) distance to the volume along the edge `a → b` by bisection on the sign
/// of its derivative, `descent · (b − a)`.
fn search_edge(spot: &ConvexSpot, a: DVec3, b: DVec3) -> EdgeSearch {
    let edge = b - a;
    let (Some(start), Some(end)) = (spot.descent(a), spot.descent(b)) else {
        return EdgeSearch::Inside;
    };
    if start.dot(edge) >= 0.0 || end.dot(edge) <= 0.0 {
        return EdgeSearch::AtEnd;
    }
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..BISECTION_STEPS {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        match spot.descent(a.lerp(b, mid)) {
            None => return EdgeSearch::Inside,
            Some(d) if d.dot(edge) < 0.0 => lo = mid,
            Some(_) => hi = mid,
        }
    }
    let p = a.lerp(b, 0.5 * (lo + hi));
    match spot.descent(p) {
        None => EdgeSearch::Inside,
        Some(_) => EdgeSearch::Interior(p),
    }
}

/// Step 7 of the module docs: whether the sets intersect, by trying the separating directions of
/// every feature of the cell (face normals, and the candidates of each corner and of each edge's
/// point closest to the volume). A cell point found in the volume proves an intersection.
fn feature_search(spot: &ConvexSpot, cell: &Cell, corners: &[DVec3; 8], tol: f64) -> bool {
    let separates = |u: Option<DVec3>| u.is_some_and(|u| gap(spot, corners, u) > tol);
    if outward_normals(cell).iter().any(|&n| separates(Some(-n))) {
        return false;
    }
    for &corner in corners {
        if spot.descent(corner).is_none() {
            return true;
        }
        if spot.candidates(corner, None).into_iter().any(separates) {
            return false;
        }
    }
    for (i, j) in EDGES {
        let (a, b) = (corners[i], corners[j]);
        match search_edge(spot, a, b) {
            EdgeSearch::AtEnd => {}
            EdgeSearch::Inside => return true,
            EdgeSearch::Interior(p) => {
                if spot.candidates(p, Some(b - a)).into_iter().any(separates) {
                    return false;
                }
            }
        }
    }
    true
}

/// Up to four points of the Minkowski difference.
#[derive(Clone, Copy, Debug)]
struct Simplex {
    points: [DVec3; 4],
    len: usize,
}

impl Simplex {
    fn empty() -> Self {
        Self {
            points: [DVec3::ZERO; 4],
            len: 0,
        }
    }

    fn single(p: DVec3) -> Self {
        Self {
            points: [p; 4],
            len: 1,
        }
    }

    /// Adds a point; callers keep `len ≤ 3` before pushing.
    fn push(&mut self, p: DVec3) {
        debug_assert!(self.len < 4);
        self.points[self.len.min(3)] = p;
        self.len = (self.len + 1).min(4);
    }

    fn points(&self) -> &[DVec3] {
        &self.points[..self.len]
    }
}

/// The origin projected onto a simplex's hull.
struct Reduction {
    /// The closest point found on a sub-simplex of at most three points.
    point: DVec3,
    /// A more accurate direction of `point` (see [`project_origin`]).
    hint: DVec3,
    /// That sub-simplex.
    simplex: Simplex,
    /// Norm of the closest point over *all* sub-simplices, the full tetrahedron included (≈ 0 when
    /// it encloses the origin).
    enclosed_norm: f64,
}

/// Brute force over all non-empty sub-simplices: every valid projection of the origin is a point
/// of the hull, so the shortest one is the hull's closest point (singletons are always valid).
fn closest_to_origin(simplex: &Simplex) -> Reduction {
    let points = simplex.points();
    let mut best = Reduction {
        point: points[0],
        hint: points[0],
        simplex: Simplex::single(points[0]),
        enclosed_norm: f64::INFINITY,
    };
    let mut best_norm2 = points[0].length_squared();
    let mut any_norm2 = f64::INFINITY;
    for mask in 1usize..(1 << points.len()) {
        let mut subset = Simplex::empty();
        for (i, &p) in points.iter().enumerate() {
            if mask & (1 << i) != 0 {
                subset.push(p);
            }
        }
        let Some((x, hint)) = project_origin(subset.points()) else {
            continue;
        };
        let norm2 = x.length_squared();
        any_norm2 = any_norm2.min(norm2);
        if subset.len <= 3 && norm2 < best_norm2 {
            best_norm2 = norm2;
            best.point = x;
            best.hint = hint;
            best.simplex = subset;
        }
    }
    best.enclosed_norm = any_norm2.sqrt();
    best
}

/// The origin's projection onto the affine hull of 1–4 points if it lies in their convex hull (all
/// barycentric coordinates non-negative), with a direction hint.
///
/// * The point is evaluated as a convex combination of the points, so even when rounding makes
///   the barycentric coordinates of a near-degenerate simplex meaningless, it is a genuine point
///   of the hull and its norm a valid upper bound of the distance.
/// * Barycentric coordinates come from signed lengths, areas and volumes (cross and triple
///   products of the points themselves) rather than from a Gram matrix, whose determinant would
///   square the conditioning of the long, thin simplices GJK builds near curved surfaces.
/// * The hint has the point's direction but is computed without the cancellation that makes a
///   tiny point's direction inaccurate: a triangle's normal, a segment's point made exactly
///   perpendicular to the segment.
fn project_origin(points: &[DVec3]) -> Option<(DVec3, DVec3)> {
    // `!(x >= 0)` also rejects NaN.
    let all_non_negative = |l: &[f64]| l.iter().all(|&l| l >= 0.0);
    let combine = |weights: &[f64]| {
        let total: f64 = weights.iter().sum();
        let x = points
            .iter()
            .zip(weights)
            .fold(DVec3::ZERO, |acc, (&p, &w)| acc + p * (w / total));
        x.is_finite().then_some(x)
    };
    match *points {
        [a] => Some((a, a)),
        [a, b] => {
            let e = b - a;
            let t = -a.dot(e) / e.length_squared();
            if !all_non_negative(&[t, 1.0 - t]) {
                return None;
            }
            let x = combine(&[1.0 - t, t])?;
            Some((x, x - e * (x.dot(e) / e.length_squared())))
        }
        [a, b, c] => {
            let n = (b - a).cross(c - a);
            // Signed areas of the sub-triangles the projected origin makes with each edge.
            let areas = [n.dot(b.cross(c)), n.dot(c.cross(a)), n.dot(a.cross(b))];
            if !all_non_negative(&areas) {
                return None;
            }
            let x = combine(&areas)?;
            let side = n.dot(a);
            let hint = if side > 0.0 {
                n
            } else if side < 0.0 {
                -n
            } else {
                x
            };
            Some((x, hint))
        }
        [a, b, c, d] => {
            let det = |p: DVec3, q: DVec3, r: DVec3| p.dot(q.cross(r));
            let sign = det(b - a, c - a, d - a).signum();
            // Signed volumes of the sub-tetrahedra the origin makes with each face.
            let volumes =
                [det(b, c, d), -det(a, c, d), det(a, b, d), -det(a, b, c)].map(|v| v * sign);
            if !all_non_negative(&volumes) {
                return None;
            }
            let x = combine(&volumes)?;
            Some((x, x))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oracle::{cell_point, random_cell, sphere_intersects_cell};
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;
    use std::f64::consts::{PI, TAU};

    fn diameter(cell: &Cell) -> f64 {
        let corners = cell.corners();
        corners
            .iter()
            .flat_map(|a| corners.iter().map(move |b| a.distance(*b)))
            .fold(0.0, f64::max)
    }

    fn random_unit(rng: &mut impl Rng) -> DVec3 {
        loop {
            let v = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            let len = v.length();
            if (0.1..=1.0).contains(&len) {
                return v / len;
            }
        }
    }

    /// Exact point membership in the spot volume (any angle).
    fn in_spot(spot: &SpotVolume, p: DVec3) -> bool {
        let q = p - spot.apex;
        let r = q.length();
        r <= spot.range && (r == 0.0 || q.dot(spot.direction) >= r * spot.angle.cos())
    }

    /// Exact distance from `p` to the spot volume (angle ≤ 90°). The volume is symmetric about its
    /// axis, so the closest point lies in the half-plane through the axis and `p`, where the volume
    /// is a circular sector: polar radius ≤ range, polar angle (from the axis) ≤ angle.
    fn distance_to_spot(spot: &SpotVolume, p: DVec3) -> f64 {
        let q = p - spot.apex;
        let r = q.length();
        let h = q.dot(spot.direction);
        let rho = (q - spot.direction * h).length();
        let (s, c) = spot.angle.sin_cos();
        if h >= r * c {
            // Inside the cone: the closest point is on the cap (or p itself).
            (r - spot.range).max(0.0)
        } else {
            // Outside the cone: the closest point is on the sector's edge from the apex to the rim.
            let t = (h * c + rho * s).clamp(0.0, spot.range);
            (h - t * c).hypot(rho - t * s)
        }
    }

    /// A unit vector orthogonal to unit `n`, random.
    fn random_orthogonal(rng: &mut impl Rng, n: DVec3) -> DVec3 {
        loop {
            let v = random_unit(rng);
            if let Some(t) = (v - n * v.dot(n)).try_normalize() {
                return t;
            }
        }
    }

    /// A random point of the spot volume (angle ≤ 90°).
    fn spot_point(rng: &mut impl Rng, spot: &SpotVolume, radius: f64, cos_t: f64) -> DVec3 {
        let t1 = spot.direction.any_orthonormal_vector();
        let t2 = spot.direction.cross(t1);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = rng.random_range(0.0..TAU);
        let u = spot.direction * cos_t + (t1 * phi.cos() + t2 * phi.sin()) * sin_t;
        spot.apex + u * radius
    }

    fn random_angle(rng: &mut impl Rng) -> f64 {
        match rng.random_range(0..10) {
            0 => FRAC_PI_2,
            1 => rng.random_range(1e-4..0.05),
            _ => rng.random_range(0.05..FRAC_PI_2),
        }
    }

    /// A random spot near the cell, aimed roughly at it (sometimes away).
    fn random_spot_near(rng: &mut impl Rng, cell: &Cell, angle: f64) -> SpotVolume {
        let diam = diameter(cell);
        let apex = cell_point(
            cell,
            rng.random_range(-0.6..1.6),
            rng.random_range(-0.6..1.6),
            rng.random_range(-0.6..1.6),
        );
        let centre = cell_point(cell, 0.5, 0.5, 0.5);
        let towards = (centre - apex).normalize_or_zero() * rng.random_range(-0.5..1.5);
        let direction = (towards + random_unit(rng) * rng.random_range(0.0..1.0))
            .try_normalize()
            .unwrap_or(DVec3::Z);
        SpotVolume {
            apex,
            direction,
            range: diam * rng.random_range(0.05..1.5),
            angle,
        }
    }

    /// Test 1: dense sampling of both sets on random cases. Any sample of one set inside the other
    /// proves an intersection, so the oracle must say `true`; when the oracle says `true` without
    /// such a witness, some cell sample must lie within the sampling resolution of the volume
    /// (no gross false positives).
    #[test]
    fn agrees_with_dense_sampling_of_both_sets() {
        let mut rng = Pcg64::seed_from_u64(0x5b07);
        const N: usize = 14;
        const SPOT_SAMPLES: usize = 3000;
        let (mut witnessed, mut near_only, mut apart) = (0, 0, 0);
        let mut routes = [0; 3];
        for case in 0..600 {
            let angle = random_angle(&mut rng);
            let (cell, spot) = if case % 3 == 2 {
                // Barely touching, barely apart or barely overlapping: no sample will witness.
                let (cell, touching, _, n) = touching_case(&mut rng, 1.0, 1.0, angle);
                let offset = rng.random_range(-0.02..0.02) * diameter(&cell) / (N - 1) as f64;
                let apex = touching.apex + n * offset;
                (cell, SpotVolume { apex, ..touching })
            } else {
                let cell = random_cell(&mut rng, 1.0);
                (cell, random_spot_near(&mut rng, &cell, angle))
            };
            let (oracle, route) = classify(&spot, &cell, Engine::GjkThenFeatures);
            // The two engines are independent algorithms: they must agree.
            let (by_features, _) = classify(&spot, &cell, Engine::FeaturesOnly);
            assert_eq!(oracle, by_features, "case {case}: {spot:?} {cell:?}");
            routes[route as usize] += 1;

            // Samples of the volume: apex, interior, cap and rim points.
            let cos_a = angle.cos();
            let mut spot_hit = cell.contains(spot.apex);
            for s in 0..SPOT_SAMPLES {
                let (radius, cos_t) = match s % 4 {
                    0 => (spot.range, cos_a),
                    1 => (spot.range, rng.random_range(cos_a..=1.0)),
                    _ => (
                        spot.range * rng.random::<f64>().cbrt(),
                        rng.random_range(cos_a..=1.0),
                    ),
                };
                spot_hit |= cell.contains(spot_point(&mut rng, &spot, radius, cos_t));
            }
            // A grid of samples of the cell.
            let grid = |i: usize| i as f64 / (N - 1) as f64;
            let mut cell_samples = Vec::with_capacity(N * N * N);
            for a in 0..N {
                for b in 0..N {
                    for c in 0..N {
                        cell_samples.push(cell_point(&cell, grid(a), grid(b), grid(c)));
                    }
                }
            }
            let cell_hit = cell_samples.iter().any(|&p| in_spot(&spot, p));

            if spot_hit || cell_hit {
                assert!(
                    oracle,
                    "case {case}: missed a sampled intersection {spot:?} {cell:?}"
                );
                witnessed += 1;
            } else if oracle {
                // Every point of the cell is within `resolution` of a grid sample (bound the
                // parameter-space derivatives of `cell_point` over half a grid step).
                let [x0, x1] = cell.x_slopes;
                let [y0, y1] = cell.y_slopes;
                let [d0, d1] = cell.depths;
                let slope =
                    (1.0 + x0.abs().max(x1.abs()).powi(2) + y0.abs().max(y1.abs()).powi(2)).sqrt();
                let resolution =
                    ((x1 - x0) * d1 + (y1 - y0) * d1 + (d1 - d0) * slope) / (2.0 * (N - 1) as f64);
                let nearest = cell_samples
                    .iter()
                    .map(|&p| distance_to_spot(&spot, p))
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    nearest <= resolution * (1.0 + 1e-9),
                    "case {case}: oracle says true but the sets are {nearest} apart \
                     (resolution {resolution}): {spot:?} {cell:?}"
                );
                near_only += 1;
            } else {
                apart += 1;
            }
        }
        // Both answers must be well represented, or the test proves little.
        eprintln!(
            "sampled: {witnessed} witnessed, {near_only} near only, {apart} apart; \
             routes (quick, gjk, features): {routes:?}"
        );
        assert!(witnessed >= 100 && near_only >= 5 && apart >= 100);
    }

    /// A boundary point `q` of the cell with a direction `n` of its normal cone (so the cell lies in
    /// `n·x ≤ n·q`): a point inside a face, on an edge or at a corner.
    fn boundary_point(rng: &mut impl Rng, cell: &Cell) -> (DVec3, DVec3) {
        let mut params = [
            rng.random_range(0.1..0.9),
            rng.random_range(0.1..0.9),
            rng.random_range(0.1..0.9),
        ];
        let [x0, x1] = cell.x_slopes;
        let [y0, y1] = cell.y_slopes;
        let normals = |axis: usize, side: usize| match (axis, side) {
            (0, 0) => -DVec3::new(1.0, 0.0, x0).normalize(),
            (0, _) => DVec3::new(1.0, 0.0, x1).normalize(),
            (1, 0) => -DVec3::new(0.0, 1.0, y0).normalize(),
            (1, _) => DVec3::new(0.0, 1.0, y1).normalize(),
            (_, 0) => DVec3::Z,
            (_, _) => DVec3::NEG_Z,
        };
        // Fix one (face), two (edge) or three (corner) parameters at 0 or 1.
        let fixed = rng.random_range(1..=3);
        let first = rng.random_range(0..3);
        let mut n = DVec3::ZERO;
        for k in 0..fixed {
            let axis = (first + k) % 3;
            let side = rng.random_range(0..2);
            params[axis] = side as f64;
            n += normals(axis, side);
        }
        (
            cell_point(cell, params[0], params[1], params[2]),
            n.normalize(),
        )
    }

    /// A random cell and a spot touching it exactly at a boundary point `q` from outside, the
    /// spot lying in the half-space `n·x ≥ n·q` and the cell in `n·x ≤ n·q`.
    fn touching_case(
        rng: &mut Pcg64,
        scale: f64,
        range_factor: f64,
        alpha: f64,
    ) -> (Cell, SpotVolume, DVec3, DVec3) {
        let cell = random_cell(rng, scale);
        let (q, n) = boundary_point(rng, &cell);
        // β: the axis's angle from −n; the volume's lowest direction along n is at β − α.
        let beta = if rng.random_bool(0.5) {
            rng.random_range(0.0..=alpha)
        } else {
            alpha + rng.random_range(0.0..1.4)
        };
        let t = random_orthogonal(rng, n);
        let direction = -n * beta.cos() + t * beta.sin();
        let lowest = if beta <= alpha {
            -n
        } else {
            -n * (beta - alpha).cos() + t * (beta - alpha).sin()
        };
        let range = range_factor * diameter(&cell) * rng.random_range(0.2..1.5);
        let touching = SpotVolume {
            apex: q - lowest * range,
            direction,
            range,
            angle: alpha,
        };
        (cell, touching, q, n)
    }

    /// Spots touching the cell exactly at a boundary point from outside (by the cap's tip, or by
    /// its rim), then moved apart by a gap 1000× the tolerance (must be `false`) and pushed in by
    /// the same amount (must be `true`).
    fn check_touching_family(
        seed: u64,
        scale: f64,
        range_factor: f64,
        angle: impl Fn(&mut Pcg64) -> f64,
    ) {
        let mut rng = Pcg64::seed_from_u64(seed);
        let mut routes = [0; 3];
        for case in 0..300 {
            let alpha = angle(&mut rng);
            let (cell, touching, q, n) = touching_case(&mut rng, scale, range_factor, alpha);
            let gap = 1e-9 * length_scale(&touching, &cell);
            let moved = |offset: DVec3| SpotVolume {
                apex: touching.apex + offset,
                ..touching
            };
            let inwards = (cell_point(&cell, 0.5, 0.5, 0.5) - q).normalize();
            let apart = moved(n * gap);
            let pushed = moved(inwards * gap);
            for engine in [Engine::GjkThenFeatures, Engine::FeaturesOnly] {
                let (touches, _) = classify(&touching, &cell, engine);
                let (apart_hits, route) = classify(&apart, &cell, engine);
                let (pushed_hits, _) = classify(&pushed, &cell, engine);
                assert!(
                    touches,
                    "case {case} {engine:?}: touching {touching:?} {cell:?}"
                );
                assert!(
                    !apart_hits,
                    "case {case} {engine:?} ({route:?}): apart by {gap}: {apart:?} {cell:?}"
                );
                assert!(
                    pushed_hits,
                    "case {case} {engine:?}: pushed in {pushed:?} {cell:?}"
                );
                if engine == Engine::GjkThenFeatures {
                    routes[route as usize] += 1;
                }
            }
        }
        eprintln!(
            "touching family {seed}: routes of the apart case (quick, gjk, features): {routes:?}"
        );
    }

    #[test]
    fn touching_is_intersecting_and_a_tiny_gap_is_not() {
        check_touching_family(1, 1.0, 1.0, random_angle);
    }

    /// Test 2: angles above 90° are the ball test, exactly.
    #[test]
    fn wide_angles_fall_back_to_the_ball() {
        let mut rng = Pcg64::seed_from_u64(2);
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..500 {
            let cell = random_cell(&mut rng, 1.0);
            let angle = match rng.random_range(0..3) {
                // π/2 rounded to f32, as a glTF importer would hand it over: just above 90°.
                0 => std::f32::consts::FRAC_PI_2 as f64,
                1 => PI,
                _ => rng.random_range(FRAC_PI_2 + 1e-9..PI),
            };
            let spot = random_spot_near(&mut rng, &cell, angle);
            let ball = sphere_intersects_cell(spot.apex, spot.range, &cell);
            assert_eq!(
                spot_intersects_cell(&spot, &cell),
                ball,
                "{spot:?} {cell:?}"
            );
            if ball { hits += 1 } else { misses += 1 }
        }
        assert!(hits > 50 && misses > 25, "{hits} {misses}");
    }

    /// The volume grows with the angle and the range and always lies in the ball; a half-ball
    /// (90°) agrees with the ball when the cell lies in front of the apex.
    #[test]
    fn monotone_in_angle_and_range_and_within_the_ball() {
        let mut rng = Pcg64::seed_from_u64(3);
        let mut in_front = 0;
        for _ in 0..1000 {
            let cell = random_cell(&mut rng, 1.0);
            let angle = rng.random_range(0.0..FRAC_PI_2);
            let spot = random_spot_near(&mut rng, &cell, angle);
            let oracle = spot_intersects_cell(&spot, &cell);
            let wider = SpotVolume {
                angle: rng.random_range(spot.angle..=FRAC_PI_2),
                ..spot
            };
            let longer = SpotVolume {
                range: spot.range * rng.random_range(1.0..2.0),
                ..spot
            };
            let ball = sphere_intersects_cell(spot.apex, spot.range, &cell);
            assert!(
                !oracle || spot_intersects_cell(&wider, &cell),
                "{spot:?} {wider:?}"
            );
            assert!(
                !oracle || spot_intersects_cell(&longer, &cell),
                "{spot:?} {longer:?}"
            );
            assert!(!oracle || ball, "{spot:?} {cell:?}");
            let half = SpotVolume {
                angle: FRAC_PI_2,
                ..spot
            };
            let ahead = |c: &DVec3| (*c - spot.apex).dot(spot.direction) >= 0.0;
            if cell.corners().iter().all(ahead) {
                assert_eq!(
                    spot_intersects_cell(&half, &cell),
                    ball,
                    "{half:?} {cell:?}"
                );
                in_front += 1;
            }
        }
        assert!(in_front > 50, "{in_front}");
    }

    fn unit_cell() -> Cell {
        Cell {
            x_slopes: [-0.5, 0.5],
            y_slopes: [-0.5, 0.5],
            depths: [1.0, 2.0],
        }
    }

    /// A cone pointing away from the cell misses it although its ball overlaps it.
    #[test]
    fn cone_pointing_away_misses_although_the_ball_overlaps() {
        let cell = unit_cell();
        // Just in front of the near face (depth 0.9), shining back towards the camera.
        let spot = SpotVolume {
            apex: DVec3::new(0.0, 0.0, -0.9),
            direction: DVec3::Z,
            range: 5.0,
            angle: 60f64.to_radians(),
        };
        assert!(sphere_intersects_cell(spot.apex, spot.range, &cell));
        assert!(!spot_intersects_cell(&spot, &cell));
        // Even the half-ball keeps its 0.1 gap; turned around, it lights the cell.
        let half = SpotVolume {
            angle: FRAC_PI_2,
            ..spot
        };
        assert!(!spot_intersects_cell(&half, &cell));
        let turned = SpotVolume {
            direction: DVec3::NEG_Z,
            ..spot
        };
        assert!(spot_intersects_cell(&turned, &cell));
        // Beside the cell (left of its left wall), shining further left.
        let beside = SpotVolume {
            apex: DVec3::new(-1.0, 0.0, -1.5),
            direction: DVec3::new(-1.0, 0.0, 0.2).normalize(),
            range: 10.0,
            angle: 45f64.to_radians(),
        };
        assert!(sphere_intersects_cell(beside.apex, beside.range, &cell));
        assert!(!spot_intersects_cell(&beside, &cell));
        // A non-unit direction is normalised; a zero one falls back to the ball.
        let long_axis = SpotVolume {
            direction: beside.direction * 7.0,
            ..beside
        };
        assert!(!spot_intersects_cell(&long_axis, &cell));
        let no_axis = SpotVolume {
            direction: DVec3::ZERO,
            ..beside
        };
        assert!(spot_intersects_cell(&no_axis, &cell));
    }

    /// Test 3: the apex inside the cell (any cone, any tiny range) or on its boundary.
    #[test]
    fn apex_inside_or_on_the_boundary() {
        let mut rng = Pcg64::seed_from_u64(4);
        for _ in 0..300 {
            let cell = random_cell(&mut rng, 1.0);
            let inside = cell_point(
                &cell,
                rng.random_range(0.0..1.0),
                rng.random_range(0.0..1.0),
                rng.random_range(0.0..1.0),
            );
            let spot = SpotVolume {
                apex: inside,
                direction: random_unit(&mut rng),
                range: [0.0, 1e-12, 1.0][rng.random_range(0..3)],
                angle: [0.0, 1e-4, 1.0, FRAC_PI_2][rng.random_range(0..4)],
            };
            assert!(spot_intersects_cell(&spot, &cell), "{spot:?} {cell:?}");

            // On the near face (exactly representable), shining away from the cell: the apex
            // still touches; lifted off the face by a hair, the spot misses.
            let on_face = cell_point(
                &cell,
                rng.random_range(0.0..1.0),
                rng.random_range(0.0..1.0),
                0.0,
            );
            let away = SpotVolume {
                apex: on_face,
                direction: DVec3::new(0.1, -0.2, 1.0).normalize(),
                range: 1.0,
                angle: 0.3,
            };
            assert!(spot_intersects_cell(&away, &cell), "{away:?} {cell:?}");
            let lifted = SpotVolume {
                apex: on_face + DVec3::Z * 1e-9 * length_scale(&away, &cell),
                ..away
            };
            assert!(!spot_intersects_cell(&lifted, &cell), "{lifted:?} {cell:?}");

            // At an edge or corner, or inside a face (as computed, i.e. up to rounding), shining
            // outwards along a normal of that boundary point: touching; moved out: apart.
            let (q, n) = boundary_point(&mut rng, &cell);
            let outwards = SpotVolume {
                apex: q,
                direction: n,
                range: 1.0,
                angle: rng.random_range(0.0..1.2),
            };
            assert!(
                spot_intersects_cell(&outwards, &cell),
                "{outwards:?} {cell:?}"
            );
            let moved = SpotVolume {
                apex: q + n * 1e-9 * length_scale(&outwards, &cell),
                ..outwards
            };
            assert!(!spot_intersects_cell(&moved, &cell), "{moved:?} {cell:?}");
        }
    }

    /// Test 3: a very narrow cone (1e-4 rad) from the eye, grazing a side wall of the cell.
    #[test]
    fn very_narrow_cone() {
        let mut rng = Pcg64::seed_from_u64(5);
        let alpha = 1e-4;
        for _ in 0..300 {
            let cell = random_cell(&mut rng, 1.0);
            // A point inside the right wall, its direction from the eye lies in that wall's plane.
            let q = cell_point(
                &cell,
                1.0,
                rng.random_range(0.1..0.9),
                rng.random_range(0.1..0.9),
            );
            let wall_normal = DVec3::new(1.0, 0.0, cell.x_slopes[1]).normalize();
            let along = q.normalize();
            let tilted = |gamma: f64| SpotVolume {
                apex: DVec3::ZERO,
                direction: along * gamma.cos() + wall_normal * gamma.sin(),
                range: 2.0 * q.length(),
                angle: alpha,
            };
            assert!(spot_intersects_cell(&tilted(0.5 * alpha), &cell));
            assert!(spot_intersects_cell(&tilted(-alpha), &cell));
            assert!(!spot_intersects_cell(&tilted(2.0 * alpha), &cell));
            assert!(!spot_intersects_cell(&tilted(1.01 * alpha), &cell));
            // A zero angle leaves a segment: grazing the wall along its plane, it touches.
            let segment = |gamma: f64| SpotVolume {
                angle: 0.0,
                ..tilted(gamma)
            };
            assert!(spot_intersects_cell(&segment(0.0), &cell));
            assert!(spot_intersects_cell(&segment(-1e-6), &cell));
            assert!(!spot_intersects_cell(&segment(1e-6), &cell));
        }
        check_touching_family(6, 1.0, 1.0, |_| alpha);
    }

    /// Non-finite or degenerate input never panics: an empty volume misses, an undefined cone is
    /// widened to the ball.
    #[test]
    fn non_finite_and_degenerate_input() {
        let cell = unit_cell();
        let base = SpotVolume {
            apex: DVec3::new(0.0, 0.0, -0.5),
            direction: DVec3::NEG_Z,
            range: 1.0,
            angle: 0.3,
        };
        let with = |f: &dyn Fn(&mut SpotVolume)| {
            let mut spot = base;
            f(&mut spot);
            spot_intersects_cell(&spot, &cell)
        };
        assert!(with(&|_| {}));
        assert!(!with(&|s| s.apex = DVec3::NAN));
        assert!(!with(&|s| s.apex = DVec3::INFINITY));
        assert!(!with(&|s| s.range = f64::NAN));
        assert!(!with(&|s| s.range = -1.0));
        assert!(!with(&|s| s.angle = -0.1));
        // Pointing away, but the cone is undefined: the ball decides.
        let away = |s: &mut SpotVolume| s.direction = DVec3::Z;
        assert!(!with(&away));
        assert!(with(&|s| {
            away(s);
            s.direction = DVec3::ZERO;
        }));
        assert!(with(&|s| {
            away(s);
            s.direction = DVec3::NAN;
        }));
        assert!(with(&|s| {
            away(s);
            s.angle = f64::NAN;
        }));
        assert!(with(&|s| {
            away(s);
            s.range = f64::INFINITY;
        }));
        // A flat cell (near = far) and a zero-width one.
        let flat = Cell {
            depths: [1.0, 1.0],
            ..cell
        };
        assert!(spot_intersects_cell(&base, &flat));
        let sliver = Cell {
            x_slopes: [0.1, 0.1],
            ..cell
        };
        assert!(spot_intersects_cell(&base, &sliver));
        let beside = SpotVolume {
            apex: DVec3::new(0.6, 0.0, -0.5),
            ..base
        };
        assert!(sphere_intersects_cell(beside.apex, beside.range, &sliver));
        assert!(!spot_intersects_cell(&beside, &sliver));
    }

    /// The tolerance band is narrow: a gap of ten tolerances is always found (by either engine),
    /// one of three tolerances by the public one; touching is never called apart.
    #[test]
    fn a_gap_of_a_few_tolerances_is_separated() {
        let mut rng = Pcg64::seed_from_u64(9);
        let mut routes = [0; 3];
        for case in 0..3000 {
            let scale = [1.0, 1e6, 1e-3][case % 3];
            let range_factor = if case % 5 == 0 { 1e-5 } else { 1.0 };
            let alpha = if case % 7 == 0 {
                1e-4
            } else {
                random_angle(&mut rng)
            };
            let (cell, touching, _, n) = touching_case(&mut rng, scale, range_factor, alpha);
            let tol = TOLERANCE * length_scale(&touching, &cell);
            let apart = |gap: f64| SpotVolume {
                apex: touching.apex + n * gap,
                ..touching
            };
            for engine in [Engine::GjkThenFeatures, Engine::FeaturesOnly] {
                let (touches, _) = classify(&touching, &cell, engine);
                assert!(touches, "case {case} {engine:?}: {touching:?} {cell:?}");
                let (hits, route) = classify(&apart(10.0 * tol), &cell, engine);
                assert!(!hits, "case {case} {engine:?}: {touching:?} {cell:?}");
                if engine == Engine::GjkThenFeatures {
                    routes[route as usize] += 1;
                }
            }
            let (hits, _) = classify(&apart(3.0 * tol), &cell, Engine::GjkThenFeatures);
            assert!(!hits, "case {case}: {touching:?} {cell:?}");
        }
        eprintln!("ten tolerances apart: routes (quick, gjk, features): {routes:?}");
        // Near touching, GJK stalls now and then: the feature search must have had work to do.
        assert!(routes[Route::Features as usize] > 0);
    }

    /// GJK and the feature search are independent algorithms: they agree on random cases at
    /// every scale.
    #[test]
    fn engines_agree_on_random_cases() {
        let mut rng = Pcg64::seed_from_u64(10);
        for case in 0..5000 {
            let cell = random_cell(&mut rng, [1.0, 1e6, 1e-3][case % 3]);
            let angle = random_angle(&mut rng);
            let mut spot = random_spot_near(&mut rng, &cell, angle);
            if case % 2 == 0 {
                spot.range *= 0.05;
            }
            let (public, _) = classify(&spot, &cell, Engine::GjkThenFeatures);
            let (features, _) = classify(&spot, &cell, Engine::FeaturesOnly);
            assert_eq!(public, features, "case {case}: {spot:?} {cell:?}");
        }
    }

    #[test]
    fn very_small_range() {
        let cell = unit_cell();
        let face = DVec3::new(0.1, 0.2, -1.0);
        let r = 1e-8;
        let spot = |apex: DVec3, direction: DVec3, range: f64| SpotVolume {
            apex,
            direction,
            range,
            angle: 0.5,
        };
        let front = face + DVec3::Z * 0.5 * r;
        assert!(spot_intersects_cell(&spot(front, DVec3::NEG_Z, r), &cell));
        assert!(!spot_intersects_cell(&spot(front, DVec3::Z, r), &cell));
        assert!(!spot_intersects_cell(
            &spot(face + DVec3::Z * 2.0 * r, DVec3::NEG_Z, r),
            &cell
        ));
        assert!(spot_intersects_cell(&spot(face, DVec3::Z, 0.0), &cell));
        assert!(!spot_intersects_cell(
            &spot(front, DVec3::NEG_Z, 0.0),
            &cell
        ));
        assert!(!spot_intersects_cell(
            &spot(face, DVec3::NEG_Z, -1.0),
            &cell
        ));
        assert!(!spot_intersects_cell(
            &spot(face, DVec3::NEG_Z, f64::NAN),
            &cell
        ));
        check_touching_family(7, 1.0, 1e-6, random_angle);
    }

    /// A spot of range `r` beside the right wall (x = 0.1·d) of a slice from depth `s` to each of
    /// `fars`, at depth 2·`s`, pointing straight at the wall: touching at a gap of 0.95 `r`, not at
    /// 1.05 `r` or 3 `r` however deep the slice reaches.
    fn assert_tolerance_stays_local(s: f64, r: f64, fars: [f64; 2]) {
        let wall = DVec3::new(1.0, 0.0, 0.1).normalize(); // outward normal of x = 0.1·d
        let on_wall = DVec3::new(0.2, 0.0, -2.0) * s;
        for far in fars {
            let cell = Cell {
                x_slopes: [-0.1, 0.1],
                y_slopes: [-0.1, 0.1],
                depths: [s, far],
            };
            let spot = |gap: f64| SpotVolume {
                apex: on_wall + wall * gap,
                direction: -wall,
                range: r,
                angle: 0.5,
            };
            assert!(spot_intersects_cell(&spot(0.95 * r), &cell), "far {far}");
            assert!(!spot_intersects_cell(&spot(1.05 * r), &cell), "far {far}");
            assert!(!spot_intersects_cell(&spot(3.0 * r), &cell), "far {far}");
        }
    }

    #[test]
    fn a_cell_reaching_very_deep_does_not_widen_a_tiny_spots_tolerance() {
        // A spot 1e-6 long in a slice reaching 10⁷ deep: its tolerance band must stay local to
        // the light (about 1e-12 of the depth 2 where it is), not grow with the cell's far corners
        // (1e-12 of 10⁷ is ten ranges).
        assert_tolerance_stays_local(1.0, 1e-6, [10.0, 1e7]);
    }

    #[test]
    fn a_spot_near_the_eye_keeps_its_tolerance_however_deep_the_cell() {
        // The same near the eye: everything 1e-14 times as large, the spot 1e-20 long. The cut
        // must end a range past the spot's far depth (about 2e-14), not a fixed length beyond it:
        // a cut at depth 2 or more made the band 1e-12 of that, ten million ranges.
        assert_tolerance_stays_local(1e-14, 1e-20, [10.0 * 1e-14, 1e7]);
    }

    /// An audit's needle spot (a miss hunt, 2026-11-30): its apex 0.008 behind the eye, pointing
    /// further behind, against a cell of a 179.985° camera whose x walls slope 1e8 — GJK's band
    /// there is about 200 wide (the corners of the cell cut a range past the light reach 2e14
    /// out), and the 0.013 between the volume and the near wall was inside it: listed. The near
    /// wall now decides, in the light's own scale; moved to touch the wall, it is listed.
    #[test]
    fn a_spot_wholly_behind_the_eye_misses_a_cell_of_a_nearly_flat_view() {
        let cell = Cell {
            x_slopes: [-166194811.279304, -99716886.7675824],
            y_slopes: [-7607.794705778687, -5705.846029334015],
            depths: [0.004788006190210581, 1775889.125],
        };
        let behind = SpotVolume {
            apex: DVec3::new(-652634.2885737368, -17.259994845615438, 0.00829731416888535),
            direction: DVec3::new(-8.09345799595742e-6, 0.997898635148469, 0.0647943971599304),
            range: 652470.0625,
            angle: 3.902640855812933e-6,
        };
        assert!(!spot_intersects_cell(&behind, &cell));
        assert_eq!(
            classify(&behind, &cell, Engine::GjkThenFeatures),
            (false, Route::Quick)
        );
        // Turned to face into the view, the needle reaches the cell's depths: the near wall
        // does not decide it (GJK does, as before).
        let turned = SpotVolume {
            direction: DVec3::new(-8.09345799595742e-6, 0.997898635148469, -0.0647943971599304),
            ..behind
        };
        assert_ne!(
            classify(&turned, &cell, Engine::GjkThenFeatures).1,
            Route::Quick
        );
        // A spot whose deepest point is exactly on the near wall of a plain cell touches it.
        let unit = unit_cell();
        for lateral in [0.0, 0.4, -0.4] {
            let touching = SpotVolume {
                apex: DVec3::new(lateral, lateral, -unit.depths[0] + 0.5),
                direction: DVec3::NEG_Z,
                range: 0.5,
                angle: 0.2,
            };
            assert!(spot_intersects_cell(&touching, &unit), "{lateral}");
            // Its ball reaching 0.5 into the cell, the cone turned away: the ball test passes
            // it, and the near wall rejects it (GJK did before, on its wider band).
            let away = SpotVolume {
                direction: DVec3::Z,
                range: 1.0,
                ..touching
            };
            assert_eq!(
                classify(&away, &unit, Engine::GjkThenFeatures),
                (false, Route::Quick),
                "{lateral}"
            );
        }
    }

    /// An audit's spot beside a cell's top wall at a 179.9° view (x walls sloping 7e7–9e7, a
    /// range of 1e13): 5.8e8 beyond the wall, inside GJK's band of 1.8e9 (the cell's corners a
    /// range past the light lie 1e21 out), so it was listed. The wall decides it now; the
    /// neighbouring cell below, which the same light misses only along a direction that is no
    /// wall's normal, is still GJK's (its band errs towards listing).
    #[test]
    fn a_spot_beyond_a_side_wall_of_a_nearly_flat_view_misses_the_cell() {
        let cell = |y_slopes| Cell {
            x_slopes: [-93809375.80349836, -72962847.84716539],
            y_slopes,
            depths: [282.58251953125, 1e308],
        };
        let spot = SpotVolume {
            apex: DVec3::new(-20037855232.0, 7084687.5, -589.5349731445312),
            direction: DVec3::new(0.4426957718968713, 0.050697569400615664, 0.8952375159707635),
            range: 9708433833984.0,
            angle: 0.002119973301887512,
        };
        let top = cell([-2866.397593995783, -0.0]);
        assert_eq!(
            classify(&spot, &top, Engine::GjkThenFeatures),
            (false, Route::Quick)
        );
        let below = cell([-5732.795187991566, -2866.397593995783]);
        assert_ne!(
            classify(&spot, &below, Engine::GjkThenFeatures).1,
            Route::Quick
        );
    }

    /// An axis along ±z that normalising left an ulp short of unit length: the component of −z
    /// perpendicular to it is rounding along the axis, which normalised *is* the axis, and the
    /// rim was put on it — the support along −z overshot the apex by 0.57 ranges (an audit's
    /// spot aimed at the eye from depth 0.5 was listed in a cell from depth 1 on).
    #[test]
    fn the_rim_stays_off_the_axis_of_a_spot_aimed_along_z() {
        let axis = DVec3::new(0.0, 0.0, f64::from(0.9f32)).normalize();
        let angle: f64 = 1.2;
        let spot = ConvexSpot {
            apex: DVec3::new(0.0, 0.0, -0.5),
            axis,
            range: 10.0,
            cos_angle: angle.cos(),
            sin_angle: angle.sin(),
        };
        // Every rim point is shallower than the apex (the cone opens towards the eye).
        assert_eq!(spot.support(DVec3::NEG_Z), spot.apex);
        let w = spot.perpendicular(DVec3::NEG_Z);
        assert!(
            w.dot(axis).abs() < 1e-12 && (w.length() - 1.0).abs() < 1e-12,
            "{w}"
        );
        let volume = SpotVolume {
            apex: spot.apex,
            direction: DVec3::new(0.0, 0.0, f64::from(0.9f32)),
            range: 10.0,
            angle,
        };
        assert!(!spot_intersects_cell(&volume, &unit_cell()));
    }

    #[test]
    fn a_negative_range_is_empty_even_inside_the_cell() {
        // The apex inside the cell would make any spot touch it; a negative range, however
        // small (well inside the ball test's rounding band), is the empty set.
        let cell = unit_cell();
        let inside = SpotVolume {
            apex: DVec3::new(0.1, -0.2, -1.5),
            direction: DVec3::NEG_Z,
            range: 1.0,
            angle: 0.3,
        };
        assert!(spot_intersects_cell(&inside, &cell));
        for range in [-1e-300, -1e-20, -1e-15] {
            let empty = SpotVolume { range, ..inside };
            assert!(!spot_intersects_cell(&empty, &cell), "range {range}");
        }
    }

    /// The public engine is GJK, the feature search only where it stalls: on random cases GJK
    /// decides nearly every case past the quick checks, and the feature search alone never
    /// hands over to it. (`engines_agree_on_random_cases` compares the two whichever runs.)
    #[test]
    fn gjk_decides_and_the_feature_search_only_takes_over() {
        let mut rng = Pcg64::seed_from_u64(17);
        let mut routes = [0; 3];
        for case in 0..2000 {
            let cell = random_cell(&mut rng, [1.0, 1e6, 1e-3][case % 3]);
            let angle = random_angle(&mut rng);
            let spot = random_spot_near(&mut rng, &cell, angle);
            let (_, route) = classify(&spot, &cell, Engine::GjkThenFeatures);
            routes[route as usize] += 1;
            let (_, alone) = classify(&spot, &cell, Engine::FeaturesOnly);
            assert_ne!(alone, Route::Gjk, "case {case}: {spot:?} {cell:?}");
        }
        let [quick, gjk, features] = routes;
        assert!(
            gjk > 500 && gjk > 20 * features,
            "routes: quick {quick}, gjk {gjk}, features {features}"
        );
    }

    /// A 45° spot from the origin down −z with range 1 (its rim is the circle of radius sin 45°
    /// at depth cos 45°), and sin 45°.
    fn forty_five_degree_spot() -> (ConvexSpot, f64) {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let spot = ConvexSpot {
            apex: DVec3::ZERO,
            axis: DVec3::NEG_Z,
            range: 1.0,
            cos_angle: h,
            sin_angle: h,
        };
        (spot, h)
    }

    #[test]
    fn descent_points_away_from_the_closest_part_of_the_volume() {
        let (spot, h) = forty_five_degree_spot();
        let close =
            |got: Option<DVec3>, want: DVec3| got.is_some_and(|g| (g - want).length() < 1e-12);
        // Beyond the rim, level with it: straight out from the rim point (h, 0, −h).
        let beyond_rim = DVec3::new(2.0, 0.0, -h);
        assert!(
            close(spot.descent(beyond_rim), DVec3::X),
            "{:?}",
            spot.descent(beyond_rim)
        );
        // Beside the side: along the side's outward normal.
        let beside = DVec3::new(1.0, 0.0, -0.2);
        assert!(close(spot.descent(beside), DVec3::new(h, 0.0, h)));
        // Past the cap, on the axis: straight down the axis.
        assert!(close(
            spot.descent(DVec3::new(0.0, 0.0, -3.0)),
            DVec3::NEG_Z
        ));
        // Inside the volume: no descent.
        assert_eq!(spot.descent(DVec3::new(0.1, 0.0, -0.5)), None);
    }

    #[test]
    fn descent_behind_the_apex_points_from_it_and_the_closed_boundary_has_none() {
        let (spot, _) = forty_five_degree_spot();
        // Behind the apex (closest to it): the unit vector from the apex, on the axis and off it.
        assert_eq!(spot.descent(DVec3::new(0.0, 0.0, 2.0)), Some(DVec3::Z));
        let behind = DVec3::new(0.3, 0.4, 1.2);
        let got = spot.descent(behind).expect("outside the volume");
        assert!((got - behind / 1.3).length() < 1e-12, "{got}");
        // On the cap and on the side: the closed volume holds them.
        assert_eq!(spot.descent(DVec3::new(0.0, 0.0, -1.0)), None);
        assert_eq!(spot.descent(DVec3::new(0.0, 0.6, -0.8)), None);
        assert_eq!(spot.descent(DVec3::new(0.5, 0.0, -0.5)), None);
        // Just outside each: a descent again.
        assert!(spot.descent(DVec3::new(0.0, 0.0, -1.0 - 1e-12)).is_some());
        assert!(spot.descent(DVec3::new(0.5 + 1e-12, 0.0, -0.5)).is_some());
    }

    /// GJK's reduction step on its own: the point of a simplex's hull nearest the origin, at a
    /// vertex (the first or another), inside an edge (and not past its end), inside a triangle,
    /// with a hint along it; a tetrahedron around the origin encloses it. (The feature search
    /// answers for GJK whenever it stalls, so the oracle's answers cannot show a reduction that
    /// stops short; this can.)
    #[test]
    fn closest_to_origin_finds_the_hulls_nearest_point() {
        let simplex = |points: &[DVec3]| {
            let mut s = Simplex::empty();
            points.iter().for_each(|&p| s.push(p));
            s
        };
        let v = DVec3::new;
        let near = |got: DVec3, want: DVec3| (got - want).length() < 1e-12;
        for (points, want) in [
            // Vertices: the second of a triangle, the end of an edge past which the line passes
            // nearer, the first of a segment.
            (
                vec![v(2.0, 1.0, 0.0), v(1.0, 0.0, 0.0), v(2.0, -1.0, 0.0)],
                v(1.0, 0.0, 0.0),
            ),
            (vec![v(3.0, 1.0, 0.0), v(1.0, 1.0, 0.0)], v(1.0, 1.0, 0.0)),
            (vec![v(0.0, 2.0, 0.0), v(3.0, 3.0, 0.0)], v(0.0, 2.0, 0.0)),
            // Inside an edge, off its middle, alone and as the nearest part of a triangle.
            (vec![v(-1.0, 1.0, 0.0), v(3.0, 1.0, 0.0)], v(0.0, 1.0, 0.0)),
            (
                vec![v(-1.0, 1.0, 0.0), v(3.0, 1.0, 0.0), v(1.0, 4.0, 0.0)],
                v(0.0, 1.0, 0.0),
            ),
            // Inside a triangle, and the same triangle with a fourth point farther off.
            (
                vec![v(1.0, -1.0, 1.0), v(-1.0, -1.0, 1.0), v(0.0, 2.0, 1.0)],
                v(0.0, 0.0, 1.0),
            ),
            (
                vec![
                    v(1.0, -1.0, 1.0),
                    v(-1.0, -1.0, 1.0),
                    v(0.0, 2.0, 1.0),
                    v(0.0, 0.0, 5.0),
                ],
                v(0.0, 0.0, 1.0),
            ),
        ] {
            let reduced = closest_to_origin(&simplex(&points));
            assert!(near(reduced.point, want), "{points:?}: {}", reduced.point);
            let hint = reduced.hint.normalize();
            assert!(
                near(hint, want.normalize()),
                "{points:?}: hint {}",
                reduced.hint
            );
            assert!(
                (reduced.enclosed_norm - want.length()).abs() < 1e-12,
                "{points:?}"
            );
            assert!(reduced.simplex.len <= 3);
            assert!(reduced.simplex.points().iter().all(|p| points.contains(p)));
        }
        // A tetrahedron around the origin encloses it, whatever the order of its points.
        let around = [
            v(1.0, 1.0, 1.0),
            v(-1.0, -1.0, 1.0),
            v(-1.0, 1.0, -1.0),
            v(1.0, -1.0, -1.0),
        ];
        for order in [
            [0, 1, 2, 3],
            [1, 0, 2, 3],
            [0, 2, 1, 3],
            [3, 2, 1, 0],
            [2, 3, 0, 1],
        ] {
            let points = order.map(|n| around[n] * 0.5 + v(0.1, 0.2, -0.1));
            let reduced = closest_to_origin(&simplex(&points));
            assert!(reduced.enclosed_norm < 1e-12, "{points:?}");
        }
        // Random tetrahedra, some far off-centre: enclosed exactly when the origin's barycentric
        // coordinates (solved for here) are all positive.
        let mut rng = Pcg64::seed_from_u64(18);
        let mut enclosing = 0;
        for _ in 0..2000 {
            let offset = random_unit(&mut rng) * rng.random_range(0.0..2.0);
            let points: [DVec3; 4] = std::array::from_fn(|_| {
                random_unit(&mut rng) * rng.random_range(0.5..4.0) + offset
            });
            let [a, b, c, d] = points;
            let m = glam::DMat3::from_cols(b - a, c - a, d - a);
            let l = m.inverse() * -a;
            let weights = [1.0 - l.x - l.y - l.z, l.x, l.y, l.z];
            if weights.iter().any(|w| w.abs() < 1e-6) {
                continue;
            }
            let inside = weights.iter().all(|&w| w > 0.0);
            enclosing += inside as usize;
            let norm = closest_to_origin(&simplex(&points)).enclosed_norm;
            assert_eq!(
                norm < 1e-9,
                inside,
                "{points:?}: {norm}, weights {weights:?}"
            );
        }
        assert!(
            (100..1900).contains(&enclosing),
            "{enclosing} of 2000 enclose the origin"
        );
    }

    /// Test 3: huge coordinates (cells a million times farther and larger).
    #[test]
    fn huge_coordinates() {
        check_touching_family(8, 1e6, 1.0, random_angle);
        let cell = Cell {
            x_slopes: [-0.5, 0.5],
            y_slopes: [-0.5, 0.5],
            depths: [1e6, 1e6 + 10.0],
        };
        // 1 cm in front of the near face at a million units, aimed at it: hits only when the
        // range reaches.
        let spot = |range: f64| SpotVolume {
            apex: DVec3::new(3.0, -2.0, -1e6 + 0.01),
            direction: DVec3::NEG_Z,
            range,
            angle: 0.2,
        };
        assert!(spot_intersects_cell(&spot(0.011), &cell));
        assert!(!spot_intersects_cell(&spot(0.009), &cell));
    }
}
