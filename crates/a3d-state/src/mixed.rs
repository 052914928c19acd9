//! MPM-MIXED as Anura3D runs it: a fully filled element is integrated at its
//! Gauss point, and after the first time step every MP of the element carries
//! the state of the element's first MP (`formats-notes/anura3d.md` §8: spread
//! inside such an element 0, equal to MP 1's injected value). Per-MP detail
//! inside an element is therefore lost; what survives is MP 1's value.
//!
//! At load step 1 every active element is fully filled: its MPs' volumes add up
//! to the element's volume (also in axisymmetry, where both carry the radius),
//! which exceeds Anura3D's `$$DEGREE_OF_FILLING` (0.9 by default), and elements
//! hold one material each. Pure computation.

use a3d_model::{AnuraModel, MaterialPoint, MpState};

/// Contiguous runs of MPs per element (Anura3D numbers MPs element by element).
fn element_runs(points: &[MaterialPoint]) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
    let mut start = 0;
    std::iter::from_fn(move || {
        if start >= points.len() {
            return None;
        }
        let e = points[start].element;
        let end = start
            + points[start..]
                .iter()
                .position(|p| p.element != e)
                .unwrap_or(points.len() - start);
        let run = start..end;
        start = end;
        Some(run)
    })
}

/// The largest differences inside one element between an MP's state and the
/// element's first MP: what the first MPM-MIXED step would overwrite.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Spread {
    /// Fully filled elements with more than one MP.
    pub elements: usize,
    /// kPa
    pub pwp: f64,
    /// kPa, over every total-stress component.
    pub stress: f64,
}

/// Spread of the states inside each element.
pub fn element_spread(points: &[MaterialPoint], states: &[MpState]) -> Spread {
    let mut out = Spread::default();
    for run in element_runs(points) {
        if run.len() < 2 {
            continue;
        }
        out.elements += 1;
        let first = &states[run.start];
        for s in &states[run] {
            out.pwp = out.pwp.max((s.pwp - first.pwp).abs());
            for c in 0..6 {
                out.stress = out.stress.max((s.total[c] - first.total[c]).abs());
            }
        }
    }
    out
}

/// What Anura3D's first MPM-MIXED step does: every MP of an element takes the
/// state of the element's first MP.
pub fn collapse_to_first(points: &[MaterialPoint], states: &mut [MpState]) {
    for run in element_runs(points) {
        let first = states[run.start];
        for s in &mut states[run] {
            *s = first;
        }
    }
}

/// Gives every MP of each fully filled element the element's volume-weighted
/// mean pwp and total stress; the saturation follows from the mean pwp with the
/// material's retention curve (as Anura3D computes it from the MAPF's Pwp).
pub fn average_elements(model: &AnuraModel, points: &[MaterialPoint], states: &mut [MpState]) {
    for run in element_runs(points) {
        let e = points[run.start].element as usize;
        if run.len() < 2 {
            continue;
        }
        let volume: f64 = points[run.clone()].iter().map(|p| p.volume).sum();
        if volume.is_nan() || volume <= 0.0 {
            continue;
        }
        let mut mean = MpState::default();
        for (p, s) in points[run.clone()].iter().zip(&states[run.clone()]) {
            let w = p.volume / volume;
            mean.pwp += w * s.pwp;
            for c in 0..6 {
                mean.total[c] += w * s.total[c];
            }
        }
        mean.saturation = super::saturation(model.material_of(e), mean.pwp);
        for s in &mut states[run] {
            *s = mean;
        }
    }
}
