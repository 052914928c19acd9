//! The state the runner carries per material point ([`Particle`]) and the
//! per-MP passes every phase of a step shares: a parallel map over the live
//! MPs into per-MP buffers ([`per_live_mp`]), the serial scatter of those
//! buffers to the nodes in MP order ([`scatter`]: sums are bit-identical for
//! any thread count), nodal velocities from momenta ([`velocities`]) and the
//! end of a step for an MP's water ([`settle_water`]). The solver
//! ([`super::step`]), the liquid ([`super::liquid_grid`]), the seepage faces
//! and MPM-MIXED's smoothing all build on these, and none of them on another.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

use rayon::prelude::*;

use super::grid::Grid;
use super::liquid::Water;

/// MPs per rayon task: large enough that scheduling costs stay negligible.
pub(super) const MIN_CHUNK: usize = 1024;

/// Accumulated plastic strain above which an MP counts as having yielded. An
/// MP at rest on its yield surface returns round-off-sized trial stresses now
/// and then (a balanced state is balanced to round-off, not exactly): that is
/// no plastic flow, and stays orders of magnitude below one microstrain.
pub const PLASTIC_STRAIN_FLOOR: f64 = 1e-6;

/// The state of one material point.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Particle<const D: usize, const NC: usize> {
    pub position: [f64; D],
    pub displacement: [f64; D],
    pub velocity: [f64; D],
    /// Shape function values at the start of the step (set in P2G).
    pub shape: [f64; NC],
    /// 1 / r at the start of the step (set in P2G) in 2D-axisymmetric
    /// models, else 0: the weight of the hoop terms.
    pub inverse_radius: f64,
    /// Effective stress σ′ (kPa).
    pub stress: [f64; 6],
    /// Mass (t; t per metre in plane strain, t per radian in axisymmetry).
    pub mass: f64,
    /// The mass gravity pulls on (t, as `mass`): the kernel's weight of the
    /// MP over g ([`super::loading`]).
    pub weight: f64,
    /// Current volume (m³; m² per metre in plane strain, m³ per radian in
    /// axisymmetry).
    pub volume: f64,
    /// The pore-water part of the stress in the internal force, added to the
    /// normal components of σ′ (kPa): S·p, p or 0 ([`super::loading`]).
    pub pore_term: f64,
    pub element: u32,
    /// Index into the solver's material models.
    pub model: u32,
    /// Yielded in the last step.
    pub yielded: bool,
    /// Accumulated plastic strain: the length of C·(σ_trial − σ) summed over
    /// the plastic updates (engineering shear).
    pub plastic_strain: f64,
    /// Has yielded: its accumulated plastic strain exceeds
    /// [`PLASTIC_STRAIN_FLOOR`].
    pub plastic: bool,
    /// Left the mesh; frozen since.
    pub lost: bool,
    /// Pore pressure p (kPa, Anura3D's sign: negative in compression).
    pub pwp: f64,
    /// The factor of p in the internal force ([`super::loading`]).
    pub pore_factor: f64,
    /// How p evolves ([`super::liquid`]).
    pub water: Water,
    /// The liquid's velocity (coupled MPs; zero otherwise).
    pub liquid_velocity: [f64; D],
    /// Degree of saturation (coupled unsaturated MPs follow their retention
    /// curve; else as mapped).
    pub saturation: f64,
    /// Initial volume: the kernel's masses and drag stay those of V₀.
    pub volume0: f64,
    /// Relative conductivity k_r of coupled unsaturated MPs (1 otherwise).
    pub conductivity: f64,
}

/// Runs `f` on every MP that is not lost and its output slot, in parallel; a
/// lost MP's slot is set to `lost` (it contributes nothing).
pub(super) fn per_live_mp<const D: usize, const NC: usize, T: Copy + Send + Sync>(
    particles: &mut [Particle<D, NC>],
    out: &mut [T],
    lost: T,
    f: impl Fn(&mut Particle<D, NC>, &mut T) + Sync,
) {
    particles
        .par_iter_mut()
        .zip(out.par_iter_mut())
        .with_min_len(MIN_CHUNK)
        .for_each(|(p, out)| {
            if p.lost {
                *out = lost;
            } else {
                f(p, out);
            }
        });
}

/// The end of the kernel's step for an MP's water: S, k_r and the mixture's
/// weight from the retention curve at the new p (coupled unsaturated MPs, with
/// the current volume), and p's term in the internal force (Bishop's
/// min(S·p, p) for coupled MPs).
pub(super) fn settle_water<const D: usize, const NC: usize>(p: &mut Particle<D, NC>) {
    match p.water {
        Water::Coupled(c) => {
            if let Some(curve) = c.retention {
                p.saturation = curve.anura3d_saturation(p.pwp).1;
                if p.saturation < 1.0 {
                    p.conductivity = c.conductivity.relative(p.saturation);
                }
                p.weight = (p.mass / p.volume0 + c.porosity * p.saturation * c.density) * p.volume;
                p.pore_factor = p.saturation;
            }
            p.pore_term = (p.pore_factor * p.pwp).min(p.pwp);
        }
        Water::Undrained { .. } | Water::Frozen => p.pore_term = p.pore_factor * p.pwp,
    }
}

/// Sums every MP's per-corner vectors into `nodal` (cleared first),
/// serially in MP order (deterministic).
pub(super) fn scatter<const D: usize, const NC: usize>(
    grid: &Grid<D, NC>,
    particles: &[Particle<D, NC>],
    per_mp: &[[[f64; D]; NC]],
    nodal: &mut [[f64; D]],
) {
    nodal.fill([0.0; D]);
    for (p, out) in particles.iter().zip(per_mp) {
        let corners = &grid.elements[p.element as usize].corners;
        for i in 0..NC {
            let node = corners[i] as usize;
            for d in 0..D {
                nodal[node][d] += out[i][d];
            }
        }
    }
}

/// Nodal velocities momentum / mass; zero at nodes lighter than `floor`
/// and in fixed directions.
pub(super) fn velocities<const D: usize>(
    mass: &[f64],
    momentum: &[[f64; D]],
    fixed: &[[bool; D]],
    floor: f64,
    velocity: &mut [[f64; D]],
) {
    for node in 0..mass.len() {
        for d in 0..D {
            velocity[node][d] = if mass[node] <= floor || fixed[node][d] {
                0.0
            } else {
                momentum[node][d] / mass[node]
            };
        }
    }
}
