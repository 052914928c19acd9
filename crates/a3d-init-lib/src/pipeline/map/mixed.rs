//! Stage 6 of [`super::map`]: MPM-MIXED models. Anura3D integrates a fully
//! filled element at one point and, after its first step, gives every MP the
//! state of the element's first MP; by default each such element carries its
//! volume-weighted mean state on all its MPs. The means themselves are in
//! [`crate::state::mixed`].

use super::MixedState;
use crate::model::{ComputationMethod, MpState};
use crate::pipeline::Project;
use crate::state;

/// What [`collapse_mixed`] did.
#[derive(Clone, Debug, Default)]
pub struct Collapse {
    /// The choice applied: `None` unless the model is MPM-MIXED.
    pub applied: Option<MixedState>,
    pub notes: Vec<String>,
    pub warnings: Vec<String>,
}

/// On an MPM-MIXED `project`, gives the MPs of each fully filled element their
/// volume-weighted mean state (`mode` `Mean`), or keeps them and warns
/// (`PerMp`); other models are left as they are.
pub fn collapse_mixed(project: &Project, mode: MixedState, states: &mut [MpState]) -> Collapse {
    if project.method != ComputationMethod::MpmMixed {
        return Collapse::default();
    }
    let points = &project.points;
    let spread = state::mixed::element_spread(points, states);
    let mut out = Collapse {
        applied: Some(mode),
        ..Collapse::default()
    };
    match mode {
        MixedState::Mean => {
            state::mixed::average_elements(&project.model, points, states);
            out.notes.push(format!(
                "MPM-MIXED: each of the {} fully filled elements carries its volume-weighted mean state on all its MPs (Anura3D integrates such an element at one point and gives every MP the state of its first MP after the first step); the largest spread inside an element was {:.3} kPa in pwp and {:.3} kPa in total stress; use $$COMPUTATION_METHOD MPM-MP when per-MP detail matters",
                spread.elements, spread.pwp, spread.stress
            ));
        }
        MixedState::PerMp => {
            out.warnings.push(format!(
                "MPM-MIXED with the mixed-state policy per-mp: Anura3D will replace the state of every MP of the {} fully filled elements by that of the element's first MP after the first step (largest spread inside an element: {:.3} kPa pwp, {:.3} kPa stress); use $$COMPUTATION_METHOD MPM-MP to keep per-MP detail",
                spread.elements, spread.pwp, spread.stress
            ));
        }
    }
    out
}
