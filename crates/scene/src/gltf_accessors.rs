//! Bounds-checked reads of glTF accessors into typed vectors.
//!
//! Why not the `gltf` crate's `Reader`: it trusts the file. It reads an accessor with whatever
//! element type the caller asks for (a `VEC3` of bytes read as `[f32; 3]` indexes past its slice
//! and panics), computes `count - 1` on a zero count, and indexes buffers without checking that a
//! buffer view lies inside its buffer. Here every byte range is computed with checked arithmetic
//! and checked against the data actually present, the component type and element type are
//! checked against what the attribute allows, sparse indices are checked against the count, and
//! floats must be finite. Every failure is a message naming the accessor; the loader adds the
//! file and the mesh.
//!
//! Steps of one read:
//! 1. Resolve the accessor: component type, element type (`SCALAR` … `VEC4`; matrices are never
//!    vertex data here), `normalized`, count; check them against what the caller allows.
//! 2. Copy the elements tightly packed into a scratch vector: from the buffer view (honouring
//!    `byteStride`), or zeros when the accessor has no view.
//! 3. Apply a sparse substitution, if any: `count` (index, value) pairs, indices `< count`,
//!    in file order. Indices that do not strictly increase (a spec MUST on the file) are not an
//!    error: the loader reports them once per accessor (`sparse_order_warnings`).
//! 4. Decode components (little-endian; normalised integers to [0, 1] or [−1, 1]).

use glam::{Vec2, Vec3, Vec4};
use gltf::json::{
    self,
    accessor::{ComponentType, GenericComponentType, IndexComponentType, Type},
    validation::Checked,
};

/// The largest accessor this loader reads, in bytes (1 GiB): a guard against files that declare
/// absurd counts.
const MAX_ACCESSOR_BYTES: usize = 1 << 30;

/// The data of a document's buffers, in file order.
pub(crate) struct BufferData<'a> {
    pub root: &'a json::Root,
    pub buffers: &'a [gltf::buffer::Data],
}

fn component_size(c: ComponentType) -> usize {
    match c {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

fn component_name(c: ComponentType) -> &'static str {
    match c {
        ComponentType::I8 => "BYTE",
        ComponentType::U8 => "UNSIGNED_BYTE",
        ComponentType::I16 => "SHORT",
        ComponentType::U16 => "UNSIGNED_SHORT",
        ComponentType::U32 => "UNSIGNED_INT",
        ComponentType::F32 => "FLOAT",
    }
}

fn type_components(t: Type) -> Option<usize> {
    match t {
        Type::Scalar => Some(1),
        Type::Vec2 => Some(2),
        Type::Vec3 => Some(3),
        Type::Vec4 => Some(4),
        Type::Mat2 | Type::Mat3 | Type::Mat4 => None,
    }
}

fn type_name(t: Type) -> &'static str {
    match t {
        Type::Scalar => "SCALAR",
        Type::Vec2 => "VEC2",
        Type::Vec3 => "VEC3",
        Type::Vec4 => "VEC4",
        Type::Mat2 => "MAT2",
        Type::Mat3 => "MAT3",
        Type::Mat4 => "MAT4",
    }
}

/// An accessor's elements, tightly packed, with how to decode them.
struct Packed {
    component: ComponentType,
    normalized: bool,
    components: usize,
    count: usize,
    bytes: Vec<u8>,
}

impl Packed {
    fn component(&self, element: usize, c: usize) -> &[u8] {
        let size = component_size(self.component);
        let at = (element * self.components + c) * size;
        &self.bytes[at..at + size]
    }

    /// Component `c` of element `e` as f32 (normalised integers mapped to [0, 1] / [−1, 1]).
    fn float(&self, e: usize, c: usize) -> f32 {
        let b = self.component(e, c);
        let n = self.normalized;
        match self.component {
            ComponentType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            ComponentType::U8 if n => b[0] as f32 / 255.0,
            ComponentType::U8 => b[0] as f32,
            ComponentType::I8 if n => (b[0] as i8 as f32 / 127.0).max(-1.0),
            ComponentType::I8 => b[0] as i8 as f32,
            ComponentType::U16 if n => u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
            ComponentType::U16 => u16::from_le_bytes([b[0], b[1]]) as f32,
            ComponentType::I16 if n => {
                (i16::from_le_bytes([b[0], b[1]]) as f32 / 32767.0).max(-1.0)
            }
            ComponentType::I16 => i16::from_le_bytes([b[0], b[1]]) as f32,
            ComponentType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        }
    }

    /// Component `c` of element `e` as an unsigned integer (for index data).
    fn unsigned(&self, e: usize, c: usize) -> u32 {
        let b = self.component(e, c);
        match self.component {
            ComponentType::U8 => b[0] as u32,
            ComponentType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
            ComponentType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            // Callers allow only unsigned component types for integer reads.
            _ => 0,
        }
    }
}

impl BufferData<'_> {
    /// The bytes of buffer view `view` and its stride, checked to lie inside its buffer.
    fn view(&self, view: usize) -> Result<(&[u8], Option<usize>), String> {
        let v = self
            .root
            .buffer_views
            .get(view)
            .ok_or_else(|| format!("bufferViews[{view}] does not exist"))?;
        let buffer = v.buffer.value();
        let data = &self
            .buffers
            .get(buffer)
            .ok_or_else(|| format!("bufferViews[{view}]: buffer {buffer} does not exist"))?
            .0;
        let start = v.byte_offset.map_or(0, |o| o.0);
        let range = usize::try_from(start)
            .ok()
            .zip(usize::try_from(v.byte_length.0).ok())
            .and_then(|(s, len)| Some(s..s.checked_add(len)?))
            .filter(|r| r.end <= data.len())
            .ok_or_else(|| {
                format!(
                    "bufferViews[{view}]: bytes {start}..{start}+{} lie outside buffer {buffer} \
                     ({} bytes)",
                    v.byte_length.0,
                    data.len()
                )
            })?;
        Ok((&data[range], v.byte_stride.map(|s| s.0)))
    }

    /// Checks that every buffer view lies inside its buffer (so image decoding, which indexes
    /// views directly, cannot go out of bounds).
    pub(crate) fn check_views(&self) -> Result<(), String> {
        (0..self.root.buffer_views.len()).try_for_each(|v| self.view(v).map(|_| ()))
    }

    /// Bytes of buffer view `view`, checked.
    pub(crate) fn view_bytes(&self, view: usize) -> Result<&[u8], String> {
        self.view(view).map(|(bytes, _)| bytes)
    }

    /// Steps 1–3 of the module docs.
    fn packed(
        &self,
        index: usize,
        allowed: &[(ComponentType, bool)],
        types: &[Type],
    ) -> Result<Packed, String> {
        let at = format!("accessors[{index}]");
        let a = self
            .root
            .accessors
            .get(index)
            .ok_or_else(|| format!("{at} does not exist"))?;
        let Checked::Valid(GenericComponentType(component)) = a.component_type else {
            return Err(format!("{at}: invalid componentType"));
        };
        let Checked::Valid(ty) = a.type_ else {
            return Err(format!("{at}: invalid type"));
        };
        if !types.contains(&ty) {
            let want: Vec<_> = types.iter().map(|&t| type_name(t)).collect();
            return Err(format!(
                "{at}: type {} where {} is required",
                type_name(ty),
                want.join(" or ")
            ));
        }
        if !allowed.contains(&(component, a.normalized)) {
            let want: Vec<_> = allowed
                .iter()
                .map(|&(c, n)| {
                    format!(
                        "{}{}",
                        component_name(c),
                        if n { " normalized" } else { "" }
                    )
                })
                .collect();
            return Err(format!(
                "{at}: componentType {}{} where {} is required",
                component_name(component),
                if a.normalized { " normalized" } else { "" },
                want.join(" or ")
            ));
        }
        let components = type_components(ty).ok_or_else(|| format!("{at}: matrix type"))?;
        let elem = component_size(component) * components;
        let count = usize::try_from(a.count.0)
            .ok()
            .filter(|&c| c.checked_mul(elem).is_some_and(|b| b <= MAX_ACCESSOR_BYTES))
            .ok_or_else(|| {
                format!(
                    "{at}: count {} of {elem}-byte elements is more than the {MAX_ACCESSOR_BYTES} \
                     bytes an accessor may hold",
                    a.count.0
                )
            })?;
        // Filled from the view below (after its range is checked, so a file cannot make this
        // allocate more than it holds), or zeros when the accessor has no view.
        let mut bytes = Vec::new();
        if let Some(view) = a.buffer_view {
            let (data, stride) = self.view(view.value()).map_err(|e| format!("{at}: {e}"))?;
            let stride = stride.unwrap_or(elem);
            if stride < elem {
                return Err(format!(
                    "{at}: byteStride {stride} of bufferViews[{}] is smaller than the element \
                     ({elem} bytes)",
                    view.value()
                ));
            }
            let offset = a.byte_offset.map_or(0, |o| o.0);
            if count > 0 {
                let end = usize::try_from(offset).ok().and_then(|o| {
                    o.checked_add(stride.checked_mul(count - 1)?)?
                        .checked_add(elem)
                });
                match end {
                    Some(end) if end <= data.len() => {}
                    _ => {
                        return Err(format!(
                            "{at}: {count} elements of {elem} bytes (stride {stride}) from byte \
                             {offset} do not fit in bufferViews[{}] ({} bytes)",
                            view.value(),
                            data.len()
                        ));
                    }
                }
                let offset = offset as usize; // fits: checked above
                bytes.reserve_exact(count * elem);
                for e in 0..count {
                    let from = offset + e * stride;
                    bytes.extend_from_slice(&data[from..from + elem]);
                }
            }
        } else {
            bytes.resize(count * elem, 0);
        }
        if let Some(sparse) = &a.sparse {
            let indices = self.sparse_indices(&at, sparse, count)?;
            let (data, _) = self
                .view(sparse.values.buffer_view.value())
                .map_err(|e| format!("{at}: {e}"))?;
            let (offset, len) = (sparse.values.byte_offset.0, indices.len() * elem);
            let values = usize::try_from(offset)
                .ok()
                .and_then(|o| data.get(o..o.checked_add(len)?))
                .ok_or_else(|| {
                    format!(
                        "{at}: sparse values ({len} bytes from byte {offset}) do not fit in \
                         bufferViews[{}]",
                        sparse.values.buffer_view.value()
                    )
                })?;
            // In file order: a repeated index (which the spec forbids, and
            // `sparse_order_warnings` reports) takes its last value.
            for (k, &i) in indices.iter().enumerate() {
                bytes[i * elem..(i + 1) * elem].copy_from_slice(&values[k * elem..(k + 1) * elem]);
            }
        }
        Ok(Packed {
            component,
            normalized: a.normalized,
            components,
            count,
            bytes,
        })
    }

    /// Step 3's indices: the `sparse.count` indices of an accessor of `count` elements, each
    /// checked to be `< count`; `at` names the accessor in errors.
    fn sparse_indices(
        &self,
        at: &str,
        sparse: &json::accessor::sparse::Sparse,
        count: usize,
    ) -> Result<Vec<usize>, String> {
        let n = usize::try_from(sparse.count.0).unwrap_or(usize::MAX);
        if n > count {
            return Err(format!(
                "{at}: sparse count {} exceeds the accessor's count {count}",
                sparse.count.0
            ));
        }
        let Checked::Valid(IndexComponentType(index_type)) = sparse.indices.component_type else {
            return Err(format!("{at}: invalid sparse.indices.componentType"));
        };
        let size = component_size(index_type);
        let view = sparse.indices.buffer_view.value();
        let (data, _) = self.view(view).map_err(|e| format!("{at}: {e}"))?;
        let (offset, len) = (sparse.indices.byte_offset.0, n * size);
        let bytes = usize::try_from(offset)
            .ok()
            .and_then(|o| data.get(o..o.checked_add(len)?))
            .ok_or_else(|| {
                format!(
                    "{at}: sparse indices ({len} bytes from byte {offset}) do not fit in \
                     bufferViews[{view}]"
                )
            })?;
        bytes
            .chunks_exact(size)
            .map(|b| {
                let i = match index_type {
                    ComponentType::U8 => b[0] as usize,
                    ComponentType::U16 => u16::from_le_bytes([b[0], b[1]]) as usize,
                    _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
                };
                if i < count {
                    Ok(i)
                } else {
                    Err(format!(
                        "{at}: sparse index {i} is out of range (count {count})"
                    ))
                }
            })
            .collect()
    }

    /// One warning per accessor whose sparse indices do not strictly increase, which the glTF
    /// spec requires of a file. The model is still well defined (the substitutions are applied
    /// in file order, so a repeated index takes its last value, as readers that do not check
    /// do), so this is reported, not fatal. An accessor whose sparse data cannot be read at all
    /// is left to the read that uses it, which makes that an error.
    pub(crate) fn sparse_order_warnings(&self) -> Vec<String> {
        let accessors = self.root.accessors.iter().enumerate();
        accessors
            .filter_map(|(a, accessor)| {
                let sparse = accessor.sparse.as_ref()?;
                let count = usize::try_from(accessor.count.0).ok()?;
                let at = format!("accessors[{a}]");
                let indices = self.sparse_indices(&at, sparse, count).ok()?;
                let k = indices.windows(2).position(|w| w[0] >= w[1])?;
                Some(format!(
                    "{at}: sparse indices must strictly increase, but element {} is {} after {}; \
                     applied in file order (a repeated index takes its last value)",
                    k + 1,
                    indices[k + 1],
                    indices[k]
                ))
            })
            .collect()
    }

    /// Floats with `N` components per element, each finite.
    fn floats<const N: usize>(
        &self,
        index: usize,
        allowed: &[(ComponentType, bool)],
        ty: Type,
    ) -> Result<Vec<[f32; N]>, String> {
        let p = self.packed(index, allowed, &[ty])?;
        debug_assert_eq!(p.components, N);
        let mut out = Vec::with_capacity(p.count);
        for e in 0..p.count {
            let v: [f32; N] = std::array::from_fn(|c| p.float(e, c));
            if let Some(bad) = v.iter().find(|x| !x.is_finite()) {
                return Err(format!(
                    "accessors[{index}]: element {e} has the non-finite value {bad}"
                ));
            }
            out.push(v);
        }
        Ok(out)
    }

    /// A `VEC3` of floats (positions, normals).
    pub(crate) fn vec3(&self, index: usize) -> Result<Vec<Vec3>, String> {
        let v = self.floats::<3>(index, &[(ComponentType::F32, false)], Type::Vec3)?;
        Ok(v.into_iter().map(Vec3::from_array).collect())
    }

    /// A `VEC4` of floats (tangents).
    pub(crate) fn vec4(&self, index: usize) -> Result<Vec<Vec4>, String> {
        let v = self.floats::<4>(index, &[(ComponentType::F32, false)], Type::Vec4)?;
        Ok(v.into_iter().map(Vec4::from_array).collect())
    }

    /// A `VEC2` of floats or normalised unsigned bytes/shorts (texture coordinates).
    pub(crate) fn tex_coords(&self, index: usize) -> Result<Vec<Vec2>, String> {
        let allowed = [
            (ComponentType::F32, false),
            (ComponentType::U8, true),
            (ComponentType::U16, true),
        ];
        let v = self.floats::<2>(index, &allowed, Type::Vec2)?;
        Ok(v.into_iter().map(Vec2::from_array).collect())
    }

    /// A `SCALAR` of unsigned bytes, shorts or ints (vertex indices).
    pub(crate) fn indices(&self, index: usize) -> Result<Vec<u32>, String> {
        let allowed = [
            (ComponentType::U8, false),
            (ComponentType::U16, false),
            (ComponentType::U32, false),
        ];
        let p = self.packed(index, &allowed, &[Type::Scalar])?;
        Ok((0..p.count).map(|e| p.unsigned(e, 0)).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A document with one buffer of `bytes` and the given views and accessors (JSON text).
    pub(super) fn root(bytes: usize, views: &str, accessors: &str) -> json::Root {
        let text = format!(
            r#"{{"asset": {{"version": "2.0"}},
                "buffers": [{{"byteLength": {bytes}}}],
                "bufferViews": [{views}],
                "accessors": [{accessors}]}}"#
        );
        json::deserialize::from_str(&text).unwrap()
    }

    fn f32_bytes(values: &[f32]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    #[test]
    fn reads_strided_floats_and_applies_sparse_values() {
        // Two VEC3 with a 16-byte stride, then sparse: index 1 replaced.
        let mut data = f32_bytes(&[1.0, 2.0, 3.0, 9.0, 4.0, 5.0, 6.0, 9.0]);
        data.extend_from_slice(&[1, 0]); // sparse index 1 (u16)
        data.extend_from_slice(&[0, 0]); // padding
        data.extend(f32_bytes(&[7.0, 8.0, 9.0]));
        let r = root(
            data.len(),
            r#"{"buffer": 0, "byteLength": 32, "byteStride": 16},
               {"buffer": 0, "byteOffset": 32, "byteLength": 2},
               {"buffer": 0, "byteOffset": 36, "byteLength": 12}"#,
            r#"{"bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC3"},
               {"bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC3",
                "sparse": {"count": 1, "indices": {"bufferView": 1, "componentType": 5123},
                           "values": {"bufferView": 2}}}"#,
        );
        let buffers = [gltf::buffer::Data(data)];
        let b = BufferData {
            root: &r,
            buffers: &buffers,
        };
        assert_eq!(
            b.vec3(0).unwrap(),
            [Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0)]
        );
        assert_eq!(
            b.vec3(1).unwrap(),
            [Vec3::new(1.0, 2.0, 3.0), Vec3::new(7.0, 8.0, 9.0)]
        );
        assert!(b.check_views().is_ok());
    }

    /// An accessor whose last strided element ends exactly at its view's end is read whole; an
    /// accessor without a view is `count` zero elements, which its sparse substitutions (here
    /// with u8 indices) overwrite; `view_bytes` is a view's own bytes; and `check_views` names
    /// a view that lies outside its buffer even when no accessor reads it.
    #[test]
    fn exact_fits_zero_filled_sparse_and_view_checks() {
        // View 0: two VEC3 16 bytes apart, 28 bytes (the second ends at the view's end).
        let mut data = f32_bytes(&[1.0, 2.0, 3.0, 0.0, 4.0, 5.0, 6.0]);
        data.extend_from_slice(&[1, 3, 0, 0]); // view 1: sparse indices 1 and 3 (u8), padding
        data.extend(f32_bytes(&[7.0, 8.0, 9.0, 10.0, 11.0, 12.0])); // view 2: their values
        let views = r#"{"buffer": 0, "byteLength": 28, "byteStride": 16},
                       {"buffer": 0, "byteOffset": 28, "byteLength": 2},
                       {"buffer": 0, "byteOffset": 32, "byteLength": 24}"#;
        let accessors = r#"{"bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC3"},
            {"componentType": 5126, "count": 4, "type": "VEC3",
             "sparse": {"count": 2, "indices": {"bufferView": 1, "componentType": 5121},
                        "values": {"bufferView": 2}}}"#;
        let r = root(data.len(), views, accessors);
        let buffers = [gltf::buffer::Data(data.clone())];
        let b = BufferData {
            root: &r,
            buffers: &buffers,
        };
        assert_eq!(
            b.vec3(0).unwrap(),
            [Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0)]
        );
        assert_eq!(
            b.vec3(1).unwrap(),
            [
                Vec3::ZERO,
                Vec3::new(7.0, 8.0, 9.0),
                Vec3::ZERO,
                Vec3::new(10.0, 11.0, 12.0)
            ]
        );
        assert_eq!(b.view_bytes(1).unwrap(), &data[28..30]);
        assert_eq!(b.view_bytes(2).unwrap(), &data[32..56]);
        assert!(b.check_views().is_ok());
        // A fourth view past the buffer's end, read by no accessor.
        let beyond = format!(r#"{views}, {{"buffer": 0, "byteOffset": 40, "byteLength": 17}}"#);
        let r = root(data.len(), &beyond, accessors);
        let b = BufferData {
            root: &r,
            buffers: &buffers,
        };
        let e = b.check_views().unwrap_err();
        assert!(
            e.starts_with("bufferViews[3]") && e.contains("outside buffer 0"),
            "{e}"
        );
        assert!(
            b.vec3(1).is_ok(),
            "the accessors do not read the broken view"
        );
    }

    /// Normalised u8 and u16 texture coordinates, and u8 and u32 indices, read the same values.
    #[test]
    fn normalized_tex_coords_and_indices_of_each_width() {
        let mut wide = Vec::new();
        for x in [0u16, 65535, 65535, 0] {
            wide.extend_from_slice(&x.to_le_bytes());
        }
        for i in [2u32, 1, 0] {
            wide.extend_from_slice(&i.to_le_bytes());
        }
        let cases = [
            (
                vec![0u8, 255, 255, 0, 2, 1, 0, 0],
                r#"{"buffer": 0, "byteLength": 4}, {"buffer": 0, "byteOffset": 4, "byteLength": 3}"#,
                r#"{"bufferView": 0, "componentType": 5121, "normalized": true, "count": 2, "type": "VEC2"},
                   {"bufferView": 1, "componentType": 5121, "count": 3, "type": "SCALAR"}"#,
            ),
            (
                wide,
                r#"{"buffer": 0, "byteLength": 8}, {"buffer": 0, "byteOffset": 8, "byteLength": 12}"#,
                r#"{"bufferView": 0, "componentType": 5123, "normalized": true, "count": 2, "type": "VEC2"},
                   {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}"#,
            ),
        ];
        for (data, views, accessors) in cases {
            let r = root(data.len(), views, accessors);
            let buffers = [gltf::buffer::Data(data)];
            let b = BufferData {
                root: &r,
                buffers: &buffers,
            };
            assert_eq!(b.tex_coords(0).unwrap(), [Vec2::Y, Vec2::X], "{accessors}");
            assert_eq!(b.indices(1).unwrap(), [2, 1, 0], "{accessors}");
        }
    }

    #[test]
    fn broken_accessors_are_errors_not_panics() {
        let data = f32_bytes(&[1.0, f32::INFINITY, 3.0, 0.0]);
        let cases = [
            // Wrong element type for positions.
            (
                r#"{"bufferView": 0, "componentType": 5126, "count": 1, "type": "VEC2"}"#,
                "type VEC2 where VEC3 is required",
            ),
            // Bytes read as floats.
            (
                r#"{"bufferView": 0, "componentType": 5121, "count": 4, "type": "VEC3"}"#,
                "componentType UNSIGNED_BYTE where FLOAT is required",
            ),
            // Past the end of the view.
            (
                r#"{"bufferView": 0, "byteOffset": 8, "componentType": 5126, "count": 1, "type": "VEC3"}"#,
                "do not fit in bufferViews[0]",
            ),
            // One byte past the end (a bound one byte loose read past the view: audit).
            (
                r#"{"bufferView": 0, "byteOffset": 5, "componentType": 5126, "count": 1, "type": "VEC3"}"#,
                "1 elements of 12 bytes (stride 12) from byte 5 do not fit in bufferViews[0] (16 bytes)",
            ),
            // Absurd count.
            (
                r#"{"bufferView": 0, "componentType": 5126, "count": 18446744073709551615, "type": "VEC3"}"#,
                "of 12-byte elements is more than the 1073741824 bytes an accessor may hold",
            ),
            // Infinity in the data.
            (
                r#"{"bufferView": 0, "componentType": 5126, "count": 1, "type": "VEC3"}"#,
                "non-finite value inf",
            ),
            // View beyond the buffer.
            (
                r#"{"bufferView": 1, "componentType": 5126, "count": 1, "type": "VEC3"}"#,
                "lie outside buffer 0",
            ),
            // One sparse element more than the accessor has.
            (
                r#"{"componentType": 5126, "count": 1, "type": "VEC3",
                    "sparse": {"count": 2, "indices": {"bufferView": 0, "componentType": 5125},
                               "values": {"bufferView": 0}}}"#,
                "sparse count 2 exceeds the accessor's count 1",
            ),
            // Sparse index out of range.
            (
                r#"{"componentType": 5126, "count": 1, "type": "VEC3",
                    "sparse": {"count": 1, "indices": {"bufferView": 0, "componentType": 5125},
                               "values": {"bufferView": 0}}}"#,
                "sparse index 1065353216 is out of range",
            ),
        ];
        for (accessor, expected) in cases {
            let r = root(
                16,
                r#"{"buffer": 0, "byteLength": 16}, {"buffer": 0, "byteOffset": 8, "byteLength": 12}"#,
                accessor,
            );
            let buffers = [gltf::buffer::Data(data.clone())];
            let b = BufferData {
                root: &r,
                buffers: &buffers,
            };
            let e = b.vec3(0).unwrap_err();
            assert!(e.contains(expected), "{accessor}: {e}");
            assert!(e.starts_with("accessors[0]"), "{e}");
        }
    }
}

#[cfg(test)]
mod boundary_tests {
    //! The reader's bounds at their edges (mutation audit: a zero count with a view, a sparse
    //! index equal to the count and a stride under the element size went untested).

    use super::tests::root;
    use super::*;

    fn read_vec3(data: Vec<u8>, views: &str, accessors: &str) -> Result<Vec<Vec3>, String> {
        let r = root(data.len(), views, accessors);
        let buffers = [gltf::buffer::Data(data)];
        BufferData {
            root: &r,
            buffers: &buffers,
        }
        .vec3(0)
    }

    /// The module docs: the `gltf` crate "computes `count - 1` on a zero count"; this reader
    /// must not. A zero-count accessor with a view is empty, not a panic or an error.
    #[test]
    fn zero_count_accessor_with_a_view_is_empty() {
        let v = read_vec3(
            vec![0; 12],
            r#"{"buffer": 0, "byteLength": 12}"#,
            r#"{"bufferView": 0, "componentType": 5126, "count": 0, "type": "VEC3"}"#,
        );
        assert_eq!(v, Ok(vec![]));
    }

    /// A sparse index equal to the count is one past the last element: an error, not a write
    /// past the end.
    #[test]
    fn sparse_index_equal_to_count_is_out_of_range() {
        // View 0: sparse index 2 (u8) + padding; view 1: one VEC3 value.
        let mut data = vec![2u8, 0, 0, 0];
        data.extend([7.0f32, 8.0, 9.0].iter().flat_map(|v| v.to_le_bytes()));
        let r = std::panic::catch_unwind(|| {
            read_vec3(
                data,
                r#"{"buffer": 0, "byteLength": 1}, {"buffer": 0, "byteOffset": 4, "byteLength": 12}"#,
                r#"{"componentType": 5126, "count": 2, "type": "VEC3",
                    "sparse": {"count": 1, "indices": {"bufferView": 0, "componentType": 5121},
                               "values": {"bufferView": 1}}}"#,
            )
        })
        .expect("no panic");
        let e = r.unwrap_err();
        assert!(
            e.contains("sparse index 2 is out of range (count 2)"),
            "{e}"
        );
    }

    /// A byteStride smaller than the element would read overlapping elements: refused.
    #[test]
    fn stride_smaller_than_the_element_is_an_error() {
        let data: Vec<u8> = (0..9).flat_map(|i| (i as f32).to_le_bytes()).collect();
        let e = read_vec3(
            data,
            r#"{"buffer": 0, "byteLength": 36, "byteStride": 4}"#,
            r#"{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}"#,
        )
        .unwrap_err();
        assert!(
            e.contains("byteStride 4 of bufferViews[0] is smaller than the element (12 bytes)"),
            "{e}"
        );
    }
}
