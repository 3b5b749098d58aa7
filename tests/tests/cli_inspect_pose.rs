//! End-to-end: `sinew inspect FILE --pose CLIP@TIME` (and `CLIP@START..END`) against forward kinematics
//! computed here, independently of sinew: this file parses the BVH text itself (channel order per
//! joint, degrees, position channels replacing OFFSET components, several roots, End Sites) and
//! composes model-space matrices in f64 with its own 3x3 arithmetic. The CLI's model-space joint
//! transforms must match within a tight tolerance, on BVH text built here and on corpus files.
#![allow(clippy::unwrap_used)] // unwrap is fine in tests

use crate::common;

use common::{assert_one_line_error, sinew};
use serde_json::Value;
use std::collections::HashMap;
use std::path::Path;

type M3 = [[f64; 3]; 3];

fn mul(a: &M3, b: &M3) -> M3 {
    let mut o = [[0.0; 3]; 3];
    for (r, row) in o.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[r][k] * b[k][c]).sum();
        }
    }
    o
}

fn apply(a: &M3, v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|r| (0..3).map(|k| a[r][k] * v[k]).sum())
}

/// Rotation about axis 0/1/2 by `deg` degrees, acting on column vectors.
fn axis_rotation(axis: usize, deg: f64) -> M3 {
    let (s, c) = deg.to_radians().sin_cos();
    match axis {
        0 => [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
        1 => [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
        _ => [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
    }
}

const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// One joint of the test's own reading of a BVH hierarchy.
struct BvhJoint {
    name: String,
    parent: Option<usize>,
    offset: [f64; 3],
    /// (is_position, axis) per channel, in file order.
    channels: Vec<(bool, usize)>,
    /// Index of the joint's first channel in a frame line.
    first: usize,
}

struct Bvh {
    joints: Vec<BvhJoint>,
    frame_time: f64,
    frames: Vec<Vec<f64>>,
}

/// The hierarchy and motion of a BVH text; End Sites become joints named `<parent>_end` with no
/// channels (sinew's documented naming; the test's files have no clashing names).
fn parse_bvh(text: &str) -> Bvh {
    let mut joints: Vec<BvhJoint> = Vec::new();
    let mut stack: Vec<usize> = Vec::new();
    let mut pending: Option<usize> = None;
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let mut channel_count = 0;
    for line in lines.by_ref() {
        let (word, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let rest = rest.trim();
        match word {
            "HIERARCHY" => {}
            "ROOT" | "JOINT" | "End" => {
                let parent = stack.last().copied();
                let name = if word == "End" {
                    format!("{}_end", joints[parent.unwrap()].name)
                } else {
                    rest.trim_end_matches('{').trim().to_string()
                };
                joints.push(BvhJoint {
                    name,
                    parent,
                    offset: [0.0; 3],
                    channels: Vec::new(),
                    first: channel_count,
                });
                pending = Some(joints.len() - 1);
            }
            "{" => stack.push(pending.take().unwrap()),
            "}" => {
                stack.pop();
            }
            "OFFSET" => {
                let v: Vec<f64> = rest
                    .split_whitespace()
                    .map(|x| x.parse().unwrap())
                    .collect();
                let j = *stack.last().unwrap();
                joints[j].offset = [v[0], v[1], v[2]];
            }
            "CHANNELS" => {
                let j = *stack.last().unwrap();
                let mut it = rest.split_whitespace();
                let n: usize = it.next().unwrap().parse().unwrap();
                joints[j].first = channel_count;
                for c in it {
                    let c = c.to_ascii_lowercase();
                    let axis = match c.as_bytes()[0] {
                        b'x' => 0,
                        b'y' => 1,
                        _ => 2,
                    };
                    joints[j].channels.push((c.ends_with("position"), axis));
                }
                assert_eq!(joints[j].channels.len(), n);
                channel_count += n;
            }
            "MOTION" => break,
            other => panic!("unexpected BVH line {other:?}"),
        }
    }
    let mut frame_time = 0.0;
    let mut frames = Vec::new();
    for line in lines {
        if let Some(v) = line.strip_prefix("Frames:") {
            let _: usize = v.trim().parse().unwrap();
        } else if let Some(v) = line.strip_prefix("Frame Time:") {
            frame_time = v.trim().parse().unwrap();
        } else {
            let values: Vec<f64> = line
                .split_whitespace()
                .map(|x| x.parse().unwrap())
                .collect();
            assert_eq!(values.len(), channel_count);
            frames.push(values);
        }
    }
    Bvh {
        joints,
        frame_time,
        frames,
    }
}

/// Model-space (rotation, position) of every joint at frame `k`.
fn forward_kinematics(bvh: &Bvh, k: usize) -> Vec<(M3, [f64; 3])> {
    let values = &bvh.frames[k];
    let mut out: Vec<(M3, [f64; 3])> = Vec::with_capacity(bvh.joints.len());
    for j in &bvh.joints {
        let mut t = j.offset;
        let mut r = IDENTITY;
        for (i, &(is_pos, axis)) in j.channels.iter().enumerate() {
            let v = values[j.first + i];
            if is_pos {
                t[axis] = v;
            } else {
                r = mul(&r, &axis_rotation(axis, v));
            }
        }
        out.push(match j.parent {
            None => (r, t),
            Some(p) => {
                let (pr, pt) = out[p];
                let moved = apply(&pr, t);
                (mul(&pr, &r), [0, 1, 2].map(|a| pt[a] + moved[a]))
            }
        });
    }
    out
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

/// Rotation matrix of a unit quaternion (x, y, z, w).
fn quat_matrix(q: &[f64]) -> M3 {
    let (x, y, z, w) = (q[0], q[1], q[2], q[3]);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - z * w),
            2.0 * (x * z + y * w),
        ],
        [
            2.0 * (x * y + z * w),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - x * w),
        ],
        [
            2.0 * (x * z - y * w),
            2.0 * (y * z + x * w),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// Compares one frame of a `--pose` report with the FK of frame `k`; returns the largest position
/// and rotation-matrix differences.
fn compare_frame(bvh: &Bvh, frame: &Value, k: usize) -> (f64, f64) {
    let fk = forward_kinematics(bvh, k);
    let got: HashMap<&str, &Value> = frame["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| (j["name"].as_str().unwrap(), j))
        .collect();
    assert_eq!(got.len(), bvh.joints.len(), "one entry per joint");
    let (mut dp, mut dr) = (0.0f64, 0.0f64);
    for (j, (r, t)) in bvh.joints.iter().zip(&fk) {
        let g = got
            .get(j.name.as_str())
            .unwrap_or_else(|| panic!("no joint {:?} in the report", j.name));
        let gt: Vec<f64> = g["translation"].as_array().unwrap().iter().map(f).collect();
        let gq: Vec<f64> = g["rotation"].as_array().unwrap().iter().map(f).collect();
        let gs: Vec<f64> = g["scale"].as_array().unwrap().iter().map(f).collect();
        let gm: Vec<f64> = g["matrix"].as_array().unwrap().iter().map(f).collect();
        for a in 0..3 {
            dp = dp.max((gt[a] - t[a]).abs());
            // The matrix's fourth column is the translation, bit for bit.
            assert_eq!(gm[12 + a], gt[a], "{}", j.name);
            assert!((gs[a] - 1.0).abs() < 1e-5, "{}: scale {gs:?}", j.name);
        }
        let qm = quat_matrix(&gq);
        for row in 0..3 {
            for col in 0..3 {
                dr = dr.max((qm[row][col] - r[row][col]).abs());
                // Column-major matrix: element (row, col) at col * 4 + row.
                dr = dr.max((gm[col * 4 + row] - r[row][col]).abs());
            }
        }
    }
    (dp, dr)
}

fn pose_json(file: &Path, spec: &str, extra: &[&str]) -> Value {
    let mut args: Vec<std::ffi::OsString> = vec![
        "inspect".into(),
        file.into(),
        "--json".into(),
        "--pose".into(),
        spec.into(),
    ];
    args.extend(extra.iter().map(|s| s.into()));
    let run = sinew(&args);
    assert_eq!(run.code, 0, "inspect --pose {spec}: {}", run.stderr);
    serde_json::from_str(&run.stdout).unwrap()
}

/// Deterministic values in `[-1, 1)`.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// Two roots, channel orders ZXY / XYZ / YZX / ZX / YXZ, a position channel below the root that
/// replaces one OFFSET component, a joint with `CHANNELS 0`, a name with a space and a colon, End
/// Sites, CRLF line ends and tabs.
const HIERARCHY: &str = "HIERARCHY
ROOT Hips
{
\tOFFSET 1.5 2 -3
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT Spine
\t{
\t\tOFFSET 0 10 0.5
\t\tCHANNELS 3 Xrotation Yrotation Zrotation
\t\tJOINT Head
\t\t{
\t\t\tOFFSET 0 8 1
\t\t\tCHANNELS 3 Yrotation Zrotation Xrotation
\t\t\tEnd Site
\t\t\t{
\t\t\t\tOFFSET 0 4 0
\t\t\t}
\t\t}
\t}
\tJOINT Left Up:Leg
\t{
\t\tOFFSET 5 -2 0.25
\t\tCHANNELS 4 Zposition Yrotation Xrotation Zrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 -12 2
\t\t}
\t}
}
ROOT Box
{
\tOFFSET 30 0 -5
\tCHANNELS 3 Yrotation Xrotation Zrotation
\tJOINT Lid
\t{
\t\tOFFSET 0 3 0
\t\tCHANNELS 2 Zrotation Xrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 2 0 0
\t\t}
\t}
\tJOINT Peg
\t{
\t\tOFFSET 1 1 1
\t\tCHANNELS 0
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 0 3
\t\t}
\t}
}
";

/// Channel kinds of HIERARCHY in frame-line order (true = position).
const CHANNEL_IS_POSITION: [bool; 19] = [
    true, true, true, false, false, false, // Hips
    false, false, false, // Spine
    false, false, false, // Head
    true, false, false, false, // Left Up:Leg
    false, false, false, // Box
];

fn synthetic_bvh(frames: usize) -> String {
    let mut rng = Lcg(18);
    let mut text = HIERARCHY.to_string();
    text.push_str(&format!("MOTION\nFrames: {frames}\nFrame Time: 0.04\n"));
    for _ in 0..frames {
        let mut values: Vec<String> = CHANNEL_IS_POSITION
            .iter()
            .map(|&p| format!("{:.4}", rng.next() * if p { 40.0 } else { 175.0 }))
            .collect();
        // Lid: two rotations.
        values.push(format!("{:.4}", rng.next() * 175.0));
        values.push(format!("{:.4}", rng.next() * 175.0));
        text.push_str(&values.join(" "));
        text.push('\n');
    }
    text.replace('\n', "\r\n")
}

#[test]
fn pose_of_a_built_bvh_matches_independent_forward_kinematics() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("twoRoots.bvh");
    let text = synthetic_bvh(9);
    std::fs::write(&path, &text).unwrap();
    let bvh = parse_bvh(&text);
    assert_eq!(bvh.joints.len(), 11, "7 joints and 4 End Sites");
    // Every frame, as a range at the file's own rate (the default).
    let report = pose_json(&path, "twoRoots@0..0.32", &[]);
    assert_eq!(report["clip"], "twoRoots");
    assert_eq!(f(&report["fps"]), 25.0);
    let frames = report["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 9);
    let joints = report["joints"].as_array().unwrap();
    assert_eq!(joints.len(), 11);
    let roots: Vec<&str> = joints
        .iter()
        .filter(|j| j["parent"].is_null())
        .map(|j| j["name"].as_str().unwrap())
        .collect();
    assert_eq!(roots, ["Hips", "Box"]);
    let (mut worst_p, mut worst_r) = (0.0f64, 0.0f64);
    for (k, frame) in frames.iter().enumerate() {
        assert!((f(&frame["time"]) - k as f64 * 0.04).abs() < 1e-6);
        let (dp, dr) = compare_frame(&bvh, frame, k);
        worst_p = worst_p.max(dp);
        worst_r = worst_r.max(dr);
    }
    // Positions reach ~70 units; f32 keeps about 7 digits.
    assert!(worst_p < 1e-4, "largest position difference {worst_p}");
    assert!(
        worst_r < 2e-6,
        "largest rotation-matrix difference {worst_r}"
    );
    // A single time gives the same numbers as the same frame of the range.
    let one = pose_json(&path, "twoRoots@0.12", &[]);
    assert_eq!(one["frames"][0], frames[3]);
    assert!(one["fps"].is_null());
}

#[test]
fn pose_of_corpus_bvh_matches_independent_forward_kinematics() {
    for (file, clip, picks) in [
        ("bvh/Boxing_Toes.bvh", "Boxing_Toes", [0usize, 1234, 3068]),
        ("bvh/cmu_01_01.bvh", "cmu_01_01", [0, 977, 2751]),
    ] {
        let Some(path) = sinew_testdata::corpus_file(file) else {
            return;
        };
        let text = std::fs::read_to_string(&path).unwrap();
        let bvh = parse_bvh(&text);
        for k in picks {
            let t = (k as f64 * bvh.frame_time) as f32;
            let report = pose_json(&path, &format!("{clip}@{t}"), &[]);
            let (dp, dr) = compare_frame(&bvh, &report["frames"][0], k);
            assert!(dp < 2e-4, "{file} frame {k}: position difference {dp}");
            assert!(dr < 2e-6, "{file} frame {k}: rotation difference {dr}");
        }
    }
}

#[test]
fn pose_text_report_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("walk.bvh");
    std::fs::write(&path, synthetic_bvh(3)).unwrap();
    let run = sinew([
        "inspect".as_ref(),
        path.as_os_str(),
        "--pose".as_ref(),
        "walk@0..0.08".as_ref(),
        "--fps".as_ref(),
        "50".as_ref(),
    ]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stdout.is_empty());
    assert!(run.stderr.contains("clip \"walk\""), "{}", run.stderr);
    assert_eq!(run.stderr.matches("t = ").count(), 5, "{}", run.stderr);
    assert!(run.stderr.contains("] Left Up:Leg "), "{}", run.stderr);
    // A clip that is not there, a malformed spec, --fps without a range: exit 2, one line.
    for spec in ["run@0.1", "walk", "walk@x"] {
        let run = sinew([
            "inspect".as_ref(),
            path.as_os_str(),
            "--pose".as_ref(),
            spec.as_ref(),
        ]);
        assert_eq!(run.code, 2, "{spec}: {}", run.stderr);
        assert_eq!(run.stderr_lines().len(), 1, "{spec}: {}", run.stderr);
    }
    let run = sinew([
        "inspect".as_ref(),
        path.as_os_str(),
        "--pose".as_ref(),
        "run@0.1".as_ref(),
    ]);
    assert_one_line_error(&run, &path);
    assert!(
        run.stderr.contains("walk"),
        "lists the clips: {}",
        run.stderr
    );
    // A file without a skeleton.
    let prop = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/prop.obj");
    let run = sinew([
        "inspect".as_ref(),
        prop.as_os_str(),
        "--pose".as_ref(),
        "walk@0".as_ref(),
    ]);
    assert_one_line_error(&run, &prop);
    assert!(run.stderr.contains("no skeleton to pose"), "{}", run.stderr);
}

#[test]
fn pose_of_a_sinew_file_keeps_undriven_joints_at_bind() {
    // fixtures/biped.sinew: "wave" drives the upper body only, so Bip01 sits at its bind pose,
    // T(0, 38, 0) with no rotation (fixtures/README.md), bit for bit.
    let biped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/biped.sinew");
    let r = pose_json(&biped, "wave@0.5", &[]);
    assert_eq!(r["joints"].as_array().unwrap().len(), 22);
    let root = &r["frames"][0]["joints"][0];
    assert_eq!(root["name"], "Bip01");
    assert_eq!(root["translation"], serde_json::json!([0.0, 38.0, 0.0]));
    assert_eq!(root["rotation"], serde_json::json!([0.0, 0.0, 0.0, 1.0]));
}
