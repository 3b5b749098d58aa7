//! Decoders of the skeleton, material, mesh (with LODs), source-vertex and mask sections.

use super::cursor::{f32s_of, vec3s, Cur, Result, Strs};
use crate::format::asset::{
    check_lod, check_source_map, LodInfo, Mask, Material, SourceVertexMap, NO_PARENT, NO_STRING,
};
use crate::format::error::{FormatError, FormatErrorKind as K};
use crate::format::write::{ATTR_NORMALS, ATTR_SKIN, ATTR_UVS, MATERIAL_RECORD};
use crate::{Lod, Mesh, Skeleton, Submesh, Transform};
use glam::{Mat4, Quat, Vec2, Vec3};

pub(super) fn source_vertices(
    c: &mut Cur,
    meshes: &[Mesh],
) -> Result<Vec<Option<SourceVertexMap>>> {
    let count = c.u32()?;
    c.skip(12)?;
    let count = c.check_count(count.into(), 16, "source-vertex maps")?;
    let mut out: Vec<Option<SourceVertexMap>> = Vec::new();
    for _ in 0..count {
        c.align()?;
        let at = c.pos;
        let mesh = c.u32()?;
        let n = c.u32()?;
        let source_vertex_count = c.u32()?;
        c.skip(4)?;
        let mi = mesh as usize;
        if mi >= meshes.len() || mi < out.len() {
            return Err(c.err_at(
                at,
                K::IndexOutOfRange {
                    what: "source-vertex map mesh (out of range or not increasing)",
                    index: mesh.into(),
                    limit: meshes.len() as u64,
                },
            ));
        }
        let b = c.elements(n.into(), 4, "source-vertex map entries")?;
        let m = SourceVertexMap {
            source_vertex_count,
            map: b
                .chunks_exact(4)
                .map(|x| u32::from_le_bytes([x[0], x[1], x[2], x[3]]))
                .collect(),
        };
        let vertices = meshes
            .get(mi)
            .and_then(|m| m.lods.first())
            .map_or(0, Lod::vertex_count);
        check_source_map(&m, vertices)
            .map_err(|e| c.err_at(at, K::Invalid(format!("mesh {mi}: {e}"))))?;
        out.resize(mi, None);
        out.push(Some(m));
    }
    Ok(out)
}

pub(super) fn masks(c: &mut Cur, strs: &Strs) -> Result<Vec<Mask>> {
    let count = c.u32()?;
    c.skip(12)?;
    let count = c.check_count(count.into(), 16, "masks")?;
    let mut out: Vec<Mask> = Vec::with_capacity(count);
    for _ in 0..count {
        c.align()?;
        let at = c.pos;
        let name = strs.read(c, "mask name string")?;
        let n = c.u32()?;
        c.skip(8)?;
        let n = c.check_count(n.into(), 8, "mask weights")?;
        let mut weights = Vec::with_capacity(n);
        for _ in 0..n {
            let joint = strs.read(c, "mask joint name string")?;
            let w_at = c.pos;
            let w = c.f32()?;
            if !w.is_finite() {
                return Err(c.err_at(
                    w_at,
                    K::NonFinite {
                        what: "mask weight",
                    },
                ));
            }
            weights.push((joint, w));
        }
        if out.iter().any(|m| m.name == name) {
            return Err(c.err_at(at, K::Invalid(format!("mask name {name:?} appears twice"))));
        }
        out.push(Mask { name, weights });
    }
    Ok(out)
}

pub(super) fn strings(c: &mut Cur) -> Result<Vec<String>> {
    let count = c.u32()?;
    let data_size = c.u32()?;
    c.skip(8)?;
    let entries = c.elements(count.into(), 8, "string entries")?;
    c.align()?;
    let data = c.elements(data_size.into(), 1, "string data bytes")?;
    let mut out = Vec::with_capacity(count as usize);
    for (i, e) in entries.chunks_exact(8).enumerate() {
        let at = u32::from_le_bytes([e[0], e[1], e[2], e[3]]);
        let len = u32::from_le_bytes([e[4], e[5], e[6], e[7]]);
        let entry_pos = 16 + i * 8;
        let s = (at as usize)
            .checked_add(len as usize)
            .and_then(|end| data.get(at as usize..end));
        let Some(s) = s else {
            return Err(c.err_at(
                entry_pos,
                K::IndexOutOfRange {
                    what: "string data",
                    index: u64::from(at) + u64::from(len),
                    limit: data_size.into(),
                },
            ));
        };
        let s = std::str::from_utf8(s)
            .map_err(|_| c.err_at(entry_pos, K::BadUtf8 { index: i as u32 }))?;
        out.push(s.to_owned());
    }
    Ok(out)
}

pub(super) fn skeleton(c: &mut Cur, strs: &Strs) -> Result<Skeleton> {
    let start = c.pos;
    let n = c.u32()?;
    c.skip(12)?;
    // Each joint needs at least 4 + 2 + 40 + 64 bytes.
    let n = c.check_count(n.into(), 110, "joints")?;
    let mut names = Vec::with_capacity(n);
    for _ in 0..n {
        names.push(strs.read(c, "joint name string")?);
    }
    c.align()?;
    let mut parents = Vec::with_capacity(n);
    for i in 0..n {
        let at = c.pos;
        let p = c.u16()?;
        if p == NO_PARENT {
            parents.push(None);
        } else if (p as usize) < i {
            parents.push(Some(p));
        } else {
            return Err(c.err_at(
                at,
                K::IndexOutOfRange {
                    what: "parent joint",
                    index: p.into(),
                    limit: i as u64,
                },
            ));
        }
    }
    c.align()?;
    let bind = c.f32s(n as u64 * 10, "bind transform floats")?;
    c.align()?;
    let inv = c.f32s(n as u64 * 16, "inverse bind floats")?;
    let bind_local = bind
        .chunks_exact(10)
        .map(|f| {
            Transform::new(
                Vec3::new(f[0], f[1], f[2]),
                Quat::from_xyzw(f[3], f[4], f[5], f[6]),
                Vec3::new(f[7], f[8], f[9]),
            )
        })
        .collect();
    let inverse_bind = inv
        .chunks_exact(16)
        .map(|f| {
            let mut a = [0f32; 16];
            a.copy_from_slice(f);
            Mat4::from_cols_array(&a)
        })
        .collect();
    Skeleton::new(names, parents, bind_local, inverse_bind)
        .map_err(|e| c.err_at(start, K::Invalid(e.to_string())))
}

pub(super) fn materials(c: &mut Cur, strs: &Strs) -> Result<Vec<Material>> {
    let count = c.u32()?;
    let at = c.pos;
    let size = c.u32()?;
    if (size as usize) < MATERIAL_RECORD || size % 4 != 0 {
        return Err(c.err_at(
            at,
            K::BadValue {
                what: "material record size",
                value: size.into(),
            },
        ));
    }
    c.skip(8)?;
    let count = c.check_count(count.into(), size as usize, "materials")?;
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        let start = c.pos;
        let name = strs.read(c, "material name string")?;
        let tex_at = c.pos;
        let tex = c.u32()?;
        let texture = if tex == NO_STRING {
            None
        } else {
            Some(strs.get(c, tex_at, tex, "texture string")?)
        };
        let mut base_color = [0f32; 4];
        for v in &mut base_color {
            *v = c.f32()?;
        }
        if !base_color.iter().all(|v| v.is_finite()) {
            return Err(c.err_at(
                start + 8,
                K::NonFinite {
                    what: "base colour",
                },
            ));
        }
        c.skip(size as usize - (c.pos - start))?;
        out.push(Material {
            name,
            base_color,
            texture,
        });
    }
    Ok(out)
}

pub(super) type Meshes = (Vec<Mesh>, Vec<Vec<LodInfo>>);

pub(super) fn meshes(c: &mut Cur, strs: &Strs, joints: Option<usize>) -> Result<Meshes> {
    let count = c.u32()?;
    c.skip(12)?;
    // A mesh needs its 16-byte record and at least one 64-byte LOD (header and metadata).
    let count = c.check_count(count.into(), 80, "meshes")?;
    let mut meshes = Vec::with_capacity(count);
    let mut infos = Vec::with_capacity(count);
    for _ in 0..count {
        c.align()?;
        let mesh_at = c.pos;
        let name = strs.read(c, "mesh name string")?;
        let lod_count = c.u32()?;
        c.skip(8)?;
        if lod_count == 0 {
            return Err(c.err_at(mesh_at, K::Invalid(format!("mesh {name:?} has no LODs"))));
        }
        let lod_count = c.check_count(lod_count.into(), 64, "LODs")?;
        let mut lods = Vec::with_capacity(lod_count);
        let mut info = Vec::with_capacity(lod_count);
        for li in 0..lod_count {
            let (lod, i) = lod(c, strs, joints).map_err(|e| match e.kind {
                K::Invalid(m) => FormatError {
                    kind: K::Invalid(format!("mesh {name:?} LOD {li}: {m}")),
                    ..e
                },
                _ => e,
            })?;
            lods.push(lod);
            info.push(i);
        }
        meshes.push(Mesh { name, lods });
        infos.push(info);
    }
    Ok((meshes, infos))
}

pub(super) fn lod(c: &mut Cur, strs: &Strs, joints: Option<usize>) -> Result<(Lod, LodInfo)> {
    c.align()?;
    let start = c.pos;
    let n = c.u32()?;
    let attributes = c.u32()?;
    if attributes & !(ATTR_NORMALS | ATTR_UVS | ATTR_SKIN) != 0 {
        return Err(c.err_at(
            start + 4,
            K::BadValue {
                what: "vertex attribute flags",
                value: attributes.into(),
            },
        ));
    }
    let index_count = c.u32()?;
    let submesh_count = c.u32()?;
    let meta_size = c.u32()?;
    if (meta_size as usize) < 20 || meta_size % 4 != 0 {
        return Err(c.err_at(
            start + 16,
            K::BadValue {
                what: "LOD metadata size",
                value: meta_size.into(),
            },
        ));
    }
    c.skip(12)?;
    let meta = c.elements(meta_size.into(), 1, "LOD metadata bytes")?;
    let mut m = Cur::new(
        meta,
        c.base + (c.pos - meta.len()) as u64,
        c.section.clone(),
    );
    let error = m.f32()?;
    let target_ratio = m.f32()?;
    let reached_ratio = m.f32()?;
    let error_model = m.f32()?;
    let flags = m.u32()?;
    if flags & !1 != 0 {
        return Err(m.err_at(
            16,
            K::BadValue {
                what: "LOD flags",
                value: flags.into(),
            },
        ));
    }
    if ![error, target_ratio, reached_ratio, error_model]
        .iter()
        .all(|v| v.is_finite())
    {
        return Err(m.err_at(
            0,
            K::NonFinite {
                what: "LOD figures",
            },
        ));
    }
    let info = LodInfo {
        target_ratio,
        reached_ratio,
        error_model,
        stopped_by_error_limit: flags & 1 != 0,
    };
    let n64 = u64::from(n);
    c.align()?;
    let positions = vec3s(c.elements(n64, 12, "positions")?).collect();
    let normals = if attributes & ATTR_NORMALS != 0 {
        c.align()?;
        vec3s(c.elements(n64, 12, "normals")?).collect()
    } else {
        Vec::new()
    };
    let uvs = if attributes & ATTR_UVS != 0 {
        c.align()?;
        c.elements(n64, 8, "uvs")?
            .chunks_exact(8)
            .map(|b| {
                let mut f = f32s_of(b);
                let mut next = || f.next().unwrap_or_default();
                Vec2::new(next(), next())
            })
            .collect()
    } else {
        Vec::new()
    };
    let (joint_ids, weights) = if attributes & ATTR_SKIN != 0 {
        c.align()?;
        let j = c
            .elements(n64, 8, "joint indices")?
            .chunks_exact(8)
            .map(|b| {
                let mut out = [0u16; 4];
                for (o, p) in out.iter_mut().zip(b.chunks_exact(2)) {
                    *o = u16::from_le_bytes([p[0], p[1]]);
                }
                out
            })
            .collect();
        c.align()?;
        let w = c
            .elements(n64, 16, "weights")?
            .chunks_exact(16)
            .map(|b| {
                let mut out = [0f32; 4];
                for (o, v) in out.iter_mut().zip(f32s_of(b)) {
                    *o = v;
                }
                out
            })
            .collect();
        (j, w)
    } else {
        (Vec::new(), Vec::new())
    };
    c.align()?;
    let indices = c
        .elements(index_count.into(), 4, "indices")?
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    c.align()?;
    let submesh_count = c.check_count(submesh_count.into(), 16, "submeshes")?;
    let mut submeshes = Vec::with_capacity(submesh_count);
    for _ in 0..submesh_count {
        let first_index = c.u32()?;
        let index_count = c.u32()?;
        let material = strs.read(c, "submesh material string")?;
        c.skip(4)?;
        submeshes.push(Submesh {
            first_index,
            index_count,
            material,
        });
    }
    let lod = Lod {
        positions,
        normals,
        uvs,
        joints: joint_ids,
        weights,
        indices,
        submeshes,
        error,
    };
    check_lod(&lod, joints).map_err(|k| c.err_at(start, k))?;
    Ok((lod, info))
}
