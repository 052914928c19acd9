//! Finding the files of an Anura3D project from whatever the user points at:
//! a `.GOM`, a `.GOM_stage<k>`, a GiD `-2.dat` export, a `.CPS_<nnn>`, or a
//! project directory. Anura3D's own rule decides the GOM for a CPS: a 2025 CPS
//! reads `<project>.GOM_stage<STAGE>`, every older version `<project>.GOM`.

use std::path::{Path, PathBuf};

use super::cps::CpsDocument;
use super::error::FormatError;

/// The files of one project, and how they were found.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ProjectFiles {
    /// Project name: the file stem Anura3D is run with.
    pub name: String,
    pub dir: PathBuf,
    pub gom: PathBuf,
    pub cps: Option<PathBuf>,
    /// The OPD of the stage (2025 projects only).
    pub opd: Option<PathBuf>,
    /// Stage number for staged (2025) projects.
    pub stage: Option<u32>,
    /// Sentences saying which files were chosen and why.
    pub notes: Vec<String>,
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Splits `name.EXT` at the last dot.
fn split_ext(name: &str) -> Option<(&str, &str)> {
    let dot = name.rfind('.')?;
    Some((&name[..dot], &name[dot + 1..]))
}

/// CPS files of project `name` in `dir`, sorted by step number.
fn cps_files(dir: &Path, name: &str) -> Vec<(u64, PathBuf)> {
    let mut out = Vec::new();
    if let Ok(entries) = std::fs::read_dir(dir) {
        for entry in entries.flatten() {
            let file = file_name(&entry.path());
            if let Some((stem, ext)) = split_ext(&file)
                && stem == name
                && let Some(step) = ext.strip_prefix("CPS_").and_then(|s| s.parse::<u64>().ok())
            {
                out.push((step, entry.path()));
            }
        }
    }
    out.sort();
    out
}

/// Resolves `path` to a project.
pub fn discover(path: &Path) -> Result<ProjectFiles, FormatError> {
    let meta = std::fs::metadata(path).map_err(|e| FormatError::io(path, e))?;
    if meta.is_dir() {
        return discover_dir(path);
    }
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let dir = if dir.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        dir
    };
    let file = file_name(path);
    let Some((stem, ext)) = split_ext(&file) else {
        return Err(FormatError::file(
            path,
            "not an Anura3D file: expected .GOM, .GOM_stage<k>, -2.dat or .CPS_<nnn>",
        ));
    };
    let mut notes = Vec::new();
    if ext == "GOM" || ext.starts_with("GOM_stage") || (ext == "dat" && stem.ends_with("-2")) {
        let (name, stage) = if ext == "dat" {
            notes.push(format!(
                "{file} is a GiD export of the GOM (GiD writes the GOM to -2.dat)"
            ));
            (stem.trim_end_matches("-2").to_string(), None)
        } else if let Some(k) = ext.strip_prefix("GOM_stage") {
            let k = k
                .parse::<u32>()
                .map_err(|_| FormatError::file(path, "expected GOM_stage<k> with a number k"))?;
            (stem.to_string(), Some(k))
        } else {
            (stem.to_string(), None)
        };
        let cps = choose_cps(&dir, &name, stage, &mut notes)?;
        let opd = stage
            .map(|k| dir.join(format!("{name}.OPD_stage{k}")))
            .filter(|p| p.exists());
        notes.insert(0, format!("GOM: {}", path.display()));
        return Ok(ProjectFiles {
            name,
            dir,
            gom: path.to_path_buf(),
            cps,
            opd,
            stage,
            notes,
        });
    }
    if ext.starts_with("CPS_") {
        let cps = CpsDocument::read(path)?;
        let name = stem.to_string();
        let (gom, stage) = if cps.is_staged() {
            let k = cps.stage();
            (dir.join(format!("{name}.GOM_stage{k}")), Some(k))
        } else {
            (dir.join(format!("{name}.GOM")), None)
        };
        notes.push(format!(
            "{file} is version {}: Anura3D reads {}",
            cps.version(),
            file_name(&gom)
        ));
        if !gom.exists() {
            return Err(FormatError::file(
                &gom,
                format!("the GOM that {file} needs does not exist"),
            ));
        }
        let opd = stage
            .map(|k| dir.join(format!("{name}.OPD_stage{k}")))
            .filter(|p| p.exists());
        return Ok(ProjectFiles {
            name,
            dir,
            gom,
            cps: Some(path.to_path_buf()),
            opd,
            stage,
            notes,
        });
    }
    Err(FormatError::file(
        path,
        "not an Anura3D file: expected .GOM, .GOM_stage<k>, -2.dat or .CPS_<nnn>",
    ))
}

/// For a GOM, the CPS that drives it: the lowest-numbered CPS whose stage matches.
fn choose_cps(
    dir: &Path,
    name: &str,
    stage: Option<u32>,
    notes: &mut Vec<String>,
) -> Result<Option<PathBuf>, FormatError> {
    let candidates = cps_files(dir, name);
    for (_, path) in &candidates {
        let cps = CpsDocument::read(path)?;
        let matches = match stage {
            Some(k) => cps.is_staged() && cps.stage() == k,
            None => !cps.is_staged(),
        };
        if matches {
            notes.push(format!("CPS: {}", path.display()));
            return Ok(Some(path.clone()));
        }
    }
    notes.push(match candidates.is_empty() {
        true => format!(
            "no {name}.CPS_<nnn> next to the GOM: defaults are used where a CPS value is needed"
        ),
        false => "no CPS matches this GOM's stage: defaults are used where a CPS value is needed"
            .to_string(),
    });
    Ok(None)
}

fn discover_dir(dir: &Path) -> Result<ProjectFiles, FormatError> {
    let mut goms: Vec<PathBuf> = Vec::new();
    let entries = std::fs::read_dir(dir).map_err(|e| FormatError::io(dir, e))?;
    for entry in entries.flatten() {
        let file = file_name(&entry.path());
        if let Some((stem, ext)) = split_ext(&file)
            && (ext == "GOM" || ext == "GOM_stage0" || (ext == "dat" && stem.ends_with("-2")))
        {
            goms.push(entry.path());
        }
    }
    goms.sort();
    match goms.len() {
        0 => Err(FormatError::file(
            dir,
            "no Anura3D project here: no .GOM, .GOM_stage0 or -2.dat file",
        )),
        1 => {
            let mut found = discover(&goms[0])?;
            found.notes.insert(
                0,
                format!("directory {}: one project, {}", dir.display(), found.name),
            );
            Ok(found)
        }
        _ => Err(FormatError::file(
            dir,
            format!(
                "several projects here ({}): name the GOM or CPS file",
                goms.iter()
                    .map(|p| file_name(p))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )),
    }
}
