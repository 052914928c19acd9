//! Large outputs written around the page cache (Linux `O_DIRECT`).
//!
//! A buffered `write` copies every byte into the page cache first. On the
//! virtual machines this tool runs on, page-cache memory that was never
//! touched costs about 3 ms per MB to hand out (the first write of the
//! 10⁶-MP case's 835 MB of outputs took 2–2.7 s of system time), while the
//! disk takes `O_DIRECT` writes at about 1.6 GB/s without a copy. So the
//! writer below collects the bytes in a page-aligned buffer and writes whole
//! pages with `O_DIRECT`; the last partial page is written padded and the
//! file cut back to its length. Where the filesystem refuses `O_DIRECT`
//! (tmpfs, other systems) the same writer writes through the page cache.

use std::fs::File;
use std::io::{self, Write};
use std::path::Path;

/// The alignment `O_DIRECT` asks of buffers, lengths and offsets (a page:
/// at least every logical block size in use).
const ALIGN: usize = 4096;

/// Bytes collected before a write (a multiple of [`ALIGN`]).
const CHUNK: usize = 1 << 22;

/// A new file, written with `O_DIRECT` where the filesystem takes it. Call
/// [`DirectFile::finish`]: bytes of a last partial page are written only there.
pub struct DirectFile {
    file: File,
    /// `CHUNK + ALIGN` bytes, of which `buf[at..at + CHUNK]` is page-aligned.
    buf: Vec<u8>,
    at: usize,
    /// Bytes collected in the aligned part.
    len: usize,
    /// Bytes written to the file so far.
    written: u64,
    direct: bool,
}

impl DirectFile {
    /// Creates (or truncates) `path`.
    pub fn create(path: &Path) -> io::Result<DirectFile> {
        let (file, direct) = open(path)?;
        let buf = vec![0u8; CHUNK + ALIGN];
        let at = buf.as_ptr().align_offset(ALIGN).min(ALIGN);
        Ok(DirectFile {
            file,
            buf,
            at,
            len: 0,
            written: 0,
            direct,
        })
    }

    /// Writes `buf[at..at + n]` (`n` a multiple of [`ALIGN`] when direct).
    /// A direct write the filesystem refuses (or one left unaligned by a
    /// short write) turns `O_DIRECT` off and goes on buffered from there.
    fn put(&mut self, n: usize) -> io::Result<()> {
        let mut done = 0;
        while done < n {
            match self.file.write(&self.buf[self.at + done..self.at + n]) {
                Ok(0) => return Err(io::ErrorKind::WriteZero.into()),
                Ok(k) => done += k,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) if self.direct && e.kind() == io::ErrorKind::InvalidInput => {
                    self.direct = false;
                    buffered(&self.file)?;
                }
                Err(e) => return Err(e),
            }
        }
        self.written += n as u64;
        Ok(())
    }

    /// Writes what is left: a direct file its last page padded, then cut
    /// back to its length.
    pub fn finish(mut self) -> io::Result<()> {
        let n = self.len;
        if !self.direct {
            return self.put(n);
        }
        let padded = n.div_ceil(ALIGN) * ALIGN;
        self.buf[self.at + n..self.at + padded].fill(0);
        self.put(padded)?;
        let length = self.written - (padded - n) as u64;
        self.file.set_len(length)
    }
}

impl Write for DirectFile {
    fn write(&mut self, data: &[u8]) -> io::Result<usize> {
        let n = data.len().min(CHUNK - self.len);
        let start = self.at + self.len;
        self.buf[start..start + n].copy_from_slice(&data[..n]);
        self.len += n;
        if self.len == CHUNK {
            self.put(CHUNK)?;
            self.len = 0;
        }
        Ok(n)
    }

    /// Whole pages only wait for [`DirectFile::finish`]; nothing to do here.
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

#[cfg(target_os = "linux")]
fn open(path: &Path) -> io::Result<(File, bool)> {
    use std::os::unix::fs::OpenOptionsExt;
    let mut options = std::fs::OpenOptions::new();
    options.write(true).create(true).truncate(true);
    let direct = rustix::fs::OFlags::DIRECT.bits() as i32;
    match options.clone().custom_flags(direct).open(path) {
        Ok(file) => Ok((file, true)),
        Err(e) if e.kind() == io::ErrorKind::InvalidInput => Ok((options.open(path)?, false)),
        Err(e) => Err(e),
    }
}

#[cfg(not(target_os = "linux"))]
fn open(path: &Path) -> io::Result<(File, bool)> {
    Ok((File::create(path)?, false))
}

/// Turns `O_DIRECT` off on `file`.
#[cfg(target_os = "linux")]
fn buffered(file: &File) -> io::Result<()> {
    let flags = rustix::fs::fcntl_getfl(file)?;
    rustix::fs::fcntl_setfl(file, flags - rustix::fs::OFlags::DIRECT)?;
    Ok(())
}

#[cfg(not(target_os = "linux"))]
fn buffered(_file: &File) -> io::Result<()> {
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lengths around the page and chunk sizes, written in pieces of awkward
    /// sizes, read back equal (direct where the test folder's filesystem
    /// takes it, buffered otherwise).
    #[test]
    fn writes_any_length_exactly() {
        let dir = tempfile::tempdir().unwrap();
        for len in [
            0,
            1,
            4095,
            4096,
            4097,
            CHUNK - 1,
            CHUNK,
            CHUNK + 1,
            2 * CHUNK + 12345,
        ] {
            let data: Vec<u8> = (0..len).map(|i| (i * 7 + i / 4096) as u8).collect();
            let path = dir.path().join(format!("f{len}"));
            let mut f = DirectFile::create(&path).unwrap();
            for piece in data.chunks(1000 + len % 977) {
                f.write_all(piece).unwrap();
            }
            f.finish().unwrap();
            assert_eq!(std::fs::read(&path).unwrap(), data, "length {len}");
        }
    }

    /// A file that was longer is cut to the new length.
    #[test]
    fn replaces_a_longer_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f");
        std::fs::write(&path, vec![9u8; 3 * ALIGN]).unwrap();
        let mut f = DirectFile::create(&path).unwrap();
        f.write_all(b"short").unwrap();
        f.finish().unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"short");
    }
}
