//! The mesh of a `.vtu` as the reader needs it: points, cells checked against
//! their types, the model dimension, which points are data points (every node
//! of every cell), which are corners, the linear fill of mid-edge nodes from
//! their corners (the Taylor–Hood rule) and the materials around each node.

use std::collections::BTreeMap;
use std::path::Path;

use super::cells::CellKind;
use super::decode::values;
use super::xml::VtuXml;
use crate::error::ParseError;

/// Points and cells of one `.vtu`.
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Coordinates in m (z = 0 in 2D).
    pub points: Vec<[f64; 3]>,
    /// Each cell's kind and its nodes' range in `nodes`.
    pub cells: Vec<(CellKind, usize)>,
    /// The cells' nodes, in order.
    pub nodes: Vec<u32>,
    /// 2 or 3.
    pub dim: usize,
    /// Cells of each kind.
    pub kinds: BTreeMap<CellKind, usize>,
    /// What was assumed or left out.
    pub notes: Vec<String>,
}

impl Mesh {
    /// The nodes of cell `c`.
    pub fn cell(&self, c: usize) -> &[u32] {
        let (kind, start) = self.cells[c];
        &self.nodes[start..start + kind.n_nodes()]
    }

    /// Per point: true when some cell uses it (a data point).
    pub fn used(&self) -> Vec<bool> {
        let mut used = vec![false; self.points.len()];
        for &n in &self.nodes {
            used[n as usize] = true;
        }
        used
    }

    /// True when some cell is quadratic.
    pub fn has_quadratic(&self) -> bool {
        self.kinds.keys().any(|k| k.is_quadratic())
    }

    /// Per point: true when it is a corner of some cell.
    pub fn corners(&self) -> Vec<bool> {
        let mut corner = vec![false; self.points.len()];
        for c in 0..self.cells.len() {
            let kind = self.cells[c].0;
            for &n in &self.cell(c)[..kind.corners()] {
                corner[n as usize] = true;
            }
        }
        corner
    }

    /// Gives every node that is no cell's corner the mean of the corners it
    /// lies between (the value of the linear field those corners define), from
    /// the first cell that has it. Returns how many nodes were filled.
    pub fn fill_linear(&self, values: &mut [f64], corner: &[bool]) -> usize {
        let mut filled = vec![false; values.len()];
        let mut count = 0;
        for c in 0..self.cells.len() {
            let kind = self.cells[c].0;
            let nodes = self.cell(c);
            for (k, between) in kind.mid_nodes().iter().enumerate() {
                let n = nodes[kind.corners() + k] as usize;
                if corner[n] || filled[n] {
                    continue;
                }
                let sum: f64 = between.iter().map(|&i| values[nodes[i] as usize]).sum();
                values[n] = sum / between.len() as f64;
                filled[n] = true;
                count += 1;
            }
        }
        count
    }

    /// Per point, the sorted distinct values of the cell array `ids` (one per
    /// cell) over the cells that use it.
    pub fn around(&self, ids: &[i64]) -> Vec<Vec<i64>> {
        let mut out: Vec<Vec<i64>> = vec![Vec::new(); self.points.len()];
        for (c, &id) in ids.iter().enumerate() {
            for &n in self.cell(c) {
                let list = &mut out[n as usize];
                if let Err(k) = list.binary_search(&id) {
                    list.insert(k, id);
                }
            }
        }
        out
    }
}

/// Integer value of a decoded index array, or `None`.
fn index(v: f64, below: usize) -> Option<usize> {
    (v >= 0.0 && v.fract() == 0.0 && v < below as f64).then_some(v as usize)
}

/// Reads the points and cells of `xml` (coordinates times `length_factor`).
pub fn read(
    path: &Path,
    bytes: &[u8],
    xml: &VtuXml,
    length_factor: f64,
) -> Result<Mesh, ParseError> {
    let coords = values(path, bytes, xml, &xml.points, xml.n_points)?;
    let mut points: Vec<[f64; 3]> = coords
        .chunks_exact(3)
        .map(|c| {
            [
                c[0] * length_factor,
                c[1] * length_factor,
                c[2] * length_factor,
            ]
        })
        .collect();
    if let Some(i) = points.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
        return Err(ParseError::new(
            path,
            xml.points.at,
            format!(
                "point {} has a coordinate that is not a finite number",
                i + 1
            ),
        ));
    }
    let types = values(path, bytes, xml, &xml.types, xml.n_cells)?;
    let offsets = values(path, bytes, xml, &xml.offsets, xml.n_cells)?;
    let n_nodes = match offsets.last() {
        None => 0,
        Some(&last) => index(last, usize::MAX).ok_or_else(|| {
            ParseError::new(path, xml.offsets.at, "the last offset is not a count")
        })?,
    };
    let connectivity = values(path, bytes, xml, &xml.connectivity, n_nodes)?;
    let mut cells = Vec::with_capacity(xml.n_cells);
    let mut nodes = Vec::with_capacity(n_nodes);
    let mut kinds: BTreeMap<CellKind, usize> = BTreeMap::new();
    let mut start = 0usize;
    let mut refused: BTreeMap<String, usize> = BTreeMap::new();
    for c in 0..xml.n_cells {
        let end = index(offsets[c], n_nodes + 1)
            .filter(|&e| e >= start)
            .ok_or_else(|| {
                ParseError::new(
                    path,
                    xml.offsets.at,
                    format!(
                        "cell {}: offset {} does not follow {start}",
                        c + 1,
                        offsets[c]
                    ),
                )
            })?;
        let code = types[c];
        if !(code.fract() == 0.0 && code.abs() < 1e15) {
            return Err(ParseError::new(
                path,
                xml.types.at,
                format!(
                    "cell {}: type {code} is not an integer (a VTK cell type code)",
                    c + 1
                ),
            ));
        }
        let kind = match CellKind::from_vtk(code as i64) {
            Ok(kind) => kind,
            Err(message) => {
                *refused.entry(message).or_default() += 1;
                start = end;
                continue;
            }
        };
        if end - start != kind.n_nodes() {
            return Err(ParseError::new(
                path,
                xml.offsets.at,
                format!(
                    "cell {} is a {} but has {} nodes (a {} has {})",
                    c + 1,
                    kind.name(),
                    end - start,
                    kind.name(),
                    kind.n_nodes()
                ),
            ));
        }
        let first = nodes.len();
        for &v in &connectivity[start..end] {
            let n = index(v, points.len()).ok_or_else(|| {
                ParseError::new(
                    path,
                    xml.connectivity.at,
                    format!(
                        "cell {} names node {v}, but there are {} points (0-based)",
                        c + 1,
                        points.len()
                    ),
                )
            })?;
            nodes.push(n as u32);
        }
        cells.push((kind, first));
        *kinds.entry(kind).or_default() += 1;
        start = end;
    }
    if let Some((message, n)) = refused.into_iter().next() {
        return Err(ParseError::new(
            path,
            xml.types.at,
            format!("{n} cells: {message}"),
        ));
    }
    if cells.is_empty() {
        return Err(ParseError::new(
            path,
            xml.types.at,
            "no cells: the nodes of the cells are the data points",
        ));
    }
    let (dim, notes) = plane_of(path, xml, &kinds, &mut points)?;
    let mesh = Mesh {
        points,
        cells,
        nodes,
        dim,
        kinds,
        notes,
    };
    let orphans = mesh.used().iter().filter(|u| !**u).count();
    let mut mesh = mesh;
    if orphans > 0 {
        mesh.notes.push(format!(
            "{orphans} points belong to no cell and were left out (the data points are the nodes of the cells)"
        ));
    }
    Ok(mesh)
}

/// The model's dimension from its cell kinds (2D or 3D, not both; from z
/// when no cell has one); 2D cells must lie in one x–y plane, which is moved
/// to z = 0 (said in the notes).
fn plane_of(
    path: &Path,
    xml: &VtuXml,
    kinds: &BTreeMap<CellKind, usize>,
    points: &mut [[f64; 3]],
) -> Result<(usize, Vec<String>), ParseError> {
    let mut notes = Vec::new();
    let dims: Vec<usize> = kinds.keys().map(|k| k.dim()).filter(|&d| d > 0).collect();
    let dim = match (dims.iter().min(), dims.iter().max()) {
        (Some(2), Some(3)) => {
            return Err(ParseError::new(
                path,
                xml.types.at,
                "the file mixes 2D and 3D cells: give the bulk mesh's results alone",
            ));
        }
        (Some(&d), _) => d,
        (None, _) if points.iter().all(|p| p[2] == 0.0) => 2,
        (None, _) => 3,
    };
    if dim == 2 {
        let z = points.first().map_or(0.0, |p| p[2]);
        if let Some(i) = points.iter().position(|p| p[2] != z) {
            return Err(ParseError::new(
                path,
                xml.points.at,
                format!(
                    "2D cells, but point {} has z = {} and point 1 z = {z}: a 2D model lies in one x–y plane",
                    i + 1,
                    points[i][2]
                ),
            ));
        }
        if z != 0.0 {
            notes.push(format!("2D cells in the plane z = {z}: z set to 0"));
            for p in points.iter_mut() {
                p[2] = 0.0;
            }
        }
    }
    Ok((dim, notes))
}
