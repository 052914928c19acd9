//! Choosing the smoothing length h: a generic simulated annealing over a scalar
//! objective on a bracket, followed by a deterministic golden-section refinement
//! so the answer does not hinge on luck. Depends on nothing else in the crate;
//! `cli` builds the leave-one-out objective from `kernel::loo`.

pub mod anneal;
pub mod refine;

pub use anneal::{AnnealSettings, anneal};
pub use refine::golden_section;

/// The result of [`calibrate`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Calibration {
    pub h: f64,
    pub value: f64,
    pub seed: u64,
    pub evaluations: usize,
    /// Every (h, f(h)) the annealer and the refinement evaluated, in order.
    pub trace: Vec<(f64, f64)>,
    pub bracket: (f64, f64),
}

/// Minimises `f` on [lo, hi]: annealing, then golden section around the best
/// point (± the annealer's final step, at least 2 % of the bracket).
pub fn calibrate(
    f: impl Fn(f64) -> f64,
    lo: f64,
    hi: f64,
    settings: &AnnealSettings,
) -> Calibration {
    let annealed = anneal(&f, lo, hi, settings);
    let delta = annealed.final_step.max(0.02 * (hi - lo));
    let (a, b) = ((annealed.x - delta).max(lo), (annealed.x + delta).min(hi));
    let refined = golden_section(&f, a, b, 1e-6 * (hi - lo), 60);
    let mut trace = annealed.trace;
    trace.extend(refined.trace.iter().copied());
    let (h, value) = if refined.value <= annealed.value {
        (refined.x, refined.value)
    } else {
        (annealed.x, annealed.value)
    };
    Calibration {
        h,
        value,
        seed: settings.seed,
        evaluations: trace.len(),
        trace,
        bracket: (lo, hi),
    }
}
