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
/// Why a calibration could not run or gave no usable answer.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CalibrateError {
    #[error("the bracket [{lo}, {hi}] is not a finite, non-empty interval")]
    BadBracket { lo: f64, hi: f64 },
    #[error(
        "the objective is not finite at h = {h} ({value}): the field values are too large or not numbers"
    )]
    NonFinite { h: f64, value: f64 },
}

/// [`calibrate`] with its inputs and every objective value checked: the
/// bracket must be finite with lo ≤ hi, and every evaluation of `f` must be
/// finite. The number of evaluations is bounded (9 + iterations + 64) whatever
/// `f` returns.
pub fn try_calibrate(
    f: impl Fn(f64) -> f64,
    lo: f64,
    hi: f64,
    settings: &AnnealSettings,
) -> Result<Calibration, CalibrateError> {
    if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
        return Err(CalibrateError::BadBracket { lo, hi });
    }
    let bad = std::cell::Cell::new(None);
    let guarded = |h: f64| {
        let v = f(h);
        if v.is_finite() {
            v
        } else {
            if bad.get().is_none() {
                bad.set(Some((h, v)));
            }
            f64::INFINITY
        }
    };
    let c = calibrate(guarded, lo, hi, settings);
    match bad.get() {
        Some((h, value)) => Err(CalibrateError::NonFinite { h, value }),
        None => Ok(c),
    }
}

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_objectives_and_brackets_are_errors_not_hangs() {
        let s = AnnealSettings::default();
        let e = try_calibrate(|h| if h > 0.5 { f64::NAN } else { h }, 0.0, 1.0, &s).unwrap_err();
        assert!(matches!(e, CalibrateError::NonFinite { .. }), "{e}");
        let e = try_calibrate(|_| f64::INFINITY, 0.0, 1.0, &s).unwrap_err();
        assert!(matches!(e, CalibrateError::NonFinite { .. }), "{e}");
        for (lo, hi) in [(0.0, f64::INFINITY), (f64::NAN, 1.0), (2.0, 1.0)] {
            assert!(try_calibrate(|h| h, lo, hi, &s).is_err());
        }
        // The unchecked entry point stays bounded on a non-finite bracket.
        let c = calibrate(|h| h, 0.0, f64::MAX, &s);
        assert!(c.evaluations <= 9 + s.iterations + 64);
        let c = try_calibrate(|h| (h - 0.3).abs(), 0.0, 1.0, &s).unwrap();
        assert!((c.h - 0.3).abs() < 1e-4);
    }
}
