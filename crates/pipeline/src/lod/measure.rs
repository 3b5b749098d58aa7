//! A simplification step's result measured against LOD 0 (the distance the LOD builder reports
//! as a floor under its error and compares candidate builds by), and the vertices the repair
//! build locks.

use crate::lod_parts::position_ids;
use crate::surface::{sample_points, TriangleGrid};
use rayon::prelude::*;
use sinew_core::glam::Vec3;
use sinew_core::Lod;
use sinew_scene::Mesh;

/// At most this many far LOD 0 vertices are locked when a step is built again.
pub(super) const REPAIR_VERTICES: usize = 16;

/// A result's distances to LOD 0, in model units.
pub(super) struct Measured {
    /// The distance of LOD 0's farthest vertex from the result's surface: exact when larger than
    /// `added`, otherwise some value up to `added` (which then decides the distance alone).
    pub(super) lost: f32,
    /// The distance of the result's farthest vertex, centroid or edge midpoint from LOD 0's surface.
    pub(super) added: f32,
    /// The result's triangles, for [`far_vertices`].
    grid: TriangleGrid,
    /// Per LOD 0 point: the triangle of `grid` where its search for `lost` ended, for
    /// [`far_vertices`]' searches to start at.
    hints: Vec<u32>,
}

impl Measured {
    /// The symmetric distance: the larger side (exact).
    pub(super) fn distance(&self) -> f32 {
        self.lost.max(self.added)
    }
}

/// The largest distance from `points` to `grid`'s triangles, as far as it is above `floor`
/// (otherwise `floor` or less); `None` as soon as one is at least `limit`. A sparse pass first
/// raises the running maximum, so that most points stop at their first triangle.
///
/// Past [`FARTHEST_CHUNK`] points the full pass runs in chunks on rayon, each from the sparse
/// pass's maximum: the result is the exact maximum either way (or `floor`), so it does not depend
/// on the chunks or the thread count, and a LOD chain on the critical path of a convert can use a
/// core the clip encoder has left.
fn farthest(points: &[Vec3], grid: &TriangleGrid, floor: f32, limit: f32) -> Option<f32> {
    farthest_hinted(points, grid, floor, limit, &mut [])
}

/// [`farthest`] with `hints`: per point, a triangle of `grid` to measure first, set to the
/// triangle each point's search ended on (for the same points against the same triangles under
/// another pose: most points stop at their hint). Any hints, or none (`hints` not one per
/// point), give the same result.
fn farthest_hinted(
    points: &[Vec3],
    grid: &TriangleGrid,
    floor: f32,
    limit: f32,
    hints: &mut [u32],
) -> Option<f32> {
    let hinted = hints.len() == points.len();
    let hints = if hinted { hints } else { &mut [] };
    let m = running_max(grid, floor, limit, points, hints, 61)?;
    if points.len() <= FARTHEST_CHUNK {
        return running_max(grid, m, limit, points, hints, 1);
    }
    let chunks: Option<Vec<f32>> = if hinted {
        points
            .par_chunks(FARTHEST_CHUNK)
            .zip(hints.par_chunks_mut(FARTHEST_CHUNK))
            .map(|(chunk, h)| running_max(grid, m, limit, chunk, h, 1))
            .collect()
    } else {
        points
            .par_chunks(FARTHEST_CHUNK)
            .map(|chunk| running_max(grid, m, limit, chunk, &mut [], 1))
            .collect()
    };
    chunks.map(|c| c.into_iter().fold(m, f32::max))
}

/// [`farthest_hinted`] over every `step`-th point from `floor`, in order.
fn running_max(
    grid: &TriangleGrid,
    floor: f32,
    limit: f32,
    points: &[Vec3],
    hints: &mut [u32],
    step: usize,
) -> Option<f32> {
    let mut m = floor;
    let mut last = u32::MAX;
    for i in (0..points.len()).step_by(step) {
        let (d, nearest) = grid.nearest_above(points[i], m, hint_at(hints, i, last));
        if let Some(h) = hints.get_mut(i) {
            *h = nearest;
        }
        last = nearest;
        m = m.max(d);
        if m >= limit {
            return None;
        }
    }
    Some(m)
}

/// The triangle point `i`'s search starts at: its hint, or without one the triangle where the
/// point before ended (`last`): neighbouring points of a list (a triangle's centroid and
/// midpoints, vertices in first-use order) are near each other.
fn hint_at(hints: &[u32], i: usize, last: u32) -> u32 {
    match hints.get(i) {
        Some(&h) if h != u32::MAX => h,
        _ => last,
    }
}

/// Points per parallel chunk of [`farthest`].
const FARTHEST_CHUNK: usize = 1024;

/// Measures the triangles `indices` (into `positions`) against LOD 0, given as its distinct
/// vertex positions and its grid: exact where it matters (see [`Measured`]).
pub(super) fn measure(
    positions: &[Vec3],
    indices: &[u32],
    base_points: &[Vec3],
    base_grid: &TriangleGrid,
) -> Measured {
    // The build's grid is made beside the first half of the measurement (it does not depend on it).
    let (added, grid) = rayon::join(
        || {
            let distinct = distinct(&sample_points(positions, indices));
            farthest(&distinct, base_grid, 0.0, f32::INFINITY).unwrap_or(f32::INFINITY)
        },
        || TriangleGrid::new(positions, indices),
    );
    let mut hints = vec![u32::MAX; base_points.len()];
    let lost = farthest_hinted(base_points, &grid, added, f32::INFINITY, &mut hints)
        .unwrap_or(f32::INFINITY);
    Measured {
        lost,
        added,
        grid,
        hints,
    }
}

/// [`measure`], or `None` as soon as the distance is known to be at least `limit`.
pub(super) fn measure_below(
    positions: &[Vec3],
    indices: &[u32],
    base_points: &[Vec3],
    base_grid: &TriangleGrid,
    limit: f32,
) -> Option<Measured> {
    // Each point once: an edge's midpoint comes from both its triangles (the same bits, as
    // float addition commutes), and a maximum does not depend on repeats or order.
    let distinct = distinct(&sample_points(positions, indices));
    let added = farthest(&distinct, base_grid, 0.0, limit)?;
    let grid = TriangleGrid::new(positions, indices);
    let mut hints = vec![u32::MAX; base_points.len()];
    let lost = farthest_hinted(base_points, &grid, added, limit, &mut hints)?;
    Some(Measured {
        lost,
        added,
        grid,
        hints,
    })
}

/// The distance of LOD 0's farthest point of `base_points` from the triangles `indices` (into
/// `positions`) as far as it is above `floor` (otherwise `floor`: a maximum over several poses
/// passes the largest so far, and most points then stop at their first triangle); `None` as soon
/// as it is known to be at least `limit`.
///
/// `hints`: per point, the triangle of `indices` to measure it against first (resized to the
/// points, new ones with none), set to where each point's search ended: the same buffer across
/// the poses of one build makes most searches one triangle long.
pub(super) fn lost_below(
    positions: &[Vec3],
    indices: &[u32],
    base_points: &[Vec3],
    (floor, limit): (f32, f32),
    hints: &mut Vec<u32>,
) -> Option<f32> {
    let grid = TriangleGrid::new(positions, indices);
    hints.resize(base_points.len(), u32::MAX);
    farthest_hinted(base_points, &grid, floor, limit, hints)
}

/// The distance of `m`'s build to LOD 0 with `extra` points of LOD 0 (its centroids and edge
/// midpoints) measured against the build's surface too; `None` as soon as it is known to be at
/// least `limit`.
pub(super) fn with_points(m: &Measured, extra: &[Vec3], limit: f32) -> Option<f32> {
    let d = m.distance();
    if d >= limit {
        return None;
    }
    farthest(extra, &m.grid, d, limit)
}

/// LOD 0's points at least half as far from the measured result as the farthest (`m.lost`, which
/// must be exact: larger than `m.added`), farthest first (ties in `base_points`' order), at most
/// [`REPAIR_VERTICES`].
pub(super) fn far_vertices(m: &Measured, base_points: &[Vec3]) -> Vec<Vec3> {
    // Each search starts where the point's search for `m.lost` ended.
    far_first(&m.grid, base_points.iter().copied(), m.lost, &m.hints)
        .into_iter()
        .map(|i| base_points[i])
        .collect()
}

/// The rest positions (`rest`) of LOD 0's vertices `used` that are farthest from a build in one
/// pose: `base_posed` is LOD 0's vertices under the pose, `build_posed` the build's source's and
/// `indices` the build's triangles. Those at least half as far as `farthest` (the largest such
/// distance, measured before), farthest first (ties in `used`' order), at most
/// [`REPAIR_VERTICES`].
pub(super) fn posed_far_vertices(
    rest: &[Vec3],
    used: &[u32],
    (base_posed, build_posed): (&[Vec3], &[Vec3]),
    indices: &[u32],
    farthest: f32,
) -> Vec<Vec3> {
    let grid = TriangleGrid::new(build_posed, indices);
    let points = used.iter().map(|&v| base_posed[v as usize]);
    far_first(&grid, points, farthest, &[])
        .into_iter()
        .map(|i| rest[used[i] as usize])
        .collect()
}

/// The positions in `points` of those more than half of `farthest` from `grid`'s triangles,
/// farthest first (ties in order), at most [`REPAIR_VERTICES`]; each search starts at its hint
/// in `hints` (see [`hint_at`]).
fn far_first(
    grid: &TriangleGrid,
    points: impl Iterator<Item = Vec3>,
    farthest: f32,
    hints: &[u32],
) -> Vec<usize> {
    let half = farthest * 0.5;
    let mut last = u32::MAX;
    let mut far: Vec<(f32, usize)> = points
        .enumerate()
        .filter_map(|(i, p)| {
            let d;
            (d, last) = grid.nearest_above(p, half, hint_at(hints, i, last));
            (d > half && d.is_finite()).then_some((d, i))
        })
        .collect();
    far.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    far.truncate(REPAIR_VERTICES);
    far.into_iter().map(|(_, i)| i).collect()
}

/// The vertices of `indices` in first-use order, one per distinct position (the first): the
/// vertex behind each point of `distinct(&used_vertices(positions, indices))`, in its order.
pub(super) fn distinct_used(positions: &[Vec3], indices: &[u32]) -> Vec<u32> {
    let mut seen = vec![false; positions.len()];
    let used: Vec<u32> = indices
        .iter()
        .copied()
        .filter(|&i| {
            seen.get_mut(i as usize)
                .is_some_and(|s| !std::mem::replace(s, true))
        })
        .collect();
    let points: Vec<Vec3> = used.iter().map(|&v| positions[v as usize]).collect();
    let (count, ids) = position_ids(&points);
    let mut taken = vec![false; count];
    used.into_iter()
        .zip(&ids)
        .filter(|&(_, &id)| !std::mem::replace(&mut taken[id as usize], true))
        .map(|(v, _)| v)
        .collect()
}

/// The posed check of the default's repair on a skinned mesh beyond the plain builds' bound
/// (docs/lod.md, "A posed check without a grid per pose"): each of LOD 0's points (`vertices`,
/// the vertex behind each of `m`'s points) measured, in each pose, against the one triangle of
/// the build (`indices`) its rest search ended on (`m`'s hints), both skinned: `base_posed` is LOD
/// 0's vertices under the poses, `source_posed` the build's source's. A point is never nearer
/// one triangle than the whole surface, so each distance is an upper bound of the point's
/// distance from the build in the pose. Returns the largest over the poses and the rest positions of that pose's points more than half as far, farthest first
/// (ties in order), at most [`REPAIR_VERTICES`].
pub(super) fn hinted_posed_far(
    m: &Measured,
    (vertices, rest): (&[u32], &[Vec3]),
    indices: &[u32],
    (base_posed, source_posed): (&[Vec<Vec3>], &[Vec<Vec3>]),
) -> (f32, Vec<Vec3>) {
    let corner = |posed: &[Vec3], t: u32, k: usize| -> Option<Vec3> {
        let v = *indices.get(3 * t as usize + k)?;
        posed.get(v as usize).copied()
    };
    let distances = |base: &Vec<Vec3>, source: &Vec<Vec3>| -> Vec<f32> {
        vertices
            .iter()
            .zip(&m.hints)
            .map(|(&v, &t)| {
                let tri = [0, 1, 2].map(|k| corner(source, t, k));
                match (base.get(v as usize), tri) {
                    (Some(&p), [Some(a), Some(b), Some(c)]) => {
                        crate::surface::point_triangle_distance(p, a, b, c)
                    }
                    _ => 0.0,
                }
            })
            .collect()
    };
    // The poses side by side (a few thousand points each, against one triangle each): the first
    // pose of the largest distance is the same whatever runs where.
    let per_pose: Vec<Vec<f32>> = base_posed
        .par_iter()
        .zip(source_posed)
        .map(|(base, source)| distances(base, source))
        .collect();
    let mut worst: (f32, Vec<f32>) = (0.0, Vec::new());
    for d in per_pose {
        let top = d.iter().copied().fold(0.0f32, f32::max);
        if top > worst.0 {
            worst = (top, d);
        }
    }
    let (top, d) = worst;
    let half = top * 0.5;
    let mut far: Vec<(f32, usize)> = d
        .iter()
        .enumerate()
        .filter(|&(_, &x)| x > half && x.is_finite())
        .map(|(i, &x)| (x, i))
        .collect();
    far.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    far.truncate(REPAIR_VERTICES);
    (
        top,
        far.into_iter()
            .filter_map(|(_, i)| rest.get(i).copied())
            .collect(),
    )
}

/// The points of `points` with distinct positions (bit for bit), first occurrences, in order.
pub(super) fn distinct(points: &[Vec3]) -> Vec<Vec3> {
    let (count, ids) = position_ids(points);
    let mut out = Vec::with_capacity(count);
    let mut taken = vec![false; count];
    for (p, &id) in points.iter().zip(&ids) {
        if !std::mem::replace(&mut taken[id as usize], true) {
            out.push(*p);
        }
    }
    out
}

/// What the repair build locks: the positions (bit patterns, sorted, each once) of `points` and,
/// for each, the corners of its largest triangle in `source` (the first such in index order).
/// Locking a vertex alone keeps it in place, but its triangles still go when its neighbours
/// collapse into one another (a thin part's tip is left with nothing to hold it); a locked
/// triangle keeps the feature.
pub(super) fn repair_locks(source: &Lod, points: &[Vec3]) -> Vec<[u32; 3]> {
    let bits = |p: &Vec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    let mut want: Vec<([u32; 3], usize)> = points
        .iter()
        .enumerate()
        .map(|(i, p)| (bits(p), i))
        .collect();
    want.sort_unstable();
    let mut best: Vec<Option<(f32, usize)>> = vec![None; points.len()];
    for (ti, t) in source.indices.chunks_exact(3).enumerate() {
        let corners = [0, 1, 2].map(|i| source.positions[t[i] as usize]);
        let area = (corners[1] - corners[0])
            .cross(corners[2] - corners[0])
            .length();
        for c in &corners {
            let key = bits(c);
            let start = want.partition_point(|w| w.0 < key);
            for w in want[start..].iter().take_while(|w| w.0 == key) {
                let b = &mut best[w.1];
                if b.is_none_or(|(a, _)| area > a) {
                    *b = Some((area, ti));
                }
            }
        }
    }
    let mut out: Vec<[u32; 3]> = want.iter().map(|w| w.0).collect();
    for (_, ti) in best.into_iter().flatten() {
        out.extend(
            source.indices[3 * ti..3 * ti + 3]
                .iter()
                .map(|&v| bits(&source.positions[v as usize])),
        );
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// A mesh's extent as meshoptimizer measures it (its vertices' largest box side): what a LOD's
/// relative error is of.
pub fn mesh_scale(mesh: &Mesh) -> f32 {
    let positions: Vec<[f32; 3]> = mesh
        .geometry
        .positions
        .iter()
        .map(|p| p.to_array())
        .collect();
    extent(&positions)
}

/// meshoptimizer's extent of `points` (0 for none).
fn extent(points: &[[f32; 3]]) -> f32 {
    if points.is_empty() {
        0.0
    } else {
        meshopt::simplify_scale_decoder(points)
    }
}

/// The extent (as [`mesh_scale`] measures it) of a mesh's largest material range, on the vertices
/// its triangles use: gltfpack converts each range to a primitive of its own and scales each
/// primitive's `-si` limit by the largest primitive's extent over its own (`Plain::Primitives`).
pub fn largest_range_scale(mesh: &Mesh) -> f32 {
    let g = &mesh.geometry;
    let ranges: Vec<&[u32]> = if g.submeshes.is_empty() {
        vec![&g.indices[..]]
    } else {
        g.submeshes
            .iter()
            .filter_map(|s| {
                let from = s.first_index as usize;
                g.indices.get(from..from + s.index_count as usize)
            })
            .collect()
    };
    let mut seen = vec![false; g.positions.len()];
    ranges
        .into_iter()
        .map(|range| {
            let mut used: Vec<[f32; 3]> = Vec::new();
            for &v in range {
                if let Some(s) = seen.get_mut(v as usize).filter(|s| !**s) {
                    *s = true;
                    used.push(g.positions[v as usize].to_array());
                }
            }
            for &v in range {
                if let Some(s) = seen.get_mut(v as usize) {
                    *s = false;
                }
            }
            extent(&used)
        })
        .fold(0.0f32, f32::max)
}

/// The next f32 above `x`, for a non-negative finite `x` (`f32::next_up`, newer than the MSRV): a
/// limit that lets a distance equal to `x` through.
pub(super) fn next_above(x: f32) -> f32 {
    f32::from_bits(x.to_bits() + 1)
}

/// The pose of the largest distance in `distances` (the first of equals) and that distance.
pub(super) fn farthest_pose(distances: &[f32]) -> Option<(usize, f32)> {
    distances
        .iter()
        .enumerate()
        .fold(None, |w, (k, &d)| match w {
            Some((_, wd)) if wd >= d => w,
            _ => Some((k, d)),
        })
}
