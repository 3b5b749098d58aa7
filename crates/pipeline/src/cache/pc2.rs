//! PC2 point caches (3ds Max, Blender's Mesh Cache modifier), little-endian:
//! `char magic[12] = "POINTCACHE2\0"; i32 version = 1; i32 numPoints; f32 startFrame; f32 sampleRate;
//! i32 numSamples;` then `numSamples x numPoints x f32[3]`.
//!
//! `sampleRate` in PC2 is the frame step between samples (1.0 = one sample per frame), not frames per
//! second; sinew writes 1.0 and start frame 0, so sample i is frame i at the bake's fps.

use super::{cache_error, read_vec3s, CacheError, Frames};

const MAGIC: &[u8; 12] = b"POINTCACHE2\0";
const HEADER: usize = 32;

/// Encodes frames as PC2 bytes.
pub fn write(frames: &Frames) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER + frames.positions.len() * 12);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&1i32.to_le_bytes());
    out.extend_from_slice(&(frames.vertex_count as i32).to_le_bytes());
    out.extend_from_slice(&0.0f32.to_le_bytes());
    out.extend_from_slice(&1.0f32.to_le_bytes());
    out.extend_from_slice(&(frames.frame_count as i32).to_le_bytes());
    for p in &frames.positions {
        for c in p.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    out
}

/// What a PC2 header says.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Header {
    /// Points per sample.
    pub points: usize,
    /// First frame.
    pub start_frame: f32,
    /// Frames between samples.
    pub sample_rate: f32,
    /// Number of samples.
    pub samples: usize,
}

/// Reads PC2 bytes; `fps` is not stored in PC2 and is left 0.
pub fn read(bytes: &[u8]) -> Result<(Header, Frames), CacheError> {
    if bytes.len() < HEADER {
        return Err(cache_error(
            "pc2",
            "header",
            bytes.len() as u64,
            "file shorter than the 32-byte header",
        ));
    }
    if &bytes[0..12] != MAGIC {
        return Err(cache_error(
            "pc2",
            "header",
            0,
            "magic is not \"POINTCACHE2\\0\"",
        ));
    }
    let i = |o: usize| i32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let f = |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    if i(12) != 1 {
        return Err(cache_error(
            "pc2",
            "header",
            12,
            format!("version {} (expected 1)", i(12)),
        ));
    }
    let (points, samples) = (i(16), i(28));
    if points < 0 || samples < 0 {
        return Err(cache_error(
            "pc2",
            "header",
            16,
            "negative point or sample count",
        ));
    }
    let header = Header {
        points: points as usize,
        start_frame: f(20),
        sample_rate: f(24),
        samples: samples as usize,
    };
    let total = header.points.checked_mul(header.samples).ok_or_else(|| {
        cache_error(
            "pc2",
            "header",
            16,
            "point count times sample count overflows",
        )
    })?;
    let positions = read_vec3s(bytes, HEADER, total, false, "pc2")?;
    if bytes.len() != HEADER + total * 12 {
        return Err(cache_error(
            "pc2",
            "frames",
            (HEADER + total * 12) as u64,
            "trailing bytes after the last sample",
        ));
    }
    Ok((
        header,
        Frames {
            vertex_count: header.points,
            frame_count: header.samples,
            fps: 0.0,
            positions,
            normals: Vec::new(),
        },
    ))
}
