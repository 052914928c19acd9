//! The mapping step as a library call: [`map`] takes a loaded [`Project`], the
//! FEM nodes and a typed [`MapConfig`] and returns the state of every MP with
//! its diagnostics and the report. Nothing is written here
//! ([`write::write_project`] does that) and nothing is printed.
//!
//! [`map`] composes stages that a caller can also run alone, one file each:
//! 1. [`inputs`] checks the FEM against the model and decides the stress source;
//! 2. [`smoothing`] chooses h (spacing rule, given, or calibrated);
//! 3. [`place`] measures the MPs' spacing, finds the material separation and
//!    the FEM's reach;
//! 4. [`interpolate`] maps the FEM fields onto the MPs with the kernel;
//! 5. [`stress`] derives the MPs' states (pwp, total stress from the FEM, the
//!    overburden or zero), or [`equilibrium`] solves for the stress at rest
//!    under gravity;
//! 6. [`mixed`] collapses MPM-MIXED elements to their mean state;
//! 7. [`plausibility`] warns about implausible pwp and refuses non-finite values;
//! 8. [`report`] builds report.json.
//!
//! Physics lives in [`crate::state`] (geostatic stress, Bishop, MPM-MIXED
//! means, dry materials); the kernel interpolation in [`crate::kernel`].

use std::time::Instant;

use super::PipelineError;
use super::Project;
use super::fem::LoadedFem;
use crate::formats::mps_table::MpDiagnostics;
use crate::kernel::Kernel;
use crate::model::MpState;

pub mod config;
pub mod equilibrium;
pub mod inputs;
pub mod interpolate;
pub mod job;
pub mod mixed;
pub mod place;
pub mod plausibility;
mod regions;
pub mod report;
pub mod smoothing;
pub mod stress;
pub mod write;

pub use crate::formats::material_map::{MaterialMap, MaterialRef};
pub use config::{
    EquilibriumOptions, MapConfig, MixedState, Outside, SmoothingLength, StressSource, UnknownName,
};
pub use interpolate::FemCloud;
pub use place::Placement;
pub use report::{InputFile, MapReport, MaterialCount, Smoothing};
pub use smoothing::ChosenH;

/// Everything `map` computes before writing.
pub struct Mapped {
    /// The model, its files and its MPs.
    pub project: Project,
    /// The FEM nodes: their fields dropped unless `fem.vtu` is wanted, and
    /// their positions and ids too when nothing else needs them
    /// ([`interpolate::KeepNodes`]); report.json keeps their count.
    pub fem: LoadedFem,
    /// The state of each MP, in MP order.
    pub states: Vec<MpState>,
    /// How each MP was mapped.
    pub diagnostics: Vec<MpDiagnostics>,
    /// What report.json says, the exact-point MAPF's h among it.
    pub report: MapReport,
}

/// Maps the FEM fields onto the project's MPs (no output written): the state
/// per MP, the mapping diagnostics and the report.
pub fn map(
    project: Project,
    mut fem: LoadedFem,
    config: &MapConfig,
) -> Result<Mapped, PipelineError> {
    let hashing = report::Hashing::start(&project, &fem);
    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
    let mut timings = Vec::new();
    let mut notes: Vec<String> = fem.notes.clone();
    let mut warnings = inputs::read_warnings(&project, &fem);
    let dim = project.n_dim();
    if let Some(words) = project
        .cps
        .as_ref()
        .and_then(crate::pipeline::check::runner::start_gravity_words)
        && config.stress != StressSource::Zero
    {
        warnings.push(format!(
            "{words}, but the MAPF holds a stress under full gravity: Anura3D starts it out of balance (set `$$GRAVITY_LOAD step 1.0 1.0` to hold full gravity from the start)"
        ));
    }

    inputs::check_fem(&project, &fem)?;
    let resolved = inputs::stress_source(config.stress, &project, &fem)?;
    let source = resolved.source;
    if config.stress == StressSource::Auto {
        notes.push(format!("stress source {source}: {}", resolved.because));
    }
    let t = Instant::now();
    let chosen = smoothing::choose_h(&fem.nodes, config.kernel, &config.h, source)?;
    if let SmoothingLength::Calibrate { .. } = config.h {
        timings.push(("calibration".to_string(), ms(t)));
    }
    let mut placement = place::place(
        &project,
        &fem,
        config.material_map.as_ref(),
        source,
        config.outside,
        config.kernel.support() * chosen.h,
    )?;
    notes.append(&mut placement.notes);
    warnings.append(&mut placement.warnings);

    // The geostatic stress maps the cloud a second time: it keeps its values;
    // otherwise the mapper takes them and frees them once its grid has a copy.
    // `--stress equilibrium` keeps it too: where no state at rest exists,
    // the geostatic state is its floor (`equilibrium::no_worse_than_geostatic`).
    let samples_again = matches!(source, StressSource::Geostatic | StressSource::Equilibrium);
    let keep = match (config.keep_fem_fields, samples_again) {
        (true, _) => interpolate::KeepNodes::All,
        (false, true) => interpolate::KeepNodes::Positions,
        // Without fem.vtu or a second mapping, the mapping is the nodes' last
        // use: their positions go to the mapper too.
        (false, false) => interpolate::KeepNodes::Nothing,
    };
    let fem_nodes = fem.nodes.len();
    let cloud = interpolate::prepare(
        &mut fem.nodes,
        &placement,
        source,
        config.settings(chosen.h),
        chosen.spacing,
        keep,
    );
    let quantities = cloud.quantities.clone();
    let t = Instant::now();
    let (mut result, sampler) = if samples_again {
        let result = interpolate::interpolate(&cloud, &placement, &project.points, &fem.paths)?;
        (result, Some(cloud))
    } else {
        let result =
            interpolate::interpolate_taking(cloud, &placement, &project.points, &fem.paths)?;
        (result, None)
    };
    timings.push(("kernel mapping".to_string(), ms(t)));

    // The kernel's index is gone: the MP positions as a slice, for the steps
    // that follow.
    let positions = positions_for(&project, source);
    let values = std::mem::take(&mut result.values);
    let stress = stress::derive_stress(&project, source, &quantities, values);
    let mut states = stress.states;
    notes.extend(stress.notes);
    if let Some(cloud) = sampler
        .as_ref()
        .filter(|_| source == StressSource::Geostatic)
    {
        let t = Instant::now();
        notes.extend(stress::geostatic_stress(
            &project,
            &positions,
            cloud,
            &mut states,
        )?);
        timings.push(("geostatic stress".to_string(), ms(t)));
    }
    let mut assumed = stress::assumed_defaults(&project, source, &quantities);
    notes.extend(assumed.iter().map(stress::default_note));
    warnings.extend(stress.warnings);
    if project.cbgeo.is_none() {
        notes.push(report::mapf_note(dim).into());
    }

    let null_points = interpolate::null_points(&result);
    warnings.extend(interpolate::null_point_warning(null_points, config.outside));
    stress::zero_skipped(&mut states, &result.status);
    let equilibrium_report = if source == StressSource::Equilibrium {
        let phase = solve_equilibrium(
            &project,
            &mut states,
            config,
            resolved.because,
            sampler.as_ref(),
            &positions,
        )?;
        notes.extend(phase.notes);
        warnings.extend(phase.warnings);
        assumed.extend(phase.assumed);
        timings.extend(phase.timings);
        Some(phase.report)
    } else {
        None
    };
    // The FEM values' row-major copy is no longer needed.
    drop(sampler);
    let diagnostics = interpolate::diagnostics(&result);
    drop(result);
    if source != StressSource::Zero {
        let g = stress::gravity(&project);
        warnings.extend(plausibility::check_plausibility(
            &positions, &states, dim, g,
        ));
    }
    drop(positions);
    let collapse = mixed::collapse_mixed(&project, config.mixed_state, &mut states);
    notes.extend(collapse.notes);
    warnings.extend(collapse.warnings);
    plausibility::check_finite(&states)?;

    let report = report::build_report(report::ReportInputs {
        project: &project,
        fem: &fem,
        fem_nodes,
        files: hashing.join()?,
        kernel: config.kernel,
        smoothing: chosen,
        stress_source: source,
        placement: &placement,
        outside: config.outside,
        null_points,
        mixed_state: collapse.applied,
        states: &states,
        assumed_defaults: assumed,
        equilibrium: equilibrium_report,
        notes,
        warnings,
        timings_ms: timings,
    });
    Ok(Mapped {
        project,
        fem,
        states,
        diagnostics,
        report,
    })
}

/// The MP positions for the steps after the kernel (the geostatic stress,
/// the equilibrium solve, the plausibility check), none when the stress is
/// zero and none of them runs.
fn positions_for(project: &Project, source: StressSource) -> Vec<[f64; 3]> {
    if source == StressSource::Zero {
        Vec::new()
    } else {
        project.mp_positions()
    }
}

/// What the equilibrium phase of [`map`] adds to the report.
struct EquilibriumPhase {
    report: equilibrium::EquilibriumReport,
    notes: Vec<String>,
    warnings: Vec<String>,
    assumed: Vec<crate::state::defaults::AssumedDefault>,
    timings: Vec<(String, f64)>,
}

/// `--stress equilibrium`: the stress at rest on Anura3D's discretisation,
/// then, where no state at rest exists, the geostatic floor from the FEM
/// `cloud` (the state written is never further out of balance than the
/// geostatic start).
fn solve_equilibrium(
    project: &Project,
    states: &mut [MpState],
    config: &MapConfig,
    because: String,
    cloud: Option<&interpolate::FemCloud<'_>>,
    positions: &[[f64; 3]],
) -> Result<EquilibriumPhase, PipelineError> {
    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
    let (mut notes, mut warnings, mut timings) = (Vec::new(), Vec::new(), Vec::new());
    let t = Instant::now();
    let report = equilibrium::equilibrium_stress(
        project,
        states,
        config.mixed_state,
        &config.equilibrium,
        because,
    )?;
    timings.push(("equilibrium stress".to_string(), ms(t)));
    if let Some(cloud) = cloud {
        let t = Instant::now();
        match equilibrium::no_worse_than_geostatic(project, positions, cloud, states, &report)? {
            Some(Ok(note)) => notes.push(note),
            Some(Err(warning)) => warnings.push(warning),
            None => {}
        }
        timings.push(("geostatic floor".to_string(), ms(t)));
    }
    notes.extend(equilibrium::notes(&report));
    let assumed = equilibrium::assumed_defaults(&report);
    warnings.extend(equilibrium::warnings(&report));
    Ok(EquilibriumPhase {
        report,
        notes,
        warnings,
        assumed,
        timings,
    })
}
