//! Why a clip is kept plain, in the compression report: a tolerance that no encoding can hold (f32
//! rounding of positions far from the origin exceeds it) is told apart from a compressed form that
//! was merely not smaller. Found on a held-out motion-capture clip whose figure stands 4.5 m from
//! the origin, in centimetres (docs/performance.md, session 28).
#![allow(clippy::unwrap_used)]

use sinew_core::glam::{Quat, Vec3};
use sinew_core::{Clip, Curve, JointDesc, Skeleton, TrackCurves, Transform};
use sinew_pipeline::compress::{compress_clip, CompressOptions, KeptPlain};

/// A root `offset` from the origin walking 1,000 units along x over 30 keys, and a child 10 units
/// above it swinging.
fn walk(offset: f32) -> (Skeleton, Clip) {
    let joint = |name: &str, parent: Option<&str>, y: f32| JointDesc {
        name: name.into(),
        parent: parent.map(Into::into),
        bind_local: Transform::from_translation(Vec3::new(0.0, y, 0.0)),
        inverse_bind: None,
    };
    let skeleton = Skeleton::from_unordered(vec![
        joint("root", None, 0.0),
        joint("arm", Some("root"), 10.0),
    ])
    .unwrap()
    .0;
    let times: Vec<f32> = (0..30).map(|k| k as f32 / 30.0).collect();
    let path = times
        .iter()
        .map(|t| Vec3::new(offset + 1000.0 * t, 0.0, 0.0))
        .collect();
    let swing = times
        .iter()
        .map(|t| Quat::from_rotation_z(0.8 * (3.0 * t).sin()))
        .collect();
    let tracks = vec![
        TrackCurves {
            joint: "root".into(),
            translation: Curve::new(times.clone(), path),
            ..Default::default()
        },
        TrackCurves {
            joint: "arm".into(),
            rotation: Curve::new(times.clone(), swing),
            ..Default::default()
        },
    ];
    let clip = Clip::from_curves("walk", times[29], 30.0, false, false, tracks).unwrap();
    (skeleton, clip)
}

#[test]
fn a_tolerance_below_the_f32_rounding_far_from_the_origin_is_reported_as_not_held() {
    // 0.001 units a million units from the origin: one f32 step there is 0.0625.
    let options = CompressOptions {
        tolerance: Some(0.001),
        error_distance: Some(0.1),
        ..CompressOptions::default()
    };
    let (skeleton, clip) = walk(1.0e6);
    let (out, report) = compress_clip(&clip, Some(&skeleton), &options);
    assert!(!report.compressed);
    assert!(!out.is_compressed());
    assert_eq!(out, clip);
    assert_eq!(report.kept_plain_because, Some(KeptPlain::ToleranceNotHeld));
    // The noise there (8 f32 steps of a coordinate of 1e6) is above half the tolerance, where the
    // limit stops falling.
    assert_eq!(report.error_limit, Some(0.0005));
    assert_eq!(report.compressed_bytes, report.plain_bytes);
    let json = serde_json::to_value(&report).unwrap();
    assert_eq!(json["kept_plain_because"], "tolerance_not_held");

    // The same walk at the origin compresses, and the report has neither field.
    let (skeleton, clip) = walk(0.0);
    let (out, report) = compress_clip(&clip, Some(&skeleton), &options);
    assert!(report.compressed && out.is_compressed());
    assert!(report.max_error <= 0.001, "{}", report.max_error);
    assert_eq!(report.kept_plain_because, None);
    assert_eq!(report.error_limit, None);
    let json = serde_json::to_value(&report).unwrap();
    assert!(json.get("kept_plain_because").is_none(), "{json}");
    assert!(json.get("error_limit").is_none(), "{json}");
}
