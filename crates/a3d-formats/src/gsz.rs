//! GeoStudio project archives (`.gsz`) read directly. Spec: `formats/gsz.md`.
//!
//! A `.gsz` is a zip holding the project XML, one folder per analysis (a `/` in
//! the analysis name is written `&3`), one subfolder per saved time step (`000`
//! = initial conditions, then the step numbers) with `node.csv`, and the mesh as
//! binary PLY (`Mesh.ply` in the analysis folder). `node.csv` row `Node = k` is PLY
//! node k − 1. Values are in the project's base units: metric (m, kPa) or
//! imperial (ft, psf), read from the XML's `UnitSystem`.

use std::path::Path;

use super::error::{FormatError, ParseError};
use super::fem::{FemReadReport, UnitOverride};
use super::fem_csv::{self, CsvOptions};
use super::input;
use super::ply;
use crate::fem::{FAILURE_NEEDS_MODEL, StepChoice};
use a3d_model::FemNodes;

/// One saved step of an analysis.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SavedStep {
    /// The folder number (`010` → 10).
    pub number: u32,
    pub folder: String,
    /// Elapsed time in s when known (time.csv or the XML).
    pub time: Option<f64>,
}

/// One analysis of the project.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Analysis {
    /// 1-based position in the XML.
    pub index: usize,
    pub name: String,
    pub kind: String,
    pub method: String,
    /// Folder in the archive (`/` written as `&3`).
    pub folder: String,
    pub steps: Vec<SavedStep>,
    pub has_mesh: bool,
}

/// What a `.gsz` holds.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct GszProject {
    pub xml_name: String,
    /// `Metric` or `Imperial`.
    pub unit_system: String,
    pub analyses: Vec<Analysis>,
}

/// An open archive and the most bytes one of its entries may expand to.
struct Archive {
    zip: zip::ZipArchive<std::fs::File>,
    entry_limit: u64,
}

fn archive(path: &Path) -> Result<Archive, FormatError> {
    let (file, len) = input::open_regular(path)?;
    if len > input::MAX_INPUT_BYTES {
        return Err(FormatError::file(
            path,
            format!(
                "{len} bytes, larger than the {}-byte limit on an input file",
                input::MAX_INPUT_BYTES
            ),
        ));
    }
    let zip = zip::ZipArchive::new(file)
        .map_err(|e| FormatError::file(path, format!("not a readable .gsz (zip) archive: {e}")))?;
    Ok(Archive {
        zip,
        entry_limit: input::entry_limit(len),
    })
}

/// Reads one entry, refusing one that expands past the archive's entry limit
/// (zip bombs) whatever size its header declares.
fn read_entry(archive: &mut Archive, path: &Path, name: &str) -> Result<Vec<u8>, FormatError> {
    let limit = archive.entry_limit;
    let entry = archive
        .zip
        .by_name(name)
        .map_err(|_| FormatError::file(path, format!("the archive has no `{name}`")))?;
    let declared = entry.size();
    match input::read_entry_limited(entry, declared, limit) {
        Ok(Ok(bytes)) => Ok(bytes),
        Ok(Err(size)) => Err(FormatError::file(
            path,
            format!(
                "`{name}` expands to {size} bytes or more, past the {limit}-byte limit for an entry of this archive (a zip bomb?)"
            ),
        )),
        Err(e) => Err(FormatError::file(
            path,
            format!("`{name}` cannot be read (truncated or corrupt archive?): {e}"),
        )),
    }
}

/// What the project XML says about one analysis.
struct XmlAnalysis {
    name: String,
    kind: String,
    method: String,
    /// `ElapsedTime` of its `<TimeStep>`s, in order.
    times: Vec<f64>,
}

/// Parses the project XML (roxmltree): the unit system and every
/// `<Analyses>/<Analysis>`. A malformed XML is an error at its line and column,
/// named `<archive>/<entry>`.
fn parse_project_xml(
    path: &Path,
    xml_name: &str,
    xml: &str,
) -> Result<(String, Vec<XmlAnalysis>), FormatError> {
    let doc = roxmltree::Document::parse(xml).map_err(|e| {
        let pos = e.pos();
        ParseError::at(
            &path.join(xml_name),
            pos.row as usize,
            pos.col as usize,
            format!("the project XML is malformed: {e}"),
        )
    })?;
    let unit_system = doc
        .descendants()
        .find_map(|n| n.attribute("UnitSystem"))
        .unwrap_or("Metric")
        .to_string();
    let analyses = doc
        .descendants()
        .find(|n| n.has_tag_name("Analyses"))
        .map(|list| {
            list.children()
                .filter(|c| c.has_tag_name("Analysis"))
                .map(|a| {
                    // A direct child first; GeoStudio writes Name, Kind and Method there.
                    let text = |tag: &str| {
                        a.children()
                            .find(|c| c.has_tag_name(tag))
                            .or_else(|| a.descendants().find(|c| c.has_tag_name(tag)))
                            .and_then(|c| c.text())
                            .unwrap_or("")
                            .trim()
                            .to_string()
                    };
                    XmlAnalysis {
                        name: text("Name"),
                        kind: text("Kind"),
                        method: text("Method"),
                        times: a
                            .descendants()
                            .filter(|n| n.has_tag_name("TimeStep"))
                            .filter_map(|n| n.attribute("ElapsedTime")?.trim().parse().ok())
                            .collect(),
                    }
                })
                .collect()
        })
        .unwrap_or_default();
    Ok((unit_system, analyses))
}

/// Reads the project's table of contents.
pub fn read_project(path: &Path) -> Result<GszProject, FormatError> {
    let mut zip = archive(path)?;
    let names: Vec<String> = zip
        .zip
        .file_names()
        .map(|n| n.map(|n| n.into_owned()))
        .collect::<Result<_, _>>()
        .map_err(|e| FormatError::file(path, format!("corrupt archive directory: {e}")))?;
    let xml_name = names
        .iter()
        .find(|n| !n.contains('/') && n.to_ascii_lowercase().ends_with(".xml"))
        .cloned()
        .ok_or_else(|| FormatError::file(path, "no project XML at the top of the archive"))?;
    let xml_bytes = read_entry(&mut zip, path, &xml_name)?;
    let xml = String::from_utf8_lossy(&xml_bytes).into_owned();
    let (unit_system, xml_analyses) = parse_project_xml(path, &xml_name, &xml)?;
    let mut analyses = Vec::new();
    for (k, block) in xml_analyses.into_iter().enumerate() {
        let name = block.name;
        let folder = name.replace('/', "&3");
        let mut steps: Vec<SavedStep> = names
            .iter()
            .filter_map(|n| {
                let rest = n.strip_prefix(&format!("{folder}/"))?;
                let (step, file) = rest.split_once('/')?;
                (file == "node.csv").then(|| {
                    step.parse::<u32>().ok().map(|num| SavedStep {
                        number: num,
                        folder: step.to_string(),
                        time: None,
                    })
                })?
            })
            .collect();
        steps.sort_by_key(|s| s.number);
        // Times: time.csv (Step → Time) when present, else the XML's time steps.
        let xml_times = block.times;
        let csv_times: Vec<(u32, f64)> =
            match read_entry(&mut zip, path, &format!("{folder}/time.csv")) {
                Ok(bytes) => String::from_utf8_lossy(&bytes)
                    .lines()
                    .skip(1)
                    .filter_map(|l| {
                        let f: Vec<&str> = l.split(',').collect();
                        Some((
                            f.get(1)?.trim().parse().ok()?,
                            f.get(3)?.trim().parse().ok()?,
                        ))
                    })
                    .collect(),
                Err(_) => Vec::new(),
            };
        for s in &mut steps {
            s.time = csv_times
                .iter()
                .find(|(n, _)| *n == s.number)
                .map(|(_, t)| *t)
                .or_else(|| {
                    if s.number == 0 {
                        Some(0.0)
                    } else {
                        xml_times.get(s.number as usize - 1).copied()
                    }
                });
        }
        analyses.push(Analysis {
            index: k + 1,
            name,
            kind: block.kind,
            method: block.method,
            has_mesh: names.iter().any(|n| *n == format!("{folder}/Mesh.ply")),
            folder,
            steps,
        });
    }
    if analyses.is_empty() {
        return Err(FormatError::file(
            path,
            format!("{xml_name} lists no analyses"),
        ));
    }
    Ok(GszProject {
        xml_name,
        unit_system,
        analyses,
    })
}

/// Reads the nodes of one analysis step, with coordinates from the analysis mesh
/// and units from the project. Returns what was converted in the report.
pub fn read_step(
    path: &Path,
    analysis: Option<&str>,
    step: &StepChoice,
    options: &CsvOptions,
) -> Result<(FemNodes, FemReadReport, String), FormatError> {
    if let StepChoice::Time(t) = step
        && !t.is_finite()
    {
        return Err(FormatError::file(
            path,
            format!("step time {t}: the time must be a finite number of seconds"),
        ));
    }
    if *step == StepChoice::Failure {
        return Err(FormatError::file(path, FAILURE_NEEDS_MODEL));
    }
    let project = read_project(path)?;
    // `1 `name`, 2 `name``: the analyses to choose from, for the errors.
    let analysis_list = || {
        project
            .analyses
            .iter()
            .map(|a| format!("{} `{}`", a.index, a.name))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let chosen = match analysis {
        None if project.analyses.len() == 1 => &project.analyses[0],
        None => {
            return Err(FormatError::file(
                path,
                format!(
                    "{} analyses; make the analysis choice by name or index: {}",
                    project.analyses.len(),
                    analysis_list()
                ),
            ));
        }
        Some(key) => project
            .analyses
            .iter()
            .find(|a| a.name == key || key.parse::<usize>().ok() == Some(a.index))
            .ok_or_else(|| {
                FormatError::file(
                    path,
                    format!("no analysis `{key}` (analyses: {})", analysis_list()),
                )
            })?,
    };
    if chosen.steps.is_empty() {
        return Err(FormatError::file(
            path,
            format!(
                "analysis `{}` has no saved results (no node.csv)",
                chosen.name
            ),
        ));
    }
    let saved = match step {
        StepChoice::Last => chosen.steps.last(),
        StepChoice::Number(n) => chosen.steps.iter().find(|s| s.number == *n),
        StepChoice::Time(t) => chosen
            .steps
            .iter()
            .filter(|s| s.time.is_some())
            .min_by(|a, b| {
                (a.time.unwrap_or(0.0) - t)
                    .abs()
                    .total_cmp(&(b.time.unwrap_or(0.0) - t).abs())
            }),
        StepChoice::Failure => None,
    }
    .ok_or_else(|| {
        FormatError::file(
            path,
            format!(
                "analysis `{}` has no saved step {step:?} (saved: {})",
                chosen.name,
                chosen
                    .steps
                    .iter()
                    .map(|s| s.folder.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )
    })?;
    if let StepChoice::Time(t) = step {
        let got = saved.time.unwrap_or(0.0);
        if (got - t).abs() > 1e-6 * t.abs().max(1.0) {
            return Err(FormatError::file(
                path,
                format!(
                    "no saved step at time {t} s; the nearest is step {} at {got} s",
                    saved.folder
                ),
            ));
        }
    }
    let mut zip = archive(path)?;
    let csv_name = format!("{}/{}/node.csv", chosen.folder, saved.folder);
    let csv = read_entry(&mut zip, path, &csv_name)?;
    let mesh_name = format!("{}/Mesh.ply", chosen.folder);
    let ply_bytes = read_entry(&mut zip, path, &mesh_name)?;
    let label = path.join(&mesh_name);
    let mesh = ply::parse_ply_nodes(&label, &ply_bytes)?;
    let (length, pressure) = if project.unit_system.eq_ignore_ascii_case("Imperial") {
        ("ft", "psf")
    } else {
        ("m", "kPa")
    };
    let options = CsvOptions {
        units: UnitOverride {
            length: Some(length.into()),
            pressure: Some(pressure.into()),
        },
        ..options.clone()
    };
    let csv_label = path.join(&csv_name);
    let (mut nodes, mut report) = fem_csv::parse_csv(&csv_label, &csv, &options)?;
    let rows = data_row_lines(&csv, report.header_line);
    let subset = join_mesh(&mut nodes, &csv_label, &rows, &mesh, &mesh_name)?;
    if length == "ft" {
        for p in &mut nodes.positions {
            for v in p.iter_mut() {
                *v *= 0.3048;
            }
        }
    }
    report.dim = nodes.dim;
    report.has_coordinates = true;
    report
        .warnings
        .retain(|w| !w.starts_with("no coordinate columns"));
    let note = format!(
        "{}: analysis {} `{}` ({} {}), step {}{}; unit system {} ({length}, {pressure}{}){}",
        path.display(),
        chosen.index,
        chosen.name,
        chosen.kind,
        chosen.method,
        saved.folder,
        saved
            .time
            .map(|t| format!(" at t = {t} s"))
            .unwrap_or_default(),
        project.unit_system,
        if length == "ft" {
            "; converted to m and kPa"
        } else {
            ""
        },
        subset.map(|s| format!("; {s}")).unwrap_or_default()
    );
    Ok((nodes, report, note))
}

/// For a `node.csv` read on its own with `--fem-mesh`: joins its rows to the
/// mesh nodes by id ([`join_mesh`], errors at the table's lines) and returns the
/// notes to report. The reader's "no coordinate columns" warning becomes a note.
pub fn attach_mesh_by_id(
    nodes: &mut FemNodes,
    report: &mut FemReadReport,
    csv_path: &Path,
    mesh: &[[f64; 3]],
    mesh_path: &Path,
) -> Result<Vec<String>, FormatError> {
    let text = super::input::read_bytes(csv_path)?;
    let rows = data_row_lines(&text, report.header_line);
    let mesh_name = mesh_path.display().to_string();
    let subset = join_mesh(nodes, csv_path, &rows, mesh, &mesh_name)?;
    report
        .warnings
        .retain(|w| !w.starts_with("no coordinate columns"));
    report.dim = nodes.dim;
    let mut notes = vec![format!(
        "{}: coordinates from {mesh_name} (node k = PLY node k − 1)",
        csv_path.display()
    )];
    notes.extend(subset.map(|n| format!("{}: {n}", csv_path.display())));
    Ok(notes)
}

/// 1-based line numbers of the data rows of a node table: the non-blank lines
/// after the header line, in order (the reader stops at the first bad row, so
/// row i of the nodes is the i-th of these).
pub fn data_row_lines(text: &[u8], header_line: usize) -> Vec<usize> {
    text.split(|&b| b == b'\n')
        .enumerate()
        .skip(header_line)
        .filter(|(_, l)| l.iter().any(|b| !b.is_ascii_whitespace()))
        .map(|(i, _)| i + 1)
        .collect()
}

/// Gives each row of a GeoStudio `node.csv` the coordinates of its mesh node:
/// row `Node = k` ↔ PLY node k − 1. GeoStudio leaves out the nodes outside an
/// analysis's region, so the table may list a subset of the mesh (ids with
/// gaps); that is fine and reported in the returned sentence. Ids not in the
/// mesh and duplicate ids are errors at their line (`row_lines[i]` is the line of
/// row i; row numbers are used when it is shorter). `mesh_name` names the mesh
/// in messages.
pub fn join_mesh(
    nodes: &mut FemNodes,
    csv_path: &Path,
    row_lines: &[usize],
    mesh: &[[f64; 3]],
    mesh_name: &str,
) -> Result<Option<String>, FormatError> {
    let line_of = |i: usize| -> usize {
        if row_lines.len() == nodes.ids.len() {
            row_lines[i]
        } else {
            i + 2
        }
    };
    let mut first_row: Vec<Option<usize>> = vec![None; mesh.len()];
    let mut errors: Vec<ParseError> = Vec::new();
    for (i, &k) in nodes.ids.iter().enumerate() {
        if k < 1 || k as usize > mesh.len() {
            errors.push(ParseError::at(
                csv_path,
                line_of(i),
                1,
                format!(
                    "node {k} is not in the mesh: {mesh_name} has {} nodes (ids 1..={})",
                    mesh.len(),
                    mesh.len()
                ),
            ));
            continue;
        }
        let slot = &mut first_row[k as usize - 1];
        match slot {
            Some(j) => errors.push(ParseError::at(
                csv_path,
                line_of(i),
                1,
                format!("duplicate node id {k} (also on line {})", line_of(*j)),
            )),
            None => *slot = Some(i),
        }
        if errors.len() >= 20 {
            break;
        }
    }
    if let Some(e) = FormatError::from_list(errors) {
        return Err(e);
    }
    for (i, &k) in nodes.ids.iter().enumerate() {
        nodes.positions[i] = mesh[k as usize - 1];
    }
    // A listed node far outside the others cannot be meant.
    if let Some(far) = super::extent::far_outlier(&nodes.positions) {
        return Err(ParseError::at(
            csv_path,
            line_of(far.index),
            1,
            format!("mesh node {} of {mesh_name}: {far}", nodes.ids[far.index]),
        )
        .into());
    }
    // Two rows at one mesh point would give it two values: refused as the
    // same rows with X and Y columns are.
    if let Some((first, second)) = super::extent::first_coincident(&nodes.positions) {
        let p = nodes.positions[first];
        return Err(ParseError::at(
            csv_path,
            line_of(second),
            1,
            format!(
                "duplicate node: mesh node {} of {mesh_name} is at the same point as mesh node {} ({}:{}): ({}, {}, {})",
                nodes.ids[second],
                nodes.ids[first],
                csv_path.display(),
                line_of(first),
                p[0],
                p[1],
                p[2]
            ),
        )
        .into());
    }
    nodes.dim = if nodes.positions.iter().all(|p| p[2] == 0.0) {
        2
    } else {
        3
    };
    let listed = nodes.ids.len();
    Ok((listed < mesh.len()).then(|| {
        format!(
            "the table lists {listed} of the {} mesh nodes (GeoStudio leaves out nodes outside the analysis's region); rows were joined to mesh nodes by their Node id",
            mesh.len()
        )
    }))
}

#[cfg(test)]
mod xml_tests {
    use super::*;

    #[test]
    fn project_xml_is_read_by_element_not_by_text() {
        let xml = "<?xml version=\"1.0\"?><GSIData><EngCoords UnitSystem=\"Imperial\"/>\
            <Analyses><Analysis><Name>Seep &amp; drawdown</Name><Kind>SEEP/W</Kind>\
            <Method>Transient</Method><TimeSteps><TimeStep ElapsedTime=\"60\"/>\
            <TimeStep ElapsedTime=\"120\"/></TimeSteps></Analysis></Analyses></GSIData>";
        let (units, analyses) = parse_project_xml(Path::new("p.gsz"), "p.xml", xml).unwrap();
        assert_eq!(units, "Imperial");
        assert_eq!(analyses.len(), 1);
        assert_eq!(analyses[0].name, "Seep & drawdown");
        assert_eq!(analyses[0].method, "Transient");
        assert_eq!(analyses[0].times, vec![60.0, 120.0]);
    }

    #[test]
    fn malformed_project_xml_is_an_error_at_its_place() {
        let xml = "<GSIData>\n<Analyses><Analysis></Analyses>\n</GSIData>";
        let err = parse_project_xml(Path::new("p.gsz"), "p.xml", xml)
            .err()
            .unwrap()
            .to_string();
        assert!(err.starts_with("p.gsz/p.xml:2:"), "{err}");
    }
}
