//! sinew-import turns the bytes of a source file (MS3D, glTF 2.0, OBJ, BVH) into a sinew [`Scene`].
//!
//! Every importer takes untrusted bytes: counts are checked against the bytes present before anything is
//! allocated, and every failure is an [`ImportError`] naming the file, the section and the byte offset,
//! line or JSON path. No input may panic.

pub mod error;

pub use error::{ImportError, Location};
pub use sinew_scene::Scene;
