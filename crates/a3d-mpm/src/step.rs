//! One explicit MPM time step (MUSL) on the fixed Anura3D background grid, and
//! the solver that owns the state between steps (for `D` coordinates and `NC`
//! corners; [`super::Simulation`] is its public handle).
//!
//! Scheme (Modified Update Stress Last, Sulsky et al. 1995):
//!
//! 1. P2G: lumped nodal mass, momentum and internal force
//!    f_int = −Σ V_p σ_p ∇N, σ = σ′ plus the pore-water part the kernel's
//!    analysis adds on the normals ([`super::loading`]: S·p in a multiphase
//!    analysis, p for undrained-effective materials, else nothing). Gravity
//!    enters as f_ext = Σ N w_p g with the kernel's weight w_p of each MP
//!    (dry, buoyant or mixture).
//!    2D-axisymmetric (x = r ≥ 0, y axial, zz the hoop component θθ): V_p and
//!    m_p are per radian (they already hold the MP radius, see `place`), the
//!    radial force gains the hoop term −V_p N_i σ_θθ / r_p, and the strain
//!    gains ε_θθ = u_r / r_p = Σ N_i u_r,i / r_p; so f_int = −Σ V_p B_pᵀ σ_p with
//!    the axisymmetric B. Nodes on the axis are fixed radially (u_r = 0 there
//!    by symmetry; Anura3D models fix them in the GOM as well).
//! 2. Nodes: unbalanced force f = f_ext + f_int, local (Cundall) damping
//!    f_d = f − α·|f|·sign(v) per component, a = f_d / m; fixed directions and
//!    nodes lighter than a tiny floor get zero acceleration and velocity.
//! 3. G2P: MP velocity += Δt Σ N a, position += Δt Σ N v_new.
//! 4. MUSL: nodal velocities are rebuilt from the updated MP momenta (fixities
//!    applied again) and give the strain increment Δε = Δt·sym(Σ v ⊗ ∇N), which
//!    the constitutive model turns into the new effective stress; volumes follow
//!    the volumetric strain. MUSL rather than USL because it keeps nodes of
//!    nearly empty elements from producing spurious strain.
//! 5. Every MP that left its element is located again (neighbour walk, then a
//!    spatial hash); one that left the mesh is frozen and counted as lost.
//!
//! Determinism: every per-MP computation runs in parallel (rayon) into per-MP
//! buffers, and all sums over MPs (scatter to nodes, energies, counts) run
//! serially in MP order, so results are bit-identical for any thread count.
//! The water of two-phase materials enters between these phases (the liquid's
//! nodal momentum beside the solid's, its drag taken implicitly, p updated
//! from both phases' strains: [`super::liquid`], `liquid_grid`, `seepage`);
//! drained materials hold their pore pressure and saturation.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

use rayon::prelude::*;

use super::b_matrix::{corner_force, strain_increment_at};
use super::grid::Grid;
use super::liquid::Water;
use super::liquid_grid::{LiquidGrid, advective_flux};
use super::loading::Analysis;
use super::loads::ExternalLoads;
use super::material::SolidModel;
use super::mixed::ElementSums;
use super::particle::{
    MIN_CHUNK, PLASTIC_STRAIN_FLOOR, Particle, per_live_mp, scatter, settle_water, velocities,
};
use super::seepage::SurfaceFlow;
use super::{MpmError, RunSettings};
use a3d_element::Element;
use a3d_model::{AnuraModel, Dimension, MaterialPoint, MpState};

/// Per-corner P2G contribution of one MP.
#[derive(Clone, Copy, Debug)]
struct Contribution<const D: usize> {
    mass: f64,
    weight: f64,
    momentum: [f64; D],
    force: [f64; D],
}

impl<const D: usize> Contribution<D> {
    const ZERO: Contribution<D> = Contribution {
        mass: 0.0,
        weight: 0.0,
        momentum: [0.0; D],
        force: [0.0; D],
    };
}

/// What one step measured.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct StepOutcome {
    /// ‖f_ext + f_int‖ / ‖f_ext‖ over free DOFs at the start of the step.
    pub residual_ratio: f64,
    /// Kinetic energy of the MPs after the step (kJ; kJ/m in plane strain,
    /// kJ per radian in axisymmetry).
    pub kinetic_energy: f64,
    /// MPs whose stress update was plastic in this step.
    pub yielded: usize,
    /// MPs that have yielded in any step so far (accumulated plastic strain
    /// above `particle::PLASTIC_STRAIN_FLOOR`, 1e-6).
    pub plastic: usize,
}

/// The explicit solver for one dimension: `D` coordinates, `NC` corners.
pub(crate) struct Solver<const D: usize, const NC: usize> {
    pub grid: Grid<D, NC>,
    pub models: Vec<SolidModel>,
    pub particles: Vec<Particle<D, NC>>,
    /// Initial stress outside the yield surface, per MP.
    pub inadmissible: Vec<bool>,
    node_mass: Vec<f64>,
    node_weight: Vec<f64>,
    node_momentum: Vec<[f64; D]>,
    node_force: Vec<[f64; D]>,
    node_acceleration: Vec<[f64; D]>,
    node_velocity: Vec<[f64; D]>,
    /// |f_ext + f_int| over the free directions of each node, last step.
    pub node_residual: Vec<f64>,
    p2g: Vec<[Contribution<D>; NC]>,
    remap: Vec<[[f64; D]; NC]>,
    gravity: [f64; D],
    /// g (m/s²), before the gravity multiplier.
    g: f64,
    /// The CPS's multipliers (gravity's among them) and load-step timing,
    /// and the GOM's loads they scale ([`RunSettings::loads`]).
    loads: a3d_model::loads::ProjectLoads,
    damping: f64,
    /// Damp a coupled mixture in the kernel's two parts
    /// ([`super::RunSettings::split_mixture_damping`]).
    split_damping: bool,
    pub dt: f64,
    pub time: f64,
    pub steps: usize,
    mass_floor: f64,
    plane_strain: bool,
    /// 2D-axisymmetric: hoop strain and force terms on.
    axisymmetric: bool,
    /// Smallest radius used in the hoop terms (m): a guard only, since MPs
    /// are interior points and never sit on the axis.
    radius_floor: f64,
    pub wave_speed: f64,
    pub min_altitude: f64,
    /// The liquid phase, when any MP is coupled.
    liquid: Option<LiquidGrid<D, NC>>,
    /// Constant external nodal forces besides gravity.
    node_load: Vec<[f64; D]>,
    /// Per material of the GOM (0-based) that MPs use: its water.
    pub waters: Vec<Option<Water>>,
    /// MPM-MIXED's element smoothing ([`RunSettings::element_smoothing`]).
    element_sums: Option<ElementSums>,
    /// Seepage faces and infiltration ([`RunSettings::hydraulic`]), where
    /// the water of partially saturated MPs flows.
    surface: Option<SurfaceFlow<D>>,
    /// The GOM's loads ([`RunSettings::loads`]).
    pub external: Option<ExternalLoads<D>>,
    /// This step's external nodal forces besides gravity: `node_load` plus
    /// the solid loads at the step's multipliers.
    load_now: Vec<[f64; D]>,
}

impl<const D: usize, const NC: usize> Solver<D, NC> {
    /// Sets up the solver on the grid of element type `E` (see
    /// [`super::Simulation::new`]).
    pub fn new<E: Element<D, NC>>(
        model: &AnuraModel,
        points: &[MaterialPoint],
        states: &[MpState],
        settings: &RunSettings,
    ) -> Result<Self, MpmError> {
        let axisymmetric = D == 2 && model.mesh.dimension == Dimension::Axisymmetric;
        let analysis = Analysis::of(&model.materials, settings.submerged_calculation);
        let mut grid = Grid::<D, NC>::new::<E>(&model.mesh, &model.solid_fixity)?;
        if axisymmetric {
            grid.fix_axis(&model.mesh);
        }
        let mut materials = MaterialSlots::new(model.materials.len());
        let mut particles = Vec::with_capacity(points.len());
        let mut inadmissible = Vec::with_capacity(points.len());
        let mut wave_speed = 0.0_f64;
        // Each MP's P-wave speed, for the density scaling.
        let mut speeds = Vec::with_capacity(points.len());
        let start = ParticleStart {
            grid: &grid,
            model,
            analysis: &analysis,
            settings,
            axisymmetric,
        };
        for (point, state) in points.iter().zip(states) {
            let (particle, speed, admissible) = start.particle(point, state, &mut materials)?;
            particles.push(particle);
            inadmissible.push(!admissible);
            wave_speed = wave_speed.max(speed);
            speeds.push(speed);
        }
        let MaterialSlots { models, waters, .. } = materials;
        let coupled = particles
            .iter()
            .any(|p| matches!(p.water, Water::Coupled(_)));
        if settings.mass_scaling && !coupled {
            wave_speed = scale_masses(&mut particles, &speeds, wave_speed);
        }
        let min_altitude = grid.min_altitude();
        let dt = settings.courant * min_altitude / wave_speed;
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(MpmError::InvalidSettings(format!(
                "time step {dt} s from Courant {} × length {min_altitude} m / wave speed {wave_speed} m/s",
                settings.courant
            )));
        }
        let max_mass = particles.iter().map(|p| p.mass).fold(0.0, f64::max);
        let n_nodes = grid.n_nodes();
        let n_points = particles.len();
        let mut gravity = [0.0; D];
        gravity[1] = -settings.gravity;
        let liquid = coupled.then(|| LiquidGrid::new(&grid, model, axisymmetric, n_points));
        let element_sums = settings
            .element_smoothing
            .then(|| ElementSums::new(grid.elements.len()));
        // The kernel applies seepage faces and infiltration only when the
        // analysis is partially saturated.
        let partially_saturated = particles
            .iter()
            .any(|p| matches!(p.water, Water::Coupled(c) if c.retention.is_some()));
        let surface = (partially_saturated && !settings.hydraulic.is_empty())
            .then(|| SurfaceFlow::new(settings.hydraulic.clone(), &grid, &model.mesh.nodes));
        let external = (!settings.loads.is_empty()).then(|| {
            // MP loads go to the MPs by their elements when the run starts.
            let located: Vec<MaterialPoint> = points
                .iter()
                .zip(&particles)
                .map(|(point, p)| MaterialPoint {
                    element: p.element,
                    ..*point
                })
                .collect();
            // γw of the kernel's `ComputeWaterSpecificWeight`: the liquid
            // density of the last two-phase material, times g.
            let gamma_w = waters.iter().rev().find_map(|w| match w {
                Some(Water::Coupled(c)) => Some(c.density * settings.gravity),
                _ => None,
            });
            ExternalLoads::new(
                &settings.loads,
                &grid,
                &model.mesh,
                &located,
                axisymmetric,
                gamma_w.filter(|_| coupled),
            )
        });
        Ok(Solver {
            grid,
            models,
            particles,
            inadmissible,
            node_mass: vec![0.0; n_nodes],
            node_weight: vec![0.0; n_nodes],
            node_momentum: vec![[0.0; D]; n_nodes],
            node_force: vec![[0.0; D]; n_nodes],
            node_acceleration: vec![[0.0; D]; n_nodes],
            node_velocity: vec![[0.0; D]; n_nodes],
            node_residual: vec![0.0; n_nodes],
            p2g: vec![[Contribution::ZERO; NC]; n_points],
            remap: vec![[[0.0; D]; NC]; n_points],
            gravity,
            g: settings.gravity,
            loads: settings.loads.clone(),
            damping: settings.damping,
            split_damping: settings.split_mixture_damping,
            dt,
            time: 0.0,
            steps: 0,
            mass_floor: 1e-10 * max_mass,
            plane_strain: D == 2,
            axisymmetric,
            radius_floor: 1e-6 * min_altitude,
            wave_speed,
            min_altitude,
            liquid,
            waters,
            node_load: vec![[0.0; D]; n_nodes],
            element_sums,
            surface,
            external,
            load_now: vec![[0.0; D]; n_nodes],
        })
    }

    /// Replaces the constant external nodal forces.
    pub fn set_nodal_loads(&mut self, loads: &[(u32, [f64; 3])]) -> Result<(), MpmError> {
        let mut node_load = vec![[0.0; D]; self.grid.n_nodes()];
        let compact = self.grid.compact_nodes();
        for &(node, f) in loads {
            let slot = compact
                .get(&node)
                .and_then(|&g| node_load.get_mut(g as usize))
                .ok_or_else(|| {
                    MpmError::InvalidSettings(format!(
                        "load on node {node}, which no active element holds"
                    ))
                })?;
            if f.iter().any(|v| !v.is_finite()) {
                return Err(MpmError::InvalidSettings(format!(
                    "load {f:?} on node {node} is not finite"
                )));
            }
            for d in 0..D {
                slot[d] += f[d];
            }
        }
        self.node_load = node_load;
        Ok(())
    }

    /// Advances the state by one time step and reports what it measured:
    /// P2G, the liquid and the external loads, the nodal solve, the seepage
    /// faces, G2P with the MUSL remap, then every MP's strain, stress, pore
    /// pressure, volume and element.
    pub fn step(&mut self) -> StepOutcome {
        // Gravity at the CPS's `$$GRAVITY_LOAD` multiplier of the step that
        // ends at t + Δt.
        self.gravity[1] = -self.g * self.loads.gravity_at(self.time + self.dt);
        self.p2g();
        self.liquid_and_loads();
        let residual_ratio = self.nodal_solve();
        self.surface_flow();
        self.g2p();
        self.update_particles();
        self.close_step(residual_ratio)
    }

    /// Phase 1, P2G: each MP's mass, weight, momentum and internal force on its
    /// element's corners, in parallel, summed to the nodes in MP order.
    fn p2g(&mut self) {
        let grid = &self.grid;
        let axisymmetric = self.axisymmetric;
        let radius_floor = self.radius_floor;
        // 1. P2G contributions, per MP in parallel.
        per_live_mp(
            &mut self.particles,
            &mut self.p2g,
            [Contribution::ZERO; NC],
            |p, out| {
                let element = &grid.elements[p.element as usize];
                let n = element.shape.values(&p.position);
                p.shape = n;
                p.inverse_radius = if axisymmetric {
                    1.0 / p.position[0].max(radius_floor)
                } else {
                    0.0
                };
                let mut total = p.stress;
                for k in 0..3 {
                    total[k] += p.pore_term;
                }
                for i in 0..NC {
                    let g = &element.shape.grad[i];
                    let force = corner_force::<D>(&total, g, n[i], p.volume, p.inverse_radius);
                    let share = p.mass * n[i];
                    let mut momentum = [0.0; D];
                    for d in 0..D {
                        momentum[d] = share * p.velocity[d];
                    }
                    out[i] = Contribution {
                        mass: share,
                        weight: p.weight * n[i],
                        momentum,
                        force,
                    };
                }
            },
        );

        // Scatter serially in MP order (deterministic sums).
        self.node_mass.fill(0.0);
        self.node_weight.fill(0.0);
        self.node_momentum.fill([0.0; D]);
        self.node_force.fill([0.0; D]);
        for (p, out) in self.particles.iter().zip(&self.p2g) {
            let corners = &grid.elements[p.element as usize].corners;
            for i in 0..NC {
                let node = corners[i] as usize;
                self.node_mass[node] += out[i].mass;
                self.node_weight[node] += out[i].weight;
                for d in 0..D {
                    self.node_momentum[node][d] += out[i].momentum[d];
                    self.node_force[node][d] += out[i].force[d];
                }
            }
        }
    }

    /// Phases 1b/1c: the liquid of coupled MPs (its mass, drag, momentum, pressure
    /// force and weight), and the external loads of the step.
    fn liquid_and_loads(&mut self) {
        let dt = self.dt;
        let grid = &self.grid;
        // 1b. The liquid of coupled MPs: its mass, drag, momentum, pressure
        // force and weight.
        if let Some(liquid) = self.liquid.as_mut() {
            liquid.p2g(
                grid,
                &mut self.particles,
                self.gravity,
                &self.node_mass,
                self.mass_floor,
            );
        }

        // 1c. External loads at the multipliers of the step that ends at
        // t + Δt (the kernel advances its clock first): solid ones beside
        // the constant nodal loads, liquid ones on the liquid's force.
        self.load_now.copy_from_slice(&self.node_load);
        if let Some(external) = self.external.as_ref() {
            let particles = &self.particles;
            external.add::<NC>(
                &self.loads,
                self.time + dt,
                |mp| {
                    let p = &particles[mp as usize];
                    (!p.lost).then(|| (grid.elements[p.element as usize].corners, p.shape))
                },
                &mut self.load_now,
                self.liquid.as_mut().map(|l| &mut l.force[..]),
            );
        }
    }

    /// Phase 2: nodal accelerations and velocities; returns the step's residual
    /// ratio ‖f_ext + f_int‖ / ‖f_ext‖ over the free directions.
    fn nodal_solve(&mut self) -> f64 {
        let dt = self.dt;
        let grid = &self.grid;
        // 2. Nodal accelerations with local damping and fixities. Where the
        // liquid of coupled MPs is, the liquid's and the solid's are solved
        // together with the drag implicit in both velocities:
        //   (M_w + Δt·C) a_w − Δt·C·a_s = F_w − C (v_w − v_s)
        //   n·ρw-mass · a_w + M_s · a_s = F_mix (damped)
        // (unconditionally stable for any permeability).
        let mut residual_sq = 0.0;
        let mut external_sq = 0.0;
        for node in 0..grid.n_nodes() {
            let m = self.node_mass[node];
            let liquid = self
                .liquid
                .as_mut()
                .filter(|l| l.mass[node] > self.mass_floor);
            if m <= self.mass_floor {
                self.node_acceleration[node] = [0.0; D];
                self.node_velocity[node] = [0.0; D];
                self.node_residual[node] = 0.0;
                if let Some(l) = liquid {
                    l.acceleration[node] = [0.0; D];
                    l.velocity[node] = [0.0; D];
                }
                continue;
            }
            let mut node_sq = 0.0;
            let mut liquid = liquid;
            for d in 0..D {
                let solid_fixed = grid.fixed[node][d];
                let velocity = if solid_fixed {
                    0.0
                } else {
                    self.node_momentum[node][d] / m
                };
                let external = self.node_weight[node] * self.gravity[d] + self.load_now[node][d];
                let unbalanced = external + self.node_force[node][d];
                let alpha = self.damping;
                // Local damping: a force less α·|force| along its velocity.
                let damp = |force: f64, v: f64| force - alpha * force.abs() * sign(v);
                let damped = match liquid.as_deref().filter(|_| self.split_damping) {
                    // The kernel damps the mixture in two parts
                    // (`LagrangianPhase.FOR`, `ApplyDampingForce` and
                    // `ApplyDampingForceWater`): the water's porosity-weighted
                    // share of the force, Σ n·S·F_w, with the liquid's
                    // velocity's sign, and the rest with the solid's.
                    Some(l) => {
                        let vw = l.momentum[node][d] / l.mass[node];
                        let fwn = l.porous[node][d];
                        damp(unbalanced - fwn, velocity) + fwn - alpha * fwn.abs() * sign(vw)
                    }
                    None => damp(unbalanced, velocity),
                };
                let mut acceleration = damped / m;
                if let Some(l) = liquid.as_deref_mut() {
                    let mw = l.mass[node];
                    let c = l.drag[node];
                    let vw = l.momentum[node][d] / mw;
                    // Local damping on the liquid's force as the kernel
                    // applies it: before the drag, with the liquid's
                    // velocity's sign; the drag itself is never damped.
                    let fw = damp(l.force[node][d], vw);
                    let aw = if l.fixed[node][d] {
                        0.0
                    } else if solid_fixed {
                        (fw - c * vw) / (mw + dt * c)
                    } else {
                        let water = l.water[node];
                        (fw - c * (vw - velocity) + dt * c * damped / m)
                            / (mw + dt * c + dt * c * water / m)
                    };
                    acceleration -= l.water[node] * aw / m;
                    l.acceleration[node][d] = aw;
                    l.velocity[node][d] = if l.fixed[node][d] { 0.0 } else { vw + aw * dt };
                }
                if solid_fixed {
                    self.node_acceleration[node][d] = 0.0;
                    self.node_velocity[node][d] = 0.0;
                    continue;
                }
                node_sq += unbalanced * unbalanced;
                external_sq += external * external;
                self.node_acceleration[node][d] = acceleration;
                self.node_velocity[node][d] = velocity + acceleration * dt;
            }
            residual_sq += node_sq;
            self.node_residual[node] = node_sq.sqrt();
        }
        ratio(residual_sq.sqrt(), external_sq.sqrt())
    }

    /// Phase 2b: seepage faces and infiltration.
    fn surface_flow(&mut self) {
        let dt = self.dt;
        let grid = &self.grid;
        // 2b. Seepage faces and infiltration ([`super::seepage`]).
        if let (Some(flow), Some(l)) = (self.surface.as_mut(), self.liquid.as_mut()) {
            flow.level = self
                .external
                .as_ref()
                .and_then(|e| e.level(&self.loads, self.time + dt));
            flow.apply(
                grid,
                &self.particles,
                l,
                &self.node_mass,
                &mut self.node_velocity,
                &mut self.node_acceleration,
                self.mass_floor,
                dt,
            );
        }
    }

    /// Phases 3/4: G2P of the solid (velocity, position, the momenta of the MUSL
    /// remap), its nodal velocities again, then the liquid's.
    fn g2p(&mut self) {
        let dt = self.dt;
        let grid = &self.grid;
        // 3. G2P: MP velocity and position, and the momenta for the MUSL remap.
        let acceleration = &self.node_acceleration;
        let node_velocity = &self.node_velocity;
        per_live_mp(
            &mut self.particles,
            &mut self.remap,
            [[0.0; D]; NC],
            |p, out| {
                let corners = &grid.elements[p.element as usize].corners;
                let n = p.shape;
                let mut a = [0.0; D];
                let mut v = [0.0; D];
                for i in 0..NC {
                    let node = corners[i] as usize;
                    for d in 0..D {
                        a[d] += n[i] * acceleration[node][d];
                        v[d] += n[i] * node_velocity[node][d];
                    }
                }
                for d in 0..D {
                    p.velocity[d] += dt * a[d];
                    let dx = dt * v[d];
                    p.position[d] += dx;
                    p.displacement[d] += dx;
                }
                for i in 0..NC {
                    let w = p.mass * n[i];
                    for d in 0..D {
                        out[i][d] = w * p.velocity[d];
                    }
                }
            },
        );

        // 4. MUSL: nodal velocities from the updated MP momenta.
        scatter(grid, &self.particles, &self.remap, &mut self.node_momentum);
        velocities(
            &self.node_mass,
            &self.node_momentum,
            &grid.fixed,
            self.mass_floor,
            &mut self.node_velocity,
        );

        // 3b/4b. The liquid: G2P of its acceleration, then its nodal velocity
        // from the updated momenta (MUSL, fixities again).
        if let Some(liquid) = self.liquid.as_mut() {
            liquid.g2p(grid, &mut self.particles, dt, self.mass_floor);
        }
    }

    /// Every live MP's strain increment, stress update, pore pressure, volume
    /// and element, in parallel ([`update_particle`]).
    fn update_particles(&mut self) {
        let step = ParticleUpdate {
            grid: &self.grid,
            models: &self.models,
            node_velocity: &self.node_velocity,
            liquid_velocity: self.liquid.as_ref().map(|l| &l.velocity[..]),
            advective: self.liquid.as_ref().map(|l| &l.advective[..]),
            dt: self.dt,
            plane_strain: self.plane_strain,
            smoothing: self.element_sums.is_some(),
        };
        self.particles
            .par_iter_mut()
            .with_min_len(MIN_CHUNK)
            .for_each(|p| update_particle(p, &step));
    }

    /// MPM-MIXED's smoothing, the clock, and what the step measured.
    fn close_step(&mut self, residual_ratio: f64) -> StepOutcome {
        let dt = self.dt;
        // MPM-MIXED: σ′ and p averaged over each single-material element
        // (after the MPs moved), then S and p's force term from the average.
        if let Some(sums) = self.element_sums.as_mut() {
            sums.smooth(&mut self.particles);
        }

        self.time += dt;
        self.steps += 1;
        let mut kinetic_energy = 0.0;
        let mut yielded = 0;
        let mut plastic = 0;
        for p in &self.particles {
            let v2: f64 = p.velocity.iter().map(|v| v * v).sum();
            kinetic_energy += 0.5 * p.mass * v2;
            if let Water::Coupled(c) = p.water {
                let w2: f64 = p.liquid_velocity.iter().map(|v| v * v).sum();
                kinetic_energy += 0.5 * c.porosity * c.density * p.volume * w2;
            }
            yielded += p.yielded as usize;
            plastic += p.plastic as usize;
        }
        StepOutcome {
            residual_ratio,
            kinetic_energy,
            yielded,
            plastic,
        }
    }

    /// The seepage face and infiltration applied (none where the analysis is
    /// not partially saturated).
    pub fn surface_boundaries(&self) -> super::seepage::HydraulicBoundaries {
        self.surface
            .as_ref()
            .map(|s| s.boundaries.clone())
            .unwrap_or_default()
    }

    /// Largest and mean displacement magnitude over the MPs still in the mesh.
    pub fn displacement_stats(&self) -> (f64, f64) {
        let mut max = 0.0_f64;
        let mut sum = 0.0;
        let mut count = 0usize;
        for p in self.particles.iter().filter(|p| !p.lost) {
            let u = p.displacement.iter().map(|v| v * v).sum::<f64>().sqrt();
            max = max.max(u);
            sum += u;
            count += 1;
        }
        (max, if count > 0 { sum / count as f64 } else { 0.0 })
    }
}

/// The solid model and the water of each GOM material that MPs use, built
/// on first use, so an unused material with an unsupported model does not
/// stop the check.
struct MaterialSlots {
    /// Per GOM material (0-based): its index into `models`.
    slots: Vec<Option<u32>>,
    /// Per GOM material (0-based): its water.
    waters: Vec<Option<Water>>,
    models: Vec<SolidModel>,
}

impl MaterialSlots {
    fn new(materials: usize) -> Self {
        MaterialSlots {
            slots: vec![None; materials],
            waters: vec![None; materials],
            models: Vec::new(),
        }
    }

    /// The model slot and the water of GOM material `index` (0-based).
    fn get(
        &mut self,
        index: usize,
        material: &a3d_model::Material,
        settings: &RunSettings,
    ) -> Result<(u32, Water), MpmError> {
        let slot = match self.slots[index] {
            Some(slot) => slot,
            None => {
                self.models.push(SolidModel::from_material(material)?);
                let slot = (self.models.len() - 1) as u32;
                self.slots[index] = Some(slot);
                slot
            }
        };
        let water = match self.waters[index] {
            Some(w) => w,
            None => {
                let w = Water::of(
                    material,
                    settings.frozen_pore_pressure,
                    settings.unsaturated_two_phase,
                )?;
                self.waters[index] = Some(w);
                w
            }
        };
        Ok((slot, water))
    }
}

/// What turns a material point and its mapped state into a [`Particle`].
struct ParticleStart<'a, const D: usize, const NC: usize> {
    grid: &'a Grid<D, NC>,
    model: &'a AnuraModel,
    analysis: &'a Analysis,
    settings: &'a RunSettings,
    axisymmetric: bool,
}

impl<const D: usize, const NC: usize> ParticleStart<'_, D, NC> {
    /// The particle of `point` with `state`, its (undrained) P-wave speed, and
    /// whether its initial stress is admissible; an error names the MP.
    fn particle(
        &self,
        point: &MaterialPoint,
        state: &MpState,
        materials: &mut MaterialSlots,
    ) -> Result<(Particle<D, NC>, f64, bool), MpmError> {
        let ParticleStart {
            grid,
            model,
            analysis,
            settings,
            axisymmetric,
        } = *self;
        let bad = |reason: String| MpmError::InvalidPoint {
            id: point.id,
            reason,
        };
        let material_index = point.material as usize;
        let material = material_index
            .checked_sub(1)
            .and_then(|i| model.materials.get(i))
            .ok_or_else(|| bad(format!("material {} does not exist", point.material)))?;
        let (slot, water) = materials.get(material_index - 1, material, settings)?;
        let models = &materials.models;
        let solid = &models[slot as usize];
        let mut position = [0.0; D];
        position.copy_from_slice(&point.position[..D]);
        let finite = position.iter().all(|v| v.is_finite())
            && state.total.iter().all(|v| v.is_finite())
            && state.pwp.is_finite()
            && state.saturation.is_finite();
        if !finite {
            return Err(bad("non-finite position or state".into()));
        }
        if !(point.volume > 0.0 && point.volume.is_finite()) {
            return Err(bad(format!("volume {} is not positive", point.volume)));
        }
        if axisymmetric && position[0] <= 0.0 {
            return Err(bad(format!(
                "radius x = {} is not positive in a 2D-axisymmetric model",
                position[0]
            )));
        }
        let element = grid
            .locate(&position, point.element)
            .ok_or_else(|| bad(format!("position {:?} is outside the mesh", point.position)))?;
        // The kernel's mass and weight of the MP, and its pore term.
        let loading = analysis.loading(material_index - 1, material, state.saturation);
        let density = loading.density;
        if !(density > 0.0 && density.is_finite() && loading.weight_density.is_finite()) {
            return Err(bad(format!(
                "material {} gives density {density} t/m³; check porosity and densities",
                point.material
            )));
        }
        let mut stress = state.effective();
        if D == 2 {
            // Plane strain: no out-of-plane shear.
            stress[4] = 0.0;
            stress[5] = 0.0;
        }
        let admissible = solid.is_admissible(&stress, D == 2);
        // The undrained wave: the liquid stiffens the mixture by K_w/n.
        let speed = ((solid.elasticity.p_wave_modulus() + water.bulk_over_n()) / density).sqrt();
        // A coupled MP's solid carries the mixture less its water.
        let mass = match water {
            Water::Coupled(c) => density - c.porosity * state.saturation * c.density,
            _ => density,
        } * point.volume;
        let particle = Particle {
            position,
            displacement: [0.0; D],
            velocity: [0.0; D],
            shape: [0.0; NC],
            inverse_radius: 0.0,
            stress,
            mass,
            weight: loading.weight_density * point.volume,
            volume: point.volume,
            pore_term: loading.pore_factor * state.pwp,
            element,
            model: slot,
            yielded: false,
            plastic_strain: 0.0,
            plastic: false,
            lost: false,
            pwp: state.pwp,
            pore_factor: loading.pore_factor,
            water,
            liquid_velocity: [0.0; D],
            saturation: state.saturation,
            volume0: point.volume,
            // The kernel sets k from S when it reads the MAPF.
            conductivity: match water {
                Water::Coupled(c) if c.retention.is_some() => {
                    c.conductivity.relative(state.saturation)
                }
                _ => 1.0,
            },
        };
        Ok((particle, speed, admissible))
    }
}

/// Density scaling of the quasi-static runs ([`RunSettings::mass_scaling`]):
/// every MP faster than the slowest (but no more than
/// [`super::MAX_MASS_SCALING`] in mass) gets its inertia raised to that wave
/// speed, its weight kept. Returns the wave speed that sets the step.
fn scale_masses<const D: usize, const NC: usize>(
    particles: &mut [Particle<D, NC>],
    speeds: &[f64],
    wave_speed: f64,
) -> f64 {
    let slowest = speeds.iter().copied().fold(f64::INFINITY, f64::min);
    let floor = wave_speed / super::MAX_MASS_SCALING.sqrt();
    let target = slowest.max(floor);
    if target.is_finite() && target > 0.0 {
        for (p, &c) in particles.iter_mut().zip(speeds) {
            if c > target {
                p.mass *= (c / target) * (c / target);
            }
        }
        return target;
    }
    wave_speed
}

/// What [`update_particle`] reads of the solver in one step.
struct ParticleUpdate<'a, const D: usize, const NC: usize> {
    grid: &'a Grid<D, NC>,
    models: &'a [SolidModel],
    node_velocity: &'a [[f64; D]],
    liquid_velocity: Option<&'a [[f64; D]]>,
    advective: Option<&'a [f64]>,
    dt: f64,
    plane_strain: bool,
    smoothing: bool,
}

/// One MP's end of a step: strain increment, stress update (and its plastic
/// strain), pore pressure, volume, water, and its element again (lost when it
/// left the mesh).
fn update_particle<const D: usize, const NC: usize>(
    p: &mut Particle<D, NC>,
    step: &ParticleUpdate<'_, D, NC>,
) {
    let ParticleUpdate {
        grid,
        models,
        node_velocity,
        liquid_velocity,
        advective,
        dt,
        plane_strain,
        smoothing,
    } = *step;
    if p.lost {
        p.yielded = false;
        return;
    }
    let element = &grid.elements[p.element as usize];
    let strain =
        strain_increment_at::<D, NC>(element, &p.shape, p.inverse_radius, node_velocity, dt);
    let model = &models[p.model as usize];
    let before = p.stress;
    let kind = model.update(&mut p.stress, &strain, plane_strain);
    p.yielded = kind.is_plastic();
    if p.yielded {
        let mut trial = before;
        model.elasticity.add_increment(&mut trial, &strain);
        let mut taken = [0.0; 6];
        for k in 0..6 {
            taken[k] = trial[k] - p.stress[k];
        }
        let e = model.elasticity.strain_of(&taken);
        p.plastic_strain += e.iter().map(|v| v * v).sum::<f64>().sqrt();
        p.plastic |= p.plastic_strain > PLASTIC_STRAIN_FLOOR;
    }
    let volumetric = strain[0] + strain[1] + strain[2];
    match p.water {
        Water::Frozen => {}
        Water::Undrained { bulk_over_n } => {
            p.pwp += bulk_over_n * volumetric;
        }
        Water::Coupled(c) => {
            let n = c.porosity;
            let s = p.saturation;
            let partial = c.retention.is_some() && s > 0.0 && s < 1.0;
            // The water's volume demand per unit volume of the
            // mixture: partially saturated, the kernel's
            // S·Δε_v + A/ρw with its advective term
            // A = Σ ∇N·(n ρw S)_node (Δu_w − Δu_s); saturated,
            // (1 − n)·Δε_v,s + n·Δε_v,w.
            let demand = match (partial, liquid_velocity, advective) {
                (true, Some(v), Some(a)) => {
                    let flux = advective_flux(
                        element,
                        a,
                        v,
                        node_velocity,
                        dt,
                        p.inverse_radius,
                        &p.shape,
                    );
                    s * volumetric + flux / c.density
                }
                _ => {
                    // The liquid's volumetric strain, from the same operator.
                    let liquid = liquid_velocity.map_or(0.0, |v| {
                        let e = strain_increment_at::<D, NC>(
                            element,
                            &p.shape,
                            p.inverse_radius,
                            v,
                            dt,
                        );
                        e[0] + e[1] + e[2]
                    });
                    (1.0 - n) * volumetric + n * liquid
                }
            };
            p.pwp += c.pressure_increment(p.pwp, s, demand);
        }
    }
    p.volume *= 1.0 + volumetric;
    if !smoothing {
        settle_water(p);
    }
    if !grid.contains(p.element, &p.position) {
        match grid.locate(&p.position, p.element) {
            Some(e) => p.element = e,
            None => {
                p.lost = true;
                p.velocity = [0.0; D];
                p.liquid_velocity = [0.0; D];
            }
        }
    }
}

#[inline]
fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// a / b with 0/0 = 0 and x/0 = ∞.
pub(crate) fn ratio(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        a / b
    } else if a == 0.0 {
        0.0
    } else {
        f64::INFINITY
    }
}
