//! Compiling a [`Scene`] into the runtime [`Asset`] that `sinew_core::format` writes as `.sinew` bytes.
//!
//! - The skeleton is kept as it is.
//! - Each scene mesh becomes a core [`Mesh`] whose LOD 0 is the imported geometry and whose further LODs
//!   are the generated ones, most detailed first. A generated LOD's `error_relative` becomes the core
//!   [`sinew_core::Lod::error`]; its ratios, model-unit error and stop reason go to
//!   [`Asset::lod_info`]. LOD 0 gets [`LodInfo::default`] (ratios 1, no error).
//! - Each [`sinew_scene::SceneClip`] becomes a [`Clip`] through [`Clip::from_curves`], which keeps every
//!   source key time, so sampling the compiled clip at a source key gives the source value exactly.
//! - Materials are copied.
//! - Each mesh's `source_vertex` map (when it has one entry per LOD-0 vertex, all below
//!   `source_vertex_count`) goes to [`Asset::source_vertex`] (the SRCV section); masks are copied.
//!
//! The result is checked with [`format::validate`], so compiling succeeds exactly when writing will.

use crate::compress::{compress_clip, ClipCompressionReport, CompressOptions, PARALLEL_VOLUME};
use rayon::prelude::*;
use sinew_core::format::{self, Asset, FormatError, LodInfo, Material, SourceVertexMap};
use sinew_core::{Clip, ClipError, Mesh, Skeleton};
use sinew_scene::{Scene, SceneClip};

/// Why a scene could not be compiled.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CompileError {
    /// A clip's curves do not make a valid clip.
    #[error("clip {clip:?}: {source}")]
    Clip {
        /// The clip's name.
        clip: String,
        /// What is wrong with it.
        source: ClipError,
    },
    /// The compiled asset breaks a rule of the format (a mesh index out of range, a non-finite value…).
    #[error(transparent)]
    Format(#[from] FormatError),
}

/// Compiles a scene into a runtime asset. Deterministic: the same scene gives the same asset.
pub fn compile(scene: &Scene) -> Result<Asset, CompileError> {
    compile_parts(scene, None)
}

/// [`compile`] with the clips already compiled (and possibly compressed) when `clips` is given.
fn compile_parts(scene: &Scene, clips: Option<Vec<Clip>>) -> Result<Asset, CompileError> {
    let mut meshes = Vec::with_capacity(scene.meshes.len());
    let mut lod_info = Vec::with_capacity(scene.meshes.len());
    let mut source_vertex = Vec::with_capacity(scene.meshes.len());
    for m in &scene.meshes {
        // The map is kept when it has one entry per LOD-0 vertex, each below the source count;
        // an identity map over the whole source is kept too (it is what the user's file has).
        let map = SourceVertexMap {
            source_vertex_count: m.source_vertex_count,
            map: m.source_vertex.clone(),
        };
        let ok = !map.map.is_empty()
            && map.map.len() == m.geometry.positions.len()
            && map.map.iter().all(|&s| s < map.source_vertex_count);
        source_vertex.push(ok.then_some(map));
        let mut lods = Vec::with_capacity(1 + m.lods.len());
        let mut info = Vec::with_capacity(1 + m.lods.len());
        lods.push(m.geometry.clone());
        info.push(LodInfo::default());
        for g in &m.lods {
            lods.push(sinew_core::Lod {
                error: g.error_relative,
                ..g.lod.clone()
            });
            info.push(LodInfo {
                target_ratio: g.target_ratio,
                reached_ratio: g.reached_ratio,
                error_model: g.error_model,
                stopped_by_error_limit: g.stopped_by_error_limit,
            });
        }
        meshes.push(Mesh {
            name: m.name.clone(),
            lods,
        });
        lod_info.push(info);
    }
    let clips = match clips {
        Some(c) => c,
        None => compile_clips(&scene.clips)?,
    };
    let materials = scene
        .materials
        .iter()
        .map(|m| Material {
            name: m.name.clone(),
            base_color: m.base_color,
            texture: m.texture.clone(),
        })
        .collect();
    let asset = Asset {
        skeleton: scene.skeleton.clone(),
        materials,
        meshes,
        lod_info,
        clips,
        source_vertex,
        masks: scene.masks.clone(),
        game: scene.game.clone(),
        axes: scene.axes,
    };
    format::validate(&asset)?;
    Ok(asset)
}

/// Each scene clip as a [`Clip`] ([`Clip::from_curves`]), in order.
fn compile_clips(clips: &[SceneClip]) -> Result<Vec<Clip>, CompileError> {
    clips
        .iter()
        .map(|c| {
            c.to_clip().map_err(|source| CompileError::Clip {
                clip: c.name.clone(),
                source,
            })
        })
        .collect()
}

/// Options of [`compile_with`].
#[derive(Debug, Clone, PartialEq)]
pub struct CompileOptions {
    /// Compress clips with these options; `None` keeps plain f32 clips. Default: compression on, with
    /// [`CompressOptions::default`] (tolerance and distance relative to the skeleton's size).
    pub compress: Option<CompressOptions>,
}

impl Default for CompileOptions {
    fn default() -> Self {
        Self {
            compress: Some(CompressOptions::default()),
        }
    }
}

/// What [`compile_with`] reports besides the asset.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct CompileReport {
    /// One entry per clip, in clip order, when compression was on.
    pub clips: Vec<ClipCompressionReport>,
}

/// Compiles a scene like [`compile`], then compresses every clip when `options.compress` is set
/// (each within its tolerance, measured against the scene's skeleton; see [`crate::compress`]).
pub fn compile_with(
    scene: &Scene,
    options: &CompileOptions,
) -> Result<(Asset, CompileReport), CompileError> {
    let compressed = match &options.compress {
        Some(o) => Some(compress_clips(&scene.clips, scene.skeleton.as_ref(), o)?),
        None => None,
    };
    compile_compressed(scene, compressed)
}

/// A scene's clips compiled and compressed, in clip order, with one report each: the clip part of
/// [`compile_with`], for callers that do it beside other work on the same scene (the LODs, which
/// touch only the meshes) and finish with [`compile_compressed`].
pub type CompressedClips = (Vec<Clip>, Vec<ClipCompressionReport>);

/// Compiles `clips` and compresses each (see [`compile_with`]); `skeleton` is the scene's.
pub fn compress_clips(
    clips: &[SceneClip],
    skeleton: Option<&Skeleton>,
    options: &CompressOptions,
) -> Result<CompressedClips, CompileError> {
    compress_clips_timed(clips, skeleton, options).map(|(done, _)| done)
}

/// [`compress_clips`], with each clip's encoding wall time in seconds (clip order; clips run in
/// parallel, so the times overlap): what `convert --timings` reports.
pub fn compress_clips_timed(
    clips: &[SceneClip],
    skeleton: Option<&Skeleton>,
    options: &CompressOptions,
) -> Result<(CompressedClips, Vec<f64>), CompileError> {
    let clips = compile_clips(clips)?;
    let timed = |clip: &Clip| {
        let started = std::time::Instant::now();
        let (c, r) = compress_clip(clip, skeleton, options);
        (c, (r, started.elapsed().as_secs_f64()))
    };
    // Clips are independent: compressed in parallel, results kept in clip order (the same bytes
    // at any thread count). Small scenes stay on the calling thread (see `PARALLEL_VOLUME`).
    let volume: usize = clips
        .iter()
        .map(|c| c.times().len() * c.tracks().len())
        .sum();
    let done: Vec<(Clip, (ClipCompressionReport, f64))> =
        if clips.len() > 1 && volume >= PARALLEL_VOLUME {
            clips.par_iter().map(timed).collect()
        } else {
            clips.iter().map(timed).collect()
        };
    let (clips, timed): (Vec<Clip>, Vec<(ClipCompressionReport, f64)>) = done.into_iter().unzip();
    let (reports, seconds) = timed.into_iter().unzip();
    Ok(((clips, reports), seconds))
}

/// Compiles a scene like [`compile`] with the clips of [`compress_clips`] (for the same scene
/// clips) in place of its own; `None` compiles them plain, as [`compile`] does.
pub fn compile_compressed(
    scene: &Scene,
    compressed: Option<CompressedClips>,
) -> Result<(Asset, CompileReport), CompileError> {
    let (clips, reports) = match compressed {
        Some((clips, reports)) => (Some(clips), reports),
        None => (None, Vec::new()),
    };
    let asset = compile_parts(scene, clips)?;
    Ok((asset, CompileReport { clips: reports }))
}

/// Compiles a scene and encodes it as `.sinew` bytes.
pub fn compile_to_bytes(scene: &Scene) -> Result<Vec<u8>, CompileError> {
    Ok(format::write(&compile(scene)?)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use sinew_core::glam::{Quat, Vec3};
    use sinew_core::{Curve, JointDesc, Lod, Submesh, TrackCurves, Transform};
    use sinew_scene::{GeneratedLod, SceneClip, SourceFormat};

    fn scene() -> Scene {
        let (skeleton, _) = sinew_core::Skeleton::from_unordered(vec![
            JointDesc {
                name: "hips".into(),
                parent: None,
                bind_local: Transform::from_translation(Vec3::Y),
                inverse_bind: None,
            },
            JointDesc {
                name: "leg".into(),
                parent: Some("hips".into()),
                bind_local: Transform::from_translation(-Vec3::Y * 0.5),
                inverse_bind: None,
            },
        ])
        .unwrap();
        let tri = |scale: f32| Lod {
            positions: vec![Vec3::ZERO, Vec3::X * scale, Vec3::Y * scale],
            normals: vec![Vec3::Z; 3],
            joints: vec![[0, 1, 0, 0]; 3],
            weights: vec![[0.5, 0.5, 0.0, 0.0]; 3],
            indices: vec![0, 1, 2],
            submeshes: vec![Submesh {
                first_index: 0,
                index_count: 3,
                material: "mat".into(),
            }],
            ..Default::default()
        };
        let mut s = Scene::new(SourceFormat::Gltf);
        s.skeleton = Some(skeleton);
        s.meshes.push(sinew_scene::Mesh {
            name: "legs".into(),
            geometry: tri(1.0),
            source_vertex: vec![0, 1, 2],
            source_vertex_count: 3,
            lods: vec![GeneratedLod {
                lod: tri(2.0),
                target_ratio: 0.5,
                reached_ratio: 1.0,
                error_relative: 0.25,
                error_model: 0.5,
                stopped_by_error_limit: true,
                uv_seams_opened: false,
            }],
            lods_not_built: Vec::new(),
        });
        s.materials.push(sinew_scene::Material {
            name: "mat".into(),
            base_color: [0.5, 0.25, 1.0, 1.0],
            texture: Some("a.png".into()),
        });
        s.clips.push(SceneClip {
            name: "kick".into(),
            duration: 1.0,
            sample_rate: 10.0,
            looping: false,
            additive: false,
            tracks: vec![TrackCurves {
                joint: "leg".into(),
                rotation: Curve::new(
                    vec![0.0, 0.4, 1.0],
                    vec![
                        Quat::IDENTITY,
                        Quat::from_xyzw(1.0, 0.0, 0.0, 0.0),
                        Quat::IDENTITY,
                    ],
                ),
                translation: Curve::new(vec![0.2], vec![Vec3::new(0.0, -0.5, 0.0)]),
                ..Default::default()
            }],
        });
        s
    }

    #[test]
    fn compiles_lods_materials_and_clips() {
        let asset = compile(&scene()).unwrap();
        assert_eq!(asset.skeleton.as_ref().unwrap().names(), ["hips", "leg"]);
        let m = &asset.meshes[0];
        assert_eq!(m.name, "legs");
        assert_eq!(m.lods.len(), 2);
        assert_eq!(m.lods[0].error, 0.0);
        assert_eq!(m.lods[1].positions[1], Vec3::X * 2.0);
        assert_eq!(m.lods[1].error, 0.25);
        assert_eq!(asset.lod_info[0][0], LodInfo::default());
        assert_eq!(
            asset.lod_info[0][1],
            LodInfo {
                target_ratio: 0.5,
                reached_ratio: 1.0,
                error_model: 0.5,
                stopped_by_error_limit: true
            }
        );
        assert_eq!(asset.materials[0].texture.as_deref(), Some("a.png"));
        let c = &asset.clips[0];
        assert_eq!(c.name(), "kick");
        assert_eq!(c.times(), [0.0, 0.4, 1.0]);
        assert_eq!(c.stride(), 4);
        assert_eq!(&c.frames()[4..8], &[1.0, 0.0, 0.0, 0.0]);
        assert_eq!(
            c.tracks()[0].translation,
            sinew_core::Channel::Constant(Vec3::new(0.0, -0.5, 0.0))
        );
    }

    #[test]
    fn bytes_read_back_to_the_compiled_asset() {
        let bytes = compile_to_bytes(&scene()).unwrap();
        let back = format::read(&bytes).unwrap();
        assert_eq!(back, compile(&scene()).unwrap());
        assert_eq!(compile_to_bytes(&scene()).unwrap(), bytes);
    }

    #[test]
    fn scene_survives_compile_write_import_compile() {
        let bytes = compile_to_bytes(&scene()).unwrap();
        let no_files =
            |_: &str| -> std::io::Result<Vec<u8>> { Err(std::io::ErrorKind::NotFound.into()) };
        let back =
            sinew_import::sinew::import("t.sinew", &bytes, &no_files, &Default::default()).unwrap();
        assert_eq!(back.source_format, SourceFormat::Sinew);
        let g = &back.meshes[0].lods[0];
        assert_eq!(
            (g.target_ratio, g.error_relative, g.error_model),
            (0.5, 0.25, 0.5)
        );
        assert_eq!(g.lod.positions, scene().meshes[0].lods[0].lod.positions);
        assert_eq!(
            back.clips[0].tracks[0].rotation,
            scene().clips[0].tracks[0].rotation
        );
        // The constant translation comes back as one key at 0 instead of 0.2; it compiles the same.
        assert_eq!(back.clips[0].tracks[0].translation.times, [0.0]);
        assert_eq!(compile_to_bytes(&back).unwrap(), bytes);
    }

    #[test]
    fn a_single_pose_clip_reports_its_raw_size() {
        // One key: nothing is animated, but the clip stores the leg's pose (and the hips').
        fn first<T: Copy>(c: &Curve<T>) -> Curve<T> {
            Curve::new(
                c.times.iter().take(1).copied().collect(),
                c.values.iter().take(1).copied().collect(),
            )
        }
        let mut s = scene();
        for t in &mut s.clips[0].tracks {
            t.translation = first(&t.translation);
            t.rotation = first(&t.rotation);
            t.scale = first(&t.scale);
        }
        let (_, report) = compile_with(&s, &CompileOptions::default()).unwrap();
        let r = &report.clips[0];
        let driven = s.clips[0]
            .tracks
            .iter()
            .filter(|t| !t.translation.is_empty() || !t.rotation.is_empty() || !t.scale.is_empty())
            .count();
        assert_eq!((r.animated_joints, r.samples), (0, 1));
        assert_eq!(r.raw_bytes, 40 * driven);
        assert!(driven > 0 && r.ratio > 0.0, "{r:?}");
    }

    #[test]
    fn compile_with_compresses_clips_within_tolerance_and_reports_them() {
        let (asset, report) = compile_with(&scene(), &CompileOptions::default()).unwrap();
        let plain = compile(&scene()).unwrap();
        assert_eq!(report.clips.len(), 1);
        let r = &report.clips[0];
        assert_eq!(r.clip, "kick");
        // One animated joint (the leg's rotation), three source keys: 3 x 40 bytes raw.
        assert_eq!((r.animated_joints, r.samples, r.raw_bytes), (1, 3, 120));
        assert!(r.max_error <= r.tolerance, "{r:?}");
        // The extent of the skeleton is 0.5 (hips to leg), so the default tolerance is 0.00025.
        assert!((r.tolerance - 0.5 * crate::compress::DEFAULT_RELATIVE_TOLERANCE).abs() < 1e-9);
        let bytes = format::write(&asset).unwrap();
        assert_eq!(format::read(&bytes).unwrap(), asset);
        assert!(asset.clips[0].is_compressed());
        assert!(
            format::clip_record_size(&asset.clips[0]) < format::clip_record_size(&plain.clips[0])
        );
        let (off, none) = compile_with(&scene(), &CompileOptions { compress: None }).unwrap();
        assert_eq!(off, plain);
        assert!(none.clips.is_empty());
    }

    #[test]
    fn bad_clips_and_bad_meshes_are_errors() {
        let mut s = scene();
        s.clips[0].duration = 0.5;
        assert!(matches!(
            compile(&s),
            Err(CompileError::Clip { clip, source: ClipError::BadDuration(_) }) if clip == "kick"
        ));
        let mut s = scene();
        s.meshes[0].lods[0].lod.indices[2] = 3;
        let e = compile(&s).unwrap_err();
        assert!(e.to_string().contains("\"legs\" LOD 1"), "{e}");
    }
}
