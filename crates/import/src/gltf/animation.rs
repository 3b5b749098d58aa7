//! Animations to clips: channels of the skeleton's joints resampled as linear keys, per joint name.

use super::anim::Interp;
use super::document::{at, floats, Loaded};
use super::skin::{decompose, Graph, Rig};
use crate::ImportError;
use glam::{Mat4, Quat, Vec3};
use rayon::prelude::*;
use sinew_core::{Curve, TrackCurves, Transform};
use sinew_scene::{Diagnostic, Scene, SceneClip};
use std::collections::{BTreeMap, HashSet};

/// Which property a channel drives.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub(super) enum Prop {
    T,
    R,
    S,
}

/// Animations with fewer keys than this (all channels) build their curves on the calling thread:
/// handing a few microseconds of work to the pool costs more than it saves.
const PARALLEL_KEYS: usize = 512;

/// One channel's keys, read and checked, before its curve is built.
struct Channel {
    node: usize,
    prop: Prop,
    interp: Interp,
    times: Vec<f32>,
    /// The sampler's output (three values per key with cubic interpolation).
    values: Keys,
}

/// A channel's output values.
enum Keys {
    Rotations(Vec<Quat>),
    Vectors(Vec<Vec3>),
}

/// A channel's curve and its largest measured deviation from the glTF interpolation.
enum Built {
    Rotation(Curve<Quat>, f32),
    Vector(Curve<Vec3>, f32),
}

impl Channel {
    /// Of a rotation channel, the interval with the largest bound on its error among those whose
    /// first pieces certainly suffice, and that bound ([`super::anim::largest_certain`]).
    fn largest_certain(&self) -> Option<(f32, usize)> {
        match &self.values {
            Keys::Rotations(q) => super::anim::largest_certain(&self.times, q, self.interp),
            Keys::Vectors(_) => None,
        }
    }

    /// [`super::anim::certain_interval_error`] of a rotation channel's interval ending at key `k`.
    fn certain_interval_error(&self, k: usize) -> Option<f32> {
        match &self.values {
            Keys::Rotations(q) => {
                super::anim::certain_interval_error(&self.times, q, self.interp, k)
            }
            Keys::Vectors(_) => None,
        }
    }

    /// The channel's curve; `known`: a rotation error this import measured already
    /// ([`super::anim::rotation_curve_known`]).
    fn curve(&self, known: f32) -> Built {
        match &self.values {
            Keys::Rotations(q) => {
                let (c, e) = super::anim::rotation_curve_known(&self.times, q, self.interp, known);
                Built::Rotation(c, e)
            }
            Keys::Vectors(v) => {
                let (c, e) = super::anim::vector_curve(&self.times, v, self.interp);
                Built::Vector(c, e)
            }
        }
    }
}

/// Value of a linear curve at `t`, clamped at the ends (the runtime's rule).
pub(super) fn curve_at<T: Copy>(c: &Curve<T>, t: f32, lerp: impl Fn(T, T, f32) -> T) -> Option<T> {
    let k = c.times.partition_point(|&x| x <= t);
    if c.values.is_empty() {
        return None;
    }
    if k == 0 {
        return Some(c.values[0]);
    }
    if k >= c.times.len() {
        return c.values.last().copied();
    }
    let (t0, t1) = (c.times[k - 1], c.times[k]);
    let a = (t - t0) / (t1 - t0);
    Some(if a <= 0.0 {
        c.values[k - 1]
    } else {
        lerp(c.values[k - 1], c.values[k], a)
    })
}

#[allow(clippy::too_many_lines)]
pub(super) fn import_animations(
    file: &str,
    l: &Loaded,
    g: &Graph,
    rig: &Rig,
    scene: &mut Scene,
) -> Result<(), ImportError> {
    let mut used_names = HashSet::new();
    let mut worst_rot = 0.0f32;
    let mut worst_vec = 0.0f32;
    for a in l.doc.animations() {
        let ai = a.index();
        let mut name = match a.name() {
            Some(s) if !s.is_empty() => s.to_string(),
            _ => format!("animation{ai}"),
        };
        if !used_names.insert(name.clone()) {
            name = format!("{name}#{ai}");
            used_names.insert(name.clone());
        }
        let mut per_node: BTreeMap<usize, TrackCurves> = BTreeMap::new();
        let mut duration = 0.0f32;
        let mut intervals: Vec<f32> = Vec::new();
        let mut skipped_weights = 0;
        let mut not_joint: Vec<String> = Vec::new();
        let mut seen: HashSet<(usize, Prop)> = HashSet::new();
        let mut channels: Vec<Channel> = Vec::new();
        let mut keys = 0usize;
        for ch in a.channels() {
            let ci = ch.index();
            let cp = format!("animations[{ai}].channels[{ci}]");
            let sampler = ch.sampler();
            let sp = format!("animations[{ai}].samplers[{}]", sampler.index());
            let interp = match sampler.interpolation() {
                gltf::animation::Interpolation::Linear => Interp::Linear,
                gltf::animation::Interpolation::Step => Interp::Step,
                gltf::animation::Interpolation::CubicSpline => Interp::Cubic,
            };
            let times = floats(file, l, &sampler.input(), 1, &format!("{sp}.input"))?;
            for (k, w) in times.windows(2).enumerate() {
                if w[1] <= w[0] {
                    return Err(at(
                        file,
                        format!("{sp}.input"),
                        format!(
                            "key times must increase: key {} at {} follows {}",
                            k + 1,
                            w[1],
                            w[0]
                        ),
                    ));
                }
                intervals.push(w[1] - w[0]);
            }
            if let Some(&t0) = times.first() {
                if t0 < 0.0 {
                    return Err(at(
                        file,
                        format!("{sp}.input"),
                        format!("negative key time {t0}"),
                    ));
                }
            }
            if let Some(&t) = times.last() {
                duration = duration.max(t);
            }
            let target = ch.target();
            let prop = match target.property() {
                gltf::animation::Property::Translation => Prop::T,
                gltf::animation::Property::Rotation => Prop::R,
                gltf::animation::Property::Scale => Prop::S,
                gltf::animation::Property::MorphTargetWeights => {
                    skipped_weights += 1;
                    continue;
                }
            };
            let node = target.node().index();
            if !rig.joint_of_node.contains_key(&node) {
                not_joint.push(g.names.get(node).cloned().unwrap_or_default());
                continue;
            }
            if !seen.insert((node, prop)) {
                scene.diagnostics.push(Diagnostic::warning(
                    "gltf-duplicate-channel",
                    format!("{cp} drives a property another channel already drives; ignored"),
                ));
                continue;
            }
            if times.is_empty() {
                continue;
            }
            let comps = if prop == Prop::R { 4 } else { 3 };
            let out = floats(file, l, &sampler.output(), comps, &format!("{sp}.output"))?;
            let per_key = if interp == Interp::Cubic { 3 } else { 1 };
            if out.len() != times.len() * per_key * comps {
                return Err(at(
                    file,
                    format!("{sp}.output"),
                    format!(
                        "{} values for {} key times ({:?} needs {per_key} per key)",
                        out.len() / comps,
                        times.len(),
                        interp
                    ),
                ));
            }
            per_node.entry(node).or_insert_with(|| TrackCurves {
                joint: g.names[node].clone(),
                ..TrackCurves::default()
            });
            keys += times.len();
            let values = match prop {
                Prop::R => Keys::Rotations(out.chunks_exact(4).map(Quat::from_slice).collect()),
                Prop::T | Prop::S => {
                    Keys::Vectors(out.chunks_exact(3).map(Vec3::from_slice).collect())
                }
            };
            channels.push(Channel {
                node,
                prop,
                interp,
                times,
                values,
            });
        }
        // Each channel's curve is its own (a rotation's densification is most of a long clip's
        // import): built side by side when there are enough keys, then put in place in channel
        // order, so the clip is the same at any thread count.
        // Most intervals of a fine capture need no added key and deviate far less than the
        // largest deviation the import reports, yet measuring them was most of its cost: the
        // interval with the largest bound among those certainly within the tolerance is measured
        // first (it is one of them, so the reported largest deviation is at least its error), and
        // each channel then leaves out the intervals that cannot exceed it or the largest so far.
        let par = keys >= PARALLEL_KEYS;
        let certain: Vec<Option<(f32, usize)>> = if par {
            channels.par_iter().map(Channel::largest_certain).collect()
        } else {
            channels.iter().map(Channel::largest_certain).collect()
        };
        let witness = certain
            .iter()
            .enumerate()
            .filter_map(|(i, c)| c.map(|(bound, k)| (bound, i, k)))
            .fold(None, |best: Option<(f32, usize, usize)>, c| match best {
                Some(b) if b.0 >= c.0 => best,
                _ => Some(c),
            });
        if let Some(e) = witness.and_then(|(_, i, k)| channels[i].certain_interval_error(k)) {
            worst_rot = worst_rot.max(e);
        }
        let known = worst_rot;
        let built: Vec<Built> = if par {
            channels.par_iter().map(|c| c.curve(known)).collect()
        } else {
            channels.iter().map(|c| c.curve(known)).collect()
        };
        for (ch, curve) in channels.iter().zip(built) {
            let Some(track) = per_node.get_mut(&ch.node) else {
                continue;
            };
            match curve {
                Built::Rotation(c, e) => {
                    worst_rot = worst_rot.max(e);
                    track.rotation = c;
                }
                Built::Vector(c, e) => {
                    worst_vec = worst_vec.max(e);
                    if ch.prop == Prop::T {
                        track.translation = c;
                    } else {
                        track.scale = c;
                    }
                }
            }
        }
        // Joints with non-joint nodes in front of them: compose those nodes into every key.
        for (node, track) in per_node.iter_mut() {
            if let Some(pre) = rig.pre.get(node) {
                *track = bake_pre(track, *pre, g.local[*node]);
            }
        }
        if skipped_weights > 0 {
            scene.diagnostics.push(
                Diagnostic::info(
                    "gltf-morph-weights-skipped",
                    format!("{name}: {skipped_weights} morph target weight channels skipped (not supported)"),
                )
                .with_figure("channels", skipped_weights as f64),
            );
        }
        if !not_joint.is_empty() {
            not_joint.sort();
            not_joint.dedup();
            scene.diagnostics.push(
                Diagnostic::warning(
                    "gltf-animated-non-joint",
                    format!(
                        "{name}: channels drive nodes that are not joints of the imported skin, ignored: {}",
                        not_joint.join(", ")
                    ),
                )
                .with_figure("nodes", not_joint.len() as f64),
            );
        }
        // The median interval: the element a full sort would put in the middle, found in linear
        // time (a long motion-capture clip has hundreds of thousands of intervals).
        let middle = intervals.len() / 2;
        if middle < intervals.len() {
            intervals.select_nth_unstable_by(middle, f32::total_cmp);
        }
        let sample_rate = match intervals.get(middle) {
            Some(&m) if m > 0.0 => {
                let r = 1.0 / m;
                if (r - r.round()).abs() < 0.01 * r {
                    r.round()
                } else {
                    r
                }
            }
            _ => 30.0,
        };
        scene.clips.push(SceneClip {
            name,
            duration,
            sample_rate,
            looping: false,
            additive: false,
            tracks: per_node.into_values().collect(),
        });
    }
    if worst_rot > 0.0 || worst_vec > 0.0 {
        scene.diagnostics.push(
            Diagnostic::info(
                "gltf-interpolation-error",
                format!(
                    "keys were added between glTF keys; largest measured deviation from glTF interpolation: rotation {worst_rot:.2e} rad, cubic translation/scale {worst_vec:.2e}"
                ),
            )
            .with_figure("rotation_rad", worst_rot as f64)
            .with_figure("vector", worst_vec as f64),
        );
    }
    Ok(())
}

/// Composes `pre` in front of every key of a track (all three channels, at the union of their times).
pub(super) fn bake_pre(track: &TrackCurves, pre: Mat4, rest: Transform) -> TrackCurves {
    let mut times: Vec<f32> = track
        .translation
        .times
        .iter()
        .chain(&track.rotation.times)
        .chain(&track.scale.times)
        .copied()
        .collect();
    times.sort_by(f32::total_cmp);
    times.dedup();
    let mut out = TrackCurves {
        joint: track.joint.clone(),
        ..TrackCurves::default()
    };
    let mut prev: Option<Quat> = None;
    for &t in &times {
        let tr =
            curve_at(&track.translation, t, |a, b, x| a.lerp(b, x)).unwrap_or(rest.translation);
        let r = curve_at(&track.rotation, t, super::anim::nlerp).unwrap_or(rest.rotation);
        let s = curve_at(&track.scale, t, |a, b, x| a.lerp(b, x)).unwrap_or(rest.scale);
        let (d, _, _) = decompose(pre * Transform::new(tr, r, s).to_mat4());
        let mut q = d.rotation;
        if let Some(p) = prev {
            if p.dot(q) < 0.0 {
                q = -q;
            }
        }
        prev = Some(q);
        out.translation.times.push(t);
        out.translation.values.push(d.translation);
        out.rotation.times.push(t);
        out.rotation.values.push(q);
        out.scale.times.push(t);
        out.scale.values.push(d.scale);
    }
    out
}
