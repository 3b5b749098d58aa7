//! The GoldSrc MDL reader never panics on damaged input: truncations at every byte of the corpus files
//! and of their companions, boundary integers written over every aligned word, and thousands of random
//! bit flips. Every failure is an error naming the damaged file and a byte offset; every success holds
//! only indices that are in range. Deterministic (fixed seeds), a few seconds in release builds.
#![allow(clippy::unwrap_used)]

use sinew_import::halflife::mdl;
use sinew_import::halflife::model::StudioModel;
use sinew_import::{ImportError, Location};
use std::collections::HashMap;

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

/// A set of files: the main one and the companions the resolver may hand out.
struct Files {
    main: &'static str,
    bytes: HashMap<&'static str, Vec<u8>>,
}

fn load(main: &'static str, companions: &[&'static str]) -> Option<Files> {
    let mut bytes = HashMap::new();
    for name in std::iter::once(&main).chain(companions) {
        bytes.insert(*name, sinew_testdata::read_corpus(&format!("mdl/{name}"))?);
    }
    Some(Files { main, bytes })
}

/// Parses with `name` replaced by `damaged`; checks the outcome. Returns whether it parsed.
fn run(files: &Files, name: &str, damaged: &[u8]) -> bool {
    let get = |n: &str| -> std::io::Result<Vec<u8>> {
        if n == name {
            return Ok(damaged.to_vec());
        }
        files
            .bytes
            .get(n)
            .cloned()
            .ok_or_else(|| std::io::Error::other("missing"))
    };
    let main = if name == files.main {
        damaged.to_vec()
    } else {
        files.bytes[files.main].clone()
    };
    let r = std::panic::catch_unwind(|| mdl::read(files.main, &main, &get, true));
    match r {
        Err(_) => panic!(
            "panic on {name} damaged to {} bytes (main {})",
            damaged.len(),
            files.main
        ),
        Ok(Err(e)) => {
            check_error(&e, name, files.main);
            false
        }
        Ok(Ok((m, _))) => {
            check_model(&m);
            true
        }
    }
}

fn check_error(e: &ImportError, damaged: &str, main: &str) {
    // A damaged companion may also make the main file's references fail (e.g. a skin reference),
    // so the error names one of the two, always with an offset inside the file it names.
    assert!(
        matches!(e.location, Location::Offset(_)),
        "error without an offset: {e}"
    );
    assert!(!e.section.is_empty(), "{e}");
    assert!(!e.message.is_empty(), "{e}");
    assert!(
        e.file == damaged || e.file == main,
        "error names {} for damage in {damaged}",
        e.file
    );
}

/// Everything an index points at exists; decoded frames have one value set per bone.
fn check_model(m: &StudioModel) {
    let nb = m.bones.len();
    assert!(nb <= mdl::MAX_BONES);
    for (i, b) in m.bones.iter().enumerate() {
        assert!(b.parent.is_none_or(|p| p < i));
    }
    for c in &m.controllers {
        assert!(c.bone < nb);
    }
    for row in &m.skin_families {
        assert!(row.iter().all(|&t| t < m.textures.len()));
    }
    for t in &m.textures {
        assert_eq!(t.indices.len(), t.width as usize * t.height as usize);
        assert_eq!(t.palette.len(), 768);
    }
    for part in &m.body_parts {
        for model in &part.submodels {
            for v in &model.vertices {
                assert!(v.influences.iter().all(|&(b, _)| b < nb));
            }
            for mesh in &model.meshes {
                for tri in &mesh.triangles {
                    for c in tri {
                        assert!(c.vertex < model.vertices.len());
                    }
                }
            }
        }
    }
    for s in &m.sequences {
        for frame in s.blends.iter().flatten() {
            assert_eq!(frame.len(), nb);
        }
    }
}

/// Sets of files: each main file with the companions it uses.
fn sets() -> Vec<Files> {
    [
        // man01.mdl is a sequence group no sequence uses, so it is never read and its damage changes
        // nothing; manT.mdl is read for the textures.
        ("man.mdl", &["manT.mdl"][..]),
        ("chrome_sphere.mdl", &[][..]),
        ("sequence_transitions.mdl", &[][..]),
    ]
    .into_iter()
    .filter_map(|(m, c)| load(m, c))
    .collect()
}

#[test]
fn every_truncation_is_an_error() {
    for files in sets() {
        let mut names: Vec<_> = files.bytes.keys().copied().collect();
        names.sort_unstable();
        for name in names {
            let full = files.bytes[name].clone();
            assert!(run(&files, name, &full), "{name} whole must parse");
            for n in 0..full.len() {
                assert!(
                    !run(&files, name, &full[..n]),
                    "{name} cut to {n} bytes parsed"
                );
            }
        }
    }
}

const WORDS: &[i64] = &[
    0,
    1,
    -1,
    2,
    3,
    127,
    128,
    129,
    255,
    256,
    0x7fff,
    0x8000,
    0xffff,
    0x1_0000,
    i32::MAX as i64,
    i32::MIN as i64,
];

#[test]
fn boundary_integers_over_every_word() {
    for files in sets() {
        let name = files.main;
        let full = files.bytes[name].clone();
        let len = full.len() as i64;
        let extra = [len - 1, len, len + 1, len / 2];
        // 32-bit counts and offsets at every aligned word.
        for at in (0..full.len().saturating_sub(3)).step_by(4) {
            for &v in WORDS.iter().chain(&extra) {
                let mut b = full.clone();
                b[at..at + 4].copy_from_slice(&(v as i32).to_le_bytes());
                run(&files, name, &b);
            }
        }
        // 16-bit triangle commands, animation offsets and run values at every even offset.
        for at in (0..full.len().saturating_sub(1)).step_by(2) {
            for v in [0i16, 1, -1, 2, -3, 255, 0x7fff, i16::MIN] {
                let mut b = full.clone();
                b[at..at + 2].copy_from_slice(&v.to_le_bytes());
                run(&files, name, &b);
            }
        }
    }
}

#[test]
fn random_bit_flips_never_panic() {
    let mut rng = Rng(0x5EED_0A11_D0C5_0001);
    for files in sets() {
        let mut names: Vec<_> = files.bytes.keys().copied().collect();
        names.sort_unstable();
        let mut parsed = 0;
        for name in names {
            let full = files.bytes[name].clone();
            for _ in 0..3000 {
                let mut b = full.clone();
                for _ in 0..1 + rng.below(8) {
                    let at = rng.below(b.len());
                    b[at] ^= 1 << rng.below(8);
                }
                parsed += run(&files, name, &b) as usize;
            }
        }
        // Most single flips land in vertex data, names or pixels and still parse.
        assert!(parsed > 0, "{}: no mutation parsed", files.main);
    }
}
