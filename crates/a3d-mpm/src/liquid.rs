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
use a3d_model::{Material, RetentionCurve};

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
    /// How the conductivity follows S (unsaturated materials).
    pub conductivity: Conductivity,
}

/// The GOM's `$$HYDR_CONDUCTIVITY_CURVE`: k = k_sat·k_r(S), as the kernel's
/// `DynUpdateParticleHydraulicConductivity*` form it (with S, not the
/// effective saturation; only while S < 1, so k keeps its last value when an
/// MP saturates again).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Conductivity {
    /// k_r = 1.
    Constant,
    /// k_r = S^r.
    Hillel { r: f64 },
    /// Mualem's k_r = √S·(1 − (1 − S^(1/λ))^λ)².
    Mualem { lambda: f64 },
}

/// The smallest relative conductivity the drag divides by (a fully dry MP's
/// water does not move).
const MIN_RELATIVE_CONDUCTIVITY: f64 = 1e-12;

impl Conductivity {
    /// k_r at saturation `s` (1 for s ≥ 1), at least 1e-12.
    pub fn relative(&self, s: f64) -> f64 {
        if s >= 1.0 {
            return 1.0;
        }
        let s = s.max(0.0);
        let kr = match *self {
            Conductivity::Constant => 1.0,
            Conductivity::Hillel { r } => s.powf(r),
            Conductivity::Mualem { lambda } => {
                let w = 1.0 - (1.0 - s.powf(1.0 / lambda)).powf(lambda);
                s.sqrt() * w * w
            }
        };
        if kr.is_finite() {
            kr.max(MIN_RELATIVE_CONDUCTIVITY)
        } else {
            MIN_RELATIVE_CONDUCTIVITY
        }
    }
}

impl Coupled {
    /// The pore-pressure increment of an MP at pressure `pwp` and saturation
    /// `saturation` whose water asks for the volume `demand` per unit volume
    /// of the mixture in this step (tension positive). It solves the storage
    /// equation with the retention curve taken secant over the step:
    ///
    ///   (n·S/K_w)·Δp − n·[S(p + Δp) − S(p)] = demand
    ///
    /// The kernel takes dS/dp at the start of the step instead. Its tangent
    /// is exact for a saturated material and for small steps, but where S
    /// turns from 1 to partial it is flat, so a pore pressure that crosses 0
    /// is driven by K_w/n over the whole step. At the demo slope's water table
    /// that makes the result depend on Δt: the largest displacement after
    /// 0.2 s is 15.8 mm at Courant 0.9 and 25.6 mm at 0.1 (docs/two-phase.md).
    /// Secant, it is 25.7 mm at both. S(p) falls as p rises, so the left-hand
    /// side rises with Δp and the root is unique: safeguarded Newton, within
    /// the bracket between 0 and demand/(n·S/K_w).
    pub(crate) fn pressure_increment(&self, pwp: f64, saturation: f64, demand: f64) -> f64 {
        let Some(curve) = self.retention else {
            return self.bulk_over_n * demand;
        };
        // n·S/K_w, the water's own compressibility (S ≥ 1e-6 keeps a dry MP
        // solvable).
        let a = saturation.max(1e-6) / self.bulk_over_n;
        let full = demand / a;
        if demand == 0.0 || !full.is_finite() {
            return 0.0;
        }
        let n = self.porosity;
        let s0 = curve.anura3d_saturation(pwp).1;
        let residual = |x: f64| a * x - n * (curve.anura3d_saturation(pwp + x).1 - s0) - demand;
        let (mut low, mut high) = if demand > 0.0 {
            (0.0, full)
        } else {
            (full, 0.0)
        };
        // The kernel's tangent step, inside the bracket, to start from.
        let tangent = demand / (a - n * curve.derivative(pwp));
        let mut x = tangent.clamp(low, high);
        for _ in 0..100 {
            let r = residual(x);
            if r.abs() <= 1e-13 * demand.abs() {
                break;
            }
            if r > 0.0 {
                high = x;
            } else {
                low = x;
            }
            let slope = a - n * curve.derivative(pwp + x);
            let newton = x - r / slope;
            x = if newton > low && newton < high {
                newton
            } else {
                0.5 * (low + high)
            };
            if high - low <= 1e-15 * (1.0 + x.abs()) {
                break;
            }
        }
        x
    }
}

/// The formulation of each material as the runner ran it, for reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Formulation {
    /// One phase, no water (`dry_material`): no pore pressure to hold.
    Dry,
    /// One phase, pore pressure frozen (drained materials, or every material
    /// with water under `--drained`).
    Drained,
    /// One phase, pore pressure from the solid's volumetric strain.
    UndrainedEffective,
    /// Two phases, single point: the water flows.
    Coupled,
}

/// The conductivity curve of an unsaturated material record: the value of
/// `$$HYDR_CONDUCTIVITY_CURVE` and the parameters on the lines after it
/// (Hillel: r; Mualem: Smin, Smax, P0, λ).
fn conductivity_of(material: &Material) -> Result<Conductivity, MpmError> {
    let props = &material.properties;
    let Some(at) = props
        .iter()
        .position(|(k, _)| k.trim() == "$$HYDR_CONDUCTIVITY_CURVE")
    else {
        return Ok(Conductivity::Constant);
    };
    let invalid = |reason: String| MpmError::InvalidProperty {
        material: material.index,
        reason,
    };
    let parameter = |i: usize| -> Result<f64, MpmError> {
        props
            .get(at + i)
            .and_then(|(_, v)| v.trim().parse::<f64>().ok())
            .filter(|v| v.is_finite())
            .ok_or_else(|| invalid(format!("conductivity curve parameter {i} is missing")))
    };
    let name = props[at].1.trim().to_ascii_lowercase();
    match name.as_str() {
        "constant" => Ok(Conductivity::Constant),
        "hillel" => {
            let r = parameter(1)?;
            if r < 0.0 {
                return Err(invalid(format!("Hillel's exponent r = {r} must be ≥ 0")));
            }
            Ok(Conductivity::Hillel { r })
        }
        "mualem" => {
            let lambda = parameter(4)?;
            if !(lambda > 0.0 && lambda < 1.0) {
                return Err(invalid(format!("Mualem's λ = {lambda} must lie in (0, 1)")));
            }
            Ok(Conductivity::Mualem { lambda })
        }
        other => Err(invalid(format!("unknown conductivity curve `{other}`"))),
    }
}

/// A numeric property of the material record by keyword.
fn property(material: &Material, keyword: &str) -> Option<f64> {
    super::material::property(material, keyword)
}

impl Water {
    /// The water of `material`; `frozen` holds every pore pressure;
    /// `unsaturated` lets `unsaturated_material_2phase_suction` run two-phase
    /// (on by default, [`super::RunSettings::unsaturated_two_phase`]).
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
                Some(n) => Err(MpmError::InvalidProperty {
                    material: material.index,
                    reason: format!(
                        "POROSITY_SOLID {n} must be in (0, 1) for a material with water"
                    ),
                }),
                None => Err(MpmError::MissingProperty {
                    material: material.index,
                    property: "POROSITY_SOLID",
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
                let (retention, conductivity) = if kind == "unsaturated_material_2phase_suction" {
                    let Some(curve) = material.retention else {
                        return Ok(Water::Frozen);
                    };
                    (Some(curve), conductivity_of(material)?)
                } else {
                    (None, Conductivity::Constant)
                };
                Ok(Water::Coupled(Coupled {
                    bulk_over_n: positive("BULK_MODULUS_LIQUID")? / n,
                    porosity: n,
                    density: material.density_liquid.unwrap_or(1000.0) / 1000.0,
                    drag: n * mu / kappa,
                    retention,
                    conductivity,
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

#[cfg(test)]
mod tests {
    use super::*;

    const CURVE: RetentionCurve = RetentionCurve::VanGenuchten {
        s_min: 0.1,
        s_max: 1.0,
        p0: 1.96,
        lambda: 0.6337,
    };

    fn water(retention: Option<RetentionCurve>) -> Coupled {
        Coupled {
            bulk_over_n: 45_000.0 / 0.58,
            porosity: 0.58,
            density: 1.0,
            drag: 0.58 * 1e-6 / 2e-11,
            retention,
            conductivity: Conductivity::Constant,
        }
    }

    fn residual(c: &Coupled, pwp: f64, s: f64, demand: f64, dp: f64) -> f64 {
        let curve = c.retention.unwrap();
        s / c.bulk_over_n * dp
            - c.porosity * (curve.anura3d_saturation(pwp + dp).1 - curve.anura3d_saturation(pwp).1)
            - demand
    }

    #[test]
    fn saturated_storage_is_kw_over_n_times_the_demand() {
        let c = water(None);
        for demand in [-1e-5, 0.0, 3e-6] {
            assert_eq!(
                c.pressure_increment(-2.0, 0.7, demand),
                c.bulk_over_n * demand
            );
        }
    }

    #[test]
    fn secant_storage_solves_the_step_equation_across_saturation() {
        let c = water(Some(CURVE));
        // From the saturated side, an expansion that the water alone would
        // answer with +0.78 kPa: the retention curve takes most of it once
        // p crosses 0.
        let (p, demand) = (-0.1, 1e-5);
        let stiff = c.bulk_over_n * demand;
        let dp = c.pressure_increment(p, 1.0, demand);
        assert!(dp > 0.1 && dp < stiff, "Δp {dp} (water alone {stiff})");
        assert!(residual(&c, p, 1.0, demand, dp).abs() < 1e-15);
        // In suction, both ways, and back across 0 under compression.
        for (p, demand) in [(0.5, 2e-4), (1.5, -3e-3), (0.05, -1e-3), (2.0, 0.0)] {
            let s = CURVE.saturation(p);
            let dp = c.pressure_increment(p, s, demand);
            assert!(
                residual(&c, p, s, demand, dp).abs() <= 1e-12 * demand.abs(),
                "p {p}, demand {demand}: Δp {dp}"
            );
            assert!(dp * demand >= 0.0, "Δp follows the demand's sign");
        }
        // Small steps: the secant tends to the kernel's tangent.
        let (p, demand) = (0.8, 1e-9);
        let s = CURVE.saturation(p);
        let tangent = demand / (s / c.bulk_over_n - c.porosity * CURVE.derivative(p));
        let dp = c.pressure_increment(p, s, demand);
        assert!((dp / tangent - 1.0).abs() < 1e-6, "{dp} vs {tangent}");
    }

    #[test]
    fn conductivity_curves_as_the_kernel_forms_them() {
        let s = 0.6_f64;
        assert_eq!(Conductivity::Constant.relative(s), 1.0);
        assert!((Conductivity::Hillel { r: 3.0 }.relative(s) - 0.216).abs() < 1e-15);
        let lambda = 0.5;
        let w = 1.0 - (1.0 - s.powf(2.0)).powf(0.5);
        let mualem = Conductivity::Mualem { lambda }.relative(s);
        assert!((mualem - s.sqrt() * w * w).abs() < 1e-15);
        for c in [
            Conductivity::Constant,
            Conductivity::Hillel { r: 3.0 },
            Conductivity::Mualem { lambda },
        ] {
            assert_eq!(c.relative(1.0), 1.0);
            assert!(c.relative(0.0) >= MIN_RELATIVE_CONDUCTIVITY);
        }
    }

    #[test]
    fn conductivity_curve_read_from_the_record() {
        let mut m = Material {
            retention: Some(CURVE),
            ..Material::new(1, "sand", "unsaturated_material_2phase_suction")
        };
        assert_eq!(conductivity_of(&m).unwrap(), Conductivity::Constant);
        let pair = |k: &str, v: &str| (format!("$${k}"), v.to_string());
        m.properties = vec![pair("HYDR_CONDUCTIVITY_CURVE", "hillel"), pair("r", "2.5")];
        assert_eq!(
            conductivity_of(&m).unwrap(),
            Conductivity::Hillel { r: 2.5 }
        );
        m.properties = vec![
            pair("HYDR_CONDUCTIVITY_CURVE", "mualem"),
            pair("Smin", "0.1"),
            pair("Smax", "1"),
            pair("P0", "2"),
            pair("lambda", "0.4"),
        ];
        assert_eq!(
            conductivity_of(&m).unwrap(),
            Conductivity::Mualem { lambda: 0.4 }
        );
        m.properties.truncate(3);
        assert!(conductivity_of(&m).is_err());
    }
}
