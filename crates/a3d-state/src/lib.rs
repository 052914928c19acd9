//! The initial state a3d-init writes: pore pressure, total and effective stress
//! per MP, in Anura3D signs (tension positive, pwp negative in compression).
//!
//! Pure computation, no I/O. [`geostatic`] builds total stresses from the
//! overburden of the model's own materials when the FEM gives only pore
//! pressures; [`bishop`] turns pwp and total stress into effective stress with the
//! material's degree of saturation; [`defaults`] holds the K0 and ν assumed
//! where the GOM gives none. The kernel mapping itself lives in `kernel`.

pub mod defaults;
pub mod geostatic;
pub mod ground;
pub mod mixed;
pub mod plausibility;

use a3d_model::{Material, MaterialPoint, MpState};

/// Degree of saturation for Bishop's equation at an Anura3D-signed pwp:
/// 1 in compression (below the water table); above it the material's retention
/// curve where the GOM gives one, otherwise 1 (Anura3D's own choice for
/// materials without partial saturation).
pub fn saturation(material: Option<&Material>, pwp: f64) -> f64 {
    match material {
        Some(m) if pwp > 0.0 => m.saturation(pwp),
        _ => 1.0,
    }
}

/// Effective stress by Bishop, σ' = σ − S·p on the normal components.
pub fn bishop(state: &MpState) -> [f64; 6] {
    state.effective()
}

/// A material whose FEM pore pressure was dropped.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct DroppedPwp {
    pub material: u32,
    pub name: String,
    /// MPs that carried a non-zero mapped pwp.
    pub points: usize,
    /// kPa
    pub max_abs_pwp: f64,
}

/// MPs of materials without a liquid phase (`dry_material`) carry no pore
/// water: their pwp is set to 0 (so σ' = σ) and their saturation to 1.
/// Anura3D subtracts the MAPF's `Pwp` from every MP's stress (with Sr = 1 in a
/// one-phase analysis), so a mapped suction would otherwise turn into tension.
/// Returns, per material, how many MPs had a non-zero value dropped.
pub fn drop_pore_water_of_dry_materials(
    materials: &[Material],
    points: &[MaterialPoint],
    states: &mut [MpState],
) -> Vec<DroppedPwp> {
    let mut out: Vec<DroppedPwp> = Vec::new();
    for (p, s) in points.iter().zip(states.iter_mut()) {
        let Some(m) = materials.get(p.material as usize - 1) else {
            continue;
        };
        if m.material_type != "dry_material" {
            continue;
        }
        if s.pwp != 0.0 {
            match out.iter_mut().find(|d| d.material == m.index) {
                Some(d) => {
                    d.points += 1;
                    d.max_abs_pwp = d.max_abs_pwp.max(s.pwp.abs());
                }
                None => out.push(DroppedPwp {
                    material: m.index,
                    name: m.name.clone(),
                    points: 1,
                    max_abs_pwp: s.pwp.abs(),
                }),
            }
        }
        s.pwp = 0.0;
        s.saturation = 1.0;
    }
    out
}
