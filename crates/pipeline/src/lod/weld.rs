//! Welding before a simplification step: vertices equal in every attribute are merged, and a
//! flat-shaded triangle soup (every corner its own vertex) is welded without its normals and rebuilt
//! flat after the step, so that meshoptimizer can collapse it at all.

use sinew_core::glam;
use sinew_core::Lod;

/// True for a flat-shaded triangle soup: every vertex is used by exactly one triangle and the three
/// corners of every triangle share one normal (a non-indexed source such as Fox.glb, whose importer
/// generated per-face normals). meshoptimizer sees every corner of such a mesh as an attribute seam
/// and cannot collapse anything, so the soup is welded without normals and rebuilt flat afterwards.
pub(super) fn is_flat_soup(lod: &Lod) -> bool {
    if lod.indices.is_empty() || lod.indices.len() != lod.positions.len() {
        return false;
    }
    let mut uses = vec![0u8; lod.positions.len()];
    for &i in &lod.indices {
        let u = &mut uses[i as usize];
        if *u > 0 {
            return false;
        }
        *u = 1;
    }
    lod.indices.chunks_exact(3).all(|t| {
        let n = lod.normals[t[0] as usize];
        lod.normals[t[1] as usize] == n && lod.normals[t[2] as usize] == n
    })
}

/// Merges vertices that are bit-for-bit equal in position, UV, joints and weights (and normal, unless
/// `ignore_normals`), with meshoptimizer's `generateVertexRemap`. Lossless when normals count; with
/// `ignore_normals` the merged vertices get area-weighted normals of the welded surface (used only as
/// a simplification attribute; [`flat_soup`] rebuilds face normals afterwards). `lod` must be valid.
pub(super) fn weld(lod: &Lod, ignore_normals: bool) -> Lod {
    const KEY: usize = 16;
    let n = lod.positions.len();
    let mut keys = vec![[0u32; KEY]; n];
    for (v, k) in keys.iter_mut().enumerate() {
        let p = lod.positions[v];
        k[0..3].copy_from_slice(&[p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]);
        if !ignore_normals {
            let q = lod.normals[v];
            k[3..6].copy_from_slice(&[q.x.to_bits(), q.y.to_bits(), q.z.to_bits()]);
        }
        if let Some(uv) = lod.uvs.get(v) {
            k[6..8].copy_from_slice(&[uv.x.to_bits(), uv.y.to_bits()]);
        }
        if let (Some(j), Some(w)) = (lod.joints.get(v), lod.weights.get(v)) {
            k[8] = j[0] as u32 | (j[1] as u32) << 16;
            k[9] = j[2] as u32 | (j[3] as u32) << 16;
            for (slot, x) in w.iter().enumerate() {
                k[10 + slot] = x.to_bits();
            }
        }
    }
    // Indices were validated against `n` (validate_lod), as generateVertexRemap requires.
    let (unique, remap) = meshopt::generate_vertex_remap(&keys, Some(&lod.indices));
    let mut first = vec![u32::MAX; unique];
    for (v, &r) in remap.iter().enumerate() {
        if let Some(f) = first.get_mut(r as usize) {
            if *f == u32::MAX {
                *f = v as u32;
            }
        }
    }
    let pick = |f: &u32| *f as usize;
    let indices: Vec<u32> = lod.indices.iter().map(|&i| remap[i as usize]).collect();
    let positions: Vec<glam::Vec3> = first.iter().map(|f| lod.positions[pick(f)]).collect();
    let normals = if ignore_normals {
        let mut acc = vec![glam::Vec3::ZERO; unique];
        for t in indices.chunks_exact(3) {
            let (a, b, c) = (t[0] as usize, t[1] as usize, t[2] as usize);
            let f = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
            acc[a] += f;
            acc[b] += f;
            acc[c] += f;
        }
        acc.iter()
            .zip(&first)
            .map(|(v, f)| v.try_normalize().unwrap_or(lod.normals[pick(f)]))
            .collect()
    } else {
        first.iter().map(|f| lod.normals[pick(f)]).collect()
    };
    Lod {
        positions,
        normals,
        uvs: if lod.uvs.is_empty() {
            Vec::new()
        } else {
            first.iter().map(|f| lod.uvs[pick(f)]).collect()
        },
        joints: if lod.joints.is_empty() {
            Vec::new()
        } else {
            first.iter().map(|f| lod.joints[pick(f)]).collect()
        },
        weights: if lod.weights.is_empty() {
            Vec::new()
        } else {
            first.iter().map(|f| lod.weights[pick(f)]).collect()
        },
        indices,
        submeshes: lod.submeshes.clone(),
        error: lod.error,
    }
}

/// Rebuilds a flat-shaded soup from a simplified welded mesh: three own vertices per triangle, each
/// with the triangle's face normal (the corner's smooth normal if the triangle has no area).
pub(super) fn flat_soup(lod: &Lod) -> Lod {
    let mut out = Lod {
        submeshes: lod.submeshes.clone(),
        error: lod.error,
        ..Lod::default()
    };
    for t in lod.indices.chunks_exact(3) {
        let c = [t[0] as usize, t[1] as usize, t[2] as usize];
        let p = c.map(|v| lod.positions[v]);
        let face = (p[1] - p[0]).cross(p[2] - p[0]).try_normalize();
        for &v in &c {
            out.indices.push(out.positions.len() as u32);
            out.positions.push(lod.positions[v]);
            out.normals.push(face.unwrap_or(lod.normals[v]));
            if let Some(uv) = lod.uvs.get(v) {
                out.uvs.push(*uv);
            }
            if let (Some(j), Some(w)) = (lod.joints.get(v), lod.weights.get(v)) {
                out.joints.push(*j);
                out.weights.push(*w);
            }
        }
    }
    out
}
