//! The plain build per material range ([`Plain::Primitives`](super::Plain::Primitives)):
//! gltfpack's `-si` as it meets a glTF export, each range a primitive of its own.

use super::{simplify_edges, Anchors, Candidate, Step, PLAIN_ERROR};
use meshopt::{SimplifyOptions, SimplifyVertex};

impl Step<'_> {
    /// [`super::Plain::Primitives`]: each material range alone on its own vertices (locks: the
    /// posed repair build's only), towards its share of the target within gltfpack's limit, 1% of the
    /// range's extent times the scene's largest mesh's extent over this mesh's (or `max_error`, of
    /// the mesh's, if smaller). The error returned is of the mesh's extent, as the other builds'
    /// are.
    pub(super) fn run_primitives(
        &self,
        target_triangles: usize,
        max_error: f32,
        keep: &Anchors,
    ) -> Candidate {
        let locks = self.flags(false, keep);
        let whole = meshopt::simplify_scale_decoder(&self.positions);
        // gltfpack scales each mesh's limit by the largest mesh's extent over its own (`-sse`
        // turns it off; on by default): 1% of the largest mesh, in model units.
        let scaled = if whole > 0.0 && self.scene_scale > whole {
            PLAIN_ERROR * self.scene_scale / whole
        } else {
            PLAIN_ERROR
        };
        let mut local_of = vec![u32::MAX; self.positions.len()];
        // Per-vertex attributes as `plain_settings` gave them (none when the source has no normals).
        let count = if self.attrs.len() == self.positions.len() * self.count {
            self.count
        } else {
            0
        };
        // The first passes (each range within the limit), in range order, kept for `go_on`'s
        // build: `by_range` asks for the same ranges with the same targets each time.
        let mut firsts: Vec<(Vec<u32>, f32)> = Vec::new();
        // Each range's share rounded down, as gltfpack rounds each primitive's share of its ratio;
        // `go_on`: ranges stopped above their share by the limit go on to it.
        let mut build = |go_on: bool| {
            let mut range = 0;
            self.by_range(target_triangles, f64::floor, |part, target| {
                // The range's vertices in first-use order, as gltfpack reindexes a primitive.
                let mut used: Vec<u32> = Vec::new();
                let local: Vec<u32> = part
                    .iter()
                    .map(|&v| {
                        if local_of[v as usize] == u32::MAX {
                            local_of[v as usize] = used.len() as u32;
                            used.push(v);
                        }
                        local_of[v as usize]
                    })
                    .collect();
                for &v in &used {
                    local_of[v as usize] = u32::MAX;
                }
                let positions: Vec<[f32; 3]> =
                    used.iter().map(|&v| self.positions[v as usize]).collect();
                let values: Vec<f32> = used
                    .iter()
                    .flat_map(|&v| {
                        let at = v as usize * count;
                        self.attrs[at..at + count].iter().copied()
                    })
                    .collect();
                let attrs = (&values[..], &self.weights[..count]);
                let local_locks: Vec<SimplifyVertex> =
                    used.iter().map(|&v| locks[v as usize]).collect();
                let own = meshopt::simplify_scale_decoder(&positions);
                let to_mesh = if whole > 0.0 { own / whole } else { 1.0 };
                let (limit, rest) = if to_mesh > 0.0 {
                    (scaled.min(max_error / to_mesh), max_error / to_mesh)
                } else {
                    (scaled, max_error)
                };
                let simplify = |from: &[u32], limit: f32, flags: SimplifyOptions| {
                    simplify_edges(from, &positions, attrs, &local_locks, target, limit, flags)
                };
                let (mut out, mut err) = if go_on {
                    std::mem::take(&mut firsts[range])
                } else {
                    let first = simplify(&local, limit, self.flags);
                    firsts.push(first.clone());
                    first
                };
                range += 1;
                // Then on to the range's share within `max_error` (`go_on`), as the other plain
                // builds go on from gltfpack's limit, but without `Prune`: unlimited, it takes
                // whole parts away to meet a count.
                if go_on && out.len() > target * 3 && rest > limit {
                    let mut flags = self.flags;
                    flags.remove(SimplifyOptions::Prune);
                    let (more, e2) = simplify(&out, rest, flags);
                    (out, err) = (more, err + e2);
                }
                let out = out.into_iter().map(|v| used[v as usize]).collect();
                (out, err * to_mesh)
            })
        };
        // gltfpack's build where it meets the target; otherwise the ranges go on (only then:
        // past the limit, every range to its rounded-down share would add error for triangles
        // the target does not ask for). Not within the builder's slack of a triangle per range:
        // a build that removed nothing would be the closest.
        let first = build(false);
        if first.indices.len() <= 3 * target_triangles {
            return first;
        }
        build(true)
    }
}
