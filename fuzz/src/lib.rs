//! Shared pieces of sinew's fuzz targets: one fuzz input holds a main file and its companion files
//! (glTF external buffers, OBJ material libraries, MDL texture and sequence-group files, the SMDs and
//! includes a QC names), separated by [`SEPARATOR`]. Companions are handed out in the order the reader
//! first asks for each name, so a seed written as `main SEP first-companion SEP second...` reproduces
//! the real file set.

use std::cell::RefCell;
use std::collections::BTreeMap;

/// Between the files of one fuzz input (also in `fuzz/dict/sinew.dict`).
pub const SEPARATOR: &[u8] = b"\n#sinew-fuzz-file#\n";

/// The files of one input: the main file first.
pub fn split_files(data: &[u8]) -> Vec<&[u8]> {
    let mut out = Vec::new();
    let mut rest = data;
    while let Some(at) = find(rest, SEPARATOR) {
        out.push(&rest[..at]);
        rest = &rest[at + SEPARATOR.len()..];
    }
    out.push(rest);
    out
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// Hands out companion files by name, in order of first request; a name asked for again gets the same
/// bytes; past the last companion, the file is missing.
pub struct Companions<'a> {
    files: Vec<&'a [u8]>,
    given: RefCell<BTreeMap<String, usize>>,
}

impl<'a> Companions<'a> {
    /// Companions from the files after the main one.
    pub fn new(files: Vec<&'a [u8]>) -> Self {
        Companions {
            files,
            given: RefCell::new(BTreeMap::new()),
        }
    }

    /// The names the reader asked for, in order of first request.
    pub fn asked(&self) -> Vec<String> {
        let given = self.given.borrow();
        let mut names: Vec<(usize, String)> = given.iter().map(|(n, &i)| (i, n.clone())).collect();
        names.sort();
        names.into_iter().map(|(_, n)| n).collect()
    }

    /// The resolver the importers take.
    pub fn resolve(&self, name: &str) -> std::io::Result<Vec<u8>> {
        let mut given = self.given.borrow_mut();
        let next = given.len();
        let index = *given.entry(name.to_string()).or_insert(next);
        self.files
            .get(index)
            .map(|b| b.to_vec())
            .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, name.to_string()))
    }
}

/// Imports `data` (main file and companions) as `file_name`'s format. An error must name the file it
/// is about, the main file or a companion the reader asked for: that is the contract every command's
/// one-line message relies on.
pub fn import(file_name: &str, data: &[u8]) {
    let files = split_files(data);
    let companions = Companions::new(files[1..].to_vec());
    let format = sinew_import::Format::from_path(std::path::Path::new(file_name))
        .expect("fuzz target names a known extension");
    let resolve = |name: &str| companions.resolve(name);
    // Missing companions are warnings here (`--allow-missing`), so the fuzzer reaches every table
    // past them; the error a missing companion gives otherwise names it like any other.
    let options = sinew_import::ImportOptions {
        allow_missing: true,
        ..Default::default()
    };
    match sinew_import::import_bytes(format, file_name, files[0], &resolve, &options) {
        Ok(scene) => {
            std::hint::black_box(scene);
        }
        Err(e) => {
            let message = e.to_string();
            let names_a_file = message.contains(file_name)
                || companions
                    .asked()
                    .iter()
                    .any(|n| message.contains(n.as_str()));
            assert!(names_a_file, "error does not name the file: {message}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_split_and_companions_are_handed_out_by_first_request() {
        let mut data = b"main".to_vec();
        data.extend_from_slice(SEPARATOR);
        data.extend_from_slice(b"one");
        data.extend_from_slice(SEPARATOR);
        data.extend_from_slice(b"two");
        let files = split_files(&data);
        assert_eq!(files, vec![&b"main"[..], b"one", b"two"]);
        let c = Companions::new(files[1..].to_vec());
        assert_eq!(c.resolve("b.bin").unwrap(), b"one");
        assert_eq!(c.resolve("a.bin").unwrap(), b"two");
        assert_eq!(c.resolve("b.bin").unwrap(), b"one");
        assert!(c.resolve("c.bin").is_err());
    }
}
