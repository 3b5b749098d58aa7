//! Reading a QC's commands the way studiomdl's `ParseScript` does, into the tables of [`super::state`].

use super::reference::{grab_animation, reference_model};
use super::simplify::build;
use super::state::{activity_number, control, lookup_texture, Sequence, State, MAX_FRAMES};
use crate::halflife::model::StudioModel;
use crate::halflife::qc::{atoi, Cursor, Script, Tok};
use crate::halflife::smd::{self, Smd};
use crate::{ImportError, Resolver};
use sinew_core::format::game::{material_flags, motion_flags};
use sinew_scene::Diagnostic;
use std::f64::consts::PI;

/// Compiles a QC script (its includes already expanded). An SMD that cannot be read is an error
/// naming the file, line and command (studiomdl stops there too), or with `allow_missing` a
/// `qc-missing-smd` warning; a script none of whose SMDs can be read is an error either way.
pub fn compile(
    qc: &str,
    script: &Script,
    resolve: Resolver<'_>,
    allow_missing: bool,
) -> Result<(StudioModel, Vec<Diagnostic>), ImportError> {
    let mut s = State {
        qc,
        resolve,
        allow_missing,
        smds_read: 0,
        first_missing: None,
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
    if s.smds_read == 0 {
        if let Some(first) = s.first_missing.take() {
            return Err(ImportError {
                message: format!("{}; no SMD the script names can be read", first.message),
                ..first
            });
        }
    }
    build(s, script)
}

pub(super) fn t_or<'a>(c: &Cursor<'a>, fallback: &'a Tok) -> &'a Tok {
    c.last().unwrap_or(fallback)
}

/// The path of an SMD named in the script: `$cd` joined with the name, `.smd` added.
pub(super) fn smd_path(cd: &str, name: &str) -> String {
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

/// Reads an SMD the script names at token `at`. A missing file is an error naming the script's file,
/// line and command, or with `allow_missing` `None` and a warning.
pub(super) fn read_smd(
    s: &mut State,
    script: &Script,
    name: &str,
    section: &str,
    at: &Tok,
) -> Result<Option<Smd>, ImportError> {
    let path = smd_path(&s.cd, name);
    match (s.resolve)(&path) {
        Ok(bytes) => {
            s.smds_read += 1;
            smd::parse(&path, &bytes).map(Some)
        }
        Err(e) => {
            let error = script.error_at(at, section, format!("cannot read {path}: {e}"));
            if !s.allow_missing {
                return Err(ImportError {
                    message: format!("{} (--allow-missing leaves it out)", error.message),
                    ..error
                });
            }
            s.diagnostics.push(Diagnostic::warning(
                "qc-missing-smd",
                format!(
                    "{} line {} ({section}): cannot read {path}: {e}; left out",
                    error.file, at.line
                ),
            ));
            s.first_missing.get_or_insert(error);
            Ok(None)
        }
    }
}

/// studiomdl's `Option_Studio`: a reference SMD with its options, as one choice of the last part.
pub(super) fn studio(s: &mut State, c: &mut Cursor, section: &str) -> Result<(), ImportError> {
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
    let Some(smd) = read_smd(s, c.script(), &name, section, tok)? else {
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

pub(super) fn texture_group(s: &mut State, c: &mut Cursor, cmd: &Tok) -> Result<(), ImportError> {
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
pub(super) fn sequence(s: &mut State, c: &mut Cursor) -> Result<(), ImportError> {
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
    let mut files: Vec<&Tok> = Vec::new();
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
        let starts = |p: &str| lower.starts_with(p);
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
            files.push(c.expect("$sequence", "an animation SMD")?);
        } else if activity_number(&t.text) != 0 {
            seq.activity = activity_number(&t.text);
            seq.weight = c.integer("$sequence", "an activity weight")?;
        } else {
            files.push(t);
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
    for tok in files {
        let (file, line) = (&tok.text, tok.line);
        let Some(smd) = read_smd(s, script, file, "$sequence", tok)? else {
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
