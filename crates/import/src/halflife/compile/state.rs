//! The tables studiomdl fills while it reads a QC: reference models, animations, sequences,
//! textures and the rest, with the lookups the readers share.

use crate::halflife::qc::{atoi, Tok};
use crate::halflife::smd::{self};
use crate::Resolver;
use sinew_core::format::game::{material_flags, motion_flags};
use sinew_scene::Diagnostic;

/// Most bones a GoldSrc model may have (`MAXSTUDIOBONES`).
pub const MAX_BONES: usize = 128;
/// Most frames one animation may have (`MAXSTUDIOANIMATIONS`).
pub const MAX_FRAMES: i32 = 512;

/// The half-life activity names, by number (`ACT_RESET` = 0 ... `ACT_FLINCH_RIGHTLEG` = 76).
pub const ACTIVITIES: [&str; 77] = [
    "ACT_RESET",
    "ACT_IDLE",
    "ACT_GUARD",
    "ACT_WALK",
    "ACT_RUN",
    "ACT_FLY",
    "ACT_SWIM",
    "ACT_HOP",
    "ACT_LEAP",
    "ACT_FALL",
    "ACT_LAND",
    "ACT_STRAFE_LEFT",
    "ACT_STRAFE_RIGHT",
    "ACT_ROLL_LEFT",
    "ACT_ROLL_RIGHT",
    "ACT_TURN_LEFT",
    "ACT_TURN_RIGHT",
    "ACT_CROUCH",
    "ACT_CROUCHIDLE",
    "ACT_STAND",
    "ACT_USE",
    "ACT_SIGNAL1",
    "ACT_SIGNAL2",
    "ACT_SIGNAL3",
    "ACT_TWITCH",
    "ACT_COWER",
    "ACT_SMALL_FLINCH",
    "ACT_BIG_FLINCH",
    "ACT_RANGE_ATTACK1",
    "ACT_RANGE_ATTACK2",
    "ACT_MELEE_ATTACK1",
    "ACT_MELEE_ATTACK2",
    "ACT_RELOAD",
    "ACT_ARM",
    "ACT_DISARM",
    "ACT_EAT",
    "ACT_DIESIMPLE",
    "ACT_DIEBACKWARD",
    "ACT_DIEFORWARD",
    "ACT_DIEVIOLENT",
    "ACT_BARNACLE_HIT",
    "ACT_BARNACLE_PULL",
    "ACT_BARNACLE_CHOMP",
    "ACT_BARNACLE_CHEW",
    "ACT_SLEEP",
    "ACT_INSPECT_FLOOR",
    "ACT_INSPECT_WALL",
    "ACT_IDLE_ANGRY",
    "ACT_WALK_HURT",
    "ACT_RUN_HURT",
    "ACT_HOVER",
    "ACT_GLIDE",
    "ACT_FLY_LEFT",
    "ACT_FLY_RIGHT",
    "ACT_DETECT_SCENT",
    "ACT_SNIFF",
    "ACT_BITE",
    "ACT_THREAT_DISPLAY",
    "ACT_FEAR_DISPLAY",
    "ACT_EXCITED",
    "ACT_SPECIAL_ATTACK1",
    "ACT_SPECIAL_ATTACK2",
    "ACT_COMBAT_IDLE",
    "ACT_WALK_SCARED",
    "ACT_RUN_SCARED",
    "ACT_VICTORY_DANCE",
    "ACT_DIE_HEADSHOT",
    "ACT_DIE_CHESTSHOT",
    "ACT_DIE_GUTSHOT",
    "ACT_DIE_BACKSHOT",
    "ACT_FLINCH_HEAD",
    "ACT_FLINCH_CHEST",
    "ACT_FLINCH_STOMACH",
    "ACT_FLINCH_LEFTARM",
    "ACT_FLINCH_RIGHTARM",
    "ACT_FLINCH_LEFTLEG",
    "ACT_FLINCH_RIGHTLEG",
];

/// An activity's number: a known name, or `ACT_<n>`; 0 when neither.
pub fn activity_number(token: &str) -> i32 {
    if let Some(i) = ACTIVITIES
        .iter()
        .position(|a| a.eq_ignore_ascii_case(token))
    {
        return i as i32;
    }
    // `get` rather than indexing: the token may hold any UTF-8, and byte 4 need not start a character.
    if let (Some(head), Some(rest)) = (token.get(..4), token.get(4..)) {
        if head.eq_ignore_ascii_case("ACT_") && !rest.is_empty() {
            return atoi(rest);
        }
    }
    0
}

/// A motion or controller channel name (`X` ... `AZR`), as studiomdl's `lookupControl`.
pub fn control(token: &str) -> Option<u32> {
    motion_flags::NAMES
        .iter()
        .take(15)
        .find(|(_, n)| n.eq_ignore_ascii_case(token))
        .map(|(b, _)| *b)
}

/// A triangle corner of a reference model: vertex, normal, uv as written.
pub(super) type SrcCorner = (usize, usize, [f32; 2]);

/// A `$hbox` line: group, bone name, corners, and the command's token for errors.
pub(super) type HboxLine = (i32, String, [f32; 3], [f32; 3], Tok);

/// A bone of the union: name, parent, default position and rotation.
pub(super) type UnionBone = (String, Option<usize>, [f32; 3], [f32; 3]);

/// A reference model as loaded: its SMD nodes and skeleton, and its submodel in model-local bones.
pub(super) struct RefModel {
    pub(super) name: String,
    pub(super) nodes: Vec<smd::Node>,
    /// Per node: position (scaled) and clipped rotation, from the skeleton block (last value wins).
    pub(super) skeleton: Vec<([f32; 3], [f32; 3])>,
    /// Vertices in their bone's space (two decimals) with the model-local bone.
    pub(super) verts: Vec<([f32; 3], usize)>,
    /// Normals in their bone's space with the model-local bone and skin slot.
    pub(super) normals: Vec<([f32; 3], usize, usize)>,
    /// Meshes: skin slot and triangles of (vertex, normal, uv) as written (v up).
    pub(super) meshes: Vec<(usize, Vec<[SrcCorner; 3]>)>,
    /// Node index to global bone, after the union.
    pub(super) bonemap: Vec<Option<usize>>,
}

/// One animation of a sequence: frames over its own nodes.
pub(super) struct Anim {
    pub(super) nodes: Vec<smd::Node>,
    /// Per frame, per node: position and rotation.
    pub(super) frames: Vec<Vec<([f32; 3], [f32; 3])>>,
}

#[derive(Default)]
pub(super) struct Sequence {
    pub(super) label: String,
    pub(super) fps: f32,
    pub(super) looping: bool,
    pub(super) activity: i32,
    pub(super) weight: i32,
    pub(super) events: Vec<(i32, i32, i32, String)>,
    pub(super) motion: u32,
    pub(super) blend: (u32, f32, f32),
    pub(super) nodes: (i32, i32, i32),
    pub(super) anims: Vec<Anim>,
}

pub(super) struct Texture {
    pub(super) name: String,
    pub(super) flags: u32,
}

pub(super) struct State<'a> {
    pub(super) qc: &'a str,
    pub(super) resolve: Resolver<'a>,
    /// A missing SMD is a warning (`--allow-missing`), not an error.
    pub(super) allow_missing: bool,
    /// SMDs read so far.
    pub(super) smds_read: usize,
    /// The first SMD that could not be read (with `allow_missing`), as the error a QC none of
    /// whose SMDs can be read gives.
    pub(super) first_missing: Option<crate::ImportError>,
    pub(super) diagnostics: Vec<Diagnostic>,
    pub(super) cd: String,
    pub(super) default_scale: f32,
    pub(super) default_adjust: [f32; 3],
    pub(super) default_zrotation: f64,
    pub(super) models: Vec<RefModel>,
    pub(super) parts: Vec<(String, Vec<Option<usize>>)>,
    pub(super) textures: Vec<Texture>,
    pub(super) texture_groups: Vec<Vec<Vec<usize>>>,
    pub(super) skinref_count: usize,
    pub(super) sequences: Vec<Sequence>,
    pub(super) controllers: Vec<(i32, String, u32, f32, f32, Tok)>,
    pub(super) hitboxes: Vec<HboxLine>,
    pub(super) hitgroups: Vec<(i32, String)>,
    pub(super) attachments: Vec<(String, [f32; 3], Tok)>,
    pub(super) eye: [f32; 3],
    pub(super) renames: Vec<(String, String)>,
    pub(super) mirrored: Vec<String>,
}

pub(super) fn lookup_texture(s: &mut State, name: &str) -> usize {
    if let Some(i) = s
        .textures
        .iter()
        .position(|t| t.name.eq_ignore_ascii_case(name))
    {
        return i;
    }
    let flags = if name.to_ascii_lowercase().contains("chrome") {
        material_flags::FLATSHADE | material_flags::CHROME
    } else {
        0
    };
    s.textures.push(Texture {
        name: name.to_string(),
        flags,
    });
    s.textures.len() - 1
}

pub(super) fn mirror_flags(nodes: &[smd::Node], mirrored: &[String]) -> Vec<bool> {
    let mut out = vec![false; nodes.len()];
    for (k, n) in nodes.iter().enumerate() {
        out[k] = mirrored.contains(&n.name) || n.parent.is_some_and(|p| p < k && out[p]);
    }
    out
}
