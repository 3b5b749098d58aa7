//! Baking skinned vertex caches: every frame of one or more clips (or of a blend of layers) posed by the
//! runtime's own [`sinew_core::Animator`] (its [`Animator::evaluate_palette`], the call a game makes
//! each frame) and skinned with [`sinew_core::skin_lod`], on the decoded [`Asset`], so that a cache is
//! bit for bit what a game draws.
//!
//! # Frames
//!
//! A clip of duration `d` baked at `fps` has `n = ceil(d * fps - 1e-3) + 1` frames (the small tolerance
//! keeps a product like `29.999998` from adding a frame); frame `i < n - 1` is clip time `i / fps`
//! (computed in f64, rounded to f32) and frame `n - 1` is exactly `d`. A looping clip sampled at `d`
//! wraps to its start, as the runtime does. Clips are baked one after another in the requested order
//! (file order when none is requested).
//!
//! A layered bake plays its layers together in one animator: normal layers blend with their weight
//! times their mask (a MASK section entry of the file), then additive layers are applied, in order.
//! It runs over the duration (and at the sample rate, unless `fps` is given) of the first layer.
//!
//! Frames are skinned in parallel with rayon; every frame is computed from scratch (a fresh copy of
//! the segment's animator with every layer's time set), so the result is the same bits for any thread
//! count.
//!
//! # Meshes
//!
//! A bake skins the meshes of the request at the same LOD, their vertices one after another in the
//! order given (triangle indices offset accordingly). No meshes given means the model's default body
//! ([`crate::body`]: submodel 0 of every body group, every mesh when there are none), its skinned
//! meshes only.
//!
//! # Vertex order
//!
//! [`VertexOrder::Split`] is the LOD's own vertex order. [`VertexOrder::Source`] (LOD 0 only) is the
//! source file's vertex order through the file's source-vertex map: source vertex `s` takes the values of
//! the first LOD-0 vertex that maps to it. Every source vertex must be used. With several meshes each
//! keeps its own source order, one mesh after another.

use crate::body::{self, BodyChoice, BodyError};
use crate::cache::Frames;
use rayon::prelude::*;
use sinew_core::format::Asset;
use sinew_core::glam::{Mat4, Vec3};
use sinew_core::{
    skin_lod, Animator, AnimatorError, BlendError, Clip, ClipError, ClipId, Lod, Mesh, Skeleton,
    SkinError,
};
use std::sync::Arc;

/// Highest frame rate a bake accepts.
pub const MAX_FPS: f32 = 1000.0;
/// Most frames one bake may produce.
pub const MAX_FRAMES: usize = 1 << 20;

/// Which vertex order a cache follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum VertexOrder {
    /// sinew's split vertex order (the LOD's vertex buffer).
    #[default]
    Split,
    /// The source file's vertex order (LOD 0 only; needs the file's source-vertex map).
    Source,
}

/// One layer of a layered bake: `clip[@mask][:weight]`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LayerSpec {
    /// Clip name.
    pub clip: String,
    /// Mask name (MASK section), or none for every joint.
    pub mask: Option<String>,
    /// Layer weight.
    pub weight: f32,
}

impl LayerSpec {
    /// Parses `clip`, `clip@mask`, `clip:0.8` or `clip@mask:0.8`. The weight must be finite and >= 0.
    pub fn parse(spec: &str) -> Result<Self, String> {
        let (rest, weight) = match spec.rsplit_once(':') {
            Some((r, w)) => {
                let w: f32 = w
                    .parse()
                    .map_err(|_| format!("layer {spec:?}: weight {w:?} is not a number"))?;
                if !w.is_finite() || w < 0.0 {
                    return Err(format!("layer {spec:?}: weight must be finite and >= 0"));
                }
                (r, w)
            }
            None => (spec, 1.0),
        };
        let (clip, mask) = match rest.split_once('@') {
            Some((c, m)) => (c, Some(m.to_string())),
            None => (rest, None),
        };
        if clip.is_empty() || mask.as_deref() == Some("") {
            return Err(format!(
                "layer {spec:?}: expected CLIP[@MASK][:WEIGHT], e.g. wave@upper:0.8"
            ));
        }
        Ok(Self {
            clip: clip.to_string(),
            mask,
            weight,
        })
    }
}

/// What to bake.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BakeRequest {
    /// Clips baked one after another; empty (with no layers) = every clip in file order.
    pub clips: Vec<String>,
    /// Layers of a layered bake (when non-empty, `clips` must be empty).
    pub layers: Vec<LayerSpec>,
    /// Frames per second; default: the sample rate of the first clip (or first layer's clip).
    pub fps: Option<f32>,
    /// Mesh indices, skinned one after another; empty = the default body's skinned meshes.
    pub meshes: Vec<usize>,
    /// LOD index.
    pub lod: usize,
    /// Vertex order of the output.
    pub vertex_order: VertexOrder,
}

/// A range of frames in a bake.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClipRange {
    /// Clip name (for a layered bake, the layers joined with `+`).
    pub name: String,
    /// First frame of the range.
    pub first_frame: usize,
    /// Number of frames.
    pub frame_count: usize,
    /// Whether the clip loops.
    pub looping: bool,
    /// Clip duration, seconds.
    pub duration: f32,
}

/// The result of a bake.
#[derive(Debug, Clone, PartialEq)]
pub struct Baked {
    /// Skinned frames in the requested vertex order (normals empty when the LOD has none).
    pub frames: Frames,
    /// Frame ranges, in bake order.
    pub clips: Vec<ClipRange>,
    /// Bind-pose positions in the output vertex order.
    pub bind_positions: Vec<Vec3>,
    /// Triangles in the output vertex order.
    pub indices: Vec<u32>,
    /// The meshes baked, in output order.
    pub meshes: Vec<usize>,
    /// Their names.
    pub mesh_names: Vec<String>,
    /// Their names joined with ` + ` (one name for one mesh).
    pub mesh_name: String,
}

/// Why a bake was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BakeError {
    /// The file has no skeleton.
    #[error("the file has no skeleton to skin with")]
    NoSkeleton,
    /// The mesh index is out of range.
    #[error("mesh {mesh} does not exist; the file has {count} meshes")]
    NoMesh {
        /// Requested mesh.
        mesh: usize,
        /// Meshes in the file.
        count: usize,
    },
    /// The LOD index is out of range.
    #[error("LOD {lod} does not exist; mesh {mesh:?} has LODs 0..={last}")]
    NoLod {
        /// Requested LOD.
        lod: usize,
        /// Mesh name.
        mesh: String,
        /// Last LOD index.
        last: usize,
    },
    /// The LOD has no joint weights.
    #[error("mesh {0:?} is not skinned")]
    NotSkinned(String),
    /// The default body could not be found.
    #[error("{0}")]
    Body(#[from] BodyError),
    /// A clip name is not in the file.
    #[error("no clip {name:?}; the file has: {}", list(available))]
    UnknownClip {
        /// Requested name.
        name: String,
        /// Clips in the file, in order.
        available: Vec<String>,
    },
    /// A mask name is not in the file.
    #[error("no mask {name:?}; the file has: {}", list(available))]
    UnknownMask {
        /// Requested name.
        name: String,
        /// Masks in the file.
        available: Vec<String>,
    },
    /// Nothing to bake.
    #[error("the file has no clips to bake")]
    NoClips,
    /// Both clips and layers were requested.
    #[error("give clips or layers, not both")]
    ClipsAndLayers,
    /// The frame rate is unusable.
    #[error("fps {0} is not usable: it must be a number above 0 and at most 1000{1}")]
    BadFps(f32, &'static str),
    /// Too many frames.
    #[error("{0} frames exceed the limit of {MAX_FRAMES}")]
    TooManyFrames(usize),
    /// Source order was requested but cannot be produced.
    #[error("source vertex order: {0}")]
    SourceOrder(String),
    /// Sampling failed.
    #[error("sampling clip {clip:?}: {source}")]
    Clip {
        /// Clip name.
        clip: String,
        /// Runtime error.
        source: ClipError,
    },
    /// Blending failed.
    #[error("blending: {0}")]
    Blend(#[from] BlendError),
    /// The animator refused a layer (a weight or mask that is not finite, ...).
    #[error("layers: {0}")]
    Animator(#[from] AnimatorError),
    /// Skinning failed.
    #[error("skinning: {0}")]
    Skin(#[from] SkinError),
    /// A time given by the caller is not a finite number.
    #[error("time {index} ({time}) is not a finite number of seconds")]
    NonFiniteTime {
        /// Its position in the times given.
        index: usize,
        /// The value.
        time: f32,
    },
    /// A time given by the caller lies outside the clip.
    #[error("time {index} ({time} s) is outside clip {clip:?}, which runs from 0 to {duration} s")]
    TimeOutOfRange {
        /// Clip name.
        clip: String,
        /// Its position in the times given.
        index: usize,
        /// The value, seconds.
        time: f32,
        /// The clip's duration, seconds.
        duration: f32,
    },
    /// A caller's output buffer has the wrong size.
    #[error("the {what} buffer holds {got} floats; {expected} are needed")]
    BufferLength {
        /// Which buffer.
        what: &'static str,
        /// Floats needed.
        expected: usize,
        /// Floats given.
        got: usize,
    },
}

fn list(names: &[String]) -> String {
    if names.is_empty() {
        "(none)".into()
    } else {
        names.join(", ")
    }
}

/// Number of frames for a clip of `duration` seconds at `fps` (see the module docs).
pub fn frame_count(duration: f32, fps: f32) -> usize {
    let span = (f64::from(duration.max(0.0)) * f64::from(fps) - 1e-3).ceil();
    if span.is_finite() && span > 0.0 {
        (span as usize).saturating_add(1)
    } else {
        1
    }
}

/// Clip time of frame `i` of `n` (see the module docs).
pub fn frame_time(i: usize, n: usize, duration: f32, fps: f32) -> f32 {
    if i + 1 >= n && i > 0 {
        duration
    } else {
        (i as f64 / f64::from(fps)) as f32
    }
}

/// Checks a frame rate: finite, above 0, at most [`MAX_FPS`].
pub fn check_fps(fps: f32, hint: &'static str) -> Result<f32, BakeError> {
    if fps.is_finite() && fps > 0.0 && fps <= MAX_FPS {
        Ok(fps)
    } else {
        Err(BakeError::BadFps(fps, hint))
    }
}

/// One contiguous segment of the bake: layers played together, every layer at the same time.
struct Segment<'a> {
    clips: Vec<&'a Clip>,
    /// The layers in one animator, all active, with their weights and masks.
    animator: Animator,
    layers: Vec<ClipId>,
    first_frame: usize,
    frame_count: usize,
    duration: f32,
}

/// The meshes of a request with their LOD: the request's, or the default body's skinned meshes.
fn chosen_lods<'a>(
    asset: &'a Asset,
    req: &BakeRequest,
) -> Result<Vec<(usize, &'a Lod)>, BakeError> {
    let given = !req.meshes.is_empty();
    let meshes = if given {
        req.meshes.clone()
    } else {
        body::select(asset, &BodyChoice::Default)?
    };
    let mut out = Vec::with_capacity(meshes.len());
    let mut first_static = None;
    for &m in &meshes {
        let mesh = asset.meshes.get(m).ok_or(BakeError::NoMesh {
            mesh: m,
            count: asset.meshes.len(),
        })?;
        let lod = mesh.lods.get(req.lod).ok_or_else(|| BakeError::NoLod {
            lod: req.lod,
            mesh: mesh.name.clone(),
            last: mesh.lods.len().saturating_sub(1),
        })?;
        if !lod.is_skinned() {
            if given {
                return Err(BakeError::NotSkinned(mesh.name.clone()));
            }
            first_static.get_or_insert(mesh.name.clone());
            continue;
        }
        out.push((m, lod));
    }
    if out.is_empty() {
        return Err(match first_static {
            Some(name) => BakeError::NotSkinned(name),
            None => BakeError::NoMesh {
                mesh: 0,
                count: asset.meshes.len(),
            },
        });
    }
    Ok(out)
}

/// Bakes the request on a decoded asset.
pub fn bake(asset: &Asset, req: &BakeRequest) -> Result<Baked, BakeError> {
    let skeleton = asset.skeleton.as_ref().ok_or(BakeError::NoSkeleton)?;
    let lods = chosen_lods(asset, req)?;
    let orders = lods
        .iter()
        .map(|&(m, lod)| output_order(asset, req, m, lod))
        .collect::<Result<Vec<_>, _>>()?;
    let names: Vec<String> = asset.clips.iter().map(|c| c.name().to_string()).collect();
    let find = |name: &str| {
        asset
            .clips
            .iter()
            .find(|c| c.name() == name)
            .ok_or_else(|| BakeError::UnknownClip {
                name: name.to_string(),
                available: names.clone(),
            })
    };
    // Each group is the layers of one segment.
    let groups: Vec<Vec<(&Clip, Option<&str>, f32)>> = if !req.layers.is_empty() {
        if !req.clips.is_empty() {
            return Err(BakeError::ClipsAndLayers);
        }
        vec![req
            .layers
            .iter()
            .map(|l| Ok((find(&l.clip)?, l.mask.as_deref(), l.weight)))
            .collect::<Result<_, BakeError>>()?]
    } else if !req.clips.is_empty() {
        req.clips
            .iter()
            .map(|c| Ok(vec![(find(c)?, None, 1.0)]))
            .collect::<Result<_, BakeError>>()?
    } else {
        asset.clips.iter().map(|c| vec![(c, None, 1.0)]).collect()
    };
    let first = groups
        .first()
        .and_then(|g| g.first())
        .ok_or(BakeError::NoClips)?
        .0;
    let fps = match req.fps {
        Some(f) => check_fps(f, "")?,
        None => check_fps(
            first.sample_rate(),
            " (the clip's own sample rate; give --fps)",
        )?,
    };
    let mut segments = Vec::with_capacity(groups.len());
    let mut total = 0usize;
    let shared = Arc::new(skeleton.clone());
    for g in groups {
        let mut animator = Animator::new(shared.clone());
        let mut layers = Vec::with_capacity(g.len());
        let mut clips = Vec::with_capacity(g.len());
        for (clip, mask, weight) in g {
            let mask = match mask {
                Some(m) => Some(
                    asset
                        .mask(m)
                        .ok_or_else(|| BakeError::UnknownMask {
                            name: m.to_string(),
                            available: asset.masks.iter().map(|m| m.name.clone()).collect(),
                        })?
                        .per_joint(skeleton),
                ),
                None => None,
            };
            let layer = animator.add_clip(Arc::new(clip.clone()));
            animator.set_mask(layer, mask)?;
            animator.set_weight(layer, weight)?;
            animator.activate(layer)?;
            layers.push(layer);
            clips.push(clip);
        }
        let duration = clips.first().map_or(0.0, |c| c.duration());
        let n = frame_count(duration, fps);
        segments.push(Segment {
            clips,
            animator,
            layers,
            first_frame: total,
            frame_count: n,
            duration,
        });
        total = total
            .checked_add(n)
            .filter(|&t| t <= MAX_FRAMES)
            .ok_or(BakeError::TooManyFrames(total.saturating_add(n)))?;
    }
    let clips = segments
        .iter()
        .map(|s| ClipRange {
            name: s
                .clips
                .iter()
                .map(|c| c.name())
                .collect::<Vec<_>>()
                .join("+"),
            first_frame: s.first_frame,
            frame_count: s.frame_count,
            looping: s.clips.first().is_some_and(|c| c.looping()),
            duration: s.duration,
        })
        .collect();

    // Frame jobs: (segment, frame within segment).
    let jobs: Vec<(usize, usize)> = segments
        .iter()
        .enumerate()
        .flat_map(|(si, s)| (0..s.frame_count).map(move |i| (si, i)))
        .collect();
    // Each mesh's slice of a frame: (first output vertex, output vertices).
    let mut spans = Vec::with_capacity(lods.len());
    let mut out_n = 0usize;
    for ((_, lod), order) in lods.iter().zip(&orders) {
        let n = order.as_ref().map_or(lod.vertex_count(), Vec::len);
        spans.push((out_n, n));
        out_n += n;
    }
    let with_normals = lods.iter().all(|(_, l)| !l.normals.is_empty());
    let mut positions = vec![Vec3::ZERO; total * out_n];
    let mut normals = vec![Vec3::ZERO; if with_normals { total * out_n } else { 0 }];
    let normal_chunks: Vec<&mut [Vec3]> = if with_normals {
        normals.chunks_mut(out_n.max(1)).collect()
    } else {
        (0..total).map(|_| &mut [][..]).collect()
    };
    positions
        .par_chunks_mut(out_n.max(1))
        .zip(normal_chunks.into_par_iter())
        .zip(jobs.par_iter())
        .try_for_each(|((pos, nor), &(si, i))| -> Result<(), BakeError> {
            let s = &segments[si];
            let t = frame_time(i, s.frame_count, s.duration, fps);
            let palette = pose_frame(s, t)?;
            for (((_, lod), order), &(first, n)) in lods.iter().zip(&orders).zip(&spans) {
                let nv = lod.vertex_count();
                let pos = &mut pos[first..first + n];
                let nor = if with_normals {
                    &mut nor[first..first + n]
                } else {
                    &mut nor[..0]
                };
                match order {
                    None => {
                        skin_lod(&palette, lod, pos, nor)?;
                    }
                    Some(order) => {
                        let mut scratch_p = vec![Vec3::ZERO; nv];
                        let mut scratch_n = vec![Vec3::ZERO; if with_normals { nv } else { 0 }];
                        skin_lod(&palette, lod, &mut scratch_p, &mut scratch_n)?;
                        for (o, &v) in order.iter().enumerate() {
                            pos[o] = scratch_p[v as usize];
                            if with_normals {
                                nor[o] = scratch_n[v as usize];
                            }
                        }
                    }
                }
            }
            Ok(())
        })?;
    let mut bind_positions = Vec::with_capacity(out_n);
    let mut indices = Vec::new();
    let mut source_base = 0u32;
    for (((m, lod), order), &(first, _)) in lods.iter().zip(&orders).zip(&spans) {
        match (order, req.vertex_order) {
            (Some(order), VertexOrder::Source) => {
                let map = asset.source_vertex(*m).map(|s| &s.map[..]).unwrap_or(&[]);
                bind_positions.extend(order.iter().map(|&v| lod.positions[v as usize]));
                indices.extend(
                    lod.indices
                        .iter()
                        .map(|&i| source_base + map.get(i as usize).copied().unwrap_or(0)),
                );
                source_base += order.len() as u32;
            }
            _ => {
                bind_positions.extend_from_slice(&lod.positions);
                indices.extend(lod.indices.iter().map(|&i| first as u32 + i));
            }
        }
    }
    let meshes: Vec<usize> = lods.iter().map(|(m, _)| *m).collect();
    let mesh_names: Vec<String> = meshes
        .iter()
        .map(|&m| asset.meshes[m].name.clone())
        .collect();
    Ok(Baked {
        frames: Frames {
            vertex_count: out_n,
            frame_count: total,
            fps,
            positions,
            normals,
        },
        clips,
        bind_positions,
        indices,
        mesh_name: mesh_names.join(" + "),
        meshes,
        mesh_names,
    })
}

/// Skins LOD `lod` of mesh `mesh` through `clip` alone at each of `times` (seconds, finite; the
/// runtime wraps a looping clip's time and clamps another's) into `out`: per time, every vertex's
/// position `x y z` in the LOD's own (split) vertex order, `times.len() * vertices * 3` floats.
///
/// Each frame is posed and skinned exactly as [`bake`] does it (a fresh copy of a one-layer
/// animator, [`Animator::evaluate_palette`], [`skin_lod`]), so at [`frame_time`]s the positions are
/// the bits `sinew bake --clip` writes. Frames run in parallel with rayon; the result is the same
/// for any thread count.
pub fn skin_into(
    skeleton: &Arc<Skeleton>,
    clip: &Arc<Clip>,
    mesh: &Mesh,
    lod: usize,
    times: &[f32],
    out: &mut [f32],
) -> Result<(), BakeError> {
    let lod_data = mesh.lods.get(lod).ok_or_else(|| BakeError::NoLod {
        lod,
        mesh: mesh.name.clone(),
        last: mesh.lods.len().saturating_sub(1),
    })?;
    if !lod_data.is_skinned() {
        return Err(BakeError::NotSkinned(mesh.name.clone()));
    }
    if let Some(index) = times.iter().position(|t| !t.is_finite()) {
        return Err(BakeError::NonFiniteTime {
            index,
            time: times[index],
        });
    }
    let nv = lod_data.vertex_count();
    if out.len() != times.len() * nv * 3 {
        return Err(BakeError::BufferLength {
            what: "positions",
            expected: times.len() * nv * 3,
            got: out.len(),
        });
    }
    if nv == 0 {
        return Ok(());
    }
    let mut animator = Animator::new(skeleton.clone());
    let layer = animator.add_clip(clip.clone());
    animator.set_mask(layer, None)?;
    animator.set_weight(layer, 1.0)?;
    animator.activate(layer)?;
    let segment = Segment {
        clips: vec![clip.as_ref()],
        animator,
        layers: vec![layer],
        first_frame: 0,
        frame_count: times.len(),
        duration: clip.duration(),
    };
    out.par_chunks_mut(nv * 3)
        .zip(times.par_iter())
        .try_for_each_init(
            || {
                let normals = if lod_data.normals.is_empty() { 0 } else { nv };
                (vec![Vec3::ZERO; nv], vec![Vec3::ZERO; normals])
            },
            |(positions, normals), (frame, &t)| -> Result<(), BakeError> {
                // Normals are skinned too when the LOD has them, as `bake` does.
                let palette = pose_frame(&segment, t)?;
                skin_lod(&palette, lod_data, positions, normals)?;
                for (o, p) in frame.chunks_exact_mut(3).zip(positions.iter()) {
                    o.copy_from_slice(&p.to_array());
                }
                Ok(())
            },
        )
}

/// For source order, the LOD-0 vertex each source vertex takes its values from.
fn output_order(
    asset: &Asset,
    req: &BakeRequest,
    mesh: usize,
    lod: &Lod,
) -> Result<Option<Vec<u32>>, BakeError> {
    if req.vertex_order == VertexOrder::Split {
        return Ok(None);
    }
    if req.lod != 0 {
        return Err(BakeError::SourceOrder(format!(
            "only LOD 0 has a source vertex order (LOD {} was asked for)",
            req.lod
        )));
    }
    let map = asset.source_vertex(mesh).ok_or_else(|| {
        BakeError::SourceOrder("the file has no source-vertex map for this mesh".into())
    })?;
    if map.map.len() != lod.vertex_count() {
        return Err(BakeError::SourceOrder(
            "the map does not match the mesh".into(),
        ));
    }
    let mut first = vec![u32::MAX; map.source_vertex_count as usize];
    for (v, &s) in map.map.iter().enumerate() {
        if let Some(slot) = first.get_mut(s as usize) {
            if *slot == u32::MAX {
                *slot = v as u32;
            }
        }
    }
    if let Some(s) = first.iter().position(|&v| v == u32::MAX) {
        return Err(BakeError::SourceOrder(format!(
            "source vertex {s} is used by no triangle vertex, so it has no skinned position"
        )));
    }
    Ok(Some(first))
}

/// Poses one frame at clip time `t`: a fresh copy of the segment's animator with every layer at `t`,
/// and the skinning palette of that pose.
fn pose_frame(segment: &Segment<'_>, t: f32) -> Result<Vec<Mat4>, BakeError> {
    let mut animator = segment.animator.clone();
    for &layer in &segment.layers {
        animator.set_time(layer, t)?;
    }
    let n = animator.skeleton().len();
    let mut models = vec![Mat4::IDENTITY; n];
    let mut palette = vec![Mat4::IDENTITY; n];
    animator
        .evaluate_palette(&mut models, &mut palette)
        .map_err(|e| match e {
            AnimatorError::Clip(source) => BakeError::Clip {
                clip: segment
                    .clips
                    .iter()
                    .map(|c| c.name())
                    .collect::<Vec<_>>()
                    .join("+"),
                source,
            },
            other => BakeError::Animator(other),
        })?;
    Ok(palette)
}

/// The mesh as Wavefront OBJ: `v` lines (bind-pose positions in the bake's vertex order) and `f` lines
/// (1-based), nothing else, so that importers keep the vertex order.
pub fn obj(baked: &Baked) -> String {
    use std::fmt::Write;
    let mut s = format!(
        "# sinew bake: mesh {:?}, {} vertices in cache order\no {}\n",
        baked.mesh_name,
        baked.bind_positions.len(),
        if baked.mesh_name.is_empty() {
            "mesh"
        } else {
            &baked.mesh_name
        }
        .replace(char::is_whitespace, "_")
    );
    for p in &baked.bind_positions {
        let _ = writeln!(s, "v {:?} {:?} {:?}", p.x, p.y, p.z);
    }
    for t in baked.indices.chunks_exact(3) {
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}
