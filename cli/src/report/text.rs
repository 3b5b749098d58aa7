//! The human-readable rendering of reports (stderr), and number formatting shared by every command.

use super::scene::InspectReport;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// A number with at most 4 decimals, trailing zeros dropped, and no `-0`.
pub fn num(x: f32) -> String {
    let s = format!("{x:.4}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" {
        "0".to_string()
    } else {
        s
    }
}

/// Numbers as [`num`] formats them, separated by spaces.
pub fn nums(v: &[f32]) -> String {
    v.iter().map(|&x| num(x)).collect::<Vec<_>>().join(", ")
}

/// The human-readable report (written to stderr by `run`).
pub fn human(r: &InspectReport) -> String {
    let mut o = String::new();
    let size = r
        .file_size
        .map_or_else(String::new, |s| format!(", {s} bytes"));
    let _ = writeln!(o, "{}: {}{size}", r.file, r.format);
    let s = &r.summary;
    let _ = writeln!(
        o,
        "  {} joints, {} clips, {} meshes ({} vertices, {} triangles), {} materials, {} warnings",
        s.joints, s.clips, s.meshes, s.vertices, s.triangles, s.materials, s.warnings
    );

    match &r.skeleton {
        None => {
            let _ = writeln!(o, "skeleton: none");
        }
        Some(sk) => {
            let _ = writeln!(o, "skeleton: {} joints", sk.joint_count);
            // Depth-first from each root, children in index order.
            let mut children: BTreeMap<Option<usize>, Vec<usize>> = BTreeMap::new();
            for j in &sk.joints {
                children.entry(j.parent).or_default().push(j.index);
            }
            let mut stack: Vec<usize> = children.get(&None).cloned().unwrap_or_default();
            stack.reverse();
            while let Some(i) = stack.pop() {
                let Some(j) = sk.joints.get(i) else { continue };
                let b = &j.bind;
                let parent = j
                    .parent
                    .map_or_else(|| "root".to_string(), |p| format!("parent {p}"));
                let _ = writeln!(
                    o,
                    "  {:indent$}[{}] {} ({parent})  T({}) R({})deg S({})",
                    "",
                    j.index,
                    j.name,
                    nums(&b.translation),
                    nums(&b.rotation_euler_deg),
                    nums(&b.scale),
                    indent = j.depth * 2
                );
                if let Some(kids) = children.get(&Some(i)) {
                    stack.extend(kids.iter().rev());
                }
            }
        }
    }

    let _ = writeln!(o, "clips: {}", r.clips.len());
    for c in &r.clips {
        let mut flags = Vec::new();
        if c.looping {
            flags.push("looping");
        }
        if c.additive {
            flags.push("additive");
        }
        let flags = if flags.is_empty() {
            String::new()
        } else {
            format!(", {}", flags.join(", "))
        };
        let _ = writeln!(
            o,
            "  \"{}\": {} s at {} fps, {} key times, {} keys (T {}, R {}, S {}){flags}",
            c.name,
            num(c.duration),
            num(c.sample_rate),
            c.key_times,
            c.keys.total,
            c.keys.translation,
            c.keys.rotation,
            c.keys.scale
        );
        let _ = writeln!(
            o,
            "    drives {} joints: {}",
            c.driven_joints.len(),
            c.driven_joints.join(", ")
        );
        if let Some(e) = &c.encodings {
            let bits = if e.quantized > 0 {
                format!(" ({}-{} bits)", e.min_bits, e.max_bits)
            } else {
                String::new()
            };
            let _ = writeln!(
                o,
                "    stored {}: {} quantized{bits}, {} f32, {} constant, {} bind channels",
                if e.compressed { "compressed" } else { "plain" },
                e.quantized,
                e.f32,
                e.constant,
                e.bind
            );
        }
        match &c.unmatched_joints {
            None => {
                let _ = writeln!(
                    o,
                    "    no skeleton in this file to match joint names against"
                );
            }
            Some(u) if u.is_empty() => {}
            Some(u) => {
                let _ = writeln!(
                    o,
                    "    {} names match no joint of the skeleton: {}",
                    u.len(),
                    u.join(", ")
                );
            }
        }
    }

    let _ = writeln!(o, "meshes: {}", r.meshes.len());
    for m in &r.meshes {
        let _ = writeln!(
            o,
            "  \"{}\": {} vertices ({} in source), {} triangles, {}{}{}",
            m.name,
            m.vertices,
            m.source_vertices,
            m.triangles,
            if m.skinned { "skinned" } else { "static" },
            if m.has_normals { ", normals" } else { "" },
            if m.has_uvs { ", uvs" } else { "" },
        );
        for sm in &m.submeshes {
            let _ = writeln!(
                o,
                "    submesh: {} triangles, material \"{}\"",
                sm.triangles, sm.material
            );
        }
        if let Some(h) = m.influences {
            let _ = writeln!(
                o,
                "    influences per vertex: 0: {}, 1: {}, 2: {}, 3: {}, 4: {}",
                h[0], h[1], h[2], h[3], h[4]
            );
        }
        if let Some(b) = &m.bounds {
            let _ = writeln!(o, "    bounds: ({}) .. ({})", nums(&b.min), nums(&b.max));
        }
        for l in &m.lods {
            let _ = writeln!(
                o,
                "    LOD {}: {} triangles, {} vertices, ratio {} (target {}), error {} ({} model units){}",
                l.level,
                l.triangles,
                l.vertices,
                num(l.reached_ratio),
                num(l.target_ratio),
                num(l.error_relative),
                num(l.error_model),
                if l.stopped_by_error_limit {
                    ", stopped by error limit"
                } else {
                    ""
                }
            );
        }
    }

    if !r.materials.is_empty() {
        let _ = writeln!(o, "materials: {}", r.materials.len());
        for m in &r.materials {
            let tex = m
                .texture
                .as_deref()
                .map_or_else(String::new, |t| format!(", texture \"{t}\""));
            let _ = writeln!(
                o,
                "  \"{}\": base colour ({}){tex}",
                m.name,
                nums(&m.base_color)
            );
        }
    }

    if !r.masks.is_empty() {
        let _ = writeln!(o, "masks: {}", r.masks.len());
        for m in &r.masks {
            let _ = writeln!(o, "  \"{}\": {} joints", m.name, m.weights.len());
        }
    }

    if !r.sections.is_empty() {
        let _ = writeln!(o, "sections (bytes):");
        for s in &r.sections {
            let _ = writeln!(
                o,
                "  {} {:>9} at {}{}",
                s.tag,
                s.size,
                s.offset,
                if s.known { "" } else { " (unknown, skipped)" }
            );
        }
    }

    for im in &r.images {
        let _ = writeln!(o, "image {:?}: {}x{}", im.name, im.width, im.height);
    }
    if let Some(g) = &r.game {
        o.push_str(&super::game::human(g));
    }

    let _ = writeln!(o, "diagnostics: {}", r.diagnostics.len());
    for d in &r.diagnostics {
        let figs = if d.figures.is_empty() {
            String::new()
        } else {
            let f: Vec<String> = d
                .figures
                .iter()
                .map(|f| format!("{}={}", f.name, f.value))
                .collect();
            format!(" ({})", f.join(", "))
        };
        let _ = writeln!(o, "  {} [{}] {}{figs}", d.level, d.code, d.message);
    }
    o
}
