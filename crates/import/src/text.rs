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
        [0xEF, 0xBB, 0xBF, rest @ ..] => utf8(rest),
        _ => utf8(bytes),
    }
}

/// UTF-8 with invalid sequences replaced. Valid text (nearly every file) goes through
/// `str::from_utf8`, whose ASCII fast path is several times quicker than the lossy decoder's.
fn utf8(bytes: &[u8]) -> String {
    match std::str::from_utf8(bytes) {
        Ok(s) => s.to_owned(),
        Err(_) => String::from_utf8_lossy(bytes).into_owned(),
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

/// One token of a text source: a run of characters without white space, a double-quoted string (the
/// quotes removed; it may be empty or hold spaces), or a brace when braces are tokens.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Token {
    /// The text, without quotes.
    pub text: String,
    /// Whether it was written in double quotes.
    pub quoted: bool,
    /// The 1-based line it starts on.
    pub line: usize,
}

/// How [`tokens`] splits text.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct TokenRules {
    /// `{` and `}` are tokens of their own even when glued to a word (QC).
    pub braces: bool,
    /// `/* ... */` comments, which may span lines (QC).
    pub block_comments: bool,
}

/// Splits text into tokens: white space separates, `//` starts a comment to the end of the line,
/// double quotes group (a quote left open ends at the end of its line). Lines end as in
/// [`numbered_lines`]. Returns the tokens and, when a block comment is left open, the line it starts on.
pub(crate) fn tokens(text: &str, rules: TokenRules) -> (Vec<Token>, Option<usize>) {
    let mut out = Vec::new();
    let mut open_block: Option<usize> = None;
    for (line_no, line) in numbered_lines(text) {
        let chars: Vec<char> = line.chars().collect();
        let mut i = 0;
        while i < chars.len() {
            let c = chars[i];
            if open_block.is_some() {
                if c == '*' && chars.get(i + 1) == Some(&'/') {
                    open_block = None;
                    i += 2;
                } else {
                    i += 1;
                }
                continue;
            }
            if c.is_whitespace() {
                i += 1;
            } else if c == '/' && chars.get(i + 1) == Some(&'/') {
                break;
            } else if rules.block_comments && c == '/' && chars.get(i + 1) == Some(&'*') {
                open_block = Some(line_no);
                i += 2;
            } else if c == '"' {
                let end = chars[i + 1..]
                    .iter()
                    .position(|&d| d == '"')
                    .map_or(chars.len(), |p| i + 1 + p);
                out.push(Token {
                    text: chars[i + 1..end].iter().collect(),
                    quoted: true,
                    line: line_no,
                });
                i = end + 1;
            } else if rules.braces && (c == '{' || c == '}') {
                out.push(Token {
                    text: c.to_string(),
                    quoted: false,
                    line: line_no,
                });
                i += 1;
            } else {
                let start = i;
                while i < chars.len()
                    && !chars[i].is_whitespace()
                    && chars[i] != '"'
                    && !(rules.braces && (chars[i] == '{' || chars[i] == '}'))
                    && !(chars[i] == '/' && matches!(chars.get(i + 1), Some('/')))
                    && !(rules.block_comments
                        && chars[i] == '/'
                        && matches!(chars.get(i + 1), Some('*')))
                {
                    i += 1;
                }
                out.push(Token {
                    text: chars[start..i].iter().collect(),
                    quoted: false,
                    line: line_no,
                });
            }
        }
    }
    (out, open_block)
}

/// The tokens of one line (no braces, no block comments), borrowed from it: white space separates,
/// `//` starts a comment, double quotes group (the quotes removed; a quote left open ends at the end
/// of the line). The same rules as [`tokens`], without allocating a string per token.
pub(crate) fn words(line: &str) -> Vec<&str> {
    let b = line.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c.is_ascii_whitespace() {
            i += 1;
        } else if c == b'/' && b.get(i + 1) == Some(&b'/') {
            break;
        } else if c == b'"' {
            let end = b[i + 1..]
                .iter()
                .position(|&d| d == b'"')
                .map_or(b.len(), |p| i + 1 + p);
            out.push(&line[i + 1..end]);
            i = end + 1;
        } else {
            let start = i;
            while i < b.len()
                && !b[i].is_ascii_whitespace()
                && b[i] != b'"'
                && !(b[i] == b'/' && b.get(i + 1) == Some(&b'/'))
            {
                i += 1;
            }
            out.push(&line[start..i]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_utf8_with_and_without_a_bom_and_replaces_invalid_bytes() {
        assert_eq!(decode(b"HIERARCHY\nROOT Hips"), "HIERARCHY\nROOT Hips");
        assert_eq!(decode("\u{feff}caf\u{e9}".as_bytes()), "caf\u{e9}");
        // Latin-1 e-acute (0xE9) is not UTF-8: it becomes U+FFFD, the rest is kept.
        assert_eq!(decode(b"# caf\xe9\nROOT"), "# caf\u{fffd}\nROOT");
        assert_eq!(decode(b"\xef\xbb\xbfa\xffb"), "a\u{fffd}b");
        assert_eq!(decode(&[0xFF, 0xFE, b'h', 0, b'i', 0]), "hi");
    }

    #[test]
    fn words_keep_quoted_spaces_and_drop_comments() {
        assert_eq!(
            words("0 \"Bip01 L Thigh\" -1 // a comment"),
            vec!["0", "Bip01 L Thigh", "-1"]
        );
        assert_eq!(words("\t1\t2  \"\"  x"), vec!["1", "2", "", "x"]);
        assert_eq!(
            words("\"open quote to the end"),
            vec!["open quote to the end"]
        );
    }

    #[test]
    fn tokens_split_braces_and_block_comments_across_lines() {
        let text = "$a \"x\"{ b }\r\n/* one\ntwo */ c//d\n{e}";
        let rules = TokenRules {
            braces: true,
            block_comments: true,
        };
        let (t, open) = tokens(text, rules);
        let got: Vec<(&str, bool, usize)> = t
            .iter()
            .map(|t| (t.text.as_str(), t.quoted, t.line))
            .collect();
        assert_eq!(
            got,
            vec![
                ("$a", false, 1),
                ("x", true, 1),
                ("{", false, 1),
                ("b", false, 1),
                ("}", false, 1),
                ("c", false, 3),
                ("{", false, 4),
                ("e", false, 4),
                ("}", false, 4),
            ]
        );
        assert_eq!(open, None);
        let (_, open) = tokens("a /* never closed\nb", rules);
        assert_eq!(open, Some(1));
    }
}
