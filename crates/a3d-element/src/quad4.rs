//! The 4-noded quadrilateral `quadrilateral_4-noded` (upstream Anura3D kernel
//! only): bilinear N1 = ¼(1−ξ)(1−η), N2 = ¼(1+ξ)(1−η), N3 = ¼(1+ξ)(1+η),
//! N4 = ¼(1−ξ)(1+η) on the square [−1, 1]², and Anura3D's local MP tables for
//! it (`formats-notes/anura3d.md` §3.2, which cite `ElemCalcQUAD.FOR`; weights
//! sum to 4). Not affine, so the MPM runner does not take it; its inverse map
//! is the trait's Newton iteration.

// The Gauss point keeps every digit Anura3D writes, beyond what an f64 holds.
#![allow(clippy::excessive_precision)]

use std::sync::LazyLock;

use super::{Element, LocalPoint};
use a3d_model::ElementType;

/// `quadrilateral_4-noded`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Quad4;

impl Element<2, 4> for Quad4 {
    const TYPE: ElementType = ElementType::Quad4;
    const CORNERS: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    const CENTROID: [f64; 2] = [0.0; 2];
    const REFERENCE_MEASURE: f64 = 4.0;
    const ORIENTATION: &'static str = "clockwise, non-convex or degenerate quadrilateral";

    #[inline]
    fn shape_values(&[x, y]: &[f64; 2]) -> [f64; 4] {
        [
            0.25 * (1.0 - x) * (1.0 - y),
            0.25 * (1.0 + x) * (1.0 - y),
            0.25 * (1.0 + x) * (1.0 + y),
            0.25 * (1.0 - x) * (1.0 + y),
        ]
    }

    #[inline]
    fn local_gradients(&[x, y]: &[f64; 2]) -> [[f64; 2]; 4] {
        [
            [-0.25 * (1.0 - y), -0.25 * (1.0 - x)],
            [0.25 * (1.0 - y), -0.25 * (1.0 + x)],
            [0.25 * (1.0 + y), 0.25 * (1.0 + x)],
            [-0.25 * (1.0 + y), 0.25 * (1.0 - x)],
        ]
    }

    #[inline]
    fn det_jacobian(corners: &[[f64; 2]; 4], xi: &[f64; 2]) -> f64 {
        Self::jacobian(corners, xi).determinant()
    }

    /// The shoelace formula over the four corners.
    fn measure(c: &[[f64; 2]; 4]) -> f64 {
        0.5 * (0..4)
            .map(|i| c[i][0] * c[(i + 1) % 4][1] - c[(i + 1) % 4][0] * c[i][1])
            .sum::<f64>()
    }

    fn inside_reference(xi: &[f64; 2], tol: f64) -> bool {
        xi.iter().all(|v| v.abs() <= 1.0 + tol)
    }

    fn local_points(count: u32) -> Option<&'static [LocalPoint]> {
        match count {
            1 => Some(&QUAD[0]),
            4 => Some(&QUAD[1]),
            _ => None,
        }
    }
}

static QUAD: LazyLock<[Vec<LocalPoint>; 2]> = LazyLock::new(|| {
    let a = 0.57735026918962576450914878050196;
    let q = |x: f64, y: f64, w: f64| LocalPoint {
        xi: [x, y, 0.0],
        weight: w,
    };
    [
        vec![q(0.0, 0.0, 4.0)],
        vec![q(-a, -a, 1.0), q(a, -a, 1.0), q(a, a, 1.0), q(-a, a, 1.0)],
    ]
});
