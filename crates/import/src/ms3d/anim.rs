//! MS3D keys as Milkshape's viewer evaluates them, resampled into linear scene curves, and the choice
//! of how position keys compose with the bind pose.

use super::convention::{euler_to_quat, Influences};
use super::parse::{File, Joint, Key};
use crate::{ImportError, PositionKeyRule};
use sinew_core::glam::{Mat4, Quat, Vec3};
use sinew_core::{Curve, JointIndex, Skeleton, TrackCurves};
use sinew_scene::{Diagnostic, SceneClip};

/// Most Milkshape frames a clip is resampled at.
const MAX_FRAMES: f64 = 1_048_576.0;
/// Most (sample time x animated joint) values a clip may hold.
const MAX_SAMPLES: usize = 1 << 22;
/// Frame rate used when the file's is not a positive, finite number.
const FALLBACK_FPS: f32 = 24.0;

/// Where a time falls among sorted key times, following the viewer: before the first key the first
/// holds, at or after the last key the last holds, else the pair `i, i+1` with `t[i] <= t < t[i+1]`.
enum Span {
    First,
    Last,
    Between(usize, f32),
}

fn locate(times: &[f32], t: f32) -> Span {
    let n = times.len();
    if n == 0 || t < times[0] {
        return Span::First;
    }
    if t >= times[n - 1] {
        return Span::Last;
    }
    let i = times.partition_point(|&x| x <= t).saturating_sub(1);
    match (times.get(i), times.get(i + 1)) {
        (Some(&a), Some(&b)) if b > a => Span::Between(i, (t - a) / (b - a)),
        _ => Span::Last,
    }
}

/// The key curves of one joint as the viewer evaluates them: rotation keys converted to quaternions
/// and slerped, position keys Hermite-interpolated with the viewer's looped tangents.
#[derive(Debug, Clone, Default)]
pub struct ViewerCurves {
    rot_times: Vec<f32>,
    rot: Vec<Quat>,
    pos_times: Vec<f32>,
    pos: Vec<Vec3>,
    tangent_in: Vec<Vec3>,
    tangent_out: Vec<Vec3>,
}

fn sorted(keys: &[Key]) -> Vec<Key> {
    let mut k = keys.to_vec();
    k.sort_by(|a, b| a.time.total_cmp(&b.time));
    k
}

impl ViewerCurves {
    /// The curves of a joint (keys sorted by time if the file did not).
    pub fn new(joint: &Joint) -> Self {
        let rk = sorted(&joint.rotation_keys);
        let pk = sorted(&joint.position_keys);
        let pos: Vec<Vec3> = pk.iter().map(|k| Vec3::from_array(k.value)).collect();
        let pos_times: Vec<f32> = pk.iter().map(|k| k.time).collect();
        let n = pos.len();
        let mut tangent_in = vec![Vec3::ZERO; n];
        let mut tangent_out = vec![Vec3::ZERO; n];
        if n > 2 {
            for k in 0..n {
                let k0 = if k == 0 { n - 1 } else { k - 1 };
                let k2 = if k + 1 >= n { 0 } else { k + 1 };
                let tangent = pos[k2] - pos[k0];
                let dt1 = pos_times[k] - pos_times[k0];
                let dt2 = pos_times[k2] - pos_times[k];
                let dt = dt1 + dt2;
                if dt != 0.0 && dt.is_finite() {
                    tangent_in[k] = tangent * (dt1 / dt);
                    tangent_out[k] = tangent * (dt2 / dt);
                }
            }
        }
        Self {
            rot_times: rk.iter().map(|k| k.time).collect(),
            rot: rk.iter().map(|k| euler_to_quat(k.value)).collect(),
            pos_times,
            pos,
            tangent_in,
            tangent_out,
        }
    }

    /// True when the joint has no keys at all.
    pub fn is_empty(&self) -> bool {
        self.rot.is_empty() && self.pos.is_empty()
    }

    /// The key rotation (relative to the bind rotation) at file time `t`, seconds.
    pub fn rotation(&self, t: f32) -> Quat {
        match (self.rot.first(), self.rot.last()) {
            (Some(&first), Some(&last)) => match locate(&self.rot_times, t) {
                Span::First => first,
                Span::Last => last,
                Span::Between(i, a) => match (self.rot.get(i), self.rot.get(i + 1)) {
                    (Some(&q0), Some(&q1)) => q0.slerp(q1, a),
                    _ => last,
                },
            },
            _ => Quat::IDENTITY,
        }
    }

    /// The key position at file time `t`, seconds.
    pub fn position(&self, t: f32) -> Vec3 {
        let (Some(&first), Some(&last)) = (self.pos.first(), self.pos.last()) else {
            return Vec3::ZERO;
        };
        match locate(&self.pos_times, t) {
            Span::First => first,
            Span::Last => last,
            Span::Between(i, s) => {
                let (Some(&p0), Some(&p1), Some(&m0), Some(&m1)) = (
                    self.pos.get(i),
                    self.pos.get(i + 1),
                    self.tangent_out.get(i),
                    self.tangent_in.get(i + 1),
                ) else {
                    return last;
                };
                let s2 = s * s;
                let s3 = s2 * s;
                let h1 = 2.0 * s3 - 3.0 * s2 + 1.0;
                let h2 = -2.0 * s3 + 3.0 * s2;
                let h3 = s3 - 2.0 * s2 + s;
                let h4 = s3 - s2;
                p0 * h1 + m0 * h3 + p1 * h2 + m1 * h4
            }
        }
    }

    /// Largest key time, if any.
    fn last_time(&self) -> Option<f32> {
        let a = self.rot_times.last().copied();
        let b = self.pos_times.last().copied();
        match (a, b) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        }
    }
}

/// Measurements of one reading of the position keys, each averaged over the clip's sample times and
/// relative to the model's size (the bind-pose bounding-box diagonal of mesh and joints).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PositionKeyFigures {
    /// Mean distance the root joints leave their bind height (y; the largest root at each time).
    pub root_height_travel: f32,
    /// Mean depth the lowest skinned vertex sinks below its bind height.
    pub floor_sink: f32,
    /// Mean distance the keyed non-root joints move off the lines of their bones (the largest
    /// joint at each time).
    pub detachment: f32,
    /// Mean growth of the skinned mesh's bounding-box diagonal.
    pub bbox_swell: f32,
    /// Largest distance between a joint's position under the two readings (filled in by the
    /// comparison; the same for both readings).
    pub max_gap: f32,
}

impl PositionKeyFigures {
    /// The sum of the measurements: lower is more plausible.
    pub fn score(&self) -> f32 {
        self.root_height_travel + self.floor_sink + self.detachment + self.bbox_swell
    }
}

struct Anim<'a> {
    file: &'a File,
    skeleton: &'a Skeleton,
    /// For each skeleton joint, its file joint index (`usize::MAX` for the static joint the importer
    /// adds for vertices without a joint: it has no keys and keeps its bind pose).
    file_of: Vec<usize>,
    curves: Vec<ViewerCurves>,
    r0: Vec<Quat>,
}

impl Anim<'_> {
    /// Local transforms in skeleton order at file time `t` under `rule` (Viewer or Parent).
    fn locals(&self, t: f32, rule: PositionKeyRule, out: &mut Vec<Mat4>) {
        out.clear();
        for (s, &f) in self.file_of.iter().enumerate() {
            let bind = self.skeleton.bind_local()[s];
            let Some(c) = self.curves.get(f) else {
                out.push(bind.to_mat4());
                continue;
            };
            if c.is_empty() {
                out.push(bind.to_mat4());
                continue;
            }
            let (tr, rot) = self.local_at(f, t, rule);
            out.push(Mat4::from_rotation_translation(rot, tr));
        }
    }

    fn local_at(&self, f: usize, t: f32, rule: PositionKeyRule) -> (Vec3, Quat) {
        let j = &self.file.joints[f];
        let c = &self.curves[f];
        let r0 = self.r0[f];
        let t0 = Vec3::from_array(j.position);
        let p = c.position(t);
        let tr = match rule {
            PositionKeyRule::Parent => t0 + p,
            _ => t0 + r0 * p,
        };
        (tr, (r0 * c.rotation(t)).normalize())
    }

    fn globals(&self, locals: &[Mat4], out: &mut Vec<Mat4>) {
        out.clear();
        for (s, l) in locals.iter().enumerate() {
            let g = match self.skeleton.parents()[s] {
                Some(p) => out.get(p as usize).copied().unwrap_or(Mat4::IDENTITY) * *l,
                None => *l,
            };
            out.push(g);
        }
    }
}

/// Builds the clip, or `None` when no joint has keys.
#[allow(clippy::too_many_arguments)]
pub(crate) fn build_clip(
    file_name: &str,
    file: &File,
    skeleton: &Skeleton,
    new_index: &[JointIndex],
    influences: Option<&[Influences]>,
    rule: PositionKeyRule,
    diagnostics: &mut Vec<Diagnostic>,
) -> Result<Option<SceneClip>, ImportError> {
    for j in &file.joints {
        if j.rotation_keys
            .iter()
            .chain(&j.position_keys)
            .any(|k| !k.time.is_finite() || !k.value.iter().all(|v| v.is_finite()))
        {
            return Err(ImportError::at_offset(
                file_name,
                "joints",
                j.offset as u64,
                format!("joint {:?} has a non-finite key", j.name),
            ));
        }
    }
    let curves: Vec<ViewerCurves> = file.joints.iter().map(ViewerCurves::new).collect();
    let Some(last_key) = curves
        .iter()
        .filter_map(ViewerCurves::last_time)
        .reduce(f32::max)
    else {
        return Ok(None);
    };
    let mut fps = file.animation_fps;
    if !(fps.is_finite() && fps > 0.0 && fps <= 10_000.0) {
        diagnostics.push(Diagnostic::warning(
            "ms3d-bad-fps",
            format!("animationFps is {fps}; {FALLBACK_FPS} frames per second are used"),
        ));
        fps = FALLBACK_FPS;
    }
    let fps64 = fps as f64;
    let key_frames = (last_key as f64 * fps64 - 1e-3).ceil().max(1.0);
    if key_frames > MAX_FRAMES {
        return Err(ImportError::in_section(
            file_name,
            "joints",
            format!(
                "the last key is at {last_key} s, frame {key_frames} at {fps} fps: more than {MAX_FRAMES} frames"
            ),
        ));
    }
    let key_frames = key_frames as u32;
    let frames = if file.total_frames >= 1 {
        (file.total_frames as u32).min(key_frames)
    } else {
        key_frames
    };
    if frames < key_frames {
        diagnostics.push(
            Diagnostic::warning(
                "ms3d-keys-beyond-timeline",
                format!("keys run to frame {key_frames} but the timeline has {frames} frames; later keys were cut off"),
            )
            .with_figure("total_frames", frames as f64)
            .with_figure("last_key_frame", key_frames as f64),
        );
    }
    // Sample times, file seconds: every frame, plus every key time strictly inside the timeline.
    let start = 1.0 / fps64;
    let end = frames as f64 / fps64;
    let mut times: Vec<f64> = (1..=frames).map(|k| k as f64 / fps64).collect();
    for c in &curves {
        for &t in c.rot_times.iter().chain(&c.pos_times) {
            let t = t as f64;
            if t > start && t < end {
                let nearest = (t * fps64).round() / fps64;
                if (t - nearest).abs() > 1e-5 {
                    times.push(t);
                }
            }
        }
    }
    times.sort_by(f64::total_cmp);
    // Clip times: strictly increasing f32 from 0.
    let mut file_times: Vec<f32> = Vec::with_capacity(times.len());
    let mut clip_times: Vec<f32> = Vec::with_capacity(times.len());
    for &t in &times {
        let ct = (t - start) as f32;
        if clip_times.last().is_some_and(|&l| ct <= l) {
            continue;
        }
        clip_times.push(ct);
        file_times.push(t as f32);
    }
    let animated: Vec<usize> = (0..file.joints.len())
        .filter(|&f| !curves[f].is_empty())
        .collect();
    if clip_times.len().saturating_mul(animated.len().max(1)) > MAX_SAMPLES {
        return Err(ImportError::in_section(
            file_name,
            "joints",
            format!(
                "{} sample times for {} animated joints is more than {MAX_SAMPLES} samples",
                clip_times.len(),
                animated.len()
            ),
        ));
    }

    let mut file_of = vec![usize::MAX; skeleton.len()];
    for (f, &s) in new_index.iter().enumerate() {
        if let Some(slot) = file_of.get_mut(s as usize) {
            *slot = f;
        }
    }
    let anim = Anim {
        file,
        skeleton,
        file_of,
        r0: file
            .joints
            .iter()
            .map(|j| euler_to_quat(j.rotation))
            .collect(),
        curves,
    };

    let chosen = decide(&anim, influences, &file_times, rule, diagnostics);

    let mut tracks = Vec::with_capacity(animated.len());
    for &f in &animated {
        let mut tv = Vec::with_capacity(file_times.len());
        let mut rv = Vec::with_capacity(file_times.len());
        for &t in &file_times {
            let (tr, rot) = anim.local_at(f, t, chosen);
            tv.push(tr);
            rv.push(rot);
        }
        tracks.push(TrackCurves {
            joint: file.joints[f].name.clone(),
            translation: Curve::new(clip_times.clone(), tv),
            rotation: Curve::new(clip_times.clone(), rv),
            scale: Curve::default(),
        });
    }
    let duration = clip_times.last().copied().unwrap_or(0.0);
    let name = std::path::Path::new(file_name)
        .file_stem()
        .and_then(|s| s.to_str())
        .filter(|s| !s.is_empty())
        .unwrap_or("default")
        .to_string();
    Ok(Some(SceneClip {
        name,
        duration,
        sample_rate: fps,
        looping: false,
        additive: false,
        tracks,
    }))
}

fn rule_name(rule: PositionKeyRule) -> &'static str {
    match rule {
        PositionKeyRule::Viewer => "viewer",
        PositionKeyRule::Parent => "parent",
        PositionKeyRule::Auto => "auto",
    }
}

/// True when some joint with a bind rotation has a position key the rotation moves.
fn readings_differ(anim: &Anim<'_>, size: f32) -> bool {
    let eps = 1e-5 * size.max(1.0);
    anim.file.joints.iter().enumerate().any(|(f, j)| {
        let r0 = anim.r0[f];
        j.position_keys.iter().any(|k| {
            let p = Vec3::from_array(k.value);
            (r0 * p - p).length() > eps
        })
    })
}

/// Below this margin (`|score difference| / larger score`) the two readings are too close to call:
/// `auto` keeps Milkshape's own viewer rule, with a warning.
const SMALL_MARGIN: f32 = 0.3;

/// The reading `rule` picks from the two scores (lower is more plausible), the other, and the margin.
/// `auto` takes the parent reading only when its score is lower by at least [`SMALL_MARGIN`]: on a
/// near tie the format's own (viewer) rule wins.
fn choose(rule: PositionKeyRule, sv: f32, sp: f32) -> (PositionKeyRule, PositionKeyRule, f32) {
    let hi = sv.max(sp);
    let margin = if hi > 0.0 { (sv - sp).abs() / hi } else { 0.0 };
    let (v, p) = (PositionKeyRule::Viewer, PositionKeyRule::Parent);
    let pair = match rule {
        PositionKeyRule::Auto if sp < sv && margin >= SMALL_MARGIN => (p, v),
        PositionKeyRule::Parent => (p, v),
        _ => (v, p),
    };
    (pair.0, pair.1, margin)
}

fn decide(
    anim: &Anim<'_>,
    influences: Option<&[Influences]>,
    times: &[f32],
    rule: PositionKeyRule,
    diagnostics: &mut Vec<Diagnostic>,
) -> PositionKeyRule {
    let ctx = Measure::new(anim, influences);
    let code = "ms3d-position-keys";
    let gap = if readings_differ(anim, ctx.size) {
        max_gap(anim, times, ctx.size)
    } else {
        0.0
    };
    if gap < AGREE_GAP {
        let has_pos = anim.file.joints.iter().any(|j| !j.position_keys.is_empty());
        if has_pos {
            let message = if gap > 0.0 {
                format!(
                    "the viewer and parent readings of the position keys place every joint within {:.3}% of the model size of each other: no decision was needed (viewer reading used)",
                    gap * 100.0
                )
            } else {
                "no joint with a bind rotation has non-zero position keys: the viewer and parent readings agree, no decision was needed".to_string()
            };
            diagnostics.push(Diagnostic::info(code, message).with_figure("max_gap", gap as f64));
        }
        return if rule == PositionKeyRule::Auto {
            PositionKeyRule::Viewer
        } else {
            rule
        };
    }
    let mut viewer = ctx.measure(anim, times, PositionKeyRule::Viewer);
    let mut parent = ctx.measure(anim, times, PositionKeyRule::Parent);
    viewer.max_gap = gap;
    parent.max_gap = gap;
    let (sv, sp) = (viewer.score(), parent.score());
    let (chosen, other, margin) = choose(rule, sv, sp);
    let formula = |r| match r {
        PositionKeyRule::Parent => "t0 + tkey",
        _ => "t0 + R0*tkey",
    };
    let (message, warn) = if rule == PositionKeyRule::Auto {
        let warn = margin < SMALL_MARGIN;
        let kept = warn && sp < sv;
        (
            format!(
                "position keys on rotated joints read as {} ({}): implausibility score {:.4} against {:.4} for {}{}; override with --ms3d-position-keys {}",
                rule_name(chosen),
                formula(chosen),
                if chosen == PositionKeyRule::Viewer { sv } else { sp },
                if chosen == PositionKeyRule::Viewer { sp } else { sv },
                rule_name(other),
                if kept {
                    " (small margin: Milkshape's own viewer rule is kept over the slightly lower score)"
                } else if warn {
                    " (small margin)"
                } else {
                    ""
                },
                rule_name(other),
            ),
            warn,
        )
    } else {
        (
            format!(
                "position keys on rotated joints read as {} ({}) as requested; auto would score {:.4} for viewer and {:.4} for parent",
                rule_name(chosen),
                formula(chosen),
                sv,
                sp
            ),
            false,
        )
    };
    let mut d = if warn {
        Diagnostic::warning(code, message)
    } else {
        Diagnostic::info(code, message)
    };
    for (prefix, f) in [("viewer", viewer), ("parent", parent)] {
        d = d
            .with_figure(
                format!("{prefix}_root_height_travel"),
                f.root_height_travel as f64,
            )
            .with_figure(format!("{prefix}_floor_sink"), f.floor_sink as f64)
            .with_figure(format!("{prefix}_detachment"), f.detachment as f64)
            .with_figure(format!("{prefix}_bbox_swell"), f.bbox_swell as f64)
            .with_figure(format!("{prefix}_score"), f.score() as f64);
    }
    d = d
        .with_figure("max_gap", gap as f64)
        .with_figure("margin", margin as f64);
    diagnostics.push(d);
    chosen
}

/// Largest distance, relative to the model size, between a joint's model-space position under the
/// two readings over the sampled times.
fn max_gap(anim: &Anim<'_>, times: &[f32], size: f32) -> f32 {
    let step = times.len().div_ceil(MAX_MEASURE_TIMES).max(1);
    let (mut lv, mut lp, mut gv, mut gp) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut gap = 0.0f32;
    for &t in times.iter().step_by(step) {
        anim.locals(t, PositionKeyRule::Viewer, &mut lv);
        anim.locals(t, PositionKeyRule::Parent, &mut lp);
        anim.globals(&lv, &mut gv);
        anim.globals(&lp, &mut gp);
        for (a, b) in gv.iter().zip(&gp) {
            gap = gap.max((a.w_axis - b.w_axis).truncate().length() / size);
        }
    }
    gap
}

/// Joint gaps below this fraction of the model size count as the readings agreeing.
const AGREE_GAP: f32 = 0.005;

/// What the plausibility measurements need: a sample of skinned vertices and the bind figures.
struct Measure {
    verts: Vec<(Vec3, [u16; 4], [f32; 4])>,
    size: f32,
    bind_min_y: f32,
    bind_diag: f32,
    bind_root_y: Vec<f32>,
    inverse_bind: Vec<Mat4>,
}

const MAX_MEASURE_VERTICES: usize = 4096;
const MAX_MEASURE_TIMES: usize = 256;

impl Measure {
    fn new(anim: &Anim<'_>, influences: Option<&[Influences]>) -> Self {
        let skel = anim.skeleton;
        let inverse_bind = skel.inverse_bind().to_vec();
        let bind_globals: Vec<Vec3> = inverse_bind
            .iter()
            .map(|m| m.inverse().transform_point3(Vec3::ZERO))
            .collect();
        let mut verts = Vec::new();
        if let Some(inf) = influences {
            let n = anim.file.vertices.len();
            let step = n.div_ceil(MAX_MEASURE_VERTICES).max(1);
            for (i, v) in anim.file.vertices.iter().enumerate().step_by(step) {
                let p = Vec3::from_array(v.position);
                if let (true, Some(&(j, w))) = (p.is_finite(), inf.get(i)) {
                    verts.push((p, j, w));
                }
            }
        }
        let points: Vec<Vec3> = if verts.is_empty() {
            bind_globals.clone()
        } else {
            verts.iter().map(|v| v.0).collect()
        };
        let (mn, mx) = bounds(points.iter().copied());
        let mut all = points.clone();
        all.extend(bind_globals.iter().copied());
        let (amn, amx) = bounds(all.into_iter());
        let size = (amx - amn).length().max(1e-6);
        let bind_root_y = (0..skel.len())
            .map(|s| bind_globals.get(s).map_or(0.0, |p| p.y))
            .collect();
        Self {
            verts,
            size,
            bind_min_y: mn.y,
            bind_diag: (mx - mn).length().max(1e-6),
            bind_root_y,
            inverse_bind,
        }
    }

    fn measure(&self, anim: &Anim<'_>, times: &[f32], rule: PositionKeyRule) -> PositionKeyFigures {
        let skel = anim.skeleton;
        let step = times.len().div_ceil(MAX_MEASURE_TIMES).max(1);
        let mut locals = Vec::with_capacity(skel.len());
        let mut globals = Vec::with_capacity(skel.len());
        let mut fig = PositionKeyFigures::default();
        // Each keyed non-root joint's bone axes in its parent's space: towards itself from the
        // parent (t0) and along its own bone towards each child (R0 * child offset).
        let mut axes: Vec<Vec<Vec3>> = vec![Vec::new(); skel.len()];
        for s in 0..skel.len() {
            let b = skel.bind_local()[s];
            if b.translation.length() > 1e-6 {
                axes[s].push(b.translation.normalize());
            }
            if let Some(p) = skel.parents()[s] {
                let d = skel.bind_local()[p as usize].rotation * b.translation;
                if d.length() > 1e-6 {
                    axes[p as usize].push(d.normalize());
                }
            }
        }
        let mut count = 0usize;
        for &t in times.iter().step_by(step) {
            count += 1;
            anim.locals(t, rule, &mut locals);
            anim.globals(&locals, &mut globals);
            let (mut travel, mut detach) = (0.0f32, 0.0f32);
            for s in 0..skel.len() {
                if skel.parents()[s].is_none() {
                    let y = globals[s].w_axis.y;
                    let dy = (y - self.bind_root_y[s]).abs();
                    travel = travel.max(dy / self.size);
                } else if anim
                    .curves
                    .get(anim.file_of[s])
                    .is_some_and(|c| !c.pos.is_empty())
                {
                    let bind_t = skel.bind_local()[s].translation;
                    let d = locals[s].w_axis.truncate() - bind_t;
                    let off = axes[s]
                        .iter()
                        .map(|a| (d - a * d.dot(*a)).length())
                        .fold(d.length(), f32::min);
                    detach = detach.max(off / self.size);
                }
            }
            fig.root_height_travel += travel;
            fig.detachment += detach;
            let skin: Vec<Mat4> = globals
                .iter()
                .zip(&self.inverse_bind)
                .map(|(g, ib)| *g * *ib)
                .collect();
            let posed: Vec<Vec3> = if self.verts.is_empty() {
                globals.iter().map(|g| g.w_axis.truncate()).collect()
            } else {
                self.verts
                    .iter()
                    .map(|(p, j, w)| {
                        let mut acc = Vec3::ZERO;
                        for k in 0..4 {
                            if w[k] > 0.0 {
                                let m = skin.get(j[k] as usize).copied().unwrap_or(Mat4::IDENTITY);
                                acc += m.transform_point3(*p) * w[k];
                            }
                        }
                        acc
                    })
                    .collect()
            };
            let (mn, mx) = bounds(posed.into_iter());
            fig.floor_sink += (self.bind_min_y - mn.y).max(0.0) / self.size;
            fig.bbox_swell += ((mx - mn).length() / self.bind_diag - 1.0).max(0.0);
        }
        let n = count.max(1) as f32;
        fig.root_height_travel /= n;
        fig.floor_sink /= n;
        fig.detachment /= n;
        fig.bbox_swell /= n;
        fig
    }
}

fn bounds(points: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    let mut mn = Vec3::splat(f32::INFINITY);
    let mut mx = Vec3::splat(f32::NEG_INFINITY);
    for p in points {
        mn = mn.min(p);
        mx = mx.max(p);
    }
    if mn.x > mx.x {
        (Vec3::ZERO, Vec3::ZERO)
    } else {
        (mn, mx)
    }
}

#[cfg(test)]
mod choose_tests {
    use crate::ms3d::anim::{choose, PositionKeyRule as R};

    #[test]
    fn a_near_tie_keeps_the_viewer_rule_and_a_clear_win_does_not() {
        // Dophi.ms3d's scores: parent 0.0285, viewer 0.0303 (margin 0.06): viewer.
        let (chosen, other, margin) = choose(R::Auto, 0.0303, 0.0285);
        assert_eq!((chosen, other), (R::Viewer, R::Parent));
        assert!((margin - 0.0594).abs() < 1e-3, "{margin}");
        // A clear parent win (the Biped root-motion fixture's kind): parent.
        assert_eq!(choose(R::Auto, 0.5, 0.1).0, R::Parent);
        // Exactly at the margin counts as clear.
        assert_eq!(choose(R::Auto, 1.0, 0.7).0, R::Parent);
        assert_eq!(choose(R::Auto, 0.1, 0.5).0, R::Viewer);
        // Explicit rules are obeyed whatever the scores.
        assert_eq!(choose(R::Parent, 0.1, 0.5).0, R::Parent);
        assert_eq!(choose(R::Viewer, 0.5, 0.1).0, R::Viewer);
    }
}
