//! What a CI job converting real folders needs from `convert` (issue 32): nothing passes silently
//! (an input with nothing to convert, missing Half-Life companions, files the folder walk passes
//! over, orphaned companions), `--strict` holds a folder to zero warnings, and `--incremental`
//! redoes exactly the inputs whose files changed, with outputs byte-identical to a full run.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common;

use common::{assert_one_line_error, sinew};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn corpus(rel: &str) -> Option<PathBuf> {
    sinew_testdata::corpus_file(rel)
}

/// Copies corpus files into `dir` (under their file names).
fn copy_in(dir: &Path, rels: &[&str]) -> Option<()> {
    for rel in rels {
        let src = corpus(rel)?;
        std::fs::copy(&src, dir.join(src.file_name().unwrap())).unwrap();
    }
    Some(())
}

/// `sinew --json convert ARGS...`: exit code, report (or Null), stderr.
fn convert(args: &[&std::ffi::OsStr]) -> (i32, Value, String) {
    let mut all: Vec<&std::ffi::OsStr> = vec!["--json".as_ref(), "convert".as_ref()];
    all.extend_from_slice(args);
    let r = sinew(all);
    let v = if r.stdout.is_empty() {
        Value::Null
    } else {
        serde_json::from_str(&r.stdout).unwrap()
    };
    (r.code, v, r.stderr)
}

/// Input file name -> status, from a report.
fn statuses(v: &Value) -> BTreeMap<String, String> {
    v["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let name = Path::new(f["input"].as_str().unwrap())
                .file_name()
                .unwrap()
                .to_string_lossy()
                .into_owned();
            (name, f["status"].as_str().unwrap().to_string())
        })
        .collect()
}

/// Every file under `dir` (relative path -> bytes), the incremental record excepted.
fn tree(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.file_name().unwrap() == ".sinew-incremental" {
                continue;
            }
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let rel = p.strip_prefix(root).unwrap().to_path_buf();
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// The report of a run whose incremental records were ignored, for a reason naming `why`.
fn assert_ignored(v: &Value, why: &str) {
    assert_eq!(v["incremental"]["state"], "ignored");
    assert!(
        v["incremental"]["reason"].as_str().unwrap().contains(why),
        "{v}"
    );
}

#[test]
fn an_input_with_nothing_to_convert_is_exit_2_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let gltf = dir.path().join("empty.gltf");
    std::fs::write(&gltf, r#"{"asset":{"version":"2.0"}}"#).unwrap();
    let smd = dir.path().join("bare.smd");
    std::fs::write(&smd, "version 1\nnodes\nend\n").unwrap();
    for input in [&gltf, &smd] {
        let out = dir.path().join("x.sinew");
        let r = sinew([
            "convert".as_ref(),
            input.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ]);
        assert_one_line_error(&r, input);
        assert!(r.stderr.contains("nothing to convert"), "{}", r.stderr);
        assert!(!out.exists());
    }
    // In a batch each fails like any bad file, and the run exits 1.
    let out = dir.path().join("out");
    let (code, v, _) = convert(&[
        gltf.as_os_str(),
        smd.as_os_str(),
        "--out-dir".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(code, 1);
    assert_eq!(
        (v["inputs"].as_u64(), v["failed"].as_u64()),
        (Some(2), Some(2))
    );
    // The real empty glTF of the corpus too.
    if let Some(empty) = corpus("gltf/magnum/empty.glb") {
        let r = sinew([
            "convert".as_ref(),
            empty.as_os_str(),
            "-o".as_ref(),
            dir.path().join("e.sinew").as_os_str(),
        ]);
        assert_one_line_error(&r, &empty);
        assert!(r.stderr.contains("nothing to convert"), "{}", r.stderr);
    }
}

/// A QC over the corpus's holy grail SMD: `$body studio "holy_grailref"`, a second body part
/// `lid_ref` on line 4, and a sequence on the reference.
const GRAIL_QC: &str = "$modelname \"grail.mdl\"\n$cd \".\"\n$body studio \"holy_grailref\"\n$body lid \"lid_ref\"\n$sequence idle \"holy_grailref\" fps 10\n";

#[test]
fn missing_qc_smds_stop_with_file_line_and_command_unless_allowed() {
    let dir = tempfile::tempdir().unwrap();
    let qc = dir.path().join("grail.qc");
    std::fs::write(&qc, GRAIL_QC).unwrap();
    let out = dir.path().join("grail.sinew");
    let run = |extra: &[&str]| {
        let mut a: Vec<&std::ffi::OsStr> = vec![qc.as_os_str(), "-o".as_ref(), out.as_os_str()];
        a.extend(extra.iter().map(|s| std::ffi::OsStr::new(*s)));
        convert(&a)
    };
    // None of its SMDs is there: studiomdl stops at the first it cannot open, and so does sinew,
    // with or without --allow-missing.
    for extra in [&[][..], &["--allow-missing"]] {
        let (code, v, err) = run(extra);
        assert_eq!((code, v), (2, Value::Null), "{err}");
        let line = err.lines().next().unwrap();
        assert!(
            line.starts_with(&format!(
                "sinew: error: {}: $body at line 3: cannot read holy_grailref.smd",
                qc.display()
            )),
            "{line}"
        );
        assert!(!out.exists());
    }
    // Some are there (the reference), one is not (the lid, line 4): an error by default...
    let Some(()) = copy_in(dir.path(), &["smd/holy_grailref.smd"]) else {
        return;
    };
    let (code, _, err) = run(&[]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(&format!(
            "{}: $body at line 4: cannot read lid_ref.smd",
            qc.display()
        )),
        "{err}"
    );
    assert!(err.contains("--allow-missing"), "{err}");
    assert!(!out.exists());
    // ... and today's warning with --allow-missing: the model without its lid.
    let (code, v, err) = run(&["--allow-missing"]);
    assert_eq!(code, 0, "{err}");
    let f = &v["files"][0];
    assert_eq!(f["warnings"], 1);
    assert_eq!(
        f["diagnostics"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|d| d["code"] == "qc-missing-smd")
            .count(),
        1
    );
    assert_eq!(f["meshes"].as_array().unwrap().len(), 1);
    assert_eq!(v["warning_codes"]["qc-missing-smd"], 1);
    assert!(out.exists());
    // An MDL without its texture file is refused the same way (man.mdl keeps them in manT.mdl).
    let Some(()) = copy_in(dir.path(), &["mdl/man.mdl"]) else {
        return;
    };
    let mdl = dir.path().join("man.mdl");
    let r = sinew([
        "convert".as_ref(),
        mdl.as_os_str(),
        "-o".as_ref(),
        dir.path().join("man.sinew").as_os_str(),
    ]);
    assert_one_line_error(&r, &mdl);
    assert!(
        r.stderr.contains("textures at byte 180") && r.stderr.contains("manT.mdl"),
        "{}",
        r.stderr
    );
}

#[test]
fn the_folder_walk_lists_every_file_it_passes_over_and_orphans_fail_the_batch() {
    let dir = tempfile::tempdir().unwrap();
    let models = dir.path().join("models");
    std::fs::create_dir_all(&models).unwrap();
    let Some(()) = copy_in(
        &models,
        &["mdl/manT.mdl", "mdl/man01.mdl", "smd/triangle.smd"],
    ) else {
        return;
    };
    std::fs::write(models.join("README.txt"), "models for the mod\n").unwrap();
    std::fs::write(models.join("icon.png"), b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR").unwrap();
    let out = dir.path().join("out");
    let (code, v, err) = convert(&[models.as_os_str(), "--out-dir".as_ref(), out.as_os_str()]);
    assert_eq!(code, 1, "{err}");
    assert_eq!(
        (
            v["inputs"].as_u64(),
            v["converted"].as_u64(),
            v["failed"].as_u64()
        ),
        (Some(1), Some(1), Some(0))
    );
    assert_eq!(v["orphans"], 2);
    let skipped: Vec<(String, String, Value)> = v["skipped"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            let file = Path::new(s["file"].as_str().unwrap())
                .file_name()
                .unwrap()
                .to_string_lossy()
                .into_owned();
            (
                file,
                s["reason"].as_str().unwrap().to_string(),
                s["model"].clone(),
            )
        })
        .collect();
    let orphan = "orphaned-companion".to_string();
    assert_eq!(
        skipped,
        [
            ("README.txt".into(), "not-a-model".into(), Value::Null),
            ("icon.png".into(), "not-a-model".into(), Value::Null),
            ("man01.mdl".into(), orphan.clone(), Value::Null),
            ("manT.mdl".into(), orphan, Value::Null),
        ]
    );
    // Each orphan is an error line naming it and the model it wants.
    for name in ["man01.mdl", "manT.mdl"] {
        let line = err
            .lines()
            .find(|l| l.contains(name))
            .unwrap_or_else(|| panic!("{err}"));
        assert!(
            line.starts_with("sinew: error: ") && line.contains("(man.mdl) is missing"),
            "{line}"
        );
    }
    // With its model, they are its companions and the batch passes.
    let Some(()) = copy_in(&models, &["mdl/man.mdl"]) else {
        return;
    };
    let (code, v, err) = convert(&[models.as_os_str(), "--out-dir".as_ref(), out.as_os_str()]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        (v["inputs"].as_u64(), v["orphans"].as_u64()),
        (Some(2), Some(0))
    );
    let man = models.join("man.mdl").display().to_string();
    let companions: Vec<&Value> = v["skipped"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["reason"] == "companion")
        .collect();
    assert_eq!(companions.len(), 2);
    assert!(
        companions.iter().all(|s| s["model"] == man.as_str()),
        "{companions:?}"
    );
}

#[test]
fn strict_fails_every_input_with_a_warning_and_writes_nothing_for_it() {
    let dir = tempfile::tempdir().unwrap();
    // cube_mtllib_after_g.obj names a material library it does not ship (warnings); triangle.smd
    // and man.mdl (with its companions) convert cleanly.
    let inputs = [
        "obj/cube_mtllib_after_g.obj",
        "smd/triangle.smd",
        "mdl/man.mdl",
        "mdl/manT.mdl",
        "mdl/man01.mdl",
    ];
    let models = dir.path().join("models");
    std::fs::create_dir_all(&models).unwrap();
    let Some(()) = copy_in(&models, &inputs) else {
        return;
    };
    let out = dir.path().join("out");
    let (code, v, err) = convert(&[models.as_os_str(), "--out-dir".as_ref(), out.as_os_str()]);
    assert_eq!(code, 0, "{err}");
    let cube = v["files"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| {
            f["input"]
                .as_str()
                .unwrap()
                .ends_with("cube_mtllib_after_g.obj")
        })
        .unwrap()
        .clone();
    let n = cube["warnings"].as_u64().unwrap();
    let listed = cube["diagnostics"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|d| d["level"] == "warning")
        .count();
    assert!(n >= 1 && n as usize == listed, "{cube}");
    assert_eq!(v["warnings"].as_u64(), Some(n));
    assert_eq!(v["inputs_with_warnings"], 1);
    assert_eq!(v["strict"], false);
    let first_code = cube["diagnostics"]
        .as_array()
        .unwrap()
        .iter()
        .find(|d| d["level"] == "warning")
        .unwrap()["code"]
        .as_str()
        .unwrap()
        .to_string();
    assert!(v["warning_codes"][&first_code].as_u64().unwrap() >= 1);

    let strict_out = dir.path().join("strict");
    let (code, v, err) = convert(&[
        models.as_os_str(),
        "--out-dir".as_ref(),
        strict_out.as_os_str(),
        "--strict".as_ref(),
    ]);
    assert_eq!(code, 1, "{err}");
    assert_eq!(v["strict"], true);
    assert_eq!(
        statuses(&v),
        BTreeMap::from([
            ("cube_mtllib_after_g.obj".to_string(), "failed".to_string()),
            ("man.mdl".to_string(), "converted".to_string()),
            ("triangle.smd".to_string(), "converted".to_string()),
        ])
    );
    let failed = v["files"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["status"] == "failed")
        .unwrap();
    let e = failed["error"].as_str().unwrap();
    let obj = models.join("cube_mtllib_after_g.obj");
    assert!(
        e.starts_with(&format!("{}: --strict: {n} warning", obj.display())),
        "{e}"
    );
    assert!(e.contains(&format!("[{first_code}]")), "{e}");
    assert_eq!(failed["warnings"].as_u64(), Some(n));
    assert!(
        err.lines().any(|l| l == format!("sinew: error: {e}")),
        "{err}"
    );
    // Nothing was written for it; the others were.
    assert!(!strict_out.join("cube_mtllib_after_g.sinew").exists());
    assert!(strict_out.join("triangle.sinew").exists() && strict_out.join("man.sinew").exists());
    // One input with -o: exit 1 with the report, nothing written.
    let one = dir.path().join("one.sinew");
    let (code, v, err) = convert(&[
        obj.as_os_str(),
        "-o".as_ref(),
        one.as_os_str(),
        "--strict".as_ref(),
    ]);
    assert_eq!(code, 1, "{err}");
    assert_eq!(v["files"][0]["status"], "failed");
    assert!(!one.exists());
}

/// Changes one texel of the first texture of a GoldSrc texture file (still a valid file).
fn touch_texel(t_mdl: &Path) {
    let mut b = std::fs::read(t_mdl).unwrap();
    let at = |o: usize| i32::from_le_bytes(b[o..o + 4].try_into().unwrap()) as usize;
    let texture = at(184); // textureindex; each texture: name[64], flags, width, height, index
    let pixels = at(texture + 76);
    b[pixels] = b[pixels].wrapping_add(1);
    std::fs::write(t_mdl, b).unwrap();
}

#[test]
fn incremental_redoes_exactly_the_changed_models_and_matches_a_full_run() {
    let dir = tempfile::tempdir().unwrap();
    let models = dir.path().join("models");
    std::fs::create_dir_all(models.join("props")).unwrap();
    let rels = [
        "mdl/man.mdl",
        "mdl/manT.mdl",
        "mdl/man01.mdl",
        "mdl/chrome_sphere.mdl",
        "ms3d/cross.ms3d",
        "bvh/test_simple.bvh",
    ];
    let Some(()) = copy_in(&models, &rels) else {
        return;
    };
    let Some(()) = copy_in(&models.join("props"), &["smd/holy_grailref.smd"]) else {
        return;
    };
    let lid = std::fs::read_to_string(corpus("smd/triangle.smd").unwrap()).unwrap();
    std::fs::write(models.join("props/lid_ref.smd"), &lid).unwrap();
    std::fs::write(models.join("props/grail.qc"), GRAIL_QC).unwrap();
    let out = dir.path().join("out");
    let inc = |out: &Path| {
        convert(&[
            models.as_os_str(),
            "--out-dir".as_ref(),
            out.as_os_str(),
            "--incremental".as_ref(),
            "--lod".as_ref(),
            "0.5".as_ref(),
        ])
    };
    let all = |s: &str| -> BTreeMap<String, String> {
        [
            "chrome_sphere.mdl",
            "cross.ms3d",
            "grail.qc",
            "man.mdl",
            "test_simple.bvh",
        ]
        .iter()
        .map(|n| (n.to_string(), s.to_string()))
        .collect()
    };

    let (code, first, err) = inc(&out);
    assert_eq!(code, 0, "{err}");
    assert_eq!(statuses(&first), all("converted"));
    assert_eq!(first["incremental"]["state"], "new");
    let written = tree(&out);
    assert!(
        written.contains_key(Path::new("man_Material1.png")),
        "{:?}",
        written.keys()
    );

    // Nothing changed: everything reused, reported as the run that wrote it reported it.
    let (code, second, err) = inc(&out);
    assert_eq!(code, 0, "{err}");
    assert_eq!(statuses(&second), all("reused"));
    assert_eq!(second["incremental"]["state"], "used");
    for (a, b) in first["files"]
        .as_array()
        .unwrap()
        .iter()
        .zip(second["files"].as_array().unwrap())
    {
        let strip = |f: &Value| {
            let mut f = f.as_object().unwrap().clone();
            f.remove("status");
            f
        };
        assert_eq!(strip(a), strip(b));
    }
    assert_eq!(tree(&out), written);

    // One SMD under the QC changes: exactly the QC is redone.
    std::fs::write(
        models.join("props/lid_ref.smd"),
        lid.replace("0  1.0 1.0 0.0", "0  1.0 2.0 0.0"),
    )
    .unwrap();
    let (code, v, err) = inc(&out);
    assert_eq!(code, 0, "{err}");
    let mut want = all("reused");
    want.insert("grail.qc".into(), "converted".into());
    assert_eq!(statuses(&v), want);
    // The texture file of man.mdl changes: exactly man.mdl is redone.
    touch_texel(&models.join("manT.mdl"));
    let (code, v, err) = inc(&out);
    assert_eq!(code, 0, "{err}");
    let mut want = all("reused");
    want.insert("man.mdl".into(), "converted".into());
    assert_eq!(statuses(&v), want);
    let after = tree(&out);
    assert_ne!(
        after[Path::new("man_Material2.png")],
        written[Path::new("man_Material2.png")]
    );
    assert_ne!(
        after[Path::new("props/grail.sinew")],
        written[Path::new("props/grail.sinew")]
    );

    // Byte for byte what a fresh full run writes.
    let fresh = dir.path().join("fresh");
    let (code, _, err) = convert(&[
        models.as_os_str(),
        "--out-dir".as_ref(),
        fresh.as_os_str(),
        "--lod".as_ref(),
        "0.5".as_ref(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(tree(&fresh), after);

    // Other options: everything is redone.
    let (_, v, _) = convert(&[
        models.as_os_str(),
        "--out-dir".as_ref(),
        out.as_os_str(),
        "--incremental".as_ref(),
    ]);
    assert_eq!(statuses(&v), all("converted"));
}

#[test]
fn a_corrupt_or_foreign_record_means_a_full_run_never_a_wrong_reuse() {
    let dir = tempfile::tempdir().unwrap();
    let models = dir.path().join("models");
    std::fs::create_dir_all(&models).unwrap();
    let Some(()) = copy_in(
        &models,
        &[
            "mdl/chrome_sphere.mdl",
            "ms3d/cross.ms3d",
            "smd/triangle.smd",
        ],
    ) else {
        return;
    };
    let out = dir.path().join("out");
    let inc = || {
        convert(&[
            models.as_os_str(),
            "--out-dir".as_ref(),
            out.as_os_str(),
            "--incremental".as_ref(),
            "--lod".as_ref(),
            "none".as_ref(),
        ])
    };
    let (code, _, err) = inc();
    assert_eq!(code, 0, "{err}");
    let written = tree(&out);
    let record = out.join(".sinew-incremental/cross.sinew.json");
    let text = std::fs::read_to_string(&record).unwrap();
    let r: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(r["format"], "sinew-incremental-record");
    assert_eq!(
        r["reads"][0]["path"].as_str().unwrap(),
        models.join("cross.ms3d").display().to_string()
    );

    // Truncated: ignored, every input converted, the same bytes.
    std::fs::write(&record, &text[..text.len() / 2]).unwrap();
    let (code, v, err) = inc();
    assert_eq!(code, 0, "{err}");
    assert_ignored(&v, "cross.sinew.json: corrupt");
    assert!(statuses(&v).values().all(|s| s == "converted"));
    assert_eq!(tree(&out), written);

    // The input changes and someone edits the record to claim it did not (without its checksum):
    // refused as corrupt, never a reuse of the old output.
    let ms3d = models.join("cross.ms3d");
    let mut bytes = std::fs::read(&ms3d).unwrap();
    let original = bytes.clone();
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    std::fs::write(&ms3d, &bytes).unwrap();
    let text = std::fs::read_to_string(&record).unwrap();
    let mut r: Value = serde_json::from_str(&text).unwrap();
    r["reads"][0]["blake3"] = blake3_hex_via_sinew(&ms3d, dir.path()).into();
    std::fs::write(&record, serde_json::to_string_pretty(&r).unwrap()).unwrap();
    let (_, v, _) = inc();
    assert_ignored(&v, "checksum");
    std::fs::write(&ms3d, &original).unwrap();

    // Another tool's JSON in its place: foreign, ignored.
    std::fs::write(&record, r#"{"format":"someone-else","files":[]}"#).unwrap();
    let (code, v, err) = inc();
    assert_eq!(code, 0, "{err}");
    assert_ignored(&v, "not a sinew record");
    assert!(statuses(&v).values().all(|s| s == "converted"));
    assert_eq!(tree(&out), written);
    // And the records written by that full run are good again.
    let (_, v, _) = inc();
    assert!(statuses(&v).values().all(|s| s == "reused"), "{v}");
}

/// The BLAKE3 of a file as sinew's own record writes it: convert it alone incrementally and read
/// the digest back from that record (the test does not hash by itself).
fn blake3_hex_via_sinew(file: &Path, scratch: &Path) -> String {
    let out = scratch.join("digest");
    let target = out.join("x.sinew");
    std::fs::create_dir_all(&out).unwrap();
    let (code, _, err) = convert(&[
        file.as_os_str(),
        "-o".as_ref(),
        target.as_os_str(),
        "--incremental".as_ref(),
        "--lod".as_ref(),
        "none".as_ref(),
    ]);
    assert_eq!(code, 0, "{err}");
    let r: Value = serde_json::from_str(
        &std::fs::read_to_string(out.join(".sinew-incremental/x.sinew.json")).unwrap(),
    )
    .unwrap();
    r["reads"][0]["blake3"].as_str().unwrap().to_string()
}
