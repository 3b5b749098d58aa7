//! Importer for the ms3d format (being written).

use crate::{ImportError, ImportOptions, Resolver};
use sinew_scene::Scene;

/// Imports a ms3d file.
pub fn import(
    file_name: &str,
    _bytes: &[u8],
    _resolve: Resolver<'_>,
    _options: &ImportOptions,
) -> Result<Scene, ImportError> {
    Err(ImportError::in_section(
        file_name,
        "file",
        "ms3d import is not implemented yet",
    ))
}
