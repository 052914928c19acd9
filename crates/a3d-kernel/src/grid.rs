//! A uniform cell grid over a fixed point cloud, the mapper's fast neighbour
//! search. The mapper's grid has cells half the kernel support wide and runs
//! its queries cell by cell: the rows of cells that the support can reach
//! from anywhere in a cell (runs of cells along x, contiguous in the sorted
//! columns) are found once per cell ([`Grid::blocks`]) and cut into blocks
//! of LANES points; every query of the cell then tests those blocks in a
//! loop the compiler vectorises (AVX-512 with `vcompresspd` where the
//! processor has it, `simd.rs`), writing the hits without a branch
//! ([`Grid::collect`]). The mapper takes the hits as they come, in the
//! grid's order ([`Hits::in_grid_order`]): no sort per query, and the order
//! a point's sums run in is fixed by the grid alone. [`Grid::within`] and
//! [`Grid::sorted`] order them by (distance, index) instead, with a bucket
//! pass and an insertion sort (the k-d tree's contract, for the tests).
//! [`Grid::nearest_others`] instead gathers the 3^dim cells around a
//! cell once for all the points of that cell.
//!
//! [`Grid::within`] has the contract of the k-d tree of `neighbours.rs` (which
//! stays the reference): physical radius in, `(index, distance)` out,
//! inclusive, sorted by (distance, index), distances computed as
//! `sqrt(Σ (p_k − q_k)²)` in axis order, so both give bit-identical lists.
//! Like `neighbours.rs` and `simd.rs`, this file sees squared distances.

use super::simd::{Avx512, Block};

/// Points sorted by cell, coordinates stored column-wise.
pub struct Grid {
    dim: usize,
    origin: [f64; 3],
    cell: f64,
    inv_cell: f64,
    /// The search radius the grid was built for (queries may use less).
    radius: f64,
    /// How far (m) rounding can move a point across a cell face: relative to
    /// the coordinates' magnitude.
    slack: f64,
    /// Cells per axis (1 along z in 2D).
    dims: [i64; 3],
    /// The cells are coarser than asked, or the slack spans cells, so that
    /// searches here test far more points than the radius holds (a tiny radius
    /// in a wide cloud, one point far from the rest): see [`Grid::is_coarse`].
    coarse: bool,
    /// Start of each cell's points in the sorted columns (length cells + 1).
    start: Vec<u32>,
    xs: Vec<f64>,
    ys: Vec<f64>,
    zs: Vec<f64>,
    /// Original index of each sorted point.
    ids: Vec<u32>,
    /// The AVX-512 distance test, where the processor has it.
    simd: Option<Avx512>,
}

/// Cell coordinates of a query (may lie outside the grid by any amount).
pub type Cell = [i64; 3];

/// The rows of cells around a cell (`[dy, dz, reach along x]`, in ascending
/// order) that a search radius reaches, from [`Grid::stencil`].
pub struct Stencil {
    rows: Vec<[i64; 3]>,
    /// Per row, its offset in cells from the cell's (`dy·nx + dz·nx·ny`)
    /// and its reach along x, for cells whose stencil lies in the grid.
    offsets: Vec<(i64, i64)>,
    /// How far the stencil reaches along x, y and z.
    reach: [i64; 3],
}

impl Stencil {
    /// The number of rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }
}

/// The blocks of LANES points that the queries of one cell test, from
/// [`Grid::blocks`].
#[derive(Default)]
pub struct Blocks {
    blocks: Vec<Block>,
}

impl Grid {
    /// Builds a grid of cells one `radius` wide, for searches up to `radius`.
    /// `dim` is 2 (z ignored) or 3.
    pub fn new(points: &[[f64; 3]], dim: usize, radius: f64) -> Grid {
        Grid::with_cells(points, dim, radius, 1)
    }

    /// A grid of cells `1/per_radius` of `radius` wide, for searches up to
    /// `radius`: the blocks of a half-radius cell hold about 3.7 times the
    /// sphere's points, against 6.4 with whole-radius cells, in 25 rows of
    /// cells rather than 9 (the mapper's choice, measured with `bench map`).
    pub fn with_cells(points: &[[f64; 3]], dim: usize, radius: f64, per_radius: u32) -> Grid {
        let n = points.len();
        let mut lo = [0.0f64; 3];
        let mut hi = [0.0f64; 3];
        if let Some(first) = points.first() {
            lo = *first;
            hi = *first;
        }
        for p in points {
            for k in 0..dim {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let mut radius = radius.abs();
        if !(radius.is_finite() && radius > 0.0) {
            radius = 0.0;
        }
        // A little wider than the radius, so that rounding in the cell index
        // never puts a point within the radius two cells away.
        let mut cell = radius / per_radius.max(1) as f64 * (1.0 + 1e-6);
        if !(cell.is_finite() && cell > 0.0) {
            cell = 1.0;
        }
        let asked = cell;
        // The extent per axis, at most the largest double (two points at
        // ±1e308 are 2e308 apart, which is infinite).
        let extent = [0, 1, 2].map(|k| (hi[k] - lo[k]).min(f64::MAX));
        // Keep the cell count near the point count (a tiny radius in a wide
        // cloud, one point far from the rest): memory proportional to the
        // points whatever the coordinates and the radius.
        let max_cells = (4 * n + 64) as f64;
        loop {
            let count: f64 = (0..dim).map(|k| (extent[k] / cell).floor() + 1.0).product();
            if count <= max_cells {
                break;
            }
            if !count.is_finite() {
                // Too many cells to count: start from cells of the widest
                // extent over max_cells^(1/dim), a finite count.
                let widest = extent[..dim].iter().copied().fold(0.0, f64::max);
                cell = cell.max(widest / max_cells.powf(1.0 / dim as f64));
                continue;
            }
            cell *= (count / max_cells).powf(1.0 / dim as f64).max(1.01);
        }
        let mut dims = [1i64; 3];
        for k in 0..dim {
            dims[k] = (extent[k] / cell).floor() as i64 + 1;
        }
        let mag = (0..dim)
            .map(|k| lo[k].abs() + hi[k].abs())
            .fold(0.0, f64::max)
            .min(f64::MAX);
        let slack = (8.0 * f64::EPSILON * (mag + 4.0 * cell + radius) + 1e-9 * cell).min(f64::MAX);
        let mut grid = Grid {
            dim,
            origin: lo,
            cell,
            inv_cell: 1.0 / cell,
            radius,
            slack,
            dims,
            coarse: cell > 4.0 * asked || slack > cell,
            start: Vec::new(),
            xs: Vec::with_capacity(n + LANES),
            ys: Vec::with_capacity(n + LANES),
            zs: Vec::with_capacity(n + LANES),
            ids: Vec::new(),
            simd: Avx512::detect(),
        };
        let n_cells = (dims[0] * dims[1] * dims[2]) as usize;
        // Every point lies in the box; the clamp only catches a multiplication
        // by 1/cell rounding a point on the far face one cell past the last.
        let last = [dims[0] - 1, dims[1] - 1, dims[2] - 1];
        let cell_of: Vec<u32> = points
            .iter()
            .map(|p| {
                let c = grid.cell(*p);
                let c = [0, 1, 2].map(|k| c[k].clamp(0, last[k]));
                grid.linear(c) as u32
            })
            .collect();
        // Counting sort by cell, stable in the original index.
        let mut start = vec![0u32; n_cells + 1];
        for &c in &cell_of {
            start[c as usize + 1] += 1;
        }
        for c in 0..n_cells {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut order = vec![0u32; n];
        for (i, &c) in cell_of.iter().enumerate() {
            order[fill[c as usize] as usize] = i as u32;
            fill[c as usize] += 1;
        }
        for &i in &order {
            let p = points[i as usize];
            grid.xs.push(p[0]);
            grid.ys.push(p[1]);
            grid.zs.push(if dim == 3 { p[2] } else { 0.0 });
        }
        // Padding, so that the last points' block of LANES reads in bounds.
        for col in [&mut grid.xs, &mut grid.ys, &mut grid.zs] {
            col.extend([f64::NAN; LANES]);
        }
        grid.ids = order;
        grid.start = start;
        grid
    }

    /// Tests distances in portable code only, never AVX-512 (the same bits).
    pub fn portable(&mut self) {
        self.simd = None;
    }

    /// The AVX-512 token this grid tests with, `None` for portable code.
    pub fn simd(&self) -> Option<Avx512> {
        self.simd
    }

    /// True when the cells came out more than 4 times wider than asked (the
    /// cell count is kept near the point count: a radius tiny against the
    /// cloud, or one point far from the rest) or the rounding slack spans a
    /// cell (coordinates huge against the cells). A search of the grid's
    /// radius then tests far more points than it finds; the mapper searches
    /// such a group with the k-d tree instead, which gives the same lists.
    pub fn is_coarse(&self) -> bool {
        self.coarse
    }

    /// Σ over the cells of (points in the cell)²: a few times the point count
    /// for radius-wide cells over an even cloud, up to its square where most
    /// points share a few cells (one point far from the rest), which is what
    /// [`Grid::nearest_others`] costs.
    pub fn crowding(&self) -> u64 {
        self.start
            .windows(2)
            .map(|w| u64::from(w[1] - w[0]).pow(2))
            .sum()
    }

    /// The cell of `q`, clamped to one cell outside the grid (those see the border).
    #[inline]
    pub fn cell(&self, q: [f64; 3]) -> Cell {
        let mut c = [0i64; 3];
        for (k, ck) in c.iter_mut().enumerate().take(self.dim) {
            let f = (q[k] - self.origin[k]) * self.inv_cell;
            let f = f.clamp(-2.0, self.dims[k] as f64 + 1.0);
            // floor(f) without a library call: truncation from −2 up, one
            // down where the sum rounded up to the next whole number (NaN
            // gives −2).
            *ck = (f + 2.0) as i64 - 2;
            if (*ck as f64) > f {
                *ck -= 1;
            }
        }
        c
    }

    /// The number of distinct [`Grid::cell_key`]s: the cells of the grid
    /// widened by the two cells on each side that [`Grid::cell`] clamps to.
    pub fn cell_keys(&self) -> u64 {
        (0..self.dim).map(|k| (self.dims[k] + 4) as u64).product()
    }

    /// A number for each cell [`Grid::cell`] gives, below [`Grid::cell_keys`],
    /// ordered as the grid orders its cells (x fastest).
    pub fn cell_key(&self, c: Cell) -> u64 {
        (0..self.dim).rev().fold(0, |key, k| {
            key * (self.dims[k] + 4) as u64 + (c[k] + 2) as u64
        })
    }

    fn linear(&self, c: Cell) -> usize {
        ((c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]) as usize
    }

    /// The original index of each point in the grid's (cell) order.
    pub fn order(&self) -> &[u32] {
        &self.ids
    }

    /// The rows of cells around a cell that points within `radius` of any
    /// point in the cell can lie in, the same for every cell: a row is kept
    /// where its cells come within the radius of the cell's box (rounded
    /// generously by the grid's slack), and reaches along x as far as that.
    pub fn stencil(&self, radius: f64) -> Stencil {
        debug_assert!(radius.abs() <= self.radius * (1.0 + 1e-6) || self.radius == 0.0);
        let r = radius.abs();
        let c = self.cell;
        let s2 = 2.0 * self.slack;
        // The gap between the boxes of two cells `d` apart along an axis.
        let gap = |d: i64| ((d.abs() - 1) as f64 * c - s2).max(0.0);
        // No row or run reaches past the grid from a query cell, which
        // [`Grid::cell`] clamps to two cells outside: the reach is bounded by
        // the grid's size, so the stencil's rows are at most about nine per
        // cell, whatever the radius, slack and cell.
        let span = self.dims[0].max(self.dims[1]).max(self.dims[2]) + 2;
        let reach = |room: f64| 1 + ((room + s2) / c).min(span as f64) as i64;
        let most = reach(r);
        let (zs, ys) = (
            if self.dim == 3 {
                most.min(self.dims[2] + 2)
            } else {
                0
            },
            most.min(self.dims[1] + 2),
        );
        let mut rows = Vec::new();
        for dz in -zs..=zs {
            for dy in -ys..=ys {
                let (gy, gz) = (gap(dy), if self.dim == 3 { gap(dz) } else { 0.0 });
                let room = r * r - gy * gy - gz * gz;
                if room >= 0.0 {
                    rows.push([dy, dz, reach(room.sqrt())]);
                }
            }
        }
        let (nx, ny) = (self.dims[0], self.dims[1]);
        let offsets = rows
            .iter()
            .map(|&[dy, dz, dx]| (dy * nx + dz * nx * ny, dx))
            .collect();
        // Rows are [dy, dz, reach along x].
        let reach = [2, 0, 1].map(|k| rows.iter().map(|r| r[k].abs()).max().unwrap_or(0));
        Stencil {
            rows,
            offsets,
            reach,
        }
    }

    /// The blocks of `stencil` around `cell`: its rows of cells clipped to
    /// the grid, each a run of grid positions (contiguous in the sorted
    /// columns), cut into blocks of LANES points. Every query in the cell
    /// shares them.
    #[inline]
    pub fn blocks(&self, stencil: &Stencil, cell: Cell, out: &mut Blocks) {
        out.blocks.clear();
        let last = [self.dims[0] - 1, self.dims[1] - 1, self.dims[2] - 1];
        let [rx, ry, rz] = stencil.reach;
        let inside = cell[0] - rx >= 0
            && cell[0] + rx <= last[0]
            && cell[1] - ry >= 0
            && cell[1] + ry <= last[1]
            && cell[2] - rz >= 0
            && cell[2] + rz <= last[2];
        if inside {
            // Every row lies in the grid, unclipped: the same runs as below
            // from the rows' offsets, without the clipping.
            // Two blocks written per row whatever its length, and kept as
            // it needs them (a run past two blocks, rare, takes the loop):
            // no branch that the runs' lengths would mispredict.
            let at = self.linear(cell) as i64;
            let blocks = &mut out.blocks;
            let mut n = 0;
            let rows = stencil.offsets.len();
            blocks.resize(2 * rows, Block::EMPTY);
            for (i, &(offset, dx)) in stencil.offsets.iter().enumerate() {
                let row = at + offset;
                let (a, b) = (
                    self.start[(row - dx) as usize],
                    self.start[(row + dx + 1) as usize],
                );
                let len = b - a;
                blocks[n] = Block {
                    at: a,
                    valid: lanes(len),
                };
                blocks[n + 1] = Block {
                    at: a + LANES as u32,
                    valid: lanes(len.saturating_sub(LANES as u32)),
                };
                n += usize::from(len > 0) + usize::from(len > LANES as u32);
                if len > 2 * LANES as u32 {
                    blocks.truncate(n);
                    split(a + 2 * LANES as u32, b, blocks);
                    n = blocks.len();
                    blocks.resize(n + 2 * (rows - i - 1), Block::EMPTY);
                }
            }
            blocks.truncate(n);
            return;
        }
        for &[dy, dz, dx] in &stencil.rows {
            let (y, z) = (cell[1] + dy, cell[2] + dz);
            if y < 0 || y > last[1] || z < 0 || z > last[2] {
                continue;
            }
            let (x0, x1) = ((cell[0] - dx).max(0), (cell[0] + dx).min(last[0]));
            if x0 > x1 {
                continue;
            }
            let (a, b) = (
                self.start[self.linear([x0, y, z])],
                self.start[self.linear([x1, y, z]) + 1],
            );
            split(a, b, &mut out.blocks);
        }
    }

    /// The points of `blocks` (from [`Grid::blocks`] for `q`'s cell) within
    /// `radius` of `q` (inclusive) into `hits`, with their squared distances
    /// `Σ (p_k − q_k)²` summed in axis order. A non-finite `q` finds nothing.
    #[inline(always)]
    pub fn collect(&self, blocks: &Blocks, q: [f64; 3], radius: f64, hits: &mut Hits) {
        hits.len = 0;
        if q[..self.dim].iter().any(|v| !v.is_finite()) {
            return;
        }
        let cols = [&self.xs[..], &self.ys[..], &self.zs[..]];
        hits.test(
            cols,
            self.dim == 3,
            &blocks.blocks,
            q,
            radius * radius,
            self.simd,
        );
    }

    /// The hits of [`Grid::collect`] for a search of `radius` as (position,
    /// distance), sorted by distance then original index, into `out`.
    pub fn sorted(&self, hits: &mut Hits, radius: f64, out: &mut Vec<(u32, f64)>) {
        out.clear();
        hits.sort(&self.ids, radius.abs(), self.dim, out);
    }

    /// Gathers the points of `cell` and its neighbours into `out` (a grid of
    /// radius-wide cells, see [`Grid::new`]).
    fn gather(&self, cell: Cell, out: &mut Candidates) {
        out.clear();
        let range = |k: usize| -> (i64, i64) {
            if k >= self.dim {
                return (0, 0);
            }
            ((cell[k] - 1).max(0), (cell[k] + 1).min(self.dims[k] - 1))
        };
        let (x0, x1) = range(0);
        let (y0, y1) = range(1);
        let (z0, z1) = range(2);
        for z in z0..=z1 {
            for y in y0..=y1 {
                if x0 > x1 {
                    continue;
                }
                // Cells x0..=x1 of one row are contiguous in the sorted columns.
                let a = self.start[self.linear([x0, y, z])] as usize;
                let b = self.start[self.linear([x1, y, z]) + 1] as usize;
                out.xs.extend_from_slice(&self.xs[a..b]);
                out.ys.extend_from_slice(&self.ys[a..b]);
                out.zs.extend_from_slice(&self.zs[a..b]);
            }
        }
    }

    /// All points within `radius` of `q` (inclusive) as (original index,
    /// distance), sorted by distance then index; `radius` at most the grid's.
    /// A convenience for single queries.
    pub fn within(&self, q: [f64; 3], radius: f64, out: &mut Vec<(u32, f64)>) {
        let (mut blocks, mut hits) = (Blocks::default(), Hits::default());
        self.blocks(&self.stencil(radius), self.cell(q), &mut blocks);
        self.collect(&blocks, q, radius, &mut hits);
        self.sorted(&mut hits, radius, out);
        for e in out.iter_mut() {
            e.0 = self.ids[e.0 as usize];
        }
    }
}

impl Grid {
    /// The nearest point to `q` as (position in the grid's order, see
    /// [`Grid::order`], distance), the lowest original index among equally
    /// near ones; `None` for an empty grid or a
    /// non-finite `q`. Searches rings of cells outward from `q`'s cell until
    /// no closer point can remain, so a query far outside the cloud costs only
    /// the rings it crosses.
    pub fn nearest(&self, q: [f64; 3]) -> Option<(u32, f64)> {
        self.nearest_except(q, usize::MAX)
    }

    /// [`Grid::nearest`] leaving out the point at position `except` (the
    /// nearest other point of a grid point; a duplicate of it is at 0).
    pub fn nearest_except(&self, q: [f64; 3], except: usize) -> Option<(u32, f64)> {
        let dim = self.dim;
        if self.ids.is_empty() || q[..dim].iter().any(|v| !v.is_finite()) {
            return None;
        }
        let mut c = [0i64; 3];
        let mut r0 = 0i64;
        for k in 0..dim {
            let f = ((q[k] - self.origin[k]) * self.inv_cell).floor();
            c[k] = f.clamp(-1e15, 1e15) as i64;
            // Rings closer than the grid are empty.
            r0 = r0.max(-c[k]).max(c[k] - (self.dims[k] - 1));
        }
        let mut best: Option<(f64, u32, usize)> = None;
        let mut r = r0;
        loop {
            if let Some((d2, _, _)) = best {
                let gap = (r - 1).max(0) as f64 * self.cell * (1.0 - 1e-9);
                if gap * gap > d2 {
                    break;
                }
            }
            let span = |k: usize| -> (i64, i64) {
                if k >= dim {
                    (0, 0)
                } else {
                    ((c[k] - r).max(0), (c[k] + r).min(self.dims[k] - 1))
                }
            };
            let (y0, y1) = span(1);
            let (z0, z1) = span(2);
            let (x0, x1) = span(0);
            for z in z0..=z1 {
                for y in y0..=y1 {
                    let shell = (dim == 3 && (z - c[2]).abs() == r) || (y - c[1]).abs() == r;
                    // A row on the ring's shell is in it whole; another row
                    // only at its two ends, where those lie in the grid.
                    let runs: [(i64, i64); 2] = if shell {
                        [(x0, x1), (1, 0)]
                    } else {
                        let end = |x: i64| {
                            if (0..self.dims[0]).contains(&x) {
                                (x, x)
                            } else {
                                (1, 0)
                            }
                        };
                        [end(c[0] - r), end(c[0] + r)]
                    };
                    for (a0, a1) in runs {
                        if a0 > a1 {
                            continue;
                        }
                        let a = self.start[self.linear([a0, y, z])] as usize;
                        let b = self.start[self.linear([a1, y, z]) + 1] as usize;
                        for j in (a..b).filter(|&j| j != except) {
                            let dx = self.xs[j] - q[0];
                            let dy = self.ys[j] - q[1];
                            let d2 = if dim == 3 {
                                let dz = self.zs[j] - q[2];
                                dx * dx + dy * dy + dz * dz
                            } else {
                                dx * dx + dy * dy
                            };
                            let id = self.ids[j];
                            if best.is_none_or(|(bd, bi, _)| (d2, id) < (bd, bi)) {
                                best = Some((d2, id, j));
                            }
                        }
                    }
                }
            }
            let covers = (0..dim).all(|k| c[k] - r <= 0 && c[k] + r >= self.dims[k] - 1);
            if covers {
                break;
            }
            r += 1;
        }
        best.map(|(d2, _, pos)| (pos as u32, d2.sqrt()))
    }
}

impl Grid {
    /// For every point of the grid (in the original order): the distance to
    /// its nearest other point (0 for a duplicate). In parallel over cells,
    /// one gathered neighbourhood per cell; a point with no other point
    /// within the grid's radius searches rings of cells outward
    /// ([`Grid::nearest_except`]). `None` only for a lone point. Needs a grid
    /// of radius-wide cells ([`Grid::new`]).
    pub fn nearest_others(&self, radius: f64) -> Vec<Option<f64>> {
        use rayon::prelude::*;
        let n_cells = self.start.len() - 1;
        let r2 = radius * radius;
        let parts: Vec<Vec<(u32, Option<f64>)>> = (0..n_cells.div_ceil(1024))
            .into_par_iter()
            .map(|block| {
                let mut out = Vec::new();
                let mut cand = Candidates::default();
                for c in block * 1024..((block + 1) * 1024).min(n_cells) {
                    let (a, b) = (self.start[c] as usize, self.start[c + 1] as usize);
                    if a == b {
                        continue;
                    }
                    let nx = self.dims[0] as usize;
                    let ny = self.dims[1] as usize;
                    let cell = [
                        (c % nx) as i64,
                        ((c / nx) % ny) as i64,
                        (c / (nx * ny)) as i64,
                    ];
                    self.gather(cell, &mut cand);
                    for k in a..b {
                        let q = [self.xs[k], self.ys[k], self.zs[k]];
                        let (mut first, mut second) = (f64::INFINITY, f64::INFINITY);
                        let n = cand.xs.len();
                        for j in 0..n {
                            let dx = cand.xs[j] - q[0];
                            let dy = cand.ys[j] - q[1];
                            let d2 = if self.dim == 3 {
                                let dz = cand.zs[j] - q[2];
                                dx * dx + dy * dy + dz * dz
                            } else {
                                dx * dx + dy * dy
                            };
                            if d2 < first {
                                second = first;
                                first = d2;
                            } else if d2 < second {
                                second = d2;
                            }
                        }
                        let d = if second <= r2 {
                            Some(second.sqrt())
                        } else {
                            self.nearest_except(q, k).map(|(_, d)| d)
                        };
                        out.push((self.ids[k], d));
                    }
                }
                out
            })
            .collect();
        let mut result = vec![None; self.ids.len()];
        for part in parts {
            for (i, d) in part {
                result[i as usize] = d;
            }
        }
        result
    }
}

/// The points around one cell, column-wise.
#[derive(Default)]
struct Candidates {
    xs: Vec<f64>,
    ys: Vec<f64>,
    zs: Vec<f64>,
}

impl Candidates {
    fn clear(&mut self) {
        self.xs.clear();
        self.ys.clear();
        self.zs.clear();
    }
}

/// The hits of [`Grid::collect`] (grid positions and squared distances,
/// `len` of the buffers in use) and the buffers of [`Grid::sorted`].
#[derive(Default)]
pub struct Hits {
    pos: Vec<u32>,
    d2: Vec<f64>,
    len: usize,
    d: Vec<f64>,
    bucket: Vec<u32>,
    counts: Vec<u32>,
    keys: Vec<u128>,
}

/// The grid positions `a..b` as blocks of LANES, the last one's lanes past
/// `b` marked invalid.
#[inline(always)]
fn split(mut at: u32, b: u32, out: &mut Vec<Block>) {
    while at < b {
        out.push(Block {
            at,
            valid: lanes(b - at),
        });
        at += LANES as u32;
    }
}

/// The valid-lane bits of a block whose run has `count` points from its
/// start: the first `min(count, LANES)` lanes.
#[inline(always)]
fn lanes(count: u32) -> u32 {
    (1u32 << count.min(LANES as u32)) - 1
}

/// Candidates tested together, in one loop the compiler vectorises (8 beat
/// 4 and 16 in `bench map`: a row of the mapper's cells holds about 7.5
/// points).
const LANES: usize = 8;

impl Hits {
    /// The hits of the last [`Grid::collect`] as (grid positions, squared
    /// distances), in the order collect found them: the stencil's rows in
    /// ascending order, each row's points in the grid's order, so ascending
    /// grid position. [`Grid::sorted`]'s distances are their square roots.
    #[inline(always)]
    pub fn in_grid_order(&self) -> (&[u32], &[f64]) {
        (&self.pos[..self.len], &self.d2[..self.len])
    }

    /// Tests the `blocks` of the padded columns `xs`, `ys`, `zs` (`zs`
    /// unread unless `d3`) against `q`: the squared distances of a block are
    /// computed together, then every lane is written and kept (the count
    /// advanced) only for a hit in a valid lane, without a branch. The lanes
    /// past a run read the following points or the padding.
    #[inline]
    fn test(
        &mut self,
        [xs, ys, zs]: [&[f64]; 3],
        d3: bool,
        blocks: &[Block],
        q: [f64; 3],
        r2: f64,
        simd: Option<Avx512>,
    ) {
        let need = (blocks.len() + 1) * LANES;
        if self.pos.len() < need {
            let size = need.next_power_of_two().max(256);
            self.pos.resize(size, 0);
            self.d2.resize(size, 0.0);
            self.bucket.resize(size, 0);
        }
        if let Some(simd) = simd {
            let cols = [xs, ys, zs];
            self.len = simd.test(cols, d3, blocks, q, r2, (&mut self.pos, &mut self.d2));
            return;
        }
        let mut len = 0;
        for &Block { at, valid } in blocks {
            let at = at as usize;
            let block = |col: &[f64]| -> [f64; LANES] {
                col[at..at + LANES].try_into().unwrap_or([f64::NAN; LANES])
            };
            let (x, y) = (block(xs), block(ys));
            let mut d2 = [0.0; LANES];
            // Σ (p_k − q_k)² in axis order, as kiddo and the brute force sum it.
            if d3 {
                let z = block(zs);
                for l in 0..LANES {
                    let (dx, dy, dz) = (x[l] - q[0], y[l] - q[1], z[l] - q[2]);
                    d2[l] = dx * dx + dy * dy + dz * dz;
                }
            } else {
                for l in 0..LANES {
                    let (dx, dy) = (x[l] - q[0], y[l] - q[1]);
                    d2[l] = dx * dx + dy * dy;
                }
            }
            let pos: &mut [u32; LANES] = (&mut self.pos[len..len + LANES]).try_into().unwrap();
            let d2s: &mut [f64; LANES] = (&mut self.d2[len..len + LANES]).try_into().unwrap();
            let mut k = 0;
            for (l, &v) in d2.iter().enumerate() {
                pos[k & (LANES - 1)] = (at + l) as u32;
                d2s[k & (LANES - 1)] = v;
                k += ((v <= r2) as u32 & (valid >> l)) as usize & 1;
            }
            len += k;
        }
        self.len = len;
    }

    /// Writes the hits to `out` as (position, distance), sorted by
    /// (distance, original index) (`ids`: original index per position; `r`:
    /// the search radius).
    ///
    /// A bucket pass first: the bucket is the fraction of the search ball
    /// (disc in 2D) inside the hit's distance, a monotone function of it, so
    /// hits of a uniform cloud spread about one per bucket and the insertion
    /// sort that follows only orders hits within a bucket. A crowded bucket
    /// (duplicates, clusters) falls back to a comparison sort.
    fn sort(&mut self, ids: &[u32], r: f64, dim: usize, out: &mut Vec<(u32, f64)>) {
        let n = self.len;
        self.d.clear();
        self.d.extend(self.d2[..n].iter().map(|v| v.sqrt()));
        let (d, d2, pos) = (&self.d[..n], &self.d2[..n], &self.pos[..n]);
        // One key per hit: the distance's bits (which order as the distance
        // does, the distance being non-negative), the original index, then
        // the hit, so that keys order exactly by (distance, index).
        let key = |k: usize| -> u128 {
            ((d[k].to_bits() as u128) << 64) | ((ids[pos[k] as usize] as u128) << 32) | k as u128
        };
        self.keys.clear();
        self.keys.resize(n, 0);
        self.counts.clear();
        self.counts.resize(2 * n + 1, 0);
        let (keys, counts, bucket) = (
            &mut self.keys[..],
            &mut self.counts[..],
            &mut self.bucket[..n],
        );
        let volume = if dim == 3 { r * r * r } else { r * r };
        let scale = (2 * n) as f64 / volume;
        let mut crowded = !(scale.is_finite() && n > 1);
        if !crowded {
            let last = (2 * n - 1) as f64;
            for k in 0..n {
                let f = if dim == 3 { d2[k] * d[k] } else { d2[k] };
                bucket[k] = (f * scale).min(last) as u32;
            }
            for &b in bucket.iter() {
                counts[b as usize] += 1;
            }
            // Exclusive prefix sums: the first slot of each bucket.
            let mut acc = 0;
            for c in counts.iter_mut() {
                crowded |= *c > MAX_BUCKET;
                let v = *c;
                *c = acc;
                acc += v;
            }
        }
        if crowded {
            for (k, slot) in keys.iter_mut().enumerate() {
                *slot = key(k);
            }
            keys.sort_unstable();
        } else {
            for (k, &b) in bucket.iter().enumerate() {
                let slot = &mut counts[b as usize];
                keys[*slot as usize] = key(k);
                *slot += 1;
            }
            // Insertion sort: the bucket order leaves inversions only within buckets.
            for i in 1..n {
                let x = keys[i];
                let mut j = i;
                while j > 0 && keys[j - 1] > x {
                    keys[j] = keys[j - 1];
                    j -= 1;
                }
                keys[j] = x;
            }
        }
        out.extend(keys.iter().map(|&key| {
            let k = key as u32 as usize;
            (pos[k], d[k])
        }));
    }
}

/// The most hits one bucket of [`Scratch::sort`] takes before it sorts by comparison.
const MAX_BUCKET: u32 = 16;
