//! Simulated annealing over one scalar variable on a bracket [lo, hi].
//!
//! Schedule (documented so results can be reproduced by hand):
//! 1. Evaluate 9 evenly spaced points of the bracket; start from the best.
//! 2. T₀ = the standard deviation of those 9 values (1 if they are all equal).
//! 3. For k = 0 … iterations−1: T_k = T₀·0.95ᵏ; step width
//!    w_k = 0.25·(hi − lo)·max(√(T_k/T₀), 0.005); candidate x' uniform in
//!    [x − w_k, x + w_k], clamped to the bracket; accept when f(x') < f(x) or with
//!    probability exp(−(f(x') − f(x))/T_k) (Metropolis).
//! 4. Return the best point seen.
//!
//! The random numbers come from `ChaCha8Rng::seed_from_u64(seed)`: the same seed
//! gives the same result on every machine and thread count.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Settings of [`anneal`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct AnnealSettings {
    pub seed: u64,
    pub iterations: usize,
    pub cooling: f64,
}

impl Default for AnnealSettings {
    fn default() -> AnnealSettings {
        AnnealSettings {
            seed: 1,
            iterations: 150,
            cooling: 0.95,
        }
    }
}

/// What [`anneal`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct Annealed {
    pub x: f64,
    pub value: f64,
    /// The last step width, used to size the refinement bracket.
    pub final_step: f64,
    pub trace: Vec<(f64, f64)>,
}

/// Minimises `f` on [lo, hi] by simulated annealing.
pub fn anneal(f: impl Fn(f64) -> f64, lo: f64, hi: f64, settings: &AnnealSettings) -> Annealed {
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let mut trace = Vec::with_capacity(settings.iterations + 9);
    let samples: Vec<(f64, f64)> = (0..9)
        .map(|k| {
            let x = lo + (hi - lo) * k as f64 / 8.0;
            (x, f(x))
        })
        .collect();
    trace.extend(samples.iter().copied());
    let (mut x, mut fx) =
        samples.iter().copied().fold(
            (lo, f64::INFINITY),
            |best, s| if s.1 < best.1 { s } else { best },
        );
    let mean = samples.iter().map(|s| s.1).sum::<f64>() / 9.0;
    let sd = (samples.iter().map(|s| (s.1 - mean).powi(2)).sum::<f64>() / 9.0).sqrt();
    let t0 = if sd > 0.0 && sd.is_finite() { sd } else { 1.0 };
    let (mut best_x, mut best_f) = (x, fx);
    let mut t = t0;
    let mut width = 0.25 * (hi - lo);
    for _ in 0..settings.iterations {
        width = 0.25 * (hi - lo) * (t / t0).sqrt().max(0.005);
        if !(width.is_finite() && width >= 0.0) {
            // A non-finite bracket: no step can be drawn (and random_range would panic).
            break;
        }
        let candidate = (x + rng.random_range(-width..=width)).clamp(lo, hi);
        let fc = f(candidate);
        trace.push((candidate, fc));
        let accept = fc < fx || rng.random_range(0.0..1.0) < (-(fc - fx) / t).exp();
        if accept {
            x = candidate;
            fx = fc;
        }
        if fx < best_f {
            best_x = x;
            best_f = fx;
        }
        t *= settings.cooling;
    }
    Annealed {
        x: best_x,
        value: best_f,
        final_step: width,
        trace,
    }
}
