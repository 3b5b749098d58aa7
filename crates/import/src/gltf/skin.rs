//! The node graph and skins: node transforms, parents, which nodes are joints, and the skeleton a skin
//! becomes (non-joint ancestors baked into the root).

use super::document::{at, floats, Loaded};
use crate::ImportError;
use glam::{Mat4, Quat, Vec3};
use sinew_core::{JointDesc, Skeleton, Transform};
use sinew_scene::Diagnostic;
use std::collections::{HashMap, HashSet};

/// The node transform as TRS, with the residual when a matrix is not a clean TRS.
pub(super) fn node_trs(node: &gltf::Node<'_>) -> (Transform, Option<(f32, bool)>) {
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
pub(super) fn decompose(m: Mat4) -> (Transform, f32, bool) {
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
pub(super) fn parents(file: &str, doc: &gltf::Document) -> Result<Vec<Option<usize>>, ImportError> {
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
pub(super) fn node_names(doc: &gltf::Document) -> Vec<String> {
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

pub(super) struct Graph {
    pub(super) parent: Vec<Option<usize>>,
    pub(super) local: Vec<Transform>,
    pub(super) world: Vec<Mat4>,
    pub(super) names: Vec<String>,
}

pub(super) fn graph(
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
pub(super) struct Rig {
    pub(super) skeleton: Skeleton,
    /// Skeleton joint index of each node that is a joint.
    pub(super) joint_of_node: HashMap<usize, u16>,
    /// Skeleton index of each entry of `skin.joints` (empty for a node skeleton).
    pub(super) skin_map: Vec<u16>,
    /// Matrix applied before the node's own TRS, per joint node, when not the identity.
    pub(super) pre: HashMap<usize, Mat4>,
    /// The chosen skin's index.
    pub(super) skin: Option<usize>,
}

pub(super) fn is_identity(m: &Mat4) -> bool {
    m.abs_diff_eq(Mat4::IDENTITY, 1e-7)
}

/// glTF's inverse bind matrices are affine (last row 0, 0, 0, 1); skinning reads that row (it
/// scales the parent's translation in the skinning matrix), so a matrix with another last row
/// would skin its vertices by a projective transform no runtime draws. Such rows are set to
/// (0, 0, 0, 1), with a warning naming the matrices (`gltf-ibm-not-affine`). `m`: column-major
/// matrices, 16 floats each.
fn affine_inverse_binds(m: &mut [f32], path: &str) -> Option<Diagnostic> {
    const TOLERANCE: f32 = 1e-5;
    const AFFINE: [f32; 4] = [0.0, 0.0, 0.0, 1.0];
    let mut fixed = Vec::new();
    for (k, a) in m.chunks_exact_mut(16).enumerate() {
        let row = [a[3], a[7], a[11], a[15]];
        if row
            .iter()
            .zip(AFFINE)
            .any(|(x, w)| (x - w).abs() > TOLERANCE)
        {
            fixed.push(format!(
                "{k} ({}, {}, {}, {})",
                row[0], row[1], row[2], row[3]
            ));
            [a[3], a[7], a[11], a[15]] = AFFINE;
        }
    }
    if fixed.is_empty() {
        return None;
    }
    let count = fixed.len();
    fixed.truncate(8);
    let more = if count > 8 {
        format!(" ({count} in all)")
    } else {
        String::new()
    };
    Some(
        Diagnostic::warning(
            "gltf-ibm-not-affine",
            format!(
                "{path}: matrices {}{more} have a last row other than (0, 0, 0, 1), which glTF \
                 requires; read with (0, 0, 0, 1)",
                fixed.join(", ")
            ),
        )
        .with_figure("matrices", count as f64),
    )
}

pub(super) fn build_rig(
    file: &str,
    l: &Loaded,
    g: &Graph,
    joints: &[usize],
    skin: Option<gltf::Skin<'_>>,
    diagnostics: &mut Vec<Diagnostic>,
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
            let mut v = v;
            if let Some(d) = affine_inverse_binds(&mut v[..joints.len() * 16], &p) {
                diagnostics.push(d);
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

#[cfg(test)]
mod tests {
    use super::affine_inverse_binds;

    #[test]
    fn inverse_bind_matrices_get_an_affine_last_row_with_a_warning() {
        // Two column-major matrices: a translation by (5, 6, 7), affine; then the same with the
        // last row (1, 2, 3, 4) (the Khronos validator's invalid_ibm.gltf has this one).
        let affine: [f32; 16] = [
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 5.0, 6.0, 7.0, 1.0,
        ];
        let mut m = affine.to_vec();
        let mut bad = affine;
        [bad[3], bad[7], bad[11], bad[15]] = [1.0, 2.0, 3.0, 4.0];
        m.extend(bad);
        let d = affine_inverse_binds(&mut m, "skins[0].inverseBindMatrices").unwrap();
        assert_eq!(d.code, "gltf-ibm-not-affine");
        assert!(
            d.message
                .starts_with("skins[0].inverseBindMatrices: matrices 1 (1, 2, 3, 4) have"),
            "{}",
            d.message
        );
        // Both are now the affine translation; the first was not touched.
        assert_eq!(m[..16], affine);
        assert_eq!(m[16..], affine);
        // Nothing to say about affine matrices, including a last row within 1e-5.
        let mut near = affine;
        near[15] = 1.0 + 4e-6;
        assert!(affine_inverse_binds(&mut near, "p").is_none());
        assert_eq!(near[15], 1.0 + 4e-6);
    }
}
