//! `map` as one library call: read the Anura3D project and the FEM files side
//! by side, map ([`crate::pipeline::map::map`]) and write the ready-to-run project with
//! its diagnostics ([`crate::pipeline::map::write::write_project`]) into an atomic, durable
//! output folder ([`crate::pipeline::io::output`]).

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::formats::fem::StepChoice;
use crate::pipeline::PipelineError;
use crate::pipeline::fem::FemOptions;
use crate::pipeline::io::output::{Destination, OutputDir, ReadLog};
use crate::pipeline::map::{MapConfig, Mapped};
use crate::pipeline::project::Project;

/// Everything `map` needs.
#[derive(Clone, Debug)]
pub struct MapJob {
    /// The Anura3D model: a GOM, `.GOM_stage<k>`, `-2.dat`, `.CPS_<nnn>` or
    /// a project folder.
    pub model: PathBuf,
    /// The FEM files and how to read them.
    pub fem: FemOptions,
    /// How to map.
    pub config: MapConfig,
    /// Without a CPS beside the model, write a complete default CPS for the
    /// model's version (else a model without a CPS is refused).
    pub generate_cps: bool,
    /// Write `fem.vtu` whatever the FEM's size (otherwise only up to
    /// [`crate::pipeline::map::write::FEM_VTU_AUTO_MAX`] nodes).
    pub fem_vtu: bool,
}

/// Loads the project and the FEM files side by side (they are independent,
/// and each fills the other's serial stretches) and maps, timing each phase.
pub fn compute(job: &MapJob) -> Result<Mapped, PipelineError> {
    if job.fem.step == StepChoice::Failure {
        return compute_at_failure(job);
    }
    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
    let (project, fem) = rayon::join(
        || {
            let t = Instant::now();
            Project::load(&job.model).map(|p| (p, ms(t)))
        },
        || {
            let t = Instant::now();
            crate::pipeline::fem::load(&job.fem).map(|f| (f, ms(t)))
        },
    );
    let (project, t_model) = project?;
    check_cps(&project, job)?;
    let (fem, t_fem) = fem?;
    map_loaded(job, project, fem, t_model, ("read FEM", t_fem))
}

/// A model without a CPS is refused unless the job writes a default one.
fn check_cps(project: &Project, job: &MapJob) -> Result<(), PipelineError> {
    if project.files.cps.is_none() && !job.generate_cps && project.cbgeo.is_none() {
        return Err(PipelineError::Input(
            crate::formats::project::missing_cps_message(&project.files),
        ));
    }
    Ok(())
}

/// `--step failure`: the model first, then FS(t) over the series on it, then
/// the map of the first saved step with FS ≤ 1 ([`crate::pipeline::stability::failure`]).
fn compute_at_failure(job: &MapJob) -> Result<Mapped, PipelineError> {
    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let project = Project::load(&job.model)?;
    check_cps(&project, job)?;
    let t_model = ms(t);
    let t = Instant::now();
    let (fem, failure) =
        crate::pipeline::stability::failure::failure_step(&project, &job.fem, &job.config.failure)?;
    let t_fem = ms(t);
    let mut mapped = map_loaded(
        job,
        project,
        fem,
        t_model,
        ("read the FEM series and FS(t)", t_fem),
    )?;
    mapped.report.notes.insert(0, failure.note());
    mapped.report.failure = Some(failure);
    Ok(mapped)
}

/// Maps FEM nodes already read onto a project already loaded; the timings
/// are of reading the model and of the FEM phase `fem_step` names.
fn map_loaded(
    job: &MapJob,
    project: Project,
    fem: crate::pipeline::fem::LoadedFem,
    t_model: f64,
    (fem_step, t_fem): (&str, f64),
) -> Result<Mapped, PipelineError> {
    let mut config = job.config.clone();
    config.kernel = config.kernel.for_dim(project.n_dim());
    config.keep_fem_fields =
        job.fem_vtu || fem.nodes.len() <= crate::pipeline::map::write::FEM_VTU_AUTO_MAX;
    let mut mapped = crate::pipeline::map::map(project, fem, &config)?;
    mapped.report.timings_ms.splice(
        0..0,
        [
            ("read model and place MPs".to_string(), t_model),
            (fem_step.to_string(), t_fem),
        ],
    );
    Ok(mapped)
}

/// Default output folder: `<project>.a3d-init/` beside the model.
pub fn default_out(project_dir: &Path, name: &str) -> PathBuf {
    project_dir.join(format!("{name}.a3d-init"))
}

/// What [`map`] wrote.
pub struct Written {
    /// The files, in the order written.
    pub files: Vec<String>,
    /// The output folder.
    pub folder: PathBuf,
}

/// `map`: computes and writes the project into the destination (default
/// `<project>.a3d-init/` beside the model; an existing folder is replaced
/// only when the destination says so, and never when it is or holds an
/// input).
pub fn map(job: &MapJob, to: Destination<'_>) -> Result<(Mapped, Written), PipelineError> {
    let reads = ReadLog::start();
    let mapped = compute(job)?;
    let files = &mapped.project.files;
    let target = to.or(|| default_out(&files.dir, &files.name));
    let dir = OutputDir::create(&target, to.replace, &reads, "map")?;
    let files = crate::pipeline::map::write::write_project(&mapped, &dir.staging(), job.fem_vtu)?;
    let folder = dir.commit()?;
    Ok((mapped, Written { files, folder }))
}
