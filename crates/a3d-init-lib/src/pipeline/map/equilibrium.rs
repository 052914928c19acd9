//! Stage 5 of [`super::map`] for `--stress equilibrium`: the total stresses
//! that hold the model at rest under gravity in the runner's own discrete
//! equations, with the mapped pore pressures held fixed. The solve itself is
//! [`crate::mpm::equilibrium`]; this stage chooses each material's elastic
//! parameters (ν from K0 where asked and given, so that flat ground gives
//! σ'h = K0·σ'v), hands it the pore state the runner will start from (the
//! MPM-MIXED element state), and turns its effective stresses into total
//! stresses σ = σ′ + S·p (Bishop, as the MAPF holds them: Anura3D subtracts
//! S·p again when it reads them).

use super::MixedState;
use crate::model::{ComputationMethod, Dimension, MaterialPoint, MpState};
use crate::mpm::equilibrium::{self, EquilibriumOutcome, EquilibriumSettings};
use crate::mpm::{Elasticity, ReturnMap, SolidModel};
use crate::pipeline::{PipelineError, Project};
use crate::state::defaults::{AssumedDefault, Parameter};

/// How the equilibrium stress is solved for.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct EquilibriumOptions {
    /// ν = K0/(1 + K0) for every material whose GOM gives K0 (flat ground
    /// then gives σ'h = K0·σ'v); otherwise the GOM's ν.
    pub k0_consistent: bool,
    /// Out-of-balance force ratio the solve must reach.
    pub tolerance: f64,
    /// Most plastic iterations.
    pub max_iterations: usize,
}

impl Default for EquilibriumOptions {
    fn default() -> Self {
        let s = EquilibriumSettings::default();
        EquilibriumOptions {
            k0_consistent: true,
            tolerance: s.tolerance,
            max_iterations: s.max_iterations,
        }
    }
}

/// Where a material's ν came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PoissonFrom {
    /// ν = K0/(1 + K0) from the GOM's `$$K0_VALUE_SOLID`.
    K0,
    /// The GOM's `$$POISSON_RATIO`.
    Gom,
    /// The GOM gives neither (with `k0_consistent`) nor ν: 0.3 assumed.
    Default,
}

/// The elastic parameters one material got in the solve.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ElasticChoice {
    pub material: u32,
    pub name: String,
    /// `linear_elasticity`, `mohr_coulomb`, …
    pub model: String,
    /// E (kPa), the GOM's.
    pub young_modulus: f64,
    /// ν used in the solve.
    pub poisson_ratio: f64,
    pub poisson_from: PoissonFrom,
    /// The GOM's K0 and ν, where given.
    pub gom_k0: Option<f64>,
    pub gom_poisson_ratio: Option<f64>,
    /// The K0 of flat ground with this ν, ν/(1 − ν).
    pub flat_ground_k0: f64,
}

/// What report.json says about the equilibrium stress.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct EquilibriumReport {
    /// Why the stress source is `equilibrium`.
    pub chosen_because: String,
    pub k0_consistent: bool,
    pub tolerance: f64,
    pub materials: Vec<ElasticChoice>,
    /// 2D: MPs that Anura3D's MAPF reader (σ'zz := τxy) puts outside their
    /// yield surface although the solved state is inside it.
    pub sigma_zz_defect_outside_yield: Option<usize>,
    /// When no equilibrium exists: the largest factor the strengths can be
    /// divided by with a state at rest ([`strength_factor`]; below 1, the
    /// strengths they would need to be raised by 1/F). With the pore
    /// pressures held, the gravity multiplier `load_factor` says little (the
    /// water pushes whatever gravity does), this does.
    pub strength_factor: Option<StrengthFactor>,
    #[serde(flatten)]
    pub outcome: EquilibriumOutcome,
}

/// Largest ν used: K0 = 1 would ask for an incompressible ν = 0.5.
const MAX_POISSON: f64 = 0.49;

/// The solve's law and elastic parameters of every material of `project`
/// that has MPs (`None` for the others), ν as `k0_consistent` says.
pub fn laws(
    project: &Project,
    k0_consistent: bool,
) -> Result<(Vec<Option<SolidModel>>, Vec<ElasticChoice>), PipelineError> {
    let materials = &project.model.materials;
    let has_mps = project.materials_with_mps();
    let mut laws = Vec::with_capacity(materials.len());
    let mut choices = Vec::new();
    for (m, &used) in materials.iter().zip(&has_mps) {
        if !used {
            laws.push(None);
            continue;
        }
        let model_error = |what: String| {
            PipelineError::Model(format!("material {} `{}`: {what}", m.index, m.name))
        };
        let gom = SolidModel::from_material(m).map_err(|e| model_error(e.to_string()))?;
        let young = m.young_modulus.unwrap_or(f64::NAN);
        let (poisson, from) = match (k0_consistent, m.k0, m.poisson_ratio) {
            (true, Some(k0), _) => ((k0 / (1.0 + k0)).clamp(0.0, MAX_POISSON), PoissonFrom::K0),
            (_, _, Some(nu)) => (nu, PoissonFrom::Gom),
            _ => (
                Parameter::PoissonRatio.default_value(),
                PoissonFrom::Default,
            ),
        };
        let elasticity = Elasticity::from_young_poisson(young, poisson).ok_or_else(|| {
            model_error(format!(
                "E = {young} kPa and ν = {poisson} cannot be used for the equilibrium solve"
            ))
        })?;
        let plasticity = gom
            .plasticity
            .map(|map| ReturnMap::new(map.criterion, elasticity));
        laws.push(Some(SolidModel {
            elasticity,
            plasticity,
        }));
        choices.push(ElasticChoice {
            material: m.index,
            name: m.name.clone(),
            model: m.model.clone().unwrap_or_default(),
            young_modulus: young,
            poisson_ratio: poisson,
            poisson_from: from,
            gom_k0: m.k0,
            gom_poisson_ratio: m.poisson_ratio,
            flat_ground_k0: poisson / (1.0 - poisson),
        });
    }
    Ok((laws, choices))
}

/// Why `project` cannot be solved for equilibrium, if it cannot: an element
/// type or dimension the runner does not take, or a material with MPs whose
/// model or parameters it cannot use.
pub fn unsupported(project: &Project) -> Option<String> {
    let mesh = &project.model.mesh;
    let simplex = mesh.element_type.n_corners() == mesh.dimension.n_dim() + 1;
    if !simplex || mesh.dimension == Dimension::Cylindrical3D {
        return Some(format!(
            "the equilibrium solve does not take {} with {} elements",
            mesh.dimension.gom_name(),
            mesh.element_type.gom_name()
        ));
    }
    laws(project, true).err().map(|e| e.to_string())
}

/// The pore state the runner starts from: on MPM-MIXED models each element's
/// MPs carry one state, the volume-weighted mean (`Mean`) or the first MP's
/// (`PerMp`, what Anura3D keeps).
fn runner_pore_state(project: &Project, mixed: MixedState, states: &[MpState]) -> Vec<MpState> {
    let mut pore = states.to_vec();
    if project.method != ComputationMethod::MpmMixed {
        return pore;
    }
    match mixed {
        MixedState::Mean => {
            crate::state::mixed::average_elements(&project.model, &project.points, &mut pore)
        }
        MixedState::PerMp => crate::state::mixed::collapse_to_first(&project.points, &mut pore),
    }
    pore
}

/// Sets the total stress of every MP of `project` (pwp and saturation from
/// `states`) to the equilibrium stress: σ = σ′ + S·p with σ′ from
/// [`equilibrium::solve`]. On MPM-MIXED models with `Mean` the MPs' pore
/// state becomes their element's mean first (as the collapse would make it).
/// `chosen_because` says why the source is `equilibrium`. A state for which
/// no equilibrium exists is still set (the best one found); the report says so.
pub fn equilibrium_stress(
    project: &Project,
    states: &mut [MpState],
    mixed: MixedState,
    options: &EquilibriumOptions,
    chosen_because: String,
) -> Result<EquilibriumReport, PipelineError> {
    let (laws, materials) = laws(project, options.k0_consistent)?;
    let pore = runner_pore_state(project, mixed, states);
    if mixed == MixedState::Mean {
        states.copy_from_slice(&pore);
    }
    let settings = solve_settings(project, options);
    let outcome = equilibrium::solve(&project.model, &project.points, &pore, &laws, &settings)
        .map_err(crate::pipeline::check::runner::runner_error)?;
    for (s, effective) in states.iter_mut().zip(&outcome.effective) {
        s.total = *effective;
        for k in 0..3 {
            s.total[k] += s.saturation * s.pwp;
        }
    }
    let defect = (project.n_dim() == 2)
        .then(|| sigma_zz_defect_outside(&project.points, &laws, &outcome.effective));
    let strength_factor = if outcome.equilibrium {
        None
    } else {
        Some(strength_factor(project, &pore, options)?)
    };
    Ok(EquilibriumReport {
        chosen_because,
        k0_consistent: options.k0_consistent,
        tolerance: options.tolerance,
        materials,
        sigma_zz_defect_outside_yield: defect,
        strength_factor,
        outcome,
    })
}

/// The solve's settings for `project` (gravity, MPM-MIXED, submerged
/// weights from its CPS) with the tolerance and iterations of `options`.
fn solve_settings(project: &Project, options: &EquilibriumOptions) -> EquilibriumSettings {
    EquilibriumSettings {
        gravity: super::stress::gravity(project),
        tolerance: options.tolerance,
        max_iterations: options.max_iterations,
        mixed: project.method == ComputationMethod::MpmMixed,
        submerged_calculation: project
            .cps
            .as_ref()
            .is_some_and(|c| c.submerged_calculation()),
    }
}

/// The runner's out-of-balance force ratio of `states` at its first step
/// (what `verify` judges first), under the CPS's gravity.
fn first_step_ratio(project: &Project, states: &[MpState]) -> Result<f64, PipelineError> {
    let settings = crate::pipeline::check::runner::with_cps(
        crate::mpm::RunSettings::verify(),
        project.cps.as_ref(),
        None,
    );
    let mut simulation =
        crate::mpm::Simulation::new(&project.model, &project.points, states, &settings)
            .map_err(crate::pipeline::check::runner::runner_error)?;
    Ok(simulation.step().residual_ratio)
}

/// Where the solve found no state at rest: its best state must not be
/// further out of balance than the geostatic start. Both are measured
/// as `verify` measures them, by the runner's first step; when the
/// geostatic state (σv from the overburden, σh = K0·σ'v + S·p, the same pore
/// state) is closer to balance, `states` takes it. Returns a note, or a
/// warning when the geostatic state was taken.
pub fn no_worse_than_geostatic(
    project: &Project,
    positions: &[[f64; 3]],
    cloud: &super::interpolate::FemCloud<'_>,
    states: &mut [MpState],
    report: &EquilibriumReport,
) -> Result<Option<Result<String, String>>, PipelineError> {
    if report.outcome.equilibrium {
        return Ok(None);
    }
    let mut geostatic = states.to_vec();
    super::stress::geostatic_stress(project, positions, cloud, &mut geostatic)?;
    let solved = first_step_ratio(project, states)?;
    let start = first_step_ratio(project, &geostatic)?;
    if solved <= start {
        return Ok(Some(Ok(format!(
            "the failed solve's best state is closer to balance than the geostatic start (out-of-balance force ratio {solved:.3e} against {start:.3e} at the runner's first step): the MAPF holds the solve's"
        ))));
    }
    states.copy_from_slice(&geostatic);
    Ok(Some(Err(format!(
        "the failed solve's best state is further out of balance than the geostatic start (out-of-balance force ratio {solved:.3e} against {start:.3e} at the runner's first step): the MAPF holds the geostatic state (σh = K0·σ'v + S·p) instead"
    ))))
}

/// MPs inside their yield surface whose σ'zz := τxy (Anura3D's 2D MAPF
/// reader) puts them outside.
fn sigma_zz_defect_outside(
    points: &[MaterialPoint],
    laws: &[Option<SolidModel>],
    effective: &[[f64; 6]],
) -> usize {
    points
        .iter()
        .zip(effective)
        .filter(|(p, s)| {
            let Some(law) = laws.get(p.material as usize - 1).and_then(Option::as_ref) else {
                return false;
            };
            let mut held = **s;
            held[2] = held[3];
            law.is_admissible(s, true) && !law.is_admissible(&held, true)
        })
        .count()
}

/// The report's notes on an equilibrium solve.
pub fn notes(report: &EquilibriumReport) -> Vec<String> {
    let o = &report.outcome;
    let mut notes = vec![format!(
        "total stress from the equilibrium solve ({}): the state at rest under gravity in the runner's discrete equations (Anura3D's MP volumes, masses, fixities), pore pressures held, σ = σ' + S·p; out-of-balance force ratio {:.2e} (elastic solve {:.2e}), {} plastic iterations in {} load steps, {} MPs on their yield surface",
        report.chosen_because,
        o.residual_ratio,
        o.elastic_residual_ratio,
        o.plastic_iterations,
        o.load_steps,
        o.yielding_points
    )];
    for m in &report.materials {
        let from = match m.poisson_from {
            PoissonFrom::K0 => {
                format!("ν = K0/(1 + K0) from K0 = {}", m.gom_k0.unwrap_or(f64::NAN))
            }
            PoissonFrom::Gom => "the GOM's ν".to_string(),
            PoissonFrom::Default => "no K0 or ν in the GOM: ν = 0.3 assumed".to_string(),
        };
        notes.push(format!(
            "equilibrium solve: material {} `{}` ({}) E = {} kPa, ν = {:.4} ({from}; flat ground gives K0 = {:.4})",
            m.material, m.name, m.model, m.young_modulus, m.poisson_ratio, m.flat_ground_k0
        ));
    }
    notes
}

/// The materials whose ν was assumed (the GOM gives neither K0, with
/// `k0_consistent`, nor ν).
pub fn assumed_defaults(report: &EquilibriumReport) -> Vec<AssumedDefault> {
    report
        .materials
        .iter()
        .filter(|m| m.poisson_from == PoissonFrom::Default)
        .map(|m| AssumedDefault {
            material: m.material,
            name: m.name.clone(),
            parameter: Parameter::PoissonRatio,
            value: m.poisson_ratio,
        })
        .collect()
}

/// The warnings of an equilibrium solve: no equilibrium, and the 2D σ'zz
/// defect.
pub fn warnings(report: &EquilibriumReport) -> Vec<String> {
    let o = &report.outcome;
    let mut warnings = Vec::new();
    if !o.equilibrium {
        let elements: Vec<String> = o
            .yielding_elements
            .iter()
            .map(|e| e.id.to_string())
            .collect();
        let strength = match report.strength_factor.as_ref().map(|f| (f.holds, f.fails)) {
            Some((Some(holds), _)) => format!(
                "a state at rest exists with the strengths divided by up to F = {holds:.3} (the equilibrium solve's factor of safety)"
            ),
            Some((None, _)) => format!(
                "no state at rest even with the strengths multiplied by {}",
                1.0 / F_MIN
            ),
            None => format!("the state holds only up to {:.3} × gravity", o.load_factor),
        };
        warnings.push(format!(
            "NO EQUILIBRIUM under gravity with these pore pressures: {strength}; at full gravity the best state found leaves an out-of-balance force ratio of {:.2e}; {} MPs keep yielding (elements {}; MPs {:?}); the MAPF holds that best state or, where it is closer to balance, the geostatic start",
            o.residual_ratio,
            o.yielding_points,
            elements.join(", "),
            o.yielding_ids
        ));
    }
    if let Some(n) = report.sigma_zz_defect_outside_yield.filter(|&n| n > 0) {
        warnings.push(format!(
            "{n} MPs of the equilibrium state start outside their yield surface in Anura3D only because its 2D MAPF reader sets σ'zz := τxy (README: \"The 2D σ'zz defect\"); its first step return-maps them"
        ));
    }
    warnings
}

/// The largest strength factor at which the equilibrium solve still finds
/// rest ([`strength_factor`]).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StrengthFactor {
    /// The largest F (every `mohr_coulomb` strength divided by it, as
    /// strength reduction divides them) with a state at rest; `None` when
    /// even [`F_MIN`] has none.
    pub holds: Option<f64>,
    /// The smallest F without one; `None` when even [`F_MAX`] has one.
    pub fails: Option<f64>,
    /// Solves run.
    pub solves: usize,
    /// Wall-clock seconds of all the solves.
    pub seconds: f64,
}

/// Relative width [`strength_factor`] bisects the factor to.
pub const STRENGTH_FACTOR_TOLERANCE: f64 = 0.005;

/// Bounds of the search of [`strength_factor`].
pub const F_MIN: f64 = 1.0 / 16.0;
pub const F_MAX: f64 = 16.0;

/// The largest factor F by which the strengths (tan φ′, c′, σt; ψ ≤ φ′_F, as
/// [`crate::mpm::fos::reduce_material`]) can be divided with the
/// equilibrium solve still finding rest under full gravity, the pore state of
/// `states` held (the runner's start: pwp and saturation; the total stress
/// is not read). Bracketed from F = 1 by ×/÷ 1.25, then bisected to a
/// relative width of [`STRENGTH_FACTOR_TOLERANCE`]. The elasticity and the
/// solve's tolerance are those of `options`, as in [`equilibrium_stress`]
/// (whose failure the factor qualifies). This is the fourth measure of stability beside limit equilibrium,
/// its Davis variant and strength reduction: the implicit solve has no
/// inertia and no damping, so where it and the explicit trials differ the
/// difference is the trials' criterion or their dynamics.
pub fn strength_factor(
    project: &Project,
    states: &[MpState],
    options: &EquilibriumOptions,
) -> Result<StrengthFactor, PipelineError> {
    let started = std::time::Instant::now();
    let (laws, _) = laws(project, options.k0_consistent)?;
    let settings = solve_settings(project, options);
    let mut solves = 0;
    let mut rests = |factor: f64| -> Result<bool, PipelineError> {
        let mut reduced = laws.clone();
        for (law, material) in reduced.iter_mut().zip(&project.model.materials) {
            let (Some(law), Some(weaker)) =
                (law, crate::mpm::fos::reduce_material(material, factor))
            else {
                continue;
            };
            let criterion = SolidModel::from_material(&weaker)
                .map_err(|e| PipelineError::Model(e.to_string()))?
                .plasticity
                .map(|map| map.criterion);
            law.plasticity = criterion.map(|c| ReturnMap::new(c, law.elasticity));
        }
        solves += 1;
        let outcome =
            equilibrium::solve(&project.model, &project.points, states, &reduced, &settings)
                .map_err(crate::pipeline::check::runner::runner_error)?;
        Ok(outcome.equilibrium)
    };
    let (mut holds, mut fails) = (None, None);
    let mut factor: f64 = 1.0;
    loop {
        if rests(factor)? {
            holds = Some(factor);
            if fails.is_some() || factor >= F_MAX {
                break;
            }
            factor = (factor * 1.25).min(F_MAX);
        } else {
            fails = Some(factor);
            if holds.is_some() || factor <= F_MIN {
                break;
            }
            factor = (factor / 1.25).max(F_MIN);
        }
    }
    if let (Some(mut lo), Some(mut hi)) = (holds, fails) {
        while hi / lo - 1.0 > STRENGTH_FACTOR_TOLERANCE {
            let mid = 0.5 * (lo + hi);
            if rests(mid)? {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (holds, fails) = (Some(lo), Some(hi));
    }
    Ok(StrengthFactor {
        holds,
        fails,
        solves,
        seconds: started.elapsed().as_secs_f64(),
    })
}
