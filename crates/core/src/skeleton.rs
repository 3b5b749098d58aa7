//! Skeletons: joint names, parents, bind pose and inverse bind matrices.

use crate::Transform;
use glam::Mat4;
use std::collections::HashMap;

/// Index of a joint in a [`Skeleton`]. Skeletons hold at most `u16::MAX` joints.
pub type JointIndex = u16;

/// Largest number of joints a skeleton may hold.
pub const MAX_JOINTS: usize = u16::MAX as usize;

/// A joint as an importer describes it, in any order, with its parent given by name.
#[derive(Debug, Clone, PartialEq)]
pub struct JointDesc {
    /// Unique joint name.
    pub name: String,
    /// Name of the parent joint; `None` for a root.
    pub parent: Option<String>,
    /// Bind-pose transform relative to the parent.
    pub bind_local: Transform,
    /// Inverse of the joint's model-space bind matrix, when the source gives one (glTF does).
    /// When `None`, it is computed from the bind-pose locals.
    pub inverse_bind: Option<Mat4>,
}

/// Why a skeleton could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SkeletonError {
    /// Two joints share a name.
    #[error("duplicate joint name {0:?}")]
    DuplicateName(String),
    /// A joint names a parent that does not exist.
    #[error("joint {joint:?} names parent {parent:?}, which does not exist")]
    MissingParent {
        /// The child.
        joint: String,
        /// The parent name that matched no joint.
        parent: String,
    },
    /// Following parents from these joints never reaches a root.
    #[error("the parents of joints {0:?} form a cycle")]
    Cycle(Vec<String>),
    /// More joints than [`MAX_JOINTS`].
    #[error("{0} joints; at most {MAX_JOINTS} are supported")]
    TooManyJoints(usize),
    /// A parent index that does not come before its child.
    #[error("joint {0} has parent {1}, which does not come before it")]
    ParentOrder(usize, usize),
    /// Arrays of different lengths.
    #[error("joint arrays have different lengths")]
    LengthMismatch,
    /// A bind transform or inverse bind matrix is NaN or infinite.
    #[error("joint {0:?} has a non-finite bind transform")]
    NonFinite(String),
}

/// A skeleton: joints ordered so that every parent comes before its children.
///
/// Built once and shared; it never changes while characters play on it.
#[derive(Debug, Clone, PartialEq)]
pub struct Skeleton {
    names: Vec<String>,
    parents: Vec<Option<JointIndex>>,
    bind_local: Vec<Transform>,
    inverse_bind: Vec<Mat4>,
    by_name: HashMap<String, JointIndex>,
    /// `bind_local` as blocks of four joints (see [`crate::soa`]), for the blend.
    bind_blocks: Vec<glam::Vec4>,
    /// [`level_order`] of `parents`.
    level_order: Vec<JointIndex>,
    /// `inverse_bind` with every entry broadcast (see [`crate::soa::Splats`]).
    inverse_bind_splats: Vec<crate::soa::Splats>,
}

impl Skeleton {
    /// Builds a skeleton from joints in any order.
    ///
    /// Joints are sorted so that each parent precedes its children; among joints at the same depth the
    /// input order is kept (roots first in input order, then a depth-first walk), so the result is
    /// deterministic. Returns the skeleton and, for each input joint, its index in the skeleton.
    pub fn from_unordered(
        joints: Vec<JointDesc>,
    ) -> Result<(Skeleton, Vec<JointIndex>), SkeletonError> {
        if joints.len() > MAX_JOINTS {
            return Err(SkeletonError::TooManyJoints(joints.len()));
        }
        let mut index_of: HashMap<&str, usize> = HashMap::with_capacity(joints.len());
        for (i, j) in joints.iter().enumerate() {
            if index_of.insert(j.name.as_str(), i).is_some() {
                return Err(SkeletonError::DuplicateName(j.name.clone()));
            }
        }
        let mut parent_of: Vec<Option<usize>> = Vec::with_capacity(joints.len());
        for j in &joints {
            match &j.parent {
                None => parent_of.push(None),
                Some(p) => match index_of.get(p.as_str()) {
                    Some(&pi) => parent_of.push(Some(pi)),
                    None => {
                        return Err(SkeletonError::MissingParent {
                            joint: j.name.clone(),
                            parent: p.clone(),
                        })
                    }
                },
            }
        }
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); joints.len()];
        for (i, p) in parent_of.iter().enumerate() {
            if let Some(p) = p {
                children[*p].push(i);
            }
        }
        // Depth-first from each root, in input order; joints never reached are on a cycle.
        let mut order: Vec<usize> = Vec::with_capacity(joints.len());
        let mut stack: Vec<usize> = Vec::new();
        for root in (0..joints.len()).filter(|&i| parent_of[i].is_none()) {
            stack.push(root);
            while let Some(j) = stack.pop() {
                order.push(j);
                stack.extend(children[j].iter().rev().copied());
            }
        }
        if order.len() != joints.len() {
            let mut reached = vec![false; joints.len()];
            for &j in &order {
                reached[j] = true;
            }
            let cycle = (0..joints.len())
                .filter(|&i| !reached[i])
                .map(|i| joints[i].name.clone())
                .collect();
            return Err(SkeletonError::Cycle(cycle));
        }
        let mut new_index = vec![0 as JointIndex; joints.len()];
        for (new, &old) in order.iter().enumerate() {
            new_index[old] = new as JointIndex;
        }
        let mut names = Vec::with_capacity(joints.len());
        let mut parents = Vec::with_capacity(joints.len());
        let mut bind_local = Vec::with_capacity(joints.len());
        let mut given_inverse = Vec::with_capacity(joints.len());
        let mut joints: Vec<Option<JointDesc>> = joints.into_iter().map(Some).collect();
        for &old in &order {
            let Some(j) = joints[old].take() else {
                continue;
            };
            parents.push(parent_of[old].map(|p| new_index[p]));
            bind_local.push(j.bind_local);
            given_inverse.push(j.inverse_bind);
            names.push(j.name);
        }
        let computed = inverse_bind_from_locals(&parents, &bind_local);
        let inverse_bind = given_inverse
            .into_iter()
            .zip(computed)
            .map(|(g, c)| g.unwrap_or(c))
            .collect();
        let skeleton = Skeleton::new(names, parents, bind_local, inverse_bind)?;
        Ok((skeleton, new_index))
    }

    /// Builds a skeleton from arrays already in parent-before-child order.
    pub fn new(
        names: Vec<String>,
        parents: Vec<Option<JointIndex>>,
        bind_local: Vec<Transform>,
        inverse_bind: Vec<Mat4>,
    ) -> Result<Skeleton, SkeletonError> {
        let n = names.len();
        if n > MAX_JOINTS {
            return Err(SkeletonError::TooManyJoints(n));
        }
        if parents.len() != n || bind_local.len() != n || inverse_bind.len() != n {
            return Err(SkeletonError::LengthMismatch);
        }
        let mut by_name = HashMap::with_capacity(n);
        for (i, name) in names.iter().enumerate() {
            if by_name.insert(name.clone(), i as JointIndex).is_some() {
                return Err(SkeletonError::DuplicateName(name.clone()));
            }
            if let Some(p) = parents[i] {
                if p as usize >= i {
                    return Err(SkeletonError::ParentOrder(i, p as usize));
                }
            }
            if !bind_local[i].is_finite() || !inverse_bind[i].is_finite() {
                return Err(SkeletonError::NonFinite(name.clone()));
            }
        }
        Ok(Skeleton {
            bind_blocks: crate::soa::from_transforms(&bind_local),
            level_order: level_order(&parents),
            inverse_bind_splats: inverse_bind.iter().map(crate::soa::splats).collect(),
            names,
            parents,
            bind_local,
            inverse_bind,
            by_name,
        })
    }

    /// The inverse bind matrices with every entry broadcast.
    pub(crate) fn inverse_bind_splats(&self) -> &[crate::soa::Splats] {
        &self.inverse_bind_splats
    }

    /// The joints level by level (see [`level_order`]).
    pub(crate) fn level_order(&self) -> &[JointIndex] {
        &self.level_order
    }

    /// The bind pose as blocks of four joints.
    pub(crate) fn bind_blocks(&self) -> &[glam::Vec4] {
        &self.bind_blocks
    }

    /// Number of joints.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// True when the skeleton has no joints.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// Joint names, in skeleton order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Parent of each joint (`None` for roots); every parent index is smaller than its child's.
    pub fn parents(&self) -> &[Option<JointIndex>] {
        &self.parents
    }

    /// Bind-pose local transforms.
    pub fn bind_local(&self) -> &[Transform] {
        &self.bind_local
    }

    /// Inverse bind matrices (model space to joint space at bind time).
    pub fn inverse_bind(&self) -> &[Mat4] {
        &self.inverse_bind
    }

    /// The index of the joint with this exact name.
    pub fn find(&self, name: &str) -> Option<JointIndex> {
        self.by_name.get(name).copied()
    }

    /// Indices of the joint and all its descendants, in skeleton order.
    pub fn subtree(&self, root: JointIndex) -> Vec<JointIndex> {
        let mut inside = vec![false; self.len()];
        let mut out = Vec::new();
        for i in 0..self.len() {
            let yes = i == root as usize || self.parents[i].is_some_and(|p| inside[p as usize]);
            if yes {
                inside[i] = true;
                out.push(i as JointIndex);
            }
        }
        out
    }
}

/// Model-space bind matrices inverted, from parent-ordered locals.
pub fn inverse_bind_from_locals(parents: &[Option<JointIndex>], locals: &[Transform]) -> Vec<Mat4> {
    let mut model: Vec<Mat4> = Vec::with_capacity(locals.len());
    for (i, local) in locals.iter().enumerate() {
        let m = match parents.get(i).copied().flatten() {
            Some(p) if (p as usize) < model.len() => model[p as usize] * local.to_mat4(),
            _ => local.to_mat4(),
        };
        model.push(m);
    }
    model.iter().map(|m| m.inverse()).collect()
}

/// The joints level by level (roots, then their children, ...), by index within a level: an order in
/// which every joint comes after its parent and joints that depend on each other are far apart.
pub(crate) fn level_order(parents: &[Option<JointIndex>]) -> Vec<JointIndex> {
    let mut depth = vec![0u32; parents.len()];
    for (i, p) in parents.iter().enumerate() {
        if let Some(p) = p.map(usize::from).filter(|&p| p < i) {
            depth[i] = depth[p] + 1;
        }
    }
    let mut order: Vec<JointIndex> = (0..parents.len() as JointIndex).collect();
    order.sort_by_key(|&j| (depth[j as usize], j));
    order
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn joint(name: &str, parent: Option<&str>, x: f32) -> JointDesc {
        JointDesc {
            name: name.into(),
            parent: parent.map(Into::into),
            bind_local: Transform::from_translation(Vec3::new(x, 0.0, 0.0)),
            inverse_bind: None,
        }
    }

    #[test]
    fn sorts_children_after_parents_and_maps_indices() {
        let (s, map) = Skeleton::from_unordered(vec![
            joint("hand", Some("arm"), 3.0),
            joint("arm", Some("root"), 2.0),
            joint("root", None, 1.0),
        ])
        .unwrap();
        assert_eq!(s.names(), ["root", "arm", "hand"]);
        assert_eq!(s.parents(), [None, Some(0), Some(1)]);
        assert_eq!(map, [2, 1, 0]);
        // The hand's bind position is 1+2+3 along x; its inverse bind moves it back to the origin.
        let p = s.inverse_bind()[2].transform_point3(Vec3::new(6.0, 0.0, 0.0));
        assert!(p.length() < 1e-6);
        assert_eq!(s.subtree(1), [1, 2]);
    }

    #[test]
    fn reports_duplicates_missing_parents_and_cycles() {
        let e = Skeleton::from_unordered(vec![joint("a", None, 0.0), joint("a", None, 0.0)]);
        assert_eq!(e.unwrap_err(), SkeletonError::DuplicateName("a".into()));
        let e = Skeleton::from_unordered(vec![joint("a", Some("zz"), 0.0)]);
        assert!(
            matches!(e.unwrap_err(), SkeletonError::MissingParent { parent, .. } if parent == "zz")
        );
        let e = Skeleton::from_unordered(vec![
            joint("r", None, 0.0),
            joint("a", Some("b"), 0.0),
            joint("b", Some("a"), 0.0),
        ]);
        assert_eq!(
            e.unwrap_err(),
            SkeletonError::Cycle(vec!["a".into(), "b".into()])
        );
    }

    #[test]
    fn several_roots_keep_input_order() {
        let (s, _) = Skeleton::from_unordered(vec![
            joint("b", None, 0.0),
            joint("a1", Some("a"), 0.0),
            joint("a", None, 0.0),
        ])
        .unwrap();
        assert_eq!(s.names(), ["b", "a", "a1"]);
    }
}
