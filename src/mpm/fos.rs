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
//! Mohr–Coulomb) is left as it is and named in the report. The run starts from
//! the given state (effective stress, frozen pore pressure and saturation) and
//! settles under gravity with local damping; F < 1 strengthens the materials.
//!
//! Criterion ("settles" versus "does not settle"), on a time window W that
//! defaults to max(20 T₀, 4 √(H/g)) with T₀ = 4H/c the fundamental-period
//! estimate of the runner and H the height of the active elements:
//!
//! * **does not settle** as soon as any MP has moved more than
//!   [`FosSettings::failure_fraction`] × H, or an MP leaves the mesh;
//! * otherwise, at t = W, with Δu₃ and Δu₄ the largest MP movements over the
//!   third and the fourth quarter of the window and q = Δu₄/Δu₃: the motion
//!   **settles** when Δu₄ ≤ [`FosSettings::noise_fraction`] × H (at rest);
//!   it **does not settle** when q > [`FosSettings::growth_ratio`] (0.9: the
//!   motion is not dying out; a mechanism keeps moving as fast or faster,
//!   q ≥ 1), or when the decaying motion, extrapolated geometrically,
//!   u∞ = u(W) + Δu₄·q/(1 − q), would still pass the failure displacement;
//!   it **settles** otherwise.
//!
//! The factor is bracketed from F = [`FosSettings::start`] by multiplying or
//! dividing by [`FosSettings::step`] (1.25: slopes of interest lie near
//! F = 1, and every settling trial costs a full window), then bisected until
//! the bracket (last settling F, first F that does not settle) is at most
//! 2 × [`FosSettings::tolerance`] wide; the reported factor is its midpoint.
//! The mechanism kept is the state at the end of the smallest F that did not
//! settle.
//!
//! A continuum with non-associated flow fails before limit equilibrium says:
//! an infinite slope of a material with ψ = 0 collapses at
//! τ/σ′n = sin φ′_F on planes parallel to the surface (Davis 1968), not at
//! tan φ′_F, so its factor is lower than limit equilibrium's (φ′ = 35°,
//! β = 20°: 1.79 instead of 1.92); with ψ = φ′ the two agree. The tests check
//! both. Each trial starts from the same state, so the
//! result is bit-identical for any number of threads (the runner is). This
//! file does no I/O and prints nothing.

use super::Simulation;
use super::run::model_height;
use super::{MpmError, RunSettings};
use crate::model::{AnuraModel, Material, MaterialPoint, MpState};

/// Everything that can stop a strength-reduction analysis.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
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
    /// on what it has, as at the end of its window).
    pub run: RunSettings,
    /// Half-width of the final bracket (default 0.01).
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
    /// A trial does not settle once an MP has moved this fraction of H
    /// (default 0.01).
    pub failure_fraction: f64,
    /// Largest accepted ratio q of the last-quarter movement to the
    /// third-quarter movement, in (0, 1) (default 0.9).
    pub growth_ratio: f64,
    /// Last-quarter movement below this fraction of H always counts as
    /// settled (default 1e-4).
    pub noise_fraction: f64,
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
                ..RunSettings::verify()
            },
            tolerance: 0.01,
            start: 1.0,
            step: 1.25,
            f_min: 1.0 / 64.0,
            f_max: 64.0,
            window: None,
            failure_fraction: 0.01,
            growth_ratio: 0.9,
            noise_fraction: 1e-4,
            tied_nodes: Vec::new(),
        }
    }
}

impl FosSettings {
    fn validate(&self) -> Result<(), FosError> {
        let bad = |s: String| Err(FosError::InvalidSettings(s));
        let positive = |v: f64| v > 0.0 && v.is_finite();
        if !positive(self.tolerance) {
            return bad(format!("tolerance {} must be > 0", self.tolerance));
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
        if !(positive(self.failure_fraction) && positive(self.noise_fraction)) {
            return bad("failure_fraction and noise_fraction must be > 0".into());
        }
        if !(self.growth_ratio > 0.0 && self.growth_ratio < 1.0) {
            return bad(format!(
                "growth_ratio {} must lie in (0, 1)",
                self.growth_ratio
            ));
        }
        Ok(())
    }
}

/// How one trial ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum TrialEnd {
    /// The motion died out within the window.
    Settled,
    /// The second-half movement exceeded the growth limit.
    Growing,
    /// An MP moved more than the failure displacement.
    DisplacementLimit,
    /// The motion decays, but so slowly that its geometric extrapolation
    /// passes the failure displacement.
    ProjectedLimit,
    /// An MP left the mesh.
    LostPoints,
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
    /// Largest MP displacement at the end (m).
    pub max_displacement: f64,
    /// Largest MP movement from W/2 to 3W/4 and from 3W/4 to W (m); `None`
    /// when the run stopped earlier.
    pub third_quarter_movement: Option<f64>,
    pub last_quarter_movement: Option<f64>,
    /// MPs that yielded at some step.
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

/// Where the bisection ended.
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
    /// The factor of safety: the midpoint of [lower, upper] when bracketed,
    /// else the bound that was reached.
    pub factor: f64,
    /// Largest F that settled (`None` when none did).
    pub lower: Option<f64>,
    /// Smallest F that did not settle (`None` when all settled).
    pub upper: Option<f64>,
    pub outcome: FosOutcome,
    /// Number of trial runs.
    pub iterations: usize,
    pub trials: Vec<Trial>,
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
    // A first simulation at F = 1 gives the time step and wave speed (they do
    // not depend on the strength).
    let probe = Simulation::new(model, points, states, &settings.run)?;
    let period = 4.0 * height / probe.wave_speed();
    let time_step = probe.time_step();
    drop(probe);
    let window = settings.window.unwrap_or_else(|| {
        let gravity = settings.run.gravity.max(f64::MIN_POSITIVE);
        (20.0 * period).max(4.0 * (height / gravity).sqrt())
    });
    let limits = Limits {
        window,
        failure: settings.failure_fraction * height,
        noise: settings.noise_fraction * height,
        growth_ratio: settings.growth_ratio,
    };

    let mut trials = Vec::new();
    let mut mechanism: Option<Mechanism> = None;
    let mut lower: Option<f64> = None;
    let mut upper: Option<f64> = None;
    let mut run_trial = |factor: f64| -> Result<bool, FosError> {
        let reduced = reduced_model(model, factor);
        let (trial, simulation) = trial(&reduced, points, states, settings, &limits, factor)?;
        trials.push(trial);
        if !trial.settled && mechanism.as_ref().is_none_or(|m| factor < m.factor) {
            mechanism = Some(capture(&simulation, factor));
        }
        Ok(trial.settled)
    };

    // Bracket.
    let mut factor = settings.start;
    let outcome = loop {
        if run_trial(factor)? {
            lower = Some(factor);
            if upper.is_some() {
                break FosOutcome::Bracketed;
            }
            if factor >= settings.f_max {
                break FosOutcome::AboveRange;
            }
            factor = (settings.step * factor).min(settings.f_max);
        } else {
            upper = Some(factor);
            if lower.is_some() {
                break FosOutcome::Bracketed;
            }
            if factor <= settings.f_min {
                break FosOutcome::BelowRange;
            }
            factor = (factor / settings.step).max(settings.f_min);
        }
    };
    // Bisect.
    if let (FosOutcome::Bracketed, Some(mut lo), Some(mut hi)) = (outcome, lower, upper) {
        while hi - lo > 2.0 * settings.tolerance {
            let mid = 0.5 * (lo + hi);
            if run_trial(mid)? {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lower = Some(lo);
        upper = Some(hi);
    }
    let factor = match (outcome, lower, upper) {
        (FosOutcome::Bracketed, Some(lo), Some(hi)) => 0.5 * (lo + hi),
        (FosOutcome::AboveRange, Some(lo), _) => lo,
        (_, _, Some(hi)) => hi,
        _ => f64::NAN,
    };
    Ok(FosReport {
        factor,
        lower,
        upper,
        outcome,
        iterations: trials.len(),
        trials,
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
    failure: f64,
    noise: f64,
    growth_ratio: f64,
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

/// Largest |a_i − b_i| over the MPs.
fn largest_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| {
            ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
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
    // Displacements at W/2 and 3W/4.
    let mut half: Option<Vec<[f64; 3]>> = None;
    let mut three_quarters: Option<Vec<[f64; 3]>> = None;
    let mut plastic = 0;
    let mut early = None;
    while simulation.steps() < settings.run.max_steps && !reached(&simulation, limits.window) {
        let outcome = simulation.step();
        let step = simulation.steps();
        if outcome.residual_ratio.is_nan() || !outcome.kinetic_energy.is_finite() {
            return Err(MpmError::Unstable { step }.into());
        }
        plastic = outcome.plastic;
        if half.is_none() && reached(&simulation, 0.5 * limits.window) {
            half = Some(simulation.displacements());
        }
        if three_quarters.is_none() && reached(&simulation, 0.75 * limits.window) {
            three_quarters = Some(simulation.displacements());
        }
        if step.is_multiple_of(8) || reached(&simulation, limits.window) {
            if simulation.lost_points() > 0 {
                early = Some(TrialEnd::LostPoints);
                break;
            }
            if simulation.displacement_stats().0 > limits.failure {
                early = Some(TrialEnd::DisplacementLimit);
                break;
            }
        }
    }
    let end_displacements = simulation.displacements();
    let max_displacement = simulation.displacement_stats().0;
    let quarters = match (&half, &three_quarters) {
        (Some(h), Some(q)) if early.is_none() => Some((
            largest_difference(q, h),
            largest_difference(&end_displacements, q),
        )),
        _ => None,
    };
    let end = match (early, quarters) {
        (Some(end), _) => end,
        // Window not completed (step cap): no evidence that it settled.
        (None, None) => TrialEnd::Growing,
        (None, Some((_, fourth))) if fourth <= limits.noise => TrialEnd::Settled,
        (None, Some((third, fourth))) if fourth > limits.growth_ratio * third => TrialEnd::Growing,
        (None, Some((third, fourth))) => {
            let q = fourth / third;
            if max_displacement + fourth * q / (1.0 - q) > limits.failure {
                TrialEnd::ProjectedLimit
            } else {
                TrialEnd::Settled
            }
        }
    };
    let trial = Trial {
        factor,
        settled: end == TrialEnd::Settled,
        end,
        steps: simulation.steps(),
        time: simulation.time(),
        max_displacement,
        third_quarter_movement: quarters.map(|q| q.0),
        last_quarter_movement: quarters.map(|q| q.1),
        plastic_points: plastic,
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
    use crate::testkit::{elastic_material, mohr_coulomb_material};

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
