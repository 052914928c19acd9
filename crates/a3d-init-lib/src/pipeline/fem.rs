//! FEM node results from every supported source, through one registry
//! ([`reader_for`]): GeoStudio-style CSV tables (with a `Mesh.ply` for a
//! `node.csv` without coordinates), GeoStudio `.gsz` projects and VTK XML
//! results (`.vtu`, `.pvd` time series: OpenGeoSys, ParaView). Several files
//! are joined by node id. Used by `map`, `inspect --fem` and `calibrate` alike.

use std::path::{Path, PathBuf};

use super::PipelineError;
use crate::formats::fem::FemReadReport;
use crate::formats::fem::StepChoice;
use crate::formats::fem_csv::{self, CsvOptions};
use crate::formats::fem_vtu::{self, VtuOptions};
use crate::model::FemNodes;

/// How FEM node files are read.
#[derive(Clone, Debug)]
pub struct FemOptions {
    pub paths: Vec<PathBuf>,
    /// Columns, units and sign convention of CSV tables (and `.gsz` steps).
    pub csv: CsvOptions,
    /// GeoStudio mesh giving the coordinates of a `node.csv` without X, Y.
    pub mesh: Option<PathBuf>,
    /// `.gsz`: analysis name or 1-based index.
    pub analysis: Option<String>,
    /// `.gsz` and `.pvd`: saved step.
    pub step: StepChoice,
    /// Arrays, units, signs and stress rule of `.vtu` and `.pvd` files.
    pub vtu: VtuOptions,
}

impl FemOptions {
    /// `paths` read with the defaults: columns by their headers, units from
    /// the headers, GeoStudio signs, the last saved step of a `.gsz`.
    pub fn files(paths: Vec<PathBuf>) -> FemOptions {
        FemOptions {
            paths,
            csv: CsvOptions::default(),
            mesh: None,
            analysis: None,
            step: StepChoice::Last,
            vtu: VtuOptions::default(),
        }
    }
}

/// The readers a FEM file can go through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FemReader {
    /// A GeoStudio `.gsz` project archive.
    Gsz,
    /// A delimited node table (GeoStudio CSV exports, `node.csv`).
    Csv,
    /// A VTK XML result: `.vtu`, or a `.pvd` time series of them.
    Vtu,
}

/// The reader for `path`, by extension (everything that is not a `.gsz`,
/// `.vtu` or `.pvd` is read as a delimited table, whose dialect is sniffed).
pub fn reader_for(path: &Path) -> FemReader {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gsz"))
    {
        FemReader::Gsz
    } else if fem_vtu::is_vtk_path(path) {
        FemReader::Vtu
    } else {
        FemReader::Csv
    }
}

/// FEM nodes read and joined, with the reports of each file.
pub struct LoadedFem {
    pub nodes: FemNodes,
    pub reports: Vec<FemReadReport>,
    /// The files read, in order.
    pub paths: Vec<PathBuf>,
    /// The sign convention the values were converted from.
    pub sign: crate::formats::fem::SignConvention,
    /// Informational sentences (what was read, how rows were joined): not warnings.
    pub notes: Vec<String>,
}

/// Reads every file of `options` through its reader and joins them.
pub fn load(options: &FemOptions) -> Result<LoadedFem, PipelineError> {
    if options.paths.is_empty() {
        return Err(PipelineError::Input("no FEM node file given".into()));
    }
    if options.step == StepChoice::Failure {
        return Err(PipelineError::Option(
            crate::formats::fem::FAILURE_NEEDS_MODEL.into(),
        ));
    }
    let mut parts = Vec::new();
    let mut reports = Vec::new();
    let mut notes = Vec::new();
    let mut sign = options.csv.sign;
    let mesh = options
        .mesh
        .as_deref()
        .map(crate::formats::ply::read_ply_nodes)
        .transpose()?;
    for path in &options.paths {
        match reader_for(path) {
            FemReader::Gsz => {
                let (nodes, report, note) = crate::formats::gsz::read_step(
                    path,
                    options.analysis.as_deref(),
                    &options.step,
                    &options.csv,
                )?;
                notes.push(note);
                parts.push(nodes);
                reports.push(report);
            }
            FemReader::Vtu => {
                let (nodes, report) = fem_vtu::read(path, &options.vtu, &options.step)?;
                if let Some(vtu) = &report.vtu {
                    notes.push(vtu_note(path, vtu));
                }
                sign = report.sign;
                parts.push(nodes);
                reports.push(report);
            }
            FemReader::Csv => {
                let (mut nodes, mut report) = fem_csv::read_csv(path, &options.csv)?;
                if !report.has_coordinates {
                    match &mesh {
                        // Rows join mesh nodes by `Node` id: a subset of the mesh is fine.
                        Some(mesh) => notes.extend(crate::formats::gsz::attach_mesh_by_id(
                            &mut nodes,
                            &mut report,
                            path,
                            mesh,
                            options.mesh.as_deref().unwrap_or(path),
                        )?),
                        None => {
                            return Err(PipelineError::Input(format!(
                                "{}: no X and Y columns; give the GeoStudio mesh (Mesh.ply) whose nodes its ids name",
                                path.display()
                            )));
                        }
                    }
                }
                parts.push(nodes);
                reports.push(report);
            }
        }
    }
    let nodes = join(parts, &options.paths)?;
    Ok(LoadedFem {
        nodes,
        reports,
        paths: options.paths.clone(),
        sign,
        notes,
    })
}

/// One line on a VTU read: the step of a series, the cells and the units.
fn vtu_note(path: &Path, vtu: &fem_vtu::VtuReport) -> String {
    let step = match &vtu.series {
        Some(c) => format!(
            ", step {} of {} (t = {}, {})",
            c.step,
            c.steps,
            fem_vtu::pvd::time_text(c.time),
            c.file.display()
        ),
        None => String::new(),
    };
    let cells: Vec<String> = vtu.cells.iter().map(|(k, n)| format!("{n} {k}")).collect();
    format!(
        "{}{step}: {}; {}; {}",
        path.display(),
        cells.join(", "),
        vtu.encoding,
        vtu.units
    )
}

/// Joins several node files: by id when every file has ids in the same set, the
/// same quantity in two files must agree.
fn join(mut parts: Vec<FemNodes>, paths: &[PathBuf]) -> Result<FemNodes, PipelineError> {
    let mut out = parts.remove(0);
    for (k, part) in parts.into_iter().enumerate() {
        let path = &paths[k + 1];
        if part.len() != out.len() {
            return Err(PipelineError::Input(format!(
                "{}: {} nodes, but {} has {}: the files do not describe the same nodes",
                path.display(),
                part.len(),
                paths[0].display(),
                out.len()
            )));
        }
        let mut order: Vec<usize> = (0..out.len()).collect();
        let pos_of: std::collections::HashMap<i64, usize> = part
            .ids
            .iter()
            .enumerate()
            .map(|(i, id)| (*id, i))
            .collect();
        for (i, id) in out.ids.iter().enumerate() {
            match pos_of.get(id) {
                Some(&j) => order[i] = j,
                None => {
                    return Err(PipelineError::Input(format!(
                        "{}: node {id} of {} is missing",
                        path.display(),
                        paths[0].display()
                    )));
                }
            }
            let (a, b) = (out.positions[i], part.positions[order[i]]);
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            if d > 1e-6 * (1.0 + a[0].abs() + a[1].abs()) {
                return Err(PipelineError::Input(format!(
                    "{}: node {id} is at {:?} but at {:?} in {}",
                    path.display(),
                    b,
                    a,
                    paths[0].display()
                )));
            }
        }
        for (q, values) in part.fields {
            let reordered: Vec<f64> = order.iter().map(|&j| values[j]).collect();
            if let Some(existing) = out.field(q) {
                if let Some(i) = (0..existing.len()).find(|&i| {
                    (existing[i] - reordered[i]).abs() > 1e-9 * (1.0 + existing[i].abs())
                }) {
                    return Err(PipelineError::Input(format!(
                        "{}: {} of node {} is {} but {} in {}",
                        path.display(),
                        q.name(),
                        out.ids[i],
                        reordered[i],
                        existing[i],
                        paths[0].display()
                    )));
                }
            } else {
                out.fields.push((q, reordered));
            }
        }
        if out.region.is_none() {
            out.region = part
                .region
                .map(|r| order.iter().map(|&j| r[j].clone()).collect());
        }
    }
    Ok(out)
}
