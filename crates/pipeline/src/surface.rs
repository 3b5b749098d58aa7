//! Distances between triangle surfaces: point to triangle, nearest triangle through a uniform grid,
//! and the sampled symmetric Hausdorff distance between two meshes. The LOD builder reports it as a
//! floor under its error (so the reported error bounds what a measurement finds) and the previews
//! print it under each LOD.
//!
//! `crates/testdata/src/geometry.rs` has its own point-to-triangle distance and grid on purpose: the
//! tests measure LODs with code that is not the code under test (and check that grid against a
//! brute-force scan).

use sinew_core::glam::Vec3;

/// Distance from `p` to triangle `abc` (closest point by Voronoi regions, after Ericson).
pub fn point_triangle_distance(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f32 {
    point_triangle_distance_squared(p, a, b, c).sqrt()
}

/// The square of [`point_triangle_distance`], whose square root it is bit for bit (a length is
/// the square root of the dot product, and the square root keeps order, so the nearest of three
/// corners is the root of the least square): a search compares squares and takes one root per
/// nearer triangle.
pub fn point_triangle_distance_squared(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.length_squared();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.length_squared();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).length_squared();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.length_squared();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).length_squared();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).length_squared();
    }
    let denom = va + vb + vc;
    if denom == 0.0 || !denom.is_finite() {
        return ap
            .length_squared()
            .min(bp.length_squared())
            .min(cp.length_squared());
    }
    let (v, w) = (vb / denom, vc / denom);
    (p - (a + ab * v + ac * w)).length_squared()
}

/// Triangles bucketed in a uniform grid (by bounding box) for nearest-surface queries.
pub struct TriangleGrid {
    tris: Vec<[Vec3; 3]>,
    /// Per triangle: its bounding box.
    boxes: Vec<(Vec3, Vec3)>,
    lo: Vec3,
    cell: f32,
    dims: [i32; 3],
    /// Per cell, the range of its entries in `entries` (cells flattened x fastest).
    starts: Vec<u32>,
    entries: Vec<u32>,
}

impl TriangleGrid {
    /// A grid of about two triangles per cell over the triangles' bounding box (at most 128 cells a
    /// side). Triangles naming a vertex past `positions` are left out.
    pub fn new(positions: &[Vec3], indices: &[u32]) -> TriangleGrid {
        let tris: Vec<[Vec3; 3]> = indices
            .chunks_exact(3)
            .filter_map(|t| {
                Some([
                    *positions.get(t[0] as usize)?,
                    *positions.get(t[1] as usize)?,
                    *positions.get(t[2] as usize)?,
                ])
            })
            .collect();
        let mut lo = Vec3::splat(f32::MAX);
        let mut hi = Vec3::splat(f32::MIN);
        for t in &tris {
            for p in t {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
        if tris.is_empty() || !(lo.is_finite() && hi.is_finite()) {
            return TriangleGrid {
                tris: Vec::new(),
                boxes: Vec::new(),
                lo: Vec3::ZERO,
                cell: 1.0,
                dims: [1, 1, 1],
                starts: vec![0, 0],
                entries: Vec::new(),
            };
        }
        let size = (hi - lo).max(Vec3::splat(1e-6));
        // Cells about the mean edge: a surface fills few cells of its box, so a cell size
        // from the box's volume would put dozens of triangles in each cell it crosses.
        let edges: f32 = tris
            .iter()
            .map(|t| (t[1] - t[0]).length() + (t[2] - t[1]).length() + (t[0] - t[2]).length())
            .sum();
        let mean_edge = edges / (3 * tris.len()) as f32;
        let cell = mean_edge.max(size.max_element() / 128.0).max(1e-6);
        let dims = [
            ((size.x / cell) as i32 + 1).min(128),
            ((size.y / cell) as i32 + 1).min(128),
            ((size.z / cell) as i32 + 1).min(128),
        ];
        let mut g = TriangleGrid {
            tris: Vec::new(),
            boxes: Vec::new(),
            lo,
            cell,
            dims,
            starts: Vec::new(),
            entries: Vec::new(),
        };
        let count = (dims[0] * dims[1] * dims[2]) as usize;
        let boxes: Vec<(Vec3, Vec3)> = tris
            .iter()
            .map(|t| (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2])))
            .collect();
        let spans: Vec<([i32; 3], [i32; 3])> = boxes
            .iter()
            .map(|&(lo, hi)| (g.coord(lo), g.coord(hi)))
            .collect();
        // Two passes (count, then fill) so every cell's list is one slice of `entries`.
        let mut starts = vec![0u32; count + 1];
        for (a, b) in &spans {
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        starts[g.flat([x, y, z]) + 1] += 1;
                    }
                }
            }
        }
        for i in 0..count {
            starts[i + 1] += starts[i];
        }
        let mut fill = starts.clone();
        let mut entries = vec![0u32; starts[count] as usize];
        for (i, (a, b)) in spans.iter().enumerate() {
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        let c = g.flat([x, y, z]);
                        entries[fill[c] as usize] = i as u32;
                        fill[c] += 1;
                    }
                }
            }
        }
        g.boxes = boxes;
        g.tris = tris;
        g.starts = starts;
        g.entries = entries;
        g
    }

    fn coord(&self, p: Vec3) -> [i32; 3] {
        let c = (p - self.lo) / self.cell;
        [
            (c.x as i32).clamp(0, self.dims[0] - 1),
            (c.y as i32).clamp(0, self.dims[1] - 1),
            (c.z as i32).clamp(0, self.dims[2] - 1),
        ]
    }

    fn flat(&self, c: [i32; 3]) -> usize {
        ((c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]) as usize
    }

    /// Distance from `p` to the nearest triangle (infinity without triangles): cells are searched
    /// in growing shells around the point's cell until no unsearched cell can hold anything closer.
    pub fn distance(&self, p: Vec3) -> f32 {
        self.distance_above(p, -1.0)
    }

    /// [`TriangleGrid::distance`] when it is above `floor`; otherwise some distance at most `floor`
    /// (the search stops at the first triangle that close). What a maximum over many points needs:
    /// most points lie near the surface and stop at their first triangle.
    pub fn distance_above(&self, p: Vec3, floor: f32) -> f32 {
        self.nearest_above(p, floor, u32::MAX).0
    }

    /// [`TriangleGrid::distance_above`] that measures triangle `hint` first (an index into the
    /// triangles given; any other value: none), and also returns the triangle of the distance it
    /// returns (`u32::MAX` without triangles). A good hint (the nearest triangle of a nearby
    /// point, or of the same point under another pose of the same triangles) ends the search at
    /// once when it is within `floor`, and otherwise bounds it from the start; the distance
    /// returned is the same with any hint where it is above `floor`.
    pub fn nearest_above(&self, p: Vec3, floor: f32, hint: u32) -> (f32, u32) {
        if self.tris.is_empty() {
            return (f32::INFINITY, u32::MAX);
        }
        let mut best = f32::INFINITY;
        let mut best_squared = f32::INFINITY;
        let mut nearest = u32::MAX;
        if let Some(t) = self.tris.get(hint as usize) {
            best_squared = point_triangle_distance_squared(p, t[0], t[1], t[2]);
            best = best_squared.sqrt();
            nearest = hint;
            if best <= floor {
                return (best, nearest);
            }
        }
        let hi = self.lo
            + Vec3::new(
                self.dims[0] as f32,
                self.dims[1] as f32,
                self.dims[2] as f32,
            ) * self.cell;
        // How far p lies outside the grid's box: every cell is at least that far.
        let outside = (self.lo - p).max(p - hi).max(Vec3::ZERO).length();
        let c = self.coord(p);
        let max_r = self.dims.iter().copied().max().unwrap_or(1);
        // The triangles of one cell (those whose box is nearer than the best so far); true when
        // the search may stop (a triangle within `floor`). `best`: the distance, its triangle and
        // the distance's square (a triangle whose square is not below it is not nearer: no root).
        let visit = |x: i32, y: i32, z: i32, best: &mut (f32, u32, f32)| -> bool {
            let cell = self.flat([x, y, z]);
            let (s, e) = (self.starts[cell] as usize, self.starts[cell + 1] as usize);
            for &t in &self.entries[s..e] {
                let (lo, hi) = self.boxes[t as usize];
                // The triangle's box is a cheap lower bound of its distance.
                if (lo - p).max(p - hi).max(Vec3::ZERO).length_squared() >= best.0 * best.0 {
                    continue;
                }
                let tri = &self.tris[t as usize];
                let squared = point_triangle_distance_squared(p, tri[0], tri[1], tri[2]);
                if squared < best.2 {
                    let d = squared.sqrt();
                    if d < best.0 {
                        *best = (d, t, squared);
                        if d <= floor {
                            return true;
                        }
                    }
                }
            }
            false
        };
        let mut best = (best, nearest, best_squared);
        for r in 0..=max_r {
            for z in (c[2] - r).max(0)..=(c[2] + r).min(self.dims[2] - 1) {
                for y in (c[1] - r).max(0)..=(c[1] + r).min(self.dims[1] - 1) {
                    let on_yz = (z - c[2]).abs() == r || (y - c[1]).abs() == r;
                    if on_yz {
                        for x in (c[0] - r).max(0)..=(c[0] + r).min(self.dims[0] - 1) {
                            if visit(x, y, z, &mut best) {
                                return (best.0, best.1);
                            }
                        }
                    } else {
                        // Inside the shell only the two x ends belong to it (r > 0 here: at
                        // r = 0 every cell is on the shell).
                        for x in [c[0] - r, c[0] + r] {
                            if x >= 0 && x < self.dims[0] && visit(x, y, z, &mut best) {
                                return (best.0, best.1);
                            }
                        }
                    }
                }
            }
            // Every cell not searched yet is at least r cells from p's cell.
            let reach = r as f32 * self.cell;
            if best.0 <= (outside * outside + reach * reach).sqrt() {
                break;
            }
        }
        (best.0, best.1)
    }
}

/// The points of a mesh a distance is measured at: every vertex a triangle uses, every triangle's
/// centroid and its three edge midpoints (the sample set of the tests and of
/// `../shared/peers/lod_hausdorff.py` without its random points).
pub fn sample_points(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut used = vec![false; positions.len()];
    let mut out = Vec::with_capacity(positions.len() + indices.len() / 3 * 4);
    for t in indices.chunks_exact(3) {
        let (Some(&a), Some(&b), Some(&c)) = (
            positions.get(t[0] as usize),
            positions.get(t[1] as usize),
            positions.get(t[2] as usize),
        ) else {
            continue;
        };
        for &i in t {
            used[i as usize] = true;
        }
        out.extend([
            (a + b + c) / 3.0,
            (a + b) * 0.5,
            (b + c) * 0.5,
            (c + a) * 0.5,
        ]);
    }
    out.extend(
        positions
            .iter()
            .zip(&used)
            .filter(|(_, &u)| u)
            .map(|(p, _)| *p),
    );
    out
}

/// The vertices that a triangle uses, each once, in index order of first use.
pub fn used_vertices(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut seen = vec![false; positions.len()];
    let mut out = Vec::new();
    for &i in indices {
        if let Some(s) = seen.get_mut(i as usize) {
            if !*s {
                *s = true;
                out.push(positions[i as usize]);
            }
        }
    }
    out
}

/// The largest distance from a sample of mesh `from` ([`sample_points`]) to the surface of `to`
/// (0 when `from` has no triangles, infinity when only `to` has none).
pub fn one_sided(from: (&[Vec3], &[u32]), to: (&[Vec3], &[u32])) -> f32 {
    farthest(
        &sample_points(from.0, from.1),
        &TriangleGrid::new(to.0, to.1),
    )
}

/// The largest distance from one of `points` to the grid's triangles.
pub fn farthest(points: &[Vec3], grid: &TriangleGrid) -> f32 {
    farthest_above(points, grid, 0.0)
}

/// [`farthest`] when it is above `floor`; otherwise `floor` (a caller to whom distances up to
/// `floor` make no difference lets most points stop at their first triangle within it).
pub fn farthest_above(points: &[Vec3], grid: &TriangleGrid, floor: f32) -> f32 {
    points
        .iter()
        .fold(sparse_floor(points, grid, floor), |m, &p| {
            m.max(grid.distance_above(p, m))
        })
}

/// The largest distance of every 61st point, at least `floor`: a pass that raises the floor first,
/// so that the full pass stops early at most points.
fn sparse_floor(points: &[Vec3], grid: &TriangleGrid, floor: f32) -> f32 {
    points
        .iter()
        .step_by(61)
        .fold(floor, |m, &p| m.max(grid.distance_above(p, m)))
}

/// Every point farther than `threshold` from the grid's triangles, with its exact distance, in the
/// order of `points`, and the largest distance as [`farthest_above`] with `floor` gives it: one
/// pass for both (each point's search stops at the lower of the two floors).
pub fn beyond_and_farthest(
    points: &[Vec3],
    grid: &TriangleGrid,
    threshold: f32,
    floor: f32,
) -> (Vec<(usize, f32)>, f32) {
    let mut beyond = Vec::new();
    let mut largest = sparse_floor(points, grid, floor);
    for (i, &p) in points.iter().enumerate() {
        let d = grid.distance_above(p, threshold.min(largest));
        if d > threshold {
            beyond.push((i, d));
        }
        largest = largest.max(d);
    }
    (beyond, largest)
}

/// The sampled symmetric Hausdorff distance: the larger of the two [`one_sided`] distances.
pub fn hausdorff(a: (&[Vec3], &[u32]), b: (&[Vec3], &[u32])) -> f32 {
    one_sided(a, b).max(one_sided(b, a))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_triangle_distance_by_region() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        assert_eq!(
            point_triangle_distance(Vec3::new(0.25, 0.25, 2.0), a, b, c),
            2.0
        );
        assert_eq!(
            point_triangle_distance(Vec3::new(-3.0, 0.0, 4.0), a, b, c),
            5.0
        );
        let d = point_triangle_distance(Vec3::new(1.0, 1.0, 0.0), a, b, c);
        assert!((d - 0.5f32.sqrt()).abs() < 1e-6, "{d}");
        assert_eq!(
            point_triangle_distance(Vec3::new(0.5, -2.0, 0.0), a, b, c),
            2.0
        );
    }

    #[test]
    fn the_grid_finds_the_nearest_triangle_as_a_scan_does() {
        // A bumpy 12 x 12 grid of quads and points above, below and beside it.
        let mut p = Vec::new();
        let mut idx = Vec::new();
        for i in 0..13 {
            for k in 0..13 {
                let (x, z) = (i as f32, k as f32);
                p.push(Vec3::new(x, (x * 0.7).sin() * (z * 0.5).cos(), z));
            }
        }
        for i in 0..12u32 {
            for k in 0..12u32 {
                let a = i * 13 + k;
                idx.extend([a, a + 1, a + 13, a + 1, a + 14, a + 13]);
            }
        }
        let grid = TriangleGrid::new(&p, &idx);
        let scan = |q: Vec3| {
            idx.chunks_exact(3)
                .map(|t| {
                    point_triangle_distance(q, p[t[0] as usize], p[t[1] as usize], p[t[2] as usize])
                })
                .fold(f32::INFINITY, f32::min)
        };
        let mut s = 0x1234_5678u32;
        let mut rnd = || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            (s % 10_000) as f32 / 10_000.0
        };
        let ntris = idx.len() as u32 / 3;
        for n in 0..300u32 {
            let q = Vec3::new(rnd() * 20.0 - 4.0, rnd() * 6.0 - 3.0, rnd() * 20.0 - 4.0);
            assert_eq!(grid.distance(q), scan(q), "{q}");
            // Any hint (a triangle, or none past the end) gives the exact distance above the
            // floor and names the triangle at that distance; within the floor, the hint when it
            // is within it.
            let hint = (n * 37) % (ntris + 5);
            let (d, t) = grid.nearest_above(q, -1.0, hint);
            assert_eq!(d, scan(q), "{q} hint {hint}");
            let tri = &idx[3 * t as usize..3 * t as usize + 3];
            let corner = |i: usize| p[tri[i] as usize];
            assert_eq!(
                point_triangle_distance(q, corner(0), corner(1), corner(2)),
                d
            );
            if hint < ntris {
                let h = &idx[3 * hint as usize..3 * hint as usize + 3];
                let dh = point_triangle_distance(
                    q,
                    p[h[0] as usize],
                    p[h[1] as usize],
                    p[h[2] as usize],
                );
                assert_eq!(grid.nearest_above(q, dh, hint), (dh, hint));
                assert!(grid.nearest_above(q, dh * 0.5, hint).0 <= dh);
            }
        }
        // A mesh against itself: no distance; against a copy moved 0.5 up: 0.5 at most.
        // (Centroids lie on their triangle up to rounding.)
        assert!(hausdorff((&p, &idx), (&p, &idx)) < 1e-5);
        let up: Vec<Vec3> = p.iter().map(|v| *v + Vec3::Y * 0.5).collect();
        let h = hausdorff((&p, &idx), (&up, &idx));
        assert!(h > 0.3 && h <= 0.5 + 1e-5, "{h}");
        assert_eq!(
            TriangleGrid::new(&p, &[]).distance(Vec3::ZERO),
            f32::INFINITY
        );
        // The maximum with early exits is the maximum of the full searches.
        let pts: Vec<Vec3> = (0..200)
            .map(|_| Vec3::new(rnd() * 14.0, rnd() * 2.0 - 1.0, rnd() * 14.0))
            .collect();
        let full = pts.iter().map(|&q| scan(q)).fold(0.0, f32::max);
        assert_eq!(farthest(&pts, &grid), full);
        // With a floor: the same maximum below it, the floor itself above it.
        assert_eq!(farthest_above(&pts, &grid, full * 0.5), full);
        assert_eq!(farthest_above(&pts, &grid, full * 2.0), full * 2.0);
        // One pass for the points beyond a threshold and the maximum: the points a scan puts
        // beyond it, in order, with their exact distances, and the same maximum as alone.
        let scans: Vec<f32> = pts.iter().map(|&q| scan(q)).collect();
        for (threshold, floor) in [
            (full * 0.5, 0.0),
            (full * 0.8, full * 0.3),
            (full * 0.2, full * 0.9),
        ] {
            let (beyond, largest) = beyond_and_farthest(&pts, &grid, threshold, floor);
            let expected: Vec<(usize, f32)> = scans
                .iter()
                .enumerate()
                .filter(|(_, &d)| d > threshold)
                .map(|(i, &d)| (i, d))
                .collect();
            assert!(!expected.is_empty() && expected.len() < pts.len());
            assert_eq!(beyond, expected, "threshold {threshold}");
            assert_eq!(largest, farthest_above(&pts, &grid, floor));
            assert_eq!(largest, full.max(floor));
        }
    }
}
