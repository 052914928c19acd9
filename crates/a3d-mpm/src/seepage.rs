//! Seepage faces and infiltration of partially saturated two-phase runs, as
//! the kernel's `ApplyNodalInfiltrationRate` (`MPMDYN2PhaseSP.FOR`) applies
//! them after the nodal velocities are updated.
//!
//! Free-surface nodes are the nodes of the sides of active elements (holding
//! MPs) that border no active element. Inside the seepage box, water may
//! leave but not enter; inside the infiltration box, it may enter at most at
//! the infiltration rate. The outward normal n̂ is the unit nodal mass
//! gradient Σ m_s ∇N (liquid-fixed directions left out), and the net outward
//! rate r = n·S·(v_w − v_s)·n̂ (less q·n̂ for infiltration). Where r < 0 it
//! is brought to 0 by normal velocity changes that keep the mixture's
//! momentum: Δv_w = −M_s·r/(n·S·(M_nw + M_s)), Δv_s = M_nw·r/(n·S·(M_nw + M_s));
//! the accelerations change by the same over Δt.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

use super::grid::{Grid, NO_ELEMENT};
use super::liquid_grid::LiquidGrid;
use super::particle::Particle;

/// A bounding box `[min, max]` per axis.
pub type Area = [[f64; 2]; 3];

/// What the CPS and GOM switch on.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct HydraulicBoundaries {
    /// CPS `$$APPLY_SEEPAGE_FACE 1` with the GOM's `$$BOUNDARY_SEEPAGE_AREA`.
    pub seepage_area: Option<Area>,
    /// CPS `$$APPLY_INFILTRATION 1` with the GOM's
    /// `$$BOUNDARY_INFILTRATION_AREA` and `$$INFILTRATION_RATE` (m/s per axis,
    /// pointing into the ground).
    pub infiltration: Option<(Area, [f64; 3])>,
}

impl HydraulicBoundaries {
    pub fn is_empty(&self) -> bool {
        self.seepage_area.is_none() && self.infiltration.is_none()
    }
}

fn inside<const D: usize>(area: &Area, x: &[f64; D]) -> bool {
    (0..D).all(|d| x[d] >= area[d][0] && x[d] <= area[d][1])
}

/// Per-node kind of surface condition this step.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Surface {
    None,
    Seepage,
    Infiltration,
}

/// The condition and its per-step work arrays.
pub(super) struct SurfaceFlow<const D: usize> {
    pub(super) boundaries: HydraulicBoundaries,
    /// Compact node coordinates.
    position: Vec<[f64; D]>,
    active: Vec<bool>,
    kind: Vec<Surface>,
    normal: Vec<[f64; D]>,
    /// This step's prescribed water level (`$$HYDRAULIC_HEAD file`): its
    /// area and head. Surface nodes in the area at or below the head are
    /// submerged, not seepage faces (the kernel's `DetectSeepageFaceNodes`).
    pub(super) level: Option<(Area, f64)>,
}

impl<const D: usize> SurfaceFlow<D> {
    pub(super) fn new<const NC: usize>(
        boundaries: HydraulicBoundaries,
        grid: &Grid<D, NC>,
        nodes: &[[f64; 3]],
    ) -> SurfaceFlow<D> {
        let position = grid
            .mesh_node
            .iter()
            .map(|&m| {
                let mut x = [0.0; D];
                x.copy_from_slice(&nodes[m as usize][..D]);
                x
            })
            .collect();
        let n_nodes = grid.n_nodes();
        SurfaceFlow {
            boundaries,
            position,
            active: vec![false; grid.elements.len()],
            kind: vec![Surface::None; n_nodes],
            level: None,
            normal: vec![[0.0; D]; n_nodes],
        }
    }

    /// The infiltration rate (m/s per axis).
    fn rate(&self) -> [f64; D] {
        let mut q = [0.0; D];
        if let Some((_, rate)) = &self.boundaries.infiltration {
            q.copy_from_slice(&rate[..D]);
        }
        q
    }

    /// Finds this step's free-surface nodes in the boxes and, where the net
    /// outward rate is negative, brings it to 0: the liquid's and the solid's
    /// nodal velocities (and accelerations, by the change over Δt) after
    /// the step's nodal solve, in their free directions.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn apply<const NC: usize>(
        &mut self,
        grid: &Grid<D, NC>,
        particles: &[Particle<D, NC>],
        l: &mut LiquidGrid<D, NC>,
        node_mass: &[f64],
        node_velocity: &mut [[f64; D]],
        node_acceleration: &mut [[f64; D]],
        mass_floor: f64,
        dt: f64,
    ) {
        self.detect(grid, particles, &l.fixed);
        let q = self.rate();
        for node in 0..grid.n_nodes() {
            let kind = self.kind[node];
            let (mw, mnw, ms) = (l.mass[node], l.water[node], node_mass[node]);
            if kind == Surface::None || mw <= mass_floor || ms <= mass_floor {
                continue;
            }
            let ns = mnw / mw;
            if ns <= 0.0 {
                continue;
            }
            let n = self.normal[node];
            let mut rate = 0.0;
            for d in 0..D {
                rate += ns * (l.velocity[node][d] - node_velocity[node][d]) * n[d];
                if kind == Surface::Infiltration {
                    rate -= q[d] * n[d];
                }
            }
            if rate >= 0.0 {
                continue;
            }
            let dw = -ms * rate / (ns * (mnw + ms));
            let dv = mnw * rate / (ns * (mnw + ms));
            for d in 0..D {
                if !l.fixed[node][d] {
                    l.velocity[node][d] += dw * n[d];
                    l.acceleration[node][d] += dw * n[d] / dt;
                }
                if !grid.fixed[node][d] {
                    node_velocity[node][d] += dv * n[d];
                    node_acceleration[node][d] += dv * n[d] / dt;
                }
            }
        }
    }

    /// Finds this step's free-surface nodes in the boxes and their outward
    /// normals; `liquid_fixed` masks the liquid's fixed directions.
    fn detect<const NC: usize>(
        &mut self,
        grid: &Grid<D, NC>,
        particles: &[Particle<D, NC>],
        liquid_fixed: &[[bool; D]],
    ) {
        self.active.fill(false);
        self.kind.fill(Surface::None);
        self.normal.fill([0.0; D]);
        for p in particles.iter().filter(|p| !p.lost) {
            self.active[p.element as usize] = true;
            let element = &grid.elements[p.element as usize];
            for i in 0..NC {
                let node = element.corners[i] as usize;
                for d in 0..D {
                    if !liquid_fixed[node][d] {
                        self.normal[node][d] += p.mass * element.shape.grad[i][d];
                    }
                }
            }
        }
        let level = self.level;
        let submerged = |x: &[f64; D]| level.is_some_and(|(area, h)| inside(&area, x) && x[1] <= h);
        for (e, element) in grid.elements.iter().enumerate() {
            if !self.active[e] {
                continue;
            }
            for k in 0..NC {
                let across = grid.neighbours[e][k];
                if across != NO_ELEMENT && self.active[across as usize] {
                    continue;
                }
                // The side opposite corner k borders no active element.
                for (i, &node) in element.corners.iter().enumerate() {
                    if i == k {
                        continue;
                    }
                    let node = node as usize;
                    let x = &self.position[node];
                    let kind = match (&self.boundaries.infiltration, &self.boundaries.seepage_area)
                    {
                        (Some((area, _)), _) if inside(area, x) => Surface::Infiltration,
                        (_, Some(area)) if inside(area, x) && !submerged(x) => Surface::Seepage,
                        _ => Surface::None,
                    };
                    if kind != Surface::None {
                        self.kind[node] = kind;
                    }
                }
            }
        }
        for (node, n) in self.normal.iter_mut().enumerate() {
            let length = n.iter().map(|v| v * v).sum::<f64>().sqrt();
            if self.kind[node] != Surface::None && length > 0.0 {
                for v in n.iter_mut() {
                    *v /= length;
                }
            } else {
                self.kind[node] = Surface::None;
            }
        }
    }
}
