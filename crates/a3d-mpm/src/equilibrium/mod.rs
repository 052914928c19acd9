//! The equilibrium solve: the effective stresses σ′ at the material points
//! for which the model is at rest under gravity in the runner's own discrete
//! equations, with the pore pressures held fixed.
//!
//! The explicit runner ([`super::step`]) balances, at every free node,
//! f_ext = Σ_p N w_p g against f_int = −Σ_p V_p B_pᵀσ_p, where σ is σ′ plus
//! the pore-water part the kernel's analysis adds on the normals and w_p the
//! weight it pulls on ([`super::loading`]: Bishop's S·p and the mixture's
//! weight in a multiphase analysis; σ′ alone with the dry or buoyant weight
//! in a one-phase one). This module finds σ′ that makes that balance hold
//! exactly: it assembles the stiffness K = Σ V Bᵀ D B with the MPs as
//! quadrature points (`system`: the same grid, fixities, B, volumes and
//! masses as the runner), solves K u = f_ext − f_pore once with a sparse
//! Cholesky factor (`sparse`) for gravity switched on from a stress-free
//! state, σ′ = D B u, and, where that leaves MPs outside their yield surface,
//! continues with an implicit load ramp and the runner's return map
//! ([`solve`]). The outcome names the residual reached (measured as `verify`
//! measures its first step), the iterations, and where the state keeps
//! yielding when no equilibrium exists.
//!
//! Pure computation: no I/O, nothing printed. The choice of the elastic
//! parameters (ν from K0, …) is the caller's, through the laws it passes.

mod ordering;
mod solve;
mod sparse;
mod system;

use super::MpmError;
use super::material::SolidModel;
use super::run::ElementScore;
use a3d_element::{Element, ElementVisitor, with_element};
use a3d_model::{AnuraModel, Dimension, MaterialPoint, MpState};

/// How the equilibrium solve runs.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct EquilibriumSettings {
    /// Gravitational acceleration g (m/s²), acting along −y.
    pub gravity: f64,
    /// The out-of-balance force ratio ‖f_ext + f_int‖/‖f_ext‖ the solve must
    /// reach (the elastic solve reaches round-off; plastic iterations stop
    /// here).
    pub tolerance: f64,
    /// Most plastic iterations (back-substitutions) in all load steps.
    pub max_iterations: usize,
    /// MPM-MIXED: every element is integrated as one point carrying its
    /// first MP's state (matters in 2D axisymmetry, where the hoop term
    /// differs between MPs).
    pub mixed: bool,
    /// The CPS's `$$SUBMERGED_CALCULATION 1` ([`super::loading`]).
    pub submerged_calculation: bool,
}

impl Default for EquilibriumSettings {
    fn default() -> Self {
        EquilibriumSettings {
            gravity: a3d_model::DEFAULT_GRAVITY,
            tolerance: 1e-8,
            max_iterations: 3000,
            mixed: false,
            submerged_calculation: false,
        }
    }
}

/// What the equilibrium solve found.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct EquilibriumOutcome {
    /// True when the residual reached the tolerance at full gravity with
    /// every MP on or inside its yield surface.
    pub equilibrium: bool,
    /// ‖f_ext + f_int‖/‖f_ext‖ of the returned state, measured per MP as the
    /// runner measures its first step.
    pub residual_ratio: f64,
    /// The same ratio for the elastic solution, before any return mapping.
    pub elastic_residual_ratio: f64,
    /// The largest gravity multiplier (≤ 1) under which equilibrium was found.
    pub load_factor: f64,
    /// Plastic iterations (one back-substitution each) in all load steps.
    pub plastic_iterations: usize,
    pub load_steps: usize,
    /// MPs whose last stress update returned to the yield surface: the
    /// plastic zone of an equilibrium, or where it keeps yielding otherwise.
    pub yielding_points: usize,
    /// 1-based ids of the first (up to 10) of those MPs.
    pub yielding_ids: Vec<u32>,
    /// Up to 10 elements with the most of those MPs (value: their count).
    pub yielding_elements: Vec<ElementScore>,
    /// Up to 10 elements with the largest remaining unbalanced force (kN;
    /// kN/m in plane strain, kN/rad in 2D axisymmetry).
    pub worst_residual_elements: Vec<ElementScore>,
    /// Unknowns (free directions of nodes carrying mass).
    pub unknowns: usize,
    /// Stored entries of K (lower triangle) and of its Cholesky factor.
    pub stiffness_entries: usize,
    pub factor_entries: usize,
    /// Seconds: assembly of K, its factorisation, the elastic solve, the
    /// plastic iterations.
    pub assembly_s: f64,
    pub factorisation_s: f64,
    pub elastic_solve_s: f64,
    pub plastic_s: f64,
    /// Per MP: the effective stress σ′ (xx, yy, zz, xy, yz, xz; kPa).
    #[serde(skip)]
    pub effective: Vec<[f64; 6]>,
}

/// Solves for the effective stresses that hold `model` at rest under gravity:
/// `points` are its MPs with the pore state of `states` (pwp and saturation;
/// the total stress is not read), `laws` the constitutive law of each material
/// (index = material − 1; `None` where no MP uses it), whose elasticity is the
/// solve's. Linear simplices only, as the runner.
pub fn solve(
    model: &AnuraModel,
    points: &[MaterialPoint],
    states: &[MpState],
    laws: &[Option<SolidModel>],
    settings: &EquilibriumSettings,
) -> Result<EquilibriumOutcome, MpmError> {
    super::check_points(points, states)?;
    let valid = settings.gravity >= 0.0 && settings.gravity.is_finite() && settings.tolerance > 0.0;
    if !valid {
        return Err(MpmError::InvalidSettings(format!(
            "gravity {} must be finite and ≥ 0, tolerance {} > 0",
            settings.gravity, settings.tolerance
        )));
    }
    with_element(
        model.mesh.element_type,
        Visit {
            model,
            points,
            states,
            laws,
            settings,
        },
    )
}

struct Visit<'a> {
    model: &'a AnuraModel,
    points: &'a [MaterialPoint],
    states: &'a [MpState],
    laws: &'a [Option<SolidModel>],
    settings: &'a EquilibriumSettings,
}

impl ElementVisitor for Visit<'_> {
    type Output = Result<EquilibriumOutcome, MpmError>;
    fn visit<const D: usize, const NC: usize, E: Element<D, NC>>(self) -> Self::Output {
        let dimension = self.model.mesh.dimension;
        if !E::AFFINE || dimension.n_dim() != D || dimension == Dimension::Cylindrical3D {
            return Err(MpmError::Unsupported(format!(
                "{} with {} elements (the equilibrium solve takes what the runner takes: \
                 2D-plane_strain and 2D-axisymmetric with triangular_3-noded, 3D-cartesian \
                 with tetrahedral_old)",
                dimension.gom_name(),
                E::TYPE.gom_name()
            )));
        }
        let system = system::System::<D, NC>::new::<E>(
            self.model,
            self.points,
            self.states,
            self.laws,
            self.settings,
        )?;
        let solved = solve::solve(&system, self.settings)?;
        Ok(outcome(self.model, self.points, &system, solved))
    }
}

/// The per-MP outcome of a solved system.
fn outcome<const D: usize, const NC: usize>(
    model: &AnuraModel,
    points: &[MaterialPoint],
    system: &system::System<D, NC>,
    solved: solve::Solved,
) -> EquilibriumOutcome {
    let effective: Vec<[f64; 6]> = system
        .points
        .iter()
        .map(|p| solved.stress[p.group as usize])
        .collect();
    let (residual_ratio, per_node) = system.verify_residual(&effective);
    let mut counts = vec![0.0; model.mesh.n_elements()];
    let mut yielding_ids = Vec::new();
    let mut yielding_points = 0;
    for (point, p) in points.iter().zip(&system.points) {
        if solved.yielding[p.group as usize] {
            yielding_points += 1;
            counts[p.element as usize] += 1.0;
            if yielding_ids.len() < 10 {
                yielding_ids.push(point.id);
            }
        }
    }
    let residuals = system.element_residuals(&per_node);
    let mut grid_to_mesh = residuals;
    grid_to_mesh.truncate(model.mesh.n_elements());
    EquilibriumOutcome {
        equilibrium: solved.converged && solved.load_factor >= 1.0,
        residual_ratio,
        elastic_residual_ratio: solved.elastic_ratio,
        load_factor: solved.load_factor,
        plastic_iterations: solved.iterations,
        load_steps: solved.load_steps,
        yielding_points,
        yielding_ids,
        yielding_elements: super::run::top_ten(model, &counts),
        worst_residual_elements: super::run::top_ten(model, &grid_to_mesh),
        unknowns: system.n_free,
        stiffness_entries: solved.stiffness_nnz,
        factor_entries: solved.factor_nnz,
        assembly_s: solved.assembly_s,
        factorisation_s: solved.factor_s,
        elastic_solve_s: solved.elastic_s,
        plastic_s: solved.plastic_s,
        effective,
    }
}
