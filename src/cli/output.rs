//! Safe output: every file is written to a temporary sibling and renamed into
//! place only when complete, an existing output is refused without `--force`,
//! and an input file is never overwritten. Output folders are built the same way:
//! in a temporary sibling folder that replaces the target at the end, so a failed
//! run leaves nothing behind.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};

/// Writes `path` atomically through `fill`. Refuses to replace an existing file
/// unless `force`.
pub fn write_new(
    path: &Path,
    force: bool,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> anyhow::Result<()> {
    if path.exists() && !force {
        bail!("{} exists; pass --force to replace it", path.display());
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let tmp = tempfile::NamedTempFile::new_in(&dir)
        .with_context(|| format!("creating a file in {}", dir.display()))?;
    {
        let mut w = BufWriter::new(tmp.as_file());
        fill(&mut w).with_context(|| format!("writing {}", path.display()))?;
        w.flush()?;
    }
    tmp.as_file().sync_all().ok();
    tmp.persist(path)
        .with_context(|| format!("renaming into {}", path.display()))?;
    Ok(())
}

/// An output folder under construction. Files go into a hidden temporary sibling;
/// [`OutputDir::commit`] moves it to the final name. Dropping it without commit
/// removes everything.
pub struct OutputDir {
    target: PathBuf,
    staging: Option<tempfile::TempDir>,
    force: bool,
}

impl OutputDir {
    /// Prepares `target`. `inputs` are the files this run reads: the target may not
    /// contain or be any of them when `--force` would delete it.
    pub fn create(target: &Path, force: bool, inputs: &[&Path]) -> anyhow::Result<OutputDir> {
        if target.exists() {
            if !force {
                bail!("{} exists; pass --force to replace it", target.display());
            }
            let target_abs = std::fs::canonicalize(target)?;
            for input in inputs {
                if let Ok(input_abs) = std::fs::canonicalize(input)
                    && input_abs.starts_with(&target_abs)
                {
                    bail!(
                        "refusing to replace {}: it holds the input {}",
                        target.display(),
                        input.display()
                    );
                }
            }
        }
        let parent = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
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
        std::fs::copy(from, self.path(name))
            .with_context(|| format!("copying {}", from.display()))?;
        Ok(())
    }

    /// Moves the finished folder into place (replacing an old one under `--force`).
    pub fn commit(mut self) -> anyhow::Result<PathBuf> {
        let staging = self.staging.take().map(tempfile::TempDir::keep);
        let Some(staging) = staging else {
            return Ok(self.target.clone());
        };
        if self.target.exists() && self.force {
            std::fs::remove_dir_all(&self.target)
                .with_context(|| format!("removing the old {}", self.target.display()))?;
        }
        std::fs::rename(&staging, &self.target)
            .with_context(|| format!("moving output into {}", self.target.display()))?;
        Ok(self.target.clone())
    }
}
