//! Vertex-cache files: PC2, MDD and EXR vertex-animation textures, written and read back.
//!
//! A cache is a block of frames, each holding one position (and for VAT optionally one normal) per
//! vertex, in a vertex order the caller chose. Writers produce bytes (the caller writes them atomically);
//! readers take untrusted bytes and check every count against the bytes present.

mod exr_header;
pub mod mdd;
pub mod pc2;
pub mod vat;

use sinew_core::glam::Vec3;

/// Baked frames: `positions[frame * vertex_count + vertex]`, likewise `normals` (may be empty).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Frames {
    /// Vertices per frame.
    pub vertex_count: usize,
    /// Number of frames.
    pub frame_count: usize,
    /// Frames per second.
    pub fps: f32,
    /// Frame-major positions.
    pub positions: Vec<Vec3>,
    /// Frame-major unit normals, or empty.
    pub normals: Vec<Vec3>,
}

impl Frames {
    /// The positions of one frame.
    pub fn frame(&self, f: usize) -> &[Vec3] {
        &self.positions[f * self.vertex_count..(f + 1) * self.vertex_count]
    }
}

/// A cache file that cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{format} {section} at byte {offset}: {message}")]
pub struct CacheError {
    /// `pc2`, `mdd` or `exr`.
    pub format: &'static str,
    /// Header, frames, layer...
    pub section: &'static str,
    /// Byte offset where the problem is.
    pub offset: u64,
    /// What is wrong.
    pub message: String,
}

pub(crate) fn cache_error(
    format: &'static str,
    section: &'static str,
    offset: u64,
    message: impl Into<String>,
) -> CacheError {
    CacheError {
        format,
        section,
        offset,
        message: message.into(),
    }
}

/// Reads `count` f32 triples starting at `offset`, checking the bytes are there first.
pub(crate) fn read_vec3s(
    bytes: &[u8],
    offset: usize,
    count: usize,
    big_endian: bool,
    format: &'static str,
) -> Result<Vec<Vec3>, CacheError> {
    let need = count
        .checked_mul(12)
        .and_then(|n| n.checked_add(offset))
        .ok_or_else(|| cache_error(format, "frames", offset as u64, "sizes overflow"))?;
    if need > bytes.len() {
        return Err(cache_error(
            format,
            "frames",
            bytes.len() as u64,
            format!(
                "{count} points need {} bytes; the file ends after {}",
                need - offset,
                bytes.len() - offset.min(bytes.len())
            ),
        ));
    }
    let f = |b: &[u8]| {
        let a = [b[0], b[1], b[2], b[3]];
        if big_endian {
            f32::from_be_bytes(a)
        } else {
            f32::from_le_bytes(a)
        }
    };
    Ok(bytes[offset..need]
        .chunks_exact(12)
        .map(|c| Vec3::new(f(&c[0..4]), f(&c[4..8]), f(&c[8..12])))
        .collect())
}
