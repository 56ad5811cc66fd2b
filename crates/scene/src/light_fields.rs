//! Light fields: seeded, reproducible sets of many lights placed by a rule — uniform in a box or
//! in the view frustum, on a model's surfaces, in clumps, or on a sphere — with colours,
//! intensities, radii and optionally spot cones.
//!
//! Why: every benchmark and stress configuration must be a file anyone can regenerate
//! (`myriad scene --gltf M --field F --lights N --seed K`), and the distributions matter for
//! assignment cost: lights spread through a box touch few clusters each, lights hugging
//! surfaces crowd where the geometry is, clumps overload a few clusters, a sphere around the
//! camera is mostly culled. The standard presets (`presets.rs`) are light fields too.
//!
//! ## Reproducibility
//! A field, a count and a seed always give the same lights, bit for bit, on any machine: one
//! PCG-64 stream, consumed light by light in a fixed order — position (on a surface, drawn again
//! while it lands where faces touch), then (only where a range is non-empty) radius, hue,
//! intensity, then the spot draws. A constant (a range with
//! `min == max`) draws nothing, so adding a constant parameter never shifts the stream.
//!
//! ## Radii
//! Either uniform in a range, or derived from the light's brightness with
//! [`radius_from_intensity`]: the distance at which inverse-square illuminance of the brightest
//! channel, `intensity · max(color) / d²`, falls to a cut-off. The glTF loader uses the same rule
//! for lights without a `range`.
//!
//! ## Surfaces
//! [`SurfaceSampler`] holds every drawn triangle of a [`Model`] in world space with a cumulative
//! area table: a triangle is picked with probability proportional to its area (binary search),
//! a point uniformly inside it (square-root barycentrics), and the light is lifted off the
//! surface along the triangle's geometric normal (the counter-clockwise front side) by an offset.
//! Spot lights on surfaces point along that normal. [`SurfaceSampler::for_view`] leaves out where
//! faces touch (a wall's foot on the floor: [`SurfaceSampler::without_pressed`]) and, for a camera
//! inside the model's bounds, the faces turned away from it whose lights would lie outside
//! them (the outside of the outer walls); the command line and the renderer's default scene
//! use it.

use crate::lights::{LightRecord, Lights};
use crate::model::{Aabb, Model};
use crate::pressed_faces::{Contacts, Rest};
use glam::Vec3;
use myriad_cluster_math::Camera;
use rand::{Rng, SeedableRng};

/// The range of a light whose brightest channel has intensity `intensity` (candela, or the
/// field's unit) when illuminance below `cutoff` is treated as nothing: `sqrt(intensity /
/// cutoff)`, from `intensity / d² = cutoff`. Zero for zero intensity.
pub fn radius_from_intensity(intensity: f32, cutoff: f32) -> f32 {
    (intensity / cutoff).sqrt()
}

/// Every drawn triangle of a model in world space, ready for area-weighted sampling.
#[derive(Clone, Debug)]
pub struct SurfaceSampler {
    corners: Vec<[Vec3; 3]>,
    /// Unit geometric normals (counter-clockwise front side).
    normals: Vec<Vec3>,
    /// `cumulative[t]` = total area of triangles `0..=t` (f64 so a million small triangles do
    /// not lose the last ones to rounding).
    cumulative: Vec<f64>,
    /// The faces each triangle rests on, whose parts of it take no light
    /// ([`SurfaceSampler::without_pressed`]); empty for every triangle until then.
    rests: Vec<Vec<Rest>>,
}

/// Draws [`SurfaceSampler::sample`] makes before it keeps a point on a part of a face that rests
/// on another (where the faces left hold almost no free area).
const MAX_DRAWS: usize = 64;

/// Which faces [`SurfaceSampler::for_view_counted`] left out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FacesLeftOut {
    /// Faces pressed flat against another face (a wall's foot on the floor): hidden from every
    /// eye, with lights that would lie inside the solid they rest on
    /// ([`SurfaceSampler::without_pressed`]).
    pub pressed: usize,
    /// Faces kept that touch others on part of their area, which takes no lights.
    pub touching: usize,
    /// Faces kept whole without looking for what they touch: the search's budget ran out (a
    /// model whose faces crowd one plane from both sides, like a large ground exported once
    /// each way). Their lights may lie inside what they rest on, as every face's did before.
    pub unchecked: usize,
    /// What the view's rule did with the rest.
    pub view: ViewFaces,
}

/// Which of the faces left after the pressed ones [`SurfaceSampler::for_view_counted`] kept for
/// its eye.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewFaces {
    /// Every face: the eye is not inside the model's bounds (or they are flat).
    Every,
    /// The faces seen from inside; `left_out` of them were dropped (possibly none).
    SeenFromInside {
        /// Faces dropped.
        left_out: usize,
    },
    /// Every face, because the rule would have kept none.
    EveryForLackOfAny,
}

impl SurfaceSampler {
    /// No triangles (yet).
    fn empty() -> Self {
        Self {
            corners: Vec::new(),
            normals: Vec::new(),
            cumulative: Vec::new(),
            rests: Vec::new(),
        }
    }

    /// The drawn triangles of `model` (every instance), leaving out degenerate ones.
    pub fn new(model: &Model) -> Self {
        Self::from_triangles(model.world_triangles().map(|(t, _)| t))
    }

    /// From triangles given directly (world space), leaving out degenerate ones.
    pub fn from_triangles(triangles: impl IntoIterator<Item = [Vec3; 3]>) -> Self {
        let mut s = Self::empty();
        let mut total = 0.0f64;
        for t in triangles {
            let area = triangle_area(&t);
            if !(area > 0.0 && area.is_finite()) {
                continue;
            }
            total += area;
            s.corners.push(t);
            s.normals
                .push((t[1] - t[0]).cross(t[2] - t[0]).normalize_or(Vec3::Y));
            s.cumulative.push(total);
            s.rests.push(Vec::new());
        }
        s
    }

    /// The triangles `keep` says yes to (by index), with what each rests on.
    fn retain(&self, mut keep: impl FnMut(usize) -> bool) -> Self {
        let mut s = Self::empty();
        let mut total = 0.0f64;
        for t in 0..self.corners.len() {
            if keep(t) {
                total += triangle_area(&self.corners[t]);
                s.corners.push(self.corners[t]);
                s.normals.push(self.normals[t]);
                s.cumulative.push(total);
                s.rests.push(self.rests[t].clone());
            }
        }
        s
    }

    /// The surfaces a view from `eye` wants lights on, lifted by `offset`
    /// ([`SurfaceSampler::for_view_counted`] also says which were left out). Never a face
    /// pressed flat against another ([`SurfaceSampler::without_pressed`]). With the eye inside the
    /// model's bounds ([`SurfaceSampler::seen_from_inside`]), a face is dropped when it faces
    /// away from the eye and its lights would lie outside the bounds
    /// ([`SurfaceSampler::seen_from`]): an outer wall's exterior face, a floor slab's underside,
    /// a roof — whose lights light nothing the eye sees (in the default atrium, 28 % of a surface
    /// field's lights). A face turned towards the eye is always kept: an object seen from a
    /// corner of its bounds (a model without a camera gets such a view) keeps its near side.
    /// From outside the bounds every face is kept; and so is every face when the rule would
    /// keep none (a closed shell wound inside out), rather than no surface at all. So the
    /// lights depend on the eye: two cameras of one model, with one seed, may place different
    /// lights.
    pub fn for_view(model: &Model, eye: Vec3, offset: f32) -> Self {
        Self::for_view_counted(model, eye, offset).0
    }

    /// [`SurfaceSampler::for_view`], and which faces it left out.
    pub fn for_view_counted(model: &Model, eye: Vec3, offset: f32) -> (Self, FacesLeftOut) {
        let (unpressed, pressed, unchecked) = Self::new(model).without_pressed_counted();
        let (kept, view) = unpressed.viewed_from(model.bounds(), eye, offset);
        let touching = kept.rests.iter().filter(|r| !r.is_empty()).count();
        (
            kept,
            FacesLeftOut {
                pressed,
                touching,
                unchecked,
                view,
            },
        )
    }

    /// These triangles without the ones pressed flat against others, and how many those were:
    /// faces covered all over by faces coplanar with them and turned the other way — two solids
    /// touching, like a wall's foot on a floor. No eye sees such a face, and a light lifted off
    /// it lies inside the solid it rests on. A face covered in part (a column's foot wider than
    /// the beam it stands on, a roof slab over a beam) is kept, and [`SurfaceSampler::sample`]
    /// places no light on the covered part. In the default atrium, 4706 of 11,048 faces are
    /// pressed; before, 23 % of a surface field's lights (seen from `Main`: 100,000 draws) were
    /// placed where faces touch, lifted into its floor slab, beams, spandrels and plinths. The
    /// exact mirror of a face (its three corners, wound the other way: a two-sided sheet) does
    /// not count as what it rests on — a sheet whose back is triangulated otherwise does, and
    /// loses both sides; two solids touching with the same triangles keep theirs. When every
    /// face is pressed, every face is kept.
    pub fn without_pressed(self) -> (Self, usize) {
        let (kept, pressed, _) = self.without_pressed_counted();
        (kept, pressed)
    }

    /// [`SurfaceSampler::without_pressed`], and how many faces were kept whole unsearched (a
    /// model whose faces crowd one plane from both sides runs out of the search's budget).
    fn without_pressed_counted(self) -> (Self, usize, usize) {
        let Contacts {
            pressed,
            rests,
            unchecked,
        } = crate::pressed_faces::contacts(&self.corners, &self.normals);
        let count = pressed.iter().filter(|&&p| p).count();
        if count == pressed.len() {
            return (self, 0, 0);
        }
        let resting = Self { rests, ..self };
        (resting.retain(|t| !pressed[t]), count, unchecked)
    }

    /// Whether `eye` looks at a model with bounds `bounds` from inside, where
    /// [`SurfaceSampler::for_view`] drops faces: the eye within the bounds, and the bounds of
    /// some thickness on every axis (a flat model has no inside, though an eye level with it
    /// lies within its bounds).
    pub fn seen_from_inside(bounds: Aabb, eye: Vec3) -> bool {
        bounds.contains(eye) && bounds.size().min_element() > 0.0
    }

    /// [`SurfaceSampler::for_view`]'s choice for a model with bounds `bounds`.
    fn viewed_from(self, bounds: Aabb, eye: Vec3, offset: f32) -> (Self, ViewFaces) {
        if !Self::seen_from_inside(bounds, eye) {
            return (self, ViewFaces::Every);
        }
        let seen = self.seen_from(bounds, eye, offset);
        match self.triangle_count() - seen.triangle_count() {
            _ if seen.triangle_count() == 0 => (self, ViewFaces::EveryForLackOfAny),
            left_out => (seen, ViewFaces::SeenFromInside { left_out }),
        }
    }

    /// The triangles whose lights an eye at `eye` inside `bounds` can be lit by: those turned
    /// towards the eye (it lies on their front side), and those whose three corners, lifted by
    /// `offset` along the normal, stay inside `bounds` (boundary included; the box is convex,
    /// so every light on such a triangle does too, up to f32 rounding). A triangle turned away
    /// with a corner lifted out is dropped whole.
    pub fn seen_from(&self, bounds: Aabb, eye: Vec3, offset: f32) -> Self {
        self.retain(|t| {
            let (corners, normal) = (&self.corners[t], self.normals[t]);
            // One corner decides the side: the triangle is planar.
            let towards = normal.dot(eye - corners[0]) > 0.0;
            towards
                || corners
                    .iter()
                    .all(|&p| bounds.contains(p + offset * normal))
        })
    }

    /// Number of (non-degenerate) triangles.
    pub fn triangle_count(&self) -> usize {
        self.corners.len()
    }

    /// Total area in square metres.
    pub fn total_area(&self) -> f64 {
        self.cumulative.last().copied().unwrap_or(0.0)
    }

    /// A point uniform over the surface and the unit normal there, or `None` without triangles.
    /// A point on a part of a face that rests on another ([`SurfaceSampler::without_pressed`])
    /// is drawn again, up to 64 draws in all: the last is kept even there, so a surface whose
    /// free part is a few percent of it may get a light where faces touch.
    pub fn sample(&self, rng: &mut impl Rng) -> Option<(Vec3, Vec3)> {
        let total = self.total_area();
        if self.corners.is_empty() {
            return None;
        }
        let mut draw = || {
            let u = rng.random_range(0.0..total);
            let t = self
                .cumulative
                .partition_point(|&c| c <= u)
                .min(self.corners.len() - 1);
            let [a, b, c] = self.corners[t];
            let r1 = rng.random_range(0.0f32..1.0).sqrt();
            let r2 = rng.random_range(0.0f32..1.0);
            (t, a * (1.0 - r1) + b * (r1 * (1.0 - r2)) + c * (r1 * r2))
        };
        let (mut t, mut p) = draw();
        for _ in 1..MAX_DRAWS {
            if !self.rests[t].iter().any(|rest| rest.holds(p)) {
                break;
            }
            (t, p) = draw();
        }
        Some((p, self.normals[t]))
    }
}

/// A triangle's area, in f64 from its f32 cross product.
fn triangle_area(t: &[Vec3; 3]) -> f64 {
    0.5 * (t[1] - t[0]).cross(t[2] - t[0]).as_dvec3().length()
}

/// Where a light field's lights go.
#[derive(Clone, Debug)]
pub enum Placement {
    /// Uniform in a box.
    Box(Aabb),
    /// Uniform by volume in the camera's view frustum between its near and far planes.
    Frustum(Camera),
    /// On a model's surfaces (area-weighted), lifted by `offset` along the surface normal.
    Surfaces {
        /// The triangles.
        surfaces: SurfaceSampler,
        /// Distance from the surface along its normal (metres, >= 0).
        offset: f32,
    },
    /// In `clumps` balls of radius `spread` whose centres are uniform in `within`; each light
    /// picks a clump uniformly and a point uniform in its ball.
    Clumps {
        /// Where the clump centres lie.
        within: Aabb,
        /// Number of clumps (>= 1).
        clumps: usize,
        /// Radius of each clump (>= 0).
        spread: f32,
    },
    /// Uniform on the surface of a sphere.
    Sphere {
        /// The sphere's centre.
        center: Vec3,
        /// The sphere's radius (>= 0).
        radius: f32,
    },
}

/// How a light field's radii are chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RadiusRule {
    /// Uniform in `[min, max)` (`min == max`: constant).
    Uniform {
        /// Smallest radius (> 0).
        min: f32,
        /// Largest radius (>= min).
        max: f32,
    },
    /// From the light's intensity and colour: [`radius_from_intensity`]`(intensity ·
    /// max(color), cutoff)`.
    FromIntensity {
        /// Illuminance treated as nothing (> 0).
        cutoff: f32,
    },
}

/// How a light field's colours are chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ColorRule {
    /// A saturated colour of uniformly random hue (one draw).
    RandomHue,
    /// The same colour for every light (no draw).
    Fixed(Vec3),
}

/// Which lights are spots, and their cones.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotRule {
    /// Probability that a light is a spot, in [0, 1].
    pub fraction: f32,
    /// Outer half angle range in degrees, within (0, 180].
    pub angle_deg: [f32; 2],
}

/// A rule for generating lights; see the module docs.
#[derive(Clone, Debug)]
pub struct LightField {
    /// Where the lights go.
    pub placement: Placement,
    /// Their radii.
    pub radius: RadiusRule,
    /// Their colours.
    pub color: ColorRule,
    /// Intensity range `[min, max)` (`min == max`: constant), min >= 0.
    pub intensity: [f32; 2],
    /// Spot lights, if any.
    pub spots: Option<SpotRule>,
}

impl LightField {
    /// A field with the `paper` preset's light parameters: radii uniform in 0.5–3 m, random
    /// hues, intensity 1, no spots.
    pub fn new(placement: Placement) -> Self {
        Self {
            placement,
            radius: RadiusRule::Uniform { min: 0.5, max: 3.0 },
            color: ColorRule::RandomHue,
            intensity: [1.0, 1.0],
            spots: None,
        }
    }

    /// The same field with radius rule `radius`.
    pub fn with_radius(self, radius: RadiusRule) -> Self {
        Self { radius, ..self }
    }

    /// The same field with colour rule `color`.
    pub fn with_color(self, color: ColorRule) -> Self {
        Self { color, ..self }
    }

    /// The same field with intensities uniform in `[min, max)`.
    pub fn with_intensity(self, min: f32, max: f32) -> Self {
        Self {
            intensity: [min, max],
            ..self
        }
    }

    /// The same field with spot lights.
    pub fn with_spots(self, spots: SpotRule) -> Self {
        Self {
            spots: Some(spots),
            ..self
        }
    }

    /// The first thing that keeps this field from generating valid lights, or `None`. Command
    /// lines check it to report bad options; [`LightField::generate`] asserts it.
    pub fn problem(&self) -> Option<String> {
        let range_ok = |[min, max]: [f32; 2]| min.is_finite() && max.is_finite() && min <= max;
        match &self.placement {
            Placement::Box(b) if !(b.min.is_finite() && b.max.is_finite() && !b.is_empty()) => {
                return Some(format!("box {} .. {} is empty or not finite", b.min, b.max));
            }
            Placement::Surfaces { surfaces, offset } => {
                if surfaces.triangle_count() == 0 {
                    return Some(
                        "no surfaces to place lights on: no drawn triangle has a positive, finite \
                         area"
                            .into(),
                    );
                }
                if !(*offset >= 0.0 && offset.is_finite()) {
                    return Some(format!(
                        "surface offset must be finite and >= 0, got {offset}"
                    ));
                }
            }
            Placement::Clumps {
                within,
                clumps,
                spread,
            } if *clumps == 0 || !(*spread >= 0.0 && spread.is_finite()) || within.is_empty() => {
                return Some(format!(
                    "clumps need >= 1 clump, a finite spread >= 0 and a non-empty box, got \
                     {clumps} clumps, spread {spread}"
                ));
            }
            Placement::Frustum(camera) => {
                // Every light lies within (|t.x| + |t.y| + 1) · far of the eye.
                let t = camera.tan_half_fov().as_dvec2();
                let reach = f64::from(camera.position.abs().max_element())
                    + (t.x.abs() + t.y.abs() + 1.0) * f64::from(camera.far);
                if !(reach < f64::from(f32::MAX) / 2.0) {
                    return Some(format!(
                        "the camera's far plane at {:e} puts the frustum's far corners past f32's \
                         range (about 3.4e38) at this field of view: give the camera a nearer \
                         far plane",
                        camera.far
                    ));
                }
            }
            Placement::Sphere { center, radius }
                if !(center.is_finite() && *radius >= 0.0 && radius.is_finite()) =>
            {
                return Some(format!(
                    "sphere centre {center}, radius {radius} are not valid"
                ));
            }
            _ => {}
        }
        match self.radius {
            RadiusRule::Uniform { min, max } if !(min > 0.0 && range_ok([min, max])) => {
                return Some(format!(
                    "radii must satisfy 0 < min <= max, got {min}..{max}"
                ));
            }
            RadiusRule::FromIntensity { cutoff } if !(cutoff > 0.0 && cutoff.is_finite()) => {
                return Some(format!("cut-off must be finite and > 0, got {cutoff}"));
            }
            _ => {}
        }
        if let ColorRule::Fixed(c) = self.color
            && !(c.is_finite() && c.min_element() >= 0.0)
        {
            return Some(format!("colour must be finite and >= 0, got {c}"));
        }
        let [i0, i1] = self.intensity;
        if !(i0 >= 0.0 && range_ok(self.intensity)) {
            return Some(format!(
                "intensities must satisfy 0 <= min <= max, got {i0}..{i1}"
            ));
        }
        if let RadiusRule::FromIntensity { .. } = self.radius {
            let dark = match self.color {
                ColorRule::Fixed(c) => c.max_element() == 0.0,
                ColorRule::RandomHue => false,
            };
            if i0 == 0.0 || dark {
                return Some(
                    "radii from intensity need intensities and colours > 0 (a zero radius is \
                     not a light)"
                        .into(),
                );
            }
            // The brightest channel of a random hue is 1; of a fixed colour, its largest.
            let channel = match self.color {
                ColorRule::Fixed(c) => c.max_element(),
                ColorRule::RandomHue => 1.0,
            };
            if let RadiusRule::FromIntensity { cutoff } = self.radius {
                let (shortest, longest) = (
                    radius_from_intensity(i0 * channel, cutoff),
                    radius_from_intensity(i1 * channel, cutoff),
                );
                if !(i1 * channel).is_finite() {
                    return Some(format!(
                        "intensity {i1:e} times the colour's brightest channel {channel:e} \
                         overflows f32"
                    ));
                }
                if !longest.is_finite() {
                    return Some(format!(
                        "cut-off {cutoff:e} is too small for intensities up to {i1}: the radius \
                         overflows f32; raise the cut-off"
                    ));
                }
                if !(shortest > 0.0) {
                    return Some(format!(
                        "cut-off {cutoff:e} is too large for intensities from {i0:e}: the radius \
                         rounds to 0; lower the cut-off"
                    ));
                }
            }
        }
        if let Some(s) = self.spots {
            let [a0, a1] = s.angle_deg;
            // Above 0 in radians, as the lights get them: 1e-45° is 0 there, and the scene
            // made from the field was refused for its first spot instead of the option (audit).
            if !((0.0..=1.0).contains(&s.fraction)
                && a0.to_radians() > 0.0
                && a1 <= 180.0
                && range_ok([a0, a1]))
            {
                return Some(format!(
                    "spots need a fraction in [0, 1] and angles 0 < min <= max <= 180 (min above 0 \
                     once in radians), got {} and {a0}..{a1}",
                    s.fraction
                ));
            }
        }
        None
    }

    /// `count` lights from `seed`, with `source_index` 0, 1, …. Panics if
    /// [`LightField::problem`] finds one.
    pub fn generate(&self, count: usize, seed: u64) -> Lights {
        if let Some(problem) = self.problem() {
            panic!("invalid light field: {problem}");
        }
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let clump_centres: Vec<Vec3> = match &self.placement {
            Placement::Clumps { within, clumps, .. } => (0..*clumps)
                .map(|_| uniform_in_box(within, &mut rng))
                .collect(),
            _ => Vec::new(),
        };
        let mut lights = Lights::with_capacity(count);
        for index in 0..count {
            let (position, normal) = match &self.placement {
                Placement::Box(b) => (uniform_in_box(b, &mut rng), None),
                Placement::Frustum(camera) => (uniform_in_frustum(camera, &mut rng), None),
                Placement::Surfaces { surfaces, offset } => {
                    // problem() guarantees triangles.
                    let (p, n) = surfaces.sample(&mut rng).unwrap_or((Vec3::ZERO, Vec3::Y));
                    (p + n * *offset, Some(n))
                }
                Placement::Clumps { spread, .. } => {
                    let c = clump_centres[rng.random_range(0..clump_centres.len())];
                    (c + in_unit_ball(&mut rng) * *spread, None)
                }
                Placement::Sphere { center, radius } => {
                    (*center + unit_vector(&mut rng) * *radius, None)
                }
            };
            let uniform_radius = match self.radius {
                RadiusRule::Uniform { min, max } => Some(draw(&mut rng, min, max)),
                RadiusRule::FromIntensity { .. } => None,
            };
            let color = match self.color {
                ColorRule::RandomHue => hue_to_rgb(rng.random_range(0.0f32..1.0)),
                ColorRule::Fixed(c) => c,
            };
            let intensity = draw(&mut rng, self.intensity[0], self.intensity[1]);
            let radius = match self.radius {
                RadiusRule::FromIntensity { cutoff } => {
                    radius_from_intensity(intensity * color.max_element(), cutoff)
                }
                RadiusRule::Uniform { .. } => uniform_radius.unwrap_or(1.0),
            };
            let mut light = LightRecord::point(position, radius)
                .with_color(color)
                .with_intensity(intensity)
                .with_source_index(index as u32);
            if let Some(s) = self.spots
                && rng.random_range(0.0f32..1.0) < s.fraction
            {
                let angle = draw(&mut rng, s.angle_deg[0], s.angle_deg[1]).to_radians();
                let direction = normal.unwrap_or_else(|| unit_vector(&mut rng));
                light = light.with_spot(direction, angle.min(std::f32::consts::PI));
            }
            lights.push(light);
        }
        lights
    }
}

/// Uniform in `[min, max)`; `min` itself, with no draw, when the range is empty.
///
/// A range whose width overflows f32 (a model's bounds near ±`f32::MAX`) is drawn in f64, where
/// `rand`'s f32 sampler would panic; every other range keeps `rand`'s sampler, so seeded scenes
/// stay what they were.
fn draw(rng: &mut impl Rng, min: f32, max: f32) -> f32 {
    if !(min < max) {
        return min;
    }
    if (max - min).is_finite() {
        return rng.random_range(min..max);
    }
    let (lo, hi) = (f64::from(min), f64::from(max));
    let t: f64 = rng.random_range(0.0..1.0);
    ((lo + t * (hi - lo)) as f32).clamp(min, max.next_down())
}

/// A point uniform in a box (three draws: x, y, z).
pub(crate) fn uniform_in_box(b: &Aabb, rng: &mut impl Rng) -> Vec3 {
    Vec3::new(
        draw(rng, b.min.x, b.max.x),
        draw(rng, b.min.y, b.max.y),
        draw(rng, b.min.z, b.max.z),
    )
}

/// A point uniform by volume in the frustum between near and far (depth density ∝ d²).
pub(crate) fn uniform_in_frustum(camera: &Camera, rng: &mut impl Rng) -> Vec3 {
    let u = rng.random_range(0.0f32..1.0);
    let (n3, f3) = (camera.near.powi(3), camera.far.powi(3));
    // Cubed in f32 where the far plane's cube fits it, as every preset's scenes were made; past
    // ∛f32::MAX ≈ 7·10¹² the cube overflowed and every light came out NaN: cubed in f64 there.
    let depth = if f3.is_finite() {
        (n3 + u * (f3 - n3)).cbrt()
    } else {
        let (n3, f3) = (
            f64::from(camera.near).powi(3),
            f64::from(camera.far).powi(3),
        );
        ((n3 + f64::from(u) * (f3 - n3)).cbrt() as f32).min(camera.far)
    };
    let t = camera.tan_half_fov();
    let view = Vec3::new(
        rng.random_range(-1.0f32..1.0) * t.x * depth,
        rng.random_range(-1.0f32..1.0) * t.y * depth,
        -depth,
    );
    let (right, up, forward) = camera.basis_f64();
    camera.position + right.as_vec3() * view.x + up.as_vec3() * view.y - forward.as_vec3() * view.z
}

/// A point uniform in the unit ball (rejection sampling).
fn in_unit_ball(rng: &mut impl Rng) -> Vec3 {
    loop {
        let v = Vec3::new(
            rng.random_range(-1.0f32..1.0),
            rng.random_range(-1.0f32..1.0),
            rng.random_range(-1.0f32..1.0),
        );
        if v.length_squared() <= 1.0 {
            return v;
        }
    }
}

/// A uniformly distributed unit vector (rejection sampling in the ball, then normalised).
pub(crate) fn unit_vector(rng: &mut impl Rng) -> Vec3 {
    loop {
        let v = Vec3::new(
            rng.random_range(-1.0f32..1.0),
            rng.random_range(-1.0f32..1.0),
            rng.random_range(-1.0f32..1.0),
        );
        let len2 = v.length_squared();
        if len2 > 1e-4 && len2 <= 1.0 {
            return v / len2.sqrt();
        }
    }
}

/// A saturated colour of hue `h` in [0, 1).
pub(crate) fn hue_to_rgb(h: f32) -> Vec3 {
    let x = h * 6.0;
    let channel = |offset: f32| (((x + offset) % 6.0 - 3.0).abs() - 1.0).clamp(0.0, 1.0);
    Vec3::new(channel(0.0), channel(4.0), channel(2.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::ONE)
    }

    #[test]
    fn radius_from_intensity_inverts_inverse_square() {
        let r = radius_from_intensity(50.0, 0.5);
        assert!((50.0 / (r * r) - 0.5).abs() < 1e-5);
        assert_eq!(radius_from_intensity(0.0, 0.1), 0.0);
    }

    #[test]
    fn cut_offs_that_overflow_or_vanish_the_radius_are_named() {
        let field = |cutoff: f32| {
            LightField::new(Placement::Box(unit_box()))
                .with_radius(RadiusRule::FromIntensity { cutoff })
                .with_intensity(1e-10, 100.0)
        };
        let tiny = field(1e-45).problem().expect("a problem");
        assert!(tiny.contains("too small"), "{tiny}");
        let huge = field(1e38).problem().expect("a problem");
        assert!(huge.contains("too large"), "{huge}");
        assert_eq!(field(0.01).problem(), None);
        assert!(field(0.01).generate(50, 1).problems().is_empty());
    }

    #[test]
    fn boxes_wider_than_f32_spans_are_drawn_without_panicking() {
        // A model's bounds near ±f32::MAX: the box is finite but its width is not (rand's f32
        // sampler panicked on it).
        let huge = Aabb::new(Vec3::splat(-3.0e38), Vec3::splat(3.0e38));
        for placement in [
            Placement::Box(huge),
            Placement::Clumps {
                within: huge,
                clumps: 4,
                spread: 1.0,
            },
        ] {
            let field = LightField::new(placement);
            assert_eq!(field.problem(), None);
            let lights = field.generate(2000, 3);
            assert!(lights.problems().is_empty(), "{:?}", lights.problems());
            let xs: Vec<f32> = lights.iter().map(|l| l.position.x).collect();
            assert!(xs.iter().all(|x| x.is_finite()));
            // Spread over the whole box, both signs.
            assert!(xs.iter().any(|&x| x < -1.0e38) && xs.iter().any(|&x| x > 1.0e38));
        }
        // Ordinary ranges keep their old draws (seeded scenes must not change).
        let mut a = rand_pcg::Pcg64::seed_from_u64(1);
        let mut b = rand_pcg::Pcg64::seed_from_u64(1);
        for _ in 0..100 {
            assert_eq!(draw(&mut a, -2.0, 3.0), b.random_range(-2.0f32..3.0));
        }
    }

    /// A far plane past ∛f32::MAX (≈ 7·10¹²) still gives lights in the frustum (its cube
    /// overflowed f32 and every light came out NaN), and one whose frustum's far corners pass
    /// f32's range is a problem of the field, named, not lights that fail later.
    #[test]
    fn frustum_fields_reach_far_planes_past_the_f32_cube() {
        for far in [6e12f32, 8e12, 1e20, 1e37] {
            let camera = Camera::new(Vec3::ONE, Vec3::NEG_Z, Vec3::Y, 60.0, 800, 600, 0.5, far);
            let field = LightField::new(Placement::Frustum(camera));
            assert_eq!(field.problem(), None, "far {far:e}");
            let lights = field.generate(500, 3);
            assert!(
                lights.problems().is_empty(),
                "far {far:e}: {:?}",
                lights.problems().first()
            );
            let t = camera.tan_half_fov();
            let mut beyond_half = 0;
            for l in lights.iter() {
                let v = camera.view_from_world_point(l.position);
                let d = -v.z;
                assert!(
                    d >= 0.5 * (1.0 - 1e-3) && d <= far * (1.0 + 1e-3),
                    "far {far:e}: {d}"
                );
                assert!(v.x.abs() <= t.x * d * 1.0001 && v.y.abs() <= t.y * d * 1.0001);
                beyond_half += usize::from(d > 0.5 * far);
            }
            // Uniform by volume: 7/8 of the lights lie past half the far plane.
            assert!(
                (400..=475).contains(&beyond_half),
                "far {far:e}: {beyond_half}"
            );
        }
        let camera = Camera::new(Vec3::ONE, Vec3::NEG_Z, Vec3::Y, 60.0, 800, 600, 0.5, 3e38);
        let problem = LightField::new(Placement::Frustum(camera)).problem();
        assert!(
            problem
                .as_deref()
                .is_some_and(|p| p.contains("far plane at 3e38")),
            "{problem:?}"
        );
    }

    #[test]
    fn fields_are_reproducible_valid_and_where_they_should_be() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0, 800, 600, 0.5, 30.0);
        let fields = [
            LightField::new(Placement::Box(Aabb::new(
                Vec3::splat(-2.0),
                Vec3::splat(3.0),
            ))),
            LightField::new(Placement::Frustum(camera)),
            LightField::new(Placement::Sphere {
                center: Vec3::new(1.0, 2.0, 3.0),
                radius: 4.0,
            }),
            LightField::new(Placement::Clumps {
                within: unit_box(),
                clumps: 3,
                spread: 0.25,
            }),
        ];
        for field in &fields {
            let a = field.generate(400, 5);
            assert_eq!(a, field.generate(400, 5));
            assert_ne!(a, field.generate(400, 6));
            assert_eq!(a.len(), 400);
            assert!(a.problems().is_empty(), "{:?}", a.problems());
            assert_eq!(a.source_index, (0..400).collect::<Vec<u32>>());
            for l in a.iter() {
                assert!((0.5..3.0).contains(&l.radius));
                let p = l.position;
                let ok = match &field.placement {
                    Placement::Box(b) => b.contains(p),
                    Placement::Frustum(c) => {
                        let v = c.view_from_world_point(p);
                        let t = c.tan_half_fov();
                        let d = -v.z;
                        (0.5 - 1e-4..=30.0 + 1e-3).contains(&d)
                            && v.x.abs() <= t.x * d * 1.0001
                            && v.y.abs() <= t.y * d * 1.0001
                    }
                    Placement::Sphere { center, radius } => {
                        ((p - *center).length() - radius).abs() < 1e-4
                    }
                    Placement::Clumps { within, spread, .. } => {
                        let grown = Aabb::new(within.min - *spread, within.max + *spread);
                        grown.contains(p)
                    }
                    Placement::Surfaces { .. } => unreachable!(),
                };
                assert!(ok, "{p} outside {:?}", field.placement);
            }
        }
    }

    #[test]
    fn clumps_concentrate_lights() {
        let field = LightField::new(Placement::Clumps {
            within: Aabb::new(Vec3::splat(-50.0), Vec3::splat(50.0)),
            clumps: 4,
            spread: 1.0,
        });
        let lights = field.generate(1000, 2);
        // Every light is within 1 m of one of at most 4 centres: cluster them greedily.
        let mut centres: Vec<Vec3> = Vec::new();
        for l in lights.iter() {
            if !centres.iter().any(|c| (*c - l.position).length() <= 2.0) {
                centres.push(l.position);
            }
        }
        assert!(centres.len() <= 4, "{} groups", centres.len());
        // Spread through their balls, not piled on the centres.
        let mut distinct: Vec<[u32; 3]> = lights
            .iter()
            .map(|l| l.position.to_array().map(f32::to_bits))
            .collect();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(distinct.len(), 1000);
    }

    #[test]
    fn surfaces_are_sampled_by_area_and_offset_along_the_normal() {
        // A 1×1 floor quad facing +Y and a 3×1 wall quad facing +Z: the wall has 3/4 of the area.
        let floor = [
            [
                Vec3::ZERO,
                Vec3::new(0.0, 0.0, 1.0),
                Vec3::new(1.0, 0.0, 1.0),
            ],
            [
                Vec3::ZERO,
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(1.0, 0.0, 0.0),
            ],
        ];
        let wall = [
            [
                Vec3::new(10.0, 0.0, 0.0),
                Vec3::new(13.0, 0.0, 0.0),
                Vec3::new(13.0, 1.0, 0.0),
            ],
            [
                Vec3::new(10.0, 0.0, 0.0),
                Vec3::new(13.0, 1.0, 0.0),
                Vec3::new(10.0, 1.0, 0.0),
            ],
        ];
        let degenerate = [[Vec3::ONE, Vec3::ONE, Vec3::ONE]];
        let surfaces =
            SurfaceSampler::from_triangles(floor.into_iter().chain(wall).chain(degenerate));
        assert_eq!(surfaces.triangle_count(), 4);
        assert!((surfaces.total_area() - 4.0).abs() < 1e-9);
        let field = LightField::new(Placement::Surfaces {
            surfaces,
            offset: 0.1,
        })
        .with_spots(SpotRule {
            fraction: 1.0,
            angle_deg: [30.0, 30.0],
        });
        let lights = field.generate(4000, 3);
        assert!(lights.problems().is_empty());
        let mut on_wall = 0;
        for l in lights.iter() {
            let p = l.position;
            let cone = l.spot.unwrap();
            if p.x >= 10.0 {
                on_wall += 1;
                assert!(
                    (p.z - 0.1).abs() < 1e-6 && (0.0..=1.0).contains(&p.y),
                    "{p}"
                );
                assert!(p.x <= 13.0);
                assert_eq!(cone.direction, Vec3::Z);
            } else {
                assert!(
                    (p.y - 0.1).abs() < 1e-6 && (0.0..=1.0).contains(&p.x),
                    "{p}"
                );
                assert_eq!(cone.direction, Vec3::Y);
            }
            assert!((cone.angle - 30f32.to_radians()).abs() < 1e-6);
        }
        // Expect 3000 on the wall; 4000 draws give a standard deviation of about 27.
        assert!((2850..3150).contains(&on_wall), "{on_wall}");
    }

    /// The twelve triangles of the box `min..max`, wound to face out (or in).
    fn box_faces(min: Vec3, max: Vec3, facing_out: bool) -> Vec<[Vec3; 3]> {
        let at = |i: usize| {
            Vec3::new(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            )
        };
        // Each face's corners counter-clockwise seen from outside.
        let quads = [
            [0, 4, 6, 2],
            [1, 3, 7, 5],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 2, 3, 1],
            [4, 5, 7, 6],
        ];
        let mut triangles = Vec::new();
        for [a, b, c, d] in quads {
            for t in [[a, b, c], [a, c, d]] {
                let mut t = t.map(at);
                if !facing_out {
                    t.swap(1, 2);
                }
                triangles.push(t);
            }
        }
        triangles
    }

    #[test]
    fn box_faces_face_the_way_they_are_asked_to() {
        let faces = SurfaceSampler::from_triangles(box_faces(Vec3::ZERO, Vec3::ONE, true));
        for (corners, normal) in faces.corners.iter().zip(&faces.normals) {
            let centroid = (corners[0] + corners[1] + corners[2]) / 3.0;
            assert!(
                (centroid - Vec3::splat(0.5)).dot(*normal) > 0.0,
                "{corners:?}"
            );
        }
    }

    #[test]
    fn only_faces_whose_lights_stay_inside_are_kept_for_an_eye_inside() {
        // A room (faces looking in) inside a building's shell (faces looking out), both boxes.
        let shell = Aabb::new(Vec3::splat(-10.0), Vec3::splat(10.0));
        let room = box_faces(Vec3::splat(-9.0), Vec3::splat(9.0), false);
        let outside = box_faces(shell.min, shell.max, true);
        let all = SurfaceSampler::from_triangles(room.iter().chain(&outside).copied());
        assert_eq!(all.triangle_count(), 24);
        let (inside, kept) = all.clone().viewed_from(shell, Vec3::ZERO, 0.2);
        assert_eq!(kept, ViewFaces::SeenFromInside { left_out: 12 });
        assert_eq!(inside.corners, room);
        // Every light is then inside the shell, lifted off the room's walls.
        let lights = LightField::new(Placement::Surfaces {
            surfaces: inside,
            offset: 0.2,
        })
        .generate(500, 4);
        for l in lights.iter() {
            let p = l.position.abs();
            let lifted = p.to_array().iter().any(|c| (c - 8.8).abs() < 1e-5);
            assert!(lifted && p.max_element() <= 9.0, "{}", l.position);
        }
        // The room's faces are turned towards the eye: kept even where their lights would
        // pass through the shell.
        let (through, _) = all.clone().viewed_from(shell, Vec3::ZERO, 19.5);
        assert_eq!(through.corners, room);
        // Seen from outside the shell, every face is kept.
        let (from_outside, kept) = all.viewed_from(shell, Vec3::splat(20.0), 0.2);
        assert_eq!(
            (from_outside.triangle_count(), kept),
            (24, ViewFaces::Every)
        );
        // A flat model has no inside: an eye level with it keeps both its faces.
        let floor = [
            [Vec3::ZERO, Vec3::Z, Vec3::X],
            [Vec3::ZERO, Vec3::X, Vec3::Z],
        ];
        let flat = Aabb::from_points(floor.iter().flatten().copied());
        let sheet = SurfaceSampler::from_triangles(floor);
        assert!(!SurfaceSampler::seen_from_inside(
            flat,
            Vec3::new(0.5, 0.0, 0.5)
        ));
        let (kept, _) = sheet.viewed_from(flat, Vec3::new(0.5, 0.0, 0.5), 0.2);
        assert_eq!(kept.triangle_count(), 2);
    }

    #[test]
    fn a_shell_wound_inside_out_keeps_every_face() {
        let bounds = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let out = SurfaceSampler::from_triangles(box_faces(bounds.min, bounds.max, true));
        let eye = Vec3::splat(0.5);
        assert_eq!(out.seen_from(bounds, eye, 0.1).triangle_count(), 0);
        let (kept, which) = out.viewed_from(bounds, eye, 0.1);
        assert_eq!(
            (kept.triangle_count(), which),
            (12, ViewFaces::EveryForLackOfAny)
        );
    }

    #[test]
    fn an_object_seen_from_a_corner_of_its_bounds_keeps_the_faces_turned_to_the_eye() {
        // An octahedron (corners ±1 on the axes), eye outside it but inside its bounds, as
        // `Model::view_of_bounds` places the eye for a model without a camera.
        let axis = |i: usize, s: f32| Vec3::AXES[i] * s;
        let mut faces = Vec::new();
        for (sx, sy, sz) in [-1.0f32, 1.0]
            .into_iter()
            .flat_map(|x| [-1.0f32, 1.0].map(|y| (x, y)))
            .flat_map(|(x, y)| [-1.0f32, 1.0].map(|z| (x, y, z)))
        {
            let (a, b, c) = (axis(0, sx), axis(1, sy), axis(2, sz));
            // Counter-clockwise seen from outside: flip on an odd number of negative signs.
            faces.push(if sx * sy * sz > 0.0 {
                [a, b, c]
            } else {
                [a, c, b]
            });
        }
        let octahedron = SurfaceSampler::from_triangles(faces);
        let bounds = Aabb::new(Vec3::NEG_ONE, Vec3::ONE);
        let eye = Vec3::splat(0.8);
        let seen = octahedron.seen_from(bounds, eye, 0.2);
        // The face towards the eye, whose lights leave the bounds at its corners, is kept.
        let facing = |s: &SurfaceSampler| {
            s.normals
                .iter()
                .any(|n| n.dot(Vec3::ONE.normalize()) > 0.999)
        };
        assert!(facing(&seen));
        // The faces turned away are dropped: every light of theirs leaves the bounds.
        assert!(seen.triangle_count() < 8, "{}", seen.triangle_count());
        for (corners, normal) in seen.corners.iter().zip(&seen.normals) {
            assert!(normal.dot(eye - corners[0]) > 0.0, "{corners:?}");
        }
    }

    #[test]
    fn the_atriums_surface_lights_stay_inside_it_seen_from_its_main_camera() {
        let model = crate::atrium::atrium();
        let bounds = model.bounds();
        let eye = model.camera(0, 1536, 768).unwrap().position;
        assert!(bounds.contains(eye));
        let outside = |surfaces: SurfaceSampler| {
            let lights = LightField::new(Placement::Surfaces {
                surfaces,
                offset: 0.2,
            })
            .generate(2000, 1);
            lights
                .iter()
                .filter(|l| !bounds.contains(l.position))
                .count()
        };
        // Every face: lights on the outer walls' exterior, under the floor and on the roof.
        assert!(outside(SurfaceSampler::new(&model)) > 400);
        assert_eq!(outside(SurfaceSampler::for_view(&model, eye, 0.2)), 0);
        let (_, left_out) = SurfaceSampler::for_view_counted(&model, eye, 0.2);
        assert_eq!(
            left_out,
            FacesLeftOut {
                pressed: 4706,
                touching: 330,
                unchecked: 0,
                view: ViewFaces::SeenFromInside { left_out: 34 }
            }
        );
        // From above the roof, every face again but the pressed ones.
        let above = SurfaceSampler::for_view(&model, Vec3::new(0.0, 40.0, 0.0), 0.2);
        assert_eq!(
            above.triangle_count(),
            SurfaceSampler::new(&model).triangle_count() - 4706
        );
    }

    #[test]
    fn no_light_lands_where_a_foot_half_over_an_opening_touches_the_floor() {
        // A floor over x < 0 (facing up) and a foot over x ∈ ±1 (facing down) at y = 0: the
        // foot is not covered all over, so both stay, and they touch over x ∈ [−1, 0].
        let up = |x0: f32, x1: f32, z: f32| {
            let (a, b, c, d) = (
                Vec3::new(x0, 0.0, -z),
                Vec3::new(x1, 0.0, -z),
                Vec3::new(x1, 0.0, z),
                Vec3::new(x0, 0.0, z),
            );
            [[a, d, c], [a, c, b]]
        };
        let flip = |t: [Vec3; 3]| [t[0], t[2], t[1]];
        let floor = up(-4.0, 0.0, 2.0);
        let foot = up(-1.0, 1.0, 1.0).map(flip);
        let all = SurfaceSampler::from_triangles(floor.into_iter().chain(foot));
        let in_contact = |s: &SurfaceSampler| {
            let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
            (0..4000)
                .filter_map(|_| s.sample(&mut rng))
                .filter(|(p, _)| p.x > -1.0 && p.x < 0.0 && p.z.abs() < 1.0)
                .count()
        };
        assert!(in_contact(&all) > 400, "{}", in_contact(&all));
        let (resting, pressed) = all.without_pressed();
        assert_eq!((resting.triangle_count(), pressed), (4, 0));
        assert_eq!(in_contact(&resting), 0);
        // The free parts still get their share: the foot's half over the opening too.
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let free_foot = (0..4000)
            .filter_map(|_| resting.sample(&mut rng))
            .filter(|(p, n)| p.x > 0.0 && n.y < 0.0)
            .count();
        assert!(free_foot > 200, "{free_foot}");
    }

    #[test]
    fn no_surface_light_of_the_atrium_lies_inside_its_floor_slab_or_beams() {
        let model = crate::atrium::atrium();
        let eye = model.camera(0, 1536, 768).unwrap().position;
        // Solids the atrium's module docs place (with a millimetre's margin inwards): the floor
        // slab, and each storey's beam over both arcades (local x ∈ ±14.7, z ∈ ±0.3 about
        // z = ±3.5), on which spandrels and piers stand and under which a gallery slab ends.
        let inner = |min: Vec3, max: Vec3| Aabb::new(min + 1e-3, max - 1e-3);
        // The slab down to just past its underside: a light lifted off a foot on the floor
        // lands on that underside, at y = −0.2.
        let mut solids = vec![Aabb::new(
            Vec3::new(-14.999, -0.201, -7.499),
            Vec3::new(14.999, -0.001, 7.499),
        )];
        for z in [-3.5, 3.5] {
            for (y0, y1) in [(5.5, 6.0), (10.5, 11.0)] {
                solids.push(inner(
                    Vec3::new(-14.7, y0, z - 0.3),
                    Vec3::new(14.7, y1, z + 0.3),
                ));
            }
        }
        let buried = |surfaces: SurfaceSampler| {
            LightField::new(Placement::Surfaces {
                surfaces,
                offset: 0.2,
            })
            .generate(20_000, 7)
            .iter()
            .filter(|l| solids.iter().any(|s| s.contains(l.position)))
            .count()
        };
        // Lifted off a wall's foot into the floor, off a spandrel's top into the beam, off the
        // beam's underside into the spandrels' tops...
        let all = SurfaceSampler::new(&model);
        assert!(buried(all.clone()) > 300, "{}", buried(all));
        // ...and none once the faces pressed against others are left out.
        assert_eq!(buried(SurfaceSampler::for_view(&model, eye, 0.2)), 0);
        assert_eq!(buried(SurfaceSampler::new(&model).without_pressed().0), 0);
    }

    #[test]
    fn radii_from_intensity_and_fixed_colours() {
        let field = LightField::new(Placement::Box(unit_box()))
            .with_radius(RadiusRule::FromIntensity { cutoff: 0.25 })
            .with_color(ColorRule::Fixed(Vec3::new(0.5, 1.0, 0.25)))
            .with_intensity(1.0, 16.0);
        let lights = field.generate(200, 1);
        for l in lights.iter() {
            assert!((1.0..16.0).contains(&l.intensity));
            assert_eq!(l.color, Vec3::new(0.5, 1.0, 0.25));
            assert!((l.radius - (l.intensity / 0.25).sqrt()).abs() < 1e-5);
        }
    }

    #[test]
    fn bad_fields_are_reported() {
        let b = LightField::new(Placement::Box(unit_box()));
        assert!(b.problem().is_none());
        let cases = [
            b.clone()
                .with_radius(RadiusRule::Uniform { min: 0.0, max: 1.0 }),
            b.clone()
                .with_radius(RadiusRule::FromIntensity { cutoff: 0.0 }),
            b.clone().with_intensity(2.0, 1.0),
            b.clone()
                .with_radius(RadiusRule::FromIntensity { cutoff: 1.0 })
                .with_intensity(0.0, 1.0),
            b.clone().with_spots(SpotRule {
                fraction: 0.5,
                angle_deg: [0.0, 10.0],
            }),
            b.clone().with_spots(SpotRule {
                fraction: 0.5,
                angle_deg: [1e-45, 1e-45],
            }),
            LightField::new(Placement::Surfaces {
                surfaces: SurfaceSampler::from_triangles([]),
                offset: 0.0,
            }),
            LightField::new(Placement::Box(Aabb::EMPTY)),
        ];
        for field in cases {
            assert!(field.problem().is_some(), "{field:?}");
        }
    }

    #[test]
    fn hues_go_round_the_wheel() {
        let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-5;
        assert_eq!(hue_to_rgb(0.0), Vec3::X);
        assert!(close(hue_to_rgb(1.0 / 3.0), Vec3::Y));
        assert!(close(hue_to_rgb(2.0 / 3.0), Vec3::Z));
        assert!(close(hue_to_rgb(0.5), Vec3::new(0.0, 1.0, 1.0)));
    }

    #[test]
    fn hues_are_saturated() {
        for k in 0..60 {
            let c = hue_to_rgb(k as f32 / 60.0);
            assert_eq!(c.max_element(), 1.0, "{c}");
            assert_eq!(c.min_element(), 0.0, "{c}");
        }
    }

    #[test]
    fn each_bad_parameter_is_named() {
        let b = LightField::new(Placement::Box(unit_box()));
        let lit = |color: Vec3, intensity: [f32; 2], cutoff: f32| {
            b.clone()
                .with_color(ColorRule::Fixed(color))
                .with_intensity(intensity[0], intensity[1])
                .with_radius(RadiusRule::FromIntensity { cutoff })
        };
        let surfaces = |offset: f32| Placement::Surfaces {
            surfaces: SurfaceSampler::from_triangles([[Vec3::ZERO, Vec3::X, Vec3::Y]]),
            offset,
        };
        let clumps = |clumps: usize, spread: f32, within: Aabb| Placement::Clumps {
            within,
            clumps,
            spread,
        };
        let sphere = |center: Vec3, radius: f32| Placement::Sphere { center, radius };
        let inf = f32::INFINITY;
        let cases = [
            (
                Placement::Box(Aabb::new(Vec3::NEG_INFINITY, Vec3::ONE)),
                "box",
            ),
            (Placement::Box(Aabb::new(Vec3::ONE, Vec3::ZERO)), "box"),
            (surfaces(-1.0), "surface offset"),
            (surfaces(inf), "surface offset"),
            (clumps(0, 1.0, unit_box()), "clumps need"),
            (clumps(2, -1.0, unit_box()), "clumps need"),
            (clumps(2, inf, unit_box()), "clumps need"),
            (
                clumps(2, 1.0, Aabb::new(Vec3::ONE, Vec3::ZERO)),
                "clumps need",
            ),
            (sphere(Vec3::splat(inf), 1.0), "sphere"),
            (sphere(Vec3::ZERO, -1.0), "sphere"),
            (sphere(Vec3::ZERO, inf), "sphere"),
        ];
        for (placement, named) in cases {
            let problem = LightField::new(placement).problem().expect("a problem");
            assert!(problem.contains(named), "{problem}");
        }
        let cut_off = "cut-off must be finite and > 0";
        let dark = "need intensities and colours > 0";
        let cases = [
            (
                b.clone()
                    .with_color(ColorRule::Fixed(Vec3::new(-1.0, 1.0, 1.0))),
                "colour",
            ),
            (
                b.clone()
                    .with_color(ColorRule::Fixed(Vec3::new(inf, 1.0, 1.0))),
                "colour",
            ),
            (lit(Vec3::ONE, [1.0, 1.0], 0.0), cut_off),
            (lit(Vec3::ONE, [1.0, 1.0], -1.0), cut_off),
            (lit(Vec3::ONE, [1.0, 1.0], inf), cut_off),
            (lit(Vec3::ONE, [0.0, 1.0], 1.0), dark),
            (lit(Vec3::ZERO, [1.0, 1.0], 1.0), dark),
            // The brightest channel times the intensity: 1e30 · 1e10 overflows.
            (
                lit(Vec3::new(1e10, 0.0, 0.0), [1.0, 1e30], 1.0),
                "brightest channel",
            ),
            // 1e10 · 1e10 / 1e-20 overflows the radius (1e10 + 1e10 would not).
            (
                lit(Vec3::new(1e10, 0.0, 0.0), [1e10, 1e10], 1e-20),
                "too small",
            ),
            // 1e-20 · 1e-20 / 1e10 rounds the radius to 0 (1e-20 / 1e-20 would not).
            (
                lit(Vec3::new(1e-20, 0.0, 0.0), [1e-20, 1e-20], 1e10),
                "too large",
            ),
        ];
        for (field, named) in cases {
            let problem = field.problem().expect("a problem");
            assert!(problem.contains(named), "{problem}");
        }
    }

    #[test]
    fn radii_from_intensity_use_the_brightest_channel() {
        let field = LightField::new(Placement::Box(unit_box()))
            .with_radius(RadiusRule::FromIntensity { cutoff: 0.5 })
            .with_color(ColorRule::Fixed(Vec3::new(0.5, 4.0, 1.0)))
            .with_intensity(2.0, 2.0);
        for l in field.generate(10, 1).iter() {
            assert_eq!(l.radius, 4.0);
        }
    }

    #[test]
    fn the_first_light_follows_the_documented_stream() {
        // A sphere: the position, then the radius and the hue.
        let center = Vec3::new(1.0, 2.0, 3.0);
        let sphere = LightField::new(Placement::Sphere {
            center,
            radius: 4.0,
        });
        let mut rng = rand_pcg::Pcg64::seed_from_u64(8);
        let position = center + unit_vector(&mut rng) * 4.0;
        let radius = rng.random_range(0.5f32..3.0);
        let color = hue_to_rgb(rng.random_range(0.0f32..1.0));
        let l = sphere.generate(1, 8).get(0);
        assert_eq!((l.position, l.radius, l.color), (position, radius, color));
        // Clumps: the centres first, then a clump and a point in its ball.
        let within = Aabb::new(Vec3::splat(-5.0), Vec3::splat(5.0));
        let clumps = LightField::new(Placement::Clumps {
            within,
            clumps: 2,
            spread: 0.5,
        });
        let mut rng = rand_pcg::Pcg64::seed_from_u64(8);
        let centres = [
            uniform_in_box(&within, &mut rng),
            uniform_in_box(&within, &mut rng),
        ];
        let c = centres[rng.random_range(0..centres.len())];
        let position = c + in_unit_ball(&mut rng) * 0.5;
        assert_eq!(clumps.generate(1, 8).get(0).position, position);
    }

    #[test]
    fn frustum_fields_fill_the_frustum_to_its_edges() {
        // A thick near plane: the depths stay between 5 and 6 m.
        let camera = Camera::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(0.0, 1.5, -2.0),
            Vec3::Y,
            60.0,
            800,
            600,
            5.0,
            6.0,
        );
        let t = camera.tan_half_fov();
        let lights = LightField::new(Placement::Frustum(camera)).generate(2000, 4);
        let (mut x, mut y) = (0.0f32, 0.0f32);
        let (mut nearest, mut farthest) = (f32::MAX, 0.0f32);
        for l in lights.iter() {
            let v = camera.view_from_world_point(l.position);
            let d = -v.z;
            nearest = nearest.min(d);
            farthest = farthest.max(d);
            x = x.max(v.x.abs() / (t.x * d));
            y = y.max(v.y.abs() / (t.y * d));
        }
        assert!((5.0 - 1e-4..5.01).contains(&nearest), "{nearest}");
        assert!(farthest > 5.99 && farthest <= 6.0 + 1e-4, "{farthest}");
        assert!(x > 0.99 && x <= 1.0001, "{x}");
        assert!(y > 0.99 && y <= 1.0001, "{y}");
    }
}
