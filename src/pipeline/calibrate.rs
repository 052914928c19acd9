//! The smoothing length h from the FEM data itself (paper Eq. 4): used by
//! `calibrate`, by `map --h auto` and by the demo.

use serde::Serialize;

use super::PipelineError;
use crate::calibrate::{AnnealSettings, Calibration, try_calibrate};
use crate::kernel::loo::{LooObjective, LooStats, Norm};
use crate::kernel::mapper;
use crate::kernel::{Kernel, KernelKind};
use crate::model::{FemNodes, Quantity};

/// The outcome of a calibration.
#[derive(Clone, Debug, Serialize)]
pub struct Outcome {
    pub h: f64,
    /// Median nearest-node spacing l.
    pub spacing: f64,
    pub h_over_l: f64,
    /// The kernel's short name (`cubic`, `gaussian`, `wendland`).
    pub kernel: &'static str,
    pub fields: Vec<String>,
    pub norm: Norm,
    pub stats: LooStats,
    pub calibration: Calibration,
    /// Set when every h is optimal (constant field): h then follows the spacing rule.
    pub fallback: Option<String>,
    /// (h, objective) on an even grid over the bracket, for plotting.
    pub curve: Vec<(f64, f64)>,
}

/// Field selection: one quantity or every field of the file. `files` names
/// the FEM file(s) in errors; a table without any field is an error.
pub fn select_fields(
    fem: &FemNodes,
    field: &str,
    files: &str,
) -> Result<Vec<Quantity>, PipelineError> {
    if fem.fields.is_empty() {
        return Err(PipelineError::Input(format!(
            "{files}: no field to calibrate on: the table has no pore-water pressure or stress column (only coordinates{})",
            if fem.region.is_some() {
                " and regions"
            } else {
                ""
            }
        )));
    }
    if field == "all" {
        return Ok(fem.fields.iter().map(|(q, _)| *q).collect());
    }
    let q = Quantity::from_name(field).ok_or_else(|| {
        PipelineError::Input(format!(
            "--field {field}: expected pwp, sxx, syy, szz, sxy, syz, sxz, esxx, … or all"
        ))
    })?;
    if fem.field(q).is_none() {
        return Err(PipelineError::Input(format!(
            "--field {field}: {files} has no such column (it has: {})",
            fem.fields
                .iter()
                .map(|(q, _)| q.name())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    Ok(vec![q])
}

/// Calibrates h on `fields` of `fem` (paper Eq. 4): the leave-one-out error
/// minimised by seeded simulated annealing and a golden-section refinement
/// over [0.3 l, 2.5 l], l the median nearest-node spacing.
pub fn calibrate_h(
    fem: &FemNodes,
    fields: &[Quantity],
    kernel: KernelKind,
    seed: u64,
    norm: Norm,
) -> Result<Outcome, PipelineError> {
    let values = field_values(fem, fields);
    let spacing = mapper::median_spacing(&fem.positions, fem.dim);
    let (lo, hi) = (0.3 * spacing, 2.5 * spacing);
    let objective = LooObjective::new(&fem.positions, fem.dim, &values, fields.len(), kernel, hi)
        .map_err(|e| PipelineError::Input(format!("calibration: {e}")))?;
    let norm_kind = norm;
    let settings = AnnealSettings {
        seed,
        ..AnnealSettings::default()
    };
    let f = |h: f64| objective.evaluate(h, norm_kind);
    let mut calibration = try_calibrate(f, lo, hi, &settings)
        .map_err(|e| PipelineError::Input(format!("calibration: {e}")))?;
    let mut fallback = None;
    if objective.is_constant() {
        let factor = kernel.spacing_factor();
        calibration.h = factor * spacing;
        fallback = Some(format!(
            "the field is constant, so every h predicts it exactly; h follows the spacing rule {factor}·l"
        ));
    }
    let curve = (0..=120)
        .map(|k| lo + (hi - lo) * k as f64 / 120.0)
        .map(|h| (h, f(h)))
        .collect();
    let stats = objective.stats(calibration.h);
    Ok(Outcome {
        h: calibration.h,
        spacing,
        h_over_l: calibration.h / spacing,
        kernel: kernel.name(),
        fields: fields.iter().map(|q| q.name()).collect(),
        norm,
        stats,
        calibration,
        fallback,
        curve,
    })
}

/// The values of `fields` at every node, row-major: node i's value of
/// `fields[k]` at `i * fields.len() + k` (0 where the file lacks the field).
fn field_values(fem: &FemNodes, fields: &[Quantity]) -> Vec<f64> {
    let n = fem.len();
    let nf = fields.len();
    let mut values = vec![0.0; n * nf];
    for (k, q) in fields.iter().enumerate() {
        for (i, v) in fem.field(*q).unwrap_or(&[]).iter().enumerate() {
            values[i * nf + k] = *v;
        }
    }
    values
}
