//! Partial-body split and masks on a hand-built Biped skeleton.

#![allow(clippy::unwrap_used)] // test helpers panic on broken fixtures by design

use sinew_core::glam::{Quat, Vec3};
use sinew_core::{Curve, JointDesc, Skeleton, TrackCurves, Transform};
use sinew_pipeline::split::{
    clip_for_mask, mask_from_joints, mask_from_subtrees, parse_mask_spec, split_clip, MaskSpec,
    SplitError,
};
use sinew_scene::SceneClip;

const BIPED: &[(&str, Option<&str>)] = &[
    ("Bip01", None),
    ("Bip01 Pelvis", Some("Bip01")),
    ("Bip01 Spine", Some("Bip01 Pelvis")),
    ("Bip01 Spine1", Some("Bip01 Spine")),
    ("Bip01 Neck", Some("Bip01 Spine1")),
    ("Bip01 Head", Some("Bip01 Neck")),
    ("Bip01 L Clavicle", Some("Bip01 Neck")),
    ("Bip01 L UpperArm", Some("Bip01 L Clavicle")),
    ("Bip01 L Forearm", Some("Bip01 L UpperArm")),
    ("Bip01 L Hand", Some("Bip01 L Forearm")),
    ("Bip01 R Clavicle", Some("Bip01 Neck")),
    ("Bip01 R UpperArm", Some("Bip01 R Clavicle")),
    ("Bip01 L Thigh", Some("Bip01 Pelvis")),
    ("Bip01 L Calf", Some("Bip01 L Thigh")),
    ("Bip01 L Foot", Some("Bip01 L Calf")),
    ("Bip01 R Thigh", Some("Bip01 Pelvis")),
    ("Bip01 R Calf", Some("Bip01 R Thigh")),
];

fn biped() -> Skeleton {
    let joints = BIPED
        .iter()
        .map(|(n, p)| JointDesc {
            name: n.to_string(),
            parent: p.map(str::to_string),
            bind_local: Transform::from_translation(Vec3::Y),
            inverse_bind: None,
        })
        .collect();
    Skeleton::from_unordered(joints).unwrap().0
}

/// A clip driving every joint of the Biped plus one joint the skeleton lacks.
fn walk() -> SceneClip {
    let mut tracks: Vec<TrackCurves> = BIPED
        .iter()
        .map(|(n, _)| n.to_string())
        .chain(["Bip01 Ponytail".to_string()])
        .map(|joint| TrackCurves {
            joint,
            rotation: Curve::new(
                vec![0.0, 1.0],
                vec![Quat::IDENTITY, Quat::from_rotation_z(0.5)],
            ),
            ..Default::default()
        })
        .collect();
    tracks[0].translation = Curve::new(vec![0.0, 1.0], vec![Vec3::ZERO, Vec3::X]);
    SceneClip {
        name: "walk".into(),
        duration: 1.0,
        sample_rate: 30.0,
        looping: true,
        additive: false,
        tracks,
    }
}

fn joints(c: &SceneClip) -> Vec<&str> {
    c.tracks.iter().map(|t| t.joint.as_str()).collect()
}

#[test]
fn split_at_spine_drives_disjoint_halves() {
    let (upper, lower) = split_clip(&walk(), &biped(), &["Bip01 Spine"]).unwrap();
    assert_eq!(upper.name, "walk.upper");
    assert_eq!(lower.name, "walk.lower");
    assert_eq!(
        joints(&upper),
        [
            "Bip01 Spine",
            "Bip01 Spine1",
            "Bip01 Neck",
            "Bip01 Head",
            "Bip01 L Clavicle",
            "Bip01 L UpperArm",
            "Bip01 L Forearm",
            "Bip01 L Hand",
            "Bip01 R Clavicle",
            "Bip01 R UpperArm",
        ]
    );
    assert_eq!(
        joints(&lower),
        [
            "Bip01",
            "Bip01 Pelvis",
            "Bip01 L Thigh",
            "Bip01 L Calf",
            "Bip01 L Foot",
            "Bip01 R Thigh",
            "Bip01 R Calf",
            "Bip01 Ponytail",
        ]
    );
    // Curves and clip settings are carried over unchanged.
    assert_eq!(lower.tracks[0].translation.values, [Vec3::ZERO, Vec3::X]);
    assert!(upper.looping && lower.looping);
    assert_eq!((upper.duration, lower.sample_rate), (1.0, 30.0));
}

#[test]
fn split_at_several_joints_and_unknown_joint() {
    let (upper, lower) =
        split_clip(&walk(), &biped(), &["Bip01 L Clavicle", "Bip01 Head"]).unwrap();
    assert_eq!(
        joints(&upper),
        [
            "Bip01 Head",
            "Bip01 L Clavicle",
            "Bip01 L UpperArm",
            "Bip01 L Forearm",
            "Bip01 L Hand"
        ]
    );
    assert_eq!(lower.tracks.len(), 18 - 5);
    let err = split_clip(&walk(), &biped(), &["Bip01 Spine", "Bip01 Spine9"]).unwrap_err();
    assert_eq!(err, SplitError::UnknownJoint("Bip01 Spine9".into()));
    assert_eq!(
        err.to_string(),
        "joint \"Bip01 Spine9\" does not exist in the skeleton"
    );
    assert_eq!(
        split_clip(&walk(), &biped(), &[]).unwrap_err(),
        SplitError::NoJoints
    );
}

#[test]
fn masks() {
    let s = biped();
    let m = mask_from_subtrees(&s, &["Bip01 L Thigh"]).unwrap();
    let inside: Vec<&str> = (0..s.len())
        .filter(|&i| m[i] == 1.0)
        .map(|i| s.names()[i].as_str())
        .collect();
    assert_eq!(inside, ["Bip01 L Thigh", "Bip01 L Calf", "Bip01 L Foot"]);
    assert_eq!(m.iter().filter(|&&w| w == 0.0).count(), 14);

    let m = mask_from_joints(&s, &["Bip01 Head", "Bip01"]).unwrap();
    assert_eq!(m.len(), 17);
    assert_eq!((m[0], m[5], m[4]), (1.0, 1.0, 0.0));
    assert_eq!(
        mask_from_joints(&s, &["Head"]).unwrap_err(),
        SplitError::UnknownJoint("Head".into())
    );

    let spec = parse_mask_spec("arms = Bip01 L UpperArm, Bip01 R UpperArm").unwrap();
    assert_eq!(
        spec,
        MaskSpec {
            name: "arms".into(),
            joints: vec!["Bip01 L UpperArm".into(), "Bip01 R UpperArm".into()]
        }
    );
    let c = clip_for_mask(&walk(), &s, &spec).unwrap();
    assert_eq!(c.name, "walk.arms");
    assert_eq!(joints(&c), ["Bip01 L UpperArm", "Bip01 R UpperArm"]);
    let bad = parse_mask_spec("arms=Bip01 L Wing").unwrap();
    assert_eq!(
        clip_for_mask(&walk(), &s, &bad).unwrap_err(),
        SplitError::UnknownJoint("Bip01 L Wing".into())
    );
    for spec in ["arms", "=Bip01", "arms=", "arms=a,,b", "a.b=Bip01"] {
        assert!(
            matches!(parse_mask_spec(spec), Err(SplitError::BadMaskSpec { spec: s, .. }) if s == spec),
            "{spec}"
        );
    }
}

#[test]
fn split_clips_carry_their_game_data() {
    use sinew_scene::game::{ClipEvent, ClipGameData};
    use sinew_scene::GameData;
    let walk = ClipGameData {
        clip: "walk".into(),
        activity: 3,
        events: vec![ClipEvent {
            frame: 13,
            event: 1004,
            kind: 0,
            options: "step.wav".into(),
        }],
        ..ClipGameData::default()
    };
    let idle = ClipGameData {
        clip: "idle".into(),
        activity: 1,
        ..ClipGameData::default()
    };
    let mut g = GameData {
        clips: vec![walk.clone(), idle.clone()],
        ..GameData::default()
    };
    let made = ["walk.upper".to_string(), "walk.lower".to_string()];
    sinew_pipeline::split::carry_game_data(&mut g, "walk", &made, false);
    let names: Vec<&str> = g.clips.iter().map(|c| c.clip.as_str()).collect();
    assert_eq!(names, ["walk.upper", "walk.lower", "idle"]);
    assert_eq!(g.clips[1].events, walk.events);
    assert_eq!(g.clips[1].activity, 3);
    // With the source kept (masks only), the copies follow it.
    sinew_pipeline::split::carry_game_data(&mut g, "idle", &["idle.arms".to_string()], true);
    let names: Vec<&str> = g.clips.iter().map(|c| c.clip.as_str()).collect();
    assert_eq!(names, ["walk.upper", "walk.lower", "idle", "idle.arms"]);
    // A clip without game data changes nothing.
    sinew_pipeline::split::carry_game_data(&mut g, "run", &["run.upper".to_string()], false);
    assert_eq!(g.clips.len(), 4);
}
