//! Explicit MPM check: is a mapped initial state in equilibrium under gravity?
//!
//! The solver runs on the Anura3D background mesh itself (fixed in space, no
//! moving mesh): linear shape functions on TRI3 in plane strain or 2D
//! axisymmetry (x the radius, per-radian volumes and masses, hoop strain and
//! force, [`step`]) and on the four corners of `tetrahedral_old` in 3D, lumped
//! nodal masses, gravity along −y,
//! nodal fixities from the GOM, local (Cundall) damping as Anura3D applies it,
//! and a MUSL update ([`step`] documents the scheme). Material points carry the
//! effective stress σ′ and the pore pressure p: the water of two-phase,
//! undrained and unsaturated two-phase materials runs ([`liquid`]: its own
//! velocity, Darcy's drag, p from both phases' volumetric strains, seepage
//! faces in [`seepage`]); drained materials, and every material under
//! [`RunSettings::frozen_pore_pressure`], hold p and S at their initial values.
//! What of p enters the internal force, and which weight
//! gravity pulls on, is the kernel's choice for the model's kind of analysis
//! ([`loading`]: σ′ with the dry or buoyant weight in a one-phase analysis,
//! Bishop's σ′ + S·p with the mixture's weight in a multiphase one).
//! Materials are linear elastic or Mohr–Coulomb ([`material`]).
//!
//! Entry points: [`verify`] runs a damped simulation until the state settles (or
//! a step/time limit) and returns a [`RunReport`] with a [`Verdict`]; [`run()`]
//! runs the same solver and can also return [`Snapshot`]s; [`Simulation`] gives
//! step-by-step control; [`fos`] finds a factor of safety by strength
//! reduction on the same runner; [`equilibrium`] solves for the stress at rest
//! in the runner's own discrete equations. The module is pure: it consumes [`a3d_model`] data,
//! does no I/O and prints nothing; it knows nothing about file formats or the
//! mapping kernels.

mod b_matrix;
pub mod elasticity;
pub mod equilibrium;
pub mod fos;
pub mod grid;
pub mod liquid;
mod liquid_grid;
pub mod loading;
pub mod loads;
pub mod material;
mod mixed;
pub mod mohr_coulomb;
mod particle;
mod principal;
pub mod run;
pub mod seepage;
mod simulation;
pub mod step;

pub use elasticity::Elasticity;
pub use equilibrium::{EquilibriumOutcome, EquilibriumSettings};
pub use fos::{FosError, FosOutcome, FosReport, FosSettings, strength_reduction};
pub use liquid::Formulation;
pub use material::SolidModel;
pub use mohr_coulomb::{MohrCoulomb, ReturnKind, ReturnMap};
pub use run::{
    ElementScore, MAX_RUN_STEPS, MonitoredPoint, REST_FRACTION, Reason, Rest, RunOutput, RunReport,
    Snapshot, StepRecord, StopReason, Verdict, run, run_streaming, verify,
};
pub use simulation::Simulation;

/// One state per MP, and at least one MP: what the runner and the
/// equilibrium solve both need before they start.
pub(crate) fn check_points(
    points: &[a3d_model::MaterialPoint],
    states: &[a3d_model::MpState],
) -> Result<(), MpmError> {
    if points.len() != states.len() {
        return Err(MpmError::LengthMismatch {
            points: points.len(),
            states: states.len(),
        });
    }
    if points.is_empty() {
        return Err(MpmError::NoMaterialPoints);
    }
    Ok(())
}
pub use step::StepOutcome;

/// Everything that can stop the MPM check before it runs.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MpmError {
    #[error("the MPM check does not support {0}")]
    Unsupported(String),
    #[error("invalid mesh: {0}")]
    InvalidMesh(String),
    #[error("element {element} is degenerate (zero area or volume)")]
    DegenerateElement { element: u64 },
    #[error("material {material}: missing property {property}")]
    MissingProperty {
        material: u32,
        property: &'static str,
    },
    #[error("material {material}: {reason}")]
    InvalidProperty { material: u32, reason: String },
    #[error("material {material}: model `{model}` is not supported by the MPM check")]
    UnsupportedMaterialModel { material: u32, model: String },
    #[error("material point {id}: {reason}")]
    InvalidPoint { id: u32, reason: String },
    #[error("{points} material points but {states} states")]
    LengthMismatch { points: usize, states: usize },
    #[error("the model has no material points")]
    NoMaterialPoints,
    #[error("invalid run settings: {0}")]
    InvalidSettings(String),
    #[error("the simulation became unstable (non-finite values) at step {step}")]
    Unstable { step: usize },
    #[error(
        "a run of {time:.3e} s at the model's time step of {dt:.3e} s would take {steps:.3e} steps, more than the {limit} a run may take: give a shorter time"
    )]
    TooManySteps {
        time: f64,
        dt: f64,
        steps: f64,
        limit: usize,
    },
    /// A snapshot could not be handed on (written) during the run.
    #[error("{0}")]
    Snapshot(String),
}

/// Limits of the equilibrium verdict. A state is reported in equilibrium only
/// when every limit holds; see [`Verdict`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Thresholds {
    /// Largest accepted out-of-balance force ratio ‖f_ext + f_int‖/‖f_ext‖
    /// over free DOFs, both at the first step (the mapped state itself) and
    /// at the last one (the run has settled). Default 1e-2, Anura3D's default
    /// `$$TOLERATED_ERROR_SOLID` force tolerance.
    pub residual_ratio: f64,
    /// Largest accepted MP displacement as a fraction of the model height.
    /// Default 1e-3: a state that moves more than 0.1 % of its height to find
    /// equilibrium was not in equilibrium in any practical sense.
    pub displacement_fraction: f64,
    /// Largest accepted fraction of MPs that start outside the yield surface,
    /// and, separately, of MPs that yield during the run. Default 1e-2: a few
    /// points right at the yield surface (e.g. cohesionless MPs near a free
    /// surface) may yield under tiny disturbances without any real plastic
    /// flow; a growing plastic zone soon exceeds 1 %.
    pub plastic_fraction: f64,
}

impl Default for Thresholds {
    fn default() -> Self {
        Thresholds {
            residual_ratio: 1e-2,
            displacement_fraction: 1e-3,
            plastic_fraction: 1e-2,
        }
    }
}

/// Settings of an MPM run.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RunSettings {
    /// Gravitational acceleration g (m/s²), acting along −y, scaled each
    /// step by [`RunSettings::loads`]' gravity multiplier (`$$GRAVITY_LOAD`;
    /// full by default).
    pub gravity: f64,
    /// Local damping factor α in [0, 1) (CPS `$$HOMOGENEOUS_LOCAL_DAMPING 1 α`).
    pub damping: f64,
    /// The CPS's `$$SUBMERGED_CALCULATION 1`: buoyant weights for every
    /// material of a one-phase analysis ([`loading`]).
    pub submerged_calculation: bool,
    /// Courant number in (0, 1] (CPS `$$COURANT_NUMBER`).
    pub courant: f64,
    /// Hard cap on the number of steps.
    pub max_steps: usize,
    /// Stop once this simulated time (s) is reached.
    pub end_time: Option<f64>,
    /// Earliest time (s) at which [`RunSettings::stop_at_equilibrium`] may
    /// stop the run; `None` = two estimated fundamental periods 2·(4H/c).
    pub min_time: Option<f64>,
    /// Record a [`StepRecord`] every this many steps (the first and the last
    /// step are always recorded).
    pub record_every: usize,
    /// Stop as soon as the residual ratio has stayed below
    /// [`Thresholds::residual_ratio`] for one estimated fundamental period
    /// (4H/c) after `min_time`.
    pub stop_at_equilibrium: bool,
    /// Times (s) at which [`run()`] takes a [`Snapshot`] (at the first step that
    /// reaches each time).
    pub snapshot_times: Vec<f64>,
    pub thresholds: Thresholds,
    /// Hold every pore pressure at its initial value (drained; the
    /// two-phase and undrained materials run as one phase with frozen p).
    pub frozen_pore_pressure: bool,
    /// Run `unsaturated_material_2phase_suction` materials two-phase,
    /// partially saturated ([`liquid`]); on by default. Off, they keep their
    /// pore pressure frozen as the other drained materials do.
    pub unsaturated_two_phase: bool,
    /// MPM-MIXED (Anura3D's default integration, [`a3d_model::ComputationMethod`]):
    /// after every step σ′ and p of the MPs of each element whose MPs share
    /// one material are replaced by their volume-weighted mean, as the
    /// kernel's `StressAndPorePressureSmoothening` does. Off (per-MP
    /// integration, `MPM-MP`) by default; the pipeline sets it from the CPS.
    pub element_smoothing: bool,
    /// Seepage faces and infiltration of partially saturated analyses
    /// ([`seepage`]); none by default.
    pub hydraulic: seepage::HydraulicBoundaries,
    /// The GOM's distributed loads with the CPS's multipliers ([`loads`]);
    /// none by default (gravity only).
    pub loads: a3d_model::loads::ProjectLoads,
    /// Damp a coupled mixture as the kernel does, in two parts: the water's
    /// porosity-weighted share Σ n·S·F_w with the liquid's velocity's sign,
    /// the rest with the solid's (`run`, to follow the kernel's dynamics).
    /// Off (the mixture's force damped as one) for the quasi-static checks:
    /// where the two parts oppose, the split holds a settling model short
    /// of rest as friction would and its residual never falls.
    pub split_mixture_damping: bool,
    /// MPs whose displacement [`run()`] records at every recorded step
    /// (0-based indices; CPS `$$OUTPUT_MATERIAL_POINTS`), none by default.
    pub monitored: Vec<u32>,
    /// Density scaling for quasi-static analyses (strength reduction): the
    /// inertia (not the weight) of every MP whose P-wave speed exceeds the
    /// slowest MP's is raised until its speed equals it, at most by
    /// [`MAX_MASS_SCALING`], so the time step is set by the slowest material
    /// instead of the stiffest (FLAC's density scaling). The state at rest
    /// is the same; the way there is not, so dynamic runs keep it off (the
    /// default). Ignored when any MP runs two-phase coupled (its water has a
    /// mass of its own).
    pub mass_scaling: bool,
}

/// The largest factor [`RunSettings::mass_scaling`] raises an MP's mass by
/// (its wave speed by at most 10).
pub const MAX_MASS_SCALING: f64 = 100.0;

impl RunSettings {
    /// Settings for the equilibrium check: α = 0.75, Courant 0.9, g = 9.81,
    /// at most 10 000 steps, stop when settled.
    pub fn verify() -> RunSettings {
        RunSettings {
            gravity: a3d_model::DEFAULT_GRAVITY,
            damping: 0.75,
            submerged_calculation: false,
            courant: 0.9,
            max_steps: 10_000,
            end_time: None,
            min_time: None,
            record_every: 100,
            stop_at_equilibrium: true,
            snapshot_times: Vec::new(),
            thresholds: Thresholds::default(),
            frozen_pore_pressure: false,
            unsaturated_two_phase: true,
            element_smoothing: false,
            hydraulic: seepage::HydraulicBoundaries::default(),
            loads: a3d_model::loads::ProjectLoads::default(),
            monitored: Vec::new(),
            split_mixture_damping: false,
            mass_scaling: false,
        }
    }

    /// Settings for an undamped dynamic run that goes to `end_time`.
    pub fn dynamic(end_time: f64) -> RunSettings {
        RunSettings {
            damping: 0.0,
            end_time: Some(end_time),
            max_steps: usize::MAX,
            stop_at_equilibrium: false,
            ..RunSettings::verify()
        }
    }

    pub(crate) fn validate(&self) -> Result<(), MpmError> {
        let bad = |s: String| Err(MpmError::InvalidSettings(s));
        if !(self.gravity >= 0.0 && self.gravity.is_finite()) {
            return bad(format!("gravity {} must be finite and ≥ 0", self.gravity));
        }
        if !(0.0..1.0).contains(&self.damping) {
            return bad(format!("damping {} must be in [0, 1)", self.damping));
        }
        if !(self.courant > 0.0 && self.courant <= 1.0) {
            return bad(format!("Courant number {} must be in (0, 1]", self.courant));
        }
        if self.max_steps == 0 || self.record_every == 0 {
            return bad("max_steps and record_every must be ≥ 1".into());
        }
        if self.end_time.is_some_and(|t| t.is_nan() || t <= 0.0) {
            return bad("end_time must be > 0".into());
        }
        let t = &self.thresholds;
        if !(t.residual_ratio > 0.0 && t.displacement_fraction > 0.0 && t.plastic_fraction >= 0.0) {
            return bad("thresholds must be positive".into());
        }
        Ok(())
    }
}

impl Default for RunSettings {
    fn default() -> Self {
        RunSettings::verify()
    }
}
