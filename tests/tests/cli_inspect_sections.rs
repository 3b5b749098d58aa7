//! `inspect --json` of a `.sinew` file lists its sections with sizes that add up to the file.
#![allow(clippy::unwrap_used)]

use std::process::Command;

#[test]
fn biped_sections_are_listed_in_file_order_and_fit_the_file() {
    let path = sinew_testdata::fixtures().join("biped.sinew");
    let out = Command::new(env!("CARGO_BIN_EXE_sinew-e2e"))
        .args(["inspect", "--json"])
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let sections = report["sections"].as_array().unwrap();
    let tags: Vec<&str> = sections
        .iter()
        .map(|s| s["tag"].as_str().unwrap())
        .collect();
    assert_eq!(
        tags,
        ["STRS", "SKEL", "MATL", "MESH", "CLIP", "SRCV", "MASK", "AXES"]
    );
    let len = std::fs::metadata(&path).unwrap().len();
    let mut end = 0;
    for s in sections {
        let (offset, size) = (s["offset"].as_u64().unwrap(), s["size"].as_u64().unwrap());
        // Sections follow each other, 16-byte aligned, after the 48-byte header and the table.
        assert!(offset >= end.max(48) && offset % 16 == 0, "{s}");
        assert!(s["checksum_ok"].as_bool().unwrap() && s["known"].as_bool().unwrap());
        end = offset + size;
    }
    assert!(
        end <= len && len - end < 16,
        "sections end at {end}, file has {len} bytes"
    );
    // The mesh dominates: 735 vertices x (pos 12 + normal 12 + uv 8 + joints 8 + weights 16) alone.
    let mesh = sections.iter().find(|s| s["tag"] == "MESH").unwrap();
    assert!(mesh["size"].as_u64().unwrap() >= 735 * 56);
}
