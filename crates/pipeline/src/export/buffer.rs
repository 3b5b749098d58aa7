//! The binary buffer of a glTF export: typed arrays appended with 4-byte alignment, each one buffer
//! view with one accessor, and the accessor bounds (`min`/`max`) glTF requires or validators check.

use gltf_json as json;
use json::accessor::{ComponentType, GenericComponentType, Type};
use json::buffer::Target;
use json::validation::{Checked::Valid, USize64};
use json::Index;

/// The bytes of buffer 0 and the views and accessors already pushed into a document.
#[derive(Debug, Default)]
pub struct Bin {
    /// Every view's bytes, each view starting on a 4-byte boundary.
    pub bytes: Vec<u8>,
}

/// What a vertex or index array is bound to (the view's `target`), or nothing (animation data,
/// inverse bind matrices, images).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Use {
    /// Vertex attributes.
    Vertices,
    /// Triangle indices.
    Indices,
    /// Anything else.
    Other,
}

fn components(ty: Type) -> usize {
    match ty {
        Type::Scalar => 1,
        Type::Vec2 => 2,
        Type::Vec3 => 3,
        Type::Vec4 | Type::Mat2 => 4,
        Type::Mat3 => 9,
        Type::Mat4 => 16,
    }
}

impl Bin {
    /// Appends `data` as a new buffer view of buffer 0 and returns it.
    pub fn view(
        &mut self,
        root: &mut json::Root,
        data: &[u8],
        usage: Use,
    ) -> Index<json::buffer::View> {
        while self.bytes.len() % 4 != 0 {
            self.bytes.push(0);
        }
        let offset = self.bytes.len();
        self.bytes.extend_from_slice(data);
        root.push(json::buffer::View {
            buffer: Index::new(0),
            byte_length: USize64(data.len() as u64),
            byte_offset: Some(USize64(offset as u64)),
            byte_stride: None,
            name: None,
            target: match usage {
                Use::Vertices => Some(Valid(Target::ArrayBuffer)),
                Use::Indices => Some(Valid(Target::ElementArrayBuffer)),
                Use::Other => None,
            },
            extensions: None,
            extras: Default::default(),
        })
    }

    /// An accessor over `values` (f32, `ty` components each). With `bounds`, `min` and `max` per
    /// component are written (required for positions and animation inputs).
    pub fn floats(
        &mut self,
        root: &mut json::Root,
        values: &[f32],
        ty: Type,
        usage: Use,
        bounds: bool,
    ) -> Index<json::Accessor> {
        let k = components(ty);
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(root, &bytes, usage);
        let (min, max) = if bounds && !values.is_empty() {
            let mut lo = vec![f32::INFINITY; k];
            let mut hi = vec![f32::NEG_INFINITY; k];
            for c in values.chunks_exact(k) {
                for (i, &v) in c.iter().enumerate() {
                    lo[i] = lo[i].min(v);
                    hi[i] = hi[i].max(v);
                }
            }
            (Some(number_array(&lo)), Some(number_array(&hi)))
        } else {
            (None, None)
        };
        root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64((values.len() / k) as u64),
            component_type: Valid(GenericComponentType(ComponentType::F32)),
            extensions: None,
            extras: Default::default(),
            type_: Valid(ty),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    /// A VEC4 accessor of unsigned shorts (skin joint indices).
    pub fn joints(&mut self, root: &mut json::Root, joints: &[[u16; 4]]) -> Index<json::Accessor> {
        let bytes: Vec<u8> = joints
            .iter()
            .flat_map(|j| j.iter().flat_map(|v| v.to_le_bytes()))
            .collect();
        let view = self.view(root, &bytes, Use::Vertices);
        root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64(joints.len() as u64),
            component_type: Valid(GenericComponentType(ComponentType::U16)),
            extensions: None,
            extras: Default::default(),
            type_: Valid(Type::Vec4),
            min: None,
            max: None,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    /// A SCALAR accessor of triangle indices: unsigned shorts when every index fits, else unsigned ints.
    pub fn indices(&mut self, root: &mut json::Root, indices: &[u32]) -> Index<json::Accessor> {
        let small = indices.iter().all(|&i| i < u32::from(u16::MAX));
        let (bytes, ct): (Vec<u8>, _) = if small {
            (
                indices
                    .iter()
                    .flat_map(|&i| (i as u16).to_le_bytes())
                    .collect(),
                ComponentType::U16,
            )
        } else {
            (
                indices.iter().flat_map(|i| i.to_le_bytes()).collect(),
                ComponentType::U32,
            )
        };
        let view = self.view(root, &bytes, Use::Indices);
        root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64(indices.len() as u64),
            component_type: Valid(GenericComponentType(ct)),
            extensions: None,
            extras: Default::default(),
            type_: Valid(Type::Scalar),
            min: None,
            max: None,
            name: None,
            normalized: false,
            sparse: None,
        })
    }
}

/// A JSON array of the exact values of `v` (each f32 widened to f64 without rounding).
fn number_array(v: &[f32]) -> json::Value {
    json::Value::Array(v.iter().map(|&x| json::Value::from(f64::from(x))).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_are_aligned_and_bounds_exact() {
        let mut root = json::Root::default();
        let mut bin = Bin::default();
        bin.indices(&mut root, &[0, 1, 2]);
        assert_eq!(bin.bytes.len(), 6);
        let a = bin.floats(
            &mut root,
            &[1.0, -2.0, 0.1, 3.0, 5.0, -0.5],
            Type::Vec3,
            Use::Vertices,
            true,
        );
        assert_eq!(root.buffer_views[1].byte_offset, Some(USize64(8)));
        assert_eq!(bin.bytes.len(), 8 + 24);
        let acc = &root.accessors[a.value()];
        assert_eq!(acc.count, USize64(2));
        assert_eq!(
            acc.min,
            Some(serde_json::json!([1.0, -2.0, f64::from(-0.5f32)]))
        );
        assert_eq!(
            acc.max,
            Some(serde_json::json!([3.0, 5.0, f64::from(0.1f32)]))
        );
    }

    #[test]
    fn large_indices_use_u32() {
        let mut root = json::Root::default();
        let mut bin = Bin::default();
        bin.indices(&mut root, &[0, 70_000, 2]);
        assert_eq!(bin.bytes.len(), 12);
        let acc = serde_json::to_value(&root.accessors[0]).expect("json");
        assert_eq!(acc["componentType"], 5125);
    }
}
