//! The one error type every importer returns.

use std::fmt;

/// Where in the input an error was found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Location {
    /// Nowhere more precise than the section.
    Unknown,
    /// A byte offset from the start of the file.
    Offset(u64),
    /// A 1-based line number of a text file.
    Line(usize),
    /// A JSON path inside a glTF document, such as `meshes[0].primitives[1].attributes.POSITION`.
    JsonPath(String),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Unknown => Ok(()),
            Location::Offset(o) => write!(f, " at byte {o}"),
            Location::Line(l) => write!(f, " at line {l}"),
            Location::JsonPath(p) => write!(f, " at {p}"),
        }
    }
}

/// An input that could not be imported: which file, which section, where, and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{file}: {section}{location}: {message}")]
pub struct ImportError {
    /// The file name as the caller gave it.
    pub file: String,
    /// The block, chunk or section of the format (e.g. `triangles`, `joints`, `MOTION`).
    pub section: String,
    /// Where in the file.
    pub location: Location,
    /// What is wrong, in one sentence.
    pub message: String,
}

impl ImportError {
    /// An error at a byte offset.
    pub fn at_offset(file: &str, section: &str, offset: u64, message: impl Into<String>) -> Self {
        Self {
            file: file.into(),
            section: section.into(),
            location: Location::Offset(offset),
            message: message.into(),
        }
    }
    /// An error at a line of a text file.
    pub fn at_line(file: &str, section: &str, line: usize, message: impl Into<String>) -> Self {
        Self {
            file: file.into(),
            section: section.into(),
            location: Location::Line(line),
            message: message.into(),
        }
    }
    /// An error at a JSON path.
    pub fn at_path(
        file: &str,
        section: &str,
        path: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Self {
            file: file.into(),
            section: section.into(),
            location: Location::JsonPath(path.into()),
            message: message.into(),
        }
    }
    /// An error with no finer location than the section.
    pub fn in_section(file: &str, section: &str, message: impl Into<String>) -> Self {
        Self {
            file: file.into(),
            section: section.into(),
            location: Location::Unknown,
            message: message.into(),
        }
    }
}
