//! Isotropic linear elasticity by bulk and shear modulus: the elastic part of
//! every constitutive model of the runner (`material`, `mohr_coulomb`), and the
//! elastic parameters the equilibrium solve takes.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

/// Isotropic linear elasticity by bulk and shear modulus (kPa).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Elasticity {
    pub bulk: f64,
    pub shear: f64,
}

impl Elasticity {
    /// From Young's modulus and Poisson's ratio; `None` unless E > 0 and
    /// −1 < ν < 0.5.
    pub fn from_young_poisson(young: f64, poisson: f64) -> Option<Elasticity> {
        if !(young > 0.0 && young.is_finite() && poisson > -1.0 && poisson < 0.5) {
            return None;
        }
        Some(Elasticity {
            bulk: young / (3.0 * (1.0 - 2.0 * poisson)),
            shear: young / (2.0 * (1.0 + poisson)),
        })
    }

    /// Lamé's first parameter λ = K − 2G/3.
    pub fn lame(&self) -> f64 {
        self.bulk - 2.0 / 3.0 * self.shear
    }

    /// Constrained (P-wave) modulus M = K + 4G/3.
    pub fn p_wave_modulus(&self) -> f64 {
        self.bulk + 4.0 / 3.0 * self.shear
    }

    /// Adds D·Δε to `stress` (Δε with engineering shear).
    #[inline]
    pub fn add_increment(&self, stress: &mut [f64; 6], strain: &[f64; 6]) {
        let two_g = 2.0 * self.shear;
        let volumetric = self.lame() * (strain[0] + strain[1] + strain[2]);
        for k in 0..3 {
            stress[k] += volumetric + two_g * strain[k];
        }
        for k in 3..6 {
            stress[k] += self.shear * strain[k];
        }
    }

    /// The strain C·Δσ (engineering shear) that an elastic stress change
    /// `stress_change` corresponds to. Used to express plastic strain
    /// increments: Δε^p = C·(σ_trial − σ_returned).
    pub fn strain_of(&self, stress_change: &[f64; 6]) -> [f64; 6] {
        let mean = (stress_change[0] + stress_change[1] + stress_change[2]) / 3.0;
        let mut out = [0.0; 6];
        for k in 0..3 {
            out[k] = mean / (3.0 * self.bulk) + (stress_change[k] - mean) / (2.0 * self.shear);
        }
        for k in 3..6 {
            out[k] = stress_change[k] / self.shear;
        }
        out
    }
}
