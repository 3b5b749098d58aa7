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
    let bytes =
        std::fs::read(path).map_err(|e| ImportError::in_section(&name, "file", e.to_string()))?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let resolve = move |rel: &str| -> std::io::Result<Vec<u8>> {
        let rel = rel.replace('\\', "/");
        std::fs::read(dir.join(rel))
    };
    import_bytes(format, &name, &bytes, &resolve, options)
}
