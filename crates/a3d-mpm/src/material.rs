//! Constitutive models of the MPM check: isotropic linear elasticity and
//! perfectly plastic Mohr–Coulomb with a tension cut-off, acting on the
//! effective stress in Anura3D's sign convention (tension positive).
//!
//! Stresses and strains are 6-vectors ordered xx, yy, zz, xy, yz, xz; strains
//! carry engineering shear (γ = 2ε). Plane strain uses the full 3D stress with
//! σzz tracked (εzz = γyz = γxz = 0), so the return mapping always sees three
//! principal stresses.
//!
//! The Mohr–Coulomb return works in principal stress space with σ1 ≥ σ2 ≥ σ3
//! (σ3 the most compressive), as in de Souza Neto, Perić & Owen (2008, ch. 8)
//! and Clausen, Damkilde & Andersen (2006): the yield planes are linear in the
//! principal stresses and the hardening is nil, so every return is the closed-
//! form solution of a 1×1, 2×2 or 3×3 linear system. Every independent set of
//! up to three active surfaces (main plane, the two edges, the apex, the
//! tension cut-off planes and their corners) is tried, smallest first, and the
//! first one that satisfies the Kuhn–Tucker conditions (all multipliers ≥ 0,
//! principal order kept, no yield function positive) is taken; the hydrostatic
//! vertex is the last resort where more surfaces meet than a 3-set can express. This file leaves out strain softening, hardening
//! and objective stress rates; it knows nothing about meshes or time steps.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

use super::MpmError;
use super::elasticity::Elasticity;
use super::mohr_coulomb::{MohrCoulomb, ReturnKind, ReturnMap};
use a3d_model::Material;

/// The constitutive model of one material.
#[derive(Clone, Debug)]
pub struct SolidModel {
    pub elasticity: Elasticity,
    /// The Mohr–Coulomb return (criterion and precomputed sets), if plastic.
    pub plasticity: Option<ReturnMap>,
}

impl SolidModel {
    /// Builds the model of a GOM material: `linear_elasticity`, `mohr_coulomb`,
    /// or `strain_softening_mohr_coulomb` (checked at its peak strength, read
    /// from the `PEAK_*` properties; softening is not modelled).
    pub fn from_material(material: &Material) -> Result<SolidModel, MpmError> {
        let missing = |property: &'static str| MpmError::MissingProperty {
            material: material.index,
            property,
        };
        let model = material.model.as_deref().unwrap_or("");
        let young = material
            .young_modulus
            .ok_or_else(|| missing("YOUNG_MODULUS"))?;
        let poisson = material
            .poisson_ratio
            .ok_or_else(|| missing("POISSON_RATIO"))?;
        let elasticity =
            Elasticity::from_young_poisson(young, poisson).ok_or(MpmError::InvalidProperty {
                material: material.index,
                reason: format!(
                    "E = {young} kPa and ν = {poisson} must satisfy E > 0, −1 < ν < 0.5"
                ),
            })?;
        let plasticity = match model {
            "linear_elasticity" => None,
            "mohr_coulomb" => {
                let phi = material
                    .friction_angle
                    .ok_or_else(|| missing("FRICTION_ANGLE"))?;
                let c = material.cohesion.ok_or_else(|| missing("COHESION"))?;
                let psi = material.dilatancy_angle.unwrap_or(0.0);
                let criterion =
                    mohr_coulomb_or_error(material.index, phi, c, psi, material.tensile_strength)?;
                Some(ReturnMap::new(criterion, elasticity))
            }
            "strain_softening_mohr_coulomb" => {
                let phi = property(material, "PEAK_FRICTION_ANGLE")
                    .ok_or_else(|| missing("PEAK_FRICTION_ANGLE"))?;
                let c =
                    property(material, "PEAK_COHESION").ok_or_else(|| missing("PEAK_COHESION"))?;
                let psi = property(material, "PEAK_DILATANCY_ANGLE").unwrap_or(0.0);
                Some(ReturnMap::new(
                    mohr_coulomb_or_error(material.index, phi, c, psi, None)?,
                    elasticity,
                ))
            }
            other => {
                return Err(MpmError::UnsupportedMaterialModel {
                    material: material.index,
                    model: other.to_string(),
                });
            }
        };
        Ok(SolidModel {
            elasticity,
            plasticity,
        })
    }

    /// Elastic predictor and plastic corrector for one strain increment.
    #[inline]
    pub fn update(
        &self,
        stress: &mut [f64; 6],
        strain: &[f64; 6],
        plane_strain: bool,
    ) -> ReturnKind {
        self.elasticity.add_increment(stress, strain);
        match &self.plasticity {
            None => ReturnKind::Elastic,
            Some(map) => map.return_stress(stress, plane_strain),
        }
    }

    /// True when the stress lies inside or on the yield surface (within a
    /// relative tolerance of 1e-9 of the stress magnitude).
    pub fn is_admissible(&self, stress: &[f64; 6], plane_strain: bool) -> bool {
        match &self.plasticity {
            None => true,
            Some(map) => {
                let mc = &map.criterion;
                let scale = stress
                    .iter()
                    .fold(mc.cohesion, |m, v| m.max(v.abs()))
                    .max(1e-6);
                mc.yield_value(stress, plane_strain) <= 1e-9 * scale
            }
        }
    }
}

fn mohr_coulomb_or_error(
    index: u32,
    phi: f64,
    c: f64,
    psi: f64,
    tensile: Option<f64>,
) -> Result<MohrCoulomb, MpmError> {
    MohrCoulomb::new(phi, c, psi, tensile).ok_or(MpmError::InvalidProperty {
        material: index,
        reason: format!(
            "Mohr–Coulomb needs 0 ≤ φ < 90°, 0 ≤ ψ < 90°, c ≥ 0; got φ = {phi}, ψ = {psi}, c = {c}"
        ),
    })
}

/// A numeric property of the material record by keyword, ignoring `$$` and case.
pub(crate) fn property(material: &Material, keyword: &str) -> Option<f64> {
    material
        .properties
        .iter()
        .find(|(k, _)| {
            k.trim()
                .trim_start_matches("$$")
                .eq_ignore_ascii_case(keyword)
        })
        .and_then(|(_, v)| v.split_whitespace().next()?.parse::<f64>().ok())
}
