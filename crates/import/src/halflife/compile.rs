//! Compiling a QC script and its SMD files into a studio model the way GoldSrc's studiomdl does, so
//! that converting the QC gives what converting the MDL studiomdl would write gives: the union of the
//! bones that vertices use (and their ancestors) in first-use order, vertices moved into their bone's
//! space and kept to two decimals, normals merged within 2 degrees, the default 90-degree turn of
//! every root bone in animations, motion extraction, looping sequences closed, and animation values
//! quantised to 16 bits per channel with studiomdl's per-bone scales. docs/formats/halflife.md lists
//! each rule with where it comes from.

use super::model::{
    BodyPart, Corner, StudioBone, StudioController, StudioMesh, StudioModel, StudioSequence,
    StudioTexture, StudioVertex, Submodel,
};
use super::qc::{atoi, Cursor, Script, Tok};
use super::scene::euler_to_quat;
use super::smd::{self, Smd};
use crate::{ImportError, Resolver};
use sinew_core::format::game::{material_flags, motion_flags};
use sinew_core::glam::{Mat3, Vec3};
use sinew_scene::Diagnostic;
use std::f64::consts::PI;

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
    if token.len() > 4 && token[..4].eq_ignore_ascii_case("ACT_") {
        return atoi(&token[4..]);
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
type SrcCorner = (usize, usize, [f32; 2]);

/// A `$hbox` line: group, bone name, corners, and the command's token for errors.
type HboxLine = (i32, String, [f32; 3], [f32; 3], Tok);

/// A bone of the union: name, parent, default position and rotation.
type UnionBone = (String, Option<usize>, [f32; 3], [f32; 3]);

/// A reference model as loaded: its SMD nodes and skeleton, and its submodel in model-local bones.
struct RefModel {
    name: String,
    nodes: Vec<smd::Node>,
    /// Per node: position (scaled) and clipped rotation, from the skeleton block (last value wins).
    skeleton: Vec<([f32; 3], [f32; 3])>,
    /// Vertices in their bone's space (two decimals) with the model-local bone.
    verts: Vec<([f32; 3], usize)>,
    /// Normals in their bone's space with the model-local bone and skin slot.
    normals: Vec<([f32; 3], usize, usize)>,
    /// Meshes: skin slot and triangles of (vertex, normal, uv) as written (v up).
    meshes: Vec<(usize, Vec<[SrcCorner; 3]>)>,
    /// Node index to global bone, after the union.
    bonemap: Vec<Option<usize>>,
}

/// One animation of a sequence: frames over its own nodes.
struct Anim {
    nodes: Vec<smd::Node>,
    /// Per frame, per node: position and rotation.
    frames: Vec<Vec<([f32; 3], [f32; 3])>>,
}

#[derive(Default)]
struct Sequence {
    label: String,
    fps: f32,
    looping: bool,
    activity: i32,
    weight: i32,
    events: Vec<(i32, i32, i32, String)>,
    motion: u32,
    blend: (u32, f32, f32),
    nodes: (i32, i32, i32),
    anims: Vec<Anim>,
}

struct Texture {
    name: String,
    flags: u32,
}

struct State<'a> {
    qc: &'a str,
    resolve: Resolver<'a>,
    diagnostics: Vec<Diagnostic>,
    cd: String,
    default_scale: f32,
    default_adjust: [f32; 3],
    default_zrotation: f64,
    models: Vec<RefModel>,
    parts: Vec<(String, Vec<Option<usize>>)>,
    textures: Vec<Texture>,
    texture_groups: Vec<Vec<Vec<usize>>>,
    skinref_count: usize,
    sequences: Vec<Sequence>,
    controllers: Vec<(i32, String, u32, f32, f32, Tok)>,
    hitboxes: Vec<HboxLine>,
    hitgroups: Vec<(i32, String)>,
    attachments: Vec<(String, [f32; 3], Tok)>,
    eye: [f32; 3],
    renames: Vec<(String, String)>,
    mirrored: Vec<String>,
}

/// Compiles a QC script (its includes already expanded).
pub fn compile(
    qc: &str,
    script: &Script,
    resolve: Resolver<'_>,
) -> Result<(StudioModel, Vec<Diagnostic>), ImportError> {
    let mut s = State {
        qc,
        resolve,
        diagnostics: Vec::new(),
        cd: String::new(),
        default_scale: 1.0,
        default_adjust: [0.0; 3],
        default_zrotation: PI / 2.0,
        models: Vec::new(),
        parts: Vec::new(),
        textures: Vec::new(),
        texture_groups: Vec::new(),
        skinref_count: 0,
        sequences: Vec::new(),
        controllers: Vec::new(),
        hitboxes: Vec::new(),
        hitgroups: Vec::new(),
        attachments: Vec::new(),
        eye: [0.0; 3],
        renames: Vec::new(),
        mirrored: Vec::new(),
    };
    let mut c = Cursor::new(script);
    while let Some(t) = c.next_any() {
        if !t.is_command() {
            // studiomdl skips everything up to the next line that starts with a command.
            continue;
        }
        let cmd = t.text.to_ascii_lowercase();
        match cmd.as_str() {
            "$modelname" | "$cdtexture" | "$cliptotextures" | "$externaltextures"
            | "$sequencegroupsize" | "$sequencegroup" | "$gamma" | "$flags" | "$bbox" | "$cbox"
            | "$root" | "$pivot" | "$lod" => while c.next_same_line().is_some() {},
            "$cd" => s.cd = c.expect("$cd", "a folder")?.text.replace('\\', "/"),
            "$scale" => s.default_scale = c.number("$scale", "a scale")?,
            "$origin" => {
                for k in 0..3 {
                    s.default_adjust[k] = c.number("$origin", "a coordinate")?;
                }
                if c.available() {
                    let r = c.number("$origin", "a rotation")?;
                    s.default_zrotation = (f64::from(r) + 90.0) * (PI / 180.0);
                }
            }
            "$eyeposition" => {
                let a = c.number("$eyeposition", "x")?;
                let b = c.number("$eyeposition", "y")?;
                let z = c.number("$eyeposition", "z")?;
                // studiomdl turns the point so that the model looks down +x.
                s.eye = [-b, a, z];
            }
            "$body" => {
                let name = c.expect("$body", "a body part name")?.text.clone();
                s.parts.push((name, Vec::new()));
                studio(&mut s, &mut c, "$body")?;
            }
            "$bodygroup" => {
                let name = c.expect("$bodygroup", "a body group name")?.text.clone();
                s.parts.push((name, Vec::new()));
                loop {
                    let Some(t) = c.next_any() else {
                        return Err(script.error_at(
                            t_or(&c, t),
                            "$bodygroup",
                            "file ends before `}`",
                        ));
                    };
                    if t.is("{") {
                        continue;
                    }
                    if t.is("}") {
                        break;
                    }
                    if t.text.eq_ignore_ascii_case("studio") {
                        studio(&mut s, &mut c, "$bodygroup")?;
                    } else if t.text.eq_ignore_ascii_case("blank") {
                        if let Some(p) = s.parts.last_mut() {
                            p.1.push(None);
                        }
                    } else if t.is_command() {
                        return Err(script.error_at(
                            t,
                            "$bodygroup",
                            "a command inside $bodygroup (missing `}`)",
                        ));
                    }
                }
            }
            "$texturegroup" => texture_group(&mut s, &mut c, t)?,
            "$texrendermode" => {
                let tex = c.expect("$texrendermode", "a texture name")?.text.clone();
                let mode = c.expect("$texrendermode", "a render mode")?;
                let i = lookup_texture(&mut s, &tex);
                match mode.text.as_str() {
                    "additive" => s.textures[i].flags |= material_flags::ADDITIVE,
                    "masked" => s.textures[i].flags |= material_flags::MASKED,
                    other => {
                        return Err(script.error_at(
                            mode,
                            "$texrendermode",
                            format!("render mode {other:?} is not one of additive, masked"),
                        ))
                    }
                }
            }
            "$sequence" => sequence(&mut s, &mut c)?,
            "$controller" => {
                let idx = c.expect("$controller", "a controller number")?;
                let index = if idx.text.eq_ignore_ascii_case("mouth") {
                    4
                } else {
                    atoi(&idx.text)
                };
                let bone = c.expect("$controller", "a bone name")?.text.clone();
                let ty = c.expect("$controller", "a channel")?;
                let Some(mut channel) = control(&ty.text) else {
                    s.diagnostics.push(Diagnostic::warning(
                        "qc-controller-type",
                        format!(
                            "line {}: unknown controller type {:?}; controller ignored",
                            ty.line, ty.text
                        ),
                    ));
                    while c.next_same_line().is_some() {}
                    continue;
                };
                let start = c.number("$controller", "a start value")?;
                let end = c.number("$controller", "an end value")?;
                if channel & (motion_flags::XR | motion_flags::YR | motion_flags::ZR) != 0
                    && ((start + 360.0) as i32) % 360 == ((end + 360.0) as i32) % 360
                {
                    channel |= motion_flags::RLOOP;
                }
                s.controllers
                    .push((index, bone, channel, start, end, t.clone()));
            }
            "$hbox" => {
                let group = c.integer("$hbox", "a hit group")?;
                let bone = c.expect("$hbox", "a bone name")?.text.clone();
                let mut v = [0f32; 6];
                for x in &mut v {
                    *x = c.number("$hbox", "a corner coordinate")?;
                }
                s.hitboxes.push((
                    group,
                    bone,
                    [v[0], v[1], v[2]],
                    [v[3], v[4], v[5]],
                    t.clone(),
                ));
            }
            "$hgroup" => {
                let group = c.integer("$hgroup", "a hit group")?;
                let bone = c.expect("$hgroup", "a bone name")?.text.clone();
                s.hitgroups.push((group, bone));
            }
            "$attachment" => {
                let _index = c.integer("$attachment", "an attachment number")?;
                let bone = c.expect("$attachment", "a bone name")?.text.clone();
                let mut o = [0f32; 3];
                for x in &mut o {
                    *x = c.number("$attachment", "an offset")?;
                }
                while c.next_same_line().is_some() {}
                s.attachments.push((bone, o, t.clone()));
            }
            "$renamebone" => {
                let from = c.expect("$renamebone", "a bone name")?.text.clone();
                let to = c.expect("$renamebone", "a new name")?.text.clone();
                s.renames.push((from, to));
            }
            "$mirrorbone" => {
                let b = c.expect("$mirrorbone", "a bone name")?.text.clone();
                s.mirrored.push(b);
            }
            _ => {
                s.diagnostics.push(Diagnostic::warning(
                    "qc-unknown-command",
                    format!(
                        "{} line {}: unknown command {} ignored",
                        script.files.get(t.file).map_or("?", String::as_str),
                        t.line,
                        t.text
                    ),
                ));
                while c.next_same_line().is_some() {}
            }
        }
    }
    build(s, script)
}

fn t_or<'a>(c: &Cursor<'a>, fallback: &'a Tok) -> &'a Tok {
    c.last().unwrap_or(fallback)
}

/// The path of an SMD named in the script: `$cd` joined with the name, `.smd` added.
fn smd_path(cd: &str, name: &str) -> String {
    let name = name.replace('\\', "/");
    let name = if name.to_ascii_lowercase().ends_with(".smd") {
        name
    } else {
        format!("{name}.smd")
    };
    if cd.is_empty() || cd == "." || cd == "./" {
        name
    } else {
        format!("{}/{name}", cd.trim_end_matches('/'))
    }
}

/// Reads an SMD the script names, or `None` with a warning when the file is missing.
fn read_smd(
    s: &mut State,
    name: &str,
    section: &str,
    line: usize,
) -> Result<Option<Smd>, ImportError> {
    let path = smd_path(&s.cd, name);
    match (s.resolve)(&path) {
        Ok(bytes) => smd::parse(&path, &bytes).map(Some),
        Err(e) => {
            s.diagnostics.push(Diagnostic::warning(
                "qc-missing-smd",
                format!(
                    "{} line {line} ({section}): cannot read {path}: {e}; left out",
                    s.qc
                ),
            ));
            Ok(None)
        }
    }
}

fn lookup_texture(s: &mut State, name: &str) -> usize {
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

/// studiomdl's `Option_Studio`: a reference SMD with its options, as one choice of the last part.
fn studio(s: &mut State, c: &mut Cursor, section: &str) -> Result<(), ImportError> {
    let tok = c.expect(section, "a reference SMD name")?;
    let name = tok.text.clone();
    let mut flip = true;
    let mut scale = s.default_scale;
    while let Some(t) = c.next_same_line() {
        if t.text.eq_ignore_ascii_case("reverse") {
            flip = false;
        } else if t.text.eq_ignore_ascii_case("scale") {
            scale = c.number(section, "a scale")?;
        }
    }
    let Some(smd) = read_smd(s, &name, section, tok.line)? else {
        if let Some(p) = s.parts.last_mut() {
            p.1.push(None);
        }
        return Ok(());
    };
    let model = reference_model(s, &name, &smd, flip, scale);
    s.models.push(model);
    let index = s.models.len() - 1;
    if let Some(p) = s.parts.last_mut() {
        p.1.push(Some(index));
    }
    Ok(())
}

/// Truncates to two decimals as studiomdl's `lookup_vertex` does (`(int)(x * 100) / 100.0`).
fn two_decimals(x: f32) -> f32 {
    (f64::from((x * 100.0) as i32) / 100.0) as f32
}

/// Wraps an angle into [-pi, pi), in double as studiomdl does, back to float.
fn clip_rotation(mut r: f32) -> f32 {
    let mut guard = 0;
    while f64::from(r) >= PI && guard < 64 {
        r = (f64::from(r) - PI * 2.0) as f32;
        guard += 1;
    }
    while f64::from(r) < -PI && guard < 128 {
        r = (f64::from(r) + PI * 2.0) as f32;
        guard += 1;
    }
    r
}

fn reference_model(s: &mut State, name: &str, smd: &Smd, flip: bool, scale: f32) -> RefModel {
    let mirrored: Vec<bool> = mirror_flags(&smd.nodes, &s.mirrored);
    // The skeleton block: every line overwrites its bone, so the last frame wins.
    let mut skeleton = vec![([0f32; 3], [0f32; 3]); smd.nodes.len()];
    if let Some((_, last)) = smd.frames.last() {
        for (k, v) in last.iter().enumerate() {
            let mut p = [v[0] * scale, v[1] * scale, v[2] * scale];
            if mirrored[k] {
                p = p.map(|x| -x);
            }
            skeleton[k] = (
                p,
                [
                    clip_rotation(v[3]),
                    clip_rotation(v[4]),
                    clip_rotation(v[5]),
                ],
            );
        }
    }
    // Bone-to-world of the reference pose (studiomdl's `bonefixup`), in studiomdl's own arithmetic:
    // vertices are truncated to two decimals in bone space, so a last-bit difference can move one
    // by 0.01.
    let mut fixup: Vec<Fixup> = Vec::with_capacity(skeleton.len());
    for (k, node) in smd.nodes.iter().enumerate() {
        let (p, r) = skeleton[k];
        let (m, im) = (angle_matrix(r), angle_imatrix(r));
        let entry = match node.parent.and_then(|q| fixup.get(q)) {
            Some(parent) => Fixup {
                m: concat(&parent.m, &m),
                im: concat(&im, &parent.im),
                org: add(transform(p, &parent.m), parent.org),
            },
            None => Fixup { m, im, org: p },
        };
        fixup.push(entry);
    }
    let adjust = s.default_adjust;
    let mut model = RefModel {
        name: name.to_string(),
        nodes: smd.nodes.clone(),
        skeleton,
        verts: Vec::new(),
        normals: Vec::new(),
        meshes: Vec::new(),
        bonemap: Vec::new(),
    };
    let normal_blend = (2.0f64 * (PI / 180.0)).cos() as f32;
    for tri in &smd.triangles {
        let slot = lookup_texture(s, &tri.material);
        let mesh = match model.meshes.iter().position(|m| m.0 == slot) {
            Some(m) => m,
            None => {
                model.meshes.push((slot, Vec::new()));
                model.meshes.len() - 1
            }
        };
        let mut corners = [(0usize, 0usize, [0f32; 2]); 3];
        for (j, v) in tri.vertices.iter().enumerate() {
            let identity = Fixup {
                m: [
                    [1.0, 0.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0, 0.0],
                    [0.0, 0.0, 1.0, 0.0],
                ],
                im: [
                    [1.0, 0.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0, 0.0],
                    [0.0, 0.0, 1.0, 0.0],
                ],
                org: [0.0; 3],
            };
            let f = fixup.get(v.bone).unwrap_or(&identity);
            let p = [
                (v.position[0] - adjust[0]) * scale,
                (v.position[1] - adjust[1]) * scale,
                (v.position[2] - adjust[2]) * scale,
            ];
            let local = transform(sub(p, f.org), &f.im).map(two_decimals);
            let n = normalize(transform(v.normal, &f.im));
            let ni = match model.normals.iter().position(|(o, b, k)| {
                Vec3::from_array(*o).dot(Vec3::from_array(n)) > normal_blend
                    && *b == v.bone
                    && *k == slot
            }) {
                Some(i) => i,
                None => {
                    model.normals.push((n, v.bone, slot));
                    model.normals.len() - 1
                }
            };
            let vi = match model
                .verts
                .iter()
                .position(|(o, b)| *o == local && *b == v.bone)
            {
                Some(i) => i,
                None => {
                    model.verts.push((local, v.bone));
                    model.verts.len() - 1
                }
            };
            // studiomdl stores corners in reverse unless `reverse` is given; the MDL reader turns
            // them back, so keep the order the MDL will read as.
            let at = if flip { 2 - j } else { j };
            corners[at] = (vi, ni, v.uv);
        }
        model.meshes[mesh].1.push(corners);
    }
    model
}

/// A bone's reference-pose matrices and world origin, as studiomdl keeps them.
struct Fixup {
    m: [[f32; 4]; 3],
    im: [[f32; 4]; 3],
    org: [f32; 3],
}

/// Sines and cosines of studiomdl's `AngleMatrix`: radians to float degrees and back, `sin` and `cos`
/// in double, kept as float.
fn studio_sincos(rot: [f32; 3]) -> [(f32, f32); 3] {
    rot.map(|r| {
        let degrees = (f64::from(r) * (180.0 / PI)) as f32;
        let angle = (f64::from(degrees) * (PI * 2.0 / 360.0)) as f32;
        (f64::from(angle).sin() as f32, f64::from(angle).cos() as f32)
    })
}

/// studiomdl's `AngleMatrix` (rows; x = roll, y = pitch, z = yaw).
fn angle_matrix(rot: [f32; 3]) -> [[f32; 4]; 3] {
    let [(sr, cr), (sp, cp), (sy, cy)] = studio_sincos(rot);
    [
        [
            cp * cy,
            sr * sp * cy + cr * -sy,
            cr * sp * cy + -sr * -sy,
            0.0,
        ],
        [
            cp * sy,
            sr * sp * sy + cr * cy,
            cr * sp * sy + -sr * cy,
            0.0,
        ],
        [-sp, sr * cp, cr * cp, 0.0],
    ]
}

/// studiomdl's `AngleIMatrix`: the transpose of [`angle_matrix`].
fn angle_imatrix(rot: [f32; 3]) -> [[f32; 4]; 3] {
    let [(sr, cr), (sp, cp), (sy, cy)] = studio_sincos(rot);
    [
        [cp * cy, cp * sy, -sp, 0.0],
        [
            sr * sp * cy + cr * -sy,
            sr * sp * sy + cr * cy,
            sr * cp,
            0.0,
        ],
        [
            cr * sp * cy + -sr * -sy,
            cr * sp * sy + -sr * cy,
            cr * cp,
            0.0,
        ],
    ]
}

/// studiomdl's `R_ConcatTransforms`.
fn concat(a: &[[f32; 4]; 3], b: &[[f32; 4]; 3]) -> [[f32; 4]; 3] {
    let mut out = [[0f32; 4]; 3];
    for i in 0..3 {
        for j in 0..4 {
            out[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
            if j == 3 {
                out[i][j] += a[i][3];
            }
        }
    }
    out
}

/// studiomdl's `VectorTransform`.
fn transform(v: [f32; 3], m: &[[f32; 4]; 3]) -> [f32; 3] {
    [0, 1, 2].map(|i| v[0] * m[i][0] + v[1] * m[i][1] + v[2] * m[i][2] + m[i][3])
}

fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// studiomdl's `VectorNormalize` (length in double).
fn normalize(v: [f32; 3]) -> [f32; 3] {
    let len = (f64::from(v[0]) * f64::from(v[0])
        + f64::from(v[1]) * f64::from(v[1])
        + f64::from(v[2]) * f64::from(v[2]))
    .sqrt();
    if len == 0.0 {
        return v;
    }
    let inv = (1.0 / len) as f32;
    v.map(|x| x * inv)
}

fn mirror_flags(nodes: &[smd::Node], mirrored: &[String]) -> Vec<bool> {
    let mut out = vec![false; nodes.len()];
    for (k, n) in nodes.iter().enumerate() {
        out[k] = mirrored.contains(&n.name) || n.parent.is_some_and(|p| p < k && out[p]);
    }
    out
}

fn texture_group(s: &mut State, c: &mut Cursor, cmd: &Tok) -> Result<(), ImportError> {
    let script = c.script();
    if s.textures.is_empty() {
        return Err(script.error_at(
            cmd,
            "$texturegroup",
            "texture groups must follow the models",
        ));
    }
    c.expect("$texturegroup", "a group name")?;
    if s.skinref_count == 0 {
        s.skinref_count = s.textures.len();
    }
    let mut depth = 0;
    let mut group: Vec<Vec<usize>> = vec![Vec::new()];
    loop {
        let Some(t) = c.next_any() else {
            return Err(script.error_at(
                cmd,
                "$texturegroup",
                "file ends before the group is closed",
            ));
        };
        if t.is("{") {
            depth += 1;
        } else if t.is("}") {
            depth -= 1;
            if depth == 0 {
                break;
            }
            group.push(Vec::new());
        } else if depth == 2 {
            let i = lookup_texture(s, &t.text);
            if let Some(g) = group.last_mut() {
                g.push(i);
            }
        } else if t.is_command() {
            return Err(script.error_at(
                t,
                "$texturegroup",
                "a command inside $texturegroup (missing `}`)",
            ));
        }
    }
    group.retain(|g| !g.is_empty());
    s.texture_groups.push(group);
    Ok(())
}

/// studiomdl's `Cmd_Sequence`.
fn sequence(s: &mut State, c: &mut Cursor) -> Result<(), ImportError> {
    let script = c.script();
    let label_tok = c.expect("$sequence", "a sequence name")?;
    let mut seq = Sequence {
        label: label_tok.text.clone(),
        fps: 30.0,
        blend: (0, 0.0, 1.0),
        ..Sequence::default()
    };
    let mut adjust = s.default_adjust;
    let mut scale = s.default_scale;
    let mut zrotation = s.default_zrotation;
    let mut files: Vec<(String, usize)> = Vec::new();
    let (mut start, mut end) = (0i32, MAX_FRAMES - 1);
    let mut depth = 0i32;
    loop {
        let t = if depth > 0 {
            match c.next_any() {
                Some(t) => t,
                None => return Err(script.error_at(label_tok, "$sequence", "missing `}`")),
            }
        } else {
            match c.next_same_line() {
                Some(t) => t,
                None => break,
            }
        };
        let lower = t.text.to_ascii_lowercase();
        let starts = |p: &str| lower.len() >= p.len() && lower[..p.len()] == *p;
        if t.is("{") {
            depth += 1;
        } else if t.is("}") {
            depth -= 1;
        } else if lower == "deform" {
        } else if lower == "event" {
            let event = c.integer("$sequence", "an event number")?;
            let frame = c.integer("$sequence", "an event frame")?;
            let mut options = String::new();
            if let Some(o) = c.next_same_line() {
                if o.is("}") {
                    depth -= 1;
                } else {
                    options = o.text.clone();
                }
            }
            seq.events.push((frame, event, 0, options));
        } else if lower == "pivot" {
            for _ in 0..3 {
                c.integer("$sequence", "a pivot value")?;
            }
        } else if lower == "fps" {
            seq.fps = c.number("$sequence", "a frame rate")?;
        } else if lower == "origin" {
            for x in &mut adjust {
                *x = c.number("$sequence", "an origin coordinate")?;
            }
        } else if lower == "rotate" {
            let r = c.number("$sequence", "a rotation")?;
            zrotation = (f64::from(r) + 90.0) * (PI / 180.0);
        } else if lower == "scale" {
            scale = c.number("$sequence", "a scale")?;
        } else if starts("loop") {
            seq.looping = true;
        } else if starts("frame") {
            start = c.integer("$sequence", "a first frame")?;
            end = c.integer("$sequence", "a last frame")?;
        } else if starts("blend") {
            let ty = c.expect("$sequence", "a blend channel")?;
            let ty = control(&ty.text).unwrap_or(u32::MAX);
            let a = c.number("$sequence", "a blend start")?;
            let b = c.number("$sequence", "a blend end")?;
            seq.blend = (ty, a, b);
        } else if starts("node") {
            let n = c.integer("$sequence", "a node")?;
            seq.nodes.0 = n;
            seq.nodes.1 = n;
        } else if starts("tran") {
            seq.nodes.0 = c.integer("$sequence", "an entry node")?;
            seq.nodes.1 = c.integer("$sequence", "an exit node")?;
        } else if starts("rtra") {
            seq.nodes.0 = c.integer("$sequence", "an entry node")?;
            seq.nodes.1 = c.integer("$sequence", "an exit node")?;
            seq.nodes.2 |= 1;
        } else if let Some(m) = control(&t.text) {
            seq.motion |= m;
        } else if lower == "animation" {
            let f = c.expect("$sequence", "an animation SMD")?;
            files.push((f.text.clone(), f.line));
        } else if activity_number(&t.text) != 0 {
            seq.activity = activity_number(&t.text);
            seq.weight = c.integer("$sequence", "an activity weight")?;
        } else {
            files.push((t.text.clone(), t.line));
        }
        if depth < 0 {
            return Err(script.error_at(t, "$sequence", "missing `{`"));
        }
    }
    if files.is_empty() {
        return Err(script.error_at(
            label_tok,
            "$sequence",
            format!("sequence {:?} names no animation", seq.label),
        ));
    }
    for (file, line) in files {
        let Some(smd) = read_smd(s, &file, "$sequence", line)? else {
            seq.anims.clear();
            break;
        };
        let anim = grab_animation(s, &smd, start, end, adjust, scale, zrotation);
        match anim {
            Some(a) => seq.anims.push(a),
            None => {
                s.diagnostics.push(Diagnostic::warning(
                    "qc-empty-animation",
                    format!("{} line {line}: {file} has no frames in range {start}..{end}; sequence {:?} left out", s.qc, seq.label),
                ));
                seq.anims.clear();
                break;
            }
        }
    }
    s.sequences.push(seq);
    Ok(())
}

/// studiomdl's `Grab_Animation` and `Shift_Animation`: frames `start..=end`, root bones moved by
/// the origin, turned by `zrotation` and scaled.
fn grab_animation(
    s: &State,
    smd: &Smd,
    start: i32,
    end: i32,
    adjust: [f32; 3],
    scale: f32,
    zrotation: f64,
) -> Option<Anim> {
    let mirrored = mirror_flags(&smd.nodes, &s.mirrored);
    let (cz, sz) = (zrotation.cos() as f32, zrotation.sin() as f32);
    let frames: Vec<Vec<([f32; 3], [f32; 3])>> = smd
        .frames
        .iter()
        .filter(|(t, _)| *t >= start && *t <= end)
        .map(|(_, values)| {
            values
                .iter()
                .enumerate()
                .map(|(k, v)| {
                    let mut pos = [v[0], v[1], v[2]];
                    let mut rot = [v[3], v[4], v[5]];
                    if smd.nodes[k].parent.is_none() {
                        let p = [pos[0] - adjust[0], pos[1] - adjust[1], pos[2] - adjust[2]];
                        pos = [cz * p[0] - sz * p[1], sz * p[0] + cz * p[1], p[2]];
                        rot[2] = (f64::from(rot[2]) + zrotation) as f32;
                    }
                    if mirrored[k] {
                        pos = pos.map(|x| -x);
                    }
                    pos = pos.map(|x| x * scale);
                    (pos, rot.map(clip_rotation))
                })
                .collect()
        })
        .collect();
    if frames.is_empty() {
        return None;
    }
    Some(Anim {
        nodes: smd.nodes.clone(),
        frames,
    })
}

/// studiomdl's `SimplifyModel` and what follows: the bone union, relinking, motion extraction,
/// quantisation, hit boxes, transitions, skins; then the studio model.
fn build(mut s: State, script: &Script) -> Result<(StudioModel, Vec<Diagnostic>), ImportError> {
    let qc = s.qc.to_string();
    let err = |section: &str, msg: String| ImportError::in_section(&qc, section, msg);

    // OptimizeAnimations: looping sequences end where they start; ExtractMotion.
    for seq in &mut s.sequences {
        let n = seq.anims.first().map_or(0, |a| a.frames.len());
        if n == 0 {
            continue;
        }
        if seq.looping {
            for a in &mut seq.anims {
                let first = a.frames[0].clone();
                if let Some(last) = a.frames.last_mut() {
                    for (k, (p, r)) in last.iter_mut().enumerate() {
                        for (c, flag) in [motion_flags::LX, motion_flags::LY, motion_flags::LZ]
                            .into_iter()
                            .enumerate()
                        {
                            if seq.motion & flag == 0 {
                                p[c] = first[k].0[c];
                            }
                        }
                        *r = first[k].1;
                    }
                }
            }
        }
    }
    let mut linear: Vec<[f32; 3]> = Vec::with_capacity(s.sequences.len());
    for seq in &mut s.sequences {
        let n = seq.anims.first().map_or(0, |a| a.frames.len());
        let mut motion = [0f32; 3];
        if n > 1 {
            let a0 = &seq.anims[0];
            let (p0, pk) = (a0.frames[0][0].0, a0.frames[n - 1][0].0);
            for (c, flag) in [motion_flags::LX, motion_flags::LY, motion_flags::LZ]
                .into_iter()
                .enumerate()
            {
                if seq.motion & flag != 0 {
                    motion[c] = pk[c] - p0[c];
                }
            }
            let roots: Vec<usize> = a0
                .nodes
                .iter()
                .enumerate()
                .filter(|(_, nd)| nd.parent.is_none())
                .map(|(k, _)| k)
                .collect();
            for a in &mut seq.anims {
                for (j, frame) in a.frames.iter_mut().enumerate() {
                    let f = (j as f64 / (n - 1) as f64) as f32;
                    for &k in &roots {
                        if let Some((p, _)) = frame.get_mut(k) {
                            for c in 0..3 {
                                p[c] -= motion[c] * f;
                            }
                        }
                    }
                }
            }
        }
        linear.push(motion);
        // Unused rotation motion of root bones is held at frame 0.
        let roots: Vec<usize> = seq
            .anims
            .first()
            .map(|a| {
                a.nodes
                    .iter()
                    .enumerate()
                    .filter(|(_, nd)| nd.parent.is_none())
                    .map(|(k, _)| k)
                    .collect()
            })
            .unwrap_or_default();
        for a in &mut seq.anims {
            let Some(first) = a.frames.first().cloned() else {
                continue;
            };
            for frame in &mut a.frames {
                for &k in &roots {
                    for (c, flag) in [motion_flags::XR, motion_flags::YR, motion_flags::ZR]
                        .into_iter()
                        .enumerate()
                    {
                        if seq.motion & flag != 0 {
                            if let (Some(f), Some(f0)) = (frame.get_mut(k), first.get(k)) {
                                f.1[c] = f0.1[c];
                            }
                        }
                    }
                }
            }
        }
    }

    // Transitions (MakeTransitions).
    let nodes = s
        .sequences
        .iter()
        .map(|q| q.nodes.0.max(0) as usize)
        .max()
        .unwrap_or(0)
        .min(255);
    let mut xnode = vec![vec![0i32; nodes]; nodes];
    for q in &s.sequences {
        let (a, b) = (q.nodes.0, q.nodes.1);
        if a != b && a >= 1 && b >= 1 && (a as usize) <= nodes && (b as usize) <= nodes {
            xnode[a as usize - 1][b as usize - 1] = b;
            if q.nodes.2 != 0 {
                xnode[b as usize - 1][a as usize - 1] = a;
            }
        }
    }
    loop {
        let mut hit = false;
        for i in 0..nodes {
            for j in 0..nodes {
                if i != j && xnode[i][j] == 0 {
                    for k in 0..nodes.saturating_sub(1) {
                        if xnode[k][j] > 0 && xnode[i][k] > 0 {
                            xnode[i][j] = -xnode[i][k];
                            hit = true;
                            break;
                        }
                    }
                }
            }
        }
        for row in &mut xnode {
            for v in row.iter_mut() {
                *v = v.abs();
            }
        }
        if !hit {
            break;
        }
    }

    // Bones used by vertices, with their ancestors, renamed, then their union in first-use order.
    for m in &mut s.models {
        for n in &mut m.nodes {
            if let Some((_, to)) = s.renames.iter().find(|(f, _)| *f == n.name) {
                n.name = to.clone();
            }
        }
    }
    let mut bones: Vec<UnionBone> = Vec::new();
    for m in &mut s.models {
        let mut used = vec![false; m.nodes.len()];
        for (_, b) in &m.verts {
            if let Some(u) = used.get_mut(*b) {
                *u = true;
            }
        }
        for k in 0..used.len() {
            if used[k] {
                let mut p = m.nodes[k].parent;
                let mut guard = 0;
                while let Some(q) = p {
                    if used[q] || guard > used.len() {
                        break;
                    }
                    used[q] = true;
                    p = m.nodes[q].parent;
                    guard += 1;
                }
            }
        }
        m.bonemap = vec![None; m.nodes.len()];
        for (j, &is_used) in used.iter().enumerate() {
            if !is_used {
                continue;
            }
            let name = &m.nodes[j].name;
            let parent = m.nodes[j].parent.and_then(|p| {
                let pn = &m.nodes[p].name;
                bones.iter().position(|b| b.0 == *pn)
            });
            let k = match bones.iter().position(|b| b.0 == *name) {
                Some(k) => {
                    if bones[k].1 != parent {
                        return Err(err(
                            "bones",
                            format!(
                                "bone {name:?} has a different parent in {} than in an earlier model",
                                m.name
                            ),
                        ));
                    }
                    k
                }
                None => {
                    bones.push((name.clone(), parent, m.skeleton[j].0, m.skeleton[j].1));
                    bones.len() - 1
                }
            };
            m.bonemap[j] = Some(k);
        }
    }
    if bones.len() >= MAX_BONES {
        return Err(err(
            "bones",
            format!(
                "{} bones used; GoldSrc models hold at most {}",
                bones.len(),
                MAX_BONES - 1
            ),
        ));
    }
    let find = |name: &str| bones.iter().position(|b| b.0.eq_ignore_ascii_case(name));

    // Bind-pose bone-to-model transforms of the union, for vertices and normals.
    let mut world: Vec<(Mat3, Vec3)> = Vec::with_capacity(bones.len());
    for b in &bones {
        let m = Mat3::from_quat(euler_to_quat(b.3));
        let entry = match b.1.and_then(|p| world.get(p).copied()) {
            Some((pm, porg)) => (pm * m, pm * Vec3::from_array(b.2) + porg),
            None => (m, Vec3::from_array(b.2)),
        };
        world.push(entry);
    }

    // Sequences relinked to the union; bones an animation lacks hold their default.
    let mut sequences = Vec::with_capacity(s.sequences.len());
    for (seq, lin) in s.sequences.iter().zip(&linear) {
        let mut blends = Vec::with_capacity(seq.anims.len());
        for a in &seq.anims {
            let map: Vec<Option<usize>> = bones
                .iter()
                .map(|b| {
                    let mut names = a.nodes.iter().map(|n| {
                        s.renames
                            .iter()
                            .find(|(f, _)| *f == n.name)
                            .map_or(n.name.as_str(), |(_, t)| t.as_str())
                    });
                    names.position(|n| n == b.0)
                })
                .collect();
            let frames: Vec<Vec<[f32; 6]>> = a
                .frames
                .iter()
                .map(|f| {
                    bones
                        .iter()
                        .enumerate()
                        .map(|(j, b)| match map[j].and_then(|k| f.get(k)) {
                            Some((p, r)) => [p[0], p[1], p[2], r[0], r[1], r[2]],
                            None => [b.2[0], b.2[1], b.2[2], b.3[0], b.3[1], b.3[2]],
                        })
                        .collect()
                })
                .collect();
            blends.push(frames);
        }
        let n = blends.first().map_or(0, Vec::len) as i32;
        sequences.push(StudioSequence {
            label: seq.label.clone(),
            fps: seq.fps,
            looping: seq.looping,
            activity: (seq.activity, seq.weight),
            events: seq
                .events
                .iter()
                .map(|(f, e, k, o)| ((*f).clamp(0, (n - 1).max(0)), *e, *k, o.clone()))
                .collect(),
            motion_type: seq.motion,
            motion_bone: 0,
            linear_movement: *lin,
            blend_type: [
                if seq.blend.0 == u32::MAX {
                    0
                } else {
                    seq.blend.0
                },
                0,
            ],
            blend_start: [seq.blend.1, 0.0],
            blend_end: [seq.blend.2, 0.0],
            nodes: seq.nodes,
            blends,
        });
    }
    quantise(&bones, &mut sequences);

    // Submodels: vertices and normals back from bone space with the union's bind pose.
    let mut body_parts: Vec<BodyPart> = s
        .parts
        .iter()
        .map(|(name, _)| BodyPart {
            name: name.clone(),
            submodels: Vec::new(),
        })
        .collect();
    for (p, (_, choices)) in s.parts.iter().enumerate() {
        for choice in choices {
            let sub = match choice.and_then(|m| s.models.get(m)) {
                None => Submodel {
                    name: "blank".into(),
                    vertices: Vec::new(),
                    meshes: Vec::new(),
                },
                Some(m) => {
                    let bone = |b: usize| m.bonemap.get(b).copied().flatten().unwrap_or(0);
                    let vertices = m
                        .verts
                        .iter()
                        .map(|(local, b)| {
                            let (rot, org) = world[bone(*b)];
                            StudioVertex {
                                position: (rot * Vec3::from_array(*local) + org).to_array(),
                                influences: vec![(bone(*b), 1.0)],
                            }
                        })
                        .collect();
                    let meshes = m
                        .meshes
                        .iter()
                        .map(|(slot, tris)| {
                            // studiomdl stores no coordinates for chrome textures (the renderer
                            // makes them from the view), so neither does the compile.
                            let chrome = s
                                .textures
                                .get(*slot)
                                .is_some_and(|t| t.flags & material_flags::CHROME != 0);
                            StudioMesh {
                                skin_slot: *slot,
                                triangles: tris
                                    .iter()
                                    .map(|t| {
                                        // Back to counter-clockwise (the MDL reader does the same).
                                        [t[2], t[1], t[0]].map(|(v, n, uv)| {
                                            let (nrm, b, _) = m.normals[n];
                                            Corner {
                                                vertex: v,
                                                normal: (world[bone(b)].0 * Vec3::from_array(nrm))
                                                    .to_array(),
                                                uv: if chrome {
                                                    [0.0, 0.0]
                                                } else {
                                                    [uv[0], 1.0 - uv[1]]
                                                },
                                            }
                                        })
                                    })
                                    .collect(),
                            }
                        })
                        .collect();
                    Submodel {
                        name: m.name.clone(),
                        vertices,
                        meshes,
                    }
                }
            };
            body_parts[p].submodels.push(sub);
        }
    }

    // Hit boxes: as given, or one per bone that vertices span (with its children's origins).
    let mut hitboxes = Vec::new();
    if s.hitboxes.is_empty() {
        let mut group = vec![i32::MIN; bones.len()];
        for (g, name) in &s.hitgroups {
            match find(name) {
                Some(k) => group[k] = *g,
                None => {
                    return Err(err(
                        "$hgroup",
                        format!("no bone {name:?} for hit group {g}"),
                    ));
                }
            }
        }
        for k in 0..bones.len() {
            if group[k] == i32::MIN {
                group[k] = bones[k].1.map_or(0, |p| group[p]);
            }
        }
        let mut bmin = vec![[0f32; 3]; bones.len()];
        let mut bmax = vec![[0f32; 3]; bones.len()];
        for m in &s.models {
            for (p, b) in &m.verts {
                let Some(k) = m.bonemap.get(*b).copied().flatten() else {
                    continue;
                };
                for c in 0..3 {
                    bmin[k][c] = bmin[k][c].min(p[c]);
                    bmax[k][c] = bmax[k][c].max(p[c]);
                }
            }
        }
        for bone in &bones {
            if let Some(j) = bone.1 {
                for c in 0..3 {
                    bmin[j][c] = bmin[j][c].min(bone.2[c]);
                    bmax[j][c] = bmax[j][c].max(bone.2[c]);
                }
            }
        }
        for k in 0..bones.len() {
            if (0..3).all(|c| bmin[k][c] < bmax[k][c] - 1.0) {
                hitboxes.push((k, group[k], bmin[k], bmax[k]));
            }
        }
    } else {
        for (g, name, min, max, t) in &s.hitboxes {
            let Some(k) = find(name) else {
                return Err(script.error_at(t, "$hbox", format!("no bone {name:?} in the model")));
            };
            hitboxes.push((k, *g, *min, *max));
        }
    }
    let mut controllers = Vec::new();
    for (index, name, channel, start, end, t) in &s.controllers {
        let Some(k) = find(name) else {
            return Err(script.error_at(
                t,
                "$controller",
                format!("no bone {name:?} in the model"),
            ));
        };
        controllers.push(StudioController {
            bone: k,
            channel: *channel,
            start: *start,
            end: *end,
            rest: 0,
            index: *index,
        });
    }
    let mut attachments = Vec::new();
    for (name, org, t) in &s.attachments {
        let Some(k) = find(name) else {
            return Err(script.error_at(
                t,
                "$attachment",
                format!("no bone {name:?} in the model"),
            ));
        };
        attachments.push((String::new(), k, *org));
    }

    // Skins: studiomdl's texture groups over the textures in first-use order.
    let skinrefs = if s.skinref_count == 0 {
        s.textures.len()
    } else {
        s.skinref_count
    };
    let mut skin_families = vec![(0..skinrefs).collect::<Vec<usize>>()];
    if let Some(groups) = s.texture_groups.first() {
        if let Some(base) = groups.first() {
            skin_families = groups
                .iter()
                .map(|row| {
                    let mut fam: Vec<usize> = (0..skinrefs).collect();
                    for (j, &b) in base.iter().enumerate() {
                        if let (Some(slot), Some(&t)) = (fam.get_mut(b), row.get(j)) {
                            *slot = t;
                        }
                    }
                    fam
                })
                .collect();
        }
    }
    let textures = s
        .textures
        .iter()
        .map(|t| StudioTexture {
            name: t.name.clone(),
            flags: t.flags,
            width: 0,
            height: 0,
            indices: Vec::new(),
            palette: Vec::new(),
        })
        .collect();

    let model = StudioModel {
        bones: bones
            .iter()
            .map(|b| StudioBone {
                name: b.0.clone(),
                parent: b.1,
                value: [b.2[0], b.2[1], b.2[2], b.3[0], b.3[1], b.3[2]],
            })
            .collect(),
        body_parts,
        textures,
        skin_families,
        sequences,
        controllers,
        hitboxes,
        attachments,
        eye_position: Some(s.eye),
        transitions: xnode
            .iter()
            .flatten()
            .map(|&v| v.clamp(0, 255) as u8)
            .collect(),
        transition_nodes: nodes as u32,
    };
    Ok((model, s.diagnostics))
}

/// studiomdl's 16-bit animation values: per bone and channel a scale from the largest difference
/// from the default over every frame of every sequence, each value truncated to a multiple of it.
fn quantise(bones: &[UnionBone], sequences: &mut [StudioSequence]) {
    for (j, b) in bones.iter().enumerate() {
        let default = [b.2[0], b.2[1], b.2[2], b.3[0], b.3[1], b.3[2]];
        for k in 0..6 {
            let diff = |v: f32| -> f32 {
                let d = v - default[k];
                if k < 3 {
                    d
                } else if f64::from(d) >= PI {
                    (f64::from(d) - PI * 2.0) as f32
                } else if f64::from(d) < -PI {
                    (f64::from(d) + PI * 2.0) as f32
                } else {
                    d
                }
            };
            let (mut minv, mut maxv) = if k < 3 {
                (-128.0f32, 128.0f32)
            } else {
                ((-PI / 8.0) as f32, (PI / 8.0) as f32)
            };
            for seq in sequences.iter() {
                for frame in seq.blends.iter().flatten() {
                    if let Some(v) = frame.get(j) {
                        let d = diff(v[k]);
                        minv = minv.min(d);
                        maxv = maxv.max(d);
                    }
                }
            }
            let scale = if minv < maxv {
                if -minv > maxv {
                    (f64::from(minv) / -32768.0) as f32
                } else {
                    maxv / 32767.0
                }
            } else {
                1.0 / 32.0
            };
            for seq in sequences.iter_mut() {
                for frame in seq.blends.iter_mut().flatten() {
                    if let Some(v) = frame.get_mut(j) {
                        let raw = (diff(v[k]) / scale) as i16;
                        v[k] = default[k] + f32::from(raw) * scale;
                    }
                }
            }
        }
    }
}
