//! Background mesh and the Anura3D model assembled from a GOM file.

use super::material::Material;

/// The `$$DIMENSION` of an Anura3D model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Dimension {
    /// `2D-plane_strain`
    PlaneStrain,
    /// `2D-axisymmetric` (x is the radius)
    Axisymmetric,
    /// `3D-cartesian`
    Cartesian3D,
    /// `3D-cylindrical`
    Cylindrical3D,
}

impl Dimension {
    /// Parses the GOM spelling.
    pub fn from_gom(s: &str) -> Option<Dimension> {
        match s {
            "2D-plane_strain" => Some(Dimension::PlaneStrain),
            "2D-axisymmetric" => Some(Dimension::Axisymmetric),
            "3D-cartesian" => Some(Dimension::Cartesian3D),
            "3D-cylindrical" => Some(Dimension::Cylindrical3D),
            _ => None,
        }
    }

    /// The GOM spelling.
    pub fn gom_name(self) -> &'static str {
        match self {
            Dimension::PlaneStrain => "2D-plane_strain",
            Dimension::Axisymmetric => "2D-axisymmetric",
            Dimension::Cartesian3D => "3D-cartesian",
            Dimension::Cylindrical3D => "3D-cylindrical",
        }
    }

    /// Number of spatial coordinates: 2 or 3.
    pub fn n_dim(self) -> usize {
        match self {
            Dimension::PlaneStrain | Dimension::Axisymmetric => 2,
            Dimension::Cartesian3D | Dimension::Cylindrical3D => 3,
        }
    }
}

/// The element types a3d-init can place material points in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum ElementType {
    /// `triangular_3-noded`: linear triangle, counter-clockwise nodes.
    Tri3,
    /// `tetrahedral_old`: 10 node ids per element, only the 4 corners enter the
    /// shape functions (N1 = 1-ξ-η-ζ, N2 = ζ, N3 = ξ, N4 = η).
    TetOld,
    /// `quadrilateral_4-noded` (upstream Anura3D kernel only).
    Quad4,
    /// The 8-noded hexahedron of CB-Geo mpm (`ED3H8`): Anura3D has none, so a
    /// GOM never names it.
    Hex8,
}

impl ElementType {
    /// Parses the GOM spelling; `None` for types a3d-init does not support.
    pub fn from_gom(s: &str) -> Option<ElementType> {
        match s {
            "triangular_3-noded" => Some(ElementType::Tri3),
            "tetrahedral_old" => Some(ElementType::TetOld),
            "quadrilateral_4-noded" => Some(ElementType::Quad4),
            _ => None,
        }
    }

    /// The GOM spelling.
    pub fn gom_name(self) -> &'static str {
        match self {
            ElementType::Tri3 => "triangular_3-noded",
            ElementType::TetOld => "tetrahedral_old",
            ElementType::Quad4 => "quadrilateral_4-noded",
            ElementType::Hex8 => "hexahedral_8-noded (CB-Geo ED3H8)",
        }
    }

    /// Node ids per element line in `$$STARTELEMCON`.
    pub fn nodes_per_element(self) -> usize {
        match self {
            ElementType::Tri3 => 3,
            ElementType::TetOld => 10,
            ElementType::Quad4 => 4,
            ElementType::Hex8 => 8,
        }
    }

    /// Corner nodes that enter the linear shape functions.
    pub fn n_corners(self) -> usize {
        match self {
            ElementType::Tri3 => 3,
            ElementType::TetOld | ElementType::Quad4 => 4,
            ElementType::Hex8 => 8,
        }
    }

    /// Spatial dimension of the element.
    pub fn n_dim(self) -> usize {
        match self {
            ElementType::Tri3 | ElementType::Quad4 => 2,
            ElementType::TetOld | ElementType::Hex8 => 3,
        }
    }

    /// MP counts per element that Anura3D accepts for this type.
    pub fn allowed_mp_counts(self) -> &'static [u32] {
        match self {
            ElementType::Tri3 => &[1, 3, 6, 12, 16, 25, 46, 88],
            ElementType::TetOld => &[1, 4, 7, 8, 10, 13, 20],
            ElementType::Quad4 => &[1, 4],
            ElementType::Hex8 => &[],
        }
    }

    /// Each face's local corner indices (its edges in 2D), the first three
    /// spanning its plane; every element type's faces cover its boundary.
    pub fn faces(self) -> &'static [&'static [usize]] {
        match self {
            ElementType::Tri3 => &[&[0, 1], &[1, 2], &[2, 0]],
            ElementType::Quad4 => &[&[0, 1], &[1, 2], &[2, 3], &[3, 0]],
            ElementType::TetOld => &[&[0, 1, 2], &[0, 1, 3], &[0, 2, 3], &[1, 2, 3]],
            ElementType::Hex8 => &[
                &[0, 1, 2, 3],
                &[4, 5, 6, 7],
                &[0, 1, 5, 4],
                &[1, 2, 6, 5],
                &[2, 3, 7, 6],
                &[3, 0, 4, 7],
            ],
        }
    }
}

/// A background mesh. Node coordinates always have three components; z is 0 in 2D.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    pub dimension: Dimension,
    pub element_type: ElementType,
    pub nodes: Vec<[f64; 3]>,
    /// 0-based node indices, `element_type.nodes_per_element()` per element.
    pub connectivity: Vec<u32>,
}

impl Mesh {
    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    pub fn n_elements(&self) -> usize {
        self.connectivity.len() / self.element_type.nodes_per_element()
    }

    /// All node indices of element `e` (0-based), as written in the GOM.
    pub fn element_nodes(&self, e: usize) -> &[u32] {
        let n = self.element_type.nodes_per_element();
        &self.connectivity[e * n..(e + 1) * n]
    }

    /// The corner node indices of element `e` that enter the shape functions.
    pub fn corners(&self, e: usize) -> &[u32] {
        &self.element_nodes(e)[..self.element_type.n_corners()]
    }

    /// Coordinates of the corners of element `e` (unused slots are zero).
    pub fn corner_coords(&self, e: usize) -> [[f64; 3]; 8] {
        let mut out = [[0.0; 3]; 8];
        for (slot, &n) in out.iter_mut().zip(self.corners(e)) {
            *slot = self.nodes[n as usize];
        }
        out
    }

    /// Axis-aligned bounding box of the nodes: (min, max).
    pub fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.nodes {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }
}

/// Everything a3d-init needs from an Anura3D GOM file, as plain data.
#[derive(Clone, Debug, PartialEq)]
pub struct AnuraModel {
    pub mesh: Mesh,
    /// Materials in file order; `materials[i].index == i + 1`.
    pub materials: Vec<Material>,
    /// Per element: 1-based material index, 0 = inactive (`$$STARTELMMAT`).
    pub element_material: Vec<u32>,
    /// Per element: (solid, liquid) MP counts (`$$START_NUMBER_OF_MATERIAL_POINTS`).
    pub mp_counts: Vec<(u32, u32)>,
    /// Per node: fixed directions of the solid phase (x, y, z), OR-ed over all
    /// `$$START_FIXITY_*_SOLID` blocks.
    pub solid_fixity: Vec<[bool; 3]>,
    /// Per node: fixed directions of the liquid phase's velocity, OR-ed over
    /// all `$$START_FIXITY_*_LIQUID` blocks (all free when there are none).
    /// The two-phase runner holds the liquid's velocity there at zero (an
    /// impermeable boundary); a free boundary drains.
    pub liquid_fixity: Vec<[bool; 3]>,
    /// Per element local damping factor (`$$STARTDAMPING`), when present.
    pub damping: Option<Vec<f64>>,
}

impl AnuraModel {
    /// The material of element `e`, or `None` when the element is inactive.
    pub fn material_of(&self, e: usize) -> Option<&Material> {
        match self.element_material[e] {
            0 => None,
            m => self.materials.get(m as usize - 1),
        }
    }
}

/// `$$COMPUTATION_METHOD` of the CPS: how Anura3D creates and integrates MPs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize)]
pub enum ComputationMethod {
    /// `MPM-MIXED` (Anura3D's default): fully filled elements are integrated at
    /// their Gauss point, so after the first step every MP of such an element
    /// carries the state of its first MP.
    #[default]
    MpmMixed,
    /// `MPM-MP`: every element is integrated at its MPs; per-MP detail survives.
    MpmMp,
    /// `FEM`: one MP per active element, whatever the GOM's counts say.
    Fem,
    /// `UL-FEM`: as `FEM`, updated Lagrangian.
    UlFem,
}

impl ComputationMethod {
    /// Parses the CPS value (case-insensitive, as Anura3D upper-cases it).
    pub fn parse(s: &str) -> Option<ComputationMethod> {
        match s.trim().to_ascii_uppercase().as_str() {
            "MPM-MIXED" => Some(ComputationMethod::MpmMixed),
            "MPM-MP" => Some(ComputationMethod::MpmMp),
            "FEM" => Some(ComputationMethod::Fem),
            "UL-FEM" => Some(ComputationMethod::UlFem),
            _ => None,
        }
    }

    /// The CPS spelling.
    pub fn cps_name(self) -> &'static str {
        match self {
            ComputationMethod::MpmMixed => "MPM-MIXED",
            ComputationMethod::MpmMp => "MPM-MP",
            ComputationMethod::Fem => "FEM",
            ComputationMethod::UlFem => "UL-FEM",
        }
    }

    /// True for `FEM` and `UL-FEM`: one MP per active element.
    pub fn one_point_per_element(self) -> bool {
        matches!(self, ComputationMethod::Fem | ComputationMethod::UlFem)
    }
}
