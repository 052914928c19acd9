//! Stage 8 of [`super::map`]: report.json from what the other stages found.
//! The report's types and the input hashing live in [`crate::pipeline::report`];
//! this file fills them in.

use super::{ChosenH, MixedState, Outside, Placement, StressSource};
use crate::formats::fem_csv::SignConvention;
use crate::formats::mapf;
use crate::kernel::KernelKind;
use crate::model::MpState;
use crate::pipeline::fem::LoadedFem;
use crate::pipeline::report::{
    InputFile, MapReport, MaterialCount, Smoothing, describe_in_background,
};
use crate::pipeline::{PipelineError, Project};
use crate::state::defaults::AssumedDefault;

/// The input files' SHA-256, read and hashed on a thread of its own beside the
/// mapping (a serial pass over every input file, which would otherwise come
/// last).
pub struct Hashing(std::thread::JoinHandle<Result<Vec<InputFile>, PipelineError>>);

impl Hashing {
    /// Starts hashing the GOM, the CPS and the FEM files.
    pub fn start(project: &Project, fem: &LoadedFem) -> Hashing {
        Hashing(describe_in_background(
            std::iter::once(&project.files.gom)
                .chain(&project.files.cps)
                .chain(&fem.paths)
                .cloned()
                .collect(),
        ))
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
        fem_nodes: r.fem.nodes.len(),
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
        notes: r.notes,
        warnings: r.warnings,
        timings_ms: r.timings_ms,
    }
}
