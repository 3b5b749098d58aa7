//! The picture of a joint mapping (`sinew map --png`): the rig's and the motion's skeletons side by
//! side in their rest poses, a line between each matched pair coloured by how it matched, unmatched
//! joints in red with their names, and the warnings written under the picture.

use super::camera::{Fit, Up, View};
use super::canvas::{Canvas, Cell, Rgb};
use super::text;
use crate::mapping::{Mapping, MatchMethod};
use sinew_core::glam::{Mat4, Vec3};
use sinew_core::{local_to_model, Skeleton};

/// Picture width, pixels.
pub const WIDTH: u32 = 1200;
/// Height of the skeleton area, pixels.
pub const AREA: u32 = 600;
/// Height of the title and legend lines above the area.
pub const HEADER: u32 = 52;
/// Height of one text line under the area.
pub const LINE: u32 = 16;

/// Line colour of an exact match.
pub const EXACT: Rgb = [40, 160, 70];
/// Line colour of a match after normalising names.
pub const NORMALISED: Rgb = [20, 150, 160];
/// Line colour of a synonym (body-part slot) match.
pub const SYNONYM: Rgb = [50, 100, 220];
/// Line colour of a fuzzy match.
pub const FUZZY: Rgb = [230, 140, 20];
/// Line colour of a pair read from a mapping file.
pub const MANUAL: Rgb = [150, 60, 200];
/// Colour of unmatched joints and their names.
pub const UNMATCHED: Rgb = [220, 40, 40];

const BACKGROUND: Rgb = [250, 250, 247];
const BONES: Rgb = [150, 150, 150];
const INK: Rgb = [40, 40, 48];

/// One side of the picture.
#[derive(Debug, Clone, Copy)]
pub struct Side<'a> {
    /// The skeleton, drawn in its rest pose; `None` draws `names` as a list.
    pub skeleton: Option<&'a Skeleton>,
    /// Joint names when there is no skeleton (a motion of clips alone).
    pub names: &'a [String],
    /// The up axis of this side's file.
    pub up: Up,
}

/// What the picture shows.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct MapPictureReport {
    /// Picture width, pixels.
    pub width: u32,
    /// Picture height, pixels.
    pub height: u32,
    /// Lines drawn between matched pairs.
    pub lines: usize,
    /// Unmatched joints drawn in red (rig, then motion).
    pub unmatched: usize,
}

/// The colour of a match method.
pub fn method_color(m: &MatchMethod) -> Rgb {
    match m {
        MatchMethod::Exact => EXACT,
        MatchMethod::Normalised => NORMALISED,
        MatchMethod::Synonym { .. } => SYNONYM,
        MatchMethod::Fuzzy { .. } => FUZZY,
        MatchMethod::File => MANUAL,
    }
}

/// Joint names with their pixel positions.
type Placed = Vec<(String, (f32, f32))>;

/// Screen positions of one side's joints by name, and its bones (parent, child).
fn layout(side: &Side<'_>, cell: Cell) -> (Placed, Vec<(usize, usize)>) {
    match side.skeleton {
        Some(s) if !s.is_empty() => {
            let mut models = vec![Mat4::IDENTITY; s.len()];
            if local_to_model(s.parents(), s.bind_local(), &mut models).is_err() {
                return (Vec::new(), Vec::new());
            }
            let pts: Vec<Vec3> = models.iter().map(|m| m.w_axis.truncate()).collect();
            let fit = Fit::new(View::front(side.up.into()), pts.iter().copied(), cell, 40.0);
            let pos = s
                .names()
                .iter()
                .zip(&pts)
                .map(|(n, &p)| {
                    let q = fit.project(p);
                    (n.clone(), (q.x, q.y))
                })
                .collect();
            let bones = s
                .parents()
                .iter()
                .enumerate()
                .filter_map(|(j, p)| p.map(|p| (p as usize, j)))
                .collect();
            (pos, bones)
        }
        _ => {
            let n = side.names.len().max(1) as f32;
            let step = ((cell.h as f32 - 40.0) / n).min(18.0);
            let pos = side
                .names
                .iter()
                .enumerate()
                .map(|(i, name)| {
                    (
                        name.clone(),
                        (cell.x as f32 + 60.0, cell.y as f32 + 20.0 + step * i as f32),
                    )
                })
                .collect();
            (pos, Vec::new())
        }
    }
}

/// The last component of a path label (the picture shows file names, not folders).
fn file_label(label: &str) -> &str {
    label.rsplit(['/', '\\']).next().unwrap_or(label)
}

/// Draws the mapping picture and encodes it as PNG.
pub fn mapping_picture(
    rig: &Side<'_>,
    motion: &Side<'_>,
    mapping: &Mapping,
) -> Result<(Vec<u8>, MapPictureReport), String> {
    let bound = mapping
        .entries
        .iter()
        .filter(|e| e.motion.is_some())
        .count();
    let unmatched_rig: Vec<&str> = mapping
        .entries
        .iter()
        .filter(|e| e.motion.is_none())
        .map(|e| e.rig.as_str())
        .collect();
    let mut lines_under: Vec<(String, Rgb)> = Vec::new();
    let list = |v: &[&str]| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.join(", ")
        }
    };
    lines_under.push((
        format!(
            "unmatched rig joints ({}): {}",
            unmatched_rig.len(),
            list(&unmatched_rig)
        ),
        UNMATCHED,
    ));
    let um: Vec<&str> = mapping
        .unmatched_motion
        .iter()
        .map(String::as_str)
        .collect();
    lines_under.push((
        format!("unmatched motion joints ({}): {}", um.len(), list(&um)),
        UNMATCHED,
    ));
    lines_under.push((format!("warnings: {}", mapping.warnings.len()), INK));
    for w in &mapping.warnings {
        lines_under.push((format!("[{}] {}", w.code, w.message), INK));
    }
    let height = HEADER + AREA + LINE * lines_under.len() as u32 + 12;
    let mut canvas = Canvas::new(WIDTH, height, BACKGROUND).ok_or("picture too large")?;
    let title = format!(
        "rig {} ({})  <-  motion {} ({}): {} of {} rig joints bound",
        file_label(&mapping.rig),
        mapping.rig_family.name(),
        file_label(&mapping.motion),
        mapping.motion_family.name(),
        bound,
        mapping.entries.len()
    );
    let t = text::fit(&title, 14.0, WIDTH as f32 - 16.0);
    text::draw(&mut canvas, 8.0, 20.0, 14.0, &t, INK);
    let mut x = 8.0;
    for (label, c) in [
        ("exact", EXACT),
        ("normalised", NORMALISED),
        ("synonym", SYNONYM),
        ("fuzzy", FUZZY),
        ("manual (file)", MANUAL),
        ("unmatched", UNMATCHED),
    ] {
        canvas.line((x, 40.0), (x + 18.0, 40.0), c, 3.0);
        text::draw(&mut canvas, x + 24.0, 44.0, 11.0, label, INK);
        x += 34.0 + text::width(label, 11.0) + 14.0;
    }
    let half = WIDTH / 2;
    let left = Cell {
        x: 0,
        y: HEADER,
        w: half,
        h: AREA,
    };
    let right = Cell {
        x: half,
        y: HEADER,
        w: half,
        h: AREA,
    };
    canvas.line(
        (half as f32, HEADER as f32 + 8.0),
        (half as f32, (HEADER + AREA) as f32 - 8.0),
        [220, 220, 215],
        1.0,
    );
    text::draw(
        &mut canvas,
        8.0,
        HEADER as f32 + 14.0,
        12.0,
        &text::fit(
            &format!("rig: {}", file_label(&mapping.rig)),
            12.0,
            half as f32 - 16.0,
        ),
        INK,
    );
    text::draw(
        &mut canvas,
        half as f32 + 8.0,
        HEADER as f32 + 14.0,
        12.0,
        &text::fit(
            &format!("motion: {}", file_label(&mapping.motion)),
            12.0,
            half as f32 - 16.0,
        ),
        INK,
    );
    let (rig_pos, rig_bones) = layout(rig, left);
    let (mot_pos, mot_bones) = layout(motion, right);
    for (pos, bones) in [(&rig_pos, &rig_bones), (&mot_pos, &mot_bones)] {
        for &(p, c) in bones.iter() {
            if let (Some(a), Some(b)) = (pos.get(p), pos.get(c)) {
                canvas.line(a.1, b.1, BONES, 2.0);
            }
        }
    }
    let find = |pos: &[(String, (f32, f32))], name: &str| {
        pos.iter().find(|(n, _)| n == name).map(|(_, p)| *p)
    };
    let mut lines = 0;
    for e in &mapping.entries {
        if let (Some(m), Some(method)) = (&e.motion, &e.method) {
            if let (Some(a), Some(b)) = (find(&rig_pos, &e.rig), find(&mot_pos, m)) {
                canvas.line(a, b, method_color(method), 1.5);
                lines += 1;
            }
        }
    }
    let matched_motion: Vec<&str> = mapping
        .entries
        .iter()
        .filter_map(|e| e.motion.as_deref())
        .collect();
    let mut unmatched = 0;
    // Names of joints that sit together (fingers, end sites) are stacked downwards, not overprinted.
    let mut labels: Vec<(f32, f32)> = Vec::new();
    for (pos, is_rig) in [(&rig_pos, true), (&mot_pos, false)] {
        for (name, p) in pos.iter() {
            let matched = if is_rig {
                !unmatched_rig.contains(&name.as_str())
            } else {
                matched_motion.contains(&name.as_str())
            };
            if matched {
                canvas.dot(*p, 3.0, [60, 60, 60]);
            } else {
                canvas.dot(*p, 4.0, UNMATCHED);
                let mut at = (p.0 + 6.0, p.1 - 3.0);
                while labels
                    .iter()
                    .any(|l| (l.0 - at.0).abs() < 60.0 && (l.1 - at.1).abs() < 10.0)
                {
                    at.1 += 10.0;
                }
                let w = text::width(name, 9.0);
                if at.0 + w > WIDTH as f32 - 4.0 {
                    at.0 = p.0 - 6.0 - w;
                }
                labels.push(at);
                text::draw(&mut canvas, at.0, at.1, 9.0, name, UNMATCHED);
                unmatched += 1;
            }
        }
    }
    for (i, (l, c)) in lines_under.iter().enumerate() {
        let t = text::fit(l, 11.0, WIDTH as f32 - 16.0);
        text::draw(
            &mut canvas,
            8.0,
            (HEADER + AREA + LINE * (i as u32 + 1)) as f32 - 2.0,
            11.0,
            &t,
            *c,
        );
    }
    let png = canvas.png()?;
    Ok((
        png,
        MapPictureReport {
            width: WIDTH,
            height,
            lines,
            unmatched,
        },
    ))
}
