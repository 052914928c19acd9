//! Where Anura3D creates material points, reproduced exactly
//! (`formats-notes/anura3d.md` §3): elements in file order, elements with
//! material 0 skipped, `nSolid` points per element from Anura3D's own local
//! tables ([`Element::local_points`]), ids numbered 1, 2, 3, … in creation
//! order, positions x = Σ Nᵢ(ξ)·xᵢ with Anura3D's shape functions, volume =
//! weight × det J(ξ), times the MP's radius x in 2D-axisymmetric models (per
//! radian; verified on the running kernel, `formats-notes/anura3d.md` §3.1
//! step 5 and §8). The geometry is the element type's [`Element`]
//! implementation, chosen once per model by [`with_element`].
//!
//! Pure computation. Element orientation is checked here (a clockwise triangle or
//! an inverted tetrahedron would get a negative volume in Anura3D); errors carry
//! the 0-based element index and the caller attaches the file line.

use crate::{Element, ElementVisitor, mesh_element, with_element};
use a3d_model::{AnuraModel, ComputationMethod, Dimension, ElementType, MaterialPoint, Mesh};

/// A problem with one element.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlaceError {
    #[error("element {}: {} (det J = {det:.6e} ≤ 0); Anura3D would give its MPs a negative volume", .element + 1, orientation_hint(*.element_type))]
    NonPositiveJacobian {
        element: usize,
        element_type: ElementType,
        det: f64,
    },
    #[error("element {}: {count} MPs per element is not allowed for {} (allowed: {allowed:?})", .element + 1, .element_type.gom_name())]
    UnsupportedCount {
        element: usize,
        element_type: ElementType,
        count: u32,
        allowed: &'static [u32],
    },
    #[error("element {}: active element (material {material}) without material points (allowed only with $$COMPUTATION_METHOD FEM or UL-FEM)", .element + 1)]
    ActiveWithoutPoints { element: usize, material: u32 },
    #[error("element {}: a material point at radius x = {x:.6e} ≤ 0 in a 2D-axisymmetric model; Anura3D would give it a non-positive volume", .element + 1)]
    NonPositiveRadius { element: usize, x: f64 },
}

fn orientation_hint(et: ElementType) -> &'static str {
    mesh_element(et).orientation()
}

impl PlaceError {
    /// The 0-based element index the error is about.
    pub fn element(&self) -> Option<usize> {
        match self {
            PlaceError::NonPositiveJacobian { element, .. }
            | PlaceError::UnsupportedCount { element, .. }
            | PlaceError::ActiveWithoutPoints { element, .. }
            | PlaceError::NonPositiveRadius { element, .. } => Some(*element),
        }
    }
}

/// Every problem found, in element order.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{} element(s) cannot hold material points: {}", .0.len(), .0.iter().take(5).map(|e| e.to_string()).collect::<Vec<_>>().join("; "))]
pub struct PlaceErrors(pub Vec<PlaceError>);

/// Orientation check of the elements for which `active(e)` holds: det J > 0 at
/// the element's centroid.
pub fn check_elements(mesh: &Mesh, active: impl Fn(usize) -> bool) -> Vec<PlaceError> {
    struct Check<'a, F>(&'a Mesh, F);
    impl<F: Fn(usize) -> bool> ElementVisitor for Check<'_, F> {
        type Output = Vec<PlaceError>;
        fn visit<const D: usize, const NC: usize, E: Element<D, NC>>(self) -> Self::Output {
            let Check(mesh, active) = self;
            (0..mesh.n_elements())
                .filter(|&e| active(e))
                .filter_map(|e| {
                    let det = E::det_jacobian(&crate::corners(mesh, e), &E::CENTROID);
                    (det.is_nan() || det <= 0.0).then_some(PlaceError::NonPositiveJacobian {
                        element: e,
                        element_type: E::TYPE,
                        det,
                    })
                })
                .collect()
        }
    }
    with_element(mesh.element_type, Check(mesh, active))
}

/// Integration weight of a material point: `weight` × det J, times the radius
/// x (per radian) in a 2D-axisymmetric model (Anura3D's
/// `AdjustParticleDiscretisation.FOR`, verified on the running kernel).
pub fn mp_volume(dimension: Dimension, weight: f64, det: f64, position: [f64; 3]) -> f64 {
    match dimension {
        Dimension::Axisymmetric => weight * det * position[0],
        _ => weight * det,
    }
}

/// Creates the MPs of `model` exactly as Anura3D does at load step 1 of an MPM
/// computation (the GOM's counts).
pub fn place_material_points(model: &AnuraModel) -> Result<Vec<MaterialPoint>, PlaceErrors> {
    place_material_points_for(model, ComputationMethod::MpmMixed)
}

/// Creates the MPs of `model` as Anura3D does for `method`: the GOM's counts for
/// MPM, and for `FEM`/`UL-FEM` one point per active element whatever the counts
/// say (Anura3D's one-point table, i.e. the mean of the corner nodes; counts of 0
/// are accepted there).
pub fn place_material_points_for(
    model: &AnuraModel,
    method: ComputationMethod,
) -> Result<Vec<MaterialPoint>, PlaceErrors> {
    struct Place<'a>(&'a AnuraModel, ComputationMethod);
    impl ElementVisitor for Place<'_> {
        type Output = Result<Vec<MaterialPoint>, PlaceErrors>;
        fn visit<const D: usize, const NC: usize, E: Element<D, NC>>(self) -> Self::Output {
            place::<D, NC, E>(self.0, self.1)
        }
    }
    with_element(model.mesh.element_type, Place(model, method))
}

/// [`place_material_points_for`] with the element type's implementation `E`.
fn place<const D: usize, const NC: usize, E: Element<D, NC>>(
    model: &AnuraModel,
    method: ComputationMethod,
) -> Result<Vec<MaterialPoint>, PlaceErrors> {
    let one_point = method.one_point_per_element();
    let mesh = &model.mesh;
    let et = E::TYPE;
    let mut errors = Vec::new();
    let total: usize = model
        .mp_counts
        .iter()
        .zip(&model.element_material)
        .filter(|(_, m)| **m > 0)
        .map(|(c, _)| if one_point { 1 } else { c.0 as usize })
        .sum();
    let mut points = Vec::with_capacity(total);
    for e in 0..mesh.n_elements() {
        let material = model.element_material[e];
        if material == 0 {
            continue;
        }
        let count = if one_point {
            1
        } else {
            model.mp_counts.get(e).map_or(0, |c| c.0)
        };
        if count == 0 {
            errors.push(PlaceError::ActiveWithoutPoints {
                element: e,
                material,
            });
            continue;
        }
        let Some(table) = E::local_points(count) else {
            errors.push(PlaceError::UnsupportedCount {
                element: e,
                element_type: et,
                count,
                allowed: et.allowed_mp_counts(),
            });
            continue;
        };
        let first_new = points.len();
        let corners = crate::corners::<D, NC>(mesh, e);
        let mut bad = None;
        for (k, lp) in table.iter().enumerate() {
            let xi = lp.coords::<D>();
            let det = E::det_jacobian(&corners, &xi);
            if det.is_nan() || det <= 0.0 {
                bad = Some(PlaceError::NonPositiveJacobian {
                    element: e,
                    element_type: et,
                    det,
                });
                break;
            }
            let position = crate::widen(&E::global_position(&corners, &xi));
            if mesh.dimension == Dimension::Axisymmetric
                && (position[0].is_nan() || position[0] <= 0.0)
            {
                bad = Some(PlaceError::NonPositiveRadius {
                    element: e,
                    x: position[0],
                });
                break;
            }
            points.push(MaterialPoint {
                id: (first_new + k + 1) as u32,
                element: e as u32,
                material,
                local: k as u32 + 1,
                position,
                volume: mp_volume(mesh.dimension, lp.weight, det, position),
            });
        }
        if let Some(error) = bad {
            points.truncate(first_new);
            errors.push(error);
        }
    }
    if errors.is_empty() {
        Ok(points)
    } else {
        Err(PlaceErrors(errors))
    }
}
