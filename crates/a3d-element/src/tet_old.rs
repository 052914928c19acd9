//! The `tetrahedral_old` element: 10 node ids per element, of which the 4
//! corners enter the linear shape functions with Anura3D's permutation
//! N1 = 1−ξ−η−ζ, N2 = ζ, N3 = ξ, N4 = η on the unit tetrahedron (det J > 0 when
//! (x2−x1)·[(x3−x1)×(x4−x1)] > 0), and Anura3D's local MP tables for it,
//! transcribed from the format notes (`formats-notes/anura3d.md` §3.2, which
//! cite `ElemCalcTETRA.FOR`; weights sum to 1/6), with the rule constants
//! evaluated in double precision as Anura3D does.

use std::sync::LazyLock;

use nalgebra::Matrix3;

use super::{Element, LocalPoint};
use a3d_model::ElementType;

/// `tetrahedral_old`.
#[derive(Clone, Copy, Debug, Default)]
pub struct TetOld;

impl Element<3, 4> for TetOld {
    const TYPE: ElementType = ElementType::TetOld;
    const CORNERS: [[f64; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    const CENTROID: [f64; 3] = [0.25; 3];
    const REFERENCE_MEASURE: f64 = 1.0 / 6.0;
    const ORIENTATION: &'static str = "inverted or degenerate tetrahedron";

    #[inline]
    fn shape_values(&[x, y, z]: &[f64; 3]) -> [f64; 4] {
        [1.0 - x - y - z, z, x, y]
    }

    fn local_gradients(_: &[f64; 3]) -> [[f64; 3]; 4] {
        [
            [-1.0, -1.0, -1.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
        ]
    }

    /// Constant: ∂x/∂ξ = x3 − x1, ∂x/∂η = x4 − x1, ∂x/∂ζ = x2 − x1.
    #[inline]
    fn jacobian(c: &[[f64; 3]; 4], _: &[f64; 3]) -> Matrix3<f64> {
        const CORNER_OF_COLUMN: [usize; 3] = [2, 3, 1];
        Matrix3::from_fn(|row, col| c[CORNER_OF_COLUMN[col]][row] - c[0][row])
    }

    #[inline]
    fn det_jacobian(corners: &[[f64; 3]; 4], xi: &[f64; 3]) -> f64 {
        Self::jacobian(corners, xi).determinant()
    }

    fn measure(corners: &[[f64; 3]; 4]) -> f64 {
        Self::det_jacobian(corners, &Self::CENTROID) / 6.0
    }

    fn inside_reference(&[x, y, z]: &[f64; 3], tol: f64) -> bool {
        x >= -tol && y >= -tol && z >= -tol && 1.0 - x - y - z >= -tol
    }

    fn local_points(count: u32) -> Option<&'static [LocalPoint]> {
        TET.iter()
            .find(|(n, _)| *n == count)
            .map(|(_, v)| v.as_slice())
    }
}

/// Tetrahedron rule constants, evaluated in double precision as Anura3D does.
struct TetConstants {
    a: f64,
    b: f64,
    c: f64,
    d: f64,
    e: f64,
}

fn tet_constants() -> TetConstants {
    let sqrt5 = 5.0f64.sqrt();
    let a = (5.0 - sqrt5) / 20.0;
    let b = (5.0 + 3.0 * sqrt5) / 20.0;
    TetConstants {
        a,
        b,
        c: (a + b) / 2.0,
        d: (3.0 * a + b) / 4.0,
        e: (a + 3.0 * b) / 4.0,
    }
}

fn tet(xi: f64, eta: f64, zeta: f64, weight: f64) -> LocalPoint {
    LocalPoint {
        xi: [xi, eta, zeta],
        weight,
    }
}

static TET: LazyLock<Vec<(u32, Vec<LocalPoint>)>> = LazyLock::new(|| {
    let TetConstants { a, b, c, d, e } = tet_constants();
    let base4 = |w: f64| {
        vec![
            tet(a, a, a, w),
            tet(a, a, b, w),
            tet(b, a, a, w),
            tet(a, b, a, w),
        ]
    };
    let with7 = |w: f64| {
        let mut v = base4(w);
        v.extend([tet(a, a, c, w), tet(c, a, a, w), tet(a, c, a, w)]);
        v
    };
    let p10 = {
        let w = 1.0 / 60.0;
        let mut v = with7(w);
        v.extend([tet(c, a, c, w), tet(a, c, c, w), tet(c, c, a, w)]);
        v
    };
    let p13 = {
        let w = 1.0 / 78.0;
        let mut v = with7(w);
        v.extend([
            tet(a, a, e, w),
            tet(e, a, a, w),
            tet(a, e, a, w),
            tet(a, a, d, w),
            tet(d, a, a, w),
            tet(a, d, a, w),
        ]);
        v
    };
    let w8 = 1.0 / 48.0;
    let p8 = vec![
        tet(0.125, 0.125, 0.125, w8),
        tet(0.125, 0.125, 0.625, w8),
        tet(0.625, 0.125, 0.125, w8),
        tet(0.125, 0.625, 0.125, w8),
        tet(0.25, 0.125, 0.25, w8),
        tet(0.25, 0.375, 0.25, w8),
        tet(0.125, 0.25, 0.375, w8),
        tet(0.375, 0.25, 0.125, w8),
    ];
    let w20 = 1.0 / 120.0;
    let p20 = [
        (0.05, 0.075, 0.075),
        (0.3, 0.1, 0.05),
        (0.55, 0.1, 0.075),
        (0.775, 0.1, 0.05),
        (0.075, 0.35, 0.05),
        (0.35, 0.35, 0.075),
        (0.525, 0.35, 0.05),
        (0.05, 0.6, 0.075),
        (0.25, 0.6, 0.1),
        (0.075, 0.8, 0.1),
        (0.075, 0.1, 0.325),
        (0.25, 0.1, 0.35),
        (0.4, 0.1, 0.325),
        (0.1, 0.3, 0.35),
        (0.2, 0.3, 0.35),
        (0.075, 0.45, 0.325),
        (0.075, 0.075, 0.525),
        (0.175, 0.075, 0.55),
        (0.075, 0.175, 0.55),
        (0.075, 0.075, 0.75),
    ]
    .iter()
    .map(|&(x, y, z)| tet(x, y, z, w20))
    .collect();
    vec![
        (1, vec![tet(d, d, d, 1.0 / 6.0)]),
        (4, base4(1.0 / 24.0)),
        (7, with7(1.0 / 42.0)),
        (8, p8),
        (10, p10),
        (13, p13),
        (20, p20),
    ]
});
