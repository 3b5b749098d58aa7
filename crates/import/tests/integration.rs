//! The integration tests of this package, one module per file beside this one, linked into one test
//! binary: one link of the whole stack instead of one per file (CI time, docs/architecture.md). A new
//! file is added here as a `mod` line.
mod bvh_corpus;
mod bvh_mutation;
mod fuzz_regressions;
mod gltf;
mod gltf_extensions;
mod gltf_meshopt;
mod gltf_panics;
mod gltf_spec_allows;
mod halflife_corpus;
mod halflife_fixture;
mod halflife_mutation;
mod halflife_qc_vs_mdl;
mod ms3d_corpus;
mod ms3d_fixtures;
mod ms3d_posed;
mod obj_corpus;
mod obj_mutation;
