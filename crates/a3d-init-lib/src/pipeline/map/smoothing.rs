//! Stage 2 of [`super::map`]: the smoothing length h, by the paper's spacing
//! rule, as given, or calibrated by leave-one-out, and how report.json
//! describes the choice.

use super::{SmoothingLength, StressSource};
use crate::kernel::mapper;
use crate::kernel::{Kernel, KernelKind};
use crate::model::{FemNodes, Quantity};
use crate::pipeline::PipelineError;
use crate::pipeline::calibrate::{Outcome, calibrate_h};

/// The smoothing length chosen for a mapping.
#[derive(Clone, Debug)]
pub struct ChosenH {
    /// h (m), and how it was chosen, as report.json says it.
    pub h: f64,
    pub rule: String,
    /// l: the median distance from a FEM node to its nearest other node (m).
    pub spacing: f64,
    /// The leave-one-out calibration, when h was calibrated.
    pub calibration: Option<Outcome>,
}

/// How a calibrated h is described in the report.
fn calibrated_rule(outcome: &Outcome, seed: u64) -> String {
    format!(
        "calibrated by leave-one-out (paper Eq. 4) on {}: h/l = {:.3}, LOO R² = {:.5}, seed {}{}",
        outcome.fields.join(", "),
        outcome.h_over_l,
        outcome.stats.r2,
        seed,
        outcome
            .fallback
            .as_deref()
            .map(|f| format!("; {f}"))
            .unwrap_or_default()
    )
}

/// Chooses h for `kernel` on `nodes` as `how` says. A calibration fits every
/// FEM field when the (resolved) stress `source` is `fem`, else the pore-water
/// pressure alone. A given h must be positive and its support no more than
/// twice the FEM's extent.
pub fn choose_h(
    nodes: &FemNodes,
    kernel: KernelKind,
    how: &SmoothingLength,
    source: StressSource,
) -> Result<ChosenH, PipelineError> {
    let dim = nodes.dim;
    let spacing = mapper::median_spacing(&nodes.positions, dim);
    let chosen = |h: f64, rule: String| ChosenH {
        h,
        rule,
        spacing,
        calibration: None,
    };
    Ok(match how {
        SmoothingLength::Calibrated { outcome, seed } => ChosenH {
            h: outcome.h,
            rule: calibrated_rule(outcome, *seed),
            spacing,
            calibration: Some((**outcome).clone()),
        },
        SmoothingLength::Calibrate { seed } => {
            let fields: Vec<Quantity> = if source == StressSource::Fem {
                nodes.fields.iter().map(|(q, _)| *q).collect()
            } else {
                vec![Quantity::Pwp]
            };
            let outcome = calibrate_h(nodes, &fields, kernel, *seed, crate::kernel::loo::Norm::L1)?;
            ChosenH {
                h: outcome.h,
                rule: calibrated_rule(&outcome, *seed),
                spacing,
                calibration: Some(outcome),
            }
        }
        SmoothingLength::Metres(h) if *h > 0.0 && h.is_finite() => {
            // A support wider than the whole FEM makes every MP weigh every
            // node (a global average at O(MPs × nodes) cost): refused.
            let diagonal = crate::diagnose::Extent::of(&nodes.positions, dim).map_or(0.0, |e| {
                (0..dim)
                    .map(|k| (e.hi[k] - e.lo[k]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            });
            if diagonal > 0.0 && kernel.support() * h > 2.0 * diagonal {
                return Err(PipelineError::Option(format!(
                    "smoothing length h = {h} m: the kernel support {:.4} m is more than twice the FEM's extent ({diagonal:.4} m across), so every MP would average every node; give an h near the node spacing l = {spacing:.4} m, or calibrate h",
                    kernel.support() * h
                )));
            }
            // A support far below the node spacing reaches no node.
            if spacing > 0.0 && kernel.support() * h < 1e-3 * spacing {
                return Err(PipelineError::Option(format!(
                    "smoothing length h = {h:?} m: the kernel support {:e} m is below a thousandth of the node spacing l = {spacing:.4} m, so no MP would have a FEM node in reach; give an h near l, or calibrate h",
                    kernel.support() * h
                )));
            }
            chosen(*h, "given as the smoothing length h".to_string())
        }
        SmoothingLength::Metres(h) => {
            return Err(PipelineError::Option(format!(
                "smoothing length h = {h}: h must be a positive number of metres"
            )));
        }
        SmoothingLength::SpacingRule => {
            let factor = kernel.spacing_factor();
            chosen(
                factor * spacing,
                format!(
                    "spacing rule h = {factor}·l with l = {spacing:.6} m, the median nearest-node spacing (paper §2.2, {})",
                    if dim == 2 {
                        "fitted on triangle meshes"
                    } else {
                        "fitted on 2D triangle meshes; on this 3D model a rule of thumb: calibrate the smoothing length h (auto)"
                    }
                ),
            )
        }
    })
}
