//! Perfectly plastic Mohr–Coulomb with a tension cut-off, acting on the
//! effective stress in Anura3D's sign convention (tension positive).
//!
//! The return works in principal stress space with σ1 ≥ σ2 ≥ σ3 (σ3 the most
//! compressive), as in de Souza Neto, Perić & Owen (2008, ch. 8) and Clausen,
//! Damkilde & Andersen (2006): the yield planes are linear in the principal
//! stresses and the hardening is nil, so every return is the closed-form
//! solution of a 1×1, 2×2 or 3×3 linear system. Every independent set of up to
//! three active surfaces (main plane, the two edges, the apex, the tension
//! cut-off planes and their corners) is tried, smallest first, and the first one
//! that satisfies the Kuhn–Tucker conditions (all multipliers ≥ 0, principal
//! order kept, no yield function positive) is taken; the hydrostatic vertex is
//! the last resort where more surfaces meet than a 3-set can express.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

use super::elasticity::Elasticity;
use super::principal::*;

/// Which part of the yield surface a stress update ended on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum ReturnKind {
    /// The trial stress was admissible and is kept.
    Elastic,
    /// Main Mohr–Coulomb plane (σ1, σ3).
    Plane,
    /// Edge σ1 = σ2 (triaxial compression: the two lateral stresses equal).
    CompressionEdge,
    /// Edge σ2 = σ3 (triaxial extension).
    ExtensionEdge,
    /// Mohr–Coulomb apex σ1 = σ2 = σ3 = c·cot φ.
    Apex,
    /// Tension cut-off plane σ1 = σt.
    TensionPlane,
    /// Tension cut-off edge σ1 = σ2 = σt.
    TensionEdge,
    /// Tension apex σ1 = σ2 = σ3 = σt.
    TensionApex,
    /// Corner of the main plane with σ1 = σt.
    PlaneTensionCorner,
    /// Corner σ2 = σ3 on the Mohr–Coulomb plane with σ1 = σt.
    ExtensionEdgeTensionCorner,
    /// Corner of the main plane with σ1 = σ2 = σt.
    PlaneTensionEdgeCorner,
}

impl ReturnKind {
    /// True for every outcome except [`ReturnKind::Elastic`].
    pub fn is_plastic(self) -> bool {
        self != ReturnKind::Elastic
    }
}

/// Perfectly plastic Mohr–Coulomb with an optional tension cut-off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MohrCoulomb {
    pub sin_phi: f64,
    pub cos_phi: f64,
    pub sin_psi: f64,
    /// Cohesion c′ (kPa).
    pub cohesion: f64,
    /// Tension cut-off σt (kPa), below the apex c·cot φ; `f64::INFINITY`
    /// when there is none or when it lies at or above the apex.
    pub tension: f64,
}

/// One linear yield surface in sorted principal space: f = a·σ − b, with the
/// flow direction n (∂g/∂σ).
#[derive(Clone, Copy, Debug)]
struct Surface {
    a: [f64; 3],
    b: f64,
    n: [f64; 3],
}

/// Number of linear surfaces: the three Mohr–Coulomb planes that matter in
/// sorted principal space (σ1σ3, σ2σ3, σ1σ2) and the three cut-off planes.
const N_SURFACES: usize = 6;
/// Index of the first cut-off plane.
const FIRST_CUTOFF: usize = 3;

impl MohrCoulomb {
    /// From friction and dilatancy angles in degrees, cohesion and tensile
    /// strength in kPa. `None` unless 0 ≤ φ < 90°, 0 ≤ ψ < 90° and c ≥ 0
    /// (ψ > φ is accepted). A tensile strength that is absent, or above the
    /// apex c·cot φ, leaves the apex as the only tension limit; a negative one
    /// is taken as 0.
    pub fn new(
        friction_deg: f64,
        cohesion: f64,
        dilatancy_deg: f64,
        tensile_strength: Option<f64>,
    ) -> Option<MohrCoulomb> {
        let ok = (0.0..90.0).contains(&friction_deg)
            && (0.0..90.0).contains(&dilatancy_deg)
            && cohesion >= 0.0
            && cohesion.is_finite();
        if !ok {
            return None;
        }
        let phi = friction_deg.to_radians();
        let psi = dilatancy_deg.to_radians();
        let (sin_phi, cos_phi) = phi.sin_cos();
        let apex = if sin_phi > 0.0 {
            cohesion * cos_phi / sin_phi
        } else {
            f64::INFINITY
        };
        let tension = match tensile_strength {
            Some(t) if t.is_finite() && t.max(0.0) < apex => t.max(0.0),
            _ => f64::INFINITY,
        };
        Some(MohrCoulomb {
            sin_phi,
            cos_phi,
            sin_psi: psi.sin(),
            cohesion,
            tension,
        })
    }

    /// Mean stress of the hydrostatic vertex of the admissible domain:
    /// min(c·cot φ, σt), infinite for φ = 0 without cut-off.
    pub fn apex(&self) -> f64 {
        if self.sin_phi > 0.0 {
            (self.cohesion * self.cos_phi / self.sin_phi).min(self.tension)
        } else {
            self.tension
        }
    }

    /// The yield value of a stress: max of the Mohr–Coulomb function
    /// f = (σ1 − σ3) + (σ1 + σ3)·sin φ − 2c·cos φ and the cut-off σ1 − σt.
    /// Negative inside, zero on the surface (kPa).
    pub fn yield_value(&self, stress: &[f64; 6], plane_strain: bool) -> f64 {
        // Jacobi rather than the trigonometric formula: the latter loses
        // accuracy (≈ √ε) at repeated eigenvalues, i.e. exactly on the edges.
        let p = if plane_strain {
            principal_plane(stress).values
        } else {
            symmetric_eigen_3d(stress).0
        };
        let s = sort_desc(p).0;
        self.yield_value_principal(&s)
    }

    fn yield_value_principal(&self, s: &[f64; 3]) -> f64 {
        let mc = (s[0] - s[2]) + (s[0] + s[2]) * self.sin_phi - 2.0 * self.cohesion * self.cos_phi;
        if self.tension.is_finite() {
            mc.max(s[0] - self.tension)
        } else {
            mc
        }
    }

    fn surfaces(&self) -> [Surface; 6] {
        let (sp, sq) = (self.sin_phi, self.sin_psi);
        let b = 2.0 * self.cohesion * self.cos_phi;
        let t = self.tension;
        [
            Surface {
                a: [1.0 + sp, 0.0, -(1.0 - sp)],
                b,
                n: [1.0 + sq, 0.0, -(1.0 - sq)],
            },
            Surface {
                a: [0.0, 1.0 + sp, -(1.0 - sp)],
                b,
                n: [0.0, 1.0 + sq, -(1.0 - sq)],
            },
            Surface {
                a: [1.0 + sp, -(1.0 - sp), 0.0],
                b,
                n: [1.0 + sq, -(1.0 - sq), 0.0],
            },
            Surface {
                a: [1.0, 0.0, 0.0],
                b: t,
                n: [1.0, 0.0, 0.0],
            },
            Surface {
                a: [0.0, 1.0, 0.0],
                b: t,
                n: [0.0, 1.0, 0.0],
            },
            Surface {
                a: [0.0, 0.0, 1.0],
                b: t,
                n: [0.0, 0.0, 1.0],
            },
        ]
    }

    /// Returns sorted principal trial stresses (σ1 ≥ σ2 ≥ σ3) to the yield
    /// surface; returns them unchanged with [`ReturnKind::Elastic`] when
    /// admissible. Builds a [`ReturnMap`] for the call; keep one per material
    /// instead where speed matters.
    pub fn return_principal(
        &self,
        elastic: &Elasticity,
        trial: &[f64; 3],
    ) -> ([f64; 3], ReturnKind) {
        ReturnMap::new(*self, *elastic).return_principal(trial)
    }

    /// Returns a full trial stress (6 components) onto the yield surface in
    /// place, rotating back with the trial's principal directions. Builds a
    /// [`ReturnMap`] for the call.
    pub fn return_stress(
        &self,
        elastic: &Elasticity,
        stress: &mut [f64; 6],
        plane_strain: bool,
    ) -> ReturnKind {
        ReturnMap::new(*self, *elastic).return_stress(stress, plane_strain)
    }

    /// Names the part of the surface a returned (sorted) principal stress lies on.
    fn classify(&self, s: &[f64; 3], tol: f64) -> ReturnKind {
        let mc = (s[0] - s[2]) + (s[0] + s[2]) * self.sin_phi - 2.0 * self.cohesion * self.cos_phi;
        let on_mc = mc.abs() <= tol;
        let at_cutoff = s
            .iter()
            .filter(|&&v| (v - self.tension).abs() <= tol)
            .count();
        let top_pair = (s[0] - s[1]).abs() <= tol;
        let bottom_pair = (s[1] - s[2]).abs() <= tol;
        match (on_mc, at_cutoff) {
            (true, 0) if top_pair && bottom_pair => ReturnKind::Apex,
            (true, 0) if top_pair => ReturnKind::CompressionEdge,
            (true, 0) if bottom_pair => ReturnKind::ExtensionEdge,
            (true, 0) => ReturnKind::Plane,
            (true, 1) if bottom_pair => ReturnKind::ExtensionEdgeTensionCorner,
            (true, 1) => ReturnKind::PlaneTensionCorner,
            (true, 2) => ReturnKind::PlaneTensionEdgeCorner,
            (_, 3) => ReturnKind::TensionApex,
            (false, 2) => ReturnKind::TensionEdge,
            _ => ReturnKind::TensionPlane,
        }
    }
}

/// One independent set of active surfaces with the inverse of its matrix
/// A_ij = a_i·D·n_j (the multipliers are Δλ = A⁻¹ f_trial).
#[derive(Clone, Copy, Debug)]
struct ActiveSet {
    members: [usize; 3],
    len: usize,
    inverse: [[f64; 3]; 3],
}

/// Largest number of active sets: 6 + 15 + 20 subsets of one to three surfaces.
const MAX_SETS: usize = 41;

/// The Mohr–Coulomb return of one material, with everything that depends
/// only on the material precomputed: D·n of every surface and the inverse
/// matrix of every independent set of up to three surfaces.
#[derive(Clone, Debug)]
pub struct ReturnMap {
    pub criterion: MohrCoulomb,
    pub elasticity: Elasticity,
    surfaces: [Surface; N_SURFACES],
    dn: [[f64; 3]; N_SURFACES],
    sets: [ActiveSet; MAX_SETS],
    n_sets: usize,
}

impl ReturnMap {
    pub fn new(criterion: MohrCoulomb, elasticity: Elasticity) -> ReturnMap {
        let surfaces = criterion.surfaces();
        let lame = elasticity.lame();
        let two_g = 2.0 * elasticity.shear;
        let mut dn = [[0.0; 3]; N_SURFACES];
        for (k, s) in surfaces.iter().enumerate() {
            let tr = s.n[0] + s.n[1] + s.n[2];
            for i in 0..3 {
                dn[k][i] = lame * tr + two_g * s.n[i];
            }
        }
        // Every set of one, two, then three surfaces, in a fixed order; sets
        // with cut-off planes only when there is a cut-off; singular sets out.
        let n_active = if criterion.tension.is_finite() {
            N_SURFACES
        } else {
            FIRST_CUTOFF
        };
        let mut candidates: Vec<([usize; 3], usize)> = Vec::with_capacity(MAX_SETS);
        for i in 0..n_active {
            candidates.push(([i, 0, 0], 1));
        }
        for i in 0..n_active {
            for j in i + 1..n_active {
                candidates.push(([i, j, 0], 2));
            }
        }
        for i in 0..n_active {
            for j in i + 1..n_active {
                for k in j + 1..n_active {
                    candidates.push(([i, j, k], 3));
                }
            }
        }
        let empty = ActiveSet {
            members: [0; 3],
            len: 0,
            inverse: [[0.0; 3]; 3],
        };
        let mut sets = [empty; MAX_SETS];
        let mut n_sets = 0;
        for (members, len) in candidates {
            let mut matrix = [[0.0; 3]; 3];
            for i in 0..len {
                let a = &surfaces[members[i]].a;
                for j in 0..len {
                    let d = &dn[members[j]];
                    matrix[i][j] = a[0] * d[0] + a[1] * d[1] + a[2] * d[2];
                }
            }
            let mut inverse = [[0.0; 3]; 3];
            let mut regular = true;
            for col in 0..len {
                let mut unit = [0.0; 3];
                unit[col] = 1.0;
                match solve_small(&matrix, &unit, len) {
                    Some(x) => {
                        for row in 0..len {
                            inverse[row][col] = x[row];
                        }
                    }
                    None => regular = false,
                }
            }
            if regular {
                sets[n_sets] = ActiveSet {
                    members,
                    len,
                    inverse,
                };
                n_sets += 1;
            }
        }
        ReturnMap {
            criterion,
            elasticity,
            surfaces,
            dn,
            sets,
            n_sets,
        }
    }

    /// Returns sorted principal trial stresses (σ1 ≥ σ2 ≥ σ3) to the yield
    /// surface; unchanged with [`ReturnKind::Elastic`] when admissible.
    pub fn return_principal(&self, trial: &[f64; 3]) -> ([f64; 3], ReturnKind) {
        let mc = &self.criterion;
        let scale = trial
            .iter()
            .fold(mc.cohesion, |m, v| m.max(v.abs()))
            .max(1e-6);
        let tol = 1e-12 * scale;
        if mc.yield_value_principal(trial) <= tol {
            return (*trial, ReturnKind::Elastic);
        }
        let mut values = [0.0; N_SURFACES];
        for (k, f) in self.surfaces.iter().enumerate() {
            values[k] = f.a[0] * trial[0] + f.a[1] * trial[1] + f.a[2] * trial[2] - f.b;
        }
        // The first set whose multipliers are non-negative and whose result is
        // ordered and admissible. Where more than three surfaces meet (e.g.
        // σ1 = σ2 = σt on the Mohr–Coulomb plane: F1, F2, T1, T2), the return
        // direction lies in the cone of all their flow vectors and, by
        // Carathéodory's theorem, in the cone of three of them, so the
        // enumeration still finds it.
        for set in &self.sets[..self.n_sets] {
            let m = set.len;
            let mut lambda = [0.0; 3];
            let mut largest = 0.0_f64;
            for i in 0..m {
                let mut l = 0.0;
                for j in 0..m {
                    l += set.inverse[i][j] * values[set.members[j]];
                }
                lambda[i] = l;
                largest = largest.max(l.abs());
            }
            if lambda[..m].iter().any(|&l| l < -1e-10 * largest) {
                continue;
            }
            let mut s = *trial;
            for j in 0..m {
                let d = &self.dn[set.members[j]];
                for i in 0..3 {
                    s[i] -= lambda[j] * d[i];
                }
            }
            let ordered = s[0] >= s[1] - tol && s[1] >= s[2] - tol;
            if ordered && mc.yield_value_principal(&sort_desc(s).0) <= tol {
                return (s, mc.classify(&s, 1e3 * tol));
            }
        }
        // The vertex. Where the cut-off meets the Mohr–Coulomb apex (e.g. c = 0
        // with σt = 0) more than three surfaces are active there and no subset
        // of three has non-negative multipliers; when nothing above fits, the
        // vertex is the return (for φ = 0 without cut-off, whose "vertex" is at
        // infinity, the hydrostatic part of the trial stress is kept).
        let apex = mc.apex();
        if apex.is_finite() {
            let kind = if mc.tension.is_finite() {
                ReturnKind::TensionApex
            } else {
                ReturnKind::Apex
            };
            ([apex; 3], kind)
        } else {
            (
                [(trial[0] + trial[1] + trial[2]) / 3.0; 3],
                ReturnKind::Apex,
            )
        }
    }

    /// Returns a full trial stress (6 components) onto the yield surface in
    /// place, rotating back with the trial's principal directions.
    pub fn return_stress(&self, stress: &mut [f64; 6], plane_strain: bool) -> ReturnKind {
        let mc = &self.criterion;
        if plane_strain {
            let frame = principal_plane(stress);
            let (sorted, order) = sort_desc(frame.values);
            let (returned, kind) = self.return_principal(&sorted);
            if kind == ReturnKind::Elastic {
                return kind;
            }
            let mut values = [0.0; 3];
            for (slot, &o) in order.iter().enumerate() {
                values[o] = returned[slot];
            }
            frame.rebuild(stress, &values);
            kind
        } else {
            // Trigonometric eigenvalues, already in descending order.
            let quick = principal_values_3d(stress);
            let scale = quick
                .iter()
                .fold(mc.cohesion, |m, v| m.max(v.abs()))
                .max(1e-6);
            // They err by up to ≈ √ε·|σ| near repeated eigenvalues; a margin of
            // 1e-6·|σ| keeps every possibly plastic state for the exact path.
            if mc.yield_value_principal(&quick) < -1e-6 * scale {
                return ReturnKind::Elastic;
            }
            let gap = (quick[0] - quick[1]).min(quick[1] - quick[2]);
            let (sorted, vectors) = match well_separated_frame(stress, &quick, gap, scale) {
                Some(vectors) => (quick, vectors),
                None => {
                    // Close eigenvalues: Jacobi, robust for any spectrum.
                    let (values, vectors) = symmetric_eigen_3d(stress);
                    let (sorted, order) = sort_desc(values);
                    let mut ordered = [[0.0; 3]; 3];
                    for row in 0..3 {
                        for (slot, &o) in order.iter().enumerate() {
                            ordered[row][slot] = vectors[row][o];
                        }
                    }
                    (sorted, ordered)
                }
            };
            let (returned, kind) = self.return_principal(&sorted);
            if kind == ReturnKind::Elastic {
                return kind;
            }
            *stress = rebuild_3d(&returned, &vectors);
            kind
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trigonometric_and_jacobi_eigenvalues_agree() {
        let s = [-12.0, -30.0, -7.5, 4.0, -3.0, 6.5];
        let a = sort_desc(principal_values_3d(&s)).0;
        let (values, vectors) = symmetric_eigen_3d(&s);
        let b = sort_desc(values).0;
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < 1e-10, "{a:?} vs {b:?}");
        }
        let rebuilt = rebuild_3d(&values, &vectors);
        for k in 0..6 {
            assert!((rebuilt[k] - s[k]).abs() < 1e-10, "{rebuilt:?} vs {s:?}");
        }
    }

    #[test]
    fn cross_product_frame_matches_jacobi() {
        let stresses = [
            [-12.0, -30.0, -7.5, 4.0, -3.0, 6.5],
            [-100.0, -40.0, -60.0, 0.0, 0.0, 0.0],
            [5.0, -80.0, -20.0, 30.0, 1.0, -2.0],
        ];
        for s in stresses {
            let values = principal_values_3d(&s);
            let scale = values.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let gap = (values[0] - values[1]).min(values[1] - values[2]);
            let frame = well_separated_frame(&s, &values, gap, scale).expect("separated");
            let rebuilt = rebuild_3d(&values, &frame);
            for k in 0..6 {
                assert!(
                    (rebuilt[k] - s[k]).abs() < 1e-11 * scale,
                    "{rebuilt:?} vs {s:?}"
                );
            }
            // Orthonormal columns.
            for a in 0..3 {
                for b in 0..3 {
                    let d: f64 = (0..3).map(|r| frame[r][a] * frame[r][b]).sum();
                    assert!((d - if a == b { 1.0 } else { 0.0 }).abs() < 1e-12);
                }
            }
        }
        // Repeated eigenvalues are left to Jacobi.
        let s = [-40.0, -100.0, -40.0, 0.0, 0.0, 0.0];
        let values = principal_values_3d(&s);
        assert!(well_separated_frame(&s, &values, 0.0, 100.0).is_none());
    }

    #[test]
    fn jacobi_handles_repeated_eigenvalues() {
        let s = [-5.0, -5.0, -5.0, 0.0, 0.0, 0.0];
        let (values, _) = symmetric_eigen_3d(&s);
        assert_eq!(values, [-5.0, -5.0, -5.0]);
        let s = [-5.0, -5.0, -9.0, 1e-30, 0.0, 0.0];
        let (values, vectors) = symmetric_eigen_3d(&s);
        let rebuilt = rebuild_3d(&values, &vectors);
        for k in 0..6 {
            assert!((rebuilt[k] - s[k]).abs() < 1e-12);
        }
    }

    #[test]
    fn plane_frame_round_trips() {
        let s = [-12.0, -30.0, -7.5, 4.0, 0.0, 0.0];
        let frame = principal_plane(&s);
        let mut out = [0.0; 6];
        frame.rebuild(&mut out, &frame.values);
        for k in 0..6 {
            assert!((out[k] - s[k]).abs() < 1e-12);
        }
    }

    #[test]
    fn small_solver_solves_and_detects_singularity() {
        let a = [[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]];
        let x = solve_small(&a, &[1.0, 2.0, 3.0], 3).expect("regular");
        for i in 0..3 {
            let r: f64 = (0..3).map(|j| a[i][j] * x[j]).sum();
            assert!((r - [1.0, 2.0, 3.0][i]).abs() < 1e-12);
        }
        let singular = [[1.0, 2.0, 0.0], [2.0, 4.0, 0.0], [0.0, 0.0, 0.0]];
        assert!(solve_small(&singular, &[1.0, 1.0, 0.0], 2).is_none());
    }
}
