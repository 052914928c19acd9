//! CB-Geo mpm's placement: where its `"gauss"` particle generator puts the
//! particles of a cell, in its order, as [`crate::place`] does for Anura3D.
//!
//! CB-Geo (`Mesh::generate_material_points`, `Cell::generate_points`) walks
//! the cells of the generator's cell set (all cells in mesh order for
//! `cset_id` −1), gives each the quadrature its element picks for
//! `nparticles_per_dir` (`*Element::quadrature`: 1–4 per direction for
//! quadrilaterals and hexahedra, 1 or 2 for triangles (1 or 3 points), one
//! point for any other count) and creates one particle at x = Σ Nⱼ(ξ) xⱼ for
//! each quadrature point, in the table's order. The tables are CB-Geo's own,
//! in `cbgeo_quadrature.rs`.

use crate::cbgeo_quadrature as q;

/// The CB-Geo cell types whose particles a3d-init places.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CbGeoCell {
    /// `ED2T3`: linear triangle.
    Tri3,
    /// `ED2Q4`: bilinear quadrilateral, nodes counter-clockwise from (−1, −1).
    Quad4,
    /// `ED3H8`: trilinear hexahedron, the bottom face (ζ = −1) first.
    Hex8,
}

impl CbGeoCell {
    /// The cell type named in `mesh.cell_type`; `None` for the types a3d-init
    /// does not place in (higher-order, GIMP, B-spline, LME, tetrahedra).
    pub fn from_name(name: &str) -> Option<CbGeoCell> {
        match name {
            "ED2T3" => Some(CbGeoCell::Tri3),
            "ED2Q4" => Some(CbGeoCell::Quad4),
            "ED3H8" => Some(CbGeoCell::Hex8),
            _ => None,
        }
    }

    /// CB-Geo's name.
    pub fn name(self) -> &'static str {
        match self {
            CbGeoCell::Tri3 => "ED2T3",
            CbGeoCell::Quad4 => "ED2Q4",
            CbGeoCell::Hex8 => "ED3H8",
        }
    }

    /// Nodes per cell line in the mesh file.
    pub fn n_nodes(self) -> usize {
        match self {
            CbGeoCell::Tri3 => 3,
            CbGeoCell::Quad4 => 4,
            CbGeoCell::Hex8 => 8,
        }
    }

    /// Spatial dimension.
    pub fn n_dim(self) -> usize {
        match self {
            CbGeoCell::Tri3 | CbGeoCell::Quad4 => 2,
            CbGeoCell::Hex8 => 3,
        }
    }

    /// How many particles the `"gauss"` generator puts in one cell for
    /// `nparticles_per_dir`.
    pub fn points_per_cell(self, per_dir: u32) -> usize {
        self.local_points(per_dir).len()
    }

    /// The local coordinates CB-Geo's quadrature gives for `per_dir`, padded
    /// to three with zeros.
    pub fn local_points(self, per_dir: u32) -> Vec<[f64; 3]> {
        let two = |t: &[[f64; 2]]| t.iter().map(|p| [p[0], p[1], 0.0]).collect();
        let three = |t: &[[f64; 3]]| t.to_vec();
        match (self, per_dir) {
            (CbGeoCell::Tri3, 2) => two(&q::QT2),
            (CbGeoCell::Tri3, _) => two(&q::QT1),
            (CbGeoCell::Quad4, 2) => two(&q::QQ2),
            (CbGeoCell::Quad4, 3) => two(&q::QQ3),
            (CbGeoCell::Quad4, 4) => two(&q::QQ4),
            (CbGeoCell::Quad4, _) => two(&q::QQ1),
            (CbGeoCell::Hex8, 2) => three(&q::QH2),
            (CbGeoCell::Hex8, 3) => three(&q::QH3),
            (CbGeoCell::Hex8, 4) => three(&q::QH4),
            (CbGeoCell::Hex8, _) => three(&q::QH1),
        }
    }

    /// The shape functions at ξ, in CB-Geo's node order and arithmetic: the
    /// element seam's for the quadrilateral and the hexahedron (the same
    /// products, bit for bit), CB-Geo's own 1 − (ξ + η) for the triangle
    /// (the seam's `Tri3` rounds 1 − ξ − η).
    pub fn shape(self, xi: [f64; 3]) -> Vec<f64> {
        use crate::Element;
        let [x, y, z] = xi;
        match self {
            CbGeoCell::Tri3 => vec![1.0 - (x + y), x, y],
            CbGeoCell::Quad4 => crate::Quad4::shape_values(&[x, y]).to_vec(),
            CbGeoCell::Hex8 => crate::Hex8::shape_values(&[x, y, z]).to_vec(),
        }
    }
}

/// The particles CB-Geo's `"gauss"` generator creates in one cell with these
/// node coordinates (`corners`, CB-Geo's node order), in its order.
pub fn gauss_points(cell: CbGeoCell, per_dir: u32, corners: &[[f64; 3]]) -> Vec<[f64; 3]> {
    cell.local_points(per_dir)
        .into_iter()
        .map(|xi| {
            let n = cell.shape(xi);
            let mut x = [0.0; 3];
            for (nj, c) in n.iter().zip(corners) {
                for k in 0..cell.n_dim() {
                    x[k] += nj * c[k];
                }
            }
            x
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_points_of_a_unit_square_are_the_scaled_tables() {
        let sq = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 2.0, 0.0],
            [0.0, 2.0, 0.0],
        ];
        let p = gauss_points(CbGeoCell::Quad4, 2, &sq);
        let a = 1.0 - 1.0 / 3f64.sqrt();
        let b = 1.0 + 1.0 / 3f64.sqrt();
        let want = [[a, a], [b, a], [b, b], [a, b]];
        for (got, w) in p.iter().zip(want) {
            assert!((got[0] - w[0]).abs() < 1e-15 && (got[1] - w[1]).abs() < 1e-15);
        }
        // CB-Geo's 3×3 table: corners, then edge midpoints, then the centre.
        let p = gauss_points(CbGeoCell::Quad4, 3, &sq);
        assert_eq!(p.len(), 9);
        assert_eq!(p[8], [1.0, 1.0, 0.0]);
        // Counts per direction CB-Geo has no table for fall back to one point.
        assert_eq!(CbGeoCell::Quad4.points_per_cell(5), 1);
        assert_eq!(CbGeoCell::Tri3.points_per_cell(2), 3);
        assert_eq!(CbGeoCell::Hex8.points_per_cell(4), 64);
    }

    #[test]
    fn every_table_sums_to_the_reference_centroid_and_measures_hold() {
        for cell in [CbGeoCell::Quad4, CbGeoCell::Hex8] {
            for n in 1..=4 {
                let pts = cell.local_points(n);
                assert_eq!(pts.len(), (n as usize).pow(cell.n_dim() as u32));
                for k in 0..3 {
                    let mean: f64 = pts.iter().map(|p| p[k]).sum::<f64>() / pts.len() as f64;
                    assert!(mean.abs() < 1e-15, "{cell:?} {n}: centroid {mean}");
                }
            }
        }
        let tri = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 2.0, 0.0]];
        use crate::Element;
        let flat = |c: &[[f64; 3]]| -> Vec<[f64; 2]> { c.iter().map(|p| [p[0], p[1]]).collect() };
        // The measures the particles' volumes come from: the element seam's.
        assert_eq!(crate::Tri3::measure(&flat(&tri).try_into().unwrap()), 3.0);
        let p = gauss_points(CbGeoCell::Tri3, 1, &tri);
        assert!((p[0][0] - 1.0).abs() < 1e-15 && (p[0][1] - 2.0 / 3.0).abs() < 1e-15);
        let cube: Vec<[f64; 3]> = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ]
        .iter()
        .map(|p| [2.0 * p[0], 3.0 * p[1], 0.5 * p[2]])
        .collect();
        assert!((crate::Hex8::measure(&cube.clone().try_into().unwrap()) - 3.0).abs() < 1e-14);
        let quad = [
            [0.0, 0.0, 0.0],
            [4.0, 0.0, 0.0],
            [3.0, 2.0, 0.0],
            [1.0, 2.0, 0.0],
        ];
        assert_eq!(crate::Quad4::measure(&flat(&quad).try_into().unwrap()), 6.0);
    }
}
