//! Checking input paths and importing them, with errors that name the file.

use crate::cli::{ImportArgs, PositionKeys};
use anyhow::bail;
use sinew_import::{Format, ImportOptions, PositionKeyRule};
use sinew_scene::Scene;
use std::path::Path;

/// The extensions sinew reads, as error messages list them.
pub const SUPPORTED: &str = ".ms3d, .gltf, .glb, .obj, .bvh, .mdl, .smd, .qc, .sinew";

/// Checks that `path` is an existing regular file with a supported extension.
pub fn check_input(path: &Path) -> anyhow::Result<Format> {
    let shown = path.display();
    match std::fs::metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => bail!("{shown}: no such file"),
        Err(e) => bail!("{shown}: cannot read: {e}"),
        Ok(m) if m.is_dir() => bail!("{shown}: is a directory, expected a file"),
        Ok(_) => {}
    }
    match Format::from_path(path) {
        Some(f) => Ok(f),
        None => {
            let ext = path
                .extension()
                .map(|e| format!("extension .{}", e.to_string_lossy()))
                .unwrap_or_else(|| "no extension".to_string());
            bail!("{shown}: unsupported file type ({ext}); sinew reads {SUPPORTED}")
        }
    }
}

/// The importer options the command-line flags select.
pub fn import_options(args: &ImportArgs) -> ImportOptions {
    ImportOptions {
        ms3d_position_keys: match args.ms3d_position_keys {
            PositionKeys::Viewer => PositionKeyRule::Viewer,
            PositionKeys::Parent => PositionKeyRule::Parent,
            PositionKeys::Auto => PositionKeyRule::Auto,
        },
        gltf_skin: args.gltf_skin,
        allow_missing: args.allow_missing,
    }
}

/// Checks and imports one input file. The error is one line naming the file.
pub fn import(path: &Path, args: &ImportArgs) -> anyhow::Result<Scene> {
    check_input(path)?;
    Ok(sinew_import::import_path(path, &import_options(args))?)
}

/// Imports a file as `format` (recognised by content, whatever its extension).
pub fn import_as(path: &Path, format: Format, args: &ImportArgs) -> anyhow::Result<Scene> {
    Ok(sinew_import::import_path_as(
        path,
        format,
        &import_options(args),
    )?)
}
