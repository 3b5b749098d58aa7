//! The reports commands print: JSON on stdout with `--json` (field names are a stable interface,
//! documented in docs/cli.md: add fields, never rename or remove them), human text on stderr.
//!
//! [`scene`] describes what a file holds (`inspect`, and the clip, mesh, LOD and diagnostic parts that
//! `convert`, `split` and `lod` print too); [`build`] fills it from an imported scene; [`text`] renders
//! reports for people; [`convert`] holds what `convert`, `split` and `lod` add.

pub mod build;
pub mod convert;
pub mod game;
pub mod html;
pub mod pose;
pub mod scene;
#[cfg(test)]
mod tests;
pub mod text;

pub use build::{add_encodings, build_report, clip_report, diag_report, mesh_report};
pub use convert::*;
pub use scene::*;
pub use text::{human, num, nums};
