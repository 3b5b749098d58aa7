//! glTF 2.0 importer (`.gltf` with external or data-URI buffers, and `.glb`).
//!
//! The JSON is parsed and validated by the gltf crate's document model ([`gltf::Gltf::from_slice`]);
//! the GLB container, buffers and accessors are read by this module with every byte range checked
//! (see [`accessor`]). One skin becomes the scene skeleton ([`ImportOptions::gltf_skin`]); animations
//! become linear-key clips ([`anim`]). docs/formats/gltf.md describes every decision.

pub mod accessor;
pub mod anim;

use crate::{ImportError, ImportOptions, Resolver};
use accessor::{read_f32, read_u32};
use anim::Interp;
use glam::{Mat3, Mat4, Quat, Vec2, Vec3};
use sinew_core::{Curve, JointDesc, Lod, Skeleton, Submesh, TrackCurves, Transform};
use sinew_scene::{Diagnostic, Material, Mesh, Scene, SceneClip, SourceFormat};
use std::collections::{BTreeMap, HashMap, HashSet};

/// A parsed document with its buffers loaded and checked.
struct Loaded {
    doc: gltf::Document,
    buffers: Vec<Vec<u8>>,
}

/// Splits a GLB container into its JSON chunk and optional BIN chunk, checking every length.
fn split_glb<'a>(file: &str, bytes: &'a [u8]) -> Result<(&'a [u8], Option<&'a [u8]>), ImportError> {
    let u32_at = |o: usize| -> Option<u32> {
        let b = bytes.get(o..o.checked_add(4)?)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let err = |o: usize, m: String| ImportError::at_offset(file, "glb", o as u64, m);
    let version =
        u32_at(4).ok_or_else(|| err(4, "file ends inside the 12-byte GLB header".into()))?;
    if version != 2 {
        return Err(err(
            4,
            format!("GLB version {version}; only version 2 is supported"),
        ));
    }
    let length =
        u32_at(8).ok_or_else(|| err(8, "file ends inside the GLB header".into()))? as usize;
    if length > bytes.len() {
        return Err(err(
            8,
            format!(
                "header says the file is {length} bytes; only {} are present",
                bytes.len()
            ),
        ));
    }
    let bytes = &bytes[..length];
    let mut chunks = Vec::new();
    let mut o = 12usize;
    while o < bytes.len() {
        let len =
            u32_at(o).ok_or_else(|| err(o, "file ends inside a chunk header".into()))? as usize;
        let ty = u32_at(o + 4).ok_or_else(|| err(o, "file ends inside a chunk header".into()))?;
        let start = o + 8;
        let end = start
            .checked_add(len)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                err(
                    o,
                    format!(
                        "chunk of {len} bytes runs past the end of the file ({} bytes)",
                        bytes.len()
                    ),
                )
            })?;
        chunks.push((o, ty, &bytes[start..end]));
        o = end;
    }
    let mut it = chunks.into_iter();
    let (_, ty, json) = it
        .next()
        .ok_or_else(|| err(12, "GLB has no chunks; the first must be JSON".into()))?;
    if ty != 0x4E4F_534A {
        return Err(err(
            12,
            format!("first chunk has type 0x{ty:08x}; expected JSON"),
        ));
    }
    let mut bin = None;
    for (off, ty, data) in it {
        if ty == 0x004E_4942 {
            if bin.is_some() {
                return Err(err(off, "a second BIN chunk".into()));
            }
            bin = Some(data);
        }
    }
    Ok((json, bin))
}

/// The JSON path (`meshes[0].primitives`) of the value that contains byte `offset` of `text`.
pub fn json_path_at(text: &[u8], offset: usize) -> String {
    enum Frame {
        Obj(Option<String>, bool),
        Arr(usize),
    }
    let mut stack: Vec<Frame> = Vec::new();
    let mut i = 0;
    let end = offset.min(text.len());
    while i < end {
        let c = text[i];
        match c {
            b'"' => {
                let start = i + 1;
                i += 1;
                while i < text.len() && text[i] != b'"' {
                    if text[i] == b'\\' {
                        i += 1;
                    }
                    i += 1;
                }
                if let Some(Frame::Obj(key, expecting)) = stack.last_mut() {
                    if *expecting {
                        let s = text.get(start..i.min(text.len())).unwrap_or(&[]);
                        *key = Some(String::from_utf8_lossy(s).into_owned());
                        *expecting = false;
                    }
                }
            }
            b'{' => stack.push(Frame::Obj(None, true)),
            b'[' => stack.push(Frame::Arr(0)),
            b'}' | b']' => {
                stack.pop();
            }
            b',' => match stack.last_mut() {
                Some(Frame::Arr(n)) => *n += 1,
                Some(Frame::Obj(_, expecting)) => *expecting = true,
                None => {}
            },
            _ => {}
        }
        i += 1;
    }
    let mut path = String::new();
    for f in &stack {
        match f {
            Frame::Obj(Some(k), _) => {
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(k);
            }
            Frame::Obj(None, _) => {}
            Frame::Arr(n) => path.push_str(&format!("[{n}]")),
        }
    }
    if path.is_empty() {
        "(root)".into()
    } else {
        path
    }
}

fn section_of(path: &str) -> &str {
    let end = path.find(['[', '.']).unwrap_or(path.len());
    &path[..end]
}

/// An error at a JSON path; the section is the path's top-level property.
fn at(file: &str, path: impl Into<String>, message: impl Into<String>) -> ImportError {
    let path = path.into();
    let section = section_of(&path).to_string();
    ImportError::at_path(file, &section, path, message)
}

/// Byte offset of a 1-based line and column.
fn offset_of(text: &[u8], line: usize, column: usize) -> usize {
    let mut l = 1;
    let mut i = 0;
    while i < text.len() && l < line {
        if text[i] == b'\n' {
            l += 1;
        }
        i += 1;
    }
    (i + column.saturating_sub(1)).min(text.len())
}

fn parse_document(file: &str, json: &[u8]) -> Result<gltf::Gltf, ImportError> {
    if json.starts_with(b"glTF") {
        return Err(ImportError::in_section(file, "json", "nested GLB header"));
    }
    let parsed = std::panic::catch_unwind(|| gltf::Gltf::from_slice(json)).map_err(|_| {
        ImportError::in_section(file, "json", "the gltf crate panicked while validating")
    })?;
    parsed.map_err(|e| match e {
        gltf::Error::Deserialize(de) => {
            let off = offset_of(json, de.line(), de.column());
            let mut path = json_path_at(json, off);
            // serde notices a missing field at the end of its object, after the last key it read.
            if de.to_string().starts_with("missing field") {
                if let Some(dot) = path.rfind('.') {
                    if !path[dot..].contains('[') {
                        path.truncate(dot);
                    }
                }
            }
            at(file, path, format!("{de}"))
        }
        gltf::Error::Validation(errors) => {
            let (path, kind) = match errors.first() {
                Some((p, k)) => (p.to_string(), format!("{k}")),
                None => ("(root)".into(), "invalid".into()),
            };
            let more = if errors.len() > 1 {
                format!(" ({} more validation errors)", errors.len() - 1)
            } else {
                String::new()
            };
            at(file, path, format!("{kind}{more}"))
        }
        other => ImportError::in_section(file, "json", other.to_string()),
    })
}

/// Decodes standard or URL-safe base64, ignoring whitespace and padding.
fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(s.len() / 4 * 3 + 3);
    let mut acc = 0u32;
    let mut bits = 0;
    for c in s.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' | b' ' | b'\n' | b'\r' | b'\t' => continue,
            _ => return None,
        } as u32;
        acc = (acc << 6) | v;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

/// Decodes `%xx` escapes of a relative URI.
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    let hex = |c: u8| (c as char).to_digit(16);
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn load(file: &str, bytes: &[u8], resolve: Resolver<'_>) -> Result<Loaded, ImportError> {
    let (json, bin) = if bytes.starts_with(b"glTF") {
        split_glb(file, bytes)?
    } else {
        (bytes, None)
    };
    let gltf = parse_document(file, json)?;
    let doc = gltf.document;
    let mut buffers = Vec::new();
    for b in doc.buffers() {
        let path = format!("buffers[{}]", b.index());
        let data: Vec<u8> = match b.source() {
            gltf::buffer::Source::Bin => {
                if b.index() != 0 {
                    return Err(at(
                        file,
                        path,
                        "only buffer 0 may refer to the GLB BIN chunk",
                    ));
                }
                bin.ok_or_else(|| at(file, &path, "refers to the GLB BIN chunk, which is absent"))?
                    .to_vec()
            }
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, payload) = rest
                        .split_once(";base64,")
                        .ok_or_else(|| at(file, &path, "data URI is not base64"))?;
                    base64_decode(payload)
                        .ok_or_else(|| at(file, &path, "data URI holds invalid base64"))?
                } else {
                    resolve(&percent_decode(uri)).map_err(|e| {
                        at(
                            file,
                            &path,
                            format!("cannot load external buffer {uri:?}: {e}"),
                        )
                    })?
                }
            }
        };
        if data.len() < b.length() {
            let what = match b.source() {
                gltf::buffer::Source::Bin => "the GLB BIN chunk",
                gltf::buffer::Source::Uri(_) => "its data",
            };
            return Err(at(
                file,
                path,
                format!(
                    "byteLength is {} but {what} holds only {} bytes",
                    b.length(),
                    data.len()
                ),
            ));
        }
        let mut data = data;
        data.truncate(b.length());
        buffers.push(data);
    }
    Ok(Loaded { doc, buffers })
}

/// Number of skins in a glTF file, so that a caller can import each one with
/// [`ImportOptions::gltf_skin`].
pub fn skin_count(file_name: &str, bytes: &[u8]) -> Result<usize, ImportError> {
    let json = if bytes.starts_with(b"glTF") {
        split_glb(file_name, bytes)?.0
    } else {
        bytes
    };
    Ok(parse_document(file_name, json)?.document.skins().count())
}

/// Reads an accessor as floats with exactly `comps` components per element.
fn floats(
    file: &str,
    l: &Loaded,
    acc: &gltf::Accessor<'_>,
    comps: usize,
    path: &str,
) -> Result<Vec<f32>, ImportError> {
    let a = format!("accessors[{}]", acc.index());
    if accessor::component_count(acc.dimensions()) != comps {
        return Err(at(
            file,
            path,
            format!(
                "{a} has type {:?}; {comps} components expected",
                acc.dimensions()
            ),
        ));
    }
    let v = read_f32(acc, &l.buffers).map_err(|m| at(file, &a, format!("{m} (used by {path})")))?;
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(at(
            file,
            &a,
            format!(
                "element {} holds a non-finite value ({}) (used by {path})",
                i / comps,
                v[i]
            ),
        ));
    }
    Ok(v)
}

fn uints(
    file: &str,
    l: &Loaded,
    acc: &gltf::Accessor<'_>,
    comps: usize,
    path: &str,
) -> Result<Vec<u32>, ImportError> {
    let a = format!("accessors[{}]", acc.index());
    if accessor::component_count(acc.dimensions()) != comps {
        return Err(at(
            file,
            path,
            format!(
                "{a} has type {:?}; {comps} components expected",
                acc.dimensions()
            ),
        ));
    }
    read_u32(acc, &l.buffers).map_err(|m| at(file, &a, format!("{m} (used by {path})")))
}

/// The node transform as TRS, with the residual when a matrix is not a clean TRS.
fn node_trs(node: &gltf::Node<'_>) -> (Transform, Option<(f32, bool)>) {
    match node.transform() {
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => (
            Transform::new(
                Vec3::from(translation),
                Quat::from_array(rotation),
                Vec3::from(scale),
            ),
            None,
        ),
        gltf::scene::Transform::Matrix { matrix } => {
            let m = Mat4::from_cols_array_2d(&matrix);
            let (t, residual, negative) = decompose(m);
            let bad = negative || residual > 1e-5;
            (t, bad.then_some((residual, negative)))
        }
    }
}

/// Decomposes an affine matrix into TRS: (transform, largest residual relative to the matrix size,
/// negative determinant).
fn decompose(m: Mat4) -> (Transform, f32, bool) {
    let negative = m.determinant() < 0.0;
    let (s, r, t) = m.to_scale_rotation_translation();
    let r = if r.is_finite() {
        r.normalize()
    } else {
        Quat::IDENTITY
    };
    let tr = Transform::new(t, r, s);
    let back = tr.to_mat4();
    let size = m.to_cols_array().iter().fold(1.0f32, |a, v| a.max(v.abs()));
    let residual = m
        .to_cols_array()
        .iter()
        .zip(back.to_cols_array())
        .fold(0.0f32, |a, (x, y)| a.max((x - y).abs()))
        / size;
    let residual = if residual.is_finite() {
        residual
    } else {
        f32::INFINITY
    };
    (tr, residual, negative)
}

/// Node graph facts: parent of each node, checked to be a forest.
fn parents(file: &str, doc: &gltf::Document) -> Result<Vec<Option<usize>>, ImportError> {
    let n = doc.nodes().count();
    let mut parent: Vec<Option<usize>> = vec![None; n];
    for node in doc.nodes() {
        for (k, c) in node.children().enumerate() {
            let ci = c.index();
            if ci == node.index() {
                return Err(at(
                    file,
                    format!("nodes[{}].children[{k}]", node.index()),
                    "node lists itself as its child",
                ));
            }
            if let Some(p) = parent[ci] {
                return Err(at(
                    file,
                    format!("nodes[{}].children[{k}]", node.index()),
                    format!("node {ci} already has parent {p}; glTF nodes form a forest"),
                ));
            }
            parent[ci] = Some(node.index());
        }
    }
    // With one parent per node, a cycle is a walk up that never ends.
    for start in 0..n {
        let mut cur = start;
        let mut steps = 0;
        while let Some(p) = parent[cur] {
            cur = p;
            steps += 1;
            if steps > n {
                let k = doc
                    .nodes()
                    .nth(p)
                    .and_then(|node| node.children().position(|c| parent[c.index()] == Some(p)))
                    .unwrap_or(0);
                return Err(at(
                    file,
                    format!("nodes[{p}].children[{k}]"),
                    format!("the node hierarchy has a cycle through node {start}"),
                ));
            }
        }
    }
    Ok(parent)
}

/// Unique names for all nodes: the glTF name, `node<N>` when unnamed, `name#N` when repeated.
fn node_names(doc: &gltf::Document) -> Vec<String> {
    let mut count: HashMap<String, usize> = HashMap::new();
    let base: Vec<String> = doc
        .nodes()
        .map(|n| match n.name() {
            Some(s) if !s.is_empty() => s.to_string(),
            _ => format!("node{}", n.index()),
        })
        .collect();
    for b in &base {
        *count.entry(b.clone()).or_default() += 1;
    }
    let mut used: HashSet<String> = HashSet::new();
    base.iter()
        .enumerate()
        .map(|(i, b)| {
            let mut name = if count[b] > 1 {
                format!("{b}#{i}")
            } else {
                b.clone()
            };
            while !used.insert(name.clone()) {
                name.push('_');
            }
            name
        })
        .collect()
}

struct Graph {
    parent: Vec<Option<usize>>,
    local: Vec<Transform>,
    world: Vec<Mat4>,
    names: Vec<String>,
}

fn graph(
    file: &str,
    doc: &gltf::Document,
    diags: &mut Vec<Diagnostic>,
) -> Result<Graph, ImportError> {
    let parent = parents(file, doc)?;
    let mut local = Vec::new();
    for node in doc.nodes() {
        let (t, bad) = node_trs(&node);
        if !t.is_finite() {
            return Err(at(
                file,
                format!("nodes[{}]", node.index()),
                "transform is not finite",
            ));
        }
        if let Some((residual, negative)) = bad {
            let what = if negative {
                "has a negative determinant (a mirror)"
            } else {
                "is not a clean translation-rotation-scale (shear)"
            };
            diags.push(
                Diagnostic::warning(
                    "gltf-matrix-not-trs",
                    format!(
                        "nodes[{}].matrix {what}; decomposed into TRS with a relative residual of {residual:.3e}",
                        node.index()
                    ),
                )
                .with_figure("node", node.index() as f64)
                .with_figure("residual", residual as f64),
            );
        }
        local.push(t);
    }
    let n = local.len();
    let mut world: Vec<Option<Mat4>> = vec![None; n];
    for i in 0..n {
        let mut chain = vec![i];
        while let Some(p) = parent[*chain.last().unwrap_or(&i)] {
            if world[p].is_some() {
                break;
            }
            chain.push(p);
        }
        for &c in chain.iter().rev() {
            if world[c].is_none() {
                let m = local[c].to_mat4();
                world[c] = Some(match parent[c].and_then(|p| world[p]) {
                    Some(pm) => pm * m,
                    None => m,
                });
            }
        }
    }
    Ok(Graph {
        parent,
        local,
        world: world
            .into_iter()
            .map(|m| m.unwrap_or(Mat4::IDENTITY))
            .collect(),
        names: node_names(doc),
    })
}

/// The chosen skeleton: which node is which joint, and the fixed transform baked in front of each
/// joint's own local transform (the non-joint nodes between it and its parent joint).
struct Rig {
    skeleton: Skeleton,
    /// Skeleton joint index of each node that is a joint.
    joint_of_node: HashMap<usize, u16>,
    /// Skeleton index of each entry of `skin.joints` (empty for a node skeleton).
    skin_map: Vec<u16>,
    /// Matrix applied before the node's own TRS, per joint node, when not the identity.
    pre: HashMap<usize, Mat4>,
    /// The chosen skin's index.
    skin: Option<usize>,
}

fn is_identity(m: &Mat4) -> bool {
    m.abs_diff_eq(Mat4::IDENTITY, 1e-7)
}

fn build_rig(
    file: &str,
    l: &Loaded,
    g: &Graph,
    joints: &[usize],
    skin: Option<gltf::Skin<'_>>,
) -> Result<Rig, ImportError> {
    let skin_path = skin.as_ref().map(|s| format!("skins[{}]", s.index()));
    let ibm: Option<Vec<f32>> = match skin.as_ref().and_then(|s| s.inverse_bind_matrices()) {
        Some(acc) => {
            let p = format!(
                "{}.inverseBindMatrices",
                skin_path.clone().unwrap_or_default()
            );
            let v = floats(file, l, &acc, 16, &p)?;
            if v.len() < joints.len() * 16 {
                return Err(at(
                    file,
                    p,
                    format!("{} matrices for {} joints", v.len() / 16, joints.len()),
                ));
            }
            Some(v)
        }
        None => None,
    };
    let mut seen = HashSet::new();
    for (k, &j) in joints.iter().enumerate() {
        if !seen.insert(j) {
            return Err(at(
                file,
                format!("{}.joints[{k}]", skin_path.clone().unwrap_or_default()),
                format!("node {j} is listed twice"),
            ));
        }
    }
    let mut descs = Vec::with_capacity(joints.len());
    let mut pre = HashMap::new();
    for (k, &j) in joints.iter().enumerate() {
        // Walk up to the nearest joint ancestor, multiplying the non-joint nodes passed on the way.
        let mut m = Mat4::IDENTITY;
        let mut parent_joint = None;
        let mut cur = g.parent[j];
        while let Some(p) = cur {
            if seen.contains(&p) {
                parent_joint = Some(p);
                break;
            }
            m = g.local[p].to_mat4() * m;
            cur = g.parent[p];
        }
        let bind_local = if is_identity(&m) {
            g.local[j]
        } else {
            pre.insert(j, m);
            decompose(m * g.local[j].to_mat4()).0
        };
        let inverse_bind = match &ibm {
            Some(v) => {
                let mut a = [0.0f32; 16];
                a.copy_from_slice(&v[k * 16..k * 16 + 16]);
                Mat4::from_cols_array(&a)
            }
            None if skin.is_some() => Mat4::IDENTITY,
            None => g.world[j].inverse(),
        };
        descs.push(JointDesc {
            name: g.names[j].clone(),
            parent: parent_joint.map(|p| g.names[p].clone()),
            bind_local,
            inverse_bind: Some(inverse_bind),
        });
    }
    let (skeleton, map) = Skeleton::from_unordered(descs).map_err(|e| {
        at(
            file,
            skin_path.clone().unwrap_or_else(|| "nodes".into()),
            format!("cannot build the skeleton: {e}"),
        )
    })?;
    let joint_of_node = joints.iter().zip(&map).map(|(&n, &i)| (n, i)).collect();
    Ok(Rig {
        skeleton,
        joint_of_node,
        skin_map: if skin.is_some() { map } else { Vec::new() },
        pre,
        skin: skin.map(|s| s.index()),
    })
}

/// Imports a glTF 2.0 file (`.gltf` or `.glb`). See docs/formats/gltf.md.
pub fn import(
    file_name: &str,
    bytes: &[u8],
    resolve: Resolver<'_>,
    options: &ImportOptions,
) -> Result<Scene, ImportError> {
    // The gltf crate's typed accessors unwrap values its validation does not always cover; a panic
    // there becomes an ordinary error instead of aborting a batch run.
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        import_inner(file_name, bytes, resolve, options)
    }))
    .unwrap_or_else(|_| {
        Err(ImportError::in_section(
            file_name,
            "json",
            "the document holds a value the gltf crate could not interpret",
        ))
    })
}

fn import_inner(
    file_name: &str,
    bytes: &[u8],
    resolve: Resolver<'_>,
    options: &ImportOptions,
) -> Result<Scene, ImportError> {
    let file = file_name;
    let l = load(file, bytes, resolve)?;
    let doc = &l.doc;
    let mut scene = Scene::new(SourceFormat::Gltf);
    let g = graph(file, doc, &mut scene.diagnostics)?;

    // The skeleton: the chosen skin, or the whole node forest when there is no skin but animations.
    let skins: Vec<gltf::Skin<'_>> = doc.skins().collect();
    let rig = if skins.is_empty() {
        if doc.animations().next().is_some() && !g.local.is_empty() {
            let all: Vec<usize> = (0..g.local.len()).collect();
            scene.diagnostics.push(Diagnostic::info(
                "gltf-node-skeleton",
                "the file has animations but no skin: every node becomes a joint",
            ));
            Some(build_rig(file, &l, &g, &all, None)?)
        } else {
            None
        }
    } else {
        let chosen = options.gltf_skin.unwrap_or(0);
        let skin = skins.get(chosen).cloned().ok_or_else(|| {
            at(
                file,
                "skins",
                format!("skin {chosen} was requested; the file has {}", skins.len()),
            )
        })?;
        if skins.len() > 1 && options.gltf_skin.is_none() {
            let others: Vec<String> = skins
                .iter()
                .skip(1)
                .map(|s| match s.name() {
                    Some(n) => format!("{} {n:?}", s.index()),
                    None => s.index().to_string(),
                })
                .collect();
            scene.diagnostics.push(
                Diagnostic::warning(
                    "gltf-several-skins",
                    format!(
                        "the file has {} skins; imported skin 0, not skins {} (choose with the gltf_skin option)",
                        skins.len(),
                        others.join(", ")
                    ),
                )
                .with_figure("skins", skins.len() as f64),
            );
        }
        let joints: Vec<usize> = skin.joints().map(|n| n.index()).collect();
        if joints.is_empty() {
            return Err(at(
                file,
                format!("skins[{chosen}].joints"),
                "the skin has no joints",
            ));
        }
        Some(build_rig(file, &l, &g, &joints, Some(skin))?)
    };

    scene.materials = materials(doc);
    import_meshes(file, &l, &g, rig.as_ref(), &mut scene)?;
    if let Some(rig) = &rig {
        import_animations(file, &l, &g, rig, &mut scene)?;
    } else if doc.animations().next().is_some() {
        scene.diagnostics.push(Diagnostic::warning(
            "gltf-animations-skipped",
            "animations need a skeleton; the file has none",
        ));
    }
    scene.skeleton = rig.map(|r| r.skeleton);
    Ok(scene)
}

fn material_names(doc: &gltf::Document) -> Vec<String> {
    let mut used = HashSet::new();
    doc.materials()
        .map(|m| {
            let i = m.index().unwrap_or(0);
            let mut n = match m.name() {
                Some(s) if !s.is_empty() => s.to_string(),
                _ => format!("material{i}"),
            };
            if !used.insert(n.clone()) {
                n = format!("{n}#{i}");
                used.insert(n.clone());
            }
            n
        })
        .collect()
}

fn materials(doc: &gltf::Document) -> Vec<Material> {
    let names = material_names(doc);
    doc.materials()
        .zip(names)
        .map(|(m, name)| {
            let pbr = m.pbr_metallic_roughness();
            let texture = pbr.base_color_texture().map(|info| {
                let img = info.texture().source();
                match img.source() {
                    gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => {
                        uri.to_string()
                    }
                    _ => format!("images[{}]", img.index()),
                }
            });
            Material {
                name,
                base_color: pbr.base_color_factor(),
                texture,
            }
        })
        .collect()
}

/// The meshes to import: (node index or None, mesh) in scene order.
fn mesh_instances<'a>(doc: &'a gltf::Document, g: &Graph) -> Vec<(Option<usize>, gltf::Mesh<'a>)> {
    let roots: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(s) => s.nodes().map(|n| n.index()).collect(),
        None => (0..g.parent.len())
            .filter(|&i| g.parent[i].is_none())
            .collect(),
    };
    let nodes: Vec<gltf::Node<'a>> = doc.nodes().collect();
    if nodes.is_empty() {
        return doc.meshes().map(|m| (None, m)).collect();
    }
    let mut out = Vec::new();
    let mut stack: Vec<usize> = roots.into_iter().rev().collect();
    while let Some(i) = stack.pop() {
        let Some(node) = nodes.get(i) else { continue };
        if let Some(m) = node.mesh() {
            out.push((Some(i), m));
        }
        let kids: Vec<usize> = node.children().map(|c| c.index()).collect();
        stack.extend(kids.into_iter().rev());
    }
    out
}

/// Area-weighted vertex normals of a triangle list; returns the normals and how many had no area.
pub fn generate_normals(positions: &[Vec3], indices: &[u32]) -> (Vec<Vec3>, usize) {
    let mut n = vec![Vec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let (a, b, c) = (t[0] as usize, t[1] as usize, t[2] as usize);
        if a >= n.len() || b >= n.len() || c >= n.len() {
            continue;
        }
        let f = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        n[a] += f;
        n[b] += f;
        n[c] += f;
    }
    let mut zero = 0;
    for v in &mut n {
        match v.try_normalize() {
            Some(u) => *v = u,
            None => {
                *v = Vec3::Z;
                zero += 1;
            }
        }
    }
    (n, zero)
}

/// Joint indices and weights of a primitive's vertices.
type Influences = (Vec<[u16; 4]>, Vec<[f32; 4]>);

/// Statistics of the influence reduction.
#[derive(Default)]
struct WeightStats {
    vertices_lost: usize,
    max_lost: f32,
    sum_lost: f64,
    zero_weight: usize,
    unnormalised: usize,
}

#[allow(clippy::too_many_lines)]
fn import_meshes(
    file: &str,
    l: &Loaded,
    g: &Graph,
    rig: Option<&Rig>,
    scene: &mut Scene,
) -> Result<(), ImportError> {
    let mat_names = material_names(&l.doc);
    let mut used_names = HashSet::new();
    let mut generated_normals = 0usize;
    let mut stats = WeightStats::default();
    for (node, mesh) in mesh_instances(&l.doc, g) {
        let mi = mesh.index();
        let node_skin = node
            .and_then(|n| l.doc.nodes().nth(n))
            .and_then(|n| n.skin())
            .map(|s| s.index());
        let skinned = match (node_skin, rig.and_then(|r| r.skin)) {
            (Some(s), Some(c)) if s == c => true,
            (Some(s), _) => {
                scene.diagnostics.push(
                    Diagnostic::warning(
                        "gltf-other-skin-mesh",
                        format!(
                            "meshes[{mi}] on nodes[{}] uses skins[{s}], which was not imported; mesh skipped",
                            node.unwrap_or(0)
                        ),
                    )
                    .with_figure("mesh", mi as f64),
                );
                continue;
            }
            _ => false,
        };
        // Static meshes go to model space; skinned vertices are already in bind space (glTF ignores the
        // skinned mesh node's transform).
        let xf = match node {
            Some(n) if !skinned => g.world[n],
            _ => Mat4::IDENTITY,
        };
        let nxf = Mat3::from_mat4(xf).inverse().transpose();
        let mut lod = Lod::default();
        let mut any_uv = false;
        let mut uv_missing = 0;
        for prim in mesh.primitives() {
            let pp = format!("meshes[{mi}].primitives[{}]", prim.index());
            let mode = prim.mode();
            use gltf::mesh::Mode;
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                scene.diagnostics.push(Diagnostic::warning(
                    "gltf-primitive-skipped",
                    format!("{pp} has mode {mode:?}; only triangles are imported"),
                ));
                continue;
            }
            let Some(pos_acc) = prim.get(&gltf::Semantic::Positions) else {
                scene.diagnostics.push(Diagnostic::warning(
                    "gltf-primitive-skipped",
                    format!("{pp} has no POSITION attribute; skipped"),
                ));
                continue;
            };
            let pos = floats(file, l, &pos_acc, 3, &format!("{pp}.attributes.POSITION"))?;
            let n = pos.len() / 3;
            let check_count = |acc: &gltf::Accessor<'_>, name: &str| -> Result<(), ImportError> {
                if acc.count() != n {
                    return Err(at(
                        file,
                        format!("{pp}.attributes.{name}"),
                        format!(
                            "accessors[{}] has {} elements; POSITION has {n}",
                            acc.index(),
                            acc.count()
                        ),
                    ));
                }
                Ok(())
            };
            // Triangle indices, local to this primitive.
            let raw: Vec<u32> = match prim.indices() {
                Some(acc) => {
                    let v = uints(file, l, &acc, 1, &format!("{pp}.indices"))?;
                    if let Some(k) = v.iter().position(|&i| i as usize >= n) {
                        return Err(at(
                            file,
                            format!("{pp}.indices"),
                            format!(
                                "index {} (entry {k} of accessors[{}]) is out of range for {n} vertices",
                                v[k],
                                acc.index()
                            ),
                        ));
                    }
                    v
                }
                None => (0..n as u32).collect(),
            };
            let tris: Vec<u32> = match mode {
                Mode::TriangleStrip => {
                    let mut t = Vec::new();
                    for k in 2..raw.len() {
                        if k % 2 == 0 {
                            t.extend_from_slice(&[raw[k - 2], raw[k - 1], raw[k]]);
                        } else {
                            t.extend_from_slice(&[raw[k - 1], raw[k - 2], raw[k]]);
                        }
                    }
                    t
                }
                Mode::TriangleFan => {
                    let mut t = Vec::new();
                    for k in 2..raw.len() {
                        t.extend_from_slice(&[raw[0], raw[k - 1], raw[k]]);
                    }
                    t
                }
                _ => {
                    let whole = raw.len() / 3 * 3;
                    if whole != raw.len() {
                        scene.diagnostics.push(Diagnostic::warning(
                            "gltf-partial-triangle",
                            format!(
                                "{pp} has {} indices, not a multiple of 3; the last {} dropped",
                                raw.len(),
                                raw.len() - whole
                            ),
                        ));
                    }
                    raw[..whole].to_vec()
                }
            };
            let positions: Vec<Vec3> = pos
                .chunks_exact(3)
                .map(|c| xf.transform_point3(Vec3::new(c[0], c[1], c[2])))
                .collect();
            let normals: Vec<Vec3> = match prim.get(&gltf::Semantic::Normals) {
                Some(acc) => {
                    check_count(&acc, "NORMAL")?;
                    let v = floats(file, l, &acc, 3, &format!("{pp}.attributes.NORMAL"))?;
                    let (gen, _) = generate_normals(&positions, &tris);
                    v.chunks_exact(3)
                        .zip(gen)
                        .map(|(c, fallback)| {
                            (nxf * Vec3::new(c[0], c[1], c[2]))
                                .try_normalize()
                                .unwrap_or(fallback)
                        })
                        .collect()
                }
                None => {
                    generated_normals += 1;
                    generate_normals(&positions, &tris).0
                }
            };
            let uvs: Option<Vec<Vec2>> = match prim.get(&gltf::Semantic::TexCoords(0)) {
                Some(acc) => {
                    check_count(&acc, "TEXCOORD_0")?;
                    let v = floats(file, l, &acc, 2, &format!("{pp}.attributes.TEXCOORD_0"))?;
                    Some(v.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect())
                }
                None => None,
            };
            let mut influences: Option<Influences> = None;
            if skinned {
                let Some(rig) = rig else { continue };
                let mut sets: Vec<(Vec<u32>, Vec<f32>)> = Vec::new();
                for s in 0.. {
                    let (Some(ja), Some(wa)) = (
                        prim.get(&gltf::Semantic::Joints(s)),
                        prim.get(&gltf::Semantic::Weights(s)),
                    ) else {
                        break;
                    };
                    check_count(&ja, &format!("JOINTS_{s}"))?;
                    check_count(&wa, &format!("WEIGHTS_{s}"))?;
                    let jv = uints(file, l, &ja, 4, &format!("{pp}.attributes.JOINTS_{s}"))?;
                    let wv = floats(file, l, &wa, 4, &format!("{pp}.attributes.WEIGHTS_{s}"))?;
                    if let Some(k) = wv.iter().position(|&w| w < 0.0) {
                        return Err(at(
                            file,
                            format!("{pp}.attributes.WEIGHTS_{s}"),
                            format!("vertex {} has a negative weight", k / 4),
                        ));
                    }
                    sets.push((jv, wv));
                }
                if sets.is_empty() {
                    scene.diagnostics.push(Diagnostic::warning(
                        "gltf-primitive-skipped",
                        format!(
                            "{pp} belongs to a skinned mesh but has no JOINTS_0/WEIGHTS_0; skipped"
                        ),
                    ));
                    continue;
                }
                let nj = rig.skin_map.len();
                let mut joints = Vec::with_capacity(n);
                let mut weights = Vec::with_capacity(n);
                for v in 0..n {
                    let mut list: Vec<(u32, f32)> = Vec::with_capacity(4 * sets.len());
                    for (s, (jv, wv)) in sets.iter().enumerate() {
                        for c in 0..4 {
                            let (j, w) = (jv[v * 4 + c], wv[v * 4 + c]);
                            if w == 0.0 {
                                continue;
                            }
                            if j as usize >= nj {
                                return Err(at(
                                    file,
                                    format!("{pp}.attributes.JOINTS_{s}"),
                                    format!("vertex {v} uses joint {j}; the skin has {nj} joints"),
                                ));
                            }
                            match list.iter_mut().find(|e| e.0 == j) {
                                Some(e) => e.1 += w,
                                None => list.push((j, w)),
                            }
                        }
                    }
                    let total: f32 = list.iter().map(|e| e.1).sum();
                    if total > 0.0 && (total - 1.0).abs() > 1e-3 {
                        stats.unnormalised += 1;
                    }
                    list.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
                    let kept: f32 = list.iter().take(4).map(|e| e.1).sum();
                    let mut jj = [0u16; 4];
                    let mut ww = [0f32; 4];
                    if total <= 0.0 || kept <= 0.0 {
                        stats.zero_weight += 1;
                        jj[0] = rig.skin_map.first().copied().unwrap_or(0);
                        ww[0] = 1.0;
                    } else {
                        if list.len() > 4 {
                            let lost = (total - kept) / total;
                            stats.vertices_lost += 1;
                            stats.max_lost = stats.max_lost.max(lost);
                            stats.sum_lost += lost as f64;
                        }
                        for (k, &(j, w)) in list.iter().take(4).enumerate() {
                            jj[k] = rig.skin_map.get(j as usize).copied().unwrap_or(0);
                            ww[k] = w / kept;
                        }
                    }
                    joints.push(jj);
                    weights.push(ww);
                }
                influences = Some((joints, weights));
            }
            let base = lod.positions.len() as u32;
            let first = lod.indices.len() as u32;
            lod.positions.extend(positions);
            lod.normals.extend(normals);
            match uvs {
                Some(u) => {
                    if !any_uv && base > 0 {
                        lod.uvs.resize(base as usize, Vec2::ZERO);
                    }
                    any_uv = true;
                    lod.uvs.extend(u);
                }
                None => {
                    uv_missing += 1;
                    if any_uv {
                        lod.uvs.resize(lod.positions.len(), Vec2::ZERO);
                    }
                }
            }
            if let Some((j, w)) = influences {
                lod.joints.extend(j);
                lod.weights.extend(w);
            }
            lod.indices.extend(tris.iter().map(|&i| i + base));
            let material = prim
                .material()
                .index()
                .and_then(|i| mat_names.get(i).cloned())
                .unwrap_or_default();
            lod.submeshes.push(Submesh {
                first_index: first,
                index_count: lod.indices.len() as u32 - first,
                material,
            });
        }
        if lod.positions.is_empty() {
            continue;
        }
        if any_uv && uv_missing > 0 {
            scene.diagnostics.push(Diagnostic::warning(
                "gltf-missing-uvs",
                format!("meshes[{mi}]: {uv_missing} primitives have no TEXCOORD_0; their UVs are set to 0"),
            ));
        }
        let mut name = match mesh.name() {
            Some(s) if !s.is_empty() => s.to_string(),
            _ => format!("mesh{mi}"),
        };
        if !used_names.insert(name.clone()) {
            name = format!("{name}#{}", node.unwrap_or(mi));
            used_names.insert(name.clone());
        }
        let count = lod.positions.len() as u32;
        scene.meshes.push(Mesh {
            name,
            geometry: lod,
            source_vertex: (0..count).collect(),
            source_vertex_count: count,
            lods: Vec::new(),
        });
    }
    if generated_normals > 0 {
        scene.diagnostics.push(
            Diagnostic::warning(
                "gltf-generated-normals",
                format!("{generated_normals} primitives have no NORMAL; area-weighted normals were generated"),
            )
            .with_figure("primitives", generated_normals as f64),
        );
    }
    if stats.vertices_lost > 0 {
        scene.diagnostics.push(
            Diagnostic::warning(
                "gltf-influences-reduced",
                format!(
                    "{} vertices had more than 4 influences; kept the 4 largest and renormalised (lost weight: max {:.4}, mean {:.4})",
                    stats.vertices_lost,
                    stats.max_lost,
                    stats.sum_lost / stats.vertices_lost as f64
                ),
            )
            .with_figure("vertices", stats.vertices_lost as f64)
            .with_figure("max_lost", stats.max_lost as f64)
            .with_figure("mean_lost", stats.sum_lost / stats.vertices_lost as f64),
        );
    }
    if stats.unnormalised > 0 {
        scene.diagnostics.push(
            Diagnostic::warning(
                "gltf-weights-renormalised",
                format!(
                    "{} vertices have weights that do not sum to 1 (off by more than 0.001); they were divided by their sum",
                    stats.unnormalised
                ),
            )
            .with_figure("vertices", stats.unnormalised as f64),
        );
    }
    if stats.zero_weight > 0 {
        scene.diagnostics.push(
            Diagnostic::warning(
                "gltf-zero-weights",
                format!(
                    "{} vertices have no weight; bound to the skin's first joint",
                    stats.zero_weight
                ),
            )
            .with_figure("vertices", stats.zero_weight as f64),
        );
    }
    Ok(())
}

/// Which property a channel drives.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
enum Prop {
    T,
    R,
    S,
}

/// Value of a linear curve at `t`, clamped at the ends (the runtime's rule).
fn curve_at<T: Copy>(c: &Curve<T>, t: f32, lerp: impl Fn(T, T, f32) -> T) -> Option<T> {
    let k = c.times.partition_point(|&x| x <= t);
    if c.values.is_empty() {
        return None;
    }
    if k == 0 {
        return Some(c.values[0]);
    }
    if k >= c.times.len() {
        return c.values.last().copied();
    }
    let (t0, t1) = (c.times[k - 1], c.times[k]);
    let a = (t - t0) / (t1 - t0);
    Some(if a <= 0.0 {
        c.values[k - 1]
    } else {
        lerp(c.values[k - 1], c.values[k], a)
    })
}

#[allow(clippy::too_many_lines)]
fn import_animations(
    file: &str,
    l: &Loaded,
    g: &Graph,
    rig: &Rig,
    scene: &mut Scene,
) -> Result<(), ImportError> {
    let mut used_names = HashSet::new();
    let mut worst_rot = 0.0f32;
    let mut worst_vec = 0.0f32;
    for a in l.doc.animations() {
        let ai = a.index();
        let mut name = match a.name() {
            Some(s) if !s.is_empty() => s.to_string(),
            _ => format!("animation{ai}"),
        };
        if !used_names.insert(name.clone()) {
            name = format!("{name}#{ai}");
            used_names.insert(name.clone());
        }
        let mut per_node: BTreeMap<usize, TrackCurves> = BTreeMap::new();
        let mut duration = 0.0f32;
        let mut intervals: Vec<f32> = Vec::new();
        let mut skipped_weights = 0;
        let mut not_joint: Vec<String> = Vec::new();
        let mut seen: HashSet<(usize, Prop)> = HashSet::new();
        for ch in a.channels() {
            let ci = ch.index();
            let cp = format!("animations[{ai}].channels[{ci}]");
            let sampler = ch.sampler();
            let sp = format!("animations[{ai}].samplers[{}]", sampler.index());
            let interp = match sampler.interpolation() {
                gltf::animation::Interpolation::Linear => Interp::Linear,
                gltf::animation::Interpolation::Step => Interp::Step,
                gltf::animation::Interpolation::CubicSpline => Interp::Cubic,
            };
            let times = floats(file, l, &sampler.input(), 1, &format!("{sp}.input"))?;
            for (k, w) in times.windows(2).enumerate() {
                if w[1] <= w[0] {
                    return Err(at(
                        file,
                        format!("{sp}.input"),
                        format!(
                            "key times must increase: key {} at {} follows {}",
                            k + 1,
                            w[1],
                            w[0]
                        ),
                    ));
                }
                intervals.push(w[1] - w[0]);
            }
            if let Some(&t0) = times.first() {
                if t0 < 0.0 {
                    return Err(at(
                        file,
                        format!("{sp}.input"),
                        format!("negative key time {t0}"),
                    ));
                }
            }
            if let Some(&t) = times.last() {
                duration = duration.max(t);
            }
            let target = ch.target();
            let prop = match target.property() {
                gltf::animation::Property::Translation => Prop::T,
                gltf::animation::Property::Rotation => Prop::R,
                gltf::animation::Property::Scale => Prop::S,
                gltf::animation::Property::MorphTargetWeights => {
                    skipped_weights += 1;
                    continue;
                }
            };
            let node = target.node().index();
            if !rig.joint_of_node.contains_key(&node) {
                not_joint.push(g.names.get(node).cloned().unwrap_or_default());
                continue;
            }
            if !seen.insert((node, prop)) {
                scene.diagnostics.push(Diagnostic::warning(
                    "gltf-duplicate-channel",
                    format!("{cp} drives a property another channel already drives; ignored"),
                ));
                continue;
            }
            if times.is_empty() {
                continue;
            }
            let comps = if prop == Prop::R { 4 } else { 3 };
            let out = floats(file, l, &sampler.output(), comps, &format!("{sp}.output"))?;
            let per_key = if interp == Interp::Cubic { 3 } else { 1 };
            if out.len() != times.len() * per_key * comps {
                return Err(at(
                    file,
                    format!("{sp}.output"),
                    format!(
                        "{} values for {} key times ({:?} needs {per_key} per key)",
                        out.len() / comps,
                        times.len(),
                        interp
                    ),
                ));
            }
            let track = per_node.entry(node).or_insert_with(|| TrackCurves {
                joint: g.names[node].clone(),
                ..TrackCurves::default()
            });
            match prop {
                Prop::R => {
                    let q: Vec<Quat> = out.chunks_exact(4).map(Quat::from_slice).collect();
                    let (c, e) = anim::rotation_curve(&times, &q, interp);
                    worst_rot = worst_rot.max(e);
                    track.rotation = c;
                }
                Prop::T | Prop::S => {
                    let v: Vec<Vec3> = out.chunks_exact(3).map(Vec3::from_slice).collect();
                    let (c, e) = anim::vector_curve(&times, &v, interp);
                    worst_vec = worst_vec.max(e);
                    if prop == Prop::T {
                        track.translation = c;
                    } else {
                        track.scale = c;
                    }
                }
            }
        }
        // Joints with non-joint nodes in front of them: compose those nodes into every key.
        for (node, track) in per_node.iter_mut() {
            if let Some(pre) = rig.pre.get(node) {
                *track = bake_pre(track, *pre, g.local[*node]);
            }
        }
        if skipped_weights > 0 {
            scene.diagnostics.push(
                Diagnostic::info(
                    "gltf-morph-weights-skipped",
                    format!("{name}: {skipped_weights} morph target weight channels skipped (not supported)"),
                )
                .with_figure("channels", skipped_weights as f64),
            );
        }
        if !not_joint.is_empty() {
            not_joint.sort();
            not_joint.dedup();
            scene.diagnostics.push(
                Diagnostic::warning(
                    "gltf-animated-non-joint",
                    format!(
                        "{name}: channels drive nodes that are not joints of the imported skin, ignored: {}",
                        not_joint.join(", ")
                    ),
                )
                .with_figure("nodes", not_joint.len() as f64),
            );
        }
        intervals.sort_by(f32::total_cmp);
        let sample_rate = match intervals.get(intervals.len() / 2) {
            Some(&m) if m > 0.0 => {
                let r = 1.0 / m;
                if (r - r.round()).abs() < 0.01 * r {
                    r.round()
                } else {
                    r
                }
            }
            _ => 30.0,
        };
        scene.clips.push(SceneClip {
            name,
            duration,
            sample_rate,
            looping: false,
            additive: false,
            tracks: per_node.into_values().collect(),
        });
    }
    if worst_rot > 0.0 || worst_vec > 0.0 {
        scene.diagnostics.push(
            Diagnostic::info(
                "gltf-interpolation-error",
                format!(
                    "keys were added between glTF keys; largest measured deviation from glTF interpolation: rotation {worst_rot:.2e} rad, cubic translation/scale {worst_vec:.2e}"
                ),
            )
            .with_figure("rotation_rad", worst_rot as f64)
            .with_figure("vector", worst_vec as f64),
        );
    }
    Ok(())
}

/// Composes `pre` in front of every key of a track (all three channels, at the union of their times).
fn bake_pre(track: &TrackCurves, pre: Mat4, rest: Transform) -> TrackCurves {
    let mut times: Vec<f32> = track
        .translation
        .times
        .iter()
        .chain(&track.rotation.times)
        .chain(&track.scale.times)
        .copied()
        .collect();
    times.sort_by(f32::total_cmp);
    times.dedup();
    let mut out = TrackCurves {
        joint: track.joint.clone(),
        ..TrackCurves::default()
    };
    let mut prev: Option<Quat> = None;
    for &t in &times {
        let tr =
            curve_at(&track.translation, t, |a, b, x| a.lerp(b, x)).unwrap_or(rest.translation);
        let r = curve_at(&track.rotation, t, anim::nlerp).unwrap_or(rest.rotation);
        let s = curve_at(&track.scale, t, |a, b, x| a.lerp(b, x)).unwrap_or(rest.scale);
        let (d, _, _) = decompose(pre * Transform::new(tr, r, s).to_mat4());
        let mut q = d.rotation;
        if let Some(p) = prev {
            if p.dot(q) < 0.0 {
                q = -q;
            }
        }
        prev = Some(q);
        out.translation.times.push(t);
        out.translation.values.push(d.translation);
        out.rotation.times.push(t);
        out.rotation.values.push(q);
        out.scale.times.push(t);
        out.scale.values.push(d.scale);
    }
    out
}
