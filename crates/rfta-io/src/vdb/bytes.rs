//! A little-endian reader over a `.vdb` file's bytes: every read names what it wanted and where,
//! and a short file is an error, never a panic.

use crate::error::{ParseError, ParseResult};

/// Reads values in order from a byte slice.
pub(super) struct Bytes<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Bytes<'a> {
    pub(super) fn new(data: &'a [u8]) -> Self {
        Self { data, at: 0 }
    }

    /// The offset of the next byte.
    pub(super) fn offset(&self) -> usize {
        self.at
    }

    /// The bytes after the next one's offset.
    pub(super) fn remaining(&self) -> usize {
        self.data.len() - self.at
    }

    /// The file's length.
    pub(super) fn len(&self) -> usize {
        self.data.len()
    }

    /// Moves to `offset` (from the start), which must lie within the file.
    pub(super) fn seek(&mut self, offset: u64, what: &str) -> ParseResult<()> {
        match usize::try_from(offset) {
            Ok(o) if o <= self.data.len() => {
                self.at = o;
                Ok(())
            }
            _ => Err(ParseError::new(format!(
                "{what} at offset {offset} lies beyond the end of the {}-byte file (truncated?)",
                self.data.len()
            ))),
        }
    }

    /// The next `n` bytes.
    pub(super) fn take(&mut self, n: usize, what: &str) -> ParseResult<&'a [u8]> {
        match self.at.checked_add(n) {
            Some(end) if end <= self.data.len() => {
                let s = &self.data[self.at..end];
                self.at = end;
                Ok(s)
            }
            _ => Err(ParseError::new(format!(
                "the file ends in {what} (wanted {n} bytes at offset {}, the file has {}): truncated?",
                self.at,
                self.data.len()
            ))),
        }
    }

    fn array<const N: usize>(&mut self, what: &str) -> ParseResult<[u8; N]> {
        let s = self.take(N, what)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    pub(super) fn u8(&mut self, what: &str) -> ParseResult<u8> {
        Ok(self.array::<1>(what)?[0])
    }

    pub(super) fn u32(&mut self, what: &str) -> ParseResult<u32> {
        self.array(what).map(u32::from_le_bytes)
    }

    pub(super) fn i32(&mut self, what: &str) -> ParseResult<i32> {
        self.array(what).map(i32::from_le_bytes)
    }

    pub(super) fn i64(&mut self, what: &str) -> ParseResult<i64> {
        self.array(what).map(i64::from_le_bytes)
    }

    pub(super) fn u64(&mut self, what: &str) -> ParseResult<u64> {
        self.array(what).map(u64::from_le_bytes)
    }

    pub(super) fn f32(&mut self, what: &str) -> ParseResult<f32> {
        self.array(what).map(f32::from_le_bytes)
    }

    pub(super) fn f64(&mut self, what: &str) -> ParseResult<f64> {
        self.array(what).map(f64::from_le_bytes)
    }

    /// A string as OpenVDB writes it: a `u32` length, then the bytes.
    pub(super) fn string(&mut self, what: &str) -> ParseResult<String> {
        let n = self.u32(what)? as usize;
        let s = self.take(n, what)?;
        Ok(String::from_utf8_lossy(s).into_owned())
    }

    /// Three `i32`s (a coordinate).
    pub(super) fn coord(&mut self, what: &str) -> ParseResult<[i32; 3]> {
        Ok([self.i32(what)?, self.i32(what)?, self.i32(what)?])
    }

    /// Three `f64`s (a `Vec3d`).
    pub(super) fn vec3d(&mut self, what: &str) -> ParseResult<[f64; 3]> {
        Ok([self.f64(what)?, self.f64(what)?, self.f64(what)?])
    }
}
