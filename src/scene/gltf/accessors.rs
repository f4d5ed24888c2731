//! Reading accessors (glTF 2.0 §3.6.2): typed, strided views into buffers, read with every
//! offset checked against the data, so a bad file is an error and never a panic.

use super::Loader;
use crate::scene::SceneError;
use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::Accessor;

/// Most elements one accessor may have: as many as a scene's primitives may reference.
const MAX_ELEMENTS: usize = 3 * crate::scene::desc::MAX_PRIMITIVES;

impl Loader<'_> {
    /// The accessor's elements as floats, `n` components each (the accessor's type must have
    /// `n` components). Normalized integers map to [0, 1] or [−1, 1] (§3.11, "Animations"
    /// and KHR_mesh_quantization use the same rule); other integers convert as they are.
    pub fn read_floats(
        &self,
        acc: &Accessor,
        what: &str,
        n: usize,
    ) -> Result<Vec<f32>, SceneError> {
        if acc.dimensions().multiplicity() != n {
            return Err(self.err(format!(
                "accessors[{}] ({what}) has type {:?}; {n} components were expected",
                acc.index(),
                acc.dimensions()
            )));
        }
        let norm = acc.normalized();
        self.read_components(acc, what, |ty, b| match (ty, norm) {
            (DataType::F32, _) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            (DataType::U32, _) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
            (DataType::U8, false) => b[0] as f32,
            (DataType::U8, true) => b[0] as f32 / 255.0,
            (DataType::I8, false) => b[0] as i8 as f32,
            (DataType::I8, true) => (b[0] as i8 as f32 / 127.0).max(-1.0),
            (DataType::U16, false) => u16::from_le_bytes([b[0], b[1]]) as f32,
            (DataType::U16, true) => u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
            (DataType::I16, false) => i16::from_le_bytes([b[0], b[1]]) as f32,
            (DataType::I16, true) => (i16::from_le_bytes([b[0], b[1]]) as f32 / 32767.0).max(-1.0),
        })
    }

    /// Vertex indices: a scalar accessor of unsigned bytes, shorts or ints (§3.7.2.1).
    pub fn read_indices(&self, acc: &Accessor, what: &str) -> Result<Vec<u32>, SceneError> {
        let ty = acc.data_type();
        if acc.dimensions() != Dimensions::Scalar
            || !matches!(ty, DataType::U8 | DataType::U16 | DataType::U32)
        {
            return Err(self.err(format!(
                "accessors[{}] ({what}) is {:?} {:?}; indices are scalar unsigned bytes, \
                 shorts or ints",
                acc.index(),
                acc.dimensions(),
                ty
            )));
        }
        self.read_components(acc, what, |ty, b| match ty {
            DataType::U8 => b[0] as u32,
            DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        })
    }

    /// Every component of every element, converted by `conv` from its little-endian bytes.
    fn read_components<T: Default + Copy>(
        &self,
        acc: &Accessor,
        what: &str,
        conv: impl Fn(DataType, &[u8]) -> T,
    ) -> Result<Vec<T>, SceneError> {
        let i = acc.index();
        if acc.sparse().is_some() {
            return Err(self.err(format!(
                "accessors[{i}] ({what}) is sparse, which mcrt does not read (in Blender, \
                 apply shape keys before exporting)"
            )));
        }
        let (count, dims) = (acc.count(), acc.dimensions().multiplicity());
        let ty = acc.data_type();
        let csize = ty.size();
        if count > MAX_ELEMENTS {
            return Err(self.err(format!(
                "accessors[{i}] ({what}) has {count} elements; mcrt reads at most {MAX_ELEMENTS}"
            )));
        }
        let total = count * dims;
        crate::check_allocation((total * std::mem::size_of::<T>()) as u64)
            .map_err(|e| self.err(format!("accessors[{i}] ({what}): {e}")))?;
        let Some(view) = acc.view() else {
            // No buffer view: all zeros (§3.6.2.3).
            return Ok(vec![T::default(); total]);
        };
        let bytes = self.view_bytes(&view)?;
        let elem = csize * dims;
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(self.err(format!(
                "bufferViews[{}] has byteStride {stride}, less than the {elem} bytes of an \
                 element of accessors[{i}]",
                view.index()
            )));
        }
        let start = acc.offset();
        let end = if count == 0 {
            Some(start)
        } else {
            (count - 1)
                .checked_mul(stride)
                .and_then(|x| x.checked_add(start))
                .and_then(|x| x.checked_add(elem))
        };
        if end.is_none_or(|e| e > bytes.len()) {
            return Err(self.err(format!(
                "accessors[{i}] ({what}) reads past the end of bufferViews[{}]: {count} \
                 elements of {elem} bytes every {stride} bytes from byte {start}, in a view of \
                 {} bytes",
                view.index(),
                bytes.len()
            )));
        }
        let mut out = Vec::with_capacity(total);
        for e in 0..count {
            let at = start + e * stride;
            for c in 0..dims {
                out.push(conv(ty, &bytes[at + c * csize..at + (c + 1) * csize]));
            }
        }
        Ok(out)
    }
}
