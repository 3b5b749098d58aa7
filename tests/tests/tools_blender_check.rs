//! `tools/blender_check_cache.py` without Blender: its `--read-only` mode reads the OBJ and the PC2 /
//! MDD that `sinew bake` writes (the same readers its Blender check uses) and must agree with the
//! bake on the counts and the first point, and refuse a cache that does not match the mesh (exit 2).
//! Needs `python3` on PATH; without it the test says so and skips, except under CI.
#![allow(clippy::unwrap_used)]

use crate::common;
use common::sinew;
use std::path::Path;
use std::process::Command;

fn script() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tools/blender_check_cache.py")
}

fn python(args: &[&std::ffi::OsStr]) -> Option<(i32, String, String)> {
    match Command::new("python3").arg(script()).args(args).output() {
        Ok(o) => Some((
            o.status.code().unwrap(),
            String::from_utf8(o.stdout).unwrap(),
            String::from_utf8(o.stderr).unwrap(),
        )),
        Err(e) => {
            assert!(
                std::env::var_os("CI").is_none(),
                "python3 is needed under CI: {e}"
            );
            eprintln!("python3 not found ({e}); skipping");
            None
        }
    }
}

#[test]
fn the_blender_check_reads_what_bake_writes() {
    let biped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/biped.sinew");
    let dir = tempfile::tempdir().unwrap();
    let mut first_points = Vec::new();
    for format in ["pc2", "mdd"] {
        let out = dir.path().join(format!("walk.{format}"));
        let run = sinew([
            "bake".as_ref(),
            biped.as_os_str(),
            "--clip".as_ref(),
            "walk".as_ref(),
            "--format".as_ref(),
            format.as_ref(),
            "-q".as_ref(),
            "-o".as_ref(),
            out.as_os_str(),
        ]);
        assert_eq!(run.code, 0, "{}", run.stderr);
        let obj = dir.path().join(format!("walk.{format}.obj"));
        let Some((code, stdout, stderr)) =
            python(&["--read-only".as_ref(), obj.as_os_str(), out.as_os_str()])
        else {
            return;
        };
        assert_eq!(code, 0, "{stderr}");
        // The sidecar says how many frames and vertices the bake holds.
        let sidecar: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.path().join(format!("walk.{format}.json"))).unwrap(),
        )
        .unwrap();
        let want = format!(
            "{} {} frames x {} vertices;",
            format.to_uppercase(),
            sidecar["frame_count"],
            sidecar["vertex_count"]
        );
        assert!(stdout.starts_with(&want), "{stdout} vs {want}");
        first_points.push(
            stdout
                .split("first point")
                .nth(1)
                .unwrap()
                .trim()
                .to_string(),
        );
    }
    // PC2 is little-endian, MDD big-endian: the same first point from both.
    assert_eq!(first_points[0], first_points[1]);

    // A cache that does not match the mesh: exit 2, one line.
    let other = dir.path().join("prop.obj");
    std::fs::write(&other, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let pc2 = dir.path().join("walk.pc2");
    let (code, _, stderr) =
        python(&["--read-only".as_ref(), other.as_os_str(), pc2.as_os_str()]).unwrap();
    assert_eq!(code, 2);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    // A truncated cache: exit 2.
    let cut = dir.path().join("cut.pc2");
    let bytes = std::fs::read(&pc2).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() - 5]).unwrap();
    let obj = dir.path().join("walk.pc2.obj");
    let (code, _, stderr) =
        python(&["--read-only".as_ref(), obj.as_os_str(), cut.as_os_str()]).unwrap();
    assert_eq!(code, 2, "{stderr}");
}
