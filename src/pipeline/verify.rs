//! `verify`'s judgement of a project folder, as library calls: what Anura3D
//! will hold (rebuilt from the files it reads by [`super::anura3d`]), where
//! a3d-init's own mps.csv disagrees with it, the 2D σ'zz defect and the
//! MPM-MIXED collapse. The equilibrium run itself is [`crate::mpm`]'s.

use std::path::PathBuf;

use super::{PipelineError, Project, anura3d};
use crate::formats::mps_table;
use crate::model::{ComputationMethod, MaterialPoint, MpState};

const MAX_IDS: usize = 10;

/// What the files Anura3D reads give, next to what a3d-init intended.
#[derive(Clone, Debug, serde::Serialize)]
pub struct KernelCheck {
    pub gom: PathBuf,
    pub cps: Option<PathBuf>,
    pub mapf: PathBuf,
    pub computation_method: &'static str,
    pub mapf_read: bool,
    pub mapf_rows: usize,
    pub smoothing_length: f64,
    /// MPs Anura3D will hold as NaN (no MAPF row within 2h): count and first ids.
    pub nan_points: usize,
    pub nan_ids: Vec<u32>,
    pub carried_saturation: usize,
    /// mps.csv against the MAPF as Anura3D reads it.
    pub mps_csv: Option<TableComparison>,
    /// 2D only: the σ'zz := SigXY defect.
    pub sigma_zz_defect: Option<SigmaZzDefect>,
    /// MPs outside their yield surface in the intended state (mps.csv, or the
    /// kernel state without the 2D defect when there is no mps.csv).
    pub intended_outside_yield: usize,
    /// MPM-MIXED: what the first step overwrites.
    pub mixed: Option<crate::state::mixed::Spread>,
    pub notes: Vec<String>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct TableComparison {
    pub rows: usize,
    pub differing: usize,
    /// (MP id, largest difference relative to the column range), worst first.
    pub worst: Vec<(u32, f64)>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct SigmaZzDefect {
    /// MPs whose σ'zz Anura3D sets from SigXY differs from the intended σ'zz.
    pub affected: usize,
    /// MPs outside their yield surface because of it (inside in the intended state).
    pub outside_because_of_defect: usize,
    /// The first step's return mapping on those MPs: largest change of each
    /// effective-stress component (xx, yy, zz, xy; kPa).
    pub first_step_change: [f64; 4],
}

/// What `verify DIR` starts from.
pub struct Judged {
    pub check: KernelCheck,
    /// The state at t = 0 as Anura3D holds it (`verify/start.csv`).
    pub start: Vec<MpState>,
    /// The runner's start: `start` with the MPM-MIXED collapse applied.
    pub run_start: Vec<MpState>,
    /// Per MP: MAPF rows Anura3D weighs (non-zero kernel value).
    pub rows_in_reach: Vec<u32>,
    /// The files read.
    pub inputs: Vec<PathBuf>,
}

/// Judges a project folder by the files Anura3D reads: its MAPF rebuilt as the
/// kernel reads it, compared with mps.csv (when it belongs to the model), the
/// 2D σ'zz defect, the yield checks and the MPM-MIXED collapse.
pub fn judge_folder(project: &Project) -> Result<Judged, PipelineError> {
    let mapf_path = project
        .files
        .dir
        .join(format!("{}.MAPF", project.files.name));
    let mapf_name = mapf_path.display().to_string();
    let table = if mapf_path.is_file() {
        Some(crate::formats::mapf::read(&mapf_path)?)
    } else {
        None
    };
    let kernel = anura3d::initial_state(project, table.as_ref(), &mapf_name)?;
    let n_dim = project.n_dim();
    let points = project.points.clone();
    // The intended state: mps.csv when it belongs to this model.
    let mps_path = project.files.dir.join("mps.csv");
    let mut notes = kernel.notes.clone();
    let mut intended: Option<Vec<MpState>> = None;
    let mut mps_csv = None;
    if mps_path.is_file() {
        let (mps_points, mps_states) = mps_table::read_states(&mps_path)?;
        if same_points(&mps_points, &points) {
            let worst =
                anura3d::differing_points(&points, &kernel.states, &mps_states, n_dim, 1e-9);
            mps_csv = Some(TableComparison {
                rows: mps_points.len(),
                differing: worst.len(),
                worst: worst.into_iter().take(MAX_IDS).collect(),
            });
            intended = Some(mps_states);
        } else {
            notes.push(format!(
                "{} holds {} MPs that are not the {} MPs Anura3D creates for this model ({}): it is ignored",
                mps_path.display(),
                mps_points.len(),
                points.len(),
                project.method.cps_name()
            ));
            mps_csv = Some(TableComparison {
                rows: mps_points.len(),
                differing: mps_points.len().max(points.len()),
                worst: Vec::new(),
            });
        }
    }
    let nan: Vec<u32> = kernel.nan_points.clone();
    // Yield checks need each material's model; materials the runner cannot
    // model are skipped here (the run reports them).
    let models: Vec<Option<crate::mpm::SolidModel>> = project
        .model
        .materials
        .iter()
        .map(|m| crate::mpm::SolidModel::from_material(m).ok())
        .collect();
    let model_of = |p: &MaterialPoint| models.get(p.material as usize - 1).and_then(Option::as_ref);
    let plane_strain = n_dim == 2;
    let intended_eff: Vec<[f64; 6]> = match &intended {
        Some(states) => states.iter().map(MpState::effective).collect(),
        None => kernel.effective.clone(),
    };
    let intended_outside = points
        .iter()
        .zip(&intended_eff)
        .filter(|(p, e)| {
            e.iter().all(|v| v.is_finite())
                && model_of(p).is_some_and(|m| !m.is_admissible(e, plane_strain))
        })
        .count();
    let sigma_zz_defect = (n_dim == 2 && kernel.mapf.is_some()).then(|| {
        let mut d = SigmaZzDefect {
            affected: 0,
            outside_because_of_defect: 0,
            first_step_change: [0.0; 4],
        };
        for ((p, k), i) in points.iter().zip(&kernel.effective).zip(&intended_eff) {
            if !k.iter().all(|v| v.is_finite()) {
                continue;
            }
            let scale = i.iter().fold(1.0f64, |m, v| m.max(v.abs()));
            if (k[2] - i[2]).abs() > 1e-9 * scale {
                d.affected += 1;
            }
            let Some(m) = model_of(p) else { continue };
            if !m.is_admissible(k, plane_strain) && m.is_admissible(i, plane_strain) {
                d.outside_because_of_defect += 1;
                let mut returned = *k;
                if let Some(map) = &m.plasticity {
                    map.return_stress(&mut returned, plane_strain);
                }
                for c in 0..4 {
                    d.first_step_change[c] = d.first_step_change[c].max((returned[c] - k[c]).abs());
                }
            }
        }
        d
    });
    // MPM-MIXED: after the first step every MP of a fully filled element holds
    // the state of the element's first MP; the runner starts from that.
    let mut states = kernel.states.clone();
    let mixed = (project.method == ComputationMethod::MpmMixed).then(|| {
        let spread = crate::state::mixed::element_spread(&points, &states);
        crate::state::mixed::collapse_to_first(&points, &mut states);
        spread
    });
    let mut inputs = vec![project.files.gom.clone(), mapf_path.clone()];
    inputs.extend(project.files.cps.clone());
    inputs.extend(project.files.opd.clone());
    if mps_path.is_file() {
        inputs.push(mps_path);
    }
    let check = KernelCheck {
        gom: project.files.gom.clone(),
        cps: project.files.cps.clone(),
        mapf: mapf_path,
        computation_method: project.method.cps_name(),
        mapf_read: kernel.mapf.is_some(),
        mapf_rows: kernel.mapf.map_or(0, |m| m.rows),
        smoothing_length: kernel.mapf.map_or(0.0, |m| m.smoothing_length),
        nan_points: nan.len(),
        nan_ids: nan.iter().take(MAX_IDS).copied().collect(),
        carried_saturation: kernel.carried_saturation,
        mps_csv,
        sigma_zz_defect,
        intended_outside_yield: intended_outside,
        mixed,
        notes,
    };
    Ok(Judged {
        check,
        rows_in_reach: kernel.rows_in_reach,
        start: kernel.states,
        run_start: states,
        inputs,
    })
}

/// True when two MP lists are the same MPs (ids, elements, positions).
pub fn same_points(a: &[MaterialPoint], b: &[MaterialPoint]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.same_as(y))
}
