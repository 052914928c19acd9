//! Finding the files of an Anura3D project from whatever the user points at:
//! a `.GOM`, a `.GOM_stage<k>`, a GiD export (`-2.dat` GOM, `-1.dat` CPS), a
//! `.CPS_<nnn>`, or a project directory (also a GiD `name.gid/` folder), and the
//! file names Anura3D will look for in the project a3d-init writes.
//!
//! Anura3D's own rule decides the GOM for a CPS: a 2025 CPS reads
//! `<project>.GOM_stage<STAGE>` (and `<project>.OPD_stage<STAGE>`, and always
//! `<project>.GOM_stage0`), every older version `<project>.GOM`. Files named
//! otherwise (a GiD `-1.dat`/`-2.dat` pair, a doubled extension such as
//! `X.GOM.GOM_stage0`, a `.GOM` driven by a 2025 CPS) are read, reported in
//! [`ProjectFiles::warnings`], and written under the names Anura3D expects
//! ([`ProjectFiles::output_names`]). Spec: `formats/gom.md` (file names).
//!
//! The name rules themselves (extensions, CPS steps, doubled extensions, the
//! output names) are in `names`; this module decides which files make a project.

use std::path::{Path, PathBuf};

use super::cps::CpsDocument;
use super::error::FormatError;

mod names;

pub use names::OutputNames;
use names::{cps_files, cps_step, file_name, is_anura3d_ext, is_gid_gom, split_ext, undouble};

/// The files of one project, and how they were found.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ProjectFiles {
    /// Project name: the file stem Anura3D is run with.
    pub name: String,
    /// The folder the project's files are read from (`.` for a bare file name).
    pub dir: PathBuf,
    /// The GOM that is read (as found, possibly misnamed).
    pub gom: PathBuf,
    /// The CPS that drives the GOM, when there is one.
    pub cps: Option<PathBuf>,
    /// Version of the CPS header (`2025`, `2024`, …), when there is a CPS.
    pub cps_version: Option<String>,
    /// The OPD of the stage (2025 projects only).
    pub opd: Option<PathBuf>,
    /// Stage number for staged (2025) projects.
    pub stage: Option<u32>,
    /// Sentences saying which files were chosen and why.
    pub notes: Vec<String>,
    /// Problems with the files as named: Anura3D would not find them, or a CPS
    /// is missing. The project a3d-init writes uses the right names.
    pub warnings: Vec<String>,
}

/// The message `map` gives when a project has no CPS and none is to be generated.
pub fn missing_cps_message(files: &ProjectFiles) -> String {
    format!(
        "{}: no CPS for project {} (looked for {name}.CPS_<nnn>{gid} in {}): Anura3D cannot run without one. Put the model's CPS beside the GOM, or ask for the generated CPS (a complete default CPS for the model's version)",
        files.gom.display(),
        files.name,
        files.dir.display(),
        name = files.name,
        gid = if is_gid_gom(&files.gom) {
            format!(" and {}-1.dat", files.name)
        } else {
            String::new()
        },
    )
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
    let not_anura3d = || {
        FormatError::file(
            path,
            "not an Anura3D file: expected .GOM, .GOM_stage<k>, .CPS_<nnn>, or a GiD -2.dat (GOM) / -1.dat (CPS)",
        )
    };
    let Some((stem, ext)) = split_ext(&file) else {
        return Err(not_anura3d());
    };
    let mut notes = Vec::new();
    let mut warnings = Vec::new();
    // `x.gom`, `x.Cps_001`: Anura3D's names are case-sensitive on Linux.
    let upper = ext.to_ascii_uppercase();
    let ext = if !is_anura3d_ext(ext) && is_anura3d_ext(&upper) {
        warnings.push(format!(
            "{file}: Anura3D looks for {stem}.{upper} (file names are case-sensitive on Linux); the run would fail as named. a3d-init writes {stem}.{upper}"
        ));
        upper.as_str()
    } else {
        ext
    };
    if ext == "dat" && (stem.ends_with("-2") || stem.ends_with("-1")) {
        return discover_gid(path, &dir, &stem[..stem.len() - 2]);
    }
    if ext == "GOM" || ext.starts_with("GOM_stage") {
        let gom_stage =
            match ext.strip_prefix("GOM_stage") {
                Some(k) => Some(k.parse::<u32>().map_err(|_| {
                    FormatError::file(path, "expected GOM_stage<k> with a number k")
                })?),
                None => None,
            };
        let doubled = undouble(&dir, stem);
        let name = doubled.clone().unwrap_or_else(|| stem.to_string());
        let renamed = file != format!("{stem}.{ext}");
        let chosen = choose_cps(&dir, &name, gom_stage, &mut notes, &mut warnings)?;
        notes.insert(0, format!("GOM: {}", path.display()));
        let facts = CpsFacts::of(chosen.as_ref(), gom_stage);
        let stage = facts.stage;
        // The name Anura3D will open: decided by the CPS, else by the file's own extension.
        let expected = match (&chosen, stage) {
            (Some((_, doc)), _) if !doc.is_staged() => format!("{name}.GOM"),
            (_, Some(k)) => format!("{name}.GOM_stage{k}"),
            (_, None) => format!("{name}.GOM"),
        };
        if doubled.is_some() {
            warnings.push(format!(
                "{file} has a doubled extension: run as project {name}, Anura3D will look for {expected} (and run as project {stem} it finds no CPS); the run would fail with the files as named. a3d-init reads it as project {name} and writes {expected}"
            ));
        } else if let Some((p, doc)) = &chosen
            && file != expected
            && !renamed
        {
            warnings.push(format!(
                "found GOM {file}, but {} is version {}: Anura3D will look for {expected}; the run would fail with the files as named. a3d-init writes {expected}",
                file_name(p),
                doc.version()
            ));
        }
        return Ok(assemble(
            name,
            dir,
            path.to_path_buf(),
            facts,
            notes,
            warnings,
        ));
    }
    if cps_step(ext).is_some() {
        let cps = CpsDocument::read(path)?;
        let name = undouble(&dir, stem).unwrap_or_else(|| stem.to_string());
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
        if name != stem {
            warnings.push(format!(
                "{file} has a doubled extension: Anura3D, run as project {name}, will look for {name}.{ext}; a3d-init writes {name}.{ext}"
            ));
        }
        if !gom.exists() {
            return Err(FormatError::file(
                &gom,
                format!("the GOM that {file} needs does not exist"),
            ));
        }
        let version = cps.version().to_string();
        let opd = find_opd(&dir, &name, stage, Some(&version), &mut notes);
        check_later_stage(&dir, &name, stage, &mut warnings);
        return Ok(ProjectFiles {
            name,
            dir,
            gom,
            cps: Some(path.to_path_buf()),
            cps_version: Some(version),
            opd,
            stage,
            notes,
            warnings,
        });
    }
    Err(not_anura3d())
}

/// A GiD export: `name-2.dat` (GOM) and `name-1.dat` (CPS) in `name.gid/`.
fn discover_gid(path: &Path, dir: &Path, name: &str) -> Result<ProjectFiles, FormatError> {
    let gom = dir.join(format!("{name}-2.dat"));
    let gid_cps = dir.join(format!("{name}-1.dat"));
    if !gom.exists() {
        return Err(FormatError::file(
            &gom,
            format!(
                "the GiD GOM of project {name} does not exist (GiD writes the GOM to {name}-2.dat and the CPS to {name}-1.dat)"
            ),
        ));
    }
    let mut notes = vec![
        format!("GOM: {}", gom.display()),
        format!("GiD export: GiD writes the GOM to {name}-2.dat and the CPS to {name}-1.dat"),
    ];
    let mut warnings = Vec::new();
    // Older problem types write other things to `-1.dat`: only a file with an
    // Anura3D header is taken as the CPS.
    let is_cps = crate::input::read_bytes(&gid_cps).is_ok_and(|b| {
        b.strip_prefix(b"\xEF\xBB\xBF".as_slice())
            .unwrap_or(&b)
            .starts_with(b"### Anura3D_")
    });
    if gid_cps.exists() && !is_cps && path != gid_cps {
        notes.push(format!(
            "{name}-1.dat has no Anura3D header: not a CPS, looking for {name}.CPS_<nnn>"
        ));
    }
    let chosen = if gid_cps.exists() && (is_cps || path == gid_cps) {
        let doc = CpsDocument::read(&gid_cps)?;
        notes.push(format!("CPS: {}", gid_cps.display()));
        Some((gid_cps, doc))
    } else {
        if path == gid_cps {
            return Err(FormatError::io(
                path,
                std::io::Error::from(std::io::ErrorKind::NotFound),
            ));
        }
        choose_cps(dir, name, None, &mut notes, &mut warnings)?
    };
    let facts = CpsFacts::of(chosen.as_ref(), None);
    Ok(assemble(
        name.to_string(),
        dir.to_path_buf(),
        gom,
        facts,
        notes,
        warnings,
    ))
}

/// What the chosen CPS says about the project: its path, header version and
/// stage (without a CPS, the stage the GOM's name gives, if any).
struct CpsFacts {
    path: Option<PathBuf>,
    version: Option<String>,
    stage: Option<u32>,
}

impl CpsFacts {
    fn of(chosen: Option<&(PathBuf, CpsDocument)>, stage_without_cps: Option<u32>) -> CpsFacts {
        match chosen {
            Some((p, doc)) => CpsFacts {
                path: Some(p.clone()),
                version: Some(doc.version().to_string()),
                stage: doc.is_staged().then(|| doc.stage()),
            },
            None => CpsFacts {
                path: None,
                version: None,
                stage: stage_without_cps,
            },
        }
    }
}

/// The project's files once the GOM and CPS are known: finds the OPD and
/// checks for a later stage's missing `GOM_stage0`.
fn assemble(
    name: String,
    dir: PathBuf,
    gom: PathBuf,
    cps: CpsFacts,
    mut notes: Vec<String>,
    mut warnings: Vec<String>,
) -> ProjectFiles {
    let opd = find_opd(&dir, &name, cps.stage, cps.version.as_deref(), &mut notes);
    check_later_stage(&dir, &name, cps.stage, &mut warnings);
    ProjectFiles {
        name,
        dir,
        gom,
        cps: cps.path,
        cps_version: cps.version,
        opd,
        stage: cps.stage,
        notes,
        warnings,
    }
}

/// The OPD of a 2025 stage: beside the GOM, or (GiD) in the sibling `name.A3D/`.
fn find_opd(
    dir: &Path,
    name: &str,
    stage: Option<u32>,
    cps_version: Option<&str>,
    notes: &mut Vec<String>,
) -> Option<PathBuf> {
    if cps_version != Some("2025") {
        return None;
    }
    let file = format!("{name}.OPD_stage{}", stage.unwrap_or(0));
    let mut places = vec![dir.join(&file)];
    if let Some(parent) = dir.parent() {
        places.push(parent.join(format!("{name}.A3D")).join(&file));
    }
    let found = places.into_iter().find(|p| p.exists());
    match &found {
        Some(p) => notes.push(format!("OPD: {}", p.display())),
        None => notes.push(format!(
            "no {file} beside the GOM (nor in {name}.A3D/): a 2025 CPS needs one; a3d-init writes a default (every output on)"
        )),
    }
    found
}

/// A 2025 run of stage k > 0 also opens `<name>.GOM_stage0` (for the dimension),
/// and continues from the restart files of the earlier stages.
fn check_later_stage(dir: &Path, name: &str, stage: Option<u32>, warnings: &mut Vec<String>) {
    if let Some(k) = stage.filter(|&k| k > 0) {
        let stage0 = format!("{name}.GOM_stage0");
        warnings.push(format!(
            "stage {k}: Anura3D also opens {stage0}{} and starts from the restart files of the earlier stages; a MAPF is read only at the first load step",
            if dir.join(&stage0).exists() {
                ""
            } else {
                ", which is not here"
            }
        ));
    }
}

/// For a GOM, the CPS that drives it: the lowest-numbered CPS whose stage
/// matches the GOM's name; failing that, the lowest-numbered CPS of the project
/// (its version then decides the names, and a warning says so).
fn choose_cps(
    dir: &Path,
    name: &str,
    stage: Option<u32>,
    notes: &mut Vec<String>,
    warnings: &mut Vec<String>,
) -> Result<Option<(PathBuf, CpsDocument)>, FormatError> {
    let candidates = cps_files(dir, name);
    let mut first = None;
    for (_, path) in &candidates {
        let cps = CpsDocument::read(path)?;
        let matches = match stage {
            Some(k) => cps.is_staged() && cps.stage() == k,
            None => !cps.is_staged(),
        };
        if matches {
            notes.push(format!("CPS: {}", path.display()));
            return Ok(Some((path.clone(), cps)));
        }
        if first.is_none() && (stage.is_none() || stage == Some(0)) {
            first = Some((path.clone(), cps));
        }
    }
    if let Some((path, cps)) = first {
        notes.push(format!("CPS: {}", path.display()));
        return Ok(Some((path, cps)));
    }
    warnings.push(match candidates.is_empty() {
        true => format!("no CPS: no {name}.CPS_<nnn> beside the GOM"),
        false => format!(
            "no CPS of project {name} matches this GOM's stage ({})",
            candidates
                .iter()
                .map(|(_, p)| file_name(p))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    });
    Ok(None)
}

/// A GOM-like file in a folder: (project name, path, rank) — lower rank wins
/// when two files belong to the same project: 0 Anura3D's own names, 1 a GiD
/// `-2.dat`, 2 a misnamed file.
fn gom_candidate(dir: &Path, path: &Path) -> Option<(String, PathBuf, u8)> {
    let file = file_name(path);
    let (stem, ext) = split_ext(&file)?;
    let rank = match ext.to_ascii_uppercase().as_str() {
        "GOM" | "GOM_STAGE0" => 0,
        "DAT" if stem.ends_with("-2") => 1,
        _ => return None,
    };
    if rank == 1 {
        return Some((stem[..stem.len() - 2].to_string(), path.to_path_buf(), 1));
    }
    // Misnamed files (doubled or lower-case extensions) come after correct names.
    let misnamed = !matches!(ext, "GOM" | "GOM_stage0");
    match undouble(dir, stem) {
        Some(inner) => Some((inner, path.to_path_buf(), 2)),
        None => Some((stem.to_string(), path.to_path_buf(), 2 * misnamed as u8)),
    }
}

fn discover_dir(dir: &Path) -> Result<ProjectFiles, FormatError> {
    let mut goms: Vec<(String, PathBuf, u8)> = Vec::new();
    let entries = std::fs::read_dir(dir).map_err(|e| FormatError::io(dir, e))?;
    for entry in entries.flatten() {
        if let Some(c) = gom_candidate(dir, &entry.path()) {
            goms.push(c);
        }
    }
    goms.sort_by(|a, b| (&a.0, a.2, &a.1).cmp(&(&b.0, b.2, &b.1)));
    let mut names: Vec<&str> = goms.iter().map(|g| g.0.as_str()).collect();
    names.dedup();
    match names.len() {
        0 => Err(FormatError::file(
            dir,
            "no Anura3D project here: no .GOM, .GOM_stage0 or GiD -2.dat file",
        )),
        1 => {
            let mut found = discover(&goms[0].1)?;
            found.notes.insert(
                0,
                format!("directory {}: one project, {}", dir.display(), found.name),
            );
            for other in &goms[1..] {
                found.notes.push(format!(
                    "also here and not used: {} (same project; {} was preferred)",
                    file_name(&other.1),
                    file_name(&goms[0].1)
                ));
            }
            Ok(found)
        }
        _ => Err(FormatError::file(
            dir,
            format!(
                "several projects here ({}): name the GOM or CPS file",
                goms.iter()
                    .map(|g| file_name(&g.1))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    const GOM: &str = "### Anura3D_2024 ###\n$$FINISH\n";

    /// A GiD export folder `<name>.gid` in `dir`: the GOM as `<name>-2.dat`,
    /// `minus_one` as `<name>-1.dat`.
    fn gid_folder(dir: &Path, name: &str, minus_one: &str) -> PathBuf {
        let gid = dir.join(format!("{name}.gid"));
        std::fs::create_dir(&gid).unwrap();
        write(&gid, &format!("{name}-2.dat"), GOM);
        write(&gid, &format!("{name}-1.dat"), minus_one);
        gid
    }
    const CPS_2024: &str = "### Anura3D_2024 ###\n$$K0_PROCEDURE\n1\n$$END\n";
    const CPS_2025: &str = "### Anura3D_2025 ###\n$$STAGE\n0\n$$END\n";

    #[test]
    fn gid_folder_reads_minus_one_dat_as_the_cps() {
        let tmp = tempfile::tempdir().unwrap();
        let gid = gid_folder(tmp.path(), "Dam", CPS_2024);
        let p = discover(&gid).unwrap();
        assert_eq!(p.name, "Dam");
        assert_eq!(p.cps.as_deref(), Some(gid.join("Dam-1.dat").as_path()));
        let names = p.output_names("2024");
        assert_eq!(
            (names.gom.as_str(), names.cps.as_str(), names.opd),
            ("Dam.GOM", "Dam.CPS_001", None)
        );
        // The CPS file itself leads to the same project.
        assert_eq!(discover(&gid.join("Dam-1.dat")).unwrap().gom, p.gom);
    }

    #[test]
    fn gid_2025_names_are_staged_and_the_opd_is_found_in_the_a3d_folder() {
        let tmp = tempfile::tempdir().unwrap();
        let gid = gid_folder(tmp.path(), "Dam", CPS_2025);
        let a3d = tmp.path().join("Dam.A3D");
        std::fs::create_dir(&a3d).unwrap();
        write(&a3d, "Dam.OPD_stage0", "$$END\n");
        let p = discover(&gid.join("Dam-2.dat")).unwrap();
        assert_eq!(p.opd.as_deref(), Some(a3d.join("Dam.OPD_stage0").as_path()));
        let names = p.output_names("2024");
        assert_eq!(names.gom, "Dam.GOM_stage0");
        assert_eq!(names.opd.as_deref(), Some("Dam.OPD_stage0"));
        assert_eq!(names.cps, "Dam.CPS_001");
    }

    #[test]
    fn older_gid_folder_keeps_its_cps_beside_the_dat_files() {
        // As in upstream tutorial folders: -2.dat (GOM), -3.dat and .dat (batch
        // files), and the CPS under its Anura3D name.
        let tmp = tempfile::tempdir().unwrap();
        let gid = gid_folder(tmp.path(), "Oedo", "\"Anura3D_2023.exe\"\nPAUSE\n");
        write(&gid, "Oedo-3.dat", "\"Anura3D_2023.exe\" \"Oedo\"\nPAUSE\n");
        write(&gid, "Oedo.dat", "PAUSE\n");
        let cps = write(&gid, "Oedo.CPS_001", CPS_2024);
        let p = discover(&gid).unwrap();
        assert_eq!(p.name, "Oedo");
        assert_eq!(p.cps, Some(cps));
        assert!(p.notes.iter().any(|n| n.contains("no Anura3D header")));
    }

    #[test]
    fn a_later_stage_names_stage0_and_the_restart() {
        let tmp = tempfile::tempdir().unwrap();
        let gom = write(tmp.path(), "C.GOM_stage1", GOM);
        write(
            tmp.path(),
            "C.CPS_002",
            "### Anura3D_2025 ###\n$$STAGE\n1\n$$END\n",
        );
        let p = discover(&gom).unwrap();
        assert_eq!(p.stage, Some(1));
        assert!(p.warnings[0].contains("C.GOM_stage0, which is not here"));
        let names = p.output_names("2025");
        assert_eq!(names.gom, "C.GOM_stage1");
        assert_eq!(names.cps, "C.CPS_002");
        assert!(names.needs_gom_stage0);
    }

    /// A GOM named otherwise than Anura3D looks for it: the project is found
    /// (from the file and from the folder), the name is reported, and the
    /// output uses the right one.
    #[test]
    fn misnamed_goms_are_read_and_reported() {
        struct Case {
            what: &'static str,
            gom: &'static str,
            cps: &'static str,
            cps_text: &'static str,
            warning: &'static str,
            version: &'static str,
            output_gom: &'static str,
        }
        let cases = [
            Case {
                what: "doubled extension picks the obvious project",
                gom: "X.GOM.GOM_stage0",
                cps: "X.CPS_001",
                cps_text: CPS_2025,
                warning: "will look for X.GOM_stage0",
                version: "2025",
                output_gom: "X.GOM_stage0",
            },
            Case {
                what: "lower-case extensions",
                gom: "L.gom",
                cps: "L.cps_001",
                cps_text: CPS_2024,
                warning: "Anura3D looks for L.GOM",
                version: "2024",
                output_gom: "L.GOM",
            },
            Case {
                what: "doubled extension with an older CPS names the GOM",
                gom: "W.GOM.GOM_stage0",
                cps: "W.CPS_001",
                cps_text: CPS_2024,
                warning: "will look for W.GOM ",
                version: "2024",
                output_gom: "W.GOM",
            },
            Case {
                what: "a GOM named for the wrong version",
                gom: "Y.GOM",
                cps: "Y.CPS_001",
                cps_text: CPS_2025,
                warning: "will look for Y.GOM_stage0",
                version: "2024",
                output_gom: "Y.GOM_stage0",
            },
        ];
        for c in cases {
            let tmp = tempfile::tempdir().unwrap();
            let gom = write(tmp.path(), c.gom, GOM);
            write(tmp.path(), c.cps, c.cps_text);
            let name = &c.gom[..1];
            let p = discover(&gom).unwrap();
            assert_eq!(p.name, name, "{}", c.what);
            assert!(p.cps.is_some(), "{}", c.what);
            if c.cps_text == CPS_2025 {
                assert_eq!(p.stage, Some(0), "{}", c.what);
            }
            assert!(
                p.warnings[0].contains(c.warning),
                "{}: {:?}",
                c.what,
                p.warnings
            );
            let names = p.output_names(c.version);
            assert_eq!(
                (names.gom.as_str(), names.cps.as_str()),
                (c.output_gom, format!("{name}.CPS_001").as_str()),
                "{}",
                c.what
            );
            assert_eq!(discover(tmp.path()).unwrap().name, name, "{}", c.what);
        }
    }

    #[test]
    fn a_folder_prefers_the_correctly_named_gom() {
        let tmp = tempfile::tempdir().unwrap();
        write(tmp.path(), "V.GOM.GOM_stage0", GOM);
        let good = write(tmp.path(), "V.GOM_stage0", GOM);
        write(tmp.path(), "V.CPS_001", CPS_2025);
        let p = discover(tmp.path()).unwrap();
        assert_eq!(p.gom, good);
        assert!(p.warnings.is_empty(), "{:?}", p.warnings);
    }

    #[test]
    fn no_cps_is_a_warning_and_the_map_message_names_the_files() {
        let tmp = tempfile::tempdir().unwrap();
        let gom = write(tmp.path(), "Z.GOM", GOM);
        let p = discover(&gom).unwrap();
        assert!(p.cps.is_none());
        assert!(p.warnings[0].starts_with("no CPS"));
        assert!(missing_cps_message(&p).contains("the generated CPS"));
        let names = p.output_names("2024");
        assert_eq!(
            (names.gom.as_str(), names.cps.as_str()),
            ("Z.GOM", "Z.CPS_001")
        );
    }
}
