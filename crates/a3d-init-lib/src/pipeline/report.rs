//! The map report (`report.json`): inputs with their SHA-256, conventions, how
//! h was chosen, counts, notes, warnings and timings.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::PipelineError;
use super::map::{MixedState, Outside};
use crate::formats::fem_csv::FemReadReport;
use crate::kernel::{Kernel, KernelKind};

#[derive(Serialize)]
pub struct InputFile {
    pub path: PathBuf,
    pub bytes: u64,
    pub sha256: String,
}

pub(super) fn describe(path: &Path) -> Result<InputFile, PipelineError> {
    use sha2::{Digest, Sha256};
    use std::io::Read;
    // Streamed: a large FEM table is not held in memory a second time.
    let (mut file, _) = crate::formats::input::open_regular(path)?;
    let io =
        |e: std::io::Error| PipelineError::Input(format!("{}: cannot read: {e}", path.display()));
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 20];
    let mut len = 0u64;
    loop {
        let n = file.read(&mut buf).map_err(io)?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
        len += n as u64;
    }
    let digest = hasher.finalize();
    Ok(InputFile {
        path: path.to_path_buf(),
        bytes: len,
        sha256: digest.iter().map(|b| format!("{b:02x}")).collect(),
    })
}

/// [`describe`] of every path, on a thread of its own: the report's hashes
/// are read beside the mapping instead of in a serial pass at its end.
pub(super) fn describe_in_background(
    paths: Vec<PathBuf>,
) -> std::thread::JoinHandle<Result<Vec<InputFile>, PipelineError>> {
    std::thread::spawn(move || paths.iter().map(|p| describe(p)).collect())
}

#[derive(Serialize)]
pub struct MaterialCount {
    pub index: u32,
    pub name: String,
    pub mps: usize,
    pub fem_nodes: Option<usize>,
}

/// The kernel and how its smoothing length was chosen (report.json holds
/// these fields at its top level).
#[derive(Serialize)]
pub struct Smoothing {
    /// `cubic`, `gaussian` or `wendland`.
    pub kernel: String,
    /// h (m).
    pub smoothing_length: f64,
    /// How h was chosen: given, the spacing rule, or calibrated.
    pub smoothing_length_rule: String,
    /// Median distance from a FEM node to its nearest other node, l (m).
    pub fem_spacing: f64,
    /// Gaussian only: the kernel mass inside the cut-off support.
    pub gaussian_truncated_mass: Option<f64>,
}

impl Smoothing {
    /// The report of `kernel` with `h` chosen by `rule`, on nodes `spacing` apart.
    pub fn new(kernel: KernelKind, h: f64, rule: String, spacing: f64, dim: usize) -> Smoothing {
        Smoothing {
            kernel: kernel.name().into(),
            smoothing_length: h,
            smoothing_length_rule: rule,
            fem_spacing: spacing,
            gaussian_truncated_mass: match kernel {
                KernelKind::Gaussian { cutoff } => {
                    Some(crate::kernel::Gaussian { cutoff }.truncated_mass(dim))
                }
                _ => None,
            },
        }
    }
}

#[derive(Serialize)]
pub struct MapReport {
    pub tool: String,
    pub inputs: Vec<InputFile>,
    pub fem: Vec<FemReadReport>,
    pub conventions: Vec<String>,
    #[serde(flatten)]
    pub smoothing: Smoothing,
    pub stress_source: String,
    pub computation_method: crate::model::ComputationMethod,
    /// MPM-MIXED only: the choice applied (`Mean` or `PerMp`).
    pub mixed_state: Option<MixedState>,
    pub calibration: Option<crate::pipeline::calibrate::Outcome>,
    pub material_separation: String,
    pub materials: Vec<MaterialCount>,
    pub fem_nodes: usize,
    pub material_points: usize,
    pub null_points: usize,
    pub null_point_policy: Outside,
    pub mapf_smoothing_length: f64,
    pub min_mp_spacing: f64,
    pub pwp_range: (f64, f64),
    pub sigma_yy_range: (f64, f64),
    /// The material parameters assumed where the GOM gives none (also
    /// among the notes); left out of report.json when there are none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub assumed_defaults: Vec<crate::state::defaults::AssumedDefault>,
    /// `--stress equilibrium`: the elastic parameters each material got, the
    /// residual reached, the plastic iterations and the verdict; left out of
    /// report.json for every other stress source.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub equilibrium: Option<super::map::equilibrium::EquilibriumReport>,
    /// `--step failure`: the saved step FS(t) chose, its time, factor and
    /// method; left out of report.json for every other step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<super::failure::FailureStep>,
    pub notes: Vec<String>,
    pub warnings: Vec<String>,
    pub timings_ms: Vec<(String, f64)>,
}
