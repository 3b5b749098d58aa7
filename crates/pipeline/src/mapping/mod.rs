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

mod file;
mod joints;
mod matching;
mod names;
#[cfg(test)]
mod tests;

pub use file::{apply_mapping, read_mapping, write_mapping, MappingError, MAPPING_FILE_VERSION};
pub use joints::JointSet;
pub use matching::{
    fuzzy_score, map_joints, Mapping, MappingEntry, MatchMethod, FUZZY_MAX_LEN, FUZZY_MAX_PAIRS,
    FUZZY_THRESHOLD,
};
pub use names::{normalise, Family, NormalName, Side, Slot};
