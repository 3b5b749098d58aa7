//! End-to-end: `convert RIG --anim MOTION --retarget` keeps the rig's feet on its own floor when the
//! motion is in other units. Each corpus motion is retargeted onto the biped fixture (hips 38 units
//! up), baked to PC2 through the runtime, and the lowest skinned vertex of every frame is compared
//! with the lowest vertex of the rest pose (the OBJ written beside the cache), in percent of the
//! rig's rest height. Before root scaling and grounding, the feet floated 48-66% of the rig's height
//! above the floor for the whole clip on these pairs.
#![allow(clippy::unwrap_used)] // unwrap is fine in tests

use crate::common;

use common::sinew;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn biped() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/biped.sinew")
}

fn convert(motion: &Path, out: &Path, extra: &[&str]) -> Value {
    let mut args: Vec<std::ffi::OsString> = vec![
        "convert".into(),
        biped().into(),
        "--anim".into(),
        motion.into(),
        "--retarget".into(),
        "--lod".into(),
        "none".into(),
        "--json".into(),
        "-o".into(),
        out.into(),
    ];
    args.extend(extra.iter().map(|s| s.into()));
    let run = sinew(&args);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let r: Value = serde_json::from_str(&run.stdout).unwrap();
    r["files"][0]["motions"][0].clone()
}

/// Per frame, the lowest vertex's height above the rest pose's lowest vertex, in percent of the
/// rest pose's height.
fn floor_offsets(sinew_file: &Path, clip: &str, dir: &Path) -> Vec<f64> {
    let pc2 = dir.join(format!("{clip}.pc2"));
    let run = sinew([
        "bake".as_ref(),
        sinew_file.as_os_str(),
        "--clip".as_ref(),
        clip.as_ref(),
        "--format".as_ref(),
        "pc2".as_ref(),
        "-q".as_ref(),
        "-o".as_ref(),
        pc2.as_os_str(),
    ]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let obj = std::fs::read_to_string(dir.join(format!("{clip}.pc2.obj"))).unwrap();
    let rest_y: Vec<f64> = obj
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| l.split_whitespace().nth(1).unwrap().parse().unwrap())
        .collect();
    let floor = rest_y.iter().copied().fold(f64::INFINITY, f64::min);
    let height = rest_y.iter().copied().fold(f64::NEG_INFINITY, f64::max) - floor;
    let bytes = std::fs::read(&pc2).unwrap();
    let int = |at: usize| i32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    let (points, samples) = (int(16), int(28));
    assert_eq!(points, rest_y.len());
    (0..samples)
        .map(|f| {
            let lowest = (0..points)
                .map(|v| {
                    let at = 32 + (f * points + v) * 12 + 4;
                    f64::from(f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()))
                })
                .fold(f64::INFINITY, f64::min);
            (lowest - floor) / height * 100.0
        })
        .collect()
}

#[test]
fn retargeted_feet_stay_on_the_rigs_floor_across_units() {
    let dir = tempfile::tempdir().unwrap();
    // (motion, clip, largest |offset| allowed in any frame, % of rig height; largest median)
    for (file, clip, worst_allowed, median_allowed) in [
        ("bvh/Boxing_Toes.bvh", "Boxing_Toes", 5.0, 4.0),
        ("bvh/cmu_walk_crlf.bvh", "cmu_walk_crlf", 8.0, 6.0),
        (
            "bvh/pfnn_hierarchy_crlf.bvh",
            "pfnn_hierarchy_crlf",
            1.0,
            1.0,
        ),
    ] {
        let Some(motion) = sinew_testdata::corpus_file(file) else {
            return;
        };
        let out = dir.path().join(format!("{clip}.sinew"));
        let m = convert(&motion, &out, &[]);
        let root = &m["root"];
        assert_eq!(root["source"], "hip-height", "{file}");
        let hm = root["hip_heights"][0].as_f64().unwrap();
        let hr = root["hip_heights"][1].as_f64().unwrap();
        let k = root["root_scale"].as_f64().unwrap();
        assert_eq!(m["root_scale"], root["root_scale"]);
        assert!(((k - hr / hm) / k).abs() < 1e-5, "{file}: {k} vs {hr}/{hm}");
        // Other units: the motion's hips are far from the rig's 35 units above its feet.
        assert!(!(0.5..2.0).contains(&k), "{file}: scale {k}");
        // Every corpus BVH has its root OFFSET at 0: its rest pose does not stand on its floor.
        assert!(
            root["standing_shift"].as_f64().unwrap() < -0.5 * hm,
            "{file}"
        );

        let mut offsets = floor_offsets(&out, clip, dir.path());
        let worst = offsets.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        offsets.sort_by(f64::total_cmp);
        let median = offsets[offsets.len() / 2];
        assert!(
            worst <= worst_allowed && median.abs() <= median_allowed,
            "{file}: lowest vertex off the floor by up to {worst:.2}% (median {median:.2}%)"
        );
    }
}

#[test]
fn root_scale_override_is_reported_and_checked() {
    let Some(motion) = sinew_testdata::corpus_file("bvh/cmu_walk_crlf.bvh") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.sinew");
    let m = convert(&motion, &out, &["--root-scale", "1.5"]);
    assert_eq!(m["root_scale"].as_f64().unwrap(), 1.5);
    assert_eq!(m["root"]["source"], "override");
    for bad in ["0", "-2", "nan"] {
        let run = sinew([
            "convert".as_ref(),
            biped().as_os_str(),
            "--anim".as_ref(),
            motion.as_os_str(),
            "--retarget".as_ref(),
            format!("--root-scale={bad}").as_ref(),
            "-o".as_ref(),
            out.as_os_str(),
        ]);
        assert_eq!(run.code, 2, "{bad}: {}", run.stderr);
        assert_eq!(run.stderr_lines().len(), 1, "{bad}: {}", run.stderr);
    }
    // Without --retarget the option is a usage error.
    let run = sinew([
        "convert".as_ref(),
        biped().as_os_str(),
        "--anim".as_ref(),
        motion.as_os_str(),
        "--root-scale".as_ref(),
        "2".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(run.code, 2, "{}", run.stderr);
}
