//! The integration tests of this package, one module per file beside this one, linked into one test
//! binary: one link of the whole stack instead of one per file (CI time, docs/architecture.md). A new
//! file is added here as a `mod` line.
mod animator_paths;
mod format;
mod format_fuzz;
mod format_game;
mod format_support;
mod runtime;
mod skinning_paths;
