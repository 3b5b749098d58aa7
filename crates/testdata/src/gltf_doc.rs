//! Small glTF documents written in a test: a JSON text with one buffer embedded as a base64 data
//! URI, for tests that state every value of the file they import.

/// Standard base64 (RFC 4648, with padding). Checked by every test whose document the importer
/// decodes (crates/import/tests/gltf.rs, gltf_extensions.rs).
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let n = u32::from(c[0]) << 16
            | u32::from(*c.get(1).unwrap_or(&0)) << 8
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A glTF 2.0 document whose buffer 0 holds `buf`; `rest` is the JSON of its other top-level
/// members (without the enclosing braces).
pub fn doc_with_buffer(buf: &[u8], rest: &str) -> Vec<u8> {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],{rest}}}"#,
        buf.len(),
        base64(buf)
    )
    .into_bytes()
}

/// Little-endian bytes of `v`.
pub fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A resolver for documents that have no files beside them: every request fails.
pub fn no_resolve(_: &str) -> std::io::Result<Vec<u8>> {
    Err(std::io::Error::other("no external files in this test"))
}
