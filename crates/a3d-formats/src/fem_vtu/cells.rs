//! The VTK cell types a FEM result is made of: which are read, how many nodes
//! each has, which of them are corners, and the corners each mid-edge (or
//! centre) node of a quadratic cell lies between, in VTK's node order. This is
//! what the Taylor–Hood rule needs: a linear field on a quadratic cell is
//! known at the corners, and its value at a mid-edge node is the mean of the
//! edge's two ends.

/// A cell type a3d-init reads from a `.vtu`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CellKind {
    Vertex,
    Tri3,
    Quad4,
    Tet4,
    Hex8,
    Wedge6,
    Pyramid5,
    Tri6,
    Quad8,
    Quad9,
    Tet10,
    Hex20,
}

impl CellKind {
    /// The kind of VTK cell type `code`; `Err` names what the code is when it
    /// is a type a3d-init does not read.
    pub fn from_vtk(code: i64) -> Result<CellKind, String> {
        Ok(match code {
            1 => CellKind::Vertex,
            5 => CellKind::Tri3,
            9 => CellKind::Quad4,
            10 => CellKind::Tet4,
            12 => CellKind::Hex8,
            13 => CellKind::Wedge6,
            14 => CellKind::Pyramid5,
            22 => CellKind::Tri6,
            23 => CellKind::Quad8,
            28 => CellKind::Quad9,
            24 => CellKind::Tet10,
            25 => CellKind::Hex20,
            3 | 4 | 21 | 35 => {
                return Err(format!(
                    "VTK cell type {code} is a line: a3d-init reads 2D and 3D results (is this a boundary mesh?)"
                ));
            }
            2 => return Err("VTK cell type 2 (poly-vertex) is not read".into()),
            other => {
                return Err(format!(
                    "VTK cell type {other} is not read (read: vertex, TRI3, QUAD4, TET4, HEX8, WEDGE6, PYRAMID5, TRI6, QUAD8, QUAD9, TET10, HEX20)"
                ));
            }
        })
    }

    /// Its name in messages and reports.
    pub fn name(self) -> &'static str {
        match self {
            CellKind::Vertex => "VERTEX",
            CellKind::Tri3 => "TRI3",
            CellKind::Quad4 => "QUAD4",
            CellKind::Tet4 => "TET4",
            CellKind::Hex8 => "HEX8",
            CellKind::Wedge6 => "WEDGE6",
            CellKind::Pyramid5 => "PYRAMID5",
            CellKind::Tri6 => "TRI6",
            CellKind::Quad8 => "QUAD8",
            CellKind::Quad9 => "QUAD9",
            CellKind::Tet10 => "TET10",
            CellKind::Hex20 => "HEX20",
        }
    }

    /// Nodes per cell.
    pub fn n_nodes(self) -> usize {
        self.corners() + self.mid_nodes().len()
    }

    /// Corner (vertex) nodes per cell: the first nodes in VTK's order.
    pub fn corners(self) -> usize {
        match self {
            CellKind::Vertex => 1,
            CellKind::Tri3 | CellKind::Tri6 => 3,
            CellKind::Quad4 | CellKind::Quad8 | CellKind::Quad9 => 4,
            CellKind::Tet4 | CellKind::Tet10 => 4,
            CellKind::Hex8 | CellKind::Hex20 => 8,
            CellKind::Wedge6 => 6,
            CellKind::Pyramid5 => 5,
        }
    }

    /// Dimension of the cell (0 for a vertex).
    pub fn dim(self) -> usize {
        match self {
            CellKind::Vertex => 0,
            CellKind::Tri3
            | CellKind::Quad4
            | CellKind::Tri6
            | CellKind::Quad8
            | CellKind::Quad9 => 2,
            _ => 3,
        }
    }

    /// True for the quadratic types (nodes other than corners).
    pub fn is_quadratic(self) -> bool {
        !self.mid_nodes().is_empty()
    }

    /// For each node after the corners, in order, the corners whose mean is a
    /// linear field's value there: an edge's two ends, or (QUAD9's centre)
    /// all four corners.
    pub fn mid_nodes(self) -> &'static [&'static [usize]] {
        match self {
            CellKind::Tri6 => &[&[0, 1], &[1, 2], &[2, 0]],
            CellKind::Quad8 => &[&[0, 1], &[1, 2], &[2, 3], &[3, 0]],
            CellKind::Quad9 => &[&[0, 1], &[1, 2], &[2, 3], &[3, 0], &[0, 1, 2, 3]],
            CellKind::Tet10 => &[&[0, 1], &[1, 2], &[0, 2], &[0, 3], &[1, 3], &[2, 3]],
            CellKind::Hex20 => &[
                &[0, 1],
                &[1, 2],
                &[2, 3],
                &[3, 0],
                &[4, 5],
                &[5, 6],
                &[6, 7],
                &[7, 4],
                &[0, 4],
                &[1, 5],
                &[2, 6],
                &[3, 7],
            ],
            _ => &[],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [CellKind; 12] = [
        CellKind::Vertex,
        CellKind::Tri3,
        CellKind::Quad4,
        CellKind::Tet4,
        CellKind::Hex8,
        CellKind::Wedge6,
        CellKind::Pyramid5,
        CellKind::Tri6,
        CellKind::Quad8,
        CellKind::Quad9,
        CellKind::Tet10,
        CellKind::Hex20,
    ];

    #[test]
    fn node_counts_are_vtks() {
        let counts: Vec<usize> = ALL.iter().map(|k| k.n_nodes()).collect();
        assert_eq!(counts, [1, 3, 4, 4, 8, 6, 5, 6, 8, 9, 10, 20]);
    }

    #[test]
    fn mid_nodes_name_corners_only_and_every_edge_once() {
        for kind in ALL {
            let mut edges: Vec<Vec<usize>> = Vec::new();
            for between in kind.mid_nodes() {
                assert!(between.iter().all(|&c| c < kind.corners()), "{kind:?}");
                let mut e = between.to_vec();
                e.sort_unstable();
                assert!(!edges.contains(&e), "{kind:?}: {e:?} twice");
                edges.push(e);
            }
        }
    }

    #[test]
    fn codes_round_trip_and_lines_are_refused_by_name() {
        for (code, kind) in [
            (5, CellKind::Tri3),
            (23, CellKind::Quad8),
            (25, CellKind::Hex20),
        ] {
            assert_eq!(CellKind::from_vtk(code), Ok(kind));
        }
        assert!(CellKind::from_vtk(3).unwrap_err().contains("line"));
        assert!(CellKind::from_vtk(29).unwrap_err().contains("29"));
        // Codes past a byte are named as written, not as a wrapped byte.
        assert!(
            CellKind::from_vtk(300)
                .unwrap_err()
                .contains("cell type 300 ")
        );
        assert!(
            CellKind::from_vtk(-5)
                .unwrap_err()
                .contains("cell type -5 ")
        );
    }
}
