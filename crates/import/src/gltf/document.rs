//! Loading a glTF document: the GLB container, JSON parsing and validation with JSON paths in errors,
//! buffers (external, data URI, GLB chunk) and typed accessor reads.

use super::accessor::{read_f32, read_u32};
use crate::{ImportError, Resolver};
use sinew_scene::Diagnostic;

/// A parsed document with its buffers loaded and checked.
pub(super) struct Loaded {
    pub(super) doc: gltf::Document,
    pub(super) buffers: Vec<Vec<u8>>,
    /// What the document lacks and was read without (`parse_document`).
    pub(super) warnings: Vec<Diagnostic>,
}

/// Splits a GLB container into its JSON chunk and optional BIN chunk, checking every length.
pub(super) fn split_glb<'a>(
    file: &str,
    bytes: &'a [u8],
) -> Result<(&'a [u8], Option<&'a [u8]>), ImportError> {
    let u32_at = |o: usize| -> Option<u32> {
        let b = bytes.get(o..o.checked_add(4)?)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let err = |o: usize, m: String| ImportError::at_offset(file, "glb", o as u64, m);
    let version =
        u32_at(4).ok_or_else(|| err(4, "file ends inside the 12-byte GLB header".into()))?;
    if version != 2 {
        return Err(err(
            4,
            format!("GLB version {version}; only version 2 is supported"),
        ));
    }
    let length =
        u32_at(8).ok_or_else(|| err(8, "file ends inside the GLB header".into()))? as usize;
    if length > bytes.len() {
        return Err(err(
            8,
            format!(
                "header says the file is {length} bytes; only {} are present",
                bytes.len()
            ),
        ));
    }
    let bytes = &bytes[..length];
    let mut chunks = Vec::new();
    let mut o = 12usize;
    while o < bytes.len() {
        let len =
            u32_at(o).ok_or_else(|| err(o, "file ends inside a chunk header".into()))? as usize;
        let ty = u32_at(o + 4).ok_or_else(|| err(o, "file ends inside a chunk header".into()))?;
        let start = o + 8;
        let end = start
            .checked_add(len)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                err(
                    o,
                    format!(
                        "chunk of {len} bytes runs past the end of the file ({} bytes)",
                        bytes.len()
                    ),
                )
            })?;
        chunks.push((o, ty, &bytes[start..end]));
        o = end;
    }
    let mut it = chunks.into_iter();
    let (_, ty, json) = it
        .next()
        .ok_or_else(|| err(12, "GLB has no chunks; the first must be JSON".into()))?;
    if ty != 0x4E4F_534A {
        return Err(err(
            12,
            format!("first chunk has type 0x{ty:08x}; expected JSON"),
        ));
    }
    let mut bin = None;
    for (off, ty, data) in it {
        if ty == 0x004E_4942 {
            if bin.is_some() {
                return Err(err(off, "a second BIN chunk".into()));
            }
            bin = Some(data);
        }
    }
    Ok((json, bin))
}

/// The JSON path (`meshes[0].primitives`) of the value that contains byte `offset` of `text`.
pub fn json_path_at(text: &[u8], offset: usize) -> String {
    enum Frame {
        Obj(Option<String>, bool),
        Arr(usize),
    }
    let mut stack: Vec<Frame> = Vec::new();
    let mut i = 0;
    let end = offset.min(text.len());
    while i < end {
        let c = text[i];
        match c {
            b'"' => {
                let start = i + 1;
                i += 1;
                while i < text.len() && text[i] != b'"' {
                    if text[i] == b'\\' {
                        i += 1;
                    }
                    i += 1;
                }
                if let Some(Frame::Obj(key, expecting)) = stack.last_mut() {
                    if *expecting {
                        let s = text.get(start..i.min(text.len())).unwrap_or(&[]);
                        *key = Some(String::from_utf8_lossy(s).into_owned());
                        *expecting = false;
                    }
                }
            }
            b'{' => stack.push(Frame::Obj(None, true)),
            b'[' => stack.push(Frame::Arr(0)),
            b'}' | b']' => {
                stack.pop();
            }
            b',' => match stack.last_mut() {
                Some(Frame::Arr(n)) => *n += 1,
                Some(Frame::Obj(_, expecting)) => *expecting = true,
                None => {}
            },
            _ => {}
        }
        i += 1;
    }
    let mut path = String::new();
    for f in &stack {
        match f {
            Frame::Obj(Some(k), _) => {
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(k);
            }
            Frame::Obj(None, _) => {}
            Frame::Arr(n) => path.push_str(&format!("[{n}]")),
        }
    }
    if path.is_empty() {
        "(root)".into()
    } else {
        path
    }
}

pub(super) fn section_of(path: &str) -> &str {
    let end = path.find(['[', '.']).unwrap_or(path.len());
    &path[..end]
}

/// An error at a JSON path; the section is the path's top-level property.
pub(super) fn at(file: &str, path: impl Into<String>, message: impl Into<String>) -> ImportError {
    let path = path.into();
    let section = section_of(&path).to_string();
    ImportError::at_path(file, &section, path, message)
}

/// Byte offset of a 1-based line and column.
pub(super) fn offset_of(text: &[u8], line: usize, column: usize) -> usize {
    let mut l = 1;
    let mut i = 0;
    while i < text.len() && l < line {
        if text[i] == b'\n' {
            l += 1;
        }
        i += 1;
    }
    (i + column.saturating_sub(1)).min(text.len())
}

/// Required extensions the importer reads itself (its own accessor reader), taken out of
/// `extensionsRequired` before the gltf crate validates the document.
const READ_HERE: [&str; 2] = ["KHR_mesh_quantization", super::meshopt::EXTENSION];

/// Gives the POSITION accessors without `min` or `max` (which the specification requires and the
/// gltf crate's validation refuses, but which sinew never reads: it reads the data itself) bounds
/// of zero, so that such a file is read; returns their indices, for a warning.
fn fill_missing_position_bounds(root: &mut gltf::json::Root) -> Vec<usize> {
    let mut positions: Vec<usize> = root
        .meshes
        .iter()
        .flat_map(|m| &m.primitives)
        .filter_map(|p| {
            p.attributes
                .get(&gltf::json::validation::Checked::Valid(
                    gltf::json::mesh::Semantic::Positions,
                ))
                .map(|i| i.value())
        })
        .collect();
    positions.sort_unstable();
    positions.dedup();
    let mut filled = Vec::new();
    for i in positions {
        let Some(a) = root.accessors.get_mut(i) else {
            continue;
        };
        if a.min.is_none() || a.max.is_none() {
            let zero = || Some(serde_json::json!([0.0, 0.0, 0.0]));
            a.min = a.min.take().or_else(zero);
            a.max = a.max.take().or_else(zero);
            filled.push(i);
        }
    }
    filled
}

/// The document, validated as [`gltf::Document::from_json`] validates it, except for what the
/// specification allows and the crate refuses: an accessor with neither `bufferView` nor `sparse`
/// (all zeros, which sinew's accessor reader gives) and a primitive without POSITION (which the
/// mesh import skips with a warning, as the specification says a client should).
fn validated(root: gltf::json::Root) -> gltf::Result<gltf::Document> {
    use gltf::json::validation::{Error, Validate};
    let mut errors = Vec::new();
    root.validate(&root, gltf::json::Path::new, &mut |path, error| {
        errors.push((path(), error))
    });
    errors.retain(|(path, error)| {
        let path = path.as_str();
        let zeros = || {
            path.strip_prefix("accessors[")
                .and_then(|rest| rest.strip_suffix("].bufferView"))
                .and_then(|i| i.parse::<usize>().ok())
                .and_then(|i| root.accessors.get(i))
                .is_some_and(|a| a.buffer_view.is_none() && a.sparse.is_none())
        };
        let no_position =
            || path.starts_with("meshes[") && path.ends_with("].attributes[\"POSITION\"]");
        !(*error == Error::Missing && (zeros() || no_position()))
    });
    if errors.is_empty() {
        Ok(gltf::Document::from_json_without_validation(root))
    } else {
        Err(gltf::Error::Validation(errors))
    }
}

/// The document, and the warnings of what it lacks and is read without.
pub(super) struct Parsed {
    pub(super) gltf: gltf::Gltf,
    pub(super) warnings: Vec<Diagnostic>,
    /// The document as JSON values when it uses EXT_meshopt_compression (whose views are
    /// decoded from it, [`super::meshopt`]); kept from sinew's own pass rather than parsed again.
    pub(super) meshopt_json: Option<serde_json::Value>,
}

/// A JSON error (syntax or type) at the JSON path of the line and column serde gives.
fn json_error(file: &str, json: &[u8], de: &serde_json::Error) -> ImportError {
    let off = offset_of(json, de.line(), de.column());
    let mut path = json_path_at(json, off);
    // serde notices a missing field at the end of its object, after the last key it read.
    if de.to_string().starts_with("missing field") {
        if let Some(dot) = path.rfind('.') {
            if !path[dot..].contains('[') {
                path.truncate(dot);
            }
        }
    }
    at(file, path, format!("{de}"))
}

pub(super) fn parse_document(file: &str, json: &[u8]) -> Result<Parsed, ImportError> {
    if json.starts_with(b"glTF") {
        return Err(ImportError::in_section(file, "json", "nested GLB header"));
    }
    // Our own pass first: indices the crate follows and enumerations it unwraps, which gltf-json
    // 1.4.1 can panic on instead of reporting (docs/reliability.md).
    let (meshopt_json, tolerated, patched) = match serde_json::from_slice::<serde_json::Value>(json)
    {
        Ok(mut value) => {
            // First, so that the channels it removes are not checked as the crate would read them.
            let tolerated = super::tolerate::tolerate(&mut value);
            super::refs::check(&value).map_err(|(path, message)| at(file, path, message))?;
            // The crate reads the changed document; its errors are placed in that text, whose
            // JSON paths are the original's (the values and their order are kept).
            let patched = if tolerated.changed {
                let text = serde_json::to_vec(&value)
                    .map_err(|e| ImportError::in_section(file, "json", e.to_string()))?;
                Some(text)
            } else {
                None
            };
            let uses_meshopt = value
                .get("extensionsUsed")
                .and_then(serde_json::Value::as_array)
                .is_some_and(|used| used.iter().any(|e| e == super::meshopt::EXTENSION));
            (uses_meshopt.then_some(value), tolerated, patched)
        }
        // serde_json skips the keys gltf-json does not know without checking their UTF-8, so a
        // document that is not UTF-8 would reach the crate unchecked (the fuzzer found one that then
        // panicked in mesh.rs): glTF JSON must be UTF-8, refuse it here.
        Err(value_error) => {
            if let Err(e) = std::str::from_utf8(json) {
                let off = e.valid_up_to();
                return Err(ImportError::at_offset(
                    file,
                    "json",
                    off as u64,
                    "JSON is not UTF-8",
                ));
            }
            // Nor is a document that is not JSON passed on: gltf-json skips the values of keys it
            // does not know without reading them whole (a number past f64's range in an unknown
            // key passed), so the checks above would be skipped and the crate could reach a panic
            // they prevent (the fuzzer found one: no `accessors`, then POSITION 1).
            return Err(json_error(file, json, &value_error));
        }
    };
    let json = patched.as_deref().unwrap_or(json);
    let mut unbounded = Vec::new();
    let parsed = crate::guard::contain(|| {
        let mut root: gltf::json::Root = gltf::json::deserialize::from_slice(json)?;
        // Extensions sinew reads itself, and those it reads without (the crate's validation refuses
        // any it does not know).
        root.extensions_required.retain(|e| {
            !READ_HERE.contains(&e.as_str()) && !super::tolerate::TEXTURE_ONLY.contains(&e.as_str())
        });
        unbounded = fill_missing_position_bounds(&mut root);
        validated(root).map(|document| gltf::Gltf {
            document,
            blob: None,
        })
    })
    .map_err(|m| {
        ImportError::in_section(
            file,
            "json",
            format!("the gltf crate panicked while validating ({m})"),
        )
    })?;
    let mut warnings = tolerated.warnings;
    if !unbounded.is_empty() {
        let list: Vec<String> = unbounded
            .iter()
            .map(|i| format!("accessors[{i}]"))
            .collect();
        warnings.push(Diagnostic::warning(
            "gltf-position-bounds-missing",
            format!(
                "{} {} no min/max, which glTF requires of POSITION; read without them (sinew reads the data itself)",
                list.join(", "),
                if list.len() == 1 { "has" } else { "have" }
            ),
        )
        .with_figure("accessors", unbounded.len() as f64));
    }
    parsed
        .map(|gltf| Parsed {
            gltf,
            warnings,
            meshopt_json,
        })
        .map_err(|e| match e {
            gltf::Error::Deserialize(de) => json_error(file, json, &de),
            gltf::Error::Validation(errors) => {
                // A required extension sinew does not read explains the rest (a Draco-compressed
                // mesh's accessors have no buffer views): it is reported first.
                let first = errors
                    .iter()
                    .find(|(p, _)| p.to_string().starts_with("extensionsRequired"))
                    .or(errors.first());
                let (path, kind) = match first {
                    Some((p, k)) => (p.to_string(), format!("{k}")),
                    None => ("(root)".into(), "invalid".into()),
                };
                let more = if errors.len() > 1 {
                    format!(" ({} more validation errors)", errors.len() - 1)
                } else {
                    String::new()
                };
                let required = path.starts_with("extensionsRequired");
                let hint = if required {
                    "; sinew reads KHR_mesh_quantization and the core glTF 2.0 \
                 (docs/formats/gltf.md): decompress the file first"
                } else {
                    ""
                };
                at(file, path, format!("{kind}{hint}{more}"))
            }
            other => ImportError::in_section(file, "json", other.to_string()),
        })
}

/// Decodes standard or URL-safe base64, ignoring whitespace and padding.
pub(super) fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(s.len() / 4 * 3 + 3);
    let mut acc = 0u32;
    let mut bits = 0;
    for c in s.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' | b' ' | b'\n' | b'\r' | b'\t' => continue,
            _ => return None,
        } as u32;
        acc = (acc << 6) | v;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

/// Decodes `%xx` escapes of a relative URI.
pub(super) fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    let hex = |c: u8| (c as char).to_digit(16);
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

pub(super) fn load(file: &str, bytes: &[u8], resolve: Resolver<'_>) -> Result<Loaded, ImportError> {
    let (json, bin) = if bytes.starts_with(b"glTF") {
        split_glb(file, bytes)?
    } else {
        (bytes, None)
    };
    let Parsed {
        gltf,
        warnings,
        meshopt_json,
    } = parse_document(file, json)?;
    let doc = gltf.document;
    // EXT_meshopt_compression: the views it compresses are decoded below, into buffers that may
    // have no data of their own (fallback buffers).
    let fallback = meshopt_json
        .as_ref()
        .map(super::meshopt::fallback_buffers)
        .unwrap_or_default();
    let mut input_bytes = bytes.len();
    let mut buffers = Vec::new();
    for b in doc.buffers() {
        let path = format!("buffers[{}]", b.index());
        let data: Vec<u8> = match b.source() {
            // (Buffer 0 without a URI is the GLB's BIN chunk when there is one.)
            gltf::buffer::Source::Bin
                if fallback.contains(&b.index()) && (b.index() != 0 || bin.is_none()) =>
            {
                // Sized and filled by the decoding below.
                buffers.push(Vec::new());
                continue;
            }
            gltf::buffer::Source::Bin => {
                if b.index() != 0 {
                    return Err(at(
                        file,
                        path,
                        "only buffer 0 may refer to the GLB BIN chunk",
                    ));
                }
                bin.ok_or_else(|| at(file, &path, "refers to the GLB BIN chunk, which is absent"))?
                    .to_vec()
            }
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, payload) = rest
                        .split_once(";base64,")
                        .ok_or_else(|| at(file, &path, "data URI is not base64"))?;
                    base64_decode(payload)
                        .ok_or_else(|| at(file, &path, "data URI holds invalid base64"))?
                } else {
                    resolve(&percent_decode(uri)).map_err(|e| {
                        at(
                            file,
                            &path,
                            format!("cannot load external buffer {uri:?}: {e}"),
                        )
                    })?
                }
            }
        };
        if data.len() < b.length() {
            let what = match b.source() {
                gltf::buffer::Source::Bin => "the GLB BIN chunk",
                gltf::buffer::Source::Uri(_) => "its data",
            };
            return Err(at(
                file,
                path,
                format!(
                    "byteLength is {} but {what} holds only {} bytes",
                    b.length(),
                    data.len()
                ),
            ));
        }
        let mut data = data;
        data.truncate(b.length());
        if !matches!(b.source(), gltf::buffer::Source::Bin) {
            input_bytes = input_bytes.saturating_add(data.len());
        }
        buffers.push(data);
    }
    if let Some(root) = &meshopt_json {
        super::meshopt::decode_views(root, &mut buffers, &fallback, input_bytes)
            .map_err(|(path, message)| at(file, path, message))?;
    }
    Ok(Loaded {
        doc,
        buffers,
        warnings,
    })
}

/// Largest image [`embedded_images`] returns.
pub const MAX_EMBEDDED_IMAGE: usize = 64 << 20;

/// The images stored inside a glTF file (in a buffer view, or a `data:` URI), as `(key, bytes)` with
/// the key materials use for them (`images[N]`, see the importer's materials). Images stored in files
/// beside it are not included (their materials name the file). An image whose bytes lie outside its
/// buffer, or larger than [`MAX_EMBEDDED_IMAGE`], is left out; a file that does not load is an error.
pub fn embedded_images(
    file: &str,
    bytes: &[u8],
    resolve: Resolver<'_>,
) -> Result<Vec<(String, Vec<u8>)>, ImportError> {
    let l = load(file, bytes, resolve)?;
    let mut out = Vec::new();
    for img in l.doc.images() {
        let data = match img.source() {
            gltf::image::Source::View { view, .. } => {
                let Some(buffer) = l.buffers.get(view.buffer().index()) else {
                    continue;
                };
                let range = view
                    .offset()
                    .checked_add(view.length())
                    .map(|end| view.offset()..end);
                match range.and_then(|r| buffer.get(r)) {
                    Some(b) => b.to_vec(),
                    None => continue,
                }
            }
            gltf::image::Source::Uri { uri, .. } => {
                let Some(payload) = uri
                    .strip_prefix("data:")
                    .and_then(|r| r.split_once(";base64,"))
                    .map(|(_, p)| p)
                else {
                    continue;
                };
                if payload.len() / 4 * 3 > MAX_EMBEDDED_IMAGE {
                    continue;
                }
                match base64_decode(payload) {
                    Some(b) => b,
                    None => continue,
                }
            }
        };
        if data.len() <= MAX_EMBEDDED_IMAGE {
            out.push((format!("images[{}]", img.index()), data));
        }
    }
    Ok(out)
}

/// Number of skins in a glTF file, so that a caller can import each one with
/// [`ImportOptions::gltf_skin`].
pub fn skin_count(file_name: &str, bytes: &[u8]) -> Result<usize, ImportError> {
    let json = if bytes.starts_with(b"glTF") {
        split_glb(file_name, bytes)?.0
    } else {
        bytes
    };
    Ok(parse_document(file_name, json)?
        .gltf
        .document
        .skins()
        .count())
}

/// Reads an accessor as floats with exactly `comps` components per element.
pub(super) fn floats(
    file: &str,
    l: &Loaded,
    acc: &gltf::Accessor<'_>,
    comps: usize,
    path: &str,
) -> Result<Vec<f32>, ImportError> {
    let a = format!("accessors[{}]", acc.index());
    if super::accessor::component_count(acc.dimensions()) != comps {
        return Err(at(
            file,
            path,
            format!(
                "{a} has type {:?}; {comps} components expected",
                acc.dimensions()
            ),
        ));
    }
    let v = read_f32(acc, &l.buffers).map_err(|m| at(file, &a, format!("{m} (used by {path})")))?;
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(at(
            file,
            &a,
            format!(
                "element {} holds a non-finite value ({}) (used by {path})",
                i / comps,
                v[i]
            ),
        ));
    }
    Ok(v)
}

pub(super) fn uints(
    file: &str,
    l: &Loaded,
    acc: &gltf::Accessor<'_>,
    comps: usize,
    path: &str,
) -> Result<Vec<u32>, ImportError> {
    let a = format!("accessors[{}]", acc.index());
    if super::accessor::component_count(acc.dimensions()) != comps {
        return Err(at(
            file,
            path,
            format!(
                "{a} has type {:?}; {comps} components expected",
                acc.dimensions()
            ),
        ));
    }
    read_u32(acc, &l.buffers).map_err(|m| at(file, &a, format!("{m} (used by {path})")))
}
