//! Small assets shared by the `.sinew` format tests, built by hand (not by the code under test).
#![allow(dead_code, clippy::unwrap_used)]

use sinew_core::format::{Asset, LodInfo, Material};
use sinew_core::glam::{Quat, Vec2, Vec3};
use sinew_core::{Curve, JointDesc, Lod, Mesh, Skeleton, Submesh, TrackCurves, Transform};

/// root -> spine -> head, plus a second root "prop".
pub fn skeleton() -> Skeleton {
    let j = |name: &str, parent: Option<&str>, t: Vec3| JointDesc {
        name: name.into(),
        parent: parent.map(Into::into),
        bind_local: Transform::new(t, Quat::from_rotation_y(0.25), Vec3::new(1.0, 2.0, 1.0)),
        inverse_bind: None,
    };
    Skeleton::from_unordered(vec![
        j("root", None, Vec3::new(0.0, 1.0, 0.0)),
        j("spine", Some("root"), Vec3::new(0.0, 0.5, 0.0)),
        j("head", Some("spine"), Vec3::new(0.0, 0.25, 0.1)),
        j("prop", None, Vec3::new(2.0, 0.0, 0.0)),
    ])
    .unwrap()
    .0
}

/// A skinned quad (two triangles, two submeshes) and a one-triangle LOD 1.
pub fn mesh() -> Mesh {
    let lod0 = Lod {
        positions: vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.5),
        ],
        normals: vec![Vec3::Z; 4],
        uvs: vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ],
        joints: vec![[0, 1, 0, 0], [1, 2, 0, 0], [2, 0, 0, 0], [3, 0, 0, 0]],
        weights: vec![
            [0.5, 0.5, 0.0, 0.0],
            [0.75, 0.25, 0.0, 0.0],
            [1.0, 0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0, 0.0],
        ],
        indices: vec![0, 1, 2, 0, 2, 3],
        submeshes: vec![
            Submesh {
                first_index: 0,
                index_count: 3,
                material: "skin".into(),
            },
            Submesh {
                first_index: 3,
                index_count: 3,
                material: "cloth".into(),
            },
        ],
        error: 0.0,
    };
    let lod1 = Lod {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        normals: vec![Vec3::Z; 3],
        uvs: Vec::new(),
        joints: vec![[0, 0, 0, 0]; 3],
        weights: vec![[1.0, 0.0, 0.0, 0.0]; 3],
        indices: vec![0, 1, 2],
        submeshes: vec![Submesh {
            first_index: 0,
            index_count: 3,
            material: "skin".into(),
        }],
        error: 0.125,
    };
    Mesh {
        name: "body".into(),
        lods: vec![lod0, lod1],
    }
}

/// A static mesh without normals, UVs or skin.
pub fn prop_mesh() -> Mesh {
    Mesh {
        name: "crate".into(),
        lods: vec![Lod {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            indices: vec![0, 1, 2],
            ..Default::default()
        }],
    }
}

/// "walk": animated root translation, spine rotation, constant head scale, and a track for a joint the
/// skeleton does not have ("tail").
pub fn walk() -> sinew_core::Clip {
    sinew_core::Clip::from_curves(
        "walk",
        1.0,
        30.0,
        true,
        false,
        vec![
            TrackCurves {
                joint: "root".into(),
                translation: Curve::new(
                    vec![0.0, 0.5, 0.75],
                    vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.5, -1.0)],
                ),
                ..Default::default()
            },
            TrackCurves {
                joint: "spine".into(),
                rotation: Curve::new(
                    vec![0.0, 0.5],
                    vec![Quat::IDENTITY, Quat::from_xyzw(0.0, 0.0, 1.0, 0.0)],
                ),
                ..Default::default()
            },
            TrackCurves {
                joint: "head".into(),
                scale: Curve::new(vec![0.0], vec![Vec3::splat(1.5)]),
                translation: Curve::new(vec![0.25], vec![Vec3::new(0.0, 0.25, 0.0)]),
                ..Default::default()
            },
            TrackCurves {
                joint: "tail".into(),
                rotation: Curve::new(vec![0.0], vec![Quat::from_xyzw(0.0, 1.0, 0.0, 0.0)]),
                ..Default::default()
            },
        ],
    )
    .unwrap()
}

/// An additive, non-looping clip with only constants.
pub fn wave() -> sinew_core::Clip {
    sinew_core::Clip::from_curves(
        "wave",
        0.0,
        24.0,
        false,
        true,
        vec![TrackCurves {
            joint: "head".into(),
            translation: Curve::new(vec![0.0], vec![Vec3::new(0.0, 0.0, 0.5)]),
            ..Default::default()
        }],
    )
    .unwrap()
}

/// Skeleton, two materials, a skinned mesh with two LODs, a static prop, two clips.
pub fn full_asset() -> Asset {
    Asset {
        skeleton: Some(skeleton()),
        materials: vec![
            Material {
                name: "skin".into(),
                base_color: [1.0, 0.8, 0.6, 1.0],
                texture: Some("textures/skin.png".into()),
            },
            Material {
                name: "cloth".into(),
                base_color: [0.1, 0.2, 0.3, 0.5],
                texture: None,
            },
        ],
        meshes: vec![mesh(), prop_mesh()],
        lod_info: vec![
            vec![
                LodInfo::default(),
                LodInfo {
                    target_ratio: 0.5,
                    reached_ratio: 0.5,
                    error_model: 0.03,
                    stopped_by_error_limit: true,
                },
            ],
            vec![LodInfo::default()],
        ],
        clips: vec![walk(), wave()],
        ..Default::default()
    }
}
