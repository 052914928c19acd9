//! Constitutive models of the MPM check: isotropic linear elasticity and
//! perfectly plastic Mohr–Coulomb with a tension cut-off, acting on the
//! effective stress in Anura3D's sign convention (tension positive).
//!
//! Stresses and strains are 6-vectors ordered xx, yy, zz, xy, yz, xz; strains
//! carry engineering shear (γ = 2ε). Plane strain uses the full 3D stress with
//! σzz tracked (εzz = γyz = γxz = 0), so the return mapping always sees three
//! principal stresses.
//!
//! The Mohr–Coulomb return works in principal stress space with σ1 ≥ σ2 ≥ σ3
//! (σ3 the most compressive), as in de Souza Neto, Perić & Owen (2008, ch. 8)
//! and Clausen, Damkilde & Andersen (2006): the yield planes are linear in the
//! principal stresses and the hardening is nil, so every return is the closed-
//! form solution of a 1×1, 2×2 or 3×3 linear system. Every independent set of
//! up to three active surfaces (main plane, the two edges, the apex, the
//! tension cut-off planes and their corners) is tried, smallest first, and the
//! first one that satisfies the Kuhn–Tucker conditions (all multipliers ≥ 0,
//! principal order kept, no yield function positive) is taken; the hydrostatic
//! vertex is the last resort where more surfaces meet than a 3-set can express. This file leaves out strain softening, hardening
//! and objective stress rates; it knows nothing about meshes or time steps.

// Numerical kernels index several small arrays with one loop counter.
#![allow(clippy::needless_range_loop)]

use super::MpmError;
use crate::model::Material;

/// Isotropic linear elasticity by bulk and shear modulus (kPa).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Elasticity {
    pub bulk: f64,
    pub shear: f64,
}

impl Elasticity {
    /// From Young's modulus and Poisson's ratio; `None` unless E > 0 and
    /// −1 < ν < 0.5.
    pub fn from_young_poisson(young: f64, poisson: f64) -> Option<Elasticity> {
        if !(young > 0.0 && young.is_finite() && poisson > -1.0 && poisson < 0.5) {
            return None;
        }
        Some(Elasticity {
            bulk: young / (3.0 * (1.0 - 2.0 * poisson)),
            shear: young / (2.0 * (1.0 + poisson)),
        })
    }

    /// Lamé's first parameter λ = K − 2G/3.
    pub fn lame(&self) -> f64 {
        self.bulk - 2.0 / 3.0 * self.shear
    }

    /// Constrained (P-wave) modulus M = K + 4G/3.
    pub fn p_wave_modulus(&self) -> f64 {
        self.bulk + 4.0 / 3.0 * self.shear
    }

    /// Adds D·Δε to `stress` (Δε with engineering shear).
    #[inline]
    pub fn add_increment(&self, stress: &mut [f64; 6], strain: &[f64; 6]) {
        let two_g = 2.0 * self.shear;
        let volumetric = self.lame() * (strain[0] + strain[1] + strain[2]);
        for k in 0..3 {
            stress[k] += volumetric + two_g * strain[k];
        }
        for k in 3..6 {
            stress[k] += self.shear * strain[k];
        }
    }

    /// The strain C·Δσ (engineering shear) that an elastic stress change
    /// `stress_change` corresponds to. Used to express plastic strain
    /// increments: Δε^p = C·(σ_trial − σ_returned).
    pub fn strain_of(&self, stress_change: &[f64; 6]) -> [f64; 6] {
        let mean = (stress_change[0] + stress_change[1] + stress_change[2]) / 3.0;
        let mut out = [0.0; 6];
        for k in 0..3 {
            out[k] = mean / (3.0 * self.bulk) + (stress_change[k] - mean) / (2.0 * self.shear);
        }
        for k in 3..6 {
            out[k] = stress_change[k] / self.shear;
        }
        out
    }
}

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

/// Eigenvectors (as columns, in the order of `values`, which must be the
/// descending eigenvalues) from cross products of the rows of σ − λI, when
/// the eigenvalues are at least 1e-3·|σ| apart; the error is then about
/// ε·|σ|/gap ≤ 1e-12. `None` for closer eigenvalues.
#[inline]
fn well_separated_frame(
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
fn null_vector(s: &[f64; 6], lambda: f64) -> Option<[f64; 3]> {
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
fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
fn normalised(v: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(&v, &v).sqrt();
    (n > 0.0 && n.is_finite()).then(|| [v[0] / n, v[1] / n, v[2] / n])
}

/// The constitutive model of one material.
#[derive(Clone, Debug)]
pub struct SolidModel {
    pub elasticity: Elasticity,
    /// The Mohr–Coulomb return (criterion and precomputed sets), if plastic.
    pub plasticity: Option<ReturnMap>,
}

impl SolidModel {
    /// Builds the model of a GOM material: `linear_elasticity`, `mohr_coulomb`,
    /// or `strain_softening_mohr_coulomb` (checked at its peak strength, read
    /// from the `PEAK_*` properties; softening is not modelled).
    pub fn from_material(material: &Material) -> Result<SolidModel, MpmError> {
        let missing = |property: &'static str| MpmError::MissingProperty {
            material: material.index,
            property,
        };
        let model = material.model.as_deref().unwrap_or("");
        let young = material
            .young_modulus
            .ok_or_else(|| missing("YOUNG_MODULUS"))?;
        let poisson = material
            .poisson_ratio
            .ok_or_else(|| missing("POISSON_RATIO"))?;
        let elasticity =
            Elasticity::from_young_poisson(young, poisson).ok_or(MpmError::InvalidProperty {
                material: material.index,
                reason: format!(
                    "E = {young} kPa and ν = {poisson} must satisfy E > 0, −1 < ν < 0.5"
                ),
            })?;
        let plasticity = match model {
            "linear_elasticity" => None,
            "mohr_coulomb" => {
                let phi = material
                    .friction_angle
                    .ok_or_else(|| missing("FRICTION_ANGLE"))?;
                let c = material.cohesion.ok_or_else(|| missing("COHESION"))?;
                let psi = material.dilatancy_angle.unwrap_or(0.0);
                let criterion =
                    mohr_coulomb_or_error(material.index, phi, c, psi, material.tensile_strength)?;
                Some(ReturnMap::new(criterion, elasticity))
            }
            "strain_softening_mohr_coulomb" => {
                let phi = property(material, "PEAK_FRICTION_ANGLE")
                    .ok_or_else(|| missing("PEAK_FRICTION_ANGLE"))?;
                let c =
                    property(material, "PEAK_COHESION").ok_or_else(|| missing("PEAK_COHESION"))?;
                let psi = property(material, "PEAK_DILATANCY_ANGLE").unwrap_or(0.0);
                Some(ReturnMap::new(
                    mohr_coulomb_or_error(material.index, phi, c, psi, None)?,
                    elasticity,
                ))
            }
            other => {
                return Err(MpmError::UnsupportedMaterialModel {
                    material: material.index,
                    model: other.to_string(),
                });
            }
        };
        Ok(SolidModel {
            elasticity,
            plasticity,
        })
    }

    /// Elastic predictor and plastic corrector for one strain increment.
    #[inline]
    pub fn update(
        &self,
        stress: &mut [f64; 6],
        strain: &[f64; 6],
        plane_strain: bool,
    ) -> ReturnKind {
        self.elasticity.add_increment(stress, strain);
        match &self.plasticity {
            None => ReturnKind::Elastic,
            Some(map) => map.return_stress(stress, plane_strain),
        }
    }

    /// True when the stress lies inside or on the yield surface (within a
    /// relative tolerance of 1e-9 of the stress magnitude).
    pub fn is_admissible(&self, stress: &[f64; 6], plane_strain: bool) -> bool {
        match &self.plasticity {
            None => true,
            Some(map) => {
                let mc = &map.criterion;
                let scale = stress
                    .iter()
                    .fold(mc.cohesion, |m, v| m.max(v.abs()))
                    .max(1e-6);
                mc.yield_value(stress, plane_strain) <= 1e-9 * scale
            }
        }
    }
}

fn mohr_coulomb_or_error(
    index: u32,
    phi: f64,
    c: f64,
    psi: f64,
    tensile: Option<f64>,
) -> Result<MohrCoulomb, MpmError> {
    MohrCoulomb::new(phi, c, psi, tensile).ok_or(MpmError::InvalidProperty {
        material: index,
        reason: format!(
            "Mohr–Coulomb needs 0 ≤ φ < 90°, 0 ≤ ψ < 90°, c ≥ 0; got φ = {phi}, ψ = {psi}, c = {c}"
        ),
    })
}

/// A numeric property of the material record by keyword, ignoring `$$` and case.
fn property(material: &Material, keyword: &str) -> Option<f64> {
    material
        .properties
        .iter()
        .find(|(k, _)| {
            k.trim()
                .trim_start_matches("$$")
                .eq_ignore_ascii_case(keyword)
        })
        .and_then(|(_, v)| v.split_whitespace().next()?.parse::<f64>().ok())
}

/// Solves the leading m×m block of `a·x = b` (m ≤ 3) by Gaussian elimination
/// with partial pivoting. `None` when (nearly) singular.
fn solve_small(a: &[[f64; 3]; 3], b: &[f64; 3], m: usize) -> Option<[f64; 3]> {
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
fn sort_desc(v: [f64; 3]) -> ([f64; 3], [usize; 3]) {
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
struct PlaneFrame {
    values: [f64; 3],
    cos2: f64,
    sin2: f64,
}

#[inline]
fn principal_plane(s: &[f64; 6]) -> PlaneFrame {
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
    fn rebuild(&self, s: &mut [f64; 6], values: &[f64; 3]) {
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
fn principal_values_3d(s: &[f64; 6]) -> [f64; 3] {
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
fn symmetric_eigen_3d(s: &[f64; 6]) -> ([f64; 3], [[f64; 3]; 3]) {
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
fn rebuild_3d(values: &[f64; 3], v: &[[f64; 3]; 3]) -> [f64; 6] {
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
