//! End to end: clip compression in `convert`, channel encodings and masks in `inspect`, and a layered
//! `bake` restricted to the `upper` mask of a split file, checked by `verify`.
#![allow(clippy::unwrap_used)]

use crate::common;
use common::{inspect_json, sinew};
use serde_json::Value;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};

fn biped() -> PathBuf {
    sinew_testdata::fixtures().join("biped.sinew")
}

/// `sinew convert INPUT -o OUT --json [extra...]`, asserting success; the `files[0]` report.
fn convert(input: &Path, out: &Path, extra: &[&str]) -> Value {
    let mut args: Vec<&OsStr> = vec![
        "convert".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--json".as_ref(),
    ];
    args.extend(extra.iter().map(OsStr::new));
    let r = sinew(args);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let v: Value = serde_json::from_str(&r.stdout).unwrap();
    v["files"][0].clone()
}

#[test]
fn default_compression_is_smaller_than_no_compress_and_within_tolerance() {
    let Some(cesium) = sinew_testdata::corpus_file("gltf/CesiumMan.glb") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("c.sinew"), dir.path().join("p.sinew"));
    let compressed = convert(&cesium, &a, &[]);
    let plain = convert(&cesium, &b, &["--no-compress"]);
    let (ca, pb) = (
        std::fs::metadata(&a).unwrap().len(),
        std::fs::metadata(&b).unwrap().len(),
    );
    assert_eq!(compressed["bytes"].as_u64().unwrap(), ca);
    assert_eq!(plain["bytes"].as_u64().unwrap(), pb);
    assert!(ca < pb, "compressed {ca} bytes, plain {pb}");

    let clips = compressed["clips"].as_array().unwrap();
    assert!(!clips.is_empty());
    for c in clips {
        let r = &c["compression"];
        assert_eq!(r["clip"], c["name"]);
        assert_eq!(r["compressed"], true, "{r}");
        let max = r["max_error"].as_f64().unwrap();
        let tol = r["tolerance"].as_f64().unwrap();
        assert!(tol > 0.0 && max <= tol, "max error {max} > tolerance {tol}");
        assert!(r["p99_error"].as_f64().unwrap() <= max);
        let (raw, comp) = (
            r["raw_bytes"].as_u64().unwrap(),
            r["compressed_bytes"].as_u64().unwrap(),
        );
        assert!(comp < r["plain_bytes"].as_u64().unwrap());
        let ratio = r["ratio"].as_f64().unwrap();
        assert!((ratio - raw as f64 / comp as f64).abs() < 1e-3 * ratio);
    }
    // With --no-compress no clip has compression figures.
    for c in plain["clips"].as_array().unwrap() {
        assert!(c["compression"].is_null());
    }

    // An explicit tolerance is used as given.
    let t = dir.path().join("t.sinew");
    let tight = convert(&cesium, &t, &["--tolerance", "0.0001"]);
    for c in tight["clips"].as_array().unwrap() {
        let r = &c["compression"];
        assert!((r["tolerance"].as_f64().unwrap() - 0.0001).abs() < 1e-9);
        assert!(r["max_error"].as_f64().unwrap() <= 0.0001);
    }
}

#[test]
fn inspect_shows_quantized_encodings_of_a_compressed_file_and_f32_of_a_plain_one() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("c.sinew"), dir.path().join("p.sinew"));
    convert(&biped(), &a, &[]);
    convert(&biped(), &b, &["--no-compress"]);

    let c = inspect_json(&a, &[]);
    let walk = &c["clips"][0];
    assert_eq!(walk["name"], "walk");
    let e = &walk["encodings"];
    assert_eq!(e["compressed"], true);
    assert_eq!(e["f32"], 0);
    assert!(e["quantized"].as_u64().unwrap() > 0);
    assert!(e["max_bits"].as_u64().unwrap() > 0 && e["max_bits"].as_u64().unwrap() <= 16);
    // The walk drives 18 joints' rotations (fixtures/README.md): each is quantized, never f32.
    let tracks = walk["tracks"].as_array().unwrap();
    let kinds: Vec<&str> = tracks
        .iter()
        .map(|t| t["encoding"]["rotation"]["kind"].as_str().unwrap())
        .collect();
    assert!(kinds.iter().all(|k| *k != "f32"), "{kinds:?}");
    let q = tracks
        .iter()
        .find(|t| t["encoding"]["rotation"]["kind"] == "quantized")
        .unwrap();
    assert_eq!(
        q["encoding"]["rotation"]["max_bits"]
            .as_array()
            .unwrap()
            .len(),
        3
    );
    let channels = tracks.len() as u64 * 3;
    let sum: u64 = ["bind", "constant", "f32", "quantized"]
        .iter()
        .map(|k| e[k].as_u64().unwrap())
        .sum();
    assert_eq!(sum, channels);

    let p = inspect_json(&b, &[]);
    let e = &p["clips"][0]["encodings"];
    assert_eq!(e["compressed"], false);
    assert_eq!(e["quantized"], 0);
    assert!(e["f32"].as_u64().unwrap() >= 18, "{e}");

    // Inputs other than .sinew have no encodings.
    let g = inspect_json(&sinew_testdata::fixtures().join("biped.gltf"), &[]);
    assert!(g["clips"][0]["encodings"].is_null());
    assert!(g["clips"][0]["tracks"][0]["encoding"].is_null());
}

#[test]
fn split_file_has_upper_and_lower_masks_and_a_masked_layer_bakes_and_verifies() {
    let dir = tempfile::tempdir().unwrap();
    let x = dir.path().join("X.sinew");
    let report = convert(
        &biped(),
        &x,
        &["--at", "Bip01 Spine1", "--mask", "arm=Bip01 R UpperArm"],
    );
    let parts: Vec<&str> = report["splits"][0]["parts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    assert_eq!(parts, ["walk.upper", "walk.lower", "walk.arm"]);

    let r = inspect_json(&x, &[]);
    let masks = r["masks"].as_array().unwrap();
    let names: Vec<&str> = masks.iter().map(|m| m["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["upper", "lower", "arm"]);
    let joints = |i: usize| -> Vec<String> {
        masks[i]["weights"]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| {
                assert_eq!(w["weight"], 1.0);
                w["joint"].as_str().unwrap().to_string()
            })
            .collect()
    };
    let (upper, lower) = (joints(0), joints(1));
    // Upper: Spine1 and everything under it; lower: the rest; together the 22 joints once each.
    assert_eq!(upper[0], "Bip01 Spine1");
    for j in ["Bip01 Head", "Bip01 R UpperArm", "Bip01 L Forearm"] {
        assert!(upper.iter().any(|u| u == j), "{j} not in upper {upper:?}");
    }
    for j in ["Bip01", "Bip01 Pelvis", "Bip01 Spine", "Bip01 L Thigh"] {
        assert!(lower.iter().any(|l| l == j), "{j} not in lower {lower:?}");
    }
    assert_eq!(upper.len() + lower.len(), 22);
    assert!(upper.iter().all(|u| !lower.contains(u)));
    assert_eq!(joints(2), ["Bip01 R UpperArm"]);
    // The masks agree with the split clips: walk.upper drives only upper joints.
    let walk_upper = r["clips"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["name"] == "walk.upper")
        .unwrap();
    for j in walk_upper["driven_joints"].as_array().unwrap() {
        assert!(upper.iter().any(|u| u == j.as_str().unwrap()), "{j}");
    }

    // Layered bake: legs from walk.lower, the wave's upper body at 0.8 restricted to `upper`.
    let exr = dir.path().join("w.exr");
    let b = sinew([
        "bake".as_ref(),
        x.as_os_str(),
        "--layer".as_ref(),
        "walk.lower".as_ref(),
        "--layer".as_ref(),
        "wave.upper@upper:0.8".as_ref(),
        "--format".as_ref(),
        "exr".as_ref(),
        "-o".as_ref(),
        exr.as_os_str(),
        "--json".as_ref(),
    ]);
    assert_eq!(b.code, 0, "{}", b.stderr);
    let v = sinew([
        "verify".as_ref(),
        exr.as_os_str(),
        "--against".as_ref(),
        x.as_os_str(),
    ]);
    assert_eq!(v.code, 0, "{}", v.stderr);
    assert!(
        v.stderr.contains("identical to the runtime"),
        "{}",
        v.stderr
    );
    assert!(
        v.stderr.contains("31 frames x 735 vertices"),
        "{}",
        v.stderr
    );

    // An unknown mask name is an error naming it.
    let bad = sinew([
        "bake".as_ref(),
        x.as_os_str(),
        "--layer".as_ref(),
        "wave.upper@nope".as_ref(),
        "--format".as_ref(),
        "exr".as_ref(),
        "-o".as_ref(),
        dir.path().join("bad.exr").as_os_str(),
    ]);
    assert_ne!(bad.code, 0);
    assert!(bad.stderr.contains("nope"), "{}", bad.stderr);
}
