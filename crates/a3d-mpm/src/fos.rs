//! Factor of safety of a state by strength reduction on the explicit runner
//! ([`strength_reduction`]): how far the mapped state, with its pore
//! pressures frozen, is from failure.
//!
//! Method (the strength-reduction method of Zienkiewicz et al. 1975, as used
//! with explicit solvers by Dawson, Roth & Drescher 1999). For a trial factor
//! F every `mohr_coulomb` material gets
//!
//! * tan φ′_F = tan φ′ / F, c′_F = c′ / F, σt_F = σt / F (every strength
//!   divided by F),
//! * ψ_F = min(ψ, φ′_F), so that the flow rule never dilates more than the
//!   reduced friction allows (an associated material stays associated).
//!
//! Every other material model (linear elasticity, strain-softening
//! Mohr–Coulomb) is left as it is and named in the report.
//!
//! **Start.** A mapped state is seldom in equilibrium on the runner's
//! mesh (a geostatic stress under a slope is not), and a trial that starts out
//! of balance moves for reasons that have nothing to do with F. So the state
//! first settles for one window with every strength divided by
//! [`FosSettings::settle_factor`] (0.5: doubled, so that a slope near failure
//! still settles); its effective stresses, on the original MP positions, with
//! the frozen pore pressures, are the start of every trial.
//!
//! **Measure.** A trial runs the fixed window W = max(20 T₀, 4 √(H/g))
//! (T₀ = 4H/c the fundamental-period estimate, H the height of the active
//! elements) from that start; its measure δ(F) is the
//! [`FosSettings::quantile`] (0.98) quantile of the MPs' displacement
//! magnitudes at the end of the window. δ is a continuous function of the
//! state and of F, and grows with F: slowly while the reduced strength still
//! carries the slope, steeply where a mechanism forms. A trial **settles**
//! when δ < δ* = [`FosSettings::failure_fraction`] × H (0.003 H: 12 mm on a
//! 4 m slope, on the steep part of δ(F) of the shipped slope). The rate of
//! motion late in the window, which the former criterion used, is not
//! monotone in F there (motion comes in bursts as the mechanism forms) and
//! was the second source of scatter. A trial whose largest displacement
//! passes H/10 stops early and does not settle. MPs that leave the mesh are
//! frozen by the runner.
//!
//! **Factor.** F is bracketed from [`FosSettings::start`] by multiplying or
//! dividing by [`FosSettings::step`], then the bracket (last settling F,
//! first F that does not) is narrowed by safeguarded regula falsi on
//! g(F) = ln δ(F) − ln δ* to at most 2 × [`FosSettings::tolerance`]; the
//! factor is the root of g interpolated linearly between the bracket's ends.
//! The factor is therefore continuous in the inputs: a 1 % change of the
//! pore pressures moves it by about as much, where the former settle /
//! does-not-settle window criterion (a ratio of quarter-window movements and
//! an extrapolation, on a start out of balance) jumped by 5–10 %.
//! The mechanism kept is the state at the end of the smallest F that did not
//! settle.
//!
//! A continuum with non-associated flow fails before limit equilibrium says:
//! an infinite slope of a material with ψ = 0 collapses at
//! τ/σ′n = sin φ′_F on planes parallel to the surface (Davis 1968), not at
//! tan φ′_F, so its factor is lower than limit equilibrium's (φ′ = 35°,
//! β = 20°: 1.79 instead of 1.92); with ψ = φ′ the two agree. The tests check
//! both. Each trial starts from the same state, so the result is
//! bit-identical for any number of threads (the runner is). This file does no
//! I/O and prints nothing.

use super::Simulation;
use super::run::model_height;
use super::{MpmError, RunSettings};
use a3d_model::{AnuraModel, Material, MaterialPoint, MpState};

/// Everything that can stop a strength-reduction analysis.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FosError {
    #[error(transparent)]
    Mpm(#[from] MpmError),
    #[error("no material of the material points is mohr_coulomb: there is no strength to reduce")]
    NothingToReduce,
    #[error("invalid strength-reduction settings: {0}")]
    InvalidSettings(String),
}

/// Settings of [`strength_reduction`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FosSettings {
    /// Gravity, damping and Courant number of every trial run;
    /// `max_steps` caps the steps of one trial (a trial that hits it is judged
    /// on what it has).
    pub run: RunSettings,
    /// Half-width of the final bracket (default 0.01, at least
    /// [`MIN_TOLERANCE`]).
    pub tolerance: f64,
    /// First trial factor (default 1).
    pub start: f64,
    /// Factor between successive trials of the bracket search (default 1.25).
    pub step: f64,
    /// The bracket search stops below `f_min` and above `f_max`
    /// (defaults 1/64 and 64).
    pub f_min: f64,
    pub f_max: f64,
    /// Time window W of one trial (s); `None` = max(20 T₀, 4 √(H/g)).
    pub window: Option<f64>,
    /// δ* over H: a trial whose measure reaches it does not settle
    /// (default 0.003).
    pub failure_fraction: f64,
    /// The quantile of the MPs' displacements that is the measure δ
    /// (default 0.98).
    pub quantile: f64,
    /// The settle phase divides the strengths by this (default 0.5);
    /// `None`: no settle phase, trials start from the given state.
    pub settle_factor: Option<f64>,
    /// Pairs of 0-based mesh nodes (primary, secondary) that share their
    /// degrees of freedom, for periodic test models; empty for Anura3D
    /// models.
    pub tied_nodes: Vec<(u32, u32)>,
}

impl Default for FosSettings {
    fn default() -> Self {
        FosSettings {
            run: RunSettings {
                max_steps: 200_000,
                stop_at_equilibrium: false,
                mass_scaling: true,
                ..RunSettings::verify()
            },
            tolerance: 0.01,
            start: 1.0,
            step: 1.25,
            f_min: 1.0 / 64.0,
            f_max: 64.0,
            window: None,
            failure_fraction: 0.003,
            quantile: 0.98,
            settle_factor: Some(0.5),
            tied_nodes: Vec::new(),
        }
    }
}

/// The narrowest half-width of the final bracket that the settings take
/// ([`FosSettings::tolerance`]).
pub const MIN_TOLERANCE: f64 = 1e-4;

impl FosSettings {
    fn validate(&self) -> Result<(), FosError> {
        let bad = |s: String| Err(FosError::InvalidSettings(s));
        let positive = |v: f64| v > 0.0 && v.is_finite();
        // Each trial judges failure from a run's displacements, which no
        // bracket narrower than about 10⁻⁴ in F can resolve; a tolerance
        // below that only adds trials (1e-15 asked for about 50 bisections).
        if !(self.tolerance >= MIN_TOLERANCE && self.tolerance < 1.0) {
            return bad(format!(
                "tolerance {} must lie in [{MIN_TOLERANCE}, 1)",
                self.tolerance
            ));
        }
        if !(positive(self.f_min) && positive(self.f_max) && self.f_min < self.f_max) {
            return bad(format!(
                "the search range [{}, {}] must be positive and non-empty",
                self.f_min, self.f_max
            ));
        }
        if !(self.start >= self.f_min && self.start <= self.f_max) {
            return bad(format!(
                "start {} must lie in [{}, {}]",
                self.start, self.f_min, self.f_max
            ));
        }
        if !(self.step > 1.0 && self.step.is_finite()) {
            return bad(format!("step {} must be > 1", self.step));
        }
        if self.window.is_some_and(|w| !positive(w)) {
            return bad("window must be > 0".into());
        }
        if !positive(self.failure_fraction) {
            return bad("failure_fraction must be > 0".into());
        }
        if !(self.quantile > 0.0 && self.quantile <= 1.0) {
            return bad(format!("quantile {} must lie in (0, 1]", self.quantile));
        }
        if self.settle_factor.is_some_and(|f| !positive(f)) {
            return bad("settle_factor must be > 0".into());
        }
        Ok(())
    }
}

/// How one trial ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum TrialEnd {
    /// δ < δ* at the end of the window.
    Settled,
    /// δ ≥ δ* at the end of the window.
    Moving,
    /// Stopped early: an MP moved more than H/10.
    Runaway,
}

/// One trial factor and what the run did.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Trial {
    pub factor: f64,
    pub settled: bool,
    pub end: TrialEnd,
    pub steps: usize,
    /// Simulated time at the end (s).
    pub time: f64,
    /// The measure δ: the quantile of the MPs' displacements at the end
    /// (m); infinite for a runaway trial.
    pub measure: f64,
    /// Largest MP displacement at the end (m).
    pub max_displacement: f64,
    /// MPs that yielded at some step.
    pub plastic_points: usize,
    /// MPs that left the mesh (frozen).
    pub lost_points: usize,
}

/// The settle phase.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Settle {
    /// Strengths divided by this.
    pub factor: f64,
    pub time: f64,
    pub steps: usize,
    /// Out-of-balance force ratio at the first and the last step.
    pub initial_residual_ratio: f64,
    pub final_residual_ratio: f64,
    pub max_displacement: f64,
    pub plastic_points: usize,
}

/// A material of the MPs and whether its strength was reduced.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MaterialNote {
    /// 1-based material index.
    pub index: u32,
    pub name: String,
    pub model: String,
}

/// Where the search ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum FosOutcome {
    /// F lies in [lower, upper], at most 2 × tolerance wide.
    Bracketed,
    /// Even F = `f_max` settles: the factor is above it.
    AboveRange,
    /// Even F = `f_min` does not settle: the factor is below it.
    BelowRange,
}

/// The state at the end of the first trial that did not settle (the smallest
/// such F): the failure mechanism.
/// The per-MP arrays are left out of the serialised form (they are for
/// plots and VTU files).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Mechanism {
    pub factor: f64,
    pub time: f64,
    /// Number of MPs in motion.
    pub points_in_motion: usize,
    /// Current MP positions (z = 0 in 2D).
    #[serde(skip)]
    pub positions: Vec<[f64; 3]>,
    #[serde(skip)]
    pub displacements: Vec<[f64; 3]>,
    #[serde(skip)]
    pub velocities: Vec<[f64; 3]>,
    /// Effective stress σ′ (kPa).
    #[serde(skip)]
    pub stresses: Vec<[f64; 6]>,
    #[serde(skip)]
    pub plastic: Vec<bool>,
    /// MPs in motion: speed at least 10 % of the largest MP speed.
    #[serde(skip)]
    pub in_motion: Vec<bool>,
}

/// The result of [`strength_reduction`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FosReport {
    /// The factor of safety: the root of ln δ − ln δ* interpolated in the
    /// final bracket, else the bound that was reached.
    pub factor: f64,
    /// Largest F that settled (`None` when none did).
    pub lower: Option<f64>,
    /// Smallest F that did not settle (`None` when all settled).
    pub upper: Option<f64>,
    pub outcome: FosOutcome,
    /// Number of trial runs.
    pub iterations: usize,
    pub trials: Vec<Trial>,
    /// The settle phase, when there was one.
    pub settle: Option<Settle>,
    /// δ*: the threshold on the measure (m).
    pub threshold: f64,
    pub reduced_materials: Vec<MaterialNote>,
    pub unreduced_materials: Vec<MaterialNote>,
    /// Window W of each trial (s), height H (m), time step (s).
    pub window: f64,
    pub model_height: f64,
    pub time_step: f64,
    pub n_points: usize,
    pub settings: FosSettings,
    pub mechanism: Option<Mechanism>,
}

/// The material with its strength divided by `factor` (see the module
/// documentation); `None` when its model is not `mohr_coulomb`.
pub fn reduce_material(material: &Material, factor: f64) -> Option<Material> {
    if material.model.as_deref() != Some("mohr_coulomb") {
        return None;
    }
    let phi = material.friction_angle?;
    let reduced_phi = (phi.to_radians().tan() / factor).atan().to_degrees();
    let psi = material.dilatancy_angle.unwrap_or(0.0);
    Some(Material {
        friction_angle: Some(reduced_phi),
        cohesion: material.cohesion.map(|c| c / factor),
        dilatancy_angle: Some(psi.min(reduced_phi)),
        tensile_strength: material.tensile_strength.map(|t| t / factor),
        ..material.clone()
    })
}

/// Finds the factor of safety of the state by strength reduction (see the
/// module documentation for the method and the criterion).
pub fn strength_reduction(
    model: &AnuraModel,
    points: &[MaterialPoint],
    states: &[MpState],
    settings: &FosSettings,
) -> Result<FosReport, FosError> {
    settings.validate()?;
    settings.run.validate()?;
    let (reduced_materials, unreduced_materials) = classify(model, points);
    if reduced_materials.is_empty() {
        return Err(FosError::NothingToReduce);
    }
    let height = model_height(model);
    // A first simulation at F = 1 gives the wave speed and the time step
    // (they do not depend on the strength): the window comes from the
    // physical wave speed, the step from the scaled one.
    let unscaled = RunSettings {
        mass_scaling: false,
        ..settings.run.clone()
    };
    let period = 4.0 * height / Simulation::new(model, points, states, &unscaled)?.wave_speed();
    let time_step = Simulation::new(model, points, states, &settings.run)?.time_step();
    let window = settings.window.unwrap_or_else(|| {
        let gravity = settings.run.gravity.max(f64::MIN_POSITIVE);
        (20.0 * period).max(4.0 * (height / gravity).sqrt())
    });
    let window_steps = (window / time_step).ceil();
    if window_steps.is_nan() || window_steps > settings.run.max_steps as f64 {
        return Err(FosError::InvalidSettings(format!(
            "a window of {window:.3e} s takes {window_steps:.3e} steps at the model's time step of {time_step:.3e} s, more than the {} a trial may take",
            settings.run.max_steps
        )));
    }
    let limits = Limits {
        window,
        threshold: settings.failure_fraction * height,
        runaway: 0.1 * height,
        quantile: settings.quantile,
    };
    let (start, settle) = match settings.settle_factor {
        Some(f) => {
            let (s, note) = settle_phase(model, points, states, settings, window, f)?;
            (s, Some(note))
        }
        None => (states.to_vec(), None),
    };

    let mut trials: Vec<Trial> = Vec::new();
    let mut mechanism: Option<Mechanism> = None;
    let mut run_trial = |factor: f64| -> Result<Trial, FosError> {
        let reduced = reduced_model(model, factor);
        let (trial, simulation) = trial(&reduced, points, &start, settings, &limits, factor)?;
        trials.push(trial);
        if !trial.settled && mechanism.as_ref().is_none_or(|m| factor < m.factor) {
            mechanism = Some(capture(&simulation, factor));
        }
        Ok(trial)
    };

    // Bracket.
    let mut lower: Option<Trial> = None;
    let mut upper: Option<Trial> = None;
    let mut factor = settings.start;
    let outcome = loop {
        let t = run_trial(factor)?;
        if t.settled {
            lower = Some(t);
            if upper.is_some() {
                break FosOutcome::Bracketed;
            }
            if factor >= settings.f_max {
                break FosOutcome::AboveRange;
            }
            factor = (settings.step * factor).min(settings.f_max);
        } else {
            upper = Some(t);
            if lower.is_some() {
                break FosOutcome::Bracketed;
            }
            if factor <= settings.f_min {
                break FosOutcome::BelowRange;
            }
            factor = (factor / settings.step).max(settings.f_min);
        }
    };
    // Narrow by safeguarded regula falsi on g = ln δ − ln δ*.
    let g = |t: &Trial| (t.measure.clamp(1e-12 * height, 1e3 * height) / limits.threshold).ln();
    let root = |lo: &Trial, hi: &Trial| {
        let (gl, gh) = (g(lo), g(hi));
        if gh > gl {
            lo.factor + (hi.factor - lo.factor) * (-gl / (gh - gl)).clamp(0.0, 1.0)
        } else {
            0.5 * (lo.factor + hi.factor)
        }
    };
    if let (FosOutcome::Bracketed, Some(mut lo), Some(mut hi)) = (outcome, lower, upper) {
        while hi.factor - lo.factor > 2.0 * settings.tolerance {
            let width = hi.factor - lo.factor;
            let mid = root(&lo, &hi).clamp(lo.factor + 0.1 * width, hi.factor - 0.1 * width);
            let t = run_trial(mid)?;
            if t.settled {
                lo = t;
            } else {
                hi = t;
            }
        }
        lower = Some(lo);
        upper = Some(hi);
    }
    let factor = match (outcome, &lower, &upper) {
        (FosOutcome::Bracketed, Some(lo), Some(hi)) => root(lo, hi),
        (FosOutcome::AboveRange, Some(lo), _) => lo.factor,
        (_, _, Some(hi)) => hi.factor,
        _ => f64::NAN,
    };
    Ok(FosReport {
        factor,
        lower: lower.map(|t| t.factor),
        upper: upper.map(|t| t.factor),
        outcome,
        iterations: trials.len(),
        trials,
        settle,
        threshold: limits.threshold,
        reduced_materials,
        unreduced_materials,
        window,
        model_height: height,
        time_step,
        n_points: points.len(),
        settings: settings.clone(),
        mechanism,
    })
}

struct Limits {
    window: f64,
    threshold: f64,
    runaway: f64,
    quantile: f64,
}

/// The materials used by MPs, split into reduced (Mohr–Coulomb) and left alone.
fn classify(
    model: &AnuraModel,
    points: &[MaterialPoint],
) -> (Vec<MaterialNote>, Vec<MaterialNote>) {
    let mut used = vec![false; model.materials.len()];
    for p in points {
        if let Some(slot) = (p.material as usize)
            .checked_sub(1)
            .and_then(|i| used.get_mut(i))
        {
            *slot = true;
        }
    }
    let mut reduced = Vec::new();
    let mut unreduced = Vec::new();
    for (material, _) in model.materials.iter().zip(&used).filter(|(_, u)| **u) {
        let note = MaterialNote {
            index: material.index,
            name: material.name.clone(),
            model: material.model.clone().unwrap_or_default(),
        };
        if reduce_material(material, 1.0).is_some() {
            reduced.push(note);
        } else {
            unreduced.push(note);
        }
    }
    (reduced, unreduced)
}

fn reduced_model(model: &AnuraModel, factor: f64) -> AnuraModel {
    let mut reduced = model.clone();
    for material in &mut reduced.materials {
        if let Some(m) = reduce_material(material, factor) {
            *material = m;
        }
    }
    reduced
}

/// The `quantile` quantile of the MPs' displacement magnitudes.
fn measure(simulation: &Simulation, quantile: f64) -> f64 {
    let mut d: Vec<f64> = simulation
        .displacements()
        .iter()
        .map(|u| (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt())
        .collect();
    if d.is_empty() {
        return 0.0;
    }
    let k = ((quantile * d.len() as f64).ceil() as usize).clamp(1, d.len()) - 1;
    *d.select_nth_unstable_by(k, f64::total_cmp).1
}

/// One window at strengths divided by `factor`; the effective stresses at the
/// end, with the frozen pore pressures, as total stresses on the original
/// MPs.
fn settle_phase(
    model: &AnuraModel,
    points: &[MaterialPoint],
    states: &[MpState],
    settings: &FosSettings,
    window: f64,
    factor: f64,
) -> Result<(Vec<MpState>, Settle), FosError> {
    let reduced = reduced_model(model, factor);
    let mut simulation = Simulation::new(&reduced, points, states, &settings.run)?;
    simulation.tie_nodes(&settings.tied_nodes)?;
    let dt = simulation.time_step();
    let mut first = None;
    let mut last = f64::NAN;
    let mut plastic = 0;
    while simulation.steps() < settings.run.max_steps && simulation.time() < window - 1e-9 * dt {
        let outcome = simulation.step();
        if outcome.residual_ratio.is_nan() || !outcome.kinetic_energy.is_finite() {
            return Err(MpmError::Unstable {
                step: simulation.steps(),
            }
            .into());
        }
        first.get_or_insert(outcome.residual_ratio);
        last = outcome.residual_ratio;
        plastic = outcome.plastic;
    }
    let stresses = simulation.effective_stresses();
    let settled = states
        .iter()
        .zip(&stresses)
        .map(|(s, sigma)| {
            let mut total = *sigma;
            for c in total.iter_mut().take(3) {
                *c += s.saturation * s.pwp;
            }
            MpState { total, ..*s }
        })
        .collect();
    let note = Settle {
        factor,
        time: simulation.time(),
        steps: simulation.steps(),
        initial_residual_ratio: first.unwrap_or(f64::NAN),
        final_residual_ratio: last,
        max_displacement: simulation.displacement_stats().0,
        plastic_points: plastic,
    };
    Ok((settled, note))
}

/// Runs one trial factor on the reduced model.
fn trial(
    model: &AnuraModel,
    points: &[MaterialPoint],
    states: &[MpState],
    settings: &FosSettings,
    limits: &Limits,
    factor: f64,
) -> Result<(Trial, Simulation), FosError> {
    let mut simulation = Simulation::new(model, points, states, &settings.run)?;
    simulation.tie_nodes(&settings.tied_nodes)?;
    let dt = simulation.time_step();
    let reached = |simulation: &Simulation, t: f64| simulation.time() >= t - 1e-9 * dt;
    let mut plastic = 0;
    let mut runaway = false;
    while simulation.steps() < settings.run.max_steps && !reached(&simulation, limits.window) {
        let outcome = simulation.step();
        let step = simulation.steps();
        if outcome.residual_ratio.is_nan() || !outcome.kinetic_energy.is_finite() {
            return Err(MpmError::Unstable { step }.into());
        }
        plastic = outcome.plastic;
        if step.is_multiple_of(32) && simulation.displacement_stats().0 > limits.runaway {
            runaway = true;
            break;
        }
    }
    let delta = if runaway {
        f64::INFINITY
    } else {
        measure(&simulation, limits.quantile)
    };
    let end = if runaway {
        TrialEnd::Runaway
    } else if delta < limits.threshold {
        TrialEnd::Settled
    } else {
        TrialEnd::Moving
    };
    let trial = Trial {
        factor,
        settled: end == TrialEnd::Settled,
        end,
        steps: simulation.steps(),
        time: simulation.time(),
        measure: delta,
        max_displacement: simulation.displacement_stats().0,
        plastic_points: plastic,
        lost_points: simulation.lost_points(),
    };
    Ok((trial, simulation))
}

fn capture(simulation: &Simulation, factor: f64) -> Mechanism {
    let velocities = simulation.velocities();
    let speed: Vec<f64> = velocities
        .iter()
        .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
        .collect();
    let top = speed.iter().copied().fold(0.0, f64::max);
    let in_motion: Vec<bool> = speed.iter().map(|&s| top > 0.0 && s >= 0.1 * top).collect();
    Mechanism {
        factor,
        time: simulation.time(),
        points_in_motion: in_motion.iter().filter(|&&b| b).count(),
        positions: simulation.positions(),
        displacements: simulation.displacements(),
        velocities,
        stresses: simulation.effective_stresses(),
        plastic: simulation.plastic_flags(),
        in_motion,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use a3d_testkit::{elastic_material, mohr_coulomb_material};

    #[test]
    fn reduction_divides_tan_phi_and_cohesion_and_caps_dilatancy() {
        let m = mohr_coulomb_material(1e4, 0.3, 2650.0, 0.4, 35.0, 12.0, 35.0);
        let r = reduce_material(&m, 2.0).unwrap();
        let tan = r.friction_angle.unwrap().to_radians().tan();
        assert!((tan - 35f64.to_radians().tan() / 2.0).abs() < 1e-12);
        assert_eq!(r.cohesion, Some(6.0));
        assert_eq!(r.dilatancy_angle, r.friction_angle);
        let weaker_dilatancy = Material {
            dilatancy_angle: Some(5.0),
            ..m.clone()
        };
        let r = reduce_material(&weaker_dilatancy, 2.0).unwrap();
        assert_eq!(r.dilatancy_angle, Some(5.0));
        assert!(reduce_material(&elastic_material(1e4, 0.3, 2650.0, 0.4), 2.0).is_none());
    }
}
