//! sinew-testdata tells tests where the shared corpus and the committed fixtures are, measures
//! geometry independently of the code under test ([`geometry`]) and writes small glTF documents
//! whose every value a test states ([`gltf_doc`]).
//!
//! The corpus is found through `SINEW_CORPUS`, else `../shared/corpus` beside the workspace root. When it
//! is missing, [`corpus`] returns `None` so tests can say so and skip, except under CI (`CI` set), where
//! it panics: CI must never pass by skipping.

pub mod geometry;
pub mod gltf_doc;

use std::path::{Path, PathBuf};

/// The workspace root.
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The committed fixtures folder.
pub fn fixtures() -> PathBuf {
    workspace_root().join("fixtures")
}

/// The shared corpus folder, or `None` (with a note on stderr) when it is absent outside CI.
pub fn corpus() -> Option<PathBuf> {
    let dir = match std::env::var_os("SINEW_CORPUS") {
        Some(d) => PathBuf::from(d),
        None => workspace_root().join("../shared/corpus"),
    };
    if dir.join("MANIFEST.tsv").is_file() {
        return Some(dir);
    }
    if std::env::var_os("CI").is_some() {
        panic!(
            "corpus not found at {} and CI is set: corpus tests must not skip",
            dir.display()
        );
    }
    eprintln!(
        "corpus not found at {}: skipping corpus test",
        dir.display()
    );
    None
}

/// A file inside the corpus, e.g. `corpus_file("ms3d/cross.ms3d")`, or `None` as for [`corpus`].
pub fn corpus_file(relative: &str) -> Option<PathBuf> {
    let path = corpus()?.join(relative);
    assert!(path.is_file(), "corpus file {} is missing", path.display());
    Some(path)
}

/// Reads a corpus file, or `None` as for [`corpus`].
pub fn read_corpus(relative: &str) -> Option<Vec<u8>> {
    let path = corpus_file(relative)?;
    Some(std::fs::read(&path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display())))
}
