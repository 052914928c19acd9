//! What `verify`, `run` and `fos` share around the built-in runner
//! ([`crate::mpm`]): its settings from the project's CPS, and the files it
//! leaves (MP snapshots as VTU, the kinetic-energy and residual history as SVG).

use std::path::{Path, PathBuf};

use plotters::style::RGBColor;

use crate::formats::cps::CpsDocument;
use crate::formats::vtu;
use crate::mpm::{self, RunSettings};
use crate::pipeline::PipelineError;
use crate::pipeline::check::start::{Start, StateSource};
use crate::pipeline::io::output::{Destination, OutputDir, ReadLog};
use crate::pipeline::io::plot::{self, Series};

/// Local damping α when neither the caller nor the CPS gives one.
pub const DEFAULT_DAMPING: f64 = 0.75;

/// Refuses a local damping α the caller gives that is not a number in
/// [0, 1) (a CPS's value is clamped as Anura3D reads it; a caller's is not
/// silently changed).
pub fn check_damping(damping: Option<f64>) -> Result<(), PipelineError> {
    match damping {
        Some(d) if !(0.0..1.0).contains(&d) => Err(PipelineError::Option(format!(
            "local damping {d}: expected a number in [0, 1)"
        ))),
        _ => Ok(()),
    }
}

/// `s` with the CPS's gravity, submerged-calculation switch and Courant number (capped at 0.9) and the local
/// damping α: `damping`, else the CPS `$$HOMOGENEOUS_LOCAL_DAMPING`, else
/// [`DEFAULT_DAMPING`], clamped to [0, 0.99].
pub fn with_cps(
    mut s: RunSettings,
    cps: Option<&CpsDocument>,
    damping: Option<f64>,
) -> RunSettings {
    if let Some(cps) = cps {
        s.gravity = cps.gravity();
        s.submerged_calculation = cps.submerged_calculation();
        if let Some(c) = cps.get_real("$$COURANT_NUMBER", 0) {
            s.courant = c.min(0.9);
        }
        s.element_smoothing = cps.computation_method() == "MPM-MIXED";
    }
    s.damping = damping
        .or_else(|| cps.and_then(CpsDocument::local_damping))
        .unwrap_or(DEFAULT_DAMPING)
        .clamp(0.0, 0.99);
    s
}

/// The seepage face and infiltration the project's CPS switches on
/// (`$$APPLY_SEEPAGE_FACE 1`, `$$APPLY_INFILTRATION 1`) over its GOM's
/// areas, and notes on what the CPS asks for and the GOM lacks.
pub fn hydraulic(
    project: &crate::pipeline::Project,
) -> (mpm::seepage::HydraulicBoundaries, Vec<String>) {
    let mut notes = Vec::new();
    let Some(cps) = project.cps.as_ref() else {
        return (Default::default(), notes);
    };
    let on = |keyword: &str| cps.get_real(keyword, 0) == Some(1.0);
    let areas = &project.info.hydraulic;
    let mut boundaries = mpm::seepage::HydraulicBoundaries::default();
    if on("$$APPLY_SEEPAGE_FACE") {
        match areas.seepage {
            Some(area) => boundaries.seepage_area = Some(area),
            None => notes.push(
                "the CPS applies a seepage face but the GOM has no $$BOUNDARY_SEEPAGE_AREA: none applied"
                    .into(),
            ),
        }
    }
    if on("$$APPLY_INFILTRATION") {
        match (areas.infiltration, areas.infiltration_rate) {
            (Some(area), Some(rate)) => boundaries.infiltration = Some((area, rate)),
            _ => notes.push(
                "the CPS applies infiltration but the GOM lacks $$BOUNDARY_INFILTRATION_AREA or $$INFILTRATION_RATE: none applied"
                    .into(),
            ),
        }
    }
    (boundaries, notes)
}

/// `s` with what the project adds to gravity: its seepage face and
/// infiltration ([`hydraulic`]) and its GOM loads ([`loads`]); with the notes
/// on what the runner does not apply.
pub fn with_project(
    mut s: RunSettings,
    project: &crate::pipeline::Project,
) -> Result<(RunSettings, Vec<String>), PipelineError> {
    let (hydraulic, mut notes) = hydraulic(project);
    s.hydraulic = hydraulic;
    let (loads, more) = loads(project)?;
    s.loads = loads;
    notes.extend(more);
    Ok((s, notes))
}

/// The GOM's load blocks with the CPS's multipliers (`$$SOLID_TRACTION[_B]`,
/// `$$LIQUID_PRESSURE[_B]`, and `$$GRAVITY_LOAD` for gravity; the kernel's
/// `step 0 1` where the CPS names none, full gravity and no loads without a
/// CPS) and load-step timing, and the water level
/// of `$$HYDRAULIC_HEAD file` (`<project>.HHBF` over the GOM's
/// `$$BOUNDARY_HYDRAULIC_HEAD_AREA`; a missing or bad file is an error, a
/// missing area a note).
pub fn loads(
    project: &crate::pipeline::Project,
) -> Result<(crate::model::loads::ProjectLoads, Vec<String>), PipelineError> {
    let mut notes = Vec::new();
    let Some(cps) = project.cps.as_ref() else {
        return Ok((Default::default(), notes));
    };
    let (load_steps, step_time) = cps.load_steps();
    let from_file = cps
        .get_token("$$HYDRAULIC_HEAD", 0)
        .is_some_and(|t| t == "file");
    let head = match (from_file, project.info.hydraulic.hydraulic_head) {
        (false, _) => None,
        (true, None) => {
            notes.push(
                "the CPS prescribes a hydraulic head from a file but the GOM has no $$BOUNDARY_HYDRAULIC_HEAD_AREA: none applied"
                    .into(),
            );
            None
        }
        (true, Some(area)) => {
            let path = hhbf_path(project);
            Some(crate::model::loads::HeadSeries {
                area,
                points: crate::formats::hhbf::read(&path)?,
            })
        }
    };
    let gravity = cps.multiplier("$$GRAVITY_LOAD");
    if let Some(words) = start_gravity_words(cps) {
        notes.push(format!(
            "{words}: Anura3D and this runner follow it, so a state mapped at full weight starts out of balance; `step 1.0 1.0` holds full gravity from the start"
        ));
    }
    let loads = crate::model::loads::ProjectLoads {
        blocks: project.info.loads.clone(),
        solid: [
            cps.multiplier("$$SOLID_TRACTION"),
            cps.multiplier("$$SOLID_TRACTION_B"),
        ],
        liquid: [
            cps.multiplier("$$LIQUID_PRESSURE"),
            cps.multiplier("$$LIQUID_PRESSURE_B"),
        ],
        gravity,
        load_steps,
        step_time,
        head,
    };
    Ok((loads, notes))
}

/// When the CPS's `$$GRAVITY_LOAD` gives the first step less (or more) than
/// full gravity: the words naming the start value, the CPS file, line and
/// keyword (``the CPS's gravity starts at 0.000·g (x.CPS_001:57:
/// `$$GRAVITY_LOAD off 0.0 1.0`)``). A state mapped at full weight then
/// starts out of balance, in Anura3D as in this runner.
pub fn start_gravity_words(cps: &CpsDocument) -> Option<String> {
    let (load_steps, step_time) = cps.load_steps();
    let start = cps
        .multiplier("$$GRAVITY_LOAD")
        .at(0.0, load_steps, step_time);
    if start == 1.0 {
        return None;
    }
    let place = match (
        cps.keyword_line("$$GRAVITY_LOAD"),
        cps.get("$$GRAVITY_LOAD"),
    ) {
        (Some(line), Some(v)) => format!(
            "{}:{line}: `$$GRAVITY_LOAD {}`",
            cps.document().path().display(),
            v.join(" ")
        ),
        _ => "$$GRAVITY_LOAD absent: the kernel's `step 0 1`".to_string(),
    };
    Some(format!(
        "the CPS's gravity starts at {start:.3}·g ({place})"
    ))
}

/// `<project>.HHBF` beside the project's files, where Anura3D looks for it.
pub fn hhbf_path(project: &crate::pipeline::Project) -> PathBuf {
    project
        .files
        .dir
        .join(format!("{}.HHBF", project.files.name))
}

/// The runner's error as a pipeline error: an unsupported element or material
/// is the model's, anything else numerical.
pub fn runner_error(e: mpm::MpmError) -> PipelineError {
    match e {
        mpm::MpmError::Unsupported(_) | mpm::MpmError::UnsupportedMaterialModel { .. } => {
            PipelineError::Model(e.to_string())
        }
        mpm::MpmError::TooManySteps { .. } => PipelineError::Option(e.to_string()),
        mpm::MpmError::Snapshot(message) => PipelineError::Output(message),
        _ => PipelineError::Numerical(e.to_string()),
    }
}

/// An MP snapshot as a VTU: positions, displacements, effective stresses,
/// plastic flags, pore pressures and, where known, saturations and liquid
/// velocities.
pub fn write_snapshot(
    out: &OutputDir<'_>,
    name: &str,
    s: &mpm::Snapshot,
) -> Result<(), PipelineError> {
    let mut arrays = vec![
        vtu::PointArray {
            name: "displacement".into(),
            components: 3,
            values: s.displacements.iter().flat_map(|d| *d).collect(),
        },
        vtu::PointArray {
            name: "effective_stress".into(),
            components: 9,
            values: s.stresses.iter().flat_map(vtu::tensor9).collect(),
        },
        vtu::PointArray {
            name: "plastic".into(),
            components: 1,
            values: s
                .plastic
                .iter()
                .map(|&p| if p { 1.0 } else { 0.0 })
                .collect(),
        },
        vtu::PointArray {
            name: "pore_pressure".into(),
            components: 1,
            values: s.pore_pressures.clone(),
        },
    ];
    if !s.saturations.is_empty() {
        arrays.push(vtu::PointArray {
            name: "saturation".into(),
            components: 1,
            values: s.saturations.clone(),
        });
    }
    if !s.liquid_velocities.is_empty() {
        arrays.push(vtu::PointArray {
            name: "liquid_velocity".into(),
            components: 3,
            values: s.liquid_velocities.iter().flat_map(|v| *v).collect(),
        });
    }
    out.write(name, |w| vtu::write_points(w, &s.positions, &arrays))
}

/// Kinetic energy and out-of-balance force ratio against time (SVG).
pub fn history_plot(path: &Path, report: &mpm::RunReport) -> Result<(), PipelineError> {
    let ke: Vec<(f64, f64)> = report
        .records
        .iter()
        .map(|r| (r.time, r.kinetic_energy))
        .collect();
    let res: Vec<(f64, f64)> = report
        .records
        .iter()
        .map(|r| (r.time, r.residual_ratio))
        .collect();
    plot::line_chart(
        path,
        "Kinetic energy and out-of-balance force ratio",
        "time t (s)",
        "kinetic energy (kJ/m) · residual ratio (–)",
        &[
            Series {
                label: "kinetic energy (kJ/m)",
                points: ke,
                color: RGBColor(31, 119, 180),
                markers: false,
            },
            Series {
                label: "residual ratio (–)",
                points: res,
                color: RGBColor(214, 39, 40),
                markers: false,
            },
        ],
        true,
    )
}

/// What a command on a mapped state begins with: the log of every file it
/// reads (started before the first read), the start `source` names, and the
/// folder its outputs go to (the destination's, else `default_name` in the
/// start's home folder).
pub fn begin(
    source: &StateSource,
    to: Destination<'_>,
    default_name: &str,
) -> Result<(ReadLog, Start, PathBuf), PipelineError> {
    let reads = ReadLog::start();
    let start = Start::load(source)?;
    let target = to.or(|| start.home.join(default_name));
    Ok((reads, start, target))
}
