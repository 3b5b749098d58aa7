//! Unit tests of the metric's anchors: error points measured about the source's anchor at each
//! time (a file apart from `tests.rs`).

#![allow(clippy::unwrap_used)]
use super::metric::Rig;
use super::options::CompressOptions;
use super::search::compress_clip;
use super::tests::swinging_tracks;
use sinew_core::format::clip_record_size;
use sinew_core::glam::{DAffine3, DQuat, DVec3, Quat, Vec3};
use sinew_core::{Clip, ClipBinding, Curve, JointDesc, Sampler, Skeleton, TrackCurves, Transform};

/// A figure that travels far from the origin (a dash in centimetres: its hips 700 units out under
/// a root that does not move): measured about its anchor (the hips), the encoder has its whole
/// tolerance there and compresses the clip, where with the f32 noise of model-space coordinates
/// near 700 it kept it plain (no encoding held the half tolerance left by the noise margin). An
/// f64 forward kinematics of the sampled poses, about nothing but the world origin, agrees that
/// the error is within the tolerance.
#[test]
fn a_figure_far_from_the_origin_is_measured_about_its_anchor() {
    // root -> hips -> three chains (two legs and a spine) of three 40-unit bones.
    let mut joints = vec![
        JointDesc {
            name: "root".into(),
            parent: None,
            bind_local: Transform::IDENTITY,
            inverse_bind: None,
        },
        JointDesc {
            name: "hips".into(),
            parent: Some("root".into()),
            bind_local: Transform::from_translation(Vec3::new(0.0, 90.0, 0.0)),
            inverse_bind: None,
        },
    ];
    for (c, dir) in [Vec3::NEG_Y, Vec3::NEG_Y, Vec3::Y].into_iter().enumerate() {
        for b in 0..3 {
            let parent = if b == 0 {
                "hips".to_string()
            } else {
                format!("c{c}b{}", b - 1)
            };
            let offset = if b == 0 {
                Vec3::new(10.0 * c as f32 - 10.0, 0.0, 0.0)
            } else {
                dir * 40.0
            };
            joints.push(JointDesc {
                name: format!("c{c}b{b}"),
                parent: Some(parent),
                bind_local: Transform::from_translation(offset),
                inverse_bind: None,
            });
        }
    }
    let skeleton = Skeleton::from_unordered(joints).unwrap().0;
    let keys = 120;
    let times: Vec<f32> = (0..keys).map(|k| k as f32 / 30.0).collect();
    let hips = usize::from(skeleton.find("hips").unwrap());
    let path = |t: f32| {
        Vec3::new(
            175.0 * t + 10.0,
            90.0 + 3.0 * (9.0 * t).sin(),
            5.0 * t.cos(),
        )
    };
    let tracks = swinging_tracks(&skeleton, &times, 1, 0.5, Some((hips, &path)));
    let clip = Clip::from_curves("dash", times[keys - 1], 30.0, false, false, tracks)
        .unwrap()
        .to_plain();
    let rig = Rig::new(&clip, Some(&skeleton), 0.1).unwrap();
    assert_eq!(rig.anchors, vec![hips]);
    let options = CompressOptions {
        tolerance: Some(0.001),
        error_distance: Some(0.1),
        ..CompressOptions::default()
    };
    let (c, r) = compress_clip(&clip, Some(&skeleton), &options);
    assert!(c.is_compressed(), "{r:?}");
    assert!(r.compressed_bytes * 3 < clip_record_size(&clip), "{r:?}");
    assert!(r.max_error <= 0.001 && r.max_error > 0.0007, "{r:?}");
    // World-space f64 forward kinematics of both clips' sampled local poses.
    let world = |c: &Clip, t: f32| -> Vec<DAffine3> {
        let binding = ClipBinding::new(c, &skeleton);
        let mut pose = skeleton.bind_local().to_vec();
        Sampler::new()
            .sample(c, &binding, &skeleton, t, &mut pose)
            .unwrap();
        let mut out: Vec<DAffine3> = Vec::new();
        for (j, l) in pose.iter().enumerate() {
            let a = DAffine3::from_scale_rotation_translation(
                l.scale.as_dvec3(),
                DQuat::from_xyzw(
                    f64::from(l.rotation.x),
                    f64::from(l.rotation.y),
                    f64::from(l.rotation.z),
                    f64::from(l.rotation.w),
                ),
                l.translation.as_dvec3(),
            );
            out.push(match skeleton.parents()[j] {
                Some(p) => out[usize::from(p)] * a,
                None => a,
            });
        }
        out
    };
    let mut worst = 0.0f64;
    let mut farthest = 0.0f64;
    for &t in clip.times() {
        let (a, b) = (world(&clip, t), world(&c, t));
        for (ma, mb) in a.iter().zip(&b) {
            farthest = farthest.max(ma.translation.abs().max_element());
            for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
                let p = axis * 0.1;
                worst = worst.max(ma.transform_point3(p).distance(mb.transform_point3(p)));
            }
        }
    }
    assert!(farthest > 650.0, "{farthest}");
    // The sampled poses are f32 (their rounding at 700 is 3e-5 a coordinate at most).
    assert!(worst <= 0.001 + 1e-4, "f64 error {worst}, report {r:?}");
}

/// The anchor of each root: down the chain of single children while the clip does not animate
/// the joint; the first it animates, or that branches, or that ends the chain.
#[test]
fn the_anchor_is_the_first_animated_or_branching_joint_below_the_root() {
    // a -> b -> c -> (d, e); f -> g; h (alone); i -> j -> k
    let links = [
        ("a", None),
        ("b", Some("a")),
        ("c", Some("b")),
        ("d", Some("c")),
        ("e", Some("c")),
        ("f", None),
        ("g", Some("f")),
        ("h", None),
        ("i", None),
        ("j", Some("i")),
        ("k", Some("j")),
    ];
    let skeleton = Skeleton::from_unordered(
        links
            .iter()
            .map(|(name, parent)| JointDesc {
                name: (*name).into(),
                parent: parent.map(Into::into),
                bind_local: Transform::IDENTITY,
                inverse_bind: None,
            })
            .collect(),
    )
    .unwrap()
    .0;
    let times = vec![0.0, 0.5, 1.0];
    let turning = |joint: &str| TrackCurves {
        joint: joint.into(),
        rotation: Curve::new(
            times.clone(),
            times.iter().map(|&t| Quat::from_rotation_y(t)).collect(),
        ),
        ..Default::default()
    };
    let still = |joint: &str| TrackCurves {
        joint: joint.into(),
        rotation: Curve::new(times.clone(), vec![Quat::IDENTITY; 3]),
        ..Default::default()
    };
    // b is keyed but still (one value throughout), f moves, i's chain is still to its end.
    let tracks = vec![
        still("b"),
        turning("d"),
        turning("f"),
        turning("g"),
        still("j"),
    ];
    let clip = Clip::from_curves("c", 1.0, 2.0, false, false, tracks)
        .unwrap()
        .to_plain();
    let rig = Rig::new(&clip, Some(&skeleton), 0.1).unwrap();
    let name = |j: usize| skeleton.names()[j].as_str();
    let anchors: Vec<&str> = rig.anchors.iter().map(|&j| name(j)).collect();
    assert_eq!(anchors, ["c", "f", "h", "k"]);
}
