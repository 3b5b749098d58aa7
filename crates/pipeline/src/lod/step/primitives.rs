//! The plain build per material range ([`Plain::Primitives`](super::Plain::Primitives)):
//! gltfpack's `-si` as it meets a glTF export, each range a primitive of its own.

use super::{simplify_edges, Anchors, Candidate, Plain, Step, PLAIN_ERROR, SLOPPY_ERROR};
use meshopt::{SimplifyOptions, SimplifyVertex};

impl Step<'_> {
    /// [`super::Plain::Primitives`]: each material range alone on its own vertices (locks: the
    /// posed repair build's only), towards its share of the target within gltfpack's limit, 1% of
    /// the scene's largest material range's extent (or `max_error`, of the mesh's, if smaller).
    /// The error returned is of the mesh's extent, as the other builds' are.
    ///
    /// Where those first passes together remove more than the target asks (each range rounds its
    /// share down and some stop below it), the triangles to spare go back to the ranges that lost
    /// the most, largest error first: a range is kept whole when its removed triangles fit in what
    /// is left to spare, otherwise simplified again to its count plus the rest. gltfpack stops
    /// there; the target is a budget, and the spare triangles make the build closer.
    pub(super) fn run_primitives(
        &self,
        target_triangles: usize,
        max_error: f32,
        keep: &Anchors,
        kind: Plain,
    ) -> Candidate {
        let locks = self.flags(false, keep);
        let whole = meshopt::simplify_scale_decoder(&self.positions);
        let mut local_of = vec![u32::MAX; self.positions.len()];
        // Per-vertex attributes as `plain_settings` gave them (none when the source has no normals).
        let count = if self.attrs.len() == self.positions.len() * self.count {
            self.count
        } else {
            0
        };
        // The first passes (each range within the limit), in the order of the ranges simplified,
        // with each range's triangles and its extent over the mesh's, kept for the later builds:
        // `by_range` asks for the same ranges with the same targets each time.
        let mut firsts: Vec<(Vec<u32>, f32)> = Vec::new();
        let mut sizes: Vec<(usize, f32)> = Vec::new();
        // Each range's share rounded down, as gltfpack rounds each primitive's share of its ratio.
        let mut build =
            |pass: &Pass, firsts: &mut Vec<(Vec<u32>, f32)>, sizes: &mut Vec<(usize, f32)>| {
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
                    // gltfpack scales each primitive's limit by the largest primitive's extent over
                    // its own (`-sse` turns it off; on by default): 1% of the scene's largest
                    // material range, in model units.
                    let scaled = if own > 0.0 && self.scene_scale > own {
                        PLAIN_ERROR * self.scene_scale / own
                    } else {
                        PLAIN_ERROR
                    };
                    let (limit, rest) = if to_mesh > 0.0 {
                        (scaled.min(max_error / to_mesh), max_error / to_mesh)
                    } else {
                        (scaled, max_error)
                    };
                    let simplify = |from: &[u32], limit: f32, flags: SimplifyOptions, to: usize| {
                        simplify_edges(from, &positions, attrs, &local_locks, to, limit, flags)
                    };
                    let k = range;
                    range += 1;
                    let (out, err) = match pass {
                        Pass::First { deep } => {
                            let to = if *deep { 0 } else { target };
                            let first = simplify(&local, limit, self.flags, to);
                            firsts.push(first.clone());
                            if !*deep {
                                sizes.push((part.len() / 3, to_mesh));
                            }
                            first
                        }
                        // On to the range's share within `max_error`, as the other plain builds go
                        // on from gltfpack's limit, but without `Prune`: unlimited, it takes whole
                        // parts away to meet a count.
                        Pass::GoOn => {
                            let (out, err) = std::mem::take(&mut firsts[k]);
                            if out.len() > target * 3 && rest > limit {
                                let mut flags = self.flags;
                                flags.remove(SimplifyOptions::Prune);
                                let (more, e2) = simplify(&out, rest, flags, target);
                                (more, err + e2)
                            } else {
                                (out, err)
                            }
                        }
                        // gltfpack's `-sa`: the sloppy simplifier on the range alone (no locks)
                        // within 10% of its extent (not scaled), on to its share.
                        Pass::Sloppy => {
                            let (out, err) = std::mem::take(&mut firsts[k]);
                            if out.len() > target * 3 {
                                let mut more = 0.0f32;
                                let sloppy = meshopt::simplify_sloppy_decoder(
                                    &out,
                                    &positions,
                                    target * 3,
                                    SLOPPY_ERROR.min(rest),
                                    Some(&mut more),
                                );
                                (sloppy, err.max(more))
                            } else {
                                (out, err)
                            }
                        }
                        Pass::Spend(counts) => match counts.get(k).copied().flatten() {
                            Some(to) if to * 3 >= local.len() => (local, 0.0),
                            Some(to) => simplify(&local, limit, self.flags, to),
                            None => std::mem::take(&mut firsts[k]),
                        },
                    };
                    let out = out.into_iter().map(|v| used[v as usize]).collect();
                    (out, err * to_mesh)
                })
            };
        // gltfpack's build where it meets the target. Otherwise each range as far as the limit
        // lets it, where that meets the target (gltfpack's build at the ratio where the limit
        // stops every range); otherwise the ranges go on (only then: past the limit, every range
        // to its rounded-down share would add error for triangles the target does not ask for).
        // Not within the builder's slack of a triangle per range: a build that removed nothing
        // would be the closest.
        let first = build(&Pass::First { deep: false }, &mut firsts, &mut sizes);
        if kind == Plain::PrimitivesSloppy {
            return if first.indices.len() <= 3 * target_triangles {
                first
            } else {
                build(&Pass::Sloppy, &mut firsts, &mut sizes)
            };
        }
        let (made, mut passes) = if first.indices.len() <= 3 * target_triangles {
            (first.indices.len() / 3, firsts)
        } else {
            let mut deep = Vec::new();
            let far = build(&Pass::First { deep: true }, &mut deep, &mut sizes);
            if far.indices.len() > 3 * target_triangles {
                return build(&Pass::GoOn, &mut firsts, &mut sizes);
            }
            (far.indices.len() / 3, deep)
        };
        // The triangles to spare, to the ranges that lost the most first.
        let mut spare = target_triangles - made;
        let mut order: Vec<usize> = (0..passes.len())
            .filter(|&k| passes[k].0.len() / 3 < sizes[k].0)
            .collect();
        // The errors in the mesh's units.
        let error = |k: usize| passes[k].1 * sizes[k].1;
        order.sort_by(|&a, &b| error(b).total_cmp(&error(a)).then(a.cmp(&b)));
        let mut counts: Vec<Option<usize>> = vec![None; passes.len()];
        for k in order {
            if spare == 0 {
                break;
            }
            let kept = passes[k].0.len() / 3;
            let removed = sizes[k].0 - kept;
            counts[k] = Some(if removed <= spare {
                sizes[k].0
            } else {
                kept + spare
            });
            spare = spare.saturating_sub(removed);
        }
        build(&Pass::Spend(counts), &mut passes, &mut sizes)
    }
}

/// Which build [`Step::run_primitives`] makes of each range it simplifies.
enum Pass {
    /// gltfpack's: within the limit, towards the range's share (`deep`: as far as the limit lets
    /// it).
    First { deep: bool },
    /// The first pass, then on to the share within the budget.
    GoOn,
    /// The first pass, then the sloppy simplifier on to the share ([`Plain::PrimitivesSloppy`]).
    Sloppy,
    /// The first (or deep) pass, but for the ranges given a count (in the order of the ranges simplified):
    /// kept whole at their own count, else simplified again within the limit to that count.
    Spend(Vec<Option<usize>>),
}
