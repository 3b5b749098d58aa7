//! The export entry point: build the document from an asset and pack it as GLB or `.gltf` bytes.

use super::container::{pack, Container};
use super::document::{build, ExportImage, ExportOptions, ExportReport};
use sinew_core::format::Asset;

/// Exports `asset` (with `images` embedded where materials name them) as glTF bytes. Deterministic:
/// the same inputs give the same bytes.
pub fn export(
    asset: &Asset,
    images: &[ExportImage],
    container: Container,
    options: &ExportOptions,
) -> Result<(Vec<u8>, ExportReport), String> {
    let built = build(asset, images, options);
    let bytes = pack(built.root, &built.bin, container)?;
    Ok((bytes, built.report))
}
