//! The report of `sinew inspect FILE --pose CLIP@TIME`: model-space joint transforms per frame, as JSON
//! (field names are a stable interface, docs/cli.md) and as text for stderr.

use super::text::num;
use serde::Serialize;
use sinew_core::Skeleton;
use sinew_pipeline::pose::Poses;
use std::fmt::Write as _;

/// `inspect --pose` report.
#[derive(Debug, Clone, Serialize)]
pub struct PoseReport {
    /// The path as given.
    pub file: String,
    /// Clip name.
    pub clip: String,
    /// Clip duration, seconds.
    pub duration: f32,
    /// Whether the clip loops.
    pub looping: bool,
    /// Frame rate of a range, or null for a single time.
    pub fps: Option<f32>,
    /// Skeleton joints, in skeleton order.
    pub joints: Vec<PoseJointReport>,
    /// Sampled frames.
    pub frames: Vec<PoseFrameReport>,
}

/// A joint of the skeleton.
#[derive(Debug, Clone, Serialize)]
pub struct PoseJointReport {
    /// Index in the skeleton.
    pub index: usize,
    /// Name.
    pub name: String,
    /// Parent index, null for a root.
    pub parent: Option<usize>,
}

/// One frame.
#[derive(Debug, Clone, Serialize)]
pub struct PoseFrameReport {
    /// Clip time, seconds.
    pub time: f32,
    /// Model-space transforms, one per joint in skeleton order.
    pub joints: Vec<PoseTransformReport>,
}

/// A joint's model-space transform.
#[derive(Debug, Clone, Serialize)]
pub struct PoseTransformReport {
    /// Joint name.
    pub name: String,
    /// Translation x, y, z.
    pub translation: [f32; 3],
    /// Rotation quaternion x, y, z, w.
    pub rotation: [f32; 4],
    /// Scale x, y, z.
    pub scale: [f32; 3],
    /// The runtime's model matrix, 16 numbers, column-major.
    pub matrix: [f32; 16],
}

/// Builds the report.
pub fn pose_report(file: &str, skeleton: &Skeleton, poses: &Poses) -> PoseReport {
    let names = skeleton.names();
    PoseReport {
        file: file.to_string(),
        clip: poses.clip.clone(),
        duration: poses.duration,
        looping: poses.looping,
        fps: poses.fps,
        joints: names
            .iter()
            .zip(skeleton.parents())
            .enumerate()
            .map(|(index, (name, parent))| PoseJointReport {
                index,
                name: name.clone(),
                parent: parent.map(usize::from),
            })
            .collect(),
        frames: poses
            .frames
            .iter()
            .map(|f| PoseFrameReport {
                time: f.time,
                joints: f
                    .joints
                    .iter()
                    .zip(names)
                    .map(|(j, name)| PoseTransformReport {
                        name: name.clone(),
                        translation: j.translation.to_array(),
                        rotation: j.rotation.to_array(),
                        scale: j.scale.to_array(),
                        matrix: j.matrix.to_cols_array(),
                    })
                    .collect(),
            })
            .collect(),
    }
}

/// The text report: a header, then per frame one line per joint.
pub fn pose_text(r: &PoseReport) -> String {
    let mut o = String::new();
    let fps = r
        .fps
        .map_or_else(String::new, |f| format!(", {} fps", num(f)));
    let _ = writeln!(
        o,
        "{}: clip {:?} ({} s{}{}), {} joints, {} frames, model space",
        r.file,
        r.clip,
        num(r.duration),
        if r.looping { ", looping" } else { "" },
        fps,
        r.joints.len(),
        r.frames.len()
    );
    let width = r.joints.iter().map(|j| j.name.len()).max().unwrap_or(0);
    for f in &r.frames {
        let _ = writeln!(o, "t = {} s", num(f.time));
        for (i, j) in f.joints.iter().enumerate() {
            let v = |a: &[f32]| a.iter().map(|&x| num(x)).collect::<Vec<_>>().join(" ");
            let _ = writeln!(
                o,
                "  [{i}] {:<width$}  T({})  Q({})  S({})",
                j.name,
                v(&j.translation),
                v(&j.rotation),
                v(&j.scale),
            );
        }
    }
    o
}
