//! The joints of one side of a mapping: names, parents and which joints a motion animates.

use sinew_core::{Skeleton, TrackCurves};
use sinew_scene::SceneClip;
use std::collections::{HashMap, HashSet};

/// The joints of one side of a mapping: names, parents and which joints the motion animates.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointSet {
    /// A label for reports and mapping files, usually the file name. May be empty.
    pub label: String,
    pub(super) names: Vec<String>,
    pub(super) parents: Vec<Option<usize>>,
    pub(super) keyed: Vec<bool>,
}

impl JointSet {
    /// A joint set from names and parent indices; every joint counts as keyed.
    ///
    /// A parent index that is out of range, points at the joint itself or closes a cycle is treated as
    /// no parent, so arbitrary input never fails.
    pub fn new(names: Vec<String>, parents: Vec<Option<usize>>) -> Self {
        let n = names.len();
        let mut parents: Vec<Option<usize>> = (0..n)
            .map(|i| parents.get(i).copied().flatten())
            .enumerate()
            .map(|(i, p)| p.filter(|&p| p < n && p != i))
            .collect();
        // Break cycles: a joint whose parent chain does not reach a root within n steps loses its parent.
        for i in 0..n {
            let mut j = i;
            let mut steps = 0;
            while let Some(p) = parents[j] {
                j = p;
                steps += 1;
                if steps > n {
                    parents[i] = None;
                    break;
                }
            }
        }
        JointSet {
            label: String::new(),
            names,
            parents,
            keyed: vec![true; n],
        }
    }

    /// A flat joint set (no parents), every joint keyed. Chains are then ordered by input order.
    pub fn from_names<S: AsRef<str>>(names: &[S]) -> Self {
        let names: Vec<String> = names.iter().map(|s| s.as_ref().to_string()).collect();
        let parents = vec![None; names.len()];
        JointSet::new(names, parents)
    }

    /// The joints of a skeleton; every joint counts as keyed (use this for rigs).
    pub fn from_skeleton(skeleton: &Skeleton) -> Self {
        let parents = skeleton
            .parents()
            .iter()
            .map(|p| p.map(usize::from))
            .collect();
        JointSet::new(skeleton.names().to_vec(), parents)
    }

    /// The joints of a motion's skeleton, keyed where some clip's track for that joint changes over time
    /// (a joint without a track, or whose keys are all equal, is unkeyed: CMU `LHipJoint`).
    pub fn from_skeleton_and_clips(skeleton: &Skeleton, clips: &[SceneClip]) -> Self {
        let mut set = JointSet::from_skeleton(skeleton);
        let mut animated: HashSet<&str> = HashSet::new();
        for clip in clips {
            for track in &clip.tracks {
                if track_varies(track) {
                    animated.insert(track.joint.as_str());
                }
            }
        }
        set.keyed = set
            .names
            .iter()
            .map(|n| animated.contains(n.as_str()))
            .collect();
        set
    }

    /// Replaces the keyed flags (missing entries count as keyed).
    pub fn with_keyed(mut self, keyed: &[bool]) -> Self {
        self.keyed = (0..self.names.len())
            .map(|i| keyed.get(i).copied().unwrap_or(true))
            .collect();
        self
    }

    /// Sets the label.
    pub fn with_label(mut self, label: impl Into<String>) -> Self {
        self.label = label.into();
        self
    }

    /// Joint names.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Parent of each joint.
    pub fn parents(&self) -> &[Option<usize>] {
        &self.parents
    }

    /// Whether each joint is animated.
    pub fn keyed(&self) -> &[bool] {
        &self.keyed
    }

    /// Index of the first joint with this exact name.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Depth of every joint (roots 0), in O(n): each chain is walked once.
    pub(super) fn depths(&self) -> Vec<usize> {
        let n = self.names.len();
        let mut depth: Vec<Option<usize>> = vec![None; n];
        let mut path = Vec::new();
        for i in 0..n {
            let mut j = i;
            // Walk up to a joint of known depth or a root (parents were made acyclic in `new`).
            let base = loop {
                if let Some(d) = depth[j] {
                    break d + 1;
                }
                path.push(j);
                match self.parents.get(j).copied().flatten() {
                    Some(p) if path.len() <= n => j = p,
                    _ => break 0,
                }
            };
            for (k, &j) in path.iter().rev().enumerate() {
                depth[j] = Some(base + k);
            }
            path.clear();
        }
        depth.into_iter().map(|d| d.unwrap_or(0)).collect()
    }

    pub(super) fn index_by_name(&self) -> HashMap<&str, usize> {
        let mut m = HashMap::with_capacity(self.names.len());
        for (i, n) in self.names.iter().enumerate() {
            m.entry(n.as_str()).or_insert(i);
        }
        m
    }
}

/// True when any curve of the track holds two different values.
pub(super) fn track_varies(track: &TrackCurves) -> bool {
    const EPS: f32 = 1e-5;
    let t = &track.translation.values;
    let s = &track.scale.values;
    let r = &track.rotation.values;
    let v3 = |v: &[sinew_core::glam::Vec3]| {
        v.first()
            .is_some_and(|a| v.iter().any(|b| (*b - *a).abs().max_element() > EPS))
    };
    let rot = r.first().is_some_and(|a| {
        r.iter()
            .any(|b| 1.0 - a.normalize().dot(b.normalize()).abs() > EPS * EPS)
    });
    v3(t) || v3(s) || rot
}
