//! The discrete equilibrium equations of one model, assembled the way the
//! explicit runner ([`crate::step`]) assembles its forces: the same grid
//! ([`Grid`]: compact corner nodes, the GOM's fixities, the axis fixed in 2D
//! axisymmetry), the same MP location, volumes, masses, weights and pore
//! terms (the kernel's, [`super::super::loading`]), the same B operator
//! ([`super::super::b_matrix`], hoop terms included) and the same free degrees
//! of freedom (free directions of nodes heavier than the runner's mass floor). What the runner measures at
//! its first step is what [`System::verify_residual`] measures here.
//!
//! Unknowns are the corner-node displacements u from a stress-free state with
//! gravity switched on; an integration group (an element, or in 2D
//! axisymmetry an MP unless the model is MPM-MIXED) carries one effective
//! stress σ′ = σ′(ε), ε = B u. Within a linear simplex B is constant, so every
//! MP of an element strains alike and the element is one group; in 2D
//! axisymmetry the hoop row N_i/r differs between MPs, and MPM-MIXED (whose MPs
//! all carry the element's first MP's state) averages it over the element,
//! h_i = Σ V_p N_i(x_p)/r_p / Σ V_p. The pore-water part of each MP's stress
//! in the internal force is held fixed and enters as a constant force.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

use super::super::MpmError;
use super::super::b_matrix::{corner_force, hoop_strain_increment, strain_increment};
use super::super::grid::Grid;
use super::super::loading::Analysis;
use super::super::material::SolidModel;
use super::EquilibriumSettings;
use super::ordering::DISSECTION_FROM;
use super::sparse::{CONSTRAINED, LowerPattern, Ordering};
use a3d_element::Element;
use a3d_model::{AnuraModel, Dimension, MaterialPoint, MpState};

/// One MP as the runner sees it at its first step.
#[derive(Clone, Copy, Debug)]
pub(super) struct Point<const NC: usize> {
    pub element: u32,
    pub shape: [f64; NC],
    /// 1/r in 2D axisymmetry (with the runner's floor), else 0.
    pub inverse_radius: f64,
    pub volume: f64,
    /// The pore-water part added to the normal components of σ′ in the
    /// internal force (kPa).
    pub pore_term: f64,
    pub group: u32,
}

/// One integration group: the MPs that share one effective stress.
#[derive(Clone, Copy, Debug)]
pub(super) struct Group<const NC: usize> {
    pub element: u32,
    /// Σ V_p over the group's MPs.
    pub volume: f64,
    /// Hoop coefficients h_i (2D axisymmetry), else 0.
    pub hoop: [f64; NC],
    /// Index into [`System::laws`].
    pub law: u32,
}

/// The assembled discrete system of one model.
pub(super) struct System<const D: usize, const NC: usize> {
    pub grid: Grid<D, NC>,
    pub points: Vec<Point<NC>>,
    pub groups: Vec<Group<NC>>,
    /// The constitutive law of each group's material (the solve's elasticity).
    pub laws: Vec<SolidModel>,
    /// Per compact node and direction: free number or [`CONSTRAINED`].
    pub dof: Vec<u32>,
    pub n_free: usize,
    /// Gravity load Σ N w_p g per compact node and direction (the runner's
    /// f_ext).
    pub external: Vec<f64>,
    /// −Σ V_p Bᵀ(pore term) per compact node and direction: the pore-water
    /// part of the internal force, held fixed.
    pub pore_force: Vec<f64>,
    /// ‖f_ext‖ over the free directions (the runner's denominator).
    pub external_norm: f64,
    pub axisymmetric: bool,
    /// Per compact node, its mesh coordinates (the ordering of large
    /// systems, [`super::ordering`]).
    pub node_positions: Vec<[f64; 3]>,
}

/// The free directions of the nodes that carry mass (heavier than 10⁻¹⁰ of the
/// heaviest MP, and not fixed) numbered in node order, and the gravity load
/// on them, summed in MP order as the runner sums it: (per node and
/// direction the free number or [`CONSTRAINED`], the free count, f_ext,
/// ‖f_ext‖²).
fn number_dofs<const D: usize, const NC: usize>(
    grid: &Grid<D, NC>,
    points: &[Point<NC>],
    masses: &[f64],
    weights: &[f64],
    gravity: f64,
) -> (Vec<u32>, u32, Vec<f64>, f64) {
    // Nodal masses and gravity, in MP order as the runner sums them.
    let n_nodes = grid.n_nodes();
    let mut node_mass = vec![0.0; n_nodes];
    let mut node_weight = vec![0.0; n_nodes];
    for ((p, &mass), &weight) in points.iter().zip(masses).zip(weights) {
        let corners = &grid.elements[p.element as usize].corners;
        for i in 0..NC {
            node_mass[corners[i] as usize] += mass * p.shape[i];
            node_weight[corners[i] as usize] += weight * p.shape[i];
        }
    }
    let max_mass = masses.iter().copied().fold(0.0, f64::max);
    let floor = 1e-10 * max_mass;
    let mut dof = vec![CONSTRAINED; n_nodes * D];
    let mut n_free = 0u32;
    let mut external = vec![0.0; n_nodes * D];
    let mut external_sq = 0.0;
    for node in 0..n_nodes {
        if node_mass[node] <= floor {
            continue;
        }
        for d in 0..D {
            if grid.fixed[node][d] {
                continue;
            }
            dof[node * D + d] = n_free;
            n_free += 1;
            let f = if d == 1 {
                node_weight[node] * -gravity
            } else {
                0.0
            };
            external[node * D + d] = f;
            external_sq += f * f;
        }
    }
    (dof, n_free, external, external_sq)
}

impl<const D: usize, const NC: usize> System<D, NC> {
    /// Builds the system of `model` with the MPs `points` holding the pore
    /// state of `states` (pwp and saturation; their total stress is not read),
    /// `laws` per material (index = material − 1; `None` for materials no MP
    /// uses), under `settings` (gravity, the submerged calculation, and one
    /// group per element for MPM-MIXED).
    pub fn new<E: Element<D, NC>>(
        model: &AnuraModel,
        points: &[MaterialPoint],
        states: &[MpState],
        laws: &[Option<SolidModel>],
        settings: &EquilibriumSettings,
    ) -> Result<System<D, NC>, MpmError> {
        let (gravity, per_element) = (settings.gravity, settings.mixed);
        let analysis = Analysis::of(&model.materials, settings.submerged_calculation);
        let axisymmetric = D == 2 && model.mesh.dimension == Dimension::Axisymmetric;
        let mut grid = Grid::<D, NC>::new::<E>(&model.mesh, &model.solid_fixity)?;
        if axisymmetric {
            grid.fix_axis(&model.mesh);
        }
        let radius_floor = 1e-6 * grid.min_altitude();
        let mut slots: Vec<Option<u32>> = vec![None; model.materials.len()];
        let mut used: Vec<SolidModel> = Vec::new();
        let mut out_points = Vec::with_capacity(points.len());
        let mut groups: Vec<Group<NC>> = Vec::new();
        let mut masses = Vec::with_capacity(points.len());
        let mut weights = Vec::with_capacity(points.len());
        for (point, state) in points.iter().zip(states) {
            let bad = |reason: String| MpmError::InvalidPoint {
                id: point.id,
                reason,
            };
            let m = point.material as usize;
            let material = m
                .checked_sub(1)
                .and_then(|i| model.materials.get(i))
                .ok_or_else(|| bad(format!("material {} does not exist", point.material)))?;
            let law = match slots[m - 1] {
                Some(slot) => slot,
                None => {
                    let law = laws.get(m - 1).and_then(Option::as_ref).ok_or_else(|| {
                        MpmError::InvalidSettings(format!(
                            "material {m} has material points but no constitutive law"
                        ))
                    })?;
                    used.push(law.clone());
                    let slot = (used.len() - 1) as u32;
                    slots[m - 1] = Some(slot);
                    slot
                }
            };
            let mut position = [0.0; D];
            position.copy_from_slice(&point.position[..D]);
            if !(position.iter().all(|v| v.is_finite())
                && state.pwp.is_finite()
                && state.saturation.is_finite())
            {
                return Err(bad("non-finite position or pore state".into()));
            }
            if !(point.volume > 0.0 && point.volume.is_finite()) {
                return Err(bad(format!("volume {} is not positive", point.volume)));
            }
            let element = grid
                .locate(&position, point.element)
                .ok_or_else(|| bad(format!("position {:?} is outside the mesh", point.position)))?;
            let loading = analysis.loading(m - 1, material, state.saturation);
            let density = loading.density;
            if !(density > 0.0 && density.is_finite() && loading.weight_density.is_finite()) {
                return Err(bad(format!(
                    "material {} gives density {density} t/m³; check porosity and densities",
                    point.material
                )));
            }
            let shape = grid.elements[element as usize].shape.values(&position);
            let inverse_radius = if axisymmetric {
                1.0 / position[0].max(radius_floor)
            } else {
                0.0
            };
            // A new group unless this MP joins the previous one (same element).
            let joins = (per_element || !axisymmetric)
                && groups
                    .last()
                    .is_some_and(|g| g.element == element && g.law == law);
            if !joins {
                groups.push(Group {
                    element,
                    volume: 0.0,
                    hoop: [0.0; NC],
                    law,
                });
            }
            let group = groups.len() - 1;
            let g = &mut groups[group];
            g.volume += point.volume;
            if axisymmetric {
                for i in 0..NC {
                    g.hoop[i] += point.volume * shape[i] * inverse_radius;
                }
            }
            masses.push(density * point.volume);
            weights.push(loading.weight_density * point.volume);
            out_points.push(Point {
                element,
                shape,
                inverse_radius,
                volume: point.volume,
                pore_term: loading.pore_factor * state.pwp,
                group: group as u32,
            });
        }
        if out_points.is_empty() {
            return Err(MpmError::NoMaterialPoints);
        }
        for g in &mut groups {
            for h in &mut g.hoop {
                *h /= g.volume;
            }
        }
        let (dof, n_free, external, external_sq) =
            number_dofs(&grid, &out_points, &masses, &weights, gravity);
        let n_nodes = grid.n_nodes();
        let node_positions = grid
            .mesh_node
            .iter()
            .map(|&m| model.mesh.nodes[m as usize])
            .collect();
        let mut system = System {
            grid,
            points: out_points,
            groups,
            laws: used,
            dof,
            n_free: n_free as usize,
            external,
            pore_force: vec![0.0; n_nodes * D],
            external_norm: external_sq.sqrt(),
            axisymmetric,
            node_positions,
        };
        let mut pore = vec![0.0; n_nodes * D];
        for p in &system.points {
            let mut s = [0.0; 6];
            s[..3].fill(p.pore_term);
            system.add_point_force(p, &s, &mut pore);
        }
        system.pore_force = pore;
        Ok(system)
    }

    /// Adds −V Bᵀσ of one MP (total stress `s`) to `force`, as the runner's P2G.
    #[inline]
    fn add_point_force(&self, p: &Point<NC>, s: &[f64; 6], force: &mut [f64]) {
        let element = &self.grid.elements[p.element as usize];
        for i in 0..NC {
            let f = corner_force::<D>(
                s,
                &element.shape.grad[i],
                p.shape[i],
                p.volume,
                p.inverse_radius,
            );
            let node = element.corners[i] as usize;
            for d in 0..D {
                force[node * D + d] += f[d];
            }
        }
    }

    /// The runner's residual ratio ‖f_ext + f_int‖/‖f_ext‖ over the free
    /// directions for per-MP effective stresses `effective` (the pore term
    /// added to the normals, forces summed in MP order), and the unbalanced
    /// force per compact node (its length over the free directions).
    pub fn verify_residual(&self, effective: &[[f64; 6]]) -> (f64, Vec<f64>) {
        let mut force = vec![0.0; self.external.len()];
        for (p, s) in self.points.iter().zip(effective) {
            let mut total = *s;
            for k in 0..3 {
                total[k] += p.pore_term;
            }
            self.add_point_force(p, &total, &mut force);
        }
        let n_nodes = self.grid.n_nodes();
        let mut per_node = vec![0.0; n_nodes];
        let mut sum = 0.0;
        for node in 0..n_nodes {
            let mut sq = 0.0;
            for d in 0..D {
                let k = node * D + d;
                if self.dof[k] != CONSTRAINED {
                    let r = self.external[k] + force[k];
                    sq += r * r;
                }
            }
            sum += sq;
            per_node[node] = sq.sqrt();
        }
        (
            super::super::step::ratio(sum.sqrt(), self.external_norm),
            per_node,
        )
    }

    /// −Σ_g V_g B_gᵀσ′_g per compact node and direction for group stresses
    /// `stress` (the effective part of the internal force).
    pub fn group_force(&self, stress: &[[f64; 6]]) -> Vec<f64> {
        let mut force = vec![0.0; self.external.len()];
        let hoop_weight = if self.axisymmetric { 1.0 } else { 0.0 };
        for (g, s) in self.groups.iter().zip(stress) {
            let element = &self.grid.elements[g.element as usize];
            for i in 0..NC {
                let f =
                    corner_force::<D>(s, &element.shape.grad[i], g.hoop[i], g.volume, hoop_weight);
                let node = element.corners[i] as usize;
                for d in 0..D {
                    force[node * D + d] += f[d];
                }
            }
        }
        force
    }

    /// The strain ε = B u of every group (engineering shear, hoop strain in
    /// the zz slot in 2D axisymmetry) for nodal displacements `u`.
    pub fn group_strain(&self, u: &[[f64; D]], g: &Group<NC>) -> [f64; 6] {
        let element = &self.grid.elements[g.element as usize];
        let mut e = strain_increment::<D, NC>(element, u, 1.0);
        if self.axisymmetric {
            e[2] = hoop_strain_increment(&g.hoop, &element.corners, u, 1.0, 1.0);
        }
        e
    }

    /// Nodal displacements from the free unknowns `x` (constrained ones 0).
    pub fn displacements(&self, x: &[f64]) -> Vec<[f64; D]> {
        let mut u = vec![[0.0; D]; self.grid.n_nodes()];
        for (k, &dof) in self.dof.iter().enumerate() {
            if dof != CONSTRAINED {
                u[k / D][k % D] = x[dof as usize];
            }
        }
        u
    }

    /// `f_ext + pore_force + force` (the out-of-balance force) at the free
    /// unknowns, scaled by `load` for the external and pore parts.
    pub fn free_residual(&self, force: &[f64], load: f64) -> Vec<f64> {
        let mut r = vec![0.0; self.n_free];
        for (k, &dof) in self.dof.iter().enumerate() {
            if dof != CONSTRAINED {
                r[dof as usize] = load * (self.external[k] + self.pore_force[k]) + force[k];
            }
        }
        r
    }

    /// The pattern of the stiffness matrix over the free unknowns (from the
    /// elements that hold MPs), ordered by nested dissection for a 3D system
    /// of [`DISSECTION_FROM`] unknowns or more, by AMD otherwise
    /// ([`super::ordering`]).
    pub fn pattern(&self) -> LowerPattern {
        let ordering = if D == 3 && self.n_free >= DISSECTION_FROM {
            Ordering::Dissection(&self.node_positions)
        } else {
            Ordering::Amd
        };
        let mut active = vec![false; self.grid.elements.len()];
        for g in &self.groups {
            active[g.element as usize] = true;
        }
        LowerPattern::new(
            self.grid
                .elements
                .iter()
                .zip(&active)
                .filter(|(_, a)| **a)
                .map(|(e, _)| e.corners),
            self.grid.n_nodes(),
            D,
            &self.dof,
            ordering,
        )
    }

    /// The lower triangle of K = Σ_g V_g B_gᵀ D_g B_g on `pattern`: for an
    /// isotropic D, K_{ai,bj} = V [λ d_ai d_bj + G (∂_j N_a ∂_i N_b + δ_ij ∇N_a·∇N_b)]
    /// with d_ai = ∂_i N_a (+ h_a for i = r in axisymmetry), plus 2G h_a h_b on
    /// the radial pair.
    pub fn stiffness(&self, pattern: &LowerPattern) -> Vec<f64> {
        let mut values = vec![0.0; pattern.nnz()];
        for g in &self.groups {
            let element = &self.grid.elements[g.element as usize];
            let elastic = &self.laws[g.law as usize].elasticity;
            let (lambda, shear) = (elastic.lame(), elastic.shear);
            let grad = &element.shape.grad;
            let mut div = *grad;
            if self.axisymmetric {
                for a in 0..NC {
                    div[a][0] += g.hoop[a];
                }
            }
            for a in 0..NC {
                for i in 0..D {
                    let col = self.dof[element.corners[a] as usize * D + i];
                    if col == CONSTRAINED {
                        continue;
                    }
                    for b in 0..NC {
                        let dot: f64 = (0..D).map(|k| grad[a][k] * grad[b][k]).sum();
                        for j in 0..D {
                            let row = self.dof[element.corners[b] as usize * D + j];
                            if row == CONSTRAINED || row < col {
                                continue;
                            }
                            let mut k =
                                lambda * div[a][i] * div[b][j] + shear * grad[a][j] * grad[b][i];
                            if i == j {
                                k += shear * dot;
                                if self.axisymmetric && i == 0 {
                                    k += 2.0 * shear * g.hoop[a] * g.hoop[b];
                                }
                            }
                            values[pattern.position(row as usize, col as usize)] += g.volume * k;
                        }
                    }
                }
            }
        }
        values
    }

    /// Per element: the sum of the unbalanced force over its corners.
    pub fn element_residuals(&self, per_node: &[f64]) -> Vec<f64> {
        self.grid
            .elements
            .iter()
            .map(|e| e.corners.iter().map(|&c| per_node[c as usize]).sum())
            .collect()
    }
}
