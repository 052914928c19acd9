//! Element geometry, one place per element type: Anura3D's shape functions
//! (with the `tetrahedral_old` permutation N2 = ζ, N3 = ξ, N4 = η), det J,
//! measures, point location, the local MP tables ([`tables`]) and the affine
//! simplex shape functions the runner uses ([`simplex`]). [`crate::place`]
//! creates MPs from these; [`crate::mpm`] integrates with them. Adding an
//! element type touches this module (and the runner's grid for `verify`).
//!
//! Pure computation on [`crate::model`] data.

pub mod simplex;
pub mod tables;

use crate::model::{ElementType, Mesh};

/// Shape function values at ξ for the element's corners (unused slots 0).
pub fn shape_values(et: ElementType, xi: [f64; 3]) -> [f64; 4] {
    let [x, y, z] = xi;
    match et {
        ElementType::Tri3 => [1.0 - x - y, x, y, 0.0],
        // tetrahedral_old: N1 = 1−ξ−η−ζ, N2 = ζ, N3 = ξ, N4 = η.
        ElementType::TetOld => [1.0 - x - y - z, z, x, y],
        ElementType::Quad4 => [
            0.25 * (1.0 - x) * (1.0 - y),
            0.25 * (1.0 + x) * (1.0 - y),
            0.25 * (1.0 + x) * (1.0 + y),
            0.25 * (1.0 - x) * (1.0 + y),
        ],
    }
}

/// Global position of local point ξ in element `e`.
pub fn global_position(mesh: &Mesh, e: usize, xi: [f64; 3]) -> [f64; 3] {
    let n = shape_values(mesh.element_type, xi);
    let c = mesh.corner_coords(e);
    let mut p = [0.0; 3];
    for i in 0..mesh.element_type.n_corners() {
        for k in 0..3 {
            p[k] += n[i] * c[i][k];
        }
    }
    p
}

/// det J of the isoparametric map of element `e` at ξ: 2·area for a TRI3, 6·volume
/// for a tetrahedron (with the tetrahedral_old permutation), the bilinear
/// Jacobian for a QUAD4.
pub fn det_jacobian(mesh: &Mesh, e: usize, xi: [f64; 3]) -> f64 {
    let c = mesh.corner_coords(e);
    let d = |a: usize, b: usize, k: usize| c[a][k] - c[b][k];
    match mesh.element_type {
        ElementType::Tri3 => d(1, 0, 0) * d(2, 0, 1) - d(2, 0, 0) * d(1, 0, 1),
        ElementType::TetOld => {
            // ∂x/∂ξ = x3 − x1, ∂x/∂η = x4 − x1, ∂x/∂ζ = x2 − x1.
            let j = [
                [d(2, 0, 0), d(3, 0, 0), d(1, 0, 0)],
                [d(2, 0, 1), d(3, 0, 1), d(1, 0, 1)],
                [d(2, 0, 2), d(3, 0, 2), d(1, 0, 2)],
            ];
            j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
                - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
                + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0])
        }
        ElementType::Quad4 => {
            let [x, y, _] = xi;
            let dn_dxi = [
                -0.25 * (1.0 - y),
                0.25 * (1.0 - y),
                0.25 * (1.0 + y),
                -0.25 * (1.0 + y),
            ];
            let dn_deta = [
                -0.25 * (1.0 - x),
                -0.25 * (1.0 + x),
                0.25 * (1.0 + x),
                0.25 * (1.0 - x),
            ];
            let (mut a, mut b, mut cc, mut dd) = (0.0, 0.0, 0.0, 0.0);
            for i in 0..4 {
                a += dn_dxi[i] * c[i][0];
                b += dn_deta[i] * c[i][0];
                cc += dn_dxi[i] * c[i][1];
                dd += dn_deta[i] * c[i][1];
            }
            a * dd - b * cc
        }
    }
}

/// Area (2D) or volume (3D) of element `e`.
pub fn element_measure(mesh: &Mesh, e: usize) -> f64 {
    match mesh.element_type {
        ElementType::Tri3 => det_jacobian(mesh, e, [0.0; 3]) / 2.0,
        ElementType::TetOld => det_jacobian(mesh, e, [0.0; 3]) / 6.0,
        ElementType::Quad4 => {
            // Shoelace formula over the four corners.
            let c = mesh.corner_coords(e);
            0.5 * (0..4)
                .map(|i| c[i][0] * c[(i + 1) % 4][1] - c[(i + 1) % 4][0] * c[i][1])
                .sum::<f64>()
        }
    }
}

/// True when `p` lies in element `e` (boundary included, relative tolerance `tol`
/// on the barycentric coordinates). QUAD4 is split into two triangles (convex quads).
pub fn point_in_element(mesh: &Mesh, e: usize, p: [f64; 3], tol: f64) -> bool {
    let c = mesh.corner_coords(e);
    let in_tri = |a: [f64; 3], b: [f64; 3], cc: [f64; 3]| {
        let det = (b[0] - a[0]) * (cc[1] - a[1]) - (cc[0] - a[0]) * (b[1] - a[1]);
        let l1 = ((b[0] - p[0]) * (cc[1] - p[1]) - (cc[0] - p[0]) * (b[1] - p[1])) / det;
        let l2 = ((cc[0] - p[0]) * (a[1] - p[1]) - (a[0] - p[0]) * (cc[1] - p[1])) / det;
        let l3 = 1.0 - l1 - l2;
        l1 >= -tol && l2 >= -tol && l3 >= -tol
    };
    match mesh.element_type {
        ElementType::Tri3 => in_tri(c[0], c[1], c[2]),
        ElementType::Quad4 => in_tri(c[0], c[1], c[2]) || in_tri(c[0], c[2], c[3]),
        ElementType::TetOld => {
            let sub = |u: [f64; 3], v: [f64; 3]| [u[0] - v[0], u[1] - v[1], u[2] - v[2]];
            let triple = |u: [f64; 3], v: [f64; 3], w: [f64; 3]| {
                u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
                    + u[2] * (v[0] * w[1] - v[1] * w[0])
            };
            let vol = triple(sub(c[1], c[0]), sub(c[2], c[0]), sub(c[3], c[0]));
            let l = [
                triple(sub(c[1], p), sub(c[2], p), sub(c[3], p)) / vol,
                triple(sub(p, c[0]), sub(c[2], c[0]), sub(c[3], c[0])) / vol,
                triple(sub(c[1], c[0]), sub(p, c[0]), sub(c[3], c[0])) / vol,
                triple(sub(c[1], c[0]), sub(c[2], c[0]), sub(p, c[0])) / vol,
            ];
            l.iter().all(|&v| v >= -tol)
        }
    }
}
