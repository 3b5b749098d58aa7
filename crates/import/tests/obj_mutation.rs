//! Truncations and thousands of random mutations of the corpus OBJ/MTL files never panic; every failure
//! is an error naming the file and a line. Deterministic (fixed seeds), bounded to a few seconds.
#![allow(clippy::unwrap_used)]

use sinew_import::{obj, ImportOptions, Location};
use sinew_testdata::read_corpus;

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const INTERESTING: &[&[u8]] = &[
    b"0",
    b"-",
    b"/",
    b"//",
    b"\n",
    b"\r",
    b" ",
    b"-1",
    b"99999999999",
    b"nan",
    b"inf",
    b"1e39",
    b"f ",
    b"f 1 2\n",
    b"l ",
    b"p ",
    b"g ",
    b"s off\n",
    b"s x\n",
    b"usemtl \n",
    b"mtllib \n",
    b"v 1 2\n",
    b"vt\n",
    b"vn 0 0 0\n",
    b"\xFE\xFF",
    b"\xFF\xFE",
    b"\xEF\xBB\xBF",
    b"\xC3",
    b"-0",
    b"Kd 1 2\n",
    b"newmtl\n",
    b"map_Kd\n",
    b"d\n",
];

fn mutate(rng: &mut Rng, input: &[u8]) -> Vec<u8> {
    let mut b = input.to_vec();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(b.len() + 1);
        match rng.below(5) {
            0 if !b.is_empty() && at < b.len() => b[at] ^= 1 << rng.below(8),
            1 if at < b.len() => {
                let end = (at + 1 + rng.below(16)).min(b.len());
                b.drain(at..end);
            }
            2 => {
                let ins = INTERESTING[rng.below(INTERESTING.len())];
                b.splice(at..at, ins.iter().copied());
            }
            3 if !b.is_empty() => {
                // Duplicate a slice (e.g. a line) somewhere else.
                let s = rng.below(b.len());
                let e = (s + 1 + rng.below(40)).min(b.len());
                let chunk = b[s..e].to_vec();
                b.splice(at..at, chunk);
            }
            _ => b.truncate(at),
        }
    }
    b
}

fn run(name: &str, obj: &[u8], mtl: Option<&[u8]>) {
    let mtl = mtl.map(<[u8]>::to_vec);
    let resolve = move |_: &str| mtl.clone().ok_or_else(|| std::io::Error::other("missing"));
    let r =
        std::panic::catch_unwind(|| obj::import(name, obj, &resolve, &ImportOptions::default()));
    match r {
        Err(_) => panic!(
            "panic on input ({} bytes): {:?}",
            obj.len(),
            String::from_utf8_lossy(obj)
        ),
        Ok(Err(e)) => {
            assert_eq!(e.file, name);
            assert!(
                matches!(e.location, Location::Line(_))
                    || e.message.contains("no faces")
                    || e.section == "encoding",
                "{e}"
            );
        }
        Ok(Ok(s)) => {
            for m in &s.meshes {
                let g = &m.geometry;
                assert!(g.indices.iter().all(|&i| (i as usize) < g.positions.len()));
                assert!(g.positions.iter().all(|p| p.is_finite()));
                assert!(g.normals.iter().all(|n| n.is_finite()));
            }
        }
    }
}

const FILES: &[(&str, Option<&str>)] = &[
    ("obj/cornell_box.obj", Some("obj/cornell_box.mtl")),
    (
        "obj/cube_mtllib_after_g.obj",
        Some("obj/cube_mtllib_after_g.mtl"),
    ),
    ("obj/testmixed.obj", None),
    ("obj/number_formats.obj", None),
    ("obj/skin-weight.obj", None),
    ("obj/box_UTF16BE.obj", None),
    ("obj/box_without_lineending.obj", None),
    ("obj/spider.obj", Some("obj/spider.mtl")),
];

#[test]
fn truncations_never_panic() {
    for (rel, mtl) in FILES {
        let Some(bytes) = read_corpus(rel) else {
            return;
        };
        let mtl = mtl.and_then(read_corpus);
        let step = (bytes.len() / 300).max(1);
        for cut in (0..bytes.len()).step_by(step) {
            run(rel, &bytes[..cut], mtl.as_deref());
            if let Some(m) = &mtl {
                run(rel, &bytes, Some(&m[..cut.min(m.len())]));
            }
        }
    }
}

#[test]
fn mutations_never_panic() {
    let start = std::time::Instant::now();
    let mut total = 0;
    for (fi, (rel, mtl)) in FILES.iter().enumerate() {
        let Some(bytes) = read_corpus(rel) else {
            return;
        };
        let mtl = mtl.and_then(read_corpus);
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15 ^ (fi as u64 + 1));
        let n = if bytes.len() > 10_000 { 150 } else { 600 };
        for _ in 0..n {
            let m = mutate(&mut rng, &bytes);
            let mm = mtl.as_ref().map(|x| mutate(&mut rng, x));
            run(rel, &m, mm.as_deref());
            total += 1;
        }
    }
    if total > 0 {
        assert!(total >= 4000, "{total}");
    }
    assert!(start.elapsed().as_secs() < 20, "took {:?}", start.elapsed());
}
