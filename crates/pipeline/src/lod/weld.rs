//! Welding before a simplification step: vertices equal in every attribute (and used by the same
//! submesh) are merged, a vertex used by several submeshes is given one copy per submesh, and a
//! flat-shaded triangle soup (every corner its own vertex) is welded without its normals and rebuilt
//! flat after the step, so that meshoptimizer can collapse it at all.

use sinew_core::glam;
use sinew_core::{Lod, Submesh};

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

/// The submesh of every vertex: the first material range (in order) whose triangles use it
/// (`u32::MAX` for a vertex no triangle uses; 0 for every used vertex of a mesh without ranges).
pub(super) fn submesh_of(lod: &Lod) -> Vec<u32> {
    let mut of = vec![u32::MAX; lod.positions.len()];
    if lod.submeshes.is_empty() {
        for &i in &lod.indices {
            of[i as usize] = 0;
        }
        return of;
    }
    for (s, sub) in lod.submeshes.iter().enumerate() {
        let range = sub.first_index as usize..(sub.first_index + sub.index_count) as usize;
        for &i in &lod.indices[range] {
            let o = &mut of[i as usize];
            if *o == u32::MAX {
                *o = s as u32;
            }
        }
    }
    of
}

/// Gives every vertex that triangles of several submeshes use one copy per submesh (appended, in
/// order of first use), so that each vertex belongs to one material range; `None` when no vertex
/// is shared. `lod` must be valid.
pub(super) fn split_shared(lod: &Lod) -> Option<Lod> {
    let of = submesh_of(lod);
    let mut out: Option<Lod> = None;
    // (vertex, submesh) -> copy, for the copies made so far (few: sorted vector, searched).
    let mut copies: Vec<((u32, u32), u32)> = Vec::new();
    for (s, sub) in lod.submeshes.iter().enumerate() {
        let s = s as u32;
        for at in sub.first_index as usize..(sub.first_index + sub.index_count) as usize {
            let v = lod.indices[at];
            if of[v as usize] == s {
                continue;
            }
            let o = out.get_or_insert_with(|| lod.clone());
            let copy = match copies.binary_search_by_key(&(v, s), |c| c.0) {
                Ok(k) => copies[k].1,
                Err(k) => {
                    let n = o.positions.len() as u32;
                    let v = v as usize;
                    o.positions.push(lod.positions[v]);
                    o.normals.push(lod.normals[v]);
                    if let Some(uv) = lod.uvs.get(v) {
                        o.uvs.push(*uv);
                    }
                    if let (Some(j), Some(w)) = (lod.joints.get(v), lod.weights.get(v)) {
                        o.joints.push(*j);
                        o.weights.push(*w);
                    }
                    copies.insert(k, ((v as u32, s), n));
                    n
                }
            };
            o.indices[at] = copy;
        }
    }
    out
}

/// Merges vertices that are bit-for-bit equal in position, joints and weights (and normal, unless
/// `ignore_normals`; and UV, unless `ignore_uvs`) and used by the same submesh, with
/// meshoptimizer's `generateVertexRemap`, and drops triangles with two corners at one position.
/// Lossless when normals and UVs count; with `ignore_normals` the merged vertices get
/// area-weighted normals of the welded surface (used only as a simplification attribute;
/// [`flat_soup`] rebuilds face normals afterwards); with `ignore_uvs` (no texture reads them) a
/// merged vertex keeps its first copy's UV. `lod` must be valid.
pub(super) fn weld(lod: &Lod, ignore_normals: bool, ignore_uvs: bool) -> Lod {
    const KEY: usize = 15;
    let n = lod.positions.len();
    let of = submesh_of(lod);
    let mut keys = vec![[0u32; KEY]; n];
    for (v, k) in keys.iter_mut().enumerate() {
        let p = lod.positions[v];
        k[0..3].copy_from_slice(&[p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]);
        if !ignore_normals {
            let q = lod.normals[v];
            k[3..6].copy_from_slice(&[q.x.to_bits(), q.y.to_bits(), q.z.to_bits()]);
        }
        if let Some(uv) = lod.uvs.get(v).filter(|_| !ignore_uvs) {
            k[6..8].copy_from_slice(&[uv.x.to_bits(), uv.y.to_bits()]);
        }
        if let (Some(j), Some(w)) = (lod.joints.get(v), lod.weights.get(v)) {
            k[8] = j[0] as u32 | (j[1] as u32) << 16;
            k[9] = j[2] as u32 | (j[3] as u32) << 16;
            for (slot, x) in w.iter().enumerate() {
                k[10 + slot] = x.to_bits();
            }
        }
        k[14] = of[v];
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
    let positions: Vec<glam::Vec3> = first.iter().map(|f| lod.positions[pick(f)]).collect();
    // Triangles with two corners at one position have no area: they are dropped (the surface
    // does not change; meshoptimizer would drop them in its first pass anyway, past its target).
    let flat = |t: &[u32]| {
        let [a, b, c] = [0, 1, 2].map(|k| positions[remap[t[k] as usize] as usize]);
        a == b || b == c || a == c
    };
    let mut submeshes = lod.submeshes.clone();
    let indices = rewrite_triangles(&lod.indices, &mut submeshes, |t| {
        (!flat(t)).then(|| [0, 1, 2].map(|k| remap[t[k] as usize]))
    });
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
        submeshes,
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

/// gltfpack's `simplifyUvSplit`: a vertex used by triangles of both UV windings (on the line where
/// a mirrored UV island meets its other half) gets a copy, appended after the source's vertices,
/// which the triangles of negative winding use instead; the two halves then meet along a seam that
/// meshoptimizer keeps (on a mirrored character, its plane of symmetry). The split source and, for
/// each copy, its original; `None` when the source has no UVs or no such vertex.
pub(super) fn split_uv_mirrors(lod: &Lod) -> Option<(Lod, Vec<u32>)> {
    if lod.uvs.len() != lod.positions.len() {
        return None;
    }
    let winding = |t: &[u32]| {
        let [a, b, c] = [0, 1, 2].map(|k| lod.uvs[t[k] as usize]);
        let area = (b - a).perp_dot(c - a);
        if area > 0.0 {
            1u8
        } else if area < 0.0 {
            2
        } else {
            0
        }
    };
    let mut seen = vec![0u8; lod.positions.len()];
    for t in lod.indices.chunks_exact(3) {
        let w = winding(t);
        for &v in t {
            seen[v as usize] |= w;
        }
    }
    let copy_of: Vec<u32> = (0..lod.positions.len() as u32)
        .filter(|&v| seen[v as usize] == 3)
        .collect();
    if copy_of.is_empty() {
        return None;
    }
    let n = lod.positions.len() as u32;
    let mut copy = vec![u32::MAX; lod.positions.len()];
    for (k, &v) in copy_of.iter().enumerate() {
        copy[v as usize] = n + k as u32;
    }
    let mut out = lod.clone();
    for t in out.indices.chunks_exact_mut(3) {
        if winding(t) == 2 {
            for v in t.iter_mut() {
                if copy[*v as usize] != u32::MAX {
                    *v = copy[*v as usize];
                }
            }
        }
    }
    fn extend<T: Copy>(values: &mut Vec<T>, copy_of: &[u32]) {
        if !values.is_empty() {
            let more: Vec<T> = copy_of.iter().map(|&v| values[v as usize]).collect();
            values.extend(more);
        }
    }
    extend(&mut out.positions, &copy_of);
    extend(&mut out.normals, &copy_of);
    extend(&mut out.uvs, &copy_of);
    extend(&mut out.joints, &copy_of);
    extend(&mut out.weights, &copy_of);
    Some((out, copy_of))
}

/// A build of a [`split_uv_mirrors`] source on the vertices before the split, as gltfpack remaps
/// its indices after simplifying: each copy back to its original (`copy_of`, the copies being the
/// last of `vertex_count` vertices); a triangle left with two corners on one vertex is dropped.
pub(super) fn merge_uv_mirrors(
    (indices, submeshes): (&mut Vec<u32>, &mut [Submesh]),
    vertex_count: usize,
    copy_of: &[u32],
) {
    if copy_of.is_empty() {
        return;
    }
    let originals = vertex_count.saturating_sub(copy_of.len());
    let back = |v: u32| {
        (v as usize)
            .checked_sub(originals)
            .and_then(|k| copy_of.get(k))
            .copied()
            .unwrap_or(v)
    };
    *indices = rewrite_triangles(indices, submeshes, |t| {
        let [a, b, d] = [back(t[0]), back(t[1]), back(t[2])];
        (a != b && b != d && a != d).then_some([a, b, d])
    });
}

/// Each triangle of `indices` through `each` (`None` drops it), range by range of `submeshes`
/// (all of `indices` when there are none), whose first indices and counts are set to the result's.
fn rewrite_triangles(
    indices: &[u32],
    submeshes: &mut [Submesh],
    mut each: impl FnMut(&[u32]) -> Option<[u32; 3]>,
) -> Vec<u32> {
    let ranges: Vec<(usize, usize)> = if submeshes.is_empty() {
        vec![(0, indices.len())]
    } else {
        submeshes
            .iter()
            .map(|s| {
                let from = s.first_index as usize;
                (from, from + s.index_count as usize)
            })
            .collect()
    };
    let mut out = Vec::with_capacity(indices.len());
    for (k, (from, to)) in ranges.into_iter().enumerate() {
        let start = out.len();
        for t in indices[from..to].chunks_exact(3) {
            out.extend(each(t).into_iter().flatten());
        }
        if let Some(s) = submeshes.get_mut(k) {
            s.first_index = start as u32;
            s.index_count = (out.len() - start) as u32;
        }
    }
    out
}
