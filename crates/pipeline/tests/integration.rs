//! The integration tests of this package, one module per file beside this one, linked into one test
//! binary: one link of the whole stack instead of one per file (CI time, docs/architecture.md). A new
//! file is added here as a `mod` line.
mod cache_formats;
mod compress_format;
mod compress_kept_plain;
mod lod;
mod mapping_names;
mod mapping_props;
mod retarget_pose;
mod split_body;
