//! Mapping files: reading and writing the editable JSON, and applying a mapping to a clip.

use super::joints::JointSet;
use super::matching::{ambiguity_warnings, Mapping, MappingEntry, MatchMethod, SetContext};
use super::names::Slot;
use sinew_core::TrackCurves;
use sinew_scene::SceneClip;
use std::collections::HashMap;

/// Version number written to and required in mapping files.
pub const MAPPING_FILE_VERSION: u64 = 1;

/// Why a mapping file was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MappingError {
    /// Not JSON.
    #[error("mapping file is not valid JSON: {0}")]
    Json(String),
    /// JSON of the wrong shape.
    #[error("mapping file: {path}: {message}")]
    Shape {
        /// JSON path of the bad value (e.g. `joints."Bip01 L Thigh"`).
        path: String,
        /// What is wrong.
        message: String,
    },
    /// A version this reader does not know.
    #[error("mapping file: version {0} is not supported (expected 1)")]
    Version(String),
    /// A key of `joints` names no rig joint.
    #[error("mapping file: rig joint {name:?} does not exist in the rig{}", label_suffix(.label))]
    UnknownRigJoint {
        /// The name.
        name: String,
        /// The rig label.
        label: String,
    },
    /// A value of `joints` names no motion joint.
    #[error("mapping file: motion joint {name:?} (for rig joint {rig:?}) does not exist in the motion{}", label_suffix(.label))]
    UnknownMotionJoint {
        /// The name.
        name: String,
        /// The rig joint it was given for.
        rig: String,
        /// The motion label.
        label: String,
    },
    /// Two rig joints name the same motion joint.
    #[error("mapping file: motion joint {name:?} is given for both {first:?} and {second:?}")]
    DuplicateMotionJoint {
        /// The motion joint.
        name: String,
        /// First rig joint naming it.
        first: String,
        /// Second rig joint naming it.
        second: String,
    },
}

pub(super) fn label_suffix(label: &str) -> String {
    if label.is_empty() {
        String::new()
    } else {
        format!(" {label:?}")
    }
}

/// Reads a mapping file (format in `docs/mapping.md`) and checks it against the rig and motion.
///
/// Every key of `joints` must be a rig joint and every non-null value a motion joint, each motion joint
/// used at most once; the error names the offending joint. Rig joints the file does not list are
/// unmatched. Entries get [`MatchMethod::File`]; the ambiguity warnings are computed as for
/// [`map_joints`]. The file's `rig`/`motion` labels are kept; they are not required to equal the sets'
/// labels.
pub fn read_mapping(
    json: &str,
    rig: &JointSet,
    motion: &JointSet,
) -> Result<Mapping, MappingError> {
    let value: serde_json::Value =
        serde_json::from_str(json).map_err(|e| MappingError::Json(e.to_string()))?;
    let shape = |path: &str, message: &str| MappingError::Shape {
        path: path.to_string(),
        message: message.to_string(),
    };
    let obj = value
        .as_object()
        .ok_or_else(|| shape("$", "expected an object"))?;
    match obj.get("version") {
        Some(v) if v.as_u64() == Some(MAPPING_FILE_VERSION) => {}
        Some(v) => return Err(MappingError::Version(v.to_string())),
        None => return Err(shape("version", "missing")),
    }
    let label = |key: &str| -> Result<String, MappingError> {
        match obj.get(key) {
            None | Some(serde_json::Value::Null) => Ok(String::new()),
            Some(serde_json::Value::String(s)) => Ok(s.clone()),
            Some(_) => Err(shape(key, "expected a string")),
        }
    };
    let rig_label = label("rig")?;
    let motion_label = label("motion")?;
    let joints = obj
        .get("joints")
        .ok_or_else(|| shape("joints", "missing"))?
        .as_object()
        .ok_or_else(|| shape("joints", "expected an object"))?;
    let mut bound: Vec<Option<usize>> = vec![None; rig.names.len()];
    let mut used: Vec<Option<usize>> = vec![None; motion.names.len()];
    let rig_index = rig.index_by_name();
    let motion_index = motion.index_by_name();
    for (key, val) in joints {
        let r = *rig_index
            .get(key.as_str())
            .ok_or_else(|| MappingError::UnknownRigJoint {
                name: key.clone(),
                label: rig.label.clone(),
            })?;
        let m =
            match val {
                serde_json::Value::Null => continue,
                serde_json::Value::String(s) => *motion_index.get(s.as_str()).ok_or_else(|| {
                    MappingError::UnknownMotionJoint {
                        name: s.clone(),
                        rig: key.clone(),
                        label: motion.label.clone(),
                    }
                })?,
                _ => {
                    return Err(shape(
                        &format!("joints.{key:?}"),
                        "expected a motion joint name or null",
                    ))
                }
            };
        if let Some(prev) = used[m] {
            return Err(MappingError::DuplicateMotionJoint {
                name: motion.names[m].clone(),
                first: rig.names[prev].clone(),
                second: key.clone(),
            });
        }
        used[m] = Some(r);
        bound[r] = Some(m);
    }
    let rc = SetContext::new(&rig.names);
    let mc = SetContext::new(&motion.names);
    let rslot: Vec<Option<Slot>> = (0..rig.names.len()).map(|i| rc.slot(i)).collect();
    let mslot: Vec<Option<Slot>> = (0..motion.names.len()).map(|i| mc.slot(i)).collect();
    let mut mapping = Mapping {
        rig: rig_label,
        motion: motion_label,
        rig_family: rc.family,
        motion_family: mc.family,
        entries: rig
            .names
            .iter()
            .enumerate()
            .map(|(r, name)| MappingEntry {
                rig: name.clone(),
                motion: bound[r].map(|m| motion.names[m].clone()),
                method: bound[r].map(|_| MatchMethod::File),
                slot: rslot[r],
                side: rc.normal[r].side,
            })
            .collect(),
        unmatched_motion: (0..motion.names.len())
            .filter(|&m| used[m].is_none())
            .map(|m| motion.names[m].clone())
            .collect(),
        warnings: Vec::new(),
    };
    mapping.warnings = ambiguity_warnings(&mapping, rig, motion, &rc, &mc, &rslot, &mslot);
    Ok(mapping)
}

/// Writes a mapping file: `version`, `rig`, `motion` labels and `joints`, one key per rig joint in rig
/// order, the motion joint's name or `null` when unmatched. Two-space indented, ends with a newline.
pub fn write_mapping(mapping: &Mapping) -> String {
    let q = |s: &str| serde_json::Value::String(s.to_string()).to_string();
    let mut out = String::new();
    out.push_str("{\n");
    out.push_str(&format!("  \"version\": {MAPPING_FILE_VERSION},\n"));
    out.push_str(&format!("  \"rig\": {},\n", q(&mapping.rig)));
    out.push_str(&format!("  \"motion\": {},\n", q(&mapping.motion)));
    if mapping.entries.is_empty() {
        out.push_str("  \"joints\": {}\n}\n");
        return out;
    }
    out.push_str("  \"joints\": {\n");
    for (i, e) in mapping.entries.iter().enumerate() {
        let v = e.motion.as_deref().map_or("null".to_string(), q);
        let comma = if i + 1 < mapping.entries.len() {
            ","
        } else {
            ""
        };
        out.push_str(&format!("    {}: {v}{comma}\n", q(&e.rig)));
    }
    out.push_str("  }\n}\n");
    out
}

/// Renames a clip's tracks from motion joint names to the rig joint names they are bound to, in rig
/// order, dropping tracks of unbound motion joints. Curves are copied unchanged (no retargeting: see
/// [`crate::retarget`] when rest and bind poses differ).
pub fn apply_mapping(clip: &SceneClip, mapping: &Mapping) -> SceneClip {
    let mut by_joint: HashMap<&str, &TrackCurves> = HashMap::new();
    for t in &clip.tracks {
        by_joint.entry(t.joint.as_str()).or_insert(t);
    }
    let tracks = mapping
        .pairs()
        .filter_map(|(r, m)| {
            by_joint.get(m).map(|t| TrackCurves {
                joint: r.to_string(),
                ..(*t).clone()
            })
        })
        .collect();
    SceneClip {
        tracks,
        ..clip.clone()
    }
}
