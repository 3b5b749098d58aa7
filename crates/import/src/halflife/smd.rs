//! The SMD text format (GoldSrc and Source flavours) read into plain structures: nodes, skeleton
//! frames and triangles, each error naming the file, the section and the line.

use crate::text::{decode, numbered_lines, truncate, words};
use crate::ImportError;
use sinew_scene::Diagnostic;
use std::collections::{BTreeMap, HashMap};

/// Most nodes an SMD may declare (Source's studiomdl limit is far lower; this bounds memory).
pub const MAX_NODES: usize = 4096;
/// Most frames (`time` blocks, and frame numbers from the first to the last) an SMD may hold.
pub const MAX_FRAMES: usize = 1 << 20;
/// Most bone values (frames x nodes) an SMD may hold: bounds memory on hostile input.
pub const MAX_VALUES: usize = 1 << 22;

/// One node of the `nodes` block.
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    /// The id written in the file.
    pub id: i32,
    /// Name.
    pub name: String,
    /// Parent, as an index into [`Smd::nodes`].
    pub parent: Option<usize>,
}

/// One vertex line of a triangle.
#[derive(Debug, Clone, PartialEq)]
pub struct SmdVertex {
    /// Parent bone (index into [`Smd::nodes`]).
    pub bone: usize,
    /// Model-space position.
    pub position: [f32; 3],
    /// Model-space normal.
    pub normal: [f32; 3],
    /// Texture coordinate as written (v up).
    pub uv: [f32; 2],
    /// Source weight links: (bone index, weight); empty for GoldSrc vertices.
    pub links: Vec<(usize, f32)>,
}

/// One triangle.
#[derive(Debug, Clone, PartialEq)]
pub struct SmdTriangle {
    /// Material (texture file name) as written.
    pub material: String,
    /// The three vertices, in file order.
    pub vertices: [SmdVertex; 3],
}

/// A parsed SMD file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Smd {
    /// Nodes in file order.
    pub nodes: Vec<Node>,
    /// Skeleton frames in time order: `(time, per node: position x y z, rotation x y z)`. A node a
    /// block does not list keeps its value from the previous block (or zeros in the first).
    pub frames: Vec<(i32, Vec<[f32; 6]>)>,
    /// Triangles.
    pub triangles: Vec<SmdTriangle>,
    /// What the reader noticed (ignored sections, filled frames).
    pub diagnostics: Vec<Diagnostic>,
}

/// A `time` block while reading: its line and the values it set.
type FrameBlock = (usize, Vec<Option<[f32; 6]>>);

struct Parser<'a> {
    file: &'a str,
    section: &'static str,
}

impl Parser<'_> {
    fn err(&self, line: usize, msg: impl Into<String>) -> ImportError {
        ImportError::at_line(self.file, self.section, line, msg)
    }
    fn int(&self, line: usize, tok: &str, what: &str) -> Result<i64, ImportError> {
        tok.parse::<i64>()
            .map_err(|_| self.err(line, format!("expected {what}, found {:?}", truncate(tok))))
    }
    fn num(&self, line: usize, tok: &str) -> Result<f32, ImportError> {
        match tok.parse::<f32>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(self.err(line, format!("non-finite number {:?}", truncate(tok)))),
            Err(_) => Err(self.err(
                line,
                format!("expected a number, found {:?}", truncate(tok)),
            )),
        }
    }
}

/// Reads an SMD file.
pub fn parse(file: &str, bytes: &[u8]) -> Result<Smd, ImportError> {
    let text = decode(bytes);
    let mut lines = numbered_lines(&text)
        .map(|(n, l)| (n, words(l)))
        .filter(|(_, w)| !w.is_empty())
        .peekable();
    let mut p = Parser {
        file,
        section: "header",
    };
    let mut smd = Smd::default();
    let Some((n, first)) = lines.next() else {
        return Err(ImportError::in_section(
            file,
            "header",
            "empty file: expected `version 1`",
        ));
    };
    if first.len() < 2 || !first[0].eq_ignore_ascii_case("version") {
        return Err(p.err(
            n,
            format!(
                "expected `version 1`, found {:?}",
                truncate(&first.join(" "))
            ),
        ));
    }
    if p.int(n, first[1], "a version number")? != 1 {
        return Err(p.err(
            n,
            format!("version {} is not supported (SMD version 1 is)", first[1]),
        ));
    }
    let mut id_index: HashMap<i32, usize> = HashMap::new();
    let mut frames: BTreeMap<i32, FrameBlock> = BTreeMap::new();
    let mut saw_nodes = false;
    while let Some((n, w)) = lines.next() {
        let keyword = w[0].to_ascii_lowercase();
        match keyword.as_str() {
            "nodes" => {
                p.section = "nodes";
                if saw_nodes {
                    return Err(p.err(n, "a second `nodes` block"));
                }
                saw_nodes = true;
                let mut parents: Vec<(usize, i32)> = Vec::new();
                loop {
                    let Some((n, w)) = lines.next() else {
                        return Err(p.err(n, "file ends inside `nodes` (no `end`)"));
                    };
                    if w[0].eq_ignore_ascii_case("end") {
                        break;
                    }
                    if w.len() < 3 {
                        return Err(p.err(n, "a node needs `id \"name\" parent`"));
                    }
                    let id = p.int(n, w[0], "a node id")?;
                    let parent = p.int(n, w[w.len() - 1], "a parent id")?;
                    let (Ok(id), Ok(parent)) = (i32::try_from(id), i32::try_from(parent)) else {
                        return Err(p.err(n, "node id out of range"));
                    };
                    if id < 0 {
                        return Err(p.err(n, format!("negative node id {id}")));
                    }
                    if smd.nodes.len() >= MAX_NODES {
                        return Err(p.err(n, format!("more than {MAX_NODES} nodes")));
                    }
                    if id_index.insert(id, smd.nodes.len()).is_some() {
                        return Err(p.err(n, format!("node id {id} appears twice")));
                    }
                    // A name may be written without quotes and with spaces: everything between
                    // the id and the parent.
                    let name = w[1..w.len() - 1].join(" ");
                    parents.push((n, parent));
                    smd.nodes.push(Node {
                        id,
                        name,
                        parent: None,
                    });
                }
                for (k, (line, parent)) in parents.into_iter().enumerate() {
                    if parent < 0 {
                        continue;
                    }
                    let Some(&pi) = id_index.get(&parent) else {
                        return Err(p.err(line, format!("parent id {parent} is not a node")));
                    };
                    if pi == k {
                        return Err(p.err(line, "a node is its own parent"));
                    }
                    smd.nodes[k].parent = Some(pi);
                }
                // Parent cycles: walk up from every node at most `len` steps.
                for k in 0..smd.nodes.len() {
                    let mut at = smd.nodes[k].parent;
                    let mut steps = 0;
                    while let Some(q) = at {
                        steps += 1;
                        if steps > smd.nodes.len() {
                            return Err(p.err(
                                n,
                                format!(
                                    "node {:?} is its own ancestor (a parent cycle)",
                                    smd.nodes[k].name
                                ),
                            ));
                        }
                        at = smd.nodes[q].parent;
                    }
                }
            }
            "skeleton" => {
                p.section = "skeleton";
                let mut current: Option<i32> = None;
                loop {
                    let Some((n, w)) = lines.next() else {
                        return Err(p.err(n, "file ends inside `skeleton` (no `end`)"));
                    };
                    if w[0].eq_ignore_ascii_case("end") {
                        break;
                    }
                    if w[0].eq_ignore_ascii_case("time") {
                        let t = p.int(n, w.get(1).copied().unwrap_or(""), "a frame time")?;
                        let t =
                            i32::try_from(t).map_err(|_| p.err(n, "frame time out of range"))?;
                        if !frames.contains_key(&t)
                            && (frames.len() >= MAX_FRAMES
                                || (frames.len() + 1).saturating_mul(smd.nodes.len().max(1))
                                    > MAX_VALUES)
                        {
                            return Err(p.err(
                                n,
                                format!("more frames than sinew reads ({MAX_FRAMES} frames, {MAX_VALUES} bone values)"),
                            ));
                        }
                        frames
                            .entry(t)
                            .or_insert_with(|| (n, vec![None; smd.nodes.len()]));
                        current = Some(t);
                        continue;
                    }
                    let Some(t) = current else {
                        return Err(p.err(n, "a bone line before the first `time`"));
                    };
                    if w.len() < 7 {
                        return Err(p.err(n, "a bone line needs `id px py pz rx ry rz`"));
                    }
                    let id = p.int(n, w[0], "a node id")?;
                    let Some(&k) = i32::try_from(id).ok().and_then(|id| id_index.get(&id)) else {
                        return Err(p.err(n, format!("node id {id} is not declared in `nodes`")));
                    };
                    let mut v = [0f32; 6];
                    for (slot, tok) in v.iter_mut().zip(&w[1..7]) {
                        *slot = p.num(n, tok)?;
                    }
                    if let Some((_, values)) = frames.get_mut(&t) {
                        values[k] = Some(v);
                    }
                }
            }
            "triangles" => {
                p.section = "triangles";
                loop {
                    let Some((n, w)) = lines.next() else {
                        return Err(p.err(n, "file ends inside `triangles` (no `end`)"));
                    };
                    if w.len() == 1 && w[0].eq_ignore_ascii_case("end") {
                        break;
                    }
                    let material = w.join(" ");
                    let mut corners = Vec::with_capacity(3);
                    for _ in 0..3 {
                        let Some((n, w)) = lines.next() else {
                            return Err(p.err(n, "file ends inside a triangle"));
                        };
                        corners.push(vertex(&p, n, &w, &id_index)?);
                    }
                    let [a, b, c]: [SmdVertex; 3] = corners
                        .try_into()
                        .map_err(|_| p.err(n, "a triangle needs three vertices"))?;
                    smd.triangles.push(SmdTriangle {
                        material,
                        vertices: [a, b, c],
                    });
                }
            }
            "vertexanimation" => {
                p.section = "vertexanimation";
                smd.diagnostics.push(Diagnostic::info(
                    "smd-vertexanimation-ignored",
                    format!("line {n}: the `vertexanimation` block (flex shapes) is not read"),
                ));
                loop {
                    let Some((_, w)) = lines.next() else {
                        return Err(p.err(n, "file ends inside `vertexanimation` (no `end`)"));
                    };
                    if w.len() == 1 && w[0].eq_ignore_ascii_case("end") {
                        break;
                    }
                }
            }
            other => {
                p.section = "file";
                return Err(p.err(
                    n,
                    format!(
                        "unknown block {:?} (expected nodes, skeleton, triangles or end)",
                        truncate(other)
                    ),
                ));
            }
        }
    }
    if let (Some((&t0, _)), Some((&t1, (line, _)))) =
        (frames.first_key_value(), frames.last_key_value())
    {
        let span = (i64::from(t1) - i64::from(t0) + 1) as u64;
        if span > MAX_FRAMES as u64
            || span.saturating_mul(smd.nodes.len().max(1) as u64) > MAX_VALUES as u64
        {
            p.section = "skeleton";
            return Err(p.err(
                *line,
                format!(
                    "frame numbers {t0} to {t1} span more frames than sinew reads ({MAX_FRAMES})"
                ),
            ));
        }
    }
    // Frames in time order; a node missing from a block keeps its previous value.
    let mut previous: Vec<[f32; 6]> = vec![[0.0; 6]; smd.nodes.len()];
    let mut filled = 0usize;
    for (t, (_, values)) in frames {
        for (k, v) in values.into_iter().enumerate() {
            match v {
                Some(v) => previous[k] = v,
                None => filled += 1,
            }
        }
        smd.frames.push((t, previous.clone()));
    }
    if filled > 0 {
        smd.diagnostics.push(Diagnostic::warning(
            "smd-missing-bone-values",
            format!(
                "{filled} bone values missing from `time` blocks took the previous frame's value"
            ),
        ));
    }
    Ok(smd)
}

/// One vertex line: `bone px py pz nx ny nz u v` then, in Source files, `links (bone weight)*`.
fn vertex(
    p: &Parser,
    n: usize,
    w: &[&str],
    id_index: &HashMap<i32, usize>,
) -> Result<SmdVertex, ImportError> {
    if w.len() < 9 {
        return Err(p.err(
            n,
            format!(
                "a vertex line needs 9 numbers (bone, position, normal, uv), found {}",
                w.len()
            ),
        ));
    }
    let bone_of = |tok: &str| -> Result<usize, ImportError> {
        let id = p.int(n, tok, "a bone id")?;
        i32::try_from(id)
            .ok()
            .and_then(|id| id_index.get(&id).copied())
            .ok_or_else(|| p.err(n, format!("bone id {id} is not declared in `nodes`")))
    };
    let bone = bone_of(w[0])?;
    let mut f = [0f32; 8];
    for (slot, tok) in f.iter_mut().zip(&w[1..9]) {
        *slot = p.num(n, tok)?;
    }
    let mut links = Vec::new();
    if w.len() > 9 {
        let count = p.int(n, w[9], "a link count")?;
        let count =
            usize::try_from(count).map_err(|_| p.err(n, format!("negative link count {count}")))?;
        if w.len() != 10 + 2 * count.min(w.len()) {
            return Err(p.err(
                n,
                format!(
                    "{count} weight links need {} tokens after the uv, found {}",
                    1 + 2 * count,
                    w.len() - 9
                ),
            ));
        }
        for k in 0..count {
            let b = bone_of(w[10 + 2 * k])?;
            let weight = p.num(n, w[11 + 2 * k])?;
            links.push((b, weight));
        }
    }
    Ok(SmdVertex {
        bone,
        position: [f[0], f[1], f[2]],
        normal: [f[3], f[4], f[5]],
        uv: [f[6], f[7]],
        links,
    })
}
