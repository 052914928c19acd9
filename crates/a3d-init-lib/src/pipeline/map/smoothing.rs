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
            // A support holding thousands of nodes (h in the wrong unit):
            // the mapping's cost grows with the count, to hours.
            if let Some(mean) =
                crowded_support(&nodes.positions, dim, kernel.support() * h, spacing)
            {
                return Err(PipelineError::Option(format!(
                    "smoothing length h = {h} m: the kernel support {:.4} m holds about {mean:.0} FEM nodes around each node (at h near the node spacing l = {spacing:.4} m, a few dozen), so every MP would weigh that many; give an h near l (is h in metres?), or calibrate h",
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

/// The most FEM nodes a given h's support may hold on average: 200 times
/// what the paper's h ≈ l gives in 3D (about 50), far past any smoothing a
/// mapping means.
pub const MAX_MEAN_NEIGHBOURS: f64 = 10_000.0;

/// The mean number of nodes within `support` of a node, where it passes
/// [`MAX_MEAN_NEIGHBOURS`]. An estimate from the median spacing `spacing`
/// first (a triangle mesh holds about 1.15/l² nodes per m², a tetrahedral
/// one about 1.41/l³ per m³), free for every sensible h; past the limit, the
/// count itself around up to 64 nodes spread through the list, so that a
/// graded mesh (a median spacing far below the mean) is not refused on an
/// estimate.
fn crowded_support(positions: &[[f64; 3]], dim: usize, support: f64, spacing: f64) -> Option<f64> {
    use rayon::prelude::*;
    let (ball, density) = if dim == 3 {
        (
            4.0 / 3.0 * std::f64::consts::PI * support.powi(3),
            std::f64::consts::SQRT_2 / spacing.powi(3),
        )
    } else {
        (
            std::f64::consts::PI * support.powi(2),
            2.0 / 3.0f64.sqrt() / spacing.powi(2),
        )
    };
    // NaN (no spacing) counts too.
    if ball * density <= MAX_MEAN_NEIGHBOURS || positions.is_empty() {
        return None;
    }
    let step = positions.len().div_ceil(64);
    let r2 = support * support;
    let counts: Vec<usize> = positions
        .par_iter()
        .step_by(step)
        .map(|q| {
            positions
                .iter()
                .filter(|p| (0..dim).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>() <= r2)
                .count()
                - 1
        })
        .collect();
    let mean = counts.iter().sum::<usize>() as f64 / counts.len() as f64;
    (mean > MAX_MEAN_NEIGHBOURS).then_some(mean)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize, l: f64) -> Vec<[f64; 3]> {
        (0..n * n)
            .map(|k| [(k % n) as f64 * l, (k / n) as f64 * l, 0.0])
            .collect()
    }

    /// Regression: `--h 5` on a 28,000-node FEM 11 m across (l =
    /// 0.04 m) passed the extent rule, and the map ran for minutes with
    /// every MP weighing nearly every node.
    #[test]
    fn a_support_holding_thousands_of_nodes_is_refused() {
        let nodes = grid(150, 0.01);
        let mean = crowded_support(&nodes, 2, 1.0, 0.01).expect("refused");
        assert!(mean > 15_000.0, "{mean}");
        // The paper's h ≈ l, and an h of 20 l, pass.
        assert_eq!(crowded_support(&nodes, 2, 0.02, 0.01), None);
        assert_eq!(crowded_support(&nodes, 2, 0.4, 0.01), None);
    }

    /// The estimate alone never refuses: twin nodes 1 µm apart give a median
    /// spacing of 1 µm, and an estimate of millions, while the support holds
    /// a few dozen nodes.
    #[test]
    fn a_graded_cloud_is_judged_by_its_counts() {
        let mut nodes = grid(60, 1.0);
        let twins: Vec<[f64; 3]> = nodes.iter().map(|p| [p[0] + 1e-6, p[1], 0.0]).collect();
        nodes.extend(twins);
        assert_eq!(crowded_support(&nodes, 2, 2.0, 1e-6), None);
    }
}
