//! A bounds-checked cursor over a section's bytes, and the string table lookups every section decoder uses.

use crate::format::asset::ALIGN;
use crate::format::error::{FormatError, FormatErrorKind as K};
use glam::Vec3;

pub(super) type Result<T> = std::result::Result<T, FormatError>;

/// A bounds-checked little-endian reader over one section (or the header).
pub(super) struct Cur<'a> {
    pub(super) data: &'a [u8],
    pub(super) pos: usize,
    /// File offset of `data[0]`.
    pub(super) base: u64,
    pub(super) section: String,
}

impl<'a> Cur<'a> {
    pub(super) fn new(data: &'a [u8], base: u64, section: impl Into<String>) -> Self {
        Self {
            data,
            pos: 0,
            base,
            section: section.into(),
        }
    }
    pub(super) fn offset(&self) -> u64 {
        self.base + self.pos as u64
    }
    pub(super) fn err(&self, kind: K) -> FormatError {
        FormatError::new(self.section.clone(), Some(self.offset()), kind)
    }
    pub(super) fn err_at(&self, pos: usize, kind: K) -> FormatError {
        FormatError::new(self.section.clone(), Some(self.base + pos as u64), kind)
    }
    pub(super) fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }
    pub(super) fn bytes(&mut self, n: usize) -> Result<&'a [u8]> {
        let available = self.remaining();
        if n > available {
            return Err(self.err(K::Truncated {
                needed: n as u64,
                available: available as u64,
            }));
        }
        let data: &'a [u8] = self.data;
        let out = data.get(self.pos..self.pos + n).unwrap_or_default();
        self.pos += n;
        Ok(out)
    }
    pub(super) fn array<const N: usize>(&mut self) -> Result<[u8; N]> {
        let b = self.bytes(N)?;
        let mut out = [0u8; N];
        out.copy_from_slice(b);
        Ok(out)
    }
    pub(super) fn u8(&mut self) -> Result<u8> {
        Ok(self.array::<1>()?[0])
    }
    pub(super) fn u16(&mut self) -> Result<u16> {
        self.array().map(u16::from_le_bytes)
    }
    pub(super) fn u32(&mut self) -> Result<u32> {
        self.array().map(u32::from_le_bytes)
    }
    pub(super) fn u64(&mut self) -> Result<u64> {
        self.array().map(u64::from_le_bytes)
    }
    pub(super) fn f32(&mut self) -> Result<f32> {
        self.array().map(f32::from_le_bytes)
    }
    pub(super) fn skip(&mut self, n: usize) -> Result<()> {
        self.bytes(n).map(|_| ())
    }
    /// Skips the zero padding up to the next multiple of [`ALIGN`] (sections start aligned).
    pub(super) fn align(&mut self) -> Result<()> {
        let pad = (ALIGN - self.pos % ALIGN) % ALIGN;
        self.skip(pad)
    }
    /// The bytes of `count` elements of `size` bytes, after checking they are present.
    pub(super) fn elements(
        &mut self,
        count: u64,
        size: usize,
        what: &'static str,
    ) -> Result<&'a [u8]> {
        let available = self.remaining() as u64;
        let needed = count.saturating_mul(size as u64);
        if needed > available {
            return Err(self.err(K::CountTooLarge {
                what,
                count,
                needed,
                available,
            }));
        }
        // `needed <= available`, which fits in usize.
        self.bytes(needed as usize)
    }
    /// Checks that `count` records of at least `min_size` bytes each can be present, so that a vector of
    /// `count` entries may be allocated.
    pub(super) fn check_count(
        &self,
        count: u64,
        min_size: usize,
        what: &'static str,
    ) -> Result<usize> {
        let available = self.remaining() as u64;
        let needed = count.saturating_mul(min_size as u64);
        if needed > available {
            return Err(self.err(K::CountTooLarge {
                what,
                count,
                needed,
                available,
            }));
        }
        Ok(count as usize)
    }
    pub(super) fn f32s(&mut self, count: u64, what: &'static str) -> Result<Vec<f32>> {
        let b = self.elements(count, 4, what)?;
        Ok(b.chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }
}

pub(super) fn f32s_of(b: &[u8]) -> impl Iterator<Item = f32> + '_ {
    b.chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
}

/// The string table, looked up by index.
pub(super) struct Strs<'a>(pub(super) &'a [String]);

impl Strs<'_> {
    pub(super) fn get(&self, c: &Cur, at: usize, index: u32, what: &'static str) -> Result<String> {
        self.0.get(index as usize).cloned().ok_or_else(|| {
            c.err_at(
                at,
                K::IndexOutOfRange {
                    what,
                    index: index.into(),
                    limit: self.0.len() as u64,
                },
            )
        })
    }
    /// Reads a u32 string index at the cursor and looks it up.
    pub(super) fn read(&self, c: &mut Cur, what: &'static str) -> Result<String> {
        let at = c.pos;
        let index = c.u32()?;
        self.get(c, at, index, what)
    }
}

pub(super) fn vec3s(b: &[u8]) -> impl Iterator<Item = Vec3> + '_ {
    b.chunks_exact(12).map(|c| {
        let mut f = f32s_of(c);
        let mut next = || f.next().unwrap_or_default();
        Vec3::new(next(), next(), next())
    })
}
