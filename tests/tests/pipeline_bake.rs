//! Baking corpus characters to EXR, PC2 and MDD, reading the files back independently of the writers,
//! checking chosen vertices against skinning done by hand here, and verifying caches exactly.
#![allow(clippy::unwrap_used, clippy::type_complexity, clippy::identity_op)]

use sinew_core::format::{self, Asset, Mask, SourceVertexMap};
use sinew_core::glam::{Mat4, Quat, Vec3};
use sinew_core::{Channel, Clip};
use sinew_pipeline::bake::{self, BakeError, BakeRequest, LayerSpec, VertexOrder};
use sinew_pipeline::cache::vat::VatEncoding;
use sinew_pipeline::verify::{self, CacheFormat, CacheOptions, NormalsPlacement, VerifyError};

/// Import -> compile -> write -> read: exactly what the runtime loads.
fn load(rel: &str) -> Option<Asset> {
    let path = sinew_testdata::corpus_file(rel)?;
    let scene = sinew_import::import_path(&path, &Default::default()).unwrap();
    let bytes = sinew_pipeline::compile::compile_to_bytes(&scene).unwrap();
    Some(format::read(&bytes).unwrap())
}

/// The local pose of `clip` at its `k`-th stored key time, read from the stored frames by hand.
fn pose_at_key(asset: &Asset, clip: &Clip, k: usize) -> Vec<(Vec3, Quat, Vec3)> {
    let skel = asset.skeleton.as_ref().unwrap();
    let mut pose: Vec<_> = skel
        .bind_local()
        .iter()
        .map(|t| (t.translation, t.rotation, t.scale))
        .collect();
    let f = &clip.frames()[k * clip.stride()..(k + 1) * clip.stride()];
    let v3 = |c: Channel<Vec3>, d: Vec3| match c {
        Channel::Bind => d,
        Channel::Constant(v) => v,
        Channel::Animated(o) => Vec3::from_slice(&f[o as usize..o as usize + 3]),
    };
    for t in clip.tracks() {
        let Some(j) = skel.find(&t.joint) else {
            continue;
        };
        let p = &mut pose[j as usize];
        p.0 = v3(t.translation, p.0);
        p.1 = match t.rotation {
            Channel::Bind => p.1,
            Channel::Constant(q) => q,
            Channel::Animated(o) => Quat::from_slice(&f[o as usize..o as usize + 4]),
        };
        p.2 = v3(t.scale, p.2);
    }
    pose
}

/// Skins vertex `v` of LOD 0 of mesh 0 by hand with glam.
fn skin_by_hand(asset: &Asset, pose: &[(Vec3, Quat, Vec3)], v: usize) -> Vec3 {
    let skel = asset.skeleton.as_ref().unwrap();
    let mut model = Vec::<Mat4>::new();
    for (i, &(t, r, s)) in pose.iter().enumerate() {
        let local = Mat4::from_scale_rotation_translation(s, r, t);
        model.push(match skel.parents()[i] {
            Some(p) => model[p as usize] * local,
            None => local,
        });
    }
    let lod = &asset.meshes[0].lods[0];
    let p = lod.positions[v];
    let mut out = Vec3::ZERO;
    for k in 0..4 {
        let j = lod.joints[v][k] as usize;
        let m = model[j] * skel.inverse_bind()[j];
        out += m.transform_point3(p) * lod.weights[v][k];
    }
    out
}

fn le_f32(b: &[u8], o: usize) -> f32 {
    f32::from_le_bytes(b[o..o + 4].try_into().unwrap())
}
fn be_f32(b: &[u8], o: usize) -> f32 {
    f32::from_be_bytes(b[o..o + 4].try_into().unwrap())
}

/// PC2 parsed from the byte layout: (points, samples, positions).
fn parse_pc2(b: &[u8]) -> (usize, usize, Vec<Vec3>) {
    assert_eq!(&b[..12], b"POINTCACHE2\0");
    let points = i32::from_le_bytes(b[16..20].try_into().unwrap()) as usize;
    let samples = i32::from_le_bytes(b[28..32].try_into().unwrap()) as usize;
    assert_eq!(b.len(), 32 + points * samples * 12);
    let pos = (0..points * samples)
        .map(|i| {
            let o = 32 + i * 12;
            Vec3::new(le_f32(b, o), le_f32(b, o + 4), le_f32(b, o + 8))
        })
        .collect();
    (points, samples, pos)
}

/// MDD parsed from the byte layout: (frames, points, times, positions).
fn parse_mdd(b: &[u8]) -> (usize, usize, Vec<f32>, Vec<Vec3>) {
    let frames = i32::from_be_bytes(b[0..4].try_into().unwrap()) as usize;
    let points = i32::from_be_bytes(b[4..8].try_into().unwrap()) as usize;
    let times = (0..frames).map(|i| be_f32(b, 8 + 4 * i)).collect();
    let base = 8 + 4 * frames;
    assert_eq!(b.len(), base + frames * points * 12);
    let pos = (0..frames * points)
        .map(|i| {
            let o = base + i * 12;
            Vec3::new(be_f32(b, o), be_f32(b, o + 4), be_f32(b, o + 8))
        })
        .collect();
    (frames, points, times, pos)
}

/// EXR read with the exr crate directly: layer name -> (width, height, R, G, B as f32, is f16).
fn parse_exr(b: &[u8]) -> Vec<(String, usize, usize, [Vec<f32>; 3], bool)> {
    use exr::prelude::*;
    let img = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(b))
        .unwrap();
    img.layer_data
        .iter()
        .map(|l| {
            let ch = |n: &str| {
                l.channel_data
                    .list
                    .iter()
                    .find(|c| c.name.to_string() == n)
                    .unwrap()
            };
            let half = matches!(ch("R").sample_data, FlatSamples::F16(_));
            let get = |n: &str| ch(n).sample_data.values_as_f32().collect::<Vec<f32>>();
            (
                l.attributes
                    .layer_name
                    .as_ref()
                    .map(|t| t.to_string())
                    .unwrap_or_default(),
                l.size.0,
                l.size.1,
                [get("R"), get("G"), get("B")],
                half,
            )
        })
        .collect()
}

fn close(a: Vec3, b: Vec3, what: &str) {
    let tol = 1e-4 * (1.0 + b.length());
    assert!((a - b).length() <= tol, "{what}: {a} vs {b}");
}

fn check_character(rel: &str) {
    let Some(asset) = load(rel) else { return };
    let lod = &asset.meshes[0].lods[0];
    let nv = lod.vertex_count();
    let clip = &asset.clips[0];
    let req = BakeRequest {
        clips: vec![clip.name().to_string()],
        ..Default::default()
    };
    let baked = bake::bake(&asset, &req).unwrap();
    let fps = clip.sample_rate();
    // Frame count computed here from the documented rule.
    let n = (clip.duration() as f64 * fps as f64 - 1e-3).ceil() as usize + 1;
    assert_eq!(baked.frames.frame_count, n, "{rel}");
    assert_eq!(baked.frames.vertex_count, nv);
    // Frame 0 is time 0; when the first key is at 0, it is that key's pose.
    assert_eq!(clip.times()[0], 0.0, "{rel}: first key");
    let pose0 = pose_at_key(&asset, clip, 0);
    let last_key = clip.times().len() - 1;
    let pose_end = (clip.times()[last_key] == clip.duration() && !clip.looping())
        .then(|| pose_at_key(&asset, clip, last_key));
    let chosen = [0, nv / 3, nv / 2, nv - 1];

    for format in [CacheFormat::Pc2, CacheFormat::Mdd, CacheFormat::Exr] {
        let opts = CacheOptions {
            format,
            encoding: VatEncoding::AbsoluteF32,
            normals: NormalsPlacement::Layer,
            max_width: 1000,
        };
        let enc = verify::encode(&baked, &req, &opts, rel, "n.exr").unwrap();
        let positions: Vec<Vec3> = match format {
            CacheFormat::Pc2 => {
                let (points, samples, pos) = parse_pc2(&enc.cache);
                assert_eq!((points, samples), (nv, n));
                pos
            }
            CacheFormat::Mdd => {
                let (frames, points, times, pos) = parse_mdd(&enc.cache);
                assert_eq!((frames, points), (n, nv));
                assert_eq!(times[1], 1.0 / fps);
                pos
            }
            CacheFormat::Exr => {
                let layers = parse_exr(&enc.cache);
                assert_eq!(layers.len(), 2);
                let p = layers.iter().find(|l| l.0 == "P").unwrap();
                // Wrapped layout: width 1000, ceil(nv / 1000) rows per frame.
                let rows = nv.div_ceil(1000);
                assert_eq!((p.1, p.2), (1000.min(nv), n * rows));
                assert!(!p.4);
                let w = p.1;
                (0..n * nv)
                    .map(|i| {
                        let (f, v) = (i / nv, i % nv);
                        let px = (f * rows + v / w) * w + v % w;
                        Vec3::new(p.3[0][px], p.3[1][px], p.3[2][px])
                    })
                    .collect()
            }
        };
        for &v in &chosen {
            close(
                positions[v],
                skin_by_hand(&asset, &pose0, v),
                &format!("{rel} {format:?} frame 0 vertex {v}"),
            );
            if let Some(pose) = &pose_end {
                close(
                    positions[(n - 1) * nv + v],
                    skin_by_hand(&asset, pose, v),
                    &format!("{rel} {format:?} last frame vertex {v}"),
                );
            }
        }
        // Bounds in the sidecar equal the bounds of the values read back.
        let lo = positions.iter().fold(Vec3::INFINITY, |a, b| a.min(*b));
        let hi = positions.iter().fold(Vec3::NEG_INFINITY, |a, b| a.max(*b));
        assert_eq!(enc.sidecar.os_remap.min, lo.to_array());
        assert_eq!(enc.sidecar.os_remap.max, hi.to_array());
        assert_eq!(enc.sidecar.os_remap.frames, n);
        // Verify passes, then fails on one changed value.
        let r = verify::verify(&asset, &enc.sidecar, &enc.cache, None).unwrap();
        assert!(r.identical(), "{rel} {format:?}: {r:?}");
        assert_eq!(r.frames, n);
        let mut bad = enc.cache.clone();
        let at = bad.len() - 5; // inside the last vertex of the last frame (PC2/MDD)
        if format != CacheFormat::Exr {
            bad[at] ^= 0x01;
            let r = verify::verify(&asset, &enc.sidecar, &bad, None).unwrap();
            assert_eq!(r.mismatches, 1, "{rel} {format:?}");
            let m = r.first.unwrap();
            assert_eq!((m.frame, m.vertex), (n - 1, nv - 1));
            // Truncated: unreadable.
            let e = verify::verify(&asset, &enc.sidecar, &enc.cache[..at], None).unwrap_err();
            assert!(matches!(e, VerifyError::Cache(_)), "{e}");
        }
    }
}

#[test]
fn cesium_man_bakes_to_every_format() {
    check_character("gltf/CesiumMan.glb");
}

#[test]
fn fox_bakes_to_every_format() {
    check_character("gltf/Fox.glb");
}

#[test]
fn all_clips_follow_each_other_in_file_order() {
    let Some(asset) = load("gltf/Fox.glb") else {
        return;
    };
    let baked = bake::bake(&asset, &BakeRequest::default()).unwrap();
    let names: Vec<_> = baked.clips.iter().map(|c| c.name.as_str()).collect();
    let file: Vec<_> = asset.clips.iter().map(Clip::name).collect();
    assert_eq!(names, file);
    let mut next = 0;
    for c in &baked.clips {
        assert_eq!(c.first_frame, next);
        next += c.frame_count;
    }
    assert_eq!(baked.frames.frame_count, next);
}

#[test]
fn f16_exr_verifies_and_a_changed_pixel_is_found() {
    let Some(asset) = load("gltf/CesiumMan.glb") else {
        return;
    };
    let req = BakeRequest::default();
    let baked = bake::bake(&asset, &req).unwrap();
    let opts = CacheOptions {
        format: CacheFormat::Exr,
        max_width: 512,
        encoding: VatEncoding::OffsetF16,
        normals: NormalsPlacement::File,
    };
    let enc = verify::encode(&baked, &req, &opts, "m", "n.exr").unwrap();
    let normals = enc.normals.as_deref().unwrap();
    let p = parse_exr(&enc.cache);
    assert_eq!(p.len(), 1);
    assert!(p[0].4, "positions stored as f16");
    let nv = baked.frames.vertex_count;
    // Offset of vertex 7 in frame 3 equals the f16 of (skinned - bind).
    let rows = nv.div_ceil(512);
    let px = (3 * rows + 7 / 512) * 512 + 7 % 512;
    let d = baked.frames.positions[3 * nv + 7] - asset.meshes[0].lods[0].positions[7];
    assert_eq!(p[0].3[0][px], half::f16::from_f32(d.x).to_f32());
    let r = verify::verify(&asset, &enc.sidecar, &enc.cache, Some(normals)).unwrap();
    assert!(r.identical(), "{r:?}");
    assert_eq!(r.compared, 2 * nv * baked.frames.frame_count);
    // Re-encode with one offset nudged by one f16 step: verify names that frame and vertex.
    let mut moved = baked.clone();
    let i = 5 * nv + 11;
    moved.frames.positions[i].y += 0.01;
    let enc2 = verify::encode(&moved, &req, &opts, "m", "n.exr").unwrap();
    let r = verify::verify(&asset, &enc.sidecar, &enc2.cache, Some(normals)).unwrap();
    assert_eq!(r.mismatches, 1);
    let m = r.first.unwrap();
    assert_eq!((m.frame, m.vertex, m.what), (5, 11, "position"));
    // Truncated EXR: unreadable.
    let e = verify::verify(
        &asset,
        &enc.sidecar,
        &enc.cache[..enc.cache.len() / 2],
        Some(normals),
    )
    .unwrap_err();
    assert!(matches!(e, VerifyError::Cache(_)), "{e}");
}

#[test]
fn output_is_identical_for_one_and_four_threads() {
    let Some(asset) = load("gltf/Fox.glb") else {
        return;
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let req = BakeRequest::default();
            let b = bake::bake(&asset, &req).unwrap();
            let opts = CacheOptions {
                format: CacheFormat::Pc2,
                ..Default::default()
            };
            let pc2 = verify::encode(&b, &req, &opts, "f", "n").unwrap().cache;
            let exr = verify::encode(&b, &req, &CacheOptions::default(), "f", "n")
                .unwrap()
                .cache;
            (pc2, exr)
        })
    };
    let (a, b) = (run(1), run(4));
    assert!(a.0 == b.0, "PC2 bytes differ between 1 and 4 threads");
    assert!(a.1 == b.1, "EXR bytes differ between 1 and 4 threads");
}

#[test]
fn bad_requests_are_refused_with_the_names_that_exist() {
    let Some(asset) = load("gltf/Fox.glb") else {
        return;
    };
    let e = bake::bake(
        &asset,
        &BakeRequest {
            clips: vec!["Swim".into()],
            ..Default::default()
        },
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "no clip \"Swim\"; the file has: Survey, Walk, Run"
    );
    for fps in [0.0, -1.0, f32::NAN, 1000.5] {
        let e = bake::bake(
            &asset,
            &BakeRequest {
                fps: Some(fps),
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(matches!(e, BakeError::BadFps(..)), "{fps}: {e}");
    }
    let e = bake::bake(
        &asset,
        &BakeRequest {
            lod: 1,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, BakeError::NoLod { lod: 1, .. }), "{e}");
    let e = bake::bake(
        &asset,
        &BakeRequest {
            layers: vec![LayerSpec::parse("Walk@upper:0.5").unwrap()],
            ..Default::default()
        },
    )
    .unwrap_err();
    assert_eq!(e.to_string(), "no mask \"upper\"; the file has: (none)");
}

#[test]
fn layer_specs_parse() {
    assert_eq!(
        LayerSpec::parse("wave@upper:0.8").unwrap(),
        LayerSpec {
            clip: "wave".into(),
            mask: Some("upper".into()),
            weight: 0.8
        }
    );
    assert_eq!(LayerSpec::parse("walk").unwrap().weight, 1.0);
    assert!(LayerSpec::parse("walk:x").is_err());
    assert!(LayerSpec::parse("walk@:1").is_err());
    assert!(LayerSpec::parse("walk:-1").is_err());
}

#[test]
fn masked_layers_blend_through_the_file_masks() {
    let Some(mut asset) = load("gltf/Fox.glb") else {
        return;
    };
    let skel = asset.skeleton.clone().unwrap();
    // "none" weighs nothing; "all" weighs every joint 1.
    asset.masks = vec![
        Mask {
            name: "none".into(),
            weights: vec![],
        },
        Mask {
            name: "all".into(),
            weights: skel.names().iter().map(|n| (n.clone(), 1.0)).collect(),
        },
    ];
    let asset = format::read(&format::write(&asset).unwrap()).unwrap();
    let walk = bake::bake(
        &asset,
        &BakeRequest {
            clips: vec!["Walk".into()],
            ..Default::default()
        },
    )
    .unwrap();
    let run = bake::bake(
        &asset,
        &BakeRequest {
            clips: vec!["Run".into()],
            ..Default::default()
        },
    )
    .unwrap();
    let layered = |spec: &[&str]| {
        bake::bake(
            &asset,
            &BakeRequest {
                layers: spec.iter().map(|s| LayerSpec::parse(s).unwrap()).collect(),
                fps: Some(24.0),
                ..Default::default()
            },
        )
        .unwrap()
    };
    // A layer through the empty mask changes nothing: Walk alone (up to the normalisation).
    let a = layered(&["Walk", "Run@none:1"]);
    assert_eq!(a.frames.frame_count, walk.frames.frame_count);
    assert_eq!(a.clips[0].name, "Walk+Run");
    for (x, y) in a.frames.positions.iter().zip(&walk.frames.positions) {
        close(*x, *y, "Walk + Run@none");
    }
    // Run through the full mask at weight 1 blends half and half: differs from both.
    let b = layered(&["Walk", "Run@all:1"]);
    let v = walk.frames.vertex_count * 5 + 100;
    assert!((b.frames.positions[v] - walk.frames.positions[v]).length() > 1e-3);
    assert!((b.frames.positions[v] - run.frames.positions[v]).length() > 1e-3);
}

#[test]
fn masks_and_source_maps_round_trip_through_the_format_and_importer() {
    let Some(asset) = load("gltf/CesiumMan.glb") else {
        return;
    };
    let mut a = asset.clone();
    let nv = a.meshes[0].lods[0].vertex_count() as u32;
    // A map folding pairs of vertices onto one source vertex.
    a.source_vertex = vec![Some(SourceVertexMap {
        source_vertex_count: nv.div_ceil(2),
        map: (0..nv).map(|v| v / 2).collect(),
    })];
    a.masks = vec![Mask {
        name: "upper".into(),
        weights: vec![("Skeleton_torso_joint_1".into(), 0.5)],
    }];
    let bytes = format::write(&a).unwrap();
    let tags: Vec<_> = format::sections(&bytes)
        .unwrap()
        .iter()
        .map(|s| s.tag.to_string())
        .collect();
    assert!(
        tags.ends_with(&["SRCV".to_string(), "MASK".to_string(), "AXES".to_string()]),
        "{tags:?}"
    );
    assert_eq!(
        u16::from_le_bytes([bytes[10], bytes[11]]),
        6,
        "minor version (1.6: the file states its axes)"
    );
    let back = format::read(&bytes).unwrap();
    assert_eq!(back, a);
    // Through the .sinew importer and compile again.
    let scene = sinew_import::sinew::import(
        "a.sinew",
        &bytes,
        &|_| Err(std::io::ErrorKind::NotFound.into()),
        &Default::default(),
    )
    .unwrap();
    assert_eq!(scene.masks, a.masks);
    assert_eq!(scene.meshes[0].source_vertex_count, nv.div_ceil(2));
    let again = sinew_pipeline::compile::compile(&scene).unwrap();
    assert_eq!(again.source_vertex, a.source_vertex);
    assert_eq!(again.masks, a.masks);
    // Source order: vertex s of the bake is split vertex 2s.
    let split = bake::bake(&back, &BakeRequest::default()).unwrap();
    let src = bake::bake(
        &back,
        &BakeRequest {
            vertex_order: VertexOrder::Source,
            ..Default::default()
        },
    )
    .unwrap();
    let ns = nv.div_ceil(2) as usize;
    assert_eq!(src.frames.vertex_count, ns);
    for f in [0, 10] {
        for s in [0, 1, ns - 1] {
            assert_eq!(
                src.frames.positions[f * ns + s],
                split.frames.positions[f * nv as usize + 2 * s]
            );
        }
    }
    // Faces are remapped into source indices.
    assert_eq!(src.indices[0], back.meshes[0].lods[0].indices[0] / 2);
    // A map entry past the source count is refused by the writer.
    let mut bad = a.clone();
    bad.source_vertex[0].as_mut().unwrap().map[3] = nv;
    assert!(format::write(&bad).is_err());
    // Source order needs LOD 0 and a map.
    let e = bake::bake(
        &asset_without_map(&back),
        &BakeRequest {
            vertex_order: VertexOrder::Source,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, BakeError::SourceOrder(_)), "{e}");
}

fn asset_without_map(a: &Asset) -> Asset {
    Asset {
        source_vertex: vec![],
        ..a.clone()
    }
}

#[test]
fn ms3d_characters_bake_to_every_format() {
    check_character("ms3d/ninja.ms3d");
    check_character("ms3d/zombie.ms3d");
}

#[test]
fn ms3d_source_order_has_the_source_vertex_count() {
    let Some(asset) = load("ms3d/ninja.ms3d") else {
        return;
    };
    let map = asset.source_vertex(0).unwrap().clone();
    let req = BakeRequest {
        vertex_order: VertexOrder::Source,
        ..Default::default()
    };
    let src = bake::bake(&asset, &req).unwrap();
    let split = bake::bake(&asset, &BakeRequest::default()).unwrap();
    let ns = map.source_vertex_count as usize;
    let nv = split.frames.vertex_count;
    assert_eq!(src.frames.vertex_count, ns);
    // Each source vertex carries the values of the first split vertex made from it.
    for s in [0, ns / 2, ns - 1] {
        let v = map.map.iter().position(|&m| m as usize == s).unwrap();
        let f = src.frames.frame_count - 1;
        assert_eq!(
            src.frames.positions[f * ns + s],
            split.frames.positions[f * nv + v]
        );
    }
    let opts = CacheOptions {
        format: CacheFormat::Mdd,
        ..Default::default()
    };
    let enc = verify::encode(&src, &req, &opts, "ninja.ms3d", "n").unwrap();
    assert!(verify::verify(&asset, &enc.sidecar, &enc.cache, None)
        .unwrap()
        .identical());
}
