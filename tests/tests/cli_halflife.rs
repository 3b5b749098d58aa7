//! Half-Life models through the command line: convert (with textures), inspect, bake + verify bit for
//! bit, folders with companions, and the errors a CI job sees.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common;

use common::{assert_one_line_error, inspect_json, sinew};
use serde_json::Value;
use std::path::Path;

fn corpus(rel: &str) -> Option<std::path::PathBuf> {
    sinew_testdata::corpus_file(rel)
}

#[test]
fn convert_man_mdl_writes_textures_and_game_data() {
    let Some(mdl) = corpus("mdl/man.mdl") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("man.sinew");
    let r = sinew([
        "--json".as_ref(),
        "convert".as_ref(),
        mdl.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let v: Value = serde_json::from_str(&r.stdout).unwrap();
    let f = &v["files"][0];
    assert_eq!(f["format"], "mdl");
    assert_eq!(f["joints"], 8);
    let textures: Vec<String> = f["textures"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| {
            Path::new(t.as_str().unwrap())
                .file_name()
                .unwrap()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    assert_eq!(
        textures,
        [
            "man_Material2.png",
            "man_Material3.png",
            "man_Material1.png",
            "man_UpperBody_Yellow.png",
            "man_LowerBody_Purple.png"
        ]
    );
    // Each PNG is 28 or 32 pixels wide and 32 high (IHDR), as the texture file stores them.
    for (name, w) in [("man_Material1.png", 32), ("man_Material2.png", 28)] {
        let b = std::fs::read(dir.path().join(name)).unwrap();
        assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n");
        assert_eq!(u32::from_be_bytes([b[16], b[17], b[18], b[19]]), w);
        assert_eq!(u32::from_be_bytes([b[20], b[21], b[22], b[23]]), 32);
    }
    let i = inspect_json(&out, &[]);
    let game = &i["game"];
    assert_eq!(game["controllers"].as_array().unwrap().len(), 3);
    assert_eq!(game["controllers"][0]["channel"], "YR");
    assert_eq!(game["clips"][1]["clip"], "walk");
    assert_eq!(game["clips"][1]["activity_name"], "ACT_WALK");
    assert_eq!(game["clips"][1]["events"][1]["frame"], 13);
    assert_eq!(
        game["body_groups"][1]["choices"].as_array().unwrap().len(),
        3
    );
    assert_eq!(i["materials"][2]["texture"], "man_Material1.png");
    let tags: Vec<&str> = i["sections"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["tag"].as_str().unwrap())
        .collect();
    assert!(tags.contains(&"GAME"), "{tags:?}");

    // --no-textures: no PNG files, materials keep the texture names.
    let out2 = dir.path().join("plain/man.sinew");
    std::fs::create_dir_all(out2.parent().unwrap()).unwrap();
    let r = sinew([
        "convert".as_ref(),
        mdl.as_os_str(),
        "-o".as_ref(),
        out2.as_os_str(),
        "--no-textures".as_ref(),
    ]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let files: Vec<_> = std::fs::read_dir(out2.parent().unwrap()).unwrap().collect();
    assert_eq!(files.len(), 1);
    assert_eq!(
        inspect_json(&out2, &[])["materials"][2]["texture"],
        "Material1.bmp"
    );
}

#[test]
fn an_mdl_sequence_bakes_and_verifies_bit_for_bit() {
    let Some(mdl) = corpus("mdl/man.mdl") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("man.sinew");
    assert_eq!(
        sinew([
            "convert".as_ref(),
            mdl.as_os_str(),
            "-o".as_ref(),
            out.as_os_str()
        ])
        .code,
        0
    );
    for format in ["pc2", "mdd", "exr"] {
        let cache = dir.path().join(format!("walk.{format}"));
        let r = sinew([
            "bake".as_ref(),
            out.as_os_str(),
            "--clip".as_ref(),
            "walk".as_ref(),
            "--format".as_ref(),
            format.as_ref(),
            "-o".as_ref(),
            cache.as_os_str(),
        ]);
        assert_eq!(r.code, 0, "{format}: {}", r.stderr);
        let v = sinew([
            "verify".as_ref(),
            cache.as_os_str(),
            "--against".as_ref(),
            out.as_os_str(),
        ]);
        assert_eq!(v.code, 0, "{format}: {}", v.stderr);
        assert!(v.stderr.contains("identical"), "{}", v.stderr);
    }
    // Straight from the MDL too.
    let cache = dir.path().join("direct.pc2");
    let r = sinew([
        "bake".as_ref(),
        mdl.as_os_str(),
        "--clip".as_ref(),
        "arms_up.blend1".as_ref(),
        "--format".as_ref(),
        "pc2".as_ref(),
        "-o".as_ref(),
        cache.as_os_str(),
    ]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let v = sinew([
        "verify".as_ref(),
        cache.as_os_str(),
        "--against".as_ref(),
        mdl.as_os_str(),
    ]);
    assert_eq!(v.code, 0, "{}", v.stderr);
}

#[test]
fn a_folder_converts_every_model_once_into_a_new_mirrored_tree() {
    let Some(root) = sinew_testdata::corpus() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("does/not/exist");
    let r = sinew([
        "--json".as_ref(),
        "convert".as_ref(),
        root.join("mdl").as_os_str(),
        root.join("smd").as_os_str(),
        "--out-dir".as_ref(),
        out.as_os_str(),
        "--lod".as_ref(),
        "none".as_ref(),
    ]);
    let v: Value = serde_json::from_str(&r.stdout).unwrap();
    let entries: Vec<(String, String)> = v["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            (
                Path::new(f["input"].as_str().unwrap())
                    .strip_prefix(&root)
                    .unwrap()
                    .display()
                    .to_string(),
                f["status"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    // manT.mdl (textures only) and man01.mdl (IDSQ) are folded into man.mdl; malformed/empty.smd
    // has no `version` line, so nothing recognises it as a model and it is skipped.
    assert_eq!(
        entries,
        [
            ("mdl/alpha_test.mdl".to_string(), "converted".to_string()),
            ("mdl/chrome_sphere.mdl".into(), "converted".into()),
            ("mdl/man.mdl".into(), "converted".into()),
            ("mdl/sequence_transitions.mdl".into(), "converted".into()),
            ("smd/WusonSMD.smd".into(), "converted".into()),
            ("smd/holy_grailref.smd".into(), "converted".into()),
            ("smd/triangle.smd".into(), "converted".into()),
        ]
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(out.join("man.sinew").is_file());
    assert!(out.join("triangle.sinew").is_file());
    assert!(out.join("man_Material1.png").is_file());
}

#[test]
fn unreadable_models_fail_with_one_line_naming_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let mut source = vec![0u8; 300];
    source[..4].copy_from_slice(b"IDST");
    source[4..8].copy_from_slice(&48i32.to_le_bytes());
    let file = dir.path().join("v48.mdl");
    std::fs::write(&file, &source).unwrap();
    let out = dir.path().join("v48.sinew");
    let r = sinew([
        "convert".as_ref(),
        file.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(r.code, 2);
    assert_one_line_error(&r, &file);
    assert!(r.stderr.contains("version 48"), "{}", r.stderr);
    assert!(!out.exists());
    let qc = dir.path().join("loop.qc");
    std::fs::write(&qc, "$include \"loop.qc\"\n").unwrap();
    let r = sinew(["inspect".as_ref(), qc.as_os_str()]);
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains("includes itself") && r.stderr.contains("line 1"),
        "{}",
        r.stderr
    );
}
