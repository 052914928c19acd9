//! Checking a mapped state on the built-in runner: `verify` (this file),
//! `run` ([`runout`]), the state they start from ([`start`]: the MAPF read
//! as the kernel reads it, [`anura3d`]; the folder's own judgement,
//! [`folder`]) and what the runner commands share ([`runner`]).
//!
//! `verify` as a library call: load the state a check starts from
//! ([`crate::pipeline::check::start`]), run the built-in explicit solver under gravity
//! ([`crate::mpm::verify`]) with settings from the project's CPS, name every
//! cause of a negative verdict separately, and write `verify.json`,
//! `start.csv`, `mps_start.vtu` and, after a run, `verify_history.svg` and
//! `mps_end.vtu`.

pub mod anura3d;
pub mod folder;
pub mod runner;
pub mod runout;
pub mod start;

use std::path::PathBuf;

use crate::formats::mps_table;
use crate::model::MpState;
use crate::mpm::{self, RunSettings};
use crate::pipeline::PipelineError;
use crate::pipeline::check::folder::KernelCheck;
use crate::pipeline::check::start::{Start, StateSource};
use crate::pipeline::io::output::{Destination, OutputDir};
use runner::{history_plot, write_snapshot};

/// How `verify` runs.
#[derive(Clone, Debug, PartialEq)]
pub struct VerifyOptions {
    /// Most explicit steps.
    pub max_steps: usize,
    /// Local damping α (`None`: the CPS `$$HOMOGENEOUS_LOCAL_DAMPING`, else
    /// [`runner::DEFAULT_DAMPING`]).
    pub damping: Option<f64>,
    /// Hold every pore pressure (the drained check; two-phase and undrained
    /// materials otherwise run coupled, [`crate::mpm::liquid`]).
    pub drained: bool,
}

impl Default for VerifyOptions {
    fn default() -> Self {
        VerifyOptions {
            max_steps: 20_000,
            damping: None,
            drained: false,
        }
    }
}

impl VerifyOptions {
    /// Refuses a damping outside [0, 1) and a step limit past
    /// [`mpm::MAX_RUN_STEPS`].
    pub fn check(&self) -> Result<(), PipelineError> {
        runner::check_damping(self.damping)?;
        if self.max_steps > mpm::MAX_RUN_STEPS {
            return Err(PipelineError::Option(format!(
                "{} steps: a run takes at most {}",
                self.max_steps,
                mpm::MAX_RUN_STEPS
            )));
        }
        Ok(())
    }

    /// The runner's settings for this project's CPS.
    pub fn settings(&self, cps: Option<&crate::formats::cps::CpsDocument>) -> RunSettings {
        let mut s = runner::with_cps(RunSettings::verify(), cps, self.damping);
        s.max_steps = self.max_steps;
        s.record_every = 10;
        s.frozen_pore_pressure = self.drained;
        s
    }
}

/// What `verify` found: every cause named separately, the Anura3D-side checks
/// and the runner's report.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VerifyOutcome {
    pub equilibrium: bool,
    pub causes: Vec<String>,
    pub anura3d: Option<KernelCheck>,
    /// `None` when the run could not start (NaN MPs, or a model the runner
    /// does not support).
    pub run: Option<mpm::RunReport>,
}

/// The causes behind a verdict, each on its own.
fn causes(check: Option<&KernelCheck>, run: Option<&mpm::RunReport>) -> Vec<String> {
    let mut out = Vec::new();
    if let Some(k) = check {
        if k.nan_points > 0 {
            out.push(format!(
                "{} MPs will hold NaN in Anura3D: no row of {} within 2h = {:.3e} m (first ids: {:?})",
                k.nan_points,
                k.mapf.display(),
                2.0 * k.smoothing_length,
                k.nan_ids
            ));
        }
        if let Some(d) = &k.sigma_zz_defect
            && d.outside_because_of_defect > 0
        {
            out.push(format!(
                "{} MPs start outside their yield surface only because Anura3D's 2D MAPF reader sets σ'zz := SigXY; its first step return-maps them, changing σ'xx, σ'yy, σ'zz, τxy by up to {:.3}, {:.3}, {:.3}, {:.3} kPa",
                d.outside_because_of_defect,
                d.first_step_change[0],
                d.first_step_change[1],
                d.first_step_change[2],
                d.first_step_change[3]
            ));
        }
        if k.intended_outside_yield > 0 {
            out.push(format!(
                "{} MPs are outside their yield surface in the intended state itself",
                k.intended_outside_yield
            ));
        }
    }
    if let Some(r) = run
        && let mpm::Verdict::NotInEquilibrium { reasons } = &r.verdict
    {
        for reason in reasons {
            if check.is_some() && matches!(reason, mpm::Reason::InadmissibleStress { .. }) {
                continue; // split into the two causes above
            }
            out.push(reason.to_string());
        }
    }
    out
}

/// Runs the equilibrium check on a loaded start (writes nothing).
pub fn check(start: &Start, options: &VerifyOptions) -> Result<VerifyOutcome, PipelineError> {
    options.check()?;
    let (settings, notes) =
        runner::with_project(options.settings(start.project.cps.as_ref()), &start.project)?;
    // A model the runner cannot simulate still gets its Anura3D-side checks
    // and start.csv; the verdict then says why no run was made.
    let mut run_error = None;
    let report = if start.runnable() {
        match mpm::verify(
            &start.project.model,
            &start.points,
            start.states(),
            &settings,
        ) {
            Ok(mut r) => {
                r.notes.splice(0..0, notes);
                Some(r)
            }
            Err(
                e
                @ (mpm::MpmError::Unsupported(_) | mpm::MpmError::UnsupportedMaterialModel { .. }),
            ) if start.kernel().is_some() => {
                run_error = Some(format!("no equilibrium run: {e}"));
                None
            }
            Err(e) => return Err(runner::runner_error(e)),
        }
    } else {
        None
    };
    let mut causes = causes(start.kernel(), report.as_ref());
    causes.extend(run_error);
    let equilibrium = report.as_ref().is_some_and(|r| r.verdict.is_equilibrium())
        && start.kernel().is_none_or(|k| k.nan_points == 0);
    Ok(VerifyOutcome {
        equilibrium,
        causes,
        anura3d: start.kernel().cloned(),
        run: report,
    })
}

/// The files `verify` writes, in order.
pub fn file_names(outcome: &VerifyOutcome) -> Vec<&'static str> {
    let mut files = vec!["verify.json", "start.csv", "mps_start.vtu"];
    if outcome.run.is_some() {
        files.extend(["verify_history.svg", "mps_end.vtu"]);
    }
    files
}

/// Writes the outcome's files into `out`'s staging folder.
pub fn write(
    outcome: &VerifyOutcome,
    start: &Start,
    out: &OutputDir<'_>,
) -> Result<(), PipelineError> {
    let json = serde_json::to_string_pretty(outcome)
        .map_err(|e| PipelineError::Output(format!("verify.json: {e}")))?;
    out.write("verify.json", |w| w.write_all(json.as_bytes()))?;
    // start.csv holds Anura3D's state at t = 0: the rows in reach are its
    // diagnostics; no Shepard ratio was computed, so that column stays empty.
    let diagnostics: Vec<mps_table::MpDiagnostics> = start
        .at_zero()
        .iter()
        .enumerate()
        .map(|(i, s)| mps_table::MpDiagnostics {
            neighbours: start.rows_in_reach().get(i).copied().unwrap_or(0),
            shepard: None,
            status: if s.pwp.is_finite() && s.total.iter().all(|v| v.is_finite()) {
                "anura3d"
            } else {
                "nan"
            },
        })
        .collect();
    out.write("start.csv", |w| {
        mps_table::write_states(w, &start.points, start.at_zero(), &diagnostics)
    })?;
    let positions: Vec<[f64; 3]> = start.points.iter().map(|p| p.position).collect();
    let at_zero = start.at_zero();
    let n = positions.len();
    let start_snapshot = mpm::Snapshot {
        step: 0,
        time: 0.0,
        displacements: vec![[0.0; 3]; n],
        stresses: at_zero.iter().map(MpState::effective).collect(),
        plastic: vec![false; n],
        pore_pressures: at_zero.iter().map(|s| s.pwp).collect(),
        saturations: at_zero.iter().map(|s| s.saturation).collect(),
        liquid_velocities: Vec::new(),
        positions,
    };
    write_snapshot(out, "mps_start.vtu", &start_snapshot)?;
    if let Some(report) = &outcome.run {
        history_plot(&out.path("verify_history.svg"), report)?;
        let end = mpm::Snapshot {
            step: report.steps,
            time: report.time,
            positions: start_snapshot
                .positions
                .iter()
                .zip(&report.final_displacements)
                .map(|(p, d)| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
                .collect(),
            displacements: report.final_displacements.clone(),
            stresses: report.final_stresses.clone(),
            plastic: report.final_plastic.clone(),
            pore_pressures: report.final_pore_pressures.clone(),
            saturations: Vec::new(),
            liquid_velocities: Vec::new(),
        };
        write_snapshot(out, "mps_end.vtu", &end)?;
    }
    Ok(())
}

/// `verify`: loads the state `source` names, checks it and writes the outputs
/// into the destination (default `verify/` in the state's folder; rerunning
/// replaces that default folder without being asked). Returns the outcome and
/// the folder written. A negative verdict is an outcome, not an error.
pub fn verify(
    source: &StateSource,
    options: &VerifyOptions,
    to: Destination<'_>,
) -> Result<(VerifyOutcome, PathBuf), PipelineError> {
    // Rerunning `verify DIR` replaces its own default subfolder.
    options.check()?;
    let own_folder = to.folder.is_none() && matches!(source, StateSource::Folder(_));
    let (reads, start, target) = runner::begin(source, to, "verify")?;
    let force = to.replace || (own_folder && target.join("verify.json").is_file());
    let dir = OutputDir::create(&target, force, &reads, "verify")?;
    let outcome = check(&start, options)?;
    write(&outcome, &start, &dir)?;
    Ok((outcome, dir.commit()?))
}
