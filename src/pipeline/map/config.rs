//! What decides a mapping: [`MapConfig`] and the choices it holds (where the
//! total stress comes from, what happens to MPs no FEM node reaches, how h is
//! chosen, what MPM-MIXED elements carry). Plain data; the stages read it.

use crate::kernel::KernelKind;
use crate::kernel::mapper::{MapSettings, OutsidePolicy};

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
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

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum StressSource {
    /// `fem` when the FEM file has total stresses, otherwise `geostatic`.
    Auto,
    /// Map the FEM total stresses.
    Fem,
    /// Overburden of the GOM materials along the vertical, σh = K0·σ'v + S·p.
    Geostatic,
    /// Zero total stress (warned).
    Zero,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum MixedState {
    /// Each fully filled element's volume-weighted mean state on all its MPs.
    Mean,
    /// Keep every MP's own mapped value (Anura3D MPM-MIXED keeps only MP 1's after the first step).
    PerMp,
}

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
    /// FEM region → GOM material, `region=material,…` (names or indices).
    pub material_map: Option<String>,
    /// MPM-MIXED models: element means or per-MP values.
    pub mixed_state: MixedState,
    /// Keep the FEM fields in [`super::Mapped::fem`] after mapping (for
    /// `fem.vtu`); without it they are freed once copied for the kernel (memory).
    pub keep_fem_fields: bool,
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
            keep_fem_fields: true,
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
