//! Unit tests of the inspect report and its human rendering.

use super::build::*;
use super::text::*;
use sinew_core::glam::{Quat, Vec3};
use sinew_core::{Curve, JointDesc, Submesh, TrackCurves};
use sinew_core::{Lod, Skeleton, Transform};
use sinew_scene::{Diagnostic, Scene};
use sinew_scene::{SceneClip, SourceFormat};
use std::path::Path;

fn scene() -> Scene {
    let joints = vec![
        JointDesc {
            name: "child".into(),
            parent: Some("root".into()),
            bind_local: Transform::new(
                Vec3::new(0.0, 2.0, 0.0),
                Quat::from_rotation_z(90f32.to_radians()),
                Vec3::ONE,
            ),
            inverse_bind: None,
        },
        JointDesc {
            name: "root".into(),
            parent: None,
            bind_local: Transform::IDENTITY,
            inverse_bind: None,
        },
    ];
    let (skeleton, _) = Skeleton::from_unordered(joints).unwrap();
    let mut s = Scene::new(SourceFormat::Ms3d);
    s.skeleton = Some(skeleton);
    s.clips.push(SceneClip {
        name: "wave".into(),
        duration: 1.0,
        sample_rate: 30.0,
        looping: true,
        additive: false,
        tracks: vec![
            TrackCurves {
                joint: "child".into(),
                translation: Curve::new(vec![0.0, 1.0], vec![Vec3::ZERO, Vec3::X]),
                rotation: Curve::new(vec![0.0, 0.5], vec![Quat::IDENTITY; 2]),
                scale: Curve::default(),
            },
            TrackCurves {
                joint: "ghost".into(),
                translation: Curve::new(vec![0.25], vec![Vec3::ZERO]),
                rotation: Curve::default(),
                scale: Curve::default(),
            },
        ],
    });
    let geometry = Lod {
        positions: vec![
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(0.0, 1.0, 3.0),
        ],
        joints: vec![[0, 0, 0, 0], [0, 1, 0, 0], [0, 1, 0, 0]],
        weights: vec![
            [1.0, 0.0, 0.0, 0.0],
            [0.5, 0.5, 0.0, 0.0],
            [0.25, 0.75, 0.0, 0.0],
        ],
        indices: vec![0, 1, 2],
        submeshes: vec![Submesh {
            first_index: 0,
            index_count: 3,
            material: "skin".into(),
        }],
        ..Lod::default()
    };
    s.meshes.push(sinew_scene::Mesh {
        name: "body".into(),
        geometry,
        source_vertex: vec![0, 1, 2],
        source_vertex_count: 3,
        lods: Vec::new(),
        lods_not_built: Vec::new(),
    });
    s.diagnostics
        .push(Diagnostic::warning("odd-thing", "Something odd.").with_figure("count", 3.0));
    s
}

#[test]
fn report_counts_joints_keys_influences_and_unmatched() {
    let r = build_report(Path::new("x.ms3d"), Some(10), &scene());
    let sk = r.skeleton.as_ref().unwrap();
    assert_eq!(sk.joint_count, 2);
    assert_eq!(sk.joints[0].name, "root");
    assert_eq!(sk.joints[1].parent, Some(0));
    assert_eq!(sk.joints[1].depth, 1);
    let e = sk.joints[1].bind.rotation_euler_deg;
    assert!((e[2] - 90.0).abs() < 1e-3 && e[0].abs() < 1e-3, "{e:?}");
    let c = &r.clips[0];
    assert_eq!(c.keys.translation, 3);
    assert_eq!(c.keys.rotation, 2);
    assert_eq!(c.keys.total, 5);
    // distinct times: 0, 0.25, 0.5, 1
    assert_eq!(c.key_times, 4);
    assert_eq!(c.driven_joints, vec!["child", "ghost"]);
    assert_eq!(
        c.unmatched_joints.as_deref(),
        Some(&["ghost".to_string()][..])
    );
    let m = &r.meshes[0];
    assert_eq!(m.influences, Some([0, 1, 2, 0, 0]));
    let b = m.bounds.as_ref().unwrap();
    assert_eq!(b.min, [-1.0, 0.0, 0.0]);
    assert_eq!(b.max, [1.0, 2.0, 3.0]);
    assert_eq!(r.summary.warnings, 1);
    assert_eq!(r.diagnostics[0].figures[0].value, 3.0);
}

#[test]
fn human_report_shows_tree_indentation() {
    let text = human(&build_report(Path::new("x.ms3d"), None, &scene()));
    assert!(text.contains("\n  [0] root (root)"), "{text}");
    assert!(
        text.contains("\n    [1] child (parent 0)  T(0, 2, 0) R(0, 0, 90)deg"),
        "{text}"
    );
    assert!(
        text.contains("1 names match no joint of the skeleton: ghost"),
        "{text}"
    );
    assert!(
        text.contains("warning [odd-thing] Something odd. (count=3)"),
        "{text}"
    );
}

#[test]
fn numbers_are_trimmed() {
    assert_eq!(num(1.0), "1");
    assert_eq!(num(-0.00001), "0");
    assert_eq!(num(2.5), "2.5");
}
