//! The strain–velocity operator B of one element at one material point, as
//! the MUSL step ([`super::step`]) uses it: the internal force of an MP on a
//! corner, f = −V Bᵀσ, and the strain increment Δε = Δt·B v, both with the
//! hoop row of 2D axisymmetry (σ_θθ / r in the radial force, u_r / r in the
//! hoop strain). A test checks that the force and the strain share one B.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

/// Internal force of one MP on one corner: −V σ·∇N, plus in 2D axisymmetry
/// the hoop term −V N σ_θθ / r in the radial component (`inverse_radius` is
/// 1/r there and 0 otherwise).
#[inline]
pub(super) fn corner_force<const D: usize>(
    s: &[f64; 6],
    g: &[f64; D],
    n: f64,
    volume: f64,
    inverse_radius: f64,
) -> [f64; D] {
    let mut f = internal_force::<D>(s, g, volume);
    if inverse_radius != 0.0 {
        f[0] -= volume * s[2] * n * inverse_radius;
    }
    f
}

/// Hoop strain increment Δε_θθ = Δt·u̇_r/r = Δt Σ N_i v_r,i / r, with the
/// shape values and radius of the step's start (those of the gradients).
#[inline]
pub(super) fn hoop_strain_increment<const D: usize, const NC: usize>(
    shape: &[f64; NC],
    corners: &[u32; NC],
    node_velocity: &[[f64; D]],
    inverse_radius: f64,
    dt: f64,
) -> f64 {
    let mut radial = 0.0;
    for i in 0..NC {
        radial += shape[i] * node_velocity[corners[i] as usize][0];
    }
    dt * radial * inverse_radius
}

/// −V σ·∇N for one corner, in D components.
#[inline]
fn internal_force<const D: usize>(s: &[f64; 6], g: &[f64; D], volume: f64) -> [f64; D] {
    let mut f = [0.0; D];
    if D == 2 {
        f[0] = -volume * (s[0] * g[0] + s[3] * g[1]);
        f[1] = -volume * (s[3] * g[0] + s[1] * g[1]);
    } else {
        // xx yy zz xy yz xz
        f[0] = -volume * (s[0] * g[0] + s[3] * g[1] + s[5] * g[D - 1]);
        f[1] = -volume * (s[3] * g[0] + s[1] * g[1] + s[4] * g[D - 1]);
        f[D - 1] = -volume * (s[5] * g[0] + s[4] * g[1] + s[2] * g[D - 1]);
    }
    f
}

/// Δε of a nodal velocity field at an MP: [`strain_increment`] with, in 2D
/// axisymmetry (`inverse_radius` = 1/r ≠ 0), the hoop component from
/// [`hoop_strain_increment`]. The solid's strain and the liquid's
/// volumetric strain both come from here.
#[inline]
pub(super) fn strain_increment_at<const D: usize, const NC: usize>(
    element: &super::grid::GridElement<D, NC>,
    shape: &[f64; NC],
    inverse_radius: f64,
    node_velocity: &[[f64; D]],
    dt: f64,
) -> [f64; 6] {
    let mut strain = strain_increment::<D, NC>(element, node_velocity, dt);
    if D == 2 && inverse_radius != 0.0 {
        strain[2] =
            hoop_strain_increment(shape, &element.corners, node_velocity, inverse_radius, dt);
    }
    strain
}

/// Δε = Δt·sym(Σ v_I ⊗ ∇N_I) with engineering shear, as a 6-vector.
#[inline]
pub(super) fn strain_increment<const D: usize, const NC: usize>(
    element: &super::grid::GridElement<D, NC>,
    node_velocity: &[[f64; D]],
    dt: f64,
) -> [f64; 6] {
    // Velocity gradient L[a][b] = ∂v_a/∂x_b.
    let mut l = [[0.0; D]; D];
    for i in 0..NC {
        let v = &node_velocity[element.corners[i] as usize];
        let g = &element.shape.grad[i];
        for a in 0..D {
            for b in 0..D {
                l[a][b] += v[a] * g[b];
            }
        }
    }
    let mut e = [0.0; 6];
    e[0] = dt * l[0][0];
    e[1] = dt * l[1][1];
    e[3] = dt * (l[0][1] + l[1][0]);
    if D == 3 {
        let z = D - 1;
        e[2] = dt * l[z][z];
        e[4] = dt * (l[1][z] + l[z][1]);
        e[5] = dt * (l[0][z] + l[z][0]);
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridElement;
    use a3d_element::Simplex;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The axisymmetric force and strain are one B matrix: for any nodal
    /// velocities v and stress σ, the power of the internal forces equals
    /// −V σ : ε̇ (f_int = −V Bᵀσ, ε̇ = B v), hoop terms included. A hoop force
    /// without the hoop strain (or the reverse) breaks this by about V σθθ u̇_r/r.
    #[test]
    fn axisymmetric_force_and_strain_share_one_b_matrix() {
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        for _ in 0..200 {
            let mut corners = [[0.0; 2]; 3];
            for c in &mut corners {
                *c = [0.1 + 2.0 * rng.random::<f64>(), 2.0 * rng.random::<f64>()];
            }
            let Some(shape) = Simplex::<2, 3>::from_corners(&corners) else {
                continue;
            };
            let element = GridElement {
                corners: [0, 1, 2],
                shape,
            };
            let velocity: Vec<[f64; 2]> = (0..3)
                .map(|_| [rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5])
                .collect();
            let stress = [
                -rng.random::<f64>(),
                -rng.random::<f64>(),
                -rng.random::<f64>(),
                rng.random::<f64>() - 0.5,
                0.0,
                0.0,
            ];
            let (a, b) = (rng.random::<f64>(), rng.random::<f64>());
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let n = [1.0 - a - b, a, b];
            let radius: f64 = (0..3).map(|i| n[i] * corners[i][0]).sum();
            let (volume, dt) = (0.7, 1.0);
            let mut strain = strain_increment::<2, 3>(&element, &velocity, dt);
            strain[2] = hoop_strain_increment(&n, &element.corners, &velocity, 1.0 / radius, dt);
            let mut power = 0.0;
            for i in 0..3 {
                let f = corner_force::<2>(&stress, &shape.grad[i], n[i], volume, 1.0 / radius);
                power += f[0] * velocity[i][0] + f[1] * velocity[i][1];
            }
            let work: f64 = (0..4).map(|k| stress[k] * strain[k]).sum();
            assert!(
                (power + volume * work).abs() < 1e-12 * (1.0 + power.abs()),
                "{power} vs {}",
                -volume * work
            );
        }
    }
}
