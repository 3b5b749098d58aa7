//! Truncations and thousands of random mutations of the corpus BVH files never panic; every failure is
//! an error naming the file and (nearly always) a line. Deterministic, bounded to a few seconds.
#![allow(clippy::unwrap_used)]

use sinew_import::{bvh, ImportOptions, Location};
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
    b"\n",
    b"\r\n",
    b" ",
    b"\t",
    b"{",
    b"}",
    b"}\n",
    b"{\n",
    b"nan",
    b"inf",
    b"1e400",
    b"99999999999999999999",
    b"End Site\n",
    b"JOINT x\n",
    b"ROOT y\n",
    b"MOTION\n",
    b"CHANNELS 7 ",
    b"Xrotation ",
    b"Yposition ",
    b"OFFSET 1 2\n",
    b"Frames: 4000000000\n",
    b"Frame Time: 0\n",
    b"\xFE\xFF",
    b"\xEF\xBB\xBF",
    b"\xC3",
];

fn mutate(rng: &mut Rng, input: &[u8]) -> Vec<u8> {
    let mut b = input.to_vec();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(b.len() + 1);
        match rng.below(5) {
            0 if at < b.len() => b[at] ^= 1 << rng.below(8),
            1 if at < b.len() => {
                let end = (at + 1 + rng.below(16)).min(b.len());
                b.drain(at..end);
            }
            2 => {
                let ins = INTERESTING[rng.below(INTERESTING.len())];
                b.splice(at..at, ins.iter().copied());
            }
            3 if !b.is_empty() => {
                let s = rng.below(b.len());
                let e = (s + 1 + rng.below(60)).min(b.len());
                let chunk = b[s..e].to_vec();
                b.splice(at..at, chunk);
            }
            _ => b.truncate(at),
        }
    }
    b
}

fn run(name: &str, bytes: &[u8]) {
    let r = std::panic::catch_unwind(|| {
        bvh::import(
            name,
            bytes,
            &|_| Err(std::io::Error::other("no")),
            &ImportOptions::default(),
        )
    });
    match r {
        Err(_) => panic!("panic on input: {:?}", String::from_utf8_lossy(bytes)),
        Ok(Err(e)) => {
            assert_eq!(e.file, name);
            assert!(
                matches!(e.location, Location::Line(_))
                    || e.section == "HIERARCHY"
                    || e.section == "MOTION",
                "{e}"
            );
        }
        Ok(Ok(s)) => {
            let sk = s.skeleton.as_ref().unwrap();
            assert!(!sk.is_empty());
            for c in &s.clips {
                assert!(c.duration.is_finite() && c.sample_rate.is_finite());
                for t in &c.tracks {
                    assert!(t.rotation.values.iter().all(|q| q.is_finite()));
                    assert!(t.translation.values.iter().all(|v| v.is_finite()));
                }
            }
        }
    }
}

/// The small files, plus the first part of a CMU file (hierarchy and 40 frames) to keep runs short.
fn inputs() -> Option<Vec<(&'static str, Vec<u8>)>> {
    let mut v = Vec::new();
    for rel in [
        "bvh/test_simple.bvh",
        "bvh/sinusoidal_xyz.bvh",
        "bvh/pfnn_hierarchy_crlf.bvh",
    ] {
        v.push((rel, read_corpus(rel)?));
    }
    let walk = read_corpus("bvh/cmu_walk_crlf.bvh")?;
    let text = String::from_utf8(walk).unwrap();
    let head: Vec<&str> = text.split_inclusive('\n').collect();
    let motion = head.iter().position(|l| l.trim() == "MOTION").unwrap();
    let mut cut: String = head[..motion + 3 + 40].concat();
    cut = cut.replacen("Frames: 344", "Frames: 40", 1);
    v.push(("bvh/cmu_walk_crlf.bvh", cut.into_bytes()));
    Some(v)
}

#[test]
fn truncations_never_panic() {
    let Some(files) = inputs() else { return };
    for (rel, bytes) in &files {
        let step = (bytes.len() / 400).max(1);
        for cut in (0..bytes.len()).step_by(step) {
            run(rel, &bytes[..cut]);
        }
        // A cut inside the hierarchy is always an error.
        let motion = String::from_utf8_lossy(bytes).find("MOTION").unwrap();
        for cut in (0..motion).step_by(step) {
            assert!(bvh::import(
                rel,
                &bytes[..cut],
                &|_| Err(std::io::Error::other("no")),
                &ImportOptions::default()
            )
            .is_err());
        }
    }
}

#[test]
fn mutations_never_panic() {
    let Some(files) = inputs() else { return };
    let start = std::time::Instant::now();
    let mut total = 0;
    for (fi, (rel, bytes)) in files.iter().enumerate() {
        let mut rng = Rng(0xD1B5_4A32_D192_ED03 ^ (fi as u64 + 1));
        for _ in 0..1200 {
            run(rel, &mutate(&mut rng, bytes));
            total += 1;
        }
    }
    assert_eq!(total, 4800);
    assert!(start.elapsed().as_secs() < 20, "took {:?}", start.elapsed());
}
