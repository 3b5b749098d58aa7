//! Geometry helpers for the LOD tests, written independently of the simplifier.
#![allow(dead_code)]

use sinew_core::glam::{Mat4, Vec3};
use sinew_core::{Lod, Skeleton};

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

/// Largest distance from any sample of `from` to the surface of `to`.
pub fn one_sided(from: &[Vec3], from_idx: &[u32], to: &[Vec3], to_idx: &[u32]) -> f32 {
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
