//! The `.sinew` reader. Layout: docs/format.md. Every count is checked against the bytes that remain
//! before anything is allocated; all arithmetic on values from the file is checked.

use super::asset::{
    check_lod, check_source_map, Asset, LodInfo, Mask, Material, SectionInfo, SourceVertexMap, Tag,
    ALIGN, HEADER_SIZE, MAGIC, NO_PARENT, NO_STRING, SECTION_ENTRY_SIZE, SECTION_VERSION,
    VERSION_MAJOR,
};
use super::error::{FormatError, FormatErrorKind as K};
use super::write::{
    ATTR_NORMALS, ATTR_SKIN, ATTR_UVS, CLIP_ADDITIVE, CLIP_LOOPING, CLIP_QUANTIZED, ENCODING_F32,
    KIND_ANIMATED, KIND_BIND, KIND_CONSTANT, KIND_QUANTIZED, MATERIAL_RECORD, TRACK_RECORD,
};
use crate::clip::{Channel, Track};
use crate::{Clip, Lod, Mesh, Skeleton, Submesh, Transform};
use glam::{Mat4, Quat, Vec2, Vec3};

type Result<T> = std::result::Result<T, FormatError>;

/// A bounds-checked little-endian reader over one section (or the header).
struct Cur<'a> {
    data: &'a [u8],
    pos: usize,
    /// File offset of `data[0]`.
    base: u64,
    section: String,
}

impl<'a> Cur<'a> {
    fn new(data: &'a [u8], base: u64, section: impl Into<String>) -> Self {
        Self {
            data,
            pos: 0,
            base,
            section: section.into(),
        }
    }
    fn offset(&self) -> u64 {
        self.base + self.pos as u64
    }
    fn err(&self, kind: K) -> FormatError {
        FormatError::new(self.section.clone(), Some(self.offset()), kind)
    }
    fn err_at(&self, pos: usize, kind: K) -> FormatError {
        FormatError::new(self.section.clone(), Some(self.base + pos as u64), kind)
    }
    fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }
    fn bytes(&mut self, n: usize) -> Result<&'a [u8]> {
        let available = self.remaining();
        if n > available {
            return Err(self.err(K::Truncated {
                needed: n as u64,
                available: available as u64,
            }));
        }
        let data: &'a [u8] = self.data;
        let out = data.get(self.pos..self.pos + n).unwrap_or_default();
        self.pos += n;
        Ok(out)
    }
    fn array<const N: usize>(&mut self) -> Result<[u8; N]> {
        let b = self.bytes(N)?;
        let mut out = [0u8; N];
        out.copy_from_slice(b);
        Ok(out)
    }
    fn u8(&mut self) -> Result<u8> {
        Ok(self.array::<1>()?[0])
    }
    fn u16(&mut self) -> Result<u16> {
        self.array().map(u16::from_le_bytes)
    }
    fn u32(&mut self) -> Result<u32> {
        self.array().map(u32::from_le_bytes)
    }
    fn u64(&mut self) -> Result<u64> {
        self.array().map(u64::from_le_bytes)
    }
    fn f32(&mut self) -> Result<f32> {
        self.array().map(f32::from_le_bytes)
    }
    fn skip(&mut self, n: usize) -> Result<()> {
        self.bytes(n).map(|_| ())
    }
    /// Skips the zero padding up to the next multiple of [`ALIGN`] (sections start aligned).
    fn align(&mut self) -> Result<()> {
        let pad = (ALIGN - self.pos % ALIGN) % ALIGN;
        self.skip(pad)
    }
    /// The bytes of `count` elements of `size` bytes, after checking they are present.
    fn elements(&mut self, count: u64, size: usize, what: &'static str) -> Result<&'a [u8]> {
        let available = self.remaining() as u64;
        let needed = count.saturating_mul(size as u64);
        if needed > available {
            return Err(self.err(K::CountTooLarge {
                what,
                count,
                needed,
                available,
            }));
        }
        // `needed <= available`, which fits in usize.
        self.bytes(needed as usize)
    }
    /// Checks that `count` records of at least `min_size` bytes each can be present, so that a vector of
    /// `count` entries may be allocated.
    fn check_count(&self, count: u64, min_size: usize, what: &'static str) -> Result<usize> {
        let available = self.remaining() as u64;
        let needed = count.saturating_mul(min_size as u64);
        if needed > available {
            return Err(self.err(K::CountTooLarge {
                what,
                count,
                needed,
                available,
            }));
        }
        Ok(count as usize)
    }
    fn f32s(&mut self, count: u64, what: &'static str) -> Result<Vec<f32>> {
        let b = self.elements(count, 4, what)?;
        Ok(b.chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }
}

fn f32s_of(b: &[u8]) -> impl Iterator<Item = f32> + '_ {
    b.chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
}

/// The validated header and section table.
struct Container {
    sections: Vec<SectionInfo>,
}

fn parse_container(bytes: &[u8]) -> Result<Container> {
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
    Ok(Asset {
        skeleton,
        materials,
        meshes,
        lod_info,
        clips,
        source_vertex,
        masks,
    })
}

fn source_vertices(c: &mut Cur, meshes: &[Mesh]) -> Result<Vec<Option<SourceVertexMap>>> {
    let count = c.u32()?;
    c.skip(12)?;
    let count = c.check_count(count.into(), 16, "source-vertex maps")?;
    let mut out: Vec<Option<SourceVertexMap>> = Vec::new();
    for _ in 0..count {
        c.align()?;
        let at = c.pos;
        let mesh = c.u32()?;
        let n = c.u32()?;
        let source_vertex_count = c.u32()?;
        c.skip(4)?;
        let mi = mesh as usize;
        if mi >= meshes.len() || mi < out.len() {
            return Err(c.err_at(
                at,
                K::IndexOutOfRange {
                    what: "source-vertex map mesh (out of range or not increasing)",
                    index: mesh.into(),
                    limit: meshes.len() as u64,
                },
            ));
        }
        let b = c.elements(n.into(), 4, "source-vertex map entries")?;
        let m = SourceVertexMap {
            source_vertex_count,
            map: b
                .chunks_exact(4)
                .map(|x| u32::from_le_bytes([x[0], x[1], x[2], x[3]]))
                .collect(),
        };
        let vertices = meshes
            .get(mi)
            .and_then(|m| m.lods.first())
            .map_or(0, Lod::vertex_count);
        check_source_map(&m, vertices)
            .map_err(|e| c.err_at(at, K::Invalid(format!("mesh {mi}: {e}"))))?;
        out.resize(mi, None);
        out.push(Some(m));
    }
    Ok(out)
}

fn masks(c: &mut Cur, strs: &Strs) -> Result<Vec<Mask>> {
    let count = c.u32()?;
    c.skip(12)?;
    let count = c.check_count(count.into(), 16, "masks")?;
    let mut out: Vec<Mask> = Vec::with_capacity(count);
    for _ in 0..count {
        c.align()?;
        let at = c.pos;
        let name = strs.read(c, "mask name string")?;
        let n = c.u32()?;
        c.skip(8)?;
        let n = c.check_count(n.into(), 8, "mask weights")?;
        let mut weights = Vec::with_capacity(n);
        for _ in 0..n {
            let joint = strs.read(c, "mask joint name string")?;
            let w_at = c.pos;
            let w = c.f32()?;
            if !w.is_finite() {
                return Err(c.err_at(
                    w_at,
                    K::NonFinite {
                        what: "mask weight",
                    },
                ));
            }
            weights.push((joint, w));
        }
        if out.iter().any(|m| m.name == name) {
            return Err(c.err_at(at, K::Invalid(format!("mask name {name:?} appears twice"))));
        }
        out.push(Mask { name, weights });
    }
    Ok(out)
}

fn strings(c: &mut Cur) -> Result<Vec<String>> {
    let count = c.u32()?;
    let data_size = c.u32()?;
    c.skip(8)?;
    let entries = c.elements(count.into(), 8, "string entries")?;
    c.align()?;
    let data = c.elements(data_size.into(), 1, "string data bytes")?;
    let mut out = Vec::with_capacity(count as usize);
    for (i, e) in entries.chunks_exact(8).enumerate() {
        let at = u32::from_le_bytes([e[0], e[1], e[2], e[3]]);
        let len = u32::from_le_bytes([e[4], e[5], e[6], e[7]]);
        let entry_pos = 16 + i * 8;
        let s = (at as usize)
            .checked_add(len as usize)
            .and_then(|end| data.get(at as usize..end));
        let Some(s) = s else {
            return Err(c.err_at(
                entry_pos,
                K::IndexOutOfRange {
                    what: "string data",
                    index: u64::from(at) + u64::from(len),
                    limit: data_size.into(),
                },
            ));
        };
        let s = std::str::from_utf8(s)
            .map_err(|_| c.err_at(entry_pos, K::BadUtf8 { index: i as u32 }))?;
        out.push(s.to_owned());
    }
    Ok(out)
}

/// The string table, looked up by index.
struct Strs<'a>(&'a [String]);

impl Strs<'_> {
    fn get(&self, c: &Cur, at: usize, index: u32, what: &'static str) -> Result<String> {
        self.0.get(index as usize).cloned().ok_or_else(|| {
            c.err_at(
                at,
                K::IndexOutOfRange {
                    what,
                    index: index.into(),
                    limit: self.0.len() as u64,
                },
            )
        })
    }
    /// Reads a u32 string index at the cursor and looks it up.
    fn read(&self, c: &mut Cur, what: &'static str) -> Result<String> {
        let at = c.pos;
        let index = c.u32()?;
        self.get(c, at, index, what)
    }
}

fn vec3s(b: &[u8]) -> impl Iterator<Item = Vec3> + '_ {
    b.chunks_exact(12).map(|c| {
        let mut f = f32s_of(c);
        let mut next = || f.next().unwrap_or_default();
        Vec3::new(next(), next(), next())
    })
}

fn skeleton(c: &mut Cur, strs: &Strs) -> Result<Skeleton> {
    let start = c.pos;
    let n = c.u32()?;
    c.skip(12)?;
    // Each joint needs at least 4 + 2 + 40 + 64 bytes.
    let n = c.check_count(n.into(), 110, "joints")?;
    let mut names = Vec::with_capacity(n);
    for _ in 0..n {
        names.push(strs.read(c, "joint name string")?);
    }
    c.align()?;
    let mut parents = Vec::with_capacity(n);
    for i in 0..n {
        let at = c.pos;
        let p = c.u16()?;
        if p == NO_PARENT {
            parents.push(None);
        } else if (p as usize) < i {
            parents.push(Some(p));
        } else {
            return Err(c.err_at(
                at,
                K::IndexOutOfRange {
                    what: "parent joint",
                    index: p.into(),
                    limit: i as u64,
                },
            ));
        }
    }
    c.align()?;
    let bind = c.f32s(n as u64 * 10, "bind transform floats")?;
    c.align()?;
    let inv = c.f32s(n as u64 * 16, "inverse bind floats")?;
    let bind_local = bind
        .chunks_exact(10)
        .map(|f| {
            Transform::new(
                Vec3::new(f[0], f[1], f[2]),
                Quat::from_xyzw(f[3], f[4], f[5], f[6]),
                Vec3::new(f[7], f[8], f[9]),
            )
        })
        .collect();
    let inverse_bind = inv
        .chunks_exact(16)
        .map(|f| {
            let mut a = [0f32; 16];
            a.copy_from_slice(f);
            Mat4::from_cols_array(&a)
        })
        .collect();
    Skeleton::new(names, parents, bind_local, inverse_bind)
        .map_err(|e| c.err_at(start, K::Invalid(e.to_string())))
}

fn materials(c: &mut Cur, strs: &Strs) -> Result<Vec<Material>> {
    let count = c.u32()?;
    let at = c.pos;
    let size = c.u32()?;
    if (size as usize) < MATERIAL_RECORD || size % 4 != 0 {
        return Err(c.err_at(
            at,
            K::BadValue {
                what: "material record size",
                value: size.into(),
            },
        ));
    }
    c.skip(8)?;
    let count = c.check_count(count.into(), size as usize, "materials")?;
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        let start = c.pos;
        let name = strs.read(c, "material name string")?;
        let tex_at = c.pos;
        let tex = c.u32()?;
        let texture = if tex == NO_STRING {
            None
        } else {
            Some(strs.get(c, tex_at, tex, "texture string")?)
        };
        let mut base_color = [0f32; 4];
        for v in &mut base_color {
            *v = c.f32()?;
        }
        if !base_color.iter().all(|v| v.is_finite()) {
            return Err(c.err_at(
                start + 8,
                K::NonFinite {
                    what: "base colour",
                },
            ));
        }
        c.skip(size as usize - (c.pos - start))?;
        out.push(Material {
            name,
            base_color,
            texture,
        });
    }
    Ok(out)
}

type Meshes = (Vec<Mesh>, Vec<Vec<LodInfo>>);

fn meshes(c: &mut Cur, strs: &Strs, joints: Option<usize>) -> Result<Meshes> {
    let count = c.u32()?;
    c.skip(12)?;
    // A mesh needs its 16-byte record and at least one 64-byte LOD (header and metadata).
    let count = c.check_count(count.into(), 80, "meshes")?;
    let mut meshes = Vec::with_capacity(count);
    let mut infos = Vec::with_capacity(count);
    for _ in 0..count {
        c.align()?;
        let mesh_at = c.pos;
        let name = strs.read(c, "mesh name string")?;
        let lod_count = c.u32()?;
        c.skip(8)?;
        if lod_count == 0 {
            return Err(c.err_at(mesh_at, K::Invalid(format!("mesh {name:?} has no LODs"))));
        }
        let lod_count = c.check_count(lod_count.into(), 64, "LODs")?;
        let mut lods = Vec::with_capacity(lod_count);
        let mut info = Vec::with_capacity(lod_count);
        for li in 0..lod_count {
            let (lod, i) = lod(c, strs, joints).map_err(|e| match e.kind {
                K::Invalid(m) => FormatError {
                    kind: K::Invalid(format!("mesh {name:?} LOD {li}: {m}")),
                    ..e
                },
                _ => e,
            })?;
            lods.push(lod);
            info.push(i);
        }
        meshes.push(Mesh { name, lods });
        infos.push(info);
    }
    Ok((meshes, infos))
}

fn lod(c: &mut Cur, strs: &Strs, joints: Option<usize>) -> Result<(Lod, LodInfo)> {
    c.align()?;
    let start = c.pos;
    let n = c.u32()?;
    let attributes = c.u32()?;
    if attributes & !(ATTR_NORMALS | ATTR_UVS | ATTR_SKIN) != 0 {
        return Err(c.err_at(
            start + 4,
            K::BadValue {
                what: "vertex attribute flags",
                value: attributes.into(),
            },
        ));
    }
    let index_count = c.u32()?;
    let submesh_count = c.u32()?;
    let meta_size = c.u32()?;
    if (meta_size as usize) < 20 || meta_size % 4 != 0 {
        return Err(c.err_at(
            start + 16,
            K::BadValue {
                what: "LOD metadata size",
                value: meta_size.into(),
            },
        ));
    }
    c.skip(12)?;
    let meta = c.elements(meta_size.into(), 1, "LOD metadata bytes")?;
    let mut m = Cur::new(
        meta,
        c.base + (c.pos - meta.len()) as u64,
        c.section.clone(),
    );
    let error = m.f32()?;
    let target_ratio = m.f32()?;
    let reached_ratio = m.f32()?;
    let error_model = m.f32()?;
    let flags = m.u32()?;
    if flags & !1 != 0 {
        return Err(m.err_at(
            16,
            K::BadValue {
                what: "LOD flags",
                value: flags.into(),
            },
        ));
    }
    if ![error, target_ratio, reached_ratio, error_model]
        .iter()
        .all(|v| v.is_finite())
    {
        return Err(m.err_at(
            0,
            K::NonFinite {
                what: "LOD figures",
            },
        ));
    }
    let info = LodInfo {
        target_ratio,
        reached_ratio,
        error_model,
        stopped_by_error_limit: flags & 1 != 0,
    };
    let n64 = u64::from(n);
    c.align()?;
    let positions = vec3s(c.elements(n64, 12, "positions")?).collect();
    let normals = if attributes & ATTR_NORMALS != 0 {
        c.align()?;
        vec3s(c.elements(n64, 12, "normals")?).collect()
    } else {
        Vec::new()
    };
    let uvs = if attributes & ATTR_UVS != 0 {
        c.align()?;
        c.elements(n64, 8, "uvs")?
            .chunks_exact(8)
            .map(|b| {
                let mut f = f32s_of(b);
                let mut next = || f.next().unwrap_or_default();
                Vec2::new(next(), next())
            })
            .collect()
    } else {
        Vec::new()
    };
    let (joint_ids, weights) = if attributes & ATTR_SKIN != 0 {
        c.align()?;
        let j = c
            .elements(n64, 8, "joint indices")?
            .chunks_exact(8)
            .map(|b| {
                let mut out = [0u16; 4];
                for (o, p) in out.iter_mut().zip(b.chunks_exact(2)) {
                    *o = u16::from_le_bytes([p[0], p[1]]);
                }
                out
            })
            .collect();
        c.align()?;
        let w = c
            .elements(n64, 16, "weights")?
            .chunks_exact(16)
            .map(|b| {
                let mut out = [0f32; 4];
                for (o, v) in out.iter_mut().zip(f32s_of(b)) {
                    *o = v;
                }
                out
            })
            .collect();
        (j, w)
    } else {
        (Vec::new(), Vec::new())
    };
    c.align()?;
    let indices = c
        .elements(index_count.into(), 4, "indices")?
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    c.align()?;
    let submesh_count = c.check_count(submesh_count.into(), 16, "submeshes")?;
    let mut submeshes = Vec::with_capacity(submesh_count);
    for _ in 0..submesh_count {
        let first_index = c.u32()?;
        let index_count = c.u32()?;
        let material = strs.read(c, "submesh material string")?;
        c.skip(4)?;
        submeshes.push(Submesh {
            first_index,
            index_count,
            material,
        });
    }
    let lod = Lod {
        positions,
        normals,
        uvs,
        joints: joint_ids,
        weights,
        indices,
        submeshes,
        error,
    };
    check_lod(&lod, joints).map_err(|k| c.err_at(start, k))?;
    Ok((lod, info))
}

fn clips(c: &mut Cur, strs: &Strs) -> Result<Vec<Clip>> {
    let count = c.u32()?;
    let at = c.pos;
    let record = c.u32()?;
    if (record as usize) < TRACK_RECORD || record % 4 != 0 {
        return Err(c.err_at(
            at,
            K::BadValue {
                what: "track record size",
                value: record.into(),
            },
        ));
    }
    c.skip(8)?;
    // A clip needs at least its 32-byte header and one key time.
    let count = c.check_count(count.into(), 36, "clips")?;
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        out.push(clip(c, strs, record as usize)?);
    }
    Ok(out)
}

fn channel(c: &mut Cur, n: usize) -> Result<(u8, [f32; 4], u32)> {
    let at = c.pos;
    let kind = c.u8()?;
    let encoding = c.u8()?;
    c.skip(2)?;
    if encoding != ENCODING_F32 {
        return Err(c.err_at(at + 1, K::UnsupportedEncoding { encoding }));
    }
    if kind > KIND_ANIMATED {
        return Err(c.err_at(
            at,
            K::BadValue {
                what: "channel kind",
                value: kind.into(),
            },
        ));
    }
    let raw: [u8; 16] = c.array()?;
    let mut v = [0f32; 4];
    for (o, f) in v.iter_mut().zip(f32s_of(&raw)) {
        *o = f;
    }
    let offset = u32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]);
    if kind == KIND_CONSTANT && !v[..n].iter().all(|x| x.is_finite()) {
        return Err(c.err_at(
            at + 4,
            K::NonFinite {
                what: "constant channel value",
            },
        ));
    }
    Ok((kind, v, offset))
}

fn vec_channel((kind, v, offset): (u8, [f32; 4], u32)) -> Channel<Vec3> {
    match kind {
        KIND_BIND => Channel::Bind,
        KIND_CONSTANT => Channel::Constant(Vec3::new(v[0], v[1], v[2])),
        _ => Channel::Animated(offset),
    }
}

fn clip(c: &mut Cur, strs: &Strs, record: usize) -> Result<Clip> {
    c.align()?;
    let start = c.pos;
    let name = strs.read(c, "clip name string")?;
    let flags = c.u32()?;
    if flags & !(CLIP_LOOPING | CLIP_ADDITIVE | CLIP_QUANTIZED) != 0 {
        return Err(c.err_at(
            start + 4,
            K::BadValue {
                what: "clip flags",
                value: flags.into(),
            },
        ));
    }
    let duration = c.f32()?;
    let sample_rate = c.f32()?;
    if !duration.is_finite() || !sample_rate.is_finite() {
        return Err(c.err_at(
            start + 8,
            K::NonFinite {
                what: "clip duration or sample rate",
            },
        ));
    }
    if flags & CLIP_QUANTIZED != 0 {
        return compressed_clip(c, strs, start, name, flags, duration, sample_rate);
    }
    let key_count = c.u32()?;
    let stride = c.u32()?;
    let track_count = c.u32()?;
    c.skip(4)?;
    let times = c.f32s(key_count.into(), "key times")?;
    c.align()?;
    let track_count = c.check_count(track_count.into(), record, "tracks")?;
    let mut tracks = Vec::with_capacity(track_count);
    for _ in 0..track_count {
        let t0 = c.pos;
        let joint = strs.read(c, "track joint string")?;
        let translation = vec_channel(channel(c, 3)?);
        let (kind, v, offset) = channel(c, 4)?;
        let rotation = match kind {
            KIND_BIND => Channel::Bind,
            KIND_CONSTANT => Channel::Constant(Quat::from_array(v)),
            _ => Channel::Animated(offset),
        };
        let scale = vec_channel(channel(c, 3)?);
        c.skip(record - (c.pos - t0))?;
        tracks.push(Track {
            joint,
            translation,
            rotation,
            scale,
        });
    }
    c.align()?;
    let frame_floats = u64::from(key_count).saturating_mul(stride.into());
    let frames = c.f32s(frame_floats, "frame floats")?;
    Clip::from_parts(
        name,
        duration,
        sample_rate,
        flags & CLIP_LOOPING != 0,
        flags & CLIP_ADDITIVE != 0,
        times,
        tracks,
        stride as usize,
        frames,
    )
    .map_err(|e| c.err_at(start, K::Invalid(e.to_string())))
}

/// The compressed clip record (clip flag bit 2), from its key count on. Layout: docs/format.md.
fn compressed_clip(
    c: &mut Cur,
    strs: &Strs,
    start: usize,
    name: String,
    flags: u32,
    duration: f32,
    sample_rate: f32,
) -> Result<Clip> {
    use crate::compressed::{QuantizedParts, SegmentComponent};
    let key_count = c.u32()?;
    let comp_at = c.pos;
    let components = c.u32()?;
    let track_count = c.u32()?;
    let seg_at = c.pos;
    let segment_len = c.u32()?;
    if segment_len == 0 {
        return Err(c.err_at(
            seg_at,
            K::BadValue {
                what: "segment length",
                value: 0,
            },
        ));
    }
    let times = c.f32s(key_count.into(), "key times")?;
    c.align()?;
    let track_count = c.check_count(track_count.into(), 8, "tracks")?;
    let mut kinds = Vec::with_capacity(track_count);
    let mut names = Vec::with_capacity(track_count);
    for _ in 0..track_count {
        names.push(strs.read(c, "track joint string")?);
        let at = c.pos;
        let k: [u8; 4] = c.array()?;
        if k[..3]
            .iter()
            .any(|&x| !matches!(x, KIND_BIND | KIND_CONSTANT | KIND_QUANTIZED))
        {
            return Err(c.err_at(
                at,
                K::BadValue {
                    what: "compressed channel kind",
                    value: u64::from(u32::from_le_bytes(k)),
                },
            ));
        }
        kinds.push(k);
    }
    c.align()?;
    let const_floats: u64 = kinds
        .iter()
        .map(|k| {
            [3u64, 4, 3]
                .iter()
                .zip(k)
                .filter(|(_, &x)| x == KIND_CONSTANT)
                .map(|(n, _)| n)
                .sum::<u64>()
        })
        .sum();
    let const_at = c.pos;
    let constants = c.f32s(const_floats, "constant floats")?;
    if !constants.iter().all(|v| v.is_finite()) {
        return Err(c.err_at(
            const_at,
            K::NonFinite {
                what: "constant channel value",
            },
        ));
    }
    c.align()?;
    let mut tracks = Vec::with_capacity(track_count);
    let mut ci = 0usize;
    let mut take = |n: usize| {
        let v = constants.get(ci..ci + n).unwrap_or(&[0.0; 4][..n]).to_vec();
        ci += n;
        v
    };
    for (joint, k) in names.into_iter().zip(&kinds) {
        // Animated channels are numbered below, once every track is known.
        let translation = match k[0] {
            KIND_CONSTANT => Channel::Constant(Vec3::from_slice(&take(3))),
            KIND_QUANTIZED => Channel::Animated(0),
            _ => Channel::Bind,
        };
        let rotation = match k[1] {
            KIND_CONSTANT => Channel::Constant(Quat::from_slice(&take(4))),
            KIND_QUANTIZED => Channel::Animated(0),
            _ => Channel::Bind,
        };
        let scale = match k[2] {
            KIND_CONSTANT => Channel::Constant(Vec3::from_slice(&take(3))),
            KIND_QUANTIZED => Channel::Animated(0),
            _ => Channel::Bind,
        };
        tracks.push(Track {
            joint,
            translation,
            rotation,
            scale,
        });
    }
    // Number the components in order (translation, rotation, scale per track).
    let mut next = 0u32;
    let mut rotations = Vec::new();
    for t in &mut tracks {
        if let Channel::Animated(o) = &mut t.translation {
            *o = next;
            next += 3;
        }
        if let Channel::Animated(o) = &mut t.rotation {
            *o = next;
            rotations.push(next);
            next += 3;
        }
        if let Channel::Animated(o) = &mut t.scale {
            *o = next;
            next += 3;
        }
    }
    if next != components {
        return Err(c.err_at(
            comp_at,
            K::BadValue {
                what: "component count",
                value: components.into(),
            },
        ));
    }
    let range_floats = c.f32s(u64::from(components) * 2, "component ranges")?;
    let ranges = range_floats.chunks_exact(2).map(|r| [r[0], r[1]]).collect();
    c.align()?;
    let seg_count = u64::from(key_count).div_ceil(u64::from(segment_len));
    let seg_bytes = c.elements(
        seg_count.saturating_mul(components.into()),
        3,
        "segment component entries",
    )?;
    let segments = seg_bytes
        .chunks_exact(3)
        .map(|b| SegmentComponent {
            bits: b[0],
            min: b[1],
            extent: b[2],
        })
        .collect();
    c.align()?;
    // The data's exact length follows from the bit widths: per segment, ceil(record bits * keys / 8).
    let comps = components as usize;
    let mut needed = 0u64;
    for (s, seg) in seg_bytes.chunks(comps.max(1) * 3).enumerate() {
        let bits: u64 =
            seg.chunks_exact(3).map(|b| u64::from(b[0])).sum::<u64>() + 2 * rotations.len() as u64;
        let first = s as u64 * u64::from(segment_len);
        let keys = u64::from(segment_len).min(u64::from(key_count).saturating_sub(first));
        needed = needed.saturating_add((bits * keys).div_ceil(8));
    }
    let data = c.elements(needed, 1, "compressed data bytes")?.to_vec();
    let parts = QuantizedParts {
        segment_len,
        ranges,
        segments,
        data,
    };
    Clip::from_quantized(
        name,
        duration,
        sample_rate,
        flags & CLIP_LOOPING != 0,
        flags & CLIP_ADDITIVE != 0,
        times,
        tracks,
        parts,
    )
    .map_err(|e| c.err_at(start, K::Invalid(e.to_string())))
}
