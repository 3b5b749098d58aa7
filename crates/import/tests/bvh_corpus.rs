//! Every corpus BVH file imports with asserted content: joint counts and names, frame counts, rates,
//! and joint local transforms at chosen frames, worked out here from the file's numbers.
#![allow(clippy::unwrap_used)]

use sinew_core::glam::{Mat3, Quat, Vec3};
use sinew_core::{ClipBinding, Sampler, Transform};
use sinew_import::{bvh, ImportError, ImportOptions, Location};
use sinew_scene::Scene;
use sinew_testdata::read_corpus;

fn no_resolve(_: &str) -> std::io::Result<Vec<u8>> {
    Err(std::io::Error::other("no"))
}

fn import_bytes(name: &str, bytes: &[u8]) -> Result<Scene, ImportError> {
    bvh::import(name, bytes, &no_resolve, &ImportOptions::default())
}

/// What the test reads from the raw text, independently of the importer: joints in file order with
/// their channel lists and first channel index, and frame lines.
struct Raw {
    joints: Vec<(String, [f32; 3], Vec<String>, usize)>,
    frames: Vec<Vec<f32>>,
    frame_time: f64,
}

fn raw(text: &str) -> Raw {
    let mut joints = Vec::new();
    let mut total = 0;
    let mut lines = text.lines().map(str::trim);
    let mut last_offset = [0.0; 3];
    let mut in_end = false;
    for l in lines.by_ref() {
        if l.starts_with("ROOT ") || l.starts_with("JOINT ") {
            let name = l.split_once(' ').unwrap().1.trim().to_string();
            joints.push((name, [0.0; 3], Vec::new(), total));
            in_end = false;
        } else if l.starts_with("End Site") {
            in_end = true;
        } else if l.starts_with("OFFSET") {
            let v: Vec<f32> = l
                .split_whitespace()
                .skip(1)
                .map(|t| t.parse().unwrap())
                .collect();
            last_offset = [v[0], v[1], v[2]];
            if !in_end {
                joints.last_mut().unwrap().1 = last_offset;
            }
        } else if l.starts_with("CHANNELS") {
            let ch: Vec<String> = l.split_whitespace().skip(2).map(String::from).collect();
            let j = joints.last_mut().unwrap();
            j.3 = total;
            total += ch.len();
            j.2 = ch;
        } else if l == "}" {
            in_end = false;
        } else if l == "MOTION" {
            break;
        }
    }
    let _ = last_offset;
    let _frames_line = lines.next().unwrap();
    let ft: f64 = lines
        .next()
        .unwrap()
        .split(':')
        .nth(1)
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    let frames = lines
        .filter(|l| !l.is_empty())
        .map(|l| l.split_whitespace().map(|t| t.parse().unwrap()).collect())
        .collect();
    Raw {
        joints,
        frames,
        frame_time: ft,
    }
}

/// Local transform of joint `j` at frame `k`, from the raw numbers: rotation matrices multiplied in
/// channel order (column vectors), positions replacing the OFFSET components.
fn expected_local(r: &Raw, j: usize, k: usize) -> (Vec3, Mat3) {
    let (_, off, ch, first) = &r.joints[j];
    let mut t = Vec3::from_array(*off);
    let mut m = Mat3::IDENTITY;
    for (i, c) in ch.iter().enumerate() {
        let v = r.frames[k][first + i];
        match c.as_str() {
            "Xposition" => t.x = v,
            "Yposition" => t.y = v,
            "Zposition" => t.z = v,
            "Xrotation" => m *= Mat3::from_rotation_x(v.to_radians()),
            "Yrotation" => m *= Mat3::from_rotation_y(v.to_radians()),
            "Zrotation" => m *= Mat3::from_rotation_z(v.to_radians()),
            other => panic!("channel {other}"),
        }
    }
    (t, m)
}

/// Samples the imported clip through sinew-core at frame k's time and compares every animated joint
/// with the raw numbers.
fn check_frames(s: &Scene, r: &Raw, frames: &[usize]) {
    let sk = s.skeleton.as_ref().unwrap();
    let sc = &s.clips[0];
    let clip = sc.to_clip().unwrap();
    let binding = ClipBinding::new(&clip, sk);
    assert!(binding.unmatched().is_empty());
    let mut sampler = Sampler::new();
    let mut out = vec![Transform::IDENTITY; sk.len()];
    for &k in frames {
        let t = (k as f64 * r.frame_time) as f32;
        sampler.sample(&clip, &binding, sk, t, &mut out).unwrap();
        for (j, (name, ..)) in r.joints.iter().enumerate() {
            let idx = sk.find(name).unwrap() as usize;
            let (et, em) = expected_local(r, j, k);
            let got = out[idx];
            assert!(
                (got.translation - et).length() < 1e-3 * (1.0 + et.length()),
                "{name} frame {k}: {} vs {et}",
                got.translation
            );
            let gm = Mat3::from_quat(got.rotation);
            let diff = (gm - em)
                .to_cols_array()
                .iter()
                .fold(0.0f32, |a, b| a.max(b.abs()));
            assert!(diff < 1e-5, "{name} frame {k}: rotation differs by {diff}");
        }
    }
}

fn load(rel: &str) -> Option<(Scene, Raw)> {
    let bytes = read_corpus(rel)?;
    let s = import_bytes(rel, &bytes).unwrap();
    let r = raw(&String::from_utf8(bytes).unwrap());
    Some((s, r))
}

fn end_site_count(text_rel: &str) -> usize {
    String::from_utf8(read_corpus(text_rel).unwrap())
        .unwrap()
        .matches("End Site")
        .count()
}

#[test]
fn cmu_01_01() {
    let Some((s, r)) = load("bvh/cmu_01_01.bvh") else {
        return;
    };
    let sk = s.skeleton.as_ref().unwrap();
    assert_eq!(r.joints.len(), 31);
    assert_eq!(end_site_count("bvh/cmu_01_01.bvh"), 7);
    assert_eq!(sk.len(), 31 + 7);
    assert_eq!(sk.names()[0], "Hips");
    assert!(
        sk.find("LeftHandIndex1_end").is_some()
            || sk.names().iter().filter(|n| n.ends_with("_end")).count() == 7
    );
    let c = &s.clips[0];
    assert_eq!(c.name, "cmu_01_01");
    assert_eq!(r.frames.len(), 2752);
    assert_eq!(c.tracks[0].rotation.times.len(), 2752);
    assert!((c.sample_rate - 120.0).abs() < 0.01, "{}", c.sample_rate);
    assert!((c.duration - 2751.0 * 0.0083333).abs() < 1e-4);
    assert!(!c.looping);
    // Root motion: frame 0 of the file starts `9.3722 17.8693 -17.3198`.
    assert_eq!(c.tracks[0].joint, "Hips");
    assert_eq!(
        c.tracks[0].translation.values[0].to_array(),
        [9.3722, 17.8693, -17.3198]
    );
    check_frames(&s, &r, &[0, 1, 1000, 2751]);
}

#[test]
fn cmu_walk_crlf() {
    let Some((s, r)) = load("bvh/cmu_walk_crlf.bvh") else {
        return;
    };
    assert_eq!(s.skeleton.as_ref().unwrap().len(), 31 + 7);
    assert_eq!(s.clips[0].tracks[0].rotation.times.len(), 344);
    assert_eq!(r.frames.len(), 344);
    check_frames(&s, &r, &[0, 100, 343]);
}

#[test]
fn boxing_toes_zxy_100hz() {
    let Some((s, r)) = load("bvh/Boxing_Toes.bvh") else {
        return;
    };
    assert_eq!(r.joints.len(), 21);
    assert_eq!(s.skeleton.as_ref().unwrap().len(), 21 + 5);
    assert_eq!(r.joints[1].2, ["Zrotation", "Xrotation", "Yrotation"]);
    let c = &s.clips[0];
    assert_eq!(c.tracks[0].rotation.values.len(), 3069);
    assert!((c.sample_rate - 100.0).abs() < 1e-3);
    assert!((c.duration - 30.68).abs() < 1e-4);
    check_frames(&s, &r, &[0, 1500, 3068]);
}

#[test]
fn pfnn_hierarchy() {
    let Some((s, r)) = load("bvh/pfnn_hierarchy_crlf.bvh") else {
        return;
    };
    assert_eq!(s.skeleton.as_ref().unwrap().len(), 38);
    assert_eq!(r.frames.len(), 60);
    assert!((s.clips[0].sample_rate - 30.0).abs() < 1e-3);
    check_frames(&s, &r, &[0, 59]);
}

#[test]
fn sinusoidal_leaf_without_end_site() {
    let Some((s, r)) = load("bvh/sinusoidal_xyz.bvh") else {
        return;
    };
    let sk = s.skeleton.as_ref().unwrap();
    assert_eq!(sk.names(), ["base", "child1", "child2", "child3"]);
    assert_eq!(sk.parents(), [None, Some(0), Some(1), Some(2)]);
    assert_eq!(sk.bind_local()[2].translation.to_array(), [-5.0, 0.0, 0.0]);
    let c = &s.clips[0];
    assert_eq!(c.tracks.len(), 4);
    assert!((c.sample_rate - 60.0).abs() < 1e-3);
    assert!((c.duration - 119.0 / 60.0).abs() < 1e-5);
    // child2's Xrotation is -90 degrees at frame 0.
    let q = c.tracks[2].rotation.values[0];
    assert!(q.angle_between(Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2)) < 1e-3);
    check_frames(&s, &r, &[0, 30, 119]);
}

#[test]
fn test_simple_two_frames() {
    let Some((s, r)) = load("bvh/test_simple.bvh") else {
        return;
    };
    let sk = s.skeleton.as_ref().unwrap();
    assert_eq!(sk.names(), ["Base", "End", "End_end"]);
    assert_eq!(sk.bind_local()[2].translation.to_array(), [0.0, 0.0, 30.0]);
    let c = &s.clips[0];
    assert_eq!(c.tracks[1].rotation.times, [0.0, 0.033_333_333_f64 as f32]);
    // Frame 1: all channels 1.0 -> root at (1, 1, 1), rotation Rz(1) Rx(1) Ry(1).
    assert_eq!(
        c.tracks[0].translation.values[1].to_array(),
        [1.0, 1.0, 1.0]
    );
    assert!(c.tracks[1].translation.is_empty());
    check_frames(&s, &r, &[0, 1]);
}

fn line_of(e: &ImportError) -> usize {
    match e.location {
        Location::Line(l) => l,
        ref other => panic!("expected a line, got {other:?} in {e}"),
    }
}

const SMALL: &str = "HIERARCHY\nROOT mixamorig:Hips\n{\n  OFFSET 1 2 3\n  CHANNELS 3 Xposition Yposition Zposition\n  JOINT Left Up Leg \n  {\n    OFFSET 0 -1 0\n    CHANNELS 4 Yrotation Xposition Zrotation Xrotation\n    End Site\n    {\n      OFFSET 0 -1 0\n    }\n  }\n}\nROOT Prop\n{\n  OFFSET 5 0 0\n  CHANNELS 1 Yrotation\n}\nMOTION\nFrames:   2\nFrame Time:\t0.5\n0 0 0  10 7 20 30 40\n1 2 3  0 0 0 0 0\n";

#[test]
fn names_multiple_roots_and_position_channels_below_root() {
    let s = import_bytes("m.bvh", SMALL.replace('\n', "\r\n").as_bytes()).unwrap();
    let sk = s.skeleton.as_ref().unwrap();
    assert_eq!(
        sk.names(),
        ["mixamorig:Hips", "Left Up Leg", "Left Up Leg_end", "Prop"]
    );
    assert_eq!(sk.parents(), [None, Some(0), Some(1), None]);
    let c = &s.clips[0];
    assert_eq!(c.duration, 0.5);
    assert_eq!(c.sample_rate, 2.0);
    let leg = c.tracks.iter().find(|t| t.joint == "Left Up Leg").unwrap();
    // Xposition replaces OFFSET.x; y, z stay from OFFSET.
    assert_eq!(leg.translation.values[0].to_array(), [7.0, -1.0, 0.0]);
    let expect = Mat3::from_rotation_y(10f32.to_radians())
        * Mat3::from_rotation_z(20f32.to_radians())
        * Mat3::from_rotation_x(30f32.to_radians());
    let got = Mat3::from_quat(leg.rotation.values[0]);
    assert!((got - expect)
        .to_cols_array()
        .iter()
        .all(|d| d.abs() < 1e-5));
    let hips = &c.tracks[0];
    assert_eq!(hips.translation.values[1].to_array(), [1.0, 2.0, 3.0]);
    assert!(hips.rotation.is_empty());
    assert_eq!(c.tracks.len(), 3);
    // Prop's single Yrotation channel is the last value of the line.
    let prop = Mat3::from_quat(c.tracks[2].rotation.values[0]);
    let expect = Mat3::from_rotation_y(40f32.to_radians());
    assert!((prop - expect)
        .to_cols_array()
        .iter()
        .all(|d| d.abs() < 1e-5));
}

#[test]
fn errors_name_the_line() {
    let cases: &[(&str, &str, usize)] = &[
        ("Frames:   2", "Frames:   3", 25),
        ("0 0 0  10 7 20 30 40", "0 0 0  10 7 20 30", 24),
        ("0 0 0  10 7 20 30 40", "0 0 0  10 7 20 30 40 1", 24),
        ("1 2 3  0 0 0 0 0", "1 2 3  0 0 0 0 inf", 25),
        ("1 2 3  0 0 0 0 0", "1 2 3  0 0 0 0 NaN", 25),
        ("1 2 3  0 0 0 0 0", "1 2 3  0 0 0 0 x", 25),
        ("CHANNELS 4 Yrotation", "CHANNELS 5 Yrotation", 9),
        ("CHANNELS 4 Yrotation", "CHANNELS 4 Wrotation", 9),
        (
            "OFFSET 0 -1 0\n    CHANNELS",
            "OFFSET 0 -1\n    CHANNELS",
            8,
        ),
        ("JOINT Left Up Leg ", "JOINT mixamorig:Hips", 6),
        ("Frame Time:\t0.5", "Frame Time:\t0", 23),
        ("Frame Time:\t0.5", "Frame Tim: 0.5", 23),
        ("    }\n  }\n}\nROOT", "    }\n  }\nROOT", 15),
        ("HIERARCHY", "HIERARCHX", 1),
    ];
    for (from, to, line) in cases {
        assert!(SMALL.contains(from), "{from}");
        let text = SMALL.replacen(from, to, 1);
        let e = import_bytes("m.bvh", text.as_bytes()).unwrap_err();
        assert_eq!(line_of(&e), *line, "{to}: {e}");
        assert!(e.to_string().starts_with("m.bvh: "), "{e}");
    }
    assert!(import_bytes("m.bvh", b"").is_err());
}

#[test]
fn huge_frame_count_is_checked_before_allocating() {
    let text = SMALL.replace("Frames:   2", "Frames: 18446744073709551615");
    let e = import_bytes("m.bvh", text.as_bytes()).unwrap_err();
    assert!(e.message.contains("only 2 frame lines"), "{e}");
}

#[test]
fn many_channels_times_many_short_lines_is_an_error_not_an_allocation() {
    // 1000 joints x 60 channels declared, then many one-value lines: the reservation must be capped by
    // the bytes present, and the first short line is the error.
    let mut text = String::from("HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\nCHANNELS 60");
    for _ in 0..10 {
        text.push_str(" Xrotation Yrotation Zrotation Xposition Yposition Zposition");
    }
    text.push('\n');
    for i in 0..999 {
        text.push_str(&format!(
            "JOINT j{i}\n{{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n}}\n"
        ));
    }
    text.push_str("}\nMOTION\nFrames: 100000\nFrame Time: 0.1\n");
    let header_lines = text.lines().count();
    text.push_str(&"1\n".repeat(100_000));
    let e = import_bytes("m.bvh", text.as_bytes()).unwrap_err();
    assert_eq!(line_of(&e), header_lines + 1, "{e}");
    assert!(e.message.contains("has 1 values, expected 3057"), "{e}");
}
