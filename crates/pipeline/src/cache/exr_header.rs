//! How many bytes an EXR file's pixels declare, read from its headers before the exr crate sees the
//! file: the crate sizes its buffers from the header, so a 27 KB file whose data window says
//! 1,073,741,824 pixels wide made it ask for 1.5 GB (docs/reliability.md). A file whose pixels would
//! take more than any compression could have packed into the bytes present is refused here.

use super::{cache_error, CacheError};

const MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
/// Version-field flags: single-part tiled, long names, deep data, multi-part.
const TILED: u32 = 0x200;
const LONG_NAMES: u32 = 0x400;
const DEEP: u32 = 0x800;
const MULTI_PART: u32 = 0x1000;

/// The most a chunk's pixels can expand over its stored bytes, by EXR compression code: none 1,
/// RLE 64 (two bytes per run of up to 128), ZIPS/ZIP/PIZ deflate's 1,032, PXR24 (deflate of 24-bit
/// values) 1,032 x 4/3, B44/B44A 32 bytes from 6 at best, DWAA/DWAB not bounded here (deflate's bound
/// times 4 is allowed).
fn expansion(compression: u8) -> u64 {
    match compression {
        0 => 1,
        1 => 64,
        2..=4 => 1032,
        5 => 1376,
        6 | 7 => 6,
        _ => 4128,
    }
}

struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Cursor<'_> {
    fn fail(&self, message: impl Into<String>) -> CacheError {
        cache_error("exr", "header", self.at as u64, message)
    }

    fn take(&mut self, n: usize) -> Result<&[u8], CacheError> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or_else(|| self.fail("header runs past the end of the file"))?;
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }

    fn u32(&mut self) -> Result<u32, CacheError> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn i32(&mut self) -> Result<i32, CacheError> {
        Ok(self.u32()? as i32)
    }

    /// A null-terminated name (at most 255 bytes with long names, 31 without); empty ends a list.
    fn name(&mut self, max: usize) -> Result<&[u8], CacheError> {
        let rest = &self.bytes[self.at..];
        let len = rest
            .iter()
            .take(max + 1)
            .position(|&b| b == 0)
            .ok_or_else(|| self.fail("name not terminated"))?;
        let out = &self.bytes[self.at..self.at + len];
        self.at += len + 1;
        Ok(out)
    }
}

/// One part's header: data window area and height, bytes per pixel over its channels, compression,
/// the `chunkCount` attribute when present.
struct Part {
    pixels: u64,
    height: u64,
    bytes_per_pixel: u64,
    compression: u8,
    chunk_count: Option<i64>,
}

/// Scan lines per chunk of a scanline image, by compression code.
fn lines_per_chunk(compression: u8) -> u64 {
    match compression {
        0..=2 => 1,
        3 | 5 => 16,
        9 => 256,
        _ => 32,
    }
}

fn read_part(c: &mut Cursor<'_>, max_name: usize) -> Result<Option<Part>, CacheError> {
    let mut window: Option<(u64, u64)> = None;
    let mut chunk_count = None;
    let mut bytes_per_pixel = 0u64;
    let mut compression = 0u8;
    let mut any = false;
    loop {
        let name = c.name(max_name)?.to_vec();
        if name.is_empty() {
            break;
        }
        any = true;
        c.name(max_name)?; // type
        let size = c.i32()?;
        let size = usize::try_from(size).map_err(|_| c.fail("negative attribute size"))?;
        let start = c.at;
        let value = c.take(size)?;
        match name.as_slice() {
            b"dataWindow" => {
                let v = |i: usize| -> Result<i64, CacheError> {
                    value
                        .get(i * 4..i * 4 + 4)
                        .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as i64)
                        .ok_or_else(|| cache_error("exr", "header", start as u64, "short box2i"))
                };
                let (x0, y0, x1, y1) = (v(0)?, v(1)?, v(2)?, v(3)?);
                if x1 < x0 || y1 < y0 {
                    return Err(cache_error(
                        "exr",
                        "header",
                        start as u64,
                        format!("data window ({x0}, {y0})..({x1}, {y1}) is empty or inverted"),
                    ));
                }
                window = Some(((x1 - x0 + 1) as u64, (y1 - y0 + 1) as u64));
            }
            b"channels" => {
                let mut ch = Cursor {
                    bytes: value,
                    at: 0,
                };
                loop {
                    if ch.name(max_name)?.is_empty() {
                        break;
                    }
                    let kind = ch.u32()?;
                    ch.take(4)?; // pLinear, reserved
                    ch.take(8)?; // x and y sampling
                    bytes_per_pixel += if kind == 1 { 2 } else { 4 };
                }
            }
            b"compression" => compression = value.first().copied().unwrap_or(0),
            b"chunkCount" => {
                chunk_count = value
                    .get(..4)
                    .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as i64);
            }
            _ => {}
        }
    }
    if !any {
        return Ok(None);
    }
    let (width, height) = window.ok_or_else(|| c.fail("a part without a dataWindow"))?;
    Ok(Some(Part {
        pixels: width * height,
        height,
        bytes_per_pixel,
        compression,
        chunk_count,
    }))
}

/// Checks that the pixels the headers declare could have been stored in `bytes`, as sinew's own walk
/// of the headers reads them and as the exr crate does; returns the declared pixel bytes of all parts
/// (by the walk).
pub fn check_declared_size(bytes: &[u8]) -> Result<u64, CacheError> {
    let declared = walk(bytes)?;
    check_as_the_crate_reads(bytes)?;
    Ok(declared)
}

/// sinew's own walk of the headers.
fn walk(bytes: &[u8]) -> Result<u64, CacheError> {
    let mut c = Cursor { bytes, at: 0 };
    if c.take(4)? != MAGIC {
        return Err(cache_error("exr", "header", 0, "not an OpenEXR file"));
    }
    let version = c.u32()?;
    if version & DEEP != 0 {
        return Err(cache_error("exr", "header", 4, "deep data is not a cache"));
    }
    let max_name = if version & LONG_NAMES != 0 { 255 } else { 31 };
    let multi = version & MULTI_PART != 0;
    let tiled = version & TILED != 0;
    let mut declared = 0u64;
    let mut chunks = 0u64;
    let mut parts = 0;
    while let Some(part) = read_part(&mut c, max_name)? {
        parts += 1;
        let bytes_of_part = part.pixels.saturating_mul(part.bytes_per_pixel);
        declared = declared.saturating_add(bytes_of_part);
        let limit = (bytes.len() as u64).saturating_mul(expansion(part.compression));
        if declared > limit {
            return Err(cache_error(
                "exr",
                "header",
                8,
                format!(
                    "the headers declare {declared} bytes of pixels, more than {} bytes could hold \
                     with compression {}",
                    bytes.len(),
                    part.compression
                ),
            ));
        }
        // Every chunk has an 8-byte entry in the offset tables, which must be in the file: the exr
        // crate walks a table as long as `chunkCount` says (the fuzzer found a 1 KB file that took
        // it past 4 GB).
        chunks = chunks.saturating_add(match part.chunk_count {
            Some(n) => u64::try_from(n)
                .map_err(|_| cache_error("exr", "header", 8, format!("negative chunkCount {n}")))?,
            None if tiled || multi => 0,
            None => part.height.div_ceil(lines_per_chunk(part.compression)),
        });
        if chunks.saturating_mul(8) > bytes.len() as u64 {
            return Err(cache_error(
                "exr",
                "header",
                8,
                format!(
                    "the headers declare {chunks} chunks, more offsets than the {} bytes hold",
                    bytes.len()
                ),
            ));
        }
        if !multi {
            break;
        }
    }
    if parts == 0 {
        return Err(cache_error("exr", "header", 8, "no part in the file"));
    }
    // The exr crate can read a header differently from the walk above (the fuzzer found a file where
    // it took a second `dataWindow`, 302 million lines tall, past an attribute the walk skipped by
    // its size): every `dataWindow` box anywhere in the file must fit as well.
    let limit = (bytes.len() as u64).saturating_mul(expansion(u8::MAX));
    for (at, area) in every_data_window(bytes) {
        if area.saturating_mul(4) > limit {
            return Err(cache_error(
                "exr",
                "header",
                at as u64,
                format!(
                    "a dataWindow of {area} pixels, more than the {} bytes could hold",
                    bytes.len()
                ),
            ));
        }
    }
    Ok(declared)
}

/// The exr crate's own reading of the headers (no pixels read yet): what it will allocate for.
fn check_as_the_crate_reads(bytes: &[u8]) -> Result<(), CacheError> {
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| cache_error("exr", "header", 0, e.to_string()))?;
    let mut crate_pixel_bytes = 0u64;
    let mut crate_chunks = 0u64;
    for h in &meta.headers {
        // A vertex cache must hold its values exactly (`verify` compares bits): the lossy
        // compressions cannot, and the crate's B44 decoder panics on some malformed blocks (the
        // fuzzer found one), so they are refused before any pixel is read.
        if h.compression.may_loose_data() {
            return Err(cache_error(
                "exr",
                "header",
                8,
                format!(
                    "{} compression is lossy: a vertex cache needs exact values",
                    h.compression
                ),
            ));
        }
        let per_pixel: u64 = h
            .channels
            .list
            .iter()
            .map(|c| c.sample_type.bytes_per_sample() as u64)
            .sum();
        let area = (h.layer_size.0 as u64).saturating_mul(h.layer_size.1 as u64);
        crate_pixel_bytes = crate_pixel_bytes.saturating_add(area.saturating_mul(per_pixel.max(1)));
        crate_chunks = crate_chunks.saturating_add(h.chunk_count as u64);
    }
    let most = (bytes.len() as u64).saturating_mul(expansion(u8::MAX));
    if crate_pixel_bytes > most || crate_chunks.saturating_mul(8) > bytes.len() as u64 {
        return Err(cache_error(
            "exr",
            "header",
            8,
            format!(
                "the headers declare {crate_pixel_bytes} bytes of pixels in {crate_chunks} chunks, \
                 more than {} bytes could hold",
                bytes.len()
            ),
        ));
    }
    Ok(())
}

/// Offset and pixel count of every `dataWindow` box2i attribute in `bytes`.
fn every_data_window(bytes: &[u8]) -> Vec<(usize, u64)> {
    const KEY: &[u8] = b"dataWindow\0box2i\0";
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(i) = bytes[from..].windows(KEY.len()).position(|w| w == KEY) {
        let at = from + i + KEY.len() + 4;
        let v = |k: usize| {
            bytes
                .get(at + 4 * k..at + 4 * k + 4)
                .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as i64)
        };
        if let (Some(x0), Some(y0), Some(x1), Some(y1)) = (v(0), v(1), v(2), v(3)) {
            let w = (x1 - x0 + 1).max(0) as u64;
            let h = (y1 - y0 + 1).max(0) as u64;
            out.push((at, w * h));
        }
        from += i + 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A single-part scanline header: `width` x `height`, channels R, G, B as f32, ZIP16 (code 3).
    fn header(width: i32, height: i32) -> Vec<u8> {
        let mut b = MAGIC.to_vec();
        b.extend_from_slice(&2u32.to_le_bytes());
        let mut attr = |name: &str, kind: &str, value: &[u8]| {
            b.extend_from_slice(name.as_bytes());
            b.push(0);
            b.extend_from_slice(kind.as_bytes());
            b.push(0);
            b.extend_from_slice(&(value.len() as i32).to_le_bytes());
            b.extend_from_slice(value);
        };
        let mut ch = Vec::new();
        for n in ["B", "G", "R"] {
            ch.extend_from_slice(n.as_bytes());
            ch.push(0);
            ch.extend_from_slice(&2u32.to_le_bytes());
            ch.extend_from_slice(&[0; 4]);
            ch.extend_from_slice(&1i32.to_le_bytes());
            ch.extend_from_slice(&1i32.to_le_bytes());
        }
        ch.push(0);
        attr("channels", "chlist", &ch);
        attr("compression", "compression", &[3]);
        let mut w = Vec::new();
        for v in [0, 0, width - 1, height - 1] {
            w.extend_from_slice(&v.to_le_bytes());
        }
        attr("dataWindow", "box2i", &w);
        b.push(0);
        b
    }

    #[test]
    fn declared_bytes_are_width_height_and_channels() {
        let mut file = header(64, 32);
        file.resize(4096, 0);
        assert_eq!(walk(&file).unwrap(), 64 * 32 * 3 * 4);
    }

    #[test]
    fn a_window_no_compression_could_fill_is_refused() {
        // 4096 bytes of ZIP can hold at most 4096 * 1032 bytes of pixels.
        let mut file = header(1 << 20, 1 << 10);
        file.resize(4096, 0);
        let e = walk(&file).unwrap_err();
        assert!(e.message.contains("12884901888 bytes"), "{e}");
        let mut inverted = header(0, 10);
        inverted.resize(4096, 0);
        assert!(walk(&inverted).unwrap_err().message.contains("inverted"));
    }

    #[test]
    fn a_chunk_count_past_the_file_is_refused() {
        // 32 lines of ZIP16 are 2 chunks: 16 bytes of offsets.
        let mut file = header(8, 32);
        file.resize(4096, 0);
        assert!(walk(&file).is_ok());
        // A chunkCount attribute of 33,554,432 in a 4 KB file.
        let mut counted = header(8, 32);
        counted.pop();
        counted.extend_from_slice(b"chunkCount\0int\0");
        counted.extend_from_slice(&4i32.to_le_bytes());
        counted.extend_from_slice(&0x0200_0000i32.to_le_bytes());
        counted.push(0);
        counted.resize(4096, 0);
        let e = walk(&counted).unwrap_err();
        assert!(e.message.contains("33554432 chunks"), "{e}");
        // 100,000 lines of ZIP16 are 6,250 chunks: 50,000 bytes of offsets.
        let mut tall = header(1, 100_000);
        tall.resize(4096, 0);
        assert!(walk(&tall).is_err());
    }

    /// A 4 x 4 RGB image of f16 samples written by the exr crate with `compression`.
    fn rgb_file(compression: exr::prelude::Compression) -> Vec<u8> {
        use exr::prelude::*;
        let channels = SpecificChannels::rgb(|_: Vec2<usize>| {
            (f16::from_f32(1.0), f16::from_f32(0.5), f16::from_f32(0.25))
        });
        let encoding = Encoding {
            compression,
            blocks: Blocks::ScanLines,
            line_order: LineOrder::Increasing,
        };
        let layer = Layer::new(Vec2(4, 4), LayerAttributes::default(), encoding, channels);
        let mut out = std::io::Cursor::new(Vec::new());
        Image::from_layer(layer)
            .write()
            .non_parallel()
            .to_buffered(&mut out)
            .expect("an EXR in memory");
        out.into_inner()
    }

    #[test]
    fn lossy_compressions_are_refused_before_any_pixel_is_read() {
        use exr::prelude::Compression;
        assert!(check_declared_size(&rgb_file(Compression::ZIP16)).is_ok());
        assert!(check_declared_size(&rgb_file(Compression::PIZ)).is_ok());
        for lossy in [Compression::B44, Compression::B44A, Compression::PXR24] {
            let e = check_declared_size(&rgb_file(lossy)).unwrap_err();
            assert!(e.message.contains("lossy"), "{lossy}: {e}");
        }
    }

    #[test]
    fn truncated_headers_are_errors() {
        let file = header(8, 8);
        for n in 0..file.len() {
            assert!(walk(&file[..n]).is_err(), "{n}");
        }
    }
}
