//! What the LOD examples (`lod_compare`, `lod_peers`) share: a scene's meshes at one LOD level as one
//! triangle soup, at rest or posed by a skinning palette of its first clip.

use sinew_core::glam::{Mat4, Vec3};
use sinew_core::{ClipBinding, Lod, Sampler};
use sinew_scene::Scene;

/// A mesh's LOD at `level` (None: LOD 0); a mesh without that level (not built) gives the last
/// level it has, which is what the runtime draws there.
pub fn level_of(m: &sinew_scene::Mesh, level: Option<usize>) -> &Lod {
    match level {
        None => &m.geometry,
        Some(k) => m
            .lods
            .get(k)
            .or(m.lods.last())
            .map_or(&m.geometry, |g| &g.lod),
    }
}

/// All meshes of a LOD level (None: LOD 0) as one soup, optionally posed by `palette` (a mesh whose
/// joints the palette does not cover stays at rest).
pub fn soup(
    scene: &Scene,
    level: Option<usize>,
    palette: Option<&[Mat4]>,
) -> (Vec<Vec3>, Vec<u32>) {
    let (mut p, mut i) = (Vec::new(), Vec::new());
    for m in &scene.meshes {
        let lod = level_of(m, level);
        let base = p.len() as u32;
        match palette {
            Some(pal)
                if lod.is_skinned()
                    && lod
                        .joints
                        .iter()
                        .flatten()
                        .all(|&j| (j as usize) < pal.len()) =>
            {
                let mut out = vec![Vec3::ZERO; lod.positions.len()];
                sinew_core::skin(
                    pal,
                    &lod.positions,
                    &[],
                    &lod.joints,
                    &lod.weights,
                    &mut out,
                    &mut [],
                )
                .expect("skinning");
                p.extend(out);
            }
            _ => p.extend_from_slice(&lod.positions),
        }
        i.extend(lod.indices.iter().map(|&x| x + base));
    }
    (p, i)
}

/// The skinning palette of the scene's first clip sampled at `at` times its duration (`at` of 1
/// or more: clip `at.floor()` at `at.fract()` of its duration), with the clip's name and that time.
pub fn pose_palette(scene: &Scene, at: f32) -> Option<(Vec<Mat4>, String, f32)> {
    let skeleton = scene.skeleton.as_ref()?;
    let c = scene.clips.get(at.floor() as usize)?;
    let clip = c.to_clip().ok()?;
    let binding = ClipBinding::new(&clip, skeleton);
    let mut locals = skeleton.bind_local().to_vec();
    let t = clip.duration() * at.fract();
    Sampler::new()
        .sample(&clip, &binding, skeleton, t, &mut locals)
        .ok()?;
    let mut models = vec![Mat4::IDENTITY; skeleton.len()];
    sinew_core::local_to_model(skeleton.parents(), &locals, &mut models).ok()?;
    let mut palette = vec![Mat4::IDENTITY; skeleton.len()];
    sinew_core::skinning_palette(&models, skeleton.inverse_bind(), &mut palette).ok()?;
    Some((palette, c.name.clone(), t))
}

/// True when `other` has the original's joints in the same order with the same inverse bind matrices
/// (within `tolerance`), so that the original's palette poses it the way it poses the original.
pub fn same_rig(original: &Scene, other: &Scene, tolerance: f32) -> bool {
    let (Some(a), Some(b)) = (&original.skeleton, &other.skeleton) else {
        return false;
    };
    a.names() == b.names()
        && a.inverse_bind()
            .iter()
            .zip(b.inverse_bind())
            .all(|(x, y)| x.abs_diff_eq(*y, tolerance))
}
