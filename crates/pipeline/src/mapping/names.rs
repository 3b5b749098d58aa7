//! Name normalisation and the synonym slots: sides, prefixes, camel case, naming families.

use serde::Serialize;

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
pub(super) fn strip_prefix_ci<'a>(s: &'a str, prefix: &str) -> Option<&'a str> {
    let head = s.get(..prefix.len())?;
    if head.eq_ignore_ascii_case(prefix) {
        s.get(prefix.len()..)
    } else {
        None
    }
}

/// Length of a `Bip01 ` / `Bip01_` style prefix at the start of `s`, if followed by more text.
pub(super) fn biped_prefix_len(s: &str) -> Option<usize> {
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
pub(super) fn is_biped_name(name: &str) -> bool {
    let s = strip_prefix_ci(name.trim(), "ValveBiped.").unwrap_or(name.trim());
    let b = s.as_bytes();
    b.len() >= 4
        && b[..3].eq_ignore_ascii_case(b"bip")
        && b[3..].first().is_some_and(|c| c.is_ascii_digit())
}

/// Splits camel case and digit runs: `LHipJoint` -> `L Hip Joint`, `Spine1` -> `Spine 1`.
pub(super) fn camel_words(part: &str, out: &mut Vec<String>) {
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

pub(super) fn side_of(word: &str) -> Option<Side> {
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
