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

    /// The shape functions at ξ, in CB-Geo's node order and arithmetic.
    pub fn shape(self, xi: [f64; 3]) -> Vec<f64> {
        let [x, y, z] = xi;
        match self {
            CbGeoCell::Tri3 => vec![1.0 - (x + y), x, y],
            CbGeoCell::Quad4 => vec![
                0.25 * (1.0 - x) * (1.0 - y),
                0.25 * (1.0 + x) * (1.0 - y),
                0.25 * (1.0 + x) * (1.0 + y),
                0.25 * (1.0 - x) * (1.0 + y),
            ],
            CbGeoCell::Hex8 => vec![
                0.125 * (1.0 - x) * (1.0 - y) * (1.0 - z),
                0.125 * (1.0 + x) * (1.0 - y) * (1.0 - z),
                0.125 * (1.0 + x) * (1.0 + y) * (1.0 - z),
                0.125 * (1.0 - x) * (1.0 + y) * (1.0 - z),
                0.125 * (1.0 - x) * (1.0 - y) * (1.0 + z),
                0.125 * (1.0 + x) * (1.0 - y) * (1.0 + z),
                0.125 * (1.0 + x) * (1.0 + y) * (1.0 + z),
                0.125 * (1.0 - x) * (1.0 + y) * (1.0 + z),
            ],
        }
    }

    /// The measure of a cell with these corner coordinates (area in 2D,
    /// volume in 3D), by the quadrature CB-Geo uses for a cell's volume
    /// (one point, weight 2ᵈ for the box elements, ½ for the triangle): the
    /// exact measure of a parallelogram, a triangle or a parallelepiped, and
    /// of any bilinear quadrilateral.
    pub fn measure(self, corners: &[[f64; 3]]) -> f64 {
        match self {
            CbGeoCell::Tri3 => {
                let [a, b, c] = [corners[0], corners[1], corners[2]];
                0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])).abs()
            }
            CbGeoCell::Quad4 => {
                // The shoelace formula: exact for any straight-sided quadrilateral.
                let mut s = 0.0;
                for i in 0..4 {
                    let (p, r) = (corners[i], corners[(i + 1) % 4]);
                    s += p[0] * r[1] - r[0] * p[1];
                }
                0.5 * s.abs()
            }
            CbGeoCell::Hex8 => hex_volume(corners),
        }
    }
}

/// A hexahedron's volume: [`crate::Hex8`]'s measure.
fn hex_volume(c: &[[f64; 3]]) -> f64 {
    use crate::Element;
    crate::Hex8::measure(&std::array::from_fn(|k| c[k]))
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
        assert_eq!(CbGeoCell::Tri3.measure(&tri), 3.0);
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
        assert!((CbGeoCell::Hex8.measure(&cube) - 3.0).abs() < 1e-14);
        let quad = [
            [0.0, 0.0, 0.0],
            [4.0, 0.0, 0.0],
            [3.0, 2.0, 0.0],
            [1.0, 2.0, 0.0],
        ];
        assert_eq!(CbGeoCell::Quad4.measure(&quad), 6.0);
    }
}
