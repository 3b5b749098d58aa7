//! The parts of a mesh (its connected pieces) and the vertices that give each its shape: what the LOD
//! builder locks so that a thin or small part is not shortened or swallowed while the whole mesh is
//! simplified.
//!
//! meshoptimizer ranks collapses by a quadric error that is zero for any collapse inside a plane: the
//! tip of a flat blade can slide back along the blade at no cost, so on a many-part character the
//! accessories' tips went first (issue 18: 4.2% of the diagonal on both LODs of a 59-part model, where
//! gltfpack stays within 0.82%). Locking, per part, the vertices at the ends of its extent along each
//! axis and the one farthest from its centre keeps every part's reach; the rest of the part still
//! simplifies.

use sinew_core::glam::Vec3;
use std::collections::HashMap;

/// Per vertex: true when it sits (bit for bit) at one of its part's extreme positions — the lowest
/// and highest along x, y and z, and the farthest from the centre of the part's bounding box. Parts
/// are the sets of triangles connected through shared positions (vertices split for UV or normal
/// seams belong to one part). Indices must be valid for `positions`.
pub(crate) fn part_extremes(positions: &[Vec3], indices: &[u32]) -> Vec<bool> {
    let key = |p: Vec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    // One id per distinct position, in order of first appearance.
    let mut ids: HashMap<[u32; 3], u32> = HashMap::with_capacity(positions.len());
    let mut id_of = Vec::with_capacity(positions.len());
    let mut at: Vec<Vec3> = Vec::new();
    for &p in positions {
        let next = at.len() as u32;
        let id = *ids.entry(key(p)).or_insert(next);
        if id == next {
            at.push(p);
        }
        id_of.push(id);
    }
    let mut parent: Vec<u32> = (0..at.len() as u32).collect();
    fn root(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            let up = parent[parent[x as usize] as usize];
            parent[x as usize] = up;
            x = up;
        }
        x
    }
    let mut used = vec![false; at.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|i| id_of[t[i] as usize]);
        for v in [a, b, c] {
            used[v as usize] = true;
        }
        for v in [b, c] {
            let (ra, rv) = (root(&mut parent, a), root(&mut parent, v));
            // The smaller id becomes the root: the result does not depend on the order of unions.
            if ra != rv {
                let (lo, hi) = (ra.min(rv), ra.max(rv));
                parent[hi as usize] = lo;
            }
        }
    }
    // Per part (keyed by its root): the ids of the lowest and highest position on each axis.
    let mut lo_hi: HashMap<u32, [u32; 6]> = HashMap::new();
    for id in 0..at.len() as u32 {
        if !used[id as usize] {
            continue;
        }
        let r = root(&mut parent, id);
        let e = lo_hi.entry(r).or_insert([id; 6]);
        let p = at[id as usize];
        for axis in 0..3 {
            // Ties keep the first id.
            if p[axis] < at[e[2 * axis] as usize][axis] {
                e[2 * axis] = id;
            }
            if p[axis] > at[e[2 * axis + 1] as usize][axis] {
                e[2 * axis + 1] = id;
            }
        }
    }
    let mut locked = vec![false; at.len()];
    let mut far: HashMap<u32, (f32, u32)> = HashMap::new();
    for id in 0..at.len() as u32 {
        if !used[id as usize] {
            continue;
        }
        let r = root(&mut parent, id);
        let Some(e) = lo_hi.get(&r) else { continue };
        let centre = Vec3::new(
            (at[e[0] as usize].x + at[e[1] as usize].x) * 0.5,
            (at[e[2] as usize].y + at[e[3] as usize].y) * 0.5,
            (at[e[4] as usize].z + at[e[5] as usize].z) * 0.5,
        );
        let d = at[id as usize].distance_squared(centre);
        let f = far.entry(r).or_insert((d, id));
        if d > f.0 {
            *f = (d, id);
        }
    }
    for e in lo_hi.values() {
        for &id in e {
            locked[id as usize] = true;
        }
    }
    for &(_, id) in far.values() {
        locked[id as usize] = true;
    }
    id_of.iter().map(|&id| locked[id as usize]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat blade along x (a strip of quads, tip at x = 10) and, apart from it, a small square.
    fn blade_and_square() -> (Vec<Vec3>, Vec<u32>) {
        let mut p = Vec::new();
        let mut idx = Vec::new();
        for i in 0..=10 {
            let w = 0.1 * (1.0 - i as f32 / 10.0) + 0.01;
            p.push(Vec3::new(i as f32, -w, 0.0));
            p.push(Vec3::new(i as f32, w, 0.0));
        }
        for i in 0..10u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            idx.extend([a, c, b, b, c, d]);
        }
        let s = p.len() as u32;
        for (x, y) in [(20.0, 0.0), (21.0, 0.0), (21.0, 1.0), (20.0, 1.0)] {
            p.push(Vec3::new(x, y, 5.0));
        }
        idx.extend([s, s + 1, s + 2, s, s + 2, s + 3]);
        (p, idx)
    }

    #[test]
    fn each_part_keeps_its_ends_and_its_farthest_vertex() {
        let (p, idx) = blade_and_square();
        let locked = part_extremes(&p, &idx);
        // The blade: its base (x = 0) and tip (x = 10) vertices are extremes along x; along y the
        // widest pair is at the base; along z everything ties, so the first vertex.
        assert!(locked[0] && locked[1], "base");
        assert!(locked[20] || locked[21], "tip");
        // Nothing in the middle of the blade is locked.
        assert!((4..16).all(|v| !locked[v]), "{locked:?}");
        // The square is its own part: the first corner at each of its x and y ends — (20, 0),
        // (21, 0) and (21, 1); (20, 1) is an end only after another corner on both axes, and every
        // corner is as far from the centre, so the first one counts for that.
        assert_eq!(
            locked[22..],
            [true, true, true, false],
            "{:?}",
            &locked[22..]
        );
    }

    #[test]
    fn a_vertex_split_at_a_seam_belongs_to_the_same_part() {
        let (mut p, mut idx) = blade_and_square();
        // The blade's tip again as a separate vertex (a UV seam) used by the last triangle.
        p.push(p[21]);
        let last = idx.len() - 1;
        idx[last] = (p.len() - 1) as u32;
        let locked = part_extremes(&p, &idx);
        // Same position, same answer.
        assert_eq!(locked[21], locked[p.len() - 1]);
        // Unused vertices are never locked.
        p.push(Vec3::splat(100.0));
        let locked = part_extremes(&p, &idx);
        assert!(!locked[p.len() - 1]);
    }
}
