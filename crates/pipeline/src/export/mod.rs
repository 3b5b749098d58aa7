//! Export to glTF 2.0: a decoded `.sinew` [`Asset`](sinew_core::format::Asset) as a `.glb` or `.gltf`
//! that any glTF viewer opens, with every clip keyed from the runtime's playback (docs/export.md).
//!
//! - [`buffer`]: the binary buffer, views and accessors;
//! - [`animation`]: clips keyed for export from the runtime's playback ([`sinew_core::Animator`]);
//! - [`keys`]: fitting a channel with the fewest keys a viewer plays as the runtime does;
//! - [`document`]: the glTF document (nodes, skin, materials, textures, meshes, LODs, animations, extras);
//! - [`container`]: GLB or single-file `.gltf` bytes;
//! - [`write`]: [`export`], the entry point.

pub mod animation;
pub mod buffer;
pub mod container;
pub mod document;
pub mod keys;
pub mod write;

pub use container::Container;
pub use document::{ExportImage, ExportOptions, ExportReport};
pub use write::export;
