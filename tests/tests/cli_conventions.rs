//! End-to-end tests of the conventions every command shares: help, usage errors, bad inputs and
//! outputs, exit codes. They run the built binary as a subprocess.
#![allow(clippy::unwrap_used)] // unwrap is fine in tests

use crate::common;

use common::{assert_one_line_error, sinew};
use std::path::Path;

#[test]
fn help_exits_0_with_an_example_for_every_command() {
    for args in [
        vec!["--help"],
        vec!["inspect", "--help"],
        vec!["completions", "--help"],
        vec!["help", "inspect"],
    ] {
        let run = sinew(&args);
        assert_eq!(run.code, 0, "{args:?}: {}", run.stderr);
        assert!(run.stdout.contains("Examples:"), "{args:?}: {}", run.stdout);
        assert!(run.stdout.contains("sinew "), "{args:?}: {}", run.stdout);
    }
    let run = sinew(["inspect", "--help"]);
    for option in ["--json", "--quiet", "--ms3d-position-keys", "--gltf-skin"] {
        assert!(run.stdout.contains(option), "inspect --help lacks {option}");
    }
}

#[test]
fn unknown_subcommand_and_bad_options_exit_2() {
    let run = sinew(["frobnicate"]);
    assert_eq!(run.code, 2);
    assert!(run.stderr.contains("frobnicate"), "{}", run.stderr);
    assert!(run.stdout.is_empty());

    let run = sinew(["inspect"]);
    assert_eq!(run.code, 2, "missing FILE argument");

    let run = sinew(["inspect", "x.bvh", "--ms3d-position-keys", "sideways"]);
    assert_eq!(run.code, 2);
    assert!(run.stderr.contains("sideways"), "{}", run.stderr);

    let run = sinew(["completions", "tcsh-ish"]);
    assert_eq!(run.code, 2);
}

#[test]
fn missing_file_exits_2_with_one_line_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nothing-here.ms3d");
    let run = sinew([Path::new("inspect"), &missing]);
    assert_one_line_error(&run, &missing);
    assert!(run.stderr.contains("no such file"), "{}", run.stderr);
    // --json does not change how errors are reported: stdout stays empty.
    let run = sinew([Path::new("inspect"), Path::new("--json"), &missing]);
    assert_one_line_error(&run, &missing);
}

#[test]
fn directory_exits_2_with_one_line_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    // A directory that even has a supported extension.
    let d = dir.path().join("looks-like.glb");
    std::fs::create_dir(&d).unwrap();
    let run = sinew([Path::new("inspect"), &d]);
    assert_one_line_error(&run, &d);
    assert!(run.stderr.contains("is a directory"), "{}", run.stderr);
}

#[test]
fn unsupported_extension_exits_2_with_one_line_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["model.fbx", "README", "archive.tar.gz"] {
        let f = dir.path().join(name);
        std::fs::write(&f, b"not a model").unwrap();
        let run = sinew([Path::new("inspect"), &f]);
        assert_one_line_error(&run, &f);
        assert!(run.stderr.contains("unsupported"), "{}", run.stderr);
    }
}

#[test]
fn garbage_in_a_supported_extension_exits_2_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in [
        ("junk.ms3d", &b"MS3D000000\x04\x00\x00\x00\xff\xff"[..]),
        ("junk.glb", &b"glTF\x02\x00\x00\x00\x10\x00\x00\x00"[..]),
        ("junk.bvh", &b"HIERARCHY\nROOT\n"[..]),
        ("junk.sinew", &b"\x00\x01\x02"[..]),
    ] {
        let f = dir.path().join(name);
        std::fs::write(&f, bytes).unwrap();
        let run = sinew([Path::new("inspect"), &f]);
        assert_one_line_error(&run, &f);
    }
}

#[test]
fn quiet_and_json_flags_are_accepted_before_or_after_the_subcommand() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("a.bvh");
    for args in [
        vec![
            "--quiet".into(),
            "inspect".into(),
            missing.clone().into_os_string(),
        ],
        vec![
            "inspect".into(),
            missing.clone().into_os_string(),
            "-q".into(),
        ],
        vec![
            "--json".into(),
            "inspect".into(),
            missing.clone().into_os_string(),
        ],
    ] {
        let run = sinew::<_, std::ffi::OsString>(args);
        // Errors are still printed under --quiet.
        assert_one_line_error(&run, &missing);
    }
}

#[test]
fn completions_print_a_script_naming_the_subcommands() {
    for shell in ["bash", "zsh", "fish", "powershell", "elvish"] {
        let run = sinew(["completions", shell]);
        assert_eq!(run.code, 0, "{shell}: {}", run.stderr);
        assert!(
            run.stdout.contains("inspect"),
            "{shell} script lacks inspect"
        );
        assert!(
            run.stdout.contains("completions"),
            "{shell} script lacks completions"
        );
    }
}
