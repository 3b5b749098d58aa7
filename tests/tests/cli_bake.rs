//! `sinew bake` and `sinew verify` end to end on corpus characters.
#![allow(clippy::unwrap_used)]

use crate::common;
use common::sinew;
use std::path::Path;

fn fox() -> Option<std::path::PathBuf> {
    sinew_testdata::corpus_file("gltf/Fox.glb")
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn pc2_bake_verifies_and_a_changed_float_fails_naming_frame_and_vertex() {
    let Some(fox) = fox() else { return };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fox.pc2");
    let r = sinew([
        "bake".as_ref(),
        fox.as_os_str(),
        "--clip".as_ref(),
        "Walk".as_ref(),
        "--format".as_ref(),
        "pc2".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
        "--json".as_ref(),
    ]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let report: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    let n = report["sidecar"]["frame_count"].as_u64().unwrap() as usize;
    let nv = report["sidecar"]["vertex_count"].as_u64().unwrap() as usize;
    assert_eq!(report["sidecar"]["clips"][0]["name"], "Walk");
    assert_eq!(
        names(dir.path()),
        ["fox.pc2", "fox.pc2.json", "fox.pc2.obj"]
    );
    let bytes = std::fs::read(&out).unwrap();
    assert_eq!(bytes.len(), 32 + n * nv * 12);
    // The OBJ has one `v` line per cache vertex.
    let obj = std::fs::read_to_string(dir.path().join("fox.pc2.obj")).unwrap();
    assert_eq!(obj.lines().filter(|l| l.starts_with("v ")).count(), nv);

    let verify = |p: &Path| {
        sinew([
            "verify".as_ref(),
            p.as_os_str(),
            "--against".as_ref(),
            fox.as_os_str(),
        ])
    };
    let ok = verify(&out);
    assert_eq!(ok.code, 0, "{}", ok.stderr);
    assert!(ok.stderr.contains("identical"), "{}", ok.stderr);

    // Change one float: frame 2, vertex 5, y.
    let mut bad = bytes.clone();
    let at = 32 + (2 * nv + 5) * 12 + 4;
    bad[at] ^= 0x10;
    std::fs::write(&out, &bad).unwrap();
    let r = verify(&out);
    assert_eq!(r.code, 1, "{}", r.stderr);
    assert!(r.stderr.contains("1 of"), "{}", r.stderr);
    assert!(r.stderr.contains("frame 2 vertex 5"), "{}", r.stderr);

    // Truncated: exit 2.
    std::fs::write(&out, &bytes[..bytes.len() - 7]).unwrap();
    let r = verify(&out);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("pc2"), "{}", r.stderr);
}

#[test]
fn exr_bake_verifies_and_truncated_exr_is_exit_2() {
    let Some(fox) = fox() else { return };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fox.exr");
    let r = sinew([
        "bake".as_ref(),
        fox.as_os_str(),
        "--layer".as_ref(),
        "Walk".as_ref(),
        "--layer".as_ref(),
        "Run:0.5".as_ref(),
        "--format".as_ref(),
        "exr".as_ref(),
        "--max-width".as_ref(),
        "500".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(
        names(dir.path()),
        [
            "fox-remap_info.json",
            "fox.exr",
            "fox.exr.obj",
            "fox_normals.exr"
        ]
    );
    let side: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("fox-remap_info.json")).unwrap())
            .unwrap();
    assert_eq!(side["layout"]["width"], 500);
    assert_eq!(side["encoding"], "offset-f16");
    assert_eq!(side["clips"][0]["name"], "Walk+Run");
    assert_eq!(side["os-remap"]["Frames"], side["frame_count"]);
    let r = sinew([
        "verify".as_ref(),
        out.as_os_str(),
        "--against".as_ref(),
        fox.as_os_str(),
    ]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let bytes = std::fs::read(&out).unwrap();
    std::fs::write(&out, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let r = sinew([
        "verify".as_ref(),
        out.as_os_str(),
        "--against".as_ref(),
        fox.as_os_str(),
    ]);
    assert_eq!(r.code, 2, "{}", r.stderr);
}

#[test]
fn bad_input_exits_2_and_writes_nothing() {
    let Some(fox) = fox() else { return };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.mdd");
    let run = |extra: &[&str]| {
        let mut args: Vec<std::ffi::OsString> = vec![
            "bake".into(),
            fox.clone().into(),
            "--format".into(),
            "mdd".into(),
            "-o".into(),
            out.clone().into(),
        ];
        args.extend(extra.iter().map(|s| s.into()));
        sinew(args)
    };
    let r = run(&["--clip", "Swim"]);
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("Survey, Walk, Run"), "{}", r.stderr);
    for fps in ["0", "-3", "NaN", "5000"] {
        let r = run(&["--fps", fps]);
        assert_eq!(r.code, 2, "fps {fps}: {}", r.stderr);
    }
    let r = run(&["--lod", "9"]);
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("LOD 9 does not exist"), "{}", r.stderr);
    let r = run(&["--layer", "Walk@upper"]);
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("no mask \"upper\""), "{}", r.stderr);
    assert!(names(dir.path()).is_empty(), "{:?}", names(dir.path()));
}

/// `sinew bake man.mdl --clip walk --format pc2 [extra] -o OUT --json`: the sidecar.
fn bake_man(man: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "bake".as_ref(),
        man.as_os_str(),
        "--clip".as_ref(),
        "walk".as_ref(),
        "--format".as_ref(),
        "pc2".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
        "--json".as_ref(),
    ];
    args.extend(extra.iter().map(|s| std::ffi::OsStr::new(*s)));
    let r = sinew(&args);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let report: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    report["sidecar"].clone()
}

fn verify(cache: &Path, against: &Path) -> common::Run {
    sinew([
        "verify".as_ref(),
        cache.as_os_str(),
        "--against".as_ref(),
        against.as_os_str(),
    ])
}

#[test]
fn bake_takes_the_default_body_or_a_body_number_and_verify_stays_exact() {
    // man.mdl: body part "studio" (reference_headless, 40 source vertices) and "heads" with three
    // choices (8, 5 and 58 source vertices).
    let Some(man) = sinew_testdata::corpus_file("mdl/man.mdl") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("man.pc2");
    let s = bake_man(&man, &out, &["--vertex-order", "source"]);
    assert_eq!(s["meshes"], serde_json::json!([0, 1]));
    assert_eq!(
        s["mesh_names"],
        serde_json::json!(["studio/reference_headless", "heads/reference_head1"])
    );
    assert_eq!(s["vertex_count"], 40 + 8);
    let r = verify(&out, &man);
    assert_eq!(r.code, 0, "{}", r.stderr);
    // Body 2 (the third head) and an explicit list give what they name.
    let out2 = dir.path().join("man2.pc2");
    let s2 = bake_man(&man, &out2, &["--body", "2", "--vertex-order", "source"]);
    assert_eq!(s2["meshes"], serde_json::json!([0, 3]));
    assert_eq!(s2["vertex_count"], 40 + 58);
    assert_eq!(verify(&out2, &man).code, 0);
    let out3 = dir.path().join("man3.pc2");
    let s3 = bake_man(&man, &out3, &["--mesh", "heads/reference_head2,0"]);
    assert_eq!(s3["meshes"], serde_json::json!([2, 0]));
    assert_eq!(verify(&out3, &man).code, 0);
    // The OBJ beside the cache holds both meshes' triangles, one after the other.
    let obj = std::fs::read_to_string(dir.path().join("man2.pc2.obj")).unwrap();
    assert_eq!(
        obj.lines().filter(|l| l.starts_with("f ")).count(),
        60 + 112
    );
    // A sidecar claiming other meshes no longer matches the cache: verify refuses (exit 2).
    let side = dir.path().join("man2.pc2.json");
    let mut j: serde_json::Value = serde_json::from_slice(&std::fs::read(&side).unwrap()).unwrap();
    j["meshes"] = serde_json::json!([0, 1]);
    std::fs::write(&side, serde_json::to_vec(&j).unwrap()).unwrap();
    assert_eq!(verify(&out2, &man).code, 2);
    // A sidecar written before `meshes` existed (mesh 0 only) still verifies its cache.
    let out4 = dir.path().join("man4.pc2");
    bake_man(&man, &out4, &["--mesh", "0"]);
    let side4 = dir.path().join("man4.pc2.json");
    let mut j: serde_json::Value = serde_json::from_slice(&std::fs::read(&side4).unwrap()).unwrap();
    j.as_object_mut().unwrap().remove("meshes");
    j.as_object_mut().unwrap().remove("mesh_names");
    std::fs::write(&side4, serde_json::to_vec(&j).unwrap()).unwrap();
    assert_eq!(verify(&out4, &man).code, 0);
    // Body 3 does not exist: exit 2, one line naming the file.
    let bad = sinew([
        "bake".as_ref(),
        man.as_os_str(),
        "--format".as_ref(),
        "pc2".as_ref(),
        "-o".as_ref(),
        dir.path().join("x.pc2").as_os_str(),
        "--body".as_ref(),
        "3".as_ref(),
    ]);
    common::assert_one_line_error(&bad, &man);
}
