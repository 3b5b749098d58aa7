//! Half-Life (GoldSrc) models: compiled MDL files (version 10) with their texture and sequence-group
//! companions, SMD files, and QC scripts compiled as studiomdl compiles them. Every path produces a
//! [`model::StudioModel`], which [`scene::build_scene`] turns into a sinew scene.

pub mod compile;
pub mod entry;
pub mod mdl;
pub mod model;
pub mod qc;
pub mod scene;
pub mod smd;
