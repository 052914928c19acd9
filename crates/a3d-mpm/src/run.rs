//! Drives a [`Simulation`] to a stop, records its history and judges the result:
//! [`verify`] and [`run`], the [`RunReport`] and its [`Verdict`].
//!
//! Verdict rules (all must hold for [`Verdict::Equilibrium`]; each failure is
//! one [`Reason`]):
//!
//! * the out-of-balance force ratio of the mapped state itself (first step,
//!   before anything moved) is below [`Thresholds::residual_ratio`] — the most
//!   direct measure of equilibrium;
//! * the ratio at the last step is below it too — the run has settled, so the
//!   displacement below is the one needed to reach equilibrium;
//! * the largest MP displacement is below
//!   [`Thresholds::displacement_fraction`] × model height (y-extent of the
//!   active elements);
//! * at most [`Thresholds::plastic_fraction`] of the MPs start outside the yield
//!   surface, and at most that fraction yield during the run (no plastic zone
//!   grows);
//! * no MP left the mesh.
//!
//! This file does no I/O; the report is plain data with `serde::Serialize`.

use super::simulation::Simulation;
use super::{MpmError, RunSettings, Thresholds};
use a3d_model::{AnuraModel, Dimension, MaterialPoint, MpState};

/// One recorded step.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct StepRecord {
    pub step: usize,
    /// Time at the end of the step (s).
    pub time: f64,
    /// MP kinetic energy at the end of the step (kJ; kJ/m in plane strain,
    /// kJ/rad in 2D axisymmetry).
    pub kinetic_energy: f64,
    /// ‖f_ext + f_int‖/‖f_ext‖ over free DOFs, measured in this step (on the
    /// state at its start).
    pub residual_ratio: f64,
    /// Largest and mean MP displacement magnitude (m).
    pub max_displacement: f64,
    pub mean_displacement: f64,
    /// MPs that yielded in this step, and in any step so far.
    pub plastic_now: usize,
    pub plastic_total: usize,
}

/// Why the run stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum StopReason {
    /// The residual stayed below the threshold for one estimated period.
    Settled,
    EndTime,
    MaxSteps,
}

/// One failed verdict condition.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "kind")]
pub enum Reason {
    /// The mapped state is out of balance at the first step.
    InitialResidual { ratio: f64, limit: f64 },
    /// The run had not settled at its last step.
    FinalResidual { ratio: f64, limit: f64 },
    /// MPs moved too far to find equilibrium.
    Displacement { max: f64, limit: f64 },
    /// Too many MPs start outside the yield surface.
    InadmissibleStress { count: usize, limit: usize },
    /// Too many MPs yielded during the run.
    PlasticGrowth { count: usize, limit: usize },
    /// MPs left the mesh.
    LostPoints { count: usize },
}

impl std::fmt::Display for Reason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Reason::InitialResidual { ratio, limit } => write!(
                f,
                "the mapped state is out of balance: force ratio {ratio:.3e} > {limit:.1e}"
            ),
            Reason::FinalResidual { ratio, limit } => write!(
                f,
                "the run did not settle: final force ratio {ratio:.3e} > {limit:.1e}"
            ),
            Reason::Displacement { max, limit } => {
                write!(f, "material points moved up to {max:.3e} m > {limit:.3e} m")
            }
            Reason::InadmissibleStress { count, limit } => write!(
                f,
                "{count} material points start outside the yield surface (limit {limit})"
            ),
            Reason::PlasticGrowth { count, limit } => write!(
                f,
                "{count} material points yielded during the run (limit {limit})"
            ),
            Reason::LostPoints { count } => write!(f, "{count} material points left the mesh"),
        }
    }
}

/// The equilibrium verdict.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "verdict")]
pub enum Verdict {
    Equilibrium {
        initial_residual_ratio: f64,
        final_residual_ratio: f64,
        max_displacement: f64,
        plastic_points: usize,
    },
    NotInEquilibrium {
        reasons: Vec<Reason>,
    },
}

impl Verdict {
    pub fn is_equilibrium(&self) -> bool {
        matches!(self, Verdict::Equilibrium { .. })
    }
}

/// An element singled out in the report.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ElementScore {
    /// 1-based element id.
    pub id: u64,
    pub centroid: [f64; 3],
    /// Residual: Σ over the corners of |f_ext + f_int| at the free
    /// directions at the first step (kN; kN/m in plane strain, kN/rad in 2D
    /// axisymmetry). Plastic: number of MPs in the element that yielded
    /// during the run.
    pub value: f64,
}

/// MP results at one moment.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Snapshot {
    pub step: usize,
    pub time: f64,
    pub positions: Vec<[f64; 3]>,
    pub displacements: Vec<[f64; 3]>,
    /// Effective stress σ′ (xx, yy, zz, xy, yz, xz; kPa).
    pub stresses: Vec<[f64; 6]>,
    /// Has yielded: accumulated plastic strain above 1e-6 (`particle::PLASTIC_STRAIN_FLOOR`).
    pub plastic: Vec<bool>,
    /// Pore pressure (kPa, Anura3D's sign: negative in compression).
    pub pore_pressures: Vec<f64>,
    /// Degree of saturation (empty where not known).
    pub saturations: Vec<f64>,
    /// Liquid velocity (m/s; zero where the water does not flow; empty where
    /// not known).
    pub liquid_velocities: Vec<[f64; 3]>,
}

/// A monitored MP's displacement over time (CPS `$$OUTPUT_MATERIAL_POINTS`,
/// the MPs whose history Anura3D writes to `<project>.PAR_<id>`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MonitoredPoint {
    /// 1-based MP id.
    pub id: u32,
    /// Position at the start (m).
    pub start: [f64; 3],
    /// (time in s, displacement in m) at every recorded step.
    pub history: Vec<(f64, [f64; 3])>,
}

/// Fraction of its peak below which the kinetic energy must stay for a
/// run to be at rest ([`Rest`]).
pub const REST_FRACTION: f64 = 0.01;

/// When a run came to rest: the first recorded time after the kinetic
/// energy's peak from which the kinetic energy stays below
/// [`REST_FRACTION`] of that peak to the end of the run.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Rest {
    /// Time to rest (s).
    pub time: f64,
    /// Time (s) and value (kJ; kJ/m in plane strain) of the peak.
    pub peak_time: f64,
    pub peak_kinetic_energy: f64,
    pub criterion: String,
}

impl Rest {
    /// The rest of a history, `None` when it never moved (a zero peak) or
    /// had not come to rest by its last record.
    pub fn find(records: &[StepRecord]) -> Option<Rest> {
        let (peak_at, peak) = records
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.kinetic_energy.total_cmp(&b.1.kinetic_energy))?;
        if peak.kinetic_energy.is_nan() || peak.kinetic_energy <= 0.0 {
            return None;
        }
        let limit = REST_FRACTION * peak.kinetic_energy;
        let calm_from = records
            .iter()
            .rposition(|r| r.kinetic_energy.is_nan() || r.kinetic_energy >= limit)
            .map_or(0, |k| k + 1);
        let rest = records.get(calm_from.max(peak_at + 1))?;
        Some(Rest {
            time: rest.time,
            peak_time: peak.time,
            peak_kinetic_energy: peak.kinetic_energy,
            criterion: format!(
                "the kinetic energy stays below {:.0} % of its peak ({:.3e} kJ at {:.3} s) from this time to the end of the run",
                100.0 * REST_FRACTION,
                peak.kinetic_energy,
                peak.time
            ),
        })
    }
}

/// Everything a run measured, with the verdict.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RunReport {
    pub dimension: Dimension,
    pub n_points: usize,
    pub n_elements: usize,
    pub time_step: f64,
    /// Largest P-wave speed over the MPs (m/s).
    pub wave_speed: f64,
    /// Smallest element altitude (m).
    pub min_element_size: f64,
    /// y-extent of the active elements (m).
    pub model_height: f64,
    pub gravity: f64,
    pub damping: f64,
    pub courant: f64,
    pub steps: usize,
    pub time: f64,
    pub stop: StopReason,
    pub thresholds: Thresholds,
    pub records: Vec<StepRecord>,
    pub initial_residual_ratio: f64,
    pub final_residual_ratio: f64,
    pub max_displacement: f64,
    /// MPs whose initial effective stress is outside the yield surface.
    pub inadmissible_points: usize,
    /// MPs that yielded during the run, excluding the inadmissible ones.
    pub plastic_points: usize,
    pub lost_points: usize,
    pub verdict: Verdict,
    /// Up to 10 elements with the largest residual at the first step.
    pub worst_residual_elements: Vec<ElementScore>,
    /// Up to 10 elements with the most MPs that yielded.
    pub plastic_elements: Vec<ElementScore>,
    /// Final MP displacements (m; z = 0 in 2D), in MP order.
    pub final_displacements: Vec<[f64; 3]>,
    /// Final effective stresses σ′ (kPa), in MP order.
    pub final_stresses: Vec<[f64; 6]>,
    /// Per MP: has yielded (accumulated plastic strain above 1e-6).
    pub final_plastic: Vec<bool>,
    /// Final pore pressures (kPa, Anura3D's sign), in MP order: the initial
    /// ones where they are frozen.
    pub final_pore_pressures: Vec<f64>,
    /// The monitored MPs' displacements over time ([`RunSettings::monitored`]).
    pub monitored: Vec<MonitoredPoint>,
    /// When the run came to rest ([`Rest::find`]), if it did.
    pub rest: Option<Rest>,
    /// How each material with MPs ran ([`super::liquid`]): (1-based
    /// material index, formulation).
    pub formulations: Vec<(u32, super::Formulation)>,
    /// The GOM's material names, in its order (material k is entry k − 1).
    pub material_names: Vec<String>,
    /// The seepage face and infiltration the run applied ([`super::seepage`]).
    pub hydraulic: super::seepage::HydraulicBoundaries,
    /// What the project asks for that the run did not apply.
    pub notes: Vec<String>,
}

/// The report of [`run`] with the snapshots taken on the way.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RunOutput {
    pub report: RunReport,
    pub snapshots: Vec<Snapshot>,
}

/// Checks whether the state is in equilibrium: a damped run (settings from
/// [`RunSettings::verify`] or the CPS) until it settles or hits its limits.
pub fn verify(
    model: &AnuraModel,
    points: &[MaterialPoint],
    states: &[MpState],
    settings: &RunSettings,
) -> Result<RunReport, MpmError> {
    let mut settings = settings.clone();
    settings.snapshot_times.clear();
    Ok(run(model, points, states, &settings)?.report)
}

/// Runs the solver with `settings` and returns the report and the snapshots
/// requested in [`RunSettings::snapshot_times`].
pub fn run(
    model: &AnuraModel,
    points: &[MaterialPoint],
    states: &[MpState],
    settings: &RunSettings,
) -> Result<RunOutput, MpmError> {
    let mut snapshots = Vec::new();
    let report = run_streaming(model, points, states, settings, &mut |_, s| {
        snapshots.push(s);
        Ok(())
    })?;
    Ok(RunOutput { report, snapshots })
}

/// Most steps a run with an end time may take (10⁷): a duration that needs
/// more at the model's time step is refused before the first step, naming
/// the count ([`MpmError::TooManySteps`]).
pub const MAX_RUN_STEPS: usize = 10_000_000;

/// [`run`], handing each snapshot to `sink` as it is taken (with the time it
/// was asked for, in [`RunSettings::snapshot_times`]) instead of keeping it:
/// memory does not grow with the number of snapshots. An error from `sink`
/// ends the run ([`MpmError::Snapshot`]).
pub fn run_streaming(
    model: &AnuraModel,
    points: &[MaterialPoint],
    states: &[MpState],
    settings: &RunSettings,
    sink: &mut dyn FnMut(f64, Snapshot) -> Result<(), String>,
) -> Result<RunReport, MpmError> {
    let mut simulation = Simulation::new(model, points, states, settings)?;
    drive(&mut simulation, model, settings, sink)
}

fn drive(
    simulation: &mut Simulation,
    model: &AnuraModel,
    settings: &RunSettings,
    sink: &mut dyn FnMut(f64, Snapshot) -> Result<(), String>,
) -> Result<RunReport, MpmError> {
    let height = model_height(model);
    let dt = simulation.time_step();
    if let Some(end) = settings.end_time {
        let steps = (end / dt).ceil();
        if steps.is_nan() || steps > MAX_RUN_STEPS as f64 {
            return Err(MpmError::TooManySteps {
                time: end,
                dt,
                steps,
                limit: MAX_RUN_STEPS,
            });
        }
    }
    let period = 4.0 * height / simulation.wave_speed();
    let min_time = settings.min_time.unwrap_or(2.0 * period);
    let window = ((period / dt).ceil() as usize).max(1);
    let tolerance = settings.thresholds.residual_ratio;

    let mut snapshot_times = settings.snapshot_times.clone();
    snapshot_times.sort_by(f64::total_cmp);
    let mut next_snapshot = 0;

    let mut records = Vec::new();
    let mut monitored = monitored_points(&settings.monitored, &simulation.positions())?;
    let mut record_monitored = |simulation: &Simulation| {
        if monitored.is_empty() {
            return;
        }
        let u = simulation.displacements();
        for m in &mut monitored {
            m.history.push((simulation.time(), u[m.id as usize - 1]));
        }
    };
    let mut calm_steps = 0usize;
    let mut initial_residual = 0.0;
    let mut worst_residual_elements = Vec::new();
    let mut last = None;
    let stop = loop {
        if simulation.steps() >= settings.max_steps {
            break StopReason::MaxSteps;
        }
        if settings
            .end_time
            .is_some_and(|t| simulation.time() >= t - 1e-9 * dt)
        {
            break StopReason::EndTime;
        }
        let outcome = simulation.step();
        let step = simulation.steps();
        if outcome.residual_ratio.is_nan() || !outcome.kinetic_energy.is_finite() {
            return Err(MpmError::Unstable { step });
        }
        if step == 1 {
            initial_residual = outcome.residual_ratio;
            worst_residual_elements = residual_elements(simulation, model);
        }
        calm_steps = if outcome.residual_ratio < tolerance {
            calm_steps + 1
        } else {
            0
        };
        let record = make_record(simulation, &outcome);
        if step == 1 || step.is_multiple_of(settings.record_every) {
            records.push(record);
            record_monitored(simulation);
        }
        last = Some(record);
        while next_snapshot < snapshot_times.len()
            && simulation.time() >= snapshot_times[next_snapshot] - 1e-9 * dt
        {
            sink(snapshot_times[next_snapshot], snapshot(simulation))
                .map_err(MpmError::Snapshot)?;
            next_snapshot += 1;
        }
        if settings.stop_at_equilibrium && simulation.time() >= min_time && calm_steps >= window {
            break StopReason::Settled;
        }
    };
    if let Some(record) = last
        && records.last().is_none_or(|r| r.step != record.step)
    {
        records.push(record);
        record_monitored(simulation);
    }
    let final_residual = last.map_or(0.0, |r| r.residual_ratio);
    let judged = judge(
        simulation,
        settings,
        height,
        initial_residual,
        final_residual,
    );
    let Judged {
        verdict,
        max_displacement,
        inadmissible,
        plastic_points,
        lost,
        n_points,
    } = judged;
    let thresholds = settings.thresholds.clone();
    let rest = Rest::find(&records);
    let report = RunReport {
        dimension: model.mesh.dimension,
        n_points,
        n_elements: model.mesh.n_elements(),
        time_step: dt,
        wave_speed: simulation.wave_speed(),
        min_element_size: simulation.min_element_size(),
        model_height: height,
        gravity: settings.gravity,
        damping: settings.damping,
        courant: settings.courant,
        steps: simulation.steps(),
        time: simulation.time(),
        stop,
        thresholds,
        records,
        initial_residual_ratio: initial_residual,
        final_residual_ratio: final_residual,
        max_displacement,
        inadmissible_points: inadmissible,
        plastic_points,
        lost_points: lost,
        verdict,
        worst_residual_elements,
        plastic_elements: plastic_elements(simulation, model),
        final_displacements: simulation.displacements(),
        final_stresses: simulation.effective_stresses(),
        final_plastic: simulation.plastic_flags(),
        final_pore_pressures: simulation.pore_pressures(),
        monitored,
        rest,
        formulations: simulation
            .formulations()
            .into_iter()
            .map(|(m, f)| {
                let dry = (m as usize)
                    .checked_sub(1)
                    .and_then(|i| model.materials.get(i))
                    .is_some_and(|mat| mat.material_type == "dry_material");
                (m, if dry { super::Formulation::Dry } else { f })
            })
            .collect(),
        material_names: model.materials.iter().map(|m| m.name.clone()).collect(),
        hydraulic: simulation.hydraulic(),
        notes: simulation.notes(),
    };
    Ok(report)
}

/// The verdict of a run and the counts it rests on.
struct Judged {
    verdict: Verdict,
    max_displacement: f64,
    inadmissible: usize,
    plastic_points: usize,
    lost: usize,
    n_points: usize,
}

/// Judges the state a run ended in against the thresholds: the residual
/// ratios at the first and last steps, the largest displacement against the
/// model's height, inadmissible and plastic MPs, MPs lost.
fn judge(
    simulation: &Simulation,
    settings: &RunSettings,
    height: f64,
    initial_residual: f64,
    final_residual: f64,
) -> Judged {
    let tolerance = settings.thresholds.residual_ratio;
    let (max_displacement, _) = simulation.displacement_stats();

    let (mut inadmissible, mut plastic_points, mut lost) = (0, 0, 0);
    simulation.for_each_point(|p| {
        inadmissible += p.inadmissible as usize;
        plastic_points += (p.plastic && !p.inadmissible) as usize;
        lost += p.lost as usize;
    });
    let n_points = simulation.n_points();
    let thresholds = &settings.thresholds;
    let plastic_limit = (thresholds.plastic_fraction * n_points as f64).floor() as usize;
    let displacement_limit = thresholds.displacement_fraction * height;
    let mut reasons = Vec::new();
    if !below(initial_residual, tolerance) {
        reasons.push(Reason::InitialResidual {
            ratio: initial_residual,
            limit: tolerance,
        });
    }
    if !below(final_residual, tolerance) {
        reasons.push(Reason::FinalResidual {
            ratio: final_residual,
            limit: tolerance,
        });
    }
    if !below(max_displacement, displacement_limit) {
        reasons.push(Reason::Displacement {
            max: max_displacement,
            limit: displacement_limit,
        });
    }
    if inadmissible > plastic_limit {
        reasons.push(Reason::InadmissibleStress {
            count: inadmissible,
            limit: plastic_limit,
        });
    }
    if plastic_points > plastic_limit {
        reasons.push(Reason::PlasticGrowth {
            count: plastic_points,
            limit: plastic_limit,
        });
    }
    if lost > 0 {
        reasons.push(Reason::LostPoints { count: lost });
    }
    let verdict = if reasons.is_empty() {
        Verdict::Equilibrium {
            initial_residual_ratio: initial_residual,
            final_residual_ratio: final_residual,
            max_displacement,
            plastic_points,
        }
    } else {
        Verdict::NotInEquilibrium { reasons }
    };

    Judged {
        verdict,
        max_displacement,
        inadmissible,
        plastic_points,
        lost,
        n_points,
    }
}

/// The monitored MPs (0-based indices) with their start positions; an index
/// past the last MP is an error naming its id.
fn monitored_points(indices: &[u32], starts: &[[f64; 3]]) -> Result<Vec<MonitoredPoint>, MpmError> {
    if let Some(&bad) = indices.iter().find(|&&i| i as usize >= starts.len()) {
        return Err(MpmError::InvalidSettings(format!(
            "monitored MP {} does not exist: the model has {} MPs",
            bad as u64 + 1,
            starts.len()
        )));
    }
    Ok(indices
        .iter()
        .map(|&i| MonitoredPoint {
            id: i + 1,
            start: starts[i as usize],
            history: Vec::new(),
        })
        .collect())
}

/// `value < limit`, false for NaN: a measurement that is not a number fails.
fn below(value: f64, limit: f64) -> bool {
    value < limit
}

fn make_record(simulation: &Simulation, outcome: &super::StepOutcome) -> StepRecord {
    let (max_displacement, mean_displacement) = simulation.displacement_stats();
    StepRecord {
        step: simulation.steps(),
        time: simulation.time(),
        kinetic_energy: outcome.kinetic_energy,
        residual_ratio: outcome.residual_ratio,
        max_displacement,
        mean_displacement,
        plastic_now: outcome.yielded,
        plastic_total: outcome.plastic,
    }
}

fn snapshot(simulation: &Simulation) -> Snapshot {
    Snapshot {
        step: simulation.steps(),
        time: simulation.time(),
        positions: simulation.positions(),
        displacements: simulation.displacements(),
        stresses: simulation.effective_stresses(),
        plastic: simulation.plastic_flags(),
        pore_pressures: simulation.pore_pressures(),
        saturations: simulation.saturations(),
        liquid_velocities: simulation.liquid_velocities(),
    }
}

/// y-extent of the nodes of active elements (all elements if none is active).
pub(crate) fn model_height(model: &AnuraModel) -> f64 {
    let mesh = &model.mesh;
    let mut low = f64::INFINITY;
    let mut high = f64::NEG_INFINITY;
    for e in 0..mesh.n_elements() {
        if model.element_material.get(e).copied().unwrap_or(0) == 0 {
            continue;
        }
        for &n in mesh.corners(e) {
            let y = mesh.nodes[n as usize][1];
            low = low.min(y);
            high = high.max(y);
        }
    }
    if high > low {
        high - low
    } else {
        let (lo, hi) = mesh.bounding_box();
        (hi[1] - lo[1]).max(f64::MIN_POSITIVE)
    }
}

fn centroid(model: &AnuraModel, e: usize) -> [f64; 3] {
    let mesh = &model.mesh;
    let corners = mesh.corners(e);
    let mut c = [0.0; 3];
    for &n in corners {
        for (k, v) in c.iter_mut().enumerate() {
            *v += mesh.nodes[n as usize][k] / corners.len() as f64;
        }
    }
    c
}

/// The ten largest positive scores, largest first, ties by element id.
pub(super) fn top_ten(model: &AnuraModel, scores: &[f64]) -> Vec<ElementScore> {
    let mut order: Vec<usize> = (0..scores.len()).filter(|&e| scores[e] > 0.0).collect();
    order.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]).then(a.cmp(&b)));
    order
        .into_iter()
        .take(10)
        .map(|e| ElementScore {
            id: e as u64 + 1,
            centroid: centroid(model, e),
            value: scores[e],
        })
        .collect()
}

fn residual_elements(simulation: &Simulation, model: &AnuraModel) -> Vec<ElementScore> {
    top_ten(model, &simulation.element_residuals())
}

fn plastic_elements(simulation: &Simulation, model: &AnuraModel) -> Vec<ElementScore> {
    let mut scores = vec![0.0; model.mesh.n_elements()];
    simulation.for_each_point(|p| {
        if p.plastic {
            scores[p.element as usize] += 1.0;
        }
    });
    top_ten(model, &scores)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn history(energies: &[f64]) -> Vec<StepRecord> {
        energies
            .iter()
            .enumerate()
            .map(|(i, &kinetic_energy)| StepRecord {
                step: i,
                time: 0.1 * i as f64,
                kinetic_energy,
                residual_ratio: 0.0,
                max_displacement: 0.0,
                mean_displacement: 0.0,
                plastic_now: 0,
                plastic_total: 0,
            })
            .collect()
    }

    #[test]
    fn rest_is_the_first_time_after_the_peak_from_which_the_energy_stays_low() {
        // Peak 10 at 0.2 s; below 0.1 from 0.6 s on (a dip to 0.05 at 0.4 s
        // that rises again does not count).
        let rest = Rest::find(&history(&[0.0, 5.0, 10.0, 3.0, 0.05, 0.5, 0.09, 0.01])).unwrap();
        assert_eq!(rest.peak_time, 0.2);
        assert_eq!(rest.peak_kinetic_energy, 10.0);
        assert!((rest.time - 0.6).abs() < 1e-12, "{rest:?}");
        assert!(rest.criterion.contains("1 %"), "{}", rest.criterion);
    }

    #[test]
    fn no_rest_without_motion_or_while_still_moving() {
        assert_eq!(Rest::find(&history(&[0.0, 0.0, 0.0])), None);
        assert_eq!(Rest::find(&history(&[0.0, 1.0, 2.0, 3.0])), None);
        assert_eq!(Rest::find(&history(&[0.0, 3.0, 2.0, 1.0])), None);
        assert_eq!(Rest::find(&[]), None);
    }
}
