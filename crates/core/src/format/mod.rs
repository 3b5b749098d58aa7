//! The `.sinew` container, version 1: a little-endian, sectioned, checksummed binary file holding a
//! skeleton, materials, meshes with their LOD chains, and clips. `docs/format.md` documents every byte.
//!
//! - [`write`](fn@write) turns an [`Asset`] into bytes. It is deterministic: the same asset gives the same bytes.
//! - [`read`] turns bytes into an [`Asset`]. It takes untrusted input: every count is checked against
//!   the bytes present before anything is allocated, every section's CRC-32 is verified, and every
//!   failure is a [`FormatError`] naming the section, the byte offset and what is wrong. It never panics.
//! - [`sections`] lists the section table (tags, offsets, sizes, checksums) for inspection.
//!
//! No file I/O happens here: bytes in, plain data out.

mod asset;
pub mod axes;
mod error;
pub mod game;
mod read;
mod times;
mod write;

pub use asset::{
    validate, Asset, LodInfo, Mask, Material, SectionInfo, SourceVertexMap, Tag, ALIGN,
    HEADER_SIZE, MAGIC, NO_PARENT, NO_STRING, SECTION_ENTRY_SIZE, SECTION_VERSION, VERSION_MAJOR,
    VERSION_MINOR, VERSION_MINOR_AXES, VERSION_MINOR_COMPACT, VERSION_MINOR_COMPRESSED,
    VERSION_MINOR_GAME, VERSION_MINOR_SHORT_TRACKS,
};
pub use axes::{Axes, Axis};
pub use error::{FormatError, FormatErrorKind};
pub use game::GameData;
pub use read::{read, sections};
pub use write::{clip_record_size, write};
