//! Stage 7 of [`super::map`]: is the mapped state believable? The pwp field
//! checked against hydrostatics (warnings, never errors; the checks are
//! in [`crate::state::plausibility`]), and every value finite (an error: nothing
//! is written).

use crate::model::MpState;
use crate::pipeline::PipelineError;

/// The plausibility warnings of the pwp in `states` at `positions` (`dim`
/// dimensions, gravity `g` in m/s²).
pub fn check_plausibility(
    positions: &[[f64; 3]],
    states: &[MpState],
    dim: usize,
    g: f64,
) -> Vec<String> {
    crate::state::plausibility::check(positions, states, dim, g)
        .into_iter()
        .map(|f| f.message)
        .collect()
}

/// An error naming the first MP (1-based) with a non-finite pwp or stress.
pub fn check_finite(states: &[MpState]) -> Result<(), PipelineError> {
    match states
        .iter()
        .position(|s| !s.pwp.is_finite() || s.total.iter().any(|v| !v.is_finite()))
    {
        Some(bad) => Err(PipelineError::Numerical(format!(
            "MP {} got a non-finite value; nothing was written",
            bad + 1
        ))),
        None => Ok(()),
    }
}
