//! Writing a mapped CB-Geo project: every file the run file names, copied
//! byte for byte (with its relative path); the particle stresses (and, for
//! two-phase particles, the pore pressures) a3d-init mapped; and the run file
//! pointing at them in the form its branch reads, every other byte kept.
//!
//! Conversions, stated in report.json's `cbgeo` section:
//! - kPa → Pa (× 1000);
//! - signs: CB-Geo's stresses are tension positive, as a3d-init's; its pore
//!   pressure is positive in compression, a3d-init's negative, so p = −pwp;
//! - single-phase particles take the total stress; two-phase particles the
//!   effective stress CB-Geo's mixture adds p to: σ′ = σ + p·I (CB-Geo's
//!   total is σ′ − p·I, which gives back the mapped σ);
//! - order: one line per particle in CB-Geo's particle order (ids from 0).

use serde::Serialize;

use super::CbGeoTarget;
use crate::formats::cbgeo::{self, Branch};
use crate::model::MpState;
use crate::pipeline::PipelineError;
use crate::pipeline::io::folder::Folder;
use crate::pipeline::map::Mapped;

/// What the CB-Geo files hold, for report.json.
#[derive(Clone, Debug, Serialize)]
pub struct CbGeoReport {
    /// The CB-Geo the run file is written for, and why.
    pub branch: Branch,
    pub branch_because: String,
    /// The run file written, and the files it now names.
    pub run_file: String,
    pub stresses_file: String,
    pub pore_pressures_file: Option<String>,
    /// The key forms written.
    pub stresses_key: String,
    pub particles: usize,
    pub two_phase_particles: usize,
    pub conventions: Vec<String>,
}

/// The name of the stresses file a3d-init writes.
const STRESSES: &str = "particles-stresses.txt";
/// The name of the pore pressure file a3d-init writes.
const PORE_PRESSURES: &str = "particles-pore-pressures.txt";

/// `want`, or `a3d-init-<want>` when a file the model names (and that is
/// copied: not the value of an initial-state key that is rewritten) already
/// has it.
fn free_name(target: &CbGeoTarget, want: &str, two_phase: bool) -> String {
    let copied = |r: &&cbgeo::Referenced| !rewritten(r, two_phase);
    if target
        .model
        .referenced
        .iter()
        .filter(copied)
        .any(|r| r.name == want)
    {
        format!("a3d-init-{want}")
    } else {
        want.to_string()
    }
}

/// The names and conventions [`write_model`] uses, for the report (filled
/// before writing, so that report.json and the files agree).
pub fn report(target: &CbGeoTarget) -> CbGeoReport {
    let m = &target.model;
    let two = target.two_phase_particles();
    let stresses_file = free_name(target, STRESSES, two > 0);
    let pore_pressures_file = (two > 0).then(|| free_name(target, PORE_PRESSURES, true));
    let mut conventions = vec![
        "units: Pa (a3d-init's kPa × 1000), m".to_string(),
        "stresses: σxx σyy σzz τxy τyz τxz per line, tension positive, one line per particle in CB-Geo's particle order (ids from 0: the generators in order, a file's lines in order, a gauss generator's cells in set order and each cell's points in CB-Geo's quadrature order)".to_string(),
    ];
    if two < target.particles() {
        conventions.push(
            "single-phase particles: the total stress (CB-Geo's single phase carries no pore pressure)".into(),
        );
    }
    if two > 0 {
        conventions.push(
            "two-phase particles: the effective stress σ′ = σ + p·I, with p = −pwp the pore pressure positive in compression (`id p` lines, Pa); CB-Geo's total σ′ − p·I is the mapped σ (saturated mixture: S = 1)".into(),
        );
    }
    CbGeoReport {
        branch: m.branch,
        branch_because: m.branch_because.clone(),
        run_file: run_file_name(target),
        stresses_key: cbgeo::write::file_key(m.branch, &stresses_file),
        stresses_file,
        pore_pressures_file,
        particles: target.particles(),
        two_phase_particles: two,
        conventions,
    }
}

/// Whether `map` rewrites the key that names `file` (the stresses always;
/// the pore pressures when it writes them), so that the file is not copied.
fn rewritten(file: &cbgeo::Referenced, pore_pressures: bool) -> bool {
    match file.initial_state_key {
        Some("particles_stresses") => true,
        Some(_) => pore_pressures,
        None => false,
    }
}

fn run_file_name(target: &CbGeoTarget) -> String {
    target
        .model
        .json_path
        .file_name()
        .map_or_else(|| "mpm.json".into(), |n| n.to_string_lossy().into_owned())
}

/// The stress CB-Geo stores for a particle (Pa): total for single phase,
/// σ′ = σ − pwp·I (= σ + p·I) for two-phase.
pub fn stored_stress(state: &MpState, two_phase: bool) -> [f64; 6] {
    let mut s = state.total;
    if two_phase {
        for c in s.iter_mut().take(3) {
            *c -= state.pwp;
        }
    }
    s.map(|v| v * 1000.0)
}

/// CB-Geo's pore pressure (Pa, compression positive).
pub fn pore_pressure(state: &MpState) -> f64 {
    -state.pwp * 1000.0
}

/// Writes the CB-Geo project into `out`; returns the names written.
pub fn write_model(
    mapped: &Mapped,
    target: &CbGeoTarget,
    out: &Folder<'_>,
) -> Result<Vec<String>, PipelineError> {
    let m = &target.model;
    // The names report.json states are the names written.
    let r = mapped.report.cbgeo.as_ref().ok_or_else(|| {
        PipelineError::Output("a CB-Geo model's map report has no cbgeo section".into())
    })?;
    let mut written = Vec::new();
    for f in &m.referenced {
        if !rewritten(f, r.pore_pressures_file.is_some()) {
            out.copy(&m.dir.join(&f.name), &f.name)?;
            written.push(f.name.clone());
        }
    }
    let states = &mapped.states;
    let two = target.two_phase();
    out.write(&r.stresses_file, |w| {
        cbgeo::write::stresses(w, states.len(), &|i| stored_stress(&states[i], two[i]))
    })?;
    written.push(r.stresses_file.clone());
    if let Some(pp) = &r.pore_pressures_file {
        // Only the two-phase particles: a single-phase one has no liquid.
        let ids: Vec<usize> = (0..states.len()).filter(|&i| two[i]).collect();
        out.write(pp, |w| {
            cbgeo::write::id_values_of(w, &ids, &|i| pore_pressure(&states[i]))
        })?;
        written.push(pp.clone());
    }
    let text = cbgeo::write::run_file(m, &r.stresses_file, r.pore_pressures_file.as_deref())
        .map_err(crate::formats::FormatError::from)?;
    out.write(&r.run_file, |w| w.write_all(text.as_bytes()))?;
    written.push(r.run_file.clone());
    Ok(written)
}
