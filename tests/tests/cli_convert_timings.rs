//! `sinew convert --timings`: each step's wall time in the report (text and JSON), and nothing else
//! changed; without the switch the report has no timings at all. The meshes and clips the timings
//! must name come from `inspect` of the source, not from the conversion under test.
#![allow(clippy::unwrap_used)] // unwrap is fine in tests

use crate::common;

use common::{inspect_json, sinew};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn biped() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/biped.gltf")
}

fn names(v: &Value, key: &str) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x[key].as_str().unwrap().to_string())
        .collect()
}

/// `convert --json` of the biped with `extra`, parsed (the one file's report).
fn convert(out: &Path, extra: &[&str]) -> Value {
    let mut args: Vec<String> = vec![
        "convert".into(),
        "--json".into(),
        biped().display().to_string(),
        "-o".into(),
        out.display().to_string(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    let run = sinew(&args);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let v: Value = serde_json::from_str(&run.stdout).unwrap();
    v["files"][0].clone()
}

fn ms(v: &Value) -> f64 {
    let x = v.as_f64().unwrap();
    assert!(x.is_finite() && x >= 0.0, "a wall time is {x}");
    x
}

#[test]
fn timings_name_every_step_mesh_lod_and_clip() {
    let dir = tempfile::tempdir().unwrap();
    let source = inspect_json(&biped(), &[]);
    let meshes = names(&source["meshes"], "name");
    let clips = names(&source["clips"], "name");
    assert_eq!(clips, ["walk", "wave"]);
    // Three LOD ratios: three levels timed per mesh.
    let f = convert(
        &dir.path().join("a.sinew"),
        &["--timings", "--lod", "0.6,0.4,0.2"],
    );
    let t = &f["timings"];
    let total = ms(&t["total_ms"]);
    for step in ["import_ms", "prepare_ms", "textures_ms", "write_ms"] {
        assert!(ms(&t[step]) <= total, "{step} above the total");
    }
    assert_eq!(names(&t["lods"], "mesh"), meshes);
    for m in t["lods"].as_array().unwrap() {
        let levels = m["levels_ms"].as_array().unwrap();
        assert_eq!(levels.len(), 3, "{m}");
        let sum: f64 = levels.iter().map(ms).sum::<f64>() + ms(&m["optimize_ms"]);
        assert!(
            sum <= total,
            "a mesh's LOD work ({sum} ms) above the total ({total} ms)"
        );
    }
    assert_eq!(names(&t["clips"], "clip"), clips);
    for c in t["clips"].as_array().unwrap() {
        assert!(ms(&c["encode_ms"]) <= total);
    }
    // Without LODs or compression those steps are not timed.
    let f = convert(
        &dir.path().join("b.sinew"),
        &["--timings", "--lod", "none", "--no-compress"],
    );
    assert_eq!(f["timings"]["lods"].as_array().unwrap().len(), 0);
    assert_eq!(f["timings"]["clips"].as_array().unwrap().len(), 0);
}

#[test]
fn without_timings_the_report_and_the_file_are_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.sinew"), dir.path().join("b.sinew"));
    let mut with = convert(&a, &["--timings"]);
    let without = convert(&b, &[]);
    assert!(without.get("timings").is_none(), "{without}");
    assert!(with.as_object_mut().unwrap().remove("timings").is_some());
    // Everything else is the same, but for the output path.
    let strip = |mut v: Value| {
        v.as_object_mut().unwrap().remove("output");
        v
    };
    assert_eq!(strip(with), strip(without));
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

#[test]
fn the_human_summary_shows_timings_only_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.sinew");
    let run = |extra: &[&str]| {
        let mut args: Vec<String> = vec![
            "convert".into(),
            biped().display().to_string(),
            "-o".into(),
            out.display().to_string(),
        ];
        args.extend(extra.iter().map(|s| s.to_string()));
        let r = sinew(&args);
        assert_eq!(r.code, 0, "{}", r.stderr);
        r.stderr
    };
    let text = run(&["--timings"]);
    assert!(text.contains("  timings: total "), "{text}");
    assert!(text.contains("clip \"walk\": encode "), "{text}");
    assert!(text.contains("LOD 1 ") && text.contains("LOD 2 "), "{text}");
    assert!(!run(&[]).contains("timings:"));
}
