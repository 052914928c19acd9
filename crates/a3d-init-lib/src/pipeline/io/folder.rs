//! A folder the writers of a use case fill: each file written through a
//! buffered, page-cache-bypassing writer (`direct`), or copied byte
//! for byte. The folder is the staging folder of an [`super::output`] commit.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::pipeline::PipelineError;

/// A folder files are written into.
pub struct Folder<'a>(pub &'a Path);

impl Folder<'_> {
    /// The path of `name` in the folder.
    pub fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    /// Writes `name` through `fill` (buffered, page-cache-bypassing for
    /// large tables).
    pub fn write(
        &self,
        name: &str,
        fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> Result<(), PipelineError> {
        let path = self.path(name);
        let io =
            |e: std::io::Error| PipelineError::Output(format!("writing {}: {e}", path.display()));
        // Large tables bypass the page cache (see `direct`); whole pages only.
        let file = crate::pipeline::io::direct::DirectFile::create(&path).map_err(io)?;
        let mut w = BufWriter::with_capacity(1 << 16, file);
        fill(&mut w).map_err(io)?;
        w.into_inner()
            .map_err(|e| io(e.into_error()))?
            .finish()
            .map_err(io)?;
        Ok(())
    }

    /// Copies `from` byte for byte to `name` (whose folders are created).
    pub fn copy(&self, from: &Path, name: &str) -> Result<(), PipelineError> {
        let to = self.path(name);
        if let Some(parent) = to.parent() {
            std::fs::create_dir_all(parent).map_err(|e| {
                PipelineError::Output(format!("creating {}: {e}", parent.display()))
            })?;
        }
        std::fs::copy(from, to)
            .map_err(|e| PipelineError::Output(format!("copying {}: {e}", from.display())))?;
        Ok(())
    }
}
