//! Probe (temporary): one mesh simplified to a count with meshoptimizer directly, in several ways,
//! against gltfpack's output at that count. `lod_probe FILE.glb MESH TARGET [GLTFPACK_OUT.glb]`
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod lod_common;

use lod_common::soup;
use meshopt::{SimplifyOptions, SimplifyVertex};
use sinew_core::glam::Vec3;
use sinew_import::{import_path, ImportOptions};
use sinew_testdata::geometry::{diagonal, hausdorff};

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let mut scene = import_path(std::path::Path::new(&a[0]), &ImportOptions::default()).unwrap();
    let mi: usize = a[1].parse().unwrap();
    if std::env::var_os("PROBE_OPT").is_some() {
        sinew_pipeline::lod::optimize_base(&mut scene.meshes[mi]).unwrap();
    }
    let target: usize = a[2].parse().unwrap();
    let g = &scene.meshes[mi].geometry;
    println!("mesh {} verts {} tris {} uvs {} skinned {} submeshes {}", scene.meshes[mi].name, g.positions.len(), g.triangle_count(), g.uvs.len(), g.is_skinned(), g.submeshes.len());
    let diag = diagonal(&g.positions);
    // Reindex on every attribute, as gltfpack does with -noq.
    let keys: Vec<[u32; 14]> = (0..g.positions.len())
        .map(|v| {
            let mut k = [0u32; 14];
            let p = g.positions[v];
            let n = g.normals[v];
            k[0..3].copy_from_slice(&[p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]);
            k[3..6].copy_from_slice(&[n.x.to_bits(), n.y.to_bits(), n.z.to_bits()]);
            if let Some(uv) = g.uvs.get(v) {
                k[6] = uv.x.to_bits();
                k[7] = uv.y.to_bits();
            }
            if let (Some(j), Some(w)) = (g.joints.get(v), g.weights.get(v)) {
                k[8] = j[0] as u32 | (j[1] as u32) << 16;
                k[9] = j[2] as u32 | (j[3] as u32) << 16;
                for s in 0..4 {
                    k[10 + s] = w[s].to_bits();
                }
            }
            k
        })
        .collect();
    let (unique, remap) = meshopt::generate_vertex_remap(&keys, Some(&g.indices));
    let mut first = vec![usize::MAX; unique];
    for (v, &r) in remap.iter().enumerate() {
        if first[r as usize] == usize::MAX {
            first[r as usize] = v;
        }
    }
    let pos: Vec<[f32; 3]> = first.iter().map(|&f| g.positions[f].to_array()).collect();
    let nrm: Vec<f32> = first.iter().flat_map(|&f| g.normals[f].to_array()).collect();
    let idx: Vec<u32> = g
        .indices
        .chunks_exact(3)
        .map(|t| [remap[t[0] as usize], remap[t[1] as usize], remap[t[2] as usize]])
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .flatten()
        .collect();
    println!("welded verts {unique} tris {}", idx.len() / 3);
    let p3: Vec<Vec3> = pos.iter().map(|p| Vec3::from_array(*p)).collect();
    let locks = vec![SimplifyVertex::None; unique];
    let run = |name: &str, w: f32, opts: SimplifyOptions, err: f32| {
        let mut e = 0.0f32;
        let out = meshopt::simplify_with_attributes_and_locks_decoder(
            &idx, &pos, &nrm, &[w, w, w], 12, &locks, target * 3, err, opts, Some(&mut e),
        );
        let h = hausdorff(&g.positions, &g.indices, &p3, &out) / diag * 100.0;
        println!("{name:40} tris {:5} err {e:.5} dist {h:.3}", out.len() / 3);
        out
    };
    let keyset = |ps: &mut dyn Iterator<Item = [f32; 3]>| {
        let mut k: Vec<[u32; 3]> = ps.map(|p| [p[0].to_bits(), p[1].to_bits(), p[2].to_bits()]).collect();
        k.sort_unstable();
        k.dedup();
        k
    };
    let skin = if g.is_skinned() { SimplifyOptions::Regularize } else { SimplifyOptions::None };
    let mine = run("normals0.5 prune reg(skin) e0.01", 0.5, SimplifyOptions::Prune | skin, 0.01);
    let mine_keys = keyset(&mut mine.iter().map(|&i| pos[i as usize]));
    run("normals0.5 prune reg(skin) einf", 0.5, SimplifyOptions::Prune | skin, f32::MAX.sqrt());
    run("normals0.5 prune", 0.5, SimplifyOptions::Prune, 1e18);
    run("normals0.5", 0.5, SimplifyOptions::None, 1e18);
    run("normals0 prune reg(skin)", 0.0, SimplifyOptions::Prune | skin, 1e18);
    run("normals0 ", 0.0, SimplifyOptions::None, 1e18);
    run("normals0.5 prune reglight", 0.5, SimplifyOptions::Prune | SimplifyOptions::RegularizeLight, 1e18);
    // The same, after a vertex-cache optimisation of the indices (the order sinew's LOD 0 has).
    {
        let mut idx2 = idx.clone();
        meshopt::optimize_vertex_cache_in_place(&mut idx2, unique);
        let mut e = 0.0f32;
        let out = meshopt::simplify_with_attributes_and_locks_decoder(
            &idx2, &pos, &nrm, &[0.5, 0.5, 0.5], 12, &locks, target * 3, 1e18, SimplifyOptions::Prune | skin, Some(&mut e),
        );
        let h = hausdorff(&g.positions, &g.indices, &p3, &out) / diag * 100.0;
        println!("{:40} tris {:5} err {e:.5} dist {h:.3}", "cache-optimised order", out.len() / 3);
        // rotated triangle order
        for r in [1usize, 7, 31] {
            let n = idx.len() / 3;
            let idx3: Vec<u32> = (0..n).flat_map(|t| { let t = (t + r) % n; idx[3*t..3*t+3].to_vec() }).collect();
            let out = meshopt::simplify_with_attributes_and_locks_decoder(
                &idx3, &pos, &nrm, &[0.5, 0.5, 0.5], 12, &locks, target * 3, 1e18, SimplifyOptions::Prune | skin, Some(&mut e),
            );
            let h = hausdorff(&g.positions, &g.indices, &p3, &out) / diag * 100.0;
            println!("{:40} tris {:5} err {e:.5} dist {h:.3}", format!("triangles rotated by {r}"), out.len() / 3);
        }
    }
    if let Some(gp) = a.get(3) {
        let o = import_path(std::path::Path::new(gp), &ImportOptions::default()).unwrap();
        let (p, i) = soup(&o, None, None);
        // only the mesh of interest: use the mesh index
        let og = &o.meshes[mi].geometry;
        let h = hausdorff(&g.positions, &g.indices, &og.positions, &og.indices) / diag * 100.0;
        println!("gltfpack: tris {} verts {} dist {h:.3} (whole file soup tris {})", og.triangle_count(), og.positions.len(), i.len() / 3);
        let _ = p;
        // Which positions does gltfpack keep that no meshopt variant keeps?
        let mut gk: Vec<[u32; 3]> = og.positions.iter().map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]).collect();
        gk.sort_unstable();
        gk.dedup();
        println!("gltfpack distinct positions {}", gk.len());
        let common = gk.iter().filter(|k| mine_keys.binary_search(k).is_ok()).count();
        println!("mine distinct positions {} common {common}", mine_keys.len());
        let mut tri_g: Vec<[[u32;3];3]> = og.indices.chunks_exact(3).map(|t| { let mut c = [0,1,2].map(|k| { let p = og.positions[t[k] as usize]; [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()] }); c.sort(); c }).collect();
        tri_g.sort();
        let mut tri_m: Vec<[[u32;3];3]> = mine.chunks_exact(3).map(|t| { let mut c = [0,1,2].map(|k| { let p = pos[t[k] as usize]; [p[0].to_bits(), p[1].to_bits(), p[2].to_bits()] }); c.sort(); c }).collect();
        tri_m.sort();
        let ct = tri_g.iter().filter(|t| tri_m.binary_search(t).is_ok()).count();
        println!("triangles in common {ct} of {}", tri_g.len());
        // weights of gltfpack vs original for same positions
        let mut diffw = 0;
        for (v, p) in og.positions.iter().enumerate() {
            if let Some(o) = g.positions.iter().position(|q| q == p) {
                if og.weights.get(v) != g.weights.get(o) || og.joints.get(v) != g.joints.get(o) { diffw += 1; if diffw < 3 { println!("w {:?} {:?} vs {:?} {:?}", og.joints.get(v), og.weights.get(v), g.joints.get(o), g.weights.get(o)); } }
            }
        }
        println!("vertices with different skin {diffw}");
    }
}
