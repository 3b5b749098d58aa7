//! Errors of the `.sinew` reader and writer.

use std::fmt;

/// What is wrong with a `.sinew` file (or with an asset given to the writer).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FormatErrorKind {
    /// The file does not start with [`super::MAGIC`].
    #[error("not a .sinew file (bad magic)")]
    BadMagic,
    /// The major version is not one this reader supports.
    #[error("format version {major}.{minor} is not supported (this reader reads 1.x)")]
    UnsupportedVersion {
        /// Major version in the file.
        major: u16,
        /// Minor version in the file.
        minor: u16,
    },
    /// Fewer bytes are present than the structure at this offset needs.
    #[error("truncated: {needed} bytes needed, {available} present")]
    Truncated {
        /// Bytes needed.
        needed: u64,
        /// Bytes present.
        available: u64,
    },
    /// The file is longer than its header says.
    #[error("the header says the file is {declared} bytes; it is {actual}")]
    FileSize {
        /// Size written in the header.
        declared: u64,
        /// Size of the bytes given.
        actual: u64,
    },
    /// A CRC-32 does not match the bytes it covers.
    #[error("checksum mismatch: stored {stored:#010x}, computed {computed:#010x}")]
    Checksum {
        /// CRC-32 stored in the file.
        stored: u32,
        /// CRC-32 of the bytes present.
        computed: u32,
    },
    /// A section lies (partly) outside the file.
    #[error("section at {offset} of {size} bytes lies outside the {file_size}-byte file")]
    SectionOutOfBounds {
        /// Section offset.
        offset: u64,
        /// Section size.
        size: u64,
        /// File size.
        file_size: u64,
    },
    /// A section or table does not start on a 16-byte boundary.
    #[error("offset {offset} is not a multiple of 16")]
    Misaligned {
        /// The offending offset.
        offset: u64,
    },
    /// A known section appears twice.
    #[error("section appears more than once")]
    DuplicateSection,
    /// A known section has a layout version this reader does not know.
    #[error("section layout version {version} is not supported (this reader knows 1)")]
    UnsupportedSectionVersion {
        /// Version in the section table.
        version: u32,
    },
    /// A count asks for more bytes than remain in the section.
    #[error("{count} {what} need {needed} bytes; {available} remain")]
    CountTooLarge {
        /// What is being counted.
        what: &'static str,
        /// The count in the file.
        count: u64,
        /// Bytes the count needs (saturated at `u64::MAX`).
        needed: u64,
        /// Bytes remaining.
        available: u64,
    },
    /// An index refers past the end of what it indexes.
    #[error("{what} index {index} is out of range (limit {limit})")]
    IndexOutOfRange {
        /// What the index refers to.
        what: &'static str,
        /// The index in the file.
        index: u64,
        /// Number of valid entries.
        limit: u64,
    },
    /// A float that must be finite is NaN or infinite.
    #[error("{what} is not finite")]
    NonFinite {
        /// Which value.
        what: &'static str,
    },
    /// A string of the string table is not valid UTF-8.
    #[error("string {index} is not valid UTF-8")]
    BadUtf8 {
        /// Index of the string.
        index: u32,
    },
    /// A channel uses a value encoding this reader does not know.
    #[error("channel encoding {encoding} is not supported (this reader knows 0, plain f32)")]
    UnsupportedEncoding {
        /// The encoding byte.
        encoding: u8,
    },
    /// An enumeration, flag set or record size holds a value this version does not define.
    #[error("{what} has the undefined value {value}")]
    BadValue {
        /// Which field.
        what: &'static str,
        /// The value in the file.
        value: u64,
    },
    /// The decoded data breaks a rule (for example a skeleton or clip that does not validate).
    #[error("{0}")]
    Invalid(String),
}

/// A `.sinew` read or write failure: the section, the byte offset from the start of the file (when
/// known), and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FormatError {
    /// `header`, `section table`, or the tag of the section (`STRS`, `SKEL`, `MATL`, `MESH`, `CLIP`,
    /// or an unknown tag).
    pub section: String,
    /// Byte offset from the start of the file, when the error has one (writer errors do not).
    pub offset: Option<u64>,
    /// What is wrong.
    pub kind: FormatErrorKind,
}

impl FormatError {
    /// An error at a position.
    pub fn new(section: impl Into<String>, offset: Option<u64>, kind: FormatErrorKind) -> Self {
        Self {
            section: section.into(),
            offset,
            kind,
        }
    }

    /// A [`FormatErrorKind::Invalid`] error.
    pub fn invalid(
        section: impl Into<String>,
        offset: Option<u64>,
        message: impl Into<String>,
    ) -> Self {
        Self::new(section, offset, FormatErrorKind::Invalid(message.into()))
    }
}

impl fmt::Display for FormatError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.offset {
            Some(o) => write!(f, "{} at byte {o}: {}", self.section, self.kind),
            None => write!(f, "{}: {}", self.section, self.kind),
        }
    }
}

impl std::error::Error for FormatError {}
