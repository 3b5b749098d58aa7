//! End-to-end: `sinew convert`, `map`, `split` and `lod` run as a subprocess over the fixtures and the
//! shared corpus. Expected figures come from the corpus MANIFEST notes, the fixture README (the biped's
//! skeleton) or from `inspect` of the *source* file, never from the conversion under test.
#![allow(clippy::unwrap_used)] // unwrap is fine in tests

use crate::common;

use common::{assert_one_line_error, inspect_json, sinew};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn arr(v: &Value) -> &Vec<Value> {
    v.as_array().expect("JSON array")
}

fn strs(v: &Value) -> Vec<String> {
    arr(v)
        .iter()
        .map(|s| s.as_str().unwrap().to_string())
        .collect()
}

/// Every corpus source file (models and motions) with a supported extension, sorted, with or
/// without the `malformed/` folders.
fn corpus_inputs(root: &Path, malformed: bool) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                if malformed || p.file_name().unwrap() != "malformed" {
                    stack.push(p);
                }
                continue;
            }
            let ext = p
                .extension()
                .map(|e| e.to_string_lossy().to_lowercase())
                .unwrap_or_default();
            if ["ms3d", "gltf", "glb", "obj", "bvh"].contains(&ext.as_str()) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

fn is_malformed(p: &Path) -> bool {
    p.components().any(|c| c.as_os_str() == "malformed")
}

fn convert_json(args: &[&std::ffi::OsStr]) -> (i32, Value, String) {
    let mut all: Vec<&std::ffi::OsStr> = vec!["convert".as_ref(), "--json".as_ref()];
    all.extend_from_slice(args);
    let run = sinew(&all);
    let v = if run.stdout.is_empty() {
        Value::Null
    } else {
        serde_json::from_str(&run.stdout).unwrap()
    };
    (run.code, v, run.stderr)
}

fn biped() -> PathBuf {
    sinew_testdata::fixtures().join("biped.sinew")
}

/// Batch over the whole corpus including the malformed files: exit 1, every file the importers
/// accept is converted and its output holds what the source holds (joints, triangles, clip names and
/// durations, two LODs per mesh); every malformed file is listed as failed, on stderr and in JSON.
#[test]
fn batch_over_corpus_converts_good_files_and_lists_every_bad_one() {
    let Some(root) = sinew_testdata::corpus() else {
        return;
    };
    let inputs = corpus_inputs(&root, true);
    assert!(inputs.len() > 30, "corpus looks incomplete: {inputs:?}");
    let dir = tempfile::tempdir().unwrap();
    let mut args: Vec<&std::ffi::OsStr> = inputs.iter().map(|p| p.as_os_str()).collect();
    args.push("--out-dir".as_ref());
    args.push(dir.path().as_os_str());
    let (code, report, stderr) = convert_json(&args);
    assert_eq!(code, 1, "a batch with bad files exits 1; stderr: {stderr}");
    assert_eq!(report["inputs"], inputs.len());
    let files = arr(&report["files"]);
    assert_eq!(files.len(), inputs.len());
    let mut converted = 0;
    for (input, f) in inputs.iter().zip(files) {
        assert_eq!(f["input"], input.display().to_string(), "order kept");
        let out = PathBuf::from(f["output"].as_str().unwrap());
        // Does the importer accept the source, and does it hold anything (a joint, a mesh, a
        // clip)? That, not the folder, decides what must convert.
        let src = sinew([Path::new("inspect"), Path::new("--json"), input]);
        let empty = src.code == 0 && {
            let v: Value = serde_json::from_str(&src.stdout).unwrap();
            v["summary"]["joints"] == 0
                && arr(&v["meshes"]).is_empty()
                && arr(&v["clips"]).is_empty()
        };
        if empty {
            assert_eq!(f["status"], "failed", "{}", input.display());
            let err = f["error"].as_str().unwrap();
            assert!(err.contains("nothing to convert"), "{err}");
            assert!(!out.exists());
            continue;
        }
        if is_malformed(input) || src.code != 0 {
            assert_eq!(f["status"], "failed", "{}", input.display());
            let err = f["error"].as_str().unwrap();
            assert!(err.contains(&input.display().to_string()), "{err}");
            assert!(
                stderr.contains(&format!("sinew: error: {err}")),
                "failure of {} not listed on stderr",
                input.display()
            );
            assert!(
                !out.exists(),
                "no output for a failed file: {}",
                out.display()
            );
            continue;
        }
        converted += 1;
        assert_eq!(
            f["status"],
            "converted",
            "{}: {}",
            input.display(),
            f["error"]
        );
        assert_eq!(f["bytes"], std::fs::metadata(&out).unwrap().len());
        let src: Value = serde_json::from_str(&src.stdout).unwrap();
        let got = inspect_json(&out, &[]);
        assert_eq!(got["format"], "sinew");
        let ctx = input.display();
        assert_eq!(got["summary"]["joints"], src["summary"]["joints"], "{ctx}");
        assert_eq!(
            got["summary"]["triangles"], src["summary"]["triangles"],
            "{ctx}"
        );
        let names = |r: &Value| -> Vec<String> {
            arr(&r["clips"])
                .iter()
                .map(|c| c["name"].as_str().unwrap().to_string())
                .collect()
        };
        assert_eq!(names(&got), names(&src), "{ctx}");
        for (a, b) in arr(&got["clips"]).iter().zip(arr(&src["clips"])) {
            let (a, b) = (
                a["duration"].as_f64().unwrap(),
                b["duration"].as_f64().unwrap(),
            );
            assert!((a - b).abs() < 1e-4, "{ctx}: duration {a} vs {b}");
        }
        // Every mesh's two levels are written or reported as not built, in order; the file
        // holds the written ones.
        for (m, r) in arr(&got["meshes"]).iter().zip(arr(&f["meshes"])) {
            if m["triangles"].as_u64().unwrap() > 0 {
                let lods = arr(&m["lods"]);
                let not_built = arr(&r["lods_not_built"]);
                assert_eq!(lods.len(), arr(&r["lods"]).len(), "{ctx}: {}", m["name"]);
                assert_eq!(
                    lods.len() + not_built.len(),
                    2,
                    "{ctx}: LODs of {}",
                    m["name"]
                );
                let ratios: Vec<f64> = lods
                    .iter()
                    .chain(not_built)
                    .map(|l| l["target_ratio"].as_f64().unwrap())
                    .collect();
                assert_eq!(ratios, [0.5, 0.25], "{ctx}");
                let mut previous = m["triangles"].as_u64().unwrap();
                for l in lods {
                    let t = l["triangles"].as_u64().unwrap();
                    assert!(t < previous, "{ctx}: {t} after {previous}");
                    previous = t;
                }
                for n in not_built {
                    assert!(
                        ["no-collapse", "previous-not-built"]
                            .contains(&n["reason"].as_str().unwrap()),
                        "{ctx}: {n}"
                    );
                }
            }
        }
    }
    assert_eq!(report["converted"], converted);
    assert_eq!(report["failed"], inputs.len() - converted);
    assert!(converted >= 30, "only {converted} converted");
    // Every malformed file is listed (13 in the corpus today, at least one per format folder).
    let failed: Vec<&Value> = files.iter().filter(|f| f["status"] == "failed").collect();
    assert!(failed.len() >= inputs.iter().filter(|p| is_malformed(p)).count());
    assert!(stderr.contains(&format!(
        "{} of {} files failed",
        failed.len(),
        inputs.len()
    )));
}

/// Figures from the corpus MANIFEST notes, checked on the converted files.
#[test]
fn converted_corpus_models_hold_manifest_figures() {
    let (Some(cesium), Some(fox), Some(zombie), Some(walk)) = (
        sinew_testdata::corpus_file("gltf/CesiumMan.glb"),
        sinew_testdata::corpus_file("gltf/Fox.glb"),
        sinew_testdata::corpus_file("ms3d/zombie.ms3d"),
        sinew_testdata::corpus_file("bvh/cmu_walk_crlf.bvh"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    // (file, joints, triangles, clip names)
    let cases: [(&Path, u64, u64, &[&str]); 4] = [
        (&cesium, 19, 4672, &[]),
        (&fox, 24, 576, &["Survey", "Walk", "Run"]),
        (&zombie, 19, 735, &[]),
        (&walk, 31, 0, &[]),
    ];
    for (input, joints, tris, clips) in cases {
        let out = dir.path().join("out.sinew");
        let (code, report, stderr) =
            convert_json(&[input.as_os_str(), "-o".as_ref(), out.as_os_str()]);
        assert_eq!(code, 0, "{}: {stderr}", input.display());
        let f = &report["files"][0];
        let r = inspect_json(&out, &[]);
        // The BVH importer keeps End Sites as `NAME_end` joints; the MANIFEST counts joints without them.
        let counted = arr(&r["skeleton"]["joints"])
            .iter()
            .filter(|j| !j["name"].as_str().unwrap().ends_with("_end"))
            .count();
        assert_eq!(counted as u64, joints, "{}", input.display());
        assert_eq!(f["joints"], r["summary"]["joints"]);
        assert_eq!(r["summary"]["triangles"], tris, "{}", input.display());
        assert!(r["summary"]["clips"].as_u64().unwrap() >= 1);
        if !clips.is_empty() {
            let names: Vec<&str> = arr(&r["clips"])
                .iter()
                .map(|c| c["name"].as_str().unwrap())
                .collect();
            assert_eq!(names, clips);
        }
        if input == walk.as_path() {
            // 344 frames at 120 Hz: 343 intervals.
            let d = r["clips"][0]["duration"].as_f64().unwrap();
            assert!((d - 343.0 / 120.0).abs() < 1e-3, "walk duration {d}");
        }
        if tris > 0 {
            let lods = arr(&r["meshes"][0]["lods"]);
            assert_eq!(lods.len(), 2);
            // The JSON report of convert carries the same LOD figures as the file.
            assert_eq!(f["meshes"][0]["lods"][0]["triangles"], lods[0]["triangles"]);
        }
    }
}

/// Same inputs, same bytes: two runs, and --jobs 1 against --jobs 4.
#[test]
fn outputs_are_byte_identical_across_runs_and_thread_counts() {
    let Some(root) = sinew_testdata::corpus() else {
        return;
    };
    let inputs: Vec<PathBuf> = [
        "gltf/CesiumMan.glb",
        "gltf/Fox.glb",
        "ms3d/zombie.ms3d",
        "obj/spider.obj",
        "bvh/cmu_walk_crlf.bvh",
    ]
    .iter()
    .map(|r| root.join(r))
    .collect();
    let run = |jobs: &str| -> Vec<Vec<u8>> {
        let dir = tempfile::tempdir().unwrap();
        let mut args: Vec<&std::ffi::OsStr> = vec!["convert".as_ref(), "--quiet".as_ref()];
        args.extend(inputs.iter().map(|p| p.as_os_str()));
        args.extend([
            "--out-dir".as_ref(),
            dir.path().as_os_str(),
            "--jobs".as_ref(),
            jobs.as_ref(),
        ]);
        let r = sinew(&args);
        assert_eq!(r.code, 0, "{}", r.stderr);
        assert!(r.stderr.is_empty(), "--quiet: {}", r.stderr);
        ["CesiumMan", "Fox", "zombie", "spider", "cmu_walk_crlf"]
            .iter()
            .map(|s| std::fs::read(dir.path().join(format!("{s}.sinew"))).unwrap())
            .collect()
    };
    let a = run("4");
    let b = run("4");
    let c = run("1");
    assert!(a.iter().all(|f| f.len() > 1000));
    assert_eq!(a, b, "two runs differ");
    assert_eq!(a, c, "--jobs 1 and --jobs 4 differ");
}

/// One file, its clips compressed in parallel inside the process (clips, candidate layouts,
/// refinements) and its LOD steps' plain builds made beside their own builds (all of them on the
/// Biped fixture, the positions-only one on jeep1's static mesh): the same bytes with one rayon
/// thread as with two and three, at every `--effort`.
#[test]
fn single_file_convert_is_byte_identical_at_any_rayon_thread_count() {
    let mut inputs = vec![biped()];
    inputs.extend(sinew_testdata::corpus_file("gltf/Fox.glb"));
    inputs.extend(sinew_testdata::corpus_file("ms3d/jeep1.ms3d"));
    let dir = tempfile::tempdir().unwrap();
    for input in &inputs {
        for effort in ["fast", "default", "max"] {
            let outputs: Vec<Vec<u8>> = ["1", "2", "3"]
                .iter()
                .map(|threads| {
                    let out = dir.path().join(format!("out-{threads}.sinew"));
                    let status = std::process::Command::new(env!("CARGO_BIN_EXE_sinew-e2e"))
                        .env("RAYON_NUM_THREADS", threads)
                        .args(["convert", "--quiet", "--effort", effort, "-o"])
                        .arg(&out)
                        .arg(input)
                        .status()
                        .expect("running the sinew binary");
                    assert!(status.success(), "{} --effort {effort}", input.display());
                    std::fs::read(&out).unwrap()
                })
                .collect();
            assert!(outputs[0].len() > 1000);
            assert_eq!(
                outputs[0],
                outputs[1],
                "{} {effort}: 1 vs 2",
                input.display()
            );
            assert_eq!(
                outputs[0],
                outputs[2],
                "{} {effort}: 1 vs 3",
                input.display()
            );
        }
    }
}

/// `map` of the CMU BVH files against the Biped fixture: the matches the Biped and CMU naming
/// conventions call for (FORMATS.md, docs/mapping.md), the unmatched helpers, the known warnings.
#[test]
fn map_cmu_bvh_onto_biped_fixture() {
    let Some(root) = sinew_testdata::corpus() else {
        return;
    };
    for bvh in ["bvh/cmu_01_01.bvh", "bvh/cmu_walk_crlf.bvh"] {
        let motion = root.join(bvh);
        let run = sinew([Path::new("map"), &biped(), &motion, Path::new("--json")]);
        assert_eq!(run.code, 0, "{}", run.stderr);
        let r: Value = serde_json::from_str(&run.stdout).unwrap();
        assert_eq!(r["rig_family"], "biped");
        assert_eq!(r["motion_family"], "cmu");
        let entry = |rig: &str| {
            arr(&r["entries"])
                .iter()
                .find(|e| e["rig"] == rig)
                .unwrap_or_else(|| panic!("no entry for {rig}"))
                .clone()
        };
        for (rig, motion, method) in [
            ("Bip01 L Thigh", "LeftUpLeg", "synonym"),
            ("Bip01 R Thigh", "RightUpLeg", "synonym"),
            ("Bip01 L Calf", "LeftLeg", "synonym"),
            ("Bip01 L Foot", "LeftFoot", "normalised"),
            ("Bip01 Pelvis", "Hips", "synonym"),
            ("Bip01 L UpperArm", "LeftArm", "synonym"),
            ("Bip01 R Forearm", "RightForeArm", "normalised"),
            ("Bip01 L Clavicle", "LeftShoulder", "synonym"),
            ("Bip01 Head", "Head", "normalised"),
        ] {
            let e = entry(rig);
            assert_eq!(e["motion"], motion, "{bvh}: {rig}");
            assert_eq!(e["method"], method, "{bvh}: {rig}");
        }
        assert_eq!(entry("Bip01 L Thigh")["slot"], "thigh");
        assert_eq!(strs(&r["unmatched_rig"]), vec!["Bip01"]);
        let unmatched = strs(&r["unmatched_motion"]);
        for helper in ["LHipJoint", "RHipJoint", "LowerBack", "Neck1"] {
            assert!(
                unmatched.contains(&helper.to_string()),
                "{bvh}: {unmatched:?}"
            );
        }
        let codes: Vec<&str> = arr(&r["warnings"])
            .iter()
            .map(|w| w["code"].as_str().unwrap())
            .collect();
        for code in ["leg-ambiguity", "spine-count", "neck-count"] {
            assert!(codes.contains(&code), "{bvh}: {codes:?}");
        }
        // The human table goes to stderr, with the method column.
        let human = sinew([Path::new("map"), &biped(), &motion]);
        assert!(human.stdout.is_empty());
        let line = human
            .stderr
            .lines()
            .find(|l| l.trim_start().starts_with("Bip01 L Thigh"))
            .unwrap();
        assert!(
            line.contains("LeftUpLeg") && line.contains("synonym (thigh)"),
            "{line}"
        );
        assert!(human.stderr.contains("unmatched motion joints"));
    }
}

#[test]
fn map_write_then_read_back_and_reject_unknown_joints() {
    let Some(walk) = sinew_testdata::corpus_file("bvh/cmu_walk_crlf.bvh") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("map.json");
    let run = sinew([
        Path::new("map"),
        &biped(),
        &walk,
        Path::new("--write"),
        &file,
        Path::new("-q"),
    ]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let written: Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    assert_eq!(written["version"], 1);
    assert_eq!(written["joints"]["Bip01 L Thigh"], "LeftUpLeg");
    assert_eq!(written["joints"]["Bip01"], Value::Null);
    // Read back: every entry is now "file".
    let run = sinew([
        Path::new("map"),
        &biped(),
        &walk,
        Path::new("--map"),
        &file,
        Path::new("--json"),
    ]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let r: Value = serde_json::from_str(&run.stdout).unwrap();
    assert_eq!(r["bound"], 21);
    assert!(arr(&r["entries"])
        .iter()
        .filter(|e| !e["motion"].is_null())
        .all(|e| e["method"] == "file"));
    // A mapping file naming a joint that does not exist: exit 2, one line naming file and joint.
    let bad = dir.path().join("bad.json");
    std::fs::write(
        &bad,
        r#"{"version": 1, "joints": {"Bip01 L Thigh": "LeftUpperLegX"}}"#,
    )
    .unwrap();
    let run = sinew([Path::new("map"), &biped(), &walk, Path::new("--map"), &bad]);
    assert_one_line_error(&run, &bad);
    assert!(run.stderr.contains("LeftUpperLegX"), "{}", run.stderr);
    let out = dir.path().join("o.sinew");
    let run = sinew([
        Path::new("convert"),
        &biped(),
        Path::new("--anim"),
        &walk,
        Path::new("--map"),
        &bad,
        Path::new("-o"),
        &out,
    ]);
    assert_one_line_error(&run, &bad);
    assert!(!out.exists());
    let bad2 = dir.path().join("bad2.json");
    std::fs::write(&bad2, r#"{"version": 1, "joints": {"Bip01 Tail": "Hips"}}"#).unwrap();
    let run = sinew([Path::new("map"), &biped(), &walk, Path::new("--map"), &bad2]);
    assert_one_line_error(&run, &bad2);
    assert!(run.stderr.contains("Bip01 Tail"), "{}", run.stderr);
}

/// The biped's skeleton (fixtures/README.md): clavicles hang from `Bip01 Neck`, so everything above
/// `Bip01 Spine` is upper body; `walk` drives 18 joints, `wave` 6 (neck, head, right arm).
#[test]
fn split_at_spine_drives_upper_and_lower_joints() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("split.sinew");
    let run = sinew([
        Path::new("split"),
        &biped(),
        Path::new("--at"),
        Path::new("Bip01 Spine"),
        Path::new("--mask"),
        Path::new("legs=Bip01 L Thigh,Bip01 R Thigh"),
        Path::new("-o"),
        &out,
        Path::new("--json"),
    ]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let r: Value = serde_json::from_str(&run.stdout).unwrap();
    let walk = arr(&r["splits"])
        .iter()
        .find(|s| s["clip"] == "walk")
        .unwrap();
    let parts = arr(&walk["parts"]);
    assert_eq!(parts[0]["name"], "walk.upper");
    assert_eq!(
        strs(&parts[0]["joints"]),
        [
            "Bip01 Spine",
            "Bip01 Spine1",
            "Bip01 Neck",
            "Bip01 Head",
            "Bip01 L UpperArm",
            "Bip01 L Forearm",
            "Bip01 R UpperArm",
            "Bip01 R Forearm"
        ]
    );
    assert_eq!(parts[1]["name"], "walk.lower");
    assert_eq!(
        strs(&parts[1]["joints"]),
        [
            "Bip01",
            "Bip01 Pelvis",
            "Bip01 L Thigh",
            "Bip01 L Calf",
            "Bip01 L Foot",
            "Bip01 L Toe0",
            "Bip01 R Thigh",
            "Bip01 R Calf",
            "Bip01 R Foot",
            "Bip01 R Toe0"
        ]
    );
    assert_eq!(parts[2]["name"], "walk.legs");
    assert_eq!(
        strs(&parts[2]["joints"]),
        ["Bip01 L Thigh", "Bip01 R Thigh"]
    );
    // The written file: the source clips are replaced by their parts, each driving its own joints.
    let got = inspect_json(&out, &[]);
    let clips: Vec<(String, Vec<String>)> = arr(&got["clips"])
        .iter()
        .map(|c| {
            (
                c["name"].as_str().unwrap().to_string(),
                strs(&c["driven_joints"]),
            )
        })
        .collect();
    let names: Vec<&str> = clips.iter().map(|c| c.0.as_str()).collect();
    assert_eq!(
        names,
        [
            "walk.upper",
            "walk.lower",
            "walk.legs",
            "wave.upper",
            "wave.lower",
            "wave.legs"
        ]
    );
    assert_eq!(clips[0].1.len(), 8);
    assert_eq!(clips[1].1.len(), 10);
    // wave (neck, head, right clavicle/arm) is all upper body: its lower part drives nothing.
    assert_eq!(clips[3].1.len(), 6);
    assert!(clips[4].1.is_empty(), "{:?}", clips[4]);
    assert_eq!(got["summary"]["joints"], 22);
}

#[test]
fn convert_with_anim_binds_cmu_walk_onto_biped_and_splits() {
    let Some(walk) = sinew_testdata::corpus_file("bvh/cmu_walk_crlf.bvh") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("biped_walk.sinew");
    let (code, r, stderr) = convert_json(&[
        biped().as_os_str(),
        "--anim".as_ref(),
        walk.as_os_str(),
        "--retarget".as_ref(),
        "--at".as_ref(),
        "Bip01 Spine".as_ref(),
        "--lod".as_ref(),
        "none".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let f = &r["files"][0];
    let m = &f["motions"][0];
    assert_eq!(m["retargeted"], true);
    assert_eq!(m["mapping"]["bound"], 21);
    assert_eq!(strs(&m["clips"]), ["cmu_walk_crlf"]);
    let got = inspect_json(&out, &[]);
    let names: Vec<&str> = arr(&got["clips"])
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "walk.upper",
            "walk.lower",
            "wave.upper",
            "wave.lower",
            "cmu_walk_crlf.upper",
            "cmu_walk_crlf.lower"
        ]
    );
    let d = got["clips"][4]["duration"].as_f64().unwrap();
    assert!((d - 343.0 / 120.0).abs() < 1e-3, "{d}");
    assert!(arr(&got["meshes"][0]["lods"]).is_empty(), "--lod none");
    // Without --retarget, the rest-pose difference is warned about.
    let (code, r, stderr) = convert_json(&[
        biped().as_os_str(),
        "--anim".as_ref(),
        walk.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let codes: Vec<&str> = arr(&r["files"][0]["diagnostics"])
        .iter()
        .map(|d| d["code"].as_str().unwrap())
        .collect();
    assert!(codes.contains(&"rest-pose-differs"), "{codes:?}");
    assert!(codes.contains(&"motion-unmatched"), "{codes:?}");
}

#[test]
fn convert_clips_cuts_an_ms3d_timeline_from_frame_1() {
    let Some(zombie) = sinew_testdata::corpus_file("ms3d/zombie.ms3d") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("z.sinew");
    let (code, r, stderr) = convert_json(&[
        zombie.as_os_str(),
        "--clips".as_ref(),
        "walk=1-25,run=25-49".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(strs(&r["files"][0]["cuts"]), ["walk", "run"]);
    let got = inspect_json(&out, &[]);
    for c in arr(&got["clips"]) {
        // 24 frame intervals at 24 fps.
        assert!((c["duration"].as_f64().unwrap() - 1.0).abs() < 1e-5, "{c}");
        // Every joint keeps its track; joints a cut holds at their bind pose are stored as bind
        // channels (no keys), so they are not listed as driven.
        assert_eq!(arr(&c["tracks"]).len(), 19, "{c}");
        let driven = arr(&c["driven_joints"]).len();
        assert!((10..=19).contains(&driven), "{c}");
    }
    // Frame 0 does not exist in Milkshape numbering: exit 2 naming the file.
    let run = sinew([
        Path::new("convert"),
        &zombie,
        Path::new("--clips"),
        Path::new("a=0-5"),
        Path::new("-o"),
        &out,
    ]);
    assert_one_line_error(&run, &zombie);
}

#[test]
fn lod_regenerates_lods_of_a_sinew_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lod.sinew");
    let run = sinew([
        Path::new("lod"),
        &biped(),
        Path::new("-o"),
        &out,
        Path::new("--lod"),
        Path::new("0.6,0.3"),
        Path::new("--lod-max-error"),
        Path::new("1"),
    ]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let got = inspect_json(&out, &[]);
    let lods = arr(&got["meshes"][0]["lods"]);
    assert_eq!(lods.len(), 2);
    assert_eq!(lods[0]["target_ratio"].as_f64().unwrap() as f32, 0.6);
    // 756 triangles (fixture README); with a generous error limit the targets are met within
    // one triangle per submesh (2 submeshes).
    let t1 = lods[0]["triangles"].as_i64().unwrap();
    let t2 = lods[1]["triangles"].as_i64().unwrap();
    assert!((t1 - 454).abs() <= 2, "{t1}");
    assert!((t2 - 227).abs() <= 2, "{t2}");
    assert_eq!(got["summary"]["triangles"], 756);
    assert_eq!(got["summary"]["clips"], 2);
}

/// `--lod-keep-uv-seams`: the biped fixture has UVs (with seams) and no texture, so by default its
/// LODs weld the copies of a vertex that differ only in UV (docs/lod.md, "UVs no texture reads");
/// with the flag the seams hold and each LOD keeps more vertices for the same triangle budget.
#[test]
fn lod_keep_uv_seams_holds_the_seams_of_an_untextured_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let fixture = sinew_testdata::fixtures().join("biped.gltf");
    let lods = |flag: Option<&str>| {
        let out = dir.path().join(format!("b{}.sinew", flag.is_some()));
        let mut args: Vec<&std::ffi::OsStr> =
            vec![fixture.as_os_str(), "-o".as_ref(), out.as_os_str()];
        args.extend(flag.map(std::ffi::OsStr::new));
        let (code, report, stderr) = convert_json(&args);
        assert_eq!(code, 0, "{stderr}");
        let mesh = &report["files"][0]["meshes"][0];
        arr(&mesh["lods"])
            .iter()
            .map(|l| {
                (
                    l["triangles"].as_i64().unwrap(),
                    l["vertices"].as_i64().unwrap(),
                )
            })
            .collect::<Vec<_>>()
    };
    let (opened, held) = (lods(None), lods(Some("--lod-keep-uv-seams")));
    assert_eq!(opened.len(), 2);
    for (o, h) in opened.iter().zip(&held) {
        assert_eq!(o.0, h.0, "triangles");
        assert!(
            o.1 < h.1,
            "vertices without the flag {} vs with it {}",
            o.1,
            h.1
        );
    }
}

/// Bad input: exit 2, one line naming the file, no output written.
#[test]
fn bad_inputs_exit_2_with_one_line_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.sinew");
    let missing = dir.path().join("missing.ms3d");
    let run = sinew([Path::new("convert"), &missing, Path::new("-o"), &out]);
    assert_one_line_error(&run, &missing);
    let run = sinew([Path::new("convert"), dir.path(), Path::new("-o"), &out]);
    assert_one_line_error(&run, dir.path());
    let fbx = dir.path().join("model.fbx");
    std::fs::write(&fbx, b"Kaydara FBX Binary").unwrap();
    let run = sinew([Path::new("convert"), &fbx, Path::new("-o"), &out]);
    assert_one_line_error(&run, &fbx);
    let corrupt = dir.path().join("corrupt.ms3d");
    std::fs::write(&corrupt, b"MS3D000000\x04\x00\x00\x00\xff\xff").unwrap();
    let run = sinew([Path::new("convert"), &corrupt, Path::new("-o"), &out]);
    assert_one_line_error(&run, &corrupt);
    // Unknown --at joint, on convert and on split: the line names the joint.
    for cmd in ["convert", "split"] {
        let run = sinew([
            Path::new(cmd),
            &biped(),
            Path::new("--at"),
            Path::new("Bip01 Spine9"),
            Path::new("-o"),
            &out,
        ]);
        assert_one_line_error(&run, &biped());
        assert!(run.stderr.contains("Bip01 Spine9"), "{}", run.stderr);
    }
    // Output in a missing directory.
    let nowhere = dir.path().join("no/such/dir/out.sinew");
    let run = sinew([Path::new("convert"), &biped(), Path::new("-o"), &nowhere]);
    assert_one_line_error(&run, &nowhere);
    assert!(!out.exists(), "no output file after any failure");
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(
        names.len(),
        2,
        "only the test's own inputs remain: {names:?}"
    );
    // Usage errors.
    let run = sinew([
        Path::new("convert"),
        &biped(),
        &biped(),
        Path::new("-o"),
        &out,
    ]);
    assert_eq!(run.code, 2);
    let run = sinew([
        Path::new("convert"),
        &biped(),
        Path::new("--lod"),
        Path::new("0.25,0.5"),
        Path::new("-o"),
        &out,
    ]);
    assert_eq!(run.code, 2);
    assert!(run.stderr.contains("--lod"), "{}", run.stderr);
    assert!(!out.exists());
}

#[test]
fn help_of_new_commands_has_examples() {
    for cmd in ["convert", "map", "split", "lod"] {
        let run = sinew([cmd, "--help"]);
        assert_eq!(run.code, 0);
        assert!(run.stdout.contains("Examples:"), "{cmd}");
        assert!(run.stdout.contains(&format!("sinew {cmd} ")), "{cmd}");
    }
    let run = sinew(["convert", "--help"]);
    for o in [
        "--out-dir",
        "--jobs",
        "--anim",
        "--map",
        "--retarget",
        "--clips",
        "--at",
        "--mask",
        "--lod",
        "--lod-max-error",
        "--lod-influences",
        "--ms3d-position-keys",
        "--gltf-skin",
    ] {
        assert!(run.stdout.contains(o), "convert --help lacks {o}");
    }
}

/// A level that cannot remove half of the triangles it asks for is not written; the JSON and the
/// human report say which and why (here an error limit far below what the biped's LODs need).
#[test]
fn levels_not_built_are_reported_instead_of_written_as_copies() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b.sinew");
    let input = biped();
    let args: Vec<&std::ffi::OsStr> = vec![
        input.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--lod-max-error".as_ref(),
        "0.00001".as_ref(),
    ];
    let (code, report, stderr) = convert_json(&args);
    assert_eq!(code, 0, "{stderr}");
    let mesh = &arr(&report["files"])[0]["meshes"][0];
    assert!(arr(&mesh["lods"]).is_empty(), "{mesh}");
    let not_built = arr(&mesh["lods_not_built"]);
    assert_eq!(not_built.len(), 2);
    assert_eq!(not_built[0]["level"], 1);
    assert_eq!(not_built[0]["reason"], "error-limit");
    assert_eq!(not_built[0]["previous_triangles"], 756);
    assert!(not_built[0]["reached_triangles"].as_u64().unwrap() > 567);
    assert_eq!(not_built[1]["reason"], "previous-not-built");
    assert!(not_built[1]["reached_triangles"].is_null());
    assert!(arr(&inspect_json(&out, &[])["meshes"][0]["lods"]).is_empty());
    // The default: no limit, both levels written at their budgets.
    let (code, report, stderr) = convert_json(&[input.as_os_str(), "-o".as_ref(), out.as_os_str()]);
    assert_eq!(code, 0, "{stderr}");
    let mesh = &arr(&report["files"])[0]["meshes"][0];
    assert!(arr(&mesh["lods_not_built"]).is_empty());
    let t: Vec<u64> = arr(&mesh["lods"])
        .iter()
        .map(|l| l["triangles"].as_u64().unwrap())
        .collect();
    assert!(t[0].abs_diff(378) <= 2 && t[1].abs_diff(189) <= 2, "{t:?}");
    assert!(arr(&mesh["lods"])
        .iter()
        .all(|l| l["stopped_by_error_limit"] == false));
}

#[test]
fn the_human_report_names_levels_not_built() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b.sinew");
    let run = sinew([
        Path::new("convert"),
        &biped(),
        Path::new("-o"),
        &out,
        Path::new("--lod-max-error"),
        Path::new("0.00001"),
    ]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stderr
            .contains("LOD 1 not built (error-limit: stopped at")
            && run.stderr.contains("LOD 2 not built (previous-not-built)"),
        "{}",
        run.stderr
    );
}
