//! Importer for Wavefront OBJ files and their MTL material libraries (see docs/formats/obj.md).
//!
//! Output: one [`sinew_scene::Mesh`] per object/group name (`o` or `g` line; faces before any such line go
//! to a mesh named after the file), each with one submesh per run of consecutive faces sharing a
//! `usemtl` material. Polygons are triangulated as fans from their first corner; points (`p`) and
//! lines (`l`) are skipped with a warning. Vertices are split where a position is used with different
//! UVs or normals; `source_vertex` holds the 0-based index of the OBJ `v` line, over the whole file.
//!
//! Missing normals are generated per mesh, weighted by triangle area and corner angle, and smoothed only
//! across faces of the same smoothing group (`s n`); faces with `s off`/`s 0` are flat. A file without any
//! `s` line is smoothed as one group.
//!
//! The text is parsed here, not by `tobj`: `tobj` gives no line numbers, has no smoothing groups, drops
//! the OBJ vertex index the scene keeps in `source_vertex`, rejects a whole file over one odd number
//! spelling and can panic on malformed MTL lines. Materials are read from the MTL files named by
//! `mtllib`, through the `resolve` callback; a missing MTL file is a warning.

use crate::text::{clip_name, decode, numbered_lines, truncate};
use crate::{ImportError, ImportOptions, Resolver};
use sinew_core::glam::{Vec2, Vec3};
use sinew_core::{Lod, Submesh};
use sinew_scene::{Diagnostic, Material, Mesh, Scene, SourceFormat};
use std::collections::HashMap;

/// How a number was read.
enum Num {
    /// A valid decimal.
    Exact(f32),
    /// Only a prefix was a number (e.g. `3.1+e2` read as `3.1`).
    Prefix(f32),
}

/// Parses a float; if the whole token is not one, the longest prefix that is (at least one digit).
fn parse_f32(tok: &str) -> Option<Num> {
    if let Ok(v) = tok.parse::<f32>() {
        return Some(Num::Exact(v));
    }
    let bytes = tok.as_bytes();
    let mut end = 0;
    while end < bytes.len() && matches!(bytes[end], b'0'..=b'9' | b'+' | b'-' | b'.' | b'e' | b'E')
    {
        end += 1;
    }
    while end > 0 {
        if let Some(p) = tok.get(..end) {
            if p.bytes().any(|b| b.is_ascii_digit()) {
                if let Ok(v) = p.parse::<f32>() {
                    return Some(Num::Prefix(v));
                }
            }
        }
        end -= 1;
    }
    None
}

/// Where a corner's normal comes from; part of the vertex key.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum NormalSource {
    /// An explicit `vn` index.
    Explicit(u32),
    /// Generated, smoothed within this smoothing group.
    Smooth(u32),
    /// Generated, flat for this face (index within the mesh).
    Flat(u32),
}

/// One face corner as written: 0-based `v`, `vt`, `vn` indices (`u32::MAX` = absent).
#[derive(Debug, Clone, Copy)]
struct Corner {
    v: u32,
    vt: u32,
    vn: u32,
}

const NONE: u32 = u32::MAX;

/// A face collected for one mesh.
#[derive(Debug)]
struct Face {
    first_corner: usize,
    corner_count: usize,
    smoothing: u32,
    material: usize,
}

/// A mesh being collected (one per object/group name).
#[derive(Debug, Default)]
struct MeshBuild {
    name: String,
    faces: Vec<Face>,
    corners: Vec<Corner>,
}

/// Counters behind warnings.
#[derive(Default)]
struct Notes {
    points: usize,
    lines: usize,
    short_faces: usize,
    number_prefix: usize,
    first_number_prefix_line: usize,
    unknown: usize,
    zero_normals: usize,
    missing_uv: usize,
}

/// Imports an OBJ file; `resolve` loads the MTL files named by `mtllib`.
pub fn import(
    file_name: &str,
    bytes: &[u8],
    resolve: Resolver<'_>,
    _options: &ImportOptions,
) -> Result<Scene, ImportError> {
    let f = file_name;
    if bytes.len() >= 2
        && matches!(bytes, [0xFE, 0xFF, ..] | [0xFF, 0xFE, ..])
        && bytes.len() % 2 != 0
    {
        return Err(ImportError::at_offset(
            f,
            "encoding",
            bytes.len() as u64 - 1,
            "UTF-16 file with an odd number of bytes",
        ));
    }
    let text = decode(bytes);

    let mut positions: Vec<Vec3> = Vec::new();
    let mut texcoords: Vec<Vec2> = Vec::new();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut meshes: Vec<MeshBuild> = Vec::new();
    let mut mesh_by_name: HashMap<String, usize> = HashMap::new();
    let mut current_mesh: Option<usize> = None;
    let mut current_name = clip_name(f);
    // Material names in first-use order; index 0 is "" (no usemtl).
    let mut material_names: Vec<String> = vec![String::new()];
    let mut material_index: HashMap<String, usize> = HashMap::new();
    material_index.insert(String::new(), 0);
    let mut current_material = 0usize;
    let mut smoothing = 1u32;
    let mut any_smoothing_line = false;
    let mut mtllibs: Vec<(usize, String)> = Vec::new();
    let mut notes = Notes::default();

    for (n, raw) in numbered_lines(&text) {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let (kw, rest) = match line.split_once(|c: char| c.is_whitespace()) {
            Some((k, r)) => (k, r.trim()),
            None => (line, ""),
        };
        match kw {
            "v" | "vn" | "vt" => {
                let want = if kw == "vt" { 1 } else { 3 };
                let mut vals = [0.0f32; 3];
                let mut count = 0;
                for tok in rest.split_ascii_whitespace().take(3) {
                    let v = match parse_f32(tok) {
                        Some(Num::Exact(v)) => v,
                        Some(Num::Prefix(v)) => {
                            if notes.number_prefix == 0 {
                                notes.first_number_prefix_line = n;
                            }
                            notes.number_prefix += 1;
                            v
                        }
                        None => {
                            return Err(ImportError::at_line(
                                f,
                                kw,
                                n,
                                format!("expected a number, found {:?}", truncate(tok)),
                            ))
                        }
                    };
                    if !v.is_finite() {
                        return Err(ImportError::at_line(
                            f,
                            kw,
                            n,
                            format!("non-finite number {:?}", truncate(tok)),
                        ));
                    }
                    vals[count] = v;
                    count += 1;
                }
                if count < want {
                    return Err(ImportError::at_line(
                        f,
                        kw,
                        n,
                        format!("`{kw}` needs {want} numbers, found {count}"),
                    ));
                }
                match kw {
                    "v" => positions.push(Vec3::from_array(vals)),
                    "vn" => normals.push(Vec3::from_array(vals)),
                    _ => texcoords.push(Vec2::new(vals[0], vals[1])),
                }
                if positions.len() >= NONE as usize
                    || normals.len() >= NONE as usize
                    || texcoords.len() >= NONE as usize
                {
                    return Err(ImportError::at_line(f, kw, n, "more than 2^32-1 elements"));
                }
            }
            "f" | "fo" => {
                let mesh_idx = match current_mesh {
                    Some(m) => m,
                    None => {
                        let m = *mesh_by_name.entry(current_name.clone()).or_insert_with(|| {
                            meshes.push(MeshBuild {
                                name: current_name.clone(),
                                ..Default::default()
                            });
                            meshes.len() - 1
                        });
                        current_mesh = Some(m);
                        m
                    }
                };
                let Some(mesh) = meshes.get_mut(mesh_idx) else {
                    return Err(ImportError::at_line(f, "f", n, "internal: mesh missing"));
                };
                let first = mesh.corners.len();
                for tok in rest.split_ascii_whitespace() {
                    let mut parts = tok.split('/');
                    let mut idx = [NONE; 3];
                    let counts = [positions.len(), texcoords.len(), normals.len()];
                    const KINDS: [&str; 3] = ["vertex", "texture coordinate", "normal"];
                    for (k, slot) in idx.iter_mut().enumerate() {
                        let Some(p) = parts.next() else { break };
                        if p.is_empty() {
                            if k == 0 {
                                return Err(ImportError::at_line(
                                    f,
                                    "f",
                                    n,
                                    format!("face corner {tok:?} has no vertex index"),
                                ));
                            }
                            continue;
                        }
                        let Ok(i) = p.parse::<i64>() else {
                            return Err(ImportError::at_line(
                                f,
                                "f",
                                n,
                                format!("bad index {:?} in face corner", truncate(p)),
                            ));
                        };
                        let count = counts[k] as i64;
                        let resolved = if i > 0 {
                            if i > count {
                                return Err(ImportError::at_line(
                                    f,
                                    "f",
                                    n,
                                    format!(
                                        "{} index {i} out of range ({count} defined so far)",
                                        KINDS[k]
                                    ),
                                ));
                            }
                            i - 1
                        } else if i < 0 {
                            let r = count + i;
                            if r < 0 {
                                return Err(ImportError::at_line(
                                    f,
                                    "f",
                                    n,
                                    format!(
                                        "relative {} index {i} reaches before the first ({} defined so far)",
                                        KINDS[k], count
                                    ),
                                ));
                            }
                            r
                        } else {
                            return Err(ImportError::at_line(
                                f,
                                "f",
                                n,
                                format!("{} index 0 (OBJ indices start at 1)", KINDS[k]),
                            ));
                        };
                        if resolved >= NONE as i64 {
                            return Err(ImportError::at_line(
                                f,
                                "f",
                                n,
                                format!("{} index {i} out of range", KINDS[k]),
                            ));
                        }
                        *slot = resolved as u32;
                    }
                    if parts.next().is_some() {
                        return Err(ImportError::at_line(
                            f,
                            "f",
                            n,
                            format!("face corner {:?} has more than 3 indices", truncate(tok)),
                        ));
                    }
                    mesh.corners.push(Corner {
                        v: idx[0],
                        vt: idx[1],
                        vn: idx[2],
                    });
                }
                let count = mesh.corners.len() - first;
                if count < 3 {
                    mesh.corners.truncate(first);
                    notes.short_faces += 1;
                    continue;
                }
                mesh.faces.push(Face {
                    first_corner: first,
                    corner_count: count,
                    smoothing,
                    material: current_material,
                });
            }
            "p" => notes.points += 1,
            "l" => notes.lines += 1,
            "o" | "g" => {
                let name = rest.split_ascii_whitespace().collect::<Vec<_>>().join(" ");
                let name = if name.is_empty() { clip_name(f) } else { name };
                if name != current_name {
                    current_name = name;
                    current_mesh = None;
                }
            }
            "s" => {
                any_smoothing_line = true;
                smoothing = if rest.eq_ignore_ascii_case("off") {
                    0
                } else {
                    match rest.parse::<u32>() {
                        Ok(v) => v,
                        Err(_) => {
                            return Err(ImportError::at_line(
                                f,
                                "s",
                                n,
                                format!(
                                    "smoothing group must be a number or `off`, found {:?}",
                                    truncate(rest)
                                ),
                            ))
                        }
                    }
                };
            }
            "usemtl" => {
                let name = rest.to_string();
                current_material = match material_index.get(&name) {
                    Some(&i) => i,
                    None => {
                        material_names.push(name.clone());
                        material_index.insert(name, material_names.len() - 1);
                        material_names.len() - 1
                    }
                };
            }
            "mtllib" => mtllibs.push((n, rest.to_string())),
            _ => notes.unknown += 1,
        }
    }

    let face_total: usize = meshes.iter().map(|m| m.faces.len()).sum();
    if face_total == 0 {
        return Err(ImportError::in_section(
            f,
            "f",
            "the file has no faces with three or more vertices",
        ));
    }

    let mut scene = Scene::new(SourceFormat::Obj);

    // Materials.
    let mut materials: Vec<Material> = Vec::new();
    for (line, lib) in &mtllibs {
        load_mtllib(
            f,
            *line,
            lib,
            resolve,
            &mut materials,
            &mut scene.diagnostics,
        );
    }
    let mut missing_materials = Vec::new();
    let defined: std::collections::HashSet<String> =
        materials.iter().map(|m| m.name.clone()).collect();
    for name in material_names.iter().skip(1) {
        if !defined.contains(name) {
            missing_materials.push(name.clone());
            materials.push(Material {
                name: name.clone(),
                base_color: [1.0, 1.0, 1.0, 1.0],
                texture: None,
            });
        }
    }
    if !missing_materials.is_empty() {
        scene.diagnostics.push(
            Diagnostic::warning(
                "obj-material-missing",
                format!(
                    "materials used but not defined in any MTL file (given white): {}",
                    missing_materials.join(", ")
                ),
            )
            .with_figure("materials", missing_materials.len() as f64),
        );
    }
    scene.materials = materials;

    for m in &meshes {
        if m.faces.is_empty() {
            continue;
        }
        let mesh = build_mesh(
            m,
            &positions,
            &texcoords,
            &normals,
            &material_names,
            any_smoothing_line,
            &mut notes,
        );
        scene.meshes.push(mesh);
    }

    let d = &mut scene.diagnostics;
    if notes.points > 0 || notes.lines > 0 {
        d.push(
            Diagnostic::warning(
                "obj-points-lines-ignored",
                format!(
                    "{} point (`p`) and {} line (`l`) elements were ignored",
                    notes.points, notes.lines
                ),
            )
            .with_figure("points", notes.points as f64)
            .with_figure("lines", notes.lines as f64),
        );
    }
    if notes.short_faces > 0 {
        d.push(
            Diagnostic::warning(
                "obj-short-faces",
                format!(
                    "{} faces with fewer than 3 vertices were ignored",
                    notes.short_faces
                ),
            )
            .with_figure("faces", notes.short_faces as f64),
        );
    }
    if notes.number_prefix > 0 {
        d.push(
            Diagnostic::warning(
                "obj-number-format",
                format!(
                    "{} numbers were not valid decimals and were read up to the first invalid character (first at line {})",
                    notes.number_prefix, notes.first_number_prefix_line
                ),
            )
            .with_figure("numbers", notes.number_prefix as f64)
            .with_figure("first_line", notes.first_number_prefix_line as f64),
        );
    }
    if notes.unknown > 0 {
        d.push(
            Diagnostic::info(
                "obj-unknown-lines",
                format!(
                    "{} lines with unsupported keywords were skipped",
                    notes.unknown
                ),
            )
            .with_figure("lines", notes.unknown as f64),
        );
    }
    if notes.zero_normals > 0 {
        d.push(
            Diagnostic::warning(
                "obj-zero-normals",
                format!(
                    "{} vertices had a zero-length normal (degenerate faces or `vn 0 0 0`) and were given +Z",
                    notes.zero_normals
                ),
            )
            .with_figure("vertices", notes.zero_normals as f64),
        );
    }
    if notes.missing_uv > 0 {
        d.push(
            Diagnostic::warning(
                "obj-missing-uvs",
                format!(
                    "{} vertices without a texture coordinate in meshes that have them were given (0, 0)",
                    notes.missing_uv
                ),
            )
            .with_figure("vertices", notes.missing_uv as f64),
        );
    }
    Ok(scene)
}

/// Angle at `a` between edges to `b` and `c`.
fn corner_angle(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let u = (b - a).normalize_or_zero();
    let v = (c - a).normalize_or_zero();
    u.dot(v).clamp(-1.0, 1.0).acos()
}

fn build_mesh(
    m: &MeshBuild,
    positions: &[Vec3],
    texcoords: &[Vec2],
    normals: &[Vec3],
    material_names: &[String],
    any_smoothing_line: bool,
    notes: &mut Notes,
) -> Mesh {
    let pos = |i: u32| positions.get(i as usize).copied().unwrap_or(Vec3::ZERO);
    let has_uv = m.corners.iter().any(|c| c.vt != NONE);

    // Triangles as corner indices (fans), with their face index.
    let mut tris: Vec<([usize; 3], usize)> = Vec::new();
    for (fi, face) in m.faces.iter().enumerate() {
        for k in 2..face.corner_count {
            tris.push((
                [
                    face.first_corner,
                    face.first_corner + k - 1,
                    face.first_corner + k,
                ],
                fi,
            ));
        }
    }

    // Generated normals: accumulate area*angle weighted face normals.
    let source_of = |c: &Corner, fi: usize, face: &Face| -> NormalSource {
        if c.vn != NONE {
            NormalSource::Explicit(c.vn)
        } else {
            let s = if any_smoothing_line {
                face.smoothing
            } else {
                1
            };
            if s == 0 {
                NormalSource::Flat(fi as u32)
            } else {
                NormalSource::Smooth(s)
            }
        }
    };
    let mut smooth_acc: HashMap<(u32, u32), Vec3> = HashMap::new();
    let mut flat_acc: HashMap<u32, Vec3> = HashMap::new();
    for (tri, fi) in &tris {
        let Some(face) = m.faces.get(*fi) else {
            continue;
        };
        let cs = tri.map(|i| {
            m.corners.get(i).copied().unwrap_or(Corner {
                v: 0,
                vt: NONE,
                vn: NONE,
            })
        });
        let p = cs.map(|c| pos(c.v));
        let area_n = (p[1] - p[0]).cross(p[2] - p[0]);
        for k in 0..3 {
            match source_of(&cs[k], *fi, face) {
                NormalSource::Explicit(_) => {}
                NormalSource::Smooth(s) => {
                    let angle = corner_angle(p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
                    *smooth_acc.entry((cs[k].v, s)).or_insert(Vec3::ZERO) += area_n * angle;
                }
                NormalSource::Flat(fid) => {
                    *flat_acc.entry(fid).or_insert(Vec3::ZERO) += area_n;
                }
            }
        }
    }

    let mut lod = Lod::default();
    let mut source_vertex = Vec::new();
    let mut vertex_of: HashMap<(u32, u32, NormalSource), u32> = HashMap::new();
    let mut current: Option<(usize, u32)> = None; // (material, first index)
    for (tri, fi) in &tris {
        let Some(face) = m.faces.get(*fi) else {
            continue;
        };
        if current.map(|c| c.0) != Some(face.material) {
            if let Some((mat, first)) = current {
                lod.submeshes.push(Submesh {
                    first_index: first,
                    index_count: lod.indices.len() as u32 - first,
                    material: material_names.get(mat).cloned().unwrap_or_default(),
                });
            }
            current = Some((face.material, lod.indices.len() as u32));
        }
        for &ci in tri {
            let c = m.corners.get(ci).copied().unwrap_or(Corner {
                v: 0,
                vt: NONE,
                vn: NONE,
            });
            let src = source_of(&c, *fi, face);
            let key = (c.v, c.vt, src);
            let idx = match vertex_of.get(&key) {
                Some(&i) => i,
                None => {
                    let i = lod.positions.len() as u32;
                    lod.positions.push(pos(c.v));
                    let raw_n = match src {
                        NormalSource::Explicit(vn) => {
                            normals.get(vn as usize).copied().unwrap_or(Vec3::ZERO)
                        }
                        NormalSource::Smooth(s) => {
                            smooth_acc.get(&(c.v, s)).copied().unwrap_or(Vec3::ZERO)
                        }
                        NormalSource::Flat(fid) => {
                            flat_acc.get(&fid).copied().unwrap_or(Vec3::ZERO)
                        }
                    };
                    let nrm = raw_n.normalize_or_zero();
                    lod.normals.push(if nrm == Vec3::ZERO {
                        notes.zero_normals += 1;
                        Vec3::Z
                    } else {
                        nrm
                    });
                    if has_uv {
                        if c.vt == NONE {
                            notes.missing_uv += 1;
                        }
                        lod.uvs
                            .push(texcoords.get(c.vt as usize).copied().unwrap_or(Vec2::ZERO));
                    }
                    source_vertex.push(c.v);
                    vertex_of.insert(key, i);
                    i
                }
            };
            lod.indices.push(idx);
        }
    }
    if let Some((mat, first)) = current {
        lod.submeshes.push(Submesh {
            first_index: first,
            index_count: lod.indices.len() as u32 - first,
            material: material_names.get(mat).cloned().unwrap_or_default(),
        });
    }
    Mesh {
        name: m.name.clone(),
        geometry: lod,
        source_vertex,
        source_vertex_count: positions.len() as u32,
        lods: Vec::new(),
        lods_not_built: Vec::new(),
    }
}

/// Loads one `mtllib` line's files into `materials`; problems become warnings.
fn load_mtllib(
    obj_file: &str,
    line: usize,
    lib: &str,
    resolve: Resolver<'_>,
    materials: &mut Vec<Material>,
    diags: &mut Vec<Diagnostic>,
) {
    // The rest of the line is one file name (names may contain spaces); if that does not load and
    // there are several words, each word is a file, as the OBJ spec has it.
    let words: Vec<&str> = lib.split_ascii_whitespace().collect();
    if words.is_empty() {
        diags.push(Diagnostic::warning(
            "obj-mtl-missing",
            format!("{obj_file}: mtllib at line {line} names no file"),
        ));
        return;
    }
    let attempts: Vec<String> = match resolve(lib) {
        Ok(bytes) => {
            parse_mtl(lib, &bytes, materials, diags);
            return;
        }
        Err(_) if words.len() > 1 => words.iter().map(|w| w.to_string()).collect(),
        Err(_) => vec![lib.to_string()],
    };
    for name in attempts {
        match resolve(&name) {
            Ok(bytes) => parse_mtl(&name, &bytes, materials, diags),
            Err(e) => diags.push(Diagnostic::warning(
                "obj-mtl-missing",
                format!(
                    "{obj_file}: material library {name:?} (mtllib at line {line}) could not be read: {e}"
                ),
            )),
        }
    }
}

/// Parses MTL text: `newmtl`, `Kd` (base colour), `d`/`Tr` (alpha), `map_Kd` (texture). Malformed lines
/// are skipped with a warning naming the line.
fn parse_mtl(name: &str, bytes: &[u8], materials: &mut Vec<Material>, diags: &mut Vec<Diagnostic>) {
    let text = decode(bytes);
    let mut index: HashMap<String, usize> = materials
        .iter()
        .enumerate()
        .map(|(i, m)| (m.name.clone(), i))
        .collect();
    let mut current: Option<usize> = None;
    let mut bad_lines: Vec<usize> = Vec::new();
    for (n, raw) in numbered_lines(&text) {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let (kw, rest) = match line.split_once(|c: char| c.is_whitespace()) {
            Some((k, r)) => (k, r.trim()),
            None => (line, ""),
        };
        let nums = || -> Option<Vec<f32>> {
            rest.split_ascii_whitespace()
                .map(|t| t.parse::<f32>().ok().filter(|v| v.is_finite()))
                .collect()
        };
        match kw {
            "newmtl" => {
                if rest.is_empty() {
                    bad_lines.push(n);
                    current = None;
                    continue;
                }
                current = Some(match index.get(rest) {
                    Some(&i) => i,
                    None => {
                        index.insert(rest.to_string(), materials.len());
                        materials.push(Material {
                            name: rest.to_string(),
                            base_color: [1.0, 1.0, 1.0, 1.0],
                            texture: None,
                        });
                        materials.len() - 1
                    }
                });
            }
            "Kd" | "d" | "Tr" | "map_Kd" => {
                let Some(m) = current.and_then(|i| materials.get_mut(i)) else {
                    bad_lines.push(n);
                    continue;
                };
                match kw {
                    "Kd" => match nums().as_deref() {
                        Some([r, g, b]) => {
                            m.base_color[0] = *r;
                            m.base_color[1] = *g;
                            m.base_color[2] = *b;
                        }
                        Some([v]) => {
                            m.base_color[0] = *v;
                            m.base_color[1] = *v;
                            m.base_color[2] = *v;
                        }
                        _ => bad_lines.push(n),
                    },
                    "d" => match nums().as_deref() {
                        Some([a]) => m.base_color[3] = *a,
                        _ => bad_lines.push(n),
                    },
                    "Tr" => match nums().as_deref() {
                        Some([t]) => m.base_color[3] = 1.0 - *t,
                        _ => bad_lines.push(n),
                    },
                    _ => {
                        // Options (`-o u v`, `-bm 1`...) come before the file name; take the last word
                        // when options are present, the whole rest otherwise (names may hold spaces).
                        let file = if rest.starts_with('-') {
                            rest.split_ascii_whitespace().last().unwrap_or("")
                        } else {
                            rest
                        };
                        if file.is_empty() {
                            bad_lines.push(n);
                        } else {
                            m.texture = Some(file.to_string());
                        }
                    }
                }
            }
            _ => {}
        }
    }
    if !bad_lines.is_empty() {
        let shown: Vec<String> = bad_lines.iter().take(10).map(|l| l.to_string()).collect();
        diags.push(
            Diagnostic::warning(
                "obj-mtl-malformed",
                format!(
                    "{name}: {} malformed material lines skipped (lines {}{})",
                    bad_lines.len(),
                    shown.join(", "),
                    if bad_lines.len() > 10 { ", ..." } else { "" }
                ),
            )
            .with_figure("lines", bad_lines.len() as f64),
        );
    }
}
