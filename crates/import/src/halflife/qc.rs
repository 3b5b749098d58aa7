//! QC scripts as tokens: a QC file and the files it `$include`s, split the way studiomdl's script
//! reader splits them (white space, double quotes, `//` and `/* */` comments, braces), each token
//! remembering its file and line so that every later error can name them.

use crate::text::{decode, tokens, TokenRules};
use crate::{ImportError, Resolver};

/// How deep `$include` may nest.
pub const MAX_INCLUDE_DEPTH: usize = 16;
/// Most tokens a script may hold, with its includes (bounds memory on hostile input).
pub const MAX_TOKENS: usize = 1 << 22;

/// One token of a script.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Tok {
    /// Text without quotes.
    pub text: String,
    /// Whether it was quoted (a quoted `{` is not a brace, a quoted `$x` not a command).
    pub quoted: bool,
    /// Index of the file it came from in [`Script::files`].
    pub file: usize,
    /// 1-based line in that file.
    pub line: usize,
}

impl Tok {
    /// True for an unquoted `{` or `}`.
    pub fn is(&self, brace: &str) -> bool {
        !self.quoted && self.text == brace
    }
    /// True for an unquoted token that starts a command (`$name`).
    pub fn is_command(&self) -> bool {
        !self.quoted && self.text.starts_with('$')
    }
}

/// A script with its includes expanded in place.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Script {
    /// File names: the QC first, then each included file as named.
    pub files: Vec<String>,
    /// Tokens in reading order.
    pub tokens: Vec<Tok>,
}

impl Script {
    /// An error at a token's file and line.
    pub fn error_at(&self, tok: &Tok, section: &str, message: impl Into<String>) -> ImportError {
        let file = self.files.get(tok.file).map_or("?", String::as_str);
        ImportError::at_line(file, section, tok.line, message)
    }
}

/// Reads a QC file and its `$include`s (resolved beside the QC by `resolve`).
pub fn load(file: &str, bytes: &[u8], resolve: Resolver<'_>) -> Result<Script, ImportError> {
    let mut script = Script::default();
    let mut stack = Vec::new();
    expand(file, bytes, resolve, &mut script, &mut stack)?;
    Ok(script)
}

fn expand(
    file: &str,
    bytes: &[u8],
    resolve: Resolver<'_>,
    script: &mut Script,
    stack: &mut Vec<String>,
) -> Result<(), ImportError> {
    let index = script.files.len();
    script.files.push(file.to_string());
    stack.push(normalise(file));
    let text = decode(bytes);
    let rules = TokenRules {
        braces: true,
        block_comments: true,
    };
    let (list, open) = tokens(&text, rules);
    if let Some(line) = open {
        return Err(ImportError::at_line(
            file,
            "comment",
            line,
            "a /* comment is never closed",
        ));
    }
    let mut it = list.into_iter().peekable();
    while let Some(t) = it.next() {
        if !t.quoted && t.text.eq_ignore_ascii_case("$include") {
            let Some(name) = it.next().filter(|n| n.line == t.line) else {
                return Err(ImportError::at_line(
                    file,
                    "$include",
                    t.line,
                    "$include needs a file name on the same line",
                ));
            };
            let key = normalise(&name.text);
            if stack.contains(&key) {
                return Err(ImportError::at_line(
                    file,
                    "$include",
                    t.line,
                    format!(
                        "{:?} includes itself (through {})",
                        name.text,
                        stack.join(" -> ")
                    ),
                ));
            }
            if stack.len() >= MAX_INCLUDE_DEPTH {
                return Err(ImportError::at_line(
                    file,
                    "$include",
                    t.line,
                    format!("includes nest deeper than {MAX_INCLUDE_DEPTH}"),
                ));
            }
            let bytes = resolve(&name.text).map_err(|e| {
                ImportError::at_line(
                    file,
                    "$include",
                    t.line,
                    format!("cannot read {:?}: {e}", name.text),
                )
            })?;
            expand(&name.text, &bytes, resolve, script, stack)?;
            continue;
        }
        if script.tokens.len() >= MAX_TOKENS {
            return Err(ImportError::at_line(
                file,
                "script",
                t.line,
                format!("more than {MAX_TOKENS} tokens"),
            ));
        }
        script.tokens.push(Tok {
            text: t.text,
            quoted: t.quoted,
            file: index,
            line: t.line,
        });
    }
    stack.pop();
    Ok(())
}

/// A path as compared for include cycles: forward slashes, lower case, no `./`.
fn normalise(path: &str) -> String {
    path.replace('\\', "/")
        .trim_start_matches("./")
        .to_ascii_lowercase()
}

/// Reads a script's tokens the way studiomdl's `GetToken` does: `next_any` crosses lines (`GetToken
/// (qtrue)`), `next_same_line` does not (`GetToken (qfalse)`), `available` tells whether another token
/// follows on the same line (`TokenAvailable`).
pub struct Cursor<'a> {
    script: &'a Script,
    pos: usize,
}

impl<'a> Cursor<'a> {
    /// A cursor at the first token.
    pub fn new(script: &'a Script) -> Self {
        Self { script, pos: 0 }
    }
    /// The script read.
    pub fn script(&self) -> &'a Script {
        self.script
    }
    /// The token read last (or the first, before any read).
    pub fn last(&self) -> Option<&'a Tok> {
        self.script
            .tokens
            .get(self.pos.saturating_sub(1))
            .or_else(|| self.script.tokens.first())
    }
    /// The next token, on any line.
    pub fn next_any(&mut self) -> Option<&'a Tok> {
        let t = self.script.tokens.get(self.pos)?;
        self.pos += 1;
        Some(t)
    }
    /// Whether another token follows on the line of the last one read.
    pub fn available(&self) -> bool {
        match (self.script.tokens.get(self.pos), self.pos.checked_sub(1)) {
            (Some(next), Some(prev)) => {
                let prev = &self.script.tokens[prev];
                next.file == prev.file && next.line == prev.line
            }
            _ => false,
        }
    }
    /// The next token if it is on the same line as the last one read.
    pub fn next_same_line(&mut self) -> Option<&'a Tok> {
        if self.available() {
            self.next_any()
        } else {
            None
        }
    }
    /// The next token on the same line, or an error naming what was expected.
    pub fn expect(&mut self, section: &str, what: &str) -> Result<&'a Tok, ImportError> {
        let at = self.last().cloned();
        self.next_same_line().ok_or_else(|| match at {
            Some(t) => self.script.error_at(
                &t,
                section,
                format!("the line ends where {what} was expected"),
            ),
            None => ImportError::in_section(
                self.script.files.first().map_or("?", String::as_str),
                section,
                format!("{what} expected"),
            ),
        })
    }
    /// The next token on the same line as a number (C `atof`: the longest numeric prefix, 0 if
    /// none, as studiomdl reads numbers).
    pub fn number(&mut self, section: &str, what: &str) -> Result<f32, ImportError> {
        let t = self.expect(section, what)?;
        let v = atof(&t.text);
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self
                .script
                .error_at(t, section, format!("{what} {:?} is not finite", t.text)))
        }
    }
    /// The next token on the same line as an integer (C `atoi`).
    pub fn integer(&mut self, section: &str, what: &str) -> Result<i32, ImportError> {
        let t = self.expect(section, what)?;
        Ok(atoi(&t.text))
    }
}

/// C's `atof`: the longest prefix that is a decimal number, 0 when there is none.
pub fn atof(s: &str) -> f32 {
    let s = s.trim_start();
    let b = s.as_bytes();
    let mut end = 0;
    let mut best = None;
    if matches!(b.first(), Some(b'+' | b'-')) {
        end = 1;
    }
    while end < b.len() && matches!(b[end], b'0'..=b'9' | b'.' | b'e' | b'E' | b'+' | b'-') {
        end += 1;
        if let Ok(v) = s[..end].parse::<f32>() {
            best = Some(v);
        }
    }
    best.unwrap_or(0.0)
}

/// C's `atoi`: an optional sign and the digits after it, 0 when there are none; saturates.
pub fn atoi(s: &str) -> i32 {
    let s = s.trim_start();
    let (neg, digits) = match s.as_bytes().first() {
        Some(b'-') => (true, &s[1..]),
        Some(b'+') => (false, &s[1..]),
        _ => (false, s),
    };
    let mut v: i64 = 0;
    for c in digits.bytes().take_while(u8::is_ascii_digit) {
        v = (v * 10 + i64::from(c - b'0')).min(i64::from(i32::MAX) + 1);
    }
    let v = if neg { -v } else { v };
    v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn files(
        map: &'static [(&'static str, &'static str)],
    ) -> impl Fn(&str) -> std::io::Result<Vec<u8>> {
        move |name: &str| {
            map.iter()
                .find(|(n, _)| *n == name)
                .map(|(_, t)| t.as_bytes().to_vec())
                .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"))
        }
    }

    #[test]
    fn includes_expand_in_place_and_tokens_keep_file_and_line() {
        let r = files(&[("common.qci", "$scale 2\n$eyeposition 0 0 72")]);
        let s = load(
            "m.qc",
            b"$cd \".\"\r\n$include \"common.qci\"\n$body b \"ref\"",
            &r,
        )
        .unwrap();
        let got: Vec<(&str, usize, usize)> = s
            .tokens
            .iter()
            .map(|t| (t.text.as_str(), t.file, t.line))
            .collect();
        assert_eq!(
            got,
            [
                ("$cd", 0, 1),
                (".", 0, 1),
                ("$scale", 1, 1),
                ("2", 1, 1),
                ("$eyeposition", 1, 2),
                ("0", 1, 2),
                ("0", 1, 2),
                ("72", 1, 2),
                ("$body", 0, 3),
                ("b", 0, 3),
                ("ref", 0, 3),
            ]
        );
        assert_eq!(s.files, ["m.qc", "common.qci"]);
    }

    #[test]
    fn an_include_cycle_is_an_error_naming_the_line() {
        let r = files(&[
            ("a.qci", "$include \"b.qci\""),
            ("b.qci", "\n$include \"A.qci\""),
        ]);
        let e = load("a.qci", b"$include \"b.qci\"", &r).unwrap_err();
        assert_eq!(e.file, "b.qci");
        assert_eq!(e.location, crate::Location::Line(2));
        assert!(e.message.contains("includes itself"), "{e}");
        let e = load("m.qc", b"$include \"missing.qci\"", &r).unwrap_err();
        assert!(e.to_string().contains("missing.qci"), "{e}");
    }

    #[test]
    fn cursor_reads_by_line_like_studiomdl() {
        let s = load("m.qc", b"$hbox 1 \"Neck\" -1 -0 -1\n1 2 1", &files(&[])).unwrap();
        let mut c = Cursor::new(&s);
        assert_eq!(c.next_any().unwrap().text, "$hbox");
        assert_eq!(c.integer("$hbox", "group").unwrap(), 1);
        assert_eq!(c.expect("$hbox", "bone").unwrap().text, "Neck");
        for v in [-1.0, 0.0, -1.0] {
            assert_eq!(c.number("$hbox", "corner").unwrap(), v);
        }
        assert!(!c.available());
        let e = c.number("$hbox", "corner").unwrap_err();
        assert_eq!(e.location, crate::Location::Line(1));
        assert_eq!(c.next_any().unwrap().text, "1");
    }

    #[test]
    fn numbers_read_as_c_does() {
        assert_eq!(atof("3.5abc"), 3.5);
        assert_eq!(atof("-0"), 0.0);
        assert_eq!(atof("x"), 0.0);
        assert_eq!(atof("1e2"), 100.0);
        assert_eq!(atoi("ACT"), 0);
        assert_eq!(atoi("-12x"), -12);
        assert_eq!(atoi("99999999999"), i32::MAX);
    }
}
