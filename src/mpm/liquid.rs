//! The water of Anura3D's two-phase materials, for the runner ([`super::step`]).
//!
//! * **Coupled** (`saturated_material_coupled`): the two-phase single-point
//!   formulation. Each MP carries the solid's velocity and the liquid's; per
//!   unit volume of the mixture
//!   - liquid: ρw·a_w = −∇p_w + ρw·g − (n·μ/κ)(v_w − v_s)
//!     (p_w pressure-positive; Darcy's drag with the intrinsic permeability κ
//!     and the dynamic viscosity μ, n·μ/κ = n·ρw·g/k);
//!   - mixture: (1 − n)ρs·a_s + n·ρw·a_w = ∇·σ + ρ_sat·g, σ = σ′ + p (Anura3D's
//!     sign, p negative in compression);
//!   - pore pressure: Δp = (K_w/n)·[(1 − n)·Δε_v,s + n·Δε_v,w], the liquid's
//!     bulk modulus over porosity on both phases' volumetric strains.
//!
//!   Lumped nodal masses; the drag is taken implicitly in the liquid's nodal
//!   update (unconditionally stable for any permeability); the liquid's
//!   velocity is held at zero where the GOM fixes it
//!   (`$$START_FIXITY_*_LIQUID`, an impermeable boundary) and a free boundary
//!   drains (p = 0 there, the weak form's natural condition).
//! * **Undrained effective** (`saturated_material_undrained_effective`), one
//!   phase: Δp = (K_w/n)·Δε_v on the solid's strain, σ′ + p in the internal
//!   force, K_w/n from the undrained Poisson's ratio as the kernel forms it.
//!   (The kernel's `StressSolid` adds the increment twice per step,
//!   `ExternalSoilModel.for` 113–124 and 147–150, so its p moves by
//!   2·(K_w/n)·Δε_v; this runner follows the closed form.)
//!
//! Everything else keeps its pore pressure frozen (drained).

use super::MpmError;
use crate::model::{Material, RetentionCurve};

/// How an MP's pore pressure evolves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Water {
    /// Frozen (dry, drained, or the runner asked to hold it).
    Frozen,
    /// Δp = (K_w/n)·Δε_v of the solid (undrained effective).
    Undrained { bulk_over_n: f64 },
    /// The two-phase single-point formulation.
    Coupled(Coupled),
}

/// The constants of a coupled MP.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Coupled {
    /// K_w / n (kPa).
    pub bulk_over_n: f64,
    /// Porosity n.
    pub porosity: f64,
    /// Liquid density ρw (t/m³).
    pub density: f64,
    /// Drag per unit volume of mixture at full saturation, n·μ/κ
    /// (kPa·s/m² = t/(m³·s)).
    pub drag: f64,
    /// Unsaturated (`unsaturated_material_2phase_suction`): the retention
    /// curve; `None` for saturated coupled materials.
    pub retention: Option<RetentionCurve>,
}

/// The formulation of each material as the runner ran it, for reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Formulation {
    /// One phase, pore pressure frozen (dry or drained materials, or every
    /// material under `--drained`).
    Drained,
    /// One phase, pore pressure from the solid's volumetric strain.
    UndrainedEffective,
    /// Two phases, single point: the water flows.
    Coupled,
}

/// A numeric property of the material record by keyword.
fn property(material: &Material, keyword: &str) -> Option<f64> {
    super::material::property(material, keyword)
}

impl Water {
    /// The water of `material`; `frozen` holds every pore pressure;
    /// `unsaturated` lets `unsaturated_material_2phase_suction` run two-phase
    /// (experimental, see [`super::RunSettings::unsaturated_two_phase`]).
    pub fn of(material: &Material, frozen: bool, unsaturated: bool) -> Result<Water, MpmError> {
        if frozen || (material.is_unsaturated() && !unsaturated) {
            return Ok(Water::Frozen);
        }
        let kind = material.material_type.as_str();
        let need = |keyword: &'static str| {
            property(material, keyword)
                .filter(|v| v.is_finite())
                .ok_or(MpmError::MissingProperty {
                    material: material.index,
                    property: keyword,
                })
        };
        let positive = |keyword: &'static str| -> Result<f64, MpmError> {
            let v = need(keyword)?;
            if v > 0.0 {
                Ok(v)
            } else {
                Err(MpmError::InvalidProperty {
                    material: material.index,
                    reason: format!("{keyword} {v} must be > 0"),
                })
            }
        };
        let porosity = || -> Result<f64, MpmError> {
            match material.porosity {
                Some(n) if n > 0.0 && n < 1.0 => Ok(n),
                other => Err(MpmError::InvalidProperty {
                    material: material.index,
                    reason: format!("porosity {other:?} must be in (0, 1)"),
                }),
            }
        };
        match kind {
            "saturated_material_undrained_effective" => {
                // The kernel forms K_w from the undrained Poisson's ratio at
                // read time (`ReadMaterialData.FOR`):
                // K_w/n = (ν_u − ν)·E / ((1 − 2ν_u)(1 + ν)(1 − 2ν)).
                let (Some(nu_u), Some(e), Some(nu)) = (
                    property(material, "POISSON_RATIO_UNDRAINED"),
                    material.young_modulus,
                    material.poisson_ratio,
                ) else {
                    return Ok(Water::Frozen);
                };
                let bulk_over_n =
                    (nu_u - nu) * e / ((1.0 - 2.0 * nu_u) * (1.0 + nu) * (1.0 - 2.0 * nu));
                if !(nu_u > nu && nu_u < 0.5 && bulk_over_n.is_finite() && bulk_over_n > 0.0) {
                    return Err(MpmError::InvalidProperty {
                        material: material.index,
                        reason: format!(
                            "POISSON_RATIO_UNDRAINED {nu_u} must lie between ν = {nu} and 0.5"
                        ),
                    });
                }
                Ok(Water::Undrained { bulk_over_n })
            }
            "saturated_material_coupled" | "unsaturated_material_2phase_suction" => {
                // Without the liquid's constants (a record made by hand, not
                // by Anura3D's GUI) the water cannot flow: held, and the
                // report says drained.
                let liquid = [
                    "INTRINSIC_PERMEABILITY_LIQUID",
                    "DYNAMIC_VISCOSITY_LIQUID",
                    "BULK_MODULUS_LIQUID",
                ];
                if liquid.iter().any(|k| property(material, k).is_none()) {
                    return Ok(Water::Frozen);
                }
                let n = porosity()?;
                let kappa = positive("INTRINSIC_PERMEABILITY_LIQUID")?;
                let mu = positive("DYNAMIC_VISCOSITY_LIQUID")?;
                let retention = if kind == "unsaturated_material_2phase_suction" {
                    // Only a constant conductivity (k_r = 1) is modelled; the
                    // others keep the pore pressure frozen.
                    let constant = material
                        .properties
                        .iter()
                        .find(|(k, _)| k.trim() == "$$HYDR_CONDUCTIVITY_CURVE")
                        .is_none_or(|(_, v)| v.trim().eq_ignore_ascii_case("constant"));
                    match material.retention {
                        Some(curve) if constant => Some(curve),
                        _ => return Ok(Water::Frozen),
                    }
                } else {
                    None
                };
                Ok(Water::Coupled(Coupled {
                    bulk_over_n: positive("BULK_MODULUS_LIQUID")? / n,
                    porosity: n,
                    density: material.density_liquid.unwrap_or(1000.0) / 1000.0,
                    drag: n * mu / kappa,
                    retention,
                }))
            }
            _ => Ok(Water::Frozen),
        }
    }

    pub fn formulation(&self) -> Formulation {
        match self {
            Water::Frozen => Formulation::Drained,
            Water::Undrained { .. } => Formulation::UndrainedEffective,
            Water::Coupled(_) => Formulation::Coupled,
        }
    }

    /// K_w/n where the pore pressure follows the strain, else 0.
    pub fn bulk_over_n(&self) -> f64 {
        match self {
            Water::Frozen => 0.0,
            Water::Undrained { bulk_over_n } => *bulk_over_n,
            Water::Coupled(c) => c.bulk_over_n,
        }
    }
}
