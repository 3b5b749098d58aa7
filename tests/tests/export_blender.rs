//! What Blender shows of `sinew export`: Blender 3.4's glTF importer brings in every node of a file
//! whatever its scene, so the default export must hold the model alone. Runs
//! `tools/blender_gltf_check.py` in Blender when `blender` is on PATH (or `SINEW_BLENDER` names it);
//! otherwise it says so and skips (CI does not install Blender: it is 200 MB, and the other export
//! tests check the same file structure without it).
#![allow(clippy::unwrap_used)]

use crate::common;
use common::sinew;
use std::path::{Path, PathBuf};
use std::process::Command;

fn blender() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("SINEW_BLENDER") {
        return Some(PathBuf::from(p));
    }
    std::env::split_paths(&std::env::var_os("PATH")?)
        .map(|d| d.join("blender"))
        .find(|p| p.is_file())
}

#[test]
fn blender_imports_one_model_from_the_default_export() {
    let Some(man) = sinew_testdata::corpus_file("mdl/man.mdl") else {
        return;
    };
    let Some(blender) = blender() else {
        eprintln!("blender not found (set SINEW_BLENDER); skipping");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("man.glb");
    let r = sinew([
        "export".as_ref(),
        man.as_os_str(),
        "--lod".as_ref(),
        "0.5,0.25".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
        "-q".as_ref(),
    ]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tools/blender_gltf_check.py");
    let o = Command::new(blender)
        .args(["-b", "--factory-startup", "--python"])
        .arg(&script)
        .arg("--")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    let line = stdout
        .lines()
        .rev()
        .find(|l| l.starts_with('{'))
        .unwrap_or_else(|| {
            panic!(
                "no report from Blender: {stdout} {}",
                String::from_utf8_lossy(&o.stderr)
            )
        });
    let report: serde_json::Value = serde_json::from_str(line).unwrap();
    let names: Vec<&str> = report["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    // The default body (headless body and first head), no LODs, no other heads, one armature,
    // every clip as an action.
    assert_eq!(
        names,
        ["heads/reference_head1", "studio/reference_headless"],
        "{report}"
    );
    assert_eq!(report["armatures"].as_array().unwrap().len(), 1, "{report}");
    assert_eq!(report["actions"], 6, "{report}");
}
