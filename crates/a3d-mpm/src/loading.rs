//! How Anura3D's kernel loads a material point under gravity, by the kind of
//! analysis the GOM's materials make (read from `ReadMaterialData.FOR`,
//! `Particle.FOR` and `MPMDYNBTSig.FOR` of the kernel source): which part of
//! the pore pressure p enters the internal force with σ′, the mass that
//! moves, and the weight gravity pulls on. The runner ([`super::step`]) and the
//! equilibrium solve ([`super::equilibrium`]) both take their forces from here,
//! so that a state one calls balanced the other does too, and both balance it
//! as the kernel does.
//!
//! * **One-phase analysis** (every material `dry_material` or
//!   `saturated_material_*`): the internal force is Σ V Bᵀσ′ alone (σ′ + p for
//!   `saturated_material_undrained_effective`); the pore pressure is otherwise
//!   only what Anura3D subtracted from the MAPF's total stress. Gravity pulls
//!   on the dry weight (the mixture's for the undrained types), except under
//!   the submerged calculation, which a `saturated_material_drained` switches
//!   on for itself and every material after it in the GOM (the CPS's
//!   `$$SUBMERGED_CALCULATION 1` for all): then on (1 − n)ρs + n·ρw − ρw (ρw = 0
//!   for dry materials), the buoyant weight. The mass that moves is the dry one
//!   (for the undrained types their weight's).
//! * **Multiphase analysis** (any `saturated_material_coupled` or
//!   `unsaturated_*` material): Bishop's total stress σ′ + S·p and the mixture's
//!   weight and mass at the MP's degree of saturation,
//!   ((1 − n)ρs + n·S·ρw). This is the kernel's mixture balance at full
//!   saturation; the kernel's water phase (Darcy flow) is not modelled, so a
//!   non-hydrostatic pore pressure is held as if the water could not move.

use a3d_model::Material;

/// The kind of analysis a model's materials make, as the kernel decides it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Analysis {
    /// More than one phase: some material is coupled or unsaturated.
    pub multiphase: bool,
    /// 0-based index of the first material that gets the submerged weight
    /// (one-phase analyses; `None`: none does).
    pub submerged_from: Option<usize>,
}

/// How one MP is loaded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Loading {
    /// The factor of the pore pressure added to σ′ on the normals in the
    /// internal force (S, 1 or 0).
    pub pore_factor: f64,
    /// Density of the mass that moves (t/m³).
    pub density: f64,
    /// Density of the weight gravity pulls on (t/m³): the body force is
    /// this × V × g.
    pub weight_density: f64,
}

impl Analysis {
    /// The analysis of `materials`; `cps_submerged` is the CPS's
    /// `$$SUBMERGED_CALCULATION` switch.
    pub fn of(materials: &[Material], cps_submerged: bool) -> Analysis {
        let multiphase = materials
            .iter()
            .any(|m| m.is_unsaturated() || m.material_type == "saturated_material_coupled");
        let submerged_from = if cps_submerged {
            Some(0)
        } else {
            materials
                .iter()
                .position(|m| m.material_type == "saturated_material_drained")
        };
        Analysis {
            multiphase,
            submerged_from,
        }
    }

    /// The loading of an MP of `material` (0-based position `index` in the
    /// GOM) at degree of saturation `saturation`.
    pub fn loading(&self, index: usize, material: &Material, saturation: f64) -> Loading {
        let n = material.porosity.unwrap_or(0.0);
        let solid = (1.0 - n) * material.density_solid.unwrap_or(0.0) / 1000.0;
        let water = if material.has_water() {
            material.density_liquid.unwrap_or(1000.0) / 1000.0
        } else {
            0.0
        };
        if self.multiphase {
            let rho = material.gamma_at_saturation(saturation, 1.0);
            return Loading {
                pore_factor: saturation,
                density: rho,
                weight_density: rho,
            };
        }
        let undrained = material
            .material_type
            .starts_with("saturated_material_undrained");
        let mixture = solid + n * water;
        let submerged = self.submerged_from.is_some_and(|first| index >= first);
        let weight_density = if submerged {
            mixture - water
        } else if undrained {
            mixture
        } else {
            solid
        };
        // The undrained types move with their mixture weight, which the
        // submerged calculation replaces by the buoyant one.
        let density = if undrained { weight_density } else { solid };
        Loading {
            pore_factor: if material.material_type == "saturated_material_undrained_effective" {
                1.0
            } else {
                0.0
            },
            density,
            weight_density,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn material(kind: &str) -> Material {
        Material {
            porosity: Some(0.4),
            density_solid: Some(2650.0),
            density_liquid: Some(1000.0),
            ..Material::new(1, "m", kind)
        }
    }

    /// `(pore factor, density, weight density)` of a loading, to 1e-12.
    #[track_caller]
    fn assert_loading(l: Loading, expect: (f64, f64, f64)) {
        let got = (l.pore_factor, l.density, l.weight_density);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(
            close(got.0, expect.0) && close(got.1, expect.1) && close(got.2, expect.2),
            "{got:?} vs {expect:?}"
        );
    }

    #[test]
    fn loadings_follow_the_kernel() {
        let dry = material("dry_material");
        let drained = material("saturated_material_drained");
        let effective = material("saturated_material_undrained_effective");
        let coupled = material("saturated_material_coupled");
        let (gamma_dry, gamma_sat) = (0.6 * 2.65, 0.6 * 2.65 + 0.4);
        // Dry only: dry weight, no pore term.
        let a = Analysis::of(std::slice::from_ref(&dry), false);
        assert_loading(a.loading(0, &dry, 1.0), (0.0, gamma_dry, gamma_dry));
        // A drained material switches the submerged weight on from itself
        // on; the undrained material before it keeps its mixture weight.
        let a = Analysis::of(&[effective.clone(), drained.clone(), dry.clone()], false);
        assert_eq!(a.submerged_from, Some(1));
        assert_loading(a.loading(0, &effective, 1.0), (1.0, gamma_sat, gamma_sat));
        let sub = gamma_sat - 1.0;
        assert_loading(a.loading(1, &drained, 1.0), (0.0, gamma_dry, sub));
        assert_loading(a.loading(2, &dry, 1.0), (0.0, gamma_dry, gamma_dry));
        // After it, an undrained material moves and weighs buoyant.
        let a = Analysis::of(&[drained, effective.clone()], false);
        assert_loading(a.loading(1, &effective, 1.0), (1.0, sub, sub));
        // The CPS's switch: buoyant from the first material on.
        let a = Analysis::of(std::slice::from_ref(&effective), true);
        assert_loading(a.loading(0, &effective, 1.0), (1.0, sub, sub));
        // Multiphase: Bishop and the mixture at S.
        let a = Analysis::of(&[coupled.clone(), dry], false);
        assert!(a.multiphase);
        let at_half = gamma_dry + 0.2;
        assert_loading(a.loading(0, &coupled, 0.5), (0.5, at_half, at_half));
    }
}
