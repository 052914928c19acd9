//! The background grid of the MPM check: the Anura3D mesh itself, fixed in
//! space, reduced to what the solver needs.
//!
//! Only the corner nodes of each element carry degrees of freedom (the six
//! mid-edge nodes of `tetrahedral_old` never enter the shape functions), so the
//! grid renumbers the corner nodes compactly in order of first appearance and
//! keeps the map back to mesh node indices. Per element it stores the compact
//! corner indices, the affine shape functions its element type gives
//! ([`Element::affine`], a [`Simplex`]) and the neighbour
//! across each face; a uniform spatial hash over element bounding boxes backs
//! up the neighbour walk when a material point has to be located from scratch.
//! In 2D axisymmetry the axis nodes are fixed radially ([`Grid::fix_axis`]).
//! This file does no physics and no I/O.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

use std::collections::HashMap;

use super::MpmError;
use a3d_element::{Element, Simplex};
use a3d_model::Mesh;

/// Marker for "no neighbour" (a boundary face).
pub const NO_ELEMENT: u32 = u32::MAX;

/// Barycentric tolerance for "inside an element": a point whose smallest shape
/// function value is ≥ −1e-10 belongs to the element.
pub const INSIDE_TOLERANCE: f64 = 1e-10;

/// One element of the grid.
#[derive(Clone, Copy, Debug)]
pub struct GridElement<const D: usize, const NC: usize> {
    /// Compact node indices of the corners.
    pub corners: [u32; NC],
    pub shape: Simplex<D, NC>,
}

/// The background grid: elements, compact nodes, fixities, neighbours and a
/// spatial hash for point location.
#[derive(Clone, Debug)]
pub struct Grid<const D: usize, const NC: usize> {
    pub elements: Vec<GridElement<D, NC>>,
    /// Mesh node index (0-based) of every compact node.
    pub mesh_node: Vec<u32>,
    /// Per compact node: directions fixed for the solid phase.
    pub fixed: Vec<[bool; D]>,
    /// Per element: the element across the face opposite each corner.
    pub neighbours: Vec<[u32; NC]>,
    hash: SpatialHash<D>,
}

impl<const D: usize, const NC: usize> Grid<D, NC> {
    /// Builds the grid from a mesh of element type `E`, which must be
    /// [`Element::AFFINE`]. `fixity` is the per-mesh-node solid fixity.
    pub fn new<E: Element<D, NC>>(
        mesh: &Mesh,
        fixity: &[[bool; 3]],
    ) -> Result<Grid<D, NC>, MpmError> {
        let n_elements = mesh.n_elements();
        let n_mesh_nodes = mesh.n_nodes();
        if n_elements == 0 {
            return Err(MpmError::InvalidMesh("the mesh has no elements".into()));
        }
        if mesh.element_type != E::TYPE || !E::AFFINE {
            return Err(MpmError::InvalidMesh(format!(
                "element type {} is not {} or has no affine shape functions",
                mesh.element_type.gom_name(),
                E::TYPE.gom_name()
            )));
        }
        if fixity.len() != n_mesh_nodes {
            return Err(MpmError::InvalidMesh(format!(
                "{} fixity entries for {n_mesh_nodes} nodes",
                fixity.len()
            )));
        }
        let mut compact = vec![NO_ELEMENT; n_mesh_nodes];
        let mut mesh_node = Vec::new();
        let mut elements = Vec::with_capacity(n_elements);
        for e in 0..n_elements {
            let ids = mesh.element_nodes(e);
            if let Some(&bad) = ids.iter().find(|&&n| n as usize >= n_mesh_nodes) {
                return Err(MpmError::InvalidMesh(format!(
                    "element {} refers to node {} but the mesh has {n_mesh_nodes} nodes",
                    e + 1,
                    bad as u64 + 1
                )));
            }
            let mut corners = [0u32; NC];
            let mut coords = [[0.0; D]; NC];
            for k in 0..NC {
                let node = ids[k] as usize;
                if compact[node] == NO_ELEMENT {
                    compact[node] = mesh_node.len() as u32;
                    mesh_node.push(node as u32);
                }
                corners[k] = compact[node];
                for d in 0..D {
                    coords[k][d] = mesh.nodes[node][d];
                }
            }
            let shape = E::affine(&coords).ok_or(MpmError::DegenerateElement {
                element: e as u64 + 1,
            })?;
            elements.push(GridElement { corners, shape });
        }
        let fixed = mesh_node
            .iter()
            .map(|&n| {
                let mut f = [false; D];
                f.copy_from_slice(&fixity[n as usize][..D]);
                f
            })
            .collect();
        let neighbours = face_neighbours(&elements);
        let hash = SpatialHash::new(mesh, &elements, &mesh_node);
        Ok(Grid {
            elements,
            mesh_node,
            fixed,
            neighbours,
            hash,
        })
    }

    /// 2D axisymmetry: fixes the radial direction (x) of every node on the
    /// axis x = 0 (within 1e-9 of the mesh's x-extent), where u_r = 0 by
    /// symmetry. Anura3D models fix these nodes in the GOM already; this makes
    /// the runner safe for meshes that do not. Returns how many nodes were
    /// newly fixed.
    pub fn fix_axis(&mut self, mesh: &Mesh) -> usize {
        let extent = self
            .mesh_node
            .iter()
            .map(|&n| mesh.nodes[n as usize][0].abs())
            .fold(0.0, f64::max);
        let tolerance = 1e-9 * extent.max(f64::MIN_POSITIVE);
        let mut count = 0;
        for (fixed, &n) in self.fixed.iter_mut().zip(&self.mesh_node) {
            if mesh.nodes[n as usize][0].abs() <= tolerance && !fixed[0] {
                fixed[0] = true;
                count += 1;
            }
        }
        count
    }

    /// Mesh node index (0-based) → compact node, for the nodes elements use.
    pub fn compact_nodes(&self) -> HashMap<u32, u32> {
        self.mesh_node
            .iter()
            .enumerate()
            .map(|(c, &n)| (n, c as u32))
            .collect()
    }

    /// Ties mesh nodes together: in every pair (primary, secondary), 0-based
    /// mesh node indices, the secondary node's corners are redirected to the
    /// primary node, so both share one set of degrees of freedom (a periodic
    /// boundary). The element shapes keep their own coordinates; fixities are
    /// combined. Chains (a ← b ← c) resolve to their first node. An element
    /// that would then use one node twice, or a node that is not an element
    /// corner, is an error. Face neighbours are not joined: a material point
    /// that crosses a tied boundary leaves the mesh.
    pub fn tie(&mut self, pairs: &[(u32, u32)]) -> Result<(), MpmError> {
        if pairs.is_empty() {
            return Ok(());
        }
        let compact = self.compact_nodes();
        let lookup = |n: u32| {
            compact.get(&n).copied().ok_or_else(|| {
                MpmError::InvalidMesh(format!(
                    "tied node {} is not an element corner",
                    n as u64 + 1
                ))
            })
        };
        let mut target: Vec<u32> = (0..self.mesh_node.len() as u32).collect();
        for &(primary, secondary) in pairs {
            let (p, s) = (lookup(primary)?, lookup(secondary)?);
            target[s as usize] = p;
        }
        // Resolve chains; a cycle longer than the node count is an error.
        let n = target.len();
        let mut resolved = target.clone();
        for (c, slot) in resolved.iter_mut().enumerate() {
            let mut r = c as u32;
            for _ in 0..=n {
                if target[r as usize] == r {
                    break;
                }
                r = target[r as usize];
            }
            if target[r as usize] != r {
                return Err(MpmError::InvalidMesh("tied nodes form a cycle".into()));
            }
            *slot = r;
        }
        for c in 0..n {
            let r = resolved[c] as usize;
            if r != c {
                for d in 0..D {
                    let fixed = self.fixed[c][d];
                    self.fixed[r][d] |= fixed;
                }
            }
        }
        for (e, element) in self.elements.iter_mut().enumerate() {
            for k in 0..NC {
                element.corners[k] = resolved[element.corners[k] as usize];
            }
            for a in 0..NC {
                for b in a + 1..NC {
                    if element.corners[a] == element.corners[b] {
                        return Err(MpmError::InvalidMesh(format!(
                            "element {} would use one node twice after tying",
                            e + 1
                        )));
                    }
                }
            }
        }
        Ok(())
    }

    pub fn n_nodes(&self) -> usize {
        self.mesh_node.len()
    }

    /// Smallest element altitude: the characteristic length of the time step.
    pub fn min_altitude(&self) -> f64 {
        self.elements
            .iter()
            .map(|e| e.shape.min_altitude())
            .fold(f64::INFINITY, f64::min)
    }

    /// True when `x` lies in element `e` (within [`INSIDE_TOLERANCE`]).
    #[inline]
    pub fn contains(&self, e: u32, x: &[f64; D]) -> bool {
        let n = self.elements[e as usize].shape.values(x);
        n.iter().all(|&v| v >= -INSIDE_TOLERANCE)
    }

    /// Finds the element containing `x`, starting from element `start`: walk
    /// towards the face with the most negative shape function, then fall back
    /// to the spatial hash. `None` when `x` is outside the mesh.
    pub fn locate(&self, x: &[f64; D], start: u32) -> Option<u32> {
        let mut e = start;
        if (e as usize) < self.elements.len() {
            for _ in 0..64 {
                let n = self.elements[e as usize].shape.values(x);
                let mut worst = 0;
                for k in 1..NC {
                    if n[k] < n[worst] {
                        worst = k;
                    }
                }
                if n[worst] >= -INSIDE_TOLERANCE {
                    return Some(e);
                }
                let next = self.neighbours[e as usize][worst];
                if next == NO_ELEMENT {
                    break;
                }
                e = next;
            }
        }
        self.search(x)
    }

    /// Point location through the spatial hash: among the elements listed in
    /// the cell of `x`, the first one with the largest smallest shape
    /// function, if that is inside.
    pub fn search(&self, x: &[f64; D]) -> Option<u32> {
        let cell = self.hash.cell_of(x)?;
        let mut best: Option<(u32, f64)> = None;
        for &e in self.hash.items_in(cell) {
            let n = self.elements[e as usize].shape.values(x);
            let low = n.iter().copied().fold(f64::INFINITY, f64::min);
            if best.is_none_or(|(_, b)| low > b) {
                best = Some((e, low));
            }
        }
        match best {
            Some((e, low)) if low >= -INSIDE_TOLERANCE => Some(e),
            _ => None,
        }
    }
}

/// For every element and corner k, the element sharing the face opposite k.
fn face_neighbours<const D: usize, const NC: usize>(
    elements: &[GridElement<D, NC>],
) -> Vec<[u32; NC]> {
    let mut faces: HashMap<[u32; D], (u32, usize)> = HashMap::with_capacity(elements.len() * NC);
    let mut neighbours = vec![[NO_ELEMENT; NC]; elements.len()];
    for (e, element) in elements.iter().enumerate() {
        for k in 0..NC {
            let mut face = [0u32; D];
            let mut slot = 0;
            for j in 0..NC {
                if j != k {
                    face[slot] = element.corners[j];
                    slot += 1;
                }
            }
            face.sort_unstable();
            match faces.remove(&face) {
                Some((other, other_k)) => {
                    neighbours[e][k] = other;
                    neighbours[other as usize][other_k] = e as u32;
                }
                None => {
                    faces.insert(face, (e as u32, k));
                }
            }
        }
    }
    neighbours
}

/// A uniform grid of cells over the mesh bounding box; each cell lists the
/// elements whose bounding box overlaps it (compressed row storage).
#[derive(Clone, Debug)]
struct SpatialHash<const D: usize> {
    low: [f64; D],
    cell_size: f64,
    cells: [usize; D],
    start: Vec<u32>,
    items: Vec<u32>,
}

impl<const D: usize> SpatialHash<D> {
    fn new<const NC: usize>(
        mesh: &Mesh,
        elements: &[GridElement<D, NC>],
        mesh_node: &[u32],
    ) -> Self {
        let mut low = [f64::INFINITY; D];
        let mut high = [f64::NEG_INFINITY; D];
        for &n in mesh_node {
            for d in 0..D {
                low[d] = low[d].min(mesh.nodes[n as usize][d]);
                high[d] = high[d].max(mesh.nodes[n as usize][d]);
            }
        }
        // Cells about the size of an average element, at most ~2 per element.
        let mut extent = 1.0;
        for d in 0..D {
            extent *= (high[d] - low[d]).max(f64::MIN_POSITIVE);
        }
        let mut cell_size = (extent / elements.len() as f64).powf(1.0 / D as f64);
        // At most the largest double (nodes at ±1e308 are an infinite side apart).
        let side = |d: usize| (high[d] - low[d]).min(f64::MAX);
        let largest_side = (0..D).map(side).fold(0.0, f64::max);
        if !(cell_size > 0.0 && cell_size.is_finite()) {
            cell_size = largest_side.max(1.0);
        }
        // Guard against very flat boxes: never more than 8·n cells along an axis.
        cell_size = cell_size.max(largest_side / (8.0 * elements.len() as f64));
        // Element boxes in cells, and the cells per axis for a cell size.
        let sized = |cell_size: f64| {
            let mut cells = [1usize; D];
            for d in 0..D {
                cells[d] = ((side(d) / cell_size).floor() as usize + 1).max(1);
            }
            cells
        };
        let boxes = |cell_size: f64, cells: [usize; D], element: &GridElement<D, NC>| {
            let mut lo = [usize::MAX; D];
            let mut hi = [0usize; D];
            for &c in &element.corners {
                let p = mesh.nodes[mesh_node[c as usize] as usize];
                for d in 0..D {
                    let i =
                        (((p[d] - low[d]) / cell_size).floor().max(0.0) as usize).min(cells[d] - 1);
                    lo[d] = lo[d].min(i);
                    hi[d] = hi[d].max(i);
                }
            }
            (lo, hi)
        };
        // No more entries than a budget proportional to the elements (elements
        // that span many cells: one node far from the rest): memory O(elements)
        // whatever the coordinates. An ordinary mesh stays well below.
        let budget = 32 * elements.len() as u64 + 1024;
        let mut cells = sized(cell_size);
        loop {
            let entries: u64 = elements
                .iter()
                .map(|e| {
                    let (lo, hi) = boxes(cell_size, cells, e);
                    (0..D).fold(1u64, |a, d| a.saturating_mul((hi[d] - lo[d] + 1) as u64))
                })
                .fold(0u64, u64::saturating_add);
            if entries <= budget || cells.iter().all(|&c| c == 1) {
                break;
            }
            cell_size *= 2.0;
            cells = sized(cell_size);
        }
        let n_cells: usize = cells.iter().product();
        let bounds = |element: &GridElement<D, NC>| boxes(cell_size, cells, element);
        let for_each_cell = |lo: [usize; D], hi: [usize; D], f: &mut dyn FnMut(usize)| {
            let mut idx = lo;
            loop {
                let mut flat = 0;
                for d in (0..D).rev() {
                    flat = flat * cells[d] + idx[d];
                }
                f(flat);
                let mut d = 0;
                loop {
                    if d == D {
                        return;
                    }
                    if idx[d] < hi[d] {
                        idx[d] += 1;
                        break;
                    }
                    idx[d] = lo[d];
                    d += 1;
                }
            }
        };
        let mut count = vec![0u32; n_cells + 1];
        for element in elements {
            let (lo, hi) = bounds(element);
            for_each_cell(lo, hi, &mut |c| count[c + 1] += 1);
        }
        for c in 0..n_cells {
            count[c + 1] += count[c];
        }
        let start = count.clone();
        let mut fill = count;
        let mut items = vec![0u32; start[n_cells] as usize];
        for (e, element) in elements.iter().enumerate() {
            let (lo, hi) = bounds(element);
            for_each_cell(lo, hi, &mut |c| {
                items[fill[c] as usize] = e as u32;
                fill[c] += 1;
            });
        }
        SpatialHash {
            low,
            cell_size,
            cells,
            start,
            items,
        }
    }

    fn cell_of(&self, x: &[f64; D]) -> Option<usize> {
        let mut flat = 0;
        for d in (0..D).rev() {
            let f = (x[d] - self.low[d]) / self.cell_size;
            // Points a hair outside the box still map to the border cell.
            let slack = 1e-9;
            if !(f >= -slack && f < self.cells[d] as f64 + slack) {
                return None;
            }
            let i = (f.floor().max(0.0) as usize).min(self.cells[d] - 1);
            flat = flat * self.cells[d] + i;
        }
        Some(flat)
    }

    fn items_in(&self, cell: usize) -> &[u32] {
        &self.items[self.start[cell] as usize..self.start[cell + 1] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use a3d_element::{TetOld, Tri3};
    use a3d_testkit::{column_tet, column_tri3, elastic_material};
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Brute force: every element that contains `x`.
    fn containing<const D: usize, const NC: usize>(grid: &Grid<D, NC>, x: &[f64; D]) -> Vec<u32> {
        (0..grid.elements.len() as u32)
            .filter(|&e| grid.contains(e, x))
            .collect()
    }

    fn check_locate<const D: usize, const NC: usize>(
        grid: &Grid<D, NC>,
        low: [f64; D],
        high: [f64; D],
        seed: u64,
    ) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        for _ in 0..2000 {
            let mut x = [0.0; D];
            for d in 0..D {
                // Up to 10 % outside the box on each side.
                let span = high[d] - low[d];
                x[d] = low[d] - 0.1 * span + 1.2 * span * rng.random::<f64>();
            }
            let start = rng.random_range(0..grid.elements.len() as u32);
            let truth = containing(grid, &x);
            match grid.locate(&x, start) {
                Some(e) => assert!(
                    truth.contains(&e),
                    "seed {seed}: {x:?} located in {e}, truth {truth:?}"
                ),
                None => assert!(
                    truth.is_empty(),
                    "seed {seed}: {x:?} not located, truth {truth:?}"
                ),
            }
            match grid.search(&x) {
                Some(e) => assert!(truth.contains(&e)),
                None => assert!(truth.is_empty()),
            }
        }
    }

    #[test]
    fn locate_agrees_with_brute_force_2d() {
        let model = column_tri3(3.0, 2.0, 6, 4, elastic_material(1e4, 0.3, 2650.0, 0.3));
        let grid = Grid::<2, 3>::new::<Tri3>(&model.mesh, &model.solid_fixity).expect("valid mesh");
        check_locate(&grid, [0.0, 0.0], [3.0, 2.0], 7);
    }

    #[test]
    fn locate_agrees_with_brute_force_3d() {
        let model = column_tet(
            1.0,
            2.0,
            1.5,
            2,
            4,
            3,
            elastic_material(1e4, 0.3, 2650.0, 0.3),
        );
        let grid =
            Grid::<3, 4>::new::<TetOld>(&model.mesh, &model.solid_fixity).expect("valid mesh");
        check_locate(&grid, [0.0, 0.0, 0.0], [1.0, 2.0, 1.5], 11);
        // Only the 4 corners of each 10-node element carry degrees of freedom.
        let corner_nodes = (3 * 5 * 4) as usize;
        assert_eq!(grid.n_nodes(), corner_nodes);
        // Interior faces have a neighbour on each side, consistently.
        for (e, neighbours) in grid.neighbours.iter().enumerate() {
            for &n in neighbours.iter().filter(|&&n| n != NO_ELEMENT) {
                assert!(grid.neighbours[n as usize].contains(&(e as u32)));
            }
        }
    }

    #[test]
    fn axis_nodes_are_fixed_radially() {
        let mut model = column_tri3(2.0, 1.0, 2, 1, elastic_material(1e4, 0.3, 2650.0, 0.3));
        for f in &mut model.solid_fixity {
            *f = [false; 3];
        }
        let mut grid =
            Grid::<2, 3>::new::<Tri3>(&model.mesh, &model.solid_fixity).expect("valid mesh");
        assert_eq!(grid.fix_axis(&model.mesh), 2);
        for (node, fixed) in grid.mesh_node.iter().zip(&grid.fixed) {
            let x = model.mesh.nodes[*node as usize][0];
            assert_eq!(fixed[0], x == 0.0, "node at x = {x}");
            assert!(!fixed[1]);
        }
        assert_eq!(grid.fix_axis(&model.mesh), 0);
    }

    #[test]
    fn out_of_range_nodes_and_degenerate_elements_are_errors() {
        let mut model = column_tri3(1.0, 1.0, 1, 1, elastic_material(1e4, 0.3, 2650.0, 0.3));
        model.mesh.connectivity[2] = 99;
        assert!(matches!(
            Grid::<2, 3>::new::<Tri3>(&model.mesh, &model.solid_fixity),
            Err(MpmError::InvalidMesh(_))
        ));
        model.mesh.connectivity[2] = model.mesh.connectivity[1];
        assert!(matches!(
            Grid::<2, 3>::new::<Tri3>(&model.mesh, &model.solid_fixity),
            Err(MpmError::DegenerateElement { element: 1 })
        ));
    }

    /// A fan of triangles sharing one apex far from the rest spans every
    /// cell of the spatial hash along x; its entries (were elements × 8·
    /// elements, 32 million here) stay within a budget proportional to the
    /// elements, and location still agrees with the brute force.
    #[test]
    fn spatial_hash_memory_is_bounded_by_the_elements() {
        let n = 2000usize;
        let mut nodes = vec![[1e6, 0.5, 0.0]];
        nodes.extend((0..=n).map(|k| [0.0, k as f64 / n as f64, 0.0]));
        let mut connectivity = Vec::new();
        for k in 0..n as u32 {
            // Counter-clockwise: the base edge upwards on x = 0, apex at +x.
            connectivity.extend_from_slice(&[k + 1, 0, k + 2]);
        }
        let mesh = Mesh {
            dimension: a3d_model::Dimension::PlaneStrain,
            element_type: a3d_model::ElementType::Tri3,
            nodes,
            connectivity,
        };
        let fixity = vec![[false; 3]; mesh.n_nodes()];
        let grid = Grid::<2, 3>::new::<Tri3>(&mesh, &fixity).expect("valid mesh");
        assert!(
            grid.hash.items.len() <= 32 * n + 1024,
            "{}",
            grid.hash.items.len()
        );
        for x in [[1.0, 0.5], [5e5, 0.5], [-1.0, 0.5], [1.0, 0.25]] {
            let truth = containing(&grid, &x);
            match grid.search(&x) {
                Some(e) => assert!(truth.contains(&e), "{x:?}"),
                None => assert!(truth.is_empty(), "{x:?}"),
            }
        }
    }
}
