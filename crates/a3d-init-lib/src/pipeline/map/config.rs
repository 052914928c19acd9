//! What decides a mapping: [`MapConfig`] and the choices it holds (where the
//! total stress comes from, what happens to MPs no FEM node reaches, how h is
//! chosen, what MPM-MIXED elements carry). Plain data; the stages read it.
//! The enums have names (`name`, `FromStr`, `Display`); the CLI's argument
//! enums convert into them.

pub use super::equilibrium::EquilibriumOptions;
use crate::formats::material_map::MaterialMap;
use crate::kernel::KernelKind;
use crate::kernel::mapper::{MapSettings, OutsidePolicy};

/// A name that is none of an enum's values.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{what} `{found}`: expected {}", .expected.join(", "))]
pub struct UnknownName {
    /// What was named, e.g. `stress source`.
    pub what: &'static str,
    pub found: String,
    pub expected: Vec<&'static str>,
}

/// `ALL`, `name`, `Display` and `FromStr` for a plain enum, from its
/// variants' names.
macro_rules! named {
    ($ty:ident, $what:literal, { $($variant:ident => $name:literal),+ $(,)? }) => {
        impl $ty {
            /// Every value, in declaration order.
            pub const ALL: &'static [$ty] = &[$($ty::$variant),+];

            /// The value's name, as [`std::str::FromStr`] reads it.
            pub fn name(self) -> &'static str {
                match self {
                    $($ty::$variant => $name),+
                }
            }
        }

        impl std::fmt::Display for $ty {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl std::str::FromStr for $ty {
            type Err = UnknownName;

            fn from_str(s: &str) -> Result<$ty, UnknownName> {
                $ty::ALL.iter().copied().find(|v| v.name() == s).ok_or_else(|| UnknownName {
                    what: $what,
                    found: s.to_string(),
                    expected: $ty::ALL.iter().map(|v| v.name()).collect(),
                })
            }
        }
    };
}

/// What happens to MPs that no FEM node reaches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Outside {
    Error,
    Nearest,
    Skip,
}

impl From<Outside> for OutsidePolicy {
    fn from(outside: Outside) -> OutsidePolicy {
        match outside {
            Outside::Error => OutsidePolicy::Error,
            Outside::Nearest => OutsidePolicy::Nearest,
            Outside::Skip => OutsidePolicy::Skip,
        }
    }
}

named!(Outside, "outside policy", { Error => "error", Nearest => "nearest", Skip => "skip" });

/// Where the MPs' total stress comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum StressSource {
    /// `fem` when the FEM file has total stresses; otherwise `equilibrium`
    /// when the ground surface is not flat (and the model can be solved),
    /// else `geostatic`.
    Auto,
    /// Map the FEM total stresses.
    Fem,
    /// Overburden of the GOM materials along the vertical, σh = K0·σ'v + S·p.
    Geostatic,
    /// The state at rest under gravity in the runner's discrete equations,
    /// pore pressures held: σ = σ' + S·p with σ' from an elastic (and, where
    /// needed, elastoplastic) solve on Anura3D's own discretisation.
    Equilibrium,
    /// Zero total stress (warned).
    Zero,
}

named!(StressSource, "stress source", {
    Auto => "auto",
    Fem => "fem",
    Geostatic => "geostatic",
    Equilibrium => "equilibrium",
    Zero => "zero",
});

/// What the MPs of a fully filled MPM-MIXED element carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum MixedState {
    /// Each fully filled element's volume-weighted mean state on all its MPs.
    Mean,
    /// Keep every MP's own mapped value (Anura3D MPM-MIXED keeps only MP 1's after the first step).
    PerMp,
}

named!(MixedState, "MPM-MIXED state", { Mean => "mean", PerMp => "per-mp" });

/// How the smoothing length h is chosen.
#[derive(Clone, Debug)]
pub enum SmoothingLength {
    /// The paper's spacing rule (§2.2): [`KernelKind::spacing_factor`] × the
    /// median nearest-node spacing.
    SpacingRule,
    /// A given h in metres.
    Metres(f64),
    /// Leave-one-out calibration (paper Eq. 4) with this annealer seed.
    Calibrate { seed: u64 },
    /// A calibration already run on these nodes (reported as calibrated).
    Calibrated {
        outcome: Box<crate::pipeline::calibrate::Outcome>,
        seed: u64,
    },
}

/// Everything that decides how the FEM fields become MP states.
#[derive(Clone, Debug)]
pub struct MapConfig {
    pub kernel: KernelKind,
    pub h: SmoothingLength,
    /// MPs no FEM node reaches.
    pub outside: Outside,
    /// Null-point threshold on the Shepard ratio Σw·l^dim.
    pub min_shepard: f64,
    pub stress: StressSource,
    /// FEM region → GOM material (names or indices), resolved against the
    /// model's materials and the FEM's regions by the placement stage.
    pub material_map: Option<MaterialMap>,
    /// MPM-MIXED models: element means or per-MP values.
    pub mixed_state: MixedState,
    /// How `equilibrium` solves (ν from K0, tolerance, iterations).
    pub equilibrium: EquilibriumOptions,
    /// Keep the FEM fields in [`super::Mapped::fem`] after mapping (for
    /// `fem.vtu`); without it they are freed once copied for the kernel (memory).
    pub keep_fem_fields: bool,
    /// How FS(t) runs when the FEM step is `failure`
    /// ([`crate::pipeline::stability::failure`]): FS(t)'s own defaults (Morgenstern–Price,
    /// 2,000 trial circles a time).
    pub failure: crate::pipeline::stability::slope::LeOptions,
}

impl Default for MapConfig {
    fn default() -> Self {
        MapConfig {
            kernel: KernelKind::Cubic,
            h: SmoothingLength::SpacingRule,
            outside: Outside::Error,
            min_shepard: 0.02,
            stress: StressSource::Auto,
            material_map: None,
            mixed_state: MixedState::Mean,
            equilibrium: EquilibriumOptions::default(),
            keep_fem_fields: true,
            failure: crate::pipeline::stability::fos_time::FosTimeOptions::default().le,
        }
    }
}

impl MapConfig {
    /// The kernel's settings with smoothing length `h`.
    pub fn settings(&self, h: f64) -> MapSettings {
        MapSettings {
            kernel: self.kernel,
            h,
            min_shepard: self.min_shepard,
            outside: self.outside.into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_back_and_others_are_refused() {
        for v in Outside::ALL {
            assert_eq!(v.name().parse::<Outside>(), Ok(*v));
        }
        for v in StressSource::ALL {
            assert_eq!(v.to_string().parse::<StressSource>(), Ok(*v));
        }
        assert_eq!("per-mp".parse::<MixedState>(), Ok(MixedState::PerMp));
        let e = "Fem".parse::<StressSource>().unwrap_err();
        assert_eq!(
            e.to_string(),
            "stress source `Fem`: expected auto, fem, geostatic, equilibrium, zero"
        );
    }
}
