//! The integration tests of this package, one module per file beside this one, linked into one test
//! binary: one link of the whole stack instead of one per file (CI time, docs/architecture.md). A new
//! file is added here as a `mod` line; `memory_bound.rs` (a global allocator) is a binary of its own.
mod cli_atomic;
mod cli_bake;
mod cli_ci_batches;
mod cli_compress_masks;
mod cli_conventions;
mod cli_convert;
mod cli_convert_timings;
mod cli_corpus_inspect;
mod cli_export;
mod cli_halflife;
mod cli_inspect_pose;
mod cli_inspect_sections;
mod cli_pictures;
mod cli_retarget_floor;
mod common;
mod export_any_rate;
mod export_blender;
mod gltf_simpleskin_threejs;
mod layout;
mod ms3d_unassigned;
mod pipeline_bake;
mod pipeline_compress_corpus;
mod pipeline_lod_corpus;
mod pipeline_lod_parts;
mod pipeline_lod_thin;
mod pipeline_sample_into;
mod report_html_browser;
mod tools_blender_check;
