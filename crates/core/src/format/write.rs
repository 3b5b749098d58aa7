//! The `.sinew` writer. Layout: docs/format.md.

use super::asset::{
    validate, Asset, Material, Tag, ALIGN, HEADER_SIZE, MAGIC, NO_PARENT, NO_STRING,
    SECTION_ENTRY_SIZE, SECTION_VERSION, VERSION_MAJOR, VERSION_MINOR, VERSION_MINOR_AXES,
    VERSION_MINOR_GAME, VERSION_MINOR_SHORT_TRACKS,
};
use super::error::FormatError;
use crate::clip::Channel;
use crate::compressed::compact_range_units;
use crate::{Clip, Mesh, Skeleton};
use std::collections::HashMap;

/// Encodes an asset as a `.sinew` file, version 1.1 (1.3 with game data, 1.5 with compressed clips,
/// whose records use 1.5's layouts, 1.6 when it states its axes).
///
/// The output depends only on the asset: the same asset gives the same bytes. Fails (without writing
/// anything) when the asset breaks a rule of [`validate`], so whatever this accepts, [`super::read`]
/// reads back equal.
pub fn write(asset: &Asset) -> Result<Vec<u8>, FormatError> {
    validate(asset)?;
    let mut strings = Strings::default();
    let mut sections: Vec<(Tag, Vec<u8>)> = Vec::new();
    if let Some(s) = &asset.skeleton {
        sections.push((Tag::SKELETON, skeleton(s, &mut strings)));
    }
    if !asset.materials.is_empty() {
        sections.push((Tag::MATERIALS, materials(&asset.materials, &mut strings)));
    }
    if !asset.meshes.is_empty() {
        sections.push((Tag::MESHES, meshes(asset, &mut strings)));
    }
    if !asset.clips.is_empty() {
        sections.push((Tag::CLIPS, clips(&asset.clips, &mut strings)));
    }
    if asset.source_vertex.iter().any(Option::is_some) {
        sections.push((Tag::SOURCE_VERTICES, source_vertices(asset)));
    }
    if !asset.masks.is_empty() {
        sections.push((Tag::MASKS, masks(&asset.masks, &mut strings)));
    }
    if !asset.game.is_empty() {
        sections.push((Tag::GAME, game(&asset.game, &mut strings)));
    }
    if let Some(a) = asset.axes {
        // up, forward, bind forward, then 13 reserved zero bytes: 16 in all.
        let mut b = vec![0u8; 16];
        b[0] = a.up.code();
        b[1] = a.forward.code();
        b[2] = a.bind_forward.code();
        sections.push((Tag::AXES, b));
    }
    sections.insert(0, (Tag::STRINGS, strings.encode()?));
    // Every compressed record is written in the 1.5 layout (packed segment entries at least).
    let minor = if asset.axes.is_some() {
        VERSION_MINOR_AXES
    } else if asset.clips.iter().any(Clip::is_compressed) {
        VERSION_MINOR_SHORT_TRACKS
    } else if !asset.game.is_empty() {
        VERSION_MINOR_GAME
    } else {
        VERSION_MINOR
    };
    Ok(assemble_minor(&sections, minor))
}

/// Header, section table, then each section at the next multiple of [`ALIGN`], zero padding between.
/// The minor version goes into the header.
pub(crate) fn assemble_minor(sections: &[(Tag, Vec<u8>)], minor: u16) -> Vec<u8> {
    let table_offset = HEADER_SIZE;
    let mut offset = pad_to(table_offset + sections.len() * SECTION_ENTRY_SIZE);
    let mut end = offset;
    let mut table = Buf::default();
    for (tag, body) in sections {
        table.bytes(&tag.0);
        table.u32(SECTION_VERSION);
        table.u64(offset as u64);
        table.u64(body.len() as u64);
        table.u32(crc32fast::hash(body));
        table.u32(0);
        end = offset + body.len();
        offset = pad_to(end);
    }
    // The file ends with the last section: no padding after it.
    let file_size = end;
    // The whole file at once: growing it by doubling copies it several times over, each copy into
    // memory touched for the first time (a page fault per page).
    let mut out = Buf(Vec::with_capacity(file_size));
    out.bytes(&MAGIC);
    out.u16(VERSION_MAJOR);
    out.u16(minor);
    out.u32(0); // flags
    out.u64(file_size as u64);
    out.u64(table_offset as u64);
    out.u32(sections.len() as u32);
    out.u32(SECTION_ENTRY_SIZE as u32);
    out.u32(0); // reserved
    let mut crc = crc32fast::Hasher::new();
    crc.update(&out.0);
    crc.update(&table.0);
    out.u32(crc.finalize());
    out.bytes(&table.0);
    for (_, body) in sections {
        out.align();
        out.bytes(body);
    }
    debug_assert_eq!(out.0.len(), file_size);
    out.0
}

fn pad_to(n: usize) -> usize {
    n.div_ceil(ALIGN) * ALIGN
}

/// A little-endian byte buffer.
#[derive(Default)]
pub(crate) struct Buf(pub(crate) Vec<u8>);

impl Buf {
    pub(crate) fn bytes(&mut self, b: &[u8]) {
        self.0.extend_from_slice(b);
    }
    pub(crate) fn u16(&mut self, v: u16) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn f32(&mut self, v: f32) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn f32s(&mut self, v: &[f32]) {
        for &x in v {
            self.f32(x);
        }
    }
    pub(crate) fn zeros(&mut self, n: usize) {
        self.0.resize(self.0.len() + n, 0);
    }
    /// Zero padding up to the next multiple of [`ALIGN`].
    pub(crate) fn align(&mut self) {
        let n = pad_to(self.0.len()) - self.0.len();
        self.zeros(n);
    }
}

/// The string table under construction: strings in first-use order, each stored once.
#[derive(Default)]
struct Strings {
    list: Vec<String>,
    index: HashMap<String, u32>,
}

impl Strings {
    fn get(&mut self, s: &str) -> u32 {
        if let Some(&i) = self.index.get(s) {
            return i;
        }
        let i = self.list.len() as u32;
        self.list.push(s.to_owned());
        self.index.insert(s.to_owned(), i);
        i
    }

    fn encode(&self) -> Result<Vec<u8>, FormatError> {
        let total: usize = self.list.iter().map(String::len).sum();
        let too_big = || FormatError::invalid("STRS", None, "string data exceeds 4 GiB");
        let count = u32::try_from(self.list.len()).map_err(|_| too_big())?;
        let data_size = u32::try_from(total).map_err(|_| too_big())?;
        let mut b = Buf::default();
        b.u32(count);
        b.u32(data_size);
        b.zeros(8);
        let mut at = 0u32;
        for s in &self.list {
            b.u32(at);
            b.u32(s.len() as u32);
            at += s.len() as u32;
        }
        b.align();
        for s in &self.list {
            b.bytes(s.as_bytes());
        }
        Ok(b.0)
    }
}

fn skeleton(s: &Skeleton, strings: &mut Strings) -> Vec<u8> {
    let mut b = Buf::default();
    b.u32(s.len() as u32);
    b.zeros(12);
    for n in s.names() {
        b.u32(strings.get(n));
    }
    b.align();
    for p in s.parents() {
        b.u16(p.unwrap_or(NO_PARENT));
    }
    b.align();
    for t in s.bind_local() {
        b.f32s(&t.translation.to_array());
        b.f32s(&t.rotation.to_array());
        b.f32s(&t.scale.to_array());
    }
    b.align();
    for m in s.inverse_bind() {
        b.f32s(&m.to_cols_array());
    }
    b.0
}

/// Bytes of one material record in version 1.
pub(crate) const MATERIAL_RECORD: usize = 32;

fn materials(list: &[Material], strings: &mut Strings) -> Vec<u8> {
    let mut b = Buf::default();
    b.u32(list.len() as u32);
    b.u32(MATERIAL_RECORD as u32);
    b.zeros(8);
    for m in list {
        b.u32(strings.get(&m.name));
        b.u32(m.texture.as_deref().map_or(NO_STRING, |t| strings.get(t)));
        b.f32s(&m.base_color);
        b.zeros(8);
    }
    b.0
}

/// Bytes of the LOD metadata record in version 1.
pub(crate) const LOD_META_RECORD: usize = 32;
/// Attribute bit: normals present.
pub(crate) const ATTR_NORMALS: u32 = 1;
/// Attribute bit: UVs present.
pub(crate) const ATTR_UVS: u32 = 2;
/// Attribute bit: joints and weights present.
pub(crate) const ATTR_SKIN: u32 = 4;

fn meshes(asset: &Asset, strings: &mut Strings) -> Vec<u8> {
    // Room for every record up front (see `assemble_minor`): the arrays plus each record's header,
    // metadata and alignment padding.
    let lods = asset.meshes.iter().flat_map(|m| &m.lods);
    let size: usize = lods
        .map(|l| {
            l.positions.len() * 12
                + l.normals.len() * 12
                + l.uvs.len() * 8
                + std::mem::size_of_val(l.joints.as_slice())
                + std::mem::size_of_val(l.weights.as_slice())
                + l.indices.len() * 4
                + l.submeshes.len() * 16
                + 16 * ALIGN
        })
        .sum();
    let mut b = Buf(Vec::with_capacity(
        16 + asset.meshes.len() * 2 * ALIGN + size,
    ));
    b.u32(asset.meshes.len() as u32);
    b.zeros(12);
    for (mi, mesh) in asset.meshes.iter().enumerate() {
        mesh_record(&mut b, asset, mi, mesh, strings);
    }
    b.0
}

fn mesh_record(b: &mut Buf, asset: &Asset, mi: usize, mesh: &Mesh, strings: &mut Strings) {
    b.align();
    b.u32(strings.get(&mesh.name));
    b.u32(mesh.lods.len() as u32);
    b.zeros(8);
    for (li, lod) in mesh.lods.iter().enumerate() {
        let info = asset.lod_info(mi, li);
        let mut attributes = 0;
        if !lod.normals.is_empty() {
            attributes |= ATTR_NORMALS;
        }
        if !lod.uvs.is_empty() {
            attributes |= ATTR_UVS;
        }
        if !lod.joints.is_empty() {
            attributes |= ATTR_SKIN;
        }
        b.align();
        b.u32(lod.positions.len() as u32);
        b.u32(attributes);
        b.u32(lod.indices.len() as u32);
        b.u32(lod.submeshes.len() as u32);
        b.u32(LOD_META_RECORD as u32);
        b.zeros(12);
        b.f32(lod.error);
        b.f32(info.target_ratio);
        b.f32(info.reached_ratio);
        b.f32(info.error_model);
        b.u32(u32::from(info.stopped_by_error_limit));
        b.zeros(12);
        b.align();
        for p in &lod.positions {
            b.f32s(&p.to_array());
        }
        if !lod.normals.is_empty() {
            b.align();
            for n in &lod.normals {
                b.f32s(&n.to_array());
            }
        }
        if !lod.uvs.is_empty() {
            b.align();
            for uv in &lod.uvs {
                b.f32s(&uv.to_array());
            }
        }
        if !lod.joints.is_empty() {
            b.align();
            for js in &lod.joints {
                for &j in js {
                    b.u16(j);
                }
            }
            b.align();
            for ws in &lod.weights {
                b.f32s(ws);
            }
        }
        b.align();
        for &i in &lod.indices {
            b.u32(i);
        }
        b.align();
        for s in &lod.submeshes {
            b.u32(s.first_index);
            b.u32(s.index_count);
            b.u32(strings.get(&s.material));
            b.u32(0);
        }
    }
}

/// Bytes of one track record in version 1.
pub(crate) const TRACK_RECORD: usize = 64;
/// Channel kind: not stored, bind value.
pub(crate) const KIND_BIND: u8 = 0;
/// Channel kind: one constant value.
pub(crate) const KIND_CONSTANT: u8 = 1;
/// Channel kind: animated, at a float offset in every frame.
pub(crate) const KIND_ANIMATED: u8 = 2;
/// Channel encoding: plain little-endian f32.
pub(crate) const ENCODING_F32: u8 = 0;
/// Clip flag: looping.
pub(crate) const CLIP_LOOPING: u32 = 1;
/// Clip flag: additive.
pub(crate) const CLIP_ADDITIVE: u32 = 2;

fn channel(b: &mut Buf, kind: u8, payload: [u32; 4]) {
    b.bytes(&[kind, ENCODING_F32, 0, 0]);
    for p in payload {
        b.u32(p);
    }
}

fn vec_channel(b: &mut Buf, c: Channel<glam::Vec3>) {
    match c {
        Channel::Bind => channel(b, KIND_BIND, [0; 4]),
        Channel::Constant(v) => channel(b, KIND_CONSTANT, [v.x, v.y, v.z, 0.0].map(f32::to_bits)),
        Channel::Animated(o) => channel(b, KIND_ANIMATED, [o, 0, 0, 0]),
    }
}

/// Clip flag: quantized (compressed) record layout.
pub(crate) const CLIP_QUANTIZED: u32 = 4;
/// Clip flag (with [`CLIP_QUANTIZED`], since 1.4): compact record, with 16-bit rotation ranges and a
/// table of per-segment rotation indices.
pub(crate) const CLIP_COMPACT: u32 = 8;
/// Clip flag (with [`CLIP_QUANTIZED`], since 1.5): short track table, u16 joint names and one byte
/// of channel kinds per track.
pub(crate) const CLIP_SHORT_TRACKS: u32 = 16;
/// Clip flag (with [`CLIP_QUANTIZED`], since 1.5): packed key times (`super::times`).
pub(crate) const CLIP_PACKED_TIMES: u32 = 32;
/// Clip flag (with [`CLIP_QUANTIZED`], since 1.5): segment entries as 5-bit widths, then the
/// sub-range starts, then their lengths (instead of three bytes per entry).
pub(crate) const CLIP_PACKED_SEGMENTS: u32 = 64;
/// Clip flag (with [`CLIP_PACKED_SEGMENTS`], since 1.5): every sub-range is the whole clip range
/// (start 0, length 255) and none is stored.
pub(crate) const CLIP_WHOLE_RANGES: u32 = 128;
/// Compressed track table kind: quantized animated channel.
pub(crate) const KIND_QUANTIZED: u8 = 3;

/// Bytes of one clip record as [`write`](fn@write) lays it out (from the record's first byte to the end of its
/// data, alignment padding before it not counted; joint names live in the string table and are not
/// counted). Plain and compressed clips alike: this is the size `convert` reports.
pub fn clip_record_size(clip: &Clip) -> usize {
    let mut strings = Strings::default();
    let mut b = Buf::default();
    clip_record(&mut b, clip, &mut strings);
    b.0.len()
}

/// Writes a compressed clip record in the 1.5 layout: packed segment entries, the short track
/// table when every joint name's string index fits in 16 bits (as it does in any file of fewer
/// than 65,536 strings), packed key times when they are smaller.
fn compressed_record(
    b: &mut Buf,
    c: &Clip,
    parts: &crate::compressed::QuantizedParts,
    strings: &mut Strings,
) {
    let start = b.0.len();
    let mut flags = CLIP_QUANTIZED;
    // Strings in the order the record names them: the clip, then its tracks.
    let name = strings.get(c.name());
    let names: Vec<u32> = c.tracks().iter().map(|t| strings.get(&t.joint)).collect();
    let short = names.iter().all(|&n| n <= u32::from(u16::MAX));
    if short {
        flags |= CLIP_SHORT_TRACKS;
    }
    // Packed key times when they take fewer bytes (after the padding that follows them).
    let packed = super::times::pack(c.times(), c.sample_rate())
        .filter(|p| pad_to(32 + p.len()) < pad_to(32 + 4 * c.times().len()));
    if packed.is_some() {
        flags |= CLIP_PACKED_TIMES;
    }
    // Segment entries: bit widths in 5 bits each (every width is at most 24), and the
    // sub-ranges left out when every one is the whole clip range (0 and 255: a clip of one
    // segment, or components without extent).
    flags |= CLIP_PACKED_SEGMENTS;
    let whole = parts.segments.iter().all(|e| e.min == 0 && e.extent == 255);
    if whole {
        flags |= CLIP_WHOLE_RANGES;
    }
    // `Clip::from_quantized` checked that the rotation ranges of such parts have 16-bit forms.
    let compact = !parts.rotation_index.is_empty();
    if compact {
        flags |= CLIP_COMPACT;
    }
    if c.looping() {
        flags |= CLIP_LOOPING;
    }
    if c.additive() {
        flags |= CLIP_ADDITIVE;
    }
    b.u32(name);
    b.u32(flags);
    b.f32(c.duration());
    b.f32(c.sample_rate());
    b.u32(c.times().len() as u32);
    b.u32(parts.ranges.len() as u32);
    b.u32(c.tracks().len() as u32);
    b.u32(parts.segment_len);
    match &packed {
        Some(p) => {
            b.u64(p.step.to_bits());
            b.u32(p.first);
            b.bytes(&[p.gap_bits, p.residual_bits, 0, 0]);
            b.bytes(&p.data);
        }
        None => b.f32s(c.times()),
    }
    align_from(b, start);
    let kind = |c: bool, a: bool| {
        if a {
            KIND_QUANTIZED
        } else if c {
            KIND_CONSTANT
        } else {
            KIND_BIND
        }
    };
    let mut constants = Vec::new();
    let mut track_kinds = Vec::with_capacity(c.tracks().len());
    for t in c.tracks() {
        let mut kinds = [0u8; 4];
        for (i, (is_const, is_anim)) in [
            (
                matches!(t.translation, Channel::Constant(_)),
                matches!(t.translation, Channel::Animated(_)),
            ),
            (
                matches!(t.rotation, Channel::Constant(_)),
                matches!(t.rotation, Channel::Animated(_)),
            ),
            (
                matches!(t.scale, Channel::Constant(_)),
                matches!(t.scale, Channel::Animated(_)),
            ),
        ]
        .into_iter()
        .enumerate()
        {
            kinds[i] = kind(is_const, is_anim);
        }
        track_kinds.push(kinds);
        if let Channel::Constant(v) = t.translation {
            constants.extend_from_slice(&v.to_array());
        }
        if let Channel::Constant(q) = t.rotation {
            constants.extend_from_slice(&q.to_array());
        }
        if let Channel::Constant(v) = t.scale {
            constants.extend_from_slice(&v.to_array());
        }
    }
    if short {
        // All names (u16), then all kinds (one byte: 2 bits per channel).
        for &n in &names {
            b.u16(n as u16);
        }
        for k in &track_kinds {
            b.bytes(&[k[0] | k[1] << 2 | k[2] << 4]);
        }
    } else {
        for (&n, k) in names.iter().zip(&track_kinds) {
            b.u32(n);
            b.bytes(k);
        }
    }
    align_from(b, start);
    b.f32s(&constants);
    align_from(b, start);
    let rotation_comps = rotation_components(c);
    for (i, r) in parts.ranges.iter().enumerate() {
        match compact_range_units(*r).filter(|_| compact && rotation_comps.contains(&i)) {
            Some([min, ext]) => {
                b.u16(min);
                b.u16(ext);
            }
            None => b.f32s(r),
        }
    }
    align_from(b, start);
    let mut widths = vec![0u8; (parts.segments.len() * 5).div_ceil(8)];
    for (i, e) in parts.segments.iter().enumerate() {
        for bit in 0..5 {
            if e.bits >> bit & 1 != 0 {
                let at = i * 5 + bit;
                widths[at / 8] |= 1 << (at % 8);
            }
        }
    }
    b.bytes(&widths);
    if !whole {
        for e in &parts.segments {
            b.bytes(&[e.min]);
        }
        for e in &parts.segments {
            b.bytes(&[e.extent]);
        }
    }
    align_from(b, start);
    if compact {
        b.bytes(&parts.rotation_index);
        align_from(b, start);
    }
    b.bytes(&parts.data);
}

/// The component numbers of a compressed clip's rotations (three per animated rotation).
fn rotation_components(c: &Clip) -> std::collections::BTreeSet<usize> {
    c.tracks()
        .iter()
        .filter_map(|t| match t.rotation {
            Channel::Animated(o) => Some(o as usize..o as usize + 3),
            _ => None,
        })
        .flatten()
        .collect()
}

/// Pads relative to `start` (clip records start aligned inside the section).
fn align_from(b: &mut Buf, start: usize) {
    let n = pad_to(b.0.len() - start) - (b.0.len() - start);
    b.zeros(n);
}

fn clips(list: &[Clip], strings: &mut Strings) -> Vec<u8> {
    let mut b = Buf::default();
    b.u32(list.len() as u32);
    b.u32(TRACK_RECORD as u32);
    b.zeros(8);
    for c in list {
        b.align();
        clip_record(&mut b, c, strings);
    }
    b.0
}

fn clip_record(b: &mut Buf, c: &Clip, strings: &mut Strings) {
    if let Some(parts) = c.quantized_parts() {
        compressed_record(b, c, parts, strings);
        return;
    }
    let start = b.0.len();
    {
        let mut flags = 0;
        if c.looping() {
            flags |= CLIP_LOOPING;
        }
        if c.additive() {
            flags |= CLIP_ADDITIVE;
        }
        b.u32(strings.get(c.name()));
        b.u32(flags);
        b.f32(c.duration());
        b.f32(c.sample_rate());
        b.u32(c.times().len() as u32);
        b.u32(c.stride() as u32);
        b.u32(c.tracks().len() as u32);
        b.u32(0);
        b.f32s(c.times());
        align_from(b, start);
        for t in c.tracks() {
            b.u32(strings.get(&t.joint));
            vec_channel(b, t.translation);
            match t.rotation {
                Channel::Bind => channel(b, KIND_BIND, [0; 4]),
                Channel::Constant(q) => channel(b, KIND_CONSTANT, q.to_array().map(f32::to_bits)),
                Channel::Animated(o) => channel(b, KIND_ANIMATED, [o, 0, 0, 0]),
            }
            vec_channel(b, t.scale);
        }
        align_from(b, start);
        b.f32s(c.frames());
    }
}

/// SRCV: `u32 entry_count; 12 zero bytes;` then per entry, 16-aligned:
/// `u32 mesh; u32 vertex_count; u32 source_vertex_count; u32 0; u32 map[vertex_count]`.
fn source_vertices(asset: &Asset) -> Vec<u8> {
    let mut b = Buf::default();
    let entries: Vec<_> = asset
        .source_vertex
        .iter()
        .enumerate()
        .filter_map(|(i, m)| m.as_ref().map(|m| (i, m)))
        .collect();
    b.u32(entries.len() as u32);
    b.zeros(12);
    for (mesh, m) in entries {
        b.align();
        b.u32(mesh as u32);
        b.u32(m.map.len() as u32);
        b.u32(m.source_vertex_count);
        b.u32(0);
        for &s in &m.map {
            b.u32(s);
        }
    }
    b.0
}

/// MASK: `u32 mask_count; 12 zero bytes;` then per mask, 16-aligned:
/// `u32 name; u32 weight_count; 8 zero bytes;` then `weight_count x (u32 joint name; f32 weight)`.
fn masks(list: &[super::asset::Mask], strings: &mut Strings) -> Vec<u8> {
    let mut b = Buf::default();
    b.u32(list.len() as u32);
    b.zeros(12);
    for m in list {
        b.align();
        b.u32(strings.get(&m.name));
        b.u32(m.weights.len() as u32);
        b.zeros(8);
        for (joint, w) in &m.weights {
            b.u32(strings.get(joint));
            b.f32(*w);
        }
    }
    b.0
}

/// Bytes of one clip record of the `GAME` section.
pub(crate) const GAME_CLIP_RECORD: usize = 96;

/// The `GAME` section (format 1.3): a 64-byte header of counts, then one table after another, each
/// starting at a multiple of 16.
fn game(g: &super::game::GameData, strings: &mut Strings) -> Vec<u8> {
    let mut b = Buf::default();
    let opt = |s: &str, strings: &mut Strings| {
        if s.is_empty() {
            NO_STRING
        } else {
            strings.get(s)
        }
    };
    let entries: usize = g.body_groups.iter().map(|bg| bg.meshes.len()).sum();
    let events: usize = g.clips.iter().map(|c| c.events.len()).sum();
    let slots = g.skin_families.first().map_or(0, Vec::len);
    b.u32(u32::from(g.eye_position.is_some()));
    b.f32s(&g.eye_position.unwrap_or_default());
    for n in [
        g.attachments.len(),
        g.hitboxes.len(),
        g.controllers.len(),
        g.body_groups.len(),
        entries,
        g.skin_families.len(),
        slots,
        g.material_flags.len(),
        g.clips.len(),
        events,
        g.transition_nodes as usize,
    ] {
        b.u32(n as u32);
    }
    b.u32(0);
    for a in &g.attachments {
        b.u32(strings.get(&a.name));
        b.u32(strings.get(&a.joint));
        b.f32s(&a.offset);
    }
    b.align();
    for h in &g.hitboxes {
        b.u32(strings.get(&h.joint));
        b.u32(h.group as u32);
        b.f32s(&h.min);
        b.f32s(&h.max);
    }
    b.align();
    for c in &g.controllers {
        b.u32(c.index as u32);
        b.u32(strings.get(&c.joint));
        b.u32(c.channel);
        b.f32(c.start);
        b.f32(c.end);
        b.u32(c.rest as u32);
    }
    b.align();
    let mut first = 0u32;
    for bg in &g.body_groups {
        b.u32(strings.get(&bg.name));
        b.u32(first);
        b.u32(bg.meshes.len() as u32);
        first += bg.meshes.len() as u32;
    }
    b.align();
    for m in g.body_groups.iter().flat_map(|bg| &bg.meshes) {
        let i = opt(m, strings);
        b.u32(i);
    }
    b.align();
    for m in g.skin_families.iter().flatten() {
        b.u32(strings.get(m));
    }
    b.align();
    for f in &g.material_flags {
        b.u32(strings.get(&f.material));
        b.u32(f.flags);
    }
    b.align();
    let mut first = 0u32;
    for c in &g.clips {
        b.u32(strings.get(&c.clip));
        b.u32(c.activity as u32);
        b.u32(c.activity_weight as u32);
        b.u32(first);
        b.u32(c.events.len() as u32);
        first += c.events.len() as u32;
        b.u32(c.motion_type);
        let j = opt(&c.motion_joint, strings);
        b.u32(j);
        b.f32s(&c.linear_movement);
        let blend = c.blend.clone().unwrap_or_default();
        b.u32(u32::from(c.blend.is_some()));
        let s = opt(&blend.sequence, strings);
        b.u32(s);
        b.u32(blend.index);
        b.u32(blend.count);
        b.u32(blend.types[0]);
        b.u32(blend.types[1]);
        b.f32s(&blend.start);
        b.f32s(&blend.end);
        b.u32(c.entry_node as u32);
        b.u32(c.exit_node as u32);
        b.u32(c.node_flags as u32);
        b.u32(0);
    }
    b.align();
    for e in g.clips.iter().flat_map(|c| &c.events) {
        b.u32(e.frame as u32);
        b.u32(e.event as u32);
        b.u32(e.kind as u32);
        b.u32(strings.get(&e.options));
    }
    b.align();
    b.bytes(&g.transitions);
    b.0
}
