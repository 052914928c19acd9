//! Geostatic total stress from the overburden along the vertical (y up).
//!
//! For an MP at p, the vertical line through p is intersected with every active
//! element above it; the total vertical stress is σv = −Σ γ·Δy over those
//! segments, with γ evaluated at sub-segment midpoints (γ may vary with the pore
//! pressure through the degree of saturation). The ground surface is therefore
//! the top of the active mesh along the vertical; gaps in the mesh carry no
//! weight. Horizontal total stress: σh = K0·σ'v + S·p with σ'v = σv − S·p, on xx
//! and zz (and yy in 3D stays vertical); shears are zero.

use crate::model::Mesh;

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
        let span = [(hi[0] - lo[0]).max(1e-12), (hi[1] - lo[1]).max(1e-12)];
        let cell = if three_d {
            (span[0] * span[1] / n_el as f64).sqrt().max(1e-12) * 2.0
        } else {
            span[0] / (n_el as f64).sqrt().max(1.0)
        };
        let n = [
            ((span[0] / cell).ceil() as usize).max(1),
            if three_d {
                ((span[1] / cell).ceil() as usize).max(1)
            } else {
                1
            },
        ];
        let mut bins = vec![Vec::new(); n[0] * n[1]];
        let clamp =
            |v: f64, k: usize| (((v - lo[k]) / cell).floor().max(0.0) as usize).min(n[k] - 1);
        for e in 0..mesh.n_elements() {
            if !active(e) {
                continue;
            }
            let corners = mesh.corner_coords(e);
            let mut emin = [f64::INFINITY; 2];
            let mut emax = [f64::NEG_INFINITY; 2];
            for c in corners.iter().take(mesh.element_type.n_corners()) {
                let h = horizontal(c, three_d);
                for k in 0..2 {
                    emin[k] = emin[k].min(h[k]);
                    emax[k] = emax[k].max(h[k]);
                }
            }
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
        let ok = if mesh.dimension.n_dim() == 2 {
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
            (0..nc).all(|i| {
                let (a, b) = (c[i], c[(i + 1) % nc]);
                clip([-(b[1] - a[1]), b[0] - a[0], 0.0], a, centroid)
            })
        } else {
            let centroid = [
                (c[0][0] + c[1][0] + c[2][0] + c[3][0]) / 4.0,
                (c[0][1] + c[1][1] + c[2][1] + c[3][1]) / 4.0,
                (c[0][2] + c[1][2] + c[2][2] + c[3][2]) / 4.0,
            ];
            [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]
                .iter()
                .all(|f| {
                    let (a, b, cc) = (c[f[0]], c[f[1]], c[f[2]]);
                    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                    let v = [cc[0] - a[0], cc[1] - a[1], cc[2] - a[2]];
                    let nrm = [
                        u[1] * v[2] - u[2] * v[1],
                        u[2] * v[0] - u[0] * v[2],
                        u[0] * v[1] - u[1] * v[0],
                    ];
                    clip(nrm, a, centroid)
                })
        };
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
    use crate::model::generate;

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
}
