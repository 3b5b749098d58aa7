//! The container: header, section table and checksums, and the entry points that decode a whole file.

use super::clips::clips;
use super::cursor::{Cur, Result, Strs};
use super::sections::{masks, materials, meshes, skeleton, source_vertices, strings};
use crate::format::asset::{
    Asset, SectionInfo, Tag, ALIGN, HEADER_SIZE, MAGIC, SECTION_ENTRY_SIZE, SECTION_VERSION,
    VERSION_MAJOR,
};
use crate::format::axes::{Axes, Axis};
use crate::format::error::{FormatError, FormatErrorKind as K};
use crate::format::game::GameData;
use crate::Skeleton;

/// The validated header and section table.
pub(super) struct Container {
    pub(super) sections: Vec<SectionInfo>,
}

pub(super) fn parse_container(bytes: &[u8]) -> Result<Container> {
    let mut h = Cur::new(bytes, 0, "header");
    let magic: [u8; 8] = match h.array() {
        Ok(m) => m,
        Err(e) => {
            // A prefix of the magic is a truncated file; anything else is not a .sinew file.
            return Err(if MAGIC.starts_with(bytes) {
                e
            } else {
                h.err_at(0, K::BadMagic)
            });
        }
    };
    if magic != MAGIC {
        return Err(h.err_at(0, K::BadMagic));
    }
    let major = h.u16()?;
    let minor = h.u16()?;
    if major != VERSION_MAJOR {
        return Err(h.err_at(8, K::UnsupportedVersion { major, minor }));
    }
    let _flags = h.u32()?;
    let file_size = h.u64()?;
    let table_offset = h.u64()?;
    let count = h.u32()?;
    let entry_size = h.u32()?;
    let _reserved = h.u32()?;
    let header_crc = h.u32()?;
    let actual = bytes.len() as u64;
    if file_size > actual {
        return Err(h.err_at(
            16,
            K::Truncated {
                needed: file_size,
                available: actual,
            },
        ));
    }
    if file_size < actual {
        return Err(h.err_at(
            16,
            K::FileSize {
                declared: file_size,
                actual,
            },
        ));
    }
    if (entry_size as usize) < SECTION_ENTRY_SIZE || entry_size % 4 != 0 {
        return Err(h.err_at(
            36,
            K::BadValue {
                what: "section entry size",
                value: entry_size.into(),
            },
        ));
    }
    let table_bytes = u64::from(count) * u64::from(entry_size);
    let table = usize::try_from(table_offset)
        .ok()
        .and_then(|start| {
            Some((
                start,
                start.checked_add(usize::try_from(table_bytes).ok()?)?,
            ))
        })
        .and_then(|(start, end)| bytes.get(start..end));
    let Some(table) = table else {
        return Err(h.err_at(
            24,
            K::CountTooLarge {
                what: "section table entries",
                count: count.into(),
                needed: table_bytes,
                available: actual.saturating_sub(table_offset),
            },
        ));
    };
    let mut crc = crc32fast::Hasher::new();
    crc.update(bytes.get(..HEADER_SIZE - 4).unwrap_or_default());
    crc.update(table);
    let computed = crc.finalize();
    if computed != header_crc {
        return Err(h.err_at(
            44,
            K::Checksum {
                stored: header_crc,
                computed,
            },
        ));
    }
    let mut sections = Vec::with_capacity(count as usize);
    let mut t = Cur::new(table, table_offset, "section table");
    for _ in 0..count {
        let start = t.pos;
        let tag = Tag(t.array()?);
        let version = t.u32()?;
        let offset = t.u64()?;
        let size = t.u64()?;
        let stored = t.u32()?;
        t.skip(entry_size as usize - (t.pos - start))?;
        let end = offset.checked_add(size);
        let body = end
            .filter(|&e| e <= actual)
            .and_then(|e| bytes.get(offset as usize..e as usize));
        let Some(body) = body else {
            return Err(t.err_at(
                start + 8,
                K::SectionOutOfBounds {
                    offset,
                    size,
                    file_size: actual,
                },
            ));
        };
        if offset % ALIGN as u64 != 0 {
            return Err(t.err_at(start + 8, K::Misaligned { offset }));
        }
        sections.push(SectionInfo {
            tag,
            version,
            offset,
            size,
            crc32: stored,
            checksum_ok: crc32fast::hash(body) == stored,
            known: tag.is_known(),
        });
    }
    Ok(Container { sections })
}

/// Lists the sections of a `.sinew` file after checking the header and the section table (magic,
/// version, size, header checksum, section bounds and alignment). Section checksums are computed and
/// reported in [`SectionInfo::checksum_ok`], not treated as errors, so a damaged file can be inspected.
pub fn sections(bytes: &[u8]) -> Result<Vec<SectionInfo>> {
    parse_container(bytes).map(|c| c.sections)
}

/// Decodes a `.sinew` file.
///
/// Checks the header, the section table and every section's CRC-32; skips sections with unknown tags;
/// rejects another major version, duplicate known sections and known sections with an unknown layout
/// version. The decoded skeleton, meshes and clips are validated as [`super::validate`] describes.
pub fn read(bytes: &[u8]) -> Result<Asset> {
    let container = parse_container(bytes)?;
    let mut found: [Option<&SectionInfo>; Tag::KNOWN.len()] = [None; Tag::KNOWN.len()];
    for s in &container.sections {
        if !s.checksum_ok {
            let body = bytes
                .get(s.offset as usize..(s.offset + s.size) as usize)
                .unwrap_or_default();
            return Err(FormatError::new(
                s.tag.to_string(),
                Some(s.offset),
                K::Checksum {
                    stored: s.crc32,
                    computed: crc32fast::hash(body),
                },
            ));
        }
        let Some(k) = Tag::KNOWN.iter().position(|&t| t == s.tag) else {
            continue;
        };
        if found[k].is_some() {
            return Err(FormatError::new(
                s.tag.to_string(),
                Some(s.offset),
                K::DuplicateSection,
            ));
        }
        if s.version != SECTION_VERSION {
            return Err(FormatError::new(
                s.tag.to_string(),
                Some(s.offset),
                K::UnsupportedSectionVersion { version: s.version },
            ));
        }
        found[k] = Some(s);
    }
    let cur = |k: usize| {
        found[k].map(|s| {
            let body = bytes
                .get(s.offset as usize..(s.offset + s.size) as usize)
                .unwrap_or_default();
            Cur::new(body, s.offset, s.tag.to_string())
        })
    };
    let strings = match cur(0) {
        Some(mut c) => strings(&mut c)?,
        None => Vec::new(),
    };
    let strs = Strs(&strings);
    let skeleton = match cur(1) {
        Some(mut c) => Some(skeleton(&mut c, &strs)?),
        None => None,
    };
    let materials = match cur(2) {
        Some(mut c) => materials(&mut c, &strs)?,
        None => Vec::new(),
    };
    let (meshes, lod_info) = match cur(3) {
        Some(mut c) => meshes(&mut c, &strs, skeleton.as_ref().map(Skeleton::len))?,
        None => (Vec::new(), Vec::new()),
    };
    let clips = match cur(4) {
        Some(mut c) => clips(&mut c, &strs)?,
        None => Vec::new(),
    };
    let source_vertex = match cur(5) {
        Some(mut c) => source_vertices(&mut c, &meshes)?,
        None => Vec::new(),
    };
    let masks = match cur(6) {
        Some(mut c) => masks(&mut c, &strs)?,
        None => Vec::new(),
    };
    let game = match cur(7) {
        Some(mut c) => super::game::game(&mut c, &strs)?,
        None => GameData::default(),
    };
    let axes = match cur(8) {
        Some(mut c) => Some(axes(&mut c)?),
        None => None,
    };
    Ok(Asset {
        skeleton,
        materials,
        meshes,
        lod_info,
        clips,
        source_vertex,
        masks,
        game,
        axes,
    })
}

/// The `AXES` section: three axis codes (up, forward, bind forward), then reserved bytes (at least 16
/// in all; more are skipped).
fn axes(c: &mut Cur) -> Result<Axes> {
    let b: [u8; 16] = c.array()?;
    let axis = |i: usize, what: &str| {
        Axis::from_code(b[i]).ok_or_else(|| {
            c.err_at(
                i,
                K::Invalid(format!("{what} axis code {} is not 0 to 5", b[i])),
            )
        })
    };
    let (up, forward, bind_forward) = (
        axis(0, "up")?,
        axis(1, "forward")?,
        axis(2, "bind forward")?,
    );
    Axes::new(up, forward, bind_forward).map_err(|m| c.err_at(0, K::Invalid(m)))
}
