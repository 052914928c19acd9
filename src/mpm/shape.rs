//! The runner's shape functions: the affine simplex functions of
//! [`crate::element::simplex`], plus Anura3D's local-to-global maps for the
//! reference parametrisations (TRI3: N1 = 1−ξ−η, N2 = ξ, N3 = η;
//! `tetrahedral_old`: N1 = 1−ξ−η−ζ, N2 = ζ, N3 = ξ, N4 = η).

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

pub use crate::element::simplex::Simplex;

/// Global position of the TRI3 local point (ξ, η): N1 = 1−ξ−η, N2 = ξ, N3 = η.
pub fn tri3_local_to_global(corners: &[[f64; 2]; 3], xi: f64, eta: f64) -> [f64; 2] {
    let n = [1.0 - xi - eta, xi, eta];
    let mut x = [0.0; 2];
    for (k, corner) in corners.iter().enumerate() {
        for d in 0..2 {
            x[d] += n[k] * corner[d];
        }
    }
    x
}

/// Global position of the `tetrahedral_old` local point (ξ, η, ζ) with
/// Anura3D's permuted shape functions N1 = 1−ξ−η−ζ, N2 = ζ, N3 = ξ, N4 = η.
pub fn tet_old_local_to_global(corners: &[[f64; 3]; 4], xi: f64, eta: f64, zeta: f64) -> [f64; 3] {
    let n = [1.0 - xi - eta - zeta, zeta, xi, eta];
    let mut x = [0.0; 3];
    for (k, corner) in corners.iter().enumerate() {
        for d in 0..3 {
            x[d] += n[k] * corner[d];
        }
    }
    x
}
