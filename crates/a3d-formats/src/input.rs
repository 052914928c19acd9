//! Opening input files safely, for every reader: only regular files are read
//! (a folder, `/dev/zero`, a FIFO or a socket is refused at once, before any
//! byte is read, so nothing hangs or fills memory), and no read goes past a size
//! limit. Readers call [`read_bytes`] or [`read_text`] instead of `std::fs::read`.
//!
//! Every file opened here is also noted in each live [`ReadLog`], so that a
//! command's outputs can be checked against everything it read, whatever
//! reader read it and on whatever thread (the output guard in
//! `pipeline::io::output` takes a `ReadLog`, not a list a command could forget to
//! fill).
//!
//! What it leaves to the readers: checking declared counts against the bytes
//! actually read (each reader knows its own record sizes).

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError, Weak};

use super::error::{FormatError, ParseError, Position};

/// Largest input file read whole (1 GiB). Larger files are refused with a message
/// rather than read.
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// Largest uncompressed archive entry, whatever the archive's size (1 GiB).
pub const MAX_ENTRY_BYTES: u64 = 1 << 30;

/// An archive entry may expand to at most this many times the archive's size
/// (deflate reaches about 1000× only on degenerate data such as zip bombs; real
/// node tables compress 3–10×) …
pub const ENTRY_EXPANSION: u64 = 32;

/// … or to this many bytes, whichever is larger (32 MiB).
pub const ENTRY_FLOOR_BYTES: u64 = 32 << 20;

/// Most bytes the arrays of one VTK file may decode to, whatever its size
/// (4 GiB of f64 values).
pub const MAX_DECODED_BYTES: u64 = 4 << 30;

/// The decoded size (as f64 values, 8 bytes each) allowed for all the arrays
/// of a VTK file of `file_bytes`: [`ENTRY_EXPANSION`] times its size, at
/// least [`ENTRY_FLOOR_BYTES`], at most [`MAX_DECODED_BYTES`]. Real output
/// (the shipped OGS files the tests read) stays well inside it; a zlib
/// bomb or a declared count the file cannot hold is refused before anything
/// is allocated.
pub fn decoded_limit(file_bytes: u64) -> u64 {
    expansion_limit(file_bytes, MAX_DECODED_BYTES)
}

/// The uncompressed size allowed for one entry of an archive of `archive_bytes`.
pub fn entry_limit(archive_bytes: u64) -> u64 {
    expansion_limit(archive_bytes, MAX_ENTRY_BYTES)
}

/// [`ENTRY_EXPANSION`] times `bytes`, at least [`ENTRY_FLOOR_BYTES`], at most
/// `most`: what compressed input of `bytes` may expand to.
fn expansion_limit(bytes: u64, most: u64) -> u64 {
    bytes
        .saturating_mul(ENTRY_EXPANSION)
        .clamp(ENTRY_FLOOR_BYTES, most)
}

/// The files read while a [`ReadLog`] lives: shared between the log and the
/// registry of live logs.
type Reads = Mutex<Vec<PathBuf>>;

/// The live logs. A log unregisters itself when dropped; dead entries are
/// pruned on the next registration.
static LIVE_LOGS: Mutex<Vec<Weak<Reads>>> = Mutex::new(Vec::new());

/// Every input file opened, by any reader on any thread, from the moment the
/// log starts until it is dropped. A command starts one before it reads
/// anything; its output guard refuses to write over any file in it. Logs of
/// calls running at the same time in one process also see each other's reads,
/// which can only make the guard stricter.
#[derive(Debug)]
pub struct ReadLog {
    reads: Arc<Reads>,
}

impl ReadLog {
    /// Starts recording.
    pub fn start() -> ReadLog {
        let reads = Arc::new(Mutex::new(Vec::new()));
        let mut live = LIVE_LOGS.lock().unwrap_or_else(PoisonError::into_inner);
        live.retain(|w| w.strong_count() > 0);
        live.push(Arc::downgrade(&reads));
        ReadLog { reads }
    }

    /// The files read so far, in the order first opened, each once.
    pub fn files(&self) -> Vec<PathBuf> {
        self.reads
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }

    /// Notes a file read other than through this module.
    pub fn note(&self, path: &Path) {
        push_once(&self.reads, path);
    }
}

impl Drop for ReadLog {
    fn drop(&mut self) {
        let mut live = LIVE_LOGS.lock().unwrap_or_else(PoisonError::into_inner);
        live.retain(|w| {
            w.strong_count() > 0 && !std::ptr::eq(w.as_ptr(), Arc::as_ptr(&self.reads))
        });
    }
}

fn push_once(reads: &Reads, path: &Path) {
    let mut reads = reads.lock().unwrap_or_else(PoisonError::into_inner);
    if !reads.iter().any(|p| p == path) {
        reads.push(path.to_path_buf());
    }
}

/// Notes `path` in every live [`ReadLog`].
fn record(path: &Path) {
    let live: Vec<Arc<Reads>> = LIVE_LOGS
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .iter()
        .filter_map(Weak::upgrade)
        .collect();
    for reads in live {
        push_once(&reads, path);
    }
}

/// Notes `path` in every live [`ReadLog`] without reading it: a file the
/// command depends on but does not open (the other outputs of a `.pvd`
/// series), which no output may then replace or delete.
pub fn protect(path: &Path) {
    record(path);
}

/// A file's identity (device, inode) where the platform has one: two paths
/// with the same identity are one file (a hard link, a symlink, `..`).
#[cfg(unix)]
pub fn identity(meta: &std::fs::Metadata) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    Some((meta.dev(), meta.ino()))
}

#[cfg(not(unix))]
pub fn identity(_meta: &std::fs::Metadata) -> Option<(u64, u64)> {
    None
}

/// Opens `path` for reading if it is a regular file (symlinks followed) and
/// returns it with its size. Anything else is refused without blocking: the
/// type is checked before opening, and the open itself is non-blocking so a file
/// swapped for a FIFO in between cannot hang the run. The path is noted in
/// every live [`ReadLog`] first.
pub fn open_regular(path: &Path) -> Result<(File, u64), FormatError> {
    record(path);
    let meta = std::fs::metadata(path).map_err(|e| FormatError::io(path, e))?;
    check_kind(path, &meta)?;
    let file = open_nonblocking(path).map_err(|e| FormatError::io(path, e))?;
    let meta = file.metadata().map_err(|e| FormatError::io(path, e))?;
    check_kind(path, &meta)?;
    Ok((file, meta.len()))
}

fn check_kind(path: &Path, meta: &std::fs::Metadata) -> Result<(), FormatError> {
    if meta.is_dir() {
        return Err(FormatError::file(path, "is a folder; expected a file"));
    }
    if !meta.is_file() {
        return Err(FormatError::file(
            path,
            "not a regular file (a device, FIFO or socket); give a file",
        ));
    }
    Ok(())
}

#[cfg(target_os = "linux")]
fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    use std::os::unix::fs::OpenOptionsExt;
    let flags = rustix::fs::OFlags::NONBLOCK.bits();
    std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(i32::try_from(flags).unwrap_or(0))
        .open(path)
}

#[cfg(not(target_os = "linux"))]
fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    File::open(path)
}

/// Opens a regular file of at most `limit` bytes (as [`open_regular`]) for a
/// reader that reads it in parts; the reader refuses it when it grows past
/// `limit` while it is read.
pub fn open_limited(path: &Path, limit: u64) -> Result<(File, u64), FormatError> {
    let (file, len) = open_regular(path)?;
    if len > limit {
        return Err(too_large(path, len, limit));
    }
    Ok((file, len))
}

/// Reads a whole regular file of at most `limit` bytes.
pub fn read_bytes_limited(path: &Path, limit: u64) -> Result<Vec<u8>, FormatError> {
    let (file, len) = open_limited(path, limit)?;
    let mut bytes = Vec::with_capacity(usize::try_from(len).unwrap_or(0));
    // The file may grow while it is read: never read more than the limit.
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| FormatError::io(path, e))?;
    if bytes.len() as u64 > limit {
        return Err(too_large(path, bytes.len() as u64, limit));
    }
    Ok(bytes)
}

/// The error for a file of `len` bytes or more over `limit`.
pub(crate) fn too_large(path: &Path, len: u64, limit: u64) -> FormatError {
    FormatError::file(
        path,
        format!("{len} bytes or more, larger than the {limit}-byte limit on an input file"),
    )
}

/// Reads a whole regular file (at most [`MAX_INPUT_BYTES`]).
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, FormatError> {
    read_bytes_limited(path, MAX_INPUT_BYTES)
}

/// Reads a regular text file, giving the place of the first invalid UTF-8 byte.
pub fn read_text(path: &Path) -> Result<String, FormatError> {
    let bytes = read_bytes(path)?;
    String::from_utf8(bytes).map_err(|e| {
        let valid = e.utf8_error().valid_up_to();
        let text = String::from_utf8_lossy(&e.as_bytes()[..valid]).into_owned();
        FormatError::Parse(ParseError::new(
            path,
            Position::of_byte(&text, valid),
            "the file is not valid UTF-8 text (binary file?)",
        ))
    })
}

/// Reads one entry of an archive through `reader`, refusing more than `limit`
/// bytes whatever size the entry declares (`declared` only sizes the buffer).
pub fn read_entry_limited(
    mut reader: impl Read,
    declared: u64,
    limit: u64,
) -> std::io::Result<Result<Vec<u8>, u64>> {
    if declared > limit {
        return Ok(Err(declared));
    }
    let mut bytes = Vec::with_capacity(usize::try_from(declared).unwrap_or(0));
    (&mut reader).take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Ok(Err(bytes.len() as u64));
    }
    Ok(Ok(bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_read_log_sees_every_file_opened_while_it_lives_on_any_thread() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b, c) = (
            dir.path().join("a"),
            dir.path().join("b"),
            dir.path().join("c"),
        );
        for p in [&a, &b, &c] {
            std::fs::write(p, "x").unwrap();
        }
        read_bytes(&a).unwrap();
        let log = ReadLog::start();
        read_bytes(&b).unwrap();
        std::thread::scope(|s| {
            s.spawn(|| read_text(&c).unwrap());
        });
        read_bytes(&b).unwrap();
        let files = log.files();
        assert!(!files.contains(&a), "{files:?}");
        assert_eq!(files.iter().filter(|p| **p == b).count(), 1, "{files:?}");
        assert!(files.contains(&c), "{files:?}");
        drop(log);
        assert!(
            LIVE_LOGS
                .lock()
                .unwrap()
                .iter()
                .all(|w| w.strong_count() > 0),
            "a dropped log stays registered"
        );
    }

    #[test]
    fn folders_and_devices_are_refused_before_reading() {
        let dir = tempfile::tempdir().unwrap();
        let e = read_bytes(dir.path()).unwrap_err().to_string();
        assert!(e.contains("is a folder"), "{e}");
        if Path::new("/dev/zero").exists() {
            let e = read_bytes(Path::new("/dev/zero")).unwrap_err().to_string();
            assert!(e.contains("not a regular file"), "{e}");
        }
    }

    #[test]
    fn a_file_over_the_limit_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("big");
        std::fs::write(&p, vec![b'a'; 100]).unwrap();
        assert!(read_bytes_limited(&p, 99).is_err());
        assert_eq!(read_bytes_limited(&p, 100).unwrap().len(), 100);
    }

    #[test]
    fn an_entry_longer_than_declared_is_cut_at_the_limit() {
        let data = vec![0u8; 1000];
        assert_eq!(read_entry_limited(&data[..], 10, 500).unwrap(), Err(501));
        assert_eq!(read_entry_limited(&data[..], 1000, 500).unwrap(), Err(1000));
        assert_eq!(
            read_entry_limited(&data[..], 0, 1000)
                .unwrap()
                .unwrap()
                .len(),
            1000
        );
    }

    #[test]
    fn entry_limit_scales_with_the_archive_within_bounds() {
        assert_eq!(entry_limit(0), ENTRY_FLOOR_BYTES);
        assert_eq!(entry_limit(10 << 20), 320 << 20);
        assert_eq!(entry_limit(u64::MAX), MAX_ENTRY_BYTES);
    }
}
