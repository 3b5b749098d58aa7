//! Checks and edits of one LOD's buffers that need nothing else of the LOD builder: that they agree
//! with each other (what meshoptimizer needs before any call), and the lowest LOD's influences cut.

use sinew_core::{Lod, MAX_INFLUENCES};

/// Checks that a LOD's buffers agree with each other: what meshoptimizer needs before any call.
pub fn validate_lod(lod: &Lod) -> Result<(), String> {
    let n = lod.positions.len();
    if n > u32::MAX as usize {
        return Err(format!("{n} vertices is more than 32-bit indices address"));
    }
    if lod.normals.len() != n {
        return Err(format!("{} normals for {n} positions", lod.normals.len()));
    }
    if !lod.uvs.is_empty() && lod.uvs.len() != n {
        return Err(format!("{} uvs for {n} positions", lod.uvs.len()));
    }
    if lod.joints.len() != lod.weights.len() || (!lod.joints.is_empty() && lod.joints.len() != n) {
        return Err(format!(
            "{} joint and {} weight sets for {n} positions",
            lod.joints.len(),
            lod.weights.len()
        ));
    }
    if lod.indices.len() % 3 != 0 {
        return Err(format!(
            "{} indices is not a whole number of triangles",
            lod.indices.len()
        ));
    }
    if let Some(bad) = lod.indices.iter().find(|&&i| i as usize >= n) {
        return Err(format!("index {bad} refers past the {n} vertices"));
    }
    if !lod.positions.iter().all(|p| p.is_finite()) {
        return Err("non-finite position".into());
    }
    let mut next = 0u32;
    for s in &lod.submeshes {
        if s.first_index != next || s.index_count % 3 != 0 {
            return Err("submeshes do not cover the indices in order, by whole triangles".into());
        }
        next = s
            .first_index
            .checked_add(s.index_count)
            .ok_or("submesh range overflows")?;
    }
    if next as usize != lod.indices.len() && !lod.submeshes.is_empty() {
        return Err("submeshes do not cover every index".into());
    }
    Ok(())
}

/// Keeps the `keep` largest influences of every vertex and renormalises them to sum to one.
pub fn limit_influences(lod: &mut Lod, keep: usize) {
    for (j, w) in lod.joints.iter_mut().zip(&mut lod.weights) {
        let mut order: [usize; MAX_INFLUENCES] = [0, 1, 2, 3];
        // Stable: equal weights keep slot order.
        order.sort_by(|&a, &b| w[b].total_cmp(&w[a]));
        let (mut nj, mut nw) = ([0u16; MAX_INFLUENCES], [0.0f32; MAX_INFLUENCES]);
        for (slot, &k) in order.iter().take(keep).enumerate() {
            nj[slot] = j[k];
            nw[slot] = w[k];
        }
        let sum: f32 = nw.iter().sum();
        if sum > 0.0 {
            for x in &mut nw {
                *x /= sum;
            }
            *j = nj;
            *w = nw;
        }
    }
}
