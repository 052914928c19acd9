//! `verify`'s judgement of a project folder, as library calls: what Anura3D
//! will hold (rebuilt from the files it reads by [`crate::pipeline::check::anura3d`]), where
//! a3d-init's own mps.csv disagrees with it, the 2D σ'zz defect and the
//! MPM-MIXED collapse. The equilibrium run itself is [`crate::mpm`]'s.

use std::path::PathBuf;

use crate::formats::mps_table;
use crate::model::{ComputationMethod, MaterialPoint, MpState};
use crate::pipeline::check::anura3d;
use crate::pipeline::{PipelineError, Project};

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

/// mps.csv row by row against the MAPF as Anura3D reads it. Every count is
/// of MPs or rows actually seen: `differing ≤ compared ≤` the model's MPs.
#[derive(Clone, Debug, serde::Serialize)]
pub struct TableComparison {
    /// Rows in mps.csv.
    pub rows: usize,
    /// The model's MPs that matched exactly one row (same id, element and
    /// position) and were compared.
    pub compared: usize,
    /// Of those, the MPs whose states differ by more than 1e-9 of a column's
    /// range.
    pub differing: usize,
    /// Rows that match no MP of the model (an unknown id, another element or
    /// position, or an id repeated).
    pub unmatched_rows: usize,
    /// The model's MPs without a row.
    pub missing: usize,
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
        let row_of = match_rows(&points, &mps_points);
        let compared: Vec<usize> = (0..points.len()).filter(|&i| row_of[i].is_some()).collect();
        let pick = |v: &[MpState], rows: bool| -> Vec<MpState> {
            compared
                .iter()
                .map(|&i| v[if rows { row_of[i].unwrap_or(i) } else { i }])
                .collect()
        };
        let compared_points: Vec<MaterialPoint> = compared.iter().map(|&i| points[i]).collect();
        let worst = anura3d::differing_points(
            &compared_points,
            &pick(&kernel.states, false),
            &pick(&mps_states, true),
            n_dim,
            1e-9,
        );
        let comparison = TableComparison {
            rows: mps_points.len(),
            compared: compared.len(),
            differing: worst.len(),
            unmatched_rows: mps_points.len() - compared.len(),
            missing: points.len() - compared.len(),
            worst: worst.into_iter().take(MAX_IDS).collect(),
        };
        if comparison.missing == 0 {
            intended = Some(pick(&mps_states, true));
        } else {
            notes.push(format!(
                "{} has no row for {} of the {} MPs Anura3D creates for this model ({}): it is not used as the intended state",
                mps_path.display(),
                comparison.missing,
                points.len(),
                project.method.cps_name()
            ));
        }
        mps_csv = Some(comparison);
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
    })
}

/// For each MP of `points`, the row of `rows` that is the same MP (same id,
/// element and position), each row used at most once: a repeated row is left
/// unmatched.
pub fn match_rows(points: &[MaterialPoint], rows: &[MaterialPoint]) -> Vec<Option<usize>> {
    let by_id: std::collections::HashMap<u32, usize> =
        points.iter().enumerate().map(|(i, p)| (p.id, i)).collect();
    let mut row_of = vec![None; points.len()];
    for (r, row) in rows.iter().enumerate() {
        if let Some(&i) = by_id.get(&row.id)
            && row_of[i].is_none()
            && row.same_as(&points[i])
        {
            row_of[i] = Some(r);
        }
    }
    row_of
}
