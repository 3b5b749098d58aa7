//! What a `.sinew` file holds ([`Asset`] and its parts), the rules an asset must follow ([`validate`]), and
//! the container's layout constants that the reader and writer share.

use super::error::{FormatError, FormatErrorKind};
use super::game::GameData;
use crate::{Clip, Lod, Mesh, Skeleton};
use std::fmt;

/// The eight bytes every `.sinew` file starts with. The high-bit first byte catches 7-bit transfers;
/// CR LF catches line-ending conversion either way; 0x1A stops a DOS `type`.
pub const MAGIC: [u8; 8] = [0x89, b'S', b'N', b'W', b'\r', b'\n', 0x1A, b'\n'];
/// Major version this crate writes and reads. Files with another major version are rejected.
pub const VERSION_MAJOR: u16 = 1;
/// Minor version this crate writes (1.1 added the source-vertex map and mask sections, which 1.0
/// readers skip). Files with a higher minor version still load.
pub const VERSION_MINOR: u16 = 1;
/// Minor version written when a file holds compressed clips (clip flag bit 2), which 1.0 and 1.1
/// readers reject.
pub const VERSION_MINOR_COMPRESSED: u16 = 2;
/// Minor version of files that hold game data (`GAME`, added in 1.3; older readers skip it).
pub const VERSION_MINOR_GAME: u16 = 3;
/// Minor version of files that hold compact compressed clips (clip flag bit 3, added in 1.4:
/// rotation indices shared per segment, 16-bit rotation ranges), which older readers reject.
pub const VERSION_MINOR_COMPACT: u16 = 4;
/// Minor version of files that hold compressed clips in the layouts added in 1.5 (clip flag bits
/// 4-7: short track tables, packed key times, packed segment entries), which older readers reject.
/// sinew writes every compressed clip so.
pub const VERSION_MINOR_SHORT_TRACKS: u16 = 5;
/// Minor version of files that state their axes (`AXES`, added in 1.6; older readers skip it).
pub const VERSION_MINOR_AXES: u16 = 6;
/// Size of the file header in bytes.
pub const HEADER_SIZE: usize = 48;
/// Size of a section table entry written by this version (readers accept larger entries).
pub const SECTION_ENTRY_SIZE: usize = 32;
/// Alignment of every section and of every array inside a section, in bytes.
pub const ALIGN: usize = 16;
/// Layout version of every section this crate knows.
pub const SECTION_VERSION: u32 = 1;
/// String index meaning "no string" (an absent texture).
pub const NO_STRING: u32 = u32::MAX;
/// Parent index meaning "root joint".
pub const NO_PARENT: u16 = u16::MAX;

/// A section's four-byte tag.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Tag(pub [u8; 4]);

impl Tag {
    /// The string table.
    pub const STRINGS: Tag = Tag(*b"STRS");
    /// The skeleton.
    pub const SKELETON: Tag = Tag(*b"SKEL");
    /// The materials.
    pub const MATERIALS: Tag = Tag(*b"MATL");
    /// The meshes and their LODs.
    pub const MESHES: Tag = Tag(*b"MESH");
    /// The clips.
    pub const CLIPS: Tag = Tag(*b"CLIP");
    /// Source-vertex maps of LOD 0 (since 1.1).
    pub const SOURCE_VERTICES: Tag = Tag(*b"SRCV");
    /// Named joint masks (since 1.1).
    pub const MASKS: Tag = Tag(*b"MASK");
    /// Game data (attachments, hit boxes, controllers, body groups, skins, clip events; since 1.3).
    pub const GAME: Tag = Tag(*b"GAME");
    /// Up and facing axes (format 1.6).
    pub const AXES: Tag = Tag(*b"AXES");
    /// The tags version 1 defines, in the order the writer emits them.
    pub const KNOWN: [Tag; 9] = [
        Tag::STRINGS,
        Tag::SKELETON,
        Tag::MATERIALS,
        Tag::MESHES,
        Tag::CLIPS,
        Tag::SOURCE_VERTICES,
        Tag::MASKS,
        Tag::GAME,
        Tag::AXES,
    ];

    /// True for the tags version 1 defines.
    pub fn is_known(self) -> bool {
        Tag::KNOWN.contains(&self)
    }
}

impl fmt::Display for Tag {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for &b in &self.0 {
            if b.is_ascii_graphic() || b == b' ' {
                write!(f, "{}", b as char)?;
            } else {
                write!(f, "\\x{b:02x}")?;
            }
        }
        Ok(())
    }
}

impl fmt::Debug for Tag {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Tag({self})")
    }
}

/// One entry of the section table, as [`sections`] reports it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SectionInfo {
    /// The section's tag.
    pub tag: Tag,
    /// The section's layout version (1 for every section of format 1.0).
    pub version: u32,
    /// Byte offset of the section from the start of the file.
    pub offset: u64,
    /// Size of the section in bytes (padding after it not included).
    pub size: u64,
    /// CRC-32 stored in the table.
    pub crc32: u32,
    /// Whether the section's bytes match the stored CRC-32.
    pub checksum_ok: bool,
    /// Whether this reader knows the tag (unknown sections are skipped by [`read`]).
    pub known: bool,
}

/// A material: what `inspect` shows and what submeshes name.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Material {
    /// Unique name, matched by [`crate::Submesh::material`].
    pub name: String,
    /// Base colour RGBA, linear.
    pub base_color: [f32; 4],
    /// Path or URI of the colour texture, if any.
    pub texture: Option<String>,
}

/// What the simplifier reached for one LOD, beyond [`Lod::error`] (the relative error).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LodInfo {
    /// Requested fraction of LOD 0's triangles.
    pub target_ratio: f32,
    /// Fraction of LOD 0's triangles actually kept.
    pub reached_ratio: f32,
    /// Simplifier error in model units.
    pub error_model: f32,
    /// True when the error limit stopped the simplifier before the target.
    pub stopped_by_error_limit: bool,
}

impl Default for LodInfo {
    /// The values of an unsimplified LOD 0: both ratios 1, no error.
    fn default() -> Self {
        Self {
            target_ratio: 1.0,
            reached_ratio: 1.0,
            error_model: 0.0,
            stopped_by_error_limit: false,
        }
    }
}

/// For each LOD-0 vertex of one mesh, the index of the source file's vertex it was split from.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct SourceVertexMap {
    /// Number of vertices in the source file's own vertex list; every `map` entry is below it.
    pub source_vertex_count: u32,
    /// One source vertex index per LOD-0 vertex.
    pub map: Vec<u32>,
}

/// A named per-joint weight mask (for masked blending), joints named as in the skeleton.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mask {
    /// Unique mask name (`upper`, `lower`...).
    pub name: String,
    /// `(joint name, weight)` pairs; joints not listed have weight 0.
    pub weights: Vec<(String, f32)>,
}

impl Mask {
    /// One weight per joint of `skeleton` (0 for joints the mask does not name; names the skeleton
    /// lacks are ignored; a joint named twice takes its last weight).
    pub fn per_joint(&self, skeleton: &Skeleton) -> Vec<f32> {
        let mut out = vec![0.0; skeleton.len()];
        for (name, w) in &self.weights {
            if let Some(slot) = skeleton.find(name).and_then(|j| out.get_mut(j as usize)) {
                *slot = *w;
            }
        }
        out
    }
}

/// Everything a `.sinew` file holds. Any part may be empty: a file may hold a skeleton and meshes, or
/// clips alone (a motion file bound by joint name to other rigs).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Asset {
    /// The skeleton mesh joint indices refer to, if any.
    pub skeleton: Option<Skeleton>,
    /// Materials named by submeshes.
    pub materials: Vec<Material>,
    /// Meshes; each has at least one LOD.
    pub meshes: Vec<Mesh>,
    /// Per mesh, per LOD: simplifier figures. May be shorter than `meshes` (or than a mesh's LODs) when
    /// writing; missing entries are written as [`LodInfo::default`]. [`read`] always fills it completely.
    pub lod_info: Vec<Vec<LodInfo>>,
    /// Clips; their tracks name joints, which need not exist in `skeleton`.
    pub clips: Vec<Clip>,
    /// Per mesh: the source-vertex map of LOD 0, or `None`. May be shorter than `meshes` (missing
    /// entries are `None`). Written in the SRCV section (format 1.1).
    pub source_vertex: Vec<Option<SourceVertexMap>>,
    /// Named joint masks, in order. Written in the MASK section (format 1.1).
    pub masks: Vec<Mask>,
    /// Game data kept from the source. Written in the GAME section (format 1.3) when not empty.
    pub game: GameData,
    /// Up and facing axes of the source format. Written in the AXES section (format 1.6) when known.
    pub axes: Option<super::axes::Axes>,
}

impl Asset {
    /// The figures of LOD `lod` of mesh `mesh` (defaults when `lod_info` has no entry).
    pub fn lod_info(&self, mesh: usize, lod: usize) -> LodInfo {
        self.lod_info
            .get(mesh)
            .and_then(|m| m.get(lod))
            .copied()
            .unwrap_or_default()
    }

    /// The source-vertex map of mesh `mesh`, if stored.
    pub fn source_vertex(&self, mesh: usize) -> Option<&SourceVertexMap> {
        self.source_vertex.get(mesh).and_then(Option::as_ref)
    }

    /// The mask named `name`.
    pub fn mask(&self, name: &str) -> Option<&Mask> {
        self.masks.iter().find(|m| m.name == name)
    }
}

/// Checks everything [`read`] checks on decoded data, so that whatever [`write`](fn@write) accepts reads back.
///
/// Rules: every mesh has at least one LOD; per LOD, normals/UVs/joints are empty or one per vertex,
/// joints and weights come together, the index count is a multiple of three, every index is below the
/// vertex count, every joint index is below the skeleton's joint count (when there is a skeleton),
/// submesh ranges lie inside the index buffer, all floats are finite, and counts fit in 32 bits.
/// Material colours, LOD figures and clip sample rates are finite; `lod_info` is no longer than the
/// meshes and LODs it describes.
pub fn validate(asset: &Asset) -> Result<(), FormatError> {
    let joints = asset.skeleton.as_ref().map(Skeleton::len);
    super::game::check(&asset.game).map_err(|m| FormatError::invalid("GAME", None, m))?;
    if let Some(a) = asset.axes {
        super::axes::Axes::new(a.up, a.forward, a.bind_forward)
            .map_err(|m| FormatError::invalid("AXES", None, m))?;
    }
    for m in &asset.materials {
        if !m.base_color.iter().all(|v| v.is_finite()) {
            return Err(FormatError::invalid(
                "MATL",
                None,
                format!("material {:?}: non-finite base colour", m.name),
            ));
        }
    }
    if u32::try_from(asset.meshes.len()).is_err() {
        return Err(FormatError::invalid(
            "MESH",
            None,
            "more than 2^32-1 meshes",
        ));
    }
    if asset.lod_info.len() > asset.meshes.len() {
        return Err(FormatError::invalid(
            "MESH",
            None,
            "lod_info has more entries than there are meshes",
        ));
    }
    for (mi, mesh) in asset.meshes.iter().enumerate() {
        if u32::try_from(mesh.lods.len()).is_err() {
            return Err(FormatError::invalid(
                "MESH",
                None,
                format!("mesh {:?} has more than 2^32-1 LODs", mesh.name),
            ));
        }
        if mesh.lods.is_empty() {
            return Err(FormatError::invalid(
                "MESH",
                None,
                format!("mesh {:?} has no LODs", mesh.name),
            ));
        }
        if asset
            .lod_info
            .get(mi)
            .is_some_and(|l| l.len() > mesh.lods.len())
        {
            return Err(FormatError::invalid(
                "MESH",
                None,
                format!("mesh {:?}: lod_info has more entries than LODs", mesh.name),
            ));
        }
        for (li, lod) in mesh.lods.iter().enumerate() {
            check_lod(lod, joints)
                .map_err(|k| k.to_string())
                .and_then(|()| check_lod_info(&asset.lod_info(mi, li)))
                .map_err(|e| {
                    FormatError::invalid(
                        "MESH",
                        None,
                        format!("mesh {:?} LOD {li}: {e}", mesh.name),
                    )
                })?;
        }
    }
    if u32::try_from(asset.clips.len()).is_err() || u32::try_from(asset.materials.len()).is_err() {
        return Err(FormatError::invalid(
            "file",
            None,
            "more than 2^32-1 clips or materials",
        ));
    }
    check_source_vertex(asset)?;
    check_masks(&asset.masks)?;
    for c in &asset.clips {
        let fits = |n: usize| u32::try_from(n).is_ok();
        if !fits(c.times().len()) || !fits(c.tracks().len()) || !fits(c.stride()) {
            return Err(FormatError::invalid(
                "CLIP",
                None,
                format!("clip {:?}: a count does not fit in 32 bits", c.name()),
            ));
        }
        if !c.sample_rate().is_finite() {
            return Err(FormatError::invalid(
                "CLIP",
                None,
                format!("clip {:?}: non-finite sample rate", c.name()),
            ));
        }
    }
    Ok(())
}

fn check_source_vertex(asset: &Asset) -> Result<(), FormatError> {
    if asset.source_vertex.len() > asset.meshes.len() {
        return Err(FormatError::invalid(
            "SRCV",
            None,
            "more source-vertex maps than meshes",
        ));
    }
    for (mi, m) in asset.source_vertex.iter().enumerate() {
        let Some(m) = m else { continue };
        let n = asset
            .meshes
            .get(mi)
            .and_then(|mesh| mesh.lods.first())
            .map_or(0, Lod::vertex_count);
        check_source_map(m, n)
            .map_err(|e| FormatError::invalid("SRCV", None, format!("mesh {mi}: {e}")))?;
    }
    Ok(())
}

/// The rules of one source-vertex map for a LOD 0 of `vertices` vertices.
pub(crate) fn check_source_map(m: &SourceVertexMap, vertices: usize) -> Result<(), String> {
    if m.map.len() != vertices {
        return Err(format!(
            "{} map entries for {vertices} LOD-0 vertices",
            m.map.len()
        ));
    }
    if let Some((v, &s)) = m
        .map
        .iter()
        .enumerate()
        .find(|(_, &s)| s >= m.source_vertex_count)
    {
        return Err(format!(
            "vertex {v} maps to source vertex {s}, but the source has {}",
            m.source_vertex_count
        ));
    }
    Ok(())
}

/// The rules of the mask list: names unique, weights finite, counts fit in 32 bits.
pub(crate) fn check_masks(masks: &[Mask]) -> Result<(), FormatError> {
    if u32::try_from(masks.len()).is_err() {
        return Err(FormatError::invalid("MASK", None, "more than 2^32-1 masks"));
    }
    for (i, m) in masks.iter().enumerate() {
        if masks[..i].iter().any(|o| o.name == m.name) {
            return Err(FormatError::invalid(
                "MASK",
                None,
                format!("mask name {:?} appears twice", m.name),
            ));
        }
        if u32::try_from(m.weights.len()).is_err() {
            return Err(FormatError::invalid(
                "MASK",
                None,
                format!("mask {:?} has more than 2^32-1 weights", m.name),
            ));
        }
        if let Some((j, _)) = m.weights.iter().find(|(_, w)| !w.is_finite()) {
            return Err(FormatError::invalid(
                "MASK",
                None,
                format!("mask {:?}: non-finite weight for joint {j:?}", m.name),
            ));
        }
    }
    Ok(())
}

fn check_lod_info(info: &LodInfo) -> Result<(), String> {
    if [info.target_ratio, info.reached_ratio, info.error_model]
        .iter()
        .all(|v| v.is_finite())
    {
        Ok(())
    } else {
        Err("non-finite LOD figures".into())
    }
}

/// The per-LOD rules of [`validate`], as the kind of error the reader reports at the LOD's offset.
pub(crate) fn check_lod(lod: &Lod, joint_count: Option<usize>) -> Result<(), FormatErrorKind> {
    let n = lod.positions.len();
    if u32::try_from(n).is_err()
        || u32::try_from(lod.indices.len()).is_err()
        || u32::try_from(lod.submeshes.len()).is_err()
    {
        return Err(FormatErrorKind::Invalid(
            "a count does not fit in 32 bits".into(),
        ));
    }
    for (what, len) in [
        ("normals", lod.normals.len()),
        ("uvs", lod.uvs.len()),
        ("joints", lod.joints.len()),
        ("weights", lod.weights.len()),
    ] {
        if len != 0 && len != n {
            return Err(FormatErrorKind::Invalid(format!(
                "{len} {what} for {n} vertices"
            )));
        }
    }
    if lod.joints.len() != lod.weights.len() {
        return Err(FormatErrorKind::Invalid(
            "joints and weights must both be present or both absent".into(),
        ));
    }
    let non_finite = |what| Err(FormatErrorKind::NonFinite { what });
    if !lod.error.is_finite() {
        return non_finite("LOD error");
    }
    if !lod.positions.iter().all(|v| v.is_finite()) {
        return non_finite("a position");
    }
    if !lod.normals.iter().all(|v| v.is_finite()) {
        return non_finite("a normal");
    }
    if !lod.uvs.iter().all(|v| v.is_finite()) {
        return non_finite("a uv");
    }
    if !lod.weights.iter().flatten().all(|v| v.is_finite()) {
        return non_finite("a weight");
    }
    if lod.indices.len() % 3 != 0 {
        return Err(FormatErrorKind::BadValue {
            what: "index count (not a multiple of 3)",
            value: lod.indices.len() as u64,
        });
    }
    if let Some(&v) = lod.indices.iter().find(|&&v| v as usize >= n) {
        return Err(FormatErrorKind::IndexOutOfRange {
            what: "vertex",
            index: v.into(),
            limit: n as u64,
        });
    }
    if let Some(limit) = joint_count {
        if let Some(&j) = lod.joints.iter().flatten().find(|&&j| j as usize >= limit) {
            return Err(FormatErrorKind::IndexOutOfRange {
                what: "joint",
                index: j.into(),
                limit: limit as u64,
            });
        }
    }
    for s in &lod.submeshes {
        let end = u64::from(s.first_index) + u64::from(s.index_count);
        if end > lod.indices.len() as u64 {
            return Err(FormatErrorKind::IndexOutOfRange {
                what: "submesh end index",
                index: end,
                limit: lod.indices.len() as u64,
            });
        }
    }
    Ok(())
}
