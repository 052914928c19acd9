//! The solve itself: one factorisation of the elastic stiffness K, the elastic
//! solution K u = f (gravity and the fixed pore-water force switched on at
//! once), and, where that leaves MPs outside their yield surface, an implicit
//! load ramp with the return map: in each load step the modified Newton
//! iteration u ← u + K⁻¹ r (the elastic K kept, so no refactorisation)
//! accelerated by Anderson mixing, cutting the step where it stalls. The
//! largest load factor reached is the gravity multiplier at which the state
//! stops holding; below 1, no equilibrium exists under gravity and the best
//! state at full gravity (smallest residual) is kept.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

use std::collections::VecDeque;
use std::time::Instant;

use rayon::prelude::*;

use super::super::MpmError;
use super::EquilibriumSettings;
use super::sparse::Cholesky;
use super::system::System;

/// What [`solve`] found, per integration group.
pub(super) struct Solved {
    pub stress: Vec<[f64; 6]>,
    /// Per group: its last stress update returned to the yield surface.
    pub yielding: Vec<bool>,
    pub converged: bool,
    pub load_factor: f64,
    /// Residual ratio of the elastic solution (before any return mapping).
    pub elastic_ratio: f64,
    /// Iterations after the elastic solve, in all load steps.
    pub iterations: usize,
    pub load_steps: usize,
    pub stiffness_nnz: usize,
    pub factor_nnz: usize,
    pub assembly_s: f64,
    pub factor_s: f64,
    pub elastic_s: f64,
    pub plastic_s: f64,
}

/// Depth of the Anderson mixing history.
const ANDERSON_DEPTH: usize = 6;
/// Iterations without a 0.1 % improvement after which a load step is cut.
const STALL: usize = 40;
/// Smallest load step tried before the ramp gives up.
const MIN_STEP: f64 = 1.0 / 512.0;

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Anderson acceleration of the fixed-point map x ↦ x + K⁻¹ r(x).
struct Anderson {
    xs: VecDeque<Vec<f64>>,
    gs: VecDeque<Vec<f64>>,
}

impl Anderson {
    fn new() -> Anderson {
        Anderson {
            xs: VecDeque::new(),
            gs: VecDeque::new(),
        }
    }

    fn reset(&mut self) {
        self.xs.clear();
        self.gs.clear();
    }

    /// The next iterate from `x` and its correction `g` = K⁻¹ r(x).
    fn next(&mut self, x: &[f64], g: &[f64]) -> Vec<f64> {
        self.xs.push_back(x.to_vec());
        self.gs.push_back(g.to_vec());
        if self.xs.len() > ANDERSON_DEPTH + 1 {
            self.xs.pop_front();
            self.gs.pop_front();
        }
        let m = self.xs.len() - 1;
        let mut out: Vec<f64> = x.iter().zip(g).map(|(a, b)| a + b).collect();
        if m == 0 {
            return out;
        }
        let dg: Vec<Vec<f64>> = (0..m)
            .map(|j| {
                self.gs[j + 1]
                    .iter()
                    .zip(&self.gs[j])
                    .map(|(a, b)| a - b)
                    .collect()
            })
            .collect();
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let gram = nalgebra::DMatrix::from_fn(m, m, |i, j| dot(&dg[i], &dg[j]));
        let rhs = nalgebra::DVector::from_fn(m, |i, _| dot(&dg[i], g));
        let trace: f64 = (0..m).map(|i| gram[(i, i)]).sum();
        let regularised = gram + nalgebra::DMatrix::identity(m, m) * (1e-12 * trace);
        let Some(gamma) = regularised.cholesky().map(|c| c.solve(&rhs)) else {
            self.reset();
            return out;
        };
        for j in 0..m {
            let gj = gamma[j];
            if !gj.is_finite() {
                self.reset();
                return x.iter().zip(g).map(|(a, b)| a + b).collect();
            }
            let (x1, x0) = (&self.xs[j + 1], &self.xs[j]);
            for k in 0..out.len() {
                out[k] -= gj * ((x1[k] - x0[k]) + dg[j][k]);
            }
        }
        out
    }
}

/// Group stresses after the strain from `x − x_c` on top of `committed`,
/// with each group's return map (`plastic`, else elastic only); and which
/// groups yielded.
fn evaluate<const D: usize, const NC: usize>(
    system: &System<D, NC>,
    x: &[f64],
    x_c: &[f64],
    committed: &[[f64; 6]],
    plastic: bool,
) -> (Vec<[f64; 6]>, Vec<bool>) {
    let delta: Vec<f64> = x.iter().zip(x_c).map(|(a, b)| a - b).collect();
    let u = system.displacements(&delta);
    system
        .groups
        .par_iter()
        .zip(committed)
        .with_min_len(1024)
        .map(|(g, s0)| {
            let strain = system.group_strain(&u, g);
            let mut s = *s0;
            let law = &system.laws[g.law as usize];
            if !plastic {
                law.elasticity.add_increment(&mut s, &strain);
                return (s, false);
            }
            let kind = law.update(&mut s, &strain, D == 2);
            (s, kind.is_plastic())
        })
        .unzip()
}

/// The out-of-balance force at the free unknowns for group stresses `stress`
/// at load factor `load`, and its ratio to the external force.
fn residual<const D: usize, const NC: usize>(
    system: &System<D, NC>,
    stress: &[[f64; 6]],
    load: f64,
) -> (Vec<f64>, f64) {
    let r = system.free_residual(&system.group_force(stress), load);
    let ratio = super::super::step::ratio(norm(&r), load * system.external_norm);
    (r, ratio)
}

/// One load step from the committed state to `target`, or `None` when it
/// stalls or the iteration budget runs out.
struct Step {
    x: Vec<f64>,
    stress: Vec<[f64; 6]>,
    yielding: Vec<bool>,
    converged: bool,
}

#[allow(clippy::too_many_arguments)]
fn load_step<const D: usize, const NC: usize>(
    system: &System<D, NC>,
    cholesky: &Cholesky,
    x_start: Vec<f64>,
    x_c: &[f64],
    committed: &[[f64; 6]],
    target: f64,
    tolerance: f64,
    budget: &mut usize,
    keep_best: bool,
) -> Step {
    let mut anderson = Anderson::new();
    let mut x = x_start;
    let mut best: Option<Step> = None;
    let mut best_ratio = f64::INFINITY;
    let mut since_best = 0;
    loop {
        let (stress, yielding) = evaluate(system, &x, x_c, committed, true);
        let (mut r, ratio) = residual(system, &stress, target);
        if ratio <= tolerance {
            return Step {
                x,
                stress,
                yielding,
                converged: true,
            };
        }
        if ratio < 0.999 * best_ratio {
            best_ratio = ratio;
            since_best = 0;
            if keep_best {
                best = Some(Step {
                    x: x.clone(),
                    stress: stress.clone(),
                    yielding: yielding.clone(),
                    converged: false,
                });
            }
        } else {
            since_best += 1;
            if ratio > 10.0 * best_ratio {
                anderson.reset();
            }
        }
        if since_best > STALL || *budget == 0 || !ratio.is_finite() {
            return best.unwrap_or(Step {
                x,
                stress,
                yielding,
                converged: false,
            });
        }
        *budget -= 1;
        cholesky.solve(&mut r);
        x = anderson.next(&x, &r);
    }
}

/// Solves `system` for equilibrium under gravity (see the module header).
pub(super) fn solve<const D: usize, const NC: usize>(
    system: &System<D, NC>,
    settings: &EquilibriumSettings,
) -> Result<Solved, MpmError> {
    let t = Instant::now();
    let pattern = system.pattern();
    let values = system.stiffness(&pattern);
    let assembly_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let cholesky = Cholesky::factor(&pattern, &values)?;
    let factor_s = t.elapsed().as_secs_f64();
    drop(values);
    let n_groups = system.groups.len();
    let zero = vec![[0.0; 6]; n_groups];
    let n = system.n_free;
    let x_c0 = vec![0.0; n];

    let t = Instant::now();
    let mut x_el = system.free_residual(&vec![0.0; system.external.len()], 1.0);
    cholesky.solve(&mut x_el);
    let (elastic, _) = evaluate(system, &x_el, &x_c0, &zero, false);
    let (_, elastic_ratio) = residual(system, &elastic, 1.0);
    drop(elastic);
    let elastic_s = t.elapsed().as_secs_f64();
    let (stress, yielding) = evaluate(system, &x_el, &x_c0, &zero, true);
    let mut out = Solved {
        stress,
        yielding,
        converged: false,
        load_factor: 0.0,
        elastic_ratio,
        iterations: 0,
        load_steps: 1,
        stiffness_nnz: pattern.nnz(),
        factor_nnz: cholesky.nnz(),
        assembly_s,
        factor_s,
        elastic_s,
        plastic_s: 0.0,
    };
    let tolerance = settings.tolerance;
    if elastic_ratio > 1e-6 {
        // A factorisation this far off is a matrix that is singular in all
        // but round-off: some part of the model is not held.
        return Err(MpmError::InvalidSettings(format!(
            "the elastic solve leaves an out-of-balance force ratio of {elastic_ratio:.2e}: the stiffness matrix is nearly singular (check that the GOM's fixities hold every part of the model)"
        )));
    }
    if !out.yielding.iter().any(|&y| y) {
        out.converged = true;
        out.load_factor = 1.0;
        return Ok(out);
    }

    // The load ramp with the return map.
    let t = Instant::now();
    let mut budget = settings.max_iterations;
    let mut x_c = x_c0;
    let mut committed = zero;
    let mut load_c = 0.0_f64;
    let mut step = 1.0_f64;
    let mut steps = 0;
    let mut iterations = 0;
    loop {
        let target = (load_c + step).min(1.0);
        let x_start: Vec<f64> = x_c
            .iter()
            .zip(&x_el)
            .map(|(a, b)| a + (target - load_c) * b)
            .collect();
        let before = budget;
        let result = load_step(
            system,
            &cholesky,
            x_start,
            &x_c,
            &committed,
            target,
            tolerance,
            &mut budget,
            false,
        );
        let used = before - budget;
        iterations += used;
        if result.converged {
            steps += 1;
            x_c = result.x;
            committed = result.stress;
            load_c = target;
            out.yielding = result.yielding;
            if target >= 1.0 {
                out.converged = true;
                break;
            }
            if used < 30 {
                step *= 2.0;
            }
            step = step.min(1.0 - load_c);
            continue;
        }
        step /= 4.0;
        if step < MIN_STEP || budget == 0 {
            break;
        }
    }
    out.load_factor = load_c;
    out.load_steps = steps.max(1);
    if out.converged {
        out.stress = committed;
    } else {
        // No equilibrium at full gravity: the best state there, from the
        // last one that held.
        let tail_budget = settings.max_iterations.min(400);
        let mut tail = tail_budget;
        let x_start: Vec<f64> = x_c
            .iter()
            .zip(&x_el)
            .map(|(a, b)| a + (1.0 - load_c) * b)
            .collect();
        let best = load_step(
            system, &cholesky, x_start, &x_c, &committed, 1.0, tolerance, &mut tail, true,
        );
        iterations += tail_budget - tail;
        out.stress = best.stress;
        out.yielding = best.yielding;
        out.converged = best.converged;
        if best.converged {
            out.load_factor = 1.0;
        }
    }
    out.iterations = iterations;
    out.plastic_s = t.elapsed().as_secs_f64();
    Ok(out)
}
