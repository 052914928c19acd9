//! The liquid phase's share of the explicit step ([`super::step`]) for
//! coupled MPs ([`super::liquid`]): its nodal arrays and per-MP buffers, the
//! P2G of its mass, drag, momentum, pressure force and weight, the G2P of its
//! acceleration with the MUSL remap of its velocity, and the advective flux
//! of the partially saturated storage at an MP. The solid–liquid nodal solve stays in the step, beside
//! the solid's.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

use super::b_matrix::corner_force;
use super::grid::{Grid, GridElement};
use super::liquid::Water;
use super::particle::{Particle, per_live_mp, scatter, velocities};

/// Per-corner P2G contribution of the liquid of one coupled MP.
#[derive(Clone, Copy, Debug)]
pub(super) struct LiquidContribution<const D: usize> {
    /// ρw·V·N: the liquid equation's mass.
    pub(super) mass: f64,
    /// n·ρw·V·N: the liquid's mass in the mixture.
    pub(super) water: f64,
    /// Drag (n·S·μ/(κ·k_r))·V₀·N.
    pub(super) drag: f64,
    pub(super) momentum: [f64; D],
    /// Pressure force −V p ∇N plus the liquid's weight ρw·V·N·g.
    pub(super) force: [f64; D],
    /// n·S times `force`: the water's share of the mixture's force, which
    /// the kernel damps apart from the solid's (`IntLoadWaterPorosity`,
    /// `GravityLoadWaterPorosity`).
    pub(super) porous: [f64; D],
    /// m_s·n·ρw·S·N: the mass-weighted nodal n·ρw·S of the advective flux
    /// (unsaturated MPs), before division by the nodal solid mass.
    pub(super) advective: f64,
}

impl<const D: usize> LiquidContribution<D> {
    pub(super) const ZERO: LiquidContribution<D> = LiquidContribution {
        mass: 0.0,
        water: 0.0,
        drag: 0.0,
        momentum: [0.0; D],
        force: [0.0; D],
        porous: [0.0; D],
        advective: 0.0,
    };
}

/// The liquid's nodal arrays and per-MP buffers, present when any MP is
/// coupled.
pub(super) struct LiquidGrid<const D: usize, const NC: usize> {
    pub(super) fixed: Vec<[bool; D]>,
    pub(super) mass: Vec<f64>,
    pub(super) water: Vec<f64>,
    pub(super) drag: Vec<f64>,
    /// Σ m_s·n·ρw·S·N, then over the nodal solid mass (the kernel's
    /// `AdvectiveFluxDarcyWater`).
    pub(super) advective: Vec<f64>,
    pub(super) momentum: Vec<[f64; D]>,
    pub(super) force: Vec<[f64; D]>,
    /// Σ n·S·(the MPs' liquid force): the water's share of the mixture's
    /// force, without external liquid loads.
    pub(super) porous: Vec<[f64; D]>,
    pub(super) acceleration: Vec<[f64; D]>,
    pub(super) velocity: Vec<[f64; D]>,
    pub(super) p2g: Vec<[LiquidContribution<D>; NC]>,
    pub(super) remap: Vec<[[f64; D]; NC]>,
}

impl<const D: usize, const NC: usize> LiquidGrid<D, NC> {
    /// The liquid's nodal arrays on `grid` for `n_points` MPs, its fixities
    /// from the GOM's `$$START_FIXITY_*_LIQUID` (and, on the axis of an
    /// axisymmetric model, no radial flow).
    pub(super) fn new(
        grid: &Grid<D, NC>,
        model: &a3d_model::AnuraModel,
        axisymmetric: bool,
        n_points: usize,
    ) -> Self {
        let n_nodes = grid.n_nodes();
        LiquidGrid {
            fixed: (0..n_nodes)
                .map(|node| {
                    let mut d = [false; D];
                    let mesh_node = grid.mesh_node[node] as usize;
                    if let Some(f) = model.liquid_fixity.get(mesh_node) {
                        d.copy_from_slice(&f[..D]);
                    }
                    // On the axis of an axisymmetric model the water cannot
                    // flow radially either.
                    if axisymmetric && grid.fixed[node][0] && model.mesh.nodes[mesh_node][0] == 0.0
                    {
                        d[0] = true;
                    }
                    d
                })
                .collect(),
            mass: vec![0.0; n_nodes],
            water: vec![0.0; n_nodes],
            drag: vec![0.0; n_nodes],
            advective: vec![0.0; n_nodes],
            porous: vec![[0.0; D]; n_nodes],
            momentum: vec![[0.0; D]; n_nodes],
            force: vec![[0.0; D]; n_nodes],
            acceleration: vec![[0.0; D]; n_nodes],
            velocity: vec![[0.0; D]; n_nodes],
            p2g: vec![[LiquidContribution::ZERO; NC]; n_points],
            remap: vec![[[0.0; D]; NC]; n_points],
        }
    }

    /// P2G of the coupled MPs' liquid (serial scatter in MP order), then the
    /// nodal n·ρw·S of the advective flux over the nodal solid mass.
    pub(super) fn p2g(
        &mut self,
        grid: &Grid<D, NC>,
        particles: &mut [Particle<D, NC>],
        gravity: [f64; D],
        node_mass: &[f64],
        floor: f64,
    ) {
        let g = gravity;
        per_live_mp(
            particles,
            &mut self.p2g,
            [LiquidContribution::ZERO; NC],
            |p, out| {
                let Water::Coupled(c) = p.water else {
                    *out = [LiquidContribution::ZERO; NC];
                    return;
                };
                let element = &grid.elements[p.element as usize];
                let n = p.shape;
                let pressure = [p.pwp, p.pwp, p.pwp, 0.0, 0.0, 0.0];
                // The kernel's constant masses and drag (of V₀), scaled
                // by S in the mixture's water and the drag.
                let m = c.density * p.volume0;
                let s = p.saturation;
                let advective = p.mass * c.porosity * c.density * s;
                for i in 0..NC {
                    let g_i = &element.shape.grad[i];
                    let mut force =
                        corner_force::<D>(&pressure, g_i, n[i], p.volume, p.inverse_radius);
                    let share = m * n[i];
                    let mut momentum = [0.0; D];
                    let mut porous = [0.0; D];
                    for d in 0..D {
                        force[d] += share * g[d];
                        momentum[d] = share * p.liquid_velocity[d];
                        porous[d] = c.porosity * s * force[d];
                    }
                    out[i] = LiquidContribution {
                        mass: share,
                        water: c.porosity * s * share,
                        drag: c.drag * s / p.conductivity * p.volume0 * n[i],
                        momentum,
                        force,
                        porous,
                        advective: advective * n[i],
                    };
                }
            },
        );
        self.mass.fill(0.0);
        self.water.fill(0.0);
        self.drag.fill(0.0);
        self.advective.fill(0.0);
        self.momentum.fill([0.0; D]);
        self.force.fill([0.0; D]);
        self.porous.fill([0.0; D]);
        for (p, out) in particles.iter().zip(&self.p2g) {
            if !matches!(p.water, Water::Coupled(_)) || p.lost {
                continue;
            }
            let corners = &grid.elements[p.element as usize].corners;
            for i in 0..NC {
                let node = corners[i] as usize;
                self.mass[node] += out[i].mass;
                self.water[node] += out[i].water;
                self.drag[node] += out[i].drag;
                self.advective[node] += out[i].advective;
                for d in 0..D {
                    self.momentum[node][d] += out[i].momentum[d];
                    self.force[node][d] += out[i].force[d];
                    self.porous[node][d] += out[i].porous[d];
                }
            }
        }
        for (a, &m) in self.advective.iter_mut().zip(node_mass) {
            *a = if m > floor { *a / m } else { 0.0 };
        }
    }

    /// G2P of the liquid's nodal acceleration into the coupled MPs'
    /// velocities, then the nodal velocities from the updated momenta
    /// (fixities again).
    pub(super) fn g2p(
        &mut self,
        grid: &Grid<D, NC>,
        particles: &mut [Particle<D, NC>],
        dt: f64,
        floor: f64,
    ) {
        let acceleration = &self.acceleration;
        per_live_mp(particles, &mut self.remap, [[0.0; D]; NC], |p, out| {
            let Water::Coupled(c) = p.water else {
                *out = [[0.0; D]; NC];
                return;
            };
            let corners = &grid.elements[p.element as usize].corners;
            let n = p.shape;
            let mut a = [0.0; D];
            for i in 0..NC {
                let node = corners[i] as usize;
                for d in 0..D {
                    a[d] += n[i] * acceleration[node][d];
                }
            }
            for d in 0..D {
                p.liquid_velocity[d] += dt * a[d];
            }
            let m = c.density * p.volume0;
            for i in 0..NC {
                for d in 0..D {
                    out[i][d] = m * n[i] * p.liquid_velocity[d];
                }
            }
        });
        // Non-coupled and lost MPs left zeros in their slots.
        scatter(grid, particles, &self.remap, &mut self.momentum);
        velocities(
            &self.mass,
            &self.momentum,
            &self.fixed,
            floor,
            &mut self.velocity,
        );
    }
}

/// The kernel's water advective flux at an MP (`CalculateParticleWaterAdvectiveFlux`):
/// Σ_J ∇N_J · A_J (Δu_w − Δu_s)_J with the nodal n·ρw·S `a` and Δu = Δt·v
/// (plus the hoop part in 2D axisymmetry).
pub(super) fn advective_flux<const D: usize, const NC: usize>(
    element: &GridElement<D, NC>,
    a: &[f64],
    liquid: &[[f64; D]],
    solid: &[[f64; D]],
    dt: f64,
    inverse_radius: f64,
    shape: &[f64; NC],
) -> f64 {
    let mut flux = 0.0;
    for i in 0..NC {
        let node = element.corners[i] as usize;
        for d in 0..D {
            flux += element.shape.grad[i][d] * a[node] * (liquid[node][d] - solid[node][d]);
        }
        if inverse_radius != 0.0 {
            flux += shape[i] * a[node] * (liquid[node][0] - solid[node][0]) * inverse_radius;
        }
    }
    dt * flux
}
