//! The table's bytes, read block by block in whole lines: the reader never
//! holds the file's text whole (a 10⁶-node export is 184 MB), only the head
//! the dialect and header are found in, then one block of data rows at a
//! time. Blocks end after a newline, so each decodes on its own to exactly
//! the text the whole file would decode to (a newline is never part of a
//! multi-byte sequence, and Windows-1252 bytes are replaced line by line as
//! they would be in the whole), and line numbers run on from block to block.

use std::io::Read;
use std::path::Path;

use crate::error::FormatError;

/// Lines the head must hold (the header is looked for in the first 50, the
/// decimal comma in the 50 after the first) …
const HEAD_LINES: usize = 51;
/// … and non-blank lines (the delimiter is sniffed from the first 20).
const HEAD_NON_BLANK: usize = 20;

/// Bytes read per block of data rows (then cut after its last newline).
pub(super) const BLOCK_BYTES: usize = 16 << 20;

/// A table being read: the bytes not yet consumed, and whether the end of
/// the input has been reached.
pub(super) struct Source<'r> {
    path: &'r Path,
    reader: &'r mut dyn Read,
    /// Bytes read and not yet consumed.
    pub(super) buf: Vec<u8>,
    eof: bool,
    read: u64,
    /// Most bytes the input may have ([`crate::input::MAX_INPUT_BYTES`] for a
    /// file).
    limit: u64,
    block: usize,
}

impl<'r> Source<'r> {
    /// Reads `reader` (named `path` in errors) in blocks of about `block`
    /// bytes, refusing more than `limit` bytes in all.
    pub(super) fn new(
        path: &'r Path,
        reader: &'r mut dyn Read,
        limit: u64,
        block: usize,
    ) -> Source<'r> {
        Source {
            path,
            reader,
            buf: Vec::new(),
            eof: false,
            read: 0,
            limit,
            block: block.max(1),
        }
    }

    /// Whether every byte of the input has been read.
    pub(super) fn at_end(&self) -> bool {
        self.eof
    }

    /// Reads one more block (fewer bytes at the end of the input).
    fn fill(&mut self) -> Result<(), FormatError> {
        if self.eof {
            return Ok(());
        }
        let want = self.block as u64;
        // Room for exactly one block: `read_to_end` would double it.
        self.buf.reserve_exact(self.block);
        let got = (&mut *self.reader)
            .take(want)
            .read_to_end(&mut self.buf)
            .map_err(|e| FormatError::io(self.path, e))? as u64;
        self.read += got;
        if self.read > self.limit {
            return Err(crate::input::too_large(self.path, self.read, self.limit));
        }
        if got < want {
            self.eof = true;
        }
        Ok(())
    }

    /// Reads until the buffer holds the first `n` bytes of the input or the
    /// input ends.
    pub(super) fn fill_to(&mut self, n: usize) -> Result<(), FormatError> {
        while self.buf.len() < n && !self.eof {
            self.fill()?;
        }
        Ok(())
    }

    /// Reads the head of the table: until the buffer's complete lines number
    /// [`HEAD_LINES`] with [`HEAD_NON_BLANK`] non-blank among them, or the
    /// input ends. Returns the bytes of those lines (the whole buffer at the
    /// end of the input) and whether any of them is non-blank.
    pub(super) fn head(&mut self) -> Result<(usize, bool), FormatError> {
        let (mut scanned, mut lines, mut non_blank) = (0, 0, 0);
        loop {
            while let Some(k) = memchr::memchr(b'\n', &self.buf[scanned..]) {
                if !is_blank_line(&self.buf[scanned..scanned + k]) {
                    non_blank += 1;
                }
                lines += 1;
                scanned += k + 1;
                if lines >= HEAD_LINES && non_blank >= HEAD_NON_BLANK {
                    return Ok((scanned, true));
                }
            }
            if self.eof {
                let last = &self.buf[scanned..];
                return Ok((self.buf.len(), non_blank > 0 || !is_blank_line(last)));
            }
            self.fill()?;
        }
    }

    /// The length of the next block of whole lines at the front of the
    /// buffer: about one block, cut after its last newline (a longer line is
    /// read whole); the rest of the input at its end; 0 when nothing is left.
    pub(super) fn next_block(&mut self) -> Result<usize, FormatError> {
        self.fill_to(self.block)?;
        let mut from = 0;
        loop {
            if let Some(k) = memchr::memrchr(b'\n', &self.buf[from..]) {
                return Ok(from + k + 1);
            }
            if self.eof {
                return Ok(self.buf.len());
            }
            from = self.buf.len();
            self.fill()?;
        }
    }

    /// Drops the first `n` bytes of the buffer (consumed).
    pub(super) fn consume(&mut self, n: usize) {
        self.buf.drain(..n);
    }
}

/// A line that is empty or white space once decoded (as `str::trim` sees
/// it; a trailing `\r` included).
fn is_blank_line(bytes: &[u8]) -> bool {
    if bytes.is_ascii() {
        // `\t` `\n` VT FF `\r` and the space: ASCII's Unicode white space.
        return bytes.iter().all(|b| matches!(b, b'\t'..=b'\r' | b' '));
    }
    String::from_utf8_lossy(bytes).trim().is_empty()
}

/// The text of `bytes` (whole lines): UTF-8, or with the bytes that are not
/// replaced (Windows-1252 exports: units like ³ only).
pub(super) fn decode(bytes: &[u8]) -> std::borrow::Cow<'_, str> {
    match std::str::from_utf8(bytes) {
        Ok(t) => std::borrow::Cow::Borrowed(t),
        Err(_) => String::from_utf8_lossy(bytes),
    }
}

/// Byte offset of 0-based line `k` of `bytes` (its length when there are
/// fewer lines).
pub(super) fn nth_line_start(bytes: &[u8], k: usize) -> usize {
    if k == 0 {
        return 0;
    }
    memchr::memchr_iter(b'\n', bytes)
        .nth(k - 1)
        .map_or(bytes.len(), |i| i + 1)
}
