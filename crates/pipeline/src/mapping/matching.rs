//! Matching rig joints to motion joints in four stages (exact, normalised, synonym slot, fuzzy) and
//! the ambiguity warnings.

use super::joints::JointSet;
use super::names::{normalise, Family, NormalName, Side, Slot};
use serde::Serialize;
use sinew_scene::Diagnostic;
use std::collections::{HashMap, HashSet};
use std::fmt;

/// Lowest fuzzy score (1 - edit distance / longer length, on normalised names) accepted as a match.
pub const FUZZY_THRESHOLD: f32 = 0.75;

/// Fuzzy matching is skipped when unmatched rig joints times unmatched motion joints exceeds this.
pub const FUZZY_MAX_PAIRS: usize = 1_000_000;

/// Normalised names longer than this (in characters) take no part in fuzzy matching.
pub const FUZZY_MAX_LEN: usize = 64;

/// Per-set facts the slot rules look at (what else is on the same side).
pub(super) struct SetContext {
    pub(super) family: Family,
    pub(super) normal: Vec<NormalName>,
    pub(super) keys: HashSet<(Side, String)>,
    pub(super) stems: HashSet<(Side, String)>,
}

impl SetContext {
    pub(super) fn new(names: &[String]) -> Self {
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
    pub(super) fn has_key(&self, side: Side, key: &str) -> bool {
        self.keys.contains(&(side, key.to_string()))
    }
    pub(super) fn has_stem(&self, side: Side, stems: &[&str]) -> bool {
        stems
            .iter()
            .any(|s| self.stems.contains(&(side, (*s).to_string())))
    }

    /// The slot of joint `i` (the rules of stage 3).
    pub(super) fn slot(&self, i: usize) -> Option<Slot> {
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
pub(super) fn edit_distance(a: &[char], b: &[char]) -> usize {
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
pub(super) fn repeated_names(names: &[String]) -> Vec<bool> {
    let mut seen = HashSet::with_capacity(names.len());
    names.iter().map(|n| !seen.insert(n.as_str())).collect()
}

pub(super) fn compatible(a: Option<Slot>, b: Option<Slot>) -> bool {
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
pub(super) fn ambiguity_warnings(
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
