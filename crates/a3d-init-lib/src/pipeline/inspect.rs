//! `inspect` as library calls: the summary of an Anura3D project (files,
//! versions, mesh, MPs, materials with their unit weights), of FEM node files
//! (how each column was read, extents, field ranges, node spacing), and of a
//! GeoStudio `.gsz` archive (analyses, saved steps, the last step's nodes).
//! The CLI prints these; `--json` serialises them as they are.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::PipelineError;
use super::fem::{FemOptions, LoadedFem};
use super::io::output::{ReadLog, write_new};
use super::project::Project;
use crate::diagnose::Extent;
use crate::formats::fem::FemReadReport;
use crate::formats::fem::StepChoice;
use crate::formats::fem_vtu;
use crate::formats::gsz::{self, GszProject};
use crate::formats::project::{OutputNames, ProjectFiles};
use crate::model::{FemNodes, Material};

/// One material of a project: its record as read, where it is used and its
/// dry unit weight.
#[derive(Clone, Debug, Serialize)]
pub struct MaterialSummary {
    #[serde(flatten)]
    pub material: Material,
    /// Elements of this material.
    pub elements: usize,
    /// MPs of this material.
    pub mps: usize,
    /// Dry unit weight γ_dry (kN/m³) at the project's gravity.
    pub gamma_dry: f64,
}

impl MaterialSummary {
    /// The summary of material `m` of `project`, its dry unit weight at gravity `g`.
    pub fn of(m: &Material, project: &Project, g: f64) -> MaterialSummary {
        let count = |materials: &mut dyn Iterator<Item = u32>| {
            materials.filter(|&index| index == m.index).count()
        };
        MaterialSummary {
            material: m.clone(),
            elements: count(&mut project.model.element_material.iter().copied()),
            mps: count(&mut project.points.iter().map(|p| p.material)),
            gamma_dry: m.gamma_dry(g),
        }
    }
}

/// What `inspect MODEL` shows of a project.
#[derive(Clone, Debug, Serialize)]
pub struct ProjectSummary {
    pub files: ProjectFiles,
    pub version: String,
    pub cps_version: Option<String>,
    /// The file names a ready-to-run project of this model uses, and why.
    #[serde(skip)]
    pub output_names: OutputNames,
    pub dimension: &'static str,
    pub element_type: &'static str,
    pub formulation: Option<String>,
    pub computation_method: &'static str,
    pub nodes: usize,
    pub elements: usize,
    pub active_elements: usize,
    pub material_points: usize,
    pub fixed_nodes: usize,
    pub bounding_box: ([f64; 3], [f64; 3]),
    pub materials: Vec<MaterialSummary>,
    pub warnings: Vec<String>,
    /// A CB-Geo model: what CB-Geo reads beyond the mesh and materials; left
    /// out of the JSON for an Anura3D project.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cbgeo: Option<CbGeoSummary>,
}

/// What `inspect` shows of a CB-Geo model beyond the common summary.
#[derive(Clone, Debug, Serialize)]
pub struct CbGeoSummary {
    /// The branch its run file is for, and why.
    pub branch: crate::formats::cbgeo::Branch,
    pub branch_because: String,
    pub cell_type: &'static str,
    pub analysis: String,
    /// m/s², x y z.
    pub gravity: [f64; 3],
    /// Per generator: `file <name>` or `gauss <n> per direction in cell set <k>`,
    /// its particle type, CB-Geo material ids and particle count.
    pub generators: Vec<String>,
    pub two_phase_particles: usize,
    /// Cell sets: (id, cells).
    pub cell_sets: Vec<(i64, usize)>,
    /// The initial stresses the run file names today.
    pub stresses_key: crate::formats::cbgeo::StressKey,
    /// Every file the run file names.
    pub files: Vec<String>,
}

impl CbGeoSummary {
    /// The summary of a CB-Geo model as loaded.
    pub fn of(t: &crate::pipeline::cbgeo::CbGeoTarget) -> CbGeoSummary {
        use crate::formats::cbgeo::Particles;
        let m = &t.model;
        let generators = m
            .generators
            .iter()
            .zip(&t.generated)
            .map(|(g, ids)| {
                let what = match &g.particles {
                    Particles::File { path, .. } => format!("file {}", path.display()),
                    Particles::Gauss { per_dir, cset_id } => {
                        format!("gauss {per_dir} per direction in cell set {cset_id}")
                    }
                };
                let kind = if g.particle_type.is_empty() {
                    "?"
                } else {
                    &g.particle_type
                };
                format!(
                    "{what}: {} {kind} particles (ids {}..{}), material ids {:?}",
                    ids.len(),
                    ids.start,
                    ids.end.saturating_sub(1).max(ids.start),
                    g.material_ids
                )
            })
            .collect();
        CbGeoSummary {
            branch: m.branch,
            branch_because: m.branch_because.clone(),
            cell_type: m.cell.name(),
            analysis: m.analysis_type.clone(),
            gravity: m.gravity,
            generators,
            two_phase_particles: t.two_phase_particles(),
            cell_sets: m.cell_sets.iter().map(|(id, s)| (*id, s.len())).collect(),
            stresses_key: m.stresses_key.clone(),
            files: m.referenced.iter().map(|r| r.name.clone()).collect(),
        }
    }
}

impl ProjectSummary {
    /// The summary of a loaded project.
    pub fn of(p: &Project) -> ProjectSummary {
        let g = p.gravity();
        let mesh = &p.model.mesh;
        ProjectSummary {
            files: p.files.clone(),
            version: p.gom_version.clone(),
            cps_version: p.cps.as_ref().map(|c| c.version().to_string()),
            output_names: p.files.output_names(&p.gom_version),
            dimension: mesh.dimension.gom_name(),
            element_type: mesh.element_type.gom_name(),
            formulation: p.info.formulation.clone(),
            computation_method: p.method.cps_name(),
            nodes: mesh.n_nodes(),
            elements: mesh.n_elements(),
            active_elements: p.model.element_material.iter().filter(|&&m| m > 0).count(),
            material_points: p.points.len(),
            fixed_nodes: p
                .model
                .solid_fixity
                .iter()
                .filter(|f| f.iter().any(|&b| b))
                .count(),
            bounding_box: mesh.bounding_box(),
            materials: p
                .model
                .materials
                .iter()
                .map(|m| MaterialSummary::of(m, p, g))
                .collect(),
            warnings: p.info.warnings.clone(),
            cbgeo: p.cbgeo.as_deref().map(CbGeoSummary::of),
        }
    }
}

/// Loads the project at `model` and summarises it; with `mps`, also writes
/// the predicted MPs to that CSV (replaced under `force`).
pub fn project(
    model: &Path,
    mps: Option<&Path>,
    force: bool,
) -> Result<ProjectSummary, PipelineError> {
    let reads = ReadLog::start();
    let p = Project::load(model)?;
    if let Some(path) = mps {
        write_new(path, force, &reads, |w| {
            crate::formats::mps_table::write_points(w, &p.points)
        })?;
    }
    Ok(ProjectSummary::of(&p))
}

/// One field's range over the FEM nodes (Anura3D signs, kPa).
#[derive(Clone, Debug, Serialize)]
pub struct FieldRange {
    pub name: String,
    pub min: f64,
    pub max: f64,
}

/// What `inspect --fem` shows of FEM node files.
#[derive(Clone, Debug, Serialize)]
pub struct FemSummary {
    /// How each file was read: dialect, columns, units, signs, warnings.
    pub reports: Vec<FemReadReport>,
    /// What joining the files (or a table and its mesh) did.
    pub notes: Vec<String>,
    /// The coordinate range of the nodes (`None` without nodes).
    pub extent: Option<Extent>,
    /// Each field's range (Anura3D signs, kPa).
    pub fields: Vec<FieldRange>,
    /// Median nearest-node distance l (m).
    pub spacing: f64,
}

impl FemSummary {
    /// The summary of loaded FEM files.
    pub fn of(fem: &LoadedFem) -> FemSummary {
        let nodes = &fem.nodes;
        FemSummary {
            reports: fem.reports.clone(),
            notes: fem.notes.clone(),
            extent: Extent::of(&nodes.positions, nodes.dim),
            fields: nodes
                .fields
                .iter()
                .map(|(q, v)| {
                    let (min, max) = v
                        .iter()
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                            (a.min(*x), b.max(*x))
                        });
                    FieldRange {
                        name: q.name(),
                        min,
                        max,
                    }
                })
                .collect(),
            spacing: crate::kernel::mapper::median_spacing(&nodes.positions, nodes.dim),
        }
    }
}

/// Reads FEM node files and summarises them.
pub fn fem(options: &FemOptions) -> Result<FemSummary, PipelineError> {
    Ok(FemSummary::of(&super::fem::load(options)?))
}

/// The last saved step of one analysis of a `.gsz`, as read.
#[derive(Clone, Debug)]
pub enum GszStep {
    /// The analysis has no saved step.
    None,
    /// The analysis has no mesh: its results cannot be placed.
    NoMesh,
    /// The step's nodes, with the note of the join of table and mesh.
    Read { nodes: FemNodes, note: String },
    /// The step could not be read.
    Unreadable(String),
}

/// What `inspect project.gsz` shows.
#[derive(Clone, Debug, Serialize)]
pub struct GszSummary {
    pub path: PathBuf,
    #[serde(flatten)]
    pub project: GszProject,
    /// Per analysis, its last saved step.
    #[serde(skip)]
    pub last_steps: Vec<GszStep>,
}

impl GszSummary {
    /// The error an archive whose listed results cannot be read is: the first
    /// unreadable step's.
    pub fn unreadable(&self) -> Option<PipelineError> {
        self.last_steps.iter().find_map(|s| match s {
            GszStep::Unreadable(e) => Some(PipelineError::Input(format!(
                "{}: the archive lists results that cannot be read: {e}",
                self.path.display()
            ))),
            _ => None,
        })
    }
}

/// Summarises a `.gsz`: its analyses and the last saved step of each (see
/// [`GszSummary::unreadable`] for an archive whose results cannot be read).
pub fn gsz(path: &Path) -> Result<GszSummary, PipelineError> {
    let project = gsz::read_project(path)?;
    let last_steps = project
        .analyses
        .iter()
        .map(|a| {
            let Some(last) = a.steps.last() else {
                return GszStep::None;
            };
            if !a.has_mesh {
                return GszStep::NoMesh;
            }
            match gsz::read_step(
                path,
                Some(&a.index.to_string()),
                &StepChoice::Number(last.number),
                &Default::default(),
            ) {
                Ok((nodes, _, note)) => GszStep::Read { nodes, note },
                Err(e) => GszStep::Unreadable(e.to_string()),
            }
        })
        .collect();
    Ok(GszSummary {
        path: path.to_path_buf(),
        project,
        last_steps,
    })
}

/// What `inspect run.pvd` (or `inspect result.vtu`) shows: the outputs of a
/// series and the arrays, cells and materials of its last output.
#[derive(Clone, Debug, Serialize)]
pub struct VtuSummary {
    pub path: PathBuf,
    /// The series' outputs (a `.pvd`), in time order.
    pub outputs: Vec<fem_vtu::pvd::Output>,
    /// Files the series lists that do not exist.
    pub missing: Vec<PathBuf>,
    /// The last output (or the `.vtu` itself), described.
    pub last: fem_vtu::VtuReport,
}

/// Summarises a `.vtu` or a `.pvd` time series.
pub fn vtu(path: &Path) -> Result<VtuSummary, PipelineError> {
    let is_pvd = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pvd"));
    if !is_pvd {
        return Ok(VtuSummary {
            path: path.to_path_buf(),
            outputs: Vec::new(),
            missing: Vec::new(),
            last: fem_vtu::describe(path)?,
        });
    }
    let series = fem_vtu::pvd::read(path)?;
    let missing: Vec<PathBuf> = series
        .outputs
        .iter()
        .filter(|o| !o.file.is_file())
        .map(|o| o.file.clone())
        .collect();
    let last_file = &series.outputs[series.outputs.len() - 1].file;
    let last = fem_vtu::describe(last_file)?;
    Ok(VtuSummary {
        path: path.to_path_buf(),
        outputs: series.outputs,
        missing,
        last,
    })
}
