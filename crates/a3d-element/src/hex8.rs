//! The 8-noded hexahedron (CB-Geo's `ED3H8`; Anura3D has none): trilinear
//! N = ⅛(1 ± ξ)(1 ± η)(1 ± ζ) on the cube [−1, 1]³, the bottom face (ζ = −1)
//! counter-clockwise from (−1, −1, −1), then the top face above it. No
//! Anura3D MP tables (CB-Geo's own placement is [`crate::cbgeo`]). Not affine,
//! so the MPM runner does not take it; its inverse map is the trait's Newton
//! iteration.

use super::{Element, LocalPoint};
use a3d_model::ElementType;

/// `ED3H8`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Hex8;

/// The corners' signs (ξ, η, ζ), in node order.
const SIGNS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

impl Element<3, 8> for Hex8 {
    const TYPE: ElementType = ElementType::Hex8;
    const CORNERS: [[f64; 3]; 8] = SIGNS;
    const CENTROID: [f64; 3] = [0.0; 3];
    const REFERENCE_MEASURE: f64 = 8.0;
    const ORIENTATION: &'static str = "inverted, twisted or degenerate hexahedron";

    #[inline]
    fn shape_values(&[x, y, z]: &[f64; 3]) -> [f64; 8] {
        SIGNS.map(|[s, t, u]| 0.125 * (1.0 + s * x) * (1.0 + t * y) * (1.0 + u * z))
    }

    #[inline]
    fn local_gradients(&[x, y, z]: &[f64; 3]) -> [[f64; 3]; 8] {
        SIGNS.map(|[s, t, u]| {
            [
                0.125 * s * (1.0 + t * y) * (1.0 + u * z),
                0.125 * t * (1.0 + s * x) * (1.0 + u * z),
                0.125 * u * (1.0 + s * x) * (1.0 + t * y),
            ]
        })
    }

    #[inline]
    fn det_jacobian(corners: &[[f64; 3]; 8], xi: &[f64; 3]) -> f64 {
        Self::jacobian(corners, xi).determinant()
    }

    /// The 2×2×2 Gauss rule on det J: exact for a trilinear hexahedron.
    fn measure(corners: &[[f64; 3]; 8]) -> f64 {
        let a = 1.0 / 3f64.sqrt();
        SIGNS
            .iter()
            .map(|[s, t, u]| Self::det_jacobian(corners, &[s * a, t * a, u * a]))
            .sum()
    }

    fn inside_reference(xi: &[f64; 3], tol: f64) -> bool {
        xi.iter().all(|v| v.abs() <= 1.0 + tol)
    }

    fn local_points(_count: u32) -> Option<&'static [LocalPoint]> {
        None
    }
}
