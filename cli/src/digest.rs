//! Content stamps for the incremental record of `convert`: a file's path, size and BLAKE3 digest (or
//! that it could not be read), so that a re-run can tell whether anything an output was made from
//! has changed.

use serde::{Deserialize, Serialize};
use std::path::Path;

/// The BLAKE3 digest of `bytes`, 64 lowercase hex digits.
pub fn hex(bytes: &[u8]) -> String {
    blake3::hash(bytes).to_hex().to_string()
}

/// What a file held when it was read: its size and digest, or `missing` when it could not be read.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stamp {
    /// The path as it was read (relative to the working folder when the input was given so).
    pub path: String,
    /// Size in bytes; absent when the file could not be read.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bytes: Option<u64>,
    /// BLAKE3 of the content; absent when the file could not be read.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blake3: Option<String>,
}

impl Stamp {
    /// The stamp of `data` read from `path` (`None`: it could not be read).
    pub fn of(path: &Path, data: Option<&[u8]>) -> Stamp {
        Stamp {
            path: path.display().to_string(),
            bytes: data.map(|d| d.len() as u64),
            blake3: data.map(hex),
        }
    }

    /// A stamp with the path and size only (no hash): for a record that needs no content check.
    pub fn unhashed(path: &Path, data: Option<&[u8]>) -> Stamp {
        Stamp {
            path: path.display().to_string(),
            bytes: data.map(|d| d.len() as u64),
            blake3: None,
        }
    }

    /// The stamp of the file at `path` now.
    pub fn read(path: &Path) -> Stamp {
        Stamp::of(path, std::fs::read(path).ok().as_deref())
    }

    /// Whether the file at this stamp's path still holds what it held (or is still missing).
    pub fn is_current(&self) -> bool {
        let now = std::fs::metadata(&self.path).ok().filter(|m| m.is_file());
        match (now, self.bytes) {
            // A different size is a change without reading the file.
            (Some(m), Some(n)) if m.len() != n => false,
            (None, None) => true,
            _ => Stamp::read(Path::new(&self.path)) == *self,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_follow_content_and_absence() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("a.smd");
        let missing = Stamp::read(&f);
        assert_eq!((missing.bytes, missing.blake3.as_deref()), (None, None));
        assert!(missing.is_current());
        std::fs::write(&f, b"abc").unwrap();
        assert!(!missing.is_current());
        let s = Stamp::read(&f);
        // BLAKE3("abc"), from the reference implementation's test vectors.
        assert_eq!(
            s.blake3.as_deref(),
            Some("6437b3ac38465133ffb63b75273a8db548c558465d79db03fd359c6cd5bd9d85")
        );
        assert_eq!(s.bytes, Some(3));
        assert!(s.is_current());
        std::fs::write(&f, b"abd").unwrap();
        assert!(!s.is_current(), "same size, other content");
        std::fs::remove_file(&f).unwrap();
        assert!(!s.is_current());
    }
}
