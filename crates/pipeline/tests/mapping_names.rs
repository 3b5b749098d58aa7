//! Joint-name mapping on real names: the corpus BVH files (names read by a plain line scan, not an
//! importer) against hand-written Biped, old Half-Life Biped and Mixamo name lists.

#![allow(clippy::unwrap_used)] // test helpers panic on broken fixtures by design

use sinew_core::{Curve, TrackCurves};
use sinew_pipeline::mapping::{
    apply_mapping, map_joints, read_mapping, write_mapping, Family, JointSet, MappingError,
    MatchMethod, Slot,
};
use sinew_scene::SceneClip;

/// Joint names and parents from `ROOT name` / `JOINT name` lines and braces.
fn bvh_joints(bytes: &[u8]) -> JointSet {
    let text = String::from_utf8_lossy(bytes);
    let mut names = Vec::new();
    let mut parents = Vec::new();
    // Stack of open blocks: Some(joint index) for a joint block, None for an End Site block.
    let mut stack: Vec<Option<usize>> = Vec::new();
    let mut pending: Option<Option<usize>> = None;
    for line in text.lines() {
        let line = line.trim();
        if line.starts_with("MOTION") {
            break;
        }
        if let Some(rest) = line
            .strip_prefix("ROOT ")
            .or_else(|| line.strip_prefix("JOINT "))
        {
            let parent = stack.iter().rev().flatten().next().copied();
            names.push(rest.trim().to_string());
            parents.push(parent);
            pending = Some(Some(names.len() - 1));
        } else if line.starts_with("End Site") {
            pending = Some(None);
        } else if line.starts_with('{') {
            stack.push(pending.take().flatten());
        } else if line.starts_with('}') {
            stack.pop();
        }
    }
    JointSet::new(names, parents)
}

fn biped_names() -> Vec<String> {
    let mut v: Vec<String> = [
        "Bip01",
        "Bip01 Pelvis",
        "Bip01 Spine",
        "Bip01 Spine1",
        "Bip01 Neck",
        "Bip01 Head",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for side in ["L", "R"] {
        for part in [
            "Clavicle", "UpperArm", "Forearm", "Hand", "Thigh", "Calf", "Foot", "Toe0",
        ] {
            v.push(format!("Bip01 {side} {part}"));
        }
    }
    v
}

/// The Biped list with parents: pelvis under Bip01, spine chain, arms under Spine1, legs under Pelvis.
fn biped() -> JointSet {
    let names = biped_names();
    let idx = |n: &str| names.iter().position(|x| x == n).unwrap();
    let parent_name = |n: &str| -> Option<String> {
        let rest = n.strip_prefix("Bip01 ")?;
        let side = rest.split(' ').next().unwrap();
        let p = match rest {
            "Pelvis" => "Bip01".to_string(),
            "Spine" => "Bip01 Pelvis".into(),
            "Spine1" => "Bip01 Spine".into(),
            "Neck" => "Bip01 Spine1".into(),
            "Head" => "Bip01 Neck".into(),
            _ if rest.ends_with("Clavicle") => "Bip01 Spine1".into(),
            _ if rest.ends_with("UpperArm") => format!("Bip01 {side} Clavicle"),
            _ if rest.ends_with("Forearm") => format!("Bip01 {side} UpperArm"),
            _ if rest.ends_with("Hand") => format!("Bip01 {side} Forearm"),
            _ if rest.ends_with("Thigh") => "Bip01 Pelvis".into(),
            _ if rest.ends_with("Calf") => format!("Bip01 {side} Thigh"),
            _ if rest.ends_with("Foot") => format!("Bip01 {side} Calf"),
            _ if rest.ends_with("Toe0") => format!("Bip01 {side} Foot"),
            _ => return None,
        };
        Some(p)
    };
    let parents = names
        .iter()
        .map(|n| parent_name(n).map(|p| idx(&p)))
        .collect();
    JointSet::new(names.clone(), parents)
}

fn expect(
    mapping: &sinew_pipeline::mapping::Mapping,
    rig: &str,
    motion: &str,
    method: MatchMethod,
) {
    let e = mapping
        .entry(rig)
        .unwrap_or_else(|| panic!("no entry {rig}"));
    assert_eq!(e.motion.as_deref(), Some(motion), "motion joint of {rig}");
    assert_eq!(e.method, Some(method), "method of {rig}");
}

#[test]
fn biped_rig_against_cmu_bvh_files() {
    for file in [
        "bvh/cmu_01_01.bvh",
        "bvh/cmu_walk_crlf.bvh",
        "bvh/pfnn_hierarchy_crlf.bvh",
    ] {
        let Some(bytes) = sinew_testdata::read_corpus(file) else {
            return;
        };
        let motion = bvh_joints(&bytes);
        assert_eq!(motion.names().len(), 31, "{file}");
        let m = map_joints(&biped(), &motion);
        assert_eq!(m.rig_family, Family::Biped);
        assert_eq!(m.motion_family, Family::Cmu);
        let syn = |slot| MatchMethod::Synonym { slot };
        expect(&m, "Bip01 Pelvis", "Hips", syn(Slot::Hips));
        expect(&m, "Bip01 Spine", "Spine", MatchMethod::Normalised);
        expect(&m, "Bip01 Spine1", "Spine1", MatchMethod::Normalised);
        expect(&m, "Bip01 Neck", "Neck", MatchMethod::Normalised);
        expect(&m, "Bip01 Head", "Head", MatchMethod::Normalised);
        for (s, side) in [("L", "Left"), ("R", "Right")] {
            let r = |p: &str| format!("Bip01 {s} {p}");
            let c = |p: &str| format!("{side}{p}");
            expect(&m, &r("Clavicle"), &c("Shoulder"), syn(Slot::Clavicle));
            expect(&m, &r("UpperArm"), &c("Arm"), syn(Slot::UpperArm));
            expect(&m, &r("Forearm"), &c("ForeArm"), MatchMethod::Normalised);
            expect(&m, &r("Hand"), &c("Hand"), MatchMethod::Normalised);
            expect(&m, &r("Thigh"), &c("UpLeg"), syn(Slot::Thigh));
            expect(&m, &r("Calf"), &c("Leg"), syn(Slot::Calf));
            expect(&m, &r("Foot"), &c("Foot"), MatchMethod::Normalised);
            expect(&m, &r("Toe0"), &c("ToeBase"), syn(Slot::Toe));
        }
        // Only the Biped root has no counterpart in the CMU layout.
        assert_eq!(m.unmatched_rig(), ["Bip01"], "{file}");
        for helper in [
            "LHipJoint",
            "RHipJoint",
            "LowerBack",
            "Neck1",
            "LThumb",
            "RThumb",
        ] {
            assert!(
                m.unmatched_motion.iter().any(|n| n == helper),
                "{file}: {helper} should stay unmatched: {:?}",
                m.unmatched_motion
            );
        }
        // 22 rig joints, 21 bound.
        assert_eq!(
            m.unmatched_motion.len(),
            31 - 21,
            "{:?}",
            m.unmatched_motion
        );
        // Spine: Biped Spine, Spine1 vs CMU LowerBack, Spine, Spine1; neck: Neck vs Neck, Neck1.
        let codes: Vec<&str> = m.warnings.iter().map(|w| w.code.as_str()).collect();
        assert!(codes.contains(&"spine-count"), "{codes:?}");
        assert!(codes.contains(&"neck-count"), "{codes:?}");
        let spine = m.warnings.iter().find(|w| w.code == "spine-count").unwrap();
        assert_eq!(spine.figures, [("rig".into(), 2.0), ("motion".into(), 3.0)]);
        assert!(spine.message.contains("LowerBack"), "{}", spine.message);
        // Biped meets CMU and "LeftLeg" is in a pair: the Leg warning names it.
        let leg = m
            .warnings
            .iter()
            .find(|w| w.code == "leg-ambiguity")
            .unwrap();
        assert!(
            leg.message.contains("\"LeftLeg\" read as calf"),
            "{}",
            leg.message
        );
    }
}

#[test]
fn unkeyed_helpers_are_reported() {
    let Some(bytes) = sinew_testdata::read_corpus("bvh/cmu_walk_crlf.bvh") else {
        return;
    };
    let motion = bvh_joints(&bytes);
    // Constant channels in this file (checked by reading the MOTION columns): the hip joints and the
    // shoulders.
    let keyed: Vec<bool> = motion
        .names()
        .iter()
        .map(|n| {
            !matches!(
                n.as_str(),
                "LHipJoint" | "RHipJoint" | "LeftShoulder" | "RightShoulder"
            )
        })
        .collect();
    let motion = motion.with_keyed(&keyed);
    let m = map_joints(&biped(), &motion);
    let w = m
        .warnings
        .iter()
        .find(|w| w.code == "unkeyed-helpers")
        .unwrap();
    assert_eq!(w.figures, [("count".into(), 4.0)]);
    assert!(w.message.contains("LHipJoint, "), "{}", w.message);
    assert!(
        w.message
            .contains("LeftShoulder (bound to Bip01 L Clavicle)"),
        "{}",
        w.message
    );
}

#[test]
fn old_half_life_biped_reads_leg_as_thigh() {
    let Some(bytes) = sinew_testdata::read_corpus("bvh/cmu_01_01.bvh") else {
        return;
    };
    let motion = bvh_joints(&bytes);
    let rig = JointSet::from_names(&[
        "Bip01",
        "Bip01 Pelvis",
        "Bip01 Spine",
        "Bip01 Spine1",
        "Bip01 Spine2",
        "Bip01 Spine3",
        "Bip01 Neck",
        "Bip01 Head",
        "Bip01 L Arm",
        "Bip01 L Arm1",
        "Bip01 L Arm2",
        "Bip01 L Hand",
        "Bip01 L Leg",
        "Bip01 L Leg1",
        "Bip01 L Foot",
        "Bip01 R Leg",
        "Bip01 R Leg1",
        "Bip01 R Foot",
    ]);
    let m = map_joints(&rig, &motion);
    let syn = |slot| MatchMethod::Synonym { slot };
    // "Bip01 L Leg" and "LeftLeg" normalise alike but mean thigh and calf: the name match is refused.
    expect(&m, "Bip01 L Leg", "LeftUpLeg", syn(Slot::Thigh));
    expect(&m, "Bip01 L Leg1", "LeftLeg", syn(Slot::Calf));
    expect(&m, "Bip01 R Leg", "RightUpLeg", syn(Slot::Thigh));
    expect(&m, "Bip01 R Leg1", "RightLeg", syn(Slot::Calf));
    expect(&m, "Bip01 L Arm", "LeftShoulder", syn(Slot::Clavicle));
    expect(&m, "Bip01 L Arm1", "LeftArm", syn(Slot::UpperArm));
    expect(&m, "Bip01 L Arm2", "LeftForeArm", syn(Slot::Forearm));
    let leg = m
        .warnings
        .iter()
        .find(|w| w.code == "leg-ambiguity")
        .unwrap();
    assert!(
        leg.message
            .contains("\"Bip01 L Leg\" read as thigh -> \"LeftUpLeg\" read as thigh"),
        "{}",
        leg.message
    );
    let conflicts: Vec<&str> = m
        .warnings
        .iter()
        .filter(|w| w.code == "slot-conflict")
        .map(|w| w.message.as_str())
        .collect();
    // Arm (clavicle here, upper arm in CMU) and both Legs.
    assert_eq!(conflicts.len(), 3, "{conflicts:?}");
    assert!(conflicts[0].contains("\"Bip01 L Arm\" and motion joint \"LeftArm\""));
    assert!(conflicts[1].contains("\"Bip01 L Leg\" and motion joint \"LeftLeg\""));
    // Flat rig (no parents): spine chain paired by input order, counts differ (4 vs 3).
    let spine = m.warnings.iter().find(|w| w.code == "spine-count").unwrap();
    assert_eq!(spine.figures, [("rig".into(), 4.0), ("motion".into(), 3.0)]);
}

#[test]
fn mixamo_names_map_to_cmu_by_normalisation() {
    let Some(bytes) = sinew_testdata::read_corpus("bvh/cmu_walk_crlf.bvh") else {
        return;
    };
    let cmu = bvh_joints(&bytes);
    let mixamo_names: Vec<String> = [
        "Hips",
        "Spine",
        "Spine1",
        "Neck",
        "Head",
        "LeftShoulder",
        "LeftArm",
        "LeftForeArm",
        "LeftHand",
        "LeftUpLeg",
        "LeftLeg",
        "LeftFoot",
        "LeftToeBase",
        "RightUpLeg",
        "RightLeg",
    ]
    .iter()
    .map(|n| format!("mixamorig:{n}"))
    .collect();
    let rig = JointSet::from_names(&mixamo_names);
    let m = map_joints(&rig, &cmu);
    assert_eq!(m.rig_family, Family::Mixamo);
    for n in &mixamo_names {
        let bare = n.strip_prefix("mixamorig:").unwrap();
        expect(&m, n, bare, MatchMethod::Normalised);
    }
    assert!(!m.warnings.iter().any(|w| w.code == "leg-ambiguity"));
}

#[test]
fn biovision_shoulder_under_collar_is_upper_arm() {
    let Some(bytes) = sinew_testdata::read_corpus("bvh/Boxing_Toes.bvh") else {
        return;
    };
    let motion = bvh_joints(&bytes);
    let m = map_joints(&biped(), &motion);
    let syn = |slot| MatchMethod::Synonym { slot };
    expect(&m, "Bip01 L Clavicle", "LeftCollar", syn(Slot::Clavicle));
    expect(&m, "Bip01 L UpperArm", "LeftShoulder", syn(Slot::UpperArm));
    expect(&m, "Bip01 L Forearm", "LeftElbow", syn(Slot::Forearm));
    expect(&m, "Bip01 L Hand", "LeftWrist", syn(Slot::Hand));
    expect(&m, "Bip01 L Thigh", "LeftHip", syn(Slot::Thigh));
    expect(&m, "Bip01 L Calf", "LeftKnee", syn(Slot::Calf));
    expect(&m, "Bip01 L Foot", "LeftAnkle", syn(Slot::Foot));
    expect(&m, "Bip01 L Toe0", "LeftToes", syn(Slot::Toe));
    // Ab, Chest form the spine chain in order.
    expect(&m, "Bip01 Spine", "Ab", syn(Slot::Spine));
    expect(&m, "Bip01 Spine1", "Chest", syn(Slot::Spine));
    expect(&m, "Bip01 Pelvis", "Hips", syn(Slot::Hips));

    // Rig and motion the other way round: the CMU LeftShoulder is a clavicle, so the exact name match
    // with the Biovision LeftShoulder (an upper arm) is refused.
    let Some(cmu) = sinew_testdata::read_corpus("bvh/cmu_walk_crlf.bvh") else {
        return;
    };
    let m = map_joints(&motion, &bvh_joints(&cmu));
    expect(&m, "LeftShoulder", "LeftArm", syn(Slot::UpperArm));
    expect(&m, "LeftCollar", "LeftShoulder", syn(Slot::Clavicle));
    expect(&m, "Hips", "Hips", MatchMethod::Exact);
}

#[test]
fn fuzzy_matches_misspellings_with_a_score() {
    let rig = JointSet::from_names(&["Bip01 L Forarm", "Bip01 Ponytail1", "Bip01 Tail"]);
    let motion = JointSet::from_names(&["LeftForeArm", "Ponytail", "Wing"]);
    let m = map_joints(&rig, &motion);
    let e = m.entry("Bip01 L Forarm").unwrap();
    assert_eq!(e.motion.as_deref(), Some("LeftForeArm"));
    // "forarm" vs "forearm": one insertion over 7 characters.
    assert_eq!(
        e.method,
        Some(MatchMethod::Fuzzy {
            score: 1.0 - 1.0 / 7.0
        })
    );
    let e = m.entry("Bip01 Ponytail1").unwrap();
    assert_eq!(e.motion.as_deref(), Some("Ponytail"));
    assert_eq!(
        e.method,
        Some(MatchMethod::Fuzzy {
            score: 1.0 - 1.0 / 9.0
        })
    );
    assert_eq!(m.unmatched_rig(), ["Bip01 Tail"]);
    assert_eq!(m.unmatched_motion, ["Wing"]);
}

#[test]
fn each_motion_joint_is_used_once() {
    let rig = JointSet::from_names(&["Head", "head", "HEAD"]);
    let motion = JointSet::from_names(&["Head"]);
    let m = map_joints(&rig, &motion);
    assert_eq!(m.pairs().collect::<Vec<_>>(), [("Head", "Head")]);
    assert_eq!(m.unmatched_rig(), ["head", "HEAD"]);
}

#[test]
fn mapping_file_round_trip_and_rejections() {
    let rig = biped().with_label("hl_scientist.ms3d");
    let motion = JointSet::from_names(&["Hips", "LeftUpLeg", "LeftLeg", "Head", "Extra \"q\""])
        .with_label("walk.bvh");
    let m = map_joints(&rig, &motion);
    let text = write_mapping(&m);
    assert!(text.starts_with(
        "{\n  \"version\": 1,\n  \"rig\": \"hl_scientist.ms3d\",\n  \"motion\": \"walk.bvh\",\n  \"joints\": {\n    \"Bip01\": null,\n    \"Bip01 Pelvis\": \"Hips\",\n"
    ), "{text}");
    assert!(text.contains("    \"Bip01 L Thigh\": \"LeftUpLeg\",\n"));
    assert!(
        text.ends_with("    \"Bip01 R Toe0\": null\n  }\n}\n"),
        "{text}"
    );
    let back = read_mapping(&text, &rig, &motion).unwrap();
    assert_eq!(back.rig, "hl_scientist.ms3d");
    assert_eq!(back.motion, "walk.bvh");
    assert_eq!(
        back.pairs().collect::<Vec<_>>(),
        m.pairs().collect::<Vec<_>>()
    );
    assert_eq!(back.pairs().count(), 4);
    assert!(back
        .entries
        .iter()
        .filter(|e| e.motion.is_some())
        .all(|e| e.method == Some(MatchMethod::File)));
    assert_eq!(back.unmatched_motion, ["Extra \"q\""]);
    assert_eq!(write_mapping(&back), text);

    // An edited file: a hand-made pair for the odd joint.
    let edited = r#"{"version":1,"rig":"r","motion":"m","joints":{"Bip01 Head":"Extra \"q\""}}"#;
    let e = read_mapping(edited, &rig, &motion).unwrap();
    assert_eq!(
        e.pairs().collect::<Vec<_>>(),
        [("Bip01 Head", "Extra \"q\"")]
    );

    let bad_rig = r#"{"version":1,"joints":{"Bip01 L Wing":"Hips"}}"#;
    let err = read_mapping(bad_rig, &rig, &motion).unwrap_err();
    assert_eq!(
        err,
        MappingError::UnknownRigJoint {
            name: "Bip01 L Wing".into(),
            label: "hl_scientist.ms3d".into()
        }
    );
    assert!(err.to_string().contains("\"Bip01 L Wing\""));
    let bad_motion = r#"{"version":1,"joints":{"Bip01 Head":"Skull"}}"#;
    let err = read_mapping(bad_motion, &rig, &motion).unwrap_err();
    assert_eq!(
        err.to_string(),
        "mapping file: motion joint \"Skull\" (for rig joint \"Bip01 Head\") does not exist in the motion \"walk.bvh\""
    );
    let dup = r#"{"version":1,"joints":{"Bip01 Head":"Hips","Bip01 Pelvis":"Hips"}}"#;
    assert!(matches!(
        read_mapping(dup, &rig, &motion).unwrap_err(),
        MappingError::DuplicateMotionJoint { name, .. } if name == "Hips"
    ));
    assert_eq!(
        read_mapping(r#"{"version":2,"joints":{}}"#, &rig, &motion).unwrap_err(),
        MappingError::Version("2".into())
    );
    assert!(matches!(
        read_mapping(r#"{"version":1,"joints":{"Bip01":3}}"#, &rig, &motion).unwrap_err(),
        MappingError::Shape { path, .. } if path == "joints.\"Bip01\""
    ));
    assert!(matches!(
        read_mapping("{\"version\":1,", &rig, &motion).unwrap_err(),
        MappingError::Json(_)
    ));
}

#[test]
fn apply_mapping_renames_and_drops() {
    let rig = biped();
    let motion = JointSet::from_names(&["Hips", "LeftUpLeg", "LHipJoint"]);
    let m = map_joints(&rig, &motion);
    let track = |j: &str, x: f32| TrackCurves {
        joint: j.into(),
        translation: Curve::new(vec![0.0], vec![sinew_core::glam::Vec3::splat(x)]),
        ..Default::default()
    };
    let clip = SceneClip {
        name: "walk".into(),
        duration: 1.0,
        sample_rate: 30.0,
        looping: true,
        additive: false,
        tracks: vec![
            track("LHipJoint", 1.0),
            track("LeftUpLeg", 2.0),
            track("Hips", 3.0),
        ],
    };
    let out = apply_mapping(&clip, &m);
    let names: Vec<&str> = out.tracks.iter().map(|t| t.joint.as_str()).collect();
    assert_eq!(names, ["Bip01 Pelvis", "Bip01 L Thigh"]);
    assert_eq!(out.tracks[0].translation.values[0].x, 3.0);
    assert_eq!(out.tracks[1].translation.values[0].x, 2.0);
    assert_eq!((out.name.as_str(), out.looping), ("walk", true));
}

#[test]
fn keyed_flags_come_from_varying_tracks() {
    use sinew_core::glam::{Quat, Vec3};
    use sinew_core::{JointDesc, Skeleton, Transform};
    let joints = ["Hips", "LHipJoint", "LeftUpLeg", "LowerBack"]
        .iter()
        .enumerate()
        .map(|(i, n)| JointDesc {
            name: n.to_string(),
            parent: (i > 0).then(|| "Hips".to_string()),
            bind_local: Transform::IDENTITY,
            inverse_bind: None,
        })
        .collect();
    let (skeleton, _) = Skeleton::from_unordered(joints).unwrap();
    let rot = |j: &str, a: f32| TrackCurves {
        joint: j.into(),
        rotation: Curve::new(
            vec![0.0, 1.0],
            vec![Quat::IDENTITY, Quat::from_rotation_x(a)],
        ),
        ..Default::default()
    };
    let mut hips = rot("Hips", 0.0);
    hips.translation = Curve::new(vec![0.0, 1.0], vec![Vec3::ZERO, Vec3::Z]);
    let clip = SceneClip {
        name: "walk".into(),
        tracks: vec![hips, rot("LHipJoint", 0.0), rot("LeftUpLeg", 0.3)],
        ..Default::default()
    };
    let set = JointSet::from_skeleton_and_clips(&skeleton, &[clip]);
    assert_eq!(set.keyed(), [true, false, true, false]);
}
