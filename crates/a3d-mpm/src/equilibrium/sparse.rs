//! The sparse side of the equilibrium solve: the pattern of the stiffness
//! matrix over the free degrees of freedom (lower triangle, compressed
//! columns), its assembly from element blocks, and its Cholesky factor (faer's
//! sparse LLᵀ with an AMD ordering, or nested dissection for large 3D systems
//! (`ordering`), run sequentially so that the result does not depend on the
//! number of threads).
//!
//! Degrees of freedom are numbered node by node (node-major, direction
//! minor), so that each column's rows come out sorted from a sorted node
//! adjacency. This file knows nothing of mechanics: it takes element
//! connectivities and dense element blocks.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::FaerError;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use super::super::MpmError;

/// Marker for a constrained (not solved for) degree of freedom.
pub(super) const CONSTRAINED: u32 = u32::MAX;

/// How the unknowns of a [`LowerPattern`] are ordered for the factor.
#[derive(Clone, Copy)]
pub(super) enum Ordering<'a> {
    /// faer's approximate minimum degree.
    Amd,
    /// Nested dissection of the nodes at these positions
    /// ([`super::ordering`]).
    Dissection(&'a [[f64; 3]]),
}

/// The lower triangle of a symmetric matrix over the free degrees of freedom,
/// in compressed sparse columns.
pub(super) struct LowerPattern {
    /// Number of free degrees of freedom.
    pub n: usize,
    pub col_ptr: Vec<usize>,
    /// Row of each entry, column by column (rows below 2³² as the free
    /// numbers are `u32`; half the memory of `usize`).
    pub row_idx: Vec<u32>,
    /// The elimination order of the free unknowns where it is not faer's
    /// AMD ([`super::ordering`]): `order[k]` is eliminated k-th.
    pub order: Option<Vec<usize>>,
}

impl LowerPattern {
    /// The pattern of a matrix assembled from elements whose corners are
    /// `elements` (compact node indices, `nodes` nodes in all) with `dim`
    /// directions per node, where `dof[node * dim + d]` is the free number of
    /// each direction or [`CONSTRAINED`], to be eliminated in the order
    /// `ordering` says.
    pub fn new<const NC: usize>(
        elements: impl Iterator<Item = [u32; NC]> + Clone,
        nodes: usize,
        dim: usize,
        dof: &[u32],
        ordering: Ordering<'_>,
    ) -> LowerPattern {
        // Node adjacency (each node with itself), compressed rows, sorted.
        let mut count = vec![0usize; nodes + 1];
        for corners in elements.clone() {
            for &a in &corners {
                count[a as usize + 1] += NC;
            }
        }
        for i in 0..nodes {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut adjacent = vec![0u32; count[nodes]];
        for corners in elements {
            for &a in &corners {
                for &b in &corners {
                    adjacent[fill[a as usize]] = b;
                    fill[a as usize] += 1;
                }
            }
        }
        let mut start = Vec::with_capacity(nodes + 1);
        let mut unique: Vec<u32> = Vec::with_capacity(adjacent.len() / 2);
        start.push(0);
        for i in 0..nodes {
            let list = &mut adjacent[count[i]..count[i + 1]];
            list.sort_unstable();
            let mut last = None;
            for &b in list.iter() {
                if last != Some(b) {
                    unique.push(b);
                    last = Some(b);
                }
            }
            start.push(unique.len());
        }
        drop(adjacent);
        // Columns in free-dof order: free dofs are numbered node-major, so
        // walking nodes and directions in order visits columns in order.
        let n = dof.iter().filter(|&&d| d != CONSTRAINED).count();
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for node in 0..nodes {
            for d in 0..dim {
                let col = dof[node * dim + d];
                if col == CONSTRAINED {
                    continue;
                }
                for &other in &unique[start[node]..start[node + 1]] {
                    for e in 0..dim {
                        let row = dof[other as usize * dim + e];
                        if row != CONSTRAINED && row >= col {
                            row_idx.push(row);
                        }
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let dissect = |p| {
            super::ordering::nested_dissection(p, dim, (&start, &unique), (dof, CONSTRAINED, n))
        };
        let order = match ordering {
            Ordering::Amd => None,
            Ordering::Dissection(p) => Some(dissect(p)),
        };
        LowerPattern {
            n,
            col_ptr,
            row_idx,
            order,
        }
    }

    /// Number of stored entries (lower triangle with the diagonal).
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Index into the values of entry (`row`, `col`), `row ≥ col`.
    #[inline]
    pub fn position(&self, row: usize, col: usize) -> usize {
        let rows = &self.row_idx[self.col_ptr[col]..self.col_ptr[col + 1]];
        match rows.binary_search(&(row as u32)) {
            Ok(k) => self.col_ptr[col] + k,
            Err(_) => unreachable!("entry ({row}, {col}) is outside the assembled pattern"),
        }
    }
}

/// The Cholesky factor L Lᵀ of a symmetric positive definite matrix.
pub(super) struct Cholesky(Factor);

/// The factor with 32-bit indices (half the symbolic structure's memory) or,
/// where L has more entries than they count, with `usize` ones.
enum Factor {
    Narrow(SymbolicCholesky<u32>, Vec<f64>),
    Wide(SymbolicCholesky<usize>, Vec<f64>),
}

/// Why a factorisation failed.
enum Failure {
    /// The indices' type cannot count the factor's entries.
    Overflow,
    OutOfMemory,
    /// Not positive definite: a mechanism.
    Mechanism,
    Other(String),
}

impl Cholesky {
    /// Factors the matrix with `pattern` and lower-triangle `values`. A matrix
    /// that is not positive definite (a mechanism: too few fixities, or
    /// elements without stiffness) is an error.
    pub fn factor(pattern: &LowerPattern, values: &[f64]) -> Result<Cholesky, MpmError> {
        let n = pattern.n;
        let too_large = |what: &str| {
            MpmError::InvalidSettings(format!(
                "the stiffness matrix of {n} unknowns could not be factored: {what}"
            ))
        };
        let narrow = narrow(&pattern.col_ptr).and_then(|col_ptr| {
            let order = match &pattern.order {
                Some(order) => Some(narrow(order)?),
                None => None,
            };
            Some((col_ptr, order))
        });
        let wide = || {
            let row_idx: Vec<usize> = pattern.row_idx.iter().map(|&r| r as usize).collect();
            factor_with(
                pattern,
                &pattern.col_ptr,
                &row_idx,
                pattern.order.as_deref(),
                values,
            )
            .map(|(s, v)| Factor::Wide(s, v))
        };
        let factor = match narrow {
            Some((col_ptr, order)) => {
                match factor_with(
                    pattern,
                    &col_ptr,
                    &pattern.row_idx,
                    order.as_deref(),
                    values,
                ) {
                    Ok((s, v)) => Ok(Factor::Narrow(s, v)),
                    Err(Failure::Overflow) => wide(),
                    Err(other) => Err(other),
                }
            }
            None => wide(),
        };
        match factor {
            Ok(f) => Ok(Cholesky(f)),
            Err(Failure::Overflow) => Err(too_large(
                "its factor has more entries than this machine can index",
            )),
            Err(Failure::OutOfMemory) => Err(too_large("its factor does not fit in memory")),
            Err(Failure::Mechanism) => Err(MpmError::InvalidSettings(
                "the stiffness matrix could not be factored (not positive definite): the model is not held in place (check the GOM's fixities)".into(),
            )),
            Err(Failure::Other(what)) => Err(MpmError::InvalidSettings(format!(
                "the stiffness matrix could not be factored ({what})"
            ))),
        }
    }

    /// Stored entries of the factor L.
    pub fn nnz(&self) -> usize {
        match &self.0 {
            Factor::Narrow(_, values) | Factor::Wide(_, values) => values.len(),
        }
    }

    /// Solves K x = b in place (`b` becomes x).
    pub fn solve(&self, b: &mut [f64]) {
        match &self.0 {
            Factor::Narrow(symbolic, values) => solve_with(symbolic, values, b),
            Factor::Wide(symbolic, values) => solve_with(symbolic, values, b),
        }
    }
}

/// `values` as `u32`, or `None` where one does not fit.
fn narrow(values: &[usize]) -> Option<Vec<u32>> {
    values.iter().map(|&v| u32::try_from(v).ok()).collect()
}

/// The factor of the matrix with columns `col_ptr`, rows `row_idx` and
/// lower-triangle `values`, eliminated in `order` (faer's AMD if `None`).
/// Large 3D systems (ordered by dissection) keep faer's fundamental
/// supernodes unmerged: 6 % less fill on them, as fast (`a3d-bench
/// equilibrium --dim 3`); the others keep faer's defaults, and their bits.
fn factor_with<I: faer::Index>(
    pattern: &LowerPattern,
    col_ptr: &[I],
    row_idx: &[I],
    order: Option<&[I]>,
    values: &[f64],
) -> Result<(SymbolicCholesky<I>, Vec<f64>), Failure> {
    let n = pattern.n;
    let matrix = SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx);
    let inverse: Vec<I>;
    let mut params = CholeskySymbolicParams::default();
    let ordering = match order {
        None => SymmetricOrdering::Amd,
        Some(order) => {
            let mut inv = vec![I::truncate(0); n];
            for (k, &i) in order.iter().enumerate() {
                inv[i.zx()] = I::truncate(k);
            }
            inverse = inv;
            params.supernodal_params.relax = None;
            SymmetricOrdering::Custom(PermRef::new_checked(order, &inverse, n))
        }
    };
    let symbolic = factorize_symbolic_cholesky(matrix, Side::Lower, ordering, params).map_err(
        |e| match e {
            FaerError::IndexOverflow => Failure::Overflow,
            FaerError::OutOfMemory => Failure::OutOfMemory,
            other => Failure::Other(format!("{other:?}")),
        },
    )?;
    let mut factor = Vec::new();
    factor
        .try_reserve_exact(symbolic.len_val())
        .map_err(|_| Failure::OutOfMemory)?;
    factor.resize(symbolic.len_val(), 0.0);
    let par = Par::Seq;
    let mut buffer =
        MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()))
            .map_err(|_| Failure::OutOfMemory)?;
    symbolic
        .factorize_numeric_llt(
            &mut factor,
            SparseColMatRef::new(matrix, values),
            Side::Lower,
            LltRegularization::default(),
            par,
            MemStack::new(&mut buffer),
            Default::default(),
        )
        .map_err(|_| Failure::Mechanism)?;
    Ok((symbolic, factor))
}

/// Solves L Lᵀ x = b in place.
fn solve_with<I: faer::Index>(symbolic: &SymbolicCholesky<I>, values: &[f64], b: &mut [f64]) {
    let n = b.len();
    let par = Par::Seq;
    let mut buffer = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, par));
    LltRef::new(symbolic, values).solve_in_place_with_conj(
        Conj::No,
        MatMut::from_column_major_slice_mut(b, n, 1),
        par,
        MemStack::new(&mut buffer),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1D chain of two-node "elements" with unit springs, node 0 fixed:
    /// K is tridiagonal; the solve of K x = 1 matches the closed form.
    #[test]
    fn chain_of_springs_solves_exactly() {
        let nodes = 6;
        let elements: Vec<[u32; 2]> = (0..nodes as u32 - 1).map(|i| [i, i + 1]).collect();
        let mut dof = vec![CONSTRAINED; nodes];
        for (i, d) in dof.iter_mut().enumerate().skip(1) {
            *d = i as u32 - 1;
        }
        let pattern = LowerPattern::new(elements.iter().copied(), nodes, 1, &dof, Ordering::Amd);
        assert_eq!(pattern.n, 5);
        assert_eq!(pattern.nnz(), 9);
        let mut values = vec![0.0; pattern.nnz()];
        for e in &elements {
            let block = [[1.0, -1.0], [-1.0, 1.0]];
            for a in 0..2 {
                for b in 0..2 {
                    let (r, c) = (dof[e[a] as usize], dof[e[b] as usize]);
                    if r != CONSTRAINED && c != CONSTRAINED && r >= c {
                        values[pattern.position(r as usize, c as usize)] += block[a][b];
                    }
                }
            }
        }
        let cholesky = Cholesky::factor(&pattern, &values).expect("positive definite");
        let mut x = vec![1.0; 5];
        cholesky.solve(&mut x);
        // A chain fixed at one end with unit loads: u_k = Σ_{j ≤ k} (n − j).
        let expect = [5.0, 9.0, 12.0, 14.0, 15.0];
        for (a, b) in x.iter().zip(expect) {
            assert!((a - b).abs() < 1e-12, "{x:?}");
        }
    }

    /// The factor with `usize` indices (taken where L outgrows `u32`) solves
    /// as the 32-bit one does, to the bit.
    #[test]
    fn wide_indices_factor_as_narrow_ones_do() {
        let nodes = 40;
        let elements: Vec<[u32; 3]> = (0..nodes as u32 - 2).map(|i| [i, i + 1, i + 2]).collect();
        let dof: Vec<u32> = (0..nodes as u32)
            .map(|i| i.checked_sub(2).unwrap_or(CONSTRAINED))
            .collect();
        let pattern = LowerPattern::new(elements.iter().copied(), nodes, 1, &dof, Ordering::Amd);
        let values: Vec<f64> = (0..pattern.nnz()).map(|k| 1.0 / (1.0 + k as f64)).collect();
        let mut values = values;
        for col in 0..pattern.n {
            values[pattern.position(col, col)] = 10.0;
        }
        let narrow = Cholesky::factor(&pattern, &values).expect("positive definite");
        assert!(matches!(narrow.0, Factor::Narrow(..)));
        let rows: Vec<usize> = pattern.row_idx.iter().map(|&r| r as usize).collect();
        let wide = match factor_with(&pattern, &pattern.col_ptr, &rows, None, &values) {
            Ok((symbolic, values)) => Cholesky(Factor::Wide(symbolic, values)),
            Err(_) => panic!("the wide factor failed"),
        };
        assert_eq!(narrow.nnz(), wide.nnz());
        let b: Vec<f64> = (0..pattern.n).map(|i| (i as f64).sin()).collect();
        let (mut x, mut y) = (b.clone(), b);
        narrow.solve(&mut x);
        wide.solve(&mut y);
        assert_eq!(x, y);
    }

    #[test]
    fn a_free_body_is_refused() {
        let elements = [[0u32, 1u32]];
        let dof = vec![0, 1];
        let pattern = LowerPattern::new(elements.iter().copied(), 2, 1, &dof, Ordering::Amd);
        let mut values = vec![0.0; pattern.nnz()];
        values[pattern.position(0, 0)] = 1.0;
        values[pattern.position(1, 0)] = -1.0;
        values[pattern.position(1, 1)] = 1.0;
        assert!(Cholesky::factor(&pattern, &values).is_err());
    }

    /// A 3D lattice of springs (three directions per node, the bottom
    /// fixed), ordered by nested dissection (of its coordinates, of
    /// coordinates full of ties, and of coordinates that are not numbers)
    /// and by AMD: the dissection is a permutation
    /// of the free unknowns that splits below its leaf size, and every
    /// factor solves K x = f to the same answer. (Its fill pays on large
    /// 3D meshes, not on a lattice this small: the benchmark measures that.)
    #[test]
    fn nested_dissection_solves_as_amd_does() {
        let n = 11usize;
        let at = |i: usize, j: usize, k: usize| (i * n + j) * n + k;
        let mut positions = vec![[0.0; 3]; n * n * n];
        let mut elements: Vec<[u32; 2]> = Vec::new();
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    positions[at(i, j, k)] = [i as f64, j as f64 * 1.3, k as f64 * 0.7];
                    for (di, dj, dk) in [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (0, 1, 1)] {
                        if i + di < n && j + dj < n && k + dk < n {
                            elements.push([at(i, j, k) as u32, at(i + di, j + dj, k + dk) as u32]);
                        }
                    }
                }
            }
        }
        let mut dof = vec![CONSTRAINED; n * n * n * 3];
        let mut free = 0u32;
        for node in 0..n * n * n {
            if positions[node][1] > 0.0 {
                for d in 0..3 {
                    dof[node * 3 + d] = free;
                    free += 1;
                }
            }
        }
        let solve = |ordering: Ordering<'_>| {
            let pattern = LowerPattern::new(elements.iter().copied(), n * n * n, 3, &dof, ordering);
            if let Some(order) = &pattern.order {
                let mut seen = order.clone();
                seen.sort_unstable();
                assert_eq!(seen, (0..pattern.n).collect::<Vec<_>>());
            }
            let mut values = vec![0.0; pattern.nnz()];
            for e in &elements {
                // An axial spring along the edge: k t tᵀ, plus a small shear term.
                let (p, q) = (positions[e[0] as usize], positions[e[1] as usize]);
                let l =
                    ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2)).sqrt();
                let t = [(q[0] - p[0]) / l, (q[1] - p[1]) / l, (q[2] - p[2]) / l];
                for (a, sa) in [(0, 1.0), (1, -1.0)] {
                    for (b, sb) in [(0, 1.0), (1, -1.0)] {
                        for r in 0..3 {
                            for c in 0..3 {
                                let shear = if r == c { 0.1 } else { 0.0 };
                                let v = sa * sb * (t[r] * t[c] + shear) / l;
                                let (row, col) =
                                    (dof[e[a] as usize * 3 + r], dof[e[b] as usize * 3 + c]);
                                if row != CONSTRAINED && col != CONSTRAINED && row >= col {
                                    values[pattern.position(row as usize, col as usize)] += v;
                                }
                            }
                        }
                    }
                }
            }
            let cholesky = Cholesky::factor(&pattern, &values).expect("positive definite");
            let mut x: Vec<f64> = (0..pattern.n)
                .map(|i| if i % 3 == 1 { -1.0 } else { 0.0 })
                .collect();
            cholesky.solve(&mut x);
            (x, cholesky.nnz())
        };
        let (amd, amd_fill) = solve(Ordering::Amd);
        let (nd, nd_fill) = solve(Ordering::Dissection(&positions));
        // Coordinates full of ties for the ordering (two levels along x,
        // all but one layer level along y, one level along z): the splits
        // fall back to even ones and still order every unknown.
        let ties: Vec<[f64; 3]> = (0..n * n * n)
            .map(|m| {
                let (i, j) = (m / (n * n), (m / n) % n);
                [(i % 2) as f64, if j + 1 < n { 0.0 } else { 1.0 }, 0.0]
            })
            .collect();
        let (tied, _) = solve(Ordering::Dissection(&ties));
        // Coordinates that are not numbers: the splits by index.
        let (unknown, _) = solve(Ordering::Dissection(&vec![[f64::NAN; 3]; n * n * n]));
        let scale = amd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for other in [&nd, &tied, &unknown] {
            let worst = amd
                .iter()
                .zip(other)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(worst <= 1e-10 * scale, "worst {worst:e} of {scale:e}");
        }
        assert!(nd_fill != amd_fill, "the orders differ");
    }
}
