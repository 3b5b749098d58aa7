//! Decoding text source files (BVH, OBJ and MTL, SMD, QC): bytes to text, numbered lines, numbers with
//! errors that name the line, and the small helpers their messages share.

use crate::ImportError;

/// Decodes text bytes: UTF-16 LE/BE when they start with a byte-order mark, otherwise UTF-8 (a UTF-8
/// BOM is skipped; invalid sequences become U+FFFD, so stray Latin-1 in comments does not fail a file).
pub(crate) fn decode(bytes: &[u8]) -> String {
    let utf16 = |be: bool| {
        let units = bytes.get(2..).unwrap_or(&[]).chunks_exact(2).map(|c| {
            if be {
                u16::from_be_bytes([c[0], c[1]])
            } else {
                u16::from_le_bytes([c[0], c[1]])
            }
        });
        char::decode_utf16(units)
            .map(|r| r.unwrap_or(char::REPLACEMENT_CHARACTER))
            .collect::<String>()
    };
    match bytes {
        [0xFE, 0xFF, ..] => utf16(true),
        [0xFF, 0xFE, ..] => utf16(false),
        [0xEF, 0xBB, 0xBF, rest @ ..] => String::from_utf8_lossy(rest).into_owned(),
        _ => String::from_utf8_lossy(bytes).into_owned(),
    }
}

/// Lines numbered from 1; `\n`, `\r\n` and lone `\r` all end a line.
pub(crate) fn numbered_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.split('\n')
        .flat_map(|l| l.strip_suffix('\r').unwrap_or(l).split('\r'))
        .enumerate()
        .map(|(i, l)| (i + 1, l))
}

/// Parses one number, rejecting anything that is not a finite decimal.
pub(crate) fn parse_finite(
    file: &str,
    section: &str,
    line: usize,
    tok: &str,
) -> Result<f64, ImportError> {
    match tok.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(ImportError::at_line(
            file,
            section,
            line,
            format!("non-finite number {tok:?}"),
        )),
        Err(_) => Err(ImportError::at_line(
            file,
            section,
            line,
            format!("expected a number, found {tok:?}"),
        )),
    }
}

/// The clip name: the file name without directories and extension.
pub(crate) fn clip_name(file_name: &str) -> String {
    let base = file_name.rsplit(['/', '\\']).next().unwrap_or(file_name);
    let stem = match base.rsplit_once('.') {
        Some((s, _)) if !s.is_empty() => s,
        _ => base,
    };
    if stem.is_empty() {
        "clip".to_string()
    } else {
        stem.to_string()
    }
}

/// Shortens text quoted in an error message.
pub(crate) fn truncate(s: &str) -> String {
    if s.chars().count() <= 40 {
        s.to_string()
    } else {
        let mut t: String = s.chars().take(40).collect();
        t.push('…');
        t
    }
}
