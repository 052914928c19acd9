//! Element geometry behind one seam: the [`Element`] trait, implemented once
//! per element type in its own file ([`Tri3`] in `tri3.rs`, [`TetOld`] in
//! `tet_old.rs`, [`Quad4`] in `quad4.rs`, [`Hex8`] in `hex8.rs`), and [`with_element`], the one place
//! that turns a mesh's [`ElementType`] into its implementation.
//!
//! An element gives, in Anura3D's parametrisation (e.g. the `tetrahedral_old`
//! permutation N2 = ζ, N3 = ξ, N4 = η): shape values and local gradients at ξ,
//! the Jacobian and det J, global gradients, its measure, the inverse map and
//! point location, Anura3D's local MP tables and, for linear simplices, the
//! affine shape functions of one element in global coordinates ([`simplex`]).
//! [`crate::place`] creates MPs through it; `a3d_mpm` builds its grid
//! through it. Callers that are not generic over the type use
//! [`mesh_element`].
//!
//! Small dense algebra (Jacobians, determinants, inverses, the Newton solve of
//! the inverse map) uses nalgebra. The one hand-written inverse left is the
//! runner's Gauss–Jordan in [`simplex`], kept for the runner's bits (see there).
//!
//! Pure computation on [`a3d_model`] data.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

pub mod cbgeo;
mod cbgeo_quadrature;
mod hex8;
pub mod place;
mod quad4;
pub mod simplex;
mod tet_old;
mod tri3;

use std::marker::PhantomData;

use nalgebra::{SMatrix, SVector};

pub use hex8::Hex8;
pub use quad4::Quad4;
pub use simplex::Simplex;
pub use tet_old::TetOld;
pub use tri3::Tri3;

use a3d_model::{ElementType, Mesh};

/// One point of a local MP table: reference coordinates (unused ones 0) and
/// reference weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalPoint {
    pub xi: [f64; 3],
    pub weight: f64,
}

impl LocalPoint {
    /// The reference coordinates of a `D`-dimensional element.
    #[inline]
    pub fn coords<const D: usize>(&self) -> [f64; D] {
        std::array::from_fn(|d| self.xi[d])
    }
}

/// Newton iterations of [`Element::local_coordinates`] before it gives up
/// (an affine element converges in one).
const NEWTON_ITERATIONS: usize = 32;

/// One element type with `D` reference (and spatial) coordinates and `NC`
/// corners that enter the shape functions. Corners are given as
/// `&[[f64; D]; NC]`, in the GOM's node order ([`corners`] reads them from a
/// mesh); local coordinates ξ as `&[f64; D]`.
pub trait Element<const D: usize, const NC: usize>: 'static {
    /// The GOM element type this implements.
    const TYPE: ElementType;
    /// Local coordinates of the corners: N_i(ξ_j) = δ_ij.
    const CORNERS: [[f64; D]; NC];
    /// Local coordinates of the reference element's centroid.
    const CENTROID: [f64; D];
    /// Measure of the reference element: what every MP table's weights sum to.
    const REFERENCE_MEASURE: f64;
    /// What det J ≤ 0 means for this shape, for error messages.
    const ORIENTATION: &'static str;
    /// The shape functions are affine in x (a straight-sided linear simplex,
    /// `D + 1` corners), so [`Element::affine`] gives them per element. The
    /// MPM runner needs this.
    const AFFINE: bool = NC == D + 1;

    /// Shape function values N_i(ξ).
    fn shape_values(xi: &[f64; D]) -> [f64; NC];

    /// Local gradients ∂N_i/∂ξ_j, one row per corner.
    fn local_gradients(xi: &[f64; D]) -> [[f64; D]; NC];

    /// det J at ξ (2·area for a TRI3, 6·volume for a tetrahedron). Each type
    /// writes it as `Self::jacobian(corners, xi).determinant()`: nalgebra's
    /// determinant needs the concrete size.
    fn det_jacobian(corners: &[[f64; D]; NC], xi: &[f64; D]) -> f64;

    /// Area (2D) or volume (3D) of the element.
    fn measure(corners: &[[f64; D]; NC]) -> f64;

    /// True when ξ lies in the reference element, with tolerance `tol` on the
    /// barycentric coordinates (on ξ itself for a QUAD4).
    fn inside_reference(xi: &[f64; D], tol: f64) -> bool;

    /// Anura3D's local points for `count` MPs per element, or `None` when
    /// Anura3D does not accept that count.
    fn local_points(count: u32) -> Option<&'static [LocalPoint]>;

    /// J = ∂x/∂ξ at ξ (row: global coordinate, column: local coordinate),
    /// Σ_i x_i ⊗ ∇_ξ N_i. Affine types override it with the corner differences.
    fn jacobian(corners: &[[f64; D]; NC], xi: &[f64; D]) -> SMatrix<f64, D, D> {
        let g = Self::local_gradients(xi);
        SMatrix::from_fn(|row, col| {
            let mut sum = 0.0;
            for i in 0..NC {
                sum += g[i][col] * corners[i][row];
            }
            sum
        })
    }

    /// Global position x(ξ) = Σ_i N_i(ξ) x_i.
    #[inline]
    fn global_position(corners: &[[f64; D]; NC], xi: &[f64; D]) -> [f64; D] {
        let n = Self::shape_values(xi);
        let mut x = [0.0; D];
        for i in 0..NC {
            for d in 0..D {
                x[d] += n[i] * corners[i][d];
            }
        }
        x
    }

    /// Global gradients ∇N_i = J⁻ᵀ ∇_ξ N_i at ξ; `None` where J is singular.
    fn global_gradients(corners: &[[f64; D]; NC], xi: &[f64; D]) -> Option<[[f64; D]; NC]> {
        let inverse_transpose = Self::jacobian(corners, xi).try_inverse()?.transpose();
        let local = Self::local_gradients(xi);
        Some(std::array::from_fn(|i| {
            (inverse_transpose * SVector::from(local[i])).into()
        }))
    }

    /// The inverse map: ξ with x(ξ) = `x`, by Newton's method from the centroid
    /// (one step for an affine element). `None` where J turns singular or the
    /// iteration does not settle.
    fn local_coordinates(corners: &[[f64; D]; NC], x: &[f64; D]) -> Option<[f64; D]> {
        let target = SVector::from(*x);
        // The size of the coordinates: residuals below rounding at this
        // scale are as good as zero.
        let scale = corners
            .iter()
            .flatten()
            .chain(x)
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(f64::MIN_POSITIVE);
        let mut xi = SVector::from(Self::CENTROID);
        let mut best: Option<(f64, SVector<f64, D>)> = None;
        for _ in 0..NEWTON_ITERATIONS {
            let at: [f64; D] = xi.into();
            let residual = target - SVector::from(Self::global_position(corners, &at));
            let r = residual.amax();
            if best.is_none_or(|(b, _)| r < b) {
                best = Some((r, xi));
            }
            let step = Self::jacobian(corners, &at).try_inverse()? * residual;
            xi += step;
            if !xi.iter().all(|v| v.is_finite()) {
                return None;
            }
            if step.amax() <= 1e-13 * (1.0 + xi.amax()) {
                return Some(xi.into());
            }
        }
        // On a sliver the steps stop shrinking at rounding noise (its
        // condition number times ε) before the strict test holds: the best
        // iterate is then the answer when it maps to x within rounding.
        best.filter(|(r, _)| *r <= 1e-11 * scale)
            .map(|(_, xi)| xi.into())
    }

    /// True when `x` lies in the element (boundary included, tolerance `tol`
    /// as in [`Element::inside_reference`]).
    fn contains(corners: &[[f64; D]; NC], x: &[f64; D], tol: f64) -> bool {
        Self::local_coordinates(corners, x).is_some_and(|xi| Self::inside_reference(&xi, tol))
    }

    /// The shape functions of this element as affine functions of x, for the
    /// runner; `None` for a type that is not [`Element::AFFINE`] and for a
    /// degenerate element.
    fn affine(corners: &[[f64; D]; NC]) -> Option<Simplex<D, NC>> {
        if Self::AFFINE {
            Simplex::from_corners(corners)
        } else {
            None
        }
    }
}

/// Work generic over the element type, run by [`with_element`] with the
/// implementation of a mesh's [`ElementType`] (Rust has no generic closures).
pub trait ElementVisitor {
    type Output;
    fn visit<const D: usize, const NC: usize, E: Element<D, NC>>(self) -> Self::Output;
}

/// Runs `visitor` with the [`Element`] implementation of `element_type`: the
/// one place that lists the element types.
pub fn with_element<V: ElementVisitor>(element_type: ElementType, visitor: V) -> V::Output {
    match element_type {
        ElementType::Tri3 => visitor.visit::<2, 3, Tri3>(),
        ElementType::TetOld => visitor.visit::<3, 4, TetOld>(),
        ElementType::Quad4 => visitor.visit::<2, 4, Quad4>(),
        ElementType::Hex8 => visitor.visit::<3, 8, Hex8>(),
    }
}

/// The corner coordinates of element `e` of `mesh`, in the form [`Element`]
/// takes them (`D` of each node's three coordinates).
#[inline]
pub fn corners<const D: usize, const NC: usize>(mesh: &Mesh, e: usize) -> [[f64; D]; NC] {
    let ids = mesh.corners(e);
    std::array::from_fn(|k| {
        let node = &mesh.nodes[ids[k] as usize];
        std::array::from_fn(|d| node[d])
    })
}

/// Widens a `D`-vector to the model's three components (z = 0 in 2D).
#[inline]
pub fn widen<const D: usize>(v: &[f64; D]) -> [f64; 3] {
    let mut out = [0.0; 3];
    out[..D].copy_from_slice(v);
    out
}

/// An element type's [`Element`] operations on element `e` of a mesh, for
/// callers that are not generic over the type. Coordinates have three
/// components (z and unused ξ components are 0 in 2D).
pub trait MeshElement: Sync {
    fn element_type(&self) -> ElementType;
    /// [`Element::ORIENTATION`].
    fn orientation(&self) -> &'static str;
    /// [`Element::REFERENCE_MEASURE`].
    fn reference_measure(&self) -> f64;
    /// [`Element::local_points`].
    fn local_points(&self, count: u32) -> Option<&'static [LocalPoint]>;
    /// [`Element::global_position`].
    fn global_position(&self, mesh: &Mesh, e: usize, xi: [f64; 3]) -> [f64; 3];
    /// [`Element::det_jacobian`].
    fn det_jacobian(&self, mesh: &Mesh, e: usize, xi: [f64; 3]) -> f64;
    /// [`Element::measure`].
    fn measure(&self, mesh: &Mesh, e: usize) -> f64;
    /// [`Element::contains`].
    fn contains(&self, mesh: &Mesh, e: usize, x: [f64; 3], tol: f64) -> bool;
}

/// The [`MeshElement`] of `element_type`.
pub fn mesh_element(element_type: ElementType) -> &'static dyn MeshElement {
    struct Erase;
    impl ElementVisitor for Erase {
        type Output = &'static dyn MeshElement;
        fn visit<const D: usize, const NC: usize, E: Element<D, NC>>(self) -> Self::Output {
            &Erased::<D, NC, E>(PhantomData)
        }
    }
    with_element(element_type, Erase)
}

/// [`MeshElement`] for the element type `E`.
struct Erased<const D: usize, const NC: usize, E>(PhantomData<fn() -> E>);

impl<const D: usize, const NC: usize, E: Element<D, NC>> MeshElement for Erased<D, NC, E> {
    fn element_type(&self) -> ElementType {
        E::TYPE
    }
    fn orientation(&self) -> &'static str {
        E::ORIENTATION
    }
    fn reference_measure(&self) -> f64 {
        E::REFERENCE_MEASURE
    }
    fn local_points(&self, count: u32) -> Option<&'static [LocalPoint]> {
        E::local_points(count)
    }
    fn global_position(&self, mesh: &Mesh, e: usize, xi: [f64; 3]) -> [f64; 3] {
        let x = E::global_position(&corners(mesh, e), &std::array::from_fn(|d| xi[d]));
        widen(&x)
    }
    fn det_jacobian(&self, mesh: &Mesh, e: usize, xi: [f64; 3]) -> f64 {
        E::det_jacobian(&corners(mesh, e), &std::array::from_fn(|d| xi[d]))
    }
    fn measure(&self, mesh: &Mesh, e: usize) -> f64 {
        E::measure(&corners(mesh, e))
    }
    fn contains(&self, mesh: &Mesh, e: usize, x: [f64; 3], tol: f64) -> bool {
        E::contains(&corners(mesh, e), &std::array::from_fn(|d| x[d]), tol)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const ALL: [ElementType; 4] = [
        ElementType::Tri3,
        ElementType::TetOld,
        ElementType::Quad4,
        ElementType::Hex8,
    ];

    fn close(a: f64, b: f64, tol: f64) -> Result<(), TestCaseError> {
        prop_assert!((a - b).abs() <= tol, "{a} vs {b} (tolerance {tol})");
        Ok(())
    }

    /// The trait's promises for one type, on an element x = A ξ + b whose
    /// corners are then moved a little, at a point ξ inside it; `r` holds
    /// numbers in [−1, 1).
    struct Check<'a>(ElementType, &'a [f64]);

    impl ElementVisitor for Check<'_> {
        type Output = Result<(), TestCaseError>;
        fn visit<const D: usize, const NC: usize, E: Element<D, NC>>(self) -> Self::Output {
            let Check(et, r) = self;
            prop_assert_eq!(E::TYPE, et);
            prop_assert_eq!((et.n_dim(), et.n_corners()), (D, NC));
            let a = SMatrix::<f64, D, D>::from_fn(|i, j| {
                (if i == j { 2.0 } else { 0.0 }) + 0.3 * r[i * 3 + j]
            });
            let corners: [[f64; D]; NC] = std::array::from_fn(|k| {
                let x = a * SVector::from(E::CORNERS[k]);
                std::array::from_fn(|d| x[d] + 10.0 * r[9 + d] + 0.05 * r[12 + 3 * k + d])
            });
            // ξ: a convex combination of the corners.
            let w: [f64; NC] = std::array::from_fn(|k| 1.5 + r[24 + k]);
            let total: f64 = w.iter().sum();
            let xi: [f64; D] = std::array::from_fn(|d| {
                (0..NC).map(|k| w[k] * E::CORNERS[k][d]).sum::<f64>() / total
            });
            prop_assert!(E::inside_reference(&xi, 0.0) && E::inside_reference(&E::CENTROID, 0.0));
            for (j, corner) in E::CORNERS.iter().enumerate() {
                prop_assert!(E::inside_reference(corner, 0.0));
                for (i, n) in E::shape_values(corner).into_iter().enumerate() {
                    close(n, if i == j { 1.0 } else { 0.0 }, 1e-15)?;
                }
                let x = E::global_position(&corners, corner);
                for d in 0..D {
                    close(x[d], corners[j][d], 1e-13)?;
                }
            }
            // Partition of unity and local gradients against central differences.
            let n = E::shape_values(&xi);
            close(n.iter().sum(), 1.0, 1e-14)?;
            let g = E::local_gradients(&xi);
            let h = 1e-6;
            for d in 0..D {
                let shifted = |s: f64| {
                    let mut p = xi;
                    p[d] += s;
                    p
                };
                let (plus, minus) = (E::shape_values(&shifted(h)), E::shape_values(&shifted(-h)));
                for i in 0..NC {
                    close(g[i][d], (plus[i] - minus[i]) / (2.0 * h), 1e-8)?;
                }
                close((0..NC).map(|i| g[i][d]).sum(), 0.0, 1e-14)?;
                let (xp, xm) = (
                    E::global_position(&corners, &shifted(h)),
                    E::global_position(&corners, &shifted(-h)),
                );
                let j = E::jacobian(&corners, &xi);
                for row in 0..D {
                    close(j[(row, d)], (xp[row] - xm[row]) / (2.0 * h), 1e-7)?;
                }
            }
            // Global gradients: Σ ∇N_i ⊗ x_i = I.
            let grad = E::global_gradients(&corners, &xi).expect("regular element");
            for p in 0..D {
                for q in 0..D {
                    let sum: f64 = (0..NC).map(|i| grad[i][q] * corners[i][p]).sum();
                    close(sum, if p == q { 1.0 } else { 0.0 }, 1e-12)?;
                }
            }
            // The inverse map and point location.
            let x = E::global_position(&corners, &xi);
            let back = E::local_coordinates(&corners, &x).expect("converges");
            for d in 0..D {
                close(back[d], xi[d], 1e-12)?;
            }
            prop_assert!(E::contains(&corners, &x, 1e-9));
            let outside: [f64; D] =
                std::array::from_fn(|d| E::CENTROID[d] + 3.0 * (E::CORNERS[0][d] - E::CENTROID[d]));
            prop_assert!(!E::contains(
                &corners,
                &E::global_position(&corners, &outside),
                1e-9
            ));
            // Every allowed table: its size, the reference weight, inside, and
            // Σ w·det J = the measure (the rules integrate det J exactly).
            prop_assert!(E::det_jacobian(&corners, &xi) > 0.0);
            let measure = E::measure(&corners);
            for &count in et.allowed_mp_counts() {
                let table = E::local_points(count).expect("allowed count");
                prop_assert_eq!(table.len(), count as usize);
                close(
                    table.iter().map(|p| p.weight).sum(),
                    E::REFERENCE_MEASURE,
                    1e-12,
                )?;
                let mut sum = 0.0;
                for p in table {
                    prop_assert!(E::inside_reference(&p.coords::<D>(), 0.0));
                    sum += p.weight * E::det_jacobian(&corners, &p.coords::<D>());
                }
                close(sum, measure, 1e-12 * measure)?;
            }
            prop_assert!(E::local_points(2).is_none());
            // The runner's affine shape functions agree with the element's.
            match E::affine(&corners) {
                Some(simplex) => {
                    prop_assert!(E::AFFINE);
                    for (i, v) in simplex.values(&x).into_iter().enumerate() {
                        close(v, n[i], 1e-12)?;
                    }
                    for i in 0..NC {
                        for d in 0..D {
                            close(simplex.grad[i][d], grad[i][d], 1e-12)?;
                        }
                    }
                    close(simplex.measure(), measure, 1e-12 * measure)?;
                }
                None => prop_assert!(!E::AFFINE),
            }
            Ok(())
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn every_element_type_keeps_the_trait_promises(
            r in proptest::collection::vec(-1.0f64..1.0, 36),
        ) {
            for et in ALL {
                with_element(et, Check(et, &r))?;
            }
        }

        /// nalgebra's determinant is the cofactor expansion placement always
        /// used (j00(j11 j22 − j12 j21) − j01(…) + j02(…), and x·y − x·y in 2D),
        /// so det J, hence MP volumes, keep their bits.
        #[test]
        fn det_jacobian_keeps_the_cofactor_bits(c in proptest::collection::vec(-50.0f64..50.0, 12)) {
            let t = [[c[0], c[1]], [c[2], c[3]], [c[4], c[5]]];
            let d = |a: usize, k: usize| t[a][k] - t[0][k];
            let tri = d(1, 0) * d(2, 1) - d(2, 0) * d(1, 1);
            prop_assert_eq!(Tri3::det_jacobian(&t, &[0.2, 0.3]).to_bits(), tri.to_bits());
            let q: [[f64; 3]; 4] = std::array::from_fn(|k| [c[3 * k], c[3 * k + 1], c[3 * k + 2]]);
            let d = |a: usize, k: usize| q[a][k] - q[0][k];
            let j = [
                [d(2, 0), d(3, 0), d(1, 0)],
                [d(2, 1), d(3, 1), d(1, 1)],
                [d(2, 2), d(3, 2), d(1, 2)],
            ];
            let tet = j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
                - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
                + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0]);
            prop_assert_eq!(TetOld::det_jacobian(&q, &[0.1; 3]).to_bits(), tet.to_bits());
        }
    }

    #[test]
    fn mesh_element_answers_for_its_type() {
        for et in ALL {
            assert_eq!(mesh_element(et).element_type(), et);
        }
    }
}
