//! A uniform cell grid over a fixed point cloud, the mapper's fast neighbour
//! search: cells at least one search radius wide, so the points within the
//! radius of a query lie in its cell and the 3^dim cells around it. Queries that
//! share a cell share one gathered candidate list ([`Candidates`]), whose
//! distances are computed in a tight loop over coordinate columns.
//!
//! Same contract as the k-d tree of `neighbours.rs` (which stays the reference):
//! physical radius in, `(index, distance)` out, inclusive, sorted by (distance,
//! index), distances computed as `sqrt(Σ (p_k − q_k)²)` in axis order, so both
//! give bit-identical lists. Like `neighbours.rs`, this file sees squared distances.

/// Points sorted by cell, coordinates stored column-wise.
pub struct Grid {
    dim: usize,
    origin: [f64; 3],
    inv_cell: f64,
    /// Cells per axis (1 along z in 2D).
    dims: [i64; 3],
    /// Start of each cell's points in the sorted columns (length cells + 1).
    start: Vec<u32>,
    xs: Vec<f64>,
    ys: Vec<f64>,
    zs: Vec<f64>,
    /// Original index of each sorted point.
    ids: Vec<u32>,
}

/// Cell coordinates of a query (may lie outside the grid by any amount).
pub type Cell = [i64; 3];

impl Grid {
    /// Builds a grid for searches up to `radius` (> 0). `dim` is 2 (z ignored) or 3.
    pub fn new(points: &[[f64; 3]], dim: usize, radius: f64) -> Grid {
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
        // A little wider than the radius, so that rounding in the cell index
        // never puts a point within the radius two cells away.
        let mut cell = radius.abs() * (1.0 + 1e-6);
        if !(cell.is_finite() && cell > 0.0) {
            cell = 1.0;
        }
        // Keep the cell count near the point count (a tiny radius in a wide cloud).
        let max_cells = (4 * n + 64) as f64;
        loop {
            let count: f64 = (0..dim)
                .map(|k| ((hi[k] - lo[k]) / cell).floor() + 1.0)
                .product();
            if count <= max_cells {
                break;
            }
            cell *= (count / max_cells).powf(1.0 / dim as f64).max(1.01);
        }
        let mut dims = [1i64; 3];
        for k in 0..dim {
            dims[k] = ((hi[k] - lo[k]) / cell).floor() as i64 + 1;
        }
        let mut grid = Grid {
            dim,
            origin: lo,
            inv_cell: 1.0 / cell,
            dims,
            start: Vec::new(),
            xs: Vec::with_capacity(n),
            ys: Vec::with_capacity(n),
            zs: Vec::with_capacity(n),
            ids: Vec::with_capacity(n),
        };
        let n_cells = (dims[0] * dims[1] * dims[2]) as usize;
        let cell_of: Vec<u32> = points
            .iter()
            .map(|p| grid.linear(grid.cell(*p)) as u32)
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
        grid.ids = order;
        grid.start = start;
        grid
    }

    /// The cell of `q`, clamped to one cell outside the grid (those see the border).
    pub fn cell(&self, q: [f64; 3]) -> Cell {
        let mut c = [0i64; 3];
        for (k, ck) in c.iter_mut().enumerate().take(self.dim) {
            let f = ((q[k] - self.origin[k]) * self.inv_cell).floor();
            *ck = if f.is_nan() {
                -2
            } else {
                (f.clamp(-2.0, self.dims[k] as f64 + 1.0)) as i64
            };
        }
        c
    }

    fn linear(&self, c: Cell) -> usize {
        ((c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]) as usize
    }

    /// The original index of each point in the grid's (cell) order.
    pub fn order(&self) -> &[u32] {
        &self.ids
    }

    /// Gathers the points of `cell` and its neighbours into `out`, with their
    /// rows of `rows` (`width` values per point, in the grid's order, see
    /// [`Grid::order`]; empty for none).
    pub fn gather(&self, cell: Cell, rows: &[f64], width: usize, out: &mut Candidates) {
        out.clear();
        out.dim = self.dim;
        out.width = width;
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
                out.ids.extend_from_slice(&self.ids[a..b]);
                if !rows.is_empty() {
                    out.rows.extend_from_slice(&rows[a * width..b * width]);
                }
            }
        }
    }

    /// All points within `radius` of `q` (inclusive) as (index, distance),
    /// sorted by distance then index; `radius` at most the grid's. A
    /// convenience for single queries; the mapper gathers once per cell.
    pub fn within(&self, q: [f64; 3], radius: f64, out: &mut Vec<(u32, f64)>) {
        let mut c = Candidates::default();
        self.gather(self.cell(q), &[], 0, &mut c);
        c.within(q, radius, out);
        for e in out.iter_mut() {
            e.0 = c.ids[e.0 as usize];
        }
    }
}

impl Grid {
    /// For every point of the grid (in the original order): the distance to
    /// its second-nearest point (its nearest other point; 0 for a duplicate)
    /// when that lies within the grid's radius, else `None`. In parallel over
    /// cells, one gathered neighbourhood per cell.
    pub fn second_nearest_within(&self, radius: f64) -> Vec<Option<f64>> {
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
                    self.gather(cell, &[], 0, &mut cand);
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
                        out.push((self.ids[k], (second <= r2).then(|| second.sqrt())));
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
pub struct Candidates {
    dim: usize,
    xs: Vec<f64>,
    ys: Vec<f64>,
    zs: Vec<f64>,
    ids: Vec<u32>,
    /// `width` values per candidate.
    rows: Vec<f64>,
    width: usize,
    d2: Vec<f64>,
    keys: Vec<u64>,
}

/// Low bits of a sort key that carry the candidate (see [`Candidates::within`]).
const LOW_BITS: u32 = 12;
const LOW_MASK: u64 = (1 << LOW_BITS) - 1;

impl Candidates {
    fn clear(&mut self) {
        self.xs.clear();
        self.ys.clear();
        self.zs.clear();
        self.ids.clear();
        self.rows.clear();
    }

    /// The row of candidate `k` (see [`Grid::gather`]).
    #[inline]
    pub fn row(&self, k: u32) -> &[f64] {
        let k = k as usize;
        &self.rows[k * self.width..(k + 1) * self.width]
    }

    /// The candidates within `radius` of `q` (inclusive) as (candidate,
    /// distance), sorted by distance then the point's original index. `out` is
    /// cleared first.
    pub fn within(&mut self, q: [f64; 3], radius: f64, out: &mut Vec<(u32, f64)>) {
        out.clear();
        let r2 = radius * radius;
        let n = self.xs.len();
        self.d2.resize(n, 0.0);
        // Σ (p_k − q_k)² in axis order, as kiddo and the brute force sum it.
        if self.dim == 3 {
            for (((d, &x), &y), &z) in self.d2.iter_mut().zip(&self.xs).zip(&self.ys).zip(&self.zs)
            {
                let (dx, dy, dz) = (x - q[0], y - q[1], z - q[2]);
                *d = dx * dx + dy * dy + dz * dz;
            }
        } else {
            for ((d, &x), &y) in self.d2.iter_mut().zip(&self.xs).zip(&self.ys) {
                let (dx, dy) = (x - q[0], y - q[1]);
                *d = dx * dx + dy * dy;
            }
        }
        if n <= 1 << LOW_BITS {
            // One u64 key per hit: the distance's bits with the lowest
            // LOW_BITS replaced by the candidate (the bits of a non-negative
            // distance order as the distance does). Hits whose truncated
            // distances tie are then ordered exactly by (distance, index).
            self.keys.clear();
            for (k, &d2) in self.d2.iter().enumerate() {
                if d2 <= r2 {
                    let d = d2.sqrt().to_bits();
                    self.keys.push(d & !LOW_MASK | k as u64);
                }
            }
            self.keys.sort_unstable();
            out.extend(self.keys.iter().map(|&key| {
                let k = (key & LOW_MASK) as u32;
                (k, self.d2[k as usize].sqrt())
            }));
            let mut start = 0;
            while start < out.len() {
                let trunc = self.keys[start] & !LOW_MASK;
                let mut end = start + 1;
                while end < out.len() && self.keys[end] & !LOW_MASK == trunc {
                    end += 1;
                }
                if end - start > 1 {
                    let ids = &self.ids;
                    out[start..end].sort_unstable_by_key(|&(k, d)| (d.to_bits(), ids[k as usize]));
                }
                start = end;
            }
        } else {
            for (k, &d2) in self.d2.iter().enumerate() {
                if d2 <= r2 {
                    out.push((k as u32, d2.sqrt()));
                }
            }
            let ids = &self.ids;
            out.sort_unstable_by_key(|&(k, d)| (d.to_bits(), ids[k as usize]));
        }
    }
}

/// Interleaves the bits of a cell's coordinates (21 bits each) into a Z-order key.
pub fn morton(c: Cell) -> u64 {
    let spread = |v: i64| -> u64 {
        let mut v = (v + 2).clamp(0, (1 << 21) - 1) as u64;
        v = (v | (v << 32)) & 0x1f00000000ffff;
        v = (v | (v << 16)) & 0x1f0000ff0000ff;
        v = (v | (v << 8)) & 0x100f00f00f00f00f;
        v = (v | (v << 4)) & 0x10c30c30c30c30c3;
        v = (v | (v << 2)) & 0x1249249249249249;
        v
    };
    spread(c[0]) | (spread(c[1]) << 1) | (spread(c[2]) << 2)
}
