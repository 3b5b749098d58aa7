//! Retargeting keeps model-space poses: a clip moved onto a skeleton with the same joint positions but
//! different bind rotations puts every joint at the same place; a skeleton twice as big moves its root
//! twice as far.

#![allow(clippy::unwrap_used)] // test helpers panic on broken fixtures by design

use sinew_core::glam::{EulerRot, Quat, Vec3};
use sinew_core::{Curve, JointDesc, Skeleton, TrackCurves, Transform};
use sinew_pipeline::mapping::{map_joints, JointSet, MatchMethod, Slot};
use sinew_pipeline::retarget::{
    rest_orientation_differences, retarget, retarget_with, RetargetError, RetargetOptions,
    RootScaleSource,
};
use sinew_scene::SceneClip;

/// (name, parent, model-space rest position): a small CMU-named body.
const BODY: &[(&str, Option<&str>, [f32; 3])] = &[
    ("Hips", None, [0.0, 90.0, 0.0]),
    ("LeftUpLeg", Some("Hips"), [10.0, 90.0, 0.0]),
    ("LeftLeg", Some("LeftUpLeg"), [10.0, 50.0, 2.0]),
    ("LeftFoot", Some("LeftLeg"), [10.0, 10.0, 0.0]),
    ("RightUpLeg", Some("Hips"), [-10.0, 90.0, 0.0]),
    ("RightLeg", Some("RightUpLeg"), [-10.0, 50.0, 2.0]),
    ("RightFoot", Some("RightLeg"), [-10.0, 10.0, 0.0]),
    ("Spine", Some("Hips"), [0.0, 100.0, 0.0]),
    ("Neck", Some("Spine"), [0.0, 130.0, 0.0]),
    ("Head", Some("Neck"), [0.0, 140.0, 1.0]),
    ("LeftArm", Some("Spine"), [15.0, 128.0, 0.0]),
    ("LeftForeArm", Some("LeftArm"), [40.0, 128.0, -1.0]),
    ("LeftHand", Some("LeftForeArm"), [65.0, 128.0, 0.0]),
];

fn pos(name: &str) -> Vec3 {
    Vec3::from(BODY.iter().find(|b| b.0 == name).unwrap().2)
}

/// A skeleton with the BODY positions scaled by `scale`, renamed by `rename`, and model-space bind
/// rotations given by `model_rot`; an optional extra root (`Bip01`) with its own rotation above the hips.
fn skeleton(
    scale: f32,
    rename: &dyn Fn(&str) -> String,
    model_rot: &dyn Fn(usize) -> Quat,
    extra_root: Option<Quat>,
) -> Skeleton {
    let mut joints = Vec::new();
    if let Some(r) = extra_root {
        joints.push(JointDesc {
            name: "Bip01".into(),
            parent: None,
            bind_local: Transform::from_rotation(r),
            inverse_bind: None,
        });
    }
    for (i, (name, parent, _)) in BODY.iter().enumerate() {
        let rot = model_rot(i);
        let (prot, ppos) = match parent {
            Some(p) => {
                let pi = BODY.iter().position(|b| b.0 == *p).unwrap();
                (model_rot(pi), pos(p) * scale)
            }
            None => (extra_root.unwrap_or(Quat::IDENTITY), Vec3::ZERO),
        };
        let local_t = prot.inverse() * (pos(name) * scale - ppos);
        let parent_name = match parent {
            Some(p) => Some(rename(p)),
            None => extra_root.map(|_| "Bip01".to_string()),
        };
        joints.push(JointDesc {
            name: rename(name),
            parent: parent_name,
            bind_local: Transform::new(local_t, prot.inverse() * rot, Vec3::ONE),
            inverse_bind: None,
        });
    }
    Skeleton::from_unordered(joints).unwrap().0
}

fn bvh_like() -> Skeleton {
    skeleton(1.0, &|n| n.to_string(), &|_| Quat::IDENTITY, None)
}

/// Arbitrary but fixed bind rotations, different for every joint.
fn twisted(i: usize) -> Quat {
    let f = i as f32 + 1.0;
    Quat::from_euler(EulerRot::ZXY, 0.7 * f, -0.45 * f + 0.3, 0.9 - 0.21 * f).normalize()
}

fn biped_name(n: &str) -> String {
    match n {
        "Hips" => "Bip01 Pelvis".into(),
        "LeftUpLeg" => "Bip01 L Thigh".into(),
        "LeftLeg" => "Bip01 L Calf".into(),
        "LeftFoot" => "Bip01 L Foot".into(),
        "RightUpLeg" => "Bip01 R Thigh".into(),
        "RightLeg" => "Bip01 R Calf".into(),
        "RightFoot" => "Bip01 R Foot".into(),
        "Spine" => "Bip01 Spine".into(),
        "Neck" => "Bip01 Neck".into(),
        "Head" => "Bip01 Head".into(),
        "LeftArm" => "Bip01 L UpperArm".into(),
        "LeftForeArm" => "Bip01 L Forearm".into(),
        "LeftHand" => "Bip01 L Hand".into(),
        _ => unreachable!(),
    }
}

const TIMES: [f32; 3] = [0.0, 0.5, 1.0];

fn walk() -> SceneClip {
    let rot = |j: &str, a: [f32; 3]| TrackCurves {
        joint: j.into(),
        rotation: Curve::new(
            TIMES.to_vec(),
            (0..3)
                .map(|k| {
                    let s = k as f32;
                    Quat::from_euler(EulerRot::ZXY, a[0] * s, a[1] * s, a[2] * (1.0 - s))
                })
                .collect(),
        ),
        ..Default::default()
    };
    let mut hips = rot("Hips", [0.1, -0.2, 0.3]);
    hips.translation = Curve::new(
        TIMES.to_vec(),
        vec![
            Vec3::new(0.0, 90.0, 0.0),
            Vec3::new(3.0, 88.0, 20.0),
            Vec3::new(1.0, 91.0, 40.0),
        ],
    );
    SceneClip {
        name: "walk".into(),
        duration: 1.0,
        sample_rate: 2.0,
        looping: false,
        additive: false,
        tracks: vec![
            hips,
            rot("LeftUpLeg", [0.5, 0.2, -0.1]),
            rot("LeftLeg", [-0.6, 0.1, 0.0]),
            rot("RightUpLeg", [-0.4, 0.0, 0.2]),
            rot("Spine", [0.05, 0.1, 0.15]),
            rot("Neck", [0.2, 0.0, -0.3]),
            rot("LeftArm", [1.0, -0.5, 0.4]),
            rot("LeftForeArm", [0.0, 1.2, 0.0]),
        ],
    }
}

/// Model positions of every joint when the clip's key `k` is applied (untracked joints at bind).
fn pose(skeleton: &Skeleton, clip: &SceneClip, k: usize) -> Vec<Vec3> {
    let mut rot: Vec<Quat> = Vec::new();
    let mut out: Vec<Vec3> = Vec::new();
    for (i, name) in skeleton.names().iter().enumerate() {
        let mut local = skeleton.bind_local()[i];
        if let Some(t) = clip.tracks.iter().find(|t| &t.joint == name) {
            if !t.translation.is_empty() {
                assert_eq!(t.translation.times[k], TIMES[k]);
                local.translation = t.translation.values[k];
            }
            if !t.rotation.is_empty() {
                assert_eq!(t.rotation.times[k], TIMES[k]);
                local.rotation = t.rotation.values[k];
            }
        }
        match skeleton.parents()[i] {
            Some(p) => {
                let p = p as usize;
                out.push(out[p] + rot[p] * local.translation);
                rot.push(rot[p] * local.rotation);
            }
            None => {
                out.push(local.translation);
                rot.push(local.rotation);
            }
        }
    }
    out
}

fn assert_close(a: Vec3, b: Vec3, what: &str) {
    assert!((a - b).abs().max_element() < 1e-4, "{what}: {a} vs {b}");
}

#[test]
fn same_positions_on_a_skeleton_with_rotated_binds() {
    let source = bvh_like();
    let target = skeleton(
        1.0,
        &biped_name,
        &twisted,
        Some(Quat::from_rotation_x(-1.2)),
    );
    let mapping = map_joints(
        &JointSet::from_skeleton(&target),
        &JointSet::from_skeleton(&source),
    );
    assert_eq!(mapping.unmatched_rig(), ["Bip01"]);
    assert_eq!(
        mapping.entry("Bip01 L Thigh").unwrap().method,
        Some(MatchMethod::Synonym { slot: Slot::Thigh })
    );
    let clip = walk();
    let out = retarget(&clip, &source, &target, &mapping).unwrap();
    assert_eq!(out.root_joints, ["Bip01 Pelvis"]);
    assert!((out.leg_scale - 1.0).abs() < 1e-6);
    // Both legs: thigh->calf->foot is 40.05 + 40.05 (the knee sits 2 units forward).
    let leg = 2.0 * (2.0 * (40.0f32 * 40.0 + 2.0 * 2.0).sqrt());
    let (s, t) = out.leg_lengths.unwrap();
    assert!((s - leg).abs() < 1e-3 && (t - leg).abs() < 1e-3, "{s} {t}");
    // Every mapped rig joint gets a rotation track; the unmapped root gets none.
    assert_eq!(out.clip.tracks.len(), 13);
    assert!(out.clip.tracks.iter().all(|t| t.joint != "Bip01"));
    for k in 0..TIMES.len() {
        let sp = pose(&source, &clip, k);
        let tp = pose(&target, &out.clip, k);
        for (si, name) in source.names().iter().enumerate() {
            let ti = target.find(&biped_name(name)).unwrap() as usize;
            assert_close(tp[ti], sp[si], &format!("{name} at key {k}"));
        }
    }
    // The bind rotations differ, so copying local rotations would be wrong: the check says so.
    let diffs = rest_orientation_differences(&source, &target, &mapping);
    assert_eq!(diffs.len(), 13);
    let hips = diffs.iter().find(|d| d.motion == "Hips").unwrap();
    assert_eq!(hips.rig, "Bip01 Pelvis");
    let expected = twisted(0).w.abs().acos().to_degrees() * 2.0;
    assert!(
        (hips.degrees - expected).abs() < 1e-2,
        "{} {expected}",
        hips.degrees
    );
    assert!(diffs.iter().all(|d| d.degrees > 5.0));
}

#[test]
fn root_translation_scales_with_leg_length() {
    let source = bvh_like();
    let target = skeleton(2.0, &|n| n.to_string(), &twisted, None);
    let mapping = map_joints(
        &JointSet::from_skeleton(&target),
        &JointSet::from_skeleton(&source),
    );
    let clip = walk();
    let out = retarget(&clip, &source, &target, &mapping).unwrap();
    assert!((out.leg_scale - 2.0).abs() < 1e-5, "{}", out.leg_scale);
    let hips = out.clip.tracks.iter().find(|t| t.joint == "Hips").unwrap();
    // Rest (0, 90, 0) -> bind (0, 180, 0); change (3, -2, 20) doubled.
    assert_close(
        hips.translation.values[1],
        Vec3::new(6.0, 176.0, 40.0),
        "hips key 1",
    );
    assert_close(
        hips.translation.values[2],
        Vec3::new(2.0, 182.0, 80.0),
        "hips key 2",
    );
    // The whole body is the source pose scaled by two.
    for k in 0..TIMES.len() {
        let sp = pose(&source, &clip, k);
        let tp = pose(&target, &out.clip, k);
        for (i, name) in source.names().iter().enumerate() {
            assert_close(tp[i], sp[i] * 2.0, &format!("{name} at key {k}"));
        }
    }
    // Same-shaped skeleton without rotated binds: no orientation difference at all.
    let same = rest_orientation_differences(&source, &bvh_like(), &mapping);
    assert!(same.iter().all(|d| d.degrees < 1e-3));
}

#[test]
fn unknown_joints_and_additive_clips_are_errors() {
    let source = bvh_like();
    let target = skeleton(1.0, &biped_name, &twisted, None);
    // A mapping made against other names.
    let other = JointSet::from_names(&["Bip01 Pelvis", "Bip01 L Thigh"]);
    let mapping = map_joints(&other, &JointSet::from_names(&["Hips", "Pelvis2"]));
    let err = retarget(&walk(), &target, &source, &mapping).unwrap_err();
    assert_eq!(
        err,
        RetargetError::UnknownTargetJoint("Bip01 Pelvis".into())
    );
    let mapping = map_joints(&other, &JointSet::from_names(&["Hips2"]));
    let err = retarget(&walk(), &source, &target, &mapping).unwrap_err();
    assert_eq!(err, RetargetError::UnknownSourceJoint("Hips2".into()));
    let mut additive = walk();
    additive.additive = true;
    let mapping = map_joints(
        &JointSet::from_skeleton(&target),
        &JointSet::from_skeleton(&source),
    );
    assert_eq!(
        retarget(&additive, &source, &target, &mapping).unwrap_err(),
        RetargetError::Additive("walk".into())
    );
}

/// The BVH convention: the rest pose has the root at the origin (its `OFFSET`, so the feet hang
/// 80 units below it) while the clip's root translation is absolute (90 above the floor). The
/// retarget must not add those 90 units to the rig's bind height: the rig's feet must reach exactly
/// their bind height, on a rig twice as big.
#[test]
fn a_rest_pose_off_its_floor_is_grounded_on_the_rig() {
    let body = bvh_like();
    let hips = body.find("Hips").unwrap() as usize;
    let mut bind = body.bind_local().to_vec();
    bind[hips].translation = Vec3::ZERO;
    let inverse = sinew_core::skeleton::inverse_bind_from_locals(body.parents(), &bind);
    let source = Skeleton::new(
        body.names().to_vec(),
        body.parents().to_vec(),
        bind,
        inverse,
    )
    .unwrap();
    let target = skeleton(2.0, &biped_name, &twisted, None);
    let mapping = map_joints(
        &JointSet::from_skeleton(&target),
        &JointSet::from_skeleton(&source),
    );
    let clip = walk();
    let out = retarget(&clip, &source, &target, &mapping).unwrap();
    assert_eq!(out.root_scale_source, RootScaleSource::HipHeight);
    assert!((out.root_scale - 2.0).abs() < 1e-5, "{}", out.root_scale);
    let (hm, hr) = out.hip_heights.unwrap();
    assert!(
        (hm - 80.0).abs() < 1e-3 && (hr - 160.0).abs() < 1e-3,
        "{hm} {hr}"
    );
    assert!(out.standing_shift < -70.0, "{}", out.standing_shift);
    // The rig's feet come down to their bind height (20) and no lower.
    let feet = ["Bip01 L Foot", "Bip01 R Foot"].map(|n| target.find(n).unwrap() as usize);
    let lowest = (0..TIMES.len())
        .map(|k| {
            let p = pose(&target, &out.clip, k);
            feet.iter().map(|&f| p[f].y).fold(f32::INFINITY, f32::min)
        })
        .fold(f32::INFINITY, f32::min);
    assert!((lowest - 20.0).abs() < 1e-3, "lowest foot {lowest}");
    // The old reading (change from the rest root at 0) would have put the hips 180 units higher.
    let hips_y = out
        .clip
        .tracks
        .iter()
        .find(|t| t.joint == "Bip01 Pelvis")
        .unwrap();
    assert!(hips_y.translation.values.iter().all(|v| v.length() < 200.0));

    // An override replaces the scale, and the feet are grounded all the same.
    let opts = RetargetOptions {
        root_scale: Some(0.5),
    };
    let out = retarget_with(&clip, &source, &target, &mapping, &opts).unwrap();
    assert_eq!(out.root_scale, 0.5);
    assert_eq!(out.root_scale_source, RootScaleSource::Override);
    let opts = RetargetOptions {
        root_scale: Some(-1.0),
    };
    assert_eq!(
        retarget_with(&clip, &source, &target, &mapping, &opts).unwrap_err(),
        RetargetError::BadRootScale(-1.0)
    );
}
