//! Safe output: every file is written to a temporary sibling and renamed into
//! place only when complete, an existing output is refused without `--force`,
//! and an input is never overwritten or deleted, whatever the flags.
//!
//! Output folders are built in a hidden staging folder beside the target. The
//! commit is one `renameat2` call: `RENAME_NOREPLACE` for a new folder, and
//! `RENAME_EXCHANGE` to replace an old one under `--force`, so at every instant
//! the target path holds either the complete old folder or the complete new one.
//! The old folder then sits under the hidden staging name and is deleted; a run
//! killed at that moment leaves a hidden `.a3d-init-staging-*` folder beside the
//! target (the target itself is complete). On a filesystem without
//! `RENAME_EXCHANGE` (or off Linux) the replacement falls back to two renames,
//! old → hidden backup, staging → target: between them the target path is
//! briefly absent while the complete old folder is kept under the backup name,
//! and it is moved back if the second rename fails. That one window cannot be
//! closed without `RENAME_EXCHANGE`.
//!
//! Inputs: before anything is created, the output path is compared with every
//! input by canonical path and by file identity (device, inode) of the input and
//! each of its ancestor folders, so a symlink, a hard link, `..` or a bind mount
//! cannot make an output delete an input. The refusal names both paths.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};

/// A file's identity (device, inode) where the platform has one.
#[cfg(unix)]
fn identity(meta: &std::fs::Metadata) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    Some((meta.dev(), meta.ino()))
}

#[cfg(not(unix))]
fn identity(_meta: &std::fs::Metadata) -> Option<(u64, u64)> {
    None
}

/// Refuses an output path that is an input, or a folder holding one (compared by
/// canonical path and by file identity, symlinks followed).
/// The `wrote      DIR/ (a, b, c)` line a command prints once its folder is written.
pub fn wrote(target: &Path, files: &[&str]) -> String {
    format!("wrote      {}/ ({})", target.display(), files.join(", "))
}

pub fn refuse_inputs(target: &Path, inputs: &[&Path]) -> anyhow::Result<()> {
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
            bail!(
                "refusing to write {}: it {what} the input {}; choose another output path",
                target.display(),
                input.display()
            );
        }
    }
    Ok(())
}

/// Writes `path` atomically through `fill`. Refuses to replace an existing file
/// unless `force`, and refuses always when `path` is one of `inputs` or is not a
/// regular file.
pub fn write_new(
    path: &Path,
    force: bool,
    inputs: &[&Path],
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> anyhow::Result<()> {
    refuse_inputs(path, inputs)?;
    if let Ok(meta) = std::fs::symlink_metadata(path) {
        if !force {
            bail!("{} exists; pass --force to replace it", path.display());
        }
        if !meta.is_file() {
            bail!(
                "{} exists and is not a regular file; refusing to replace it",
                path.display()
            );
        }
    }
    let dir = parent_of(path);
    let tmp = tempfile::Builder::new()
        .prefix(".a3d-init-")
        .tempfile_in(&dir)
        .with_context(|| format!("creating a file in {}", dir.display()))?;
    {
        let mut w = BufWriter::new(tmp.as_file());
        fill(&mut w).with_context(|| format!("writing {}", path.display()))?;
        w.flush()?;
    }
    tmp.as_file().sync_all().ok();
    if force {
        tmp.persist(path)
            .with_context(|| format!("renaming into {}", path.display()))?;
    } else {
        tmp.persist_noclobber(path)
            .with_context(|| format!("renaming into {}", path.display()))?;
    }
    Ok(())
}

fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// An output folder under construction. Files go into a hidden temporary sibling;
/// [`OutputDir::commit`] moves it to the final name. Dropping it without commit
/// removes everything, and so does every failed commit.
pub struct OutputDir {
    target: PathBuf,
    staging: Option<tempfile::TempDir>,
    force: bool,
}

impl OutputDir {
    /// Prepares `target`. `inputs` are the files this run reads: the target may
    /// neither be nor hold any of them, whatever `force` says.
    pub fn create(target: &Path, force: bool, inputs: &[&Path]) -> anyhow::Result<OutputDir> {
        refuse_inputs(target, inputs)?;
        // `.`, `..`, `/` or a folder holding the working directory: replacing it
        // would pull the ground from under the run (and the user).
        if target.file_name().is_none() {
            bail!(
                "{}: give the output folder by name, not `.`, `..` or `/`",
                target.display()
            );
        }
        if let (Ok(t), Ok(cwd)) = (
            std::fs::canonicalize(target),
            std::env::current_dir().and_then(std::fs::canonicalize),
        ) && cwd.starts_with(&t)
        {
            bail!(
                "refusing to write {}: it holds the working directory",
                target.display()
            );
        }
        if let Ok(meta) = std::fs::symlink_metadata(target) {
            if !force {
                bail!("{} exists; pass --force to replace it", target.display());
            }
            let is_dir = std::fs::metadata(target).is_ok_and(|m| m.is_dir());
            if !meta.is_symlink() && !is_dir {
                bail!(
                    "{} exists and is not a folder; refusing to replace it",
                    target.display()
                );
            }
        }
        let parent = parent_of(target);
        std::fs::create_dir_all(&parent)
            .with_context(|| format!("creating {}", parent.display()))?;
        let staging = tempfile::Builder::new()
            .prefix(".a3d-init-staging-")
            .tempdir_in(&parent)
            .with_context(|| format!("creating a folder in {}", parent.display()))?;
        Ok(OutputDir {
            target: target.to_path_buf(),
            staging: Some(staging),
            force,
        })
    }

    /// Path of `name` inside the staging folder.
    pub fn path(&self, name: &str) -> PathBuf {
        self.staging
            .as_ref()
            .map_or_else(|| self.target.join(name), |s| s.path().join(name))
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
    ) -> anyhow::Result<()> {
        let path = self.path(name);
        let file =
            std::fs::File::create(&path).with_context(|| format!("creating {}", path.display()))?;
        let mut w = BufWriter::new(file);
        fill(&mut w).with_context(|| format!("writing {}", path.display()))?;
        w.flush()?;
        Ok(())
    }

    /// Copies an input file into the staging folder, byte for byte.
    pub fn copy(&self, from: &Path, name: &str) -> anyhow::Result<()> {
        let meta = std::fs::metadata(from).with_context(|| from.display().to_string())?;
        if !meta.is_file() {
            bail!("{}: not a regular file", from.display());
        }
        std::fs::copy(from, self.path(name))
            .with_context(|| format!("copying {}", from.display()))?;
        Ok(())
    }

    /// Moves the finished folder into place (replacing an old one under `--force`,
    /// atomically where the filesystem allows; see the module notes). On any error
    /// the staging folder is removed and the old target is left as it was.
    pub fn commit(mut self) -> anyhow::Result<PathBuf> {
        let Some(staging) = self.staging.take() else {
            return Ok(self.target.clone());
        };
        let target = self.target.clone();
        let exists = std::fs::symlink_metadata(&target).is_ok();
        if !exists {
            rename_noreplace(staging.path(), &target)
                .with_context(|| format!("moving output into {}", target.display()))?;
            // The staging path is gone; keep() stops TempDir from looking for it.
            let _ = staging.keep();
            return Ok(target);
        }
        if !self.force {
            bail!("{} exists; pass --force to replace it", target.display());
        }
        match exchange(staging.path(), &target) {
            Ok(()) => {
                // The staging path now holds the old output: dropping TempDir deletes it.
                remove_old(staging);
                Ok(target)
            }
            Err(e) if exchange_unsupported(&e) => replace_by_two_renames(staging, &target),
            Err(e) => Err(anyhow::Error::new(e).context(format!(
                "replacing {} with the new output",
                target.display()
            ))),
        }
    }
}

/// Deletes an old output now under the staging name (a folder, or a symlink that
/// pointed at one).
fn remove_old(staging: tempfile::TempDir) {
    let path = staging.keep();
    match std::fs::symlink_metadata(&path) {
        Ok(m) if m.is_dir() => {
            let _ = std::fs::remove_dir_all(&path);
        }
        Ok(_) => {
            let _ = std::fs::remove_file(&path);
        }
        Err(_) => {}
    }
}

/// The fallback without `RENAME_EXCHANGE`: old → hidden backup, staging → target,
/// backup deleted; the old folder is moved back if the second rename fails.
fn replace_by_two_renames(staging: tempfile::TempDir, target: &Path) -> anyhow::Result<PathBuf> {
    let parent = parent_of(target);
    let backup = tempfile::Builder::new()
        .prefix(".a3d-init-old-")
        .tempdir_in(&parent)
        .with_context(|| format!("creating a folder in {}", parent.display()))?;
    let backup_path = backup.keep();
    // rename() onto an empty folder replaces it.
    if let Err(e) = std::fs::rename(target, &backup_path) {
        let _ = std::fs::remove_dir(&backup_path);
        return Err(
            anyhow::Error::new(e).context(format!("moving the old {} aside", target.display()))
        );
    }
    if let Err(e) = rename_noreplace(staging.path(), target) {
        let _ = std::fs::rename(&backup_path, target);
        return Err(e.context(format!("moving output into {}", target.display())));
    }
    let _ = staging.keep();
    match std::fs::symlink_metadata(&backup_path) {
        Ok(m) if m.is_dir() => {
            let _ = std::fs::remove_dir_all(&backup_path);
        }
        _ => {
            let _ = std::fs::remove_file(&backup_path);
        }
    }
    Ok(target.to_path_buf())
}

#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
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
fn rename_noreplace(from: &Path, to: &Path) -> anyhow::Result<()> {
    #[cfg(target_os = "linux")]
    {
        use rustix::fs::{CWD, RenameFlags, renameat_with};
        match renameat_with(CWD, from, CWD, to, RenameFlags::NOREPLACE) {
            Ok(()) => return Ok(()),
            Err(e) => {
                let e = std::io::Error::from(e);
                if !exchange_unsupported(&e) {
                    if e.kind() == std::io::ErrorKind::AlreadyExists {
                        bail!("{} appeared while this run was writing", to.display());
                    }
                    return Err(e.into());
                }
            }
        }
    }
    if std::fs::symlink_metadata(to).is_ok() {
        bail!("{} appeared while this run was writing", to.display());
    }
    std::fs::rename(from, to)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A temporary folder holding `out/old.txt`: (the folder, `out`).
    fn old_output() -> (tempfile::TempDir, PathBuf) {
        let tmp = tempfile::tempdir().unwrap();
        let target = tmp.path().join("out");
        std::fs::create_dir(&target).unwrap();
        std::fs::write(target.join("old.txt"), "old").unwrap();
        (tmp, target)
    }

    /// `out` holds `new.txt` and not `old.txt`, and nothing is left beside it.
    fn assert_replaced(tmp: &Path, target: &Path) {
        assert!(!target.join("old.txt").exists());
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
        let out = OutputDir::create(&target, true, &[]).unwrap();
        out.write("new.txt", |w| w.write_all(b"new")).unwrap();
        out.commit().unwrap();
        assert_replaced(tmp.path(), &target);
    }

    #[test]
    fn two_rename_fallback_replaces_too() {
        let (tmp, target) = old_output();
        let staging = tempfile::tempdir_in(tmp.path()).unwrap();
        std::fs::write(staging.path().join("new.txt"), "new").unwrap();
        replace_by_two_renames(staging, &target).unwrap();
        assert_replaced(tmp.path(), &target);
    }

    #[test]
    fn an_output_holding_or_being_an_input_is_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let input = tmp.path().join("in.csv");
        std::fs::write(&input, "x").unwrap();
        let e = refuse_inputs(tmp.path(), &[&input])
            .unwrap_err()
            .to_string();
        assert!(e.contains("holds the input"), "{e}");
        let e = refuse_inputs(&input, &[&input]).unwrap_err().to_string();
        assert!(e.contains("is the input"), "{e}");
        refuse_inputs(&tmp.path().join("elsewhere"), &[&input]).unwrap();
    }
}
