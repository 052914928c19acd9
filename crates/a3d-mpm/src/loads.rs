//! The GOM's distributed loads ([`a3d_model::loads`]) as forces on the
//! grid and the MPs, built once when the run starts and scaled every step by
//! the CPS multipliers, as the Anura3D kernel does (`BuildLoad.FOR`
//! `Load2D`/`Load3D`, `MPMInit.FOR` `TransferExternalLoadsToParticles`,
//! `LagrangianPhase.FOR`, `MPMDYN2PhaseSP.FOR`):
//!
//! * **On nodes.** One-point integration over the side: each corner gets
//!   measure/n_corners × the mean of the corner values (a segment's length or
//!   a triangle's area; 2D-axisymmetric: the mean of value × radius, and a
//!   corner on the axis hands 7/8 of its share to the other, as the kernel's
//!   `Load2D`). Solid values are tractions per component; a liquid value is
//!   the first component only, a pressure (negative in compression) along
//!   the side's normal turned out of the elements with MPs that hold the
//!   side (out of the last of them, in element order, where two do).
//! * **On MPs.** The side's total (measure × mean value; liquid: each
//!   component × the same component of the side's unit normal, as the
//!   kernel's `DetermineLoadPerParticle`, with the normal as the node order
//!   gives it) is shared equally by the MPs the kernel's tables put next to
//!   that side, in every element with MPs that holds it. The MPs carry their
//!   share as they move (mapped with their shape functions each step). In 2D
//!   the kernel finds the side only across a neighbouring element, so a load
//!   on a side at the mesh's edge reaches no MP there; the runner does the
//!   same and says so.
//!
//! Solid loads act on the mixture (or the solid of one-phase materials);
//! liquid loads on the liquid equation of two-phase MPs only (the mixture
//! feels them through the liquid's inertia). Where no MP runs two-phase they
//! have nothing to act on, and the runner says so.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

use std::collections::HashMap;

use super::grid::{Grid, NO_ELEMENT};
use a3d_model::loads::{LoadPhase, LoadTarget, ProjectLoads, SideLoad};
use a3d_model::{MaterialPoint, Mesh};

/// The kernel's "is applied" threshold for MP loads (`IsLoadApplied`): a side
/// whose values are all within this of 0 is skipped.
const APPLIED: f64 = 1e-4;

/// Anura3D's MPs next to each side of an element, per MP count (1-based
/// local MP numbers; `ElemCalcTRI.FOR` / `ElemCalcTETRA.FOR`
/// `DetermineAdjacentParticles*`). Sides of TRI3: 1 = corners 1–2,
/// 2 = 3–1, 3 = 2–3. Sides of `tetrahedral_old`: 1 = corners {1, 2, 3},
/// 2 = {1, 2, 4}, 3 = {1, 3, 4}, 4 = {2, 3, 4}.
fn adjacent_mps(dim: usize, count: usize, side: usize) -> Option<&'static [u32]> {
    const TRI: [(usize, [&[u32]; 3]); 7] = [
        (3, [&[1, 2], &[1, 3], &[2, 3]]),
        (6, [&[2, 4, 6], &[3, 4, 5], &[1, 5, 6]]),
        (12, [&[4, 6, 8, 11], &[4, 5, 9, 12], &[5, 6, 7, 10]]),
        (
            16,
            [&[3, 8, 10, 12, 15], &[4, 8, 9, 13, 16], &[2, 9, 10, 11, 14]],
        ),
        (
            25,
            [
                &[3, 15, 19, 21, 25],
                &[4, 16, 18, 22, 24],
                &[2, 14, 17, 20, 23],
            ],
        ),
        (
            46,
            [
                &[2, 4, 6, 25, 27, 31, 33, 43, 45],
                &[2, 3, 7, 26, 28, 32, 34, 44, 46],
                &[3, 4, 5, 23, 24, 29, 30, 41, 42],
            ],
        ),
        (
            88,
            [
                &[8, 10, 12, 61, 63, 66, 68, 72, 74, 84, 86],
                &[8, 9, 13, 62, 64, 65, 67, 71, 73, 83, 85],
                &[9, 10, 11, 59, 60, 69, 75, 76, 81, 82, 87],
            ],
        ),
    ];
    const TET: [(usize, [&[u32]; 4]); 6] = [
        (4, [&[1, 2, 3], &[1, 2, 4], &[1, 3, 4], &[2, 3, 4]]),
        (
            7,
            [
                &[1, 2, 3, 5, 6],
                &[1, 2, 4, 5, 7],
                &[1, 3, 4, 6, 7],
                &[2, 3, 4],
            ],
        ),
        (
            8,
            [&[1, 2, 3, 5], &[1, 2, 4, 7], &[1, 3, 4, 8], &[2, 3, 4, 6]],
        ),
        (
            10,
            [
                &[1, 2, 3, 5, 6, 8],
                &[1, 2, 4, 5, 7, 9],
                &[1, 3, 4, 6, 7, 10],
                &[2, 3, 4, 8, 9, 10],
            ],
        ),
        (
            13,
            [
                &[1, 2, 3, 5, 6, 8, 9, 11, 12],
                &[1, 2, 4, 5, 7, 8, 10, 11, 13],
                &[1, 3, 4, 6, 7, 9, 10, 12, 13],
                &[2, 3, 4],
            ],
        ),
        (
            20,
            [
                &[1, 2, 3, 4, 11, 12, 13, 17, 18, 20],
                &[1, 5, 8, 10, 11, 16, 17, 19, 20],
                &[1, 2, 3, 4, 5, 6, 7, 8],
                &[4, 7, 9, 10],
            ],
        ),
    ];
    if count == 1 {
        return Some(&[1]);
    }
    if dim == 2 {
        TRI.iter()
            .find(|(n, _)| *n == count)
            .and_then(|(_, t)| t.get(side.checked_sub(1)?).copied())
    } else {
        TET.iter()
            .find(|(n, _)| *n == count)
            .and_then(|(_, t)| t.get(side.checked_sub(1)?).copied())
    }
}

/// The local corners (0-based) of each side, in the kernel's side order.
fn side_corners(dim: usize) -> &'static [&'static [usize]] {
    if dim == 2 {
        &[&[0, 1], &[2, 0], &[1, 2]]
    } else {
        &[&[0, 1, 2], &[0, 1, 3], &[0, 2, 3], &[1, 2, 3]]
    }
}

/// A block's nodal forces at multiplier 1: its phase, load system and
/// (grid node, force) pairs.
type NodalForces<const D: usize> = (LoadPhase, usize, Vec<(u32, [f64; D])>);

/// The water level's sides: per grid node its force under a unit pressure
/// (outward, tension positive) and its height y; with γw (kN/m³).
type WaterLevel<const D: usize> = (Vec<(u32, [f64; D], f64)>, f64);

/// The loads of a run, built for its grid and MPs; the multipliers that
/// scale them stay in the caller's [`ProjectLoads`].
pub(crate) struct ExternalLoads<const D: usize> {
    nodal: Vec<NodalForces<D>>,
    /// (phase, system, MP index, force at multiplier 1).
    on_mps: Vec<(LoadPhase, usize, u32, [f64; D])>,
    head: Option<WaterLevel<D>>,
    /// What was not applied, and why.
    pub notes: Vec<String>,
}

/// The water level's load ([`WaterLevel`]): the kernel's unit pressure on the
/// free-surface sides in `$$BOUNDARY_HYDRAULIC_HEAD_AREA`, as nodal forces
/// with each node's height, and γw. `None`, with a note saying why, when no
/// MP runs two-phase; an empty load, with its note, when no side lies in the
/// area.
fn head_load<const D: usize, const NC: usize>(
    series: &a3d_model::loads::HeadSeries,
    gamma_w: Option<f64>,
    grid: &Grid<D, NC>,
    active: &dyn Fn(usize) -> bool,
    coords: &dyn Fn(u32) -> [f64; D],
    axisymmetric: bool,
    notes: &mut Vec<String>,
) -> Option<WaterLevel<D>> {
    match gamma_w {
        None => {
            notes.push(
                "$$HYDRAULIC_HEAD file: the water level loads two-phase materials, and none runs two-phase here; not applied"
                    .into(),
            );
            None
        }
        Some(gamma) => {
            let sides = head_sides(grid, active, coords, &series.area);
            if sides.is_empty() {
                notes.push(
                    "$$HYDRAULIC_HEAD file: no free-surface side lies in $$BOUNDARY_HYDRAULIC_HEAD_AREA; not applied"
                        .into(),
                );
            }
            // The kernel's unit pressure on every corner.
            let unit = SideLoad {
                corners: Vec::new(),
                values: vec![[1.0; 3]; D],
                line: 0,
            };
            let mut forces: Vec<(u32, [f64; D], f64)> = Vec::new();
            for (e, nodes) in sides {
                let x: Vec<[f64; D]> = nodes
                    .iter()
                    .map(|&n| coords(grid.mesh_node[n as usize]))
                    .collect();
                let mut at = Side::new(&unit, x);
                at.turn_out_of(grid, e, &nodes, coords);
                let f = at.nodal_forces(LoadPhase::Liquid, axisymmetric);
                for (k, &node) in nodes.iter().enumerate() {
                    match forces.iter_mut().find(|(n, _, _)| *n == node) {
                        Some((_, sum, _)) => (0..D).for_each(|d| sum[d] += f[k][d]),
                        None => forces.push((node, f[k], at.x[k][1])),
                    }
                }
            }
            Some((forces, gamma))
        }
    }
}

/// An MP load's side: the grid, the MPs of each active element (by local
/// number), the elements that hold every corner of the side, and its corners.
struct SideOnMps<'a, const D: usize, const NC: usize> {
    grid: &'a Grid<D, NC>,
    in_element: &'a HashMap<u32, Vec<u32>>,
    holders: &'a [usize],
    grid_nodes: &'a [u32],
}

impl<const D: usize, const NC: usize> SideOnMps<'_, D, NC> {
    /// Shares the side's `total` force among the MPs next to it in each
    /// active element that holds it (the kernel's tables), handing each MP
    /// and its share to `push`; whether any MP was reached.
    fn spread(&self, total: [f64; D], mut push: impl FnMut(u32, [f64; D])) -> bool {
        let grid = self.grid;
        let mut reached = false;
        for &e in self
            .holders
            .iter()
            .filter(|&&e| self.in_element.contains_key(&(e as u32)))
        {
            let Some(side_number) = element_side(grid, e, self.grid_nodes) else {
                continue;
            };
            let mps = &self.in_element[&(e as u32)];
            let Some(table) = adjacent_mps(D, mps.len(), side_number) else {
                continue;
            };
            let loaded: Vec<u32> = table
                .iter()
                .filter_map(|&k| mps.get(k as usize - 1).copied())
                .collect();
            let share = 1.0 / loaded.len().max(1) as f64;
            for &mp in &loaded {
                let mut f = [0.0; D];
                for d in 0..D {
                    f[d] = total[d] * share;
                }
                push(mp, f);
                reached = true;
            }
        }
        reached
    }
}

/// The geometry of a side: its unit normal as the kernel's node order gives
/// it (2D: the left normal of corner 1 → 2; 3D: (c2 − c1) × (c3 − c1)) and
/// its measure (length or area).
fn side_geometry<const D: usize>(corners: &[[f64; D]]) -> ([f64; D], f64) {
    let mut normal = [0.0; D];
    let measure;
    if D == 2 {
        let a = [corners[1][0] - corners[0][0], corners[1][1] - corners[0][1]];
        measure = (a[0] * a[0] + a[1] * a[1]).sqrt();
        normal[0] = -a[1] / measure;
        normal[1] = a[0] / measure;
    } else {
        let a: Vec<f64> = (0..3).map(|d| corners[1][d] - corners[0][d]).collect();
        let b: Vec<f64> = (0..3).map(|d| corners[2][d] - corners[0][d]).collect();
        let c = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        let length = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        measure = 0.5 * length;
        for d in 0..3 {
            normal[d] = c[d] / length;
        }
    }
    (normal, measure)
}

impl<const D: usize> ExternalLoads<D> {
    /// Builds the loads of `loads` on `grid` for the MPs `points` (in
    /// Anura3D's order, each with its grid element now).
    /// `axisymmetric`: 2D-axisymmetric weighting; `gamma_w`: the unit weight
    /// of the water of the two-phase materials (kN/m³), `None` when no MP
    /// runs two-phase.
    pub fn new<const NC: usize>(
        loads: &ProjectLoads,
        grid: &Grid<D, NC>,
        mesh: &Mesh,
        points: &[MaterialPoint],
        axisymmetric: bool,
        gamma_w: Option<f64>,
    ) -> ExternalLoads<D> {
        let liquid = gamma_w.is_some();
        let compact = grid.compact_nodes();
        // The MPs of each element, by local number, and the active elements.
        let mut in_element: HashMap<u32, Vec<u32>> = HashMap::new();
        for (i, p) in points.iter().enumerate() {
            in_element.entry(p.element).or_default().push(i as u32);
        }
        let active = |e: usize| in_element.contains_key(&(e as u32));
        // Elements by corner node, ascending (the kernel's node–element lists).
        let mut by_node: HashMap<u32, Vec<usize>> = HashMap::new();
        for (e, el) in grid.elements.iter().enumerate() {
            for &c in &el.corners {
                by_node.entry(c).or_default().push(e);
            }
        }
        let coords = |node: u32| {
            let mut x = [0.0; D];
            x.copy_from_slice(&mesh.nodes[node as usize][..D]);
            x
        };
        let mut out = ExternalLoads {
            nodal: Vec::new(),
            on_mps: Vec::new(),
            head: None,
            notes: Vec::new(),
        };
        if let Some(series) = &loads.head {
            out.head = head_load(
                series,
                gamma_w,
                grid,
                &active,
                &coords,
                axisymmetric,
                &mut out.notes,
            );
        }
        for block in &loads.blocks {
            if block.sides.is_empty() {
                continue;
            }
            if block.phase == LoadPhase::Liquid && !liquid {
                out.notes.push(format!(
                    "{} ({} sides): a liquid pressure acts on the liquid of two-phase materials, and none runs two-phase here; not applied",
                    block.keyword,
                    block.sides.len()
                ));
                continue;
            }
            let mut nodal: Vec<(u32, [f64; D])> = Vec::new();
            let mut skipped = Vec::new();
            for side in &block.sides {
                let Some(grid_nodes) = side
                    .corners
                    .iter()
                    .map(|n| compact.get(n).copied())
                    .collect::<Option<Vec<u32>>>()
                else {
                    skipped.push(side.line);
                    continue;
                };
                let mut at = Side::new(side, side.corners.iter().map(|&n| coords(n)).collect());
                // The elements (grid indices, ascending) that hold every corner.
                let holders: Vec<usize> = by_node
                    .get(&grid_nodes[0])
                    .map(|list| {
                        list.iter()
                            .copied()
                            .filter(|&e| {
                                grid_nodes
                                    .iter()
                                    .all(|n| grid.elements[e].corners.contains(n))
                            })
                            .collect()
                    })
                    .unwrap_or_default();
                match block.target {
                    LoadTarget::Nodes => {
                        if block.phase == LoadPhase::Liquid {
                            // Turned out of each active element that holds the
                            // side, in element order: the kernel's loops leave
                            // it pointing out of the last one.
                            for &e in holders.iter().filter(|&&e| active(e)) {
                                at.turn_out_of(grid, e, &grid_nodes, &coords);
                            }
                        }
                        let forces = at.nodal_forces(block.phase, axisymmetric);
                        for (k, f) in forces.into_iter().enumerate() {
                            nodal.push((grid_nodes[k], f));
                        }
                    }
                    LoadTarget::MaterialPoints => {
                        let applied = side
                            .values
                            .iter()
                            .any(|v| v.iter().any(|c| c.abs() > APPLIED));
                        if !applied {
                            continue;
                        }
                        let total = at.total(block.phase, axisymmetric);
                        let on = SideOnMps {
                            grid,
                            in_element: &in_element,
                            holders: &holders,
                            grid_nodes: &grid_nodes,
                        };
                        let reached = on.spread(total, |mp, f| {
                            out.on_mps.push((block.phase, block.system, mp, f));
                        });
                        if !reached {
                            skipped.push(side.line);
                        }
                    }
                }
            }
            if !skipped.is_empty() {
                let lines: Vec<String> = skipped.iter().map(u32::to_string).collect();
                out.notes.push(format!(
                    "{}: the side(s) at GOM line(s) {} reach no {} (as in Anura3D, which finds an MP load's side only across a neighbouring element in 2D); not applied",
                    block.keyword,
                    lines.join(", "),
                    if block.target == LoadTarget::Nodes { "grid node" } else { "material point" },
                ));
            }
            if !nodal.is_empty() {
                out.nodal.push((block.phase, block.system, nodal));
            }
        }
        out
    }

    /// The prescribed water level of `loads` (these loads' project) at
    /// `time`: its area and head, when one is applied.
    pub fn level(&self, loads: &ProjectLoads, time: f64) -> Option<([[f64; 2]; 3], f64)> {
        self.head.as_ref()?;
        let series = loads.head.as_ref()?;
        Some((series.area, series.at(time)))
    }

    /// Adds the loads at `time` (s), at the multipliers of `loads` (these
    /// loads' project): solid ones to `solid` (per grid node), liquid ones to
    /// `liquid`. MP loads go to the corners of each MP's element with its
    /// shape values `shape(mp)`.
    pub fn add<const NC: usize>(
        &self,
        loads: &ProjectLoads,
        time: f64,
        corners_and_shape: impl Fn(u32) -> Option<([u32; NC], [f64; NC])>,
        solid: &mut [[f64; D]],
        mut liquid: Option<&mut [[f64; D]]>,
    ) {
        for (phase, system, forces) in &self.nodal {
            let m = loads.multiplier(*phase, *system, time);
            if let Some(target) = target_of(*phase, solid, &mut liquid) {
                for (node, f) in forces {
                    for d in 0..D {
                        target[*node as usize][d] += m * f[d];
                    }
                }
            }
        }
        if let Some((forces, gamma_w)) = &self.head {
            // `UpdateMultipliersWaterForSpaceDependency`: each node's unit
            // force × its pressure −γw·(h − y) below the level (h = 0 taken
            // as 1e-6, as the kernel does), on the liquid and the mixture.
            let series = loads.head.as_ref().expect("a head with its series");
            let mut h = series.at(time);
            // γw = ρw·g × the gravity multiplier (`ComputeWaterSpecificWeight`).
            let gamma_w = gamma_w * loads.gravity_at(time);
            if h == 0.0 {
                h = 1e-6;
            }
            for (node, f, y) in forces {
                let p = if *y <= h { -gamma_w * (h - y) } else { 0.0 };
                for d in 0..D {
                    solid[*node as usize][d] += p * f[d];
                    if let Some(l) = liquid.as_deref_mut() {
                        l[*node as usize][d] += p * f[d];
                    }
                }
            }
        }
        for (phase, system, mp, f) in &self.on_mps {
            let Some((corners, shape)) = corners_and_shape(*mp) else {
                continue;
            };
            let m = loads.multiplier(*phase, *system, time);
            if let Some(target) = target_of(*phase, solid, &mut liquid) {
                for i in 0..NC {
                    for d in 0..D {
                        target[corners[i] as usize][d] += m * shape[i] * f[d];
                    }
                }
            }
        }
    }
}

/// Where a load of `phase` goes: the solid's (mixture's) nodal forces, or
/// the liquid's when there is a liquid.
fn target_of<'a, const D: usize>(
    phase: LoadPhase,
    solid: &'a mut [[f64; D]],
    liquid: &'a mut Option<&mut [[f64; D]]>,
) -> Option<&'a mut [[f64; D]]> {
    match phase {
        LoadPhase::Solid => Some(solid),
        LoadPhase::Liquid => liquid.as_deref_mut(),
    }
}

/// The free-surface sides of the water level: per active element (in order)
/// each side whose neighbour exists and holds no MP (the kernel's
/// `BoundaryElementSurface` = 1; a side on the mesh's edge is not one) and
/// whose corners all lie in `area`; with the element and the side's grid
/// nodes (`GetAndUpdateHydraulicHeadLoad`).
fn head_sides<const D: usize, const NC: usize>(
    grid: &Grid<D, NC>,
    active: &dyn Fn(usize) -> bool,
    coords: &dyn Fn(u32) -> [f64; D],
    area: &[[f64; 2]; 3],
) -> Vec<(usize, Vec<u32>)> {
    let inside = |node: u32| {
        let x = coords(grid.mesh_node[node as usize]);
        (0..D).all(|d| x[d] >= area[d][0] && x[d] <= area[d][1])
    };
    let mut sides = Vec::new();
    for (e, el) in grid.elements.iter().enumerate() {
        if !active(e) {
            continue;
        }
        for local in side_corners(D) {
            let opposite = (0..NC)
                .find(|k| !local.contains(k))
                .expect("a corner off the side");
            let across = grid.neighbours[e][opposite];
            if across == NO_ELEMENT || active(across as usize) {
                continue;
            }
            let nodes: Vec<u32> = local.iter().map(|&k| el.corners[k]).collect();
            if nodes.iter().all(|&n| inside(n)) {
                sides.push((e, nodes));
            }
        }
    }
    sides
}

/// The kernel's side number (1-based) of the side with corners `nodes` in
/// grid element `e`, or `None`. In 2D the kernel finds it only across a
/// neighbouring element (`DetermineElementSideSurface`).
fn element_side<const D: usize, const NC: usize>(
    grid: &Grid<D, NC>,
    e: usize,
    nodes: &[u32],
) -> Option<usize> {
    let el = &grid.elements[e];
    side_corners(D).iter().enumerate().find_map(|(s, local)| {
        let same = local.iter().all(|&k| nodes.contains(&el.corners[k]));
        if !same {
            return None;
        }
        if D == 2 {
            // The corner opposite the side indexes its neighbour.
            let opposite = (0..NC).find(|k| !local.contains(k))?;
            if grid.neighbours[e][opposite] == NO_ELEMENT {
                return None;
            }
        }
        Some(s + 1)
    })
}

/// One loaded side where the run places it: its load, corner coordinates,
/// unit normal (turned as the caller decided) and measure.
struct Side<'a, const D: usize> {
    load: &'a SideLoad,
    x: Vec<[f64; D]>,
    normal: [f64; D],
    measure: f64,
}

impl<'a, const D: usize> Side<'a, D> {
    /// The side `load` at the corner coordinates `x`, with the normal its
    /// node order gives ([`side_geometry`]).
    fn new(load: &'a SideLoad, x: Vec<[f64; D]>) -> Side<'a, D> {
        let (normal, measure) = side_geometry(&x);
        Side {
            load,
            x,
            normal,
            measure,
        }
    }

    /// Turns the normal out of grid element `e`, which holds the side's grid
    /// nodes `nodes`, as the kernel's `Load2D`/`Load3D` do: against the first
    /// of its other corners that is off the side's line or plane.
    fn turn_out_of<const NC: usize>(
        &mut self,
        grid: &Grid<D, NC>,
        e: usize,
        nodes: &[u32],
        coords: &dyn Fn(u32) -> [f64; D],
    ) {
        for &c in &grid.elements[e].corners {
            if nodes.contains(&c) {
                continue;
            }
            let other = coords(grid.mesh_node[c as usize]);
            let dot: f64 = (0..D)
                .map(|d| (other[d] - self.x[0][d]) * self.normal[d])
                .sum();
            if dot > 0.0 {
                self.normal.iter_mut().for_each(|v| *v = -*v);
                return;
            } else if dot < 0.0 {
                return;
            }
        }
    }

    /// Consistent nodal forces of one side at multiplier 1 (`Load2D`/`Load3D`
    /// with one integration point).
    fn nodal_forces(&self, phase: LoadPhase, axisymmetric: bool) -> Vec<[f64; D]> {
        let (side, x, normal, measure) = (self.load, &self.x, self.normal, self.measure);
        let n = x.len();
        let traction = |k: usize| {
            let mut t = [0.0; D];
            for d in 0..D {
                t[d] = match phase {
                    LoadPhase::Solid => side.values[k][d],
                    LoadPhase::Liquid => side.values[k][0] * normal[d],
                };
            }
            t
        };
        let radius = |k: usize| if axisymmetric { x[k][0] } else { 1.0 };
        let mut mean = [0.0; D];
        for k in 0..n {
            let t = traction(k);
            for d in 0..D {
                mean[d] += t[d] * radius(k) / n as f64;
            }
        }
        let mut forces = vec![[0.0; D]; n];
        for k in 0..n {
            for d in 0..D {
                forces[k][d] = measure / n as f64 * mean[d];
            }
        }
        if axisymmetric && let Some(on_axis) = (0..n).find(|&k| x[k][0] < 1e-60) {
            // `Load2D`: the corner on the axis gives 7/8 of its share to the other.
            let moved = forces[on_axis];
            for k in 0..n {
                for d in 0..D {
                    let shift = moved[d] / (n - 1) as f64 * (7.0 / 8.0);
                    if x[k][0] < 1e-60 {
                        forces[k][d] -= shift;
                    } else {
                        forces[k][d] += shift;
                    }
                }
            }
        }
        forces
    }

    /// The total force of an MP load's side at multiplier 1
    /// (`DetermineLoadPerParticle` × the number of loaded MPs).
    fn total(&self, phase: LoadPhase, axisymmetric: bool) -> [f64; D] {
        let (side, x, normal, measure) = (self.load, &self.x, self.normal, self.measure);
        let n = x.len();
        let mut total = [0.0; D];
        for k in 0..n {
            let radius = if axisymmetric { x[k][0] } else { 1.0 };
            for d in 0..D {
                let v = match phase {
                    LoadPhase::Solid => side.values[k][d],
                    LoadPhase::Liquid => side.values[k][d] * normal[d],
                };
                total[d] += v * radius / n as f64 * measure;
            }
        }
        total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_cover_every_count_and_side() {
        for &count in &[1, 3, 6, 12, 16, 25, 46, 88] {
            for side in 1..=3 {
                let t = adjacent_mps(2, count, side).unwrap();
                assert!(t.iter().all(|&k| k >= 1 && k as usize <= count));
            }
        }
        for &count in &[1, 4, 7, 8, 10, 13, 20] {
            for side in 1..=4 {
                let t = adjacent_mps(3, count, side).unwrap();
                assert!(t.iter().all(|&k| k >= 1 && k as usize <= count));
            }
        }
        assert!(adjacent_mps(2, 5, 1).is_none());
    }

    #[test]
    fn a_uniform_traction_splits_evenly_and_sums_to_its_resultant() {
        let side = SideLoad {
            corners: vec![0, 1],
            values: vec![[0.0, -20.0, 0.0], [0.0, -20.0, 0.0]],
            line: 1,
        };
        let x = vec![[0.0, 1.0], [0.1, 1.0]];
        let f = Side::new(&side, x.clone()).nodal_forces(LoadPhase::Solid, false);
        assert!((f[0][1] + 1.0).abs() < 1e-12 && (f[1][1] + 1.0).abs() < 1e-12);
        // A liquid pressure acts along the normal only: −10 kPa on the left
        // normal (0, 1) of 0 → 1.
        let side = SideLoad {
            values: vec![[-10.0, 99.0, 0.0], [-10.0, 99.0, 0.0]],
            ..side
        };
        let f = Side::new(&side, x).nodal_forces(LoadPhase::Liquid, false);
        assert!(f[0][0].abs() < 1e-12 && (f[0][1] + 0.5).abs() < 1e-12);
    }

    #[test]
    fn a_face_load_in_3d_uses_the_face_area() {
        let side = SideLoad {
            corners: vec![0, 1, 2],
            values: vec![[0.0, -3.0, 0.0]; 3],
            line: 1,
        };
        let face = Side::new(
            &side,
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
        );
        assert!((face.measure - 0.5).abs() < 1e-12);
        assert!((face.normal[1] + 1.0).abs() < 1e-12);
        let f = face.nodal_forces(LoadPhase::Solid, false);
        let total: f64 = f.iter().map(|v| v[1]).sum();
        assert!((total + 1.5).abs() < 1e-12);
    }
}
