//! `--step failure`: the hand-off at the failure time as one step. FS(t) by
//! limit equilibrium over every saved step of a `.gsz` analysis or every
//! output of a `.pvd` series ([`crate::pipeline::stability::fos_time::fos_over_time`]), and the
//! first saved step whose factor is at most 1: the state `map` then maps.
//! The report names the time, the factor, the method and the bisected
//! crossing; a series that never fails is an error.

use crate::pipeline::PipelineError;
use crate::pipeline::fem::{FemOptions, FemReader, LoadedFem, reader_for};
use crate::pipeline::project::Project;
use crate::pipeline::stability::fos_time::{self, FosTimeOptions, SeriesInput};
use crate::pipeline::stability::slope::LeOptions;

/// The saved step `--step failure` chose, and why.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FailureStep {
    /// The series read (`.gsz` or `.pvd`).
    pub series: String,
    /// Saved steps in the series.
    pub saved_steps: usize,
    /// The chosen step's index in the series (0-based, time order).
    pub step: usize,
    /// Its time (s, and h).
    pub time: f64,
    pub time_h: f64,
    /// Its factor of safety (≤ 1).
    pub factor: f64,
    /// The method of slices.
    pub method: &'static str,
    /// The saved step before it: its time (s) and factor (> 1); `None` when
    /// the first saved step already fails.
    pub before: Option<(f64, f64)>,
    /// The time at which FS(t) reaches 1, bisected between the two saved
    /// steps (pore pressure linear in time between them), when bisected.
    pub crossing_time: Option<f64>,
    /// Limit equilibrium over the whole curve (s).
    pub runtime_s: f64,
}

/// The series `fem` names: one `.gsz` (every saved step of its analysis) or
/// one `.pvd`.
fn series_input(fem: &FemOptions) -> Result<SeriesInput, PipelineError> {
    let refuse = || {
        PipelineError::Option(
            "step `failure` needs one time series: a .gsz (every saved step of its analysis) or a .pvd"
                .into(),
        )
    };
    let [path] = fem.paths.as_slice() else {
        return Err(refuse());
    };
    match reader_for(path) {
        FemReader::Gsz => Ok(SeriesInput::Gsz {
            path: path.clone(),
            analysis: fem.analysis.clone(),
            csv: fem.csv.clone(),
        }),
        FemReader::Vtu
            if path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("pvd")) =>
        {
            Ok(SeriesInput::Pvd {
                path: path.clone(),
                vtu: fem.vtu.clone(),
            })
        }
        _ => Err(refuse()),
    }
}

/// FS(t) on `project` over the series `fem` names, by `le`, and the FEM
/// nodes of the first saved step with FS ≤ 1; an error when none fails.
pub fn failure_step(
    project: &Project,
    fem: &FemOptions,
    le: &LeOptions,
) -> Result<(LoadedFem, FailureStep), PipelineError> {
    let input = series_input(fem)?;
    let mut series = fos_time::load_series(&input)?;
    let curve = fos_time::fos_over_time(
        project,
        &series,
        &FosTimeOptions {
            le: le.clone(),
            srm: false,
            ..FosTimeOptions::default()
        },
    )?;
    let saved = curve.saved();
    let name = fem.paths[0].display().to_string();
    let Some(k) = curve.first_failing_output() else {
        let (t, f) = saved
            .iter()
            .copied()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((f64::NAN, f64::NAN));
        return Err(PipelineError::Input(format!(
            "{name}: no saved step fails: FS({}) stays above 1 over its {} steps (lowest {f:.3} at t = {t} s = {:.3} h); map a step by number, last or time=<time>",
            curve.method,
            saved.len(),
            t / 3600.0
        )));
    };
    let (time, factor) = saved[k];
    let step = FailureStep {
        series: name,
        saved_steps: saved.len(),
        step: k,
        time,
        time_h: time / 3600.0,
        factor,
        method: curve.method,
        before: k.checked_sub(1).map(|j| saved[j]),
        crossing_time: curve.crossing.as_ref().map(|c| c.time),
        runtime_s: curve.limit_equilibrium_runtime_s,
    };
    let nodes = series.swap_remove(k).1;
    Ok((nodes, step))
}

impl FailureStep {
    /// One sentence for the map report's notes.
    pub fn note(&self) -> String {
        let before = match self.before {
            Some((t, f)) => format!(", after FS = {f:.3} at t = {t} s"),
            None => ", the first saved step".into(),
        };
        let crossing = self
            .crossing_time
            .map(|t| {
                format!(
                    "; FS(t) reaches 1 at t = {t:.1} s ({:.4} h), bisected",
                    t / 3600.0
                )
            })
            .unwrap_or_default();
        format!(
            "step failure: {} saved step {} of {} at t = {} s ({:.4} h), FS = {:.3} by {} (the first with FS ≤ 1{before}){crossing}; FS(t) in {:.1} s",
            self.series,
            self.step,
            self.saved_steps,
            self.time,
            self.time_h,
            self.factor,
            self.method,
            self.runtime_s
        )
    }
}
