//! GoldSrc MDL (version 10) read into a studio model: the header and every (count, offset) table it
//! points to, bounds-checked before use; run-length animation values decoded per frame; texture and
//! sequence-group companion files (`NAMET.mdl`, `NAME01.mdl` ...) read beside it when they exist.
//! Layout notes and decisions: docs/formats/halflife.md.

use super::model::{
    BodyPart, Corner, StudioBone, StudioController, StudioMesh, StudioModel, StudioSequence,
    StudioTexture, StudioVertex, Submodel,
};
use super::scene::euler_to_quat;
use crate::{ImportError, Resolver};
use sinew_core::glam::{Mat3, Vec3};
use sinew_scene::Diagnostic;

/// Bytes of the file header.
pub const HEADER_SIZE: usize = 244;
/// Bytes of the header of a sequence-group file (`IDSQ`).
pub const GROUP_HEADER_SIZE: usize = 76;
/// Most bones a GoldSrc model may have (`MAXSTUDIOBONES`).
pub const MAX_BONES: usize = 128;
/// Most decoded animation values (frames x bones x blends) one file may ask for: bounds memory.
pub const MAX_ANIMATION_VALUES: u64 = 1 << 22;
/// Largest texture side accepted.
pub const MAX_TEXTURE_SIDE: u32 = 4096;

const BONE: usize = 112;
const CONTROLLER: usize = 24;
const HITBOX: usize = 32;
const SEQUENCE: usize = 176;
const EVENT: usize = 76;
const GROUP: usize = 104;
const TEXTURE: usize = 80;
const BODYPART: usize = 76;
const MODEL: usize = 112;
const MESH: usize = 20;
const ATTACHMENT: usize = 88;

/// Bounds-checked reads from one file's bytes, with errors naming the file, section and offset.
struct Bytes<'a> {
    file: &'a str,
    b: &'a [u8],
}

impl Bytes<'_> {
    fn err(&self, section: &str, offset: usize, msg: impl Into<String>) -> ImportError {
        ImportError::at_offset(self.file, section, offset as u64, msg)
    }
    fn get(&self, section: &str, at: usize, n: usize) -> Result<&[u8], ImportError> {
        at.checked_add(n)
            .and_then(|end| self.b.get(at..end))
            .ok_or_else(|| {
                self.err(
                    section,
                    at,
                    format!(
                        "{n} bytes needed at byte {at}, the file has {}",
                        self.b.len()
                    ),
                )
            })
    }
    fn i32(&self, section: &str, at: usize) -> Result<i32, ImportError> {
        let s = self.get(section, at, 4)?;
        Ok(i32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }
    fn f32(&self, section: &str, at: usize) -> Result<f32, ImportError> {
        let s = self.get(section, at, 4)?;
        let v = f32::from_le_bytes([s[0], s[1], s[2], s[3]]);
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(section, at, "a number is not finite"))
        }
    }
    fn vec3(&self, section: &str, at: usize) -> Result<[f32; 3], ImportError> {
        Ok([
            self.f32(section, at)?,
            self.f32(section, at + 4)?,
            self.f32(section, at + 8)?,
        ])
    }
    fn i16(&self, section: &str, at: usize) -> Result<i16, ImportError> {
        let s = self.get(section, at, 2)?;
        Ok(i16::from_le_bytes([s[0], s[1]]))
    }
    fn u16(&self, section: &str, at: usize) -> Result<u16, ImportError> {
        let s = self.get(section, at, 2)?;
        Ok(u16::from_le_bytes([s[0], s[1]]))
    }
    fn name(&self, section: &str, at: usize, n: usize) -> Result<String, ImportError> {
        let s = self.get(section, at, n)?;
        let end = s.iter().position(|&c| c == 0).unwrap_or(n);
        Ok(s[..end].iter().map(|&c| char::from(c)).collect())
    }
    /// A table of `count` records of `size` bytes at `offset`, checked to lie inside the file.
    fn table(
        &self,
        section: &str,
        count_at: usize,
        offset_at: usize,
        size: usize,
    ) -> Result<(usize, usize), ImportError> {
        let count = self.i32(section, count_at)?;
        let offset = self.i32(section, offset_at)?;
        self.check_table(section, count, offset, size, count_at)
    }
    fn check_table(
        &self,
        section: &str,
        count: i32,
        offset: i32,
        size: usize,
        at: usize,
    ) -> Result<(usize, usize), ImportError> {
        if count < 0 {
            return Err(self.err(section, at, format!("negative count {count}")));
        }
        if count == 0 {
            return Ok((0, 0));
        }
        let offset = usize::try_from(offset)
            .map_err(|_| self.err(section, at, format!("negative offset {offset}")))?;
        let need = (count as usize).checked_mul(size);
        match need.and_then(|n| offset.checked_add(n)) {
            Some(end) if end <= self.b.len() => Ok((count as usize, offset)),
            _ => Err(self.err(
                section,
                at,
                format!(
                    "{count} records of {size} bytes at byte {offset} run past the end of the {}-byte file",
                    self.b.len()
                ),
            )),
        }
    }
}

/// Checks the first bytes: a GoldSrc MDL (`IDST`, version 10), or an error naming what it is.
fn check_magic(f: &Bytes) -> Result<(), ImportError> {
    let magic = f.get("header", 0, 4)?;
    let version = f.i32("header", 4)?;
    match magic {
        b"IDST" if version == 10 => Ok(()),
        b"IDST" if (44..=49).contains(&version) => Err(f.err(
            "header",
            4,
            format!("Source-engine MDL version {version} is not supported; sinew reads GoldSrc MDL version 10"),
        )),
        b"IDST" => Err(f.err(
            "header",
            4,
            format!("MDL version {version} is not supported; sinew reads GoldSrc MDL version 10"),
        )),
        b"IDSQ" => Err(f.err(
            "header",
            0,
            "this is a sequence-group file (IDSQ); convert its main model, whose name it shares without the digits",
        )),
        b"IDPO" => Err(f.err(
            "header",
            0,
            format!("Quake MDL (IDPO, version {version}) is not supported; sinew reads GoldSrc MDL version 10"),
        )),
        _ => Err(f.err(
            "header",
            0,
            format!("not a Half-Life model (magic {:?}, expected \"IDST\")", String::from_utf8_lossy(magic)),
        )),
    }
}

/// Checks the header's file length against the bytes present: a shorter file was cut off.
fn check_length(f: &Bytes) -> Result<(), ImportError> {
    let declared = f.i32("header", 72)?;
    if declared < 0 || declared as usize > f.b.len() {
        return Err(f.err(
            "header",
            72,
            format!(
                "truncated: the header says {declared} bytes, the file has {}",
                f.b.len()
            ),
        ));
    }
    Ok(())
}

/// A warning when the file holds textures and nothing else (no bone, sequence or body part): a
/// model's texture file (`NAMET.mdl`), which is read with its model; converted alone it has
/// nothing to convert, and the warning says which file to convert instead.
fn textures_only(f: &Bytes) -> Result<Option<Diagnostic>, ImportError> {
    let count = |at: usize| f.i32("header", at);
    let (bones, sequences, textures, bodyparts) =
        (count(140)?, count(164)?, count(180)?, count(204)?);
    if bones != 0 || sequences != 0 || bodyparts != 0 || textures <= 0 {
        return Ok(None);
    }
    let model = match file_stem(f.file).strip_suffix(['T', 't']) {
        Some(m) if !m.is_empty() => format!("{m}.mdl"),
        _ => "its model".to_string(),
    };
    Ok(Some(
        Diagnostic::warning(
            "mdl-textures-only",
            format!(
                "the file holds {textures} textures and no bone, sequence or body part: a model's texture file, which the model reads; convert {model}"
            ),
        )
        .with_figure("textures", f64::from(textures)),
    ))
}

/// The companion file names of a model file: `<stem>T.mdl` and the sequence group files.
pub fn texture_companion(file: &str) -> String {
    format!("{}T.mdl", file_stem(file))
}

/// A file's name without its folders and its extension (`models/man.mdl` -> `man`).
fn file_stem(file: &str) -> &str {
    let base = file.rsplit(['/', '\\']).next().unwrap_or(file);
    base.rsplit_once('.').map_or(base, |(s, _)| s)
}

/// The companion files an MDL's header names, by file name: its texture file (`NAMET.mdl`) when it
/// keeps no textures itself, and the file of every sequence group after the first, whether or not
/// a sequence uses it (studiomdl writes them all). Reads the header and the group table only.
pub fn companions(file: &str, bytes: &[u8]) -> Result<Vec<String>, ImportError> {
    let f = Bytes { file, b: bytes };
    check_magic(&f)?;
    f.get("header", 0, HEADER_SIZE)?;
    let mut out = Vec::new();
    if f.i32("textures", 180)? == 0 {
        out.push(texture_companion(file));
    }
    let (ngroups, gat) = f.table("sequence groups", 172, 176, GROUP)?;
    for g in 1..ngroups {
        let name = f.name("sequence groups", gat + g * GROUP + 32, 64)?;
        out.push(name.rsplit(['/', '\\']).next().unwrap_or(&name).to_string());
    }
    Ok(out)
}

/// Reads an MDL and its companions (through `resolve`). A companion that cannot be read is an error
/// naming it, or with `allow_missing` a warning (what needs it is left out).
pub fn read(
    file: &str,
    bytes: &[u8],
    resolve: Resolver<'_>,
    allow_missing: bool,
) -> Result<(StudioModel, Vec<Diagnostic>), ImportError> {
    let f = Bytes { file, b: bytes };
    check_magic(&f)?;
    f.get("header", 0, HEADER_SIZE)?;
    check_length(&f)?;
    let mut diagnostics = Vec::new();
    if let Some(d) = textures_only(&f)? {
        diagnostics.push(d);
    }
    let mut model = StudioModel::default();
    let eye = f.vec3("header", 76)?;
    model.eye_position = Some(eye);

    // Bones.
    let (nbones, at) = f.table("bones", 140, 144, BONE)?;
    if nbones > MAX_BONES {
        return Err(f.err(
            "bones",
            140,
            format!("{nbones} bones; GoldSrc models hold at most {MAX_BONES}"),
        ));
    }
    let mut scales = Vec::with_capacity(nbones);
    for i in 0..nbones {
        let o = at + i * BONE;
        let mut scale = [0f32; 6];
        for (k, v) in scale.iter_mut().enumerate() {
            *v = f.f32("bones", o + 88 + 4 * k)?;
        }
        scales.push(scale);
        let parent = f.i32("bones", o + 32)?;
        let parent = match parent {
            -1 => None,
            p if p >= 0 && (p as usize) < i => Some(p as usize),
            p => {
                return Err(f.err(
                    "bones",
                    o + 32,
                    format!("bone {i} has parent {p}: parents must come before their children (a cycle or a bad index)"),
                ))
            }
        };
        let mut value = [0f32; 6];
        for (k, v) in value.iter_mut().enumerate() {
            *v = f.f32("bones", o + 64 + 4 * k)?;
        }
        model.bones.push(StudioBone {
            name: f.name("bones", o, 32)?,
            parent,
            value,
        });
    }
    let bone_index = |section: &str, at: usize, v: i32| -> Result<usize, ImportError> {
        usize::try_from(v)
            .ok()
            .filter(|&b| b < nbones)
            .ok_or_else(|| {
                f.err(
                    section,
                    at,
                    format!("bone index {v} is not below the bone count {nbones}"),
                )
            })
    };

    // Bone controllers, hit boxes, attachments.
    let (n, at) = f.table("bone controllers", 148, 152, CONTROLLER)?;
    for i in 0..n {
        let o = at + i * CONTROLLER;
        model.controllers.push(StudioController {
            bone: bone_index("bone controllers", o, f.i32("bone controllers", o)?)?,
            channel: f.i32("bone controllers", o + 4)? as u32,
            start: f.f32("bone controllers", o + 8)?,
            end: f.f32("bone controllers", o + 12)?,
            rest: f.i32("bone controllers", o + 16)?,
            index: f.i32("bone controllers", o + 20)?,
        });
    }
    let (n, at) = f.table("hit boxes", 156, 160, HITBOX)?;
    for i in 0..n {
        let o = at + i * HITBOX;
        model.hitboxes.push((
            bone_index("hit boxes", o, f.i32("hit boxes", o)?)?,
            f.i32("hit boxes", o + 4)?,
            f.vec3("hit boxes", o + 8)?,
            f.vec3("hit boxes", o + 20)?,
        ));
    }
    let (n, at) = f.table("attachments", 212, 216, ATTACHMENT)?;
    for i in 0..n {
        let o = at + i * ATTACHMENT;
        model.attachments.push((
            f.name("attachments", o, 32)?,
            bone_index("attachments", o + 36, f.i32("attachments", o + 36)?)?,
            f.vec3("attachments", o + 40)?,
        ));
    }

    // Sequence groups and their files.
    let (ngroups, gat) = f.table("sequence groups", 172, 176, GROUP)?;
    let mut group_files: Vec<Option<Vec<u8>>> = vec![None; ngroups];
    let dir_of_group = |g: usize| -> Result<String, ImportError> {
        let name = f.name("sequence groups", gat + g * GROUP + 32, 64)?;
        Ok(name.rsplit(['/', '\\']).next().unwrap_or(&name).to_string())
    };

    // Sequences.
    let (nseq, sat) = f.table("sequences", 164, 168, SEQUENCE)?;
    let mut budget = MAX_ANIMATION_VALUES;
    for i in 0..nseq {
        let o = sat + i * SEQUENCE;
        let section = format!("sequences[{i}]");
        let sec = section.as_str();
        let label = f.name(sec, o, 32)?;
        let fps = f.f32(sec, o + 32)?;
        let flags = f.i32(sec, o + 36)?;
        let mut seq = StudioSequence {
            label: label.clone(),
            fps,
            looping: flags & 1 != 0,
            activity: (f.i32(sec, o + 40)?, f.i32(sec, o + 44)?),
            motion_type: f.i32(sec, o + 68)? as u32,
            linear_movement: f.vec3(sec, o + 76)?,
            blend_type: [f.i32(sec, o + 128)? as u32, f.i32(sec, o + 132)? as u32],
            blend_start: [f.f32(sec, o + 136)?, f.f32(sec, o + 140)?],
            blend_end: [f.f32(sec, o + 144)?, f.f32(sec, o + 148)?],
            nodes: (
                f.i32(sec, o + 160)?,
                f.i32(sec, o + 164)?,
                f.i32(sec, o + 168)?,
            ),
            ..StudioSequence::default()
        };
        let motion_bone = f.i32(sec, o + 72)?;
        seq.motion_bone = if nbones == 0 {
            0
        } else {
            bone_index(sec, o + 72, motion_bone)?
        };
        let (nev, eat) =
            f.check_table(sec, f.i32(sec, o + 48)?, f.i32(sec, o + 52)?, EVENT, o + 48)?;
        for e in 0..nev {
            let eo = eat + e * EVENT;
            seq.events.push((
                f.i32(sec, eo)?,
                f.i32(sec, eo + 4)?,
                f.i32(sec, eo + 8)?,
                f.name(sec, eo + 12, 64)?,
            ));
        }
        let frames = f.i32(sec, o + 56)?;
        let blends = f.i32(sec, o + 120)?;
        if frames < 1 || !(1..=16).contains(&blends) {
            return Err(f.err(
                sec,
                o + 56,
                format!("{frames} frames and {blends} blends (need at least 1 frame and 1 to 16 blends)"),
            ));
        }
        // A model without bones still gets a (empty) pose per frame: count frames as at least one bone.
        let values = (frames as u64) * (blends as u64) * (nbones.max(1) as u64);
        if values > budget {
            return Err(f.err(
                sec,
                o + 56,
                format!("{frames} frames x {blends} blends x {nbones} bones is more animation than sinew reads ({MAX_ANIMATION_VALUES} bone poses per file)"),
            ));
        }
        budget -= values;
        let group = f.i32(sec, o + 156)?;
        let group = usize::try_from(group)
            .ok()
            .filter(|&g| g < ngroups.max(1))
            .ok_or_else(|| {
                f.err(
                    sec,
                    o + 156,
                    format!("sequence group {group} does not exist ({ngroups} groups)"),
                )
            })?;
        let anim_index = f.i32(sec, o + 124)?;
        let data: Option<Bytes> = if group == 0 {
            Some(Bytes { file, b: bytes })
        } else {
            if group_files[group].is_none() {
                let name = dir_of_group(group)?;
                match resolve(&name) {
                    Ok(b) => group_files[group] = Some(b),
                    Err(e) if !allow_missing => {
                        return Err(f.err(
                            sec,
                            o + 156,
                            format!("cannot read sequence group file {name} for sequence {label:?}: {e} (--allow-missing converts without it)"),
                        ))
                    }
                    Err(e) => diagnostics.push(Diagnostic::warning(
                        "mdl-missing-sequence-group",
                        format!("sequence group file {name} ({e}): sequence {label:?} left out"),
                    )),
                }
            }
            group_files[group].as_deref().map(|b| Bytes { file, b })
        };
        if let Some(data) = data {
            if group > 0 {
                let magic = data.get(sec, 0, 4).ok();
                if magic != Some(b"IDSQ".as_slice()) {
                    return Err(f.err(
                        sec,
                        o + 156,
                        format!(
                            "sequence group file {} is not an IDSQ file",
                            dir_of_group(group)?
                        ),
                    ));
                }
            }
            for b in 0..blends as usize {
                seq.blends.push(decode_blend(
                    &data,
                    &model,
                    &scales,
                    anim_index,
                    b,
                    frames as usize,
                    sec,
                )?);
            }
        }
        model.sequences.push(seq);
    }

    // Transitions.
    let nt = f.i32("transitions", 236)?;
    let tat = f.i32("transitions", 240)?;
    if nt > 0 {
        let n = nt as usize;
        let (_, at) = f.check_table("transitions", nt.saturating_mul(nt.min(4096)), tat, 1, 236)?;
        if n > 255 {
            return Err(f.err("transitions", 236, format!("{n} transition nodes")));
        }
        model.transitions = f.get("transitions", at, n * n)?.to_vec();
        model.transition_nodes = n as u32;
    }

    // Textures, here or in NAMET.mdl.
    let ntex = f.i32("textures", 180)?;
    let texture_file: Option<Vec<u8>> = if ntex == 0 {
        let name = texture_companion(file);
        match resolve(&name) {
            Ok(b) => Some(b),
            Err(e) if !allow_missing => {
                return Err(f.err(
                    "textures",
                    180,
                    format!("the model keeps its textures in {name}, which cannot be read: {e} (--allow-missing converts without them)"),
                ))
            }
            Err(e) => {
                diagnostics.push(Diagnostic::warning(
                    "mdl-missing-textures",
                    format!("texture file {name} ({e}): materials have no images and texture coordinates stay in texels"),
                ));
                None
            }
        }
    } else {
        None
    };
    let tex_name = texture_companion(file);
    let tf = match &texture_file {
        Some(b) => {
            let t = Bytes { file: &tex_name, b };
            check_magic(&t)?;
            t.get("header", 0, HEADER_SIZE)?;
            check_length(&t)?;
            t
        }
        None => Bytes { file, b: bytes },
    };
    read_textures(&tf, &mut model)?;

    // Body parts, models, meshes.
    let (nparts, pat) = f.table("body parts", 204, 208, BODYPART)?;
    let world = bind_world(&model);
    for p in 0..nparts {
        let o = pat + p * BODYPART;
        let section = format!("bodyparts[{p}]");
        let name = f.name(&section, o, 64)?;
        let (nmodels, mat) = f.check_table(
            &section,
            f.i32(&section, o + 64)?,
            f.i32(&section, o + 72)?,
            MODEL,
            o + 64,
        )?;
        let mut part = BodyPart {
            name,
            submodels: Vec::new(),
        };
        for m in 0..nmodels {
            let mo = mat + m * MODEL;
            let section = format!("bodyparts[{p}].models[{m}]");
            part.submodels
                .push(read_submodel(&f, &section, mo, &model, &world)?);
        }
        model.body_parts.push(part);
    }
    Ok((model, diagnostics))
}

/// The bind pose's bone-to-model rotation and origin of every bone (parents come first).
fn bind_world(model: &StudioModel) -> Vec<(Mat3, Vec3)> {
    let mut world: Vec<(Mat3, Vec3)> = Vec::with_capacity(model.bones.len());
    for b in &model.bones {
        let v = b.value;
        let m = Mat3::from_quat(euler_to_quat([v[3], v[4], v[5]]));
        let p = Vec3::new(v[0], v[1], v[2]);
        let e = match b.parent.and_then(|q| world.get(q).copied()) {
            Some((pm, po)) => (pm * m, pm * p + po),
            None => (m, p),
        };
        world.push(e);
    }
    world
}

fn read_textures(f: &Bytes, model: &mut StudioModel) -> Result<(), ImportError> {
    let (n, at) = f.table("textures", 180, 184, TEXTURE)?;
    for i in 0..n {
        let o = at + i * TEXTURE;
        let section = format!("textures[{i}]");
        let width = f.i32(&section, o + 68)?;
        let height = f.i32(&section, o + 72)?;
        let index = f.i32(&section, o + 76)?;
        let side = |v: i32| {
            u32::try_from(v)
                .ok()
                .filter(|&v| v > 0 && v <= MAX_TEXTURE_SIDE)
        };
        let (Some(w), Some(h)) = (side(width), side(height)) else {
            return Err(f.err(
                &section,
                o + 68,
                format!("texture size {width}x{height} (sides 1 to {MAX_TEXTURE_SIDE})"),
            ));
        };
        let pixels = (w * h) as usize;
        let (_, data_at) = f.check_table(&section, 1, index, pixels + 768, o + 76)?;
        model.textures.push(StudioTexture {
            name: f.name(&section, o, 64)?,
            flags: f.i32(&section, o + 64)? as u32,
            width: w,
            height: h,
            indices: f.get(&section, data_at, pixels)?.to_vec(),
            palette: f.get(&section, data_at + pixels, 768)?.to_vec(),
        });
    }
    let refs = f.i32("skins", 192)?;
    let families = f.i32("skins", 196)?;
    let skin_at = f.i32("skins", 200)?;
    if refs > 0 && families > 0 {
        let count = refs
            .checked_mul(families)
            .ok_or_else(|| f.err("skins", 192, "skin table too large"))?;
        let (_, at) = f.check_table("skins", count, skin_at, 2, 192)?;
        for fam in 0..families as usize {
            let mut row = Vec::with_capacity(refs as usize);
            for r in 0..refs as usize {
                let pos = at + 2 * (fam * refs as usize + r);
                let t = f.i16("skins", pos)?;
                let t = usize::try_from(t)
                    .ok()
                    .filter(|&t| t < model.textures.len())
                    .ok_or_else(|| {
                        f.err(
                            "skins",
                            pos,
                            format!(
                                "texture {t} does not exist ({} textures)",
                                model.textures.len()
                            ),
                        )
                    })?;
                row.push(t);
            }
            model.skin_families.push(row);
        }
    }
    Ok(())
}

/// Decodes one blend of a sequence: per frame, per bone, the six values `default + stored * scale`.
fn decode_blend(
    data: &Bytes,
    model: &StudioModel,
    scales: &[[f32; 6]],
    anim_index: i32,
    blend: usize,
    frames: usize,
    section: &str,
) -> Result<Vec<Vec<[f32; 6]>>, ImportError> {
    let nbones = model.bones.len();
    let base = usize::try_from(anim_index).map_err(|_| {
        data.err(
            section,
            0,
            format!("negative animation offset {anim_index}"),
        )
    })?;
    let mut out = vec![Vec::with_capacity(nbones); frames];
    for (b, bone) in model.bones.iter().enumerate() {
        let at = base
            .checked_add((blend * nbones + b) * 12)
            .ok_or_else(|| data.err(section, base, "animation offset overflows"))?;
        let mut per_channel: Vec<Vec<f32>> = Vec::with_capacity(6);
        for k in 0..6 {
            let off = data.u16(section, at + 2 * k)?;
            let scale = scales.get(b).map_or(0.0, |s| s[k]);
            let default = bone.value[k];
            let mut values = vec![default; frames];
            if off != 0 {
                let raw = decode_channel(data, at + off as usize, frames, section)?;
                for (v, r) in values.iter_mut().zip(raw) {
                    *v = default + f32::from(r) * scale;
                }
            }
            per_channel.push(values);
        }
        for (fr, frame) in out.iter_mut().enumerate() {
            frame.push([
                per_channel[0][fr],
                per_channel[1][fr],
                per_channel[2][fr],
                per_channel[3][fr],
                per_channel[4][fr],
                per_channel[5][fr],
            ]);
        }
    }
    Ok(out)
}

/// The stored 16-bit values of one channel for frames `0..frames`: runs of `(valid, total)` with
/// `valid` values; frames past `valid` in a run repeat its last value.
fn decode_channel(
    data: &Bytes,
    start: usize,
    frames: usize,
    section: &str,
) -> Result<Vec<i16>, ImportError> {
    let mut out = Vec::with_capacity(frames);
    let mut at = start;
    while out.len() < frames {
        let head = data.get(section, at, 2)?;
        let (valid, total) = (head[0] as usize, head[1] as usize);
        if total == 0 || valid == 0 {
            return Err(data.err(
                section,
                at,
                format!("animation run with {valid} values over {total} frames"),
            ));
        }
        // More values than frames: the engine reads the first `total` and skips the rest; so does this.
        if out.len() + total > frames {
            return Err(data.err(
                section,
                at,
                format!("animation run of {total} frames passes the sequence's {frames} frames"),
            ));
        }
        for k in 0..total {
            let v = data.i16(section, at + 2 + 2 * k.min(valid - 1))?;
            out.push(v);
        }
        at += 2 * (valid + 1);
    }
    Ok(out)
}

fn read_submodel(
    f: &Bytes,
    section: &str,
    mo: usize,
    model: &StudioModel,
    world: &[(Mat3, Vec3)],
) -> Result<Submodel, ImportError> {
    let name = f.name(section, mo, 64)?;
    let (nmesh, meshat) = f.check_table(
        section,
        f.i32(section, mo + 72)?,
        f.i32(section, mo + 76)?,
        MESH,
        mo + 72,
    )?;
    let (nverts, vinfo) = f.check_table(
        section,
        f.i32(section, mo + 80)?,
        f.i32(section, mo + 84)?,
        1,
        mo + 80,
    )?;
    let (_, vidx) = f.check_table(
        section,
        nverts as i32,
        f.i32(section, mo + 88)?,
        12,
        mo + 88,
    )?;
    let (nnorms, ninfo) = f.check_table(
        section,
        f.i32(section, mo + 92)?,
        f.i32(section, mo + 96)?,
        1,
        mo + 92,
    )?;
    let (_, nidx) = f.check_table(
        section,
        nnorms as i32,
        f.i32(section, mo + 100)?,
        12,
        mo + 100,
    )?;
    let nbones = model.bones.len();
    let bone_of = |at: usize| -> Result<usize, ImportError> {
        let b = f.get(section, at, 1)?[0] as usize;
        if b < nbones {
            Ok(b)
        } else {
            Err(f.err(
                section,
                at,
                format!("vertex bone {b} is not below the bone count {nbones}"),
            ))
        }
    };
    let to_model = |b: usize, v: [f32; 3], point: bool| -> [f32; 3] {
        let (m, o) = world
            .get(b)
            .copied()
            .unwrap_or((Mat3::IDENTITY, Vec3::ZERO));
        let r = m * Vec3::from_array(v);
        if point {
            (r + o).to_array()
        } else {
            r.to_array()
        }
    };
    let mut vertices = Vec::with_capacity(nverts);
    for i in 0..nverts {
        let b = bone_of(vinfo + i)?;
        vertices.push(StudioVertex {
            position: to_model(b, f.vec3(section, vidx + 12 * i)?, true),
            influences: vec![(b, 1.0)],
        });
    }
    let mut normals = Vec::with_capacity(nnorms);
    for i in 0..nnorms {
        let b = bone_of(ninfo + i)?;
        normals.push(to_model(b, f.vec3(section, nidx + 12 * i)?, false));
    }
    let mut meshes = Vec::with_capacity(nmesh);
    for k in 0..nmesh {
        let me = meshat + k * MESH;
        let msec = format!("{section}.meshes[{k}]");
        let skin_slot = f.i32(&msec, me + 8)?;
        let skin_slot = usize::try_from(skin_slot).map_err(|_| {
            f.err(
                &msec,
                me + 8,
                format!("negative skin reference {skin_slot}"),
            )
        })?;
        let texture = model
            .skin_families
            .first()
            .and_then(|row| row.get(skin_slot))
            .or(if model.skin_families.is_empty() {
                Some(&skin_slot)
            } else {
                None
            })
            .and_then(|&t| model.textures.get(t));
        let (w, h) = texture.map_or((1.0, 1.0), |t| (t.width as f32, t.height as f32));
        let tri_at = f.i32(&msec, me + 4)?;
        let mut at = usize::try_from(tri_at)
            .map_err(|_| f.err(&msec, me + 4, format!("negative triangle offset {tri_at}")))?;
        let tsec = format!("{msec}.tricmds");
        let mut triangles = Vec::new();
        loop {
            let n = f.i16(&tsec, at)?;
            at += 2;
            if n == 0 {
                break;
            }
            let count = n.unsigned_abs() as usize;
            if count < 3 {
                return Err(f.err(
                    &tsec,
                    at - 2,
                    format!(
                        "a {} of {count} vertices",
                        if n > 0 { "strip" } else { "fan" }
                    ),
                ));
            }
            let mut corners = Vec::with_capacity(count);
            for j in 0..count {
                let c = at + 8 * j;
                let v = f.i16(&tsec, c)?;
                let nn = f.i16(&tsec, c + 2)?;
                let s = f.i16(&tsec, c + 4)?;
                let t = f.i16(&tsec, c + 6)?;
                let v = usize::try_from(v)
                    .ok()
                    .filter(|&v| v < nverts)
                    .ok_or_else(|| {
                        f.err(
                            &tsec,
                            c,
                            format!("vertex {v} is not below the vertex count {nverts}"),
                        )
                    })?;
                let nn = usize::try_from(nn)
                    .ok()
                    .filter(|&n| n < nnorms)
                    .ok_or_else(|| {
                        f.err(
                            &tsec,
                            c + 2,
                            format!("normal {nn} is not below the normal count {nnorms}"),
                        )
                    })?;
                corners.push(Corner {
                    vertex: v,
                    normal: normals[nn],
                    uv: [f32::from(s) / w, f32::from(t) / h],
                });
            }
            at += 8 * count;
            for j in 0..count - 2 {
                let tri = if n < 0 {
                    [corners[0], corners[j + 1], corners[j + 2]]
                } else if j % 2 == 0 {
                    [corners[j], corners[j + 1], corners[j + 2]]
                } else {
                    [corners[j + 1], corners[j], corners[j + 2]]
                };
                // studiomdl stored the source triangles reversed; turn them back.
                triangles.push([tri[2], tri[1], tri[0]]);
            }
            if triangles.len() > (1 << 24) {
                return Err(f.err(&tsec, at, "more than 16 million triangles"));
            }
        }
        meshes.push(StudioMesh {
            skin_slot,
            triangles,
        });
    }
    Ok(Submodel {
        name,
        vertices,
        meshes,
    })
}
