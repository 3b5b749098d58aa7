//! sinew-import turns the bytes of a source file (MS3D, glTF 2.0, OBJ, BVH, Half-Life MDL/SMD/QC,
//! `.sinew`) into a sinew
//! [`Scene`].
//!
//! Every importer takes untrusted bytes: counts are checked against the bytes present before anything is
//! allocated, and every failure is an [`ImportError`] naming the file, the section and the byte offset,
//! line or JSON path. No input may panic.
//!
//! Each format is one module with one entry point, `import(file_name, bytes, resolve, options)`.
//! `resolve` loads files the input refers to (glTF external buffers, OBJ material libraries) by the
//! relative path written in the input; [`import_path`] supplies one that reads beside the input file.

pub mod bvh;
pub mod error;
pub mod gltf;
mod guard;
pub mod halflife;
pub mod ms3d;
pub mod obj;
pub mod sinew;
mod text;

pub use error::{ImportError, Location};
pub use sinew_scene::Scene;

use std::path::Path;

/// Loads a file that the input refers to, by the relative path written in the input.
pub type Resolver<'a> = &'a dyn Fn(&str) -> std::io::Result<Vec<u8>>;

/// How MS3D position keys combine with a joint's bind pose (see docs/formats/ms3d.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PositionKeyRule {
    /// Milkshape's viewer: `t = t0 + R0 * tkey`.
    Viewer,
    /// Added in the parent's space: `t = t0 + tkey`.
    Parent,
    /// Decide per file from how plausible each reading's animation is.
    #[default]
    Auto,
}

/// Options for all importers; each reads the fields that concern it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImportOptions {
    /// MS3D: how position keys compose with the bind pose.
    pub ms3d_position_keys: PositionKeyRule,
    /// glTF: which skin becomes the skeleton when the file has several (`None`: the first, with a
    /// diagnostic listing the others).
    pub gltf_skin: Option<usize>,
    /// Half-Life: a file the model names that cannot be read (an SMD of a QC's `$body`, `$bodygroup`
    /// or `$sequence`, an MDL's `NAMET.mdl` or sequence-group file) is a warning and what needs it is
    /// left out. Off (the default), it is an error naming the file, line and command, as studiomdl
    /// and the engine refuse it. Either way a QC none of whose SMDs can be read is an error.
    pub allow_missing: bool,
}

/// The source formats sinew reads, by file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// `.ms3d`
    Ms3d,
    /// `.gltf` or `.glb`
    Gltf,
    /// `.obj`
    Obj,
    /// `.bvh`
    Bvh,
    /// `.sinew`
    Sinew,
    /// `.mdl` (GoldSrc, version 10)
    Mdl,
    /// `.smd`
    Smd,
    /// `.qc`
    Qc,
}

impl Format {
    /// The format for a path's extension (case-insensitive), if sinew reads it.
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "ms3d" => Format::Ms3d,
            "gltf" | "glb" => Format::Gltf,
            "obj" => Format::Obj,
            "bvh" => Format::Bvh,
            "sinew" => Format::Sinew,
            "mdl" => Format::Mdl,
            "smd" => Format::Smd,
            "qc" => Format::Qc,
            _ => return None,
        })
    }
}

/// What a file is, by its content: a model or motion sinew converts, a companion that belongs to
/// another file (a Half-Life texture or sequence-group file), or neither.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    /// A file to convert, in this format.
    Model(Format),
    /// A GoldSrc `NAMET.mdl`: textures only; read with its model.
    MdlTextures,
    /// A GoldSrc `NAME01.mdl` sequence group (`IDSQ`); read with its model.
    MdlSequenceGroup,
    /// Anything else (material libraries, buffers, images, unknown files).
    Other,
}

impl FileKind {
    /// Recognises a file by its first bytes, using the extension only for text formats that have no
    /// signature (OBJ, glTF JSON) and to confirm the loose text signatures of BVH, SMD and QC.
    pub fn sniff(path: &Path, head: &[u8]) -> FileKind {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        let i32_at = |at: usize| {
            head.get(at..at + 4)
                .map_or(0, |b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        };
        if head.starts_with(b"IDSQ") {
            return FileKind::MdlSequenceGroup;
        }
        if head.starts_with(b"IDST") {
            // numbones, numseq, numbodyparts, numtextures
            let (bones, seqs, parts, textures) =
                (i32_at(140), i32_at(164), i32_at(204), i32_at(180));
            return if bones == 0 && seqs == 0 && parts == 0 && textures > 0 {
                FileKind::MdlTextures
            } else {
                FileKind::Model(Format::Mdl)
            };
        }
        if head.starts_with(b"MS3D000000") {
            return FileKind::Model(Format::Ms3d);
        }
        if head.starts_with(&sinew_core::format::MAGIC) {
            return FileKind::Model(Format::Sinew);
        }
        if head.starts_with(b"glTF") {
            return FileKind::Model(Format::Gltf);
        }
        let text = String::from_utf8_lossy(&head[..head.len().min(512)]).to_ascii_lowercase();
        let first = text.trim_start_matches('\u{feff}').trim_start();
        match ext.as_str() {
            "gltf" => FileKind::Model(Format::Gltf),
            "obj" => FileKind::Model(Format::Obj),
            "bvh" if first.starts_with("hierarchy") => FileKind::Model(Format::Bvh),
            "smd" if first.starts_with("version") => FileKind::Model(Format::Smd),
            "qc" => FileKind::Model(Format::Qc),
            _ if first.starts_with("hierarchy") => FileKind::Model(Format::Bvh),
            _ => FileKind::Other,
        }
    }
}

/// Imports bytes of a known format.
pub fn import_bytes(
    format: Format,
    file_name: &str,
    bytes: &[u8],
    resolve: Resolver<'_>,
    options: &ImportOptions,
) -> Result<Scene, ImportError> {
    match format {
        Format::Ms3d => ms3d::import(file_name, bytes, resolve, options),
        Format::Gltf => gltf::import(file_name, bytes, resolve, options),
        Format::Obj => obj::import(file_name, bytes, resolve, options),
        Format::Bvh => bvh::import(file_name, bytes, resolve, options),
        Format::Sinew => sinew::import(file_name, bytes, resolve, options),
        Format::Mdl => halflife::entry::import_mdl(file_name, bytes, resolve, options),
        Format::Smd => halflife::entry::import_smd(file_name, bytes, resolve, options),
        Format::Qc => halflife::entry::import_qc(file_name, bytes, resolve, options),
    }
}

/// Reads a file, picks the importer by extension, and resolves referenced files beside it.
pub fn import_path(path: &Path, options: &ImportOptions) -> Result<Scene, ImportError> {
    let name = path.display().to_string();
    let format = Format::from_path(path).ok_or_else(|| {
        ImportError::in_section(
            &name,
            "file",
            "unsupported extension (expected .ms3d, .gltf, .glb, .obj, .bvh, .mdl, .smd, .qc or .sinew)",
        )
    })?;
    import_path_as(path, format, options)
}

/// Reads a file as the given format, resolving referenced files beside it.
pub fn import_path_as(
    path: &Path,
    format: Format,
    options: &ImportOptions,
) -> Result<Scene, ImportError> {
    let name = path.display().to_string();
    let bytes =
        std::fs::read(path).map_err(|e| ImportError::in_section(&name, "file", e.to_string()))?;
    let resolve = beside(path);
    import_bytes(format, &name, &bytes, &resolve, options)
}

/// A resolver that reads files by the relative path written in `path` (backslashes allowed),
/// from the folder `path` is in.
pub fn beside(path: &Path) -> impl Fn(&str) -> std::io::Result<Vec<u8>> {
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    move |rel: &str| -> std::io::Result<Vec<u8>> {
        let rel = rel.replace('\\', "/");
        std::fs::read(dir.join(rel))
    }
}
