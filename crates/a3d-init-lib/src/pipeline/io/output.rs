//! Safe, durable output: every file is written to a temporary sibling (or a
//! hidden staging folder) and published by a rename only when complete and on
//! disk; an existing output is refused without `force`; and an input is never
//! overwritten or deleted, whatever the flags.
//!
//! **Durable before visible.** Before the rename that publishes an output,
//! every file in it and the staging folder itself are synced (`fsync`), so a
//! power cut or a kernel crash cannot leave the new name pointing at data that
//! never reached the disk. After the rename, the parent folder is synced so the
//! new name itself survives. An error from any sync is an error of the run,
//! naming the path; the old output then stays in place. The order is recorded
//! for tests ([`trace`], feature `output-trace`), and `tests/it/durability.rs` also
//! checks it with `strace` where the machine has it.
//!
//! **Atomic.** Output folders are built in a hidden staging folder beside the
//! target. The commit is one `renameat2` call: `RENAME_NOREPLACE` for a new
//! folder, and `RENAME_EXCHANGE` to replace an old one under `force`, so at
//! every instant the target path holds either the complete old folder or the
//! complete new one. The old folder then sits under the hidden staging name and
//! is deleted; a run killed at that moment leaves a hidden
//! `.a3d-init-staging-*` folder beside the target (the target itself is
//! complete). On a filesystem without `RENAME_EXCHANGE` (or off Linux) the
//! replacement falls back to two renames, old → hidden backup, staging →
//! target: between them the target path is briefly absent while the complete
//! old folder is kept under the backup name, and it is moved back if the second
//! rename fails. That one window cannot be closed without `RENAME_EXCHANGE`.
//!
//! **Interrupted.** Every hidden path a run is writing (a staging folder, a
//! temporary sibling, an old output set aside) is listed while it exists.
//! [`discard_unfinished`] deletes them all: the command line calls it on
//! SIGINT, SIGTERM or SIGHUP before it exits, so Ctrl-C leaves neither a
//! partial output nor a hidden folder. It waits for a commit's renames to
//! end, so it finds either the unfinished new folder or the old one set
//! aside, never the only copy of an output. Only SIGKILL (or a crash of the
//! machine) can leave a `.a3d-init-staging-*` folder behind.
//!
//! **Inputs.** The guard takes a [`ReadLog`]: every file the command opened
//! through [`crate::formats::input`], on any thread, since it started. Before
//! anything is created, and again just before the commit replaces anything, the
//! output path is compared with every one of them by canonical path and by file
//! identity (device, inode) of the input and each of its ancestor folders, so a
//! symlink, a hard link, `..` or a bind mount cannot make an output delete an
//! input. The refusal names both paths.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

pub use crate::formats::input::ReadLog;
use crate::formats::input::identity;
use crate::pipeline::PipelineError;

/// Where a command writes its output folder, and whether an existing one may
/// be replaced (an input is never replaced, whatever this says).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Destination<'a> {
    /// The folder; `None`: the command's default folder.
    pub folder: Option<&'a Path>,
    /// Replace an existing folder (the CLI's `--force`).
    pub replace: bool,
}

impl<'a> Destination<'a> {
    /// `folder` (or the command's default), replacing an existing one when
    /// `replace`.
    pub fn new(folder: Option<&'a Path>, replace: bool) -> Destination<'a> {
        Destination { folder, replace }
    }

    /// The folder given, else `default`.
    pub fn or(&self, default: impl FnOnce() -> PathBuf) -> PathBuf {
        self.folder.map_or_else(default, Path::to_path_buf)
    }
}

fn refused(message: String) -> PipelineError {
    PipelineError::Output(message)
}

fn io_error(what: impl std::fmt::Display, e: std::io::Error) -> PipelineError {
    PipelineError::Output(format!("{what}: {e}"))
}

/// Refuses an output path that is an input, or a folder holding one (compared by
/// canonical path and by file identity, symlinks followed).
pub fn refuse_inputs(target: &Path, inputs: &[PathBuf]) -> Result<(), PipelineError> {
    // A target that does not exist yet holds nothing.
    let Ok(target_meta) = std::fs::metadata(target) else {
        return Ok(());
    };
    let target_id = identity(&target_meta);
    let target_abs = std::fs::canonicalize(target).ok();
    for input in inputs {
        let Ok(input_abs) = std::fs::canonicalize(input) else {
            continue;
        };
        let mut clash = target_abs
            .as_ref()
            .is_some_and(|t| input_abs.starts_with(t));
        if !clash && target_id.is_some() {
            clash = input_abs
                .ancestors()
                .filter_map(|a| std::fs::metadata(a).ok())
                .any(|m| identity(&m) == target_id);
        }
        if clash {
            let what = if target_meta.is_dir() { "holds" } else { "is" };
            return Err(refused(format!(
                "refusing to write {}: it {what} the input {}; choose another output path",
                target.display(),
                input.display()
            )));
        }
    }
    Ok(())
}

/// Writes `path` atomically and durably through `fill`. Refuses to replace an
/// existing file unless `force`, and refuses always when `path` is a file the
/// command read (`reads`) or is not a regular file.
pub fn write_new(
    path: &Path,
    force: bool,
    reads: &ReadLog,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), PipelineError> {
    refuse_inputs(path, &reads.files())?;
    if let Ok(meta) = std::fs::symlink_metadata(path) {
        if !force {
            return Err(PipelineError::Exists(path.to_path_buf()));
        }
        if !meta.is_file() {
            return Err(refused(format!(
                "{} exists and is not a regular file; refusing to replace it",
                path.display()
            )));
        }
    }
    let dir = parent_of(path);
    let listed: Unfinished;
    let tmp = tempfile::Builder::new()
        .prefix(".a3d-init-")
        .tempfile_in(&dir)
        .map_err(|e| io_error(format_args!("creating a file in {}", dir.display()), e))?;
    listed = Unfinished::new(tmp.path());
    {
        let mut w = BufWriter::new(tmp.as_file());
        fill(&mut w)
            .and_then(|()| w.flush())
            .map_err(|e| io_error(format_args!("writing {}", path.display()), e))?;
    }
    sync::file(tmp.as_file(), tmp.path())?;
    refuse_inputs(path, &reads.files())?;
    let persisted = if force {
        tmp.persist(path)
    } else {
        tmp.persist_noclobber(path)
    };
    persisted.map_err(|e| io_error(format_args!("renaming into {}", path.display()), e.error))?;
    drop(listed);
    sync::trace_event(trace::Event::Rename(path.to_path_buf()));
    sync::dir(&dir)
}

/// The hidden paths this process is writing and has neither published nor
/// removed: staging folders, temporary siblings of single files, old
/// outputs set aside for deletion. A commit holds the lock across its
/// renames.
static UNFINISHED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn unfinished() -> MutexGuard<'static, Vec<PathBuf>> {
    UNFINISHED.lock().unwrap_or_else(PoisonError::into_inner)
}

/// A path listed in [`UNFINISHED`] for as long as this lives. Declared before
/// the temporary folder or file it names, so that it outlives it: the path
/// is removed, then unlisted.
struct Unfinished(PathBuf);

impl Unfinished {
    fn new(path: &Path) -> Unfinished {
        unfinished().push(path.to_path_buf());
        Unfinished(path.to_path_buf())
    }
}

impl Drop for Unfinished {
    fn drop(&mut self) {
        let mut list = unfinished();
        if let Some(i) = list.iter().rposition(|p| *p == self.0) {
            list.swap_remove(i);
        }
    }
}

/// Deletes every unfinished output of this process (see the module notes)
/// and returns the paths it removed. For a signal handler that then ends
/// the process: it waits for a commit's renames to finish, and keeps the
/// list locked from then on, so that nothing is published after it.
pub fn discard_unfinished() -> Vec<PathBuf> {
    let list = unfinished();
    let mut removed = Vec::new();
    for path in list.iter() {
        // A thread still writing may add a file while the folder goes: a
        // few passes.
        for _ in 0..5 {
            remove_path(path);
            if std::fs::symlink_metadata(path).is_err() {
                removed.push(path.clone());
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
    }
    // Held until the process ends.
    std::mem::forget(list);
    removed
}

fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The file every output folder holds, naming the tool and the command that
/// wrote it: `force` replaces a folder only when it holds this (or is empty),
/// so a mistyped `--out` cannot delete a folder of the user's.
pub const MARKER: &str = ".a3d-init-output";

/// The first line of [`MARKER`], by which an output folder is recognised.
const MARKER_HEAD: &str = "a3d-init output folder";

fn marker_text(command: &str) -> String {
    format!(
        "{MARKER_HEAD}\ntool: a3d-init {}\ncommand: {command}\n\nWritten by a3d-init; replacing an output may replace this folder whole.\n",
        env!("CARGO_PKG_VERSION")
    )
}

/// Whether the existing `target` may be replaced: an empty folder, or a
/// folder holding a3d-init's [`MARKER`] (symlinks followed). Anything else is
/// an error naming the folder and why.
fn replaceable(target: &Path) -> Result<(), PipelineError> {
    let meta = std::fs::metadata(target).map_err(|e| io_error(target.display(), e))?;
    if !meta.is_dir() {
        return Err(refused(format!(
            "{} exists and is not a folder; refusing to replace it",
            target.display()
        )));
    }
    let mut entries = std::fs::read_dir(target).map_err(|e| io_error(target.display(), e))?;
    if entries.next().is_none() {
        return Ok(());
    }
    let marker = target.join(MARKER);
    // Read directly, not as an input (an input is never replaced).
    let is_ours = std::fs::symlink_metadata(&marker).is_ok_and(|m| m.is_file())
        && std::fs::File::open(&marker).is_ok_and(|f| {
            let mut head = Vec::new();
            std::io::Read::read_to_end(&mut std::io::Read::take(f, 256), &mut head).is_ok()
                && head.starts_with(MARKER_HEAD.as_bytes())
        });
    if is_ours {
        return Ok(());
    }
    Err(refused(format!(
        "refusing to replace {}: it is not empty and a3d-init did not write it (no {MARKER} in it); replacing an output applies only to a3d-init's own output folders: choose another output path",
        target.display()
    )))
}

/// An output folder under construction. Files go into a hidden temporary sibling;
/// [`OutputDir::commit`] syncs it and moves it to the final name. Dropping it
/// without commit removes everything, and so does every failed commit.
pub struct OutputDir<'a> {
    target: PathBuf,
    staging: Option<tempfile::TempDir>,
    /// The staging folder's place in [`UNFINISHED`], dropped after it.
    listed: Option<Unfinished>,
    force: bool,
    reads: &'a ReadLog,
}

impl<'a> OutputDir<'a> {
    /// Prepares `target`. `reads` holds the files this command read: the target
    /// may neither be nor hold any of them, whatever `force` says (checked now
    /// and again at the commit).
    ///
    /// An existing `target` is replaced (under `force`) only when it is an
    /// empty folder or an output folder of a3d-init (it holds [`MARKER`]);
    /// anything else is refused whatever `force` says. `command` names the
    /// command in the new folder's marker.
    pub fn create(
        target: &Path,
        force: bool,
        reads: &'a ReadLog,
        command: &str,
    ) -> Result<OutputDir<'a>, PipelineError> {
        refuse_inputs(target, &reads.files())?;
        // `.`, `..`, `/` or a folder holding the working directory: replacing it
        // would pull the ground from under the run (and the user).
        if target.file_name().is_none() {
            return Err(refused(format!(
                "{}: give the output folder by name, not `.`, `..` or `/`",
                target.display()
            )));
        }
        if let (Ok(t), Ok(cwd)) = (
            std::fs::canonicalize(target),
            std::env::current_dir().and_then(std::fs::canonicalize),
        ) && cwd.starts_with(&t)
        {
            return Err(refused(format!(
                "refusing to write {}: it holds the working directory",
                target.display()
            )));
        }
        if std::fs::symlink_metadata(target).is_ok() {
            if !force {
                return Err(PipelineError::Exists(target.to_path_buf()));
            }
            replaceable(target)?;
        }
        let parent = parent_of(target);
        std::fs::create_dir_all(&parent)
            .map_err(|e| io_error(format_args!("creating {}", parent.display()), e))?;
        let staging = tempfile::Builder::new()
            .prefix(".a3d-init-staging-")
            .tempdir_in(&parent)
            .map_err(|e| io_error(format_args!("creating a folder in {}", parent.display()), e))?;
        let listed = Unfinished::new(staging.path());
        let dir = OutputDir {
            target: target.to_path_buf(),
            staging: Some(staging),
            listed: Some(listed),
            force,
            reads,
        };
        dir.write(MARKER, |w| w.write_all(marker_text(command).as_bytes()))?;
        Ok(dir)
    }

    /// Path of `name` inside the staging folder.
    pub fn path(&self, name: &str) -> PathBuf {
        self.staging
            .as_ref()
            .map_or_else(|| self.target.join(name), |s| s.path().join(name))
    }

    /// The staging folder itself (files written there are published by
    /// [`OutputDir::commit`]).
    pub fn staging(&self) -> PathBuf {
        self.path("")
    }

    /// Final path of `name` once committed.
    pub fn final_path(&self, name: &str) -> PathBuf {
        self.target.join(name)
    }

    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Writes `name` into the staging folder.
    pub fn write(
        &self,
        name: &str,
        fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> Result<(), PipelineError> {
        let path = self.path(name);
        let file = std::fs::File::create(&path)
            .map_err(|e| io_error(format_args!("creating {}", path.display()), e))?;
        let mut w = BufWriter::new(file);
        fill(&mut w)
            .and_then(|()| w.flush())
            .map_err(|e| io_error(format_args!("writing {}", path.display()), e))?;
        Ok(())
    }

    /// Copies an input file into the staging folder, byte for byte.
    pub fn copy(&self, from: &Path, name: &str) -> Result<(), PipelineError> {
        let meta = std::fs::metadata(from).map_err(|e| io_error(from.display(), e))?;
        if !meta.is_file() {
            return Err(PipelineError::Input(format!(
                "{}: not a regular file",
                from.display()
            )));
        }
        std::fs::copy(from, self.path(name))
            .map_err(|e| io_error(format_args!("copying {}", from.display()), e))?;
        Ok(())
    }

    /// Syncs the finished folder and moves it into place (replacing an old one
    /// under `force`, atomically where the filesystem allows; see the module
    /// notes), then syncs the parent folder. On any error the staging folder is
    /// removed and the old target is left as it was.
    pub fn commit(mut self) -> Result<PathBuf, PipelineError> {
        // Unlisted when this returns, after the staging folder is published
        // or removed (declared first, dropped last).
        let _listed = self.listed.take();
        let Some(staging) = self.staging.take() else {
            return Ok(self.target.clone());
        };
        sync::tree(staging.path())?;
        let target = self.target.clone();
        let parent = parent_of(&target);
        refuse_inputs(&target, &self.reads.files())?;
        let exists = std::fs::symlink_metadata(&target).is_ok();
        if !exists {
            {
                let _renaming = unfinished();
                rename_noreplace(staging.path(), &target)?;
            }
            // The staging path is gone; keep() stops TempDir from looking for it.
            let _ = staging.keep();
            sync::trace_event(trace::Event::Rename(target.clone()));
            sync::dir(&parent)?;
            return Ok(target);
        }
        if !self.force {
            return Err(PipelineError::Exists(target.to_path_buf()));
        }
        let exchanged = {
            let _renaming = unfinished();
            exchange(staging.path(), &target)
        };
        match exchanged {
            Ok(()) => {
                sync::trace_event(trace::Event::Rename(target.clone()));
                // The new name must be on disk before the old data goes.
                let synced = sync::dir(&parent);
                // The staging path now holds the old output.
                remove_old(staging);
                synced.map(|()| target)
            }
            Err(e) if exchange_unsupported(&e) => replace_by_two_renames(staging, &target),
            Err(e) => Err(io_error(
                format_args!("replacing {} with the new output", target.display()),
                e,
            )),
        }
    }
}

/// Deletes an old output now under the staging name (a folder, or a symlink that
/// pointed at one).
fn remove_old(staging: tempfile::TempDir) {
    remove_path(&staging.keep());
}

fn remove_path(path: &Path) {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => {
            let _ = std::fs::remove_dir_all(path);
        }
        Ok(_) => {
            let _ = std::fs::remove_file(path);
        }
        Err(_) => {}
    }
}

/// The fallback without `RENAME_EXCHANGE`: old → hidden backup, staging → target,
/// parent synced, backup deleted; the old folder is moved back if the second
/// rename fails.
fn replace_by_two_renames(
    staging: tempfile::TempDir,
    target: &Path,
) -> Result<PathBuf, PipelineError> {
    let parent = parent_of(target);
    let backup = tempfile::Builder::new()
        .prefix(".a3d-init-old-")
        .tempdir_in(&parent)
        .map_err(|e| io_error(format_args!("creating a folder in {}", parent.display()), e))?;
    let backup_path = backup.keep();
    let _listed = Unfinished::new(&backup_path);
    {
        // Both renames under the lock: an interruption between them would
        // find the old output set aside and the new one not yet in place.
        let _renaming = unfinished();
        // rename() onto an empty folder replaces it.
        if let Err(e) = std::fs::rename(target, &backup_path) {
            let _ = std::fs::remove_dir(&backup_path);
            return Err(io_error(
                format_args!("moving the old {} aside", target.display()),
                e,
            ));
        }
        if let Err(e) = rename_noreplace(staging.path(), target) {
            let _ = std::fs::rename(&backup_path, target);
            return Err(e);
        }
    }
    let _ = staging.keep();
    sync::trace_event(trace::Event::Rename(target.to_path_buf()));
    let synced = sync::dir(&parent);
    remove_path(&backup_path);
    synced.map(|()| target.to_path_buf())
}

#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    #[cfg(feature = "output-trace")]
    if trace::no_exchange() {
        return Err(std::io::Error::from(std::io::ErrorKind::Unsupported));
    }
    use rustix::fs::{CWD, RenameFlags, renameat_with};
    renameat_with(CWD, a, CWD, b, RenameFlags::EXCHANGE).map_err(std::io::Error::from)
}

#[cfg(not(target_os = "linux"))]
fn exchange(_a: &Path, _b: &Path) -> std::io::Result<()> {
    Err(std::io::Error::from(std::io::ErrorKind::Unsupported))
}

fn exchange_unsupported(e: &std::io::Error) -> bool {
    e.kind() == std::io::ErrorKind::Unsupported || matches!(e.raw_os_error(), Some(22 | 38 | 95)) // EINVAL, ENOSYS, EOPNOTSUPP
}

/// Renames `from` to `to`, failing if `to` exists (atomically where the
/// filesystem has `RENAME_NOREPLACE`).
fn rename_noreplace(from: &Path, to: &Path) -> Result<(), PipelineError> {
    let appeared = || {
        refused(format!(
            "{} appeared while this run was writing",
            to.display()
        ))
    };
    let failed = |e| io_error(format_args!("moving output into {}", to.display()), e);
    #[cfg(target_os = "linux")]
    {
        use rustix::fs::{CWD, RenameFlags, renameat_with};
        match renameat_with(CWD, from, CWD, to, RenameFlags::NOREPLACE) {
            Ok(()) => return Ok(()),
            Err(e) => {
                let e = std::io::Error::from(e);
                if !exchange_unsupported(&e) {
                    if e.kind() == std::io::ErrorKind::AlreadyExists {
                        return Err(appeared());
                    }
                    return Err(failed(e));
                }
            }
        }
    }
    if std::fs::symlink_metadata(to).is_ok() {
        return Err(appeared());
    }
    std::fs::rename(from, to).map_err(failed)
}

/// The syncs, each an error of the run when it fails.
pub(super) mod sync {
    use std::path::Path;

    use super::trace::Event;
    use super::{PipelineError, io_error};

    pub(in crate::pipeline) fn trace_event(_event: Event) {
        #[cfg(feature = "output-trace")]
        super::trace::push(_event);
    }

    fn check(path: &Path, result: std::io::Result<()>, event: Event) -> Result<(), PipelineError> {
        #[cfg(feature = "output-trace")]
        let result = result.and_then(|()| super::trace::injected(path));
        result.map_err(|e| io_error(format_args!("syncing {} to disk", path.display()), e))?;
        trace_event(event);
        Ok(())
    }

    /// Flushes an open file's data and metadata to disk.
    pub(in crate::pipeline) fn file(
        file: &std::fs::File,
        path: &Path,
    ) -> Result<(), PipelineError> {
        check(path, file.sync_all(), Event::SyncFile(path.to_path_buf()))
    }

    /// Flushes a folder's entries (new names, removed names) to disk.
    pub(in crate::pipeline) fn dir(path: &Path) -> Result<(), PipelineError> {
        let result = std::fs::File::open(path).and_then(|d| d.sync_all());
        check(path, result, Event::SyncDir(path.to_path_buf()))
    }

    /// Every file under `root` (folders included, `root` last) synced.
    pub(in crate::pipeline) fn tree(root: &Path) -> Result<(), PipelineError> {
        let entries = std::fs::read_dir(root)
            .map_err(|e| io_error(format_args!("listing {}", root.display()), e))?;
        let mut paths: Vec<_> = entries
            .map(|e| e.map(|e| e.path()))
            .collect::<Result<_, _>>()
            .map_err(|e| io_error(format_args!("listing {}", root.display()), e))?;
        paths.sort();
        for path in paths {
            let meta = std::fs::symlink_metadata(&path).map_err(|e| io_error(path.display(), e))?;
            if meta.is_dir() {
                tree(&path)?;
            } else if meta.is_file() {
                let f = std::fs::File::open(&path)
                    .map_err(|e| io_error(format_args!("opening {}", path.display()), e))?;
                file(&f, &path)?;
            }
        }
        dir(root)
    }
}

/// The order of syncs and publishing renames, recorded for tests, and a sync
/// that fails on purpose (feature `output-trace` only; without it nothing is
/// recorded and nothing is injected).
pub mod trace {
    use std::path::PathBuf;

    /// One step of publishing an output.
    #[derive(Clone, Debug, PartialEq, Eq)]
    pub enum Event {
        /// A file's data and metadata synced.
        SyncFile(PathBuf),
        /// A folder's entries synced.
        SyncDir(PathBuf),
        /// An output published under this name.
        Rename(PathBuf),
    }

    #[cfg(feature = "output-trace")]
    pub use recording::*;

    #[cfg(feature = "output-trace")]
    mod recording {
        use std::path::Path;
        use std::sync::{Mutex, PoisonError};

        use super::Event;

        static EVENTS: Mutex<Option<Vec<Event>>> = Mutex::new(None);
        static FAIL: Mutex<Option<String>> = Mutex::new(None);
        static NO_EXCHANGE: Mutex<bool> = Mutex::new(false);

        /// Starts recording (clearing what was recorded).
        pub fn start() {
            *EVENTS.lock().unwrap_or_else(PoisonError::into_inner) = Some(Vec::new());
        }

        /// Stops recording and returns the events.
        pub fn take() -> Vec<Event> {
            EVENTS
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .take()
                .unwrap_or_default()
        }

        /// Makes every sync of a path whose file name contains `name` fail
        /// (`None`: none).
        pub fn fail_sync_of(name: Option<&str>) {
            *FAIL.lock().unwrap_or_else(PoisonError::into_inner) = name.map(str::to_string);
        }

        /// Pretends the filesystem has no `RENAME_EXCHANGE` (the two-rename
        /// fallback runs).
        pub fn disable_exchange(off: bool) {
            *NO_EXCHANGE.lock().unwrap_or_else(PoisonError::into_inner) = off;
        }

        pub(in crate::pipeline) fn no_exchange() -> bool {
            *NO_EXCHANGE.lock().unwrap_or_else(PoisonError::into_inner)
        }

        pub(in crate::pipeline) fn push(event: Event) {
            if let Some(events) = EVENTS
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .as_mut()
            {
                events.push(event);
            }
        }

        pub(in crate::pipeline) fn injected(path: &Path) -> std::io::Result<()> {
            let fail = FAIL.lock().unwrap_or_else(PoisonError::into_inner);
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
            match (&*fail, name) {
                (Some(f), Some(n)) if n.contains(f.as_str()) => {
                    Err(std::io::Error::other("injected sync failure"))
                }
                _ => Ok(()),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A temporary folder holding an earlier output `out/` (its marker and
    /// `old.txt`): (the folder, `out`).
    fn old_output() -> (tempfile::TempDir, PathBuf) {
        let tmp = tempfile::tempdir().unwrap();
        let target = tmp.path().join("out");
        std::fs::create_dir(&target).unwrap();
        std::fs::write(target.join("old.txt"), "old").unwrap();
        std::fs::write(target.join(MARKER), marker_text("map")).unwrap();
        (tmp, target)
    }

    #[test]
    fn force_replaces_only_an_empty_folder_or_an_own_output() {
        let tmp = tempfile::tempdir().unwrap();
        let reads = ReadLog::start();
        // A folder of the user's: refused, untouched, nothing left beside it.
        let documents = tmp.path().join("Documents");
        std::fs::create_dir(&documents).unwrap();
        std::fs::write(documents.join("paper.docx"), "thesis").unwrap();
        let e = OutputDir::create(&documents, true, &reads, "map")
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("a3d-init did not write it"), "{e}");
        assert!(e.contains("Documents"), "{e}");
        // A marker that is not ours does not count.
        std::fs::write(documents.join(MARKER), "something else").unwrap();
        assert!(OutputDir::create(&documents, true, &reads, "map").is_err());
        assert_eq!(
            std::fs::read_to_string(documents.join("paper.docx")).unwrap(),
            "thesis"
        );
        let names: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().collect();
        assert_eq!(names.len(), 1);
        // An empty folder is replaced, and the new folder carries the marker.
        let empty = tmp.path().join("empty");
        std::fs::create_dir(&empty).unwrap();
        let out = OutputDir::create(&empty, true, &reads, "verify").unwrap();
        out.commit().unwrap();
        let marker = std::fs::read_to_string(empty.join(MARKER)).unwrap();
        assert!(
            marker.starts_with(MARKER_HEAD) && marker.contains("command: verify"),
            "{marker}"
        );
        // So it can be replaced again; the marker was not read as an input.
        OutputDir::create(&empty, true, &reads, "verify")
            .unwrap()
            .commit()
            .unwrap();
        assert!(
            !reads.files().iter().any(|f| f.ends_with(MARKER)),
            "{:?}",
            reads.files()
        );
    }

    /// `out` holds `new.txt` and not `old.txt`, and nothing is left beside it.
    fn assert_replaced(tmp: &Path, target: &Path) {
        assert!(!target.join("old.txt").exists());
        assert!(target.join(MARKER).exists());
        assert_eq!(
            std::fs::read_to_string(target.join("new.txt")).unwrap(),
            "new"
        );
        let names: Vec<_> = std::fs::read_dir(tmp)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["out"]);
    }

    #[test]
    fn force_replaces_a_folder_completely_and_leaves_no_staging() {
        let (tmp, target) = old_output();
        let reads = ReadLog::start();
        let out = OutputDir::create(&target, true, &reads, "test").unwrap();
        out.write("new.txt", |w| w.write_all(b"new")).unwrap();
        out.commit().unwrap();
        assert_replaced(tmp.path(), &target);
    }

    #[test]
    fn two_rename_fallback_replaces_too() {
        let (tmp, target) = old_output();
        let staging = tempfile::tempdir_in(tmp.path()).unwrap();
        std::fs::write(staging.path().join("new.txt"), "new").unwrap();
        std::fs::write(staging.path().join(MARKER), marker_text("map")).unwrap();
        replace_by_two_renames(staging, &target).unwrap();
        assert_replaced(tmp.path(), &target);
    }

    #[test]
    fn an_output_holding_or_being_an_input_is_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let input = tmp.path().join("in.csv");
        std::fs::write(&input, "x").unwrap();
        let inputs = [input.clone()];
        let e = refuse_inputs(tmp.path(), &inputs).unwrap_err().to_string();
        assert!(e.contains("holds the input"), "{e}");
        let e = refuse_inputs(&input, &inputs).unwrap_err().to_string();
        assert!(e.contains("is the input"), "{e}");
        refuse_inputs(&tmp.path().join("elsewhere"), &inputs).unwrap();
    }

    #[test]
    fn a_file_read_after_the_folder_was_prepared_is_still_protected_at_commit() {
        let (tmp, target) = old_output();
        let reads = ReadLog::start();
        let out = OutputDir::create(&target, true, &reads, "test").unwrap();
        crate::formats::input::read_bytes(&target.join("old.txt")).unwrap();
        out.write("new.txt", |w| w.write_all(b"new")).unwrap();
        let e = out.commit().unwrap_err().to_string();
        assert!(e.contains("holds the input"), "{e}");
        assert_eq!(
            std::fs::read_to_string(target.join("old.txt")).unwrap(),
            "old"
        );
        let names: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "the staging folder is removed");
    }
}
