//! Importer for Biovision BVH motion files (see docs/formats/bvh.md).
//!
//! A BVH file becomes a [`Scene`] with a skeleton (bind pose: translation = `OFFSET`, identity
//! rotation; each `End Site` becomes a leaf joint named `<parent>_end`) and one clip keyed by joint
//! name: frame 0 at time 0, `sample_rate = 1 / Frame Time`, `duration = (frames - 1) * Frame Time`,
//! not looping. Position channels *replace* the `OFFSET` component they name; rotation channels compose
//! in the order listed (`Zrotation Xrotation Yrotation` is `Rz * Rx * Ry` acting on column vectors),
//! in degrees.
//!
//! The parser is line based: keywords are the first word of a line, a joint's name is the rest of its
//! `ROOT`/`JOINT` line (trimmed, so names may contain spaces or colons), and each frame of `MOTION`
//! is one line holding exactly as many numbers as the hierarchy declares channels. Every error names
//! the line.

use crate::text::{clip_name, decode, numbered_lines, parse_finite, truncate};
use crate::{ImportError, ImportOptions, Resolver};
use sinew_core::glam::{DQuat, DVec3, Quat, Vec3};
use sinew_core::{Curve, JointDesc, Skeleton, TrackCurves, Transform};
use sinew_scene::{Diagnostic, Scene, SceneClip, SourceFormat};

/// One channel of a joint's `CHANNELS` list.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ChannelKind {
    Pos(usize),
    Rot(usize),
}

/// A joint as read from HIERARCHY.
#[derive(Debug)]
struct RawJoint {
    name: String,
    parent: Option<usize>,
    offset: DVec3,
    channels: Vec<ChannelKind>,
    /// Index of this joint's first value in a frame line.
    first_channel: usize,
    end_site: bool,
}

/// Deepest nesting accepted, so that a hostile file cannot build an absurd hierarchy.
const MAX_DEPTH: usize = 4096;
/// Most channels a single joint may declare.
const MAX_CHANNELS_PER_JOINT: usize = 64;

fn err(file: &str, section: &str, line: usize, msg: impl Into<String>) -> ImportError {
    ImportError::at_line(file, section, line, msg)
}

fn channel_kind(tok: &str) -> Option<ChannelKind> {
    let lower = tok.to_ascii_lowercase();
    Some(match lower.as_str() {
        "xposition" => ChannelKind::Pos(0),
        "yposition" => ChannelKind::Pos(1),
        "zposition" => ChannelKind::Pos(2),
        "xrotation" => ChannelKind::Rot(0),
        "yrotation" => ChannelKind::Rot(1),
        "zrotation" => ChannelKind::Rot(2),
        _ => return None,
    })
}

/// Imports a BVH file.
pub fn import(
    file_name: &str,
    bytes: &[u8],
    _resolve: Resolver<'_>,
    _options: &ImportOptions,
) -> Result<Scene, ImportError> {
    let text = decode(bytes);
    let mut it = numbered_lines(&text);
    let f = file_name;

    // HIERARCHY header.
    let mut header_line = 0;
    for (n, l) in it.by_ref() {
        let t = l.trim();
        if t.is_empty() {
            continue;
        }
        if !t.eq_ignore_ascii_case("HIERARCHY") {
            return Err(err(
                f,
                "HIERARCHY",
                n,
                format!("expected HIERARCHY, found {:?}", truncate(t)),
            ));
        }
        header_line = n;
        break;
    }
    if header_line == 0 {
        return Err(ImportError::in_section(
            f,
            "HIERARCHY",
            "file is empty (no HIERARCHY line)",
        ));
    }

    let mut joints: Vec<RawJoint> = Vec::new();
    let mut names: std::collections::HashSet<String> = std::collections::HashSet::new();
    // Stack of open nodes (indices into `joints`).
    let mut stack: Vec<usize> = Vec::new();
    // A ROOT/JOINT/End Site line seen, waiting for its `{`.
    let mut pending: Option<usize> = None;
    let mut total_channels = 0usize;
    let mut motion_line = 0usize;
    let mut last_line = header_line;

    for (n, raw) in it.by_ref() {
        last_line = n;
        let t = raw.trim();
        if t.is_empty() {
            continue;
        }
        let (kw, rest) = match t.split_once(|c: char| c.is_ascii_whitespace()) {
            Some((k, r)) => (k, r.trim()),
            None => (t, ""),
        };
        let open_after;
        match kw {
            k if k.eq_ignore_ascii_case("ROOT") || k.eq_ignore_ascii_case("JOINT") => {
                let is_root = k.eq_ignore_ascii_case("ROOT");
                if pending.is_some() {
                    return Err(err(f, "HIERARCHY", n, "expected `{` before this joint"));
                }
                let (name, brace) = match rest.strip_suffix('{') {
                    Some(r) => (r.trim(), true),
                    None => (rest, false),
                };
                if name.is_empty() {
                    return Err(err(f, "HIERARCHY", n, format!("{kw} without a name")));
                }
                if is_root && !stack.is_empty() {
                    return Err(err(
                        f,
                        "HIERARCHY",
                        n,
                        "ROOT inside another joint (missing `}`?)",
                    ));
                }
                if !is_root && stack.is_empty() {
                    return Err(err(f, "HIERARCHY", n, "JOINT outside any ROOT"));
                }
                if let Some(parent) = stack.last() {
                    if joints.get(*parent).is_some_and(|p| p.end_site) {
                        return Err(err(f, "HIERARCHY", n, "JOINT inside an End Site"));
                    }
                }
                if !names.insert(name.to_string()) {
                    return Err(err(
                        f,
                        "HIERARCHY",
                        n,
                        format!("duplicate joint name {name:?}"),
                    ));
                }
                joints.push(RawJoint {
                    name: name.to_string(),
                    parent: stack.last().copied(),
                    offset: DVec3::ZERO,
                    channels: Vec::new(),
                    first_channel: total_channels,
                    end_site: false,
                });
                pending = Some(joints.len() - 1);
                open_after = brace;
            }
            k if k.eq_ignore_ascii_case("End") => {
                let (site, brace) = match rest.strip_suffix('{') {
                    Some(r) => (r.trim(), true),
                    None => (rest, false),
                };
                if !site.eq_ignore_ascii_case("Site") {
                    return Err(err(
                        f,
                        "HIERARCHY",
                        n,
                        format!("expected `End Site`, found {:?}", truncate(t)),
                    ));
                }
                if pending.is_some() {
                    return Err(err(f, "HIERARCHY", n, "expected `{` before End Site"));
                }
                let Some(&parent) = stack.last() else {
                    return Err(err(f, "HIERARCHY", n, "End Site outside any joint"));
                };
                let Some(p) = joints.get(parent) else {
                    return Err(err(f, "HIERARCHY", n, "End Site outside any joint"));
                };
                if p.end_site {
                    return Err(err(f, "HIERARCHY", n, "End Site inside an End Site"));
                }
                let base = format!("{}_end", p.name);
                let mut name = base.clone();
                let mut k = 2;
                while names.contains(&name) {
                    name = format!("{base}{k}");
                    k += 1;
                }
                names.insert(name.clone());
                joints.push(RawJoint {
                    name,
                    parent: Some(parent),
                    offset: DVec3::ZERO,
                    channels: Vec::new(),
                    first_channel: total_channels,
                    end_site: true,
                });
                pending = Some(joints.len() - 1);
                open_after = brace;
            }
            "{" => {
                let Some(p) = pending.take() else {
                    return Err(err(
                        f,
                        "HIERARCHY",
                        n,
                        "`{` without a ROOT, JOINT or End Site",
                    ));
                };
                if stack.len() >= MAX_DEPTH {
                    return Err(err(f, "HIERARCHY", n, "hierarchy nested too deeply"));
                }
                stack.push(p);
                if !rest.is_empty() {
                    return Err(err(f, "HIERARCHY", n, "unexpected text after `{`"));
                }
                continue;
            }
            "}" => {
                if pending.is_some() {
                    return Err(err(f, "HIERARCHY", n, "`}` before the joint's `{`"));
                }
                if stack.pop().is_none() {
                    return Err(err(f, "HIERARCHY", n, "unmatched `}`"));
                }
                if !rest.is_empty() && rest.chars().any(|c| c != '}') {
                    return Err(err(f, "HIERARCHY", n, "unexpected text after `}`"));
                }
                for _ in rest.chars() {
                    if stack.pop().is_none() {
                        return Err(err(f, "HIERARCHY", n, "unmatched `}`"));
                    }
                }
                continue;
            }
            k if k.eq_ignore_ascii_case("OFFSET") => {
                let Some(&cur) = stack.last() else {
                    return Err(err(f, "HIERARCHY", n, "OFFSET outside any joint"));
                };
                let toks: Vec<&str> = rest.split_ascii_whitespace().take(4).collect();
                if toks.len() != 3 {
                    return Err(err(f, "HIERARCHY", n, "OFFSET needs exactly 3 numbers"));
                }
                let mut v = [0.0f64; 3];
                for (slot, tok) in v.iter_mut().zip(&toks) {
                    *slot = parse_finite(f, "HIERARCHY", n, tok)?;
                }
                if let Some(j) = joints.get_mut(cur) {
                    j.offset = DVec3::from_array(v);
                }
                continue;
            }
            k if k.eq_ignore_ascii_case("CHANNELS") => {
                let Some(&cur) = stack.last() else {
                    return Err(err(f, "HIERARCHY", n, "CHANNELS outside any joint"));
                };
                let mut toks = rest.split_ascii_whitespace();
                let count_tok = toks.next().unwrap_or("");
                let count: usize = count_tok.parse().map_err(|_| {
                    err(
                        f,
                        "HIERARCHY",
                        n,
                        format!("expected a channel count, found {count_tok:?}"),
                    )
                })?;
                if count > MAX_CHANNELS_PER_JOINT {
                    return Err(err(
                        f,
                        "HIERARCHY",
                        n,
                        format!("{count} channels on one joint (at most {MAX_CHANNELS_PER_JOINT})"),
                    ));
                }
                let mut chans = Vec::with_capacity(count);
                for tok in toks {
                    let Some(c) = channel_kind(tok) else {
                        return Err(err(
                            f,
                            "HIERARCHY",
                            n,
                            format!("unknown channel {:?}", truncate(tok)),
                        ));
                    };
                    chans.push(c);
                }
                if chans.len() != count {
                    return Err(err(
                        f,
                        "HIERARCHY",
                        n,
                        format!(
                            "CHANNELS declares {count} channels but lists {}",
                            chans.len()
                        ),
                    ));
                }
                let Some(j) = joints.get_mut(cur) else {
                    return Err(err(f, "HIERARCHY", n, "CHANNELS outside any joint"));
                };
                if j.end_site {
                    return Err(err(f, "HIERARCHY", n, "CHANNELS inside an End Site"));
                }
                if !j.channels.is_empty() {
                    return Err(err(f, "HIERARCHY", n, "second CHANNELS line for one joint"));
                }
                // Channels are laid out in the order the CHANNELS lines appear.
                j.first_channel = total_channels;
                total_channels += count;
                j.channels = chans;
                continue;
            }
            k if k.eq_ignore_ascii_case("MOTION") => {
                if pending.is_some() || !stack.is_empty() {
                    return Err(err(
                        f,
                        "HIERARCHY",
                        n,
                        "MOTION before every joint was closed with `}`",
                    ));
                }
                motion_line = n;
                break;
            }
            _ => {
                return Err(err(
                    f,
                    "HIERARCHY",
                    n,
                    format!("unexpected {:?}", truncate(t)),
                ))
            }
        }
        if open_after {
            if let Some(p) = pending.take() {
                if stack.len() >= MAX_DEPTH {
                    return Err(err(f, "HIERARCHY", n, "hierarchy nested too deeply"));
                }
                stack.push(p);
            }
        }
    }
    if motion_line == 0 {
        return Err(err(f, "HIERARCHY", last_line, "file ends before MOTION"));
    }
    if joints.is_empty() {
        return Err(err(f, "HIERARCHY", motion_line, "no ROOT joint"));
    }

    // MOTION header: `Frames: n` and `Frame Time: t`.
    let mut next_nonblank = |what: &str| -> Result<(usize, String), ImportError> {
        for (n, l) in it.by_ref() {
            let t = l.trim();
            if !t.is_empty() {
                return Ok((n, t.to_string()));
            }
        }
        Err(ImportError::in_section(
            f,
            "MOTION",
            format!("file ends before `{what}`"),
        ))
    };
    let (frames_line, t) = next_nonblank("Frames:")?;
    let frames: usize = match t.split_once(':') {
        Some((k, v)) if k.trim().eq_ignore_ascii_case("Frames") => {
            v.trim().parse().map_err(|_| {
                err(
                    f,
                    "MOTION",
                    frames_line,
                    format!("expected a frame count, found {:?}", truncate(v.trim())),
                )
            })?
        }
        _ => {
            return Err(err(
                f,
                "MOTION",
                frames_line,
                format!("expected `Frames: n`, found {:?}", truncate(&t)),
            ))
        }
    };
    let (ft_line, t) = next_nonblank("Frame Time:")?;
    let frame_time = match t.split_once(':') {
        Some((k, v))
            if k.split_ascii_whitespace()
                .map(|w| w.to_ascii_lowercase())
                .eq(["frame", "time"].iter().map(|s| s.to_string())) =>
        {
            parse_finite(f, "MOTION", ft_line, v.trim())?
        }
        _ => {
            return Err(err(
                f,
                "MOTION",
                ft_line,
                format!("expected `Frame Time: seconds`, found {:?}", truncate(&t)),
            ))
        }
    };
    if frame_time <= 0.0 {
        return Err(err(
            f,
            "MOTION",
            ft_line,
            format!("frame time {frame_time} is not positive"),
        ));
    }

    // Frame lines: collect the non-blank lines first, so the frame count is checked against the lines
    // present before anything is allocated from it.
    let data_lines: Vec<(usize, &str)> = it.filter(|(_, l)| !l.trim().is_empty()).collect();
    if data_lines.len() < frames {
        let at = data_lines.last().map(|d| d.0).unwrap_or(ft_line);
        return Err(err(
            f,
            "MOTION",
            at,
            format!(
                "`Frames: {frames}` (line {frames_line}) but only {} frame lines follow",
                data_lines.len()
            ),
        ));
    }
    let mut diagnostics = Vec::new();
    if data_lines.len() > frames {
        diagnostics.push(
            Diagnostic::warning(
                "bvh-extra-frames",
                format!(
                    "{} lines after the last declared frame were ignored",
                    data_lines.len() - frames
                ),
            )
            .with_figure("ignored_lines", (data_lines.len() - frames) as f64),
        );
    }
    // Each value takes at least two bytes (a digit and a separator), which caps the reservation by the
    // bytes present even when the lines turn out to hold too few values.
    let mut values: Vec<f64> = Vec::with_capacity(
        frames
            .saturating_mul(total_channels)
            .min(text.len() / 2 + 1),
    );
    for (k, (n, l)) in data_lines.iter().take(frames).enumerate() {
        let before = values.len();
        for tok in l.split_ascii_whitespace() {
            if values.len() - before == total_channels {
                return Err(err(
                    f,
                    "MOTION",
                    *n,
                    format!("frame {k} has more than {total_channels} values"),
                ));
            }
            values.push(parse_finite(f, "MOTION", *n, tok)?);
        }
        let got = values.len() - before;
        if got != total_channels {
            return Err(err(
                f,
                "MOTION",
                *n,
                format!("frame {k} has {got} values, expected {total_channels}"),
            ));
        }
    }

    // Key times; they must stay strictly increasing in f32.
    let mut times = Vec::with_capacity(frames);
    for k in 0..frames {
        let t = (k as f64 * frame_time) as f32;
        if !t.is_finite() || times.last().is_some_and(|&p: &f32| t <= p) {
            return Err(err(
                f,
                "MOTION",
                ft_line,
                format!("frame time {frame_time} too small or too large for {frames} frames"),
            ));
        }
        times.push(t);
    }

    // Skeleton.
    let descs: Vec<JointDesc> = joints
        .iter()
        .map(|j| JointDesc {
            name: j.name.clone(),
            parent: j.parent.and_then(|p| joints.get(p)).map(|p| p.name.clone()),
            bind_local: Transform::from_translation(j.offset.as_vec3()),
            inverse_bind: None,
        })
        .collect();
    let (skeleton, _) = Skeleton::from_unordered(descs)
        .map_err(|e| ImportError::in_section(f, "HIERARCHY", format!("invalid skeleton: {e}")))?;
    let end_sites = joints.iter().filter(|j| j.end_site).count();
    if end_sites > 0 {
        diagnostics.push(
            Diagnostic::info(
                "bvh-end-sites",
                format!("{end_sites} End Sites became leaf joints named `<parent>_end`"),
            )
            .with_figure("end_sites", end_sites as f64),
        );
    }

    let mut scene = Scene::new(SourceFormat::Bvh);
    if frames == 0 {
        diagnostics.push(Diagnostic::warning(
            "bvh-no-frames",
            "`Frames: 0`: the file holds a skeleton and no motion",
        ));
    } else {
        let mut tracks = Vec::new();
        for j in joints.iter().filter(|j| !j.channels.is_empty()) {
            let has_pos = j.channels.iter().any(|c| matches!(c, ChannelKind::Pos(_)));
            let has_rot = j.channels.iter().any(|c| matches!(c, ChannelKind::Rot(_)));
            let mut tr = Vec::with_capacity(if has_pos { frames } else { 0 });
            let mut rot = Vec::with_capacity(if has_rot { frames } else { 0 });
            let mut prev = Quat::IDENTITY;
            for k in 0..frames {
                let start = k * total_channels + j.first_channel;
                let vals = values.get(start..start + j.channels.len()).unwrap_or(&[]);
                let mut t = j.offset;
                let mut q = DQuat::IDENTITY;
                for (c, &v) in j.channels.iter().zip(vals) {
                    match *c {
                        ChannelKind::Pos(a) => t[a] = v,
                        ChannelKind::Rot(a) => {
                            let r = v.to_radians();
                            q *= match a {
                                0 => DQuat::from_rotation_x(r),
                                1 => DQuat::from_rotation_y(r),
                                _ => DQuat::from_rotation_z(r),
                            };
                        }
                    }
                }
                if has_pos {
                    let v: Vec3 = t.as_vec3();
                    if !v.is_finite() {
                        return Err(err(
                            f,
                            "MOTION",
                            data_lines.get(k).map(|d| d.0).unwrap_or(0),
                            format!("joint {:?}: position overflows f32", j.name),
                        ));
                    }
                    tr.push(v);
                }
                if has_rot {
                    let mut qf = q.normalize().as_quat();
                    if qf.dot(prev) < 0.0 {
                        qf = -qf;
                    }
                    prev = qf;
                    rot.push(qf);
                }
            }
            tracks.push(TrackCurves {
                joint: j.name.clone(),
                translation: if has_pos {
                    Curve::new(times.clone(), tr)
                } else {
                    Curve::default()
                },
                rotation: if has_rot {
                    Curve::new(times.clone(), rot)
                } else {
                    Curve::default()
                },
                scale: Curve::default(),
            });
        }
        let duration = ((frames - 1) as f64 * frame_time) as f32;
        scene.clips.push(SceneClip {
            name: clip_name(f),
            duration,
            sample_rate: (1.0 / frame_time) as f32,
            looping: false,
            additive: false,
            tracks,
        });
    }
    scene.skeleton = Some(skeleton);
    scene.diagnostics = diagnostics;
    Ok(scene)
}
