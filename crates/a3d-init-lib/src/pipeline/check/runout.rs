//! `run` as a library call: the built-in explicit solver kept going for a given
//! time from the same start `verify` judges, with MP snapshots (a
//! demonstration of run-out, not a replacement for Anura3D). Writes
//! `run.json`, `run_history.svg` and one `mps_t<time>.vtu` per snapshot.

use std::path::{Path, PathBuf};

use crate::mpm::{self, RunSettings};
use crate::pipeline::PipelineError;
use crate::pipeline::check::runner::{self, history_plot, write_snapshot};
use crate::pipeline::check::start::StateSource;
use crate::pipeline::io::output::{Destination, OutputDir};

/// Local damping α of a run-out unless the caller gives one (the CPS's
/// damping is for reaching equilibrium, not for run-out): light, so that the
/// mass moves as it would.
pub const RUNOUT_DAMPING: f64 = 0.05;

/// How `run` runs.
#[derive(Clone, Debug, PartialEq)]
pub struct RunOptions {
    /// Simulated time (s), positive.
    pub time: f64,
    /// Snapshot times (s).
    pub snapshots: Vec<f64>,
    /// Local damping α (`None`: the CPS's `$$HOMOGENEOUS_LOCAL_DAMPING` as
    /// Anura3D applies it, 0 when it is switched off; [`RUNOUT_DAMPING`] when
    /// the CPS does not say).
    pub damping: Option<f64>,
    /// Hold every pore pressure (two-phase and undrained materials otherwise
    /// run coupled, [`crate::mpm::liquid`]).
    pub drained: bool,
}

impl RunOptions {
    /// The runner's settings for this project's CPS (gravity, Courant number).
    pub fn settings(
        &self,
        cps: Option<&crate::formats::cps::CpsDocument>,
    ) -> Result<RunSettings, PipelineError> {
        runner::check_damping(self.damping)?;
        if !(self.time.is_finite() && self.time > 0.0) {
            return Err(PipelineError::Option(format!(
                "simulated time {}: expected a positive number of seconds",
                self.time
            )));
        }
        if let Some(t) = self.snapshots.iter().find(|t| !t.is_finite() || **t < 0.0) {
            return Err(PipelineError::Option(format!(
                "snapshot time {t}: expected a number of seconds ≥ 0"
            )));
        }
        if self.snapshots.len() > MAX_SNAPSHOTS {
            return Err(PipelineError::Option(format!(
                "{} snapshot times: a run writes at most {MAX_SNAPSHOTS}",
                self.snapshots.len()
            )));
        }
        let mut sorted = self.snapshots.clone();
        sorted.sort_by(f64::total_cmp);
        if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
            return Err(PipelineError::Option(format!(
                "snapshot time {} is given twice",
                w[0]
            )));
        }

        let damping = self
            .damping
            .or_else(|| cps.and_then(|c| c.local_damping_setting()))
            .unwrap_or(RUNOUT_DAMPING);
        let mut s = runner::with_cps(RunSettings::verify(), cps, Some(damping));
        s.frozen_pore_pressure = self.drained;
        s.record_every = 10;
        s.end_time = Some(self.time);
        s.stop_at_equilibrium = false;
        s.max_steps = usize::MAX;
        s.snapshot_times = self.snapshots.clone();
        // The run-out follows the kernel's dynamics, its damping included.
        s.split_mixture_damping = true;
        Ok(s)
    }
}

/// What `run` wrote.
pub struct RunOutcome {
    pub report: mpm::RunReport,
    /// Snapshot files written, in time order (each `.vtu` with an `.svg` of
    /// the deformed body beside it).
    pub snapshots: Vec<String>,
    pub folder: PathBuf,
}

/// `run`: loads the state `source` names, runs it for `options.time` and
/// writes the outputs into the destination (default `run/` in the state's
/// folder).
pub fn run(
    source: &StateSource,
    options: &RunOptions,
    to: Destination<'_>,
) -> Result<RunOutcome, PipelineError> {
    let (reads, start, target) = runner::begin(source, to, "run")?;
    let (mut settings, notes) = runner::with_project(
        options.settings(start.project.cps.as_ref())?,
        &start.project,
    )?;
    settings.monitored = monitored(&start.project)?;
    let dir = OutputDir::create(&target, to.replace, &reads, "run")?;
    // Each snapshot is written as it is taken, under the name of the time
    // asked for: memory does not grow with their number.
    let names = snapshot_names(&settings.snapshot_times);
    let mut snapshots = Vec::new();
    let mut report = mpm::run_streaming(
        &start.project.model,
        &start.points,
        start.states(),
        &settings,
        &mut |asked, s| {
            let name = names
                .iter()
                .find(|(t, _)| *t == asked)
                .map_or_else(|| format!("mps_t{asked}.vtu"), |(_, n)| n.clone());
            write_snapshot(&dir, &name, &s).map_err(|e| e.to_string())?;
            let svg = name.replace(".vtu", ".svg");
            deformed_plot(&dir.path(&svg), asked, &s).map_err(|e| e.to_string())?;
            snapshots.push(name);
            Ok(())
        },
    )
    .map_err(runner::runner_error)?;
    report.notes.splice(0..0, notes);
    let late: Vec<String> = settings
        .snapshot_times
        .iter()
        .filter(|&&t| t > options.time)
        .map(|t| t.to_string())
        .collect();
    if !late.is_empty() {
        report.notes.push(format!(
            "snapshot times past the end of the run ({} s) are not taken: {} s",
            options.time,
            late.join(", ")
        ));
    }
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| PipelineError::Output(format!("run.json: {e}")))?;
    dir.write("run.json", |w| w.write_all(json.as_bytes()))?;
    history_plot(&dir.path("run_history.svg"), &report)?;
    Ok(RunOutcome {
        report,
        snapshots,
        folder: dir.commit()?,
    })
}

/// The 0-based MP indices of the CPS's monitored MPs
/// (`$$OUTPUT_MATERIAL_POINTS`, by MP id, checked against the MP count),
/// none without a CPS. An MP's id is Anura3D's running counter, its index
/// plus one (`place`), as `mpm::run` numbers them back.
fn monitored(project: &crate::pipeline::Project) -> Result<Vec<u32>, PipelineError> {
    let Some(cps) = project.cps.as_ref() else {
        return Ok(Vec::new());
    };
    let ids = cps.output_material_points(project.points.len())?;
    Ok(ids.into_iter().map(|id| id - 1).collect())
}

/// The deformed body at a snapshot: every MP at its position, coloured by
/// its displacement's magnitude.
fn deformed_plot(path: &Path, time: f64, s: &mpm::Snapshot) -> Result<(), PipelineError> {
    let dots: Vec<(f64, f64, f64)> = s
        .positions
        .iter()
        .zip(&s.displacements)
        .map(|(x, u)| (x[0], x[1], (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt()))
        .collect();
    crate::pipeline::io::plot::field_map(
        path,
        &format!("MPs at t = {time} s, coloured by displacement"),
        "|u| (m)",
        &dots,
    )
}

/// Most snapshot times one run takes.
pub const MAX_SNAPSHOTS: usize = 1000;

/// The file name of each snapshot time: `mps_t<time>.vtu` with two decimals
/// (`mps_t0.30.vtu`), or as many more as it takes for distinct times to get
/// distinct names (`mps_t0.001.vtu`, `mps_t0.002.vtu`); sorted by time.
pub fn snapshot_names(times: &[f64]) -> Vec<(f64, String)> {
    let mut sorted = times.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup();
    let distinct = |names: &[(f64, String)]| names.windows(2).all(|w| w[0].1 != w[1].1);
    for decimals in 2..=17 {
        let names: Vec<(f64, String)> = sorted
            .iter()
            .map(|&t| (t, format!("mps_t{t:.decimals$}.vtu")))
            .collect();
        if distinct(&names) {
            return names;
        }
    }
    // Rust's shortest round-trip form differs for every distinct number.
    sorted
        .iter()
        .map(|&t| (t, format!("mps_t{t}.vtu")))
        .collect()
}
