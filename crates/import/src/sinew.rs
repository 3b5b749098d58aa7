//! Importer for sinew's own `.sinew` files (layout: docs/format.md), through `sinew_core::format::read`.
//!
//! The scene it builds is what `sinew_pipeline::compile` would compile back to the same asset:
//! - the skeleton as stored;
//! - per mesh, LOD 0 as the geometry (with `source_vertex` the stored SRCV map, else the identity map) and further LODs as
//!   [`GeneratedLod`]s carrying the stored figures;
//! - materials and masks as stored;
//! - per clip, one curve per stored channel: an animated channel gets a key at every stored key time
//!   with the stored frame value; a constant channel one key at time 0; a bind channel no keys. Values
//!   are copied, never interpolated, so compiling the scene again gives the same key times and frames.
//!   A compressed clip is decoded first; its curves hold the decoded values at its kept key times.

use crate::{ImportError, ImportOptions, Resolver};
use sinew_core::format::{self, Asset, FormatError};
use sinew_core::glam::{Quat, Vec3};
use sinew_core::{Channel, Clip, Curve, TrackCurves};
use sinew_scene::{GeneratedLod, Material, Mesh, Scene, SceneClip, SourceFormat};

/// Imports a `.sinew` file. `resolve` and `options` are unused: a `.sinew` file refers to no other
/// file (texture paths are kept as strings).
pub fn import(
    file_name: &str,
    bytes: &[u8],
    _resolve: Resolver<'_>,
    _options: &ImportOptions,
) -> Result<Scene, ImportError> {
    let asset = format::read(bytes).map_err(|e| to_import_error(file_name, e))?;
    Ok(scene_from_asset(asset))
}

fn to_import_error(file_name: &str, e: FormatError) -> ImportError {
    let message = e.kind.to_string();
    match e.offset {
        Some(o) => ImportError::at_offset(file_name, &e.section, o, message),
        None => ImportError::in_section(file_name, &e.section, message),
    }
}

/// Builds the scene for a decoded asset (see the module docs).
pub fn scene_from_asset(asset: Asset) -> Scene {
    let mut scene = Scene::new(SourceFormat::Sinew);
    let lod_info = asset.lod_info.clone();
    let maps = asset.source_vertex;
    scene.masks = asset.masks;
    scene.game = asset.game;
    scene.axes = asset.axes;
    for (mi, mesh) in asset.meshes.into_iter().enumerate() {
        let mut lods = mesh.lods.into_iter().enumerate();
        let geometry = lods.next().map(|(_, l)| l).unwrap_or_default();
        let n = geometry.positions.len() as u32;
        let generated = lods
            .map(|(li, lod)| {
                let info = lod_info
                    .get(mi)
                    .and_then(|m| m.get(li))
                    .copied()
                    .unwrap_or_default();
                GeneratedLod {
                    error_relative: lod.error,
                    lod,
                    target_ratio: info.target_ratio,
                    reached_ratio: info.reached_ratio,
                    error_model: info.error_model,
                    stopped_by_error_limit: info.stopped_by_error_limit,
                    uv_seams_opened: false,
                }
            })
            .collect();
        let (source_vertex, source_vertex_count) = match maps.get(mi).cloned().flatten() {
            Some(m) => (m.map, m.source_vertex_count),
            None => ((0..n).collect(), n),
        };
        scene.meshes.push(Mesh {
            name: mesh.name,
            geometry,
            source_vertex,
            source_vertex_count,
            lods: generated,
            lods_not_built: Vec::new(),
        });
    }
    scene.materials = asset
        .materials
        .into_iter()
        .map(|m| Material {
            name: m.name,
            base_color: m.base_color,
            texture: m.texture,
        })
        .collect();
    scene.clips = asset.clips.iter().map(scene_clip).collect();
    scene.skeleton = asset.skeleton;
    scene
}

/// A clip's stored channels as curves with keys at the stored key times. A compressed clip is
/// decoded first ([`Clip::to_plain`]): its curves get the decoded values at its kept key times.
fn scene_clip(clip: &Clip) -> SceneClip {
    let plain;
    let clip = if clip.is_compressed() {
        plain = clip.to_plain();
        &plain
    } else {
        clip
    };
    let times = clip.times();
    let stride = clip.stride();
    let frames = clip.frames();
    // Frame `k`'s floats at `o..o + N`; `from_parts` checked that every offset fits the stride.
    let at = |k: usize, o: u32, n: usize| -> &[f32] {
        let start = k * stride + o as usize;
        frames.get(start..start + n).unwrap_or(&[0.0; 4][..n])
    };
    let vec_curve = |c: Channel<Vec3>| match c {
        Channel::Bind => Curve::default(),
        Channel::Constant(v) => Curve::new(vec![0.0], vec![v]),
        Channel::Animated(o) => Curve::new(
            times.to_vec(),
            (0..times.len())
                .map(|k| Vec3::from_slice(at(k, o, 3)))
                .collect(),
        ),
    };
    let tracks = clip
        .tracks()
        .iter()
        .map(|t| TrackCurves {
            joint: t.joint.clone(),
            translation: vec_curve(t.translation),
            rotation: match t.rotation {
                Channel::Bind => Curve::default(),
                Channel::Constant(q) => Curve::new(vec![0.0], vec![q]),
                Channel::Animated(o) => Curve::new(
                    times.to_vec(),
                    (0..times.len())
                        .map(|k| Quat::from_slice(at(k, o, 4)))
                        .collect(),
                ),
            },
            scale: vec_curve(t.scale),
        })
        .collect();
    SceneClip {
        name: clip.name().to_owned(),
        duration: clip.duration(),
        sample_rate: clip.sample_rate(),
        looping: clip.looping(),
        additive: clip.additive(),
        tracks,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Location;
    use sinew_core::format::{LodInfo, Material as FormatMaterial};
    use sinew_core::{ClipBinding, JointDesc, Lod, Sampler, Skeleton, Submesh, Transform};

    fn no_files(_: &str) -> std::io::Result<Vec<u8>> {
        Err(std::io::ErrorKind::NotFound.into())
    }

    fn clip() -> Clip {
        Clip::from_curves(
            "swing",
            2.0,
            4.0,
            true,
            false,
            vec![
                TrackCurves {
                    joint: "arm".into(),
                    translation: Curve::new(vec![0.0, 1.0], vec![Vec3::ZERO, Vec3::X]),
                    rotation: Curve::new(vec![0.5], vec![Quat::from_xyzw(0.0, 1.0, 0.0, 0.0)]),
                    ..Default::default()
                },
                TrackCurves {
                    joint: "hand".into(),
                    scale: Curve::new(vec![0.25, 1.5], vec![Vec3::ONE, Vec3::new(2.0, 1.0, 1.0)]),
                    ..Default::default()
                },
            ],
        )
        .unwrap()
    }

    fn asset() -> Asset {
        let (skeleton, _) = Skeleton::from_unordered(vec![
            JointDesc {
                name: "arm".into(),
                parent: None,
                bind_local: Transform::from_translation(Vec3::X),
                inverse_bind: None,
            },
            JointDesc {
                name: "hand".into(),
                parent: Some("arm".into()),
                bind_local: Transform::from_translation(Vec3::X),
                inverse_bind: None,
            },
        ])
        .unwrap();
        let lod = |n: usize, error: f32| Lod {
            positions: (0..n).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect(),
            normals: vec![Vec3::Y; n],
            joints: vec![[1, 0, 0, 0]; n],
            weights: vec![[1.0, 0.0, 0.0, 0.0]; n],
            indices: vec![0, 1, 2],
            submeshes: vec![Submesh {
                first_index: 0,
                index_count: 3,
                material: "steel".into(),
            }],
            error,
            ..Default::default()
        };
        Asset {
            skeleton: Some(skeleton),
            materials: vec![FormatMaterial {
                name: "steel".into(),
                base_color: [0.5, 0.5, 0.5, 1.0],
                texture: None,
            }],
            meshes: vec![sinew_core::Mesh {
                name: "arm".into(),
                lods: vec![lod(4, 0.0), lod(3, 0.125)],
            }],
            lod_info: vec![vec![
                LodInfo::default(),
                LodInfo {
                    target_ratio: 0.25,
                    reached_ratio: 0.5,
                    error_model: 0.75,
                    stopped_by_error_limit: false,
                },
            ]],
            clips: vec![clip()],
            ..Default::default()
        }
    }

    #[test]
    fn imports_skeleton_meshes_lods_materials_and_clips() {
        let bytes = format::write(&asset()).unwrap();
        let s = import("a.sinew", &bytes, &no_files, &ImportOptions::default()).unwrap();
        assert_eq!(s.source_format, SourceFormat::Sinew);
        assert_eq!(s.skeleton.as_ref().unwrap().names(), ["arm", "hand"]);
        let m = &s.meshes[0];
        assert_eq!(m.geometry.positions.len(), 4);
        assert_eq!(m.source_vertex, [0, 1, 2, 3]);
        assert_eq!(m.source_vertex_count, 4);
        assert_eq!(m.lods.len(), 1);
        let g = &m.lods[0];
        assert_eq!(g.lod.positions.len(), 3);
        assert_eq!(
            (
                g.error_relative,
                g.target_ratio,
                g.reached_ratio,
                g.error_model
            ),
            (0.125, 0.25, 0.5, 0.75)
        );
        assert_eq!(s.materials[0].name, "steel");

        let c = &s.clips[0];
        assert_eq!(
            (c.name.as_str(), c.duration, c.sample_rate),
            ("swing", 2.0, 4.0)
        );
        assert!(c.looping && !c.additive);
        // Keys at the union of source key times 0, 0.25, 1, 1.5 (0.5 was a constant's only key).
        let arm = &c.tracks[0];
        assert_eq!(arm.translation.times, [0.0, 0.25, 1.0, 1.5]);
        assert_eq!(
            arm.translation.values,
            [Vec3::ZERO, Vec3::X * 0.25, Vec3::X, Vec3::X]
        );
        assert_eq!(arm.rotation.times, [0.0]);
        assert_eq!(arm.rotation.values, [Quat::from_xyzw(0.0, 1.0, 0.0, 0.0)]);
        assert!(arm.scale.is_empty());
        let hand = &c.tracks[1];
        assert!(hand.translation.is_empty());
        assert_eq!(hand.scale.values[3], Vec3::new(2.0, 1.0, 1.0));
    }

    #[test]
    fn clips_rebuilt_from_the_scene_equal_the_stored_clips() {
        let bytes = format::write(&asset()).unwrap();
        let s = import("a.sinew", &bytes, &no_files, &ImportOptions::default()).unwrap();
        let c = &s.clips[0];
        let again = c.to_clip().unwrap();
        assert_eq!(again, clip());
    }

    /// A walking arm: 61 keys of a smooth rotation and translation, enough for compression to pay.
    fn animated_scene() -> Scene {
        let mut scene = Scene::new(SourceFormat::Gltf);
        scene.skeleton = asset().skeleton;
        let times: Vec<f32> = (0..61).map(|k| k as f32 / 30.0).collect();
        let rot = times
            .iter()
            .map(|t| Quat::from_rotation_z((t * 3.0).sin() * 0.8))
            .collect();
        let pos = times
            .iter()
            .map(|t| Vec3::new(1.0, (t * 2.0).cos() * 0.3, 0.0))
            .collect();
        scene.clips.push(SceneClip {
            name: "walk".into(),
            duration: 2.0,
            sample_rate: 30.0,
            // Not looping: a looping clip sampled at its duration wraps to time 0.
            looping: false,
            additive: false,
            tracks: vec![
                TrackCurves {
                    joint: "arm".into(),
                    rotation: Curve::new(times.clone(), rot),
                    ..Default::default()
                },
                TrackCurves {
                    joint: "hand".into(),
                    translation: Curve::new(times, pos),
                    ..Default::default()
                },
            ],
        });
        scene
    }

    #[test]
    fn compressed_clips_import_as_their_decoded_values() {
        let scene = animated_scene();
        let (compiled, report) =
            sinew_pipeline::compile::compile_with(&scene, &Default::default()).unwrap();
        let stored = &compiled.clips[0];
        assert!(stored.is_compressed() && report.clips[0].compressed);
        assert!(stored.frames().is_empty());
        let bytes = format::write(&compiled).unwrap();
        let s = import("c.sinew", &bytes, &no_files, &ImportOptions::default()).unwrap();
        let c = &s.clips[0];
        assert_eq!((c.name.as_str(), c.duration), ("walk", 2.0));
        let skeleton = s.skeleton.as_ref().unwrap();
        let binding = ClipBinding::new(stored, skeleton);
        let mut pose = vec![Transform::IDENTITY; skeleton.len()];
        let (arm, hand) = (&c.tracks[0], &c.tracks[1]);
        assert_eq!(arm.rotation.times, stored.times());
        assert_eq!(hand.translation.times, stored.times());
        assert!(arm.translation.is_empty() && hand.rotation.is_empty());
        for (k, &t) in stored.times().iter().enumerate() {
            // The decoded clip sampled at its own key time is the stored (dequantized) key.
            Sampler::new()
                .sample(stored, &binding, skeleton, t, &mut pose)
                .unwrap();
            let r = arm.rotation.values[k];
            assert!(
                r.dot(pose[0].rotation).abs() > 1.0 - 1e-6,
                "t {t}: {r} vs {}",
                pose[0].rotation
            );
            let p = hand.translation.values[k];
            assert!(p.distance(pose[1].translation) < 1e-5, "t {t}: {p}");
            // And it is the source animation within the tolerance, not zeros.
            assert!((r.length() - 1.0).abs() < 1e-3);
            let source = Quat::from_rotation_z((t * 3.0).sin() * 0.8);
            assert!(r.angle_between(source) < 0.01, "t {t}");
            assert!(p.distance(Vec3::new(1.0, (t * 2.0).cos() * 0.3, 0.0)) < 0.01);
        }
    }

    #[test]
    fn errors_name_the_file_section_and_offset() {
        let mut bytes = format::write(&asset()).unwrap();
        let e = import(
            "x.sinew",
            &bytes[..40],
            &no_files,
            &ImportOptions::default(),
        )
        .unwrap_err();
        assert_eq!((e.file.as_str(), e.section.as_str()), ("x.sinew", "header"));
        let last = bytes.len() - 1;
        bytes[last] ^= 0xFF;
        let e = import("x.sinew", &bytes, &no_files, &ImportOptions::default()).unwrap_err();
        assert_eq!(e.section, "CLIP");
        let clip_at = format::sections(&bytes).unwrap()[4].offset;
        assert_eq!(e.location, Location::Offset(clip_at));
        assert!(e.message.contains("checksum"), "{}", e.message);
    }
}
