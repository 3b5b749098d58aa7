//! Half-Life MDL, SMD and QC import on the shared corpus, with values checked against the bytes.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use sinew_import::{import_path, ImportOptions};
use sinew_scene::Scene;
use sinew_testdata::corpus_file;

fn import(rel: &str) -> Option<Scene> {
    let path = corpus_file(rel)?;
    Some(import_path(&path, &ImportOptions::default()).unwrap_or_else(|e| panic!("{rel}: {e}")))
}

/// Fraction of triangles whose face normal (counter-clockwise corners) points the way of their
/// corner normals.
fn front_facing(scene: &Scene) -> f32 {
    let (mut good, mut all) = (0, 0);
    for m in &scene.meshes {
        let g = &m.geometry;
        for t in g.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| g.positions[i as usize]);
            let face = (b - a).cross(c - a);
            let n = g.normals[t[0] as usize] + g.normals[t[1] as usize] + g.normals[t[2] as usize];
            if face.length() > 1e-6 {
                all += 1;
                if face.dot(n) > 0.0 {
                    good += 1;
                }
            }
        }
    }
    good as f32 / all.max(1) as f32
}

#[test]
fn mdl_triangles_face_the_way_of_their_normals() {
    for f in [
        "man.mdl",
        "chrome_sphere.mdl",
        "alpha_test.mdl",
        "sequence_transitions.mdl",
    ] {
        let Some(s) = import(&format!("mdl/{f}")) else {
            return;
        };
        let r = front_facing(&s);
        eprintln!("{f}: {r}");
        assert!(r > 0.95, "{f}: {r}");
    }
}
