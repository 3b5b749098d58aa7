//! EXT_meshopt_compression (gltfpack `-c`): buffer views stored compressed by meshoptimizer's
//! vertex and index codecs, decoded into the bytes of the view they stand for before any accessor
//! reads them. The codecs are meshoptimizer's own (the `meshopt` crate), which are written to take
//! untrusted input; every range and size is checked here before anything is allocated.

use super::refs::Problem;
use serde_json::Value;

fn problem(path: impl Into<String>, message: impl Into<String>) -> Problem {
    (path.into(), message.into())
}

/// The extension's name.
pub(super) const EXTENSION: &str = "EXT_meshopt_compression";

/// The most bytes the compressed views of one file may decode to (and its fallback buffers hold):
/// 16 MiB plus 1,024 per input byte. meshoptimizer's vertex codec stores a byte channel that is
/// zero over a block of up to 256 vertices in 2 bits, so a legitimate file decodes to up to about
/// 1,024 times its compressed size; a file that declares more is refused before allocating.
fn decoded_limit(input_bytes: usize) -> usize {
    (16usize << 20).saturating_add(input_bytes.saturating_mul(1024))
}

/// The buffers marked as fallback (`extensions.EXT_meshopt_compression.fallback`): their bytes are
/// the decoded views, so they need no data in the file.
pub(super) fn fallback_buffers(root: &Value) -> Vec<usize> {
    root.get("buffers")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .enumerate()
        .filter(|(_, b)| {
            b.pointer("/extensions/EXT_meshopt_compression/fallback")
                .and_then(Value::as_bool)
                == Some(true)
        })
        .map(|(i, _)| i)
        .collect()
}

/// A non-negative integer at `key` of `v` (absent: `default`, when there is one).
fn integer(v: &Value, path: &str, key: &str, default: Option<usize>) -> Result<usize, Problem> {
    match v.get(key) {
        None => default.ok_or_else(|| problem(path, format!("{key} is missing"))),
        Some(x) => x
            .as_u64()
            .and_then(|n| usize::try_from(n).ok())
            .ok_or_else(|| problem(path, format!("{key} must be a non-negative integer"))),
    }
}

/// A 4-byte word block of `N` words: the element type that makes the vertex codec decode
/// `4 * N`-byte vertices (its vertex size is the element's size).
#[derive(Clone)]
struct Words<const N: usize>([u32; N]);

impl<const N: usize> Default for Words<N> {
    fn default() -> Self {
        Words([0; N])
    }
}

/// The bytes of decoded words, in memory order (the codecs write bytes; `to_ne_bytes` gives them
/// back as they were written).
fn word_bytes<const N: usize>(words: &[[u32; N]]) -> Vec<u8> {
    words
        .iter()
        .flatten()
        .flat_map(|w| w.to_ne_bytes())
        .collect()
}

fn words_of<const N: usize>(bytes: &[u8]) -> Vec<[u32; N]> {
    bytes
        .chunks_exact(4 * N)
        .map(|c| {
            std::array::from_fn(|k| {
                u32::from_ne_bytes([c[4 * k], c[4 * k + 1], c[4 * k + 2], c[4 * k + 3]])
            })
        })
        .collect()
}

/// `count` vertices of `4 * N` bytes decoded by the vertex codec.
fn decode_vertices<const N: usize>(encoded: &[u8], count: usize) -> Option<Vec<u8>> {
    let v = meshopt::decode_vertex_buffer::<Words<N>>(encoded, count).ok()?;
    Some(
        v.iter()
            .flat_map(|w| w.0)
            .flat_map(u32::to_ne_bytes)
            .collect(),
    )
}

/// The exponential filter over vertices of `4 * N` bytes, in place.
fn filter_exponential<const N: usize>(bytes: &mut Vec<u8>) {
    let mut words = words_of::<N>(bytes);
    meshopt::decode_filter_exp::<N>(&mut words);
    *bytes = word_bytes(&words);
}

/// Calls `$f::<N>($args)` for the `N` in 1..=64 equal to `$n` (a vertex of `4 * N` bytes: the
/// extension's strides are multiples of 4 up to 256).
macro_rules! by_words {
    ($n:expr, $f:ident $args:tt, [$($k:literal)*]) => {
        match $n {
            $($k => Some($f::<$k> $args),)*
            _ => None,
        }
    };
}

macro_rules! words_1_to_64 {
    ($n:expr, $f:ident $args:tt) => {
        by_words!($n, $f $args, [1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24
            25 26 27 28 29 30 31 32 33 34 35 36 37 38 39 40 41 42 43 44 45 46 47 48 49 50 51 52 53 54
            55 56 57 58 59 60 61 62 63 64])
    };
}

/// 16-bit components of 8-byte vertices, for the octahedral and quaternion filters.
fn shorts_of(bytes: &[u8]) -> Vec<[i16; 4]> {
    bytes
        .chunks_exact(8)
        .map(|c| std::array::from_fn(|k| i16::from_ne_bytes([c[2 * k], c[2 * k + 1]])))
        .collect()
}

fn short_bytes(v: &[[i16; 4]]) -> Vec<u8> {
    v.iter().flatten().flat_map(|x| x.to_ne_bytes()).collect()
}

/// Applies the view's filter to its decoded vertices; `Err` names what is wrong.
fn apply_filter(filter: &str, stride: usize, bytes: &mut Vec<u8>) -> Result<(), String> {
    match (filter, stride) {
        ("NONE", _) => {}
        ("OCTAHEDRAL", 4) => {
            let mut v: Vec<[i8; 4]> = bytes
                .chunks_exact(4)
                .map(|c| std::array::from_fn(|k| c[k] as i8))
                .collect();
            meshopt::decode_filter_oct(&mut v);
            *bytes = v.iter().flatten().map(|&x| x as u8).collect();
        }
        ("OCTAHEDRAL", 8) | ("QUATERNION", 8) => {
            let mut v = shorts_of(bytes);
            if filter == "OCTAHEDRAL" {
                meshopt::decode_filter_oct(&mut v);
            } else {
                meshopt::decode_filter_quat(&mut v);
            }
            *bytes = short_bytes(&v);
        }
        ("EXPONENTIAL", s) if s % 4 == 0 => {
            words_1_to_64!(s / 4, filter_exponential(bytes))
                .ok_or_else(|| format!("byteStride {s} is not one the extension allows"))?;
        }
        ("OCTAHEDRAL" | "QUATERNION" | "EXPONENTIAL", s) => {
            return Err(format!("filter {filter} does not take byteStride {s}"));
        }
        (other, _) => return Err(format!("unknown filter {other:?}")),
    }
    Ok(())
}

/// Index bytes (little-endian, `stride` 2 or 4 bytes each) of decoded indices.
fn index_bytes(indices: Vec<u32>, stride: usize) -> Vec<u8> {
    if stride == 2 {
        indices
            .iter()
            .flat_map(|&i| (i as u16).to_le_bytes())
            .collect()
    } else {
        indices.iter().flat_map(|i| i.to_le_bytes()).collect()
    }
}

/// Decodes one compressed view's data (`encoded`): `count` elements of `stride` bytes.
fn decode(
    mode: &str,
    filter: &str,
    encoded: &[u8],
    count: usize,
    stride: usize,
) -> Result<Vec<u8>, String> {
    match mode {
        "ATTRIBUTES" => {
            if stride % 4 != 0 || !(4..=256).contains(&stride) {
                return Err(format!(
                    "byteStride {stride} must be a multiple of 4 from 4 to 256"
                ));
            }
            let mut bytes = words_1_to_64!(stride / 4, decode_vertices(encoded, count))
                .flatten()
                .ok_or("the vertex data does not decode")?;
            apply_filter(filter, stride, &mut bytes)?;
            Ok(bytes)
        }
        "TRIANGLES" | "INDICES" => {
            if stride != 2 && stride != 4 {
                return Err(format!("byteStride {stride} must be 2 or 4 for indices"));
            }
            if filter != "NONE" {
                return Err(format!("filter {filter} does not apply to indices"));
            }
            let decoded = if mode == "TRIANGLES" {
                if count % 3 != 0 {
                    return Err(format!("count {count} is not a whole number of triangles"));
                }
                meshopt::decode_index_buffer::<u32>(encoded, count)
            } else {
                meshopt::decode_index_sequence::<u32>(encoded, count)
            };
            let indices = decoded.map_err(|_| "the index data does not decode".to_string())?;
            Ok(index_bytes(indices, stride))
        }
        other => Err(format!("unknown mode {other:?}")),
    }
}

/// Decodes every compressed buffer view of `root` into `buffers` (the view's own range of its own
/// buffer, usually a fallback buffer, which is sized here). `input_bytes`: the file's bytes and its
/// loaded buffers', which bound what may be decoded ([`decoded_limit`]).
pub(super) fn decode_views(
    root: &Value,
    buffers: &mut [Vec<u8>],
    fallback: &[usize],
    input_bytes: usize,
) -> Result<(), Problem> {
    let limit = decoded_limit(input_bytes);
    let mut decoded_total = 0usize;
    // Fallback buffers get their declared length, zeroed, when it is within the limit.
    let declared = |i: usize| {
        root.pointer(&format!("/buffers/{i}/byteLength"))
            .and_then(Value::as_u64)
            .and_then(|n| usize::try_from(n).ok())
            .unwrap_or(0)
    };
    let mut fallback_total = 0usize;
    for &i in fallback {
        let Some(buffer) = buffers.get_mut(i) else {
            continue;
        };
        if buffer.is_empty() {
            let n = declared(i);
            fallback_total = fallback_total.saturating_add(n);
            if fallback_total > limit {
                return Err(problem(
                    format!("buffers[{i}]"),
                    format!(
                        "fallback buffers of {fallback_total} bytes are more than its compressed data may decode to ({limit})"
                    ),
                ));
            }
            buffer.resize(n, 0);
        }
    }
    let views = root.get("bufferViews").and_then(Value::as_array);
    for (v, view) in views.into_iter().flatten().enumerate() {
        let Some(ext) = view.pointer("/extensions/EXT_meshopt_compression") else {
            continue;
        };
        let path = format!("bufferViews[{v}].extensions.{EXTENSION}");
        let source = integer(ext, &path, "buffer", None)?;
        let offset = integer(ext, &path, "byteOffset", Some(0))?;
        let length = integer(ext, &path, "byteLength", None)?;
        let stride = integer(ext, &path, "byteStride", None)?;
        let count = integer(ext, &path, "count", None)?;
        let mode = ext.get("mode").and_then(Value::as_str).unwrap_or("");
        let filter = ext.get("filter").and_then(Value::as_str).unwrap_or("NONE");
        let size = count
            .checked_mul(stride)
            .filter(|&s| s <= limit.saturating_sub(decoded_total))
            .ok_or_else(|| {
                problem(
                    &path,
                    format!("{count} elements of {stride} bytes are more than the file may decode to ({limit} bytes in all)"),
                )
            })?;
        decoded_total += size;
        let encoded = buffers
            .get(source)
            .and_then(|b| b.get(offset..offset.checked_add(length)?))
            .ok_or_else(|| {
                problem(
                    &path,
                    format!("bytes {offset}..+{length} are not in buffers[{source}]"),
                )
            })?
            .to_vec();
        let bytes = decode(mode, filter, &encoded, count, stride).map_err(|m| problem(&path, m))?;
        let view_path = format!("bufferViews[{v}]");
        let target = integer(view, &view_path, "buffer", None)?;
        let target_offset = integer(view, &view_path, "byteOffset", Some(0))?;
        let target_length = integer(view, &view_path, "byteLength", None)?;
        if bytes.len() > target_length {
            return Err(problem(
                &path,
                format!(
                    "decodes to {} bytes, more than the view's byteLength {target_length}",
                    bytes.len()
                ),
            ));
        }
        let into = buffers
            .get_mut(target)
            .and_then(|b| b.get_mut(target_offset..target_offset.checked_add(bytes.len())?))
            .ok_or_else(|| {
                problem(
                    &view_path,
                    format!(
                        "bytes {target_offset}..+{} are not in buffers[{target}]",
                        bytes.len()
                    ),
                )
            })?;
        into.copy_from_slice(&bytes);
    }
    Ok(())
}
