//! glTF 2.0 importer (`.gltf` with external or data-URI buffers, and `.glb`).
//!
//! The JSON is parsed and validated by the gltf crate's document model ([`gltf::Document::from_json`],
//! after the extensions read here, KHR_mesh_quantization and EXT_meshopt_compression, are taken out
//! of `extensionsRequired`, and what the specification allows and the crate refuses made readable
//! first, `tolerate.rs`); the GLB container, buffers (meshopt-compressed views decoded) and
//! accessors are read by this module with every byte range checked
//! (see [`accessor`]). One skin becomes the scene skeleton ([`crate::ImportOptions::gltf_skin`]); animations
//! become linear-key clips ([`anim`]). docs/formats/gltf.md describes every decision.

pub mod accessor;
pub mod anim;
mod animation;
mod build;
mod document;
mod mesh;
mod meshopt;
mod refs;
mod skin;
mod tolerate;

pub use build::import;
pub use document::{embedded_images, json_path_at, skin_count, MAX_EMBEDDED_IMAGE};
pub use mesh::generate_normals;
