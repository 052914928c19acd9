//! Stage 8 of [`super::map`]: report.json, its types (inputs with their
//! SHA-256, conventions, how h was chosen, counts, notes, warnings and
//! timings) and how the other stages' findings fill them in.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::{ChosenH, MixedState, Outside, Placement, StressSource};
use crate::formats::fem::{FemReadReport, SignConvention};
use crate::formats::mapf;
use crate::kernel::{Kernel, KernelKind};
use crate::model::MpState;
use crate::pipeline::fem::LoadedFem;
use crate::pipeline::{PipelineError, Project};
use crate::state::defaults::AssumedDefault;

#[derive(Serialize)]
pub struct InputFile {
    pub path: PathBuf,
    pub bytes: u64,
    pub sha256: String,
}

pub(crate) fn describe(path: &Path) -> Result<InputFile, PipelineError> {
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
pub(crate) fn describe_in_background(
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
    pub equilibrium: Option<crate::pipeline::map::equilibrium::EquilibriumReport>,
    /// `--step failure`: the saved step FS(t) chose, its time, factor and
    /// method; left out of report.json for every other step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<crate::pipeline::stability::failure::FailureStep>,
    /// A CB-Geo model: the branch, the files written, units, signs, the
    /// stress each particle gets and the particle order; left out of
    /// report.json for an Anura3D model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cbgeo: Option<crate::pipeline::cbgeo::write::CbGeoReport>,
    pub notes: Vec<String>,
    pub warnings: Vec<String>,
    pub timings_ms: Vec<(String, f64)>,
}

/// The input files' SHA-256, read and hashed on a thread of its own beside the
/// mapping (a serial pass over every input file, which would otherwise come
/// last).
pub struct Hashing(std::thread::JoinHandle<Result<Vec<InputFile>, PipelineError>>);

impl Hashing {
    /// Starts hashing the model's files (GOM and CPS, or a CB-Geo run file
    /// and the files it names) and the FEM files.
    pub fn start(project: &Project, fem: &LoadedFem) -> Hashing {
        let mut paths = vec![project.files.gom.clone()];
        paths.extend(project.files.cps.iter().cloned());
        if let Some(t) = &project.cbgeo {
            // The files a CB-Geo run file names (mesh, particles, sets, …).
            let m = &t.model;
            paths.extend(m.referenced.iter().map(|r| m.dir.join(&r.name)));
        }
        paths.extend(fem.paths.iter().cloned());
        Hashing(describe_in_background(paths))
    }

    /// Waits for the hashes.
    pub fn join(self) -> Result<Vec<InputFile>, PipelineError> {
        self.0
            .join()
            .map_err(|_| PipelineError::Input("hashing the input files failed".into()))?
    }
}

/// The note on how the MAPF's columns meet Anura3D's reader in `dim` dimensions.
pub fn mapf_note(dim: usize) -> &'static str {
    if dim == 2 {
        "Anura3D's MAPF reader puts τxy into σ'zz in 2D (a kernel defect); mps.csv holds the intended σzz"
    } else {
        "3D MAPF: τyz is written under SigXZ[kPa] and τxz under SigYZ[kPa], cancelling Anura3D's swapped reader"
    }
}

/// What [`build_report`] reads: the inputs and every stage's outcome.
pub struct ReportInputs<'a> {
    pub project: &'a Project,
    pub fem: &'a LoadedFem,
    /// The FEM nodes read (`fem`'s may be gone by now, see
    /// [`super::interpolate::KeepNodes`]).
    pub fem_nodes: usize,
    /// The input files with their SHA-256 ([`Hashing`]).
    pub files: Vec<InputFile>,
    pub kernel: KernelKind,
    pub smoothing: ChosenH,
    /// The resolved stress source.
    pub stress_source: StressSource,
    pub placement: &'a Placement,
    pub outside: Outside,
    /// MPs no FEM node reached.
    pub null_points: usize,
    /// The MPM-MIXED choice applied, if the model is MPM-MIXED.
    pub mixed_state: Option<MixedState>,
    /// The final state of each MP.
    pub states: &'a [MpState],
    /// The material defaults the states rely on.
    pub assumed_defaults: Vec<AssumedDefault>,
    /// The equilibrium solve, when it gave the stress.
    pub equilibrium: Option<super::equilibrium::EquilibriumReport>,
    pub notes: Vec<String>,
    pub warnings: Vec<String>,
    pub timings_ms: Vec<(String, f64)>,
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    })
}

/// The map report: conventions, h, counts per material, ranges, notes,
/// warnings and timings.
pub fn build_report(r: ReportInputs<'_>) -> MapReport {
    let points = &r.project.points;
    let node_groups = r.placement.node_groups.as_ref();
    let materials = r
        .project
        .model
        .materials
        .iter()
        .map(|m| MaterialCount {
            index: m.index,
            name: m.name.clone(),
            mps: points.iter().filter(|p| p.material == m.index).count(),
            fem_nodes: node_groups.map(|g| g.iter().filter(|&&x| x == m.index).count()),
        })
        .collect();
    let sign = match r.fem.sign {
        SignConvention::GeoStudio => {
            "FEM sign geostudio: stresses compression positive and pwp positive below the water table in the file; all were negated into Anura3D's convention"
        }
        SignConvention::TensionPositive => "FEM sign tension-positive: values kept as in the file",
        SignConvention::Ogs => {
            "FEM sign ogs (OpenGeoSys): pressure positive in compression in the file, negated; stresses tension positive, kept"
        }
    };
    let min_mp = r.placement.min_mp_spacing;
    MapReport {
        tool: format!("a3d-init {}", env!("CARGO_PKG_VERSION")),
        inputs: r.files,
        fem: r.fem.reports.clone(),
        conventions: vec![
            "units: m, kPa, kN/m³, s".into(),
            "output signs (Anura3D): tension positive, pore pressure negative in compression"
                .into(),
            sign.into(),
            "MAPF Sig* columns are total stresses; Anura3D forms σ' = σ − S·p (Bishop)".into(),
        ],
        smoothing: Smoothing::new(
            r.kernel,
            r.smoothing.h,
            r.smoothing.rule,
            r.smoothing.spacing,
            r.project.n_dim(),
        ),
        stress_source: r.stress_source.name().to_string(),
        computation_method: r.project.method,
        mixed_state: r.mixed_state,
        calibration: r.smoothing.calibration,
        material_separation: r.placement.separation.clone(),
        materials,
        fem_nodes: r.fem_nodes,
        material_points: points.len(),
        null_points: r.null_points,
        null_point_policy: r.outside,
        mapf_smoothing_length: mapf::exact_point_smoothing_length(min_mp),
        min_mp_spacing: min_mp,
        pwp_range: range(r.states.iter().map(|s| s.pwp)),
        sigma_yy_range: range(r.states.iter().map(|s| s.total[1])),
        assumed_defaults: r.assumed_defaults,
        equilibrium: r.equilibrium,
        failure: None,
        cbgeo: r
            .project
            .cbgeo
            .as_ref()
            .map(|t| crate::pipeline::cbgeo::write::report(t)),
        notes: r.notes,
        warnings: r.warnings,
        timings_ms: r.timings_ms,
    }
}
