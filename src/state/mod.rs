//! The initial state a3d-init writes: pore pressure, total and effective stress
//! per MP, in Anura3D signs (tension positive, pwp negative in compression).
//!
//! Pure computation, no I/O. [`geostatic`] builds total stresses from the
//! overburden of the model's own materials when the FEM gives only pore
//! pressures; [`bishop`] turns pwp and total stress into effective stress with the
//! material's degree of saturation. The kernel mapping itself lives in `kernel`.

pub mod geostatic;
pub mod plausibility;

use crate::model::{Material, MpState};

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
