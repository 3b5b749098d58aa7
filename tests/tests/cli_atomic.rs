//! The output contract under pressure: files get the permissions a new file gets (the umask), two
//! processes writing one output never leave a torn file, and a batch killed at any moment leaves only
//! complete outputs.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_sinew-e2e")
}

fn fixture(rel: &str) -> std::path::PathBuf {
    sinew_testdata::fixtures().join(rel)
}

/// Runs the binary under a shell with the given umask.
#[cfg(unix)]
fn with_umask(mask: &str, args: &[&std::ffi::OsStr]) -> std::process::ExitStatus {
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg(format!("umask {mask}; exec \"$0\" \"$@\""))
        .arg(bin());
    cmd.args(args);
    cmd.stderr(Stdio::null()).status().unwrap()
}

#[cfg(unix)]
#[test]
fn outputs_honour_the_umask() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let src = fixture("biped.gltf");
    for (mask, mode) in [("022", 0o644), ("077", 0o600), ("002", 0o664)] {
        let out = dir.path().join(format!("b{mask}.sinew"));
        let s = with_umask(
            mask,
            &[
                "convert".as_ref(),
                src.as_os_str(),
                "-o".as_ref(),
                out.as_os_str(),
                "--lod".as_ref(),
                "none".as_ref(),
            ],
        );
        assert!(s.success());
        let got = std::fs::metadata(&out).unwrap().permissions().mode() & 0o777;
        assert_eq!(got, mode, "umask {mask}");
    }
}

fn is_complete_sinew(p: &Path) -> bool {
    std::fs::read(p).is_ok_and(|b| sinew_core::format::read(&b).is_ok())
}

#[test]
fn two_writers_of_one_output_never_tear_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("same.sinew");
    let a = fixture("biped.gltf");
    let b = fixture("prop.obj");
    // Reference outputs of each writer alone.
    let ref_a = dir.path().join("a.sinew");
    let ref_b = dir.path().join("b.sinew");
    for (src, o) in [(&a, &ref_a), (&b, &ref_b)] {
        assert!(Command::new(bin())
            .args(["--quiet", "convert"])
            .arg(src)
            .arg("-o")
            .arg(o)
            .status()
            .unwrap()
            .success());
    }
    let (want_a, want_b) = (
        std::fs::read(&ref_a).unwrap(),
        std::fs::read(&ref_b).unwrap(),
    );
    for _ in 0..12 {
        let mut kids: Vec<_> = [&a, &b]
            .iter()
            .map(|src| {
                Command::new(bin())
                    .args(["--quiet", "convert"])
                    .arg(src)
                    .arg("-o")
                    .arg(&out)
                    .spawn()
                    .unwrap()
            })
            .collect();
        // Read while they write: the file is absent or whole, never a part.
        for _ in 0..50 {
            if let Ok(bytes) = std::fs::read(&out) {
                assert!(
                    bytes == want_a || bytes == want_b,
                    "a torn file of {} bytes",
                    bytes.len()
                );
            }
        }
        for k in &mut kids {
            assert!(k.wait().unwrap().success());
        }
        let bytes = std::fs::read(&out).unwrap();
        assert!(bytes == want_a || bytes == want_b);
    }
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".sinew-tmp-"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[cfg(unix)]
#[test]
fn a_batch_killed_at_any_moment_leaves_only_complete_outputs() {
    let Some(corpus) = sinew_testdata::corpus() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    for (k, delay_ms) in [5u64, 20, 40, 80, 150, 300].into_iter().enumerate() {
        let out = dir.path().join(format!("run{k}"));
        let mut child = Command::new(bin())
            .args(["--quiet", "convert"])
            .arg(corpus.join("ms3d"))
            .arg(corpus.join("gltf"))
            .arg(corpus.join("mdl"))
            .arg("--out-dir")
            .arg(&out)
            .arg("--jobs")
            .arg("2")
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(delay_ms));
        let _ = child.kill(); // SIGKILL: no clean-up can run
        let _ = child.wait();
        let mut outputs = 0;
        if out.is_dir() {
            for e in std::fs::read_dir(&out).unwrap() {
                let p = e.unwrap().path();
                let name = p.file_name().unwrap().to_string_lossy().into_owned();
                if name.ends_with(".sinew") && !name.starts_with('.') {
                    outputs += 1;
                    assert!(
                        is_complete_sinew(&p),
                        "{} is not a complete file",
                        p.display()
                    );
                }
            }
        }
        eprintln!("killed after {delay_ms} ms: {outputs} complete outputs");
    }
}
