//! Linear shape functions on simplices: the 3-noded triangle (2D) and the four
//! corners of Anura3D's `tetrahedral_old` (3D).
//!
//! Within a straight-sided simplex the shape function of a corner is its
//! barycentric coordinate, so it is an affine function of the position with a
//! constant gradient. [`Simplex`] stores that affine map once per element;
//! evaluating N at a point is then a handful of multiply-adds, and the gradients
//! need no evaluation at all.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

/// The affine shape functions of one straight-sided simplex with `NC = D + 1`
/// corners: N_i(x) = λ_i(x), the barycentric coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Simplex<const D: usize, const NC: usize> {
    /// Position of corner 0; evaluation works relative to it so that large
    /// coordinates (e.g. UTM) keep their precision.
    pub origin: [f64; D],
    /// Constant gradient ∇N_i of every corner's shape function.
    pub grad: [[f64; D]; NC],
    /// Signed area (2D) or volume (3D): positive for counter-clockwise
    /// triangles and for tetrahedra with (x2−x1)·[(x3−x1)×(x4−x1)] > 0.
    pub signed_measure: f64,
}

impl<const D: usize, const NC: usize> Simplex<D, NC> {
    /// Builds the shape functions of the simplex with these corners. Returns
    /// `None` when the simplex is degenerate (zero or non-finite measure) or
    /// when `NC != D + 1`.
    pub fn from_corners(corners: &[[f64; D]; NC]) -> Option<Self> {
        if NC != D + 1 {
            return None;
        }
        // Jacobian J with columns x_k − x_0 (k = 1..D); λ_k = (J⁻¹ (x − x0))_k.
        let origin = corners[0];
        let mut jac = [[0.0; D]; D];
        for k in 0..D {
            for row in 0..D {
                jac[row][k] = corners[k + 1][row] - origin[row];
            }
        }
        let (inverse, det) = invert(jac)?;
        let factorial = (1..=D).map(|k| k as f64).product::<f64>();
        let signed_measure = det / factorial;
        let mut grad = [[0.0; D]; NC];
        grad[1..].copy_from_slice(&inverse);
        for d in 0..D {
            grad[0][d] = -(1..NC).map(|k| grad[k][d]).sum::<f64>();
        }
        if !signed_measure.is_finite() || signed_measure == 0.0 {
            return None;
        }
        Some(Simplex {
            origin,
            grad,
            signed_measure,
        })
    }

    /// Shape function values at `x`. They sum to 1 exactly (N_0 is computed as
    /// the complement) and are all in [0, 1] when `x` lies inside.
    #[inline]
    pub fn values(&self, x: &[f64; D]) -> [f64; NC] {
        let mut rel = [0.0; D];
        for d in 0..D {
            rel[d] = x[d] - self.origin[d];
        }
        let mut n = [0.0; NC];
        let mut rest = 0.0;
        for k in 1..NC {
            let mut v = 0.0;
            for d in 0..D {
                v += self.grad[k][d] * rel[d];
            }
            n[k] = v;
            rest += v;
        }
        n[0] = 1.0 - rest;
        n
    }

    /// Area (2D) or volume (3D), always positive.
    pub fn measure(&self) -> f64 {
        self.signed_measure.abs()
    }

    /// The smallest altitude (distance from a corner to the opposite face):
    /// |∇N_i| = 1 / h_i, so this is 1 / max_i |∇N_i|. Used as the element's
    /// characteristic length for the time step.
    pub fn min_altitude(&self) -> f64 {
        let mut largest = 0.0_f64;
        for g in &self.grad {
            let norm = g.iter().map(|c| c * c).sum::<f64>().sqrt();
            largest = largest.max(norm);
        }
        1.0 / largest
    }

    /// Centroid of the simplex.
    pub fn centroid(&self, corners: &[[f64; D]; NC]) -> [f64; D] {
        let mut c = [0.0; D];
        for corner in corners {
            for d in 0..D {
                c[d] += corner[d] / NC as f64;
            }
        }
        c
    }
}

/// Inverts a small square matrix by Gauss–Jordan elimination with partial
/// pivoting and returns it with the determinant. `None` when singular.
///
/// Hand-written on purpose, though [`crate::Element::global_gradients`]
/// has the same gradients through nalgebra's closed-form inverse, which is
/// faster here (`cargo bench --bench mpm -- affine_setup`: 1.3× on TRI3, 3× on
/// tetrahedra; 2 to 10 ms per 10⁵ elements, once per run). nalgebra's inverse
/// differs in the last bits, and the runner amplifies them: on the demo slope
/// `verify` settles after 5444 steps instead of 5521 and the factor of safety
/// moves from 1.117 to 1.055. This inverse keeps the runner's results
/// (verify.json, fos.json) bit-identical to what it has always produced.
fn invert<const D: usize>(mut a: [[f64; D]; D]) -> Option<([[f64; D]; D], f64)> {
    let mut inv = [[0.0; D]; D];
    for i in 0..D {
        inv[i][i] = 1.0;
    }
    let scale = a
        .iter()
        .flat_map(|row| row.iter())
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return None;
    }
    let mut det = 1.0;
    for col in 0..D {
        let mut pivot = col;
        for row in col + 1..D {
            if a[row][col].abs() > a[pivot][col].abs() {
                pivot = row;
            }
        }
        if a[pivot][col].abs() <= 1e-14 * scale {
            return None;
        }
        if pivot != col {
            a.swap(pivot, col);
            inv.swap(pivot, col);
            det = -det;
        }
        let p = a[col][col];
        det *= p;
        for k in 0..D {
            a[col][k] /= p;
            inv[col][k] /= p;
        }
        for row in 0..D {
            if row != col {
                let factor = a[row][col];
                if factor != 0.0 {
                    for k in 0..D {
                        a[row][k] -= factor * a[col][k];
                        inv[row][k] -= factor * inv[col][k];
                    }
                }
            }
        }
    }
    Some((inv, det))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Element, TetOld, Tri3};
    use proptest::prelude::*;

    fn tri() -> [[f64; 2]; 3] {
        [[0.3, -0.2], [2.1, 0.4], [0.9, 1.7]]
    }

    fn tet() -> [[f64; 3]; 4] {
        [
            [0.0, 0.0, 0.0],
            [1.0, 0.1, 0.2],
            [0.2, 1.1, -0.1],
            [0.1, 0.3, 1.2],
        ]
    }

    /// The simplex on `corners`, after checking N_j(x_i) = δ_ij.
    fn kronecker_at_corners<const D: usize, const N: usize>(
        corners: &[[f64; D]; N],
    ) -> Simplex<D, N> {
        let s = Simplex::<D, N>::from_corners(corners).expect("valid simplex");
        for (i, corner) in corners.iter().enumerate() {
            for (j, v) in s.values(corner).iter().enumerate() {
                let expected = if i == j { 1.0 } else { 0.0 };
                assert!((v - expected).abs() < 1e-14, "N{j}(x{i}) = {v}");
            }
        }
        s
    }

    #[test]
    fn triangle_shape_functions_are_kronecker_at_corners() {
        let c = tri();
        let s = kronecker_at_corners(&c);
        // Area by the cross product.
        let area = 0.5
            * ((c[1][0] - c[0][0]) * (c[2][1] - c[0][1])
                - (c[2][0] - c[0][0]) * (c[1][1] - c[0][1]));
        assert!((s.signed_measure - area).abs() < 1e-14);
    }

    #[test]
    fn tetrahedron_shape_functions_are_kronecker_at_corners() {
        let c = tet();
        let s = kronecker_at_corners(&c);
        assert!(s.signed_measure > 0.0);
    }

    #[test]
    fn minimum_altitude_of_right_triangle_is_the_hypotenuse_altitude() {
        let s = Simplex::<2, 3>::from_corners(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
            .expect("valid triangle");
        assert!((s.min_altitude() - 0.5_f64.sqrt()).abs() < 1e-14);
    }

    #[test]
    fn degenerate_simplices_are_rejected() {
        assert!(Simplex::<2, 3>::from_corners(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]).is_none());
        assert!(Simplex::<2, 4>::from_corners(&[[0.0; 2]; 4]).is_none());
    }

    #[test]
    fn local_mappings_follow_anura3d_node_order() {
        let c = tet();
        // ζ = 1 is corner 2, ξ = 1 corner 3, η = 1 corner 4.
        assert_eq!(TetOld::global_position(&c, &[0.0, 0.0, 1.0]), c[1]);
        assert_eq!(TetOld::global_position(&c, &[1.0, 0.0, 0.0]), c[2]);
        assert_eq!(TetOld::global_position(&c, &[0.0, 1.0, 0.0]), c[3]);
        let t = tri();
        assert_eq!(Tri3::global_position(&t, &[1.0, 0.0]), t[1]);
        assert_eq!(Tri3::global_position(&t, &[0.0, 1.0]), t[2]);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(128))]

        /// Partition of unity, linear completeness (Σ N_i x_i = x) and
        /// Σ ∇N_i = 0 at arbitrary points of a random tetrahedron.
        #[test]
        fn tetrahedron_reproduces_linear_fields(
            jitter in proptest::collection::vec(-0.3f64..0.3, 12),
            point in proptest::collection::vec(-0.5f64..1.5, 3),
        ) {
            let mut c = tet();
            for (k, j) in jitter.iter().enumerate() {
                c[k / 3][k % 3] += j;
            }
            let s = Simplex::<3, 4>::from_corners(&c).expect("jittered tetrahedron stays valid");
            let x = [point[0], point[1], point[2]];
            let n = s.values(&x);
            prop_assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            for d in 0..3 {
                let rebuilt: f64 = (0..4).map(|k| n[k] * c[k][d]).sum();
                prop_assert!((rebuilt - x[d]).abs() < 1e-12);
                let grad_sum: f64 = (0..4).map(|k| s.grad[k][d]).sum();
                prop_assert!(grad_sum.abs() < 1e-10);
            }
        }

        /// The local-to-global map and the barycentric shape functions agree:
        /// evaluating N at the mapped point returns Anura3D's (N1, ζ, ξ, η).
        #[test]
        fn tet_old_local_coordinates_round_trip(xi in 0.0f64..0.33, eta in 0.0f64..0.33, zeta in 0.0f64..0.33) {
            let c = tet();
            let s = Simplex::<3, 4>::from_corners(&c).expect("valid tetrahedron");
            let n = s.values(&TetOld::global_position(&c, &[xi, eta, zeta]));
            let expected = [1.0 - xi - eta - zeta, zeta, xi, eta];
            for k in 0..4 {
                prop_assert!((n[k] - expected[k]).abs() < 1e-12);
            }
        }
    }
}
