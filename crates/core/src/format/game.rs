//! Game data a model carries besides its skeleton, meshes and clips — attachments, hit boxes, bone
//! controllers, body groups, skin families, material flags, and per clip its activity, events, motion
//! extraction and blend parameters — kept from the source (Half-Life MDL and QC) in the `GAME` section
//! (format 1.3). The runtime does not interpret it; games and tools read it. Joints, meshes, materials
//! and clips are referred to by name, so pipeline steps that reorder or rename nothing keep it valid.

/// Everything of a model's game data; empty when the source had none.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GameData {
    /// Eye position in model space, if the source gave one.
    pub eye_position: Option<[f32; 3]>,
    /// Named points attached to joints.
    pub attachments: Vec<Attachment>,
    /// Hit boxes, one joint each.
    pub hitboxes: Vec<Hitbox>,
    /// Bone controllers: joint channels a game drives directly.
    pub controllers: Vec<BoneController>,
    /// Body groups: sets of interchangeable meshes, the first the default.
    pub body_groups: Vec<BodyGroup>,
    /// Skin families: per family, the material used in each skin slot (family 0 is the default).
    pub skin_families: Vec<Vec<String>>,
    /// Material flags of the source (Half-Life values: see [`material_flags`]).
    pub material_flags: Vec<MaterialFlags>,
    /// Per-clip data.
    pub clips: Vec<ClipGameData>,
    /// Transition graph between sequence nodes: `nodes x nodes` bytes, row = from node, column = to
    /// node; empty when the source had none.
    pub transitions: Vec<u8>,
    /// Number of nodes of the transition graph (`transitions.len() == nodes * nodes`).
    pub transition_nodes: u32,
}

impl GameData {
    /// True when there is nothing to store.
    pub fn is_empty(&self) -> bool {
        *self == GameData::default()
    }

    /// The record of a clip, by name.
    pub fn clip(&self, name: &str) -> Option<&ClipGameData> {
        self.clips.iter().find(|c| c.clip == name)
    }
}

/// A named point fixed to a joint.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Attachment {
    /// Name (may be empty: Half-Life attachments are numbered).
    pub name: String,
    /// The joint it moves with.
    pub joint: String,
    /// Position in the joint's space.
    pub offset: [f32; 3],
}

/// An axis-aligned box in a joint's space, used for hit detection.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Hitbox {
    /// The joint it moves with.
    pub joint: String,
    /// Hit group (Half-Life: 0 generic, 1 head, 2 chest, 3 stomach, 4-7 arms and legs).
    pub group: i32,
    /// Minimum corner.
    pub min: [f32; 3],
    /// Maximum corner.
    pub max: [f32; 3],
}

/// A joint channel driven by the game (a head turning towards a target, a mouth opening).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BoneController {
    /// Controller number (Half-Life: 0-3, 4 is the mouth).
    pub index: i32,
    /// The joint it moves.
    pub joint: String,
    /// Channel as motion flags ([`motion_flags`]): one of X, Y, Z, XR, YR, ZR, possibly with RLOOP.
    pub channel: u32,
    /// Value at controller input 0 (degrees for rotations, units for translations).
    pub start: f32,
    /// Value at controller input 1.
    pub end: f32,
    /// Rest value as stored by the source.
    pub rest: i32,
}

/// A set of interchangeable meshes (Half-Life body part): the first is shown by default.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BodyGroup {
    /// Group name.
    pub name: String,
    /// Mesh names, in choice order; an empty name is a blank choice (nothing drawn).
    pub meshes: Vec<String>,
}

/// Flags of one material.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MaterialFlags {
    /// Material name.
    pub material: String,
    /// Flags ([`material_flags`]).
    pub flags: u32,
}

/// What a source says about one clip beyond its keys.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ClipGameData {
    /// Clip name.
    pub clip: String,
    /// Activity number (Half-Life `ACT_*`; 0 = none).
    pub activity: i32,
    /// Activity weight.
    pub activity_weight: i32,
    /// Events, by frame.
    pub events: Vec<ClipEvent>,
    /// Motion extraction flags ([`motion_flags`], e.g. LX).
    pub motion_type: u32,
    /// The joint whose motion was extracted (empty when none).
    pub motion_joint: String,
    /// Movement over the whole clip that was taken out of the keys (model units).
    pub linear_movement: [f32; 3],
    /// Blend parameters when the clip is one blend of a blended sequence.
    pub blend: Option<ClipBlend>,
    /// Transition-graph node this clip starts in.
    pub entry_node: i32,
    /// Transition-graph node this clip ends in.
    pub exit_node: i32,
    /// Node flags (Half-Life: 1 = the transition may run in reverse).
    pub node_flags: i32,
}

/// An event fired when playback passes a frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ClipEvent {
    /// Frame number (frame k is at time k / sample rate).
    pub frame: i32,
    /// Event number (Half-Life: 1004 plays a sound, 5001 a muzzle flash, ...).
    pub event: i32,
    /// Event type as stored.
    pub kind: i32,
    /// Options text (a sound path, ...).
    pub options: String,
}

/// One blend of a blended sequence: the clips `sequence.blend0 ...` share `sequence` and `count`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ClipBlend {
    /// The sequence the blends came from.
    pub sequence: String,
    /// This blend's index.
    pub index: u32,
    /// Number of blends of the sequence.
    pub count: u32,
    /// Blend controls as motion flags ([`motion_flags`]; 0 = unused).
    pub types: [u32; 2],
    /// Control value of the first blend.
    pub start: [f32; 2],
    /// Control value of the last blend.
    pub end: [f32; 2],
}

/// Half-Life motion and controller channel flags (`studio.h` `STUDIO_X` ...).
pub mod motion_flags {
    /// Position X.
    pub const X: u32 = 0x1;
    /// Position Y.
    pub const Y: u32 = 0x2;
    /// Position Z.
    pub const Z: u32 = 0x4;
    /// Rotation X.
    pub const XR: u32 = 0x8;
    /// Rotation Y.
    pub const YR: u32 = 0x10;
    /// Rotation Z.
    pub const ZR: u32 = 0x20;
    /// Linear motion X (extracted).
    pub const LX: u32 = 0x40;
    /// Linear motion Y.
    pub const LY: u32 = 0x80;
    /// Linear motion Z.
    pub const LZ: u32 = 0x100;
    /// Automove X.
    pub const AX: u32 = 0x200;
    /// Automove Y.
    pub const AY: u32 = 0x400;
    /// Automove Z.
    pub const AZ: u32 = 0x800;
    /// Automove rotation X.
    pub const AXR: u32 = 0x1000;
    /// Automove rotation Y.
    pub const AYR: u32 = 0x2000;
    /// Automove rotation Z.
    pub const AZR: u32 = 0x4000;
    /// Controller wraps around (360 degrees).
    pub const RLOOP: u32 = 0x8000;

    /// The flags' names, in bit order, as QC files spell them.
    pub const NAMES: [(u32, &str); 16] = [
        (X, "X"),
        (Y, "Y"),
        (Z, "Z"),
        (XR, "XR"),
        (YR, "YR"),
        (ZR, "ZR"),
        (LX, "LX"),
        (LY, "LY"),
        (LZ, "LZ"),
        (AX, "AX"),
        (AY, "AY"),
        (AZ, "AZ"),
        (AXR, "AXR"),
        (AYR, "AYR"),
        (AZR, "AZR"),
        (RLOOP, "RLOOP"),
    ];

    /// The names of the set flags joined by `|`, or an empty string.
    pub fn describe(flags: u32) -> String {
        let mut names: Vec<String> = NAMES
            .iter()
            .filter(|(bit, _)| flags & bit != 0)
            .map(|(_, n)| (*n).to_string())
            .collect();
        let unknown = flags & !NAMES.iter().fold(0, |a, (b, _)| a | b);
        if unknown != 0 {
            names.push(format!("{unknown:#x}"));
        }
        names.join("|")
    }
}

/// Half-Life texture flags (`studio.h` `STUDIO_NF_*`).
pub mod material_flags {
    /// Flat shading.
    pub const FLATSHADE: u32 = 0x1;
    /// Chrome (environment-mapped).
    pub const CHROME: u32 = 0x2;
    /// Full bright (no lighting).
    pub const FULLBRIGHT: u32 = 0x4;
    /// No mipmaps.
    pub const NOMIPS: u32 = 0x8;
    /// Alpha.
    pub const ALPHA: u32 = 0x10;
    /// Additive blending.
    pub const ADDITIVE: u32 = 0x20;
    /// Masked: palette index 255 is transparent.
    pub const MASKED: u32 = 0x40;

    /// The flags' names, in bit order.
    pub const NAMES: [(u32, &str); 7] = [
        (FLATSHADE, "flatshade"),
        (CHROME, "chrome"),
        (FULLBRIGHT, "fullbright"),
        (NOMIPS, "nomips"),
        (ALPHA, "alpha"),
        (ADDITIVE, "additive"),
        (MASKED, "masked"),
    ];

    /// The names of the set flags, with unknown bits in hexadecimal.
    pub fn describe(flags: u32) -> Vec<String> {
        let mut names: Vec<String> = NAMES
            .iter()
            .filter(|(bit, _)| flags & bit != 0)
            .map(|(_, n)| (*n).to_string())
            .collect();
        let unknown = flags & !NAMES.iter().fold(0, |a, (b, _)| a | b);
        if unknown != 0 {
            names.push(format!("{unknown:#x}"));
        }
        names
    }
}

/// Checks the rules a writer enforces: finite numbers, a square transition table, skin families of
/// equal length. Returns the reason of the first broken rule.
pub(crate) fn check(g: &GameData) -> Result<(), String> {
    let finite = |v: &[f32], what: &str| {
        if v.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(format!("{what} is not finite"))
        }
    };
    if let Some(e) = &g.eye_position {
        finite(e, "eye position")?;
    }
    for a in &g.attachments {
        finite(&a.offset, "attachment offset")?;
    }
    for h in &g.hitboxes {
        finite(&h.min, "hit box corner")?;
        finite(&h.max, "hit box corner")?;
    }
    for c in &g.controllers {
        finite(&[c.start, c.end], "controller range")?;
    }
    for c in &g.clips {
        finite(&c.linear_movement, "linear movement")?;
        if let Some(b) = &c.blend {
            finite(&b.start, "blend start")?;
            finite(&b.end, "blend end")?;
        }
    }
    if let Some(first) = g.skin_families.first() {
        if g.skin_families.iter().any(|f| f.len() != first.len()) {
            return Err("skin families differ in length".into());
        }
    }
    let n = g.transition_nodes as usize;
    if n.checked_mul(n) != Some(g.transitions.len()) {
        return Err(format!(
            "{} transition bytes for {n} nodes (need {n} x {n})",
            g.transitions.len()
        ));
    }
    Ok(())
}
