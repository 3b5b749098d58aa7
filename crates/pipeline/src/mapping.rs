//! Joint-name mapping: which joint of a motion (a BVH walk, a glTF clip) drives which joint of a rig.
//!
//! [`map_joints`] matches a rig's joints to a motion's joints in four stages, each only among the joints
//! still unmatched, one-to-one:
//! 1. **exact** name;
//! 2. **normalised** name: case, separators ` _-.:`, prefixes (`Bip01 `, `mixamorig:`, `Armature|`,
//!    `DEF-`, `ValveBiped.`, any `namespace:`), camel case, and the `L`/`Left`/`R`/`Right` spellings are
//!    folded away (see [`normalise`]);
//! 3. **synonym slots** ([`Slot`]): hips/pelvis, spine chain, neck chain, head, clavicle, upper arm,
//!    forearm, hand, thigh, calf, foot, toe and fingers, per side, with chains paired by their order from
//!    the root;
//! 4. **fuzzy**: normalised edit distance between normalised names, same side, score at least
//!    [`FUZZY_THRESHOLD`].
//!
//! A match in stages 1, 2 and 4 is refused when the two names fall in different slots (the CMU
//! `LeftShoulder` is a clavicle, a Biovision `LeftShoulder` under a `LeftCollar` is an upper arm). The
//! result, a [`Mapping`], lists each rig joint with its motion joint and how it was found, what stayed
//! unmatched, and warnings for the known ambiguities. Mappings are saved and edited as JSON
//! ([`write_mapping`], [`read_mapping`]); [`apply_mapping`] renames a clip's tracks onto the rig.
//!
//! The rules are documented with their reasons in `docs/mapping.md`.

use serde::Serialize;
use sinew_core::{Skeleton, TrackCurves};
use sinew_scene::{Diagnostic, SceneClip};
use std::collections::{HashMap, HashSet};
use std::fmt;

/// Lowest fuzzy score (1 - edit distance / longer length, on normalised names) accepted as a match.
pub const FUZZY_THRESHOLD: f32 = 0.75;

/// Fuzzy matching is skipped when unmatched rig joints times unmatched motion joints exceeds this.
pub const FUZZY_MAX_PAIRS: usize = 1_000_000;

/// Normalised names longer than this (in characters) take no part in fuzzy matching.
pub const FUZZY_MAX_LEN: usize = 64;

/// Version number written to and required in mapping files.
pub const MAPPING_FILE_VERSION: u64 = 1;

/// The joints of one side of a mapping: names, parents and which joints the motion animates.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointSet {
    /// A label for reports and mapping files, usually the file name. May be empty.
    pub label: String,
    names: Vec<String>,
    parents: Vec<Option<usize>>,
    keyed: Vec<bool>,
}

impl JointSet {
    /// A joint set from names and parent indices; every joint counts as keyed.
    ///
    /// A parent index that is out of range, points at the joint itself or closes a cycle is treated as
    /// no parent, so arbitrary input never fails.
    pub fn new(names: Vec<String>, parents: Vec<Option<usize>>) -> Self {
        let n = names.len();
        let mut parents: Vec<Option<usize>> = (0..n)
            .map(|i| parents.get(i).copied().flatten())
            .enumerate()
            .map(|(i, p)| p.filter(|&p| p < n && p != i))
            .collect();
        // Break cycles: a joint whose parent chain does not reach a root within n steps loses its parent.
        for i in 0..n {
            let mut j = i;
            let mut steps = 0;
            while let Some(p) = parents[j] {
                j = p;
                steps += 1;
                if steps > n {
                    parents[i] = None;
                    break;
                }
            }
        }
        JointSet {
            label: String::new(),
            names,
            parents,
            keyed: vec![true; n],
        }
    }

    /// A flat joint set (no parents), every joint keyed. Chains are then ordered by input order.
    pub fn from_names<S: AsRef<str>>(names: &[S]) -> Self {
        let names: Vec<String> = names.iter().map(|s| s.as_ref().to_string()).collect();
        let parents = vec![None; names.len()];
        JointSet::new(names, parents)
    }

    /// The joints of a skeleton; every joint counts as keyed (use this for rigs).
    pub fn from_skeleton(skeleton: &Skeleton) -> Self {
        let parents = skeleton
            .parents()
            .iter()
            .map(|p| p.map(usize::from))
            .collect();
        JointSet::new(skeleton.names().to_vec(), parents)
    }

    /// The joints of a motion's skeleton, keyed where some clip's track for that joint changes over time
    /// (a joint without a track, or whose keys are all equal, is unkeyed: CMU `LHipJoint`).
    pub fn from_skeleton_and_clips(skeleton: &Skeleton, clips: &[SceneClip]) -> Self {
        let mut set = JointSet::from_skeleton(skeleton);
        let mut animated: HashSet<&str> = HashSet::new();
        for clip in clips {
            for track in &clip.tracks {
                if track_varies(track) {
                    animated.insert(track.joint.as_str());
                }
            }
        }
        set.keyed = set
            .names
            .iter()
            .map(|n| animated.contains(n.as_str()))
            .collect();
        set
    }

    /// Replaces the keyed flags (missing entries count as keyed).
    pub fn with_keyed(mut self, keyed: &[bool]) -> Self {
        self.keyed = (0..self.names.len())
            .map(|i| keyed.get(i).copied().unwrap_or(true))
            .collect();
        self
    }

    /// Sets the label.
    pub fn with_label(mut self, label: impl Into<String>) -> Self {
        self.label = label.into();
        self
    }

    /// Joint names.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Parent of each joint.
    pub fn parents(&self) -> &[Option<usize>] {
        &self.parents
    }

    /// Whether each joint is animated.
    pub fn keyed(&self) -> &[bool] {
        &self.keyed
    }

    /// Index of the first joint with this exact name.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Depth of every joint (roots 0), in O(n): each chain is walked once.
    fn depths(&self) -> Vec<usize> {
        let n = self.names.len();
        let mut depth: Vec<Option<usize>> = vec![None; n];
        let mut path = Vec::new();
        for i in 0..n {
            let mut j = i;
            // Walk up to a joint of known depth or a root (parents were made acyclic in `new`).
            let base = loop {
                if let Some(d) = depth[j] {
                    break d + 1;
                }
                path.push(j);
                match self.parents.get(j).copied().flatten() {
                    Some(p) if path.len() <= n => j = p,
                    _ => break 0,
                }
            };
            for (k, &j) in path.iter().rev().enumerate() {
                depth[j] = Some(base + k);
            }
            path.clear();
        }
        depth.into_iter().map(|d| d.unwrap_or(0)).collect()
    }

    fn index_by_name(&self) -> HashMap<&str, usize> {
        let mut m = HashMap::with_capacity(self.names.len());
        for (i, n) in self.names.iter().enumerate() {
            m.entry(n.as_str()).or_insert(i);
        }
        m
    }
}

/// True when any curve of the track holds two different values.
fn track_varies(track: &TrackCurves) -> bool {
    const EPS: f32 = 1e-5;
    let t = &track.translation.values;
    let s = &track.scale.values;
    let r = &track.rotation.values;
    let v3 = |v: &[sinew_core::glam::Vec3]| {
        v.first()
            .is_some_and(|a| v.iter().any(|b| (*b - *a).abs().max_element() > EPS))
    };
    let rot = r.first().is_some_and(|a| {
        r.iter()
            .any(|b| 1.0 - a.normalize().dot(b.normalize()).abs() > EPS * EPS)
    });
    v3(t) || v3(s) || rot
}

/// Which side of the body a name says it is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// No side token.
    Centre,
    /// `L`, `Left`, `.L`, `_l`...
    Left,
    /// `R`, `Right`, `.R`, `_r`...
    Right,
}

/// A name after normalisation: its side and the remaining words joined, lowercase.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct NormalName {
    /// Side token found in the name.
    pub side: Side,
    /// Remaining words, lowercase, joined without separators (`"Bip01 L UpperArm"` gives `"upperarm"`).
    pub key: String,
}

impl NormalName {
    /// The key without trailing digits (`spine1` gives `spine`).
    pub fn stem(&self) -> &str {
        self.key.trim_end_matches(|c: char| c.is_ascii_digit())
    }
    /// The trailing digits of the key (`spine1` gives `1`, `leg` gives ``).
    pub fn number(&self) -> &str {
        &self.key[self.stem().len()..]
    }
}

/// Strips a prefix, ASCII case-insensitively.
fn strip_prefix_ci<'a>(s: &'a str, prefix: &str) -> Option<&'a str> {
    let head = s.get(..prefix.len())?;
    if head.eq_ignore_ascii_case(prefix) {
        s.get(prefix.len()..)
    } else {
        None
    }
}

/// Length of a `Bip01 ` / `Bip01_` style prefix at the start of `s`, if followed by more text.
fn biped_prefix_len(s: &str) -> Option<usize> {
    let b = s.as_bytes();
    if b.len() < 4 || !b[..3].eq_ignore_ascii_case(b"bip") {
        return None;
    }
    let digits = b[3..].iter().take_while(|c| c.is_ascii_digit()).count();
    if digits == 0 {
        return None;
    }
    let sep = 3 + digits;
    match b.get(sep) {
        Some(b' ' | b'_' | b'.' | b'-') if b.len() > sep + 1 => Some(sep + 1),
        _ => None,
    }
}

/// True for a name in the 3ds Max Biped family (`Bip01 ...`, `ValveBiped.Bip01_...`).
fn is_biped_name(name: &str) -> bool {
    let s = strip_prefix_ci(name.trim(), "ValveBiped.").unwrap_or(name.trim());
    let b = s.as_bytes();
    b.len() >= 4
        && b[..3].eq_ignore_ascii_case(b"bip")
        && b[3..].first().is_some_and(|c| c.is_ascii_digit())
}

/// Splits camel case and digit runs: `LHipJoint` -> `L Hip Joint`, `Spine1` -> `Spine 1`.
fn camel_words(part: &str, out: &mut Vec<String>) {
    let chars: Vec<char> = part.chars().collect();
    let mut word = String::new();
    for (i, &c) in chars.iter().enumerate() {
        if i > 0 {
            let prev = chars[i - 1];
            let next = chars.get(i + 1).copied();
            let boundary = (prev.is_lowercase() && c.is_uppercase())
                || (prev.is_alphabetic() && c.is_ascii_digit())
                || (prev.is_ascii_digit() && c.is_alphabetic())
                || (prev.is_uppercase()
                    && c.is_uppercase()
                    && next.is_some_and(|n| n.is_lowercase()));
            if boundary && !word.is_empty() {
                out.push(std::mem::take(&mut word).to_lowercase());
            }
        }
        word.push(c);
    }
    if !word.is_empty() {
        out.push(word.to_lowercase());
    }
}

fn side_of(word: &str) -> Option<Side> {
    match word {
        "l" | "left" => Some(Side::Left),
        "r" | "right" => Some(Side::Right),
        _ => None,
    }
}

/// Normalises a joint name (the rules of stage 2, documented in `docs/mapping.md`).
///
/// In order: everything up to the last `|` (`Armature|`) and the last `:` (`mixamorig:`, any namespace) is
/// dropped; a `ValveBiped.` / `DEF-` / `DEF_` / `DEF.` prefix and a `Bip01 ` / `Bip01_` prefix (any
/// digits) are dropped; the rest is split into words at ` _-.` and at camel-case and letter/digit
/// boundaries and lowercased; a first or last word `l`/`left`/`r`/`right` becomes the side. A bare
/// `Bip01` stays `bip01`.
pub fn normalise(name: &str) -> NormalName {
    let mut s = name.trim();
    if let Some(i) = s.rfind('|') {
        s = &s[i + 1..];
    }
    if let Some(i) = s.rfind(':') {
        s = &s[i + 1..];
    }
    for p in ["ValveBiped.", "DEF-", "DEF_", "DEF."] {
        if let Some(rest) = strip_prefix_ci(s, p) {
            s = rest;
        }
    }
    if let Some(n) = biped_prefix_len(s) {
        s = &s[n..];
    }
    let mut words = Vec::new();
    for part in s.split([' ', '_', '-', '.', ':', '\t']) {
        if !part.is_empty() {
            camel_words(part, &mut words);
        }
    }
    let mut side = Side::Centre;
    if words.len() > 1 {
        if let Some(sd) = words.first().and_then(|w| side_of(w)) {
            side = sd;
            words.remove(0);
        } else if let Some(sd) = words.last().and_then(|w| side_of(w)) {
            side = sd;
            words.pop();
        }
    }
    NormalName {
        side,
        key: words.concat(),
    }
}

/// A name family, detected from the names of a joint set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    /// 3ds Max Character Studio Biped (`Bip01 L Thigh`, old Half-Life `Bip01 L Leg`).
    Biped,
    /// CMU motion capture as converted to BVH (`LeftUpLeg`, `LHipJoint`, `LowerBack`).
    Cmu,
    /// Mixamo (`mixamorig:LeftUpLeg`).
    Mixamo,
    /// None of the above.
    Other,
}

impl Family {
    /// Detects the family: Biped when any name has a `Bip01` style prefix, Mixamo when any has a
    /// `mixamorig` prefix, CMU when a normalised name is `upleg`, `hipjoint` or `lowerback`.
    pub fn detect(names: &[String]) -> Family {
        if names.iter().any(|n| is_biped_name(n)) {
            return Family::Biped;
        }
        if names
            .iter()
            .any(|n| strip_prefix_ci(n.trim(), "mixamorig").is_some())
        {
            return Family::Mixamo;
        }
        if names.iter().any(|n| {
            matches!(
                normalise(n).key.as_str(),
                "upleg" | "hipjoint" | "lowerback"
            )
        }) {
            return Family::Cmu;
        }
        Family::Other
    }

    /// Lowercase name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Family::Biped => "biped",
            Family::Cmu => "cmu",
            Family::Mixamo => "mixamo",
            Family::Other => "other",
        }
    }
}

/// A body part that names in different families agree on (stage 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Slot {
    /// `Pelvis`, `Hips`, a side-less `Hip`.
    Hips,
    /// `Spine`, `Spine1`..., `Chest`, `UpperChest`, `Ab`, `Abdomen`, `Torso`, `LowerBack`: a chain.
    Spine,
    /// `Neck`, `Neck1`...: a chain.
    Neck,
    /// `Head`.
    Head,
    /// `Clavicle`, `Collar`, `Shoulder` (when the side has no collar/clavicle), old Biped `Arm` (when
    /// `Arm2` exists).
    Clavicle,
    /// `UpperArm`, `UpArm`, CMU `Arm`, `Shoulder` below a collar, old Biped `Arm1` (with `Arm2`).
    UpperArm,
    /// `Forearm`, `LowerArm`, `Elbow`, old Biped `Arm2` (or `Arm1` without `Arm2`).
    Forearm,
    /// `Hand`, `Wrist`.
    Hand,
    /// `Thigh`, `UpLeg`, `UpperLeg`, a sided `Hip`, old Biped `Leg`.
    Thigh,
    /// `Calf`, `LowerLeg`, `Shin`, `Knee`, CMU `Leg`, old Biped `Leg1`.
    Calf,
    /// `Foot`, `Ankle`.
    Foot,
    /// `Toe`, `Toe0`, `Toes`, `ToeBase`, `Ball`: a chain.
    Toe,
    /// A finger chain: 0 thumb, 1 index, 2 middle, 3 ring, 4 pinky (Biped `FingerNM`: finger N).
    Finger(u8),
}

impl Slot {
    /// Lowercase name for reports (`finger0`...).
    pub fn name(self) -> String {
        match self {
            Slot::Hips => "hips".into(),
            Slot::Spine => "spine".into(),
            Slot::Neck => "neck".into(),
            Slot::Head => "head".into(),
            Slot::Clavicle => "clavicle".into(),
            Slot::UpperArm => "upper_arm".into(),
            Slot::Forearm => "forearm".into(),
            Slot::Hand => "hand".into(),
            Slot::Thigh => "thigh".into(),
            Slot::Calf => "calf".into(),
            Slot::Foot => "foot".into(),
            Slot::Toe => "toe".into(),
            Slot::Finger(n) => format!("finger{n}"),
        }
    }

    /// True for slots that have a left and a right joint.
    pub fn is_sided(self) -> bool {
        !matches!(self, Slot::Hips | Slot::Spine | Slot::Neck | Slot::Head)
    }
}

/// Per-set facts the slot rules look at (what else is on the same side).
struct SetContext {
    family: Family,
    normal: Vec<NormalName>,
    keys: HashSet<(Side, String)>,
    stems: HashSet<(Side, String)>,
}

impl SetContext {
    fn new(names: &[String]) -> Self {
        let normal: Vec<NormalName> = names.iter().map(|n| normalise(n)).collect();
        let keys = normal.iter().map(|n| (n.side, n.key.clone())).collect();
        let stems = normal
            .iter()
            .map(|n| (n.side, n.stem().to_string()))
            .collect();
        SetContext {
            family: Family::detect(names),
            normal,
            keys,
            stems,
        }
    }
    fn has_key(&self, side: Side, key: &str) -> bool {
        self.keys.contains(&(side, key.to_string()))
    }
    fn has_stem(&self, side: Side, stems: &[&str]) -> bool {
        stems
            .iter()
            .any(|s| self.stems.contains(&(side, (*s).to_string())))
    }

    /// The slot of joint `i` (the rules of stage 3).
    fn slot(&self, i: usize) -> Option<Slot> {
        let n = self.normal.get(i)?;
        let side = n.side;
        let stem = n.stem();
        let num = n.number();
        let slot = match stem {
            "pelvis" | "hips" => Slot::Hips,
            "hip" if side == Side::Centre => Slot::Hips,
            "hip" => Slot::Thigh,
            "spine" | "chest" | "upperchest" | "ab" | "abdomen" | "torso" | "lowerback" => {
                Slot::Spine
            }
            "neck" => Slot::Neck,
            "head" => Slot::Head,
            "clavicle" | "collar" | "collarbone" => Slot::Clavicle,
            "shoulder" => {
                if self.has_stem(side, &["clavicle", "collar", "collarbone"]) {
                    Slot::UpperArm
                } else {
                    Slot::Clavicle
                }
            }
            "upperarm" | "uparm" | "humerus" => Slot::UpperArm,
            "arm" => {
                if self.has_key(side, "arm2") {
                    match num {
                        "" => Slot::Clavicle,
                        "1" => Slot::UpperArm,
                        "2" => Slot::Forearm,
                        _ => return None,
                    }
                } else if self.has_key(side, "arm1")
                    && !self.has_stem(side, &["forearm", "lowerarm"])
                {
                    match num {
                        "" => Slot::UpperArm,
                        "1" => Slot::Forearm,
                        _ => return None,
                    }
                } else if num.is_empty() {
                    Slot::UpperArm
                } else {
                    return None;
                }
            }
            "forearm" | "lowerarm" | "elbow" => Slot::Forearm,
            "hand" | "wrist" => Slot::Hand,
            "thigh" | "upleg" | "upperleg" => Slot::Thigh,
            "calf" | "lowerleg" | "shin" | "knee" => Slot::Calf,
            "leg" => {
                let has_thigh = self.has_stem(side, &["thigh", "upleg", "upperleg", "hip"]);
                if has_thigh {
                    if num.is_empty() {
                        Slot::Calf
                    } else {
                        return None;
                    }
                } else if self.has_key(side, "leg1") || self.family == Family::Biped {
                    match num {
                        "" => Slot::Thigh,
                        "1" => Slot::Calf,
                        _ => return None,
                    }
                } else if num.is_empty() {
                    Slot::Calf
                } else {
                    return None;
                }
            }
            "foot" | "ankle" => Slot::Foot,
            "toe" | "toes" | "toebase" | "ball" => Slot::Toe,
            "thumb" | "handthumb" => Slot::Finger(0),
            "index" | "handindex" | "indexfinger" => Slot::Finger(1),
            "middle" | "handmiddle" | "middlefinger" => Slot::Finger(2),
            "ring" | "handring" | "ringfinger" => Slot::Finger(3),
            "pinky" | "handpinky" | "little" | "littlefinger" => Slot::Finger(4),
            "finger" => match num.as_bytes().first() {
                Some(d @ b'0'..=b'4') => Slot::Finger(d - b'0'),
                _ => return None,
            },
            _ => return None,
        };
        if slot.is_sided() == (side != Side::Centre) {
            Some(slot)
        } else {
            None
        }
    }
}

/// How a rig joint's motion joint was found.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "method", rename_all = "snake_case")]
pub enum MatchMethod {
    /// Identical names.
    Exact,
    /// Identical after [`normalise`].
    Normalised,
    /// Same body-part slot and side (chains paired by order).
    Synonym {
        /// The slot both joints fall in.
        slot: Slot,
    },
    /// Similar normalised names.
    Fuzzy {
        /// 1 - edit distance / longer length, in `[FUZZY_THRESHOLD, 1]`.
        score: f32,
    },
    /// Read from a mapping file.
    File,
}

impl fmt::Display for MatchMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MatchMethod::Exact => write!(f, "exact"),
            MatchMethod::Normalised => write!(f, "normalised"),
            MatchMethod::Synonym { slot } => write!(f, "synonym ({})", slot.name()),
            MatchMethod::Fuzzy { score } => write!(f, "fuzzy ({score:.2})"),
            MatchMethod::File => write!(f, "file"),
        }
    }
}

/// One rig joint and what drives it.
#[derive(Debug, Clone, PartialEq)]
pub struct MappingEntry {
    /// Rig joint name.
    pub rig: String,
    /// The motion joint bound to it, if any.
    pub motion: Option<String>,
    /// How the match was made; `None` when unmatched.
    pub method: Option<MatchMethod>,
    /// The rig joint's body-part slot, if it has one (used by retargeting to find legs).
    pub slot: Option<Slot>,
    /// The rig joint's side.
    pub side: Side,
}

/// The result of matching a rig's joints to a motion's joints.
#[derive(Debug, Clone, PartialEq)]
pub struct Mapping {
    /// Label of the rig (from [`JointSet::label`] or the mapping file).
    pub rig: String,
    /// Label of the motion.
    pub motion: String,
    /// Family detected for the rig names.
    pub rig_family: Family,
    /// Family detected for the motion names.
    pub motion_family: Family,
    /// One entry per rig joint, in rig order.
    pub entries: Vec<MappingEntry>,
    /// Motion joints bound to no rig joint, in motion order.
    pub unmatched_motion: Vec<String>,
    /// Known ambiguities met while matching (codes in `docs/mapping.md`).
    pub warnings: Vec<Diagnostic>,
}

impl Mapping {
    /// The motion joint bound to a rig joint.
    pub fn motion_for(&self, rig: &str) -> Option<&str> {
        self.entries
            .iter()
            .find(|e| e.rig == rig)
            .and_then(|e| e.motion.as_deref())
    }

    /// The rig joint a motion joint is bound to.
    pub fn rig_for(&self, motion: &str) -> Option<&str> {
        self.entries
            .iter()
            .find(|e| e.motion.as_deref() == Some(motion))
            .map(|e| e.rig.as_str())
    }

    /// The entry of a rig joint.
    pub fn entry(&self, rig: &str) -> Option<&MappingEntry> {
        self.entries.iter().find(|e| e.rig == rig)
    }

    /// Bound pairs `(rig, motion)`, in rig order.
    pub fn pairs(&self) -> impl Iterator<Item = (&str, &str)> {
        self.entries
            .iter()
            .filter_map(|e| e.motion.as_deref().map(|m| (e.rig.as_str(), m)))
    }

    /// Rig joints bound to nothing, in rig order.
    pub fn unmatched_rig(&self) -> Vec<&str> {
        self.entries
            .iter()
            .filter(|e| e.motion.is_none())
            .map(|e| e.rig.as_str())
            .collect()
    }
}

/// Levenshtein distance over characters.
fn edit_distance(a: &[char], b: &[char]) -> usize {
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    let mut cur = vec![0; b.len() + 1];
    for (i, ca) in a.iter().enumerate() {
        cur[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    prev[b.len()]
}

/// The fuzzy score of two normalised keys: `1 - distance / longer length`.
pub fn fuzzy_score(a: &str, b: &str) -> f32 {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let longer = a.len().max(b.len());
    if longer == 0 {
        return 0.0;
    }
    1.0 - edit_distance(&a, &b) as f32 / longer as f32
}

/// True for every name that already occurred earlier in the list.
fn repeated_names(names: &[String]) -> Vec<bool> {
    let mut seen = HashSet::with_capacity(names.len());
    names.iter().map(|n| !seen.insert(n.as_str())).collect()
}

fn compatible(a: Option<Slot>, b: Option<Slot>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => a == b,
        _ => true,
    }
}

/// Matches a rig's joints to a motion's joints (stages described in the module docs).
///
/// Deterministic: ties are broken by rig order, then motion order. Never fails; what cannot be matched
/// is reported as unmatched.
pub fn map_joints(rig: &JointSet, motion: &JointSet) -> Mapping {
    let rc = SetContext::new(&rig.names);
    let mc = SetContext::new(&motion.names);
    let rslot: Vec<Option<Slot>> = (0..rig.names.len()).map(|i| rc.slot(i)).collect();
    let mslot: Vec<Option<Slot>> = (0..motion.names.len()).map(|i| mc.slot(i)).collect();
    let mut bound: Vec<Option<(usize, MatchMethod)>> = vec![None; rig.names.len()];
    // Mappings work by name: a repeated name (which no valid skeleton has) takes no part after its
    // first occurrence, on either side.
    let mut used = repeated_names(&motion.names);
    for (r, rep) in repeated_names(&rig.names).into_iter().enumerate() {
        if rep {
            bound[r] = Some((usize::MAX, MatchMethod::Exact));
        }
    }
    let mut conflicts: Vec<(String, String)> = Vec::new();

    // Stage 1: exact.
    let by_name = motion.index_by_name();
    for (r, name) in rig.names.iter().enumerate() {
        if let Some(&m) = by_name.get(name.as_str()) {
            if used[m] || bound[r].is_some() {
                continue;
            }
            if compatible(rslot[r], mslot[m]) {
                bound[r] = Some((m, MatchMethod::Exact));
                used[m] = true;
            } else {
                conflicts.push((name.clone(), motion.names[m].clone()));
            }
        }
    }

    // Stage 2: normalised.
    let mut by_normal: HashMap<(Side, &str), Vec<usize>> = HashMap::new();
    for (i, n) in mc.normal.iter().enumerate() {
        if !n.key.is_empty() {
            by_normal
                .entry((n.side, n.key.as_str()))
                .or_default()
                .push(i);
        }
    }
    for r in 0..rig.names.len() {
        if bound[r].is_some() {
            continue;
        }
        let n = &rc.normal[r];
        let Some(cands) = by_normal.get(&(n.side, n.key.as_str())) else {
            continue;
        };
        for &m in cands {
            if used[m] {
                continue;
            }
            if compatible(rslot[r], mslot[m]) {
                bound[r] = Some((m, MatchMethod::Normalised));
                used[m] = true;
                break;
            }
            conflicts.push((rig.names[r].clone(), motion.names[m].clone()));
        }
    }

    // Stage 3: synonym slots, chains paired by order from the root.
    let chains = |set: &JointSet, slots: &[Option<Slot>], ctx: &SetContext| {
        let depth = set.depths();
        let mut c: HashMap<(Slot, Side), Vec<usize>> = HashMap::new();
        for (i, s) in slots.iter().enumerate() {
            if let Some(s) = s {
                c.entry((*s, ctx.normal[i].side)).or_default().push(i);
            }
        }
        for v in c.values_mut() {
            v.sort_by_key(|&i| (depth[i], i));
        }
        c
    };
    let rchains = chains(rig, &rslot, &rc);
    let mchains = chains(motion, &mslot, &mc);
    let mut keys: Vec<&(Slot, Side)> = rchains.keys().collect();
    keys.sort();
    for key in keys {
        let (Some(rs), Some(ms)) = (rchains.get(key), mchains.get(key)) else {
            continue;
        };
        for (&r, &m) in rs.iter().zip(ms) {
            if bound[r].is_none() && !used[m] {
                bound[r] = Some((m, MatchMethod::Synonym { slot: key.0 }));
                used[m] = true;
            }
        }
    }

    // Stage 4: fuzzy.
    let free_r: Vec<usize> = (0..rig.names.len())
        .filter(|&r| bound[r].is_none())
        .collect();
    let free_m: Vec<usize> = (0..motion.names.len()).filter(|&m| !used[m]).collect();
    if free_r.len().saturating_mul(free_m.len()) <= FUZZY_MAX_PAIRS {
        let mut cands: Vec<(f32, usize, usize)> = Vec::new();
        for &r in &free_r {
            let rn = &rc.normal[r];
            let rl = rn.key.chars().count();
            if !(3..=FUZZY_MAX_LEN).contains(&rl) {
                continue;
            }
            for &m in &free_m {
                let mn = &mc.normal[m];
                let ml = mn.key.chars().count();
                if mn.side != rn.side
                    || !(3..=FUZZY_MAX_LEN).contains(&ml)
                    || !compatible(rslot[r], mslot[m])
                {
                    continue;
                }
                let score = fuzzy_score(&rn.key, &mn.key);
                if score >= FUZZY_THRESHOLD {
                    cands.push((score, r, m));
                }
            }
        }
        cands.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
        for (score, r, m) in cands {
            if bound[r].is_none() && !used[m] {
                bound[r] = Some((m, MatchMethod::Fuzzy { score }));
                used[m] = true;
            }
        }
    }

    // Drop the placeholders of repeated rig names and list what stayed unmatched.
    let bound: Vec<Option<(usize, MatchMethod)>> = bound
        .into_iter()
        .map(|b| b.filter(|&(m, _)| m < motion.names.len()))
        .collect();
    let mut matched = vec![false; motion.names.len()];
    for &(m, _) in bound.iter().flatten() {
        matched[m] = true;
    }
    let entries = rig
        .names
        .iter()
        .enumerate()
        .map(|(r, name)| MappingEntry {
            rig: name.clone(),
            motion: bound[r].map(|(m, _)| motion.names[m].clone()),
            method: bound[r].map(|(_, k)| k),
            slot: rslot[r],
            side: rc.normal[r].side,
        })
        .collect();
    let mut mapping = Mapping {
        rig: rig.label.clone(),
        motion: motion.label.clone(),
        rig_family: rc.family,
        motion_family: mc.family,
        entries,
        unmatched_motion: (0..motion.names.len())
            .filter(|&m| !matched[m])
            .map(|m| motion.names[m].clone())
            .collect(),
        warnings: Vec::new(),
    };
    for (r, m) in conflicts {
        mapping.warnings.push(Diagnostic::warning(
            "slot-conflict",
            format!(
                "rig joint {r:?} and motion joint {m:?} have matching names but mean different \
                     body parts in their families; not matched by name"
            ),
        ));
    }
    let warnings = ambiguity_warnings(&mapping, rig, motion, &rc, &mc, &rslot, &mslot);
    mapping.warnings.extend(warnings);
    mapping
}

/// Warnings for the known ambiguities: Leg names across families, spine and neck counts, unkeyed
/// helper joints in the motion.
fn ambiguity_warnings(
    mapping: &Mapping,
    rig: &JointSet,
    motion: &JointSet,
    rc: &SetContext,
    mc: &SetContext,
    rslot: &[Option<Slot>],
    mslot: &[Option<Slot>],
) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    let motion_index = motion.index_by_name();
    let mut rig_of_motion: Vec<Option<&str>> = vec![None; motion.names.len()];
    for e in &mapping.entries {
        if let Some(&m) = e.motion.as_deref().and_then(|m| motion_index.get(m)) {
            rig_of_motion[m] = Some(e.rig.as_str());
        }
    }
    let describe = |names: &[String], ctx: &SetContext, slots: &[Option<Slot>], i: usize| {
        let slot = slots
            .get(i)
            .copied()
            .flatten()
            .map_or("no slot".to_string(), Slot::name);
        let _ = ctx;
        format!("{:?} read as {slot}", names[i])
    };

    // "Leg": thigh in old Biped names, calf in CMU and Mixamo names.
    if rc.family != mc.family && (rc.family == Family::Biped || mc.family == Family::Biped) {
        let is_leg =
            |ctx: &SetContext, i: usize| ctx.normal.get(i).is_some_and(|n| n.stem() == "leg");
        let mut involved = Vec::new();
        for e in &mapping.entries {
            let (Some(r), Some(m)) = (
                rig.find(&e.rig),
                e.motion.as_deref().and_then(|m| motion.find(m)),
            ) else {
                continue;
            };
            if is_leg(rc, r) || is_leg(mc, m) {
                involved.push(format!(
                    "{} -> {}",
                    describe(&rig.names, rc, rslot, r),
                    describe(&motion.names, mc, mslot, m)
                ));
            }
        }
        if !involved.is_empty() {
            out.push(Diagnostic::warning(
                "leg-ambiguity",
                format!(
                    "\"Leg\" means the thigh in old Biped names but the calf in CMU and Mixamo names; \
                     rig names are {}, motion names are {}; check: {}",
                    rc.family.name(),
                    mc.family.name(),
                    involved.join("; ")
                ),
            ));
        }
    }

    // Chain counts.
    for (slot, code) in [(Slot::Spine, "spine-count"), (Slot::Neck, "neck-count")] {
        let rj: Vec<&str> = (0..rig.names.len())
            .filter(|&i| rslot[i] == Some(slot))
            .map(|i| rig.names[i].as_str())
            .collect();
        let mj: Vec<&str> = (0..motion.names.len())
            .filter(|&i| mslot[i] == Some(slot))
            .map(|i| motion.names[i].as_str())
            .collect();
        if rj.len() != mj.len() && !rj.is_empty() && !mj.is_empty() {
            out.push(
                Diagnostic::warning(
                    code,
                    format!(
                        "the rig has {} {} joints ({}) but the motion has {} ({}); unpaired ones stay \
                         unmatched and their rotation is lost",
                        rj.len(),
                        slot.name(),
                        rj.join(", "),
                        mj.len(),
                        mj.join(", ")
                    ),
                )
                .with_figure("rig", rj.len() as f64)
                .with_figure("motion", mj.len() as f64),
            );
        }
    }

    // Unkeyed helpers in the motion.
    let unkeyed: Vec<String> = (0..motion.names.len())
        .filter(|&i| !motion.keyed.get(i).copied().unwrap_or(true))
        .map(|i| match rig_of_motion[i] {
            Some(r) => format!("{} (bound to {r})", motion.names[i]),
            None => motion.names[i].clone(),
        })
        .collect();
    if !unkeyed.is_empty() {
        out.push(
            Diagnostic::warning(
                "unkeyed-helpers",
                format!(
                    "motion joints without animation (helpers or constant channels): {}; rig joints \
                     bound to them keep one fixed pose",
                    unkeyed.join(", ")
                ),
            )
            .with_figure("count", unkeyed.len() as f64),
        );
    }
    out
}

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

fn label_suffix(label: &str) -> String {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalise_folds_prefixes_sides_and_case() {
        let n = |s: &str| {
            let n = normalise(s);
            (n.side, n.key)
        };
        assert_eq!(n("Bip01 L UpperArm"), (Side::Left, "upperarm".into()));
        assert_eq!(n("Bip01_R_Forearm"), (Side::Right, "forearm".into()));
        assert_eq!(n("mixamorig:LeftForeArm"), (Side::Left, "forearm".into()));
        assert_eq!(n("Armature|DEF-thigh.L"), (Side::Left, "thigh".into()));
        assert_eq!(n("LHipJoint"), (Side::Left, "hipjoint".into()));
        assert_eq!(n("Spine1"), (Side::Centre, "spine1".into()));
        assert_eq!(n("Bip01"), (Side::Centre, "bip01".into()));
        assert_eq!(n("ValveBiped.Bip01_L_Hand"), (Side::Left, "hand".into()));
        assert_eq!(n("ns:RightHandIndex1"), (Side::Right, "handindex1".into()));
    }

    #[test]
    fn match_method_serialises_and_displays() {
        let m = MatchMethod::Synonym { slot: Slot::Thigh };
        assert_eq!(
            serde_json::to_string(&m).unwrap(),
            r#"{"method":"synonym","slot":"thigh"}"#
        );
        assert_eq!(m.to_string(), "synonym (thigh)");
        let f = MatchMethod::Fuzzy { score: 0.5 };
        assert_eq!(
            serde_json::to_string(&f).unwrap(),
            r#"{"method":"fuzzy","score":0.5}"#
        );
        assert_eq!(f.to_string(), "fuzzy (0.50)");
        assert_eq!(
            serde_json::to_string(&MatchMethod::Exact).unwrap(),
            r#"{"method":"exact"}"#
        );
    }

    #[test]
    fn fuzzy_score_is_one_minus_relative_distance() {
        assert_eq!(fuzzy_score("forarm", "forearm"), 1.0 - 1.0 / 7.0);
        assert_eq!(fuzzy_score("abc", "abc"), 1.0);
        assert_eq!(fuzzy_score("", ""), 0.0);
    }
}
