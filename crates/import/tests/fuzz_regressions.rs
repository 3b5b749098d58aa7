//! Inputs the fuzzer found (fuzz/regressions/<target>/, minimised by libFuzzer), replayed through the
//! importers in an ordinary test build: no panic, no runaway allocation, and an error names the file. fuzz/run replay replays the same files through the instrumented targets.
#![allow(clippy::unwrap_used)]

use sinew_import::{import_bytes, Format, ImportOptions};
use std::path::Path;

/// Between the files of one fuzz input (fuzz/src/lib.rs); these regressions hold one file each.
const SEPARATOR: &[u8] = b"\n#sinew-fuzz-file#\n";

fn replay(target: &str, format: Format, name: &str) -> Vec<(String, Result<usize, String>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fuzz/regressions")
        .join(target);
    let mut out = Vec::new();
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .collect();
    files.sort();
    for path in files {
        let bytes = std::fs::read(&path).unwrap();
        assert!(
            !bytes.windows(SEPARATOR.len()).any(|w| w == SEPARATOR),
            "{}: companions are not replayed here",
            path.display()
        );
        let none = |_: &str| -> std::io::Result<Vec<u8>> { Err(std::io::Error::other("absent")) };
        // Companions are absent here: read on past them (a warning each), to reach what follows.
        let options = ImportOptions {
            allow_missing: true,
            ..ImportOptions::default()
        };
        let result = import_bytes(format, name, &bytes, &none, &options);
        let file = path.file_name().unwrap().to_string_lossy().to_string();
        match result {
            // Clips read: what a convert would go on with.
            Ok(scene) => out.push((file, Ok(scene.clips.len()))),
            Err(e) => {
                assert_eq!(e.file, name, "{e}");
                out.push((file, Err(e.to_string())));
            }
        }
    }
    out
}

/// The error of one regression file of `target` (replayed with the others, as `name`).
fn error_of(target: &str, format: Format, name: &str, file: &str) -> String {
    let results = replay(target, format, name);
    let (_, result) = results.into_iter().find(|(f, _)| f == file).unwrap();
    result.unwrap_err()
}

#[test]
fn an_mdl_without_bones_declaring_two_billion_frames_is_refused_before_allocating() {
    let e = error_of(
        "mdl",
        Format::Mdl,
        "m.mdl",
        "no_bones_two_billion_frames.mdl",
    );
    assert!(e.contains("more animation than sinew reads"), "{e}");
    assert!(e.contains("sequences["), "{e}");
}

#[test]
fn a_qc_sequence_option_that_is_not_utf8_is_read_as_an_option() {
    // `$sequence i"\xff\xff`: the option is not an activity; the script names no SMD, so nothing to read.
    let results = replay("qc", Format::Qc, "m.qc");
    assert_eq!(results.len(), 1);
    eprintln!("{results:?}");
    match &results[0].1 {
        Ok(clips) => assert_eq!(*clips, 0),
        Err(e) => assert!(e.starts_with("m.qc"), "{e}"),
    }
}

#[test]
fn a_gltf_with_a_key_that_is_not_utf8_is_refused_before_the_gltf_crate_sees_it() {
    // An unknown key with byte 0xFF, and a POSITION accessor that does not exist: gltf-json skipped the
    // key unchecked and then panicked on the index.
    let e = error_of("gltf", Format::Gltf, "m.gltf", "unknown_key_not_utf8.gltf");
    assert_eq!(e, "m.gltf: json at byte 65: JSON is not UTF-8");
}

#[test]
fn a_gltf_with_a_number_past_f64_in_an_unknown_key_is_refused_before_the_gltf_crate_sees_it() {
    // `"extent":1e999` in a node, and a POSITION accessor that does not exist: gltf-json skipped the
    // unknown key without reading the number, sinew's own pass (serde_json::Value) failed on it and
    // was skipped, and gltf-json panicked on the index (found by the glb target from gltfpack -c
    // seeds, session 27; minimised by hand).
    let file = "number_out_of_range_in_unknown_key.gltf";
    let e = error_of("gltf", Format::Gltf, "m.gltf", file);
    assert!(
        e.starts_with("m.gltf: nodes at nodes[0].extent: number out of range"),
        "{e}"
    );
}

#[test]
fn a_sinew_game_section_with_billions_of_empty_skin_families_is_refused() {
    // Checksums made consistent (the sinew fuzz target rewrites them so mutations reach the decoders).
    let results = replay("sinew", Format::Sinew, "m.sinew");
    assert_eq!(results.len(), 1);
    let e = results[0].1.as_ref().unwrap_err();
    assert!(e.contains("skin families without slots"), "{e}");
}
