//! Geometry measurements for LOD tests (point-to-triangle distance, surface samples, Hausdorff distance,
//! skinned positions), written independently of the simplifier and the runtime they check.

use sinew_core::glam::{Mat4, Vec3};
use sinew_core::{Clip, ClipBinding, Lod, Sampler, Skeleton};

/// Distance from a point to a triangle (closest point by region tests, Ericson's method).
pub fn point_triangle_distance(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (p - a).length();
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (p - b).length();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).length();
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (p - c).length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).length();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).length();
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (p - (a + ab * v + ac * w)).length()
}

/// Points sampled on a mesh: every vertex used by a triangle, every triangle's centroid and edge midpoints.
pub fn surface_samples(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut out = Vec::new();
    for t in indices.chunks_exact(3) {
        let (a, b, c) = (
            positions[t[0] as usize],
            positions[t[1] as usize],
            positions[t[2] as usize],
        );
        out.extend([
            a,
            b,
            c,
            (a + b + c) / 3.0,
            (a + b) * 0.5,
            (b + c) * 0.5,
            (c + a) * 0.5,
        ]);
    }
    out
}

/// Triangles bucketed in a uniform grid (by bounding box) for nearest-surface queries.
pub struct TriangleGrid {
    tris: Vec<[Vec3; 3]>,
    lo: Vec3,
    cell: f32,
    dims: [i32; 3],
    cells: Vec<Vec<u32>>,
}

impl TriangleGrid {
    /// Builds a grid of about two triangles per cell over the triangles' bounding box.
    pub fn new(positions: &[Vec3], indices: &[u32]) -> Self {
        let tris: Vec<[Vec3; 3]> = indices
            .chunks_exact(3)
            .map(|t| {
                [
                    positions[t[0] as usize],
                    positions[t[1] as usize],
                    positions[t[2] as usize],
                ]
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
        let size = (hi - lo).max(Vec3::splat(1e-6));
        let volume = size.x * size.y * size.z;
        let cell = (volume / (tris.len().max(1) as f32 / 2.0))
            .cbrt()
            .max(size.max_element() / 128.0);
        let dims = [
            ((size.x / cell) as i32 + 1).min(256),
            ((size.y / cell) as i32 + 1).min(256),
            ((size.z / cell) as i32 + 1).min(256),
        ];
        let mut cells = vec![Vec::new(); (dims[0] * dims[1] * dims[2]) as usize];
        let mut g = TriangleGrid {
            tris: Vec::new(),
            lo,
            cell,
            dims,
            cells: Vec::new(),
        };
        for (i, t) in tris.iter().enumerate() {
            let a = g.coord(t[0].min(t[1]).min(t[2]));
            let b = g.coord(t[0].max(t[1]).max(t[2]));
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        cells[g.flat([x, y, z])].push(i as u32);
                    }
                }
            }
        }
        g.tris = tris;
        g.cells = cells;
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

    /// Distance from `p` to the nearest triangle: cells are searched in growing shells around the
    /// point's cell until no unsearched cell can hold anything closer.
    pub fn distance(&self, p: Vec3) -> f32 {
        if self.tris.is_empty() {
            return f32::MAX;
        }
        // Distance from p to the grid's box: shells must reach past it.
        let hi = self.lo
            + Vec3::new(
                self.dims[0] as f32,
                self.dims[1] as f32,
                self.dims[2] as f32,
            ) * self.cell;
        let outside = (self.lo - p).max(p - hi).max(Vec3::ZERO).length();
        let c = self.coord(p);
        let max_r = self.dims.iter().copied().max().unwrap_or(1);
        let mut best = f32::MAX;
        for r in 0..=max_r {
            for z in (c[2] - r).max(0)..=(c[2] + r).min(self.dims[2] - 1) {
                for y in (c[1] - r).max(0)..=(c[1] + r).min(self.dims[1] - 1) {
                    for x in (c[0] - r).max(0)..=(c[0] + r).min(self.dims[0] - 1) {
                        let on_shell =
                            (x - c[0]).abs() == r || (y - c[1]).abs() == r || (z - c[2]).abs() == r;
                        if !on_shell {
                            continue;
                        }
                        for &t in &self.cells[self.flat([x, y, z])] {
                            let t = &self.tris[t as usize];
                            best = best.min(point_triangle_distance(p, t[0], t[1], t[2]));
                        }
                    }
                }
            }
            // Every cell not yet searched is at least r cells from p's cell (p's projection onto the
            // grid's box lies in that cell; p is `outside` further, at a right or obtuse angle).
            let reach = r as f32 * self.cell;
            if best <= (outside * outside + reach * reach).sqrt() {
                break;
            }
        }
        best
    }
}

/// Largest distance from any sample of `from` to the surface of `to`.
pub fn one_sided(from: &[Vec3], from_idx: &[u32], to: &[Vec3], to_idx: &[u32]) -> f32 {
    let grid = TriangleGrid::new(to, to_idx);
    surface_samples(from, from_idx)
        .iter()
        .map(|&p| grid.distance(p))
        .fold(0.0, f32::max)
}

/// The same as [`one_sided`] by brute force over every triangle (to check the grid).
pub fn one_sided_brute(from: &[Vec3], from_idx: &[u32], to: &[Vec3], to_idx: &[u32]) -> f32 {
    let tris: Vec<[Vec3; 3]> = to_idx
        .chunks_exact(3)
        .map(|t| [to[t[0] as usize], to[t[1] as usize], to[t[2] as usize]])
        .collect();
    surface_samples(from, from_idx)
        .iter()
        .map(|&p| {
            tris.iter()
                .map(|t| point_triangle_distance(p, t[0], t[1], t[2]))
                .fold(f32::MAX, f32::min)
        })
        .fold(0.0, f32::max)
}

/// Symmetric Hausdorff distance (sampled) between two triangle meshes.
pub fn hausdorff(a: &[Vec3], ai: &[u32], b: &[Vec3], bi: &[u32]) -> f32 {
    one_sided(a, ai, b, bi).max(one_sided(b, bi, a, ai))
}

/// Length of the bounding-box diagonal.
pub fn diagonal(positions: &[Vec3]) -> f32 {
    let lo = positions
        .iter()
        .fold(Vec3::splat(f32::MAX), |m, p| m.min(*p));
    let hi = positions
        .iter()
        .fold(Vec3::splat(f32::MIN), |m, p| m.max(*p));
    (hi - lo).length()
}

/// Linear blend skinning written out plainly for the tests: sum of w * (model * inverse bind) * p.
pub fn skin_positions(lod: &Lod, skeleton: &Skeleton, models: &[Mat4]) -> Vec<Vec3> {
    lod.positions
        .iter()
        .enumerate()
        .map(|(v, &p)| {
            let mut out = Vec3::ZERO;
            for k in 0..4 {
                let w = lod.weights[v][k];
                let j = lod.joints[v][k] as usize;
                out += (models[j] * skeleton.inverse_bind()[j]).transform_point3(p) * w;
            }
            out
        })
        .collect()
}

/// Model matrices from local transforms (parents first).
pub fn model_matrices(skeleton: &Skeleton, locals: &[sinew_core::Transform]) -> Vec<Mat4> {
    let mut m: Vec<Mat4> = Vec::new();
    for (i, l) in locals.iter().enumerate() {
        let x = match skeleton.parents()[i] {
            Some(p) => m[p as usize] * l.to_mat4(),
            None => l.to_mat4(),
        };
        m.push(x);
    }
    m
}

/// Model matrices of the skeleton posed by `clip` at time `t` (the runtime's sampler; the bind pose
/// where the clip drives nothing), for [`skin_positions`]. Panics when the clip cannot be sampled
/// (a test's setup error).
pub fn posed_models(skeleton: &Skeleton, clip: &Clip, t: f32) -> Vec<Mat4> {
    let binding = ClipBinding::new(clip, skeleton);
    let mut locals = skeleton.bind_local().to_vec();
    if let Err(e) = Sampler::new().sample(clip, &binding, skeleton, t, &mut locals) {
        panic!("sampling {:?} at {t}: {e}", clip.name());
    }
    model_matrices(skeleton, &locals)
}
