//! End-to-end: `sinew inspect` over the shared corpus. Expected values come from the corpus MANIFEST
//! notes or are counted here straight from the file bytes, never from sinew's own code.
//! The malformed files must fail cleanly.
#![allow(clippy::unwrap_used)] // unwrap is fine in tests

use crate::common;

use common::{assert_one_line_error, inspect_json, sinew};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn corpus_path(rel: &str) -> Option<PathBuf> {
    sinew_testdata::corpus_file(rel)
}

fn arr(v: &Value) -> &Vec<Value> {
    v.as_array().expect("JSON array")
}

fn u(v: &Value) -> u64 {
    v.as_u64().expect("JSON unsigned integer")
}

fn joint_names(r: &Value) -> Vec<String> {
    arr(&r["skeleton"]["joints"])
        .iter()
        .map(|j| j["name"].as_str().unwrap().to_string())
        .collect()
}

fn total_submeshes(r: &Value) -> usize {
    arr(&r["meshes"])
        .iter()
        .map(|m| arr(&m["submeshes"]).len())
        .sum()
}

/// Every file under `*/malformed/` fails with exit 2 and one line naming it. The one edge case that
/// is not an error by the corpus' own notes (non-finite normals) may instead import with a warning.
#[test]
fn every_malformed_corpus_file_exits_2_naming_the_file() {
    let Some(root) = sinew_testdata::corpus() else {
        return;
    };
    let mut seen = 0;
    let mut formats: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    formats.sort();
    for fmt in formats {
        let dir = fmt.join("malformed");
        if !dir.is_dir() {
            continue;
        }
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        for f in files {
            seen += 1;
            let run = sinew([Path::new("inspect"), &f]);
            let name = f.file_name().unwrap().to_str().unwrap();
            if name == "BoxWithInfinites.glb" && run.code == 0 {
                let r = inspect_json(&f, &[]);
                let warned = arr(&r["diagnostics"]).iter().any(|d| {
                    d["level"] == "warning"
                        && d["message"]
                            .as_str()
                            .unwrap()
                            .to_lowercase()
                            .contains("finite")
                });
                assert!(warned, "{name} imported without a non-finite warning");
                continue;
            }
            assert_one_line_error(&run, &f);
        }
    }
    // ms3d 1, gltf 7, obj 4, smd 1 (MANIFEST.tsv).
    assert_eq!(seen, 13, "malformed files found");
}

// ---------------------------------------------------------------- MS3D

/// What the test reads from an MS3D file by itself: triangle count, group count, joints
/// (name, parent name, rotation keys, position keys) and the animation fps.
struct Ms3dFacts {
    triangles: usize,
    groups: usize,
    fps: f32,
    joints: Vec<(String, String, usize, usize)>,
}

fn ms3d_facts(bytes: &[u8]) -> Ms3dFacts {
    let u16_at = |o: usize| u16::from_le_bytes([bytes[o], bytes[o + 1]]) as usize;
    let cstr = |o: usize, n: usize| {
        let s = &bytes[o..o + n];
        let end = s.iter().position(|&b| b == 0).unwrap_or(n);
        String::from_utf8_lossy(&s[..end]).into_owned()
    };
    assert_eq!(&bytes[..10], b"MS3D000000");
    let mut o = 14;
    let nv = u16_at(o);
    o += 2 + nv * 15;
    let nt = u16_at(o);
    o += 2 + nt * 70;
    let ng = u16_at(o);
    o += 2;
    for _ in 0..ng {
        o += 1 + 32;
        let n = u16_at(o);
        o += 2 + n * 2 + 1;
    }
    let nm = u16_at(o);
    o += 2 + nm * 361;
    let fps = f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
    o += 12;
    let nj = u16_at(o);
    o += 2;
    let mut joints = Vec::new();
    for _ in 0..nj {
        let name = cstr(o + 1, 32);
        let parent = cstr(o + 33, 32);
        o += 1 + 32 + 32 + 24;
        let nr = u16_at(o);
        let np = u16_at(o + 2);
        o += 4 + (nr + np) * 16;
        joints.push((name, parent, nr, np));
    }
    Ms3dFacts {
        triangles: nt,
        groups: ng,
        fps,
        joints,
    }
}

fn check_ms3d(rel: &str, expect_joints: usize, expect_tris: usize, expect_groups: usize) {
    let Some(path) = corpus_path(rel) else { return };
    let facts = ms3d_facts(&std::fs::read(&path).unwrap());
    // The independent reading agrees with MANIFEST.tsv ...
    assert_eq!(facts.joints.len(), expect_joints, "{rel}: joints in file");
    assert_eq!(facts.triangles, expect_tris, "{rel}: triangles in file");
    assert_eq!(facts.groups, expect_groups, "{rel}: groups in file");
    // ... and so does sinew.
    let r = inspect_json(&path, &[]);
    assert_eq!(r["format"], "ms3d");
    assert_eq!(u(&r["summary"]["triangles"]) as usize, expect_tris, "{rel}");
    assert_eq!(total_submeshes(&r), expect_groups, "{rel}: submeshes");
    assert_eq!(u(&r["summary"]["joints"]) as usize, expect_joints, "{rel}");
    if expect_joints == 0 {
        return;
    }
    let names = joint_names(&r);
    let mut want: Vec<String> = facts.joints.iter().map(|j| j.0.clone()).collect();
    let mut got = names.clone();
    want.sort();
    got.sort();
    assert_eq!(got, want, "{rel}: joint names");
    for j in arr(&r["skeleton"]["joints"]) {
        let name = j["name"].as_str().unwrap();
        let fact = facts.joints.iter().find(|f| f.0 == name).unwrap();
        let parent = j["parent_name"].as_str().unwrap_or("");
        assert_eq!(parent, fact.1, "{rel}: parent of {name}");
    }
    let keyed: Vec<&str> = facts
        .joints
        .iter()
        .filter(|j| j.2 + j.3 > 0)
        .map(|j| j.0.as_str())
        .collect();
    if !keyed.is_empty() {
        let clips = arr(&r["clips"]);
        assert!(!clips.is_empty(), "{rel}: keys but no clip");
        let c = &clips[0];
        assert_eq!(
            c["sample_rate"].as_f64().unwrap() as f32,
            facts.fps,
            "{rel}: fps"
        );
        let mut driven: Vec<&str> = arr(&c["driven_joints"])
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        driven.sort();
        let mut keyed = keyed.clone();
        keyed.sort();
        assert_eq!(driven, keyed, "{rel}: driven joints");
        assert_eq!(arr(&c["unmatched_joints"]).len(), 0, "{rel}: unmatched");
    }
    for m in arr(&r["meshes"]) {
        if let Some(h) = m["influences"].as_array() {
            let sum: u64 = h.iter().map(u).sum();
            assert_eq!(
                sum,
                u(&m["vertices"]),
                "{rel}: influence histogram covers every vertex"
            );
        }
    }
}

#[test]
fn inspect_ms3d_corpus() {
    // (file, joints, triangles, groups) from MANIFEST.tsv; groups of jeep1/Wuson/etc. as noted there.
    check_ms3d("ms3d/cross.ms3d", 9, 76, ms3d_groups("ms3d/cross.ms3d"));
    check_ms3d(
        "ms3d/animated_cylinder.ms3d",
        3,
        168,
        ms3d_groups("ms3d/animated_cylinder.ms3d"),
    );
    check_ms3d("ms3d/ninja.ms3d", 28, 1007, 2);
    check_ms3d("ms3d/zombie.ms3d", 19, 735, ms3d_groups("ms3d/zombie.ms3d"));
    check_ms3d(
        "ms3d/zombie02.ms3d",
        19,
        735,
        ms3d_groups("ms3d/zombie02.ms3d"),
    );
    check_ms3d("ms3d/jeep1.ms3d", 0, 2032, 7);
    check_ms3d("ms3d/Wuson.ms3d", 0, 3732, 1);
    check_ms3d("ms3d/twospheres_withmats.ms3d", 0, 240, 2);
}

/// Group count read independently, for files whose MANIFEST note does not give it.
fn ms3d_groups(rel: &str) -> usize {
    sinew_testdata::read_corpus(rel).map_or(0, |b| ms3d_facts(&b).groups)
}

#[test]
fn inspect_ms3d_human_report_shows_the_tree() {
    let Some(path) = corpus_path("ms3d/cross.ms3d") else {
        return;
    };
    let run = sinew([Path::new("inspect"), &path]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stdout.is_empty(), "human report must go to stderr");
    assert!(run.stderr.contains("skeleton: 9 joints"), "{}", run.stderr);
    let quiet = sinew([Path::new("inspect"), Path::new("--quiet"), &path]);
    assert_eq!(quiet.code, 0);
    assert!(quiet.stderr.is_empty() && quiet.stdout.is_empty());
}

// ---------------------------------------------------------------- OBJ

/// Triangles of an OBJ counted here: each `f` line with n corners gives n - 2 triangles.
fn obj_triangles(text: &str) -> usize {
    text.lines()
        .map(str::trim_start)
        .filter(|l| l.starts_with("f ") || l.starts_with("f\t"))
        .map(|l| l.split_whitespace().count().saturating_sub(3))
        .sum()
}

fn decode(bytes: &[u8]) -> String {
    if bytes.starts_with(&[0xFE, 0xFF]) {
        let units: Vec<u16> = bytes[2..]
            .chunks_exact(2)
            .map(|c| u16::from_be_bytes([c[0], c[1]]))
            .collect();
        return String::from_utf16(&units).unwrap();
    }
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn inspect_obj_corpus() {
    for rel in [
        "obj/spot.obj",
        "obj/cornell_box.obj",
        "obj/spider.obj",
        "obj/regr01.obj",
        "obj/cube_mtllib_after_g.obj",
        "obj/box_UTF16BE.obj",
        "obj/box_without_lineending.obj",
        "obj/testmixed.obj",
        "obj/number_formats.obj",
        "obj/skin-weight.obj",
    ] {
        let Some(path) = corpus_path(rel) else { return };
        let tris = obj_triangles(&decode(&std::fs::read(&path).unwrap()));
        let r = inspect_json(&path, &[]);
        assert_eq!(r["format"], "obj", "{rel}");
        assert_eq!(
            u(&r["summary"]["triangles"]) as usize,
            tris,
            "{rel}: triangles"
        );
        assert!(r["skeleton"].is_null(), "{rel}: OBJ has no skeleton");
        assert_eq!(arr(&r["clips"]).len(), 0, "{rel}");
    }
    // MANIFEST: spot.obj has 5856 triangles; cornell_box has 10 usemtl over 9 objects.
    let Some(spot) = corpus_path("obj/spot.obj") else {
        return;
    };
    assert_eq!(u(&inspect_json(&spot, &[])["summary"]["triangles"]), 5856);
    // testmixed.obj holds points and lines: they are ignored with a warning.
    let Some(mixed) = corpus_path("obj/testmixed.obj") else {
        return;
    };
    let r = inspect_json(&mixed, &[]);
    assert!(u(&r["summary"]["warnings"]) >= 1, "points/lines warning");
}

// ---------------------------------------------------------------- glTF

fn check_gltf(rel: &str, extra: &[&str], joints: u64, tris: u64, clips: &[&str]) -> Value {
    let path = corpus_path(rel).unwrap();
    let r = inspect_json(&path, extra);
    assert_eq!(r["format"], "gltf", "{rel}");
    assert_eq!(u(&r["summary"]["joints"]), joints, "{rel}: joints");
    assert_eq!(u(&r["summary"]["triangles"]), tris, "{rel}: triangles");
    let names: Vec<&str> = arr(&r["clips"])
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    if !clips.is_empty() {
        assert_eq!(names, clips, "{rel}: clip names");
    }
    for c in arr(&r["clips"]) {
        assert_eq!(
            arr(&c["unmatched_joints"]).len(),
            0,
            "{rel}: unmatched joints"
        );
    }
    r
}

#[test]
fn inspect_gltf_corpus() {
    if sinew_testdata::corpus().is_none() {
        return;
    }
    // (joints, triangles) from MANIFEST.tsv.
    let fox = check_gltf("gltf/Fox.glb", &[], 24, 576, &["Survey", "Walk", "Run"]);
    assert_eq!(
        fox["meshes"][0]["has_normals"], true,
        "Fox: normals generated"
    );
    check_gltf("gltf/CesiumMan.glb", &[], 19, 4672, &[]);
    check_gltf("gltf/RiggedFigure.glb", &[], 19, 256, &[]);
    check_gltf("gltf/RiggedSimple.glb", &[], 2, 188, &[]);
    check_gltf("gltf/SimpleSkin.gltf", &[], 2, 8, &[]);
    check_gltf("gltf/BoxTextured.glb", &[], 0, 12, &[]);
    check_gltf("gltf/SimpleSparseAccessor.gltf", &[], 0, 12, &[]);
    check_gltf("gltf/quad_skin.glb", &[], 10, 2, &[]);
    let anim = corpus_path("gltf/magnum/animation.glb").unwrap();
    assert_eq!(
        arr(&inspect_json(&anim, &[])["clips"]).len(),
        4,
        "magnum animation.glb"
    );
    // Two skins of 2 and 3 joints: --gltf-skin picks one.
    check_gltf("gltf/magnum/skin.glb", &["--gltf-skin", "0"], 2, 0, &[]);
    check_gltf("gltf/magnum/skin.glb", &["--gltf-skin", "1"], 3, 0, &[]);
}

// ---------------------------------------------------------------- BVH

/// Joint names (ROOT/JOINT lines), frame count and frame time, read here from the text.
fn bvh_facts(text: &str) -> (Vec<String>, usize, f64) {
    let mut names = Vec::new();
    let mut frames = 0;
    let mut frame_time = 0.0;
    for line in text.lines() {
        let l = line.trim();
        if let Some(rest) = l.strip_prefix("ROOT ").or_else(|| l.strip_prefix("JOINT ")) {
            names.push(rest.trim().to_string());
        } else if let Some(rest) = l.strip_prefix("Frames:") {
            frames = rest.trim().parse().unwrap();
        } else if let Some(rest) = l.strip_prefix("Frame Time:") {
            frame_time = rest.trim().parse().unwrap();
        }
    }
    (names, frames, frame_time)
}

#[test]
fn inspect_bvh_corpus() {
    // Joint counts per MANIFEST.tsv: 31, 31, 21, 31, 4, 2.
    for (rel, joints) in [
        ("bvh/cmu_01_01.bvh", 31),
        ("bvh/cmu_walk_crlf.bvh", 31),
        ("bvh/Boxing_Toes.bvh", 21),
        ("bvh/pfnn_hierarchy_crlf.bvh", 31),
        ("bvh/sinusoidal_xyz.bvh", 4),
        ("bvh/test_simple.bvh", 2),
    ] {
        let Some(path) = corpus_path(rel) else { return };
        let (names, frames, frame_time) =
            bvh_facts(&String::from_utf8_lossy(&std::fs::read(&path).unwrap()));
        assert_eq!(names.len(), joints, "{rel}: test's own count");
        let r = inspect_json(&path, &[]);
        assert_eq!(r["format"], "bvh");
        let got = joint_names(&r);
        for n in &names {
            assert!(got.contains(n), "{rel}: joint {n} missing from {got:?}");
        }
        let clips = arr(&r["clips"]);
        assert_eq!(clips.len(), 1, "{rel}: one clip");
        let c = &clips[0];
        assert_eq!(
            u(&c["key_times"]) as usize,
            frames,
            "{rel}: one key time per frame"
        );
        let duration = c["duration"].as_f64().unwrap();
        let want = (frames - 1) as f64 * frame_time;
        assert!(
            (duration - want).abs() < 1e-3,
            "{rel}: duration {duration} vs {want}"
        );
        let rate = c["sample_rate"].as_f64().unwrap();
        assert!((rate - 1.0 / frame_time).abs() < 0.01, "{rel}: rate {rate}");
        let mut driven: Vec<String> = arr(&c["driven_joints"])
            .iter()
            .map(|v| v.as_str().unwrap().into())
            .collect();
        driven.sort();
        let mut want_names = names.clone();
        want_names.sort();
        assert_eq!(driven, want_names, "{rel}: every BVH joint has channels");
        assert_eq!(arr(&c["unmatched_joints"]).len(), 0);
    }
}
