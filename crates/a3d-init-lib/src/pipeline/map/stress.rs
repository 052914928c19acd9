//! Stage 5 of [`super::map`]: the MPs' states from the mapped fields. The
//! pore-water pressure and saturation, the total stress from the FEM (σzz by
//! plane-strain elasticity where a 2D FEM lacks it), from the overburden
//! ([`geostatic_stress`]) or zero; dry materials lose their pore water, and
//! MPs the kernel skipped get a zero state. The physics is in [`crate::state`].

use super::{FemCloud, StressSource};
use crate::kernel::mapper::{MapSettings, OutsidePolicy, PointStatus};
use crate::model::{MpState, Quantity, StressComponent};
use crate::pipeline::{PipelineError, Project};
use crate::state::defaults::{self, AssumedDefault, Parameter};
use crate::state::{self, geostatic};

/// The MPs' states with what the report says about them.
#[derive(Clone, Debug)]
pub struct DerivedStress {
    /// The state of each MP, in MP order.
    pub states: Vec<MpState>,
    pub notes: Vec<String>,
    pub warnings: Vec<String>,
}

/// Gravity (m/s²): the CPS's, or Anura3D's default without a CPS.
pub fn gravity(project: &Project) -> f64 {
    project.gravity()
}

/// True when the stress `source` `fem` on a 2D `project` lacks σzz among the
/// mapped `quantities`: it then comes from plane-strain elasticity.
fn plane_strain_zz(project: &Project, source: StressSource, quantities: &[Quantity]) -> bool {
    source == StressSource::Fem
        && project.n_dim() == 2
        && !quantities.contains(&Quantity::TotalStress(StressComponent::Zz))
}

/// The material defaults ([`crate::state::defaults`]) the stress of
/// `project`'s MPs relies on, for the resolved stress `source` and the mapped
/// `quantities`: K0 for the geostatic stress, ν for a plane-strain σzz; only
/// materials that have MPs.
pub fn assumed_defaults(
    project: &Project,
    source: StressSource,
    quantities: &[Quantity],
) -> Vec<AssumedDefault> {
    let mut parameters = Vec::new();
    if source == StressSource::Geostatic {
        parameters.push(Parameter::K0);
    }
    if plane_strain_zz(project, source, quantities) {
        parameters.push(Parameter::PoissonRatio);
    }
    let materials = &project.model.materials;
    let has_mps = project.materials_with_mps();
    defaults::assumed(materials, &parameters)
        .into_iter()
        .filter(|d| has_mps[d.material as usize - 1])
        .collect()
}

/// The report's note on a default the stress relies on.
pub fn default_note(assumed: &AssumedDefault) -> String {
    match assumed.parameter {
        Parameter::K0 => {
            format!("{assumed} for its geostatic horizontal stress, σh = K0·σ'v + S·p")
        }
        Parameter::PoissonRatio => {
            format!("{assumed} for its plane-strain σzz, σ'zz = ν(σ'xx + σ'yy)")
        }
    }
}

/// The state of each MP of `project` from `values`, the mapped rows of
/// `quantities` (row-major, one row per MP; freed once read), for the resolved
/// stress `source`: pwp and saturation, and with `fem` the mapped total stress.
/// Dry materials then lose their pore water. With `geostatic` the total stress
/// is left at zero for [`geostatic_stress`].
pub fn derive_stress(
    project: &Project,
    source: StressSource,
    quantities: &[Quantity],
    values: Vec<f64>,
) -> DerivedStress {
    let n_fields = quantities.len();
    let column = |q: Quantity| quantities.iter().position(|x| *x == q);
    let plane_strain_zz = plane_strain_zz(project, source, quantities);
    let mut states: Vec<MpState> = Vec::with_capacity(project.points.len());
    for (i, p) in project.points.iter().enumerate() {
        let material = project.model.materials.get(p.material as usize - 1);
        let row = &values[i * n_fields..(i + 1) * n_fields];
        let pwp = column(Quantity::Pwp).map_or(0.0, |k| row[k]);
        let mut total = [0.0; 6];
        if source == StressSource::Fem {
            for c in StressComponent::ALL {
                if let Some(k) = column(Quantity::TotalStress(c)) {
                    total[c.index()] = row[k];
                }
            }
            if plane_strain_zz {
                // Plane strain, elastic: σ'zz = ν(σ'xx + σ'yy).
                let s = state::saturation(material, pwp);
                let nu = Parameter::PoissonRatio.value(material);
                total[2] = nu * (total[0] - s * pwp + total[1] - s * pwp) + s * pwp;
            }
        }
        states.push(MpState {
            pwp,
            total,
            saturation: state::saturation(material, pwp),
        });
    }
    // The mapped rows are in `states` now.
    drop(values);
    let mut notes = Vec::new();
    if plane_strain_zz {
        notes.push("σzz was not in the FEM file: set from plane-strain elasticity, σ'zz = ν(σ'xx + σ'yy), with each material's ν".into());
    }
    let dropped = state::drop_pore_water_of_dry_materials(
        &project.model.materials,
        &project.points,
        &mut states,
    );
    if !dropped.is_empty() {
        let list: Vec<String> = dropped
            .iter()
            .map(|d| {
                format!(
                    "{} `{}` ({} MPs, |pwp| up to {:.3} kPa)",
                    d.material, d.name, d.points, d.max_abs_pwp
                )
            })
            .collect();
        let why = if project.cbgeo.is_some() {
            "CB-Geo's single phase carries no pore pressure, and its stresses file gets the total stress"
        } else {
            "as Anura3D would otherwise subtract the MAPF's Pwp from their stress"
        };
        notes.push(format!(
            "FEM pore pressure dropped on MPs of materials without a liquid phase (dry_material): {}; they carry pwp = 0 and σ' = σ, {why}",
            list.join(", ")
        ));
    }
    let mut warnings = Vec::new();
    if source == StressSource::Zero {
        warnings.push(
            "the stress source is zero: all total stresses are 0; the MPs start unstressed".into(),
        );
    }
    DerivedStress {
        states,
        notes,
        warnings,
    }
}

/// Sets the total stress of every MP (at `positions`) from the overburden of
/// `project`'s materials along the vertical: γ per element averaged over a
/// few points inside it, with the pwp `cloud` maps there (nearest node where
/// none is in reach), then σh = K0·σ'v + S·p with each MP's pwp and
/// saturation from `states`. Returns the report's notes.
pub fn geostatic_stress(
    project: &Project,
    positions: &[[f64; 3]],
    cloud: &FemCloud<'_>,
    states: &mut [MpState],
) -> Result<Vec<String>, PipelineError> {
    let g = gravity(project);
    let model = &project.model;
    let active = |e: usize| model.element_material[e] > 0;
    // γ per element, averaged over a few points inside it (pwp mapped there).
    let (sample_pts, sample_elements) = geostatic::element_samples(&model.mesh, active);
    let sample_groups: Option<Vec<u32>> = cloud.groups.map(|_| {
        sample_elements
            .iter()
            .map(|&e| model.element_material[e as usize])
            .collect()
    });
    let sample_settings = MapSettings {
        outside: OutsidePolicy::Nearest,
        ..cloud.settings
    };
    let sampled = cloud.map_with(&sample_pts, sample_groups.as_deref(), &sample_settings)?;
    let n_fields = cloud.quantities.len();
    let k_pwp = cloud.column(Quantity::Pwp).unwrap_or(0);
    let mut gamma_sum = vec![(0.0f64, 0usize); model.mesh.n_elements()];
    for (s, &e) in sample_elements.iter().enumerate() {
        let m = model.material_of(e as usize);
        let p = sampled.values[s * n_fields + k_pwp];
        let saturation = match m {
            Some(m) if p > 0.0 && !m.is_unsaturated() => 0.0,
            other => state::saturation(other, p),
        };
        let slot = &mut gamma_sum[e as usize];
        slot.0 += m.map_or(0.0, |m| m.gamma_at_saturation(saturation, g));
        slot.1 += 1;
    }
    let gamma: Vec<f64> = gamma_sum
        .iter()
        .map(|&(sum, n)| if n > 0 { sum / n as f64 } else { 0.0 })
        .collect();
    let sigma_v = geostatic::overburden(&model.mesh, active, &gamma, positions);
    for (i, p) in project.points.iter().enumerate() {
        let m = model.materials.get(p.material as usize - 1);
        let k0 = Parameter::K0.value(m);
        states[i].total =
            geostatic::geostatic_tensor(sigma_v[i], k0, states[i].pwp, states[i].saturation);
    }
    Ok(vec![format!(
        "total stress from the overburden of the model's materials along the vertical (g = {g} m/s²; γ per element, averaged over 4–5 points inside it: saturated below the water table, from the retention curve or dry above), σh = K0·σ'v + S·p with each material's K0"
    )])
}

/// MPs the kernel skipped (status in `status`, in MP order) keep a zero
/// state in the outputs rather than NaN.
pub fn zero_skipped(states: &mut [MpState], status: &[PointStatus]) {
    for (s, st) in states.iter_mut().zip(status) {
        if *st == PointStatus::Skipped {
            *s = MpState {
                pwp: 0.0,
                total: [0.0; 6],
                saturation: 1.0,
            };
        }
    }
}
