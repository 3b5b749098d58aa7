//! Checking input paths and importing them, with errors that name the file.

use crate::cli::{ImportArgs, PositionKeys};
use crate::digest::Stamp;
use anyhow::bail;
use sinew_import::{Format, ImportError, ImportOptions, PositionKeyRule};
use sinew_scene::Scene;
use std::cell::RefCell;
use std::path::{Path, PathBuf};

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

/// Imports `path` (as `format`, or by its extension after [`check_input`]) like [`import`], and
/// returns with the result the stamp of every file read: the input first, then each file the
/// importer asked for beside it (companions, SMDs, includes, buffers, images, material libraries),
/// in the order asked, missing ones included. Both the incremental record and the folder walk's
/// report use them. The contents are hashed only with `hash` (the incremental record needs it;
/// the folder walk needs the paths alone, and hashing a large input costs more than a third of
/// importing it).
pub fn import_tracked(
    path: &Path,
    format: Option<Format>,
    args: &ImportArgs,
    hash: bool,
) -> (anyhow::Result<Scene>, Vec<Stamp>) {
    let reads = RefCell::new(Vec::new());
    let result = import_recording(path, format, args, &reads, hash);
    (result, reads.into_inner())
}

fn import_recording(
    path: &Path,
    format: Option<Format>,
    args: &ImportArgs,
    reads: &RefCell<Vec<Stamp>>,
    hash: bool,
) -> anyhow::Result<Scene> {
    let stamp = |p: &Path, data: Option<&[u8]>| {
        if hash {
            Stamp::of(p, data)
        } else {
            Stamp::unhashed(p, data)
        }
    };
    let format = match format {
        Some(f) => f,
        None => check_input(path)?,
    };
    let name = path.display().to_string();
    let bytes =
        std::fs::read(path).map_err(|e| ImportError::in_section(&name, "file", e.to_string()))?;
    reads.borrow_mut().push(stamp(&normal(path), Some(&bytes)));
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let inner = sinew_import::beside(path);
    let resolve = |rel: &str| -> std::io::Result<Vec<u8>> {
        let got = inner(rel);
        let at = normal(&dir.join(rel.replace('\\', "/")));
        let mut list = reads.borrow_mut();
        if !list.iter().any(|s| Path::new(&s.path) == at) {
            list.push(stamp(&at, got.as_ref().ok().map(Vec::as_slice)));
        }
        got
    };
    Ok(sinew_import::import_bytes(
        format,
        &name,
        &bytes,
        &resolve,
        &import_options(args),
    )?)
}

/// A path with `.` and `..` components folded (without touching the file system).
pub fn normal(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                if !out.pop() {
                    out.push("..");
                }
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}
