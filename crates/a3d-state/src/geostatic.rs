//! Geostatic total stress from the overburden along the vertical (y up).
//!
//! For an MP at p, the vertical line through p is intersected with every active
//! element above it; the total vertical stress is σv = −Σ γ·Δy over those
//! segments, with γ evaluated at sub-segment midpoints (γ may vary with the pore
//! pressure through the degree of saturation). The ground surface is therefore
//! the top of the active mesh along the vertical; gaps in the mesh carry no
//! weight. Horizontal total stress: σh = K0·σ'v + S·p with σ'v = σv − S·p, on xx
//! and zz (and yy in 3D stays vertical); shears are zero.
//!
//! [`overburden`] evaluates the column integral with γ constant per element
//! (the caller averages γ over [`element_samples`]). In 2D it is a sweep from the
//! top down, O((N + E) log N) time and linear memory for N points and E elements:
//! an element entirely above the sweep line adds γ·h(x) (its chord length, linear
//! between its vertices' x) to a Fenwick tree over the points' x; the elements
//! the sweep line cuts are found in a uniform grid and add their partial chord.
//! In 3D each point walks its own column (linear memory, time O(N · column)).
//! A vertical face shared by two elements counts once: the line belongs to the
//! element on its +x side (half-open rule).

use rayon::prelude::*;

use a3d_model::Mesh;

/// One piece of a vertical column above a point: the element it lies in, its
/// midpoint, and its height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub element: u32,
    pub midpoint: [f64; 3],
    pub dy: f64,
}

/// Samples of the column above each query point, in CSR layout.
#[derive(Clone, Debug, Default)]
pub struct Columns {
    /// `offsets[i]..offsets[i+1]` indexes `samples` for point i.
    pub offsets: Vec<usize>,
    pub samples: Vec<Sample>,
}

/// Elements binned by their horizontal extent, for vertical-ray queries.
pub struct VerticalIndex<'m> {
    mesh: &'m Mesh,
    lo: [f64; 2],
    cell: f64,
    n: [usize; 2],
    bins: Vec<Vec<u32>>,
}

fn horizontal(p: &[f64; 3], three_d: bool) -> [f64; 2] {
    if three_d { [p[0], p[2]] } else { [p[0], 0.0] }
}

impl<'m> VerticalIndex<'m> {
    /// Indexes the elements for which `active(e)` holds.
    pub fn new(mesh: &'m Mesh, active: impl Fn(usize) -> bool) -> VerticalIndex<'m> {
        let three_d = mesh.dimension.n_dim() == 3;
        let (lo3, hi3) = mesh.bounding_box();
        let lo = horizontal(&lo3, three_d);
        let hi = horizontal(&hi3, three_d);
        let n_el = mesh.n_elements().max(1);
        // Spans at most the largest double (±1e308 apart is infinite).
        let span = [
            (hi[0] - lo[0]).clamp(1e-12, f64::MAX),
            (hi[1] - lo[1]).clamp(1e-12, f64::MAX),
        ];
        let mut cell = if three_d {
            let area = span[0] * span[1];
            if area.is_finite() {
                (area / n_el as f64).sqrt().max(1e-12) * 2.0
            } else {
                // Square roots of each span: their product cannot overflow.
                span[0].sqrt() * span[1].sqrt() / (n_el as f64).sqrt() * 2.0
            }
        } else {
            span[0] / (n_el as f64).sqrt().max(1.0)
        };
        // Never more than 4 bins per element along an axis (a stretched box,
        // one node far from the rest), and no more bin entries than a budget
        // proportional to the elements: memory O(elements) whatever the
        // coordinates. Neither binds on an ordinary mesh.
        cell = cell.max(span[0].max(span[1]) / (4.0 * n_el as f64));
        let boxes: Vec<Option<([f64; 2], [f64; 2])>> = (0..mesh.n_elements())
            .map(|e| {
                active(e).then(|| {
                    let mut emin = [f64::INFINITY; 2];
                    let mut emax = [f64::NEG_INFINITY; 2];
                    for c in mesh
                        .corner_coords(e)
                        .iter()
                        .take(mesh.element_type.n_corners())
                    {
                        let h = horizontal(c, three_d);
                        for k in 0..2 {
                            emin[k] = emin[k].min(h[k]);
                            emax[k] = emax[k].max(h[k]);
                        }
                    }
                    (emin, emax)
                })
            })
            .collect();
        let budget = 32 * n_el as u64 + 1024;
        let (n, clamp) = loop {
            let n = [
                ((span[0] / cell).ceil() as usize).max(1),
                if three_d {
                    ((span[1] / cell).ceil() as usize).max(1)
                } else {
                    1
                },
            ];
            let clamp = move |v: f64, k: usize| {
                (((v - lo[k]) / cell).floor().max(0.0) as usize).min(n[k] - 1)
            };
            let entries: u64 = boxes
                .iter()
                .flatten()
                .map(|(a, b)| {
                    let w = |k: usize| (clamp(b[k], k) - clamp(a[k], k) + 1) as u64;
                    w(0).saturating_mul(w(1))
                })
                .fold(0u64, u64::saturating_add);
            if entries <= budget || n == [1, 1] {
                break (n, clamp);
            }
            cell *= 2.0;
        };
        let mut bins = vec![Vec::new(); n[0] * n[1]];
        for (e, b) in boxes.iter().enumerate() {
            let Some((emin, emax)) = b else {
                continue;
            };
            for i in clamp(emin[0], 0)..=clamp(emax[0], 0) {
                for j in clamp(emin[1], 1)..=clamp(emax[1], 1) {
                    bins[j * n[0] + i].push(e as u32);
                }
            }
        }
        VerticalIndex {
            mesh,
            lo,
            cell,
            n,
            bins,
        }
    }

    /// The y-interval where the vertical line through `p` crosses element `e`.
    fn crossing(&self, e: usize, p: &[f64; 3]) -> Option<(f64, f64)> {
        let mesh = self.mesh;
        let c = mesh.corner_coords(e);
        let (mut y_lo, mut y_hi) = (f64::NEG_INFINITY, f64::INFINITY);
        let eps = 1e-12;
        // Each face (edge in 2D) gives a half-space a·x + b·y + c·z ≤ d containing
        // the element; on the line x = p.x, z = p.z it bounds y.
        let mut clip = |normal: [f64; 3], point: [f64; 3], inside: [f64; 3]| -> bool {
            let side = |q: [f64; 3]| (0..3).map(|k| normal[k] * (q[k] - point[k])).sum::<f64>();
            let sign = if side(inside) > 0.0 { -1.0 } else { 1.0 };
            let nn = [normal[0] * sign, normal[1] * sign, normal[2] * sign];
            // nn·(x − point) ≤ 0 inside.
            let rest = nn[0] * (p[0] - point[0]) + nn[2] * (p[2] - point[2]);
            let scale = nn.iter().map(|v| v.abs()).fold(0.0, f64::max).max(1e-300);
            if nn[1].abs() <= eps * scale {
                // The face is vertical. A line lying in it belongs to the element on
                // its +x side only (half-open rule), so shared faces count once.
                let tol = eps * scale * self.cell;
                return rest < -tol
                    || (rest <= tol && (nn[0] < 0.0 || (nn[0] == 0.0 && nn[2] < 0.0)));
            }
            let bound = point[1] - rest / nn[1];
            if nn[1] > 0.0 {
                y_hi = y_hi.min(bound);
            } else {
                y_lo = y_lo.max(bound);
            }
            true
        };
        let nc = mesh.element_type.n_corners();
        let centroid = {
            let mut s = [0.0; 3];
            for q in c.iter().take(nc) {
                for k in 0..3 {
                    s[k] += q[k] / nc as f64;
                }
            }
            s
        };
        // Each face (edge in 2D) bounds the element by the plane through its
        // first corners (its edge's line in 2D).
        let ok = mesh.element_type.faces().iter().all(|f| {
            if mesh.dimension.n_dim() == 2 {
                let (a, b) = (c[f[0]], c[f[1]]);
                return clip([-(b[1] - a[1]), b[0] - a[0], 0.0], a, centroid);
            }
            let (a, b, cc) = (c[f[0]], c[f[1]], c[f[2]]);
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [cc[0] - a[0], cc[1] - a[1], cc[2] - a[2]];
            let nrm = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            clip(nrm, a, centroid)
        });
        (ok && y_hi > y_lo).then_some((y_lo, y_hi))
    }

    /// Samples of the column above `p` (from p.y up), `sub` midpoints per element crossing.
    pub fn column_above(&self, p: &[f64; 3], sub: usize, out: &mut Vec<Sample>) {
        let three_d = self.mesh.dimension.n_dim() == 3;
        let h = horizontal(p, three_d);
        let i = (((h[0] - self.lo[0]) / self.cell).floor().max(0.0) as usize).min(self.n[0] - 1);
        let j = (((h[1] - self.lo[1]) / self.cell).floor().max(0.0) as usize).min(self.n[1] - 1);
        for &e in &self.bins[j * self.n[0] + i] {
            let Some((lo, hi)) = self.crossing(e as usize, p) else {
                continue;
            };
            let lo = lo.max(p[1]);
            if hi <= lo {
                continue;
            }
            let dy = (hi - lo) / sub as f64;
            for k in 0..sub {
                let y = lo + (k as f64 + 0.5) * dy;
                out.push(Sample {
                    element: e,
                    midpoint: [p[0], y, p[2]],
                    dy,
                });
            }
        }
    }

    /// Columns above every point.
    pub fn columns(&self, points: &[[f64; 3]], sub: usize) -> Columns {
        let mut cols = Columns {
            offsets: Vec::with_capacity(points.len() + 1),
            samples: Vec::new(),
        };
        cols.offsets.push(0);
        for p in points {
            self.column_above(p, sub, &mut cols.samples);
            cols.offsets.push(cols.samples.len());
        }
        cols
    }
}

/// Total vertical stress (negative, compression) at each point from its column,
/// with `gamma[s]` the unit weight (kN/m³) at sample s.
pub fn vertical_stress(columns: &Columns, gamma: &[f64]) -> Vec<f64> {
    (0..columns.offsets.len() - 1)
        .map(|i| {
            let r = columns.offsets[i]..columns.offsets[i + 1];
            -columns.samples[r.clone()]
                .iter()
                .zip(&gamma[r])
                .map(|(s, g)| g * s.dy)
                .sum::<f64>()
        })
        .collect()
}

/// Points where the caller evaluates γ for each active element: the centroid and
/// the midpoints between the centroid and each corner. Returns the points and the
/// element of each; average γ over an element's points for [`overburden`].
pub fn element_samples(mesh: &Mesh, active: impl Fn(usize) -> bool) -> (Vec<[f64; 3]>, Vec<u32>) {
    let nc = mesh.element_type.n_corners();
    let mut points = Vec::new();
    let mut elements = Vec::new();
    for e in 0..mesh.n_elements() {
        if !active(e) {
            continue;
        }
        let c = mesh.corner_coords(e);
        let mut centroid = [0.0; 3];
        for q in c.iter().take(nc) {
            for k in 0..3 {
                centroid[k] += q[k] / nc as f64;
            }
        }
        points.push(centroid);
        elements.push(e as u32);
        for q in c.iter().take(nc) {
            points.push([
                0.5 * (centroid[0] + q[0]),
                0.5 * (centroid[1] + q[1]),
                0.5 * (centroid[2] + q[2]),
            ]);
            elements.push(e as u32);
        }
    }
    (points, elements)
}

/// Total vertical stress (negative, compression) at each point: −∫ γ dy over the
/// active elements above it, with `gamma[e]` (kN/m³) constant per element.
pub fn overburden(
    mesh: &Mesh,
    active: impl Fn(usize) -> bool + Sync,
    gamma: &[f64],
    points: &[[f64; 3]],
) -> Vec<f64> {
    if mesh.dimension.n_dim() == 2 {
        return overburden_2d(mesh, &active, gamma, points);
    }
    let index = VerticalIndex::new(mesh, &active);
    points
        .par_iter()
        .map_init(Vec::new, |buf, p| {
            buf.clear();
            index.column_above(p, 1, buf);
            -buf.iter()
                .map(|s| gamma.get(s.element as usize).copied().unwrap_or(0.0) * s.dy)
                .sum::<f64>()
        })
        .collect()
}

/// The y-interval of a convex polygon on the vertical line at `x`.
fn chord(poly: &[[f64; 3]], x: f64) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (x0, x1) = (a[0].min(b[0]), a[0].max(b[0]));
        if x < x0 || x > x1 {
            continue;
        }
        if a[0] == b[0] {
            lo = lo.min(a[1].min(b[1]));
            hi = hi.max(a[1].max(b[1]));
        } else {
            let y = a[1] + (x - a[0]) * (b[1] - a[1]) / (b[0] - a[0]);
            lo = lo.min(y);
            hi = hi.max(y);
        }
    }
    (hi > lo).then_some((lo, hi))
}

/// Range-add, point-query Fenwick tree of linear functions a + b·x.
struct LinearFenwick {
    a: Vec<f64>,
    b: Vec<f64>,
}

impl LinearFenwick {
    fn new(n: usize) -> LinearFenwick {
        LinearFenwick {
            a: vec![0.0; n + 1],
            b: vec![0.0; n + 1],
        }
    }

    fn add_at(&mut self, i: usize, a: f64, b: f64) {
        let mut i = i + 1;
        while i < self.a.len() {
            self.a[i] += a;
            self.b[i] += b;
            i += i & i.wrapping_neg();
        }
    }

    /// Adds a + b·x to the positions `lo..hi`.
    fn range_add(&mut self, lo: usize, hi: usize, a: f64, b: f64) {
        if lo < hi {
            self.add_at(lo, a, b);
            self.add_at(hi, -a, -b);
        }
    }

    fn value(&self, i: usize, x: f64) -> f64 {
        let (mut a, mut b) = (0.0, 0.0);
        let mut i = i + 1;
        while i > 0 {
            a += self.a[i];
            b += self.b[i];
            i -= i & i.wrapping_neg();
        }
        a + b * x
    }
}

struct Element2d {
    e: usize,
    poly: Vec<[f64; 3]>,
    lo: [f64; 2],
    hi: [f64; 2],
}

fn overburden_2d(
    mesh: &Mesh,
    active: &(impl Fn(usize) -> bool + Sync),
    gamma: &[f64],
    points: &[[f64; 3]],
) -> Vec<f64> {
    let nc = mesh.element_type.n_corners();
    let elements: Vec<Element2d> = (0..mesh.n_elements())
        .filter(|&e| active(e) && gamma.get(e).is_some_and(|g| *g != 0.0))
        .map(|e| {
            let poly: Vec<[f64; 3]> = mesh.corner_coords(e)[..nc].to_vec();
            let mut lo = [f64::INFINITY; 2];
            let mut hi = [f64::NEG_INFINITY; 2];
            for q in &poly {
                for k in 0..2 {
                    lo[k] = lo[k].min(q[k]);
                    hi[k] = hi[k].max(q[k]);
                }
            }
            Element2d { e, poly, lo, hi }
        })
        .filter(|el| el.hi[0] > el.lo[0] && el.hi[1] > el.lo[1])
        .collect();
    let mut xs: Vec<f64> = points.iter().map(|p| p[0]).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let slot = |x: f64| xs.partition_point(|&v| v < x);
    let grid = StraddleGrid::new(&elements);
    let mut by_top: Vec<usize> = (0..elements.len()).collect();
    by_top.sort_by(|&i, &j| elements[j].lo[1].total_cmp(&elements[i].lo[1]));
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&i, &j| points[j][1].total_cmp(&points[i][1]));
    let mut tree = LinearFenwick::new(xs.len());
    let mut next = 0;
    let mut out = vec![0.0; points.len()];
    let mut breaks: Vec<f64> = Vec::with_capacity(8);
    for &i in &order {
        let p = points[i];
        // Every element entirely above the sweep line adds its whole chord.
        while next < by_top.len() && elements[by_top[next]].lo[1] >= p[1] {
            let el = &elements[by_top[next]];
            next += 1;
            let g = gamma[el.e];
            breaks.clear();
            breaks.extend(el.poly.iter().map(|q| q[0]));
            breaks.sort_by(f64::total_cmp);
            breaks.dedup();
            for w in breaks.windows(2) {
                let (xa, xb) = (w[0], w[1]);
                // The chord is linear on (xa, xb): two inner values give it.
                let (t1, t2) = (xa + (xb - xa) / 3.0, xa + 2.0 * (xb - xa) / 3.0);
                let h1 = chord(&el.poly, t1).map_or(0.0, |(l, h)| h - l);
                let h2 = chord(&el.poly, t2).map_or(0.0, |(l, h)| h - l);
                let slope = (h2 - h1) / (t2 - t1);
                let intercept = h1 - slope * t1;
                tree.range_add(slot(xa), slot(xb), g * intercept, g * slope);
            }
        }
        let k = slot(p[0]);
        let mut total = tree.value(k, p[0]);
        // Elements the sweep line cuts: the part of their chord above the point.
        for &j in grid.candidates(p[0], p[1]) {
            let el = &elements[j as usize];
            if !(el.lo[1] < p[1] && p[1] < el.hi[1] && el.lo[0] <= p[0] && p[0] < el.hi[0]) {
                continue;
            }
            if let Some((lo, hi)) = chord(&el.poly, p[0]) {
                let dy = hi - lo.max(p[1]);
                if dy > 0.0 {
                    total += gamma[el.e] * dy;
                }
            }
        }
        out[i] = -total;
    }
    out
}

/// Elements binned by bounding box on a uniform grid, for "which elements may
/// contain this point" queries. The cell grows until the bins hold at most 32
/// entries per element, so memory stays linear on any mesh.
struct StraddleGrid {
    lo: [f64; 2],
    cell: f64,
    n: [usize; 2],
    offsets: Vec<usize>,
    items: Vec<u32>,
}

impl StraddleGrid {
    fn new(elements: &[Element2d]) -> StraddleGrid {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        let mut size = 0.0;
        for el in elements {
            for k in 0..2 {
                lo[k] = lo[k].min(el.lo[k]);
                hi[k] = hi[k].max(el.hi[k]);
            }
            size += (el.hi[0] - el.lo[0]) + (el.hi[1] - el.lo[1]);
        }
        if elements.is_empty() || !(hi[0] - lo[0]).is_finite() || !(hi[1] - lo[1]).is_finite() {
            return StraddleGrid {
                lo: [0.0; 2],
                cell: 1.0,
                n: [1, 1],
                offsets: vec![0, 0],
                items: Vec::new(),
            };
        }
        let span = [(hi[0] - lo[0]).max(1e-300), (hi[1] - lo[1]).max(1e-300)];
        let mut cell = (size / (2 * elements.len()) as f64).max(span[0].max(span[1]) / 4096.0);
        let budget = 32 * elements.len() + 1024;
        loop {
            let n = [
                ((span[0] / cell).ceil() as usize).clamp(1, 4096),
                ((span[1] / cell).ceil() as usize).clamp(1, 4096),
            ];
            let range = |el: &Element2d, k: usize| {
                let a = (((el.lo[k] - lo[k]) / cell).floor().max(0.0) as usize).min(n[k] - 1);
                let b = (((el.hi[k] - lo[k]) / cell).floor().max(0.0) as usize).min(n[k] - 1);
                a..=b
            };
            let entries: usize = elements
                .iter()
                .map(|el| range(el, 0).count() * range(el, 1).count())
                .sum();
            if entries > budget && (n[0] > 1 || n[1] > 1) {
                cell *= 2.0;
                continue;
            }
            let mut counts = vec![0usize; n[0] * n[1] + 1];
            for el in elements {
                for j in range(el, 1) {
                    for i in range(el, 0) {
                        counts[j * n[0] + i + 1] += 1;
                    }
                }
            }
            for c in 1..counts.len() {
                counts[c] += counts[c - 1];
            }
            let mut fill = counts.clone();
            let mut items = vec![0u32; entries];
            for (k, el) in elements.iter().enumerate() {
                for j in range(el, 1) {
                    for i in range(el, 0) {
                        let c = j * n[0] + i;
                        items[fill[c]] = k as u32;
                        fill[c] += 1;
                    }
                }
            }
            return StraddleGrid {
                lo,
                cell,
                n,
                offsets: counts,
                items,
            };
        }
    }

    fn candidates(&self, x: f64, y: f64) -> &[u32] {
        let i = ((x - self.lo[0]) / self.cell).floor();
        let j = ((y - self.lo[1]) / self.cell).floor();
        if !(i >= 0.0 && j >= 0.0) || i as usize >= self.n[0] || j as usize >= self.n[1] {
            return &[];
        }
        let c = j as usize * self.n[0] + i as usize;
        &self.items[self.offsets[c]..self.offsets[c + 1]]
    }
}

/// Total stress tensor from σv, K0, pwp and S: σ'v = σv − S·p, σ'h = K0·σ'v,
/// σh = σ'h + S·p on xx and zz, σyy = σv, shears zero.
pub fn geostatic_tensor(sigma_v: f64, k0: f64, pwp: f64, saturation: f64) -> [f64; 6] {
    let eff_v = sigma_v - saturation * pwp;
    let sigma_h = k0 * eff_v + saturation * pwp;
    [sigma_h, sigma_v, sigma_h, 0.0, 0.0, 0.0]
}

#[cfg(test)]
mod tests {
    use super::*;
    use a3d_testkit::generate;

    #[test]
    fn column_above_a_point_in_a_block_has_the_block_height() {
        let mesh = generate::structured_tri_mesh(0.0, 0.0, 4.0, 10.0, 4, 10);
        let index = VerticalIndex::new(&mesh, |_| true);
        for (x, y) in [(0.3, 0.2), (2.0, 5.0), (3.9, 9.5), (1.0, 3.0)] {
            let mut out = Vec::new();
            index.column_above(&[x, y, 0.0], 2, &mut out);
            let total: f64 = out.iter().map(|s| s.dy).sum();
            assert!((total - (10.0 - y)).abs() < 1e-9, "x={x} y={y}: {total}");
        }
    }

    #[test]
    fn column_in_a_tet_box_has_the_box_height() {
        let mesh = generate::structured_tet_mesh(2.0, 0.0, 3.0, 2.0, 2, 3, 2);
        let index = VerticalIndex::new(&mesh, |_| true);
        for p in [[0.3, 0.2, 0.7], [1.37, 1.5, 1.11], [1.9, 2.9, 0.05]] {
            let mut out = Vec::new();
            index.column_above(&p, 1, &mut out);
            let total: f64 = out.iter().map(|s| s.dy).sum();
            assert!((total - (3.0 - p[1])).abs() < 1e-9, "{p:?}: {total}");
        }
    }

    /// The old per-point column walk, as the oracle of [`overburden`].
    fn brute_force(mesh: &Mesh, gamma: &[f64], points: &[[f64; 3]]) -> Vec<f64> {
        let index = VerticalIndex::new(mesh, |_| true);
        points
            .iter()
            .map(|p| {
                let mut out = Vec::new();
                index.column_above(p, 1, &mut out);
                -out.iter()
                    .map(|s| gamma[s.element as usize] * s.dy)
                    .sum::<f64>()
            })
            .collect()
    }

    #[test]
    fn sweep_equals_the_column_walk_on_a_distorted_mesh() {
        use rand::{RngExt, SeedableRng};
        let mut mesh = generate::structured_tri_mesh(0.0, 0.0, 6.0, 4.0, 12, 8);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for p in &mut mesh.nodes {
            // A sloping top and jiggled interior nodes, still counter-clockwise.
            p[1] *= 1.0 - 0.05 * p[0];
            if p[0] > 0.0 && p[0] < 6.0 && p[1] > 0.0 {
                p[0] += rng.random_range(-0.1..0.1);
                p[1] += rng.random_range(-0.05..0.05);
            }
        }
        let gamma: Vec<f64> = (0..mesh.n_elements())
            .map(|e| 15.0 + (e % 7) as f64)
            .collect();
        let points: Vec<[f64; 3]> = (0..500)
            .map(|_| {
                [
                    rng.random_range(0.01..5.99),
                    rng.random_range(0.0..2.5),
                    0.0,
                ]
            })
            .collect();
        let fast = overburden(&mesh, |_| true, &gamma, &points);
        let slow = brute_force(&mesh, &gamma, &points);
        for (k, (a, b)) in fast.iter().zip(&slow).enumerate() {
            assert!(
                (a - b).abs() < 1e-9 * (1.0 + b.abs()),
                "{k} {:?}: {a} vs {b}",
                points[k]
            );
        }
    }

    #[test]
    fn geostatic_tensor_dry_and_submerged() {
        assert_eq!(
            geostatic_tensor(-100.0, 0.5, 0.0, 1.0),
            [-50.0, -100.0, -50.0, 0.0, 0.0, 0.0]
        );
        // σv = −100, p = −40: σ'v = −60, σ'h = −30, σh = −70.
        assert_eq!(
            geostatic_tensor(-100.0, 0.5, -40.0, 1.0),
            [-70.0, -100.0, -70.0, 0.0, 0.0, 0.0]
        );
    }

    /// One node of a 3D mesh at z = 1e308 made the vertical index ask
    /// for 10^155 bins ("capacity overflow"); its bins and entries stay
    /// proportional to the elements. (The GOM reader refuses such a node
    /// first; the index must not depend on that.)
    #[test]
    fn vertical_index_is_bounded_with_a_node_at_z_1e308() {
        let model = a3d_testkit::column_tet(
            1.0,
            2.0,
            1.0,
            4,
            8,
            4,
            a3d_testkit::elastic_material(1e4, 0.3, 2650.0, 0.3),
        );
        let mut mesh = model.mesh.clone();
        let n_el = mesh.n_elements();
        let far = mesh.nodes.iter().position(|p| p[1] == 0.0).unwrap();
        mesh.nodes[far][2] = 1e308;
        let index = VerticalIndex::new(&mesh, |_| true);
        let entries: usize = index.bins.iter().map(Vec::len).sum();
        assert!(index.bins.len() <= 16 * n_el + 64, "{}", index.bins.len());
        assert!(entries <= 32 * n_el + 1024, "{entries}");
        let gamma = vec![20.0; n_el];
        let sigma = overburden(
            &mesh,
            |_| true,
            &gamma,
            &[[0.5, 1.5, 0.5], [0.5, 1.0, 1e307]],
        );
        assert_eq!(sigma.len(), 2);
    }
}
