//! Anura3D's file-name rules: how a file name splits into project and
//! extension, which extensions are Anura3D's (`GOM`, `GOM_stage<k>`,
//! `CPS_<nnn>`, `OPD_stage<k>`, `MAPF`), the CPS files of a project, doubled
//! extensions, and the names of the project a3d-init writes ([`OutputNames`]).
//! Deciding which files make up a project is the parent module's.

use std::path::{Path, PathBuf};

use super::ProjectFiles;

/// File names of the ready-to-run project, as Anura3D will look for them.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct OutputNames {
    /// The GOM: `<project>.GOM`, or `<project>.GOM_stage<k>` for a 2025 CPS.
    pub gom: String,
    /// The CPS: the input CPS's own name when it is `<project>.CPS_<nnn>`, else
    /// `<project>.CPS_001`.
    pub cps: String,
    /// `<project>.OPD_stage<k>` for a 2025 CPS.
    pub opd: Option<String>,
    /// True when the stage is above 0: a 2025 run also opens `<project>.GOM_stage0`.
    pub needs_gom_stage0: bool,
    /// Why these names.
    pub reason: String,
}

impl ProjectFiles {
    /// The names Anura3D will look for, decided by the CPS version (`gom_version`
    /// is used for a generated CPS, which takes the model's own header).
    pub fn output_names(&self, gom_version: &str) -> OutputNames {
        let version = self.cps_version.as_deref().unwrap_or(gom_version);
        let name = &self.name;
        let cps = self
            .cps
            .as_deref()
            .map(file_name)
            .filter(|f| {
                split_ext(f).is_some_and(|(stem, ext)| stem == name && cps_step(ext).is_some())
            })
            .unwrap_or_else(|| format!("{name}.CPS_001"));
        if version == "2025" {
            let k = self.stage.unwrap_or(0);
            OutputNames {
                gom: format!("{name}.GOM_stage{k}"),
                cps,
                opd: Some(format!("{name}.OPD_stage{k}")),
                needs_gom_stage0: k > 0,
                reason: format!(
                    "CPS header 2025: Anura3D reads {name}.GOM_stage{k} and {name}.OPD_stage{k}{}",
                    if k > 0 {
                        format!(", and {name}.GOM_stage0 for the dimension")
                    } else {
                        String::new()
                    }
                ),
            }
        } else {
            OutputNames {
                gom: format!("{name}.GOM"),
                cps,
                opd: None,
                needs_gom_stage0: false,
                reason: format!("CPS header {version} (before 2025): Anura3D reads {name}.GOM"),
            }
        }
    }
}

/// The last component of `path` (lossy UTF-8), empty when there is none.
pub(super) fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Splits `name.EXT` at the last dot.
pub(super) fn split_ext(name: &str) -> Option<(&str, &str)> {
    let dot = name.rfind('.')?;
    Some((&name[..dot], &name[dot + 1..]))
}

/// `CPS_001` → 1.
pub(super) fn cps_step(ext: &str) -> Option<u64> {
    ext.strip_prefix("CPS_")?.parse().ok()
}

/// True for an extension Anura3D gives its project files.
pub(super) fn is_anura3d_ext(ext: &str) -> bool {
    ext == "GOM"
        || ext == "MAPF"
        || ext
            .strip_prefix("GOM_stage")
            .or_else(|| ext.strip_prefix("OPD_stage"))
            .is_some_and(|k| k.parse::<u32>().is_ok())
        || cps_step(ext).is_some()
}

/// True for a GiD export's GOM, `<project>-2.dat`.
pub(super) fn is_gid_gom(path: &Path) -> bool {
    file_name(path).ends_with("-2.dat")
}

/// CPS files of project `name` in `dir`, sorted by step number.
pub(super) fn cps_files(dir: &Path, name: &str) -> Vec<(u64, PathBuf)> {
    let mut out = Vec::new();
    if let Ok(entries) = std::fs::read_dir(dir) {
        for entry in entries.flatten() {
            let file = file_name(&entry.path());
            if let Some((stem, ext)) = split_ext(&file)
                && stem == name
                && let Some(step) = cps_step(&ext.to_ascii_uppercase())
            {
                out.push((step, entry.path()));
            }
        }
    }
    out.sort();
    out
}

/// For a stem with a doubled extension (`X.GOM` of `X.GOM.GOM_stage0`), the
/// project Anura3D users mean: `X`, unless `X.GOM` is itself consistent (its own
/// CPS files exist beside it).
pub(super) fn undouble(dir: &Path, stem: &str) -> Option<String> {
    let (inner, ext) = split_ext(stem)?;
    if inner.is_empty() || !is_anura3d_ext(ext) || !cps_files(dir, stem).is_empty() {
        return None;
    }
    Some(inner.to_string())
}
