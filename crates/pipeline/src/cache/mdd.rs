//! MDD point caches (LightWave; read by Blender and others), big-endian:
//! `i32 numFrames; i32 numPoints; f32 times[numFrames];` then `numFrames x numPoints x f32[3]`.
//! sinew writes `times[i] = i / fps` seconds.

use super::{cache_error, read_vec3s, CacheError, Frames};

/// Encodes frames as MDD bytes.
pub fn write(frames: &Frames) -> Vec<u8> {
    let mut out = Vec::with_capacity(8 + frames.frame_count * 4 + frames.positions.len() * 12);
    out.extend_from_slice(&(frames.frame_count as i32).to_be_bytes());
    out.extend_from_slice(&(frames.vertex_count as i32).to_be_bytes());
    for f in 0..frames.frame_count {
        out.extend_from_slice(&frame_time(f, frames.fps).to_be_bytes());
    }
    for p in &frames.positions {
        for c in p.to_array() {
            out.extend_from_slice(&c.to_be_bytes());
        }
    }
    out
}

/// Time of frame `f` at `fps`, as written in the MDD time table.
pub fn frame_time(f: usize, fps: f32) -> f32 {
    if fps > 0.0 {
        (f as f64 / fps as f64) as f32
    } else {
        0.0
    }
}

/// Reads MDD bytes, returning the time table and the frames (fps estimated from the first interval).
pub fn read(bytes: &[u8]) -> Result<(Vec<f32>, Frames), CacheError> {
    if bytes.len() < 8 {
        return Err(cache_error(
            "mdd",
            "header",
            bytes.len() as u64,
            "file shorter than the 8-byte header",
        ));
    }
    let i = |o: usize| i32::from_be_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let (frames, points) = (i(0), i(4));
    if frames < 0 || points < 0 {
        return Err(cache_error(
            "mdd",
            "header",
            0,
            "negative frame or point count",
        ));
    }
    let (frames, points) = (frames as usize, points as usize);
    let times_end = frames
        .checked_mul(4)
        .and_then(|n| n.checked_add(8))
        .filter(|&n| n <= bytes.len())
        .ok_or_else(|| {
            cache_error(
                "mdd",
                "times",
                8,
                format!("{frames} frame times do not fit in the file"),
            )
        })?;
    let times: Vec<f32> = bytes[8..times_end]
        .chunks_exact(4)
        .map(|c| f32::from_be_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let total = frames.checked_mul(points).ok_or_else(|| {
        cache_error(
            "mdd",
            "header",
            0,
            "frame count times point count overflows",
        )
    })?;
    let positions = read_vec3s(bytes, times_end, total, true, "mdd")?;
    if bytes.len() != times_end + total * 12 {
        return Err(cache_error(
            "mdd",
            "frames",
            (times_end + total * 12) as u64,
            "trailing bytes after the last frame",
        ));
    }
    let fps = if times.len() > 1 && times[1] > times[0] {
        1.0 / (times[1] - times[0])
    } else {
        0.0
    };
    Ok((
        times,
        Frames {
            vertex_count: points,
            frame_count: frames,
            fps,
            positions,
            normals: Vec::new(),
        },
    ))
}
