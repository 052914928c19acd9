//! Small dense linear algebra of the Mohr–Coulomb return: principal stresses
//! and frames of a symmetric 3×3 stress (closed-form for well-separated
//! eigenvalues, Jacobi otherwise), the in-plane frame of a plane-strain stress,
//! and the ≤ 3×3 solves of the return's active sets. Hand-written because they
//! run per MP per step (`benches/mpm.rs`).

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

/// Eigenvectors (as columns, in the order of `values`, which must be the
/// descending eigenvalues) from cross products of the rows of σ − λI, when
/// the eigenvalues are at least 1e-3·|σ| apart; the error is then about
/// ε·|σ|/gap ≤ 1e-12. `None` for closer eigenvalues.
#[inline]
pub(super) fn well_separated_frame(
    s: &[f64; 6],
    values: &[f64; 3],
    gap: f64,
    scale: f64,
) -> Option<[[f64; 3]; 3]> {
    if gap.is_nan() || gap <= 1e-3 * scale {
        return None;
    }
    let v1 = null_vector(s, values[0])?;
    let mut v3 = null_vector(s, values[2])?;
    // Re-orthogonalise against v1, then complete the right-handed frame.
    let d = dot(&v1, &v3);
    for k in 0..3 {
        v3[k] -= d * v1[k];
    }
    let v3 = normalised(v3)?;
    let v2 = cross(&v3, &v1);
    Some([
        [v1[0], v2[0], v3[0]],
        [v1[1], v2[1], v3[1]],
        [v1[2], v2[2], v3[2]],
    ])
}

/// Unit vector spanning the null space of σ − λI for a simple eigenvalue λ:
/// the largest cross product of two rows.
#[inline]
pub(super) fn null_vector(s: &[f64; 6], lambda: f64) -> Option<[f64; 3]> {
    let r0 = [s[0] - lambda, s[3], s[5]];
    let r1 = [s[3], s[1] - lambda, s[4]];
    let r2 = [s[5], s[4], s[2] - lambda];
    let candidates = [cross(&r0, &r1), cross(&r0, &r2), cross(&r1, &r2)];
    let mut best = candidates[0];
    let mut best_norm = dot(&best, &best);
    for c in &candidates[1..] {
        let n = dot(c, c);
        if n > best_norm {
            best = *c;
            best_norm = n;
        }
    }
    normalised(best)
}

#[inline]
pub(super) fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
pub(super) fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub(super) fn normalised(v: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(&v, &v).sqrt();
    (n > 0.0 && n.is_finite()).then(|| [v[0] / n, v[1] / n, v[2] / n])
}

/// Solves the leading m×m block of `a·x = b` (m ≤ 3) by Gaussian elimination
/// with partial pivoting. `None` when (nearly) singular.
pub(super) fn solve_small(a: &[[f64; 3]; 3], b: &[f64; 3], m: usize) -> Option<[f64; 3]> {
    let mut a = *a;
    let mut b = *b;
    let scale = (0..m)
        .flat_map(|i| (0..m).map(move |j| (i, j)))
        .fold(0.0_f64, |acc, (i, j)| acc.max(a[i][j].abs()));
    if scale == 0.0 {
        return None;
    }
    for col in 0..m {
        let mut pivot = col;
        for row in col + 1..m {
            if a[row][col].abs() > a[pivot][col].abs() {
                pivot = row;
            }
        }
        if a[pivot][col].abs() <= 1e-12 * scale {
            return None;
        }
        a.swap(pivot, col);
        b.swap(pivot, col);
        for row in col + 1..m {
            let factor = a[row][col] / a[col][col];
            for k in col..m {
                a[row][k] -= factor * a[col][k];
            }
            b[row] -= factor * b[col];
        }
    }
    let mut x = [0.0; 3];
    for row in (0..m).rev() {
        let mut sum = b[row];
        for k in row + 1..m {
            sum -= a[row][k] * x[k];
        }
        x[row] = sum / a[row][row];
    }
    Some(x)
}

/// Sorts three values in descending order; also returns, for each sorted
/// slot, the index it came from.
#[inline]
pub(super) fn sort_desc(v: [f64; 3]) -> ([f64; 3], [usize; 3]) {
    let mut order = [0, 1, 2];
    if v[order[0]] < v[order[1]] {
        order.swap(0, 1);
    }
    if v[order[1]] < v[order[2]] {
        order.swap(1, 2);
    }
    if v[order[0]] < v[order[1]] {
        order.swap(0, 1);
    }
    ([v[order[0]], v[order[1]], v[order[2]]], order)
}

/// Principal decomposition of a plane-strain stress (xy in plane, zz out of
/// plane, yz = xz = 0): values are (σa, σb, σzz) with σa ≥ σb the in-plane ones.
pub(super) struct PlaneFrame {
    pub(super) values: [f64; 3],
    cos2: f64,
    sin2: f64,
}

#[inline]
pub(super) fn principal_plane(s: &[f64; 6]) -> PlaneFrame {
    let centre = 0.5 * (s[0] + s[1]);
    let half = 0.5 * (s[0] - s[1]);
    let radius = (half * half + s[3] * s[3]).sqrt();
    let (cos2, sin2) = if radius > 0.0 {
        (half / radius, s[3] / radius)
    } else {
        (1.0, 0.0)
    };
    PlaneFrame {
        values: [centre + radius, centre - radius, s[2]],
        cos2,
        sin2,
    }
}

impl PlaneFrame {
    /// Writes the stress with principal values `values` (same slots as
    /// `self.values`) and this frame's directions.
    pub(super) fn rebuild(&self, s: &mut [f64; 6], values: &[f64; 3]) {
        let centre = 0.5 * (values[0] + values[1]);
        let half = 0.5 * (values[0] - values[1]);
        s[0] = centre + half * self.cos2;
        s[1] = centre - half * self.cos2;
        s[3] = half * self.sin2;
        s[2] = values[2];
        s[4] = 0.0;
        s[5] = 0.0;
    }
}

/// Eigenvalues of a symmetric 3×3 stress by the trigonometric formula (not
/// ordered). Accurate to round-off relative to the deviatoric magnitude.
#[inline]
pub(super) fn principal_values_3d(s: &[f64; 6]) -> [f64; 3] {
    let off = s[3] * s[3] + s[4] * s[4] + s[5] * s[5];
    let mean = (s[0] + s[1] + s[2]) / 3.0;
    let (d0, d1, d2) = (s[0] - mean, s[1] - mean, s[2] - mean);
    let p2 = d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * off;
    if p2 <= 0.0 {
        return [s[0], s[1], s[2]];
    }
    let p = (p2 / 6.0).sqrt();
    // det(B) / 2 with B = (A − mean·I) / p.
    let det = d0 * (d1 * d2 - s[4] * s[4]) - s[3] * (s[3] * d2 - s[4] * s[5])
        + s[5] * (s[3] * s[4] - d1 * s[5]);
    let r = (det / (2.0 * p * p * p)).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let first = mean + 2.0 * p * phi.cos();
    let third = mean + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
    [first, 3.0 * mean - first - third, third]
}

/// Eigen-decomposition of a symmetric 3×3 stress by cyclic Jacobi rotations.
/// Returns the eigenvalues and the eigenvectors as columns (`v[row][k]`).
pub(super) fn symmetric_eigen_3d(s: &[f64; 6]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut a = [[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]];
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let norm = a.iter().flat_map(|r| r.iter()).map(|x| x * x).sum::<f64>();
    for _sweep in 0..32 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        if off <= 1e-34 * norm {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            let apq = a[p][q];
            if apq == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let c = 1.0 / (t * t + 1.0).sqrt();
            let sn = t * c;
            let tau = sn / (1.0 + c);
            a[p][p] -= t * apq;
            a[q][q] += t * apq;
            a[p][q] = 0.0;
            a[q][p] = 0.0;
            let r = 3 - p - q;
            let g = a[r][p];
            let h = a[r][q];
            a[r][p] = g - sn * (h + g * tau);
            a[p][r] = a[r][p];
            a[r][q] = h + sn * (g - h * tau);
            a[q][r] = a[r][q];
            for row in 0..3 {
                let g = v[row][p];
                let h = v[row][q];
                v[row][p] = g - sn * (h + g * tau);
                v[row][q] = h + sn * (g - h * tau);
            }
        }
    }
    ([a[0][0], a[1][1], a[2][2]], v)
}

/// σ = Σ_k λ_k v_k v_kᵀ in Voigt order xx, yy, zz, xy, yz, xz.
pub(super) fn rebuild_3d(values: &[f64; 3], v: &[[f64; 3]; 3]) -> [f64; 6] {
    let mut s = [0.0; 6];
    for k in 0..3 {
        let (x, y, z) = (v[0][k], v[1][k], v[2][k]);
        let l = values[k];
        s[0] += l * x * x;
        s[1] += l * y * y;
        s[2] += l * z * z;
        s[3] += l * x * y;
        s[4] += l * y * z;
        s[5] += l * x * z;
    }
    s
}
