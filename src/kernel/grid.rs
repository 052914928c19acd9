//! A uniform cell grid over a fixed point cloud, the mapper's fast neighbour
//! search, with cells one search radius wide. A query visits the rows of
//! cells (runs of cells along x, contiguous in the sorted columns) that the
//! sphere of the radius can reach, each row cut to the sphere's chord, and
//! tests every point of those rows in one branch-free loop over coordinate
//! columns. The hits are ordered by a bucket pass and an insertion sort
//! (`Scratch::sort`).
//! [`Grid::nearest_others`] instead gathers the 3^dim cells around a
//! cell once for all the points of that cell.
//!
//! Same contract as the k-d tree of `neighbours.rs` (which stays the reference):
//! physical radius in, `(index, distance)` out, inclusive, sorted by (distance,
//! index), distances computed as `sqrt(Σ (p_k − q_k)²)` in axis order, so both
//! give bit-identical lists. Like `neighbours.rs`, this file sees squared distances.

/// Points sorted by cell, coordinates stored column-wise.
pub struct Grid {
    dim: usize,
    origin: [f64; 3],
    cell: f64,
    inv_cell: f64,
    /// The search radius the grid was built for (queries may use less).
    radius: f64,
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
    /// Builds a grid of cells one `radius` wide, for searches up to `radius`
    /// (cells of half the radius fit the sphere closer but cost more rows per
    /// query: slower at the mapper's 20–100 nodes in reach). `dim` is 2 (z
    /// ignored) or 3.
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
        let mut radius = radius.abs();
        if !(radius.is_finite() && radius > 0.0) {
            radius = 0.0;
        }
        // A little wider than the radius, so that rounding in the cell index
        // never puts a point within the radius two cells away.
        let mut cell = radius * (1.0 + 1e-6);
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
            cell,
            inv_cell: 1.0 / cell,
            radius,
            dims,
            start: Vec::new(),
            xs: Vec::with_capacity(n),
            ys: Vec::with_capacity(n),
            zs: Vec::with_capacity(n),
            ids: Vec::with_capacity(n),
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

    /// The cells along axis `k` that points within `reach` of `q_k` can lie
    /// in, clamped to the grid (empty when `lo > hi`). `slack` (in cells)
    /// covers the rounding of the cell index.
    fn span(&self, k: usize, q_k: f64, reach: f64, slack: f64) -> (i64, i64) {
        let o = self.origin[k];
        let lo = ((q_k - reach) - o) * self.inv_cell - slack;
        let hi = ((q_k + reach) - o) * self.inv_cell + slack;
        // floor() by truncation: below zero only the sign matters (the span
        // is clamped to the grid), and `as` saturates above.
        let lo = if lo > 0.0 { lo as i64 } else { 0 };
        let hi = if hi >= 0.0 {
            (hi as i64).min(self.dims[k] - 1)
        } else {
            -1
        };
        (lo, hi)
    }

    /// The distance from `q_k` to cell `c` along axis `k`, rounded down by
    /// `slack` metres (0 inside the cell).
    fn gap(&self, k: usize, q_k: f64, c: i64, slack: f64) -> f64 {
        let a = self.origin[k] + c as f64 * self.cell;
        let b = a + self.cell;
        ((a - q_k).max(q_k - b) - slack).max(0.0)
    }

    /// All points within `radius` of `q` (inclusive) as (position in the
    /// grid's order, distance), sorted by distance then original index.
    /// `radius` is at most the grid's. A non-finite `q` finds nothing.
    pub fn query(&self, q: [f64; 3], radius: f64, out: &mut Vec<(u32, f64)>, s: &mut Scratch) {
        out.clear();
        s.clear();
        let dim = self.dim;
        if self.ids.is_empty() || q[..dim].iter().any(|v| !v.is_finite()) {
            return;
        }
        debug_assert!(radius.abs() <= self.radius * (1.0 + 1e-6) || self.radius == 0.0);
        let r2 = radius * radius;
        let r = radius.abs();
        // Rounding slack: relative to the coordinates' magnitude, in cells and metres.
        let mag = (0..dim)
            .map(|k| q[k].abs() + self.origin[k].abs())
            .fold(r, f64::max);
        let slack_m = 8.0 * f64::EPSILON * mag + 1e-9 * self.cell;
        let slack_c = slack_m * self.inv_cell + 1e-9;
        let (x0, x1) = self.span(0, q[0], r, slack_c);
        let (y0, y1) = self.span(1, q[1], r, slack_c);
        let (z0, z1) = if dim == 3 {
            self.span(2, q[2], r, slack_c)
        } else {
            (0, 0)
        };
        if x0 > x1 || y0 > y1 || z0 > z1 {
            return;
        }
        for z in z0..=z1 {
            let gz = if dim == 3 {
                self.gap(2, q[2], z, slack_m)
            } else {
                0.0
            };
            for y in y0..=y1 {
                let gy = self.gap(1, q[1], y, slack_m);
                let rem = r2 - gy * gy - gz * gz;
                if rem < 0.0 {
                    continue;
                }
                // The chord of the sphere along this row of cells.
                let (a0, a1) = self.span(0, q[0], rem.sqrt() + slack_m, slack_c);
                let (a0, a1) = (a0.max(x0), a1.min(x1));
                if a0 > a1 {
                    continue;
                }
                let a = self.start[self.linear([a0, y, z])] as usize;
                let b = self.start[self.linear([a1, y, z]) + 1] as usize;
                if dim == 3 {
                    s.test3(a..b, [&self.xs, &self.ys, &self.zs], q, r2);
                } else {
                    s.test2(a..b, [&self.xs, &self.ys], q, r2);
                }
            }
        }
        s.sort(&self.ids, r, dim, out);
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
        self.query(q, radius, out, &mut Scratch::default());
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

/// Reusable buffers of [`Grid::query`]: the hits found so far (position in
/// the grid's order and squared distance) and the sort keys.
#[derive(Default)]
pub struct Scratch {
    pos: Vec<u32>,
    d2: Vec<f64>,
    d: Vec<f64>,
    bucket: Vec<u32>,
    counts: Vec<u32>,
    keys: Vec<u64>,
    len: usize,
}

impl Scratch {
    fn clear(&mut self) {
        self.len = 0;
    }

    /// Room for `extra` more hits.
    #[inline]
    fn reserve(&mut self, extra: usize) {
        let need = self.len + extra;
        if self.pos.len() < need {
            let size = need.next_power_of_two().max(256);
            self.pos.resize(size, 0);
            self.d2.resize(size, 0.0);
            self.bucket.resize(size, 0);
        }
    }

    /// Tests the 3D points of `run`: every point's squared distance is
    /// written, and the slot is kept (the count advanced) only for a hit, so
    /// the loop has no branch to mispredict.
    #[inline]
    fn test3(
        &mut self,
        run: std::ops::Range<usize>,
        [xs, ys, zs]: [&[f64]; 3],
        q: [f64; 3],
        r2: f64,
    ) {
        let (a, b) = (run.start, run.end);
        self.reserve(b - a);
        let mut n = self.len;
        let (pos, d2s) = (&mut self.pos[..], &mut self.d2[..]);
        for (((j, &x), &y), &z) in (a..b).zip(&xs[a..b]).zip(&ys[a..b]).zip(&zs[a..b]) {
            // Σ (p_k − q_k)² in axis order, as kiddo and the brute force sum it.
            let (dx, dy, dz) = (x - q[0], y - q[1], z - q[2]);
            let d2 = dx * dx + dy * dy + dz * dz;
            pos[n] = j as u32;
            d2s[n] = d2;
            n += (d2 <= r2) as usize;
        }
        self.len = n;
    }

    /// [`Scratch::test3`] in 2D.
    #[inline]
    fn test2(&mut self, run: std::ops::Range<usize>, [xs, ys]: [&[f64]; 2], q: [f64; 3], r2: f64) {
        let (a, b) = (run.start, run.end);
        self.reserve(b - a);
        let mut n = self.len;
        let (pos, d2s) = (&mut self.pos[..], &mut self.d2[..]);
        for ((j, &x), &y) in (a..b).zip(&xs[a..b]).zip(&ys[a..b]) {
            let (dx, dy) = (x - q[0], y - q[1]);
            let d2 = dx * dx + dy * dy;
            pos[n] = j as u32;
            d2s[n] = d2;
            n += (d2 <= r2) as usize;
        }
        self.len = n;
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
        if n > 1 << LOW_BITS {
            out.extend((0..n).map(|k| (pos[k], d[k])));
            out.sort_unstable_by_key(|&(p, d)| (d.to_bits(), ids[p as usize]));
            return;
        }
        // One u64 key per hit: the distance's bits with the lowest LOW_BITS
        // replaced by the hit (the bits of a non-negative distance order as
        // the distance does); hits whose truncated keys tie are put in exact
        // (distance, index) order at the end.
        let key = |k: usize| d[k].to_bits() & !LOW_MASK | k as u64;
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
            let last = 2 * n - 1;
            for k in 0..n {
                let f = if dim == 3 { d2[k] * d[k] } else { d2[k] };
                let b = ((f * scale) as usize).min(last);
                bucket[k] = b as u32;
                counts[b] += 1;
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
            let k = (key & LOW_MASK) as usize;
            (pos[k], d[k])
        }));
        let mut start = 0;
        while start < n {
            let trunc = keys[start] & !LOW_MASK;
            let mut end = start + 1;
            while end < n && keys[end] & !LOW_MASK == trunc {
                end += 1;
            }
            if end - start > 1 {
                out[start..end].sort_unstable_by_key(|&(p, d)| (d.to_bits(), ids[p as usize]));
            }
            start = end;
        }
    }
}

/// Low bits of a sort key that carry the hit (see [`Scratch::sort`]).
const LOW_BITS: u32 = 12;
const LOW_MASK: u64 = (1 << LOW_BITS) - 1;

/// The most hits one bucket of [`Scratch::sort`] takes before it sorts by comparison.
const MAX_BUCKET: u32 = 16;

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
