//! The parts of a mesh (its connected pieces) and the vertices that give each its shape: what the LOD
//! builder gives meshoptimizer's `Priority` so that a thin or small part is not shortened or
//! swallowed while the whole mesh is simplified.
//!
//! meshoptimizer ranks collapses by a quadric error that is zero for any collapse inside a plane: the
//! tip of a flat blade can slide back along the blade at no cost, so on a many-part character the
//! accessories' tips went first (issue 18: 4.2% of the diagonal on both LODs of a 59-part model, where
//! gltfpack stays within 0.82%). Per part, the vertices at the ends of its extent along each axis and
//! the one farthest from its centre cost their displacement when moved, whatever the part's size
//! (issue 30: a size threshold let parts of 12 to 60 triangles lose their tips); the rest of the
//! part simplifies as before.

use sinew_core::glam::Vec3;

/// One id per distinct position (bit for bit, so -0.0 and 0.0 differ), numbered in order of first
/// appearance: the number of ids and each vertex's id. meshoptimizer's hashed `generateVertexRemap`
/// does the grouping (a SipHash map of the bit patterns took a third of the LOD builder's own time
/// on CesiumMan).
pub(crate) fn position_ids(positions: &[Vec3]) -> (usize, Vec<u32>) {
    if positions.is_empty() {
        return (0, Vec::new());
    }
    let keys: Vec<[u32; 3]> = positions
        .iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect();
    meshopt::generate_vertex_remap(&keys, None)
}

/// Per vertex: true when it sits (bit for bit) at one of its part's extreme positions — the lowest
/// and highest along x, y and z, and the farthest from the centre of the part's bounding box — in
/// every part, whatever its size. Parts
/// are the sets of triangles connected through shared positions (vertices split for UV or normal
/// seams belong to one part). Indices must be valid for `positions`.
pub(crate) fn part_extremes(positions: &[Vec3], indices: &[u32]) -> Vec<bool> {
    let (count, id_of) = position_ids(positions);
    let mut at: Vec<Vec3> = vec![Vec3::ZERO; count];
    for (&id, &p) in id_of.iter().zip(positions) {
        at[id as usize] = p;
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
    // Per part (indexed by its root): the ids of the lowest and highest position on each axis.
    let mut lo_hi: Vec<Option<[u32; 6]>> = vec![None; at.len()];
    for id in 0..at.len() as u32 {
        if !used[id as usize] {
            continue;
        }
        let r = root(&mut parent, id);
        let e = lo_hi[r as usize].get_or_insert([id; 6]);
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
    let mut far: Vec<Option<(f32, u32)>> = vec![None; at.len()];
    for id in 0..at.len() as u32 {
        if !used[id as usize] {
            continue;
        }
        let r = root(&mut parent, id);
        let Some(e) = lo_hi[r as usize] else { continue };
        let centre = Vec3::new(
            (at[e[0] as usize].x + at[e[1] as usize].x) * 0.5,
            (at[e[2] as usize].y + at[e[3] as usize].y) * 0.5,
            (at[e[4] as usize].z + at[e[5] as usize].z) * 0.5,
        );
        let d = at[id as usize].distance_squared(centre);
        let f = far[r as usize].get_or_insert((d, id));
        if d > f.0 {
            *f = (d, id);
        }
    }
    for e in lo_hi.iter().flatten() {
        for &id in e {
            locked[id as usize] = true;
        }
    }
    for (_, id) in far.iter().flatten() {
        locked[*id as usize] = true;
    }
    id_of.iter().map(|&id| locked[id as usize]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat blade along x (a strip of `n` quads, tip at x = n) and, apart from it, a small square.
    fn blade_and_square_n(n: u32) -> (Vec<Vec3>, Vec<u32>) {
        let mut p = Vec::new();
        let mut idx = Vec::new();
        for i in 0..=n {
            let w = 0.1 * (1.0 - i as f32 / n as f32) + 0.01;
            p.push(Vec3::new(i as f32, -w, 0.0));
            p.push(Vec3::new(i as f32, w, 0.0));
        }
        for i in 0..n {
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

    /// The small blade: 10 quads, 20 triangles.
    fn blade_and_square() -> (Vec<Vec3>, Vec<u32>) {
        blade_and_square_n(10)
    }

    #[test]
    fn each_part_keeps_its_ends_and_its_farthest_vertex() {
        // A blade of 40 quads (80 triangles, not small): its base (x = 0) and tip (x = 40) are its
        // ends along x; along y the widest pair is at the base; along z everything ties, so the
        // first vertex; the farthest from the centre is a base or tip vertex.
        let (p, idx) = blade_and_square_n(40);
        let locked = part_extremes(&p, &idx);
        assert!(locked[0] && locked[1], "base");
        assert!(locked[80] || locked[81], "tip");
        assert!((4..76).all(|v| !locked[v]), "{locked:?}");
        // The square is its own part, of two triangles: its extremes too (three of its corners:
        // the fourth is no axis's first end and ties for the farthest).
        assert_eq!(&locked[82..], &[true, true, true, false]);
        // The small blade (20 triangles): its base and tip too, and nothing in between.
        let (p, idx) = blade_and_square();
        let locked = part_extremes(&p, &idx);
        assert!(locked[0] && locked[1], "base");
        assert!(locked[20] || locked[21], "tip");
        assert!((4..16).all(|v| !locked[v]), "{locked:?}");
    }

    #[test]
    fn a_vertex_split_at_a_seam_belongs_to_the_same_part() {
        let (mut p, mut idx) = blade_and_square_n(40);
        // The tip's first vertex (x = 40, the first at the highest x: locked) again as a separate
        // vertex (a UV seam), used by one of the two triangles that use it.
        let tip = 80u32;
        assert!(part_extremes(&p, &idx)[tip as usize]);
        p.push(p[tip as usize]);
        let copy = (p.len() - 1) as u32;
        let at = idx.iter().position(|&i| i == tip).unwrap_or(0);
        idx[at] = copy;
        let locked = part_extremes(&p, &idx);
        // Same position, same part, same answer: both locked.
        assert!(locked[tip as usize] && locked[copy as usize]);
        // Unused vertices are never locked.
        p.push(Vec3::splat(100.0));
        let locked = part_extremes(&p, &idx);
        assert!(!locked[p.len() - 1]);
    }
}
