//! `fos` as a library call: the factor of safety by strength reduction on the
//! built-in runner ([`crate::mpm::fos`]), with the pore pressures frozen, on
//! the same start `verify` judges ([`super::start`]: for a map folder, the
//! state Anura3D will hold). Writes `fos.json` (every trial, the materials
//! reduced and left alone), `fos_trials.svg` (largest displacement per trial
//! F) and, where a mechanism formed, `fos_mechanism.svg` (displacement
//! magnitude at the first F that did not settle) and `fos_mechanism.vtu` (the
//! same MPs with displacement, velocity and an `in_motion` flag).

use std::path::{Path, PathBuf};

use plotters::style::RGBColor;

use super::PipelineError;
use super::output::{Destination, OutputDir, ReadLog};
use super::plot::{self, Series};
use super::runner;
use super::start::{Start, StateSource};
use crate::formats::cps::CpsDocument;
use crate::formats::vtu;
use crate::model::{AnuraModel, MaterialPoint, MpState};
use crate::mpm::fos::{FosOutcome, FosReport, FosSettings, strength_reduction};

/// How `fos` runs.
#[derive(Clone, Debug, PartialEq)]
pub struct FosOptions {
    /// Local damping α of the trial runs (`None`: the CPS
    /// `$$HOMOGENEOUS_LOCAL_DAMPING`, else [`runner::DEFAULT_DAMPING`]).
    pub damping: Option<f64>,
    /// Half-width of the final bracket on F.
    pub tolerance: f64,
    /// Time window of one trial (s); `None`: max(20 T₀, 4 √(H/g)).
    pub window: Option<f64>,
    /// Every pore pressure set to zero (σ′ = σ) before the analysis.
    pub zero_pwp: bool,
}

impl Default for FosOptions {
    fn default() -> Self {
        FosOptions {
            damping: None,
            tolerance: 0.01,
            window: None,
            zero_pwp: false,
        }
    }
}

impl FosOptions {
    /// Strength-reduction settings from the CPS (gravity, Courant number,
    /// local damping) and these options.
    pub fn settings(&self, cps: Option<&CpsDocument>) -> FosSettings {
        let mut s = FosSettings::default();
        s.run = runner::with_cps(s.run, cps, self.damping);
        s.tolerance = self.tolerance;
        s.window = self.window;
        s
    }
}

/// The states with every pore pressure set to zero (σ′ = σ; weights kept).
pub fn without_pore_pressure(states: &[MpState]) -> Vec<MpState> {
    states.iter().map(|s| MpState { pwp: 0.0, ..*s }).collect()
}

/// The analysis of one set of states (writes nothing).
pub fn analyse(
    model: &AnuraModel,
    points: &[MaterialPoint],
    states: &[MpState],
    settings: &FosSettings,
) -> Result<FosReport, PipelineError> {
    use crate::mpm::fos::FosError;
    strength_reduction(model, points, states, settings).map_err(|e| match e {
        FosError::Mpm(e) => runner::runner_error(e),
        FosError::NothingToReduce => PipelineError::Model(e.to_string()),
        FosError::InvalidSettings(_) => PipelineError::Option(e.to_string()),
    })
}

/// The files [`write()`] leaves for `report`, in order.
pub fn file_names(report: &FosReport) -> Vec<&'static str> {
    let mut files = vec!["fos.json", "fos_trials.svg"];
    if report.mechanism.is_some() {
        files.extend(["fos_mechanism.svg", "fos_mechanism.vtu"]);
    }
    files
}

/// Writes the report's files into `dir`'s staging folder.
pub fn write(report: &FosReport, dir: &OutputDir<'_>) -> Result<(), PipelineError> {
    let json = serde_json::to_string_pretty(report)
        .map_err(|e| PipelineError::Output(format!("fos.json: {e}")))?;
    dir.write("fos.json", |w| w.write_all(json.as_bytes()))?;
    trials_plot(&dir.path("fos_trials.svg"), report)?;
    let Some(m) = &report.mechanism else {
        return Ok(());
    };
    let field: Vec<(f64, f64, f64)> = m
        .positions
        .iter()
        .zip(&m.displacements)
        .map(|(p, u)| (p[0], p[1], norm(u)))
        .collect();
    plot::field_map(
        &dir.path("fos_mechanism.svg"),
        &format!(
            "Failure mechanism: displacement at F = {:.3} (first F that does not settle), t = {:.2} s",
            m.factor, m.time
        ),
        "|u| (m)",
        &field,
    )?;
    let flags = |v: &[bool]| v.iter().map(|&b| f64::from(u8::from(b))).collect();
    let arrays = vec![
        vtu::PointArray {
            name: "displacement".into(),
            components: 3,
            values: m.displacements.iter().flat_map(|d| *d).collect(),
        },
        vtu::PointArray {
            name: "velocity".into(),
            components: 3,
            values: m.velocities.iter().flat_map(|v| *v).collect(),
        },
        vtu::PointArray {
            name: "in_motion".into(),
            components: 1,
            values: flags(&m.in_motion),
        },
        vtu::PointArray {
            name: "plastic".into(),
            components: 1,
            values: flags(&m.plastic),
        },
        vtu::PointArray {
            name: "effective_stress".into(),
            components: 9,
            values: m.stresses.iter().flat_map(vtu::tensor9).collect(),
        },
    ];
    dir.write("fos_mechanism.vtu", |w| {
        vtu::write_points(w, &m.positions, &arrays)
    })
}

fn norm(v: &[f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn trials_plot(path: &Path, report: &FosReport) -> Result<(), PipelineError> {
    let pick = |settled: bool| -> Vec<(f64, f64)> {
        report
            .trials
            .iter()
            .filter(|t| t.settled == settled)
            .map(|t| (t.factor, t.max_displacement.max(1e-12)))
            .collect()
    };
    plot::line_chart(
        path,
        "Strength reduction: largest MP displacement per trial",
        "strength reduction factor F (–)",
        "largest MP displacement (m)",
        &[
            Series {
                label: "settles",
                points: pick(true),
                color: RGBColor(44, 160, 44),
                markers: true,
            },
            Series {
                label: "does not settle",
                points: pick(false),
                color: RGBColor(214, 39, 40),
                markers: true,
            },
        ],
        true,
    )
}

/// One line: the factor with its bracket, or the bound reached.
pub fn factor_line(report: &FosReport) -> String {
    match (report.outcome, report.lower, report.upper) {
        (FosOutcome::Bracketed, Some(lo), Some(hi)) => format!(
            "FS = {:.2} ± {:.2} (settles at F = {lo:.4}, not at F = {hi:.4}; {} trials)",
            report.factor,
            0.5 * (hi - lo),
            report.iterations
        ),
        (FosOutcome::AboveRange, Some(lo), _) => format!(
            "FS > {lo} (still settles at the largest F tried; {} trials)",
            report.iterations
        ),
        _ => format!(
            "FS < {} (does not settle at the smallest F tried; {} trials)",
            report.factor, report.iterations
        ),
    }
}

/// Analyses `states` and writes the outputs into `out` (replaced under
/// `force`); returns the report and the folder written.
pub fn analyse_into(
    start: &Start,
    states: &[MpState],
    options: &FosOptions,
    out: &Path,
    force: bool,
    reads: &ReadLog,
) -> Result<(FosReport, PathBuf), PipelineError> {
    // The output is checked before the analysis: a refusal comes at once.
    let dir = OutputDir::create(out, force, reads)?;
    let settings = options.settings(start.project.cps.as_ref());
    let report = analyse(&start.project.model, &start.points, states, &settings)?;
    write(&report, &dir)?;
    Ok((report, dir.commit()?))
}

/// `fos`: loads the state `source` names (for a map folder, the state Anura3D
/// will hold, as `verify` judges it), finds the factor of safety and writes
/// the outputs into the destination (default `fos/` in the state's folder).
pub fn fos(
    source: &StateSource,
    options: &FosOptions,
    to: Destination<'_>,
) -> Result<(FosReport, PathBuf), PipelineError> {
    let (reads, start, target) = runner::begin(source, to, "fos")?;
    let states = if options.zero_pwp {
        without_pore_pressure(start.states())
    } else {
        start.states().to_vec()
    };
    analyse_into(&start, &states, options, &target, to.replace, &reads)
}

/// The demo's two analyses of one start: with every pore pressure set to
/// zero, and with the mapped pore pressures. Writes `fos_zero_pwp/` and
/// `fos_mapped/` under `target`; returns both reports with their folders.
pub fn zero_and_mapped(
    start: &Start,
    target: &Path,
    reads: &ReadLog,
) -> Result<[(FosReport, PathBuf); 2], PipelineError> {
    let options = FosOptions::default();
    let zero = analyse_into(
        start,
        &without_pore_pressure(start.states()),
        &options,
        &target.join("fos_zero_pwp"),
        true,
        reads,
    )?;
    let mapped = analyse_into(
        start,
        start.states(),
        &options,
        &target.join("fos_mapped"),
        true,
        reads,
    )?;
    Ok([zero, mapped])
}
