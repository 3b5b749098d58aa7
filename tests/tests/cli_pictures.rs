//! `sinew preview` and `sinew map --png` end to end: the PNG decodes, has the documented size, is not
//! blank, is the same bytes on every run, and matches committed golden pictures within a small
//! tolerance. Regenerate the goldens with `SINEW_BLESS=1` (and look at them before committing).
#![allow(clippy::unwrap_used)]

use crate::common;
use common::{assert_one_line_error, sinew};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// Decoded RGB pixels: (width, height, bytes).
fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
    let file = std::fs::File::open(path).unwrap();
    let mut r = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Asserts the picture is not blank: many colours, and more than `min_share` of the pixels differ
/// from the top-left (background) pixel.
fn assert_not_blank(pixels: &[u8], label: &str, min_share: f64) {
    let colours: HashSet<[u8; 3]> = pixels.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    assert!(
        colours.len() > 50,
        "{label}: only {} colours",
        colours.len()
    );
    let bg = &pixels[0..3];
    let differ = pixels.chunks_exact(3).filter(|p| *p != bg).count();
    let share = differ as f64 / (pixels.len() / 3) as f64;
    assert!(
        share > min_share,
        "{label}: only {share} of pixels differ from the background"
    );
}

fn count(pixels: &[u8], c: [u8; 3]) -> usize {
    pixels.chunks_exact(3).filter(|p| *p == c).count()
}

fn run_ok(args: &[&std::ffi::OsStr]) -> serde_json::Value {
    let r = sinew(args);
    assert_eq!(r.code, 0, "{:?}: {}", args, r.stderr);
    serde_json::from_str(&r.stdout).unwrap()
}

fn fixture(name: &str) -> PathBuf {
    sinew_testdata::fixtures().join(name)
}

fn golden(name: &str) -> PathBuf {
    sinew_testdata::workspace_root()
        .join("tests/golden")
        .join(name)
}

/// Compares with a golden picture: same size, and at most 0.5% of pixels differ by more than 8 in
/// some channel. With `SINEW_BLESS=1` the golden is rewritten instead.
fn assert_golden(made: &Path, name: &str) {
    let g = golden(name);
    if std::env::var_os("SINEW_BLESS").is_some() {
        std::fs::create_dir_all(g.parent().unwrap()).unwrap();
        std::fs::copy(made, &g).unwrap();
        return;
    }
    let (w, h, a) = decode(made);
    let (gw, gh, b) = decode(&g);
    assert_eq!((w, h), (gw, gh), "{name}: size");
    let off = a
        .chunks_exact(3)
        .zip(b.chunks_exact(3))
        .filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| x.abs_diff(*y) > 8))
        .count();
    let share = off as f64 / f64::from(w * h);
    assert!(
        share <= 0.005,
        "{name}: {share} of pixels differ from the golden picture"
    );
}

#[test]
fn preview_of_the_biped_has_the_documented_layout_and_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("biped.png");
    let args = |o: &Path| -> Vec<std::ffi::OsString> {
        vec![
            "preview".into(),
            fixture("biped.sinew").into(),
            "--lod".into(),
            "0.5,0.25".into(),
            "-o".into(),
            o.into(),
            "--json".into(),
        ]
    };
    let a: Vec<std::ffi::OsString> = args(&out);
    let r = run_ok(&a.iter().map(|s| s.as_os_str()).collect::<Vec<_>>());
    // Two rest views + two LODs = 4 columns; the 6-pose clip strips make it 6; 1 + 2 clip rows.
    assert_eq!(
        (r["columns"].as_u64(), r["rows"].as_u64()),
        (Some(6), Some(3))
    );
    assert_eq!(
        (r["width"].as_u64(), r["height"].as_u64()),
        (Some(6 * 256), Some(30 + 3 * 274 + 16))
    );
    let (w, h, px) = decode(&out);
    assert_eq!((w, h), (1536, 868));
    assert_not_blank(&px, "biped preview", 0.2);
    // The skeleton is drawn: bone orange and joint yellow pixels are there.
    assert!(count(&px, [235, 120, 20]) > 100);
    assert!(count(&px, [255, 210, 40]) > 50);
    // LODs: fewer triangles than LOD 0, a positive measured error that grows along the chain.
    let lods = r["lods"].as_array().unwrap();
    assert_eq!(lods.len(), 2);
    assert!(lods[0]["triangles"].as_u64().unwrap() < r["triangles"].as_u64().unwrap());
    let e1 = lods[0]["error_measured"].as_f64().unwrap();
    let e2 = lods[1]["error_measured"].as_f64().unwrap();
    assert!(e1 > 0.0 && e2 >= e1, "{e1} {e2}");
    assert_eq!(r["clips"][0]["clip"], "walk");
    assert_eq!(r["clips"][0]["times"].as_array().unwrap().len(), 6);
    // Same bytes on another run.
    let again = dir.path().join("again.png");
    let b: Vec<std::ffi::OsString> = args(&again);
    run_ok(&b.iter().map(|s| s.as_os_str()).collect::<Vec<_>>());
    assert!(std::fs::read(&out).unwrap() == std::fs::read(&again).unwrap());
}

#[test]
fn preview_goldens() {
    let dir = tempfile::tempdir().unwrap();
    let biped = dir.path().join("biped.png");
    let r = run_ok(&[
        "preview".as_ref(),
        fixture("biped.gltf").as_os_str(),
        "--clip".as_ref(),
        "wave".as_ref(),
        "--frames".as_ref(),
        "3".as_ref(),
        "--names".as_ref(),
        "-o".as_ref(),
        biped.as_os_str(),
        "--json".as_ref(),
    ]);
    assert_eq!(r["clips"].as_array().unwrap().len(), 1);
    assert_eq!(
        (r["width"].as_u64(), r["height"].as_u64()),
        (Some(768), Some(30 + 2 * 274 + 16))
    );
    assert_golden(&biped, "preview_biped_wave.png");
    let prop = dir.path().join("prop.png");
    let r = run_ok(&[
        "preview".as_ref(),
        fixture("prop.obj").as_os_str(),
        "--lod".as_ref(),
        "0.5".as_ref(),
        "-o".as_ref(),
        prop.as_os_str(),
        "--json".as_ref(),
    ]);
    assert_eq!(r["rows"], 1);
    let (_, _, px) = decode(&prop);
    assert_not_blank(&px, "prop preview", 0.2);
    assert_golden(&prop, "preview_prop.png");
}

#[test]
fn map_png_of_two_fixtures_matches_its_golden() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("map.png");
    let r = run_ok(&[
        "map".as_ref(),
        fixture("biped.sinew").as_os_str(),
        fixture("biped.gltf").as_os_str(),
        "--png".as_ref(),
        out.as_os_str(),
        "--json".as_ref(),
    ]);
    let warnings = r["warnings"].as_array().unwrap().len() as u64;
    assert_eq!(r["picture"]["width"], 1200);
    assert_eq!(
        r["picture"]["height"].as_u64().unwrap(),
        52 + 600 + 16 * (3 + warnings) + 12
    );
    assert_eq!(r["picture"]["lines"], 22);
    assert_eq!(r["picture"]["unmatched"], 0);
    let (w, h, px) = decode(&out);
    assert_eq!(
        (w, h),
        (1200, r["picture"]["height"].as_u64().unwrap() as u32)
    );
    assert!(
        count(&px, [40, 160, 70]) > 500,
        "exact-match lines are green"
    );
    assert_golden(&out, "map_biped_biped.png");
}

#[test]
fn map_png_shows_unmatched_joints_in_red() {
    let Some(bvh) = sinew_testdata::corpus_file("bvh/cmu_walk_crlf.bvh") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("map.png");
    let r = run_ok(&[
        "map".as_ref(),
        fixture("biped.sinew").as_os_str(),
        bvh.as_os_str(),
        "--png".as_ref(),
        out.as_os_str(),
        "--json".as_ref(),
    ]);
    let unmatched = r["unmatched_rig"].as_array().unwrap().len()
        + r["unmatched_motion"].as_array().unwrap().len();
    assert_eq!(
        r["picture"]["unmatched"].as_u64().unwrap() as usize,
        unmatched
    );
    assert_eq!(
        r["picture"]["lines"].as_u64().unwrap(),
        r["bound"].as_u64().unwrap()
    );
    let (_, _, px) = decode(&out);
    // Thin lines on a plain ground: a few percent of the pixels.
    assert_not_blank(&px, "map", 0.03);
    assert!(count(&px, [220, 40, 40]) > 100, "unmatched joints are red");
    assert!(count(&px, [50, 100, 220]) > 100, "synonym lines are blue");
}

#[test]
fn previews_of_corpus_models_are_quick_and_deterministic() {
    let files = [
        "gltf/CesiumMan.glb",
        "gltf/Fox.glb",
        "ms3d/zombie.ms3d",
        "ms3d/jeep1.ms3d",
        "mdl/man.mdl",
        "obj/spot.obj",
        "bvh/cmu_walk_crlf.bvh",
        "gltf/magnum/empty.glb",
    ];
    let dir = tempfile::tempdir().unwrap();
    for f in files {
        let Some(path) = sinew_testdata::corpus_file(f) else {
            return;
        };
        let a = dir.path().join("a.png");
        let b = dir.path().join("b.png");
        let start = std::time::Instant::now();
        run_ok(&[
            "preview".as_ref(),
            path.as_os_str(),
            "-o".as_ref(),
            a.as_os_str(),
            "--json".as_ref(),
        ]);
        let took = start.elapsed().as_secs_f64();
        // Well under a second on a quiet machine (docs/cli.md lists the times); generous here
        // because tests share the machine.
        assert!(took < 5.0, "{f}: {took} s");
        run_ok(&[
            "preview".as_ref(),
            path.as_os_str(),
            "-o".as_ref(),
            b.as_os_str(),
            "--json".as_ref(),
        ]);
        assert!(
            std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
            "{f}: bytes differ"
        );
        let (_, _, px) = decode(&a);
        if f != "gltf/magnum/empty.glb" {
            assert_not_blank(&px, f, 0.1);
        }
    }
}

#[test]
fn bad_picture_arguments_exit_2_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.jpg");
    let r = sinew([
        "preview".as_ref(),
        fixture("biped.sinew").as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_one_line_error(&r, &out);
    let png = dir.path().join("x.png");
    let input = fixture("biped.sinew");
    let r = sinew([
        "preview".as_ref(),
        input.as_os_str(),
        "--clip".as_ref(),
        "nope".as_ref(),
        "-o".as_ref(),
        png.as_os_str(),
    ]);
    assert_one_line_error(&r, &input);
    assert!(r.stderr.contains("nope") && r.stderr.contains("walk"));
    assert!(!png.exists());
    let r = sinew([
        "preview".as_ref(),
        input.as_os_str(),
        "--frames".as_ref(),
        "0".as_ref(),
        "-o".as_ref(),
        png.as_os_str(),
    ]);
    assert_one_line_error(&r, &input);
    let r = sinew([
        "map".as_ref(),
        input.as_os_str(),
        fixture("biped.gltf").as_os_str(),
        "--png".as_ref(),
        out.as_os_str(),
    ]);
    assert_one_line_error(&r, &out);
}

#[test]
fn bake_preview_draws_the_written_cache() {
    let dir = tempfile::tempdir().unwrap();
    let mut outputs = Vec::new();
    for (name, format) in [("a", "pc2"), ("b", "pc2"), ("c", "exr")] {
        // The same file names in separate folders: the title names the cache file.
        let sub = dir.path().join(name);
        std::fs::create_dir(&sub).unwrap();
        let cache = sub.join(format!("walk.{format}"));
        let png = sub.join("walk.png");
        let r = run_ok(&[
            "bake".as_ref(),
            fixture("biped.sinew").as_os_str(),
            "--clip".as_ref(),
            "wave".as_ref(),
            "--format".as_ref(),
            format.as_ref(),
            "-o".as_ref(),
            cache.as_os_str(),
            "--preview".as_ref(),
            png.as_os_str(),
            "--json".as_ref(),
        ]);
        assert_eq!(
            r["preview"]["frames"],
            serde_json::json!([0, 6, 12, 18, 24, 30])
        );
        assert!(r["outputs"]
            .as_array()
            .unwrap()
            .iter()
            .any(|o| o.as_str() == png.to_str()));
        let (w, h, px) = decode(&png);
        assert_eq!((w, h), (6 * 256, 30 + 18 + 256 + 8));
        assert_not_blank(&px, "bake preview", 0.1);
        outputs.push(std::fs::read(&png).unwrap());
    }
    assert!(outputs[0] == outputs[1], "same bytes on another run");
    // The f16 offsets of the EXR draw (almost) the same picture as the exact PC2 floats.
    assert_eq!(outputs[0].len() > 1000, outputs[2].len() > 1000);
    let r = sinew([
        "bake".as_ref(),
        fixture("biped.sinew").as_os_str(),
        "--format".as_ref(),
        "pc2".as_ref(),
        "-o".as_ref(),
        dir.path().join("d.pc2").as_os_str(),
        "--preview".as_ref(),
        dir.path().join("d.gif").as_os_str(),
    ]);
    assert_one_line_error(&r, &dir.path().join("d.gif"));
    assert!(
        !dir.path().join("d.pc2").exists(),
        "nothing written on a bad --preview"
    );
}

#[test]
fn preview_draws_the_default_body_or_the_one_asked_for() {
    let Some(man) = sinew_testdata::corpus_file("mdl/man.mdl") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("man.png");
    let shown = |extra: &[&str]| {
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "preview".as_ref(),
            man.as_os_str(),
            "--clip".as_ref(),
            "walk".as_ref(),
            "-o".as_ref(),
            out.as_os_str(),
            "--json".as_ref(),
        ];
        args.extend(extra.iter().map(|s| std::ffi::OsStr::new(*s)));
        let r = run_ok(&args);
        (r["meshes"].clone(), r["triangles"].as_u64().unwrap())
    };
    assert_eq!(
        shown(&[]),
        (
            serde_json::json!(["studio/reference_headless", "heads/reference_head1"]),
            60 + 12
        )
    );
    assert_eq!(
        shown(&["--body", "1"]),
        (
            serde_json::json!(["studio/reference_headless", "heads/reference_head2"]),
            60 + 6
        )
    );
    assert_eq!(
        shown(&["--mesh", "3"]).0,
        serde_json::json!(["heads/reference_head3"])
    );
}

/// Columns of a cell (col, row 0 of a contact sheet) holding any pixel other than the cell's
/// background.
fn silhouette_width(px: &[u8], width: u32, col: u32) -> usize {
    let (x0, y0, size) = (col * 256 + 2, 30 + 18, 252u32);
    let at = |x: u32, y: u32| {
        let i = ((y * width + x) * 3) as usize;
        [px[i], px[i + 1], px[i + 2]]
    };
    // The cell's own background, from its top-left pixel.
    let bg = at(x0 + 1, y0 + 1);
    (x0..x0 + size)
        .filter(|&x| (y0 + 20..y0 + size).any(|y| at(x, y) != bg))
        .count()
}

#[test]
fn front_is_front_by_the_files_own_axes() {
    // The biped faces +Z (glTF's convention): seen from the front its arms spread wide, from the
    // side it is narrow. No --up given.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("biped.png");
    let r = run_ok(&[
        "preview".as_ref(),
        fixture("biped.sinew").as_os_str(),
        "--clip".as_ref(),
        "walk".as_ref(),
        "--frames".as_ref(),
        "2".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
        "--json".as_ref(),
    ]);
    assert_eq!(
        r["axes"],
        serde_json::json!({"up": "+y", "forward": "+z", "bind_forward": "+z", "from": "file"})
    );
    let (w, _, px) = decode(&out);
    let (front, side) = (silhouette_width(&px, w, 0), silhouette_width(&px, w, 1));
    assert!(front > 2 * side, "front {front} px wide, side {side}");
    // A Half-Life model states Z up, facing +X as it plays and -Y in its bind pose, and draws with
    // its textures (man.mdl: five materials with images).
    let Some(man) = sinew_testdata::corpus_file("mdl/man.mdl") else {
        return;
    };
    let out = dir.path().join("man.png");
    let r = run_ok(&[
        "preview".as_ref(),
        man.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--json".as_ref(),
    ]);
    assert_eq!(
        r["axes"],
        serde_json::json!({"up": "+z", "forward": "+x", "bind_forward": "-y", "from": "file"})
    );
    assert_eq!(r["textured_materials"], 5);
    // --up overrides the file, with that axis's convention for both poses.
    let r = run_ok(&[
        "preview".as_ref(),
        man.as_os_str(),
        "--up".as_ref(),
        "z".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
        "--json".as_ref(),
    ]);
    assert_eq!(r["axes"]["from"], "--up");
    assert_eq!(r["axes"]["bind_forward"], "+x");
}

#[test]
fn gltf_images_stored_inside_the_file_are_drawn_and_exported() {
    // CesiumMan stores a JPEG in a buffer view, Fox a PNG: both are found, decoded and drawn, and the
    // export embeds them instead of noting them as missing.
    let dir = tempfile::tempdir().unwrap();
    for (file, mime) in [
        ("gltf/CesiumMan.glb", "image/jpeg"),
        ("gltf/Fox.glb", "image/png"),
    ] {
        let Some(path) = sinew_testdata::corpus_file(file) else {
            return;
        };
        let png = dir.path().join("p.png");
        let r = run_ok(&[
            "preview".as_ref(),
            path.as_os_str(),
            "--frames".as_ref(),
            "1".as_ref(),
            "-o".as_ref(),
            png.as_os_str(),
            "--json".as_ref(),
        ]);
        assert_eq!(r["textured_materials"], 1, "{file}");
        let gltf = dir.path().join("e.gltf");
        let r = run_ok(&[
            "export".as_ref(),
            path.as_os_str(),
            "-o".as_ref(),
            gltf.as_os_str(),
            "--json".as_ref(),
        ]);
        assert_eq!(r["images"], 1, "{file}: {r}");
        let doc: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&gltf).unwrap()).unwrap();
        assert_eq!(doc["images"][0]["mimeType"], mime, "{file}");
        // The embedded bytes are the source's image, decodable.
        let bytes = std::fs::read(&path).unwrap();
        let found = sinew_import::gltf::embedded_images(file, &bytes, &|_: &str| {
            Err(std::io::Error::other("no files"))
        })
        .unwrap();
        assert_eq!(found.len(), 1);
        let img = sinew_pipeline::texture::decode_image("x", &found[0].1).unwrap();
        assert!(img.width >= 64 && img.height >= 64, "{file}");
        // Damaged image bytes decode to nothing, without a panic.
        for cut in [10, found[0].1.len() / 3] {
            let _ = sinew_pipeline::texture::decode_image("x", &found[0].1[..cut]);
        }
    }
}
