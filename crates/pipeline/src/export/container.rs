//! Packing a built document: a binary `.glb` (JSON chunk and BIN chunk) or a single `.gltf` with its
//! buffer as a base64 data URI, so that one export is always one file.

use gltf_json as json;
use json::validation::USize64;

/// How the document is packed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Container {
    /// Binary glTF (`.glb`).
    Glb,
    /// JSON glTF (`.gltf`), pretty-printed, buffer embedded as a data URI.
    Gltf,
}

impl Container {
    /// The container an output path asks for by its extension (`.glb` or `.gltf`, any case).
    pub fn from_extension(ext: &str) -> Option<Container> {
        if ext.eq_ignore_ascii_case("glb") {
            Some(Container::Glb)
        } else if ext.eq_ignore_ascii_case("gltf") {
            Some(Container::Gltf)
        } else {
            None
        }
    }
}

/// Adds buffer 0 for `bin` (when it is not empty) and serialises. Deterministic: the JSON is written
/// field by field in the types' order, maps sorted by key.
pub fn pack(mut root: json::Root, bin: &[u8], container: Container) -> Result<Vec<u8>, String> {
    if !bin.is_empty() {
        root.buffers.push(json::Buffer {
            byte_length: USize64(bin.len() as u64),
            name: None,
            uri: match container {
                Container::Glb => None,
                Container::Gltf => Some(format!(
                    "data:application/octet-stream;base64,{}",
                    base64(bin)
                )),
            },
            extensions: None,
            extras: Default::default(),
        });
    }
    match container {
        Container::Gltf => {
            let mut text = root.to_vec_pretty().map_err(|e| e.to_string())?;
            text.push(b'\n');
            Ok(text)
        }
        Container::Glb => {
            let mut text = root.to_vec().map_err(|e| e.to_string())?;
            while text.len() % 4 != 0 {
                text.push(b' ');
            }
            let mut data = bin.to_vec();
            while data.len() % 4 != 0 {
                data.push(0);
            }
            let total = 12 + 8 + text.len() + if data.is_empty() { 0 } else { 8 + data.len() };
            let total =
                u32::try_from(total).map_err(|_| "the GLB would exceed 4 GiB".to_string())?;
            let mut out = Vec::with_capacity(total as usize);
            out.extend_from_slice(b"glTF");
            out.extend_from_slice(&2u32.to_le_bytes());
            out.extend_from_slice(&total.to_le_bytes());
            out.extend_from_slice(&(text.len() as u32).to_le_bytes());
            out.extend_from_slice(b"JSON");
            out.extend_from_slice(&text);
            if !data.is_empty() {
                out.extend_from_slice(&(data.len() as u32).to_le_bytes());
                out.extend_from_slice(b"BIN\0");
                out.extend_from_slice(&data);
            }
            Ok(out)
        }
    }
}

/// Standard base64 with padding.
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let v = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(v >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use crate::export::container::*;

    #[test]
    fn base64_matches_the_rfc_examples() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
        assert_eq!(base64(&[0xff, 0xfe]), "//4=");
    }

    #[test]
    fn glb_chunks_are_aligned_and_sized() {
        let root = json::Root::default();
        let out = pack(root, &[1, 2, 3], Container::Glb).expect("packed");
        assert_eq!(&out[0..4], b"glTF");
        assert_eq!(
            u32::from_le_bytes([out[8], out[9], out[10], out[11]]) as usize,
            out.len()
        );
        let json_len = u32::from_le_bytes([out[12], out[13], out[14], out[15]]) as usize;
        assert_eq!(json_len % 4, 0);
        let bin_at = 20 + json_len;
        assert_eq!(&out[bin_at + 4..bin_at + 8], b"BIN\0");
        assert_eq!(&out[bin_at + 8..], &[1, 2, 3, 0]);
        assert_eq!(out.len() % 4, 0);
    }

    #[test]
    fn extension_picks_the_container() {
        assert_eq!(Container::from_extension("GLB"), Some(Container::Glb));
        assert_eq!(Container::from_extension("gltf"), Some(Container::Gltf));
        assert_eq!(Container::from_extension("obj"), None);
    }
}
