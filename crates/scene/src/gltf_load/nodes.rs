//! Step 5: the node hierarchy walked iteratively into instances, cameras and lights, and what
//! makes a `KHR_lights_punctual` light usable.

use super::{Loader, finite_vec3, quoted};
use crate::light_fields::radius_from_intensity;
use crate::lights::LightRecord;
use crate::model::{
    DirectionalLight, Instance, ModelCamera, PlacedLight, Projection, PunctualKind,
    SkippedPunctualLight,
};
use glam::{Mat4, Quat, Vec3};
use gltf::json::{self, validation::Checked};

/// How many node visits a hierarchy may expand to (a node reached along several paths counts
/// once per path): a guard against files whose shared children multiply exponentially.
const MAX_NODE_VISITS: usize = 1 << 22;

/// Why a light or camera whose node maps its axis to nothing has no direction.
const NO_AXIS: &str =
    "its node's transform maps the -Z axis to zero (a zero scale or a singular matrix)";

/// `v` at unit length, or zero only when `v` is zero. A node's scale scales the axes a light or
/// camera points along (1e-30, 1e20, or [1, 1, 1e-30]) but not their direction (the
/// `KHR_lights_punctual` spec: scale does not affect a light). f32's `normalize_or_zero`
/// squares the length, which underflows below about 1e-19 (to zero, or to a subnormal that
/// normalises off unit length: 2.6e-4 off at 1e-21) and overflows above about 1e19 (to zero, as
/// if there were no direction); f64 holds the square of every f32, so it takes over wherever the
/// square is not a normal f32. Ordinary vectors keep f32's result bit for bit.
fn unit_or_zero(v: Vec3) -> Vec3 {
    if v.length_squared().is_normal() {
        v.normalize_or_zero()
    } else {
        v.as_dvec3().normalize_or_zero().as_vec3()
    }
}

/// The first three of `nodes`, each described, joined with "; " and followed by "and N more"
/// when there are more; `None` when `nodes` is empty.
pub(super) fn first_few(nodes: &[usize], describe: impl Fn(usize) -> String) -> Option<String> {
    const NAMED: usize = 3;
    if nodes.is_empty() {
        return None;
    }
    let named: Vec<String> = nodes.iter().take(NAMED).map(|&n| describe(n)).collect();
    let more = nodes.len() - named.len();
    let tail = if more > 0 {
        format!(" and {more} more")
    } else {
        String::new()
    };
    Some(format!("{}{tail}", named.join("; ")))
}

impl Loader<'_> {
    /// A node's own transform, checked to be finite and, given as a `matrix`, affine.
    fn local_transform(node: &json::Node) -> Result<Mat4, String> {
        let m = match node.matrix {
            Some(m) => {
                // Column-major: the last row is elements 3, 7, 11 and 15.
                let last_row = [m[3], m[7], m[11], m[15]];
                if last_row != [0.0, 0.0, 0.0, 1.0] {
                    return Err(format!(
                        "matrix has last row {last_row:?}, not [0, 0, 0, 1]: the spec requires \
                         a matrix made of translation, rotation and scale"
                    ));
                }
                Mat4::from_cols_array(&m)
            }
            None => {
                let t = Vec3::from_array(node.translation.unwrap_or([0.0; 3]));
                let s = Vec3::from_array(node.scale.unwrap_or([1.0; 3]));
                let q = node.rotation.as_ref().map_or([0.0, 0.0, 0.0, 1.0], |r| r.0);
                let q = Quat::from_array(q);
                let len = q.length();
                if !(len > 0.0 && len.is_finite()) {
                    return Err(format!("rotation {q} is not a unit quaternion"));
                }
                Mat4::from_scale_rotation_translation(s, q / len, t)
            }
        };
        if m.is_finite() {
            Ok(m)
        } else {
            Err("transform is not finite".into())
        }
    }

    /// Step 5: the iterative walk of the node hierarchy.
    pub(super) fn walk_nodes(&mut self) -> Result<(), String> {
        let nodes = &self.root.nodes;
        // Which nodes are some node's child: the roots of a file without scenes are the others.
        let mut has_parent = vec![false; nodes.len()];
        for child in nodes.iter().flat_map(|n| n.children.iter().flatten()) {
            if let Some(flag) = has_parent.get_mut(child.value()) {
                *flag = true;
            }
        }
        let locals = nodes
            .iter()
            .enumerate()
            .map(|(i, n)| {
                Self::local_transform(n).map_err(|e| format!("nodes[{i}]{}: {e}", quoted(&n.name)))
            })
            .collect::<Result<Vec<_>, _>>()?;
        for (i, n) in nodes.iter().enumerate() {
            let trs = [
                ("translation", n.translation.is_some()),
                ("rotation", n.rotation.is_some()),
                ("scale", n.scale.is_some()),
            ];
            let given: Vec<&str> = trs.iter().filter(|t| t.1).map(|t| t.0).collect();
            // The spec requires unit quaternions; another length is normalised (`local_transform`),
            // and said so, as every repair is (it was silent, audit). The tolerance is the
            // glTF validator's order: a quaternion stored in f32 may be a few ulps off.
            if n.matrix.is_none()
                && let Some(r) = &n.rotation
            {
                let len = Quat::from_array(r.0).length();
                if len.is_finite() && len > 0.0 && (len - 1.0).abs() > 1e-5 {
                    self.model.warnings.push(format!(
                        "nodes[{i}]{}: rotation {:?} has length {len}, not 1 (the spec requires \
                         a unit quaternion); normalised",
                        quoted(&n.name),
                        r.0
                    ));
                }
            }
            if n.matrix.is_some() && !given.is_empty() {
                self.model.warnings.push(format!(
                    "nodes[{i}]{}: has both matrix and {} (the spec allows one or the other); \
                     the matrix is used",
                    quoted(&n.name),
                    given.join(", ")
                ));
            }
        }
        let scene = self
            .root
            .scene
            .map(|s| s.value())
            .or((!self.root.scenes.is_empty()).then_some(0));
        let roots: Vec<usize> = match scene {
            Some(s) => self
                .root
                .scenes
                .get(s)
                .ok_or_else(|| format!("scene {s} does not exist"))?
                .nodes
                .iter()
                .map(|n| n.value())
                .collect(),
            None => {
                let roots: Vec<usize> = (0..nodes.len()).filter(|&i| !has_parent[i]).collect();
                if !nodes.is_empty() {
                    self.model.warnings.push(format!(
                        "no scene: drawing the {} node(s) without a parent",
                        roots.len()
                    ));
                }
                roots
            }
        };
        enum Step {
            Enter(usize, Mat4),
            Leave(usize),
        }
        let mut on_path = vec![false; nodes.len()];
        let mut stack: Vec<Step> = roots
            .iter()
            .rev()
            .map(|&n| Step::Enter(n, Mat4::IDENTITY))
            .collect();
        let mut visits = 0usize;
        // How many times the walk reaches each node: more than once breaks the spec's strict
        // trees (two parents, a scene root that is also a child or is listed twice).
        let mut reached = vec![0u32; nodes.len()];
        while let Some(step) = stack.pop() {
            let (n, parent) = match step {
                Step::Leave(n) => {
                    on_path[n] = false;
                    continue;
                }
                Step::Enter(n, parent) => (n, parent),
            };
            let node = nodes
                .get(n)
                .ok_or_else(|| format!("node {n} does not exist"))?;
            let at = format!("nodes[{n}]{}", quoted(&node.name));
            if on_path[n] {
                return Err(format!(
                    "{at} is its own ancestor (a cycle in the node hierarchy)"
                ));
            }
            visits += 1;
            reached[n] += 1;
            if visits > MAX_NODE_VISITS {
                return Err(format!(
                    "the node hierarchy expands to more than {MAX_NODE_VISITS} node instances"
                ));
            }
            let world = parent * locals[n];
            if !world.is_finite() {
                return Err(format!("{at}: world transform is not finite"));
            }
            if let Some(mesh) = node.mesh {
                let mesh = mesh.value();
                if mesh >= self.model.meshes.len() {
                    return Err(format!("{at}: mesh {mesh} does not exist"));
                }
                self.model.instances.push(Instance {
                    mesh,
                    world_from_local: world,
                    node: n,
                    name: node.name.clone(),
                });
            }
            if let Some(camera) = node.camera {
                self.camera(camera.value(), n, node, world)
                    .map_err(|e| format!("{at}: {e}"))?;
            }
            if let Some(light) = node
                .extensions
                .as_ref()
                .and_then(|e| e.khr_lights_punctual.as_ref())
            {
                self.light(light.light.value(), n, node, world)
                    .map_err(|e| format!("{at}: {e}"))?;
            }
            on_path[n] = true;
            stack.push(Step::Leave(n));
            for child in node.children.iter().flatten().rev() {
                stack.push(Step::Enter(child.value(), world));
            }
        }
        let repeated: Vec<usize> = (0..nodes.len()).filter(|&n| reached[n] > 1).collect();
        if let Some(named) = first_few(&repeated, |n| {
            format!("nodes[{n}]{} {} times", quoted(&nodes[n].name), reached[n])
        }) {
            self.model.warnings.push(format!(
                "{} node(s) reached along more than one path ({named}); the spec requires strict \
                 trees (a node has at most one parent; a scene lists only nodes without one, each \
                 once): each is drawn once per path",
                repeated.len()
            ));
        }
        Ok(())
    }

    fn camera(
        &mut self,
        index: usize,
        node: usize,
        n: &json::Node,
        world: Mat4,
    ) -> Result<(), String> {
        let c = self
            .root
            .cameras
            .get(index)
            .ok_or_else(|| format!("camera {index} does not exist"))?;
        let at = format!("cameras[{index}]{}", quoted(&c.name));
        let projection = match c.type_ {
            Checked::Valid(json::camera::Type::Perspective) => {
                let p = c.perspective.as_ref().ok_or_else(|| {
                    format!("{at}: type perspective without a perspective object")
                })?;
                if !(p.yfov > 0.0 && p.yfov < std::f32::consts::PI) {
                    return Err(format!("{at}: yfov {} is not in (0, π)", p.yfov));
                }
                if !(p.znear > 0.0 && p.znear.is_finite()) {
                    return Err(format!("{at}: znear {} is not finite and > 0", p.znear));
                }
                // An infinite projection (no zfar) gets a far plane beyond znear, which f32
                // cannot hold past f32::MAX.
                if p.zfar.is_none() && !(p.znear < f32::MAX) {
                    return Err(format!(
                        "{at}: znear {:e} without a zfar leaves no room for a far plane (it must \
                         be below f32::MAX)",
                        p.znear
                    ));
                }
                if let Some(f) = p.zfar
                    && !(f > p.znear && f.is_finite())
                {
                    return Err(format!(
                        "{at}: zfar {f} is not finite and > znear {}",
                        p.znear
                    ));
                }
                // The spec requires aspectRatio > 0. Only the output size sets the aspect here,
                // so a bad one changes nothing; it is dropped and reported.
                let aspect_ratio = p.aspect_ratio.filter(|a| *a > 0.0 && a.is_finite());
                if let Some(a) = p.aspect_ratio
                    && aspect_ratio.is_none()
                {
                    self.model.warnings.push(format!(
                        "{at}: aspectRatio {a} is not finite and > 0; ignored (the aspect \
                         follows the output size)"
                    ));
                }
                Projection::Perspective {
                    yfov: p.yfov,
                    znear: p.znear,
                    zfar: p.zfar,
                    aspect_ratio,
                }
            }
            Checked::Valid(json::camera::Type::Orthographic) => {
                let o = c.orthographic.as_ref().ok_or_else(|| {
                    format!("{at}: type orthographic without an orthographic object")
                })?;
                let ok = o.xmag.is_finite()
                    && o.xmag != 0.0
                    && o.ymag.is_finite()
                    && o.ymag != 0.0
                    && o.znear >= 0.0
                    && o.zfar > o.znear
                    && o.zfar.is_finite();
                if !ok {
                    return Err(format!(
                        "{at}: orthographic xmag {}, ymag {}, znear {}, zfar {} are not valid",
                        o.xmag, o.ymag, o.znear, o.zfar
                    ));
                }
                Projection::Orthographic {
                    xmag: o.xmag,
                    ymag: o.ymag,
                    znear: o.znear,
                    zfar: o.zfar,
                }
            }
            Checked::Invalid => return Err(format!("{at}: invalid type")),
        };
        let position = world.transform_point3(Vec3::ZERO);
        let forward = unit_or_zero(world.transform_vector3(Vec3::NEG_Z));
        let up = world.transform_vector3(Vec3::Y);
        let up = unit_or_zero(up - forward * forward.dot(up));
        let degenerate = if forward == Vec3::ZERO {
            Some(NO_AXIS)
        } else if up == Vec3::ZERO {
            Some("its node's transform maps the up axis (+Y) to zero or onto the view axis")
        } else {
            None
        };
        if let Some(why) = degenerate {
            self.model.warnings.push(format!(
                "{at}: {why}, so the camera has no view direction; left out"
            ));
            return Ok(());
        }
        let name = c
            .name
            .clone()
            .or_else(|| n.name.clone())
            .unwrap_or_else(|| format!("camera {index}"));
        self.model.cameras.push(ModelCamera {
            name,
            node,
            position,
            forward,
            up,
            projection,
        });
        Ok(())
    }

    /// A node's `KHR_lights_punctual` light: a row of [`Model::lights`](crate::Model::lights)
    /// (point, spot) or a [`DirectionalLight`]. A light whose values cannot make a light is left
    /// out, listed in [`Model::skipped_lights`](crate::Model::skipped_lights) and warned about (see
    /// "Invalid lights" in the module docs); only a light index that does not exist is an error,
    /// since then the document itself is broken.
    fn light(
        &mut self,
        index: usize,
        node: usize,
        n: &json::Node,
        world: Mat4,
    ) -> Result<(), String> {
        let light = self
            .root
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .and_then(|l| l.lights.get(index))
            .ok_or_else(|| format!("KHR_lights_punctual light {index} does not exist"))?;
        let at = format!("KHR_lights_punctual lights[{index}]{}", quoted(&light.name));
        let name = light.name.clone().or_else(|| n.name.clone());
        match self.usable_light(light, &at, world) {
            Ok(Usable::Directional { direction, color }) => {
                self.model.directional_lights.push(DirectionalLight {
                    name,
                    direction,
                    color,
                    intensity: light.intensity,
                });
            }
            Ok(Usable::Clustered {
                record,
                kind,
                range,
            }) => {
                let row = self.model.lights.len() as u32;
                self.model.lights.push(record.with_source_index(row));
                self.model.placed_lights.push(PlacedLight {
                    name,
                    node,
                    light: index,
                    kind,
                    range,
                });
            }
            Err(reason) => {
                self.model.warnings.push(format!(
                    "nodes[{node}]{}: {at}: {reason}; left out",
                    quoted(&n.name)
                ));
                self.model.skipped_lights.push(SkippedPunctualLight {
                    name,
                    node,
                    light: index,
                    reason,
                });
            }
        }
        Ok(())
    }

    /// What `light`, placed by a node with transform `world`, becomes; `Err` says why it cannot
    /// be a light. Values the loader repairs (an inner cone outside the outer) are warned about
    /// here, under `at`.
    fn usable_light(
        &mut self,
        light: &json::extensions::scene::khr_lights_punctual::Light,
        at: &str,
        world: Mat4,
    ) -> Result<Usable, String> {
        use json::extensions::scene::khr_lights_punctual::Type;
        let color = finite_vec3(light.color, "color")?;
        if color.min_element() < 0.0 || !(light.intensity >= 0.0 && light.intensity.is_finite()) {
            // A number past f32's range in the file arrives here as infinity: say so, rather
            // than show "inf" as if the file held it (audit).
            let beyond = if light.intensity.is_infinite() {
                " (the file's value is beyond f32's range)"
            } else {
                ""
            };
            return Err(format!(
                "color {color} and intensity {}{beyond} must be finite and >= 0",
                light.intensity
            ));
        }
        // The renderer shades with colour × intensity in f32: an infinite product would show
        // nothing of the light (it skips it) while the lists hold it.
        if !(color * light.intensity).is_finite() {
            return Err(format!(
                "color {} times intensity {} overflows f32 (at most {} a channel)",
                crate::json::show_vec3(color),
                crate::json::show_f32(light.intensity),
                crate::json::show_f32(f32::MAX)
            ));
        }
        let direction = unit_or_zero(world.transform_vector3(Vec3::NEG_Z));
        let kind = match light.type_ {
            Checked::Valid(Type::Directional) => {
                if direction == Vec3::ZERO {
                    return Err(format!("{NO_AXIS}, so the light has no direction"));
                }
                return Ok(Usable::Directional { direction, color });
            }
            Checked::Valid(Type::Point) => PunctualKind::Point,
            Checked::Valid(Type::Spot) => {
                let spot = light
                    .spot
                    .as_ref()
                    .ok_or("type spot without a spot object")?;
                let outer = spot.outer_cone_angle;
                if !(outer > 0.0 && outer <= std::f32::consts::PI) {
                    return Err(format!("outerConeAngle {outer} is not in (0, π]"));
                }
                if outer > std::f32::consts::FRAC_PI_2 {
                    // The spec stops at π/2; the assignment, the oracle and the shaders handle
                    // cones up to π (a spot wider than a hemisphere), so the light is kept as is.
                    self.model.warnings.push(format!(
                        "{at}: outerConeAngle {outer} is above the spec's π/2; kept as a cone \
                         wider than a hemisphere"
                    ));
                }
                let mut inner = spot.inner_cone_angle;
                // The spec wants 0 <= inner < outer. Only the outer cone bounds the light, so a
                // bad inner angle is kept usable (clamped) and reported, not fatal.
                if !(inner >= 0.0 && inner < outer) {
                    // Below the outer angle even where 0.999 of it rounds back to it (subnormal).
                    let below = if outer * 0.999 < outer {
                        outer * 0.999
                    } else {
                        0.0
                    };
                    let clamped = if inner.is_nan() {
                        0.0
                    } else {
                        inner.clamp(0.0, below)
                    };
                    self.model.warnings.push(format!(
                        "{at}: innerConeAngle {inner} is not in [0, outerConeAngle {outer}); \
                         clamped to {clamped}"
                    ));
                    inner = clamped;
                }
                PunctualKind::Spot {
                    inner_cone_angle: inner,
                    outer_cone_angle: outer,
                }
            }
            Checked::Invalid => return Err("invalid type".into()),
        };
        let range = match light.range {
            Some(r) if r > 0.0 && r.is_finite() => Some(r),
            Some(r) => return Err(format!("range {r} is not finite and > 0")),
            None => None,
        };
        let radius = range.unwrap_or_else(|| {
            radius_from_intensity(
                light.intensity * color.max_element(),
                self.options.light_cutoff,
            )
        });
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(format!(
                "no range, and its intensity gives the radius {radius} (lights nothing, or \
                 everything)"
            ));
        }
        let position = world.transform_point3(Vec3::ZERO);
        let mut record = LightRecord::point(position, radius)
            .with_color(color)
            .with_intensity(light.intensity);
        if let PunctualKind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } = kind
        {
            if direction == Vec3::ZERO {
                return Err(format!("{NO_AXIS}, so the light has no direction"));
            }
            record = record
                .with_spot(direction, outer_cone_angle)
                .with_spot_inner_angle(inner_cone_angle);
        }
        Ok(Usable::Clustered {
            record,
            kind,
            range,
        })
    }
}

/// What a valid `KHR_lights_punctual` light becomes (see `Loader::usable_light`).
enum Usable {
    /// A sun: only a direction.
    Directional { direction: Vec3, color: Vec3 },
    /// A point or spot light, ready for [`Model::lights`](crate::Model::lights) but for its
    /// `source_index`.
    Clustered {
        record: LightRecord,
        kind: PunctualKind,
        range: Option<f32>,
    },
}
