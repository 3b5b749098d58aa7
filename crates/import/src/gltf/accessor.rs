//! A bounds-checked reader for glTF accessors (dense, strided, normalized, sparse).
//!
//! The gltf crate's own readers can panic on malformed files, so every byte range here is checked with
//! checked arithmetic against the bytes actually present before anything is allocated.

use gltf::accessor::{DataType, Dimensions};

/// Most elements an accessor without a bufferView (implicit zeros, possibly sparse) may declare.
pub const MAX_IMPLICIT_ELEMENTS: usize = 1 << 24;

/// Why an accessor could not be read; the caller adds file and JSON path.
pub type ReadResult<T> = Result<T, String>;

/// Bytes of one component.
pub fn component_size(t: DataType) -> usize {
    match t {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

/// Components per element.
pub fn component_count(d: Dimensions) -> usize {
    match d {
        Dimensions::Scalar => 1,
        Dimensions::Vec2 => 2,
        Dimensions::Vec3 => 3,
        Dimensions::Vec4 | Dimensions::Mat2 => 4,
        Dimensions::Mat3 => 9,
        Dimensions::Mat4 => 16,
    }
}

/// Byte layout of one element: (rows per column, columns, column stride, element size).
fn layout(t: DataType, d: Dimensions) -> (usize, usize, usize, usize) {
    let cs = component_size(t);
    let (rows, cols) = match d {
        Dimensions::Mat2 => (2, 2),
        Dimensions::Mat3 => (3, 3),
        Dimensions::Mat4 => (4, 4),
        other => (component_count(other), 1),
    };
    let col_bytes = rows * cs;
    // Matrix columns start on 4-byte boundaries (glTF 2.0 3.6.2.4).
    let col_stride = if cols > 1 {
        col_bytes.div_ceil(4) * 4
    } else {
        col_bytes
    };
    (rows, cols, col_stride, col_stride * cols)
}

/// One component as a float; `normalized` maps integers to [0, 1] or [-1, 1] as glTF defines.
fn component(t: DataType, normalized: bool, b: &[u8]) -> f32 {
    match t {
        DataType::I8 => {
            let v = b[0] as i8 as f32;
            if normalized {
                (v / 127.0).max(-1.0)
            } else {
                v
            }
        }
        DataType::U8 => {
            let v = b[0] as f32;
            if normalized {
                v / 255.0
            } else {
                v
            }
        }
        DataType::I16 => {
            let v = i16::from_le_bytes([b[0], b[1]]) as f32;
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        DataType::U16 => {
            let v = u16::from_le_bytes([b[0], b[1]]) as f32;
            if normalized {
                v / 65535.0
            } else {
                v
            }
        }
        DataType::U32 => {
            let v = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            if normalized {
                (v as f64 / u32::MAX as f64) as f32
            } else {
                v as f32
            }
        }
        DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

/// One component as an unsigned integer (indices, joint indices); `None` for floats and negatives.
fn component_u32(t: DataType, b: &[u8]) -> Option<u32> {
    match t {
        DataType::U8 => Some(b[0] as u32),
        DataType::U16 => Some(u16::from_le_bytes([b[0], b[1]]) as u32),
        DataType::U32 => Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        DataType::I8 | DataType::I16 | DataType::F32 => None,
    }
}

/// The bytes of a buffer view, checked against the buffer data present.
fn view_bytes<'b>(view: &gltf::buffer::View<'_>, buffers: &'b [Vec<u8>]) -> ReadResult<&'b [u8]> {
    let buffer = view.buffer();
    let data = buffers
        .get(buffer.index())
        .ok_or_else(|| format!("buffer {} was not loaded", buffer.index()))?;
    let start = view.offset();
    let end = start
        .checked_add(view.length())
        .ok_or("bufferView byteOffset + byteLength overflows")?;
    data.get(start..end).ok_or_else(|| {
        format!(
            "bufferView {} spans bytes {start}..{end} of buffer {}, which holds {} bytes",
            view.index(),
            buffer.index(),
            data.len()
        )
    })
}

/// A raw accessor: component type, components per element, and one element's bytes at a time.
struct Elements<'b> {
    data_type: DataType,
    rows: usize,
    cols: usize,
    col_stride: usize,
    /// Source bytes and stride; `None` for an accessor without a bufferView (all zeros).
    source: Option<(&'b [u8], usize)>,
    count: usize,
}

/// Resolves the dense part of an accessor and checks its byte range before anything is allocated.
fn elements<'b>(acc: &gltf::Accessor<'_>, buffers: &'b [Vec<u8>]) -> ReadResult<Elements<'b>> {
    let data_type = acc.data_type();
    let (rows, cols, col_stride, elem) = layout(data_type, acc.dimensions());
    let count = acc.count();
    let source = match acc.view() {
        None => {
            if count > MAX_IMPLICIT_ELEMENTS {
                return Err(format!(
                    "count {count} without a bufferView exceeds the limit of {MAX_IMPLICIT_ELEMENTS} elements"
                ));
            }
            None
        }
        Some(view) => {
            let bytes = view_bytes(&view, buffers)?;
            let stride = view.stride().unwrap_or(elem);
            if stride < elem {
                return Err(format!(
                    "byteStride {stride} is smaller than the element size {elem}"
                ));
            }
            let offset = acc.offset();
            if count > 0 {
                let need = (count - 1)
                    .checked_mul(stride)
                    .and_then(|x| x.checked_add(elem))
                    .and_then(|x| x.checked_add(offset))
                    .ok_or("accessor byte range overflows")?;
                if need > bytes.len() {
                    return Err(format!(
                        "count {count} (stride {stride}, byteOffset {offset}) needs {need} bytes; bufferView {} holds {}",
                        view.index(),
                        bytes.len()
                    ));
                }
            }
            let slice = bytes.get(offset.min(bytes.len())..).unwrap_or(&[]);
            Some((slice, stride))
        }
    };
    Ok(Elements {
        data_type,
        rows,
        cols,
        col_stride,
        source,
        count,
    })
}

impl Elements<'_> {
    fn comps(&self) -> usize {
        self.rows * self.cols
    }
    /// Calls `f(component_bytes)` for every component of element `i` from `bytes` (one element).
    fn each_component(&self, bytes: &[u8], mut f: impl FnMut(&[u8])) {
        let cs = component_size(self.data_type);
        for c in 0..self.cols {
            for r in 0..self.rows {
                let o = c * self.col_stride + r * cs;
                f(&bytes[o..o + cs]);
            }
        }
    }
}

/// Reads a sparse block: (indices, value bytes, element size), checked against the bytes present.
fn sparse_parts<'b>(
    acc: &gltf::Accessor<'_>,
    buffers: &'b [Vec<u8>],
    elem: usize,
) -> ReadResult<Option<(Vec<usize>, &'b [u8])>> {
    let Some(sparse) = acc.sparse() else {
        return Ok(None);
    };
    let n = sparse.count();
    if n > acc.count() {
        return Err(format!(
            "sparse count {n} is larger than the accessor count {}",
            acc.count()
        ));
    }
    let idx = sparse.indices();
    let isz = match idx.index_type() {
        gltf::accessor::sparse::IndexType::U8 => 1,
        gltf::accessor::sparse::IndexType::U16 => 2,
        gltf::accessor::sparse::IndexType::U32 => 4,
    };
    let ibytes = view_bytes(&idx.view(), buffers)?;
    let ineed = n
        .checked_mul(isz)
        .and_then(|x| x.checked_add(idx.offset()))
        .ok_or("sparse indices byte range overflows")?;
    if ineed > ibytes.len() {
        return Err(format!(
            "sparse count {n} needs {ineed} bytes of indices; bufferView {} holds {}",
            idx.view().index(),
            ibytes.len()
        ));
    }
    let vals = sparse.values();
    let vbytes = view_bytes(&vals.view(), buffers)?;
    let vneed = n
        .checked_mul(elem)
        .and_then(|x| x.checked_add(vals.offset()))
        .ok_or("sparse values byte range overflows")?;
    if vneed > vbytes.len() {
        return Err(format!(
            "sparse count {n} needs {vneed} bytes of values; bufferView {} holds {}",
            vals.view().index(),
            vbytes.len()
        ));
    }
    let ib = &ibytes[idx.offset()..ineed];
    let mut indices = Vec::with_capacity(n);
    for k in 0..n {
        let b = &ib[k * isz..k * isz + isz];
        let i = match isz {
            1 => b[0] as usize,
            2 => u16::from_le_bytes([b[0], b[1]]) as usize,
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
        };
        if i >= acc.count() {
            return Err(format!(
                "sparse index {i} (entry {k}) is out of range for count {}",
                acc.count()
            ));
        }
        indices.push(i);
    }
    Ok(Some((indices, &vbytes[vals.offset()..vneed])))
}

/// Reads any accessor as floats, `count * components` long; integers are converted (and normalized
/// when the accessor says so). Sparse substitutions are applied.
pub fn read_f32(acc: &gltf::Accessor<'_>, buffers: &[Vec<u8>]) -> ReadResult<Vec<f32>> {
    let e = elements(acc, buffers)?;
    let normalized = acc.normalized();
    let comps = e.comps();
    let total = e
        .count
        .checked_mul(comps)
        .ok_or("accessor size overflows")?;
    let mut out = Vec::with_capacity(total);
    match e.source {
        None => out.resize(total, 0.0),
        // Float vectors and scalars (key times, positions, rotations: nearly every accessor) in
        // one pass over the bytes; `elements` checked the range.
        Some((bytes, stride)) if e.data_type == DataType::F32 && e.cols == 1 => {
            let elem = e.rows * 4;
            let float = |c: &[u8]| f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            if stride == elem {
                out.extend(bytes[..e.count * elem].chunks_exact(4).map(float));
            } else {
                for i in 0..e.count {
                    let el = &bytes[i * stride..i * stride + elem];
                    out.extend(el.chunks_exact(4).map(float));
                }
            }
        }
        Some((bytes, stride)) => {
            for i in 0..e.count {
                let el = &bytes[i * stride..];
                e.each_component(el, |b| out.push(component(e.data_type, normalized, b)));
            }
        }
    }
    let (_, _, _, elem) = layout(e.data_type, acc.dimensions());
    if let Some((indices, values)) = sparse_parts(acc, buffers, elem)? {
        for (k, &i) in indices.iter().enumerate() {
            let el = &values[k * elem..(k + 1) * elem];
            let mut c = 0;
            e.each_component(el, |b| {
                out[i * comps + c] = component(e.data_type, normalized, b);
                c += 1;
            });
        }
    }
    Ok(out)
}

/// Reads an unsigned-integer accessor (indices, joint indices) as `u32`, `count * components` long.
pub fn read_u32(acc: &gltf::Accessor<'_>, buffers: &[Vec<u8>]) -> ReadResult<Vec<u32>> {
    let e = elements(acc, buffers)?;
    if acc.normalized() || component_u32(e.data_type, &[0, 0, 0, 0]).is_none() {
        return Err(format!(
            "component type {:?}{} where an unsigned integer type is required",
            e.data_type,
            if acc.normalized() {
                " (normalized)"
            } else {
                ""
            }
        ));
    }
    let comps = e.comps();
    let total = e
        .count
        .checked_mul(comps)
        .ok_or("accessor size overflows")?;
    let mut out = Vec::with_capacity(total);
    match e.source {
        None => out.resize(total, 0),
        Some((bytes, stride)) => {
            for i in 0..e.count {
                let el = &bytes[i * stride..];
                e.each_component(el, |b| out.push(component_u32(e.data_type, b).unwrap_or(0)));
            }
        }
    }
    let (_, _, _, elem) = layout(e.data_type, acc.dimensions());
    if let Some((indices, values)) = sparse_parts(acc, buffers, elem)? {
        for (k, &i) in indices.iter().enumerate() {
            let el = &values[k * elem..(k + 1) * elem];
            let mut c = 0;
            e.each_component(el, |b| {
                out[i * comps + c] = component_u32(e.data_type, b).unwrap_or(0);
                c += 1;
            });
        }
    }
    Ok(out)
}
