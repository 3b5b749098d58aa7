//! The entry point: a loaded document to a Scene (skeleton, materials, meshes, clips, diagnostics).

use super::animation::import_animations;
use super::document::{at, load};
use super::mesh::{import_meshes, materials};
use super::skin::{build_rig, graph};
use crate::{ImportError, ImportOptions, Resolver};
use sinew_scene::{Diagnostic, Scene, SourceFormat};

/// Imports a glTF 2.0 file (`.gltf` or `.glb`). See docs/formats/gltf.md.
pub fn import(
    file_name: &str,
    bytes: &[u8],
    resolve: Resolver<'_>,
    options: &ImportOptions,
) -> Result<Scene, ImportError> {
    // Last resort: our own checks (`refs`) run before the gltf crate's, but should the crate still
    // panic on something they miss, the file fails with an ordinary error and nothing is printed.
    contained(file_name, || {
        import_inner(file_name, bytes, resolve, options)
    })
}

/// `f`, with a panic inside it (the gltf crate's) contained on this thread: an ordinary error that
/// names the file, and nothing printed.
fn contained<T>(file: &str, f: impl FnOnce() -> Result<T, ImportError>) -> Result<T, ImportError> {
    crate::guard::contain(f).unwrap_or_else(|m| {
        Err(ImportError::in_section(
            file,
            "json",
            format!("the gltf crate could not interpret the document ({m})"),
        ))
    })
}

pub(super) fn import_inner(
    file_name: &str,
    bytes: &[u8],
    resolve: Resolver<'_>,
    options: &ImportOptions,
) -> Result<Scene, ImportError> {
    let file = file_name;
    let l = load(file, bytes, resolve)?;
    let doc = &l.doc;
    let mut scene = Scene::new(SourceFormat::Gltf);
    scene.diagnostics.extend(l.warnings.iter().cloned());
    let g = graph(file, doc, &mut scene.diagnostics)?;

    // The skeleton: the chosen skin, or the whole node forest when there is no skin but animations.
    let skins: Vec<gltf::Skin<'_>> = doc.skins().collect();
    let rig = if skins.is_empty() {
        if doc.animations().next().is_some() && !g.local.is_empty() {
            let all: Vec<usize> = (0..g.local.len()).collect();
            scene.diagnostics.push(Diagnostic::info(
                "gltf-node-skeleton",
                "the file has animations but no skin: every node becomes a joint",
            ));
            Some(build_rig(file, &l, &g, &all, None, &mut scene.diagnostics)?)
        } else {
            None
        }
    } else {
        let chosen = options.gltf_skin.unwrap_or(0);
        let skin = skins.get(chosen).cloned().ok_or_else(|| {
            at(
                file,
                "skins",
                format!("skin {chosen} was requested; the file has {}", skins.len()),
            )
        })?;
        if skins.len() > 1 && options.gltf_skin.is_none() {
            let others: Vec<String> = skins
                .iter()
                .skip(1)
                .map(|s| match s.name() {
                    Some(n) => format!("{} {n:?}", s.index()),
                    None => s.index().to_string(),
                })
                .collect();
            scene.diagnostics.push(
                Diagnostic::warning(
                    "gltf-several-skins",
                    format!(
                        "the file has {} skins; imported skin 0, not skins {} (choose with the gltf_skin option)",
                        skins.len(),
                        others.join(", ")
                    ),
                )
                .with_figure("skins", skins.len() as f64),
            );
        }
        let joints: Vec<usize> = skin.joints().map(|n| n.index()).collect();
        if joints.is_empty() {
            return Err(at(
                file,
                format!("skins[{chosen}].joints"),
                "the skin has no joints",
            ));
        }
        Some(build_rig(
            file,
            &l,
            &g,
            &joints,
            Some(skin),
            &mut scene.diagnostics,
        )?)
    };

    scene.materials = materials(doc);
    // Meshes and animations read the document and write different parts of the scene: each into
    // a scene of its own, at the same time, then merged in the order they ran in before (meshes,
    // then clips, each part's diagnostics in its own order; the meshes' error first). A
    // single-file convert's import is on its critical path (CesiumMan: 4.6M and 3.2M instructions).
    // A panic on the other thread is contained there, as `import` contains one on this thread
    // (quietly, with the same message).
    let (meshes, clips) = rayon::join(
        || {
            contained(file, || {
                let mut part = Scene::new(SourceFormat::Gltf);
                import_meshes(file, &l, &g, rig.as_ref(), &mut part).map(|()| part)
            })
        },
        || {
            contained(file, || {
                let mut part = Scene::new(SourceFormat::Gltf);
                match &rig {
                    Some(rig) => import_animations(file, &l, &g, rig, &mut part)?,
                    None if doc.animations().next().is_some() => {
                        part.diagnostics.push(Diagnostic::warning(
                            "gltf-animations-skipped",
                            "animations need a skeleton; the file has none",
                        ));
                    }
                    None => {}
                }
                Ok(part)
            })
        },
    );
    let (meshes, clips) = (meshes?, clips?);
    scene.meshes = meshes.meshes;
    scene.diagnostics.extend(meshes.diagnostics);
    scene.clips = clips.clips;
    scene.diagnostics.extend(clips.diagnostics);
    scene.skeleton = rig.map(|r| r.skeleton);
    Ok(scene)
}
