//! The leave-one-out objective of the paper (Eq. 4):
//! E(h) = Σⱼ |f(xⱼ) − f̂₋ⱼ(xⱼ, h)|, where f̂₋ⱼ predicts node j from all the
//! other nodes with Eq. 1. A node's own value never predicts it.
//!
//! For speed the neighbour lists are built once, at the support radius of h_max,
//! and reused for every h (only neighbours with d < support·h count). Parallel
//! over nodes with rayon; the sum runs over fixed chunks combined in order, so
//! the value is bit-identical for any thread count.
//!
//! **No-neighbour penalty.** A node with no other node inside the support at h
//! cannot be predicted; its error is taken as |fⱼ − mean(f)|, the error of the
//! most naive prediction. This keeps E(h) finite and makes too-small h costly.

use rayon::prelude::*;

use super::neighbours::NeighbourIndex;
use super::{Kernel, KernelKind};

/// The error norm summed over nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Norm {
    /// Σ|e| (the paper's Eq. 4).
    L1,
    /// √(Σe²/n).
    L2,
    /// Σ|e|/max(|f|, 1e-3·range).
    Relative,
}

/// Why an objective cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LooError {
    #[error("no field to calibrate on: the node table has coordinates but no values")]
    NoFields,
    #[error("at least 3 nodes are needed to calibrate h, found {0}")]
    TooFewNodes(usize),
    #[error("all nodes are at the same place: no spacing to calibrate against")]
    Coincident,
    #[error("node {node} has a non-finite value ({value})")]
    NonFinite { node: usize, value: f64 },
    #[error("field {field}: values too large for a finite error sum (mean or variance overflows)")]
    TooLarge { field: usize },
    #[error("the largest smoothing length {0} is not a positive finite number")]
    BadRange(f64),
}

/// Statistics of the leave-one-out predictions at one h.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LooStats {
    pub h: f64,
    pub objective: f64,
    pub r2: f64,
    pub mae: f64,
    pub max_error: f64,
    pub without_neighbours: usize,
}

/// Eq. 4 with neighbour lists built once.
pub struct LooObjective {
    kernel: KernelKind,
    /// Row-major n × n_fields, each field divided by its scale.
    values: Vec<f64>,
    n_fields: usize,
    /// Per-field scale (1 for one field; the standard deviation for joint calibration).
    scale: Vec<f64>,
    mean: Vec<f64>,
    offsets: Vec<usize>,
    neighbours: Vec<(u32, f64)>,
    h_max: f64,
    constant: bool,
}

const CHUNK: usize = 1024;

impl LooObjective {
    /// Builds the objective for `n_fields` fields (row-major `values`). With more
    /// than one field each is normalised by its standard deviation (joint calibration).
    pub fn new(
        positions: &[[f64; 3]],
        dim: usize,
        values: &[f64],
        n_fields: usize,
        kernel: KernelKind,
        h_max: f64,
    ) -> Result<LooObjective, LooError> {
        let n = positions.len();
        if n_fields == 0 {
            return Err(LooError::NoFields);
        }
        if n < 3 {
            return Err(LooError::TooFewNodes(n));
        }
        if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(LooError::NonFinite {
                node: i / n_fields.max(1) + 1,
                value: *v,
            });
        }
        if !(h_max.is_finite() && h_max > 0.0) {
            return Err(LooError::BadRange(h_max));
        }
        let first = positions[0];
        if positions.iter().all(|p| p == &first) {
            return Err(LooError::Coincident);
        }
        let mut mean = vec![0.0; n_fields];
        let mut scale = vec![1.0; n_fields];
        for k in 0..n_fields {
            let m = (0..n).map(|i| values[i * n_fields + k]).sum::<f64>() / n as f64;
            let var = (0..n)
                .map(|i| (values[i * n_fields + k] - m).powi(2))
                .sum::<f64>()
                / n as f64;
            if !m.is_finite() || !var.is_finite() {
                return Err(LooError::TooLarge { field: k + 1 });
            }
            mean[k] = m;
            if n_fields > 1 && var > 0.0 {
                scale[k] = var.sqrt();
            }
        }
        let constant = (0..n_fields).all(|k| (0..n).all(|i| values[i * n_fields + k] == values[k]));
        let scaled: Vec<f64> = values
            .iter()
            .enumerate()
            .map(|(i, v)| v / scale[i % n_fields])
            .collect();
        let mean: Vec<f64> = mean.iter().zip(&scale).map(|(m, s)| m / s).collect();
        let index = NeighbourIndex::new(positions, dim);
        let radius = kernel.support() * h_max;
        let lists: Vec<Vec<(u32, f64)>> = positions
            .par_chunks(CHUNK)
            .enumerate()
            .flat_map_iter(|(c, chunk)| {
                let mut scratch = Vec::new();
                chunk
                    .iter()
                    .enumerate()
                    .map(|(k, p)| {
                        let i = (c * CHUNK + k) as u32;
                        index.within(*p, radius, &mut scratch);
                        scratch
                            .iter()
                            .copied()
                            .filter(|(j, _)| *j != i)
                            .collect::<Vec<_>>()
                    })
                    .collect::<Vec<_>>()
            })
            .collect();
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0);
        let mut neighbours = Vec::with_capacity(lists.iter().map(Vec::len).sum());
        for l in lists {
            neighbours.extend(l);
            offsets.push(neighbours.len());
        }
        Ok(LooObjective {
            kernel,
            values: scaled,
            n_fields,
            scale,
            mean,
            offsets,
            neighbours,
            h_max,
            constant,
        })
    }

    /// True when every field is constant: every h predicts it exactly.
    pub fn is_constant(&self) -> bool {
        self.constant
    }

    pub fn h_max(&self) -> f64 {
        self.h_max
    }

    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Prediction errors of node j (one per field, in scaled units); `false` when
    /// node j has no neighbour inside the support (the penalty is used).
    fn node_errors(&self, j: usize, h: f64, out: &mut [f64]) -> bool {
        let nf = self.n_fields;
        let support = self.kernel.support() * h;
        let mut sum_w = 0.0;
        out.iter_mut().for_each(|v| *v = 0.0);
        for &(i, d) in &self.neighbours[self.offsets[j]..self.offsets[j + 1]] {
            if d >= support {
                break;
            }
            let w = self.kernel.shape(d / h);
            if w <= 0.0 {
                continue;
            }
            sum_w += w;
            for (k, o) in out.iter_mut().enumerate() {
                *o += w * self.values[i as usize * nf + k];
            }
        }
        let own = &self.values[j * nf..(j + 1) * nf];
        if sum_w > 0.0 {
            for (k, o) in out.iter_mut().enumerate() {
                *o = own[k] - *o / sum_w;
            }
            true
        } else {
            for (k, o) in out.iter_mut().enumerate() {
                *o = own[k] - self.mean[k];
            }
            false
        }
    }

    /// E(h) in the given norm (scaled units for joint calibration; the field's own
    /// units for one field).
    pub fn evaluate(&self, h: f64, norm: Norm) -> f64 {
        let n = self.len();
        let nf = self.n_fields;
        let range = self.range();
        let chunk_sums: Vec<f64> = (0..n)
            .collect::<Vec<_>>()
            .par_chunks(CHUNK)
            .map(|idx| {
                let mut e = vec![0.0; nf];
                let mut s = 0.0;
                for &j in idx {
                    self.node_errors(j, h, &mut e);
                    for (k, v) in e.iter().enumerate() {
                        s += match norm {
                            Norm::L1 => v.abs(),
                            Norm::L2 => v * v,
                            Norm::Relative => {
                                v.abs() / self.values[j * nf + k].abs().max(1e-3 * range)
                            }
                        };
                    }
                }
                s
            })
            .collect();
        let total: f64 = chunk_sums.iter().sum();
        match norm {
            Norm::L2 => (total / (n * nf) as f64).sqrt(),
            _ => total,
        }
    }

    fn range(&self) -> f64 {
        let (lo, hi) = self
            .values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(*v), b.max(*v))
            });
        (hi - lo).max(1e-300)
    }

    /// R², MAE and max error of the predictions at h, in the field's units
    /// (first field when several).
    pub fn stats(&self, h: f64) -> LooStats {
        let n = self.len();
        let nf = self.n_fields;
        let mut e = vec![0.0; nf];
        let (mut sse, mut sst, mut mae, mut max_error, mut without) = (0.0, 0.0, 0.0, 0.0f64, 0);
        for j in 0..n {
            if !self.node_errors(j, h, &mut e) {
                without += 1;
            }
            let err = e[0] * self.scale[0];
            sse += err * err;
            sst += ((self.values[j * nf] - self.mean[0]) * self.scale[0]).powi(2);
            mae += err.abs();
            max_error = max_error.max(err.abs());
        }
        LooStats {
            h,
            objective: self.evaluate(h, Norm::L1),
            r2: if sst > 0.0 { 1.0 - sse / sst } else { 1.0 },
            mae: mae / n as f64,
            max_error,
            without_neighbours: without,
        }
    }
}

/// O(n²) oracle of [`LooObjective::evaluate`] for one field and the L1 norm.
pub fn loo_brute_force(
    positions: &[[f64; 3]],
    dim: usize,
    values: &[f64],
    kernel: KernelKind,
    h: f64,
) -> f64 {
    let n = positions.len();
    let mean = values.iter().sum::<f64>() / n as f64;
    let support = kernel.support() * h;
    let mut total = 0.0;
    for j in 0..n {
        let mut pairs: Vec<(f64, usize)> = (0..n)
            .filter(|&i| i != j)
            .map(|i| {
                (
                    (0..dim)
                        .map(|k| (positions[i][k] - positions[j][k]).powi(2))
                        .sum::<f64>()
                        .sqrt(),
                    i,
                )
            })
            .filter(|(d, _)| *d < support)
            .collect();
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let (mut num, mut den) = (0.0, 0.0);
        for (d, i) in pairs {
            let w = kernel.shape(d / h);
            if w > 0.0 {
                num += w * values[i];
                den += w;
            }
        }
        total += if den > 0.0 {
            (values[j] - num / den).abs()
        } else {
            (values[j] - mean).abs()
        };
    }
    total
}
