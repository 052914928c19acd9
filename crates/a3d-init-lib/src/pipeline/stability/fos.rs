//! `fos` as a library call: the factor of safety of the state `verify` judges
//! ([`crate::pipeline::check::start`]: for a map folder, the state Anura3D will hold), by limit
//! equilibrium ([`crate::pipeline::stability::slope`], the default: Morgenstern–Price, the seed
//! paper's method) or by strength reduction on the built-in runner
//! ([`crate::mpm::fos`], `FosMethod::Srm`), pore pressures frozen. Where both
//! run (strength reduction always runs the default limit equilibrium beside
//! it; a limit-equilibrium method runs strength reduction when asked) the
//! report compares them, with the limit-equilibrium factor on Davis-reduced
//! strengths for the non-associated flow rule.
//!
//! Writes `fos.json` (the method's report at the top level, `factor` and
//! `method` first; the other analysis under `limit_equilibrium` or
//! `strength_reduction`; the comparison), for limit equilibrium
//! `fos_surface.svg` (the critical surface over the pore pressure), for
//! strength reduction `fos_trials.svg` (largest displacement per trial F)
//! and, where a mechanism formed, `fos_mechanism.svg` and
//! `fos_mechanism.vtu`.

use std::path::{Path, PathBuf};

use plotters::style::RGBColor;

use crate::formats::cps::CpsDocument;
use crate::formats::vtu;
use crate::model::{AnuraModel, MaterialPoint, MpState};
use crate::mpm::fos::{FosOutcome, FosReport, FosSettings, strength_reduction};
use crate::pipeline::PipelineError;
use crate::pipeline::check::runner;
use crate::pipeline::check::start::{Start, StateSource};
use crate::pipeline::io::output::{Destination, OutputDir, ReadLog};
use crate::pipeline::io::plot::{self, Series};
use crate::pipeline::stability::slope::{LeOptions, LeReport};
use crate::slope::{Interslice, Method};

/// Which factor of safety.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum FosMethod {
    /// Limit equilibrium by a method of slices.
    Le(Method),
    /// Strength reduction on the built-in runner.
    Srm,
}

impl FosMethod {
    pub fn name(self) -> &'static str {
        match self {
            FosMethod::Le(m) => m.name(),
            FosMethod::Srm => "srm",
        }
    }
}

/// How `fos` runs.
#[derive(Clone, Debug, PartialEq)]
pub struct FosOptions {
    pub method: FosMethod,
    /// Limit equilibrium (its `method` is replaced by [`FosOptions::method`]
    /// when that is a method of slices).
    pub le: LeOptions,
    /// With a method of slices, run strength reduction too and compare.
    pub with_srm: bool,
    /// Strength reduction: local damping α of the trial runs (`None`: the
    /// CPS `$$HOMOGENEOUS_LOCAL_DAMPING`, else [`runner::DEFAULT_DAMPING`]).
    pub damping: Option<f64>,
    /// Strength reduction: half-width of the final bracket on F.
    pub tolerance: f64,
    /// Strength reduction: time window of one trial (s); `None`: the
    /// runner's default.
    pub window: Option<f64>,
    /// Every pore pressure set to zero (σ′ = σ) before the analysis.
    pub zero_pwp: bool,
    /// Strength reduction: hold every pore pressure, as limit equilibrium
    /// does (the default). Off, two-phase coupled and undrained
    /// materials run with their water; with `zero_pwp` they are held anyway
    /// (a dry slope has no water to run).
    pub drained: bool,
}

impl Default for FosOptions {
    fn default() -> Self {
        FosOptions {
            method: FosMethod::Le(Method::MorgensternPrice(Interslice::HalfSine)),
            le: LeOptions::default(),
            with_srm: false,
            damping: None,
            tolerance: 0.01,
            window: None,
            zero_pwp: false,
            drained: true,
        }
    }
}

impl FosOptions {
    /// Strength reduction as `verify --fos` runs it: these options with the
    /// method `srm`.
    pub fn srm() -> FosOptions {
        FosOptions {
            method: FosMethod::Srm,
            ..FosOptions::default()
        }
    }

    /// Strength-reduction settings from the CPS (gravity, Courant number,
    /// local damping) and these options.
    pub fn settings(&self, cps: Option<&CpsDocument>) -> FosSettings {
        let mut s = FosSettings::default();
        s.run = runner::with_cps(s.run, cps, self.damping);
        // Zero pore pressure is a dry slope: no water to run.
        s.run.frozen_pore_pressure = self.drained || self.zero_pwp;
        s.tolerance = self.tolerance;
        s.window = self.window;
        s
    }

    /// The limit-equilibrium options with the method asked (the default
    /// method beside strength reduction).
    fn le_options(&self) -> LeOptions {
        let mut le = self.le.clone();
        if let FosMethod::Le(m) = self.method {
            le.method = m;
        }
        le
    }
}

/// Strength reduction beside limit equilibrium on the same state.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Comparison {
    pub limit_equilibrium_method: &'static str,
    pub limit_equilibrium: f64,
    pub strength_reduction: f64,
    /// SRM over LE.
    pub ratio: f64,
    /// The limit-equilibrium factor on Davis-reduced strengths (on the
    /// critical surface): what a continuum with the materials' dilatancy
    /// should give; `None` when it could not be computed.
    pub limit_equilibrium_davis: Option<f64>,
    /// The largest strength factor at which the implicit equilibrium solve
    /// still finds rest with the same pore pressures held; `None`
    /// where the solve does not take the model.
    pub equilibrium_solve: Option<crate::pipeline::map::equilibrium::StrengthFactor>,
    /// Why there is no `equilibrium_solve`.
    pub equilibrium_solve_skipped: Option<String>,
    pub note: String,
}

/// What `fos` found.
#[derive(Clone, Debug, PartialEq)]
pub struct FosAnalysis {
    pub method: FosMethod,
    /// The factor of the method asked.
    pub factor: f64,
    pub limit_equilibrium: Option<LeReport>,
    pub strength_reduction: Option<FosReport>,
    pub comparison: Option<Comparison>,
    /// Why limit equilibrium did not run beside strength reduction.
    pub limit_equilibrium_skipped: Option<String>,
    pub n_points: usize,
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

/// The files [`write()`] leaves for `analysis`, in order.
pub fn file_names(analysis: &FosAnalysis) -> Vec<&'static str> {
    let mut files = vec!["fos.json"];
    if analysis.limit_equilibrium.is_some() {
        files.push("fos_surface.svg");
    }
    if let Some(report) = &analysis.strength_reduction {
        files.push("fos_trials.svg");
        if report.mechanism.is_some() {
            files.extend(["fos_mechanism.svg", "fos_mechanism.vtu"]);
        }
    }
    files
}

/// `fos.json`: the asked method's report at the top level with `method`,
/// the other analysis and the comparison beside it.
pub fn json(analysis: &FosAnalysis) -> Result<serde_json::Value, PipelineError> {
    let value = |v: Result<serde_json::Value, serde_json::Error>| {
        v.map_err(|e| PipelineError::Output(format!("fos.json: {e}")))
    };
    let le = analysis
        .limit_equilibrium
        .as_ref()
        .map(|r| value(serde_json::to_value(r)))
        .transpose()?;
    let srm = analysis
        .strength_reduction
        .as_ref()
        .map(|r| value(serde_json::to_value(r)))
        .transpose()?;
    let (main, other_key, other) = match analysis.method {
        FosMethod::Srm => (srm, "limit_equilibrium", le),
        FosMethod::Le(_) => (le, "strength_reduction", srm),
    };
    let mut object = serde_json::Map::new();
    object.insert("factor".into(), analysis.factor.into());
    object.insert("method".into(), analysis.method.name().into());
    if let Some(serde_json::Value::Object(m)) = main {
        for (k, v) in m {
            object.entry(k).or_insert(v);
        }
    }
    if let Some(o) = other {
        object.insert(other_key.into(), o);
    }
    if let Some(c) = &analysis.comparison {
        object.insert("comparison".into(), value(serde_json::to_value(c))?);
    }
    if let Some(why) = &analysis.limit_equilibrium_skipped {
        object.insert("limit_equilibrium_skipped".into(), why.clone().into());
    }
    Ok(serde_json::Value::Object(object))
}

/// Writes the analysis' files into `dir`'s staging folder; `field` is the
/// pore pressure per MP (x, y, pwp) for the surface plot.
pub fn write(
    analysis: &FosAnalysis,
    field: &[(f64, f64, f64)],
    ground: &[[f64; 2]],
    dir: &OutputDir<'_>,
) -> Result<(), PipelineError> {
    let text = serde_json::to_string_pretty(&json(analysis)?)
        .map_err(|e| PipelineError::Output(format!("fos.json: {e}")))?;
    dir.write("fos.json", |w| w.write_all(text.as_bytes()))?;
    if let Some(le) = &analysis.limit_equilibrium {
        crate::pipeline::stability::slope::write_surface_plot(
            &dir.path("fos_surface.svg"),
            &format!(
                "Critical slip surface: {} FS = {:.3} ({})",
                le.method, le.factor, le.surface_kind
            ),
            le,
            field,
            ground,
        )?;
    }
    match &analysis.strength_reduction {
        Some(report) => write_srm(report, dir),
        None => Ok(()),
    }
}

fn write_srm(report: &FosReport, dir: &OutputDir<'_>) -> Result<(), PipelineError> {
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

/// One line: the strength-reduction factor with its bracket, or the bound
/// reached.
pub fn srm_factor_line(report: &FosReport) -> String {
    match (report.outcome, report.lower, report.upper) {
        (FosOutcome::Bracketed, Some(lo), Some(hi)) => format!(
            "FS = {:.3} (interpolated between F = {lo:.4}, which settles, and F = {hi:.4}, which does not; {} trials)",
            report.factor, report.iterations
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

/// One line: a limit-equilibrium factor with its method and surface.
pub fn le_factor_line(report: &LeReport) -> String {
    let both = match (report.force_factor, report.moment_factor, report.lambda) {
        (Some(ff), Some(fm), Some(l)) => format!(", F_f = {ff:.4}, F_m = {fm:.4} at λ = {l:.4}"),
        _ => String::new(),
    };
    format!(
        "FS = {:.3} ({}, {} surface{both}; best circle {:.3})",
        report.factor, report.method, report.surface_kind, report.analysis.circular.factor
    )
}

/// One line for the method asked.
pub fn factor_line(analysis: &FosAnalysis) -> String {
    match (
        &analysis.method,
        &analysis.limit_equilibrium,
        &analysis.strength_reduction,
    ) {
        (FosMethod::Srm, _, Some(r)) => srm_factor_line(r),
        (FosMethod::Le(_), Some(r), _) => le_factor_line(r),
        _ => format!("FS = {}", analysis.factor),
    }
}

/// The analyses `options` asks for on `states` (writes nothing).
pub fn analyse_state(
    start: &Start,
    states: &[MpState],
    options: &FosOptions,
) -> Result<FosAnalysis, PipelineError> {
    runner::check_damping(options.damping)?;
    let project = &start.project;
    let gravity = project.gravity();
    let le_options = options.le_options();
    let run_srm = options.method == FosMethod::Srm || options.with_srm;
    let le = crate::pipeline::stability::slope::analyse_state(
        &project.model,
        gravity,
        &start.points,
        states,
        &le_options,
    );
    let (limit_equilibrium, skipped) = match (le, options.method) {
        (Ok(r), _) => (Some(r), None),
        // Beside strength reduction, limit equilibrium is a comparison only.
        (Err(e), FosMethod::Srm) => (None, Some(e.to_string())),
        (Err(e), FosMethod::Le(_)) => return Err(e),
    };
    let strength_reduction = if run_srm {
        let mut settings = options.settings(project.cps.as_ref());
        settings.run = runner::with_project(settings.run, project)?.0;
        // A factor of safety is of the slope under its full weight, whatever
        // gravity ramp the CPS runs Anura3D with.
        settings.run.loads.gravity = crate::model::loads::Multiplier::FULL;
        Some(analyse(&project.model, &start.points, states, &settings)?)
    } else {
        None
    };
    let comparison = match (&limit_equilibrium, &strength_reduction) {
        (Some(le), Some(srm)) => Some(compare(start, states, gravity, &le_options, le, srm)),
        _ => None,
    };
    let factor = match options.method {
        FosMethod::Srm => strength_reduction.as_ref().map_or(f64::NAN, |r| r.factor),
        FosMethod::Le(_) => limit_equilibrium.as_ref().map_or(f64::NAN, |r| r.factor),
    };
    Ok(FosAnalysis {
        method: options.method,
        factor,
        limit_equilibrium,
        strength_reduction,
        comparison,
        limit_equilibrium_skipped: skipped,
        n_points: start.points.len(),
    })
}

fn compare(
    start: &Start,
    states: &[MpState],
    gravity: f64,
    options: &LeOptions,
    le: &LeReport,
    srm: &FosReport,
) -> Comparison {
    let davis = crate::pipeline::stability::slope::davis_factor(
        &start.project.model,
        gravity,
        &start.points,
        states,
        options,
        &le.critical_surface,
        le.analysis.critical.axis,
    )
    .ok();
    let project = &start.project;
    let (equilibrium_solve, equilibrium_solve_skipped) =
        match crate::pipeline::map::equilibrium::unsupported(project) {
            Some(why) => (None, Some(why)),
            None => match crate::pipeline::map::equilibrium::strength_factor(
                project,
                states,
                &crate::pipeline::map::equilibrium::EquilibriumOptions::default(),
            ) {
                Ok(f) => (Some(f), None),
                Err(e) => (None, Some(e.to_string())),
            },
        };
    Comparison {
        limit_equilibrium_method: le.method,
        limit_equilibrium: le.factor,
        strength_reduction: srm.factor,
        ratio: srm.factor / le.factor,
        limit_equilibrium_davis: davis,
        equilibrium_solve,
        equilibrium_solve_skipped,
        note: "Strength reduction divides tan φ′ and c′ by F and keeps ψ_F = min(ψ, φ′_F); \
               with ψ < φ′ the continuum fails before limit equilibrium says (Davis 1968): \
               limit equilibrium on the strengths c* = β·c′_F, tan φ* = β·tan φ′_F, \
               β = cos ψ_F cos φ′_F/(1 − sin ψ_F sin φ′_F), on the critical surface, \
               reaches 1 at the factor given as limit_equilibrium_davis"
            .into(),
    }
}

/// Analyses `states` and writes the outputs into `out` (replaced under
/// `force`); returns the analysis and the folder written.
pub fn analyse_into(
    start: &Start,
    states: &[MpState],
    options: &FosOptions,
    out: &Path,
    force: bool,
    reads: &ReadLog,
) -> Result<(FosAnalysis, PathBuf), PipelineError> {
    // The output is checked before the analysis: a refusal comes at once.
    let dir = OutputDir::create(out, force, reads, "fos")?;
    let analysis = analyse_state(start, states, options)?;
    let field: Vec<(f64, f64, f64)> = start
        .points
        .iter()
        .zip(states)
        .map(|(p, s)| (p.position[0], p.position[1], s.pwp))
        .collect();
    let ground = analysis
        .limit_equilibrium
        .as_ref()
        .map(|r| r.ground.clone())
        .unwrap_or_default();
    write(&analysis, &field, &ground, &dir)?;
    Ok((analysis, dir.commit()?))
}

/// `fos`: loads the state `source` names (for a map folder, the state Anura3D
/// will hold, as `verify` judges it), finds the factor of safety and writes
/// the outputs into the destination (default `fos/` in the state's folder).
pub fn fos(
    source: &StateSource,
    options: &FosOptions,
    to: Destination<'_>,
) -> Result<(FosAnalysis, PathBuf), PipelineError> {
    let (reads, start, target) = runner::begin(source, to, "fos")?;
    let states = if options.zero_pwp {
        without_pore_pressure(start.states())
    } else {
        start.states().to_vec()
    };
    analyse_into(&start, &states, options, &target, to.replace, &reads)
}

/// The demo's two analyses of one start (limit equilibrium, Morgenstern–
/// Price): with every pore pressure set to zero, and with the mapped pore
/// pressures. Writes `fos_zero_pwp/` and `fos_mapped/` under `target`;
/// returns both with their folders.
pub fn zero_and_mapped(
    start: &Start,
    target: &Path,
    reads: &ReadLog,
) -> Result<[(FosAnalysis, PathBuf); 2], PipelineError> {
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
