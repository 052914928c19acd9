//! The fill-reducing ordering of large 3D systems: nested dissection of the
//! mesh's nodes by their coordinates. The nodes are split at the median
//! along each axis in turn, the nodes level with the median kept on one
//! side (a plane of nodes is never cut in two); the nodes of the lower part
//! that touch the upper one form that axis's separator, and the axis with
//! the smallest separator is taken. The separator is numbered after both
//! parts, which are split the same way in turn down to parts of [`LEAF`]
//! nodes, each ordered by faer's AMD on its own graph. The separators are
//! planes, so the fill they cause grows more slowly with the mesh than the
//! minimum degree's alone.
//!
//! Chosen by measurement (`a3d-bench equilibrium`, README *Performance*):
//! on the generated 3D slopes (tetrahedral_old) it keeps 18 % fewer entries
//! in L than the widest-axis dissection it replaced at 3.0×10⁴ unknowns,
//! 16 % at 6.5×10⁴ and 15 % at 1.3×10⁵ (and that one 15–29 % fewer than
//! AMD); in 2D (TRI3) AMD keeps less fill, and on small regular lattices
//! too, so 2D systems and small ones keep AMD (and their solutions keep
//! their bits).
//!
//! Deterministic: the split sorts by (coordinate, node), nothing depends on
//! threads.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;

/// Free unknowns from which the nested dissection replaces AMD (3D only).
pub(super) const DISSECTION_FROM: usize = 25_000;

/// Nodes below which a part is not split further (ordered by AMD instead;
/// 32–256 keep about as much fill, 1024 6 % more).
const LEAF: usize = 64;

/// The order in which to eliminate the free unknowns: `order[k]` is the
/// free number eliminated k-th. `positions[node]` are the node coordinates
/// (the first `dim` used), `adjacency` the nodes' neighbours (compressed
/// rows: `adjacency.0` the row starts, `adjacency.1` the neighbours),
/// `dof[node * dim + i]` the free number of each direction or
/// `constrained` (the marker of a direction not solved for).
pub(super) fn nested_dissection(
    positions: &[[f64; 3]],
    dim: usize,
    adjacency: (&[usize], &[u32]),
    (dof, constrained, n_free): (&[u32], u32, usize),
) -> Vec<usize> {
    let n_nodes = positions.len();
    let free = |node: usize| {
        dof[node * dim..(node + 1) * dim]
            .iter()
            .any(|&f| f != constrained)
    };
    let nodes: Vec<u32> = (0..n_nodes as u32).filter(|&n| free(n as usize)).collect();
    let mut state = Dissection {
        positions,
        dim,
        adjacency,
        local: vec![u32::MAX; n_nodes],
        label: vec![0; n_nodes],
        next_label: 0,
        order: Vec::with_capacity(nodes.len()),
    };
    state.dissect(nodes);
    let mut out = Vec::with_capacity(n_free);
    for node in state.order {
        let node = node as usize;
        out.extend(
            dof[node * dim..(node + 1) * dim]
                .iter()
                .filter(|&&f| f != constrained)
                .map(|&f| f as usize),
        );
    }
    out
}

struct Dissection<'a> {
    positions: &'a [[f64; 3]],
    dim: usize,
    adjacency: (&'a [usize], &'a [u32]),
    /// Per node, its index within the leaf being ordered (`u32::MAX`
    /// outside it).
    local: Vec<u32>,
    /// Per node, the label of the part it was last put in.
    label: Vec<u32>,
    next_label: u32,
    /// The nodes in elimination order.
    order: Vec<u32>,
}

impl Dissection<'_> {
    fn dissect(&mut self, mut nodes: Vec<u32>) {
        if nodes.len() <= LEAF {
            nodes.sort_unstable();
            self.leaf(&nodes);
            return;
        }
        // The smallest separator among the splits that leave each side a
        // quarter of the nodes or more (ties in the coordinates can leave
        // less); where none does, the most even split. The recursion then
        // stays O(log n) deep.
        let n = nodes.len();
        let mut best: Option<(Vec<u32>, Vec<u32>, Vec<u32>)> = None;
        let score = |(separator, lower, upper): &(Vec<u32>, Vec<u32>, Vec<u32>)| {
            let smaller = (separator.len() + lower.len()).min(upper.len());
            if 4 * smaller >= n {
                (0, separator.len())
            } else {
                (1, n - smaller)
            }
        };
        for axis in 0..self.dim {
            let split = self.split(nodes.clone(), axis);
            if best.as_ref().is_none_or(|b| score(&split) < score(b)) {
                best = Some(split);
            }
        }
        let Some((separator, lower, upper)) = best else {
            // No axis (never for 2 or 3): the part as one leaf.
            nodes.sort_unstable();
            self.leaf(&nodes);
            return;
        };
        self.dissect(lower);
        self.dissect(upper);
        let mut separator = separator;
        separator.sort_unstable();
        self.order.extend(separator);
    }

    /// Splits `nodes` at the median along `axis`: (separator, lower, upper).
    fn split(&mut self, mut nodes: Vec<u32>, axis: usize) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
        let positions = self.positions;
        let mid = nodes.len() / 2;
        nodes.select_nth_unstable_by(mid, |&a, &b| {
            positions[a as usize][axis]
                .total_cmp(&positions[b as usize][axis])
                .then(a.cmp(&b))
        });
        // The nodes level with the median go to one side together, so that
        // a plane of nodes is not cut in two: to the upper side, or, where
        // the median is the lowest level, to the lower one.
        // Where neither leaves both sides some nodes (all level, or a
        // coordinate that is not a number), the split by index.
        let level = positions[nodes[mid] as usize][axis];
        let parts = two_sides(&nodes, |n| positions[n as usize][axis] < level)
            .or_else(|| two_sides(&nodes, |n| positions[n as usize][axis] <= level));
        let (lower, upper) = match parts {
            Some(parts) => parts,
            None => {
                let upper = nodes.split_off(mid);
                (nodes, upper)
            }
        };
        self.next_label += 1;
        let upper_label = self.next_label;
        for &n in &upper {
            self.label[n as usize] = upper_label;
        }
        let (starts, neighbours) = self.adjacency;
        let (separator, lower): (Vec<u32>, Vec<u32>) = lower.into_iter().partition(|&n| {
            let n = n as usize;
            neighbours[starts[n]..starts[n + 1]]
                .iter()
                .any(|&m| self.label[m as usize] == upper_label)
        });
        (separator, lower, upper)
    }

    /// Orders a leaf (`nodes` sorted) by faer's AMD on the graph its nodes
    /// span.
    fn leaf(&mut self, nodes: &[u32]) {
        for (k, &n) in nodes.iter().enumerate() {
            self.local[n as usize] = k as u32;
        }
        let (starts, neighbours) = self.adjacency;
        let mut col_ptr = Vec::with_capacity(nodes.len() + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0usize);
        for &n in nodes {
            let n = n as usize;
            let first = row_idx.len();
            row_idx.extend(
                neighbours[starts[n]..starts[n + 1]]
                    .iter()
                    .map(|&m| self.local[m as usize])
                    .filter(|&k| k != u32::MAX)
                    .map(|k| k as usize),
            );
            row_idx[first..].sort_unstable();
            col_ptr.push(row_idx.len());
        }
        for &n in nodes {
            self.local[n as usize] = u32::MAX;
        }
        let k = nodes.len();
        let (mut perm, mut perm_inv) = (vec![0usize; k], vec![0usize; k]);
        let graph = SymbolicSparseColMatRef::new_checked(k, k, &col_ptr, None, &row_idx);
        let mut buffer = MemBuffer::new(amd::order_scratch::<usize>(k, row_idx.len()));
        let ordered = amd::order(
            &mut perm,
            &mut perm_inv,
            graph,
            amd::Control::default(),
            MemStack::new(&mut buffer),
        );
        match ordered {
            Ok(_) => self.order.extend(perm.iter().map(|&p| nodes[p])),
            // Only an allocation failure: the node numbering is an order too.
            Err(_) => self.order.extend_from_slice(nodes),
        }
    }
}

/// `nodes` parted by `lower` into (those it holds for, the others), or
/// `None` where either would be empty.
fn two_sides(nodes: &[u32], lower: impl Fn(u32) -> bool) -> Option<(Vec<u32>, Vec<u32>)> {
    let (a, b): (Vec<u32>, Vec<u32>) = nodes.iter().partition(|&&n| lower(n));
    (!a.is_empty() && !b.is_empty()).then_some((a, b))
}
