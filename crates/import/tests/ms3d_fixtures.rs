//! MS3D fixtures written by the generator: every optional-block variant and both position-key
//! conventions (issue 9).
#![allow(clippy::unwrap_used)]

use sinew_import::{ms3d, ImportOptions, PositionKeyRule};
use sinew_scene::{Level, Scene};

fn fixture(name: &str) -> Vec<u8> {
    std::fs::read(sinew_testdata::fixtures().join("ms3d").join(name)).unwrap()
}

fn import(name: &str, rule: PositionKeyRule) -> Scene {
    let opts = ImportOptions {
        ms3d_position_keys: rule,
        ..Default::default()
    };
    ms3d::import(
        name,
        &fixture(name),
        &|_| Err(std::io::ErrorKind::NotFound.into()),
        &opts,
    )
    .unwrap()
}

fn decision(s: &Scene) -> &sinew_scene::Diagnostic {
    s.diagnostics
        .iter()
        .find(|d| d.code == "ms3d-position-keys")
        .expect("an ms3d-position-keys diagnostic")
}

fn figure(d: &sinew_scene::Diagnostic, name: &str) -> f64 {
    d.figures.iter().find(|f| f.0 == name).unwrap().1
}

#[test]
fn auto_reads_the_biped_root_motion_as_parent() {
    let s = import("biped_root_motion.ms3d", PositionKeyRule::Auto);
    let d = decision(&s);
    assert!(d.message.contains("read as parent"), "{}", d.message);
    assert_eq!(d.level, Level::Info, "{d:?}");
    assert!(d.message.contains("--ms3d-position-keys viewer"));
    // Under the viewer's rule the root sinks 30 units (the walk length) below its bind height.
    assert!(figure(d, "viewer_floor_sink") > 5.0 * figure(d, "parent_floor_sink"));
    let sk = s.skeleton.as_ref().unwrap();
    assert_eq!(sk.names()[0], "Bip01");
    assert!(sk.find("Bip01 L Calf").is_some());
    // The root's translation at the last key: t0 + tkey = (0, 39.5, 0) + (30, 0, 0) (bob is 0 there).
    let root = s.clips[0]
        .tracks
        .iter()
        .find(|t| t.joint == "Bip01")
        .unwrap();
    let last = *root.translation.values.last().unwrap();
    assert!(
        (last.x - 30.0).abs() < 1e-3 && (last.y - 39.5).abs() < 1e-2,
        "{last}"
    );
}

#[test]
fn explicit_settings_override_auto() {
    let s = import("biped_root_motion.ms3d", PositionKeyRule::Viewer);
    assert!(decision(&s).message.contains("read as viewer"));
    assert!(decision(&s).message.contains("as requested"));
    let root = s.clips[0]
        .tracks
        .iter()
        .find(|t| t.joint == "Bip01")
        .unwrap();
    // Viewer: t0 + Rz(-90 deg) * (30, 0, 0) = (0, 39.5 - 30, 0).
    let last = *root.translation.values.last().unwrap();
    assert!(last.x.abs() < 1e-3 && (last.y - 9.5).abs() < 1e-2, "{last}");
    let s = import("sliding_arm.ms3d", PositionKeyRule::Parent);
    assert!(decision(&s).message.contains("read as parent"));
}

#[test]
fn auto_reads_the_sliding_rig_as_viewer() {
    let s = import("sliding_arm.ms3d", PositionKeyRule::Auto);
    let d = decision(&s);
    assert!(d.message.contains("read as viewer"), "{}", d.message);
    assert!(figure(d, "viewer_detachment") < 1e-4);
    assert!(figure(d, "parent_detachment") > 0.01);
}

#[test]
fn every_variant_gives_the_same_mesh_and_weights() {
    let names = [
        "variant_after_joints.ms3d",
        "variant_after_comments.ms3d",
        "variant_sub1.ms3d",
        "variant_sub2.ms3d",
        "variant_sub3.ms3d",
        "variant_joint_extra.ms3d",
        "variant_full.ms3d",
    ];
    let with_extra: Vec<Scene> = names[2..]
        .iter()
        .map(|n| import(n, PositionKeyRule::Auto))
        .collect();
    for s in &with_extra {
        let g = &s.meshes[0].geometry;
        assert_eq!(
            g.vertex_count(),
            with_extra[0].meshes[0].geometry.vertex_count()
        );
        assert_eq!(g.joints, with_extra[0].meshes[0].geometry.joints);
        for (w, w0) in g
            .weights
            .iter()
            .zip(&with_extra[0].meshes[0].geometry.weights)
        {
            for k in 0..4 {
                assert!((w[k] - w0[k]).abs() < 1e-6);
            }
        }
        // Child-end vertices are 60/40 between root (0) and tip (1): sub-version 1 stores 153/102
        // of 255, the others 60/40 of 100.
        let split = g
            .weights
            .iter()
            .filter(|w| (w[0] - 0.6).abs() < 1e-6 && (w[1] - 0.4).abs() < 1e-6)
            .count();
        assert_eq!(split, 4);
        assert!(
            s.diagnostics.iter().all(|d| d.level == Level::Info),
            "{:?}",
            s.diagnostics
        );
    }
    // Without vertex extra every vertex belongs wholly to its own joint.
    for n in &names[..2] {
        let s = import(n, PositionKeyRule::Auto);
        assert!(s.meshes[0]
            .geometry
            .weights
            .iter()
            .all(|w| *w == [1.0, 0.0, 0.0, 0.0]));
    }
    // The parsed blocks are what the generator wrote.
    let f = ms3d::parse("v", &fixture("variant_full.ms3d")).unwrap();
    let c = f.comments.unwrap();
    assert_eq!(c.model.as_deref(), Some("variant model comment"));
    assert_eq!(c.joints[0].index, 1);
    assert_eq!(c.joints[0].text, "tip comment");
    assert_eq!(f.vertex_extra.unwrap().sub_version, 2);
    assert_eq!(f.joint_extra.unwrap().1.len(), 2);
    assert_eq!(f.model_extra.unwrap().alpha_ref, 0.5);
    let f = ms3d::parse("v", &fixture("variant_sub3.ms3d")).unwrap();
    assert_eq!(f.vertex_extra.unwrap().sub_version, 3);
    assert!(f.joint_extra.is_none() && f.trailing.is_none());
    let f = ms3d::parse("v", &fixture("variant_after_joints.ms3d")).unwrap();
    assert!(f.comments.is_none());
}
