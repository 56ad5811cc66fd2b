//! Step 3's meshes: a primitive's accessors read with bounds checks, strips and fans turned
//! into lists, indices checked, missing normals and tangents generated.

use super::Loader;
use crate::model::{Aabb, Primitive, TangentSource};
use crate::tangents::{flat_normals, generate_tangents};
use glam::Vec3;
use gltf::json::{self, validation::Checked};

impl Loader<'_> {
    fn attribute(
        &self,
        p: &json::mesh::Primitive,
        semantic: json::mesh::Semantic,
    ) -> Option<usize> {
        p.attributes
            .get(&Checked::Valid(semantic))
            .map(|index| index.value())
    }

    /// One primitive as a triangle list, or `None` (with a warning) when it draws no triangles.
    pub(super) fn primitive(
        &mut self,
        p: &json::mesh::Primitive,
        at: &str,
    ) -> Result<Option<Primitive>, String> {
        use json::mesh::{Mode, Semantic};
        let Checked::Valid(mode) = p.mode else {
            return Err(format!("{at}: invalid mode"));
        };
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            self.model
                .warnings
                .push(format!("{at}: mode {mode:?} draws no triangles; left out"));
            return Ok(None);
        }
        let Some(position_accessor) = self.attribute(p, Semantic::Positions) else {
            self.model
                .warnings
                .push(format!("{at}: no POSITION attribute; left out"));
            return Ok(None);
        };
        fn read<T>(at: &str, what: &str, r: Result<T, String>) -> Result<T, String> {
            r.map_err(|e| format!("{at} {what}: {e}"))
        }
        let positions = read(at, "POSITION", self.data.vec3(position_accessor))?;
        let n = positions.len();
        let same_count = |what: &str, len: usize| {
            if len == n {
                Ok(())
            } else {
                Err(format!(
                    "{at}: {what} has {len} elements but POSITION has {n}"
                ))
            }
        };
        let mut normals = match self.attribute(p, Semantic::Normals) {
            Some(a) => Some(read(at, "NORMAL", self.data.vec3(a))?),
            None => None,
        };
        let mut tex_coords = match self.attribute(p, Semantic::TexCoords(0)) {
            Some(a) => read(at, "TEXCOORD_0", self.data.tex_coords(a))?,
            None => Vec::new(),
        };
        let mut tangents = match self.attribute(p, Semantic::Tangents) {
            Some(a) => read(at, "TANGENT", self.data.vec4(a))?,
            None => Vec::new(),
        };
        if let Some(normals) = &normals {
            same_count("NORMAL", normals.len())?;
        }
        if !tex_coords.is_empty() {
            same_count("TEXCOORD_0", tex_coords.len())?;
        }
        if !tangents.is_empty() {
            same_count("TANGENT", tangents.len())?;
        }
        let stream: Vec<u32> = match p.indices {
            Some(a) => read(at, "indices", self.data.indices(a.value()))?,
            None => {
                let n32 = u32::try_from(n)
                    .map_err(|_| format!("{at}: {n} vertices without indices are too many"))?;
                (0..n32).collect()
            }
        };
        if let Some((e, &bad)) = stream.iter().enumerate().find(|&(_, &i)| i as usize >= n) {
            return Err(format!(
                "{at}: index {bad} (element {e} of the indices) is out of range (POSITION has {n} vertices)"
            ));
        }
        let mut indices = match mode {
            Mode::Triangles => {
                if !stream.len().is_multiple_of(3) {
                    self.model.warnings.push(format!(
                        "{at}: {} indices are not whole triangles; the last {} dropped",
                        stream.len(),
                        stream.len() % 3
                    ));
                }
                let whole = stream.len() - stream.len() % 3;
                let mut s = stream;
                s.truncate(whole);
                s
            }
            Mode::TriangleStrip => strip_to_list(&stream),
            // Mode::TriangleFan, the only remaining triangle mode.
            _ => fan_to_list(&stream),
        };
        let mut positions = positions;
        match &mut normals {
            Some(normals) => {
                let mut fixed = 0;
                for v in normals.iter_mut() {
                    if (v.length_squared() - 1.0).abs() > 2e-3 {
                        *v = v.normalize_or(Vec3::Z);
                        fixed += 1;
                    }
                }
                if fixed > 0 {
                    self.model.warnings.push(format!(
                        "{at}: {fixed} normal(s) were not unit length and were normalised"
                    ));
                }
            }
            None => {
                // glTF: without normals, flat normals; tangents are then ignored.
                let (p, nr, t, i) = flat_normals(&positions, &tex_coords, &indices);
                positions = p;
                normals = Some(nr);
                tex_coords = t;
                indices = i;
                tangents.clear();
            }
        }
        let normals = normals.unwrap_or_default();
        let material = p.material.map(|m| m.value());
        let wants_tangents = material
            .and_then(|m| self.model.materials.get(m))
            .is_some_and(|m| m.normal_texture.is_some());
        let tangent_source = if !tangents.is_empty() {
            TangentSource::File
        } else if wants_tangents && !tex_coords.is_empty() {
            tangents = generate_tangents(&positions, &normals, &tex_coords, &indices);
            TangentSource::Generated
        } else {
            if wants_tangents {
                self.model.warnings.push(format!(
                    "{at}: the material has a normal map but the primitive has no TEXCOORD_0; no tangents"
                ));
            }
            TangentSource::None
        };
        if p.targets.as_ref().is_some_and(|t| !t.is_empty()) {
            self.model
                .warnings
                .push(format!("{at}: morph targets ignored"));
        }
        Ok(Some(Primitive {
            bounds: Aabb::from_points(positions.iter().copied()),
            positions,
            normals,
            tex_coords,
            tangents,
            tangent_source,
            indices,
            material,
        }))
    }
}

/// A triangle strip as a list. glTF: triangle `i` is `(i, i + 1 + i % 2, i + 2 − i % 2)`, so every
/// triangle keeps the first one's winding.
pub(super) fn strip_to_list(stream: &[u32]) -> Vec<u32> {
    (0..stream.len().saturating_sub(2))
        .flat_map(|i| {
            let odd = i % 2;
            [stream[i], stream[i + 1 + odd], stream[i + 2 - odd]]
        })
        .collect()
}

/// A triangle fan as a list. glTF: triangle `i` is `(i + 1, i + 2, 0)`.
pub(super) fn fan_to_list(stream: &[u32]) -> Vec<u32> {
    (0..stream.len().saturating_sub(2))
        .flat_map(|i| [stream[i + 1], stream[i + 2], stream[0]])
        .collect()
}
