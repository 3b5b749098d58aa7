//! Memory bound of the readers: a file that declares huge counts must be refused having allocated a few
//! megabytes at most, whatever count it lies about. Every reader is run in this process under a counting
//! allocator on small real files in which, one at a time, every 16- and 32-bit word of the first bytes
//! (every word after that, every 4th offset) is set to a huge value, and on hand-made text files that
//! declare huge frame counts and frame numbers. docs/reliability.md states the bound.
#![allow(clippy::unwrap_used, unsafe_code)]

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Counts live heap bytes and their high-water mark since the last [`reset_peak`].
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is forwarded to the system allocator unchanged; only counters are added.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let live = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(live, Ordering::Relaxed);
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            let live = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(live, Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size >= layout.size() {
                let grow = new_size - layout.size();
                let live = LIVE.fetch_add(grow, Ordering::Relaxed) + grow;
                PEAK.fetch_max(live, Ordering::Relaxed);
            } else {
                LIVE.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
            }
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// One measurement at a time: the counters are global.
static SERIAL: Mutex<()> = Mutex::new(());

/// Peak heap bytes above what was live before `f` ran.
fn peak_of(f: impl FnOnce()) -> usize {
    let before = LIVE.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    f();
    PEAK.load(Ordering::Relaxed).saturating_sub(before)
}

/// The bound docs/reliability.md states for a refused or accepted input of `n` bytes: 4 MiB plus 64
/// bytes per input byte (decoded meshes and clips are larger than the bytes that hold them).
fn bound(n: usize) -> usize {
    (4 << 20) + 64 * n
}

/// The EXR reader is the exr crate's, which sizes its buffers from the header: sinew refuses a header
/// declaring more pixel bytes than deflate (at most 1,032 to 1) could have packed into the file, so the
/// bound grows with that ratio (docs/reliability.md).
fn exr_bound(n: usize) -> usize {
    (16 << 20) + 4 * 1032 * n
}

type Read = dyn Fn(&[u8]);

fn import_as(format: sinew_import::Format, name: &'static str) -> Box<Read> {
    Box::new(move |bytes: &[u8]| {
        let none = |_: &str| -> std::io::Result<Vec<u8>> { Err(std::io::Error::other("none")) };
        // Companions are absent: read on past them, so every table is reached.
        let options = sinew_import::ImportOptions {
            allow_missing: true,
            ..Default::default()
        };
        let _ = sinew_import::import_bytes(format, name, bytes, &none, &options);
    })
}

/// Every huge-count mutation of `bytes`; returns (mutations, worst peak, its offset).
fn sweep(label: &str, bytes: &[u8], read: &Read) -> (usize, usize, usize) {
    sweep_within(label, bytes, read, bound)
}

fn sweep_within(
    label: &str,
    bytes: &[u8],
    read: &Read,
    bound: fn(usize) -> usize,
) -> (usize, usize, usize) {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let mut offsets: Vec<usize> = (0..bytes.len().min(1024)).collect();
    offsets.extend((1024..bytes.len().min(64 * 1024)).step_by(4));
    let mut runs = 0;
    let mut worst = (0, 0);
    let mut copy = bytes.to_vec();
    for &at in &offsets {
        for (width, value) in [
            (2, 0xFFFF_u32),
            (2, 0x7FFF),
            (4, 0x7FFF_FFFF),
            (4, 0xFFFF_FFFF),
            (4, 0x4000_0000),
        ] {
            if at + width > copy.len() {
                continue;
            }
            copy[at..at + width].copy_from_slice(&value.to_le_bytes()[..width]);
            let peak = peak_of(|| read(&copy));
            copy[at..at + width].copy_from_slice(&bytes[at..at + width]);
            runs += 1;
            if peak > worst.0 {
                worst = (peak, at);
            }
            assert!(
                peak <= bound(bytes.len()),
                "{label}: {value:#x} at byte {at} made the reader allocate {peak} bytes (bound {})",
                bound(bytes.len())
            );
        }
    }
    eprintln!(
        "{label}: {} bytes, {runs} mutations, worst peak {} KiB (offset {})",
        bytes.len(),
        worst.0 >> 10,
        worst.1
    );
    (runs, worst.0, worst.1)
}

fn fixture(rel: &str) -> Vec<u8> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn binary_readers_refuse_huge_counts_within_the_bound() {
    use sinew_import::Format;
    let (runs, _, _) = sweep(
        "ms3d",
        &fixture("fixtures/ms3d/biped_root_motion.ms3d"),
        &*import_as(Format::Ms3d, "m.ms3d"),
    );
    assert!(runs > 5 * 1000, "{runs}");
    sweep(
        ".sinew",
        &fixture("fixtures/biped.sinew"),
        &*import_as(Format::Sinew, "m.sinew"),
    );
    let rig = sinew_fixtures::mdl::rig_files();
    // The sequence-group file is not offered: the reader must refuse without it, within the bound.
    sweep("mdl", &rig[0].1, &*import_as(Format::Mdl, "rig.mdl"));
}

#[test]
fn cache_readers_refuse_huge_counts_within_the_bound() {
    use sinew_core::glam::Vec3;
    use sinew_pipeline::cache::{mdd, pc2, Frames};
    let vertex_count = 50;
    let frame_count = 20;
    let frames = Frames {
        vertex_count,
        frame_count,
        fps: 30.0,
        positions: (0..vertex_count * frame_count)
            .map(|i| Vec3::new(i as f32, 1.0, 2.0))
            .collect(),
        normals: Vec::new(),
    };
    let pc2_bytes = pc2::write(&frames);
    let (_, read) = pc2::read(&pc2_bytes).unwrap();
    assert_eq!(read.positions[77], Vec3::new(77.0, 1.0, 2.0));
    sweep("pc2", &pc2_bytes, &|b: &[u8]| {
        let _ = pc2::read(b);
    });
    sweep("mdd", &mdd::write(&frames), &|b: &[u8]| {
        let _ = mdd::read(b);
    });
}

#[test]
fn exr_reader_refuses_huge_sizes_within_the_bound() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("wave.exr");
    let run = common::sinew([
        "bake".as_ref(),
        fixture_path("fixtures/biped.sinew").as_os_str(),
        "--clip".as_ref(),
        "wave".as_ref(),
        "--format".as_ref(),
        "exr".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let bytes = std::fs::read(&out).unwrap();
    assert!(sinew_pipeline::cache::vat::read_exr(&bytes).is_ok());
    sweep_within(
        "exr",
        &bytes,
        &|b: &[u8]| {
            let _ = sinew_pipeline::cache::vat::read_exr(b);
        },
        exr_bound,
    );
}

fn fixture_path(rel: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel)
}

/// Text files declaring huge counts: BVH frames, SMD frame numbers, OBJ indices, QC frame ranges,
/// glTF accessor and sparse counts and GLB chunk lengths.
#[test]
fn text_and_json_readers_refuse_huge_counts_within_the_bound() {
    use sinew_import::Format;
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let bvh = "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition \
               Zrotation Xrotation Yrotation\n End Site\n {\n  OFFSET 0 1 0\n }\n}\nMOTION\n\
               Frames: 4000000000\nFrame Time: 0.033\n0 0 0 0 0 0\n";
    let smd_frames = "version 1\nnodes\n0 \"root\" -1\nend\nskeleton\ntime 0\n0 0 0 0 0 0 0\n\
                      time 2000000000\n0 0 0 0 0 0 0\nend\n";
    let smd_node = "version 1\nnodes\n2000000000 \"root\" -1\nend\nskeleton\ntime 0\n\
                    2000000000 0 0 0 0 0 0\nend\n";
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4000000000\nf -4000000000 1 2\n";
    let accessor = r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":12,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAA"}],
        "bufferViews":[{"buffer":0,"byteLength":12}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":4000000000,"type":"VEC3","min":[0,0,0],"max":[1,1,1]}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}]}"#;
    let sparse = r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":12,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAA"}],
        "bufferViews":[{"buffer":0,"byteLength":12}],
        "accessors":[{"componentType":5126,"count":1,"type":"VEC3","min":[0,0,0],"max":[1,1,1],
          "sparse":{"count":2000000000,"indices":{"bufferView":0,"componentType":5125},"values":{"bufferView":0}}}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}]}"#;
    let mut glb = b"glTF".to_vec();
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&0xFFFF_FFF0u32.to_le_bytes());
    glb.extend_from_slice(&0xFFFF_FF00u32.to_le_bytes());
    glb.extend_from_slice(b"JSON{}");
    let cases: Vec<(&str, Format, &str, Vec<u8>)> = vec![
        ("bvh frames", Format::Bvh, "m.bvh", bvh.into()),
        ("smd frame number", Format::Smd, "m.smd", smd_frames.into()),
        ("smd node number", Format::Smd, "m.smd", smd_node.into()),
        ("obj index", Format::Obj, "m.obj", obj.into()),
        (
            "gltf accessor count",
            Format::Gltf,
            "m.gltf",
            accessor.into(),
        ),
        ("gltf sparse count", Format::Gltf, "m.gltf", sparse.into()),
        ("glb lengths", Format::Gltf, "m.glb", glb),
    ];
    for (label, format, name, bytes) in cases {
        let read = import_as(format, name);
        let peak = peak_of(|| read(&bytes));
        eprintln!("{label}: peak {} KiB", peak >> 10);
        assert!(peak <= 4 << 20, "{label}: {peak} bytes");
    }
    // A QC asking for a frame range far past its SMD's frames.
    let qc = "$modelname \"m.mdl\"\n$body studio \"ref\"\n\
              $sequence idle \"ref\" frame 0 2000000000 fps 30\n";
    let reference = "version 1\nnodes\n0 \"root\" -1\nend\nskeleton\ntime 0\n0 0 0 0 0 0 0\nend\n\
                     triangles\nskin.bmp\n0 0 0 0 0 0 1 0 0\n0 1 0 0 0 0 1 1 0\n0 0 1 0 0 0 1 0 1\nend\n";
    let resolve = |_: &str| -> std::io::Result<Vec<u8>> { Ok(reference.as_bytes().to_vec()) };
    let peak = peak_of(|| {
        let _ = sinew_import::import_bytes(
            Format::Qc,
            "m.qc",
            qc.as_bytes(),
            &resolve,
            &sinew_import::ImportOptions::default(),
        );
    });
    eprintln!("qc frame range: peak {} KiB", peak >> 10);
    assert!(peak <= 4 << 20, "qc frame range: {peak} bytes");
}

/// EXR inputs the fuzzer found (fuzz/regressions/exr): refused, within the bound.
#[test]
fn exr_fuzz_regressions_are_refused_within_the_bound() {
    let dir = fixture_path("fuzz/regressions/exr");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap().flatten() {
        let bytes = std::fs::read(entry.path()).unwrap();
        let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
        let mut result = None;
        let peak = peak_of(|| result = Some(sinew_pipeline::cache::vat::read_exr(&bytes)));
        let e = result.unwrap().unwrap_err();
        eprintln!("{}: {e}; peak {} KiB", entry.path().display(), peak >> 10);
        assert!(peak <= bound(bytes.len()), "{peak}");
        seen += 1;
    }
    assert!(seen >= 1);
}
