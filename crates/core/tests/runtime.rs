//! Runtime core: blending, the animator and skinning, against values worked out by hand.

#![allow(clippy::unwrap_used)] // helpers of tests

use sinew_core::glam::{Mat4, Quat, Vec3, Vec4};
use sinew_core::{
    apply_additive, local_to_model, skin, skin_lod, skinning_palette, Animator, AnimatorError,
    BlendBuffers, BlendError, Clip, ClipId, Curve, JointDesc, Layer, Lod, Skeleton, SkinError,
    TrackCurves, Transform,
};
use std::f32::consts::{FRAC_1_SQRT_2, FRAC_PI_2, FRAC_PI_3, FRAC_PI_6};
use std::sync::Arc;

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

fn assert_close(a: Vec3, b: Vec3) {
    assert!(close(a, b), "{a} != {b}");
}

/// Same rotation: `a == ±b` component-wise within 1e-6 (an angle from `acos` of the dot product would
/// turn a one-ulp difference into 3e-4 rad).
fn assert_rot(a: Quat, b: Quat) {
    let d = (Vec4::from(a) - Vec4::from(b))
        .abs()
        .max_element()
        .min((Vec4::from(a) + Vec4::from(b)).abs().max_element());
    assert!(d < 1e-6, "{a} != {b}");
}

/// Two joints: a shoulder at the origin and an elbow one unit along +x.
fn arm() -> Skeleton {
    Skeleton::from_unordered(vec![
        JointDesc {
            name: "shoulder".into(),
            parent: None,
            bind_local: Transform::IDENTITY,
            inverse_bind: None,
        },
        JointDesc {
            name: "elbow".into(),
            parent: Some("shoulder".into()),
            bind_local: Transform::from_translation(Vec3::X),
            inverse_bind: None,
        },
    ])
    .unwrap()
    .0
}

// ---------------------------------------------------------------- blending

#[test]
fn masks_select_joints_per_layer() {
    let bind = [Transform::IDENTITY; 2];
    let a = [Transform::from_translation(Vec3::new(1.0, 0.0, 0.0)); 2];
    let b = [Transform::from_translation(Vec3::new(0.0, 5.0, 0.0)); 2];
    let lower = [1.0, 0.0];
    let upper = [0.0, 1.0];
    let driven = [0u16, 1];
    let mut buf = BlendBuffers::new(2);
    let mut out = [Transform::IDENTITY; 2];
    buf.blend(
        &bind,
        &[
            Layer::new(&a, &driven).with_mask(&lower),
            Layer::new(&b, &driven).with_mask(&upper),
        ],
        &[],
        &mut out,
    )
    .unwrap();
    assert_eq!(out[0].translation, Vec3::new(1.0, 0.0, 0.0));
    assert_eq!(out[1].translation, Vec3::new(0.0, 5.0, 0.0));

    // A half mask on joint 1 with the layer at weight 0.5: joint 1 gets 0.25 of b, 0.75 of bind.
    let half = [1.0, 0.5];
    buf.blend(
        &bind,
        &[Layer::new(&b, &driven).with_weight(0.5).with_mask(&half)],
        &[],
        &mut out,
    )
    .unwrap();
    assert_eq!(out[0].translation, Vec3::new(0.0, 2.5, 0.0));
    assert_eq!(out[1].translation, Vec3::new(0.0, 1.25, 0.0));
}

#[test]
fn bind_pose_fills_weights_below_one() {
    let bind = [Transform::new(
        Vec3::new(0.0, 0.0, 8.0),
        Quat::IDENTITY,
        Vec3::ONE,
    )];
    let pose = [Transform::new(
        Vec3::new(4.0, 0.0, 0.0),
        Quat::from_rotation_z(FRAC_PI_2),
        Vec3::splat(3.0),
    )];
    let mut buf = BlendBuffers::new(1);
    let mut out = [Transform::IDENTITY];
    buf.blend(
        &bind,
        &[Layer::new(&pose, &[0]).with_weight(0.25)],
        &[],
        &mut out,
    )
    .unwrap();
    // 0.25 * (4,0,0) + 0.75 * (0,0,8); scale 0.25 * 3 + 0.75 * 1.
    assert_eq!(out[0].translation, Vec3::new(1.0, 0.0, 6.0));
    assert_eq!(out[0].scale, Vec3::splat(1.5));
    // Half weight between identity and 90 degrees: 45 degrees (nlerp is exact at the midpoint).
    buf.blend(
        &bind,
        &[Layer::new(&pose, &[0]).with_weight(0.5)],
        &[],
        &mut out,
    )
    .unwrap();
    assert_rot(out[0].rotation, Quat::from_rotation_z(FRAC_PI_2 / 2.0));
    assert_eq!(out[0].translation, Vec3::new(2.0, 0.0, 4.0));
}

#[test]
fn weights_above_one_are_normalised() {
    let bind = [Transform::from_translation(Vec3::splat(100.0))];
    let a = [Transform::from_translation(Vec3::new(4.0, 0.0, 0.0))];
    let b = [Transform::from_translation(Vec3::new(0.0, 8.0, 0.0))];
    let mut buf = BlendBuffers::new(1);
    let mut out = [Transform::IDENTITY];
    buf.blend(
        &bind,
        &[
            Layer::new(&a, &[0]).with_weight(3.0),
            Layer::new(&b, &[0]).with_weight(1.0),
        ],
        &[],
        &mut out,
    )
    .unwrap();
    // (3*(4,0,0) + 1*(0,8,0)) / 4; the bind pose takes no part.
    assert_eq!(out[0].translation, Vec3::new(3.0, 2.0, 0.0));
    assert_eq!(buf.total_weight(0), Some(4.0));
}

#[test]
fn rotations_blend_along_the_shortest_path() {
    let bind = [Transform::IDENTITY];
    let q60 = Quat::from_rotation_z(FRAC_PI_3);
    let q120 = Quat::from_rotation_z(2.0 * FRAC_PI_3);
    let a = [Transform::from_rotation(q60)];
    for b_rot in [q120, -q120] {
        let b = [Transform::from_rotation(b_rot)];
        let mut buf = BlendBuffers::new(1);
        let mut out = [Transform::IDENTITY];
        buf.blend(
            &bind,
            &[Layer::new(&a, &[0]), Layer::new(&b, &[0])],
            &[],
            &mut out,
        )
        .unwrap();
        assert_rot(out[0].rotation, Quat::from_rotation_z(FRAC_PI_2));
        assert!((out[0].rotation.length() - 1.0).abs() < 1e-6);
    }
    // The first layer may itself be the negated quaternion: -q60 and q120 still meet at 90 degrees.
    let a = [Transform::from_rotation(-q60)];
    let b = [Transform::from_rotation(q120)];
    let mut buf = BlendBuffers::new(1);
    let mut out = [Transform::IDENTITY];
    buf.blend(
        &bind,
        &[Layer::new(&a, &[0]), Layer::new(&b, &[0])],
        &[],
        &mut out,
    )
    .unwrap();
    assert_rot(out[0].rotation, Quat::from_rotation_z(FRAC_PI_2));
}

#[test]
fn additive_layers_apply_on_top_with_weight_and_mask() {
    let mut base = [Transform::new(
        Vec3::new(1.0, 0.0, 0.0),
        Quat::from_rotation_z(FRAC_PI_6),
        Vec3::splat(2.0),
    ); 2];
    let delta = [Transform::new(
        Vec3::new(0.0, 2.0, 0.0),
        Quat::from_rotation_z(FRAC_PI_3),
        Vec3::splat(1.5),
    ); 2];
    let mask = [1.0, 0.0];
    apply_additive(
        &mut base,
        &Layer::new(&delta, &[0, 1])
            .with_weight(0.5)
            .with_mask(&mask),
    )
    .unwrap();
    // t: (1,0,0) + 0.5*(0,2,0); r: half of 60 degrees on top of 30; s: 2 * (1 + 0.5*(1.5-1)).
    assert_eq!(base[0].translation, Vec3::new(1.0, 1.0, 0.0));
    assert_rot(base[0].rotation, Quat::from_rotation_z(FRAC_PI_3));
    assert_eq!(base[0].scale, Vec3::splat(2.5));
    // Masked out: unchanged bit for bit.
    assert_eq!(base[1].translation, Vec3::new(1.0, 0.0, 0.0));
    assert_eq!(base[1].rotation, Quat::from_rotation_z(FRAC_PI_6));
    assert_eq!(base[1].scale, Vec3::splat(2.0));
}

#[test]
fn additive_at_full_weight_on_the_reference_gives_the_source() {
    // Reference R and source S; the delta made by the documented convention.
    let r = Transform::new(
        Vec3::new(1.0, 2.0, 3.0),
        Quat::from_rotation_x(0.4),
        Vec3::new(1.0, 2.0, 4.0),
    );
    let s = Transform::new(
        Vec3::new(-1.0, 0.5, 3.0),
        Quat::from_rotation_y(1.1) * Quat::from_rotation_x(0.2),
        Vec3::new(2.0, 1.0, 1.0),
    );
    let d = Transform::new(
        s.translation - r.translation,
        s.rotation * r.rotation.inverse(),
        s.scale / r.scale,
    );
    let mut base = [r];
    apply_additive(&mut base, &Layer::new(&[d], &[0])).unwrap();
    assert_close(base[0].translation, s.translation);
    assert_rot(base[0].rotation, s.rotation);
    assert_close(base[0].scale, s.scale);
}

#[test]
fn blend_validates_lengths_and_indices() {
    let mut buf = BlendBuffers::new(2);
    let one = [Transform::IDENTITY];
    let two = [Transform::IDENTITY; 2];
    assert_eq!(
        buf.accumulate(&Layer::new(&one, &[0])),
        Err(BlendError::Length {
            what: "pose",
            expected: 2,
            got: 1
        })
    );
    assert_eq!(
        buf.accumulate(&Layer::new(&two, &[0]).with_mask(&[1.0])),
        Err(BlendError::Length {
            what: "mask",
            expected: 2,
            got: 1
        })
    );
    assert_eq!(
        buf.accumulate(&Layer::new(&two, &[0, 7])),
        Err(BlendError::JointIndex {
            joint: 7,
            joints: 2
        })
    );
    let mut out = [Transform::IDENTITY; 3];
    assert_eq!(
        buf.resolve(&two, &mut out),
        Err(BlendError::Length {
            what: "output",
            expected: 2,
            got: 3
        })
    );
    assert_eq!(
        apply_additive(&mut out, &Layer::new(&two, &[0])),
        Err(BlendError::Length {
            what: "pose",
            expected: 3,
            got: 2
        })
    );
}

// ---------------------------------------------------------------- animator

/// A clip holding the shoulder at a constant x translation.
fn hold(name: &str, x: f32, looping: bool, additive: bool) -> Arc<Clip> {
    Arc::new(
        Clip::from_curves(
            name,
            1.0,
            30.0,
            looping,
            additive,
            vec![TrackCurves {
                joint: "shoulder".into(),
                translation: Curve::new(vec![0.0], vec![Vec3::new(x, 0.0, 0.0)]),
                ..Default::default()
            }],
        )
        .unwrap(),
    )
}

fn shoulder_x(anim: &mut Animator) -> f32 {
    let mut out = [Transform::IDENTITY; 2];
    anim.evaluate(&mut out).unwrap();
    out[0].translation.x
}

fn weights(anim: &Animator, a: ClipId, b: ClipId) -> (f32, f32) {
    (
        anim.effective_weight(a).unwrap(),
        anim.effective_weight(b).unwrap(),
    )
}

#[test]
fn cross_fade_runs_when_the_current_clip_ends() {
    let mut anim = Animator::new(Arc::new(arm()));
    let a = anim.add_clip(hold("a", 2.0, false, false));
    let b = anim.add_clip(hold("b", 10.0, false, false));
    anim.play(a).unwrap();
    anim.enqueue(b, 0.5).unwrap();
    assert_eq!(anim.current(), Some(a));
    assert_eq!(anim.queued().collect::<Vec<_>>(), [(b, 0.5)]);
    anim.update(0.5);
    assert_eq!(weights(&anim, a, b), (1.0, 0.0));
    assert!(!anim.is_active(b).unwrap());
    assert_eq!(shoulder_x(&mut anim), 2.0);
    // Reaching the end starts b at fade 0 (start of the fade).
    anim.update(0.5);
    assert_eq!(anim.current(), Some(b));
    assert_eq!(anim.queued().count(), 0);
    assert_eq!(weights(&anim, a, b), (1.0, 0.0));
    assert_eq!(shoulder_x(&mut anim), 2.0);
    // Middle of the fade: half each.
    anim.update(0.25);
    assert_eq!(weights(&anim, a, b), (0.5, 0.5));
    assert_eq!(anim.time(b).unwrap(), 0.25);
    assert_eq!(shoulder_x(&mut anim), 6.0);
    // End of the fade: b alone, a dormant.
    anim.update(0.25);
    assert_eq!(weights(&anim, a, b), (0.0, 1.0));
    assert!(!anim.is_active(a).unwrap());
    assert_eq!(shoulder_x(&mut anim), 10.0);
}

#[test]
fn queue_advances_in_order_and_carries_time_past_the_end() {
    let mut anim = Animator::new(Arc::new(arm()));
    let a = anim.add_clip(hold("a", 1.0, false, false));
    let b = anim.add_clip(hold("b", 2.0, true, false));
    let c = anim.add_clip(hold("c", 3.0, false, false));
    anim.enqueue(a, 0.0).unwrap(); // nothing current: starts now
    anim.enqueue(b, 0.0).unwrap();
    anim.enqueue(c, 0.0).unwrap();
    assert_eq!(anim.current(), Some(a));
    anim.update(1.25);
    assert_eq!(anim.current(), Some(b));
    assert_eq!(anim.time(b).unwrap(), 0.25);
    assert!(!anim.is_active(a).unwrap());
    assert_eq!(shoulder_x(&mut anim), 2.0);
    // b loops: the end of its cycle starts c.
    anim.update(0.5);
    assert_eq!(anim.current(), Some(b));
    anim.update(0.5);
    assert_eq!(anim.current(), Some(c));
    assert_eq!(anim.time(c).unwrap(), 0.25);
    assert_eq!(shoulder_x(&mut anim), 3.0);
    // c ends with an empty queue: it stays current and holds.
    anim.update(5.0);
    assert_eq!(anim.current(), Some(c));
    assert_eq!(anim.time(c).unwrap(), 1.0);
    assert_eq!(shoulder_x(&mut anim), 3.0);
}

#[test]
fn immediate_cross_fade_and_skip() {
    let mut anim = Animator::new(Arc::new(arm()));
    let a = anim.add_clip(hold("a", 0.0, true, false));
    let b = anim.add_clip(hold("b", 8.0, true, false));
    anim.play(a).unwrap();
    anim.update(0.3);
    anim.cross_fade(b, 1.0).unwrap();
    assert_eq!(weights(&anim, a, b), (1.0, 0.0));
    assert_eq!(anim.time(b).unwrap(), 0.0);
    anim.update(0.25);
    assert_eq!(weights(&anim, a, b), (0.75, 0.25));
    assert_eq!(shoulder_x(&mut anim), 2.0);
    // Skip: the queued clip starts now, without waiting for b to end.
    anim.enqueue(a, 0.0).unwrap();
    assert!(anim.skip());
    assert_eq!(anim.current(), Some(a));
    assert_eq!(weights(&anim, a, b), (1.0, 0.0));
    assert!(!anim.skip());
}

#[test]
fn dormant_clips_cost_nothing_and_activate_without_rebinding() {
    let skeleton = Arc::new(arm());
    let mut anim = Animator::new(skeleton.clone());
    let base = anim.add_clip(hold("base", 1.0, true, false));
    // Drives the elbow only.
    let wave = Arc::new(
        Clip::from_curves(
            "wave",
            1.0,
            30.0,
            true,
            false,
            vec![TrackCurves {
                joint: "elbow".into(),
                translation: Curve::new(vec![0.0], vec![Vec3::new(0.0, 3.0, 0.0)]),
                ..Default::default()
            }],
        )
        .unwrap(),
    );
    let w = anim.add_clip(wave);
    let binding = anim.binding(w).unwrap().clone();
    assert_eq!(binding.driven(), [1]);
    anim.play(base).unwrap();
    assert!(!anim.is_active(w).unwrap());
    assert_eq!(anim.effective_weight(w).unwrap(), 0.0);
    let mut out = [Transform::IDENTITY; 2];
    anim.evaluate(&mut out).unwrap();
    assert_eq!(out[1].translation, Vec3::X); // bind
                                             // Activate with a mask letting it drive only the elbow (which it alone drives anyway).
    anim.set_mask(w, Some(vec![0.0, 1.0])).unwrap();
    anim.activate(w).unwrap();
    anim.evaluate(&mut out).unwrap();
    assert_eq!(out[0].translation, Vec3::new(1.0, 0.0, 0.0));
    assert_eq!(out[1].translation, Vec3::new(0.0, 3.0, 0.0));
    assert!(Arc::ptr_eq(&binding, anim.binding(w).unwrap()));
    // Back to dormant.
    anim.deactivate(w).unwrap();
    anim.evaluate(&mut out).unwrap();
    assert_eq!(out[1].translation, Vec3::X);
    assert_eq!(anim.current(), Some(base));
}

#[test]
fn additive_clip_in_the_animator_and_bad_arguments() {
    let mut anim = Animator::new(Arc::new(arm()));
    let base = anim.add_clip(hold("base", 1.0, true, false));
    let add = anim.add_clip(hold("lean", 0.5, true, true));
    anim.play(base).unwrap();
    anim.activate(add).unwrap();
    anim.set_weight(add, 2.0).unwrap();
    // 1 + 2 * 0.5.
    assert_eq!(shoulder_x(&mut anim), 2.0);
    assert_eq!(
        anim.set_mask(add, Some(vec![1.0])),
        Err(AnimatorError::BadMask {
            expected: 2,
            got: 1
        })
    );
    assert!(matches!(
        anim.set_mask(add, Some(vec![1.0, -1.0])),
        Err(AnimatorError::BadMask { .. })
    ));
    assert_eq!(
        anim.play(ClipId(9)),
        Err(AnimatorError::UnknownClip(ClipId(9)))
    );
    assert_eq!(
        anim.cross_fade(base, -1.0),
        Err(AnimatorError::BadValue("fade length"))
    );
    let mut short = [Transform::IDENTITY; 1];
    assert!(matches!(
        anim.evaluate(&mut short),
        Err(AnimatorError::Clip(sinew_core::ClipError::OutputLength {
            expected: 2,
            got: 1
        }))
    ));
}

// ---------------------------------------------------------------- skinning

/// Shoulder and elbow both rotated 90 degrees about z; returns the palette.
fn bent_arm_palette() -> Vec<Mat4> {
    let s = arm();
    let q = Quat::from_rotation_z(FRAC_PI_2);
    let locals = [
        Transform::from_rotation(q),
        Transform::new(Vec3::X, q, Vec3::ONE),
    ];
    let mut models = [Mat4::IDENTITY; 2];
    local_to_model(s.parents(), &locals, &mut models).unwrap();
    // The elbow sits at (0,1,0).
    assert_close(
        models[1].transform_point3(Vec3::ZERO),
        Vec3::new(0.0, 1.0, 0.0),
    );
    let mut palette = vec![Mat4::IDENTITY; 2];
    skinning_palette(&models, s.inverse_bind(), &mut palette).unwrap();
    palette
}

#[test]
fn skins_a_bent_two_joint_arm() {
    let palette = bent_arm_palette();
    let positions = [
        Vec3::new(1.5, 0.2, 0.0), // between the joints, half each
        Vec3::new(2.0, 0.0, 0.0), // forearm tip, elbow only
        Vec3::new(0.5, 0.0, 1.0), // upper arm, shoulder only
    ];
    let normals = [Vec3::Y, Vec3::Y, Vec3::Z];
    let joints = [[0, 1, 0, 0], [1, 0, 0, 0], [0, 0, 0, 0]];
    let weights = [
        [0.5, 0.5, 0.0, 0.0],
        [1.0, 0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0, 0.0],
    ];
    let mut p = [Vec3::ZERO; 3];
    let mut n = [Vec3::ZERO; 3];
    skin(
        &palette, &positions, &normals, &joints, &weights, &mut p, &mut n,
    )
    .unwrap();
    // Vertex 0 by hand: the shoulder (rotate 90) takes (1.5,0.2,0) to (-0.2,1.5,0); the elbow's
    // palette (to the elbow, rotate 90, back out along x, rotate 90) takes it to (-0.5,0.8,0).
    // Half each: (-0.35, 1.15, 0).
    assert_close(p[0], Vec3::new(-0.35, 1.15, 0.0));
    // Its normal +y goes to -x under the shoulder and to -y under the elbow (180 degrees);
    // the blend points halfway: (-0.70710677, -0.70710677, 0).
    assert_close(n[0], Vec3::new(-FRAC_1_SQRT_2, -FRAC_1_SQRT_2, 0.0));
    // Vertex 1: one unit past the elbow (0,1,0) along the forearm, which points along -x.
    assert_close(p[1], Vec3::new(-1.0, 1.0, 0.0));
    assert_close(n[1], Vec3::new(0.0, -1.0, 0.0));
    // Vertex 2: rotated 90 degrees about z with the shoulder; z untouched.
    assert_close(p[2], Vec3::new(0.0, 0.5, 1.0));
    assert_close(n[2], Vec3::Z);
    for v in n {
        assert!((v.length() - 1.0).abs() < 1e-6);
    }

    // The same through a Lod, and bit-identical on a second run.
    let lod = Lod {
        positions: positions.to_vec(),
        normals: normals.to_vec(),
        joints: joints.to_vec(),
        weights: weights.to_vec(),
        ..Default::default()
    };
    let mut p2 = [Vec3::ZERO; 3];
    let mut n2 = [Vec3::ZERO; 3];
    skin_lod(&palette, &lod, &mut p2, &mut n2).unwrap();
    assert_eq!(p, p2);
    assert_eq!(n, n2);
    // Positions only.
    let mut p3 = [Vec3::ZERO; 3];
    skin(
        &palette,
        &positions,
        &[],
        &joints,
        &weights,
        &mut p3,
        &mut [],
    )
    .unwrap();
    assert_eq!(p, p3);
}

#[test]
fn skinning_with_only_the_elbow_bent() {
    let s = arm();
    let locals = [
        Transform::IDENTITY,
        Transform::new(Vec3::X, Quat::from_rotation_z(FRAC_PI_2), Vec3::ONE),
    ];
    let mut models = [Mat4::IDENTITY; 2];
    local_to_model(s.parents(), &locals, &mut models).unwrap();
    let mut palette = [Mat4::IDENTITY; 2];
    skinning_palette(&models, s.inverse_bind(), &mut palette).unwrap();
    let mut p = [Vec3::ZERO; 1];
    let mut n = [Vec3::ZERO; 1];
    skin(
        &palette,
        &[Vec3::new(1.5, 0.2, 0.0)],
        &[Vec3::Y],
        &[[0, 1, 0, 0]],
        &[[0.5, 0.5, 0.0, 0.0]],
        &mut p,
        &mut n,
    )
    .unwrap();
    // Shoulder: unchanged (1.5,0.2,0). Elbow: (0.5,0.2,0) about the elbow turns to (-0.2,0.5,0),
    // i.e. (0.8,0.5,0). Half each: (1.15,0.35,0). The normal blends +y and -x: 45 degrees.
    assert_close(p[0], Vec3::new(1.15, 0.35, 0.0));
    assert_close(n[0], Vec3::new(-FRAC_1_SQRT_2, FRAC_1_SQRT_2, 0.0));
}

#[test]
fn skinning_validates_lengths_and_joint_indices() {
    let palette = [Mat4::IDENTITY; 2];
    let pos = [Vec3::ZERO; 2];
    let mut out = [Vec3::ZERO; 2];
    let mut out_n = [Vec3::ZERO; 2];
    let w = [[1.0, 0.0, 0.0, 0.0]; 2];
    assert_eq!(
        skin(&palette, &pos, &pos, &[[0; 4]], &w, &mut out, &mut out_n),
        Err(SkinError::Length {
            what: "joints",
            expected: 2,
            got: 1
        })
    );
    assert_eq!(
        skin(
            &palette,
            &pos,
            &pos[..1],
            &[[0; 4]; 2],
            &w,
            &mut out,
            &mut out_n
        ),
        Err(SkinError::Length {
            what: "normals",
            expected: 2,
            got: 1
        })
    );
    // A zero-weight slot still has to name a joint in the palette.
    assert_eq!(
        skin(
            &palette,
            &pos,
            &pos,
            &[[0; 4], [1, 0, 0, 2]],
            &w,
            &mut out,
            &mut out_n
        ),
        Err(SkinError::JointIndex {
            vertex: 1,
            joint: 2,
            palette: 2
        })
    );
    let mut models = [Mat4::IDENTITY; 1];
    assert_eq!(
        local_to_model(&[None, Some(0)], &[Transform::IDENTITY; 2], &mut models),
        Err(SkinError::Length {
            what: "models",
            expected: 2,
            got: 1
        })
    );
    let mut pal = [Mat4::IDENTITY; 3];
    assert_eq!(
        skinning_palette(&palette, &palette, &mut pal),
        Err(SkinError::Length {
            what: "palette",
            expected: 2,
            got: 3
        })
    );
    let static_lod = Lod {
        positions: pos.to_vec(),
        ..Default::default()
    };
    assert_eq!(
        skin_lod(&palette, &static_lod, &mut out, &mut []),
        Err(SkinError::Length {
            what: "joints",
            expected: 2,
            got: 0
        })
    );
}
